"""Spatial flexible multibody dynamics (issue 18): nodes carrying a position and three
directors, geometrically exact director beams, joints as quadratic constraints with Lagrange
multipliers, ground contact, loads, and a system that collects them for the one HHT-alpha
integrator (cardillo style: components contribute mass, forces and constraints).

One thing per file:

- ``system.py``        :class:`System`, the :class:`~pantocosim.core.model.SecondOrderModel`
- ``constraint_set.py`` quadratic constraints g(q) = 1/2 q^T H q + b^T q + c (vectorised)
- ``beam3d.py``        the 3D beam element set (:class:`DirectorBeam`)
- ``joints.py``        clamp, spherical, revolute and universal joints (node-node or ground)
- ``contact.py``       penalty-damper ground contact (seed 002, eq. 17)
- ``loads.py``         gravity and nodal moments (the torque pulse)
- ``statics.py``       static equilibrium by Newton with load stepping
- ``linearize.py``     linearised inertia and stiffness on the constraint manifold,
                       natural frequencies (seed 004, 9.8)
- ``double_pendulum.py`` the spatial double pendulum of seed 002 and its runner
"""

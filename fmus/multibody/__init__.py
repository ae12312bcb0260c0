"""Spatial flexible multibody dynamics: nodes carrying a position and three
directors, geometrically exact director beams, joints as quadratic constraints with Lagrange
multipliers, ground contact, loads, and a system that collects them for the one HHT-alpha
integrator (cardillo style: components contribute mass, forces and constraints).

One thing per file:

- ``system.py``        :class:`~.system.System`, the :class:`~pantocosim.core.model.SecondOrderModel`
- ``pattern.py``       the one CSR pattern of every matrix, scatter kernels, SuperLU solve
- ``constraint_set.py`` quadratic constraints g(q, t) = 1/2 q^T H q + b^T q + c + r(t)
                       (vectorised, numba kernel; r: a time law of actuators)
- ``beam3d.py``        the 3D beam element set (:class:`~.beam3d.DirectorBeam`, numba element kernel)
- ``rigid_body.py``    a rigid body carried by a node (mass, centre, inertia tensor)
- ``joints.py``        clamp, revolute and universal joints (node-node or ground)
- ``prismatic.py``     prismatic joint (a guide: sliding without relative rotation)
- ``planar.py``        planar joint (a body kept in a plane)
- ``distance.py``      distance between body points: massless link or linear actuator
- ``ground_contact.py`` penalty-damper ground contact (the pendulum paper, eq. 17)
- ``loads.py``         gravity and nodal moments (the torque pulse)
- ``statics.py``       static equilibrium by Newton with load stepping
- ``linearize.py``     linearised inertia and stiffness on the constraint manifold,
                       natural frequencies (Cardona & Jordi, 9.8)
- ``double_pendulum.py`` the paper's spatial double pendulum and its runner
"""

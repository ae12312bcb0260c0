"""Rigid bodies, distance constraints (links and linear actuators), prismatic and planar
joints of the multibody core against closed forms."""

import numpy as np
import pytest

from pantocosim.core.hht import HHTIntegrator, HHTSettings
from pantocosim.multibody.distance import Distance
from pantocosim.multibody.joints import Clamp, Revolute
from pantocosim.multibody.linearize import natural_frequencies
from pantocosim.multibody.loads import Gravity, NodalForce, NodalMoment
from pantocosim.multibody.planar import Planar
from pantocosim.multibody.prismatic import Prismatic
from pantocosim.multibody.rigid_body import RigidBody
from pantocosim.multibody.statics import solve_static
from pantocosim.multibody.system import System

# Accelerations (~G), velocities, multipliers and energies below come from small,
# well-conditioned solves and products: a few ulp from the closed forms. Their tolerances
# (1e-12 absolute, about 500 ulp(G); relative 1e-12 or 1e-13, 4500 or 450 ulp) are far from
# that floor, and a wrong term in a force or a mass moves them by orders of magnitude more.

G = 9.81


def rotation(axis, angle):
    from scipy.spatial.transform import Rotation
    axis = np.asarray(axis, float)
    return Rotation.from_rotvec(angle * axis / np.linalg.norm(axis)).as_matrix()


def test_rigid_body_kinetic_energy_is_that_of_the_rotating_body():
    """A body turning about its node with angular velocity w: T = 1/2 w . I_O w with
    I_O = I_G + m (|c|^2 1 - c c^T) (parallel axes), for a skew triad and inertia."""
    R = rotation([1, 2, 3], 0.7)
    IG = np.array([[0.3, 0.02, -0.01], [0.02, 0.25, 0.03], [-0.01, 0.03, 0.4]])
    m, c = 2.5, np.array([0.1, -0.3, 0.2])
    s = System()
    n = s.add_node([1.0, 2.0, -1.0], R)
    s.add(RigidBody(n, m, IG, s.X0[n] + c))
    s.assemble()
    w = np.array([0.4, -1.1, 0.7])
    v = np.zeros(s.n_dofs)
    v[s.d_dofs(n)] = np.cross(w, R.T).reshape(9)        # d_i' = w x d_i, node at rest
    IO = IG + m * (c @ c * np.eye(3) - np.outer(c, c))
    assert s.kinetic_energy(v) == pytest.approx(0.5 * w @ IO @ w, rel=1e-13)
    v[s.x_dofs(n)] = u = np.array([0.3, 0.2, -0.5])       # plus a translation of the node
    expected = 0.5 * w @ IO @ w + 0.5 * m * u @ u + m * u @ np.cross(w, c)
    assert s.kinetic_energy(v) == pytest.approx(expected, rel=1e-13)


def test_rigid_body_rejects_an_impossible_inertia():
    s = System()
    n = s.add_node([0, 0, 0])
    s.add(RigidBody(n, 1.0, np.diag([1.0, 0.1, 0.1])))       # 0.1 + 0.1 < 1
    with pytest.raises(ValueError, match="triangle inequality"):
        s.assemble()


def physical_pendulum(b=0.4, m=3.0, Izz=0.05):
    """A body hinged about Z at its node, centre of mass b below it."""
    s = System(constraint_scale=1.0)
    n = s.add_node([0, 0, 0])
    body = s.add(RigidBody(n, m, np.diag([0.04, 0.03, Izz]), [0, -b, 0]))
    s.add(Revolute(n, axis=[0, 0, 1]))
    s.add(Gravity([0, -G, 0]))
    s.assemble()
    return s, n, body


def test_physical_pendulum_frequency_and_hinge_force():
    """omega^2 = m g b / (I_G + m b^2); at rest the hinge carries the weight m g."""
    b, m, Izz = 0.4, 3.0, 0.05
    s, n, _ = physical_pendulum(b, m, Izz)
    q = solve_static(s, loads=[c for c in s.components if isinstance(c, Gravity)])
    w, _ = natural_frequencies(s, q, n=1)
    assert w[0] == pytest.approx(np.sqrt(m * G * b / (Izz + m * b * b)), rel=1e-10)
    hinge = next(c for c in s.components if isinstance(c, Revolute))
    assert np.allclose(-s.multipliers(q, hinge)[:3], [0, m * G, 0], atol=1e-10)


def test_distance_link_pendulum_tension_and_frequency():
    """A ball on a massless link of length L (spherical ends): tension m g at rest, the two
    pendulum modes sqrt(g/L) (its own spin is free: zero frequencies)."""
    L, m, r = 0.8, 2.0, 0.05
    s = System(constraint_scale=1.0)
    n = s.add_node([0, -L, 0])
    s.add(RigidBody(n, m, 0.4 * m * r * r * np.eye(3)))
    link = s.add(Distance(n, None, None, [0, 0, 0]))
    s.add(Gravity([0, -G, 0]))
    s.assemble()
    # hanging at rest is the equilibrium (the free spin leaves the static tangent singular):
    # the multipliers of the consistent start are the static ones, with a = 0
    q, _, a = s.consistent_start(0.0, s.reference())
    assert np.allclose(a, 0.0, atol=1e-12)
    assert link.force(s, q) == pytest.approx(-m * G, rel=1e-12)        # pulls: tension
    w, _ = natural_frequencies(s, q)
    assert np.allclose(np.sort(np.abs(w))[:3], 0.0, atol=1e-4)
    assert np.allclose(w[-2:], np.sqrt(G / L), rtol=1e-10)


def test_linear_actuator_force_and_consistent_velocity():
    """A ball hung from a fixed point by an actuator of length L(t): the actuator pulls with
    m (g - L''); from v = 0 the projected start moves the ball at -L' (straight down)."""
    m = 2.0
    A, W = 0.1, 3.0

    def law(t):
        return 0.5 + A * np.sin(W * t), A * W * np.cos(W * t), -A * W * W * np.sin(W * t)

    s = System(constraint_scale=1.0)
    n = s.add_node([0, -0.5, 0])
    s.add(RigidBody(n, m, 0.01 * np.eye(3)))
    act = s.add(Distance(n, None, None, [0, 0, 0], length=law))
    s.add(Gravity([0, -G, 0]))
    s.assemble()
    t = 0.4
    L, Ld, Ldd = law(t)
    q = s.reference()
    q[s.x_dofs(n)] = [0, -L, 0]
    q, v, a = s.consistent_start(t, q, project_velocity=True)
    assert np.allclose(v[s.x_dofs(n)], [0, -Ld, 0], atol=1e-14)
    assert np.allclose(a[s.x_dofs(n)], [0, -Ldd, 0], atol=1e-12)
    assert act.force(s, q) == pytest.approx(-m * (G - Ldd), rel=1e-12)
    assert s.constraint_drift(q, t) < 1e-15


def test_prismatic_joint_slides_along_its_axis_only():
    """A block on a guide fixed to the ground (inclined by 30 degrees, turned about the
    guide axis): it slides down with g sin 30 (HHT exact for a constant acceleration), a
    moment on it and a force across the guide move nothing else, and the guide's multipliers
    carry m g cos 30 plus the cross force."""
    th = np.radians(30.0)
    axis = np.array([np.cos(th), -np.sin(th), 0.0])
    R = rotation(axis, 0.4) @ rotation([0, 0, 1], -th)        # d1 along the axis, skew d2, d3
    m = 1.5
    s = System(constraint_scale=1.0)
    base = s.add_node([0, 0, 0], R)
    blk = s.add_node([0.2 * np.cos(th), -0.2 * np.sin(th), 0], R)
    s.add(RigidBody(base, 1.0, 0.01 * np.eye(3)))
    s.add(RigidBody(blk, m, np.diag([0.01, 0.02, 0.025])))
    s.add(Clamp(base))
    guide = s.add(Prismatic(base, blk, axis=axis))
    s.add(Gravity([0, -G, 0]))
    s.add(NodalMoment(blk, [0.3, -0.2, 0.5]))
    s.add(NodalForce(blk, [0.0, 0.0, 2.0]))
    s.assemble()
    q, v, a = s.consistent_start(0.0, s.reference())
    assert np.allclose(a[s.x_dofs(blk)], G * np.sin(th) * axis, atol=1e-12)
    assert np.allclose(a[s.d_dofs(blk)], 0.0, atol=1e-12)
    normal = -s.multipliers(q, guide)[3:]                # guide force on the block . w
    weight = np.array([0, -m * G, 2.0])
    assert np.linalg.norm(normal) == pytest.approx(np.linalg.norm(weight - (weight @ axis)
                                                                  * axis), rel=1e-12)
    integ = HHTIntegrator(s, HHTSettings(alpha=-0.05, rtol=1e-11))
    integ.initialize(0.0, q, v, a0=a)
    for _ in range(100):
        integ.step(5e-3)
    travel = integ.q[s.x_dofs(blk)] - s.X0[blk]
    assert np.allclose(travel, 0.5 * G * np.sin(th) * 0.5 ** 2 * axis, atol=1e-9)
    assert np.allclose(integ.q[s.d_dofs(blk)], R.T.reshape(9), atol=1e-12)


def test_planar_joint_keeps_the_body_in_its_plane():
    """A body in the plane z = 0.3 under an out-of-plane force and moment falls freely in
    the plane (a = g) without turning out of it; the joint takes the out-of-plane load."""
    s = System(constraint_scale=1.0)
    n = s.add_node([0.1, 0.2, 0.3], rotation([0, 0, 1], 0.5))
    s.add(RigidBody(n, 2.0, np.diag([0.02, 0.03, 0.04]), [0.25, 0.2, 0.3]))
    plane = s.add(Planar(n, [0, 0, 1]))
    s.add(Gravity([0, -G, 0]))
    s.add(NodalForce(n, [0, 0, 5.0]))
    s.add(NodalMoment(n, [1.0, -0.5, 0.0]))
    s.assemble()
    q, v, a = s.consistent_start(0.0, s.reference())
    assert np.allclose(a[s.x_dofs(n)], [0, -G, 0], atol=1e-12)
    assert np.allclose(a[s.d_dofs(n)], 0.0, atol=1e-12)
    assert s.multipliers(q, plane)[0] == pytest.approx(5.0, rel=1e-12)


def test_rotation_vector_history_is_continuous_over_turns():
    """The node-23 rotation of the pendulum figures: theta u stays continuous through
    theta = pi and 2 pi (scipy returns |phi| <= pi)."""
    from pantocosim.multibody.double_pendulum import rotation_vector
    axis = np.array([0.6, 0.0, -0.8])
    angles = np.linspace(0.0, 5 * np.pi, 41)
    phi = None
    for th in angles:
        phi = rotation_vector(rotation(axis, th), phi)
        assert np.allclose(phi, th * axis, atol=1e-9)

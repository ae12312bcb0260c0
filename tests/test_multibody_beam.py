"""The 3D director beam against closed forms and finite differences."""

import numpy as np
import pytest

from pantocosim.multibody.beam3d import Section, straight_beam
from pantocosim.multibody.ground_contact import GroundContact
from pantocosim.multibody.joints import Clamp, Revolute, Universal
from pantocosim.multibody.linearize import natural_frequencies
from pantocosim.multibody.loads import Gravity, NodalForce, NodalMoment
from pantocosim.multibody.statics import solve_static
from pantocosim.multibody.system import System

E, B, RHO = 2.1e11, 0.01, 7800.0
A, I = B * B, B ** 4 / 12
SEC = Section(E=E, A=A, I1=I, I2=I, J=0.1406 * B ** 4, rho=RHO)


def cantilever(n, load_component):
    s = System()
    beam = straight_beam(s, [0, 0, 0], [1, 0, 0], n, SEC)
    s.add(Clamp(beam.nodes[0]))
    load = s.add(load_component(beam.nodes[-1]))
    s.assemble()
    return s, beam, load


def test_cantilever_tip_deflection_small_load():
    """P L^3/(3 E I) + P L/(k G A); linear Timoshenko elements with one-point integration
    under-estimate it by P L^3/(12 E I n^2)."""
    P = 1.0
    exact = P / (3 * E * I) + P / (SEC.shear_factor * SEC.G * A)
    for n in (10, 20):
        s, beam, load = cantilever(n, lambda node: NodalForce(node, [0.0, -P, 0.0]))
        q = solve_static(s, loads=[load])
        tip = -s.position(q, beam.nodes[-1])[1]
        assert abs(tip / exact - 1) < 1.2 / (4 * n * n)
        assert abs(tip - (exact - P / (12 * E * I * n * n))) < 2e-3 * exact / n ** 2


@pytest.mark.parametrize("fraction", [0.5, 1.0])
def test_cantilever_rolls_up_under_end_moment(fraction):
    """M = 2 pi E I / L bends the cantilever into a full circle: the tip comes back to the
    root with its reference orientation; M = pi E I / L gives a half circle (tip at
    (0, 2 L/pi), turned by pi)."""
    M = fraction * 2 * np.pi * E * I
    s, beam, load = cantilever(16, lambda node: NodalMoment(node, [0.0, 0.0, M]))
    q = solve_static(s, loads=[load], steps=int(16 * fraction))
    tip = s.position(q, beam.nodes[-1])
    Rrel = s.R0[beam.nodes[-1]].T @ s.triad(q, beam.nodes[-1])
    angle = np.arccos(np.clip((np.trace(Rrel) - 1) / 2, -1, 1))
    if fraction == 1.0:
        assert np.linalg.norm(tip) < 1e-10
        assert angle < 1e-7
    else:
        assert np.allclose(tip, [0.0, 2 / np.pi, 0.0], atol=1e-10)
        assert abs(angle - np.pi) < 1e-6
    assert s.constraint_drift(q) < 1e-12


def test_free_free_beam_frequencies():
    """(beta L)^2 sqrt(E I/(rho A L^4)) with beta L = 4.7300, 7.8532, 10.9956 (each twice:
    two bending planes); six rigid-body modes first."""
    s = System()
    straight_beam(s, [0, 0, 0], [1, 0, 0], 40, SEC)
    s.assemble()
    w, _ = natural_frequencies(s, s.reference(), n=12)
    closed = np.array([4.730041, 7.853205, 10.995608]) ** 2 * np.sqrt(E * I / (RHO * A))
    assert np.all(np.abs(w[:6]) < 1e-3 * closed[0])
    for k, tol in enumerate((2e-3, 5e-3, 1e-2)):
        assert np.allclose(w[6 + 2 * k:8 + 2 * k], closed[k], rtol=tol)


def _fd_tangent(fun, x, h=1e-6):
    cols = []
    for j in range(x.size):
        dx = np.zeros_like(x)
        dx[j] = h
        cols.append((fun(x + dx) - fun(x - dx)) / (2 * h))
    return np.stack(cols, axis=-1)


def test_element_tangent_against_central_differences():
    s = System()
    beam = straight_beam(s, [0, 0, 0], [1, 0.2, 0.1], 3, SEC)
    s.assemble()
    rng = np.random.default_rng(0)
    qe = s.reference()[beam.dofs] + 0.05 * rng.standard_normal(beam.dofs.shape)
    f, K = beam.element_forces(qe)
    Kfd = np.stack([_fd_tangent(lambda x: beam.element_forces(x[None], False)[0][0], qe[e])
                    for e in range(qe.shape[0])])
    assert np.max(np.abs(K - Kfd)) < 1e-6 * np.max(np.abs(K))


def test_system_tangent_against_central_differences():
    """The whole Newton tangent: beams, joints, orthonormality, end moment, gravity and a
    penetrating contact (stiffness and damping matrices)."""
    s = System(constraint_scale=1e3)
    b1 = straight_beam(s, [0, 0, 0], [0.5, 0, 0], 2, SEC)
    b2 = straight_beam(s, [0.5, 0, 0], [0.5, -0.3, 0.4], 2, SEC)
    s.add(Revolute(b1.nodes[0], axis=[0, 0, 1]))
    s.add(Universal(b1.nodes[-1], b2.nodes[0], [0, 0, 1], [0.6, 0.8, 0]))
    s.add(NodalMoment(b1.nodes[1], [0.3, 0.2, 5.0]))
    s.add(Gravity())
    s.add(GroundContact(b2.nodes[-1], offset=-0.2, stiffness=1e5, damping=30.0))
    s.assemble()
    rng = np.random.default_rng(3)
    q = s.reference() + 0.02 * rng.standard_normal(s.n_dofs)
    v = rng.standard_normal(s.n_dofs)
    z = np.zeros(s.n_dofs)
    ev = s.evaluate(0.0, q, v, z)
    K = ev.stiffness.toarray()
    Kfd = _fd_tangent(lambda x: s.evaluate(0.0, x, v, z, tangent=False).f_rest, q)
    assert np.max(np.abs(K - Kfd)) < 1e-6 * np.max(np.abs(K))
    C = ev.damping.toarray()
    Cfd = _fd_tangent(lambda x: s.evaluate(0.0, q, x, z, tangent=False).f_rest, v)
    assert np.max(np.abs(C - Cfd)) < 1e-6 * np.max(np.abs(C))

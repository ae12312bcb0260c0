"""Catenary elements: analytic tangents against central finite differences, symmetry, mass
and weight of the ANCF cable (3.1.1) and the tension-only bar (3.1.2)."""

import numpy as np
import pytest

from pantocosim.catenary import ancf_cable, bar


def _fd_jacobian(fun, x, h):
    n = x.size
    J = np.zeros((fun(x).size, n))
    for i in range(n):
        d = np.zeros(n)
        d[i] = h
        J[:, i] = (fun(x + d) - fun(x - d)) / (2 * h)
    return J


def _cable_state(rng, L=0.9):
    # a sagging, stretched, staggered element: positions, slopes (3.2)
    e = np.concatenate([[0.0, 0.2, 5.30], [1.0015, -0.0067, -0.012],
                        [L, 0.194, 5.291], [1.0012, -0.0066, -0.008]])
    return e + rng.normal(0.0, 2e-3, 12)


@pytest.mark.parametrize("EI", [0.0, 195.0])
def test_cable_tangent_matches_finite_differences(EI):
    rng = np.random.default_rng(1)
    e = _cable_state(rng)
    args = dict(Le=0.9, EA=1.4e7, EI=EI, N0=2.0e4)
    f, K = ancf_cable.element_forces(e, **args)
    Kfd = _fd_jacobian(lambda x: ancf_cable.element_forces(x, want_K=False, **args)[0][0],
                       e, 1e-7)
    rel = np.max(np.abs(Kfd - K[0])) / np.max(np.abs(K[0]))
    assert rel < 1e-6, rel
    assert np.max(np.abs(K[0] - K[0].T)) <= 1e-12 * np.max(np.abs(K[0]))  # hyperelastic


def test_cable_tension_measures_gradients():
    """dh/de, dh/dN0 and df/dN0 used by the initial-configuration Newton (3.1.3)."""
    rng = np.random.default_rng(2)
    e = _cable_state(rng)[None, :]
    dX = np.zeros((1, 3))

    def meas(E, N0):
        h, dh, dhN, dfN = (np.empty(1), np.empty((1, 12)), np.empty(1), np.empty((1, 12)))
        ancf_cable.cable_tension_measures(E, dX, np.array([0.9]), np.array([1.4e7]),
                                          np.array([N0]), ancf_cable.GAUSS_XI,
                                          ancf_cable.GAUSS_W, h, dh, dhN, dfN)
        return h, dh, dhN, dfN

    h, dh, dhN, dfN = meas(e, 2e4)
    g = _fd_jacobian(lambda x: meas(x[None, :], 2e4)[0], e[0], 1e-7)[0]
    assert np.max(np.abs(g - dh[0])) < 1e-6 * np.max(np.abs(dh[0]))
    hN = (meas(e, 2e4 + 1.0)[0] - meas(e, 2e4 - 1.0)[0]) / 2.0
    assert abs(hN[0] - dhN[0]) < 1e-6 * abs(dhN[0])
    fN = (ancf_cable.element_forces(e, 0.9, 1.4e7, 0.0, 2e4 + 1.0, False)[0]
          - ancf_cable.element_forces(e, 0.9, 1.4e7, 0.0, 2e4 - 1.0, False)[0]) / 2.0
    assert np.max(np.abs(fN[0] - dfN[0])) < 1e-6 * np.max(np.abs(dfN[0]))


def test_cable_rigid_translation_is_force_free_and_mass_exact():
    L, mu = 0.8, 1.35
    e = np.concatenate([[0, 0, 5.3], [1, 0, 0], [L, 0, 5.3], [1, 0, 0]])
    f, _ = ancf_cable.element_forces(e, L, 1.4e7, 195.0, 0.0)
    assert np.max(np.abs(f)) < 1e-6          # unstretched, straight: no force
    f2, _ = ancf_cable.element_forces(e + np.tile([0.3, -0.1, 0.7, 0, 0, 0], 2), L, 1.4e7,
                                      195.0, 0.0)
    assert np.max(np.abs(f2 - f)) < 1e-6
    M = ancf_cable.mass_matrix(mu, L)
    t = np.tile([0.0, 0.0, 1.0, 0.0, 0.0, 0.0], 2)   # unit z translation
    # sums of four rounded entries (fractions of mu L): a few ulp; rel 1e-14 is 45 ulp
    assert t @ M @ t == pytest.approx(mu * L, rel=1e-14)
    g = ancf_cable.gravity_vector(mu, L, 9.81)
    assert np.allclose(g, -9.81 * M @ t, rtol=1e-13, atol=1e-14)    # products: a few ulp
    assert np.all(np.linalg.eigvalsh(M) > 0)


@pytest.mark.parametrize("l0, slack", [(0.85, False), (0.95, True)])
def test_bar_tangent_matches_finite_differences(l0, slack):
    X = np.array([0.0, 0.2, 6.5, 0.01, 0.21, 5.6])   # length 0.9001
    f, K, s = bar.element_forces(X, l0, 2.0e5, tension_only=True)
    assert bool(s[0]) is slack
    Kfd = _fd_jacobian(lambda x: bar.element_forces(x, l0, 2.0e5, True, False)[0][0], X, 1e-7)
    if slack:
        assert np.all(f == 0.0) and np.all(K == 0.0) and np.all(Kfd == 0.0)
    else:
        assert np.max(np.abs(Kfd - K[0])) < 1e-6 * np.max(np.abs(K[0]))
        N = 2.0e5 * (np.linalg.norm(X[3:] - X[:3]) - l0) / l0
        # the stretch l - l0 = 0.05 m of a 0.9 m bar carries ulp(0.9 m) / 0.05 m = 2e-15
        # relative error per rounding: rel 1e-12 is some 500 of them
        assert np.linalg.norm(f[0, 3:]) == pytest.approx(N, rel=1e-12)


def test_bilateral_bar_in_compression_has_tangent():
    X = np.array([0.0, 0.0, 6.5, 0.0, 0.05, 5.6])
    f, K, s = bar.element_forces(X, 0.95, 2.0e5, tension_only=False)
    # compressed, not slack: the internal force at the lower node j points up
    assert not s[0] and f[0, 5] > 0
    Kfd = _fd_jacobian(lambda x: bar.element_forces(x, 0.95, 2.0e5, False, False)[0][0],
                       X, 1e-7)
    assert np.max(np.abs(Kfd - K[0])) < 1e-6 * np.max(np.abs(K[0]))

"""One straight wire against analytic solutions: tensioned-beam frequencies, the exact
(elastic) catenary under self weight, and the moving constant force on a taut string
(the closed form of a constant force moving on a taut string), the last one on the shared HHT-alpha integrator."""

import numpy as np
from scipy.integrate import quad
from scipy.optimize import brentq

from pantocosim.catenary.mesh import straight_wire
from pantocosim.catenary.model import CatenaryModel
from pantocosim.core.hht import FactorReuse, HHTIntegrator, HHTSettings

MU, EA, EI, T, L = 1.35, 1.4e7, 195.0, 20000.0, 60.0


def test_tensioned_beam_frequencies():
    model = CatenaryModel(straight_wire(L, 60, MU, EA, EI, T, gravity=0.0))
    f, phi = model.modes(20)
    n = np.arange(1, 11)
    k = n * np.pi / L
    exact = np.sqrt((EI * k**4 + T * k**2) / MU) / (2 * np.pi)
    # vertical and lateral bending modes are degenerate pairs
    for fam in (f[0::2], f[1::2]):
        err = np.max(np.abs(fam / exact - 1))
        assert err < 0.005, err
    # the z-part of the lowest pair spans sin(pi x/L)
    S = model.structure
    zd = S.fmap[model.mesh.node_dofs[1:-1, 2]]
    x = S.absolute(model.x_static)[model.mesh.node_dofs[1:-1, 0]]
    s1 = np.sin(np.pi * x / L)
    z = phi[zd, :2]
    proj = z @ np.linalg.lstsq(z, s1, rcond=None)[0]
    assert np.linalg.norm(proj - s1) < 1e-3 * np.linalg.norm(s1)


def _exact_elastic_catenary_sag(w, N0, EA, L):
    """Pinned ends at equal height, reference length L with pre-tension N0 and the
    element's law N = N0 + EA (lambda^2 - 1)/2, tension T = N lambda: integrate
    dx/dchi = lambda H / T, dz/dchi = lambda V / T with V = w (chi - L/2); for a constant
    stretch this is the cosh catenary."""

    def stretch(Tt):
        lam = 1.0
        for _ in range(60):
            lam -= ((N0 + EA * (lam * lam - 1) / 2) * lam - Tt) / (N0 + EA * (3 * lam * lam - 1) / 2)
        return lam

    def dx(c, H):
        Tt = np.hypot(H, w * (c - L / 2))
        return stretch(Tt) * H / Tt

    H = brentq(lambda H: quad(dx, 0, L, args=(H,), epsabs=1e-13, epsrel=1e-13)[0] - L,
               1e3, 1e5, xtol=1e-10)

    def dz(c):
        Tt = np.hypot(H, w * (c - L / 2))
        return -stretch(Tt) * w * (c - L / 2) / Tt

    return quad(dz, 0, L / 2, epsabs=1e-14, epsrel=1e-13)[0], H


def test_static_sag_matches_exact_catenary():
    g = 9.81
    model = CatenaryModel(straight_wire(L, 60, MU, EA, EI, T, gravity=g))
    x = model.structure.full(model.q_static)
    sag_fe = -x[model.mesh.node_dofs[30, 2]]
    sag, H = _exact_elastic_catenary_sag(MU * g, T, EA, L)
    assert abs(sag_fe / sag - 1) < 1e-3, (sag_fe, sag)
    # bending (EI) is the only modelled difference: 2e-5 of the sag here
    assert abs(sag_fe / sag - 1) < 1e-4
    # the same number from the cosh formula of an inextensible chain with the same H
    # differs by the elastic stretch only (H/EA ~ 0.15 %)
    cosh = H / (MU * g) * (np.cosh(MU * g * L / (2 * H)) - 1)
    assert abs(cosh / sag - 1) < 3e-3
    assert model.equilibrium_residual(model.q_static) < 1e-8


def test_moving_force_on_taut_string():
    F = 10.0
    c = np.sqrt(T / MU)
    beta = 0.5
    v = beta * c
    model = CatenaryModel(straight_wire(L, 120, MU, EA, 0.0, T, gravity=0.0), x0=[0.0],
                          speed=v)
    integ = HHTIntegrator(model, HHTSettings(alpha=-0.05, reuse_factorization=FactorReuse.ACROSS_STEPS))
    integ.initialize(0.0, model.q_static, None, [F])
    h = 1e-3
    z0 = model.wire_height(0.0, model.q_static)[0]
    ts, ws = [], []
    for _ in range(int(L / v / h)):
        integ.step(h, [F])
        ts.append(integ.t)
        ws.append(model.wire_height(integ.t, integ.q)[0] - z0)
    ts, ws = np.array(ts), np.array(ws)
    n = np.arange(1, 20001)[:, None]
    amp = 2 * F * L / (n**2 * np.pi**2 * T * (1 - beta**2))
    exact = (amp * (np.sin(n * np.pi * v * ts / L) - beta * np.sin(n * np.pi * c * ts / L))
             * np.sin(n * np.pi * v * ts / L)).sum(0)
    err = np.max(np.abs(ws - exact)) / np.max(np.abs(exact))
    assert err < 0.02, err
    # the dynamic peak exceeds the quasi-static one F L / (4 T (1 - beta^2)) as it should
    assert np.max(ws) > F * L / (4 * T)

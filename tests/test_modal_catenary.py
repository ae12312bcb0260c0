"""The modal catenary: the physics, not the speed.

- with every mode it is the linear model (Newton and the closed-form step);
- its static correction keeps the static response exact at any pantograph position, with
  one or two pantographs, and with slack droppers (a slack dropper carries no force and
  leaves the wire as free as in the linear model);
- the closed-form step equals Newton-Raphson on the same model, droppers slackening;
- the modes from the banded eigensolver are those of the dense problem;
- the default cutoff meets the accuracy targets against the linear model (slow).
"""

import dataclasses

import numpy as np
import pytest
import scipy.linalg as sla

from pantocosim.catenary.definition import load_catenary, with_spans
from pantocosim.catenary.linear import LinearCatenary
from pantocosim.catenary.modal import ModalCatenary
from pantocosim.catenary.modal_step import ModalHHT
from pantocosim.core.hht import HHTIntegrator, HHTSettings
from pantocosim.core.stepper_contract import closed_form_step

V = 300 / 3.6
H = 1e-3


@pytest.fixture(scope="module")
def line4():
    return with_spans(load_catenary("en50318"), 4)


@pytest.fixture(scope="module")
def lin4(line4):
    return LinearCatenary(line4, x0=[30.0], speed=V)


@pytest.fixture(scope="module")
def modal20(lin4):
    return ModalCatenary(linear=lin4, cutoff_hz=20.0, keep_basis=True)


def _load(t):
    """A moving force that lifts the wire enough to slacken droppers."""
    return np.array([150.0 + 120.0 * np.sin(2 * np.pi * 6 * t)
                     + 60.0 * np.sin(2 * np.pi * 13 * t)])


def _newton(model, steps, load=_load):
    integ = HHTIntegrator(model, HHTSettings(alpha=-0.05, rtol=1e-12, etol=0.0))
    integ.initialize(0.0, model.static_state(load(0.0)), None, load(0.0))
    out = [model.wire_height(0.0, integ.q)[0]]
    for n in range(steps):
        integ.step(H, load((n + 1) * H))
        out.append(model.wire_height(integ.t, integ.q)[0])
    return np.array(out), integ


@pytest.mark.slow
def test_modal_with_every_mode_equals_linear():
    line2 = with_spans(load_catenary("en50318"), 2)
    li = LinearCatenary(line2, x0=[20.0], speed=V)
    mo = ModalCatenary(linear=li, cutoff_hz=np.inf)
    assert mo.m == li.n_dofs and not mo.corrected and mo.n_dofs == li.n_dofs
    z_li, i_li = _newton(li, 200)
    z_mo, i_mo = _newton(mo, 200)
    assert np.max(np.abs(z_li - z_mo)) < 1e-9
    assert np.max(np.abs(li.support_uplift(i_li.q) - mo.support_uplift(i_mo.q))) < 1e-9
    assert i_li.model._slack_committed.any()                 # droppers did slacken
    assert np.array_equal(li._slack_committed, mo._slack_committed)


@pytest.mark.parametrize("cutoff", [5.0, 20.0])
def test_static_flexibility_at_the_contact_point_is_exact_anywhere(lin4, modal20, cutoff):
    """Under an upward force the droppers keep taut at, the modal statics at any position
    (nodes, inside elements, at supports) equal the linear model's, and so does the whole
    displacement field: the truncated modes' static part is in the residual."""
    mo = modal20 if cutoff == 20.0 else ModalCatenary(linear=lin4, cutoff_hz=cutoff,
                                                       keep_basis=True)
    assert 0 < mo.m < 400 and mo.corrected
    xs = np.concatenate([np.linspace(62.0, 178.0, 23), [120.0, 120.5, 121.0, 180.0, 60.0]])
    F = 40.0
    worst = 0.0
    for x in xs:
        t = (x - 30.0) / V                      # the pantograph's position at time t
        st = lin4.static_solution([(x, F)])
        assert not st.slack.any()
        y = mo.static_state(np.array([F]), t=t)
        up = lin4.wire_height(t, st.q)[0] - lin4.wire_height(t, lin4.q_static)[0]
        worst = max(worst, abs(lin4.wire_height(t, st.q)[0] - mo.wire_height(t, y)[0]) / up)
    assert worst < 1e-9
    dq = st.q - lin4.q_static
    assert np.max(np.abs(mo.full_displacement(t, y) - dq)) < 1e-9 * np.max(np.abs(dq))


def test_two_pantographs_statics_exact(line4):
    """The residual flexibility between two contact points (cross terms of G) is exact."""
    li = LinearCatenary(line4, x0=[70.0, 125.5], speed=V)
    mo = ModalCatenary(linear=li, cutoff_hz=10.0)
    F = np.array([30.0, 45.0])
    st = li.static_solution(list(zip(li.x0, F)))
    assert not st.slack.any()
    y = mo.static_state(F)
    assert np.max(np.abs(li.wire_height(0.0, st.q) - mo.wire_height(0.0, y))) < 1e-12
    assert np.max(np.abs(li.support_uplift(st.q) - mo.support_uplift(y))) < 1e-12


@pytest.mark.parametrize("F", [300.0, 800.0, 1500.0])
def test_a_slack_dropper_carries_no_force_in_the_modal_model(lin4, modal20, F):
    """With 20 Hz of modes, a force that slackens droppers: the modal statics have the
    linear model's slack set and its displacement field (the linear model's slackening is
    checked against droppers taken out of K0 in test_linear_catenary): each slack dropper's
    force leaves exactly, including the local flexibility the modes cannot show."""
    mo = modal20
    st = lin4.static_solution([(30.0, F)])
    y = mo.static_state(np.array([F]))
    N_mo = mo.dropper_forces(y)
    assert st.slack.any()
    assert np.array_equal(N_mo == 0.0, st.slack)
    assert np.all(N_mo[~st.slack] > 0.0)
    # a slack dropper is compressed as far as in the linear model (its ends move freely)
    e_lin = lin4.droppers.vectors.dots(st.q - lin4.q_static)
    e_mo = mo.T @ y
    assert np.max(np.abs(e_lin - e_mo)) < 1e-9 * np.max(np.abs(e_lin))
    dq = st.q - lin4.q_static
    assert np.max(np.abs(mo.full_displacement(0.0, y) - dq)) < 1e-9 * np.max(np.abs(dq))


@pytest.mark.slow
def test_closed_form_step_equals_newton_with_slackening(line4):
    li = LinearCatenary(line4, x0=(60.0,), speed=V)
    newton, closed = (ModalCatenary(linear=li, cutoff_hz=20.0) for _ in range(2))
    y0 = newton.static_state(_load(0.0))
    ref = HHTIntegrator(newton, HHTSettings(alpha=-0.05, rtol=1e-12, etol=0.0))
    ref.initialize(0.0, y0, None, _load(0.0))
    cf = closed_form_step(closed, HHTSettings(alpha=-0.05))
    assert isinstance(cf, ModalHHT)
    cf.initialize(0.0, y0, None, _load(0.0))
    err, slack_steps, switches = 0.0, 0, 0
    for n in range(250):
        t1 = (n + 1) * H
        ref.step(H, _load(t1))
        cf.begin(H, [(cp.dofs, cp.weights) for cp in closed.contact_points(t1)])
        while not cf.finish(_load(t1)):
            pass
        err = max(err, float(np.max(np.abs(cf.q - ref.q))))
        slack_steps += bool(cf.committed.any())
        switches += cf.passes > 1
    assert slack_steps > 20 and switches > 0
    assert err < 1e-10                 # on modal coordinates of ~0.1 (uplifts ~0.1 m)
    N = closed.dropper_forces(cf.q)
    assert np.all(N[cf.committed] == 0.0) and np.all(N >= 0.0)


def test_banded_modes_are_the_dense_ones():
    from pantocosim.catenary.modal_basis import modes_below

    li = LinearCatenary(with_spans(load_catenary("en50318"), 2), x0=[20.0], speed=V)
    S = li.structure
    f, Phi = modes_below(li.K0, li.M, 40.0,
                         bands=(S.lower_band(li.K0_data), S.lower_band(S.M_data)))
    lam_d = sla.eigh(li.K0.toarray(), li.M.toarray(), eigvals_only=True)
    lam = (2 * np.pi * f) ** 2
    assert f.size == int(np.sum(lam_d < (2 * np.pi * 40.0) ** 2))
    assert np.max(np.abs(lam - lam_d[:f.size]) / lam_d[:f.size]) < 1e-9
    assert np.max(np.abs(Phi.T @ (li.M @ Phi) - np.eye(f.size))) < 1e-8
    res = li.K0 @ Phi - (li.M @ Phi) * lam
    assert np.max(np.linalg.norm(res, axis=0) / (lam * np.linalg.norm(li.M @ Phi, axis=0))) \
        < 1e-8


@pytest.mark.slow
def test_default_cutoff_meets_the_targets_against_linear():
    """A short en50318-300 run (the hardest preset for the modal model: 0.69 of the wave
    speed) with the default cutoff, against the linear model at the same time step: the
    modal model's accuracy targets (mean 0.5 %, sigma 2 %, actual max / min 3 %)."""
    from pantocosim.catenary.models import DEFAULT_MODAL_CUTOFF_HZ
    from pantocosim.master.run import prepare, run_monolithic
    from pantocosim.master.scenario import load_scenario

    sc = dataclasses.replace(load_scenario("en50318-300"), window_supports=(4, 5),
                             modal_cutoff_hz=DEFAULT_MODAL_CUTOFF_HZ)
    stats = {}
    for kind in ("linear", "modal"):
        res = run_monolithic(prepare(dataclasses.replace(sc, catenary_model=kind)), None,
                             progress=False)
        assert res.error is None
        stats[kind] = res.statistics()[0]
    ref, got = stats["linear"], stats["modal"]
    rel = lambda q: abs(getattr(got, q) - getattr(ref, q)) / abs(getattr(ref, q))  # noqa: E731
    assert rel("mean_n") < 0.005
    assert rel("std_n") < 0.02
    assert rel("max_n") < 0.03 and rel("min_n") < 0.03


def test_screened_slack_set_is_the_double_precision_one(modal20):
    """The slack check with its kept reference and single-precision rows gives the set of
    the full double-precision product N0 + k_a T y, also for forces within 1e-8 N of zero
    and over a drifting sequence of states (reference kept, rows taken, references
    renewed)."""
    from pantocosim.catenary import modal_kernels as kern
    from pantocosim.catenary.modal_step import ModalHHT

    st = ModalHHT(modal20, HHTSettings(alpha=-0.05))
    dr, T = modal20.droppers, modal20.T_K
    rng = np.random.default_rng(7)
    y = np.zeros(modal20.n_dofs)
    zero = np.zeros_like(y)
    slack = np.zeros(len(dr), dtype=bool)
    near, checked = 0, 0
    for n in range(300):
        y[:T.shape[1]] += rng.standard_normal(T.shape[1]) * 2e-4 / (1.0 + np.arange(T.shape[1]))
        if n % 3 == 0:                  # put some droppers' forces right at the threshold
            for d in rng.choice(len(dr), 4, replace=False):
                target = rng.choice([-1.0, 1.0]) * 10.0 ** rng.uniform(-8, 0)
                N = dr.N0[d] + dr.ka[d] * (T[d] @ y[:T.shape[1]])
                y[:T.shape[1]] += (target - N) / dr.ka[d] * T[d] / (T[d] @ T[d])
                near += 1
        kern.screen_slack(*st._screen, y, zero, *st._screen_work, slack)
        exact = dr.tension_only & (dr.N0 + dr.ka * (T @ y[:T.shape[1]]) < 0.0)
        assert np.array_equal(slack, exact), n
        checked += int(exact.any())
    assert near >= 400 and checked > 50

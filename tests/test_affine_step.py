"""Closed-form HHT steps of the linear catenary: the same solution as
Newton-Raphson on the linear model, with exact dropper slackening; the monolithic step
condensed on the contact points equals the assembled monolithic Newton solution, for a
linear (closed-form) and a nonlinear (Newton) pantograph; the condensed penalty law."""

import numpy as np
import pytest

from pantocosim.catenary.definition import load_catenary, with_spans
from pantocosim.catenary.linear import LinearCatenary
from pantocosim.core.affine_hht import AffineHHT
from pantocosim.interaction.penalty_contact import PenaltyContact
from pantocosim.core.hht import HHTIntegrator, HHTSettings

V = 300 / 3.6
H = 1e-3


def _load(t):
    """A moving force that lifts the wire enough to slacken droppers."""
    return np.array([150.0 + 120.0 * np.sin(2 * np.pi * 6 * t) + 60.0 * np.sin(2 * np.pi * 13 * t)])


@pytest.fixture(scope="module")
def line4():
    return with_spans(load_catenary("en50318"), 4)


def _pair(line4):
    newton = LinearCatenary(line4, x0=(60.0,), speed=V)
    closed = LinearCatenary(line4, x0=(60.0,), speed=V)
    q0 = newton.static_state([150.0])
    ref = HHTIntegrator(newton, HHTSettings(alpha=-0.05, rtol=1e-12, etol=0.0))
    ref.initialize(0.0, q0, None, _load(0.0))
    aff = AffineHHT(closed.affine_form(), HHTSettings(alpha=-0.05), keep_free_response=True)
    aff.initialize(0.0, q0, None, _load(0.0))
    return newton, closed, ref, aff


def _affine_step(aff, model, F):
    aff.begin(H, [(cp.dofs, cp.weights) for cp in model.contact_points(aff.t + H)])
    while not aff.finish(F):
        pass


@pytest.mark.slow
def test_closed_form_step_equals_newton_with_exact_slackening(line4):
    newton, closed, ref, aff = _pair(line4)
    err, slack_steps, switches = 0.0, 0, 0
    for n in range(400):
        t1 = (n + 1) * H
        ref.step(H, _load(t1))
        _affine_step(aff, closed, _load(t1))
        err = max(err, float(np.max(np.abs(aff.q - ref.q))))
        slack_steps += bool(aff.committed.any())
        switches += aff.passes > 1
    assert slack_steps > 20 and switches > 0          # droppers did slacken and re-tension
    assert err < 1e-9                                 # m, on uplifts of ~0.1 m
    # a slack dropper of the closed-form state carries no force
    N = closed.dropper_forces(aff.q)
    assert np.all(N[aff.committed] == 0.0) and np.all(N >= 0.0)


def test_kept_products_follow_the_state(line4):
    """The right-hand side comes from kept products [K d, K v, K a, M v, M a] advanced by
    K Delta from the step's own equation: after 400 steps with droppers slackening they equal
    the products formed from the state to round-off."""
    from pantocosim.core import affine_hht
    from pantocosim.core.affine_kernels import state_products

    _, closed, _, aff = _pair(line4)
    for n in range(400):
        _affine_step(aff, closed, _load((n + 1) * H))
    assert aff.n_steps - aff._synced == 400 < affine_hht.RESYNC_STEPS    # never re-formed
    P = np.zeros_like(aff._P)
    state_products(aff._M, aff._K, aff.q, aff.form.q_ref, aff.v, aff.a, P,
                   np.zeros(aff.form.n), np.zeros(aff.form.n))
    for kept, formed in zip(aff._P, P):
        assert np.max(np.abs(kept - formed)) < 1e-8 * np.max(np.abs(formed))


def test_rollback_repeats_a_step_bitwise(line4):
    _, closed, _, aff = _pair(line4)
    for n in range(30):
        _affine_step(aff, closed, _load((n + 1) * H))
    saved = aff.get_state()
    _affine_step(aff, closed, np.array([400.0]))
    first = aff.q.copy()
    aff.set_state(saved)
    _affine_step(aff, closed, np.array([400.0]))
    assert np.array_equal(aff.q, first)


def test_an_older_state_comes_back_with_its_products(line4):
    """Restoring a state saved several steps back (its kept products are no longer in a
    buffer, they come from the saved state): the steps repeat bit for bit."""
    _, closed, _, aff = _pair(line4)
    for n in range(30):
        _affine_step(aff, closed, _load((n + 1) * H))
    saved = aff.get_state()
    for n in range(30, 40):
        _affine_step(aff, closed, _load((n + 1) * H))
    first = aff.q.copy()
    aff.set_state(saved)
    for n in range(30, 40):
        _affine_step(aff, closed, _load((n + 1) * H))
    assert np.array_equal(aff.q, first)


def test_a_saved_state_copies_its_products_only_when_they_would_be_overwritten(line4):
    """A state saved and freed before the next step never copies the kept products; one still
    held when a step reuses its buffer gets its own copy first, and one pickled carries
    them: either way the steps from it repeat bit for bit."""
    import pickle

    _, closed, _, aff = _pair(line4)
    for n in range(20):
        _affine_step(aff, closed, _load((n + 1) * H))
    freed = aff.get_state()
    assert freed["products"].buffer is aff._P                # no copy at the save
    del freed
    _affine_step(aff, closed, _load(21 * H))
    _affine_step(aff, closed, _load(22 * H))
    held = aff.get_state()
    frozen = pickle.loads(pickle.dumps(held))
    assert frozen["products"].buffer is None
    for n in range(22, 26):
        _affine_step(aff, closed, _load((n + 1) * H))
    assert held["products"].buffer is None                   # copied before the overwrite
    first = aff.q.copy()
    for state in (held, frozen):
        aff.set_state(state)
        for n in range(22, 26):
            _affine_step(aff, closed, _load((n + 1) * H))
        assert np.array_equal(aff.q, first)


@pytest.mark.parametrize("pantograph", ["en50318-2mass", "dsa380-rigid"])
def test_condensed_monolithic_equals_the_assembled_newton_solution(pantograph):
    from pantocosim.interaction.condensed import CondensedStepper
    from pantocosim.interaction.stepper_factory import AssembledStepper, make_stepper
    from pantocosim.master.run import prepare
    from pantocosim.master.scenario import load_scenario
    import dataclasses

    sc = load_scenario("tests/data/short-en50318.toml")
    pans = [dataclasses.replace(sc.pantographs[0], model=pantograph)]
    sc = dataclasses.replace(sc, catenary_model="linear", pantographs=pans)
    prep = prepare(sc)
    settings = HHTSettings.for_runs(sc.alpha, 1e-10)
    fast = make_stepper(prep.catenary, settings, prep.pantographs, prep.contact)
    assert isinstance(fast, CondensedStepper)
    ref = AssembledStepper(prep.catenary, prep.pantographs, prep.contact,
                           HHTSettings.for_runs(sc.alpha, 1e-10))
    q0 = np.concatenate([prep.q_cat0] + prep.q_pan0)
    for stepper in (fast, ref):
        stepper.initialize(0.0, q0)
    cat = prep.catenary
    dF = du = 0.0
    for _ in range(250):
        fast.step(sc.dt)
        ref.step(sc.dt)
        (F1, z1, _), (F2, z2, _) = fast.contacts(), ref.contacts()
        dF = max(dF, abs(F1[0] - F2[0]), abs(z1[0] - z2[0]) * 5e4)
        du = max(du, float(np.max(np.abs(cat.support_uplift(fast.structure_q)
                                          - cat.support_uplift(ref.structure_q)))))
    assert F2[0] > 50.0
    assert dF < 1e-5            # N (contact force; height error times k_H)
    assert du < 1e-9            # m (support uplift)


def test_condensed_penalty_law_solves_the_law_with_the_structure_compliance():
    contact = PenaltyContact(50_000.0, 20.0)
    G = np.array([[4e-5, 1e-6], [1e-6, 5e-5]])
    Hm = np.array([[2e-2, 1e-4], [1e-4, 3e-2]])
    z0, v0 = np.array([5.3, 5.3]), np.array([0.01, -0.02])
    for z_p, lost in ((np.array([5.303, 5.302]), None), (np.array([5.303, 5.2999]), 1)):
        v_p = np.array([0.0, 0.05])
        F, Jz, Jv, settled = contact.condensed(z_p, v_p, z0, v0, G, Hm)
        assert settled
        z_w, v_w = z0 + G @ F, v0 + Hm @ F
        law = [contact.force(z_p[k], z_w[k], v_p[k], v_w[k]) for k in range(2)]
        # law: k (z_p - z_w) of 5.3 m heights, floor k ulp(5.3 m) = 4.4e-11 N; atol ~20 of them
        assert np.allclose(F, law, rtol=1e-12, atol=1e-9)
        if lost is not None:
            assert F[lost] == 0.0 and F[1 - lost] > 0.0
        # the Jacobian against central differences
        e = 1e-7
        for j in range(2):
            dz = np.zeros(2)
            dz[j] = e
            Fp = contact.condensed(z_p + dz, v_p, z0, v0, G, Hm)[0]
            Fm = contact.condensed(z_p - dz, v_p, z0, v0, G, Hm)[0]
            assert np.allclose((Fp - Fm) / (2 * e), Jz[:, j], rtol=1e-6, atol=1e-3)

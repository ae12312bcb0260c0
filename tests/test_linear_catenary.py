"""Linear and modal catenary: the physics, not the speed.

- linear equals nonlinear under a small moving load to the linearisation's round-off, and the
  difference scales like the load squared;
- a slack dropper carries no force: its force is exactly 0 and the solution equals a model
  whose dropper was taken out of K0 (and the slack pattern is the nonlinear one's);
- (the modal model's physics: tests/test_modal_catenary.py)
- the model registry, the scenario field and the monolithic run with each model.
"""

import dataclasses

import numpy as np
import pytest

from pantocosim.catenary.definition import load_catenary, with_spans
from pantocosim.catenary.linear import LinearCatenary
from pantocosim.catenary.model import CatenaryModel
from pantocosim.core.hht import HHTIntegrator, HHTSettings

V = 300 / 3.6


@pytest.fixture(scope="module")
def line4():
    return with_spans(load_catenary("en50318"), 4)


@pytest.fixture(scope="module")
def models(line4):
    return (CatenaryModel(line4, x0=[30.0], speed=V), LinearCatenary(line4, x0=[30.0], speed=V))


def _moving_load(model, F, steps=250):
    integ = HHTIntegrator(model, HHTSettings.for_runs(-0.05, 1e-10))
    integ.initialize(0.0, model.static_state(np.array([F])), np.zeros(model.n_dofs),
                     np.array([F]))
    z = [model.wire_height(0.0, integ.q)[0]]
    for _ in range(steps):
        integ.step(1e-3, np.array([F]))
        z.append(model.wire_height(integ.t, integ.q)[0])
    return np.array(z), integ


@pytest.mark.slow
def test_linear_equals_nonlinear_for_a_small_moving_load(models):
    nl, li = models
    errs = []
    for F in (1.0, 2.0, 4.0):
        z_nl, _ = _moving_load(nl, F)
        z_li, _ = _moving_load(li, F)
        errs.append(np.max(np.abs(z_nl - z_li)))
    # the wire's motion under the load is millimetres; the linearisation error a 1e-6 of it
    assert errs[0] < 1e-7
    ratios = np.array(errs[1:]) / np.array(errs[:-1])
    assert np.all(np.abs(ratios - 4.0) < 0.4), (errs, ratios)   # ~ F^2


def test_linear_statics_match_nonlinear_to_second_order(models):
    nl, li = models
    d = []
    for F in (2.0, 4.0):
        a = nl.static_solution([(60.0, F)]).q
        b = li.static_solution([(60.0, F)]).q
        d.append(np.max(np.abs(a - b)))
    assert d[0] < 1e-6 and abs(d[1] / d[0] - 4.0) < 0.2
    assert li.equilibrium_residual(li.q_static) < 1e-9


def test_a_slack_dropper_carries_no_force(models, line4):
    nl, li = models
    x, F = 60.0, 1500.0
    st = li.static_solution([(x, F)])
    forces = li.dropper_forces(st.q)
    slack = st.slack
    assert slack.any() and not slack.all()
    assert np.all(forces[slack] == 0.0)                 # exactly
    assert np.all(forces[~slack] > 0.0)
    # the same as a linear model whose slack droppers' axial stiffness k_a b b^T is taken
    # out of K0 and whose force N0 b leaves the load (solved directly, no Woodbury)
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla

    dr = li.droppers
    K = li.K0.tolil()
    P = np.zeros(li.n_dofs)
    from pantocosim.catenary.statics import point_load_vector

    P += point_load_vector(li.structure, li.locator, [(x, F)])
    for d in np.flatnonzero(slack):
        b = dr.vectors.dense(d)
        K = K - dr.ka[d] * sp.csr_matrix(np.outer(b, b))
        P += dr.N0[d] * b
    dq = spla.spsolve(sp.csc_matrix(K), P - li.r0)
    assert np.max(np.abs(li.q_static + dq - st.q)) < 1e-9 * np.max(np.abs(dq))
    # the slack pattern near the load is the nonlinear model's at a moderate load
    F2 = 700.0
    s_li = li.static_solution([(x, F2)]).slack
    s_nl = nl.dropper_forces(nl.static_solution([(x, F2)]).q) == 0.0
    assert s_li.any() and np.array_equal(s_li, s_nl)


def test_dynamic_slackening_keeps_one_factorization(line4):
    li = LinearCatenary(line4, x0=[30.0], speed=V)
    z, integ = _moving_load(li, 400.0, steps=300)
    assert li._slack_committed.any() or li.dropper_forces(integ.q).min() == 0.0
    # M (initial acceleration) and the run's Newton matrix: nothing else was factorized
    assert set(li._factors) <= {(1.0, 0.0, 0.0), HHTSettings.for_runs(-0.05).newton_coefficients(
        1e-3)} | {(0.0, 0.0, 1.0)}
    # the run of the linear model with slackening follows the nonlinear one: the static
    # states under 400 N differ by the geometric nonlinearity (5.0 mm of a 90 mm motion),
    # which the moving load has left behind after 0.25 s (0.3 mm)
    nl = CatenaryModel(line4, x0=[30.0], speed=V)
    z_nl, _ = _moving_load(nl, 400.0, steps=300)
    assert np.max(np.abs(z - z_nl)) < 0.06 * np.ptp(z_nl)
    assert np.max(np.abs(z - z_nl)[250:]) < 0.005 * np.ptp(z_nl)


def test_registry_and_scenario_field(tmp_path):
    from pantocosim.catenary.models import CATENARY_MODELS, MODEL_NAMES, model_name
    from pantocosim.core.errors import ParameterError
    from pantocosim.master.scenario import load_scenario, scenario_path

    assert MODEL_NAMES == ("nonlinear", "linear", "modal") == tuple(CATENARY_MODELS)
    assert model_name(1) == "linear" and model_name("modal") == "modal"
    with pytest.raises(ParameterError):
        model_name(3)
    sc = load_scenario("en50318-300")
    assert sc.catenary_model == "nonlinear"
    text = scenario_path("en50318-300").read_text()
    bad = tmp_path / "bad.toml"
    bad.write_text(text.replace("[simulation]", '[simulation]\ncatenary_model = "spline"'))
    with pytest.raises(ParameterError, match="catenary_model"):
        load_scenario(bad)
    good = tmp_path / "good.toml"
    good.write_text(text.replace("[simulation]", '[simulation]\ncatenary_model = "linear"'))
    assert load_scenario(good).catenary_model == "linear"


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["linear", "modal"])
def test_monolithic_run_with_each_model(kind):
    """A short monolithic run of the regression scenario with the linear and modal models:
    contact forces within a few percent of the nonlinear run."""
    from pantocosim.master.regress import REGRESSION_DIR
    from pantocosim.master.run import prepare, run_monolithic
    from pantocosim.master.scenario import load_scenario

    sc = load_scenario(REGRESSION_DIR / "short-en50318.toml")
    sc = dataclasses.replace(sc, duration_s=0.5, newton_rtol=1e-6)     # default cutoff
    forces = {}
    for k in ("nonlinear", kind):
        prep = prepare(dataclasses.replace(sc, catenary_model=k))
        res = run_monolithic(prep, None, progress=False)
        assert res.error is None
        forces[k] = np.asarray(res.columns["contact_force_1"])
    ref, got = forces["nonlinear"], forces[kind]
    print(kind, np.mean(ref), np.mean(got), np.std(ref), np.std(got), np.max(np.abs(got - ref)))
    if kind == "linear":
        assert np.max(np.abs(got - ref)) < 0.03 * np.mean(ref)
    else:
        # the modal model at its default cutoff (docs/modal-cutoff.md): the accuracy targets
        # on the mean and sigma; its own truncation adds a few newtons to max |dF|
        assert abs(np.mean(got) - np.mean(ref)) < 0.005 * np.mean(ref)
        assert abs(np.std(got) - np.std(ref)) < 0.02 * np.std(ref)
        assert np.max(np.abs(got - ref)) < 0.07 * np.mean(ref)

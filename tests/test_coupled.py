"""Monolithic pantograph-catenary model, static start, run outputs, scenario validation
and the coupling algorithms on in-process subsystems."""

import json
from pathlib import Path

import numpy as np
import pytest

from pantocosim.interaction.coupled import CoupledSystem, RigidWire
from pantocosim.interaction.penalty_contact import PenaltyContact
from pantocosim.core.errors import ParameterError
from pantocosim.core.hht import HHTIntegrator, HHTSettings
from pantocosim.master.cli import main
from pantocosim.master.cosim import run_cosim
from pantocosim.master.run import prepare, run_monolithic
from pantocosim.master.scenario import load_scenario
from pantocosim.pantograph.presets import load_pantograph

SHORT = str(Path(__file__).with_name("data") / "short-en50318.toml")
#: agreement of two evaluations of a contact wire height [m]
HEIGHT_TOL = 1e-12


@pytest.fixture(scope="module")
def short_monolithic():
    prep = prepare(SHORT)
    return prep, run_monolithic(prep, None, progress=False)


@pytest.mark.parametrize("name", ["dsa380-rigid", "dsa380-lumped3", "en50318-2mass"])
def test_rigid_wire_gives_constant_force_equal_to_uplift(name):
    pant = load_pantograph(name, speed_kmh=300.0)
    F0 = pant.options.mean_uplift
    system = CoupledSystem(RigidWire(1, height=5.3), [pant], PenaltyContact())
    q0 = pant.static_equilibrium(F0, 5.3 + F0 / 50_000.0)
    integ = HHTIntegrator(system, HHTSettings(alpha=-0.05))
    integ.initialize(0.0, q0, np.zeros(pant.n_dofs))
    forces = []
    for _ in range(1000):
        integ.step(1e-3)
        forces.append(system.contact_forces(integ.t, integ.q, integ.v)[0])
    assert np.max(np.abs(np.array(forces) - F0)) / F0 < 1e-6


def test_rigid_wire_from_a_frozen_catenary_checks_contact_location():
    """A wire frozen in its static shape: the pantograph riding it feels exactly the penalty
    of the interpolated height (3.13) at every position."""
    from pantocosim.catenary.model import CatenaryModel

    cat = CatenaryModel("en50318", x0=(30.0,), speed=250 / 3.6)
    pant = load_pantograph("en50318-2mass")
    wire = RigidWire(1, catenary=cat, q=cat.q_static)
    system = CoupledSystem(wire, [pant], PenaltyContact())
    z0 = cat.wire_height(0.0, cat.q_static)[0]
    q0 = pant.static_equilibrium(115.0, z0 + 115.0 / 50_000.0)
    integ = HHTIntegrator(system, HHTSettings(alpha=-0.05))
    integ.initialize(0.0, q0, np.zeros(2))
    for _ in range(200):
        integ.step(1e-3)
        st = system.contact_state(integ.t, integ.q, integ.v)[0]
        z_w_expected = cat.contact_wire_height(cat.q_static, [30.0 + 250 / 3.6 * integ.t])[0]
        # the same interpolation summed in another order: a few ulp(5.3 m) = 8.9e-16 m
        # apart; HEIGHT_TOL is over a thousand of them, a 1 mm error along the wire ~1e-6 m
        assert st[2] == pytest.approx(z_w_expected, abs=HEIGHT_TOL)
        # a difference of two 5.3 m heights times k: its rounding floor is k ulp(5.3 m)
        # = 4.4e-11 N, so the force is held to k HEIGHT_TOL = 5e-8 N, not to a relative 1e-12
        assert st[0] == pytest.approx(max(0.0, 50_000.0 * (st[1] - z_w_expected)),
                                      abs=50_000.0 * HEIGHT_TOL)


def test_coupled_tangent_matches_finite_differences():
    from pantocosim.catenary.model import CatenaryModel

    cat = CatenaryModel("en50318", x0=(31.3,), speed=80.0)
    pant = load_pantograph("dsa380-rigid", speed_kmh=288.0, friction_force=3.0,
                           friction_smoothing=1e-2)
    contact = PenaltyContact(50_000.0, 20.0)
    system = CoupledSystem(cat, [pant], contact)
    qp = pant.static_equilibrium(150.0, cat.wire_height(0.02, cat.q_static)[0] + 0.004)
    q = np.concatenate([cat.q_static, qp])
    rng = np.random.default_rng(1)
    v = 1e-3 * rng.standard_normal(q.size)
    a = 1e-2 * rng.standard_normal(q.size)
    ev = system.evaluate(0.02, q, v, a, None)
    c_a, c_v, c_f = 3.0, 7.0, 0.9
    S = system.assembled(ev, c_a, c_v, c_f).toarray()

    def residual(qq):
        e = system.evaluate(0.02, qq, v + c_v * (qq - q), a + c_a * (qq - q), None,
                            tangent=False)
        return e.f_inertia + c_f * e.f_rest

    # check the columns of the pantograph and of the catenary DOFs near the contact point
    cp = cat.contact_points(0.02)[0]
    cols = list(cp.dofs) + list(range(system.n_cat, system.n_dofs))
    for j in cols:
        h = 1e-7 * max(1.0, abs(q[j]))
        dq = np.zeros_like(q)
        dq[j] = h
        fd = (residual(q + dq) - residual(q - dq)) / (2 * h)
        assert np.allclose(S[:, j], fd, rtol=1e-5, atol=1e-6 * np.max(np.abs(S[:, j]))), j
    # the Woodbury solve equals a direct solve of the assembled matrix; the contact
    # linearisation is the one of ``ev``, whatever was evaluated since
    r = rng.standard_normal(q.size)
    x = system.newton_solve(system.factorize(system.effective_matrix(ev, c_a, c_v, c_f)), ev, r)
    assert np.allclose(S @ x, r, rtol=0, atol=1e-8 * np.max(np.abs(r)))


def test_static_start_is_an_equilibrium(short_monolithic):
    prep, run = short_monolithic
    system = CoupledSystem(prep.catenary, prep.pantographs, prep.contact)
    q0 = np.concatenate([prep.q_cat0] + prep.q_pan0)
    ev = system.evaluate(0.0, q0, np.zeros_like(q0), np.zeros_like(q0), None)
    assert np.max(np.abs(ev.f_rest)) < 1e-7
    assert prep.static_forces[0] == pytest.approx(115.0, rel=0.02)
    # the actuation delivers the mean uplift at the mean loaded height of the window
    pant = prep.pantographs[0]
    q_mean = pant.static_equilibrium(115.0, prep.actuation.height[0])
    assert pant.contact_height(q_mean) == pytest.approx(prep.actuation.height[0])


@pytest.mark.slow
def test_implicit_coupling_reproduces_monolithic(short_monolithic):
    prep, mono = short_monolithic
    Fm = mono.columns["contact_force_1"]
    for acc in ("iqn-imvj", "iqn-ils", "aitken"):
        res = run_cosim(prepare(SHORT), None, "implicit", acc, progress=False,
                        in_process=True, tolerance=1e-8)
        assert res.error is None
        Fi = res.columns["contact_force_1"]
        assert np.max(np.abs(Fi - Fm)) < 1e-6 * Fm.mean()
        assert res.coupling_iterations.max() <= 6


def _linear_interface_run(accelerator, steps=6):
    """Coupling iterations per step of an implicit iteration on a linear interface map
    H(F) = A F + b(t) with a constant Jacobian A (two pantographs)."""
    from pantocosim.master.coupling import ACCELERATORS

    A = np.array([[-0.8, 0.1], [0.05, -1.2]])
    acc = ACCELERATORS[accelerator](initial_relaxation=0.5)
    F = np.zeros(2)
    counts = []
    for n in range(steps):
        b = np.array([100.0 + 5.0 * n, 80.0 - 3.0 * n * n])
        acc.reset()
        for it in range(1, 30):
            H = A @ F + b
            if np.max(np.abs(H - F)) <= 1e-9:
                acc.converged(F, H)
                break
            F = acc.update(F, H)
        counts.append(it)
        assert np.allclose(F, np.linalg.solve(np.eye(2) - A, b), atol=1e-8)
    return counts


def test_iqn_imvj_carries_the_interface_jacobian_across_steps():
    """IQN-IMVJ learns the interface Jacobian in the first steps and keeps it, so a later
    step converges at its second pass (one exact Newton update); IQN-ILS starts every step
    from a relaxation and needs the secants of that step."""
    imvj = _linear_interface_run("iqn-imvj")
    ils = _linear_interface_run("iqn-ils")
    assert imvj[-3:] == [2, 2, 2]
    assert min(ils[1:]) >= 3


@pytest.mark.slow
def test_explicit_coupling_is_close_to_monolithic(short_monolithic):
    prep, mono = short_monolithic
    Fm = mono.columns["contact_force_1"]
    for scheme in ("jacobi", "gauss-seidel"):
        res = run_cosim(prepare(SHORT), None, scheme, progress=False, in_process=True)
        F = res.columns["contact_force_1"]
        assert abs(F.mean() - Fm.mean()) < 0.01 * Fm.mean()
        assert abs(F.std() - Fm.std()) < 0.1 * Fm.std()


@pytest.mark.slow
def test_run_cli_writes_outputs_and_json(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["run", SHORT, "--out", str(out), "--json", "--quiet"]) == 0
    summary = json.loads(capsys.readouterr().out)
    st = summary["statistics"]
    for key in ("mean_n", "std_n", "stat_max_n", "stat_min_n", "max_n", "min_n",
                "loss_of_contact_percent", "max_uplift_at_support_m"):
        assert np.isfinite(st[key]), key
    assert st["stat_max_n"] == pytest.approx(st["mean_n"] + 3 * st["std_n"])
    assert summary["coupling"] == "monolithic" and summary["scenario"] == "short-en50318"
    assert summary["wall_time_s"] > 0 and summary["simulated_time_s"] > 0.6
    header = (out / "timeseries.csv").read_text().splitlines()[0].split(",")
    assert header[:5] == ["time", "x_1", "contact_force_1", "contact_height_1", "wire_height_1"]
    for png in ("contact_force.png", "spectrum.png", "support_uplift.png"):
        assert (out / png).stat().st_size > 10_000


def _scenario_file(tmp_path, **changes):
    text = Path(SHORT).read_text()
    for old, new in changes.items():
        assert old in text, old
        text = text.replace(old, new)
    p = tmp_path / "bad.toml"
    p.write_text(text)
    return str(p)


@pytest.mark.parametrize("old, new, message", [
    ('model = "en50318-2mass"', 'model = "no-such"', r"pantographs\[0\].model"),
    ("speed_kmh = 250.0", "speed_kmh = 400.0", "speed_kmh = 400.0.*wave speed.*--force"),
    ("window_m = [35.0, 60.0]", "window_m = [35.0, 900.0]", r"analysis.window_m"),
    ("dt = 0.001", "dtt = 0.001", "simulation.dtt"),
    ('newton_rtol = 1e-10', 'newton_rtol = 0.5', "simulation.newton_rtol = 0.5"),
])
def test_bad_scenarios_name_the_field(tmp_path, old, new, message):
    bad = _scenario_file(tmp_path, **{old: new})
    with pytest.raises(ParameterError, match=message):
        prepare(bad)
    assert main(["run", bad, "--quiet"]) == 2


def test_unknown_scenario_is_named():
    with pytest.raises(ParameterError, match="scenario"):
        load_scenario("no-such-scenario")


class _Discarding:
    """Wraps a subsystem: discards (status 2, like fmi2Discard) steps longer than h_max
    inside a time interval."""

    def __init__(self, inner, h_max, t_from, t_to):
        self.inner, self.h_max, self.t_from, self.t_to = inner, h_max, t_from, t_to
        self.discards = 0

    def step(self, t, h):
        if h > self.h_max and self.t_from <= t < self.t_to:
            self.discards += 1
            err = RuntimeError(f"doStep(t = {t:.6g}, h = {h:.3g}) returned DISCARD")
            err.status = 2
            raise err
        self.inner.step(t, h)

    def __getattr__(self, name):
        return getattr(self.inner, name)


@pytest.mark.parametrize("scheme", ["jacobi", "implicit"])
def test_discard_rolls_back_and_halves_the_step(scheme):
    from pantocosim.core.errors import ConvergenceError
    from pantocosim.master.cosim import in_process_subsystems
    from pantocosim.master.coupling import Coupler, CouplingSettings

    prep = prepare(SHORT)
    cat, pans = in_process_subsystems(prep)
    pans[0] = _Discarding(pans[0], h_max=3e-4, t_from=0.05, t_to=0.06)
    coupler = Coupler(cat, pans, prep.contact, CouplingSettings(scheme=scheme,
                                                                tolerance=1e-8))
    coupler.initialise(prep.static_forces)
    for i in range(100):
        coupler.step(i * 1e-3, 1e-3)
    assert pans[0].discards > 0 and coupler.halvings >= 10 * 2
    assert abs(cat.integ.t - 0.1) < 1e-12 and abs(pans[0].integ.t - 0.1) < 1e-12
    # below the floor the run stops with the participant's message
    coupler.s.min_step = 5e-4
    pans[0].t_from, pans[0].t_to = 0.1, 0.2
    with pytest.raises(ConvergenceError, match="discarded down to.*DISCARD"):
        coupler.step(0.1, 1e-3)


class _CountingStates:
    """A participant that counts its state saves."""

    def __init__(self, inner):
        self.inner, self.saves = inner, 0

    def get_state(self):
        self.saves += 1
        return self.inner.get_state()

    def __getattr__(self, name):
        return getattr(self.inner, name)


@pytest.mark.parametrize("scheme", ["jacobi", "gauss-seidel"])
def test_a_discard_between_checkpoints_is_rolled_back_by_replay(scheme):
    """Explicit schemes save the states every checkpoint_steps steps: a step discarded 18
    steps after the checkpoint is rolled back by restoring it and replaying the journal, and
    the run is the one of a coupler saving the states at every step."""
    from pantocosim.master.cosim import in_process_subsystems
    from pantocosim.master.coupling import Coupler, CouplingSettings

    runs = []
    for period in (1, 32):
        prep = prepare(SHORT)
        cat, pans = in_process_subsystems(prep)
        cat = _CountingStates(cat)
        pans[0] = _Discarding(pans[0], h_max=3e-4, t_from=0.05, t_to=0.052)
        coupler = Coupler(cat, pans, prep.contact,
                          CouplingSettings(scheme=scheme, checkpoint_steps=period))
        coupler.initialise(prep.static_forces)
        for i in range(70):
            coupler.step(i * 1e-3, 1e-3)
        assert pans[0].discards == 6 and coupler.halvings == 6
        runs.append((cat.saves, np.concatenate([coupler.forces, cat.integ.q, cat.integ.v,
                                                pans[0].integ.q, pans[0].integ.v])))
    (saves_1, end_1), (saves_32, end_32) = runs
    # period 32: checkpoints at t = 0, 0.032 and at each discard that had to replay
    assert saves_1 > 70 and saves_32 == 6
    assert np.array_equal(end_1, end_32)


@pytest.mark.parametrize("scheme", ["jacobi", "implicit"])
def test_warm_up_leaves_the_coupled_run_as_it_was(scheme):
    """Coupler.warm_up takes a step and puts the participants and the coupler back: the
    steps that follow are bit for bit those of a coupler without it."""
    from pantocosim.master.cosim import in_process_subsystems
    from pantocosim.master.coupling import Coupler, CouplingSettings

    runs = []
    for warm in (False, True):
        prep = prepare(SHORT)
        cat, pans = in_process_subsystems(prep)
        coupler = Coupler(cat, pans, prep.contact, CouplingSettings(scheme=scheme,
                                                                    tolerance=1e-8))
        coupler.initialise(prep.static_forces)
        if warm:
            coupler.warm_up(0.0, 1e-3)
            assert coupler.iterations == [] and cat.integ.t == 0.0
        rows = []
        for i in range(20):
            coupler.step(i * 1e-3, 1e-3)
            rows.append(np.concatenate([coupler.forces, cat.integ.q[:50], pans[0].integ.q]))
        runs.append((np.array(rows), list(coupler.iterations)))
    assert np.array_equal(runs[0][0], runs[1][0]) and runs[0][1] == runs[1][1]

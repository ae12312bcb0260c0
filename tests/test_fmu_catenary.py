"""Catenary FMU: validation, port contract, exactness vs the in-process model, rollback,
bad input, built-in penalty vs monolithic, SSP, third-party masters, bare venv.

Every FMU is loaded in a subprocess (tests/fmu_catenary_probe.py, the run_* scripts), never in
the pytest process (pythonfmu B4/B5, docs/pythonfmu-notes.md)."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from recipes import read_csv, run_recipe

#: FMUs or long runs: outside `pytest -m "not slow"` (CI runs everything)
pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[1]
PROBE = Path(__file__).with_name("fmu_catenary_probe.py")
SHORT = {"catenary_definition": "en50318", "spans": 4, "speed_kmh": 300.0}
H = 1e-3


def probe(check, fmu, python=sys.executable, **args):
    proc = subprocess.run([python, str(PROBE), check, str(fmu), json.dumps(args)],
                          capture_output=True, text=True, timeout=900, cwd=str(PROBE.parent))
    lines = [l for l in proc.stdout.splitlines() if l.startswith("RESULT ")]
    assert proc.returncode == 0 and lines, proc.stdout[-4000:] + proc.stderr[-4000:]
    return json.loads(lines[-1][7:])


def short_catenary(x0, speed_kmh=300.0):
    from pantocosim.catenary.definition import load_catenary, with_spans
    from pantocosim.catenary.model import CatenaryModel

    return CatenaryModel(with_spans(load_catenary("en50318"), 4), x0=x0,
                         speed=speed_kmh / 3.6)


# ------------------------------------------------------------------------- model description
def test_catenary_fmu_validates_and_has_the_port_contract(fmus):
    from fmpy import read_model_description
    from fmpy.validation import validate_fmu

    path = fmus["catenary"]
    assert validate_fmu(str(path)) == []
    md = read_model_description(str(path))
    assert md.coSimulation.canGetAndSetFMUstate and md.coSimulation.canSerializeFMUstate
    v = {x.name: x for x in md.modelVariables}
    params = {"catenary_definition": "String", "spans": "Integer", "element_size": "Real",
              "speed_kmh": "Real", "n_pantographs": "Integer", "hht_alpha": "Real",
              "contact_mode": "Integer", "contact_stiffness": "Real",
              "contact_damping": "Real", "n_substeps": "Integer",
              "factorization": "Integer", "window_start": "Real", "window_end": "Real",
              "averaging_step": "Real"}
    for k in range(1, 5):
        params[f"position_{k}"] = params[f"static_force_{k}"] = "Real"
    for name, typ in params.items():
        assert v[name].causality == "parameter" and v[name].type == typ, name
    assert v["catenary_definition"].start == "en50318" and float(v["hht_alpha"].start) == -0.05
    assert float(v["contact_stiffness"].start) == 50000.0
    assert int(v["factorization"].start) == 2
    ports = {(x.name, x.causality, x.unit) for x in md.modelVariables
             if x.causality in ("input", "output")}
    expected = set()
    for k in range(1, 5):
        expected |= {(f"contact_force_{k}", "input", "N"),
                     (f"pantograph_height_{k}", "input", "m"),
                     (f"pantograph_velocity_{k}", "input", "m/s"),
                     (f"wire_height_{k}", "output", "m"),
                     (f"wire_velocity_{k}", "output", "m/s"),
                     (f"contact_force_out_{k}", "output", "N")}
    expected |= {(f"support_uplift_{j}", "output", "m") for j in range(64)}
    expected |= {("n_supports", "output", "1"), ("train_speed_kmh", "output", "km/h")}
    for k in range(1, 5):
        expected |= {(f"operating_height_{k}", "output", "m"),
                     (f"operating_height_slope_{k}", "output", "m/N"),
                     (f"static_height_{k}", "output", "m"),
                     (f"static_height_slope_{k}", "output", "m/N")}
    assert ports == expected
    assert "t + h" in v["contact_force_1"].description
    assert "t + h" in v["pantograph_height_1"].description
    assert all(x.initial == "exact" for x in md.modelVariables if x.causality == "output")


# ------------------------------------------------------------------------- mode 0
@pytest.mark.parametrize("policy", [1, 2])
def test_mode0_equals_the_in_process_model_and_rolls_back_bitwise(fmus, policy):
    """Same forces through FMI as into CatenaryModel + HHTIntegrator with the same
    factorization policy (1: once per step; 2: reuse across steps, the default) and the run
    settings (linear predictor, Newton tolerance newton_rtol)."""
    from pantocosim.core.hht import HHTIntegrator, HHTSettings
    from pantocosim.fmi.catenary_slave import FACTORIZATION_POLICIES

    x0, F0 = [30.0, 95.0], [120.0, 100.0]
    steps = 120
    t = H * np.arange(1, steps + 1)
    forces = np.column_stack([F0[0] + 30 * np.sin(2 * np.pi * 5 * t),
                              F0[1] + 20 * np.sin(2 * np.pi * 3 * t) + 40 * t])
    params = dict(SHORT, n_pantographs=2, position_1=x0[0], position_2=x0[1],
                  static_force_1=F0[0], static_force_2=F0[1], factorization=policy,
                  newton_rtol=1e-6)
    res = probe("catenary_trace", fmus["catenary"], params=params, forces=forces.tolist(),
                n_uplift=5)
    # in-process reference: CatenaryModel + HHTIntegrator with the same settings
    m = short_catenary(x0)
    settings = HHTSettings.for_runs(-0.05, 1e-6)
    settings.reuse_factorization = FACTORIZATION_POLICIES[policy]
    integ = HHTIntegrator(m, settings)
    integ.initialize(0.0, m.static_state(np.array(F0)), np.zeros(m.n_dofs), np.array(F0))
    ref = [list(m.wire_height(0.0, integ.q)) + list(m.wire_velocity(0.0, integ.q, integ.v))]
    for F in forces:
        integ.step(H, F.copy())
        ref.append(list(m.wire_height(integ.t, integ.q))
                   + list(m.wire_velocity(integ.t, integ.q, integ.v)))
    ref = np.array(ref)
    rows = np.array(res["rows"])
    got = np.vstack([np.array(res["initial"])[None, :4], rows[:, :4]])
    assert np.max(np.abs(got - ref)) <= 1e-12 * np.max(np.abs(ref))
    assert np.array_equal(got[:, :2], ref[:, :2])   # wire heights bitwise
    # contact_force_out echoes the input force; support uplift as the model's
    assert np.array_equal(rows[:, 4:6], forces)
    up = m.support_uplift(integ.q)
    assert np.array_equal(rows[-1, 6:11], up[:5])
    assert res["n_supports"] == 5.0
    assert res["rollback_equal"] and res["serialized_equal"]


def test_bad_input_is_discarded_with_a_message_naming_the_parameter(fmus):
    res = probe("catenary_bad_input", fmus["catenary"],
                params=dict(SHORT, static_force_1=100.0))
    expect = {"unknown_catenary": "catenary", "nan_force": "contact_force_1 = nan",
              "negative_force": "contact_force_1 = -5.0",
              "bad_n_pantographs": "n_pantographs", "position_off_line": "position_1",
              "negative_static_force": "static_force_1", "bad_alpha": "hht_alpha = 0.5",
              "bad_factorization": "factorization", "bad_rtol": "newton_rtol = 0.5",
              "bad_stiffness": "contact_stiffness = -1.0",
              "nan_height_mode1": "pantograph_height_1 = nan"}
    inputs = {"nan_force", "negative_force", "nan_height_mode1"}
    for case, text in expect.items():
        r = res[case]
        # a bad parameter fails fmi2ExitInitializationMode (fmi2Error), a bad input its step
        assert r["init_status"] == (0 if case in inputs else 3), (case, r)
        assert r["status"] == 2, (case, r)   # fmi2Discard
        assert any(text in m for m in r["messages"]), (case, r["messages"])
    assert any("no-such-catenary.toml" in m for m in res["unknown_catenary"]["messages"])
    assert res["nan_force"]["after_status"] == 0
    assert 5.0 < res["nan_force"]["after_height"] < 5.6


# ------------------------------------------------------------------------- mode 1
def monolithic_short(steps, x0=30.0, pantograph="en50318-2mass", speed_kmh=300.0):
    """In-process monolithic run of a pantograph on the short catenary (static start at the
    static handshake of the SSP)."""
    from pantocosim.interaction.penalty_contact import PenaltyContact
    from pantocosim.interaction.coupled import CoupledSystem
    from pantocosim.core.hht import FactorReuse, HHTIntegrator, HHTSettings
    from pantocosim.pantograph.presets import load_pantograph

    cat = short_catenary([x0], speed_kmh)
    pan = load_pantograph(pantograph, speed_kmh=speed_kmh)
    contact = PenaltyContact()
    F0 = pan.options.mean_uplift
    qc = cat.static_state([F0])
    z_w = cat.wire_height(0.0, qc)[0]
    qp = pan.static_equilibrium(F0, z_w + F0 / contact.stiffness)
    system = CoupledSystem(cat, [pan], contact)
    q0 = np.concatenate([qc, qp])
    integ = HHTIntegrator(system, HHTSettings(alpha=-0.05, reuse_factorization=FactorReuse.PER_STEP))
    integ.initialize(0.0, q0, np.zeros(system.n_dofs), None)
    rec = []

    def record():
        st = system.contact_state(integ.t, integ.q, integ.v)[0]
        rec.append((integ.t, st[0], st[1], st[2], st[3], st[4]))  # t, F, z_p, z_w, v_p, v_w

    record()
    for _ in range(steps):
        integ.step(H)
        record()
    return np.array(rec), F0


def test_mode1_builtin_penalty_reproduces_the_monolithic_catenary(fmus):
    """Given the monolithic pantograph motion z_p(t), v_p(t) as inputs, the catenary FMU's
    built-in penalty contact solves the same catenary equations: its contact force and wire
    height equal the monolithic ones to the Newton tolerance."""
    steps = 150
    mono, F0 = monolithic_short(steps)
    assert mono[0, 1] == pytest.approx(F0, rel=1e-9)
    inputs = mono[1:, [2, 4]]
    res = probe("catenary_penalty", fmus["catenary"],
                params=dict(SHORT, position_1=30.0, static_force_1=F0, newton_rtol=1e-10),
                inputs=inputs.tolist())
    rows = np.array(res["rows"])
    assert res["initial"][0] == pytest.approx(F0, rel=1e-9)
    dF = np.max(np.abs(rows[:, 0] - mono[1:, 1]))
    dz = np.max(np.abs(rows[:, 1] - mono[1:, 3]))
    assert dF < 1e-6 * F0, dF
    assert dz < 1e-9, dz
    assert res["rollback_equal"] and res["serialized_equal"]


# ------------------------------------------------------------------------- fmpy
def test_fmpy_simulate_fmu_on_a_pantograph_under_a_prescribed_force(fmus, tmp_path):
    from pantocosim.master.standalone import simulate_pantograph
    from pantocosim.pantograph.presets import load_pantograph

    out = tmp_path / "single.csv"
    stats, _ = run_recipe("fmpy_single", "--fmu", fmus["en50318-2mass"], "--stop", 0.5,
                          "--step", H, "--force", "120 + 30*sin(2*pi*5*t)", "--out", out)
    c = read_csv(out)
    ref = simulate_pantograph(load_pantograph("en50318-2mass"),
                              lambda t: 120.0 + 30.0 * np.sin(2 * np.pi * 5.0 * t), 0.5, H)
    # the recipe feeds F(t + h) at t (the FMU's force-at-t+h convention): bitwise equal to
    # the stand-alone run
    assert np.array_equal(c["contact_height_1"], ref.contact_height)
    assert stats["mean_n"] == pytest.approx(np.mean(ref.contact_force), rel=0.05)
    assert stats["samples"] == 501


# ------------------------------------------------------------------------- bare venv
@pytest.mark.slow
def test_every_fmu_steps_in_a_bare_venv(fmus, tmp_path_factory):
    """A venv with only numpy, scipy, numba and fmpy (not this project) instantiates and steps
    each FMU (the FMU bundles pantocosim and pythonfmu's Python files)."""
    venv = tmp_path_factory.mktemp("bare") / "venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True, timeout=300)
    py = venv / "bin" / "python"
    pip = subprocess.run([str(py), "-m", "pip", "install", "-q", "numpy", "scipy", "numba",
                          "fmpy"], capture_output=True, text=True, timeout=1200)
    assert pip.returncode == 0, pip.stdout + pip.stderr
    check = subprocess.run([str(py), "-c", "import pantocosim"], capture_output=True)
    assert check.returncode != 0  # the project is not installed there
    res = probe("smoke", fmus["catenary"], python=str(py),
                params=dict(SHORT, static_force_1=120.0),
                inputs={"contact_force_1": 125.0}, outputs=["wire_height_1"], steps=5)
    assert 5.0 < res["outputs"]["wire_height_1"] < 5.6 and not res["errors"]
    assert "resources" in res["pantocosim_from"]
    for name in ("en50318-2mass", "dsa380-rigid"):
        res = probe("smoke", fmus[name], python=str(py), inputs={"contact_force": 120.0},
                    outputs=["contact_height"], steps=20)
        assert 4.0 < res["outputs"]["contact_height"] < 7.0 and not res["errors"], name

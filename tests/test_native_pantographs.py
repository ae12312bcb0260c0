"""The native nonlinear pantograph FMUs of ``pantocosim export-native`` (the rigid and the
flexible DSA-380, fmus/native/nonlinear_pantograph.c): in a C host with no Python they give the
Python FMU's stepper's numbers and allocate nothing in doStep, and build again from their own
sources; a data file out of bounds is refused naming it; in fmpy they refuse bad input with the
Python FMU's statuses, keep their state through refused steps, roll back and serialise; FMI
3.0 validates; in our master they give the Python pantograph FMU's contact force, and the
implicit coupling the monolithic run's (all slow: each export takes 10-20 s)."""

import dataclasses
import json
import shutil
import subprocess
import zipfile

import numpy as np
import pytest

from pantocosim.core.hht import HHTIntegrator, HHTSettings
from pantocosim.interaction.pantograph_start import start_state
from pantocosim.master.native.build import CFLAGS
from pantocosim.master.native.data_file import pack_data, read_data
from pantocosim.master.native.models import export_pantograph, export_scenario
from pantocosim.master.results.files import read_csv
from pantocosim.master.run import prepare, run_monolithic
from pantocosim.master.run.setup import scenario_pantograph
from pantocosim.master.scenario import load_scenario
from test_fmu_cosim import cli, scenario_with
from test_native_fmus import DISCARD, ERROR, OK, host, required, run_host  # noqa: F401
from test_native_fmus import assert_states_roll_back, rewritten, slave, status_of

pytestmark = pytest.mark.slow

DT = 0.001
IDENTIFIER = "pantocosim_pantograph_native"


def with_model(model: str, **changes):
    """dsa380-ave-300 (linear catenary: a quick set-up) with pantograph ``model``."""
    sc = load_scenario("dsa380-ave-300")
    pans = [dataclasses.replace(p, model=model) for p in sc.pantographs]
    return dataclasses.replace(sc, pantographs=pans, catenary_model="linear", **changes)


@pytest.fixture(scope="module", params=["dsa380-rigid", "dsa380-flexible"])
def exported(request, tmp_path_factory):
    """(prepared scenario, unpacked native pantograph FMU folder, .fmu file)."""
    required("gcc", "gcc")
    prep = prepare(with_model(request.param))
    out = tmp_path_factory.mktemp("native-pantograph")
    fmu = export_pantograph(prep, 0, out / f"{request.param}.fmu", win64=False)
    folder = out / request.param
    with zipfile.ZipFile(fmu) as z:
        z.extractall(folder)
    return prep, folder, fmu


def forced(F0, t):
    """The host's pantograph mode: F0 (1 + 0.1 sin(2 pi 7 t))."""
    return F0 * (1.0 + 0.1 * np.sin(2.0 * np.pi * 7.0 * t))


def python_fmu_stepper(prep):
    """The Python pantograph FMU's model, start and integrator for the scenario's start."""
    sc = prep.scenario
    model = scenario_pantograph(sc, 0)
    F0 = float(prep.static_forces[0])
    q0, F0 = start_state(model, 0, height=float(prep.pantographs[0].contact_height(
        prep.q_pan0[0])), force=F0)
    integ = HHTIntegrator(model, HHTSettings(alpha=sc.alpha))
    integ.initialize(0.0, q0, np.zeros(model.n_dofs), np.array([F0]))
    return model, integ, F0


def test_in_a_c_host_the_pantograph_equals_the_python_fmu_stepper(exported, host, tmp_path):
    prep, folder, _ = exported
    steps = 300
    got, counts = run_host(host, ["pantograph", folder, steps, DT], tmp_path)
    model, integ, F0 = python_fmu_stepper(prep)
    want = []
    for i in range(steps):
        t1 = (i + 1) * DT
        integ.step(DT, np.array([forced(F0, t1)]))
        want.append([t1, model.contact_height(integ.q), model.contact_velocity(integ.q,
                                                                               integ.v)])
    want = np.array(want)
    assert np.ptp(want[:, 1]) > 1e-4
    for col in (1, 2):
        assert np.max(np.abs(got[:, col] - want[:, col])) <= 1e-10 * np.max(
            np.abs(want[:, col])), col
    assert counts["allocations in doStep"] == 0
    assert counts["allocations outside doStep"] > 0


def test_the_fmu_builds_from_its_own_sources(exported, host, tmp_path):
    """sources/ alone, compiled with the export's C99 flags, gives the same numbers."""
    _, folder, _ = exported
    copy = tmp_path / "rebuilt"
    shutil.copytree(folder, copy)
    lib = copy / "binaries" / "linux64" / f"{IDENTIFIER}.so"
    lib.unlink()
    sources = sorted((copy / "sources").glob("*.c"))
    subprocess.run(["gcc", *CFLAGS, "-fPIC", "-shared", "-fvisibility=hidden",
                    *map(str, sources), "-o", str(lib), "-lm"], check=True)
    runs = [run_host(host, ["pantograph", f, 50, DT], tmp_path)[0] for f in (folder, copy)]
    assert np.array_equal(runs[0], runs[1])


def test_bad_inputs_get_the_python_fmus_statuses_and_keep_the_state(exported):
    _, folder, _ = exported
    fmu, vr = slave(folder, IDENTIFIER)
    ref, _ = slave(folder, IDENTIFIER)
    F, out = [vr["contact_force"]], [vr["contact_height"], vr["contact_velocity"]]
    for bad in (float("nan"), -1.0, float("inf")):
        fmu.setReal(F, [bad])
        assert status_of(fmu.doStep, 0.0, DT) == DISCARD
    fmu.setReal(F, [1e7])                       # drives the collector off its range
    assert status_of(fmu.doStep, 0.0, 0.05) == DISCARD
    for f in (fmu, ref):                         # the state was kept: the same next step
        f.setReal(F, [150.0])
        assert status_of(f.doStep, 0.0, DT) == OK
    assert fmu.getReal(out) == ref.getReal(out)
    assert status_of(fmu.doStep, DT, 1.5 * DT) == DISCARD     # not a whole number of steps
    assert status_of(fmu.doStep, DT, 2 * DT) == OK
    assert fmu.getReal([vr["newton_iterations"]])[0] >= 2.0


def altered(sections: dict, name: str, index: int, value) -> dict:
    """A copy of ``sections`` with entry ``index`` of section ``name`` set to ``value``."""
    out = dict(sections)
    out[name] = sections[name].copy()
    out[name][index] = value
    return out


def test_a_data_file_out_of_bounds_is_refused_naming_it(exported, host, tmp_path):
    """Sizes, indices and values are checked before anything is allocated: instantiation
    fails with the file and what is wrong, no crash."""
    _, folder, _ = exported
    kind, sections = read_data(folder / "resources" / "model.pcsdata")
    short = dict(sections, q0=sections["q0"][:-1])
    cases = {"section q0": pack_data(kind, short),
             "internal step": pack_data(kind, altered(sections, "scalars", 0, -1.0)),
             "must be finite": pack_data(kind, altered(sections, "constants", 3, np.nan))}
    if kind == "dsa380-flexible":
        cases["sizes 1e+09 unknowns"] = pack_data(kind, altered(sections, "constants", 0,
                                                                     1e9))
        cases["pg[5] = 100000"] = pack_data(kind, altered(sections, "pg", 5, 100000))
        cases["an index in"] = pack_data(kind, altered(sections, "constants", 8, 1e4))
    for reason, data in cases.items():
        bad = rewritten(folder, tmp_path, data)
        proc = subprocess.run([str(host), "pantograph", str(bad), "1", str(DT)],
                              capture_output=True, text=True, timeout=60)
        assert proc.returncode != 0 and "Segmentation" not in proc.stderr, (reason, proc.stderr)
        assert reason in proc.stderr and "model.pcsdata" in proc.stderr, (reason, proc.stderr)


def test_fixed_parameters_accept_the_exported_value_and_refuse_another(exported):
    """The export's values are accepted; another value is an error (the instance fails, as
    with the other native FMUs)."""
    from fmpy import read_model_description
    from fmpy.fmi2 import FMU2Slave

    _, folder, _ = exported
    md = read_model_description(str(folder / "modelDescription.xml"))
    var = {v.name: v for v in md.modelVariables}

    def fresh():
        fmu = FMU2Slave(guid=md.guid, unzipDirectory=str(folder), modelIdentifier=IDENTIFIER,
                        instanceName="fresh")
        fmu.instantiate()
        return fmu

    names = ("speed_kmh", "static_force", "initial_height", "hht_alpha", "friction_force")
    fmu = fresh()
    for name in names:
        v = var[name]
        assert status_of(fmu.setReal, [v.valueReference], [float(v.start)]) == OK
    v = var["start_mode"]
    assert status_of(fmu.setInteger, [v.valueReference], [int(v.start)]) == OK
    for name in names:
        v = var[name]
        assert status_of(fresh().setReal, [v.valueReference], [float(v.start) + 1.0]) == ERROR
    assert status_of(fresh().setInteger, [v.valueReference], [2]) == ERROR
    assert var["one_way_damper"].variability == "fixed"


def test_fmu_states_roll_back_and_serialize(exported):
    _, folder, _ = exported
    fmu, vr = slave(folder, IDENTIFIER)
    F, out = [vr["contact_force"]], [vr["contact_height"], vr["contact_velocity"]]
    _, _, heights = assert_states_roll_back(fmu, F, out, 20)
    assert heights[0] != pytest.approx(0.0)


def test_fmi3_fmu_validates_and_gives_the_fmi2_numbers(exported, tmp_path):
    from fmpy import simulate_fmu
    from fmpy.validation import validate_fmu

    prep, _, fmu2 = exported
    fmu3 = export_pantograph(prep, 0, tmp_path / "fmi3.fmu", fmi=3, win64=False)
    assert validate_fmu(str(fmu3)) == []
    assert validate_fmu(str(fmu2)) == []
    inputs = np.array([(t, 120.0 + 30.0 * np.sin(40 * t)) for t in np.arange(0, 0.05, DT)],
                      dtype=[("time", float), ("contact_force", float)])
    runs = [simulate_fmu(str(f), stop_time=0.05, step_size=DT, input=inputs,
                         output=["contact_height"]) for f in (fmu2, fmu3)]
    assert np.array_equal(runs[0]["contact_height"], runs[1]["contact_height"])


def test_export_native_writes_the_rigid_pantograph_and_names_what_stays_python(tmp_path,
                                                                             capsys):
    from pantocosim.master.cli import main

    required("gcc", "gcc")
    assert main(["export-native", "dsa380-ave-300", "--out", str(tmp_path / "n"),
                 "--win64", "no"]) == 0
    out = capsys.readouterr().out
    assert f"wrote {tmp_path / 'n' / 'dsa380-rigid.fmu'}" in out
    assert "catenary: the scenario's nonlinear model" in out
    assert "stays a Python FMU" in out


def test_a_lumped_chain_with_friction_stays_python_with_the_reason(tmp_path):
    required("gcc", "gcc")
    sc = load_scenario("en50318-300")
    pans = [dataclasses.replace(p, options={"friction_force": 5.0}) for p in sc.pantographs]
    prep = prepare(dataclasses.replace(sc, pantographs=pans, catenary_model="linear"))
    written, kept = export_scenario(prep, tmp_path, win64=False)
    assert [p.name for p in written] == ["catenary.fmu"]
    assert len(kept) == 1 and "no constant-matrix form (collector friction" in kept[0][1]


# ---------------------------------------------------------------------- in our master
@pytest.mark.parametrize("model", ["dsa380-rigid", "dsa380-flexible"])
@pytest.mark.parametrize("scheme", ["jacobi", "implicit"])
def test_native_pantograph_in_our_master_gives_the_python_pantograph_fmus_force(
        scheme, model, fmus, tmp_path):
    """dsa380-ave-300 (0.2 s) with the Python nonlinear catenary FMU: the native DSA-380 FMU
    and the Python one give the same contact force to 1e-9 of the mean."""
    from pantocosim.master.cosim import run_cosim
    from pantocosim.master.fmu.check import FmuPlan

    required("gcc", "gcc")
    sc = load_scenario("dsa380-ave-300")
    pans = [dataclasses.replace(p, model=model) for p in sc.pantographs]
    sc = dataclasses.replace(sc, pantographs=pans, duration_s=0.2, window_supports=None,
                             window_m=(33.0, 40.0))
    prep = prepare(sc)
    native = export_pantograph(prep, 0, tmp_path / f"{model}.fmu", win64=False)
    forces = {}
    for label, pantograph in (("python", fmus[model]), ("native", native)):
        res = run_cosim(prep, None, scheme, plan=FmuPlan(fmus["catenary"], [pantograph],
                                                         [None]), progress=False)
        assert res.error is None, res.error
        forces[label] = res.columns["contact_force_1"]
    py, nat = forces["python"], forces["native"]
    assert len(py) == len(nat) == prep.n_steps + 1
    assert np.max(np.abs(nat - py)) <= 1e-9 * np.mean(py), scheme


def test_implicit_with_the_native_pantograph_equals_the_monolithic_run(tmp_path):
    """`pantocosim run --coupling implicit --native-pantographs` on a short scenario with the
    rigid DSA-380 and tight tolerances reproduces the monolithic run to the bar the Python
    FMUs meet (tests/test_fmu_cosim.py: 1e-6 of the mean force)."""
    required("gcc", "gcc")
    scenario = scenario_with(tmp_path, "dsa380-rigid")
    mono = run_monolithic(prepare(str(scenario)), None, progress=False)
    out = tmp_path / "implicit"
    proc = cli("run", scenario, "--coupling", "implicit", "--native-pantographs", "--out", out,
               "--quiet", "--no-plots", "--json")
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert proc.stdout.startswith("pantograph 1 (dsa380-rigid): native FMU\n")
    summary = json.loads(proc.stdout.split("\n", 1)[1])
    assert summary["coupling"] == "implicit"
    F = read_csv(out / "timeseries.csv")["contact_force_1"]
    Fm = mono.columns["contact_force_1"]
    assert np.max(np.abs(F - Fm)) < 1e-6 * Fm.mean()


def test_native_pantographs_needs_a_co_simulation(capsys):
    from pantocosim.master.cli import main

    assert main(["run", "dsa380-ave-300", "--native-pantographs"]) == 2
    assert "--native-pantographs" in capsys.readouterr().err


def test_the_ssp_writer_takes_a_native_pantograph_and_libcosim_runs_it(fmus, tmp_path):
    """`pantocosim ssp --pantograph` of the native rigid DSA-380: the SSP holds it beside the
    Python catenary FMU (built-in penalty contact); libcosim runs it 0.3 s and the mean force
    over 33-50 m is our master's with the same native FMU (explicit coupling) to 2 %."""
    from pantocosim.master.cosim import run_cosim
    from pantocosim.master.fmu.check import FmuPlan
    from pantocosim.master.ssp import write_pantograph_ssp
    from recipes import run_recipe

    required("gcc", "gcc")
    sc = dataclasses.replace(load_scenario("dsa380-ave-300"), duration_s=0.3,
                             window_supports=None, window_m=(33.0, 50.0))
    prep = prepare(sc)
    native = export_pantograph(prep, 0, tmp_path / "dsa380-rigid.fmu", win64=False)
    ssp, _ = write_pantograph_ssp(native, "dsa380-ave-300", tmp_path / "mix.ssp")
    stats, _ = run_recipe("libcosim", "--ssp", ssp, "--stop", 0.3, "--window", 33, 50,
                          "--out", tmp_path / "lc.csv")
    ours = run_cosim(prep, None, "jacobi", plan=FmuPlan(fmus["catenary"], [native], [None]),
                     progress=False)
    assert ours.error is None, ours.error
    mean = ours.statistics()[0].mean_n
    assert stats["samples"] > 100
    assert stats["mean_n"] == pytest.approx(mean, rel=0.02)


def test_a_ramp_start_is_the_python_fmus(tmp_path):
    """start = "ramp" exports start_mode 1: lowered, no contact force at t0, the torque
    ramped (thesis 3.3.1); 80 steps free of contact equal the Python FMU's stepper."""
    from fmpy import read_model_description

    from pantocosim.master.scenario import RampSpec

    required("gcc", "gcc")
    sc = with_model("dsa380-rigid")
    pans = [dataclasses.replace(p, start="ramp", ramp=RampSpec(33.0, 4.0, 5.2))
            for p in sc.pantographs]
    prep = prepare(dataclasses.replace(sc, pantographs=pans))
    fmu = export_pantograph(prep, 0, tmp_path / "ramp.fmu", win64=False)
    with zipfile.ZipFile(fmu) as z:
        z.extractall(tmp_path / "ramp")
    md = read_model_description(str(tmp_path / "ramp" / "modelDescription.xml"))
    var = {v.name: v for v in md.modelVariables}
    assert int(var["start_mode"].start) == 1 and float(var["contact_force"].start) == 0.0
    slave_, vr = slave(tmp_path / "ramp", IDENTIFIER)
    model = scenario_pantograph(prep.scenario, 0)
    ramp = model.options.ramp
    q0, F0 = start_state(model, 1, height=float(prep.actuation.height[0]),
                         force=model.options.mean_uplift, lowered_height=ramp.lowered_height)
    assert F0 == 0.0
    integ = HHTIntegrator(model, HHTSettings(alpha=prep.scenario.alpha))
    integ.initialize(0.0, q0, np.zeros(model.n_dofs), np.array([0.0]))
    got, want = [], []
    for i in range(80):
        slave_.doStep(i * DT, DT)
        integ.step(DT, np.array([0.0]))
        got.append(slave_.getReal([vr["contact_height"]])[0])
        want.append(model.contact_height(integ.q))
    got, want = np.array(got), np.array(want)
    assert np.ptp(want) > 1e-3                      # the ramped torque raises it
    assert np.max(np.abs(got - want)) <= 1e-12 * np.max(np.abs(want))

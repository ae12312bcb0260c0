"""The FMI 3.0 FMUs (``pantocosim build-fmus`` writes them into ``fmi3/``): the same slave
cores as the FMI 2.0 FMUs behind the FMI 3.0 front and embedding library. They pass fmpy's FMI
3.0 validation, have the FMI 2.0 FMUs' ports and units, give the FMI 2.0 FMUs' numbers in
fmpy's ``simulate_fmu``, in our master (explicit and implicit; the implicit run equals the
monolithic one) and in a C host started with a clean environment, refuse what they do
not honour with FMI 3.0 statuses, and roll back bit for bit. FMUs never load into the pytest
process: fmpy, the master and the C host run in subprocesses."""

import json
import shutil
import subprocess
import sys
import textwrap
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import numpy as np
import pytest
from fmi_script import Script, results
from test_native_host import (CATENARY_RUN, DISCARD, ERROR, OK, PANTOGRAPH_RUN,
                              assert_clean_exit, host, run_host, run_twin, stepping_script)

from pantocosim.master.results.files import read_csv
from pantocosim.master.run import prepare, run_monolithic

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[1]
SHORT = Path(__file__).with_name("data") / "short-en50318.toml"
NAMES = ["dsa380-rigid", "dsa380-flexible", "dsa380-lumped3", "en50318-2mass", "catenary"]
#: FMI 3.0 type of each FMI 2.0 type of the ports
TYPES = {"Real": "Float64", "Integer": "Int32", "Boolean": "Boolean", "String": "String"}


@pytest.fixture(scope="session")
def fmus3(built):
    """The generic FMI 3.0 FMUs by name."""
    return {p.stem: p for p in (built / "fmi3").glob("*.fmu")}


def variables(fmu: Path) -> dict:
    """{name: (type, causality, variability, unit)} of a model description (FMI 2.0 types
    given as their FMI 3.0 names)."""
    with zipfile.ZipFile(fmu) as z:
        md = ET.fromstring(z.read("modelDescription.xml"))
    out = {}
    for v in md.iter("ScalarVariable"):
        t = next(c for c in v if c.tag in TYPES)
        out[v.get("name")] = (TYPES[t.tag], v.get("causality"), v.get("variability"),
                              t.get("unit"))
    for v in md.iterfind("ModelVariables/*"):
        if v.tag in TYPES.values():
            out[v.get("name")] = (v.tag, v.get("causality"), v.get("variability"),
                                  v.get("unit"))
    return out


# ----------------------------------------------------------------------- the model descriptions
def test_every_fmi3_fmu_passes_fmpys_validation(built):
    from fmpy import read_model_description
    from fmpy.validation import validate_fmu

    files = sorted((built / "fmi3").glob("*.fmu")) + sorted(
        (built / "fmi3" / "dsa380-ave-300").glob("*.fmu"))
    assert [f.stem for f in files] == sorted(NAMES) * 2
    for fmu in files:
        assert validate_fmu(str(fmu)) == [], fmu
        md = read_model_description(str(fmu))
        assert md.fmiVersion == "3.0"
        cs = md.coSimulation
        assert cs.canGetAndSetFMUstate and cs.canSerializeFMUstate, fmu
        with zipfile.ZipFile(fmu) as z:       # the project's library, not pythonfmu3's
            assert f"binaries/x86_64-linux/{cs.modelIdentifier}.so" in z.namelist()
            assert "resources/pantocosim_fmi3_bridge.py" in z.namelist()
            assert not [n for n in z.namelist() if n.startswith("sources/")]


@pytest.mark.parametrize("name", NAMES)
def test_fmi3_ports_and_units_are_the_fmi2_ones(built, name):
    v2, v3 = variables(built / f"{name}.fmu"), variables(built / "fmi3" / f"{name}.fmu")
    assert v3.pop("time") == ("Float64", "independent", "continuous", "s")
    assert v3 == v2


# ----------------------------------------------------------------------- fmpy.simulate_fmu
SIMULATE = textwrap.dedent("""
    import json, sys
    import numpy as np
    import scipy.sparse.linalg  # noqa: F401  (before any FMU is loaded)
    from fmpy import simulate_fmu

    fmu, port, outputs, params, events = json.loads(sys.argv[1])
    t = np.arange(0.0, 0.1005, 1e-3)
    signal = 120.0 + 30.0 * np.sin(40.0 * t) if port == "contact_force" else (
        params.pop("_height") + 2e-3 * np.sin(40.0 * t))
    sig = np.array(list(zip(t, signal)), dtype=[("time", float), (port, float)])
    r = simulate_fmu(fmu, start_time=0.0, stop_time=0.1, step_size=1e-3, input=sig,
                     output=outputs, output_interval=1e-3, start_values=params,
                     use_event_mode=events)
    print(json.dumps({k: r[k].tolist() for k in outputs}))
""")


def simulate(fmu: Path, port: str, outputs: list, params: dict, events=False) -> dict:
    proc = subprocess.run([sys.executable, "-c", SIMULATE,
                           json.dumps([str(fmu), port, outputs, params, events])],
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return {k: np.array(v) for k, v in json.loads(proc.stdout.splitlines()[-1]).items()}


@pytest.mark.parametrize("name", NAMES)
def test_simulate_fmu_gives_the_fmi2_numbers(built, name):
    """fmpy.simulate_fmu, 100 steps: the pantographs under a varying force, the catenary with
    its built-in penalty contact under a varying pantograph height (its contact force is an
    output: equal to 1e-9 N)."""
    if name == "catenary":
        params = {**CATENARY_RUN[0], "static_force_1": 0.0, "contact_mode": 1,
                  "extrapolate_heights": False, "_height": 5.5}
        port, outputs = "pantograph_height_1", ["contact_force_out_1", "wire_height_1"]
    else:
        params, port = PANTOGRAPH_RUN[0], "contact_force"
        outputs = ["contact_height", "contact_velocity"]
    a = simulate(built / f"{name}.fmu", port, outputs, dict(params))
    b = simulate(built / "fmi3" / f"{name}.fmu", port, outputs, dict(params))
    assert len(a[outputs[0]]) == len(b[outputs[0]]) == 101
    for key in outputs:
        assert np.ptp(a[key]) > 0.0                      # the run is not a constant
        tol = 1e-9 if key == "contact_force_out_1" else 1e-12
        np.testing.assert_allclose(b[key], a[key], rtol=0.0, atol=tol, err_msg=key)
    if name == "catenary":
        assert np.ptp(a["contact_force_out_1"]) > 10.0    # the contact force moved [N]


def test_simulate_fmu_in_event_mode_gives_the_same_numbers(built):
    """fmpy's simulate_fmu with event mode (the FMU declares hasEventMode: it passes through
    event mode after initialisation and never asks for event handling)."""
    params, port, outputs = PANTOGRAPH_RUN
    fmu = built / "fmi3" / "en50318-2mass.fmu"
    a = simulate(fmu, port, list(outputs), dict(params))
    b = simulate(fmu, port, list(outputs), dict(params), events=True)
    for key in outputs:
        np.testing.assert_array_equal(b[key], a[key])


# ----------------------------------------------------------------------- our master
def cli(cwd: Path, *args):
    return subprocess.run([sys.executable, "-m", "pantocosim.master.cli", *map(str, args)],
                          capture_output=True, text=True, timeout=1800, cwd=cwd)


def short_scenario(folder: Path, fmi: int) -> Path:
    p = folder / f"short-fmi{fmi}.toml"
    p.write_text(SHORT.read_text().replace('name = "short-en50318"',
                                           f'name = "short-fmi{fmi}"') + f"fmi = {fmi}\n")
    return p


@pytest.mark.parametrize("coupling", ["implicit", "explicit", "gauss-seidel"])
def test_our_master_runs_fmi3_fmus_as_fmi2_ones(built, tmp_path, coupling):
    """The short scenario (tight tolerances) through the FMI 3.0 and the FMI 2.0 FMUs of the
    run's build: contact forces equal to 1e-9 N; the implicit run equals the monolithic one
    to 1e-6 relative."""
    work = built.parent.parent                       # dist/fmus of the run's build
    forces = {}
    for fmi in (3, 2):
        out = tmp_path / f"{coupling}-{fmi}"
        proc = cli(work, "run", short_scenario(tmp_path, fmi), "--coupling", coupling,
                   "--out", out, "--quiet", "--no-plots", "--json")
        assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
        assert "building FMUs" not in proc.stderr      # the run's build, not a new one
        forces[fmi] = read_csv(out / "timeseries.csv")["contact_force_1"]
    F3, F2 = forces[3], forces[2]
    assert len(F3) == len(F2) > 100 and np.ptp(F2) > 1.0
    assert np.max(np.abs(F3 - F2)) <= 1e-9
    if coupling == "implicit":
        Fm = run_monolithic(prepare(str(short_scenario(tmp_path, 2))), None,
                            progress=False).columns["contact_force_1"]
        assert np.max(np.abs(F3 - Fm)) < 1e-6 * Fm.mean()


# ----------------------------------------------------------------------- the SSP
SSP_SHORT = ROOT / "tests" / "data" / "ssp-short.toml"


@pytest.fixture(scope="module")
def short_packages(tmp_path_factory, built):
    """The scenario files of tests/data/ssp-short.toml in FMI 3.0 and FMI 2.0."""
    from pantocosim.master.ssp import write_scenario_package

    out = tmp_path_factory.mktemp("short3")
    for fmi in (3, 2):
        write_scenario_package(out / f"fmi{fmi}", scenarios=[SSP_SHORT], quiet=True, fmi=fmi)
    return out


def test_the_fmi3_scenario_ssp_is_valid_and_holds_fmi3_fmus(built):
    from pantocosim.master.ssp import validate_ssp

    ssp = built / "fmi3" / "dsa380-ave-300.ssp"
    validate_ssp(ssp)                                   # the SSP 1.0 schemas
    with zipfile.ZipFile(ssp) as z:
        fmus = [n for n in z.namelist() if n.endswith(".fmu")]
        assert sorted(fmus) == ["resources/catenary.fmu", "resources/dsa380-rigid.fmu"]
        for name in fmus:
            with zipfile.ZipFile(z.open(name)) as f:
                assert ET.fromstring(f.read("modelDescription.xml")).get("fmiVersion") \
                    == "3.0"
    assert not (built / "fmi3" / "dsa380-ave-300" / "cofmupy.json").exists()


def test_ecos_runs_the_fmi3_ssp_as_the_fmi2_one(short_packages, tmp_path):
    """ecos (ecospy) runs the short scenario's FMI 3.0 SSP as shipped: the contact force of
    its FMI 2.0 SSP to 1e-9 N. Skipped where ecospy or its libtbb.so.12 is missing."""
    from recipes import read_csv as read_recipe_csv
    from recipes import require_ecospy, run_recipe

    require_ecospy()
    forces = {}
    for fmi in (3, 2):
        out = tmp_path / f"ecos{fmi}.csv"
        stats, _ = run_recipe("ecos", "--ssp", short_packages / f"fmi{fmi}" / "ssp-short.ssp",
                              "--out", out)
        assert stats["master"] == "ecos"
        forces[fmi] = read_recipe_csv(out)["contact_force_1"]
    assert len(forces[3]) == len(forces[2]) > 100 and np.ptp(forces[2]) > 1.0
    assert np.max(np.abs(forces[3] - forces[2])) <= 1e-9


def test_ssp_command_pairs_an_fmi3_pantograph_with_the_fmi3_catenary(fmus3, tmp_path):
    fmu = tmp_path / "mine.fmu"
    shutil.copy(fmus3["en50318-2mass"], fmu)
    proc = subprocess.run([sys.executable, "-m", "pantocosim.master.cli", "ssp",
                           "--pantograph", str(fmu), "--scenario", str(SSP_SHORT), "--out",
                           str(tmp_path / "mine.ssp")], capture_output=True, text=True,
                          timeout=900)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    with zipfile.ZipFile(tmp_path / "mine.ssp") as z:
        for name in ("resources/mine.fmu", "resources/catenary.fmu"):
            with zipfile.ZipFile(z.open(name)) as f:
                assert ET.fromstring(f.read("modelDescription.xml")).get("fmiVersion") \
                    == "3.0", name


# ----------------------------------------------------------------------- the C host
@pytest.mark.parametrize("name", NAMES)
def test_every_fmi3_fmu_runs_in_the_c_host_as_in_fmpy(host, fmus3, tmp_path, name):
    case = CATENARY_RUN if name == "catenary" else PANTOGRAPH_RUN
    script = stepping_script(tmp_path, fmus3[name], case)
    native, twin = run_host(host, script, tmp_path), run_twin(script)
    assert_clean_exit(native)
    assert twin.returncode == 0, twin.stderr[-3000:]
    a, b = results(native.stdout), results(twin.stdout)
    gets = list(b)
    assert len(gets) == 40
    for line in gets:
        assert a[line][0] == OK and b[line][0] == OK
        np.testing.assert_allclose(a[line][1:], b[line][1:], rtol=1e-12, atol=0.0)
    assert np.ptp([b[line][1] for line in gets]) > 1e-7


@pytest.mark.parametrize("name", ["en50318-2mass", "catenary"])
def test_the_c_host_gives_the_same_numbers_with_fmi3_and_fmi2(host, fmus3, fmus, tmp_path,
                                                             name):
    case = CATENARY_RUN if name == "catenary" else PANTOGRAPH_RUN
    (tmp_path / "3").mkdir()
    (tmp_path / "2").mkdir()
    s3 = stepping_script(tmp_path / "3", fmus3[name], case)
    s2 = stepping_script(tmp_path / "2", fmus[name], case)
    p3, p2 = run_host(host, s3, tmp_path / "3"), run_host(host, s2, tmp_path / "2")
    assert_clean_exit(p3)
    assert_clean_exit(p2)
    a, b = results(p3.stdout), results(p2.stdout)
    assert list(a) == list(b) and len(a) > 40
    for line in a:
        assert a[line] == b[line]                     # 17 digits: bit for bit


def test_refused_calls_return_fmi3_statuses_and_the_instance_stays_usable(host, fmus3,
                                                                           tmp_path):
    s = Script(tmp_path)
    s.load("A", fmus3["en50318-2mass"])
    s.load("B", fmus3["en50318-2mass"])
    s.start("A", "A", PANTOGRAPH_RUN[0])
    s.start("B", "B", PANTOGRAPH_RUN[0])
    lines = {
        "first_step": s.call("step", "A", 0.0, 1e-3),
        "unknown_vr": s.call("set", "A", "r", 99999, 1.0),
        "fixed_late": s.set("A", "speed_kmh", 123.0),
        "real_on_int32": s.call("set", "A", "r", s.vr("A", "start_mode"), 2.5),
        "after_refusals": s.call("step", "A", 1e-3, 1e-3),
        "state": s.call("getstate", "A", 0),
        "freed": s.call("freestate", "A", 0),
        "set_freed": s.call("setstate", "A", 0),
        "b_state": s.call("getstate", "B", 1),
        "serialize_b": s.call("serialize", "B", 1),
        "garbage": s.call("garbage", "A", 2),
        "deserialize_b_into_a": s.call("deserialize", "A", 1, "B"),
        "set_deserialized": s.call("setstate", "A", 1),
        "h_zero": s.call("step", "A", 0.0, 0.0),
        "terminate_after_discard": s.call("terminated", "A"),
        "last_time_after_discard": s.call("lasttime", "A"),
        "wrong_time": s.call("step", "A", 0.5, 1e-3),
        "unsupported": s.call("unsupported", "A"),
        "valid_after_all": s.call("step", "A", 0.0, 1e-3),   # B's time (its state)
        "last_time_after_ok": s.call("lasttime", "A"),
    }
    lines["foreign_in_memory"] = s.call("setstate", "A", 1, "B")
    s.call("free", "A")
    s.call("free", "B")
    proc = run_host(host, s, tmp_path)
    assert_clean_exit(proc)
    r = results(proc.stdout)
    expected = {"first_step": OK, "unknown_vr": ERROR, "fixed_late": ERROR,
                "real_on_int32": ERROR, "after_refusals": OK, "state": OK, "freed": OK,
                "set_freed": ERROR, "garbage": ERROR, "deserialize_b_into_a": OK,
                "set_deserialized": OK, "h_zero": DISCARD, "wrong_time": DISCARD,
                "unsupported": ERROR, "valid_after_all": OK, "foreign_in_memory": ERROR}
    assert {k: r[lines[k]][0] for k in expected} == expected
    # a discard the master may roll back from does not ask to terminate
    assert r[lines["terminate_after_discard"]] == [OK, 0]
    assert r[lines["last_time_after_discard"]] == [OK, 0.0]
    assert r[lines["last_time_after_ok"]] == [OK, 1e-3]
    for text in ("logStatusError fmi3SetFloat64: unknown value reference 99999",
                 "logStatusError fmi3SetFloat64: 'speed_kmh' (vr",
                 "can only be set before fmi3ExitInitializationMode (FMI 3.0)",
                 "logStatusError fmi3SetFloat64: 'start_mode' (vr",
                 "logStatusError fmi3SetFMUState:", "(freed, of another instance",
                 "logStatusError fmi3DeserializeFMUState: the bytes are not a pantocosim",
                 "logStatusDiscard fmi3DoStep(t = 0.0, h = 0.0)",
                 "logStatusDiscard fmi3DoStep(t = 0.5, h = 0.001): the communication point",
                 "logStatusError fmi3GetOutputDerivatives: not supported"):
        assert text in proc.stdout, text


def test_event_mode_follows_the_fmi3_state_machine(host, fmus3, tmp_path):
    s = Script(tmp_path)
    s.load("A", fmus3["en50318-2mass"])
    s.load("B", fmus3["en50318-2mass"])
    s.call("instantiate", "A", "events", "events")
    s.call("setup", "A", 0.0)
    s.call("enter", "A")
    s.set("A", "initial_contact_force", 120.0)
    s.call("exit", "A")                               # into event mode
    lines = {
        "step_in_event_mode": s.call("step", "A", 0.0, 1e-3),
        "update": s.call("update", "A"),
        "step_mode": s.call("stepmode", "A"),
        "step": s.call("step", "A", 0.0, 1e-3),
        "step_mode_twice": s.call("stepmode", "A"),
        "event_mode": s.call("eventmode", "A"),
        "update_again": s.call("update", "A"),
        "back": s.call("stepmode", "A"),
        "next_step": s.call("step", "A", 1e-3, 1e-3),
    }
    s.start("B", "no_events", PANTOGRAPH_RUN[0])
    lines["b_event_mode"] = s.call("eventmode", "B")
    lines["b_update"] = s.call("update", "B")
    lines["b_step_mode"] = s.call("stepmode", "B")
    lines["b_step"] = s.call("step", "B", 0.0, 1e-3)
    proc = run_host(host, s, tmp_path)
    assert_clean_exit(proc)
    r = results(proc.stdout)
    expected = {"step_in_event_mode": ERROR, "update": OK, "step_mode": OK, "step": OK,
                "step_mode_twice": ERROR, "event_mode": OK, "update_again": OK, "back": OK,
                "next_step": OK, "b_event_mode": ERROR, "b_update": ERROR,
                "b_step_mode": ERROR, "b_step": OK}
    assert {k: r[lines[k]][0] for k in expected} == expected
    assert r[lines["update"]] == [OK, 0, 0, 0, 0, 0]   # nothing to update, no next event
    assert "fmi3DoStep: in event mode: call fmi3EnterStepMode first" in proc.stdout
    assert "fmi3EnterEventMode: the instance was made with eventModeUsed = false" \
        in proc.stdout


def test_a_failed_initialisation_returns_fmi3error_and_asks_to_terminate(host, fmus3,
                                                                        tmp_path):
    s = Script(tmp_path)
    s.load("A", fmus3["catenary"])
    s.start("A", "cat", {"catenary_definition": "no-such-line"})
    exit_line = len(s.lines)
    step = s.call("step", "A", 0.0, 1e-3)
    terminate = s.call("terminated", "A")
    proc = run_host(host, s, tmp_path)
    assert_clean_exit(proc)
    r = results(proc.stdout)
    assert r[exit_line][0] == ERROR and r[step][0] == DISCARD
    assert r[terminate] == [OK, 1]
    assert "no-such-line" in proc.stdout


@pytest.mark.parametrize("name", ["dsa380-rigid", "catenary"])
def test_state_rollback_is_bit_for_bit(host, fmus3, tmp_path, name):
    """Step, save, step on, restore, step again: the same values to the last bit; the
    serialized state continues in a fresh instance to the same values."""
    params, port, outputs = CATENARY_RUN if name == "catenary" else PANTOGRAPH_RUN
    s = Script(tmp_path)
    s.load("A", fmus3[name])
    s.load("B", fmus3[name])
    s.start("A", "A", params)
    s.start("B", "B", params)

    def steps(alias, k0, n):
        lines = []
        for k in range(k0, k0 + n):
            s.set(alias, port, 120.0 + 30.0 * np.sin(40.0 * (k + 1) * 1e-3))
            s.call("step", alias, repr(k * 1e-3), repr(1e-3))
            lines.append(s.get(alias, *outputs))
        return lines

    steps("A", 0, 5)
    s.call("getstate", "A", 0)
    s.call("serialize", "A", 0)
    first = steps("A", 5, 5)
    restored = s.call("setstate", "A", 0)
    again = steps("A", 5, 5)
    s.call("deserialize", "B", 0, "A")
    moved = s.call("setstate", "B", 0)
    fresh = steps("B", 5, 5)
    proc = run_host(host, s, tmp_path)
    assert_clean_exit(proc)
    r = results(proc.stdout)
    assert r[restored][0] == OK and r[moved][0] == OK
    for a, b, c in zip(first, again, fresh):
        assert r[a][0] == OK
        assert r[a] == r[b] == r[c]                   # 17 digits: bit for bit
    assert len({tuple(r[a][1:]) for a in first}) == 5  # the steps moved

"""The Python FMUs in a C host (their embedding library, no Python host): the C host of
fmus/native/host (compiled here with the system's C compiler) dlopens each FMU's linux64
binary and runs the FMI 2.0 call sequence in a clean environment (no LD_PRELOAD, no PYTHONPATH, no virtual environment on PATH, another
working folder). Its outputs equal fmpy's; every refused call returns fmi2Error (fmi2Discard
from doStep) with a categorised message; the process never aborts."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from fmi_script import Script, results
from tooling import c_compiler

ROOT = Path(__file__).resolve().parents[1]
TWIN = ROOT / "tests" / "fmi_script.py"
OK, WARNING, DISCARD, ERROR = 0, 1, 2, 3

#: the parameters and the input of each FMU's run (a short line for the catenary)
PANTOGRAPH_RUN = ({"initial_contact_force": 120.0}, "contact_force",
                  ("contact_height", "contact_velocity"))
CATENARY_RUN = ({"catenary_definition": "en50318", "spans": 4, "speed_kmh": 250.0,
                 "position_1": 30.0, "static_force_1": 120.0}, "contact_force_1",
                ("wire_height_1", "wire_velocity_1", "support_uplift_1"))


@pytest.fixture(scope="session")
def host(tmp_path_factory):
    """The C host (FMI 2.0 and 3.0), compiled with the system's C compiler."""
    from pantocosim.master.native.host import HOST_NAME, host_sources

    exe = tmp_path_factory.mktemp("host") / HOST_NAME
    subprocess.run([c_compiler(), "-std=c99", "-O1", "-o", str(exe),
                    *map(str, host_sources()), "-ldl", "-lm"], check=True)
    return exe


def clean_env(home: Path, **extra) -> dict:
    """What a C host started from a desktop has: no Python variables, no venv on PATH."""
    env = {"PATH": "/usr/local/bin:/usr/bin:/bin", "HOME": str(home), "LANG": "C.UTF-8"}
    env.update(extra)
    return env


def run_host(host, script: Script, tmp: Path, **env) -> subprocess.CompletedProcess:
    work = tmp / "elsewhere"
    work.mkdir(exist_ok=True)
    return subprocess.run([str(host), "script"], input=script.text(), capture_output=True,
                          text=True, cwd=work, env=clean_env(tmp, **env), timeout=600)


def run_twin(script: Script) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(TWIN)], input=script.text(),
                          capture_output=True, text=True, cwd=TWIN.parent, timeout=600)


def stepping_script(tmp: Path, fmu: Path, case, steps: int = 40, h: float = 1e-3):
    """start, then ``steps`` doSteps under a varying input, reading the outputs each step."""
    params, port, outputs = case
    s = Script(tmp)
    s.load("A", fmu)
    s.start("A", "unit", params)
    for k in range(steps):
        s.set("A", port, 120.0 + 30.0 * np.sin(40.0 * (k + 1) * h))
        s.call("step", "A", repr(k * h), repr(h))
        s.get("A", *outputs)
    s.call("terminate", "A")
    s.call("free", "A")
    return s


def assert_clean_exit(proc):
    """Exit code 0, no abort, no message without a category."""
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    assert "(null)" not in proc.stdout
    assert "corrupted" not in proc.stderr and "Fatal" not in proc.stderr, proc.stderr[-3000:]


@pytest.mark.parametrize("name", ["dsa380-rigid", "dsa380-flexible", "dsa380-lumped3",
                                  "en50318-2mass", "catenary"])
def test_every_fmu_runs_in_the_c_host_as_in_fmpy(host, fmus, tmp_path, name):
    case = CATENARY_RUN if name == "catenary" else PANTOGRAPH_RUN
    script = stepping_script(tmp_path, fmus[name], case)
    native, twin = run_host(host, script, tmp_path), run_twin(script)
    assert_clean_exit(native)
    assert twin.returncode == 0, twin.stderr[-3000:]
    a, b = results(native.stdout), results(twin.stdout)
    gets = [line for line in b]
    assert len(gets) == 40
    for line in gets:
        assert a[line][0] == OK and b[line][0] == OK
        np.testing.assert_allclose(a[line][1:], b[line][1:], rtol=1e-12, atol=0.0)
    moved = np.ptp([b[line][1] for line in gets])
    assert moved > 1e-7                               # the run is not a constant


def test_refused_calls_return_fmi2error_and_the_instance_stays_usable(host, fmus, tmp_path):
    s = Script(tmp_path)
    s.load("A", fmus["en50318-2mass"])
    s.load("B", fmus["en50318-2mass"])
    s.start("A", "A", PANTOGRAPH_RUN[0])
    s.start("B", "B", PANTOGRAPH_RUN[0])
    lines = {
        "first_step": s.call("step", "A", 0.0, 1e-3),
        "unknown_vr": s.call("set", "A", "r", 99999, 1.0),
        "fixed_late": s.set("A", "speed_kmh", 123.0),
        "after_refusals": s.call("step", "A", 1e-3, 1e-3),
        "state": s.call("getstate", "A", 0),
        "freed": s.call("freestate", "A", 0),
        "set_freed": s.call("setstate", "A", 0),
        "free_freed": s.call("freestate", "A", 0),
        "b_state": s.call("getstate", "B", 1),
        "serialize_b": s.call("serialize", "B", 1),
        "garbage": s.call("garbage", "A", 2),
        "deserialize_b_into_a": s.call("deserialize", "A", 1, "B"),
        "set_deserialized": s.call("setstate", "A", 1),
        "h_zero": s.call("step", "A", 0.0, 0.0),
        "terminated_after_discard": s.call("terminated", "A"),
        "unsupported": s.call("unsupported", "A"),
        "valid_after_all": s.call("step", "A", 0.0, 1e-3),   # B's time (its state)
        "terminated_after_ok": s.call("terminated", "A"),
    }
    lines["foreign_in_memory"] = s.call("setstate", "A", 1, "B")   # B's own state pointer
    s.call("free", "A")
    s.call("free", "B")
    proc = run_host(host, s, tmp_path)
    assert_clean_exit(proc)
    r = results(proc.stdout)
    expected = {"first_step": OK, "unknown_vr": ERROR, "fixed_late": ERROR,
                "after_refusals": OK, "state": OK, "freed": OK, "set_freed": ERROR,
                "free_freed": ERROR, "garbage": ERROR, "deserialize_b_into_a": OK,
                "set_deserialized": OK, "h_zero": DISCARD, "unsupported": ERROR,
                "valid_after_all": OK, "foreign_in_memory": ERROR}
    assert {k: r[lines[k]][0] for k in expected} == expected
    assert r[lines["terminated_after_discard"]] == [OK, 1]
    assert r[lines["terminated_after_ok"]] == [OK, 0]
    log = proc.stdout
    for text in ("logStatusError fmi2SetReal: unknown value reference 99999",
                 "logStatusError fmi2SetReal: 'speed_kmh'",
                 "logStatusError fmi2SetFMUstate:", "(freed, of another instance",
                 "logStatusError fmi2DeSerializeFMUstate: the bytes are not a pantocosim",
                 "logStatusDiscard fmi2DoStep(t = 0.0, h = 0.0)",
                 "logStatusError fmi2SetRealInputDerivatives: not supported"):
        assert text in log, text


def test_a_failed_initialisation_returns_fmi2error(host, fmus, tmp_path):
    s = Script(tmp_path)
    s.load("A", fmus["catenary"])
    s.start("A", "cat", {"catenary_definition": "no-such-line"})
    step = s.call("step", "A", 0.0, 1e-3)
    proc = run_host(host, s, tmp_path)
    assert_clean_exit(proc)
    r = results(proc.stdout)
    assert r[step - 1][0] == ERROR                  # fmi2ExitInitializationMode
    assert r[step][0] == DISCARD
    assert "logStatusError initialisation: " in proc.stdout
    assert "no-such-line" in proc.stdout


def test_no_python_found_is_logged_and_instantiate_returns_null(host, fmus, tmp_path):
    s = Script(tmp_path)
    s.load("A", fmus["en50318-2mass"])
    runtime = tmp_path / "A" / "resources" / "pantocosim_runtime.txt"
    runtime.write_text("executable=/nonexistent/bin/python\n")
    line = s.call("instantiate", "A", "lost")
    proc = subprocess.run([str(host), "script"], input=s.text(), capture_output=True, text=True,
                          cwd=tmp_path, timeout=120,
                          env={"PATH": str(tmp_path / "empty"), "HOME": str(tmp_path),
                               "PANTOCOSIM_PYTHON": "/nonexistent/python3"})
    assert_clean_exit(proc)
    assert results(proc.stdout)[line][0] == ERROR      # NULL
    assert "LOG lost 3 logStatusError no usable Python runtime" in proc.stdout
    assert "/nonexistent/bin/python: does not run" in proc.stdout
    assert "Set PANTOCOSIM_PYTHON" in proc.stdout


def test_pantocosim_python_names_the_runtime(host, fmus, tmp_path):
    """An FMU whose building Python is gone runs on the one $PANTOCOSIM_PYTHON names."""
    script = stepping_script(tmp_path, fmus["en50318-2mass"], PANTOGRAPH_RUN, steps=3)
    runtime = tmp_path / "A" / "resources" / "pantocosim_runtime.txt"
    runtime.write_text("executable=/nonexistent/bin/python\n")
    proc = run_host(host, script, tmp_path, PANTOCOSIM_PYTHON=sys.executable)
    assert_clean_exit(proc)
    assert [v[0] for v in results(proc.stdout).values()] == [OK] * len(results(proc.stdout))


# ----------------------------------------------------------------------- bad inputs
#: (FMU, parameters, input value or None) -> what must happen, and a text of the message
GUARDS = {
    "pantograph_substeps": ("en50318-2mass", {"n_substeps": 10 ** 9}, None, "n_substeps"),
    "catenary_substeps": ("catenary", {"n_substeps": 10 ** 9}, None, "n_substeps"),
    "tiny_elements": ("catenary", {"element_size": 1e-4}, None, "element_size = 0.0001"),
    "small_elements": ("catenary", {"element_size": 1e-2}, None, "max_dofs ="),
    "endless_line": ("catenary", {"spans": 100000}, None, "spans = 100000"),
    "more_spans_than_outputs": ("catenary", {"spans": 70}, None, "at most 63 spans"),
    "catenary_beyond_wave_speed": ("catenary", {"speed_kmh": 1e5}, None,
                                   "must be below the contact wire's wave speed"),
}


@pytest.mark.parametrize("case", list(GUARDS))
def test_parameters_the_model_cannot_represent_are_refused_at_initialisation(host, fmus,
                                                                             tmp_path, case):
    name, params, _, text = GUARDS[case]
    base = CATENARY_RUN[0] if name == "catenary" else PANTOGRAPH_RUN[0]
    s = Script(tmp_path)
    s.load("A", fmus[name])
    s.start("A", "guard", {**base, **params})
    exit_line = len(s.lines)
    step = s.call("step", "A", 0.0, 1e-3)
    proc = run_host(host, s, tmp_path)             # answers at once: nothing is built
    assert_clean_exit(proc)
    r = results(proc.stdout)
    assert r[exit_line][0] == ERROR and r[step][0] == DISCARD
    assert text in proc.stdout


def test_a_collector_driven_out_of_the_mechanism_is_discarded(host, fmus, tmp_path):
    """dsa380-rigid under 1e7 N: the step that leaves the mechanism's heights is discarded
    and undone; the collector never reads far off."""
    s = Script(tmp_path)
    s.load("A", fmus["dsa380-rigid"])
    s.start("A", "far", PANTOGRAPH_RUN[0])
    s.set("A", "contact_force", 1e7)
    steps = [s.call("step", "A", repr(k * 1e-3), 1e-3) for k in range(30)]
    read = s.get("A", "contact_height")
    proc = run_host(host, s, tmp_path)
    assert_clean_exit(proc)
    r = results(proc.stdout)
    assert DISCARD in [r[line][0] for line in steps]
    assert "outside the heights pantograph 'dsa380-rigid' represents" in proc.stdout
    assert 4.0 < r[read][1] < 7.0


def test_a_speed_beyond_the_pantograph_is_refused(host, fmus, tmp_path):
    """dsa380-rigid at 1e6 km/h: the aerodynamic uplift no spring carries."""
    s = Script(tmp_path)
    s.load("A", fmus["dsa380-rigid"])
    s.start("A", "fast", {**PANTOGRAPH_RUN[0], "speed_kmh": 1e6})
    exit_line = len(s.lines)
    step = s.call("step", "A", 0.0, 1e-3)
    proc = run_host(host, s, tmp_path)
    assert_clean_exit(proc)
    r = results(proc.stdout)
    assert r[exit_line][0] == ERROR and r[step][0] == DISCARD
    assert "speed_kmh = 1000000.0: the aerodynamic uplift at this speed" in proc.stdout


def test_a_state_taken_before_initialisation_is_refused_after_it(host, fmus, tmp_path):
    s = Script(tmp_path)
    s.load("A", fmus["en50318-2mass"])
    s.call("instantiate", "A", "early")
    s.call("setup", "A", 0.0)
    s.call("enter", "A")
    s.call("getstate", "A", 0)
    s.call("exit", "A")
    s.call("step", "A", 0.0, 1e-3)
    refused = s.call("setstate", "A", 0)
    step = s.call("step", "A", 1e-3, 1e-3)
    proc = run_host(host, s, tmp_path)
    assert_clean_exit(proc)
    r = results(proc.stdout)
    assert r[refused][0] == ERROR and r[step][0] == OK
    assert "taken before fmi2ExitInitializationMode" in proc.stdout

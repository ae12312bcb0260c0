"""The embedding library (fmus/fmi/embedding/) on its own: compiled with every warning
and GCC's static analyser, and run in the C host of fmus/native/host and in a threaded Python
host over a small slave (tests/c_hosts/slow_slave.py) instead of a built FMU: the runtime
probe reads any answer without overflow and within a time bound, names the interpreter it
tried and what it lacked; no Python error outlives a call; an instance or FMU state freed on
another thread waits for the call under way; a missing resources folder is named."""

import json
import os
import shutil
import subprocess
import sys
import sysconfig
import textwrap
import time
from pathlib import Path

import pytest
from fmi_script import results
from tooling import missing
from test_native_host import assert_clean_exit, clean_env, host  # noqa: F401  (fixture)

from pantocosim.fmi.embedding import BRIDGE_SOURCE, COMMON_SOURCES, EXPORTS
from pantocosim.master.fmu.embedding import compile_export_library, compiler

ROOT = Path(__file__).resolve().parents[1]
SLAVE = ROOT / "tests" / "c_hosts" / "slow_slave.py"
OK, WARNING, ERROR = 0, 1, 3


@pytest.fixture(scope="session")
def libraries(tmp_path_factory):
    """{FMI version: the embedding library compiled as build-fmus compiles it}."""
    if compiler() is None:
        missing("a C compiler", "apt-get install -y gcc")
    work = tmp_path_factory.mktemp("export")
    return {v: compile_export_library(work, v) for v in (2, 3)}


def slow_fmu(folder: Path, library: Path, fmi: int = 2, runtime: str = sys.executable) -> Path:
    """An extracted FMU folder of the slow slave with the embedding library of ``fmi``."""
    export = EXPORTS[fmi]
    folder.mkdir(parents=True, exist_ok=True)     # the host reads the FMI version here
    (folder / "modelDescription.xml").write_text(
        f'<fmiModelDescription fmiVersion="{fmi}.0" modelName="slow"/>\n')
    (folder / "binaries" / export.platform).mkdir(parents=True)
    shutil.copy(library, folder / "binaries" / export.platform / "slow.so")
    res = folder / "resources"
    res.mkdir()
    shutil.copy(BRIDGE_SOURCE, res / f"{export.bridge_module}.py")
    shutil.copy(SLAVE, res / "slow_slave.py")
    (res / "slavemodule.txt").write_text("slow_slave\n")
    (res / "pantocosim_runtime.txt").write_text(f"executable={runtime}\n")
    return folder


def run(host, folder: Path, calls: list[str], tmp: Path, timeout=120, **env):
    script = "\n".join([f"load A {folder} slow token", *calls]) + "\n"
    start = time.monotonic()
    proc = subprocess.run([str(host), "script"], input=script, capture_output=True, text=True,
                          cwd=tmp, timeout=timeout, env=clean_env(tmp, **env))
    return proc, time.monotonic() - start


def fake_python(tmp: Path, body: str) -> Path:
    exe = tmp / "fake-python"
    exe.write_text("#!/bin/sh\nPATH=/usr/bin:/bin\n" + textwrap.dedent(body))
    exe.chmod(0o755)
    return exe


@pytest.mark.parametrize("fmi", [2, 3])
def test_the_library_compiles_clean_with_all_warnings_and_the_analyser(libraries, fmi,
                                                                        tmp_path):
    cmd = [compiler(), "-std=c11", "-O2", "-fPIC", "-shared", "-fvisibility=hidden", "-Wall",
           "-Wextra", "-fanalyzer", "-o", str(tmp_path / "lib.so"), str(EXPORTS[fmi].source),
           *map(str, COMMON_SOURCES), "-ldl", "-lpthread"]
    done = subprocess.run(cmd, capture_output=True, text=True)
    if "fanalyzer" in done.stderr and "unrecognized" in done.stderr:
        pytest.skip("the C compiler has no -fanalyzer (GCC >= 10)")
    assert done.returncode == 0 and done.stderr == "", done.stderr


@pytest.mark.parametrize("answer", ["long_first_line", "long_missing_line"])
def test_a_long_probe_answer_is_refused_without_overflow(host, libraries, tmp_path, answer):
    body = {"long_first_line": "head -c 100000 /dev/zero | tr '\\0' x; echo; echo /x; echo\n",
            "long_missing_line": "echo; echo /x; head -c 5000 /dev/zero | tr '\\0' m; echo\n"}
    exe = fake_python(tmp_path, body[answer])
    fmu = slow_fmu(tmp_path / "fmu", libraries[2], runtime="/nonexistent/python")
    proc, _ = run(host, fmu, ["instantiate A a"], tmp_path, PANTOCOSIM_PYTHON=str(exe),
                  PATH=str(tmp_path / "empty"))
    assert_clean_exit(proc)
    assert results(proc.stdout)[2][0] == ERROR
    assert f"PANTOCOSIM_PYTHON = {exe}: is not a Python that answers the probe" in proc.stdout


def test_a_probe_that_never_answers_is_stopped_and_named(host, libraries, tmp_path):
    pid_file = tmp_path / "probe.pid"
    exe = fake_python(tmp_path, f"echo $$ > {pid_file}\nexec sleep 600\n")
    fmu = slow_fmu(tmp_path / "fmu", libraries[2], runtime="/nonexistent/python")
    proc, wall = run(host, fmu, ["instantiate A a"], tmp_path, PANTOCOSIM_PYTHON=str(exe),
                     PANTOCOSIM_PROBE_TIMEOUT_S="2", PATH=str(tmp_path / "empty"))
    assert_clean_exit(proc)
    assert results(proc.stdout)[2][0] == ERROR
    assert f"PANTOCOSIM_PYTHON = {exe}: did not answer within 2 s" in proc.stdout
    assert wall < 30.0
    with pytest.raises(ProcessLookupError):          # stopped, and reaped
        os.kill(int(pid_file.read_text()), 0)


@pytest.mark.parametrize("value", ["abc", "-1", "0", "nan", "inf", "1e6", "1e5x"])
def test_a_bad_probe_time_bound_is_refused_naming_the_variable(host, libraries, tmp_path,
                                                               value):
    fmu = slow_fmu(tmp_path / "fmu", libraries[2])
    proc, _ = run(host, fmu, ["instantiate A a"], tmp_path, PANTOCOSIM_PROBE_TIMEOUT_S=value)
    assert_clean_exit(proc)
    assert results(proc.stdout)[2][0] == ERROR
    assert (f"PANTOCOSIM_PROBE_TIMEOUT_S = '{value}': not a time bound: give seconds, a "
            "number > 0 and below 1e+06 (default 30)") in proc.stdout


def test_a_probe_time_bound_with_blanks_is_taken(host, libraries, tmp_path):
    exe = fake_python(tmp_path, "exec sleep 600\n")
    fmu = slow_fmu(tmp_path / "fmu", libraries[2], runtime="/nonexistent/python")
    proc, wall = run(host, fmu, ["instantiate A a"], tmp_path, PANTOCOSIM_PYTHON=str(exe),
                     PANTOCOSIM_PROBE_TIMEOUT_S=" 1 ", PATH=str(tmp_path / "empty"))
    assert results(proc.stdout)[2][0] == ERROR
    assert f"PANTOCOSIM_PYTHON = {exe}: did not answer within 1 s" in proc.stdout
    assert wall < 20.0


def test_a_skipped_interpreter_is_a_warning_naming_the_one_used(host, libraries, tmp_path):
    exe = fake_python(tmp_path, "exec sleep 600\n")
    fmu = slow_fmu(tmp_path / "fmu", libraries[2])
    proc, _ = run(host, fmu, ["instantiate A a", "free A"], tmp_path,
                  PANTOCOSIM_PYTHON=str(exe), PANTOCOSIM_PROBE_TIMEOUT_S="1")
    assert_clean_exit(proc)
    assert results(proc.stdout)[2][0] == OK
    assert (f"LOG a 1 logStatusWarning the FMUs run in the build's Python {sys.executable}"
            in proc.stdout)
    assert f"skipped: PANTOCOSIM_PYTHON = {exe}: did not answer within 1 s" in proc.stdout


def test_a_python_error_of_one_call_does_not_poison_the_next(host, libraries, tmp_path):
    """fmi2GetIntegerStatus(fmi2LastSuccessfulTime): the bridge's value is a float."""
    fmu = slow_fmu(tmp_path / "fmu", libraries[2])
    calls = ["instantiate A a", "setup A 0", "enter A", "exit A", "step A 0 0.001",
             "intstatus A 2", "step A 0.001 0.001", "get A r 0", "free A"]
    proc, _ = run(host, fmu, calls, tmp_path)
    assert_clean_exit(proc)
    r = results(proc.stdout)
    assert r[7][0] == ERROR
    assert "fmi2GetIntegerStatus: status kind 2 has no integer value" in proc.stdout
    assert r[8] == [OK] and r[9] == [OK, 0.002]
    assert "SystemError" not in proc.stdout


THREADS = r'''
import ctypes as C, json, os, pathlib, sys, threading, time
marks = pathlib.Path(os.environ["SLOW_SLAVE_MARKS"])
lib = C.CDLL(sys.argv[1])
LOG = C.CFUNCTYPE(None, C.c_void_p, C.c_char_p, C.c_int, C.c_char_p, C.c_char_p, C.c_char_p)
logged = []
logger = LOG(lambda env, name, status, category, fmt, text: logged.append(text.decode()))
class Callbacks(C.Structure):
    _fields_ = [("logger", LOG), ("allocate", C.c_void_p), ("free", C.c_void_p),
                ("finished", C.c_void_p), ("env", C.c_void_p)]
callbacks = Callbacks(logger, None, None, None, None)
lib.fmi2Instantiate.restype = C.c_void_p
lib.fmi2Instantiate.argtypes = [C.c_char_p, C.c_int, C.c_char_p, C.c_char_p,
                                C.POINTER(Callbacks), C.c_int, C.c_int]
for name in ("fmi2SetupExperiment", "fmi2EnterInitializationMode", "fmi2ExitInitializationMode",
             "fmi2SetReal", "fmi2DoStep", "fmi2GetFMUstate", "fmi2SetFMUstate",
             "fmi2FreeFMUstate", "fmi2SerializedFMUstateSize"):
    getattr(lib, name).restype = C.c_int
lib.fmi2FreeInstance.argtypes = [C.c_void_p]
lib.fmi2SetupExperiment.argtypes = [C.c_void_p, C.c_int, C.c_double, C.c_double, C.c_int,
                                    C.c_double]
lib.fmi2DoStep.argtypes = [C.c_void_p, C.c_double, C.c_double, C.c_int]
for name in ("fmi2EnterInitializationMode", "fmi2ExitInitializationMode"):
    getattr(lib, name).argtypes = [C.c_void_p]
c = C.c_void_p(lib.fmi2Instantiate(b"A", 1, b"", sys.argv[2].encode(), C.byref(callbacks), 0, 1))
out = {"instantiated": bool(c.value)}
lib.fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0)
lib.fmi2EnterInitializationMode(c)
lib.fmi2ExitInitializationMode(c)
vr, delay = (C.c_uint * 1)(1), (C.c_double * 1)(0.6)
lib.fmi2SetReal(c, vr, 1, delay)                     # serialising and stepping take 0.6 s
state = C.c_void_p()
out["get_state"] = lib.fmi2GetFMUstate(c, C.byref(state))

def in_thread(name, fn, call):
    """Run fn on a thread; return once the slave says ``call`` is under way (30 s at most)."""
    def body():
        out[name + "_start"] = time.monotonic()
        out[name] = fn()
        out[name + "_end"] = time.monotonic()
    t = threading.Thread(target=body)
    t.start()
    deadline = time.monotonic() + 30.0
    while not (marks / call).exists():
        assert time.monotonic() < deadline, f"{call} never began"
        time.sleep(0.005)
    out[name + "_begun"] = time.monotonic()
    return t

size = C.c_size_t(0)
t = in_thread("size", lambda: lib.fmi2SerializedFMUstateSize(c, state, C.byref(size)),
              "serialize")
copy = C.c_void_p(state.value)
out["free_state"] = lib.fmi2FreeFMUstate(c, C.byref(copy))
out["free_state_end"] = time.monotonic()
t.join()
out["size_bytes"] = size.value
out["set_freed_state"] = lib.fmi2SetFMUstate(c, state)
t = in_thread("step", lambda: lib.fmi2DoStep(c, 0.0, 1e-3, 1), "step")
lib.fmi2FreeInstance(c)
out["free_instance_end"] = time.monotonic()
t.join()
out["step_after_free"] = lib.fmi2DoStep(c, 1e-3, 1e-3, 1)
out["logged"] = logged
print(json.dumps(out))
'''


def test_a_state_or_instance_freed_on_another_thread_waits_for_the_call(libraries, tmp_path):
    fmu = slow_fmu(tmp_path / "fmu", libraries[2])
    script = tmp_path / "threads.py"
    script.write_text(THREADS)
    marks = tmp_path / "marks"
    marks.mkdir()
    proc = subprocess.run([sys.executable, str(script), str(fmu / "binaries" / "linux64" /
                                                         "slow.so"),
                           f"file://{fmu}/resources"], capture_output=True, text=True,
                          timeout=120, env={**os.environ, "SLOW_SLAVE_MARKS": str(marks)})
    assert proc.returncode == 0, proc.stderr[-3000:]
    out = json.loads(proc.stdout.splitlines()[-1])
    assert out["instantiated"] and out["get_state"] == OK
    assert out["size"] == OK and out["size_bytes"] > 0
    # the free, made once the call was under way, waited for it (0.6 s from its start),
    # whatever the order in which the two threads read the clock after it
    assert out["size_begun"] < out["free_state_end"] and out["size_begun"] < out["size_end"]
    assert out["free_state"] == OK and out["free_state_end"] >= out["size_start"] + 0.55
    assert out["set_freed_state"] == ERROR
    assert out["step"] == OK and out["free_instance_end"] >= out["step_start"] + 0.55
    assert out["step_after_free"] == ERROR


def test_an_fmi3_fmu_without_its_resources_names_them(host, libraries, tmp_path):
    fmu = slow_fmu(tmp_path / "fmu", libraries[3], fmi=3)
    shutil.rmtree(fmu / "resources")
    proc, _ = run(host, fmu, ["instantiate A a"], tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert results(proc.stdout)[2][0] == ERROR
    assert f"the FMU's resources folder {fmu}/resources is missing" in proc.stdout
    assert "pantocosim_fmi3_bridge.py" in proc.stdout
    (fmu / "resources").mkdir()
    proc, _ = run(host, fmu, ["instantiate A a"], tmp_path)
    assert f"{fmu}/resources has no readable pantocosim_fmi3_bridge.py" in proc.stdout


def shared_libpython() -> Path | None:
    """This Python's shared libpython, found as the library's probe finds it."""
    v = sysconfig.get_config_var
    for name in (v("INSTSONAME"), v("LDLIBRARY")):
        for folder in (v("LIBDIR"), "/usr/lib/" + (v("MULTIARCH") or "")):
            path = Path(folder or "", name or "")
            if name and ".so" in name and path.is_file():
                return path
    return None


def test_a_host_with_its_own_libpython_names_it_and_what_it_lacks(host, libraries, tmp_path):
    """The FMU runs in the Python already loaded in the host's process; a module missing
    there is named with that Python."""
    lib = shared_libpython()
    if lib is None:
        pytest.skip("this Python has no shared libpython")
    fmu = slow_fmu(tmp_path / "fmu", libraries[2])
    proc, _ = run(host, fmu, ["instantiate A a"], tmp_path, LD_PRELOAD=str(lib),
                  SLOW_SLAVE_IMPORT="no_such_module_of_the_host")
    assert_clean_exit(proc)
    assert results(proc.stdout)[2][0] == ERROR
    # the host's Python starts without the venv: what it lacks first depends on the install
    line = next(t for t in proc.stdout.splitlines() if "fmi2Instantiate: No module named" in t)
    assert f"[in Python {sys.version.split()[0]} (sys.executable " in line
    assert f"the host process's own Python ({lib}, already loaded" in line

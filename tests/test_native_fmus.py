"""The native C FMUs of ``pantocosim export-native``: the C host (fmus/native/host,
compiled here) runs them with no Python on PATH from another folder and gets the Python
models' numbers; the win64 binaries under wine give the Linux numbers; the FMU's own
sources/ build the same library; doStep allocates nothing; bad data and bad inputs get the
statuses the Python FMUs give; in our master (explicit and implicit) the native catenary
gives the Python catenary FMU's contact force."""

import dataclasses
import shutil
import subprocess
import zipfile
from pathlib import Path

import numpy as np
import pytest
from tooling import required

from pantocosim.master.native.build import CFLAGS

ROOT = Path(__file__).resolve().parents[1]
STEPS, DT = 600, 0.001


@pytest.fixture(scope="module")
def prepared():
    from pantocosim.master.run import prepare
    from pantocosim.master.scenario import load_scenario

    sc = dataclasses.replace(load_scenario("en50318-300"), catenary_model="linear")
    return prepare(sc)


@pytest.fixture(scope="module")
def exported(prepared, tmp_path_factory):
    """The scenario's native FMUs, unpacked: {name: folder}."""
    from pantocosim.master.native.models import export_scenario

    required("gcc", "gcc")
    out = tmp_path_factory.mktemp("native")
    written, kept = export_scenario(prepared, out / "fmus")
    assert kept == []
    folders = {}
    for fmu in written:
        folder = out / fmu.stem
        with zipfile.ZipFile(fmu) as z:
            z.extractall(folder)
        folders[fmu.stem] = folder
    folders["files"] = {p.stem: p for p in written}
    folders["mean_uplift"] = float(prepared.pantographs[0].options.mean_uplift)
    return folders


@pytest.fixture(scope="module")
def host(tmp_path_factory):
    from pantocosim.master.native.host import build_host

    required("gcc", "gcc")
    return build_host(tmp_path_factory.mktemp("host"))


def run_host(exe, args, tmp_path, wrapper=()):
    """The host in an environment with no Python at all (an empty PATH, no PYTHON* or
    PANTOCOSIM_* variables), from another folder."""
    empty = tmp_path / "empty-path"
    work = tmp_path / "elsewhere"
    empty.mkdir(exist_ok=True)
    work.mkdir(exist_ok=True)
    env = {"PATH": str(empty), "HOME": str(tmp_path), "LANG": "C"}
    if wrapper:
        env.update(WINEDEBUG="-all", WINEPREFIX=str(tmp_path.parent / "wineprefix"))
    proc = subprocess.run([*wrapper, str(exe), *map(str, args)], capture_output=True,
                          text=True, cwd=work, env=env, timeout=900)
    assert proc.returncode == 0, proc.stderr[-3000:]
    rows = [line.split() for line in proc.stdout.splitlines() if line[:1].isdigit()]
    counts = {line.split(":")[0]: int(line.split(":")[1]) for line in proc.stdout.splitlines()
              if line.startswith("allocations") and line.split(":")[1].strip().isdigit()}
    return np.array(rows, dtype=float), counts


def forcing(F0, t):
    """The host's forced mode: F0 (1 + 0.1 sin(2 pi 7 t)) + 20 N after 0.3 s."""
    return F0 * (1.0 + 0.1 * np.sin(2.0 * 3.141592653589793 * 7.0 * t)) + (20.0 if t > 0.3
                                                                             else 0.0)


@pytest.mark.slow
def test_modal_catenary_in_a_c_host_equals_the_python_model(host, tmp_path):
    """The native modal catenary (modes below the scenario's cutoff, static corrections at the
    droppers and the moving contact points) against the Python modal model's closed-form
    steps under the host's forcing."""
    from pantocosim.master.native.models import export_catenary
    from pantocosim.master.run import prepare
    from pantocosim.master.scenario import load_scenario

    prep = prepare(dataclasses.replace(load_scenario("en50318-300"), catenary_model="modal"))
    fmu = export_catenary(prep, tmp_path / "modal.fmu", "modal", win64=False)
    folder = tmp_path / "modal"
    with zipfile.ZipFile(fmu) as z:
        z.extractall(folder)
    got, counts = run_host(host, ["forced", folder, STEPS, DT], tmp_path)
    want = python_catenary(prep, STEPS)
    motion = np.max(np.abs(want[:, 1] - want[0, 1]))
    assert motion > 1e-3
    assert np.max(np.abs(got[:, 1] - want[:, 1])) < 1e-9 * motion
    assert np.max(np.abs(got[:, 2] - want[:, 2])) < 1e-9 * np.max(np.abs(want[:, 2]))
    assert np.max(np.abs(got[:, 3:] - want[:, 3:])) < 1e-9 * np.max(np.abs(want[:, 3:]))
    assert counts["allocations in doStep"] == 0


def python_catenary(prep, steps):
    """The Python catenary FMU's stepper and outputs under the host's forcing: rows of t,
    wire height and velocity, support uplifts."""
    from pantocosim.core.hht import HHTSettings
    from pantocosim.interaction.stepper_factory import make_stepper

    sc, model = prep.scenario, prep.catenary
    F0 = prep.static_forces
    integ = make_stepper(model, HHTSettings.for_runs(sc.alpha, sc.newton_rtol), redo=True)
    integ.initialize(0.0, model.static_state(F0), np.zeros(model.n_dofs), F0.copy())
    rows = []
    for i in range(steps):
        t1 = (i + 1) * DT
        integ.step(DT, forcing(F0, t1))
        z, v = model.wire_state(integ.t, integ.q, integ.v)
        rows.append([t1, *np.ravel(np.column_stack([z, v])), *model.support_uplift(integ.q)])
    return np.array(rows)


def test_catenary_in_a_c_host_equals_the_python_model(prepared, exported, host, tmp_path):
    got, counts = run_host(host, ["forced", exported["catenary"], STEPS, DT], tmp_path)
    want = python_catenary(prepared, STEPS)
    assert got.shape == want.shape
    motion = np.max(np.abs(want[:, 1] - want[0, 1]))
    assert motion > 1e-3                        # the wire moves (a real test)
    assert np.max(np.abs(got[:, 1] - want[:, 1])) < 1e-9 * motion
    assert np.max(np.abs(got[:, 2] - want[:, 2])) < 1e-9 * np.max(np.abs(want[:, 2]))
    uplift = np.max(np.abs(want[:, 3:]))
    assert np.max(np.abs(got[:, 3:] - want[:, 3:])) < 1e-9 * uplift
    # droppers slackened on the way: the exact slackening was exercised
    dr = prepared.catenary.droppers
    assert counts["allocations in doStep"] == 0
    assert counts["allocations outside doStep"] > 0     # the counting works
    assert dr is not None


def pantograph_matches(prep, folder, host, tmp_path):
    """The native pantograph of ``prep``'s first pantograph in the C host against the Python
    pantograph FMU's stepper (the same model, start and closed-form step), to 1e-12."""
    from pantocosim.core.hht import HHTIntegrator, HHTSettings
    from pantocosim.master.run.setup import scenario_pantograph

    sc = prep.scenario
    got, counts = run_host(host, ["pantograph", folder, STEPS, DT], tmp_path)
    model = scenario_pantograph(sc, 0)
    F0 = float(prep.static_forces[0])
    q0 = model.static_equilibrium(F0, prep.pantographs[0].contact_height(prep.q_pan0[0]))
    integ = HHTIntegrator(model, HHTSettings(alpha=sc.alpha))
    assert integ.closed_form
    integ.initialize(0.0, q0, np.zeros(model.n_dofs), np.array([F0]))
    want = []
    for i in range(STEPS):
        t1 = (i + 1) * DT
        integ.step(DT, np.array([F0 * (1.0 + 0.1 * np.sin(2.0 * 3.141592653589793 * 7.0 * t1))]))
        want.append([t1, integ.q[0], integ.v[0]])
    want = np.array(want)
    assert np.max(np.abs(want[:, 1] - want[0, 1])) > 1e-4
    assert np.max(np.abs(got[:, 1] - want[:, 1])) <= 1e-12 * np.max(np.abs(want[:, 1]))
    assert np.max(np.abs(got[:, 2] - want[:, 2])) <= 1e-12 * np.max(np.abs(want[:, 2]))
    assert counts["allocations in doStep"] == 0


def test_pantograph_in_a_c_host_equals_the_python_fmu_stepper(prepared, exported, host,
                                                               tmp_path):
    pantograph_matches(prepared, exported["en50318-2mass"], host, tmp_path)


def test_three_mass_pantograph_in_a_c_host_equals_the_python_fmu_stepper(host, tmp_path):
    from pantocosim.master.native.models import export_pantograph
    from pantocosim.master.run import prepare
    from pantocosim.master.scenario import load_scenario

    text = (ROOT / "master" / "scenarios" / "en50318-300.toml").read_text()
    path = tmp_path / "lumped3.toml"
    path.write_text(text.replace("en50318-2mass", "dsa380-lumped3"))
    prep = prepare(dataclasses.replace(load_scenario(str(path)), catenary_model="linear"))
    fmu = export_pantograph(prep, 0, tmp_path / "dsa380-lumped3.fmu", win64=False)
    folder = tmp_path / "lumped3"
    with zipfile.ZipFile(fmu) as z:
        z.extractall(folder)
    pantograph_matches(prep, folder, host, tmp_path)


def test_the_fmu_builds_from_its_own_sources(exported, host, tmp_path):
    """sources/ alone, any C99 compiler flags of the issue, gives the same numbers."""
    folder = exported["catenary"]
    copy = tmp_path / "rebuilt"
    shutil.copytree(folder, copy)
    lib = copy / "binaries" / "linux64" / "pantocosim_catenary_native.so"
    lib.unlink()
    sources = sorted((copy / "sources").glob("*.c"))
    subprocess.run(["gcc", *CFLAGS, "-fPIC", "-shared", "-fvisibility=hidden",
                    f"-I{copy / 'sources'}", *map(str, sources), "-o", str(lib), "-lm"],
                   check=True)
    a, _ = run_host(host, ["forced", folder, 50, DT], tmp_path)
    b, _ = run_host(host, ["forced", copy, 50, DT], tmp_path)
    assert np.array_equal(a, b)
    deps = subprocess.run(["ldd", str(lib)], capture_output=True, text=True).stdout
    libs = {line.split()[0] for line in deps.splitlines() if "=>" in line}
    assert libs <= {"libm.so.6", "libc.so.6"}, libs


@pytest.mark.slow
def test_win64_binaries_under_wine_give_the_linux_numbers(exported, host, tmp_path):
    mingw = required("x86_64-w64-mingw32-gcc", "gcc-mingw-w64-x86-64")
    wine = shutil.which("wine64") or required("wine", "wine64")
    from pantocosim.master.native.host import HOST_NAME, host_sources

    exe = tmp_path / (HOST_NAME + ".exe")
    subprocess.run([mingw, *CFLAGS, "-o", str(exe), *map(str, host_sources())], check=True)
    n = 200
    for name, mode in (("catenary", "forced"), ("en50318-2mass", "pantograph")):
        folder = exported[name]
        assert (folder / "binaries" / "win64" / f"{'pantocosim_catenary_native' if name == 'catenary' else 'pantocosim_pantograph_native'}.dll").exists()
        linux, _ = run_host(host, [mode, folder, n, DT], tmp_path)
        windows, counts = run_host(exe, [mode, "Z:" + str(folder).replace("/", "\\"), n, DT],
                                   tmp_path, wrapper=(wine,))
        assert windows.shape == linux.shape
        scale = np.max(np.abs(linux), axis=0)
        assert np.all(np.abs(windows - linux) <= 1e-12 * np.maximum(scale, 1e-300)), name
        assert counts["allocations in doStep"] == 0


def test_coupled_loop_runs_without_python(exported, host, tmp_path):
    got, counts = run_host(host, ["coupled", exported["catenary"], exported["en50318-2mass"],
                                  400, DT], tmp_path)
    F = got[:, 1]
    mean_uplift = exported["mean_uplift"]
    assert np.all(np.isfinite(F)) and np.all(F >= 0.0)
    assert abs(F.mean() / mean_uplift - 1.0) < 0.2       # the pantograph presses on the wire
    assert np.all(np.abs(got[:, 2] - got[:, 3]) < 0.05)  # and follows it
    assert counts["allocations in doStep"] == 0


def test_the_host_names_what_it_cannot_load(exported, host, tmp_path):
    """The FMI version comes from modelDescription.xml, the library from the host's platform
    folder: an FMU without either is refused naming the file (exit 2), never run."""
    cases = {}
    md = (exported["catenary"] / "modelDescription.xml").read_text()
    old = shutil.copytree(exported["catenary"], tmp_path / "fmi1")
    (old / "modelDescription.xml").write_text(md.replace('fmiVersion="2.0"',
                                                         'fmiVersion="1.0"', 1))
    cases[old] = "fmiVersion 1.0 (2.0 or 3.0 accepted)"
    bare = shutil.copytree(exported["catenary"], tmp_path / "no-binaries")
    shutil.rmtree(bare / "binaries" / "linux64")
    cases[bare] = f"cannot load {bare}/binaries/linux64/pantocosim_catenary_native.so"
    nameless = shutil.copytree(exported["catenary"], tmp_path / "no-variable")
    (nameless / "modelDescription.xml").write_text(md.replace('name="n_supports"',
                                                              'name="supports"', 1))
    cases[nameless] = "modelDescription.xml: no variable n_supports"
    for folder, message in cases.items():
        proc = subprocess.run([str(host), "forced", str(folder), "5", str(DT)],
                              capture_output=True, text=True, timeout=60)
        assert proc.returncode == 2 and message in proc.stderr, (message, proc.stderr)
        assert not [line for line in proc.stdout.splitlines() if line[:1].isdigit()]


# ---------------------------------------------------------------------- FMI behaviour
OK, DISCARD, ERROR = 0, 2, 3


def slave(folder, identifier):
    """The native FMU of ``folder`` in fmpy, initialised."""
    from fmpy import read_model_description
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(str(folder / "modelDescription.xml"))
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=str(folder), modelIdentifier=identifier,
                    instanceName="native")
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.exitInitializationMode()
    return fmu, {v.name: v.valueReference for v in md.modelVariables}


def status_of(call, *args) -> int:
    from fmpy.fmi1 import FMICallException

    try:
        call(*args)
    except FMICallException as exc:
        return exc.status
    return OK


def test_bad_inputs_get_the_python_fmus_statuses(exported):
    cat = exported["catenary"]
    fmu, vr = slave(cat, "pantocosim_catenary_native")
    ref, _ = slave(cat, "pantocosim_catenary_native")
    F = [vr["contact_force_1"]]
    out = [vr["wire_height_1"], vr["wire_velocity_1"]]
    for bad in (float("nan"), -1.0, float("inf")):
        fmu.setReal(F, [bad])
        assert status_of(fmu.doStep, 0.0, DT) == DISCARD        # refused, state kept
    fmu.setReal(F, [150.0])
    ref.setReal(F, [150.0])
    fmu.doStep(0.0, DT)
    ref.doStep(0.0, DT)
    assert fmu.getReal(out) == ref.getReal(out)
    # a communication step that is not a whole number of internal steps, or more of them than
    # the FMU takes in one call: refused, the instance steps on
    assert status_of(fmu.doStep, DT, 1.5 * DT) == DISCARD
    assert status_of(fmu.doStep, DT, 2e6) == DISCARD
    # a contact force no pantograph applies is refused before the step
    fmu.setReal(F, [1e300])
    assert status_of(fmu.doStep, DT, DT) == DISCARD
    fmu.setReal(F, [150.0])
    ref.setReal(F, [150.0])
    assert status_of(fmu.doStep, DT, DT) == OK
    ref.doStep(DT, DT)
    assert fmu.getReal(out) == ref.getReal(out)
    # a step that would take the pantograph off the contact wire is refused before it is taken
    far, vr2 = slave(cat, "pantocosim_catenary_native")
    assert status_of(far.doStep, 0.0, 10.0) == DISCARD
    far.setReal([vr2["contact_force_1"]], [150.0])
    assert status_of(far.doStep, 0.0, 2 * DT) == OK
    # fixed parameters: the export's value is accepted, another one is refused naming it
    from fmpy import read_model_description
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(str(cat / "modelDescription.xml"))
    fresh = FMU2Slave(guid=md.guid, unzipDirectory=str(cat),
                      modelIdentifier="pantocosim_catenary_native", instanceName="fresh")
    fresh.instantiate()
    speed = next(v for v in md.modelVariables if v.name == "speed_kmh")
    assert status_of(fresh.setReal, [speed.valueReference], [float(speed.start)]) == OK
    assert status_of(fresh.setReal, [speed.valueReference], [250.0]) == ERROR
    pan, pvr = slave(exported["en50318-2mass"], "pantocosim_pantograph_native")
    pan.setReal([pvr["contact_force"]], [float("nan")])
    assert status_of(pan.doStep, 0.0, DT) == DISCARD
    pan.setReal([pvr["contact_force"]], [150.0])
    assert status_of(pan.doStep, 0.0, 2e6) == DISCARD           # 2e9 internal steps: refused
    pan.setReal([pvr["contact_force"]], [1e9])                 # throws the head off its range
    assert status_of(pan.doStep, 0.0, DT) == DISCARD
    assert status_of(pan.doStep, 0.0, DT) == DISCARD           # only a rollback recovers


def other_token(token: str) -> str:
    """token with its first hex digit changed: another export's, as far as the FMU knows."""
    return token[0] + ("1" if token[1] == "0" else "0") + token[2:]


def test_another_guid_is_refused_with_one_message_and_the_right_one_simulates(exported,
                                                                              capfd):
    from fmpy import read_model_description, simulate_fmu
    from fmpy.fmi2 import FMU2Slave

    folder = exported["en50318-2mass"]
    md = read_model_description(str(folder / "modelDescription.xml"))
    for guid in (other_token(md.guid), ""):
        fmu = FMU2Slave(guid=guid, unzipDirectory=str(folder),
                        modelIdentifier="pantocosim_pantograph_native", instanceName="wrong")
        capfd.readouterr()
        with pytest.raises(Exception, match="[Ii]nstantiate"):
            fmu.instantiate(loggingOn=True)
        log = capfd.readouterr().out
        assert log.count("instantiation token") == 1 and md.guid in log, log
        assert f'"{guid}"' in log, log
        fmu.freeLibrary()
    force = np.array([(0.0, 200.0), (1.0, 200.0)], dtype=[("time", float),
                                                          ("contact_force", float)])
    result = simulate_fmu(str(folder), stop_time=20 * DT, step_size=DT, output_interval=DT,
                          input=force, output=["contact_height"])
    z = result["contact_height"]
    assert len(z) == 21 and np.all(np.isfinite(z))
    assert np.all(np.diff(z) < 0.0)         # 200 N, above its static force, presses it down


def assert_states_roll_back(fmu, F, out, steps):
    """Under a varying ``F``: ``steps`` steps after the first, redone from its FMU state and
    from that state serialized and read back, give the same ``out`` bit for bit. Returns
    (the state, its serialization, the outputs)."""
    fmu.setReal(F, [130.0])
    fmu.doStep(0.0, DT)
    state = fmu.getFMUstate()
    blob = fmu.serializeFMUstate(state)
    runs = []
    for restore in (lambda: state, lambda: state, lambda: fmu.deSerializeFMUstate(blob)):
        fmu.setFMUstate(restore())
        for i in range(1, steps):
            fmu.setReal(F, [130.0 + 40.0 * np.sin(i / 3.0)])
            fmu.doStep(i * DT, DT)
        runs.append(fmu.getReal(out))
    assert runs[0] == runs[1] == runs[2]
    return state, blob, runs[0]


def test_fmu_states_roll_back_and_serialize(exported):
    fmu, vr = slave(exported["catenary"], "pantocosim_catenary_native")
    F, out = [vr["contact_force_1"]], [vr["wire_height_1"], vr["support_uplift_1"]]
    state, blob, _ = assert_states_roll_back(fmu, F, out, 30)
    fmu.freeFMUstate(state)
    damaged = bytearray(blob)
    damaged[-1] ^= 0xFF
    assert status_of(fmu.deSerializeFMUstate, bytes(damaged)) == ERROR


def test_validate_fmu_finds_no_problem(exported):
    from fmpy.validation import validate_fmu

    for path in exported["files"].values():
        assert validate_fmu(str(path)) == [], path


def rewritten(folder: Path, tmp_path: Path, data: bytes) -> Path:
    copy = tmp_path / f"fmu-{len(list(tmp_path.glob('fmu-*')))}"
    shutil.copytree(folder, copy)
    (copy / "resources" / "model.pcsdata").write_bytes(data)
    return copy


def test_a_damaged_or_foreign_data_file_is_an_error_naming_it(exported, host, tmp_path):
    from pantocosim.master.native.data_file import pack_data, read_data
    from pantocosim.master.native.headers import fields

    cat = exported["catenary"]
    path = cat / "resources" / "model.pcsdata"
    good = path.read_bytes()
    kind, sections = read_data(path)
    damaged = bytearray(good)
    damaged[len(good) // 2] ^= 0x10
    sizes = dict(sections, sizes=sections["sizes"].copy())
    sizes["sizes"][fields("LIN_SIZE").index("PANTOGRAPHS")] = 9
    fast = dict(sections, scalars=sections["scalars"].copy())
    scalar = fields("CAT_SCALAR").index
    fast["scalars"][scalar("SPEED")] = fast["scalars"][scalar("WAVE_SPEED")]
    pantograph = (exported["en50318-2mass"] / "resources" / "model.pcsdata").read_bytes()
    cases = {"checksum mismatch": bytes(damaged), "not a pantocosim data file": b"\x7fELF" * 40,
             "shorter than its": good[:20], "payload bytes": good[:-8],
             "model kind 3": pantograph, "section sizes": pack_data(kind, sizes),
             "wave speed": pack_data(kind, fast)}
    for reason, data in cases.items():
        folder = rewritten(cat, tmp_path, data)
        proc = subprocess.run([str(host), "forced", str(folder), "1", str(DT)],
                              capture_output=True, text=True, timeout=60)
        assert proc.returncode == 4, (reason, proc.stdout, proc.stderr)   # no crash
        assert reason in proc.stderr and "model.pcsdata" in proc.stderr, (reason, proc.stderr)


# ---------------------------------------------------------------------- in our master
@pytest.mark.slow
@pytest.mark.parametrize("model", ["linear", "modal"])
@pytest.mark.parametrize("scenario", ["en50318-300", "dsa380-ave-300"])
def test_native_catenary_in_our_master_gives_the_python_catenary_fmus_force(
        scenario, model, fmus, tmp_path):
    """Explicit (Jacobi) and implicit co-simulation with the Python pantograph FMU: the native
    catenary FMU and the Python catenary FMU of the same model (linear, modal) give the same
    contact force to 1e-9."""
    from pantocosim.master.cosim import run_cosim
    from pantocosim.master.fmu.check import FmuPlan
    from pantocosim.master.native.models import export_catenary
    from pantocosim.master.run import prepare
    from pantocosim.master.scenario import load_scenario

    required("gcc", "gcc")
    sc = dataclasses.replace(load_scenario(scenario), catenary_model=model)
    prep = prepare(sc)
    native = export_catenary(prep, tmp_path / "catenary.fmu", model, win64=False)
    pantographs = [fmus[p.model] for p in sc.pantographs]
    for scheme in ("jacobi", "implicit"):
        forces = {}
        for label, catenary in (("python", fmus["catenary"]), ("native", native)):
            res = run_cosim(prep, None, scheme, plan=FmuPlan(catenary, pantographs, [None]),
                            progress=False)
            assert res.error is None, res.error
            forces[label] = res.columns["contact_force_1"]
        py, nat = forces["python"], forces["native"]
        assert len(py) == len(nat) == prep.n_steps + 1
        assert np.max(np.abs(nat - py)) <= 1e-9 * np.max(np.abs(py)), scheme


@pytest.mark.slow
@pytest.mark.parametrize("model", ["linear", "modal"])
def test_native_catenary_implicit_equals_the_monolithic_run(model, fmus, tmp_path):
    """The implicit coupling of the native catenary FMU with the Python pantograph FMU
    reproduces the monolithic run of the same catenary model to the bar the Python FMUs meet
    (tests/test_fmu_cosim.py: 1e-6 of the mean force, tight coupling tolerance)."""
    from pantocosim.master.cosim import run_cosim
    from pantocosim.master.fmu.check import FmuPlan
    from pantocosim.master.native.models import export_catenary
    from pantocosim.master.run import prepare, run_monolithic
    from pantocosim.master.scenario import load_scenario

    required("gcc", "gcc")
    short = Path(__file__).parent / "data" / "short-en50318.toml"
    sc = dataclasses.replace(load_scenario(str(short)), catenary_model=model)
    prep = prepare(sc)
    mono = run_monolithic(prep, None, progress=False).columns["contact_force_1"]
    native = export_catenary(prep, tmp_path / "catenary.fmu", model, win64=False)
    res = run_cosim(prep, None, "implicit",
                    plan=FmuPlan(native, [fmus[p.model] for p in sc.pantographs], [None]),
                    progress=False)
    assert res.error is None, res.error
    F = res.columns["contact_force_1"]
    assert len(F) == len(mono) == prep.n_steps + 1
    assert np.max(np.abs(F - mono)) < 1e-6 * mono.mean()


# ---------------------------------------------------------------------- FMI 3.0
def test_fmi3_fmus_validate_and_give_the_fmi2_numbers(prepared, exported, tmp_path):
    from fmpy import extract, read_model_description
    from fmpy.fmi3 import FMU3Slave
    from fmpy.validation import validate_fmu

    from pantocosim.master.native.models import export_scenario

    written, _ = export_scenario(prepared, tmp_path / "fmi3", fmi=3, win64=False)
    for path in written:
        assert validate_fmu(str(path)) == [], path
        with zipfile.ZipFile(path) as z:
            names = z.namelist()
        assert "sources/buildDescription.xml" in names
        assert any(n.startswith("binaries/x86_64-linux/") for n in names)
    fmi3 = next(p for p in written if p.stem == "catenary")
    md = read_model_description(str(fmi3))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    wrong = FMU3Slave(guid=other_token(md.guid), unzipDirectory=extract(str(fmi3)),
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="wrong")
    with pytest.raises(Exception, match="[Ii]nstantiate"):
        wrong.instantiate()                   # another instantiationToken: refused
    fmu = FMU3Slave(guid=md.guid, unzipDirectory=extract(str(fmi3)),
                    modelIdentifier=md.coSimulation.modelIdentifier, instanceName="c3")
    fmu.instantiate()
    fmu.enterInitializationMode(startTime=0.0)
    fmu.exitInitializationMode()
    assert fmu.getInt32([vr["n_pantographs"]]) == [1]
    fmu2, vr2 = slave(exported["catenary"], "pantocosim_catenary_native")
    F0 = float(prepared.static_forces[0])
    for i in range(100):
        F = F0 + 50.0 * np.sin(i / 7.0)
        fmu.setFloat64([vr["contact_force_1"]], [F])
        fmu.doStep(i * DT, DT)
        fmu2.setReal([vr2["contact_force_1"]], [F])
        fmu2.doStep(i * DT, DT)
    names = ["wire_height_1", "wire_velocity_1", "support_uplift_1"]
    assert fmu.getFloat64([vr[n] for n in names]) == fmu2.getReal([vr2[n] for n in names])
    state = fmu.getFMUState()
    fmu.doStep(100 * DT, DT)
    after = fmu.getFloat64([vr["wire_height_1"]])
    fmu.setFMUState(state)
    fmu.doStep(100 * DT, DT)
    assert fmu.getFloat64([vr["wire_height_1"]]) == after


@pytest.mark.slow
@pytest.mark.parametrize("model", ["linear", "modal"])
def test_penalty_contact_inside_equals_the_python_catenary_fmu(model, prepared, exported, fmus,
                                                               tmp_path):
    """contact_mode 1 (pantograph heights in, the penalty law inside, solved implicitly with
    the wire): the native catenary gives the Python catenary FMU's contact force (the same
    model), through a loss of contact."""
    from pantocosim.catenary.models import model_code

    if model == "linear":
        cat = exported["catenary"]
    else:
        from pantocosim.master.native.models import export_catenary
        from pantocosim.master.run import prepare

        prepared = prepare(dataclasses.replace(prepared.scenario, catenary_model=model))
        fmu = export_catenary(prepared, tmp_path / "modal.fmu", model, win64=False)
        cat = tmp_path / "modal"
        with zipfile.ZipFile(fmu) as z:
            z.extractall(cat)
    sc = prepared.scenario
    F0 = float(prepared.static_forces[0])
    params = {"catenary_definition": sc.catenary, "speed_kmh": sc.speed_kmh,
              "n_pantographs": 1, "position_1": sc.pantographs[0].position_m,
              "static_force_1": F0, "hht_alpha": sc.alpha, "contact_mode": 1,
              "catenary_model": model_code(model),
              "modal_cutoff_hz": sc.modal_cutoff_hz, "newton_rtol": sc.newton_rtol}
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(str(fmus["catenary"]))
    pvr = {v.name: v.valueReference for v in md.modelVariables}
    py = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(fmus["catenary"])),
                   modelIdentifier=md.coSimulation.modelIdentifier, instanceName="python")
    py.instantiate()
    py.setupExperiment(startTime=0.0)
    for name, value in params.items():
        if isinstance(value, str):
            py.setString([pvr[name]], [value])
        elif isinstance(value, int):
            py.setInteger([pvr[name]], [value])
        else:
            py.setReal([pvr[name]], [float(value)])
    py.enterInitializationMode()
    py.exitInitializationMode()
    from fmpy.fmi2 import FMU2Slave as Slave

    md2 = read_model_description(str(cat / "modelDescription.xml"))
    nvr = {v.name: v.valueReference for v in md2.modelVariables}
    na = Slave(guid=md2.guid, unzipDirectory=str(cat),
               modelIdentifier="pantocosim_catenary_native", instanceName="native")
    na.instantiate()
    na.setupExperiment(startTime=0.0)
    na.setInteger([nvr["contact_mode"]], [1])
    na.enterInitializationMode()
    na.exitInitializationMode()
    z0 = na.getReal([nvr["wire_height_1"]])[0] + F0 / prepared.contact.stiffness
    forces = []
    for i in range(800):
        t = i * DT
        z = z0 + 0.004 * np.sin(2 * np.pi * 3 * t)
        v = 0.004 * 2 * np.pi * 3 * np.cos(2 * np.pi * 3 * t)
        row = []
        for fmu, vr in ((py, pvr), (na, nvr)):
            fmu.setReal([vr["pantograph_height_1"], vr["pantograph_velocity_1"]], [z, v])
            fmu.doStep(t, DT)
            row.append(fmu.getReal([vr["contact_force_out_1"]])[0])
        forces.append(row)
    forces = np.array(forces)
    assert forces[:, 0].min() == 0.0 and forces[:, 0].max() > 150.0     # loses contact
    assert np.max(np.abs(forces[:, 1] - forces[:, 0])) <= 1e-9 * forces[:, 0].max()


def syscall_counts(strace_output: Path) -> dict:
    """{system call: calls} of ``strace -c``'s table."""
    out = {}
    for line in strace_output.read_text().splitlines():
        words = line.split()
        if len(words) >= 5 and words[0][0].isdigit() and words[-1] != "total":
            out[words[-1]] = int(words[3])
    return out


def test_do_step_makes_no_system_call(exported, host, tmp_path):
    """The host's system calls over 30 and over 300 steps of the catenary are the same but
    for the writes of its printed rows: a step makes none (no file, no memory from the
    system, no clock call outside the vDSO)."""
    strace = required("strace", "strace")
    counts = []
    for steps in (30, 300):
        table = tmp_path / f"strace-{steps}.txt"
        subprocess.run([strace, "-f", "-c", "-o", str(table), str(host), "forced",
                        str(exported["catenary"]), str(steps), str(DT)], check=True,
                       capture_output=True, timeout=600)
        counts.append({k: v for k, v in syscall_counts(table).items() if k != "write"})
    assert counts[0] and counts[0] == counts[1]


def test_export_refuses_a_speed_at_or_above_the_wave_speed(tmp_path, capsys):
    from pantocosim.master.cli import main

    text = (ROOT / "master" / "scenarios" / "en50318-300.toml").read_text()
    path = tmp_path / "fast.toml"
    path.write_text(text.replace("speed_kmh = 300.0", "speed_kmh = 600.0"))
    out = tmp_path / "out"
    for extra in ([], ["--force"]):
        assert main(["export-native", str(path), "--out", str(out), *extra]) == 2
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and "speed_kmh = 600.0" in err, err
        assert "wave speed" in err
    assert not list(out.glob("*.fmu"))

"""Bad input, interrupts and full disks: every user error ends with one line naming
the file or flag, the field and the value, and exit status 2; Ctrl-C ends with status 130 and
keeps what was computed; nothing already written is lost; no silent wrong result.

One parametrized test per class of case (scenario, catenary and pantograph files, flags,
formulas, output places, FMU files, lost results, full disks, interrupts). The commands run
in this process through ``cli.main`` (fast) except where a real SIGINT or an FMU is needed
(child processes). ``scripts/bad_input_probe.py`` runs a larger set of the same kinds.
"""

import errno
import json
import os
import shutil
import signal
import subprocess
import sys
import time
import tracemalloc
import zipfile
from pathlib import Path

import pytest

from full_disk import FullDisk
from waiting import cpu_seconds, wait_until

from pantocosim.core.errors import ParameterError
from pantocosim.master.cli import main

ROOT = Path(__file__).resolve().parents[1]
CATENARY = ROOT / "fmus" / "catenary" / "data" / "en50318.toml"
PANTOGRAPH = ROOT / "fmus" / "pantograph" / "data" / "en50318-2mass.toml"

SCENARIO = """\
name = "bad"
catenary = "en50318"
spans = 4
speed_kmh = 250.0

[[pantographs]]
model = "en50318-2mass"
position_m = 30.0
start = "static"

[analysis]
window_m = [35.0, 60.0]

[simulation]
dt = 0.001
"""
RAMP = 'start = "ramp"\nramp = {{ start_m = {}, length_m = {}, lowered_height = {} }}'
SECOND = '\n[[pantographs]]\nmodel = "en50318-2mass"\nposition_m = {}\nstart = "static"\n'


def edited(text: str, *pairs) -> str:
    for old, new in pairs:
        assert old in text, old
        text = text.replace(old, new, 1)
    return text


def error_lines(err: str) -> list[str]:
    return [l for l in err.splitlines() if l.strip() and not l.startswith("building FMUs")]


@pytest.fixture
def no_long_work(monkeypatch):
    """The long work of a command (the catenary's static solves, time stepping) fails the
    test if it starts: refusals must come before it, on a machine of any speed."""
    import pantocosim.catenary.model as catenary_model
    from pantocosim.core.hht import HHTIntegrator

    def started(*args, **kwargs):
        raise AssertionError("the long work started before the refusal")

    for name in ("solve_static", "solve_initial_configuration"):
        monkeypatch.setattr(catenary_model, name, started)
    monkeypatch.setattr(HHTIntegrator, "step", started)


def run_cli(capsys, *argv) -> tuple[int, list[str]]:
    try:
        code = main([str(a) for a in argv])
    except SystemExit as exc:   # argparse
        code = exc.code
    return code, error_lines(capsys.readouterr().err)


def assert_one_line_error(code, lines, *names):
    """Exit status 2, one line, naming every string of ``names`` (field, value, file)."""
    assert code == 2, lines
    assert len(lines) == 1, lines
    assert "Traceback" not in lines[0]
    for name in names:
        assert name in lines[0], f"{name!r} not in {lines[0]!r}"


def leftovers(folder: Path) -> list[str]:
    """Staging folders a command left behind."""
    return [p.name for p in folder.iterdir() if p.name.endswith(".partial")]


# ----------------------------------------------------------------------------- scenarios
@pytest.mark.parametrize("pairs, names", [
    ([("speed_kmh = 250.0", 'speed_kmh = "fast"')], ["speed_kmh", "'fast'"]),
    ([("spans = 4", "spans = 2.5")], ["spans", "2.5"]),
    ([("spans = 4", "spans = 100000")], ["spans = 100000", "DOFs", "--max-dofs"]),
    ([("dt = 0.001", "dt = 1e-09")], ["simulation.dt = 1e-09", "--max-steps"]),
    ([("dt = 0.001", "dt = 0.001\nduration_s = 100.0")], ["simulation.duration_s = 100.0"]),
    ([('start = "static"', RAMP.format(31.0, 0.0, 5.0))],
     ["pantographs[0].ramp.length_m = 0.0"]),
    ([('start = "static"', RAMP.format(10.0, 2.0, 5.0))],
     ["pantographs[0].ramp.start_m = 10.0", "position_m = 30"]),
    ([('start = "static"', RAMP.format(31.0, 2.0, 50.0))],
     ["pantographs[0].ramp.lowered_height = 50.0", "contact wire"]),
    ([('start = "static"', RAMP.format(31.0, 20.0, 5.0))],
     ["pantographs[0].ramp.length_m = 20.0", "window"]),
    ([("\n[analysis]", SECOND.format(30.0) + "\n[analysis]")],
     ["pantographs[1].position_m = 30.0", "apart"]),
    ([("\n[analysis]", SECOND.format(31.0) + "\n[analysis]")],
     ["pantographs[1].position_m = 31.0"]),
    ([("window_m = [35.0, 60.0]", "window_m = [35.0, 60.0]\nwindow_supports = [1, 2]")],
     ["analysis.window_m = [35.0, 60.0]", "not both"]),
    ([("position_m = 30.0", "position_m = 40.0")], ["pantographs[0].position_m = 40.0"]),
    ([("speed_kmh = 250.0", "speed_kmh = 250.0\nspeed = 1.0")], ["speed = 1.0", "unknown"]),
    ([('start = "static"', 'start = "static"\noptions = { static_force = -5.0 }')],
     ["pantographs[0].options.static_force = -5.0"]),
])
def test_bad_scenario_is_one_line_naming_field_and_value(tmp_path, capsys, pairs, names,
                                                          no_long_work):
    sc = tmp_path / "bad.toml"
    sc.write_text(edited(SCENARIO, *pairs))
    code, lines = run_cli(capsys, "run", sc, "--quiet", "--no-plots", "--out", tmp_path / "o")
    assert_one_line_error(code, lines, "bad.toml", *names)
    assert not (tmp_path / "o").exists() and not leftovers(tmp_path)


@pytest.mark.parametrize("content, names", [
    (bytes(range(256)), ["file", "not a text (UTF-8) TOML file"]),
    ('name = "Zaragoza\xf1"\n'.encode("latin-1"), ["byte 0xf1"]),
    (b"name = \n[[[", ["invalid TOML"]),
    (None, ["is a folder"]),
])
def test_unreadable_scenario_file(tmp_path, capsys, content, names):
    sc = tmp_path / "sc.toml"
    if content is None:
        sc.mkdir()
    else:
        sc.write_bytes(content)
    code, lines = run_cli(capsys, "run", sc, "--quiet", "--out", tmp_path / "o")
    assert_one_line_error(code, lines, "sc.toml", *names)


# ----------------------------------------------------------------------------- catenary files
@pytest.mark.parametrize("pairs, names", [
    ([("tension = 20000.0", "tension = 0.0")], ["contact_wire.tension = 0.0"]),
    ([("element_size = 1.0", "element_size = 0.0001")],
     ["geometry.element_size = 0.0001", "DOFs", "GB", "--max-dofs"]),
    ([("count = 10", "count = 100000")], ["spans.count = 100000", "--max-dofs"]),
    ([("49.5, 55.0]", "49.5, 70.0]")], ["droppers.positions[8] = 70.0", "outside span"]),
    ([("gravity = 9.81", "gravity = -9.81")], ["gravity = -9.81"]),
    ([('type = "steady_arm"', 'type = "magic"')], ["type", "magic"]),
])
def test_bad_catenary_file_is_one_line(tmp_path, capsys, pairs, names, no_long_work):
    cat = tmp_path / "cat.toml"
    cat.write_text(edited(CATENARY.read_text(), *pairs))
    code, lines = run_cli(capsys, "static", cat)
    assert_one_line_error(code, lines, "cat.toml", *names)
    # the same file through a scenario names the catenary file too
    sc = tmp_path / "sc.toml"
    sc.write_text(edited(SCENARIO, ('catenary = "en50318"', f'catenary = "{cat}"'),
                         ("spans = 4\n", "")))
    code, lines = run_cli(capsys, "run", sc, "--quiet", "--out", tmp_path / "o")
    assert_one_line_error(code, lines, "cat.toml", *names)


def test_size_guard_estimate_and_override():
    """The DOF estimate is within 1 % of the built model; the limit is lifted by --max-dofs."""
    import dataclasses

    from pantocosim.catenary.definition import load_catenary, with_spans
    from pantocosim.catenary.mesh import estimate_dofs
    from pantocosim.catenary.model import CatenaryModel
    from pantocosim.master.size_limits import check_catenary_size

    for name, spans, size in (("en50318", 4, None), ("ave64", 3, 2.0)):
        d = with_spans(load_catenary(name), spans)
        if size:
            d = dataclasses.replace(d, element_size=size)
        assert estimate_dofs(d) == pytest.approx(CatenaryModel(d).n_dofs, rel=0.01), name
    d = load_catenary("en50318")
    with pytest.raises(ParameterError, match="--max-dofs 7680"):
        check_catenary_size(d, "spans", 10, "x.toml", max_dofs=5000)
    assert check_catenary_size(d, "spans", 10, "x.toml", max_dofs=7680) == 7680


# ----------------------------------------------------------------------------- pantograph files
@pytest.mark.parametrize("pairs, content, names", [
    ([], os.urandom(300), ["file", "pan.toml"]),
    ([("masses = [7.2, 15.0]", "masses = [-7.2, 15.0]")], None, ["chain.masses[0] = -7.2"]),
    ([("uplift_mass = 2", "uplift_mass = 2\ncolour = 1")], None, ["colour", "unknown"]),
    ([("static_force = 115.0", 'static_force = "x"')], None, ["static_force", "'x'"]),
])
def test_bad_pantograph_file_is_one_line(tmp_path, capsys, pairs, content, names):
    pan = tmp_path / "pan.toml"
    if content is None:
        pan.write_text(edited(PANTOGRAPH.read_text(), *pairs))
    else:
        pan.write_bytes(content)
    code, lines = run_cli(capsys, "modal", pan)
    assert_one_line_error(code, lines, "pan.toml", *names)


# ----------------------------------------------------------------------------- flags
PAN = ["pantograph", "en50318-2mass", "--force", "120"]


@pytest.mark.parametrize("argv, names", [
    (["run", "--coupling", "nope"], ["argument --coupling", "'nope'"]),
    (["frobnicate"], ["'frobnicate'"]),
    (["run", "en50318-250", "--max-dofs", "0"], ["--max-dofs = 0"]),
    (["run", "en50318-250", "--max-steps", "many"], ["--max-steps", "'many'"]),
    (["run", "en50318-250", "--modal-cutoff-hz", "nan"], ["--modal-cutoff-hz = nan"]),
    (PAN + ["--dt", "10", "--duration", "1"], ["--dt = 10.0", "--duration"]),
    (PAN + ["--duration", "1e9"], ["--duration = 1000000000.0", "--max-steps"]),
    (PAN + ["--duration", "inf"], ["--duration = inf"]),
    (PAN + ["--duration", "0.1", "--alpha", "0.5"], ["--alpha = 0.5"]),
    (PAN + ["--duration", "0.1", "--speed", "-100"], ["--speed = -100.0"]),
    (["modes", "en50318", "--count", "100000"], ["--count = 100000"]),
    (["modes", "en50318", "--element-size", "1e-4"], ["--element-size = 0.0001", "DOFs"]),
    (["static", "en50318", "--element-size", "nan"], ["--element-size = nan"]),
    (["pendulum", "--step", "5", "--duration", "1"], ["--step = 5.0"]),
    (["pendulum", "--duration", "-1"], ["--duration = -1.0"]),
    (["regress", "--only", "nope"], ["--only = 'nope'", "pantograph-en50318-2mass"]),
    (["build-fmus", "--only", "nope"], ["--only = 'nope'", "catenary"]),
])
def test_bad_flag_is_one_line(tmp_path, capsys, monkeypatch, argv, names, no_long_work):
    monkeypatch.chdir(tmp_path)
    code, lines = run_cli(capsys, *argv)
    assert_one_line_error(code, lines, *names)
    assert not (tmp_path / "out").exists()


# ----------------------------------------------------------------------------- formulas
@pytest.mark.parametrize("formula, reason", [
    ("9**9**9", "overflows"),
    ("10**400", "overflows"),
    ("__import__('os').system('true')", "functions"),
    ("(lambda: 1)()", "functions"),
    ("t.__class__", "attribute"),
    ("'a'*10**9", "not a number"),
    ("[1, 2]", "list"),
    ("open", "unknown name 'open'"),
    ("nan", "unknown name 'nan'"),
    ("sin", "is a function"),
    ("where(t > 1, 1, x=2)", "positional"),
    ("1/0", "division by zero"),
    ("exp(10000*t)", "within +/- 100000"),
    ("120 +", "not a valid formula"),
    ("", "empty"),
    ("+".join(["t"] * 2000), "too long"),
    ("(" * 300 + "1" + ")" * 300, "not a valid formula"),
])
def test_bad_force_formula_is_refused_quickly(formula, reason):
    from pantocosim.master.standalone import force_expression

    tracemalloc.start()
    try:
        with pytest.raises(ParameterError) as exc:
            f = force_expression(formula)
            for t in (0.0, 0.05, 0.1):
                f(t)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert exc.value.field == "--force" and reason in str(exc.value)
    # refused before any work: no big number or string was made (9**9**9 takes 150 MB,
    # 'a' * 10**9 1 GB); memory, not time, so the machine's speed does not matter
    assert peak < 10e6


def test_force_formula_values():
    import math

    from pantocosim.master.standalone import force_expression

    f = force_expression("120 + 30*sin(4*pi*t)")
    assert f(0.125) == pytest.approx(150.0) and f(0.375) == pytest.approx(90.0)
    g = force_expression("where(t > 0.5, 100, 120) + 2**3 - 7 % 4 + abs(-1) * e")
    assert g(1.0) == pytest.approx(100 + 8 - 3 + math.e)
    assert g(0.0) == pytest.approx(120 + 8 - 3 + math.e)
    assert force_expression("(" * 90 + "120" + ")" * 90)(0.3) == 120.0


def test_cli_force_formula_is_one_line(capsys, tmp_path):
    code, lines = run_cli(capsys, "pantograph", "en50318-2mass", "--force", "9**9**9",
                          "--duration", "0.1", "--out", tmp_path / "p")
    assert_one_line_error(code, lines, "--force = '9**9**9'", "overflows")


# ----------------------------------------------------------------------------- output places
def _short(tmp_path) -> Path:
    sc = tmp_path / "sc.toml"
    sc.write_text(SCENARIO)
    return sc


@pytest.mark.parametrize("kind", ["file", "under a file", "proc", "plot proc", "plot folder",
                                  "plot suffix", "plot missing folder", "pantograph file"])
def test_unwritable_output_is_one_line(tmp_path, capsys, monkeypatch, kind,
                                      no_long_work):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "afile").write_text("keep me\n")
    (tmp_path / "adir").mkdir()
    if "proc" in kind and not Path("/proc/self").exists():
        pytest.skip("no /proc")
    sc = _short(tmp_path)
    argv, names = {
        "file": (["run", sc, "--out", "afile"], ["--out = 'afile'", "is a file"]),
        "under a file": (["run", sc, "--out", "afile/sub"], ["--out = 'afile/sub'"]),
        "proc": (["run", sc, "--out", "/proc/pantocosim"], ["--out = '/proc/pantocosim'"]),
        "plot proc": (["static", "en50318", "--plot", "/proc/x.png"],
                      ["--plot = '/proc/x.png'"]),
        "plot folder": (["static", "en50318", "--plot", "adir"],
                        ["--plot = 'adir'", "folder"]),
        "plot suffix": (["static", "en50318", "--plot", "x.nope"],
                        ["--plot = 'x.nope'", ".png"]),
        "plot missing folder": (["static", "en50318", "--plot", "no/dir/x.png"],
                                ["--plot = 'no/dir/x.png'"]),
        "pantograph file": (PAN + ["--duration", "0.05", "--out", "afile"],
                            ["--out = 'afile'"]),
    }[kind]
    code, lines = run_cli(capsys, *argv, *(["--quiet"] if argv[0] == "run" else []))
    assert_one_line_error(code, lines, *names)
    assert (tmp_path / "afile").read_text() == "keep me\n"
    assert not leftovers(tmp_path)


# ----------------------------------------------------------------------------- FMU files
@pytest.fixture(scope="module")
def generic_fmus(built):
    """The folder of the generic FMUs, the run's (never loaded here: the checks read model
    descriptions)."""
    return built


def _bad_fmu(kind: str, path: Path, real: Path) -> Path:
    if kind == "text":
        path.write_text("this is not an FMU\n")
    elif kind == "truncated":
        path.write_bytes(real.read_bytes()[:real.stat().st_size // 2])
    elif kind == "empty":
        path.write_bytes(b"")
    elif kind == "folder":
        path.mkdir()
    elif kind == "corrupt":
        data = bytearray(real.read_bytes())
        data[len(data) // 3: len(data) // 3 + 64] = bytes(64)   # inside a member
        path.write_bytes(bytes(data))
    else:
        with zipfile.ZipFile(path, "w") as z:
            if kind == "badxml":
                z.writestr("modelDescription.xml", "<fmiModelDescription <<<")
            z.writestr("resources/x.txt", "x")
    return path


@pytest.mark.parametrize("kind, reason", [
    ("text", "not a zip archive"), ("truncated", "not a zip archive"), ("empty", "empty"),
    ("folder", "is a folder"), ("corrupt", "damaged"), ("nomd", "no modelDescription.xml"),
    ("badxml", "unreadable modelDescription.xml"),
])
def test_broken_fmu_file_is_one_line(tmp_path, capsys, monkeypatch, generic_fmus, kind,
                                     reason):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "dist").mkdir()
    (tmp_path / "dist" / "fmus").symlink_to(generic_fmus)
    _bad_fmu(kind, tmp_path / "bad.fmu", generic_fmus / "en50318-2mass.fmu")
    sc = tmp_path / "sc.toml"
    sc.write_text(edited(SCENARIO, ('start = "static"', 'start = "static"\nfmu = "bad.fmu"')))
    code, lines = run_cli(capsys, "run", sc, "--coupling", "jacobi", "--quiet", "--out", "o")
    assert_one_line_error(code, lines, "sc.toml", "pantographs[0].fmu = 'bad.fmu'", reason)
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("case, names", [
    ("another model", ["pantographs[0].fmu", "dsa380-rigid.fmu", "'en50318-2mass'"]),
    ("the catenary", ["pantographs[0].fmu", "catenary.fmu", "not a pantocosim pantograph"]),
    ("five pantographs", ["pantographs = 5", "at most 4"]),
    ("70 spans", ["spans = 70", "71 supports", "64", "monolithic"]),
])
def test_fmu_that_would_give_a_wrong_result_is_refused(generic_fmus, case, names):
    """A pantograph FMU of another model, too many pantographs or supports for the catenary
    FMU: refused before anything runs (not run with a silently wrong result)."""
    import dataclasses

    from pantocosim.master.fmu.check import check_fmus
    from pantocosim.master.scenario import load_scenario

    sc = load_scenario(ROOT / "tests" / "data" / "short-en50318.toml")
    pans = [generic_fmus / "en50318-2mass.fmu"]
    n_sup = 5
    if case == "another model":
        pans = [generic_fmus / "dsa380-rigid.fmu"]
    elif case == "the catenary":
        pans = [generic_fmus / "catenary.fmu"]
    elif case == "five pantographs":
        sc.pantographs = [dataclasses.replace(sc.pantographs[0], position_m=20.0 + 10 * k)
                          for k in range(5)]
        pans = pans * 5
    else:
        sc.spans, n_sup = 70, 71
    with pytest.raises(ParameterError) as exc:
        check_fmus(sc, n_sup, generic_fmus / "catenary.fmu", pans)
    for name in names:
        assert name in str(exc.value), str(exc.value)
    # a parameter file goes to any pantograph FMU as its parameter_file
    sc.spans, sc.pantographs = 4, sc.pantographs[:1]
    sc.pantographs[0].model = str(PANTOGRAPH)
    plan = check_fmus(sc, 5, generic_fmus / "catenary.fmu", [generic_fmus / "dsa380-rigid.fmu"])
    assert plan.parameter_files == [str(PANTOGRAPH.resolve())]


# ----------------------------------------------------------------------------- lost results
@pytest.fixture(scope="module")
def good_run(tmp_path_factory):
    """The files of a good monolithic run of the short scenario (with plots)."""
    base = tmp_path_factory.mktemp("good")
    sc = base / "sc.toml"
    sc.write_text(SCENARIO)
    assert main(["run", str(sc), "--quiet", "--out", str(base / "out")]) == 0
    return {p.name: p.read_bytes() for p in (base / "out").iterdir()}


@pytest.mark.parametrize("case, names", [
    ("broken FMU", ["pantographs[0].fmu", "not a zip archive"]),
    ("five pantographs", ["pantographs = 5"]),
    ("window", ["analysis.window_m"]),
    ("size guard", ["spans = 100000"]),
    ("full disk (time series)", ["--out", "timeseries.csv", "No space left on device",
                                 "as they were"]),
    ("full disk (summary)", ["--out", "summary.json", "No space left on device"]),
])
def test_failing_run_leaves_earlier_results_intact(tmp_path, capsys, monkeypatch,
                                                   generic_fmus, good_run, case, names):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "dist").mkdir()
    (tmp_path / "dist" / "fmus").symlink_to(generic_fmus)
    out = tmp_path / "out"
    out.mkdir()
    for name, data in good_run.items():
        (out / name).write_bytes(data)
    text, extra = SCENARIO, ["--coupling", "jacobi"]
    if case == "broken FMU":
        _bad_fmu("truncated", tmp_path / "bad.fmu", generic_fmus / "en50318-2mass.fmu")
        text = edited(text, ('start = "static"', 'start = "static"\nfmu = "bad.fmu"'))
    elif case == "five pantographs":
        text = edited(text, ("spans = 4", "spans = 8"), ("window_m = [35.0, 60.0]",
                                                          "window_m = [200.0, 240.0]"),
                      *[("\n[analysis]", SECOND.format(40.0 + 20 * k) + "\n[analysis]")
                        for k in range(4)])
    elif case == "window":
        text, extra = edited(text, ("[35.0, 60.0]", "[35.0, 1e5]")), []
    elif case == "size guard":
        text, extra = edited(text, ("spans = 4", "spans = 100000")), []
    elif case == "full disk (time series)":
        import pantocosim.master.results.recorder as recorder

        monkeypatch.setattr(recorder, "open", lambda p, mode: FullDisk(open(p, mode), 30_000),
                            raising=False)
        extra = []
    else:
        import pantocosim.master.run.outcome as run_results

        def full(path, data):
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

        monkeypatch.setattr(run_results, "write_json", full)
        extra = ["--no-plots"]
    sc = tmp_path / "bad.toml"
    sc.write_text(text)
    code, lines = run_cli(capsys, "run", sc, "--quiet", "--out", out, *extra)
    assert_one_line_error(code, lines, *names)
    assert {p.name: p.read_bytes() for p in out.iterdir()} == good_run
    assert not leftovers(tmp_path)


def test_second_good_run_replaces_the_files_it_owns(tmp_path, capsys, good_run):
    """A run into an --out holding an earlier run (and a file of the user's) replaces the
    earlier run's files whole, removes its plots when it makes none, keeps the user's file."""
    out = tmp_path / "out"
    out.mkdir()
    for name, data in good_run.items():
        (out / name).write_bytes(data)
    (out / "notes.txt").write_text("mine\n")
    sc = _short(tmp_path)
    assert main(["run", str(sc), "--quiet", "--no-plots", "--out", str(out)]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["notes.txt", "summary.json",
                                                      "timeseries.csv"]
    assert (out / "timeseries.csv").read_bytes() == good_run["timeseries.csv"]
    summary = json.loads((out / "summary.json").read_text())
    assert summary["completed"] is True and "stopped" not in summary
    assert summary["files"]["summary"] == str(out / "summary.json")
    assert not leftovers(tmp_path)


def test_output_folder_commit_and_discard(tmp_path, monkeypatch):
    """Staged files replace ours whole; a failed move keeps the staging folder (named in the
    error); a discard leaves --out as it was."""
    from pantocosim.core.errors import OutputError
    from pantocosim.master.output_folder import OutputFolder

    out = tmp_path / "out"
    out.mkdir()
    (out / "a.csv").write_text("old a\n")
    (out / "b.png").write_text("old b\n")
    (out / "mine.txt").write_text("mine\n")
    f = OutputFolder(out, known=["a.csv", "b.png"])
    (f.path / "a.csv").write_text("new a\n")
    f.discard()
    assert not f.path.exists() and (out / "a.csv").read_text() == "old a\n"
    f = OutputFolder(out, known=["a.csv", "b.png"])
    (f.path / "a.csv").write_text("new a\n")
    f.commit()
    assert sorted(p.name for p in out.iterdir()) == ["a.csv", "mine.txt"]
    assert (out / "a.csv").read_text() == "new a\n" and not f.path.exists()
    f = OutputFolder(out, known=["a.csv"])
    (f.path / "a.csv").write_text("newer a\n")

    def refuse(src, dst):
        raise OSError(errno.EXDEV, os.strerror(errno.EXDEV))

    monkeypatch.setattr(os, "replace", refuse)
    with pytest.raises(OutputError, match=str(f.path)):
        f.commit()
    f.discard()
    assert (f.path / "a.csv").read_text() == "newer a\n"
    assert (out / "a.csv").read_text() == "new a\n"


# ----------------------------------------------------------------------------- interrupts
def _child(argv, cwd):
    """The command in a child process that takes SIGINT as a terminal's Ctrl-C does."""
    return subprocess.Popen([sys.executable, "-m", "pantocosim.master.cli", *map(str, argv)],
                            cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            stdin=subprocess.DEVNULL,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))


def _interrupt_when_stepping(proc, folder: Path, limit: float = 300):
    """SIGINT once the run is in its time loop: its time series holds rows (the recorder's
    file buffer reached the disk)."""
    t0 = time.perf_counter()
    while proc.poll() is None and time.perf_counter() - t0 < limit:
        if any(p.stat().st_size > 2000 for p in folder.glob(".*.partial/timeseries.csv")):
            break
        time.sleep(0.05)
    assert proc.poll() is None, proc.communicate()
    proc.send_signal(signal.SIGINT)
    t1 = time.perf_counter()
    out, err = proc.communicate(timeout=30)
    return out, err, time.perf_counter() - t1


def _long_scenario(tmp_path) -> Path:
    sc = tmp_path / "long.toml"
    sc.write_text(edited(SCENARIO, ("spans = 4", "spans = 6"),
                         ("window_m = [35.0, 60.0]", "window_m = [150.0, 250.0]")))
    return sc


def _check_interrupted(proc, out, err, waited, folder):
    assert proc.returncode == 130, out + err
    lines = error_lines(err)
    assert len(lines) == 1 and "interrupted" in lines[0], lines
    assert "FATAL" not in err and "doStep" not in err and "Traceback" not in err
    summary = json.loads((folder / "summary.json").read_text())
    stop = summary["stopped"]
    assert summary["completed"] is False and stop["interrupted"] is True
    assert 0 < stop["steps"] < stop["of_steps"]
    rows = (folder / "timeseries.csv").read_text().splitlines()
    assert len(rows) == stop["steps"] + 2                      # header, t = 0, the steps
    assert float(rows[-1].split(",")[0]) == pytest.approx(stop["time_s"])
    assert f"t = {stop['time_s']:.6g} s" in lines[0]
    assert not leftovers(folder.parent)


@pytest.mark.slow
def test_ctrl_c_in_a_monolithic_run_keeps_what_was_computed(tmp_path):
    sc = _long_scenario(tmp_path)
    proc = _child(["run", sc, "--quiet", "--no-plots", "--out", "out"], tmp_path)
    out, err, waited = _interrupt_when_stepping(proc, tmp_path)
    _check_interrupted(proc, out, err, waited, tmp_path / "out")


@pytest.mark.slow
@pytest.mark.parametrize("coupling", ["jacobi", "implicit"])
def test_ctrl_c_in_a_cosimulation_is_an_interrupt_not_an_fmu_failure(tmp_path, coupling,
                                                                     generic_fmus):
    (tmp_path / "dist").mkdir()
    shutil.copytree(generic_fmus, tmp_path / "dist" / "fmus")
    sc = _long_scenario(tmp_path)
    proc = _child(["run", sc, "--quiet", "--no-plots", "--out", "out", "--coupling",
                   coupling], tmp_path)
    out, err, waited = _interrupt_when_stepping(proc, tmp_path)
    _check_interrupted(proc, out, err, waited, tmp_path / "out")


def test_ctrl_c_during_the_set_up_keeps_earlier_results(tmp_path, good_run):
    out = tmp_path / "out"
    out.mkdir()
    for name, data in good_run.items():
        (out / name).write_bytes(data)
    sc = _long_scenario(tmp_path)
    proc = _child(["run", sc, "--quiet", "--out", "out"], tmp_path)
    # the staging folder made, then a little CPU past it: the command holds the folder (a
    # Ctrl-C within the instant it is created, before the command has it, would leave it)
    wait_until(lambda: list(tmp_path.glob(".out.*.partial")), "the staging folder", proc=proc)
    made = cpu_seconds(proc.pid)
    wait_until(lambda: cpu_seconds(proc.pid) >= made + 0.3, "0.3 s of CPU in the set-up",
               proc=proc)
    proc.send_signal(signal.SIGINT)          # during the set-up (the static start)
    stdout, err = proc.communicate(timeout=30)
    assert proc.returncode == 130, stdout + err
    lines = error_lines(err)
    assert lines == ["pantocosim run: interrupted (Ctrl-C) during the set-up: nothing "
                     "written, out is as it was"]
    assert {p.name: p.read_bytes() for p in out.iterdir()} == good_run
    assert not leftovers(tmp_path)


@pytest.mark.slow
def test_ctrl_c_in_other_commands_is_one_line(tmp_path):
    proc = _child(["static", "en50318", "--element-size", "0.3"], tmp_path)
    # past the imports (about 1.5 s of CPU), inside the static solve
    wait_until(lambda: cpu_seconds(proc.pid) >= 2.5, "2.5 s of CPU in the child", proc=proc)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=30)
    assert proc.returncode == 130, out + err
    assert error_lines(err) == ["pantocosim static: interrupted (Ctrl-C)"]
    # a stand-alone pantograph run keeps the steps it made
    proc = _child(["pantograph", "dsa380-rigid", "--force", "120", "--duration", "500",
                   "--out", "p"], tmp_path)
    wait_until(lambda: list(tmp_path.glob(".p.*.partial")), "the staging folder", proc=proc)
    begun = cpu_seconds(proc.pid)            # the time loop follows at once: let it step
    wait_until(lambda: cpu_seconds(proc.pid) >= begun + 1.0, "1 s of CPU in the time loop",
               proc=proc)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=30)
    assert proc.returncode == 130, out + err
    (line,) = error_lines(err)
    assert "interrupted (Ctrl-C) at t = " in line and "dsa380-rigid.csv" in line
    rows = (tmp_path / "p" / "dsa380-rigid.csv").read_text().splitlines()
    step = int(line.split("after step ")[1].split()[0])
    assert len(rows) == step + 2 and 0 < step < 500_000


# ----------------------------------------------------------------------------- silent results
@pytest.mark.slow
def test_custom_pantograph_file_goes_to_the_fmu(tmp_path, generic_fmus):
    """A pantograph given by a parameter file with a preset's FMU: the FMU gets the file (and
    the options), so the co-simulation is the monolithic run of that pantograph."""
    (tmp_path / "dist").mkdir()
    shutil.copytree(generic_fmus, tmp_path / "dist" / "fmus")
    pan = tmp_path / "custom.toml"
    pan.write_text(edited(PANTOGRAPH.read_text(),
                          ("stiffness = [4200.0, 50.0]", "stiffness = [8000.0, 80.0]"),
                          ("static_force = 115.0", "static_force = 105.0")))
    sc = tmp_path / "sc.toml"
    sc.write_text(edited(SCENARIO, ('model = "en50318-2mass"', f'model = "{pan}"'),
                         ('start = "static"',
                          'start = "static"\nfmu = "dist/fmus/en50318-2mass.fmu"'),
                         ("dt = 0.001", "dt = 0.001\nnewton_rtol = 1e-10\n"
                                        "coupling_rtol = 1e-9")))
    stats = {}
    for coupling in ("monolithic", "implicit"):
        proc = subprocess.run([sys.executable, "-m", "pantocosim.master.cli", "run", str(sc),
                               "--quiet", "--no-plots", "--json", "--coupling", coupling,
                               "--out", coupling], cwd=tmp_path, capture_output=True,
                              text=True, timeout=600)
        assert proc.returncode == 0, proc.stderr
        stats[coupling] = json.loads(proc.stdout)["statistics"]
    mono, cosim = stats["monolithic"], stats["implicit"]
    # the preset's own run has mean 100.5 N, sigma 25.2 N: this is another pantograph
    assert abs(mono["mean_n"] - 100.5) > 5.0
    # the iterative co-simulation reproduces the monolithic solve (tight tolerances)
    assert cosim["mean_n"] == pytest.approx(mono["mean_n"], rel=1e-5)
    assert cosim["std_n"] == pytest.approx(mono["std_n"], rel=1e-4)


# ----------------------------------------------------------------------------- ecos
@pytest.mark.parametrize("ci", ["", "true"])
def test_ecos_test_skips_without_its_native_library(monkeypatch, ci):
    """Loading ecospy without libtbb.so.12 raises OSError: the ecos test skips, not errors
    (on CI, where .ci/run installs libtbb12, it fails naming the library)."""
    import builtins

    real_import = builtins.__import__

    def no_tbb(name, *args, **kwargs):
        if name == "ecospy":
            raise OSError("libtbb.so.12: cannot open shared object file: No such file or "
                          "directory")
        return real_import(name, *args, **kwargs)

    from recipes import require_ecospy

    monkeypatch.delitem(sys.modules, "ecospy", raising=False)
    monkeypatch.setattr(builtins, "__import__", no_tbb)
    monkeypatch.setenv("CI", ci)
    outcome = pytest.fail.Exception if ci else pytest.skip.Exception
    with pytest.raises(outcome, match="libtbb.so.12"):
        require_ecospy()


@pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")
def test_a_ctrl_c_lost_in_a_finaliser_still_stops_the_run():
    """Python drops a KeyboardInterrupt raised inside ``__del__`` (numba's compiler runs
    llvmlite finalisers during a set-up); the next stop request must still see it."""
    import gc
    import os

    from pantocosim.master.interrupt import remember_interrupts, stop_on_interrupt

    class Finaliser:
        def __del__(self):
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.05)    # the handler runs here, inside __del__, and is dropped

    with remember_interrupts():
        Finaliser()
        gc.collect()
        with stop_on_interrupt() as stop:
            assert stop.requested
        with stop_on_interrupt() as stop:   # remembered once
            assert not stop.requested


@pytest.mark.parametrize("value", ["lots", "-1"])
def test_a_bad_cache_size_is_one_line_before_any_work(tmp_path, capsys, monkeypatch, value,
                                                      no_long_work):
    monkeypatch.setenv("PANTOCOSIM_CACHE_MB", value)
    scenario = tmp_path / "s.toml"
    scenario.write_text(SCENARIO)
    code, lines = run_cli(capsys, "run", scenario, "--out", tmp_path / "out")
    assert_one_line_error(code, lines, "PANTOCOSIM_CACHE_MB", repr(value))
    assert not (tmp_path / "out").exists()


def test_an_unusable_cache_root_is_one_warning_per_cache(tmp_path):
    """A file where the cache root should be: the run ends as usual, with one warning line
    for each cache it could not use, naming the path."""
    (tmp_path / "xdg").mkdir()
    (tmp_path / "xdg" / "pantocosim").write_text("not a folder")
    (tmp_path / "s.toml").write_text(edited(SCENARIO, ("spans = 4", "spans = 3")))
    env = {k: v for k, v in os.environ.items() if not k.startswith(("PANTOCOSIM_", "NUMBA_"))}
    env.update(XDG_CACHE_HOME=str(tmp_path / "xdg"), MPLCONFIGDIR=str(tmp_path / "mpl"))
    done = subprocess.run([sys.executable, "-m", "pantocosim.master.cli", "run", "s.toml",
                           "--out", "out"], cwd=tmp_path, env=env, text=True,
                          capture_output=True, timeout=600)
    assert done.returncode == 0, done.stderr
    warned = [line for line in done.stderr.splitlines() if line.strip()]
    assert warned and all(line.startswith("pantocosim: warning: cache "
                                          f"{tmp_path / 'xdg' / 'pantocosim'}/")
                          for line in warned), done.stderr
    assert len(warned) == len({line.split()[3] for line in warned})   # one per cache
    assert (tmp_path / "out").is_dir()

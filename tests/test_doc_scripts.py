"""The scripts behind docs/ run on short settings, so their tables cannot rot.

Each test takes under 20 s on one core except those marked ``slow`` (thesis study: six runs;
flexible vs rigid: the flexible model's set-up and FRFs).

Each script runs as a user runs it (``python scripts/X.py``, a child process) on the short test
scenario, writing into ``tmp_path`` (never into docs/), and the figures it prints or writes are
checked against the physics: the mean contact force is the pantograph's mean uplift, a
refinement changes little, tables have their rows and finite numbers. The full studies and
their figures are in the docs pages the scripts name.

Not here: ``third_party_figures.py`` runs the full default scenario in four foreign masters
(minutes a row); the masters themselves run the short SSP in tests/test_interop.py.
"""

import json
import math
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SCRIPTS = ROOT / "scripts"
SHORT = str(ROOT / "tests" / "data" / "short-en50318.toml")


@pytest.fixture(scope="module")
def short_ref():
    """EN 50317 statistics of the short scenario run in-process (monolithic, 1 ms): what each
    script must report for the same run, whatever it does around it."""
    from pantocosim.master.run import prepare, run_monolithic
    from pantocosim.master.scenario import load_scenario

    res = run_monolithic(prepare(load_scenario(SHORT)), None, progress=False)
    st = res.statistics()[0].as_dict()
    assert 50.0 < st["mean_n"] < 150.0 and 0.0 < st["std_n"] < st["mean_n"]  # physical
    return st


def script(name: str, *args, cwd: Path, timeout: float = 300.0) -> str:
    """Run ``scripts/<name>`` with ``args``; its standard output (exit 0 required)."""
    proc = subprocess.run([sys.executable, str(SCRIPTS / name), *map(str, args)], cwd=cwd,
                          capture_output=True, text=True, timeout=timeout)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    return proc.stdout


def rows_of(table: str, first: str) -> list[list[str]]:
    """Cells of the Markdown rows whose first cell is ``first``."""
    out = []
    for line in table.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if line.startswith("|") and cells[0] == first:
            out.append(cells)
    return out


def number(cell: str) -> float:
    """The first number in a table cell."""
    return float(re.search(r"[-+]?\d[\d,]*\.?\d*(?:e[-+]?\d+)?", cell).group().replace(",", ""))


def page_copy(name: str, tmp_path: Path) -> Path:
    dest = tmp_path / name
    shutil.copy(ROOT / "docs" / name, dest)
    return dest


def test_tables_module_puts_text_between_markers_only():
    sys.path.insert(0, str(SCRIPTS))
    try:
        from _tables import markdown_table, put_between
    finally:
        sys.path.remove(str(SCRIPTS))
    assert markdown_table(("a", "b"), [(1, "x")]) == "| a | b |\n|---|---|\n| 1 | x |\n"
    doc = "intro\n<!-- s -->\nold\n<!-- e -->\nrest\n"
    assert put_between(doc, ("<!-- s -->", "<!-- e -->"), "new\n") == \
        "intro\n<!-- s -->\nnew\n<!-- e -->\nrest\n"
    with pytest.raises(ValueError, match="<!-- e -->"):
        put_between("<!-- s -->", ("<!-- s -->", "<!-- e -->"), "x")


@pytest.mark.slow
def test_tolerance_study(tmp_path, short_ref):
    out = script("tolerance_study.py", SHORT, 1e-10, 1e-6, cwd=tmp_path)
    ref, loose = rows_of(out, "1e-10")[0], rows_of(out, "1e-06")[0]
    assert number(ref[5]) == 0.0                       # the reference against itself
    assert 0.0 <= number(loose[5]) < 0.05              # 1e-6: far below the step's error
    assert number(ref[1]) == pytest.approx(short_ref["mean_n"], abs=1e-4)
    assert number(ref[2]) == pytest.approx(short_ref["std_n"], abs=1e-4)
    assert abs(number(loose[2]) - number(ref[2])) < 0.01
    assert number(loose[6]) <= number(ref[6])          # fewer Newton iterations


@pytest.mark.slow
def test_timestep_study(tmp_path, short_ref):
    script("timestep_study.py", "--quick", "--docs", tmp_path, cwd=tmp_path)
    page = (tmp_path / "timestep-study.md").read_text()
    diff = float(re.search(r"Relative difference of sigma: ([\d.]+) %", page).group(1))
    assert diff < 2.0                                  # the page's acceptance
    at_1ms = rows_of(page, "1")[0]
    assert number(at_1ms[1]) == pytest.approx(short_ref["mean_n"], abs=1e-3)
    assert number(at_1ms[2]) == pytest.approx(short_ref["std_n"], abs=1e-3)
    e4, e2 = (number(rows_of(page, h)[0][1]) for h in ("4", "2"))
    assert 0.0 < e2 < e4                               # the error falls as the step halves


@pytest.mark.slow
def test_fast_catenary_study(tmp_path, short_ref):
    page = page_copy("fast-catenary.md", tmp_path)
    before = page.read_text()
    cache = tmp_path / "study.json"
    out = script("fast_catenary_study.py", "--scenarios", SHORT, "--models", "linear",
                 "--cache", cache, "--docs", page, cwd=tmp_path)
    runs = json.loads(cache.read_text())
    ref, lin = (runs[f"{SHORT}/{m}"]["statistics"][0] for m in ("nonlinear", "linear"))
    assert ref["mean_n"] == pytest.approx(short_ref["mean_n"], abs=1e-9)
    assert lin["mean_n"] == pytest.approx(ref["mean_n"], rel=0.005)
    assert lin["std_n"] == pytest.approx(ref["std_n"], rel=0.03)
    assert len(rows_of(out, SHORT)) == 2
    statics = [r for r in (l.split("|") for l in out.splitlines())
               if len(r) == 7 and r[2].strip() in ("support 2", "midspan 2-3")]
    assert len(statics) == 6
    for r in statics:                                  # linear vs nonlinear static uplift
        assert 0.0 < number(r[3]) and abs(number(r[5])) < 5.0
    after = page.read_text()
    assert after != before
    assert after.split("<!-- study:start -->")[0] == before.split("<!-- study:start -->")[0]


@pytest.mark.slow
def test_modal_cutoff_study(tmp_path):
    page = page_copy("modal-cutoff.md", tmp_path)
    cache = tmp_path / "cutoff.json"
    out = script("modal_cutoff_study.py", "--scenarios", SHORT, "--cutoffs", 100,
                 "--cache", cache, "--docs", page, cwd=tmp_path)
    runs = json.loads(cache.read_text())
    lin, modal = runs[f"{SHORT}/linear"], runs[f"{SHORT}/modal/100"]
    assert 0 < modal["modes"] < lin["dofs"]
    assert modal["statistics"]["std_n"] == pytest.approx(lin["statistics"]["std_n"], rel=0.03)
    assert modal["statistics"]["mean_n"] == pytest.approx(lin["statistics"]["mean_n"],
                                                          rel=0.005)
    row = rows_of(out, SHORT)[1]
    assert row[1] == "100" and all(math.isfinite(number(c)) for c in row[3:9])
    assert "<!-- cutoff:start -->" in page.read_text() and SHORT in page.read_text()


@pytest.mark.slow
def test_en50318_sensitivity(tmp_path, short_ref):
    script("en50318_sensitivity.py", "--scenario", SHORT, "--only", "base", "elem-2",
           "--out", tmp_path, cwd=tmp_path)
    rows = {r["name"]: r for r in json.loads((tmp_path / "sensitivity-250.json").read_text())}
    base, coarse = rows["base"], rows["elem-2"]
    # the base variation is the preset rewritten: the same run
    assert base["statistics"]["std_n"] == pytest.approx(short_ref["std_n"], rel=1e-6)
    # a wire is softer at mid-span than at a support (EN 50318 reference: ~0.3-0.6 mm/N)
    assert 0.1 < base["elasticity_support_mm_per_n"] < base["elasticity_mid_mm_per_n"] < 1.5
    assert coarse["statistics"]["std_n"] == pytest.approx(base["statistics"]["std_n"], rel=0.1)
    md = (tmp_path / "sensitivity-250.md").read_text()
    assert len(rows_of(md, "base")[0]) == 11


@pytest.mark.slow
def test_thesis_study(tmp_path):
    script("thesis_study.py", "--scenario", SHORT, "--out", tmp_path / "out", "--docs",
           tmp_path, cwd=tmp_path, timeout=600)
    rows = {r["case"]: r for r in json.loads((tmp_path / "out" / "results.json").read_text())}
    assert len(rows) == 6
    base = rows["base: no friction, c = 42 000 two-way"]
    assert 50.0 < base["mean_n"] < 200.0 and 0.0 < base["std_n"] < base["mean_n"]
    # a one-way damper pushes the collector up: the mean force rises (docs/thesis-study.md)
    for c in ("42 000", "500 000"):
        two = rows["base: no friction, c = 42 000 two-way" if c == "42 000"
                   else "c = 500 000, two-way"]
        assert rows[f"c = {c}, one-way"]["mean_n"] > two["mean_n"]
    assert (tmp_path / "thesis-study.md").exists()
    assert (tmp_path / "figures" / "thesis-study.png").stat().st_size > 10_000


@pytest.mark.slow
def test_step_lower_bound_table(tmp_path):
    out = script("step_lower_bound.py", SHORT, 2, cwd=tmp_path)
    rows = [r for r in (l.split("|") for l in out.splitlines()) if len(r) == 5
            and r[1].strip() not in ("part", "---")]
    assert len(rows) == 5
    for r in rows:
        assert 0.0 < number(r[3]) <= number(r[2]) < 1e6   # best <= median, in microseconds


def test_factor_policy_study(tmp_path):
    """Every threshold converges the same steps: iterations between 1 and the limit, the
    tightest threshold factorizing and at least as often as the loosest, and the contact
    force within the Newton tolerance's reach of the runs' setting."""
    page = tmp_path / "page.md"
    page.write_text("<!-- factorizations:start -->\n<!-- factorizations:end -->\n")
    out = script("factor_policy_study.py", "--scenario", SHORT, "--steps", 40, "--docs", page,
                 cwd=tmp_path)
    rows = [rows_of(out, k)[0] for k in ("1", "2 (runs)", "3", "4")]
    its = [number(r[1]) for r in rows]
    facts = [number(r[2]) for r in rows]
    assert all(1.0 <= x < 30.0 for x in its)
    assert facts[0] > 0.0 and facts[0] >= facts[3] >= 0.0
    assert rows[1][4] == "0" and all(number(r[4]) < 1e-2 for r in rows if r[4] != "0")
    assert "| 2 (runs) |" in page.read_text()


def test_performance_page_tables_are_the_bench_files(tmp_path):
    """docs/performance.md's tables are what scripts/performance_tables.py writes from
    docs/bench.json: rewriting them changes nothing, and a changed figure in the bench file
    changes the page."""
    page = tmp_path / "performance.md"
    shutil.copy(ROOT / "docs" / "performance.md", page)
    script("performance_tables.py", "--page", page, cwd=tmp_path)
    assert page.read_text() == (ROOT / "docs" / "performance.md").read_text()
    bench = json.loads((ROOT / "docs" / "bench.json").read_text())
    row = bench["cases"]["en50318-300"]["implicit"]
    row["real_time_factor"] = 7.25
    (tmp_path / "bench.json").write_text(json.dumps(bench))
    out = script("performance_tables.py", "--page", page, "--bench", tmp_path / "bench.json",
                 cwd=tmp_path)
    assert rows_of(out, "nonlinear")[1][:3] == ["nonlinear", "implicit (FMUs)", "7.25"]
    assert "| nonlinear | implicit (FMUs) | 7.25 |" in page.read_text()


def test_calibrate_dsa380_reproduces_the_recorded_calibration(tmp_path):
    out = script("calibrate_dsa380.py", cwd=tmp_path, timeout=600)
    rec = json.loads((ROOT / "fmus" / "pantograph" / "data"
                      / "dsa380-calibration.json").read_text())
    got = json.loads(out[:out.rindex("}") + 1])
    assert got["mode_labels"] == got["target_labels"]
    assert got["frequencies_hz"] == pytest.approx(rec["frequencies_hz"], rel=1e-6)


@pytest.mark.slow
def test_compare_flexible_rigid(tmp_path):
    out = script("compare_flexible_rigid.py", "--quick", "--out", tmp_path, cwd=tmp_path,
                 timeout=600)
    assert len(list(tmp_path.glob("flex-*.png"))) >= 4
    # Table 2.2 as docs/flexible-vs-rigid.md quotes it: rigid and flexible (steel) [Hz]
    doc = {"1": (0.6551, 0.6551), "2": (1.2439, 1.2380), "3": (5.6231, 5.5984),
           "4": (7.8705, 7.7347)}
    for mode, (rigid, flexible) in doc.items():
        row = rows_of(out, mode)[0]
        assert number(row[1]) == pytest.approx(rigid, abs=1e-4)
        assert number(row[2]) == pytest.approx(flexible, rel=1e-3)



def readings_module():
    sys.path.insert(0, str(SCRIPTS))
    try:
        import en50318_readings
    finally:
        sys.path.remove(str(SCRIPTS))
    return en50318_readings


def test_en50318_reading_inputs(tmp_path):
    """Each reading is the validation scenario with its changes (``from`` first): the
    inputs it writes load, and carry the changes and nothing else."""
    import dataclasses

    from pantocosim.catenary.definition import load_catenary
    from pantocosim.master.scenario import load_scenario

    R = readings_module()
    readings = R.load_readings()
    by_name = {r["name"]: r for r in readings}
    run = [r for r in readings if "of" not in r]
    assert len(run) == 18 and len(readings) == 24
    loaded = {(r["name"], v): load_scenario(R.scenario_file(r, by_name, v, tmp_path))
              for r in run for v in R.SPEEDS}
    assert len(loaded) == 36
    base = load_scenario("en50318-300")
    same = ("name", "description", "source")
    assert dataclasses.replace(loaded["preset", 300], **{k: getattr(base, k) for k in same}) \
        == base
    sc = loaded["csup300-lumped-constraint-dt0.25", 300]
    assert (sc.dt, sc.alpha, sc.contact_law, sc.speed_kmh) == (0.00025, -0.05, "constraint",
                                                               300.0)
    raw = load_catenary(sc.catenary).raw
    assert raw["contact_support"] == {"type": "spring", "stiffness": 300.0, "mass": 1.0}
    assert raw["messenger_support"] == {"type": "spring", "stiffness": 5.0e4}
    preset = load_catenary("en50318").raw
    assert {k: v for k, v in raw.items() if "support" not in k and k != "name"} == \
        {k: v for k, v in preset.items() if "support" not in k and k != "name"}
    k5 = loaded["preset-k5e5", 250]
    assert (k5.contact_law, k5.contact_stiffness, k5.catenary) == ("penalty", 5e5, "en50318")
    assert loaded["preset-constraint-newmark", 250].alpha == 0.0


@pytest.mark.slow
def test_en50318_readings(tmp_path, short_ref):
    page = page_copy("en50318-validation.md", tmp_path)
    out = script("en50318_readings.py", "--quick", "--only", "preset", "preset-constraint",
                 "--spectrum", "preset", "--out", tmp_path / "out", "--docs", page,
                 cwd=tmp_path, timeout=600)
    rows = json.loads((tmp_path / "out" / "readings.json").read_text())
    assert [(r["reading"], r["speed"]) for r in rows] == [
        ("preset", 250), ("preset", 300), ("preset-constraint", 250),
        ("preset-constraint", 300)]
    pen, con = rows[0]["statistics"], rows[2]["statistics"]
    # the same pantograph uplift: the same mean force whatever the contact law
    assert con["mean_n"] == pytest.approx(pen["mean_n"], abs=1.0)
    # no contact mode: a smoother force than the 5e4 N/m penalty's
    assert con["std_n"] < pen["std_n"]
    # the step's part of the loss of contact: the rigid contact's only
    assert pen["step_loss_percent"] is None
    assert 0.0 <= con["step_loss_percent"] <= con["loss_of_contact_percent"]
    assert len(rows_of(out, "a: preset")) == 2 and len(rows_of(out, "c: preset-constraint")) == 2
    text = page.read_text()
    assert "c: preset-constraint" in text.split("<!-- readings:start -->")[1]
    assert (tmp_path / "figures" / "en50318-spectrum.png").stat().st_size > 10_000
    # the zero-phase filter of a reading is that of every run (master/results/statistics.py)
    R = readings_module()
    import numpy as np

    from pantocosim.master.results.statistics import contact_statistics

    t = np.arange(0.0, 2.0, 1e-3)
    F = 100 + 20 * np.sin(2 * np.pi * 3 * t) + 5 * np.sin(2 * np.pi * 40 * t)
    x = 30 + 70 * t
    run = {"time": t, "x": x, "force": F, "uplift": np.zeros((t.size, 2)),
           "support_x": np.array([0.0, 200.0]), "law": "penalty", "stiffness": 5e4}
    mine = R.statistics(run, (60.0, 120.0))
    ref = contact_statistics(t, F, x, (60.0, 120.0), run["uplift"], run["support_x"])
    assert mine["std_n"] == pytest.approx(ref.std_n, rel=1e-12)
    ideal = R.statistics(run, (60.0, 120.0), "ideal")
    assert ideal["std_n"] == pytest.approx(20 / np.sqrt(2), rel=0.02)   # the 3 Hz part only

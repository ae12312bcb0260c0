"""Sweep files, case hashing, the worker's record of a failing case, the EN 50367 assessment,
the results table and the report. Fast: no Dask cluster, no full run."""

import csv
import json
import math
import subprocess
import sys
from pathlib import Path

import pytest

from pantocosim.core.errors import ParameterError
from pantocosim.master.campaign.assessment import assess, load_criteria
from pantocosim.master.campaign.spec import SWEEP_DIR, load_sweep
from pantocosim.master.campaign.table import ResultsTable, columns, read_table, rows_of

BASE = """
scenario = "en50318-300"
[set]
catenary_model = "linear"
spans = 5
analysis.window_supports = [2, 3]
"""


def sweep_file(tmp_path, text, name="s-sweep.toml"):
    p = tmp_path / name
    p.write_text(BASE + text)
    return p


# ------------------------------------------------------------------------- sweep files
def test_shipped_sweeps_load():
    files = sorted(SWEEP_DIR.glob("*sweep*.toml"))
    assert any(f.name == "en50318-speeds-sweep.toml" for f in files)
    for f in files:
        sw = load_sweep(f)
        assert sw.cases and len({c.key for c in sw.cases}) == len(sw.cases)
    assert len(load_sweep("en50318-pantographs-sweep").cases) == 16


def test_product_and_zip(tmp_path):
    axes = '[axes]\nspeed_kmh = [200.0, 250.0]\npantograph = ["en50318-2mass", "dsa380-rigid"]\n'
    prod = load_sweep(sweep_file(tmp_path, axes))
    assert [c.values for c in prod.cases] == [
        {"speed_kmh": 200.0, "pantograph": "en50318-2mass"},
        {"speed_kmh": 200.0, "pantograph": "dsa380-rigid"},
        {"speed_kmh": 250.0, "pantograph": "en50318-2mass"},
        {"speed_kmh": 250.0, "pantograph": "dsa380-rigid"}]
    zf = tmp_path / "z2.toml"
    zf.write_text('combine = "zip"\n' + BASE + axes)
    z = load_sweep(zf)
    assert [c.values for c in z.cases] == [
        {"speed_kmh": 200.0, "pantograph": "en50318-2mass"},
        {"speed_kmh": 250.0, "pantograph": "dsa380-rigid"}]
    c = z.cases[1]
    assert c.scenario["speed_kmh"] == 250.0
    assert [p["model"] for p in c.scenario["pantographs"]] == ["dsa380-rigid"]
    assert c.scenario["spans"] == 5 and c.scenario["simulation"]["catenary_model"] == "linear"
    assert c.descriptors["catenary_model"] == "linear" and c.run["coupling"] == "monolithic"


def test_set_entry_is_a_scenario_field_not_swallowed(tmp_path):
    # 'combine' after [set] is a field of [set]: rejected as an unknown scenario field
    with pytest.raises(ParameterError, match="set.combine"):
        load_sweep(sweep_file(tmp_path, 'combine = "zip"\n[axes]\nspeed_kmh = [200.0]\n'))


def test_catenary_field_and_hash(tmp_path):
    sw = load_sweep(sweep_file(tmp_path, "[axes]\ncatenary.contact_wire.tension = "
                               "[18000.0, 20000, 20000.0001]\n"))
    t = [c.catenary["contact_wire"]["tension"] for c in sw.cases]
    assert t == [18000.0, 20000, 20000.0001]
    assert sw.cases[0].catenary["messenger_wire"]["tension"] == 16000.0   # rest as the file
    keys = [c.key for c in sw.cases]
    assert len(set(keys)) == 3
    # 20000 as integer is the unmodified preset: same inputs as a sweep that changes nothing
    plain = load_sweep(sweep_file(tmp_path, "[axes]\nspeed_kmh = [300]\n", "p.toml"))
    assert plain.cases[0].key == keys[1]
    # name, description and key order do not enter the hash; the coupling does
    other = tmp_path / "o.toml"
    other.write_text('name = "x"\ndescription = "y"\nscenario = "en50318-300"\n[set]\n'
                     'analysis.window_supports = [2, 3]\nspans = 5\n'
                     'catenary_model = "linear"\n[axes]\nspeed_kmh = [300.0]\n')
    assert load_sweep(other).cases[0].key == keys[1]
    coupled = load_sweep(sweep_file(tmp_path, '[run]\ncoupling = "implicit"\n'
                                    "[axes]\nspeed_kmh = [300.0]\n", "c.toml"))
    assert coupled.cases[0].key != keys[1]


def test_base_scenario_relative_to_sweep_file(tmp_path):
    (tmp_path / "sub").mkdir()
    src = Path(load_sweep("en50318-speeds-sweep").scenario_path)
    (tmp_path / "sub" / "mine.toml").write_text(src.read_text().replace("en50318-300", "mine"))
    f = tmp_path / "sub" / "m-sweep.toml"
    f.write_text('scenario = "mine.toml"\n[axes]\nspeed_kmh = [250.0]\n')
    sw = load_sweep(f)
    assert sw.scenario_path == (tmp_path / "sub" / "mine.toml").resolve()
    assert sw.cases[0].descriptors["scenario"] == "mine"


@pytest.mark.parametrize("text, expected", [
    ("[axes]\nspeed_kmh = [200.0, -5.0]\n", "axes.speed_kmh = -5.0: .*must be > 0"),
    ("[axes]\nspeed_kmh = []\n", "axes.speed_kmh = \\[\\]: must be a non-empty array"),
    ("[axes]\nspeed_kmh = [200.0, 200.0]\n", "repeats 200.0"),
    ("[axes]\ncatenary.contact_wire.tenson = [1.0]\n", "contact_wire.tenson = 1.0: unknown"),
    ("[axes]\ncatenary.contact_wire.tension = [-1.0]\n", "tension = -1.0: must be > 0"),
    ('[axes]\npantograph = ["nope"]\n', "axes.pantograph = 'nope': .*unknown preset"),
    ('[axes]\ncoupling = ["magic"]\n', "axes.coupling = 'magic': must be one of"),
    ("[axes]\nsimulation.dtt = [0.001]\n", "simulation.dtt = 0.001: unknown field"),
    ("[axes]\npantographs.3.model = [\"dsa380-rigid\"]\n", "no index of an array of 1"),
    ("[axes]\ndt = [0.5]\n", "simulation.dt = 0.5: must be <= 0.01"),
    ("[axes]\nspans = [5]\n", "axes.spans = \\[5\\]: is also given in \\[set\\]"),
    ('[run]\ncoupling = "fast"\n[axes]\nspeed_kmh = [200.0]\n', "run.coupling = 'fast'"),
    ("", "axes = None: missing field"),
])
def test_bad_sweep_files_name_file_field_value(tmp_path, text, expected):
    f = sweep_file(tmp_path, text)
    with pytest.raises(ParameterError, match=expected) as err:
        load_sweep(f)
    assert str(f) in str(err.value)


def test_bad_top_level_fields(tmp_path):
    for text, expected in [('scenario = "nope"\n[axes]\nspeed_kmh = [1.0]\n', "unknown scenario"),
                           ('scenario = "en50318-300"\ncombine = "all"\n[axes]\nspeed_kmh = [1.0]',
                            "combine = 'all'"),
                           ('scenario = "en50318-300"\ncombine = "zip"\n[axes]\n'
                            'speed_kmh = [1.0, 2.0]\ndt = [0.001]', "needs axes of one length"),
                           ('scenario = "en50318-300"\ncriteria = "x.toml"\n[axes]\n'
                            'speed_kmh = [1.0]', "criteria = 'x.toml'"),
                           ('scenario = "en50318-300"\nspeed = 3\n[axes]\nspeed_kmh = [1.0]',
                            "speed = 3: unknown field")]:
        f = tmp_path / "t.toml"
        f.write_text(text)
        with pytest.raises(ParameterError, match=expected):
            load_sweep(f)


def test_cli_bad_sweep_is_one_line_exit_2(tmp_path):
    f = sweep_file(tmp_path, "[axes]\nspeed_kmh = [-1.0]\n")
    proc = subprocess.run([sys.executable, "-m", "pantocosim.master.cli", "sweep", str(f)],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 2
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "axes.speed_kmh = -1.0" in lines[0] and str(f) in lines[0]


# ------------------------------------------------------------------------- worker
def test_failing_case_is_recorded(tmp_path):
    """A case above 0.7 of the wave speed fails in its run: status, message and case.json
    are recorded (the sweep goes on), and the folder holds the scenario as run."""
    from pantocosim.master.campaign.execute import previous, task_of
    from pantocosim.master.campaign.worker import run_case

    sw = load_sweep(sweep_file(tmp_path, "[axes]\nspeed_kmh = [420.0]\n"))
    case = sw.cases[0]
    record = run_case(task_of(case, tmp_path / "out"))
    assert record["status"] == "failed"
    assert "speed_kmh = 420.0" in record["error"] and "wave speed" in record["error"]
    folder = Path(record["folder"])
    assert json.loads((folder / "case.json").read_text())["status"] == "failed"
    assert "speed_kmh = 420.0" in (folder / "scenario.toml").read_text()
    assert previous(case, tmp_path / "out", retry_failed=False)["status"] == "failed"
    assert previous(case, tmp_path / "out", retry_failed=True) is None


def test_unexpected_exception_is_recorded_with_traceback(tmp_path, monkeypatch):
    from pantocosim.master.campaign import worker
    from pantocosim.master.campaign.execute import task_of
    from pantocosim.master.campaign.worker import run_case

    def boom(*a, **k):
        raise ZeroDivisionError("boom")

    monkeypatch.setattr(worker, "prepare", boom)
    sw = load_sweep(sweep_file(tmp_path, "[axes]\ncatenary.contact_wire.tension = [21000.0]\n"))
    record = run_case(task_of(sw.cases[0], tmp_path))
    assert record["status"] == "failed" and record["error"] == "ZeroDivisionError: boom"
    folder = Path(record["folder"])
    assert "ZeroDivisionError" in (folder / "error.txt").read_text()
    # the case's own catenary file, referenced by absolute path from its scenario
    assert "tension = 21000.0" in (folder / "catenary.toml").read_text()
    assert f'catenary = "{folder / "catenary.toml"}"' in (folder / "scenario.toml").read_text()


# ------------------------------------------------------------------------- assessment
def stats(mean=120.0, std=20.0, loss=0.0, uplift=0.05, **kw):
    d = {"mean_n": mean, "std_n": std, "stat_max_n": mean + 3 * std,
         "stat_min_n": mean - 3 * std, "max_n": mean + 2 * std, "min_n": mean - 2 * std,
         "loss_of_contact_percent": loss, "max_uplift_at_support_m": uplift}
    d.update(kw)
    return d


def test_en50367_criteria():
    c = load_criteria()
    assert all(k.source and k.verified is False for k in c.items)
    # band at 300 km/h: 0.00047 v^2 + 60 = 102.3 N .. 0.00097 v^2 + 70 = 157.3 N
    assert assess(c, stats(mean=102.31, std=10), 300)["mean_force_band"] is True
    assert assess(c, stats(mean=102.29, std=10), 300)["mean_force_band"] is False
    assert assess(c, stats(mean=157.29, std=10), 300)["mean_force_band"] is True
    assert assess(c, stats(mean=157.31, std=10), 300)["mean_force_band"] is False
    assert assess(c, stats(mean=100.0, std=10), 200)["mean_force_band"] is True  # 78.8-108.8
    # sigma <= 0.3 F_m
    assert assess(c, stats(mean=150, std=45.0), 300)["sigma_ratio"] is True
    assert assess(c, stats(mean=150, std=45.01), 300)["sigma_ratio"] is False
    # F_m - 3 sigma > 0 (strict)
    assert assess(c, stats(mean=150, std=50.0), 300)["stat_min_positive"] is False
    assert assess(c, stats(mean=150, std=49.99), 300)["stat_min_positive"] is True
    # no loss of contact
    assert assess(c, stats(loss=0.01), 300)["no_loss_of_contact"] is False
    r = assess(c, stats(mean=130, std=30, uplift=0.06), 300)
    assert math.isclose(r["uplift_space_2s0_m"], 0.12)
    assert r["assessment"] == "pass"
    assert assess(c, stats(mean=130, std=40), 300)["assessment"] == "fail"
    r = assess(c, None, 300)
    assert r["assessment"] == "n/a" and r["sigma_ratio"] is None
    # no support in the window: the uplift is NaN, reported as None, not a verdict
    assert assess(c, stats(uplift=float("nan")), 300)["uplift_space_2s0_m"] is None


def test_criteria_file_validation_and_speed_range(tmp_path):
    f = tmp_path / "c.toml"
    f.write_text('[[criteria]]\nname = "s"\nkind = "ratio_max"\nquantity = "std_n"\n'
                 'reference = "mean_n"\nfactor = 0.2\nmin_speed_kmh = 250.0\n'
                 'source = "test"\nverified = false\n')
    c = load_criteria(str(f))
    assert assess(c, stats(mean=100, std=25), 200)["s"] is None
    assert assess(c, stats(mean=100, std=25), 250)["s"] is False
    for bad, expected in [("kind = \"ratio_max\"", "kind = 'between'"),
                          ("quantity = \"std_n\"", "quantity = 'sigma'"),
                          ("factor = 0.2", "factor = -0.2")]:
        repl = {"kind = \"ratio_max\"": 'kind = "between"',
                "quantity = \"std_n\"": 'quantity = "sigma"', "factor = 0.2": "factor = -0.2"}
        f.write_text(f.read_text().replace(bad, repl[bad]))
        with pytest.raises(ParameterError, match=expected):
            load_criteria(str(f))
        f.write_text(f.read_text().replace(repl[bad], bad))


# ------------------------------------------------------------------------- table, report
def fake_sweep(tmp_path):
    """A finished sweep folder from made-up records (no simulation)."""
    from pantocosim.master.campaign.execute import _keep_inputs

    sw = load_sweep(sweep_file(tmp_path, "[axes]\nspeed_kmh = [200.0, 250.0, 300.0]\n"
                                '"catenary.contact_wire.tension" = [18000.0, 20000.0]\n'))
    out = tmp_path / "out"
    out.mkdir()
    crit = load_criteria()
    _keep_inputs(sw, crit, out)
    table = ResultsTable(out, columns([n for n, _ in sw.axes], crit), parquet_every_s=0)
    for c in sw.cases:
        v = c.values["speed_kmh"]
        if v == 300.0 and c.values["catenary.contact_wire.tension"] == 18000.0:
            rec = {"status": "failed", "error": "speed_kmh = 300.0: exceeds", "folder": "x"}
        else:
            std = {200.0: 12.0, 250.0: 20.0, 300.0: 36.0}[v]
            s = stats(mean=100.0 if v == 200.0 else 115.0,
                      std=std + 1e-4 * c.values["catenary.contact_wire.tension"],
                      uplift=0.0001 * v)
            rec = {"status": "ok", "error": None, "folder": "x", "case_wall_time_s": 3.0,
                   "summary": {"wall_time_s": 2.0, "steps": 100, "target_mean_n": [115.0],
                               "pantographs": [{"index": 1, "model": "en50318-2mass",
                                                "statistics": s}]}}
        table.add(rows_of(rec, c, crit))
    table.close()
    return sw, out


def test_results_table_csv_and_parquet(tmp_path):
    sw, out = fake_sweep(tmp_path)
    with open(out / "results.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    pq_rows = read_table(out)
    assert len(rows) == len(pq_rows) == 6
    r = next(x for x in pq_rows if x["speed_kmh"] == 250.0
             and x["catenary.contact_wire.tension"] == 20000.0)
    assert r["status"] == "ok" and r["pantograph_model"] == "en50318-2mass"
    assert math.isclose(r["std_n"], 22.0) and r["sigma_ratio"] is True
    assert r["mean_force_band"] is True and r["assessment"] == "pass"   # 89.4..130.6 N
    failed = [x for x in pq_rows if x["status"] == "failed"]
    assert len(failed) == 1 and failed[0]["assessment"] == "n/a"
    assert failed[0]["error"].startswith("speed_kmh = 300.0")
    csv_failed = [x for x in rows if x["status"] == "failed"][0]
    assert csv_failed["mean_n"] == "" and csv_failed["assessment"] == "n/a"


def test_report_from_results(tmp_path):
    from pantocosim.master.campaign.report import make_report

    sw, out = fake_sweep(tmp_path)
    md = make_report(out)
    text = md.read_text()
    for f in ("force_vs_speed.png", "sigma_vs_speed_kmh.png",
              "sigma_vs_catenary_contact_wire_tension.png", "pass_fail.png"):
        assert (out / "report" / f).stat().st_size > 10_000, f
        assert f"({f})" in text
    assert "6 in the sweep, 5 ok, 1 failed" in text
    # sigma at 300 km/h: 36 + 2 = 38 N > 0.3 * 115 N: the one ok row at 300 km/h fails
    assert "4 pass every applicable check, 1 fail" in text
    assert "speed_kmh = 300.0: exceeds" in text
    # an edited criteria file changes the verdicts without a re-run
    strict = out / "strict.toml"
    strict.write_text((out / "criteria.toml").read_text().replace("factor = 0.3", "factor = 0.1"))
    text = make_report(out, str(strict), tmp_path / "r2").read_text()
    assert "0 pass every applicable check, 5 fail" in text


def test_resume_skips_done_cases_without_a_cluster(tmp_path):
    """Every case already has its case.json: nothing is submitted (no cluster is started),
    and the results table is rebuilt from the records."""
    from pantocosim.master.campaign.execute import case_folder, run_sweep

    sw = load_sweep(sweep_file(tmp_path, "[axes]\nspeed_kmh = [200.0, 250.0]\n"))
    out = tmp_path / "out"
    for c in sw.cases:
        f = case_folder(out, c.key)
        f.mkdir(parents=True)
        (f / "case.json").write_text(json.dumps({
            "key": c.key, "status": "ok", "error": None, "folder": str(f),
            "summary": {"pantographs": [{"index": 1, "model": "en50318-2mass",
                                         "statistics": stats(mean=c.values["speed_kmh"])}]}}))
    outcome = run_sweep(sw, out, scheduler="tcp://127.0.0.1:1", echo=lambda *a: None)
    assert (outcome.skipped, outcome.ok, outcome.failed) == (2, 0, 0)
    assert sorted(r["mean_n"] for r in read_table(out)) == [200.0, 250.0]


def test_interrupted_sweep_keeps_cases_finished_on_workers(tmp_path):
    """A case whose worker wrote case.json but whose result had not reached the client when
    the sweep was interrupted still gets its row."""
    from pantocosim.master.campaign.execute import Outcome, _late, case_folder

    sw = load_sweep(sweep_file(tmp_path, "[axes]\nspeed_kmh = [200.0, 250.0]\n"))
    out = tmp_path / "out"
    out.mkdir()
    done = sw.cases[1]
    f = case_folder(out, done.key)
    f.mkdir(parents=True)
    (f / "case.json").write_text(json.dumps({
        "key": done.key, "status": "ok", "error": None, "folder": str(f),
        "summary": {"pantographs": [{"index": 1, "model": "en50318-2mass",
                                     "statistics": stats(mean=111.0)}]}}))
    crit = load_criteria()
    table = ResultsTable(out, columns(["speed_kmh"], crit))
    outcome = Outcome(folder=out, total=2)
    _late(sw.cases, out, outcome, table, crit)
    table.close()
    assert outcome.ok == 1
    assert [(r["speed_kmh"], r["mean_n"]) for r in read_table(out)] == [(250.0, 111.0)]

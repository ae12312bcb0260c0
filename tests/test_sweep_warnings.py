"""A sweep case whose run is warned (master/stability.py) is marked as such: status
``warned`` in case.json and the results table, the warnings in their column, the statistics
kept but marked and not assessed in the report, and the sweep's exit status 1."""

import json
from pathlib import Path

from test_sweep import fake_sweep, stats

from pantocosim.master.campaign.assessment import load_criteria
from pantocosim.master.campaign.table import ResultsTable, columns, read_table, rows_of

SWEEP = """\
name = "stiff"
scenario = "{scenario}"

[run]
coupling = "monolithic"

[set]
contact.stiffness = 1.0e7

[axes]
speed_kmh = [250.0]
"""

SCENARIO = (Path(__file__).with_name("data") / "three-spans.toml").read_text()


def test_worker_records_a_warned_case(tmp_path):
    """The monolithic case at k = 1e7 N/m, dt = 1 ms runs on the worker code (no cluster):
    status warned, the contact-frequency warning in case.json and in the table's column."""
    from pantocosim.master.campaign.execute import task_of
    from pantocosim.master.campaign.spec import load_sweep
    from pantocosim.master.campaign.worker import run_case

    (tmp_path / "three.toml").write_text(SCENARIO)
    path = tmp_path / "stiff-sweep.toml"
    path.write_text(SWEEP.format(scenario="three.toml"))
    sweep = load_sweep(str(path))
    out = tmp_path / "out"
    record = run_case(task_of(sweep.cases[0], out))
    assert record["status"] == "warned" and record["error"] is None
    assert len(record["warnings"]) == 1 and "contact frequency 188 Hz" in record["warnings"][0]
    saved = json.loads((out / "cases" / sweep.cases[0].key / "case.json").read_text())
    assert saved["status"] == "warned" and saved["warnings"] == record["warnings"]
    crit = load_criteria()
    (row,) = rows_of(record, sweep.cases[0], crit)
    assert row["status"] == "warned" and "188 Hz" in row["warnings"]
    assert abs(row["mean_n"] - 115.9) < 0.5          # the statistics stay, marked
    table = ResultsTable(out, columns([n for n, _ in sweep.axes], crit), parquet_every_s=0)
    table.add([row])
    table.close()
    assert read_table(out)[0]["warnings"] == row["warnings"]


def test_report_marks_warned_rows(tmp_path):
    from pantocosim.master.campaign.report import make_report

    sw, out = fake_sweep(tmp_path)
    crit = load_criteria()
    rows = read_table(out)
    case = sw.cases[0]
    rec = {"status": "warned", "error": None, "folder": "x",
           "warnings": ["the pantograph: contact frequency 188 Hz is not resolved"],
           "summary": {"target_mean_n": [115.0], "pantographs": [
               {"index": 1, "model": "en50318-2mass", "statistics": stats(mean=115.9)}]}}
    table = ResultsTable(out, columns([n for n, _ in sw.axes], crit), parquet_every_s=0)
    table.add([r for r in rows if r["case"] != case.key] + rows_of(rec, case, crit))
    table.close()
    text = make_report(out).read_text()
    assert "5 ok" not in text and "1 warned (statistics doubtful, not assessed)" in text
    assert "115.9*" in text and "**warned**" in text
    assert "## Warned cases" in text and "188 Hz is not resolved" in text

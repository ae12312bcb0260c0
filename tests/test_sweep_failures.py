"""A sweep stays whole when a case cannot write (a full disk) or the scheduler goes away: the
case's files are staged and moved in (no half-written or 0-byte file in a case folder), the
sweep stops with one line naming what failed and the file (exit 2), and resumes afterwards."""

import json
import os

from pathlib import Path

import pytest

from full_disk import FullDisk

from pantocosim.master.campaign import execute
from pantocosim.master.campaign.execute import SweepStopped, case_folder, task_of
from pantocosim.master.campaign.spec import load_sweep
from pantocosim.master.campaign.worker import CASE_FILE, run_case

SCENARIO = (Path(__file__).with_name("data") / "three-spans.toml").read_text()
SWEEP = """\
name = "small"
scenario = "three.toml"

[run]
coupling = "monolithic"

[axes]
catenary.contact_wire.tension = [20000.0, 21000.0]
"""


@pytest.fixture
def sweep(tmp_path):
    (tmp_path / "three.toml").write_text(SCENARIO)
    (tmp_path / "small-sweep.toml").write_text(SWEEP)
    return load_sweep(str(tmp_path / "small-sweep.toml"))


def files_under(folder):
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*") if p.is_file())


def test_a_case_that_cannot_write_leaves_nothing_and_says_which_file(tmp_path, sweep,
                                                                    monkeypatch):
    import pantocosim.master.results.recorder as recorder

    monkeypatch.setattr(recorder, "open", lambda p, mode: FullDisk(open(p, mode), 30_000),
                        raising=False)
    out = tmp_path / "out"
    case = sweep.cases[0]
    record = run_case(task_of(case, out))
    assert record["status"] == "lost"
    assert record["fatal"].startswith("file = '") and \
        record["fatal"].endswith("timeseries.csv': cannot be written: No space left on device")
    assert files_under(out) == []           # no case folder, no staging folder, no case.json
    monkeypatch.undo()
    record = run_case(task_of(case, out))   # the disk has room again: the case runs
    assert record["status"] == "ok"
    folder = case_folder(out, case.key)
    assert files_under(out) == [f"cases/{case.key}/{n}" for n in
                                ("case.json", "catenary.toml", "scenario.toml", "summary.json",
                                 "timeseries.csv")]
    assert all((folder / n).stat().st_size > 0 for n in os.listdir(folder))
    # the case folder's scenario names the catenary file in the case folder, and runs again
    assert f"{folder}/catenary.toml" in (folder / "scenario.toml").read_text()
    summary = json.loads((folder / "summary.json").read_text())
    assert summary["files"]["summary"] == str(folder / "summary.json")


class _Future:
    def __init__(self, key, result=None, error=None):
        self.key, self._result, self._error = key, result, error

    def result(self):
        if self._error:
            raise self._error
        return self._result


def _collect(sweep, tmp_path, futures, monkeypatch):
    import distributed

    monkeypatch.setattr(distributed, "as_completed", lambda fs: iter(fs))
    from pantocosim.master.campaign.assessment import load_criteria
    from pantocosim.master.campaign.table import ResultsTable, columns

    crit = load_criteria()
    table = ResultsTable(tmp_path / "out", columns([n for n, _ in sweep.axes], crit),
                         parquet_every_s=0)
    outcome = execute.Outcome(folder=tmp_path / "out", total=len(sweep.cases))
    try:
        return execute._collect(futures, 0.0, tmp_path / "out", False, table, crit, outcome)
    finally:
        table.close()


def test_a_fatal_case_stops_the_sweep_with_one_line(tmp_path, sweep, monkeypatch):
    (tmp_path / "out").mkdir()
    case = sweep.cases[0]
    fatal = "file = '/x/timeseries.csv': cannot be written: No space left on device"
    record = {"key": case.key, "status": "lost", "error": fatal, "fatal": fatal}
    futures = {"a": (case, _Future("a", record))}
    with pytest.raises(SweepStopped) as err:
        _collect(sweep, tmp_path, futures, monkeypatch)
    assert str(err.value) == (f"case 1 ({case.label}) could not write its results: {fatal}; "
                              f"the sweep stopped, the cases done are kept in "
                              f"{tmp_path / 'out'}: run it again to resume")


def test_a_lost_scheduler_stops_the_sweep_with_one_line(tmp_path, sweep, monkeypatch):
    from distributed.client import FutureCancelledError

    (tmp_path / "out").mkdir()
    gone = FutureCancelledError("case-x", reason="scheduler-connection-lost")
    futures = {"a": (sweep.cases[0], _Future("a", error=gone))}
    with pytest.raises(SweepStopped, match=r"^the connection to the Dask scheduler was lost "
                       r"\(it stopped or is unreachable\): 0 of 2 cases done, kept in .*; run "
                       r"the sweep again to resume$"):
        _collect(sweep, tmp_path, futures, monkeypatch)


def test_staging_folders_of_a_killed_sweep_are_removed_on_resume(tmp_path, sweep):
    """Every case done already: nothing runs, and what a killed worker staged is gone."""
    from pantocosim.master.campaign.execute import run_sweep

    out = tmp_path / "out"
    for case in sweep.cases:
        folder = case_folder(out, case.key)
        folder.mkdir(parents=True)
        (folder / CASE_FILE).write_text(json.dumps({"key": case.key, "status": "failed",
                                                    "error": "x", "folder": str(folder)}))
    staged = out / "cases" / ".abc.x1y2.partial"
    staged.mkdir()
    (staged / "timeseries.csv").write_text("time\n")
    outcome = run_sweep(sweep, out, scheduler="tcp://127.0.0.1:1", echo=lambda *a: None)
    assert (outcome.skipped, outcome.ok) == (2, 0)
    assert not staged.exists()


def test_the_clients_reconnect_tracebacks_are_dropped():
    import asyncio
    import logging

    quiet = execute._QuietReconnect()

    def record(level, exc):
        info = (type(exc), exc, None) if exc else None
        return logging.LogRecord("distributed.client", level, "x", 1, "", None, info)

    assert not quiet.filter(record(logging.ERROR, asyncio.CancelledError()))
    assert not quiet.filter(record(logging.ERROR, ConnectionRefusedError(111, "refused")))
    assert quiet.filter(record(logging.ERROR, ValueError("a bug")))      # kept
    assert quiet.filter(record(logging.WARNING, None))


def test_a_refused_case_names_its_own_folder(tmp_path):
    """A case the run refuses (a speed above 0.7 of the wave speed) names the scenario file
    in its case folder, which it keeps, not the staging folder it ran in."""
    (tmp_path / "three.toml").write_text(SCENARIO)
    (tmp_path / "fast-sweep.toml").write_text(
        'name = "fast"\nscenario = "three.toml"\n[axes]\nspeed_kmh = [900.0]\n')
    (case,) = load_sweep(str(tmp_path / "fast-sweep.toml")).cases
    out = tmp_path / "out"
    record = run_case(task_of(case, out))
    folder = case_folder(out, case.key)
    assert record["status"] == "failed", record
    assert record["error"].startswith(f"{folder / 'scenario.toml'}: speed_kmh = 900.0"), record
    assert ".partial" not in record["error"]
    assert (folder / "scenario.toml").is_file()

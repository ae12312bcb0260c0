"""One case of a sweep, run on a Dask worker (a worker process, one thread).

The case writes its own run folder as ``pantocosim run`` does (``timeseries.csv``,
``summary.json``, plots if asked) plus ``scenario.toml`` (and ``catenary.toml`` when the sweep
changes catenary fields), which ``pantocosim run`` runs again as they are, and last
``case.json``: status, error, timings, worker memory. ``case.json`` marks the case done, so a
sweep run again skips it. Any error of the run is caught and recorded: the sweep goes on.

The files are written into a staging folder beside the case folder
(:class:`~pantocosim.master.output_folder.OutputFolder`) and moved in when the run is done, so
the case folder never holds a half-written file. A case that cannot write its files (a full
disk) leaves its folder as it was, writes no ``case.json`` (it runs again on resume) and
returns its record with ``fatal``: the message naming the file, which stops the sweep.
"""

from __future__ import annotations

import dataclasses
import json
import os
import time
import traceback
from pathlib import Path

import psutil
import tomli_w

from pantocosim.core.errors import OutputError, PantocosimError
from pantocosim.master.campaign.axes import COUPLINGS
from pantocosim.master.cosim import run_cosim
from pantocosim.master.output_folder import OutputFolder, writing
from pantocosim.master.run import finish, prepare, run_monolithic
from pantocosim.master.scenario import load_scenario

CASE_FILE = "case.json"


def run_case(task: dict) -> dict:
    """Run one case (``task`` from :func:`pantocosim.master.campaign.execute.task_of`) and
    return its record (also written to ``case.json`` in its folder)."""
    folder = Path(task["folder"])
    started = time.time()
    t0, cpu0 = time.perf_counter(), time.process_time()
    record = {"key": task["key"], "index": task["index"], "values": task["values"],
              "folder": str(folder), "status": "ok", "error": None, "summary": None}
    times = {}
    stage = None
    try:
        stage = OutputFolder(folder, known=CASE_FILES, field="case folder")
        _write_inputs(task, stage.path, stage.path)
        summary = _run(stage.path, task["run"], times, report_dir=folder)
        record["summary"] = _essentials(summary)
        record["warnings"] = list(summary.get("warnings") or [])
        if summary.get("error"):
            record.update(status="failed", error=_in_case_folder(summary["error"], stage,
                                                                 folder))
        elif record["warnings"]:
            record["status"] = "warned"   # ran, but its numbers are doubtful
    except OutputError as exc:   # cannot write: stop the sweep, keep the folder as it was
        return _fatal(record, stage, exc)
    except PantocosimError as exc:
        record.update(status="failed", error=_in_case_folder(str(exc), stage, folder))
    except Exception as exc:  # noqa: BLE001 - any failure of one case is recorded
        record.update(status="failed", error=_in_case_folder(f"{type(exc).__name__}: {exc}",
                                                             stage, folder))
        try:
            (stage.path / "error.txt").write_text(traceback.format_exc())
        except (OSError, AttributeError):
            pass
    record.update(times)
    record.update(case_wall_time_s=time.perf_counter() - t0,
                  case_cpu_time_s=time.process_time() - cpu0, started_at=started,
                  finished_at=time.time(), **_worker())
    try:
        if task.get("catenary") is not None:   # the inputs as they are in the case folder
            _write_inputs(task, stage.path, folder)
        stage.commit()
        tmp = folder / (CASE_FILE + ".tmp")
        try:
            with writing("file", folder / CASE_FILE):
                tmp.write_text(json.dumps(record, indent=2, default=str) + "\n")
                os.replace(tmp, folder / CASE_FILE)
        finally:
            tmp.unlink(missing_ok=True)
    except OutputError as exc:
        return _fatal(record, stage, exc)
    return record


#: the files a case writes into its folder (``case.json`` apart)
CASE_FILES = ("scenario.toml", "catenary.toml", "error.txt", "timeseries.csv", "summary.json",
              "contact_force.png", "spectrum.png", "support_uplift.png")


def _in_case_folder(message: str, stage, folder: Path) -> str:
    """``message`` naming the case folder where it names the staging folder (which is gone
    once the case's files are moved in)."""
    if stage is None:
        return message
    return message.replace(str(stage.path), str(folder))


def _write_inputs(task: dict, into: Path, named: Path) -> None:
    """``scenario.toml`` (and ``catenary.toml``) into ``into``, the scenario naming the
    catenary file in the folder ``named``."""
    scenario = dict(task["scenario"])
    if task.get("catenary") is not None:
        with writing("file", into / "catenary.toml"):
            (into / "catenary.toml").write_text(tomli_w.dumps(task["catenary"]))
        scenario["catenary"] = str(named / "catenary.toml")
    with writing("file", into / "scenario.toml"):
        (into / "scenario.toml").write_text(tomli_w.dumps(scenario))


def _fatal(record: dict, stage, exc: Exception) -> dict:
    """The record of a case that could not write its files: nothing of it is kept, no
    ``case.json`` (the case runs again on resume)."""
    if stage is not None:
        stage.discard()
    record.update(status="lost", error=str(exc), fatal=str(exc))
    return record


def _run(folder: Path, run: dict, times: dict, report_dir: Path | None = None) -> dict:
    t = time.perf_counter()
    prep = prepare(load_scenario(folder / "scenario.toml"), force=run["force"])
    times["prepare_time_s"] = time.perf_counter() - t
    scheme = COUPLINGS[run["coupling"]]
    t = time.perf_counter()
    if scheme == "monolithic":
        result = run_monolithic(prep, folder, progress=False)
    else:
        result = run_cosim(prep, folder, scheme=scheme, accelerator=run["accelerator"],
                           progress=False)
    times["run_time_s"] = time.perf_counter() - t

    if isinstance(result.error, OutputError):   # a full disk while the run wrote
        raise result.error
    result = dataclasses.replace(result, coupling=run["coupling"])   # the campaign's name
    t = time.perf_counter()
    summary = finish(result, folder, plots=run["plots"], report_dir=report_dir)
    times["finish_time_s"] = time.perf_counter() - t
    return summary


def _essentials(summary: dict) -> dict:
    """What the results table needs of a run's summary."""
    keys = ("wall_time_s", "setup_time_s", "simulated_time_s", "steps", "catenary_dofs",
            "target_mean_n", "analysis_window_m", "newton_iterations_mean",
            "coupling_iterations_mean", "warnings")
    out = {k: summary[k] for k in keys if k in summary}
    out["pantographs"] = [{"index": p["index"], "model": p["model"],
                           "statistics": p["statistics"]} for p in summary["pantographs"]]
    return out


def _worker() -> dict:
    """Which worker ran the case and its resident memory now [MB]."""
    try:
        from distributed import get_worker

        address = get_worker().address
    except (ImportError, ValueError):
        address = "local"
    return {"worker": address, "worker_pid": os.getpid(),
            "worker_rss_mb": psutil.Process().memory_info().rss / 2**20}

"""Running a sweep on Dask: a LocalCluster of worker processes by default, or any scheduler.

Cases already done (their folder ``cases/<hash>/case.json`` exists) are skipped, so running a
sweep again resumes it; failed cases are run again only with ``retry_failed``. Each case is
one task (:func:`pantocosim.master.campaign.worker.run_case`); results are written as tasks
finish. A task lost with its worker is recorded as ``lost`` (and run again next time).
"""

from __future__ import annotations

import asyncio
import json
import logging
import os
import shutil
import sys
import time
import warnings
import uuid
from dataclasses import dataclass, field
from pathlib import Path

from tqdm import tqdm

from pantocosim.core.errors import ParameterError, PantocosimError
from pantocosim.master.campaign.assessment import load_criteria
from pantocosim.master.campaign.spec import Sweep
from pantocosim.master.campaign.table import ResultsTable, columns, rows_of
from pantocosim.master.campaign.worker import CASE_FILE, run_case
from pantocosim.master.interrupt import children_deaf_to_ctrl_c
from pantocosim.master.output_folder import writing
from pantocosim.master.campaign.axes import COUPLINGS
from pantocosim.master.fmu.build import default_out, ensure_fmus
from pantocosim.master.folder_lock import FolderLock
from pantocosim.master.interrupt import raise_if_swallowed

#: seconds to wait for ``--workers N`` workers to join a given scheduler
WAIT_FOR_WORKERS_S = 120.0
#: Dask's setting of the workers' statistical profiler (environment variable)
PROFILE_ENV = "DASK_DISTRIBUTED__WORKER__PROFILE__ENABLED"


@dataclass
class Outcome:
    folder: Path
    total: int
    skipped: int = 0
    ok: int = 0
    #: cases that ran with warnings (:mod:`pantocosim.master.stability`)
    warned: int = 0
    failed: int = 0
    lost: int = 0
    interrupted: bool = False
    stats: dict = field(default_factory=dict)
    collected: set = field(default_factory=set)     # keys of the cases recorded this run


def case_folder(out: Path, key: str) -> Path:
    return Path(out).resolve() / "cases" / key


def task_of(case, out: Path) -> dict:
    """The plain data a worker needs to run ``case``."""
    return {"key": case.key, "index": case.index, "values": case.values,
            "folder": str(case_folder(out, case.key)), "scenario": case.scenario,
            "catenary": case.catenary, "run": case.run}


def previous(case, out: Path, retry_failed: bool) -> dict | None:
    """The record of a case done in an earlier run of the sweep, if it counts as done."""
    path = case_folder(out, case.key) / CASE_FILE
    try:
        record = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    if record.get("key") != case.key or (record.get("status") != "ok" and retry_failed):
        return None
    return record


def run_sweep(sweep: Sweep, out: Path, scheduler: str | None = None,
              workers: int | None = None, retry_failed: bool = False,
              progress: bool | None = None, echo=print) -> Outcome:
    """Run the cases of ``sweep`` not done yet in ``out``; write the results table."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    criteria = load_criteria(sweep.criteria, base=Path(sweep.source).parent)
    with writing("--out", out):
        _keep_inputs(sweep, criteria, out)
    for staged in (out / "cases").glob(".*.partial"):   # of cases a killed sweep left
        shutil.rmtree(staged, ignore_errors=True)
    table = ResultsTable(out, columns([n for n, _ in sweep.axes], criteria))
    outcome = Outcome(folder=out, total=len(sweep.cases))
    todo = []
    for case in sweep.cases:
        record = previous(case, out, retry_failed)
        if record is None:
            todo.append(case)
        else:
            outcome.skipped += 1
            table.add(rows_of(record, case, criteria))
    echo(f"sweep {sweep.name}: {len(sweep.cases)} cases, {outcome.skipped} already done, "
         f"{len(todo)} to run; results in {out}")
    if sweep.duplicates:
        echo(f"  ({sweep.duplicates} duplicate combinations left out)")
    records = []
    try:
        if todo:
            _prebuild_fmus(todo)
            records = _execute(todo, out, scheduler, workers, progress, echo, table,
                               criteria, outcome)
    except KeyboardInterrupt:
        outcome.interrupted = True
        _late(todo, out, outcome, table, criteria)
        echo(f"interrupted: {outcome.skipped + outcome.ok + outcome.warned + outcome.failed} of "
             f"{outcome.total} cases done; run the sweep again to resume")
    finally:
        table.close()
    outcome.stats = timing_statistics(records)
    with writing("file", out / "sweep.json"):
        (out / "sweep.json").write_text(json.dumps(
            {"name": sweep.name, "source": sweep.source, "cases": outcome.total,
             "skipped": outcome.skipped, "ok": outcome.ok, "warned": outcome.warned,
             "failed": outcome.failed,
             "lost": outcome.lost, "interrupted": outcome.interrupted,
             "scheduler": scheduler or "local", "timing": outcome.stats,
             "load_average": list(os.getloadavg()) if hasattr(os, "getloadavg") else None},
            indent=2) + "\n")
    return outcome


def _late(todo, out: Path, outcome: Outcome, table, criteria) -> None:
    """Rows of the cases that finished on their worker (``case.json`` written) but whose
    result had not reached this process when the sweep was interrupted."""
    for case in todo:
        if case.key not in outcome.collected:
            record = previous(case, out, retry_failed=False)
            if record is not None:
                setattr(outcome, record["status"], getattr(outcome, record["status"]) + 1)
                table.add(rows_of(record, case, criteria))


def _keep_inputs(sweep: Sweep, criteria, out: Path) -> None:
    """Copies of the sweep and criteria files beside the results (what ``report`` reads)."""
    for src, name in ((sweep.source, "sweep.toml"), (criteria.source, "criteria.toml")):
        if Path(src).resolve() != (out / name).resolve():
            shutil.copyfile(src, out / name)
    (out / "cases.json").write_text(json.dumps(
        [{"index": c.index, "case": c.key, "values": c.values, **c.descriptors}
         for c in sweep.cases], indent=1, default=str) + "\n")


def _prebuild_fmus(cases) -> None:
    """Build the FMUs of the co-simulated cases once, here, before workers need them, and
    point each case's pantographs at their FMU by absolute path (the catenary FMU is found
    in ``dist/fmus`` of the worker's working folder: start workers in this folder)."""
    cosim = [c for c in cases if COUPLINGS[c.run["coupling"]] != "monolithic"]
    if not cosim:
        return
    dist = default_out()
    wanted = {dist / "catenary.fmu"}
    for c in cosim:
        for p in c.scenario["pantographs"]:
            if not p.get("fmu"):
                p["fmu"] = str((dist / f"{Path(p['model']).stem}.fmu").resolve())
                wanted.add(dist / f"{Path(p['model']).stem}.fmu")

    with FolderLock(dist, "dist/fmus", wait=True, required=False):   # one build at a time in that folder
        ensure_fmus(sorted(wanted), dist)


def make_client(scheduler: str | None, workers: int | None, n_cases: int, echo):
    """A Dask client: to ``scheduler`` (address, or a scheduler file) or to a new LocalCluster
    of ``workers`` single-threaded worker processes on this machine."""
    from distributed import Client, LocalCluster

    if scheduler:
        try:
            if Path(scheduler).is_file():
                client = Client(scheduler_file=scheduler, timeout="30s")
            else:
                client = Client(scheduler, timeout="30s")
        except (OSError, TimeoutError, ValueError) as exc:
            raise ParameterError("--scheduler", scheduler,
                                 f"cannot connect to the Dask scheduler ({exc})") from None
        if workers:
            try:
                client.wait_for_workers(workers, timeout=WAIT_FOR_WORKERS_S)
            except TimeoutError:
                client.close()
                raise PantocosimError(f"fewer than {workers} workers joined {scheduler} "
                                      f"within {WAIT_FOR_WORKERS_S:g} s") from None
        return client, None
    import dask

    n = workers or max(1, min(os.cpu_count() or 1, n_cases))
    # Dask's statistical profiler keeps an hour of per-second profiles in each worker: off,
    # so worker memory stays flat over a campaign (docs/campaigns.md), unless asked for
    profile = os.environ.get(PROFILE_ENV, "false").lower() in ("1", "true", "yes")
    _quiet_resource_tracker()
    cluster = None
    try:
        with children_deaf_to_ctrl_c(), dask.config.set(
                {"distributed.worker.profile.enabled": profile}), warnings.catch_warnings():
            # a dashboard port in use (another cluster) moves the dashboard to a free port;
            # the sweep's "dashboard:" line says where, so Dask's own warning is not printed
            warnings.filterwarnings("ignore", message=r"Port \d+ is already in use",
                                    category=UserWarning)
            cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                                   host="127.0.0.1", dashboard_address="127.0.0.1:8787")
        return Client(cluster), cluster
    except BaseException:          # a Ctrl-C of the start: stop what was started
        if cluster is not None:
            _close_quietly(None, cluster)
        raise


#: the -W option that keeps multiprocessing's resource tracker from warning
_TRACKER_QUIET = "ignore:resource_tracker:UserWarning"


def _quiet_resource_tracker() -> None:
    """Worker processes the nanny kills mid-case (a stopped sweep) leave their semaphores to
    multiprocessing's resource tracker, which removes them and warns at exit: the tracker,
    started with this interpreter's -W options, is started without that warning."""
    if _TRACKER_QUIET not in sys.warnoptions:
        sys.warnoptions.append(_TRACKER_QUIET)


def _close_quietly(client, cluster) -> None:
    """Close the client and our cluster; the nanny's notices of workers it had to kill
    (cases stopped mid-way) are not shown."""
    nanny = logging.getLogger("distributed.nanny")
    level = nanny.level
    nanny.setLevel(logging.ERROR)
    try:
        if client is not None and cluster is not None:
            client.run(_quiet_cancellations, True)     # workers stopped mid-case: no notices
        if client is not None:
            client.close(timeout=10)
        if cluster is not None:
            cluster.close()
    except Exception:  # noqa: BLE001 - closing a client whose scheduler is gone
        pass
    finally:
        nanny.setLevel(level)


def _execute(todo, out, scheduler, workers, progress, echo, table, criteria, outcome):
    """Submit the cases and collect them as they finish; returns their records."""
    client, cluster = make_client(scheduler, workers, len(todo), echo)
    quiet = _QuietReconnect()
    logging.getLogger("distributed.client").addFilter(quiet)
    if cluster is not None:   # our own workers: no warning for the tasks a stop cancels
        client.run(_quiet_cancellations)
    try:
        _describe(client, echo)
        token = uuid.uuid4().hex[:8]
        submitted = time.time()
        futures = {}
        for case in todo:
            f = client.submit(run_case, task_of(case, out), key=f"case-{case.key}-{token}",
                              pure=False)
            futures[f.key] = (case, f)
        try:
            return _collect(futures, submitted, out, progress, table, criteria, outcome)
        finally:
            for _, f in futures.values():
                f.cancel()
    finally:
        _close_quietly(client, cluster)
        logging.getLogger("distributed.client").removeFilter(quiet)


def _describe(client, echo) -> None:
    info = client.scheduler_info()
    echo(f"  Dask scheduler {client.scheduler.address}, "
         f"{len(info.get('workers', {}))} workers")
    if any(n > 1 for n in client.nthreads().values()):
        echo("  warning: workers with more than one thread run several cases in one "
             "process (start them with --nthreads 1: FMUs and the worker memory "
             "figures want one case per process)")
    link = _dashboard(client)
    if link:
        echo(f"  dashboard: {link}")


def _collect(futures, submitted, out, progress, table, criteria, outcome) -> list:
    """Records of the cases in the order they finish, each written to the table at once; a
    task that raised (its worker died, the task was cancelled) is recorded as lost."""
    from distributed import as_completed

    enabled = sys.stderr.isatty() if progress is None else progress
    records = []
    with tqdm(total=len(futures), desc="cases", unit="case", disable=not enabled,
              file=sys.stderr) as bar:
        for f in as_completed([f for _, f in futures.values()]):
            case, _ = futures[f.key]
            try:
                record = f.result()
            except Exception as exc:  # noqa: BLE001 - the worker or the task was lost
                if "scheduler-connection-lost" in str(exc):
                    done = outcome.skipped + outcome.ok + outcome.warned + outcome.failed
                    raise SweepStopped(f"the connection to the Dask scheduler was lost (it "
                                       f"stopped or is unreachable): {done} of "
                                       f"{outcome.total} cases done, kept in {out}; run the "
                                       "sweep again to resume") from None
                record = {"key": case.key, "status": "lost",
                          "error": f"{type(exc).__name__}: {exc}",
                          "folder": str(case_folder(out, case.key))}
            if record.get("fatal"):
                raise SweepStopped(f"case {case.index + 1} ({case.label}) could not write its "
                                   f"results: {record['fatal']}; the sweep stopped, the cases "
                                   f"done are kept in {out}: run it again to resume")
            record.update(submitted_at=submitted, received_at=time.time())
            records.append(record)
            outcome.collected.add(case.key)
            setattr(outcome, record["status"], getattr(outcome, record["status"]) + 1)
            if record["status"] != "ok":
                why = record["error"] or "; ".join(record.get("warnings") or [])
                bar.write(f"case {case.index + 1} ({case.label}) {record['status']}: {why}")
            table.add(rows_of(record, case, criteria))
            bar.update(1)
            raise_if_swallowed()    # a Ctrl-C lost inside a callback still stops the sweep
    return records


def _quiet_cancellations(closing: bool = False) -> None:
    """In a worker of our own: no warning for the tasks a stop cancels; when ``closing``, no
    notice at all (a worker stopped mid-case reports a lost scheduler)."""
    logging.getLogger("distributed.worker.state_machine").setLevel(logging.ERROR)
    if closing:
        logging.getLogger("distributed").setLevel(logging.CRITICAL + 1)


class SweepStopped(PantocosimError):
    """The sweep cannot go on (the scheduler is gone, a case cannot write); says why."""


class _QuietReconnect(logging.Filter):
    """Drops the Dask client's tracebacks of a failed reconnection (the sweep says it in one
    line)."""

    def filter(self, record: logging.LogRecord) -> bool:
        exc = record.exc_info[1] if record.exc_info else None
        if record.levelno < logging.ERROR or exc is None:
            return True
        return not isinstance(exc, (OSError, asyncio.CancelledError))   # CommClosedError too


def _dashboard(client) -> str | None:
    """The dashboard address, when the scheduler serves one (needs bokeh)."""
    try:
        services = client.scheduler_info().get("services", {})
    except Exception:  # noqa: BLE001 - informative only
        return None
    return client.dashboard_link if "dashboard" in services else None


def timing_statistics(records: list) -> dict:
    """Wall time of the sweep against the cases' own wall times, CPU time of the cases over
    the wall time (the cores the cases had on average), dispatch overhead, worker memory.
    Overhead of a case: the time its worker idled between the previous case (or the
    submission) and this one, plus the time its result took to reach the client."""
    done = [r for r in records if "case_wall_time_s" in r]
    if not done:
        return {}
    first = min(r["submitted_at"] for r in done)
    last = max(r["received_at"] for r in done)
    wall = last - first
    own = sum(r["case_wall_time_s"] for r in done)
    gaps, returns, memory = [], [], {}
    for w in sorted({r["worker"] for r in done}):
        mine = sorted((r for r in done if r["worker"] == w), key=lambda r: r["started_at"])
        prev_end = first
        for r in mine:
            gaps.append(max(0.0, r["started_at"] - prev_end))
            prev_end = r["finished_at"]
        memory[w] = [round(r["worker_rss_mb"], 1) for r in mine]
    for r in done:
        returns.append(max(0.0, r["received_at"] - r["finished_at"]))
    n = len(done)
    overhead = (sum(gaps) + sum(returns)) / n
    cpu = sum(r.get("case_cpu_time_s", 0.0) for r in done)
    return {"cases_run": n, "wall_time_s": wall, "sum_case_wall_time_s": own,
            "wall_over_sum": wall / own if own > 0 else None,
            "sum_case_cpu_time_s": cpu, "cores_used": cpu / wall if wall > 0 else None,
            "mean_case_wall_time_s": own / n,
            "overhead_per_case_s": overhead,
            "overhead_percent_of_case": 100.0 * overhead / (own / n) if own > 0 else None,
            "dispatch_gap_mean_s": sum(gaps) / n, "result_return_mean_s": sum(returns) / n,
            "worker_rss_mb": memory}

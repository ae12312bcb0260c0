"""`pantocosim sweep` on Dask: a LocalCluster of 2 worker processes, a scheduler
and a worker started as separate processes on localhost, resume after an interrupted sweep.
Each sweep has 3 short cases (5 spans, one analysed span, linear catenary), one of which
fails (above 0.7 of the wave speed) and is recorded while the others go on."""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from waiting import group_size, wait_until

#: Dask clusters and several runs each: outside `pytest -m "not slow"` (CI runs everything)
pytestmark = pytest.mark.slow

SWEEP = """
name = "test-3"
scenario = "en50318-300"
[set]
catenary_model = "linear"
spans = 5
analysis.window_supports = [2, 3]
[axes]
speed_kmh = [{speeds}]
"""
CLI = [sys.executable, "-m", "pantocosim.master.cli"]


def write_sweep(tmp_path, speeds=(200.0, 300.0, 420.0)):
    f = tmp_path / "t-sweep.toml"
    f.write_text(SWEEP.format(speeds=", ".join(str(s) for s in speeds)))
    return f


def sweep(args, cwd, timeout=600):
    return subprocess.run(CLI + ["sweep", *map(str, args), "--quiet"], capture_output=True,
                          text=True, timeout=timeout, cwd=cwd)


def results(out):
    from pantocosim.master.campaign.table import read_table

    return {r["speed_kmh"]: r for r in read_table(out)}


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """Statistics of the 300 km/h case run directly (prepare + run_monolithic, this
    process), from the scenario the sweep builds for it."""
    import tomli_w

    from pantocosim.master.campaign.spec import load_sweep
    from pantocosim.master.run import prepare, run_monolithic
    from pantocosim.master.scenario import load_scenario

    tmp = tmp_path_factory.mktemp("reference")
    case = next(c for c in load_sweep(write_sweep(tmp)).cases if c.values["speed_kmh"] == 300)
    (tmp / "case.toml").write_text(tomli_w.dumps(case.scenario))
    result = run_monolithic(prepare(load_scenario(tmp / "case.toml")), None, progress=False)
    return result.statistics()[0].as_dict()


def check_results(out, proc, reference):
    """2 cases ok with sensible statistics, the 420 km/h case failed with its message, the
    300 km/h case as run directly."""
    assert proc.returncode == 1, proc.stdout + proc.stderr   # 1: a case failed
    assert "2 ok, 1 failed" in proc.stdout, proc.stdout
    rows = results(out)
    assert sorted(rows) == [200.0, 300.0, 420.0]
    bad = rows[420.0]
    assert bad["status"] == "failed" and "wave speed" in bad["error"]
    assert bad["mean_n"] is None and bad["assessment"] == "n/a"
    for v in (200.0, 300.0):
        r = rows[v]
        assert r["status"] == "ok", r
        # constant 115 N uplift of the EN 50318-type pantograph; one span analysed
        assert abs(r["mean_n"] - 115.0) < 0.04 * 115.0, r
        assert 5.0 < r["std_n"] < 60.0 and r["loss_of_contact_percent"] == 0.0
        assert r["assessment"] in ("pass", "fail")
        folder = Path(r["folder"])
        assert (folder / "timeseries.csv").exists() and (folder / "summary.json").exists()
    # faster is rougher on this line
    assert rows[300.0]["std_n"] > rows[200.0]["std_n"]
    for k in ("mean_n", "std_n", "max_n", "min_n", "max_uplift_at_support_m"):
        assert rows[300.0][k] == pytest.approx(reference[k], rel=1e-9, abs=1e-12), k
    with open(out / "results.csv") as fh:
        assert len(fh.read().strip().splitlines()) == 4
    return rows


def test_local_cluster_two_workers(tmp_path, reference):
    out = tmp_path / "out"
    proc = sweep([write_sweep(tmp_path), "--workers", "2", "--out", out], tmp_path)
    rows = check_results(out, proc, reference)
    assert "dashboard: http://127.0.0.1:" in proc.stdout
    ok = [r for r in rows.values() if r["status"] == "ok"]
    # worker processes, not threads: the cases ran in processes other than this one
    pids = {r["worker_pid"] for r in rows.values()}
    assert os.getpid() not in pids and len(ok) == 2
    timing = json.loads((out / "sweep.json").read_text())["timing"]
    assert timing["cases_run"] == 3 and timing["sum_case_wall_time_s"] > 0
    # the case folder's scenario runs again with `pantocosim run` (checked in-process above)
    assert "speed_kmh = 300.0" in (Path(rows[300.0]["folder"]) / "scenario.toml").read_text()
    # the report of this sweep
    rep = subprocess.run(CLI + ["report", str(out)], capture_output=True, text=True,
                         timeout=300)
    assert rep.returncode == 0, rep.stderr
    text = (out / "report" / "report.md").read_text()
    assert "3 in the sweep, 2 ok, 1 failed" in text and (out / "report" / "pass_fail.png").exists()


def test_scheduler_and_worker_processes(tmp_path, reference):
    """The cluster path: `dask scheduler` and `dask worker` as separate processes, the sweep
    given the scheduler's address."""
    dask = str(Path(sys.executable).parent / "dask")
    sched_file = tmp_path / "scheduler.json"
    procs = []
    try:
        procs.append(subprocess.Popen(
            [dask, "scheduler", "--host", "127.0.0.1", "--port", "0",
             "--dashboard-address", "127.0.0.1:0", "--scheduler-file", str(sched_file)],
            cwd=tmp_path, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        deadline = time.time() + 60
        while not sched_file.exists() and time.time() < deadline:
            time.sleep(0.2)
        address = json.loads(sched_file.read_text())["address"]
        procs.append(subprocess.Popen(
            [dask, "worker", address, "--nthreads", "1", "--nworkers", "1",
             "--host", "127.0.0.1", "--no-dashboard"],
            cwd=tmp_path, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        out = tmp_path / "out"
        proc = sweep([write_sweep(tmp_path), "--scheduler", address, "--workers", "1",
                      "--out", out], tmp_path)
        rows = check_results(out, proc, reference)
        assert f"Dask scheduler {address}" in proc.stdout
        assert len({r["worker"] for r in rows.values()}) == 1
        assert json.loads((out / "sweep.json").read_text())["scheduler"] == address
    finally:
        for p in reversed(procs):
            p.terminate()
        for p in procs:
            try:
                p.wait(timeout=30)
            except subprocess.TimeoutExpired:
                p.kill()


def test_resume_after_interruption(tmp_path):
    """Ctrl-C after the first case: the finished case is kept and not run again; running the
    sweep again runs only the rest."""
    from pantocosim.master.campaign.spec import load_sweep

    speeds = (200.0, 220.0, 240.0, 260.0, 280.0, 300.0)   # a case takes about a second
    f = write_sweep(tmp_path, speeds)
    out = tmp_path / "out"
    keys = [c.key for c in load_sweep(f).cases]
    proc = subprocess.Popen(CLI + ["sweep", str(f), "--workers", "1", "--out", str(out),
                                   "--quiet"], cwd=tmp_path, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.time() + 400
        while time.time() < deadline:
            done = [k for k in keys if (out / "cases" / k / "case.json").exists()]
            if done or proc.poll() is not None:
                break
            time.sleep(0.2)
        assert done, "no case finished"
        proc.send_signal(signal.SIGINT)
        stdout, stderr = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert proc.returncode == 130, stdout + stderr
    assert "interrupted" in stdout and "run the sweep again to resume" in stdout
    finished = {k: (out / "cases" / k / "case.json").stat().st_mtime_ns for k in keys
                if (out / "cases" / k / "case.json").exists()}
    assert 1 <= len(finished) < len(speeds), stdout + stderr
    # the table holds the cases that finished (one that a worker was finishing while the
    # cluster shut down may come only with the next run: its case.json is what counts)
    first = results(out)
    assert 1 <= len(first) <= len(finished), (first, finished, stdout, stderr)
    assert {r["case"] for r in first.values()} <= set(finished)
    again = sweep([f, "--workers", "1", "--out", out], tmp_path)
    assert again.returncode == 0, again.stdout + again.stderr
    assert f"{len(finished)} already done, {len(speeds) - len(finished)} to run" in \
        again.stdout, \
        (again.stdout, finished)
    for k, mtime in finished.items():            # not run again
        assert (out / "cases" / k / "case.json").stat().st_mtime_ns == mtime
    rows = results(out)
    assert sorted(rows) == list(speeds)
    assert all(r["status"] == "ok" for r in rows.values())
    for v, r in first.items():
        assert rows[v]["mean_n"] == r["mean_n"]


def test_cases_through_the_fmus(tmp_path, reference):
    """A co-simulated case (explicit coupling of the FMUs) runs in a worker process; the FMUs
    are built once before submission; its statistics agree with the monolithic run."""
    f = tmp_path / "fmu-sweep.toml"
    f.write_text(write_sweep(tmp_path, (300.0,)).read_text().replace(
        "[axes]", '[run]\ncoupling = "explicit"\n[axes]'))
    out = tmp_path / "out"
    proc = sweep([f, "--workers", "1", "--out", out], tmp_path)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    row = results(out)[300.0]
    assert row["status"] == "ok" and row["coupling"] == "explicit"
    assert row["worker_pid"] != os.getpid() and row["setup_time_s"] > 0   # FMU set-up
    assert (tmp_path / "dist" / "fmus" / "catenary.fmu").exists()
    assert row["mean_n"] == pytest.approx(reference["mean_n"], rel=2e-3)
    assert row["std_n"] == pytest.approx(reference["std_n"], rel=2e-2)


@pytest.mark.parametrize("moment", ["workers starting", "cases running"])
def test_ctrl_c_of_a_sweep_of_short_cases_is_one_line(tmp_path, moment):
    """A terminal's Ctrl-C reaches the whole process group (the command and its Dask
    workers): whether the workers are still starting or running cases, the sweep stops with
    status 130, its one line, and nothing on stderr (no worker traceback or notice)."""
    f = write_sweep(tmp_path, (200.0, 210.0, 220.0, 230.0, 240.0, 250.0, 260.0, 270.0))
    out = tmp_path / "out"
    proc = subprocess.Popen(CLI + ["sweep", str(f), "--workers", "2", "--out", str(out),
                                   "--quiet"], cwd=tmp_path, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        deadline = time.time() + 400
        while time.time() < deadline and proc.poll() is None:
            if moment == "workers starting" and (out / "cases.json").exists():
                # the worker processes are started (and importing)
                wait_until(lambda: group_size(proc.pid) >= 3, "the workers' processes",
                           proc=proc)
                break
            if moment == "cases running" and list(out.glob("cases/*/case.json")):
                break
            time.sleep(0.05)
        assert proc.poll() is None, "the sweep ended before the Ctrl-C"
        os.killpg(proc.pid, signal.SIGINT)
        stdout, stderr = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.communicate()
    assert proc.returncode == 130, stdout + stderr
    assert stderr.strip() == "", stderr
    lines = [line for line in stdout.splitlines() if line.startswith("interrupted")]
    assert len(lines) == 1 and "run the sweep again to resume" in lines[0], stdout

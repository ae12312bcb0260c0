"""``pantocosim run --realtime``: step pacing and the step-time report (no timing thresholds:
the machine is shared, only the shape and consistency of the figures are checked)."""

import json
from pathlib import Path

import pytest

from pantocosim.master.pacing import StepClock, describe

DATA = Path(__file__).with_name("data")


def short_scenario(tmp_path, duration=0.05) -> Path:
    """tests/data/short-en50318.toml cut to ``duration`` seconds (window inside the run)."""
    text = (DATA / "short-en50318.toml").read_text()
    text = text.replace("window_m = [35.0, 60.0]", "window_m = [30.5, 33.0]")
    text = text.replace("coupling_rtol = 1e-9", f"coupling_rtol = 1e-9\nduration_s = {duration}")
    path = tmp_path / "short.toml"
    path.write_text(text)
    return path


def check_timing(summary, steps, paced=True):
    st = summary["step_time"]
    assert st["steps"] == steps
    assert 0.0 < st["p50_ms"] <= st["p99_ms"] <= st["max_ms"]
    assert st["mean_ms"] <= st["max_ms"]
    if not paced:
        assert "realtime" not in summary
        return
    rt = summary["realtime"]
    assert rt["paced"] and rt["steps"] == steps and rt["deadline_ms"] == pytest.approx(1.0)
    assert 0 <= rt["missed_deadlines"] <= steps
    assert rt["worst_lateness_ms"] >= 0.0
    assert (rt["missed_deadlines"] == 0) == (rt["worst_lateness_ms"] == 0.0)


def test_realtime_run_reports_step_times_and_deadlines(tmp_path, capsys):
    from pantocosim.master.cli import main

    out = tmp_path / "out"
    assert main(["run", str(short_scenario(tmp_path)), "--realtime", "--no-plots", "--quiet",
                 "--out", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "step time p50" in printed and "missed deadlines" in printed
    summary = json.loads((out / "summary.json").read_text())
    assert summary["steps"] == 50
    check_timing(summary, 50)
    # a paced loop never ends before its last deadline
    assert summary["wall_time_s"] >= 0.05


def test_cosim_loop_is_paced_by_the_same_clock(tmp_path):
    from pantocosim.master.cosim import run_cosim
    from pantocosim.master.run import finish, prepare

    prep = prepare(str(short_scenario(tmp_path)))
    for scheme in ("jacobi", "implicit"):
        res = run_cosim(prep, None, scheme=scheme, progress=False, in_process=True,
                        realtime=True)
        assert res.error is None
        summary = finish(res, None, plots=False)
        check_timing(summary, 50)
        res = run_cosim(prep, None, scheme=scheme, progress=False, in_process=True)
        check_timing(finish(res, None, plots=False), 50, paced=False)


def test_clock_waits_for_each_deadline_and_counts_late_steps():
    """A fake clock: a step of 0.3 dt waits for its deadline, a 2.5 dt step is late by
    1.5 dt, the schedule is kept (the next step starts at once, is still 0.6 dt late, and
    the one after catches up)."""
    now = [0.0]
    work = {0: 0.3, 1: 2.5, 2: 0.1, 3: 0.1}

    def sleep(s):
        now[0] += s

    def clock():
        now[0] += 1e-9  # each reading costs a little (the busy-wait ends)
        return now[0]

    c = StepClock(1.0, realtime=True, clock=clock, sleep=sleep, spin_s=0.0)
    ends = []
    for k in c.steps(4):
        now[0] += work[k]
        ends.append(now[0])
    s = c.summary()
    assert s["realtime"]["missed_deadlines"] == 2  # step 1 (1.5 late) and step 2 (0.6 late)
    assert s["realtime"]["worst_lateness_ms"] == pytest.approx(1500.0, rel=1e-6)
    assert ends[0] == pytest.approx(0.3, abs=1e-6) and ends[3] == pytest.approx(3.7, abs=1e-6)
    assert now[0] >= 4.0  # waited for the last deadline
    assert s["step_time"]["max_ms"] == pytest.approx(2500.0, rel=1e-6)
    assert "2 missed deadlines" in describe(s)


def test_paced_loop_collects_garbage_in_its_waits_only():
    """Inside a paced loop the automatic collector is off; a reference cycle made in a step
    is collected in the wait that follows, and the collector is back on after the loop."""
    import gc
    import weakref

    class Node:
        pass

    now = [0.0]

    def sleep(s):
        now[0] += s

    def clock():
        now[0] += 1e-9
        return now[0]

    assert gc.isenabled()
    c = StepClock(1.0, realtime=True, clock=clock, sleep=sleep, spin_s=0.0)
    refs = []
    for k in c.steps(3):
        assert not gc.isenabled()
        if k == 0:
            for _ in range(2 * gc.get_threshold()[0]):   # young objects past the threshold
                a, b = Node(), Node()
                a.other, b.other = b, a
            refs.append(weakref.ref(a))
            del a, b
        now[0] += 0.1
        if k == 1:
            assert refs[0]() is None       # collected in the wait after step 0
    assert gc.isenabled()

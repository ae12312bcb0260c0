"""Step timing and real-time pacing of a run's time loop (``pantocosim run --realtime``).

Every coupling drives its steps through one :class:`StepClock`::

    clock = StepClock(dt, realtime=args.realtime)
    for k in clock.steps(n_steps):
        ...one step and its recorded row...
    result.summary.update(clock.summary())

The clock times the body of each loop iteration (the step and its recorded row: the work a
hardware-in-the-loop cycle has to finish before its deadline) with ``time.perf_counter``.
With ``realtime=True`` it paces the loop as a HIL loop would: step k (0-based) must end by
its deadline ``t0_wall + (k + 1) h``, where ``t0_wall`` is the wall time the loop started;
the clock sleeps until shortly before the deadline and busy-waits the rest, so the next step
starts on the deadline. A step that ends after its deadline is a missed deadline (its
lateness is the difference); the schedule is not shifted, so the following steps start at
once and catch up if they can, as a fixed-rate loop does.

The summary reports the compute time per step (p50, p99, max, mean, over every step,
without the waiting) and, when paced, the missed deadlines (count and worst lateness).
"""

from __future__ import annotations

import time

import numpy as np

#: below this much time to the deadline the clock busy-waits instead of sleeping
#: (time.sleep overshoots by 50-100 us on Linux)
SPIN_S = 3e-4


class StepClock:
    """Times each step and, if ``realtime``, paces the steps to the wall clock."""

    def __init__(self, dt: float, realtime: bool = False, spin_s: float = SPIN_S,
                 clock=time.perf_counter, sleep=time.sleep):
        if not dt > 0:
            raise ValueError(f"step size {dt!r} must be > 0")
        self.dt = float(dt)
        self.realtime = bool(realtime)
        self.spin_s = float(spin_s)
        self._clock = clock
        self._sleep = sleep
        self.compute_s = np.zeros(0)
        self.lateness_s = np.zeros(0)
        self.n_done = 0

    def steps(self, n: int):
        """Yield 0 .. n-1, timing (and pacing) the loop body run between two yields."""
        n = int(n)
        clock, dt = self._clock, self.dt
        self.compute_s = np.zeros(n)
        self.lateness_s = np.zeros(n)
        self.n_done = 0
        t0 = clock()
        for k in range(n):
            start = clock()
            yield k
            end = clock()
            self.compute_s[k] = end - start
            self.n_done = k + 1
            if self.realtime:
                deadline = t0 + (k + 1) * dt
                if end > deadline:
                    self.lateness_s[k] = end - deadline
                else:
                    self._wait(deadline)

    def _wait(self, deadline: float) -> None:
        clock = self._clock
        remaining = deadline - clock()
        if remaining > self.spin_s:
            self._sleep(remaining - self.spin_s)
        while clock() < deadline:
            pass

    def summary(self) -> dict:
        """``step_time`` (always) and ``realtime`` (paced runs) entries of the run summary."""
        c = self.compute_s[:self.n_done] * 1e3
        if len(c):
            p50, p99 = np.percentile(c, [50.0, 99.0])
            timing = {"steps": int(len(c)), "p50_ms": float(p50), "p99_ms": float(p99),
                      "max_ms": float(c.max()), "mean_ms": float(c.mean())}
        else:
            timing = {"steps": 0, "p50_ms": 0.0, "p99_ms": 0.0, "max_ms": 0.0, "mean_ms": 0.0}
        out = {"step_time": timing}
        if self.realtime:
            late = self.lateness_s[:self.n_done]
            missed = late > 0.0
            out["realtime"] = {
                "paced": True, "deadline_ms": self.dt * 1e3, "steps": int(len(late)),
                "missed_deadlines": int(missed.sum()),
                "missed_percent": float(100.0 * missed.mean()) if len(late) else 0.0,
                "worst_lateness_ms": float(late.max() * 1e3) if len(late) else 0.0}
        return out


def describe(summary: dict) -> str | None:
    """One line on the step times and deadlines of a run summary (None if not timed)."""
    st = summary.get("step_time")
    if not st or not st.get("steps"):
        return None
    line = (f"  step time p50 {st['p50_ms']:.3f} ms, p99 {st['p99_ms']:.3f} ms, max "
            f"{st['max_ms']:.3f} ms over {st['steps']} steps")
    rt = summary.get("realtime")
    if rt:
        line += (f"; paced to {rt['deadline_ms']:g} ms: {rt['missed_deadlines']} missed "
                 f"deadlines ({rt['missed_percent']:.1f} %), worst {rt['worst_lateness_ms']:.3f}"
                 f" ms late")
    return line

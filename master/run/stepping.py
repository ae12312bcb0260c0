"""The monolithic reference run (``pantocosim run --coupling monolithic``): catenary,
pantographs and penalty contacts advanced together by the stepper the catenary model declares
(:func:`~pantocosim.interaction.stepper_factory.make_stepper`: Newton-Raphson on the assembled system, or
the closed-form structure step condensed on the contact points), one row of the time series
per step.
"""

from __future__ import annotations

import sys
import time as _time
from pathlib import Path

import numpy as np
from tqdm import tqdm

from pantocosim.core.errors import PantocosimError
from pantocosim.core.hht import HHTSettings
from pantocosim.core.stepper_contract import CoupledStepper, StepReport, warm_up
from pantocosim.interaction.stepper_factory import make_stepper
from pantocosim.master import stability
from pantocosim.master.interrupt import interrupted_at, stop_on_interrupt
from pantocosim.master.pacing import StepClock
from pantocosim.master.results.recorder import Recorder
from pantocosim.master.run.outcome import RunResult, column_names
from pantocosim.master.run.setup import Prepared


def progress_bar(total: int, label: str, enabled: bool | None = None):
    if enabled is None:
        enabled = sys.stderr.isatty()
    return tqdm(total=total, desc=label, unit="step", disable=not enabled, mininterval=0.5,
                smoothing=0.1)


def monolithic_stepper(prep: Prepared, settings: HHTSettings) -> CoupledStepper:
    """The stepper of catenary + pantographs + contacts in the static start, prepared and
    warmed up for steps of the scenario's dt (a paced loop then has no first-use step)."""
    stepper = make_stepper(prep.catenary, settings, prep.pantographs, prep.contact,
                           contact_state=prep.contact_law_state)
    stepper.initialize(0.0, np.concatenate([prep.q_cat0] + list(prep.q_pan0)))
    stepper.prepare(prep.scenario.dt)
    warm_up(stepper, prep.scenario.dt)
    return stepper


class RowWriter:
    """One row of the time series (:func:`~.outcome.column_names`) per step: the
    stepper's contacts and support uplifts, into the recorder and the stability monitor."""

    def __init__(self, prep: Prepared, stepper, rec: Recorder, monitor):
        self.prep, self.stepper, self.rec, self.monitor = prep, stepper, rec, monitor
        self.n_p = len(prep.pantographs)
        self.row = np.zeros(len(rec.names))
        #: times of the steps whose contact active set did not settle
        self.unsettled = []

    def step(self, report: StepReport) -> None:
        """The row of a step from its report."""
        if not report.settled:
            self.unsettled.append(self.stepper.t)
        self(report.iterations)

    def __call__(self, newton_iterations: int) -> None:
        st, row, n_p = self.stepper, self.row, self.n_p
        forces, heights, wire = st.contacts()
        t = st.t
        x = self.prep.catenary.positions(t)
        row[0] = t
        for k in range(n_p):
            row[1 + 4 * k:5 + 4 * k] = (x[k], forces[k], heights[k], wire[k])
        row[1 + 4 * n_p:-1] = self.prep.catenary.support_uplift(st.structure_q)
        row[-1] = newton_iterations
        self.rec.append(row)
        self.monitor.check(t, row[2:2 + 4 * n_p:4])


def run_monolithic(prep: Prepared, out_dir: Path | None, progress: bool | None = None,
                   realtime: bool = False) -> RunResult:
    """Integrate catenary + pantographs + penalty contacts monolithically (reference); with
    ``realtime`` each step is paced to the wall clock (:mod:`pantocosim.master.pacing`)."""
    sc = prep.scenario
    warnings = stability.check(prep, "monolithic")
    monitor = stability.Monitor(prep)
    stepper = monolithic_stepper(prep, HHTSettings.for_runs(sc.alpha, sc.newton_rtol))
    names = column_names(len(prep.pantographs), len(prep.support_x))
    rec = Recorder(None if out_dir is None else Path(out_dir) / "timeseries.csv", names,
                   rows=prep.n_steps + 1)
    t_wall = _time.perf_counter()
    record = RowWriter(prep, stepper, rec, monitor)
    error = None
    record(0)
    bar = progress_bar(prep.n_steps, f"{sc.name} monolithic", progress)
    clock = StepClock(sc.dt, realtime=realtime)
    with stop_on_interrupt() as stop:
        try:
            stop.check(stepper.t, 0, prep.n_steps)   # a Ctrl-C during the set-up
            for k in clock.steps(prep.n_steps):
                record.step(stepper.step(sc.dt))
                bar.update(1)
                stop.check(stepper.t, k + 1, prep.n_steps)
        except PantocosimError as exc:
            error = exc
        except KeyboardInterrupt:
            error = interrupted_at(rec.columns()["time"][-1], len(rec) - 1, prep.n_steps)
        finally:
            bar.close()
            rec.close()
    warnings += stability.unsettled_contacts(record.unsettled, len(prep.pantographs))
    return RunResult(prep=prep, coupling="monolithic", columns=rec.columns(),
                     wall_time_s=_time.perf_counter() - t_wall, error=error,
                     summary=clock.summary(), warnings=warnings)

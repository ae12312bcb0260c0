"""The results of a run: the time-series layout (:func:`column_names`), the
:class:`RunResult` every coupling returns and :func:`finish`, which computes the EN 50317
statistics and writes the JSON summary and the plots.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

try:
    import resource
except ImportError:  # pragma: no cover - not on every platform
    resource = None

from pantocosim.core.errors import Interrupted
from pantocosim.master.results import plots as P
from pantocosim.master.output_folder import writing
from pantocosim.master.results.files import write_json
from pantocosim.master.run.setup import Prepared
from pantocosim.master.stability import departures, step_separations
from pantocosim.master.results.statistics import contact_statistics, window_mask

#: the step counters of a monolithic run: the Newton iterations of its step
MONOLITHIC_COUNTERS = ("newton_iterations",)
#: the step counters of a co-simulation: the coupling iterations (passes over the step:
#: 1 for the explicit schemes) and the catenary's Newton iterations over all of them
COSIM_COUNTERS = ("coupling_iterations", "newton_iterations")


def column_names(n_pantographs: int, n_supports: int, counters=MONOLITHIC_COUNTERS
                 ) -> list[str]:
    """time, (x, contact force, contact height, wire height) per pantograph, the support
    uplifts, then the step ``counters``."""
    names = ["time"]
    for k in range(1, n_pantographs + 1):
        names += [f"x_{k}", f"contact_force_{k}", f"contact_height_{k}", f"wire_height_{k}"]
    names += [f"support_uplift_{j}" for j in range(n_supports)]
    return names + list(counters)


@dataclass(frozen=True)
class RunResult:
    prep: Prepared
    coupling: str
    columns: dict
    wall_time_s: float
    error: Exception | None = None
    #: wall time spent before the time stepping (co-simulation: FMU set-up)
    setup_time_s: float = 0.0
    summary: dict = field(default_factory=dict)
    #: implicit co-simulation: the interface residual tolerance [N] (None: not iterative)
    coupling_tolerance: float | None = None
    #: what makes the numbers doubtful (:mod:`pantocosim.master.stability`)
    warnings: list = field(default_factory=list)

    @property
    def coupling_iterations(self) -> np.ndarray | None:
        """Coupling iterations per step of an iterative co-simulation, else None."""
        if self.coupling_tolerance is None:
            return None
        return self.columns["coupling_iterations"][1:]

    def statistics(self):
        prep = self.prep
        c = self.columns
        n_p = len(prep.pantographs)
        uplift = np.column_stack([c[f"support_uplift_{j}"] for j in range(len(prep.support_x))])
        return [contact_statistics(c["time"], c[f"contact_force_{k}"], c[f"x_{k}"],
                                   prep.window_m, uplift, prep.support_x)
                for k in range(1, n_p + 1)]


#: the files a run writes into its output folder (:func:`finish`)
RESULT_FILES = ("timeseries.csv", "summary.json", "contact_force.png", "spectrum.png",
                "support_uplift.png")


def holds_complete_run(folder: Path) -> bool:
    """Whether ``folder`` holds the summary of a run that completed (``completed``)."""
    try:
        return json.loads((Path(folder) / "summary.json").read_text()).get("completed") is True
    except (OSError, ValueError, AttributeError):
        return False


def finish(result: RunResult, out_dir: Path | None, plots: bool = True,
           report_dir: Path | None = None) -> dict:
    """Statistics, JSON summary and plots of a finished (or stopped) run, written into
    ``out_dir``; the summary names the files in ``report_dir`` (default ``out_dir``: where
    they end up, :class:`~pantocosim.master.output_folder.OutputFolder`). A stopped run's
    summary says where it stopped (``stopped``)."""
    prep = result.prep
    sc = prep.scenario
    c = result.columns
    stats = result.statistics() if result.error is None else []
    summary = {
        "scenario": sc.name,
        "coupling": result.coupling,
        "catenary": prep.definition.name,
        "speed_kmh": sc.speed_kmh,
        "dt_s": sc.dt,
        "wall_time_s": result.wall_time_s,
        "setup_time_s": result.setup_time_s,
        "simulated_time_s": float(c["time"][-1]) if len(c["time"]) else 0.0,
        "steps": int(len(c["time"]) - 1),
        "catenary_dofs": int(prep.catenary.n_dofs),
        "catenary_model": sc.catenary_model,
        "catenary_modes": getattr(prep.catenary, "n_modes", None),
        "analysis_window_m": list(prep.window_m),
        "target_mean_n": [float(p.options.mean_uplift) for p in prep.pantographs],
        "statistics": stats[0].as_dict() if stats else None,
        "pantographs": [{"index": k + 1, "model": spec.model, "position_m": spec.position_m,
                         "start": spec.start,
                         "statistics": stats[k].as_dict() if stats else None}
                        for k, spec in enumerate(sc.pantographs)],
        "newton_iterations_mean": float(np.mean(c["newton_iterations"][1:]))
        if len(c["time"]) > 1 else 0.0,
    }
    coupling = result.coupling_iterations
    if coupling is not None and len(coupling):
        summary["coupling_iterations_mean"] = float(np.mean(coupling))
        summary["coupling_iterations_max"] = int(np.max(coupling))
    if result.coupling_tolerance is not None:
        summary["coupling_tolerance_n"] = float(result.coupling_tolerance)
    peak = peak_memory_mb()
    if peak is not None:
        summary["peak_memory_mb"] = peak
    summary["completed"] = result.error is None
    if result.error is not None:
        summary["error"] = str(result.error)
        summary["stopped"] = {"reason": str(result.error),
                              "interrupted": isinstance(result.error, Interrupted),
                              "time_s": summary["simulated_time_s"],
                              "steps": summary["steps"], "of_steps": int(prep.n_steps)}
    summary.update(result.summary)
    inside = [c[f"contact_force_{k}"][window_mask(c[f"x_{k}"], *prep.window_m)]
              for k in range(1, len(prep.pantographs) + 1)] if stats else []
    summary["warnings"] = (list(result.warnings) + departures(prep, stats)
                           + step_separations(prep, inside))
    #: the statistics are doubtful (see the warnings)
    summary["flagged"] = bool(summary["warnings"])
    if out_dir is not None:
        out = Path(out_dir)
        shown = Path(report_dir) if report_dir is not None else out
        summary["files"] = {"timeseries": str(shown / "timeseries.csv"),
                            "summary": str(shown / "summary.json")}
        if plots and stats:
            n_p = len(prep.pantographs)
            labels = [f"pantograph {k}" for k in range(1, n_p + 1)]
            forces = [c[f"contact_force_{k}"] for k in range(1, n_p + 1)]
            positions = [c[f"x_{k}"] for k in range(1, n_p + 1)]
            title = f"{sc.name} ({result.coupling}, {sc.speed_kmh:g} km/h)"
            with writing("file", out / "contact_force.png"):
                P.plot_contact_force(out / "contact_force.png", c["time"], positions, forces,
                                     prep.window_m, prep.support_x, prep.dropper_x, labels,
                                     title)
            masks = [window_mask(x, *prep.window_m) for x in positions]
            with writing("file", out / "spectrum.png"):
                P.plot_spectrum(out / "spectrum.png", c["time"], forces, masks, labels, title)
            uplift = np.column_stack([c[f"support_uplift_{j}"]
                                      for j in range(len(prep.support_x))])
            with writing("file", out / "support_uplift.png"):
                P.plot_support_uplift(out / "support_uplift.png", c["time"], uplift,
                                      prep.support_x, title)
            summary["files"].update(contact_force=str(shown / "contact_force.png"),
                                    spectrum=str(shown / "spectrum.png"),
                                    support_uplift=str(shown / "support_uplift.png"))
        with writing("file", out / "summary.json"):
            write_json(out / "summary.json", summary)
    return summary


def peak_memory_mb() -> float | None:
    """This process's peak resident memory in MB: ``VmHWM`` of /proc/self/status on Linux
    (``ru_maxrss`` keeps the peak of the process that started this one, a bench or a
    campaign driver, across exec), ``ru_maxrss`` elsewhere; None where neither exists."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmHWM:"):
                return float(line.split()[1]) / 1024.0
    except OSError:
        pass
    if resource is None:  # pragma: no cover - not on every platform
        return None
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0

"""Running a scenario, in three steps every coupling shares:

- set-up (:mod:`.setup`): ``prepare(scenario)`` checks the scenario against its catenary
  (:mod:`.checks`), builds the models, sets the pantographs' actuation and solves the
  static start;
- stepping: :func:`~.stepping.run_monolithic` (the reference) or
  :func:`~pantocosim.master.cosim.run_cosim` (the FMUs, or in-process subsystems);
- results (:mod:`.outcome`): ``finish(result, out_dir)`` computes the EN 50317
  statistics and writes the JSON summary and the plots beside the CSV time series.

This package gathers their entry points.
"""

from pantocosim.master.run.outcome import (RESULT_FILES, RunResult, finish,  # noqa: F401
                                          holds_complete_run)
from pantocosim.master.run.setup import Prepared, prepare  # noqa: F401
from pantocosim.master.run.stepping import run_monolithic  # noqa: F401

"""Running a scenario, in three steps every coupling shares:

- set-up (:mod:`.run_setup`): ``prepare(scenario)`` checks the scenario against its catenary
  (:mod:`.run_checks`), builds the models, sets the pantographs' actuation and solves the
  static start;
- stepping: :func:`~.run_stepping.run_monolithic` (the reference) or
  :func:`~.cosim.run_cosim` (the FMUs, or in-process subsystems);
- results (:mod:`.run_results`): ``finish(result, out_dir)`` computes the EN 50317
  statistics and writes the JSON summary and the plots beside the CSV time series.

This module gathers their entry points.
"""

from pantocosim.master.run_results import RESULT_FILES, RunResult, finish  # noqa: F401
from pantocosim.master.run_setup import Prepared, prepare  # noqa: F401
from pantocosim.master.run_stepping import run_monolithic  # noqa: F401

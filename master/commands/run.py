"""``pantocosim run``: the main job, a pantograph-catenary simulation of a scenario."""

from __future__ import annotations

import dataclasses
import json
from contextlib import contextmanager
from pathlib import Path

from pantocosim.master.coupling import ACCELERATORS, DEFAULT_ACCELERATOR, SCHEME_NAMES
from pantocosim.master.size_limits import MAX_DOFS, MAX_STEPS, check_limit_option


def add_cache_option(p) -> None:
    """``--no-cache``: compute the set-up (the moving-load run behind the operating heights)
    instead of taking it from the set-up cache (pantocosim.core.disk_cache)."""
    p.add_argument("--no-cache", action="store_true", help="compute the set-up again instead "
                   "of taking it from the cache on disk (~/.cache/pantocosim/setup)")


def add_parser(sub):
    p = sub.add_parser("run", help="simulate a scenario and print EN 50317 statistics",
                       description="Simulate SCENARIO (preset name or TOML file; default "
                       "dsa380-ave-300) and write the time series (CSV), a JSON summary with "
                       "the EN 50317 contact-force statistics, and plots.")
    p.add_argument("scenario", nargs="?", default=None, help="scenario preset or file")
    p.add_argument("--coupling", default="monolithic", choices=["monolithic", *SCHEME_NAMES],
                   help="monolithic reference solve, or co-simulation of the FMUs: explicit "
                   "(= jacobi), gauss-seidel, implicit (iterative with rollback)")
    p.add_argument("--native-pantographs", action="store_true",
                   help="co-simulation: run each pantograph that has a native form (lumped "
                   "chains with constant matrices, the rigid and the flexible DSA-380) as a "
                   "native C FMU exported for the run (pantocosim export-native), the others "
                   "and the catenary as Python FMUs")
    p.add_argument("--accelerator", default=DEFAULT_ACCELERATOR, choices=list(ACCELERATORS),
                   help="interface acceleration of the implicit coupling")
    p.add_argument("--catenary-model", default=None, choices=["nonlinear", "linear", "modal"],
                   help="catenary model (default: the scenario's [simulation] catenary_model, "
                   "else nonlinear, the reference)")
    p.add_argument("--modal-cutoff-hz", type=float, default=None,
                   help="modal catenary: modes below this frequency (default: the scenario's "
                   "modal_cutoff_hz)")
    p.add_argument("--out", default=None, help="output folder (default out/SCENARIO-COUPLING); "
                   "the run writes beside it and moves its files in when done (earlier "
                   "results are replaced only by a run that computed something; a run that "
                   "stopped early, by Ctrl-C or a solver failure, goes to OUT-stopped when OUT "
                   "holds a complete run)")
    p.add_argument("--json", action="store_true", help="print the JSON summary")
    p.add_argument("--force", action="store_true",
                   help="run even above 0.7 of the wave speed")
    p.add_argument("--no-plots", action="store_true", help="skip the PNG plots")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    add_cache_option(p)
    add_size_options(p)
    p.add_argument("--realtime", action="store_true",
                   help="pace each step to the wall clock as a hardware-in-the-loop loop "
                   "would (step k ends no earlier than start + (k + 1) dt; the loop busy-waits, "
                   "keeping one core, and collects garbage between steps) and report missed "
                   "deadlines; the step-time percentiles are reported either way")
    return p


def add_size_options(p, steps: bool = True) -> None:
    """``--max-dofs`` (and ``--max-steps``): lift the size guard's limits
    (:mod:`pantocosim.master.size_limits`)."""
    p.add_argument("--max-dofs", type=int, default=None, metavar="N",
                   help=f"build catenary models of up to N DOFs (default {MAX_DOFS:,})")
    if steps:
        p.add_argument("--max-steps", type=int, default=None, metavar="N",
                       help=f"run up to N time steps (default {MAX_STEPS:,})")


def print_statistics(summary: dict) -> None:
    print(f"scenario {summary['scenario']} ({summary['coupling']}), "
          f"{summary['speed_kmh']:g} km/h on {summary['catenary']}, window "
          f"{summary['analysis_window_m'][0]:g}-{summary['analysis_window_m'][1]:g} m")
    warnings = summary.get("warnings") or []
    flag = " [FLAGGED: see the warnings below]" if warnings else ""
    for p in summary["pantographs"]:
        s = p["statistics"]
        if s is None:
            continue
        print(f"  pantograph {p['index']} ({p['model']}){flag}: mean {s['mean_n']:.2f} N, "
              f"sigma {s['std_n']:.2f} N, stat max {s['stat_max_n']:.1f} N, stat min "
              f"{s['stat_min_n']:.1f} N, max {s['max_n']:.1f} N, min {s['min_n']:.1f} N, "
              f"loss of contact {s['loss_of_contact_percent']:.2f} %, max uplift at "
              f"support {1000 * s['max_uplift_at_support_m']:.1f} mm")
    extra = ""
    if "coupling_iterations_mean" in summary:
        extra = (f", coupling iterations mean {summary['coupling_iterations_mean']:.2f} "
                 f"max {summary['coupling_iterations_max']}")
    print(f"  simulated {summary['simulated_time_s']:.3f} s in {summary['wall_time_s']:.1f} s "
          f"wall (real-time factor {summary['wall_time_s'] / max(summary['simulated_time_s'], 1e-9):.2f})"
          f"{extra}")
    from pantocosim.master.pacing import describe

    timing = describe(summary)
    if timing:
        print(timing)
    for w in warnings:
        print(f"  WARNING: {w}")
    if "files" in summary:
        print(f"  results in {Path(summary['files']['summary']).parent}")


@contextmanager
def named_as_options(args):
    """A bad scenario field that the command line set (``--modal-cutoff-hz``) named as its
    option."""
    from pantocosim.core.errors import ParameterError

    try:
        yield
    except ParameterError as exc:
        if exc.field != "simulation.modal_cutoff_hz" or args.modal_cutoff_hz is None:
            raise
        raise ParameterError("--modal-cutoff-hz", exc.value, exc.reason) from None


def with_model(scenario, catenary_model=None, modal_cutoff_hz=None):
    """The scenario with the command line's catenary model and cutoff (None: as given)."""
    from pantocosim.core.errors import ParameterError

    changes = {}
    if catenary_model is not None:
        changes["catenary_model"] = catenary_model
    if modal_cutoff_hz is not None:
        if not modal_cutoff_hz > 0:
            raise ParameterError("--modal-cutoff-hz", modal_cutoff_hz, "must be > 0")
        changes["modal_cutoff_hz"] = float(modal_cutoff_hz)
    return dataclasses.replace(scenario, **changes) if changes else scenario


def run(args) -> int:
    from pantocosim.core.errors import Interrupted, OutputError, PantocosimError
    from pantocosim.master.interrupt import stop_on_interrupt
    from pantocosim.master.output_folder import OutputFolder
    from pantocosim.master.run import RESULT_FILES, finish, holds_complete_run
    from pantocosim.master.scenario import load_scenario
    check_limit_option("--max-dofs", args.max_dofs)
    check_limit_option("--max-steps", args.max_steps)
    scenario = with_model(load_scenario(args.scenario), args.catenary_model,
                          args.modal_cutoff_hz)
    from pantocosim.master.coupling import SCHEME_NAMES

    coupling = SCHEME_NAMES.get(args.coupling, args.coupling)   # an alias -> its scheme
    out = Path(args.out) if args.out else Path("out") / f"{scenario.name}-{args.coupling}"
    folder = None
    try:
        folder = OutputFolder(out, known=RESULT_FILES)
        result = simulate(args, scenario, coupling, folder.path)
        if len(result.columns["time"]) < 2 or isinstance(result.error, OutputError):
            raise result.error   # nothing computed (the set-up failed), or a full disk
        target = out   # a run that stopped early never replaces a complete one
        if result.error is not None and holds_complete_run(out):
            target = out.with_name(f"{out.name}-stopped")
        with stop_on_interrupt() as late:   # a Ctrl-C now waits until the files are in place
            summary = finish(result, folder.path, plots=not args.no_plots,
                             report_dir=target)
            folder.commit(into=target)
    except OutputError as exc:
        if folder is None or exc.field == "--out":   # --out itself, or moving into place
            if folder is not None:
                folder.discard()
            raise
        folder.discard()
        raise OutputError("--out", out, f"{Path(exc.path).name} {exc.reason}; nothing was "
                          f"moved into {out}: the results there are as they were") from None
    except (Interrupted, KeyboardInterrupt):   # before the time loop (loading, static start)
        if folder is not None:
            folder.discard()
        raise Interrupted(f"interrupted (Ctrl-C) during the set-up: nothing written, {out} is "
                          "as it was") from None
    except BaseException:
        if folder is not None:
            folder.discard()
        raise
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        print_statistics(summary)
    kept = (f"; the complete results of an earlier run in {out} are kept"
            if target != out else "")
    if isinstance(result.error, Interrupted):
        raise Interrupted(f"{result.error}; the results so far are in {target} (summary.json "
                          f"says where the run stopped){kept}")
    if result.error is not None:
        raise PantocosimError(f"run stopped: {result.error} (results so far kept in "
                              f"{target}){kept}")
    if late.requested:
        raise Interrupted(f"interrupted (Ctrl-C) while the results were written: they are "
                          f"complete in {out}")
    return 0


def simulate(args, scenario, coupling: str, out: Path):
    """Set up and run the scenario (monolithic or co-simulation) writing into ``out``."""
    from pantocosim.master.run import prepare, run_monolithic

    plan = None
    if args.native_pantographs and coupling == "monolithic":
        from pantocosim.core.errors import ParameterError

        raise ParameterError("--native-pantographs", True, "runs the pantographs as native "
                             "FMUs in a co-simulation: give --coupling jacobi, gauss-seidel or "
                             "implicit")
    if coupling != "monolithic":
        from pantocosim.master.cosim import fmu_paths
        from pantocosim.master.scenario import require_port_contact

        require_port_contact(scenario, f"the {coupling} coupling")   # before the set-up
        plan = fmu_paths(scenario)   # the FMU files are checked before the long set-up
    with named_as_options(args):
        prep = prepare(scenario, force=args.force, max_dofs=args.max_dofs,
                       max_steps=args.max_steps)
    progress = None if not args.quiet else False
    if coupling == "monolithic":
        result = run_monolithic(prep, out, progress=progress, realtime=args.realtime)
    else:
        from pantocosim.master.cosim import run_cosim
        from pantocosim.master.native.models import native_pantographs

        with native_pantographs(prep, plan, args.native_pantographs) as (plan, notes):
            for note in notes:
                print(note)
            result = run_cosim(prep, out, scheme=coupling, accelerator=args.accelerator,
                               progress=progress, realtime=args.realtime, plan=plan)
    return dataclasses.replace(result, coupling=args.coupling)   # the name the user gave

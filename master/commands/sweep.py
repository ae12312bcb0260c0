"""``pantocosim sweep``: a campaign of runs over axes, executed on Dask."""

from __future__ import annotations

from pathlib import Path

from pantocosim.master.commands.run import add_cache_option


def add_parser(sub):
    p = sub.add_parser("sweep", help="run a campaign of cases (sweep file) on Dask",
                       description="Run every case of SWEEP (a sweep file or a preset of "
                       "master/sweeps) on Dask: a LocalCluster of worker processes on this "
                       "machine, or the scheduler at --scheduler. Writes one run folder per "
                       "case and the results table (results.csv, results.parquet) as cases "
                       "finish; cases already done in --out are skipped (resume).")
    p.add_argument("sweep", help="sweep file or preset")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="Dask scheduler address (tcp://host:8786) or scheduler file; "
                   "default: a LocalCluster on this machine")
    p.add_argument("--workers", type=int, default=None, metavar="N",
                   help="LocalCluster: number of worker processes (default: cores, at most "
                   "the cases); with --scheduler: wait for N workers before starting")
    p.add_argument("--out", default=None, help="output folder (default out/sweep-NAME)")
    p.add_argument("--retry-failed", action="store_true",
                   help="run the cases that failed in an earlier run again")
    p.add_argument("--list", action="store_true", help="list the cases and stop")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument("--wait", action="store_true",
                   help="if another sweep writes --out, wait for it to end (default: stop)")
    add_cache_option(p)
    return p


def run(args) -> int:
    from pantocosim.core.errors import ParameterError
    from pantocosim.master.campaign.execute import run_sweep
    from pantocosim.master.campaign.spec import load_sweep

    if args.workers is not None and args.workers < 1:
        raise ParameterError("--workers", args.workers, "must be >= 1")
    sweep = load_sweep(args.sweep)
    if args.list:
        for c in sweep.cases:
            print(f"{c.index + 1:4d}  {c.key}  {c.run['coupling']:12s} {c.label}")
        return 0
    out = Path(args.out) if args.out else Path("out") / f"sweep-{sweep.name}"
    from pantocosim.master.folder_lock import FolderLock

    with FolderLock(out, "--out", wait=args.wait):
        outcome = run_sweep(sweep, out, scheduler=args.scheduler, workers=args.workers,
                            retry_failed=args.retry_failed,
                            progress=False if args.quiet else None)
    t = outcome.stats
    warned = (f"{outcome.warned} warned (doubtful numbers: see the warnings column), "
              if outcome.warned else "")
    print(f"done: {outcome.ok} ok, {warned}{outcome.failed} failed, {outcome.lost} lost, "
          f"{outcome.skipped} from earlier runs; results in {out}/results.csv")
    if t:
        print(f"  wall {t['wall_time_s']:.1f} s for {t['cases_run']} cases of "
              f"{t['sum_case_wall_time_s']:.1f} s in all (ratio {t['wall_over_sum']:.2f}), "
              f"{t['cores_used']:.2f} cores busy on average; "
              f"overhead per case {t['overhead_per_case_s'] * 1e3:.0f} ms "
              f"({t['overhead_percent_of_case']:.2f} % of a case)")
    if outcome.interrupted:
        return 130
    return 1 if outcome.failed or outcome.lost or outcome.warned else 0

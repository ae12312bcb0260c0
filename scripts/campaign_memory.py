"""Worker memory over a campaign: the same short case N times as N distinct cases
(tiny changes of the Newton tolerance, so each has its own hash) on a LocalCluster of one
worker process; prints the worker's resident memory after each case.

    python scripts/campaign_memory.py --cases 12 [--profile] [--out DIR]

``--profile`` keeps Dask's statistical profiler of the worker on (``pantocosim sweep`` turns
it off on its LocalCluster: it keeps an hour of per-second profiles in the worker's memory).
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

SWEEP = """
name = "memory"
scenario = "en50318-300"
[set]
catenary_model = "linear"
spans = 5
analysis.window_supports = [2, 3]
[axes]
newton_rtol = [{values}]
"""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=12)
    ap.add_argument("--profile", action="store_true",
                    help="keep Dask's statistical profiler of the worker on")
    ap.add_argument("--out", default=None)
    args = ap.parse_args()
    import os

    from pantocosim.master.campaign.execute import run_sweep
    from pantocosim.master.campaign.spec import load_sweep

    out = Path(args.out or tempfile.mkdtemp(prefix="campaign-memory-"))
    out.mkdir(parents=True, exist_ok=True)
    f = out / "memory-sweep.toml"
    f.write_text(SWEEP.format(values=", ".join(f"{1e-4 * (1 - 1e-6 * i):.12g}"
                                               for i in range(args.cases))))
    from pantocosim.master.campaign.execute import PROFILE_ENV

    os.environ[PROFILE_ENV] = "true" if args.profile else "false"
    outcome = run_sweep(load_sweep(f), out / "run", workers=1, progress=False)
    for worker, rss in outcome.stats["worker_rss_mb"].items():
        print(f"{worker}: worker RSS after each case [MB]: {rss}")
        print(f"  growth from case 2 to case {len(rss)}: {rss[-1] - rss[1]:+.1f} MB")


if __name__ == "__main__":
    main()

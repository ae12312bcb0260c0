"""Tutorial: a campaign at four speeds on your line (two static uplifts), its EN 50367 assessment and report.

    python docs/tutorials/campaign.py [--out DIR] [--figures DIR] [--workers N]

Writes the line of the catenary tutorial, a scenario and a sweep file into DIR (default
``tutorial-campaign``), runs ``pantocosim sweep`` (a Dask LocalCluster of N workers, default
2) and ``pantocosim report``, and writes ``summary.json``; the report's figures go into
--figures when given.
"""

from __future__ import annotations

import argparse
import csv
import json
import shutil
from pathlib import Path

from own_catenary import LINE  # the line of the catenary tutorial (beside this script)
from tutorial_cli import FILES, pantocosim

SCENARIO = (FILES / "my-line-200.toml").read_text()

SWEEP = (FILES / "my-line-speeds.toml").read_text()


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("tutorial-campaign"))
    ap.add_argument("--figures", type=Path, default=None, help="also copy the figures here")
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args(argv)
    out = args.out.resolve()
    out.mkdir(parents=True, exist_ok=True)
    (out / "my-line.toml").write_text(LINE)
    (out / "my-line-200.toml").write_text(SCENARIO)
    (out / "my-line-speeds.toml").write_text(SWEEP)

    # --8<-- [start:run]
    pantocosim("sweep", "my-line-speeds.toml", "--workers", str(args.workers),
               "--out", "campaign", "--quiet", cwd=out)
    pantocosim("report", "campaign", cwd=out)
    # --8<-- [end:run]

    with open(out / "campaign" / "results.csv", newline="") as fh:
        rows = list(csv.DictReader(fh))
    keep = ("speed_kmh", "pantographs.0.options.static_force", "status", "mean_n", "std_n", "stat_max_n", "stat_min_n", "max_n",
            "min_n", "loss_of_contact_percent", "max_uplift_at_support_m",
            "mean_force_band", "sigma_ratio", "stat_min_positive", "no_loss_of_contact",
            "assessment")
    cases = sorted(({k: r.get(k) for k in keep} for r in rows),
                   key=lambda r: (-float(r["pantographs.0.options.static_force"]),
                                  float(r["speed_kmh"])))
    summary = {"cases": cases,
               "report_files": sorted(p.name for p in (out / "campaign" / "report").iterdir())}
    (out / "summary.json").write_text(json.dumps(summary, indent=2))
    print("F_0 [N] speed   F_m [N]  sigma [N]  F_m-3s [N]  F_max [N]  uplift [mm]  verdict")
    for c in cases:
        print(f"{float(c['pantographs.0.options.static_force']):7.0f} "
              f"{float(c['speed_kmh']):5.0f} {float(c['mean_n']):9.1f} {float(c['std_n']):10.1f}"
              f" {float(c['stat_min_n']):11.1f} {float(c['max_n']):10.1f}"
              f" {1e3 * float(c['max_uplift_at_support_m']):12.1f}  {c['assessment']}")
    if args.figures:
        args.figures.mkdir(parents=True, exist_ok=True)
        for name in ("force_vs_speed.png", "pass_fail.png"):
            shutil.copy(out / "campaign" / "report" / name, args.figures / f"campaign-{name}")
    return summary


if __name__ == "__main__":
    main()

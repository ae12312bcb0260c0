"""``pantocosim bench``: speed and memory figures of the solvers (ratios from one run)."""

from __future__ import annotations

import json
from pathlib import Path


def add_parser(sub):
    p = sub.add_parser("bench", help="benchmark the solvers and the co-simulation",
                       description="Run fixed cases (en50318-300 with 10 spans, a 40-span AVE "
                       "line) monolithic, explicit and implicit and print wall time, real-time "
                       "factor, time per step (mean, p99, max), iterations, peak memory and "
                       "the ratios floor_ratio, cosim_over_monolithic, implicit_over_explicit.")
    p.add_argument("--quick", action="store_true", help="shorter simulated times")
    p.add_argument("--json", action="store_true", help="print the results as JSON")
    p.add_argument("--out", help="also write the results as JSON to this file")
    p.add_argument("--case", action="append", metavar="NAME",
                   help="run only this case (repeatable; en50318-300, dsa380-ave-300-40span, "
                   "the fast-model cases, time-to-result: end to end against time stepping "
                   "with a cold and a warm set-up cache, fmu-start: the catenary FMU's "
                   "instantiate-to-first-step time in fmpy, cold and warm, native-loop: the "
                   "native C FMUs of export-native stepped from a C loop beside the Python "
                   "catenary FMU and the floor solve, native-dsa380: the native rigid "
                   "and flexible DSA-380 FMUs' doStep in that loop beside the Python FMUs'); skips the cold first run and the span "
                   "scaling")
    return p


def run(args) -> int:
    from pantocosim.master.benchmarks import bench
    from pantocosim.master.output_folder import check_writable_file, write_whole

    if args.out:
        check_writable_file("--out", args.out)       # before the benchmarks' minutes
    res = bench(quick=args.quick, printer=(lambda *a, **k: None) if args.json else print,
                cases=args.case)
    if args.json:
        print(json.dumps(res, indent=2))
    if args.out:
        text = json.dumps(res, indent=2) + "\n"
        write_whole("--out", args.out, lambda tmp: Path(tmp).write_text(text))
    return 0

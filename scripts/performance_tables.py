#!/usr/bin/env python3
"""The tables of docs/performance.md from the JSON file ``pantocosim bench --out`` wrote
(``docs/bench.json``): the en50318-300 figures of the nonlinear, linear and modal models and
the growth with the number of spans.

    python scripts/performance_tables.py [--bench docs/bench.json] [--page docs/performance.md]

It prints the tables and writes them between the page's markers; a figure the JSON does
not hold (the step percentiles of an older bench) is a dash.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from _tables import markdown_table, write_between

ROOT = Path(__file__).resolve().parents[1]
#: (row label of the first row, case) of the en50318-300 table
MODELS = (("nonlinear", "en50318-300"),
          ("linear", "en50318-300-linear"),
          ("modal, 100 Hz", "en50318-300-modal"))
#: coupling key of the bench JSON -> its label
COUPLINGS = {"monolithic": "monolithic", "explicit": "explicit (FMUs)",
             "implicit": "implicit (FMUs)"}
FIGURES_HEAD = ("catenary model (DOFs)", "coupling", "RTF", "p99 ms", "max ms", "floor_ratio",
                "peak memory")
SPANS_HEAD = ("spans", "DOFs", "wall per simulated second")


def _ms(value) -> str:
    """A time or ratio as the page gives it: two decimals below 10, one above; a dash when
    the bench did not record it."""
    if value is None:
        return "—"
    return f"{value:.2f}" if value < 10 else f"{value:.1f}"


def figures_table(bench: dict) -> str:
    """The en50318-300 table: one row per catenary model and coupling."""
    rows = []
    for label, case in MODELS:
        runs = bench["cases"][case]
        for i, (key, coupling) in enumerate(COUPLINGS.items()):
            r = runs[key]
            model = f"{label} ({r['catenary_dofs']})" if i == 0 else label.split(",")[0]
            rows.append((model, coupling, _ms(r["real_time_factor"]), _ms(r.get("p99_step_ms")),
                         _ms(r.get("max_step_ms")), f"{r['floor_ratio']:.1f}",
                         f"{r['peak_memory_mb']:.0f} MB"))
    return markdown_table(FIGURES_HEAD, rows)


def spans_table(bench: dict) -> str:
    """Wall time per simulated second against the number of spans (AVE line, monolithic)."""
    nonlinear = bench["scaling"]["nonlinear"]
    cost, dofs = nonlinear["cost_per_simulated_s"], nonlinear["catenary_dofs"]
    rows = [(spans, f"{dofs[spans]:,}", f"{cost[spans]:.1f} s")
            for spans in sorted(cost, key=int)]
    return markdown_table(SPANS_HEAD, rows)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--bench", type=Path, default=ROOT / "docs" / "bench.json")
    p.add_argument("--page", type=Path, default=ROOT / "docs" / "performance.md")
    args = p.parse_args(argv)
    bench = json.loads(args.bench.read_text())
    tables = {"figures": figures_table(bench), "spans": spans_table(bench)}
    for name, text in tables.items():
        print(text)
        write_between(args.page, (f"<!-- {name}:start -->", f"<!-- {name}:end -->"), text)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

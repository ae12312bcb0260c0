"""``pantocosim validate``: run a standard's reference case and compare the statistics with
its acceptance ranges (EN 50318)."""

from __future__ import annotations

import json
from pathlib import Path

from pantocosim.master.validation import standard_names


def add_parser(sub):
    p = sub.add_parser("validate", help="run a standard's reference case against its ranges",
                       description="Run the reference scenario of STANDARD at every speed "
                       "whose acceptance ranges the project holds (master/validation/"
                       "STANDARD.toml) with the reference models (nonlinear catenary, "
                       "monolithic coupling), print for each quantity the range, our value and "
                       "whether it lies inside, and write the table (validation.md, "
                       "validation.json) and each run's time series and summary to the output "
                       "folder. Exit status 0 when every quantity is inside, 1 otherwise.")
    p.add_argument("standard", nargs="?", default="en50318", metavar="STANDARD",
                   help=f"standard (known: {', '.join(standard_names())}; default en50318)")
    p.add_argument("--speed", type=float, nargs="+", metavar="KMH",
                   help="only these speeds [km/h] (default: all the file holds)")
    p.add_argument("--out", default=None, help="output folder (default out/validate-STANDARD)")
    p.add_argument("--json", action="store_true", help="print the JSON report")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    return p


def run_speed(ranges, out: Path, quiet: bool) -> dict:
    """Run one speed's scenario (nonlinear catenary, monolithic); its summary."""
    from pantocosim.core.errors import PantocosimError
    from pantocosim.master.commands.run import with_model
    from pantocosim.master.run import finish, prepare, run_monolithic
    from pantocosim.master.scenario import load_scenario

    scenario = with_model(load_scenario(ranges.scenario), "nonlinear")
    folder = out / scenario.name
    result = run_monolithic(prepare(scenario), folder, progress=False if quiet else None)
    summary = finish(result, folder, plots=False)
    if result.error is not None:
        raise PantocosimError(f"{scenario.name}: run stopped: {result.error} (results so far "
                              f"kept in {folder})")
    return summary


def report(std, outcomes: list) -> dict:
    """The JSON report; ``outcomes``: (ranges, run summary, compared rows) per speed."""
    out = {"standard": std.standard, "source": std.source, "speeds": []}
    for ranges, summary, rows in outcomes:
        out["speeds"].append({
            "speed_kmh": ranges.speed_kmh, "scenario": ranges.scenario,
            "catenary_model": "nonlinear", "coupling": "monolithic",
            "analysis_window_m": summary["analysis_window_m"],
            "all_inside": all(r.inside for r in rows),
            "rows": [{"quantity": r.key, "label": r.quantity.label, "unit": r.quantity.unit,
                      "low": r.low, "high": r.high, "value": r.value, "inside": r.inside}
                     for r in rows]})
    return out


def markdown(std, outcomes: list) -> str:
    from pantocosim.master.validation import markdown_table

    lines = [f"# {std.standard} validation", "", f"Ranges: {std.source}.", "",
             "Reference models: nonlinear catenary, monolithic coupling; statistics of the "
             "0-20 Hz filtered contact force over whole spans (EN 50317).", ""]
    for ranges, summary, rows in outcomes:
        w = summary["analysis_window_m"]
        lines += [f"## {ranges.speed_kmh:g} km/h (scenario {ranges.scenario}, window "
                  f"{w[0]:g}-{w[1]:g} m)", ""]
        lines += markdown_table(rows) + [""]
    return "\n".join(lines)


def print_table(ranges, rows) -> None:
    print(f"  {ranges.speed_kmh:g} km/h (scenario {ranges.scenario}):")
    print(f"    {'quantity':40s} {'range':>16s} {'ours':>9s}  inside")
    for r in rows:
        rng = f"{r.low:g} - {r.high:g} {r.quantity.unit}"
        print(f"    {r.quantity.label:40s} {rng:>16s} {r.value:9.2f}  "
              f"{'yes' if r.inside else 'NO'}")
    n_in = sum(r.inside for r in rows)
    print(f"    {n_in} of {len(rows)} inside")


def run(args) -> int:
    from pantocosim.core.errors import ParameterError, PantocosimError
    from pantocosim.master.validation import compare, load_standard

    std = load_standard(args.standard)
    speeds = list(std.speeds) if not args.speed else [std.at(v) for v in dict.fromkeys(args.speed)]
    out = Path(args.out) if args.out else Path("out") / f"validate-{std.name}"
    if out.exists() and not out.is_dir():
        raise ParameterError("--out", str(out), "exists and is not a folder")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ParameterError("--out", str(out), f"cannot create the folder: {exc}") from None
    outcomes = []
    for ranges in speeds:
        summary = run_speed(ranges, out, args.quiet)
        outcomes.append((ranges, summary, compare(ranges, summary["statistics"])))
    data = report(std, outcomes)
    try:
        (out / "validation.json").write_text(json.dumps(data, indent=2) + "\n")
        (out / "validation.md").write_text(markdown(std, outcomes))
    except OSError as exc:
        raise PantocosimError(f"cannot write the validation table to {out}: {exc}") from None
    if args.json:
        print(json.dumps(data, indent=2))
    else:
        print(f"{std.standard} ({std.description})")
        print(f"  ranges: {std.source}")
        for ranges, _, rows in outcomes:
            print_table(ranges, rows)
        print(f"  table written to {out / 'validation.md'} and validation.json")
    return 0 if all(s["all_inside"] for s in data["speeds"]) else 1

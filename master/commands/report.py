"""``pantocosim report``: plots and a Markdown summary of a sweep's results."""

from __future__ import annotations


def add_parser(sub):
    p = sub.add_parser("report", help="plots and summary of a sweep folder",
                       description="Read the results of `pantocosim sweep` in DIR, assess "
                       "every row against the criteria (DIR/criteria.toml or --criteria) and "
                       "write DIR/report/: force against speed with the criteria bands, sigma "
                       "against each swept parameter, the pass/fail matrix, report.md.")
    p.add_argument("dir", help="output folder of a sweep")
    p.add_argument("--criteria", default=None,
                   help="criteria preset or TOML file (default: the sweep's copy)")
    p.add_argument("--out", default=None, help="report folder (default DIR/report)")
    return p


def run(args) -> int:
    from pantocosim.master.campaign.report import make_report

    md = make_report(args.dir, args.criteria, args.out)
    print(f"report: {md}")
    return 0

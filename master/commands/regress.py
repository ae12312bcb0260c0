"""``pantocosim regress``: fmpy-scripted regression runs of the FMUs against stored references."""

from __future__ import annotations


def add_parser(sub):
    p = sub.add_parser("regress", help="run the FMU regression cases against references",
                       description="Run a fixed set of cases through the FMUs (fmpy) and "
                       "compare statistics and time series with the references stored in "
                       "master/regression/ (their history.toml says when and why each changed).")
    p.add_argument("--update", action="store_true", help="rewrite the references")
    p.add_argument("--reason", default=None, help="why the references change (with --update)")
    p.add_argument("--only", nargs="*", help="run only these cases")
    return p


def run(args) -> int:
    from pantocosim.master.regress import run_regression

    ok = run_regression(update=args.update, reason=args.reason, only=args.only)
    return 0 if ok else 1

"""``pantocosim report DIR``: plots and a Markdown summary of a sweep folder.

Reads the results table (``results.parquet``, else ``results.csv``), the case list
(``cases.json``) and the criteria (``criteria.toml``, the copy the sweep made, or another
file), assesses every row again (so an edited criteria file needs no re-run) and writes
``report/``: contact force against speed per pantograph with the criteria bands, sigma against
each swept parameter, the pass/fail matrix, and ``report.md``.
"""

from __future__ import annotations

import json
import math
from collections import defaultdict
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from pantocosim.core.errors import ParameterError  # noqa: E402
from pantocosim.master.campaign.assessment import (Band, Criteria, Max, Min,  # noqa: E402
                                                   RatioMax, assess, load_criteria)
from pantocosim.master.campaign.table import SHOWN, read_table  # noqa: E402

#: rows of the pass/fail matrix drawn at most (the Markdown table has them all)
MATRIX_ROWS = 120
COLORS = {True: "#4caf50", False: "#e53935", None: "#d0d0d0", "run failed": "#616161"}


def make_report(folder: Path, criteria_file: str | None = None, out: Path | None = None) -> Path:
    folder = Path(folder)
    rows = read_table(folder)
    if rows is None:
        raise ParameterError("DIR", str(folder), "holds no results.parquet or results.csv of "
                             "a sweep")
    crit_src = criteria_file or (folder / "criteria.toml")
    criteria = load_criteria(str(crit_src))
    cases = _cases(folder)
    axes = _axes(cases)
    for r in rows:
        stats = r if r.get("status") == "ok" and r.get("mean_n") is not None else None
        r.update(assess(criteria, stats, float(r["speed_kmh"])))
    rows.sort(key=lambda r: (r["index"], r.get("pantograph") or 0))
    out = Path(out) if out else folder / "report"
    out.mkdir(parents=True, exist_ok=True)
    figures = [plot_force_vs_speed(out / "force_vs_speed.png", rows, criteria, axes)]
    for axis in axes:
        figures.append(plot_sigma_vs(out / f"sigma_vs_{_slug(axis)}.png", rows, axis, axes,
                                     criteria))
    figures.append(plot_pass_fail(out / "pass_fail.png", rows, criteria, axes))
    md = out / "report.md"
    md.write_text(summary_markdown(folder, rows, cases, criteria, axes,
                                   [f for f in figures if f is not None]))
    return md


# ------------------------------------------------------------------------------ inputs
def _cases(folder: Path) -> list:
    try:
        return json.loads((folder / "cases.json").read_text())
    except (OSError, ValueError):
        return []


def _axes(cases: list) -> list:
    names = []
    for c in cases:
        for k in c.get("values", {}):
            if k not in names:
                names.append(k)
    return names


def _column(axis: str) -> str:
    """The table column that holds an axis."""
    return {"pantograph": "pantograph_model"}.get(axis, axis)


def _slug(name: str) -> str:
    return "".join(ch if ch.isalnum() or ch in "-_" else "_" for ch in name)


def _ok(rows):
    return [r for r in rows if r.get("status") == "ok" and r.get("mean_n") is not None]


def _others(r, axes, skip) -> tuple:
    return tuple((a, r.get(_column(a))) for a in axes if a not in skip)


def _label(key) -> str:
    return ", ".join(f"{a} = {_fmt(v)}" for a, v in key)


def _fmt(v) -> str:
    if isinstance(v, float):
        return f"{v:g}"
    return "" if v is None else str(v)


# ------------------------------------------------------------------------------ plots
def plot_force_vs_speed(path: Path, rows, criteria: Criteria, axes) -> Path | None:
    """Per pantograph model: F_m, F_m +/- 3 sigma and the actual extremes against speed, one
    line per combination of the other axes (and pantograph position), criteria shaded."""
    ok = _ok(rows)
    if not ok:
        return None
    models = sorted({r["pantograph_model"] for r in ok})
    ncols = min(2, len(models))
    nrows = math.ceil(len(models) / ncols)
    fig, axs = plt.subplots(nrows, ncols, figsize=(max(7.0, 6.0 * ncols), 0.6 + 4.4 * nrows),
                            squeeze=False, sharey=True)
    for ax in axs.flat[len(models):]:
        ax.set_visible(False)
    speeds = np.array(sorted({float(r["speed_kmh"]) for r in ok}))
    v = np.linspace(speeds.min() * 0.95, speeds.max() * 1.05, 100) if len(speeds) else speeds
    for k, (ax, model) in enumerate(zip(axs.flat, models)):
        _criteria_bands(ax, criteria, v)
        groups = defaultdict(list)
        for r in ok:
            if r["pantograph_model"] == model:
                key = _others(r, axes, {"speed_kmh", "pantograph"})
                if len({x["pantograph"] for x in ok}) > 1:
                    key += (("pantograph", r["pantograph"]),)
                groups[key].append(r)
        for i, (key, rs) in enumerate(sorted(groups.items(), key=lambda kv: str(kv[0]))):
            rs.sort(key=lambda r: r["speed_kmh"])
            x = [r["speed_kmh"] for r in rs]
            color = f"C{i % 10}"
            label = _label(key) or "F_m"
            ax.plot(x, [r["mean_n"] for r in rs], "o-", color=color, label=label)
            ax.fill_between(x, [r["stat_min_n"] for r in rs], [r["stat_max_n"] for r in rs],
                            color=color, alpha=0.15)
            ax.plot(x, [r["stat_max_n"] for r in rs], "--", color=color, lw=0.8)
            ax.plot(x, [r["stat_min_n"] for r in rs], "--", color=color, lw=0.8)
            ax.plot(x, [r["max_n"] for r in rs], "^", color=color, ms=5, mfc="none")
            ax.plot(x, [r["min_n"] for r in rs], "v", color=color, ms=5, mfc="none")
        ax.plot([], [], "k--", lw=0.8, label="F_m +/- 3 sigma")
        ax.plot([], [], "k^", mfc="none", label="actual max")
        ax.plot([], [], "kv", mfc="none", label="actual min")
        ax.set_title(model)
        ax.set_xlabel("speed [km/h]")
        ax.grid(alpha=0.3)
        if k == 0 or len(groups) > 1:
            ax.legend(fontsize=7, loc="upper left")
    for row in axs:
        row[0].set_ylabel("contact force [N]")
    fig.suptitle("F_m (o), F_m +/- 3 sigma and actual extremes against speed")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def _criteria_bands(ax, criteria: Criteria, v) -> None:
    for c in criteria.checks:
        if isinstance(c, Band) and c.quantity == "mean_n":
            ax.fill_between(v, c.lower(v), c.upper(v), color="#a5d6a7", alpha=0.35,
                            label=f"{c.title}")
        elif isinstance(c, (Min, Max)) and c.quantity in ("stat_min_n", "min_n", "max_n",
                                                           "stat_max_n", "mean_n"):
            ax.axhline(c.limit, color="#c62828", lw=1.0, ls=":", label=c.title)


def plot_sigma_vs(path: Path, rows, axis: str, axes, criteria: Criteria) -> Path | None:
    """Standard deviation against one swept parameter, one series per combination of the
    others; the ratio criteria (sigma <= factor F_m) as crosses at each point's limit."""
    ok = _ok(rows)
    if not ok:
        return None
    col = _column(axis)
    values = [r.get(col) for r in ok]
    numeric = all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in values)
    cats = sorted({str(x) for x in values})
    def xpos(x):
        return float(x) if numeric else cats.index(str(x))
    skip = {axis}
    groups = defaultdict(list)
    multi = len({r["pantograph"] for r in ok}) > 1
    for r in ok:
        key = _others(r, axes, skip)
        if multi:
            key += (("pantograph", r["pantograph"]),)
        groups[key].append(r)
    fig, ax = plt.subplots(figsize=(7.5, 4.6))
    legend = len(groups) <= 12
    ratios = [c for c in criteria.checks if isinstance(c, RatioMax) and c.quantity == "std_n"]
    for i, (key, rs) in enumerate(sorted(groups.items(), key=lambda kv: str(kv[0]))):
        rs.sort(key=lambda r: xpos(r.get(col)))
        x = [xpos(r.get(col)) for r in rs]
        ax.plot(x, [r["std_n"] for r in rs], "o-" if legend else "o", color=f"C{i % 10}",
                label=_label(key) if legend else None, ms=5)
        for c in ratios:
            ax.plot(x, [c.factor * r[c.reference] for r in rs], "x", color=f"C{i % 10}",
                    ms=6, alpha=0.7)
    if ratios:
        ax.plot([], [], "x", color="grey", label=f"limit: {ratios[0].title}")
    if not numeric:
        ax.set_xticks(range(len(cats)), cats, rotation=20, ha="right", fontsize=8)
    ax.set_xlabel(axis)
    ax.set_ylabel("standard deviation sigma [N]")
    ax.set_title(f"Contact-force standard deviation against {axis}")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def plot_pass_fail(path: Path, rows, criteria: Criteria, axes) -> Path | None:
    """Cases (rows) against criteria (columns): green pass, red fail, light grey not
    applicable, dark grey run failed."""
    if not rows:
        return None
    shown = rows[:MATRIX_ROWS]
    names = [c.name for c in criteria.checks]
    n, m = len(shown), len(names) + 1
    fig, ax = plt.subplots(figsize=(2.2 + 1.3 * m, 1.2 + 0.28 * n))
    for i, r in enumerate(shown):
        failed_run = r.get("status") != "ok"
        for j, name in enumerate(names + ["assessment"]):
            value = r.get(name)
            if failed_run:
                color, text = COLORS["run failed"], r.get("status", "")
            elif name == "assessment":
                color = COLORS[{"pass": True, "fail": False}.get(value)]
                text = value or ""
            else:
                color, text = COLORS[value], {True: "pass", False: "fail"}.get(value, "n/a")
            ax.add_patch(plt.Rectangle((j, i), 1, 1, color=color, ec="white"))
            ax.text(j + 0.5, i + 0.5, text, ha="center", va="center", fontsize=7,
                    color="white" if failed_run else "black")
    ax.set_xlim(0, m)
    ax.set_ylim(n, 0)
    ax.set_xticks(np.arange(m) + 0.5, names + ["overall"], rotation=25, ha="right",
                  fontsize=8)
    labels = [f"{r['index'] + 1}: {_case_label(r, axes)}" for r in shown]
    ax.set_yticks(np.arange(n) + 0.5, labels, fontsize=7)
    ax.tick_params(length=0)
    title = "EN 50367 / TSI assessment"
    if len(rows) > MATRIX_ROWS:
        title += f" (first {MATRIX_ROWS} of {len(rows)} rows; all in report.md)"
    ax.set_title(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def _case_label(r, axes) -> str:
    parts = [f"{a.split('.')[-1]} {_fmt(r.get(_column(a)))}" for a in axes]
    if "pantograph" not in axes:
        parts.append(str(r.get("pantograph_model")))
    if r.get("pantograph") and r.get("pantograph") != 1:
        parts.append(f"pantograph {r['pantograph']}")
    return ", ".join(parts)


# ------------------------------------------------------------------------------ summary
def summary_markdown(folder: Path, rows, cases, criteria: Criteria, axes, figures) -> str:
    try:
        sweep = json.loads((folder / "sweep.json").read_text())
    except (OSError, ValueError):
        sweep = {}
    done = {r["case"] for r in rows}
    status = defaultdict(set)
    for r in rows:
        status[r["status"]].add(r["case"])
    missing = [c for c in cases if c["case"] not in done]
    lines = [f"# Campaign {sweep.get('name', folder.name)}", ""]
    if sweep.get("source"):
        lines.append(f"Sweep file: `{sweep['source']}`; results: `{folder}`.")
    warned = (f"{len(status['warned'])} warned (statistics doubtful, not assessed), "
              if status["warned"] else "")
    lines += ["", f"Cases: {len(cases) or len(done)} in the sweep, {len(status['ok'])} ok, "
              f"{warned}{len(status['failed'])} failed, {len(status['lost'])} lost, "
              f"{len(missing)} not run yet. Rows assessed against **{criteria.name}** "
              f"(`{criteria.source}`).", ""]
    ok_rows = _ok(rows)
    verdicts = defaultdict(int)
    for r in ok_rows:
        verdicts[r["assessment"]] += 1
    lines += [f"Assessment of the {len(ok_rows)} pantograph passages simulated: "
              f"{verdicts['pass']} pass every applicable check, {verdicts['fail']} fail one "
              "or more.", ""]
    lines += ["## Criteria", "", "| criterion | check | source | verified |", "|---|---|---|---|"]
    for c in criteria.items:
        lines.append(f"| {c.name} | {c.title} | {c.source} | {'yes' if c.verified else 'no'} |")
    lines += ["", "## Results", ""]
    checks = [c.name for c in criteria.checks]
    reports = [c.name for c in criteria.items if not c.checks]
    head = (["case"] + [a for a in axes if a not in SHOWN]
            + ["speed [km/h]", "pantograph", "F_m [N]", "sigma [N]", "F_m-3s [N]", "max [N]", "min [N]",
               "loss [%]"] + reports + checks + ["overall"])
    head = list(dict.fromkeys(head))
    lines += ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        cells = [str(r["index"] + 1)]
        cells += [_fmt(r.get(_column(a))) for a in axes if a not in SHOWN]
        cells.append(_fmt(r["speed_kmh"]))
        cells.append(f"{r.get('pantograph')}: {r.get('pantograph_model')}")
        if r.get("status") in ("ok", "warned") and r.get("mean_n") is not None:
            mark = "*" if r.get("status") == "warned" else ""   # doubtful: see below
            cells += [f"{r[k]:.1f}{mark}" for k in ("mean_n", "std_n", "stat_min_n", "max_n",
                                                    "min_n")]
            cells.append(f"{r['loss_of_contact_percent']:.2f}{mark}")
            cells += [_num(r.get(k)) for k in reports]
            cells += [{True: "pass", False: "**fail**"}.get(r.get(k), "n/a") for k in checks]
            cells.append("**warned**" if mark else
                         "pass" if r["assessment"] == "pass" else "**fail**")
        else:
            cells += [r.get("status", "")] + [""] * (len(head) - len(cells) - 1)
        lines.append("| " + " | ".join(cells[:len(head)]) + " |")
    warned = [r for r in rows if r.get("status") == "warned"]
    if warned:
        lines += ["", "## Warned cases", "", "These cases ran, but their numbers are doubtful "
                  "(marked * above, not assessed):", ""]
        seen = set()
        for r in warned:
            if r["case"] not in seen:
                seen.add(r["case"])
                lines.append(f"- case {r['index'] + 1} (`{r['case']}`): {r.get('warnings')}")
    failed = [r for r in rows if r.get("status") not in ("ok", "warned")]
    if failed:
        lines += ["", "## Failed cases", ""]
        seen = set()
        for r in failed:
            if r["case"] not in seen:
                seen.add(r["case"])
                lines.append(f"- case {r['index'] + 1} (`{r['case']}`): {r.get('error')}")
    t = sweep.get("timing") or {}
    if t:
        lines += ["", "## Timing (last run of the sweep)", "",
                  f"{t['cases_run']} cases in {t['wall_time_s']:.1f} s wall; their own wall "
                  f"times add up to {t['sum_case_wall_time_s']:.1f} s (ratio "
                  f"{t['wall_over_sum']:.2f}); dispatch overhead "
                  f"{1e3 * t['overhead_per_case_s']:.0f} ms a case "
                  f"({t['overhead_percent_of_case']:.2f} %)."]
    lines += ["", "## Figures", ""]
    lines += [f"![{f.stem}]({f.name})" for f in figures]
    return "\n".join(lines) + "\n"


def _num(x) -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "n/a"
    return f"{x:.4g}"

#!/usr/bin/env python3
"""The readings of the EN 50318 reference model, each run whole at 250 and 300 km/h.

A reading is the validation scenario of its speed with the dotted-path changes listed in
``master/validation/en50318-readings/readings.toml`` (as a sweep's ``[set]``; the catenary
fields on a copy of the preset catenary). Each run uses the reference models (nonlinear
catenary, monolithic coupling), as ``pantocosim validate`` does, one at a time; its inputs are
written to ``--out``/inputs/NAME-SPEED (``scenario.toml``, ``catenary.toml``: ``pantocosim
run`` takes them) and its time series cached in ``--out``/runs (a run is redone only when its
files change). Readings with ``of`` re-analyse another reading's runs with another window or
filter. Usage::

    nice -n 10 .venv/bin/python scripts/en50318_readings.py [--only NAME ...]
        [--out DIR] [--docs PAGE] [--spectrum NAME ...] [--quick]

``--docs`` writes the table between the page's ``<!-- readings:start/end -->`` markers and,
with ``--spectrum``, the spectrum table between ``<!-- spectrum:start/end -->`` and the figure
``figures/en50318-spectrum.png`` beside the page. ``--quick`` runs each reading on 4 spans
with the window x = 60-120 m (a check of the script, not of the standard).
"""

from __future__ import annotations

import argparse
import copy
import dataclasses
import hashlib
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

from _tables import markdown_table, write_between

ROOT = Path(__file__).resolve().parents[1]
READINGS = ROOT / "master" / "validation" / "en50318-readings"
SPEEDS = (250, 300)
CUTOFF_HZ = 20.0
#: frequency bands [Hz] of the sigma decomposition: span passing and its first harmonics;
#: the pantograph's own modes; dropper passing and the 5e4 N/m contact mode; the rest
BANDS = ((0.0, 3.0), (3.0, 10.0), (10.0, 15.0), (15.0, 20.0))
#: the quantities of the table: (column, ContactStatistics field, scale, range key)
COLUMNS = [("mean", "mean_n", 1.0, "mean"), ("sigma", "std_n", 1.0, "std"),
           ("stat max", "stat_max_n", 1.0, "stat_max"), ("stat min", "stat_min_n", 1.0,
                                                          "stat_min"),
           ("max", "max_n", 1.0, "max"), ("min", "min_n", 1.0, "min"),
           ("uplift [mm]", "max_uplift_at_support_m", 1000.0, "uplift"),
           ("loss [%]", "loss_of_contact_percent", 1.0, "loss_of_contact")]


def load_readings() -> list[dict]:
    """The readings of ``readings.toml``; a ``from`` or ``of`` must name a reading above."""
    from pantocosim.core.errors import ParameterError
    from pantocosim.core.params import load_toml

    path = READINGS / "readings.toml"
    readings, seen = load_toml(path)["readings"], set()
    for i, r in enumerate(readings):
        for key in ("from", "of"):
            if key in r and r[key] not in seen:
                raise ParameterError(f"readings.{i}.{key}", r[key],
                                     "must name a reading listed above it", str(path))
        seen.add(r["name"])
    return readings


def changes(reading: dict, by_name: dict) -> list[tuple[str, object]]:
    """The reading's [(dotted path, value)]: those of the reading it starts ``from``, then
    its own ``set`` (a table with a ``type`` is one value: it replaces the whole table)."""
    first = changes(by_name[reading["from"]], by_name) if "from" in reading else []
    return first + _leaves(reading.get("set", {}))


def _leaves(table: dict, prefix: str = "") -> list[tuple[str, object]]:
    out = []
    for key, value in table.items():
        if isinstance(value, dict) and "type" not in value:
            out += _leaves(value, f"{prefix}{key}.")
        else:
            out.append((f"{prefix}{key}", value))
    return out


def scenario_file(reading: dict, by_name: dict, speed: int, out: Path) -> Path:
    """Write the reading's inputs at ``speed`` (the validation scenario with its changes; a
    copy of the catenary when a catenary field changes) to ``out``/inputs; their scenario."""
    import tomli_w

    from pantocosim.catenary.definition import load_catenary
    from pantocosim.core.params import load_toml
    from pantocosim.master.campaign.axes import CaseInputs, make_axis
    from pantocosim.master.scenario import scenario_path

    case = CaseInputs(scenario=load_toml(scenario_path(f"en50318-{speed}")), run={})
    case.scenario.update(name=f"en50318-{reading['name']}-{speed}",
                         description=f"EN 50318 reading {reading['name']} at {speed} km/h")
    for path, value in changes(reading, by_name):
        if path.startswith("catenary.") and case.catenary is None:
            case.catenary = copy.deepcopy(load_catenary(case.scenario["catenary"]).raw)
        make_axis(path).apply(case, copy.deepcopy(value))
    folder = out / "inputs" / f"{reading['name']}-{speed}"
    folder.mkdir(parents=True, exist_ok=True)
    if case.catenary is not None:
        case.catenary["name"] = f"en50318-{reading['name']}"
        (folder / "catenary.toml").write_text(tomli_w.dumps(case.catenary))
        case.scenario["catenary"] = str((folder / "catenary.toml").resolve())
    (folder / "scenario.toml").write_text(tomli_w.dumps(case.scenario))
    return folder / "scenario.toml"


# ---------------------------------------------------------------------------- filters
def lowpass(kind: str, force: np.ndarray, dt: float) -> np.ndarray:
    """The 0-20 Hz contact force: ``zero-phase`` (every run's, master/results/statistics.py),
    ``causal`` (the same Butterworth once, forward) or ``ideal`` (FFT band)."""
    from scipy import signal

    from pantocosim.master.results.statistics import lowpass as zero_phase

    if kind == "zero-phase":
        return zero_phase(force, dt, CUTOFF_HZ)
    if kind == "causal":
        sos = signal.butter(4, CUTOFF_HZ * 2.0 * dt, btype="low", output="sos")
        return signal.sosfilt(sos, force, zi=signal.sosfilt_zi(sos) * force[0])[0]
    if kind == "ideal":
        spec = np.fft.rfft(force)
        spec[np.fft.rfftfreq(len(force), dt) > CUTOFF_HZ] = 0.0
        return np.fft.irfft(spec, len(force))
    raise ValueError(f"unknown filter {kind!r}")


def statistics(run: dict, window: tuple[float, float], kind: str = "zero-phase") -> dict:
    """EN 50317 quantities of a cached run over ``window`` with the filter ``kind`` (with
    ``zero-phase``: those of master/results/statistics.py)."""
    from pantocosim.master.results.statistics import window_mask

    t, x, F = run["time"], run["x"], run["force"]
    f = lowpass(kind, F, float(np.median(np.diff(t))))
    mask = window_mask(x, *window)
    fw = f[mask]
    mean, std = float(fw.mean()), float(fw.std())
    sx = run["support_x"]
    inside = (sx >= window[0]) & (sx <= window[1])
    uplift = float(np.max(run["uplift"][mask][:, inside])) if inside.any() else float("nan")
    return {"mean_n": mean, "std_n": std, "stat_max_n": mean + 3 * std,
            "stat_min_n": mean - 3 * std, "max_n": float(fw.max()), "min_n": float(fw.min()),
            "loss_of_contact_percent": 100.0 * float(np.mean(F[mask] <= 0.0)),
            "step_loss_percent": step_loss(run, F[mask] <= 0.0),
            "max_uplift_at_support_m": uplift}


def step_loss(run: dict, off: np.ndarray) -> float | None:
    """The part [%] of a rigid contact's loss of contact (``off``: the window's samples at
    zero force) in separations of at most UNRESOLVED_SEPARATION_STEPS steps, which the step
    does not resolve (master/stability.py); None for a compliant law."""
    from pantocosim.interaction.contact_laws import make_contact
    from pantocosim.master.stability import UNRESOLVED_SEPARATION_STEPS, run_lengths

    if make_contact(str(run["law"]), float(run["stiffness"]), 0.0).compliance != 0.0:
        return None
    runs = run_lengths(off)
    return 100.0 * float(runs[runs <= UNRESOLVED_SEPARATION_STEPS].sum()) / max(off.size, 1)


# ---------------------------------------------------------------------------- runs
def run_files(sc) -> list[Path]:
    """The files a scenario's run depends on (scenario, catenary, pantograph)."""
    from pantocosim.catenary.definition import DATA_DIR as CAT
    from pantocosim.pantograph.presets import preset_path

    files = [Path(sc.source)]
    files.append(Path(sc.catenary) if sc.catenary.endswith(".toml")
                 else CAT / f"{sc.catenary}.toml")
    return files + [preset_path(p.model) for p in sc.pantographs]


def quick(sc):
    """The short version of a reading's scenario (``--quick``)."""
    return dataclasses.replace(sc, spans=4, window_supports=None, window_m=(60.0, 120.0))


def cached_run(path: Path, out: Path, short: bool) -> dict:
    """The run of the scenario file ``path`` (reference models), from the cache when its
    files are unchanged."""
    from pantocosim.master.commands.run import with_model
    from pantocosim.master.run import prepare, run_monolithic
    from pantocosim.master.scenario import load_scenario
    from pantocosim.master.stability import contact_mass

    sc = with_model(load_scenario(path), "nonlinear")
    if short:
        sc = quick(sc)
    digest = hashlib.sha256(b"".join(f.read_bytes() for f in run_files(sc))
                            + (b"quick" if short else b"")).hexdigest()[:16]
    cache = out / "runs" / f"{path.stem}-{digest}.npz"
    if cache.exists():
        with np.load(cache, allow_pickle=False) as z:
            return {k: z[k] for k in z.files} | json.loads(str(z["meta"]))
    t0 = time.perf_counter()
    prep = prepare(sc)
    res = run_monolithic(prep, None, progress=False)
    c = res.columns
    run = {"time": c["time"], "x": c["x_1"], "force": c["contact_force_1"],
           "uplift": np.column_stack([c[f"support_uplift_{j}"]
                                      for j in range(len(prep.support_x))]),
           "support_x": prep.support_x, "dropper_x": prep.dropper_x,
           "window": np.array(prep.window_m)}
    meta = {"error": None if res.error is None else str(res.error),
            "wall_s": time.perf_counter() - t0, "dt": sc.dt, "alpha": sc.alpha,
            "law": sc.contact_law, "stiffness": sc.contact_stiffness,
            "head_mass": contact_mass(prep.pantographs[0], prep.q_pan0[0],
                                      float(prep.pantographs[0].options.mean_uplift))}
    cache.parent.mkdir(parents=True, exist_ok=True)
    np.savez(cache, meta=json.dumps(meta), **run)
    return run | meta


def reading_rows(reading: dict, by_name: dict, out: Path, short: bool) -> list[dict]:
    """One row per speed: the reading's statistics (or its run's error)."""
    base = by_name[reading["of"]] if "of" in reading else reading
    rows = []
    for speed in SPEEDS:
        run = cached_run(scenario_file(base, by_name, speed, out), out, short)
        window = tuple(run["window"])
        if "window_supports" in reading and not short:
            i, j = reading["window_supports"]
            window = (float(run["support_x"][i]), float(run["support_x"][j]))
        row = {"reading": reading["name"], "speed": speed, "wall_s": run["wall_s"]}
        if run["error"] is not None:
            row["error"] = run["error"]
        else:
            row["statistics"] = statistics(run, window, reading.get("filter", "zero-phase"))
        rows.append(row)
    return rows


# ---------------------------------------------------------------------------- tables
def table(readings: list[dict], rows: list[dict]) -> str:
    from pantocosim.master.stability import UNRESOLVED_SEPARATION_STEPS
    from pantocosim.master.validation import load_standard

    std = load_standard("en50318")
    info = {r["name"]: r for r in readings}
    head = ["reading", "km/h", *(c[0] for c in COLUMNS), "inside", "assumed", "calibrated"]
    cells = []
    for row in rows:
        r = info[row["reading"]]
        first = [f"{r['group']}: {r['name']}", row["speed"]]
        tail = [", ".join(r["assumed"]) or "-", ", ".join(r["calibrated"]) or "none"]
        if "error" in row:
            cells.append(first + [f"run stopped: {row['error']}"] + [""] * 8 + tail)
            continue
        ranges = std.at(float(row["speed"])).ranges
        vals, inside = [], 0
        for _, field, scale, key in COLUMNS:
            v = scale * row["statistics"][field]
            lo, hi = ranges[key]
            ok = lo <= round(v, 1) <= hi
            inside += ok
            vals.append(f"{v:.1f}" if ok else f"**{v:.1f}**")
        step = row["statistics"].get("step_loss_percent")
        if step is not None:
            vals[-1] += f" ({step:.1f})"
        cells.append(first + vals + [f"{inside}/8"] + tail)
    return ("Generated by `scripts/en50318_readings.py`; **bold**: outside the EN 50318 "
            "range; loss [%] of the raw force, in parentheses for the constraint contact the "
            f"part in separations of at most {UNRESOLVED_SEPARATION_STEPS} steps, which the "
            "step does not resolve (\"Loss of contact and the step\" below).\n\n"
            + markdown_table(head, cells))


def band_sigma(force: np.ndarray, dt: float) -> list[float]:
    """The standard deviation of ``force`` carried by each of :data:`BANDS` (Parseval on
    the samples, mean removed: the squares add up to the variance)."""
    x = force - force.mean()
    X = np.fft.rfft(x)
    f = np.fft.rfftfreq(len(x), dt)
    w = np.full(len(X), 2.0)
    w[0] = 1.0
    if len(x) % 2 == 0:
        w[-1] = 1.0
    p = w * np.abs(X) ** 2 / len(x) ** 2
    return [float(np.sqrt(p[(f >= lo) & (f < hi if hi < BANDS[-1][1] else f <= hi)].sum()))
            for lo, hi in BANDS]


def spectrum(runs: dict, speed: int, page: Path | None) -> str:
    """The amplitude spectrum of the filtered contact force in the window for each named
    run, with the span, dropper and contact-mode frequencies; the sigma each frequency band
    carries and the peak after each support. Returns the two tables."""
    from pantocosim.master.results.statistics import force_spectrum, window_mask

    v = speed / 3.6
    heads, cells = ["reading", "support x [m]", "peak [N]", "at [m] after the support"], []
    bhead = ["reading", "sigma [N]", *(f"{lo:g}-{hi:g} Hz" for lo, hi in BANDS)]
    bcells = []
    fig = None
    if page is not None:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(8, 4.2))
    for name, run in runs.items():
        t, x = run["time"], run["x"]
        f = lowpass("zero-phase", run["force"], float(np.median(np.diff(t))))
        mask = window_mask(x, *run["window"])
        freqs, amp = force_spectrum(t, f, mask)
        dt = float(np.median(np.diff(t)))
        bcells.append((name, f"{f[mask].std():.1f}",
                       *(f"{b:.1f}" for b in band_sigma(f[mask], dt))))
        if fig is not None:
            keep = freqs <= 25.0
            ax.plot(freqs[keep], amp[keep], label=name)
        sx = run["support_x"]
        for s in sx[(sx >= run["window"][0]) & (sx < run["window"][1])]:
            near = (x >= s) & (x <= s + 15.0)
            i = int(np.argmax(np.where(near, f, -np.inf)))
            cells.append((name, f"{s:g}", f"{f[i]:.1f}", f"{x[i] - s:.1f}"))
    if fig is not None:
        run = next(iter(runs.values()))
        span = float(np.diff(run["support_x"]).mean())
        dx = np.diff(np.sort(run["dropper_x"]))
        spacing = float(np.median(dx[dx > 1.0]))
        marks = [(v / span * n, "span" if n == 1 else None) for n in range(1, 15)]
        for fx, lab in marks:
            ax.axvline(fx, color="0.8", lw=0.6, label=lab and f"span passing {v / span:.2f} Hz "
                       "and harmonics")
        ax.axvline(v / spacing, color="k", ls="--", lw=1,
                   label=f"dropper passing {v / spacing:.1f} Hz ({spacing:g} m)")
        m1 = run.get("head_mass")
        k = run.get("stiffness")
        if m1 and run.get("law") == "penalty":
            fc = np.sqrt(k / m1) / (2 * np.pi)
            ax.axvline(fc, color="r", ls=":", lw=1.2,
                       label=f"contact mode {fc:.1f} Hz (penalty {k:g} N/m on {m1:g} kg)")
        ax.set_xlabel("frequency [Hz]")
        ax.set_ylabel("amplitude [N]")
        ax.set_title(f"0-20 Hz contact force, spans 5-6, {speed} km/h")
        ax.legend(fontsize=7)
        fig.tight_layout()
        dest = page.parent / "figures" / "en50318-spectrum.png"
        dest.parent.mkdir(exist_ok=True)
        fig.savefig(dest, dpi=110)
    return ("sigma of the 0-20 Hz force by frequency band (the squares add up to sigma "
            "squared):\n\n" + markdown_table(bhead, bcells)
            + "\nThe largest filtered force after each support of the window (x from the "
            "support to 15 m after it):\n\n" + markdown_table(heads, cells))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", nargs="*", help="these readings (default: all)")
    ap.add_argument("--out", type=Path, default=ROOT / "out" / "en50318-readings")
    ap.add_argument("--docs", type=Path, help="page to write the tables into")
    ap.add_argument("--spectrum", nargs="*", default=[],
                    help="readings whose 300 km/h spectrum and peaks to show")
    ap.add_argument("--quick", action="store_true", help="4 spans, window 60-120 m")
    args = ap.parse_args(argv)
    try:
        os.nice(10)
    except OSError:
        pass
    from pantocosim.core.errors import ParameterError

    try:
        readings = load_readings()
    except ParameterError as exc:
        print(exc, file=sys.stderr)
        return 2
    by_name = {r["name"]: r for r in readings}
    unknown = [n for n in (args.only or []) + args.spectrum if n not in by_name]
    if unknown:
        print(f"unknown reading(s): {', '.join(unknown)} (known: {', '.join(by_name)})",
              file=sys.stderr)
        return 2
    chosen = [by_name[n] for n in args.only] if args.only else readings
    rows = []
    for r in chosen:
        for row in reading_rows(r, by_name, args.out, args.quick):
            rows.append(row)
            st = row.get("statistics")
            print(f"{r['name']:22s} {row['speed']} " + (
                f"run stopped: {row['error']}" if st is None else
                "  ".join(f"{c[0]} {c[2] * st[c[1]]:.1f}" for c in COLUMNS))
                + f"  ({row['wall_s']:.0f} s)", flush=True)
    text = table(readings, rows)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "readings.json").write_text(json.dumps(rows, indent=1))
    (args.out / "readings.md").write_text(text)
    print(text)
    spec = None
    if args.spectrum:
        runs = {n: cached_run(scenario_file(by_name[n], by_name, 300, args.out), args.out,
                              args.quick)
                for n in args.spectrum}
        spec = spectrum(runs, 300, args.docs)
        print(spec)
    if args.docs:
        write_between(args.docs, ("<!-- readings:start -->", "<!-- readings:end -->"), text)
        if spec is not None:
            write_between(args.docs, ("<!-- spectrum:start -->", "<!-- spectrum:end -->"),
                          spec)
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Tutorial: the fast catenary models in a real-time loop.

    python docs/tutorials/realtime.py [--out DIR] [--figures DIR]

Runs a 1 s passage of the EN 50318-type 2-mass pantograph over the 10-span reference
catenary with the nonlinear, linear and modal catenary models (``pantocosim run``), the fast
ones paced to the wall clock (``--realtime``), then the same loop in Python with a place for
the hardware's input and output; writes ``summary.json`` and the figure ``step-times.png``
(also into --figures when given).
"""

from __future__ import annotations

import argparse
import json
import shutil
from pathlib import Path

from tutorial_cli import FILES, pantocosim  # (beside this script)


HIL = (FILES / "hil.toml").read_text()


def python_loop(scenario: Path, n_steps: int) -> dict:
    """The monolithic time loop of ``pantocosim run`` written out, paced to the wall clock."""
    # --8<-- [start:loop]
    from pantocosim.core.hht import HHTSettings
    from pantocosim.master.pacing import StepClock
    from pantocosim.master.run import prepare
    from pantocosim.master.run.stepping import monolithic_stepper
    from pantocosim.master.scenario import load_scenario

    sc = load_scenario(scenario)
    sc.catenary_model = "linear"
    prep = prepare(sc)                                  # model set-up: before the loop
    stepper = monolithic_stepper(prep, HHTSettings.for_runs(sc.alpha, sc.newton_rtol))
    clock = StepClock(sc.dt, realtime=True)             # step k ends at t0 + (k + 1) dt
    forces = []
    for k in clock.steps(n_steps):
        stepper.step(sc.dt)
        F, z_pantograph, z_wire = stepper.contacts()    # one of each per pantograph
        forces.append(F[0])                             # ... to the hardware, and back
    timing = clock.summary()
    # --8<-- [end:loop]
    return {"timing": timing_of(timing), "forces": forces}


def step_time_plot(runs: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = list(runs)
    fig, ax = plt.subplots(figsize=(7, 3.2))
    for i, key in enumerate(("p50_ms", "p99_ms", "max_ms")):
        ax.bar([j + 0.27 * (i - 1) for j in range(len(names))],
               [runs[n]["timing"][key] for n in names], width=0.27,
               label=key.split("_")[0])
    ax.axhline(1.0, color="k", lw=1, ls="--", label="period (1 ms)")
    ax.set_yscale("log")
    ax.set_xticks(range(len(names)), names)
    ax.set_ylabel("compute time per step [ms]")
    ax.legend(fontsize=8)
    ax.grid(True, axis="y", alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def timing_of(summary: dict) -> dict:
    """Step times (p50_ms, p99_ms, max_ms, ...) and, when paced, the missed deadlines."""
    return {**summary["step_time"], **summary.get("realtime", {})}


def main(argv=None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("tutorial-realtime"))
    ap.add_argument("--figures", type=Path, default=None, help="also copy the figures here")
    args = ap.parse_args(argv)
    out = args.out.resolve()
    out.mkdir(parents=True, exist_ok=True)
    (out / "hil.toml").write_text(HIL)

    runs = {}
    # --8<-- [start:run]
    for model, paced in (("nonlinear", False), ("linear", True), ("modal", True)):
        summary = json.loads(pantocosim(
            "run", "hil.toml", "--catenary-model", model, "--json", "--out", f"runs/{model}",
            *(["--realtime"] if paced else []), cwd=out))
        runs[model] = {"timing": timing_of(summary),
                       "mean_force_n": summary["pantographs"][0]["statistics"]["mean_n"],
                       "std_n": summary["pantographs"][0]["statistics"]["std_n"]}
    # --8<-- [end:run]
    loop = python_loop(out / "hil.toml", 1000)
    with open(out / "runs" / "linear" / "timeseries.csv") as fh:
        cli = [float(line.split(",")[2]) for line in list(fh)[2:]]   # F after each step
    runs["linear, Python loop"] = {
        "timing": loop["timing"], "mean_force_n": runs["linear"]["mean_force_n"],
        "std_n": runs["linear"]["std_n"],
        "max_force_difference_to_cli_n": max(abs(a - b) for a, b in zip(loop["forces"], cli))}
    step_time_plot(runs, out / "step-times.png")
    (out / "summary.json").write_text(json.dumps(runs, indent=2))
    print("model                 F_m [N]  p50 [ms]  p99 [ms]  max [ms]  missed deadlines")
    for name, r in runs.items():
        t = r["timing"]
        print(f"{name:<20} {r['mean_force_n']:8.1f} {t['p50_ms']:9.3f} "
              f"{t['p99_ms']:9.3f} {t['max_ms']:9.3f}  "
              f"{t.get('missed_deadlines', '-')}")
    print("the Python loop's contact force differs from pantocosim run's (linear) by at most "
          f"{runs['linear, Python loop']['max_force_difference_to_cli_n']:.2e} N")
    if args.figures:
        args.figures.mkdir(parents=True, exist_ok=True)
        shutil.copy(out / "step-times.png", args.figures / "step-times.png")
    return runs


if __name__ == "__main__":
    main()

"""``pantocosim pendulum``: the spatial flexible double pendulum with impacts
of the pendulum paper (docs/pendulum.md).

Runs the paper's three cases (E = 2.1e15 "rigid", 2.1e11 steel, 2.1e10 Pa) with the
multibody core on the HHT-alpha integrator, and writes into OUT (``--out docs/figures``
refreshes the figures of docs/pendulum.md):

- ``pendulum_trajectories.png``: tips of bar 1 (node 12) and bar 2 (node 23) in the planes
  XY, XZ, YZ (the paper's Figs. 4-6);
- ``pendulum_node23.png``: X component of the rotation vector, vertical velocity and vertical
  acceleration of node 23, one column per case (the paper's Fig. 7);
- ``pendulum_energy.png``: the energy account of each case;
- ``pendulum_summary.json`` and the printed table of the maximum out-of-plane displacement of
  node 12 against the paper's values, the energy balance and the constraint drift.

The pendulum's data are read from ``--params`` (default: the package's
``multibody/data/double_pendulum.toml``); ``--pulse-shape``, ``--pulse-peak`` and
``--bar-mass`` select another reading of the paper's illegible torque pulse and bar mass.
The modelling choices the paper leaves open are listed in
:mod:`pantocosim.multibody.double_pendulum`.
"""

from __future__ import annotations

import json
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from pantocosim.core.hht_defaults import DEFAULT_ALPHA

#: the files the command writes into its output folder
OUTPUT_FILES = ("pendulum_trajectories.png", "pendulum_node23.png", "pendulum_energy.png",
                "pendulum_summary.json")


def add_parser(sub):
    p = sub.add_parser("pendulum", help="spatial flexible double pendulum with impacts",
                       description="The three cases (rigid, steel, E = 2.1e10) of the spatial "
                       "double pendulum with impacts of the pendulum paper (ENIEF 9, "
                       "docs/pendulum.md): figures, out-of-plane maxima against the paper, "
                       "energy account.")
    p.add_argument("--out", default="pendulum_out", help="output folder (default pendulum_out)")
    p.add_argument("--duration", type=float, default=1.5, help="simulated time [s]")
    p.add_argument("--step", type=float, default=2.5e-4,
                   help="HHT time step [s] (default 0.25 ms: 1 ms under-resolves the "
                   "k = 1e6 N/m contact, energy errors of several per cent); a case that "
                   "fails is run again at half and a quarter of it")
    p.add_argument("--alpha", type=float, default=DEFAULT_ALPHA, help="HHT alpha")
    p.add_argument("--cases", default="rigid,steel,soft", help="comma-separated cases")
    p.add_argument("--params", default=None,
                   help="pendulum data file (default: the package's double_pendulum.toml)")
    p.add_argument("--pulse-shape", default=None, choices=["triangular", "rectangular"],
                   help="torque pulse shape (default: the data file's)")
    p.add_argument("--pulse-peak", type=float, default=None,
                   help="torque pulse peak [N m] (default: the data file's)")
    p.add_argument("--bar-mass", default=None,
                   help='mass of each bar [kg], or "density" for density x section x length '
                   "(default: the data file's)")
    return p


def spec_from_args(args):
    """The pendulum's data: the data file with the command line's reading on top."""
    from pantocosim.core.errors import ParameterError
    from pantocosim.core.params import check_number
    from pantocosim.multibody.double_pendulum import load_spec

    over = {}
    if getattr(args, "pulse_shape", None) is not None:
        over["pulse_shape"] = args.pulse_shape
    if getattr(args, "pulse_peak", None) is not None:
        over["pulse_peak"] = check_number("--pulse-peak", args.pulse_peak)
    mass = getattr(args, "bar_mass", None)
    if mass is not None:
        if mass.strip() == "density":
            over["bar_mass"] = None
        else:
            try:
                value = float(mass)
            except ValueError:
                raise ParameterError("--bar-mass", mass,
                                     'must be "density" or a mass in kg > 0') from None
            over["bar_mass"] = check_number("--bar-mass", value, positive=True)
    return load_spec(getattr(args, "params", None), **over)


def run(args) -> int:
    from pantocosim.core.errors import ParameterError
    from pantocosim.master.commands.pantograph import check_times
    from pantocosim.master.output_folder import OutputFolder
    from pantocosim.multibody.double_pendulum import CASES

    cases = [c.strip() for c in args.cases.split(",") if c.strip()]
    if not cases:
        raise ParameterError("--cases", args.cases, f"no case given (known: "
                             f"{', '.join(CASES)})")
    for c in cases:
        if c not in CASES:
            raise ParameterError("--cases", c, f"unknown case (known: {', '.join(CASES)})")
    check_times(args.duration, args.step, args.alpha, None, dt_name="--step")
    spec = spec_from_args(args)
    folder = OutputFolder(args.out, known=OUTPUT_FILES)
    try:
        runs, summary = _simulate(cases, args, folder.path, spec)
        folder.commit()
    except BaseException:
        folder.discard()
        raise
    out = Path(args.out)
    print(f"\nreading: {spec.reading()}")
    print("\n| case | E (Pa) | max out-of-plane node 12 (m) | paper (m) |")
    print("|---|---|---|---|")
    for c, s in summary.items():
        print(f"| {c} | {s['E']:.1e} | {s['max_out_of_plane_node12_m']:.3e} | {s['paper_m']:g} |")
    print("\n| case | pulse work (J) | contact dissipation (J) | HHT dissipation (J) | "
          "max residual / scale |")
    print("|---|---|---|---|---|")
    for c, s in summary.items():
        print(f"| {c} | {s['pulse_work_J']:.4f} | {s['contact_dissipation_J']:.4f} | "
              f"{s['hht_dissipation_J']:.4f} | {s['max_energy_residual_over_scale']:.2e} |")
    print("\n| case | node 23: max abs rotation X (rad) | max abs vertical velocity (m/s) | "
          "max abs vertical acceleration (m/s2) |")
    print("|---|---|---|---|")
    for c, s in summary.items():
        print(f"| {c} | {s['node23_max_abs_rotation_x_rad']:.3f} | "
              f"{s['node23_max_abs_vertical_velocity_m_s']:.3f} | "
              f"{s['node23_max_abs_vertical_acceleration_m_s2']:.4g} |")
    print(f"\nfigures and pendulum_summary.json in {out}")
    return 0


def _simulate(cases, args, out: Path, spec):
    """Run the cases and write the figures and pendulum_summary.json into ``out``."""
    from pantocosim.core.errors import ConvergenceError
    from pantocosim.master.output_folder import writing
    from pantocosim.multibody.double_pendulum import CASES, simulate_case

    runs, summary = {}, {}
    for c in cases:
        E, paper = CASES[c]
        start = time.perf_counter()
        try:
            model, r, h = simulate_case(replace(spec, E=E), args.duration, args.step,
                                        alpha=args.alpha)
        except ConvergenceError as exc:
            # a beam element turned over within one step, or Newton failed, at every step
            raise ConvergenceError(f"--step = {args.step!r}: case {c!r} failed at the step "
                                   f"and its halves ({exc}); a shorter time step may "
                                   "help") from None
        runs[c] = r
        en = r.energy
        scale = max(abs(en["pulse_work"][-1]), en["kinetic"].max())
        contact = np.nonzero(r.positions[23][:, 1] < model.spec.ground)[0]
        summary[c] = {
            "E": E,
            "max_out_of_plane_node12_m": float(np.abs(r.positions[12][:, 2]).max()),
            "paper_m": paper,
            "reading": spec.reading(),
            "pulse_shape": spec.pulse_shape,
            "pulse_peak_N_m": spec.pulse_peak,
            "bar_mass_kg": spec.mass,
            "step_s": h,
            "first_impact_s": float(r.t[contact[0]]) if contact.size else None,
            "pulse_work_J": float(en["pulse_work"][-1]),
            "contact_dissipation_J": float(en["contact_dissipation"][-1]),
            "hht_dissipation_J": float(en["hht_dissipation"][-1]),
            "max_energy_residual_over_scale": float(np.abs(en["hht_dissipation"]).max() / scale),
            "energy_scale_J": float(scale),
            "max_constraint_drift": float(r.drift.max()),
            "mean_newton_iterations": float(r.iterations[1:].mean()),
            "node23_max_abs_rotation_x_rad": float(np.abs(r.rotations[23][:, 0]).max()),
            "node23_max_abs_vertical_velocity_m_s": float(np.abs(r.velocities[23][:, 1]).max()),
            "node23_max_abs_vertical_acceleration_m_s2": float(
                np.abs(r.accelerations[23][:, 1]).max()),
            "wall_time_s": round(time.perf_counter() - start, 1),
        }
        print(f"{c:>6}: E = {E:.2e} Pa, node 12 out of plane max "
              f"{summary[c]['max_out_of_plane_node12_m']:.3e} m (paper {paper:g} m), "
              f"first impact {summary[c]['first_impact_s']} s, drift "
              f"{summary[c]['max_constraint_drift']:.1e}, step {h:g} s, "
              f"{summary[c]['wall_time_s']} s",
              flush=True)
    with writing("file", out):
        _figures(runs, out, args, summary)
        (out / "pendulum_summary.json").write_text(json.dumps(summary, indent=2) + "\n")
    return runs, summary


def _figures(runs, out, args, summary) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    planes = [(0, 1, "X", "Y"), (0, 2, "X", "Z"), (2, 1, "Z", "Y")]
    fig, axes = plt.subplots(2, 3, figsize=(13, 8))
    for c, r in runs.items():
        for row, node in enumerate((12, 23)):
            for col, (i, j, a, b) in enumerate(planes):
                ax = axes[row, col]
                ax.plot(r.positions[node][:, i], r.positions[node][:, j], lw=0.8, label=c)
                ax.set_xlabel(f"{a} [m]")
                ax.set_ylabel(f"{b} [m]")
                ax.set_title(f"node {node}, plane {a}{b}")
    axes[0, 0].legend()
    fig.tight_layout()
    fig.savefig(out / "pendulum_trajectories.png", dpi=120)
    plt.close(fig)
    _node23_figure(runs, out, plt, summary)

    fig, axes = plt.subplots(len(runs), 1, figsize=(9, 3.2 * len(runs)), squeeze=False)
    for ax, (c, r) in zip(axes[:, 0], runs.items()):
        en = r.energy
        for k in ("kinetic", "strain", "contact", "pulse_work", "contact_dissipation",
                  "hht_dissipation"):
            ax.plot(r.t, en[k], lw=0.8, label=k)
        ax.plot(r.t, en["gravity"] - en["gravity"][0], lw=0.8, label="gravity - gravity(0)")
        ax.set_title(f"{c}: energy account [J], HHT alpha = {args.alpha}")
        ax.legend(fontsize=7, ncol=3)
    axes[-1, 0].set_xlabel("t [s]")
    fig.tight_layout()
    fig.savefig(out / "pendulum_energy.png", dpi=120)
    plt.close(fig)


def _node23_figure(runs, out, plt, summary) -> None:
    """The paper's Fig. 7 for every case: X component of the rotation vector, vertical
    velocity and vertical (HHT) acceleration of node 23, first contact marked."""
    rows = [("rotations", 0, "rotation vector X [rad]"),
            ("velocities", 1, "vertical velocity [m/s]"),
            ("accelerations", 1, "vertical acceleration [m/s2]")]
    fig, axes = plt.subplots(3, len(runs), figsize=(4.4 * len(runs), 8.5), sharex=True,
                             squeeze=False)
    for col, (c, r) in enumerate(runs.items()):
        impact = summary[c]["first_impact_s"]
        for row, (field, comp, label) in enumerate(rows):
            ax = axes[row, col]
            ax.plot(r.t, getattr(r, field)[23][:, comp], lw=0.6 if row == 2 else 0.8)
            if impact is not None:
                ax.axvline(impact, color="k", lw=0.5, ls=":")
            if col == 0:
                ax.set_ylabel(label)
        axes[0, col].set_title(f"node 23, {c}")
        axes[-1, col].set_xlabel("t [s]")
    fig.tight_layout()
    fig.savefig(out / "pendulum_node23.png", dpi=120)
    plt.close(fig)

"""``pantocosim pantograph``: stand-alone time simulation under a prescribed contact force."""

from __future__ import annotations

from pathlib import Path

from pantocosim.core.hht_defaults import DEFAULT_ALPHA


def add_parser(sub):
    p = sub.add_parser("pantograph", help="simulate a pantograph under a prescribed force",
                       description="Integrate PANTOGRAPH (HHT-alpha) from static equilibrium "
                       "under a contact force law F(t) [N, positive pushes the collector "
                       "down]; writes a CSV time series and a PNG plot.")
    p.add_argument("pantograph", help="preset name or parameter file")
    p.add_argument("--force", required=True,
                   help='contact force in t, e.g. "120 + 30*sin(4*pi*t)"')
    p.add_argument("--duration", type=float, required=True, help="simulated time [s]")
    p.add_argument("--dt", type=float, default=1e-3, help="time step [s] (default 1 ms)")
    p.add_argument("--alpha", type=float, default=DEFAULT_ALPHA, help="HHT alpha in [-1/3, 0]")
    p.add_argument("--speed", type=float, default=0.0,
                   help="train speed [km/h] for the aerodynamic uplift (default 0)")
    p.add_argument("--friction", type=float, default=None, help="collector friction f_r [N]")
    p.add_argument("--linear", action="store_true", help="integrate the linearised model")
    p.add_argument("--out", default="out/pantograph", help="output folder")
    p.add_argument("--max-steps", type=int, default=None, metavar="N",
                   help="run up to N time steps (default: the size guard's limit)")
    return p


def check_times(duration: float, dt: float, alpha: float, max_steps: int | None,
                dt_name: str = "--dt") -> int:
    """The number of steps of ``--duration`` in steps of ``--dt`` (checked)."""
    from pantocosim.core.errors import ParameterError
    from pantocosim.core.params import check_number
    from pantocosim.master.size_limits import check_limit_option, check_steps

    check_number("--duration", duration, positive=True)
    check_number(dt_name, dt, positive=True)
    check_number("--alpha", alpha, minimum=-1.0 / 3.0, maximum=0.0)
    check_limit_option("--max-steps", max_steps)
    if dt > duration:
        raise ParameterError(dt_name, dt, f"longer than --duration = {duration:g} s: the run "
                             "would have no step")
    n_steps = int(round(duration / dt))
    check_steps(n_steps, "--duration", duration, None, max_steps)
    return n_steps


def run(args) -> int:
    from pantocosim.core.errors import Interrupted
    from pantocosim.master.interrupt import stop_on_interrupt
    from pantocosim.master.output_folder import OutputFolder
    from pantocosim.master.standalone import force_expression, simulate_pantograph
    from pantocosim.pantograph.presets import load_pantograph

    from pantocosim.core.errors import ParameterError
    from pantocosim.core.params import check_number

    check_times(args.duration, args.dt, args.alpha, args.max_steps)
    check_number("--speed", args.speed, nonnegative=True)
    if args.friction is not None:
        check_number("--friction", args.friction, nonnegative=True)
    overrides = {"speed_kmh": args.speed}
    if args.friction is not None:
        overrides["friction_force"] = args.friction
    model = load_pantograph(args.pantograph, **overrides)
    force = force_expression(args.force)
    stem = f"{model.name}{'-linear' if args.linear else ''}"
    folder = OutputFolder(args.out, known=[f"{stem}.csv", f"{stem}.png"])
    try:
        with stop_on_interrupt() as stop:
            try:
                res = simulate_pantograph(model, force, args.duration, args.dt, args.alpha,
                                          linear=args.linear, stop=stop)
            except ParameterError as exc:   # the model's speed is this command's --speed
                raise exc.renamed({"speed_kmh": "--speed"}) from None
        if res.stopped is not None and len(res.time) < 2:
            raise Interrupted(f"{res.stopped}: nothing written")
        with stop_on_interrupt() as late:   # a Ctrl-C now waits until the files are in place
            csv, png = write_outputs(folder.path, stem, model, res, args.force)
            folder.commit()
    except BaseException:
        folder.discard()
        raise
    h = res.contact_height
    print(f"{model.name}: {len(res.time) - 1} steps of {args.dt:g} s, "
          f"mean Newton iterations {res.iterations[1:].mean():.2f}")
    print(f"contact height: start {h[0]:.5f} m, min {h.min():.5f} m, max {h.max():.5f} m")
    out = Path(args.out)
    print(f"wrote {out / csv.name} and {out / png.name}")
    if res.stopped is not None:
        raise Interrupted(f"{res.stopped}; the results so far are in {out / csv.name}")
    if late.requested:
        raise Interrupted(f"interrupted (Ctrl-C) while the results were written: they are "
                          f"complete in {out}")
    return 0


def write_outputs(out: Path, stem: str, model, res, formula: str):
    """The CSV time series and the PNG plot of a stand-alone run."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from pantocosim.master.output_folder import writing
    from pantocosim.master.results.files import write_csv

    with writing("file", out / f"{stem}.csv"):
        csv = write_csv(out / f"{stem}.csv", res.columns(model.dof_names))
    fig, axes = plt.subplots(2, 1, sharex=True, figsize=(8, 6))
    axes[0].plot(res.time, res.contact_force)
    axes[0].set_ylabel("contact force [N]")
    axes[1].plot(res.time, res.contact_height)
    axes[1].set_ylabel("contact height [m]")
    axes[1].set_xlabel("time [s]")
    axes[0].set_title(f"{model.name} under F(t) = {formula}")
    for ax in axes:
        ax.grid(True, alpha=0.3)
    fig.tight_layout()
    png = out / f"{stem}.png"
    with writing("file", png):
        fig.savefig(png, dpi=120)
    plt.close(fig)
    return csv, png

"""``pantocosim static``: static configuration of a catenary (thesis 3.1.3)."""

from __future__ import annotations

import json

import numpy as np

from pantocosim.master.commands.run import add_size_options


def add_parser(sub):
    p = sub.add_parser("static", help="static configuration of a catenary",
                       description="Solve the initial-configuration problem of CATENARY "
                       "(dropper lengths and wire pre-tensions that put the contact wire at "
                       "its design heights under the design tensions) and report heights, "
                       "tensions, dropper forces and the elasticity along the central span "
                       "(static uplift per unit upward force, in m/N).")
    p.add_argument("catenary", metavar="CATENARY",
                   help="preset name (en50318, benchmark55, ave64) or definition file")
    p.add_argument("--json", action="store_true", help="print JSON")
    p.add_argument("--plot", metavar="FILE.png", help="side view and elasticity plot")
    p.add_argument("--element-size", type=float, default=None,
                   help="override the definition's target element size [m]")
    add_size_options(p, steps=False)
    return p


def run(args) -> int:
    from pantocosim.catenary.analysis import static_report
    from pantocosim.catenary.model import CatenaryModel
    from pantocosim.core.params import check_number

    from pantocosim.master.output_folder import check_file_target
    from pantocosim.master.size_limits import check_cli_catenary

    if args.element_size is not None:
        check_number("--element-size", args.element_size, positive=True)
    if args.plot:
        check_file_target("--plot", args.plot)
    check_cli_catenary(args.catenary, args.element_size, args.max_dofs)
    model = CatenaryModel(args.catenary, element_size=args.element_size)
    report, extra = static_report(model)
    if args.plot:
        plot_static(model, report, args.plot)
    if args.json:
        print(json.dumps(report, indent=2))
        return 0
    d = model.definition
    print(f"{d.name}: {d.n_spans} spans, {report['n_dofs']} DOFs, "
          f"{report['n_elements']} elements")
    print(f"  equilibrium residual        {extra['equilibrium_residual']:.2e} of the weight")
    print(f"  max contact-wire height error at droppers  {report['max_height_error_m']:.2e} m")
    print(f"  contact wire tension  {report['contact_wire_tension_n']:.1f} N "
          f"(design {d.contact.tension:g} N)")
    print(f"  messenger tension     {report['messenger_tension_n']:.1f} N "
          f"(design {d.messenger.tension:g} N)")
    f = np.array(report["dropper_forces_n"])
    print(f"  dropper forces        {f.min():.1f} .. {f.max():.1f} N "
          f"({int(np.sum(f <= 0))} slack)")
    el = report["elasticity_m_per_n"]
    print(f"  elasticity along span {extra['span'] + 1} (uplift per 100 N):")
    for x, v in zip(el["x_m"], el["value"]):
        print(f"    x = {x:8.2f} m   {v * 100 * 1000:7.2f} mm   ({v * 1000:.4f} mm/N)")
    if args.plot:
        print(f"  plot written to {args.plot}")
    return 0


def plot_static(model, report, path) -> None:
    """Side view (vertical scale exaggerated), contact-wire height in the central span and
    elasticity along it."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    S = model.structure
    mesh = model.mesh
    xa = S.absolute(model.x_static)
    nd = mesh.node_dofs
    fig, ax = plt.subplots(3, 1, figsize=(11, 9))
    cx, cz = xa[nd[mesh.contact_nodes, 0]], xa[nd[mesh.contact_nodes, 2]]
    mx, mz = xa[nd[mesh.messenger_nodes, 0]], xa[nd[mesh.messenger_nodes, 2]]
    ax[0].plot(cx, cz, "C0-", lw=1, label="contact wire")
    ax[0].plot(mx, mz, "C1-", lw=1, label="messenger wire")
    for b in mesh.dropper_bars:
        d = S.bars.dofs[b]
        ax[0].plot([xa[d[0]], xa[d[3]]], [xa[d[2]], xa[d[5]]], "k-", lw=0.5)
    for b, *_ in mesh.arms:
        d = S.bars.dofs[b]
        ax[0].plot([xa[d[0]], xa[d[3]]], [xa[d[2]], xa[d[5]]], "C2-", lw=1.5)
    for x in model.support_x:
        ax[0].axvline(x, color="0.7", lw=0.8, zorder=0)
    ax[0].set_ylabel("height above rail [m]")
    ax[0].set_title(f"{model.definition.name if model.definition else 'catenary'}: "
                    "static configuration (vertical scale exaggerated)")
    ax[0].legend(loc="lower right", fontsize=8)
    from pantocosim.catenary.analysis import central_span

    s = central_span(model.support_x)
    a, b = model.support_x[s], model.support_x[s + 1]
    xs = np.linspace(a, b, 601)
    z = model.contact_wire_height(model.q_static, xs)
    ax[1].plot(xs, (z - model.definition.contact_wire_height) * 1000, "C0-",
               label="static contact wire")
    m = (mesh.dropper_x >= a) & (mesh.dropper_x <= b)
    ax[1].plot(mesh.dropper_x[m], (mesh.dropper_design_z[m]
                                   - model.definition.contact_wire_height) * 1000,
               "kx", label="design at droppers")
    ax[1].set_ylabel("height - support height [mm]")
    ax[1].legend(fontsize=8)
    el = report["elasticity_m_per_n"]
    ax[2].plot(el["x_m"], np.array(el["value"]) * 100 * 1000, "C3o-", ms=3)
    ax[2].set_ylabel("uplift per 100 N [mm]")
    ax[2].set_xlabel("x along track [m]")
    ax[2].set_title(f"elasticity along span {s + 1}")
    for k in (1, 2):
        ax[k].set_xlim(a, b)
        ax[k].grid(alpha=0.3)
    fig.tight_layout()
    from pantocosim.master.output_folder import save_figure

    save_figure(fig, "--plot", path)
    plt.close(fig)

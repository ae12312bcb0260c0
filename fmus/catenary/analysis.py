"""Static report of a catenary: heights at droppers against design, tensions, dropper forces
and elasticity (static uplift per unit upward force at the contact wire) along a span."""

from __future__ import annotations

import numpy as np

from .statics import group_horizontal_tensions


def central_span(support_x) -> int:
    """Index of the span analysed by default (the middle one; EN 50318 analyses central
    spans) of a line with supports at ``support_x``."""
    return (len(support_x) - 1) // 2


def central_window(support_x) -> tuple[float, float]:
    """The central span [m]: the default analysis window (catenary FMU, third-party runs)."""
    s = central_span(support_x)
    return float(support_x[s]), float(support_x[s + 1])


def elasticity_positions(model, span: int | None = None, step: float = 2.0) -> np.ndarray:
    """Supports, droppers and points about every ``step`` m along one span."""
    s = central_span(model.support_x) if span is None else span
    a, b = model.support_x[s], model.support_x[s + 1]
    n = max(2, int(round((b - a) / step)))
    xs = set(np.round(np.linspace(a, b, n + 1), 6))
    xs.update(np.round(model.mesh.dropper_x[(model.mesh.dropper_x > a)
                                            & (model.mesh.dropper_x < b)], 6))
    return np.array(sorted(xs))


def static_report(model, elasticity_force: float = 100.0, step: float = 2.0) -> dict:
    """The JSON of ``pantocosim static`` plus extra figures under ``"_extra"``."""
    S = model.structure
    mesh = model.mesh
    q = model.q_static
    x = S.full(q)
    z_dr = x[mesh.node_dofs[mesh.dropper_contact_nodes, 2]]
    H = group_horizontal_tensions(mesh, x)
    names = mesh.group_names
    Hc = np.array([h for h, n in zip(H, names) if n.startswith("contact")])
    Hm = np.array([h for h, n in zip(H, names) if n.startswith("messenger")])
    d = model.definition
    xe = elasticity_positions(model, step=step)
    el = model.elasticity(xe, elasticity_force)
    forces = model.dropper_forces(q)
    Tc = d.contact.tension if d is not None else mesh.group_tension[0]
    Tm = d.messenger.tension if d is not None else float("nan")
    report = {
        "n_dofs": int(model.n_dofs),
        "n_elements": int(len(S.cables) + len(S.bars)),
        "contact_wire_height_at_droppers_m": [float(v) for v in z_dr],
        "design_height_at_droppers_m": [float(v) for v in mesh.dropper_design_z],
        "max_height_error_m": float(np.max(np.abs(z_dr - mesh.dropper_design_z))),
        "contact_wire_tension_n": float(np.mean(Hc)),
        "messenger_tension_n": float(np.mean(Hm)) if Hm.size else float("nan"),
        "dropper_forces_n": [float(v) for v in forces],
        "elasticity_m_per_n": {"x_m": [float(v) for v in xe], "value": [float(v) for v in el]},
    }
    extra = {
        "equilibrium_residual": model.equilibrium_residual(q),
        "contact_tension_max_rel_error": float(np.max(np.abs(Hc / Tc - 1))),
        "messenger_tension_max_rel_error": (float(np.max(np.abs(Hm / Tm - 1)))
                                            if Hm.size else float("nan")),
        "elasticity_force_n": elasticity_force,
        "span": central_span(model.support_x),
    }
    return report, extra

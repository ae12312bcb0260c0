"""The constants of the native FMUs, read from the Python models: the one place that knows
the models' and steppers' internals (the native models in ``fmus/native/`` step exactly
these constants with the same closed-form steps).

- linear catenary (:class:`~pantocosim.catenary.linear.LinearCatenary`, its
  :meth:`~pantocosim.catenary.linear.LinearCatenary.affine_form`): the bands of M and K0, q_static, r0, Rayleigh coefficients, the
  droppers' vectors b, axial stiffnesses k_a and pre-tensions N0 (exact slackening), the
  contact wire's reference geometry for the Hermite contact point (3.11)-(3.13), the rows
  behind ``support_uplift_j`` and the static start under the static contact forces;
- lumped pantograph (:meth:`~pantocosim.pantograph.lumped.LumpedPantograph.linear_form`):
  M, C, K, B and the start state.

Each function returns ``{section name: array}`` for :func:`pantocosim.master.native.build.write_data`.
"""

from __future__ import annotations

import numpy as np

from pantocosim.core.errors import ParameterError
from pantocosim.core.hht import HHTIntegrator


def _i32(x) -> np.ndarray:
    return np.ascontiguousarray(x, dtype=np.int32)


def _f64(x) -> np.ndarray:
    return np.ascontiguousarray(x, dtype=np.float64)


def _text(s: str) -> np.ndarray:
    """A string as int32 words (NUL padded)."""
    raw = s.encode() + b"\0"
    raw += b"\0" * (-len(raw) % 4)
    return np.frombuffer(raw, dtype=np.int32).copy()


def wire_geometry(model) -> dict:
    """The contact wire's elements at the reference configuration (contact_point.py):
    x range, Hermite coordinates of x, lengths, z DOFs (-1 fixed) and fixed heights."""
    loc = model.locator
    free = np.asarray(loc.z_free, dtype=np.int64)
    zfix = np.where(free >= 0, 0.0, loc.x_full_ref[loc.z_full_dofs])
    return {"wire_xs": _f64(loc.x_start), "wire_xe": _f64(loc.x_end),
            "wire_Ex": _f64(loc.E_x).ravel(), "wire_Le": _f64(loc.Le),
            "wire_dof": _i32(free).ravel(), "wire_zfix": _f64(zfix).ravel(),
            "x_range": (loc.x_min, loc.x_max)}


def support_rows(model) -> tuple[np.ndarray, np.ndarray]:
    """(free DOF or -1, static height) behind each ``support_uplift_j``."""
    model.support_uplift(model.q_static)            # forms the model's rows
    free, moving, z_static = model._support_free
    return _i32(np.where(moving, free, -1)), _f64(np.where(moving, z_static, 0.0))


def check_speed(model) -> None:
    """The train speed below the contact wire's wave speed (the FMU refuses another)."""
    wave = model.definition.contact.wave_speed
    if not model.speed < wave:
        raise ParameterError("speed_kmh", model.speed * 3.6, f"must be below the contact "
                             f"wire's wave speed c = {wave * 3.6:.0f} km/h: at or above it the "
                             "wire cannot carry the moving load")


def linear_catenary(model, settings, h: float, static_forces, contact, definition: str,
                    spans: int, rtol: float, model_code: int = 1, cutoff: float = 0.0) -> dict:
    """The sections of a linear catenary stepped with HHT ``settings`` at internal step
    ``h`` from the static start under ``static_forces``."""
    check_speed(model)
    form = model.affine_form()
    dr = form.unilateral
    F0 = np.asarray(static_forces, dtype=float)
    q0 = model.static_state(F0 if np.any(F0 != 0.0) else None)
    vec = dr.vectors
    if vec.idx.shape[1] != 6:
        raise ParameterError("droppers", vec.idx.shape[1], "the native model takes droppers "
                             "of 6 coordinates (two 3D nodes)")
    wire = wire_geometry(model)
    x_min, x_max = wire.pop("x_range")
    s_dof, s_z = support_rows(model)
    n = form.n
    sizes = [n, form.M_band.shape[0] - 1, form.K_band.shape[0] - 1, len(dr.ka), 6,
             len(model.x0), len(model.locator.Le), len(s_dof), spans, model_code]
    scalars = [h, settings.alpha, settings.beta, settings.gamma, form.alpha_r, form.beta_r,
               model.speed, model.definition.contact.wave_speed, contact.stiffness,
               contact.damping, x_min, x_max, cutoff, rtol, 0.0, 0.0]
    return {"sizes": _i32(sizes), "scalars": _f64(scalars),
            "M_band": _f64(form.M_band).ravel(), "K_band": _f64(form.K_band).ravel(),
            "q_ref": _f64(form.q_ref), "r0": _f64(form.r0), "q0": _f64(q0), "F0": _f64(F0),
            "x0": _f64(model.x0), "drop_idx": _i32(vec.idx).ravel(),
            "drop_val": _f64(vec.val).ravel(), "drop_ka": _f64(dr.ka),
            "drop_N0": _f64(dr.N0), "drop_tension": _i32(dr.tension_only),
            **wire, "support_dof": s_dof, "support_z": s_z, "definition": _text(definition)}


def lumped_pantograph(model, settings, h: float, height: float, force: float,
                      name: str) -> dict:
    """The sections of a constant-matrix pantograph (its ``linear_form``) stepped with HHT
    ``settings`` at internal step ``h``, in the static start at contact height ``height``
    under the contact force ``force`` (the Python pantograph FMU's start_mode 0): M, C, K, B,
    the loads w, and the Python integrator's own start (q0, a0, f_rest0) and inverse step
    matrix S^-1 of its closed-form step (hht.py), so that C repeats its arithmetic."""
    q0 = model.static_equilibrium(force, height)
    form = model.linear_form()
    if form is None:
        raise ParameterError("pantograph", name, "has no constant-matrix form (collector "
                             "friction or a one-way damper): it stays a Python FMU")
    n = model.n_dofs
    w0 = np.zeros(3)
    form.fill(0.0, np.array([force]), w0)
    integ = HHTIntegrator(model, settings)
    integ.initialize(0.0, q0, np.zeros(n), np.array([force]))
    a0, f0 = integ.a.copy(), integ.f_rest.copy()
    integ.step(h, np.array([force]))            # forms S^-1 of step h (_step_linear)
    S_inv = integ.closed_form_step.S_inv
    lo, hi = model.height_range()
    o = model.options
    scalars = [h, settings.alpha, settings.beta, settings.gamma, lo, hi, o.static_force,
               o.aero_c1, o.aero_c2, o.speed_kmh, height, force, o.friction_force,
               o.friction_smoothing, 0.0, 0.0]
    return {"sizes": _i32([n, 0]), "scalars": _f64(scalars),
            "M": _f64(form.M).ravel(), "C": _f64(form.C).ravel(), "K": _f64(form.K).ravel(),
            "B": _f64(np.atleast_2d(form.B).reshape(n, 3)).ravel(), "w0": _f64(w0),
            "q0": _f64(q0), "a0": _f64(a0), "f0": _f64(f0), "S_inv": _f64(S_inv).ravel(),
            "preset": _text(name)}


def modal_catenary(model, settings, h: float, static_forces, contact, definition: str,
                   spans: int, rtol: float, cutoff: float) -> dict:
    """The sections of a modal catenary (:class:`~pantocosim.catenary.modal.ModalCatenary`)
    stepped with HHT ``settings`` at internal step ``h`` from the static start under
    ``static_forces``: the modal and residual tables of its interfaces (modal_residual.py),
    the droppers' rows T_K, the contact wire's geometry with the wire DOFs numbered as the
    tables' rows, the supports' rows."""
    check_speed(model)
    lin, flex, dr = model.linear, model.flex, model.droppers
    F0 = np.asarray(static_forces, dtype=float)
    y0 = model.static_state(F0 if np.any(F0 != 0.0) else None)
    wire = wire_geometry(lin)
    x_min, x_max = wire.pop("x_range")
    loc = lin.locator
    wire["wire_dof"] = _i32(flex.elem_s).ravel()                 # rows of the S tables
    wire["wire_zfix"] = _f64(loc.x_full_ref[loc.z_full_dofs]).ravel()
    m, nz, nx = model.m, model.nz, model.nx
    nS = flex.S.size
    sizes = [model.n_dofs, m, nz, nx, len(dr.ka), len(model.x0), len(loc.Le), flex.sup.size,
             nS, flex.band if nx else 0, spans, 2]
    scalars = [h, settings.alpha, settings.beta, settings.gamma, lin.alpha_r, lin.beta_r,
               model.speed, model.definition.contact.wave_speed, contact.stiffness,
               contact.damping, x_min, x_max, cutoff, rtol, 0.0, 0.0, float(model.kbar),
               lin.beta_r]
    C_band = flex.C_band if nx else np.zeros((nS, 1))
    return {"sizes": _i32(sizes), "scalars": _f64(scalars),
            "Phi_S": _f64(flex.Phi_S).ravel(), "Q_S": _f64(flex.Q_S[:, :nz]).ravel(),
            "C_band": _f64(C_band).ravel(), "omega2": _f64(model.omega2),
            "zeta_c": _f64(model.zeta_c), "r0": _f64(model.r0), "T_K": _f64(model.T_K).ravel(),
            "Phi_sup": _f64(flex.Phi_sup).ravel(), "Q_sup": _f64(flex.Q_sup[:, :nz]).ravel(),
            "C_sup": _f64(flex.C_sup if nx else np.zeros((flex.sup.size, nS))).ravel(),
            "q0": _f64(y0), "F0": _f64(F0), "x0": _f64(model.x0), "drop_ka": _f64(dr.ka),
            "drop_N0": _f64(dr.N0), "drop_tension": _i32(dr.tension_only), **wire,
            "definition": _text(definition)}

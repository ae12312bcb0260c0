"""The constants of the native FMUs, read from the Python models: the one place that knows
the models' and steppers' internals (the native models in ``fmus/native/`` step exactly
these constants with the same closed-form steps).

- linear catenary (:class:`~pantocosim.catenary.linear.LinearCatenary`, its
  :meth:`~pantocosim.catenary.linear.LinearCatenary.affine_form`): the bands of M and K0, q_static, r0, Rayleigh coefficients, the
  droppers' vectors b, axial stiffnesses k_a and pre-tensions N0 (exact slackening), the
  contact wire's reference geometry for the Hermite contact point (3.11)-(3.13), the rows
  behind ``support_uplift_j`` and the static start under the static contact forces;
- lumped pantograph (:meth:`~pantocosim.pantograph.lumped.LumpedPantograph.linear_form`):
  M, C, K, B and the start state;
- rigid DSA-380 (:class:`~pantocosim.pantograph.dsa380.Dsa380Model`): the kernels'
  parameter vector, the options and the actuation torques, placed by the names of
  ``fmus/native/dsa380_rigid.h``.

Each function returns ``{section name: array}`` for :func:`pantocosim.master.native.build.write_data`.
"""

from __future__ import annotations

import numpy as np

from pantocosim.catenary.models import model_code
from pantocosim.core.errors import ParameterError
from pantocosim.core.hht import HHTIntegrator
from pantocosim.interaction.pantograph_start import start_state
from pantocosim.master.native.headers import header_numbers, pack
from pantocosim.pantograph import dsa380_flexible as flex
from pantocosim.pantograph import dsa380_kinematics as kin


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


def catenary_scalars(model, rayleigh, settings, h: float, contact, x_range, rtol: float,
                     cutoff: float) -> dict:
    """The CAT_SCALAR fields (pcs_layout.h) of a catenary ``model`` with Rayleigh damping
    ``rayleigh`` = (alpha_r, beta_r)."""
    return {"STEP": h, "ALPHA": settings.alpha, "BETA": settings.beta,
            "GAMMA": settings.gamma, "RAYLEIGH_MASS": rayleigh[0],
            "RAYLEIGH_STIFFNESS": rayleigh[1], "SPEED": model.speed,
            "WAVE_SPEED": model.definition.contact.wave_speed,
            "CONTACT_STIFFNESS": contact.stiffness, "CONTACT_DAMPING": contact.damping,
            "WIRE_START": x_range[0], "WIRE_END": x_range[1], "MODAL_CUTOFF": cutoff,
            "NEWTON_RTOL": rtol}


def linear_catenary(model, settings, h: float, static_forces, contact, definition: str,
                    spans: int, rtol: float, cutoff: float = 0.0) -> dict:
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
    sizes = {"DOFS": form.n, "BAND_M": form.M_band.shape[0] - 1,
             "BAND_K": form.K_band.shape[0] - 1, "DROPPERS": len(dr.ka), "DROPPER_WIDTH": 6,
             "PANTOGRAPHS": len(model.x0), "WIRE_ELEMENTS": len(model.locator.Le),
             "SUPPORTS": len(s_dof), "SPANS": spans, "MODEL_CODE": model_code("linear")}
    scalars = catenary_scalars(model, (form.alpha_r, form.beta_r), settings, h, contact,
                               (x_min, x_max), rtol, cutoff)
    return {"sizes": pack(sizes, np.int32, "LIN_SIZE"),
            "scalars": pack(scalars, np.float64, "CAT_SCALAR"),
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
    scalars = {"STEP": h, "ALPHA": settings.alpha, "BETA": settings.beta,
               "GAMMA": settings.gamma, "HEIGHT_MIN": lo, "HEIGHT_MAX": hi,
               "STATIC_FORCE": o.static_force, "AERO_C1": o.aero_c1, "AERO_C2": o.aero_c2,
               "SPEED_KMH": o.speed_kmh, "INITIAL_HEIGHT": height, "INITIAL_FORCE": force,
               "FRICTION_FORCE": o.friction_force,
               "FRICTION_SMOOTHING": o.friction_smoothing}
    return {"sizes": pack({"MASSES": n}, np.int32, "PAN_SIZE"),
            "scalars": pack(scalars, np.float64, "PAN_SCALAR"),
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
    sizes = {"COORDINATES": model.n_dofs, "MODES": m, "DROPPER_COORDINATES": nz,
             "PANTOGRAPH_COORDINATES": nx, "DROPPERS": len(dr.ka),
             "PANTOGRAPHS": len(model.x0), "WIRE_ELEMENTS": len(loc.Le),
             "SUPPORTS": flex.sup.size, "WIRE_DOFS": nS, "BAND": flex.band if nx else 0,
             "SPANS": spans, "MODEL_CODE": model_code("modal")}
    scalars = catenary_scalars(model, (lin.alpha_r, lin.beta_r), settings, h, contact,
                               (x_min, x_max), rtol, cutoff)
    scalars["DROPPER_STIFFNESS"] = float(model.kbar)
    C_band = flex.C_band if nx else np.zeros((nS, 1))
    return {"sizes": pack(sizes, np.int32, "MOD_SIZE"),
            "scalars": pack(scalars, np.float64, "CAT_SCALAR", "MOD_SCALAR"),
            "Phi_S": _f64(flex.Phi_S).ravel(), "Q_S": _f64(flex.Q_S[:, :nz]).ravel(),
            "C_band": _f64(C_band).ravel(), "omega2": _f64(model.omega2),
            "zeta_c": _f64(model.zeta_c), "r0": _f64(model.r0), "T_K": _f64(model.T_K).ravel(),
            "Phi_sup": _f64(flex.Phi_sup).ravel(), "Q_sup": _f64(flex.Q_sup[:, :nz]).ravel(),
            "C_sup": _f64(flex.C_sup if nx else np.zeros((flex.sup.size, nS))).ravel(),
            "q0": _f64(y0), "F0": _f64(F0), "x0": _f64(model.x0), "drop_ka": _f64(dr.ka),
            "drop_N0": _f64(dr.N0), "drop_tension": _i32(dr.tension_only), **wire,
            "definition": _text(definition)}


def header_constants(header: str, prefix: str) -> dict[str, int]:
    """The ``#define <prefix><NAME> number`` lines of a native header: {NAME: number}."""
    return {name[len(prefix):]: int(value) for name, value in header_numbers(header).items()
            if name.startswith(prefix)}


def dsa380_constants(model) -> np.ndarray:
    """The constants of the native rigid DSA-380 (``fmus/native/dsa380_rigid.h``): the
    kernels' parameter vector (its layout checked name by name against
    :mod:`pantocosim.pantograph.dsa380_kinematics`), then the pitch lock, the actuation
    torques of the static start and the ramp (2.14), (3.3.1), and the options."""
    layout = header_constants("dsa380_rigid.h", "DSA_P_")
    for name, index in layout.items():
        if getattr(kin, name) != index:
            raise RuntimeError(f"dsa380_rigid.h: DSA_P_{name} = {index}, the kernels' "
                               f"{name} = {getattr(kin, name)}")
    keys = header_constants("dsa380_rigid.h", "DSA_K_")
    o = model.options
    ramp = o.ramp is not None and model.torque_lowered is not None
    values = {"PITCH_LOCK": float(model.pitch_lock), "TORQUE": model.torque,
              "RAMP": float(ramp), "TORQUE_LOWERED": model.torque_lowered if ramp else 0.0,
              "RAMP_START": o.ramp.start if ramp else 0.0,
              "RAMP_DURATION": o.ramp.duration if ramp else 0.0,
              "AERO_FORCE": o.aero_force, "FRICTION_FORCE": o.friction_force,
              "FRICTION_SMOOTHING": o.friction_smoothing,
              "ONE_WAY_DAMPER": float(bool(o.one_way_damper))}
    k = np.zeros(keys.pop("COUNT"))
    k[:layout["NPAR"]] = model.params.vector()
    for name, index in keys.items():
        k[index] = values[name]
    return k


def rigid_body(model) -> dict:
    """The body sections of the native rigid DSA-380: its constants."""
    return {"constants": _f64(dsa380_constants(model))}


def nonlinear_pantograph(model, body, settings, h: float, start_mode: int, height: float,
                         force: float, name: str, lowered_height: float | None = None) -> dict:
    """The sections of a native nonlinear pantograph FMU (``nonlinear_pantograph.c``,
    ``NLP_SCALAR`` of ``pcs_layout.h``): ``model`` (its options as the Python FMU builds them) in
    the start of the Python FMU's ``start_mode`` (0: static at ``height`` under ``force``, < 0
    the mean uplift; 1: ramp raising from ``lowered_height``), which sets its actuation
    torques, then its ``body`` sections (:func:`rigid_body`, :func:`dsa380_flexible_data`),
    stepped with the HHT ``settings`` at internal step ``h``."""
    q0, F0 = start_state(model, start_mode, height=height, force=force,
                         lowered_height=lowered_height)
    lo, hi = model.height_range()
    o = model.options
    ramp = o.ramp
    values = {"STEP": h, "ALPHA": settings.alpha, "RTOL": settings.rtol,
              "ETOL": settings.etol, "MAX_ITERATIONS": settings.max_iterations,
              "LINEAR_PREDICTOR": float(settings.predictor == "linear"), "HEIGHT_MIN": lo,
              "HEIGHT_MAX": hi, "STATIC_FORCE": o.static_force, "AERO_C1": o.aero_c1,
              "AERO_C2": o.aero_c2, "SPEED_KMH": o.speed_kmh,
              "FRICTION_FORCE": o.friction_force, "FRICTION_SMOOTHING": o.friction_smoothing,
              "ONE_WAY_DAMPER": float(bool(o.one_way_damper)), "INITIAL_HEIGHT": height,
              "INITIAL_CONTACT_FORCE": force, "START_MODE": start_mode,
              "RAMP_START_TIME": ramp.start if ramp else 0.0,
              "RAMP_DURATION": ramp.duration if ramp else 0.0,
              "LOWERED_HEIGHT": ramp.lowered_height if ramp else 0.0, "START_FORCE": F0}
    return {"scalars": pack(values, np.float64, "NLP_SCALAR"), **body(model), "q0": _f64(q0), "preset": _text(name)}


def dsa380_flexible_data(model) -> dict:
    """The constants and arrays of the native flexible DSA-380
    (``fmus/native/dsa380_flexible.h``): the model's topology (elements' coordinate pairs,
    2x2 maps, reference coordinates, section stiffnesses), constant mass matrix and gravity,
    Gauss rule, the indices of the points the springs, damper, torque and contact act on, the
    options and the actuation torques."""
    keys = header_constants("dsa380_flexible.h", "DSF_K_")
    o = model.options
    ints, reals = model._ints, model._reals
    ramp = o.ramp is not None and model.torque_lowered is not None
    values = {"N": model.n_dofs, "NE": model.n_elements, "NG": len(model._xi),
              "P5": ints[flex.I_P5], "P11": ints[flex.I_P11], "P12": ints[flex.I_P12],
              "P1P": ints[flex.I_P1P], "S1": ints[flex.I_S1], "Y10": ints[flex.I_Y10],
              "Y5": ints[flex.I_Y5], "KL": reals[flex.R_KL], "L0": reals[flex.R_L0],
              "C": reals[flex.R_C], "X13": reals[flex.R_X13], "Y13": reals[flex.R_Y13],
              "KR": reals[flex.R_KR], "TH0": reals[flex.R_TH0],
              "ONE_WAY_DAMPER": float(bool(o.one_way_damper)),
              "FRICTION_FORCE": o.friction_force, "FRICTION_SMOOTHING": o.friction_smoothing,
              "AERO_FORCE": o.aero_force, "TORQUE": model.torque, "RAMP": float(ramp),
              "TORQUE_LOWERED": model.torque_lowered if ramp else 0.0,
              "RAMP_START": o.ramp.start if ramp else 0.0,
              "RAMP_DURATION": o.ramp.duration if ramp else 0.0}
    k = np.zeros(keys.pop("COUNT"))
    for key, index in keys.items():
        k[index] = values[key]
    return {"constants": _f64(k), "q_ref": _f64(model.q_ref), "M": _f64(model.M).ravel(),
            "Qg": _f64(model.Qg), "E0": _f64(model._E0).ravel(),
            "length": _f64(model._length), "EA": _f64(model._EA), "EI": _f64(model._EI),
            "pg": _i32(model._pg).ravel(), "pR": _f64(model._pR).ravel(),
            "xi_g": _f64(model._xi), "w_g": _f64(model._w)}

"""What every pantograph model shares: the port contract, uplift, ramp raising, friction law.

Port contract (README.md, "The FMUs and their ports"; docs/third-party.md), identical for
every variant:
  input  ``contact_force`` F [N] >= 0, pushes the collector down (and the wire up);
  output ``contact_height`` [m] above the rail and ``contact_velocity`` [m/s].

A pantograph model is a :class:`~pantocosim.core.model.SecondOrderModel` whose ``inputs`` are
``[F]``. The contact force enters ``f_rest`` as ``+F * dh/dq`` (a downward force does negative
work on an upward height), so the integrator weights it like every other force.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, replace

import numpy as np

from ..core.errors import ParameterError
from ..core.model import SecondOrderModel
from ..core.params import Table, check_number
from ..core.schema import Field, Section


@dataclass
class Ramp:
    """Ramp raising (thesis 3.3.1): the uplift actuation grows linearly from its value at the
    lowered height to the full value between ``start`` and ``start + duration`` [s]."""

    start: float = 0.0
    duration: float = 1.0
    lowered_height: float = 5.0

    def factor(self, t: float) -> float:
        if self.duration <= 0.0:
            return 1.0 if t >= self.start else 0.0
        return min(1.0, max(0.0, (t - self.start) / self.duration))


@dataclass
class PantographOptions:
    """Options common to every pantograph model (defaults: EN 50367 AC uplift, no friction)."""

    #: static uplift [N]: contact force at standstill
    static_force: float = 70.0
    #: aerodynamic uplift F_aero = aero_c1 * v + aero_c2 * v^2, v in km/h (EN 50367 AC curve)
    aero_c1: float = 0.0
    aero_c2: float = 0.00097
    #: train speed [km/h], used by the aerodynamic law only
    speed_kmh: float = 0.0
    #: collector friction (2.15)-(2.17): amplitude f_r [N] and smoothing k_t [m/s]
    friction_force: float = 0.0
    friction_smoothing: float = 1e-4
    #: the damper acts only while the mechanism moves down
    one_way_damper: bool = False
    #: ramp raising; None = static start
    ramp: Ramp | None = None

    def validate(self, source: str | None = None) -> None:
        for f in OPTIONS.fields:
            if f.kind == "number":
                check_number(f.name, getattr(self, f.name), source=source, positive=f.positive,
                             nonnegative=f.nonnegative)
        if self.aero_force < 0.0 and self.mean_uplift <= 0.0:
            field = "aero_c2" if self.aero_c2 < 0.0 else "aero_c1"
            raise ParameterError(field, getattr(self, field), self.uplift_lost(), source)
        if self.ramp is not None:
            for f in RAMP.fields:
                check_number(f"ramp.{f.name}", getattr(self.ramp, f.name), source=source,
                             positive=f.positive, nonnegative=f.nonnegative)

    def replaced(self, source: str | None = None, **changes) -> "PantographOptions":
        """A validated copy with some fields changed; unknown names raise ParameterError."""
        known = {f.name for f in fields(self)}
        for key, value in changes.items():
            if key not in known:
                raise ParameterError(f"options.{key}", value, "unknown pantograph option",
                                     source)
        out = replace(self, **changes)
        out.validate(source)
        return out

    @property
    def aero_force(self) -> float:
        """Aerodynamic uplift [N] at the train speed."""
        v = self.speed_kmh
        return self.aero_c1 * v + self.aero_c2 * v * v

    @property
    def mean_uplift(self) -> float:
        """Static plus aerodynamic uplift: the mean contact force the pantograph aims for."""
        return self.static_force + self.aero_force

    def uplift_lost(self, speed_kmh: float | None = None) -> str:
        """Why the options are unusable at ``speed_kmh`` (default: theirs): the mean uplift
        is not positive there."""
        v = self.speed_kmh if speed_kmh is None else speed_kmh
        mean = self.static_force + self.aero_c1 * v + self.aero_c2 * v * v
        return (f"the mean uplift static_force + aero_c1 v + aero_c2 v^2 = {mean:.1f} N at "
                f"{v:g} km/h: the pantograph does not press on the wire (must be > 0)")

    def highest_speed_kmh(self) -> float | None:
        """The speed [km/h] above which the mean uplift is not positive (None: none)."""
        a, b, c = self.aero_c2, self.aero_c1, self.static_force
        if a < 0.0:
            return (-b - math.sqrt(b * b - 4.0 * a * c)) / (2.0 * a)
        if a == 0.0 and b < 0.0:
            return -c / b
        return None

    @classmethod
    def from_table(cls, table: Table) -> "PantographOptions":
        """Read the ``[options]`` table of a parameter file (missing keys keep defaults)."""
        OPTIONS.check_keys(table)
        kwargs = {}
        for f in OPTIONS.fields:   # read by kind; validate() checks the ranges
            if table.has(f.name):
                kwargs[f.name] = (table.boolean(f.name) if f.kind == "boolean"
                                  else table.number(f.name))
        if table.has("ramp"):
            r = table.sub("ramp")
            RAMP.check_keys(r)
            kwargs["ramp"] = Ramp(start=r.number("start", RAMP["start"].default),
                                  duration=r.number("duration"),
                                  lowered_height=RAMP.read(r, "lowered_height", required=True))
        opts = cls(**kwargs)
        opts.validate(table.source)
        return opts


#: the declared fields of a parameter file's ``[options]`` (defaults: the dataclass's)
OPTIONS = Section("options", [
    Field("static_force", unit="N", default=PantographOptions.static_force, nonnegative=True,
          doc="static uplift: contact force at standstill"),
    Field("aero_c1", unit="N h/km", default=PantographOptions.aero_c1,
          doc="aerodynamic uplift F_aero = aero_c1 v + aero_c2 v^2, v in km/h",
          rule="static_force + F_aero > 0 at the run's speed"),
    Field("aero_c2", unit="N h^2/km^2", default=PantographOptions.aero_c2,
          doc="(EN 50367 AC curve by default)"),
    Field("speed_kmh", unit="km/h", default=PantographOptions.speed_kmh, nonnegative=True,
          doc="train speed for the aerodynamic law (a scenario sets it)"),
    Field("friction_force", unit="N", default=PantographOptions.friction_force,
          nonnegative=True, doc="collector friction amplitude f_r, (2.15)-(2.17)"),
    Field("friction_smoothing", unit="m/s", default=PantographOptions.friction_smoothing,
          positive=True, doc="friction smoothing velocity k_t, (2.16)"),
    Field("one_way_damper", "boolean", default=PantographOptions.one_way_damper,
          doc="the damper acts only while the mechanism moves down"),
], doc="Options common to every pantograph model; a scenario's `options` table overrides "
       "them.", extra=("ramp",))
#: ``[options.ramp]``: ramp raising instead of a static start
RAMP = Section("options.ramp", [
    Field("start", unit="s", default=Ramp.start, nonnegative=True, doc="start of the raising"),
    Field("duration", unit="s", default=Ramp.duration, nonnegative=True,
          doc="time to reach the full uplift"),
    Field("lowered_height", unit="m", default=Ramp.lowered_height, positive=True,
          doc="height of the lowered collector"),
], doc="Optional: ramp raising (thesis 3.3.1); the actuation grows linearly from its value at "
       "the lowered height. In a file, `duration` and `lowered_height` are required.")


def smooth_friction(v_rel: float, f_r: float, k_t: float) -> tuple[float, float]:
    """Smoothed Coulomb friction (2.16): F = f_r (2/pi) atan(v_rel / k_t) and dF/dv_rel."""
    force = f_r * (2.0 / math.pi) * math.atan(v_rel / k_t)
    dforce = f_r * (2.0 / math.pi) / (k_t + v_rel * v_rel / k_t)
    return force, dforce


class PantographModel(SecondOrderModel):
    """Base class of the pantograph variants (rigid DSA-380, lumped-mass chains, flexible)."""

    #: preset name, e.g. "dsa380-rigid"
    name: str = "pantograph"
    #: one label per generalised coordinate (for plots, mode labels and CSV columns)
    dof_names: tuple[str, ...] = ()

    def __init__(self, options: PantographOptions | None = None):
        self.options = options or PantographOptions()
        self.options.validate()

    # --- port contract -------------------------------------------------------------------
    def contact_height(self, q: np.ndarray) -> float:
        """Height of the contact point above the rail [m]."""
        raise NotImplementedError

    def contact_height_gradient(self, q: np.ndarray) -> np.ndarray:
        """d(contact_height)/dq; the contact force F enters f_rest as +F * gradient."""
        raise NotImplementedError

    def contact_velocity(self, q: np.ndarray, v: np.ndarray) -> float:
        return float(self.contact_height_gradient(q) @ v)

    def height_range(self) -> tuple[float, float]:
        """Contact heights [m above the rail] the model represents. Default: above the rail
        and below twice the working height (a lumped chain is linear about it)."""
        return (0.0, 2.0 * self.working_height)

    # --- initial states ------------------------------------------------------------------
    def static_equilibrium(self, contact_force: float | None = None,
                           height: float | None = None) -> np.ndarray:
        """Equilibrium under ``contact_force`` (default: the mean uplift) with the contact
        point at ``height`` (default: the preset working height). Sets the model's actuation
        (uplift force or torque) so that this state is an equilibrium and returns q0."""
        raise NotImplementedError

    def equilibrium(self, contact_force: float, height: float) -> tuple[np.ndarray, float]:
        """(q, actuation): the equilibrium under ``contact_force`` with the contact point at
        ``height`` and the actuation (force or torque) that holds it there; nothing is set
        (:meth:`static_equilibrium` sets the actuation)."""
        raise NotImplementedError

    def lowered_equilibrium(self, height: float) -> np.ndarray:
        """Equilibrium without contact at a lowered ``height`` (ramp-raising start)."""
        raise NotImplementedError

    def _equilibrium_at_working_height(self, working_height: float, source) -> None:
        """The default static equilibrium, computed at construction; an unreachable working
        height is reported as the parameter-file field ``frame.working_height``."""
        try:
            self.static_equilibrium()
        except ParameterError as exc:
            if exc.field != "height":
                raise
            raise ParameterError("frame.working_height", working_height, exc.reason,
                                 source) from None

    # --- linearisation -------------------------------------------------------------------
    def linearize(self, q0: np.ndarray, contact_force: float | None = None):
        """M, C, K of the linearised model about (q0, v = 0) with a constant contact force
        (thesis 2.1.2, annex B), from the model's analytic tangents."""
        F = self.options.mean_uplift if contact_force is None else contact_force
        n = self.n_dofs
        ev = self.evaluate(0.0 if self.options.ramp is None else 1e9, np.asarray(q0, float),
                           np.zeros(n), np.zeros(n), np.array([F]), tangent=True)
        K = np.array(ev.stiffness, dtype=float)
        if ev.inertia_q is not None:
            K = K + np.asarray(ev.inertia_q, float)
        return (np.array(ev.mass, dtype=float), np.array(ev.damping, dtype=float), K)

    def mode_label(self, shape: np.ndarray, mass: np.ndarray) -> str:
        """Name of a mode from its shape (dominant coordinate by kinetic energy)."""
        energy = np.abs(np.real(shape) * (mass @ np.real(shape)))
        return self.dof_names[int(np.argmax(energy))] if self.dof_names else "mode"


class TorqueActuatedPantograph(PantographModel):
    """A pantograph raised by a torque on its lower arm (the rigid and the flexible DSA-380):
    the torque M0 that makes the working position an equilibrium (2.14), and the ramp from
    the lowered position's torque (3.3.1). Subclasses give :meth:`equilibrium` and
    :attr:`working_height`."""

    torque: float = 0.0
    torque_lowered: float | None = None

    @property
    def working_height(self) -> float:
        """Default contact height above the rail [m] (the parameter file's)."""
        raise NotImplementedError

    def equilibrium(self, contact_force: float, height: float) -> tuple[np.ndarray, float]:
        """(q0, M0): shape and actuation torque with the contact point at ``height`` under
        ``contact_force`` (no state is changed)."""
        raise NotImplementedError

    def static_equilibrium(self, contact_force=None, height=None):
        """Equilibrium under ``contact_force`` [N] (default: mean uplift) with the contact
        point at ``height`` [m above rail] (default: working height). Stores the actuation
        torque M0 (2.14) in :attr:`torque` and returns q0 (2.11)-(2.13)."""
        F = self.options.mean_uplift if contact_force is None else \
            reject_nonfinite_force(contact_force)
        if F < 0.0:
            raise ParameterError("contact_force", contact_force, "must be >= 0", self.name)
        h = self.working_height if height is None else float(height)
        check_number("height", h, source=self.name, positive=True)
        q0, M0 = self.equilibrium(F, h)
        self.torque = M0
        self.q_equilibrium = q0.copy()
        self.static_contact_force = F
        if self.options.ramp is not None:
            self.lowered_equilibrium(self.options.ramp.lowered_height)
        else:
            self.torque_lowered = None
        return q0

    def lowered_equilibrium(self, height):
        """Equilibrium without contact force at a lowered contact ``height`` (ramp start,
        thesis 3.3.1): stores its torque M_low in :attr:`torque_lowered` and returns q."""
        h = check_number("ramp.lowered_height", height, source=self.name, positive=True)
        q, M_low = self.equilibrium(0.0, h)
        self.torque_lowered = M_low
        return q

    def actuation_torque(self, t: float) -> float:
        """Torque on bar 1 at time t (2.14), ramp-weighted (3.3.1)."""
        ramp = self.options.ramp
        if ramp is None or self.torque_lowered is None:
            return self.torque
        return self.torque_lowered + ramp.factor(t) * (self.torque - self.torque_lowered)

    def equilibrium_info(self) -> dict:
        """Extra equilibrium data for reports (used by ``pantocosim modal``)."""
        return {"actuation_torque_nm": float(self.torque),
                "lowered_torque_nm": None if self.torque_lowered is None
                else float(self.torque_lowered)}


def reject_nonfinite_force(F) -> float:
    """Contact force input check used by every model (NaN/inf are bad input)."""
    x = float(F)
    if not math.isfinite(x):
        raise ParameterError("contact_force", F, "must be finite")
    return x

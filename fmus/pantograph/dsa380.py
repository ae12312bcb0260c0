"""Nonlinear rigid-body DSA-380 pantograph (thesis 2.1.1, annexes A-B).

Generalised coordinates q = (theta, x10, y10, theta7) (2.1): lower-arm angle, position of the
collector centre (point 10, the contact point) and collector pitch. Heights are measured from
the rail: the fixed pivots sit on the roof frame whose origin (point 2) is at ``base_height``.

The hot path (residual and exact tangents) is the numba kernel
:func:`pantocosim.pantograph.dsa380_kinematics.evaluate_kernel`; this module holds the
parameter set (TOML, validated on load), the static equilibrium (2.11)-(2.14), the
ramp-raising torque (3.3.1) and the collector pitch lock (A.37).

The thesis does not publish the DSA-380 data: the preset ``data/dsa380-rigid.toml`` is a
constructed, calibrated set (see ``scripts/calibrate_dsa380.py`` and
``docs/dsa380-calibration.md``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..core.errors import ParameterError
from ..core.model import Evaluation
from ..core.params import Table, check_number, load_toml
from ..core.schema import Field, Section
from . import dsa380_kinematics as kin
from .base import PantographOptions, TorqueActuatedPantograph, reject_nonfinite_force

DATA_DIR = Path(__file__).resolve().parent / "data"
PRESET_FILE = DATA_DIR / "dsa380-rigid.toml"

#: mode labels by dominant coordinate (kinetic-energy sense)
MODE_LABELS = {"theta": "mechanism", "x10": "collector horizontal",
               "y10": "collector vertical", "theta7": "collector pitch"}



@dataclass
class Bar:
    """One rigid bar: length L, mass m, inertia I about its centre of gravity, and the centre
    of gravity at distance LG and angle thetaG from the bar's reference end (Fig. 2.5)."""

    L: float
    m: float
    I: float
    LG: float = 0.0
    thetaG: float = 0.0


#: kernel parameter slots (dsa380_kinematics) filled from each bar, offset by its number
_BAR_SLOTS = ((kin.L1, "L"), (kin.M_, "m"), (kin.I_, "I"), (kin.LG_, "LG"), (kin.THG_, "thetaG"))
#: kernel parameter slots filled from scalar fields of the parameter set
_SCALAR_SLOTS = ((kin.TH34, "theta34"), (kin.R6, "r"), (kin.THR, "theta_r"), (kin.L1P, "L1p"),
                 (kin.TH1P, "theta_1p"), (kin.SIG_LO, "lower_branch"),
                 (kin.SIG_UP, "upper_branch"), (kin.KR, "k_r"), (kin.THR0, "theta_r0"),
                 (kin.KL, "k_l"), (kin.LL0, "l0"), (kin.CDAMP, "c"), (kin.GRAV, "g"))


@dataclass
class Dsa380Parameters:
    """Geometry, inertia, springs and damper of the rigid DSA-380 model (Fig. 2.2-2.5).

    Fixed points (x, y) are relative to point 2 of the roof frame, which sits at
    ``base_height`` above the rail. Bars 1-6 form the mechanism, bar 7 is the collector
    (reference point 10, its centre)."""

    base_height: float
    p1: tuple[float, float]
    p13: tuple[float, float]
    bars: list[Bar]                 # bars 1..7
    theta34: float                  # constant angle between bars 3 and 4 (A.1)
    r: float                        # |1-6| on bar 1
    theta_r: float                  # angle between bar 1 and 1-6
    L1p: float                      # damper lever on bar 1 (A.13)
    theta_1p: float
    lower_branch: float = 1.0       # assembly mode of the lower loop (+1/-1)
    upper_branch: float = 1.0       # assembly mode of the upper loop (+1/-1)
    k_r: float = 0.0                # torsional spring at joint 1 [N m/rad]
    theta_r0: float = 0.0           # its unloaded angle [rad]
    k_l: float = 0.0                # each collector spring [N/m]
    l0: float = 0.0                 # their unloaded length [m]
    c: float = 0.0                  # damper constant [N s/m]
    g: float = 9.81
    theta_min: float = 0.2          # mechanical stops of the lower arm [rad]
    theta_max: float = 1.2
    working_height: float = 5.3     # default contact height above the rail [m]
    source: str | None = None
    extra: dict = field(default_factory=dict)

    # ------------------------------------------------------------------ vector
    def vector(self) -> np.ndarray:
        """Flat parameter vector of the numba kernels (layout in dsa380_kinematics)."""
        P = np.zeros(kin.NPAR)
        yb = self.base_height
        P[kin.X1], P[kin.Y1] = self.p1[0], self.p1[1] + yb
        P[kin.X2], P[kin.Y2] = 0.0, yb
        P[kin.X13], P[kin.Y13] = self.p13[0], self.p13[1] + yb
        for i, b in enumerate(self.bars):
            for index, attribute in _BAR_SLOTS:
                P[index + i] = getattr(b, attribute)
        for index, attribute in _SCALAR_SLOTS:
            P[index] = getattr(self, attribute)
        return P

    # ------------------------------------------------------------------ validation
    def validate(self) -> None:
        """Physical checks; errors name the source, the field and the value."""
        src = self.source
        check_number("frame.base_height", self.base_height, source=src, nonnegative=True)
        for i, b in enumerate(self.bars):
            n = f"bar{i + 1}"
            check_number(f"{n}.L", b.L, source=src, positive=True)
            check_number(f"{n}.m", b.m, source=src, positive=True)
            check_number(f"{n}.I", b.I, source=src, nonnegative=True)
            check_number(f"{n}.LG", b.LG, source=src, nonnegative=True)
            check_number(f"{n}.thetaG", b.thetaG, source=src)
        if self.bars[6].I + self.bars[6].m * self.bars[6].LG ** 2 <= 0.0:
            raise ParameterError("bar7.I", self.bars[6].I, "collector pitch inertia must be > 0",
                                 src)
        for name in ("theta34", "theta_r", "theta_1p", "theta_r0"):
            check_number(f"links.{name}" if name != "theta_r0" else "springs.theta_r0",
                         getattr(self, name), source=src)
        check_number("links.r", self.r, source=src, positive=True)
        check_number("damper.L1p", self.L1p, source=src, positive=True)
        check_number("springs.k_r", self.k_r, source=src, nonnegative=True)
        check_number("springs.k_l", self.k_l, source=src, positive=True)
        check_number("springs.l0", self.l0, source=src, nonnegative=True)
        check_number("damper.c", self.c, source=src, nonnegative=True)
        check_number("g", self.g, source=src, nonnegative=True)
        for name in ("lower_branch", "upper_branch"):
            v = getattr(self, name)
            if v not in (1.0, -1.0, 1, -1):
                raise ParameterError(f"links.{name}", v, "must be +1 or -1", src)
        check_number("frame.theta_min", self.theta_min, source=src)
        check_number("frame.theta_max", self.theta_max, source=src)
        if not self.theta_min < self.theta_max:
            raise ParameterError("frame.theta_max", self.theta_max,
                                 f"must be > frame.theta_min = {self.theta_min}", src)
        check_number("frame.working_height", self.working_height, source=src, positive=True)
        # the loops must close, and point 5 must rise monotonically, over the stops' range
        P = self.vector()
        ths = np.linspace(self.theta_min, self.theta_max, 121)
        y5p = np.empty_like(ths)
        for k, th in enumerate(ths):
            ok, A, V, p5 = kin.mechanism_terms(P, th)
            if not ok > 0.0:
                raise ParameterError("frame.theta_min/theta_max",
                                     (self.theta_min, self.theta_max),
                                     f"the loops (A.1) cannot be closed at theta = {th:.4f} rad: "
                                     "check bar lengths and the fixed points", src)
            y5p[k] = p5[3]
        if not (np.all(y5p > 0.0) or np.all(y5p < 0.0)):
            raise ParameterError("frame.theta_min/theta_max", (self.theta_min, self.theta_max),
                                 "point 5 must move monotonically with theta over the range", src)
        sep = np.hypot(self.p1[0], self.p1[1])
        if sep <= 0.0:
            raise ParameterError("frame.x1", self.p1, "points 1 and 2 must differ", src)


#: the declared fields of a rigid DSA-380 parameter file (figures 2.3-2.5 of the thesis
#: name the points and bars)
ROOT = Section("", [
    Field("name", "string", default="dsa380-rigid", doc="model name"),
    Field("description", "string", default="", doc="free text"),
], extra=("frame", "bars", "links", "springs", "damper", "options", "variant", "calibration"),
    doc="`calibration` is a free table the calibration script writes (not read).")
FRAME = Section("frame", [
    Field("base_height", unit="m", nonnegative=True, doc="height of the roof frame's origin "
          "(point 2) above the rail"),
    Field("x1", unit="m", doc="point 1 (lower-arm pivot) relative to point 2, x"),
    Field("y1", unit="m", doc="and y", rule="points 1 and 2 differ"),
    Field("theta_min", unit="rad", doc="lower-arm stop, low",
          rule="the loops (A.1) close and point 5 moves monotonically over the range"),
    Field("theta_max", unit="rad", doc="lower-arm stop, high"),
    Field("working_height", unit="m", positive=True, doc="contact height of the static start"),
    Field("g", unit="m/s^2", default=9.81, nonnegative=True, doc="gravity"),
])
BAR = Section("bars.barN", [
    Field("L", unit="m", positive=True, doc="length"),
    Field("m", unit="kg", positive=True, doc="mass"),
    Field("I", unit="kg m^2", nonnegative=True, doc="inertia about the centre of gravity"),
    Field("LG", unit="m", default=0.0, nonnegative=True, doc="centre of gravity: distance "
          "from the bar's reference end"),
    Field("thetaG", unit="rad", default=0.0, doc="and angle (Fig. 2.5)"),
], title="`[bars.bar1]` ... `[bars.bar7]`", extra=("tube",),
    doc="Seven rigid bars; `tube` (outer and inner diameter) is read by the flexible model.")
LINKS = Section("links", [
    Field("theta34", unit="rad", doc="angle between bars 3 and 4 (rigid joint at point 4)"),
    Field("r", unit="m", positive=True, doc="|1-6|: point 6 on bar 1 (head-levelling rod "
          "pivot)"),
    Field("theta_r", unit="rad", doc="angle between bar 1 and segment 1-6"),
    Field("lower_branch", default=1.0, doc="assembly mode (+1 or -1) of loop fixed-1-2-3"),
    Field("upper_branch", default=1.0, doc="assembly mode (+1 or -1) of loop 1-4-5-6"),
])
SPRINGS = Section("springs", [
    Field("k_r", unit="N m/rad", nonnegative=True, doc="torsional spring at joint 1"),
    Field("theta_r0", unit="rad", doc="its unloaded angle"),
    Field("k_l", unit="N/m", positive=True, doc="each collector spring, point 5 to the "
          "collector ends 11/12"),
    Field("l0", unit="m", nonnegative=True, doc="their unloaded length"),
])
DAMPER = Section("damper", [
    Field("c", unit="N s/m", nonnegative=True, doc="damping coefficient"),
    Field("L1p", unit="m", positive=True, doc="lever 1-1p on bar 1"),
    Field("theta_1p", unit="rad", doc="angle between bar 1 and the lever"),
    Field("x13", unit="m", doc="fixed damper end 13 relative to point 2, x"),
    Field("y13", unit="m", doc="and y"),
])
VARIANT = Section("variant", [
    Field("pitch_lock", "boolean", default=False, doc="lock the collector pitch (A.37): "
          "three coordinates instead of four"),
], doc="Optional table.")


def _read_bar(t: Table, name: str) -> Bar:
    s = t.sub(name)
    BAR.check_keys(s)
    return Bar(**{f.name: f.read(s) for f in BAR.fields})


def read_parameters(path: str | Path) -> tuple[Dsa380Parameters, Table, dict]:
    """Read and validate a DSA-380 parameter file (TOML)."""
    source = str(path)
    data = load_toml(path)
    root = Table(data, source)
    ROOT.check_keys(root)
    fr = root.sub("frame")
    FRAME.check_keys(fr)
    bars_t = root.sub("bars")
    bars_t.unknown_keys({f"bar{i}" for i in range(1, 8)})
    bars = [_read_bar(bars_t, f"bar{i}") for i in range(1, 8)]
    ln = root.sub("links")
    LINKS.check_keys(ln)
    sp = root.sub("springs")
    SPRINGS.check_keys(sp)
    dp = root.sub("damper")
    DAMPER.check_keys(dp)
    params = Dsa380Parameters(
        base_height=FRAME.read(fr, "base_height"),
        p1=(FRAME.read(fr, "x1"), FRAME.read(fr, "y1")),
        p13=(DAMPER.read(dp, "x13"), DAMPER.read(dp, "y13")),
        bars=bars,
        theta34=LINKS.read(ln, "theta34"), r=LINKS.read(ln, "r"),
        theta_r=LINKS.read(ln, "theta_r"),
        L1p=DAMPER.read(dp, "L1p"), theta_1p=DAMPER.read(dp, "theta_1p"),
        lower_branch=LINKS.read(ln, "lower_branch"), upper_branch=LINKS.read(ln, "upper_branch"),
        k_r=SPRINGS.read(sp, "k_r"), theta_r0=SPRINGS.read(sp, "theta_r0"),
        k_l=SPRINGS.read(sp, "k_l"), l0=SPRINGS.read(sp, "l0"),
        c=DAMPER.read(dp, "c"), g=FRAME.read(fr, "g"),
        theta_min=FRAME.read(fr, "theta_min"), theta_max=FRAME.read(fr, "theta_max"),
        working_height=FRAME.read(fr, "working_height"),
        source=source)
    params.validate()
    variant = root.sub("variant", required=False)
    VARIANT.check_keys(variant)
    flags = {"pitch_lock": VARIANT.read(variant, "pitch_lock")}
    return params, root, flags


class Dsa380Model(TorqueActuatedPantograph):
    """Rigid-body DSA-380 pantograph, q = (theta, x10, y10, theta7) (2.1).

    ``pitch_lock=True`` removes theta7 (A.37: theta7 = 0 and its derivatives vanish), leaving
    q = (theta, x10, y10). The actuation torque on bar 1 is set by :meth:`static_equilibrium`
    ((2.14), stored in :attr:`torque`); with ``options.ramp`` it is
    M_low + ramp.factor(t) (M0 - M_low) (thesis 3.3.1, only the torque is weighted)."""

    name = "dsa380-rigid"

    def __init__(self, params: Dsa380Parameters, options: PantographOptions | None = None,
                 pitch_lock: bool = False, name: str = "dsa380-rigid"):
        super().__init__(options)
        params.validate()
        self.params = params
        self.name = name
        self.pitch_lock = bool(pitch_lock)
        self.n_dofs = 3 if self.pitch_lock else 4
        self.dof_names = ("theta", "x10", "y10") if self.pitch_lock else \
            ("theta", "x10", "y10", "theta7")
        self._P = params.vector()
        self._vec = np.zeros((3, 4))
        self._mat = np.zeros((4, 4, 4))
        self._q4 = np.zeros(4)
        self._v4 = np.zeros(4)
        self._a4 = np.zeros(4)
        self._gradient = np.zeros(self.n_dofs)
        self._gradient[2] = 1.0
        self.torque = 0.0
        self.torque_lowered = None
        self.q_equilibrium = None
        self._equilibrium_at_working_height(params.working_height, params.source)

    # ------------------------------------------------------------------ kernel access
    def _kernel(self, q, v, a, F, M_act, F_aero, f_r, k_t, one_way):
        n = self.n_dofs
        q4, v4, a4 = self._q4, self._v4, self._a4
        q4[:n] = q
        v4[:n] = v
        a4[:n] = a
        if n == 3:
            q4[3] = v4[3] = a4[3] = 0.0
        ok = kin.evaluate_kernel(self._P, q4, v4, a4, F, M_act, F_aero, f_r, k_t, one_way,
                                 self._vec, self._mat)
        if not ok > 0.0:
            raise ParameterError("theta", float(q4[0]),
                                 "the mechanism loops (A.1) cannot be closed at this angle",
                                 self.name)
        return self._vec, self._mat

    def evaluate(self, t, q, v, a, inputs, tangent=True):
        """Residual pieces and exact tangents (A.36), (3.27)-(3.34), (B.19)."""
        F = 0.0 if inputs is None else reject_nonfinite_force(inputs[0])
        o = self.options
        vec, mat = self._kernel(np.asarray(q, float), np.asarray(v, float),
                                np.asarray(a, float), F, self.actuation_torque(t),
                                o.aero_force, o.friction_force, o.friction_smoothing,
                                bool(o.one_way_damper))
        n = self.n_dofs
        if not tangent:
            return Evaluation(f_inertia=vec[0, :n].copy(), f_rest=vec[1, :n].copy())
        return Evaluation(f_inertia=vec[0, :n].copy(), f_rest=vec[1, :n].copy(),
                          mass=mat[0, :n, :n].copy(), inertia_q=mat[1, :n, :n].copy(),
                          damping=mat[2, :n, :n].copy(), stiffness=mat[3, :n, :n].copy())

    # ------------------------------------------------------------------ port contract
    def contact_height(self, q):
        return float(q[2])

    def contact_height_gradient(self, q):
        return self._gradient

    # ------------------------------------------------------------------ post-processing
    def energies(self, q, v, inputs=None) -> dict:
        """Kinetic energy T (A.7), potential V (A.10) (gravity from the rail and springs) and
        the damper power -c v_a^2 (2.33) at (q, v); used by the energy balance (2.30)-(2.34)."""
        n = self.n_dofs
        F = 0.0 if inputs is None else float(inputs[0])
        o = self.options
        vec, _ = self._kernel(np.asarray(q, float), np.asarray(v, float), np.zeros(n), F, 0.0,
                              0.0, o.friction_force, o.friction_smoothing,
                              bool(o.one_way_damper))
        return {"T": float(vec[2, 0]), "V": float(vec[2, 1]),
                "damper_power": float(vec[2, 2]), "friction_force": float(vec[2, 3])}

    def points(self, q) -> dict:
        """Absolute positions of the named points (for plots and checks)."""
        pts = kin.mechanism_points(self._P, float(q[0]))
        names = ("1", "2", "3", "4", "5", "6", "5b", "1p")
        out = {k: pts[i].copy() for i, k in enumerate(names)}
        th7 = 0.0 if self.pitch_lock else float(q[3])
        half = 0.5 * self.params.bars[6].L
        p10 = np.array([q[1], q[2]], float)
        e7 = np.array([math.cos(th7), math.sin(th7)])
        out["10"] = p10
        out["11"] = p10 - half * e7
        out["12"] = p10 + half * e7
        out["13"] = np.array([self._P[kin.X13], self._P[kin.Y13]])
        return out

    def point5(self, theta: float) -> np.ndarray:
        """(x5, y5, x5', y5', x5'', y5'') at theta."""
        ok, A, V, p5 = kin.mechanism_terms(self._P, float(theta))
        return p5

    def generalized_inertia(self, theta: float) -> np.ndarray:
        """(A, A', A'') of the mechanism (A.7)."""
        ok, A, V, p5 = kin.mechanism_terms(self._P, float(theta))
        return A

    #: travel [m] allowed beyond the mechanism's reachable heights (the collector's springs)
    HEIGHT_MARGIN = 0.5

    def height_range(self) -> tuple[float, float]:
        """The mechanism's reachable heights between its stops, unloaded and under twice the
        mean uplift, widened by :attr:`HEIGHT_MARGIN`."""
        lo0, hi0 = self.reachable_heights(0.0)
        lo1, hi1 = self.reachable_heights(2.0 * self.options.mean_uplift)
        return (min(lo0, lo1) - self.HEIGHT_MARGIN, max(hi0, hi1) + self.HEIGHT_MARGIN)

    def reachable_heights(self, contact_force: float | None = None) -> tuple[float, float]:
        """Range of contact heights the mechanism can reach between its stops."""
        F = self.options.mean_uplift if contact_force is None else float(contact_force)
        dx, dy, th7 = self._collector_offset(F - self.options.aero_force)
        ya = self.point5(self.params.theta_min)[1] + dy
        yb = self.point5(self.params.theta_max)[1] + dy
        return (min(ya, yb), max(ya, yb))

    def mode_label(self, shape, mass) -> str:
        """Dominant coordinate of a mode in the kinetic-energy sense, named as in Table 2.2."""
        energy = np.abs(np.real(shape) * (np.asarray(mass) @ np.real(shape)))
        return MODE_LABELS[self.dof_names[int(np.argmax(energy))]]

    # ------------------------------------------------------------------ equilibrium
    def _collector_offset(self, load: float):
        """Collector equilibrium relative to point 5 under a net downward load on point 10
        (contact force minus aero uplift): (x10 - x5, y10 - y5, theta7); (2.12) generalised
        to the full collector (springs, weight and its offset L_G7)."""
        p = self.params
        th = 0.5 * (p.theta_min + p.theta_max)
        p5 = self.point5(th)
        half = 0.5 * p.bars[6].L
        W = p.bars[6].m * p.g + load
        # (2.12): 2 k_l (l - l0) z / l = W, l = sqrt(z^2 + (L7/2)^2); z = y5 - y10
        try:
            z = self._solve_drop(W, half)
        except ParameterError as exc:
            raise self._uncarried(exc, W, half) from None
        n = self.n_dofs
        q = np.zeros(n)
        q[0] = th
        q[1] = p5[0]
        q[2] = p5[1] - z
        idx = [1, 2] if n == 3 else [1, 2, 3]
        zero = np.zeros(n)
        for it in range(60):
            vec, mat = self._kernel(q, zero, zero, load, 0.0, 0.0, 0.0, 1.0, False)
            r = vec[1, idx]
            Kc = mat[3][np.ix_(idx, idx)]
            dq = np.linalg.solve(Kc, -r)
            # limit the pitch step (the collector is soft in pitch)
            if n == 4 and abs(dq[2]) > 0.2:
                dq *= 0.2 / abs(dq[2])
            q[idx] += dq
            if np.max(np.abs(dq)) < 1e-14 * (1.0 + np.max(np.abs(q[idx]))):
                break
        vec, mat = self._kernel(q, zero, zero, load, 0.0, 0.0, 0.0, 1.0, False)
        res = np.max(np.abs(vec[1, idx]))
        if not res < 1e-8 * max(1.0, abs(W)):
            raise ParameterError("contact_force", load,
                                 f"no collector equilibrium found (residual {res:.3g} N)",
                                 self.name)
        th7 = 0.0 if n == 3 else float(q[3])
        return float(q[1] - p5[0]), float(q[2] - p5[1]), th7

    def _uncarried(self, exc: ParameterError, W: float, half: float) -> ParameterError:
        """The springs' refusal of the collector load ``W``, naming the speed when it is the
        aerodynamic uplift at the speed the springs cannot carry (the load without it they
        can)."""
        o = self.options
        if o.aero_force == 0.0:
            return exc
        try:
            self._solve_drop(W + o.aero_force, half)
        except ParameterError:
            return exc
        return ParameterError(
            "speed_kmh", o.speed_kmh,
            f"the aerodynamic uplift at this speed, {o.aero_force:.3g} N (aero_c1 v + aero_c2 "
            f"v^2), leaves the collector a net load of {W:.3g} N that its springs "
            f"(springs.k_l = {self.params.k_l:g} N/m) cannot carry")

    def _solve_drop(self, W: float, half: float) -> float:
        """Scalar (2.12) for the symmetric collector drop z = y5 - y10 (bisection).

        Beyond the length where the springs are unloaded (|z| > z_s) the vertical spring force
        grows monotonically, so the hanging root (|z| > z_s, sign of W) is unique."""
        p = self.params
        k, l0 = p.k_l, p.l0
        zs = math.sqrt(max(l0 * l0 - half * half, 0.0))
        if W == 0.0:
            return zs

        def fz(z):
            ll = math.hypot(z, half)
            return 2.0 * k * (ll - l0) * z / ll - W

        s = 1.0 if W > 0 else -1.0
        a, b = s * zs, s * (zs + 1.0)
        while fz(b) * s < 0.0:
            b = s * (abs(b) * 2.0)
            if abs(b) > 1e3:
                raise ParameterError("springs.k_l", k, "collector springs cannot carry the "
                                     f"load {W:.6g} N", p.source)
        for _ in range(200):
            m = 0.5 * (a + b)
            if fz(m) * s < 0.0:
                a = m
            else:
                b = m
        return 0.5 * (a + b)

    def _theta_for_y5(self, y5: float, height: float, F: float) -> float:
        p = self.params
        ya = self.point5(p.theta_min)[1]
        yb = self.point5(p.theta_max)[1]
        if not (min(ya, yb) <= y5 <= max(ya, yb)):
            lo, hi = self.reachable_heights(F)
            raise ParameterError("height", height,
                                 f"the mechanism cannot reach this contact height: reachable "
                                 f"range {lo:.4f} .. {hi:.4f} m above the rail "
                                 f"(lower-arm stops {p.theta_min:.4f} .. {p.theta_max:.4f} rad)",
                                 self.name)
        a, b = p.theta_min, p.theta_max
        th = a + (b - a) * (y5 - ya) / (yb - ya)
        for _ in range(100):
            p5 = self.point5(th)
            f = p5[1] - y5
            if abs(f) < 1e-14:
                break
            if (f > 0) == (yb > ya):
                b = th
            else:
                a = th
            step = th - f / p5[3]
            th = step if min(a, b) < step < max(a, b) else 0.5 * (a + b)
        return th

    @property
    def working_height(self) -> float:
        return self.params.working_height

    def equilibrium(self, F: float, height: float) -> tuple[np.ndarray, float]:
        """(2.12)-(2.14): collector drop, theta from (2.13), torque M0 from (2.14)."""
        o = self.options
        net = F - o.aero_force
        dx, dy, th7 = self._collector_offset(net)
        theta = self._theta_for_y5(height - dy, height, F)
        p5 = self.point5(theta)
        n = self.n_dofs
        q0 = np.zeros(n)
        q0[0] = theta
        q0[1] = p5[0] + dx
        q0[2] = height
        if n == 4:
            q0[3] = th7
        zero = np.zeros(n)
        vec, _ = self._kernel(q0, zero, zero, F, 0.0, o.aero_force, 0.0, 1.0, False)
        # (2.14) generalised: the torque balances gravity, springs and the transmitted load
        M0 = float(vec[1, 0])
        return q0, M0


def load_dsa380(path: str | Path | None = None, options: PantographOptions | None = None,
                pitch_lock: bool | None = None) -> Dsa380Model:
    """Load a rigid DSA-380 parameter file (None: the preset ``dsa380-rigid.toml``)."""
    path = PRESET_FILE if path is None else Path(path)
    params, root, flags = read_parameters(path)
    if options is None:
        options = PantographOptions.from_table(root.sub("options", required=False))
    lock = flags["pitch_lock"] if pitch_lock is None else bool(pitch_lock)
    name = ROOT.read(root, "name")
    return Dsa380Model(params, options, pitch_lock=lock, name=name)

"""Flexible-bar DSA-380 pantograph: in-house substitute for the thesis' ANSYS model (2.2).

Every bar of the rigid model (:mod:`pantocosim.pantograph.dsa380`, thesis 2.1.1) and the
massless links 8 (point 4 -> 6) and 9 (point 1 -> 1p) of thesis 2.2 are meshed with planar
ANCF beam elements (:mod:`pantocosim.pantograph.beam_ancf`) with the tube sections of thesis
Table 2.1, steel E = 210 GPa. Joints (thesis 2.2: "se acoplan los movimientos horizontal y
vertical de los nodos coincidentes"):

* pin joints share the node position, each bar keeps its own slope (independent rotations);
* welded joints (bars 3-4 at point 4; link 8 on bar 1 at point 4; link 9 on bar 1 at point 1)
  tie the slopes by a fixed rotation, r_x(b) = R(alpha) r_x(a);
* points 1, 2 (pivots) and 13 (damper end) are fixed to the roof frame.

All these constraints are linear, so the generalised coordinates (free node positions and
independent slopes) give every element's coordinates as e_k = T_k q + c_k and the mass matrix
is constant. The model's q is the DISPLACEMENT u = q_abs - q_ref of these coordinates from the
reference configuration q_ref (the rigid model's equilibrium at the working height, all bars
straight and unstrained): absolute positions ~5 m above the rail would otherwise put a
round-off floor of eps * 5 m * EA / l (~1e-6 N for steel) under every residual.

The collector springs k_l (A.11), the torsional spring k_r and actuation torque at joint 1
(acting on the slope of bar 1 at point 1, (2.14)), the damper 13-1p (A.13), collector friction
(2.15)-(2.17), aerodynamic uplift and the contact force on point 10 are those of the rigid
model, read from the same parameter file. Bars 1-7 take the rigid bars' masses
(density m / (A L), checked against steel), so that as E grows the model converges to the rigid
one; the collector's calibrated pitch inertia beyond its tube's is a rotary inertia at point 10.

Residual convention of :mod:`pantocosim.core.model`: f_inertia = M a (M constant),
f_rest = dU/dq + dV_springs/dq - Q_gravity + damper + friction - M_act dphi1/dq
+ (F - F_aero) dy10/dq.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, replace
from pathlib import Path

import numpy as np
import scipy.linalg as sla
from numba import njit

from ..core.errors import ParameterError
from ..core.model import Evaluation
from ..core.params import Table, check_number, load_toml
from ..core.schema import OPTIONAL, Field, Section
from . import beam_ancf as beam
from .base import PantographOptions, TorqueActuatedPantograph, reject_nonfinite_force
from .dsa380 import Dsa380Model, read_parameters

DATA_DIR = Path(__file__).resolve().parent / "data"
PRESET_FILE = DATA_DIR / "dsa380-flexible.toml"

N_BARS = 9
#: (start point, end point) of bars 1..9 (thesis Fig. 2.2; links 8, 9 of thesis 2.2)
BAR_ENDS = (("1", "4"), ("2", "3"), ("3", "4"), ("4", "5"), ("6", "5b"), ("5b", "5"),
            ("11", "12"), ("4", "6"), ("1", "1p"))
BAR_NAMES = ("lower arm", "lower control rod", "upper-arm lever", "upper arm",
             "head-levelling rod", "head bracket", "collector", "link 4-6", "link 1-1p")
GROUND = ("1", "2")
STEEL_E = 210e9
STEEL_RHO = 7850.0


@dataclass
class FlexibleParameters:
    """Material, tube sections (thesis Table 2.1) and mesh of the flexible DSA-380; the
    geometry, masses, springs and damper are those of the rigid parameter set ``rigid``."""

    rigid: object                    # Dsa380Parameters
    E: float = STEEL_E
    rho: float = STEEL_RHO
    link_density_ratio: float = 1e-3  # links 8, 9: nominally massless (thesis 2.2)
    sections: tuple = ()             # (r_int, r_ext) of bars 1..9 [m]
    mesh: tuple = ()                 # elements per bar 1..9
    mass_tolerance: float = 0.02
    source: str | None = None

    def area(self, b: int) -> float:
        ri, ro = self.sections[b]
        return math.pi * (ro * ro - ri * ri)

    def second_moment(self, b: int) -> float:
        ri, ro = self.sections[b]
        return math.pi * (ro ** 4 - ri ** 4) / 4.0

    def validate(self) -> None:
        src = self.source
        check_number("material.E", self.E, source=src, positive=True)
        check_number("material.rho", self.rho, source=src, positive=True)
        check_number("material.link_density_ratio", self.link_density_ratio, source=src,
                     positive=True)
        if len(self.sections) != N_BARS or len(self.mesh) != N_BARS:
            raise ParameterError("sections/mesh", (len(self.sections), len(self.mesh)),
                                 f"need {N_BARS} bars", src)
        for b, (ri, ro) in enumerate(self.sections):
            name = f"sections.bar{b + 1}"
            check_number(name + "[0]", ri, source=src, nonnegative=True)
            check_number(name + "[1]", ro, source=src, positive=True)
            if not ri < ro:
                raise ParameterError(name, [ri, ro], "need r_int < r_ext", src)
        for b, n in enumerate(self.mesh):
            if isinstance(n, bool) or not isinstance(n, int) or n < 1:
                raise ParameterError(f"mesh.bar{b + 1}", n, "must be an integer >= 1", src)
        if self.mesh[6] % 2:
            raise ParameterError("mesh.bar7", self.mesh[6],
                                 "must be even (point 10, the collector centre, is a node)", src)
        rp = self.rigid
        for b in range(7):
            bar = rp.bars[b]
            rho_b = bar.m / (self.area(b) * bar.L)
            if abs(rho_b / self.rho - 1.0) > self.mass_tolerance:
                raise ParameterError(
                    f"sections.bar{b + 1}", list(self.sections[b]),
                    f"tube mass rho A L = {self.rho * self.area(b) * bar.L:.4g} kg differs from "
                    f"the rigid bar's m = {bar.m:.4g} kg by more than "
                    f"{100 * self.mass_tolerance:g} % (thesis (2.29))", src)
            want_lg = 0.0 if b == 6 else 0.5 * bar.L
            if abs(bar.LG - want_lg) > 1e-9 * bar.L or abs(bar.thetaG) > 1e-12:
                raise ParameterError(f"bars.bar{b + 1}.LG", bar.LG,
                                     "the flexible model needs uniform bars (CoG at mid-length)",
                                     src)
            tube = bar.m * (bar.L ** 2 / 12.0 + self.second_moment(b) / self.area(b))
            if b < 6 and abs(bar.I / tube - 1.0) > 0.01:
                raise ParameterError(f"bars.bar{b + 1}.I", bar.I,
                                     f"differs from the uniform tube's {tube:.6g} kg m2 "
                                     "(the beam carries its own inertia)", src)
            if b == 6 and bar.I < tube * (1.0 - 1e-12):
                raise ParameterError("bars.bar7.I", bar.I,
                                     f"below the collector tube's own {tube:.6g} kg m2", src)


#: the declared fields of a flexible DSA-380 parameter file
ROOT = Section("", [
    Field("name", "string", default="dsa380-flexible", doc="model name"),
    Field("description", "string", default="", doc="free text"),
    Field("rigid_model", "file", doc="rigid DSA-380 parameter file giving the geometry, "
          "relative to this file"),
], extra=("frame", "material", "sections", "mesh", "options"))
FRAME = Section("frame", [
    Field("working_height", unit="m", default=OPTIONAL, positive=True,
          doc="contact height of the static start (default: the rigid model's)"),
], doc="Optional table.")
MATERIAL = Section("material", [
    Field("E", unit="Pa", positive=True, doc="Young's modulus of the tubes"),
    Field("rho", unit="kg/m^3", positive=True, doc="density of the tubes"),
    Field("link_density_ratio", default=1e-3, positive=True,
          doc="density of the joint links relative to rho"),
    Field("mass_tolerance", default=0.02, positive=True,
          doc="accepted relative difference between a tube's mass and the rigid bar's"),
])
SECTIONS = Section("sections", [
    Field("barN", "numbers", unit="m", length=2, nonnegative=True,
          doc="[r_int, r_ext] of bar N's tube, N = 1 ... 9 (thesis Table 2.1)"),
])
MESH = Section("mesh", [
    Field("barN", "integer", minimum=1, doc="beam elements of bar N, N = 1 ... 9"),
])


def read_flexible(path: str | Path):
    """Read and validate a flexible DSA-380 file; returns (FlexibleParameters, root Table)."""
    path = Path(path)
    source = str(path)
    root = Table(load_toml(path), source)
    ROOT.check_keys(root)
    rel = ROOT.read(root, "rigid_model")
    rigid_path = Path(rel) if Path(rel).is_absolute() else path.parent / rel
    if not rigid_path.exists():
        raise ParameterError("rigid_model", rel, "no such parameter file", source)
    rigid, _, flags = read_parameters(rigid_path)
    fr = root.sub("frame", required=False)
    FRAME.check_keys(fr)
    if fr.has("working_height"):
        rigid.working_height = FRAME.read(fr, "working_height")
    mat = root.sub("material")
    MATERIAL.check_keys(mat)
    sec = root.sub("sections")
    sec.unknown_keys({f"bar{i}" for i in range(1, N_BARS + 1)})
    mesh = root.sub("mesh")
    mesh.unknown_keys({f"bar{i}" for i in range(1, N_BARS + 1)})
    params = FlexibleParameters(
        rigid=rigid,
        **{f.name: f.read(mat) for f in MATERIAL.fields},
        sections=tuple(tuple(replace(SECTIONS["barN"], name=f"bar{i}").read(sec))
                       for i in range(1, N_BARS + 1)),
        mesh=tuple(replace(MESH["barN"], name=f"bar{i}").read(mesh)
                   for i in range(1, N_BARS + 1)),
        source=source)
    params.validate()
    return params, root


# ---------------------------------------------------------------------------------------
# numba kernel: elements + springs, damper, torsion/actuation, friction, contact

# integer slots
I_P5, I_P11, I_P12, I_P1P, I_S1, I_Y10, I_Y5, I_ONEWAY = range(8)
# real slots
R_KL, R_L0, R_C, R_X13, R_Y13, R_KR, R_TH0, R_MACT, R_FNET, R_FR, R_KT = range(11)


@njit(cache=True, error_model="numpy")
def _spring(q, ga, gb, k, l0, f, K, with_K):
    dx = q[gb] - q[ga]
    dy = q[gb + 1] - q[ga + 1]
    ll = math.sqrt(dx * dx + dy * dy)
    ux = dx / ll
    uy = dy / ll
    T = k * (ll - l0)
    f[gb] += T * ux
    f[gb + 1] += T * uy
    f[ga] -= T * ux
    f[ga + 1] -= T * uy
    if with_K:
        u = (ux, uy)
        for i in range(2):
            for j in range(2):
                kij = k * u[i] * u[j] + T / ll * ((1.0 if i == j else 0.0) - u[i] * u[j])
                K[gb + i, gb + j] += kij
                K[ga + i, ga + j] += kij
                K[gb + i, ga + j] -= kij
                K[ga + i, gb + j] -= kij
    return 0.5 * k * (ll - l0) * (ll - l0)


@njit(cache=True, error_model="numpy")
def assemble(u, v, q_ref, q, ints, reals, pg, pR, pc0, E0, length, EA, EI, xi_g, w_g, Qg,
             dE, Fe, Ke, Ue, f, K, C, extra, with_K):
    """f_rest (and with_K its exact tangents K = df/du, C = df/dv) of the flexible model at
    the displacement u from the reference configuration q_ref (q = q_ref + u is filled in).

    extra = (spring energy, torsion energy, damper power, friction force)."""
    n = u.shape[0]
    for i in range(n):
        q[i] = q_ref[i] + u[i]
    for i in range(n):
        f[i] = -Qg[i]
    if with_K:
        for i in range(n):
            for j in range(n):
                K[i, j] = 0.0
                C[i, j] = 0.0
    # ---- beam elements (ANCF), vectorised
    beam.gather(u, pg, pR, pc0, dE)
    beam.elastic_elements(E0, dE, length, EA, EI, xi_g, w_g, Fe, Ke, Ue)
    beam.scatter_add(pg, pR, Fe, Ke, f, K, with_K)
    # ---- collector springs point 5 -> 11, 12 (A.11)
    g5 = ints[I_P5]
    Vs = _spring(q, g5, ints[I_P11], reals[R_KL], reals[R_L0], f, K, with_K)
    Vs += _spring(q, g5, ints[I_P12], reals[R_KL], reals[R_L0], f, K, with_K)
    # ---- torsional spring k_r and actuation torque on the slope of bar 1 at joint 1 (2.14)
    gs = ints[I_S1]
    a = q[gs]
    b = q[gs + 1]
    s = a * a + b * b
    phi = math.atan2(b, a)
    g0 = -b / s
    g1 = a / s
    mom = reals[R_KR] * (phi - reals[R_TH0]) - reals[R_MACT]
    f[gs] += mom * g0
    f[gs + 1] += mom * g1
    if with_K:
        h00 = 2.0 * a * b / (s * s)
        h01 = (b * b - a * a) / (s * s)
        kr = reals[R_KR]
        K[gs, gs] += kr * g0 * g0 + mom * h00
        K[gs, gs + 1] += kr * g0 * g1 + mom * h01
        K[gs + 1, gs] += kr * g1 * g0 + mom * h01
        K[gs + 1, gs + 1] += kr * g1 * g1 - mom * h00
    Vt = 0.5 * reals[R_KR] * (phi - reals[R_TH0]) ** 2
    # ---- damper between fixed point 13 and point 1p (A.13)-(A.19); one-way: only while
    #      point 5 moves down
    gp = ints[I_P1P]
    cd = reals[R_C]
    if ints[I_ONEWAY] != 0 and v[ints[I_Y5]] > 0.0:
        cd = 0.0
    dx = q[gp] - reals[R_X13]
    dy = q[gp + 1] - reals[R_Y13]
    ll = math.sqrt(dx * dx + dy * dy)
    ux = dx / ll
    uy = dy / ll
    ldot = ux * v[gp] + uy * v[gp + 1]
    f[gp] += cd * ldot * ux
    f[gp + 1] += cd * ldot * uy
    if with_K:
        u = (ux, uy)
        pv0 = v[gp] - ldot * ux  # (I - u u^T) v
        pv1 = v[gp + 1] - ldot * uy
        pv = (pv0, pv1)
        for i in range(2):
            for j in range(2):
                C[gp + i, gp + j] += cd * u[i] * u[j]
                K[gp + i, gp + j] += cd / ll * (ldot * ((1.0 if i == j else 0.0) - u[i] * u[j])
                                                + u[i] * pv[j])
    # ---- collector friction (2.15)-(2.17): v_r = y10dot - y5dot
    iy10 = ints[I_Y10]
    iy5 = ints[I_Y5]
    f_roz = 0.0
    fr_amp = reals[R_FR]
    if fr_amp > 0.0:
        kt = reals[R_KT]
        vr = v[iy10] - v[iy5]
        f_roz = fr_amp * (2.0 / math.pi) * math.atan(vr / kt)
        df = fr_amp * (2.0 / math.pi) / (kt + vr * vr / kt)
        f[iy10] += f_roz
        f[iy5] -= f_roz
        if with_K:
            C[iy10, iy10] += df
            C[iy10, iy5] -= df
            C[iy5, iy10] -= df
            C[iy5, iy5] += df
    # ---- contact force (down) minus aerodynamic uplift on point 10
    f[iy10] += reals[R_FNET]
    extra[0] = Vs
    extra[1] = Vt
    extra[2] = -cd * ldot * ldot
    extra[3] = f_roz
    return 0


@njit(cache=True, error_model="numpy")
def matvec(A, x, out):
    """out = A x with a fixed summation order (bitwise reproducible, unlike BLAS whose SIMD
    paths depend on memory alignment: an FMU must equal the stand-alone run bit for bit)."""
    n = A.shape[0]
    for i in range(n):
        s = 0.0
        for j in range(A.shape[1]):
            s += A[i, j] * x[j]
        out[i] = s
    return out


@njit(cache=True, error_model="numpy")
def lu_factor(A):
    """LU with partial pivoting (Doolittle, fixed operation order, see :func:`matvec`)."""
    n = A.shape[0]
    LU = A.copy()
    piv = np.arange(n)
    for k in range(n):
        p = k
        big = abs(LU[k, k])
        for i in range(k + 1, n):
            if abs(LU[i, k]) > big:
                big = abs(LU[i, k])
                p = i
        if p != k:
            for j in range(n):
                tmp = LU[k, j]
                LU[k, j] = LU[p, j]
                LU[p, j] = tmp
            t = piv[k]
            piv[k] = piv[p]
            piv[p] = t
        d = LU[k, k]
        if d == 0.0:
            continue
        for i in range(k + 1, n):
            lik = LU[i, k] / d
            LU[i, k] = lik
            if lik != 0.0:
                for j in range(k + 1, n):
                    LU[i, j] -= lik * LU[k, j]
    return LU, piv


@njit(cache=True, error_model="numpy")
def lu_solve(LU, piv, b):
    n = LU.shape[0]
    x = np.empty(n)
    for i in range(n):
        x[i] = b[piv[i]]
    for i in range(n):
        s = x[i]
        for j in range(i):
            s -= LU[i, j] * x[j]
        x[i] = s
    for i in range(n - 1, -1, -1):
        s = x[i]
        for j in range(i + 1, n):
            s -= LU[i, j] * x[j]
        x[i] = s / LU[i, i]
    return x


def dense_solver(S):
    """``solve(rhs)`` for a dense matrix S by :func:`lu_factor` (reproducible bit for bit)."""
    LU, piv = lu_factor(np.ascontiguousarray(S, dtype=float))
    if not np.all(np.isfinite(LU)) or np.any(np.diag(LU) == 0.0):
        raise np.linalg.LinAlgError("singular Newton matrix")

    def solve(rhs):
        return lu_solve(LU, piv, np.ascontiguousarray(rhs, dtype=float))

    return solve


# ---------------------------------------------------------------------------------------

class _Dofs:
    def __init__(self):
        self.n = 0
        self.names: list[str] = []

    def pair(self, name: str, suffix=("x", "y")) -> int:
        g = self.n
        self.n += 2
        self.names += [f"u_{name}_{suffix[0]}", f"u_{name}_{suffix[1]}"]
        return g


def _rot(alpha: float) -> np.ndarray:
    c, s = math.cos(alpha), math.sin(alpha)
    return np.array([[c, -s], [s, c]])


class Dsa380FlexibleModel(TorqueActuatedPantograph):
    """Flexible-bar DSA-380 (thesis 2.2) on the HHT interface; same ports, options, springs,
    damper and actuation torque (with ramp, 3.3.1) as :class:`Dsa380Model`."""

    name = "dsa380-flexible"

    def __init__(self, params: FlexibleParameters, options: PantographOptions | None = None,
                 name: str = "dsa380-flexible"):
        super().__init__(options)
        params.validate()
        self.params = params
        self.name = name
        rp = params.rigid
        #: the rigid model with the same data: initial guesses and comparisons
        self.rigid = Dsa380Model(rp, self.options, pitch_lock=False, name="dsa380-rigid")
        self._build()
        self.torque = 0.0
        self.torque_lowered = None
        self.q_equilibrium = None
        self._equilibrium_at_working_height(rp.working_height, params.source)

    # ------------------------------------------------------------------ topology
    def _build(self) -> None:
        """The model's constant parts: DOFs, elements, mass and weight, work arrays, and the
        reference configuration (the rigid equilibrium at the working height)."""
        rig = self.rigid
        point_g = self._number_dofs(rig.points(rig.q_equilibrium), float(rig.q_equilibrium[0]))
        self._elements()
        self._mass_and_weight()
        self._buffers(point_g)
        # reference (stress-free) configuration: the rigid equilibrium at the working height;
        # the generalised coordinates are displacements from it
        self.q_ref = self._absolute_from_rigid(rig.q_equilibrium)
        self._E0 = np.zeros((self.n_elements, 8))
        beam.gather(self.q_ref, self._pg, self._pR, self._pc, self._E0)

    def _number_dofs(self, pts: dict, theta: float) -> dict[str, int]:
        """Bar lengths, welded slopes, the DOFs of every node (positions, slopes); returns
        the first DOF of each named point."""
        p, rp = self.params, self.params.rigid
        L = [b.L for b in rp.bars] + [float(np.linalg.norm(pts["6"] - pts["4"])), rp.L1p]
        self.bar_lengths = np.array(L)
        # welded slopes (bar, end) -> (bar, end, angle): r_x(b) = R(alpha) r_x(a)
        ang = lambda u: math.atan2(u[1], u[0])  # noqa: E731
        alpha8 = ang(pts["6"] - pts["4"]) - theta
        welds = {(3, 0): (2, 1, rp.theta34 - math.pi),
                 (7, 0): (0, 1, alpha8),
                 (8, 0): (0, 0, rp.theta_1p)}
        self.welds = welds
        dofs = _Dofs()
        point_g: dict[str, int] = {}
        for nm in ("3", "4", "5", "6", "5b", "1p", "11", "12"):
            point_g[nm] = dofs.pair("P" + nm)
        ground = {nm: pts[nm] for nm in GROUND}
        I2 = np.eye(2)
        slope: dict[tuple[int, int], tuple[int, np.ndarray]] = {}
        node_pos: list[list[tuple[int, np.ndarray]]] = []
        node_slope: list[list[tuple[int, np.ndarray]]] = []
        for b in range(N_BARS):
            n = p.mesh[b]
            s_name, e_name = BAR_ENDS[b]
            pos = []
            slo = []
            for k in range(n + 1):
                # position
                if k == 0 or k == n:
                    nm = s_name if k == 0 else e_name
                    pos.append((-1, ground[nm]) if nm in ground else (point_g[nm], None))
                else:
                    label = "P10" if (b == 6 and 2 * k == n) else f"bar{b + 1}_n{k}"
                    pos.append((dofs.pair(label), None))
                # slope
                end = 0 if k == 0 else (1 if k == n else -1)
                if end >= 0 and (b, end) in welds:
                    ab, aend, alpha = welds[(b, end)]
                    ga, Ra, _ = slope[(ab, aend)]
                    slo.append((ga, _rot(alpha) @ Ra, False))
                else:
                    label = "P10" if (b == 6 and 2 * k == n) else f"bar{b + 1}_n{k}"
                    slo.append((dofs.pair(label, ("dx", "dy")), I2, True))
                if end >= 0:
                    slope[(b, end)] = slo[-1]
            node_pos.append(pos)
            node_slope.append(slo)
        self.n_dofs = dofs.n
        self.dof_names = tuple(dofs.names)
        self.point_dofs = dict(point_g)
        self.point_dofs["10"] = node_pos[6][p.mesh[6] // 2][0]
        self.slope1 = node_slope[0][0][0]
        self.slope10 = node_slope[6][p.mesh[6] // 2][0]
        self.node_pos, self.node_slope = node_pos, node_slope
        return point_g

    def _elements(self) -> None:
        """The beam elements: their DOFs (with the welds' rotations and ground positions),
        lengths, stiffnesses, and element mass and gravity."""
        p, rp = self.params, self.params.rigid
        L = self.bar_lengths.tolist()
        node_pos, node_slope, I2 = self.node_pos, self.node_slope, np.eye(2)
        ne = int(sum(p.mesh))
        pg = np.full((ne, 4), -1, dtype=np.int64)
        pR = np.zeros((ne, 4, 2, 2))
        pc = np.zeros((ne, 4, 2))
        length = np.empty(ne)
        EA = np.empty(ne)
        EI = np.empty(ne)
        bar_of = np.empty(ne, dtype=np.int64)
        self.rho_bar = np.empty(N_BARS)
        Me = []
        Qe = []
        k = 0
        for b in range(N_BARS):
            n = p.mesh[b]
            A = p.area(b)
            I = p.second_moment(b)
            if b < 7:
                rho_b = rp.bars[b].m / (A * L[b])
            else:
                rho_b = p.rho * p.link_density_ratio
            self.rho_bar[b] = rho_b
            le = L[b] / n
            Mb = beam.element_mass(le, rho_b * A, rho_b * I)
            Qb = beam.element_gravity(le, rho_b * A, rp.g)
            for j in range(n):
                for slot, (g, R) in enumerate((node_pos[b][j], node_slope[b][j][:2],
                                               node_pos[b][j + 1], node_slope[b][j + 1][:2])):
                    if slot % 2 == 0 and g < 0:
                        pc[k, slot] = R  # ground position (stored in the R slot above)
                    else:
                        pg[k, slot] = g
                        pR[k, slot] = I2 if R is None else R
                length[k] = le
                EA[k] = p.E * A
                EI[k] = p.E * I
                bar_of[k] = b
                Me.append(Mb)
                Qe.append(Qb)
                k += 1
        self._pg, self._pR, self._pc = pg, pR, pc
        self._length, self._EA, self._EI = length, EA, EI
        self.bar_of = bar_of
        self.n_elements = ne
        self._Me = np.array(Me)
        self._Qe = np.array(Qe)

    def _mass_and_weight(self) -> None:
        """The constant mass matrix (with the collector's pitch inertia beyond its tube) and
        the weight vector."""
        p, rp = self.params, self.params.rigid
        n = self.n_dofs
        M = np.zeros((n, n))
        Qg = np.zeros(n)
        beam.scatter_add(self._pg, self._pR, self._Qe, self._Me, Qg, M, True)
        # collector pitch inertia beyond its tube (calibrated I7 of the rigid model)
        b7 = rp.bars[6]
        tube7 = b7.m * (b7.L ** 2 / 12.0 + p.second_moment(6) / p.area(6))
        self.collector_extra_inertia = max(b7.I - tube7, 0.0)
        s10 = self.slope10
        M[s10:s10 + 2, s10:s10 + 2] += self.collector_extra_inertia * np.eye(2)
        self.M = M
        self.M.flags.writeable = False
        self.Qg = Qg

    def _buffers(self, point_g: dict[str, int]) -> None:
        """Work arrays of the evaluation and the kernel's integer and real parameters."""
        rp, n = self.params.rigid, self.n_dofs
        ne = self.n_elements
        self._dE = np.zeros((ne, 8))
        self._q = np.zeros(n)
        self._pc0 = np.zeros_like(self._pc)
        self._Fe = np.zeros((ne, 8))
        self._Ke = np.zeros((ne, 8, 8))
        self._Ue = np.zeros((ne, 2))
        self._extra = np.zeros(4)
        self._xi = np.asarray(beam.GAUSS_XI, float)
        self._w = np.asarray(beam.GAUSS_W, float)
        self._ints = np.array([point_g["5"], point_g["11"], point_g["12"], point_g["1p"],
                               self.slope1, self.point_dofs["10"] + 1, point_g["5"] + 1, 0],
                              dtype=np.int64)
        P13 = np.array(rp.p13) + np.array([0.0, rp.base_height])
        self._reals = np.array([rp.k_l, rp.l0, rp.c, P13[0], P13[1], rp.k_r, rp.theta_r0,
                                0.0, 0.0, 0.0, 1.0])
        self._gradient = np.zeros(n)
        self._gradient[self.point_dofs["10"] + 1] = 1.0

    def absolute(self, u) -> np.ndarray:
        """Absolute node positions and slopes q_ref + u."""
        return self.q_ref + np.asarray(u, float)

    def q_from_rigid(self, q_rigid) -> np.ndarray:
        """Displacement u of the undeformed bars placed in the rigid model's configuration."""
        return self._absolute_from_rigid(q_rigid) - self.q_ref

    def _absolute_from_rigid(self, q_rigid) -> np.ndarray:
        pts = self.rigid.points(q_rigid)
        q = np.zeros(self.n_dofs)
        for b in range(N_BARS):
            s_name, e_name = BAR_ENDS[b]
            A, B = pts[s_name], pts[e_name]
            n = self.params.mesh[b]
            t = (B - A) / self.bar_lengths[b]
            for k in range(n + 1):
                g, _ = self.node_pos[b][k]
                if g >= 0:
                    q[g:g + 2] = A + (B - A) * k / n
                gs, _, owned = self.node_slope[b][k]
                if owned:
                    q[gs:gs + 2] = t
        return q

    # ------------------------------------------------------------------ evaluation
    def _assemble(self, q, v, F, M_act, with_K=True, aero=None, friction=True):
        o = self.options
        r = self._reals
        r[R_MACT] = M_act
        r[R_FNET] = F - (o.aero_force if aero is None else aero)
        r[R_FR] = o.friction_force if friction else 0.0
        r[R_KT] = o.friction_smoothing
        self._ints[I_ONEWAY] = 1 if o.one_way_damper else 0
        n = self.n_dofs
        f = np.empty(n)
        if with_K:
            K = np.empty((n, n))
            C = np.empty((n, n))
        else:
            K = C = np.empty((1, 1))
        assemble(q, v, self.q_ref, self._q, self._ints, r, self._pg, self._pR, self._pc0,
                 self._E0, self._length, self._EA, self._EI, self._xi, self._w, self.Qg,
                 self._dE, self._Fe, self._Ke, self._Ue, f, K, C, self._extra, with_K)
        if not np.all(np.isfinite(f)):
            raise ParameterError("q", "non-finite", "the flexible model cannot be evaluated "
                                 "here (degenerate element or spring)", self.name)
        return f, K, C

    def evaluate(self, t, q, v, a, inputs, tangent=True):
        """Residual pieces and exact tangents; the mass matrix is constant (inertia_q None)."""
        F = 0.0 if inputs is None else reject_nonfinite_force(inputs[0])
        q = np.asarray(q, float)
        v = np.asarray(v, float)
        f, K, C = self._assemble(q, v, F, self.actuation_torque(t), with_K=tangent)
        fin = matvec(self.M, np.ascontiguousarray(a, dtype=float), np.empty(self.n_dofs))
        if not tangent:
            return Evaluation(f_inertia=fin, f_rest=f)
        return Evaluation(f_inertia=fin, f_rest=f, mass=self.M, inertia_q=None, damping=C,
                          stiffness=K)

    def factorize(self, S):
        """Dense LU in numba: reproducible bit for bit across processes (FMU = stand-alone)."""
        return dense_solver(S)

    # ------------------------------------------------------------------ port contract
    def contact_height(self, q):
        i = self.point_dofs["10"] + 1
        return float(self.q_ref[i] + q[i])

    def contact_height_gradient(self, q):
        return self._gradient

    # ------------------------------------------------------------------ post-processing
    def point(self, q, name: str) -> np.ndarray:
        """Position of a named point (1, 2, 3, 4, 5, 6, 5b, 1p, 10, 11, 12)."""
        if name in GROUND:
            return self.rigid.points(self.rigid.q_equilibrium)[name].copy()
        g = self.point_dofs[name]
        return self.q_ref[g:g + 2] + np.asarray(q[g:g + 2], float)

    def bar_angle_at_1(self, q) -> float:
        """Angle of bar 1 at joint 1 (the flexible counterpart of theta)."""
        g = self.slope1
        qa = self.absolute(q)
        return math.atan2(qa[g + 1], qa[g])

    def bar_curves(self, q, per_element: int = 6) -> list[np.ndarray]:
        """Centre lines of bars 1..9 (list of (m, 2) arrays) for plots."""
        E = np.zeros((self.n_elements, 8))
        beam.gather(self.absolute(q), self._pg, self._pR, self._pc, E)
        out = [[] for _ in range(N_BARS)]
        xs = np.linspace(0.0, 1.0, per_element + 1)
        for k in range(self.n_elements):
            b = self.bar_of[k]
            for j, xi in enumerate(xs):
                if j == 0 and out[b]:
                    continue
                N, _, _ = beam.shape_derivatives(xi, self._length[k])
                out[b].append([N @ E[k, 0::2], N @ E[k, 1::2]])
        return [np.array(c) for c in out]

    def energies(self, q, v, inputs=None) -> dict:
        """Kinetic energy T, potential V (strain, gravity from the rail, springs) and the
        damper power (2.30)-(2.34)."""
        q = np.asarray(q, float)
        v = np.asarray(v, float)
        F = 0.0 if inputs is None else float(inputs[0])
        self._assemble(q, v, F, 0.0, with_K=False, aero=0.0)
        Vg = -float(np.sum(self._Qe * (self._E0 + self._dE)))
        return {"T": 0.5 * float(v @ self.M @ v),
                "V": float(self._Ue.sum()) + Vg + float(self._extra[0] + self._extra[1]),
                "strain": float(self._Ue.sum()), "damper_power": float(self._extra[2]),
                "friction_force": float(self._extra[3])}

    def strain_energy_by_bar(self, q, dq=None) -> np.ndarray:
        """Elastic energy of each bar at q, or (dq given) of the increment dq with the
        tangent element stiffness at q (mode classification)."""
        q = np.asarray(q, float)
        self._assemble(q, np.zeros(self.n_dofs), 0.0, 0.0, with_K=False)
        out = np.zeros(N_BARS)
        if dq is None:
            np.add.at(out, self.bar_of, self._Ue.sum(axis=1))
            return out
        # element tangent stiffness at q (self._dE holds the element displacements at q)
        Fe = np.zeros((self.n_elements, 8))
        Ke = np.zeros((self.n_elements, 8, 8))
        Ue = np.zeros((self.n_elements, 2))
        beam.elastic_elements(self._E0, self._dE, self._length, self._EA, self._EI, self._xi,
                              self._w, Fe, Ke, Ue)
        dE = np.zeros((self.n_elements, 8))
        beam.gather(np.asarray(dq, float), self._pg, self._pR, self._pc0, dE)
        u = 0.5 * np.einsum("ki,kij,kj->k", dE, Ke, dE)
        np.add.at(out, self.bar_of, u)
        return out

    def mode_label(self, shape, mass) -> str:
        """Bar bending when the beams store most of the mode's potential energy, otherwise the
        rigid-body name of Table 2.2 (collector pitch / vertical / horizontal, mechanism)."""
        phi = np.real(np.asarray(shape, float))
        q0 = self.q_equilibrium
        F = getattr(self, "static_contact_force", self.options.mean_uplift)
        _, K, _ = self._assemble(q0, np.zeros(self.n_dofs), F, self.torque)
        total = float(phi @ K @ phi)
        ub = self.strain_energy_by_bar(q0, phi)
        if total > 0.0 and 2.0 * ub.sum() > 0.5 * total:
            order = np.argsort(ub)[::-1]
            bars = [int(order[0]) + 1]
            if ub[order[1]] > 0.5 * ub[order[0]]:
                bars.append(int(order[1]) + 1)
            return "bending bar " + " + ".join(str(b) for b in bars)
        g10 = self.point_dofs["10"]
        s10 = self.slope10
        m7 = self.params.rigid.bars[6].m
        I7 = self.params.rigid.bars[6].I
        ke = {"collector horizontal": m7 * phi[g10] ** 2,
              "collector vertical": m7 * phi[g10 + 1] ** 2,
              "collector pitch": I7 * (phi[s10] ** 2 + phi[s10 + 1] ** 2)}
        total_ke = float(phi @ np.asarray(mass) @ phi)
        ke["mechanism"] = total_ke - sum(ke.values())
        return max(ke, key=ke.get)

    # ------------------------------------------------------------------ equilibrium
    def _newton(self, q, F, torque, height=None, tol=1e-10, max_it=60):
        """Static Newton: f_rest(q, M) = 0 and, with ``height``, y10 = height with the torque
        as extra unknown ((2.11)-(2.14) for the flexible model)."""
        n = self.n_dofs
        zero = np.zeros(n)
        iy = self.point_dofs["10"] + 1
        g = self.slope1
        q = q.copy()
        scale = max(1.0, float(np.max(np.abs(self.Qg))) * 10.0, abs(F))
        for it in range(max_it):
            f, K, _ = self._assemble(q, zero, F, torque, friction=False)
            if height is None:
                res = np.max(np.abs(f))
                dq = dense_solver(K)(-f)
                dM = 0.0
            else:
                a, b = self.q_ref[g] + q[g], self.q_ref[g + 1] + q[g + 1]
                s = a * a + b * b
                gphi = np.zeros(n)
                gphi[g], gphi[g + 1] = -b / s, a / s
                A = np.zeros((n + 1, n + 1))
                A[:n, :n] = K
                A[:n, n] = -gphi
                A[n, iy] = 1.0
                gap = self.q_ref[iy] + q[iy] - height
                rhs = -np.append(f, gap)
                res = max(np.max(np.abs(f)), abs(gap) * 1e6)
                sol = dense_solver(A)(rhs)
                dq, dM = sol[:n], sol[n]
            step = float(np.max(np.abs(dq)))
            if step > 0.05:  # limit the first steps far from equilibrium
                dq *= 0.05 / step
                dM *= 0.05 / step
            q += dq
            torque += dM
            if res < tol * scale or step < 1e-14 * (1.0 + float(np.max(np.abs(q)))):
                break
        f, K, _ = self._assemble(q, zero, F, torque, friction=False)
        res = float(np.max(np.abs(f)))
        # round-off floor of absolute nodal coordinates: eps |q| times the stiffest entry
        floor = 64.0 * np.finfo(float).eps * float(np.max(np.abs(np.diag(K)))) * \
            max(1.0, float(np.max(np.abs(q))))
        if not res < 1e-6 * scale + floor:
            raise ParameterError("contact_force", F, f"no static equilibrium of the flexible "
                                 f"model found (residual {res:.3g} N)", self.name)
        return q, torque

    @property
    def working_height(self) -> float:
        return self.params.rigid.working_height

    def equilibrium(self, contact_force: float, height: float):
        """(q0, M0): shape and actuation torque with point 10 at ``height`` under
        ``contact_force``; starts from the rigid solution (2.11)-(2.14)."""
        rig = self.rigid
        saved = (rig.torque, rig.torque_lowered, rig.q_equilibrium)
        try:
            qr = rig.static_equilibrium(contact_force, height)
            M0 = rig.torque
        finally:
            rig.torque, rig.torque_lowered, rig.q_equilibrium = saved
        return self._newton(self.q_from_rigid(qr), contact_force, M0, height=height)

    def equilibrium_under_torque(self, contact_force: float, torque: float, q_guess=None):
        """Static shape under a given actuation torque and contact force (height free), e.g.
        the rigid model's M0: gives the flexible static drop of point 10 (thesis 2.3.2)."""
        q = self.q_equilibrium if q_guess is None else np.asarray(q_guess, float)
        q, _ = self._newton(q, contact_force, torque, height=None)
        return q

    def equilibrium_info(self) -> dict:
        return {**super().equilibrium_info(), "n_dofs": self.n_dofs,
                "n_elements": self.n_elements}

    # ------------------------------------------------------------------ linear analysis
    def modes(self, q0=None, contact_force=None, n_modes: int = 8, shift_hz: float = 0.1):
        """Undamped modes (2.21)-(2.24) by shift-invert (accurate for the lowest modes even when
        the axial modes reach 1e7 rad/s): returns (frequencies [Hz], shapes, labels)."""
        q0 = self.q_equilibrium if q0 is None else q0
        Mm, _, K = self.linearize(q0, contact_force)
        s = (2.0 * math.pi * shift_hz) ** 2
        mu, phi = sla.eigh(Mm, K + s * Mm)
        order = np.argsort(mu)[::-1][:n_modes]
        w2 = 1.0 / mu[order] - s
        phi = phi[:, order]
        phi = phi / np.sqrt(np.einsum("ir,ij,jr->r", phi, Mm, phi))
        freqs = np.sqrt(np.clip(w2, 0.0, None)) / (2.0 * math.pi)
        labels = [self.mode_label(phi[:, r], Mm) for r in range(len(freqs))]
        return freqs, phi, labels


def load_dsa380_flexible(path: str | Path | None = None,
                         options: PantographOptions | None = None, **changes
                         ) -> Dsa380FlexibleModel:
    """Load a flexible DSA-380 file (None: the preset). ``changes`` override
    FlexibleParameters fields (e.g. ``E=210e12`` or ``mesh=(...)``)."""
    path = PRESET_FILE if path is None else Path(path)
    params, root = read_flexible(path)
    known = {f.name for f in fields(FlexibleParameters)}
    for k, v in changes.items():
        if k not in known:
            raise ParameterError(k, v, "unknown flexible-model parameter", str(path))
        setattr(params, k, v)
    if options is None:
        options = PantographOptions.from_table(root.sub("options", required=False))
    return Dsa380FlexibleModel(params, options, name=ROOT.read(root, "name"))

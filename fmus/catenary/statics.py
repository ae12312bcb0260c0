"""Static equilibrium (3.5)-(3.8) and the initial-configuration problem (3.1.3).

Static equilibrium: F(q) = F_elast(q) - F_ext = 0 solved by Newton-Raphson,
K_T dq = -F (3.8), with load stepping on the point loads when a full step fails (droppers
that go slack make the problem non-smooth).

Initial configuration (the first method of thesis ref. [19]): the elastic equilibrium
equations are augmented with constraints and unknown parameters and solved together by
Newton-Raphson on y = [q, p]:

    unknown p                                constraint
    unstretched length of every dropper      contact-wire height at the dropper = design
    pre-tension N0 of each wire in each span span-averaged horizontal tension = design
    height of each steady-arm pin / spring   height of the supported node = design
    anchor

so that at static equilibrium the contact wire lies at the design heights (pre-sag included)
and every wire carries its design (horizontal) tension. Droppers are bilateral during this
solve; afterwards every dropper must be in tension. The lateral position of each steady-arm
pin is then corrected so that the stagger at the support equals the design value.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from ..core.errors import ConvergenceError, ParameterError
from . import ancf_cable


@dataclass
class StaticResult:
    q: np.ndarray
    iterations: int
    residual: float          # max |F| / max |applied load|
    load_steps: int = 1


def _solve(K, rhs):
    return spla.splu(sp.csc_matrix(K)).solve(rhs)


def point_load_vector(S, locator, point_loads) -> np.ndarray:
    """Free-DOF vector of upward forces F at track positions x: [(x, F), ...], (3.13)."""
    f = np.zeros(S.n_free)
    for x, F in point_loads or ():
        cp = locator.point(float(x))
        np.add.at(f, cp.dofs, F * cp.weights)
    return f


def solve_static(S, q0, f_applied=None, tol: float = 1e-10, max_iter: int = 40,
                 tension_only: bool = True, max_halvings: int = 12) -> StaticResult:
    """Equilibrium f_int(q) = weight + f_applied from q0 (load stepping on f_applied)."""
    w = S.weight
    P = np.zeros(S.n_free) if f_applied is None else np.asarray(f_applied, float)
    q = np.array(q0, dtype=float)
    scale = max(float(np.max(np.abs(w))), float(np.max(np.abs(P))), 1e-300)
    lam, dlam, steps, total = 0.0, 1.0, 0, 0
    first = True
    while True:
        target = min(1.0, lam + dlam)
        if first:
            target, first = 1.0, False
        ok, qn, it, res = _newton(S, q, w + target * P, tol * scale, max_iter, tension_only)
        total += it
        if ok:
            q, lam, steps = qn, target, steps + 1
            if lam >= 1.0:
                return StaticResult(q=q, iterations=it, residual=res / scale,
                                    load_steps=steps)
            dlam = min(2 * dlam, 1.0 - lam)
        else:
            dlam *= 0.5
            max_halvings -= 1
            if max_halvings < 0 or not np.isfinite(dlam):
                raise ConvergenceError(
                    f"static equilibrium did not converge (load factor {lam:.3g}, "
                    f"residual {res:.3e} N)", residual=res)


def _newton(S, q, f_ext, atol, max_iter, tension_only):
    """Newton-Raphson (3.8). Converged when max|F| <= atol, or when the correction is at
    the round-off level of q (1e-13 m) and the residual stopped decreasing: the axial forces
    then carry their round-off floor (about EA * 1e-16)."""
    res = np.inf
    prev = np.inf
    dq_size = np.inf
    for it in range(max_iter + 1):
        f, K, _ = S.internal(S.full(q), True, tension_only)
        R = f[S.free] - f_ext
        res = float(np.max(np.abs(R)))
        if not np.isfinite(res):
            return False, q, it, res
        if res <= atol or (dq_size <= 1e-13 and res >= 0.5 * prev):
            return True, q, it, res
        if it == max_iter:
            break
        dq = _solve(S.csr(K), -R)
        dq_size = float(np.max(np.abs(dq)))
        prev = res
        q = q + dq
    return False, q, max_iter, res


# ====================================================================== initial configuration
@dataclass
class InitialConfiguration:
    q: np.ndarray
    iterations: int
    residual: float              # max |F| / max |weight|
    height_error: float          # max |z - design| at droppers and supports [m]
    tension_error: float         # max relative error of span-averaged horizontal tensions


def _params(mesh) -> np.ndarray:
    S = mesh.structure
    pa = []
    for a in mesh.anchors:
        pa.append(S.x_full[a.index] if a.kind == "pin" else S.springs.anchor[a.index])
    return np.concatenate([S.bars.l0[mesh.dropper_bars], S.cables.N0_group,
                           np.array(pa, float)])


def _set_params(mesh, p) -> None:
    S = mesh.structure
    nd, ng = mesh.dropper_bars.size, S.cables.N0_group.size
    S.bars.l0[mesh.dropper_bars] = p[:nd]
    k = mesh.dropper_k
    if k.size and np.all(np.isfinite(k)):
        S.bars.EA[mesh.dropper_bars] = k * p[:nd]      # N = k (l - l0)
    S.cables.N0_group[:] = p[nd:nd + ng]
    for k, a in enumerate(mesh.anchors):
        if a.kind == "pin":
            S.x_full[a.index] = p[nd + ng + k]
        else:
            S.springs.anchor[a.index] = p[nd + ng + k]


def group_horizontal_tensions(mesh, x_full) -> np.ndarray:
    """Span-averaged horizontal tension (1/L) int N r'_x dchi of every wire group."""
    C = mesh.structure.cables
    h, _, _, _ = _tension_measures(C, x_full)
    Lsum = np.bincount(C.group, C.Le, minlength=C.N0_group.size)
    return np.bincount(C.group, h, minlength=C.N0_group.size) / Lsum


def element_tensions(S, x_full) -> np.ndarray:
    """True axial tension N |r'| at the mid-point of every cable element."""
    return S.cables.tensions(x_full)


def _tension_measures(C, x_full):
    """Horizontal force measures of the cables ``C`` (a CableSet) and their gradients."""
    E = x_full[C.dofs]
    ne = E.shape[0]
    h = np.empty(ne)
    dh = np.empty((ne, 12))
    dhN = np.empty(ne)
    dfN = np.empty((ne, 12))
    ancf_cable.cable_tension_measures(E, C.dX, C.Le, C.EA, C.N0(),
                                      ancf_cable.GAUSS_XI, ancf_cable.GAUSS_W, h, dh, dhN, dfN)
    return h, dh, dhN, dfN


def _augmented(mesh, q, want_J=True):
    S = mesh.structure
    C, B = S.cables, S.bars
    n = S.n_free
    nd, ng, na = mesh.dropper_bars.size, C.N0_group.size, len(mesh.anchors)
    x = S.full(q)
    f, K, _ = S.internal(x, want_J, tension_only=False)
    R = f[S.free] - S.weight
    h, dh, dhN, dfN = _tension_measures(C, x)
    Lsum = np.bincount(C.group, C.Le, minlength=ng)
    H = np.bincount(C.group, h, minlength=ng) / Lsum
    cz = mesh.node_dofs[mesh.dropper_contact_nodes, 2]
    g = np.concatenate([
        x[cz] - mesh.dropper_design_z,
        H - mesh.group_tension,
        np.array([x[a.target] - a.design for a in mesh.anchors], float)])
    if not want_J:
        return R, g, None
    fm = S.fmap
    rows, cols, vals = [], [], []

    def add(r, c, v):
        r = np.asarray(r)
        c = np.broadcast_to(np.asarray(c), r.shape).ravel()
        v = np.broadcast_to(np.asarray(v, float), r.shape).ravel()
        rows.append(r.ravel())
        cols.append(c)
        vals.append(v)

    # dR/dp
    bd = B.dofs[mesh.dropper_bars]
    X = x[bd]
    dvec = X[:, 3:] - X[:, :3] + B.dX[mesh.dropper_bars]
    ln = np.linalg.norm(dvec, axis=1)
    u = dvec / ln[:, None]
    l0 = B.l0[mesh.dropper_bars]
    kd = mesh.dropper_k
    if kd.size and np.all(np.isfinite(kd)):
        dN = -kd * np.ones_like(ln)                      # N = k (l - l0)
    else:
        dN = -B.EA[mesh.dropper_bars] * ln / l0**2   # N = EA (l - l0) / l0
    dF = np.hstack([-u, u]) * dN[:, None]
    add(fm[bd], n + np.arange(nd)[:, None], dF)
    add(fm[C.dofs], n + nd + C.group[:, None], dfN)
    if na:
        fb, Kb, _ = B.tangent_blocks(x)
    for k, a in enumerate(mesh.anchors):
        col = n + nd + ng + k
        if a.kind == "pin":
            add(fm[B.dofs[a.bar]], col, Kb[a.bar][:, a.comp])
        else:
            add([fm[S.springs.dofs[a.index, 0]]], col, [-S.springs.k[a.index]])
    # dg/dq and dg/dp
    add(n + np.arange(nd), fm[cz], 1.0)
    add(n + nd + C.group[:, None] + 0 * C.dofs, fm[C.dofs], dh / Lsum[C.group][:, None])
    add(n + nd + np.arange(ng), n + nd + np.arange(ng),
        np.bincount(C.group, dhN, minlength=ng) / Lsum)
    for k, a in enumerate(mesh.anchors):
        add([n + nd + ng + k], [fm[a.target]], [1.0])
    r = np.concatenate(rows)
    c = np.concatenate(cols)
    v = np.concatenate(vals)
    ok = (r >= 0) & (c >= 0)
    N = n + nd + ng + na
    B = sp.coo_matrix((v[ok], (r[ok], c[ok])), shape=(N, N)).tocsc()
    Kfull = sp.bmat([[S.csr(K), None], [None, sp.csr_matrix((nd + ng + na,) * 2)]])
    return R, g, (Kfull + B).tocsc()


def solve_initial_configuration(mesh, tol: float = 1e-9,
                                max_iter: int = 60) -> InitialConfiguration:
    """Find dropper lengths, wire pre-tensions and support anchors (3.1.3); the mesh's
    structure is updated in place and the equilibrium coordinates returned.

    Converged when max|F| <= tol * max|weight| (the round-off floor of the axial forces is
    about 1e-10 of it), heights and stagger within 1e-10 m and tensions within 1e-10."""
    S = mesh.structure
    q = S.x_full[S.free].copy()
    fscale = float(np.max(np.abs(S.weight)))
    Tscale = float(np.max(mesh.group_tension)) if mesh.group_tension.size else 1.0
    nd = mesh.dropper_bars.size
    ng = S.cables.N0_group.size
    p = _params(mesh)
    for it in range(max_iter + 1):
        R, g, J = _augmented(mesh, q)
        rR = float(np.max(np.abs(R))) / fscale
        gz = np.concatenate([g[:nd], g[nd + ng:]])
        rz = float(np.max(np.abs(gz))) if gz.size else 0.0
        rT = float(np.max(np.abs(g[nd:nd + ng]))) / Tscale if ng else 0.0
        if not (np.isfinite(rR) and np.isfinite(rz) and np.isfinite(rT)):
            raise ConvergenceError("initial configuration: non-finite residual")
        if rR <= tol and rz <= 1e-10 and rT <= 1e-10:
            break
        if it == max_iter:
            raise ConvergenceError(
                f"initial configuration did not converge: force residual {rR:.3e}, "
                f"height error {rz:.3e} m, tension error {rT:.3e}", residual=rR)
        dy = spla.splu(J).solve(-np.concatenate([R, g]))
        # damped step: limit the change of any coordinate to 0.5 m
        s = min(1.0, 0.5 / max(float(np.max(np.abs(dy[:S.n_free]))), 1e-300))
        q = q + s * dy[:S.n_free]
        p = p + s * dy[S.n_free:]
        _set_params(mesh, p)
    l0 = S.bars.l0[mesh.dropper_bars]
    if np.any(l0 <= 0):
        i = int(np.argmin(l0))
        raise ParameterError(f"droppers.positions[{i}]", float(mesh.dropper_x[i]),
                             "no dropper length reaches the design height (negative)")
    R, g, _ = _augmented(mesh, q, want_J=False)
    gz = np.concatenate([g[:nd], g[nd + ng:]])
    return InitialConfiguration(
        q=q, iterations=it, residual=float(np.max(np.abs(R))) / fscale,
        height_error=float(np.max(np.abs(gz))) if gz.size else 0.0,
        tension_error=float(np.max(np.abs(g[nd:nd + ng]) / mesh.group_tension)) if ng else 0.0)

"""The linear catenary on its modes below a cutoff, with a moving static correction.

Coordinates y = [eta (m modal), xi (one per pantograph)]:

    q - q_static = Phi eta + Psi(t) G(t)^-1 xi,
    Psi = (K0^-1 - Phi Omega^-2 Phi^T) N(t),   G = N^T Psi   (residual flexibility),

N(t) the contact-wire interpolation (3.13) at the pantographs. Psi is K0- and M-orthogonal
to the modes, so the modal equations stay diagonal,

    eta'' + (alpha + beta omega^2) eta' + omega^2 eta = Phi^T (N F - dropper correction),

and xi, the contact-point height the truncated modes miss, is quasi-static: G^-1 xi = F.
The contact point's static flexibility N^T K0^-1 N is exact at every position. K0^-1 N comes
from the kept banded factorization of K0 through its cached unit-vector solves (one solve per
contact-wire DOF a pantograph meets: the part that still scales with the DOFs, with the set-up
and the modes). Droppers (:mod:`.linear_droppers`) slacken through a corrective force on the
reduced coordinates, their elongation b . (Phi eta + Psi G^-1 xi); its rank-one tangents
enter the diagonal Newton matrix by Woodbury. Per step the cost is O(modes x (pantographs +
droppers)).
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from ..core.errors import ConvergenceError
from ..core.model import Evaluation, SecondOrderModel
from .linear import LinearCatenary
from .modal_basis import modes_below
from .model import CatenaryModel


class ModalCatenary(SecondOrderModel):
    """``ModalCatenary(catenary, x0, speed, cutoff_hz=...)``, or around a ``linear`` model."""

    name = "modal"

    def __init__(self, catenary=None, x0=(0.0,), speed: float = 0.0, *, cutoff_hz: float = 20.0,
                 element_size=None, linear: LinearCatenary | None = None):
        lin = self.linear = linear or LinearCatenary(catenary, x0, speed,
                                                      element_size=element_size)
        self.cutoff_hz = float(cutoff_hz)
        self.frequencies, self.Phi = modes_below(lin.K0, lin.M, self.cutoff_hz)
        self.omega2 = (2.0 * np.pi * self.frequencies) ** 2
        self.m = self.Phi.shape[1]
        self.n_p = len(lin.x0)
        self.n_dofs = self.m + self.n_p
        #: a complete basis leaves no residual flexibility: xi is then unused (held at 0)
        self.corrected = self.m < lin.n_dofs
        self.x0, self.speed = lin.x0, lin.speed
        self.definition, self.mesh, self.structure = lin.definition, lin.mesh, lin.structure
        self.zeta_c = lin.alpha_r + lin.beta_r * self.omega2       # Phi^T C Phi (diagonal)
        self.r0 = self.Phi.T @ lin.r0
        dr = self.droppers = lin.droppers
        vec = dr.vectors
        self.B_phi = np.einsum("dk,dkm->dm", vec.val, np.vstack([self.Phi, np.zeros(
            (1, self.m))])[vec._pad_idx])                          # b_d . phi_j
        self.K0_solve = lin._factor_cache(0.0, 0.0, 1.0).solve     # cached columns K0^-1 e_j
        self._b_cols: dict[int, np.ndarray] = {}                   # b_d . K0^-1 e_j by j
        dz = self.mesh.node_dofs[self.mesh.support_contact_nodes, 2]
        self._sup = self.structure.fmap[dz]
        self.Phi_sup = np.where((self._sup >= 0)[:, None], self.Phi[self._sup], 0.0)
        self.q_static = np.zeros(self.n_dofs)
        self._slack_committed = np.zeros(len(dr), dtype=bool)
        self._geo = None

    # ------------------------------------------------------------------ delegated geometry
    def positions(self, t):
        return self.linear.positions(t)

    @property
    def support_x(self):
        return self.linear.support_x

    wire_height = CatenaryModel.wire_height
    wire_velocity = CatenaryModel.wire_velocity

    # ------------------------------------------------------------------ moving correction
    def geometry(self, t: float):
        """Contact points in y, G^-1, the droppers' and supports' rows of Psi G^-1 at t."""
        t = float(t)
        if self._geo is not None and self._geo.t == t:
            return self._geo
        cps = self.linear.contact_points(t)
        m, npan = self.m, self.n_p
        phi = np.array([cp.weights @ self.Phi[cp.dofs] for cp in cps])         # (np, m)
        flex = np.zeros((npan, npan))
        Hb = np.zeros((len(self.droppers), npan))
        Hs = np.zeros((self._sup.size, npan))
        for k, cp in enumerate(cps):
            cols = self.K0_solve._cached(cp.dofs)
            col = sum(w * c for w, c in zip(cp.weights, cols))               # K0^-1 N_k
            for j, cj in enumerate(cps):
                flex[j, k] = cj.weights @ col[cj.dofs]
            Hb[:, k] = self.droppers.vectors.dots(col)
            Hs[:, k] = np.where(self._sup >= 0, col[self._sup], 0.0)
        inv_w2 = phi / self.omega2                                            # (np, m)
        if self.corrected:
            G = flex - phi @ inv_w2.T
            G = 0.5 * (G + G.T)
            Ginv = np.linalg.inv(G)
            Hb = (Hb - self.B_phi @ inv_w2.T) @ Ginv
            Hs = (Hs - self.Phi_sup @ inv_w2.T) @ Ginv
        else:
            G = Ginv = np.eye(npan)
            Hb, Hs = 0.0 * Hb, 0.0 * Hs
        wxi = 1.0 if self.corrected else 0.0
        points = []
        for k, cp in enumerate(cps):
            e = np.zeros(1)
            points.append(SimpleNamespace(
                dofs=np.concatenate([np.arange(m), [m + k]]),
                weights=np.concatenate([phi[k], [wxi]]),
                offset=float(cp.weights @ self.linear.q_static[cp.dofs] + cp.offset),
                dweights_dx=np.concatenate([cp.dweights_dx @ self.Phi[cp.dofs], e]),
                doffset_dx=float(cp.dweights_dx @ self.linear.q_static[cp.dofs]
                                 + cp.doffset_dx),
                element=cp.element, xi=cp.xi))
        T = np.hstack([self.B_phi, Hb])           # dropper elongation = T @ y
        self._geo = SimpleNamespace(t=t, phi=phi, G=G, Ginv=Ginv, T=T, Hs=Hs, points=points)
        return self._geo

    def contact_points(self, t: float):
        return self.geometry(t).points

    # ------------------------------------------------------------------ model interface
    def input_vector(self, t, inputs) -> np.ndarray:
        F = np.atleast_1d(np.asarray(inputs, dtype=float))
        g = self.geometry(t)
        return np.concatenate([g.phi.T @ F, F if self.corrected else 0.0 * F])

    def _dropper_forces(self, g, y, v):
        dr = self.droppers
        N = dr.N0 + dr.ka * (g.T @ y)
        slack = dr.slack(N)
        removed = g.T[slack].T @ N[slack]
        c = self._slack_committed
        if c.any():
            removed += g.T[c].T @ (dr.beta * dr.ka[c] * (g.T[c] @ v))
        return removed, slack, N

    def evaluate(self, t, q, v, a, inputs, tangent=True) -> Evaluation:
        g = self.geometry(t)
        m = self.m
        removed, slack, _ = self._dropper_forces(g, q, v)
        f_rest = np.empty(self.n_dofs)
        f_rest[:m] = self.zeta_c * v[:m] + self.omega2 * q[:m] + self.r0
        f_rest[m:] = g.Ginv @ q[m:]
        f_rest -= removed
        if inputs is not None:
            f_rest -= self.input_vector(t, inputs)
        f_in = np.zeros(self.n_dofs)
        f_in[:m] = a[:m]
        ev = Evaluation(f_inertia=f_in, f_rest=f_rest,
                        structure_key=(slack.tobytes(), self._slack_committed.tobytes()))
        ev.slack_sets = (slack, self._slack_committed.copy())
        return ev

    def effective_matrix(self, ev, c_a, c_v, c_f):
        rows, s = self.droppers.removed_stiffness(*ev.slack_sets, c_v, c_f)
        return SimpleNamespace(c=(c_a, c_v, c_f), rows=rows, s=s)

    def factorize(self, S):
        """Solve with diag(c_a + c_f (c_v zeta + omega^2)) on eta, c_f G^-1 on xi (G at the
        latest evaluated time), minus the slack droppers' rank-one terms (Woodbury)."""
        return _ModalSolve(self, *S.c, S.rows, S.s)

    def commit(self, t, q, v, a, inputs) -> None:
        self._slack_committed = self._dropper_forces(self.geometry(t), q, v)[1]

    def get_internal_state(self):
        return {"slack": self._slack_committed.copy()}

    def set_internal_state(self, state) -> None:
        n = len(self.droppers)
        self._slack_committed = (np.zeros(n, dtype=bool) if state is None
                                 else np.array(state["slack"], dtype=bool).copy())

    # ------------------------------------------------------------------ results
    def dropper_forces(self, q) -> np.ndarray:
        g = self._geo or self.geometry(0.0)
        N = self.droppers.N0 + self.droppers.ka * (g.T @ q)
        return np.where(self.droppers.slack(N), 0.0, N)

    def support_uplift(self, q) -> np.ndarray:
        """Uplift at the supports (Phi eta + the static correction at the latest time)."""
        g = self._geo or self.geometry(0.0)
        return self.Phi_sup @ q[:self.m] + g.Hs @ q[self.m:]

    def full_displacement(self, t, q) -> np.ndarray:
        """q_full - q_static on the linear model's DOFs (for checks; O(DOFs))."""
        g = self.geometry(t)
        out = self.Phi @ q[:self.m]
        for k, cp in enumerate(self.linear.contact_points(t)):
            col = sum(w * c for w, c in zip(cp.weights, self.K0_solve._cached(cp.dofs)))
            psi = col - self.Phi @ (g.phi[k] / self.omega2)
            out += psi * (g.Ginv[k] @ q[self.m:])
        return out

    def static_state(self, forces=None, t: float = 0.0, max_iter: int = 50) -> np.ndarray:
        """Static equilibrium in y under the pantographs' forces (slack set included)."""
        y = np.zeros(self.n_dofs)
        if forces is None:
            return y
        F = np.broadcast_to(np.asarray(forces, float), self.x0.shape)
        zero = np.zeros(self.n_dofs)
        saved, self._slack_committed = self._slack_committed, np.zeros(len(self.droppers), bool)
        try:
            used = None
            for _ in range(max_iter):
                ev = self.evaluate(t, y, zero, zero, F)
                if used is not None and np.array_equal(used, ev.slack_sets[0]):
                    return y
                y = y - self.factorize(self.effective_matrix(ev, 0.0, 0.0, 1.0))(ev.f_rest)
                used = ev.slack_sets[0]
        finally:
            self._slack_committed = saved
        raise ConvergenceError("modal catenary statics: the slack set did not settle")


class _ModalSolve:
    """(A0 - sum_d s_d t_d t_d^T)^-1 with A0 = diag on eta (+) c_f G^-1 on xi."""

    def __init__(self, model: ModalCatenary, c_a, c_v, c_f, rows, s):
        self.model, self.c, self.rows, self.s = model, (c_a, c_v, c_f), rows, s
        self.diag = c_a + c_f * (c_v * model.zeta_c + model.omega2)
        self._memo = None

    def _a0_solve(self, g, r):
        m, c_f = self.model.m, self.c[2]
        x = np.empty_like(r)
        x[:m] = (r[:m].T / self.diag).T
        x[m:] = g.G @ r[m:] / c_f if c_f else r[m:]
        return x

    def _update(self, g):
        if self._memo is None or self._memo[0] is not g:
            Ts = g.T[self.rows]                                  # (ns, m + np)
            U = self._a0_solve(g, Ts.T.copy())
            small = np.eye(self.rows.size) - self.s[:, None] * (Ts @ U)
            self._memo = (g, Ts, U, small)
        return self._memo

    def __call__(self, r):
        g = self.model._geo
        r = np.asarray(r, dtype=float)
        x = self._a0_solve(g, r)
        if not self.rows.size:
            return x
        _, Ts, U, small = self._update(g)
        return x + U @ np.linalg.solve(small, self.s * (Ts @ x))

"""The catenary linearised about its static equilibrium, with unilateral droppers.

    M a + C v + K0 (q - q_static) + r0 - sum_{d slack} (N_d b_d + beta k_a,d (b_d . v) b_d)
        = sum_k N_k(t)^T F_k

M, C = alpha M + beta K0 (Rayleigh (3.1)) and K0 (the tangent at the static configuration
(3.5), all droppers taut) are those of :class:`~pantocosim.catenary.model.CatenaryModel`;
r0 = F_elast(q_static) - F_weight is the initial configuration's round-off. Droppers follow
:mod:`.linear_droppers`: the stiffness of the slack ones (the set at the current iterate) and
their damping share (the set committed at the end of the previous step, as in the nonlinear
model, so the residual stays continuous within a step) leave the kept factorization as
rank-one updates (:mod:`pantocosim.core.lowrank`). The Newton matrix of each (c_a, c_v, c_f)
is factorized once per run; ``structure_key`` is the slack sets, so the integrator's
"refactorization" on a change of set costs the small Woodbury matrix only.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from ..core.affine_hht import AffineForm
from ..core.banded import BandedCholesky
from ..core.errors import ConvergenceError
from ..core.lowrank import ColumnCache, LowRankSolve
from ..core.model import Evaluation
from ..core.scatter import scatter_add
from .linear_droppers import LinearDroppers
from .model import CatenaryModel
from .statics import point_load_vector


class LinearCatenary(CatenaryModel):
    """``LinearCatenary(catenary, x0, speed)``: the same arguments, geometry, statics of the
    reference configuration and public interface as :class:`CatenaryModel`; constant
    matrices and exact dropper slackening in the dynamics and in :meth:`static_solution`."""

    name = "linear"
    #: its HHT steps are taken in closed form on :meth:`affine_form`
    #: (:class:`~pantocosim.core.affine_hht.AffineHHT`)
    stepping = "affine"
    #: its own :meth:`evaluate` (the reference model's fused iterate does not apply)
    fused_iterate = False

    def __init__(self, catenary, x0=(0.0,), speed: float = 0.0, **kwargs):
        super().__init__(catenary, x0, speed, **kwargs)
        S = self.structure
        self.K0 = S.csr(self.K0_data)
        self.C0 = S.csr(self._C_base)
        f, _, _ = S.internal(self.x_static, False)
        self.r0 = f[S.free] - self.weight
        self.droppers = LinearDroppers(S, self.mesh.dropper_bars, self.x_static, self.beta_r)
        self._factors: dict[tuple, ColumnCache] = {}

    # ------------------------------------------------------------------ forces
    def _dropper_terms(self, dq, v):
        """(force to take out of f_rest, slack set at dq)."""
        dr = self.droppers
        N = dr.axial(dq)
        slack = dr.slack(N)
        out = dr.force(N, slack)
        if self._slack_committed.any():
            out += dr.force(dr.beta * dr.ka * dr.vectors.dots(v), self._slack_committed)
        return out, slack

    def evaluate(self, t, q, v, a, inputs, tangent=True) -> Evaluation:
        dq = q - self.q_static
        removed, slack = self._dropper_terms(dq, v)
        f_rest = self.C0 @ v
        f_rest += self.K0 @ dq
        f_rest += self.r0
        f_rest -= removed
        if inputs is not None:
            f_rest -= self.input_vector(t, inputs)
        ev = Evaluation(f_inertia=self._M_own @ a, f_rest=f_rest,
                        structure_key=(slack.tobytes(), self._slack_committed.tobytes()))
        ev.slack_sets = (slack, self._slack_committed.copy())
        if tangent:
            ev.mass, ev.damping, ev.stiffness = self.M, self.C0, self.K0
        return ev

    def dropper_forces(self, q: np.ndarray) -> np.ndarray:
        """Axial force of every dropper (N, tension positive, exactly zero when slack)."""
        N = self.droppers.axial(q - self.q_static)
        return np.where(self.droppers.slack(N), 0.0, N)

    # ------------------------------------------------------------------ Newton matrix
    def effective_matrix(self, ev, c_a, c_v, c_f):
        """c_a M + c_f (c_v C + K) with the slack droppers' rank-one terms taken out, tagged
        with what :meth:`factorize` needs to reuse the run's factorization."""
        base = super().effective_matrix(ev, c_a, c_v, c_f)
        sets = getattr(ev, "slack_sets", None)
        if sets is None:
            return base
        rows, s = self.droppers.removed_stiffness(sets[0], sets[1], c_v, c_f)
        if rows.size:
            b = self.droppers.vectors.val[rows]
            blocks = -s[:, None, None] * b[:, :, None] * b[:, None, :]
            data = base.data.copy()
            scatter_add(data, self._dropper_pos[rows].ravel(), blocks.ravel())
            base = self.structure.csr(data)
        base.pc_linear = (float(c_a), float(c_v), float(c_f), rows, s)
        return base

    def _factor_cache(self, c_a, c_v, c_f) -> ColumnCache:
        key = (c_a, c_v, c_f)
        if key not in self._factors:
            data = c_a * self.M.data + c_f * (c_v * self.C0.data + self.K0.data)
            chol = BandedCholesky.factor(self.structure.lower_band(data))
            if chol is None:
                raise ConvergenceError(f"linear catenary: Newton matrix {key} is not "
                                       "positive definite")
            self._factors[key] = ColumnCache(chol, self.droppers.vectors)
        return self._factors[key]

    def factorize(self, S):
        """The kept banded Cholesky of (c_a, c_v, c_f) with the slack droppers' Woodbury
        update; a matrix without the tag falls back to :class:`CatenaryModel`'s."""
        tag = getattr(S, "pc_linear", None)
        if tag is None:
            return super().factorize(S)
        c_a, c_v, c_f, rows, s = tag
        return LowRankSolve(self._factor_cache(c_a, c_v, c_f), rows, s)

    def commit(self, t, q, v, a, inputs) -> None:
        self._slack_committed = self.droppers.slack(self.droppers.axial(q - self.q_static))

    # ------------------------------------------------------------------ closed-form steps
    def affine_form(self):
        """The model as an :class:`~pantocosim.core.affine_hht.AffineForm`: its HHT steps
        are then taken in closed form (:mod:`pantocosim.core.affine_hht`), the same solution
        as Newton-Raphson on :meth:`evaluate`."""
        S = self.structure

        def forces(t, q, v, F):
            self.commit(t, q, v, None, None)
            zero = np.zeros(self.n_dofs)
            return self.evaluate(t, q, v, zero, F, tangent=False).f_rest

        return AffineForm(n=self.n_dofs, M_band=S.lower_band(S.M_data),
                          K_band=S.lower_band(self.K0_data), alpha_r=self.alpha_r,
                          beta_r=self.beta_r, q_ref=self.q_static, r0=self.r0,
                          unilateral=self.droppers, factor=self._factor_cache, forces=forces)

    # ------------------------------------------------------------------ statics
    def static_solution(self, point_loads=(), tol: float = 1e-10, max_iter: int = 50):
        """Static equilibrium K0 dq + r0 - sum_slack N_d b_d = P of the linear model, with
        its slack set (active-set Newton on the kept factorization of K0)."""
        P = point_load_vector(self.structure, self.locator, point_loads)
        cache = self._factor_cache(0.0, 0.0, 1.0)
        dr = self.droppers
        q = self.q_static.copy()
        used = None
        scale = max(float(np.max(np.abs(self.weight))), float(np.max(np.abs(P))))
        for it in range(max_iter):
            dq = q - self.q_static
            N = dr.axial(dq)
            slack = dr.slack(N)
            R = self.K0 @ dq + self.r0 - dr.force(N, slack) - P
            res = float(np.max(np.abs(R)))
            # a solve with the slack set it produces is exact (the problem is linear in it)
            if res <= tol * scale or (used is not None and np.array_equal(used, slack)):
                return SimpleNamespace(q=q, iterations=it, residual=res / scale, slack=slack)
            rows, s = dr.removed_stiffness(slack, np.zeros_like(slack), 0.0, 1.0)
            q = q - LowRankSolve(cache, rows, s)(R)
            used = slack
        raise ConvergenceError(f"linear catenary statics: residual {res:.3e} N after "
                               f"{max_iter} iterations", residual=res)

"""HHT-alpha steps of the modal catenary in closed form (the interface of
:class:`~pantocosim.core.affine_hht.AffineHHT`, so :mod:`pantocosim.core.condensed` and the
catenary FMU take them like the linear model's).

With y_{n+1} = y_p + Delta (the Newmark predictors y_p, v_p of (3.16)-(3.17)), the HHT
equation (3.16) of :class:`~.modal.ModalCatenary` is, for a given slack set,

    A Delta = alpha f_n - c_f f_rest(y_p, v_p) + c_f [slack and committed terms at y_p, v_p]
              + c_f sum_k F_k n_k(t + h),

A = diag(c_a + c_f (c_v zeta_j + omega_j^2)) on eta, c_f k (1 + c_v beta) on zeta,
c_f G(t + h)^-1 on xi, less the slack droppers' rank-one rows c_f k_a t_d t_d^T (and the
committed ones' damping share): diagonal plus a small Woodbury correction, nothing to
factorize. Delta = Delta_free + sum_k F_k w_k; the slack set is checked once at y_{n+1} (the
previous step's set is the first guess) and the step re-solved when it changed, so
slackening stays exact. f_{n+1} = (alpha f_n - f_inertia(a_{n+1})) / c_f follows from (3.16).
"""

from __future__ import annotations

import numpy as np

from ..core.affine_hht import _new_id, check_slack_passes, restore_step_state, step_state
from . import modal_kernels as _k


class ModalHHT:
    """``ModalHHT(model, settings)``: ``initialize(t0, y0, v0, F0)``; per step
    ``begin(h, loads)``, read :attr:`q_p`, :attr:`v_p`, :attr:`delta_free`, :attr:`W`, then
    ``finish(F)`` (False: the slack set changed and the step was re-solved; supply F
    again)."""

    def __init__(self, model, settings, keep_free_response: bool = False):
        self.model, self.settings = model, settings
        self.keep_free_response = keep_free_response
        N = self.N = model.n_dofs
        self.K = model.m + model.nz                  # the coordinates droppers see
        self.t, self.n_steps = 0.0, 0
        self.q, self.v, self.a, self.f = (np.zeros(N) for _ in range(4))
        self.q_p, self.v_p, self._zero = (np.zeros(N) for _ in range(3))
        self._rhs, self.delta_free, self._delta = (np.zeros(N) for _ in range(3))
        self._rhs2, self._sf = np.zeros(N), np.zeros(N)
        self.committed = np.zeros(len(model.droppers), dtype=bool)
        self._y, self._e = np.zeros(N), np.zeros(len(model.droppers))
        self._slack_buf = np.zeros(len(model.droppers), dtype=bool)
        self._slack = np.zeros(len(model.droppers), dtype=bool)
        self._F = np.zeros(0)
        self.W = np.zeros((0, N))
        self._h, self._coef = None, None
        self._loads = []
        self.passes = 0
        self._id = _new_id()
        self._memo = None

    # ------------------------------------------------------------------ set-up
    def initialize(self, t0: float, q0, v0=None, F0=None) -> None:
        """State at t0; a0 from the mass rows of -f_rest(t0, y0, v0, F0) (the quasi-static
        rows as the integrator's initial acceleration takes them)."""
        model = self.model
        self.t, self.n_steps = float(t0), 0
        self.q[:] = q0
        self.v[:] = 0.0 if v0 is None else v0
        self.committed = model.dropper_slack(self.q)
        model.set_internal_state({"slack": self.committed})
        ev = model.evaluate(self.t, self.q, self.v, self._zero, F0, tangent=False)
        self.f[:] = ev.f_rest
        self.a[:] = -ev.f_rest
        self._h = None
        self._id, self._memo = _new_id(), None

    @property
    def c_v(self) -> float:
        return self._coef[1]

    # ------------------------------------------------------------------ one step
    def begin(self, h: float, loads) -> None:
        s = self.settings
        if h != self._h:
            self._coef = s.newton_coefficients(h)
            self._h = h
        self._loads = list(loads)
        self.passes = 0
        memo = self._memo
        if memo is not None and memo[0] == (self._id, h):
            self.q_p[:], self.v_p[:], self._rhs[:] = memo[1]
            self.model.geometry(self.t + h)
            self._solve(self.committed)
            return
        c_a, c_v, c_f = self._coef
        model = self.model
        g = model.geometry(self.t + h)
        _k.predict_rhs(self.q, self.v, self.a, self.f, h, s.alpha, s.beta, s.gamma, c_f,
                       model.zeta_c, model.omega2, model.r0, model.kbar, model.linear.beta_r,
                       model.m, model.nz, g.Ginv, self.q_p, self.v_p, self._rhs)
        if self.keep_free_response:
            self._memo = ((self._id, h), (self.q_p.copy(), self.v_p.copy(), self._rhs.copy()))
        self._solve(self.committed)

    def _solve(self, slack: np.ndarray) -> None:
        """delta_free and W for the slack set ``slack``."""
        model = self.model
        c_a, c_v, c_f = self._coef
        rhs = self._rhs
        if slack.any() or self.committed.any():
            dr = model.droppers
            _k.slack_forces(model.T_K, dr.N0, dr.ka, dr.beta, slack, self.committed, self.q_p,
                            self.v_p, self._sf)
            rhs = self._rhs2
            np.multiply(self._sf, c_f, out=rhs)
            rhs += self._rhs
        solve = model.step_solve(c_a, c_v, c_f, slack, self.committed)
        solve(rhs, out=self.delta_free)
        m = len(self._loads)
        if self.W.shape[0] != m:
            self.W = np.zeros((m, self.N))
        n = self._zero
        for k, (dofs, w) in enumerate(self._loads):
            if dofs is self.model.contact_dofs:   # the model's own points: every y, in order
                np.multiply(w, c_f, out=n)
            else:
                n[:] = 0.0
                n[dofs] = c_f * np.asarray(w, dtype=float)
            solve(n, out=self.W[k])
        n[:] = 0.0
        self._slack = slack
        self.passes += 1

    def finish(self, F) -> bool:
        model, dr = self.model, self.model.droppers
        F = F if type(F) is np.ndarray and F.dtype == np.float64 else np.asarray(F, float)
        if _k.step_and_check(self.delta_free, self.W, F.reshape(-1), self.q_p, model.T_K,
                             dr.N0, dr.ka, dr.tension_only, self._delta, self._y, self._e,
                             self._slack_buf, self._slack):
            slack = self._slack_buf.copy()
            check_slack_passes("modal catenary", self.passes, self.t + self._h,
                               self.n_steps + 1)
            self._solve(slack)
            return False
        delta = self._delta
        c_a, c_v, c_f = self._coef
        _k.finish_step(self.q_p, self.v_p, delta, c_a, c_v, c_f, self.settings.alpha, model.m,
                       self.q, self.v, self.a, self.f)
        slack = self._slack
        if not np.array_equal(slack, self.committed):
            self.committed = slack
            model.set_internal_state({"slack": slack})
        self.t += self._h
        self.n_steps += 1
        self._id = _new_id()
        return True

    # ------------------------------------------------------------------ state
    def get_state(self) -> dict:
        return step_state(self)

    def set_state(self, state: dict) -> None:
        restore_step_state(self, state)
        self.model.set_internal_state({"slack": self.committed})

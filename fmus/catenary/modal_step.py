"""HHT-alpha steps of the modal catenary in closed form (the interface of
:class:`~pantocosim.core.affine_hht.AffineHHT`, so :mod:`pantocosim.interaction.condensed` and the
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

Per step: one kernel for the predictor and rhs, one for delta_free and W (the Woodbury pieces
kept per pair of slack and committed sets), one for the check and the end of the step. The
check does not form T y[:K] (droppers x coordinates, the bulk of a step) each time: a kept
reference and a bound of the droppers' drift from it settle most droppers; the others take
their row, in single precision with a bound of its error (double precision when that is too
close); every few steps every row and a new reference. The set is the one of the
double-precision product, to round-off.
"""

from __future__ import annotations

import numpy as np

from ..core.affine_hht import _new_id, check_slack_passes, restore_step_state, step_state
from ..core.stepper_contract import register_closed_form_step
from . import modal_kernels as _k

#: slack sets whose Woodbury pieces are kept (first in, first out)
KEPT_SOLVES = 64


@register_closed_form_step("modal")
class ModalHHT:
    """``ModalHHT(model, settings)``: ``initialize(t0, y0, v0, F0)``; per step
    ``begin(h, loads)``, read :attr:`q_p`, :attr:`v_p`, :attr:`delta_free`, :attr:`W`, then
    ``finish(F)`` (False: the slack set changed and the step was re-solved; supply F
    again): a :class:`~pantocosim.core.stepper_contract.ClosedFormStep`, registered as ``"modal"``.

    The constant step data are the model's (:class:`~.modal.ModalCatenary`): ``omega2``
    and ``zeta_c`` (the modal diagonal), ``kbar`` and ``T_K`` (the droppers' static
    correction and elongation rows), ``droppers`` (their rank-one terms), ``r0``, and the
    moving interface ``geometry(t)``; :class:`ModalSolve` holds the Woodbury pieces of a
    slack set."""

    def __init__(self, model, settings, keep_free_response: bool = False):
        self.model, self.settings = model, settings
        self.keep_free_response = keep_free_response
        N = self.N = model.n_dofs
        self.K = model.m + model.nz                  # the coordinates droppers see
        self.t, self.n_steps = 0.0, 0
        self.q, self.v, self.a, self.f = (np.zeros(N) for _ in range(4))
        self.q_p, self.v_p, self._zero = (np.zeros(N) for _ in range(3))
        self._rhs, self.delta_free, self._delta = (np.zeros(N) for _ in range(3))
        self._r, self._sf = np.zeros(N), np.zeros(N)
        nd = len(model.droppers)
        self.committed = np.zeros(nd, dtype=bool)
        self._slack_buf = np.zeros(nd, dtype=bool)
        self._slack = np.zeros(nd, dtype=bool)
        self._screen = _screen_tables(model)
        ref = np.zeros((3, nd))
        ref[0] = np.nan                     # no reference yet: the first check takes every row
        nb = self._screen[2].shape[1]
        self._screen_work = (np.zeros(self.K), ref, np.zeros((2, nb)),
                             np.zeros(self.K, dtype=np.float32))
        self.W = np.zeros((0, N))
        self._L = np.zeros((0, N))
        self._h, self._coef = None, None
        self._solves = {}
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

    def prepare(self, h: float) -> None:
        """Nothing to pay ahead: the Newton matrix is diagonal plus the Woodbury pieces of
        each slack set, formed when the set first occurs."""

    # ------------------------------------------------------------------ one step
    def begin(self, h: float, loads) -> None:
        s = self.settings
        if h != self._h:
            self._coef = s.newton_coefficients(h)
            self._h = h
            self._solves.clear()
        self._loads = loads = list(loads)
        self.passes = 0
        memo = self._memo
        if memo is not None and memo[0] == (self._id, h):
            self.q_p[:], self.v_p[:], self._rhs[:] = memo[1]
            self._load_rows(loads, self.model.geometry(self.t + h))
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
        self._load_rows(loads, g)
        self._solve(self.committed)

    def _load_rows(self, loads, g) -> None:
        """The loads' weights as rows on y (:attr:`_L`): the model's own contact points
        are the geometry's rows themselves."""
        own, pts = self.model.contact_dofs, g.points
        if len(loads) == len(pts) and all(d is own and w is p.weights
                                          for (d, w), p in zip(loads, pts)):
            self._L = g.Wc
        else:
            self._L = L = np.zeros((len(loads), self.N))
            for k, (dofs, w) in enumerate(loads):
                L[k, dofs] = w
        if self.W.shape[0] != len(loads):
            self.W = np.zeros((len(loads), self.N))

    def _woodbury(self, slack: np.ndarray) -> ModalSolve:
        """The solve with the step's Newton matrix less the rank-one rows of ``slack`` and
        the committed set (kept per pair of sets)."""
        key = slack.tobytes() + self.committed.tobytes()
        ws = self._solves.get(key)
        if ws is None:
            c_a, c_v, c_f = self._coef
            rows, s = self.model.droppers.removed_stiffness(slack, self.committed, c_v, c_f)
            ws = ModalSolve(self.model, c_a, c_v, c_f, rows, s)
            if len(self._solves) >= KEPT_SOLVES:
                del self._solves[next(iter(self._solves))]
            self._solves[key] = ws
        return ws

    def _solve(self, slack: np.ndarray) -> None:
        """delta_free and W for the slack set ``slack``."""
        model, dr = self.model, self.model.droppers
        ws = self._woodbury(slack)
        _k.solve_step(self._rhs, self.q_p, self.v_p, self._coef[2], model.T_K, dr.N0, dr.ka,
                      dr.beta, slack, self.committed, ws.inv_diag, model._g.G, ws.U, ws.rows,
                      ws.small_inv, ws.s, ws.y, self._L, self._sf, self._r, self.delta_free,
                      self.W)
        self._slack = slack
        self.passes += 1

    def finish(self, F) -> bool:
        F = F if type(F) is np.ndarray and F.dtype == np.float64 else np.asarray(F, float)
        c_a, c_v, c_f = self._coef
        changed = _k.finish_step(self.delta_free, self.W, F.reshape(-1), self.q_p, self.v_p,
                                 *self._screen, *self._screen_work, self._slack,
                                 self.committed, c_a, c_v, c_f, self.settings.alpha,
                                 self.model.m, self._delta, self._slack_buf, self.q, self.v,
                                 self.a, self.f)
        if changed < 0:
            check_slack_passes("modal catenary", self.passes, self.t + self._h,
                               self.n_steps + 1)
            self._solve(self._slack_buf.copy())
            return False
        if changed:
            self.committed = self._slack
            self.model.set_internal_state({"slack": self._slack})
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


def _screen_tables(model) -> tuple:
    """(T32, T_K, Tb, Tm, tol, N0, k_a, tension_only, most) of
    :func:`~.modal_kernels.screen_slack`: T_K in single precision; on blocks of
    SCREEN_BLOCK coordinates, |k_a,d| times the 2-norms (Tb, a hair up for their own
    rounding) and the largest entries (Tm) of t_d; the factors 2 gamma_{K+2} of single and
    double precision (tol; gamma_n = n u / (1 - n u)); a new reference when more than an
    eighth of the droppers are open."""
    T = model.T_K
    nd, K = T.shape
    dr = model.droppers
    ka = np.abs(dr.ka)[:, None]
    edges = np.arange(0, K, _k.SCREEN_BLOCK)
    if K:
        Tb = np.sqrt(np.add.reduceat(T * T, edges, axis=1)) * ka * (1.0 + 1e-9)
        Tm = np.maximum.reduceat(np.abs(T), edges, axis=1) * ka
    else:
        Tb = Tm = np.zeros((nd, 0))
    tol = np.array([2.0 * (K + 2) * u / (1.0 - (K + 2) * u) for u in (2.0 ** -24, 2.0 ** -53)])
    return (np.ascontiguousarray(T, dtype=np.float32), T, np.ascontiguousarray(Tb),
            np.ascontiguousarray(Tm), tol, dr.N0, dr.ka, dr.tension_only, max(1, nd // 8))


class ModalSolve:
    """(A0 - sum_d s_d t_d t_d^T)^-1 with A0 = diag on eta and zeta (+) c_f G^-1 on xi (G at
    the latest geometry). The diagonal, U = T diag^-1 and the droppers' Gram matrix
    T diag^-1 T^T are the model's per coefficient set (:meth:`~.modal.ModalCatenary.woodbury_base`),
    so a slack set costs the inverse of its own small block only."""

    def __init__(self, model, c_a, c_v, c_f, rows, s):
        self.model, self.c = model, (c_a, c_v, c_f)
        self.inv_diag, self.U, gram = model.woodbury_base(c_a, c_v, c_f)
        self.K = model.m + model.nz
        self.rows = np.ascontiguousarray(rows, dtype=np.int64)
        self.s = np.ascontiguousarray(s, dtype=float)
        ns = self.rows.size
        self.small_inv = np.empty((ns, ns))
        if not _k.slack_block_inverse(gram, self.rows, self.s, np.empty((ns, 2 * ns)),
                                      self.small_inv):
            raise np.linalg.LinAlgError("modal catenary: singular slack-set correction")
        self.y = np.zeros(ns)

    def __call__(self, r, out=None):
        r = np.ascontiguousarray(r, dtype=float)
        out = np.empty_like(r) if out is None else out
        _k.diag_woodbury(r, 1.0, self.inv_diag, self.K, self.model._g.G, self.c[2], self.U,
                         self.model.T_K, self.rows, self.small_inv, self.s, self.y, out)
        return out

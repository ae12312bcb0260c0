"""HHT-alpha steps of a linear structure with unilateral rank-one elements, in closed form.

The structure (an :class:`AffineForm`, e.g. the linear catenary's
:meth:`~pantocosim.catenary.linear.LinearCatenary.affine_form`):

    M a + C v + K d + r0 - sum_{s slack at d} (N0_s + k_s b_s . d) b_s
        - sum_{s in the committed slack set} beta k_s (b_s . v) b_s = sum_k F_k n_k(t),

with C = alpha_r M + beta_r K (Rayleigh, (3.1)), d = q - q_ref and loads F_k on vectors
n_k(t) (the moving contact points, (3.13)). With q_{n+1} = q_p + Delta (the Newmark
predictors q_p, v_p of (3.16)-(3.17)), the HHT equation (3.16) is linear in Delta for a given
slack set:

    A_s Delta = alpha f_n - c_f (C v_p + K d_p + r0)
                + c_f [sum_slack (N0 + k b . d_p) b + sum_committed beta k (b . v_p) b]
                + c_f sum_k F_k n_k,

A_s = c_a M + c_f (c_v C + K) less the slack elements' rank-one terms (Woodbury on the kept
factorization, :mod:`.lowrank`). Hence Delta = Delta_free + sum_k F_k w_k with
w_k = c_f A_s^-1 n_k: a step is one solve with the factor kept for the run, the response
columns from cached unit-vector solves, and one product with the sparse band of M (the
right-hand side comes from kept products of the state, :mod:`.affine_kernels`). Whoever
supplies F_k (an FMU input, or a penalty contact solved on the small interface,
:mod:`.condensed`) calls :meth:`AffineHHT.finish`; the slack set is checked at q_{n+1} and the
step re-solved with the new set when it changed, so slackening is exact. The new
f_{n+1} = (alpha f_n - M a_{n+1}) / c_f follows from (3.16) itself (with M Delta).
"""

from __future__ import annotations

import weakref
from collections import OrderedDict
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from . import affine_kernels as kern
from .banded import SparseBand
from .errors import ConvergenceError
from .lowrank import LowRankSolve
from .state_label import new_label as _new_id
from .stepper_contract import register_closed_form_step

#: slack-set re-solves of one step before it is declared not converged
MAX_SLACK_PASSES = 20
#: steps after which the kept products of the state are formed again from it
#: (:mod:`.affine_kernels`: they carry the round-off of their updates)
RESYNC_STEPS = 4096
#: memory the unilateral elements' columns may take when solved at set-up
#: (:meth:`AffineHHT.prepare`)
PREFILL_BYTES = 256 * 2**20
#: Woodbury solves kept, one per slack set (a dropper slackens and re-tensions over a few
#: steps, and neighbouring droppers do so in turn: the same sets come back)
KEPT_SLACK_SETS = 64


def check_slack_passes(what: str, passes: int, t: float, step: int) -> None:
    """Refuse another re-solve of a step whose slack set keeps changing."""
    if passes >= MAX_SLACK_PASSES:
        raise ConvergenceError(f"{what}: the slack set does not settle at t = {t:.6g} s after "
                               f"{passes} passes", time=t, step=step)


def step_state(st) -> dict:
    """The state of a closed-form HHT stepper (:class:`AffineHHT`, the modal catenary's):
    time, step count, q, v, a, f_n, state label and committed slack set."""
    return {"t": st.t, "n_steps": st.n_steps, "q": st.q.copy(), "v": st.v.copy(),
            "a": st.a.copy(), "f": st.f.copy(), "id": st._id,
            "committed": st.committed.copy()}


def restore_step_state(st, state: dict) -> None:
    """Put back a :func:`step_state`."""
    st.t, st.n_steps = float(state["t"]), int(state["n_steps"])
    for name in ("q", "v", "a", "f"):
        getattr(st, name)[:] = state[name]
    st.committed = np.array(state["committed"], dtype=bool)
    st._id = state["id"]


class KeptProducts:
    """The kept products of a saved state (:meth:`AffineHHT.get_state`): the stepper's buffer
    itself for as long as the stepper leaves it alone, a copy of it from the moment the
    stepper is about to write it (:meth:`detach`), or when the state is pickled or copied. A
    master that frees each saved state before the next step (fmi2FreeFMUstate) never pays for
    the copy."""

    __slots__ = ("buffer", "data", "__weakref__")

    def __init__(self, buffer: np.ndarray):
        self.buffer, self.data = buffer, None

    def detach(self) -> None:
        if self.buffer is not None:
            self.data, self.buffer = self.buffer.copy(), None

    @property
    def array(self) -> np.ndarray:
        return self.buffer if self.buffer is not None else self.data

    def __getstate__(self):
        return self.array.copy()

    def __setstate__(self, data) -> None:
        self.buffer, self.data = None, data


@dataclass
class AffineForm:
    """What :class:`AffineHHT` needs of a linear structure: the constant data of its step
    (a native export writes these)."""

    n: int
    #: mass and stiffness, lower band storage (LAPACK 'L'): X_band[k, j] = X[j + k, j]
    M_band: np.ndarray
    K_band: np.ndarray
    #: Rayleigh damping C = alpha_r M + beta_r K (3.1)
    alpha_r: float
    beta_r: float
    #: the reference configuration d = q - q_ref is measured from
    q_ref: np.ndarray
    #: f_rest at q_ref, v = 0, no load (round-off of the statics)
    r0: np.ndarray
    #: the unilateral elements: axial(d, out), slack(N), slack_after(N_p, b_free, b_W, F,
    #: b_delta, previous), force(coef, mask),
    #: removed_stiffness(slack, damped, c_v, c_f), step_terms(N, v, slack, damped, c_v, c_f,
    #: out), vectors, beta, ka, N0 (:mod:`..catenary.linear_droppers`)
    unilateral: Any
    #: (c_a, c_v, c_f) -> ColumnCache of the kept factorization of c_a M + c_f (c_v C + K)
    factor: Callable
    #: (t, q, v, F) -> f_rest, with the committed slack set at q (initial acceleration)
    forces: Callable


class AffineHHT:
    """``AffineHHT(form, settings)``; ``initialize(t0, q0, v0, F0)``; per step
    ``begin(h, loads)``, read :attr:`q_p`, :attr:`v_p`, :attr:`delta_free`, :attr:`W`,
    then ``finish(F)`` (False: the slack set changed, the free response and W were
    re-solved; supply F again): a :class:`~.stepper_contract.ClosedFormStep`, registered as
    ``"affine"`` (a model declaring ``stepping = "affine"`` gives its ``affine_form()``).

    The constant step data: :attr:`form` (matrices, unilateral elements' rank-one terms
    ``form.unilateral``), :meth:`factorization` (the kept banded factor of the step's
    Newton matrix)."""

    def __init__(self, form: AffineForm, settings, keep_free_response: bool = False):
        self.form = form
        #: keep the free response of each step for a redo from the same state (the FMU's
        #: rollback); a monolithic run never redoes a step
        self.keep_free_response = keep_free_response
        self.settings = settings
        n = form.n
        self.t, self.n_steps = 0.0, 0
        self.q, self.v, self.a, self.f = (np.zeros(n) for _ in range(4))
        self.q_p, self.v_p, self.d_p = (np.zeros(n) for _ in range(3))
        self._rhs, self.delta_free, self._delta = (np.zeros(n) for _ in range(3))
        #: M and K for the products (empty band diagonals skipped)
        self._M, self._K = (SparseBand.from_band(b).parts for b in (form.M_band, form.K_band))
        #: the kept products [K d, K v, K a, M v, M a] of the state (:mod:`.affine_kernels`)
        #: and of the state before the last step (a step writes the other buffer, so a
        #: rollback of it swaps them back)
        self._P, self._P_prev = np.zeros((5, n)), np.zeros((5, n))
        #: the saved states' :class:`KeptProducts` still on each buffer (by id of the buffer)
        self._on_buffer = {id(b): weakref.WeakSet() for b in (self._P, self._P_prev)}
        self._prev_id = None
        #: n_steps when each buffer was last formed from the state itself
        self._synced = self._prev_synced = 0
        #: the right-hand side solved with the slack terms, its load and rank-one terms
        #: (``_corr``, kept zero between steps), work vectors
        self._R, self._corr, self._MD, self._x, self._below = (np.zeros(n) for _ in range(5))
        #: axial forces at the predictor, b . Delta_free and b . w_k of the elements
        n_el = len(form.unilateral.ka)
        self._N_p, self._b_free, self._b_delta = (np.zeros(n_el) for _ in range(3))
        self._b_W = np.zeros((0, n_el))
        self._R_used, self._removed = self._rhs, None
        self.committed = np.zeros(len(form.unilateral.ka), dtype=bool)
        self.W = np.zeros((0, n))
        self._h, self._cache, self._coef = None, None, None
        self._woodbury: OrderedDict = OrderedDict()
        self._loads, self._slack = (), None
        self.passes = 0
        self._id = _new_id()
        #: (state id, h) of the last step begun: a step redone from the same state
        #: (co-simulation rollback) skips the prediction and the solve
        self._memo = None

    # ------------------------------------------------------------------ set-up
    def initialize(self, t0: float, q0, v0=None, F0=None) -> None:
        """State at t0; a0 from M a0 = -f_rest(t0, q0, v0, F0) (droppers slack at q0 also
        without force in the damping)."""
        fm = self.form
        self.t, self.n_steps = float(t0), 0
        self.q[:] = q0
        self.v[:] = 0.0 if v0 is None else v0
        un = fm.unilateral
        self.committed = un.slack(un.axial(self.q - fm.q_ref))
        self.f[:] = fm.forces(self.t, self.q, self.v, F0)
        self.a[:] = -fm.factor(1.0, 0.0, 0.0).solve(self.f)
        self._h = None
        self._form_products()
        self._prev_id = None
        self._id, self._memo = _new_id(), None

    @property
    def c_v(self) -> float:
        """dv/dq of the step begun, (3.18)."""
        return self._coef[1]

    def factorization(self, h: float):
        """(kept factorization, (c_a, c_v, c_f)) of A = c_a M + c_f (c_v C + K) for steps
        of h (3.18): a :class:`~.lowrank.ColumnCache` whose ``solve`` is the banded Cholesky
        factor (:class:`~.banded.BandedCholesky`), made once per coefficient set."""
        coef = self.settings.newton_coefficients(h)
        return self.form.factor(*coef), coef

    def _coefficients(self, h: float):
        if h != self._h:
            self._coef = self.settings.newton_coefficients(h)
            self._coef_arr = np.array(self._coef)
            self._cache = self.form.factor(*self._coef)
            self._h = h
        return self._coef

    def prepare(self, h: float) -> None:
        """Pay at set-up what the steps of size h would pay on first use: the factorization,
        every unilateral element's column A^-1 b_d (when they fit in
        :data:`PREFILL_BYTES`), one Woodbury solve and the slack elements' terms with no
        element slack (numba loads its kernels on first call). A paced loop then has no
        first-use step."""
        c_a, c_v, c_f = self._coefficients(h)
        un = self.form.unilateral
        n_el = len(un.ka)
        if n_el == 0:
            return
        if n_el * self.form.n * 8 <= PREFILL_BYTES:
            self._cache.prefill()
        rows = np.arange(min(n_el, 2), dtype=np.int64)
        LowRankSolve(self._cache, rows, np.ones(rows.size)).solve_into(self._rhs, self._x)
        none = np.zeros(n_el, dtype=bool)
        un.step_terms(self._N_p, self.v_p, none, none, c_v, c_f, self._x)

    def _to_write(self, buffer: np.ndarray) -> np.ndarray:
        """``buffer``, once the saved states still on it have their own copy."""
        watchers = self._on_buffer[id(buffer)]
        if watchers:                  # (listing an empty WeakSet costs 2 us a step)
            for kept in list(watchers):
                kept.detach()
            watchers.clear()
        return buffer

    def _form_products(self) -> None:
        """The kept products from the state itself."""
        self._to_write(self._P)
        kern.state_products(self._M, self._K, self.q, self.form.q_ref, self.v, self.a,
                            self._P, self._x, self._below)
        self._synced = self.n_steps

    # ------------------------------------------------------------------ one step
    def begin(self, h: float, loads) -> None:
        """Predict t + h and solve the free response and the load responses w_k of
        ``loads`` [(dofs, weights) of n_k(t + h)] for the slack set at the predictor."""
        fm, s = self.form, self.settings
        c_a, c_v, c_f = self._coefficients(h)
        self._loads = list(loads)
        self.passes = 0
        if self._memo == (self._id, h):
            # the step is redone from the state it was begun from (a co-simulation
            # rollback): the free response, W and the slack set are still in their buffers
            # (only a begin from another state overwrites them)
            self.passes = 1
            return
        if self.n_steps - self._synced >= RESYNC_STEPS:
            self._form_products()
        kern.predict_rhs(self.q, self.v, self.a, fm.q_ref, self._P, fm.r0, self.f, h, s.beta,
                         s.gamma, fm.alpha_r, fm.beta_r, s.alpha, c_f, self.q_p, self.v_p,
                         self.d_p, self._rhs)
        un = fm.unilateral
        un.axial(self.d_p, out=self._N_p)
        self._solve(un.slack(self._N_p))
        if self.keep_free_response:
            self._memo = (self._id, h)

    def _lowrank(self, rows, s) -> LowRankSolve:
        """The Woodbury solve of a slack set (the last :data:`KEPT_SLACK_SETS` kept)."""
        key = (self._h, rows.tobytes(), s.tobytes())
        kept = self._woodbury
        solve = kept.get(key)
        if solve is None:
            solve = kept[key] = LowRankSolve(self._cache, rows, s)
            if len(kept) > KEPT_SLACK_SETS:
                kept.popitem(last=False)
        else:
            kept.move_to_end(key)
        return solve

    def _solve(self, slack: np.ndarray) -> None:
        """delta_free and W for the slack set ``slack``."""
        un = self.form.unilateral
        c_a, c_v, c_f = self._coef
        rows = ()
        if slack.any() or self.committed.any():
            rhs = self._R
            rhs[:] = self._rhs
            rows, s = un.step_terms(self._N_p, self.v_p, slack, self.committed, c_v, c_f, rhs)
        if len(rows):
            solve = self._lowrank(rows, s)
            solve.solve_into(rhs, self.delta_free)
            self._R_used, self._removed = rhs, (rows, s)
        else:
            solve = self._cache.solve
            solve.solve_into(self._rhs, self.delta_free)
            self._R_used, self._removed = self._rhs, None
        m = len(self._loads)
        if self.W.shape[0] != m:
            self.W = np.zeros((m, self.form.n))
        for k, (dofs, w) in enumerate(self._loads):
            solve.solve_sparse(dofs, c_f * np.asarray(w, dtype=float), out=self.W[k])
        vec = un.vectors                        # the elements' elongations b . delta
        vec.dots(self.delta_free, out=self._b_free)
        if self._b_W.shape[0] != m:
            self._b_W = np.zeros((m, len(un.ka)))
        for k in range(m):
            vec.dots(self.W[k], out=self._b_W[k])
        self._slack = slack
        self.passes += 1

    def finish(self, F) -> bool:
        """Take the step with the loads F (one per load vector), or re-solve for the slack
        set at the resulting q_{n+1} and return False."""
        F = F if type(F) is np.ndarray and F.dtype == np.float64 else np.asarray(F, float)
        if F.size != self.W.shape[0]:
            raise ValueError(f"{F.size} loads given for {self.W.shape[0]} load vectors")
        F = F.reshape(-1)
        b_delta = self._b_delta                          # b . Delta of every element
        slack, changed = self.form.unilateral.slack_after(self._N_p, self._b_free, self._b_W,
                                                          F, b_delta, self._slack)
        if changed:
            check_slack_passes("linear structure", self.passes, self.t + self._h,
                               self.n_steps + 1)
            self._solve(slack)
            return False
        self._advance(F, b_delta)
        self._swap_products()
        self.committed = slack
        self.t += self._h
        self.n_steps += 1
        self._prev_id, self._id = self._id, _new_id()
        return True

    def _swap_products(self) -> None:
        self._P, self._P_prev = self._P_prev, self._P
        self._synced, self._prev_synced = self._prev_synced, self._synced

    def _advance(self, F, b_delta) -> None:
        """q, v, a of the step (Delta = Delta_free + sum_k F_k w_k) and the kept products,
        with A Delta = the right-hand side solved + the loads + the slack elements' rank-one
        terms (A_s = A less them; ``b_delta``: their b . Delta)."""
        c_f = self._coef[2]
        corr = self._corr
        for (dofs, w), Fk in zip(self._loads, F):
            kern.scatter_scaled(dofs, w, c_f * Fk, corr)
        if self._removed is not None:
            rows, s = self._removed
            self.form.unilateral.vectors.combine(s * b_delta[rows], rows, out=corr)
        fm, st = self.form, self.settings
        self._to_write(self._P_prev)
        kern.advance(self._M, self.q_p, self.v_p, self.delta_free, self.W, F, self._delta,
                     self._R_used, corr, self._h, st.alpha, st.beta, st.gamma,
                     self._coef_arr, fm.alpha_r, fm.beta_r, self.f, self.q, self.v, self.a, self._P, self._P_prev,
                     self._MD, self._below)
        self._prev_synced = self._synced

    # ------------------------------------------------------------------ state
    def get_state(self) -> dict:
        """The state with its kept products (:class:`KeptProducts`: copied only when a step
        is about to overwrite them while the state is still held)."""
        kept = KeptProducts(self._P)
        self._on_buffer[id(self._P)].add(kept)
        return {**step_state(self), "products": kept, "synced": self._synced}

    def set_state(self, state: dict) -> None:
        """Put back a :meth:`get_state` (with its kept products, so the steps that follow
        repeat bit for bit); those of the current or the previous state are still in their
        buffers."""
        current, label = self._id, state["id"]
        restore_step_state(self, state)
        if label == current:
            return
        if label == self._prev_id:
            self._swap_products()
            self._prev_id = current
            return
        products = state["products"]
        products = products.array if isinstance(products, KeptProducts) else products
        if products is self._P_prev:
            self._swap_products()
        elif products is not self._P:
            self._to_write(self._P)[:] = products
        self._synced = int(state["synced"])
        self._prev_id = None


@register_closed_form_step("affine")
def affine_step(model, settings, redo: bool = False) -> AffineHHT:
    """The closed-form step of a model with an ``affine_form()``."""
    return AffineHHT(model.affine_form(), settings, keep_free_response=redo)

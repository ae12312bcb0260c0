"""HHT-alpha time integration with Newton-Raphson (Hilber, Hughes & Taylor 1977).

The one integrator of the project: it drives every pantograph model, the catenary, and the
assembled monolithic system through :class:`pantocosim.core.model.SecondOrderModel`.

Standard form (the thesis writes it with eta = -alpha in
(3.16)-(3.24) with inconsistent signs):

    f_inertia(q_{n+1}, a_{n+1}) + (1 + alpha) f_rest_{n+1} - alpha f_rest_n = 0,
    q_{n+1} = q_n + h v_n + h^2 ((1/2 - beta) a_n + beta a_{n+1}),         (3.16)
    v_{n+1} = v_n + h ((1 - gamma) a_n + gamma a_{n+1}),
    alpha in [-1/3, 0],  gamma = 1/2 - alpha,  beta = (1 - alpha)^2 / 4.

``f_rest`` holds damping, internal, external and coupling forces, so a force applied through
a coupling port is weighted exactly like an internal force. Newton-Raphson iterates on
q_{n+1} with v and a expressed through (3.18); convergence is checked with the energy norm
|dq . R| (thesis 3.3.2) and with the residual relative to the size of the forces in it.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from numba import njit

from .errors import ConvergenceError, ParameterError
from .factor_reuse import FactorPolicy, FactorReuse, Factorization
from .hht_defaults import ALPHA_MAX, ALPHA_MIN, DEFAULT_ALPHA, RUN_RTOL, RUN_RTOL_MAX  # noqa: F401
from .model import SecondOrderModel
from .newmark_residual import iterate_kinematics, weighted_residual
from .state_label import new_label
from .stepper_contract import StepReport


@dataclass
class HHTSettings:
    alpha: float = DEFAULT_ALPHA
    #: residual test: ||R||_inf <= rtol * (size of the forces in R)
    rtol: float = 1e-10
    #: energy test: |dq_k . R_k| <= etol * |dq_0 . R_0|
    etol: float = 1e-14
    max_iterations: int = 30
    #: factorization policy of the Newton matrix (:class:`FactorReuse`)
    reuse_factorization: FactorReuse = FactorReuse.NEVER
    #: with reuse across steps: a step that needed more iterations than this marks the
    #: factorization stale, so the next step refactorizes at its first iteration; a step
    #: still unconverged after ``refresh_after + 4`` iterations refactorizes at once
    refresh_after: int = 6
    #: Newton starting guess: "constant" (a_{n+1} = a_n) or "linear" (a_{n+1} = 2 a_n -
    #: a_{n-1}, which follows a load moving along the wire much better); the converged
    #: solution does not depend on it
    predictor: str = "constant"
    #: models that declare a :class:`~pantocosim.core.model.LinearForm` (constant matrices,
    #: e.g. the lumped pantographs without friction or one-way damper) are stepped in closed
    #: form: one precomputed product per step instead of Newton-Raphson (the same solution
    #: to round-off); False forces the Newton path
    closed_form_linear: bool = True

    @classmethod
    def for_runs(cls, alpha: float, rtol: float | None = None) -> "HHTSettings":
        """The settings of simulation runs (monolithic solver, co-simulation subsystems,
        catenary FMU): one factorization kept across steps and refreshed after a step that
        needed more than two iterations, the linear predictor, and the residual tolerance
        ``rtol`` (default :data:`RUN_RTOL`; docs/performance.md shows its effect on the
        contact force is far below the time-discretization error). Checked: ``alpha`` in
        [-1/3, 0] and ``rtol`` in (0, :data:`RUN_RTOL_MAX`]."""
        out = cls(alpha=alpha, rtol=RUN_RTOL if rtol is None else float(rtol),
                  reuse_factorization=FactorReuse.ACROSS_STEPS, refresh_after=2,
                  predictor="linear")
        out.validate()
        if not out.rtol <= RUN_RTOL_MAX:
            raise ParameterError("rtol", out.rtol, f"must lie in (0, {RUN_RTOL_MAX:g}]")
        return out

    def validate(self, source: str | None = None) -> None:
        if not np.isfinite(self.alpha) or not (ALPHA_MIN <= self.alpha <= ALPHA_MAX):
            raise ParameterError("alpha", self.alpha, "HHT alpha must lie in [-1/3, 0]", source)
        if not isinstance(self.reuse_factorization, FactorReuse):
            raise ParameterError("reuse_factorization", self.reuse_factorization,
                                 "must be one of " + ", ".join(
                                     f"FactorReuse.{r.name}" for r in FactorReuse), source)
        if not (self.rtol > 0) or not (self.etol >= 0):
            raise ParameterError("rtol", self.rtol, "tolerances must be positive", source)
        if self.predictor not in ("constant", "linear"):
            raise ParameterError("predictor", self.predictor, 'must be "constant" or "linear"',
                                 source)
        if int(self.max_iterations) < 1:
            raise ParameterError("max_iterations", self.max_iterations, "must be >= 1", source)

    @property
    def gamma(self) -> float:
        return 0.5 - self.alpha

    @property
    def beta(self) -> float:
        return 0.25 * (1.0 - self.alpha) ** 2

    def newton_coefficients(self, h: float) -> tuple[float, float, float]:
        """(c_a, c_v, c_f) of the Newton matrix c_a M + c_f (c_v C + K) for step h: da/dq,
        dv/dq from (3.18) and the weight 1 + alpha of the forces at t + h."""
        return 1.0 / (self.beta * h * h), self.gamma / (self.beta * h), 1.0 + self.alpha


@njit(cache=True)
def _predict(q, v, a, a_guess, f_rest, h, alpha, beta, gamma):
    """Newmark predictors q_p, v_p of (3.16)-(3.17), the first iterate q_p + beta h^2 a_guess
    and the history term alpha f_rest_n."""
    n = q.shape[0]
    q_p = np.empty(n)
    v_p = np.empty(n)
    q0 = np.empty(n)
    hist = np.empty(n)
    cq = (0.5 - beta) * h * h
    cv = (1.0 - gamma) * h
    cg = beta * h * h
    for i in range(n):
        q_p[i] = q[i] + h * v[i] + cq * a[i]
        v_p[i] = v[i] + cv * a[i]
        q0[i] = q_p[i] + cg * a_guess[i]
        hist[i] = alpha * f_rest[i]
    return q_p, v_p, q0, hist


@njit(cache=True)
def _newton_update(q, x, R):
    """q - x for the Newton correction dq = -x, with |dq . R|, max |dq| and max |q - x|."""
    n = q.shape[0]
    out = np.empty(n)
    e = 0.0
    dq_max = 0.0
    q_max = 0.0
    for i in range(n):
        out[i] = q[i] - x[i]
        e += x[i] * R[i]
        dq_max = max(dq_max, abs(x[i]))
        q_max = max(q_max, abs(out[i]))
    return out, abs(e), dq_max, q_max


@njit(cache=True)
def _linear_step(q, v, a, a_prev, f_rest, w, S_inv, C, K, B, h, alpha, beta, gamma):
    """One HHT-alpha step of M a + C v + K q + B w = 0 in closed form, in place:

        S a_{n+1} = -(1 + alpha) (C v_p + K q_p + B w_{n+1}) + alpha f_rest_n,
        S = M + (1 + alpha) (gamma h C + beta h^2 K),

    with the Newmark predictors q_p, v_p; then q, v from (3.16), f_rest at t_{n+1}. On
    return a_prev holds a_n and (q, v, a, f_rest) the new step; ``w`` is w_{n+1}."""
    n = q.shape[0]
    m = w.shape[0]
    cq = (0.5 - beta) * h * h
    cv = (1.0 - gamma) * h
    c1 = 1.0 + alpha
    for i in range(n):
        a_prev[i] = a[i]
        q[i] = q[i] + h * v[i] + cq * a[i]      # q_p
        v[i] = v[i] + cv * a[i]                 # v_p
    for i in range(n):                          # f_rest <- right-hand side (row i only)
        r = 0.0
        for j in range(n):
            r += C[i, j] * v[j] + K[i, j] * q[j]
        for j in range(m):
            r += B[i, j] * w[j]
        f_rest[i] = alpha * f_rest[i] - c1 * r
    cg = beta * h * h
    cs = gamma * h
    for i in range(n):
        r = 0.0
        for j in range(n):
            r += S_inv[i, j] * f_rest[j]
        a[i] = r
    for i in range(n):
        q[i] += cg * a[i]
        v[i] += cs * a[i]
    for i in range(n):
        r = 0.0
        for j in range(n):
            r += C[i, j] * v[j] + K[i, j] * q[j]
        for j in range(m):
            r += B[i, j] * w[j]
        f_rest[i] = r


@njit(cache=True)
def _shift(q, v, a, f_rest, dq, dv, da, df, scale):
    """(q, v, a, f_rest) += scale (dq, dv, da, df) (:meth:`HHTIntegrator.shift_last_step`)."""
    for i in range(q.shape[0]):
        q[i] += scale * dq[i]
        v[i] += scale * dv[i]
        a[i] += scale * da[i]
    for i in range(f_rest.shape[0]):
        f_rest[i] += scale * df[i]


#: steps from one state kept for a redo (an implicit coupling's passes over one step)
KEPT_PASSES = 16


def _inputs_key(inputs) -> bytes | None:
    """Step inputs (None or an array) as a key: equal keys are bitwise equal inputs."""
    return None if inputs is None else inputs.dtype.str.encode() + inputs.tobytes()


def _vector(x, n: int) -> np.ndarray:
    return np.ascontiguousarray(x, dtype=np.float64).reshape(n)


class _Convergence:
    """The tests of a Newton iteration: the residual against the size of the forces in it,
    the energy norm |dq . R| against the first iteration's (thesis 3.3.2), or a correction
    at the round-off of q."""

    def __init__(self, rtol: float, etol: float):
        self.rtol, self.etol = rtol, etol
        self.e0 = self.e_prev = None
        self.dq_size = self.q_size = 0.0       # set by the first update
        self.done = False

    def converged(self, res_norm: float, scale: float) -> bool:
        done = res_norm <= self.rtol * max(scale, 1e-300)
        if not done and self.e_prev is not None and self.e0 is not None:
            done = self.e_prev <= self.etol * self.e0 or self.dq_size <= 1e-15 * self.q_size
        self.done = done
        return done

    def update(self, q, x, R):
        """q - x (the Newton correction dq = -x), recording the energy and the sizes."""
        q, e, self.dq_size, self.q_size = _newton_update(q, x, R)
        if self.e0 is None:
            self.e0 = max(e, 1e-300)
        self.e_prev = e
        return q


@dataclass
class _StepEnd:
    """A converged Newton step: t_{n+1}, q, v, a, the last evaluation, the iterations taken,
    the residual, the factorizations made and the factorization in use."""

    t: float
    q: np.ndarray
    v: np.ndarray
    a: np.ndarray
    ev: Any
    iterations: int
    residual: float
    refactorizations: int
    factor: Factorization | None


@dataclass
class ClosedFormStep:
    """The closed-form step of a model with a :class:`~.model.LinearForm`: its matrices,
    the load vector w, and S^-1 for the step size ``h`` (:func:`_linear_step`)."""

    form: Any
    C: np.ndarray
    K: np.ndarray
    B: np.ndarray
    w: np.ndarray
    alpha: float
    beta: float
    gamma: float
    #: the step size S_inv was formed for (None: not yet)
    h: float | None = None
    S_inv: np.ndarray | None = None


class HHTIntegrator:
    """Advances one :class:`SecondOrderModel` in time.

    Usage::

        integ = HHTIntegrator(model, HHTSettings(alpha=DEFAULT_ALPHA))
        integ.initialize(t0, q0, v0, inputs0)          # computes a0 unless given
        info = integ.step(h, inputs_at_t_plus_h)
    """

    def __init__(self, model: SecondOrderModel, settings: HHTSettings | None = None):
        self.model = model
        self.settings = settings or HHTSettings()
        self.settings.validate()
        self.t = 0.0
        self.n_steps = 0
        n = model.n_dofs
        self.q = np.zeros(n)
        self.v = np.zeros(n)
        self.a = np.zeros(n)
        self.a_prev = None      # a_{n-1}, for the linear predictor
        self.f_rest = np.zeros(n)
        self.inputs = None
        self._policy = FactorPolicy(self.settings)
        self._label = new_label()    # of the current state (:mod:`.state_label`)
        #: the steps taken from the last state stepped from: (its label, h, {inputs key: end
        #: state}). A step redone from that state (a co-simulation rollback) with inputs
        #: already seen is that end state, bit for bit, at no cost. (Starting the Newton
        #: iteration of a pass with new inputs from the previous pass's a_{n+1} was measured
        #: on dsa380-ave-300, implicit: 12 % more iterations than the linear predictor.)
        self._last_step = None
        self.total_iterations = 0
        self.total_factorizations = 0
        self._linear: ClosedFormStep | None = None
        self._linear_info = StepReport(iterations=1)
        #: the model evaluates an iterate's residual itself (:meth:`~.model.SecondOrderModel.iterate`)
        self._fused = bool(model.fused_iterate)
        self._bind_linear()

    def _bind_linear(self) -> None:
        """Use the closed-form step if the model declares itself linear (small dense)."""
        self._linear = None
        if not self.settings.closed_form_linear:
            return
        form = self.model.linear_form()
        if form is None:
            return
        n = self.model.n_dofs
        mats = [np.ascontiguousarray(x, dtype=np.float64) for x in (form.M, form.C, form.K)]
        B = np.ascontiguousarray(np.atleast_2d(form.B), dtype=np.float64).reshape(n, -1)
        if any(x.shape != (n, n) for x in mats):
            raise ParameterError("linear_form", [x.shape for x in mats],
                                 f"M, C, K must be {n} x {n}")
        s = self.settings
        self._linear = ClosedFormStep(form, mats[1], mats[2], B, np.zeros(B.shape[1]),
                                      float(s.alpha), float(s.beta), float(s.gamma))

    @property
    def closed_form(self) -> bool:
        """True when steps are taken in closed form (a linear model, no Newton)."""
        return self._linear is not None

    @property
    def closed_form_step(self) -> ClosedFormStep | None:
        """The closed-form step's constant data (its matrices and S^-1 once a step of size
        ``h`` was taken; read by the native FMU export), None for a Newton stepper."""
        return self._linear

    def prepare(self, h: float) -> None:
        """Nothing to pay ahead: the first Newton step factorizes (a warm-up step pays it,
        :func:`~.stepper_contract.warm_up`)."""

    # ------------------------------------------------------------------ setup
    def initialize(self, t0: float, q0, v0=None, inputs0=None, a0=None) -> None:
        """Set the initial state; a0 solves M(q0) a0 = -f_rest(t0, q0, v0) unless given."""
        n = self.model.n_dofs
        self.t = float(t0)
        self.q = np.array(q0, dtype=float).reshape(n)
        self.v = np.zeros(n) if v0 is None else np.array(v0, dtype=float).reshape(n)
        self.inputs = None if inputs0 is None else np.array(inputs0, dtype=float)
        zero = np.zeros(n)
        ev = self.model.evaluate(self.t, self.q, self.v, zero, self.inputs, tangent=True)
        if a0 is None:
            # at a = 0 the Newton matrix with c_a = 1, c_v = c_f = 0 is the mass matrix
            solve = self.model.factorize(self.model.effective_matrix(ev, 1.0, 0.0, 0.0))
            self.a = -np.asarray(self.model.newton_solve(solve, ev, ev.f_rest + ev.f_inertia),
                                 dtype=float).reshape(n)
        else:
            self.a = np.array(a0, dtype=float).reshape(n)
        self.f_rest = np.array(ev.f_rest, dtype=float)
        self.a_prev = None
        self.n_steps = 0
        self._policy.reset()
        self._label, self._last_step = new_label(), None
        self._bind_linear()
        self.model.commit(self.t, self.q, self.v, self.a, self.inputs)

    # ------------------------------------------------------------------ stepping
    def step(self, h: float, inputs=None) -> StepReport:
        """Advance from t to t + h with the coupling inputs valid at t + h."""
        if self._linear is not None:
            return self._step_linear(h, inputs)
        inputs = None if inputs is None else np.asarray(inputs, dtype=float)
        start = self._label
        passes = self._passes_from(start, h)
        seen = passes.get(_inputs_key(inputs)) if passes else None
        if seen is not None:
            return self._repeat(seen, inputs)
        predicted = self._predict(h)
        factor = self._policy.start(h, start)
        end = self._newton(h, inputs, predicted, factor)
        info = self._commit(end, inputs)
        self._remember(start, h, passes, end.residual)
        return info

    def _predict(self, h: float):
        """(q_p, v_p, first iterate, alpha f_rest_n) of a step of size h, (3.16)-(3.17),
        with the settings' predictor of a_{n+1}."""
        s = self.settings
        a_guess = self.a
        if s.predictor == "linear" and self.a_prev is not None:
            a_guess = 2.0 * self.a - self.a_prev
        return _predict(self.q, self.v, self.a, a_guess, self.f_rest, h, s.alpha, s.beta,
                        s.gamma)

    def _newton(self, h: float, inputs, predicted, factor) -> "_StepEnd":
        """Newton-Raphson on q_{n+1} from the predicted iterate: R of (3.16) with v, a from
        (3.18), the Newton matrix factorized as the policy says."""
        s, model, policy = self.settings, self.model, self._policy
        c_a, c_v, c_f = s.newton_coefficients(h)
        q_p, v_p, q, hist = predicted
        t1 = self.t + h
        n = q.shape[0]
        test = _Convergence(s.rtol, s.etol)
        refactorizations = 0
        for k in range(s.max_iterations + 1):
            ev, need_tangent, a, v, R, res_norm, scale = self._iterate(
                t1, q, predicted, (c_a, c_v, c_f), inputs, factor, k)
            if not np.isfinite(res_norm):
                raise ConvergenceError(
                    f"HHT: non-finite residual at t = {t1:.6g} s (step {self.n_steps + 1})",
                    time=t1, step=self.n_steps + 1, residual=res_norm)
            if test.converged(res_norm, scale) or k == s.max_iterations:
                break
            if need_tangent:
                S = model.effective_matrix(ev, c_a, c_v, c_f)
                factor = Factorization(ev.structure_key, h, S, model.factorize(S))
                policy.made(k, factor)
                refactorizations += 1
            q = test.update(q, _vector(model.newton_solve(factor.solve, ev, R), n), R)
        if not test.done:
            raise ConvergenceError(
                f"HHT Newton-Raphson did not converge at t = {t1:.6g} s (step "
                f"{self.n_steps + 1}, h = {h:.3g} s): residual {res_norm:.3e} after "
                f"{s.max_iterations} iterations", time=t1, step=self.n_steps + 1,
                residual=res_norm)
        return _StepEnd(t1, q, v, a, ev, k, res_norm, refactorizations, factor)

    def _iterate(self, t1, q, predicted, coefficients, inputs, factor, k: int):
        """(evaluation, whether it has the tangent, a, v, R, max |R|, size of the forces) at
        iterate k. The tangent is evaluated when the policy factorizes: always without a kept
        factorization, and when the structure key moved away from it. A model with a fused
        iterate (``fused_iterate``) gives it all in one call, else it is evaluated between
        the kernels of :mod:`.newmark_residual`."""
        need_tangent = self._policy.needs_tangent(k, factor)
        out = self._evaluate(t1, q, predicted, coefficients, inputs, need_tangent)
        if not need_tangent and out[0].structure_key != factor.structure_key:
            need_tangent = True
            out = self._evaluate(t1, q, predicted, coefficients, inputs, True)
        return (out[0], need_tangent) + out[1:]

    def _evaluate(self, t1, q, predicted, coefficients, inputs, tangent: bool):
        """(evaluation, a, v, R, max |R|, size of the forces) at the iterate q."""
        q_p, v_p, _, hist = predicted
        c_a, c_v, c_f = coefficients
        model = self.model
        if self._fused:
            return model.iterate(t1, q, q_p, v_p, c_a, c_v, c_f, hist, inputs, tangent)
        a, v = iterate_kinematics(q, q_p, v_p, c_a, c_v)
        ev = model.evaluate(t1, q, v, a, inputs, tangent=tangent)
        n = q.shape[0]
        R, r_max, scale = weighted_residual(_vector(ev.f_inertia, n), _vector(ev.f_rest, n),
                                            hist, c_f)
        return ev, a, v, R, r_max, scale

    def _commit(self, end: "_StepEnd", inputs) -> StepReport:
        """Take the converged step: the new state, the counters, the kept factorization."""
        self.t = end.t
        self.a_prev = self.a
        self.q, self.v, self.a = end.q, end.v, end.a
        self.f_rest = np.array(end.ev.f_rest, dtype=float)
        self.inputs = None if inputs is None else inputs.copy()
        self.n_steps += 1
        self.total_iterations += end.iterations
        self.total_factorizations += end.refactorizations
        self._policy.finish(end.iterations, end.factor)
        self.model.commit(self.t, self.q, self.v, self.a, self.inputs)
        self._label = new_label()
        return StepReport(iterations=end.iterations, residual=end.residual,
                          refactorizations=end.refactorizations)

    def _remember(self, start, h: float, passes: dict | None, residual: float) -> None:
        """Keep the step's end state under its inputs for a redo from ``start``."""
        end = {"t": self.t, "q": self.q, "v": self.v, "a": self.a, "a_prev": self.a_prev,
               "f_rest": self.f_rest, "factor": self._policy.factor,
               "stale": self._policy.stale, "residual": residual, "label": self._label}
        passes = passes or {}
        if len(passes) >= KEPT_PASSES:
            passes.pop(next(iter(passes)))
        passes[_inputs_key(self.inputs)] = end
        self._last_step = (start, h, passes)

    def _passes_from(self, start, h: float) -> dict | None:
        """The steps of size h taken from the state labelled ``start`` (by their inputs)."""
        last = self._last_step
        return last[2] if last is not None and last[0] == start and last[1] == h else None

    def _repeat(self, end: dict, inputs) -> StepReport:
        """The step last taken from this state with these inputs, again: its end state."""
        self.t = end["t"]
        self.q, self.v, self.a, self.a_prev, self.f_rest = (
            end[k].copy() for k in ("q", "v", "a", "a_prev", "f_rest"))
        self.inputs = None if inputs is None else inputs.copy()
        self._policy.factor, self._policy.stale = end["factor"], end["stale"]
        self._label = end["label"]
        self.n_steps += 1
        self.model.commit(self.t, self.q, self.v, self.a, self.inputs)
        return StepReport(iterations=0, residual=end["residual"])

    def _step_linear(self, h: float, inputs) -> StepReport:
        """The closed-form step of a :class:`~.model.LinearForm` model: writes q, v, a, a_prev,
        f_rest and inputs in place (no allocation once the arrays exist)."""
        lin = self._linear
        C, K, B, w = lin.C, lin.K, lin.B, lin.w
        alpha, beta, gamma = lin.alpha, lin.beta, lin.gamma
        if h != lin.h:
            S = lin.form.M + (1.0 + alpha) * (gamma * h * C + beta * h * h * K)
            lin.h, lin.S_inv = h, np.ascontiguousarray(np.linalg.inv(S))
        S_inv = lin.S_inv
        t1 = self.t + h
        stored = self.inputs
        if inputs is None:
            stored = self.inputs = None
        elif (stored is None or type(inputs) is not np.ndarray
              or stored.shape != inputs.shape):
            stored = self.inputs = np.array(inputs, dtype=float)
        else:
            stored[...] = inputs
        lin.form.fill(t1, stored, w)
        if self.a_prev is None:
            self.a_prev = np.empty_like(self.a)
        _linear_step(self.q, self.v, self.a, self.a_prev, self.f_rest, w, S_inv, C, K, B, h,
                     alpha, beta, gamma)
        self.t = t1
        self.n_steps += 1
        self.total_iterations += 1
        self.model.commit(t1, self.q, self.v, self.a, stored)
        return self._linear_info

    def input_response(self, h: float, inputs0, inputs1) -> tuple:
        """(dq, dv, da, df): how a closed-form step of size h from the current state changes
        when its inputs go from ``inputs0`` to ``inputs1`` (the step is affine in its inputs;
        the state is left as it was)."""
        saved = self.get_state()
        self.step(h, inputs0)
        base = [x.copy() for x in (self.q, self.v, self.a, self.f_rest)]
        self.set_state(saved)
        self.step(h, inputs1)
        out = tuple(x - b for x, b in zip((self.q, self.v, self.a, self.f_rest), base))
        self.set_state(saved)
        return out

    def shift_last_step(self, response: tuple, scale: float, inputs) -> None:
        """The last closed-form step as if taken with ``inputs``: the state moves by
        ``scale`` times an :meth:`input_response` (exact: the step is affine in its
        inputs)."""
        dq, dv, da, df = response
        _shift(self.q, self.v, self.a, self.f_rest, dq, dv, da, df, scale)
        self.inputs[...] = inputs

    # ------------------------------------------------------------------ state
    def get_state(self) -> dict:
        """Everything the next step depends on (copies), for rollback."""
        return {
            "t": self.t, "n_steps": self.n_steps,
            "q": self.q.copy(), "v": self.v.copy(), "a": self.a.copy(),
            "a_prev": None if self.a_prev is None else self.a_prev.copy(),
            "stale": self._policy.stale,
            "f_rest": self.f_rest.copy(),
            "inputs": None if self.inputs is None else self.inputs.copy(),
            # the factorization is immutable once made: keep a reference (in-memory) and the
            # matrix it came from (so a deserialized state refactorizes bitwise identically)
            "factor": self._policy.factor,
            "model": self.model.get_internal_state(),
            "label": self._label,
        }

    def set_state(self, state: dict) -> None:
        self.t = float(state["t"])
        self.n_steps = int(state["n_steps"])
        self.q = np.array(state["q"], dtype=float)
        self.v = np.array(state["v"], dtype=float)
        self.a = np.array(state["a"], dtype=float)
        a_prev = state.get("a_prev")
        self.a_prev = None if a_prev is None else np.array(a_prev, dtype=float)
        self._policy.stale = bool(state.get("stale", False))
        self.f_rest = np.array(state["f_rest"], dtype=float)
        self.inputs = None if state["inputs"] is None else np.array(state["inputs"], float)
        factor = state.get("factor")
        if factor is not None and factor.solve is None:
            factor = replace(factor, solve=self.model.factorize(factor.matrix))
        self._policy.factor = factor
        self._label = state.get("label") or new_label()
        self.model.set_internal_state(state.get("model"))

    @staticmethod
    def picklable_state(state):
        """:func:`picklable_state`."""
        return picklable_state(state)


def picklable_state(state):
    """A copy of a stepper's state (:meth:`HHTIntegrator.get_state`, or one holding such
    states) that pickles: every kept :class:`Factorization` without its solve object
    (:meth:`HHTIntegrator.set_state` factorizes its matrix again, bit for bit)."""
    if isinstance(state, Factorization):
        return replace(state, solve=None)
    if isinstance(state, dict):
        return {k: picklable_state(v) for k, v in state.items()}
    if type(state) in (list, tuple):
        return type(state)(picklable_state(v) for v in state)
    return state

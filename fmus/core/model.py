"""The interface every dynamic subsystem offers to the integrator (docs/architecture.md).

A model is a second-order system

    f_inertia(q, a) + f_rest(t, q, v, inputs) = 0,
    f_rest = f_damping(q, v) + f_internal(q) - f_external(t) - f_coupling(t, q, inputs),

where ``inputs`` are the values of the model's coupling ports at time t (e.g. the contact
force on a pantograph, or the forces of every pantograph on the catenary). The integrator
needs the two force pieces and their tangents:

    mass       = d f_inertia / d a
    inertia_q  = d f_inertia / d q   (None when the mass matrix is constant)
    damping    = d f_rest / d v
    stiffness  = d f_rest / d q

Matrices are dense ``numpy`` arrays for small models and ``scipy.sparse`` matrices for large
ones; a model may also override :meth:`SecondOrderModel.effective_matrix` and
:meth:`SecondOrderModel.newton_solve` to exploit its structure (banded storage, factorization
reuse). Models know nothing of integrators or FMI.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from .stepper_contract import NEWTON


@dataclass
class Evaluation:
    """Residual pieces of a model at (t, q, v, a) and, if requested, their tangents."""

    f_inertia: np.ndarray
    f_rest: np.ndarray
    mass: Any = None
    inertia_q: Any = None
    damping: Any = None
    stiffness: Any = None
    #: Changes whenever the tangent's structure changes (e.g. a dropper slackens); solvers
    #: that reuse a factorization refactorize when it changes.
    structure_key: Any = None


@dataclass
class LinearForm:
    """A model that is linear with constant matrices (declared by
    :meth:`SecondOrderModel.linear_form`):

        f_inertia = M a,    f_rest = C v + K q + B w(t, inputs),

    with dense M, C, K (n x n) and B (n x m). ``fill(t, inputs, w)`` writes the load vector
    w (length m) at time t in place: time laws and coupling inputs, nothing that depends on
    q, v or a. The integrator then takes each HHT-alpha step in closed form (one
    precomputed n x n product, no Newton iteration, no allocation)."""

    M: np.ndarray
    C: np.ndarray
    K: np.ndarray
    B: np.ndarray
    fill: Callable[[float, Any, np.ndarray], None]


class SecondOrderModel:
    """Base class of the models the HHT-alpha integrator (:mod:`pantocosim.core.hht`) drives."""

    n_dofs: int = 0
    #: how the model is stepped (:mod:`.stepper_contract`): Newton-Raphson HHT on :meth:`evaluate`
    #: unless a model with a closed-form step names it
    stepping: str = NEWTON
    #: the model offers :meth:`iterate` (a Newton iterate's kinematics, forces and weighted
    #: residual in one call); False: the integrator evaluates between its own kernels
    fused_iterate: bool = False

    def linear_form(self) -> LinearForm | None:
        """The model's :class:`LinearForm` if it is linear with constant matrices (with its
        current options), else None. It must give the same forces as :meth:`evaluate` (to
        round-off) at every (t, q, v, a, inputs)."""
        return None

    def evaluate(self, t: float, q: np.ndarray, v: np.ndarray, a: np.ndarray,
                 inputs: np.ndarray | None, tangent: bool = True) -> Evaluation:
        raise NotImplementedError

    def iterate(self, t: float, q: np.ndarray, q_p: np.ndarray, v_p: np.ndarray, c_a: float,
                c_v: float, c_f: float, hist: np.ndarray, inputs: np.ndarray | None,
                tangent: bool):
        """With ``fused_iterate``: (evaluation, a, v, R, max |R|, size of the forces) at the
        iterate q, with a = c_a (q - q_p), v = v_p + c_v (q - q_p) and R = f_inertia +
        c_f f_rest - hist, bit for bit what :meth:`evaluate` between the kernels of
        :mod:`.newmark_residual` gives."""
        raise NotImplementedError(f"{type(self).__name__} declares no fused iterate")

    # --- hooks with generic default implementations -------------------------------------

    def effective_matrix(self, ev: Evaluation, c_a: float, c_v: float, c_f: float):
        """Newton matrix dR/dq = c_a*mass + inertia_q + c_f*(c_v*damping + stiffness)."""
        S = c_a * ev.mass + c_f * (c_v * ev.damping + ev.stiffness)
        if ev.inertia_q is not None:
            S = S + ev.inertia_q
        return S

    def factorize(self, S):
        """Return a callable ``solve(rhs)`` for the Newton matrix ``S``."""
        if sp.issparse(S):
            lu = spla.splu(sp.csc_matrix(S))
            return lu.solve
        lu = _dense_lu(np.asarray(S))
        return lu

    def newton_solve(self, solve, ev: Evaluation, rhs):
        """The solution of the Newton matrix at ``ev`` for ``rhs``, with ``solve`` from
        :meth:`factorize` (possibly of an earlier iterate): ``solve(rhs)``. A model whose
        Newton matrix has a part carried by the evaluation (the coupled system's contact
        linearisation) adds it here, so nothing is left behind between calls."""
        return solve(rhs)

    def static_force_scale(self, f_rest: np.ndarray) -> float:
        """The size of the forces a static residual ``f_rest`` (at v = a = 0) is measured
        against; by default 1 N (an absolute tolerance)."""
        return 1.0

    def commit(self, t: float, q: np.ndarray, v: np.ndarray, a: np.ndarray,
               inputs: np.ndarray | None) -> None:
        """Called once a step is accepted (e.g. to update history-dependent sets)."""

    def get_internal_state(self) -> Any:
        """Extra state beyond (t, q, v, a) that a step depends on (for FMU rollback)."""
        return None

    def set_internal_state(self, state: Any) -> None:
        """Restore what :meth:`get_internal_state` returned."""


def _dense_lu(S: np.ndarray):
    """``solve(rhs)`` by LU (LAPACK getrf/getrs, as ``scipy.linalg.lu_factor``/``lu_solve``);
    a float vector or matrix of the right height goes to getrs directly (the same LAPACK call
    without ``lu_solve``'s checks, which cost ten times the solve of a small body)."""
    lu, piv = sla.lu_factor(S, check_finite=False)
    getrs, = sla.get_lapack_funcs(("getrs",), (lu,))

    def solve(rhs):
        b = np.asarray(rhs)
        if b.dtype == lu.dtype and b.ndim in (1, 2) and b.shape[0] == lu.shape[0] and b.size:
            x, info = getrs(lu, piv, b)
            if info == 0:
                return x
        return sla.lu_solve((lu, piv), rhs, check_finite=False)

    return solve

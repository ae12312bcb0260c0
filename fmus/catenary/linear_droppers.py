"""The droppers of a catenary linearised about its static configuration, as unilateral
elements (thesis 3.1.2, the tension-only bar of (3.4) linearised).

About the static configuration (dropper direction u0, axial force N0 > 0, axial stiffness
k_a = EA / l0) the dropper's axial force is, to first order,

    N(q) = N0 + k_a b . (q - q_static),     b = [-u0 on end i, +u0 on end j],

and its force on the free DOFs is N b plus the pre-tension (geometric) stiffness
N0 / l (I - u0 u0^T) across the dropper, both inside K0. A dropper is slack when N < 0; its
axial force N b (and the axial share beta k_a b b^T of the Rayleigh damping) is then taken
out, so it carries no axial force at all; its stiffness leaves the Newton matrix as the
rank-one k_a b b^T (:mod:`pantocosim.core.lowrank`). The force is continuous through the
switch (N = 0 there), so the active set settles in a Newton step or two. The geometric term
(a lateral stiffness N0 / l of some 100 N/m, first order in the ends' relative lateral
motion) stays: it belongs to the linearisation of the direction, not to the axial law.
"""

from __future__ import annotations

import numpy as np

from numba import njit

from ..core.lowrank import SparseVectors


@njit(cache=True, inline="always")
def _is_slack(tension_only, N):
    """A tension-only dropper carries no force at a negative axial force N."""
    return tension_only and N < 0.0


@njit(cache=True)
def _slack_of(tension_only, N, out):
    for d in range(N.shape[0]):
        out[d] = _is_slack(tension_only[d], N[d])


@njit(cache=True)
def _slack_after(tension_only, ka, N_p, b_free, b_W, F, b_delta, slack, previous):
    """b . Delta = b . Delta_free + sum_k F_k b . w_k into ``b_delta``, the slack set at
    N_p + k_a b . Delta into ``slack``; True when it differs from ``previous``."""
    changed = False
    for d in range(N_p.shape[0]):
        bd = b_free[d]
        for k in range(F.shape[0]):
            bd += F[k] * b_W[k, d]
        b_delta[d] = bd
        slack[d] = _is_slack(tension_only[d], N_p[d] + ka[d] * bd)
        changed = changed or slack[d] != previous[d]
    return changed


@njit(cache=True)
def _removed_scales(ka, beta, slack, damped, c_v, c_f, rows, s):
    """The nonzero rank-one scales c_f k_a (slack + c_v beta damped) into ``rows``, ``s``;
    returns their count."""
    m = 0
    for d in range(ka.shape[0]):
        sd = c_f * ka[d] * ((1.0 if slack[d] else 0.0) + (c_v * beta if damped[d] else 0.0))
        if sd != 0.0:
            rows[m] = d
            s[m] = sd
            m += 1
    return m


@njit(cache=True)
def _step_terms(idx, val, ka, beta, N, v, slack, damped, c_v, c_f, out, rows, s):
    """out += c_f sum_{d slack} N_d b_d + c_f sum_{d damped} beta k_a,d (b_d . v) b_d, and
    :func:`_removed_scales`."""
    for d in range(idx.shape[0]):
        if not (slack[d] or damped[d]):
            continue
        coef = 0.0
        if slack[d]:
            coef += N[d]
        if damped[d]:
            bv = 0.0
            for k in range(idx.shape[1]):
                if idx[d, k] >= 0:
                    bv += val[d, k] * v[idx[d, k]]
            coef += beta * ka[d] * bv
        for k in range(idx.shape[1]):
            if idx[d, k] >= 0:
                out[idx[d, k]] += c_f * coef * val[d, k]
    return _removed_scales(ka, beta, slack, damped, c_v, c_f, rows, s)


class LinearDroppers:
    """Droppers ``bars`` (indices into ``structure.bars``) linearised at ``x_static``."""

    def __init__(self, structure, bars: np.ndarray, x_static: np.ndarray, beta: float):
        B = structure.bars
        self.bars = np.asarray(bars, dtype=np.int64)
        dofs = B.dofs[self.bars]
        X = x_static[dofs]
        d = X[:, 3:] - X[:, :3] + B.dX[self.bars]
        length = np.linalg.norm(d, axis=1)
        u = d / length[:, None]
        self.N0 = B.axial_forces(x_static, tension_only=False)[self.bars]
        self.ka = B.EA[self.bars] / B.l0[self.bars]
        self.tension_only = B.tension_only[self.bars].copy()
        self.beta = float(beta)
        self.vectors = SparseVectors(structure.fmap[dofs], np.hstack([-u, u]),
                                     structure.n_free)

    def __len__(self) -> int:
        return self.bars.size

    def axial(self, dq: np.ndarray, out=None) -> np.ndarray:
        """Linearised axial force N of every dropper at q = q_static + dq (tension > 0),
        into ``out`` if given."""
        out = self.vectors.dots(dq, out=out)
        out *= self.ka
        out += self.N0
        return out

    def slack(self, N: np.ndarray) -> np.ndarray:
        """The droppers that carry no force at axial force N."""
        out = np.empty(len(self), dtype=bool)
        _slack_of(self.tension_only, np.asarray(N, dtype=float), out)
        return out

    def slack_after(self, N_p, b_free, b_W, F, b_delta, previous) -> tuple[np.ndarray, bool]:
        """(slack set, changed from ``previous``) at the end of a step: N = N_p + k_a b . Delta
        with b . Delta = ``b_free`` + F . ``b_W`` (written into ``b_delta``)."""
        slack = np.empty(len(self), dtype=bool)
        changed = _slack_after(self.tension_only, self.ka, N_p, b_free, b_W, F, b_delta,
                               slack, previous)
        return slack, changed

    def force(self, coef: np.ndarray, mask: np.ndarray, out=None) -> np.ndarray:
        """sum over the ``mask`` droppers of coef_d b_d (free DOFs), added to ``out`` if
        given."""
        rows = np.flatnonzero(mask)
        out = np.zeros(self.vectors.n) if out is None else out
        if rows.size:
            self.vectors.combine(coef[rows], rows, out=out)
        return out

    def removed_stiffness(self, slack: np.ndarray, damped_slack: np.ndarray, c_v: float,
                          c_f: float) -> tuple[np.ndarray, np.ndarray]:
        """(rows, s): the rank-one scales s_d of c_f (k_a [d slack] + c_v beta k_a [d in the
        damping's slack set]) b b^T that leave the Newton matrix c_a M + c_f (c_v C + K)."""
        rows = np.empty(len(self), dtype=np.int64)
        s = np.empty(len(self))
        m = _removed_scales(self.ka, self.beta, slack, damped_slack, float(c_v), float(c_f),
                            rows, s)
        return rows[:m], s[:m]

    def step_terms(self, N, v, slack, damped_slack, c_v: float, c_f: float, out):
        """The slack droppers' share of an HHT step in one pass: adds to ``out`` the forces
        they no longer carry, c_f (N_d b_d [d slack] + beta k_a (b_d . v) b_d [d in the
        damping's slack set]) at axial forces N, velocity v, and returns
        :meth:`removed_stiffness`."""
        rows = np.empty(len(self), dtype=np.int64)
        s = np.empty(len(self))
        m = _step_terms(self.vectors.idx, self.vectors.val, self.ka, self.beta, N, v, slack,
                        damped_slack, float(c_v), float(c_f), out, rows, s)
        return rows[:m], s[:m]

"""Banded Cholesky factorization (LAPACK dpbtrf/dpbtrs) with cached unit-vector solves.

A factorization is reused across many Newton iterations and time steps; the solves against
unit vectors ``A^-1 e_j`` it is asked for again and again (the columns of the contact-wire
DOFs under a moving pantograph, for the low-rank contact update) are kept in a small
least-recently-used cache, so a pantograph pays one solve per DOF it meets, not per step.
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass

import numpy as np
from numba import njit
from scipy.linalg.lapack import dpbtrf, dpbtrs

from . import band_window

#: solution entries below this are set to zero in :func:`band_solve`: the solve of a unit
#: vector decays geometrically away from its entry and would otherwise run into subnormal
#: numbers, which x86 processors handle a hundred times slower (1e-250 is far below any
#: physical value of this project)
TINY = 1e-250


@njit(cache=True, fastmath=True)
def band_solve(LT, b, x):
    """x = (L L^T)^-1 b with ``LT[j, 0] = 1 / L[j, j]``, ``LT[j, k] = L[j + k, j]`` (the
    factor's columns as rows): forward and back substitution in place of x (b may be x).
    Rows are taken two at a time (half the passes over x, whose dependency chain bounds the
    speed); the loops over the band width vectorize."""
    n, w = LT.shape
    if w == 1:
        for i in range(n):
            x[i] = b[i] * LT[i, 0] * LT[i, 0]
        return
    if x is not b:
        for i in range(n):
            x[i] = b[i]
    full = max(n - w, 0)          # rows j, j + 1 both with their whole band inside
    j = 0
    while j + 1 < full:
        x0 = _flush(x[j] * LT[j, 0])
        x1 = _flush((x[j + 1] - LT[j, 1] * x0) * LT[j + 1, 0])
        x[j], x[j + 1] = x0, x1
        for k in range(2, w):
            x[j + k] -= LT[j, k] * x0 + LT[j + 1, k - 1] * x1
        x[j + w] -= LT[j + 1, w - 1] * x1
        j += 2
    for j in range(j, n):
        xj = x[j] * LT[j, 0]
        x[j] = xj
        for k in range(1, min(w, n - j)):
            x[j + k] -= LT[j, k] * xj
    j = n - 1
    while j > full:
        s = x[j]
        for k in range(1, min(w, n - j)):
            s -= LT[j, k] * x[j + k]
        x[j] = s * LT[j, 0]
        j -= 1
    while j >= 1:                 # rows j - 1, j: x[j + 1 .. j + w - 1] known
        s1 = 0.0
        s0 = 0.0
        for k in range(1, w - 1):
            xk = x[j + k]
            s1 += LT[j, k] * xk
            s0 += LT[j - 1, k + 1] * xk
        s1 += LT[j, w - 1] * x[j + w - 1]
        x1 = _flush((x[j] - s1) * LT[j, 0])
        x[j] = x1
        x[j - 1] = _flush((x[j - 1] - s0 - LT[j - 1, 1] * x1) * LT[j - 1, 0])
        j -= 2
    if j == 0:
        s = x[0]
        for k in range(1, min(w, n)):
            s -= LT[0, k] * x[k]
        x[0] = _flush(s * LT[0, 0])


@njit(cache=True, inline="always")
def _flush(v):
    """v, or 0 when |v| < TINY (no subnormal numbers in a solve)."""
    return v if abs(v) >= TINY else 0.0


#: relative size below which a local solve (:func:`local_band_solve`) treats the solution as
#: zero: far below the round-off of every sum it enters
LOCAL_RTOL = 1e-20


@njit(cache=True, fastmath=True)
def local_band_solve(LT, x, lo, hi, rtol):
    """x <- (L L^T)^-1 x for x zero outside [lo, hi] (a unit vector, a dropper's direction):
    the solution decays geometrically away from [lo, hi], so each substitution stops once
    w consecutive entries are below ``rtol`` times the largest (the rest stays zero). On the
    catenary's step matrix this touches a few thousand entries whatever the line length."""
    n, w = LT.shape
    big = 0.0
    quiet = 0
    i = lo
    while i < n:
        xi = x[i] * LT[i, 0]
        x[i] = xi
        for k in range(1, min(w, n - i)):
            x[i + k] -= LT[i, k] * xi
        a = abs(xi)
        big = max(big, a)
        quiet = quiet + 1 if (i > hi and a <= rtol * big) else 0
        if quiet >= w:
            break
        i += 1
    end = min(i, n - 1)
    for k in range(end + 1, min(end + w, n)):
        x[k] = 0.0                                   # tiny partial sums past the stop
    big = 0.0
    quiet = 0
    for i in range(end, -1, -1):
        s = x[i]
        for k in range(1, min(w, end + 1 - i)):
            s -= LT[i, k] * x[i + k]
        s *= LT[i, 0]
        x[i] = s
        a = abs(s)
        big = max(big, a)
        quiet = quiet + 1 if (i < lo and a <= rtol * big) else 0
        if quiet >= w:
            break


@njit(cache=True)
def _sum_columns(store, span, slots, values, out):
    """out = sum_i values[i] store[slots[i]], each column added over its nonzero range."""
    for i in range(out.shape[0]):
        out[i] = 0.0
    for r in range(slots.shape[0]):
        col = store[slots[r]]
        c = values[r]
        for i in range(span[slots[r], 0], span[slots[r], 1]):
            out[i] += c * col[i]


@njit(cache=True)
def _factor_rows(LT, R):
    """The factor's rows R[j, k] = L[j, j - k] (zero for j < k) from its columns as rows
    LT[j, k] = L[j + k, j]; the reciprocal diagonal stays in column 0."""
    n, w = LT.shape
    for j in range(n):
        R[j, 0] = LT[j, 0]
        for k in range(1, w):
            R[j, k] = LT[j - k, k] if j >= k else 0.0


@njit(cache=True)
def _factor_layouts(cb, rows):
    """The factor's columns as rows LT (:class:`BandedCholesky`) from LAPACK's lower band
    storage ``cb``, and (``rows``) its rows R (:func:`_factor_rows`), in one pass over cb."""
    w, n = cb.shape
    LT = np.empty((n, w))
    R = np.empty((n if rows else 0, w))
    for j in range(n):
        d = 1.0 / cb[0, j]
        LT[j, 0] = d
        for k in range(1, w):
            LT[j, k] = cb[k, j]
        if rows:
            R[j, 0] = d
            for k in range(1, w):
                R[j, k] = cb[k, j - k] if j >= k else 0.0
    return LT, R


@dataclass
class SparseBand:
    """A symmetric band matrix (lower band storage) for products: the diagonals below the
    main one that are filled more than ``min_fill`` kept as rows of ``diags`` (their
    ``offsets``), the entries of the sparser ones as coordinates (i > j) ``ci``, ``cj``,
    ``cv``. The catenary's mass couples only equal coordinates of nearby nodes, so most of
    its band diagonals are empty and a product skips them."""

    main: np.ndarray
    offsets: np.ndarray
    diags: np.ndarray
    ci: np.ndarray
    cj: np.ndarray
    cv: np.ndarray

    @classmethod
    def from_band(cls, band: np.ndarray, min_fill: float = 0.1) -> "SparseBand":
        w, n = band.shape
        dense = [k for k in range(1, w) if np.count_nonzero(band[k, :n - k]) > min_fill * n]
        ci, cj, cv = [], [], []
        for k in range(1, w):
            if k not in dense:
                j = np.flatnonzero(band[k, :n - k])
                ci.append(j + k)
                cj.append(j)
                cv.append(band[k, j])
        cat = (lambda parts, dt: np.concatenate(parts).astype(dt) if parts
               else np.zeros(0, dt))
        return cls(main=np.ascontiguousarray(band[0], dtype=float),
                   offsets=np.array(dense, dtype=np.int64),
                   diags=np.ascontiguousarray(band[dense], dtype=float).reshape(len(dense), n),
                   ci=cat(ci, np.int64), cj=cat(cj, np.int64), cv=cat(cv, float))

    @property
    def parts(self) -> tuple:
        """The arrays a numba kernel takes."""
        return self.main, self.offsets, self.diags, self.ci, self.cj, self.cv


class BandedCholesky:
    """``solve = BandedCholesky.factor(ab)``; ``solve(r)``, ``solve.solve_sparse(dofs, w)``.

    ``ab``: (bandwidth + 1, n) lower band storage (LAPACK 'L'); overwritten.
    ``factor`` returns None when the matrix is not positive definite."""

    #: unit-vector solves kept (each n floats)
    cache_size = 48

    def __init__(self, LT: np.ndarray, cb: np.ndarray | None = None,
                 R: np.ndarray | None = None):
        self.n = LT.shape[0]
        self._cb = cb
        #: the factor's columns as rows, LT[j, 0] = 1 / L[j, j], LT[j, k] = L[j + k, j]
        self.LT = LT
        #: the substitution with the pending sums in registers (:mod:`.band_window`), which
        #: also needs the factor's rows R[j, k] = L[j, j - k]; None: :func:`band_solve`
        self._window = band_window.solver(self.LT.shape[1])
        self.R = None
        if self._window is not None:
            self.R = R
            if R is None:
                self.R = np.empty_like(LT)
                _factor_rows(LT, self.R)
        #: unit-vector solves A^-1 e_j kept as rows of _store (j -> row, least recently
        #: used first) with the range of their nonzero entries
        self._slots: OrderedDict[int, int] = OrderedDict()
        self._store = np.empty((self.cache_size, self.n))   # a row is zeroed when taken
        self._span = np.zeros((self.cache_size, 2), dtype=np.int64)
        self._solved = 0                  # columns solved so far (a row may have changed)
        self._last_slots = None           # ((dofs, _solved), rows) of the last solve_sparse

    @classmethod
    def factor(cls, ab: np.ndarray) -> "BandedCholesky | None":
        """By LAPACK (dpbtrf) from the lower band storage ``ab`` (overwritten)."""
        cb, info = dpbtrf(ab, lower=1, overwrite_ab=1)
        if info != 0:
            return None
        rows = band_window.solver(cb.shape[0]) is not None
        LT, R = _factor_layouts(cb, rows)
        return cls(LT, cb, R if rows else None)

    @property
    def cb(self) -> np.ndarray:
        """The factor in LAPACK's lower band storage (for dpbtrs)."""
        if self._cb is None:
            self._cb = np.array(self.LT.T, order="C")
            self._cb[0] = 1.0 / self._cb[0]
        return self._cb

    def __call__(self, rhs: np.ndarray) -> np.ndarray:
        rhs = np.asarray(rhs, dtype=float)
        if rhs.ndim == 1 and rhs.flags.c_contiguous:
            return self.solve_into(rhs, np.empty(self.n))
        x, _ = dpbtrs(self.cb, rhs, lower=1)
        return x

    def solve_into(self, rhs: np.ndarray, out: np.ndarray) -> np.ndarray:
        """``out`` = A^-1 rhs without allocating (``out`` may be ``rhs``)."""
        if self._window is not None:
            self._window.solve(self.LT, self.R, rhs, out)
        else:
            band_solve(self.LT, rhs, out)
        return out

    def solve_local(self, lo: int, hi: int, values=None) -> np.ndarray:
        """A^-1 b for b zero outside [lo, hi] (``values``: b; None: the unit vector e_lo),
        by :func:`local_band_solve`."""
        x = np.zeros(self.n)
        if values is None:
            x[lo] = 1.0
        else:
            x[lo:hi + 1] = values[lo:hi + 1]
        self._local(x, lo, hi)
        return x

    def _local(self, x: np.ndarray, lo: int, hi: int) -> None:
        """x <- A^-1 x in place for x zero outside [lo, hi] (:func:`local_band_solve`)."""
        if self._window is not None:
            self._window.local(self.LT, self.R, x, lo, hi, LOCAL_RTOL)
        else:
            local_band_solve(self.LT, x, lo, hi, LOCAL_RTOL)

    def _slot(self, j: int) -> int:
        """The row of :attr:`_store` holding A^-1 e_j (solved and kept on first use; the least
        recently used column gives up its row)."""
        slots = self._slots
        slot = slots.get(j)
        if slot is None:
            if len(slots) < self.cache_size:
                slot = len(slots)
            else:
                _, slot = slots.popitem(last=False)
            col = self._store[slot]
            col[:] = 0.0
            col[j] = 1.0
            self._local(col, j, j)
            self._solved += 1
            nz = np.flatnonzero(col)
            self._span[slot] = (nz[0], nz[-1] + 1) if nz.size else (0, 0)
            slots[j] = slot
        else:
            slots.move_to_end(j)
        return slot

    def solve_sparse(self, dofs, values, out=None) -> np.ndarray:
        """A^-1 b for b with ``values`` at ``dofs`` (zero elsewhere), into ``out`` if given."""
        x = np.zeros(self.n) if out is None else out
        _sum_columns(self._store, self._span, self._slots_of(dofs),
                     np.asarray(values, dtype=float), x)
        return x

    def _slots_of(self, dofs) -> np.ndarray:
        """The rows of :attr:`_store` of ``dofs``' columns. The same dofs as the last call,
        with no column solved since, keep their rows (a pantograph stays on an element for
        many steps)."""
        key = dofs.tobytes() if isinstance(dofs, np.ndarray) else tuple(dofs)
        if self._last_slots is not None and self._last_slots[0] == (key, self._solved):
            return self._last_slots[1]
        if len(dofs) > self.cache_size:      # a column would give up its row while in use
            raise ValueError(f"{len(dofs)} entries: at most {self.cache_size} (cache_size)")
        slots = np.empty(len(dofs), dtype=np.int64)
        for i, j in enumerate(dofs.tolist() if isinstance(dofs, np.ndarray) else dofs):
            slots[i] = self._slot(int(j))
        self._last_slots = ((key, self._solved), slots)
        return slots

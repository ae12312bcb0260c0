"""Finite-element structure in absolute nodal coordinates: collects the contributions of its
element sets into sparse global vectors and matrices (thesis 3.1, 3.3.3).

DOFs are numbered by the mesh builder (:mod:`pantocosim.catenary.mesh`) along the track; the
"full" vector holds every coordinate, fixed ones included, and the "free" vector ``q`` the
unknowns. Global matrices live on one CSR pattern over the free DOFs (the union of all
element couplings), so mass, damping, stiffness and the Newton matrix share ``indices`` and
``indptr`` and are combined by adding their ``data`` arrays.

The structure knows no element type. Each part is an *element set* (all elements of one type,
vectorised) that follows the small protocol :class:`Element`: its DOFs, then mass and weight,
forces and tangent, and named outputs. The sets in this package are
:class:`~pantocosim.catenary.ancf_cable.CableSet`, :class:`~pantocosim.catenary.bar.BarSet`,
:class:`~pantocosim.catenary.point_mass.PointMasses` and
:class:`~pantocosim.catenary.ground_spring.GroundSprings`. Element loops and scatters are
numba kernels inside the sets; nothing loops over elements in Python.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np
import scipy.sparse as sp
from numba import njit



@njit(cache=True)
def _band_storage(data, src, dst, rows, n):
    """(rows, n) band storage holding data[src[i]] at flat position dst[i], zero elsewhere."""
    out = np.zeros(rows * n)
    for i in range(src.shape[0]):
        out[dst[i]] = data[src[i]]
    return out.reshape(rows, n)


class Element(Protocol):
    """What an element set gives the structure (see ``docs/architecture.md``).

    ``dofs``: (n_elements, m) full DOFs of each element. After the free numbering the
    structure calls ``bind(structure, pos)`` once, ``pos`` holding for every element the
    m x m positions of its couplings on the shared pattern (-1 where a DOF is fixed),
    flattened; the set keeps it and allocates its work arrays there (never per step).
    """

    dofs: np.ndarray

    def bind(self, structure: "Structure", pos: np.ndarray) -> None: ...

    def add_mass(self, M: np.ndarray, f_weight: np.ndarray, gravity: float) -> None:
        """Add mass (pattern data) and weight (full vector) once, at build time."""

    def add_forces(self, x_full: np.ndarray, f: np.ndarray, K: np.ndarray | None,
                   tension_only: bool) -> None:
        """Add internal forces (full vector) and, unless K is None, the tangent (pattern
        data) at x_full. ``tension_only=False`` asks unilateral elements to act bilateral."""

    def outputs(self, x_full: np.ndarray) -> dict[str, np.ndarray]:
        """Named per-element results at x_full (forces, tensions) for reports."""


def _pairs(dofs: np.ndarray, fmap: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Free (row, col) of every m x m coupling of every element, flattened."""
    m = dofs.shape[1]
    r = np.broadcast_to(dofs[:, :, None], (dofs.shape[0], m, m)).ravel()
    c = np.broadcast_to(dofs[:, None, :], (dofs.shape[0], m, m)).ravel()
    return fmap[r], fmap[c]


class Structure:
    """Element sets on a set of full DOFs.

    Built by setting the coordinate arrays below, adding element sets with :meth:`add` and
    calling :meth:`finalize`. Parts are assembled in the order they were added.
    """

    def __init__(self, n_full: int, gravity: float = 9.81):
        self.n_full = int(n_full)
        self.gravity = float(gravity)
        #: coordinates are stored relative to ``offset`` (the station x on x-position DOFs,
        #: zero elsewhere): absolute = x_full + offset. Fixed DOFs keep their x_full value.
        self.x_full = np.zeros(self.n_full)
        self.offset = np.zeros(self.n_full)
        self.fixed = np.zeros(self.n_full, dtype=bool)
        self.zpos = np.zeros(self.n_full, dtype=bool)  # z-position DOFs (weight acts on them)
        self.parts: dict[str, Element] = {}

    def add(self, name: str, element: Element) -> Element:
        """Register an element set under ``name`` (``structure.parts[name]``)."""
        if name in self.parts:
            raise ValueError(f"structure already has a part named {name!r}")
        self.parts[name] = element
        return element

    # the parts the catenary's solvers address by name
    cables = property(lambda self: self.parts["cables"])
    bars = property(lambda self: self.parts["bars"])
    springs = property(lambda self: self.parts["springs"])

    # ------------------------------------------------------------------ build
    def finalize(self) -> None:
        """Free numbering, CSR pattern, element binding, constant mass matrix and weight."""
        self.free = np.flatnonzero(~self.fixed)
        self.n_free = self.free.size
        fmap = -np.ones(self.n_full, dtype=np.int64)
        fmap[self.free] = np.arange(self.n_free)
        self.fmap = fmap
        positions = self._pattern([el.dofs for el in self.parts.values()])
        for el, pos in zip(self.parts.values(), positions):
            el.bind(self, pos)
        self.M_data = np.zeros(self.nnz)
        self.f_weight_full = np.zeros(self.n_full)
        for el in self.parts.values():
            el.add_mass(self.M_data, self.f_weight_full, self.gravity)

    def _pattern(self, dof_blocks: list[np.ndarray]) -> list[np.ndarray]:
        """Shared CSR pattern (with the full diagonal) and its lower band storage maps;
        returns each block's positions on the pattern."""
        n = self.n_free
        pairs = [_pairs(d, self.fmap) for d in dof_blocks]
        diag = np.arange(n)
        rows = np.concatenate([r for r, _ in pairs] + [diag])
        cols = np.concatenate([c for _, c in pairs] + [diag])
        ok = (rows >= 0) & (cols >= 0)
        keys = np.where(ok, rows * n + cols, -1)
        uk, inv = np.unique(keys[ok], return_inverse=True)
        pos = -np.ones(keys.size, dtype=np.int64)
        pos[ok] = inv
        self.nnz = uk.size
        self.indices = (uk % n).astype(np.int32)
        self.indptr = np.concatenate([[0], np.cumsum(np.bincount(uk // n, minlength=n))]
                                     ).astype(np.int32)
        ur, uc = uk // n, uk % n
        low = ur >= uc
        self.bandwidth = int(np.max(ur - uc)) if uk.size else 0
        self.band_src = np.flatnonzero(low)
        self.band_dst = ((ur[low] - uc[low]) * n + uc[low]).astype(np.int64)
        ends = np.cumsum([0] + [r.size for r, _ in pairs])
        return [pos[a:b] for a, b in zip(ends[:-1], ends[1:])]

    # ------------------------------------------------------------------ helpers
    def csr(self, data) -> sp.csr_matrix:
        """A CSR matrix on the shared pattern (no copy of ``data``)."""
        return sp.csr_matrix((data, self.indices, self.indptr), shape=(self.n_free,) * 2)

    def absolute(self, x_full: np.ndarray) -> np.ndarray:
        """Absolute coordinates of a full vector."""
        return x_full + self.offset

    def full(self, q: np.ndarray) -> np.ndarray:
        x = self.x_full.copy()
        x[self.free] = q
        return x

    def lower_band(self, data) -> np.ndarray:
        """(bandwidth + 1, n) lower band storage (LAPACK 'L') of pattern data."""
        return _band_storage(data, self.band_src, self.band_dst, self.bandwidth + 1,
                             self.n_free)

    @property
    def mass(self) -> sp.csr_matrix:
        return self.csr(self.M_data)

    @property
    def weight(self) -> np.ndarray:
        """External weight on the free DOFs (the gravity vector, negative z)."""
        return self.f_weight_full[self.free]

    # ------------------------------------------------------------------ forces
    def internal(self, x_full: np.ndarray, want_K: bool = True, tension_only: bool = True):
        """Elastic forces (full vector), tangent data on the pattern (or None) and the
        slack flags of the bars. ``tension_only=False`` treats every bar as bilateral."""
        f = np.zeros(self.n_full)
        K = np.zeros(self.nnz) if want_K else None
        for el in self.parts.values():
            el.add_forces(x_full, f, K, tension_only)
        return f, K, self.bars.slack.copy()

    def outputs(self, x_full: np.ndarray) -> dict[str, np.ndarray]:
        """Every part's outputs at x_full, keyed ``"part.name"``."""
        return {f"{p}.{k}": v for p, el in self.parts.items()
                for k, v in el.outputs(x_full).items()}

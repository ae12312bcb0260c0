"""Points on the contact wire: element and local coordinate of a track position x,
(3.11)-(3.13).

The local coordinate chi_c of x inside a contact-wire element solves the cubic (3.12) on the
*reference* configuration (the static equilibrium the locator is built from); as in the
thesis, it is then kept fixed during the dynamics (the wire barely moves along x). The
height of the wire there is (3.13)

    z = S1 z_i + S2 z_i' + S3 z_j + S4 z_j' = w . x_full[dofs].
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from ..core.errors import ParameterError
from .ancf_cable import shape, shape_dxi


@dataclass
class ContactPoint:
    """z of the contact wire at one track position: ``weights @ q[dofs] + offset``.

    ``dofs`` index the free coordinate vector q. ``offset`` gathers the part from fixed DOFs
    (non-zero only in an element that touches an anchored line end). ``dweights_dx`` is
    d(weights)/dx, for the convective part of the wire velocity under a moving point.
    """

    dofs: np.ndarray
    weights: np.ndarray
    offset: float
    element: int
    xi: float
    dweights_dx: np.ndarray
    doffset_dx: float = 0.0


@njit(cache=True)
def _local_coordinate(c, L, x, xi):
    """xi in [0, 1] with x(xi) = x on the Hermite cubic (3.12) of the element's reference
    coordinates c = (x_i, x_i', x_j, x_j'): Newton from ``xi``."""
    for _ in range(30):
        step = ((shape(xi, L) * c).sum() - x) / (shape_dxi(xi, L) * c).sum()
        xi -= step
        if abs(step) < 1e-15:
            break
    return min(max(xi, 0.0), 1.0)


@njit(cache=True)
def _point(x_start, x_end, E_x, Le, x):
    """(element k, xi, weights, d weights / dx) of track position x inside
    [x_start[0], x_end[-1]]: the element search, (3.12) and the Hermite functions (3.13)."""
    k = np.searchsorted(x_start, x, side="right") - 1
    k = min(max(k, 0), x_start.shape[0] - 1)
    L = Le[k]
    c = E_x[k]
    xi = _local_coordinate(c, L, x, (x - x_start[k]) / max(x_end[k] - x_start[k], 1e-300))
    s_xi = shape_dxi(xi, L)
    return k, xi, shape(xi, L), s_xi / (s_xi * c).sum()


class ContactLocator:
    """Locates track positions on the contact wire of a mesh at a reference configuration."""

    def __init__(self, mesh, x_full_ref: np.ndarray):
        S = mesh.structure
        self.mesh = mesh
        self.elems = np.asarray(mesh.contact_elems)
        self.Le = np.ascontiguousarray(S.cables.Le[self.elems], dtype=float)
        E = S.absolute(x_full_ref)[S.cables.dofs[self.elems]]
        self.E_x = E[:, [0, 3, 6, 9]]          # x, x', x_j, x_j'
        self.x_start = np.ascontiguousarray(E[:, 0])
        self.x_end = np.ascontiguousarray(E[:, 6])
        zd = S.cables.dofs[self.elems][:, [2, 5, 8, 11]]
        self.z_full_dofs = zd
        self.z_free = S.fmap[zd]                 # -1 for fixed
        self._all_free = np.all(self.z_free >= 0, axis=1)
        self.x_full_ref = x_full_ref
        self.x_min, self.x_max = float(self.x_start[0]), float(self.x_end[-1])

    def _located(self, x: float):
        """(k, xi, weights, dweights_dx) of track position x (:func:`_point`)."""
        if not (self.x_min - 1e-9 <= x <= self.x_max + 1e-9):
            raise ParameterError("pantograph position", float(x),
                                 f"outside the contact wire [{self.x_min:g}, "
                                 f"{self.x_max:g}] m")
        return _point(self.x_start, self.x_end, self.E_x, self.Le, float(x))

    def locate(self, x: float) -> tuple[int, float]:
        """(element position in the contact chain, xi in [0, 1]) of track position x."""
        k, xi, _, _ = self._located(x)
        return int(k), xi

    def point(self, x: float) -> ContactPoint:
        k, xi, w, dw = self._located(x)
        free = self.z_free[k]
        if self._all_free[k]:
            return ContactPoint(dofs=free, weights=w, offset=0.0, element=int(self.elems[k]),
                                xi=xi, dweights_dx=dw)
        m = free >= 0
        zfix = self.x_full_ref[self.z_full_dofs[k][~m]]
        return ContactPoint(dofs=free[m], weights=w[m], offset=float(w[~m] @ zfix),
                            element=int(self.elems[k]), xi=xi, dweights_dx=dw[m],
                            doffset_dx=float(dw[~m] @ zfix))

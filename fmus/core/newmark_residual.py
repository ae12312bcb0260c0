"""The residual of an HHT-alpha step at a Newton iterate (thesis (3.16)-(3.18)), as compiled
kernels that the integrator (:mod:`.hht`) calls between model evaluations and that a model
offering a fused iterate (:meth:`~.model.SecondOrderModel.iterate`) calls inside its own
compiled evaluation, so both give the same numbers bit for bit:

    a = c_a (q - q_p),   v = v_p + c_v (q - q_p)                      (3.18)
    R = f_inertia + c_f f_rest - hist                                 (3.16)
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def iterate_kinematics(q, q_p, v_p, c_a, c_v):
    """a = c_a (q - q_p), v = v_p + c_v (q - q_p): (3.18) at a Newton iterate."""
    n = q.shape[0]
    a = np.empty(n)
    v = np.empty(n)
    for i in range(n):
        d = q[i] - q_p[i]
        a[i] = c_a * d
        v[i] = v_p[i] + c_v * d
    return a, v


@njit(cache=True)
def weighted_residual(f_inertia, f_rest, hist, c_f):
    """R = f_inertia + c_f f_rest - hist, (3.16), with max |R| and the size of the forces
    in it (max of the three terms' max norms); NaN norms when R is not finite."""
    n = f_inertia.shape[0]
    R = np.empty(n)
    r_max = 0.0
    scale = 0.0
    total = 0.0     # carries any NaN or infinity (branch-free loop: it vectorizes)
    for i in range(n):
        fi = f_inertia[i]
        fr = c_f * f_rest[i]
        h = hist[i]
        r = fi + fr - h
        R[i] = r
        total += r
        ar = abs(r)
        r_max = ar if ar > r_max else r_max
        m = max(abs(fi), abs(fr), abs(h))
        scale = m if m > scale else scale
    if not np.isfinite(total):
        return R, np.nan, np.nan
    return R, r_max, scale

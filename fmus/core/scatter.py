"""Adding element contributions into global arrays at precomputed positions."""

from __future__ import annotations

from numba import njit


@njit(cache=True)
def scatter_add(out, idx, vals):
    """out[idx[i]] += vals[i] for idx[i] >= 0 (idx and vals flattened alike; -1 skips)."""
    for i in range(idx.shape[0]):
        k = idx[i]
        if k >= 0:
            out[k] += vals[i]

"""The modes of the linearised catenary below a cutoff: K0 phi = omega^2 M phi (thesis 3.3,
modal analysis about the static configuration), mass-normalised (Phi^T M Phi = I)."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla


def count_below(K, M, omega2: float) -> int:
    """Number of eigenvalues of (K, M) below omega2 (Sylvester's inertia: negative pivots of
    an unpivoted LU of K - omega2 M in the banded order)."""
    A = sp.csc_matrix(K - omega2 * M)
    lu = spla.splu(A, permc_spec="NATURAL", diag_pivot_thresh=0.0,
                   options={"SymmetricMode": True})
    return int(np.sum(lu.U.diagonal() < 0.0))


def modes_below(K, M, cutoff_hz: float, max_modes: int | None = None):
    """(frequencies [Hz], mass-normalised modes (n, m)) of every mode below ``cutoff_hz``
    (at least one; ``inf``: all of them, by a dense solve)."""
    n = K.shape[0]
    if not np.isfinite(cutoff_hz):                 # every mode (dense; small models only)
        import scipy.linalg as sla

        lam, phi = sla.eigh(K.toarray(), M.toarray())
        return np.sqrt(np.maximum(lam, 0.0)) / (2.0 * np.pi), phi
    w2 = (2.0 * np.pi * cutoff_hz) ** 2
    m = max(1, count_below(K, M, w2))
    m = min(m, n - 2 if max_modes is None else max_modes)
    lam, phi = spla.eigsh(sp.csc_matrix(K), k=m, M=sp.csc_matrix(M), sigma=0.0, which="LM")
    order = np.argsort(lam)
    lam, phi = lam[order], phi[:, order]
    # eigsh's vectors are M-orthonormal; normalise again against round-off
    phi = phi / np.sqrt(np.einsum("ij,ij->j", phi, M @ phi))
    return np.sqrt(np.maximum(lam, 0.0)) / (2.0 * np.pi), phi

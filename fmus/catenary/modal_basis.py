"""The modes of the linearised catenary below a cutoff: K0 phi = omega^2 M phi (thesis 3.3,
modal analysis about the static configuration), mass-normalised (Phi^T M Phi = I).

K0 and M are banded (the DOFs are numbered along the track: a few stations wide whatever
the line's length), so the eigenvalues come from the banded generalized problem without a
dense matrix: LAPACK's split Cholesky of M and Crawford's reduction (dpbstf, dsbgst) keep the
band, dsbtrd makes it tridiagonal and dsterf gives every eigenvalue. Each mode below the
cutoff then comes from inverse iteration on K0 - lambda M with its eigenvalue as shift (a band
LU, dgbtrf, per mode; within a cluster of close eigenvalues the vectors are kept
M-orthogonal and Rayleigh-Ritz-rotated). Cost O(n kd^2) per mode and O(n^2 kd) for the
eigenvalues; memory O(n (kd + modes)).
"""

from __future__ import annotations

import ctypes

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
from numba import njit
from scipy.linalg import cython_lapack
from scipy.linalg.lapack import dgbtrf, dgbtrs

from ..core.errors import ParameterError

#: eigenvalues closer than this (relative) are iterated together as a cluster
CLUSTER_RTOL = 1e-5
#: inverse iterations per mode (the shift is the eigenvalue: each gains ~1e-6 or better)
ITERATIONS = 3


# ---------------------------------------------------------------------- LAPACK band routines
def _lapack(name: str, nargs: int):
    """A LAPACK routine of scipy's bundled library that scipy.linalg.lapack does not wrap
    (all arguments by reference, Fortran convention)."""
    cap = cython_lapack.__pyx_capi__[name]
    get_name = ctypes.pythonapi.PyCapsule_GetName
    get_name.restype, get_name.argtypes = ctypes.c_char_p, [ctypes.py_object]
    get_ptr = ctypes.pythonapi.PyCapsule_GetPointer
    get_ptr.restype, get_ptr.argtypes = ctypes.c_void_p, [ctypes.py_object, ctypes.c_char_p]
    return ctypes.CFUNCTYPE(None, *([ctypes.c_void_p] * nargs))(get_ptr(cap, get_name(cap)))


def _p(x):
    return ctypes.c_void_p(x.ctypes.data) if isinstance(x, np.ndarray) else ctypes.c_char_p(x)


def _i(v: int) -> np.ndarray:
    return np.array([v], dtype=np.int32)


def band_eigenvalues(K_band: np.ndarray, M_band: np.ndarray) -> np.ndarray:
    """Every eigenvalue of K x = lambda M x, ascending; K_band, M_band: (kd + 1, n) lower
    band storage (LAPACK 'L'), M positive definite."""
    kd1, n = K_band.shape
    kd = kd1 - 1
    A = np.asfortranarray(K_band, dtype=np.float64).copy(order="F")
    B = np.asfortranarray(M_band, dtype=np.float64).copy(order="F")
    info, ld, nn, k = _i(0), _i(kd1), _i(n), _i(kd)
    _lapack("dpbstf", 6)(_p(b"L"), _p(nn), _p(k), _p(B), _p(ld), _p(info))
    if info[0] != 0:
        raise np.linalg.LinAlgError(f"dpbstf: mass matrix not positive definite ({info[0]})")
    work, x = np.zeros(2 * n), np.zeros(1)
    _lapack("dsbgst", 13)(_p(b"N"), _p(b"L"), _p(nn), _p(k), _p(k), _p(A), _p(ld), _p(B),
                          _p(ld), _p(x), _p(_i(1)), _p(work), _p(info))
    if info[0] != 0:
        raise np.linalg.LinAlgError(f"dsbgst failed ({info[0]})")
    d, e = np.zeros(n), np.zeros(max(n - 1, 1))
    _lapack("dsbtrd", 12)(_p(b"N"), _p(b"L"), _p(nn), _p(k), _p(A), _p(ld), _p(d), _p(e),
                          _p(x), _p(_i(1)), _p(work), _p(info))
    if info[0] != 0:
        raise np.linalg.LinAlgError(f"dsbtrd failed ({info[0]})")
    return np.sort(sla.eigvalsh_tridiagonal(d, e[:n - 1], lapack_driver="sterf"))


@njit(cache=True)
def _general_band(L, sigma, M):
    """dgbtrf storage (kl = ku = kd, kd rows of fill space) of the symmetric matrix of
    lower band L - sigma M."""
    kd1, n = L.shape
    kd = kd1 - 1
    ab = np.zeros((3 * kd + 1, n))
    for k in range(kd1):
        for j in range(n - k):
            a = L[k, j] - sigma * M[k, j]
            ab[2 * kd + k, j] = a               # A[j + k, j]
            if k:
                ab[2 * kd - k, j + k] = a       # A[j, j + k]
    return ab


@njit(cache=True)
def _band_matmat(L, X):
    """A @ X for the symmetric matrix of lower band L (X: (n, c))."""
    kd1, n = L.shape
    c = X.shape[1]
    Y = np.zeros((n, c))
    for j in range(n):
        for q in range(c):
            Y[j, q] += L[0, j] * X[j, q]
        for k in range(1, kd1):
            if j + k < n:
                a = L[k, j]
                for q in range(c):
                    Y[j + k, q] += a * X[j, q]
                    Y[j, q] += a * X[j + k, q]
    return Y


def band_modes(K_band: np.ndarray, M_band: np.ndarray, lam: np.ndarray,
               seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """(eigenvalues, M-orthonormal modes (n, m)) for the eigenvalue estimates ``lam``
    (ascending) by inverse iteration, each with its own shift; within a cluster of close
    eigenvalues each vector is M-orthogonalised against the cluster's earlier ones at every
    iteration, and the cluster is Rayleigh-Ritz-rotated at the end."""
    K_band = np.ascontiguousarray(K_band, dtype=np.float64)
    M_band = np.ascontiguousarray(M_band, dtype=np.float64)
    kd = K_band.shape[0] - 1
    n, m = K_band.shape[1], lam.size
    rng = np.random.default_rng(seed)
    Phi = np.empty((n, m))
    out = np.empty(m)
    floor = 1e-12 * max(abs(float(lam[-1])), 1.0) if m else 0.0
    i = 0
    while i < m:
        j = i + 1
        while j < m and lam[j] - lam[j - 1] <= CLUSTER_RTOL * abs(lam[j]) + floor:
            j += 1
        X = Phi[:, i:j]
        for c in range(j - i):
            lu, piv, _ = dgbtrf(_general_band(K_band, float(lam[i + c]), M_band), kd, kd)
            x = rng.standard_normal((n, 1))
            for _ in range(ITERATIONS):
                x, _ = dgbtrs(lu, kd, kd, _band_matmat(M_band, x), piv)
                for _ in range(2 if c else 0):          # against the cluster's earlier ones
                    x -= X[:, :c] @ (X[:, :c].T @ _band_matmat(M_band, x))
                x /= np.sqrt(float(x[:, 0] @ _band_matmat(M_band, x)[:, 0]))
            X[:, c] = x[:, 0]
        w, V = sla.eigh(X.T @ _band_matmat(K_band, X), X.T @ _band_matmat(M_band, X))
        Phi[:, i:j] = X @ V
        out[i:j] = w
        i = j
    return out, Phi


def modes_below(K, M, cutoff_hz: float, max_modes: int | None = None, bands=None):
    """(frequencies [Hz], mass-normalised modes (n, m)) of every mode below ``cutoff_hz``
    (at least one; ``inf``: all of them, by a dense solve), at most ``max_modes`` (default
    n - 2: a finite cutoff keeping more is refused). ``bands``: (K_band, M_band) in lower band
    storage if known (else taken from the sparse K, M)."""
    n = K.shape[0]
    if not np.isfinite(cutoff_hz):                 # every mode (dense; small models only)
        lam, phi = sla.eigh(K.toarray(), M.toarray())
        return np.sqrt(np.maximum(lam, 0.0)) / (2.0 * np.pi), phi
    if bands is None:
        bands = (_lower_band(K), _lower_band(M))
    lam_all = band_eigenvalues(*bands)
    w2 = (2.0 * np.pi * cutoff_hz) ** 2
    m = max(1, int(np.searchsorted(lam_all, w2)))
    limit = n - 2 if max_modes is None else max_modes
    if m > limit:
        f_max = np.sqrt(max(float(lam_all[limit]), 0.0)) / (2.0 * np.pi)
        raise ParameterError("modal_cutoff_hz", cutoff_hz, f"keeps {m} of the model's {n} "
                             f"modes, more than the {limit} it takes (the static correction "
                             f"needs the modes above the cutoff); accepted: > 0 and at most "
                             f"{f_max:.6g} Hz")
    lam, phi = band_modes(*bands, lam_all[:m])
    return np.sqrt(np.maximum(lam, 0.0)) / (2.0 * np.pi), phi


def _lower_band(A) -> np.ndarray:
    """Lower band storage of a symmetric sparse matrix."""
    A = sp.coo_matrix(A)
    low = A.row >= A.col
    k = A.row[low] - A.col[low]
    L = np.zeros((int(k.max()) + 1 if k.size else 1, A.shape[0]))
    np.add.at(L, (k, A.col[low]), A.data[low])
    return L

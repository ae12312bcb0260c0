"""Linear analysis of a linearised pantograph: modes (2.21)-(2.28) and FRF (2.36), (2.40)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla


@dataclass
class ModalResult:
    #: undamped natural frequencies [Hz], ascending (2.23)-(2.24)
    frequencies_hz: np.ndarray
    #: damping ratio of each mode from the damped eigenproblem (2.27)-(2.28)
    damping_ratios: np.ndarray
    #: mass-normalised undamped mode shapes, one column per mode
    shapes: np.ndarray
    #: complex eigenvalues of the damped system (2.28), ascending |lambda|
    eigenvalues: np.ndarray


def undamped_modes(M: np.ndarray, K: np.ndarray, shift_hz: float = 0.1):
    """(K - omega^2 M) phi = 0 (2.23): returns omega^2 ascending and mass-normalised shapes.

    Solved in shift-invert form M phi = mu (K + s M) phi, omega^2 = 1/mu - s, which keeps the
    lowest modes accurate when stiff (axial) modes make K ill-conditioned; falls back to the
    direct form if K + s M is not positive definite."""
    s = (2.0 * np.pi * shift_hz) ** 2
    try:
        mu, phi = sla.eigh(M, K + s * M)
    except np.linalg.LinAlgError:
        return sla.eigh(K, M)
    order = np.argsort(mu)[::-1]
    w2 = 1.0 / mu[order] - s
    phi = phi[:, order]
    phi = phi / np.sqrt(np.einsum("ir,ij,jr->r", phi, M, phi))
    return w2, phi


def state_space_modes(M: np.ndarray, C: np.ndarray, K: np.ndarray):
    """Damped modes from the first-order form A Y' + B Y = 0 (2.26)-(2.27).

    Returns eigenvalues lambda_r, eigenvectors Y_r (columns) and the modal constants
    a_r = Y_r^T A Y_r.
    """
    n = M.shape[0]
    Z = np.zeros((n, n))
    A = np.block([[C, M], [M, Z]])
    B = np.block([[K, Z], [Z, -M]])
    lam, Y = sla.eig(-B, A)
    a = np.einsum("ir,ij,jr->r", Y, A, Y)
    return lam, Y, a


def modal_analysis(M, C, K) -> ModalResult:
    """Natural frequencies, damping ratios and shapes (thesis 2.1.3)."""
    M = np.asarray(M, float)
    C = np.asarray(C, float)
    K = np.asarray(K, float)
    n = M.shape[0]
    w2, phi = undamped_modes(M, K)
    freqs = np.sqrt(np.clip(w2, 0.0, None)) / (2 * np.pi)
    lam, Y, _ = state_space_modes(M, C, K)
    order = np.argsort(np.abs(lam))
    lam = lam[order]
    Y = Y[:, order]
    # match each undamped mode with the damped eigenvector whose displacement part resembles
    # it most (modal assurance criterion); (2.28): lambda = omega (-zeta + i sqrt(1 - zeta^2))
    zeta = np.empty(n)
    for r in range(n):
        u = Y[:n, :]
        mac = np.abs(phi[:, r] @ M @ u) ** 2 / (
            (phi[:, r] @ M @ phi[:, r]) * np.real(np.einsum("ij,ik,kj->j", u.conj(), M, u)))
        j = int(np.argmax(mac))
        if abs(lam[j].imag) > 1e-12 * abs(lam[j]):
            zeta[r] = -lam[j].real / abs(lam[j])
        else:  # overdamped: modal (proportional-damping) estimate
            zeta[r] = (phi[:, r] @ C @ phi[:, r]) / (2 * np.sqrt(max(w2[r], 1e-300)))
    return ModalResult(frequencies_hz=freqs, damping_ratios=zeta, shapes=phi, eigenvalues=lam)


def frf_direct(M, C, K, freqs_hz) -> np.ndarray:
    """Receptance H(omega) = (K - omega^2 M + i omega C)^-1 (2.36); shape (nf, n, n)."""
    M = np.asarray(M, float)
    C = np.asarray(C, float)
    K = np.asarray(K, float)
    out = np.empty((len(freqs_hz), M.shape[0], M.shape[0]), dtype=complex)
    for i, f in enumerate(np.asarray(freqs_hz, float)):
        w = 2 * np.pi * f
        out[i] = np.linalg.inv(K - w * w * M + 1j * w * C)
    return out


def frf_modal(M, C, K, freqs_hz) -> np.ndarray:
    """Receptance by modal superposition of the 2n damped modes (2.40):
    H(omega) = sum_r psi_r psi_r^T / (a_r (i omega - lambda_r)), psi_r the displacement part."""
    M = np.asarray(M, float)
    n = M.shape[0]
    lam, Y, a = state_space_modes(M, np.asarray(C, float), np.asarray(K, float))
    psi = Y[:n, :]
    w = 2 * np.pi * np.asarray(freqs_hz, float)
    weights = 1.0 / (a[None, :] * (1j * w[:, None] - lam[None, :]))  # (nf, 2n)
    return np.einsum("ir,fr,jr->fij", psi, weights, psi)

"""Contact-force statistics of EN 50317 / EN 50318: the one implementation every coupling mode
uses.

The contact force is low-pass filtered 0-20 Hz with a zero-phase (forward-backward) Butterworth
filter, then analysed over a window of whole spans away from the model ends: mean, standard
deviation, statistical extremes mean +/- 3 sigma, actual extremes, percentage of loss of contact
(time share of the raw force at zero), maximum uplift at the supports in the window.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from pantocosim.core.errors import ParameterError


def lowpass(values: np.ndarray, dt: float, cutoff_hz: float = 20.0, order: int = 4) -> np.ndarray:
    """Zero-phase Butterworth low-pass (forward-backward, so the order doubles)."""
    values = np.asarray(values, dtype=float)
    nyquist = 0.5 / dt
    if cutoff_hz >= nyquist:
        return values.copy()
    from scipy import signal  # imported on use: 1-4 s that a run needs only at its end

    sos = signal.butter(order, cutoff_hz / nyquist, btype="low", output="sos")
    padlen = min(len(values) - 1, 3 * (2 * len(sos) + 1) * 4)
    return signal.sosfiltfilt(sos, values, padlen=padlen)


@dataclass
class ContactStatistics:
    mean_n: float
    std_n: float
    stat_max_n: float
    stat_min_n: float
    max_n: float
    min_n: float
    loss_of_contact_percent: float
    max_uplift_at_support_m: float
    samples: int
    window_start_m: float
    window_end_m: float

    def as_dict(self) -> dict:
        return {k: float(v) if isinstance(v, (float, np.floating)) else v
                for k, v in asdict(self).items()}


def window_mask(position: np.ndarray, start_m: float, end_m: float) -> np.ndarray:
    """Samples whose pantograph position lies in [start_m, end_m]."""
    if not end_m > start_m:
        raise ParameterError("analysis window", (start_m, end_m), "end must exceed start")
    tol = 1e-9 * max(1.0, abs(start_m), abs(end_m))  # round-off of x0 + v t at the bounds
    mask = (position >= start_m - tol) & (position <= end_m + tol)
    if mask.sum() < 2:
        raise ParameterError("analysis window", (start_m, end_m),
                             "contains no samples of the run (outside the simulated passage)")
    return mask


def contact_statistics(time: np.ndarray, force: np.ndarray, position: np.ndarray,
                       window: tuple[float, float], support_uplift: np.ndarray | None = None,
                       support_x: np.ndarray | None = None, cutoff_hz: float = 20.0
                       ) -> ContactStatistics:
    """Statistics of one pantograph's contact force over the analysis window.

    ``support_uplift`` (time x supports) and ``support_x`` give the maximum uplift of the
    supports that lie inside the window, over the pantograph's passage through the window.
    """
    time = np.asarray(time, float)
    force = np.asarray(force, float)
    dt = float(np.median(np.diff(time)))
    filtered = lowpass(force, dt, cutoff_hz)
    mask = window_mask(np.asarray(position, float), *window)
    f = filtered[mask]
    mean = float(f.mean())
    std = float(f.std())
    loss = 100.0 * float(np.mean(force[mask] <= 0.0))
    uplift = float("nan")
    if support_uplift is not None and support_x is not None:
        sx = np.asarray(support_x, float)
        inside = (sx >= window[0]) & (sx <= window[1])
        if inside.any():
            uplift = float(np.max(np.asarray(support_uplift)[mask][:, inside]))
    return ContactStatistics(mean_n=mean, std_n=std, stat_max_n=mean + 3 * std,
                             stat_min_n=mean - 3 * std, max_n=float(f.max()),
                             min_n=float(f.min()), loss_of_contact_percent=loss,
                             max_uplift_at_support_m=uplift, samples=int(mask.sum()),
                             window_start_m=float(window[0]), window_end_m=float(window[1]))


def force_spectrum(time: np.ndarray, force: np.ndarray, mask: np.ndarray | None = None):
    """One-sided amplitude spectrum [N] of the contact force (mean removed, Hann window)."""
    time = np.asarray(time, float)
    f = np.asarray(force, float)
    if mask is not None:
        time, f = time[mask], f[mask]
    dt = float(np.median(np.diff(time)))
    x = f - f.mean()
    w = np.hanning(len(x))
    amp = 2.0 * np.abs(np.fft.rfft(x * w)) / w.sum()
    freqs = np.fft.rfftfreq(len(x), dt)
    return freqs, amp

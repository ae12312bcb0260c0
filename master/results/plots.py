"""Plots of a coupled run: contact force along the track, its spectrum, uplift at supports."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from pantocosim.master.results.statistics import force_spectrum, lowpass  # noqa: E402


def plot_contact_force(path: Path, time, positions, forces, window, support_x, dropper_x,
                       labels, title: str) -> Path:
    """Raw and 0-20 Hz contact force against the pantograph position, with supports (solid)
    and droppers (dotted) marked and the analysis window shaded."""
    fig, ax = plt.subplots(figsize=(11, 4.5))
    dt = float(np.median(np.diff(time)))
    for x, f, label in zip(positions, forces, labels):
        ax.plot(x, f, lw=0.5, alpha=0.45, label=f"{label} raw")
        ax.plot(x, lowpass(f, dt), lw=1.2, label=f"{label} 0-20 Hz")
    lo = min(float(np.min(x)) for x in positions)
    hi = max(float(np.max(x)) for x in positions)
    for xs in support_x:
        if lo <= xs <= hi:
            ax.axvline(xs, color="k", lw=0.8, alpha=0.6)
    for xd in dropper_x:
        if lo <= xd <= hi:
            ax.axvline(xd, color="grey", lw=0.5, ls=":", alpha=0.6)
    ax.axvspan(window[0], window[1], color="tab:green", alpha=0.08, label="analysis window")
    ax.set_xlabel("position along the track x [m]")
    ax.set_ylabel("contact force [N]")
    ax.set_title(title)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8, ncol=3, loc="upper right")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def plot_spectrum(path: Path, time, forces, masks, labels, title: str) -> Path:
    fig, ax = plt.subplots(figsize=(8, 4))
    for f, m, label in zip(forces, masks, labels):
        freqs, amp = force_spectrum(time, f, m)
        keep = freqs <= 40.0
        ax.plot(freqs[keep], amp[keep], lw=1.0, label=label)
    ax.axvline(20.0, color="k", ls="--", lw=0.8, label="20 Hz (EN 50317)")
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("amplitude [N]")
    ax.set_title(title)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def plot_support_uplift(path: Path, time, uplift, support_x, title: str) -> Path:
    """Uplift of the contact wire at every support against time."""
    fig, ax = plt.subplots(figsize=(10, 4))
    uplift = np.asarray(uplift)
    for j, xs in enumerate(support_x):
        ax.plot(time, 1000.0 * uplift[:, j], lw=0.8, label=f"x = {xs:.0f} m")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("uplift at support [mm]")
    ax.set_title(title)
    ax.grid(True, alpha=0.3)
    if len(support_x) <= 14:
        ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path

#!/usr/bin/env python3
"""Flexible-bar vs rigid DSA-380 (thesis 2.3): frequencies (Table 2.2), static drop of
point 10 under 120 N (2.3.2, Fig. 2.14), time responses (Figs. 2.13, 2.15), FRFs (Figs.
2.19, 2.20, 2.22) and mode shapes; writes ``docs/figures/flex-*.png`` and prints the tables
quoted in ``docs/flexible-vs-rigid.md``.

    python scripts/compare_flexible_rigid.py [--quick] [--out docs/figures]
"""

from __future__ import annotations

import argparse
import copy
import math
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from pantocosim.core.hht import HHTIntegrator, HHTSettings  # noqa: E402
from pantocosim.core.linear_model import LinearModel  # noqa: E402
from pantocosim.pantograph.base import PantographOptions  # noqa: E402
from pantocosim.pantograph.dsa380 import load_dsa380  # noqa: E402
from pantocosim.pantograph.dsa380_flexible import (PRESET_FILE, load_dsa380_flexible,  # noqa
                                                   read_flexible)
from pantocosim.pantograph.modal import modal_analysis  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
F0 = 120.0
THESIS = [(0.77339, 0.6551, "collector pitch"), (1.2448, 1.2439, "mechanism"),
          (5.6362, 5.6231, "collector vertical"), (7.777, 7.8705, "collector horizontal"),
          (21.7733, None, "bar 5 bending"), (25.2445, None, "bar 5 bending + mechanism")]


def opts():
    return PantographOptions(static_force=F0, aero_c2=0.0)


# ----------------------------------------------------------------------------- frequencies

def frequencies(rigid, flex, stiff, fine):
    q0 = rigid.static_equilibrium(F0)
    M, C, K = rigid.linearize(q0, F0)
    rr = modal_analysis(M, C, K)
    ff, phi, labels = flex.modes(n_modes=8)
    Mf, Cf, Kf = flex.linearize(flex.q_equilibrium, F0)
    zf = modal_analysis(Mf, Cf, Kf).damping_ratios
    fs, _, ls = stiff.modes(n_modes=4)
    fn, _, _ = fine.modes(n_modes=6)
    print("\n## Natural frequencies, linearised about 120 N at 5.3 m (Table 2.2)\n")
    print("| mode | rigid [Hz] | flexible steel [Hz] | zeta flex | flex/rigid | flexible "
          "E x1000 [Hz] | mesh x2 change | thesis rigid | thesis ANSYS | label (flexible) |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for r in range(6):
        fr = rr.frequencies_hz[r] if r < 4 else None
        th = THESIS[r]
        print(f"| {r + 1} | {fr:.4f} |" if fr is not None else f"| {r + 1} | - |", end="")
        print(f" {ff[r]:.4f} | {zf[r]:.4f} |", end="")
        print(f" {100 * (ff[r] / fr - 1):+.2f} % |" if fr is not None else " - |", end="")
        print(f" {fs[r]:.5f} ({100 * (fs[r] / fr - 1):+.4f} %) |" if r < 4 else " - |", end="")
        print(f" {100 * (fn[r] / ff[r] - 1):+.4f} % |", end="")
        print(f" {th[1]} |" if th[1] else " - |", end="")
        print(f" {th[0]} ({th[2]}) | {labels[r]} |")
    print("\nfurther flexible modes: " + ", ".join(f"{f:.2f} Hz ({l})"
                                                   for f, l in zip(ff[6:], labels[6:])))
    print(f"dofs: flexible {flex.n_dofs} ({flex.n_elements} elements), mesh x2 {fine.n_dofs}")
    return ff, phi, labels


def plot_modes(flex, phi, freqs, labels, out):
    q0 = flex.q_equilibrium
    base = flex.bar_curves(q0)
    fig, axes = plt.subplots(2, 3, figsize=(13, 7.5))
    for r, ax in enumerate(axes.flat):
        shape = phi[:, r]
        # scale: largest node displacement 0.15 m (translations only, not slopes)
        pos = [i for i, nm in enumerate(flex.dof_names) if not nm.endswith(("_dx", "_dy"))]
        disp = np.max(np.abs(shape[pos]))
        amp = 0.15 / max(disp, 1e-12)
        for b, c in enumerate(base):
            ax.plot(c[:, 0], c[:, 1], color="0.75", lw=1.5)
        for sgn, col in ((1, "C0"), (-1, "C3")):
            curves = flex.bar_curves(q0 + sgn * amp * shape)
            for c in curves:
                ax.plot(c[:, 0], c[:, 1], color=col, lw=1.2)
        ax.set_aspect("equal")
        ax.set_title(f"mode {r + 1}: {freqs[r]:.3f} Hz\n{labels[r]}", fontsize=10)
        ax.grid(True, alpha=0.3)
        ax.set_xlabel("x [m]")
        ax.set_ylabel("height above rail [m]")
    fig.suptitle("Flexible DSA-380: first six modes about 120 N at 5.3 m (grey: equilibrium; "
                 "blue/red: +/- scaled shape)")
    fig.tight_layout()
    fig.savefig(out / "flex-mode-shapes.png", dpi=110)
    plt.close(fig)


# ----------------------------------------------------------------------------- static drop

def static_drop(rigid, flex, out):
    q0r = rigid.static_equilibrium(F0)
    M0 = rigid.torque
    h = flex.params.rigid.working_height
    qf = flex.equilibrium_under_torque(F0, M0, flex.q_equilibrium)
    drop = flex.contact_height(qf) - h
    flex.static_equilibrium(F0)
    print("\n## Static response under 120 N (thesis 2.3.2)\n")
    print(f"rigid model: torque M0 = {M0:.3f} N m holds point 10 at {h:.4f} m")
    print(f"flexible model under the same M0: point 10 at {flex.contact_height(qf):.6f} m, "
          f"i.e. {1e3 * drop:+.3f} mm (thesis: about -7 mm)")
    print(f"flexible model: torque to hold {h:.4f} m = {flex.torque:.3f} N m "
          f"({100 * (flex.torque / M0 - 1):+.2f} %)")
    # deflection of bar 4 relative to the tangent at point 4 (thesis Fig. 2.14)
    qa = flex.absolute(qf)
    g = flex.node_slope[3][0]
    slope4 = g[1] @ qa[g[0]:g[0] + 2]
    t = slope4 / np.linalg.norm(slope4)
    p4 = flex.point(qf, "4")
    p5 = flex.point(qf, "5")
    d = p5 - p4
    bend = t[0] * d[1] - t[1] * d[0]
    print(f"bar 4: tip (point 5) deflection from the tangent at point 4 = {1e3 * bend:+.3f} mm")
    U = flex.strain_energy_by_bar(qf)
    print("strain energy by bar [J]: " + ", ".join(f"{b + 1}: {u:.4f}" for b, u in enumerate(U)))
    # figure: mechanism, rigid vs flexible equilibrium (deformation x50)
    qr_f = flex.q_from_rigid(q0r)
    fig, axes = plt.subplots(1, 2, figsize=(12, 5.5))
    mag = 50.0
    for c in flex.bar_curves(qr_f):
        axes[0].plot(c[:, 0], c[:, 1], color="0.5", lw=2)
    for c in flex.bar_curves(qr_f + mag * (qf - qr_f)):
        axes[0].plot(c[:, 0], c[:, 1], color="C3", lw=1.2)
    axes[0].set_aspect("equal")
    axes[0].set_title(f"equilibrium under 120 N and the rigid torque M0\n"
                      f"grey: rigid; red: flexible, displacements x{mag:g}")
    axes[0].set_xlabel("x [m]")
    axes[0].set_ylabel("height above rail [m]")
    # bar 4 alone: rigid vs flexible (as Fig. 2.14)
    cr = flex.bar_curves(qr_f, 12)[3]
    cf = flex.bar_curves(qf, 12)[3]
    s = np.linspace(0, 1, len(cr)) * flex.bar_lengths[3]
    axes[1].plot(s, 1e3 * (cf[:, 1] - cr[:, 1]), "C3", label="flexible - rigid, vertical")
    axes[1].plot(s, 1e3 * (cf[:, 0] - cr[:, 0]), "C0", label="flexible - rigid, along track")
    axes[1].set_xlabel("arc length along bar 4 from point 4 [m]")
    axes[1].set_ylabel("displacement [mm]")
    axes[1].set_title(f"bar 4 (thesis Fig. 2.14): point 10 drops {1e3 * -drop:.2f} mm")
    axes[1].legend()
    for ax in axes:
        ax.grid(True, alpha=0.3)
    fig.tight_layout()
    fig.savefig(out / "flex-static-drop.png", dpi=110)
    plt.close(fig)
    return drop, M0


# ----------------------------------------------------------------------------- time response

def run_time(model, q_init, force, duration, dt, linear_about=None):
    """HHT-alpha (-0.05) from rest at q_init under F(t); returns t, y10(t)."""
    if linear_about is not None:
        q0, F_lin = linear_about
        M, C, K = model.linearize(q0, F_lin)
        grad = np.asarray(model.contact_height_gradient(q0), float)
        system = LinearModel(M, C, K, input_matrix=-grad[:, None], q_ref=q0)
        inp = lambda t: np.array([force(t) - F_lin])  # noqa: E731
    else:
        system = model
        inp = lambda t: np.array([force(t)])  # noqa: E731
    integ = HHTIntegrator(system, HHTSettings(alpha=-0.05))
    integ.initialize(0.0, q_init, np.zeros(model.n_dofs), inp(0.0))
    n = int(round(duration / dt))
    ts = np.arange(n + 1) * dt
    ys = np.empty(n + 1)
    for i in range(n + 1):
        if i:
            integ.step(dt, inp(ts[i]))
        ys[i] = model.contact_height(integ.q)
    return ts, ys


def time_responses(rigid, flex, out, duration):
    """Figs. 2.13 and 2.15: both models at rest in the same initial position (the rigid
    configuration 50 mm above the working height, undeformed bars), with the rigid model's
    torque M0 for 120 N at the working height; load -120 N or -120 - 30 sin(4 pi t) N."""
    h = flex.params.rigid.working_height
    q0r = rigid.static_equilibrium(F0, h)
    M0 = rigid.torque
    probe = copy.deepcopy(rigid)
    q_init_r = probe.static_equilibrium(F0, h + 0.05)
    q_init_f = flex.q_from_rigid(q_init_r)
    flex.torque = M0
    flex.torque_lowered = None
    cases = {"2.13": ("F = 120 N", lambda t: F0),
             "2.15": ("F = 120 + 30 sin(4 pi t) N",
                      lambda t: F0 + 30.0 * math.sin(4 * math.pi * t))}
    fig, axes = plt.subplots(2, 1, figsize=(10, 8))
    print("\n## Time responses (thesis Figs. 2.13, 2.15): from 50 mm above the working height, "
          "rigid torque M0\n")
    for ax, (fig_no, (label, force)) in zip(axes, cases.items()):
        t0 = time.perf_counter()
        t, yr = run_time(rigid, q_init_r, force, duration, 1e-3)
        t1 = time.perf_counter()
        _, yf = run_time(flex, q_init_f, force, duration, 1e-3)
        t2 = time.perf_counter()
        _, yl = run_time(rigid, q_init_r, force, duration, 1e-3, linear_about=(q0r, F0))
        y_init = yr[0]
        ax.plot(t, 1e3 * (yr - y_init), label="rigid, nonlinear")
        ax.plot(t, 1e3 * (yf - y_init), label="flexible (steel), nonlinear")
        ax.plot(t, 1e3 * (yl - y_init), "--", label="rigid, linearised about 120 N", lw=1)
        ax.set_ylabel("Delta y10 [mm]")
        ax.set_title(f"thesis Fig. {fig_no}: {label} from rest 50 mm above {h} m")
        ax.grid(True, alpha=0.3)
        ax.legend()
        last = t > duration - 1.0
        off = np.mean(yf[last] - yr[last])
        print(f"Fig. {fig_no} ({label}): final mean offset flexible - rigid = "
              f"{1e3 * off:+.3f} mm; max |flexible - rigid| after removing it = "
              f"{1e3 * np.max(np.abs((yf - yr)[t > 1.0] - off)):.3f} mm; "
              f"rigid {t1 - t0:.1f} s, flexible {t2 - t1:.1f} s wall")
    axes[-1].set_xlabel("time [s]")
    fig.tight_layout()
    fig.savefig(out / "flex-time-response.png", dpi=110)
    plt.close(fig)
    flex.static_equilibrium(F0)


# ----------------------------------------------------------------------------- FRFs

def frf_linear(model, q0, freqs):
    """|H33| = |y10 / F| of the linearised model (2.36) (one column solve per frequency)."""
    M, C, K = model.linearize(q0, F0)
    b = np.asarray(model.contact_height_gradient(q0), float)
    H = np.empty(len(freqs), complex)
    for i, f in enumerate(freqs):
        w = 2 * math.pi * f
        H[i] = b @ np.linalg.solve(K - w * w * M + 1j * w * C, b)
    return H


def frf_nonlinear(model, q0, freqs, amplitude):
    """Thesis 2.3.3: harmonic force of each frequency, peak-to-peak of the steady state / 2A.
    Starts on the linear steady state (Re/Im of H F) so that only the nonlinear transient
    remains; integrates >= 3 s and measures the last 2 periods (at least 1 s)."""
    M, C, K = model.linearize(q0, F0)
    b = np.asarray(model.contact_height_gradient(q0), float)
    out = np.empty(len(freqs))
    for i, f in enumerate(freqs):
        w = 2 * math.pi * f
        X = np.linalg.solve(K - w * w * M + 1j * w * C, -b * amplitude)  # F = F0 + A sin wt
        q_init = q0 + np.imag(X)
        v_init = np.imag(1j * w * X)  # d/dt Im(X e^{iwt}) at t = 0
        period = 1.0 / f
        dt = min(1e-3, period / 200.0)
        duration = max(3.0, 8 * period)
        force = lambda t: F0 + amplitude * math.sin(w * t)  # noqa: E731
        # rtol 1e-6: in slow quasi-static motion the assembled residual is tiny while the
        # stiffest bars (EA / l ~ 1e10 N/m) leave a round-off floor ~ eps |q| EA / l
        integ = HHTIntegrator(model, HHTSettings(alpha=-0.05, rtol=1e-6))
        # the linear steady-state acceleration: the nearly massless links would otherwise get
        # a huge a0 from the small nonlinear imbalance of the linear initial state
        integ.initialize(0.0, q_init, v_init, np.array([force(0.0)]),
                         a0=np.imag(-w * w * X))
        n = int(round(duration / dt))
        window = max(2 * period, 1.0)
        ys = []
        for k in range(1, n + 1):
            integ.step(dt, np.array([force(k * dt)]))
            if k * dt >= duration - window:
                ys.append(model.contact_height(integ.q))
        out[i] = (max(ys) - min(ys)) / (2 * amplitude)
    return out


def frfs(rigid, flex, out, quick):
    q0r = rigid.static_equilibrium(F0)
    q0f = flex.static_equilibrium(F0)
    fl = np.logspace(np.log10(0.2), np.log10(30.0), 600)
    Hr = frf_linear(rigid, q0r, fl)
    Hf = frf_linear(flex, q0f, fl)
    fn = np.array([0.3, 0.6, 1.0, 1.2, 1.4, 2.0, 3.0, 4.0, 5.0, 5.4, 5.6, 5.8, 6.5, 8.0, 10.0,
                   14.0, 20.0, 22.5, 25.0, 30.0])
    if quick:
        fn = fn[::3]
    t0 = time.perf_counter()
    Nr = frf_nonlinear(rigid, q0r, fn, 10.0)
    t1 = time.perf_counter()
    Nf = frf_nonlinear(flex, q0f, fn, 10.0)
    t2 = time.perf_counter()
    print("\n## FRF |y10/F| (Figs. 2.19, 2.20, 2.22)\n")
    i1 = np.argmax(np.abs(Hr) * (fl < 3))
    j1 = np.argmax(np.abs(Hf) * (fl < 3))
    i2 = np.argmax(np.abs(Hr) * (fl > 3))
    j2 = np.argmax(np.abs(Hf) * (fl > 3))
    print(f"linear peaks: rigid {fl[i1]:.3f} Hz {abs(Hr[i1]) * 1e3:.3f} mm/N, "
          f"{fl[i2]:.3f} Hz {abs(Hr[i2]) * 1e3:.3f} mm/N; flexible {fl[j1]:.3f} Hz "
          f"{abs(Hf[j1]) * 1e3:.3f} mm/N, {fl[j2]:.3f} Hz {abs(Hf[j2]) * 1e3:.3f} mm/N")
    for k in (20.0, 22.5, 25.0, 30.0):
        i = np.argmin(np.abs(fl - k))
        print(f"  at {fl[i]:.2f} Hz: rigid {abs(Hr[i]):.3e} m/N, flexible {abs(Hf[i]):.3e} m/N")
    print("| f [Hz] | rigid linear | rigid nonlinear 10 N | flexible linear | flexible "
          "nonlinear 10 N | [mm/N] |")
    print("|---|---|---|---|---|---|")
    Hr_n = np.abs(frf_linear(rigid, q0r, fn))
    Hf_n = np.abs(frf_linear(flex, q0f, fn))
    for k, f in enumerate(fn):
        print(f"| {f:g} | {1e3 * Hr_n[k]:.4f} | {1e3 * Nr[k]:.4f} | {1e3 * Hf_n[k]:.4f} | "
              f"{1e3 * Nf[k]:.4f} | |")
    print(f"nonlinear sweeps: rigid {t1 - t0:.1f} s, flexible {t2 - t1:.1f} s wall")
    # figures
    fig, ax = plt.subplots(figsize=(9, 5.5))
    ax.semilogy(fn, Nr, "o-", label="rigid, nonlinear (10 N)")
    ax.semilogy(fn, Nf, "s--", label="flexible, nonlinear (10 N)")
    ax.set_title("thesis Fig. 2.19: nonlinear rigid vs flexible, |y10 / F|")
    _frf_axes(ax, fig, out / "flex-frf-nonlinear.png")
    fig, ax = plt.subplots(figsize=(9, 5.5))
    ax.semilogy(fl, np.abs(Hf), label="flexible, linearised")
    ax.semilogy(fn, Nf, "s", label="flexible, nonlinear (10 N)")
    ax.semilogy(fl, np.abs(Hr), "--", label="rigid, linearised")
    ax.semilogy(fn, Nr, "o", mfc="none", label="rigid, nonlinear (10 N)")
    ax.set_title("thesis Fig. 2.20 / 2.22: linearised and nonlinear, rigid and flexible")
    _frf_axes(ax, fig, out / "flex-frf-all.png")
    return fn, Nr, Nf


def _frf_axes(ax, fig, path):
    ax.set_xscale("log")
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("|H33| = |y10 / F| [m/N]")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer FRF points, shorter runs")
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "figures")
    args = ap.parse_args(argv)
    out = args.out
    out.mkdir(parents=True, exist_ok=True)
    rigid = load_dsa380(None, opts())
    flex = load_dsa380_flexible(None, opts())
    stiff = load_dsa380_flexible(None, opts(), E=1000 * flex.params.E)
    fine = load_dsa380_flexible(None, opts(),
                                mesh=tuple(2 * n for n in read_flexible(PRESET_FILE)[0].mesh))
    ff, phi, labels = frequencies(rigid, flex, stiff, fine)
    plot_modes(flex, phi, ff, labels, out)
    static_drop(rigid, flex, out)
    time_responses(rigid, flex, out, 4.0 if args.quick else 8.0)
    frfs(rigid, flex, out, args.quick)
    print(f"\nfigures in {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

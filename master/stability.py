"""Numerical stability of a run: checked before it starts and watched while it runs.

Before. The explicit (Jacobi) and Gauss-Seidel couplings exchange the penalty force once per
step: each side steps under the force of the previous exchange, a lag of one step plus the
half step of the held force. Around the contact the catenary is a taut wire, whose point
receptance is that of a dashpot, ``1 / (i w Z_w)`` with the wire impedance
``Z_w = 2 sqrt(T rho)`` (contact-wire tension and mass per length, waves leaving both ways),
and the pantograph is its contact mass ``m_p`` (receptance ``-1 / (m_p w^2)``; the mass seen
at the contact point, ``1 / (g^T M^-1 g)`` of the model's linearisation, ``g`` the gradient of
its contact height). The lag of ``1.5 dt`` turns the dashpot's -90 degrees into -180 degrees at
``w* = pi / (3 dt)``; the exchange is stable while the loop gain there is below 1::

    G = |k_c + i w* c_c| * sqrt((1 / (w* Z_w))^2 + (1 / (m_p w*^2))^2) < 1.

Measured on en50318 (3 spans, 250 km/h, en50318-2mass; ``scripts/stability_breakpoints.py``,
checked in ``tests/test_stability.py``):
the Jacobi and Gauss-Seidel couplings break between k_c = 3e5 (G = 0.87) and 4e5 N/m
(G = 1.16) at 1 ms, between 8e4 (G = 1.2) and 1.2e5 N/m at 5 ms and between 8e4 (G = 2.6)
and 1e5 N/m at 10 ms: at longer steps the catenary is stiffer than a wire alone, so the limit
errs on the safe side there. A run with ``G >= 1`` is refused, one with ``G >= 0.5`` warned.

Any coupling, the monolithic one too, warns when the step does not resolve the contact
frequency ``f_c = sqrt(k_c / m_p) / (2 pi)``: above ``1 / (10 dt)`` the contact force chatters
at a frequency the step only aliases (loss-of-contact figures are then the step's, not the
system's).

During. :class:`Monitor` stops a run whose contact force is not finite or exceeds
:data:`FORCE_CAP_FACTOR` times the pantograph's static force (its mean uplift when larger),
or whose pantograph stays off the wire for :data:`SEPARATION_LIMIT_S` after its raising: the
run ends with :class:`Diverged`, its results so far kept as for Ctrl-C.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pantocosim.core.errors import ParameterError, PantocosimError

#: the exchange's loop gain at which an explicit or Gauss-Seidel run is refused
GAIN_LIMIT = 1.0
#: ... and at which it is warned as near the limit
GAIN_WARNING = 0.5
#: steps per contact period below which the contact frequency counts as not resolved
STEPS_PER_CONTACT_PERIOD = 10
#: a contact force above this multiple of the static force stops the run
FORCE_CAP_FACTOR = 20.0
#: a pantograph out of contact this long [s] (after its raising) has not come back to the
#: wire: under its uplift force a pantograph returns within tens of milliseconds
SEPARATION_LIMIT_S = 0.5
#: couplings that exchange the force once per step
STAGGERED = ("jacobi", "explicit", "gauss-seidel")


class Diverged(PantocosimError):
    """A run's numerics failed (a non-finite or runaway contact force); says when and why."""


def contact_mass(pantograph, q0, force: float) -> float:
    """The pantograph's mass seen at the contact point [kg]: ``1 / (g^T M^-1 g)`` of its
    linearisation about ``q0`` under ``force``."""
    M, _, _ = pantograph.linearize(q0, force)
    g = np.asarray(pantograph.contact_height_gradient(q0), float)
    return float(1.0 / (g @ np.linalg.solve(M, g)))


def wire_impedance(definition) -> float:
    """Point impedance of the contact wire [N s/m]: ``2 sqrt(T rho)``."""
    return 2.0 * math.sqrt(definition.contact.tension * definition.contact.mass_per_length)


def critical_frequency(dt: float) -> float:
    """``w* = pi / (3 dt)`` [rad/s], where the exchange's lag turns the loop (module
    docstring)."""
    return math.pi / (3.0 * dt)


def receptance(dt: float, mass: float, impedance: float) -> float:
    """``|1 / (i w* Z_w) - 1 / (m_p w*^2)|`` of wire and pantograph at ``w*``."""
    w = critical_frequency(dt)
    return math.hypot(1.0 / (w * impedance), 1.0 / (mass * w * w))


def exchange_gain(stiffness: float, damping: float, dt: float, mass: float,
                  impedance: float) -> float:
    """Loop gain of a once-per-step exchange of the penalty force (module docstring)."""
    law = math.hypot(stiffness, critical_frequency(dt) * damping)
    return law * receptance(dt, mass, impedance)


def contact_frequency(stiffness: float, mass: float) -> float:
    """``sqrt(k_c / m_p) / (2 pi)`` [Hz]."""
    return math.sqrt(stiffness / mass) / (2.0 * math.pi)


@dataclass
class Estimate:
    """The stability figures of one pantograph's contact."""
    mass: float              # m_p [kg]
    impedance: float         # Z_w [N s/m]
    gain: float              # G of the staggered exchange
    frequency: float         # f_c [Hz]


def estimates(prep) -> list[Estimate]:
    """:class:`Estimate` of every pantograph of a :class:`~pantocosim.master.run.Prepared`."""
    sc = prep.scenario
    z = wire_impedance(prep.definition)
    out = []
    for k, pan in enumerate(prep.pantographs):
        m = contact_mass(pan, prep.q_pan0[k], float(pan.options.mean_uplift))
        out.append(Estimate(mass=m, impedance=z,
                            gain=exchange_gain(sc.contact_stiffness, sc.contact_damping,
                                               sc.dt, m, z),
                            # a rigid contact (compliance 0) has no contact mode
                            frequency=(contact_frequency(sc.contact_stiffness, m)
                                       if prep.contact.compliance > 0.0 else 0.0)))
    return out


def _largest_stable_step(sc, est: Estimate) -> float | None:
    """The largest dt with a gain below the limit (bisection on the monotone gain); None if
    no step runs (the contact damping alone gives ``c_c / Z_w`` at any step)."""
    lo, hi = 1e-9, sc.dt
    if exchange_gain(sc.contact_stiffness, sc.contact_damping, lo, est.mass,
                     est.impedance) >= GAIN_LIMIT:
        return None
    for _ in range(60):
        mid = math.sqrt(lo * hi)
        if exchange_gain(sc.contact_stiffness, sc.contact_damping, mid, est.mass,
                         est.impedance) < GAIN_LIMIT:
            lo = mid
        else:
            hi = mid
    return lo


def _culprit(sc, est: Estimate) -> tuple[str, float, str]:
    """The contact field that sets the gain, its value and the largest one that runs."""
    w = critical_frequency(sc.dt)
    budget = GAIN_LIMIT / receptance(sc.dt, est.mass, est.impedance)   # |k + i w c| that runs
    if sc.contact_stiffness >= w * sc.contact_damping:
        rest = max(budget ** 2 - (w * sc.contact_damping) ** 2, 0.0)
        return "contact.stiffness", sc.contact_stiffness, f"contact.stiffness < {math.sqrt(rest):.3g} N/m"
    # the damping's share of the gain tends to c_c / Z_w at small steps
    return ("contact.damping", sc.contact_damping,
            f"contact.damping < {GAIN_LIMIT * est.impedance:.3g} N s/m")


def check(prep, coupling: str) -> list[str]:
    """Refuse (:class:`ParameterError`) a staggered coupling beyond its stability limit;
    return the warnings of the run (near the limit, contact frequency not resolved)."""
    sc = prep.scenario
    name = {"jacobi": "explicit (Jacobi)"}.get(coupling, coupling)
    warnings = []
    for k, est in enumerate(estimates(prep)):
        who = f"pantograph {k + 1}" if len(prep.pantographs) > 1 else "the pantograph"
        if coupling in STAGGERED:
            if est.gain >= GAIN_LIMIT:
                field, value, smaller = _culprit(sc, est)
                step = _largest_stable_step(sc, est)
                runs = ("no step size runs it; " if step is None else
                        f"runs with simulation.dt <= {step:.2g} s, ")
                raise ParameterError(
                    field, value,
                    f"the {name} coupling is unstable at simulation.dt = {sc.dt:g} s "
                    f"({who}: exchange gain {est.gain:.3g} >= {GAIN_LIMIT:g}, contact mass "
                    f"{est.mass:.3g} kg, wire impedance {est.impedance:.3g} N s/m); {runs}"
                    f"{smaller}, --coupling implicit or monolithic", sc.source)
            if est.gain >= GAIN_WARNING:
                warnings.append(
                    f"{who}: the {name} coupling is near its stability limit at dt = "
                    f"{sc.dt:g} s (exchange gain {est.gain:.2f}, refused at "
                    f"{GAIN_LIMIT:g}); check against --coupling implicit or a smaller step")
        if est.frequency * sc.dt > 1.0 / STEPS_PER_CONTACT_PERIOD:
            warnings.append(
                f"{who}: contact frequency {est.frequency:.0f} Hz (contact.stiffness = "
                f"{sc.contact_stiffness:g} N/m on a contact mass of {est.mass:.3g} kg) is not "
                f"resolved by dt = {sc.dt:g} s (needs dt <= "
                f"{1.0 / (STEPS_PER_CONTACT_PERIOD * est.frequency):.2g} s): the force "
                "chatters and the loss of contact is the step's")
    return warnings


class Monitor:
    """Stops a run whose contact forces are not finite or run away, or whose pantograph does
    not come back to the wire (:class:`Diverged`)."""

    def __init__(self, prep):
        static = np.asarray(prep.static_forces, float)
        uplift = np.array([float(p.options.mean_uplift) for p in prep.pantographs])
        self.cap = FORCE_CAP_FACTOR * np.maximum(np.maximum(static, uplift), 1.0)
        #: when each pantograph is raised (0 for a static start) and last touched the wire
        self.raised = np.array([0.0 if p.options.ramp is None else
                                p.options.ramp.start + p.options.ramp.duration
                                for p in prep.pantographs])
        self.touched = self.raised.copy()

    def check(self, t: float, forces) -> None:
        F = np.asarray(forces, float)
        self.touched[F > 0.0] = t
        off = t - np.maximum(self.touched, self.raised)
        if (off > SEPARATION_LIMIT_S).any():
            k = int(np.argmax(off))
            raise Diverged(f"the numerics failed at t = {t:.6g} s: pantograph {k + 1} left "
                           f"the wire at t = {self.touched[k]:.6g} s and has not come back "
                           "(under its uplift force it would within tens of ms)")
        bad = ~np.isfinite(F) | (np.abs(F) > self.cap)
        if bad.any():
            k = int(np.argmax(bad))
            why = ("is not finite" if not np.isfinite(F[k]) else
                   f"exceeds {FORCE_CAP_FACTOR:g} times the static force ({self.cap[k]:.0f} N)")
            raise Diverged(f"the numerics failed at t = {t:.6g} s: the contact force of "
                           f"pantograph {k + 1} ({F[k]:.4g} N) {why} (a diverging coupling, "
                           "or impacts the step does not resolve)")

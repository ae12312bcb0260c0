"""Numerical stability of a run: checked before it starts, watched while it runs, judged
after it ends.

Before. The staggered couplings (Jacobi, Gauss-Seidel) exchange the penalty force once per
step; two loop gains bound them, derived and measured in docs/stability.md ("Before a run"):
the wave gain of the wire's dashpot and the pantograph's contact mass under the exchange's lag
of ``1.5 dt`` (:func:`exchange_gain`)::

    G_w = |k_c + i w* c_c| * sqrt((1 / (w* Z_w))^2 + (1 / (m_p w*^2))^2),  w* = pi / (3 dt)

and the gain through a catenary's instantaneous compliance ``s`` at the contact (a modal
model's static correction; :func:`feedthrough_gain`)::

    G_s = 3 s (k_c + 4 c_c / (|alpha| dt))

The exchange gain is ``G = max(G_w, G_s)``: a run with ``G >= 1`` (:data:`GAIN_LIMIT`) is
refused, one with ``G >= 0.5`` (:data:`GAIN_WARNING`) warned. Any coupling, the monolithic
one too, warns when the step does not resolve the contact frequency
``f_c = sqrt(k_c / m_p) / (2 pi)`` (above ``1 / (10 dt)``), and when a rigid contact meets
a contact point without mass (the modal model's static correction).

During. :class:`Monitor` stops a run whose contact force is not finite or exceeds
:data:`FORCE_CAP_FACTOR` times the pantograph's static force (its mean uplift when larger),
or whose pantograph stays off the wire for :data:`SEPARATION_LIMIT_S` after its raising: the
run ends with :class:`Diverged`, its results so far kept as for Ctrl-C.

After. :func:`departures` flags a run whose mean contact force departs from the mean uplift
its static start sets by more than :data:`MEAN_DEPARTURE` of it, or whose loss of contact
exceeds what the normal law of its own force statistics predicts by more than
:data:`LOSS_EXCESS_POINTS` (a force that alternates from step to step loses contact while
its filtered statistics say it should not). :func:`step_separations` flags the separations
of a rigid contact that last at most :data:`UNRESOLVED_SEPARATION_STEPS` steps (the step's,
not the line's).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pantocosim.core.errors import ParameterError, PantocosimError
from pantocosim.interaction.penalty_contact import DEFAULT_CONTACT_STIFFNESS, max_passes

#: the exchange's loop gain at which an explicit or Gauss-Seidel run is refused
GAIN_LIMIT = 1.0
#: ... and at which it is warned as near the limit
GAIN_WARNING = 0.5
#: steps per contact period below which the contact frequency counts as not resolved
STEPS_PER_CONTACT_PERIOD = 10
#: a rigid contact's separation lasting at most this many steps is not resolved by the step
#: (docs/en50318-validation.md, "Loss of contact and the step")
UNRESOLVED_SEPARATION_STEPS = 3
#: a contact force above this multiple of the static force stops the run
FORCE_CAP_FACTOR = 20.0
#: a pantograph out of contact this long [s] (after its raising) has not come back to the
#: wire: under its uplift force a pantograph returns within tens of milliseconds
SEPARATION_LIMIT_S = 0.5
#: couplings that exchange the force once per step
STAGGERED = ("jacobi", "explicit", "gauss-seidel")
#: the exchange's first-order hold ``2 F_n - F_(n-1)`` on a force alternating from step to step
HOLD_GAIN_NYQUIST = 3.0
#: track spacing [m] at which the catenary's contact compliance is read along a run ...
COMPLIANCE_SPACING_M = 0.05
#: ... in at most this many readings
COMPLIANCE_SAMPLES = 20000
#: a mean contact force farther than this share of the mean uplift from it flags the run
MEAN_DEPARTURE = 0.2
#: loss of contact [percentage points] beyond the normal law of the run's own force
#: statistics that flags the run
LOSS_EXCESS_POINTS = 10.0


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
    """``G_w``: loop gain of a once-per-step exchange of the penalty force between the wire
    and the contact mass (module docstring)."""
    law = math.hypot(stiffness, critical_frequency(dt) * damping)
    return law * receptance(dt, mass, impedance)


def nyquist_velocity_gain(dt: float, alpha: float) -> float:
    """``|v / x|`` of the HHT-alpha velocity of a displacement alternating from step to step:
    ``(2 gamma - 1) / (dt (2 beta - gamma)) = 4 / (|alpha| dt)``; infinite at alpha = 0."""
    return math.inf if alpha == 0.0 else 4.0 / (abs(alpha) * dt)


def feedthrough_gain(stiffness: float, damping: float, dt: float, alpha: float,
                     compliance: float) -> float:
    """``G_s = 3 s (k_c + 4 c_c / (|alpha| dt))``: loop gain of the exchange through the
    catenary's instantaneous compliance ``s`` at the contact (module docstring)."""
    if compliance <= 0.0:
        return 0.0
    law = stiffness + (damping * nyquist_velocity_gain(dt, alpha) if damping > 0.0 else 0.0)
    return HOLD_GAIN_NYQUIST * law * compliance


def run_compliance(prep) -> np.ndarray:
    """The largest instantaneous compliance [m/N] each pantograph meets on the run, from the
    catenary's ``contact_compliance`` every :data:`COMPLIANCE_SPACING_M` of track (a row's
    sum of magnitudes: it bounds the loop through several pantographs)."""
    duration = prep.duration
    n = int(min(math.ceil(abs(prep.scenario.speed) * duration / COMPLIANCE_SPACING_M) + 1,
                COMPLIANCE_SAMPLES))
    times = np.linspace(0.0, duration, max(n, 1))
    return np.abs(prep.catenary.contact_compliance(times)).sum(axis=2).max(axis=0)


def contact_frequency(stiffness: float, mass: float) -> float:
    """``sqrt(k_c / m_p) / (2 pi)`` [Hz]."""
    return math.sqrt(stiffness / mass) / (2.0 * math.pi)


@dataclass
class Estimate:
    """The stability figures of one pantograph's contact."""
    mass: float              # m_p [kg]
    impedance: float         # Z_w [N s/m]
    compliance: float        # s [m/N]: the largest instantaneous compliance on the run
    wave_gain: float         # G_w of the wire and the contact mass
    feedthrough_gain: float  # G_s of the compliance
    frequency: float         # f_c [Hz]

    @property
    def gain(self) -> float:
        """The exchange gain ``G = max(G_w, G_s)``."""
        return max(self.wave_gain, self.feedthrough_gain)


def estimates(prep) -> list[Estimate]:
    """:class:`Estimate` of every pantograph of a :class:`~pantocosim.master.run.Prepared`."""
    sc = prep.scenario
    z = wire_impedance(prep.definition)
    compliance = run_compliance(prep)
    out = []
    for k, pan in enumerate(prep.pantographs):
        m = contact_mass(pan, prep.q_pan0[k], float(pan.options.mean_uplift))
        s = float(compliance[k])
        out.append(Estimate(
            mass=m, impedance=z, compliance=s,
            wave_gain=exchange_gain(sc.contact_stiffness, sc.contact_damping, sc.dt, m, z),
            feedthrough_gain=feedthrough_gain(sc.contact_stiffness, sc.contact_damping, sc.dt,
                                              sc.alpha, s),
            # a rigid contact (compliance 0) has no contact mode
            frequency=(contact_frequency(sc.contact_stiffness, m)
                       if prep.contact.compliance > 0.0 else 0.0)))
    return out


def _wave_gain_at(sc, est: Estimate, dt: float) -> float:
    return exchange_gain(sc.contact_stiffness, sc.contact_damping, dt, est.mass, est.impedance)


def _largest_stable_step(sc, est: Estimate) -> float | None:
    """The largest dt with both gains below the limit (bisection on the monotone ``G_w``;
    ``G_s`` does not fall with the step); None if no step runs (``G_s`` at this step, or the
    contact damping alone, which gives ``c_c / Z_w`` at any step)."""
    lo, hi = 1e-9, sc.dt
    if est.feedthrough_gain >= GAIN_LIMIT or _wave_gain_at(sc, est, lo) >= GAIN_LIMIT:
        return None
    for _ in range(60):
        mid = math.sqrt(lo * hi)
        if _wave_gain_at(sc, est, mid) < GAIN_LIMIT:
            lo = mid
        else:
            hi = mid
    if feedthrough_gain(sc.contact_stiffness, sc.contact_damping, lo, sc.alpha,
                        est.compliance) >= GAIN_LIMIT:
        return None
    return lo


def _culprit(sc, est: Estimate) -> tuple[str, float, str]:
    """The contact field that sets ``G_w``, its value and the largest one that runs."""
    w = critical_frequency(sc.dt)
    budget = GAIN_LIMIT / receptance(sc.dt, est.mass, est.impedance)   # |k + i w c| that runs
    if sc.contact_stiffness >= w * sc.contact_damping:
        rest = max(budget ** 2 - (w * sc.contact_damping) ** 2, 0.0)
        return "contact.stiffness", sc.contact_stiffness, f"contact.stiffness < {math.sqrt(rest):.3g} N/m"
    # the damping's share of the gain tends to c_c / Z_w at small steps
    return ("contact.damping", sc.contact_damping,
            f"contact.damping < {GAIN_LIMIT * est.impedance:.3g} N s/m")


def _down(x: float) -> float:
    """``x`` rounded down to 3 significant digits (a bound that still holds as printed)."""
    e = math.floor(math.log10(x)) - 2
    return math.floor(x / 10.0 ** e) * 10.0 ** e


def _feedthrough_culprit(prep, est: Estimate) -> tuple[str, float, str]:
    """What the user set that makes ``G_s``: the contact damping when its share is the
    larger, else a contact stiffness the scenario sets, else the catenary model's setting
    of its compliance (the modal cutoff); with what runs."""
    sc = prep.scenario
    budget = GAIN_LIMIT / (HOLD_GAIN_NYQUIST * est.compliance)   # k_c + c_c |v/x| that runs
    velocity = nyquist_velocity_gain(sc.dt, sc.alpha)
    damped = sc.contact_damping > 0.0
    stiffness = f"contact.stiffness < {_down(budget):.3g} N/m" + (" without contact damping"
                                                                   if damped else "")
    if damped and sc.contact_damping * velocity >= sc.contact_stiffness:
        rest = (budget - sc.contact_stiffness) / velocity
        runs = f"contact.damping < {_down(rest):.3g} N s/m" if rest > 0.0 else stiffness
        return "contact.damping", sc.contact_damping, runs
    setting = prep.catenary.compliance_setting
    if sc.contact_stiffness != DEFAULT_CONTACT_STIFFNESS or setting is None:
        return "contact.stiffness", sc.contact_stiffness, stiffness
    return f"simulation.{setting}", getattr(sc, setting), stiffness


def _setting_names(setting: str) -> str:
    """A catenary model's setting as the scenario and the command line name it."""
    return f"simulation.{setting} (--{setting.replace('_', '-')})"


def _refusal(prep, est: Estimate, name: str, who: str) -> ParameterError:
    """The one-line refusal of a staggered coupling beyond its limit."""
    sc = prep.scenario
    if est.wave_gain >= est.feedthrough_gain:
        field, value, smaller = _culprit(sc, est)
        step = _largest_stable_step(sc, est)
        runs = ("no step size runs it; " if step is None else
                f"runs with simulation.dt <= {step:.2g} s, ")
        return ParameterError(
            field, value,
            f"the {name} coupling is unstable at simulation.dt = {sc.dt:g} s "
            f"({who}: exchange gain {est.gain:.3g} >= {GAIN_LIMIT:g}, contact mass "
            f"{est.mass:.3g} kg, wire impedance {est.impedance:.3g} N s/m); {runs}"
            f"{smaller}, --coupling implicit or monolithic", sc.source)
    field, value, smaller = _feedthrough_culprit(prep, est)
    setting = prep.catenary.compliance_setting
    higher = "" if setting is None else f", a higher {_setting_names(setting)}"
    return ParameterError(
        field, value,
        f"the {name} coupling is unstable at simulation.dt = {sc.dt:g} s through the "
        f"catenary's instantaneous compliance at the contact ({who}: {est.compliance:.3g} "
        f"m/N, exchange gain {est.gain:.3g} >= {GAIN_LIMIT:g}); no smaller step runs it; "
        f"runs with {smaller}{higher}, --coupling implicit or monolithic", sc.source)


def _near_limit(prep, est: Estimate, name: str, who: str) -> str:
    sc = prep.scenario
    if est.wave_gain >= est.feedthrough_gain:
        return (f"{who}: the {name} coupling is near its stability limit at dt = {sc.dt:g} s "
                f"(exchange gain {est.gain:.2f}, refused at {GAIN_LIMIT:g}); check against "
                "--coupling implicit or a smaller step")
    setting = prep.catenary.compliance_setting
    higher = "" if setting is None else f" or a higher {_setting_names(setting)}"
    return (f"{who}: the {name} coupling is near its stability limit through the catenary's "
            f"instantaneous compliance at the contact ({est.compliance:.3g} m/N, exchange gain "
            f"{est.gain:.2f}, refused at {GAIN_LIMIT:g}); check against --coupling implicit"
            f"{higher}")


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
                raise _refusal(prep, est, name, who)
            if est.gain >= GAIN_WARNING:
                warnings.append(_near_limit(prep, est, name, who))
        if prep.contact.compliance == 0.0 and est.compliance > 0.0:
            warnings.append(_massless_contact_point(who, est))
        if est.frequency * sc.dt > 1.0 / STEPS_PER_CONTACT_PERIOD:
            warnings.append(
                f"{who}: contact frequency {est.frequency:.0f} Hz (contact.stiffness = "
                f"{sc.contact_stiffness:g} N/m on a contact mass of {est.mass:.3g} kg) is not "
                f"resolved by dt = {sc.dt:g} s (needs dt <= "
                f"{1.0 / (STEPS_PER_CONTACT_PERIOD * est.frequency):.2g} s): the force "
                "chatters and the loss of contact is the step's")
    return warnings


def unsettled_contacts(times, m: int) -> list[str]:
    """The warning of a run whose contact active set gave up in some steps (``times``: their
    ends) over ``m`` contacts; none if it always settled."""
    if not times:
        return []
    return [f"the penalty contact's active set did not settle in {len(times)} step(s) "
            f"(first at t = {times[0]:.6g} s): the set of pantographs in contact still changed "
            f"after {max_passes(m)} passes and those steps keep the last pass's forces; a "
            "smaller dt may settle it"]


def _massless_contact_point(who: str, est: Estimate) -> str:
    return (f"{who}: a rigid contact on a catenary whose contact point moves without mass "
            f"(an instantaneous compliance of {est.compliance:.3g} m/N: the modal model's "
            "static correction): the loss of contact is that truncated model's, which grows "
            "with the contact's stiffness and with a shrinking dt, not the line's; the linear "
            "or nonlinear catenary tells it")


def run_lengths(flags: np.ndarray) -> np.ndarray:
    """The lengths of the runs of True in ``flags``."""
    edges = np.diff(np.concatenate([[0], flags.astype(np.int8), [0]]))
    return np.flatnonzero(edges == -1) - np.flatnonzero(edges == 1)


def step_separations(prep, window_forces) -> list[str]:
    """Warnings of a rigid contact (compliance 0) whose loss of contact in the analysis
    window (``window_forces``: each pantograph's raw force there) comes from separations of
    at most :data:`UNRESOLVED_SEPARATION_STEPS` steps: a separation the step does not
    resolve lasts the same steps at any dt, so that part of the loss of contact is the
    step's."""
    if prep.contact.compliance != 0.0:
        return []
    out = []
    many = len(prep.pantographs) > 1
    for k, force in enumerate(window_forces, start=1):
        runs = run_lengths(np.asarray(force) <= 0.0)
        short = runs[runs <= UNRESOLVED_SEPARATION_STEPS]
        if short.size == 0:
            continue
        who = f"pantograph {k}" if many else "the pantograph"
        share, total = (100.0 * n / max(len(force), 1) for n in (short.sum(), runs.sum()))
        out.append(f"{who}: {share:.2f} % of its {total:.2f} % loss of contact are "
                   f"{short.size} separation(s) of the rigid contact lasting at most "
                   f"{int(short.max())} step(s) of dt = {prep.scenario.dt:g} s: a separation "
                   "that short is the step's, not the line's (it keeps its number of steps "
                   "as dt shrinks); halve dt to tell")
    return out


def departures(prep, statistics) -> list[str]:
    """Warnings of a finished run whose statistics (one
    :class:`~pantocosim.master.results.statistics.ContactStatistics` per pantograph) depart grossly
    from what its static start sets: a mean contact force off the mean uplift by more than
    :data:`MEAN_DEPARTURE` of it, or a loss of contact above the normal law of the run's mean
    and standard deviation by more than :data:`LOSS_EXCESS_POINTS`."""
    from scipy.special import ndtr

    out = []
    many = len(prep.pantographs) > 1
    for k, (pan, st) in enumerate(zip(prep.pantographs, statistics)):
        who = f"pantograph {k + 1}" if many else "the pantograph"
        target = float(pan.options.mean_uplift)
        doubt = "the numbers are doubtful; check against --coupling implicit or monolithic"
        if abs(st.mean_n - target) > MEAN_DEPARTURE * abs(target):
            out.append(f"{who}: mean contact force {st.mean_n:.1f} N departs from the "
                       f"{target:.1f} N mean uplift its static start sets (by more than "
                       f"{100 * MEAN_DEPARTURE:.0f} %): {doubt}")
        expected = 100.0 * float(ndtr(-st.mean_n / st.std_n)) if st.std_n > 0 else 0.0
        if st.loss_of_contact_percent > expected + LOSS_EXCESS_POINTS:
            out.append(f"{who}: loss of contact {st.loss_of_contact_percent:.1f} % where its "
                       f"force statistics (mean {st.mean_n:.1f} N, standard deviation "
                       f"{st.std_n:.1f} N) predict {expected:.1f} % (normal law): the force "
                       f"alternates faster than its statistics resolve; {doubt}")
    return out


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

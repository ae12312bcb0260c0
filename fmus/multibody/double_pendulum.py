"""The spatial double pendulum with impacts of the pendulum paper ("Resultados y discusion",
Fig. 2b).

Two bars of 1 m, 10 director-beam elements each (paper numbering: node 1 is the ground,
bar 1 = nodes 2-12, bar 2 = nodes 13-23). Bar 1 hangs from the ground by a revolute joint
about Z at node 2 (the paper's "rotula", which keeps its first element in the XY plane); a
universal joint joins node 12 (bar 1) to node 13 (bar 2); node 23 strikes the ground plane
y = -1.8 m through the penalty-damper contact of the pendulum paper, eq. 17. Gravity is -Y.

The data are in ``data/double_pendulum.toml`` (:func:`load_spec`). Where the paper is silent,
inconsistent or illegible:

- mass: the paper gives "m1 = m2 = 1 kg" beside a density of 7800 kg/m3 and a section of
  9e-4 m2, which make 7.02 kg per bar. ``bars.mass = "density"`` takes the density;
  a number sets the bar mass and the density becomes mass / (A L);
- Ix = Iy = 8.3e-8 m4 are the bending inertias, Iz = 4.15e-8 m4 the torsion constant J;
- initial configuration (the paper's figure is not legible): bar 1 horizontal along +X,
  bar 2 from (1, 0, 0) leaning 30 degrees out of the XY plane, direction (cos 30, 0, sin 30),
  at rest; the universal joint's cross axes are Z in bar 1 and Y in bar 2;
- the torque pulse (Fig. 2a, "tipo funcion delta"; its axis shows 0.02 s and a peak read as
  200 or 2000 N m): about -Z on node 2, ``pulse.shape`` "triangular" (0 -> peak at
  duration/2 -> 0) or "rectangular" (peak from 0 to duration), ``pulse.peak``,
  ``pulse.duration``;
- contact: k = 1e6 N/m, c = 100 N s/m, the same in every case as in the paper.

The default reading, a rectangular pulse of 200 N m over 0.02 s on bars of 7.02 kg (density),
is the one of eight (peak 200 or 2000 N m, triangular or rectangular, 7.02 or 1 kg) closest
to the paper's out-of-plane maxima of node 12 among those whose node 23 strikes the ground in
every case: within a factor 2.17 of all three (docs/pendulum.md, scripts/pendulum_readings.py).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from pantocosim.core.hht import FactorReuse, HHTIntegrator, HHTSettings

from ..core.errors import ConvergenceError, ParameterError
from ..core.hht import DEFAULT_ALPHA
from ..core.params import Table, check_number, load_toml
from .beam3d import Section, straight_beam
from .ground_contact import GroundContact
from .joints import Revolute, Universal
from .loads import Gravity, NodalMoment, triangular_pulse
from .system import System

#: the three cases of the pendulum paper: Young's modulus (Pa) and the paper's maximum out-of-plane
#: displacement of node 12 (m)
CASES = {"rigid": (2.1e15, 9e-7), "steel": (2.1e11, 0.025), "soft": (2.1e10, 0.08)}

#: the pendulum's data (the default reading of the paper)
DATA_FILE = Path(__file__).resolve().parent / "data" / "double_pendulum.toml"


def rectangular_pulse(peak: float, duration: float, axis=(0.0, 0.0, 1.0)):
    """m(t) = peak * axis for 0 <= t < duration, 0 otherwise (impulse peak * duration)."""
    axis = np.asarray(axis, dtype=float)

    def m(t):
        return peak * axis if 0.0 <= t < duration else 0.0 * axis

    return m


#: pulse shape name -> m(peak, duration, axis) (a function of t)
PULSE_SHAPES = {"triangular": triangular_pulse, "rectangular": rectangular_pulse}


@dataclass
class PendulumSpec:
    E: float = 2.1e11
    n_elements: int = 10
    length: float = 1.0
    rho: float = 7800.0
    area: float = 9e-4
    I_bending: float = 8.3e-8
    J_torsion: float = 4.15e-8
    nu: float = 0.3
    lean_deg: float = 30.0
    ground: float = -1.8
    contact_stiffness: float = 1.0e6
    contact_damping: float = 100.0
    pulse_shape: str = "rectangular"
    pulse_peak: float = 200.0
    pulse_duration: float = 0.02
    #: mass of each bar (kg); None: rho * area * length
    bar_mass: float | None = None
    gravity: float = 9.81

    def __post_init__(self):
        if self.pulse_shape not in PULSE_SHAPES:
            raise ParameterError("pulse.shape", self.pulse_shape,
                                 f"must be one of {sorted(PULSE_SHAPES)}")
        if self.bar_mass is not None:
            check_number("bars.mass", self.bar_mass, positive=True)

    @property
    def mass_density(self) -> float:
        """The density the beam elements take (kg/m3): rho, or bar_mass / (A L)."""
        if self.bar_mass is None:
            return self.rho
        return self.bar_mass / (self.area * self.length)

    @property
    def mass(self) -> float:
        """Mass of one bar (kg)."""
        return self.mass_density * self.area * self.length

    def reading(self) -> str:
        """The reading of the illegible data, e.g. 'triangular 200 N m, 7.02 kg'."""
        return f"{self.pulse_shape} {self.pulse_peak:g} N m, {self.mass:.3g} kg"


def load_spec(path: str | Path | None = None, **overrides) -> PendulumSpec:
    """The :class:`PendulumSpec` of a data file (default :data:`DATA_FILE`), every field
    checked (unknown fields, types, signs and the pulse shape are errors naming the file and
    the field); ``overrides`` (PendulumSpec field names) replace the file's values."""
    p = Path(path) if path is not None else DATA_FILE
    t = Table(load_toml(p), source=p.name)
    t.unknown_keys(["bars", "pulse", "start", "ground", "gravity"])
    bars, pulse, start, ground, grav = (t.sub(k) for k in ("bars", "pulse", "start",
                                                             "ground", "gravity"))
    bars.unknown_keys(["length", "elements", "density", "area", "I_bending", "J_torsion",
                       "nu", "mass"])
    pulse.unknown_keys(["shape", "peak", "duration"])
    start.unknown_keys(["lean_deg"])
    ground.unknown_keys(["y", "stiffness", "damping"])
    grav.unknown_keys(["g"])
    if not bars.has("mass"):
        raise ParameterError("bars.mass", None, "missing field", p.name)
    mass = bars.data["mass"]
    if isinstance(mass, str):
        if mass != "density":
            raise ParameterError("bars.mass", mass, 'must be "density" or a mass in kg > 0',
                                 p.name)
        bar_mass = None
    else:
        bar_mass = bars.number("mass", positive=True)
    spec = dict(
        length=bars.number("length", positive=True),
        n_elements=bars.integer("elements", minimum=1),
        rho=bars.number("density", positive=True),
        area=bars.number("area", positive=True),
        I_bending=bars.number("I_bending", positive=True),
        J_torsion=bars.number("J_torsion", positive=True),
        nu=bars.number("nu", minimum=0.0, maximum=0.5),
        bar_mass=bar_mass,
        pulse_shape=pulse.string("shape", choices=PULSE_SHAPES),
        pulse_peak=pulse.number("peak"),
        pulse_duration=pulse.number("duration", positive=True),
        lean_deg=start.number("lean_deg", minimum=-90.0, maximum=90.0),
        ground=ground.number("y", maximum=0.0),
        contact_stiffness=ground.number("stiffness", positive=True),
        contact_damping=ground.number("damping", nonnegative=True),
        gravity=grav.number("g", nonnegative=True),
    )
    unknown = set(overrides) - set(PendulumSpec.__dataclass_fields__)
    if unknown:
        raise ParameterError(sorted(unknown)[0], overrides[sorted(unknown)[0]],
                             "not a field of the pendulum")
    spec.update(overrides)
    return PendulumSpec(**spec)


@dataclass
class DoublePendulum:
    system: System
    bar1: object
    bar2: object
    contact: GroundContact
    pulse: NodalMoment
    spec: PendulumSpec = field(default_factory=PendulumSpec)

    def node(self, paper_number: int) -> int:
        """System node of the paper's node number (2..23; with other than 10 elements per
        bar, the node at the same place along the bar)."""
        n = self.spec.n_elements
        if 2 <= paper_number <= 12:
            return int(self.bar1.nodes[round((paper_number - 2) * n / 10)])
        if 13 <= paper_number <= 23:
            return int(self.bar2.nodes[round((paper_number - 13) * n / 10)])
        raise ValueError(f"no node {paper_number} (bars: 2-12, 13-23)")


def build(spec: PendulumSpec | None = None, constraint_scale: float | None = None):
    spec = spec or PendulumSpec()
    sec = Section(E=spec.E, A=spec.area, I1=spec.I_bending, I2=spec.I_bending,
                  J=spec.J_torsion, rho=spec.mass_density, nu=spec.nu)
    # balance the constraint rows with the bending stiffness of an element
    scale = constraint_scale or spec.E * spec.I_bending * spec.n_elements / spec.length
    s = System(constraint_scale=scale)
    L = spec.length
    lean = np.radians(spec.lean_deg)
    tip1 = np.array([L, 0.0, 0.0])
    t2 = np.array([np.cos(lean), 0.0, np.sin(lean)])
    bar1 = straight_beam(s, [0.0, 0.0, 0.0], tip1, spec.n_elements, sec, d1=[0, 0, 1],
                         name="bar 1")
    bar2 = straight_beam(s, tip1, tip1 + L * t2, spec.n_elements, sec, d1=[0, 1, 0],
                         name="bar 2")
    s.add(Revolute(bar1.nodes[0], axis=[0.0, 0.0, 1.0]))
    s.add(Universal(bar1.nodes[-1], bar2.nodes[0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]))
    s.add(Gravity([0.0, -spec.gravity, 0.0]))
    moment = PULSE_SHAPES[spec.pulse_shape](spec.pulse_peak, spec.pulse_duration,
                                            [0.0, 0.0, -1.0])
    pulse = s.add(NodalMoment(bar1.nodes[0], moment, "pulse"))
    contact = s.add(GroundContact(bar2.nodes[-1], normal=[0.0, 1.0, 0.0], offset=spec.ground,
                                  stiffness=spec.contact_stiffness,
                                  damping=spec.contact_damping))
    s.assemble()
    return DoublePendulum(s, bar1, bar2, contact, pulse, spec)


@dataclass
class Run:
    t: np.ndarray
    positions: dict            # paper node number -> (n, 3)
    velocities: dict
    accelerations: dict        # the HHT accelerations of the node
    rotations: dict            # rotation vector of the node's triad from its reference
    energy: dict               # name -> (n,) time series
    drift: np.ndarray          # max |g| per step
    iterations: np.ndarray


def rotation_vector(R, previous=None) -> np.ndarray:
    """The rotation vector phi = theta u of R (the pendulum paper, eq. 1), the one of the family
    (theta + 2 pi k) u nearest ``previous``: continuous through theta = pi and over
    several turns."""
    phi = Rotation.from_matrix(R).as_rotvec()
    theta = np.linalg.norm(phi)
    if previous is None or np.linalg.norm(previous) < 1e-12:
        return phi
    # near the identity any axis will do: keep the previous one
    u = phi / theta if theta > 1e-12 else previous / np.linalg.norm(previous)
    k = np.round((u @ previous - theta) / (2.0 * np.pi))
    return (theta + 2.0 * np.pi * k) * u


def simulate(model, t_end: float, h, alpha: float = DEFAULT_ALPHA, nodes=(12, 23),
             rtol: float = 1e-8, progress=None) -> Run:
    """Integrate with the project's HHT-alpha integrator and keep the histories of
    ``nodes`` (paper numbering: position, velocity, acceleration, rotation vector) and the
    energy account:

        E = kinetic + strain + gravity + contact (elastic),
        W = work of the pulse, D = contact dissipation (both by the trapezoidal rule),
        HHT dissipation = E(0) + W - D - E(t).

    ``h`` is the step size, or a function of t giving it (e.g. finer steps through an
    impact)."""
    s = model.system
    q, v, a = s.consistent_start(0.0, s.reference())
    # one factorization per step (chord iterations): the same solution as full Newton to
    # 1e-11 m through an impact, at less than half the cost
    integ = HHTIntegrator(s, HHTSettings(alpha=alpha, rtol=rtol, max_iterations=40,
                                         reuse_factorization=FactorReuse.PER_STEP))
    integ.initialize(0.0, q, v, a0=a)
    step_size = h if callable(h) else (lambda t: h)
    times = [0.0]
    while times[-1] < t_end - 1e-12:
        times.append(min(times[-1] + step_size(times[-1]), t_end))
    n_steps = len(times) - 1
    ids = {k: model.node(k) for k in nodes}
    T = np.zeros(n_steps + 1)
    pos, vel, acc, rot = ({k: np.zeros((n_steps + 1, 3)) for k in nodes} for _ in range(4))
    keys = ["kinetic", "strain", "gravity", "contact"]
    en = {k: np.zeros(n_steps + 1) for k in keys + ["pulse_work", "contact_dissipation"]}
    drift = np.zeros(n_steps + 1)
    its = np.zeros(n_steps + 1, dtype=int)

    def record(i, t, q, v, a, p_prev):
        T[i] = t
        for k, nid in ids.items():
            pos[k][i] = s.position(q, nid)
            vel[k][i] = s.position(v, nid)
            acc[k][i] = s.position(a, nid)
            rot[k][i] = rotation_vector(s.triad(q, nid) @ s.R0[nid].T,
                                        rot[k][i - 1] if i else None)
        e = s.energies(t, q, v)
        for k in keys:
            en[k][i] = e.get(k, 0.0)
        p = (model.pulse.powers(t, q, v)["external"], model.contact.powers(t, q, v)["dissipation"])
        if i > 0:
            dt = t - T[i - 1]
            en["pulse_work"][i] = en["pulse_work"][i - 1] + 0.5 * dt * (p[0] + p_prev[0])
            en["contact_dissipation"][i] = (en["contact_dissipation"][i - 1]
                                            + 0.5 * dt * (p[1] + p_prev[1]))
        drift[i] = s.constraint_drift(q)
        return p

    p = record(0, 0.0, integ.q, integ.v, integ.a, None)
    for i in range(1, n_steps + 1):
        info = integ.step(times[i] - times[i - 1])
        its[i] = info.iterations
        p = record(i, integ.t, integ.q, integ.v, integ.a, p)
        if progress is not None:
            progress(i, n_steps)
    total = en["kinetic"] + en["strain"] + en["gravity"] + en["contact"]
    en["total"] = total
    en["hht_dissipation"] = total[0] + en["pulse_work"] - en["contact_dissipation"] - total
    return Run(T, pos, vel, acc, rot, en, drift, its)


def simulate_case(spec: PendulumSpec, t_end: float, h: float, alpha: float = DEFAULT_ALPHA,
                  nodes=(12, 23), divisors=(1, 2, 4), progress=None):
    """Build and :func:`simulate` ``spec`` with the step ``h``; a run that fails (a beam
    element turning by 90 degrees within a step, or Newton) is run again with the step
    ``h / d`` for the next divisor d. Returns (model, run, step used); the last failure is
    raised as a :class:`ConvergenceError` naming the steps tried.

    The rectangular pulse's jumps at 0 and at its end and the fast bars of a large pulse
    need such shorter steps: the rigid case of the rectangular 200 N m pulse runs at h / 2."""
    errors = []
    for d in divisors:
        model = build(spec)
        try:
            return model, simulate(model, t_end, h / d, alpha=alpha, nodes=nodes,
                                   progress=progress), h / d
        except (FloatingPointError, ConvergenceError) as exc:
            errors.append(f"h = {h / d:g} s: {exc}")
    raise ConvergenceError("; ".join(errors))

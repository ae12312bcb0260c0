"""The mean operating height of each pantograph: where its actuation is set to deliver the
mean uplift (static + aerodynamic).

A pantograph's pneumatic actuation is regulated so that it presses with the target mean force
at its operating height. With a stiff mechanism (the rigid DSA-380 has about 2 kN/m at the
head) that height must be the mean height of the contact wire under the moving pantograph,
which a moving load lifts more than a static one. It is computed here from the catenary
linearised about its static configuration (M, C = alpha M + beta K0, K0) under the constant
mean forces moving at the train speed, integrated with HHT-alpha steps in closed form
(:mod:`pantocosim.core.affine_hht`: one banded factorization for the whole run, one solve a
step), and averaged over the analysis window.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pantocosim.catenary.linear_droppers import LinearDroppers
from pantocosim.core.affine_hht import AffineForm
from pantocosim.core.banded import BandedCholesky
from pantocosim.core.disk_cache import cached
from pantocosim.core.errors import ConvergenceError
from pantocosim.core.hht import DEFAULT_ALPHA, HHTSettings
from pantocosim.core.lowrank import ColumnCache
from pantocosim.core.structure_stepping import stepper_under_inputs


class LinearisedCatenary:
    """M a + C v + K0 (q - q_static) = sum_k N_k(t)^T F_k: the catenary linearised about its
    static configuration with every dropper taut (C = alpha M + beta K0, (3.1); K0 the tangent
    (3.5)), as an :class:`~pantocosim.core.affine_hht.AffineForm` whose HHT steps are taken in
    closed form (one kept banded factorization, one solve a step)."""

    #: stepped in closed form on :meth:`affine_form` (:mod:`pantocosim.core.stepper_contract`)
    stepping = "affine"

    def __init__(self, catenary):
        self.cat = catenary
        self.n_dofs = catenary.n_dofs
        self.speed = catenary.speed
        #: the moving load points: the catenary's contact points
        self.contact_points = catenary.contact_points
        st = catenary.structure
        self.M = catenary.M
        self.K0 = st.csr(catenary.K0_data)
        self.C = st.csr(catenary._C_base)
        self.q_static = catenary.q_static
        self._factors: dict = {}

    def _factor(self, c_a: float, c_v: float, c_f: float):
        """The kept banded Cholesky factor of c_a M + c_f (c_v C + K0)."""
        key = (c_a, c_v, c_f)
        if key not in self._factors:
            data = c_a * self.M.data + c_f * (c_v * self.C.data + self.K0.data)
            chol = BandedCholesky.factor(self.cat.structure.lower_band(data))
            if chol is None:
                raise ConvergenceError(f"linearised catenary: HHT matrix {key} is not "
                                       "positive definite")
            self._factors[key] = ColumnCache(chol, self._taut.vectors)
        return self._factors[key]

    def _forces(self, t, q, v, F) -> np.ndarray:
        """f_rest = C v + K0 (q - q_static) - sum_k N_k^T F_k."""
        return self.C @ v + self.K0 @ (q - self.q_static) - self.cat.input_vector(t, F)

    def affine_form(self):
        """The model as an AffineForm: no unilateral elements (every dropper stays in K0)."""
        cat, st = self.cat, self.cat.structure
        self._taut = LinearDroppers(st, np.zeros(0, np.int64), cat.x_static, cat.beta_r)
        return AffineForm(n=self.n_dofs, M_band=st.lower_band(st.M_data),
                          K_band=st.lower_band(cat.K0_data), alpha_r=cat.alpha_r,
                          beta_r=cat.beta_r, q_ref=self.q_static, r0=np.zeros(self.n_dofs),
                          unilateral=self._taut, factor=self._factor, forces=self._forces)


def mean_dynamic_wire_height(catenary, forces, window: tuple[float, float], dt: float,
                             duration: float, alpha: float = DEFAULT_ALPHA) -> np.ndarray:
    """Mean contact-wire height under each moving constant force over the window [m]; kept
    in the set-up cache (:mod:`pantocosim.core.disk_cache`) under the linearised model's
    matrices, its static configuration, the moving points and every argument."""
    model = LinearisedCatenary(catenary)
    forces = np.asarray(forces, dtype=float)
    parts = (type(catenary).__name__, model.M, model.K0, model.C, model.q_static,
             catenary.positions(0.0), catenary.positions(1.0), forces,
             tuple(map(float, window)), float(dt), float(duration), float(alpha))
    return cached("mean-wire-height", parts, lambda: {"z": _moving_load_run(
        catenary, model, forces, window, dt, duration, alpha)})["z"]


def _moving_load_run(catenary, model, forces, window, dt, duration, alpha) -> np.ndarray:
    """:func:`mean_dynamic_wire_height` computed: the HHT-alpha run of the linearised model
    under the moving forces (its declared stepper,
    :func:`~pantocosim.core.structure_stepping.stepper_under_inputs`)."""
    q0 = catenary.static_state(forces)  # start from the static deflection: short transient
    integ = stepper_under_inputs(model, HHTSettings(alpha=alpha))
    integ.initialize(0.0, q0, np.zeros(model.n_dofs), forces)
    n = len(forces)
    total = np.zeros(n)
    count = np.zeros(n)
    for _ in range(law_run_steps(duration, dt)):
        integ.step(dt, forces)
        x = catenary.positions(integ.t)
        inside = (x >= window[0]) & (x <= window[1])
        if inside.any():
            z = catenary.wire_height(integ.t, integ.q)
            total[inside] += z[inside]
            count[inside] += 1
    if np.any(count == 0):
        raise ValueError("a pantograph never enters the analysis window")
    return total / count


#: time after the last pantograph leaves the analysis window until a run ends [s]
RUN_TAIL_S = 0.2


def passage_duration(window_end: float, positions, speed: float) -> float:
    """Duration of a run by default: until the last pantograph leaves the analysis window,
    plus :data:`RUN_TAIL_S`."""
    return max((window_end - float(x)) / speed for x in positions) + RUN_TAIL_S


#: most HHT steps of one moving-load run behind the start laws (about 20 times the run of
#: the en50318 line at 250 km/h with 1 ms steps; a minute or two on one core)
MAX_LAW_STEPS = 200_000


def law_run_steps(duration: float, dt: float) -> int:
    """The steps of one moving-load run of :func:`mean_dynamic_wire_height`."""
    return int(np.ceil(duration / dt - 1e-9))


#: contact forces [N] between which the start laws below are secants (the range of mean and
#: static contact forces of the project's pantographs)
LAW_FORCES = (100.0, 200.0)


@dataclass(frozen=True)
class ContactHeightLaws:
    """What the catenary tells a pantograph about its start, per pantograph, as contact
    heights h(F) = offset + slope F (slope includes the penalty compliance 1/k_H):

    - ``operating``: the pantograph's operating height under a mean uplift F (the mean
      dynamic wire height of :func:`mean_dynamic_wire_height` + F / k_H), where its actuation
      is set to deliver F;
    - ``static``: its contact height at t0 when it presses with a static force F at its start
      position (the static wire height under F + F / k_H).

    Both are secants through :data:`LAW_FORCES` of laws that are linear up to the catenary's
    geometric nonlinearity."""

    operating_offset: np.ndarray
    operating_slope: np.ndarray
    static_offset: np.ndarray
    static_slope: np.ndarray


def mean_dynamic_height_law(catenary, k: int, window: tuple[float, float], dt: float,
                            duration: float, alpha: float = DEFAULT_ALPHA) -> tuple[float, float]:
    """(offset, slope): the mean dynamic wire height of :func:`mean_dynamic_wire_height` under
    pantograph ``k``'s constant force F alone is offset + slope F (secant through
    :data:`LAW_FORCES`: the runs start from the nonlinear static state, as the monolithic
    start's does)."""
    f1, f2 = LAW_FORCES
    forces = np.zeros(len(catenary.x0))
    z = []
    for f in (f1, f2):
        forces[k] = f
        z.append(mean_dynamic_wire_height(catenary, forces, window, dt, duration, alpha)[k])
    slope = (z[1] - z[0]) / (f2 - f1)
    return z[0] - slope * f1, slope


def static_height_law(catenary, k: int) -> tuple[float, float]:
    """(offset, slope): the static contact-wire height at pantograph ``k``'s start position
    under its upward force F alone is offset + slope F (secant through :data:`LAW_FORCES`)."""
    f1, f2 = LAW_FORCES
    forces = np.zeros(len(catenary.x0))
    z = []
    for f in (f1, f2):
        forces[k] = f
        z.append(catenary.wire_height(0.0, catenary.static_state(forces))[k])
    slope = (z[1] - z[0]) / (f2 - f1)
    return z[0] - slope * f1, slope


def contact_height_laws(catenary, contact_stiffness: float, window: tuple[float, float],
                        dt: float, duration: float, alpha: float = DEFAULT_ALPHA
                        ) -> ContactHeightLaws:
    """The start laws of every pantograph of ``catenary`` (a CatenaryModel); each force acts
    alone (the cross terms of several pantographs are left out). A standing train (speed 0)
    has no moving-load run: a force that does not move leaves the wire at its static
    deflection, so its operating law is its static law."""
    n = len(catenary.x0)
    st = np.array([static_height_law(catenary, k) for k in range(n)])
    if catenary.speed == 0.0:
        op = st
    else:
        op = np.array([mean_dynamic_height_law(catenary, k, window, dt, duration, alpha)
                       for k in range(n)])
    compliance = 1.0 / contact_stiffness
    return ContactHeightLaws(operating_offset=op[:, 0], operating_slope=op[:, 1] + compliance,
                             static_offset=st[:, 0], static_slope=st[:, 1] + compliance)

"""The monolithic step of a linear structure and small bodies in penalty contact, condensed
on the contact points (exact: the structure is affine in the contact forces).

For a structure stepped by :class:`~.affine_hht.AffineHHT`, the contact-wire height and
velocity at contact k at t_{n+1} are affine in the contact forces F (3.13):

    z_w = z_free + G F,    v_w = v_free + H F,
    G_kj = n_k . w_j,      H_kj = c_v n_k . w_j + V n'_k . w_j   (V n' the convective term),

so the coupled HHT step of (3.16) reduces to the bodies' coordinates with the penalty law
(3.9)-(3.10) solved with the structure's compliance (:class:`InterfaceContacts`, a small
:class:`~.model.SecondOrderModel` stepped by the one HHT integrator); the structure then takes
the step with the converged forces. The result is the monolithic Newton-Raphson solution of
the assembled system (:mod:`.coupled`) to the Newton tolerance.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
from numba import njit

from ..core.hht import HHTIntegrator
from ..core.model import Evaluation, SecondOrderModel
from ..core.stepper_contract import StepReport, ClosedFormStep
from .penalty_contact import condensed_forces


@njit(cache=True)
def _point_free(dofs, w, dw, q_p, v_p, delta_free, c_v):
    """(w . q, w . v, dw . q) at the free response q = q_p + delta_free,
    v = v_p + c_v delta_free."""
    z = 0.0
    v = 0.0
    slope = 0.0
    for i in range(dofs.shape[0]):
        j = dofs[i]
        qj = q_p[j] + delta_free[j]
        z += w[i] * qj
        v += w[i] * (v_p[j] + c_v * delta_free[j])
        slope += dw[i] * qj
    return z, v, slope


@njit(cache=True)
def _point_response(dofs, w, dw, x):
    """(w . x[dofs], dw . x[dofs])."""
    g = 0.0
    h = 0.0
    for i in range(dofs.shape[0]):
        xj = x[dofs[i]]
        g += w[i] * xj
        h += dw[i] * xj
    return g, h


@njit(cache=True)
def _bodies_on_interface(k, c, x, zf, vf, P, Pv, work, active, trial, A, F, heights, wire):
    """The penalty law (:func:`~.penalty_contact.condensed_forces`) between bodies whose
    contact heights are z_f + P F, v_f + P_v F and the interface x = [z0, v0, G, H] (flat),
    into F; then the bodies' heights and the wire's, z0 + G F. ``work``: 2 m + 2 m^2.
    Returns whether the law's active set settled."""
    m = zf.shape[0]
    dz, dv = work[:m], work[m:2 * m]
    Ge = work[2 * m:2 * m + m * m].reshape((m, m))
    He = work[2 * m + m * m:2 * m + 2 * m * m].reshape((m, m))
    for i in range(m):
        dz[i] = zf[i] - x[i]
        dv[i] = vf[i] - x[m + i]
        for j in range(m):
            Ge[i, j] = x[2 * m + i * m + j]
            He[i, j] = x[2 * m + m * m + i * m + j]
        Ge[i, i] -= P[i]
        He[i, i] -= Pv[i]
    settled = condensed_forces(k, c, dz, dv, Ge, He, active, trial, A, F)
    for i in range(m):
        heights[i] = zf[i] + P[i] * F[i]
        acc = x[i]
        for j in range(m):
            acc += x[2 * m + i * m + j] * F[j]
        wire[i] = acc
    return settled


class InterfaceContacts(SecondOrderModel):
    """Bodies (pantographs) in penalty contact with a structure condensed on the contact
    points. ``inputs`` of a step: [z_free (m), v_free (m), G (m x m), H (m x m)] flat."""

    def __init__(self, bodies: Sequence, contact):
        self.bodies = list(bodies)
        self.contact = contact
        sizes = [b.n_dofs for b in self.bodies]
        self.offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(int)
        self.n_dofs = int(self.offsets[-1])
        self.m = len(self.bodies)
        self.forces = np.zeros(self.m)
        self.heights = np.zeros(self.m)
        self.wire_heights = np.zeros(self.m)
        #: the last evaluation's active set settled
        #: (:meth:`.penalty_contact.PenaltyContact.condensed`)
        self.settled = True
        self._zero = np.zeros(1)

    def split(self, x):
        return [x[self.offsets[k]:self.offsets[k + 1]] for k in range(self.m)]

    def unpack(self, inputs):
        m = self.m
        z0, v0 = inputs[:m], inputs[m:2 * m]
        G = inputs[2 * m:2 * m + m * m].reshape(m, m)
        H = inputs[2 * m + m * m:].reshape(m, m)
        return z0, v0, G, H

    def evaluate(self, t, q, v, a, inputs, tangent=True):
        qs, vs, as_ = self.split(q), self.split(v), self.split(a)
        evs = [b.evaluate(t, qs[k], vs[k], as_[k], self._zero, tangent=tangent)
               for k, b in enumerate(self.bodies)]
        g = [np.asarray(b.contact_height_gradient(qs[k]), dtype=float)
             for k, b in enumerate(self.bodies)]
        z_p = np.array([b.contact_height(qs[k]) for k, b in enumerate(self.bodies)])
        v_p = np.array([b.contact_velocity(qs[k], vs[k]) for k, b in enumerate(self.bodies)])
        z0, v0, G, H = self.unpack(inputs)
        F, Jz, Jv, self.settled = self.contact.condensed(z_p, v_p, z0, v0, G, H)
        f_in = np.concatenate([e.f_inertia for e in evs])
        f_rest = np.concatenate([e.f_rest for e in evs])
        for k in range(self.m):
            o = self.offsets[k]
            f_rest[o:o + g[k].size] += F[k] * g[k]
        self.forces[:] = F
        self.heights[:] = z_p
        self.wire_heights[:] = z0 + G @ F
        ev = Evaluation(f_inertia=f_in, f_rest=f_rest,
                        structure_key=(tuple(e.structure_key for e in evs), tuple(F > 0.0)))
        ev.parts = (evs, g, Jz, Jv)
        return ev

    def effective_matrix(self, ev, c_a, c_v, c_f):
        """Block-diagonal bodies' Newton matrices plus the condensed contact's
        c_f (g_k (Jz_kj + c_v Jv_kj) g_j^T)."""
        evs, g, Jz, Jv = ev.parts
        S = np.zeros((self.n_dofs, self.n_dofs))
        o = self.offsets
        for k, (b, e) in enumerate(zip(self.bodies, evs)):
            S[o[k]:o[k + 1], o[k]:o[k + 1]] = np.asarray(b.effective_matrix(e, c_a, c_v, c_f))
        J = c_f * (Jz + c_v * Jv)
        for k in range(self.m):
            for j in range(self.m):
                if J[k, j] != 0.0:
                    S[o[k]:o[k] + g[k].size, o[j]:o[j] + g[j].size] += J[k, j] * np.outer(
                        g[k], g[j])
        return S

    def commit(self, t, q, v, a, inputs):
        for k, (b, qk, vk, ak) in enumerate(zip(self.bodies, self.split(q), self.split(v),
                                                self.split(a))):
            b.commit(t, qk, vk, ak, None)

    def get_internal_state(self):
        return [b.get_internal_state() for b in self.bodies]

    def set_internal_state(self, state):
        if state is not None:
            for b, s in zip(self.bodies, state):
                b.set_internal_state(s)


class NewtonBodies:
    """Bodies and condensed contacts stepped by Newton-Raphson (:class:`InterfaceContacts`
    under the one HHT integrator): any body model."""

    def __init__(self, bodies, contact, settings):
        self.contacts = InterfaceContacts(bodies, contact)
        self.integ = HHTIntegrator(self.contacts, settings)
        self._saved = None

    def initialize(self, t0, q_bodies, x0) -> np.ndarray:
        q = np.concatenate([np.asarray(x, float) for x in q_bodies])
        self.integ.initialize(t0, q, None, x0.copy())
        zero = np.zeros_like(q)
        self.contacts.evaluate(t0, q, zero, zero, x0, tangent=False)
        return self.contacts.forces.copy()

    def begin(self) -> None:
        self._saved = None

    @property
    def q(self) -> np.ndarray:
        return self.integ.q

    @property
    def v(self) -> np.ndarray:
        return self.integ.v

    def get_state(self):
        c = self.contacts
        return self.integ.get_state(), [x.copy() for x in (c.forces, c.heights,
                                                            c.wire_heights)]

    def set_state(self, state) -> None:
        self.integ.set_state(state[0])
        for dst, src in zip((self.forces, self.heights, self.wire_heights), state[1]):
            dst[:] = src

    def solve(self, h, x) -> int:
        """Step the bodies against the interface ``x``; the forces, heights and wire heights
        are then in :attr:`forces`, :attr:`heights`, :attr:`wire_heights`."""
        if self._saved is None:
            self._saved = self.integ.get_state()
        else:
            self.integ.set_state(self._saved)
        return self.integ.step(h, x).iterations

    @property
    def settled(self) -> bool:
        """The contacts' active set settled in the last evaluation of the last solve."""
        return self.contacts.settled

    @property
    def forces(self):
        return self.contacts.forces

    @property
    def heights(self):
        return self.contacts.heights

    @property
    def wire_heights(self):
        return self.contacts.wire_heights


class LinearBodies:
    """Bodies with a :class:`~.model.LinearForm` (constant matrices, contact height linear
    in q), each under the closed-form HHT step. A step is affine in the body's contact force,
    so each body takes its step once with a guess (its last force), the penalty law is solved
    on the interface in closed form with the body's compliance z_p = z_pf + P F,
    v_p = v_pf + P_v F, and the step is shifted to the solved force
    (:meth:`~.hht.HHTIntegrator.shift_last_step`): no Newton, no second step."""

    def __init__(self, bodies, contact, settings):
        self.bodies, self.contact = list(bodies), contact
        self.integs = [HHTIntegrator(b, settings) for b in self.bodies]
        if not all(i.closed_form for i in self.integs):
            raise ValueError("LinearBodies needs bodies with a linear form")
        m = len(self.bodies)
        self.forces, self.heights, self.wire_heights = (np.zeros(m) for _ in range(3))
        self._free = np.zeros((4, m))       # z_pf, v_pf, P, P_v of the current step
        self._applied = np.zeros(m)         # the force each body's step was taken with
        self._stepped = False
        #: the contacts' active set settled in the last solve
        self.settled = True
        self._units, self._units_h = None, None
        self._u = np.zeros(1)
        self._work = (np.zeros(2 * m + 2 * m * m), np.zeros(m, dtype=np.bool_),
                      np.zeros(m, dtype=np.bool_), np.zeros((m, m + 1)))

    @staticmethod
    def applicable(bodies) -> bool:
        return all(b.linear_form() is not None for b in bodies)

    def initialize(self, t0, q_bodies, x0) -> np.ndarray:
        m = len(self.bodies)
        z0, v0 = x0[:m], x0[m:2 * m]
        z_p = np.array([b.contact_height(q) for b, q in zip(self.bodies, q_bodies)])
        F = self.contact.condensed(z_p, np.zeros(m), z0, v0, np.zeros((m, m)),
                                   np.zeros((m, m)))[0]
        for integ, q, Fk in zip(self.integs, q_bodies, F):
            integ.initialize(t0, q, None, np.array([Fk]))
        self.forces[:], self.heights[:], self.wire_heights[:] = F, z_p, z0
        return F.copy()

    def _contact(self, k):
        integ, b = self.integs[k], self.bodies[k]
        return b.contact_height(integ.q), b.contact_velocity(integ.q, integ.v)

    def begin(self) -> None:
        self._stepped = False

    @property
    def q(self) -> np.ndarray:
        return np.concatenate([i.q for i in self.integs])

    @property
    def v(self) -> np.ndarray:
        return np.concatenate([i.v for i in self.integs])

    def get_state(self):
        return ([i.get_state() for i in self.integs],
                [x.copy() for x in (self.forces, self.heights, self.wire_heights,
                                    self._applied)])

    def set_state(self, state) -> None:
        for integ, s in zip(self.integs, state[0]):
            integ.set_state(s)
        for dst, src in zip((self.forces, self.heights, self.wire_heights, self._applied),
                            state[1]):
            dst[:] = src
        self._stepped = False

    def _take_steps(self, h) -> None:
        """Each body's step with its last force; its free contact height and compliance."""
        zf, vf, P, Pv = self._free
        if self._units_h != h:               # the response to F is fixed by h
            self._units = [i.input_response(h, np.zeros(1), np.ones(1)) for i in self.integs]
            self._units_h = h
            for k, b in enumerate(self.bodies):
                dq, dv = self._units[k][:2]
                P[k] = b.contact_height(dq) - b.contact_height(np.zeros_like(dq))
                Pv[k] = b.contact_velocity(dq, dv)
        for k, integ in enumerate(self.integs):
            self._u[0] = self._applied[k] = self.forces[k]
            integ.step(h, self._u)
            z, v = self._contact(k)
            zf[k], vf[k] = z - P[k] * self._applied[k], v - Pv[k] * self._applied[k]
        self._stepped = True

    def solve(self, h, x) -> int:
        if not self._stepped:
            self._take_steps(h)
        zf, vf, P, Pv = self._free
        F = self.forces
        self.settled = bool(_bodies_on_interface(
            self.contact.stiffness, self.contact.damping, x, zf, vf, P, Pv, *self._work, F,
            self.heights, self.wire_heights))
        for k, integ in enumerate(self.integs):
            if F[k] != self._applied[k]:
                self._u[0] = F[k]
                integ.shift_last_step(self._units[k], F[k] - self._applied[k], self._u)
                self._applied[k] = F[k]
        return 1


def bodies_solver(bodies, contact, settings):
    """:class:`LinearBodies` when every body has a linear form, else :class:`NewtonBodies`."""
    if settings.closed_form_linear and LinearBodies.applicable(bodies):
        return LinearBodies(bodies, contact, settings)
    return NewtonBodies(bodies, contact, settings)


class CondensedStepper:
    """One HHT-alpha step of structure + bodies + contacts: the structure's free response,
    the bodies' step on the condensed interface, the structure's step with the forces (a
    :class:`~pantocosim.core.stepper_contract.Stepper`; the structure's constant step data
    are those of :attr:`structure`)."""

    #: the bodies' Newton iterations may fail half-way through a step
    closed_form = False

    def __init__(self, structure: ClosedFormStep, points, bodies, contact, settings,
                 speed: float = 0.0):
        #: ``points(t)``: the structure's contact points at t (dofs, weights, offset,
        #: dweights_dx, doffset_dx), one per body
        self.structure, self.points, self.speed = structure, points, float(speed)
        self.bodies = bodies_solver(bodies, contact, settings)
        self._sizes = np.cumsum([b.n_dofs for b in bodies])
        m = len(bodies)
        self.m = m
        self._inputs = np.zeros(2 * m + 2 * m * m)

    @property
    def t(self) -> float:
        return self.structure.t

    @property
    def structure_q(self) -> np.ndarray:
        """The structure's coordinates."""
        return self.structure.q

    @property
    def q(self) -> np.ndarray:
        """[structure | body 1 | ...] (a new array)."""
        return np.concatenate([self.structure.q, self.bodies.q])

    @property
    def v(self) -> np.ndarray:
        """[structure | body 1 | ...] velocities (a new array)."""
        return np.concatenate([self.structure.v, self.bodies.v])

    def contacts(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(contact forces, contact heights, wire heights), one per body."""
        b = self.bodies
        return b.forces, b.heights, b.wire_heights

    def prepare(self, h: float) -> None:
        """The structure's set-up for steps of h."""
        self.structure.prepare(h)

    def initialize(self, t0: float, q0, v0=None, inputs0=None) -> None:
        """Start at rest in the static configuration q0 = [structure | body 1 | ...]."""
        n = len(q0) - int(self._sizes[-1] if len(self._sizes) else 0)
        q_structure = np.asarray(q0[:n], float)
        q_bodies = np.split(np.asarray(q0[n:], float), self._sizes[:-1])
        self._inputs[:] = 0.0
        self._inputs[:self.m] = [cp.weights @ q_structure[cp.dofs] + cp.offset
                                 for cp in self.points(t0)]
        F0 = self.bodies.initialize(t0, q_bodies, self._inputs)
        self.structure.initialize(t0, q_structure, None, F0)

    def interface(self, cps) -> np.ndarray:
        """[z_free, v_free, G, H] of the step begun on the structure."""
        st, m, V = self.structure, self.m, self.speed
        c_v = st.c_v
        x = self._inputs
        G = x[2 * m:2 * m + m * m].reshape(m, m)
        H = x[2 * m + m * m:].reshape(m, m)
        for k, cp in enumerate(cps):
            z, v, slope = _point_free(cp.dofs, cp.weights, cp.dweights_dx, st.q_p, st.v_p,
                                      st.delta_free, c_v)
            x[k] = z + cp.offset
            x[m + k] = v + V * (slope + cp.doffset_dx)
            for j in range(m):
                g, dg = _point_response(cp.dofs, cp.weights, cp.dweights_dx, st.W[j])
                G[k, j] = g
                H[k, j] = c_v * g + V * dg
        return x

    def get_state(self):
        return self.structure.get_state(), self.bodies.get_state(), self._inputs.copy()

    def set_state(self, state) -> None:
        self.structure.set_state(state[0])
        self.bodies.set_state(state[1])
        self._inputs[:] = state[2]

    def step(self, h: float, inputs=None) -> StepReport:
        """Advance structure and bodies by h (no inputs); reports the bodies' Newton
        iterations of the last pass."""
        st = self.structure
        cps = self.points(st.t + h)
        st.begin(h, [(cp.dofs, cp.weights) for cp in cps])
        self.bodies.begin()
        while True:
            iterations = self.bodies.solve(h, self.interface(cps))
            if st.finish(self.bodies.forces):
                return StepReport(iterations=iterations, settled=self.bodies.settled)

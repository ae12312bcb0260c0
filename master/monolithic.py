"""Monolithic pantograph-catenary system: the reference solver (thesis 3.2-3.3).

The catenary and any number of pantographs are assembled into one
:class:`~pantocosim.core.model.SecondOrderModel` coupled by penalty contact elements
(:mod:`pantocosim.master.contact`), and the one HHT-alpha integrator advances it with
Newton-Raphson on all coordinates at once. Contact is lost and recovered through the penalty
law; droppers slacken inside the catenary model.

DOF layout: ``[catenary | pantograph 1 | pantograph 2 | ...]``.

Contact element k (3.9)-(3.13): z_w = N_k(t) . q_c[dofs_k] (Hermite interpolation at the
pantograph's position x_k(t) = x0_k + v t), z_p = h_k(q_p), F = law(z_p - z_w). The force acts
as +F dh/dq_p on the pantograph (down) and -F N_k on the wire (up), and enters f_rest, so it is
weighted by the integrator exactly as a force through an FMU port.
"""

from __future__ import annotations

from typing import Sequence

import numpy as np
import scipy.sparse as sp

from pantocosim.core.model import Evaluation, SecondOrderModel
from pantocosim.master.contact import PenaltyContact
from pantocosim.pantograph.base import PantographModel


class CoupledSystem(SecondOrderModel):
    """Catenary + pantographs + penalty contacts as one second-order system."""

    def __init__(self, catenary, pantographs: Sequence[PantographModel],
                 contact: PenaltyContact):
        self.catenary = catenary
        self.pantographs = list(pantographs)
        self.contact = contact
        self.n_cat = int(catenary.n_dofs)
        sizes = [p.n_dofs for p in self.pantographs]
        self.offsets = np.concatenate([[self.n_cat], self.n_cat + np.cumsum(sizes)]).astype(int)
        self.n_dofs = int(self.offsets[-1])

    # ------------------------------------------------------------------ helpers
    def split(self, x: np.ndarray):
        """(catenary part, [pantograph parts]) views of a global vector."""
        return x[:self.n_cat], [x[self.offsets[k]:self.offsets[k + 1]]
                                for k in range(len(self.pantographs))]

    def contact_state(self, t: float, q: np.ndarray, v: np.ndarray):
        """Per pantograph: (F, z_p, z_w, v_p, v_w, dofs, N, gradient, dF/dgap, dF/dvrel)."""
        qc, qps = self.split(q)
        vc, vps = self.split(v)
        out = []
        offsets = getattr(self.catenary, "contact_offsets", None)
        offsets = offsets(t) if offsets is not None else np.zeros(len(self.pantographs))
        for k, (pant, (dofs, N)) in enumerate(zip(self.pantographs,
                                                  self.catenary.contact_points(t))):
            z_w = float(N @ qc[dofs]) + float(offsets[k])
            v_w = float(N @ vc[dofs])
            g = np.asarray(pant.contact_height_gradient(qps[k]), dtype=float)
            z_p = pant.contact_height(qps[k])
            v_p = float(g @ vps[k])
            F, dF, cF = self.contact.force_and_derivatives(z_p, z_w, v_p, v_w)
            out.append((F, z_p, z_w, v_p, v_w, dofs, N, g, dF, cF))
        return out

    def contact_forces(self, t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        return np.array([c[0] for c in self.contact_state(t, q, v)])

    # ------------------------------------------------------------------ model interface
    def evaluate(self, t, q, v, a, inputs, tangent=True):
        qc, qps = self.split(q)
        vc, vps = self.split(v)
        ac, aps = self.split(a)
        n_p = len(self.pantographs)
        ev_c = self.catenary.evaluate(t, qc, vc, ac, np.zeros(n_p), tangent=tangent)
        ev_p = [p.evaluate(t, qps[k], vps[k], aps[k], np.zeros(1), tangent=tangent)
                for k, p in enumerate(self.pantographs)]
        f_in = np.concatenate([ev_c.f_inertia] + [e.f_inertia for e in ev_p])
        f_rest = np.concatenate([ev_c.f_rest] + [e.f_rest for e in ev_p])
        contacts = self.contact_state(t, q, v)
        rows, cols, kvals, cvals = [], [], [], []
        key = []
        for k, (F, z_p, z_w, v_p, v_w, dofs, N, g, dF, cF) in enumerate(contacts):
            o = self.offsets[k]
            pdofs = np.arange(o, o + g.size)
            f_rest[pdofs] += F * g
            f_rest[dofs] -= F * N
            key.append(F > 0.0)
            if tangent and (dF != 0.0 or cF != 0.0):
                # F depends on u = [q_p, q_c[dofs]] through w = [g, -N]
                idx = np.concatenate([pdofs, dofs])
                w = np.concatenate([g, -N])
                s = np.concatenate([g, -N])  # force direction on [pantograph, wire]
                rows.append(np.repeat(idx, idx.size))
                cols.append(np.tile(idx, idx.size))
                outer = np.outer(s, w).ravel()
                kvals.append(dF * outer)
                cvals.append(cF * outer)
        ev = Evaluation(f_inertia=f_in, f_rest=f_rest,
                        structure_key=(ev_c.structure_key, tuple(key)))
        if not tangent:
            return ev
        ev.mass = _block_diag(ev_c.mass, [e.mass for e in ev_p])
        ev.damping = _block_diag(ev_c.damping, [e.damping for e in ev_p])
        ev.stiffness = _block_diag(ev_c.stiffness, [e.stiffness for e in ev_p])
        iq = [e.inertia_q for e in ev_p]
        if ev_c.inertia_q is not None or any(x is not None for x in iq):
            zc = ev_c.inertia_q if ev_c.inertia_q is not None else sp.csr_matrix(
                (self.n_cat, self.n_cat))
            ev.inertia_q = _block_diag(zc, [x if x is not None else np.zeros((p.n_dofs,) * 2)
                                            for x, p in zip(iq, self.pantographs)])
        if rows:
            r = np.concatenate(rows)
            c = np.concatenate(cols)
            shape = (self.n_dofs, self.n_dofs)
            ev.stiffness = ev.stiffness + sp.csr_matrix((np.concatenate(kvals), (r, c)), shape)
            if any(np.any(x) for x in cvals):
                ev.damping = ev.damping + sp.csr_matrix((np.concatenate(cvals), (r, c)), shape)
        return ev

    def commit(self, t, q, v, a, inputs):
        qc, qps = self.split(q)
        vc, vps = self.split(v)
        ac, aps = self.split(a)
        self.catenary.commit(t, qc, vc, ac, None)
        for k, p in enumerate(self.pantographs):
            p.commit(t, qps[k], vps[k], aps[k], None)

    def get_internal_state(self):
        return (self.catenary.get_internal_state(),
                [p.get_internal_state() for p in self.pantographs])

    def set_internal_state(self, state):
        if state is None:
            return
        self.catenary.set_internal_state(state[0])
        for p, s in zip(self.pantographs, state[1]):
            p.set_internal_state(s)


class RigidWire(SecondOrderModel):
    """A catenary stand-in without degrees of freedom: the contact wire is rigid and lies at
    ``height`` (or at the heights a frozen catenary configuration gives at the contact points,
    when ``catenary`` and ``q`` are given). Used to check the penalty element and the
    contact-point location."""

    n_dofs = 0

    def __init__(self, n_pantographs: int, height: float | None = None, catenary=None,
                 q=None):
        self.n_pantographs = n_pantographs
        self.height = height
        self.catenary = catenary
        self.q = None if q is None else np.asarray(q, float)

    def evaluate(self, t, q, v, a, inputs, tangent=True):
        z = np.zeros(0)
        empty = sp.csr_matrix((0, 0))
        return Evaluation(f_inertia=z, f_rest=z.copy(), mass=empty, damping=empty,
                          stiffness=empty, structure_key=None)

    def contact_points(self, t):
        return [(np.zeros(0, dtype=int), np.zeros(0))] * self.n_pantographs

    def contact_offsets(self, t):
        if self.catenary is None:
            return np.full(self.n_pantographs, float(self.height))
        return np.array([float(N @ self.q[dofs]) for dofs, N in self.catenary.contact_points(t)])


def _block_diag(first, rest):
    return sp.block_diag([sp.csr_matrix(first)] + [sp.csr_matrix(np.asarray(x)) for x in rest],
                         format="csr")

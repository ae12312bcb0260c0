"""Catenary + pantographs + contacts assembled into one model (thesis 3.2-3.3).

The catenary and any number of pantographs are assembled into one
:class:`~pantocosim.core.model.SecondOrderModel` coupled by contact elements of the
scenario's law (:mod:`pantocosim.interaction.contact_laws`: the penalty law
:mod:`~pantocosim.interaction.penalty_contact`, or the rigid
:mod:`~pantocosim.interaction.constraint_contact` whose multipliers the Newton correction
solves with the coordinates). The monolithic reference solver (``master/run/stepping.py``)
advances it with the one HHT-alpha integrator, Newton-Raphson on all coordinates at once.
Contact is lost and recovered through the penalty law; droppers slacken inside the catenary
model.

DOF layout: ``[catenary | pantograph 1 | pantograph 2 | ...]``.

Contact element k (3.9)-(3.13): z_w = N_k(t) . q_c[dofs_k] (Hermite interpolation at the
pantograph's position x_k(t) = x0_k + v t), z_p = h_k(q_p), F = law(z_p - z_w). The force acts
as +F dh/dq_p on the pantograph (down) and -F N_k on the wire (up), and enters f_rest, so it is
weighted by the integrator exactly as a force through an FMU port.
"""

from __future__ import annotations

from types import SimpleNamespace
from typing import Sequence

import numpy as np
import scipy.sparse as sp

from ..core.banded import BandedCholesky
from ..core.errors import ConvergenceError
from ..core.model import Evaluation, SecondOrderModel
from .contact_registry import ContactLaw

#: relative round-off of the coordinates: a static Newton update below it has converged
STATIC_ROUNDOFF = 16.0 * np.finfo(float).eps


class CoupledSystem(SecondOrderModel):
    """Catenary + pantographs + contacts as one second-order system."""

    def __init__(self, catenary, pantographs: Sequence, contact: ContactLaw):
        self.catenary = catenary
        self.pantographs = list(pantographs)
        self.contact = contact
        self.n_cat = int(catenary.n_dofs)
        sizes = [p.n_dofs for p in self.pantographs]
        self.offsets = np.concatenate([[self.n_cat], self.n_cat + np.cumsum(sizes)]).astype(int)
        self.n_dofs = int(self.offsets[-1])
        #: the law's part in this system (its force, Newton correction and state)
        self.law = contact.bind(self)

    # ------------------------------------------------------------------ helpers
    def split(self, x: np.ndarray):
        """(catenary part, [pantograph parts]) views of a global vector."""
        return x[:self.n_cat], [x[self.offsets[k]:self.offsets[k + 1]]
                                for k in range(len(self.pantographs))]

    def contact_state(self, t: float, q: np.ndarray, v: np.ndarray):
        """Per pantograph: (F, z_p, z_w, v_p, v_w, contact point, gradient, dF/dgap, dF/dvrel).

        The wire velocity seen by the moving pantograph includes the convective term
        V dz_w/dx, as in :meth:`~pantocosim.catenary.model.CatenaryModel.wire_velocity`."""
        qc, qps = self.split(q)
        vc, vps = self.split(v)
        speed = float(self.catenary.speed)
        out = []
        for k, (pant, cp) in enumerate(zip(self.pantographs, self.catenary.contact_points(t))):
            z_w = float(cp.weights @ qc[cp.dofs]) + float(cp.offset)
            v_w = float(cp.weights @ vc[cp.dofs])
            if speed:
                v_w += speed * (float(cp.dweights_dx @ qc[cp.dofs]) + float(cp.doffset_dx))
            g = np.asarray(pant.contact_height_gradient(qps[k]), dtype=float)
            z_p = pant.contact_height(qps[k])
            v_p = float(pant.contact_velocity(qps[k], vps[k]))
            F, dF, cF = self.law.force(k, z_p, z_w, v_p, v_w)
            out.append((F, z_p, z_w, v_p, v_w, cp, g, dF, cF))
        return out

    def contact_forces(self, t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        return np.array([c[0] for c in self.contact_state(t, q, v)])

    # ------------------------------------------------------------------ model interface
    def evaluate(self, t, q, v, a, inputs, tangent=True):
        qc, qps = self.split(q)
        vc, vps = self.split(v)
        ac, aps = self.split(a)
        ev_c = self.catenary.evaluate(t, qc, vc, ac, None, tangent=tangent)
        ev_p = [p.evaluate(t, qps[k], vps[k], aps[k], np.zeros(1), tangent=tangent)
                for k, p in enumerate(self.pantographs)]
        f_in = np.concatenate([ev_c.f_inertia] + [e.f_inertia for e in ev_p])
        f_rest = np.concatenate([ev_c.f_rest] + [e.f_rest for e in ev_p])
        speed = float(self.catenary.speed)
        lin = []
        states = self.contact_state(t, q, v)
        for k, (F, z_p, z_w, v_p, v_w, cp, g, dF, cF) in enumerate(states):
            o = self.offsets[k]
            f_rest[o:o + g.size] += F * g
            if cp.dofs.size:
                np.add.at(f_rest, cp.dofs, -F * cp.weights)
            if dF != 0.0 or cF != 0.0:
                # F depends on the gap through w = [g on q_p, -N on q_c] and, with contact
                # damping, on the convective wire velocity V dN/dx . q_c
                wq_c = -dF * cp.weights
                if cF and speed:
                    wq_c = wq_c - cF * speed * cp.dweights_dx
                lin.append((k, cp, g, dF, cF, wq_c))
        ev = Evaluation(f_inertia=f_in, f_rest=f_rest, structure_key=(
            ev_c.structure_key, tuple(e.structure_key for e in ev_p)))
        ev.parts = (ev_c, ev_p)
        # the contact linearisation of this evaluation: newton_solve adds it to the (possibly
        # reused) factorization as a low-rank update
        ev.contact_lin = (t, lin)
        self.law.add_residual(ev, states, f_rest)
        # the global tangents are never assembled (mass, damping, stiffness stay None): the
        # Newton matrix comes from the parts in effective_matrix; assembled() builds it for
        # checks
        return ev

    def effective_matrix(self, ev, c_a, c_v, c_f):
        """The block-diagonal part (catenary, pantographs) of the Newton matrix; the contact
        terms are added in :meth:`factorize`'s solve by the Woodbury identity."""
        ev_c, ev_p = ev.parts
        return _BlockNewton(
            self.catenary.effective_matrix(ev_c, c_a, c_v, c_f),
            [p.effective_matrix(e, c_a, c_v, c_f) for p, e in zip(self.pantographs, ev_p)],
            c_v, c_f)

    def newton_solve(self, solve, ev, rhs):
        """The Newton correction with the blocks' factorization ``solve`` and the contact
        linearisation of the evaluation ``ev`` (the contact law's, ``law.newton_solve``)."""
        return self.law.newton_solve(solve, ev, rhs)

    def factorize(self, S):
        """Factorize the subsystem blocks once (catenary: banded Cholesky); the returned
        ``solve(r, contact_lin)`` adds the contact linearisation U V^T of an evaluation
        (rank = contacts in touch) exactly:
        (A + U V^T)^-1 r = A^-1 r - A^-1 U (I + V^T A^-1 U)^-1 V^T A^-1 r."""
        cat_solve = self.catenary.factorize(S.cat)
        pan_solves = [p.factorize(Sp) for p, Sp in zip(self.pantographs, S.pans)]
        cache: dict = {}
        n_cat = self.n_cat

        def block_solve(r):
            x = np.empty_like(r)
            x[:n_cat] = cat_solve(r[:n_cat])
            for k, ps in enumerate(pan_solves):
                o, e = self.offsets[k], self.offsets[k + 1]
                x[o:e] = ps(r[o:e])
            return x

        def contact_update(t, lin):
            """A^-1 U (n x m), V^T as (pantograph slice, values, catenary dofs, values) rows
            and I + V^T A^-1 U for the current contact linearisation."""
            m = len(lin)
            cols = []
            rows = []
            for j, (k, cp, g, dF, cF, wq_c) in enumerate(lin):
                o = self.offsets[k]
                key = (t, k, g.tobytes())
                col = cache.get(key)
                if col is None:
                    col = np.zeros(self.n_dofs)
                    if cp.dofs.size:
                        col[:n_cat] = _sparse_solve(cat_solve, n_cat, cp.dofs, -cp.weights)
                    ps = pan_solves[k]
                    col[o:o + g.size] = np.asarray(ps(g), dtype=float).reshape(g.size)
                    if len(cache) > 64:
                        cache.clear()
                    cache[key] = col
                cols.append(col)
                # V_j = c_f (dF w + c_v cF w + convective part)
                rows.append((slice(o, o + g.size), S.c_f * (dF + S.c_v * cF) * g, cp.dofs,
                             S.c_f * (wq_c - S.c_v * cF * cp.weights)))
            AU = cols[0][:, None] if m == 1 else np.column_stack(cols)
            Vt_AU = np.array([[v_dot(row, col) for col in cols] for row in rows])
            return AU, rows, np.eye(m) + Vt_AU

        def v_dot(row, x):
            """V_j . x for one row of contact_update."""
            return row[1] @ x[row[0]] + row[3] @ x[row[2]]

        memo = [None, None]

        def solve(r, contact_lin):
            r = np.asarray(r, dtype=float)
            x = block_solve(r)
            t, lin = contact_lin
            if not lin:
                return x
            key = _linearisation_key(t, lin)
            if memo[0] != key:
                memo[0], memo[1] = key, contact_update(t, lin)
            AU, rows, small = memo[1]
            if len(rows) == 1:      # one contact: the 1 x 1 solve is a division (as LAPACK's)
                return x - AU[:, 0] * (v_dot(rows[0], x) / small[0, 0])
            vx = np.array([v_dot(row, x) for row in rows])
            return x - AU @ np.linalg.solve(small, vx)

        #: the weight of the forces in this Newton matrix (a multiplier's correction needs it)
        solve.c_f, solve.c_v = S.c_f, S.c_v
        return solve

    def assembled(self, ev, c_a=0.0, c_v=0.0, c_f=1.0):
        """The full Newton matrix c_a M + inertia_q + c_f (c_v C + K) including contact, as a
        sparse matrix (for checks; the solver never assembles it)."""
        ev_c, ev_p = ev.parts
        blocks = [sp.csr_matrix(self.catenary.effective_matrix(ev_c, c_a, c_v, c_f))]
        blocks += [sp.csr_matrix(np.asarray(p.effective_matrix(e, c_a, c_v, c_f)))
                   for p, e in zip(self.pantographs, ev_p)]
        S = sp.block_diag(blocks, format="lil")
        t, lin = ev.contact_lin
        for k, cp, g, dF, cF, wq_c in lin:
            o = self.offsets[k]
            u = np.zeros(self.n_dofs)
            u[o:o + g.size] = g
            np.add.at(u, cp.dofs, -cp.weights)
            vj = np.zeros(self.n_dofs)
            vj[o:o + g.size] = (dF + c_v * cF) * g
            np.add.at(vj, cp.dofs, wq_c - c_v * cF * cp.weights)
            S = S + sp.csr_matrix(np.outer(u, c_f * vj))
        return sp.csr_matrix(S)

    def static_solve(self, q0, t: float = 0.0, tol: float = 1e-10, max_iter: int = 60):
        """Static equilibrium f_rest(t, q, 0) = 0 of the coupled system by Newton-Raphson
        (the static start: pantographs and catenary in equilibrium in contact). Converged
        when the residual is below ``tol`` times the catenary's largest internal force, or
        when the Newton update is at the round-off of the coordinates
        (``STATIC_ROUNDOFF * max |q|``: the residual of a stiff contact or a long line cannot
        get smaller than its own round-off)."""
        q = np.array(q0, dtype=float)
        zero = np.zeros(self.n_dofs)
        for it in range(max_iter):
            ev = self.evaluate(t, q, zero, zero, None, tangent=True)
            R = ev.f_rest
            scale = max(self.catenary.static_force_scale(ev.parts[0].f_rest), 1.0)
            limit = tol * scale
            if float(np.max(np.abs(R))) <= limit:
                return q
            dq = -self.newton_solve(self.factorize(self.effective_matrix(ev, 0.0, 0.0, 1.0)),
                                    ev, R)
            q = q + dq
            if float(np.max(np.abs(dq))) <= STATIC_ROUNDOFF * float(np.max(np.abs(q),
                                                                         initial=1.0)):
                return q
        exc = ConvergenceError(f"static start did not converge: residual "
                               f"{float(np.max(np.abs(R))):.3e} N against the tolerance "
                               f"{limit:.3e} N after {max_iter} iterations",
                               time=t, residual=float(np.max(np.abs(R))))
        exc.tolerance = limit
        raise exc

    def commit(self, t, q, v, a, inputs):
        qc, qps = self.split(q)
        vc, vps = self.split(v)
        ac, aps = self.split(a)
        self.catenary.commit(t, qc, vc, ac, None)
        for k, p in enumerate(self.pantographs):
            p.commit(t, qps[k], vps[k], aps[k], None)
        self.law.commit()

    def get_internal_state(self):
        return (self.catenary.get_internal_state(),
                [p.get_internal_state() for p in self.pantographs], self.law.get_state())

    def set_internal_state(self, state):
        if state is None:
            return
        self.catenary.set_internal_state(state[0])
        for p, s in zip(self.pantographs, state[1]):
            p.set_internal_state(s)
        self.law.set_state(state[2])


class RigidWire(SecondOrderModel):
    """A catenary stand-in without degrees of freedom: the contact wire is rigid and lies at
    ``height`` (or at the heights a frozen catenary configuration gives at the contact points,
    when ``catenary`` and ``q`` are given). Used to check the penalty element and the
    contact-point location."""

    n_dofs = 0
    #: the wire does not move along the track
    speed = 0.0

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
        if self.catenary is None:
            heights = np.full(self.n_pantographs, float(self.height))
        else:
            heights = self.catenary.wire_height(t, self.q)
        empty_i, empty_f = np.zeros(0, dtype=int), np.zeros(0)
        return [SimpleNamespace(dofs=empty_i, weights=empty_f, offset=float(z),
                                dweights_dx=empty_f, doffset_dx=0.0) for z in heights]


def _linearisation_key(t, lin) -> tuple:
    """What the contact linearisation ``lin`` of an evaluation at t depends on: the contact
    points (fixed by t), each contact's body gradient and its dF/dgap, dF/dvrel. The Newton
    iterations of a step in steady contact meet the same one again."""
    return (t, tuple((k, dF, cF, g.tobytes()) for k, cp, g, dF, cF, wq_c in lin))


def _sparse_solve(solve, n, dofs, values):
    """solve(b) for b with ``values`` at ``dofs``: from the cached unit-vector solves of a
    :class:`~pantocosim.core.banded.BandedCholesky`, by a whole solve otherwise."""
    if isinstance(solve, BandedCholesky):
        return solve.solve_sparse(dofs, values)
    b = np.zeros(n)
    np.add.at(b, dofs, values)
    return solve(b)


class _BlockNewton:
    """Block-diagonal Newton matrix of the coupled system (contact terms excluded)."""

    def __init__(self, cat, pans, c_v, c_f):
        self.cat, self.pans, self.c_v, self.c_f = cat, pans, c_v, c_f

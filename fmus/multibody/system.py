"""The multibody system: nodes, components, constraints, one SecondOrderModel.

Each node carries 12 coordinates [x, d1, d2, d3]: its position and the three directors of the
cross-section triad R = [d1 d2 d3] (no rotation parameters, hence no singularity at a rotation
of 2 pi, and a constant mass matrix). The components (beams, loads, contact, joints) follow
cardillo's pattern: they contribute mass, forces with tangents and quadratic constraints; the
system collects them (one thing per file, one collector).

The unknowns handed to the HHT-alpha integrator are q = [node coordinates, lambda], the
multipliers of the constraints g(q) = 0 (Lagrange equations with multipliers, seed 004,
eq. 112; seed 002 eq. 15 without the augmented-Lagrangian penalty):

    f_inertia = [M a_x ; 0],
    f_rest    = [f(t, q, v) + s G(q)^T lambda ; s g(q)],

``s`` (``constraint_scale``) only balances the rows of the Newton matrix. With the HHT weights
the constraint rows read (1 + alpha) g_{n+1} - alpha g_n = 0: index-3 HHT, the constraints
hold at every step to the Newton tolerance (drift reported by :meth:`constraint_drift`).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from pantocosim.core.model import Evaluation, SecondOrderModel

from .constraint_set import ConstraintSet, orthonormality
from .triplets import Triplets

NODE_DOFS = 12


class System(SecondOrderModel):
    #: systems with at most this many unknowns hand dense matrices to the integrator
    #: (assembly by np.bincount and LAPACK are cheaper than sparse bookkeeping there)
    DENSE_LIMIT = 800

    def __init__(self, constraint_scale: float = 1.0e6):
        self.X0: list[np.ndarray] = []
        self.R0: list[np.ndarray] = []
        self.components: list = []
        self.constraint_scale = float(constraint_scale)
        self.n_q = 0
        self.n_c = 0
        self.n_dofs = 0
        self.M = None
        self.constraints: ConstraintSet | None = None
        self._bound = False

    # ------------------------------------------------------------------ building
    def add_node(self, x, R=None) -> int:
        """A node at position ``x`` with the orthonormal triad ``R`` (columns d1, d2, d3)."""
        R = np.eye(3) if R is None else np.asarray(R, dtype=float)
        if not np.allclose(R.T @ R, np.eye(3), atol=1e-12):
            raise ValueError("the node triad must be orthonormal")
        self.X0.append(np.asarray(x, dtype=float).copy())
        self.R0.append(R.copy())
        self._bound = False
        return len(self.X0) - 1

    def add(self, component):
        self.components.append(component)
        self._bound = False
        return component

    @staticmethod
    def x_dofs(node) -> np.ndarray:
        return NODE_DOFS * np.asarray(node)[..., None] + np.arange(3)

    @staticmethod
    def d_dofs(node, i=None) -> np.ndarray:
        """Director coordinates of a node: all nine (i None) or those of d_{i+1}."""
        if i is None:
            return NODE_DOFS * np.asarray(node)[..., None] + 3 + np.arange(9)
        return NODE_DOFS * np.asarray(node)[..., None] + 3 + 3 * i + np.arange(3)

    @staticmethod
    def node_dofs(node) -> np.ndarray:
        return NODE_DOFS * np.asarray(node)[..., None] + np.arange(NODE_DOFS)

    def assemble(self) -> "System":
        """Number the coordinates, collect the constant mass matrix and the constraints."""
        n_nodes = len(self.X0)
        self.n_q = NODE_DOFS * n_nodes
        self.n_dofs = self.n_q          # until the constraints are counted
        M = Triplets(self.n_q)
        sets = [orthonormality(self.d_dofs(np.arange(n_nodes)))]
        n_rows = sets[0].size
        self._rows_of = {}
        for comp in self.components:
            if hasattr(comp, "bind"):
                comp.bind(self)
        for comp in self.components:
            if hasattr(comp, "add_mass"):
                comp.add_mass(M)
            if hasattr(comp, "constraints"):
                own = comp.constraints(self)
                size = sum(c.size for c in own)
                self._rows_of[id(comp)] = slice(n_rows, n_rows + size)
                n_rows += size
                sets.extend(own)
        self.M = M.tocsr()
        self.constraints = ConstraintSet.concatenate(sets)
        self.n_c = self.constraints.size
        self.n_dofs = self.n_q + self.n_c
        self._rows = np.repeat(np.arange(self.n_c), self.constraints.idx.shape[1])
        z = sp.csr_matrix((self.n_c, self.n_c))
        self._mass_full = sp.block_diag([self.M, z], format="csr")
        self.dense = self.n_dofs <= self.DENSE_LIMIT
        if self.dense:
            self._mass_full = self._mass_full.toarray()
        self._bound = True
        return self

    def reference(self) -> np.ndarray:
        """q of the reference configuration (multipliers 0)."""
        q = np.zeros(self.n_dofs)
        for k, (x, R) in enumerate(zip(self.X0, self.R0)):
            q[NODE_DOFS * k:NODE_DOFS * (k + 1)] = np.concatenate([x, R.T.reshape(9)])
        return q

    # ------------------------------------------------------------------ pieces
    def constraint_jacobian(self, q, t: float = 0.0) -> tuple[np.ndarray, sp.csr_matrix]:
        """(g, G): values at (q, t) and the sparse (n_c, n_q) Jacobian at q."""
        cs = self.constraints
        qq = q[:self.n_q]
        G = sp.csr_matrix((cs.gradients(qq).reshape(-1), (self._rows, cs.idx.reshape(-1))),
                          shape=(self.n_c, self.n_q))
        return cs.values(qq, t), G

    def forces(self, t, q, v, tangent=True):
        """f(t, q, v) of the node equations (internal + damping - external) and its tangents
        K = df/dq, C = df/dv as :class:`Triplets` (None unless ``tangent``)."""
        nq = self.n_q
        f = np.zeros(nq)
        K = Triplets(self.n_dofs) if tangent else None
        C = Triplets(self.n_dofs) if tangent else None
        for comp in self.components:
            if hasattr(comp, "add_forces"):
                comp.add_forces(t, q[:nq], v[:nq], f, K, C)
        return f, K, C

    def evaluate(self, t, q, v, a, inputs=None, tangent=True) -> Evaluation:
        nq, nc, s = self.n_q, self.n_c, self.constraint_scale
        lam = q[nq:]
        f, K, C = self.forces(t, q, v, tangent)
        g, G = self.constraint_jacobian(q, t)
        f_rest = np.concatenate([f + s * (G.T @ lam), s * g])
        f_inertia = np.concatenate([self.M @ a[:nq], np.zeros(nc)])
        ev = Evaluation(f_inertia=f_inertia, f_rest=f_rest)
        if tangent:
            cs = self.constraints
            K.add(cs.idx, cs.idx, (s * lam)[:, None, None] * cs.H)
            Gc = G.tocoo()
            K.add_entries(Gc.row + nq, Gc.col, s * Gc.data)
            K.add_entries(Gc.col, Gc.row + nq, s * Gc.data)
            if self.dense:
                ev.mass, ev.damping, ev.stiffness = self._mass_full, C.toarray(), K.toarray()
            else:
                ev.mass, ev.damping, ev.stiffness = self._mass_full, C.tocsr(), K.tocsr()
        return ev

    def consistent_start(self, t, q, v=None, project_velocity: bool = False):
        """Multipliers and accelerations consistent with (q, v) at t: the KKT system
        [M G^T; G 0] [a; s lambda] = [-f; -v^T H v - r''(t)] (second time derivative of
        g(q, t) = 0, r the driven part). ``project_velocity``: first replace v by its
        M-orthogonal projection on G v + r'(t) = 0 (for a start that moves an actuator).
        Returns (q with lambda, v, a)."""
        nq, s = self.n_q, self.constraint_scale
        q = np.array(q, dtype=float)
        v = np.zeros(self.n_dofs) if v is None else np.array(v, dtype=float)
        q[nq:] = 0.0
        _, G = self.constraint_jacobian(q, t)
        r = self.constraints.time_terms(t)
        A = sp.bmat([[self.M, G.T], [G, None]], format="csc")
        if project_velocity:
            v[:nq] = spla.spsolve(A, np.concatenate([self.M @ v[:nq], -r[1]]))[:nq]
        f, _, _ = self.forces(t, q, v, tangent=False)
        curv = self.constraints.curvature(v[:nq])
        sol = spla.spsolve(A, np.concatenate([-f, -curv - r[2]]))
        a = np.zeros(self.n_dofs)
        a[:nq] = sol[:nq]
        q[nq:] = sol[nq:] / s
        v[nq:] = 0.0
        return q, v, a

    # ------------------------------------------------------------------ reports
    def kinetic_energy(self, v) -> float:
        vq = v[:self.n_q]
        return 0.5 * float(vq @ (self.M @ vq))

    def energies(self, t, q, v) -> dict:
        """Kinetic energy and every component's potential (strain, gravity, contact) and
        power (external work rate, dissipation rate)."""
        out = {"kinetic": self.kinetic_energy(v)}
        nq = self.n_q
        for comp in self.components:
            if hasattr(comp, "energy"):
                for key, val in comp.energy(t, q[:nq], v[:nq]).items():
                    out[key] = out.get(key, 0.0) + val
        return out

    def constraint_drift(self, q, t: float = 0.0) -> float:
        """max |g(q, t)|: how far q lies off the constraint manifold."""
        return float(np.max(np.abs(self.constraints.values(q[:self.n_q], t))))

    def multipliers(self, q, component) -> np.ndarray:
        """s lambda of ``component``'s constraints (in the order of its sets): the
        generalised constraint force on the node coordinates is -G_c^T (s lambda)."""
        rows = self._rows_of[id(component)]
        return self.constraint_scale * q[self.n_q + rows.start:self.n_q + rows.stop]

    def position(self, q, node) -> np.ndarray:
        return q[self.x_dofs(node)]

    def triad(self, q, node) -> np.ndarray:
        """R = [d1 d2 d3] of a node."""
        return q[self.d_dofs(node)].reshape(3, 3).T

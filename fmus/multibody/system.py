"""The multibody system: nodes, components, constraints, one SecondOrderModel.

Each node carries 12 coordinates [x, d1, d2, d3]: its position and the three directors of the
cross-section triad R = [d1 d2 d3] (no rotation parameters, hence no singularity at a rotation
of 2 pi, and a constant mass matrix). The components (beams, loads, contact, joints) follow
cardillo's pattern: they contribute mass, forces with tangents and quadratic constraints; the
system collects them (one thing per file, one collector).

The unknowns handed to the HHT-alpha integrator are q = [node coordinates, lambda], the
multipliers of the constraints g(q) = 0 (Lagrange equations with multipliers, Cardona & Jordi,
eq. 112; the pendulum paper eq. 15 without the augmented-Lagrangian penalty):

    f_inertia = [M a_x ; 0],
    f_rest    = [f(t, q, v) + s G(q)^T lambda ; s g(q)],

``s`` (``constraint_scale``) only balances the rows of the Newton matrix. With the HHT weights
the constraint rows read (1 + alpha) g_{n+1} - alpha g_n = 0: index-3 HHT, the constraints
hold at every step to the Newton tolerance (drift reported by :meth:`System.constraint_drift`).
Constraints may depend on time (actuators: g(q, t), ``constraint_set.py``).

The components follow the protocol of :class:`~.component.Component`.

K and C are :class:`PatternMatrix`: small components ``add`` blocks, element sets scatter
into ``K.data`` at the positions they located.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from pantocosim.core.model import Evaluation, SecondOrderModel
from pantocosim.core.scatter import scatter_add

from .constraint_set import ConstraintSet, orthonormality
from .pattern import Pattern, PatternMatrix, factorize_csr
from .triplets import Triplets

NODE_DOFS = 12


class System(SecondOrderModel):
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
            comp.bind(self)
        for comp in self.components:
            comp.add_mass(M)
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
        self._build_pattern()
        self._bound = True
        return self

    def _build_pattern(self) -> None:
        """The one CSR pattern of the Newton matrix: mass, the couplings of every component
        that has a tangent (``tangent_dofs``), the constraints; components that scatter by
        positions get them (``locate``)."""
        Mc = self.M.tocoo()
        rows, cols = [Mc.row], [Mc.col]
        for comp in self.components:
            d = comp.tangent_dofs()
            if d is not None:
                d = np.asarray(d)
                rows.append(np.broadcast_to(d[:, :, None], d.shape + d.shape[-1:]))
                cols.append(np.broadcast_to(d[:, None, :], d.shape + d.shape[-1:]))
        r, c = self.constraints.couplings(self.n_q)
        self.pattern = Pattern(self.n_dofs, rows + r, cols + c)
        for comp in self.components:
            comp.locate(self.pattern)
        self.constraints.locate(self.pattern, self.n_q)
        self._mass_data = np.zeros(self.pattern.nnz)
        scatter_add(self._mass_data, self.pattern.positions(Mc.row, Mc.col), Mc.data)
        self._mass_full = self.pattern.matrix(self._mass_data)

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
        K = df/dq, C = df/dv as :class:`PatternMatrix` (None unless ``tangent``)."""
        nq = self.n_q
        f = np.zeros(nq)
        K = PatternMatrix(self.pattern) if tangent else None
        C = PatternMatrix(self.pattern) if tangent else None
        for comp in self.components:
            comp.add_forces(t, q[:nq], v[:nq], f, K, C)
        return f, K, C

    def evaluate(self, t, q, v, a, inputs=None, tangent=True) -> Evaluation:
        nq, nc, s = self.n_q, self.n_c, self.constraint_scale
        f, K, C = self.forces(t, q, v, tangent)
        g = self.constraints.add_forces(t, q, q[nq:], s, f, K.data if tangent else None)
        f_rest = np.concatenate([f, s * g])
        f_inertia = np.concatenate([self.M @ a[:nq], np.zeros(nc)])
        key = tuple(c.state_key(q[:nq]) for c in self.components)
        ev = Evaluation(f_inertia=f_inertia, f_rest=f_rest, structure_key=key)
        if tangent:
            ev.mass, ev.damping, ev.stiffness = self._mass_full, C.tocsr(), K.tocsr()
        return ev

    def effective_matrix(self, ev, c_a, c_v, c_f):
        """c_a M + c_f (c_v C + K): one sum of data arrays on the shared pattern."""
        if ev.mass is not self._mass_full or ev.inertia_q is not None:
            return super().effective_matrix(ev, c_a, c_v, c_f)
        return self.pattern.matrix(c_a * self._mass_data
                                   + c_f * (c_v * ev.damping.data + ev.stiffness.data))

    def factorize(self, S):
        return factorize_csr(S) if sp.isspmatrix_csr(S) else super().factorize(S)

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

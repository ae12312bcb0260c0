"""The catenary as a second-order model on the shared HHT-alpha integrator (thesis 3.3.3).

    f_inertia = M a                                   (constant mass, (3.25))
    f_rest    = C v + F_elast(q) - F_weight - sum_k N_k^T F_k      ((3.26), (3.12)-(3.13))

with C = alpha M + beta K0 (Rayleigh (3.1); K0 the tangent at the static configuration) and
F_k >= 0 the contact force of pantograph k pushing the contact wire up at
x_k(t) = x0_k + V t (3.11). The force enters ``f_rest``, so the integrator weights it like
any internal force.

Coordinates ``q`` (free DOFs, numbered along the track): y, z and the slopes are absolute;
x positions are stored relative to each node's station (absolute x = station + q) to keep
round-off small on long lines. Heights are from the rail, so z_wire = N @ q[dofs] exactly.

Slack droppers (thesis 3.1.2, 3.3.3): the elastic force of a dropper follows the tension-only
law at the current Newton iterate (the force is continuous: zero at the unstretched length),
so the set used by the elastic force and tangent is updated *within* the iterations; the
dropper's share of the Rayleigh damping (beta K0_d) is removed according to the slack set
*committed* at the end of the previous accepted step (keeps the residual continuous within a
step). Both sets are deterministic functions of the iterate / the committed state; the
committed set is the model's internal state (:meth:`CatenaryModel.get_internal_state`), and
``Evaluation.structure_key`` changes whenever either set changes.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from numba import njit

from ..core.banded import BandedCholesky, SparseBand
from ..core.errors import ParameterError
from ..core.model import Evaluation, SecondOrderModel
from ..core.scatter import scatter_add
from .compiled_forces import CompiledForces, _inertia_and_rest
from .contact_point import ContactLocator, ContactPoint
from .definition import CatenaryDefinition, load_catenary
from .mesh import CatenaryMesh, build_mesh
from .statics import (InitialConfiguration, point_load_vector, solve_initial_configuration,
                      solve_static)


#: the fill above which a band diagonal of M or C is multiplied whole in the residual (the
#: sparser ones entry by entry): the fastest on the EN 50318 and AVE lines
BAND_FILL = 0.3

#: damping matrices kept for the last slack sets of the droppers (each one nnz floats)
KEPT_DAMPINGS = 4


class CatenaryModel(SecondOrderModel):
    """Finite-element catenary with moving point loads.

    ``CatenaryModel(catenary, x0=(x_1, ...), speed=V)``: ``catenary`` is a preset name, a
    path, a :class:`CatenaryDefinition` or a prepared :class:`CatenaryMesh`. Construction
    solves the initial-configuration problem (definitions) or the static equilibrium
    (bare meshes), which becomes the reference configuration.
    """

    def __init__(self, catenary, x0=(0.0,), speed: float = 0.0, *,
                 element_size: float | None = None, rayleigh: tuple | None = None):
        if isinstance(catenary, CatenaryMesh):
            mesh = catenary
        else:
            d = catenary if isinstance(catenary, CatenaryDefinition) else load_catenary(catenary)
            mesh = build_mesh(d, element_size)
        self.mesh = mesh
        self.definition = mesh.definition
        S = self.structure = mesh.structure
        self.n_dofs = S.n_free
        self.speed = float(speed)
        self.x0 = np.atleast_1d(np.asarray(x0, dtype=float))
        if not np.all(np.isfinite(self.x0)) or not np.isfinite(self.speed):
            raise ParameterError("x0", list(self.x0), "positions and speed must be finite")
        # reference (static) configuration
        self.initial_configuration: InitialConfiguration | None = None
        if mesh.definition is not None and mesh.dropper_bars.size:
            self.initial_configuration = solve_initial_configuration(mesh)
            self.q_static = self.initial_configuration.q
        else:
            self.q_static = solve_static(S, S.x_full[S.free]).q
        self.x_static = S.full(self.q_static)
        self.locator = ContactLocator(mesh, self.x_static)
        for x in self.x0:
            self.locator.locate(float(x))   # validates the start positions
        # matrices on the shared pattern
        f, K0, _ = S.internal(self.x_static, True, tension_only=False)
        self.K0_data = K0
        if rayleigh is None:
            rayleigh = self.definition.rayleigh() if self.definition is not None else (0.0, 0.0)
        self.alpha_r, self.beta_r = float(rayleigh[0]), float(rayleigh[1])
        self.M = S.mass
        self.weight = S.weight
        self._C_base = self.alpha_r * S.M_data + self.beta_r * K0
        _, Kb, _ = S.bars.tangent_blocks(self.x_static)
        db = mesh.dropper_bars
        self._dropper_C = self.beta_r * Kb[db].reshape(len(db), 36)
        self._dropper_pos = S.bars.pos_blocks[db]
        self._slack_committed = np.zeros(len(db), dtype=bool)
        # damping matrix for the committed slack set (see _damping)
        self._C = {self._slack_committed.tobytes(): S.csr(self._C_base.copy())}
        # for the residual: M on its own (sparser) pattern
        self._M_own = S.mass.copy()
        self._M_own.eliminate_zeros()
        # ... and M, C (all droppers taut) as symmetric sparse bands, the slack droppers'
        # share of C taken out block by block (:func:`_inertia_and_rest`)
        self._M_band = SparseBand.from_band(S.lower_band(S.M_data), BAND_FILL).parts
        self._C_band = SparseBand.from_band(S.lower_band(self._C_base), BAND_FILL).parts
        self._dropper_free = S.fmap[S.bars.dofs[db]]
        self._cp_cache: tuple | None = None
        self._loads: tuple | None = None
        self._support_free = None
        #: the residual in one compiled call (None: a structure evaluated part by part)
        self._compiled = CompiledForces.of(S)
        self._no_loads = np.zeros(0)

    # ------------------------------------------------------------------ geometry
    def positions(self, t: float) -> np.ndarray:
        """Track positions x_k(t) = x0_k + V t of the pantographs, (3.11)."""
        return self.x0 + self.speed * float(t)

    def contact_points(self, t: float) -> list[ContactPoint]:
        """For each pantograph, the contact-wire point under it: z_wire = weights @ q[dofs]
        (+ offset, zero except in an element touching an anchored line end). The local
        coordinate comes from the reference (static) configuration (3.12) and is not
        updated with the motion, as in the thesis."""
        t = float(t)
        if self._cp_cache is None or self._cp_cache[0] != t:
            self._cp_cache = (t, [self.locator.point(x) for x in self.positions(t)])
        return self._cp_cache[1]

    def wire_height(self, t: float, q: np.ndarray) -> np.ndarray:
        """Height of the contact wire above the rail at each pantograph, (3.13)."""
        return self.wire_state(t, q, q)[0]

    def wire_velocity(self, t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """d/dt of :meth:`wire_height`: the wire's vertical velocity plus the convective
        term V dz/dx seen by the moving pantograph."""
        return self.wire_state(t, q, v)[1]

    def wire_state(self, t: float, q: np.ndarray, v: np.ndarray):
        """(:meth:`wire_height`, :meth:`wire_velocity`) in one pass over the points:
        z = w . q[dofs] + offset (3.13), dz/dt = w . v[dofs] + V (dw/dx . q[dofs] +
        d offset/dx)."""
        cps = self.contact_points(t)
        z, vz = np.empty(len(cps)), np.empty(len(cps))
        for k, cp in enumerate(cps):
            zk, vk, slope = _wire_point(cp.dofs, cp.weights, cp.dweights_dx, q, v)
            z[k] = zk + cp.offset
            vz[k] = vk + self.speed * (slope + cp.doffset_dx)
        return z, vz

    def contact_wire_height(self, q: np.ndarray, x) -> np.ndarray:
        """Contact-wire height at arbitrary track positions x (same interpolation)."""
        out = []
        for xx in np.atleast_1d(x):
            cp = self.locator.point(float(xx))
            out.append(cp.weights @ q[cp.dofs] + cp.offset)
        return np.array(out)

    @property
    def support_x(self) -> np.ndarray:
        return self.mesh.support_x

    def support_uplift(self, q: np.ndarray) -> np.ndarray:
        """Uplift of the contact wire at every support (steady arm) relative to the static
        configuration; zero at the two anchored line ends."""
        if self._support_free is None:
            dz = self.mesh.node_dofs[self.mesh.support_contact_nodes, 2]
            free = self.structure.fmap[dz]
            self._support_free = (free, free >= 0, self.x_static[dz])
        free, moving, z_static = self._support_free
        return np.where(moving, q[free] - z_static, 0.0)

    def dropper_forces(self, q: np.ndarray) -> np.ndarray:
        """Axial force of every dropper (N, tension positive, zero when slack)."""
        return self.structure.bars.axial_forces(self.structure.full(q))[self.mesh.dropper_bars]

    #: the model setting that sets :meth:`contact_compliance` (None: nothing does)
    compliance_setting: str | None = None

    def contact_compliance(self, times) -> np.ndarray:
        """The catenary's instantaneous compliance at its contact points [m/N], one
        (pantographs x pantographs) matrix per time in ``times``: how far each contact point
        moves under the contact forces applied within the same instant, with no mass or
        damping between (docs/stability.md). Zero here: every DOF of the contact wire
        carries mass."""
        n = len(self.x0)
        return np.zeros((np.atleast_1d(times).size, n, n))

    # ------------------------------------------------------------------ statics
    def static_solution(self, point_loads=(), tol: float = 1e-10):
        """Static equilibrium (3.5)-(3.8) with upward point loads [(x, F), ...] on the
        contact wire (droppers tension-only); returns a StaticResult."""
        P = point_load_vector(self.structure, self.locator, point_loads)
        return solve_static(self.structure, self.q_static, P, tol=tol)

    def static_state(self, forces=None, t: float = 0.0) -> np.ndarray:
        """q0 for the integrator: static equilibrium with the pantographs' static contact
        forces (one per pantograph, at x_k(t)); ``None`` gives the unloaded configuration."""
        if forces is None:
            return self.q_static.copy()
        forces = np.broadcast_to(np.asarray(forces, float), self.x0.shape)
        return self.static_solution(list(zip(self.positions(t), forces))).q

    def elasticity(self, x, force: float = 100.0) -> np.ndarray:
        """Static uplift per unit force (m/N) under an upward force at each x."""
        z0 = self.contact_wire_height(self.q_static, x)
        out = []
        for xx, z in zip(np.atleast_1d(x), z0):
            q = self.static_solution([(float(xx), force)]).q
            out.append((self.contact_wire_height(q, [xx])[0] - z) / force)
        return np.array(out)

    def equilibrium_residual(self, q: np.ndarray) -> float:
        """max |F_elast - F_weight| / max |F_weight| at q (static, droppers tension-only)."""
        f, _, _ = self.structure.internal(self.structure.full(q), False)
        R = f[self.structure.free] - self.weight
        return float(np.max(np.abs(R)) / np.max(np.abs(self.weight)))

    # ------------------------------------------------------------------ modal analysis
    def modes(self, count: int = 10, shift: float = 0.0):
        """Lowest ``count`` natural frequencies (Hz) and mode shapes (columns) about the
        static configuration: K0 phi = omega^2 M phi (eigsh, shift-invert)."""
        K = self.structure.csr(self.K0_data)
        count = int(count)
        if count < 1 or count >= self.n_dofs:
            raise ParameterError("count", count, f"must be in [1, {self.n_dofs - 1}]")
        lam, phi = spla.eigsh(sp.csc_matrix(K), k=count, M=sp.csc_matrix(self.M),
                              sigma=shift, which="LM")
        order = np.argsort(lam)
        lam, phi = lam[order], phi[:, order]
        return np.sqrt(np.maximum(lam, 0.0)) / (2 * np.pi), phi

    # ------------------------------------------------------------------ dynamics
    def _damping(self, slack) -> sp.csr_matrix:
        """C on the shared pattern without the Rayleigh share of the ``slack`` droppers,
        the last :data:`KEPT_DAMPINGS` sets' kept (a dropper slackening and tightening
        again over a few steps comes back to a set seen)."""
        key = slack.tobytes()
        kept = self._C
        C = kept.pop(key, None)
        if C is None:
            data = self._C_base.copy()
            if slack.any():
                scatter_add(data, self._dropper_pos[slack].ravel(),
                            -self._dropper_C[slack].ravel())
            C = self.structure.csr(data)
            if len(kept) >= KEPT_DAMPINGS:
                kept.pop(next(iter(kept)))
        kept[key] = C          # most recently used last
        return C

    def input_vector(self, t: float, inputs) -> np.ndarray:
        """sum_k N_k^T F_k on the free DOFs (upward contact forces)."""
        P = np.zeros(self.n_dofs)
        if inputs is None:
            return P
        F = np.atleast_1d(np.asarray(inputs, dtype=float))
        if F.shape != self.x0.shape:
            raise ParameterError("inputs", F.tolist(),
                                 f"needs one contact force per pantograph ({self.x0.size})")
        if not np.all(np.isfinite(F)):
            raise ParameterError("inputs", F.tolist(), "contact forces must be finite")
        for cp, Fk in zip(self.contact_points(t), F):
            if Fk != 0.0:
                np.add.at(P, cp.dofs, Fk * cp.weights)
        return P

    def _step_loads(self, t: float, inputs) -> np.ndarray:
        """:meth:`input_vector`, kept while t and the forces stay (a step's iterations);
        read only."""
        key = (float(t), np.asarray(inputs, dtype=float).tobytes())
        if self._loads is None or self._loads[0] != key:
            self._loads = (key, self.input_vector(t, inputs))
        return self._loads[1]

    def evaluate(self, t, q, v, a, inputs, tangent=True) -> Evaluation:
        S = self.structure
        loads = self._loads_at(t, inputs)
        if self._compiled is not None:
            Ma, f_rest, K, slack_now = self._compiled.evaluate(
                q, v, a, tangent, self._M_band, self._C_band, self._slack_committed,
                self._dropper_free, self._dropper_C, self.weight, loads)
        else:
            f, K, slack_now = S.internal(S.full(q), tangent)
            Ma, f_rest = _inertia_and_rest(self._M_band, a, self._C_band, v,
                                           self._slack_committed, self._dropper_free,
                                           self._dropper_C, f, S.free, self.weight, loads)
        return self._evaluation(Ma, f_rest, K, slack_now)

    @property
    def fused_iterate(self) -> bool:
        """:meth:`iterate` in one compiled call (:class:`CompiledForces`) when every part
        of the structure has a compiled kernel."""
        return self._compiled is not None

    def iterate(self, t, q, q_p, v_p, c_a, c_v, c_f, hist, inputs, tangent):
        a, v, Ma, f_rest, R, r_max, scale, K, slack_now = self._compiled.iterate(
            q, q_p, v_p, c_a, c_v, c_f, hist, tangent, self._M_band, self._C_band,
            self._slack_committed, self._dropper_free, self._dropper_C, self.weight,
            self._loads_at(t, inputs))
        return self._evaluation(Ma, f_rest, K, slack_now), a, v, R, r_max, scale

    def _loads_at(self, t, inputs) -> np.ndarray:
        """The step loads (:meth:`_step_loads`), empty without inputs."""
        return self._no_loads if inputs is None else self._step_loads(t, inputs)

    def _evaluation(self, Ma, f_rest, K, slack_bars) -> Evaluation:
        """The :class:`Evaluation` of M a, f_rest and (None: no tangent) the stiffness data,
        keyed on the droppers' slack sets now and committed."""
        slack_now = slack_bars[self.mesh.dropper_bars]
        ev = Evaluation(f_inertia=Ma, f_rest=f_rest,
                        structure_key=(slack_now.tobytes(), self._slack_committed.tobytes()))
        if K is not None:
            ev.mass = self.M
            ev.damping = self._damping(self._slack_committed)
            ev.stiffness = self.structure.csr(K)
        return ev

    def static_force_scale(self, f_rest) -> float:
        """The largest internal force of the line at a static state: |f_rest + weight|."""
        return float(np.max(np.abs(f_rest + self.weight)))

    def effective_matrix(self, ev, c_a, c_v, c_f):
        """c_a M + c_f (c_v C + K) on the shared pattern (adds data arrays only)."""
        return self.structure.csr(_newton_data(ev.mass.data, ev.damping.data,
                                               ev.stiffness.data, c_a, c_v, c_f))

    def factorize(self, S):
        """Banded Cholesky (LAPACK dpbtrf, :class:`BandedCholesky`, which caches unit-vector
        solves) of a matrix on the model's pattern: the DOF numbering keeps the
        bandwidth at a few stations whatever the line length. Falls back to sparse LU if the
        matrix is not positive definite."""
        st = self.structure
        if sp.issparse(S) and S.shape == (st.n_free, st.n_free) and S.nnz == st.nnz:
            solve = BandedCholesky.factor(st.lower_band(S.tocsr().data))
            if solve is not None:
                return solve
        lu = spla.splu(sp.csc_matrix(S))
        return lu.solve

    def commit(self, t, q, v, a, inputs) -> None:
        if self._compiled is not None:
            self._slack_committed = self._compiled.compressed(q, self.mesh.dropper_bars)
            return
        S = self.structure
        N = S.bars.axial_forces(S.full(q), tension_only=False)[self.mesh.dropper_bars]
        self._slack_committed = N < 0.0

    def get_internal_state(self):
        return {"slack": self._slack_committed.copy()}

    def set_internal_state(self, state) -> None:
        if state is None:
            self._slack_committed = np.zeros(len(self.mesh.dropper_bars), dtype=bool)
        else:
            self._slack_committed = np.array(state["slack"], dtype=bool).copy()


@njit(cache=True)
def _wire_point(dofs, w, dw, q, v):
    """(w . q[dofs], w . v[dofs], dw . q[dofs]) of one contact point (3.13)."""
    z = 0.0
    vz = 0.0
    slope = 0.0
    for i in range(dofs.shape[0]):
        j = dofs[i]
        z += w[i] * q[j]
        vz += w[i] * v[j]
        slope += dw[i] * q[j]
    return z, vz, slope


@njit(cache=True)
def _newton_data(M, C, K, c_a, c_v, c_f):
    """c_a M + c_f (c_v C + K), entry by entry, of matrices on one pattern."""
    out = np.empty(M.shape[0])
    for i in range(M.shape[0]):
        out[i] = c_a * M[i] + c_f * (c_v * C[i] + K[i])
    return out

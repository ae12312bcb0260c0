"""The linear catenary on its modes below a cutoff, with static corrections at its interfaces.

Coordinates y = [eta (m modal), zeta (one per dropper), xi (one per pantograph)]:

    q - q_static = Phi eta + Q zeta + psi(t) G(t)^-1 xi

(:mod:`.modal_residual`): Phi the modes below the cutoff (thesis 3.3, K0 phi = omega^2 M phi),
Q the droppers' residual shapes, psi(t) = R_perp N(t) the residual shapes of the contact
points (N(t) the interpolation (3.13) at the pantographs), G = N^T psi. All three are K0- and
M-orthogonal, so the stiffness stays diagonal:

    eta'' + (alpha + beta omega^2) eta' + omega^2 eta = Phi^T f,
    k (zeta + beta zeta') = Q^T f,        G^-1 xi = N^T f,

f = sum_k N_k F_k + sum_{d slack} b_d N_d (the contact forces and the forces the slack
droppers no longer carry, :mod:`.linear_droppers`). zeta and xi are quasi-static (the
residual's inertia is left out); zeta keeps the stiffness-proportional Rayleigh damping
(3.1), so that a slack dropper's damping share leaves consistently. The static response is
exact: for any pantograph position and any set of slack droppers it equals the linear
model's; a slack dropper's force N_d = N0_d + k_a,d b_d . q is exactly zero. The droppers'
elongations T y (T = [B Phi, B Q, 0]) are constant rows, and xi leaves them alone; the
contact height is z_w = phi(x) eta + (Q^T N) zeta + xi. Per step the cost is
O((modes + droppers) x (pantographs + droppers)), independent of the finite-element DOFs;
the closed-form step is :mod:`.modal_step`, the cutoff study docs/modal-cutoff.md.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from ..core.errors import ConvergenceError, ParameterError
from ..core.model import Evaluation, SecondOrderModel
from .linear import LinearCatenary
from . import modal_kernels as _k
from .modal_basis import modes_below
from .modal_residual import InterfaceFlexibility
from .modal_step import ModalSolve
from .model import CatenaryModel
from ..core.disk_cache import cached

#: modes kept above the cutoff per static-correction coordinate (a dropper, a contact
#: point): with fewer the residual flexibility is round-off (docs/modal-cutoff.md)
SPARE_MODES = 2
#: coefficient sets (time steps) whose shared Woodbury pieces are kept
KEPT_BASES = 4


def kept_modes_below(lin: LinearCatenary, cutoff_hz: float, bands, max_modes: int):
    """:func:`~.modal_basis.modes_below` of the linear model's (K0, M) ``bands``, at most
    ``max_modes``, kept in the set-up cache (:mod:`pantocosim.core.disk_cache`) under the bands
    and the cutoff: the band eigensolution is most of the modal model's set-up."""
    def compute():
        f, phi = modes_below(lin.K0, lin.M, cutoff_hz, max_modes=max_modes, bands=bands)
        return {"frequencies": f, "Phi": phi}

    key = (bands[0], bands[1], float(cutoff_hz), int(max_modes))
    basis = cached("modal-basis", key, compute)
    return basis["frequencies"], basis["Phi"]


class ModalCatenary(SecondOrderModel):
    """``ModalCatenary(catenary, x0, speed, cutoff_hz=...)``, or around a ``linear`` model."""

    name = "modal"
    #: its HHT steps are taken in closed form (:class:`~.modal_step.ModalHHT`)
    stepping = "modal"

    def __init__(self, catenary=None, x0=(0.0,), speed: float = 0.0, *, cutoff_hz: float = 20.0,
                 element_size=None, linear: LinearCatenary | None = None,
                 keep_basis: bool = False):
        lin = self.linear = linear or LinearCatenary(catenary, x0, speed,
                                                      element_size=element_size)
        self.cutoff_hz = float(cutoff_hz)
        S = lin.structure
        spare = len(lin.droppers) + len(lin.x0)    # the static correction's coordinates
        bands = (S.lower_band(lin.K0_data), S.lower_band(S.M_data))
        self.frequencies, self.Phi = kept_modes_below(lin, self.cutoff_hz, bands,
                                                      lin.n_dofs - SPARE_MODES * spare)
        self.omega2 = (2.0 * np.pi * self.frequencies) ** 2
        self.m = m = self.Phi.shape[1]
        self.n_p = len(lin.x0)
        self.x0, self.speed = lin.x0, lin.speed
        self.definition, self.mesh, self.structure = lin.definition, lin.mesh, lin.structure
        dr = self.droppers = lin.droppers
        #: a complete basis leaves no residual: no zeta, no xi
        self.corrected = m < lin.n_dofs
        seps = [a - b for a in self.x0 for b in self.x0]
        flex = self.flex = self._flexibility(seps)
        self.nz = len(dr) if self.corrected else 0
        self.nx = self.n_p if self.corrected else 0
        self.n_dofs = m + self.nz + self.nx
        self.kbar = flex.kbar
        self.zeta_c = lin.alpha_r + lin.beta_r * self.omega2       # Phi^T C Phi (diagonal)
        self.r0 = np.concatenate([self.Phi.T @ lin.r0, flex.Q_r0[:self.nz],
                                  np.zeros(self.nx)])
        if not keep_basis:          # the modes on every DOF: only checks need them
            self.Phi = None
        #: dropper elongations b_d . (q - q_static) = T @ y (constant rows; xi: zero)
        self.T = np.zeros((len(dr), self.n_dofs))
        self.T[:, :m] = flex.B_phi
        self.T[:, m:m + self.nz] = flex.B_Q[:, :self.nz]
        self.T_K = np.ascontiguousarray(self.T[:, :m + self.nz])
        self.q_static = np.zeros(self.n_dofs)
        self._slack_committed = np.zeros(len(dr), dtype=bool)
        self._bases = {}
        self._init_geometry()
        _k.warm_up()

    def _flexibility(self, separations) -> InterfaceFlexibility:
        """The interfaces' modal and residual tables (:mod:`.modal_residual`); a cutoff whose
        modes above leave the residual singular is refused."""
        try:
            return InterfaceFlexibility(self.linear, self.Phi, self.omega2, separations,
                                        residual=self.corrected)
        except np.linalg.LinAlgError:
            raise ParameterError("modal_cutoff_hz", self.cutoff_hz, f"the "
                                 f"{self.linear.n_dofs - self.m} modes above it leave the "
                                 "static correction singular; accepted: > 0 and below "
                                 f"{self.frequencies[-1]:.6g} Hz") from None

    # ------------------------------------------------------------------ delegated geometry
    @property
    def n_modes(self) -> int:
        """Number of modes kept (the run summary's ``catenary_modes``)."""
        return self.m

    def positions(self, t):
        return self.linear.positions(t)

    @property
    def support_x(self):
        return self.linear.support_x

    wire_height = CatenaryModel.wire_height
    wire_velocity = CatenaryModel.wire_velocity
    wire_state = CatenaryModel.wire_state

    # ------------------------------------------------------------------ moving correction
    def _init_geometry(self):
        """Persistent buffers of the contact points (refilled for each new time)."""
        npan, N, m, nz = self.n_p, self.n_dofs, self.m, self.nz
        loc = self.linear.locator
        self._loc = (np.ascontiguousarray(loc.x_start), np.ascontiguousarray(loc.x_end),
                     np.ascontiguousarray(loc.E_x), np.ascontiguousarray(loc.Le),
                     np.ascontiguousarray(self.flex.elem_s),
                     np.ascontiguousarray(loc.x_full_ref[loc.z_full_dofs]))
        g = self._g = SimpleNamespace(
            t=None, S_idx=np.zeros((npan, 4), np.int64), w=np.zeros((npan, 4)),
            dw=np.zeros((npan, 4)), offset=np.zeros(npan), doffset=np.zeros(npan),
            Wc=np.zeros((npan, N)), Wcx=np.zeros((npan, N)), G=np.zeros((self.nx, self.nx)),
            Ginv=np.zeros((self.nx, self.nx)))
        g.phi, g.phix = g.Wc[:, :m], g.Wcx[:, :m]
        g.qd, g.qdx = g.Wc[:, m:m + nz], g.Wcx[:, m:m + nz]
        for k in range(self.nx):
            g.Wc[k, m + nz + k] = 1.0
        flex = self.flex
        self._Q_S = np.ascontiguousarray(flex.Q_S[:, :nz])
        self._Q_sup = np.ascontiguousarray(flex.Q_sup[:, :nz])
        self._inv_omega2 = 1.0 / self.omega2
        self._uplift_work = (np.zeros(self.m + nz), np.zeros(self.nx))
        dofs = self.contact_dofs = np.arange(N)
        g.points = [SimpleNamespace(dofs=dofs, weights=g.Wc[k], dweights_dx=g.Wcx[k],
                                    offset=0.0, doffset_dx=0.0, element=-1)
                    for k in range(npan)]

    def geometry(self, t: float):
        """The contact points in y (weights [phi(x), Q^T N, e_k]) and G(t), G(t)^-1 of the
        contact residual at time t. The buffers are the model's: valid until another time
        is asked for."""
        t = float(t)
        g = self._g
        if g.t == t:
            return g
        xs = self.linear.x0 + self.speed * t
        lo, hi = self._loc[0][0], self._loc[1][-1]
        for x in xs:
            if not lo - 1e-9 <= x <= hi + 1e-9:
                self.linear.locator.locate(float(x))      # raises the ParameterError
        e = _k.locate_points(xs, *self._loc, g.S_idx, g.w, g.dw, g.offset, g.doffset)
        flex = self.flex
        _k.point_rows(g.S_idx, g.w, g.dw, flex.Phi_S, self._Q_S, g.phi, g.phix, g.qd, g.qdx)
        if self.nx and not _k.residual_flexibility(g.S_idx, g.w, flex.C_band, flex.band,
                                                   g.phi, self._inv_omega2, g.qd, self.kbar,
                                                   g.G, g.Ginv):
            raise ValueError("modal catenary: pantographs farther apart than the residual "
                             "tables cover")
        for k, p in enumerate(g.points):
            p.offset, p.doffset_dx = float(g.offset[k]), float(g.doffset[k])
            p.element = int(self.linear.locator.elems[e[k]])
        g.t = t
        return g

    #: the cutoff sets the static correction, hence :meth:`contact_compliance`
    compliance_setting = "modal_cutoff_hz"

    def contact_compliance(self, times) -> np.ndarray:
        """G(t) of the contact points' static correction at each time [m/N] (pantographs x
        pantographs): xi follows the contact forces at once (G^-1 xi = N^T f has neither
        mass nor damping), a massless spring in series with the contact (docs/stability.md).
        The droppers' residual zeta is not instantaneous (its Rayleigh share beta k damps
        it); a complete basis has no residual: zero. The geometry buffers are left at the
        time they held."""
        times = np.atleast_1d(np.asarray(times, dtype=float))
        out = np.zeros((times.size, self.n_p, self.n_p))
        if not self.nx:
            return out
        held = self._g.t
        for i, t in enumerate(times):
            out[i] = self.geometry(t).G
        if held is not None:
            self.geometry(held)
        return out

    def contact_points(self, t: float):
        return self.geometry(t).points

    # ------------------------------------------------------------------ model interface
    def input_vector(self, t, inputs) -> np.ndarray:
        F = np.atleast_1d(np.asarray(inputs, dtype=float))
        return self.geometry(t).Wc.T @ F

    def _dropper_forces(self, y, v):
        dr = self.droppers
        N = dr.N0 + dr.ka * (self.T @ y)
        slack = dr.slack(N)
        return self.slack_forces(y, v, slack, self._slack_committed), slack, N

    def dropper_slack(self, y) -> np.ndarray:
        """The droppers slack at y."""
        k = self.m + self.nz
        return self.droppers.slack(self.droppers.N0 + self.droppers.ka * (
            self.T[:, :k] @ y[:k]))

    def slack_forces(self, y, v, slack, committed) -> np.ndarray:
        """The forces the droppers no longer carry: sum_{slack} N_d t_d (N_d at y) and the
        committed ones' damping share sum beta k_a (t_d . v) t_d, on y."""
        dr = self.droppers
        out = np.zeros(self.n_dofs)
        if slack.any() or committed.any():
            _k.slack_forces(self.T_K, dr.N0, dr.ka, dr.beta, slack, committed,
                            np.ascontiguousarray(y, dtype=float),
                            np.ascontiguousarray(v, dtype=float), out)
        return out

    def woodbury_base(self, c_a, c_v, c_f) -> tuple:
        """(1 / diag, U = T_K diag^-1, T_K diag^-1 T_K^T) of the Newton matrix's diagonal
        part c_a + c_f (c_v zeta + omega^2) on eta, c_f k (1 + c_v beta) on zeta (1 when
        c_f = 0): the pieces every slack set's Woodbury solve shares (the last
        :data:`KEPT_BASES` coefficient sets kept)."""
        key = (float(c_a), float(c_v), float(c_f))
        kept = self._bases
        if key in kept:
            return kept[key]
        m = self.m
        d = np.empty(m + self.nz)
        d[:m] = c_a + c_f * (c_v * self.zeta_c + self.omega2)
        d[m:] = c_f * self.kbar * (1.0 + c_v * self.linear.beta_r) if c_f else 1.0
        inv_diag = 1.0 / d
        U = self.T_K * inv_diag
        base = kept[key] = (inv_diag, U, self.T_K @ U.T)
        if len(kept) > KEPT_BASES:
            del kept[next(iter(kept))]
        return base

    def evaluate(self, t, q, v, a, inputs, tangent=True) -> Evaluation:
        g = self.geometry(t)
        m, nz = self.m, self.nz
        removed, slack, _ = self._dropper_forces(q, v)
        f_rest = np.empty(self.n_dofs)
        f_rest[:m] = self.zeta_c * v[:m] + self.omega2 * q[:m]
        f_rest[m:m + nz] = self.kbar * (q[m:m + nz] + self.linear.beta_r * v[m:m + nz])
        f_rest[m + nz:] = g.Ginv @ q[m + nz:]
        f_rest += self.r0
        f_rest -= removed
        if inputs is not None:
            f_rest -= self.input_vector(t, inputs)
        f_in = np.zeros(self.n_dofs)
        f_in[:m] = a[:m]
        ev = Evaluation(f_inertia=f_in, f_rest=f_rest,
                        structure_key=(slack.tobytes(), self._slack_committed.tobytes()))
        ev.slack_sets = (slack, self._slack_committed.copy())
        return ev

    def effective_matrix(self, ev, c_a, c_v, c_f):
        rows, s = self.droppers.removed_stiffness(*ev.slack_sets, c_v, c_f)
        return SimpleNamespace(c=(c_a, c_v, c_f), rows=rows, s=s)

    def factorize(self, S):
        """Solve with diag(c_a + c_f (c_v zeta + omega^2)) on eta, c_f k on zeta, c_f G^-1
        on xi (G at the latest evaluated time), minus the slack droppers' rank-one terms
        (Woodbury)."""
        return ModalSolve(self, *S.c, S.rows, S.s)

    def commit(self, t, q, v, a, inputs) -> None:
        self._slack_committed = self._dropper_forces(q, v)[1]

    def get_internal_state(self):
        return {"slack": self._slack_committed.copy()}

    def set_internal_state(self, state) -> None:
        n = len(self.droppers)
        self._slack_committed = (np.zeros(n, dtype=bool) if state is None
                                 else np.array(state["slack"], dtype=bool).copy())

    # ------------------------------------------------------------------ results
    def dropper_forces(self, q) -> np.ndarray:
        N = self.droppers.N0 + self.droppers.ka * (self.T @ q)
        return np.where(self.droppers.slack(N), 0.0, N)

    def support_uplift(self, q) -> np.ndarray:
        """Uplift at the supports (modes, droppers' residual, contact residual at the
        latest evaluated time)."""
        g = self._g if self._g.t is not None else self.geometry(0.0)
        out = np.empty(self.flex.sup.size)
        yt, c = self._uplift_work
        _k.support_uplift(self.flex.Phi_sup, self._Q_sup, self.flex.C_sup, self._inv_omega2,
                          float(self.kbar), g.S_idx, g.w, g.phi, g.qd, g.Ginv,
                          np.ascontiguousarray(q, dtype=float), self.m, self.nz, self.nx, yt,
                          c, out)
        return out

    def full_displacement(self, t, q) -> np.ndarray:
        """q_full - q_static on the linear model's DOFs (for checks; O(DOFs); a model built
        with ``keep_basis=True``)."""
        if self.Phi is None:
            raise ValueError("full_displacement needs ModalCatenary(..., keep_basis=True)")
        lin, m, nz = self.linear, self.m, self.nz
        out = self.Phi @ q[:m]
        if nz:
            Q = self.flex.Q_full(lin, self.Phi)
            out += Q @ q[m:m + nz]
        if self.nx:
            g = self.geometry(t)
            solve = lin._factor_cache(0.0, 0.0, 1.0).solve
            for k, cp in enumerate(list(lin.contact_points(t))):
                Nk = np.zeros(lin.n_dofs)
                Nk[cp.dofs] = cp.weights
                psi = np.asarray(solve(Nk)).ravel() - self.Phi @ (g.phi[k] / self.omega2)
                if nz:
                    psi -= Q @ g.qd[k] / self.kbar
                out += psi * (g.Ginv[k] @ q[m + nz:])
        return out

    def static_state(self, forces=None, t: float = 0.0, max_iter: int = 50) -> np.ndarray:
        """Static equilibrium in y under the pantographs' forces (slack set included)."""
        y = np.zeros(self.n_dofs)
        if forces is None:
            return y
        F = np.broadcast_to(np.asarray(forces, float), self.x0.shape)
        zero = np.zeros(self.n_dofs)
        saved, self._slack_committed = self._slack_committed, np.zeros(len(self.droppers), bool)
        try:
            used = None
            for _ in range(max_iter):
                ev = self.evaluate(t, y, zero, zero, F)
                if used is not None and np.array_equal(used, ev.slack_sets[0]):
                    return y
                y = y - self.factorize(self.effective_matrix(ev, 0.0, 0.0, 1.0))(ev.f_rest)
                used = ev.slack_sets[0]
        finally:
            self._slack_committed = saved
        raise ConvergenceError("modal catenary statics: the slack set did not settle")

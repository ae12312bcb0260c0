"""Lumped-mass pantographs: a vertical chain of n masses (head first) on springs and dampers.

    head m1 -k1/c1- m2 -k2/c2- ... - mn -kn/cn- ground (reference height h_ref(t))

Coordinates are the absolute heights of the masses above the rail. Forces are net of the
weights (as in EN 50318-type reference models): the uplift F_up(t) = ramp(t) * (static +
aerodynamic) acts on the ``uplift_mass``, the contact force F pushes the head down. Options as
the rigid model: collector friction between head and the mass below (2.16), one-way ground
damper, ramp raising that weights the uplift and the reference height (thesis 3.3.1).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from ..core.errors import ParameterError
from ..core.model import Evaluation, LinearForm
from ..core.params import Table, load_toml
from ..core.schema import OPTIONAL, Field, Section
from .base import PantographModel, PantographOptions, smooth_friction


@dataclass
class ChainParameters:
    masses: np.ndarray
    stiffness: np.ndarray
    damping: np.ndarray
    names: tuple[str, ...]
    uplift_mass: int = -1  # 0-based index
    working_height: float = 5.3

    def validate(self, source: str | None = None) -> None:
        n = len(self.masses)
        if n < 1:
            raise ParameterError("chain.masses", list(self.masses), "needs at least one mass",
                                 source)
        for key, arr in (("stiffness", self.stiffness), ("damping", self.damping)):
            if len(arr) != n:
                raise ParameterError(f"chain.{key}", list(arr),
                                     f"must have {n} entries (one per mass)", source)
        for i, m in enumerate(self.masses):
            if not np.isfinite(m) or m <= 0:
                raise ParameterError(f"chain.masses[{i}]", float(m), "must be > 0", source)
        for key, arr in (("stiffness", self.stiffness), ("damping", self.damping)):
            for i, x in enumerate(arr):
                if not np.isfinite(x) or x < 0:
                    raise ParameterError(f"chain.{key}[{i}]", float(x), "must be >= 0", source)
        for i, k in enumerate(self.stiffness[:-1]):
            if k <= 0:
                raise ParameterError(f"chain.stiffness[{i}]", float(k),
                                     "springs between masses must be > 0", source)
        if not (-n <= self.uplift_mass < n):
            raise ParameterError("chain.uplift_mass", self.uplift_mass + 1,
                                 f"must be between 1 and {n}", source)
        if not np.isfinite(self.working_height) or self.working_height <= 0:
            raise ParameterError("chain.working_height", self.working_height, "must be > 0",
                                 source)


class LumpedPantograph(PantographModel):
    """n-mass chain pantograph on the common pantograph interface."""

    def __init__(self, params: ChainParameters, options: PantographOptions | None = None,
                 name: str = "lumped"):
        super().__init__(options)
        params.validate(name)
        self.params = params
        self.name = name
        self.n_dofs = len(params.masses)
        self.dof_names = tuple(params.names)
        n = self.n_dofs
        self._M = np.diag(np.asarray(params.masses, dtype=float))
        k = np.asarray(params.stiffness, dtype=float)
        self._K = _chain_matrix(k)
        self._c = np.asarray(params.damping, dtype=float)
        self._C_two_way = _chain_matrix(self._c)
        c_up = self._c.copy()
        c_up[-1] = 0.0
        self._C_up = _chain_matrix(c_up)
        self._gradient = np.zeros(n)
        self._gradient[0] = 1.0
        self._e_uplift = np.zeros(n)
        self._e_uplift[params.uplift_mass] = 1.0
        self._e_ground = np.zeros(n)
        self._e_ground[-1] = 1.0
        self.reference_height = params.working_height
        self.lowered_reference = params.working_height

    # --- port contract -------------------------------------------------------------------
    @property
    def working_height(self) -> float:
        """Contact height of the parameter file [m] (the chain is linear about it)."""
        return self.params.working_height

    def contact_height(self, q):
        return float(q[0])

    def contact_height_gradient(self, q):
        return self._gradient

    def contact_velocity(self, q, v):
        return float(v[0])

    # --- loading -------------------------------------------------------------------------
    def reference(self, t: float) -> float:
        """Ground-spring reference height h_ref(t), weighted by the ramp factor (3.3.1)."""
        ramp = self.options.ramp
        if ramp is None:
            return self.reference_height
        f = ramp.factor(t)
        return self.lowered_reference + f * (self.reference_height - self.lowered_reference)

    def uplift_force(self, t: float) -> float:
        ramp = self.options.ramp
        f = 1.0 if ramp is None else ramp.factor(t)
        return f * self.options.mean_uplift

    def evaluate(self, t, q, v, a, inputs, tangent=True):
        F = 0.0 if inputs is None else float(inputs[0])
        kn = self.params.stiffness[-1]
        C = self._C_two_way
        if self.options.one_way_damper and v[-1] > 0.0:
            C = self._C_up  # ground damper idle while the mechanism moves up
        f_rest = C @ v + self._K @ q
        f_rest[-1] -= kn * self.reference(t)
        f_rest -= self.uplift_force(t) * self._e_uplift
        f_rest[0] += F
        damping = C
        fr = self.options.friction_force
        if fr > 0.0 and self.n_dofs > 1:
            force, dforce = smooth_friction(v[0] - v[1], fr, self.options.friction_smoothing)
            f_rest[0] += force
            f_rest[1] -= force
            damping = C.copy()
            damping[0, 0] += dforce
            damping[0, 1] -= dforce
            damping[1, 0] -= dforce
            damping[1, 1] += dforce
        return Evaluation(f_inertia=self._M @ a, f_rest=f_rest, mass=self._M, inertia_q=None,
                          damping=damping, stiffness=self._K)

    def linear_form(self):
        """Constant M, C, K without collector friction and one-way damper: f_rest = C v + K q
        + B w with w = (h_ref(t), F_up(t), F) (the forces of :meth:`evaluate`)."""
        o = self.options
        if o.one_way_damper or (o.friction_force > 0.0 and self.n_dofs > 1):
            return None
        B = np.column_stack([-self.params.stiffness[-1] * self._e_ground, -self._e_uplift,
                             self._gradient])
        return LinearForm(M=self._M, C=self._C_two_way, K=self._K, B=B, fill=self._fill_load)

    def _fill_load(self, t, inputs, w):
        ramp = self.options.ramp
        if ramp is None:
            w[0] = self.reference_height
            w[1] = self.options.mean_uplift
        else:
            w[0] = self.reference(t)
            w[1] = self.uplift_force(t)
        w[2] = 0.0 if inputs is None else inputs[0]

    # --- initial states ------------------------------------------------------------------
    def static_equilibrium(self, contact_force=None, height=None):
        """Heights of the masses in equilibrium under the contact force F with the head at
        ``height``; sets the reference height h_ref accordingly."""
        F = self.options.mean_uplift if contact_force is None else float(contact_force)
        h = self.params.working_height if height is None else float(height)
        z, self.reference_height = self.equilibrium(F, h)
        if self.options.ramp is None:
            self.lowered_reference = self.reference_height
        return z

    def equilibrium(self, contact_force: float, height: float) -> tuple[np.ndarray, float]:
        """(heights of the masses, reference height h_ref) in equilibrium under the contact
        force F with the head at ``height`` (nothing is set)."""
        F, h = float(contact_force), float(height)
        if not np.isfinite(F) or F < 0:
            raise ParameterError("contact_force", contact_force, "must be finite and >= 0",
                                 self.name)
        if not np.isfinite(h) or h <= 0:
            raise ParameterError("height", height, "must be > 0", self.name)
        n = self.n_dofs
        uplift = self.options.mean_uplift
        k = np.asarray(self.params.stiffness, dtype=float)
        # load carried by spring i (between mass i and the one below): contact force F above
        # the uplift mass, F - uplift below it; the ground spring carries F - uplift.
        u = self.params.uplift_mass % n
        carried = np.where(np.arange(n) < u, F, F - uplift)
        if k[-1] == 0.0:
            if abs(F - uplift) > 1e-12 * max(1.0, uplift):
                raise ParameterError("contact_force", F,
                                     "no equilibrium: the ground spring is zero and F differs "
                                     f"from the uplift {uplift:.6g} N", self.name)
            carried[-1] = 0.0
            k = k.copy()
            k[-1] = 1.0
        # spring i is compressed by carried[i]: z_i - z_{i+1} = -carried[i] / k_i
        z = np.empty(n)
        z[0] = h
        for i in range(n - 1):
            z[i + 1] = z[i] + carried[i] / k[i]
        return z, z[-1] + carried[-1] / k[-1]

    def lowered_equilibrium(self, height):
        """All masses at the lowered height with no load (ramp start, thesis 3.3.1)."""
        h = float(height)
        if not np.isfinite(h) or h <= 0:
            raise ParameterError("ramp.lowered_height", height, "must be > 0", self.name)
        self.lowered_reference = h
        return np.full(self.n_dofs, h)


def _chain_matrix(k: np.ndarray) -> np.ndarray:
    """Tridiagonal matrix of a chain: element i joins mass i and i+1, the last joins ground."""
    n = len(k)
    K = np.zeros((n, n))
    for i in range(n):
        K[i, i] += k[i]
        if i + 1 < n:
            K[i + 1, i + 1] += k[i]
            K[i, i + 1] -= k[i]
            K[i + 1, i] -= k[i]
    return K


#: the declared fields of a lumped-mass parameter file
ROOT = Section("", [
    Field("name", "string", default=OPTIONAL, doc="model name (default: the file's name)"),
    Field("description", "string", default="", doc="free text"),
], extra=("chain", "options"))
CHAIN = Section("chain", [
    Field("masses", "numbers", unit="kg", positive=True, doc="masses from the head (mass 1, "
          "in contact) down to the frame"),
    Field("stiffness", "numbers", unit="N/m", nonnegative=True, rule="one per mass",
          doc="spring k_i between mass i and mass i+1 (the last one to the roof)"),
    Field("damping", "numbers", unit="N s/m", nonnegative=True, rule="one per mass",
          doc="damper c_i beside spring k_i"),
    Field("names", "any", default=OPTIONAL, rule="one string per mass",
          doc='labels of the masses (default "mass 1", ...)'),
    Field("uplift_mass", "integer", default=OPTIONAL, minimum=1, rule="at most the number "
          "of masses", doc="mass (1 = head) that carries the uplift force (default: the "
          "last)"),
    Field("working_height", unit="m", positive=True, doc="contact height of the static "
          "start"),
], doc="A chain of masses joined by springs and dampers; the first mass is the head.")


def read_chain(path: str | Path) -> tuple[ChainParameters, Table]:
    """Read and validate a lumped-mass parameter file; returns (ChainParameters, root Table)."""
    source = str(path)
    data = load_toml(path)
    root = Table(data, source)
    ROOT.check_keys(root)
    chain = root.sub("chain")
    CHAIN.check_keys(chain)
    masses = CHAIN.read(chain, "masses")
    n = len(masses)
    names = chain._get("names", [f"mass {i + 1}" for i in range(n)], required=False)
    if not isinstance(names, list) or len(names) != n or not all(isinstance(s, str) for s in names):
        raise ParameterError("chain.names", names, f"must be {n} strings", source)
    uplift = CHAIN.read(chain, "uplift_mass")
    uplift = n if uplift is None else uplift
    if uplift > n:
        raise ParameterError("chain.uplift_mass", uplift, f"must be between 1 and {n}", source)
    params = ChainParameters(
        masses=np.array(masses),
        stiffness=np.array(replace(CHAIN["stiffness"], length=n).read(chain)),
        damping=np.array(replace(CHAIN["damping"], length=n).read(chain)),
        names=tuple(names), uplift_mass=uplift - 1,
        working_height=CHAIN.read(chain, "working_height"))
    params.validate(source)
    return params, root


def load_chain(path: str | Path, options: PantographOptions | None = None
               ) -> LumpedPantograph:
    """Load a lumped-mass parameter file (``[chain]`` and ``[options]`` tables)."""
    params, root = read_chain(path)
    if options is None:
        options = PantographOptions.from_table(root.sub("options", required=False))
    name = ROOT.read(root, "name")
    name = Path(path).stem if name is None else name
    return LumpedPantograph(params, options, name=name)

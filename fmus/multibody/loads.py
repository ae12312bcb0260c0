"""Loads on nodes: gravity, nodal forces and nodal moments (the torque pulse of the pendulum paper,
Fig. 2a).

A moment m acting on a node does the virtual work m . delta theta, and with directors
delta theta = 1/2 sum_i d_i x delta d_i, so its generalised force on director d_i is
Q_i = 1/2 m x d_i (a configuration-dependent load; its power is m . omega with
omega = 1/2 sum_i d_i x d_i'). ``scale`` multiplies a load (load stepping in statics).
"""

from __future__ import annotations

import numpy as np

from ..core.scatter import scatter_add
from .component import Component


def _skew(m):
    return np.array([[0.0, -m[2], m[1]], [m[2], 0.0, -m[0]], [-m[1], m[0], 0.0]])


def _as_function(value):
    if callable(value):
        return value
    const = np.asarray(value, dtype=float)
    return lambda t: const


class Gravity(Component):
    """Weight of every mass of the system, f = M u_g with u_g = g at the position coordinates
    (exact consistent load since the shape functions sum to one); potential -f . x."""

    def __init__(self, g=(0.0, -9.81, 0.0)):
        self.g = np.asarray(g, dtype=float)
        self.scale = 1.0

    def bind(self, system) -> None:
        self._system = system
        self._f = None

    def _load(self):
        sysm = self._system
        if self._f is None:   # after assembly, once every mass is in M
            u = np.zeros(sysm.n_q)
            u.reshape(-1, 12)[:, :3] = self.g
            self._f = sysm.M @ u
        return self._f

    def add_forces(self, t, q, v, f, K, C) -> None:
        f -= self.scale * self._load()

    def energy(self, t, q, v) -> dict:
        return {"gravity": -float(self.scale * self._load() @ q)}


class NodalForce(Component):
    """A force F(t) (vector or function of t) on a node's position; potential -F.x when
    constant."""

    def __init__(self, node: int, force):
        self.node = node
        self.force = _as_function(force)
        self.scale = 1.0

    def bind(self, system) -> None:
        self.dofs = system.x_dofs(self.node)

    def add_forces(self, t, q, v, f, K, C) -> None:
        f[self.dofs] -= self.scale * self.force(t)

    def powers(self, t, q, v) -> dict:
        return {"external": float(self.scale * self.force(t) @ v[self.dofs])}


class NodalMoment(Component):
    """A moment m(t) (spatial components, vector or function of t) on a node's triad."""

    def __init__(self, node: int, moment, name: str = "moment"):
        self.node = node
        self.moment = _as_function(moment)
        self.scale = 1.0
        self.name = name

    def bind(self, system) -> None:
        self.dofs = [system.d_dofs(self.node, i) for i in range(3)]

    def tangent_dofs(self) -> np.ndarray:
        return np.concatenate(self.dofs)[None, :]

    def locate(self, pattern) -> None:
        self.pos = np.concatenate([pattern.positions(d[:, None], d[None, :]).ravel()
                                   for d in self.dofs])

    def add_forces(self, t, q, v, f, K, C) -> None:
        m = self.scale * np.asarray(self.moment(t), dtype=float)
        if not np.any(m):
            return
        S = 0.5 * _skew(m)
        for d in self.dofs:
            f[d] -= S @ q[d]
        if K is not None:
            scatter_add(K.data, self.pos, np.tile(-S.ravel(), 3))

    def angular_velocity(self, q, v) -> np.ndarray:
        return 0.5 * sum(np.cross(q[d], v[d]) for d in self.dofs)

    def powers(self, t, q, v) -> dict:
        m = self.scale * np.asarray(self.moment(t), dtype=float)
        return {"external": float(m @ self.angular_velocity(q, v))}


def triangular_pulse(peak: float, duration: float, axis=(0.0, 0.0, 1.0)):
    """m(t) = peak * axis * tri(t): 0 at t = 0, peak at duration/2, 0 from duration on
    (our reading of the 'delta-like' torque of the pendulum paper, Fig. 2a)."""
    axis = np.asarray(axis, dtype=float)

    def m(t):
        if t <= 0.0 or t >= duration:
            return 0.0 * axis
        x = t / duration
        return peak * (2.0 * x if x < 0.5 else 2.0 * (1.0 - x)) * axis

    return m

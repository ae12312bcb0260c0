"""The component protocol of the multibody system: what a beam, a body, a load, a joint or a
contact gives the :class:`~.system.System`. Every member has a default that adds nothing, so
a component defines only what it contributes and the system calls every member of every
component.

| member | called | does |
|---|---|---|
| ``bind(system)`` | at assembly | keeps its coordinates, precomputes |
| ``add_mass(M)`` | at assembly | adds its constant mass blocks (:class:`~.triplets.Triplets`) |
| ``constraints(system)`` | at assembly | its :class:`~.constraint_set.ConstraintSet` list |
| ``tangent_dofs()`` | at assembly | (k, m) coordinate groups its tangent couples, or None |
| ``locate(pattern)`` | at assembly | keeps the positions of its blocks on the pattern |
| ``add_forces(t, q, v, f, K, C)`` | every evaluation | adds forces to f, tangents to K, C |
| ``state_key(q)`` | every evaluation | a hashable state the tangent depends on (contact) |
| ``energy(t, q, v)`` | reports | named potentials |
"""

from __future__ import annotations


class Component:
    """A part of a multibody system; the defaults contribute nothing."""

    def bind(self, system) -> None:
        """Keep the system's coordinates of this component."""

    def add_mass(self, M) -> None:
        """Add constant mass blocks to the triplets ``M``."""

    def constraints(self, system) -> list:
        """The constraint sets this component imposes."""
        return []

    def tangent_dofs(self):
        """(k, m) coordinate groups the tangent couples, or None without a tangent."""
        return None

    def locate(self, pattern) -> None:
        """Keep the positions of the tangent blocks on the system's pattern."""

    def add_forces(self, t, q, v, f, K, C) -> None:
        """Add forces to f and their tangents to K (stiffness) and C (damping)."""

    def state_key(self, q):
        """A hashable state the tangent depends on (None: none)."""
        return None

    def energy(self, t, q, v) -> dict:
        """Named potentials at (t, q, v)."""
        return {}

"""Explicit parallel (Jacobi) coupling: every participant steps with the contact forces
predicted at t + h from the law's values at the last communication points."""

from __future__ import annotations

from .base import Scheme


class Jacobi(Scheme):
    name = "jacobi"
    aliases = ("explicit",)

    def step(self, coupler, t, h, states):
        F = coupler.predicted_forces(t, h)
        coupler.set_all(F)
        coupler.step_all(t, h)
        return F, 1

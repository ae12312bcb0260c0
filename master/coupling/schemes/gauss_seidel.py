"""Explicit serial (Gauss-Seidel) coupling: the catenary steps first with the predicted
forces; the pantographs then step with the forces of the new wire against their predicted
heights."""

from __future__ import annotations

from .base import Scheme


class GaussSeidel(Scheme):
    name = "gauss-seidel"

    def step(self, coupler, t, h, states):
        F = coupler.predicted_forces(t, h)
        coupler.cat.set_forces(F)
        coupler.step_catenary(t, h)
        F = coupler.contact_forces(predict_h=h)   # fresh wire, predicted pantograph height
        for k, p in enumerate(coupler.pans):
            p.set_forces(F[k:k + 1])
            p.step(t, h)
        return F, 1

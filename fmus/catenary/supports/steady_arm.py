"""``type = "steady_arm"``: a bar of ``length`` [m], ``mass`` [kg] and ``EA`` [N] from a pin
at the mast to the contact wire, pulled by the stagger. Contact wire only; needs a non-zero
stagger at every intermediate mast. The pin's height and lateral position are unknowns of the
initial configuration: the wire sits at its design height and stagger."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...core.errors import ParameterError
from ...core.schema import Field, Section
from ..parts import Anchor
from .registry import Site, Support, register

DEFAULT_EA = 2.0e7       # N, a stiff arm


@register("steady_arm")
@dataclass(frozen=True)
class SteadyArm(Support):
    length: float
    mass: float
    EA: float = DEFAULT_EA

    wires = ("contact",)
    n_own_nodes = 1          # the pin at the mast

    FIELDS = Section("", [
        Field("length", unit="m", positive=True, doc="arm from the pin at the mast to the "
              "contact wire"),
        Field("mass", unit="kg", nonnegative=True, doc="mass of the arm"),
        Field("EA", unit="N", default=DEFAULT_EA, positive=True, doc="axial stiffness"),
    ], extra=("type",))

    @classmethod
    def from_table(cls, table, wire):
        cls.FIELDS.check_keys(table)
        return cls(**{f.name: f.read(table) for f in cls.FIELDS.fields})

    def check_line(self, stagger, n_spans, source):
        for i in range(1, n_spans):
            if stagger[i % len(stagger)] == 0.0:
                raise ParameterError("geometry.stagger", stagger,
                                     f"a steady arm needs non-zero stagger (support {i + 1})",
                                     source)

    def attach(self, site: Site, parts) -> None:
        S, s = site.structure, site.number
        pdof = site.own_dofs[0]
        S.fixed[pdof] = True
        ys, h_c = site.definition.support_stagger()[s], site.height
        Lt, phi = self._pull(site)
        S.x_full[pdof] = [0.0, ys + np.sign(ys) * Lt * np.cos(phi), h_c + Lt * np.sin(phi)]
        S.offset[pdof[0]] = site.definition.support_x[s]
        b = parts.bar(list(pdof) + list(site.dofs[:3]), self.length, self.EA, self.mass, False)
        parts.anchors.append(Anchor("pin", int(pdof[2]), int(site.dofs[2]), h_c, bar=b, comp=2))
        parts.anchors.append(Anchor("pin", int(pdof[1]), int(site.dofs[1]), ys, bar=b, comp=1))
        parts.arms.append((b, site.own_nodes[0], site.node, ys))

    def _pull(self, site: Site) -> tuple[float, float]:
        """First guess of the arm: length stretched by the estimated pull (the wire's weight
        between the neighbouring droppers and the lateral pull of the stagger) and its angle
        to the horizontal."""
        d, s = site.definition, site.number
        xs, stag = d.support_x, d.support_stagger()
        xsup, ys = xs[s], stag[s]
        dl = xsup - xs[s - 1] - d.dropper_positions[s - 1][-1]
        dr = d.dropper_positions[s][0]
        Fv = d.gravity * (d.contact.mass_per_length * (dl + dr) / 2 + self.mass / 2)
        Fy = d.contact.tension * (abs(ys - stag[s - 1]) / (xsup - xs[s - 1])
                                  + abs(ys - stag[s + 1]) / (xs[s + 1] - xsup))
        phi = np.arctan2(Fv, Fy)
        return self.length * (1.0 + np.hypot(Fv, Fy) / self.EA), phi

"""The mean operating height of each pantograph: where its actuation is set to deliver the
mean uplift (static + aerodynamic).

A pantograph's pneumatic actuation is regulated so that it presses with the target mean force
at its operating height. With a stiff mechanism (the rigid DSA-380 has about 2 kN/m at the
head) that height must be the mean height of the contact wire under the moving pantograph,
which a moving load lifts more than a static one. It is computed here from the catenary
linearised about its static configuration (M, C = alpha M + beta K0, K0) under the constant
mean forces moving at the train speed, integrated with the project's HHT-alpha integrator (one
banded factorization for the whole run), and averaged over the analysis window.
"""

from __future__ import annotations

import numpy as np

from pantocosim.core.hht import HHTIntegrator, HHTSettings
from pantocosim.core.model import Evaluation, SecondOrderModel


class LinearisedCatenary(SecondOrderModel):
    """M a + C v + K0 (q - q_static) = sum_k N_k(t)^T F_k on the catenary's own pattern."""

    def __init__(self, catenary):
        self.cat = catenary
        self.n_dofs = catenary.n_dofs
        st = catenary.structure
        self.M = catenary.M
        self.K0 = st.csr(catenary.K0_data)
        self.C = st.csr(catenary._C_base)
        self.q_static = catenary.q_static

    def evaluate(self, t, q, v, a, inputs, tangent=True):
        f_rest = self.C @ v + self.K0 @ (q - self.q_static) - self.cat.input_vector(t, inputs)
        ev = Evaluation(f_inertia=self.M @ a, f_rest=f_rest, structure_key=0)
        if tangent:
            ev.mass, ev.damping, ev.stiffness = self.M, self.C, self.K0
        return ev

    def effective_matrix(self, ev, c_a, c_v, c_f):
        return self.cat.effective_matrix(ev, c_a, c_v, c_f)

    def factorize(self, S):
        return self.cat.factorize(S)


def mean_dynamic_wire_height(catenary, forces, window: tuple[float, float], dt: float,
                             duration: float, alpha: float = -0.05) -> np.ndarray:
    """Mean contact-wire height under each moving constant force over the window [m]."""
    model = LinearisedCatenary(catenary)
    forces = np.asarray(forces, dtype=float)
    q0 = catenary.static_state(forces)  # start from the static deflection: short transient
    integ = HHTIntegrator(model, HHTSettings(alpha=alpha, reuse_factorization=True))
    integ.initialize(0.0, q0, np.zeros(model.n_dofs), forces)
    n = len(forces)
    total = np.zeros(n)
    count = np.zeros(n)
    for _ in range(int(np.ceil(duration / dt - 1e-9))):
        integ.step(dt, forces)
        x = catenary.positions(integ.t)
        inside = (x >= window[0]) & (x <= window[1])
        if inside.any():
            z = catenary.wire_height(integ.t, integ.q)
            total[inside] += z[inside]
            count[inside] += 1
    if np.any(count == 0):
        raise ValueError("a pantograph never enters the analysis window")
    return total / count

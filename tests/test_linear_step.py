"""The closed-form HHT-alpha step of linear models (lumped pantographs without friction or
one-way damper): same forces as ``evaluate``, same solution as the Newton path to round-off,
state updated in place, nonlinear options keep Newton."""

import numpy as np
import pytest

from pantocosim.core.hht import HHTIntegrator, HHTSettings
from pantocosim.pantograph.base import Ramp
from pantocosim.pantograph.presets import load_pantograph

LUMPED = ["en50318-2mass", "dsa380-lumped3"]


def force(t):
    return 120.0 + 30.0 * np.sin(4 * np.pi * t) + 20.0 * np.sin(40 * np.pi * t)


@pytest.mark.parametrize("name", LUMPED)
@pytest.mark.parametrize("ramp", [None, Ramp(start=0.05, duration=0.3, lowered_height=5.0)])
def test_linear_form_gives_the_forces_of_evaluate(name, ramp):
    model = load_pantograph(name, **({} if ramp is None else {"ramp": ramp}))
    model.static_equilibrium(120.0, 5.3)
    form = model.linear_form()
    assert form is not None
    rng = np.random.default_rng(1)
    w = np.zeros(form.B.shape[1])
    for t in (0.0, 0.1, 0.2, 1.0):
        q = 5.0 + rng.standard_normal(model.n_dofs) * 0.1
        v, a = rng.standard_normal((2, model.n_dofs))
        F = np.array([100.0 + 50 * rng.random()])
        ev = model.evaluate(t, q, v, a, F)
        form.fill(t, F, w)
        f_rest = form.C @ v + form.K @ q + form.B @ w
        # sums of stiffness terms of ~1e7 N/m times 5 m heights that cancel: their rounding
        # is eps times the sum of the terms' sizes |K| |q|; 4500 ulp of the (smaller) result
        assert np.allclose(f_rest, ev.f_rest, rtol=0, atol=1e-12 * np.abs(form.K @ q).max())
        assert np.array_equal(form.M @ a, ev.f_inertia)


def run(name, closed, steps=1000, h=1e-3, **options):
    model = load_pantograph(name, **options)
    q0 = model.static_equilibrium(force(0.0))
    integ = HHTIntegrator(model, HHTSettings(alpha=-0.05, closed_form_linear=closed))
    integ.initialize(0.0, q0, np.zeros(model.n_dofs), np.array([force(0.0)]))
    out = np.empty((steps, 3, model.n_dofs))
    for i in range(steps):
        integ.step(h, np.array([force((i + 1) * h)]))
        out[i] = integ.q, integ.v, integ.a
    return integ, out


@pytest.mark.parametrize("name", LUMPED)
def test_closed_form_equals_the_newton_path_to_round_off(name):
    integ, closed = run(name, True)
    assert integ.closed_form and integ.total_factorizations == 0
    newton_integ, newton = run(name, False)
    assert not newton_integ.closed_form
    # the Newton path's own round-off: a = (q - q_p) / (beta h^2) with q ~ 5 m (an ulp of q
    # is 9e-16 m, times 1/(beta h^2) ~ 1e6 is 1e-9 m/s^2); measured 7e-13, 2e-10, 6e-10
    for k, tol in ((0, 1e-11), (1, 1e-8), (2, 1e-8)):
        scale = np.abs(newton[:, k]).max()
        assert np.abs(closed[:, k] - newton[:, k]).max() <= tol * scale


@pytest.mark.parametrize("name", LUMPED)
def test_closed_form_step_updates_in_place_and_rolls_back(name):
    model = load_pantograph(name)
    integ = HHTIntegrator(model, HHTSettings(alpha=-0.05))
    integ.initialize(0.0, model.static_equilibrium(120.0), None, np.array([120.0]))
    u = np.array([120.0])
    integ.step(1e-3, u)
    arrays = [integ.q, integ.v, integ.a, integ.a_prev, integ.f_rest, integ.inputs]
    state = integ.get_state()
    first = []
    for i in range(5):
        u[0] = 125.0 + i
        integ.step(1e-3, u)
        first.append(integ.q.copy())
    assert all(x is y for x, y in zip(arrays, [integ.q, integ.v, integ.a, integ.a_prev,
                                                integ.f_rest, integ.inputs]))
    integ.set_state(state)
    for i in range(5):
        u[0] = 125.0 + i
        integ.step(1e-3, u)
        assert np.array_equal(integ.q, first[i])


@pytest.mark.parametrize("options", [{"friction_force": 6.0}, {"one_way_damper": True}])
def test_nonlinear_options_keep_newton(options):
    integ, out = run("en50318-2mass", True, steps=50, **options)
    assert not integ.closed_form and integ.total_factorizations > 0
    assert np.all(np.isfinite(out))

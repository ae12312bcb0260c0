"""HHT-alpha integrator: order of accuracy, numerical dissipation, energy conservation."""

import numpy as np
import pytest

from pantocosim.core.errors import ConvergenceError, ParameterError
from pantocosim.core.hht import FactorReuse, HHTIntegrator, HHTSettings
from pantocosim.core.linear_model import LinearModel
from pantocosim.core.model import Evaluation, SecondOrderModel


def _free_oscillator_error(h, alpha, t_end=1.0, omega=2 * np.pi * 2.0, zeta=0.05):
    m, k = 1.0, omega**2
    c = 2 * zeta * omega * m
    model = LinearModel([[m]], [[c]], [[k]])
    integ = HHTIntegrator(model, HHTSettings(alpha=alpha))
    integ.initialize(0.0, [1.0], [0.0])
    n = int(round(t_end / h))
    for _ in range(n):
        integ.step(h)
    wd = omega * np.sqrt(1 - zeta**2)
    exact = np.exp(-zeta * omega * t_end) * (np.cos(wd * t_end)
                                            + zeta * omega / wd * np.sin(wd * t_end))
    return abs(integ.q[0] - exact)


@pytest.mark.parametrize("alpha", [0.0, -0.05, -0.3])
def test_second_order_accuracy(alpha):
    hs = [4e-3, 2e-3, 1e-3, 5e-4]
    errs = [_free_oscillator_error(h, alpha) for h in hs]
    orders = np.diff(np.log(errs)) / np.diff(np.log(hs))
    assert abs(orders[-1] - 2.0) < 0.1, (errs, orders)


def _amplification_matrix(alpha, omega_h):
    """One-step map of (q, h v, h^2 a) for an undamped unit oscillator, built column by column."""
    h = 1.0
    k = omega_h**2
    A = np.zeros((2, 2))
    for j, (q0, v0) in enumerate([(1.0, 0.0), (0.0, 1.0)]):
        model = LinearModel([[1.0]], [[0.0]], [[k]])
        integ = HHTIntegrator(model, HHTSettings(alpha=alpha))
        integ.initialize(0.0, [q0], [v0])
        integ.step(h)
        A[:, j] = [integ.q[0], integ.v[0]]
    return A


@pytest.mark.parametrize("alpha", [0.0, -0.1, -0.2, -1.0 / 3.0])
def test_spectral_radius_at_infinity(alpha):
    # The full method has a 3x3 amplification matrix in (q, v, a); at omega*h -> infinity the
    # dominant eigenvalue of the iteration over many steps tends to (1+alpha)/(1-alpha).
    omega_h = 1e4
    model = LinearModel([[1.0]], [[0.0]], [[omega_h**2]])
    B = np.zeros((3, 3))
    for j in range(3):
        x0 = np.zeros(3)
        x0[j] = 1.0
        integ = HHTIntegrator(model, HHTSettings(alpha=alpha))
        integ.initialize(0.0, [x0[0]], [x0[1]], a0=[x0[2]])
        integ.f_rest = model.evaluate(0, integ.q, integ.v, integ.a, None).f_rest
        integ.step(1.0)
        B[:, j] = [integ.q[0], integ.v[0], integ.a[0]]
    rho = max(abs(np.linalg.eigvals(B)))
    expected = (1 + alpha) / (1 - alpha)
    assert rho == pytest.approx(expected, rel=0.01)


def test_alpha_zero_conserves_energy():
    omega = 2 * np.pi * 3.0
    model = LinearModel([[2.0]], [[0.0]], [[2.0 * omega**2]])
    integ = HHTIntegrator(model, HHTSettings(alpha=0.0))
    integ.initialize(0.0, [0.01], [0.3])
    e0 = 0.5 * 2.0 * integ.v[0] ** 2 + 0.5 * 2.0 * omega**2 * integ.q[0] ** 2
    energies = []
    for _ in range(5000):
        integ.step(2e-3)
        energies.append(0.5 * 2.0 * integ.v[0] ** 2 + 0.5 * 2.0 * omega**2 * integ.q[0] ** 2)
    assert max(abs(np.array(energies) - e0)) / e0 < 1e-9


def test_alpha_negative_dissipates_high_frequencies():
    omega = 2 * np.pi * 400.0
    model = LinearModel([[1.0]], [[0.0]], [[omega**2]])
    integ = HHTIntegrator(model, HHTSettings(alpha=-0.3))
    integ.initialize(0.0, [1.0], [0.0])
    for _ in range(50):
        integ.step(1e-2)
    assert abs(integ.q[0]) < 1e-3


class _Cubic(SecondOrderModel):
    """Duffing oscillator q'' + q + eps q^3 = 0: nonlinear residual for Newton tests."""

    n_dofs = 1

    def __init__(self, eps):
        self.eps = eps

    def evaluate(self, t, q, v, a, inputs, tangent=True):
        return Evaluation(f_inertia=a.copy(), f_rest=q + self.eps * q**3,
                          mass=np.eye(1), damping=np.zeros((1, 1)),
                          stiffness=np.array([[1 + 3 * self.eps * q[0] ** 2]]))


def test_newton_converges_quadratically_and_conserves_energy_nonlinear():
    model = _Cubic(eps=10.0)
    integ = HHTIntegrator(model, HHTSettings(alpha=0.0))
    integ.initialize(0.0, [1.0], [0.0])
    energy = lambda q, v: 0.5 * v**2 + 0.5 * q**2 + 0.25 * 10.0 * q**4
    e0 = energy(integ.q[0], integ.v[0])
    iters = [integ.step(1e-3).iterations for _ in range(2000)]
    assert max(iters) <= 5
    # trapezoidal rule on a nonlinear system: energy error bounded, O(h^2)
    assert abs(energy(integ.q[0], integ.v[0]) - e0) / e0 < 1e-4


def test_failure_names_time_step_and_residual():
    model = _Cubic(eps=10.0)
    integ = HHTIntegrator(model, HHTSettings(alpha=0.0, max_iterations=1))
    integ.initialize(0.0, [1.0], [0.0])
    with pytest.raises(ConvergenceError) as err:
        integ.step(0.5)
    msg = str(err.value)
    assert "t = 0.5" in msg and "step 1" in msg and "residual" in msg
    assert err.value.step == 1


def test_bad_alpha_is_rejected():
    with pytest.raises(ParameterError, match="alpha"):
        HHTIntegrator(_Cubic(1.0), HHTSettings(alpha=0.2))


def test_factorization_reuse_matches_full_newton():
    model = _Cubic(eps=1.0)
    out = []
    for reuse in (FactorReuse.NEVER, FactorReuse.ACROSS_STEPS):
        integ = HHTIntegrator(model, HHTSettings(alpha=-0.1, reuse_factorization=reuse))
        integ.initialize(0.0, [1.0], [0.0])
        for _ in range(500):
            integ.step(1e-2)
        out.append(integ.q[0])
    assert out[0] == pytest.approx(out[1], abs=1e-9)


def test_state_rollback_is_bitwise():
    model = _Cubic(eps=3.0)
    integ = HHTIntegrator(model, HHTSettings(alpha=-0.1, reuse_factorization=FactorReuse.ACROSS_STEPS))
    integ.initialize(0.0, [1.0], [0.0])
    for _ in range(10):
        integ.step(1e-2)
    saved = integ.get_state()
    first = [integ.step(1e-2) and integ.q.copy() for _ in range(5)]
    integ.set_state(saved)
    second = [integ.step(1e-2) and integ.q.copy() for _ in range(5)]
    assert all(np.array_equal(x, y) for x, y in zip(first, second))


def test_step_policy_redo_reuses_factorization_bitwise():
    model = _Cubic(eps=3.0)
    integ = HHTIntegrator(model, HHTSettings(alpha=-0.1, reuse_factorization=FactorReuse.PER_STEP))
    integ.initialize(0.0, [1.0], [0.0])
    for _ in range(5):
        integ.step(1e-2)
    saved = integ.get_state()
    first = integ.step(1e-2)
    q1 = integ.q.copy()
    integ.set_state(saved)
    again = integ.step(1e-2)
    assert np.array_equal(integ.q, q1)
    assert first.refactorizations == 1 and again.refactorizations == 0


class _ForcedCubic(_Cubic):
    """The Duffing oscillator under an input force: q'' + q + eps q^3 = F."""

    def evaluate(self, t, q, v, a, inputs, tangent=True):
        ev = super().evaluate(t, q, v, a, inputs, tangent)
        ev.f_rest = ev.f_rest - (0.0 if inputs is None else inputs[0])
        return ev


def test_a_redone_step_with_inputs_seen_is_repeated_and_with_new_inputs_solved():
    """After a rollback, a step with inputs already taken from that state is its end state
    at no cost (bit for bit); new inputs are solved by Newton-Raphson."""
    integ = HHTIntegrator(_ForcedCubic(eps=3.0), HHTSettings.for_runs(-0.1, 1e-8))
    integ.initialize(0.0, [1.0], [0.0], [0.0])
    for _ in range(5):
        integ.step(1e-2, np.array([2.0]))
    saved = integ.get_state()
    ends = {}
    for F in (2.0, 2.5):                          # two passes of one step, as a coupling does
        integ.set_state(saved)
        assert integ.step(1e-2, np.array([F])).iterations > 0
        ends[F] = (integ.q.copy(), integ.v.copy(), integ.a.copy())
    for F in (2.0, 2.5):
        integ.set_state(saved)
        assert integ.step(1e-2, np.array([F])).iterations == 0
        assert all(np.array_equal(x, y) for x, y in zip((integ.q, integ.v, integ.a), ends[F]))
    integ.set_state(saved)
    assert integ.step(1e-2, np.array([2.25])).iterations > 0
    assert ends[2.0][0][0] < integ.q[0] < ends[2.5][0][0]
    # the next step goes on from the repeated state as from the computed one
    integ.set_state(saved)
    integ.step(1e-2, np.array([2.5]))
    assert integ.step(1e-2, np.array([2.5])).iterations > 0


def test_run_settings_converge_to_the_tight_solution_and_roll_back_bitwise():
    """HHTSettings.for_runs (factorization kept across steps, linear predictor, loose
    tolerance): the solution stays within the tolerance's reach of the tight full-Newton one,
    the linear predictor starts closer to it, and a rollback (which must restore a_{n-1})
    repeats the steps bitwise."""
    model = _Cubic(eps=3.0)
    runs = {}
    for name, s in {"tight": HHTSettings(alpha=-0.1),
                    "runs": HHTSettings.for_runs(-0.1, 1e-6),
                    "constant": HHTSettings.for_runs(-0.1, 1e-6)}.items():
        if name == "constant":
            s.predictor = "constant"
        integ = HHTIntegrator(model, s)
        integ.initialize(0.0, [1.0], [0.0])
        for _ in range(300):
            integ.step(1e-2)
        runs[name] = integ
    assert abs(runs["runs"].q[0] - runs["tight"].q[0]) < 1e-5
    assert runs["runs"].total_iterations < runs["constant"].total_iterations
    integ = runs["runs"]
    saved = integ.get_state()
    first = [integ.step(1e-2) and integ.q.copy() for _ in range(5)]
    integ.set_state(saved)
    second = [integ.step(1e-2) and integ.q.copy() for _ in range(5)]
    assert all(np.array_equal(x, y) for x, y in zip(first, second))
    with pytest.raises(ParameterError, match="predictor"):
        HHTSettings(predictor="quadratic").validate()


@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_non_finite_residual_stops_the_step(bad):
    """A NaN or infinite force anywhere in the residual is reported, not iterated on."""

    class Blowing(LinearModel):
        def evaluate(self, t, q, v, a, inputs, tangent=True):
            ev = super().evaluate(t, q, v, a, inputs, tangent)
            if t > 0.0:
                ev.f_rest = ev.f_rest.copy()
                ev.f_rest[1] = bad
            return ev

    integ = HHTIntegrator(Blowing(np.eye(3), np.zeros((3, 3)), np.eye(3)), HHTSettings())
    integ.initialize(0.0, [1.0, 0.0, 0.0])
    with pytest.raises(ConvergenceError, match="non-finite"):
        integ.step(1e-3)


def test_factor_policy_keeps_reuses_and_drops_a_factorization():
    """ACROSS_STEPS keeps the factorization for steps of the same size until a step needs
    more than refresh_after iterations; an iteration past refresh_after + 4 factorizes;
    NEVER factorizes at every iteration; PER_STEP reuses the first one of a redone step."""
    from pantocosim.core.factor_reuse import FactorPolicy, Factorization

    f = Factorization(structure_key=None, h=1e-3, matrix=None, solve=None)
    s = HHTSettings(reuse_factorization=FactorReuse.ACROSS_STEPS, refresh_after=2)
    p = FactorPolicy(s)
    assert p.start(1e-3, None) is None
    p.finish(2, f)
    assert p.start(1e-3, None) is f and p.start(2e-3, None) is None
    assert not p.needs_tangent(6, f) and p.needs_tangent(7, f) and p.needs_tangent(0, None)
    p.finish(3, f)
    assert p.stale and p.start(1e-3, None) is None
    # a step redone from the same state takes what its first pass made at iteration 0
    g = Factorization(structure_key=None, h=1e-3, matrix=None, solve=None)
    assert p.start(1e-3, "a") is None
    p.made(0, g)
    assert p.start(1e-3, "a") is g and p.start(1e-3, "b") is None
    assert p.start(2e-3, "a") is None
    p.start(1e-3, "c")
    p.made(1, f)                                        # not at the first iteration
    assert p.start(1e-3, "c") is None
    s.reuse_factorization = FactorReuse.PER_STEP
    assert p.start(1e-3, "a") is g
    s.reuse_factorization = FactorReuse.NEVER          # read at each use
    assert p.start(1e-3, "a") is None
    assert not p.needs_tangent(0, f) and p.needs_tangent(1, f)

"""The native rigid and flexible DSA-380 (fmus/native/dsa380_rigid.c, dsa380_flexible.c) and
the dense HHT engine (fmus/native/hht_dense.c), built here as a shared library with a probe
(tests/c_hosts/dsa380_probe.c) and called through ctypes: residual and tangents equal the
Python kernels' at random states with every option on and off, the tangents equal finite
differences, a trajectory under a prescribed force equals HHTIntegrator's, a failed step
leaves the state as it was, and the native tangent at equilibrium gives `pantocosim modal`'s
natural frequencies."""

import ctypes
import io
import json
import subprocess
from contextlib import redirect_stdout
from pathlib import Path

import numpy as np
import pytest

from pantocosim.core.hht import HHTIntegrator, HHTSettings
from pantocosim.master.native.build import CFLAGS, SOURCE_DIR
from pantocosim.master.native.export import dsa380_constants, dsa380_flexible_data
from pantocosim.pantograph.base import Ramp
from pantocosim.pantograph.dsa380 import load_dsa380
from pantocosim.pantograph.modal import modal_analysis
from pantocosim.pantograph.presets import load_pantograph
from test_native_fmus import required

PROBE = Path(__file__).resolve().parent / "c_hosts" / "dsa380_probe.c"
LIBM_MATH = PROBE.parent / "libm_math.c"
P = ctypes.POINTER(ctypes.c_double)

#: option sets: every option of the rigid model on alone, then all together
CASES = {
    "plain": {},
    "aero": {"speed_kmh": 300.0},
    "friction": {"friction_force": 15.0, "friction_smoothing": 2e-3},
    "one_way": {"one_way_damper": True},
    "ramp": {"ramp": Ramp(start=0.002, duration=0.03, lowered_height=5.2)},
    "pitch_lock": {"pitch_lock": True},
    "all": {"speed_kmh": 300.0, "friction_force": 15.0, "friction_smoothing": 2e-3,
            "one_way_damper": True, "ramp": Ramp(start=0.002, duration=0.03,
                                                 lowered_height=5.2)},
}


def build_probe(lib, math_source):
    """The probe library of the native DSA-380 sources with the elementary functions of
    math_source (pcs_math.c as shipped, or the C library's: c_hosts/libm_math.c)."""
    cc = required("gcc", "gcc")
    sources = [SOURCE_DIR / f"{name}.c" for name in ("dsa380_rigid", "dsa380_flexible",
                                                      "hht_dense", "actuation")]
    subprocess.run([cc, *CFLAGS, "-fPIC", "-shared", f"-I{SOURCE_DIR}", "-o", str(lib),
                    str(PROBE), *map(str, sources), str(math_source), "-lm"], check=True)
    so = ctypes.CDLL(str(lib))
    so.probe_evaluate.argtypes = [ctypes.c_double, P, P, P, ctypes.c_double, P, P,
                                  ctypes.c_char_p]
    so.probe_start.argtypes = [ctypes.c_double, ctypes.c_double, ctypes.c_double, ctypes.c_int,
                               ctypes.c_int, ctypes.c_double, P, ctypes.c_double,
                               ctypes.c_char_p]
    so.probe_flex_setup.argtypes = [P, ctypes.c_long, *[P] * 7,
                                    ctypes.POINTER(ctypes.c_int), P, P, P, ctypes.c_char_p]
    so.probe_flex_evaluate.argtypes = so.probe_evaluate.argtypes
    so.probe_flex_start.argtypes = so.probe_start.argtypes
    so.probe_step.argtypes = [ctypes.c_double, ctypes.c_double, P,
                              ctypes.POINTER(ctypes.c_int), ctypes.c_char_p]
    return so


@pytest.fixture(scope="module")
def probe(tmp_path_factory):
    return build_probe(tmp_path_factory.mktemp("dsa380") / "probe.so",
                       SOURCE_DIR / "pcs_math.c")


@pytest.fixture(scope="module")
def probe_libm(tmp_path_factory):
    """The probe on the C library's sin, cos, atan, atan2 and pow (those the Python kernels
    call)."""
    return build_probe(tmp_path_factory.mktemp("dsa380-libm") / "probe.so", LIBM_MATH)


def ptr(x: np.ndarray):
    return x.ctypes.data_as(P)


def model_of(case: str):
    """The preset's rigid DSA-380 with the options of ``case``, in its static start."""
    opts = dict(CASES[case])
    lock = opts.pop("pitch_lock", False)
    base = load_pantograph("dsa380-rigid", **opts)
    return load_dsa380(None, base.options, pitch_lock=lock)


class Native:
    """The probe's model, set up with a Python model's exported constants."""

    def __init__(self, so, model):
        self.so, self.n = so, model.n_dofs
        k = dsa380_constants(model)
        msg = ctypes.create_string_buffer(512)
        assert so.probe_setup(ptr(k), len(k), msg) == 0, msg.value
        assert so.probe_n() == self.n

    def evaluate(self, t, q, v, a, F):
        n = self.n
        f, mats = np.zeros(2 * n), np.zeros(4 * n * n)
        msg = ctypes.create_string_buffer(512)
        arrays = [np.ascontiguousarray(x, float) for x in (q, v, a)]
        status = self.so.probe_evaluate(t, *map(ptr, arrays), F, ptr(f), ptr(mats), msg)
        assert status == 0, msg.value
        return f[:n], f[n:], mats.reshape(4, n, n)


def random_state(model, rng):
    n = model.n_dofs
    q = model.q_equilibrium + rng.uniform(-1, 1, n) * np.array([0.05, 0.01, 0.02, 0.05])[:n]
    return q, rng.normal(0.0, 0.3, n), rng.normal(0.0, 5.0, n)


def close(native, python, rtol):
    """Equal to ``rtol`` of the Python array's largest entry."""
    python = np.asarray(python, float)
    scale = max(np.max(np.abs(python)), 1e-300)
    assert np.max(np.abs(native - python)) <= rtol * scale, (native, python)


def kernels_equal(native, model, states, count: int, seed: int) -> None:
    """At ``count`` random states (``states(model, rng)``), times and forces: the native
    residual pieces and tangents equal the Python model's to 1e-12 (a constant mass matrix:
    inertia_q None in Python, zero in C)."""
    rng = np.random.default_rng(seed)
    for _ in range(count):
        q, v, a = states(model, rng)
        t, F = rng.uniform(0.0, 0.05), rng.uniform(0.0, 300.0)
        f_in, f_rest, mats = native.evaluate(t, q, v, a, F)
        ev = model.evaluate(t, q, v, a, np.array([F]), tangent=True)
        close(f_in, ev.f_inertia, 1e-12)
        close(f_rest, ev.f_rest, 1e-12)
        inertia_q = np.zeros_like(mats[1]) if ev.inertia_q is None else ev.inertia_q
        for got, want in zip(mats, (ev.mass, inertia_q, ev.damping, ev.stiffness)):
            close(got, want, 1e-12)


@pytest.mark.parametrize("case", sorted(CASES))
def test_residual_and_tangents_equal_the_python_kernels(probe, case):
    model = model_of(case)
    kernels_equal(Native(probe, model), model, random_state, 25, 7)


@pytest.mark.parametrize("case", ["plain", "friction", "one_way", "pitch_lock", "all"])
def test_tangents_equal_central_differences(probe, case):
    model = model_of(case)
    native = Native(probe, model)
    rng = np.random.default_rng(11)
    n = model.n_dofs
    for _ in range(5):
        q, v, a = random_state(model, rng)
        t, F = 0.01, 150.0
        f_in, f_rest, (M, Kin, C, K) = native.evaluate(t, q, v, a, F)
        for which, tangent, step in ((0, Kin + K, 1e-6), (1, C, 1e-6), (2, M, 1e-3)):
            fd = np.zeros((n, n))
            for j in range(n):
                args = [q.copy(), v.copy(), a.copy()]
                args[which][j] += step
                plus = sum(native.evaluate(t, *args, F)[:2])
                args[which][j] -= 2 * step
                minus = sum(native.evaluate(t, *args, F)[:2])
                fd[:, j] = (plus - minus) / (2 * step)
            close(tangent, fd, 1e-6)


def python_trajectory(model, settings, q0, F0, forces, h):
    integ = HHTIntegrator(model, settings)
    integ.initialize(0.0, q0, np.zeros(model.n_dofs), np.array([F0]))
    rows, its = [], []
    for F in forces:
        its.append(integ.step(h, np.array([F])).iterations)
        rows.append(np.concatenate([integ.q, integ.v, integ.a]))
    return np.array(rows), its


def native_trajectory(probe, start, n, settings, q0, F0, forces, h):
    """The probe's engine started by ``start`` (probe_start, probe_flex_start) at q0 under
    F0, stepped under ``forces``: rows (q, v, a) and the iteration counts."""
    msg = ctypes.create_string_buffer(512)
    q0 = np.ascontiguousarray(q0, float)
    assert start(settings.alpha, settings.rtol, settings.etol, settings.max_iterations,
                 int(settings.predictor == "linear"), 0.0, ptr(q0), F0, msg) == 0, msg.value
    rows, its = [], []
    out, it = np.zeros(3 + 5 * n), ctypes.c_int()
    for F in forces:
        assert probe.probe_step(h, F, ptr(out), ctypes.byref(it), msg) == 0, msg.value
        rows.append(out[3:3 + 3 * n].copy())
        its.append(it.value)
    return np.array(rows), its


def forcing(model, steps: int, h: float = 1e-3):
    """(q0, F0, forces): F(t) = F0 (1 + 0.3 sin(2 pi 6 t)) from the static start (the ramp:
    from the lowered start, no force for 40 ms)."""
    F0 = model.options.mean_uplift
    t = h * np.arange(1, steps + 1)
    forces = F0 * (1.0 + 0.3 * np.sin(2.0 * np.pi * 6.0 * t))
    if model.options.ramp is None:
        return model.q_equilibrium, F0, forces
    return (model.lowered_equilibrium(model.options.ramp.lowered_height), 0.0,
            np.where(t > 0.04, forces, 0.0))


@pytest.mark.parametrize("case", sorted(CASES))
@pytest.mark.parametrize("predictor", ["constant", "linear"])
def test_a_stepped_trajectory_equals_hht_integrators(probe, case, predictor):
    """200 steps of 1 ms under F(t) = F0 (1 + 0.3 sin(2 pi 6 t)), the Python FMU's settings
    (HHT alpha -0.05, full Newton), from the static start (the ramp: lowered, no force)."""
    model = model_of(case)
    settings = HHTSettings(alpha=-0.05, predictor=predictor)
    q0, F0, forces = forcing(model, 200)
    want, its_py = python_trajectory(model, settings, q0, F0, forces, 1e-3)
    Native(probe, model)
    got, its_c = native_trajectory(probe, probe.probe_start, model.n_dofs, settings, q0, F0,
                                   forces, 1e-3)
    scale = np.max(np.abs(want), axis=0)
    assert np.all(np.abs(got - want) <= 1e-10 * scale), np.max(np.abs(got - want) / scale)
    assert its_c == its_py
    assert np.ptp(want[:, 2]) > 1e-3      # the collector moved


def test_a_failed_step_leaves_the_state_and_says_why(probe):
    model = model_of("plain")
    n = model.n_dofs
    settings = HHTSettings(alpha=-0.05, max_iterations=2, rtol=1e-14, etol=0.0)
    msg = ctypes.create_string_buffer(512)
    Native(probe, model)
    q0 = np.ascontiguousarray(model.q_equilibrium)
    assert probe.probe_start(-0.05, 1e-10, 1e-14, 30, 0, 0.0, ptr(q0), 120.0, msg) == 0
    before, after, it = np.zeros(3 + 5 * n), np.zeros(3 + 5 * n), ctypes.c_int()
    assert probe.probe_step(1e-3, 130.0, ptr(before), ctypes.byref(it), msg) == 0
    # a force that drives the mechanism beyond its loops, then a Newton held to 2 iterations
    assert probe.probe_step(0.1, 1e5, ptr(after), ctypes.byref(it), msg) == 1
    assert np.array_equal(before, after)
    assert b"loops (A.1) cannot be closed" in msg.value
    assert probe.probe_start(settings.alpha, settings.rtol, settings.etol, 2, 0, 0.0, ptr(q0),
                             120.0, msg) == 0
    assert probe.probe_step(1e-3, 300.0, ptr(after), ctypes.byref(it), msg) == 1
    assert b"did not converge" in msg.value and b"after 2 iterations" in msg.value
    assert probe.probe_step(1e-3, np.nan, ptr(after), ctypes.byref(it), msg) == 1
    assert b"contact_force" in msg.value


def test_natural_frequencies_of_the_native_tangent_equal_pantocosim_modal(probe):
    from pantocosim.master.cli import main

    out = io.StringIO()
    with redirect_stdout(out):
        assert main(["modal", "dsa380-rigid", "--json"]) == 0
    want = json.loads(out.getvalue())["frequencies_hz"]
    model = load_pantograph("dsa380-rigid")
    q0 = model.static_equilibrium(120.0)
    n = model.n_dofs
    _, _, (M, Kin, C, K) = Native(probe, model).evaluate(0.0, q0, np.zeros(n), np.zeros(n),
                                                         120.0)
    got = modal_analysis(M, C, K + Kin).frequencies_hz
    assert len(want) == n
    assert np.allclose(got, want, rtol=1e-9, atol=0.0), (got, want)


# ---------------------------------------------------------------------- the flexible DSA-380
FLEX_CASES = {k: v for k, v in CASES.items() if k != "pitch_lock"}


def flexible_of(case: str):
    """The preset's flexible DSA-380 with the options of ``case``, in its static start."""
    return load_pantograph("dsa380-flexible", **CASES[case])


class NativeFlexible(Native):
    """The probe's flexible model, set up with a Python model's exported data (kept alive
    here: the C model reads the arrays in place)."""

    def __init__(self, so, model):
        self.so, self.n = so, model.n_dofs
        self.data = dsa380_flexible_data(model)
        d = self.data
        msg = ctypes.create_string_buffer(512)
        arrays = [ptr(d[name]) for name in ("q_ref", "M", "Qg", "E0", "length", "EA", "EI")]
        status = so.probe_flex_setup(
            ptr(d["constants"]), len(d["constants"]), *arrays,
            d["pg"].ctypes.data_as(ctypes.POINTER(ctypes.c_int)), ptr(d["pR"]),
            ptr(d["xi_g"]), ptr(d["w_g"]), msg)
        assert status == 0, msg.value
        self.evaluate_call = so.probe_flex_evaluate

    def evaluate(self, t, q, v, a, F):
        n = self.n
        f, mats = np.zeros(2 * n), np.zeros(4 * n * n)
        msg = ctypes.create_string_buffer(512)
        arrays = [np.ascontiguousarray(x, float) for x in (q, v, a)]
        assert self.evaluate_call(t, *map(ptr, arrays), F, ptr(f), ptr(mats), msg) == 0, \
            msg.value
        return f[:n], f[n:], mats.reshape(4, n, n)


def flexible_state(model, rng):
    n = model.n_dofs
    return (model.q_equilibrium + rng.normal(0.0, 1e-4, n), rng.normal(0.0, 0.05, n),
            rng.normal(0.0, 1.0, n))


@pytest.mark.parametrize("case", sorted(FLEX_CASES))
def test_flexible_residual_and_tangents_equal_the_python_kernels(probe, case):
    model = flexible_of(case)
    kernels_equal(NativeFlexible(probe, model), model, flexible_state, 10, 5)


@pytest.mark.parametrize("case", sorted(FLEX_CASES))
def test_flexible_trajectory_equals_hht_integrators(probe, probe_libm, case):
    """100 steps of 1 ms under the prescribed force of the rigid model's test. The
    accelerations of the stiff beams turn one ulp of an elementary function's value into
    some 1e-10 of their largest: they and the Newton iterations are compared on the C
    library's functions (those the Python kernels call), positions and velocities also on
    the shipped, correctly rounded ones (glibc's atan2 is not, for about one argument in a
    thousand)."""
    model = flexible_of(case)
    settings = HHTSettings(alpha=-0.05)
    n = model.n_dofs
    q0, F0, forces = forcing(model, 100)
    want, its_py = python_trajectory(model, settings, q0, F0, forces, 1e-3)
    for lib, blocks in ((probe_libm, range(3)), (probe, range(2))):
        native = NativeFlexible(lib, model)
        got, its = native_trajectory(lib, lib.probe_flex_start, n, settings, q0, F0, forces,
                                     1e-3)
        assert native.n == n
        for block in blocks:        # q, v, a: each to 1e-10 of its largest entry
            w, g = want[:, block * n:(block + 1) * n], got[:, block * n:(block + 1) * n]
            assert np.max(np.abs(g - w)) <= 1e-10 * np.max(np.abs(w)), block
        if lib is probe_libm:       # (an ulp apart, a Newton step may end one iteration later)
            assert its == its_py
    y10 = int(native.data["constants"][8])
    assert np.ptp(want[:, y10]) > 1e-3      # the collector moved


def test_flexible_natural_frequencies_equal_pantocosim_modal(probe):
    """The lowest ten modes (the mechanism's and the first bending modes)."""
    from pantocosim.master.cli import main

    out = io.StringIO()
    with redirect_stdout(out):
        assert main(["modal", "dsa380-flexible", "--json", "--count", "10"]) == 0
    want = json.loads(out.getvalue())["frequencies_hz"]
    model = flexible_of("plain")
    q0 = model.static_equilibrium(120.0)
    n = model.n_dofs
    _, _, (M, Kin, C, K) = NativeFlexible(probe, model).evaluate(0.0, q0, np.zeros(n),
                                                                 np.zeros(n), 120.0)
    got = modal_analysis(M, C, K + Kin).frequencies_hz[:10]
    assert np.allclose(got, want, rtol=1e-9, atol=0.0), (got, want)

"""Catenary line models: initial configuration (3.1.3), static report and CLI, mesh
convergence, symmetry, definition validation, dynamics with slack droppers and rollback."""

import json
import math
from pathlib import Path

import numpy as np
import pytest

from pantocosim.catenary.definition import DATA_DIR, load_catenary
from pantocosim.catenary.model import CatenaryModel
from pantocosim.catenary.statics import (element_tensions, group_horizontal_tensions,
                                         solve_static)
from pantocosim.core.errors import ParameterError
from pantocosim.core.hht import FactorReuse, HHTIntegrator, HHTSettings
from pantocosim.master.cli import main

EN_TEXT = (DATA_DIR / "en50318.toml").read_text()


def _write(tmp_path, text, name="cat.toml"):
    p = Path(tmp_path) / name
    p.write_text(text)
    return p


def _small_text(spans=3, element_size=2.0):
    return (EN_TEXT.replace("count = 10", f"count = {spans}")
            .replace("element_size = 1.0 ", f"element_size = {element_size} "))


@pytest.fixture(scope="module")
def en():
    return CatenaryModel("en50318")


@pytest.fixture(scope="module")
def small(tmp_path_factory):
    p = _write(tmp_path_factory.mktemp("cat"), _small_text(), "small.toml")
    return p


# ---------------------------------------------------------------- statics and CLI
@pytest.mark.slow
def test_static_cli_json_and_plot(en, tmp_path, capsys):
    png = tmp_path / "side.png"
    assert main(["static", "en50318", "--json", "--plot", str(png)]) == 0
    r = json.loads(capsys.readouterr().out)
    assert set(r) == {"n_dofs", "n_elements", "contact_wire_height_at_droppers_m",
                      "design_height_at_droppers_m", "max_height_error_m",
                      "contact_wire_tension_n", "messenger_tension_n", "dropper_forces_n",
                      "elasticity_m_per_n"}
    assert r["n_dofs"] == en.n_dofs
    assert len(r["dropper_forces_n"]) == 90 == len(r["contact_wire_height_at_droppers_m"])
    z, zd = np.array(r["contact_wire_height_at_droppers_m"]), np.array(
        r["design_height_at_droppers_m"])
    assert r["max_height_error_m"] < 1e-3
    # the report's formula on the same (reported) heights: equal bit for bit
    assert np.max(np.abs(z - zd)) == r["max_height_error_m"]
    # design: pre-sag parabola, 55 mm at mid-span, first/last dropper at 5.3 m (a few
    # roundings of 5.3 m: 1e-12 m is 1100 ulp)
    assert zd[4] == pytest.approx(5.3 - 0.055, abs=1e-12) and zd[0] == pytest.approx(5.3)
    assert abs(r["contact_wire_tension_n"] / 20000 - 1) < 0.005
    assert abs(r["messenger_tension_n"] / 16000 - 1) < 0.005
    assert min(r["dropper_forces_n"]) > 0.0
    el = r["elasticity_m_per_n"]
    x, v = np.array(el["x_m"]), np.array(el["value"])
    assert x[0] == 300.0 and x[-1] == 360.0 and np.all(v > 0)
    mid = v[np.argmin(np.abs(x - 330.0))]
    assert mid > 1.3 * v[0] and mid > 1.3 * v[-1]       # softer at mid-span (0.51 vs 0.37)
    assert 1e-4 < mid < 1e-3                            # 0.1 - 1 mm/N, a real catenary's
    assert png.stat().st_size > 10000


def test_equilibrium_and_tensions(en):
    S = en.structure
    x = S.full(en.q_static)
    # residual of the static equations relative to the applied loads (weights)
    assert en.equilibrium_residual(en.q_static) < 1e-8
    # every wire span carries its design horizontal tension; true axial tension close
    H = group_horizontal_tensions(en.mesh, x)
    assert np.max(np.abs(H / en.mesh.group_tension - 1)) < 1e-9
    Te = element_tensions(S, x)
    design = en.mesh.group_tension[S.cables.group]
    assert np.max(np.abs(Te / design - 1)) < 0.005           # true tension, every element
    assert np.all(Te >= design * (1 - 1e-6))                 # >= horizontal component
    assert np.all(en.dropper_forces(en.q_static) > 0)
    # droppers keep the defined axial stiffness k = EA / l0 = 1e5 N/m at their final length
    db = en.mesh.dropper_bars
    # EA = k l0 divided by l0: two roundings, within 2 ulp of k
    assert np.allclose(S.bars.EA[db] / S.bars.l0[db], 1.0e5, rtol=1e-12)
    # an independent static solve from the *initial guess* geometry with the found
    # dropper lengths and pre-tensions (droppers tension-only) lands on the same state
    res = solve_static(S, S.x_full[S.free])
    zc = S.full(res.q)[en.mesh.node_dofs[en.mesh.dropper_contact_nodes, 2]]
    assert np.max(np.abs(zc - en.mesh.dropper_design_z)) < 1e-6
    assert np.max(np.abs(res.q - en.q_static)) < 1e-6


def test_static_configuration_is_symmetric(en):
    S, mesh = en.structure, en.mesh
    xa = S.absolute(en.x_static)
    cx = xa[mesh.node_dofs[mesh.contact_nodes, 0]]
    cz = xa[mesh.node_dofs[mesh.contact_nodes, 2]]
    mz = xa[mesh.node_dofs[mesh.messenger_nodes, 2]]
    assert np.max(np.abs(cx + cx[::-1] - 600.0)) < 1e-6
    assert np.max(np.abs(cz - cz[::-1])) < 1e-9
    assert np.max(np.abs(mz - mz[::-1])) < 1e-9
    f = en.dropper_forces(en.q_static)
    assert np.max(np.abs(f - f[::-1])) < 1e-6 * np.max(f)


def test_halving_element_size_changes_heights_below_half_mm(en):
    fine = CatenaryModel("en50318", element_size=0.5)
    xs = np.linspace(1.0, 599.0, 1197)
    dz = fine.contact_wire_height(fine.q_static, xs) - en.contact_wire_height(en.q_static, xs)
    assert np.max(np.abs(dz)) < 5e-4, np.max(np.abs(dz))
    zm = lambda m: m.structure.full(m.q_static)[m.mesh.node_dofs[m.mesh.messenger_nodes[
        np.argmin(np.abs(m.structure.absolute(m.x_static)[m.mesh.node_dofs[
            m.mesh.messenger_nodes, 0]] - 330.0))], 2]]
    assert abs(zm(fine) - zm(en)) < 5e-4


@pytest.mark.parametrize("name", ["benchmark55", "ave64"])
def test_other_presets_initial_configuration(name):
    m = CatenaryModel(name, element_size=2.0)
    ic = m.initial_configuration
    assert ic.height_error < 1e-9 and ic.tension_error < 1e-9 and ic.residual < 1e-8
    assert np.all(m.dropper_forces(m.q_static) > 0)
    d = m.definition
    assert np.max(np.abs(m.contact_wire_height(m.q_static, m.mesh.dropper_x)
                         - d.design_contact_height(m.mesh.dropper_x))) < 1e-6
    # contact wire at the intermediate supports at its design height
    up = m.structure.full(m.q_static)[m.mesh.node_dofs[m.mesh.support_contact_nodes, 2]]
    assert np.max(np.abs(up - d.contact_wire_height)) < 1e-9


# ---------------------------------------------------------------- definitions
@pytest.mark.parametrize("old, new, field, value", [
    ("tension = 20000.0", "tension = -20000.0", "contact_wire.tension", -20000.0),
    ("positions = [5.0, 10.5, 17.0, 23.5, 30.0, 36.5, 43.0, 49.5, 55.0]",
     "positions = [5.0, 10.5, 17.0, 23.5, 30.0, 36.5, 43.0, 49.5, 65.0]",
     "droppers.positions[8]", 65.0),
    ("EA = 1.1e7                   # N (assumed)\n", "", "messenger_wire.EA", None),
    ("presag = 0.055", "presag = nan", "geometry.presag", "nan"),
    ("length = 60.0", "length = 60.0\nlengths = [60.0, \"x\"]", "spans.lengths[1]", "x"),
])
def test_bad_definitions_name_field_and_value(tmp_path, old, new, field, value):
    assert old in EN_TEXT
    p = _write(tmp_path, EN_TEXT.replace(old, new, 1), "bad.toml")
    with pytest.raises(ParameterError) as exc:
        load_catenary(p)
    e = exc.value
    assert e.field == field
    if value == "nan":
        assert math.isnan(e.value)
    else:
        assert e.value == value
    assert "bad.toml" in str(e) and field in str(e)


def test_cli_reports_bad_definition(tmp_path, capsys):
    p = _write(tmp_path, EN_TEXT.replace("tension = 16000.0", "tension = -1.0"), "neg.toml")
    assert main(["static", str(p)]) == 2
    err = capsys.readouterr().err
    assert "neg.toml" in err and "messenger_wire.tension" in err and "-1.0" in err
    assert main(["static", "no-such-preset"]) == 2


def test_rayleigh_coefficients_hit_target_ratios():
    d = load_catenary("en50318")
    a, b = d.rayleigh()
    for f, z in zip(d.damping_frequencies_hz, d.damping_ratios):
        w = 2 * np.pi * f
        # a 2 x 2 solve of condition 800 (1 and 20 Hz): error <= ~800 ulp = 1.8e-13
        assert a / (2 * w) + b * w / 2 == pytest.approx(z, rel=1e-12)


# ---------------------------------------------------------------- dynamics
def test_contact_points_and_force_input(small):
    m = CatenaryModel(small, x0=[37.3, 91.0], speed=50.0)
    q, n = m.q_static, m.n_dofs
    t = 0.21
    cps = m.contact_points(t)
    xk = m.positions(t)
    assert np.allclose(xk, [37.3 + 10.5, 91.0 + 10.5])
    z = m.wire_height(t, q)
    for cp, zk, x in zip(cps, z, xk):
        assert cp.offset == 0.0
        assert cp.weights @ q[cp.dofs] == zk
    # consistent with the design: pre-sag parabola plus sag between droppers (< 5 mm)
    assert np.all(np.abs(z - load_catenary(small).design_contact_height(xk)) < 5e-3)
    # the input enters f_rest as -N^T F
    zero = np.zeros(n)
    e0 = m.evaluate(t, q, zero, zero, [0.0, 0.0], tangent=False)
    e1 = m.evaluate(t, q, zero, zero, [120.0, 80.0], tangent=False)
    P = np.zeros(n)
    for cp, F in zip(cps, [120.0, 80.0]):
        np.add.at(P, cp.dofs, F * cp.weights)
    assert np.allclose(e0.f_rest - e1.f_rest, P, rtol=0, atol=1e-9)
    # static equilibrium at rest: f_rest = 0 up to round-off
    assert np.max(np.abs(e0.f_rest)) < 1e-7
    # velocity output = d/dt of the height output (finite difference along a motion)
    v = np.random.default_rng(0).normal(0, 0.01, n)
    h = 1e-6
    fd = (m.wire_height(t + h, q + h * v) - m.wire_height(t - h, q - h * v)) / (2 * h)
    assert np.allclose(m.wire_velocity(t, q, v), fd, rtol=1e-5, atol=1e-8)


def test_static_start_with_contact_force(small):
    m = CatenaryModel(small, x0=[90.0], speed=0.0)
    q0 = m.static_state([150.0])
    up = m.wire_height(0.0, q0) - m.wire_height(0.0, m.q_static)
    assert 0.01 < up[0] < 0.1
    u = m.support_uplift(q0)
    assert u[0] == 0.0 and u[-1] == 0.0 and np.all(np.abs(u[1:-1]) > 0)
    assert up[0] / 150.0 == pytest.approx(m.elasticity([90.0], 150.0)[0], rel=1e-9)


def _run(model, integ, steps, F):
    qs = []
    for _ in range(steps):
        integ.step(1e-3, [F])
        qs.append(integ.q.copy())
    return qs


def test_slack_droppers_and_bitwise_rollback(small):
    F = 300.0
    m = CatenaryModel(small, x0=[40.0], speed=80.0)
    integ = HHTIntegrator(m, HHTSettings(alpha=-0.1, reuse_factorization=FactorReuse.ACROSS_STEPS))
    integ.initialize(0.0, m.static_state([F]), None, [F])
    keys, slack_seen, hist = set(), 0, []
    for _ in range(250):
        integ.step(1e-3, [F])
        s = m.get_internal_state()["slack"]
        slack_seen = max(slack_seen, int(s.sum()))
        keys.add(m.evaluate(integ.t, integ.q, integ.v, integ.a, [F], False).structure_key)
        hist.append(m.wire_height(integ.t, integ.q)[0])
        f = m.dropper_forces(integ.q)
        assert np.all(f >= 0.0)
        assert np.array_equal(f == 0.0, s)                 # committed set = zero-force set
    assert slack_seen >= 1 and len(keys) >= 2
    assert integ.total_factorizations >= 2
    # rollback: the same steps from a saved state reproduce q bitwise
    state = integ.get_state()
    a = _run(m, integ, 40, F)
    integ.set_state(state)
    b = _run(m, integ, 40, F)
    assert all(np.array_equal(x, y) for x, y in zip(a, b))
    # also through a pickled state (factorization dropped and rebuilt)
    import pickle

    integ.set_state(pickle.loads(pickle.dumps(HHTIntegrator.picklable_state(state))))
    c = _run(m, integ, 40, F)
    assert all(np.array_equal(x, y) for x, y in zip(a, c))


def test_residual_damping_leaves_out_the_committed_slack_droppers(small):
    """f_rest = C v + F_elast - F_weight (3.26) with C the Rayleigh damping less the share
    beta K0_d of the droppers slack at the last commit, against the damping matrix
    assembled on the sparse pattern."""
    m = CatenaryModel(small, x0=[40.0], speed=80.0)
    n = m.n_dofs
    rng = np.random.default_rng(7)
    q = m.q_static + 1e-4 * rng.standard_normal(n)
    v, a = rng.standard_normal(n), rng.standard_normal(n)
    S = m.structure
    f, _, _ = S.internal(S.full(q), False)
    for slack in (np.zeros(len(m.mesh.dropper_bars), bool),
                  rng.random(len(m.mesh.dropper_bars)) < 0.4):
        m.set_internal_state({"slack": slack})
        ev = m.evaluate(0.0, q, v, a, None, tangent=False)
        C = m._damping(slack)
        expected = C @ v + f[S.free] - m.weight
        assert np.abs(ev.f_rest - expected).max() <= 1e-13 * np.abs(C @ v).max()
        assert np.abs(ev.f_inertia - m.M @ a).max() <= 1e-13 * np.abs(m.M @ a).max()
    taut = m._damping(np.zeros_like(slack)) @ v
    assert slack.any() and np.abs(C @ v - taut).max() > 1e-6 * np.abs(taut).max()


def test_modes_cli(small, capsys):
    assert main(["modes", str(small), "--count", "6", "--json"]) == 0
    f = json.loads(capsys.readouterr().out)["frequencies_hz"]
    assert len(f) == 6 and np.all(np.diff(f) >= 0) and 0.3 < f[0] < 3.0
    m = CatenaryModel(small)
    f2, phi = m.modes(6)
    assert np.allclose(f, f2, rtol=1e-8)
    # mass-normalised, K-orthogonal shapes
    Mphi = m.M @ phi
    assert np.allclose(phi.T @ Mphi, np.eye(6) * np.diag(phi.T @ Mphi), atol=1e-8)

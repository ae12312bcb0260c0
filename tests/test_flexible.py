"""Flexible-bar DSA-380 (thesis 2.2-2.3): ANCF element tangents, convergence to the
rigid model as E grows, steel frequencies and bar bending modes (Table 2.2), mesh refinement,
static drop (2.3.2), time response, preset/CLI path, bad files, FMU swap."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from pantocosim.core.errors import ParameterError
from pantocosim.pantograph import beam_ancf as beam
from pantocosim.pantograph.base import PantographOptions, Ramp
from pantocosim.pantograph.dsa380_flexible import (PRESET_FILE, Dsa380FlexibleModel,
                                                   load_dsa380_flexible, read_flexible)
from pantocosim.pantograph.modal import modal_analysis

ROOT = Path(__file__).resolve().parents[1]
PROBE = Path(__file__).with_name("fmu_probe.py")
F_STATIC = 120.0   # thesis 2.2: linearised about the equilibrium under 120 N on point 10
STEEL = 210e9


def _opts(**kw):
    return PantographOptions(static_force=F_STATIC, **kw)


@pytest.fixture(scope="module")
def steel():
    return load_dsa380_flexible(None, _opts())


@pytest.fixture(scope="module")
def stiff():
    return load_dsa380_flexible(None, _opts(), E=1000 * STEEL)


@pytest.fixture(scope="module")
def rigid_freqs(steel):
    r = steel.rigid
    q0 = r.static_equilibrium(F_STATIC)
    return modal_analysis(*r.linearize(q0, F_STATIC)).frequencies_hz


# ------------------------------------------------------------------------- tangents

def test_element_forces_and_tangents_match_central_differences():
    """dU/de and d2U/de2 of the ANCF element (axial + exact curvature) against central
    differences, at large rotations and strains, several lengths and stiffnesses."""
    rng = np.random.default_rng(7)
    ne = 6
    length = np.array([0.1, 0.3, 0.5, 1.0, 0.2, 0.7])
    EA = np.array([1.0, 3.0, 2.0, 5.0, 4.0, 1.5])
    EI = np.array([0.2, 0.1, 0.5, 0.3, 0.4, 0.05])
    # straight reference elements at random angles, displaced by O(0.1 l) (large strains)
    E0 = np.zeros((ne, 8))
    for k in range(ne):
        t = rng.uniform(-np.pi, np.pi)
        d = np.array([np.cos(t), np.sin(t)])
        p = rng.normal(size=2) * 3.0
        E0[k] = np.r_[p, d, p + length[k] * d, d]
    dE = 0.1 * rng.normal(size=(ne, 8))
    dE[:, 0::4] *= length[:, None]
    dE[:, 1::4] *= length[:, None]

    def run(dE):
        F = np.zeros((ne, 8))
        K = np.zeros((ne, 8, 8))
        U = np.zeros((ne, 2))
        beam.elastic_elements(E0, dE, length, EA, EI, beam.GAUSS_XI, beam.GAUSS_W, F, K, U)
        return F, K, U.sum(axis=1)

    F, K, U = run(dE)
    h = 1e-6
    Fn = np.zeros_like(F)
    Kn = np.zeros_like(K)
    for j in range(8):
        d = np.zeros((ne, 8))
        d[:, j] = h
        Fp, _, Up = run(dE + d)
        Fm, _, Um = run(dE - d)
        Fn[:, j] = (Up - Um) / (2 * h)
        Kn[:, :, j] = (Fp - Fm) / (2 * h)
    errF = max(np.max(np.abs(Fn[k] - F[k])) / np.max(np.abs(F[k])) for k in range(ne))
    errK = max(np.max(np.abs(Kn[k] - K[k])) / np.max(np.abs(K[k])) for k in range(ne))
    print(f"\nelement vs central FD: force {errF:.1e}, stiffness {errK:.1e}")
    for k in range(ne):
        assert np.max(np.abs(Fn[k] - F[k])) <= 1e-6 * np.max(np.abs(F[k]))
        assert np.max(np.abs(Kn[k] - K[k])) <= 1e-6 * np.max(np.abs(K[k]))
        # symmetric up to rounding: 4500 ulp of the largest entry
        assert np.allclose(K[k], K[k].T, rtol=0, atol=1e-12 * np.max(np.abs(K[k])))
    # a rigid motion of the reference is strain-free: no force
    R = np.array([[np.cos(0.7), -np.sin(0.7)], [np.sin(0.7), np.cos(0.7)]])
    moved = np.zeros_like(E0)
    for k in range(ne):
        for p in range(4):
            v = R @ E0[k, 2 * p:2 * p + 2]
            moved[k, 2 * p:2 * p + 2] = v + (np.array([0.3, -0.2]) if p % 2 == 0 else 0.0)
    F, _, U = run(moved - E0)
    assert np.max(np.abs(F)) < 1e-9 and np.max(U) < 1e-20


def test_model_tangents_match_central_differences():
    """Assembled stiffness and damping (elements, springs, torsion and actuation, damper,
    friction, contact) against central differences of f_rest, away from equilibrium."""
    m = load_dsa380_flexible(None, _opts(friction_force=5.0, friction_smoothing=0.05))
    rng = np.random.default_rng(3)
    n = m.n_dofs
    q = m.q_equilibrium + 1e-3 * rng.normal(size=n)
    v = 0.1 * rng.normal(size=n)
    a = rng.normal(size=n)
    inp = np.array([130.0])
    ev = m.evaluate(0.0, q, v, a, inp)
    assert ev.inertia_q is None
    assert np.allclose(ev.f_inertia, ev.mass @ a)
    h = 1e-6
    K = np.zeros((n, n))
    C = np.zeros((n, n))
    for j in range(n):
        e = np.zeros(n)
        e[j] = h
        K[:, j] = (m.evaluate(0, q + e, v, a, inp, False).f_rest
                   - m.evaluate(0, q - e, v, a, inp, False).f_rest) / (2 * h)
        C[:, j] = (m.evaluate(0, q, v + e, a, inp, False).f_rest
                   - m.evaluate(0, q, v - e, a, inp, False).f_rest) / (2 * h)
    errK = np.max(np.abs(K - ev.stiffness)) / np.max(np.abs(ev.stiffness))
    errC = np.max(np.abs(C - ev.damping)) / np.max(np.abs(ev.damping))
    print(f"\nmodel tangents vs central FD: stiffness {errK:.2e}, damping {errC:.2e}")
    assert errK < 1e-6 and errC < 1e-6


# ------------------------------------------------------------------------- rigid limit

def test_stiff_material_converges_to_the_rigid_model(stiff, steel, rigid_freqs):
    """E x 1000: first four frequencies within 0.5 % of the rigid model's, the same
    actuation torque (2.14) and static shape; the static drop shrinks as 1/E."""
    f, _, labels = stiff.modes(n_modes=4)
    rel = f / rigid_freqs[:4] - 1.0
    print("\nE x1000 vs rigid [Hz]:", np.round(f, 5), np.round(rigid_freqs[:4], 5),
          "rel", np.array2string(rel, precision=2))
    assert np.all(np.abs(rel) < 0.005)
    assert labels == ["collector pitch", "mechanism", "collector vertical",
                      "collector horizontal"]
    # static: equilibrium at the working height, torque and node positions
    r = stiff.rigid
    qr = r.static_equilibrium(F_STATIC)
    M_rigid = r.torque
    assert abs(stiff.torque / M_rigid - 1.0) < 1e-4
    assert np.max(np.abs(stiff.q_equilibrium - stiff.q_from_rigid(qr))) < 1e-5
    # static drop of point 10 under the rigid model's torque and 120 N (thesis 2.3.2)
    h = stiff.params.rigid.working_height
    drop_stiff = h - stiff.contact_height(stiff.equilibrium_under_torque(F_STATIC, M_rigid))
    drop_steel = h - steel.contact_height(steel.equilibrium_under_torque(F_STATIC, M_rigid))
    print(f"static drop of point 10 under the rigid torque: steel {1e3 * drop_steel:.3f} mm, "
          f"E x1000 {1e6 * drop_stiff:.3f} um")
    assert abs(drop_stiff) < 1e-5
    # the drop is the bars' compliance, ~ 1/E, once the nominal mass of the links 8, 9 (a
    # constant 2.5e-3 N m on the torque balance at 1e-3 rho) is taken out
    drops = []
    for E in (STEEL, 1000 * STEEL):
        m = load_dsa380_flexible(None, _opts(), E=E, link_density_ratio=1e-9)
        drops.append(h - m.contact_height(m.equilibrium_under_torque(F_STATIC, M_rigid)))
    print(f"without link mass: steel {1e3 * drops[0]:.4f} mm, E x1000 {1e6 * drops[1]:.4f} um")
    assert abs(drops[0] / drops[1] / 1000.0 - 1.0) < 0.02


# ------------------------------------------------------------------------- steel

def test_steel_frequencies_and_bar_bending_modes(steel, rigid_freqs):
    """Steel: first four within 5 % of rigid (Table 2.2); the first bar bending modes lie in
    15-40 Hz (thesis: 21.77 and 25.24 Hz), classified from the beams' strain energy."""
    f, phi, labels = steel.modes(n_modes=8)
    rel = f[:4] / rigid_freqs[:4] - 1.0
    print("\nsteel modes [Hz]:", [f"{x:.4f} ({lab})" for x, lab in zip(f, labels)])
    print("steel vs rigid, first four:", np.array2string(100 * rel, precision=3), "%")
    assert np.all(np.abs(rel) < 0.05)
    assert labels[:4] == ["collector pitch", "mechanism", "collector vertical",
                          "collector horizontal"]
    bending = [(x, lab) for x, lab in zip(f, labels) if lab.startswith("bending")]
    assert len(bending) >= 2
    for x, lab in bending[:2]:
        assert 15.0 < x < 40.0, (x, lab)
    assert {lab for _, lab in bending[:2]} >= {"bending bar 4", "bending bar 5"}
    # the CLI path (modal_analysis on linearize) gives the same frequencies
    M, C, K = steel.linearize(steel.q_equilibrium, F_STATIC)
    res = modal_analysis(M, C, K)
    assert np.allclose(res.frequencies_hz[:6], f[:6], rtol=1e-5)


def test_mesh_refinement_changes_the_first_six_frequencies_little(steel):
    f1, _, _ = steel.modes(n_modes=6)
    mesh2 = tuple(2 * n for n in read_flexible(PRESET_FILE)[0].mesh)
    fine = load_dsa380_flexible(None, _opts(), mesh=mesh2)
    f2, _, _ = fine.modes(n_modes=6)
    rel = f2 / f1 - 1.0
    print(f"\nmesh x2 ({steel.n_dofs} -> {fine.n_dofs} dofs): relative change",
          np.array2string(rel, precision=2))
    assert np.all(np.abs(rel) < 0.005)


def test_mass_and_inertia_equal_the_rigid_bars(steel):
    """Consistent mass: total mass and the collector's pitch inertia are the rigid model's."""
    rp = steel.params.rigid
    n = steel.n_dofs
    # a vertical translation of the collector's nodes: kinetic mass = m7
    coll = np.zeros(n)
    for g, _ in steel.node_pos[6]:
        coll[g + 1] = 1.0
    # sums of the element masses' entries (tens of terms): 1e-12 is 4500 ulp
    assert np.isclose(coll @ steel.M @ coll, rp.bars[6].m, rtol=1e-12)
    # gravity: total weight of bars 1-7 (+ the nominal links) equals sum m g
    W = -np.sum(steel._Qe[:, 1::2])
    m_links = sum(steel.rho_bar[b] * steel.params.area(b) * steel.bar_lengths[b]
                  for b in (7, 8))
    assert np.isclose(W, (sum(b.m for b in rp.bars) + m_links) * rp.g, rtol=1e-12)
    assert m_links < 1e-3


# ------------------------------------------------------------------------- time response

def test_time_response_follows_the_rigid_model():
    """Thesis Fig. 2.15: F = 120 + 30 sin(4 pi t) from the static equilibrium: the flexible
    and rigid responses nearly coincide (1 s, HHT alpha = -0.05)."""
    from pantocosim.master.standalone import simulate_pantograph
    from pantocosim.pantograph.presets import load_pantograph

    force = lambda t: 120.0 + 30.0 * np.sin(4 * np.pi * t)  # noqa: E731
    flex = load_pantograph("dsa380-flexible")
    assert isinstance(flex, Dsa380FlexibleModel)
    rf = simulate_pantograph(flex, force, 1.0, 1e-3)
    rr = simulate_pantograph(load_pantograph("dsa380-rigid"), force, 1.0, 1e-3)
    dev = np.max(np.abs(rf.contact_height - rr.contact_height))
    amp = np.ptp(rr.contact_height)
    print(f"\nflexible vs rigid contact height over 1 s: max deviation {1e3 * dev:.3f} mm "
          f"(rigid peak-to-peak {1e3 * amp:.2f} mm), mean Newton iterations "
          f"{rf.iterations[1:].mean():.2f}")
    assert dev < 0.05 * amp
    assert rf.iterations[1:].max() <= 6


def test_energy_is_conserved_without_damper():
    """Energy balance (2.30)-(2.34) with the damper removed: T + V + F y10 - M0 phi1 stays
    constant under a constant load step (HHT alpha = 0), checking energies() against the
    residual (elastic, gravity, springs, torsion, actuation)."""
    from pantocosim.core.hht import HHTIntegrator, HHTSettings

    params, _ = read_flexible(PRESET_FILE)
    params.rigid.c = 0.0
    m = Dsa380FlexibleModel(params, _opts())
    F = 150.0

    def total(q, v):
        e = m.energies(q, v)
        return e["T"] + e["V"] + F * m.contact_height(q) - m.torque * m.bar_angle_at_1(q)

    integ = HHTIntegrator(m, HHTSettings(alpha=0.0))
    integ.initialize(0.0, m.q_equilibrium, np.zeros(m.n_dofs), np.array([F]))
    E0 = total(integ.q, integ.v)
    drift = 0.0
    T_max = 0.0
    for _ in range(1000):
        integ.step(5e-4, np.array([F]))
        drift = max(drift, abs(total(integ.q, integ.v) - E0))
        T_max = max(T_max, m.energies(integ.q, integ.v)["T"])
    print(f"\nenergy drift {drift:.2e} J with kinetic energy up to {T_max:.3f} J")
    assert T_max > 0.1 and drift < 1e-6 * T_max * 10


def test_ramp_friction_and_one_way_damper_options():
    """Options as in the rigid model: ramp torque (3.3.1), friction (2.16), one-way damper."""
    from pantocosim.core.hht import HHTIntegrator, HHTSettings

    o = _opts(friction_force=3.0, one_way_damper=True,
              ramp=Ramp(start=0.0, duration=0.5, lowered_height=5.0))
    m = load_dsa380_flexible(None, o)
    assert m.torque_lowered is not None
    # the bars' compliance (~3 mm at point 10) costs k_r * 3 mm / (dy5/dtheta) ~ 13 N m
    assert abs(m.torque_lowered - m.rigid.torque_lowered) < 20.0
    assert abs(m.torque - m.rigid.torque) < 20.0
    assert m.actuation_torque(0.0) == m.torque_lowered
    # the ramp's end: torque_lowered + (torque - torque_lowered) 1.0, terms of one size: 45 ulp
    assert np.isclose(m.actuation_torque(1.0), m.torque, rtol=1e-14)
    q0 = m.lowered_equilibrium(5.0)
    assert abs(m.contact_height(q0) - 5.0) < 1e-9
    integ = HHTIntegrator(m, HHTSettings(alpha=-0.05))
    integ.initialize(0.0, q0, np.zeros(m.n_dofs), np.array([0.0]))
    for _ in range(200):
        integ.step(1e-3, np.array([0.0]))
    assert m.contact_height(integ.q) > 5.0 + 1e-3  # rising under the ramped torque


# ------------------------------------------------------------------------- data files

def test_bad_parameter_files_name_the_field(tmp_path):
    text = PRESET_FILE.read_text().replace('rigid_model = "dsa380-rigid.toml"',
                                           f'rigid_model = "{PRESET_FILE.parent}/'
                                           'dsa380-rigid.toml"')
    cases = {
        "sections.bar4": text.replace("bar4 = [0.0524, 0.055]", "bar4 = [0.050, 0.055]"),
        "mesh.bar7": text.replace("bar7 = 2", "bar7 = 3"),
        "material.E": text.replace("E = 210e9", "E = -1.0"),
        "mesh.bar2": text.replace("bar2 = 4", "bar2 = 0"),
        "rigid_model": text.replace("dsa380-rigid.toml\"", "nope.toml\""),
    }
    for field, body in cases.items():
        p = tmp_path / f"{field}.toml"
        p.write_text(body)
        with pytest.raises(ParameterError) as exc:
            load_dsa380_flexible(p)
        assert exc.value.field.startswith(field), (field, str(exc.value))
        assert str(p) in str(exc.value)


# ------------------------------------------------------------------------- FMU

@pytest.mark.slow
def test_flexible_fmu_builds_validates_and_swaps_for_the_rigid_one(fmus):
    """The flexible FMU has the rigid FMU's ports, validates, runs as the stand-alone model
    and rolls back / deserialises bit for bit."""
    from fmpy import read_model_description
    from fmpy.validation import validate_fmu

    from pantocosim.master.standalone import simulate_pantograph
    from pantocosim.pantograph.presets import load_pantograph

    paths = {name: fmus[name] for name in ("dsa380-flexible", "dsa380-rigid")}
    ports = {}
    for name, path in paths.items():
        assert validate_fmu(str(path)) == [], name
        md = read_model_description(str(path))
        ports[name] = [(v.name, v.causality, v.unit) for v in md.modelVariables
                       if v.causality in ("input", "output")]
    assert ports["dsa380-flexible"] == ports["dsa380-rigid"]
    proc = subprocess.run([sys.executable, str(PROBE), "pantograph_trace",
                           str(paths["dsa380-flexible"]), json.dumps({"F0": 120.0,
                                                                      "steps": 200})],
                          capture_output=True, text=True, timeout=600)
    lines = [l for l in proc.stdout.splitlines() if l.startswith("RESULT ")]
    assert proc.returncode == 0 and lines, proc.stdout + proc.stderr
    res = json.loads(lines[-1][7:])
    ref = simulate_pantograph(load_pantograph("dsa380-flexible"),
                              lambda t: 120 + 30 * np.sin(4 * np.pi * t), 0.2, 1e-3)
    # the probe accumulates t += h, the stand-alone run uses i * h: the force differs by an
    # ulp at some steps, so the heights agree to round-off (not bit for bit)
    assert np.max(np.abs(np.array(res["heights"]) - ref.contact_height[1:])) < 1e-12
    assert res["rollback_equal"] and res["serialized_equal"]


@pytest.mark.slow
def test_flexible_pantograph_swaps_into_a_scenario_by_name(tmp_path):
    """Monolithic pantograph-catenary run with ``model = "dsa380-flexible"``: no code change;
    the contact force statistics stay close to the rigid pantograph's."""
    from pantocosim.master.run import prepare, run_monolithic

    src = (ROOT / "tests" / "data" / "short-en50318.toml").read_text()
    stats = {}
    for model in ("dsa380-rigid", "dsa380-flexible"):
        p = tmp_path / f"{model}.toml"
        p.write_text(src.replace('model = "en50318-2mass"', f'model = "{model}"'))
        res = run_monolithic(prepare(str(p)), None, progress=False)
        F = np.asarray(res.columns["contact_force_1"])
        stats[model] = (F.mean(), F.std())
    print("\ncontact force mean/std rigid vs flexible:", stats)
    (mr, sr), (mf, sf) = stats["dsa380-rigid"], stats["dsa380-flexible"]
    assert abs(mf - mr) < 0.01 * mr and abs(sf - sr) < 0.05 * sr

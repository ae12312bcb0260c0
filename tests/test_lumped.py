"""Lumped-mass pantographs, linear analysis (modes, FRF) and the stand-alone simulation."""

import json

import numpy as np
import pytest

from pantocosim.core.errors import ParameterError
from pantocosim.master.cli import main
from pantocosim.master.standalone import force_expression, simulate_pantograph
from pantocosim.pantograph.base import PantographOptions, Ramp
from pantocosim.pantograph.modal import frf_direct, frf_modal, modal_analysis
from pantocosim.pantograph.presets import load_pantograph, preset_defaults


def _fd_tangents(model, t, q, v, a, F, eps=1e-6):
    n = model.n_dofs
    K = np.zeros((n, n))
    C = np.zeros((n, n))
    for j in range(n):
        dq = np.zeros(n)
        dq[j] = eps * max(1.0, abs(q[j]))
        fp = model.evaluate(t, q + dq, v, a, F).f_rest
        fm = model.evaluate(t, q - dq, v, a, F).f_rest
        K[:, j] = (fp - fm) / (2 * dq[j])
        dv = np.zeros(n)
        dv[j] = 1e-7
        fp = model.evaluate(t, q, v + dv, a, F).f_rest
        fm = model.evaluate(t, q, v - dv, a, F).f_rest
        C[:, j] = (fp - fm) / (2e-7)
    return K, C


@pytest.mark.parametrize("name", ["dsa380-lumped3", "en50318-2mass"])
def test_lumped_tangents_match_finite_differences(name):
    model = load_pantograph(name, friction_force=6.0, friction_smoothing=1e-2)
    q = model.static_equilibrium(120.0) + 0.01 * np.arange(model.n_dofs)
    v = np.linspace(0.05, -0.03, model.n_dofs)
    a = np.ones(model.n_dofs)
    F = np.array([130.0])
    ev = model.evaluate(0.3, q, v, a, F)
    K, C = _fd_tangents(model, 0.3, q, v, a, F)
    assert np.allclose(ev.stiffness, K, rtol=1e-6, atol=1e-6 * np.abs(K).max())
    assert np.allclose(ev.damping, C, rtol=1e-6, atol=1e-6 * np.abs(C).max())


def test_two_mass_frequencies_match_closed_form():
    model = load_pantograph("en50318-2mass")
    q0 = model.static_equilibrium(115.0)
    M, C, K = model.linearize(q0, 115.0)
    m1, m2, k1, k2 = 7.2, 15.0, 4200.0, 50.0
    # det(K - w^2 M) = 0 for the two-mass chain
    b = -(k1 / m1 + (k1 + k2) / m2)
    c = k1 * k2 / (m1 * m2)
    w2 = np.sort(np.roots([1.0, b, c]).real)
    res = modal_analysis(M, C, K)
    # eigenvalues of a symmetric problem err by ~eps max(w2) each: relative to the smaller
    # one eps w2[1] / w2[0] (ratio ~400), halved by the square root; 16 times that
    rel = 16 * np.finfo(float).eps * w2[1] / w2[0] / 2
    assert res.frequencies_hz == pytest.approx(np.sqrt(w2) / (2 * np.pi), rel=rel)


@pytest.mark.parametrize("name", ["dsa380-lumped3", "dsa380-rigid"])
def test_frf_direct_equals_modal_superposition(name):
    model = load_pantograph(name)
    M, C, K = model.linearize(model.static_equilibrium(120.0), 120.0)
    f = np.linspace(0.05, 30.0, 300)
    Hd = frf_direct(M, C, K, f)
    Hm = frf_modal(M, C, K, f)
    assert np.max(np.abs(Hd - Hm)) / np.max(np.abs(Hd)) < 1e-8
    # static limit: H(0) = K^-1
    assert np.allclose(frf_direct(M, C, K, [0.0])[0].real, np.linalg.inv(K), rtol=1e-10)


def test_static_start_is_equilibrium_with_mean_uplift():
    model = load_pantograph("dsa380-lumped3", speed_kmh=300.0)
    assert model.options.mean_uplift == pytest.approx(70 + 0.00097 * 300**2)
    res = simulate_pantograph(model, lambda t: model.options.mean_uplift, 1.0, 1e-3)
    assert np.max(np.abs(res.contact_height - 5.3)) < 1e-9


def test_harmonic_steady_state_matches_frf():
    model = load_pantograph("en50318-2mass")
    F0, dF, f = 115.0, 20.0, 3.0
    res = simulate_pantograph(model, lambda t: F0 + dF * np.sin(2 * np.pi * f * t), 30.0, 5e-4,
                              alpha=0.0)
    M, C, K = model.linearize(model.static_equilibrium(F0), F0)
    H = frf_direct(M, C, K, [f])[0][0, 0]
    tail = res.time > 20.0
    amp = 0.5 * (res.contact_height[tail].max() - res.contact_height[tail].min())
    assert amp == pytest.approx(dF * abs(H), rel=2e-3)


def test_one_way_damper_only_damps_downward_motion():
    opts = PantographOptions(static_force=115.0, aero_c2=0.0, one_way_damper=True)
    model = load_pantograph("en50318-2mass", options=opts)
    q = model.static_equilibrium(115.0)
    up = model.evaluate(0, q, np.array([0.0, 0.1]), np.zeros(2), np.array([115.0]))
    down = model.evaluate(0, q, np.array([0.0, -0.1]), np.zeros(2), np.array([115.0]))
    assert up.damping[1, 1] == pytest.approx(10.0)  # only the head-frame damper
    assert down.damping[1, 1] == pytest.approx(100.0)


def test_ramp_raising_reaches_working_state():
    opts = PantographOptions(static_force=115.0, aero_c2=0.0,
                             ramp=Ramp(start=0.5, duration=1.0, lowered_height=4.8))
    model = load_pantograph("en50318-2mass", options=opts)
    model.static_equilibrium(0.0, 5.3)  # final reference: head at 5.3 m without contact
    q_low = model.lowered_equilibrium(4.8)
    assert np.allclose(q_low, 4.8)
    assert model.uplift_force(0.0) == 0.0 and model.uplift_force(2.0) == pytest.approx(115.0)
    res = simulate_pantograph(model, lambda t: 0.0, 40.0, 2e-3, q0=q_low)
    assert res.contact_height[0] == pytest.approx(4.8)
    assert res.contact_height[-1] == pytest.approx(5.3, abs=2e-3)


def test_bad_inputs_name_the_parameter(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[chain]\nmasses = [7.2, -15.0]\nstiffness = [4200.0, 50.0]\n"
                   "damping = [10.0, 90.0]\nworking_height = 5.3\n")
    with pytest.raises(ParameterError, match=r"chain.masses\[1\] = -15.0"):
        load_pantograph(bad)
    with pytest.raises(ParameterError, match="unknown preset"):
        load_pantograph("no-such-pantograph")
    with pytest.raises(ParameterError, match="--force = '120/\\(t-t\\)'"):
        force_expression("120/(t-t)")
    with pytest.raises(ParameterError, match="contact_force = nan"):
        load_pantograph("en50318-2mass").static_equilibrium(float("nan"))


@pytest.mark.parametrize("name", ["dsa380-rigid", "dsa380-flexible", "dsa380-lumped3",
                                  "en50318-2mass"])
def test_preset_defaults_are_the_built_models(name):
    """The FMU's start values (preset_defaults, no model built) are the options and working
    height of the model the preset builds."""
    d = preset_defaults(name)
    if name != "dsa380-flexible":   # the flexible model's build is slow; same frame file
        model = load_pantograph(name)
        assert d.options == model.options
        q0 = model.static_equilibrium()
        assert model.contact_height(q0) == pytest.approx(d.working_height, abs=1e-9)
    assert d.options.static_force == (115.0 if name == "en50318-2mass" else 70.0)


def test_preset_defaults_of_a_broken_file_name_the_field(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[chain]\nmasses = [7.2, 15.0]\nstiffness = [4200.0, 50.0]\n"
                   "damping = [10.0, 90.0]\nworking_height = -5.3\n[options]\n"
                   "static_force = 70.0\n")
    with pytest.raises(ParameterError, match=r"chain.working_height = -5.3"):
        preset_defaults(bad)
    bad.write_text(bad.read_text().replace("working_height = -5.3", "working_height = 5.3")
                   .replace("static_force = 70.0", "static_force = -1.0"))
    with pytest.raises(ParameterError, match=r"static_force = -1.0"):
        preset_defaults(bad)
    bad.write_text(bad.read_text().replace("-1.0", "90.0"))
    assert preset_defaults(bad).options.static_force == 90.0


def test_cli_modal_json_and_pantograph_outputs(tmp_path, capsys):
    assert main(["modal", "en50318-2mass", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["frequencies_hz"] == sorted(data["frequencies_hz"])
    assert data["mode_labels"] == ["frame", "head"]
    assert len(data["damping_ratios"]) == 2
    out = tmp_path / "run"
    assert main(["pantograph", "dsa380-lumped3", "--force", "120 + 30*sin(4*pi*t)",
                 "--duration", "0.5", "--out", str(out)]) == 0
    csv = out / "dsa380-lumped3.csv"
    header = csv.read_text().splitlines()[0].split(",")
    assert header[:4] == ["time", "contact_force", "contact_height", "contact_velocity"]
    assert (out / "dsa380-lumped3.png").stat().st_size > 10000
    assert main(["pantograph", "en50318-2mass", "--force", "nan", "--duration", "1"]) == 2
    assert "--force = 'nan'" in capsys.readouterr().err

"""Stability of a run: the staggered couplings' limit before a run, the contact-frequency
warning of any coupling, the monitor that stops a diverging run, and the warnings in the
summaries of runs and sweeps (master/stability.py).

The measured breakpoints: en50318, 3 spans, 250 km/h, en50318-2mass, explicit (Jacobi) or
Gauss-Seidel, in-process subsystems (the FMUs' algorithm): the force runs away or the
pantograph leaves the wire (loss of contact above 1 %) from these stiffnesses on."""

import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pytest

from pantocosim.core.errors import ParameterError
from pantocosim.master import stability
from pantocosim.master.cli import main

SCENARIO = (Path(__file__).with_name("data") / "three-spans.toml").read_text() + """\

[simulation]
dt = {dt}
alpha = -0.05
{duration}
[contact]
stiffness = {k}
damping = {c}
"""

#: (dt [s], largest stiffness measured stable, smallest measured unstable [N/m])
MEASURED = [(0.001, 3e5, 4e5), (0.005, 8e4, 1.2e5), (0.01, 8e4, 1e5)]
#: unstable explicit / Gauss-Seidel settings seen in runs: (coupling, k [N/m], c [N s/m], dt [s], field)
ISSUE_ROWS = [("explicit", 1e7, 0.0, 0.001, "contact.stiffness"),
              ("explicit", 1e6, 0.0, 0.01, "contact.stiffness"),
              ("explicit", 1e7, 0.0, 0.01, "contact.stiffness"),
              ("explicit", 5e6, 0.0, 0.005, "contact.stiffness"),
              ("gauss-seidel", 1e7, 0.0, 0.01, "contact.stiffness"),
              ("explicit", 5e4, 1e5, 0.01, "contact.damping")]
HEAD_MASS = 7.2           # en50318-2mass: the head
WIRE_IMPEDANCE = 2.0 * math.sqrt(20000.0 * 1.35)   # en50318 contact wire


def scenario_file(folder: Path, k=5e4, c=0.0, dt=0.001, duration=None) -> Path:
    path = folder / "s.toml"
    extra = "" if duration is None else f"duration_s = {duration}\n"
    path.write_text(SCENARIO.format(k=k, c=c, dt=dt, duration=extra))
    return path


@pytest.fixture(scope="module")
def prepared(tmp_path_factory):
    from pantocosim.master.run import prepare

    return prepare(str(scenario_file(tmp_path_factory.mktemp("stab"))))


def with_contact(prep, k, c, dt):
    from pantocosim.core.penalty_contact import PenaltyContact

    sc = dataclasses.replace(prep.scenario, contact_stiffness=k, contact_damping=c, dt=dt)
    return dataclasses.replace(prep, scenario=sc, contact=PenaltyContact(k, c))


def gain(k, dt, c=0.0):
    return stability.exchange_gain(k, c, dt, HEAD_MASS, WIRE_IMPEDANCE)


def test_gain_separates_the_measured_breakpoints_at_1_ms():
    assert gain(3e5, 0.001) == pytest.approx(0.87, abs=0.01)
    assert gain(4e5, 0.001) == pytest.approx(1.16, abs=0.01)
    assert gain(3e5, 0.001) < stability.GAIN_LIMIT < gain(4e5, 0.001)


@pytest.mark.parametrize("dt,stable,unstable", MEASURED)
def test_gain_never_passes_a_measured_unstable_case(dt, stable, unstable):
    """Every stiffness measured unstable is refused; at longer steps the limit errs on the
    safe side (the catenary is stiffer there than a wire alone) by less than 3x."""
    assert gain(unstable, dt) >= stability.GAIN_LIMIT
    assert gain(stable, dt) < 3.0 * stability.GAIN_LIMIT


def test_default_contact_runs_unwarned_at_1_ms_and_is_warned_near_the_limit_at_5_ms():
    assert gain(5e4, 0.001) == pytest.approx(0.145, abs=0.005)
    assert stability.GAIN_WARNING <= gain(5e4, 0.005) < stability.GAIN_LIMIT


def test_contact_mass_and_wire_impedance_from_the_models(prepared):
    est = stability.estimates(prepared)[0]
    assert est.mass == pytest.approx(HEAD_MASS, rel=1e-9)
    assert est.impedance == pytest.approx(WIRE_IMPEDANCE, rel=1e-12)
    assert est.frequency == pytest.approx(math.sqrt(5e4 / 7.2) / (2 * math.pi), rel=1e-9)


def test_rigid_dsa380_contact_mass_is_its_linearised_mass_at_the_head():
    from pantocosim.pantograph.presets import load_pantograph

    pan = load_pantograph("dsa380-rigid")
    q0 = pan.static_equilibrium()
    m = stability.contact_mass(pan, q0, pan.options.mean_uplift)
    M, _, _ = pan.linearize(q0)
    g = pan.contact_height_gradient(q0)
    assert m == pytest.approx(1.0 / (g @ np.linalg.solve(M, g)), rel=1e-12)
    assert 1.0 < m < 50.0


@pytest.mark.parametrize("coupling,k,c,dt,field", ISSUE_ROWS)
def test_issue_rows_are_refused_naming_the_field_and_what_runs(prepared, coupling, k, c, dt,
                                                               field):
    from pantocosim.master.coupling import SCHEME_NAMES

    scheme = SCHEME_NAMES.get(coupling, coupling)
    with pytest.raises(ParameterError) as err:
        stability.check(with_contact(prepared, k, c, dt), scheme)
    text = str(err.value)
    assert err.value.field == field
    assert text.startswith(f"{Path(prepared.scenario.source).name}: {field} = ") or \
        text.startswith(f"{prepared.scenario.source}: {field} = ")
    for part in (f"simulation.dt = {dt:g} s", "exchange gain", "--coupling implicit",
                 "monolithic"):
        assert part in text, text
    if field == "contact.damping":   # c / Z_w >= 1 at any step
        assert "no step size runs it" in text and "contact.damping < 329 N s/m" in text
        return
    # the step and the stiffness the message proposes run
    proposed = float(text.split("simulation.dt <= ")[1].split(" s")[0])
    assert gain(k, proposed, c) < stability.GAIN_LIMIT * 1.05
    stiffness = float(text.split("contact.stiffness < ")[1].split(" N/m")[0])
    assert gain(stiffness, dt) == pytest.approx(stability.GAIN_LIMIT, rel=0.01)


def test_implicit_and_monolithic_are_not_refused_but_warned_when_unresolved(prepared):
    prep = with_contact(prepared, 1e7, 0.0, 0.001)
    for coupling in ("implicit", "monolithic"):
        warnings = stability.check(prep, coupling)
        assert len(warnings) == 1
        assert "contact frequency 188 Hz" in warnings[0]
        assert "dt = 0.001 s" in warnings[0]


def test_near_limit_is_warned(prepared):
    warnings = stability.check(with_contact(prepared, 5e4, 0.0, 0.005), "jacobi")
    assert any("near its stability limit" in w and "exchange gain 0.7" in w
               for w in warnings), warnings
    assert stability.check(prepared, "jacobi") == []


def test_monitor_stops_on_runaway_and_non_finite_forces(prepared):
    mon = stability.Monitor(prepared)
    cap = mon.cap[0]
    assert cap == pytest.approx(20.0 * max(115.0, prepared.static_forces[0]), rel=1e-9)
    mon.check(0.1, [cap * 0.99])
    with pytest.raises(stability.Diverged, match=r"^the numerics failed at t = 0\.25 s: the "
                       r"contact force of "
                       r"pantograph 1 \(2400 N\) exceeds 20 times"):
        mon.check(0.25, [2400.0])
    with pytest.raises(stability.Diverged, match="is not finite"):
        mon.check(0.3, [float("nan")])
    mon = stability.Monitor(prepared)
    mon.check(0.1, [100.0])
    mon.check(0.55, [0.0])
    with pytest.raises(stability.Diverged, match=r"^the numerics failed at t = 0\.61 s: "
                       r"pantograph 1 left the wire at t = 0\.1 s and has not come back"):
        mon.check(0.61, [0.0])


def test_a_diverging_run_stops_and_keeps_its_partial_results(prepared, monkeypatch, tmp_path):
    """Past the check (bypassed here), the explicit run at k = 1e7 N/m, dt = 10 ms diverges
    and the monitor stops it; the steps so far are kept and the summary says where."""
    from pantocosim.master.cosim import run_cosim
    from pantocosim.master.run import finish

    monkeypatch.setattr(stability, "check", lambda prep, coupling: [])
    prep = with_contact(prepared, 1e7, 0.0, 0.01)
    prep = dataclasses.replace(prep, n_steps=100)
    result = run_cosim(prep, tmp_path, scheme="jacobi", in_process=True, progress=False)
    assert isinstance(result.error, stability.Diverged)
    n = len(result.columns["time"])
    assert 2 < n < 101   # the pantograph leaves the wire at once and does not come back
    summary = finish(result, tmp_path, plots=False)
    assert summary["completed"] is False
    assert summary["stopped"]["steps"] == n - 1
    assert summary["stopped"]["reason"].startswith("the numerics failed at t = ")
    assert json.loads((tmp_path / "summary.json").read_text())["stopped"]["of_steps"] == 100


def test_run_command_warns_the_monolithic_1e7_case(tmp_path, capsys, monkeypatch):
    """The monolithic run at k = 1e7 N/m, dt = 1 ms: exit 0, the statistics flagged, the
    warning printed and in summary.json."""
    monkeypatch.chdir(tmp_path)
    path = scenario_file(tmp_path, k=1e7)
    code = main(["run", str(path), "--no-plots", "--quiet", "--out", str(tmp_path / "o")])
    out = capsys.readouterr().out
    assert code == 0
    assert "[FLAGGED" in out
    assert "WARNING: the pantograph: contact frequency 188 Hz" in out
    summary = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert len(summary["warnings"]) == 1 and "188 Hz" in summary["warnings"][0]
    assert summary["flagged"] is True


def test_run_command_summary_has_an_empty_warnings_list(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    path = scenario_file(tmp_path)
    assert main(["run", str(path), "--no-plots", "--quiet", "--out", str(tmp_path / "o")]) == 0
    assert "WARNING" not in capsys.readouterr().out
    summary = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert summary["warnings"] == [] and summary["flagged"] is False


@pytest.mark.slow
@pytest.mark.parametrize("coupling,k,c,dt,field", ISSUE_ROWS)
def test_run_command_refuses_the_issue_rows(tmp_path, capsys, monkeypatch, built, coupling,
                                           k, c, dt, field):
    """Through the command line with the FMUs: exit 2, one line, nothing written."""
    monkeypatch.chdir(built.parent.parent)
    path = scenario_file(tmp_path, k=k, c=c, dt=dt)
    out = tmp_path / "o"
    code = main(["run", str(path), "--coupling", coupling, "--no-plots", "--quiet",
                 "--out", str(out)])
    err = [l for l in capsys.readouterr().err.splitlines() if l.strip()
           and not l.startswith("building")]
    assert code == 2
    assert len(err) == 1 and f"s.toml: {field} = " in err[0] and "unstable" in err[0], err
    assert not out.exists()


@pytest.mark.slow
def test_run_command_warns_the_near_limit_case(tmp_path, capsys, monkeypatch, built):
    """Explicit through the FMUs, default contact at dt = 5 ms (G = 0.74): it runs, exit 0,
    the statistics flagged and the warning in summary.json."""
    monkeypatch.chdir(built.parent.parent)
    path = scenario_file(tmp_path, dt=0.005)
    code = main(["run", str(path), "--coupling", "explicit", "--no-plots", "--quiet",
                 "--out", str(tmp_path / "o")])
    out = capsys.readouterr().out
    assert code == 0
    assert "[FLAGGED" in out and "near its stability limit at dt = 0.005 s (exchange gain " \
        "0.74, refused at 1)" in out
    summary = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert len(summary["warnings"]) == 1
    assert summary["pantographs"][0]["statistics"]["mean_n"] == pytest.approx(116.1, abs=0.5)


def test_breakpoint_script_runs_a_short_case(monkeypatch, capsys):
    import importlib.util
    import sys

    path = Path(__file__).resolve().parents[1] / "scripts" / "stability_breakpoints.py"
    spec = importlib.util.spec_from_file_location("stability_breakpoints", path)
    script = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(script)
    monkeypatch.setattr(stability, "check", stability.check)   # the script replaces it
    monkeypatch.setattr(sys, "argv", ["x", "jacobi", "0.001", "5e4", "--duration", "0.05"])
    script.main()
    out = capsys.readouterr().out
    assert out.startswith("jacobi dt = 0.001 s, k = 5e+04 N/m: G = 0.15, max force ")
    assert "out of contact 0.0 % of the steps" in out

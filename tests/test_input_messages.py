"""Messages name the file and the field: the start-state failure (which start, which residual
against which tolerance, which setting), files named in a scenario (taken from the scenario's
folder), pantograph fields that leave no uplift at the scenario's speed (``run`` and
``modal``)."""

import json
import math
from pathlib import Path

import pytest

from pantocosim.core.errors import ConvergenceError
from pantocosim.master.cli import main

ROOT = Path(__file__).resolve().parents[1]
PANTOGRAPH = ROOT / "fmus" / "pantograph" / "data" / "en50318-2mass.toml"
CATENARY = ROOT / "fmus" / "catenary" / "data" / "en50318.toml"

SCENARIO = """\
name = "three-spans"
catenary = "{catenary}"
spans = 3
speed_kmh = 250.0

[[pantographs]]
model = "{model}"
position_m = {x}
{start}

[analysis]
window_supports = [1, 2]

[contact]
stiffness = {k}
"""
STATIC = 'start = "static"'
RAMP = 'start = "ramp"\nramp = { start_m = 10.0, length_m = 20.0, lowered_height = 5.0 }'


def scenario(folder: Path, catenary="en50318", model="en50318-2mass", k=5e4, ramp=False,
             name="s.toml") -> Path:
    path = folder / name
    path.write_text(SCENARIO.format(catenary=catenary, model=model, k=k,
                                    x=10.0 if ramp else 30.0, start=RAMP if ramp else STATIC))
    return path


def one_error_line(capsys) -> str:
    err = [l for l in capsys.readouterr().err.splitlines() if l.strip()]
    assert len(err) == 1, err
    return err[0]


# ------------------------------------------------------------------ the start state
@pytest.mark.parametrize("k,ramp", [(1e8, False), (1e12, False), (1e12, True), (5e4, True)])
def test_start_states_converge_to_round_off(tmp_path, k, ramp):
    """The start state converges when Newton's update reaches the coordinates' round-off:
    stiff contacts (a static start: the same force as with the default contact) and the
    lowered pantograph of a ramp start on three spans (its residual stays at 5e-9 N, above
    1e-10 times the catenary's forces)."""
    from pantocosim.master.run import prepare

    prep = prepare(str(scenario(tmp_path, k=k, ramp=ramp)))
    expected = 0.0 if ramp else 116.89
    assert prep.static_forces[0] == pytest.approx(expected, abs=0.01)


@pytest.mark.parametrize("ramp", [False, True])
def test_start_failure_names_the_start_the_residual_and_the_setting(tmp_path, capsys,
                                                                    monkeypatch, ramp):
    from pantocosim.interaction.coupled import CoupledSystem

    def fails(self, q0, t=0.0, tol=1e-10, max_iter=60):
        exc = ConvergenceError("static start did not converge", residual=6.574e-08)
        exc.tolerance = 1.0e-8
        raise exc

    monkeypatch.setattr(CoupledSystem, "static_solve", fails)
    path = scenario(tmp_path, k=1e8, ramp=ramp)
    assert main(["run", str(path), "--no-plots", "--quiet", "--out",
                 str(tmp_path / "o")]) == 2
    line = one_error_line(capsys)
    assert "residual 6.57e-08 N against the tolerance 1e-08 N" in line
    if ramp:
        assert f"{path}: catenary = 'en50318': the start state (pantograph 1: ramp start, " \
            "lowered) did not converge" in line
        assert "static start" not in line
    else:
        assert f"{path}: contact.stiffness = 1e+08: the start state (pantograph 1: static " \
            "start, in contact) did not converge" in line
        assert "a softer contact (default 50000 N/m) starts" in line


# ------------------------------------------------------------------ files named in a scenario
def test_relative_files_are_taken_from_the_scenario_folder(tmp_path, monkeypatch):
    from pantocosim.master.scenario import load_scenario

    (tmp_path / "data").mkdir()
    (tmp_path / "data" / "cat.toml").write_text(CATENARY.read_text())
    (tmp_path / "data" / "pan.toml").write_text(PANTOGRAPH.read_text())
    (tmp_path / "scenarios").mkdir()
    path = scenario(tmp_path / "scenarios", catenary="../data/cat.toml",
                    model="../data/pan.toml")
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    monkeypatch.chdir(elsewhere)
    sc = load_scenario(str(path))
    assert sc.catenary == str((tmp_path / "data" / "cat.toml").resolve())
    assert sc.pantographs[0].model == str((tmp_path / "data" / "pan.toml").resolve())


def test_a_missing_file_names_the_scenario_and_the_field(tmp_path, capsys, monkeypatch):
    (tmp_path / "scenarios").mkdir()
    path = scenario(tmp_path / "scenarios", catenary="../cat.toml")
    (tmp_path / "cat.toml").write_text(CATENARY.read_text())   # not where the scenario is
    monkeypatch.chdir(tmp_path / "scenarios")
    (tmp_path / "scenarios" / "sub").mkdir()
    monkeypatch.chdir(tmp_path / "scenarios" / "sub")   # ../cat.toml from here is wrong too
    path.write_text(path.read_text().replace("../cat.toml", "../nope.toml"))
    assert main(["run", str(path), "--no-plots", "--quiet"]) == 2
    line = one_error_line(capsys)
    assert line == (f"pantocosim run: error: {path}: catenary = '../nope.toml': no such file: "
                    f"{tmp_path / 'scenarios' / '..' / 'nope.toml'} (relative paths are taken "
                    "from the scenario's folder)")


# ------------------------------------------------------------------ pantograph fields
def test_negative_aero_c2_is_named_at_the_scenario_speed(tmp_path, capsys):
    pan = tmp_path / "neg.toml"
    pan.write_text(PANTOGRAPH.read_text().replace("aero_c2 = 0.0", "aero_c2 = -0.01"))
    path = scenario(tmp_path, model="neg.toml")
    assert main(["run", str(path), "--no-plots", "--quiet", "--out",
                 str(tmp_path / "o")]) == 2
    line = one_error_line(capsys)
    assert f"pantographs[0].model = '{pan}': {pan}: aero_c2 = -0.01: the mean uplift " \
        "static_force + aero_c1 v + aero_c2 v^2 = -510.0 N at 250 km/h: the pantograph " \
        "does not press on the wire (must be > 0)" in line
    assert "contact_force" not in line


def test_modal_warns_the_same_file(tmp_path, capsys):
    pan = tmp_path / "neg.toml"
    pan.write_text(PANTOGRAPH.read_text().replace("aero_c2 = 0.0", "aero_c2 = -0.01"))
    assert main(["modal", str(pan), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    top = math.sqrt(115.0 / 0.01)   # 107.2 km/h
    assert out["warnings"] == [
        f"neg.toml: options.aero_c2 = -0.01: the mean uplift static_force + aero_c1 v + "
        f"aero_c2 v^2 is zero at {top:.0f} km/h and negative above: the pantograph does "
        "not press on the wire there, and pantocosim run refuses it at those speeds"]
    assert main(["modal", "en50318-2mass", "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["warnings"] == []


def test_highest_speed_of_the_uplift_law():
    from pantocosim.pantograph.base import PantographOptions

    assert PantographOptions(static_force=115.0, aero_c2=-0.01).highest_speed_kmh() == \
        pytest.approx(math.sqrt(11500.0), rel=1e-12)
    assert PantographOptions(static_force=100.0, aero_c1=-0.5, aero_c2=0.0) \
        .highest_speed_kmh() == pytest.approx(200.0)
    assert PantographOptions().highest_speed_kmh() is None

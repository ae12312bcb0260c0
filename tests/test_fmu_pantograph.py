"""Pantograph FMUs: build, validation, port contract, rollback, bad input."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

#: FMUs or long runs: outside `pytest -m "not slow"` (CI runs everything)
pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[1]
PROBE = Path(__file__).with_name("fmu_probe.py")
LUMPED = ["dsa380-lumped3", "en50318-2mass"]
ALL = LUMPED + ["dsa380-rigid"]


@pytest.fixture(scope="module")
def fmus(fmus):
    """The session's pantograph FMUs of :data:`ALL`."""
    return {name: fmus[name] for name in ALL}


def probe(check, fmu, **args):
    proc = subprocess.run([sys.executable, str(PROBE), check, str(fmu), json.dumps(args)],
                          capture_output=True, text=True, timeout=600)
    lines = [l for l in proc.stdout.splitlines() if l.startswith("RESULT ")]
    assert proc.returncode == 0 and lines, proc.stdout + proc.stderr
    return json.loads(lines[-1][7:])


def test_the_staged_package_leaves_out_the_master_and_the_pendulum(tmp_path):
    """The package an FMU bundles: the models without the master and the multibody core
    (no FMU runs the pendulum) and the native FMUs' C sources, stamped as the installed package is stamped."""
    from pantocosim.core.stamp import UNBUNDLED, package_stamp
    from pantocosim.master.fmu.build import model_package_dir, stage_package

    pkg, stamp = stage_package(tmp_path)
    assert set(UNBUNDLED) == {"master", "multibody", "native"}
    assert (model_package_dir() / "multibody").is_dir()
    assert not any((pkg / name).exists() for name in UNBUNDLED)
    assert (pkg / "pantograph").is_dir() and (pkg / "catenary").is_dir()
    assert stamp.read_text().strip() == package_stamp(pkg) == package_stamp()


def test_every_fmu_bundles_the_models_only(built):
    """No FMU of the build (every preset's pantograph and the catenary) carries the master or
    the multibody core, and none is stale."""
    import zipfile

    from pantocosim.master.fmu.build import is_stale
    from pantocosim.pantograph.presets import PRESETS

    fmus = {p.stem: p for p in built.glob("*.fmu")}
    assert set(PRESETS) | {"catenary"} <= set(fmus)          # every FMU is checked
    for name, fmu in fmus.items():
        names = zipfile.ZipFile(fmu).namelist()
        assert any(n.startswith("resources/pantocosim/pantograph/") for n in names), name
        assert not [n for n in names if n.startswith(("resources/pantocosim/multibody/",
                                                     "resources/pantocosim/master/"))], name
        assert not is_stale(fmu), name


def test_every_pantograph_fmu_validates_with_the_same_ports(fmus):
    from fmpy import read_model_description
    from fmpy.validation import validate_fmu

    from pantocosim.pantograph.presets import preset_defaults

    ports = None
    assert set(fmus) == set(ALL)
    for name, path in fmus.items():
        assert validate_fmu(str(path)) == [], name
        md = read_model_description(str(path))
        sig = sorted((v.name, v.causality, v.unit) for v in md.modelVariables
                     if v.causality in ("input", "output"))
        if ports is None:
            ports = sig
        assert sig == ports, name
        assert md.coSimulation.canGetAndSetFMUstate and md.coSimulation.canSerializeFMUstate
        timing = next(v for v in md.modelVariables if v.name == "contact_force").description
        assert "t + h" in timing
        start = {v.name: v.start for v in md.modelVariables}
        d = preset_defaults(name)      # the start values are the preset's
        assert float(start["static_force"]) == d.options.static_force
        assert float(start["aero_c2"]) == d.options.aero_c2
        assert float(start["initial_height"]) == d.working_height
    assert ports == [("contact_force", "input", "N"), ("contact_height", "output", "m"),
                     ("contact_velocity", "output", "m/s"),
                     ("operating_height", "input", "m"),
                     ("operating_height_slope", "input", "m/N"),
                     ("static_height", "input", "m"), ("static_height_slope", "input", "m/N"),
                     ("train_speed_kmh", "input", "km/h")]


@pytest.mark.parametrize("name", ALL)
def test_fmu_matches_standalone_and_rolls_back_bitwise(fmus, name):
    from pantocosim.master.standalone import simulate_pantograph
    from pantocosim.pantograph.presets import load_pantograph

    res = probe("pantograph_trace", fmus[name], F0=120.0, steps=500)
    ref = simulate_pantograph(load_pantograph(name), lambda t: 120 + 30 * np.sin(4 * np.pi * t),
                              0.5, 1e-3)
    assert np.array_equal(np.array(res["heights"]), ref.contact_height[1:])
    assert res["rollback_equal"] and res["serialized_equal"]


def test_bad_input_is_discarded_with_a_message(fmus, tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[chain]\nmasses = [-7.2, 15.0]\nstiffness = [4200.0, 50.0]\n"
                   "damping = [10.0, 90.0]\nworking_height = 5.3\n")
    res = probe("pantograph_bad_input", fmus["en50318-2mass"], bad_file=str(bad))
    assert res["nan_status"] == 2  # fmi2Discard
    assert any("contact_force = nan" in m for m in res["nan_messages"])
    assert res["after_discard_height"] == pytest.approx(5.3, abs=0.01)
    assert res["bad_file_init_status"] == 3  # fmi2Error from fmi2ExitInitializationMode
    assert res["bad_file_status"] == 2
    assert any("chain.masses[0] = -7.2" in m for m in res["bad_file_messages"])

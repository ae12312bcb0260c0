"""The files of ``pantocosim export-native``: one FMU per pantograph, never one written over
another; each fixes its own pantograph's start (height and force)."""

import dataclasses
import re
import shutil
import zipfile
from pathlib import Path

import pytest

from pantocosim.master.cli import main
from test_bad_input import SCENARIO, SECOND, edited
from pantocosim.master.native.models import pantograph_files
from pantocosim.master.scenario import PantographSpec

TWO = edited(SCENARIO, ("\n[analysis]", SECOND.format(10.0) + "\n[analysis]"))


def spec(model: str) -> PantographSpec:
    return PantographSpec(model=model, position_m=0.0)


def test_pantographs_of_one_model_get_distinct_files():
    assert pantograph_files([spec("a")]) == ["a.fmu"]
    assert pantograph_files([spec("a"), spec("b")]) == ["a.fmu", "b.fmu"]
    assert pantograph_files([spec("a"), spec("b"), spec("a")]) == ["a-1.fmu", "b.fmu",
                                                                   "a-3.fmu"]


def fixed_start(fmu: Path, name: str) -> float:
    text = zipfile.ZipFile(fmu).read("modelDescription.xml").decode()
    return float(re.search(rf'name="{name}".*?start="([^"]+)"', text, re.S).group(1))


@pytest.mark.slow
def test_two_pantographs_of_one_model_are_two_fmus(tmp_path, capsys):
    """Two en50318-2mass pantographs 20 m apart: two FMUs, each with its pantograph's static
    contact force (as ``prepare`` gives it on the linear catenary, the export's default)."""
    from pantocosim.master.run import prepare
    from pantocosim.master.scenario import load_scenario

    if shutil.which("gcc") is None and shutil.which("cc") is None:
        pytest.skip("no C compiler")
    path = tmp_path / "two.toml"
    path.write_text(TWO)
    out = tmp_path / "out"
    assert main(["export-native", str(path), "--out", str(out), "--win64", "no"]) == 0
    files = sorted(p.name for p in out.iterdir())
    assert files == ["catenary.fmu", "en50318-2mass-1.fmu", "en50318-2mass-2.fmu"]
    sc = dataclasses.replace(load_scenario(str(path)), catenary_model="linear")
    forces = prepare(sc).static_forces
    assert abs(forces[0] - forces[1]) > 1e-6           # the two starts differ
    for k in (0, 1):
        got = fixed_start(out / f"en50318-2mass-{k + 1}.fmu", "initial_contact_force")
        assert got == pytest.approx(forces[k], rel=1e-12)

"""Refusals in one line (exit 2, naming the option or field, the value and what is
accepted) for cases that used to end in a traceback or a silent default: a modal cutoff above
what the model can keep, a contact law a native FMU cannot hold, bad environment values,
unwritable ``--out`` folders, a missing compiler, a third-party FMU's array port."""

from pathlib import Path

import pytest

from pantocosim.catenary.definition import load_catenary, with_spans
from pantocosim.catenary.linear import LinearCatenary
from pantocosim.catenary.modal import SPARE_MODES, ModalCatenary
from pantocosim.core.errors import ParameterError
from pantocosim.master.cli import main

SCENARIO = """\
name = "refused"
catenary = "en50318"
spans = 3
speed_kmh = 250.0

[[pantographs]]
model = "en50318-2mass"
position_m = 30.0
start = "static"

[analysis]
window_supports = [1, 2]
"""


def run_cli(capsys, *argv) -> tuple[int, list[str]]:
    try:
        code = main([str(a) for a in argv])
    except SystemExit as exc:   # argparse
        code = exc.code
    err = capsys.readouterr().err
    return code, [line for line in err.splitlines() if line.strip()]


def assert_one_line(code, lines, *names):
    assert code == 2, lines
    assert len(lines) == 1 and "Traceback" not in lines[0], lines
    for name in names:
        assert name in lines[0], f"{name!r} not in {lines[0]!r}"


def scenario(folder: Path, extra: str = "") -> Path:
    path = folder / "s.toml"
    path.write_text(SCENARIO + extra)
    return path


# ------------------------------------------------------------------ modal cutoff
@pytest.fixture(scope="module")
def lin2():
    return LinearCatenary(with_spans(load_catenary("en50318"), 2), x0=[20.0], speed=70.0)


def test_modal_cutoff_above_the_kept_modes_is_refused_with_the_highest_accepted(lin2):
    """A cutoff above every mode is refused naming the highest accepted cutoff, which builds
    and leaves 2 (droppers + pantographs) modes above it."""
    with pytest.raises(ParameterError) as info:
        ModalCatenary(linear=lin2, cutoff_hz=1e9)
    assert info.value.field == "modal_cutoff_hz" and "accepted" in info.value.reason
    highest = float(info.value.reason.split("at most ")[1].split(" Hz")[0])
    model = ModalCatenary(linear=lin2, cutoff_hz=highest)
    spare = SPARE_MODES * (len(lin2.droppers) + 1)
    assert model.m == lin2.n_dofs - spare and model.corrected


@pytest.mark.parametrize("command", ["run", "export-native"])
def test_modal_cutoff_above_the_modes_is_one_line_naming_the_option(tmp_path, capsys,
                                                                    command):
    code, lines = run_cli(capsys, command, scenario(tmp_path), "--catenary-model", "modal",
                          "--modal-cutoff-hz", "5000", "--out", tmp_path / "out")
    assert_one_line(code, lines, "--modal-cutoff-hz = 5000.0", "accepted", "at most")
    assert not (tmp_path / "out").exists()


def test_modal_cutoff_of_the_scenario_is_named_as_its_field(tmp_path, capsys):
    path = scenario(tmp_path, '\n[simulation]\ncatenary_model = "modal"\n'
                    "modal_cutoff_hz = 1e9\n")
    code, lines = run_cli(capsys, "run", path, "--out", tmp_path / "out")
    assert_one_line(code, lines, "s.toml", "simulation.modal_cutoff_hz = 1000000000.0",
                    "at most")


# ------------------------------------------------------------------ contact law
def test_export_native_refuses_the_constraint_law_before_the_set_up(tmp_path, capsys):
    path = scenario(tmp_path, '\n[contact]\nlaw = "constraint"\n')
    code, lines = run_cli(capsys, "export-native", path, "--out", tmp_path / "out")
    assert_one_line(code, lines, "s.toml", "contact.law = 'constraint'", '"penalty"')
    assert not (tmp_path / "out").exists()

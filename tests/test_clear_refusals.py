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
from short_scenarios import THREE_SPANS



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
    path.write_text(THREE_SPANS + extra)
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


# ------------------------------------------------------------------ output places, compiler
@pytest.fixture
def no_set_up(monkeypatch):
    """The scenario's set-up fails the test if it starts: the refusal comes before it."""
    import pantocosim.master.run as run_package

    def started(*args, **kwargs):
        raise AssertionError("the set-up started before the refusal")

    monkeypatch.setattr(run_package, "prepare", started)


@pytest.mark.parametrize("where, reason", [
    ("afile", "is a file, not a folder"), ("afile/sub", "a folder above it is a file"),
    ("/proc/pantocosim-x", "cannot create the folder")])
def test_export_native_out_is_checked_before_the_set_up(tmp_path, capsys, monkeypatch,
                                                        no_set_up, where, reason):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "afile").write_text("x")
    code, lines = run_cli(capsys, "export-native", scenario(tmp_path), "--out", where)
    assert_one_line(code, lines, f"--out = '{where}'", reason)
    assert not [p for p in tmp_path.iterdir() if p.name.endswith(".partial")]


def test_a_missing_compiler_in_cc_is_named_before_the_set_up(tmp_path, capsys, monkeypatch,
                                                             no_set_up):
    monkeypatch.setenv("CC", str(tmp_path / "no-such-gcc"))
    code, lines = run_cli(capsys, "export-native", scenario(tmp_path), "--out", tmp_path / "o")
    assert_one_line(code, lines, "CC = ", "no-such-gcc", "no such compiler")
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("where, reason", [
    ("afolder", "is a folder"), ("afile/x.json", "cannot be written there"),
    ("/proc/x.json", "cannot be written there")])
def test_bench_out_is_checked_before_the_benchmarks(tmp_path, capsys, monkeypatch, where,
                                                    reason):
    import pantocosim.master.benchmarks as benchmarks

    def started(*args, **kwargs):
        raise AssertionError("the benchmarks started before the refusal")

    monkeypatch.setattr(benchmarks, "bench", started)
    monkeypatch.chdir(tmp_path)
    (tmp_path / "afolder").mkdir()
    (tmp_path / "afile").write_text("x")
    code, lines = run_cli(capsys, "bench", "--quick", "--out", where)
    assert_one_line(code, lines, f"--out = '{where}'", reason)


# ------------------------------------------------------------------ third-party FMU ports
def test_an_array_port_of_a_third_party_fmu_is_named_as_an_array(tmp_path):
    """An FMI 3.0 pantograph whose contact_force is an array is refused as such, not as
    missing."""
    import zipfile

    from pantocosim.master.ssp import pantograph_connections

    ports = [("contact_force", "input", "<Dimension start=\"2\"/>"),
             ("contact_height", "output", ""), ("contact_velocity", "output", "")]
    variables = "".join(f'<Float64 name="{n}" valueReference="{i}" causality="{c}">{d}'
                        "</Float64>" for i, (n, c, d) in enumerate(ports))
    fmu = tmp_path / "array.fmu"
    with zipfile.ZipFile(fmu, "w") as z:
        z.writestr("modelDescription.xml", '<fmiModelDescription fmiVersion="3.0" '
                   'modelName="P" instantiationToken="{0}"><CoSimulation modelIdentifier="P"/>'
                   f"<ModelVariables>{variables}</ModelVariables></fmiModelDescription>")
    with pytest.raises(ParameterError) as info:
        pantograph_connections(fmu)
    assert info.value.value == "contact_force"
    assert "a Real array input instead of a Real input" in info.value.reason
    assert "missing" not in info.value.reason

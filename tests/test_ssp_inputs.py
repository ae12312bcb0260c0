"""`pantocosim ssp` and the third-party recipes check the FMU files they are given before
anything is built or run: the command never writes over its input, and an FMU without a binary
for this platform, with a model description inconsistent with its FMI version, or whose binary
or slave module is another model's is refused in one line (exit status 2)."""

import subprocess
import sys
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SHORT = ROOT / "tests" / "data" / "ssp-short.toml"
PORTS = {"contact_force": "input", "contact_height": "output", "contact_velocity": "output"}


def fake_fmu(path: Path, version="2.0", ident="Panto", binaries=None, slave=None,
             variable_tag=None) -> Path:
    """A zip with a model description of the pantograph ports, ``binaries`` {entry: bytes}
    (default: a linux64 library of ``ident`` exporting fmi2DoStep) and, when given, a
    PythonFMU slave module text."""
    attrs = {"guid": "{0}"} if version == "2.0" else {"instantiationToken": "{0}"}
    root = ET.Element("fmiModelDescription", fmiVersion=version, modelName=ident, **attrs)
    ET.SubElement(root, "CoSimulation", modelIdentifier=ident)
    variables = ET.SubElement(root, "ModelVariables")
    tag = variable_tag or ("ScalarVariable" if version == "2.0" else "Float64")
    for i, (name, causality) in enumerate(PORTS.items()):
        v = ET.SubElement(variables, tag, name=name, valueReference=str(i + 1),
                          causality=causality)
        if tag == "ScalarVariable":
            ET.SubElement(v, "Real")
    if binaries is None:
        binaries = {f"binaries/linux64/{ident}.so": b"\x7fELF ... fmi2DoStep ..."}
    with zipfile.ZipFile(path, "w") as z:
        z.writestr("modelDescription.xml", ET.tostring(root, encoding="unicode"))
        for entry, data in binaries.items():
            z.writestr(entry, data)
        if slave is not None:
            z.writestr("resources/slavemodule.txt", "slave_module")
            z.writestr("resources/slave_module.py", slave)
    return path


def ssp(*args):
    return subprocess.run([sys.executable, "-m", "pantocosim.master.cli", "ssp",
                           *map(str, args)], capture_output=True, text=True, timeout=600)


def one_line_refusal(proc, prefix: str) -> str:
    assert proc.returncode == 2, proc.stdout + proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in proc.stderr, proc.stderr
    assert lines[0].startswith(prefix), lines[0]
    return lines[0]


def test_the_ssp_command_never_writes_over_its_fmu(tmp_path):
    fmu = fake_fmu(tmp_path / "my.fmu")
    before = fmu.read_bytes()
    line = one_line_refusal(ssp("--pantograph", fmu, "--scenario", SHORT, "--out", fmu),
                            "pantocosim ssp: error: --out = ")
    assert "my.fmu" in line and "--pantograph" in line and "replace" in line, line
    assert fmu.read_bytes() == before
    link = tmp_path / "link.ssp"                    # the same file under another name
    link.symlink_to(fmu)
    one_line_refusal(ssp("--pantograph", fmu, "--scenario", SHORT, "--out", link),
                     "pantocosim ssp: error: --out = ")
    assert fmu.read_bytes() == before


@pytest.mark.parametrize("case, texts", [
    ("no binary", ["has no binary for this platform", "binaries/linux64/Panto.so", "win64"]),
    ("only sources", ["has no binary for this platform", "compile them for linux64"]),
    ("3.0 with 2.0 variables", ["fmiVersion 3.0", "FMI 2.0 variables (ScalarVariable)"]),
    ("2.0 with 3.0 variables", ["fmiVersion 2.0", "FMI 3.0 variables (Float64)"]),
    ("another model's binary", ["Catenary.so, not Panto.so", "modelIdentifier 'Panto'"]),
    ("an FMI 3.0 binary", ["does not export fmi2DoStep", "not an FMI 2.0"]),
    ("another model's slave", ["defines no class Panto", "slave_module.py"]),
])
def test_the_ssp_command_refuses_an_fmu_that_cannot_run_or_lies(tmp_path, case, texts):
    fmu = tmp_path / "p.fmu"
    if case == "no binary":
        fake_fmu(fmu, binaries={"binaries/win64/Panto.dll": b"fmi2DoStep"})
    elif case == "only sources":
        fake_fmu(fmu, binaries={"sources/panto.c": b"int x;"})
    elif case == "3.0 with 2.0 variables":
        fake_fmu(fmu, version="3.0", variable_tag="ScalarVariable",
                 binaries={"binaries/x86_64-linux/Panto.so": b"fmi3DoStep"})
    elif case == "2.0 with 3.0 variables":
        fake_fmu(fmu, variable_tag="Float64")
    elif case == "another model's binary":
        fake_fmu(fmu, binaries={"binaries/linux64/Catenary.so": b"fmi2DoStep"})
    elif case == "an FMI 3.0 binary":
        fake_fmu(fmu, binaries={"binaries/linux64/Panto.so": b"fmi3DoStep"})
    else:
        fake_fmu(fmu, slave="class Catenary(Fmi2Slave):\n    pass\n")
    out = tmp_path / "x.ssp"
    proc = ssp("--pantograph", fmu, "--scenario", SHORT, "--out", out)
    line = one_line_refusal(proc, "pantocosim ssp: error: ")
    assert all(t in line for t in texts), line
    assert not out.exists()


def test_a_consistent_fmu_passes_the_checks(tmp_path):
    from pantocosim.master.fmu.binary_check import check_binary_fmu

    check_binary_fmu(fake_fmu(tmp_path / "a.fmu", slave="class Panto(X):\n    pass\n"), "fmu")
    check_binary_fmu(fake_fmu(tmp_path / "b.fmu", version="3.0", binaries={
        "binaries/x86_64-linux/Panto.so": b"fmi3DoStep"}), "fmu")


def recipe(name, *args, cwd):
    return subprocess.run([sys.executable, "-m", f"pantocosim.master.thirdparty.{name}",
                           *map(str, args)], capture_output=True, text=True, timeout=600,
                          cwd=cwd)


def test_the_recipes_refuse_a_lying_fmu_in_one_line(tmp_path):
    fmu = fake_fmu(tmp_path / "p.fmu", binaries={"binaries/linux64/Catenary.so": b"fmi2DoStep"})
    line = one_line_refusal(recipe("fmpy_single", "--fmu", fmu, "--stop", "0.01",
                                   cwd=tmp_path), "pantocosim.master.thirdparty.fmpy_single: ")
    assert "Catenary.so, not Panto.so" in line, line
    package = tmp_path / "s.ssp"
    with zipfile.ZipFile(package, "w") as z:
        z.writestr("SystemStructure.ssd", (
            '<ssd:SystemStructureDescription xmlns:ssd="http://ssp-standard.org/SSP1/'
            'SystemStructureDescription" version="1.0" name="x"><ssd:System name="s">'
            '<ssd:Elements><ssd:Component name="pantograph" source="resources/p.fmu"/>'
            '</ssd:Elements></ssd:System></ssd:SystemStructureDescription>'))
        z.write(fmu, "resources/p.fmu")
    for name, tool in (("fmpy_ssp", "fmpy"), ("libcosim", "libcosim")):
        line = one_line_refusal(recipe(name, "--ssp", package, cwd=tmp_path),
                                f"{tool} recipe: error: ")
        assert "component 'pantograph' = 'resources/p.fmu'" in line, line
        assert "Catenary.so, not Panto.so" in line, line


def test_a_failed_recipe_child_is_one_line_naming_its_log(tmp_path, capsys):
    from pantocosim.master.thirdparty.common import failed

    proc = subprocess.CompletedProcess([], 1, stdout="WALL 1\n", stderr=(
        "Traceback (most recent call last):\n  File \"x\", line 1\n    boom()\n"
        "fmpy.FMUError: fmi2DoStep failed\n"))
    with pytest.raises(SystemExit) as stop:
        failed("recipe", proc)
    line = str(stop.value.code)
    assert "\n" not in line and "fmpy.FMUError: fmi2DoStep failed" in line, line
    log = Path(line.rsplit("its output: ", 1)[1].rstrip(")"))
    assert "Traceback" in log.read_text()
    log.unlink()
    assert capsys.readouterr().err == ""

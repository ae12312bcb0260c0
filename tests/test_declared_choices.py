"""A choice between implementations is declared (a protocol, a registry, a type), never
guessed from the attributes an object happens to have: no ``hasattr`` in the package except
on the standard library's modules, whose members depend on the platform."""

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: modules whose members differ between platforms (os.getloadavg, signal.pause)
PLATFORM_MODULES = {"os", "signal"}


def hasattr_calls(path: Path, root: Path = ROOT) -> list[str]:
    """``file:line`` of each hasattr(...) whose object is not a platform module."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if (isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
                and node.func.id == "hasattr" and node.args
                and not (isinstance(node.args[0], ast.Name)
                         and node.args[0].id in PLATFORM_MODULES)):
            found.append(f"{path.relative_to(root)}:{node.lineno}")
    return found


def test_no_hasattr_chooses_an_implementation():
    files = sorted(p for d in ("fmus", "master") for p in (ROOT / d).rglob("*.py"))
    assert len(files) > 100
    assert [hit for p in files for hit in hasattr_calls(p)] == []


def test_the_check_finds_a_hasattr(tmp_path):
    sample = tmp_path / "sample.py"
    sample.write_text("import os\nx = hasattr(os, 'getloadavg')\ny = hasattr(x, 'solve')\n")
    assert hasattr_calls(sample, tmp_path) == ["sample.py:3"]

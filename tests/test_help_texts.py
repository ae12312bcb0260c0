"""Version words in what users read first: every help text of the command line and of
build_fmus.py, and the project's one-line descriptions, that names an FMI version names both
versions the FMUs and the commands accept (2.0 and 3.0)."""

import argparse
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from pantocosim.master.cli import build_parser

ROOT = Path(__file__).resolve().parents[1]
VERSION = re.compile(r"\b([23])\.0\b")


def _parsers(parser: argparse.ArgumentParser, path: str):
    """(command path, parser) of ``parser`` and of every subcommand below it."""
    yield path, parser
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield from _parsers(sub, f"{path} {name}")


def stale(text: str) -> str | None:
    """What is wrong with ``text``: it names FMI and one version but not the other."""
    text = " ".join(text.split())
    if "FMI" not in text:
        return None
    versions = set(VERSION.findall(text))
    if versions and versions != {"2", "3"}:
        return f"names FMI {' and '.join(sorted(v + '.0' for v in versions))} only"
    return None


def test_the_rule_catches_a_single_version():
    assert stale("Pantograph-catenary interaction as FMI 2.0 co-simulation.") is not None
    assert stale("your pantograph FMU (FMI 3.0)") is not None
    assert stale("your pantograph FMU (FMI 2.0 or 3.0)") is None
    assert stale("simulate a scenario and print EN 50317 statistics") is None


def test_every_command_help_names_both_fmi_versions():
    found = [f"{path}: {why}" for path, parser in _parsers(build_parser(), "pantocosim")
             if (why := stale(parser.format_help()))]
    assert not found, "\n".join(found)


def test_build_fmus_script_help_names_both_fmi_versions():
    out = subprocess.run([sys.executable, str(ROOT / "build_fmus.py"), "--help"],
                         capture_output=True, text=True, timeout=120, check=True).stdout
    assert "--fmi" in out and stale(out) is None, out


@pytest.mark.parametrize("where", ["pyproject", "mkdocs", "package", "home", "readme"])
def test_project_descriptions_name_both_fmi_versions(where):
    if where == "pyproject":
        text = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["description"]
    elif where == "mkdocs":
        text = re.search(r"^site_description: (.*)$", (ROOT / "mkdocs.yml").read_text(),
                         re.M).group(1)
    elif where == "package":
        import pantocosim

        text = pantocosim.__doc__.split("\n\n")[0]
    else:
        page = ROOT / ("docs/index.md" if where == "home" else "README.md")
        text = page.read_text().split("\n\n")[1]        # the paragraph under the title
    assert "FMI" in text and stale(text) is None, text

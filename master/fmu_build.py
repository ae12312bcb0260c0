"""Entry point of the FMU build for the CLI: delegates to the repository's ``build_fmus.py``
(the builder stages the installed model package, so it works from any working folder)."""

from __future__ import annotations

import importlib.util
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_OUT = ROOT / "dist" / "fmus"


def _builder():
    path = ROOT / "build_fmus.py"
    spec = importlib.util.spec_from_file_location("pantocosim_build_fmus", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def build_fmus(out: Path = DEFAULT_OUT, only=None, quiet: bool = False):
    return _builder().build(Path(out), only=only, quiet=quiet)

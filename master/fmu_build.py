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


def is_stale(fmu: Path) -> bool:
    """True when the FMU bundles another version of the model package than the one installed
    (its build stamp differs): such an FMU refuses to initialise, so it is rebuilt."""
    from pantocosim.fmi.slave_base import bundled_stamp, package_stamp

    return bundled_stamp(fmu) != package_stamp()


def ensure_fmus(paths, out: Path = DEFAULT_OUT) -> None:
    """Build the FMUs among ``paths`` (files in ``out``) that are missing or stale (built from
    another version of the model package than the installed one)."""
    import sys

    todo = sorted({Path(p).stem for p in paths
                   if Path(p).parent == Path(out) and (not Path(p).exists() or is_stale(p))})
    if todo:
        print(f"building FMUs {', '.join(todo)} into {out}", file=sys.stderr, flush=True)
        build_fmus(out, only=todo, quiet=True)

"""Shared fixtures: the FMUs are built once per test session, as ``pantocosim build-fmus``
builds them (generic FMUs, the default scenario's FMUs, SSP file and CoFmuPy configuration)."""

import pytest


@pytest.fixture(scope="session")
def built(tmp_path_factory):
    """The output folder of ``pantocosim build-fmus``."""
    from pantocosim.master.fmu_build import build_all

    out = tmp_path_factory.mktemp("dist") / "fmus"
    build_all(out, quiet=True)
    return out


@pytest.fixture(scope="session")
def fmus(built):
    """The generic FMUs by name."""
    return {p.stem: p for p in built.glob("*.fmu")}

"""Shared fixtures and the run's own folders.

Every cache the project keeps in the user's home (extracted FMUs, generated kernels, set-up
results) goes to a folder of this run instead, shared by its pytest-xdist workers: suites
started side by side do not meet, and a fresh home behaves like any other. The FMUs are built
once per run, as ``pantocosim build-fmus`` builds them (generic FMUs, the default scenario's
FMUs, SSP file and CoFmuPy configuration): the first worker builds them under a file lock, the
others reuse them. Tests that use them are part of the full suite (marked slow here)."""

import os
from pathlib import Path

import pytest
from filelock import FileLock
from tooling import missing

#: the cache (and matplotlib's configuration) variables and the folder each one names under
#: the run's folder
CACHE_VARIABLES = {"XDG_CACHE_HOME": "cache", "PANTOCOSIM_FMU_CACHE": "cache/pantocosim/fmus",
                   "PANTOCOSIM_KERNEL_DIR": "cache/pantocosim/kernels",
                   "PANTOCOSIM_CACHE_DIR": "cache/pantocosim/setup",
                   "MPLCONFIGDIR": "config/matplotlib"}


def pytest_collection_modifyitems(items):
    """Tests that need the built FMUs (the ``built`` fixture, directly or through another)
    belong to the full suite: they are marked slow."""
    for item in items:
        if "built" in getattr(item, "fixturenames", ()):
            item.add_marker(pytest.mark.slow)


def run_folder(tmp_path_factory) -> Path:
    """The folder of this run, the same for every xdist worker (each worker's base temp is a
    subfolder of the run's)."""
    base = tmp_path_factory.getbasetemp()
    return base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base


@pytest.fixture(scope="session", autouse=True)
def run_caches(tmp_path_factory):
    """Points the project's caches (and XDG_CACHE_HOME, for the libraries) to the run's folder
    for the whole session, child processes included."""
    root = run_folder(tmp_path_factory)
    saved = {name: os.environ.get(name) for name in CACHE_VARIABLES}
    for name, sub in CACHE_VARIABLES.items():
        os.environ[name] = str(root / sub)
    yield root / "cache"
    for name, value in saved.items():
        if value is None:
            os.environ.pop(name, None)
        else:
            os.environ[name] = value


def once_per_run(tmp_path_factory, name: str, make) -> Path:
    """``run folder / name``, made by ``make(path)`` by the first worker that asks (the others
    wait on a file lock and reuse it)."""
    root = run_folder(tmp_path_factory)
    path = root / name
    done = root / f"{name}.done"
    with FileLock(str(root / f"{name}.lock")):
        if not done.exists():
            make(path)
            done.touch()
    return path


@pytest.fixture(scope="session")
def built(tmp_path_factory, run_caches):
    """The output folder of ``pantocosim build-fmus``."""
    from pantocosim.master.fmu.dist import build_all

    return once_per_run(tmp_path_factory, "dist", lambda d: build_all(d / "fmus", quiet=True)) \
        / "fmus"


@pytest.fixture(scope="session")
def fmus(built):
    """The generic FMUs by name."""
    return {p.stem: p for p in built.glob("*.fmu")}


@pytest.fixture(scope="session")
def cofmupy_python(tmp_path_factory, run_caches) -> str:
    """The Python of a venv holding CoFmuPy 1.0 (it pins pythonfmu 0.6.3, this project 0.7.0,
    so it cannot share the test venv): the venv named by PANTOCOSIM_COFMUPY_VENV, or one made
    for this run from the package index. Where it cannot be installed the test is skipped (on
    CI, where CI is set, it fails)."""
    given = os.environ.get("PANTOCOSIM_COFMUPY_VENV")
    venv = Path(given) if given else once_per_run(tmp_path_factory, "cofmupy-venv", _make_venv)
    python = venv / "bin" / "python"
    problem = _cofmupy_problem(python)
    if problem:
        missing(f"a Python with cofmupy==1.0.0 and numba at {venv} ({problem})",
                "set PANTOCOSIM_COFMUPY_VENV or let the run make the venv")
    return str(python)


def _make_venv(venv: Path) -> None:
    """A venv with CoFmuPy 1.0 and numba (a failed install leaves it without them)."""
    import subprocess
    import sys

    made = subprocess.run([sys.executable, "-m", "venv", str(venv)], capture_output=True,
                          text=True)
    if made.returncode == 0:
        made = subprocess.run([str(venv / "bin" / "python"), "-m", "pip", "install", "-q",
                               "--no-cache-dir", "cofmupy==1.0.0", "numba"],
                              capture_output=True, text=True, timeout=900)
    venv.mkdir(exist_ok=True)
    (venv / "install.log").write_text(made.stdout + made.stderr)


def _cofmupy_problem(python: Path) -> str:
    """Why ``python`` cannot run the CoFmuPy recipe ('' when it can)."""
    import subprocess

    if not python.exists():
        return f"the venv has no bin/python (see {python.parent.parent / 'install.log'})"
    check = subprocess.run([str(python), "-c", "import cofmupy, numba"], capture_output=True,
                           text=True)
    return (check.stderr.strip().splitlines() or ["import failed"])[-1] \
        if check.returncode else ""

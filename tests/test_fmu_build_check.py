"""An FMU without a binary for this platform is never written by ``build-fmus`` and never
loaded by a run: both say so in one line naming the file."""

import zipfile

import pytest

import pantocosim.master.fmu.build as build
from pantocosim.core.errors import ParameterError
from pantocosim.master.fmu.runtime import FmuError, FmuInstance


def without_binaries(fmu):
    """Rewrite the FMU file ``fmu`` without its ``binaries/`` folder."""
    tmp = fmu.with_name(fmu.name + ".stripped")
    with zipfile.ZipFile(fmu) as src, zipfile.ZipFile(tmp, "w") as dst:
        for info in src.infolist():
            if not info.filename.startswith("binaries/"):
                dst.writestr(info, src.read(info))
    tmp.replace(fmu)


def test_a_built_fmu_without_its_binary_is_refused_and_not_written(tmp_path, monkeypatch):
    install = build.install_export_library

    def install_and_lose_the_binaries(fmu, library, fmi=2):
        install(fmu, library, fmi)
        without_binaries(fmu)

    monkeypatch.setattr(build, "install_export_library", install_and_lose_the_binaries)
    with pytest.raises(ParameterError, match="has no binary for this platform") as refused:
        build.build_fmus(tmp_path / "out", only=["en50318-2mass"], quiet=True)
    assert "build-fmus" in str(refused.value) and "no binaries" in str(refused.value)
    assert not (tmp_path / "out" / "en50318-2mass.fmu").exists()


def test_a_run_refuses_an_fmu_whose_binary_cannot_be_loaded(tmp_path):
    (fmu,) = build.build_fmus(tmp_path / "out", only=["en50318-2mass"], quiet=True)
    without_binaries(fmu)
    with pytest.raises(FmuError) as refused:
        FmuInstance(fmu, "pantograph_1")
    message = str(refused.value)
    assert "pantograph_1" in message and str(fmu) in message
    assert "its binary cannot be loaded" in message and len(message.splitlines()) == 1


def test_an_fmu_built_after_a_python_fmu_ran_in_the_process_has_its_binary(tmp_path):
    """A Python FMU run in a process puts its own copy of pythonfmu first on sys.path; an
    FMU built afterwards in that process still takes the installed builder and its
    binaries."""
    import subprocess
    import sys

    (first,) = build.build_fmus(tmp_path / "a", only=["en50318-2mass"], quiet=True)
    script = (
        "import zipfile\n"
        "from pathlib import Path\n"
        "from pantocosim.master.fmu.runtime import FmuInstance\n"
        f"FmuInstance(Path({str(first)!r}), 'p1')\n"
        "from pantocosim.master.fmu.build import build_fmus\n"
        f"(later,) = build_fmus(Path({str(tmp_path / 'b')!r}), only=['dsa380-rigid'],"
        " quiet=True)\n"
        "print(sorted(n for n in zipfile.ZipFile(later).namelist()"
        " if n.startswith('binaries/')))\n")
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          timeout=300)          # a fresh process: pytest's has pythonfmu
    assert done.returncode == 0, done.stderr
    assert "binaries/linux64/Dsa380Rigid.so" in done.stdout, done.stdout

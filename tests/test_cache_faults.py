"""Caches never stop a run: an extracted FMU folder that is damaged is extracted again, and an
FMU cache folder that cannot be written leaves each FMU extracted into a temporary folder;
either way with one warning naming the folder (the set-up and kernel caches are tested in
test_disk_cache.py and test_kernel_cache.py)."""

import zipfile

import pytest

from pantocosim.core import user_cache
from pantocosim.master.fmu.runtime import extract_cached

FILES = {"modelDescription.xml": "<fmiModelDescription fmiVersion='2.0'/>\n" * 20,
         "resources/model.py": "x = 1\n" * 50}


@pytest.fixture
def fmu(tmp_path, monkeypatch):
    monkeypatch.setattr(user_cache, "_warned", set())
    monkeypatch.setenv("PANTOCOSIM_FMU_CACHE", str(tmp_path / "fmus"))
    path = tmp_path / "demo.fmu"
    with zipfile.ZipFile(path, "w") as archive:
        for name, text in FILES.items():
            archive.writestr(name, text)
    return path


def contents(folder):
    return {name: (folder / name).read_text() for name in FILES}


@pytest.mark.parametrize("damage", ["truncated", "edited", "removed"])
def test_a_damaged_extracted_fmu_is_extracted_again(fmu, tmp_path, damage):
    first = extract_cached(fmu)
    assert (first / ".complete").exists() and contents(first) == FILES
    md = first / "modelDescription.xml"
    if damage == "truncated":
        md.write_text(FILES["modelDescription.xml"][:30])
    elif damage == "edited":
        md.write_text(FILES["modelDescription.xml"].replace("2.0", "3.0"))
    else:
        md.unlink()
    with pytest.warns(UserWarning, match="extracted FMU damaged") as seen:
        again = extract_cached(fmu)
    assert len(seen) == 1 and "modelDescription.xml" in str(seen[0].message)
    assert again == first and contents(again) == FILES


def test_a_sound_extracted_fmu_is_reused_without_a_word(fmu, recwarn):
    first = extract_cached(fmu)
    (first / "resources" / "__pycache__").mkdir()          # what Python adds is not damage
    (first / "resources" / "__pycache__" / "model.pyc").write_bytes(b"\0")
    assert extract_cached(fmu) == first and not recwarn.list


def test_a_file_where_the_fmu_cache_should_be(fmu, tmp_path):
    (tmp_path / "fmus").write_text("not a folder")
    with pytest.warns(UserWarning, match="PANTOCOSIM_FMU_CACHE") as seen:
        folder = extract_cached(fmu)
    assert len(seen) == 1 and str(tmp_path / "fmus") in str(seen[0].message)
    assert contents(folder) == FILES and (tmp_path / "fmus").read_text() == "not a folder"


SIMULATE = """import sys
from fmpy import simulate_fmu
rows = simulate_fmu(sys.argv[1], stop_time=0.05, step_size=1e-3, output_interval=1e-3)
print(len(rows), float(rows["contact_height"][-1]))
"""


@pytest.fixture(scope="module")
def pantograph_fmu(tmp_path_factory):
    from pantocosim.master.fmu.build import build_fmus

    (fmu,) = build_fmus(tmp_path_factory.mktemp("fmus"), only=["en50318-2mass"], quiet=True)
    return fmu


def simulate_in_fmpy(fmu, cache_home):
    import os
    import subprocess
    import sys

    env = {k: v for k, v in os.environ.items()
           if not k.startswith(("PANTOCOSIM_", "NUMBA_"))}
    env["XDG_CACHE_HOME"] = str(cache_home)
    done = subprocess.run([sys.executable, "-c", SIMULATE, str(fmu)], env=env, text=True,
                          capture_output=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    rows, height = done.stdout.split()
    return int(rows), float(height), [l for l in done.stderr.splitlines() if l.strip()]


@pytest.mark.slow
def test_the_fmu_runs_beside_damaged_or_unusable_caches(pantograph_fmu, tmp_path):
    """Inside an FMU run by fmpy: damaged kernel and set-up entries, then a file where the
    cache root should be; every run gives every row and the same result."""
    cache = tmp_path / "cache"
    rows, height, warned = simulate_in_fmpy(pantograph_fmu, cache)
    assert rows == 51 and not warned
    damaged = list(cache.rglob("*.nb[ic]")) + list(cache.rglob("*.npz"))
    assert any(p.suffix == ".nbi" for p in damaged)
    for p in damaged:
        p.write_bytes(p.read_bytes()[: p.stat().st_size // 3])
    again = simulate_in_fmpy(pantograph_fmu, cache)
    assert again[:2] == (rows, height)
    assert again[2] and all(l.startswith("pantocosim: warning: cache ") for l in again[2])
    assert simulate_in_fmpy(pantograph_fmu, cache) == (rows, height, [])   # rebuilt
    blocked = tmp_path / "blocked"
    blocked.mkdir()
    (blocked / "pantocosim").write_text("a file")
    rows_b, height_b, warned_b = simulate_in_fmpy(pantograph_fmu, blocked)
    assert (rows_b, height_b) == (rows, height)
    assert warned_b and all(str(blocked / "pantocosim") in l for l in warned_b)

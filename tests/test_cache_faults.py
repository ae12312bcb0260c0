"""Caches never stop a run: an extracted FMU folder that is damaged is extracted again, and an
FMU cache folder that cannot be written leaves each FMU extracted into a temporary folder;
either way with one warning naming the folder (the set-up and kernel caches are tested in
test_disk_cache.py and test_kernel_cache.py)."""

import zipfile

import pytest

from pantocosim.core import user_cache
from pantocosim.master.fmu_runtime import extract_cached

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

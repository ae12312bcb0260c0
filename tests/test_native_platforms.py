"""The native FMUs' sources on the six platforms of the Modelica Reference-FMUs, built with
the clang of the ``ziglang`` wheel (-std=c99 -pedantic -Werror, the FMI 3.0 front): each
binary has its platform's format and exports the FMI functions; a clang build for a CPU
with fused multiply-add, without -ffp-contract=off, holds no fused multiply-add (the sources
forbid them) and gives the gcc linux64 binaries' coupled run bit for bit. The macOS binaries
are checked for their format and exports only (untested on Apple hardware)."""

import dataclasses
import shutil
import subprocess
import sys
import zipfile

import pytest

from test_native_fmus import run_host
from tooling import required

pytestmark = pytest.mark.slow

#: zig target: (FMI 2.0 folder, FMI 3.0 folder, extension, file magic, machine)
TARGETS = {
    "x86_64-linux-gnu": ("linux64", "x86_64-linux", "so", b"\x7fELF", b"\x3e\x00"),
    "aarch64-linux-gnu": ("linux64", "aarch64-linux", "so", b"\x7fELF", b"\xb7\x00"),
    "x86_64-windows-gnu": ("win64", "x86_64-windows", "dll", b"MZ", b"\x64\x86"),
    "x86-windows-gnu": ("win32", "x86-windows", "dll", b"MZ", b"\x4c\x01"),
    "x86_64-macos": ("darwin64", "x86_64-darwin", "dylib", b"\xcf\xfa\xed\xfe", b"\x07\x00"),
    "aarch64-macos": ("darwin64", "aarch64-darwin", "dylib", b"\xcf\xfa\xed\xfe", b"\x0c\x00"),
}
FLAGS = ["-std=c99", "-O3", "-Wall", "-Wextra", "-pedantic", "-Werror", "-shared", "-fPIC"]


def zig_cc(target, sources, out, extra=()):
    pytest.importorskip("ziglang")
    subprocess.run([sys.executable, "-m", "ziglang", "cc", "-target", target, *FLAGS, *extra,
                    f"-I{sources}", *map(str, sorted(sources.glob("*.c"))), "-o", str(out)],
                   check=True, capture_output=True, timeout=600)


@pytest.fixture(scope="module")
def fmus(tmp_path_factory):
    """The FMI 2.0 and 3.0 native FMUs of en50318-300 on six spans, unpacked."""
    from pantocosim.master.native.models import export_scenario
    from pantocosim.master.run import prepare
    from pantocosim.master.scenario import load_scenario

    required("gcc", "gcc")
    out = tmp_path_factory.mktemp("platforms")
    prep = prepare(dataclasses.replace(load_scenario("en50318-300"), catenary_model="linear",
                                       spans=6, window_supports=(1, 3)))
    folders = {}
    for fmi in (2, 3):
        for fmu in export_scenario(prep, out / f"fmi{fmi}", fmi=fmi, win64=False)[0]:
            name = "catenary" if fmu.stem == "catenary" else "pantograph"
            with zipfile.ZipFile(fmu) as z:
                z.extractall(out / f"{name}{fmi}")
            folders[name, fmi] = out / f"{name}{fmi}"
    return folders


def test_six_platforms_build_with_their_format_and_exports(fmus, tmp_path):
    for fmi in (3,):
        sources = fmus["catenary", fmi] / "sources"
        for target, (folder2, folder3, ext, magic, machine) in TARGETS.items():
            out = tmp_path / f"{target}-{fmi}.{ext}"
            zig_cc(target, sources, out, ["-O1"])
            data = out.read_bytes()
            assert data.startswith(magic), target
            if magic == b"\x7fELF":
                assert data[18:20] == machine, target
            elif magic == b"MZ":
                pe = int.from_bytes(data[60:64], "little")
                assert data[pe:pe + 4] == b"PE\0\0" and data[pe + 4:pe + 6] == machine, target
            else:
                assert data[4:6] == machine, target
            assert f"fmi{fmi}DoStep".encode() in data, target


def test_a_clang_build_with_fma_gives_the_linux64_bits(fmus, tmp_path):
    rows = {}
    for build in ("gcc", "clang"):
        cat = shutil.copytree(fmus["catenary", 2], tmp_path / f"cat-{build}")
        pan = shutil.copytree(fmus["pantograph", 2], tmp_path / f"pan-{build}")
        if build == "clang":
            for folder, name in ((cat, "catenary"), (pan, "pantograph")):
                lib = folder / "binaries" / "linux64" / f"pantocosim_{name}_native.so"
                zig_cc("x86_64-linux-gnu", folder / "sources", lib, ["-mcpu=haswell"])
                assert objdump_fma(lib) == 0
        rows[build], _ = run_host(host_exe(tmp_path), ["coupled", cat, pan, 300, 0.001],
                                  tmp_path)
    assert rows["clang"].tobytes() == rows["gcc"].tobytes()


def objdump_fma(lib) -> int:
    """The fused multiply-adds in a library's code."""
    objdump = required("objdump", "binutils")
    text = subprocess.run([objdump, "-d", str(lib)], capture_output=True, text=True).stdout
    return text.count("vfmadd") + text.count("vfmsub") + text.count("vfnmadd")


def host_exe(tmp_path):
    from test_native_fmus import CFLAGS, HOST_SOURCE

    exe = tmp_path / "realtime_host"
    if not exe.exists():
        subprocess.run([required("gcc", "gcc"), *CFLAGS, "-D_POSIX_C_SOURCE=200809L", "-o",
                        str(exe), str(HOST_SOURCE), "-ldl", "-lm"], check=True)
    return exe

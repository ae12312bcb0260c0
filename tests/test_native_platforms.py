"""The native FMUs' sources on the six platforms of the Modelica Reference-FMUs, built with
the clang of the ``ziglang`` wheel (-std=c99 -pedantic -Werror, the FMI 3.0 front): each
binary has its platform's format and exports the FMI functions; a clang build for a CPU
with fused multiply-add, without -ffp-contract=off, holds no fused multiply-add (the sources
forbid them) and gives the gcc linux64 binaries' coupled run bit for bit. Every binary this
machine can run, FMI 2.0 and FMI 3.0, runs a coupled loop (the linear catenary with the
2-mass pantograph and with the rigid and flexible DSA-380) in the C host (fmus/native/host)
built for its own platform, which loads its platform's binaries folder, and gives the linux64
FMI 2.0 numbers bit for bit: aarch64-linux under qemu-user, win64 (the shipped binaries) and
win32 under wine. The macOS binaries (untested on Apple hardware) are checked through their Mach-O load commands: CPU,
libSystem alone, exports, minimum macOS, and the arm64 ad-hoc signature's page hashes."""

import dataclasses
import hashlib
import shutil
import struct
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest

from test_native_fmus import run_host
from tooling import missing, required

pytestmark = pytest.mark.slow

#: zig target: (FMI 2.0 folder, FMI 3.0 folder, extension, file magic, machine); the FMI 2.0
#: folders as docs/tutorials/hil.md chooses them (aarch64 Linux: FMI 2.0.5's platform tuple;
#: both macOS builds: one universal library in darwin64)
TARGETS = {
    "x86_64-linux-gnu": ("linux64", "x86_64-linux", "so", b"\x7fELF", b"\x3e\x00"),
    "aarch64-linux-gnu": ("aarch64-linux", "aarch64-linux", "so", b"\x7fELF", b"\xb7\x00"),
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
    from pantocosim.master.native.host import build_host

    required("gcc", "gcc")
    return build_host(tmp_path)


# ----------------------------------------------- the binaries this machine runs, bit for bit
#: the coupled runs: case -> (scenario, its pantograph's model and FMU)
PAIRS = {"en50318-300": ("en50318-300", "en50318-2mass"),
         "dsa380-ave-300": ("dsa380-ave-300", "dsa380-rigid"),
         "dsa380-flexible": ("dsa380-ave-300", "dsa380-flexible")}
STEPS, DT = 300, 0.001
AARCH64_ROOT = Path("/usr/aarch64-linux-gnu")
HOST_FLAGS = ["-std=c99", "-O3", "-ffp-contract=off", "-Wall", "-Wextra", "-pedantic", "-Werror"]
LIB_FLAGS = [*HOST_FLAGS, "-shared"]
SSE = ["-msse2", "-mfpmath=sse"]          # a 32-bit x86 build: doubles in SSE registers


@pytest.fixture(scope="module")
def coupled_fmus(tmp_path_factory):
    """The FMI 2.0 and 3.0 native catenary and pantograph FMUs of en50318-300 (2-mass
    pantograph) and dsa380-ave-300 (rigid, and flexible, DSA-380) on six spans, with their
    shipped Linux and Windows x86-64 binaries, unpacked: {(case, FMI version): (catenary
    folder, pantograph folder)}."""
    from pantocosim.master.native.models import export_scenario
    from pantocosim.master.run import prepare
    from pantocosim.master.scenario import load_scenario

    required("gcc", "gcc")
    required("x86_64-w64-mingw32-gcc", "gcc-mingw-w64-x86-64")
    out = tmp_path_factory.mktemp("coupled")
    pairs = {}
    for scenario, (name, pantograph) in PAIRS.items():
        sc = load_scenario(name)
        pans = [dataclasses.replace(p, model=pantograph) for p in sc.pantographs]
        prep = prepare(dataclasses.replace(sc, pantographs=pans, catenary_model="linear",
                                           spans=6, window_supports=(1, 3)))
        for fmi in (2, 3):
            folder = out / f"{scenario}-fmi{fmi}"
            written, kept = export_scenario(prep, folder, fmi=fmi, win64=True)
            assert [p.stem for p in written] == ["catenary", pantograph] and kept == []
            for fmu in written:
                with zipfile.ZipFile(fmu) as z:
                    z.extractall(folder / fmu.stem)
            pairs[scenario, fmi] = (folder / "catenary", folder / pantograph)
    return pairs


@pytest.fixture(scope="module")
def linux_rows(coupled_fmus, tmp_path_factory):
    """The linux64 FMI 2.0 coupled run of each pair: {scenario: rows t F z_pantograph
    z_wire}."""
    tmp = tmp_path_factory.mktemp("linux64")
    return {scenario: run_host(host_exe(tmp), ["coupled", *folders, STEPS, DT], tmp)[0]
            for (scenario, fmi), folders in coupled_fmus.items() if fmi == 2}


def zig_build(target):
    def build(sources, out, host=False):
        pytest.importorskip("ziglang")
        cmd = [sys.executable, "-m", "ziglang", "cc", "-target", target]
        if host:
            cmd += [*HOST_FLAGS, "-o", str(out), *map(str, sources), "-ldl", "-lm"]
        else:
            cmd += [*LIB_FLAGS, "-fPIC", "-fvisibility=hidden", f"-I{sources}",
                    *map(str, sorted(sources.glob("*.c"))), "-o", str(out), "-lm"]
        subprocess.run(cmd, check=True, capture_output=True, timeout=600)
    return build


def mingw_build(compiler, package, extra=()):
    def build(sources, out, host=False):
        cc = required(compiler, package)
        if host:
            cmd = [cc, *HOST_FLAGS, *extra, "-o", str(out), *map(str, sources)]
        else:
            cmd = [cc, *LIB_FLAGS, *extra, f"-I{sources}", *map(str, sorted(sources.glob("*.c"))),
                   "-o", str(out), "-static-libgcc"]
        subprocess.run(cmd, check=True, capture_output=True, timeout=600)
    return build


def qemu_aarch64():
    qemu = required("qemu-aarch64", "qemu-user")
    if not (AARCH64_ROOT / "lib" / "ld-linux-aarch64.so.1").exists():
        missing("the aarch64 C library in /usr/aarch64-linux-gnu",
                "apt-get install -y libc6-arm64-cross")
    return (qemu, "-L", str(AARCH64_ROOT))


def wine():
    return (shutil.which("wine") or required("wine", "wine"),)


def windows_path(path) -> str:
    return "Z:" + str(path).replace("/", "\\")


#: platform: (builder, runner, zig target (TARGETS: its FMI 2.0 and 3.0 binaries folders),
#: library suffix, a path as the host sees it, rebuilt from sources/: False for the binaries
#: export-native ships). The host built for a platform loads that platform's folder.
PLATFORMS = {
    "aarch64-linux": (zig_build("aarch64-linux-gnu"), qemu_aarch64, "aarch64-linux-gnu",
                      ".so", str, True),
    "win64": (mingw_build("x86_64-w64-mingw32-gcc", "gcc-mingw-w64-x86-64"), wine,
              "x86_64-windows-gnu", ".dll", windows_path, False),
    "win32": (mingw_build("i686-w64-mingw32-gcc", "gcc-mingw-w64-i686", SSE), wine,
              "x86-windows-gnu", ".dll", windows_path, True),
}
MISSING_32BIT_WINE = ("32-bit wine", "dpkg --add-architecture i386 && apt-get update && "
                      "apt-get install -y wine32")


@pytest.fixture(scope="module", params=sorted(PLATFORMS))
def platform(request, coupled_fmus, tmp_path_factory):
    """A platform's C host and the pairs' libraries in its own binaries folders, built once:
    (name, host, runner, {(case, FMI version): (catenary folder, pantograph folder) as the
    host sees them})."""
    from pantocosim.master.native.host import HOST_NAME, host_sources

    name = request.param
    build, runner, target, suffix, seen, rebuilt = PLATFORMS[name]
    wrapper = runner()
    out = tmp_path_factory.mktemp(name)
    host = out / (HOST_NAME + (".exe" if suffix == ".dll" else ""))
    build(host_sources(), host, host=True)
    probe = subprocess.run([*wrapper, str(host)], capture_output=True, text=True, timeout=300,
                           env={"PATH": "/usr/bin:/bin", "HOME": str(out), "WINEDEBUG": "-all",
                                "WINEPREFIX": str(tmp_path_factory.getbasetemp() /
                                                  "wineprefix")})
    if "usage" not in probe.stderr:
        missing(*MISSING_32BIT_WINE) if name == "win32" else pytest.fail(
            f"the {name} host does not start: {probe.stderr[-2000:]}")
    pairs = {}
    for (scenario, fmi), folders in coupled_fmus.items():
        folder = TARGETS[target][fmi - 2]
        copies = []
        for fmu in folders:
            copy = shutil.copytree(fmu, out / f"{scenario}-fmi{fmi}" / fmu.name)
            identifier = next((copy / "binaries" / TARGETS["x86_64-linux-gnu"][fmi - 2])
                              .glob("*.so")).stem
            if rebuilt:     # this platform's library alone, in its own folder
                shutil.rmtree(copy / "binaries")
                (copy / "binaries" / folder).mkdir(parents=True)
                build(copy / "sources", copy / "binaries" / folder / (identifier + suffix))
            assert (copy / "binaries" / folder / (identifier + suffix)).exists()
            copies.append(seen(copy))
        pairs[scenario, fmi] = tuple(copies)
    return name, host, wrapper, pairs


def assert_linux64_numbers(linux, got, label):
    """The rows of a coupled run equal the linux64 FMI 2.0 rows bit for bit."""
    assert linux.shape == got.shape == (STEPS, 4)
    assert np.all(linux[:, 1] > 0.0) and linux[:, 1].mean() > 50.0    # in contact throughout
    assert got.tobytes() == linux.tobytes(), (
        f"{label}: max |diff| {np.max(np.abs(got - linux), axis=0)}")


@pytest.mark.parametrize("scenario", sorted(PAIRS))
def test_fmi3_coupled_run_gives_the_fmi2_bits_on_linux64(coupled_fmus, linux_rows, scenario,
                                                         tmp_path):
    got, counts = run_host(host_exe(tmp_path), ["coupled", *coupled_fmus[scenario, 3], STEPS,
                                                DT], tmp_path)
    assert_linux64_numbers(linux_rows[scenario], got, f"x86_64-linux FMI 3.0, {scenario}")
    assert counts["allocations in doStep"] == 0


@pytest.mark.parametrize("fmi", [2, 3])
@pytest.mark.parametrize("scenario", sorted(PAIRS))
def test_coupled_run_on_each_platform_gives_the_linux64_bits(platform, linux_rows, scenario,
                                                             fmi, tmp_path):
    name, host, wrapper, pairs = platform
    proc_rows, counts = run_host(host, ["coupled", *pairs[scenario, fmi], STEPS, DT], tmp_path,
                                 wrapper=wrapper)
    assert_linux64_numbers(linux_rows[scenario], proc_rows, f"{name} FMI {fmi}.0, {scenario}")
    if name.startswith("win") and fmi == 3:
        # FMI 3.0 has no memory callbacks and the host interposes malloc on Linux only
        assert "allocations in doStep" not in counts
    else:
        assert counts["allocations in doStep"] == 0


# ------------------------------------------------------- macOS: the Mach-O load commands
#: zig target with its minimum macOS: (CPU type, minimum version)
MACOS = {"aarch64-macos.11.0": (0x0100000C, (11, 0, 0)),
         "x86_64-macos.10.15": (0x01000007, (10, 15, 0))}
LIBSYSTEM = "/usr/lib/libSystem.B.dylib"
LC_SYMTAB, LC_CODE_SIGNATURE, LC_VERSION_MIN_MACOSX, LC_BUILD_VERSION = 0x2, 0x1D, 0x24, 0x32
#: the commands that link a dynamic library: load, weak, reexport, lazy, upward
LC_DYLIBS = {0xC, 0x80000018, 0x8000001F, 0x20, 0x80000023}
CS_ADHOC, CS_SHA256 = 0x2, 2


def macho(data: bytes) -> dict:
    """What a 64-bit Mach-O library says of itself: CPU, file type, linked libraries,
    platform and minimum OS (LC_BUILD_VERSION, else LC_VERSION_MIN_MACOSX), its code
    signature's bytes (LC_CODE_SIGNATURE), defined and undefined external symbols."""
    magic, cpu, _, filetype, ncmds = struct.unpack_from("<5I", data, 0)
    assert magic == 0xFEEDFACF
    info = {"cpu": cpu, "filetype": filetype, "dylibs": [], "platform": None, "minos": None,
            "signature": None, "signature_offset": None, "exports": set(), "imports": set()}
    pos = 32
    for _ in range(ncmds):
        cmd, size = struct.unpack_from("<2I", data, pos)
        if cmd in LC_DYLIBS:
            (name,) = struct.unpack_from("<I", data, pos + 8)
            info["dylibs"].append(data[pos + name:pos + size].split(b"\0")[0].decode())
        elif cmd == LC_BUILD_VERSION:
            info["platform"], minos = struct.unpack_from("<2I", data, pos + 8)
            info["minos"] = (minos >> 16, (minos >> 8) & 0xFF, minos & 0xFF)
        elif cmd == LC_VERSION_MIN_MACOSX:
            (minos,) = struct.unpack_from("<I", data, pos + 8)
            info["platform"], info["minos"] = 1, (minos >> 16, (minos >> 8) & 0xFF, minos & 0xFF)
        elif cmd == LC_CODE_SIGNATURE:
            offset, n = struct.unpack_from("<2I", data, pos + 8)
            info["signature"], info["signature_offset"] = data[offset:offset + n], offset
        elif cmd == LC_SYMTAB:
            symoff, nsyms, stroff, _ = struct.unpack_from("<4I", data, pos + 8)
            for k in range(nsyms):
                strx, ntype, _, desc = struct.unpack_from("<IBBH", data, symoff + 16 * k)
                name = data[stroff + strx:].split(b"\0")[0].decode()
                if ntype & 0xE0 or not ntype & 0x01:
                    continue                          # a debugging or a private symbol
                kind = ntype & 0x0E
                if kind == 0x0E:
                    info["exports"].add(name)         # defined in a section
                elif kind == 0x0:
                    info["imports"].add((name, desc >> 8))  # from the library of this
                    # ordinal (two-level namespace: 1 is the first LC_LOAD_DYLIB)
        pos += size
    return info


def code_directory(signature: bytes) -> bytes:
    """The CodeDirectory blob of a code signature's SuperBlob."""
    magic, _, count = struct.unpack_from(">3I", signature, 0)
    assert magic == 0xFADE0CC0
    for k in range(count):
        slot, offset = struct.unpack_from(">2I", signature, 12 + 8 * k)
        if slot == 0:
            assert struct.unpack_from(">I", signature, offset)[0] == 0xFADE0C02
            return signature[offset:]
    raise AssertionError("no CodeDirectory")


def test_macos_binaries_link_libsystem_only_with_their_minimum_os_and_signature(fmus,
                                                                              tmp_path):
    """Untested on Apple hardware: the libraries' load commands as macOS's loader reads
    them."""
    for fmi in (2, 3):
        sources = fmus["catenary", fmi] / "sources"
        for target, (cpu, minos) in MACOS.items():
            lib = tmp_path / f"{target}-{fmi}.dylib"
            zig_cc(target, sources, lib, ["-fvisibility=hidden"])
            data = lib.read_bytes()
            info = macho(data)
            assert (info["cpu"], info["filetype"]) == (cpu, 6), target    # MH_DYLIB
            assert info["dylibs"] == [LIBSYSTEM], target
            assert (info["platform"], info["minos"]) == (1, minos), target  # PLATFORM_MACOS
            fmi_exports = {s for s in info["exports"] if s.startswith(f"_fmi{fmi}")}
            assert {"_fmi2Instantiate" if fmi == 2 else "_fmi3InstantiateCoSimulation",
                    f"_fmi{fmi}DoStep", f"_fmi{fmi}FreeInstance",
                    f"_fmi{fmi}GetFMUstate" if fmi == 2 else "_fmi3GetFMUState",
                    f"_fmi{fmi}GetVersion"} <= fmi_exports, target
            assert info["exports"] - fmi_exports <= {"__mh_dylib_header", "___dso_handle"}
            names = {name for name, _ in info["imports"]}
            assert {"_fopen", "_fread", "_snprintf"} <= names, target     # the C library
            assert {ordinal for _, ordinal in info["imports"]} == {1}, target  # all libSystem
            if target.startswith("aarch64"):
                # arm64 macOS runs signed code only: an ad-hoc signature whose page hashes
                # are those of the file as written
                cd = code_directory(info["signature"])
                _, _, _, flags, hash_offset, _, n_special, n_code, code_limit = \
                    struct.unpack_from(">9I", cd, 0)
                hash_size, hash_type, _, page_log2 = struct.unpack_from(">4B", cd, 36)
                assert flags & CS_ADHOC and hash_type == CS_SHA256 and hash_size == 32
                assert code_limit == info["signature_offset"]
                page = 1 << page_log2
                assert n_code == -(-code_limit // page) and n_special >= 0
                for k in range(n_code):
                    digest = hashlib.sha256(data[k * page:min((k + 1) * page, code_limit)])
                    slot = cd[hash_offset + 32 * k:hash_offset + 32 * (k + 1)]
                    assert digest.digest() == slot, (target, k)

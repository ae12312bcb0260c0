"""The native FMUs under AddressSanitizer and UndefinedBehaviorSanitizer: the shipped sources
of ``fmus/native/`` (both FMI fronts, every model) linked with the C program
``tests/c_hosts/native_probe.c``. The FMI 2.0 and 3.0 call sequences, on every model of the
table (linear and modal catenary, lumped pantograph, rigid and flexible DSA-380) with its own
value references and inputs, get the standard's statuses (every phase, unknown value
references, NULL arrays, NaN, infinite and huge inputs and steps, terminate then step, reset
and reuse, a failed reset, two instances with their own allocators, truncated, damaged and
foreign FMU states, another, empty or NULL GUID / instantiationToken); and some 300 damaged and crafted data
files (fixed seed) are each refused with a logged reason naming the file, or run; no
sanitizer report, no leak, no block freed through another instance's allocator."""

import dataclasses
import random
import shutil
import struct
import subprocess
import zipfile
from pathlib import Path

import numpy as np
import pytest

from tooling import required

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[1]
PROBE = ROOT / "tests" / "c_hosts" / "native_probe.c"
SANITIZE = ["-O1", "-g", "-fno-omit-frame-pointer", "-fsanitize=address,undefined",
            "-fno-sanitize-recover=all"]
ENV = {"ASAN_OPTIONS": "detect_leaks=1:abort_on_error=0",
       "UBSAN_OPTIONS": "print_stacktrace=1:halt_on_error=1", "PATH": "/usr/bin:/bin"}
SANITIZER_REPORTS = ("AddressSanitizer", "LeakSanitizer", "runtime error:")
#: the probe binary's instantiation token (its model_table.c)
TOKEN = "{0123abcd-0000-1111-2222-333344445555}"


@pytest.fixture(scope="module")
def probe(tmp_path_factory):
    """native_probe linked with every native source, both fronts and every model."""
    from pantocosim.master.native.build import (CFLAGS, SOURCE_DIR, NativeModel,
                                                model_table)

    cc = required("gcc", "gcc")
    out = tmp_path_factory.mktemp("probe")
    table = out / "model_table.c"
    table.write_text(model_table(NativeModel((), (), (
        "pcs_linear_catenary", "pcs_modal_catenary", "pcs_lumped_pantograph",
        "pcs_dsa380_rigid", "pcs_dsa380_flexible")), TOKEN))
    sources = sorted(SOURCE_DIR.glob("*.c"))
    flags = [f for f in CFLAGS if not f.startswith("-O")]
    exe = out / "native_probe"
    subprocess.run([cc, *flags, *SANITIZE, f"-I{SOURCE_DIR}", f"-I{SOURCE_DIR / 'fmi2'}",
                    f"-I{SOURCE_DIR / 'fmi3'}", str(PROBE), *map(str, sources), str(table),
                    "-o", str(exe), "-lm"], check=True)
    return exe


@pytest.fixture(scope="module")
def folders(tmp_path_factory):
    """Unpacked native FMUs of en50318-300 on six spans (the modal model below 20 Hz): linear
    catenary, pantograph, modal catenary; and the rigid and the flexible DSA-380 of
    dsa380-ave-300."""
    from pantocosim.master.native.models import (export_catenary, export_pantograph,
                                                 export_scenario)
    from pantocosim.master.run import prepare
    from pantocosim.master.scenario import load_scenario

    required("gcc", "gcc")
    out = tmp_path_factory.mktemp("fmus")
    scenario = dataclasses.replace(load_scenario("en50318-300"), spans=6,
                                   window_supports=(1, 3), modal_cutoff_hz=20.0)
    written, _ = export_scenario(prepare(dataclasses.replace(scenario, catenary_model="linear")),
                                 out / "linear", win64=False)
    written.append(export_catenary(prepare(dataclasses.replace(scenario, catenary_model="modal")),
                                   out / "modal.fmu", "modal", win64=False))
    names = ["linear", "pantograph", "modal"]
    for model in ("dsa380-rigid", "dsa380-flexible"):
        dsa = load_scenario("dsa380-ave-300")
        pans = [dataclasses.replace(p, model=model) for p in dsa.pantographs]
        prep = prepare(dataclasses.replace(dsa, pantographs=pans, catenary_model="linear"))
        written.append(export_pantograph(prep, 0, out / f"{model}.fmu", win64=False))
        names.append(model)
    result = {}
    for name, fmu in zip(names, written):
        with zipfile.ZipFile(fmu) as z:
            z.extractall(out / name)
        result[name] = out / name
    return result


def run(exe, args, timeout=600):
    proc = subprocess.run([str(exe), *map(str, args)], capture_output=True, text=True, env=ENV,
                          timeout=timeout)
    reports = [r for r in SANITIZER_REPORTS if r in proc.stderr]
    assert not reports, proc.stderr[-4000:]
    return proc


#: probe name of each model of the table: the fixture's folder
WALKED = {"linear": "linear", "modal": "modal", "lumped": "pantograph",
          "dsa380-rigid": "dsa380-rigid", "dsa380-flexible": "dsa380-flexible"}


def test_call_sequences_get_the_standards_statuses(probe, folders, tmp_path):
    """Both walks over every model of the table, each with its own value references and
    inputs; at least as many checks per model and FMI version as the walks hold."""
    percent = tmp_path / "folder%41"                 # a native path, not a URI
    shutil.copytree(folders["linear"], percent)
    proc = run(probe, ["conformance", percent,
                       *(f"{name}={folders[key]}" for name, key in WALKED.items())])
    failed = [line for line in proc.stdout.splitlines() if line.startswith("FAIL")]
    assert failed == [] and proc.returncode == 0, "\n".join(failed) + proc.stderr[-2000:]
    counts = {}
    for line in proc.stdout.splitlines():
        if line.startswith("ok "):
            model, check = line[3:].split(": ", 1)
            version = check.split(" ", 1)[0]
            counts[model, version] = counts.get((model, version), 0) + 1
    for model in WALKED:           # 71 and 369 checks each when written
        assert counts[model, "fmi2"] >= 71 and counts[model, "fmi3"] >= 369, (model, counts)
    assert counts["any", "fmi2"] >= 10


# ---------------------------------------------------------------------- crafted data files
HEADER = 40


def reheader(data: bytes, **fields) -> bytes:
    """data with header fields replaced (version, bom, kind, count, payload) and the checksum
    of its payload recomputed, as a crafted file would have it."""
    from pantocosim.master.native.data_file import fnv1a

    version, bom, kind, count = struct.unpack_from("<4I", data, 8)
    size, _ = struct.unpack_from("<2Q", data, 24)
    v = dict(version=version, bom=bom, kind=kind, count=count, payload=size)
    v.update(fields)
    payload = data[HEADER:]
    return (data[:8] + struct.pack("<4I", v["version"], v["bom"], v["kind"], v["count"])
            + struct.pack("<2Q", v["payload"], fnv1a(payload)) + payload)


def section_offsets(data: bytes) -> list[int]:
    pos, out = HEADER, []
    for _ in range(struct.unpack_from("<I", data, 20)[0]):
        out.append(pos)
        typ, = struct.unpack_from("<I", data, pos + 24)
        n, = struct.unpack_from("<Q", data, pos + 32)
        nbytes = n * (8 if typ == 1 else 4)
        pos += 40 + nbytes + (-nbytes % 8)
    return out


def with_field(data: bytes, offset: int, fmt: str, value) -> bytes:
    raw = bytearray(data)
    struct.pack_into(fmt, raw, offset, value)
    return reheader(bytes(raw))


SIZES = [-2**31, -7, -1, 0, 1, 3, 17, 46341, 65536, 2**20, 2**24 + 1, 2**31 - 1]
VALUES = [float("nan"), float("inf"), -float("inf"), 0.0, -1.0, 1e308, -1e308, 1e-300]


def crafted(good: dict, rng: random.Random):
    """(folder kind, label, bytes) of damaged and crafted data files."""
    from pantocosim.master.native.data_file import pack_data, read_data

    parsed = {k: read_data_bytes(v, read_data) for k, v in good.items()}
    for kind, data in good.items():
        for i in range(20):                                   # random damage
            raw = bytearray(data)
            for _ in range(rng.randint(1, 8)):
                raw[rng.randrange(len(raw))] ^= 1 << rng.randrange(8)
            yield kind, f"damage {i}", bytes(raw)
        for i in range(6):                                    # truncation
            yield kind, f"truncated {i}", data[:rng.randrange(len(data))]
        for name, value in (("version", 2), ("bom", 0x04030201), ("kind", 0), ("kind", 99),
                            ("count", 0), ("count", 2**32 - 1), ("payload", 2**63)):
            yield kind, f"header {name} = {value}", reheader(data, **{name: value})
        offsets = section_offsets(data)
        for i in range(10):                                   # a section's count or type
            pos = rng.choice(offsets)
            count = rng.choice([2**61, 2**63, 2**64 - 1, 2**32, 0,
                                struct.unpack_from("<Q", data, pos + 32)[0] + 1])
            yield kind, f"section count {count}", with_field(data, pos + 32, "<Q", count)
            yield kind, "section type", with_field(data, pos + 24, "<I", rng.choice([0, 3, 1, 2]))
        name, sections = parsed[kind]
        sized = "sizes" if "sizes" in sections else "constants"   # the DSA-380: constants
        for i in range(24):                                   # sizes, consistent checksum
            s = dict(sections, **{sized: sections[sized].copy()})
            s[sized][rng.randrange(s[sized].size)] = rng.choice(SIZES)
            yield kind, f"{sized} {s[sized].tolist()[:12]}", pack_data(name, s)
        floats = [k for k, a in sections.items() if a.dtype == np.float64]
        for i in range(12):                                   # values
            key = rng.choice(floats + ["scalars"] * 4)
            s = dict(sections, **{key: sections[key].copy()})
            s[key][rng.randrange(s[key].size)] = rng.choice(VALUES)
            yield kind, f"{key} value", pack_data(name, s)
        ints = [k for k, a in sections.items() if a.dtype == np.int32
                and k not in ("sizes", "definition", "preset")]
        for key in ints:                                      # indices
            for value in (-2, 2**31 - 1, int(sections[sized][0])):
                s = dict(sections, **{key: sections[key].copy()})
                if s[key].size:
                    s[key][rng.randrange(s[key].size)] = value
                    yield kind, f"{key} = {value}", pack_data(name, s)
        for key in rng.sample(sorted(sections), 4):           # a section missing, retyped
            yield kind, f"no {key}", pack_data(name, {k: a for k, a in sections.items()
                                                      if k != key})
            other = (sections[key].astype(np.int32) if sections[key].dtype == np.float64
                     else sections[key].astype(np.float64))
            yield kind, f"{key} retyped", pack_data(name, dict(sections, **{key: other}))
        text = "definition" if "definition" in sections else "preset"
        yield kind, "text without NUL", pack_data(
            name, dict(sections, **{text: np.full(4, 0x41414141, np.int32)}))


def read_data_bytes(data: bytes, read_data):
    import tempfile

    with tempfile.NamedTemporaryFile(suffix=".pcsdata") as f:
        f.write(data)
        f.flush()
        return read_data(f.name)


def too_large(linear: bytes) -> bytes:
    """A consistent linear catenary file of 10 000 droppers: its dropper columns and Woodbury
    work would take 1.4 GiB (the file itself 2 MB)."""
    from pantocosim.master.native.data_file import pack_data, read_data
    from pantocosim.master.native.headers import fields

    _, s = read_data_bytes(linear, read_data)
    nd = 10_000
    reps = -(-nd // s["drop_ka"].size)
    s = dict(s, sizes=s["sizes"].copy())
    s["sizes"][fields("LIN_SIZE").index("DROPPERS")] = nd
    for key, width in (("drop_idx", 6), ("drop_val", 6), ("drop_ka", 1), ("drop_N0", 1),
                       ("drop_tension", 1)):
        s[key] = np.tile(s[key], reps)[:nd * width]
    return pack_data("linear", s)


def test_damaged_and_crafted_data_files_are_refused_with_a_reason(probe, folders, tmp_path):
    good = {k: (folders[k] / "resources" / "model.pcsdata").read_bytes() for k in folders}
    cases = list(crafted(good, random.Random(46)))
    cases.append(("linear", "1.4 GiB", too_large(good["linear"])))
    assert len(cases) >= 200
    dirs = []
    for i, (kind, label, data) in enumerate(cases):
        folder = tmp_path / f"case{i:03d}"
        shutil.copytree(folders[kind] / "resources", folder / "resources")
        (folder / "resources" / "model.pcsdata").write_bytes(data)
        dirs.append(folder)
    proc = run(probe, ["data", *dirs], timeout=1200)
    assert proc.returncode == 0, proc.stderr[-3000:]     # no leak, no foreign free
    lines = proc.stdout.splitlines()
    assert len(lines) == len(cases)
    outcome = dict(zip((c[1] for c in cases), lines))
    for (kind, label, _), line in zip(cases, lines):
        assert line.startswith(("refused ", "ran ")), (label, line)
        if line.startswith("refused"):
            assert "model.pcsdata" in line, (kind, label, line)
    refused = sum(line.startswith("refused") for line in lines)
    assert refused >= 0.8 * len(cases)
    assert "above the limit" in outcome["1.4 GiB"]
    assert all(outcome[f"header count = {2**32 - 1}"].startswith("refused") for _ in (0,))

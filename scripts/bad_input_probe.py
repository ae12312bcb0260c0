"""A hostile but realistic user: bad scenario, catenary and pantograph files, bad command-line
flags, broken FMU files, unwritable or occupied output places, Ctrl-C, a full disk and huge
models, each run through the ``pantocosim`` command in a child process and classified:

- ``clear``: exit 2 with one error line that names the field and the value (and, for an
  interrupt, exit 130 with one line, the results so far kept and the stop recorded);
- ``unclear``: exit 2 (or 130) but the message misses the field or the value, or has several
  lines, or is misleading (an interrupt reported as an FMU failure);
- ``traceback``: a Python traceback or an unexpected exit code;
- ``silent``: exit 0 where the input must be refused, or a wrong result;
- ``lost``: earlier results in the output folder damaged;
- ``hang``: no answer within the case's limit of CPU time (10 s for an error; on a shared
  machine the wall time may be longer), or 10 s after a SIGINT.

Usage::

    python scripts/bad_input_probe.py [--only SUBSTRING] [--json FILE] [--keep DIR] [-v]

It builds the FMUs once into its work folder (``dist/fmus``) and mounts a small tmpfs for the
full-disk case when it may (root); otherwise that case is skipped. Prints one row per case
and the counts per class.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

ROOT = Path(__file__).resolve().parents[1]
PY = sys.executable
#: an error must come within this much CPU time [s] (a shared machine may take longer in
#: wall time: a case is killed after WALL_FACTOR times its limit)
ERROR_TIMEOUT = 10.0
WALL_FACTOR = 6.0
CLASSES = ("clear", "unclear", "traceback", "silent", "lost", "hang", "skipped")


# ----------------------------------------------------------------------------- TOML
def _toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int,)):
        return str(v)
    if isinstance(v, float):
        if math.isnan(v):
            return "nan"
        if math.isinf(v):
            return "inf" if v > 0 else "-inf"
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, list):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{k} = {_toml_value(x)}" for k, x in v.items()) + " }"
    raise TypeError(type(v))


def dump_toml(d: dict, prefix: str = "") -> str:
    """A small TOML writer (scalars, arrays, tables, arrays of tables)."""
    lines, tables = [], []
    for k, v in d.items():
        if isinstance(v, dict) and k not in ("ramp", "options"):
            tables.append((k, v))
        elif isinstance(v, list) and v and all(isinstance(x, dict) for x in v):
            tables.append((k, v))
        else:
            lines.append(f"{k} = {_toml_value(v)}")
    out = "\n".join(lines) + "\n"
    for k, v in tables:
        name = f"{prefix}{k}"
        if isinstance(v, list):
            for item in v:
                out += f"\n[[{name}]]\n" + dump_toml(item, name + ".")
        else:
            out += f"\n[{name}]\n" + dump_toml(v, name + ".")
    return out


DELETE = object()


def mutate(base: dict, changes: dict) -> dict:
    """A deep copy of ``base`` with dotted-path ``changes`` (list indices as numbers)."""
    d = json.loads(json.dumps(base, allow_nan=True))
    for path, value in changes.items():
        node = d
        parts = path.split(".")
        for p in parts[:-1]:
            key = int(p) if isinstance(node, list) else p
            if isinstance(node, dict) and key not in node:
                node[key] = {}
            node = node[key]
        last = int(parts[-1]) if isinstance(node, list) else parts[-1]
        if value is DELETE:
            del node[last]
        else:
            node[last] = value
    return d


SCENARIO = {
    "name": "probe", "catenary": "en50318", "spans": 4, "speed_kmh": 250.0,
    "pantographs": [{"model": "en50318-2mass", "position_m": 30.0, "start": "static"}],
    "analysis": {"window_m": [35.0, 60.0]},
    "simulation": {"dt": 0.001},
}
#: a coarse catenary (few DOFs) for long lines
COARSE = {"geometry.element_size": 10.0, "droppers.positions": [10.0, 30.0, 50.0]}


def catenary_base() -> dict:
    return tomllib.loads((ROOT / "fmus/catenary/data/en50318.toml").read_text())


def pantograph_base(name: str = "en50318-2mass") -> dict:
    return tomllib.loads((ROOT / f"fmus/pantograph/data/{name}.toml").read_text())


# ----------------------------------------------------------------------------- cases
@dataclass
class Case:
    name: str
    kind: str
    argv: list
    files: dict = field(default_factory=dict)      # name -> str | bytes | callable(dir)
    expect: str = "error"                          # error | interrupt | ok
    names: tuple = ()                              # the error line must contain these
    check: Callable | None = None                  # ok: (dir, proc) -> None | "why wrong"
    timeout: float = ERROR_TIMEOUT
    setup: Callable | None = None                  # (dir) -> None, before the command
    after: Callable | None = None                  # (dir, proc) -> None | "lost: ..."
    sigint_when: Callable | None = None            # (dir, t) -> bool: send SIGINT now
    needs: str = ""                                # "tmpfs": skip without one
    env: dict = field(default_factory=dict)        # environment; "{dir}": the case's folder


def scenario_case(name, changes, names, kind="scenario", argv_extra=(), files_extra=None,
                  **kw):
    text = dump_toml(mutate(SCENARIO, changes))
    return Case(name, kind, ["run", "sc.toml", "--quiet", "--no-plots", "--out", "out",
                             *argv_extra],
                files={"sc.toml": text, **(files_extra or {})}, names=names, **kw)


def catenary_case(name, changes, names, via="static", **kw):
    text = dump_toml(mutate(catenary_base(), changes))
    if via == "static":
        return Case(name, "catenary", ["static", "cat.toml"], files={"cat.toml": text},
                    names=names, **kw)
    sc = dump_toml(mutate(SCENARIO, {"catenary": "cat.toml"}))
    return Case(name, "catenary", ["run", "sc.toml", "--quiet", "--no-plots", "--out", "out"],
                files={"cat.toml": text, "sc.toml": sc}, names=names, **kw)


def pantograph_case(name, changes, names, base="en50318-2mass", via="modal", **kw):
    text = dump_toml(mutate(pantograph_base(base), changes))
    argv = (["modal", "pan.toml"] if via == "modal" else
            ["pantograph", "pan.toml", "--force", "120", "--duration", "0.05", "--out", "pout"])
    return Case(name, "pantograph", argv, files={"pan.toml": text}, names=names, **kw)


def good_run(sub="out", coupling="monolithic", scenario=None):
    """setup: a good earlier run into ``sub`` (its files are kept for the lost-result check)."""
    def setup(d: Path):
        (d / "good.toml").write_text(dump_toml(scenario or SCENARIO))
        proc = _run(["run", "good.toml", "--quiet", "--no-plots", "--out", sub,
                     "--coupling", coupling], d, 120)
        if proc.returncode != 0:
            raise RuntimeError(f"set-up run failed: {proc.stderr[-500:]}")
        snap = {p.relative_to(d / sub).as_posix(): p.read_bytes()
                for p in (d / sub).rglob("*") if p.is_file()}
        (d / ".snapshot.json").write_text(json.dumps({k: v.hex() for k, v in snap.items()}))
    return setup


def unchanged(sub="out"):
    """after: the earlier run's files are byte-identical."""
    def after(d: Path, proc):
        snap = json.loads((d / ".snapshot.json").read_text())
        for rel, hexdata in snap.items():
            p = d / sub / rel
            if not p.exists():
                return f"lost: {sub}/{rel} removed"
            if p.read_bytes() != bytes.fromhex(hexdata):
                return f"lost: {sub}/{rel} changed ({p.stat().st_size} bytes)"
        return None
    return after


def fmu_file(kind: str):
    """Files standing in for an FMU: not a zip, truncated, empty, a folder, no model
    description, a broken model description."""
    def make(d: Path):
        p = d / "bad.fmu"
        real = (d / "dist/fmus/en50318-2mass.fmu").read_bytes()
        if kind == "text":
            p.write_text("this is not an FMU\n")
        elif kind == "truncated":
            p.write_bytes(real[:len(real) // 2])
        elif kind == "empty":
            p.write_bytes(b"")
        elif kind == "folder":
            p.mkdir()
            (p / "modelDescription.xml").write_text("<x/>")
        elif kind in ("nomd", "badxml"):
            import zipfile

            with zipfile.ZipFile(p, "w") as z:
                if kind == "badxml":
                    z.writestr("modelDescription.xml", "<fmiModelDescription <<<")
                z.writestr("resources/x.txt", "x")
        elif kind == "random":
            p.write_bytes(os.urandom(4096))
    return make


def interrupt_check(d: Path, proc):
    """An interrupted run: results so far and a summary that says where the run stopped."""
    s = d / "out" / "summary.json"
    if not s.exists():
        return "results lost: no out/summary.json"
    summary = json.loads(s.read_text())
    if not any(k in summary for k in ("stopped", "interrupted")) and "interrupt" not in \
            json.dumps(summary).lower():
        return "summary does not say where the run stopped"
    rows = (d / "out" / "timeseries.csv").read_text().count("\n") - 1 \
        if (d / "out" / "timeseries.csv").exists() else -1
    if rows < 1:
        return f"no time series rows kept ({rows})"
    return None


def stepping():
    """sigint_when: the run is in its time loop (its time series, in the output folder or in
    a staging folder beside it, holds rows: the first block is written after 500 steps)."""
    def when(d: Path, t: float):
        if t > 120:
            return True
        for p in list(d.glob(".*/timeseries.csv")) + list(d.glob("out/timeseries.csv")):
            try:
                if p.stat().st_size > 2000:
                    return True
            except OSError:   # moved into place meanwhile
                pass
        return False
    return when


def cases(tmpfs: Path | None) -> list[Case]:
    C: list[Case] = []
    S = scenario_case
    # --------------------------------------------------------------- scenario files
    C += [
        Case("scenario binary", "scenario", ["run", "sc.toml", "--quiet", "--out", "out"],
             files={"sc.toml": bytes(range(256)) * 4}, names=("sc.toml",)),
        Case("scenario random bytes", "scenario", ["run", "sc.toml", "--quiet", "--out", "out"],
             files={"sc.toml": b"\xff\xfe\x00name = 1\x81\x82"}, names=("sc.toml",)),
        Case("scenario latin-1", "scenario", ["run", "sc.toml", "--quiet", "--out", "out"],
             files={"sc.toml": 'name = "Zaragoza\xf1"\n'.encode("latin-1")},
             names=("sc.toml",)),
        Case("scenario empty", "scenario", ["run", "sc.toml", "--quiet", "--out", "out"],
             files={"sc.toml": ""}, names=("sc.toml",)),
        Case("scenario syntax", "scenario", ["run", "sc.toml", "--quiet", "--out", "out"],
             files={"sc.toml": "name = \n[[["}, names=("sc.toml",)),
        Case("scenario is a folder", "scenario", ["run", "scdir", "--quiet", "--out", "out"],
             files={"scdir/x": ""}, names=("scdir",)),
        Case("scenario missing", "scenario", ["run", "nope.toml", "--quiet", "--out", "out"],
             names=("nope.toml",)),
        S("speed string", {"speed_kmh": "fast"}, ("speed_kmh", "fast")),
        S("speed negative", {"speed_kmh": -10.0}, ("speed_kmh", "-10")),
        S("speed zero", {"speed_kmh": 0.0}, ("speed_kmh", "0")),
        S("speed nan", {"speed_kmh": float("nan")}, ("speed_kmh", "nan")),
        S("speed inf", {"speed_kmh": float("inf")}, ("speed_kmh", "inf")),
        S("speed bool", {"speed_kmh": True}, ("speed_kmh", "True")),
        S("speed above wave", {"speed_kmh": 900.0}, ("speed_kmh", "900")),
        S("spans 1", {"spans": 1}, ("spans", "1")),
        S("spans 0", {"spans": 0}, ("spans", "0")),
        S("spans -3", {"spans": -3}, ("spans", "-3")),
        S("spans float", {"spans": 2.5}, ("spans", "2.5")),
        S("spans string", {"spans": "ten"}, ("spans", "ten")),
        S("spans 100000", {"spans": 100000}, ("spans", "100000")),
        S("unknown top key", {"speed": 300.0}, ("speed", "300")),
        S("catenary unknown", {"catenary": "nope"}, ("catenary", "nope")),
        S("catenary number", {"catenary": 42}, ("catenary", "42")),
        S("name number", {"name": 5}, ("name", "5")),
        S("pantographs missing", {"pantographs": DELETE}, ("pantographs",)),
        S("pantographs empty", {"pantographs": []}, ("pantographs", "[]")),
        S("pantographs string", {"pantographs": "x"}, ("pantographs", "x")),
        S("model unknown", {"pantographs.0.model": "nope"}, ("model", "nope")),
        S("model number", {"pantographs.0.model": 3}, ("model", "3")),
        S("model missing file", {"pantographs.0.model": "missing.toml"},
          ("model", "missing.toml")),
        S("position string", {"pantographs.0.position_m": "a"}, ("position_m", "a")),
        S("position negative", {"pantographs.0.position_m": -5.0}, ("position_m", "-5")),
        S("position huge", {"pantographs.0.position_m": 1e9}, ("position_m", "1000000000")),
        S("position past window start", {"pantographs.0.position_m": 40.0},
          ("position_m", "40")),
        S("start unknown", {"pantographs.0.start": "flying"}, ("start", "flying")),
        S("ramp with static start", {"pantographs.0.ramp": {"start_m": 31.0, "length_m": 2.0,
                                                            "lowered_height": 5.0}},
          ("ramp",)),
        S("ramp missing", {"pantographs.0.start": "ramp"}, ("ramp",)),
        S("ramp length 0", {"pantographs.0.start": "ramp",
                            "pantographs.0.ramp": {"start_m": 31.0, "length_m": 0.0,
                                                   "lowered_height": 5.0}},
          ("ramp.length_m", "0")),
        S("ramp length negative", {"pantographs.0.start": "ramp",
                                   "pantographs.0.ramp": {"start_m": 31.0, "length_m": -1.0,
                                                          "lowered_height": 5.0}},
          ("length_m", "-1")),
        S("ramp lowered above wire", {"pantographs.0.start": "ramp",
                                      "pantographs.0.ramp": {"start_m": 31.0, "length_m": 2.0,
                                                             "lowered_height": 50.0}},
          ("lowered_height", "50")),
        S("ramp lowered zero", {"pantographs.0.start": "ramp",
                                "pantographs.0.ramp": {"start_m": 31.0, "length_m": 2.0,
                                                       "lowered_height": 0.0}},
          ("lowered_height", "0")),
        S("ramp start behind pantograph", {"pantographs.0.start": "ramp",
                                           "pantographs.0.ramp": {"start_m": 10.0,
                                                                  "length_m": 2.0,
                                                                  "lowered_height": 5.0}},
          ("ramp.start_m", "10")),
        S("ramp ends in window", {"pantographs.0.start": "ramp",
                                  "pantographs.0.ramp": {"start_m": 31.0, "length_m": 20.0,
                                                         "lowered_height": 5.0}},
          ("ramp", "20")),
        S("ramp unknown key", {"pantographs.0.start": "ramp",
                               "pantographs.0.ramp": {"start_m": 31.0, "length_m": 2.0,
                                                      "lowered_height": 5.0, "speed": 1.0}},
          ("speed", "1")),
        S("ramp string", {"pantographs.0.start": "ramp", "pantographs.0.ramp": "fast"},
          ("ramp", "fast")),
        S("two pantographs same position",
          {"pantographs": [SCENARIO["pantographs"][0], SCENARIO["pantographs"][0]]},
          ("position_m", "30")),
        S("two pantographs 1 m apart",
          {"pantographs": [SCENARIO["pantographs"][0],
                           dict(SCENARIO["pantographs"][0], position_m=30.5)]},
          ("position_m", "30.5")),
        S("options string", {"pantographs.0.options": "x"}, ("options", "x")),
        S("options unknown", {"pantographs.0.options": {"foo": 1.0}}, ("foo", "1")),
        S("options static_force negative", {"pantographs.0.options": {"static_force": -5.0}},
          ("static_force", "-5")),
        S("options static_force string", {"pantographs.0.options": {"static_force": "x"}},
          ("static_force", "x")),
        S("options friction nan", {"pantographs.0.options": {"friction_force": float("nan")}},
          ("friction_force", "nan")),
        S("pantograph unknown key", {"pantographs.0.colour": "red"}, ("colour", "red")),
        S("fmu number", {"pantographs.0.fmu": 5}, ("fmu", "5")),
        S("fmu empty string", {"pantographs.0.fmu": ""}, ("fmu", "''"),
          argv_extra=("--coupling", "jacobi")),
        S("catenary binary file", {"catenary": "cat.toml"}, ("cat.toml",),
          files_extra={"cat.toml": bytes(range(200, 256)) * 3}),
        S("spans 400 (size guard)", {"spans": 400}, ("spans", "400")),
        S("analysis missing", {"analysis": DELETE}, ("analysis",)),
        S("window_supports reversed", {"analysis": {"window_supports": [3, 1]}},
          ("window_supports", "3")),
        S("window_supports beyond", {"analysis": {"window_supports": [1, 99]}},
          ("window_supports", "99")),
        S("window_supports float", {"analysis": {"window_supports": [1.5, 3]}},
          ("window_supports", "1.5")),
        S("window_supports bool", {"analysis": {"window_supports": [True, 3]}},
          ("window_supports", "True")),
        S("window_m one", {"analysis": {"window_m": [10.0]}}, ("window_m", "10")),
        S("window_m huge", {"analysis": {"window_m": [35.0, 1e6]}}, ("window_m", "1000000")),
        S("window_m strings", {"analysis": {"window_m": ["a", "b"]}}, ("window_m", "a")),
        S("window_m reversed", {"analysis": {"window_m": [60.0, 35.0]}}, ("window_m", "60")),
        S("window both", {"analysis": {"window_m": [35.0, 60.0], "window_supports": [1, 2]}},
          ("window",)),
        S("analysis unknown", {"analysis.window": [1, 2]}, ("window", "1")),
        S("dt zero", {"simulation.dt": 0.0}, ("dt", "0")),
        S("dt large", {"simulation.dt": 0.5}, ("dt", "0.5")),
        S("dt string", {"simulation.dt": "x"}, ("dt", "x")),
        S("dt tiny", {"simulation.dt": 1e-9}, ("dt", "1e-09")),
        S("alpha positive", {"simulation.alpha": 0.5}, ("alpha", "0.5")),
        S("duration 100", {"simulation.duration_s": 100.0}, ("duration_s", "100")),
        S("duration short", {"simulation.duration_s": 0.01}, ("duration_s", "0.01")),
        S("duration negative", {"simulation.duration_s": -1.0}, ("duration_s", "-1")),
        S("newton_rtol zero", {"simulation.newton_rtol": 0.0}, ("newton_rtol", "0")),
        S("newton_rtol large", {"simulation.newton_rtol": 0.5}, ("newton_rtol", "0.5")),
        S("catenary_model unknown", {"simulation.catenary_model": "quantum"},
          ("catenary_model", "quantum")),
        S("modal cutoff negative", {"simulation.modal_cutoff_hz": -1.0},
          ("modal_cutoff_hz", "-1")),
        S("simulation unknown", {"simulation.steps": 10}, ("steps", "10")),
        S("simulation string", {"simulation": "fast"}, ("simulation", "fast")),
        S("contact stiffness zero", {"contact": {"stiffness": 0.0}}, ("stiffness", "0")),
        S("contact damping negative", {"contact": {"damping": -1.0}}, ("damping", "-1")),
        S("contact unknown", {"contact": {"friction": 0.2}}, ("friction", "0.2")),
        S("five pantographs cosim",
          {"spans": 8, "analysis.window_m": [200.0, 240.0],
           "pantographs": [dict(SCENARIO["pantographs"][0], position_m=20.0 + 30 * k)
                           for k in range(5)]},
          ("pantographs", "5"), argv_extra=("--coupling", "jacobi")),
    ]
    # --------------------------------------------------------------- catenary files
    K = catenary_case
    C += [
        Case("catenary binary", "catenary", ["static", "cat.toml"],
             files={"cat.toml": os.urandom(512)}, names=("cat.toml",)),
        Case("catenary empty", "catenary", ["static", "cat.toml"], files={"cat.toml": ""},
             names=("cat.toml", "spans")),
        Case("catenary unknown preset", "catenary", ["static", "nope"], names=("nope",)),
        Case("catenary folder", "catenary", ["static", "catdir.toml"],
             files={"catdir.toml/x": ""}, names=("catdir.toml",)),
        K("spans missing", {"spans": DELETE}, ("spans",)),
        K("spans.count 0", {"spans.count": 0}, ("spans.count", "0")),
        K("spans.count string", {"spans.count": "x"}, ("spans.count", "x")),
        K("spans.count 100000", {"spans.count": 100000}, ("spans.count", "100000")),
        K("spans.length negative", {"spans.length": -60.0}, ("spans.length", "-60")),
        K("spans.lengths empty", {"spans": {"lengths": []}}, ("spans.lengths", "[]")),
        K("element_size tiny", {"geometry.element_size": 1e-4},
          ("element_size", "0.0001")),
        K("element_size zero", {"geometry.element_size": 0.0}, ("element_size", "0")),
        K("element_size above half span", {"geometry.element_size": 40.0},
          ("element_size", "40")),
        K("stagger 2 m", {"geometry.stagger": [2.0]}, ("stagger", "2")),
        K("stagger empty", {"geometry.stagger": []}, ("stagger", "[]")),
        K("system height small", {"geometry.system_height": 0.05}, ("system_height", "0.05")),
        K("wire height negative", {"geometry.contact_wire_height": -1.0},
          ("contact_wire_height", "-1")),
        K("presag negative", {"geometry.presag": -0.1}, ("presag", "-0.1")),
        K("tension zero", {"contact_wire.tension": 0.0}, ("tension", "0")),
        K("mass string", {"contact_wire.mass_per_length": "x"}, ("mass_per_length", "x")),
        K("EI negative", {"messenger_wire.EI": -1.0}, ("EI", "-1")),
        K("messenger missing", {"messenger_wire": DELETE}, ("messenger_wire",)),
        K("wire unknown key", {"contact_wire.colour": "red"}, ("colour", "red")),
        K("droppers outside span", {"droppers.positions": [5.0, 70.0]}, ("positions", "70")),
        K("droppers decreasing", {"droppers.positions": [30.0, 10.0]}, ("positions", "10")),
        K("droppers one", {"droppers.positions": [30.0]}, ("positions", "30")),
        K("droppers string", {"droppers.positions": "x"}, ("positions", "x")),
        K("droppers EA and k", {"droppers.EA": 1e5}, ("EA",)),
        K("support type unknown", {"contact_support.type": "magic"}, ("type", "magic")),
        K("steady arm length 0", {"contact_support.length": 0.0}, ("length", "0")),
        K("messenger spring negative", {"messenger_support": {"type": "spring",
                                                              "stiffness": -1.0}},
          ("stiffness", "-1")),
        K("damping ratio 1.5", {"damping.ratios": [1.5, 0.01]}, ("ratios", "1.5")),
        K("damping frequency 0", {"damping.frequencies_hz": [0.0, 1.0]},
          ("frequencies_hz", "0")),
        K("gravity negative", {"gravity": -9.81}, ("gravity", "-9.81")),
        K("droppers nan", {"droppers.positions": [5.0, float("nan")]}, ("positions", "nan")),
        K("damping ratios one", {"damping.ratios": [0.01]}, ("ratios", "0.01")),
        K("unknown top key", {"colour": "red"}, ("colour", "red")),
        K("stitch too long", {"stitch_wire": {"mass_per_length": 0.5, "EA": 1e6, "EI": 0.0,
                                              "tension": 3000.0, "length": 100.0}},
          ("stitch_wire.length", "100")),
        K("bad field via scenario", {"contact_wire.tension": -5.0}, ("tension", "-5"),
          via="run"),
        K("element_size tiny via scenario", {"geometry.element_size": 1e-4},
          ("element_size", "0.0001"), via="run"),
    ]
    # --------------------------------------------------------------- pantograph files
    P = pantograph_case
    C += [
        Case("pantograph binary", "pantograph", ["modal", "pan.toml"],
             files={"pan.toml": os.urandom(300)}, names=("pan.toml",)),
        Case("pantograph empty", "pantograph", ["modal", "pan.toml"], files={"pan.toml": ""},
             names=("pan.toml",)),
        Case("pantograph unknown preset", "pantograph", ["modal", "nope"], names=("nope",)),
        P("chain mass negative", {"chain.masses": [-7.2, 15.0]}, ("masses", "-7.2")),
        P("chain mass string", {"chain.masses": ["a", 15.0]}, ("masses", "a")),
        P("chain lengths differ", {"chain.stiffness": [4200.0]}, ("stiffness", "4200")),
        P("chain stiffness zero", {"chain.stiffness": [0.0, 50.0]}, ("stiffness", "0")),
        P("chain uplift_mass 9", {"chain.uplift_mass": 9}, ("uplift_mass", "9")),
        P("chain unknown key", {"chain.colour": "red"}, ("colour", "red")),
        P("options unknown", {"options.foo": 1.0}, ("foo", "1")),
        P("options static negative", {"options.static_force": -1.0}, ("static_force", "-1")),
        P("working height negative", {"chain.working_height": -1.0},
          ("working_height", "-1")),
        P("top unknown key", {"colour": "red"}, ("colour", "red")),
        P("chain missing", {"chain": DELETE}, ("pan.toml",)),
        P("rigid bar mass negative", {"bars.bar1.m": -1.0}, ("bar1", "-1"),
          base="dsa380-rigid"),
        P("rigid damper string", {"damper.c": "x"}, ("damper.c", "x"), base="dsa380-rigid"),
        P("rigid working height unreachable", {"frame.working_height": 50.0},
          ("working_height", "50"), base="dsa380-rigid"),
        P("chain mass nan via pantograph", {"chain.masses": [float("nan"), 15.0]},
          ("masses", "nan"), via="pantograph"),
    ]
    # --------------------------------------------------------------- command-line flags
    def cli(name, argv, names, **kw):
        return Case(name, "cli", argv, names=names, **kw)

    pan = ["pantograph", "en50318-2mass", "--out", "pout"]
    C += [
        cli("unknown command", ["frobnicate"], ("frobnicate",)),
        cli("run coupling unknown", ["run", "en50318-250", "--coupling", "nope"],
            ("--coupling", "nope")),
        cli("run accelerator unknown", ["run", "en50318-250", "--accelerator", "x"],
            ("--accelerator", "x")),
        cli("run cutoff negative", ["run", "en50318-250", "--modal-cutoff-hz", "-1"],
            ("--modal-cutoff-hz", "-1")),
        cli("run cutoff nan", ["run", "en50318-250", "--modal-cutoff-hz", "nan"],
            ("--modal-cutoff-hz", "nan")),
        cli("run cutoff word", ["run", "en50318-250", "--modal-cutoff-hz", "high"],
            ("--modal-cutoff-hz", "high")),
        cli("run scenario unknown", ["run", "nope"], ("scenario", "nope")),
        cli("pantograph dt > duration", pan + ["--force", "120", "--dt", "10",
                                               "--duration", "1"], ("--dt", "10")),
        cli("pantograph dt zero", pan + ["--force", "120", "--dt", "0", "--duration", "1"],
            ("--dt", "0")),
        cli("pantograph dt nan", pan + ["--force", "120", "--dt", "nan", "--duration", "1"],
            ("--dt", "nan")),
        cli("pantograph duration negative", pan + ["--force", "120", "--duration", "-1"],
            ("--duration", "-1")),
        cli("pantograph duration inf", pan + ["--force", "120", "--duration", "inf"],
            ("--duration", "inf")),
        cli("pantograph duration huge", pan + ["--force", "120", "--duration", "1e9"],
            ("--duration", "1000000000")),
        cli("pantograph alpha 0.5", pan + ["--force", "120", "--duration", "0.1",
                                           "--alpha", "0.5"], ("alpha", "0.5")),
        cli("pantograph speed negative", pan + ["--force", "120", "--duration", "0.1",
                                                "--speed", "-100"], ("speed", "-100")),
        cli("pantograph friction negative", pan + ["--force", "120", "--duration", "0.1",
                                                   "--friction", "-1"], ("friction", "-1")),
        cli("force 9**9**9", pan + ["--force", "9**9**9", "--duration", "0.1"],
            ("--force", "9**9**9")),
        cli("force import", pan + ["--force", "__import__('os').system('true')",
                                   "--duration", "0.1"], ("--force", "__import__")),
        cli("force attribute", pan + ["--force", "t.__class__", "--duration", "0.1"],
            ("--force", "t.__class__")),
        cli("force lambda", pan + ["--force", "(lambda: 1)()", "--duration", "0.1"],
            ("--force", "lambda")),
        cli("force string repeat", pan + ["--force", "'a'*10**9", "--duration", "0.1"],
            ("--force", "'a'")),
        cli("force big power", pan + ["--force", "10**400", "--duration", "0.1"],
            ("--force", "10**400")),
        cli("force exp overflow", pan + ["--force", "exp(10000*t)", "--duration", "0.1"],
            ("force", "exp(10000*t)")),
        cli("force empty", pan + ["--force", "", "--duration", "0.1"], ("--force",)),
        cli("force syntax", pan + ["--force", "120 +", "--duration", "0.1"],
            ("--force", "120 +")),
        cli("force list", pan + ["--force", "[1, 2]", "--duration", "0.1"],
            ("--force", "[1, 2]")),
        cli("force division by zero", pan + ["--force", "1/0", "--duration", "0.1"],
            ("force", "1/0")),
        cli("force unknown name", pan + ["--force", "open", "--duration", "0.1"],
            ("--force", "open")),
        cli("force nested parentheses (valid)", pan + ["--force", "(" * 90 + "120" + ")" * 90,
                                                       "--duration", "0.05"], (),
            expect="ok"),
        cli("force too deeply nested", pan + ["--force", "(" * 300 + "1" + ")" * 300,
                                              "--duration", "0.1"], ("--force",)),
        cli("force nan name", pan + ["--force", "nan", "--duration", "0.1"],
            ("--force", "nan")),
        cli("force keyword", pan + ["--force", "where(t > 1, 1, x=2)", "--duration", "0.1"],
            ("--force", "where")),
        cli("run max-dofs zero", ["run", "en50318-250", "--max-dofs", "0"],
            ("--max-dofs", "0")),
        cli("run max-steps word", ["run", "en50318-250", "--max-steps", "many"],
            ("--max-steps", "many")),
        cli("static max-dofs too small", ["static", "en50318", "--max-dofs", "1000"],
            ("spans.count", "10")),
        cli("force long", pan + ["--force", "+".join(["t"] * 20000), "--duration", "0.1"],
            ("--force",)),
        cli("modal force negative", ["modal", "en50318-2mass", "--force", "-1"],
            ("--force", "-1")),
        cli("modal height zero", ["modal", "en50318-2mass", "--height", "0"],
            ("--height", "0")),
        cli("modal height unreachable", ["modal", "dsa380-rigid", "--height", "50"],
            ("height", "50")),
        cli("modal count zero", ["modal", "en50318-2mass", "--count", "0"], ("--count", "0")),
        cli("modes count zero", ["modes", "en50318", "--count", "0"], ("--count", "0")),
        cli("modes count huge", ["modes", "en50318", "--count", "100000"],
            ("--count", "100000")),
        cli("modes element size tiny", ["modes", "en50318", "--element-size", "1e-4"],
            ("--element-size", "0.0001")),
        cli("static element size tiny", ["static", "en50318", "--element-size", "1e-4"],
            ("--element-size", "0.0001")),
        cli("static element size negative", ["static", "en50318", "--element-size", "-1"],
            ("--element-size", "-1")),
        cli("static element size nan", ["static", "en50318", "--element-size", "nan"],
            ("--element-size", "nan")),
        cli("pendulum duration negative", ["pendulum", "--duration", "-1", "--out", "pend"],
            ("--duration", "-1")),
        cli("pendulum step zero", ["pendulum", "--step", "0", "--out", "pend"],
            ("--step", "0")),
        cli("pendulum step > duration", ["pendulum", "--step", "5", "--duration", "1",
                                         "--out", "pend"], ("--step", "5")),
        cli("pendulum alpha 2", ["pendulum", "--alpha", "2", "--duration", "0.01",
                                 "--out", "pend"], ("alpha", "2")),
        cli("pendulum case unknown", ["pendulum", "--cases", "nope", "--out", "pend"],
            ("--cases", "nope")),
        cli("build-fmus only nope", ["build-fmus", "--only", "nope", "--out", "bf"],
            ("--only", "nope")),
        cli("regress only nope", ["regress", "--only", "nope"], ("--only", "nope")),
        cli("regress update without reason", ["regress", "--update"], ("--reason",)),
    ]
    # --------------------------------------------------------------- FMU files
    def fmu_case(name, kind, names, **kw):
        text = dump_toml(mutate(SCENARIO, {"pantographs.0.fmu": "bad.fmu"}))
        return Case(name, "fmu", ["run", "sc.toml", "--quiet", "--no-plots", "--out", "out",
                                  "--coupling", "jacobi"],
                    files={"sc.toml": text, "bad.fmu": fmu_file(kind)}, names=names, **kw)

    C += [
        fmu_case("fmu text file", "text", ("fmu", "bad.fmu")),
        fmu_case("fmu truncated zip", "truncated", ("fmu", "bad.fmu")),
        fmu_case("fmu empty", "empty", ("fmu", "bad.fmu")),
        fmu_case("fmu folder", "folder", ("fmu", "bad.fmu")),
        fmu_case("fmu random bytes", "random", ("fmu", "bad.fmu")),
        fmu_case("fmu zip without model description", "nomd", ("fmu", "bad.fmu")),
        fmu_case("fmu broken model description", "badxml", ("fmu", "bad.fmu")),
        Case("fmu missing", "fmu", ["run", "sc.toml", "--quiet", "--out", "out",
                                    "--coupling", "jacobi"],
             files={"sc.toml": dump_toml(mutate(SCENARIO, {"pantographs.0.fmu": "no.fmu"}))},
             names=("fmu", "no.fmu")),
        Case("fmu of another model", "fmu",
             ["run", "sc.toml", "--quiet", "--no-plots", "--out", "out", "--coupling",
              "jacobi"],
             files={"sc.toml": dump_toml(mutate(SCENARIO, {
                 "pantographs.0.fmu": "dist/fmus/dsa380-rigid.fmu"}))},
             names=("fmu", "dsa380-rigid")),
        Case("fmu is the catenary", "fmu",
             ["run", "sc.toml", "--quiet", "--no-plots", "--out", "out", "--coupling",
              "jacobi"],
             files={"sc.toml": dump_toml(mutate(SCENARIO, {
                 "pantographs.0.fmu": "dist/fmus/catenary.fmu"}))},
             names=("fmu", "catenary.fmu")),
        Case("custom pantograph file, preset FMU", "fmu",
             ["run", "sc.toml", "--quiet", "--no-plots", "--out", "out", "--coupling",
              "jacobi"],
             files={"custom.toml": dump_toml(mutate(pantograph_base(), {
                 "name": "custom", "chain.stiffness": [8000.0, 80.0],
                 "options.static_force": 105.0})),
                 "sc.toml": dump_toml(mutate(SCENARIO, {
                     "pantographs.0.model": "custom.toml",
                     "pantographs.0.fmu": "dist/fmus/en50318-2mass.fmu"}))},
             expect="ok", timeout=90, check=custom_file_check, names=("custom.toml",)),
        Case("cosim 70 spans uplift", "fmu",
             ["run", "sc.toml", "--quiet", "--no-plots", "--out", "out", "--coupling",
              "jacobi"],
             files={"cat.toml": dump_toml(mutate(catenary_base(), COARSE)),
                    "sc.toml": dump_toml(mutate(SCENARIO, {
                        "catenary": "cat.toml", "spans": 70,
                        "pantographs.0.position_m": 3830.0,
                        "analysis.window_m": [3835.0, 3900.0]}))},
             expect="ok", timeout=120, check=uplift_check, names=("spans", "70")),
    ]
    # --------------------------------------------------------------- output places
    def out_case(name, argv, names, files=None, **kw):
        return Case(name, "output", argv, files=files or {}, names=names, **kw)

    short = dump_toml(SCENARIO)
    C += [
        out_case("run --out is a file", ["run", "sc.toml", "--quiet", "--out", "afile"],
                 ("--out", "afile"), files={"sc.toml": short, "afile": "keep me\n"},
                 after=lambda d, p: None if (d / "afile").read_text() == "keep me\n"
                 else "lost: afile changed"),
        out_case("run --out under /proc", ["run", "sc.toml", "--quiet", "--out",
                                           "/proc/pantocosim-probe"],
                 ("--out", "/proc/pantocosim-probe"), files={"sc.toml": short}),
        out_case("run --out under a file", ["run", "sc.toml", "--quiet", "--out",
                                            "afile/sub"], ("--out", "afile/sub"),
                 files={"sc.toml": short, "afile": "x"}),
        out_case("run --out /dev/null", ["run", "sc.toml", "--quiet", "--out", "/dev/null"],
                 ("--out", "/dev/null"), files={"sc.toml": short}),
        out_case("static --plot under /proc", ["static", "en50318", "--plot",
                                               "/proc/x.png"], ("--plot", "/proc/x.png")),
        out_case("static --plot missing folder", ["static", "en50318", "--plot",
                                                  "no/such/dir/x.png"],
                 ("--plot", "no/such/dir/x.png")),
        out_case("static --plot a folder", ["static", "en50318", "--plot", "adir"],
                 ("--plot", "adir"), files={"adir/x": ""}),
        out_case("static --plot bad suffix", ["static", "en50318", "--plot", "x.nope"],
                 ("--plot", "x.nope")),
        out_case("pantograph --out is a file", pan[:2] + ["--force", "120", "--duration",
                                                          "0.05", "--out", "afile"],
                 ("--out", "afile"), files={"afile": "x"}),
        out_case("pantograph --out under /proc", pan[:2] + ["--force", "120", "--duration",
                                                            "0.05", "--out", "/proc/p"],
                 ("--out", "/proc/p")),
        out_case("pendulum --out under /proc", ["pendulum", "--duration", "0.01", "--out",
                                                "/proc/p"], ("--out", "/proc/p")),
        out_case("build-fmus --out under /proc", ["build-fmus", "--only", "catenary",
                                                  "--out", "/proc/p"], ("--out", "/proc/p")),
    ]
    # --------------------------------------------------------------- numerics and files
    def unstable(name, changes, names, coupling="explicit"):
        return S(name, changes, names, kind="stability", argv_extra=("--coupling", coupling))

    negative_aero = dump_toml(mutate(pantograph_base(), {"options.aero_c2": -0.01}))
    C += [
        unstable("explicit 1e7 N/m at 1 ms", {"contact.stiffness": 1e7},
                 ("contact.stiffness", "10000000")),
        unstable("explicit 1e6 N/m at 10 ms", {"contact.stiffness": 1e6, "simulation.dt": 0.01},
                 ("contact.stiffness", "1000000")),
        unstable("explicit 1e7 N/m at 10 ms", {"contact.stiffness": 1e7, "simulation.dt": 0.01},
                 ("contact.stiffness", "10000000")),
        unstable("explicit 5e6 N/m at 5 ms", {"contact.stiffness": 5e6, "simulation.dt": 0.005},
                 ("contact.stiffness", "5000000")),
        unstable("gauss-seidel 1e7 N/m at 10 ms",
                 {"contact.stiffness": 1e7, "simulation.dt": 0.01},
                 ("contact.stiffness", "10000000"), coupling="gauss-seidel"),
        unstable("explicit damping 1e5 N s/m at 10 ms",
                 {"contact.damping": 1e5, "simulation.dt": 0.01},
                 ("contact.damping", "100000")),
        S("catenary file beside the scenario's folder", {"catenary": "../cat.toml"},
          ("catenary", "../cat.toml", "scenario's folder")),
        S("pantograph without uplift at the speed", {"pantographs.0.model": "pan.toml"},
          ("aero_c2", "-0.01", "250 km/h"), files_extra={"pan.toml": negative_aero}),
    ]
    # --------------------------------------------------------------- lost results
    def lost_case(name, changes, names, coupling="jacobi", files=None, **kw):
        text = dump_toml(mutate(SCENARIO, changes))
        return Case(name, "lost", ["run", "bad.toml", "--quiet", "--no-plots", "--out", "out",
                                   "--coupling", coupling],
                    files={"bad.toml": text, **(files or {})}, names=names,
                    setup=good_run(), after=unchanged(), timeout=ERROR_TIMEOUT, **kw)

    C += [
        lost_case("set-up fails: missing FMU", {"pantographs.0.fmu": "no.fmu"},
                  ("fmu", "no.fmu")),
        lost_case("set-up fails: broken FMU", {"pantographs.0.fmu": "bad.fmu"},
                  ("fmu", "bad.fmu"), files={"bad.fmu": fmu_file("truncated")}),
        lost_case("set-up fails: 5 pantographs",
                  {"spans": 8, "analysis.window_m": [200.0, 240.0],
                   "pantographs": [dict(SCENARIO["pantographs"][0], position_m=20.0 + 30 * k)
                                   for k in range(5)]}, ("pantographs", "5")),
        lost_case("set-up fails: monolithic bad window", {"analysis.window_m": [35.0, 1e5]},
                  ("window_m", "100000"), coupling="monolithic"),
    ]
    # --------------------------------------------------------------- interrupts
    long_sc = dump_toml(mutate(SCENARIO, {"spans": 10, "analysis.window_m": [240.0, 360.0]}))
    C += [
        Case("Ctrl-C monolithic", "interrupt",
             ["run", "sc.toml", "--no-plots", "--quiet", "--out", "out"],
             files={"sc.toml": long_sc}, expect="interrupt", sigint_when=stepping(),
             check=interrupt_check, timeout=120),
        Case("Ctrl-C jacobi", "interrupt",
             ["run", "sc.toml", "--no-plots", "--quiet", "--out", "out", "--coupling",
              "jacobi"],
             files={"sc.toml": long_sc}, expect="interrupt", sigint_when=stepping(),
             check=interrupt_check, timeout=120),
        Case("Ctrl-C implicit", "interrupt",
             ["run", "sc.toml", "--no-plots", "--quiet", "--out", "out", "--coupling",
              "implicit"],
             files={"sc.toml": long_sc}, expect="interrupt", sigint_when=stepping(),
             check=interrupt_check, timeout=120),
        Case("Ctrl-C during set-up keeps earlier results", "interrupt",
             ["run", "sc.toml", "--no-plots", "--quiet", "--out", "out"],
             files={"sc.toml": long_sc}, expect="interrupt", setup=good_run(),
             sigint_when=lambda d, t: t > 2.0, after=unchanged(), timeout=60),
        Case("Ctrl-C static", "interrupt", ["static", "en50318", "--element-size", "0.3"],
             expect="interrupt", sigint_when=lambda d, t: t > 3.0, timeout=60),
        Case("Ctrl-C pantograph", "interrupt",
             ["pantograph", "dsa380-rigid", "--out", "pout", "--force",
              "120 + 30*sin(4*pi*t)", "--duration", "500"],
             expect="interrupt", sigint_when=lambda d, t: t > 3.0, timeout=60),
    ]
    # --------------------------------------------------------------- caches
    def cache_case(name, env, files=None, setup=None, expect="ok", names=()):
        argv = ["run", "sc.toml", "--quiet", "--no-plots", "--out", "out"]
        return Case(name, "cache", argv, files={"sc.toml": dump_toml(SCENARIO),
                                                **(files or {})},
                    env={"MPLCONFIGDIR": "{dir}/mpl", **env}, expect=expect, names=names,
                    setup=setup, check=None if expect != "ok" else cache_warned,
                    timeout=120 if expect == "ok" else ERROR_TIMEOUT)

    xdg = {"XDG_CACHE_HOME": "{dir}/xdg", "PANTOCOSIM_CACHE_DIR": "", "NUMBA_CACHE_DIR": ""}
    C += [
        cache_case("cache size not a number", {"PANTOCOSIM_CACHE_MB": "lots"},
                   expect="error", names=("PANTOCOSIM_CACHE_MB", "lots")),
        cache_case("cache size negative", {"PANTOCOSIM_CACHE_MB": "-3"},
                   expect="error", names=("PANTOCOSIM_CACHE_MB", "-3")),
        cache_case("cache root is a file", xdg, files={"xdg/pantocosim": "a file"}),
        cache_case("set-up cache is a file", dict(xdg, PANTOCOSIM_CACHE_DIR="{dir}/setup"),
                   files={"setup": "a file"}),
        cache_case("numba cache is a file", xdg, files={"xdg/pantocosim/numba": "a file"}),
        cache_case("numba cache damaged", xdg, setup=damaged_caches),
    ]
    if tmpfs is not None:                # root: mounts are possible
        C += [cache_case("cache full", xdg, setup=full_cache),
              cache_case("cache read-only", xdg, setup=read_only_cache)]
        C[-2].after = C[-1].after = unmount_cache
    # --------------------------------------------------------------- full disk
    if tmpfs is not None:
        # the second run writes more than the first (a longer window)
        longer = dump_toml(mutate(SCENARIO, {"analysis.window_m": [35.0, 150.0]}))
        C.append(Case("full disk", "disk",
                      ["run", "sc.toml", "--no-plots", "--quiet", "--out", str(tmpfs / "out")],
                      files={"sc.toml": longer}, names=("space",),
                      setup=disk_setup(tmpfs), after=disk_after(tmpfs), timeout=60,
                      needs="tmpfs"))
    else:
        C.append(Case("full disk", "disk", [], needs="tmpfs"))
    return C


def cache_warned(d: Path, proc):
    """A run beside an unusable cache: results written, each stderr line a one-line cache
    warning naming a path of the case's folder, at most one per cache."""
    if not (d / "out" / "summary.json").exists():
        return "no results"
    lines = error_lines(proc.stderr)
    if not lines:
        return "no warning"
    bad = [l for l in lines if not l.startswith(f"pantocosim: warning: cache {d}")]
    if bad:
        return f"not a cache warning: {bad[0][:120]}"
    if len({l.split()[3] for l in lines}) != len(lines):
        return f"{len(lines)} warnings for {len({l.split()[3] for l in lines})} caches"
    return None


def damaged_caches(d: Path) -> None:
    """Fill the case's caches with a run, then truncate every numba entry and set-up entry."""
    env = dict(os.environ, XDG_CACHE_HOME=str(d / "xdg"), MPLCONFIGDIR=str(d / "mpl"),
               PANTOCOSIM_CACHE_DIR="", NUMBA_CACHE_DIR="")
    subprocess.run([PY, "-m", "pantocosim.master.cli", "run", "sc.toml", "--quiet",
                    "--no-plots", "--out", "first"], cwd=d, env=env, capture_output=True,
                   timeout=600)
    for p in list((d / "xdg").rglob("*.nb[ic]")) + list((d / "xdg").rglob("*.npz")):
        p.write_bytes(p.read_bytes()[: p.stat().st_size // 3])


def full_cache(d: Path) -> None:
    """The case's cache root on a 64 kB file system (full at once)."""
    (d / "xdg").mkdir()
    subprocess.run(["mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", str(d / "xdg")],
                   check=True)


def read_only_cache(d: Path) -> None:
    """The case's cache root filled by a run, then mounted read-only."""
    damaged_caches(d)                                   # fills it (and damages it)
    shutil.rmtree(d / "xdg" / "pantocosim" / "setup")   # a set-up entry it lacks
    subprocess.run(["mount", "--bind", str(d / "xdg"), str(d / "xdg")], check=True)
    subprocess.run(["mount", "-o", "remount,bind,ro", str(d / "xdg")], check=True)


def unmount_cache(d: Path, proc):
    subprocess.run(["umount", str(d / "xdg")], capture_output=True)
    return None


def custom_file_check(d: Path, proc):
    """The co-simulation of a custom parameter file agrees with the monolithic run."""
    cos = json.loads((d / "out/summary.json").read_text())["pantographs"][0]["statistics"]
    mono = _run(["run", "sc.toml", "--quiet", "--no-plots", "--json", "--out", "mono"], d, 60)
    if mono.returncode != 0:
        return f"monolithic run failed: {mono.stderr.strip()[-200:]}"
    ref = json.loads((d / "mono/summary.json").read_text())["pantographs"][0]["statistics"]
    for key in ("mean_n", "std_n"):
        if abs(cos[key] - ref[key]) > 0.02 * abs(ref[key]):
            return f"{key}: co-simulation {cos[key]:.2f} N, monolithic {ref[key]:.2f} N"
    return None


def uplift_check(d: Path, proc):
    s = json.loads((d / "out/summary.json").read_text())
    up = s["pantographs"][0]["statistics"]["max_uplift_at_support_m"]
    if not up or not up > 1e-4:
        return f"max uplift at support {up} m in a window past support 63"
    return None


def disk_setup(mount: Path):
    def setup(d: Path):
        subprocess.run(["umount", str(mount)], capture_output=True)
        mount.mkdir(parents=True, exist_ok=True)
        r = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=160k", "tmpfs", str(mount)],
                           capture_output=True, text=True)
        if r.returncode:
            raise RuntimeError(f"mount failed: {r.stderr}")
        (d / "good.toml").write_text(dump_toml(SCENARIO))
        proc = _run(["run", "good.toml", "--quiet", "--no-plots", "--out",
                     str(mount / "out")], d, 60)
        if proc.returncode:
            raise RuntimeError(f"set-up run failed: {proc.stderr[-400:]}")
        snap = {p.name: p.read_bytes().hex() for p in (mount / "out").iterdir()}
        (d / ".snapshot.json").write_text(json.dumps(snap))
        # fill the disk but for a few kB: the second run cannot complete its time series
        free = shutil.disk_usage(mount).free
        (mount / "filler").write_bytes(b"\0" * max(0, free - 20_000))
    return setup


def disk_after(mount: Path):
    def after(d: Path, proc):
        try:
            snap = json.loads((d / ".snapshot.json").read_text())
            for name, hexdata in snap.items():
                p = mount / "out" / name
                if not p.exists() or p.read_bytes() != bytes.fromhex(hexdata):
                    return f"lost: {name} damaged by the full disk"
            return None
        finally:
            subprocess.run(["umount", str(mount)], capture_output=True)
    return after


# ----------------------------------------------------------------------------- running
def _run(argv, cwd: Path, timeout: float):
    return subprocess.run([PY, "-m", "pantocosim.master.cli", *argv], cwd=cwd,
                          capture_output=True, text=True, timeout=timeout,
                          stdin=subprocess.DEVNULL)


def cpu_seconds(pid: int, last: float) -> float:
    """CPU time (user + system) of a running process [s] (Linux /proc; else ``last``)."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            fields = f.read().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    except (OSError, IndexError, ValueError):
        return last


def error_lines(stderr: str) -> list[str]:
    """The lines of stderr that are not progress notes."""
    return [l for l in stderr.splitlines()
            if l.strip() and not l.startswith("building FMUs") and not l.startswith("note:")]


def run_case(case: Case, work: Path, verbose: bool = False) -> dict:
    d = work / "".join(c if c.isalnum() else "_" for c in case.name)
    if d.exists():
        shutil.rmtree(d)
    d.mkdir(parents=True)
    (d / "dist").symlink_to(work / "dist")
    row = {"case": case.name, "kind": case.kind, "argv": case.argv}
    if case.needs == "tmpfs" and not case.argv:
        row.update(cls="skipped", detail="no tmpfs (not root)")
        return row
    for name, content in case.files.items():
        p = d / name
        p.parent.mkdir(parents=True, exist_ok=True)
        if callable(content):
            content(d)
        elif isinstance(content, bytes):
            p.write_bytes(content)
        else:
            p.write_text(content)
    if case.setup:
        case.setup(d)
    t0 = time.perf_counter()
    # output to files (a pipe could fill up while we poll); SIGINT as in a terminal (a
    # background shell job would start us with it ignored)
    fo, fe = open(d / ".stdout", "w+"), open(d / ".stderr", "w+")
    env = dict(os.environ, **{k: v.format(dir=d) for k, v in case.env.items()})
    proc = subprocess.Popen([PY, "-m", "pantocosim.master.cli", *case.argv], cwd=d, env=env,
                            stdout=fo, stderr=fe, text=True, stdin=subprocess.DEVNULL,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    sent, why, cpu = None, None, 0.0
    while proc.poll() is None:
        t = time.perf_counter() - t0
        cpu = cpu_seconds(proc.pid, cpu)
        if case.sigint_when is not None and sent is None and case.sigint_when(d, t):
            proc.send_signal(signal.SIGINT)
            sent = t
        if sent is not None and t - sent > ERROR_TIMEOUT:
            why = f"no answer {ERROR_TIMEOUT:g} s after SIGINT"
        elif sent is None and cpu > case.timeout:
            why = f"{cpu:.0f} s of CPU time without an answer (limit {case.timeout:g} s)"
        elif t > WALL_FACTOR * case.timeout:
            why = f"no answer after {t:.0f} s"
        if why:
            proc.kill()
            proc.wait()
            break
        time.sleep(0.05)
    fo.seek(0)
    fe.seek(0)
    out, err = fo.read(), fe.read()
    fo.close()
    fe.close()
    if why:
        row.update(cls="hang", seconds=round(time.perf_counter() - t0, 1),
                   cpu=round(cpu, 1), detail=why)
        if case.after:
            case.after(d, None)
        return row
    proc.stdout, proc.stderr = out, err
    row["cpu"] = round(cpu, 1)
    elapsed = time.perf_counter() - t0
    proc.stdout, proc.stderr = out, err
    row["seconds"] = round(elapsed, 1)
    row["exit"] = proc.returncode
    lines = error_lines(err)
    row["message"] = lines[-1] if lines else ""
    row["cls"], row["detail"] = classify(case, proc, lines, d)
    if case.after:
        why = case.after(d, proc)
        if why and row["cls"] in ("clear", "unclear"):
            row["cls"], row["detail"] = "lost", why
    if verbose:
        print(err[-3000:], file=sys.stderr)
    return row


def classify(case: Case, proc, lines: list[str], d: Path) -> tuple[str, str]:
    err = proc.stderr
    code = proc.returncode
    if "Traceback (most recent call last)" in err:
        return "traceback", next((l for l in reversed(lines) if l.strip()), "")[:200]
    if case.expect == "interrupt":
        if code != 130:
            return ("traceback" if code not in (0, 2) else "unclear",
                    f"exit {code} after SIGINT")
        if len(lines) != 1:
            return "unclear", f"{len(lines)} lines after SIGINT"
        if "FATAL" in lines[0] or "doStep" in lines[0]:
            return "unclear", "interrupt reported as an FMU failure"
        if case.check:
            why = case.check(d, proc)
            if why:
                return "lost", why
        return "clear", ""
    if code == 0:
        if case.expect == "ok":
            why = case.check(d, proc) if case.check else None
            return ("silent", why) if why else ("clear", "handled (exit 0, result checked)")
        return "silent", "exit 0 for bad input"
    if code == 2:
        if len(lines) != 1:
            return "unclear", f"{len(lines)} error lines"
        missing = [n for n in case.names if n.lower() not in lines[0].lower()]
        if missing:
            return "unclear", f"message misses {missing}"
        return "clear", ""
    if code in (-signal.SIGKILL, 137):
        return "traceback", "killed (memory?)"
    return "traceback", f"exit {code}"


def mount_tmpfs(work: Path) -> Path | None:
    if os.geteuid() != 0 or not shutil.which("mount"):
        return None
    m = work / "tmpfs"
    m.mkdir(exist_ok=True)
    r = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=160k", "tmpfs", str(m)],
                       capture_output=True)
    if r.returncode:
        return None
    subprocess.run(["umount", str(m)], capture_output=True)
    return m


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", action="append", help="run cases whose name contains this")
    ap.add_argument("--kind", action="append", help="run cases of this kind")
    ap.add_argument("--json", type=Path, help="write the rows as JSON")
    ap.add_argument("--keep", type=Path, help="work folder (kept); default a temporary one")
    ap.add_argument("--list", action="store_true", help="list the cases")
    ap.add_argument("-v", "--verbose", action="store_true")
    args = ap.parse_args(argv)
    work = (args.keep or Path(tempfile.mkdtemp(prefix="pantocosim_probe_"))).resolve()
    work.mkdir(parents=True, exist_ok=True)
    tmpfs = mount_tmpfs(work)
    todo = cases(tmpfs)
    if args.only:
        todo = [c for c in todo if any(s.lower() in c.name.lower() for s in args.only)]
    if args.kind:
        todo = [c for c in todo if c.kind in args.kind]
    if args.list:
        for c in todo:
            print(f"{c.kind:<11} {c.name}")
        return 0
    if not (work / "dist/fmus/catenary.fmu").exists():
        r = _run(["build-fmus", "--no-ssp"], work, 600)
        if r.returncode:
            print(r.stderr, file=sys.stderr)
            return 1
    rows = []
    for case in todo:
        row = run_case(case, work, args.verbose)
        rows.append(row)
        print(f"{row['cls']:<9} {row.get('exit', '-')!s:>4} {row.get('seconds', 0):>5}s "
              f"{row.get('cpu', 0):>5}cpu "
              f"{case.kind:<10} {case.name:<42} {row.get('detail') or row.get('message', '')}"
              [:230], flush=True)
    counts = {c: sum(r["cls"] == c for r in rows) for c in CLASSES}
    n = len(rows) - counts["skipped"]
    print(f"\n{n} cases: " + ", ".join(f"{k} {v}" for k, v in counts.items()))
    errors = [r for r in rows if r.get("exit") == 2]
    if errors:
        named = sum(r["cls"] in ("clear", "lost") for r in errors)
        print(f"exit-2 messages naming field and value: {named}/{len(errors)}")
    if args.json:
        args.json.write_text(json.dumps({"counts": counts, "rows": rows}, indent=1) + "\n")
    if not args.keep:
        shutil.rmtree(work, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())

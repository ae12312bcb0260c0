"""Shared helpers of the third-party recipes (``python -m pantocosim.master.thirdparty.X``
for X in libcosim, ecos, fmpy_ssp, cofmupy_json, fmpy_single; docs/third-party.md).

Not a recipe itself. Every recipe runs the foreign master in a child process (``--child``):
pythonfmu may abort at process exit (docs/third-party.md, "Process exit"), so the child
imports scipy.sparse.linalg before any FMU, writes the time series as CSV, prints its wall
time and ends with ``os._exit``. The parent reads the CSV and prints the EN 50317 statistics
computed with ``pantocosim.master.results.statistics.contact_statistics``.
"""

from __future__ import annotations

import argparse
import csv
import json
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from pantocosim.catenary.analysis import central_window
from pantocosim.core.errors import ParameterError
from pantocosim.fmi.catenary_ports import MAX_SUPPORTS
from pantocosim.master.fmu.binary_check import check_binary_fmu
from pantocosim.master.fmu.check import read_fmu
from pantocosim.master.ssp import scenario_support_x
from pantocosim.master.results.statistics import contact_statistics

DEFAULT_SSP = Path("dist") / "fmus" / "dsa380-ave-300.ssp"
NS = {"ssd": "http://ssp-standard.org/SSP1/SystemStructureDescription",
      "ssv": "http://ssp-standard.org/SSP1/SystemStructureParameterValues"}


# ------------------------------------------------------------------------- SSP
def read_ssd(ssp: str | Path) -> dict:
    """Per component: its values (the FMU's start values, overlaid by the SSD's parameter
    values); the connections and the default stop time of an SSP file."""
    from fmpy import read_model_description

    with zipfile.ZipFile(ssp) as z:
        root = ET.fromstring(z.read("SystemStructure.ssd"))
        params: dict = {}
        for comp in root.iter(f"{{{NS['ssd']}}}Component"):
            with z.open(comp.get("source")) as f:
                md = read_model_description(f)
            p = params.setdefault(comp.get("name"), {})
            for v in md.modelVariables:
                if v.start is not None:
                    p[v.name] = _typed(v.type, v.start)
            for par in comp.iter(f"{{{NS['ssv']}}}Parameter"):
                (val,) = list(par)
                p[par.get("name")] = _typed(val.tag.split("}")[1], val.get("value"))
    sets = sorted({ps.get("name") for ps in root.iter(f"{{{NS['ssv']}}}ParameterSet")})
    exp = root.find("ssd:DefaultExperiment", NS)
    stop = float(exp.get("stopTime")) if exp is not None and exp.get("stopTime") else None
    return {"parameters": params, "stop_time": stop, "parameter_sets": sets}


def refuse(module: str, exc: Exception):
    """Stop a recipe on bad input: one line, exit status 2."""
    print(f"{module}: error: {' '.join(str(exc).split())}", file=sys.stderr)
    raise SystemExit(2)


def check_fmu(module: str, fmu: str | Path, field: str) -> None:
    """Refuse (:func:`refuse`) an FMU file that cannot run here or is not what its model
    description says (:func:`pantocosim.master.fmu.binary_check.check_binary_fmu`)."""
    try:
        read_fmu(Path(fmu), field, None)
        check_binary_fmu(Path(fmu), field)
    except ParameterError as exc:
        refuse(module, exc)


def check_ssp_fmus(module: str, ssp: str | Path) -> None:
    """:func:`check_fmu` on every FMU of the SSP file ``ssp``."""
    try:
        with zipfile.ZipFile(ssp) as z:
            root = ET.fromstring(z.read("SystemStructure.ssd"))
            with tempfile.TemporaryDirectory(prefix="pantocosim_ssp_check_") as tmp:
                for comp in root.iter(f"{{{NS['ssd']}}}Component"):
                    fmu = Path(tmp) / Path(comp.get("source")).name
                    fmu.write_bytes(z.read(comp.get("source")))
                    try:
                        read_fmu(fmu, f"component {comp.get('name')!r}", str(ssp))
                        check_binary_fmu(fmu, f"component {comp.get('name')!r}", str(ssp))
                    except ParameterError as exc:
                        refuse(module, str(exc).replace(str(fmu), comp.get("source")))
    except (OSError, KeyError, zipfile.BadZipFile, ET.ParseError) as exc:
        refuse(module, f"--ssp = '{ssp}': not a readable SSP file ({exc})")


def _typed(kind: str, text: str):
    if kind == "Real":
        return float(text)
    if kind == "Integer":
        return int(text)
    if kind == "Boolean":
        return text in ("true", "1", True)
    return text


def catenary_layout(cat_params: dict) -> np.ndarray:
    """Support positions of the catenary the SSP's catenary FMU builds."""
    return scenario_support_x(cat_params)


def swap_pantograph(ssp: str | Path, fmu: str | Path, dest: str | Path) -> Path:
    """A copy of ``ssp`` whose pantograph FMU file is replaced by ``fmu`` (same entry name,
    nothing else edited): the swap a user makes by hand."""
    with zipfile.ZipFile(ssp) as z:
        root = ET.fromstring(z.read("SystemStructure.ssd"))
        (comp,) = [c for c in root.iter(f"{{{NS['ssd']}}}Component")
                   if c.get("name") == "pantograph"]
        with zipfile.ZipFile(dest, "w", zipfile.ZIP_DEFLATED) as out:
            for item in z.infolist():
                if item.filename == comp.get("source"):
                    out.write(fmu, item.filename)
                else:
                    out.writestr(item, z.read(item.filename))
    return Path(dest)


def columns(n_supports: int) -> list[str]:
    return (["time", "x_1", "contact_force_1", "contact_height_1", "wire_height_1"]
            + [f"support_uplift_{j}" for j in range(n_supports)])


# ------------------------------------------------------------------------- child side
def write_csv(path: str | Path, names: list[str], rows) -> None:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(names)
        for r in rows:
            w.writerow([repr(float(x)) for x in r])


def read_csv(path: str | Path) -> dict:
    with open(path) as f:
        rows = list(csv.reader(f))
    data = np.array(rows[1:], dtype=float).reshape(len(rows) - 1, len(rows[0]))
    return {h: data[:, i] for i, h in enumerate(rows[0])}


# ------------------------------------------------------------------------- parent side
def failed(module: str, proc: subprocess.CompletedProcess):
    """Stop a recipe whose co-simulation child failed with one line: the first refusal an FMU
    logged (its first sentence), else the child's last error line; the child's whole output
    is kept in a log file the line names."""
    text = proc.stdout + proc.stderr
    said = [line for line in text.splitlines()
            if line.startswith(("[DISCARD]", "[ERROR]", "[FATAL]"))]
    errors = [line.strip() for line in proc.stderr.splitlines()
              if line.strip() and not line.startswith((" ", "Traceback", "During handling"))]
    if said:
        reason = f": {REFUSED} {said[0].split('. ')[0]}"
    else:
        reason = f": {errors[-1]}" if errors else ""
    with tempfile.NamedTemporaryFile("w", prefix=f"{module.rsplit('.', 1)[-1]}-",
                                     suffix=".log", delete=False) as log:
        log.write(text)
    raise SystemExit(f"{module}: the co-simulation failed (exit code {proc.returncode})"
                     f"{reason} (its output: {log.name})")


#: what precedes an FMU's refusal in the line of :func:`failed`
REFUSED = "the FMU said"


def run_child(module: str, args: list) -> tuple:
    """Run ``python -m MODULE --child ARGS``; returns its wall time (printed as ``WALL <s>``),
    the part of it spent in initialisation (``INIT <s>``: model set-up and numba JIT) and the
    process CPU time of the run (``CPU <s>``), the last two None when not printed."""
    cmd = [sys.executable, "-m", module, "--child", *map(str, args)]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    wall = [l for l in proc.stdout.splitlines() if l.startswith("WALL ")]
    if proc.returncode != 0 or not wall:
        failed(module, proc)
    init = None
    cpu = None
    for line in proc.stdout.splitlines():
        if line.startswith("CPU "):
            cpu = float(line.split()[1])
        if line.startswith("NOTE "):
            print(line[5:])
        if line.startswith("INIT "):
            init = float(line.split()[1])
    return float(wall[-1].split()[1]), init, cpu


# ------------------------------------------------------------------------- recipes
def parser(doc: str, out_default: str) -> argparse.ArgumentParser:
    """A recipe's argument parser: its ``--out`` and the hidden child-process arguments."""
    p = argparse.ArgumentParser(description=doc.splitlines()[0])
    p.add_argument("--out", type=Path, help=f"time series CSV (default: {out_default})")
    p.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    p.add_argument("child_args", nargs="*", help=argparse.SUPPRESS)
    return p


def ssp_parser(doc: str, tool: str) -> argparse.ArgumentParser:
    """:func:`parser` with the arguments of the recipes that run an SSP."""
    p = parser(doc, f"results/<ssp>-{tool}.csv")
    p.add_argument("--ssp", type=Path, default=DEFAULT_SSP)
    p.add_argument("--step", type=float, default=1e-3, help="communication step [s]")
    p.add_argument("--stop", type=float, help="stop time [s] (default: the SSP's)")
    p.add_argument("--window", type=float, nargs=2, metavar=("START", "END"),
                   help="analysis window [m] (default: supports 5..6)")
    return p


def ssp_run(a: argparse.Namespace, tool: str) -> SimpleNamespace:
    """What a recipe needs of the SSP named by its arguments: ``ssd`` (:func:`read_ssd`),
    ``cat`` (the catenary component's parameters), ``support_x``, ``stop``, ``window``,
    ``out``, ``n_sup`` (support uplift columns written, at most the FMU's MAX_SUPPORTS) and ``tool``."""
    check_ssp_fmus(f"{tool} recipe", a.ssp)
    ssd = read_ssd(a.ssp)
    cat = ssd["parameters"]["catenary"]
    support_x = catenary_layout(cat)
    return SimpleNamespace(
        tool=tool, ssd=ssd, cat=cat, support_x=support_x,
        stop=a.stop if a.stop is not None else ssd["stop_time"],
        window=a.window or ssp_window(cat, support_x),
        out=a.out or Path("results") / f"{a.ssp.stem}-{tool}.csv",
        n_sup=min(len(support_x), MAX_SUPPORTS))


def run_ssp_child(module: str, a: argparse.Namespace, r: SimpleNamespace,
                  *extra) -> None:
    """Run an SSP recipe's child (arguments: SSP, step, stop, CSV, supports, x0, V, extra)
    and report its statistics."""
    wall = run_child(module, ["--", a.ssp.resolve(), a.step, r.stop, r.out, r.n_sup,
                              r.cat["position_1"], r.cat["speed_kmh"] / 3.6, *extra])
    report(r.tool, r.out, r.window, r.support_x, wall, {"ssp": str(a.ssp), "step_s": a.step})


def ssp_window(cat: dict, support_x: np.ndarray) -> tuple[float, float]:
    """The analysis window of the catenary FMU's parameters (window_start, window_end), else
    the middle span of the line (the FMU's own default)."""
    if cat.get("window_end", 0.0) > cat.get("window_start", 0.0):
        return float(cat["window_start"]), float(cat["window_end"])

    return central_window(support_x)


def report(master: str, csv_path: Path, window, support_x, wall, extra=None) -> dict:
    """EN 50317 statistics of the run in ``csv_path``; prints a table and a JSON line
    ``STATISTICS {...}`` and writes ``<csv>.json``."""
    c = read_csv(csv_path)
    n_sup = sum(1 for k in c if k.startswith("support_uplift_"))
    uplift = (np.column_stack([c[f"support_uplift_{j}"] for j in range(n_sup)])
              if n_sup else None)
    st = contact_statistics(c["time"], c["contact_force_1"], c["x_1"], tuple(window), uplift,
                            support_x[:n_sup] if n_sup else None)
    wall, init, cpu = (tuple(wall) + (None, None))[:3] if isinstance(wall, tuple) else (
        wall, None, None)
    out = dict(st.as_dict(), master=master, wall_time_s=wall, init_time_s=init, cpu_time_s=cpu,
               steps=int(len(c["time"]) - 1), timeseries=str(csv_path))
    if extra:
        out.update(extra)
    init_text = f" (of which {init:.2f} s initialisation)" if init is not None else ""
    if cpu is not None:
        init_text += f", {cpu:.2f} s CPU"
    print(f"{master}: {out['steps']} steps in {wall:.2f} s wall{init_text}; contact force over "
          f"{window[0]:g}..{window[1]:g} m (EN 50317, 20 Hz low-pass):")
    for key, label in (("mean_n", "mean [N]"), ("std_n", "std [N]"),
                       ("stat_max_n", "mean + 3 std [N]"), ("stat_min_n", "mean - 3 std [N]"),
                       ("max_n", "max [N]"), ("min_n", "min [N]"),
                       ("loss_of_contact_percent", "loss of contact [%]"),
                       ("max_uplift_at_support_m", "max uplift at support [m]")):
        print(f"  {label:28s} {out[key]:.6g}")
    Path(csv_path).with_suffix(".json").write_text(json.dumps(out, indent=2) + "\n")
    print("STATISTICS " + json.dumps(out))
    return out


if __name__ == "__main__":
    sys.exit(__doc__)

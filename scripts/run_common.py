"""Shared helpers of the third-party recipes (run_libcosim.py, run_ecos.py, run_fmpy_single.py).

Not a recipe itself. Every recipe runs the foreign master in a child process (``--child``)
that imports only numpy, scipy and the master (never ``pantocosim``: the FMUs import the copy
bundled in their resources, and pythonfmu may abort at process exit, design/fmi-toolchain.md
B5); the child writes the time series as CSV, prints its wall time and ends with
``os._exit(0)``. The parent reads the CSV and prints the EN 50317 statistics computed with
``pantocosim.master.statistics.contact_statistics``.
"""

from __future__ import annotations

import argparse
import csv
import json
import subprocess
import sys
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path
from types import SimpleNamespace

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_SSP = ROOT / "dist" / "fmus" / "dsa380-ave-300.ssp"
NS = {"ssd": "http://ssp-standard.org/SSP1/SystemStructureDescription",
      "ssv": "http://ssp-standard.org/SSP1/SystemStructureParameterValues"}


# ------------------------------------------------------------------------- SSP
def read_ssd(ssp: str | Path) -> dict:
    """Parameters per component, connections and the default stop time of an SSP file."""
    with zipfile.ZipFile(ssp) as z:
        root = ET.fromstring(z.read("SystemStructure.ssd"))
    params: dict = {}
    sets = sorted({ps.get("name") for ps in root.iter(f"{{{NS['ssv']}}}ParameterSet")})
    for comp in root.iter(f"{{{NS['ssd']}}}Component"):
        p = params.setdefault(comp.get("name"), {})
        for par in comp.iter(f"{{{NS['ssv']}}}Parameter"):
            (val,) = list(par)
            kind = val.tag.split("}")[1]
            text = val.get("value")
            p[par.get("name")] = (float(text) if kind == "Real" else int(text)
                                  if kind == "Integer" else text)
    exp = root.find("ssd:DefaultExperiment", NS)
    stop = float(exp.get("stopTime")) if exp is not None and exp.get("stopTime") else None
    return {"parameters": params, "stop_time": stop, "parameter_sets": sets}


def catenary_layout(cat_params: dict) -> np.ndarray:
    """Support positions of the catenary the SSP's catenary FMU builds."""
    from pantocosim.catenary.definition import load_catenary, with_spans

    d = load_catenary(cat_params.get("catenary", "en50318"))
    if int(cat_params.get("spans", 0)):
        d = with_spans(d, int(cat_params["spans"]))
    return np.asarray(d.support_x, float)


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
def run_child(script: str | Path, args: list) -> tuple:
    """Run ``script --child ARGS``; returns its wall time (printed as ``WALL <s>``), the part
    of it spent in initialisation (``INIT <s>``: model set-up and numba JIT) and the process
    CPU time of the run (``CPU <s>``), the last two None when not printed."""
    cmd = [sys.executable, str(script), "--child", *map(str, args)]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    wall = [l for l in proc.stdout.splitlines() if l.startswith("WALL ")]
    if proc.returncode != 0 or not wall:
        sys.stderr.write(proc.stdout[-6000:] + proc.stderr[-6000:])
        raise SystemExit(f"{Path(script).name}: the co-simulation failed "
                         f"(exit code {proc.returncode})")
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
    ``out``, ``n_sup`` (support uplift columns written, at most 64) and ``tool``."""
    ssd = read_ssd(a.ssp)
    cat = ssd["parameters"]["catenary"]
    support_x = catenary_layout(cat)
    return SimpleNamespace(
        tool=tool, ssd=ssd, cat=cat, support_x=support_x,
        stop=a.stop if a.stop is not None else ssd["stop_time"],
        window=a.window or default_window(support_x),
        out=a.out or Path("results") / f"{a.ssp.stem}-{tool}.csv",
        n_sup=min(len(support_x), 64))


def run_ssp_child(script: str | Path, a: argparse.Namespace, r: SimpleNamespace,
                  *extra) -> None:
    """Run an SSP recipe's child (arguments: SSP, step, stop, CSV, supports, x0, V, extra)
    and report its statistics."""
    wall = run_child(script, ["--", a.ssp.resolve(), a.step, r.stop, r.out, r.n_sup,
                              r.cat["position_1"], r.cat["speed_kmh"] / 3.6, *extra])
    report(r.tool, r.out, r.window, r.support_x, wall, {"ssp": str(a.ssp), "step_s": a.step})


def default_window(support_x: np.ndarray) -> tuple[float, float]:
    """Supports 5..6 (the thesis' spans 5-6) when the line has them."""
    if len(support_x) < 7:
        raise SystemExit("the line has fewer than 6 spans: give --window START END (m)")
    return float(support_x[5]), float(support_x[6])


def report(master: str, csv_path: Path, window, support_x, wall, extra=None) -> dict:
    """EN 50317 statistics of the run in ``csv_path``; prints a table and a JSON line
    ``STATISTICS {...}`` and writes ``<csv>.json``."""
    from pantocosim.master.statistics import contact_statistics

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

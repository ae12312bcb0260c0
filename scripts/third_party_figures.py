#!/usr/bin/env python3
"""The figures table of docs/third-party.md, from runs: the shipped SSP of the default
scenario in each third-party master, and with its pantograph FMU swapped for every other
pantograph FMU (a file swap inside the SSP, nothing else edited), against ``pantocosim run``
of the same scenario with that pantograph (monolithic).

    python scripts/third_party_figures.py [--work DIR]
        [--masters libcosim ecos fmpy cofmupy omsimulator]
        [--models dsa380-rigid en50318-2mass dsa380-lumped3] [--docs docs/third-party.md]

Writes the table between the markers ``<!-- figures:start -->`` and ``<!-- figures:end -->``
of the docs page and prints it; the page's rows of masters and models not run stay.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import subprocess
import sys
import time
from pathlib import Path

from _tables import put_between

ROOT = Path(__file__).resolve().parents[1]
START, END = "<!-- figures:start -->", "<!-- figures:end -->"
MASTERS = {"libcosim": "libcosim", "ecos": "ecos", "fmpy": "fmpy_ssp",
           "cofmupy": "cofmupy_json", "omsimulator": "omsimulator"}
#: masters run by default (OMSimulator is built by hand: --masters omsimulator, with
#: $OMSIMULATOR or OMSimulator on PATH)
DEFAULT_MASTERS = ["libcosim", "ecos", "fmpy", "cofmupy"]


def reference(scenario: str, model: str) -> dict:
    """``pantocosim run`` (monolithic) of the scenario with ``model`` as its pantograph."""
    from pantocosim.master.run import prepare, run_monolithic
    from pantocosim.master.scenario import load_scenario

    sc = load_scenario(scenario)
    sc.pantographs = [dataclasses.replace(sc.pantographs[0], model=model, fmu=None)]
    t = time.perf_counter()
    res = run_monolithic(prepare(sc), None, progress=False)
    out = res.statistics()[0].as_dict()
    out["wall_time_s"] = time.perf_counter() - t
    return out


def third_party(master: str, ssp: Path, work: Path, extra=()) -> dict:
    module = f"pantocosim.master.thirdparty.{MASTERS[master]}"
    csv = work / f"{ssp.stem}-{master}.csv"
    proc = subprocess.run([sys.executable, "-m", module, "--ssp", str(ssp), "--out", str(csv),
                           *extra], capture_output=True, text=True, cwd=work)
    lines = [l for l in proc.stdout.splitlines() if l.startswith("STATISTICS ")]
    if proc.returncode != 0 or not lines:
        return {"error": (proc.stdout + proc.stderr).strip().splitlines()[-1:]}
    return json.loads(lines[-1][len("STATISTICS "):])


def cofmupy_swap(folder: Path, model: str, work: Path) -> Path:
    """The shipped CoFmuPy configuration with the pantograph FMU swapped for ``model``'s (a
    CoFmuPy configuration names its FMU files: the swap is that path)."""
    config = json.loads((folder / "cofmupy.json").read_text())
    for fmu in config["fmus"]:
        fmu["path"] = str(folder / (f"{model}.fmu" if fmu["id"] == "pantograph"
                                    else fmu["path"]))
    dest = work / f"cofmupy-{model}.json"
    dest.write_text(json.dumps(config, indent=2))
    return dest


def failure(error) -> str:
    """A failed run's cell: the FMU's refusal where it gave one."""
    from pantocosim.master.thirdparty.common import REFUSED

    text = " ".join(error) if isinstance(error, list) else str(error)
    if REFUSED in text:
        return "refused: " + text.split(REFUSED, 1)[1].strip().split("] ", 1)[-1]
    return f"failed: {text}"


def table(rows: list[dict]) -> str:
    out = ["| master | pantograph FMU | mean [N] | ref. mean | Δ mean | σ [N] | ref. σ | Δ σ "
           "| max uplift [mm] | wall [s] |",
           "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        s, ref = r["stats"], r["ref"]
        if "error" in s:
            out.append(f"| {r['master']} | {r['model']} | {failure(s['error'])} |||||||| |")
            continue
        dm = 100 * (s["mean_n"] / ref["mean_n"] - 1)
        ds = 100 * (s["std_n"] / ref["std_n"] - 1)
        out.append(f"| {r['master']} | {r['model']} | {s['mean_n']:.2f} | {ref['mean_n']:.2f} "
                   f"| {dm:+.2f} % | {s['std_n']:.2f} | {ref['std_n']:.2f} | {ds:+.2f} % "
                   f"| {1e3 * s['max_uplift_at_support_m']:.1f} | {s['wall_time_s']:.0f} |")
    return "\n".join(out)


def _key(line: str) -> tuple[str, str]:
    cells = [c.strip() for c in line.strip().strip("|").split("|")]
    return cells[0], cells[1]


def merged(old: str, new: str, models: list[str]) -> str:
    """The table ``new`` with the rows of ``old`` (the page's) it does not replace, ordered
    by pantograph and master."""
    head = new.splitlines()[:2]
    rows = {_key(l): l for l in old.strip().splitlines()[2:] if l.startswith("|")}
    rows.update({_key(l): l for l in new.splitlines()[2:]})
    order = list(dict.fromkeys([_key(l)[1] for l in old.strip().splitlines()[2:]
                                if l.startswith("|")] + models))
    keys = sorted(rows, key=lambda k: (order.index(k[1]), list(MASTERS).index(k[0])
                                       if k[0] in MASTERS else len(MASTERS)))
    return "\n".join(head + [rows[k] for k in keys])


def main(argv=None) -> int:
    from pantocosim.master.fmu.dist import build_all
    from pantocosim.master.thirdparty.common import swap_pantograph

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--work", type=Path, default=ROOT / "out" / "third-party")
    ap.add_argument("--masters", nargs="*", default=DEFAULT_MASTERS, choices=list(MASTERS))
    ap.add_argument("--models", nargs="*",
                    default=["dsa380-rigid", "en50318-2mass", "dsa380-lumped3"])
    ap.add_argument("--scenario", default="dsa380-ave-300")
    ap.add_argument("--docs", type=Path, default=ROOT / "docs" / "third-party.md")
    ap.add_argument("--keep", type=Path, help="figures.json of an earlier run: its rows of "
                    "other masters or models stay in the table")
    ap.add_argument("--cofmupy-python", default=str(Path.home() / ".cache" / "pantocosim"
                                                    / "cofmupy-venv" / "bin" / "python"),
                    help="the Python of a venv with CoFmuPy 1.0 and numba")
    a = ap.parse_args(argv)
    a.work.mkdir(parents=True, exist_ok=True)
    fmus = a.work / "dist" / "fmus"
    build_all(fmus, quiet=True)
    shipped = fmus / f"{a.scenario}.ssp"
    rows = []
    for model in a.models:
        ref = reference(a.scenario, model)
        ssp = a.work / f"{a.scenario}-{model}.ssp"
        swap_pantograph(shipped, fmus / a.scenario / f"{model}.fmu", ssp)
        for master in a.masters:
            extra = (["--python", a.cofmupy_python, "--config",
                      cofmupy_swap(fmus / a.scenario, model, a.work)]
                     if master == "cofmupy" else [])
            rows.append({"master": master, "model": model, "ref": ref,
                         "stats": third_party(master, ssp, a.work, extra)})
            print(table(rows[-1:]).splitlines()[-1], flush=True)
    if a.keep:
        done = {(r["master"], r["model"]) for r in rows}
        rows = [r for r in json.loads(a.keep.read_text())
                if (r["master"], r["model"]) not in done] + rows
        models = list(dict.fromkeys([r["model"] for r in rows]))
        rows.sort(key=lambda r: (models.index(r["model"]), list(MASTERS).index(r["master"])))
    page = a.docs.read_text()
    text = table(rows)
    if START in page and END in page:
        text = merged(page[page.index(START) + len(START):page.index(END)], text,
                      list(dict.fromkeys(a.models)))
        a.docs.write_text(put_between(page, (START, END), text))
    print(text)
    (a.work / "figures.json").write_text(json.dumps(rows, indent=2) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())

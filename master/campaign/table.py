"""The results table of a sweep: one row per case and pantograph, in CSV and Parquet.

Rows are appended to ``results.csv`` as cases finish (flushed at once), and
``results.parquet`` is rewritten from all rows (to a temporary file, then renamed, so a reader
never sees half a file) at most every few seconds and when the sweep ends.
"""

from __future__ import annotations

import csv
import json
import math
import os
import time
from pathlib import Path

from pantocosim.master.campaign.assessment import STATISTICS, Criteria, assess
from pantocosim.master.output_folder import writing

#: columns that describe every case, whatever its axes
DESCRIPTORS = ("scenario", "speed_kmh", "catenary", "catenary_model", "coupling")
#: axes already shown by a descriptor or the pantograph columns
SHOWN = set(DESCRIPTORS) | {"pantograph"}
TIMINGS = ("case_wall_time_s", "case_cpu_time_s", "prepare_time_s", "run_time_s", "finish_time_s",
           "run_wall_time_s", "setup_time_s", "steps", "simulated_time_s", "worker",
           "worker_pid", "worker_rss_mb", "started_at", "finished_at")


def columns(axis_names: list, criteria: Criteria) -> list:
    axes = [a for a in axis_names if a not in SHOWN]
    return (["index", "case", "status", "error", "warnings", *DESCRIPTORS, *axes, "pantograph",
             "pantograph_model", "target_mean_n", *STATISTICS,
             *[c.name for c in criteria.items], "assessment", *TIMINGS, "folder"])


def rows_of(record: dict, case, criteria: Criteria) -> list[dict]:
    """The table rows of a case's record (one per pantograph; one row if the run has no
    statistics)."""
    base = {"index": case.index, "case": case.key, "status": record["status"],
            "error": record.get("error"),
            "warnings": "; ".join(record.get("warnings") or []) or None, **case.descriptors,
            "folder": record.get("folder")}
    for name, value in case.values.items():
        if name not in SHOWN:
            base[name] = json.dumps(value) if isinstance(value, (list, dict)) else value
    summary = record.get("summary") or {}
    base["run_wall_time_s"] = summary.get("wall_time_s")
    base["setup_time_s"] = summary.get("setup_time_s")
    base["steps"] = summary.get("steps")
    base["simulated_time_s"] = summary.get("simulated_time_s")
    for k in TIMINGS:
        if k in record:
            base[k] = record[k]
    pans = summary.get("pantographs") or [
        {"index": k + 1, "model": p.get("model"), "statistics": None}
        for k, p in enumerate(case.scenario.get("pantographs", []))]
    targets = summary.get("target_mean_n") or []
    rows = []
    for k, p in enumerate(pans):
        stats = p.get("statistics") if record["status"] in ("ok", "warned") else None
        row = dict(base, pantograph=p["index"], pantograph_model=_model(p["model"]),
                   target_mean_n=targets[k] if k < len(targets) else None)
        for s in STATISTICS:
            row[s] = None if stats is None else stats.get(s)
        row.update(assess(criteria, stats, case.descriptors["speed_kmh"]))
        rows.append(row)
    return rows


def _model(name: str) -> str:
    return Path(name).stem if name and ("/" in name or name.endswith(".toml")) else name


class ResultsTable:
    """``results.csv`` and ``results.parquet`` in ``folder``."""

    def __init__(self, folder: Path, names: list, parquet_every_s: float = 5.0):
        self.folder = Path(folder)
        self.names = names
        self.rows: list = []
        self.every = parquet_every_s
        self._last = 0.0
        self.csv_path = self.folder / "results.csv"
        self.parquet_path = self.folder / "results.parquet"
        with writing("file", self.csv_path):
            self._fh = open(self.csv_path, "w", newline="")
            self._csv = csv.DictWriter(self._fh, fieldnames=names, extrasaction="ignore")
            self._csv.writeheader()
            self._fh.flush()

    def add(self, rows: list) -> None:
        with writing("file", self.csv_path):
            for r in rows:
                self._csv.writerow({k: _cell(r.get(k)) for k in self.names})
            self._fh.flush()
        self.rows += rows
        if time.monotonic() - self._last >= self.every:
            self.write_parquet()

    def write_parquet(self) -> None:
        import pyarrow as pa
        import pyarrow.parquet as pq

        data = {k: [_value(r.get(k)) for r in self.rows] for k in self.names}
        table = pa.table(data)
        tmp = self.parquet_path.with_suffix(".parquet.tmp")
        try:
            with writing("file", self.parquet_path):
                pq.write_table(table, tmp)
                os.replace(tmp, self.parquet_path)
        finally:
            tmp.unlink(missing_ok=True)
        self._last = time.monotonic()

    def close(self) -> None:
        if not self._fh.closed:
            with writing("file", self.csv_path):
                self._fh.close()
        self.write_parquet()


def _cell(x):
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return ""
    return x


def _value(x):
    return None if isinstance(x, float) and math.isnan(x) else x


def read_table(folder: Path):
    """The results table of a sweep folder as a pandas-free dict of columns (Parquet if
    present, else CSV)."""
    folder = Path(folder)
    pq_path, csv_path = folder / "results.parquet", folder / "results.csv"
    if pq_path.exists():
        import pyarrow.parquet as pq

        return pq.read_table(pq_path).to_pylist()
    if csv_path.exists():
        with open(csv_path, newline="") as fh:
            return [{k: _parse(v) for k, v in r.items()} for r in csv.DictReader(fh)]
    return None


def _parse(text: str):
    if text == "":
        return None
    if text in ("True", "False"):
        return text == "True"
    try:
        return float(text) if any(c in text for c in ".eE") or not text.lstrip("-").isdigit() \
            else int(text)
    except ValueError:
        return text

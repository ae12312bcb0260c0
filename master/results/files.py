"""Result files: CSV time series (fmpy-style column names, ``time`` first) and JSON summaries."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np


def write_csv(path: str | Path, columns: dict[str, np.ndarray]) -> Path:
    """Write equally long columns as CSV with a header row (as fmpy.util.write_csv does)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    names = list(columns)
    data = np.column_stack([np.asarray(columns[k], dtype=float) for k in names])
    np.savetxt(path, data, delimiter=",", header=",".join(names), comments="", fmt="%.10g")
    return path


def read_csv(path: str | Path) -> dict[str, np.ndarray]:
    arr = np.genfromtxt(path, delimiter=",", names=True)
    return {name: np.asarray(arr[name]) for name in arr.dtype.names}


def write_json(path: str | Path, data: dict) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(data, indent=2, default=_to_builtin) + "\n")
    return path


def _to_builtin(x):
    if isinstance(x, np.generic):
        return x.item()
    if isinstance(x, np.ndarray):
        return x.tolist()
    raise TypeError(f"not JSON serialisable: {type(x).__name__}")

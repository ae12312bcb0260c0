"""Running the third-party recipes (``python -m pantocosim.master.thirdparty.X``) from tests:
each runs its master in a child process and prints ``STATISTICS {json}``."""

import csv
import json
import subprocess
import sys

import numpy as np
import pytest
from tooling import missing


def run_recipe(name, *args, cwd=None, timeout=1200):
    """(statistics, stdout) of recipe ``name`` (libcosim, ecos, fmpy_ssp, cofmupy_json,
    fmpy_single)."""
    proc = subprocess.run([sys.executable, "-m", f"pantocosim.master.thirdparty.{name}",
                           *map(str, args)], capture_output=True, text=True, timeout=timeout,
                          cwd=cwd)
    assert proc.returncode == 0, proc.stdout[-4000:] + proc.stderr[-4000:]
    lines = [l for l in proc.stdout.splitlines() if l.startswith("STATISTICS ")]
    assert lines, proc.stdout[-4000:] + proc.stderr[-4000:]
    return json.loads(lines[-1][len("STATISTICS "):]), proc.stdout


def read_csv(path):
    with open(path) as f:
        rows = list(csv.reader(f))
    data = np.array(rows[1:], dtype=float)
    return {h: data[:, i] for i, h in enumerate(rows[0])}


def require_ecospy() -> None:
    """Skip where ecospy cannot be used: not installed (ImportError), or its native library
    cannot load because libtbb.so.12 is missing (OSError from ctypes, which
    ``pytest.importorskip`` does not catch)."""
    try:
        import ecospy  # noqa: F401
    except (ImportError, OSError) as exc:
        missing(f"ecospy ({exc})", "pip install ecospy; apt-get install -y libtbb12")

"""`pantocosim regress`: the FMU regression cases match the stored references."""

import subprocess
import sys

import pytest

#: FMUs or long runs: outside `pytest -m "not slow"` (CI runs everything)
pytestmark = pytest.mark.slow


def test_regression_cases_match_references(tmp_path):
    """In a folder of the test's own: the command builds its FMUs into dist/fmus/ there."""
    proc = subprocess.run([sys.executable, "-m", "pantocosim.master.cli",
                           "regress"], capture_output=True, text=True, timeout=1500,
                          cwd=tmp_path)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    rows = [l for l in proc.stdout.splitlines() if l.startswith(("pantograph-", "short-"))]
    assert len(rows) == 5 and all(" ok " in l for l in rows), proc.stdout

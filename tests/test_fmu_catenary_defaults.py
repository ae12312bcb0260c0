"""The catenary FMU with its default parameters (a standing train, speed 0) runs in fmpy's
``simulate_fmu`` at once; its start laws are then the static ones; a speed whose start laws
would take an endless moving-load run is refused naming ``speed_kmh``. Each FMU is loaded in
a subprocess (docs/pythonfmu-notes.md)."""

import json
import subprocess
import sys

import pytest

pytestmark = pytest.mark.slow

SCRIPT = r'''
import json, sys, fmpy
messages = []
try:
    r = fmpy.simulate_fmu(sys.argv[1], stop_time=0.01, step_size=1e-3,
                          start_values=json.loads(sys.argv[2]),
                          logger=lambda *a: messages.append(a[4].decode()))
    out = {n: [float(r[n][0]), float(r[n][-1])] for n in r.dtype.names}
    out["rows"] = len(r)
except Exception as exc:
    out = {"error": str(exc)}
out["messages"] = messages
print("RESULT " + json.dumps(out))
'''


def simulate(fmu, start_values: dict) -> dict:
    proc = subprocess.run([sys.executable, "-c", SCRIPT, str(fmu), json.dumps(start_values)],
                          capture_output=True, text=True, timeout=300)
    lines = [line for line in proc.stdout.splitlines() if line.startswith("RESULT ")]
    assert proc.returncode == 0 and lines, proc.stdout[-3000:] + proc.stderr[-3000:]
    return json.loads(lines[-1][7:])


def test_the_defaults_run_with_the_static_start_laws(fmus):
    out = simulate(fmus["catenary"], {})
    assert "error" not in out, out
    assert out["time"][-1] == pytest.approx(0.01)
    assert out["operating_height_1"] == out["static_height_1"]
    assert out["operating_height_slope_1"] == out["static_height_slope_1"]
    assert 4.5 < out["static_height_1"][0] < 6.0
    assert 0.0 < out["static_height_slope_1"][0] < 1e-2


def test_a_crawling_train_is_refused_naming_the_speed(fmus):
    out = simulate(fmus["catenary"], {"speed_kmh": 0.01})
    assert "error" in out
    refusal = [m for m in out["messages"] if "speed_kmh = 0.01" in m]
    assert refusal and "moving-load run" in refusal[0] and "at least" in refusal[0]

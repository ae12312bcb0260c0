"""Co-simulation through the FMUs with our master, run as the CLI in subprocesses
(pythonfmu FMUs never load into the pytest process)."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from pantocosim.master.results.files import read_csv
from pantocosim.master.run import prepare, run_monolithic

#: FMUs or long runs: outside `pytest -m "not slow"` (CI runs everything)
pytestmark = pytest.mark.slow

SHORT = Path(__file__).with_name("data") / "short-en50318.toml"


def cli(*args, timeout=900):
    proc = subprocess.run([sys.executable, "-m", "pantocosim.master.cli",
                           *map(str, args)], capture_output=True, text=True, timeout=timeout)
    return proc


def scenario_with(tmp_path, model):
    p = tmp_path / f"short-{model}.toml"
    p.write_text(SHORT.read_text().replace('model = "en50318-2mass"', f'model = "{model}"')
                 .replace('name = "short-en50318"', f'name = "short-{model}"'))
    return p


def short_with_catenary(tmp_path, catenary_model):
    """The short scenario with ``catenary_model`` (nonlinear: the file itself)."""
    if catenary_model == "nonlinear":
        return SHORT
    p = tmp_path / f"short-{catenary_model}.toml"
    p.write_text(SHORT.read_text().replace('name = "short-en50318"',
                                           f'name = "short-{catenary_model}"')
                 + f'catenary_model = "{catenary_model}"\n')
    return p


@pytest.mark.parametrize("catenary_model", ["nonlinear", "linear", "modal"])
def test_implicit_fmu_coupling_equals_monolithic(tmp_path, catenary_model):
    """Tight tolerances: the iterative coupling through the FMUs reproduces the monolithic
    solution of the same catenary model (linear and modal: closed-form steps on both
    sides)."""
    scenario = short_with_catenary(tmp_path, catenary_model)
    mono = run_monolithic(prepare(str(scenario)), None, progress=False)
    out = tmp_path / "implicit"
    proc = cli("run", scenario, "--coupling", "implicit", "--out", out, "--quiet",
               "--no-plots", "--json")
    assert proc.returncode == 0, proc.stdout + proc.stderr
    summary = json.loads(proc.stdout)
    assert summary["coupling"] == "implicit"
    assert summary["coupling_iterations_max"] <= 6
    F = read_csv(out / "timeseries.csv")["contact_force_1"]
    Fm = mono.columns["contact_force_1"]
    # CSV keeps 10 significant digits
    assert np.max(np.abs(F - Fm)) < 1e-6 * Fm.mean()


@pytest.mark.parametrize("model", ["en50318-2mass", "dsa380-lumped3", "dsa380-rigid"])
def test_explicit_fmu_coupling_runs_for_every_pantograph_model(tmp_path, model):
    """Swapping the pantograph is a change of the scenario file only."""
    sc = scenario_with(tmp_path, model)
    out = tmp_path / model
    proc = cli("run", sc, "--coupling", "explicit", "--out", out, "--quiet", "--no-plots",
               "--json")
    assert proc.returncode == 0, proc.stdout + proc.stderr
    st = json.loads(proc.stdout)["statistics"]
    assert 50.0 < st["mean_n"] < 200.0 and st["std_n"] > 0.0
    mono = run_monolithic(prepare(str(sc)), None, progress=False).statistics()[0]
    assert abs(st["mean_n"] - mono.mean_n) < 0.01 * mono.mean_n


def test_bad_pantograph_option_names_the_field(tmp_path):
    sc = tmp_path / "bad.toml"
    sc.write_text(SHORT.read_text().replace('start = "static"',
                                            'start = "static"\noptions = { aero_c2 = nan }'))
    proc = cli("run", sc, "--coupling", "explicit", "--out", tmp_path / "bad", "--quiet")
    assert proc.returncode == 2
    assert "aero_c2 = nan" in proc.stderr


def test_master_reports_the_fmu_message(tmp_path):
    """A bad parameter set through FMI: fmi2ExitInitializationMode returns fmi2Error with a
    message naming the parameter, the master's FMU layer raises it as an FmuError, a later
    step is discarded, the process survives."""
    code = (
        "from pantocosim.master.fmu.build import build_fmus\n"
        "from pantocosim.master.fmu.runtime import FmuInstance, FmuError\n"
        "import os\n"
        f"p = build_fmus({str(tmp_path)!r}, only=['en50318-2mass'], quiet=True)[0]\n"
        "i = FmuInstance(p, 'pan')\n"
        "try:\n"
        "    i.initialize({'start_mode': 7, 'speed_kmh': float('nan')})\n"
        "    print('NO ERROR')\n"
        "except FmuError as e:\n"
        "    print('STATUS', e.status)\n"
        "    print('MESSAGE', e)\n"
        "try:\n"
        "    i.do_step(0.0, 1e-3)\n"
        "except FmuError as e:\n"
        "    print('STEP', e.status)\n"
        "i.terminate()\n"
        "print('ALIVE', flush=True)\n"
        "os._exit(0)\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=600)
    assert "STATUS 3" in proc.stdout, proc.stdout + proc.stderr
    assert "speed_kmh = nan" in proc.stdout
    assert "STEP 2" in proc.stdout
    assert "ALIVE" in proc.stdout


def test_real_vector_exchanges_values_through_fmi(fmus):
    """RealVector (the master's per-step exchange) writes and reads the FMU's variables as
    fmpy's setReal/getReal do."""
    code = (
        "from pantocosim.master.fmu.runtime import FmuInstance\n"
        "import os\n"
        f"i = FmuInstance({str(fmus['en50318-2mass'])!r}, 'pan')\n"
        "i.initialize({'speed_kmh': 300.0})\n"
        "i.reals(['contact_force']).set([123.5])\n"
        "both = i.reals(['contact_height', 'contact_force'])\n"
        "print('GOT', list(both.get()) == i.get_real(both.refs).tolist(), both.get()[1])\n"
        "i.terminate()\n"
        "os._exit(0)\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=600)
    assert "GOT True 123.5" in proc.stdout, proc.stdout + proc.stderr


def test_real_vector_failure_is_an_fmu_error():
    """A failing fmi2GetReal/fmi2SetReal of a RealVector raises FmuError with the call's
    status and the instance's name (an FMU stand-in: nothing is loaded)."""
    from types import SimpleNamespace

    from pantocosim.master.fmu.runtime import Fmi2Api, FmuError, FmuInstance, RealVector

    class Refused(Exception):
        status = 3

    def refuse(*args):
        raise Refused("fmi2GetReal failed")

    fmu = FmuInstance.__new__(FmuInstance)
    fmu.name, fmu.path, fmu.fatal, fmu.api = "pan", Path("pan.fmu"), False, Fmi2Api
    fmu.slave = SimpleNamespace(component=None, fmi2GetReal=refuse, fmi2SetReal=refuse)
    vector = RealVector(fmu, [1, 2])
    for call in (vector.get, lambda: vector.set([1.0, 2.0])):
        with pytest.raises(FmuError) as err:
            call()
        assert err.value.status == 3 and err.value.instance == "pan"

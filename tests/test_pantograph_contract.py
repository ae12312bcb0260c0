"""Any pantograph FMU with the three contract ports couples with the catenary FMU
(``pantocosim ssp --pantograph FMU``), and a pantograph FMU in the SSP either runs its model
or is refused with what the master did not give (docs/third-party.md, "Pantograph FMU
contract").

The contract-only FMU is written and built here (pythonfmu): the EN 50318 two-mass pantograph
of fmus/pantograph/data/en50318-2mass.toml with the ports contact_force, contact_height and
contact_velocity only. FMUs run in child processes."""

import json
import subprocess
import sys
import textwrap
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import pytest
from recipes import require_ecospy, run_recipe

ROOT = Path(__file__).resolve().parents[1]
SHORT = ROOT / "tests" / "data" / "ssp-short.toml"

#: en50318-2mass.toml: head m1 - k1/c1 - frame m2 - k2/c2 - ground; the uplift on the frame
CONTRACT_FMU = '''
import numpy as np
from pythonfmu import Fmi2Causality, Fmi2Slave, Fmi2Variability, Real


class ContractTwoMass(Fmi2Slave):
    """Two-mass pantograph with the contract ports only; HHT-alpha steps (closed form) with
    the input force held over the step (the value set before doStep(t, h) is the force at t).
    Static start at INITIAL_HEIGHT, the uplift delivered at ACTUATION_HEIGHT."""

    author = "pantocosim tests"
    M = np.diag([7.2, 15.0])
    K1, K2, C1, C2 = 4200.0, 50.0, 10.0, 90.0
    UPLIFT = 115.0
    ALPHA = -0.05
    ACTUATION_HEIGHT = {actuation!r}
    INITIAL_HEIGHT = {initial!r}

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.contact_force = 0.0
        self._q = self._v = None
        self.register_variable(Real("contact_force", causality=Fmi2Causality.input,
                                    variability=Fmi2Variability.continuous))
        self.register_variable(Real(
            "contact_height", causality=Fmi2Causality.output,
            variability=Fmi2Variability.continuous,
            getter=lambda: self.INITIAL_HEIGHT if self._q is None else float(self._q[0])))
        self.register_variable(Real(
            "contact_velocity", causality=Fmi2Causality.output,
            variability=Fmi2Variability.continuous,
            getter=lambda: 0.0 if self._v is None else float(self._v[0])))
        k1, k2, c1, c2 = self.K1, self.K2, self.C1, self.C2
        self.K = np.array([[k1, -k1], [-k1, k1 + k2]])
        self.C = np.array([[c1, -c1], [-c1, c1 + c2]])

    def _load(self, F):
        return np.array([-F, self.UPLIFT + self.K2 * self._ref])

    def exit_initialization_mode(self):
        k1, k2 = self.K1, self.K2
        self._ref = self.ACTUATION_HEIGHT + self.UPLIFT / k1
        F = self.UPLIFT - (self.INITIAL_HEIGHT - self.ACTUATION_HEIGHT) / (1 / k1 + 1 / k2)
        self._q = np.array([self.INITIAL_HEIGHT, self.INITIAL_HEIGHT + F / k1])
        self._v = np.zeros(2)
        self._a = np.zeros(2)
        self._f = self._load(F)
        a = self.ALPHA
        self._beta, self._gamma = (1 - a) ** 2 / 4, (1 - 2 * a) / 2
        return True

    def do_step(self, t, h):
        a, b, g = self.ALPHA, self._beta, self._gamma
        q, v, acc = self._q, self._v, self._a
        f_new = self._load(float(self.contact_force))
        qs = q + h * v + h * h * (0.5 - b) * acc
        vs = v + h * (1 - g) * acc
        lhs = self.M + (1 + a) * (g * h * self.C + b * h * h * self.K)
        rhs = ((1 + a) * f_new - a * self._f - (1 + a) * (self.C @ vs + self.K @ qs)
               + a * (self.C @ v + self.K @ q))
        acc_new = np.linalg.solve(lhs, rhs)
        self._q = qs + b * h * h * acc_new
        self._v = vs + g * h * acc_new
        self._a, self._f = acc_new, f_new
        return True
'''

#: fmpy's simulate_ssp on an SSP (argv 1), optionally with the SSD's parameter bindings
#: (argv 2 = "bind"); prints RAN or FAILED and the FMUs' messages
FMPY_CHILD = textwrap.dedent('''
    import os, sys
    import scipy.sparse.linalg  # noqa: F401
    from fmpy.ssp.simulation import simulate_ssp
    from fmpy.ssp.ssd import Parameter, ParameterSet, read_ssd
    ssp, bind = sys.argv[1], len(sys.argv) > 2
    ps = None
    if bind:
        ps = ParameterSet(name="ssd", parameters=[
            Parameter(name=f"{c.name}.{p.name}", type=p.type, value=p.value)
            for c in read_ssd(ssp).system.elements for b in c.parameterBindings
            for p in b.parameterValues[0].parameters])
    try:
        res = simulate_ssp(ssp, stop_time=0.0105, step_size=1e-3, parameter_set=ps)
        print("RAN", len(res), flush=True)
    except Exception as exc:
        print("FAILED", exc, flush=True)
    os._exit(0)
''')


def cli(*args, cwd=None):
    return subprocess.run([sys.executable, "-m", "pantocosim.master.cli", "ssp",
                           *map(str, args)], capture_output=True, text=True, timeout=900,
                          cwd=cwd)


def fmpy_ssp(ssp, bind=False):
    proc = subprocess.run([sys.executable, "-c", FMPY_CHILD, str(ssp)]
                          + (["bind"] if bind else []), capture_output=True, text=True,
                          timeout=900)
    return proc.stdout + proc.stderr


# ------------------------------------------------------------------ bad input
def fake_fmu(path: Path, ports: dict, version: str = "2.0") -> Path:
    """A zip holding only a model description with ``ports`` {name: causality}."""
    root = ET.Element("fmiModelDescription", fmiVersion=version, modelName="x",
                      guid="{0}")
    ET.SubElement(root, "CoSimulation", modelIdentifier="x")
    variables = ET.SubElement(root, "ModelVariables")
    for i, (name, causality) in enumerate(ports.items()):
        v = ET.SubElement(variables, "ScalarVariable", name=name, valueReference=str(i),
                          causality=causality)
        ET.SubElement(v, "Real")
    with zipfile.ZipFile(path, "w") as z:
        z.writestr("modelDescription.xml", ET.tostring(root, encoding="unicode"))
    return path


@pytest.mark.parametrize("case, texts", [
    ("missing", ["no_velocity.fmu", "port = 'contact_velocity'", "missing"]),
    ("causality", ["wrong.fmu", "port = 'contact_height'", "a Real input instead of a Real "
                   "output"]),
    ("text", ["notes.fmu", "not an FMU", "accepted"]),
    ("fmi1", ["fmi1.fmu", "fmiVersion = '1.0'", "accepted: 2.0 or 3.0"]),
])
def test_ssp_command_refuses_bad_fmus_in_one_line(tmp_path, case, texts):
    full = {"contact_force": "input", "contact_height": "output",
            "contact_velocity": "output"}
    if case == "missing":
        fmu = fake_fmu(tmp_path / "no_velocity.fmu",
                       {k: v for k, v in full.items() if k != "contact_velocity"})
    elif case == "causality":
        fmu = fake_fmu(tmp_path / "wrong.fmu", dict(full, contact_height="input"))
    elif case == "text":
        fmu = tmp_path / "notes.fmu"
        fmu.write_text("not a zip")
    else:
        fmu = fake_fmu(tmp_path / "fmi1.fmu", full, version="1.0")
    proc = cli("--pantograph", fmu, "--scenario", SHORT, "--out", tmp_path / "x.ssp")
    assert proc.returncode == 2, proc.stdout + proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in proc.stderr, proc.stderr
    assert lines[0].startswith("pantocosim ssp: error: ")
    assert all(t in lines[0] for t in texts), lines[0]
    assert not (tmp_path / "x.ssp").exists()


# ------------------------------------------------------------------ the contract-only FMU
@pytest.fixture(scope="module")
def contract_ssp(tmp_path_factory):
    """The contract-only FMU (static start from this catenary's laws, as the command prints
    them for an FMU without the start-law inputs) and its SSP written by the command."""
    from pantocosim.master.ssp import scenario_start_values

    laws = scenario_start_values(SHORT)["laws"]
    k1, k2, uplift = 4200.0, 50.0, 115.0
    k_s = 1.0 / (1.0 / k1 + 1.0 / k2)
    h_op = laws["operating_height"] + laws["operating_height_slope"] * uplift
    F = ((uplift - k_s * (laws["static_height"] - h_op))
         / (1.0 + k_s * laws["static_height_slope"]))
    h0 = laws["static_height"] + laws["static_height_slope"] * F
    work = tmp_path_factory.mktemp("contract")
    script = work / "contract_two_mass.py"
    script.write_text(CONTRACT_FMU.format(actuation=h_op, initial=h0))
    from pythonfmu.builder import FmuBuilder

    fmu = Path(FmuBuilder.build_FMU(script, dest=work))
    ssp = work / "contract.ssp"
    proc = cli("--pantograph", fmu, "--scenario", SHORT, "--out", ssp)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "optional inputs connected: none" in proc.stdout
    assert f"{laws['static_height']:.6f} m" in proc.stdout
    return ssp


@pytest.fixture(scope="module")
def monolithic_2mass():
    import dataclasses

    from pantocosim.master.run import prepare, run_monolithic
    from pantocosim.master.scenario import load_scenario

    sc = load_scenario(SHORT)
    sc.pantographs = [dataclasses.replace(sc.pantographs[0], model="en50318-2mass",
                                          fmu=None)]
    return run_monolithic(prepare(sc), None, progress=False).statistics()[0]


@pytest.mark.slow
def test_contract_ssp_is_valid_and_connects_the_three_ports(contract_ssp):
    from fmpy.ssp.ssd import read_ssd

    ssd = read_ssd(str(contract_ssp), validate=True)
    links = {(c.startElement, c.startConnector, c.endElement, c.endConnector)
             for c in ssd.system.connections}
    assert links == {("pantograph", "contact_height", "catenary", "pantograph_height_1"),
                     ("pantograph", "contact_velocity", "catenary", "pantograph_velocity_1"),
                     ("catenary", "contact_force_out_1", "pantograph", "contact_force")}
    (pan,) = [e for e in ssd.system.elements if e.name == "pantograph"]
    assert not pan.parameterBindings          # nothing of ours is bound on a foreign FMU


@pytest.mark.slow
@pytest.mark.parametrize("master", ["libcosim", "ecos"])
def test_contract_only_pantograph_couples(master, contract_ssp, monolithic_2mass, tmp_path):
    """libcosim and ecos give the catenary the pantograph's height at t0 (in initialisation
    mode, or before the first step): the contract-only two-mass FMU runs the monolithic
    en50318-2mass statistics. Measured (1 ms, both masters): mean 114.079 N against
    114.077 N (+0.002 %), sigma 43.766 N against 43.262 N (+1.2 %): the FMU holds the force
    of t over the step, a one-step lag of the explicit coupling (our FMUs extrapolate it:
    -0.1 %)."""
    if master == "ecos":
        require_ecospy()
    stats, _ = run_recipe(master, "--ssp", contract_ssp, "--out", tmp_path / "run.csv")
    ref = monolithic_2mass
    assert stats["mean_n"] == pytest.approx(ref.mean_n, rel=2e-3)
    assert stats["std_n"] == pytest.approx(ref.std_n, rel=0.02)
    assert stats["max_uplift_at_support_m"] == pytest.approx(ref.max_uplift_at_support_m,
                                                             rel=0.03)


@pytest.mark.slow
def test_contract_only_pantograph_in_fmpy_is_refused_with_the_reason(contract_ssp):
    """fmpy's simulate_ssp exchanges nothing in initialisation mode: the catenary settles on
    its start value and refuses the pantograph's height when it first arrives (t = h)."""
    out = fmpy_ssp(contract_ssp)
    assert "FAILED" in out and "pantograph_height_1 = " in out, out
    assert "did not start on this catenary" in out and "libcosim" in out, out


# ------------------------------------------------------------------ the swap
@pytest.fixture(scope="module")
def swapped(tmp_path_factory, fmus):
    """The short scenario's SSP with the generic en50318-2mass FMU in place of its own."""
    from pantocosim.master.ssp import write_scenario_package
    from pantocosim.master.thirdparty.common import swap_pantograph

    out = tmp_path_factory.mktemp("short")
    write_scenario_package(out, scenarios=[SHORT], quiet=True)
    return swap_pantograph(out / "ssp-short.ssp", fmus["en50318-2mass"], out / "swap.ssp")


@pytest.mark.slow
def test_generic_pantograph_in_fmpy_is_refused_not_run_wrong(swapped):
    """No parameter set (fmpy's default): the generic FMU starts on its own defaults; the
    catenary refuses its height at t = h. With the SSD's bindings (start_mode 2): the
    pantograph refuses at fmi2ExitInitializationMode, naming the start-law inputs."""
    out = fmpy_ssp(swapped)
    assert "FAILED fmi2DoStep failed" in out and "mm from the height this catenary" in out, out
    out = fmpy_ssp(swapped, bind=True)
    assert "FAILED fmi2ExitInitializationMode failed" in out, out
    assert "start-law inputs operating_height" in out and "were not given" in out, out


@pytest.mark.slow
def test_generic_pantograph_in_libcosim_runs_its_model(swapped, monolithic_2mass, tmp_path):
    """libcosim applies the SSD's bindings and exchanges in initialisation mode: the start
    laws and the train speed reach the generic FMU, which runs its own model."""
    stats, _ = run_recipe("libcosim", "--ssp", swapped, "--out", tmp_path / "lc.csv")
    assert stats["mean_n"] == pytest.approx(monolithic_2mass.mean_n, rel=2e-3)
    assert stats["std_n"] == pytest.approx(monolithic_2mass.std_n, rel=0.01)


@pytest.mark.slow
def test_ssp_command_on_our_pantograph_fmu_connects_every_port(fmus, tmp_path):
    """A pantocosim pantograph FMU: every optional input connected (start laws, train
    speed) and the scenario's pantograph parameters bound, as in build-fmus' SSP."""
    from fmpy.ssp.ssd import read_ssd

    ssp = tmp_path / "ours.ssp"
    proc = cli("--pantograph", fmus["en50318-2mass"], "--scenario", SHORT, "--out", ssp)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    ssd = read_ssd(str(ssp), validate=True)
    inputs = {c.endConnector for c in ssd.system.connections if c.endElement == "pantograph"}
    assert inputs == {"contact_force", "operating_height", "operating_height_slope",
                      "static_height", "static_height_slope", "train_speed_kmh"}
    (pan,) = [e for e in ssd.system.elements if e.name == "pantograph"]
    bound = {p.name for b in pan.parameterBindings for p in b.parameterValues[0].parameters}
    assert bound == {"speed_kmh", "hht_alpha", "start_mode", "force_extrapolation"}

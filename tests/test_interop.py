"""The shipped files in third-party masters, unpatched: the SSP is valid and
tool-friendly and holds nothing of one pantograph model; fmpy's SSP support and CoFmuPy run
the default scenario from the FMUs' start values alone; a pantograph swap inside the SSP is a
file swap in libcosim; a non-editable install builds and runs from any folder.

FMUs run in child processes (the recipes), never in the pytest process."""

import dataclasses
import os
import re
import shutil
import subprocess
import sys
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import numpy as np
import pytest
from recipes import read_csv, require_ecospy, run_recipe

#: FMUs or long runs: outside `pytest -m "not slow"` (CI runs everything)
pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[1]
SHORT = ROOT / "tests" / "data" / "ssp-short.toml"
NS = {"ssd": "http://ssp-standard.org/SSP1/SystemStructureDescription",
      "ssv": "http://ssp-standard.org/SSP1/SystemStructureParameterValues"}
IDENT = re.compile(r"^[A-Za-z][A-Za-z0-9_]*$")


def monolithic(scenario, model=None, steps=None):
    """``pantocosim run`` (monolithic) of ``scenario``, optionally with another pantograph
    model, or only its first ``steps`` steps (same start): (Prepared, RunResult)."""
    from pantocosim.master.run import prepare, run_monolithic
    from pantocosim.master.scenario import load_scenario

    sc = load_scenario(scenario)
    if model:
        sc.pantographs = [dataclasses.replace(sc.pantographs[0], model=model, fmu=None)]
    prep = prepare(sc)
    if steps:
        prep = dataclasses.replace(prep, n_steps=steps)
    return prep, run_monolithic(prep, None, progress=False)


# ------------------------------------------------------------------------- the SSP
def test_shipped_ssp_is_valid_and_holds_no_pantograph_values(built):
    from fmpy.ssp.ssd import read_ssd

    ssp = built / "dsa380-ave-300.ssp"
    read_ssd(str(ssp), validate=True)          # the SSP 1.0 schemas fmpy ships
    with zipfile.ZipFile(ssp) as z:
        assert set(z.namelist()) == {"SystemStructure.ssd", "resources/dsa380-rigid.fmu",
                                     "resources/catenary.fmu"}
        root = ET.fromstring(z.read("SystemStructure.ssd"))
    names = [root.get("name")] + [e.get("name") for e in root.iter(f"{{{NS['ssd']}}}System")]
    components = list(root.iter(f"{{{NS['ssd']}}}Component"))
    assert len(components) == 2                  # the pantograph and the catenary
    for comp in components:
        names.append(comp.get("name"))
        connectors = [c.get("name") for c in comp.iter(f"{{{NS['ssd']}}}Connector")]
        names += connectors
        params = {p.get("name"): list(p)[0] for p in comp.iter(f"{{{NS['ssv']}}}Parameter")}
        assert comp.get("name") not in params
        assert not [p for p in params.values() if p.tag.endswith("String")]
        assert set(params) <= set(connectors)
        if comp.get("name") == "pantograph":
            # generic to every pantograph model: the scenario's speed and integrator, the
            # handshake start; no start height, no start force
            assert set(params) == {"speed_kmh", "hht_alpha", "start_mode",
                                   "force_extrapolation"}
    assert all(IDENT.match(n) for n in names), [n for n in names if not IDENT.match(n)]
    annotations = ET.tostring(root).decode()
    assert "org.openmodelica" in annotations and 'description="oms-ma"' in annotations


def test_outputs_declare_no_direct_feedthrough(fmus):
    assert {"catenary", "en50318-2mass", "dsa380-rigid"} <= set(fmus)
    for name, path in fmus.items():
        with zipfile.ZipFile(path) as z:
            md = ET.fromstring(z.read("modelDescription.xml"))
        outputs = md.findall("ModelStructure/Outputs/Unknown")
        assert outputs and all(u.get("dependencies") == "" for u in outputs), name


def test_scenario_fmus_carry_the_scenario_in_their_start_values(built):
    from fmpy import read_model_description

    start = {v.name: v.start for v in read_model_description(
        str(built / "dsa380-ave-300" / "catenary.fmu")).modelVariables}
    assert start["catenary_definition"] == "ave64" and start["contact_mode"] == "1"
    assert float(start["speed_kmh"]) == 300.0 and float(start["position_1"]) == 32.0
    for model in ("dsa380-rigid", "en50318-2mass", "dsa380-lumped3", "dsa380-flexible"):
        start = {v.name: v.start for v in read_model_description(
            str(built / "dsa380-ave-300" / f"{model}.fmu")).modelVariables}
        assert start["start_mode"] == "2" and float(start["speed_kmh"]) == 300.0, model
        assert 5.2 < float(start["operating_height"]) < 5.4, model


# ------------------------------------------------------------------------- the start
def test_handshake_start_is_the_monolithic_static_start():
    """The start laws and the pantograph's static start on them give the monolithic static
    start (prepare: catenary, pantograph and contact solved together) to a fraction of a
    newton, for every pantograph model."""
    from pantocosim.catenary.operating_height import contact_height_laws
    from pantocosim.master.run import prepare
    from pantocosim.master.scenario import load_scenario
    from pantocosim.interaction.pantograph_start import static_start_on_laws

    for model in ("en50318-2mass", "dsa380-rigid"):
        sc = load_scenario(SHORT)
        sc.pantographs = [dataclasses.replace(sc.pantographs[0], model=model)]
        prep = prepare(sc)
        laws = contact_height_laws(prep.catenary, sc.contact_stiffness, prep.window_m, sc.dt,
                                   prep.duration, sc.alpha)
        pan = prep.pantographs[0]
        q, F = static_start_on_laws(pan, laws.operating_offset[0], laws.operating_slope[0],
                                    laws.static_offset[0], laws.static_slope[0])
        # secant laws: within a few newtons (a dropper slackens between the secant forces)
        assert F == pytest.approx(prep.static_forces[0], rel=0.03), model
        h_mono = pan.contact_height(prep.q_pan0[0])
        assert pan.contact_height(q) == pytest.approx(h_mono, abs=1e-3), model
        # the actuation the laws set is the monolithic one: same operating height
        z_op = laws.operating_offset[0] + laws.operating_slope[0] * pan.options.mean_uplift
        assert z_op == pytest.approx(prep.actuation.height[0], abs=1e-4)


# ------------------------------------------------------------------------- masters
@pytest.fixture(scope="module")
def default_monolithic_1s():
    return monolithic("dsa380-ave-300", steps=1000)


@pytest.fixture(scope="module")
def fmpy_default_1s(built, tmp_path_factory):
    out = tmp_path_factory.mktemp("fmpy") / "fmpy.csv"
    stats, _ = run_recipe("fmpy_ssp", "--ssp", built / "dsa380-ave-300.ssp", "--stop", 1.0,
                          "--window", 40.0, 110.0, "--out", out)
    return read_csv(out), stats


@pytest.mark.slow
def test_fmpy_simulate_ssp_runs_the_shipped_ssp_unpatched(fmpy_default_1s,
                                                          default_monolithic_1s):
    """fmpy sets no parameter, exchanges nothing at initialisation and passes 0 at the first
    step: the scenario FMUs' start values alone give the monolithic run's contact force."""
    c, _ = fmpy_default_1s
    prep, mono = default_monolithic_1s
    F_mono = np.asarray(mono.columns["contact_force_1"])[1:]
    F = c["contact_force_1"]
    assert len(F) == len(F_mono) == 1000
    assert np.all(np.isfinite(F)) and F.min() > 50.0
    # explicit (zero-order hold, extrapolated) coupling against the monolithic solution
    assert np.max(np.abs(F - F_mono)) < 0.02 * prep.static_forces[0]
    assert np.mean(F) == pytest.approx(np.mean(F_mono), rel=2e-3)


@pytest.mark.slow
def test_cofmupy_runs_the_shipped_config(built, fmpy_default_1s, cofmupy_python, tmp_path):
    """CoFmuPy with the shipped configuration (Jacobi, no start values set): the same run as
    fmpy's SSP support (both pass 0 at the first step and couple by Jacobi)."""
    out = tmp_path / "cofmupy.csv"
    stats, _ = run_recipe("cofmupy_json", "--ssp", built / "dsa380-ave-300.ssp", "--python",
                          cofmupy_python, "--stop", 1.0, "--window", 40.0, 110.0,
                          "--out", out)
    c = read_csv(out)
    ref, ref_stats = fmpy_default_1s
    assert np.max(np.abs(c["contact_force_1"] - ref["contact_force_1"])) < 1e-6
    assert stats["std_n"] == pytest.approx(ref_stats["std_n"], rel=1e-6)


@pytest.fixture(scope="module")
def short_package(tmp_path_factory):
    """The scenario files of tests/data/ssp-short.toml (its FMUs, SSP, CoFmuPy config)."""
    from pantocosim.master.ssp import write_scenario_package

    out = tmp_path_factory.mktemp("short")
    write_scenario_package(out, scenarios=[SHORT], quiet=True)
    return out


@pytest.mark.slow
@pytest.mark.parametrize("model", ["en50318-2mass", "dsa380-lumped3"])
def test_pantograph_swap_in_libcosim_is_a_file_swap(short_package, fmus, model, tmp_path):
    """The SSP's pantograph FMU replaced by another model's generic FMU, nothing else edited:
    libcosim runs that model's own start (the handshake) and statistics."""
    from pantocosim.master.thirdparty.common import swap_pantograph

    ssp = swap_pantograph(short_package / "ssp-short.ssp", fmus[model], tmp_path / "s.ssp")
    out = tmp_path / "libcosim.csv"
    stats, _ = run_recipe("libcosim", "--ssp", ssp, "--out", out)
    c = read_csv(out)
    prep, mono = monolithic(SHORT, model=model)
    ref = mono.statistics()[0]
    # the start is this model's: its monolithic static contact force, not the DSA-380's (the
    # start laws are secants: a dropper that slackens under the static force leaves the
    # settled catenary within a few newtons of the monolithic start)
    assert c["contact_force_1"][0] == pytest.approx(prep.static_forces[0], rel=0.03)
    assert stats["mean_n"] == pytest.approx(ref.mean_n, rel=2e-3)
    assert stats["std_n"] == pytest.approx(ref.std_n, rel=0.01)


@pytest.mark.slow
@pytest.mark.parametrize("master", ["libcosim", "ecos"])
def test_linear_catenary_scenario_runs_in_third_party_masters(master, tmp_path):
    """The scenario package of a linear-catenary scenario (catenary_model baked into the
    catenary FMU) in libcosim and ecos: the statistics of the monolithic linear run."""
    from pantocosim.master.ssp import write_scenario_package

    if master == "ecos":
        require_ecospy()
    scenario = ROOT / "tests" / "data" / "ssp-short-linear.toml"
    write_scenario_package(tmp_path, scenarios=[scenario], quiet=True)
    out = tmp_path / f"{master}.csv"
    stats, _ = run_recipe(master, "--ssp", tmp_path / "ssp-short-linear.ssp", "--out", out)
    _, mono = monolithic(scenario)
    ref = mono.statistics()[0]
    assert stats["mean_n"] == pytest.approx(ref.mean_n, rel=2e-3)
    assert stats["std_n"] == pytest.approx(ref.std_n, rel=0.01)
    assert stats["max_uplift_at_support_m"] == pytest.approx(ref.max_uplift_at_support_m,
                                                             rel=0.01)


@pytest.mark.slow
def test_ecos_runs_the_short_ssp(short_package, tmp_path):
    """ecos (ecospy) runs the short scenario's SSP as shipped: the monolithic statistics.
    Skipped where ecospy or its libtbb.so.12 is missing."""
    require_ecospy()
    out = tmp_path / "ecos.csv"
    stats, _ = run_recipe("ecos", "--ssp", short_package / "ssp-short.ssp", "--out", out)
    c = read_csv(out)
    assert stats["master"] == "ecos" and np.all(np.isfinite(c["contact_force_1"]))
    prep, mono = monolithic(SHORT)
    ref = mono.statistics()[0]
    assert stats["mean_n"] == pytest.approx(ref.mean_n, rel=2e-3)
    assert stats["std_n"] == pytest.approx(ref.std_n, rel=0.01)


# ------------------------------------------------------------------------- installed package
@pytest.mark.slow
def test_non_editable_install_builds_and_runs_from_any_folder(tmp_path):
    """``pip install .`` (not editable) in a fresh venv: build-fmus, a co-simulation through
    the FMUs and a recipe work from a folder outside the checkout."""
    venv = tmp_path / "venv"
    source = tmp_path / "source"           # pip builds in the source tree: a copy of it
    shutil.copytree(ROOT, source, ignore=shutil.ignore_patterns(
        ".git", ".venv", "dist", "out", "build", "*.egg-info", "__pycache__"))
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True, timeout=300)
    pip = subprocess.run([str(venv / "bin" / "python"), "-m", "pip", "install", "-q",
                          "--no-cache-dir", str(source)], capture_output=True, text=True,
                         timeout=1800)
    assert pip.returncode == 0, pip.stdout[-3000:] + pip.stderr[-3000:]
    work = tmp_path / "work"
    work.mkdir()
    scenario = work / "short.toml"
    scenario.write_text((ROOT / "tests" / "data" / "short-en50318.toml").read_text()
                        .replace("[simulation]", "[simulation]\nduration_s = 0.5"))
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}

    def run(*args):
        proc = subprocess.run([str(a) for a in args], capture_output=True, text=True,
                              cwd=work, env=env, timeout=1800)
        assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
        return proc.stdout

    cli = venv / "bin" / "pantocosim"
    run(cli, "build-fmus", "--only", "en50318-2mass", "catenary")
    assert (work / "dist" / "fmus" / "en50318-2mass.fmu").exists()
    out = run(cli, "run", scenario, "--coupling", "explicit", "--out", work / "out")
    assert (work / "out" / "summary.json").exists(), out
    out = run(venv / "bin" / "python", "-m", "pantocosim.master.thirdparty.fmpy_single",
              "--fmu", work / "dist" / "fmus" / "en50318-2mass.fmu", "--stop", 0.1)
    assert "STATISTICS" in out
    # the installed package is not the checkout
    where = run(venv / "bin" / "python", "-c", "import pantocosim; print(pantocosim.__file__)")
    assert str(ROOT) not in where

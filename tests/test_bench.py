"""``pantocosim bench`` building blocks (the full benchmark is not a test: its figures go to
docs/performance.md)."""

import tomllib

from pantocosim.master import benchmarks as bench
from pantocosim.master.scenario import load_scenario


def test_bench_scenarios_are_valid(tmp_path):
    for name, (cat, spans, pan, v, x0) in bench.CASES.items():
        path = tmp_path / f"{name}.toml"
        options = bench.CASE_OPTIONS.get(name, {})
        path.write_text(bench.scenario_text(name, cat, spans, pan, v, x0, 0.5, options))
        tomllib.loads(path.read_text())
        sc = load_scenario(str(path))
        assert sc.spans == spans and sc.duration_s == 0.5 and sc.dt == 1e-3
        assert sc.catenary_model == options.get("catenary_model", "nonlinear")
        assert sc.window_m[0] > x0 and sc.window_m[1] < x0 + v / 3.6 * 0.5


def test_floor_is_one_banded_solve():
    floor = bench.floor_per_step("en50318", 2, repeats=5)
    assert 0.0 < floor < 0.1


def test_case_filter_and_scenario_options(tmp_path):
    import pytest

    from pantocosim.core.errors import ParameterError

    assert bench.select_cases(None) == list(bench.CASES) + ["time-to-result", "fmu-start",
                                                            "native-loop", "native-dsa380"]
    assert bench.select_cases(["en50318-300", "en50318-300"]) == ["en50318-300"]
    assert bench.select_cases(["time-to-result"]) == ["time-to-result"]
    with pytest.raises(ParameterError, match="--case"):
        bench.select_cases(["nope"])
    cat, spans, pan, v, x0 = bench.CASES["en50318-300"]
    text = bench.scenario_text("x", cat, spans, pan, v, x0, 0.5,
                               simulation={"newton_rtol": 1e-6, "label": "a"})
    sim = tomllib.loads(text)["simulation"]
    assert sim["newton_rtol"] == 1e-6 and sim["label"] == "a" and sim["duration_s"] == 0.5


def test_native_loop_reads_the_c_hosts_percentiles():
    text = ("2 177.5 5.34 5.34\ncatenary doStep us: p50 212.00 p99 283.00 max 1658.00\n"
            "pantograph doStep us: p50 0.20 p99 0.86 max 19.00\n")
    assert bench._host_percentiles(text, "catenary") == {"p50_ms": 0.212, "p99_ms": 0.283,
                                                         "max_ms": 1.658}
    assert bench._host_percentiles(text, "pantograph")["max_ms"] == 0.019
    p = bench._percentiles([3e-3, 1e-3, 2e-3])
    assert p["p50_ms"] == 2.0 and p["max_ms"] == 3.0


def test_step_time_percentiles_reach_the_table():
    summary = {"step_time": {"steps": 10, "p50_ms": 1.0, "p99_ms": 2.5, "max_ms": 4.0,
                             "mean_ms": 1.2}}
    entry = {"real_time_factor": 1.2, "time_per_step_ms": 1.2, "newton_iterations_per_step": 2.0,
             "floor_ratio": 4.0, "peak_memory_mb": 100.0, "setup_s": 0.0}
    entry.update(bench.step_time_entry(summary))
    assert entry["p99_step_ms"] == 2.5 and entry["max_step_ms"] == 4.0
    line = bench.format_entry("en50318-300", "monolithic", entry)
    assert "p99  2.50" in line and "max  4.00" in line
    # a summary without step times (an older run) still prints
    assert "p99     -" in bench.format_entry("c", "explicit",
                                             {**entry, **bench.step_time_entry({})})


def test_scaling_line_reports_growth_and_modes():
    sc = {"spans": [10, 20, 40], "cost_per_simulated_s": {10: 0.4, 20: 0.8, 40: 1.7},
          "catenary_dofs": {10: 9216, 20: 18576, 40: 37296}, "modes": {10: 80, 20: 160, 40: 320},
          "growth_per_doubling": [2.0, 2.125], "growth_first_to_last": 4.25}
    line = bench.scaling_line("modal", sc)
    assert "80, 160, 320 modes" in line and "4.25x" in line and "2.00, 2.12" in line
    assert "10 -> 40 spans" in line
    # a model scaled over fewer spans (it does not fit on 40) says so
    short = {"spans": [10, 20], "cost_per_simulated_s": {10: 0.4, 20: 0.8},
             "catenary_dofs": {10: 9216, 20: 18576}, "modes": {10: 80, 20: 160},
             "growth_per_doubling": [2.0], "growth_first_to_last": 2.0}
    assert "10 -> 20 spans 2.00x" in bench.scaling_line("modal", short)
    assert bench.SCALING_SPANS_OF["modal"][-1] < bench.SCALING_SPANS[-1]


def test_a_runs_peak_memory_is_its_own_not_its_parents():
    """A run started by a large process (the bench, a campaign driver) reports its own peak
    resident memory: ru_maxrss carries the parent's across exec, VmHWM does not."""
    import subprocess
    import sys

    parent = bytearray(500 * 2**20)
    parent[::4096] = b"\1" * len(parent[::4096])            # resident, not only reserved
    code = ("import resource\nfrom pantocosim.master.run.outcome import peak_memory_mb\n"
            "print(peak_memory_mb(), resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)")
    own, inherited = map(float, subprocess.run([sys.executable, "-c", code], check=True,
                                               capture_output=True, text=True).stdout.split())
    assert inherited > 500.0                                 # the premise: ru_maxrss inherits
    assert 10.0 < own < 400.0
    del parent

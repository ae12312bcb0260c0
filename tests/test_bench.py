"""``pantocosim bench`` building blocks (the full benchmark is not a test: its figures go to
docs/performance.md)."""

import tomllib

from pantocosim.master import bench
from pantocosim.master.scenario import load_scenario


def test_bench_scenarios_are_valid(tmp_path):
    for name, (cat, spans, pan, v, x0) in bench.CASES.items():
        path = tmp_path / f"{name}.toml"
        path.write_text(bench.scenario_text(name, cat, spans, pan, v, x0, 0.5))
        tomllib.loads(path.read_text())
        sc = load_scenario(str(path))
        assert sc.spans == spans and sc.duration_s == 0.5 and sc.dt == 1e-3
        assert sc.window_m[0] > x0 and sc.window_m[1] < x0 + v / 3.6 * 0.5


def test_floor_is_one_banded_solve():
    floor = bench.floor_per_step("en50318", 2, repeats=5)
    assert 0.0 < floor < 0.1

"""EN 50318 acceptance ranges (master/validation) and ``pantocosim validate``."""

from __future__ import annotations

import copy
import json

import pytest

from pantocosim.core.errors import ParameterError
from pantocosim.core.params import load_toml
from pantocosim.master.cli import main
from pantocosim.master.validation import (DATA_DIR, QUANTITIES, compare, load_standard,
                                          markdown_table, parse_standard)

#: the statistics of the en50318 preset before its messenger support was calibrated, SI units
BEFORE = {"mean_n": 114.7, "std_n": 30.3, "stat_max_n": 205.5, "stat_min_n": 23.9,
          "max_n": 179.8, "min_n": 55.4, "max_uplift_at_support_m": 0.0363,
          "loss_of_contact_percent": 0.0}


def test_en50318_ranges_load_with_both_speeds():
    std = load_standard("en50318")
    assert [s.speed_kmh for s in std.speeds] == [250.0, 300.0]
    r250, r300 = std.at(250.0), std.at(300.0)
    assert r250.scenario == "en50318-250" and r300.scenario == "en50318-300"
    assert r250.ranges["mean"] == (110.0, 120.0) and r250.ranges["std"] == (26.0, 31.0)
    assert r250.ranges["uplift"] == (48.0, 55.0) and r300.ranges["uplift"] == (55.0, 65.0)
    assert r300.ranges["stat_min"] == (-5.0, 20.0)
    assert set(r250.ranges) == set(QUANTITIES)
    with pytest.raises(ParameterError, match="no ranges at this speed"):
        std.at(200.0)


def test_compare_flags_the_quantities_outside():
    rows = compare(load_standard("en50318").at(250.0), BEFORE)
    assert [r.key for r in rows] == list(QUANTITIES)
    uplift = rows[6]
    assert uplift.value == pytest.approx(36.3) and uplift.quantity.unit == "mm"
    assert [r.inside for r in rows] == [True] * 6 + [False, True]
    worse = dict(BEFORE, std_n=31.2, loss_of_contact_percent=0.02,
                 max_uplift_at_support_m=0.048)
    inside = {r.key: r.inside for r in compare(load_standard("en50318").at(250.0), worse)}
    assert not inside["std"] and not inside["loss_of_contact"]
    assert inside["uplift"]          # the range's ends are inside
    table = markdown_table(rows)
    assert len(table) == 2 + len(QUANTITIES)
    assert "| maximum uplift at the steady arm | 48 - 55 mm | 36.30 | **no** |" in table


@pytest.mark.parametrize("edit, field", [
    (lambda d: d["speeds"][0].update(std=[31.0, 26.0]), r"speeds\[0\]\.std"),
    (lambda d: d["speeds"][1].pop("uplift"), r"speeds\[1\]\.uplift"),
    (lambda d: d["speeds"][0].update(sigma=[1.0, 2.0]), r"speeds\[0\]\.sigma"),
    (lambda d: d["speeds"][1].update(speed_kmh=250.0), r"speeds\[1\]\.speed_kmh"),
    (lambda d: d["speeds"][0].update(mean=[110.0]), r"speeds\[0\]\.mean"),
    (lambda d: d.pop("source"), "source"),
])
def test_bad_range_files_name_the_field(edit, field):
    data = copy.deepcopy(load_toml(DATA_DIR / "en50318.toml"))
    edit(data)
    with pytest.raises(ParameterError, match=field):
        parse_standard(data, "bad.toml", "bad")


@pytest.mark.parametrize("argv, text", [
    (["validate", "no-such"], "unknown (known: en50318)"),
    (["validate", "--speed", "200"], "no ranges at this speed"),
])
def test_validate_user_errors_exit_2_with_one_line(argv, text, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert text in err and len(err.splitlines()) == 1


def test_validate_out_must_be_a_folder(tmp_path, capsys):
    f = tmp_path / "file"
    f.write_text("x")
    assert main(["validate", "--out", str(f)]) == 2
    assert "exists and is not a folder" in capsys.readouterr().err


@pytest.mark.slow
def test_validate_en50318_at_250_kmh_is_inside_every_range(tmp_path, capsys):
    """The reference pantograph on the reference catenary at 250 km/h (a full run, about
    30 s): every EN 50318 quantity inside its range."""
    assert main(["validate", "en50318", "--speed", "250", "--out", str(tmp_path),
                 "--quiet"]) == 0
    printed = capsys.readouterr().out
    data = json.loads((tmp_path / "validation.json").read_text())
    (speed,) = data["speeds"]
    assert speed["speed_kmh"] == 250.0 and speed["all_inside"]
    assert [r["quantity"] for r in speed["rows"]] == list(QUANTITIES)
    summary = json.loads((tmp_path / "en50318-250" / "summary.json").read_text())
    stats = summary["statistics"]
    for row in speed["rows"]:
        q = QUANTITIES[row["quantity"]]
        assert row["value"] == pytest.approx(q.scale * stats[q.field])
        assert row["low"] <= row["value"] <= row["high"]
    assert summary["analysis_window_m"] == [240.0, 360.0]
    assert "8 of 8 inside" in printed
    assert "| mean contact force | 110 - 120 N |" in (tmp_path / "validation.md").read_text()

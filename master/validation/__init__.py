"""Acceptance ranges of a validation standard and the comparison of a run's statistics with
them (``pantocosim validate``).

A standard is a TOML file in this folder (``en50318.toml``): ``standard``, ``description``,
``source`` and one ``[[speeds]]`` table per speed with ``speed_kmh``, ``scenario`` (the
scenario preset that runs it) and a ``[low, high]`` range for each quantity of
:data:`QUANTITIES`, in the quantity's display unit. Loading validates every field
(:class:`ParameterError` naming file, field and value).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from pantocosim.core.errors import ParameterError
from pantocosim.core.params import Table, load_toml

DATA_DIR = Path(__file__).resolve().parent


@dataclass(frozen=True)
class Quantity:
    label: str
    field: str          # ContactStatistics field (SI)
    unit: str           # display unit of the ranges
    scale: float = 1.0  # display value = scale * SI value


#: range key -> quantity, in the order of the tables (EN 50317 / EN 50318 statistics)
QUANTITIES = {
    "mean": Quantity("mean contact force", "mean_n", "N"),
    "std": Quantity("standard deviation", "std_n", "N"),
    "stat_max": Quantity("statistical maximum (mean + 3 sigma)", "stat_max_n", "N"),
    "stat_min": Quantity("statistical minimum (mean - 3 sigma)", "stat_min_n", "N"),
    "max": Quantity("actual maximum", "max_n", "N"),
    "min": Quantity("actual minimum", "min_n", "N"),
    "uplift": Quantity("maximum uplift at the steady arm", "max_uplift_at_support_m", "mm",
                       1000.0),
    "loss_of_contact": Quantity("loss of contact", "loss_of_contact_percent", "%"),
}


@dataclass(frozen=True)
class SpeedRanges:
    speed_kmh: float
    scenario: str
    ranges: dict            # quantity key -> (low, high) in display units


@dataclass(frozen=True)
class Standard:
    name: str
    standard: str
    description: str
    source: str
    speeds: tuple[SpeedRanges, ...]

    def at(self, speed_kmh: float) -> SpeedRanges:
        for s in self.speeds:
            if s.speed_kmh == speed_kmh:
                return s
        raise ParameterError("--speed", speed_kmh, "no ranges at this speed (known: "
                             + ", ".join(f"{s.speed_kmh:g}" for s in self.speeds) + " km/h)")


@dataclass(frozen=True)
class Row:
    key: str
    quantity: Quantity
    low: float
    high: float
    value: float            # display unit

    @property
    def inside(self) -> bool:
        return self.low <= self.value <= self.high


def standard_names() -> list[str]:
    return sorted(p.stem for p in DATA_DIR.glob("*.toml"))


def parse_standard(data: dict, source: str, name: str) -> Standard:
    """Validate a parsed standard file."""
    t = Table(data, source)
    t.unknown_keys(["standard", "description", "source", "speeds"])
    raw = t._get("speeds", None, True)
    if not isinstance(raw, list) or not raw:
        raise ParameterError("speeds", raw, "must be a non-empty array of tables", source)
    speeds = []
    for i, item in enumerate(raw):
        s = Table(item, source, f"speeds[{i}]")
        s.unknown_keys(["speed_kmh", "scenario", *QUANTITIES])
        ranges = {}
        for key in QUANTITIES:
            low, high = s.numbers(key, length=2)
            if low > high:
                raise ParameterError(f"speeds[{i}].{key}", [low, high], "low must not exceed "
                                     "high", source)
            ranges[key] = (low, high)
        speed = s.number("speed_kmh", positive=True)
        if any(p.speed_kmh == speed for p in speeds):
            raise ParameterError(f"speeds[{i}].speed_kmh", speed, "given twice", source)
        speeds.append(SpeedRanges(speed, s.string("scenario"), ranges))
    return Standard(name=name, standard=t.string("standard"),
                    description=t.string("description", ""), source=t.string("source"),
                    speeds=tuple(speeds))


def load_standard(name: str) -> Standard:
    """The acceptance ranges of a standard by name (``en50318``)."""
    path = DATA_DIR / f"{name}.toml"
    if not path.exists():
        raise ParameterError("standard", name, f"unknown (known: {', '.join(standard_names())})")
    return parse_standard(load_toml(path), path.name, name)


def compare(ranges: SpeedRanges, statistics: dict) -> list[Row]:
    """One row per quantity: its range and the run's value (``statistics``: the
    ContactStatistics dict of a run, SI units)."""
    return [Row(key, q, *ranges.ranges[key], q.scale * float(statistics[q.field]))
            for key, q in QUANTITIES.items()]


def markdown_table(rows: list[Row]) -> list[str]:
    lines = ["| quantity | range | ours | inside |", "|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r.quantity.label} | {r.low:g} - {r.high:g} {r.quantity.unit} | "
                     f"{r.value:.2f} | {'yes' if r.inside else '**no**'} |")
    return lines

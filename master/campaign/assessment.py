"""EN 50367 / TSI assessment of contact-force statistics, with criteria from a data file.

The criteria file (``campaign/en50367.toml``, commented) lists checks of one statistic each;
the kinds (band, max, min, ratio_max, report) are the classes below, registered in ``KINDS``.
``assess(criteria, stats, speed_kmh)`` returns one column per criterion: True/False for a
check (None when the run has no statistics or the criterion does not apply at that speed),
the reported value for ``report``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

from pantocosim.core.errors import ParameterError
from pantocosim.core.params import Table, load_toml

CRITERIA_DIR = Path(__file__).resolve().parent
STATISTICS = ("mean_n", "std_n", "stat_max_n", "stat_min_n", "max_n", "min_n",
              "loss_of_contact_percent", "max_uplift_at_support_m")


class Criterion:
    """A check of one statistic; subclasses read their own fields of the table."""

    def __init__(self, t: Table):
        self.name = t.string("name")
        self.title = t.string("title", self.name)
        self.quantity = t.string("quantity", choices=STATISTICS)
        self.source = t.string("source")
        self.verified = t.boolean("verified")
        self.min_speed_kmh = (t.number("min_speed_kmh", nonnegative=True)
                              if t.has("min_speed_kmh") else None)

    fields: tuple = ()
    checks = True

    def evaluate(self, stats: dict, speed_kmh: float):
        if self.min_speed_kmh is not None and speed_kmh < self.min_speed_kmh:
            return None
        x = stats.get(self.quantity)
        if x is None or (isinstance(x, float) and math.isnan(x)):
            return None
        return self.check(float(x), stats, speed_kmh)

    def check(self, x, stats, v):  # pragma: no cover - abstract
        raise NotImplementedError


@dataclass
class Polynomial:
    c0: float = 0.0
    c1: float = 0.0
    c2: float = 0.0

    def __call__(self, v):
        return self.c0 + self.c1 * v + self.c2 * v * v

    @classmethod
    def from_table(cls, t: Table) -> "Polynomial":
        t.unknown_keys({"c0", "c1", "c2"})
        return cls(t.number("c0", 0.0), t.number("c1", 0.0), t.number("c2", 0.0))


class Band(Criterion):
    fields = ("lower", "upper")

    def __init__(self, t):
        super().__init__(t)
        self.lower = Polynomial.from_table(t.sub("lower"))
        self.upper = Polynomial.from_table(t.sub("upper"))

    def check(self, x, stats, v):
        return self.lower(v) <= x <= self.upper(v)


class Max(Criterion):
    fields = ("limit", "strict")

    def __init__(self, t):
        super().__init__(t)
        self.limit = t.number("limit")
        self.strict = t.boolean("strict", False)

    def check(self, x, stats, v):
        return x < self.limit if self.strict else x <= self.limit


class Min(Max):
    def check(self, x, stats, v):
        return x > self.limit if self.strict else x >= self.limit


class RatioMax(Criterion):
    fields = ("reference", "factor")

    def __init__(self, t):
        super().__init__(t)
        self.reference = t.string("reference", choices=STATISTICS)
        self.factor = t.number("factor", positive=True)

    def check(self, x, stats, v):
        ref = stats.get(self.reference)
        return None if ref is None else x <= self.factor * float(ref)


class Report(Criterion):
    fields = ("factor",)
    checks = False

    def __init__(self, t):
        super().__init__(t)
        self.factor = t.number("factor", 1.0, positive=True)

    def check(self, x, stats, v):
        return self.factor * x


KINDS = {"band": Band, "max": Max, "min": Min, "ratio_max": RatioMax, "report": Report}
COMMON = {"name", "title", "kind", "quantity", "source", "verified", "min_speed_kmh"}


@dataclass
class Criteria:
    name: str
    description: str
    source: str
    items: list

    @property
    def checks(self) -> list:
        return [c for c in self.items if c.checks]


def criteria_path(name_or_path: str, base: Path | None = None) -> Path:
    for cand in ([base / name_or_path] if base else []) + [Path(name_or_path),
                                                           CRITERIA_DIR / f"{name_or_path}.toml"]:
        if cand.is_file():
            return cand
    presets = sorted(p.stem for p in CRITERIA_DIR.glob("*.toml"))
    raise ParameterError("criteria", name_or_path,
                         f"unknown criteria (presets: {', '.join(presets)}) and no such file")


def load_criteria(name_or_path: str = "en50367", base: Path | None = None) -> Criteria:
    path = criteria_path(name_or_path, base)
    source = str(path)
    t = Table(load_toml(path), source)
    t.unknown_keys({"name", "description", "criteria"})
    raw = t._get("criteria", None, True)
    if not isinstance(raw, list) or not raw:
        raise ParameterError("criteria", raw, "must be a non-empty array of tables", source)
    items, names = [], set()
    for i, entry in enumerate(raw):
        ct = Table(entry, source, f"criteria[{i}]")
        kind = ct.string("kind", choices=KINDS)
        cls = KINDS[kind]
        ct.unknown_keys(COMMON | set(cls.fields))
        c = cls(ct)
        if c.name in names or c.name in STATISTICS:
            raise ParameterError(f"criteria[{i}].name", c.name, "must be unique and not the "
                                 "name of a statistic", source)
        names.add(c.name)
        items.append(c)
    return Criteria(t.string("name", path.stem), t.string("description", ""), source, items)


def assess(criteria: Criteria, stats: dict | None, speed_kmh: float) -> dict:
    """One column per criterion plus ``assessment``: "pass" when every applicable check
    passes, "fail" when one fails, "n/a" without statistics."""
    out = {c.name: (None if stats is None else c.evaluate(stats, speed_kmh))
           for c in criteria.items}
    verdicts = [out[c.name] for c in criteria.checks if out[c.name] is not None]
    if stats is None:
        out["assessment"] = "n/a"
    else:
        out["assessment"] = "pass" if all(verdicts) else "fail"
    return out

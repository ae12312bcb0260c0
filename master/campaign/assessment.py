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
from pantocosim.core.schema import OPTIONAL, Field, Format, Section

CRITERIA_DIR = Path(__file__).resolve().parent
STATISTICS = ("mean_n", "std_n", "stat_max_n", "stat_min_n", "max_n", "min_n",
              "loss_of_contact_percent", "max_uplift_at_support_m")


#: the fields every criterion has (``[[criteria]]``)
CRITERION = Section("criteria", [
    Field("name", "string", doc="column name in the results table",
          rule="unique, not the name of a statistic"),
    Field("kind", "string", choices=("band", "max", "min", "ratio_max", "report"),
          doc="what is checked (the fields of each kind below)"),
    Field("title", "string", default=OPTIONAL, doc="label in the report (default: name)"),
    Field("quantity", "string", choices=STATISTICS, doc="the statistic checked"),
    Field("source", "string", doc="where the criterion comes from (clause of the standard)"),
    Field("verified", "boolean", doc="whether the value was checked against the standard's "
          "text"),
    Field("min_speed_kmh", unit="km/h", default=OPTIONAL, nonnegative=True,
          doc="applies from this speed on"),
], array=True, doc="One `[[criteria]]` table per check (at least one).")
#: a ``band`` criterion's ``lower`` and ``upper`` tables
POLYNOMIAL = Section("criteria.lower", [
    Field("c0", unit="N", default=0.0, doc="constant term"),
    Field("c1", unit="N h/km", default=0.0, doc="times v [km/h]"),
    Field("c2", unit="N h^2/km^2", default=0.0, doc="times v^2"),
], title="`lower`, `upper` of a band", doc="A polynomial of the speed: "
         "c0 + c1 v + c2 v^2, v in km/h.")


class Criterion:
    """A check of one statistic; subclasses read their own fields of the table."""

    def __init__(self, t: Table):
        self.name = CRITERION.read(t, "name")
        title = CRITERION.read(t, "title")
        self.title = self.name if title is None else title
        self.quantity = CRITERION.read(t, "quantity")
        self.source = CRITERION.read(t, "source")
        self.verified = CRITERION.read(t, "verified")
        self.min_speed_kmh = CRITERION.read(t, "min_speed_kmh")

    #: the kind's own fields (a Section)
    FIELDS = Section("criteria", [])

    @classmethod
    def field_names(cls) -> set:
        return set(cls.FIELDS.names)
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
        POLYNOMIAL.check_keys(t)
        return cls(*(f.read(t) for f in POLYNOMIAL.fields))


class Band(Criterion):
    """`quantity` between two polynomials of the speed."""

    FIELDS = Section("criteria", [
        Field("lower", "table", doc="lower bound (polynomial)"),
        Field("upper", "table", doc="upper bound (polynomial)")])

    def __init__(self, t):
        super().__init__(t)
        self.lower = Polynomial.from_table(t.sub("lower"))
        self.upper = Polynomial.from_table(t.sub("upper"))

    def check(self, x, stats, v):
        return self.lower(v) <= x <= self.upper(v)


class Max(Criterion):
    """`quantity` at most `limit`."""

    FIELDS = Section("criteria", [
        Field("limit", doc="the limit, in the quantity's unit"),
        Field("strict", "boolean", default=False, doc="the limit itself fails")])

    def __init__(self, t):
        super().__init__(t)
        self.limit = self.FIELDS.read(t, "limit")
        self.strict = self.FIELDS.read(t, "strict")

    def check(self, x, stats, v):
        return x < self.limit if self.strict else x <= self.limit


class Min(Max):
    """`quantity` at least `limit`."""

    def check(self, x, stats, v):
        return x > self.limit if self.strict else x >= self.limit


class RatioMax(Criterion):
    """`quantity` at most `factor` times the statistic `reference`."""

    FIELDS = Section("criteria", [
        Field("reference", "string", choices=STATISTICS, doc="the reference statistic"),
        Field("factor", positive=True, doc="the factor")])

    def __init__(self, t):
        super().__init__(t)
        self.reference = self.FIELDS.read(t, "reference")
        self.factor = self.FIELDS.read(t, "factor")

    def check(self, x, stats, v):
        ref = stats.get(self.reference)
        return None if ref is None else x <= self.factor * float(ref)


class Report(Criterion):
    """No check: `factor` times `quantity` is reported as a column."""

    FIELDS = Section("criteria", [
        Field("factor", default=1.0, positive=True, doc="scale of the reported value")])
    checks = False

    def __init__(self, t):
        super().__init__(t)
        self.factor = self.FIELDS.read(t, "factor")

    def check(self, x, stats, v):
        return self.factor * x


KINDS = {"band": Band, "max": Max, "min": Min, "ratio_max": RatioMax, "report": Report}
assert tuple(KINDS) == CRITERION["kind"].choices
ROOT = Section("", [
    Field("name", "string", default=OPTIONAL, doc="name (default: the file's name)"),
    Field("description", "string", default="", doc="free text"),
], extra=("criteria",))
FORMAT = Format("criteria", "Criteria files", """\
A criteria file lists the checks of the contact-force statistics that a campaign assesses
(`criteria` of a sweep file; `pantocosim report --criteria FILE`). The preset `en50367`
(`master/campaign/en50367.toml`, commented) holds the EN 50367 / TSI checks with their sources
and whether each was verified against the standard's text. A case passes when every check
that applies at its speed passes.
""", (ROOT, CRITERION, *(Section("criteria", cls.FIELDS.fields, title=f'`kind = "{kind}"`',
                                  doc=cls.__doc__ or "") for kind, cls in KINDS.items()),
      POLYNOMIAL))


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
    ROOT.check_keys(t)
    raw = t._get("criteria", None, True)
    if not isinstance(raw, list) or not raw:
        raise ParameterError("criteria", raw, "must be a non-empty array of tables", source)
    items, names = [], set()
    for i, entry in enumerate(raw):
        ct = Table(entry, source, f"criteria[{i}]")
        kind = CRITERION.read(ct, "kind")
        cls = KINDS[kind]
        ct.unknown_keys(set(CRITERION.names) | cls.field_names())
        c = cls(ct)
        if c.name in names or c.name in STATISTICS:
            raise ParameterError(f"criteria[{i}].name", c.name, "must be unique and not the "
                                 "name of a statistic", source)
        names.add(c.name)
        items.append(c)
    name = ROOT.read(t, "name")
    return Criteria(path.stem if name is None else name, ROOT.read(t, "description"), source,
                    items)


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

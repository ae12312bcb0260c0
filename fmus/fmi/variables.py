"""Declared FMU variables: one table per FMU kind (:mod:`.catenary_ports`,
:mod:`.pantograph_ports`) from which the slave registers its variables, the master takes its
port names, the SSP writer its connectors and the documentation its FMU reference page.

A row is a :class:`Variable` (name, causality, type, unit, start, range, meaning); the rows
of one pantograph (``_k``) or one support (``_j``) are an :class:`Each` group, expanded index
by index. A :class:`Range` is both the accepted values the reference shows and the check the
slave applies (:meth:`Variable.checked`); a range the model checks (the HHT parameter, the
penalty law) is a :class:`Described` one, shown but checked by the model.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Iterator

from pantocosim.core.errors import ParameterError

#: most integration steps in one communication step (every FMU's ``n_substeps``): a doStep
#: answers in bounded time
MAX_SUBSTEPS = 10_000

CAUSALITIES = ("parameter", "input", "output", "local")
TYPES = ("Real", "Integer", "Boolean", "String")


# ---------------------------------------------------------------------- ranges
class Range:
    """Accepted values of a variable: :meth:`text` for the reference, :meth:`check` for
    the slave (raises ParameterError naming the variable)."""

    def text(self) -> str:
        return ""

    def check(self, name: str, value) -> None:
        """Accept everything (a range the model checks)."""


@dataclass(frozen=True)
class Described(Range):
    """Accepted values the model checks (its own message); shown in the reference only."""

    what: str

    def text(self) -> str:
        return self.what


@dataclass(frozen=True)
class Choices(Range):
    """One of the integer codes, each with its meaning."""

    codes: dict

    def text(self) -> str:
        return ", ".join(f"{c} = {m}" for c, m in self.codes.items())

    def check(self, name, value):
        if value not in self.codes:
            raise ParameterError(name, value, "must be " + ", ".join(
                f"{c} ({m})" for c, m in self.codes.items()))


@dataclass(frozen=True)
class Interval(Range):
    """lo <= value <= hi (either bound may be None: open); ``note`` says what a bound value
    means (``0 = as defined``)."""

    lo: float | None = None
    hi: float | None = None
    note: str = ""

    def text(self) -> str:
        if self.lo is not None and self.hi is not None:
            out = f"{self.lo:g} .. {self.hi:g}"
        elif self.lo is not None:
            out = f">= {self.lo:g}"
        else:
            out = f"<= {self.hi:g}"
        return f"{out} ({self.note})" if self.note else out

    def check(self, name, value):
        if (self.lo is not None and not value >= self.lo) or (
                self.hi is not None and not value <= self.hi):
            raise ParameterError(name, value, f"must be {self.text()}")


@dataclass(frozen=True)
class Positive(Range):
    """value > 0."""

    def text(self) -> str:
        return "> 0"

    def check(self, name, value):
        if not value > 0:
            raise ParameterError(name, value, "must be > 0")


ANY = Range()


# ---------------------------------------------------------------------- rows
@dataclass(frozen=True)
class Variable:
    """One declared variable. In an :class:`Each` group, ``name`` and ``meaning`` hold the
    group's index (``{k}``, ``{j}``). ``start`` is a value or, for a start that depends on
    the FMU's model (a pantograph preset's defaults), a function of that context."""

    name: str
    causality: str
    type: str
    unit: str | None
    start: Any
    meaning: str
    range: Range = ANY
    #: a Real parameter a master may change after initialisation (none today)
    tunable: bool = False

    def __post_init__(self):
        if self.causality not in CAUSALITIES or self.type not in TYPES:
            raise ValueError(f"variable {self.name}: causality {self.causality!r}, type "
                             f"{self.type!r}")

    def start_value(self, context=None):
        return self.start(context) if callable(self.start) else self.start

    def checked(self, value):
        """``value`` if it lies in the range, else ParameterError naming the variable."""
        self.range.check(self.name, value)
        return value

    def indexed(self, **index) -> "Variable":
        """The row of one index of its group (``name_1``, its meaning for pantograph 1)."""
        return Variable(self.name.format(**index), self.causality, self.type, self.unit,
                        self.start, self.meaning.format(**index), self.range, self.tunable)


def real(name: str, causality: str, unit: str | None, start, meaning: str,
         range_: Range = ANY) -> Variable:
    """A Real variable's row."""
    return Variable(name, causality, "Real", unit, start, meaning, range_)


def parameter(kind: str, name: str, start, meaning: str, range_: Range = ANY) -> Variable:
    """The row of an Integer, Boolean or String parameter (they have no unit)."""
    return Variable(name, "parameter", kind, None, start, meaning, range_)


@dataclass(frozen=True)
class Each:
    """Rows repeated for every value of an index: ``index`` the placeholder (``k``, ``j``),
    ``values`` its values; the rows of one value come together, in order."""

    index: str
    values: range
    rows: tuple

    def expand(self) -> Iterator[Variable]:
        for i in self.values:
            for row in self.rows:
                yield row.indexed(**{self.index: i})


@dataclass(frozen=True)
class VariableTable:
    """The variables of one kind of FMU, in the order the FMU registers them."""

    entries: tuple
    _rows: dict = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        rows = {}
        for e in self.entries:
            for row in (e.rows if isinstance(e, Each) else (e,)):
                rows[row.name] = row
        rows.update((v.name, v) for v in self)
        object.__setattr__(self, "_rows", rows)

    def __iter__(self) -> Iterator[Variable]:
        """Every variable, indexed groups expanded (the FMU's variables, in order)."""
        for e in self.entries:
            yield from (e.expand() if isinstance(e, Each) else (e,))

    def __getitem__(self, name: str) -> Variable:
        """The variable ``name`` (``wire_height_1``), or the row declared as ``name``
        (``wire_height_{k}``: a group's row)."""
        return self._rows[name]

    def names(self, name: str, values) -> tuple[str, ...]:
        """The variable names of the row ``name`` of a group for the index ``values``
        (``names("wire_height_{k}", range(1, 3))`` -> wire_height_1, wire_height_2)."""
        row = self[name]
        index = next(e.index for e in self.entries if isinstance(e, Each) and row in e.rows)
        return tuple(name.format(**{index: i}) for i in values)

    def of(self, causality: str) -> tuple[Variable, ...]:
        return tuple(v for v in self if v.causality == causality)


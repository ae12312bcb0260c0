"""Declared fields of the TOML data files: each field is written once.

A data-file format is a list of :class:`Section` objects (one TOML table each, e.g.
``[simulation]``), each holding :class:`Field` objects: name, kind, unit, default, accepted
range and a one-line meaning. The loaders read every field through its declaration
(``SIMULATION.read(table, "dt")``), so the checks, their error messages (those of
:class:`~pantocosim.core.params.Table`) and the reference pages of the documentation, which are
generated from the same declarations, cannot disagree. Rules between fields (a window inside
the line, a stitch wire shorter than a span) stay in the loaders' code; their text is
declared with the field as ``rule``.

Only the standard library is used, so the declarations travel inside the FMUs with the loaders.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any, Iterable

from .params import Table


class _Required:
    def __repr__(self) -> str:  # pragma: no cover
        return "REQUIRED"


class _Optional:
    def __repr__(self) -> str:  # pragma: no cover
        return "OPTIONAL"


#: default of a field that must be given
REQUIRED: Any = _Required()
#: default of a field that may be left out (read as None)
OPTIONAL: Any = _Optional()

#: kinds of field and what the reference calls them
KINDS = {"number": "number", "integer": "integer", "string": "string", "boolean": "boolean",
         "numbers": "array of numbers", "integers": "array of integers", "table": "table", "tables": "array of tables",
         "file": "preset name or file", "any": "see meaning"}


@dataclass(frozen=True)
class Field:
    """One field of a data-file table."""

    name: str
    kind: str = "number"
    unit: str = ""
    default: Any = REQUIRED
    doc: str = ""
    positive: bool = False
    nonnegative: bool = False
    minimum: float | None = None
    maximum: float | None = None
    choices: tuple | None = None
    length: int | None = None
    increasing: bool = False
    #: a condition the loader checks in code, in words (cross-field rules)
    rule: str = ""

    @property
    def required(self) -> bool:
        return self.default is REQUIRED

    def read(self, table: Table, required: bool = False) -> Any:
        """The field's value in ``table``, checked (errors name file, field and value);
        ``required``: the field must be there whatever its default (one of two ways of
        giving a value was chosen)."""
        if required:
            return replace(self, default=REQUIRED).read(table)
        if self.default is OPTIONAL:
            if not table.has(self.name):
                return None
            default = None
        else:
            default = None if self.default is REQUIRED else self.default
        kind = self.kind
        if kind == "number":
            return table.number(self.name, default, positive=self.positive,
                                nonnegative=self.nonnegative, minimum=self.minimum,
                                maximum=self.maximum)
        if kind == "integer":
            return table.integer(self.name, default, minimum=self.minimum)
        if kind in ("string", "file"):
            return table.string(self.name, default, choices=self.choices)
        if kind == "boolean":
            return table.boolean(self.name, default)
        if kind == "numbers":
            return table.numbers(self.name, default, length=self.length,
                                 positive=self.positive, nonnegative=self.nonnegative,
                                 increasing=self.increasing)
        raise TypeError(f"field {self.name}: kind {kind!r} is read by its loader")

    # ----------------------------------------------------------------- reference text
    def default_text(self) -> str:
        if self.default is REQUIRED:
            return "required"
        if self.default is OPTIONAL:
            return "optional"
        if isinstance(self.default, bool):
            return "true" if self.default else "false"
        if isinstance(self.default, str):
            return f'"{self.default}"'
        if isinstance(self.default, (list, tuple)):
            return "[" + ", ".join(f"{x:g}" if isinstance(x, float) else repr(x)
                                   for x in self.default) + "]"
        if isinstance(self.default, float):
            return f"{self.default:g}"
        return str(self.default)

    def accepted(self) -> str:
        """The accepted values in words, from the same attributes the check uses."""
        parts = []
        if self.choices is not None:
            parts.append("one of " + ", ".join(f'"{c}"' for c in self.choices))
        if self.length is not None:
            parts.append(f"{self.length} entries")
        each = "each " if self.kind == "numbers" else ""
        if self.positive:
            parts.append(f"{each}> 0")
        if self.nonnegative:
            parts.append(f"{each}>= 0")
        if self.minimum is not None and self.maximum is not None:
            parts.append(f"{self.minimum:g} to {self.maximum:g}")
        elif self.minimum is not None:
            parts.append(f">= {self.minimum:g}")
        elif self.maximum is not None:
            parts.append(f"<= {self.maximum:g}")
        if self.increasing:
            parts.append("strictly increasing")
        if self.rule:
            parts.append(self.rule)
        return "; ".join(parts) if parts else "any"


class Section:
    """The declared fields of one TOML table (``path`` as it appears in a file, "" = root)."""

    def __init__(self, path: str, fields: Iterable[Field], doc: str = "",
                 extra: Iterable[str] = (), array: bool = False, title: str = ""):
        self.path = path
        #: heading of the section in the reference (default: the table's name)
        self.title = title
        #: an array of tables (``[[path]]``)
        self.array = array
        self.fields = tuple(fields)
        self.doc = doc
        #: keys accepted but read elsewhere (sub-tables documented as sections of their own)
        self.extra = tuple(extra)
        self._by_name = {f.name: f for f in self.fields}

    @property
    def names(self) -> list[str]:
        return [f.name for f in self.fields] + list(self.extra)

    def __getitem__(self, name: str) -> Field:
        return self._by_name[name]

    def check_keys(self, table: Table) -> None:
        """Reject keys of ``table`` that are not declared (catches typos)."""
        table.unknown_keys(self.names)

    def read(self, table: Table, name: str, required: bool = False) -> Any:
        return self._by_name[name].read(table, required)


@dataclass(frozen=True)
class Format:
    """A data-file format: its sections in the order a reference lists them."""

    name: str
    title: str
    doc: str
    sections: tuple


def markdown(fmt: Format) -> str:
    """The reference page of a format: one table of fields per section."""
    out = [f"# {fmt.title}\n", fmt.doc.strip() + "\n"]
    for sec in fmt.sections:
        head = sec.title or (("`[[{}]]`" if sec.array else "`[{}]`").format(sec.path)
                             if sec.path else "Top level")
        out.append(f"\n## {head}\n")
        if sec.doc:
            out.append(sec.doc.strip() + "\n")
        if not sec.fields:
            out.append("\nNo other fields.\n" if sec.extra else "")
            continue
        out.append("\n| field | type | unit | default | accepted | meaning |\n"
                   "|---|---|---|---|---|---|\n")
        for f in sec.fields:
            cells = [f"`{f.name}`", KINDS.get(f.kind, f.kind), f.unit or "-",
                     f.default_text(), f.accepted(), f.doc]
            out.append("| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |\n")
    return "".join(out)

"""The one registry idiom: entries by name, each with an explicit, stable integer code where a
file or an FMU parameter stores the choice as a number.

A registry is a read-only mapping name -> entry (a class, a factory, a module name) filled by
``add`` or the decorator ``register``; ``entry(name)`` refuses an unknown name with a
:class:`~.errors.ParameterError` listing the known ones, ``code``/``name_of`` translate
between names and codes. A code is given once, by hand, and never reused: an FMU built today
keeps its meaning when an entry is added (tests/test_registry.py holds today's codes).
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from typing import Any

from .errors import ParameterError


class Registry(Mapping):
    """Entries of one kind by name, optionally coded (module docstring). ``field`` names the
    setting that chooses an entry, in errors."""

    def __init__(self, kind: str, field: str | None = None, coded: bool = False):
        self.kind, self.field, self.coded = kind, field or kind, coded
        self._entries: dict[str, Any] = {}
        self._codes: dict[str, int] = {}

    def add(self, name: str, entry, code: int | None = None):
        """Register ``entry`` under ``name`` (and ``code`` in a coded registry); returns it.
        A name or code given twice to different entries is a programming error."""
        if (code is None) == self.coded:
            raise ValueError(f"{self.kind} {name!r}: a code is "
                             f"{'required' if self.coded else 'not used'} here")
        old = self._entries.get(name)
        if old is not None and _qualname(old) != _qualname(entry):
            raise ValueError(f"{self.kind} {name!r} registered twice")
        if code is not None:
            taken = {c: n for n, c in self._codes.items()}.get(code)
            if taken not in (None, name):
                raise ValueError(f"{self.kind} code {code} taken by {taken!r}")
            self._codes[name] = int(code)
        self._entries[name] = entry
        return entry

    def register(self, name: str, code: int | None = None):
        """Decorator: ``add(name, obj, code)``."""
        return lambda obj: self.add(name, obj, code)

    def entry(self, name: str):
        """The entry called ``name``; a ParameterError naming the known ones otherwise."""
        if name not in self._entries:
            raise ParameterError(self.field, name,
                                 f"must be one of {', '.join(map(str, self))}")
        return self._entries[name]

    def code(self, name: str) -> int:
        """The stable code of ``name``."""
        self.entry(name)
        return self._codes[name]

    def name_of(self, code) -> str:
        """The name whose code is ``code``; a ParameterError listing the codes otherwise."""
        for name, c in self._codes.items():
            if c == code:
                return name
        raise ParameterError(self.field, code, "must be " + ", ".join(
            f"{c} ({n})" for n, c in self._codes.items()))

    def codes(self) -> dict[str, int]:
        """name -> code, in code order."""
        return dict(sorted(self._codes.items(), key=lambda item: item[1]))

    @contextmanager
    def swapped(self, name: str, entry):
        """Within the block, ``name`` stands for ``entry`` (a study timing or wrapping an
        entry); the registered one is back after it."""
        old = self._entries[name]
        self._entries[name] = entry
        try:
            yield
        finally:
            self._entries[name] = old

    def copy(self) -> "Registry":
        new = Registry(self.kind, self.field, self.coded)
        new._entries, new._codes = dict(self._entries), dict(self._codes)
        return new

    def __getitem__(self, name: str):
        return self._entries[name]

    def __iter__(self) -> Iterator[str]:
        return iter(self._entries)

    def __len__(self) -> int:
        return len(self._entries)

    def __repr__(self) -> str:
        return f"Registry({self.kind!r}: {', '.join(map(str, self))})"


def _qualname(obj) -> tuple:
    """What identifies an entry across a module reload: its module and qualified name."""
    return (getattr(obj, "__module__", None), getattr(obj, "__qualname__", repr(obj)))

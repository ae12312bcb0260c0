"""Loading and validating the project's TOML data files (parameter sets, catenaries, scenarios).

Errors name the file, the dotted field and the bad value (:class:`ParameterError`). Only the
standard library and numpy are used, so the same code validates parameter files inside an FMU.
"""

from __future__ import annotations

import math
import tomllib
from pathlib import Path
from typing import Any, Iterable

import numpy as np

from .errors import ParameterError


def load_toml(path: str | Path) -> dict:
    """Read a TOML file; syntax errors and missing files become :class:`ParameterError`."""
    p = Path(path)
    try:
        with open(p, "rb") as fh:
            return tomllib.load(fh)
    except FileNotFoundError:
        raise ParameterError("file", str(p), "no such file") from None
    except IsADirectoryError:
        raise ParameterError("file", str(p), "is a folder, not a TOML file") from None
    except UnicodeDecodeError as exc:
        raise ParameterError("file", str(p), f"not a text (UTF-8) TOML file: byte "
                             f"0x{exc.object[exc.start]:02x} at offset {exc.start}") from None
    except tomllib.TOMLDecodeError as exc:
        raise ParameterError("file", str(p), f"invalid TOML: {exc}") from None
    except OSError as exc:
        raise ParameterError("file", str(p), f"cannot be read: {exc.strerror}") from None


class Table:
    """A view of one TOML table that reads typed, checked fields.

    ``Table(data, source="dsa380.toml").number("bars.m1", positive=True)`` returns a float or
    raises ``ParameterError("bars.m1", value, "must be > 0", "dsa380.toml")``.
    """

    def __init__(self, data: dict, source: str | None = None, prefix: str = ""):
        if not isinstance(data, dict):
            raise ParameterError(prefix or "<root>", data, "must be a table", source)
        self.data = data
        self.source = source
        self.prefix = prefix

    def _name(self, key: str) -> str:
        return f"{self.prefix}.{key}" if self.prefix else key

    def _get(self, key: str, default: Any, required: bool):
        node: Any = self.data
        parts = key.split(".")
        for i, part in enumerate(parts):
            if not isinstance(node, dict) or part not in node:
                if required and default is _MISSING:
                    raise ParameterError(self._name(key), None, "missing field", self.source)
                return default
            node = node[part]
        return node

    def has(self, key: str) -> bool:
        return self._get(key, _MISSING, required=False) is not _MISSING

    def sub(self, key: str, required: bool = True) -> "Table":
        value = self._get(key, {} if not required else _MISSING, required)
        return Table(value, self.source, self._name(key))

    def number(self, key: str, default: Any = None, *, positive: bool = False,
               nonnegative: bool = False, minimum: float | None = None,
               maximum: float | None = None) -> float:
        required = default is None
        value = self._get(key, _MISSING if required else default, required)
        return check_number(self._name(key), value, source=self.source, positive=positive,
                            nonnegative=nonnegative, minimum=minimum, maximum=maximum)

    def integer(self, key: str, default: Any = None, *, minimum: int | None = None) -> int:
        required = default is None
        value = self._get(key, _MISSING if required else default, required)
        if isinstance(value, bool) or not isinstance(value, int):
            raise ParameterError(self._name(key), value, "must be an integer", self.source)
        if minimum is not None and value < minimum:
            raise ParameterError(self._name(key), value, f"must be >= {minimum}", self.source)
        return int(value)

    def string(self, key: str, default: Any = None, *, choices: Iterable[str] | None = None) -> str:
        required = default is None
        value = self._get(key, _MISSING if required else default, required)
        if not isinstance(value, str):
            raise ParameterError(self._name(key), value, "must be a string", self.source)
        if choices is not None and value not in choices:
            raise ParameterError(self._name(key), value,
                                 f"must be one of {sorted(choices)}", self.source)
        return value

    def boolean(self, key: str, default: Any = None) -> bool:
        required = default is None
        value = self._get(key, _MISSING if required else default, required)
        if not isinstance(value, bool):
            raise ParameterError(self._name(key), value, "must be true or false", self.source)
        return value

    def numbers(self, key: str, default: Any = None, *, length: int | None = None,
                positive: bool = False, nonnegative: bool = False,
                increasing: bool = False) -> list[float]:
        required = default is None
        value = self._get(key, _MISSING if required else default, required)
        name = self._name(key)
        if not isinstance(value, (list, tuple)):
            raise ParameterError(name, value, "must be an array of numbers", self.source)
        if length is not None and len(value) != length:
            raise ParameterError(name, value, f"must have {length} entries", self.source)
        out = [check_number(f"{name}[{i}]", x, source=self.source, positive=positive,
                            nonnegative=nonnegative) for i, x in enumerate(value)]
        if increasing and any(b <= a for a, b in zip(out, out[1:])):
            raise ParameterError(name, value, "must be strictly increasing", self.source)
        return out

    def unknown_keys(self, allowed: Iterable[str]) -> None:
        """Reject keys that are not in ``allowed`` (catches typos in data files)."""
        allowed = set(allowed)
        for key in self.data:
            if key not in allowed:
                raise ParameterError(self._name(key), self.data[key],
                                     f"unknown field (allowed: {sorted(allowed)})", self.source)


class _Missing:
    def __repr__(self) -> str:  # pragma: no cover
        return "<missing>"


_MISSING: Any = _Missing()


def check_number(name: str, value: Any, *, source: str | None = None, positive: bool = False,
                 nonnegative: bool = False, minimum: float | None = None,
                 maximum: float | None = None) -> float:
    """Return ``value`` as a finite float or raise a :class:`ParameterError` naming it."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        try:
            if isinstance(value, np.generic):
                value = value.item()
            else:
                raise TypeError
        except TypeError:
            raise ParameterError(name, value, "must be a number", source) from None
    x = float(value)
    if not math.isfinite(x):
        raise ParameterError(name, value, "must be finite", source)
    if positive and not x > 0:
        raise ParameterError(name, value, "must be > 0", source)
    if nonnegative and not x >= 0:
        raise ParameterError(name, value, "must be >= 0", source)
    if minimum is not None and x < minimum:
        raise ParameterError(name, value, f"must be >= {minimum}", source)
    if maximum is not None and x > maximum:
        raise ParameterError(name, value, f"must be <= {maximum}", source)
    return x

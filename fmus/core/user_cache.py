"""The folder of pantocosim's caches: ``$XDG_CACHE_HOME/pantocosim``, or
``~/.cache/pantocosim`` when that variable is unset, empty or relative (the XDG base
directory specification ignores a relative one).

Every cache is an optimisation: a cache that cannot be read or written (damaged, foreign,
read-only, full, a file where a folder should be) never stops a run. The run goes on without
it and :func:`cache_warning` says so once, on one line naming the path and what to do."""

from __future__ import annotations

import os
import warnings
from pathlib import Path


class CacheWarning(UserWarning):
    """A cache could not be used; the run goes on without it."""


_warned: set[str] = set()


def cache_root() -> Path:
    """``<user cache>/pantocosim``, absolute."""
    home = os.environ.get("XDG_CACHE_HOME", "")
    base = Path(home) if home and os.path.isabs(home) else Path.home() / ".cache"
    return base / "pantocosim"


def describe(exc: BaseException) -> str:
    """An OS error as its reason only (``Read-only file system``), others as type and text."""
    if isinstance(exc, OSError) and exc.strerror:
        return exc.strerror
    return f"{type(exc).__name__}: {exc}"


def cache_warning(path, problem: str, remedy: str, once_for: str | None = None) -> None:
    """Warn once per ``path`` and ``problem`` (or once per ``once_for`` when given): one line
    naming both and what to do."""
    message = f"cache {path}: {problem}; going on without it ({remedy})"
    seen = once_for or message
    if seen in _warned:
        return
    _warned.add(seen)
    warnings.warn(CacheWarning(message), stacklevel=3)


def _one_line(message, category, filename, lineno, line=None):
    if issubclass(category, CacheWarning):
        return f"pantocosim: warning: {message}\n"
    return _default_format(message, category, filename, lineno, line)


_default_format = warnings.formatwarning
warnings.formatwarning = _one_line

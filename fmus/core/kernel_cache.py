"""Where numba keeps the machine code of the package's kernels (``@njit(cache=True)``).

Numba's own locators keep it beside the source file, or under ``NUMBA_CACHE_DIR`` in a
folder named after the source file's absolute path. Either way a package copied to a new
folder compiles every kernel again: an FMU extracted by fmpy into a fresh temporary folder
paid 4-8 s of compilation at each instantiation. :class:`PackageCacheLocator` keeps the
kernels of every ``pantocosim`` module in one folder per module and source content, under
the user's cache (``$XDG_CACHE_HOME/pantocosim/numba``, or ``$NUMBA_CACHE_DIR/pantocosim``
when set), so every copy of the same source (the command line, the campaign workers, each
extraction of each FMU) shares them. Numba still checks each entry against the source's
content hash and the CPU, so a changed file or another machine compiles again, never loads
a stale kernel.
"""

from __future__ import annotations

import functools
import hashlib
import os
from pathlib import Path

from numba.core import caching, config

from .user_cache import cache_root

#: modules whose kernels are located here (their names start with it)
PACKAGE_PREFIX = "pantocosim."


def root() -> Path:
    """The folder of the package's kernel caches."""
    if config.CACHE_DIR:
        return Path(config.CACHE_DIR) / "pantocosim"
    return cache_root() / "numba"


@functools.lru_cache(maxsize=None)
def _source_digest(path: str, mtime_ns: int, size: int) -> str:
    """The content digest of a source file, read once per version of it (every kernel of a
    module asks for it)."""
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()[:16]


class PackageCacheLocator(caching._SourceFileBackedLocatorMixin, caching._CacheLocator):
    """The cache folder of a package kernel: ``<root>/<module>-<source digest>``."""

    def __init__(self, py_func, py_file):
        self._py_file = py_file
        self._lineno = py_func.__code__.co_firstlineno
        st = os.stat(py_file)
        digest = _source_digest(py_file, st.st_mtime_ns, st.st_size)
        self._cache_path = str(root() / f"{py_func.__module__}-{digest}")

    def get_cache_path(self) -> str:
        return self._cache_path

    @classmethod
    def from_function(cls, py_func, py_file):
        """A locator for the package's functions (None for others, or when the folder cannot
        be written: numba's own locators then apply)."""
        if not str(getattr(py_func, "__module__", "") or "").startswith(PACKAGE_PREFIX):
            return None
        return super().from_function(py_func, py_file)


def install() -> None:
    """Put :class:`PackageCacheLocator` first in numba's locators (before any kernel of the
    package is decorated)."""
    impl = getattr(caching, "CacheImpl", None) or caching._CacheImpl   # numba < 0.61
    locators = impl._locator_classes
    if PackageCacheLocator not in locators:
        locators.insert(0, PackageCacheLocator)

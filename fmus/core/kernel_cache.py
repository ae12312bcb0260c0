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

The cache never stops a run: a damaged, truncated or foreign entry (``.nbi``/``.nbc``) is
compiled again and rewritten, and a folder that cannot be made or written (read-only, full, a
file in its place) leaves the kernels compiled at each run; either way with one warning line
(:func:`pantocosim.core.user_cache.cache_warning`).
"""

from __future__ import annotations

import atexit
import functools
import hashlib
import os
import shutil
import tempfile
from pathlib import Path

from numba.core import caching, config
from numba.core.compiler import CompileResult

from .user_cache import cache_root, cache_warning, describe

REMEDY = "kernels are compiled at each run: make it a writable folder, free space or set " \
         "NUMBA_CACHE_DIR"

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

    def ensure_cache_path(self) -> None:
        """Make the folder, or accept one that can only be read (a read-only cache still
        gives its kernels; the ones it lacks are compiled at each run, with a warning)."""
        try:
            super().ensure_cache_path()
        except OSError as exc:
            path = self.get_cache_path()
            if not (os.path.isdir(path) and os.access(path, os.R_OK | os.X_OK)):
                cache_warning(root(), f"cannot be made or written ({describe(exc)})", REMEDY,
                              once_for=f"unwritable {root()}")
                raise

    @classmethod
    def from_function(cls, py_func, py_file):
        """A locator for the package's functions (None for others, or when the folder cannot
        be written: numba's own locators then apply)."""
        if not _ours(py_func):
            return None
        return super().from_function(py_func, py_file)


def _ours(py_func) -> bool:
    return str(getattr(py_func, "__module__", "") or "").startswith(PACKAGE_PREFIX)


class ScratchCacheLocator(PackageCacheLocator):
    """The last resort of a package kernel whose other folders all fail: a private temporary
    folder of this process (the kernels are compiled, not shared)."""

    def __init__(self, py_func, py_file):
        super().__init__(py_func, py_file)
        self._cache_path = _scratch_folder()

    @classmethod
    def from_function(cls, py_func, py_file):
        if not _ours(py_func) or not os.path.exists(py_file):
            return None
        return cls(py_func, py_file)


@functools.lru_cache(maxsize=None)
def _scratch_folder() -> str:
    folder = tempfile.mkdtemp(prefix="pantocosim-numba-")
    atexit.register(shutil.rmtree, folder, True)
    return folder


def _is_package_cache(cache) -> bool:
    """Whether numba's ``cache`` holds a kernel of the package (in any locator's folder)."""
    return _ours(getattr(cache, "_py_func", None))


def _folder_of(cache) -> Path:
    """The folder to name for ``cache``: the package's root, or numba's own folder."""
    locator = cache._impl.locator
    return root() if isinstance(locator, PackageCacheLocator) else Path(cache._cache_path)


def _guarded_load(load):
    @functools.wraps(load)
    def load_overload(self, sig, target_context):
        try:
            found = load(self, sig, target_context)
            _check_is_of(found, self._py_func)
            return found
        except Exception as exc:  # noqa: BLE001 - a damaged entry is compiled again
            if not _is_package_cache(self):
                raise
            index = Path(self._cache_file._index_path)
            cache_warning(index, f"damaged kernel cache entry ({describe(exc)})",
                          "the kernel is compiled again and the entry rewritten",
                          once_for=f"damaged {_folder_of(self)}")
            _forget(index)
            return None
    load_overload.pantocosim_guard = True
    return load_overload


def _check_is_of(found, py_func) -> None:
    """Raise if a loaded kernel is another function's (a foreign ``.nbc`` under this name)."""
    if isinstance(found, CompileResult) and found.fndesc.qualname != py_func.__qualname__:
        raise ValueError(f"the entry holds {found.fndesc.qualname}, not "
                         f"{py_func.__qualname__}")


def _guarded_save(save):
    @functools.wraps(save)
    def save_overload(self, sig, data):
        try:
            return save(self, sig, data)
        except Exception as exc:  # noqa: BLE001 - an unwritable cache only costs time
            if not _is_package_cache(self):
                raise
            folder = _folder_of(self)
            cache_warning(folder, f"kernels not kept ({describe(exc)})", REMEDY,
                          once_for=f"unwritable {folder}")
            return None
    save_overload.pantocosim_guard = True
    return save_overload


def _forget(index: Path) -> None:
    """Remove a damaged index so that the next save starts a new one (a read-only cache
    keeps it: each run then compiles)."""
    try:
        index.unlink(missing_ok=True)
    except OSError:
        pass


def install() -> None:
    """Put :class:`PackageCacheLocator` first in numba's locators and
    :class:`ScratchCacheLocator` last, and make numba's loads and saves of the package's
    kernels survive a damaged or unwritable cache (before any kernel is decorated)."""
    impl = getattr(caching, "CacheImpl", None) or caching._CacheImpl   # numba < 0.61
    locators = impl._locator_classes
    if PackageCacheLocator not in locators:
        locators.insert(0, PackageCacheLocator)
    if ScratchCacheLocator not in locators:
        locators.append(ScratchCacheLocator)
    if not getattr(caching.Cache.load_overload, "pantocosim_guard", False):
        caching.Cache.load_overload = _guarded_load(caching.Cache.load_overload)
        caching.Cache.save_overload = _guarded_save(caching.Cache.save_overload)

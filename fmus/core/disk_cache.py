"""A content-addressed cache on disk of set-up results (named arrays), shared by every process
of a machine: the command line, the campaign workers and the FMUs.

An entry's key is the SHA-256 of every input that changes it, given as values (arrays by
dtype, shape and bytes; numbers and strings by repr) together with the model package's build
stamp (:mod:`.stamp`), so a changed input or a changed package misses. An entry is an ``.npz``
file written whole under a temporary name and moved in place: processes that fill one entry
at once leave one valid entry. An entry that does not load, or whose stored key is not its
own, is computed again with a warning, never trusted. A folder that cannot be written
(read-only, full, a file in its place) is read where it can be and otherwise skipped, with one
warning line: the cache never stops a run.

Settings (environment, so that worker processes and FMUs inherit them):
``PANTOCOSIM_NO_CACHE=1`` (the command line's ``--no-cache``) computes everything;
``PANTOCOSIM_CACHE_DIR`` is the folder (default ``$XDG_CACHE_HOME/pantocosim/setup``);
``PANTOCOSIM_CACHE_MB`` bounds its size (default :data:`DEFAULT_LIMIT_MB`): the entries used
least recently go first, and an entry over half of it is not kept.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path
from typing import Callable

import numpy as np
import scipy.sparse as sp

from .errors import ParameterError
from .stamp import process_stamp
from .user_cache import cache_root, cache_warning, describe

DEFAULT_LIMIT_MB = 512
_KEY_FIELD = "__key__"


def enabled() -> bool:
    return os.environ.get("PANTOCOSIM_NO_CACHE", "") in ("", "0")


def folder() -> Path:
    given = os.environ.get("PANTOCOSIM_CACHE_DIR")
    if given:
        return Path(given)

    return cache_root() / "setup"


def _feed(h, part) -> None:
    if isinstance(part, np.ndarray):
        h.update(f"array {part.dtype.str} {part.shape}".encode())
        h.update(np.ascontiguousarray(part).tobytes())
    elif sp.issparse(part):
        part = part.tocsr()
        h.update(f"sparse {part.shape}".encode())
        for a in (part.indptr, part.indices, part.data):
            _feed(h, np.asarray(a))
    elif isinstance(part, (tuple, list)):
        h.update(f"seq {len(part)}".encode())
        for p in part:
            _feed(h, p)
    elif isinstance(part, (bool, int, float, str, np.number)) or part is None:
        h.update(f"{type(part).__name__} {part!r}".encode())
    else:
        raise TypeError(f"cannot key a {type(part).__name__}")
    h.update(b"\0")


def key(kind: str, parts) -> str:
    """The entry key of ``kind`` computed from ``parts`` (with the package stamp)."""
    h = hashlib.sha256()
    _feed(h, (kind, process_stamp(), tuple(parts)))
    return h.hexdigest()


REMEDY = "make it a writable folder, free space, set PANTOCOSIM_CACHE_DIR, or --no-cache"


def _load(path: Path, expected: str) -> dict[str, np.ndarray] | None:
    try:
        with np.load(path, allow_pickle=False) as data:
            if str(data[_KEY_FIELD]) != expected:
                raise ValueError("the entry's stored key is another one")
            out = {k: data[k] for k in data.files if k != _KEY_FIELD}
    except (FileNotFoundError, NotADirectoryError):
        return None
    except Exception as exc:  # noqa: BLE001 - a corrupt or foreign entry is computed again
        cache_warning(path, f"entry unusable ({describe(exc)})",
                      "it is computed again and rewritten")
        return None
    try:
        os.utime(path)                               # recently used: evicted last
    except OSError:
        pass                                         # a read-only cache is still read
    return out


def _store(path: Path, expected: str, arrays: dict[str, np.ndarray]) -> None:
    part = path.with_name(f".{path.stem}.{os.getpid()}.{id(arrays)}.tmp.npz")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        np.savez(part, **{_KEY_FIELD: np.array(expected)}, **arrays)
        os.replace(part, path)
    except OSError as exc:                           # a full or read-only disk: no cache
        cache_warning(path.parent, f"set-up results not kept ({describe(exc)})", REMEDY)
        _remove(part)
        return
    _evict(path.parent)


def _remove(path: Path) -> None:
    """Remove ``path`` if it is there and can be (a read-only cache keeps it)."""
    try:
        path.unlink(missing_ok=True)
    except OSError:
        pass


def limit_bytes() -> float:
    """The size the cache folder is kept under (``PANTOCOSIM_CACHE_MB``)."""
    given = os.environ.get("PANTOCOSIM_CACHE_MB", "").strip()
    if not given:
        return DEFAULT_LIMIT_MB * 2.0**20
    try:
        mb = float(given)
    except ValueError:
        mb = float("nan")
    if not mb >= 0.0:
        raise ParameterError("PANTOCOSIM_CACHE_MB", given,
                             "not a size: give megabytes, a number >= 0 (default "
                             f"{DEFAULT_LIMIT_MB})", source="environment variable")
    return mb * 2**20


def check_settings() -> None:
    """Refuse a bad ``PANTOCOSIM_CACHE_MB`` (ParameterError naming it) before any work."""
    if enabled():
        limit_bytes()


def _evict(root: Path) -> None:
    limit = limit_bytes()
    entries = []
    for f in root.glob("*.npz"):
        try:
            st = f.stat()
        except OSError:
            continue
        entries.append((st.st_mtime, st.st_size, f))
    total = sum(size for _, size, _ in entries)
    for _, size, f in sorted(entries):
        if total <= limit:
            break
        _remove(f)
        total -= size


def cached(kind: str, parts, compute: Callable[[], dict[str, np.ndarray]]
           ) -> dict[str, np.ndarray]:
    """``compute()`` (named arrays), or its entry kept for ``kind`` and ``parts``."""
    if not enabled():
        return compute()
    limit = limit_bytes()                            # a bad setting is refused at once
    k = key(kind, parts)
    root = folder()
    if root.exists() and not root.is_dir():
        cache_warning(root, "a file where the cache folder should be", REMEDY)
        return compute()
    path = root / f"{kind}-{k[:32]}.npz"
    found = _load(path, k)
    if found is not None:
        return found
    arrays = {name: np.asarray(a) for name, a in compute().items()}
    if sum(a.nbytes for a in arrays.values()) <= limit / 2:
        _store(path, k, arrays)          # a larger entry would push out every other one
    return arrays

"""The model package's build stamp: a digest of its source and data files. FMUs carry the
stamp they were built with; caches key their entries on it."""

from __future__ import annotations

import functools
import hashlib
from pathlib import Path

import pantocosim

#: files that make up the model (a change of any of them changes the stamp)
STAMPED_SUFFIXES = (".py", ".toml", ".c", ".h")
#: subpackages that are not part of the FMUs' model: the master (the FMUs are driven by one),
#: the multibody core (the double pendulum, which no FMU runs) and the native FMUs' C sources
#: (``native``, compiled into the native FMUs by ``export-native``). FMUs do not bundle them
#: and the stamp does not cover them.
UNBUNDLED = ("master", "multibody", "native")


def package_stamp(package_dir: str | Path | None = None) -> str:
    """SHA-256 over the model package's source and data files (relative path + content),
    without the :data:`UNBUNDLED` subpackages."""
    if package_dir is None:
        package_dir = Path(pantocosim.__file__).resolve().parent
    root = Path(package_dir)
    h = hashlib.sha256()
    for f in sorted(root.rglob("*")):
        rel = f.relative_to(root)
        if rel.parts[0] in UNBUNDLED:
            continue
        if f.suffix in STAMPED_SUFFIXES and "__pycache__" not in f.parts and f.is_file():
            h.update(rel.as_posix().encode())
            h.update(b"\0")
            h.update(f.read_bytes())
            h.update(b"\0")
    return h.hexdigest()[:16]


@functools.lru_cache(maxsize=1)
def process_stamp() -> str:
    """The stamp of the package this process imported (computed once)."""
    return package_stamp()

"""The folder of pantocosim's caches: ``$XDG_CACHE_HOME/pantocosim``, or
``~/.cache/pantocosim`` when that variable is unset, empty or relative (the XDG base
directory specification ignores a relative one)."""

from __future__ import annotations

import os
from pathlib import Path


def cache_root() -> Path:
    """``<user cache>/pantocosim``, absolute."""
    home = os.environ.get("XDG_CACHE_HOME", "")
    base = Path(home) if home and os.path.isabs(home) else Path.home() / ".cache"
    return base / "pantocosim"

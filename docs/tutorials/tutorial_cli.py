"""What every tutorial script shares: the folder of the data files its page shows, and the
command line run as a user runs it."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

#: the tutorials' data files, shown on their pages
FILES = Path(__file__).resolve().parent / "files"


def pantocosim(*args: str, cwd: Path) -> str:
    """Run ``pantocosim ARGS`` (the installed command line) and return what it prints."""
    proc = subprocess.run([sys.executable, "-m", "pantocosim.master.cli", *args], cwd=cwd,
                          capture_output=True, text=True)
    if proc.returncode != 0:
        sys.exit(f"pantocosim {' '.join(args)} failed:\n{proc.stderr}")
    return proc.stdout

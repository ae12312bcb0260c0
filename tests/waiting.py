"""Waits on what can be observed, each with a deadline, instead of sleeps that guess how far
another process or thread has got."""

from __future__ import annotations

import os
import time
from pathlib import Path


def wait_until(condition, what: str, timeout: float = 60.0, proc=None) -> None:
    """Return once ``condition()`` holds; an AssertionError naming ``what`` when ``timeout``
    seconds pass first or ``proc`` (a Popen) ends first."""
    deadline = time.monotonic() + timeout
    while not condition():
        if proc is not None and proc.poll() is not None:
            raise AssertionError(f"the process ended (status {proc.returncode}) before {what}")
        if time.monotonic() > deadline:
            raise AssertionError(f"{what}: not within {timeout:g} s")
        time.sleep(0.02)


def cpu_seconds(pid: int) -> float:
    """The CPU time [s] process ``pid`` has used (Linux /proc: user + system)."""
    fields = Path(f"/proc/{pid}/stat").read_text().rpartition(")")[2].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def group_size(pgid: int) -> int:
    """How many processes the process group ``pgid`` holds (Linux /proc)."""
    count = 0
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            count += int(stat.read_text().rpartition(")")[2].split()[2]) == pgid
        except (OSError, ValueError, IndexError):
            pass                                  # a process that ended meanwhile
    return count


def later_mtime(path: Path) -> None:
    """Return once the file system stamps a new file later than ``path`` (so that the next
    file written sorts after it by modification time)."""
    probe = path.parent / f".{path.name}.probe"

    def later() -> bool:
        probe.touch()
        return probe.stat().st_mtime_ns > path.stat().st_mtime_ns

    try:
        wait_until(later, f"a modification time later than {path.name}'s", timeout=10.0)
    finally:
        probe.unlink(missing_ok=True)

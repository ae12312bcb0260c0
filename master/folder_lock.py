"""One writer per output folder: ``pantocosim sweep`` and ``pantocosim build-fmus`` hold a
lock on their ``--out`` while they write it.

The lock is an advisory ``flock`` on ``OUT/.pantocosim.lock``, which also holds who has it
(pid, host, command, since when). The system releases it when its process ends, however it
ends, so a lock left by a killed process is stale at once and the next command takes it.
A second command finds the lock held and stops with one line naming the holder (exit status
2), or with ``--wait`` waits until the holder is done.
"""

from __future__ import annotations

import fcntl
import json
import os
import socket
import sys
import time
from pathlib import Path

from pantocosim.core.errors import OutputError, PantocosimError
from pantocosim.master.output_folder import reason

LOCK_NAME = ".pantocosim.lock"


class FolderBusy(PantocosimError):
    """Another process writes the folder; names it."""


def holder_of(folder) -> dict:
    """Who holds, or last held, the lock of ``folder`` (empty if nobody wrote one)."""
    try:
        return json.loads((Path(folder) / LOCK_NAME).read_text() or "{}")
    except (OSError, ValueError):
        return {}


def describe(holder: dict) -> str:
    if not holder:
        return "another process"
    since = time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(holder.get("since", 0)))
    return (f"pid {holder.get('pid')} on {holder.get('host')} ({holder.get('command')!r}, "
            f"since {since})")


class FolderLock:
    """``with FolderLock(out, field="--out", wait=False):`` holds the lock of ``out``; with
    ``required=False`` a folder where no lock file can be made (read-only) is used without."""

    def __init__(self, folder, field: str = "--out", wait: bool = False, echo=None,
                 required: bool = True):
        self.folder = Path(folder)
        self.field = field
        self.wait = wait
        self.required = required
        self.echo = echo or (lambda text: print(text, file=sys.stderr))
        self._fd = None

    def __enter__(self) -> "FolderLock":
        path = self.folder / LOCK_NAME
        try:
            self.folder.mkdir(parents=True, exist_ok=True)
            fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        except OSError as exc:
            if not self.required:
                return self
            raise OutputError(self.field, self.folder,
                              f"cannot create the lock file {LOCK_NAME}: {reason(exc)}") from None
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = describe(holder_of(self.folder))
            if not self.wait:
                os.close(fd)
                raise FolderBusy(f"{self.field} = {str(self.folder)!r}: {holder} is writing "
                                 "there; wait for it to end, run with --wait, or give "
                                 "another folder") from None
            self.echo(f"waiting for {holder} to finish writing {self.folder}")
            fcntl.flock(fd, fcntl.LOCK_EX)
        self._fd = fd
        me = {"pid": os.getpid(), "host": socket.gethostname(),
              "command": " ".join(["pantocosim", *sys.argv[1:]]) if sys.argv else "",
              "since": time.time()}
        try:
            os.ftruncate(fd, 0)
            os.pwrite(fd, (json.dumps(me) + "\n").encode(), 0)
        except OSError:
            pass   # the lock holds without its description (a full disk)
        return self

    def __exit__(self, *exc) -> None:
        if self._fd is not None:   # the file keeps the last holder's description
            fcntl.flock(self._fd, fcntl.LOCK_UN)
            os.close(self._fd)
            self._fd = None

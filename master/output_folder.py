"""Output folders that never lose earlier results.

A command writes into a fresh folder beside its ``--out`` (``.NAME.XXXX.partial``) and moves
the files into ``--out`` when it is done, or when it stops after computing something (an
interrupt, a solver failure: the summary then says where it stopped). A run that fails before
computing anything, or cannot write its files (a full disk), leaves ``--out`` as it was. Only
the files a command writes are replaced; other files in ``--out`` are never touched, so
``--out .`` is safe.

The folder is checked when the command starts, before any long set-up: ``--out`` naming a
file, or a place that cannot be created or written, is an error naming ``--out``.

A staging folder holds a lock (``flock`` on its ``.pantocosim.owner``) while its command
runs; the system releases it however the command ends, so a staging folder left by a killed
command (``kill -9``, SIGTERM) is unlocked, and the next command writing the same ``--out``
removes it. The folder and its lock are made with SIGINT and SIGTERM held back, so a Ctrl-C
cannot fall between the two and leave a folder without a lock. A staging folder kept after a failed move (the error names it) has no lock file
and stays.
"""

from __future__ import annotations

import fcntl
import os
import shutil
import signal
import tempfile
import threading
from contextlib import contextmanager
from pathlib import Path

from pantocosim.core.errors import OutputError

#: the lock file of a staging folder, held while its command runs
OWNER = ".pantocosim.owner"


def reason(exc: OSError) -> str:
    """The system's reason of an OSError, without the path (the message names it)."""
    return exc.strerror or str(exc) or type(exc).__name__


def write_error(field: str, path, exc: OSError) -> OutputError:
    """The :class:`OutputError` naming ``path`` for an OSError while writing it."""
    return OutputError(field, path, f"cannot be written: {reason(exc)}")


@contextmanager
def writing(field: str, path):
    """Turn an OSError while writing ``path`` into an :class:`OutputError` naming it."""
    try:
        yield
    except OutputError:
        raise
    except OSError as exc:
        raise write_error(field, path, exc) from None


class OutputFolder:
    """``--out`` of a command, written through a fresh staging folder beside it.

    ``known`` are the file names the command owns in ``--out``: at :meth:`commit` those the
    staging folder does not hold are removed (a plot of an earlier run would not match the new
    summary); other files are left alone.
    """

    def __init__(self, out, known=(), field: str = "--out"):
        self.out = Path(out)
        self.field = field
        self.known = tuple(known)
        self._kept = False
        if str(out) == "":
            raise OutputError(field, out, "empty folder name")
        if self.out.exists() and not self.out.is_dir():
            raise OutputError(field, out, "is a file, not a folder; give a folder name")
        parent = self.out.absolute().parent
        prefix = f".{self.out.name or 'out'}."
        try:
            parent.mkdir(parents=True, exist_ok=True)
            remove_abandoned(parent, prefix)
            with signals_held():
                self.path = Path(tempfile.mkdtemp(prefix=prefix, suffix=".partial",
                                                  dir=parent))
                self._owner = own(self.path)
        except (FileExistsError, NotADirectoryError):
            raise OutputError(field, out, "cannot create the folder: a folder above it is a "
                              "file") from None
        except OSError as exc:
            raise OutputError(field, out, f"cannot create the folder: {reason(exc)}") from None

    def commit(self, into=None) -> Path:
        """Move the staged files into ``--out`` (or the folder ``into`` beside it; each file
        replaced whole) and remove the staging folder; earlier files of ours that this run did
        not write are removed."""
        self.out = Path(into) if into is not None else self.out
        try:
            self.out.mkdir(parents=True, exist_ok=True)
            staged = {p.name for p in self.path.iterdir()} - {OWNER}
            for name in self.known:
                old = self.out / name
                if name not in staged and old.is_file():
                    old.unlink()
            for name in sorted(staged, key=lambda n: n == "summary.json"):  # summary last
                os.replace(self.path / name, self.out / name)
            self._release()
            self.path.rmdir()
        except OSError as exc:
            self._release()
            self._kept = True
            raise OutputError(self.field, self.out, f"cannot move the results into place: "
                              f"{reason(exc)} (they are in {self.path})") from None
        return self.out

    def discard(self) -> None:
        """Remove the staging folder; ``--out`` stays as it was. After a failed
        :meth:`commit` the staging folder is kept (the error names it)."""
        if not self._kept:
            self._release()
            shutil.rmtree(self.path, ignore_errors=True)

    def _release(self) -> None:
        """Remove the staging folder's lock file and let the lock go."""
        if self._owner is not None:
            (self.path / OWNER).unlink(missing_ok=True)
            self._owner.close()
            self._owner = None


#: the signals held back while a staging folder and its lock are made
HELD_SIGNALS = frozenset({signal.SIGINT, signal.SIGTERM})


@contextmanager
def signals_held():
    """SIGINT and SIGTERM arriving inside the block are delivered when it ends, to the
    handlers in place before it (main thread only: elsewhere Python runs no handler)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    pending = []
    previous = {s: signal.signal(s, lambda signum, frame: pending.append(signum))
                for s in HELD_SIGNALS}
    try:
        yield
    finally:
        for s, handler in previous.items():
            signal.signal(s, signal.SIG_DFL if handler is None else handler)
        for s in pending:
            signal.raise_signal(s)


def own(path: Path):
    """Lock the staging folder ``path`` for this process: the lock file is locked under
    another name and then renamed, so that another process never finds it unlocked while
    this one runs. Returns the open file (the lock lasts while it is open)."""
    fresh = path / (OWNER + ".new")
    f = open(fresh, "w")
    fcntl.flock(f.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
    os.replace(fresh, path / OWNER)
    return f


def remove_abandoned(parent: Path, prefix: str) -> None:
    """Remove the staging folders ``prefix*.partial`` in ``parent`` whose command ended
    without removing them (their lock is free); best effort."""
    for folder in parent.glob(f"{prefix}*.partial"):
        try:
            with open(folder / OWNER) as f:
                fcntl.flock(f.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
                shutil.rmtree(folder, ignore_errors=True)
        except OSError:            # no lock file (kept on purpose), or its command runs
            continue


def check_file_target(field: str, path) -> Path:
    """A file a command will write (``--plot FILE.png``): refused at once if it is a folder,
    has a suffix matplotlib cannot write, or its folder cannot take a new file."""
    from matplotlib.figure import Figure

    p = Path(path)
    kinds = Figure().canvas.get_supported_filetypes()
    if str(path) == "" or p.is_dir():
        raise OutputError(field, path, "is a folder; give a file name such as plot.png")
    if p.suffix[1:].lower() not in kinds:
        raise OutputError(field, path, f"unknown picture format {p.suffix or '(none)'!r}; "
                          f"give a file name ending in .png, .pdf or .svg")
    return check_writable_file(field, path)


def check_writable_file(field: str, path) -> Path:
    """A file a command will write (``--out FILE.json``): refused at once if it is a folder
    or its folder cannot take a new file."""
    p = Path(path)
    if str(path) == "" or p.is_dir():
        raise OutputError(field, path, "is a folder; give a file name")
    try:
        with tempfile.NamedTemporaryFile(dir=p.absolute().parent, prefix=f".{p.name}."):
            pass
    except OSError as exc:
        raise OutputError(field, path, f"cannot be written there: {reason(exc)}") from None
    return p


def write_whole(field: str, path, write) -> None:
    """``write(tmp)`` into a temporary file beside ``path``, then moved onto it (an earlier
    file is replaced whole or not at all); errors name ``field``."""
    p = Path(path)
    tmp = p.with_name(f".{p.name}.partial")
    try:
        with writing(field, path):
            write(tmp)
            os.replace(tmp, p)
    finally:
        tmp.unlink(missing_ok=True)


def save_figure(fig, field: str, path) -> None:
    """``fig.savefig(path)`` through a temporary file beside it; errors name ``field``."""
    fmt = Path(path).suffix[1:].lower()
    write_whole(field, path, lambda tmp: fig.savefig(tmp, dpi=120, format=fmt))

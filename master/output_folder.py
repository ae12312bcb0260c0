"""Output folders that never lose earlier results.

A command writes into a fresh folder beside its ``--out`` (``.NAME.XXXX.partial``) and moves
the files into ``--out`` when it is done, or when it stops after computing something (an
interrupt, a solver failure: the summary then says where it stopped). A run that fails before
computing anything, or cannot write its files (a full disk), leaves ``--out`` as it was. Only
the files a command writes are replaced; other files in ``--out`` are never touched, so
``--out .`` is safe.

The folder is checked when the command starts, before any long set-up: ``--out`` naming a
file, or a place that cannot be created or written, is an error naming ``--out``.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from contextlib import contextmanager
from pathlib import Path

from pantocosim.core.errors import OutputError


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
        if str(out) == "":
            raise OutputError(field, out, "empty folder name")
        if self.out.exists() and not self.out.is_dir():
            raise OutputError(field, out, "is a file, not a folder; give a folder name")
        parent = self.out.absolute().parent
        try:
            parent.mkdir(parents=True, exist_ok=True)
            self.path = Path(tempfile.mkdtemp(prefix=f".{self.out.name or 'out'}.",
                                              suffix=".partial", dir=parent))
        except (FileExistsError, NotADirectoryError):
            raise OutputError(field, out, "cannot create the folder: a folder above it is a "
                              "file") from None
        except OSError as exc:
            raise OutputError(field, out, f"cannot create the folder: {reason(exc)}") from None

    def commit(self) -> Path:
        """Move the staged files into ``--out`` (each replaced whole) and remove the staging
        folder; earlier files of ours that this run did not write are removed."""
        try:
            self.out.mkdir(parents=True, exist_ok=True)
            staged = {p.name for p in self.path.iterdir()}
            for name in self.known:
                old = self.out / name
                if name not in staged and old.is_file():
                    old.unlink()
            for name in sorted(staged, key=lambda n: n == "summary.json"):  # summary last
                os.replace(self.path / name, self.out / name)
            self.path.rmdir()
        except OSError as exc:
            self._kept = True
            raise OutputError(self.field, self.out, f"cannot move the results into place: "
                              f"{reason(exc)} (they are in {self.path})") from None
        return self.out

    def discard(self) -> None:
        """Remove the staging folder; ``--out`` stays as it was. After a failed
        :meth:`commit` the staging folder is kept (the error names it)."""
        if not getattr(self, "_kept", False):
            shutil.rmtree(self.path, ignore_errors=True)


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

"""Exceptions shared by models, solvers, FMU slaves and the master."""

from __future__ import annotations


class PantocosimError(Exception):
    """Base class of every error this package raises on purpose."""


class ParameterError(PantocosimError, ValueError):
    """A parameter or data-file field has a bad value.

    The message always names the source (file or object), the field and the offending value,
    e.g. ``dsa380.toml: bars.m1 = -1.0: must be > 0``.
    """

    def __init__(self, field: str, value, reason: str, source: str | None = None):
        self.field = field
        self.value = value
        self.reason = reason
        self.source = source
        where = f"{source}: " if source else ""
        super().__init__(f"{where}{field} = {value!r}: {reason}")

    def renamed(self, names: dict[str, str]) -> "ParameterError":
        """The same error under the caller's name of the field (e.g. an FMU parameter's
        name for a model field); fields not in ``names`` keep theirs."""
        return ParameterError(names.get(self.field, self.field), self.value, self.reason,
                              self.source)


class ConvergenceError(PantocosimError, RuntimeError):
    """Newton-Raphson did not converge; names time, step and residual."""

    def __init__(self, message: str, time: float = float("nan"), step: int = -1,
                 residual: float = float("nan")):
        self.time = time
        self.step = step
        self.residual = residual
        super().__init__(message)


class OutputError(PantocosimError, OSError):
    """A result file or folder cannot be written (full disk, no permission, not a folder).

    Names the command-line field (``--out``, ``--plot``) or the file and the system's reason,
    e.g. ``--out = '/proc/x': cannot create the folder: No such file or directory``.
    """

    def __init__(self, field: str, path, reason: str):
        self.field = field
        self.path = str(path)
        self.reason = reason
        super().__init__(f"{field} = {self.path!r}: {reason}")


class Interrupted(PantocosimError):
    """The user stopped a run (Ctrl-C, SIGINT); says where it stopped. Exit status 130."""

    exit_code = 130

"""Loading and driving FMI 2.0 co-simulation FMUs through fmpy (``FMU2Slave``).

- FMUs are extracted once per content hash into a fixed cache folder, so numba's on-disk cache
  inside the bundled package stays warm across runs (docs/pythonfmu-notes.md);
- every log message of an instance is captured (for error reports) and FMI call failures
  become :class:`FmuError` with the status and the instance's last messages;
- interface variables are exchanged with one vector ``getReal``/``setReal`` call per FMU.
"""

from __future__ import annotations

import hashlib
import os
import shutil
from ctypes import byref
from pathlib import Path

# numpy, scipy.sparse.linalg and numba are imported before any pythonfmu FMU is loaded: this
# avoids the intermittent abort at exit of docs/pythonfmu-notes.md (B5).
import numpy as np
import scipy.sparse.linalg  # noqa: F401
import numba  # noqa: F401

from pantocosim.core.errors import PantocosimError

STATUS_NAMES = ["OK", "WARNING", "DISCARD", "ERROR", "FATAL", "PENDING"]


class FmuError(PantocosimError):
    def __init__(self, message: str, status: int = 3, instance: str = ""):
        self.status = status
        self.instance = instance
        super().__init__(message)


def cache_dir() -> Path:
    base = os.environ.get("PANTOCOSIM_FMU_CACHE")
    if base:
        return Path(base)
    return Path(os.environ.get("XDG_CACHE_HOME", Path.home() / ".cache")) / "pantocosim" / "fmus"


def extract_cached(fmu_path: str | Path) -> Path:
    """Extract ``fmu_path`` into a folder named after its content hash (reused across runs).
    The folder appears whole (extracted beside it, then renamed), so processes sharing the
    cache never see or remove one another's half-extracted folder."""
    from fmpy import extract

    fmu_path = Path(fmu_path)
    if not fmu_path.exists():
        raise FmuError(f"FMU file not found: {fmu_path}", status=3)
    digest = hashlib.sha256(fmu_path.read_bytes()).hexdigest()[:16]
    target = cache_dir() / f"{fmu_path.stem}-{digest}"
    marker = target / ".complete"
    if not marker.exists():
        target.parent.mkdir(parents=True, exist_ok=True)
        part = target.parent / f".{target.name}.{os.getpid()}.partial"
        shutil.rmtree(part, ignore_errors=True)
        extract(str(fmu_path), unzipdir=str(part))
        (part / ".complete").write_text("ok\n")
        _move_into_place(part, target)
    return target


def _move_into_place(part: Path, target: Path) -> None:
    """Rename the extracted folder ``part`` to ``target``; where another process got there
    first, keep its folder (same content) and drop ours; an incomplete leftover is replaced."""
    if target.exists() and not (target / ".complete").exists():
        shutil.rmtree(target, ignore_errors=True)
    try:
        os.rename(part, target)
    except OSError:
        shutil.rmtree(part, ignore_errors=True)
        if not (target / ".complete").exists():
            raise


_LOGS: dict[str, list[tuple[int, str]]] = {}
_CALLBACKS = None


def _callbacks():
    """fmi2CallbackFunctions whose logger stores messages per instance name."""
    global _CALLBACKS
    if _CALLBACKS is None:
        from fmpy.fmi2 import fmi2CallbackFunctions, fmi2CallbackLoggerTYPE, defaultCallbacks

        def logger(component, instance_name, status, category, message):
            name = instance_name.decode("utf-8", "replace") if instance_name else ""
            text = message.decode("utf-8", "replace") if message else ""
            _LOGS.setdefault(name, []).append((int(status), text))

        cb = fmi2CallbackFunctions()
        cb.logger = fmi2CallbackLoggerTYPE(logger)
        cb.allocateMemory = defaultCallbacks.allocateMemory
        cb.freeMemory = defaultCallbacks.freeMemory
        try:
            from fmpy.logging import addLoggerProxy

            addLoggerProxy(byref(cb))
        except Exception:  # pragma: no cover - fmpy without the proxy
            pass
        _CALLBACKS = (cb, logger)
    return _CALLBACKS[0]


class FmuInstance:
    """One instantiated co-simulation FMU with name-based variable access."""

    def __init__(self, fmu_path: str | Path, instance_name: str):
        from fmpy import read_model_description
        from fmpy.fmi2 import FMU2Slave, fmi2False

        self.path = Path(fmu_path)
        self.name = instance_name
        unzip = extract_cached(self.path)
        self.md = read_model_description(str(unzip))
        self.variables = {v.name: v for v in self.md.modelVariables}
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.slave = FMU2Slave(guid=self.md.guid, unzipDirectory=str(unzip),
                               modelIdentifier=self.md.coSimulation.modelIdentifier,
                               instanceName=instance_name)
        _LOGS[instance_name] = []
        self.fatal = False
        self._call("instantiate", lambda: self.slave.instantiate(callbacks=_callbacks(),
                                                                  loggingOn=True))
        self.t = 0.0
        #: doStep's noSetFMUStatePriorToCurrentPoint: the master may roll back
        self._no_set_prior = fmi2False

    # ------------------------------------------------------------------ errors
    def messages(self, min_status: int = 1) -> list[str]:
        return [f"[{STATUS_NAMES[s]}] {m}" for s, m in _LOGS.get(self.name, [])
                if s >= min_status]

    def _call(self, what, fn, *args):
        """``fn(*args)``; a failure becomes :class:`FmuError` naming ``what`` (a string, or a
        function giving it: per-step calls format their label only when they fail)."""
        try:
            return fn(*args)
        except Exception as exc:
            status = getattr(exc, "status", 3)
            if status == 4:
                self.fatal = True  # the instance is dangling: never call it again (B4)
            msgs = self.messages()
            detail = ("; ".join(m.splitlines()[0] for m in msgs[-3:])) if msgs else str(exc)
            what = what() if callable(what) else what
            raise FmuError(f"{self.name} ({self.path.name}): {what} returned "
                           f"{STATUS_NAMES[status] if isinstance(status, int) and status < 6 else status}: "
                           f"{detail}", status=status if isinstance(status, int) else 3,
                           instance=self.name) from None

    # ------------------------------------------------------------------ variables
    def has(self, name: str) -> bool:
        return name in self.vr

    def refs(self, names) -> list[int]:
        try:
            return [self.vr[n] for n in names]
        except KeyError as exc:
            raise FmuError(f"{self.name} ({self.path.name}) has no variable {exc.args[0]!r}",
                           instance=self.name) from None

    def set_start_values(self, values: dict) -> None:
        """Set parameters of any type by name (before exitInitializationMode)."""
        for name, value in values.items():
            ref = self.refs([name])
            kind = self.variables[name].type
            if kind == "Real":
                self._call(f"setReal({name})", lambda: self.slave.setReal(ref, [float(value)]))
            elif kind == "Integer":
                self._call(f"setInteger({name})", lambda: self.slave.setInteger(ref, [int(value)]))
            elif kind == "Boolean":
                self._call(f"setBoolean({name})", lambda: self.slave.setBoolean(ref, [bool(value)]))
            else:
                self._call(f"setString({name})", lambda: self.slave.setString(ref, [str(value)]))

    def initialize(self, start_values: dict, start_time: float = 0.0) -> None:
        self._call("setupExperiment", lambda: self.slave.setupExperiment(startTime=start_time))
        self._call("enterInitializationMode", self.slave.enterInitializationMode)
        self.set_start_values(start_values)
        self._call("exitInitializationMode", self.slave.exitInitializationMode)
        self.t = start_time

    def reals(self, names) -> "RealVector":
        """The Real variables ``names``, exchanged together (:class:`RealVector`)."""
        return RealVector(self, self.refs(names))

    def set_real(self, refs: list[int], values) -> None:
        self.slave.setReal(refs, list(values))

    def get_real(self, refs: list[int]) -> np.ndarray:
        return np.asarray(self.slave.getReal(refs), dtype=float)

    def do_step(self, t: float, h: float) -> None:
        self._call(lambda: f"doStep(t = {t:.6g}, h = {h:.3g})", self.slave.doStep, t, h,
                   self._no_set_prior)

    # ------------------------------------------------------------------ state
    def get_state(self):
        return self._call("getFMUstate", self.slave.getFMUstate)

    def set_state(self, state) -> None:
        self._call("setFMUstate", self.slave.setFMUstate, state)

    def free_state(self, state) -> None:
        self._call("freeFMUstate", self.slave.freeFMUstate, state)

    def serialize_state(self, state) -> bytes:
        return self._call("serializeFMUstate", lambda: self.slave.serializeFMUstate(state))

    def deserialize_state(self, data: bytes):
        return self._call("deSerializeFMUstate", lambda: self.slave.deSerializeFMUstate(data))

    def terminate(self) -> None:
        if self.fatal:
            return
        try:
            self.slave.terminate()
            self.slave.freeInstance()
        except Exception:  # noqa: BLE001 - best effort at shutdown
            pass


class RealVector:
    """Real variables of one FMU read or written together every step: the value references
    and the C arrays of fmpy's ``fmi2GetReal``/``fmi2SetReal`` are built once, so an exchange
    allocates nothing but the values it returns."""

    def __init__(self, fmu: FmuInstance, refs: list[int]):
        from fmpy.fmi2 import fmi2Real, fmi2ValueReference

        self.fmu = fmu
        self.refs = list(refs)
        self.n = len(self.refs)
        self._vr = (fmi2ValueReference * self.n)(*self.refs)
        self._buffer = (fmi2Real * self.n)()
        #: the C buffer seen as a numpy array (no copy)
        self._values = np.ctypeslib.as_array(self._buffer) if self.n else np.zeros(0)

    def get(self) -> np.ndarray:
        """The current values (a new array)."""
        slave = self.fmu.slave
        self.fmu._call("getReal", slave.fmi2GetReal, slave.component, self._vr, self.n,
                       self._buffer)
        return self._values.copy()

    def set(self, values) -> None:
        """Set the variables to ``values`` (one per reference)."""
        self._values[:] = values
        slave = self.fmu.slave
        self.fmu._call("setReal", slave.fmi2SetReal, slave.component, self._vr, self.n,
                       self._buffer)

"""Loading and driving FMI 2.0 and 3.0 co-simulation FMUs through fmpy (``FMU2Slave``,
``FMU3Slave``; the version is the model description's, :data:`APIS`).

- FMUs are extracted once per content hash into a fixed cache folder, so numba's on-disk cache
  inside the bundled package stays warm across runs (docs/pythonfmu-notes.md);
- every log message of an instance is captured (for error reports) and FMI call failures
  become :class:`FmuError` with the status and the instance's last messages;
- interface variables are exchanged with one vector ``getReal``/``setReal`` call per FMU
  (``getFloat64``/``setFloat64`` in FMI 3.0).
"""

from __future__ import annotations

import atexit
import hashlib
import os
import shutil
import tempfile
import xml.etree.ElementTree as ET
import zipfile
import zlib
from ctypes import byref
from pathlib import Path

# numpy, scipy.sparse.linalg and numba are imported before any pythonfmu FMU is loaded: this
# avoids the intermittent abort at exit of docs/pythonfmu-notes.md (B5).
import numpy as np
import scipy.sparse.linalg  # noqa: F401
import numba  # noqa: F401
# So are the installed pythonfmu and pythonfmu3: a Python FMU loaded in this process puts its
# resources, with its own copy of them (no binaries inside), first on sys.path, and an FMU
# built later in the process would take that copy's builder and carry no binary.
import pythonfmu  # noqa: F401
import pythonfmu3  # noqa: F401

from pantocosim.core.errors import PantocosimError
from pantocosim.core.registry import Registry
from pantocosim.core.user_cache import cache_root, cache_warning, describe

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

    return cache_root() / "fmus"


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
    if marker.exists():
        damage = _damage(fmu_path, target)
        if damage is None:
            return target
        cache_warning(target, f"extracted FMU damaged ({damage})", "extracting it again")
        shutil.rmtree(target, ignore_errors=True)
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        part = target.parent / f".{target.name}.{os.getpid()}.partial"
        shutil.rmtree(part, ignore_errors=True)
        extract(str(fmu_path), unzipdir=str(part))
        (part / ".complete").write_text("ok\n")
        _move_into_place(part, target)
        if _damage(fmu_path, target) is None:
            return target
    except OSError as exc:
        cache_warning(target.parent, f"FMU not extracted there ({describe(exc)})",
                      "extracting into a temporary folder: make it a writable folder, free "
                      "space or set PANTOCOSIM_FMU_CACHE")
    scratch = Path(tempfile.mkdtemp(prefix=f"pantocosim-{fmu_path.stem}-"))
    atexit.register(shutil.rmtree, scratch, True)
    extract(str(fmu_path), unzipdir=str(scratch))
    return scratch


def _damage(fmu_path: Path, folder: Path) -> str | None:
    """What differs between the extracted ``folder`` and the archive ``fmu_path`` (each
    archived file's presence, size and CRC-32), or None."""
    with zipfile.ZipFile(fmu_path) as archive:
        for info in archive.infolist():
            if info.is_dir():
                continue
            path = folder / info.filename
            try:
                if path.stat().st_size != info.file_size:
                    return f"{info.filename}: size differs from the FMU's"
                crc = 0
                with open(path, "rb") as f:
                    for block in iter(lambda: f.read(1 << 20), b""):
                        crc = zlib.crc32(block, crc)
            except OSError as exc:
                return f"{info.filename}: {describe(exc)}"
            if crc != info.CRC:
                return f"{info.filename}: content differs from the FMU's"
    return None


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


class Fmi2Api:
    """What differs between the FMI versions, for FMI 2.0 (fmpy's ``FMU2Slave``)."""

    #: the setter of each variable type of the model description
    SETTERS = {"Real": "setReal", "Integer": "setInteger", "Boolean": "setBoolean",
               "String": "setString"}
    REAL = "Real"

    @staticmethod
    def make(md, unzip: Path, instance_name: str):
        from fmpy.fmi2 import FMU2Slave

        return FMU2Slave(guid=md.guid, unzipDirectory=str(unzip),
                         modelIdentifier=md.coSimulation.modelIdentifier,
                         instanceName=instance_name)

    @staticmethod
    def instantiate(slave, instance_name: str) -> None:
        slave.instantiate(callbacks=_callbacks(), loggingOn=True)

    @staticmethod
    def enter_initialization(fmu, start_time: float) -> None:
        fmu._call("setupExperiment", lambda: fmu.slave.setupExperiment(startTime=start_time))
        fmu._call("enterInitializationMode", fmu.slave.enterInitializationMode)

    @staticmethod
    def do_step(slave, t: float, h: float) -> None:
        # noSetFMUStatePriorToCurrentPoint false: the master may roll back
        slave.doStep(t, h, 0)

    @staticmethod
    def real_calls(slave):
        """(get, set) of Real values through C arrays: fn(instance, vr, n, values)."""
        return ((lambda vr, n, buf: slave.fmi2GetReal(slave.component, vr, n, buf)),
                (lambda vr, n, buf: slave.fmi2SetReal(slave.component, vr, n, buf)))

    @staticmethod
    def c_types():
        from fmpy.fmi2 import fmi2Real, fmi2ValueReference

        return fmi2ValueReference, fmi2Real

    STATE_CALLS = {"get": "getFMUstate", "set": "setFMUstate", "free": "freeFMUstate"}


class Fmi3Api(Fmi2Api):
    """FMI 3.0 (fmpy's ``FMU3Slave``): Float64 and Int32 variables, the start time given to
    fmi3EnterInitializationMode, fmi3DoStep's flags."""

    SETTERS = {"Float64": "setFloat64", "Int32": "setInt32", "Boolean": "setBoolean",
               "String": "setString"}
    REAL = "Float64"

    @staticmethod
    def make(md, unzip: Path, instance_name: str):
        from fmpy.fmi3 import FMU3Slave

        return FMU3Slave(guid=md.instantiationToken, unzipDirectory=str(unzip),
                         modelIdentifier=md.coSimulation.modelIdentifier,
                         instanceName=instance_name)

    @staticmethod
    def instantiate(slave, instance_name: str) -> None:
        def log_message(env, status, category, message):
            text = message.decode("utf-8", "replace") if message else ""
            _LOGS.setdefault(instance_name, []).append((int(status), text))

        slave.instantiate(loggingOn=True, logMessage=log_message)

    @staticmethod
    def enter_initialization(fmu, start_time: float) -> None:
        fmu._call("enterInitializationMode",
                  lambda: fmu.slave.enterInitializationMode(startTime=start_time))

    @staticmethod
    def do_step(slave, t: float, h: float) -> None:
        slave.doStep(t, h, False)

    @staticmethod
    def real_calls(slave):
        return ((lambda vr, n, buf: slave.fmi3GetFloat64(slave.component, vr, n, buf, n)),
                (lambda vr, n, buf: slave.fmi3SetFloat64(slave.component, vr, n, buf, n)))

    @staticmethod
    def c_types():
        from fmpy.fmi3 import fmi3Float64, fmi3ValueReference

        return fmi3ValueReference, fmi3Float64

    STATE_CALLS = {"get": "getFMUState", "set": "setFMUState", "free": "freeFMUState"}


#: the model description's fmiVersion -> its API
APIS = Registry("FMI API", "fmiVersion")
APIS.add("2.0", Fmi2Api)
APIS.add("3.0", Fmi3Api)


def fmi_version(fmu_path: str | Path) -> int:
    """The FMI major version of an FMU file (its model description's ``fmiVersion``)."""
    with zipfile.ZipFile(fmu_path) as z:
        return int(float(ET.fromstring(z.read("modelDescription.xml")).get("fmiVersion")))


class FmuInstance:
    """One instantiated co-simulation FMU (FMI 2.0 or 3.0, as its model description says)
    with name-based variable access."""

    def __init__(self, fmu_path: str | Path, instance_name: str):
        from fmpy import read_model_description

        self.path = Path(fmu_path)
        self.name = instance_name
        unzip = extract_cached(self.path)
        self.md = read_model_description(str(unzip))
        if self.md.fmiVersion not in APIS:
            raise FmuError(f"{self.name} ({self.path.name}): FMI {self.md.fmiVersion}: "
                           f"accepted: {', '.join(APIS)}", instance=self.name)
        self.api = APIS[self.md.fmiVersion]
        self.variables = {v.name: v for v in self.md.modelVariables}
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        _LOGS[instance_name] = []
        try:
            self.slave = self.api.make(self.md, unzip, instance_name)
        except Exception as exc:     # fmpy: no library for this platform, one that fails to load
            raise FmuError(f"{self.name} ({self.path}): its binary cannot be loaded: "
                           f"{str(exc).splitlines()[0] if str(exc) else type(exc).__name__}",
                           instance=self.name) from None
        self.fatal = False
        self._call("instantiate", lambda: self.api.instantiate(self.slave, instance_name))
        self.t = 0.0

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

    #: the Python value of each variable type
    CONVERT = {"Real": float, "Float64": float, "Integer": int, "Int32": int, "Boolean": bool,
               "String": str}

    def set_start_values(self, values: dict) -> None:
        """Set parameters of any type by name (before exitInitializationMode)."""
        for name, value in values.items():
            ref = self.refs([name])
            kind = self.variables[name].type
            setter = getattr(self.slave, self.api.SETTERS[kind])
            x = self.CONVERT[kind](value)
            self._call(f"{self.api.SETTERS[kind]}({name})", lambda: setter(ref, [x]))

    def initialize(self, start_values: dict, start_time: float = 0.0) -> None:
        self.api.enter_initialization(self, start_time)
        self.set_start_values(start_values)
        self._call("exitInitializationMode", self.slave.exitInitializationMode)
        self.t = start_time

    def reals(self, names) -> "RealVector":
        """The Real variables ``names``, exchanged together (:class:`RealVector`)."""
        return RealVector(self, self.refs(names))

    def set_real(self, refs: list[int], values) -> None:
        RealVector(self, refs).set(values)

    def get_real(self, refs: list[int]) -> np.ndarray:
        return RealVector(self, refs).get()

    def do_step(self, t: float, h: float) -> None:
        self._call(lambda: f"doStep(t = {t:.6g}, h = {h:.3g})", self.api.do_step, self.slave,
                   t, h)

    # ------------------------------------------------------------------ state
    def _state_call(self, what: str, *args):
        name = self.api.STATE_CALLS[what]
        return self._call(name, getattr(self.slave, name), *args)

    def get_state(self):
        return self._state_call("get")

    def set_state(self, state) -> None:
        self._state_call("set", state)

    def free_state(self, state) -> None:
        self._state_call("free", state)

    def terminate(self) -> None:
        if self.fatal:
            return
        try:
            self.slave.terminate()
            self.slave.freeInstance()
        except Exception:  # noqa: BLE001 - best effort at shutdown
            pass


class RealVector:
    """Real (FMI 3.0: Float64) variables of one FMU read or written together every step: the
    value references and the C arrays of fmpy's ``fmi2GetReal``/``fmi2SetReal``
    (``fmi3GetFloat64``/``fmi3SetFloat64``) are built once, so an exchange allocates nothing
    but the values it returns."""

    def __init__(self, fmu: FmuInstance, refs: list[int]):
        ref_type, real_type = fmu.api.c_types()
        self.fmu = fmu
        self.refs = list(refs)
        self.n = len(self.refs)
        self._vr = (ref_type * self.n)(*self.refs)
        self._buffer = (real_type * self.n)()
        #: the C buffer seen as a numpy array (no copy)
        self._values = np.ctypeslib.as_array(self._buffer) if self.n else np.zeros(0)
        self._get, self._set = fmu.api.real_calls(fmu.slave)
        self._names = (f"get{fmu.api.REAL}", f"set{fmu.api.REAL}")

    def get(self) -> np.ndarray:
        """The current values (a new array)."""
        self.fmu._call(self._names[0], self._get, self._vr, self.n, self._buffer)
        return self._values.copy()

    def set(self, values) -> None:
        """Set the variables to ``values`` (one per reference)."""
        self._values[:] = values
        self.fmu._call(self._names[1], self._set, self._vr, self.n, self._buffer)

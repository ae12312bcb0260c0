"""Shared machinery of the project's slaves (thin adapters over model objects).

The slaves are version-neutral: an FMU's slave class mixes in the front of its FMI version
(:mod:`pantocosim.fmi.front`: pythonfmu for FMI 2.0, pythonfmu3 for FMI 3.0), which makes the
variables, logs with the version's statuses and names the version's calls. Everything below
holds for both versions; the FMI 2.0 names stand for their FMI 3.0 counterparts.

Works around the pythonfmu 0.7.0 behaviours of docs/pythonfmu-notes.md:
- no exception may escape a callback (the wrapper turns it into fmi2Fatal and may crash): every
  callback is guarded; bad input is logged and reported as fmi2Discard from ``do_step``
  (pythonfmu offers no other non-fatal error status);
- the default FMU state holds registered variables only: the full internal state is saved
  (deep copies) and serialised with pickle;
- several FMUs bundle the same package ``pantocosim``; a process imports it once, so each
  slave checks that the imported package is the one it was built with (build stamp);
- units and a UnitDefinitions section are added to the model description;
- outputs are declared ``initial="exact"`` so that ``fmpy validate`` passes;
- the FMI 2.0 state machine is checked here (:meth:`GuardedSlave.do_step`): a step after
  fmi2Terminate, a step size <= 0 and a communication point other than the FMU's current time
  are discarded with a message; FMU states carry the model and instance they belong to.

Non-OK statuses reachable from Python (pythonfmu 0.7.0, src/pythonfmu/PySlaveInstance.cpp and
fmi2.cpp): only ``do_step`` returning False gives one (fmi2Discard). A Python exception in any
callback gives fmi2Fatal and releases the slave (``handle_py_exception``), and the return values
of the setters and of ``_set_fmu_state`` are ignored (fmi2OK). So a refused call (wrongly typed
or unknown variable, a fixed parameter set after initialisation, a foreign FMU state) is logged
with status fmi2Error, not applied, and the next doStep returns fmi2Discard naming it.
"""

from __future__ import annotations

import math
import operator
import pickle
import traceback
import uuid
import zipfile
from pathlib import Path
from typing import Any, Callable

import numpy as np
import pantocosim
from pantocosim.core.stamp import package_stamp

from ..core.errors import PantocosimError, ParameterError
from ..core.hht import HHTIntegrator
from .front import Status
from .variables import VariableTable

STAMP_FILE = "pantocosim_build_stamp.txt"

#: accepted distance between doStep's communication point and the FMU's current time:
#: TIME_RTOL * max(1, |t|) + STEP_RTOL * h. The FMU's time after a step is the master's
#: ``t + h`` (as pythonfmu's fmi2LastSuccessfulTime), so only the master's own rounding
#: (``t += h``, ``t = t0 + k h``, integer nanoseconds) has to be absorbed: a few ulps of t.
TIME_RTOL = 1e-9
STEP_RTOL = 1e-6

_INT32 = 2 ** 31



def fmi_type(var) -> str:
    """The neutral kind of a variable (Real, Integer, Boolean, String; given by the front)."""
    return var.kind


#: the Python value of each FMI type, as pythonfmu's own getters return it
_NORMALISE = {"Real": float, "Integer": int, "Boolean": bool, "String": str}
_GET_DEFAULT = {"Real": float("nan"), "Integer": 0, "Boolean": False, "String": ""}


def lossless(value, kind: str):
    """``value`` (float, int, bool or str) as FMI type ``kind`` if nothing is lost (Real 2.0
    -> Integer 2, Real 1.0 -> Boolean true, Integer -> Real, ...), else None. Strings never
    convert to or from the other types."""
    if isinstance(value, str) or kind == "String":
        return value if isinstance(value, str) and kind == "String" else None
    x = float(value)  # exact for bool, int32 and float
    if kind == "Real":
        return x
    if not math.isfinite(x) or x != math.floor(x):
        return None
    if kind == "Integer":
        return int(x) if -_INT32 <= x < _INT32 else None
    if kind == "Boolean":
        return bool(x) if x in (0.0, 1.0) else None
    return None


def bundled_stamp(fmu: str | Path) -> str | None:
    """The package stamp an FMU file was built with (None: not a pantocosim FMU, or
    unreadable)."""
    try:
        with zipfile.ZipFile(fmu) as z:
            return z.read(f"resources/{STAMP_FILE}").decode().strip()
    except (KeyError, OSError, zipfile.BadZipFile):
        return None


class GuardedSlave:
    """Base of the project's slaves: variable helpers, guarded callbacks, full state. A
    version-neutral core: an FMU's class mixes in a front (:func:`front.slave_class`)."""

    author = "pantocosim"
    license = "MIT"
    #: the declared variables (:mod:`pantocosim.fmi.variables`) :meth:`declare` registers
    variables = VariableTable(())
    #: start values baked in by the FMU build (a scenario's FMUs, master/ssp.py):
    #: variable name -> value, given by :meth:`apply_start_values` at the end of __init__
    start_values: dict = {}

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self.author, self.license = GuardedSlave.author, GuardedSlave.license
        self._units: set[str] = set()
        #: first error found in parameters or inputs; do_step reports it as a discard
        self._error: str | None = None
        #: names of internal attributes that make up the FMU state besides registered vars
        self._state_attributes: list[str] = []
        self._in_initialization = False
        self._logged_fallbacks: set[str] = set()
        #: refused calls since the last doStep; the next doStep discards naming them
        self._refused: list[str] = []
        #: value references of the Real variables of :meth:`real`: each is kept in its
        #: attribute, which its getter reads outside initialisation mode
        self._attribute_reals: set[int] = set()
        #: the FMU's current time: the start time, then the end of each accepted step
        self._time = 0.0
        self._terminated = False
        self._model_id = self._model_identity()
        # The instance an in-memory FMU state belongs to. pythonfmu 0.7.0 passes the address of
        # the C++ component's logger as ``logger`` (PySlaveInstance.cpp ``initialize``); it is
        # unique among live instances and survives fmi2Reset (which re-creates this object).
        logger = kwargs.get("logger")
        self._instance_id = (f"component@{logger:#x}" if isinstance(logger, int) and logger
                             else uuid.uuid4().hex)

    def _model_identity(self) -> str:
        """Class, preset and build stamp: FMU states are exchanged only within one model."""
        cls = type(self)
        stamp = ""
        try:
            if self.resources and (Path(self.resources) / STAMP_FILE).exists():
                stamp = (Path(self.resources) / STAMP_FILE).read_text().strip()
        except OSError:
            pass
        preset = getattr(self, "preset", None)
        return (f"{cls.__module__}.{cls.__qualname__}"
                + (f" preset {preset!r}" if preset else "") + (f" build {stamp}" if stamp else ""))

    @property
    def initialised(self) -> bool:
        """True after a successful fmi2ExitInitializationMode (fixed parameters are frozen)."""
        return False

    # ------------------------------------------------------------------ initialisation mode
    def enter_initialization_mode(self):
        self._in_initialization = True

    def exit_initialization_mode(self):
        self._in_initialization = False
        self.guarded("initialisation", self.initialise)
        return True

    def initialise(self) -> None:
        """Build the model and its start from the parameters (subclasses)."""

    def update_initial_outputs(self) -> None:
        """Outputs a master may read in initialisation mode, from the parameters and inputs
        set so far (subclasses; called by the output getters in that mode)."""

    def _output_value(self, name: str):
        if self._in_initialization:
            try:
                self.update_initial_outputs()
            except Exception as exc:  # noqa: BLE001 - an early read; initialise() decides
                self.log(f"initialisation outputs not available yet: {exc}",
                         Status.warning)
        return getattr(self, name)

    # ------------------------------------------------------------------ variables
    def declare(self, context=None) -> None:
        """Register the variables of :attr:`variables`, in order (``context``: what a start
        that depends on the model reads, the preset's defaults)."""
        register = {"Real": lambda v, start: self.real(v.name, start, v.causality, v.unit,
                                                         v.meaning, v.tunable),
                    "Integer": lambda v, start: self.integer(v.name, start, v.meaning),
                    "Boolean": lambda v, start: self.boolean(v.name, start, v.meaning),
                    "String": lambda v, start: self.string(v.name, start, v.meaning)}
        for v in self.variables:
            if v.type != "Real" and v.causality != "parameter":
                raise ValueError(f"{v.name}: only Real variables are ports")
            register[v.type](v, v.start_value(context))

    def value(self, name: str):
        """The value of variable ``name`` as its type (a Real finite), checked against its
        declared range (ParameterError naming it)."""
        var = self.variables[name]
        x = getattr(self, name)
        if var.type == "Real":
            x = self.finite(name, x)
        elif var.type == "Integer":
            x = int(x)
        return var.checked(x)

    def real(self, name: str, value: float, causality: str, unit: str | None = None,
             description: str | None = None, tunable: bool = False) -> None:
        setattr(self, name, float(value))
        kwargs: dict[str, Any] = {"description": description, "unit": unit}
        if causality == "parameter":
            kwargs.update(causality="parameter", variability="tunable" if tunable else "fixed")
        elif causality == "output":
            kwargs.update(causality="output", variability="continuous", initial="exact",
                          getter=lambda: self._output_value(name))
        else:
            kwargs.update(causality="input" if causality == "input" else "local",
                          variability="continuous")
        if unit:
            self._units.add(unit)
        var = self.make_variable("Real", name, **kwargs)
        if "." not in name:
            self._attribute_reals.add(var.value_reference)

    def integer(self, name: str, value: int, description: str | None = None) -> None:
        setattr(self, name, int(value))
        self.make_variable("Integer", name, "parameter", "fixed", description=description)

    def boolean(self, name: str, value: bool, description: str | None = None) -> None:
        setattr(self, name, bool(value))
        self.make_variable("Boolean", name, "parameter", "fixed", description=description)

    def string(self, name: str, value: str, description: str | None = None) -> None:
        setattr(self, name, str(value))
        self.make_variable("String", name, "parameter", "fixed", description=description)

    def given_or_start(self, name: str, given) -> float:
        """The value of input ``name``, or its baked start value where the master passed none
        (``given(value)`` false: masters that never set an input pass 0, CoFmuPy sets every
        input to 0 before initialisation)."""
        value = getattr(self, name)
        if given(value) or name not in self.start_values:
            return value
        if name not in self._logged_fallbacks:
            self._logged_fallbacks.add(name)
            self.log(f"{name} = {value!r} was not given by the master: using its start value "
                     f"{self.start_values[name]!r} (this FMU's scenario)", Status.warning)
        return self.start_values[name]

    def apply_start_values(self) -> None:
        """Give the baked :attr:`start_values` to the registered variables."""
        names = {v.name for v in self.vars.values()}
        for name, value in self.start_values.items():
            if name not in names:
                raise KeyError(f"start value for an unknown variable {name!r}")
            setattr(self, name, type(getattr(self, name))(value))

    # ------------------------------------------------------------------ errors
    def fail(self, message: str, status: Status = Status.error) -> None:
        """Record and log an error; every later do_step returns fmi2Discard."""
        if self._error is None:
            self._error = message
        self.log(message, status)

    #: True when the FMU's embedding library gives each call its own status (pantocosim's
    #: library, ``pantocosim.fmi.embedding``): a refused call then returns fmi2Error itself.
    #: pythonfmu's library returns fmi2OK for it, so the next doStep also reports it.
    statuses_per_call = False

    def refuse(self, message: str) -> None:
        """A call that is not applied: logged (fmi2Error); with pythonfmu's library also
        reported by the next do_step (fmi2Discard)."""
        if not self.statuses_per_call:
            self._refused.append(message)
        self.log(message, Status.error)

    # ------------------------------------------------------------------ FMI state machine
    def setup_experiment(self, start_time, stop_time=None, tolerance=None):
        try:
            t0 = float(start_time)
            if not math.isfinite(t0):
                self.fail(f"{self.fmi_call('SetupExperiment')}: startTime = "
                          f"{start_time!r}: must be finite")
                return
            self._time = t0
        except Exception as exc:  # noqa: BLE001 - nothing may escape a callback
            self.fail(f"{self.fmi_call('SetupExperiment')}: {type(exc).__name__}: {exc}")

    def terminate(self):
        self._terminated = True

    def time_tolerance(self, step_size: float) -> float:
        return TIME_RTOL * max(1.0, abs(self._time)) + STEP_RTOL * abs(step_size)

    def _do_step_call(self, t: float, h: float) -> str:
        """The doStep call named in a refusal."""
        return f"{self.fmi_call('DoStep')}(t = {t!r}, h = {h!r})"

    def _step_refusal(self, t: float, h: float) -> str | None:
        """Why doStep(t, h) is not taken (FMI state machine), or None."""
        _do_step_call = self._do_step_call
        if self._terminated:
            return (f"{_do_step_call(t, h)} after {self.fmi_call('Terminate')}: only "
                    f"{self.fmi_call('Reset')} or {self.fmi_call('FreeInstance')} may follow")
        if self._refused:
            msgs, self._refused = self._refused, []
            more = f" (and {len(msgs) - 3} more)" if len(msgs) > 3 else ""
            return (f"{_do_step_call(t, h)} not taken: refused since the last step: "
                    + " | ".join(msgs[:3]) + more)
        if not (math.isfinite(h) and h > 0.0):
            return f"{_do_step_call(t, h)}: the communication step size must be finite and > 0"
        if not math.isfinite(t) or abs(t - self._time) > self.time_tolerance(h):
            return (f"{_do_step_call(t, h)}: the communication point {t!r} is not the FMU's "
                    f"current time {self._time!r} (the start time, the end of the last "
                    "accepted step, or the time of the FMU state set last)")
        return None

    def do_step(self, current_time, step_size):
        """The FMI 2.0 checks, then :meth:`advance`; the FMU's time moves on success."""
        try:
            t, h = float(current_time), float(step_size)
            problem = self._step_refusal(t, h)
            if problem is not None:
                self.log(problem, Status.discard)
                return False
            ok = bool(self.advance(t, h))
            if ok:
                self._time = t + h
            return ok
        except Exception as exc:  # noqa: BLE001 - nothing may escape a callback
            self.log(f"{self._do_step_call(current_time, step_size)}: "
                     f"{type(exc).__name__}: {exc}", Status.discard)
            return False

    def advance(self, current_time: float, step_size: float) -> bool:
        """The model's step from ``current_time`` (checked) by ``step_size`` (> 0)."""
        raise NotImplementedError

    # ------------------------------------------------------------------ typed get/set
    def _not_settable(self, var) -> str | None:
        if var.setter is None:
            return "it cannot be set"
        if not self.initialised:
            return None
        if var.causality.name == "input":
            return None
        if var.causality.name == "parameter" and var.variability.name == "tunable":
            return None
        return (f"a {var.variability.name} {var.causality.name} can only be set before "
                f"{self.fmi_call('ExitInitializationMode')} (FMI {self.fmi_version}.0)")

    def _set(self, call: str, kind: str, vrs, values) -> None:
        for vr, value in zip(vrs, values):
            try:
                var = self.vars.get(vr)
                if var is None:
                    self.refuse(f"{call}: unknown value reference {vr}: not applied")
                    continue
                what = f"{call}: {var.name!r} (vr {vr}, {self.TYPE_NAMES[fmi_type(var)]})"
                why = self._not_settable(var)
                if why:
                    self.refuse(f"{what}: {why}: {value!r} not applied")
                    continue
                target = fmi_type(var)
                x = value if target == kind else lossless(value, target)
                if x is None:
                    names = self.TYPE_NAMES
                    self.refuse(f"{what}: the {names[kind]} value {value!r} does not convert "
                                f"to {names[target]} without loss: not applied")
                    continue
                var.setter(x)
            except Exception as exc:  # noqa: BLE001 - nothing may escape a callback
                self.refuse(f"{call}: vr {vr}: {type(exc).__name__}: {exc}: not applied")

    def _get(self, call: str, kind: str, vrs) -> list:
        out = []
        for vr in vrs:
            x = None
            try:
                var = self.vars.get(vr)
                if var is None:
                    self.refuse(f"{call}: unknown value reference {vr}")
                else:
                    source = fmi_type(var)
                    value = _NORMALISE[source](var.getter())
                    x = value if source == kind else lossless(value, kind)
                    if x is None:
                        names = self.TYPE_NAMES
                        self.refuse(f"{call}: {var.name!r} (vr {vr}) is a {names[source]} "
                                    f"variable; its value {value!r} does not convert to "
                                    f"{names[kind]} without loss")
            except Exception as exc:  # noqa: BLE001 - nothing may escape a callback
                self.refuse(f"{call}: vr {vr}: {type(exc).__name__}: {exc}")
            out.append(_GET_DEFAULT[kind] if x is None else x)
        return out

    def _fast_access(self):
        """(getters of every Real variable, setters of the Real inputs) by value reference:
        the per-step path of fmi2GetReal/fmi2SetReal, which needs none of the checks of
        :meth:`_get`/:meth:`_set` (registered once, at instantiation)."""
        fast = self.__dict__.get("_fast_real")
        if fast is None or fast[2] != len(self.vars):
            reals = [(vr, v) for vr, v in self.vars.items() if fmi_type(v) == "Real"]
            fast = self._fast_real = (
                {vr: v.getter for vr, v in reals},
                {vr: v.setter for vr, v in reals
                 if v.causality.name == "input" and v.setter is not None},
                len(self.vars))
        return fast

    def set_real(self, vrs, values):
        setters = self._fast_access()[1]
        if all(vr in setters for vr in vrs):      # inputs: settable in every state
            try:
                for vr, value in zip(vrs, values):
                    setters[vr](float(value))
                return
            except Exception:  # noqa: BLE001 - the checked path says what went wrong
                pass
        self._set(self.fmi_call("SetReal"), "Real", vrs, values)

    def set_integer(self, vrs, values):
        self._set(self.fmi_call("SetInteger"), "Integer", vrs, values)

    def set_boolean(self, vrs, values):
        self._set(self.fmi_call("SetBoolean"), "Boolean", vrs, values)

    def set_string(self, vrs, values):
        self._set(self.fmi_call("SetString"), "String", vrs, values)

    def get_real(self, vrs):
        try:
            if not self._in_initialization:
                read = self._attribute_reader(vrs)
                if read is not None:
                    return read(self.__dict__)
            getters = self._fast_access()[0]
            return [float(getters[vr]()) for vr in vrs]
        except Exception:  # noqa: BLE001 - the checked path says what went wrong
            return self._get(self.fmi_call("GetReal"), "Real", vrs)

    #: lists of value references whose attribute reader is kept (a master reads a few
    #: fixed lists every step)
    MAX_READERS = 32

    def _attribute_reader(self, vrs):
        """A function of the instance's ``__dict__`` giving the values of the Real variables
        ``vrs`` (one C-level lookup), kept per list of references; None if one of them is not
        a variable of :meth:`real` (kept in its attribute, read by its getter outside
        initialisation mode)."""
        key = tuple(vrs)
        readers = self.__dict__.setdefault("_attribute_readers", {})
        if key not in readers:
            if len(readers) >= self.MAX_READERS:
                readers.clear()
            readers[key] = self._make_attribute_reader(key)
        return readers[key]

    def _make_attribute_reader(self, vrs: tuple):
        if not vrs or not all(vr in self._attribute_reals for vr in vrs):
            return None
        names = [self.vars[vr].name for vr in vrs]
        if len(names) == 1:
            name = names[0]
            return lambda d: [float(d[name])]
        lookup = operator.itemgetter(*names)
        return lambda d: list(map(float, lookup(d)))

    def get_integer(self, vrs):
        return self._get(self.fmi_call("GetInteger"), "Integer", vrs)

    def get_boolean(self, vrs):
        return self._get(self.fmi_call("GetBoolean"), "Boolean", vrs)

    def get_string(self, vrs):
        return self._get(self.fmi_call("GetString"), "String", vrs)

    def guarded(self, what: str, fn: Callable[[], Any]) -> bool:
        """Run ``fn`` and turn any exception into a logged error (never escapes)."""
        try:
            fn()
            return True
        except Exception as exc:  # noqa: BLE001 - nothing may escape a callback

            if isinstance(exc, PantocosimError):
                self.fail(f"{what}: {exc}")
            else:
                self.fail(f"{what}: {type(exc).__name__}: {exc}\n{traceback.format_exc()}")
            return False

    def check_build_stamp(self) -> None:
        """The imported ``pantocosim`` must be the one bundled in this FMU (its build stamp)."""
        if not self.resources:
            return
        stamp_file = Path(self.resources) / STAMP_FILE
        if not stamp_file.exists():
            return
        built = stamp_file.read_text().strip()
        here = package_stamp()
        if built != here:
            self.fail(f"this FMU was built with pantocosim {built} but the process imported "
                      f"pantocosim {here} from {Path(pantocosim.__file__).parent}: rebuild the "
                      f"FMUs (build_fmus.py) or run them in a process without another pantocosim")

    def substeps(self) -> int:
        """``n_substeps``, checked: 1 .. :data:`~.variables.MAX_SUBSTEPS` (its declared
        range)."""
        return self.value("n_substeps")

    @staticmethod
    def finite(name: str, value: float) -> float:
        x = float(value)
        if not math.isfinite(x):
            raise ParameterError(name, value, "must be finite")
        return x

    # ------------------------------------------------------------------ state
    def _get_fmu_state(self) -> dict:
        try:
            state = {"model": self._model_id, "instance": self._instance_id,
                     "instance_name": self.instance_name, "deserialized": False,
                     "time": self._time, "initialised": self.initialised,
                     "vars": self._variable_values(),
                     "error": self._error}
            for name in self._state_attributes:
                state[name] = self._copy_attribute(name)
            return state
        except Exception as exc:  # noqa: BLE001 - nothing may escape a callback
            msg = f"{self.fmi_call('GetFMUstate')}: {type(exc).__name__}: {exc}"
            self.refuse(msg)
            return {"invalid": msg}

    def _state_refusal(self, state) -> str | None:
        """Why ``state`` may not be set into this instance, or None. A state belongs to one
        model (class, preset, build); an in-memory state also to one instance, a deserialized
        one may go into any instance of its model (FMI 2.0)."""
        if not isinstance(state, dict):
            return "not a pantocosim FMU state"
        if "invalid" in state:
            return str(state["invalid"])
        if "model" not in state:
            return "not a pantocosim FMU state"
        if state["model"] != self._model_id:
            return f"the state is one of model {state['model']}; this FMU is {self._model_id}"
        if state.get("initialised") is False and self.initialised:
            return (f"the state was taken before {self.fmi_call('ExitInitializationMode')} "
                    "and this instance "
                    "is initialised (its model is built): set it before initialisation, or "
                    "take the state after it")
        if not state.get("deserialized") and state.get("instance") != self._instance_id:
            return (f"in-memory state of another instance ({state.get('instance_name')!r}; "
                    f"this is {self.instance_name!r}); copy a state between instances with "
                    f"{self.fmi_call('SerializeFMUstate')} and "
                    f"{self.fmi_call('DeSerializeFMUstate')}")
        return None

    def _set_fmu_state(self, state) -> None:
        try:
            problem = self._state_refusal(state)
        except Exception as exc:  # noqa: BLE001 - nothing may escape a callback
            problem = f"{type(exc).__name__}: {exc}"
        if problem is not None:
            self.refuse(f"{self.fmi_call('SetFMUstate')}: {problem}: state not applied")
            return
        try:
            self._set_variable_values(*state["vars"])
            self._error = state.get("error")
            self._time = float(state["time"])
            for name in self._state_attributes:
                self._restore_attribute(name, state[name])
        except Exception as exc:  # noqa: BLE001 - partly applied: the instance is unusable
            self.fail(f"{self.fmi_call('SetFMUstate')}: {type(exc).__name__}: {exc}")

    def _state_variables(self) -> tuple:
        """(names, read): every variable's name in registration order and a function giving
        their values as a tuple, read from the attribute each is kept in (:meth:`real`,
        :meth:`integer`) in one C-level lookup; the getter only for a variable without one.
        Variables are registered once, in ``__init__``: built on first use. The independent
        variable (FMI 3.0's time) is the state's ``time``, not one of them."""
        cached = self.__dict__.get("_state_var_reader")
        if cached is not None and cached[2] == len(self.vars):
            return cached[:2]
        variables = [v for v in self.vars.values() if v.causality.name != "independent"]
        names = tuple(v.name for v in variables)
        d = self.__dict__
        if len(names) > 1 and all(n in d for n in names):
            lookup = operator.itemgetter(*names)

            def read():
                return lookup(d)
        else:
            pairs = [(v.name, v.getter) for v in variables]

            def read():
                return tuple(d[n] if n in d else getter() for n, getter in pairs)
        self._state_var_reader = (names, read, len(self.vars))
        return names, read

    def _variable_values(self) -> tuple:
        """(names, values) of every variable for the FMU state. A master saves the state
        every communication step, so this is cheap (no per-variable Python code)."""
        names, read = self._state_variables()
        return names, read()

    def _set_variable_values(self, names, values) -> None:
        """Put back :meth:`_variable_values` (the variables that can be set)."""
        setters = self.__dict__.get("_state_var_setters")
        if setters is None or len(setters) != len(self.vars):
            setters = self._state_var_setters = {v.name: v.setter for v in self.vars.values()}
        for name, value in zip(names, values):
            setter = setters.get(name)
            if setter is not None:
                setter(value)

    @staticmethod
    def _copy_value(value):
        """A deep copy of a state value (arrays and plain numbers without pickling)."""
        if value is None or isinstance(value, (bool, int, float, str)):
            return value
        if type(value) is np.ndarray and value.dtype != object:
            return value.copy()
        return pickle.loads(pickle.dumps(value))

    def _copy_attribute(self, name: str):
        """Deep copy of an internal attribute for the FMU state (override for big objects)."""
        return self._copy_value(getattr(self, name))

    def _restore_attribute(self, name: str, value) -> None:
        setattr(self, name, self._copy_value(value))

    @staticmethod
    def _picklable_state(state: dict) -> dict:
        return state

    @classmethod
    def _fmu_state_to_bytes(cls, state: dict) -> bytes:
        try:
            return pickle.dumps(cls._picklable_state(state), protocol=pickle.HIGHEST_PROTOCOL)
        except Exception as exc:  # noqa: BLE001 - nothing may escape a callback
            return pickle.dumps({"invalid": f"{cls.fmi_call('SerializeFMUstate')} failed: "
                                            f"{type(exc).__name__}: {exc}"})

    @staticmethod
    def _fmu_state_from_bytes(data: bytes) -> dict:
        """The state, marked as deserialized (it may go into any instance of its model)."""
        try:
            state = pickle.loads(data)
        except Exception as exc:  # noqa: BLE001 - nothing may escape a callback
            return {"invalid": f"the bytes are not a pantocosim FMU state "
                               f"({type(exc).__name__}: {exc})"}
        if isinstance(state, dict):
            state["deserialized"] = True
        return state


class IntegratorSlave(GuardedSlave):
    """A slave that advances one HHT integrator (``self._integ``): the integrator's state
    (q, v, a, t, previous forces, model sets, factorization) is part of the FMU state; a state
    set before initialisation is applied at its end (:meth:`apply_pending_state`)."""

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self._integ = None
        self._pending_integ_state = None

    def apply_pending_state(self) -> None:
        if self._pending_integ_state is not None:
            self._integ.set_state(self._pending_integ_state)
            self._pending_integ_state = None

    @property
    def _integ_state(self):
        return None if self._integ is None else self._integ.get_state()

    @_integ_state.setter
    def _integ_state(self, state):
        if state is None:
            return
        if self._integ is None:
            self._pending_integ_state = state  # applied at the end of initialisation
        else:
            self._integ.set_state(state)

    def _copy_attribute(self, name):
        if name == "_integ_state":
            return self._integ_state  # get_state copies (the factorization is immutable)
        return super()._copy_attribute(name)

    def _restore_attribute(self, name, value):
        if name == "_integ_state":
            self._integ_state = value  # set_state copies
            return
        super()._restore_attribute(name, value)

    @property
    def initialised(self) -> bool:
        return self._integ is not None

    @staticmethod
    def _picklable_state(state: dict) -> dict:
        out = dict(state)
        if out.get("_integ_state") is not None:
            out["_integ_state"] = HHTIntegrator.picklable_state(out["_integ_state"])
        return out

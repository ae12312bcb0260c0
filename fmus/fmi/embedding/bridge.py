"""Python side of the FMUs' embedding libraries (``fmi2_export.c``, ``fmi3_export.c``).

Each FMU carries a copy of this module as ``resources/pantocosim_fmi2_bridge.py`` (FMI 2.0)
or ``resources/pantocosim_fmi3_bridge.py`` (FMI 3.0); the library imports it and calls
:func:`instantiate` with its FMI version, then the methods of :class:`Adapter` (FMI 2.0) or
:class:`Adapter3` (FMI 3.0), one per FMI call. Every method returns ``(status, value)``: the FMI status of the call (the
most severe message the slave logged during it, ``STATUS_LOG_FLAG`` added when messages are
waiting in :meth:`Adapter.take_log`) and the call's result. Nothing raises: an exception of the
slave is the call's fmi2Error, with its message.

It uses the standard library only: it runs before the model package is chosen
(:func:`forget_vanished_modules`).
"""

from __future__ import annotations

import importlib
import os
import sys
import traceback
import xml.etree.ElementTree as ET
from pathlib import Path

OK, WARNING, DISCARD, ERROR = 0, 1, 2, 3
STATUS_LOG_FLAG = 16
#: fmi2StatusKind
DO_STEP_STATUS, PENDING_STATUS, LAST_SUCCESSFUL_TIME, TERMINATED = range(4)
#: modules of an FMU: the model package and the generated slave modules
FMU_MODULES = ("pantocosim", "pantocosim_fmu_")


def forget_vanished_modules() -> None:
    """Drop from ``sys.modules`` the FMU modules whose file no longer exists: an earlier
    FMU's extraction folder, deleted since (fmpy's ``simulate_fmu`` deletes it), so that this
    FMU imports its own copy."""
    for name, module in list(sys.modules.items()):
        if not name.startswith(FMU_MODULES):
            continue
        path = getattr(module, "__file__", None)
        if path and not os.path.exists(path):
            del sys.modules[name]


#: the model description's attribute the instantiate call's token must equal, by FMI version
TOKEN_ATTRIBUTE = {2: "guid", 3: "instantiationToken"}


def check_guid(resources: Path, guid: str, fmi: int = 2) -> None:
    """The GUID (FMI 2.0) or instantiation token (FMI 3.0) given to instantiate must be the
    model description's."""
    md = resources.parent / "modelDescription.xml"
    if not guid or not md.is_file():
        return
    attribute = TOKEN_ATTRIBUTE[fmi]
    expected = ET.parse(md).getroot().get(attribute)
    if expected and expected != guid:
        name = "fmuGUID" if fmi == 2 else attribute
        raise ValueError(f"{name} {guid!r} is not this FMU's ({expected!r} in "
                         f"{md}): the model description and the binary do not match")


def import_slave_module(name: str, resources: Path):
    """The FMU's slave module, from its own resources (an older copy of the same name, from
    another file, is replaced)."""
    own = resources / f"{name}.py"
    loaded = sys.modules.get(name)
    if loaded is not None:
        path = Path(getattr(loaded, "__file__", "") or "")
        if path != own and (not path.is_file() or path.read_bytes() != own.read_bytes()):
            del sys.modules[name]
    return importlib.import_module(name)


def slave_class(module, fmi: int = 2):
    """The deepest slave class of FMI version ``fmi`` (a core with that version's front)
    defined in ``module``."""
    found = [c for c in vars(module).values()
             if isinstance(c, type) and getattr(c, "fmi_version", None) == fmi
             and c.__module__ == module.__name__]
    if not found:
        raise ImportError(f"{module.__name__} defines no FMI {fmi}.0 slave class")
    return max(found, key=lambda c: len(c.__mro__))


def instantiate(resources: str, instance_name: str, guid: str, visible: int,
                component_id: int, fmi: int = 2) -> "Adapter":
    """The adapter of a new instance of FMI version ``fmi`` (fmi2Instantiate,
    fmi3InstantiateCoSimulation); raises with the reason."""
    res = Path(resources)
    while sys.path.count(resources) > 1:           # the library inserts it at every call
        sys.path.reverse()
        sys.path.remove(resources)
        sys.path.reverse()
    forget_vanished_modules()
    check_guid(res, guid, fmi)
    module = import_slave_module((res / "slavemodule.txt").read_text().strip(), res)
    kwargs = dict(instance_name=instance_name, resources=resources, visible=bool(visible),
                  logger=component_id)
    return ADAPTERS[fmi](slave_class(module, fmi), kwargs)


def _level(status) -> int:
    return int(getattr(status, "value", status))


class Adapter:
    """One FMU instance: the slave object and the status rules of FMI 2.0."""

    def __init__(self, cls, kwargs: dict):
        self._cls, self._kwargs = cls, kwargs
        #: the FMI call names of the slave's version (its front's)
        self.call_name = cls.fmi_call
        self._log: list[tuple[int, str, str]] = []
        self._strings: list[str] = []
        self._last_step = OK
        #: a discarded step asks the master to stop (fmi2Terminated), as a master that
        #: cannot roll back would otherwise retry the same step for ever; the next
        #: accepted step, an FMU state set or a reset clears it
        self._discarded = False
        self.slave = None
        self._new_slave()

    def _new_slave(self) -> None:
        self.slave = self._cls(**self._kwargs)
        # refusals are answered by the refused call's own status (see GuardedSlave.refuse)
        self.slave.statuses_per_call = True

    # ------------------------------------------------------------------ statuses
    def _status(self, floor: int = OK, call: str = "") -> int:
        """The call's status from the messages the slave logged (moved to our log)."""
        queue = self.slave.log_queue if self.slave is not None else []
        status = floor
        for msg in queue:
            level = _level(msg.status)
            status = max(status, level)
            self._log.append((min(level, ERROR), msg.category or "logAll", str(msg.msg)))
        queue.clear()
        if status == DISCARD and call != "do_step":
            status = ERROR                           # fmi2Discard is doStep's alone
        status = min(status, ERROR)                  # the instance stays usable
        return status | (STATUS_LOG_FLAG if self._log else 0)

    def _error(self, call: str, exc: BaseException) -> int:
        detail = "".join(traceback.format_exception(type(exc), exc, exc.__traceback__, limit=4))
        self._log.append((ERROR, "logStatusError", f"{call}: {type(exc).__name__}: {exc}\n"
                                                    f"{detail}"))
        return self._status(ERROR, call)

    def _call(self, call: str, fn, *args, floor: int = OK):
        try:
            value = fn(*args)
        except Exception as exc:  # noqa: BLE001 - every failure is the call's status
            return self._error(call, exc), None
        return self._status(floor, call), value

    def take_log(self) -> list[tuple[int, str, str]]:
        out, self._log = self._log, []
        return out

    def status(self):
        return self._status(), None

    # ------------------------------------------------------------------ life cycle
    def set_debug_logging(self, on: int, categories: list[str]):
        known = set(getattr(self.slave, "log_categories", {}))
        unknown = [c for c in categories if c not in known]
        if unknown:
            self._log.append((ERROR, "logStatusError",
                              f"{self.call_name('SetDebugLogging')}: unknown log categories "
                              f"{unknown}; known: {sorted(known)}"))
            return self._status(ERROR), None
        return self._status(), None

    def setup_experiment(self, tol_defined, tol, start, stop_defined, stop):
        return self._call(self.call_name("SetupExperiment"), self.slave.setup_experiment,
                          start, stop if stop_defined else None, tol if tol_defined else None)

    def enter_initialization_mode(self):
        return self._call(self.call_name("EnterInitializationMode"),
                          self.slave.enter_initialization_mode)

    def exit_initialization_mode(self):
        return self._call(self.call_name("ExitInitializationMode"),
                          self.slave.exit_initialization_mode)

    def terminate(self):
        return self._call(self.call_name("Terminate"), self.slave.terminate)

    def reset(self):
        self._discarded = False
        return self._call(self.call_name("Reset"), self._new_slave)

    def free(self):
        self.slave = None
        return self._status(), None

    def cancel_step(self):
        self._log.append((ERROR, "logStatusError", "fmi2CancelStep: not supported: fmi2DoStep "
                          "never returns fmi2Pending"))
        return self._status(ERROR), None

    # ------------------------------------------------------------------ stepping
    def do_step(self, t: float, h: float):
        try:
            ok = bool(self.slave.do_step(t, h))
        except Exception as exc:  # noqa: BLE001 - the guarded slave never raises
            self._last_step, self._discarded = ERROR, True
            return self._error(self.call_name("DoStep"), exc), None
        if not ok and not self.slave.log_queue:
            self._log.append((DISCARD, "logStatusDiscard",
                              f"{self.call_name('DoStep')}(t = {t!r}, h = {h!r}): step not "
                              "taken"))
        status = self._status(OK if ok else DISCARD, "do_step")
        self._last_step = status & ~STATUS_LOG_FLAG
        self._discarded = self._last_step == DISCARD
        return status, None

    def status_of(self, kind: int):
        s = self.slave
        if kind == DO_STEP_STATUS:
            return self._status(), self._last_step
        if kind == LAST_SUCCESSFUL_TIME:
            return self._status(), float(getattr(s, "_time", 0.0))
        if kind == TERMINATED:
            return self._status(), int(self._discarded or bool(
                getattr(s, "_terminated", False) or getattr(s, "_error", None)))
        self._log.append((DISCARD, "logStatusDiscard", f"status kind {kind}: not available"))
        return self._status(ERROR), None

    # ------------------------------------------------------------------ variables
    def get_real(self, vrs):
        return self._call(self.call_name("GetReal"), self.slave.get_real, vrs)

    def get_integer(self, vrs):
        return self._call(self.call_name("GetInteger"), self.slave.get_integer, vrs)

    def get_boolean(self, vrs):
        status, values = self._call(self.call_name("GetBoolean"), self.slave.get_boolean, vrs)
        return status, None if values is None else [int(bool(v)) for v in values]

    def get_string(self, vrs):
        status, values = self._call(self.call_name("GetString"), self.slave.get_string, vrs)
        self._strings = [] if values is None else [str(v) for v in values]
        return status, self._strings                 # kept: the host reads the pointers

    def set_real(self, vrs, values):
        return self._call(self.call_name("SetReal"), self.slave.set_real, vrs,
                          values)

    def set_integer(self, vrs, values):
        return self._call(self.call_name("SetInteger"), self.slave.set_integer, vrs,
                          values)

    def set_boolean(self, vrs, values):
        return self._call(self.call_name("SetBoolean"), self.slave.set_boolean, vrs,
                          [bool(v) for v in values])

    def set_string(self, vrs, values):
        return self._call(self.call_name("SetString"), self.slave.set_string, vrs,
                          values)

    # ------------------------------------------------------------------ FMU states
    def _checked_state(self, call: str, state):
        if isinstance(state, dict) and "invalid" in state:
            self._log.append((ERROR, "logStatusError", f"{call}: {state['invalid']}"))
            return self._status(ERROR), None
        return self._status(), state

    def get_state(self):
        call = self.call_name("GetFMUstate")
        status, state = self._call(call, self.slave._get_fmu_state)
        if status & ~STATUS_LOG_FLAG >= DISCARD:
            return status, None
        return self._checked_state(call, state)

    def set_state(self, state):
        status = self._call(self.call_name("SetFMUstate"), self.slave._set_fmu_state, state)
        if status[0] & ~STATUS_LOG_FLAG < DISCARD:
            self._discarded = False
        return status

    def serialize(self, state):
        status, data = self._call(self.call_name("SerializeFMUstate"),
                                  self._cls._fmu_state_to_bytes, state)
        if data is not None and not isinstance(data, bytes):
            data = bytes(data)
        return status, data

    def deserialize(self, data: bytes):
        call = self.call_name("DeSerializeFMUstate")
        status, state = self._call(call, self._cls._fmu_state_from_bytes, data)
        if status & ~STATUS_LOG_FLAG >= DISCARD:
            return status, None
        return self._checked_state(call, state)


class Adapter3(Adapter):
    """One FMI 3.0 co-simulation instance: the FMI 2.0 rules where FMI 3.0 keeps them, and
    what FMI 3.0 changes: the start time comes with fmi3EnterInitializationMode, fmi3DoStep
    returns its flags and the last successful time with its status, and an instance made with
    ``eventModeUsed`` passes through event mode (the FMU has no events of its own: its
    discrete states never need an update, and it never asks for event handling)."""

    _event_mode_used = False
    #: instantiated, initialisation (set by the calls), event, step
    _mode = "instantiated"

    def use_event_mode(self, used: int):
        self._event_mode_used = bool(used)
        return self._status(), None

    def _refused(self, call: str, why: str):
        self._log.append((ERROR, "logStatusError", f"{call}: {why}"))
        return self._status(ERROR), None

    def enter_initialization_mode(self, tol_defined=0, tol=0.0, start=0.0, stop_defined=0,
                                  stop=0.0):
        def enter():
            self.slave.setup_experiment(start, stop if stop_defined else None,
                                        tol if tol_defined else None)
            self.slave.enter_initialization_mode()

        self._mode = "initialisation"
        return self._call("fmi3EnterInitializationMode", enter)

    def exit_initialization_mode(self):
        result = super().exit_initialization_mode()
        self._mode = "event" if self._event_mode_used else "step"
        return result

    def reset(self):
        self._mode = "instantiated"
        return super().reset()

    def enter_event_mode(self):
        if not self._event_mode_used:
            return self._refused("fmi3EnterEventMode", "the instance was made with "
                                 "eventModeUsed = false")
        if self._mode not in ("step", "event"):
            return self._refused("fmi3EnterEventMode", "only after "
                                 "fmi3ExitInitializationMode")
        self._mode = "event"
        return self._status(), None

    def update_discrete_states(self):
        """(status, (discreteStatesNeedUpdate, terminateSimulation,
        nominalsOfContinuousStatesChanged, valuesOfContinuousStatesChanged,
        nextEventTimeDefined, nextEventTime))."""
        if self._mode != "event":
            return self._refused("fmi3UpdateDiscreteStates", "only in event mode")
        s = self.slave
        final = bool(getattr(s, "_terminated", False) or getattr(s, "_error", None))
        return self._status(), (0, int(final), 0, 0, 0, 0.0)

    def enter_step_mode(self):
        if self._mode != "event":
            return self._refused("fmi3EnterStepMode", "only in event mode (after "
                                 "fmi3ExitInitializationMode with eventModeUsed, or "
                                 "fmi3EnterEventMode)")
        self._mode = "step"
        return self._status(), None

    def do_step(self, t: float, h: float):
        """(status, (eventHandlingNeeded, terminateSimulation, earlyReturn,
        lastSuccessfulTime)). The FMU has no events and never returns early; a discarded
        step asks to terminate only when the instance cannot take any further step (a
        failed initialisation, a step after fmi3Terminate): other discards leave the choice
        to the master (roll back and retry, or stop)."""
        s = self.slave
        if self._mode == "event":
            status, _ = self._refused("fmi3DoStep", "in event mode: call fmi3EnterStepMode "
                                      "first")
            return status, (0, 0, 0, float(getattr(s, "_time", t)))
        status, _ = super().do_step(t, h)
        failed = (status & ~STATUS_LOG_FLAG) >= DISCARD
        final = bool(getattr(s, "_terminated", False) or getattr(s, "_error", None))
        return status, (0, int(failed and final), 0, float(getattr(s, "_time", t)))


#: FMI major version -> the adapter of its instances
ADAPTERS = {2: Adapter, 3: Adapter3}

"""Shared machinery of the project's pythonfmu slaves (thin adapters over model objects).

Works around the pythonfmu 0.7.0 behaviour measured in design/fmi-toolchain.md:
- no exception may escape a callback (the wrapper turns it into fmi2Fatal and may crash): every
  callback is guarded; bad input is logged and reported as fmi2Discard from ``do_step``
  (pythonfmu offers no other non-fatal error status);
- the default FMU state holds registered variables only: the full internal state is saved
  (deep copies) and serialised with pickle;
- several FMUs bundle the same package ``pantocosim``; a process imports it once, so each
  slave checks that the imported package is the one it was built with (build stamp);
- units and a UnitDefinitions section are added to the model description;
- outputs are declared ``initial="exact"`` so that ``fmpy validate`` passes.
"""

from __future__ import annotations

import hashlib
import math
import pickle
import traceback
from pathlib import Path
from typing import Any, Callable
from xml.etree.ElementTree import Element, SubElement

from pythonfmu.enums import Fmi2Causality, Fmi2Initial, Fmi2Status, Fmi2Variability
from pythonfmu.fmi2slave import Fmi2Slave
from pythonfmu.variables import Boolean, Integer, Real, String

STAMP_FILE = "pantocosim_build_stamp.txt"


def package_stamp(package_dir: str | Path | None = None) -> str:
    """SHA-256 over the model package's source and data files (relative path + content); the
    ``master`` subpackage of an installed package is not part of the model (FMUs do not
    bundle it)."""
    if package_dir is None:
        import pantocosim

        package_dir = Path(pantocosim.__file__).resolve().parent
    root = Path(package_dir)
    h = hashlib.sha256()
    for f in sorted(root.rglob("*")):
        rel = f.relative_to(root)
        if rel.parts[0] == "master":
            continue
        if f.suffix in (".py", ".toml") and "__pycache__" not in f.parts and f.is_file():
            h.update(rel.as_posix().encode())
            h.update(b"\0")
            h.update(f.read_bytes())
            h.update(b"\0")
    return h.hexdigest()[:16]


def bundled_stamp(fmu: str | Path) -> str | None:
    """The package stamp an FMU file was built with (None: not a pantocosim FMU, or
    unreadable)."""
    import zipfile

    try:
        with zipfile.ZipFile(fmu) as z:
            return z.read(f"resources/{STAMP_FILE}").decode().strip()
    except (KeyError, OSError, zipfile.BadZipFile):
        return None


class UnitReal(Real):
    """A Real variable with a ``unit`` attribute."""

    def __init__(self, name: str, unit: str | None = None, **kwargs):
        super().__init__(name, **kwargs)
        self.unit = unit

    def to_xml(self) -> Element:
        node = super().to_xml()
        if self.unit:
            node.find("Real").set("unit", self.unit)
        return node


class GuardedSlave(Fmi2Slave):
    """Base of the project's slaves: variable helpers, guarded callbacks, full state."""

    author = "pantocosim"
    license = "MIT"
    #: start values baked in by the FMU build (a scenario's FMUs, master/fmu_scenario.py):
    #: variable name -> value, given by :meth:`apply_start_values` at the end of __init__
    start_values: dict = {}

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        self._units: set[str] = set()
        #: first error found in parameters or inputs; do_step reports it as a discard
        self._error: str | None = None
        #: names of internal attributes that make up the FMU state besides registered vars
        self._state_attributes: list[str] = []
        self._in_initialization = False

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
                         Fmi2Status.warning)
        return getattr(self, name)

    # ------------------------------------------------------------------ variables
    def real(self, name: str, value: float, causality: str, unit: str | None = None,
             description: str | None = None, tunable: bool = False) -> None:
        setattr(self, name, float(value))
        kwargs: dict[str, Any] = {"description": description}
        if causality == "parameter":
            kwargs.update(causality=Fmi2Causality.parameter,
                          variability=Fmi2Variability.tunable if tunable
                          else Fmi2Variability.fixed)
        elif causality == "input":
            kwargs.update(causality=Fmi2Causality.input, variability=Fmi2Variability.continuous)
        elif causality == "output":
            kwargs.update(causality=Fmi2Causality.output, variability=Fmi2Variability.continuous,
                          initial=Fmi2Initial.exact,
                          getter=lambda: self._output_value(name))
        else:
            kwargs.update(causality=Fmi2Causality.local, variability=Fmi2Variability.continuous)
        if unit:
            self._units.add(unit)
        self.register_variable(UnitReal(name, unit=unit, **kwargs))

    def integer(self, name: str, value: int, description: str | None = None) -> None:
        setattr(self, name, int(value))
        self.register_variable(Integer(name, causality=Fmi2Causality.parameter,
                                       variability=Fmi2Variability.fixed,
                                       description=description))

    def boolean(self, name: str, value: bool, description: str | None = None) -> None:
        setattr(self, name, bool(value))
        self.register_variable(Boolean(name, causality=Fmi2Causality.parameter,
                                       variability=Fmi2Variability.fixed,
                                       description=description))

    def string(self, name: str, value: str, description: str | None = None) -> None:
        setattr(self, name, str(value))
        self.register_variable(String(name, causality=Fmi2Causality.parameter,
                                      variability=Fmi2Variability.fixed,
                                      description=description))

    def apply_start_values(self) -> None:
        """Give the baked :attr:`start_values` to the registered variables."""
        names = {v.name for v in self.vars.values()}
        for name, value in self.start_values.items():
            if name not in names:
                raise KeyError(f"start value for an unknown variable {name!r}")
            setattr(self, name, type(getattr(self, name))(value))

    def to_xml(self, model_options: dict[str, str] = dict()) -> Element:
        root = super().to_xml(model_options)
        # every output is a state output (no direct feedthrough within a step): declaring it
        # lets masters that check algebraic loops (OMSimulator) see there is none
        for unknown in root.iterfind("ModelStructure/Outputs/Unknown"):
            unknown.set("dependencies", "")
        if self._units:
            units = Element("UnitDefinitions")
            for u in sorted(self._units):
                SubElement(units, "Unit", {"name": u})
            index = [child.tag for child in root].index("CoSimulation") + 1
            root.insert(index, units)
        return root

    # ------------------------------------------------------------------ errors
    def fail(self, message: str, status: Fmi2Status = Fmi2Status.error) -> None:
        """Record and log an error; the next do_step returns fmi2Discard."""
        if self._error is None:
            self._error = message
        self.log(message, status)

    def guarded(self, what: str, fn: Callable[[], Any]) -> bool:
        """Run ``fn`` and turn any exception into a logged error (never escapes)."""
        try:
            fn()
            return True
        except Exception as exc:  # noqa: BLE001 - nothing may escape a callback
            from pantocosim.core.errors import PantocosimError

            if isinstance(exc, PantocosimError):
                self.fail(f"{what}: {exc}")
            else:
                self.fail(f"{what}: {type(exc).__name__}: {exc}\n{traceback.format_exc()}")
            return False

    def check_build_stamp(self) -> None:
        """The imported ``pantocosim`` must be the one bundled in this FMU (design §2)."""
        if not self.resources:
            return
        stamp_file = Path(self.resources) / STAMP_FILE
        if not stamp_file.exists():
            return
        built = stamp_file.read_text().strip()
        here = package_stamp()
        if built != here:
            import pantocosim

            self.fail(f"this FMU was built with pantocosim {built} but the process imported "
                      f"pantocosim {here} from {Path(pantocosim.__file__).parent}: rebuild the "
                      f"FMUs (build_fmus.py) or run them in a process without another pantocosim")

    @staticmethod
    def finite(name: str, value: float) -> float:
        x = float(value)
        if not math.isfinite(x):
            from pantocosim.core.errors import ParameterError

            raise ParameterError(name, value, "must be finite")
        return x

    # ------------------------------------------------------------------ state
    def _get_fmu_state(self) -> dict:
        state = {"vars": {v.name: v.getter() for v in self.vars.values()},
                 "error": self._error}
        for name in self._state_attributes:
            state[name] = self._copy_attribute(name)
        return state

    def _set_fmu_state(self, state: dict) -> None:
        for v in self.vars.values():
            if v.name in state["vars"] and v.setter is not None:
                v.setter(state["vars"][v.name])
        self._error = state.get("error")
        for name in self._state_attributes:
            self._restore_attribute(name, state[name])

    def _copy_attribute(self, name: str):
        """Deep copy of an internal attribute for the FMU state (override for big objects)."""
        return pickle.loads(pickle.dumps(getattr(self, name)))

    def _restore_attribute(self, name: str, value) -> None:
        setattr(self, name, pickle.loads(pickle.dumps(value)))

    @staticmethod
    def _fmu_state_to_bytes(state: dict) -> bytes:
        return pickle.dumps(state, protocol=pickle.HIGHEST_PROTOCOL)

    @staticmethod
    def _fmu_state_from_bytes(data: bytes) -> dict:
        return pickle.loads(data)


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

    @staticmethod
    def _fmu_state_to_bytes(state: dict) -> bytes:
        from pantocosim.core.hht import HHTIntegrator

        out = dict(state)
        if out.get("_integ_state") is not None:
            out["_integ_state"] = HHTIntegrator.picklable_state(out["_integ_state"])
        return pickle.dumps(out, protocol=pickle.HIGHEST_PROTOCOL)

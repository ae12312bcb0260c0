"""What a sweep axis (or a ``[set]`` entry) changes: the registry of axis kinds.

An axis name is resolved, in this order, to

- a run option (``coupling``, ``accelerator``): how the case is run, not the scenario;
- ``pantograph``: the model of every pantograph of the scenario;
- ``catenary.<dotted path>``: a field of the catenary definition (``catenary.contact_wire.
  tension``); the case runs on its own copy of the definition;
- a shortcut for a ``[simulation]`` field (``catenary_model``, ``dt``, ...);
- any other dotted path: a field of the scenario (``speed_kmh``, ``spans``, ``catenary``,
  ``contact.stiffness``, ``pantographs.1.position_m``; integers index arrays).

Values are checked where they land: run options here, scenario and catenary fields by the
scenario and catenary validation of the case (:mod:`.spec`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from pantocosim.core.errors import ParameterError
from pantocosim.master.coupling import ACCELERATORS, SCHEME_NAMES

#: couplings a case can run with: the monolithic solve or a co-simulation scheme (its
#: aliases too, as in ``pantocosim run``) -> the name it runs under
COUPLINGS = {"monolithic": "monolithic", **SCHEME_NAMES}

#: axis names that stand for a field of the scenario's [simulation] table
SIMULATION_SHORTCUTS = ("catenary_model", "modal_cutoff_hz", "dt", "alpha", "duration_s",
                        "newton_rtol", "coupling_rtol")


@dataclass
class CaseInputs:
    """The inputs of one case while it is being built: scenario and catenary TOML tables
    (``catenary`` stays None until a catenary field is changed) and the run options."""
    scenario: dict
    run: dict
    catenary: dict | None = None
    catenary_source: str | None = None
    changed_catenary: list = field(default_factory=list)


def set_path(data, path: list[str], value) -> None:
    """Set ``data[path[0]][path[1]]... = value``; missing tables are created, integer
    segments index arrays. Raises ValueError with the reason."""
    node = data
    for i, key in enumerate(path):
        last = i == len(path) - 1
        if isinstance(node, list):
            if not key.isdigit() or int(key) >= len(node):
                raise ValueError(f"'{key}' is no index of an array of {len(node)} entries")
            key = int(key)
        elif not isinstance(node, dict):
            raise ValueError(f"'{'.'.join(path[:i])}' is a value, not a table")
        elif not last and key not in node:
            node[key] = {}
        if last:
            node[key] = value
        else:
            node = node[key]


class Axis:
    """One kind of axis: ``apply(case, value)`` changes the case inputs."""

    def __init__(self, name: str):
        self.name = name

    def apply(self, case: CaseInputs, value) -> None:  # pragma: no cover - abstract
        raise NotImplementedError


class RunOption(Axis):
    def __init__(self, name: str, choices):
        super().__init__(name)
        self.choices = sorted(choices)

    def apply(self, case, value):
        if value not in self.choices:
            raise ValueError(f"must be one of {self.choices}")
        case.run[self.name] = value


class PantographModel(Axis):
    def apply(self, case, value):
        if not isinstance(value, str):
            raise ValueError("must be a pantograph preset name or parameter file")
        pans = case.scenario.get("pantographs")
        if not isinstance(pans, list) or not pans:
            raise ValueError("the base scenario has no [[pantographs]]")
        for p in pans:
            if isinstance(p, dict):
                p["model"] = value
                p.pop("fmu", None)   # the FMU of the new model, not of the base one


class CatenaryField(Axis):
    def __init__(self, name: str):
        super().__init__(name)
        self.path = name.split(".")[1:]

    def apply(self, case, value):
        if case.catenary is None:
            raise ValueError("the scenario's catenary could not be loaded")
        set_path(case.catenary, self.path, value)
        case.changed_catenary.append(self.name)


class ScenarioField(Axis):
    def __init__(self, name: str, path: list[str]):
        super().__init__(name)
        self.path = path

    def apply(self, case, value):
        set_path(case.scenario, self.path, value)


def make_axis(name: str) -> Axis:
    """The axis kind of ``name`` (module docstring); raises ParameterError for names that
    cannot be a path."""
    parts = name.split(".")
    if not name or any(not p for p in parts):
        raise ParameterError("axis", name, "must be a name or a dotted path")
    if name == "coupling":
        return RunOption(name, COUPLINGS)
    if name == "accelerator":
        return RunOption(name, ACCELERATORS)
    if name == "pantograph":
        return PantographModel(name)
    if parts[0] == "catenary" and len(parts) > 1:
        return CatenaryField(name)
    if name in SIMULATION_SHORTCUTS:
        return ScenarioField(name, ["simulation", name])
    return ScenarioField(name, parts)

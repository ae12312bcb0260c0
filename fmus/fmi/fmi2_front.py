"""FMI 2.0 front of the project's slaves (pythonfmu 0.7.0): variables, statuses, call names
and model description of FMI 2.0 (:mod:`pantocosim.fmi.front`)."""

from __future__ import annotations

from xml.etree.ElementTree import Element, SubElement

from pythonfmu.enums import Fmi2Causality, Fmi2Initial, Fmi2Status, Fmi2Variability
from pythonfmu.fmi2slave import Fmi2Slave
from pythonfmu.variables import Boolean, Integer, Real, String


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


_CLASSES = {"Real": UnitReal, "Integer": Integer, "Boolean": Boolean, "String": String}


class Fmi2Front(Fmi2Slave):
    fmi_version = 2
    TYPE_NAMES = {"Real": "Real", "Integer": "Integer", "Boolean": "Boolean",
                  "String": "String"}

    def make_variable(self, kind: str, name: str, causality: str, variability: str,
                      initial: str | None = None, unit: str | None = None,
                      description: str | None = None, getter=None):
        kwargs = dict(causality=Fmi2Causality[causality],
                      variability=Fmi2Variability[variability], description=description)
        if initial:
            kwargs["initial"] = Fmi2Initial[initial]
        if getter is not None:
            kwargs["getter"] = getter
        if kind == "Real":
            kwargs["unit"] = unit
        var = _CLASSES[kind](name, **kwargs)
        var.kind = kind
        self.register_variable(var)
        return var

    @staticmethod
    def fmi_call(name: str) -> str:
        return "fmi2" + name

    def log(self, msg: str, status=Fmi2Status.ok, category=None):
        super().log(msg, Fmi2Status(int(status)), category)

    def to_xml(self, model_options: dict[str, str] = dict()) -> Element:
        root = super().to_xml(model_options)
        # every output is a state output (no direct feedthrough within a step): declaring it
        # lets masters that check algebraic loops (OMSimulator) see there is none
        for unknown in root.iterfind("ModelStructure/Outputs/Unknown"):
            unknown.set("dependencies", "")
        units = sorted(getattr(self, "_units", ()))
        if units:
            node = Element("UnitDefinitions")
            for u in units:
                SubElement(node, "Unit", {"name": u})
            index = [child.tag for child in root].index("CoSimulation") + 1
            root.insert(index, node)
        return root

"""FMI 2.0 front of the project's slaves (pythonfmu 0.7.0): variables, statuses, call names
and model description of FMI 2.0 (:mod:`pantocosim.fmi.front`)."""

from __future__ import annotations

from xml.etree.ElementTree import Element, SubElement

from pythonfmu.enums import Fmi2Causality, Fmi2Initial, Fmi2Status, Fmi2Variability
from pythonfmu.fmi2slave import Fmi2Slave
from pythonfmu.variables import Boolean, Integer, Real, String

from .front import VariableMaker


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


class Fmi2Front(VariableMaker, Fmi2Slave):
    fmi_version = 2
    VARIABLE_CLASSES = {"Real": UnitReal, "Integer": Integer, "Boolean": Boolean,
                        "String": String}
    ENUMS = (Fmi2Causality, Fmi2Variability, Fmi2Initial)
    TYPE_NAMES = {"Real": "Real", "Integer": "Integer", "Boolean": "Boolean",
                  "String": "String"}

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

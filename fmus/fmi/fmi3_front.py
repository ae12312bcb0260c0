"""FMI 3.0 front of the project's slaves (pythonfmu3 0.3.4): variables, statuses, call names
and model description of FMI 3.0 (:mod:`pantocosim.fmi.front`).

The ports keep their FMI 2.0 names and units: Real is Float64, Integer is Int32. pythonfmu3's
builder reads start values through ``get_float64``/``get_int32``, which are the core's typed
getters here; the embedding library calls the core through its bridge (``fmi3_export.c``).
"""

from __future__ import annotations

from xml.etree.ElementTree import Element, SubElement

from pythonfmu3.enums import Fmi3Causality, Fmi3Initial, Fmi3Status, Fmi3Variability
from pythonfmu3.fmi3slave import Fmi3Slave
from pythonfmu3.variables import Boolean, Float64, Int32, String

from .front import VariableMaker

#: FMI 2.0 call names (without prefix) whose FMI 3.0 name differs
_RENAMED = {"SetReal": "SetFloat64", "GetReal": "GetFloat64", "SetInteger": "SetInt32",
            "GetInteger": "GetInt32", "GetFMUstate": "GetFMUState",
            "SetFMUstate": "SetFMUState", "FreeFMUstate": "FreeFMUState",
            "SerializeFMUstate": "SerializeFMUState",
            "DeSerializeFMUstate": "DeserializeFMUState",
            "SetupExperiment": "EnterInitializationMode"}


class Fmi3Front(VariableMaker, Fmi3Slave):
    fmi_version = 3
    VARIABLE_CLASSES = {"Real": Float64, "Integer": Int32, "Boolean": Boolean, "String": String}
    ENUMS = (Fmi3Causality, Fmi3Variability, Fmi3Initial)
    TYPE_NAMES = {"Real": "Float64", "Integer": "Int32", "Boolean": "Boolean",
                  "String": "String"}

    def __init__(self, **kwargs):
        super().__init__(**kwargs)
        # FMI 3.0 wants its independent variable declared: the FMU's time (the start time,
        # then the end of the last accepted step; the core's ``_time``)
        self.make_variable("Real", "time", "independent", "continuous", unit="s",
                           description="time", getter=lambda: self.__dict__.get("_time", 0.0))

    @staticmethod
    def fmi_call(name: str) -> str:
        return "fmi3" + _RENAMED.get(name, name)

    def log(self, msg: str, status=Fmi3Status.ok, category=None, debug: bool = False):
        super().log(msg, Fmi3Status(int(status)), category, debug)

    # pythonfmu3's builder reads the start values through these
    def get_float64(self, vrs):
        return self.get_real(vrs)

    def get_int32(self, vrs):
        return self.get_integer(vrs)

    def set_float64(self, vrs, values):
        return self.set_real(vrs, values)

    def set_int32(self, vrs, values):
        return self.set_integer(vrs, values)

    def to_xml(self, model_options: dict[str, str] = dict()) -> Element:
        root = super().to_xml(model_options)
        # event mode is supported (the embedding library's bridge); the FMU has no events of
        # its own
        root.find("CoSimulation").set("hasEventMode", "true")
        # every output is a state output (no direct feedthrough within a step)
        for output in root.iterfind("ModelStructure/Output"):
            output.set("dependencies", "")
        units = sorted(getattr(self, "_units", ()))
        if units:
            node = Element("UnitDefinitions")
            for u in units:
                SubElement(node, "Unit", {"name": u})
            index = [child.tag for child in root].index("CoSimulation") + 1
            root.insert(index, node)
        return root

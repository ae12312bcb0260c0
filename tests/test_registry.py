"""The registry idiom (pantocosim.core.registry): names, stable codes, one-line refusals; the
codes an FMU parameter or a file stores never change."""

import pytest

from pantocosim.core.errors import ParameterError
from pantocosim.core.registry import Registry


def test_todays_codes_never_change():
    from pantocosim.catenary.models import CATENARY_MODELS, MODEL_NAMES, model_code, model_name

    # the catenary FMU's Integer catenary_model: FMUs already built keep these meanings
    assert CATENARY_MODELS.codes() == {"nonlinear": 0, "linear": 1, "modal": 2}
    assert MODEL_NAMES == ("nonlinear", "linear", "modal")
    assert [model_code(n) for n in MODEL_NAMES] == [0, 1, 2]
    assert [model_name(c) for c in (2, 1, 0)] == ["modal", "linear", "nonlinear"]


def test_the_fmu_parameter_offers_the_codes():
    from pantocosim.fmi.catenary_ports import VARIABLES

    choices = VARIABLES["catenary_model"].range
    assert choices.codes == {0: "nonlinear", 1: "linear", 2: "modal"}


def test_a_new_entry_takes_a_new_code_and_keeps_the_others():
    reg = Registry("thing", "thing_model", coded=True)
    reg.add("a", 1, code=0)
    reg.add("c", 3, code=5)
    reg.add("b", 2, code=1)
    assert reg.codes() == {"a": 0, "b": 1, "c": 5} and list(reg) == ["a", "c", "b"]
    assert reg.name_of(5) == "c" and reg.code("b") == 1
    with pytest.raises(ValueError, match="code 1 taken by 'b'"):
        reg.add("d", 4, code=1)
    with pytest.raises(ValueError, match="a code is required"):
        reg.add("d", 4)
    with pytest.raises(ParameterError, match=r"thing_model.*must be 0 \(a\), 5 \(c\), 1 \(b\)"):
        reg.name_of(2)
    with pytest.raises(ParameterError, match="must be one of a, c, b"):
        reg.entry("z")


def test_registration_is_checked():
    reg = Registry("law")

    @reg.register("x")
    class X:
        pass

    assert reg.entry("x") is X and "x" in reg and len(reg) == 1
    with pytest.raises(ValueError, match="registered twice"):
        reg.add("x", int)
    with pytest.raises(ValueError, match="not used"):
        reg.add("y", int, code=3)
    with reg.swapped("x", int):
        assert reg["x"] is int
    assert reg["x"] is X
    other = reg.copy()
    other.add("y", float)
    assert "y" not in reg

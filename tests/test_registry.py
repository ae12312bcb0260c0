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


def test_every_registry_uses_the_idiom():
    # a closed-form step is registered by the module of the model that declares it
    import pantocosim.catenary.linear  # noqa: F401
    import pantocosim.catenary.modal  # noqa: F401
    from pantocosim.catenary.models import CATENARY_MODELS
    from pantocosim.catenary.supports import SUPPORTS
    from pantocosim.core.stepper_contract import CLOSED_FORM_STEPS
    from pantocosim.fmi.embedding import EXPORTS
    from pantocosim.fmi.front import FRONTS
    from pantocosim.interaction.contact_laws import CONTACT_LAWS
    from pantocosim.master.cli import COMMANDS
    from pantocosim.master.coupling import ACCELERATORS, SCHEMES
    from pantocosim.master.fmu.build import FMI_BUILDS
    from pantocosim.master.fmu.runtime import APIS
    from pantocosim.pantograph.presets import MODEL_KINDS, PRESETS

    expected = {
        "catenary models": (CATENARY_MODELS, ["nonlinear", "linear", "modal"]),
        "closed-form steps": (CLOSED_FORM_STEPS, ["affine", "modal"]),
        "contact laws": (CONTACT_LAWS, ["constraint", "penalty"]),
        "supports": (SUPPORTS, ["fixed", "spring", "steady_arm"]),
        "schemes": (SCHEMES, ["jacobi", "gauss-seidel", "implicit"]),
        "accelerators": (ACCELERATORS, ["iqn-imvj", "iqn-ils", "aitken"]),
        "fronts": (FRONTS, [2, 3]), "exports": (EXPORTS, [2, 3]), "builds": (FMI_BUILDS, [2, 3]),
        "apis": (APIS, ["2.0", "3.0"]),
        "presets": (PRESETS, ["dsa380-rigid", "dsa380-flexible", "dsa380-lumped3",
                              "en50318-2mass"]),
        "pantograph model kinds": (MODEL_KINDS, ["chain", "rigid_model", ""]),
    }
    for what, (reg, names) in expected.items():
        assert isinstance(reg, Registry), what
        assert sorted(map(str, reg)) == sorted(map(str, names)), what
    assert len(COMMANDS) == 14 and isinstance(COMMANDS, Registry)


def test_the_cli_fails_loudly_on_a_missing_command_module(monkeypatch):
    from pantocosim.master import cli

    commands = cli.COMMANDS.copy()
    commands.add("ghost", "pantocosim.master.commands.ghost")
    monkeypatch.setattr(cli, "COMMANDS", commands)
    with pytest.raises(ModuleNotFoundError, match="pantocosim.master.commands.ghost"):
        cli.build_parser()

"""The open catenary assembly: the structure collects element sets through one protocol,
supports are classes behind a registry, and the worked example of docs/architecture.md
(run from the page itself, so that it cannot rot)."""

import re
import sys
import tomllib
import types
from pathlib import Path

import numpy as np
import pytest

from pantocosim.catenary import supports
from pantocosim.catenary.definition import DATA_DIR, parse_definition
from pantocosim.catenary.model import CatenaryModel
from pantocosim.core.errors import ParameterError
from pantocosim.core.params import load_toml

DOC = Path(__file__).resolve().parents[1] / "docs" / "architecture.md"


def _small(**tables):
    raw = load_toml(DATA_DIR / "en50318.toml")
    raw["spans"]["count"] = 3
    raw["geometry"]["element_size"] = 2.0
    raw.update(tables)
    return raw


def test_structure_collects_parts_and_outputs():
    m = CatenaryModel(parse_definition(_small(), "small.toml"))
    S = m.structure
    assert list(S.parts) == ["cables", "bars", "points", "springs"]
    out = S.outputs(m.x_static)
    assert set(out) == {"cables.tension", "bars.axial_force", "springs.force"}
    assert np.array_equal(out["bars.axial_force"], S.bars.axial_forces(m.x_static))
    assert out["cables.tension"].shape == (len(S.cables),)


def test_support_types_are_registered_and_validate_their_tables():
    assert {"fixed", "spring", "steady_arm"} <= set(supports.SUPPORTS)
    with pytest.raises(ParameterError) as exc:
        parse_definition(_small(messenger_support={"type": "steady_arm", "length": 1.0,
                                                   "mass": 1.0}), "bad.toml")
    assert exc.value.field == "messenger_support.type" and exc.value.value == "steady_arm"
    with pytest.raises(ParameterError) as exc:
        parse_definition(_small(contact_support={"type": "spring", "stiffness": -1.0}),
                         "bad.toml")
    assert exc.value.field == "contact_support.stiffness" and "bad.toml" in str(exc.value)


def test_worked_example_of_the_architecture_page(monkeypatch):
    text = DOC.read_text()
    code = re.findall(r"```python\n(.*?)```", text, re.S)[0]
    table = tomllib.loads(re.findall(r"```toml\n(.*?)```", text, re.S)[0])
    monkeypatch.setattr(supports.registry, "SUPPORTS", supports.SUPPORTS.copy())
    module = types.ModuleType("architecture_example")
    monkeypatch.setitem(sys.modules, module.__name__, module)
    exec(compile(code, str(DOC), "exec"), module.__dict__)
    assert "elastic_bracket" in supports.registry.SUPPORTS
    d = parse_definition(_small(**table), "bracket.toml")
    m = CatenaryModel(d)
    ic = m.initial_configuration
    assert ic.height_error < 1e-9 and ic.tension_error < 1e-9 and ic.residual < 1e-8
    S = m.structure
    assert len(S.springs.k) == 2 * (len(m.support_x) - 2)
    # the messenger sits at its design height over the intermediate masts
    mz = m.mesh.node_dofs[m.mesh.messenger_nodes, 2]
    xm = S.absolute(m.x_static)[m.mesh.node_dofs[m.mesh.messenger_nodes, 0]]
    at_mast = np.isin(np.round(xm, 6), np.round(m.support_x[1:-1], 6))
    assert np.allclose(m.x_static[mz][at_mast], d.contact_wire_height + d.system_height,
                       atol=1e-9)
    with pytest.raises(ParameterError, match="elastic_bracket"):
        parse_definition(_small(messenger_support={"type": "bracket"}), "bad.toml")

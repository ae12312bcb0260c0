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


def _random_state(m, rng, size=3e-3):
    n = m.n_dofs
    return (m.q_static + size * rng.standard_normal(n), rng.standard_normal(n),
            rng.standard_normal(n))


def test_compiled_residual_is_the_part_by_part_one_bit_for_bit():
    """CompiledForces (one call) against Structure.internal + the model's products, with
    slack droppers committed and taut ones slackening, with and without loads and tangent."""
    from pantocosim.core.newmark_residual import iterate_kinematics, weighted_residual
    m = CatenaryModel(parse_definition(_small(), "small.toml"), x0=(20.0,), speed=80.0)
    parts = CatenaryModel(parse_definition(_small(), "small.toml"), x0=(20.0,), speed=80.0)
    parts._compiled = None
    assert m._compiled is not None
    rng = np.random.default_rng(7)
    seen = np.zeros(3, dtype=bool)      # slack now, slack committed, the two sets apart
    for trial in range(4):
        q, v, a = _random_state(m, rng, 10 ** -(trial + 1))
        m.commit(0.0, q, v, a, None)
        parts.commit(0.0, q, v, a, None)
        assert np.array_equal(m._slack_committed, parts._slack_committed)
        q2 = q + 1e-3 * rng.standard_normal(q.size)
        for tangent in (False, True):
            for inputs in (None, np.array([130.0])):
                e1 = m.evaluate(0.01, q2, v, a, inputs, tangent)
                e0 = parts.evaluate(0.01, q2, v, a, inputs, tangent)
                assert np.array_equal(e1.f_inertia, e0.f_inertia)
                assert np.array_equal(e1.f_rest, e0.f_rest)
                assert e1.structure_key == e0.structure_key
                if tangent:
                    assert np.array_equal(e1.stiffness.data, e0.stiffness.data)
                    assert np.array_equal(e1.damping.data, e0.damping.data)
        slack_now = np.frombuffer(e1.structure_key[0], dtype=bool)
        committed = np.frombuffer(e1.structure_key[1], dtype=bool)
        seen |= [slack_now.any(), committed.any(), (slack_now != committed).any()]
    assert seen.all()
    # the fused iterate: kinematics, evaluation and HHT residual in one call
    q_p, v_p, hist = q, v, rng.standard_normal(q.size)
    ev, a1, v1, R, r_max, scale = m.iterate(0.01, q2, q_p, v_p, 4e6, 2e3, 0.95, hist,
                                            np.array([130.0]), False)
    a0, v0 = iterate_kinematics(q2, q_p, v_p, 4e6, 2e3)
    e0 = parts.evaluate(0.01, q2, v0, a0, np.array([130.0]), False)
    R0, r0, s0 = weighted_residual(e0.f_inertia, e0.f_rest, hist, 0.95)
    assert np.array_equal(a1, a0) and np.array_equal(v1, v0) and np.array_equal(R, R0)
    assert (r_max, scale) == (r0, s0) and r_max > 0.0

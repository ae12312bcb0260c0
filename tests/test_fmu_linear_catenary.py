"""The catenary FMU with catenary_model = 1 (linear) equals the in-process linear model under
the same closed-form steps (tests/test_affine_step.py checks those against
Newton-Raphson); the FMU runs in a subprocess (tests/fmu_catenary_probe.py)."""

import numpy as np
import pytest
from test_fmu_catenary import H, SHORT, probe

#: FMUs or long runs: outside `pytest -m "not slow"` (CI runs everything)
pytestmark = pytest.mark.slow


def test_linear_catenary_fmu_equals_the_in_process_linear_model(fmus):
    from pantocosim.catenary.definition import load_catenary, with_spans
    from pantocosim.catenary.linear import LinearCatenary
    from pantocosim.core.structure_stepping import ForcedStepper
    from pantocosim.interaction.stepper_factory import make_stepper
    from pantocosim.core.hht import HHTSettings

    x0, F0 = [30.0], [120.0]
    steps = 150
    t = H * np.arange(1, steps + 1)
    forces = (F0[0] + 250.0 * np.sin(2 * np.pi * 4 * t) ** 2)[:, None]   # slackens droppers
    params = dict(SHORT, n_pantographs=1, position_1=x0[0], static_force_1=F0[0],
                  newton_rtol=1e-6, catenary_model=1)
    res = probe("catenary_trace", fmus["catenary"], params=params, forces=forces.tolist(),
                n_uplift=5)
    m = LinearCatenary(with_spans(load_catenary("en50318"), 4), x0=x0, speed=300.0 / 3.6)
    integ = make_stepper(m, HHTSettings.for_runs(-0.05, 1e-6), redo=True)
    assert isinstance(integ, ForcedStepper)
    integ.initialize(0.0, m.static_state(np.array(F0)), np.zeros(m.n_dofs), np.array(F0))
    ref = [list(m.wire_height(0.0, integ.q)) + list(m.wire_velocity(0.0, integ.q, integ.v))]
    slack_seen = False
    for F in forces:
        integ.step(H, F.copy())
        slack_seen |= bool(integ.structure.committed.any())
        ref.append(list(m.wire_height(integ.t, integ.q))
                   + list(m.wire_velocity(integ.t, integ.q, integ.v)))
    ref = np.array(ref)
    rows = np.array(res["rows"])
    got = np.vstack([np.array(res["initial"])[None, :2], rows[:, :2]])
    assert slack_seen
    assert np.max(np.abs(got - ref)) <= 1e-12 * np.max(np.abs(ref))
    assert np.array_equal(rows[-1, 3:8], m.support_uplift(integ.q)[:5])
    assert res["rollback_equal"] and res["serialized_equal"]

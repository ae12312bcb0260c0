"""The penalty law condensed on the contact points searches its active set (the contacts
whose gap and force are positive) for at most 2 m + 2 passes: a search that gives up is never
silent: the step reports it, the monolithic run warns in its summary, the catenary FMU
discards the step and keeps its state."""

import dataclasses
import json

import numpy as np
import pytest

from pantocosim.fmi import catenary_slave
from pantocosim.fmi.front import slave_class
from pantocosim.interaction.condensed import CondensedStepper
from pantocosim.interaction.penalty_contact import PenaltyContact, max_passes
from pantocosim.master.cli import main
from short_scenarios import LINEAR, THREE_SPANS

CatenarySlave = slave_class(catenary_slave.CatenarySlave, 2)


def test_a_cycling_active_set_is_reported():
    """One contact whose solved force is negative (1 + k G + c H < 0, a velocity response
    against the gap): active -> F < 0 -> inactive -> F = 0 with a positive law force ->
    active ...; the search gives up after 4 passes and says so."""
    law = PenaltyContact(5e4, 100.0)
    G, H = np.array([[1e-6]]), np.array([[-0.02]])         # 1 + 0.05 - 2 < 0
    F, _, _, settled = law.condensed(np.array([1e-3]), np.zeros(1), np.zeros(1),
                                     np.zeros(1), G, H)
    assert not settled and max_passes(1) == 4
    # the same contact with a positive velocity response settles on the law's force
    F, _, _, settled = law.condensed(np.array([1e-3]), np.zeros(1), np.zeros(1),
                                     np.zeros(1), G, -H)
    assert settled and F[0] == pytest.approx(50.0 / (1.0 + 0.05 + 2.0), rel=1e-12)




def unsettled_from(step_index: int, monkeypatch) -> list:
    """CondensedStepper.step reports an unsettled active set from its ``step_index``-th call
    on (the law's own flag is tested above); returns the list of calls."""
    calls = []
    step = CondensedStepper.step

    def reporting(self, h, inputs=None):
        report = step(self, h, inputs)
        calls.append(self.t)
        return dataclasses.replace(report, settled=len(calls) < step_index)

    monkeypatch.setattr(CondensedStepper, "step", reporting)
    return calls


@pytest.mark.slow
def test_the_run_summary_warns_of_steps_whose_active_set_gave_up(tmp_path, capsys,
                                                                 monkeypatch):
    path = tmp_path / "s.toml"
    path.write_text(THREE_SPANS + LINEAR)
    calls = unsettled_from(100, monkeypatch)
    assert main(["run", str(path), "--quiet", "--no-plots", "--json",
                 "--out", str(tmp_path / "out")]) == 0
    out = capsys.readouterr().out
    summary = json.loads(out[out.index("{"):])
    (warning,) = [w for w in summary["warnings"] if "active set" in w]
    assert f"did not settle in {len(calls) - 99} step(s)" in warning
    assert f"first at t = {calls[99]:.6g} s" in warning
    assert summary["flagged"] is True


def test_the_catenary_fmu_discards_a_step_whose_active_set_gave_up(monkeypatch):
    s = CatenarySlave(instance_name="active-set")
    s.setup_experiment(0.0)
    s.enter_initialization_mode()
    for name, value in {"catenary_definition": "en50318", "spans": 4, "speed_kmh": 300.0,
                        "n_pantographs": 1, "position_1": 30.0, "static_force_1": 120.0,
                        "catenary_model": 1, "contact_mode": 1}.items():
        setattr(s, name, value)
    s.exit_initialization_mode()
    assert s._error is None, s._error
    assert s.do_step(0.0, 1e-3)
    height = s.wire_height_1
    logged = []
    monkeypatch.setattr(s, "log", lambda message, status=None: logged.append(message))
    unsettled_from(1, monkeypatch)
    assert not s.do_step(1e-3, 1e-3)
    assert s._time == pytest.approx(1e-3) and s._integ.t == pytest.approx(1e-3)
    assert s.wire_height_1 == height
    assert "active set did not settle" in logged[-1] and "doStep(t = 0.001" in logged[-1]

"""The contact laws of a scenario (``[contact] law``): the penalty law and the constraint
(rigid, unilateral) contact of the monolithic solver.

The constraint contact is the limit of the penalty law as its stiffness grows: on the short
EN 50318 scenario (250 km/h, no loss of contact with either law) the statistics of a
penalty run approach those of the constraint run from 5e4 to 5e6 N/m, and at 5e6 N/m lie
within 0.5 % of sigma and 0.05 N of the mean (above that the contact mode is no longer
resolved by the 1 ms step; the raw force of the rigid contact leaves the wire for a few
samples where the penalty spring stays compressed, which the 0-20 Hz statistics do not
see). Loss of contact and re-contact: at 300 km/h the head leaves the
wire and comes back; off the wire the force is zero and the head below it, on the wire the
gap is closed. A step the constraint cannot satisfy stops the run with a non-zero exit.
"""

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from pantocosim.core.errors import ConvergenceError, ParameterError

ROOT = Path(__file__).resolve().parents[1]
SHORT = ROOT / "tests" / "data" / "short-en50318.toml"


def short(**changes):
    from pantocosim.master.scenario import load_scenario

    return dataclasses.replace(load_scenario(SHORT), newton_rtol=1e-6, **changes)


def run(sc):
    from pantocosim.master.run import prepare, run_monolithic

    res = run_monolithic(prepare(sc), None, progress=False)
    assert res.error is None, res.error
    return res


@pytest.fixture(scope="module")
def constraint_250():
    return run(short(contact_law="constraint"))


def test_registry_declares_both_laws():
    from pantocosim.interaction.contact_laws import CONTACT_LAWS, make_contact

    assert set(CONTACT_LAWS) >= {"penalty", "constraint"}
    pen, con = make_contact("penalty", 2e5, 3.0), make_contact("constraint", 5e4, 0.0)
    assert pen.compliance == pytest.approx(5e-6) and pen.damping == 3.0
    assert con.compliance == 0.0 and not con.across_ports and not con.condensable
    assert pen.across_ports and pen.condensable
    assert pen.fields == ("stiffness", "damping") and con.fields == ()


@pytest.mark.slow
def test_constraint_is_the_limit_of_a_stiffening_penalty(constraint_250):
    ref = constraint_250.statistics()[0]
    gaps = []
    for k in (5e4, 5e5, 5e6):
        st = run(short(contact_law="penalty", contact_stiffness=k)).statistics()[0]
        gaps.append(abs(st.std_n - ref.std_n))
        if k == 5e6:
            assert st.std_n == pytest.approx(ref.std_n, rel=0.005)
            assert st.mean_n == pytest.approx(ref.mean_n, abs=0.05)
            assert st.max_n == pytest.approx(ref.max_n, rel=0.01)
            assert st.min_n == pytest.approx(ref.min_n, rel=0.01)
    assert gaps[0] > gaps[1] > gaps[2]
    assert gaps[0] > 1.0              # the 5e4 N/m contact mode is a real difference


def test_closed_contact_has_no_gap(constraint_250):
    c = constraint_250.columns
    F = c["contact_force_1"][1:]
    gap = (c["contact_height_1"] - c["wire_height_1"])[1:]
    on = F > 0.0
    assert on.mean() > 0.95
    assert np.max(np.abs(gap[on])) < 1e-4      # penalty 5e4 N/m: about 2 mm at 100 N
    assert np.median(np.abs(gap[on])) < 1e-5     # a thousandth of the penalty's


def test_loss_of_contact_and_recontact():
    res = run(short(contact_law="constraint", speed_kmh=300.0))
    c = res.columns
    F = c["contact_force_1"][1:]
    gap = (c["contact_height_1"] - c["wire_height_1"])[1:]
    off = F == 0.0
    assert off.any() and (~off[np.argmax(off):]).any()     # leaves the wire, comes back
    assert np.max(gap[off]) < 1e-6                          # off the wire: the head below it
    assert (F >= 0.0).all()
    assert 0.0 < off.mean() < 0.1                           # brief separations


def test_a_failing_constraint_step_is_an_error_not_a_result(tmp_path, monkeypatch, capsys):
    from pantocosim.interaction import constraint_contact as cc
    from pantocosim.master.cli import main

    monkeypatch.setattr(cc.ConstraintContact, "from_fields",
                        classmethod(lambda cls, stiffness, damping: cls(gap_tolerance=1e-30)))
    sc = tmp_path / "s.toml"
    sc.write_text(SHORT.read_text() + '\n[contact]\nlaw = "constraint"\n')
    code = main(["run", str(sc), "--out", str(tmp_path / "out"), "--quiet", "--no-plots"])
    assert code != 0
    assert "constraint contact 1 not satisfied" in capsys.readouterr().err


def test_commit_check_names_the_violation():
    from pantocosim.interaction.constraint_contact import ConstraintContact, ConstraintInSystem

    class Sys:
        pantographs = [object()]

    bound = ConstraintInSystem(ConstraintContact(), Sys())
    bound._last = (1.25, np.array([3e-3]), np.array([0.0]))   # penetration without force
    with pytest.raises(ConvergenceError, match=r"t = 1.25 s\).*gap 0.003 m"):
        bound.commit()
    bound._last = (1.25, np.array([-3e-3]), np.array([0.0]))  # open, no force: fine
    bound.commit()


def test_scenario_contact_law_fields(tmp_path):
    from pantocosim.master.scenario import load_scenario

    base = SHORT.read_text()
    f = tmp_path / "a.toml"
    f.write_text(base + '\n[contact]\nlaw = "constraint"\nstiffness = 1e5\n')
    with pytest.raises(ParameterError, match="contact.stiffness.*not used by law"):
        load_scenario(f)
    f.write_text(base + '\n[contact]\nlaw = "rigid"\n')
    with pytest.raises(ParameterError, match="contact.law"):
        load_scenario(f)
    f.write_text(base + '\n[contact]\nlaw = "constraint"\n')
    assert load_scenario(f).contact_law == "constraint"
    assert load_scenario(SHORT).contact_law == "penalty"


def test_cosimulation_refuses_the_constraint_law(tmp_path):
    from pantocosim.master.scenario import load_scenario, require_port_contact

    f = tmp_path / "a.toml"
    f.write_text(SHORT.read_text() + '\n[contact]\nlaw = "constraint"\n')
    with pytest.raises(ParameterError, match='contact.law.*"penalty" law only.*monolithic'):
        require_port_contact(load_scenario(f), "the jacobi coupling")
    require_port_contact(load_scenario(SHORT), "the jacobi coupling")


@pytest.mark.slow
def test_constraint_statistics_converge_and_short_separations_are_named():
    """dt halved three times (1 to 0.125 ms), nonlinear catenary at 250 km/h, where the
    0-20 Hz force never comes near zero (minimum 58 N): the statistics converge (each
    halving moves them less than 0.1 N), the raw loss of contact shrinks with the step (its
    separations last 1-3 steps at every dt) and every one of them is named as the step's in
    the run's warnings."""
    from pantocosim.master.run import finish
    from pantocosim.master.stability import UNRESOLVED_SEPARATION_STEPS

    rows = []
    for dt in (1e-3, 5e-4, 2.5e-4, 1.25e-4):
        res = run(short(contact_law="constraint", dt=dt))
        st = res.statistics()[0]
        warnings = finish(res, None, plots=False)["warnings"]
        rows.append((st, warnings))
        assert st.min_n > 50.0
        named = [w for w in warnings if "separation(s) of the rigid contact" in w]
        if st.loss_of_contact_percent > 0.0:
            (w,) = named
            share = float(w.split(": ")[1].split(" %")[0])
            assert share == pytest.approx(st.loss_of_contact_percent, abs=0.01)
            longest = int(w.split("lasting at most ")[1].split()[0])
            assert 1 <= longest <= UNRESOLVED_SEPARATION_STEPS
        else:
            assert not named
    for (a, _), (b, _) in zip(rows, rows[1:]):
        for field in ("mean_n", "std_n", "max_n", "min_n"):
            assert abs(getattr(a, field) - getattr(b, field)) < 0.1, field
        assert b.loss_of_contact_percent <= a.loss_of_contact_percent + 1e-9
    assert rows[-1][0].loss_of_contact_percent <= rows[0][0].loss_of_contact_percent / 4


@pytest.mark.slow
def test_a_rigid_contact_on_the_modal_catenary_is_warned():
    """The modal model's contact point has no mass above its cutoff: a rigid contact's loss
    of contact there grows as dt shrinks (1.7 % at 1 ms, 4.6 % at 0.5 ms on this case), and
    the run says why before it starts."""
    res = run(short(contact_law="constraint", catenary_model="modal"))
    (w,) = [w for w in res.warnings if "contact point moves without mass" in w]
    assert "m/N" in w and "linear or nonlinear catenary" in w
    assert not [w for w in run(short(contact_law="constraint")).warnings
                if "without mass" in w]

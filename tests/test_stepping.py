"""The stepping contract: the factory picks the stepper each model declares (the same one for
the monolithic run, the catenary FMU and in-process co-simulation), and the worked example of
docs/architecture.md (a stepper added by registration alone) steps like Newton-Raphson on the
same model, under given forces and with a pantograph in contact."""

import re
import sys
import types
from pathlib import Path

import numpy as np
import pytest

from pantocosim.catenary.definition import load_catenary, with_spans
from pantocosim.catenary.models import make_catenary
from pantocosim.core import stepper_contract as contract
from pantocosim.core.affine_hht import AffineHHT
from pantocosim.interaction.condensed import CondensedStepper
from pantocosim.core.errors import ParameterError
from pantocosim.core.hht import FactorReuse, HHTIntegrator, HHTSettings
from pantocosim.interaction.penalty_contact import PenaltyContact
from pantocosim.core.structure_stepping import ForcedStepper
from pantocosim.interaction.stepper_factory import AssembledStepper, make_stepper
from pantocosim.pantograph.presets import load_pantograph

DOC = Path(__file__).resolve().parents[1] / "docs" / "architecture.md"
SETTINGS = HHTSettings.for_runs(-0.05, 1e-10)


@pytest.fixture(scope="module")
def line2():
    return with_spans(load_catenary("en50318"), 2)


def test_the_catenary_models_declare_their_stepping():
    from pantocosim.catenary.linear import LinearCatenary
    from pantocosim.catenary.modal import ModalCatenary
    from pantocosim.catenary.modal_step import ModalHHT
    from pantocosim.catenary.model import CatenaryModel

    assert CatenaryModel.stepping == contract.NEWTON
    assert LinearCatenary.stepping == "affine" and ModalCatenary.stepping == "modal"
    assert contract.CLOSED_FORM_STEPS["modal"] is ModalHHT


def test_the_factory_picks_what_the_model_declares(line2):
    cat = make_catenary("linear", line2, x0=[20.0], speed=250 / 3.6)
    pan = load_pantograph("en50318-2mass", speed_kmh=250.0)
    alone = make_stepper(cat, SETTINGS, redo=True)
    with_pan = make_stepper(cat, SETTINGS, [pan], PenaltyContact(50_000.0, 0.0))
    assert type(alone) is ForcedStepper and type(with_pan) is CondensedStepper
    for st in (alone.structure, with_pan.structure):
        assert type(st) is AffineHHT
    assert alone.structure.keep_free_response and not with_pan.structure.keep_free_response
    assert type(make_stepper(pan, SETTINGS)) is HHTIntegrator
    # in-process co-simulation takes the catenary's stepper from the same factory
    from pantocosim.master.cosim import ModelSubsystem

    sub = ModelSubsystem(cat, cat.static_state([120.0]), SETTINGS, [120.0],
                         lambda integ: cat.wire_state(integ.t, integ.q, integ.v))
    assert type(sub.integ) is ForcedStepper


def test_an_unknown_stepping_is_refused():
    class Odd:
        stepping = "no-such-stepper"

    with pytest.raises(ParameterError, match="no-such-stepper") as exc:
        make_stepper(Odd(), SETTINGS)
    assert "affine" in str(exc.value) and "newton" in str(exc.value)
    # it says what to import
    assert "@register_closed_form_step('no-such-stepper') in the module of Odd" in str(exc.value)


def test_settings_take_a_factorization_policy_not_a_flag():
    assert SETTINGS.reuse_factorization is FactorReuse.ACROSS_STEPS
    with pytest.raises(ParameterError, match="reuse_factorization"):
        HHTSettings(reuse_factorization=True).validate()


@pytest.fixture()
def example(monkeypatch):
    """The worked example of docs/architecture.md, run from the page itself."""
    text = DOC.read_text().split("## Worked example: a stepper", 1)[1]
    code = "\n".join(re.findall(r"```python\n(.*?)```", text, re.S))
    monkeypatch.setattr(contract, "CLOSED_FORM_STEPS", contract.CLOSED_FORM_STEPS.copy())
    module = types.ModuleType("stepper_example")
    monkeypatch.setitem(sys.modules, module.__name__, module)
    exec(compile(code, str(DOC), "exec"), module.__dict__)
    assert "diagonal" in contract.CLOSED_FORM_STEPS
    return module


def _bed(module, x0=(10.0,)):
    return module.SpringBed(n=121, spacing=0.5, m=0.8, k=2.0e4, c=3.0, z0=5.3, x0=x0,
                            speed=200 / 3.6)


def test_worked_example_steps_like_newton_under_given_forces(example):
    bed = _bed(example, x0=(10.0, 25.0))
    closed = make_stepper(bed, SETTINGS)
    assert isinstance(closed, ForcedStepper) and type(closed.structure).__name__ == "DiagonalHHT"
    newton = HHTIntegrator(bed, HHTSettings(alpha=-0.05, rtol=1e-13, etol=0.0))
    F0 = np.array([120.0, 100.0])
    for st in (closed, newton):
        st.initialize(0.0, np.zeros(bed.n_dofs), None, F0)
    h, err, size = 1e-3, 0.0, 0.0
    for n in range(500):
        t = (n + 1) * h
        F = F0 + 40.0 * np.sin(2 * np.pi * np.array([5.0, 7.0]) * t)
        report = closed.step(h, F)
        newton.step(h, F)
        err = max(err, float(np.max(np.abs(closed.q - newton.q))))
        size = max(size, float(np.max(np.abs(newton.q))))
    assert report.iterations == 1 and size > 1e-3
    assert err < 1e-9 * size
    # the state round-trips: a step redone from a saved state is the same step
    saved = closed.get_state()
    closed.step(h, F0)
    first = closed.q.copy()
    closed.set_state(saved)
    closed.step(h, F0)
    assert np.array_equal(closed.q, first)


def test_worked_example_runs_a_pantograph_like_the_assembled_newton(example):
    bed = _bed(example)
    pan = load_pantograph("en50318-2mass", speed_kmh=200.0)
    contact = PenaltyContact(50_000.0, 0.0)
    F0 = pan.options.mean_uplift
    cp = bed.contact_points(0.0)[0]
    q_bed = np.zeros(bed.n_dofs)
    q_bed[cp.dofs] = F0 * cp.weights / bed.k          # the static deflection under F0
    z_wire = bed.z0 + cp.weights @ q_bed[cp.dofs]
    q0 = np.concatenate([q_bed, pan.static_equilibrium(F0, z_wire + F0 / contact.stiffness)])
    fast = make_stepper(bed, SETTINGS, [pan], contact)

    class NewtonBed(type(bed)):
        stepping = contract.NEWTON

    newton_bed = _bed(example)
    newton_bed.__class__ = NewtonBed
    ref = make_stepper(newton_bed, SETTINGS, [pan], contact)
    assert isinstance(fast, CondensedStepper) and isinstance(ref, AssembledStepper)
    for st in (fast, ref):
        st.initialize(0.0, q0)
        st.prepare(1e-3)
    dF = 0.0
    forces = []
    for _ in range(400):
        fast.step(1e-3)
        ref.step(1e-3)
        (F1, z1, w1), (F2, z2, w2) = fast.contacts(), ref.contacts()
        dF = max(dF, abs(F1[0] - F2[0]))
        forces.append(F2[0])
    assert np.ptp(forces) > 5.0 and min(forces) > 0.0   # the contact force varies, in contact
    assert dF < 1e-6                                    # N
    assert np.max(np.abs(fast.structure_q - ref.structure_q)) < 1e-10

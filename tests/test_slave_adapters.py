"""The FMU slaves' per-step paths, on slave objects in this process (no FMU build): the
fmi2GetReal fast path gives what the checked path gives, the FMU state puts every variable
back, and the catenary prepares its structure once, at its first step."""

import math

import pytest

from pantocosim.fmi import catenary_slave
from pantocosim.fmi.front import slave_class

#: the catenary slave as its FMI 2.0 FMU has it (the core with the FMI 2.0 front)
CatenarySlave = slave_class(catenary_slave.CatenarySlave, 2)

LINEAR = {"catenary_definition": "en50318", "spans": 4, "speed_kmh": 300.0,
          "n_pantographs": 1, "position_1": 30.0, "static_force_1": 120.0,
          "catenary_model": 1}


def _vr(slave, name):
    return next(vr for vr, v in slave.vars.items() if v.name == name)


def _initialised(params=LINEAR):
    s = CatenarySlave(instance_name="in-process")
    s.setup_experiment(0.0)
    s.enter_initialization_mode()
    for name, value in params.items():
        setattr(s, name, value)
    s.exit_initialization_mode()
    assert s._error is None, s._error
    return s


@pytest.fixture(scope="module")
def catenary():
    return _initialised()


def test_get_real_fast_path_equals_the_checked_path(catenary):
    s = catenary
    assert s.do_step(0.0, 1e-3)
    names = ["wire_height_1", "wire_velocity_1", "support_uplift_1", "contact_force_1",
             "speed_kmh", "newton_iterations"]
    vrs = [_vr(s, n) for n in names]
    fast = s.get_real(vrs)
    assert fast == s._get("fmi2GetReal", "Real", vrs)
    assert all(type(x) is float for x in fast)
    assert fast[0] == s.wire_height_1 and fast[0] != 0.0
    # a variable that is not a Real of real() (an Integer) goes the checked way: converted
    assert s.get_real([_vr(s, "spans")]) == [4.0]
    # an unknown reference is refused (the next doStep discards), not read
    assert math.isnan(s.get_real([10 ** 6])[0])
    assert s._refused
    s._refused.clear()


def test_get_real_in_initialisation_mode_reads_through_the_getters():
    s = CatenarySlave(instance_name="laws")
    s.setup_experiment(0.0)
    s.enter_initialization_mode()
    for name, value in LINEAR.items():
        setattr(s, name, value)
    vr = _vr(s, "static_height_1")
    assert s.get_real([vr])[0] > 0.0    # the start law, computed on the read
    assert s.static_height_1 > 0.0


def _count_law_runs(monkeypatch) -> list:
    from pantocosim.catenary import operating_height

    runs = []
    original = operating_height.mean_dynamic_wire_height

    def counted(*args, **kwargs):
        runs.append(1)
        return original(*args, **kwargs)
    monkeypatch.setattr(operating_height, "mean_dynamic_wire_height", counted)
    return runs


def test_start_laws_are_computed_only_when_a_master_reads_them(monkeypatch):
    """The moving-load runs behind the operating-height law cost nothing to a master that
    reads other outputs (in initialisation mode or after) and never the laws; the first read
    of a law computes them, in the handshake start (no static force) too."""
    runs = _count_law_runs(monkeypatch)
    handshake = dict(LINEAR, static_force_1=0.0, contact_mode=1, pantograph_height_1=5.35)
    s = CatenarySlave(instance_name="handshake")
    s.setup_experiment(0.0)
    s.enter_initialization_mode()
    for name, value in handshake.items():
        setattr(s, name, value)
    assert s.get_real([_vr(s, "train_speed_kmh")]) == [300.0]
    s.exit_initialization_mode()
    assert s._error is None, s._error
    assert s.do_step(0.0, 1e-3)
    assert s.get_real([_vr(s, "wire_height_1")])[0] > 5.0
    assert runs == []
    offset, slope = s.get_real([_vr(s, "operating_height_1"), _vr(s, "operating_height_slope_1")])
    assert 5.0 < offset < 5.8 and 1e-5 < slope < 1e-3       # m, m/N: a wire under uplift
    assert len(runs) == 2                                    # two forces of the secant
    assert s.get_real([_vr(s, "operating_height_1")]) == [offset] and len(runs) == 2


def test_fmu_state_puts_every_variable_back(catenary):
    s = catenary
    state = s._get_fmu_state()
    before = {v.name: v.getter() for v in s.vars.values()}
    t = s._time
    assert s.do_step(t, 1e-3)
    s.window_start = 12.0        # a parameter changed after the state was taken
    s._set_fmu_state(state)
    assert {v.name: v.getter() for v in s.vars.values()} == before
    assert s._time == t


def test_the_catenary_prepares_its_structure_once_at_its_first_step(monkeypatch):
    from pantocosim.core.affine_hht import AffineHHT

    calls = []
    prepare = AffineHHT.prepare
    monkeypatch.setattr(AffineHHT, "prepare", lambda self, h: (calls.append(h),
                                                                 prepare(self, h)))
    s = _initialised()
    assert calls == []
    assert s.do_step(0.0, 1e-3)
    assert calls == [1e-3]
    assert s.do_step(1e-3, 5e-4)     # a halved step: no second set-up
    assert calls == [1e-3]


def test_the_start_values_of_the_law_outputs_compute_nothing(monkeypatch):
    """Reading every variable before initialisation mode (what pythonfmu's builder does for
    the model description's start values) runs no moving-load run."""
    runs = _count_law_runs(monkeypatch)
    s = CatenarySlave(instance_name="build")
    values = s.get_real([_vr(s, "operating_height_1"), _vr(s, "static_height_slope_2")])
    assert values == [0.0, 0.0] and runs == []


@pytest.mark.parametrize("version", [2, 3])
def test_the_slaves_register_the_variables_they_declare(version):
    """Each slave's FMU variables are its declared table's rows, in order, with their
    causality, type, unit, start value and meaning (the model description, the master's port
    names, the SSP writer and the FMU reference read the same table)."""
    from pantocosim.fmi.catenary_ports import VARIABLES as CATENARY
    from pantocosim.fmi.pantograph_ports import VARIABLES as PANTOGRAPH
    from pantocosim.fmi.pantograph_slave import PantographSlave
    from pantocosim.pantograph.presets import preset_defaults

    cases = [(catenary_slave.CatenarySlave, CATENARY, None)] + [
        (type("Preset", (PantographSlave,), {"preset": p}), PANTOGRAPH, preset_defaults(p))
        for p in ("dsa380-rigid", "en50318-2mass")]
    for core, table, context in cases:
        slave = slave_class(core, version)(instance_name="declared", resources=".")
        registered = [v for v in slave.vars.values() if v.causality.name != "independent"]
        assert [v.name for v in registered] == [v.name for v in table]
        for var, row in zip(registered, table):
            assert (var.causality.name, var.kind, var.description) == (
                row.causality, row.type, row.meaning), row.name
            assert getattr(var, "unit", None) == row.unit, row.name
            assert slave.__dict__[row.name] == row.start_value(context), row.name
    assert len(CATENARY.names("support_uplift_{j}", range(64))) == 64
    assert PANTOGRAPH["contact_force"].unit == "N"


def test_a_parameter_outside_its_declared_range_is_refused_naming_it():
    from pantocosim.core.errors import ParameterError

    s = CatenarySlave(instance_name="ranges")
    for name, bad in (("n_pantographs", 5), ("contact_mode", 2), ("factorization", 3),
                      ("catenary_model", 3), ("spans", -1), ("averaging_step", 0.0),
                      ("static_force_2", -1.0), ("n_substeps", 0)):
        good = getattr(s, name)
        setattr(s, name, bad)
        with pytest.raises(ParameterError) as err:
            s.value(name)
        assert err.value.field == name
        setattr(s, name, good)
        s.value(name)


@pytest.mark.parametrize("preset", ["en50318-2mass", "dsa380-rigid"])
def test_a_step_out_of_the_pantograph_range_is_discarded_and_undone(preset):
    """A contact force the pantograph cannot take (1e12 N) is discarded and leaves the
    FMU as it was before the step: the next valid step is taken, from the same state, and
    gives what it gives without the refused one (docs/third-party.md)."""
    from pantocosim.fmi import pantograph_slave

    cls = slave_class(type("P", (pantograph_slave.PantographSlave,), {"preset": preset}), 2)

    def started():
        s = cls(instance_name=preset)
        s.setup_experiment(0.0)
        s.enter_initialization_mode()
        s.exit_initialization_mode()
        assert s._error is None, s._error
        s.contact_force = 120.0
        assert s.do_step(0.0, 1e-3)
        return s

    s, reference = started(), started()
    before = (s.contact_height, s.contact_velocity)
    s.contact_force = 1e12
    assert not s.do_step(1e-3, 1e-3)
    assert (s.contact_height, s.contact_velocity) == before
    for slave in (s, reference):
        slave.contact_force = 125.0
        assert slave.do_step(1e-3, 1e-3), slave._error
    assert s._error is None
    assert (s.contact_height, s.contact_velocity) == (reference.contact_height,
                                                      reference.contact_velocity)

"""FMI 2.0 state machine and typed get/set of the FMUs, through fmpy in subprocesses
(tests/fmu_state_probe.py).

The FMUs' embedding library (pantocosim.fmi.embedding) gives every call its own FMI status: a
refused set, get or setFMUstate returns fmi2Error, logs the reason with status fmi2Error and
is not applied; the instance stays usable and the next valid call is honoured. A refused
doStep returns fmi2Discard. No call is ever fatal.
"""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

#: FMUs or long runs: outside `pytest -m "not slow"` (CI runs everything)
pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[1]
PROBE = Path(__file__).with_name("fmu_state_probe.py")
OK, DISCARD, ERROR = 0, 2, 3

PANTOGRAPH = {"params": {"initial_contact_force": 120.0}, "inputs": {"contact_force": 120.0},
              "outputs": ["contact_height", "contact_velocity"],
              "string_param": "parameter_file", "bool_param": "one_way_damper"}
CATENARY = {"params": {"catenary_definition": "en50318", "spans": 4, "speed_kmh": 300.0,
                       "position_1": 30.0, "static_force_1": 120.0},
            "inputs": {"contact_force_1": 120.0},
            "outputs": ["wire_height_1", "wire_velocity_1", "support_uplift_1"],
            "string_param": "catenary_definition", "bool_param": "extrapolate_heights"}
CASES = {"en50318-2mass": PANTOGRAPH, "catenary": CATENARY}


@pytest.fixture(scope="module")
def fmus(fmus):
    """The session's FMUs of :data:`CASES`."""
    return {name: fmus[name] for name in CASES}


def probe(check, fmu, **args):
    proc = subprocess.run([sys.executable, str(PROBE), check, str(fmu), json.dumps(args)],
                          capture_output=True, text=True, timeout=900, cwd=str(PROBE.parent))
    lines = [l for l in proc.stdout.splitlines() if l.startswith("RESULT ")]
    # exit code 0: the process survived every call
    assert proc.returncode == 0 and lines, proc.stdout[-4000:] + proc.stderr[-4000:]
    res = json.loads(lines[-1][7:])
    assert 4 not in res["statuses"] and -1 not in res["statuses"], res["statuses"]
    return res


def expect(record, status, *texts, log_status=None):
    """A recorded call: its returned status, and a logged message containing every text."""
    got, msgs = record
    assert got == status, record
    if texts:
        assert any(all(t in m for t in texts) and (log_status is None or st == log_status)
                   for st, m in msgs), record


def quiet(record):
    """An OK call that logged nothing at status >= warning."""
    assert record[0] == OK and not [m for st, m in record[1] if st >= 1], record


@pytest.fixture(scope="module", params=list(CASES))
def state_machine(request, fmus):
    return request.param, probe("state_machine", fmus[request.param], **CASES[request.param])


def test_step_size_and_communication_point(state_machine):
    _, r = state_machine
    expect(r["h_zero"], DISCARD, "h = 0.0", "step size must be finite and > 0")
    expect(r["h_negative"], DISCARD, "h = -0.001", "step size must be finite and > 0")
    expect(r["ahead"], DISCARD, "communication point 0.001 is not the FMU's current time 0.0")
    quiet(r["first_valid"])
    expect(r["behind"], DISCARD, "communication point 0.0 is not the FMU's current time 0.001")
    quiet(r["repeated_addition"])


def test_step_after_terminate_is_discarded(state_machine):
    _, r = state_machine
    quiet(r["terminate"])
    expect(r["after_terminate"], DISCARD, "after fmi2Terminate")


def test_fmu_state_of_another_instance_is_refused(state_machine):
    _, r = state_machine
    expect(r["foreign_instance_set"], ERROR, "fmi2SetFMUstate", "is not an FMU state of "
           "instance 'A' (freed, of another instance", log_status=ERROR)
    quiet(r["foreign_instance_next_step"])  # A kept its own state and time
    quiet(r["foreign_instance_after"])


def test_rollback_and_deserialized_state_in_a_fresh_instance(state_machine):
    _, r = state_machine
    quiet(r["rollback_set"])
    quiet(r["deserialized_set"])
    assert r["rollback_equal"] and r["deserialized_equal"]  # bitwise
    expect(r["garbage_deserialize"], ERROR, "fmi2DeSerializeFMUstate: the bytes are not a "
           "pantocosim FMU state", log_status=ERROR)
    expect(r["garbage_set"], ERROR, "is not an FMU state of instance 'C'", log_status=ERROR)
    quiet(r["garbage_next_step"])


def test_fmi2_reset_keeps_the_instance(state_machine):
    _, r = state_machine
    quiet(r["reset"])
    quiet(r["own_state_after_reset"])
    quiet(r["own_state_after_reset_step"])


def test_lossless_wrongly_typed_sets_are_honoured(state_machine):
    _, r = state_machine
    quiet(r["real_to_integer_lossless"])
    quiet(r["real_to_boolean"])
    assert r["n_substeps_after_2.0"] == 2 and r["bool_after_1.0"] is True
    quiet(r["real_to_integer_lossless_step"])


def test_refused_calls_return_fmi2error_and_the_next_valid_call_is_honoured(state_machine):
    name, r = state_machine
    string_param = CASES[name]["string_param"]
    expect(r["real_to_integer_lossy"], ERROR, "fmi2SetReal: 'n_substeps'", "Real value 2.5 does "
           "not convert to Integer without loss: not applied", log_status=ERROR)
    expect(r["real_to_string"], ERROR, f"fmi2SetReal: '{string_param}'", "does not convert to "
           "String", log_status=ERROR)
    expect(r["unknown_vr_set"], ERROR, "fmi2SetReal: unknown value reference 99999",
           log_status=ERROR)
    assert r["n_substeps_after_2.5"] == 1  # not applied
    assert r["string_after_real"] == {"en50318-2mass": "", "catenary": "en50318"}[name]
    quiet(r["refused_sets_next_step"])  # the instance stays usable
    quiet(r["refused_sets_step_after"])
    expect(r["unknown_vr_get"], ERROR, "fmi2GetReal: unknown value reference 99999",
           log_status=ERROR)
    assert r["unknown_vr_get_value"] is None   # fmpy raises: no value
    quiet(r["unknown_vr_get_next_step"])


def test_fixed_parameter_after_initialisation_is_refused(state_machine):
    name, r = state_machine
    expect(r["fixed_after_init"], ERROR, "fmi2SetReal: 'speed_kmh'", "a fixed parameter can only "
           "be set before fmi2ExitInitializationMode", log_status=ERROR)
    assert r["fixed_after_init_value"] == CASES[name]["params"].get("speed_kmh", 0.0)
    quiet(r["fixed_after_init_next_step"])
    quiet(r["fixed_after_init_step_after"])


def test_state_of_another_model_is_refused(fmus):
    """A pantograph state set into the catenary FMU; a serialized one too."""
    r = probe("foreign_model", fmus["catenary"], params=CATENARY["params"],
              inputs=CATENARY["inputs"], other=str(fmus["en50318-2mass"]),
              other_params=PANTOGRAPH["params"], other_inputs=PANTOGRAPH["inputs"])
    expect(r["set"], ERROR, "fmi2SetFMUstate", "is not an FMU state of instance 'P'",
           log_status=ERROR)
    quiet(r["next_step"])
    quiet(r["step_after"])
    expect(r["deserialized_set"], ERROR, "fmi2SetFMUstate: the state is one of model "
           "pantocosim_fmu_en50318_2mass.En50318TwoMass preset 'en50318-2mass'",
           "this FMU is pantocosim_fmu_catenary.Catenary", log_status=ERROR)
    quiet(r["deserialized_next_step"])


@pytest.mark.parametrize("name", list(CASES))
def test_start_time_is_honoured(fmus, name):
    """setupExperiment(startTime = 5) and doStep(5 + k h, h): the same outputs as from 0."""
    case = CASES[name]
    r = probe("start_time", fmus[name], params=case["params"], inputs=case["inputs"],
              outputs=case["outputs"], t0=5.0, steps=200)
    a, b = r["runs"]["0.0"], r["runs"]["5.0"]
    assert a["statuses"] == [OK] and b["statuses"] == [OK]
    assert np.array_equal(np.array(a["rows"]), np.array(b["rows"]))
    assert np.ptp(np.array(a["rows"])[:, 0]) > 0  # the run moves

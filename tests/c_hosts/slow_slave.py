"""A small FMU slave for the tests of the embedding libraries (tests/test_export_library.py):
what the bridge calls, with a settable delay in its steps and state serialisation, so that a
test can act on another thread while a call is under way, and the import of the module the
environment variable SLOW_SLAVE_IMPORT names, if set (a missing one is then named by the
library). Variables: vr 0 ``x`` (grows by h each step), vr 1 ``delay`` [s]. A delayed call
creates the file of its name (``step``, ``serialize``) in the folder SLOW_SLAVE_MARKS names,
if set, as it begins: what a test waits for to know the call is under way."""

import os
import pickle
import time
from pathlib import Path

if os.environ.get("SLOW_SLAVE_IMPORT"):
    __import__(os.environ["SLOW_SLAVE_IMPORT"])


def _begun(call: str) -> None:
    """Say that ``call`` is under way (module docstring)."""
    if os.environ.get("SLOW_SLAVE_MARKS"):
        (Path(os.environ["SLOW_SLAVE_MARKS"]) / call).touch()


class Message:
    def __init__(self, status, category, msg):
        self.status, self.category, self.msg = status, category, msg


class SlowSlave:
    fmi_version = 2
    log_categories = {"logAll": ""}

    def __init__(self, instance_name, resources, visible, logger):
        self.log_queue = []
        self.statuses_per_call = False
        self.values = {0: 0.0, 1: 0.0}
        self._time = 0.0

    @staticmethod
    def fmi_call(name):
        return f"fmi2{name}"

    def setup_experiment(self, start, stop, tol):
        self._time = start

    def enter_initialization_mode(self):
        pass

    def exit_initialization_mode(self):
        pass

    def terminate(self):
        pass

    def do_step(self, t, h):
        _begun("step")
        time.sleep(self.values[1])
        self.values[0] += h
        self._time = t + h
        self.log_queue.append(Message(0, "logAll", f"stepped to {self._time}"))
        return True

    def get_real(self, vrs):
        return [self.values[vr] for vr in vrs]

    def set_real(self, vrs, values):
        for vr, v in zip(vrs, values):
            if vr not in self.values:
                raise KeyError(f"unknown value reference {vr}")
            self.values[vr] = float(v)

    def _get_fmu_state(self):
        return dict(self.values)

    def _set_fmu_state(self, state):
        self.values = dict(state)

    @staticmethod
    def _fmu_state_to_bytes(state):
        _begun("serialize")
        time.sleep(state[1])
        return pickle.dumps(state)

    @staticmethod
    def _fmu_state_from_bytes(data):
        return pickle.loads(data)

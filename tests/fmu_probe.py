"""Runs FMU checks in a separate process and prints one JSON line (used by test_fmu_*.py).

Separate processes keep pythonfmu's process-exit defects (docs/pythonfmu-notes.md, B5) and any
fatal FMU status away from the pytest process; the probe ends with ``os._exit``.

    python fmu_probe.py CHECK FMU [JSON-ARGS]
"""

from __future__ import annotations

import json
import os
import sys
import traceback

import numpy as np
import scipy.sparse.linalg  # noqa: F401  (B5: import before loading FMUs)


def _open(fmu, name="A"):
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    d = extract(fmu)
    md = read_model_description(d)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    s = FMU2Slave(guid=md.guid, unzipDirectory=d, modelIdentifier=md.coSimulation.modelIdentifier,
                  instanceName=name)
    return s, vr, md, d


def _logger_callbacks(messages):
    from ctypes import byref

    from fmpy.fmi2 import defaultCallbacks, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE

    def logger(component, instance, status, category, message):
        messages.append((int(status), message.decode("utf-8", "replace")))

    cb = fmi2CallbackFunctions()
    cb.logger = fmi2CallbackLoggerTYPE(logger)
    cb.allocateMemory = defaultCallbacks.allocateMemory
    cb.freeMemory = defaultCallbacks.freeMemory
    from fmpy.logging import addLoggerProxy

    addLoggerProxy(byref(cb))
    return cb, logger


def _init(s, params, messages=None):
    cb = None
    if messages is not None:
        cb = _logger_callbacks(messages)
        s.instantiate(callbacks=cb[0], loggingOn=True)
    else:
        s.instantiate()
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    for vr_, kind, value in params:
        getattr(s, f"set{kind}")([vr_], [value])
    s.exitInitializationMode()
    return cb


def pantograph_trace(fmu, args):
    """Prescribed force, rollback and serialisation of a pantograph FMU."""
    s, vr, md, d = _open(fmu)
    F0 = args.get("F0", 120.0)
    _init(s, [(vr["initial_contact_force"], "Real", F0)])
    h = args.get("h", 1e-3)
    n = args.get("steps", 500)
    t = 0.0
    heights = []
    for i in range(n):
        F = F0 + 30.0 * np.sin(4 * np.pi * (t + h))
        s.setReal([vr["contact_force"]], [F])
        s.doStep(t, h)
        t += h
        heights.append(s.getReal([vr["contact_height"]])[0])

    def run10(slave):
        out = []
        for i in range(10):
            slave.setReal([vr["contact_force"]], [F0 + 50.0])
            slave.doStep(t + i * h, h)
            out.append(slave.getReal([vr["contact_height"], vr["contact_velocity"]]))
        return out

    state = s.getFMUstate()
    a = run10(s)
    s.setFMUstate(state)
    b = run10(s)
    blob = s.serializeFMUstate(state)
    s2 = _open(fmu, "B")[0]
    _init(s2, [(vr["initial_contact_force"], "Real", F0)])
    s2.setFMUstate(s2.deSerializeFMUstate(blob))
    c = run10(s2)
    return {"heights": heights, "rollback_equal": a == b, "serialized_equal": a == c,
            "state_bytes": len(blob)}


def pantograph_bad_input(fmu, args):
    """NaN force and a bad parameter file: discard/error with a message, process survives."""
    out = {}
    msgs: list = []
    s, vr, md, d = _open(fmu)
    _init(s, [], msgs)
    s.setReal([vr["contact_force"]], [float("nan")])
    try:
        s.doStep(0.0, 1e-3)
        out["nan_status"] = 0
    except Exception as exc:  # FMICallException
        out["nan_status"] = getattr(exc, "status", -1)
    out["nan_messages"] = [m for st, m in msgs if st >= 2]
    s.setReal([vr["contact_force"]], [120.0])
    s.doStep(0.0, 1e-3)  # still usable after a discard
    out["after_discard_height"] = s.getReal([vr["contact_height"]])[0]
    msgs2: list = []
    s3 = _open(fmu, "C")[0]
    try:
        _init(s3, [(vr["parameter_file"], "String", args["bad_file"])], msgs2)
        out["bad_file_init_status"] = 0
    except Exception as exc:  # fmi2ExitInitializationMode: fmi2Error
        out["bad_file_init_status"] = getattr(exc, "status", -1)
    try:
        s3.setReal([vr["contact_force"]], [120.0])
        s3.doStep(0.0, 1e-3)
        out["bad_file_status"] = 0
    except Exception as exc:
        out["bad_file_status"] = getattr(exc, "status", -1)
    out["bad_file_messages"] = [m for st, m in msgs2 if st >= 2]
    return out


CHECKS = {"pantograph_trace": pantograph_trace, "pantograph_bad_input": pantograph_bad_input}

def main(checks: dict) -> None:
    """``python PROBE CHECK FMU [JSON-ARGS]``: run one check, print ``RESULT {json}``, and end
    with ``os._exit`` (0, or 1 after a traceback)."""
    check, fmu = sys.argv[1], sys.argv[2]
    args = json.loads(sys.argv[3]) if len(sys.argv) > 3 else {}
    try:
        result = checks[check](fmu, args)
        print("RESULT " + json.dumps(result))
        sys.stdout.flush()
        os._exit(0)
    except Exception:
        traceback.print_exc()
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(1)


if __name__ == "__main__":
    main(CHECKS)

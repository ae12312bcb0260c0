"""Runs catenary-FMU checks in a separate process and prints one JSON line (test_fmu_catenary).

Separate processes keep pythonfmu's process-exit defects (docs/pythonfmu-notes.md, B5) and any
fatal FMU status away from the pytest process; the probe ends with ``os._exit``. It imports
only numpy, scipy and fmpy (never pantocosim), so it also runs in a bare venv::

    python fmu_catenary_probe.py CHECK FMU [JSON-ARGS]
"""

from __future__ import annotations

import os
import sys

import numpy as np
import scipy.sparse.linalg  # noqa: F401  (B5: import before loading FMUs)


from fmu_probe import _init as _init_typed, main  # noqa: E402  (same folder; shared helpers)


def _open(fmu, name="A"):
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    d = extract(fmu)
    md = read_model_description(d)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    types = {v.name: v.type for v in md.modelVariables}
    s = FMU2Slave(guid=md.guid, unzipDirectory=d, modelIdentifier=md.coSimulation.modelIdentifier,
                  instanceName=name)
    s._pc_vr, s._pc_types = vr, types
    return s, vr


def _init(s, params: dict, messages=None):
    """instantiate + setup + parameters (by name, typed from the model description) + init."""
    return _init_typed(s, [(s._pc_vr[name], s._pc_types[name], value)
                           for name, value in params.items()], messages)


def _status(fn):
    try:
        fn()
        return 0
    except Exception as exc:  # fmpy's FMICallException carries .status
        return getattr(exc, "status", -1)


def catenary_trace(fmu, args):
    """Mode 0 under prescribed forces; rollback and serialisation into a fresh instance."""
    s, vr = _open(fmu)
    params = args["params"]
    _init(s, params)
    n = int(params.get("n_pantographs", 1))
    forces = np.array(args["forces"])             # (steps, n): force at t_{i+1}
    h = float(args.get("h", 1e-3))
    fvr = [vr[f"contact_force_{k}"] for k in range(1, n + 1)]
    out_names = ([f"wire_height_{k}" for k in range(1, n + 1)]
                 + [f"wire_velocity_{k}" for k in range(1, n + 1)]
                 + [f"contact_force_out_{k}" for k in range(1, n + 1)]
                 + [f"support_uplift_{j}" for j in range(args.get("n_uplift", 4))])
    ovr = [vr[x] for x in out_names]
    initial = s.getReal(ovr)
    t = 0.0
    rows = []
    for F in forces:
        s.setReal(fvr, list(map(float, F)))
        s.doStep(t, h)
        t += h
        rows.append(s.getReal(ovr))

    def run10(slave):
        out = []
        for i in range(10):
            slave.setReal(fvr, [float(forces[-1][k]) + 40.0 * (i + 1) for k in range(n)])
            slave.doStep(t + i * h, h)
            out.append(slave.getReal(ovr))
        return out

    state = s.getFMUstate()
    a, b, c, blob = _replay(fmu, params, s, state, run10)
    n_sup = s.getReal([vr["n_supports"]])[0]
    return {"names": out_names, "initial": initial, "rows": rows, "rollback_equal": a == b,
            "serialized_equal": a == c, "state_bytes": len(blob), "n_supports": n_sup,
            "after": a}


def _replay(fmu, params, s, state, run):
    """``run`` from ``state`` (taken on ``s``), again after restoring it, and on a second
    instance from the serialized state: (first, after rollback, after deserialization,
    serialized bytes)."""
    a = run(s)
    s.setFMUstate(state)
    b = run(s)
    blob = s.serializeFMUstate(state)
    s2 = _open(fmu, "B")[0]
    _init(s2, params)
    s2.setFMUstate(s2.deSerializeFMUstate(blob))
    return a, b, run(s2), blob


def catenary_penalty(fmu, args):
    """Mode 1 (built-in penalty) with prescribed pantograph heights/velocities."""
    s, vr = _open(fmu)
    # the inputs are the pantograph's values at t + h (an iterating master): no extrapolation
    params = dict(args["params"], contact_mode=1, extrapolate_heights=False)
    _init(s, params)
    h = float(args.get("h", 1e-3))
    zvr = [vr["pantograph_height_1"], vr["pantograph_velocity_1"]]
    ovr = [vr["contact_force_out_1"], vr["wire_height_1"], vr["wire_velocity_1"]]
    initial = s.getReal(ovr)
    rows = []
    t = 0.0
    for z, v in args["inputs"]:
        s.setReal(zvr, [float(z), float(v)])
        s.doStep(t, h)
        t += h
        rows.append(s.getReal(ovr))
    state = s.getFMUstate()

    def run10(slave):
        out = []
        for i in range(10):
            z, v = args["inputs"][-1]
            slave.setReal(zvr, [float(z) + 1e-3 * (i + 1), float(v)])
            slave.doStep(t + i * h, h)
            out.append(slave.getReal(ovr))
        return out

    a, b, c, _ = _replay(fmu, params, s, state, run10)
    return {"initial": initial, "rows": rows, "rollback_equal": a == b,
            "serialized_equal": a == c}


def catenary_bad_input(fmu, args):
    """Each bad input gives fmi2Discard (status 2) with a message; the process survives."""
    base = args.get("params", {})
    cases = {
        "unknown_catenary": ({"catenary_definition": "no-such-catenary.toml"}, None),
        "nan_force": ({}, ("contact_force_1", float("nan"))),
        "negative_force": ({}, ("contact_force_1", -5.0)),
        "bad_n_pantographs": ({"n_pantographs": 7}, None),
        "position_off_line": ({"position_1": 1.0e5}, None),
        "negative_static_force": ({"static_force_1": -10.0}, None),
        "bad_alpha": ({"hht_alpha": 0.5}, None),
        "bad_factorization": ({"factorization": 5}, None),
        "bad_rtol": ({"newton_rtol": 0.5}, None),
        "bad_stiffness": ({"contact_stiffness": -1.0}, None),
        "nan_height_mode1": ({"contact_mode": 1}, ("pantograph_height_1", float("nan"))),
    }
    out = {}
    for i, (case, (params, inp)) in enumerate(cases.items()):
        msgs: list = []
        s, vr = _open(fmu, f"I{i}")
        init = _status(lambda: _init(s, dict(base, **params), msgs))
        if inp is not None:
            s.setReal([vr[inp[0]]], [inp[1]])
        st = _status(lambda: s.doStep(0.0, 1e-3))
        res = {"init_status": init, "status": st,
               "messages": [m for lvl, m in msgs if lvl >= 2]}
        if case == "nan_force":
            # still usable after a discard
            s.setReal([vr["contact_force_1"]], [100.0])
            res["after_status"] = _status(lambda: s.doStep(0.0, 1e-3))
            res["after_height"] = s.getReal([vr["wire_height_1"]])[0]
        out[case] = res
    return out


def smoke(fmu, args):
    """Instantiate and step one FMU (used in the bare venv: numpy, scipy, numba, fmpy only)."""
    s, vr = _open(fmu)
    msgs: list = []
    _init(s, args.get("params", {}), msgs)
    inputs = args.get("inputs", {})
    outs = args["outputs"]
    t, h = 0.0, 1e-3
    vals = []
    for i in range(int(args.get("steps", 20))):
        for name, value in inputs.items():
            s.setReal([vr[name]], [float(value)])
        s.doStep(t, h)
        t += h
        vals = s.getReal([vr[o] for o in outs])
    s.terminate()
    import pantocosim  # noqa: F401  (imported by the FMU from its resources)

    return {"outputs": dict(zip(outs, vals)), "errors": [m for lvl, m in msgs if lvl >= 2],
            "pantocosim_from": os.path.dirname(sys.modules["pantocosim"].__file__)}


CHECKS = {"catenary_trace": catenary_trace, "catenary_penalty": catenary_penalty,
          "catenary_bad_input": catenary_bad_input, "smoke": smoke}

if __name__ == "__main__":
    main(CHECKS)

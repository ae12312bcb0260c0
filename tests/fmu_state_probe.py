"""FMI 2.0 state-machine checks of a pantocosim FMU through fmpy, in a separate process
(test_fmu_state_machine.py); prints one ``RESULT {json}`` line and ends with ``os._exit``.

    python fmu_state_probe.py CHECK FMU [JSON-ARGS]

Every FMI call is recorded as ``[status, [[log status, message], ...]]``: the status the call
returned (0 OK, 2 discard, 3 error, 4 fatal; fmpy raises FMICallException with .status) and
the messages the FMU logged during the call.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse.linalg  # noqa: F401  (B5: import before loading FMUs)

from fmu_probe import _logger_callbacks, _open, main  # noqa: E402  (same folder)


#: (status, message) of every message logged in this process. fmpy's native logger proxy
#: keeps one Python logger per process (the last registered one), so all instances share one
#: callback; calls are sequential, so the messages logged during a call are that call's.
MESSAGES: list = []
_CALLBACKS: list = []


def _callbacks():
    if not _CALLBACKS:
        _CALLBACKS.append(_logger_callbacks(MESSAGES))  # kept alive for the process
    return _CALLBACKS[0][0]


class Probe:
    """One FMU instance; ``call`` records the status and the messages logged meanwhile."""

    def __init__(self, fmu, name, calls):
        self.s, self.vr, self.md, _ = _open(fmu, name)
        self.types = {v.name: v.type for v in self.md.modelVariables}
        self.calls = calls
        self.s.instantiate(callbacks=_callbacks(), loggingOn=True)

    def call(self, fn, *args):
        start = len(MESSAGES)
        try:
            value = fn(*args)
            status = 0
        except Exception as exc:  # fmpy's FMICallException carries .status
            value, status = None, getattr(exc, "status", -1)
        self.calls.append(status)
        return value, [status, [list(m) for m in MESSAGES[start:]]]

    def init(self, params, t0=0.0, extra=()):
        """setupExperiment(t0), parameters (typed from the model description), ``extra``
        calls (recorded) in initialisation mode, exitInitializationMode."""
        s = self.s
        self.call(s.setupExperiment, None, t0)
        self.call(s.enterInitializationMode)
        for name, value in params.items():
            self.call(getattr(s, f"set{self.types[name]}"), [self.vr[name]], [value])
        out = [self.call(*c) for c in extra]
        self.call(s.exitInitializationMode)
        return out

    def step(self, t, h, inputs=None):
        for name, value in (inputs or {}).items():
            self.call(self.s.setReal, [self.vr[name]], [float(value)])
        return self.call(self.s.doStep, t, h)[1]

    def real(self, names):
        return self.s.getReal([self.vr[n] for n in names])


def state_machine(fmu, args):
    """Every FMI 2.0 state-machine case and the typed sets and gets on one FMU."""
    calls: list = []
    params, inputs = args["params"], args["inputs"]
    h = 1e-3
    out = {}

    a = Probe(fmu, "A", calls)
    a.init(params)
    s, vr = a.s, a.vr
    out["h_zero"] = a.step(0.0, 0.0, inputs)
    out["h_negative"] = a.step(0.0, -h, inputs)
    out["ahead"] = a.step(h, h, inputs)
    out["first_valid"] = a.step(0.0, h, inputs)
    out["behind"] = a.step(0.0, h, inputs)
    out["repeated_addition"] = a.step(0.0 + h, h, inputs)  # t = 2e-3 next
    t = 0.0 + h + h
    for _ in range(3):
        a.step(t, h, inputs)
        t += h

    # another instance's in-memory state; another run later accepts nothing stale
    b = Probe(fmu, "B", calls)
    b.init(params)
    b.step(0.0, h, inputs)
    state_b, _ = b.call(b.s.getFMUstate)
    out["foreign_instance_set"] = a.call(s.setFMUstate, state_b)[1]
    out["foreign_instance_next_step"] = a.step(t, h, inputs)
    out["foreign_instance_after"] = a.step(t + h, h, inputs)
    t += 2 * h

    # rollback in the same instance; then serialized into a fresh instance
    state_a, _ = a.call(s.getFMUstate)
    names = args["outputs"]

    def run(p, t_start):
        rows = []
        for i in range(10):
            p.step(t_start + i * h, h, {k: v + 10.0 * (i + 1) for k, v in inputs.items()})
            rows.append(p.real(names))
        return rows

    first = run(a, t)
    out["rollback_set"] = a.call(s.setFMUstate, state_a)[1]
    again = run(a, t)
    blob, _ = a.call(s.serializeFMUstate, state_a)
    c = Probe(fmu, "C", calls)
    c.init(params)
    restored, _ = c.call(c.s.deSerializeFMUstate, blob)
    out["deserialized_set"] = c.call(c.s.setFMUstate, restored)[1]
    fresh = run(c, t)
    out["rollback_equal"] = first == again
    out["deserialized_equal"] = first == fresh
    # garbage bytes: refused, never fatal
    junk, out["garbage_deserialize"] = c.call(c.s.deSerializeFMUstate, b"not a state")
    out["garbage_set"] = c.call(c.s.setFMUstate, junk)[1]
    out["garbage_next_step"] = c.step(t + 10 * h, h, inputs)

    # wrongly typed and unknown sets/gets (CoFmuPy sets everything with fmi2SetReal)
    ivr, svr, bvr = (vr["n_substeps"], vr[args["string_param"]], vr[args["bool_param"]])
    d = Probe(fmu, "D", calls)
    res = d.init(params, extra=[
        (d.s.setReal, [ivr], [2.0]), (d.s.setReal, [bvr], [0.0]), (d.s.setReal, [bvr], [1.0])])
    out["real_to_integer_lossless"] = res[0][1]
    out["real_to_boolean"] = res[1][1]
    out["n_substeps_after_2.0"] = d.s.getInteger([ivr])[0]
    out["bool_after_1.0"] = bool(d.s.getBoolean([bvr])[0])
    out["real_to_integer_lossless_step"] = d.step(0.0, h, inputs)

    e = Probe(fmu, "E", calls)
    res = e.init(params, extra=[(e.s.setReal, [ivr], [2.5]), (e.s.setReal, [svr], [1.0]),
                                (e.s.setReal, [99999], [1.0])])
    out["real_to_integer_lossy"] = res[0][1]
    out["real_to_string"] = res[1][1]
    out["unknown_vr_set"] = res[2][1]
    out["n_substeps_after_2.5"] = e.s.getInteger([ivr])[0]
    out["string_after_real"] = e.s.getString([svr])[0].decode()
    out["refused_sets_next_step"] = e.step(0.0, h, inputs)
    out["refused_sets_step_after"] = e.step(h, h, inputs)
    value, out["unknown_vr_get"] = e.call(e.s.getReal, [99999])
    out["unknown_vr_get_value"] = repr(value[0]) if value else None
    out["unknown_vr_get_next_step"] = e.step(2 * h, h, inputs)
    speed = vr["speed_kmh"]
    out["fixed_after_init"] = e.call(e.s.setReal, [speed], [123.0])[1]
    out["fixed_after_init_value"] = e.s.getReal([speed])[0]
    out["fixed_after_init_next_step"] = e.step(3 * h, h, inputs)
    out["fixed_after_init_step_after"] = e.step(4 * h, h, inputs)
    t_e = 5 * h

    # fmi2Reset keeps the instance (an in-memory state from before the reset is its own)
    state_e, _ = e.call(e.s.getFMUstate)
    out["reset"] = e.call(e.s.reset)[1]
    e.init(params)
    out["own_state_after_reset"] = e.call(e.s.setFMUstate, state_e)[1]
    out["own_state_after_reset_step"] = e.step(t_e, h, inputs)

    # terminate
    out["terminate"] = a.call(s.terminate)[1]
    out["after_terminate"] = a.step(t + 10 * h, h, inputs)
    out["statuses"] = sorted(set(calls))
    return out


def foreign_model(fmu, args):
    """A state of another model (``args['other']``, another FMU) set into this FMU."""
    calls: list = []
    other = Probe(args["other"], "other", calls)
    other.init(args["other_params"])
    other.step(0.0, 1e-3, args["other_inputs"])
    state, _ = other.call(other.s.getFMUstate)
    blob, _ = other.call(other.s.serializeFMUstate, state)
    p = Probe(fmu, "P", calls)
    p.init(args["params"])
    out = {"set": p.call(p.s.setFMUstate, state)[1],
           "next_step": p.step(0.0, 1e-3, args["inputs"]),
           "step_after": p.step(1e-3, 1e-3, args["inputs"])}
    restored, _ = p.call(p.s.deSerializeFMUstate, blob)
    out["deserialized_set"] = p.call(p.s.setFMUstate, restored)[1]
    out["deserialized_next_step"] = p.step(2e-3, 1e-3, args["inputs"])
    out["statuses"] = sorted(set(calls))
    return out


def start_time(fmu, args):
    """The same run from t0 = 0 and from t0 = args['t0'] (time t0 + k h): outputs per step."""
    calls: list = []
    h, n = float(args.get("h", 1e-3)), int(args.get("steps", 200))
    runs = {}
    for t0 in (0.0, float(args["t0"])):
        p = Probe(fmu, f"t0_{t0:g}", calls)
        p.init(args["params"], t0=t0)
        rows, statuses = [], []
        for k in range(n):
            u = {name: v + 20.0 * np.sin(4 * np.pi * (k + 1) * h)
                 for name, v in args["inputs"].items()}
            statuses.append(p.step(t0 + k * h, h, u)[0])
            rows.append(p.real(args["outputs"]))
        runs[repr(t0)] = {"rows": rows, "statuses": sorted(set(statuses))}
    return {"runs": runs, "statuses": sorted(set(calls))}


CHECKS = {"state_machine": state_machine, "foreign_model": foreign_model,
          "start_time": start_time}

if __name__ == "__main__":
    main(CHECKS)

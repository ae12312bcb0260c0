"""Where the explicit (Jacobi) and Gauss-Seidel couplings break, against the law of
``master/stability.py`` (docs/stability.md).

Runs the en50318 case (3 spans, 250 km/h, en50318-2mass, static start) through the coupling
on in-process subsystems (the FMUs' algorithm) for 0.6 s at each step size and contact
stiffness given, with the stability check bypassed, and prints the largest contact force,
the share of steps out of contact and the law's gain G::

    python scripts/stability_breakpoints.py jacobi 0.001 3e5,4e5
"""

from __future__ import annotations

import argparse
import dataclasses

import numpy as np

from pantocosim.master import stability
from pantocosim.master.cosim import run_cosim
from pantocosim.master.run import prepare
from pantocosim.master.scenario import parse_scenario

SCENARIO = {"name": "three-spans", "catenary": "en50318", "spans": 3, "speed_kmh": 250.0,
            "pantographs": [{"model": "en50318-2mass", "position_m": 30.0,
                             "start": "static"}],
            "analysis": {"window_supports": [1, 2]}}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("scheme", choices=["jacobi", "gauss-seidel"])
    p.add_argument("steps", help="step sizes [s], comma-separated")
    p.add_argument("stiffnesses", help="contact stiffnesses [N/m], comma-separated")
    p.add_argument("--duration", type=float, default=0.6)
    args = p.parse_args()
    base = prepare(parse_scenario(SCENARIO, "stability_breakpoints"))
    stability.check = lambda prep, coupling: []    # run past the limit on purpose
    for dt in map(float, args.steps.split(",")):
        for k in map(float, args.stiffnesses.split(",")):
            sc = dataclasses.replace(base.scenario, contact_stiffness=k, dt=dt)
            prep = dataclasses.replace(prepare(sc), n_steps=int(args.duration / dt))
            est = stability.estimates(prep)[0]
            r = run_cosim(prep, None, scheme=args.scheme, in_process=True, progress=False)
            F = r.columns["contact_force_1"]
            print(f"{args.scheme} dt = {dt:g} s, k = {k:.3g} N/m: G = {est.gain:.2f}, max force "
                  f"{np.max(np.abs(F)):.0f} N, out of contact {100 * np.mean(F <= 0):.1f} % "
                  f"of the steps{', stopped: ' + str(r.error) if r.error else ''}",
                  flush=True)


if __name__ == "__main__":
    main()

"""Lower bound of one catenary time step on en50318-300 (docs/performance.md).

Times, in one process and interleaved, the floor solve (the banded Cholesky solve with the
run's Newton matrix factorised) and the parts of a residual evaluation no iteration strategy
can avoid: the ANCF and bar kernels with their scatter, C v and M a. Prints a Markdown table
of the median and best of 30 rounds (or ``rounds``) of 100 calls, in microseconds.

    python scripts/step_lower_bound.py [scenario] [rounds]
"""

from __future__ import annotations

import sys
import time

import numpy as np
from _tables import markdown_table

from pantocosim.master.benchmarks import factorised_newton_matrix
from pantocosim.master.run import prepare
from pantocosim.master.scenario import load_scenario


def main(argv: list[str]) -> None:
    sc = load_scenario(argv[0] if argv else "en50318-300")
    rounds = int(argv[1]) if len(argv) > 1 else 30
    cat = prepare(sc).catenary
    S = cat.structure
    rng = np.random.default_rng(0)
    q = cat.q_static.copy()
    v = rng.random(cat.n_dofs) * 1e-3
    a = rng.random(cat.n_dofs) * 1e-2
    solve = factorised_newton_matrix(cat, sc.dt, sc.alpha)
    r = rng.random(cat.n_dofs)
    x = S.full(q)
    C = cat._damping(cat._slack_committed)
    M = cat._M_own
    parts = {
        "floor solve (banded Cholesky)": lambda: solve(r),
        "residual evaluation (CatenaryModel.evaluate)":
            lambda: cat.evaluate(0.0, q, v, a, None, tangent=False),
        "ANCF and bar kernels with scatter": lambda: S.internal(x, False),
        "C v (CSR)": lambda: C @ v,
        "M a (CSR)": lambda: M @ a,
    }
    times = {k: [] for k in parts}
    for f in parts.values():
        f()
    for _ in range(rounds):
        for k, f in parts.items():
            t = time.perf_counter()
            for _ in range(100):
                f()
            times[k].append((time.perf_counter() - t) / 100 * 1e6)
    print(f"## One step's unavoidable parts ({sc.name}, {cat.n_dofs} DOFs)\n")
    print(markdown_table(("part", "median [us]", "best [us]"),
                         [(k, f"{np.median(t):.0f}", f"{np.min(t):.0f}")
                          for k, t in times.items()]), end="")


if __name__ == "__main__":
    main(sys.argv[1:])

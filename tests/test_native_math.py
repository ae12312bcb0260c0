"""The native models' elementary functions (fmus/native/pcs_math.c): sin, cos, atan, atan2
and s^(-3/2) from + - * / sqrt and exact constants only, so that no platform's C library
decides a bit of the DSA-380 models' numbers. Over a wide sample each is correctly rounded
(the double nearest the 60-digit value, mpmath), hence the C library's value but where the
C library is not correctly rounded (glibc: about one argument in a thousand, then 1 ulp
apart); the special values are C99 Annex F's. That the bits are the same on every platform
is tests/test_native_platforms.py's coupled flexible and rigid DSA-380 runs (aarch64, win64,
win32 against linux64)."""

import ctypes
import math
import subprocess

import mpmath
import numpy as np
import pytest

from pantocosim.master.native.build import CFLAGS, SOURCE_DIR
from test_native_fmus import required

#: sin and cos are accurate for |x| below 2^19 pi (pcs_math.h)
SIN_RANGE = 2.0 ** 19 * math.pi
#: name in pcs_math.h: (the C library's, the exact function)
FUNCTIONS = {"sin": (math.sin, mpmath.sin), "cos": (math.cos, mpmath.cos),
             "atan": (math.atan, mpmath.atan), "atan2": (math.atan2, mpmath.atan2),
             "pow_minus_three_halves": (lambda s: s ** -1.5, lambda s: s ** mpmath.mpf(-1.5))}


@pytest.fixture(scope="module")
def lib(tmp_path_factory):
    out = tmp_path_factory.mktemp("pcs_math") / "pcs_math.so"
    subprocess.run([required("gcc", "gcc"), *CFLAGS, "-fPIC", "-shared", f"-I{SOURCE_DIR}",
                    "-o", str(out), str(SOURCE_DIR / "pcs_math.c"), "-lm"], check=True)
    so = ctypes.CDLL(str(out))
    for name in FUNCTIONS:
        f = getattr(so, f"pcs_{name}")
        f.restype = ctypes.c_double
        f.argtypes = [ctypes.c_double] * (2 if name == "atan2" else 1)
    return so


def signed_log_uniform(rng, n, lo, hi):
    """n values of magnitude log-uniform in [2^lo, 2^hi], either sign."""
    return rng.choice([-1.0, 1.0], n) * np.exp2(rng.uniform(lo, hi, n))


def samples(rng, n):
    """{function: argument tuples}: the models' range densely, the wide range thinly."""
    angles = np.concatenate([rng.uniform(-4.0, 4.0, n),
                             signed_log_uniform(rng, n, -30, math.log2(SIN_RANGE))])
    ratios = np.concatenate([rng.uniform(-3.0, 3.0, n), signed_log_uniform(rng, n, -40, 70)])
    ys, xs = (np.concatenate([rng.uniform(-2.0, 2.0, n), signed_log_uniform(rng, n, -30, 30)])
              for _ in range(2))
    squares = np.concatenate([rng.uniform(0.01, 10.0, n), np.exp2(rng.uniform(-60, 60, n))])
    return {"sin": [(x,) for x in angles], "cos": [(x,) for x in angles],
            "atan": [(x,) for x in ratios], "atan2": list(zip(ys, xs)),
            "pow_minus_three_halves": [(s,) for s in squares]}


def test_correctly_rounded_over_a_wide_sample(lib):
    mpmath.mp.prec = 200
    rng = np.random.default_rng(20261205)
    for name, args in samples(rng, 2_000).items():
        ours, exact = getattr(lib, f"pcs_{name}"), FUNCTIONS[name][1]
        wrong = [a for a in args if ours(*a) != float(exact(*map(mpmath.mpf, a)))]
        assert wrong == [], (name, len(wrong), wrong[:3])


def test_the_c_library_s_value_but_where_it_is_not_correctly_rounded(lib):
    rng = np.random.default_rng(7)
    for name, args in samples(rng, 20_000).items():
        ours, libm = getattr(lib, f"pcs_{name}"), FUNCTIONS[name][0]
        apart = [(a, ours(*a), libm(*a)) for a in args if ours(*a) != libm(*a)]
        assert len(apart) < 0.005 * len(args), (name, len(apart))
        for _, mine, theirs in apart:
            assert mine == np.nextafter(theirs, mine), (name, mine, theirs)   # 1 ulp


def test_special_values_are_c99_annex_f(lib):
    inf, nan, pi = math.inf, math.nan, math.pi
    for x in (0.0, -0.0, 1e-300, -5e-324):
        assert math.copysign(1.0, lib.pcs_sin(x)) == math.copysign(1.0, x)
        assert lib.pcs_sin(x) == x and lib.pcs_cos(x) == 1.0 and lib.pcs_atan(x) == x
    for x in (inf, -inf, nan):
        assert math.isnan(lib.pcs_sin(x)) and math.isnan(lib.pcs_cos(x))
    assert lib.pcs_atan(inf) == pi / 2 and lib.pcs_atan(-inf) == -pi / 2
    assert math.isnan(lib.pcs_atan(nan))
    cases = [(y, x) for y in (0.0, -0.0, 1.0, -1.0, 1e300, -1e-300, inf, -inf)
             for x in (0.0, -0.0, 2.0, -2.0, 1e-300, -1e300, inf, -inf)]
    for y, x in cases:
        got, want = lib.pcs_atan2(y, x), math.atan2(y, x)
        assert got == want and math.copysign(1.0, got) == math.copysign(1.0, want), (y, x)
    assert math.isnan(lib.pcs_atan2(nan, 1.0)) and math.isnan(lib.pcs_atan2(1.0, nan))
    p = lib.pcs_pow_minus_three_halves
    assert p(0.0) == inf and p(inf) == 0.0 and math.isnan(p(-1.0)) and math.isnan(p(nan))
    assert p(4.0) == 0.125 and p(2.0 ** -100) == 2.0 ** 150 and p(2.0 ** -600) == 2.0 ** 900

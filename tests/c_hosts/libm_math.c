/*
 * pcs_math.h's functions from the C library, for tests/test_native_dsa380.py: the native
 * DSA-380 built on the libm that the Python kernels (numba) call, where a comparison needs
 * the elementary functions' bits to be the same on both sides (the flexible model's
 * accelerations turn one ulp of an angle into some 1e-10 of their largest value). The
 * shipped pcs_math.c is correctly rounded (tests/test_native_math.py); glibc is not, for
 * about one argument in a thousand.
 */
#include <math.h>

#include "pcs_math.h"

double pcs_sin(double x) { return sin(x); }
double pcs_cos(double x) { return cos(x); }
double pcs_atan(double x) { return atan(x); }
double pcs_atan2(double y, double x) { return atan2(y, x); }
double pcs_pow_minus_three_halves(double s) { return pow(s, -1.5); }

void pcs_sincos(double x, double *s, double *c)
{
    *s = sin(x);
    *c = cos(x);
}

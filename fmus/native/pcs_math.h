/*
 * The elementary functions of the native DSA-380 models (dsa380_rigid.c, dsa380_flexible.c)
 * computed by the FMU itself, so that no platform's C library decides a bit of their
 * numbers: the sin, cos, atan, atan2 and pow of glibc, the Windows C runtime and mingw-w64
 * differ in the last bit for about one argument in a thousand (mingw-w64's atan for one in
 * twenty), and the models' outputs with them. These use + - * / sqrt floor frexp ldexp
 * (exact, or correctly rounded by IEEE 754, on every platform) and exact hexadecimal
 * constants, each operation rounded to double (pcs_float.h), hence give the same bits on
 * every platform (pcs_math.c gives the algorithms).
 *
 * Accuracy (tests/test_native_math.py, against 50-digit values and the C library over a
 * wide sample): correctly rounded but for arguments whose exact value lies within about
 * 2^-30 ulp of the midpoint between two doubles (none of the samples), hence the C library's
 * value wherever the C library is correctly rounded (glibc: all but about one in a thousand);
 * sin and cos for |x| < 2^19 pi (the reduction's range; the models' angles are a few
 * radians), beyond it deterministic but not accurate. Non-finite arguments give what C99's
 * Annex F gives (NaN, or atan's and atan2's limits).
 */
#ifndef PCS_MATH_H
#define PCS_MATH_H

double pcs_sin(double x);
double pcs_cos(double x);
/* sin and cos of x from one argument reduction */
void pcs_sincos(double x, double *s, double *c);
double pcs_atan(double x);
/* the angle of the point (x, y) in [-pi, pi] */
double pcs_atan2(double y, double x);
/* s^(-3/2) (pow(s, -1.5)) for s in [2^-500, 2^500]; beyond, 1 / (s sqrt(s)) */
double pcs_pow_minus_three_halves(double s);

#endif

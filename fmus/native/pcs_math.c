/*
 * Portable sin, cos, atan, atan2 and s^(-3/2) (pcs_math.h). Each is computed in double-double
 * arithmetic (a value as the unevaluated sum hi + lo of two doubles, about 104 bits, from
 * Knuth's TwoSum and Dekker's TwoProduct, exact when no operation is fused: pcs_float.h) and
 * rounded once at the end; the error before that rounding (the series' truncation below
 * 2^-34 ulp, the double-double arithmetic below 2^-45 ulp) leaves a result correctly rounded
 * but where the exact value lies within about 2^-30 ulp of the midpoint between two doubles.
 *
 *   sin, cos   x = n pi/2 + r, |r| <= pi/4 (Cody-Waite with pi/2 in three parts of 33 bits
 *              plus a tail, fdlibm's; r as a double-double); then the Taylor series of sin
 *              or cos in r (12 terms) and the quadrant n mod 4
 *   atan       |x| reduced by atan(x) = atan(c) + atan((x - c) / (1 + x c)), c = 0, 1/2, 1,
 *              3/2 or infinity by |x|'s interval (fdlibm's s_atan.c), the quotient and
 *              atan(c) as double-doubles, then the Taylor series of atan (35 terms)
 *   atan2      the double-double y / x (both scaled by one power of two) into atan, moved
 *              into the quadrant of (x, y) with pi as a double-double
 *   s^(-3/2)   1 / (s sqrt(s)) with sqrt(s) = r + (s - r^2) / (2 r), r = sqrt(s) rounded
 *
 * The interval boundaries and the split constants of pi/2, atan(1/2), atan(1), atan(3/2)
 * and pi are fdlibm's (Copyright (C) 1993 by Sun Microsystems, Inc. All rights reserved.
 * Developed at SunPro, a Sun Microsystems, Inc. business. Permission to use, copy, modify,
 * and distribute this software is freely granted, provided that this notice is preserved.)
 */
#include "pcs_math.h"

#include <math.h>

#include "pcs_float.h"

/* ------------------------------------------------------------------ double-doubles */

typedef struct {
    double hi, lo;             /* the value hi + lo, |lo| <= ulp(hi) / 2 */
} Dd;

static Dd dd(double hi, double lo)
{
    Dd r;
    r.hi = hi;
    r.lo = lo;
    return r;
}

/* a + b exactly (Knuth's TwoSum) */
static Dd two_sum(double a, double b)
{
    double s = a + b, v = s - a;
    return dd(s, (a - (s - v)) + (b - v));
}

/* a + b exactly for |a| >= |b| (Dekker's Fast2Sum) */
static Dd fast_two_sum(double a, double b)
{
    double s = a + b;
    return dd(s, b - (s - a));
}

/* a = hi + lo in two halves of 26 bits (Veltkamp; |a| < 2^995) */
static void split(double a, double *hi, double *lo)
{
    double c = 0x1.0000002p27 * a;           /* (2^27 + 1) a */
    *hi = c - (c - a);
    *lo = a - *hi;
}

/* a b exactly (Dekker's TwoProduct) */
static Dd two_prod(double a, double b)
{
    double p = a * b, ah, al, bh, bl;
    split(a, &ah, &al);
    split(b, &bh, &bl);
    return dd(p, ((ah * bh - p) + ah * bl + al * bh) + al * bl);
}

static Dd dd_add(Dd a, Dd b)
{
    Dd s = two_sum(a.hi, b.hi);
    return fast_two_sum(s.hi, s.lo + (a.lo + b.lo));
}

static Dd dd_mul(Dd a, Dd b)
{
    Dd p = two_prod(a.hi, b.hi);
    return fast_two_sum(p.hi, p.lo + (a.hi * b.lo + a.lo * b.hi));
}

/* a / b: the quotient of the high parts and the quotient of the remainder */
static Dd dd_div(Dd a, Dd b)
{
    double q = a.hi / b.hi;
    Dd p = two_prod(q, b.hi);
    double rest = (((a.hi - p.hi) - p.lo) + a.lo) - q * b.lo;
    return fast_two_sum(q, rest / b.hi);
}

/* sum c_k z^k, k < n (Horner) */
static Dd horner(const double (*c)[2], int n, Dd z)
{
    Dd p = dd(c[n - 1][0], c[n - 1][1]);
    int k;
    for (k = n - 2; k >= 0; k--) p = dd_add(dd_mul(p, z), dd(c[k][0], c[k][1]));
    return p;
}

/* ------------------------------------------------------------------ sin and cos */

/* (-1)^k / (2k + 1)!, k = 0..11, as double-doubles: sin x = x sum c_k x^2k (the first term left
   out is below 2^-92 for |x| <= pi/4) */
static const double SIN_TAYLOR[12][2] = {
    {0x1.0000000000000p+0, 0.0},
    {-0x1.5555555555555p-3, -0x1.5555555555555p-57},
    {0x1.1111111111111p-7, 0x1.1111111111111p-63},
    {-0x1.a01a01a01a01ap-13, -0x1.a01a01a01a01ap-73},
    {0x1.71de3a556c734p-19, -0x1.c154f8ddc6c00p-73},
    {-0x1.ae64567f544e4p-26, 0x1.c062e06d1f209p-80},
    {0x1.6124613a86d09p-33, 0x1.f28e0cc748ebep-87},
    {-0x1.ae7f3e733b81fp-41, -0x1.1d8656b0ee8cbp-97},
    {0x1.952c77030ad4ap-49, 0x1.ac981465ddc6cp-103},
    {-0x1.2f49b46814157p-57, -0x1.2650f61dbdcb4p-112},
    {0x1.71b8ef6dcf572p-66, -0x1.d043ae40c4647p-120},
    {-0x1.761b41316381ap-75, 0x1.3423c7d91404fp-130}};
/* (-1)^k / (2k)!, k = 0..11: cos x = sum c_k x^2k (the first term left out is below 2^-87) */
static const double COS_TAYLOR[12][2] = {
    {0x1.0000000000000p+0, 0.0},
    {-0x1.0000000000000p-1, 0.0},
    {0x1.5555555555555p-5, 0x1.5555555555555p-59},
    {-0x1.6c16c16c16c17p-10, 0x1.f49f49f49f49fp-65},
    {0x1.a01a01a01a01ap-16, 0x1.a01a01a01a01ap-76},
    {-0x1.27e4fb7789f5cp-22, -0x1.cbbc05b4fa99ap-76},
    {0x1.1eed8eff8d898p-29, -0x1.2aec959e14c06p-83},
    {-0x1.93974a8c07c9dp-37, -0x1.05d6f8a2efd1fp-92},
    {0x1.ae7f3e733b81fp-45, 0x1.1d8656b0ee8cbp-101},
    {-0x1.6827863b97d97p-53, -0x1.eec01221a8b0bp-107},
    {0x1.e542ba4020225p-62, 0x1.ea72b4afe3c2fp-120},
    {-0x1.0ce396db7f853p-70, 0x1.aebcdbd20331cp-124}};
/* 2/pi; pi/2 = PIO2_1 + PIO2_2 + PIO2_3 + PIO2_3T, the first three of 33 bits (fdlibm) */
static const double INVPIO2 = 0x1.45f306dc9c883p-1, PIO2_1 = 0x1.921fb54400000p+0,
                    PIO2_2 = 0x1.0b4611a600000p-34, PIO2_3 = 0x1.3198a2e000000p-69,
                    PIO2_3T = 0x1.b839a252049c1p-104;
static const double PIO4 = 0x1.921fb54442d18p-1;

/* sin(x + y), |x + y| <= pi/4, |y| <= ulp(x) / 2, to about 2^-100 */
static double kernel_sin(double x, double y)
{
    Dd s = dd_mul(horner(SIN_TAYLOR, 12, two_prod(x, x)), dd(x, 0.0));
    double z = x * x;
    /* + y cos x, its series to z^4 */
    return s.hi + (s.lo + y * (1.0 - z * (0.5 - z * (1.0 / 24.0 - z * (1.0 / 720.0
                                                                        - z / 40320.0)))));
}

/* cos(x + y), as kernel_sin */
static double kernel_cos(double x, double y)
{
    Dd c = horner(COS_TAYLOR, 12, two_prod(x, x));
    double z = x * x;
    /* - y sin x, its series to x^9 */
    return c.hi + (c.lo - y * x * (1.0 - z * (1.0 / 6.0 - z * (1.0 / 120.0
                                                                - z * (1.0 / 5040.0
                                                                       - z / 362880.0)))));
}

/* x = n pi/2 + y[0] + y[1] (Cody-Waite: x - n PIO2_1 and n PIO2_2, n PIO2_3 are exact for
   |n| < 2^20, the rest is summed as a double-double); returns n mod 4 */
static int reduce(double x, double y[2])
{
    double fn, q;
    Dd r;
    if (fabs(x) <= PIO4) {
        y[0] = x;
        y[1] = 0.0;
        return 0;
    }
    fn = floor(x * INVPIO2 + 0.5);
    r = two_sum(x - fn * PIO2_1, -(fn * PIO2_2));
    r = fast_two_sum(r.hi, (r.lo - fn * PIO2_3) - fn * PIO2_3T);
    y[0] = r.hi;
    y[1] = r.lo;
    q = fn - 4.0 * floor(fn * 0.25);         /* exact: 0, 1, 2 or 3 */
    return (int)q;
}

void pcs_sincos(double x, double *s, double *c)
{
    double y[2], ks, kc;
    int n;
    if (!isfinite(x)) {
        *s = *c = x - x;
        return;
    }
    if (fabs(x) < 0x1p-27) {                 /* sin x = x, cos x = 1 once rounded */
        *s = x;
        *c = 1.0;
        return;
    }
    n = reduce(x, y);
    ks = kernel_sin(y[0], y[1]);
    kc = kernel_cos(y[0], y[1]);
    switch (n) {
    case 0: *s = ks; *c = kc; break;
    case 1: *s = kc; *c = -ks; break;
    case 2: *s = -ks; *c = -kc; break;
    default: *s = -kc; *c = ks; break;
    }
}

double pcs_sin(double x)
{
    double s, c;
    pcs_sincos(x, &s, &c);
    return s;
}

double pcs_cos(double x)
{
    double s, c;
    pcs_sincos(x, &s, &c);
    return c;
}

/* ------------------------------------------------------------------ atan and atan2 */

/* (-1)^k / (2k + 1), k = 0..34: atan t = t sum c_k t^2k for |t| <= 0.4375 (the first term
   left out is below 2^-90) */
static const double ATAN_TAYLOR[35][2] = {
    {0x1.0000000000000p+0, 0.0},
    {-0x1.5555555555555p-2, -0x1.5555555555555p-56},
    {0x1.999999999999ap-3, -0x1.999999999999ap-57},
    {-0x1.2492492492492p-3, -0x1.2492492492492p-57},
    {0x1.c71c71c71c71cp-4, 0x1.c71c71c71c71cp-58},
    {-0x1.745d1745d1746p-4, 0x1.745d1745d1746p-59},
    {0x1.3b13b13b13b14p-4, -0x1.3b13b13b13b14p-58},
    {-0x1.1111111111111p-4, -0x1.1111111111111p-60},
    {0x1.e1e1e1e1e1e1ep-5, 0x1.e1e1e1e1e1e1ep-61},
    {-0x1.af286bca1af28p-5, -0x1.af286bca1af28p-59},
    {0x1.8618618618618p-5, 0x1.8618618618618p-59},
    {-0x1.642c8590b2164p-5, -0x1.642c8590b2164p-60},
    {0x1.47ae147ae147bp-5, -0x1.eb851eb851eb8p-61},
    {-0x1.2f684bda12f68p-5, -0x1.2f684bda12f68p-59},
    {0x1.1a7b9611a7b96p-5, 0x1.1a7b9611a7b96p-61},
    {-0x1.0842108421084p-5, -0x1.0842108421084p-60},
    {0x1.f07c1f07c1f08p-6, -0x1.f07c1f07c1f08p-61},
    {-0x1.d41d41d41d41dp-6, -0x1.0750750750750p-60},
    {0x1.bacf914c1bad0p-6, -0x1.bacf914c1bad0p-60},
    {-0x1.a41a41a41a41ap-6, -0x1.0690690690690p-60},
    {0x1.8f9c18f9c18fap-6, -0x1.f3831f3831f38p-61},
    {-0x1.7d05f417d05f4p-6, -0x1.7d05f417d05f4p-62},
    {0x1.6c16c16c16c17p-6, -0x1.f49f49f49f49fp-61},
    {-0x1.5c9882b931057p-6, -0x1.310572620ae4cp-61},
    {0x1.4e5e0a72f0539p-6, 0x1.e0a72f0539783p-60},
    {-0x1.4141414141414p-6, -0x1.4141414141414p-62},
    {0x1.3521cfb2b78c1p-6, 0x1.a90e7d95bc60ap-61},
    {-0x1.29e4129e4129ep-6, -0x1.04a7904a7904ap-60},
    {0x1.1f7047dc11f70p-6, 0x1.1f7047dc11f70p-60},
    {-0x1.15b1e5f75270dp-6, -0x1.15b1e5f75270dp-64},
    {0x1.0c9714fbcda3bp-6, -0x1.f79b47582192ep-61},
    {-0x1.0410410410410p-6, -0x1.0410410410410p-60},
    {0x1.f81f81f81f820p-7, -0x1.f81f81f81f820p-61},
    {-0x1.e9131abf0b767p-7, -0x1.503d226357e17p-62},
    {0x1.dae6076b981dbp-7, -0x1.9f89467e251a0p-63}};
/* atan(1/2), atan(1), atan(3/2), atan(infinity) = pi/2 and pi as double-doubles (fdlibm) */
static const double ATAN_HI[] = {0x1.dac670561bb4fp-2, 0x1.921fb54442d18p-1,
                                 0x1.f730bd281f69bp-1, 0x1.921fb54442d18p+0};
static const double ATAN_LO[] = {0x1.a2b7f222f65e2p-56, 0x1.1a62633145c07p-55,
                                 0x1.007887af0cbbdp-56, 0x1.1a62633145c07p-54};
static const double PI = 0x1.921fb54442d18p+1, PI_LO = 0x1.1a62633145c07p-53;

/* atan(a + al) for 0 <= a < 2^66, |al| <= ulp(a) / 2 */
static Dd atan_dd(double a, double al)
{
    Dd t, r;
    int id;
    if (a < 0.4375) { id = -1; t = dd(a, 0.0); }
    else if (a < 0.6875) { id = 0; t = dd_div(dd(2.0 * a - 1.0, 0.0), two_sum(2.0, a)); }
    else if (a < 1.1875) { id = 1; t = dd_div(dd(a - 1.0, 0.0), two_sum(a, 1.0)); }
    else if (a < 2.4375) {
        id = 2;
        t = dd_div(dd(a - 1.5, 0.0), dd_add(two_prod(1.5, a), dd(1.0, 0.0)));
    } else { id = 3; t = dd_div(dd(-1.0, 0.0), dd(a, 0.0)); }
    r = dd_mul(horner(ATAN_TAYLOR, 35, dd_mul(t, t)), t);
    r = fast_two_sum(r.hi, r.lo + al / (1.0 + a * a));      /* + al atan'(a) */
    return id < 0 ? r : dd_add(dd(ATAN_HI[id], ATAN_LO[id]), r);
}

double pcs_atan(double x)
{
    double a = fabs(x), r;
    if (isnan(x)) return x + x;
    if (a < 0x1p-29) return x;               /* atan x = x once rounded */
    r = a >= 0x1p66 ? ATAN_HI[3] : atan_dd(a, 0.0).hi;
    return x < 0.0 ? -r : r;
}

/* atan(|y / x|) for finite non-zero x, y: both scaled by one power of two first */
static Dd atan_ratio(double y, double x)
{
    int e;
    Dd q;
    (void)frexp(fabs(x) > fabs(y) ? x : y, &e);
    x = fabs(ldexp(x, -e));
    y = fabs(ldexp(y, -e));
    if (y > 0x1p60 * x) return dd(ATAN_HI[3], ATAN_LO[3]);
    if (y < 0x1p-60 * x) return dd(y / x, 0.0);
    q = dd_div(dd(y, 0.0), dd(x, 0.0));
    return atan_dd(q.hi, q.lo);
}

double pcs_atan2(double y, double x)
{
    Dd z;
    int neg_y = signbit(y) != 0, neg_x = signbit(x) != 0;
    double r;
    if (isnan(x) || isnan(y)) return x + y;
    if (y == 0.0) return neg_x ? (neg_y ? -PI : PI) : y;
    if (x == 0.0 || (isinf(y) && !isinf(x))) return neg_y ? -ATAN_HI[3] : ATAN_HI[3];
    if (isinf(x)) {
        r = isinf(y) ? (neg_x ? 3.0 * ATAN_HI[1] : ATAN_HI[1]) : (neg_x ? PI : 0.0);
        return neg_y ? -r : r;
    }
    z = atan_ratio(y, x);
    r = neg_x ? dd_add(dd(PI, PI_LO), dd(-z.hi, -z.lo)).hi : z.hi;
    return neg_y ? -r : r;
}

/* ------------------------------------------------------------------ s^(-3/2) */

double pcs_pow_minus_three_halves(double s)
{
    double r, e;
    Dd p;
    if (!(s >= 0x1p-500 && s <= 0x1p500)) return 1.0 / (s * sqrt(s));   /* beyond use */
    r = sqrt(s);
    p = two_prod(r, r);
    e = ((s - p.hi) - p.lo) / (2.0 * r);    /* sqrt(s) = r + e */
    return dd_div(dd(1.0, 0.0), dd_mul(dd(s, 0.0), fast_two_sum(r, e))).hi;
}

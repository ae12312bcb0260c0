/*
 * The rigid DSA-380 (dsa380_rigid.h): the arithmetic of dsa380_kinematics.evaluate_kernel.
 *
 * The mechanism (bars 1-6) moves with theta alone: its two loops (A.1) close in closed form
 * (circle intersections, (A.2)-(A.3)) on truncated Taylor series ("jets") in theta to third
 * order, so the implicit derivatives (A.4)-(A.5), the inertia A(theta) (A.7) and its A', A''
 * are exact. The collector (bar 7) is a rigid body in (x10, y10, theta7) (A.6)-(A.9), held by
 * two springs k_l from point 5 to its ends (A.11), Hessian (B.19); a torsional spring k_r at
 * joint 1 (A.10), a damper between 13 and 1p (A.13)-(A.19), collector friction (2.15)-(2.17),
 * the actuation torque (2.14) and the contact force and aerodynamic uplift on point 10.
 */
#include "dsa380_rigid.h"
#include "pcs_float.h"
#include "pcs_math.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

/* a truncated Taylor series (f, f', f''/2, f'''/6) in theta */
typedef struct { double c[4]; } Jet;

static Jet jc(double c) { Jet r = {{c, 0.0, 0.0, 0.0}}; return r; }

static Jet jadd(Jet a, Jet b)
{
    Jet r = {{a.c[0] + b.c[0], a.c[1] + b.c[1], a.c[2] + b.c[2], a.c[3] + b.c[3]}};
    return r;
}

static Jet jsub(Jet a, Jet b)
{
    Jet r = {{a.c[0] - b.c[0], a.c[1] - b.c[1], a.c[2] - b.c[2], a.c[3] - b.c[3]}};
    return r;
}

static Jet jscale(Jet a, double s)
{
    Jet r = {{a.c[0] * s, a.c[1] * s, a.c[2] * s, a.c[3] * s}};
    return r;
}

static Jet jaddc(Jet a, double c) { a.c[0] = a.c[0] + c; return a; }

static Jet jmul(Jet a, Jet b)
{
    Jet r = {{a.c[0] * b.c[0],
              a.c[0] * b.c[1] + a.c[1] * b.c[0],
              a.c[0] * b.c[2] + a.c[1] * b.c[1] + a.c[2] * b.c[0],
              a.c[0] * b.c[3] + a.c[1] * b.c[2] + a.c[2] * b.c[1] + a.c[3] * b.c[0]}};
    return r;
}

static Jet jdiv(Jet a, Jet b)
{
    Jet r;
    r.c[0] = a.c[0] / b.c[0];
    r.c[1] = (a.c[1] - b.c[1] * r.c[0]) / b.c[0];
    r.c[2] = (a.c[2] - b.c[1] * r.c[1] - b.c[2] * r.c[0]) / b.c[0];
    r.c[3] = (a.c[3] - b.c[1] * r.c[2] - b.c[2] * r.c[1] - b.c[3] * r.c[0]) / b.c[0];
    return r;
}

static Jet jsqrt(Jet a)
{
    Jet r;
    r.c[0] = sqrt(a.c[0]);
    r.c[1] = a.c[1] / (2.0 * r.c[0]);
    r.c[2] = (a.c[2] - r.c[1] * r.c[1]) / (2.0 * r.c[0]);
    r.c[3] = (a.c[3] - 2.0 * r.c[1] * r.c[2]) / (2.0 * r.c[0]);
    return r;
}

static void jsincos(Jet a, Jet *s, Jet *c)
{
    pcs_sincos(a.c[0], &s->c[0], &c->c[0]);
    s->c[1] = a.c[1] * c->c[0];
    c->c[1] = -a.c[1] * s->c[0];
    s->c[2] = (a.c[1] * c->c[1] + 2.0 * a.c[2] * c->c[0]) / 2.0;
    c->c[2] = -(a.c[1] * s->c[1] + 2.0 * a.c[2] * s->c[0]) / 2.0;
    s->c[3] = (a.c[1] * c->c[2] + 2.0 * a.c[2] * c->c[1] + 3.0 * a.c[3] * c->c[0]) / 3.0;
    c->c[3] = -(a.c[1] * s->c[2] + 2.0 * a.c[2] * s->c[1] + 3.0 * a.c[3] * s->c[0]) / 3.0;
}

/* d/dtheta of a jet (the top coefficient is lost) */
static Jet jderiv(Jet a)
{
    Jet r = {{a.c[1], 2.0 * a.c[2], 3.0 * a.c[3], 0.0}};
    return r;
}

static Jet jatan2(Jet y, Jet x)
{
    Jet r2 = jadd(jmul(x, x), jmul(y, y));
    Jet w = jdiv(jsub(jmul(x, jderiv(y)), jmul(y, jderiv(x))), r2);
    Jet r = {{pcs_atan2(y.c[0], x.c[0]), w.c[0], w.c[1] / 2.0, w.c[2] / 3.0}};
    return r;
}

/* joint X of a two-bar chain P -(la)- X -(lb)- Q, closed form of (A.2)-(A.3); returns h^2
   (<= 0: the loop cannot close) */
static double circle_point(Jet px, Jet py, Jet qx, Jet qy, double la, double lb,
                           double sigma, Jet *xx, Jet *yy)
{
    Jet dx = jsub(qx, px), dy = jsub(qy, py);
    Jet d2 = jadd(jmul(dx, dx), jmul(dy, dy));
    Jet d = jsqrt(d2);
    Jet aa = jdiv(jaddc(d2, la * la - lb * lb), jscale(d, 2.0));
    Jet h2 = jsub(jc(la * la), jmul(aa, aa));
    Jet h, fa, fh;
    if (!(h2.c[0] > 0.0)) {
        *xx = px;
        *yy = py;
        return h2.c[0];
    }
    h = jscale(jsqrt(h2), sigma);
    fa = jdiv(aa, d);
    fh = jdiv(h, d);
    *xx = jadd(px, jsub(jmul(fa, dx), jmul(fh, dy)));
    *yy = jadd(py, jadd(jmul(fa, dy), jmul(fh, dx)));
    return h2.c[0];
}

/* the mechanism's points (1, 2, 3, 4, 5, 6, 5b, 1p) and bar angles (1..6) as jets in theta;
   returns min h^2 of the two loops (A.1) */
static double mechanism_jets(const double *P, double theta, Jet *px, Jet *py, Jet *ang)
{
    Jet th = {{theta, 1.0, 0.0, 0.0}}, s1, c1, s4, c4, s6, c6, sp, cp;
    double h_lo, h_up;
    px[0] = jc(P[DSA_P_X1]);
    py[0] = jc(P[DSA_P_Y1]);
    px[1] = jc(P[DSA_P_X2]);
    py[1] = jc(P[DSA_P_Y2]);
    jsincos(th, &s1, &c1);
    px[3] = jadd(px[0], jscale(c1, P[DSA_P_L1]));
    py[3] = jadd(py[0], jscale(s1, P[DSA_P_L1]));
    /* lower loop fixed-1-2-3: 2 -(L2)- 3 -(L3)- 4 */
    h_lo = circle_point(px[1], py[1], px[3], py[3], P[DSA_P_L1 + 1], P[DSA_P_L1 + 2],
                        P[DSA_P_SIG_LO], &px[2], &py[2]);
    ang[0] = th;
    ang[1] = jatan2(jsub(py[2], py[1]), jsub(px[2], px[1]));
    ang[2] = jatan2(jsub(py[3], py[2]), jsub(px[3], px[2]));
    ang[3] = jaddc(ang[2], P[DSA_P_TH34] - M_PI);
    jsincos(ang[3], &s4, &c4);
    px[4] = jadd(px[3], jscale(c4, P[DSA_P_L1 + 3]));
    py[4] = jadd(py[3], jscale(s4, P[DSA_P_L1 + 3]));
    /* upper loop 1-4-5-6: 6 -(L5)- 5b -(L6)- 5, point 6 on bar 1 at (r, theta_r) */
    jsincos(jaddc(th, P[DSA_P_THR]), &s6, &c6);
    px[5] = jadd(px[0], jscale(c6, P[DSA_P_R6]));
    py[5] = jadd(py[0], jscale(s6, P[DSA_P_R6]));
    h_up = circle_point(px[5], py[5], px[4], py[4], P[DSA_P_L1 + 4], P[DSA_P_L1 + 5],
                        P[DSA_P_SIG_UP], &px[6], &py[6]);
    ang[4] = jatan2(jsub(py[6], py[5]), jsub(px[6], px[5]));
    ang[5] = jatan2(jsub(py[4], py[6]), jsub(px[4], px[6]));
    /* damper lever point 1p (A.13) */
    jsincos(jaddc(th, P[DSA_P_TH1P]), &sp, &cp);
    px[7] = jadd(px[0], jscale(cp, P[DSA_P_L1P]));
    py[7] = jadd(py[0], jscale(sp, P[DSA_P_L1P]));
    return h_lo < h_up ? h_lo : h_up;
}

/* start point (index into the points) of bars 1..6 */
static const int BAR_START[6] = {0, 1, 2, 3, 5, 6};

/* inertia A(theta) (A.7), gravity + torsional-spring potential (A.10) and point 5:
   A = (A, A', A''), V = (V, V', V''), p5 = (x5, y5, x5', y5', x5'', y5''); returns min h^2 of
   the loops (<= 0: they do not close) */
static double mechanism(const double *P, double theta, double *A, double *V, double *p5)
{
    Jet px[8], py[8], ang[6];
    double ok = mechanism_jets(P, theta, px, py, ang), g = P[DSA_P_GRAV], dth;
    int i;
    for (i = 0; i < 3; i++) A[i] = V[i] = 0.0;
    if (!(ok > 0.0)) return ok;
    for (i = 0; i < 6; i++) {
        int st = BAR_START[i];
        Jet sg, cg, xg, yg, xd, yd, wd, ai;
        double m = P[DSA_P_M_ + i];
        jsincos(jaddc(ang[i], -P[DSA_P_THG_ + i]), &sg, &cg);
        xg = jadd(px[st], jscale(cg, P[DSA_P_LG_ + i]));
        yg = jadd(py[st], jscale(sg, P[DSA_P_LG_ + i]));
        xd = jderiv(xg);
        yd = jderiv(yg);
        wd = jderiv(ang[i]);
        ai = jadd(jscale(jadd(jmul(xd, xd), jmul(yd, yd)), m), jscale(jmul(wd, wd),
                                                                       P[DSA_P_I_ + i]));
        A[0] += ai.c[0];
        A[1] += ai.c[1];
        A[2] += 2.0 * ai.c[2];
        V[0] += g * m * yg.c[0];
        V[1] += g * m * yg.c[1];
        V[2] += 2.0 * g * m * yg.c[2];
    }
    dth = theta - P[DSA_P_THR0];
    V[0] += 0.5 * P[DSA_P_KR] * dth * dth;
    V[1] += P[DSA_P_KR] * dth;
    V[2] += P[DSA_P_KR];
    p5[0] = px[4].c[0];
    p5[1] = py[4].c[0];
    p5[2] = px[4].c[1];
    p5[3] = py[4].c[1];
    p5[4] = 2.0 * px[4].c[2];
    p5[5] = 2.0 * py[4].c[2];
    return ok;
}

/* the physical ranges of the parameter set (dsa380.Dsa380Parameters.validate): 0 or -1 with
   the value named in msg */
static int check_ranges(const double *k, char *msg)
{
    static const struct { int index, count; double lo; int open; const char *name; } R[] = {
        {DSA_P_L1, 7, 0.0, 1, "bar length"}, {DSA_P_M_, 7, 0.0, 1, "bar mass"},
        {DSA_P_I_, 7, 0.0, 0, "bar inertia"}, {DSA_P_LG_, 7, 0.0, 0, "centre-of-gravity offset"},
        {DSA_P_R6, 1, 0.0, 1, "links.r"}, {DSA_P_L1P, 1, 0.0, 1, "damper.L1p"},
        {DSA_P_KR, 1, 0.0, 0, "springs.k_r"}, {DSA_P_KL, 1, 0.0, 1, "springs.k_l"},
        {DSA_P_LL0, 1, 0.0, 0, "springs.l0"}, {DSA_P_CDAMP, 1, 0.0, 0, "damper.c"},
        {DSA_P_GRAV, 1, 0.0, 0, "g"}, {DSA_K_FRICTION_FORCE, 1, 0.0, 0, "friction_force"}};
    size_t r;
    int i;
    for (r = 0; r < sizeof R / sizeof R[0]; r++)
        for (i = R[r].index; i < R[r].index + R[r].count; i++)
            if (R[r].open ? !(k[i] > R[r].lo) : !(k[i] >= R[r].lo)) {
                snprintf(msg, HHT_MSG, "DSA-380 constants: %s (value %d) = %g (must be %s %g)",
                         R[r].name, i, k[i], R[r].open ? ">" : ">=", R[r].lo);
                return -1;
            }
    for (i = DSA_P_SIG_LO; i <= DSA_P_SIG_UP; i++)
        if (k[i] != 1.0 && k[i] != -1.0) {
            snprintf(msg, HHT_MSG, "DSA-380 constants: assembly mode (value %d) = %g (must be "
                     "+1 or -1)", i, k[i]);
            return -1;
        }
    return 0;
}

int dsa380_setup(Dsa380 *m, const double *k, long count, char *msg)
{
    int i;
    if (count != DSA_K_COUNT) {
        snprintf(msg, HHT_MSG, "DSA-380 constants: %ld values, this model takes %d", count,
                 DSA_K_COUNT);
        return -1;
    }
    for (i = 0; i < DSA_K_COUNT; i++)
        if (!isfinite(k[i])) {
            snprintf(msg, HHT_MSG, "DSA-380 constants: value %d is %g (must be finite)", i,
                     k[i]);
            return -1;
        }
    if (check_ranges(k, msg)) return -1;
    memset(m, 0, sizeof *m);
    memcpy(m->P, k, sizeof m->P);
    m->n_dofs = k[DSA_K_PITCH_LOCK] != 0.0 ? 3 : 4;
    m->act.torque = k[DSA_K_TORQUE];
    m->act.ramp = k[DSA_K_RAMP] != 0.0;
    m->act.torque_lowered = k[DSA_K_TORQUE_LOWERED];
    m->act.ramp_start = k[DSA_K_RAMP_START];
    m->act.ramp_duration = k[DSA_K_RAMP_DURATION];
    m->aero_force = k[DSA_K_AERO_FORCE];
    m->friction_force = k[DSA_K_FRICTION_FORCE];
    m->friction_smoothing = k[DSA_K_FRICTION_SMOOTHING];
    m->one_way = k[DSA_K_ONE_WAY_DAMPER] != 0.0;
    if (m->friction_force > 0.0 && !(m->friction_smoothing > 0.0)) {
        snprintf(msg, HHT_MSG, "DSA-380 constants: friction_smoothing = %g (must be > 0)",
                 m->friction_smoothing);
        return -1;
    }
    return 0;
}

/* inertia (A.9) and d(M a)/dq (3.28) */
static void inertia(Dsa380 *m, const double *A, double sg, double cg)
{
    double (*Mm)[4] = m->mat[0], (*Kin)[4] = m->mat[1], *a = m->a4;
    double m7 = m->P[DSA_P_M_ + 6], LG7 = m->P[DSA_P_LG_ + 6];
    int k, j;
    Mm[0][0] = A[0];
    Mm[1][1] = m7;
    Mm[2][2] = m7;
    Mm[1][3] = Mm[3][1] = -m7 * LG7 * sg;
    Mm[2][3] = Mm[3][2] = m7 * LG7 * cg;
    Mm[3][3] = m->P[DSA_P_I_ + 6] + m7 * LG7 * LG7;
    for (k = 0; k < 4; k++) {
        double s = 0.0;
        for (j = 0; j < 4; j++) s += Mm[k][j] * a[j];
        m->vec[0][k] = s;
    }
    Kin[0][0] = A[1] * a[0];
    Kin[1][3] = -m7 * LG7 * cg * a[3];
    Kin[2][3] = -m7 * LG7 * sg * a[3];
    Kin[3][3] = -m7 * LG7 * (cg * a[1] + sg * a[2]);
}

/* Coriolis and centrifugal terms of T = 1/2 qdot^T M qdot, gravity and the torsional spring
   (A.10) */
static void motion_terms(Dsa380 *m, const double *A, const double *V, double sg, double cg)
{
    double *fr = m->vec[1], (*Cd)[4] = m->mat[2], (*Ks)[4] = m->mat[3];
    double m7 = m->P[DSA_P_M_ + 6], LG7 = m->P[DSA_P_LG_ + 6], g = m->P[DSA_P_GRAV];
    double w = m->v4[0], w7 = m->v4[3];
    fr[0] += 0.5 * A[1] * w * w;
    Ks[0][0] += 0.5 * A[2] * w * w;
    Cd[0][0] += A[1] * w;
    fr[1] += -m7 * LG7 * cg * w7 * w7;
    fr[2] += -m7 * LG7 * sg * w7 * w7;
    Ks[1][3] += m7 * LG7 * sg * w7 * w7;
    Ks[2][3] += -m7 * LG7 * cg * w7 * w7;
    Cd[1][3] += -2.0 * m7 * LG7 * cg * w7;
    Cd[2][3] += -2.0 * m7 * LG7 * sg * w7;
    fr[0] += V[1];
    Ks[0][0] += V[2];
    fr[2] += m7 * g;
    fr[3] += m7 * g * LG7 * cg;
    Ks[3][3] += -m7 * g * LG7 * sg;
}

/* the collector springs from point 5 to the ends 11, 12 (A.11), Hessian (B.19) */
static void collector_springs(Dsa380 *m, const double *p5)
{
    double *fr = m->vec[1], (*Ks)[4] = m->mat[3];
    double half = 0.5 * m->P[DSA_P_L1 + 6], kl = m->P[DSA_P_KL], l0 = m->P[DSA_P_LL0];
    double c7 = pcs_cos(m->q4[3]), s7 = pcs_sin(m->q4[3]), x10 = m->q4[1], y10 = m->q4[2];
    double D[2][4], gl[4], se;
    int k, j, side;
    for (side = 0; side < 2; side++) {
        double dx, dy, ll, ux, uy, tension;
        se = side == 0 ? -1.0 : 1.0;
        dx = p5[0] - x10 - se * half * c7;
        dy = p5[1] - y10 - se * half * s7;
        ll = sqrt(dx * dx + dy * dy);
        ux = dx / ll;
        uy = dy / ll;
        D[0][0] = p5[2];
        D[1][0] = p5[3];
        D[0][1] = -1.0;
        D[1][1] = 0.0;
        D[0][2] = 0.0;
        D[1][2] = -1.0;
        D[0][3] = se * half * s7;
        D[1][3] = -se * half * c7;
        for (j = 0; j < 4; j++) gl[j] = ux * D[0][j] + uy * D[1][j];
        tension = kl * (ll - l0);
        for (k = 0; k < 4; k++) {
            fr[k] += tension * gl[k];
            for (j = 0; j < 4; j++) {
                double hkj = (D[0][k] * D[0][j] + D[1][k] * D[1][j] - gl[k] * gl[j]) / ll;
                Ks[k][j] += kl * gl[k] * gl[j] + tension * hkj;
            }
        }
        Ks[0][0] += tension * (ux * p5[4] + uy * p5[5]);
        Ks[3][3] += tension * se * half * (ux * c7 + uy * s7);
    }
}

/* damper length l_a and its theta-derivatives (A.14), (A.20) */
static void damper_geometry(const double *P, double theta, double *la, double *d1,
                            double *d2)
{
    double c = pcs_cos(theta + P[DSA_P_TH1P]), s = pcs_sin(theta + P[DSA_P_TH1P]);
    double dx = P[DSA_P_X1] + P[DSA_P_L1P] * c - P[DSA_P_X13];
    double dy = P[DSA_P_Y1] + P[DSA_P_L1P] * s - P[DSA_P_Y13];
    double tx = -P[DSA_P_L1P] * s, ty = P[DSA_P_L1P] * c;
    *la = sqrt(dx * dx + dy * dy);
    *d1 = (dx * tx + dy * ty) / *la;
    *d2 = (tx * tx + ty * ty - P[DSA_P_L1P] * (dx * c + dy * s)) / *la - *d1 * *d1 / *la;
}

/* the damper between 13 and 1p (A.13)-(A.19), one-way when asked (it acts while point 5
   descends), and the collector friction (2.15)-(2.17), (3.31)-(3.33) */
static void damper_and_friction(Dsa380 *m, const double *p5)
{
    double *fr = m->vec[1], (*Cd)[4] = m->mat[2], (*Ks)[4] = m->mat[3];
    double w = m->v4[0], la, la1, la2, wdown = 1.0, cth;
    damper_geometry(m->P, m->q4[0], &la, &la1, &la2);
    if (m->one_way && p5[3] * w > 0.0) wdown = 0.0;
    cth = m->P[DSA_P_CDAMP] * wdown;
    fr[0] += cth * la1 * la1 * w;
    Cd[0][0] += cth * la1 * la1;
    Ks[0][0] += 2.0 * cth * la1 * la2 * w;
    if (m->friction_force > 0.0) {
        double f_r = m->friction_force, k_t = m->friction_smoothing;
        double vr = m->v4[2] - p5[3] * w;
        double f_roz = f_r * (2.0 / M_PI) * pcs_atan(vr / k_t);
        double df = f_r * (2.0 / M_PI) / (k_t + vr * vr / k_t);
        double dvr_dth = -p5[5] * w;
        fr[0] += -f_roz * p5[3];
        fr[2] += f_roz;
        Cd[0][0] += df * p5[3] * p5[3];
        Cd[0][2] += -df * p5[3];
        Cd[2][0] += -df * p5[3];
        Cd[2][2] += df;
        Ks[0][0] += -df * dvr_dth * p5[3] - f_roz * p5[5];
        Ks[2][0] += df * dvr_dth;
    }
}

/* the 4-coordinate kernel at m->q4, v4, a4 (A.36), (3.27)-(3.34), (B.19) into m->vec[0..1]
   and m->mat; returns the loop-closure measure */
static double kernel(Dsa380 *m, double F, double M_act)
{
    double A[3], V[3], p5[6], ok = mechanism(m->P, m->q4[0], A, V, p5);
    double th7 = m->q4[3], sg, cg;
    memset(m->vec, 0, sizeof m->vec);
    memset(m->mat, 0, sizeof m->mat);
    if (!(ok > 0.0)) return ok;
    sg = pcs_sin(th7 - m->P[DSA_P_THG_ + 6]);
    cg = pcs_cos(th7 - m->P[DSA_P_THG_ + 6]);
    inertia(m, A, sg, cg);
    motion_terms(m, A, V, sg, cg);
    collector_springs(m, p5);
    damper_and_friction(m, p5);
    m->vec[1][0] -= M_act;
    m->vec[1][2] += F - m->aero_force;
    return ok;
}

int dsa380_evaluate(void *model, double t, const double *q, const double *v, const double *a,
                    const double *inputs, int tangent, HhtEval *out, char *msg)
{
    Dsa380 *m = (Dsa380 *)model;
    int n = m->n_dofs, i, j;
    double F = inputs ? inputs[0] : 0.0;
    if (!isfinite(F)) {
        snprintf(msg, HHT_MSG, "contact_force = %g: must be finite", F);
        return -1;
    }
    for (i = 0; i < 4; i++) {
        m->q4[i] = i < n ? q[i] : 0.0;
        m->v4[i] = i < n ? v[i] : 0.0;
        m->a4[i] = i < n ? a[i] : 0.0;
    }
    if (!(kernel(m, F, actuation_torque(&m->act, t)) > 0.0)) {
        snprintf(msg, HHT_MSG, "theta = %.6g rad: the mechanism loops (A.1) cannot be closed "
                 "at this angle", m->q4[0]);
        return -1;
    }
    for (i = 0; i < n; i++) {
        out->f_inertia[i] = m->vec[0][i];
        out->f_rest[i] = m->vec[1][i];
        if (!tangent) continue;
        for (j = 0; j < n; j++) {
            out->mass[i * n + j] = m->mat[0][i][j];
            out->inertia_q[i * n + j] = m->mat[1][i][j];
            out->damping[i * n + j] = m->mat[2][i][j];
            out->stiffness[i * n + j] = m->mat[3][i][j];
        }
    }
    return 0;
}

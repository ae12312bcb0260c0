/*
 * The flexible-bar DSA-380 (dsa380_flexible.h): the arithmetic of dsa380_flexible.assemble
 * and beam_ancf.elastic_elements, gather and scatter_add.
 *
 * Beam elements: planar ANCF, e = (r1, r1_x, r2, r2_x), cubic Hermite shape functions;
 * U = 1/2 int (EA eps^2 + EI (kappa - kappa0)^2) dx with eps = r0_x . dr_x + |dr_x|^2 / 2
 * and kappa = (r_x x r_xx) / |r_x|^3, measured from the straight reference E0, 5 Gauss points.
 */
#include "dsa380_flexible.h"
#include "pcs_float.h"
#include "pcs_math.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif


size_t dsf_work_bytes(int n, int ne)
{
    if (n < 1 || n > DSF_MAX_N || ne < 1 || ne > DSF_MAX_NE) return 0;
    return ((size_t)n + 16 * (size_t)ne + 64 * (size_t)ne) * sizeof(double);
}

/* an index constant in [lo, hi]; -1 with the reason in msg otherwise */
static int index_of(const double *k, int which, int lo, int hi, char *msg)
{
    double x = k[which];
    if (!(x >= lo && x <= hi) || x != floor(x)) {
        snprintf(msg, HHT_MSG, "flexible DSA-380 constants: value %d = %g (an index in %d .. %d)",
                 which, x, lo, hi);
        return -1;
    }
    return (int)x;
}

static int finite_array(const double *x, size_t n, const char *name, char *msg)
{
    size_t i;
    for (i = 0; i < n; i++)
        if (!isfinite(x[i])) {
            snprintf(msg, HHT_MSG, "flexible DSA-380: %s[%lu] = %g (must be finite)", name,
                     (unsigned long)i, x[i]);
            return -1;
        }
    return 0;
}

static int check_arrays(const Dsa380Flex *m, char *msg)
{
    size_t n = (size_t)m->n, ne = (size_t)m->ne, i;
    const DsfArrays *a = &m->a;
    if (finite_array(a->q_ref, n, "q_ref", msg) || finite_array(a->M, n * n, "M", msg) ||
        finite_array(a->Qg, n, "Qg", msg) || finite_array(a->E0, 8 * ne, "E0", msg) ||
        finite_array(a->EA, ne, "EA", msg) || finite_array(a->EI, ne, "EI", msg) ||
        finite_array(a->pR, 16 * ne, "pR", msg) ||
        finite_array(a->xi_g, (size_t)m->ng, "xi_g", msg) ||
        finite_array(a->w_g, (size_t)m->ng, "w_g", msg))
        return -1;
    for (i = 0; i < ne; i++)
        if (!(a->length[i] > 0.0 && a->EA[i] > 0.0 && a->EI[i] > 0.0) ||
            !isfinite(a->length[i])) {
            snprintf(msg, HHT_MSG, "flexible DSA-380: element %lu: length %g m, EA %g N, EI %g "
                     "N m^2 (each must be > 0)", (unsigned long)i, a->length[i], a->EA[i],
                     a->EI[i]);
            return -1;
        }
    for (i = 0; i < 4 * ne; i++)
        if (a->pg[i] < -1 || a->pg[i] > m->n - 2) {
            snprintf(msg, HHT_MSG, "flexible DSA-380: pg[%lu] = %d (accepted -1 .. %d)",
                     (unsigned long)i, a->pg[i], m->n - 2);
            return -1;
        }
    return 0;
}

static int read_indices(Dsa380Flex *m, const double *k, char *msg)
{
    int top = m->n - 2;
    if ((m->p5 = index_of(k, DSF_K_P5, 0, top, msg)) < 0) return -1;
    if ((m->p11 = index_of(k, DSF_K_P11, 0, top, msg)) < 0) return -1;
    if ((m->p12 = index_of(k, DSF_K_P12, 0, top, msg)) < 0) return -1;
    if ((m->p1p = index_of(k, DSF_K_P1P, 0, top, msg)) < 0) return -1;
    if ((m->s1 = index_of(k, DSF_K_S1, 0, top, msg)) < 0) return -1;
    if ((m->y10 = index_of(k, DSF_K_Y10, 0, m->n - 1, msg)) < 0) return -1;
    if ((m->y5 = index_of(k, DSF_K_Y5, 0, m->n - 1, msg)) < 0) return -1;
    return 0;
}

int dsf_setup(Dsa380Flex *m, const double *k, long count, const DsfArrays *arrays, void *work,
              size_t work_bytes, char *msg)
{
    memset(m, 0, sizeof *m);
    if (count != DSF_K_COUNT || finite_array(k, DSF_K_COUNT, "constants", msg)) {
        if (count != DSF_K_COUNT)
            snprintf(msg, HHT_MSG, "flexible DSA-380 constants: %ld values, this model takes %d",
                     count, DSF_K_COUNT);
        return -1;
    }
    if ((m->n = index_of(k, DSF_K_N, 2, DSF_MAX_N, msg)) < 0 ||
        (m->ne = index_of(k, DSF_K_NE, 1, DSF_MAX_NE, msg)) < 0 ||
        (m->ng = index_of(k, DSF_K_NG, 1, DSF_MAX_NG, msg)) < 0 || read_indices(m, k, msg))
        return -1;
    m->a = *arrays;
    if (check_arrays(m, msg)) return -1;
    if (!work || work_bytes < dsf_work_bytes(m->n, m->ne)) {
        snprintf(msg, HHT_MSG, "flexible DSA-380: %lu bytes of work memory (needs %lu)",
                 (unsigned long)work_bytes, (unsigned long)dsf_work_bytes(m->n, m->ne));
        return -1;
    }
    m->kl = k[DSF_K_KL]; m->l0 = k[DSF_K_L0]; m->c = k[DSF_K_C];
    m->x13 = k[DSF_K_X13]; m->y13 = k[DSF_K_Y13]; m->kr = k[DSF_K_KR]; m->th0 = k[DSF_K_TH0];
    m->one_way = k[DSF_K_ONE_WAY_DAMPER] != 0.0;
    m->friction_force = k[DSF_K_FRICTION_FORCE];
    m->friction_smoothing = k[DSF_K_FRICTION_SMOOTHING];
    m->aero_force = k[DSF_K_AERO_FORCE];
    m->act.torque = k[DSF_K_TORQUE];
    m->act.ramp = k[DSF_K_RAMP] != 0.0;
    m->act.torque_lowered = k[DSF_K_TORQUE_LOWERED];
    m->act.ramp_start = k[DSF_K_RAMP_START];
    m->act.ramp_duration = k[DSF_K_RAMP_DURATION];
    if (!(m->kl > 0.0 && m->l0 >= 0.0 && m->c >= 0.0 && m->kr >= 0.0 &&
          m->friction_force >= 0.0) ||
        (m->friction_force > 0.0 && !(m->friction_smoothing > 0.0))) {
        snprintf(msg, HHT_MSG, "flexible DSA-380: springs k_l = %g N/m (> 0), l0 = %g m (>= 0), "
                 "damper c = %g N s/m (>= 0), k_r = %g N m/rad (>= 0), friction %g N (>= 0) "
                 "smoothed over %g m/s (> 0)", m->kl, m->l0, m->c, m->kr, m->friction_force,
                 m->friction_smoothing);
        return -1;
    }
    m->q = (double *)work;
    m->dE = m->q + m->n;
    m->Fe = m->dE + 8 * (size_t)m->ne;
    m->Ke = m->Fe + 8 * (size_t)m->ne;
    return 0;
}

/* Hermite functions' x-derivatives at xi: N_x, N_xx (beam_ancf.shape_derivatives) */
static void shape_derivatives(double xi, double l, double *Nx, double *Nxx)
{
    double x2 = xi * xi;
    Nx[0] = (-6.0 * xi + 6.0 * x2) / l;
    Nx[1] = 1.0 - 4.0 * xi + 3.0 * x2;
    Nx[2] = (6.0 * xi - 6.0 * x2) / l;
    Nx[3] = 3.0 * x2 - 2.0 * xi;
    Nxx[0] = (-6.0 + 12.0 * xi) / (l * l);
    Nxx[1] = (-4.0 + 6.0 * xi) / l;
    Nxx[2] = (6.0 - 12.0 * xi) / (l * l);
    Nxx[3] = (6.0 * xi - 2.0) / l;
}

/* one Gauss point's strains: the reference r0_x, r0_xx, the displacement's d_x, d_xx */
typedef struct {
    double Sx[2][8], Sxx[2][8];
    double r0x, r0y, dx, dy, dxx, dyy, r0xx, r0yy;
} Point;

static void gauss_point(const double *E0, const double *dE, double xi, double l, Point *p)
{
    double Nx[4], Nxx[4], ux, uy;
    int a;
    shape_derivatives(xi, l, Nx, Nxx);
    memset(p, 0, sizeof *p);
    for (a = 0; a < 4; a++) {
        p->Sx[0][2 * a] = Nx[a];
        p->Sx[1][2 * a + 1] = Nx[a];
        p->Sxx[0][2 * a] = Nxx[a];
        p->Sxx[1][2 * a + 1] = Nxx[a];
        p->r0x += Nx[a] * E0[2 * a];
        p->r0y += Nx[a] * E0[2 * a + 1];
        p->r0xx += Nxx[a] * E0[2 * a];
        p->r0yy += Nxx[a] * E0[2 * a + 1];
    }
    /* N1' = -N3', N1'' = -N3'': node 1's displacement drops out exactly */
    ux = dE[4] - dE[0];
    uy = dE[5] - dE[1];
    p->dx = Nx[2] * ux + Nx[1] * dE[2] + Nx[3] * dE[6];
    p->dy = Nx[2] * uy + Nx[1] * dE[3] + Nx[3] * dE[7];
    p->dxx = Nxx[2] * ux + Nxx[1] * dE[2] + Nxx[3] * dE[6];
    p->dyy = Nxx[2] * uy + Nxx[1] * dE[3] + Nxx[3] * dE[7];
}

/* the elastic force dU/de (f) and its exact Hessian (K, 8 x 8) of one element */
static void element(const Dsa380Flex *m, int k, double *f, double *K)
{
    double l = m->a.length[k], ce[8], se[8], ke[8], epse[8];
    int gp, i, j;
    memset(f, 0, 8 * sizeof(double));
    memset(K, 0, 64 * sizeof(double));
    for (gp = 0; gp < m->ng; gp++) {
        Point p;
        double wl = m->a.w_g[gp] * l, rx0, rx1, rxx0, rxx1, s0, kap0, eps, s, c, s32, s52,
               s72, kap, ea, ei;
        gauss_point(m->a.E0 + 8 * k, m->dE + 8 * k, m->a.xi_g[gp], l, &p);
        rx0 = p.r0x + p.dx;
        rx1 = p.r0y + p.dy;
        rxx0 = p.r0xx + p.dxx;
        rxx1 = p.r0yy + p.dyy;
        s0 = p.r0x * p.r0x + p.r0y * p.r0y;
        kap0 = (p.r0x * p.r0yy - p.r0y * p.r0xx) * pcs_pow_minus_three_halves(s0);
        eps = p.r0x * p.dx + p.r0y * p.dy + 0.5 * (p.dx * p.dx + p.dy * p.dy);
        s = rx0 * rx0 + rx1 * rx1;
        c = rx0 * rxx1 - rx1 * rxx0;
        s32 = pcs_pow_minus_three_halves(s);
        s52 = s32 / s;
        s72 = s52 / s;
        kap = c * s32 - kap0;
        for (i = 0; i < 8; i++) {
            epse[i] = p.Sx[0][i] * rx0 + p.Sx[1][i] * rx1;
            se[i] = 2.0 * epse[i];
            ce[i] = p.Sx[0][i] * rxx1 - p.Sx[1][i] * rxx0 + p.Sxx[1][i] * rx0 -
                    p.Sxx[0][i] * rx1;
            ke[i] = s32 * ce[i] - 1.5 * c * s52 * se[i];
        }
        ea = m->a.EA[k] * wl;
        ei = m->a.EI[k] * wl;
        for (i = 0; i < 8; i++) f[i] += ea * eps * epse[i] + ei * kap * ke[i];
        for (i = 0; i < 8; i++)
            for (j = 0; j < 8; j++) {
                double sxsx = p.Sx[0][i] * p.Sx[0][j] + p.Sx[1][i] * p.Sx[1][j];
                double cee = p.Sx[0][i] * p.Sxx[1][j] - p.Sx[1][i] * p.Sxx[0][j] +
                             p.Sxx[1][i] * p.Sx[0][j] - p.Sxx[0][i] * p.Sx[1][j];
                double kee = s32 * cee - 1.5 * s52 * (ce[i] * se[j] + se[i] * ce[j]) +
                             3.75 * c * s72 * se[i] * se[j] - 3.0 * c * s52 * sxsx;
                K[8 * i + j] += ea * (epse[i] * epse[j] + eps * sxsx) +
                                ei * (ke[i] * ke[j] + kap * kee);
            }
    }
}

/* element displacements from the unknowns: pair p of element k is R u[g:g+2] (g >= 0) */
static void gather(Dsa380Flex *m, const double *u)
{
    int k, p, i;
    for (k = 0; k < m->ne; k++)
        for (p = 0; p < 4; p++) {
            int g = m->a.pg[4 * k + p];
            const double *R = m->a.pR + 16 * k + 4 * p;
            for (i = 0; i < 2; i++)
                m->dE[8 * k + 2 * p + i] = g >= 0 ? 0.0 + (R[2 * i] * u[g] + R[2 * i + 1] *
                                                            u[g + 1]) : 0.0;
        }
}

/* f += T^T Fe and (K given) K += T^T Ke T of element k */
static void scatter(const Dsa380Flex *m, int k, double *f, double *K)
{
    int p, r, i, j, a, b, n = m->n;
    const double *Fe = m->Fe + 8 * k, *Ke = m->Ke + 64 * k;
    for (p = 0; p < 4; p++) {
        int gp = m->a.pg[4 * k + p];
        const double *Rp = m->a.pR + 16 * k + 4 * p;
        if (gp < 0) continue;
        for (j = 0; j < 2; j++) f[gp + j] += Rp[j] * Fe[2 * p] + Rp[2 + j] * Fe[2 * p + 1];
        if (!K) continue;
        for (r = 0; r < 4; r++) {
            int gr = m->a.pg[4 * k + r];
            const double *Rr = m->a.pR + 16 * k + 4 * r;
            if (gr < 0) continue;
            for (j = 0; j < 2; j++)
                for (b = 0; b < 2; b++) {
                    double s = 0.0;
                    for (i = 0; i < 2; i++)
                        for (a = 0; a < 2; a++)
                            s += Rp[2 * i + j] * Ke[8 * (2 * p + i) + 2 * r + a] *
                                 Rr[2 * a + b];
                    K[(gp + j) * n + gr + b] += s;
                }
        }
    }
}

/* a spring k (unloaded length l0) between the pairs ga and gb of the absolute q (A.11) */
static void spring(const Dsa380Flex *m, int ga, int gb, double *f, double *K)
{
    const double *q = m->q;
    double dx = q[gb] - q[ga], dy = q[gb + 1] - q[ga + 1], ll = sqrt(dx * dx + dy * dy);
    double u[2], T = m->kl * (ll - m->l0);
    int i, j, n = m->n;
    u[0] = dx / ll;
    u[1] = dy / ll;
    f[gb] += T * u[0];
    f[gb + 1] += T * u[1];
    f[ga] -= T * u[0];
    f[ga + 1] -= T * u[1];
    if (!K) return;
    for (i = 0; i < 2; i++)
        for (j = 0; j < 2; j++) {
            double kij = m->kl * u[i] * u[j] + T / ll * ((i == j ? 1.0 : 0.0) - u[i] * u[j]);
            K[(gb + i) * n + gb + j] += kij;
            K[(ga + i) * n + ga + j] += kij;
            K[(gb + i) * n + ga + j] -= kij;
            K[(ga + i) * n + gb + j] -= kij;
        }
}

/* the torsional spring k_r and the actuation torque on the slope of bar 1 at joint 1 (2.14) */
static void torsion(const Dsa380Flex *m, double M_act, double *f, double *K)
{
    int g = m->s1, n = m->n;
    double a = m->q[g], b = m->q[g + 1], s = a * a + b * b, phi = pcs_atan2(b, a);
    double g0 = -b / s, g1 = a / s, mom = m->kr * (phi - m->th0) - M_act;
    double h00, h01;
    f[g] += mom * g0;
    f[g + 1] += mom * g1;
    if (!K) return;
    h00 = 2.0 * a * b / (s * s);
    h01 = (b * b - a * a) / (s * s);
    K[g * n + g] += m->kr * g0 * g0 + mom * h00;
    K[g * n + g + 1] += m->kr * g0 * g1 + mom * h01;
    K[(g + 1) * n + g] += m->kr * g1 * g0 + mom * h01;
    K[(g + 1) * n + g + 1] += m->kr * g1 * g1 - mom * h00;
}

/* the damper between 13 and 1p (A.13)-(A.19), one-way when asked (while point 5 rises it
   is off) */
static void damper(const Dsa380Flex *m, const double *v, double *f, double *K, double *C)
{
    int g = m->p1p, n = m->n, i, j;
    double cd = m->one_way && v[m->y5] > 0.0 ? 0.0 : m->c;
    double dx = m->q[g] - m->x13, dy = m->q[g + 1] - m->y13, ll = sqrt(dx * dx + dy * dy);
    double u[2], pv[2], ldot;
    u[0] = dx / ll;
    u[1] = dy / ll;
    ldot = u[0] * v[g] + u[1] * v[g + 1];
    f[g] += cd * ldot * u[0];
    f[g + 1] += cd * ldot * u[1];
    if (!K) return;
    pv[0] = v[g] - ldot * u[0];
    pv[1] = v[g + 1] - ldot * u[1];
    for (i = 0; i < 2; i++)
        for (j = 0; j < 2; j++) {
            C[(g + i) * n + g + j] += cd * u[i] * u[j];
            K[(g + i) * n + g + j] += cd / ll * (ldot * ((i == j ? 1.0 : 0.0) - u[i] * u[j]) +
                                                 u[i] * pv[j]);
        }
}

/* the collector friction (2.15)-(2.17) on the relative velocity y10dot - y5dot */
static void friction(const Dsa380Flex *m, const double *v, double *f, double *C)
{
    int a = m->y10, b = m->y5, n = m->n;
    double fr = m->friction_force, kt = m->friction_smoothing, vr, f_roz, df;
    if (!(fr > 0.0)) return;
    vr = v[a] - v[b];
    f_roz = fr * (2.0 / M_PI) * pcs_atan(vr / kt);
    df = fr * (2.0 / M_PI) / (kt + vr * vr / kt);
    f[a] += f_roz;
    f[b] -= f_roz;
    if (!C) return;
    C[a * n + a] += df;
    C[a * n + b] -= df;
    C[b * n + a] -= df;
    C[b * n + b] += df;
}

int dsf_evaluate(void *model, double t, const double *u, const double *v, const double *acc,
                 const double *inputs, int tangent, HhtEval *out, char *msg)
{
    Dsa380Flex *m = (Dsa380Flex *)model;
    int n = m->n, i, j, k;
    double F = inputs ? inputs[0] : 0.0, *f = out->f_rest;
    double *K = tangent ? out->stiffness : NULL, *C = tangent ? out->damping : NULL;
    if (!isfinite(F)) {
        snprintf(msg, HHT_MSG, "contact_force = %g: must be finite", F);
        return -1;
    }
    for (i = 0; i < n; i++) {
        m->q[i] = m->a.q_ref[i] + u[i];
        f[i] = -m->a.Qg[i];
    }
    if (tangent)
        for (i = 0; i < n * n; i++) K[i] = C[i] = out->inertia_q[i] = 0.0;
    gather(m, u);
    for (k = 0; k < m->ne; k++) element(m, k, m->Fe + 8 * k, m->Ke + 64 * k);
    for (k = 0; k < m->ne; k++) scatter(m, k, f, K);
    spring(m, m->p5, m->p11, f, K);
    spring(m, m->p5, m->p12, f, K);
    torsion(m, actuation_torque(&m->act, t), f, K);
    damper(m, v, f, K, C);
    friction(m, v, f, C);
    f[m->y10] += F - m->aero_force;
    for (i = 0; i < n; i++) {
        double s = 0.0;
        for (j = 0; j < n; j++) s += m->a.M[i * n + j] * acc[j];
        out->f_inertia[i] = s;
        if (!isfinite(f[i])) {
            snprintf(msg, HHT_MSG, "the flexible model cannot be evaluated here (degenerate "
                     "element or spring)");
            return -1;
        }
    }
    if (tangent) memcpy(out->mass, m->a.M, (size_t)n * n * sizeof(double));
    return 0;
}

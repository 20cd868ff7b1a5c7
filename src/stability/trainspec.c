/* Spectra of front trains by the monodromy of the shifted variational
 * equation (see trainspec.h and docs/numerics.md, "Spectra of front trains"). */
#include "bkfront/trainspec.h"

#include "bkfront/cycle.h"
#include "bkfront/hill.h"
#include "bkfront/options.h"

#include <gsl/gsl_math.h>

#include <complex.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "trainspec_internal.h"

/* ------------------------------------------------------------- meshes */

void trainspec_mesh_free(mesh *m)
{
    free(m->h);
    free(m->g0);
    free(m->m);
    free(m->ab0);
    free(m->aphi);
    free(m->a);
    free(m->b0);
    free(m->phi);
    memset(m, 0, sizeof *m);
}

/* The steps each cycle step needs (a real number: the meshes spread them
 * evenly, see mesh_bounds) for |sigma| up to reach.  Where the cycle step
 * is not stiff a step spans at most RESOLVE_TURN e-foldings or radians of
 * the fastest local solution, the roots of lambda^2 = a lambda + b; where
 * it is stiff, RESOLVE_TURN of the slow solution only.  Either way at most
 * PROFILE_TURN of the profile's change.
 *
 * Stiff cycle steps:  In p = exp(-sigma z / s) u (the perturbation of psi
 * itself) the system is p'' = ap p' + bp p with ap = -mu phi - 2 sigma / s,
 * bp = b0 - sigma (sigma + gamma phi): on a slow branch (phi > 0) one
 * solution decays at Re ap <= -mu (phi + 2 re_floor / gamma) and the other,
 * the one the spectrum is made of, varies at |bp / ap| only.  There the
 * L-stable Radau step, which damps the fast solution as the flow does,
 * needs to resolve the slow one alone: steps O(mu) times longer. */
int trainspec_mesh_needs(ctx *x, double reach, bkf_error *err)
{
    if (x->need && reach == x->sigma_reach) return BKF_OK;
    size_t n = x->node_count;
    double *f = malloc(n * sizeof *f), *fp = malloc(n * sizeof *fp), *slow = malloc(n * sizeof *slow);
    double *phi = malloc(n * sizeof *phi), *rate = malloc(n * sizeof *rate);
    double *need = realloc(x->need, n * sizeof *need);
    if (need) x->need = need;
    int rc = !f || !fp || !slow || !phi || !rate || !need ? bkf_error_set(err, BKF_ENOMEM, "out of memory")
                                                          : bkf_cycle_profile_sample(x->cycle, x->nodes, n, f, fp, err);
    for (size_t i = 0; rc == BKF_OK && i < n; i++) {
        phi[i] = f[i] * f[i] - 1.0;
        double a = x->mu * fabs(phi[i]), b_fixed = fabs(1.0 + 2.0 * x->mu * f[i] * fp[i]);
        double b = b_fixed + x->beta * reach * (reach + x->gamma * fabs(phi[i]));
        rate[i] = 0.5 * a + sqrt(0.25 * a * a + b);
        slow[i] = b_fixed + reach * (reach + x->gamma * fabs(phi[i])); /* bounds |bp| */
    }
    for (size_t i = 0; rc == BKF_OK && i + 1 < n; i++) {
        double len = x->nodes[i + 1] - x->nodes[i];
        double plain = len * fmax(rate[i], rate[i + 1]) / RESOLVE_TURN;
        double decay = x->mu * (fmin(phi[i], phi[i + 1]) + 2.0 * x->re_floor / x->gamma);
        double stiff = decay > 0.0 ? len * fmax(slow[i], slow[i + 1]) / decay / RESOLVE_TURN : INFINITY;
        /* stiff steps, of length len / stiff, must damp the fast solution */
        int use_stiff = stiff < plain && decay * len >= STIFF_MIN * fmax(stiff, 1.0);
        need[i] = fmax(fmax(use_stiff ? stiff : plain, fabs(f[i + 1] - f[i]) / PROFILE_TURN), NODE_SHARE);
    }
    x->sigma_reach = reach;
    free(f);
    free(fp);
    free(slow);
    free(phi);
    free(rate);
    return rc;
}

/* The Radau IIA (three stages, order 5, L-stable) tableau. */
#define SQ6 2.449489742783178098197284
static const double RADAU_C[3] = {(4.0 - SQ6) / 10.0, (4.0 + SQ6) / 10.0, 1.0};
#define RA11 ((88.0 - 7.0 * SQ6) / 360.0)
#define RA12 ((296.0 - 169.0 * SQ6) / 1800.0)
#define RA13 ((-2.0 + 3.0 * SQ6) / 225.0)
#define RA21 ((296.0 + 169.0 * SQ6) / 1800.0)
#define RA22 ((88.0 + 7.0 * SQ6) / 360.0)
#define RA23 ((-2.0 - 3.0 * SQ6) / 225.0)
#define RA31 ((16.0 - SQ6) / 36.0)
#define RA32 ((16.0 + SQ6) / 36.0)
#define RA33 (1.0 / 9.0)
static const double RADAU_A[3][3] = {{RA11, RA12, RA13}, {RA21, RA22, RA23}, {RA31, RA32, RA33}};
#define RA2(q1, q2, q3, j1, j2, j3) (q1 * j1 + q2 * j2 + q3 * j3)
/* A^2 */
static const double RADAU_A2[3][3] = {
    {RA2(RA11, RA12, RA13, RA11, RA21, RA31), RA2(RA11, RA12, RA13, RA12, RA22, RA32), RA2(RA11, RA12, RA13, RA13, RA23, RA33)},
    {RA2(RA21, RA22, RA23, RA11, RA21, RA31), RA2(RA21, RA22, RA23, RA12, RA22, RA32), RA2(RA21, RA22, RA23, RA13, RA23, RA33)},
    {RA2(RA31, RA32, RA33, RA11, RA21, RA31), RA2(RA31, RA32, RA33, RA12, RA22, RA32), RA2(RA31, RA32, RA33, RA13, RA23, RA33)}};

/* A mesh on the step boundaries bounds[0..steps] (ascending in [0, T]):
 * the coefficients at each step's Radau points. */
int trainspec_mesh_fill(ctx *x, const double *bounds, size_t steps, mesh *m, bkf_error *err)
{
    trainspec_mesh_free(m);
    m->steps = steps;
    size_t cap = steps ? steps : 1;
    m->h = malloc(cap * sizeof *m->h);
    m->a = malloc(STRIDE * cap * sizeof *m->a);
    m->b0 = malloc(STRIDE * cap * sizeof *m->b0);
    m->phi = malloc(STRIDE * cap * sizeof *m->phi);
    m->g0 = malloc(9 * cap * sizeof *m->g0);
    m->m = malloc(9 * cap * sizeof *m->m);
    m->ab0 = malloc(3 * cap * sizeof *m->ab0);
    m->aphi = malloc(3 * cap * sizeof *m->aphi);
    double *z = malloc(STRIDE * cap * sizeof *z), *f = malloc(STRIDE * cap * sizeof *f);
    double *fp = malloc(STRIDE * cap * sizeof *fp);
    int rc = BKF_OK;
    if (!m->h || !m->a || !m->b0 || !m->phi || !m->g0 || !m->m || !m->ab0 || !m->aphi || !z || !f || !fp) {
        rc = bkf_error_set(err, BKF_ENOMEM, "out of memory");
        goto done;
    }
    for (size_t k = 0; k < steps; k++) {
        double h = bounds[k + 1] - bounds[k];
        m->h[k] = h;
        for (int q = 0; q < 3; q++) z[STRIDE * k + q] = fmin(bounds[k] + RADAU_C[q] * h, x->T);
    }
    rc = bkf_cycle_profile_sample(x->cycle, z, STRIDE * steps, f, fp, err);
    if (rc != BKF_OK) goto done;
    m->trace_sum = 0.0;
    for (size_t i = 0; i < STRIDE * steps; i++) {
        m->phi[i] = f[i] * f[i] - 1.0;
        m->a[i] = -x->mu * m->phi[i];
        m->b0[i] = -(1.0 + 2.0 * x->mu * f[i] * fp[i]);
    }
    for (size_t i = 0; i < steps; i++) {
        const double *a = m->a + STRIDE * i, *b0 = m->b0 + STRIDE * i, *phi = m->phi + STRIDE * i;
        double h = m->h[i];
        /* Radau quadrature (order 5) of the trace -mu phi */
        m->trace_sum += h * (RADAU_A[2][0] * a[0] + RADAU_A[2][1] * a[1] + RADAU_A[2][2] * a[2]);
        for (int q = 0; q < 3; q++) {
            m->ab0[3 * i + q] = m->aphi[3 * i + q] = 0.0;
            for (int j = 0; j < 3; j++) {
                m->ab0[3 * i + q] += RADAU_A[q][j] * b0[j];
                m->aphi[3 * i + q] += RADAU_A[q][j] * phi[j];
                double ab = 0.0, ap = 0.0;
                for (int l = 0; l < 3; l++) {
                    ab += RADAU_A[q][l] * b0[l] * RADAU_A[l][j];
                    ap += RADAU_A[q][l] * phi[l] * RADAU_A[l][j];
                }
                m->g0[9 * i + 3 * q + j] = (q == j) - h * RADAU_A[q][j] * a[j] - h * h * ab;
                m->m[9 * i + 3 * q + j] = ap;
            }
        }
    }
done:
    free(z);
    free(f);
    free(fp);
    if (rc != BKF_OK) trainspec_mesh_free(m);
    return rc;
}

/* The step boundaries of a mesh of `substeps` times the steps the cycle
 * steps need (mesh_needs), spread evenly in the cumulative need, so that
 * doubling substeps halves every step: *bounds (steps + 1 values). */
int trainspec_mesh_bounds(ctx *x, size_t substeps, double **bounds, size_t *steps, bkf_error *err)
{
    double total = 0.0;
    for (size_t i = 0; i + 1 < x->node_count; i++) total += x->need[i];
    double count = fmax(ceil(total), MESH_MIN_STEPS) * (double)substeps;
    if (count > MESH_MAX_STEPS)
        return bkf_error_set(err, BKF_EBUDGET, "the spectrum needs more than %d steps per period (mu = %.15g)",
                             MESH_MAX_STEPS, x->mu);
    size_t k_max = (size_t)count;
    double *b = malloc((k_max + 1) * sizeof *b);
    if (!b) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    /* boundary k sits where the cumulative need reaches k total / k_max,
     * linear within each cycle step */
    double below = 0.0, per_step = total / count;
    size_t i = 0;
    b[0] = 0.0;
    for (size_t k = 1; k < k_max; k++) {
        double target = (double)k * per_step;
        while (i + 2 < x->node_count && below + x->need[i] < target) below += x->need[i++];
        double frac = x->need[i] > 0.0 ? fmin(1.0, (target - below) / x->need[i]) : 1.0;
        b[k] = x->nodes[i] + frac * (x->nodes[i + 1] - x->nodes[i]);
    }
    b[k_max] = x->T;
    *bounds = b;
    *steps = k_max;
    return BKF_OK;
}

int trainspec_mesh_build(ctx *x, size_t substeps, mesh *m, bkf_error *err)
{
    double *bounds = NULL;
    size_t steps = 0;
    int rc = trainspec_mesh_bounds(x, substeps, &bounds, &steps, err);
    if (rc == BKF_OK) rc = trainspec_mesh_fill(x, bounds, steps, m, err);
    free(bounds);
    return rc;
}

/* ---------------------------------------------------------- monodromy */

/* The Radau IIA step i at sigma in p = exp(-sigma z / s) u, where the
 * solution that survives varies slowly (see mesh_needs): (p, p') after the
 * step = e (p, p') before it, e[0..3] row-major, and de = de/dsigma when de
 * is not NULL.  With V the stages of p', the stages of p are p0 + h A V, so
 * the six stage equations reduce to three:
 *     G V = (I - h A diag(ap) - h^2 A diag(bp) A) V = p0' + h p0 A bp.
 * The monodromy is taken in p's basis: u's is exp(k T) K P K^-1 with
 * K = [[1, 0], [k, 1]], k = sigma / s, the same multipliers times exp(k T),
 * which the eigenvalue condition divides out again (monodromy), so neither
 * K nor exp(k h) (a complex exponential per step) is ever formed. */
void trainspec_radau_step(const ctx *x, const mesh *m, size_t i, double complex sigma, double complex e[4],
                       double complex de[4])
{
    double h = m->h[i];
    double complex k = sigma / x->s, G[3][3], r[3][4];
    /* ap = a - 2 k, bp = b0 - sigma^2 - gamma sigma phi: G = G0 + 2 k h A
     * + h^2 sigma^2 A^2 + h^2 gamma sigma M (mesh_fill made G0 and M) */
    double complex c1 = 2.0 * k * h, c2 = h * h * sigma * sigma, c3 = h * h * x->gamma * sigma;
    double complex s2 = sigma * sigma, gs = x->gamma * sigma;
    const double *g0 = m->g0 + 9 * i, *mm = m->m + 9 * i;
    int nrhs = de ? 4 : 2;
    for (int q = 0; q < 3; q++) {
        for (int j = 0; j < 3; j++)
            G[q][j] = g0[3 * q + j] + c1 * RADAU_A[q][j] + c2 * RADAU_A2[q][j] + c3 * mm[3 * q + j];
        /* right-hand sides for (p0, p0') = (1, 0) and (0, 1); A 1 = c */
        r[q][0] = h * (m->ab0[3 * i + q] - s2 * RADAU_C[q] - gs * m->aphi[3 * i + q]);
        r[q][1] = 1.0;
    }
    /* LU with partial pivoting, kept for the derivative's solve */
    int perm[3] = {0, 1, 2};
    double complex inv[3];
    for (int c = 0; c < 3; c++) {
        int piv = c;
        for (int q = c + 1; q < 3; q++)
            if (fabs(creal(G[q][c])) + fabs(cimag(G[q][c])) > fabs(creal(G[piv][c])) + fabs(cimag(G[piv][c])))
                piv = q;
        if (piv != c) {
            for (int j = 0; j < 3; j++) {
                double complex t = G[c][j];
                G[c][j] = G[piv][j], G[piv][j] = t;
            }
            for (int j = 0; j < 2; j++) {
                double complex t = r[c][j];
                r[c][j] = r[piv][j], r[piv][j] = t;
            }
            int t = perm[c];
            perm[c] = perm[piv], perm[piv] = t;
        }
        inv[c] = 1.0 / G[c][c];
        for (int q = c + 1; q < 3; q++) {
            double complex l = G[q][c] * inv[c];
            G[q][c] = l;
            for (int j = c + 1; j < 3; j++) G[q][j] -= l * G[c][j];
            r[q][0] -= l * r[c][0], r[q][1] -= l * r[c][1];
        }
    }
    double complex V[3][4];
    for (int q = 2; q >= 0; q--)
        for (int rhs = 0; rhs < 2; rhs++) {
            double complex sum = r[q][rhs];
            for (int j = q + 1; j < 3; j++) sum -= G[q][j] * V[j][rhs];
            V[q][rhs] = sum * inv[q];
        }
    if (de) {
        /* G dV = dr - dG V: dG = 2 h / s A + 2 h^2 sigma A^2 + h^2 gamma M,
         * dr0 = -h (2 sigma c + gamma A phi), dr1 = 0 */
        double complex d2 = 2.0 * h * h * sigma;
        double d1 = 2.0 * h / x->s, d3 = h * h * x->gamma;
        double complex b[3][2];
        for (int q = 0; q < 3; q++) {
            double complex dr0 = -h * (2.0 * sigma * RADAU_C[q] + x->gamma * m->aphi[3 * i + q]);
            for (int rhs = 0; rhs < 2; rhs++) {
                double complex sum = rhs == 0 ? dr0 : 0.0;
                for (int j = 0; j < 3; j++)
                    sum -= (d1 * RADAU_A[q][j] + d2 * RADAU_A2[q][j] + d3 * mm[3 * q + j]) * V[j][rhs];
                b[q][rhs] = sum;
            }
        }
        for (int q = 0; q < 3; q++) {
            r[q][2] = b[perm[q]][0];
            r[q][3] = b[perm[q]][1];
        }
        for (int c = 0; c < 3; c++)
            for (int q = c + 1; q < 3; q++) r[q][2] -= G[q][c] * r[c][2], r[q][3] -= G[q][c] * r[c][3];
        for (int q = 2; q >= 0; q--)
            for (int rhs = 2; rhs < 4; rhs++) {
                double complex sum = r[q][rhs];
                for (int j = q + 1; j < 3; j++) sum -= G[q][j] * V[j][rhs];
                V[q][rhs] = sum * inv[q];
            }
    }
    /* p1 = p0 + h sum A_3j V_j, p1' = V_3 */
    for (int rhs = 0; rhs < nrhs; rhs++) {
        double complex sum = 0;
        for (int j = 0; j < 3; j++) sum += RADAU_A[2][j] * V[j][rhs];
        double complex *out = rhs < 2 ? e : de;
        int col = rhs & 1;
        out[col] = (rhs == 0) + h * sum;
        out[2 + col] = V[2][rhs];
    }
}

/* Keeps the entries of v (count of them) near 1 in modulus, the factor
 * moved into *scale (a log). */
void trainspec_rescale(double complex *v, size_t count, double *scale)
{
    /* the largest component: a norm within sqrt 2 of the modulus, and no hypot */
    double big = 0.0;
    for (size_t i = 0; i < count; i++) {
        double re = fabs(creal(v[i])), im = fabs(cimag(v[i]));
        big = re > big ? re : big;
        big = im > big ? im : big;
    }
    if (!(big > 0x1p200 || big < 0x1p-200) || big == 0.0) return;
    int e2;
    frexp(big, &e2);
    for (size_t i = 0; i < count; i++) v[i] = ldexp(creal(v[i]), -e2) + I * ldexp(cimag(v[i]), -e2);
    *scale += e2 * M_LN2;
}

/* 2x2 products, row-major: out = a b */
static void mul2(const double complex a[4], const double complex b[4], double complex out[4])
{
    double complex o0 = a[0] * b[0] + a[1] * b[2], o1 = a[0] * b[1] + a[1] * b[3];
    double complex o2 = a[2] * b[0] + a[3] * b[2], o3 = a[2] * b[1] + a[3] * b[3];
    out[0] = o0, out[1] = o1, out[2] = o2, out[3] = o3;
}

/* The monodromy of p over mesh m at sigma: p[0..3] (row-major) times
 * exp(*scale), and its derivative in sigma into dp (same scale) when dp is
 * not NULL (a pass with the derivative costs about two without: it counts
 * twice in the work). */
void trainspec_monodromy_matrix(ctx *x, const mesh *m, double complex sigma, double complex p[4], double complex *dp,
                             double *scale)
{
    double cost = (dp ? 2.0 : 1.0) * (double)m->steps;
    x->evaluations++;
    p[0] = 1, p[1] = 0, p[2] = 0, p[3] = 1;
    if (dp) dp[0] = dp[1] = dp[2] = dp[3] = 0;
    *scale = 0.0;
    if (!x->stop && x->cancel && *x->cancel) x->stop = BKF_ECANCELED;
    if (!x->stop && x->work + cost > x->max_work) x->stop = BKF_EBUDGET;
    if (x->stop) {
        /* every caller's search then fails at once; the entry point reports why */
        *scale = NAN;
        return;
    }
    x->work += cost;
    for (size_t i = 0; i < m->steps; i++) {
        double complex e[4], de[4];
        trainspec_radau_step(x, m, i, sigma, e, dp ? de : NULL);
        if (dp) {
            double complex t1[4], t2[4];
            mul2(de, p, t1);
            mul2(e, dp, t2);
            for (int q = 0; q < 4; q++) dp[q] = t1[q] + t2[q];
        }
        mul2(e, p, p);
        /* a step's factor is O(1) in p's basis (the growth exp(k h) is
         * u's): every eighth step is often enough to stay far from overflow */
        if ((i & 7) == 7 || i + 1 == m->steps) {
            if (dp) {
                double complex both[8] = {p[0], p[1], p[2], p[3], dp[0], dp[1], dp[2], dp[3]};
                trainspec_rescale(both, 8, scale);
                for (int q = 0; q < 4; q++) p[q] = both[q], dp[q] = both[4 + q];
            } else {
                trainspec_rescale(p, 4, scale);
            }
        }
    }
}

/* ln of the two multipliers of psi's perturbation over one period at sigma,
 * divided by exp(sigma T / s): w[0] the larger in modulus, w[1] the
 * smaller, and their derivatives in sigma into dw (NULL: not wanted).  The
 * product is kept scaled (its log in `scale`) so that neither stiff decay
 * nor growth over- or underflows; the smaller multiplier comes from
 * det M = exp(trace_sum), free of cancellation.  In p's basis (radau_step)
 * the larger is exp(sigma T / s) times P's larger eigenvalue, so w[0] is
 * ln of that eigenvalue itself, and w[1] = trace_sum - w[0] - 2 sigma T / s. */
static void monodromy(ctx *x, const mesh *m, double complex sigma, double complex w[2], double complex *dw)
{
    double complex p[4], dp[4];
    double scale;
    trainspec_monodromy_matrix(x, m, sigma, p, dw ? dp : NULL, &scale);
    double complex half = 0.5 * (p[0] + p[3]), det = p[0] * p[3] - p[1] * p[2];
    double complex root = csqrt(half * half - det);
    double complex big = cabs(half + root) >= cabs(half - root) ? half + root : half - root;
    double complex shift = sigma * x->T / x->s;
    w[0] = scale + clog(big);
    w[1] = m->trace_sum - w[0] - 2.0 * shift;
    if (!dw) return;
    /* big^2 - tr big + det = 0: d big (2 big - tr) = d tr big - d det */
    double complex dtr = dp[0] + dp[3], ddet = dp[0] * p[3] + p[0] * dp[3] - dp[1] * p[2] - p[1] * dp[2];
    dw[0] = (dtr * big - ddet) / ((2.0 * big - (p[0] + p[3])) * big);
    dw[1] = -dw[0] - 2.0 * x->T / x->s;
}

double trainspec_wrap(double phase)
{
    return phase - 2.0 * M_PI * floor(phase / (2.0 * M_PI) + 0.5);
}

/* ------------------------------------------------------ curve tracing */

typedef struct {
    double y;
    int found;         /* the family's multiplier reaches modulus 1 right of a_lo */
    double a;          /* Re sigma there */
    double slope;      /* da/dy along the curve */
    double phase;      /* arg of the multiplier (principal), then unwrapped */
    double rate;       /* d phase / dy along the curve */
} curve_point;

/* Newton on Re w[f](a + i y) = 0 in a from the prediction g (the last
 * height's point continued along its slope): one pass with the derivative
 * per step, where the bracketing below takes about six passes per height.
 * The point is taken once a step is at most sqrt(tol_a) (quadratic
 * convergence: the error after it is of order tol_a), its phase, slope and
 * rate from the derivative at the step's start (first order in the step).
 * 0 when Newton does not settle inside the window, or Re w does not fall
 * with a there: the bracketing decides. */
static int height_newton(ctx *x, const mesh *m, const window *win, double y, double g, int f, double tol_a,
                         curve_point *p)
{
    double a = g;
    for (int it = 0; it < TRACE_NEWTON_MAX; it++) {
        double complex w[2], dw[2];
        monodromy(x, m, a + I * y, w, dw);
        double re = creal(dw[f]), im = cimag(dw[f]);
        if (!(re < 0.0) || !isfinite(creal(w[f])) || !isfinite(cimag(w[f]))) return 0;
        double step = -creal(w[f]) / re, next = a + step;
        if (!(next > win->a_lo && next < win->a_hi)) return 0;
        if (fabs(step) <= sqrt(tol_a)) {
            *p = (curve_point){.y = y, .found = 1, .a = next, .phase = cimag(w[f]) + im * step,
                               .slope = im / re, .rate = (re * re + im * im) / re};
            return 1;
        }
        a = next;
    }
    return 0;
}

/* Both families' rightmost a in [a_lo, a_hi] where Re w(a + i y) = 0: by
 * Newton from the predictions guess[f] where given (NAN otherwise) and it
 * settles, else by the Illinois variant of regula falsi, the bracket
 * shrunk around the prediction first.  Re w decreases in a: the
 * multipliers shrink to the right. */
static int height_at(ctx *x, const mesh *m, window *win, double y, const double guess[FAMILIES],
                     curve_point pt[FAMILIES])
{
    /* the curves only propose candidates (polished on the meshes, their
     * value and error the polish's) and tell where they leave the window:
     * a to 1e-6 is plenty for both, and 1e-3 tol cost two or three more
     * monodromies per family and height */
    double tol_a = fmax(1e-3 * x->tol, TRACE_TOL);
    int settled[FAMILIES], all = 1;
    for (int f = 0; f < FAMILIES; f++) {
        settled[f] = isfinite(guess[f]) && guess[f] > win->a_lo && guess[f] < win->a_hi &&
                     height_newton(x, m, win, y, guess[f], f, tol_a, &pt[f]);
        all &= settled[f];
    }
    if (all) return BKF_OK;
    double complex w[2], wh[2] = {0};
    monodromy(x, m, win->a_lo + I * y, w, NULL);
    int inside = 0;
    for (int f = 0; f < FAMILIES; f++) inside |= !settled[f] && creal(w[f]) >= 0.0;
    /* the bracket's right end, only where a family still needs one */
    for (int grow = 0; inside; grow++) {
        monodromy(x, m, win->a_hi + I * y, wh, NULL);
        if (creal(wh[0]) < 0.0) break;
        if (grow > 40) return BKF_ENUMERIC;
        win->a_hi *= 2.0;
    }
    for (int f = 0; f < FAMILIES; f++) {
        if (settled[f]) continue;
        curve_point *p = &pt[f];
        p->y = y;
        p->found = 0;
        if (creal(w[f]) < 0.0) continue;
        double lo = win->a_lo, hi = win->a_hi, flo = creal(w[f]), fhi = creal(wh[f]);
        /* shrink the bracket around the prediction */
        if (isfinite(guess[f]) && guess[f] > lo && guess[f] < hi) {
            double g = guess[f], d = fmax(1e-3, 100.0 * tol_a);
            for (int k = 0; k < 2; k++, d *= 8.0) {
                double complex wg[2];
                double t = fmin(fmax(g, lo + 0.5 * tol_a), hi - 0.5 * tol_a);
                monodromy(x, m, t + I * y, wg, NULL);
                double ft = creal(wg[f]);
                if (ft >= 0.0) {
                    lo = t, flo = ft;
                    g = t + d;
                } else {
                    hi = t, fhi = ft;
                    g = t - d;
                }
                if (!(g > lo && g < hi)) break;
            }
        }
        int side = 0;
        for (int it = 0; it < 200 && hi - lo > tol_a; it++) {
            double t = (lo * fhi - hi * flo) / (fhi - flo);
            if (!(t > lo && t < hi)) t = 0.5 * (lo + hi);
            double complex wt[2];
            monodromy(x, m, t + I * y, wt, NULL);
            double ft = creal(wt[f]);
            if (fabs(ft) < 1e-3 * tol_a) {
                lo = hi = t;
                break;
            }
            if (ft >= 0.0) {
                lo = t, flo = ft;
                if (side == -1) fhi *= 0.5;
                side = -1;
            } else {
                hi = t, fhi = ft;
                if (side == 1) flo *= 0.5;
                side = 1;
            }
        }
        double a = 0.5 * (lo + hi);
        double complex wv[2], dw[2];
        monodromy(x, m, a + I * y, wv, dw);
        p->found = 1;
        p->a = a;
        p->phase = cimag(wv[f]);
        /* along Re w = 0: da/dy = Im w' / Re w', dphase/dy = |w'|^2 / Re w' */
        double re = creal(dw[f]), im = cimag(dw[f]);
        if (re == 0.0) return BKF_ENUMERIC;
        p->slope = im / re;
        p->rate = (re * re + im * im) / re;
    }
    return BKF_OK;
}

/* One sampled height: both families. */
typedef struct {
    curve_point fam[FAMILIES];
} height;

typedef struct {
    height *h;
    size_t count, cap;
} curve;

static int curve_insert(curve *c, size_t at, const height *p)
{
    if (c->count == c->cap) {
        size_t cap = c->cap ? 2 * c->cap : 256;
        height *g = realloc(c->h, cap * sizeof *g);
        if (!g) return BKF_ENOMEM;
        c->h = g;
        c->cap = cap;
    }
    memmove(&c->h[at + 1], &c->h[at], (c->count - at) * sizeof *c->h);
    c->h[at] = *p;
    c->count++;
    return BKF_OK;
}

/* Does the interval between two samples need a sample in between: an edge
 * of the curve, a phase step the rates do not account for, or a bend the
 * linear interpolation of a misses. */
static int needs_split(const ctx *x, const curve_point *p, const curve_point *q, double min_dy)
{
    double dy = q->y - p->y;
    if (dy <= min_dy) return 0;
    if (p->found != q->found) return dy > min_dy * (EDGE_FRACTION / CURVE_MIN_FRACTION);
    if (!p->found) return 0;
    double est = 0.5 * (p->rate + q->rate) * dy;
    double darg = trainspec_wrap(q->phase - p->phase);
    double turns = nearbyint((est - darg) / (2.0 * M_PI));
    if (fabs(est - (darg + 2.0 * M_PI * turns)) > 0.3) return 1;
    if (fabs(q->slope - p->slope) * dy > fmax(0.05 * fabs(p->a) + 1e-3, 100.0 * x->tol)) return 1;
    return 0;
}

static void predict(const height *p, const height *q, double y, double guess[FAMILIES])
{
    for (int f = 0; f < FAMILIES; f++) {
        guess[f] = NAN;
        const curve_point *near = p && p->fam[f].found ? &p->fam[f] : q && q->fam[f].found ? &q->fam[f] : NULL;
        if (near) guess[f] = near->a + near->slope * (y - near->y);
    }
}

/* Trace both families over [y0, y1] into c (appending, y increasing),
 * refining where needs_split says so. */
static int trace(ctx *x, window *win, double y0, double y1, double y_scale, curve *c)
{
    double min_dy = y_scale * CURVE_MIN_FRACTION;
    size_t start = c->count;
    for (int i = 0; i <= CURVE_START; i++) {
        if (i == 0 && start > 0) continue; /* y0 is the previous pass's last point */
        double y = y0 + (y1 - y0) * i / CURVE_START, guess[FAMILIES];
        predict(c->count ? &c->h[c->count - 1] : NULL, NULL, y, guess);
        height h;
        int rc = height_at(x, &x->coarse, win, y, guess, h.fam);
        if (rc != BKF_OK) return rc;
        if (curve_insert(c, c->count, &h) != BKF_OK) return BKF_ENOMEM;
    }
    for (size_t i = start ? start - 1 : 0; i + 1 < c->count;) {
        int split = 0;
        for (int f = 0; f < FAMILIES; f++)
            split |= needs_split(x, &c->h[i].fam[f], &c->h[i + 1].fam[f], min_dy);
        if (!split) {
            i++;
            continue;
        }
        double y = 0.5 * (c->h[i].fam[0].y + c->h[i + 1].fam[0].y), guess[FAMILIES];
        predict(&c->h[i], &c->h[i + 1], y, guess);
        height mid;
        int rc = height_at(x, &x->coarse, win, y, guess, mid.fam);
        if (rc != BKF_OK) return rc;
        if (curve_insert(c, i + 1, &mid) != BKF_OK) return BKF_ENOMEM;
    }
    return BKF_OK;
}

/* ------------------------------------------------------------ candidates */

/* Every point of the traced curve where the multiplier's phase is a multiple
 * of 2 pi / classes, with its mirror image below the real axis. */
static int collect(curve *c, int fam, size_t classes, candidates *out)
{
    if (c->count == 0) return BKF_OK;
    double step = 2.0 * M_PI / (double)classes;
    /* unwrap the phase with the rates */
    double psi = 0.0;
    for (size_t i = 0; i < c->count; i++) {
        curve_point *p = &c->h[i].fam[fam];
        if (!p->found) continue;
        if (i > 0 && c->h[i - 1].fam[fam].found) {
            const curve_point *q = &c->h[i - 1].fam[fam];
            double est = 0.5 * (p->rate + q->rate) * (p->y - q->y);
            double darg = trainspec_wrap(p->phase - q->phase);
            psi += darg + 2.0 * M_PI * nearbyint((est - darg) / (2.0 * M_PI));
        } else {
            psi = p->phase;
            /* a point alone on the real axis is a candidate itself */
            double l = psi / step;
            if (p->y == 0.0 && fabs(l - nearbyint(l)) < 1e-6) {
                long cls = ((long)nearbyint(l) % (long)classes + (long)classes) % (long)classes;
                if (trainspec_cand_push(out, (candidate){p->a, 0.0, (size_t)cls, fam, 0}) != BKF_OK) return BKF_ENOMEM;
            }
        }
        p->phase = psi; /* unwrapped from here on */
        if (i == 0 || !c->h[i - 1].fam[fam].found) continue;
        const curve_point *q = &c->h[i - 1].fam[fam];
        double lo = fmin(q->phase, p->phase), hi = fmax(q->phase, p->phase);
        for (double l = floor(lo / step) + 1.0; l * step <= hi; l += 1.0) {
            if (l * step == lo) continue;
            double t = (l * step - q->phase) / (p->phase - q->phase);
            double dy = p->y - q->y;
            /* Hermite interpolation of a with the slopes */
            double h00 = 2 * t * t * t - 3 * t * t + 1, h10 = t * t * t - 2 * t * t + t;
            double h01 = -2 * t * t * t + 3 * t * t, h11 = t * t * t - t * t;
            double a = h00 * q->a + h10 * dy * q->slope + h01 * p->a + h11 * dy * p->slope;
            double y = q->y + t * dy;
            long cls = ((long)l % (long)classes + (long)classes) % (long)classes;
            if (trainspec_cand_push(out, (candidate){a, y, (size_t)cls, fam, 0}) != BKF_OK) return BKF_ENOMEM;
            if (y > 0.0) {
                size_t mirror = (size_t)((classes - (size_t)cls) % classes);
                if (trainspec_cand_push(out, (candidate){a, -y, mirror, fam, 1}) != BKF_OK) return BKF_ENOMEM;
            }
        }
    }
    return BKF_OK;
}

/* ------------------------------------------------------------- polishing */

/* Newton on w(sigma) = i theta (mod 2 pi i), over whichever family fits
 * best, on mesh m.  With deriv (NULL: not wanted) holding both families'
 * derivatives from a polish of the same eigenvalue on a coarser mesh, the
 * steps take those instead of a pass with the derivative (which costs two
 * without it): the derivatives of two meshes differ by the meshes' error,
 * so the iteration contracts by about that much per step and stops on the
 * same small step as Newton's; where it does not settle within CHORD_MAX
 * steps, Newton takes over.  The derivatives last computed go back into
 * deriv. */
#define CHORD_MAX 4
int trainspec_polish(ctx *x, const mesh *m, double theta, double complex *sigma, double *last_step,
                     double complex deriv[2])
{
    double complex s = *sigma;
    *last_step = INFINITY;
    int chord = deriv && deriv[0] != 0 && deriv[1] != 0 && isfinite(creal(deriv[0])) &&
                isfinite(cimag(deriv[0])) && isfinite(creal(deriv[1])) && isfinite(cimag(deriv[1]));
    for (int it = 0, chords = 0; it < NEWTON_MAX; it++) {
        double complex w0[2], dw[2];
        int use_chord = chord && chords < CHORD_MAX;
        if (use_chord) {
            monodromy(x, m, s, w0, NULL);
            dw[0] = deriv[0], dw[1] = deriv[1];
            chords++;
        } else {
            monodromy(x, m, s, w0, dw);
            if (deriv) deriv[0] = dw[0], deriv[1] = dw[1];
        }
        int fam = 0;
        double complex r[2];
        for (int f = 0; f < FAMILIES; f++) r[f] = creal(w0[f]) + I * trainspec_wrap(cimag(w0[f]) - theta);
        if (cabs(r[1]) < cabs(r[0])) fam = 1;
        if (dw[fam] == 0 || !isfinite(creal(dw[fam])) || !isfinite(cimag(dw[fam]))) return BKF_ENUMERIC;
        double complex step = r[fam] / dw[fam];
        if (cabs(step) > 0.5) step *= 0.5 / cabs(step);
        s -= step;
        *last_step = cabs(step);
        if (!isfinite(creal(s)) || !isfinite(cimag(s))) return BKF_ENUMERIC;
        if (*last_step < 1e-4 * x->tol) break;
    }
    *sigma = s;
    return *last_step < 1e-2 * x->tol ? BKF_OK : BKF_ENUMERIC;
}

static int by_a_desc(const void *pa, const void *pb)
{
    const candidate *a = pa, *b = pb;
    if (a->cls != b->cls) return a->cls < b->cls ? -1 : 1;
    return (a->a < b->a) - (a->a > b->a);
}

static int eig_desc(const void *pa, const void *pb)
{
    const bkf_trainspec_eigenvalue *a = pa, *b = pb;
    if (a->j != b->j) return a->j < b->j ? -1 : 1;
    return (a->re < b->re) - (a->re > b->re);
}

/* ------------------------------------------------------------------ api */

bkf_trainspec_options bkf_trainspec_options_default(void)
{
    return (bkf_trainspec_options){.tol = 1e-6, .per_kappa = 3, .max_work = 0, .cancel = NULL};
}

const char *bkf_trainspec_verdict_name(bkf_trainspec_verdict v)
{
    switch (v) {
    case BKF_TRAINSPEC_STABLE: return "yes";
    case BKF_TRAINSPEC_UNSTABLE: return "no";
    default: return "unresolved";
    }
}

int bkf_trainspec_check(const bkf_model_params *p, const bkf_trainspec_train *t,
                        const bkf_trainspec_options *o, bkf_error *err)
{
    if (!p || !t) return bkf_error_set(err, BKF_EINPUT, "parameters and train are required");
    int rc;
    if ((rc = bkf_model_check_positive("gamma", p->gamma, err)) != BKF_OK) return rc;
    if ((rc = bkf_model_check_positive("S", p->S, err)) != BKF_OK) return rc;
    if ((rc = bkf_model_check_nu_active(p->nu, err)) != BKF_OK) return rc;
    if (!(p->c > 0.0) || !isfinite(p->c))
        return bkf_error_set(err, BKF_EINPUT,
                             "c must be finite and > 0 for a spectrum (with c = 0 the fronts are phase waves "
                             "of uncoupled oscillators: every mode is neutral)");
    if (t->n < 1) return bkf_error_set(err, BKF_EINPUT, "n must be >= 1");
    if (!(t->v > p->c) || !isfinite(t->v))
        return bkf_error_set(err, BKF_EINPUT, "v must be finite and > c = %.15g (fronts are supersonic)", p->c);
    if (o) {
        if (!(o->tol >= TOL_MIN && o->tol <= TOL_MAX))
            return bkf_error_set(err, BKF_EINPUT, "tol must be in [%g, %g]", TOL_MIN, TOL_MAX);
        if (o->per_kappa < 1 || o->per_kappa > PER_KAPPA_MAX)
            return bkf_error_set(err, BKF_EINPUT, "per_kappa must be in [1, %d]", PER_KAPPA_MAX);
        if (o->max_work != 0 && !(o->max_work >= 1e5 && o->max_work <= 1e12))
            return bkf_error_set(err, BKF_EINPUT, "max_work must be 0 (default) or in [1e5, 1e12]");
    }
    return BKF_OK;
}

void trainspec_ctx_free(ctx *x)
{
    trainspec_mesh_free(&x->coarse);
    trainspec_mesh_free(&x->fine);
    bkf_cycle_free(x->cycle);
    free(x->nodes);
    free(x->need);
}

int trainspec_ctx_init(ctx *x, const bkf_model_params *p, const bkf_trainspec_train *t, double tol,
                    const bkf_trainspec_options *o, bkf_error *err)
{
    memset(x, 0, sizeof *x);
    x->max_work = o && o->max_work > 0 ? o->max_work : MAX_WORK_DEFAULT;
    x->cancel = o ? o->cancel : NULL;
    x->gamma = p->gamma;
    x->c = p->c;
    x->nu = p->nu;
    x->S = p->S;
    x->n = t->n;
    x->v = t->v;
    x->tol = tol;
    x->s = sqrt((t->v - p->c) * (t->v + p->c)) / t->v;
    x->mu = p->gamma / x->s;
    x->beta = (p->c / t->v) * (p->c / t->v) / (x->s * x->s);
    x->L = p->S / (double)t->n;
    x->cycle = bkf_cycle_alloc();
    if (!x->cycle) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    bkf_cycle_options co = bkf_cycle_options_default();
    co.tol = 1e-12;
    /* The Radau meshes subdivide the cycle's own steps (bkf_cycle_mesh).
     * bd2x2, the stiff default since issue 20, takes longer steps than
     * bsimp: on n = 12 (mu 47) 4 substeps a step were then pre-asymptotic
     * (convergence ratio 23 against fifth order's 32); the meshes keep
     * bsimp's steps, for which the substep counts were measured, and
     * rk8pd's up to mu 30 as before bd2x2 took over from mu 20. */
    co.stepper = x->mu > BKF_CYCLE_EXPLICIT_MU_MAX ? BKF_STEPPER_IMPLICIT : BKF_STEPPER_EXPLICIT;
    int rc = bkf_cycle_solve(x->cycle, x->mu, x->nu, &co, err);
    if (rc != BKF_OK) return rc;
    const bkf_cycle_result *cr = bkf_cycle_get(x->cycle);
    x->T = cr->period;
    x->log_m = cr->log_multiplier;
    size_t count = bkf_cycle_mesh(x->cycle, NULL, 0);
    x->nodes = malloc((count + 1) * sizeof *x->nodes);
    if (!x->nodes) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    bkf_cycle_mesh(x->cycle, x->nodes, count);
    x->nodes[count] = x->T;
    x->node_count = count + 1;
    x->substeps = SUBSTEPS_START;
    x->re_floor = -2.0 * WINDOW_DEPTH * x->gamma;
    return BKF_OK;
}

/* The coarse mesh for a window up to height B: a step turns the fastest
 * solution, u ~ exp(+-sqrt(beta) sigma z), by at most RESOLVE_TURN (see
 * mesh_needs).  The fine one only the polish uses: meshes_for_polish
 * builds it, once the trace has settled the window (each build samples
 * the profile at three points a step, a third of a trace pass's cost at
 * mu 2). */
static int meshes_for(ctx *x, double B, const window *win, bkf_error *err)
{
    trainspec_mesh_free(&x->fine);
    int rc = trainspec_mesh_needs(x, hypot(B, win->a_hi), err);
    return rc != BKF_OK ? rc : trainspec_mesh_build(x, x->substeps, &x->coarse, err);
}

/* Trace both families over [0, B], B grown until the curves stay left of
 * a_lo in its upper quarter. */
static int trace_all(ctx *x, window *win, curve *c, double *y_max, bkf_error *err)
{
    /* beyond |sigma| ~ gamma v / c the spectrum is in its asymptotic regime */
    double B = fmax(2.0, x->gamma * x->v / x->c);
    double y0 = 0.0;
    for (;;) {
        int mrc = meshes_for(x, B, win, err);
        if (mrc != BKF_OK) return mrc;
        int rc = trace(x, win, y0, B, B, c);
        if (rc == BKF_ENOMEM) return bkf_error_set(err, rc, "out of memory");
        if (rc != BKF_OK)
            return bkf_error_set(err, rc, "spectrum: the multiplier curve could not be traced (mu = %.15g)", x->mu);
        int above = 0;
        for (int f = 0; f < FAMILIES; f++)
            for (size_t i = 0; i < c->count; i++)
                if (c->h[i].fam[f].found && c->h[i].fam[f].y > 0.75 * B) above = 1;
        if (!above) break;
        if (2.0 * B > Y_MAX_LIMIT)
            return bkf_error_set(err, BKF_EBUDGET,
                                 "spectrum: eigenvalues right of %.3g reach beyond |Im sigma| = %g", win->a_lo,
                                 Y_MAX_LIMIT);
        y0 = B;
        B *= 2.0;
    }
    *y_max = B;
    return BKF_OK;
}

/* ------------------------------------------------- Hill's stage (trainspec_hill.c) */

/* The error estimate of sigma polished to sf on the fine mesh (last Newton
 * step step_f) from sc on the coarse one. */
/* Hill's band alone: the meshes for its height, no curves. */
static int band_alone(ctx *x, const hill_stage *hs, window *win, double a_hi, double *y_max, int *fallback,
                      bkf_error *err)
{
    *fallback = 1;
    x->stop = 0;
    *y_max = hs->y_trust;
    win->a_hi = a_hi;
    x->substeps = SUBSTEPS_START;
    return meshes_for(x, hs->y_trust, win, err);
}

/* The candidates of every class: Hill's where it is cheap; where Hill's
 * first round vouches for its band (and no more than HILL_PER_CLASS - 1
 * are asked per class), Hill's band alone; else the traced curves', and
 * where the trace cannot close its window, Hill's band alone, M grown
 * until it vouches (*fallback set; trace_err says why the trace failed). */
static int gather(ctx *x, size_t classes, size_t keep, window *win, candidates *cs, hill_stage *hs, double *y_max,
                  size_t *curve_points, int *fallback, bkf_error *trace_err, bkf_error *err)
{
    curve heights = {0};
    *fallback = 0;
    int rc = trainspec_hill_candidates(x, classes, win, cs, hs, err);
    if (rc != BKF_OK) return rc;
    double a_hi = win->a_hi;
    if (hs->modes && hs->complete && hs->descended && keep < HILL_PER_CLASS) {
        bkf_error_set(trace_err, BKF_OK, "not traced: Hill's band vouched for its rightmost");
        return band_alone(x, hs, win, a_hi, y_max, fallback, err);
    }
    double max_work = x->max_work;
    /* where Hill has answered the trace is the cross-check: it may spend a
     * fifth of the budget, the rest polishes */
    if (hs->modes) x->max_work = x->work + HILL_TRACE_SHARE * (max_work - x->work);
    rc = trace_all(x, win, &heights, y_max, trace_err);
    x->max_work = max_work;
    if (rc != BKF_OK && rc != BKF_ENOMEM && x->stop != BKF_ECANCELED && hs->modes) {
        int hrc = trainspec_hill_grow(x, classes, win, cs, hs, err);
        if (hrc != BKF_OK) {
            free(heights.h);
            return hrc;
        }
    }
    if (rc != BKF_OK && rc != BKF_ENOMEM && x->stop != BKF_ECANCELED && hs->modes && hs->complete &&
        hs->descended) {
        heights.count = 0;
        rc = band_alone(x, hs, win, a_hi, y_max, fallback, err);
    } else if (rc != BKF_OK) {
        if (err) *err = *trace_err;
    }
    if (rc == BKF_OK) *curve_points += heights.count;
    for (int f = 0; f < FAMILIES && rc == BKF_OK; f++)
        if (collect(&heights, f, classes, cs) != BKF_OK) rc = bkf_error_set(err, BKF_ENOMEM, "out of memory");
    free(heights.h);
    return rc;
}

/* A class polishes at most this many times polish_n of the curves'
 * candidates (the rightmost first): the rest lie left of those and are
 * reached only where many of them fail or repeat one eigenvalue. */
#define POLISH_TRIES 2

/* Does the polish try candidate c, the tried-th of its class's curve
 * candidates (Hill's are all tried, see polish_candidates)? */
static int polish_tries(const candidate *c, size_t classes, size_t polish_n, size_t *tried)
{
    if (2 * c->cls > classes) return 0;
    return c->fam < 0 || (*tried)++ < POLISH_TRIES * polish_n;
}

/* The meshes of the polish, for the |sigma| of the candidates it may polish
 * rather than for the window's height: the window reaches |sigma| 2.8 at the
 * paper's n = 12 (mu 47) where its eigenvalues sit below 0.13, and a mesh
 * for the window's reach has about twice the steps.  Each value's error is
 * still its own pair of meshes' (estimate), so a candidate the meshes
 * resolve less well shows it in its estimate and the refinement. */
static int meshes_for_polish(ctx *x, size_t classes, size_t polish_n, candidates *cs, bkf_error *err)
{
    /* no candidate (items may then be NULL, which qsort may not take) */
    if (cs->count) qsort(cs->items, cs->count, sizeof *cs->items, by_a_desc);
    double reach = 0.0;
    for (size_t i = 0; i < cs->count;) {
        size_t cls = cs->items[i].cls, tried = 0;
        for (; i < cs->count && cs->items[i].cls == cls; i++)
            if (polish_tries(&cs->items[i], classes, polish_n, &tried))
                reach = fmax(reach, hypot(cs->items[i].a, cs->items[i].y));
    }
    reach = POLISH_MARGIN * reach + POLISH_REACH_MIN;
    int rc = BKF_OK;
    if (reach < x->sigma_reach) {
        rc = trainspec_mesh_needs(x, reach, err);
        if (rc == BKF_OK) rc = trainspec_mesh_build(x, x->substeps, &x->coarse, err);
    }
    return rc != BKF_OK ? rc : trainspec_mesh_build(x, 2 * x->substeps, &x->fine, err);
}

/* A candidate further left of its class's keep-th polished value than
 * this (relative to that value, and absolute) is not polished: the
 * candidates' distance from their coarse values was at most 0.05 |Re| +
 * 2.2e-3 (1.1 times it) in 17587 polishes on the paper's table and ten
 * random sets (mu 0.56-462), a quarter of this. */
#define POLISH_SKIP_REL 0.2
#define POLISH_SKIP_ABS 0.01
/* ... and a coarse value further left of it than this many times the
 * largest coarse-fine difference of the spectrum's polishes so far
 * (plus 10 tol) is not polished on the fine mesh. */
#define POLISH_SKIP_COARSE 8.0

/* Per polished eigenvalue, both families' sigma-derivatives at its last
 * polish (trainspec_polish): the next, finer mesh's polish steps with them. */
typedef struct {
    double complex d[2];
    double complex coarse; /* its value on the coarse mesh (polish_candidates) */
} derivs;

/* The keep-th largest Re sigma of eig[from..to) (-inf while fewer), the
 * translation aside: the cut reports it besides the keep, never instead of
 * one (counted, it let class 0's rightmost -3.3e-4 be skipped as left of
 * the translation's 1.5e-10). */
static double kth_re(const ctx *x, const bkf_trainspec_eigenvalue *eig, size_t from, size_t to, size_t keep)
{
    double top[PER_KAPPA_MAX + 1];
    size_t n = 0;
    for (size_t k = from; k < to; k++) {
        if (eig[k].j == 0 && hypot(eig[k].re, eig[k].im) < 10.0 * x->tol) continue;
        size_t at = n < keep ? n++ : keep;
        while (at > 0 && top[at - 1] < eig[k].re) {
            if (at < keep) top[at] = top[at - 1];
            at--;
        }
        if (at < keep) top[at] = eig[k].re;
    }
    return n == keep ? top[keep - 1] : -INFINITY;
}

/* The best few candidates of each class polished on both meshes into eig
 * (*n_eig of them), duplicates dropped; mirrored classes (j > classes/2)
 * come out of their partners by conjugation later.  How many are polished
 * per class does not depend on how many are reported: the rightmost must
 * not depend on per_kappa.  Once a class has keep values, a candidate
 * that lies left of the keep-th by more than a candidate's distance from
 * its eigenvalue (POLISH_SKIP_*) is not polished, and a coarse value left
 * of it by more than the coarse mesh's error (8 times the largest
 * coarse-fine difference seen, POLISH_SKIP_COARSE) not on the fine mesh:
 * the cut to keep per class would drop either whatever its value, and
 * those polishes were most of the polish (paper table: 5 per class polished
 * for 1 reported). */
static void polish_candidates(ctx *x, size_t classes, size_t keep, candidates *cs, bkf_trainspec_eigenvalue *eig,
                              derivs *dv, size_t *n_eig)
{
    size_t polish_n = (keep > 3 ? keep : 3) + 2;
    double coarse_err = 0.0;
    if (cs->count) qsort(cs->items, cs->count, sizeof *cs->items, by_a_desc);
    for (size_t i = 0; i < cs->count;) {
        size_t cls = cs->items[i].cls, taken = 0, tried = 0, start_n = *n_eig;
        for (; i < cs->count && cs->items[i].cls == cls; i++) {
            /* Hill's candidates are few and accurate: every one is polished,
             * whatever the traced ones, whose interpolated a can rank a far
             * eigenvalue before a near one, have taken */
            if ((taken >= polish_n && cs->items[i].fam >= 0) || !polish_tries(&cs->items[i], classes, polish_n, &tried))
                continue;
            candidate cd = cs->items[i];
            double kth = kth_re(x, eig, start_n, *n_eig, keep);
            if (cd.a < kth - (POLISH_SKIP_REL * fabs(kth) + POLISH_SKIP_ABS)) continue;
            double theta = 2.0 * M_PI * (double)cls / (double)classes;
            double complex sc = cd.a + I * cd.y, sf, d[2] = {NAN, NAN};
            double step_c, step_f;
            if (trainspec_polish(x, &x->coarse, theta, &sc, &step_c, d) != BKF_OK) continue;
            /* one eigenvalue reached again on the same mesh: the same value to
             * Newton's last step, no fine polish needed to tell */
            int seen = 0;
            for (size_t k = start_n; k < *n_eig; k++)
                if (cabs(dv[k].coarse - sc) < 10.0 * x->tol) seen = 1;
            if (seen) continue;
            if (creal(sc) < kth - (POLISH_SKIP_COARSE * coarse_err + 10.0 * x->tol)) continue;
            sf = sc;
            if (trainspec_polish(x, &x->fine, theta, &sf, &step_f, d) != BKF_OK) continue;
            coarse_err = fmax(coarse_err, cabs(sf - sc));
            double e = trainspec_estimate(sc, sf, step_f);
            int dup = 0;
            for (size_t k = start_n; k < *n_eig; k++)
                if (cabs((eig[k].re + I * eig[k].im) - sf) < 10.0 * fmax(e, x->tol)) dup = 1;
            if (dup) continue;
            dv[*n_eig].d[0] = d[0], dv[*n_eig].d[1] = d[1], dv[*n_eig].coarse = sc;
            eig[(*n_eig)++] = (bkf_trainspec_eigenvalue){creal(sf), cimag(sf), e, cls, 0.0, 0};
            taken++;
        }
    }
}

/* The translation mode, polished from 0 where the candidates missed it:
 * the gauge.  Where the traced curves missed it the meshes are too coarse. */
static void translation(ctx *x, bkf_trainspec_eigenvalue *eig, derivs *dv, size_t *n_eig)
{
    size_t k = 0;
    while (k < *n_eig && !(eig[k].j == 0 && hypot(eig[k].re, eig[k].im) < 10.0 * x->tol)) k++;
    if (k == *n_eig) {
        double complex sc = 0.0, sf, *d = dv[*n_eig].d;
        double step_c, step_f = INFINITY;
        d[0] = d[1] = NAN;
        int ok = trainspec_polish(x, &x->coarse, 0.0, &sc, &step_c, d) == BKF_OK;
        sf = sc;
        ok = ok && trainspec_polish(x, &x->fine, 0.0, &sf, &step_f, d) == BKF_OK;
        eig[(*n_eig)++] = (bkf_trainspec_eigenvalue){creal(sf), cimag(sf), ok ? trainspec_estimate(sc, sf, step_f) : INFINITY,
                                                     0, 0.0, 0};
    }
    eig[k].translation = 1;
}

/* Does eigenvalue k still need a finer mesh: its estimate above tol, or
 * (the translation) its distance from 0. */
static int unsettled(const ctx *x, const bkf_trainspec_eigenvalue *e)
{
    return e->err > x->tol || (e->translation && hypot(e->re, e->im) > x->tol);
}

/* Eigenvalues that the cut to `keep` per class will drop whatever their
 * errors are dropped before the refinement, which would otherwise refine
 * the mesh for them alone: those with keep + 1 others of their class right
 * of them beyond both errors (the cut keeps one beyond `keep` only as the
 * conjugate of the keep-th, and one further would be that one's conjugate,
 * the keep-th's own value: a duplicate). */
static void drop_hidden(bkf_trainspec_eigenvalue *eig, derivs *dv, size_t *n_eig, size_t keep)
{
    size_t w = 0;
    for (size_t i = 0; i < *n_eig; i++) {
        size_t right = 0;
        for (size_t k = 0; k < *n_eig; k++)
            right += k != i && eig[k].j == eig[i].j && !eig[k].translation &&
                     eig[k].re - eig[k].err > eig[i].re + eig[i].err;
        if (eig[i].translation || right < keep + 1) dv[w] = dv[i], eig[w++] = eig[i];
    }
    *n_eig = w;
}

/* The mesh refined until every estimate meets tol and the translation
 * mode sits at 0 within it.  Each refinement halves every step: the new
 * coarse mesh is the old fine one, on which the values in hand were
 * polished, so only the fine polish is redone, and only for the
 * eigenvalues whose estimate is still above tol (the others keep theirs). */
static int refine(ctx *x, size_t classes, bkf_trainspec_eigenvalue *eig, derivs *dv, size_t n_eig, bkf_error *err)
{
    /* per eigenvalue, the substeps of the fine mesh its value was polished on */
    size_t *on = malloc((n_eig ? n_eig : 1) * sizeof *on);
    if (!on) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    for (size_t k = 0; k < n_eig; k++) on[k] = 2 * x->substeps;
    int rc = BKF_OK;
    for (int r = 0;; r++) {
        double worst = 0.0;
        for (size_t k = 0; k < n_eig; k++) {
            worst = fmax(worst, eig[k].err);
            if (eig[k].translation) worst = fmax(worst, hypot(eig[k].re, eig[k].im));
        }
        if (worst <= x->tol) break;
        if (r == MESH_REFINEMENTS) {
            rc = bkf_error_set(err, BKF_ETOL,
                               "spectrum: an eigenvalue's estimated error %.3g exceeds tol %.3g at %zu "
                               "steps per period",
                               worst, x->tol, x->fine.steps);
            break;
        }
        x->substeps *= 2;
        mesh t = x->coarse;
        x->coarse = x->fine;
        x->fine = t;
        if ((rc = trainspec_mesh_build(x, 2 * x->substeps, &x->fine, err)) != BKF_OK) break;
        for (size_t k = 0; k < n_eig; k++) {
            if (!unsettled(x, &eig[k])) continue;
            double theta = 2.0 * M_PI * (double)eig[k].j / (double)classes;
            double complex sc = eig[k].re + I * eig[k].im, sf;
            double step_c = 0.0, step_f;
            if (on[k] != x->substeps && trainspec_polish(x, &x->coarse, theta, &sc, &step_c, dv[k].d) != BKF_OK)
                continue;
            sf = sc;
            if (trainspec_polish(x, &x->fine, theta, &sf, &step_f, dv[k].d) != BKF_OK) continue;
            eig[k].re = creal(sf);
            eig[k].im = cimag(sf);
            eig[k].err = trainspec_estimate(sc, sf, step_f);
            on[k] = 2 * x->substeps;
        }
    }
    free(on);
    return rc;
}

/* The conjugates of the classes 0 < j < classes/2 as the classes
 * classes - j, all sorted, and `keep` per class kept. */
static void mirror_and_cut(size_t classes, size_t keep, bkf_trainspec_eigenvalue *eig, size_t *count)
{
    size_t n_eig = *count;
    for (size_t k = 0, polished = n_eig; k < polished; k++)
        if (eig[k].j > 0 && 2 * eig[k].j < classes) {
            eig[n_eig] = eig[k];
            eig[n_eig].j = classes - eig[k].j;
            eig[n_eig++].im = -eig[k].im;
        }
    qsort(eig, n_eig, sizeof *eig, eig_desc);
    size_t w = 0;
    for (size_t i = 0; i < n_eig; i++) {
        size_t same = 0;
        /* the translation is reported besides the `keep`, never instead of one
         * (with keep 1 it took class 0's only place: issue 31's window edge
         * -0.203 printed for sigma_max -4.08e-4) */
        for (size_t k = 0; k < w; k++) same += eig[k].j == eig[i].j && !eig[k].translation;
        /* a conjugate pair (j = 0 or n/2) is never split by the cut */
        int partner = w > 0 && eig[w - 1].j == eig[i].j &&
                      fabs(eig[w - 1].re - eig[i].re) <= eig[w - 1].err + eig[i].err &&
                      fabs(eig[w - 1].im + eig[i].im) <= eig[w - 1].err + eig[i].err && eig[i].im != 0.0;
        if (same < keep || eig[i].translation || partner) eig[w++] = eig[i];
    }
    *count = w;
}

/* Hill's band alone: its rightmost eigenvalue must be one the meshes
 * confirm, else the band's candidates were not converged. */
static int confirm_band(const hill_stage *hs, const bkf_trainspec_eigenvalue *eig, size_t n_eig,
                        const bkf_error *trace_err, bkf_error *err)
{
    double complex top = NAN;
    for (size_t k = 0; k < n_eig; k++)
        if (!eig[k].translation && !(creal(top) >= eig[k].re)) top = eig[k].re + I * eig[k].im;
    double miss = INFINITY;
    for (size_t k = 0; k < hs->count; k++) miss = fmin(miss, cabs(hs->at[k] - conj(top)));
    for (size_t k = 0; k < hs->count; k++) miss = fmin(miss, cabs(hs->at[k] - top));
    if (isfinite(creal(top)) && !(miss <= HILL_AGREE * (1.0 + cabs(top))))
        return bkf_error_set(err, BKF_ETOL,
                             "spectrum: Hill's method at %zu modes and the Radau meshes disagree on the "
                             "rightmost eigenvalue by %.3g (%s)",
                             hs->modes, miss, trace_err->message);
    return BKF_OK;
}

/* Spectrum in `classes` phase classes: per class the `keep` rightmost
 * eigenvalues, polished on the fine mesh with error estimates. */
static int spectrum(ctx *x, size_t classes, size_t keep, bkf_trainspec_eigenvalue **out, size_t *count,
                    window *win, double *y_max, size_t *curve_points, size_t *hill_modes, bkf_error *err)
{
    candidates cs = {0};
    hill_stage hs;
    bkf_error trace_err = {0};
    int fallback = 0;
    size_t n_eig = 0;
    bkf_trainspec_eigenvalue *eig = NULL;
    derivs *dv = NULL;
    int rc = gather(x, classes, keep, win, &cs, &hs, y_max, curve_points, &fallback, &trace_err, err);
    *hill_modes = hs.modes;
    size_t polish_n = (keep > 3 ? keep : 3) + 2;
    if (rc == BKF_OK) {
        eig = calloc(2 * (classes + 2) * (polish_n + HILL_PER_CLASS + 1), sizeof *eig);
        dv = calloc(2 * (classes + 2) * (polish_n + HILL_PER_CLASS + 1), sizeof *dv);
        if (!eig || !dv) rc = bkf_error_set(err, BKF_ENOMEM, "out of memory");
    }
    if (rc == BKF_OK) rc = meshes_for_polish(x, classes, polish_n, &cs, err);
    if (rc == BKF_OK) {
        polish_candidates(x, classes, keep, &cs, eig, dv, &n_eig);
        translation(x, eig, dv, &n_eig);
        drop_hidden(eig, dv, &n_eig, keep);
        rc = refine(x, classes, eig, dv, n_eig, err);
    }
    if (rc == BKF_OK) mirror_and_cut(classes, keep, eig, &n_eig);
    if (rc == BKF_OK && fallback) rc = confirm_band(&hs, eig, n_eig, &trace_err, err);
    trainspec_hill_stage_free(&hs);
    free(cs.items);
    free(dv);
    if (rc != BKF_OK) {
        free(eig);
        return rc;
    }
    *out = eig;
    *count = n_eig;
    return BKF_OK;
}

/* The reason a search was cut short, over whatever failure it produced. */
int trainspec_stopped(const ctx *x, int rc, bkf_error *err)
{
    if (x->stop == BKF_ECANCELED) return bkf_error_set(err, BKF_ECANCELED, "spectrum: canceled");
    if (x->stop == BKF_EBUDGET)
        return bkf_error_set(err, BKF_EBUDGET,
                             "the spectrum needs more than %.3g Radau steps in all (mu = %.15g; the budget is "
                             "max_work)",
                             x->max_work, x->mu);
    return rc;
}

static window initial_window(const ctx *x, double *r_inf)
{
    *r_inf = x->s * x->log_m / (2.0 * x->T);
    return (window){.a_lo = fmax(0.5 * *r_inf, -WINDOW_DEPTH * x->gamma), .a_hi = fmax(1.0, x->gamma)};
}

void bkf_trainspec_result_free(bkf_trainspec_result *r)
{
    if (!r) return;
    free(r->eigenvalues);
    r->eigenvalues = NULL;
    r->count = 0;
}

int bkf_trainspec_ring(const bkf_model_params *p, const bkf_trainspec_train *t,
                       const bkf_trainspec_options *options, bkf_trainspec_result *r, bkf_error *err)
{
    if (!r) return bkf_error_set(err, BKF_EINPUT, "result is NULL");
    memset(r, 0, sizeof *r);
    bkf_trainspec_options o = options ? *options : bkf_trainspec_options_default();
    int rc = bkf_trainspec_check(p, t, &o, err);
    if (rc != BKF_OK) return rc;
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    ctx x;
    rc = trainspec_ctx_init(&x, p, t, o.tol, &o, err);
    window win = initial_window(&x, &r->r_inf);
    if (rc == BKF_OK)
        rc = spectrum(&x, t->n, o.per_kappa, &r->eigenvalues, &r->count, &win, &r->y_max,
                      &r->curve_points, &r->hill_modes, err);
    rc = trainspec_stopped(&x, rc, err);
    if (rc == BKF_OK) {
        r->params = *p;
        r->n = t->n;
        r->v = t->v;
        r->mu = x.mu;
        r->T = x.T;
        r->L = x.L;
        r->a_lo = win.a_lo;
        r->mesh_steps = x.fine.steps;
        r->liouville_residual = fabs(x.fine.trace_sum - x.log_m);
        for (size_t i = 0; i < r->count; i++)
            if (r->eigenvalues[i].translation)
                r->translation_residual = hypot(r->eigenvalues[i].re, r->eigenvalues[i].im);
        r->sigma_max = -INFINITY;
        for (size_t i = 0; i < r->count; i++) {
            bkf_trainspec_eigenvalue *e = &r->eigenvalues[i];
            e->kappa = 2.0 * M_PI * (double)e->j / p->S;
            if (e->translation || e->re <= r->sigma_max) continue;
            r->sigma_max = e->re;
            r->sigma_max_im = e->im;
            r->sigma_max_err = e->err;
            r->kappa_max = e->kappa;
        }
        if (!isfinite(r->sigma_max)) {
            /* nothing right of a_lo but the translation */
            r->sigma_max = win.a_lo;
            r->sigma_max_err = 0.0;
            r->sigma_is_bound = 1;
            r->verdict = BKF_TRAINSPEC_STABLE;
        } else {
            r->complex_pair = fabs(r->sigma_max_im) > r->sigma_max_err;
            r->verdict = r->sigma_max + r->sigma_max_err < 0.0   ? BKF_TRAINSPEC_STABLE
                         : r->sigma_max - r->sigma_max_err > 0.0 ? BKF_TRAINSPEC_UNSTABLE
                                                                 : BKF_TRAINSPEC_UNRESOLVED;
        }
        r->evaluations = x.evaluations;
        r->work = x.work;
    }
    trainspec_ctx_free(&x);
    bkf_gsl_handler_pop(handler);
    if (rc != BKF_OK) bkf_trainspec_result_free(r);
    return rc;
}

int bkf_trainspec_root(const bkf_model_params *params, const bkf_speeds_root *root, double tol,
                       size_t per_kappa, bkf_trainspec_result *result, bkf_error *err)
{
    if (!root) return bkf_error_set(err, BKF_EINPUT, "root is NULL");
    if (root->status != BKF_OK) {
        if (result) memset(result, 0, sizeof *result);
        return bkf_speeds_root_status(root, err);
    }
    bkf_trainspec_train train = {root->n, root->v};
    bkf_trainspec_options o = bkf_trainspec_options_default();
    o.tol = tol;
    o.per_kappa = per_kappa;
    return bkf_trainspec_ring(params, &train, &o, result, err);
}

const char *bkf_trainspec_kind_name(const bkf_trainspec_result *result)
{
    return result->complex_pair ? "complex" : "real";
}

bkf_trainspec_shown bkf_trainspec_shown_of(const bkf_trainspec_result *r)
{
    if (r->sigma_is_bound) return (bkf_trainspec_shown){NAN, NAN, NAN, NAN, NULL, r->sigma_max};
    return (bkf_trainspec_shown){r->sigma_max, r->sigma_max_im, r->sigma_max_err, r->kappa_max,
                                 bkf_trainspec_kind_name(r), NAN};
}

const char *bkf_trainspec_bound_note(double bound, char *buf, size_t size)
{
    char b[32];
    bkf_format_number(bound, b, sizeof b);
    snprintf(buf, size,
             "sigma_max nan: no eigenvalue but the translation found right of Re sigma = %s (the "
             "edge of the window searched): every eigenvalue left of %s",
             b, b);
    return buf;
}

int bkf_trainspec_line(const bkf_model_params *p, const bkf_trainspec_train *t,
                       const bkf_trainspec_options *options, size_t count, bkf_trainspec_eigenvalue *out,
                       bkf_error *err)
{
    bkf_trainspec_options o = options ? *options : bkf_trainspec_options_default();
    int rc = bkf_trainspec_check(p, t, &o, err);
    if (rc != BKF_OK) return rc;
    if (count < 2 || count > 100000) return bkf_error_set(err, BKF_EINPUT, "count must be in [2, 100000]");
    if (!out) return bkf_error_set(err, BKF_EINPUT, "out is NULL");
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    ctx x;
    rc = trainspec_ctx_init(&x, p, t, o.tol, &o, err);
    double r_inf, y_max;
    size_t points = 0, n_eig = 0;
    window win = initial_window(&x, &r_inf);
    bkf_trainspec_eigenvalue *eig = NULL;
    size_t hill_modes = 0;
    if (rc == BKF_OK) rc = spectrum(&x, count, 1, &eig, &n_eig, &win, &y_max, &points, &hill_modes, err);
    rc = trainspec_stopped(&x, rc, err);
    if (rc == BKF_OK) {
        double L = x.L;
        for (size_t i = 0; i < count; i++)
            out[i] = (bkf_trainspec_eigenvalue){NAN, NAN, NAN, i, 2.0 * M_PI * (double)i / ((double)count * L), 0};
        /* the rightmost of each class (the translation too: the branch it is on
         * passes through 0 at kappa 0); not the last listed, which at kappa 0 was
         * the translation below class 0's rightmost (issue 31: 8.8e-11 for 0.0697) */
        for (size_t k = 0; k < n_eig; k++) {
            size_t j = eig[k].j;
            if (out[j].re >= eig[k].re) continue;
            out[j].re = eig[k].re;
            out[j].im = eig[k].im;
            out[j].err = eig[k].err;
        }
    }
    free(eig);
    trainspec_ctx_free(&x);
    bkf_gsl_handler_pop(handler);
    return rc;
}

/* The train spectrum's monodromy: the Radau IIA meshes over one period of
 * the profile and the monodromy of the perturbation p over them, with its
 * sigma-derivative (docs/numerics.md, "The monodromy", "The mesh"). */
#include "bkfront/cycle.h"

#include <gsl/gsl_math.h>

#include <complex.h>
#include <math.h>
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
    free(m->pstep);
    memset(m, 0, sizeof *m);
}

/* Every run of stiff (or of non-stiff) cycle steps gets a whole number
 * of steps, at least MESH_MIN_STEPS in all: the meshes' steps, spread
 * evenly in the cumulative need (mesh_bounds), then never straddle a
 * change of basis, at any number of substeps. */
static void whole_runs(ctx *x)
{
    size_t n = x->node_count - 1;
    double total = 0.0;
    for (size_t i = 0; i < n; i++) total += x->need[i];
    double grow = total < MESH_MIN_STEPS ? MESH_MIN_STEPS / total : 1.0;
    for (size_t r0 = 0, r1; r0 < n; r0 = r1) {
        double sum = 0.0;
        for (r1 = r0; r1 < n && x->stiff[r1] == x->stiff[r0]; r1++) sum += grow * x->need[r1];
        double scale = grow * ceil(sum - 1e-9) / sum;
        for (size_t i = r0; i < r1; i++) x->need[i] *= scale;
    }
}

/* The steps each cycle step needs (a real number: the meshes spread them
 * evenly, see mesh_bounds) for |sigma| up to reach.  Where the cycle step
 * is not stiff a step spans at most RESOLVE_TURN e-foldings or radians of
 * the fastest local solution, the roots of lambda^2 = a lambda + b; where
 * it is stiff, RESOLVE_TURN of the slow solution only.  Either way at most
 * PROFILE_TURN of the profile's change.  Steps that are not stiff are
 * taken in u's basis (radau_step), whose rates these are: p's are |sigma|
 * / s faster (issue 31: with p's steps on meshes for u's rates, c / v =
 * 0.085, p turned 2.7 radians a step at the window's top, the damped
 * monodromy kept a curve right of a_lo up to |Im sigma| 1e4 and the
 * spectrum was refused).  Stiff steps are taken in p's basis.
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
    unsigned char *stiff = realloc(x->stiff, n);
    if (stiff) x->stiff = stiff;
    int rc = !f || !fp || !slow || !phi || !rate || !need || !stiff ? bkf_error_set(err, BKF_ENOMEM, "out of memory")
                                                          : bkf_cycle_profile_sample(x->cycle, x->nodes, n, f, fp, err);
    for (size_t i = 0; rc == BKF_OK && i < n; i++) {
        phi[i] = f[i] * f[i] - 1.0;
        double a = x->mu * fabs(phi[i]), b_fixed = fabs(1.0 + 2.0 * x->mu * f[i] * fp[i]);
        double b = b_fixed + x->beta * reach * (reach + x->gamma * fabs(phi[i]));
        /* u's rates: the steps that are not stiff are taken in u's basis */
        rate[i] = 0.5 * a + sqrt(0.25 * a * a + b);
        slow[i] = b_fixed + reach * (reach + x->gamma * fabs(phi[i])); /* bounds |bp| */
    }
    /* the non-stiff steps' limits loosened for a looser tol (COARSEN_TOL) */
    double g = fmin(COARSEN_MAX, fmax(1.0, pow(x->tol / COARSEN_TOL, 0.2)));
    for (size_t i = 0; rc == BKF_OK && i + 1 < n; i++) {
        double len = x->nodes[i + 1] - x->nodes[i];
        double plain = len * fmax(rate[i], rate[i + 1]) / (g * RESOLVE_TURN);
        double decay = x->mu * (fmin(phi[i], phi[i + 1]) + 2.0 * x->re_floor / x->gamma);
        double stiff = decay > 0.0 ? len * fmax(slow[i], slow[i + 1]) / decay / RESOLVE_TURN : INFINITY;
        /* stiff steps, of length len / stiff, must damp the fast solution */
        int use_stiff = stiff < plain && decay * len >= STIFF_MIN * fmax(stiff, 1.0);
        double loose = use_stiff ? 1.0 : g;
        need[i] = fmax(fmax(use_stiff ? stiff : plain, fabs(f[i + 1] - f[i]) / (loose * PROFILE_TURN)),
                       NODE_SHARE / loose);
        x->stiff[i] = (unsigned char)use_stiff;
    }
    if (rc == BKF_OK) whole_runs(x);
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
    m->pstep = malloc(cap);
    m->g0 = malloc(9 * cap * sizeof *m->g0);
    m->m = malloc(9 * cap * sizeof *m->m);
    m->ab0 = malloc(3 * cap * sizeof *m->ab0);
    m->aphi = malloc(3 * cap * sizeof *m->aphi);
    double *z = malloc(STRIDE * cap * sizeof *z), *f = malloc(STRIDE * cap * sizeof *f);
    double *fp = malloc(STRIDE * cap * sizeof *fp);
    int rc = BKF_OK;
    if (!m->h || !m->a || !m->b0 || !m->phi || !m->pstep || !m->g0 || !m->m || !m->ab0 || !m->aphi || !z || !f || !fp) {
        rc = bkf_error_set(err, BKF_ENOMEM, "out of memory");
        goto done;
    }
    for (size_t k = 0, i = 0; k < steps; k++) {
        double h = bounds[k + 1] - bounds[k], mid = bounds[k] + 0.5 * h;
        m->h[k] = h;
        /* the basis of the cycle step the step lies in (they never straddle
         * a change, whole_runs) */
        while (i + 2 < x->node_count && x->nodes[i + 1] <= mid) i++;
        m->pstep[k] = x->stiff ? x->stiff[i] : 0;
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
    /* whole_runs made total a whole number (up to rounding) */
    double count = fmax(ceil(total - 1e-6), MESH_MIN_STEPS) * (double)substeps;
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

/* A step's transfer of (u, u') into that of (p, p') but for the scalar
 * exp(-k h): (u, u') = exp(k z) K (p, p'), K = [[1, 0], [k, 1]], so E_p =
 * exp(-k h) K^-1 E_u K; K^-1 E_u K and its sigma-derivative (dk/dsigma =
 * 1/s) when de is not NULL (trainspec_radau_step; the monodromy changes
 * basis once a run of u steps instead).  The scalars commute with every
 * step: the monodromy takes them all at once (one complex exponential a
 * pass). */
/* a = [[1, 0], [c, 1]] a (K for c = k, K^-1 for c = -k), and da its
 * sigma-derivative (dc = dc/dsigma) when not NULL: a transfer taken into
 * u's basis before a run of u steps and back after it, so that the run's
 * steps are not conjugated one by one. */
static void change_basis(double complex a[4], double complex *da, double complex c, double dc)
{
    if (da) {
        da[2] += dc * a[0] + c * da[0];
        da[3] += dc * a[1] + c * da[1];
    }
    a[2] += c * a[0];
    a[3] += c * a[1];
}

static void conjugate_k(double complex e[4], double complex *de, double complex k, double s)
{
    double complex dk = 1.0 / s;
    double complex t0 = e[0] + k * e[1], t2 = e[2] + k * e[3];
    if (de) {
        double complex dt0 = de[0] + k * de[1] + dk * e[1], dt2 = de[2] + k * de[3] + dk * e[3];
        double complex d2 = dt2 - dk * t0 - k * dt0, d3 = de[3] - dk * e[1] - k * de[1];
        de[0] = dt0, de[2] = d2, de[3] = d3;
    }
    e[3] = e[3] - k * e[1];
    e[2] = t2 - k * t0;
    e[0] = t0;
}

/* The Radau IIA step i at sigma in its own basis: p = exp(-sigma z / s) u
 * on stiff steps (m->pstep), where the solution that survives the
 * L-stable step varies slowly (see mesh_needs), u elsewhere, where p's
 * solutions turn at |sigma| / s and u's at sqrt(beta) |sigma| only:
 * (p, p') (or (u, u')) after the step = e times it before, e[0..3]
 * row-major, and de = de/dsigma when de is not NULL.  With V the stages
 * of p', the stages of p are p0 + h A V, so the six stage equations reduce
 * to three:
 *     G V = (I - h A diag(ap) - h^2 A diag(bp) A) V = p0' + h p0 A bp.
 * The monodromy is kept in p's basis: u's is exp(k T) K P K^-1 with
 * K = [[1, 0], [k, 1]], k = sigma / s, the same multipliers times exp(k T),
 * which the eigenvalue condition divides out again (monodromy); a run of u
 * steps enters it through K and K^-1 and the scalars exp(-k h) (see
 * conjugate_k). */
static void radau_step(const ctx *x, const mesh *m, size_t i, double complex sigma, double complex e[4],
                       double complex de[4])
{
    double h = m->h[i];
    int pb = m->pstep[i];
    /* p: ap = a - 2 k, bp = b0 - sigma^2 - gamma sigma phi: G = G0 + 2 k h A
     * + h^2 sigma^2 A^2 + h^2 gamma sigma M (mesh_fill made G0 and M); u:
     * a, b0 + beta sigma (sigma + gamma phi), the same with the sigma terms
     * weighted -beta and no k */
    double wq = pb ? 1.0 : -x->beta;
    double complex k = sigma / x->s, G[3][3], r[3][4];
    double complex c1 = pb ? 2.0 * k * h : 0.0, c2 = wq * h * h * sigma * sigma, c3 = wq * h * h * x->gamma * sigma;
    double complex s2 = wq * sigma * sigma, gs = wq * x->gamma * sigma;
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
        double complex d2 = wq * 2.0 * h * h * sigma;
        double d1 = pb ? 2.0 * h / x->s : 0.0, d3 = wq * h * h * x->gamma;
        double complex b[3][2];
        for (int q = 0; q < 3; q++) {
            double complex dr0 = -wq * h * (2.0 * sigma * RADAU_C[q] + x->gamma * m->aphi[3 * i + q]);
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

void trainspec_radau_step(const ctx *x, const mesh *m, size_t i, double complex sigma, double complex e[4],
                          double complex de[4])
{
    radau_step(x, m, i, sigma, e, de);
    if (m->pstep[i]) return;
    conjugate_k(e, de, sigma / x->s, x->s);
    double h = m->h[i];
    double complex g = cexp(-sigma / x->s * h);
    for (int j = 0; j < 4; j++) {
        if (de) de[j] = g * (de[j] - h / x->s * e[j]);
        e[j] *= g;
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
    double hu = 0.0; /* the u steps' length: their scalars exp(-k h) all at once */
    double complex k = sigma / x->s;
    int in_u = 0;    /* p (and dp) hold u's transfer, K times p's, through a run of u steps */
    for (size_t i = 0; i < m->steps; i++) {
        double complex e[4], de[4];
        radau_step(x, m, i, sigma, e, dp ? de : NULL);
        if (!m->pstep[i]) hu += m->h[i];
        if (in_u != !m->pstep[i]) {
            change_basis(p, dp, in_u ? -k : k, in_u ? -1.0 / x->s : 1.0 / x->s);
            in_u = !in_u;
        }
        if (dp) {
            double complex t1[4], t2[4];
            mul2(de, p, t1);
            mul2(e, dp, t2);
            for (int q = 0; q < 4; q++) dp[q] = t1[q] + t2[q];
        }
        mul2(e, p, p);
        /* a step's factor is O(1) in p's basis (the growth exp(k h) is
         * u's, and the u steps' is taken out: exp(sqrt(beta) |sigma| h) is
         * left): every eighth step is often enough to stay far from overflow */
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
    if (in_u) change_basis(p, dp, -k, -1.0 / x->s);
    /* exp(-k hu): its modulus into the scale, its phase into p (and d/dsigma
     * of it, -hu/s times it, into dp) */
    double complex turn = cexp(-I * cimag(k) * hu);
    *scale -= creal(k) * hu;
    for (int q = 0; q < 4; q++) {
        if (dp) dp[q] = turn * (dp[q] - hu / x->s * p[q]);
        p[q] *= turn;
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
void trainspec_monodromy(ctx *x, const mesh *m, double complex sigma, double complex w[2], double complex *dw)
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

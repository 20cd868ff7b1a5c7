/* The collocation engine's mesh (colloc.c): the Gauss tables, the interval
 * polynomials, the Gauss step, remeshing, and the cyclic Newton that
 * condenses the stages per interval.  Below the guesses (colloc_guess.c) and
 * the solve (colloc.c), which call it; it calls neither. */
#include "colloc_internal.h"

#include <float.h>
#include <gsl/gsl_math.h>
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

/* Complete unrolling of the loops over the M stages in solve_rows and
 * gauss_step, whose Newton iterations are one serial chain (-O2 kept them
 * as loops: the matrix then went through row pointers and memory, and a
 * cold T at mu 1e4 was latency-bound); the arithmetic and its order are
 * unchanged.  On condense, whose intervals are independent, it gained
 * nothing. */
#if defined(__GNUC__) && !defined(__clang__)
#define BKF_UNROLL _Pragma("GCC unroll 8")
#else
#define BKF_UNROLL
#endif

/* ------------------------------------------------------------ tables */

/* The Lagrange basis on the nodes (0, c_1..c_m) at theta. */
void colloc_lagrange_weights(const double *c, double theta, double *l)
{
    double th[M + 1];
    th[0] = 0.0;
    for (int i = 0; i < M; i++) th[i + 1] = c[i];
    for (int k = 0; k <= M; k++) {
        l[k] = 1.0;
        for (int q = 0; q <= M; q++)
            if (q != k) l[k] *= (theta - th[q]) / (th[k] - th[q]);
    }
}

static void gauss_init(gauss_table *g)
{
    /* Legendre roots on [-1, 1] by Newton from Chebyshev-like guesses */
    for (int i = 0; i < M; i++) {
        double z = cos(M_PI * (i + 0.75) / (M + 0.5)), dp = 1.0;
        for (int it = 0; it < 100; it++) {
            double p0 = 1.0, p1 = z;
            for (int k = 2; k <= M; k++) {
                double p2 = ((2.0 * k - 1.0) * z * p1 - (k - 1.0) * p0) / k;
                p0 = p1;
                p1 = p2;
            }
            if (M == 1) p0 = 1.0;
            dp = M * (z * p1 - p0) / (z * z - 1.0);
            double dz = p1 / dp;
            z -= dz;
            if (fabs(dz) < 1e-17) break;
        }
        g->c[M - 1 - i] = 0.5 * (1.0 + z);
        g->w[M - 1 - i] = 1.0 / ((1.0 - z * z) * dp * dp);
    }
    /* A_il = integral over [0, c_i] of the Lagrange basis l_l: Gauss
     * quadrature is exact on its degree m - 1 */
    for (int i = 0; i < M; i++)
        for (int l = 0; l < M; l++) {
            double s = 0.0;
            for (int k = 0; k < M; k++) {
                double u = g->c[i] * g->c[k], lv = 1.0;
                for (int q = 0; q < M; q++)
                    if (q != l) lv *= (u - g->c[q]) / (g->c[l] - g->c[q]);
                s += g->w[k] * lv;
            }
            g->A[i][l] = g->c[i] * s;
        }
    for (int i = 0; i < M; i++) {
        g->Ac[i] = 0.0;
        for (int l = 0; l < M; l++) {
            g->Ac[i] += g->A[i][l] * g->c[l];
            double s = 0.0;
            for (int k = 0; k < M; k++) s += g->A[i][k] * g->A[k][l];
            g->A2[i][l] = s;
        }
    }
    for (int l = 0; l < M; l++) {
        g->p[l] = 0.0;
        for (int i = 0; i < M; i++) g->p[l] += g->w[i] * g->A[i][l];
    }
    double th[M + 1];
    th[0] = 0.0;
    for (int i = 0; i < M; i++) th[i + 1] = g->c[i];
    g->mfact = 1.0;
    for (int k = 1; k <= M; k++) g->mfact *= k;
    for (int k = 0; k <= M; k++) {
        double d = 1.0;
        for (int l = 0; l <= M; l++)
            if (l != k) d *= th[k] - th[l];
        g->dd[k] = 1.0 / d;
    }
    for (int i = 0; i < M; i++)
        colloc_lagrange_weights(g->c, g->c[i] < 0.5 ? 2.0 * g->c[i] : 2.0 * g->c[i] - 1.0, g->halves[i]);
    colloc_lagrange_weights(g->c, 1.0, g->end);
    for (int k = 0; k <= M; k++) {
        double *b = g->basis[k];
        memset(b, 0, sizeof g->basis[k]);
        b[0] = 1.0;
        int deg = 0;
        for (int q = 0; q <= M; q++) {
            if (q == k) continue;
            /* b *= (theta - th_q) / (th_k - th_q) */
            double d = 1.0 / (th[k] - th[q]);
            for (int p = ++deg; p >= 0; p--) b[p] = ((p ? b[p - 1] : 0.0) - th[q] * b[p]) * d;
        }
    }
}

/* The tables are the same for every object: built once (a cold T at
 * mu 0.1 built them per solve, 36k of its 250k instructions). */
static gauss_table gauss_shared;
static pthread_once_t gauss_once = PTHREAD_ONCE_INIT;
static void gauss_shared_init(void) { gauss_init(&gauss_shared); }

bkf_colloc *bkf_colloc_alloc(void)
{
    bkf_colloc *c = calloc(1, sizeof *c);
    if (!c) return NULL;
    pthread_once(&gauss_once, gauss_shared_init);
    c->g = gauss_shared;
    return c;
}

void bkf_colloc_free(bkf_colloc *c)
{
    if (!c) return;
    free(c->t);
    free(c->x);
    free(c->y);
    free(c->X);
    free(c->Z);
    free(c->lin);
    free(c->du);
    free(c->ts);
    free(c->xs);
    free(c->ys);
    free(c->Xs);
    free(c->keep);
    free(c);
}

int colloc_grow(double **p, size_t count)
{
    double *q = realloc(*p, count * sizeof *q);
    if (!q) return 0;
    *p = q;
    return 1;
}

int colloc_reserve(bkf_colloc *c, size_t n)
{
    if (n <= c->cap) return 1;
    size_t cap = n + n / 2 + 16;
    if (!colloc_grow(&c->t, cap + 1) || !colloc_grow(&c->x, cap + 1) || !colloc_grow(&c->y, cap + 1) ||
        !colloc_grow(&c->X, cap * M) || !colloc_grow(&c->Z, cap * 4 * M) || !colloc_grow(&c->lin, cap * 8) ||
        !colloc_grow(&c->du, 2 * (cap + 1)))
        return 0;
    c->cap = cap;
    return 1;
}

int colloc_reserve_scratch(bkf_colloc *c, size_t n)
{
    if (n <= c->scap) return 1;
    size_t cap = n + n / 2 + 16;
    if (!colloc_grow(&c->ts, cap + 1) || !colloc_grow(&c->xs, cap + 1) || !colloc_grow(&c->ys, cap + 1) ||
        !colloc_grow(&c->Xs, cap * M))
        return 0;
    c->scap = cap;
    return 1;
}

void colloc_set_params(bkf_colloc *c, double mu, double nu)
{
    c->mu = mu;
    c->nu = nu;
    c->a = sqrt(1.0 + mu * mu);
    c->b = mu / c->a;
}

/* ------------------------------------------------- interval polynomials */

/* Stage y values of interval j (linear in the stage x values). */
void colloc_stage_y(const bkf_colloc *c, size_t j, double *Y)
{
    const gauss_table *g = &c->g;
    const double *X = c->X + j * M;
    double tau_a = (c->t[j + 1] - c->t[j]) * c->T / c->a;
    for (int i = 0; i < M; i++) {
        double ax = 0.0;
        for (int l = 0; l < M; l++) ax += g->A[i][l] * X[l];
        Y[i] = c->y[j] + tau_a * (c->nu * g->c[i] - ax);
    }
}

/* The collocation polynomial of interval j (degree m through its start and
 * its stages) at theta in [0, 1]. */
void colloc_poly_eval(const bkf_colloc *c, size_t j, double theta, double *xv, double *yv)
{
    const gauss_table *g = &c->g;
    double Y[M], l[M + 1];
    colloc_stage_y(c, j, Y);
    colloc_lagrange_weights(g->c, theta, l);
    double sx = l[0] * c->x[j], sy = l[0] * c->y[j];
    for (int i = 0; i < M; i++) {
        sx += l[i + 1] * c->X[j * M + i];
        sy += l[i + 1] * Y[i];
    }
    *xv = sx;
    *yv = sy;
}

/* Gaussian elimination with partial pivoting on the M x M block of r, for
 * the right-hand sides in columns M..ncol-1, which the solutions
 * overwrite.  0 if the block is singular.  divide: by the pivot rather than
 * times its inverse, the rounding gauss_step always had (its results decide the turn's step
 * acceptance, hence the mesh: the inverse moved T at mu 1e4 by 24 ulps).
 * Inlined, so that ncol and divide are constants and the loops unroll. */
#if defined(__GNUC__)
__attribute__((always_inline))
#endif
static inline int solve_rows(double r[M][M + 4], int ncol, int divide)
{
    BKF_UNROLL
    for (int k = 0; k < M; k++) {
        int piv = k;
        double best = fabs(r[k][k]);
        BKF_UNROLL
        for (int i = k + 1; i < M; i++)
            if (fabs(r[i][k]) > best) {
                best = fabs(r[i][k]);
                piv = i;
            }
        if (!(best > 0.0)) return 0;
        if (piv != k) {
            BKF_UNROLL
            for (int l = k; l < ncol; l++) {
                double t = r[k][l];
                r[k][l] = r[piv][l];
                r[piv][l] = t;
            }
        }
        double inv = 1.0 / r[k][k];
        BKF_UNROLL
        for (int i = k + 1; i < M; i++) {
            double f = divide ? r[i][k] / r[k][k] : r[i][k] * inv;
            if (f == 0.0 && !divide) continue;
            BKF_UNROLL
            for (int l = k + 1; l < ncol; l++) r[i][l] -= f * r[k][l];
        }
        if (!divide) r[k][k] = inv;
    }
    BKF_UNROLL
    for (int col = M; col < ncol; col++)
        BKF_UNROLL
        for (int i = M - 1; i >= 0; i--) {
            double s = r[i][col];
            BKF_UNROLL
            for (int l = i + 1; l < M; l++) s -= r[i][l] * r[l][col];
            r[i][col] = divide ? s / r[i][i] : s * r[i][i];
        }
    return 1;
}

/* One Gauss step of length tau from (x0, y0): the stage equations R(X) = 0
 * by Newton from the guess in X, until a correction is below goal (1 +
 * |x0|); the end values into (x1, y1).  0 if Newton does not converge (the
 * step is too long for its guess). */
int colloc_gauss_step(const bkf_colloc *c, double x0, double y0, double tau, double goal, double *X, double *x1,
                      double *y1)
{
    const gauss_table *g = &c->g;
    const double mu = c->mu, nu = c->nu, a = c->a, tt = tau * tau, tm = tau * mu;
    /* What does not change over the iterations, hoisted out of them, and
     * the stages iterated in a local copy (the stores through X made the
     * compiler reload the tables); every sum in the order of the plain
     * formula, so the result is the same to the bit. */
    double B[M][M], C[M][M], r0[M], nac[M];
    BKF_UNROLL
    for (int i = 0; i < M; i++) {
        BKF_UNROLL
        for (int l = 0; l < M; l++) {
            B[i][l] = (i == l) + tt * g->A2[i][l];
            C[i][l] = tm * g->A[i][l];
        }
        r0[i] = tau * a * g->c[i] * y0;
        nac[i] = nu * g->Ac[i];
    }
    double Xl[M];
    memcpy(Xl, X, sizeof Xl);
    for (int it = 0; it < 12; it++) {
        double F[M], Fp[M], mat[M][M + 4], dmax = 0.0;
        BKF_UNROLL
        for (int i = 0; i < M; i++) {
            F[i] = lienard_F(Xl[i]);
            Fp[i] = Xl[i] * Xl[i] - 1.0;
        }
        BKF_UNROLL
        for (int i = 0; i < M; i++) {
            double a2x = 0.0, af = 0.0;
            BKF_UNROLL
            for (int l = 0; l < M; l++) {
                a2x += g->A2[i][l] * Xl[l];
                af += g->A[i][l] * F[l];
                mat[i][l] = B[i][l] + C[i][l] * Fp[l];
            }
            mat[i][M] = -(Xl[i] - x0 - r0[i] - tt * (nac[i] - a2x) + tm * af);
        }
        if (!solve_rows(mat, M + 1, 1)) {
            memcpy(X, Xl, sizeof Xl);
            return 0;
        }
        BKF_UNROLL
        for (int i = 0; i < M; i++) {
            Xl[i] += mat[i][M];
            if (fabs(mat[i][M]) > dmax) dmax = fabs(mat[i][M]);
        }
        if (!isfinite(dmax) || dmax > 10.0) {
            memcpy(X, Xl, sizeof Xl);
            return 0;
        }
        if (dmax <= goal * (1.0 + fabs(x0))) {
            memcpy(X, Xl, sizeof Xl);
            double pX = 0.0, wF = 0.0, wX = 0.0;
            BKF_UNROLL
            for (int l = 0; l < M; l++) {
                pX += g->p[l] * Xl[l];
                wF += g->w[l] * lienard_F(Xl[l]);
                wX += g->w[l] * Xl[l];
            }
            *x1 = x0 + tau * a * y0 + tt * (0.5 * nu - pX) - tm * wF;
            *y1 = y0 + tau / a * (nu - wX);
            return isfinite(*x1) && isfinite(*y1);
        }
    }
    memcpy(X, Xl, sizeof Xl);
    return 0;
}

/* Move the solution onto the mesh ts[0..n].  The old polynomials between
 * mesh points are only of stage order, and far off inside under-resolved
 * fast layers (mu 1e3: the bisected guess needed Newton corrections of 1e5),
 * so each new interval is re-integrated by Gauss steps from the nearest old
 * mesh point (superconvergent) with the polynomials as the stages' start;
 * where a step does not converge, the polynomial values stay. */
static int remesh_to(bkf_colloc *c, const double *ts, size_t n)
{
    if (!colloc_reserve_scratch(c, n)) return BKF_ENOMEM;
    size_t j = 0;
    for (size_t k = 0; k < n; k++) {
        double h = ts[k + 1] - ts[k];
        while (j + 1 < c->n && c->t[j + 1] <= ts[k]) j++;
        double hj = c->t[j + 1] - c->t[j], th0 = (ts[k] - c->t[j]) / hj, xv, yv, X[M];
        if (th0 > 0.0) {
            /* a partial step from the old mesh point */
            double tau = (ts[k] - c->t[j]) * c->T, x1, y1;
            for (int i = 0; i < M; i++) colloc_poly_eval(c, j, c->g.c[i] * th0, &X[i], &yv);
            if (colloc_gauss_step(c, c->x[j], c->y[j], tau, STAGE_GOAL, X, &x1, &y1)) {
                xv = x1;
                yv = y1;
            } else {
                colloc_poly_eval(c, j, th0, &xv, &yv);
            }
        } else {
            xv = c->x[j];
            yv = c->y[j];
        }
        c->xs[k] = xv;
        c->ys[k] = yv;
        size_t jj = j;
        for (int i = 0; i < M; i++) {
            double s = ts[k] + c->g.c[i] * h, unused;
            while (jj + 1 < c->n && c->t[jj + 1] <= s) jj++;
            colloc_poly_eval(c, jj, (s - c->t[jj]) / (c->t[jj + 1] - c->t[jj]), &c->Xs[k * M + i], &unused);
        }
        double stage[M], x1, y1;
        memcpy(stage, c->Xs + k * M, sizeof stage);
        if (colloc_gauss_step(c, xv, yv, h * c->T, STAGE_GOAL, stage, &x1, &y1))
            memcpy(c->Xs + k * M, stage, sizeof stage);
    }
    if (!colloc_reserve(c, n)) return BKF_ENOMEM;
    memcpy(c->t, ts, (n + 1) * sizeof *ts);
    memcpy(c->x, c->xs, n * sizeof *c->x);
    memcpy(c->y, c->ys, n * sizeof *c->y);
    memcpy(c->X, c->Xs, n * M * sizeof *c->X);
    c->n = n;
    c->x[n] = c->x[0];
    c->y[n] = c->y[0];
    c->t[0] = 0.0;
    c->t[n] = 1.0;
    return BKF_OK;
}

/* A mesh of n intervals that equidistributes |u^(m+1)|^(1/(m+1)), the
 * (m+1)-th derivative estimated from the jumps of the polynomials' constant
 * m-th derivatives between neighbouring intervals (de Boor; AUTO's adapt). */
int colloc_equidistribute(bkf_colloc *c, size_t n)
{
    const gauss_table *g = &c->g;
    size_t n0 = c->n;
    double *D = malloc(2 * n0 * sizeof *D), *rho = malloc((n0 + 1) * sizeof *rho), *ts = malloc((n + 1) * sizeof *ts);
    if (!D || !rho || !ts) {
        free(D);
        free(rho);
        free(ts);
        return BKF_ENOMEM;
    }
    for (size_t j = 0; j < n0; j++) {
        double Y[M], h = c->t[j + 1] - c->t[j], dx = g->dd[0] * c->x[j], dy = g->dd[0] * c->y[j];
        colloc_stage_y(c, j, Y);
        for (int i = 0; i < M; i++) {
            dx += g->dd[i + 1] * c->X[j * M + i];
            dy += g->dd[i + 1] * Y[i];
        }
        double s = g->mfact / pow(h, M);
        D[2 * j] = dx * s;
        D[2 * j + 1] = dy * s;
    }
    double total = 0.0;
    rho[0] = 0.0;
    for (size_t j = 0; j < n0; j++) {
        size_t jm = j ? j - 1 : n0 - 1, jp = j + 1 < n0 ? j + 1 : 0;
        double h = c->t[j + 1] - c->t[j], hm = c->t[jm + 1] - c->t[jm], hp = c->t[jp + 1] - c->t[jp];
        double em = fmax(fabs(D[2 * j] - D[2 * jm]), fabs(D[2 * j + 1] - D[2 * jm + 1])) / (0.5 * (h + hm));
        double ep = fmax(fabs(D[2 * jp] - D[2 * j]), fabs(D[2 * jp + 1] - D[2 * j + 1])) / (0.5 * (h + hp));
        double dens = pow(0.5 * (em + ep), 1.0 / (M + 1));
        rho[j + 1] = dens * h;
        total += dens * h;
    }
    /* a floor keeps smooth stretches from being stripped of intervals */
    double floor = 0.02 * total;
    double acc = 0.0;
    for (size_t j = 0; j < n0; j++) {
        acc += rho[j + 1] + floor * (c->t[j + 1] - c->t[j]);
        rho[j + 1] = acc;
    }
    total = acc;
    ts[0] = 0.0;
    size_t j = 0;
    for (size_t k = 1; k < n; k++) {
        double target = total * (double)k / (double)n;
        while (j + 1 < n0 && rho[j + 1] < target) j++;
        double f = (target - rho[j]) / (rho[j + 1] - rho[j]);
        ts[k] = c->t[j] + f * (c->t[j + 1] - c->t[j]);
    }
    ts[n] = 1.0;
    int rc = remesh_to(c, ts, n);
    free(D);
    free(rho);
    free(ts);
    return rc;
}

int colloc_bisect(bkf_colloc *c)
{
    size_t n = 2 * c->n;
    double *ts = malloc((n + 1) * sizeof *ts);
    if (!ts) return BKF_ENOMEM;
    for (size_t j = 0; j < c->n; j++) {
        ts[2 * j] = c->t[j];
        ts[2 * j + 1] = 0.5 * (c->t[j] + c->t[j + 1]);
    }
    ts[n] = 1.0;
    int rc = remesh_to(c, ts, n);
    free(ts);
    return rc;
}

/* ------------------------------------------------------------- Newton */

/* Condense interval j: Z = the stage corrections' columns (residual, dx_j,
 * dy_j, dT), lin = G (row-major 2x2), g, r.  0 if the stage matrix is
 * singular. */
static int condense(const bkf_colloc *c, size_t j, double *Z, double *lin)
{
    const gauss_table *g = &c->g;
    const double *X = c->X + j * M;
    const double mu = c->mu, nu = c->nu, a = c->a;
    double h = c->t[j + 1] - c->t[j], tau = h * c->T, xj = c->x[j], yj = c->y[j];
    double F[M], Fp[M], R[M];
    for (int i = 0; i < M; i++) {
        F[i] = lienard_F(X[i]);
        Fp[i] = X[i] * X[i] - 1.0;
    }
    double mat[M][M + 4];
    for (int i = 0; i < M; i++) {
        double a2x = 0.0, af = 0.0;
        for (int l = 0; l < M; l++) {
            a2x += g->A2[i][l] * X[l];
            af += g->A[i][l] * F[l];
        }
        double lin_part = nu * g->Ac[i] - a2x;
        R[i] = X[i] - xj - tau * a * g->c[i] * yj - tau * tau * lin_part + tau * mu * af;
        double rtau = -a * g->c[i] * yj - 2.0 * tau * lin_part + mu * af;
        for (int l = 0; l < M; l++)
            mat[i][l] = (i == l) + tau * tau * g->A2[i][l] + tau * mu * g->A[i][l] * Fp[l];
        mat[i][M] = -R[i];
        mat[i][M + 1] = 1.0;
        mat[i][M + 2] = tau * a * g->c[i];
        mat[i][M + 3] = -h * rtau;
    }
    if (!solve_rows(mat, M + 4, 0)) return 0;
    /* the sums from the local rows, Z stored after (stores through Z make
     * the compiler reload the tables) */
    double pX = 0.0, wF = 0.0, wX = 0.0, gz[4] = {0}, wz[4] = {0};
    for (int l = 0; l < M; l++) {
        pX += g->p[l] * X[l];
        wF += g->w[l] * F[l];
        wX += g->w[l] * X[l];
        double gl = tau * tau * g->p[l] + tau * mu * g->w[l] * Fp[l];
        for (int col = 0; col < 4; col++) {
            gz[col] += gl * mat[l][M + col];
            wz[col] += g->w[l] * mat[l][M + col];
        }
    }
    for (int col = 0; col < 4; col++)
        for (int i = 0; i < M; i++) Z[col * M + i] = mat[i][M + col];
    double Ex = c->x[j + 1] - xj - tau * a * yj - tau * tau * (0.5 * nu - pX) + tau * mu * wF;
    double Ey = c->y[j + 1] - yj - tau / a * (nu - wX);
    double Qt = a * yj + 2.0 * tau * (0.5 * nu - pX) - mu * wF;
    double ta = tau / a;
    lin[0] = 1.0 - gz[1];
    lin[1] = tau * a - gz[2];
    lin[2] = -ta * wz[1];
    lin[3] = 1.0 - ta * wz[2];
    lin[4] = h * Qt - gz[3];
    lin[5] = h / a * (nu - wX) - ta * wz[3];
    lin[6] = -Ex - gz[0];
    lin[7] = -Ey - ta * wz[0];
    return isfinite(lin[0] + lin[1] + lin[2] + lin[3] + lin[4] + lin[5] + lin[6] + lin[7]);
}

/* Integral of -mu (x^2 - 1) over the period by the Gauss quadrature of the
 * stages. */
double colloc_log_multiplier(const bkf_colloc *c)
{
    double L = 0.0;
    for (size_t j = 0; j < c->n; j++) {
        double s = 0.0;
        for (int i = 0; i < M; i++) {
            double x = c->X[j * M + i];
            s += c->g.w[i] * (x * x - 1.0);
        }
        L += (c->t[j + 1] - c->t[j]) * s;
    }
    return -c->mu * c->T * L;
}

/* Newton on the current mesh until the correction is below `goal`
 * (relative to T and to the cycle's size); the last correction is applied,
 * so what it leaves is of the order of its square. */
int colloc_newton(bkf_colloc *c, double goal, bkf_error *err)
{
    const size_t n = c->n;
    double size = fmin(1.0, 2.0 * sqrt(fmax(1.0 - c->nu * c->nu, 0.0)));
    double previous = INFINITY;
    for (int it = 0; it < MAX_NEWTON; it++) {
        c->x[n] = c->x[0];
        c->y[n] = c->y[0];
        double P[4] = {1, 0, 0, 1}, q[2] = {0, 0}, s[2] = {0, 0}, pmax = 1.0;
        for (size_t j = 0; j < n; j++) {
            double *lin = c->lin + 8 * j;
            if (!condense(c, j, c->Z + 4 * M * j, lin))
                return bkf_error_set(err, BKF_ENUMERIC,
                                     "collocation at mu = %.15g, nu = %.15g: singular stage system", c->mu,
                                     c->nu);
            double P0 = lin[0] * P[0] + lin[1] * P[2], P1 = lin[0] * P[1] + lin[1] * P[3];
            double P2 = lin[2] * P[0] + lin[3] * P[2], P3 = lin[2] * P[1] + lin[3] * P[3];
            P[0] = P0, P[1] = P1, P[2] = P2, P[3] = P3;
            double q0 = lin[0] * q[0] + lin[1] * q[1] + lin[4], q1 = lin[2] * q[0] + lin[3] * q[1] + lin[5];
            q[0] = q0, q[1] = q1;
            double s0 = lin[0] * s[0] + lin[1] * s[1] + lin[6], s1 = lin[2] * s[0] + lin[3] * s[1] + lin[7];
            s[0] = s0, s[1] = s1;
            double pm = fmax(fmax(fabs(P0), fabs(P1)), fmax(fabs(P2), fabs(P3)));
            if (pm > pmax) pmax = pm;
        }
        c->solves += n;
        c->iterations++;
        if (!(pmax <= PRODUCT_MAX))
            return bkf_error_set(err, BKF_ENUMERIC,
                                 "collocation at mu = %.15g, nu = %.15g: the interval maps' product reaches "
                                 "%.2g (repelling stretch): refused",
                                 c->mu, c->nu, pmax);
        c->trace = P[0] + P[3];
        double dx0 = c->nu - c->x[0];
        double B00 = P[0] - 1.0, B01 = P[1], B10 = P[2], B11 = P[3] - 1.0;
        double r0 = -s[0] - B00 * dx0, r1 = -s[1] - B10 * dx0;
        double det = B01 * q[1] - q[0] * B11;
        if (!(fabs(det) > 1e-300) || !isfinite(det))
            return bkf_error_set(err, BKF_ENUMERIC, "collocation at mu = %.15g, nu = %.15g: singular cyclic system",
                                 c->mu, c->nu);
        double dy0 = (r0 * q[1] - q[0] * r1) / det, dT = (B01 * r1 - B11 * r0) / det;
        double *du = c->du;
        du[0] = dx0;
        du[1] = dy0;
        double dmax = fabs(dT) / c->T;
        for (size_t j = 0; j < n; j++) {
            const double *lin = c->lin + 8 * j;
            double a0 = du[2 * j], a1 = du[2 * j + 1];
            du[2 * j + 2] = lin[0] * a0 + lin[1] * a1 + lin[4] * dT + lin[6];
            du[2 * j + 3] = lin[2] * a0 + lin[3] * a1 + lin[5] * dT + lin[7];
        }
        /* the recursion's return to du_0 measures its conditioning */
        double scale = fmax(fabs(dx0) + fabs(dy0) + fabs(dT) / c->T, 1e-300);
        double closure = fmax(fabs(du[2 * n] - du[0]), fabs(du[2 * n + 1] - du[1]));
        if (!(closure <= CLOSURE_MAX * scale + 1e3 * DBL_EPSILON))
            return bkf_error_set(err, BKF_ENUMERIC,
                                 "collocation at mu = %.15g, nu = %.15g: the cyclic solve is ill-conditioned "
                                 "(mismatch %.2g): refused",
                                 c->mu, c->nu, closure / scale);
        for (size_t j = 0; j < n; j++) {
            const double *Z = c->Z + 4 * M * j;
            double a0 = du[2 * j], a1 = du[2 * j + 1];
            for (int i = 0; i < M; i++) {
                double d = Z[i] + Z[M + i] * a0 + Z[2 * M + i] * a1 + Z[3 * M + i] * dT;
                if (fabs(d) > dmax * size) dmax = fabs(d) / size;
            }
            if (fmax(fabs(a0), fabs(a1)) > dmax * size) dmax = fmax(fabs(a0), fabs(a1)) / size;
        }
        if (!isfinite(dmax))
            return bkf_error_set(err, BKF_ENUMERIC, "collocation at mu = %.15g, nu = %.15g: Newton diverged",
                                 c->mu, c->nu);
        /* damped while far (a loose guess) */
        double lambda = dmax > 0.3 ? 0.3 / dmax : 1.0;
        for (size_t j = 0; j < n; j++) {
            const double *Z = c->Z + 4 * M * j;
            double a0 = du[2 * j], a1 = du[2 * j + 1];
            for (int i = 0; i < M; i++)
                c->X[j * M + i] += lambda * (Z[i] + Z[M + i] * a0 + Z[2 * M + i] * a1 + Z[3 * M + i] * dT);
            c->x[j] += lambda * a0;
            c->y[j] += lambda * a1;
        }
        c->T += lambda * dT;
        c->x[n] = c->x[0];
        c->y[n] = c->y[0];
        if (!(c->T > 0.0))
            return bkf_error_set(err, BKF_ENUMERIC, "collocation at mu = %.15g, nu = %.15g: T went negative",
                                 c->mu, c->nu);
        if (lambda == 1.0 && dmax <= goal) return BKF_OK;
        /* stalled at rounding: no longer shrinking quadratically */
        if (lambda == 1.0 && dmax <= 1e3 * DBL_EPSILON && dmax > 0.25 * previous) return BKF_OK;
        /* or at the rounding of an ill-conditioned cyclic solve (mu 1e4,
         * nu 0.99: the product reaches 1e8 and the stages' corrections
         * bounce at 1e-7 while T's are at 2e-15, for 13 iterations): T
         * moves by less than what a converged Newton leaves (the estimate
         * adds that, 1e-4 tol) */
        if (lambda == 1.0 && dmax > 0.25 * previous && fabs(dT) <= goal * goal * c->T) return BKF_OK;
        previous = lambda == 1.0 ? dmax : INFINITY;
    }
    return bkf_error_set(err, BKF_ENUMERIC,
                         "collocation at mu = %.15g, nu = %.15g: Newton did not converge in %d iterations", c->mu,
                         c->nu, MAX_NEWTON);
}


/* Gauss-Legendre collocation for the limit cycle (colloc.h).
 *
 * Per mesh interval j (length h in s, tau = h T in z) the stage values X_i
 * at the Gauss points c_i are the unknowns; the stage y values are linear in
 * them, Y_i = y_j + (tau/a) (nu c_i - (A X)_i), so they are eliminated in
 * closed form and the interval's Newton matrix is m x m, not 2m x 2m:
 *     R_i = X_i - x_j - tau a c_i y_j - tau^2 (nu (A c)_i - (A^2 X)_i)
 *           + tau mu (A F(X))_i = 0
 * (a b = mu).  The end of the interval follows from the quadrature weights w:
 *     x_{j+1} = x_j + tau a y_j + tau^2 (nu/2 - w^T A X) - tau mu w^T F(X),
 *     y_{j+1} = y_j + (tau/a) (nu - w^T X).
 * Newton condenses the stages per interval (one m x m LU, four right-hand
 * sides), which leaves du_{j+1} = G_j du_j + g_j dT + r_j; the periodicity
 * du_n = du_0 and the phase dx_0 = nu - x_0 reduce that to a 2x2 system for
 * (dy_0, dT) through the product of the G_j.  That product is the discrete
 * monodromy: it is stable where the cycle attracts; inside canards, where
 * the orbit follows the repelling slow branch, its partial products grow
 * like exp(mu x the time there), and the forward recursion's mismatch
 * du_n - du_0 shows it: the engine refuses then (the shooting engine answers). */
#include "bkfront/colloc.h"

#include <float.h>
#include <gsl/gsl_math.h>
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#define M BKF_COLLOC_M
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
/* Newton iterations per mesh before the solve refuses. */
#define MAX_NEWTON 30
/* Largest partial product of interval maps, and largest relative mismatch
 * of the forward recursion, that the cyclic solve accepts. */
#define PRODUCT_MAX 1e10
#define CLOSURE_MAX 1e-3
/* Largest mesh of the pair (intervals of the finer). */
#define MAX_INTERVALS 40000
#define MIN_INTERVALS 8
/* The estimate |T_N - T_2N| / EST_DIVISOR of the finer T: the error of
 * Gauss collocation falls like h^(2m) (2^8 = 256 on bisection for m = 4);
 * 16 keeps the estimate honest while the mesh is still outside the
 * asymptotic range. */
#define EST_DIVISOR 16.0
#define ACCEPT_MARGIN 3.0
/* The same for the pair of a turn's mesh and its coarsening (merged
 * pairs), with TURN_FLOOR below: that pair is at the edge of the asymptotic
 * range (mu 20.5, nu -0.96, tol 1e-10: |T_N - T_N/2| was 4 times T_N's
 * error of 1.8e-12; mu 28, nu 0.5: it agreed by chance to 4e-14 against a
 * true 7.6e-13), which the floor covers; a divisor of 2 instead cost a
 * second turn at mu 30-100 (1.7 times the instructions). */
#define PAIRED_DIVISOR 16.0
/* and never below this fraction of the turn's local tolerance (relative):
 * the true error was at most 2e-4 of it over tests/wave/test_colloc.c,
 * test_cycle_engine.c and test_extremes.c (3e-3 made the cycle's estimate
 * at tol 1e-12 too coarse for Floquet's lambda at gamma 10, which
 * colloc_turn_tol now also answers). */
#define TURN_FLOOR 1e-3
/* Newton's goal in that pair, times sqrt(tol): what it leaves, of the
 * square, is 1e-2 tol, added to the estimate.  The turn's mesh values and
 * stages start the finer Newton within about 1e-6 (mu 30-1e4, tol 1e-10),
 * and the coarser from the finer's: 0.01 (converge's) took each a second
 * or third iteration for a T that had moved by 1e-15 relative (the stages
 * were still moving at 1e-7 - 1e-8). */
#define PAIRED_GOAL 0.1

typedef struct {
    double c[M], w[M], A[M][M], A2[M][M], Ac[M], p[M];
    double dd[M + 1];  /* divided-difference weights on the nodes (0, c_1..c_m) */
    double mfact;      /* m! */
    /* a step's stages from the polynomials of its two halves: stage i is
     * the first half's polynomial (on the nodes 0, c) at 2 c_i, or the
     * second's at 2 c_i - 1 */
    double halves[M][M + 1];
    /* the same basis in powers of theta: basis[k][p] */
    double basis[M + 1][M + 1];
    /* the basis at theta = 1: a step's end value from its start and stages */
    double end[M + 1];
} gauss_table;

struct bkf_colloc {
    double mu, nu, a, b;
    size_t n, cap;
    double *t;      /* mesh in s, n + 1 */
    double *x, *y;  /* mesh values, n + 1 (index n duplicates 0) */
    double *X;      /* stage x values, n M */
    double T;
    int have_guess, have_solution;
    /* work */
    double *Z;      /* n x 4 x M condensed columns */
    double *lin;    /* n x 8: G (4), g (2), r (2) */
    double *du;     /* 2 (n + 1) */
    double *ts, *xs, *ys, *Xs; /* remesh scratch */
    size_t scap;
    gauss_table g;
    size_t iterations, solves;
    double trace, log_mult;
    size_t pair_n; /* the coarser mesh of the last accepted pair */
    int paired;    /* the mesh is pairs of half steps (bkf_colloc_guess_turn) */
    int uniform;   /* a uniform mesh of a smooth cycle (bkf_colloc_guess_series) */
    double local_tol; /* of those steps */
    double *keep;  /* the finer solution while its coarsening is solved */
    size_t keep_cap;
};

/* ------------------------------------------------------------ tables */

/* The Lagrange basis on the nodes (0, c_1..c_m) at theta. */
static void lagrange_weights(const double *c, double theta, double *l)
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
        lagrange_weights(g->c, g->c[i] < 0.5 ? 2.0 * g->c[i] : 2.0 * g->c[i] - 1.0, g->halves[i]);
    lagrange_weights(g->c, 1.0, g->end);
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

static int grow(double **p, size_t count)
{
    double *q = realloc(*p, count * sizeof *q);
    if (!q) return 0;
    *p = q;
    return 1;
}

static int reserve(bkf_colloc *c, size_t n)
{
    if (n <= c->cap) return 1;
    size_t cap = n + n / 2 + 16;
    if (!grow(&c->t, cap + 1) || !grow(&c->x, cap + 1) || !grow(&c->y, cap + 1) || !grow(&c->X, cap * M) ||
        !grow(&c->Z, cap * 4 * M) || !grow(&c->lin, cap * 8) || !grow(&c->du, 2 * (cap + 1)))
        return 0;
    c->cap = cap;
    return 1;
}

static int reserve_scratch(bkf_colloc *c, size_t n)
{
    if (n <= c->scap) return 1;
    size_t cap = n + n / 2 + 16;
    if (!grow(&c->ts, cap + 1) || !grow(&c->xs, cap + 1) || !grow(&c->ys, cap + 1) || !grow(&c->Xs, cap * M))
        return 0;
    c->scap = cap;
    return 1;
}

static void set_params(bkf_colloc *c, double mu, double nu)
{
    c->mu = mu;
    c->nu = nu;
    c->a = sqrt(1.0 + mu * mu);
    c->b = mu / c->a;
}

static double lienard_F(double x) { return x * x * x / 3.0 - x; }

/* ------------------------------------------------- interval polynomials */

/* Stage y values of interval j (linear in the stage x values). */
static void stage_y(const bkf_colloc *c, size_t j, double *Y)
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
static void poly_eval(const bkf_colloc *c, size_t j, double theta, double *xv, double *yv)
{
    const gauss_table *g = &c->g;
    double Y[M], l[M + 1];
    stage_y(c, j, Y);
    lagrange_weights(g->c, theta, l);
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
#define STAGE_GOAL 1e-12
static int gauss_step(const bkf_colloc *c, double x0, double y0, double tau, double goal, double *X, double *x1,
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
    if (!reserve_scratch(c, n)) return BKF_ENOMEM;
    size_t j = 0;
    for (size_t k = 0; k < n; k++) {
        double h = ts[k + 1] - ts[k];
        while (j + 1 < c->n && c->t[j + 1] <= ts[k]) j++;
        double hj = c->t[j + 1] - c->t[j], th0 = (ts[k] - c->t[j]) / hj, xv, yv, X[M];
        if (th0 > 0.0) {
            /* a partial step from the old mesh point */
            double tau = (ts[k] - c->t[j]) * c->T, x1, y1;
            for (int i = 0; i < M; i++) poly_eval(c, j, c->g.c[i] * th0, &X[i], &yv);
            if (gauss_step(c, c->x[j], c->y[j], tau, STAGE_GOAL, X, &x1, &y1)) {
                xv = x1;
                yv = y1;
            } else {
                poly_eval(c, j, th0, &xv, &yv);
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
            poly_eval(c, jj, (s - c->t[jj]) / (c->t[jj + 1] - c->t[jj]), &c->Xs[k * M + i], &unused);
        }
        double stage[M], x1, y1;
        memcpy(stage, c->Xs + k * M, sizeof stage);
        if (gauss_step(c, xv, yv, h * c->T, STAGE_GOAL, stage, &x1, &y1)) memcpy(c->Xs + k * M, stage, sizeof stage);
    }
    if (!reserve(c, n)) return BKF_ENOMEM;
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
static int equidistribute(bkf_colloc *c, size_t n)
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
        stage_y(c, j, Y);
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

static int bisect(bkf_colloc *c)
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
static double log_multiplier(const bkf_colloc *c)
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
static int newton(bkf_colloc *c, double goal, bkf_error *err)
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

/* ------------------------------------------------------------- guesses */

/* Step-doubled Gauss steps: a step of length tau against two of tau/2,
 * accepted where their end values agree within the local tolerance; the
 * error of the end values (superconvergent, order 2m) is of the step's
 * tau^(2m+1), so the next step is scaled by its 1/(2m+1)-th root, and by
 * the predictive factor of Gustafsson's controller (Hairer-Wanner IV.8, as
 * in RADAU5), which extrapolates the change of the error constant from the
 * last two accepted steps: along a slow branch towards its fold the
 * constant grew by 1.4 a step and the plain rule was rejected every third
 * step, in a jump's entry by 1e4 a step (mu 1e3, nu -0.96: 84 rejections
 * in 180 steps of a turn, 17 with the prediction; Gauss steps per turn 786
 * -> 611).  No growth right after a rejection. */
#define TURN_GROW_MAX 4.0
#define TURN_SHRINK 0.25
#define TURN_STAGE_GOAL 1e-4

/* Stage guess of a step from (x0, y0): the Euler line. */
static void stage_guess(const bkf_colloc *c, double x0, double y0, double tau, double *X)
{
    double xd = (c->a * y0 - c->mu * lienard_F(x0)) * tau;
    if (fabs(xd) > 4.0) xd = copysign(4.0, xd);
    for (int l = 0; l < M; l++) X[l] = x0 + c->g.c[l] * xd;
}

/* Stages of a step of ratio r times the length of the last one, which
 * started at x0 with stages X: that step's polynomial beyond its end, at
 * 1 + r c_i (the Euler line's guess took Newton a third iteration). */
static void stage_extrapolate(const gauss_table *g, double x0, const double *X, double r, double *out)
{
    double a[M + 1];
    for (int p = 0; p <= M; p++) {
        a[p] = g->basis[0][p] * x0;
        for (int k = 0; k < M; k++) a[p] += g->basis[k + 1][p] * X[k];
    }
    for (int i = 0; i < M; i++) {
        double theta = 1.0 + r * g->c[i], s = a[M];
        for (int p = M - 1; p >= 0; p--) s = s * theta + a[p];
        out[i] = s;
    }
}

/* Extrapolate only this far (in lengths of the last step). */
#define EXTRAPOLATE_MAX 2.0

/* A Gauss step from the guess in X or, where Newton does not converge from
 * it, from the Euler line. */
static int guarded_step(const bkf_colloc *c, double x0, double y0, double tau, double goal, int guessed, double *X,
                        double *x1, double *y1)
{
    if (guessed) {
        double Xg[M];
        memcpy(Xg, X, sizeof Xg);
        if (gauss_step(c, x0, y0, tau, goal, Xg, x1, y1)) {
            memcpy(X, Xg, sizeof Xg);
            return 1;
        }
    }
    stage_guess(c, x0, y0, tau, X);
    return gauss_step(c, x0, y0, tau, goal, X, x1, y1);
}

/* A turn's end values from the step's polynomial at its end, sum_k
 * end_k (x0, X)_k (the collocation polynomial through the start and the
 * stages), not from gauss_step's quadrature x0 + tau a y0 + tau^2 (nu/2 -
 * p^T X) - tau mu w^T F(X): on a slow branch at large mu that sums terms
 * of 1e4 for a change of 1e-3, and its rounding, about eps tau mu, is all
 * the step doubling then measured (at mu 1e4, tol 1e-12 the differences
 * were 0-1e-11 in multiples of 4.5e-13 where the local tolerance is 1e-11,
 * steps of 1-8 where the error allowed about 80).  Both are the same
 * polynomial; the interpolation's rounding is eps |x| (a few 1e-16), and
 * its weight on the stages' Newton error is O(1) where the quadrature's is
 * tau mu. */
static double end_value(const gauss_table *g, double x0, const double *X, double *magnitude)
{
    double s = g->end[0] * x0, m = fabs(s);
    for (int k = 0; k < M; k++) {
        double v = g->end[k + 1] * X[k];
        s += v;
        m += fabs(v);
    }
    if (magnitude) *magnitude = m;
    return s;
}

/* Below ROUND_SIGNAL times the rounding of the step doubling's difference
 * (eps times the sum of end_value's terms for x, and of |y0| + |y1 - y0|
 * for y1 = y0 + tau/a (nu - w^T X)) the difference says nothing about the
 * step's truncation error: such a step is accepted, and the predictive
 * factor (which assumes the error grows like tau^(2m+1)) is not used. */
#define ROUND_SIGNAL 4.0

/* Two Gauss steps of tau/2 from (xs, ys): stages into Xa, Xb, ends into
 * (xa, ya) (the middle) and (xb, yb).  prev (the last half step's start
 * and stages, of length tau/2 / ratio) or NULL: the first stages' guess.
 * (Inlined: out of line, its calls were 1% of a cold T at mu 10.) */
#if defined(__GNUC__)
__attribute__((always_inline))
#endif
static inline int half_steps(const bkf_colloc *c, double xs, double ys, double tau, double goal, const double *prev,
                             double ratio, double *Xa, double *Xb, double *xa, double *ya, double *xb, double *yb)
{
    int guessed = prev && ratio <= EXTRAPOLATE_MAX;
    if (guessed) stage_extrapolate(&c->g, prev[0], prev + 1, ratio, Xa);
    if (!guarded_step(c, xs, ys, 0.5 * tau, goal, guessed, Xa, xa, ya)) return 0;
    *xa = end_value(&c->g, xs, Xa, NULL);
    stage_extrapolate(&c->g, xs, Xa, 1.0, Xb);
    if (!guarded_step(c, *xa, *ya, 0.5 * tau, goal, 1, Xb, xb, yb)) return 0;
    *xb = end_value(&c->g, *xa, Xb, NULL);
    return 1;
}

/* One turn from (x0, y0) on the section x = nu (x' > 0) back to it: the
 * turn ends where it next crosses the section upwards after crossing it
 * downwards, so the mesh closes on the section (ending at a fixed T, the
 * closure fell in the jump, where the shot's 1e-5 in T is a shift of
 * O(mu 1e-5 T) in x and Newton, damped, took 8-30 iterations to move it).
 * from_below: (x0, y0) is below the section on the way up (a landing from
 * the left slow branch), and the first upward crossing ends it. */
static int turn_mesh(bkf_colloc *c, double x0, double y0, double T, double local_tol, int record, int from_below,
                     bkf_error *err)
{
    double size = fmin(1.0, 2.0 * sqrt(fmax(1.0 - c->nu * c->nu, 0.0)));
    double tol = local_tol * size;
    /* the stages to a small part of the local tolerance: the turn gives a
     * mesh and a start, which the global Newton corrects anyway */
    double goal = fmax(STAGE_GOAL, TURN_STAGE_GOAL * tol);
    /* the full step only measures the halves' error: what its Newton
     * leaves, of the square of its last correction, is then 1e-2 of the
     * local tolerance (one iteration from the halves' polynomials instead
     * of two) */
    double full_goal = fmax(goal, 0.1 * sqrt(tol));
    /* the first step: a unit of the fast time 1/mu, at most T/64 */
    double t = 0.0, h = fmin(T / 64.0, 1.0 / fmax(c->mu, 1.0)), xs = x0, ys = y0;
    size_t n = 0, n_prev = 0;
    double prev[M + 1], tau_prev = 1.0;
    /* the last accepted step and its error (floored at its rounding: an
     * error of 0 would make the prediction 0), for the predictive factor;
     * signal_acc: that error was above its rounding */
    double e_acc = 0.0, tau_acc = 1.0;
    int closed = 0, went_down = from_below, rejected = 0, signal_acc = 0;
    /* about what mu 1e4 needs, so that the arrays do not grow step by step
     * (their reallocation was 4% of a cold solve there) */
    if (record && !reserve(c, 640)) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    while (!closed) {
        double tau = h;
        double Xf[M], Xa[M], Xb[M], xf, yf, xa, ya, xb, yb;
        int ok = half_steps(c, xs, ys, tau, goal, n_prev ? prev : NULL, tau / tau_prev, Xa, Xb, &xa, &ya, &xb, &yb);
        if (ok) {
            /* the full step starts from the halves' polynomials, within
             * about the local error of its solution (the Euler line took
             * Newton several iterations more) */
            for (int i = 0; i < M; i++) {
                const double *l = c->g.halves[i];
                int first = c->g.c[i] < 0.5;
                double s = l[0] * (first ? xs : xa);
                for (int k = 0; k < M; k++) s += l[k + 1] * (first ? Xa : Xb)[k];
                Xf[i] = s;
            }
            ok = gauss_step(c, xs, ys, tau, full_goal, Xf, &xf, &yf);
        }
        double e = INFINITY, rho = 0.0;
        if (ok) {
            double mx;
            xf = end_value(&c->g, xs, Xf, &mx);
            e = fmax(fabs(xf - xb), fabs(yf - yb));
            rho = DBL_EPSILON * (mx + fabs(ys) + fabs(yf - ys));
        }
        /* the tolerance, floored at what the difference can resolve (at
         * tol 1e-14, nu 0.999 the local tolerance, 9e-16 x the cycle's
         * size, is below it) */
        double tol_step = fmax(tol, ROUND_SIGNAL * rho);
        if (!(e <= tol_step)) {
            h = tau * (ok ? fmax(TURN_SHRINK, 0.9 * pow(tol_step / e, 1.0 / (2 * M + 1))) : TURN_SHRINK);
            rejected = 1;
            if (!(h > 1e-14 * T))
                return bkf_error_set(err, BKF_ENUMERIC,
                                     "collocation at mu = %.15g, nu = %.15g: the guess's step underflows",
                                     c->mu, c->nu);
            continue;
        }
        if (xs > c->nu && xb <= c->nu) went_down = 1;
        if (went_down && xs < c->nu && xb >= c->nu) {
            /* the section inside this step: Newton on its length */
            double s = tau * (c->nu - xs) / (xb - xs);
            for (int it = 0; it < 20; it++) {
                if (!half_steps(c, xs, ys, s, goal, NULL, 1.0, Xa, Xb, &xa, &ya, &xb, &yb))
                    return bkf_error_set(err, BKF_ENUMERIC,
                                         "collocation at mu = %.15g, nu = %.15g: the guess's turn does not close",
                                         c->mu, c->nu);
                double xd = c->a * yb - c->mu * lienard_F(xb), ds = (c->nu - xb) / xd;
                if (!(xd > 0.0)) break;
                s = fmin(fmax(s + ds, 0.0), tau);
                if (fabs(ds) <= 1e-13 * (t + s)) break;
            }
            tau = s;
            closed = 1;
        }
        if (record && n + 2 > MAX_INTERVALS)
            return bkf_error_set(err, BKF_ETOL,
                                 "collocation at mu = %.15g, nu = %.15g: local tol %g needs more than %d intervals",
                                 c->mu, c->nu, local_tol, MAX_INTERVALS);
        if (!record) {
            /* (only the landing) */
        } else if (!reserve(c, n + 2)) {
            return bkf_error_set(err, BKF_ENOMEM, "out of memory");
        } else {
        c->t[n] = t;
        c->x[n] = xs;
        c->y[n] = ys;
        memcpy(c->X + n * M, Xa, sizeof Xa);
        c->t[n + 1] = t + 0.5 * tau;
        c->x[n + 1] = xa;
        c->y[n + 1] = ya;
        memcpy(c->X + (n + 1) * M, Xb, sizeof Xb);
        n += 2;
        }
        t += tau;
        prev[0] = xa;
        memcpy(prev + 1, Xb, sizeof Xb);
        n_prev = 1;
        tau_prev = tau;
        xs = xb;
        ys = yb;
        /* the prediction (tau / tau_acc) (e_acc / ee)^(1/(2m+1)) where it is
         * below 1, under the one root (pow was 4% of a cold solve) */
        int signal = e > ROUND_SIGNAL * rho;
        double ee = signal ? e : fmax(rho, 1e-6 * tol), r = 1.0;
        if (signal && signal_acc) {
            double q = tau / tau_acc, qn = 1.0;
            for (int k = 0; k < 2 * M + 1; k++) qn *= q;
            r = fmin(1.0, qn * e_acc / ee);
        }
        double factor = 0.9 * pow(tol_step / ee * r, 1.0 / (2 * M + 1));
        h = tau * fmin(rejected ? 1.0 : TURN_GROW_MAX, factor);
        e_acc = ee;
        signal_acc = signal;
        tau_acc = tau;
        rejected = 0;
        if (!closed && t > 4.0 * T)
            return bkf_error_set(err, BKF_ENUMERIC,
                                 "collocation at mu = %.15g, nu = %.15g: the guess's turn does not return to the "
                                 "section",
                                 c->mu, c->nu);
    }
    if (!record) {
        c->x[0] = xs;
        c->y[0] = ys;
        c->T = t;
        return BKF_OK;
    }
    for (size_t j = 0; j < n; j++) c->t[j] /= t;
    c->T = t;
    c->n = n;
    c->t[n] = 1.0;
    c->x[n] = c->x[0];
    c->y[n] = c->y[0];
    c->paired = 1;
    c->local_tol = local_tol;
    return BKF_OK;
}

int bkf_colloc_guess_turn(bkf_colloc *c, double mu, double nu, double x0, double y0, double T, double local_tol,
                          bkf_error *err)
{
    if (!c || !(T > 0.0) || !(local_tol > 0.0) || !isfinite(x0) || !isfinite(y0))
        return bkf_error_set(err, BKF_EINPUT, "collocation guess needs T > 0, local_tol > 0 and a finite start");
    set_params(c, mu, nu);
    c->have_guess = c->have_solution = 0;
    c->uniform = 0;
    if (!reserve(c, 1)) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    /* a first turn lands on the cycle: from a start off it by d the turn's
     * phase is off by about d mu and the jump by d mu^2, which Newton, damped,
     * moved in 8-13 iterations from a shot's 1e-5 at mu 300-1e4 */
    int rc = turn_mesh(c, x0, y0, T, local_tol, 0, 0, err);
    if (rc == BKF_OK) rc = turn_mesh(c, c->x[0], c->y[0], c->T, local_tol, 1, 0, err);
    if (rc == BKF_OK) c->have_guess = 1;
    return rc;
}

/* The landing's start on the left slow branch.  Only what happens from the
 * fold on reaches the section: the branch attracts like exp(-mu^2 times
 * the integral of (x^2 - 1)^2 / (nu - x) dx), about exp(-0.15 mu^2) from
 * here to the fold (15 at mu 10), and every orbit on the branch leaves the
 * fold along the same jump.  (A start nearer the fold saves little: at
 * -1.2, 40 of about 1200 Gauss steps at mu 1e3, and the pair's Newton
 * iterations varied more than that; the attraction at mu 10 would be
 * exp(-1).) */
#define LANDING_X (-1.5)

int bkf_colloc_guess_relaxation(bkf_colloc *c, double mu, double nu, double T, double local_tol, bkf_error *err)
{
    if (!c || !(mu >= 1.0) || !(fabs(nu) < 1.0) || !(T > 0.0) || !(local_tol > 0.0))
        return bkf_error_set(err, BKF_EINPUT,
                             "collocation guess needs mu >= 1, |nu| < 1, T > 0 and local_tol > 0");
    set_params(c, mu, nu);
    c->have_guess = c->have_solution = 0;
    if (!reserve(c, 1)) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    /* on the slow manifold to first order: x' = a (y - b F(x)) = y' / (b F'(x)) */
    double x0 = LANDING_X, y0 = c->b * lienard_F(x0) + (nu - x0) / (c->a * c->a * c->b * (x0 * x0 - 1.0));
    int rc = turn_mesh(c, x0, y0, T, local_tol, 0, 1, err);
    if (rc == BKF_OK) rc = turn_mesh(c, c->x[0], c->y[0], T, local_tol, 1, 0, err);
    if (rc == BKF_OK) c->have_guess = 1;
    return rc;
}

/* ------------------------------------------------- Lindstedt series */

/* u = f - nu in the time tau = omega z solves
 *     omega^2 u'' + mu omega (d/dtau) G(u) + u = 0,  G(u) = u^3/3 + nu u^2 - w u,
 * w = 1 - nu^2 (G' = (u + nu)^2 - 1).  With u = sum mu^k u_k, omega =
 * sum mu^k omega_k and u_0 = r sin tau, order k + 1 reads
 *     u_{k+1}'' + u_{k+1} = R_{k+1} = sum_{j=1}^{k+1} W_j u_{k+1-j}''
 *                                     - sum_{i=0}^{k} omega_i G_{k-i}',
 * W_j the mu^j coefficient of 1 - omega^2, G_j that of G(u).  Its cos tau
 * part vanishes for one amplitude correction B_k sin tau of u_k (it adds
 * -2 w B_k cos tau: the fundamental of G'(u_0) sin tau is 2 w sin tau),
 * which at k = 0 fixes r = 2 sqrt(w); its sin tau part for omega_{k+1}
 * (-2 omega_{k+1} u_0'' = 2 r omega_{k+1} sin tau).  The rest is solved
 * harmonic by harmonic, with u_{k+1}(0) = 0 (the phase x(0) = nu).
 * Products on a grid of SERIES_GRID points, harmonics by direct sums: u_k
 * has harmonics up to 2k + 1, G_k up to 2k + 3, below SERIES_GRID / 2 up
 * to SERIES_ORDER_MAX.  omega is even in mu (mu -> -mu, tau -> -tau). */
#define SERIES_ORDER_MAX 12
#define SERIES_GRID 64
#define SERIES_HARM (2 * SERIES_ORDER_MAX + 3)

typedef struct {
    double omega;                /* sum of the orders kept */
    double ca[SERIES_HARM + 1];  /* u = sum ca_n cos n tau + sb_n sin n tau */
    double sb[SERIES_HARM + 1];
    int harmonics, order;        /* highest harmonic, highest order kept */
    double residual;             /* the last term kept over the radius */
    double omega_k[SERIES_ORDER_MAX + 1];
} lindstedt_series;

/* DFT of v on the grid of P points: cos and sin coefficients up to
 * harmonic h, from the tables cm[n][p] = cos(2 pi n p / P), sm likewise
 * (dense rows: the loops vectorise). */
typedef double series_row[SERIES_GRID];
static void series_dft(int P, const series_row *cm, const series_row *sm, const double *v, int h, double *a,
                       double *b)
{
    for (int n = 0; n <= h; n++) {
        double sa = 0.0, sbv = 0.0;
        for (int p = 0; p < P; p++) {
            sa += v[p] * cm[n][p];
            sbv += v[p] * sm[n][p];
        }
        a[n] = (n ? 2.0 : 1.0) * sa / P;
        b[n] = n ? 2.0 * sbv / P : 0.0;
    }
}

static void series_grid(int P, const series_row *cm, const series_row *sm, const double *a, const double *b, int h,
                        double *v)
{
    for (int p = 0; p < P; p++) v[p] = a[0];
    for (int n = 1; n <= h; n++)
        for (int p = 0; p < P; p++) v[p] += a[n] * cm[n][p] + b[n] * sm[n][p];
}

/* The series to `order` (at most SERIES_ORDER_MAX), or fewer where its
 * terms stop shrinking (it converges for mu below a radius of order 1,
 * smaller at |nu| ~ 0.5: truncated at its smallest term).  residual: the
 * last term kept, relative to the cycle's radius (the size of what is
 * left out, where the terms shrink geometrically). */
static void lindstedt(double mu, double nu, int order, lindstedt_series *out)
{
    enum { PMAX = SERIES_GRID, K = SERIES_ORDER_MAX, H = SERIES_HARM };
    if (!(mu > 0.0)) order = 0;
    if (order > K) order = K;
    /* the grid resolves G_{order-1}'s harmonics, up to 2 order + 1, without
     * aliasing: P > 2 (2 order + 1) */
    int P = 8;
    while (P <= 2 * (2 * order + 1)) P *= 2;
    double ct[PMAX], st[PMAX];
    series_row cm[H + 1], sm[H + 1];
    for (int p = 0; p < P; p++) {
        ct[p] = cos(2.0 * M_PI * p / P);
        st[p] = sin(2.0 * M_PI * p / P);
    }
    for (int n = 0; n <= 2 * order + 1 && n <= H; n++)
        for (int p = 0, q = 0; p < P; p++, q = (q + n) & (P - 1)) {
            cm[n][p] = ct[q];
            sm[n][p] = st[q];
        }
    const double w = 1.0 - nu * nu, r = 2.0 * sqrt(w);
    static const double zero[H + 1];
    double ua[K + 1][H + 1], ub[K + 1][H + 1], ga[K + 1][H + 1], gb[K + 1][H + 1];
    double u[K + 1][PMAX], sq[K + 1][PMAX], om[K + 1], W[K + 2];
    memset(ua, 0, sizeof ua);
    memset(ub, 0, sizeof ub);
    memset(out, 0, sizeof *out);
    ub[0][1] = r;
    om[0] = 1.0;
    /* the mu^k coefficient of G(u) on the grid, its harmonics into ga, gb */
#define SERIES_G(k)                                                                         \
    do {                                                                                    \
        series_grid(P, cm, sm, ua[k], ub[k], 2 * (k) + 1, u[k]);                            \
        double gv[PMAX];                                                                     \
        for (int p = 0; p < P; p++) {                                                       \
            double s2 = 0.0, s3 = 0.0;                                                      \
            for (int i = 0; i <= (k); i++) s2 += u[i][p] * u[(k) - i][p];                   \
            sq[k][p] = s2;                                                                  \
            for (int i = 0; i <= (k); i++) s3 += u[i][p] * sq[(k) - i][p];                  \
            gv[p] = s3 / 3.0 + nu * s2 - w * u[k][p];                                       \
        }                                                                                   \
        series_dft(P, cm, sm, gv, 2 * (k) + 3, ga[k], gb[k]);                               \
    } while (0)
    SERIES_G(0);
    double sum_a[H + 1] = {0}, sum_b[H + 1] = {0}, omega = 1.0, scale = r, last = r;
    memcpy(sum_b, ub[0], sizeof sum_b);
    int kept = 0;
    for (int k = 0; k < order; k++) {
        double ra[H + 1], rb[H + 1];
        int h = 2 * k + 3;
        for (int pass = 0; pass < 2; pass++) {
            /* W_j = -(sum_{i=0}^{j} omega_i omega_{j-i}), omega_{k+1} not yet known */
            for (int j = 1; j <= k + 1; j++) {
                double s = 0.0;
                for (int i = 1; i < j; i++) s += om[i] * om[j - i];
                W[j] = -(s + (j <= k ? 2.0 * om[j] : 0.0));
            }
            for (int n = 0; n <= h; n++) {
                double sa = 0.0, sbv = 0.0;
                for (int j = 1; j <= k + 1; j++) {
                    const double *pa = n <= 2 * (k + 1 - j) + 1 ? ua[k + 1 - j] : zero;
                    const double *pb = n <= 2 * (k + 1 - j) + 1 ? ub[k + 1 - j] : zero;
                    sa -= W[j] * n * n * pa[n];
                    sbv -= W[j] * n * n * pb[n];
                }
                for (int i = 0; i <= k; i++) {
                    if (n > 2 * (k - i) + 3) continue;
                    sa -= om[i] * n * gb[k - i][n];
                    sbv += om[i] * n * ga[k - i][n];
                }
                ra[n] = sa;
                rb[n] = sbv;
            }
            if (pass || k == 0) break;
            /* the amplitude correction B sin tau of u_k, and what it adds
             * to G_k: G'(u_0) B sin tau = B (2 w sin tau - w sin 3 tau +
             * nu r - nu r cos 2 tau) (r^2 = 4 w), to (u^2)_k 2 u_0 B sin tau */
            double B = ra[1] / (2.0 * w);
            ub[k][1] += B;
            sum_b[1] += pow(mu, k) * B;
            ga[k][0] += B * nu * r;
            ga[k][2] -= B * nu * r;
            gb[k][1] += 2.0 * B * w;
            gb[k][3] -= B * w;
            for (int p = 0, q = 0; p < P; p++, q = (q + 1) & (P - 1)) {
                u[k][p] += B * st[q];
                sq[k][p] += 2.0 * B * st[q] * u[0][p];
            }
        }
        om[k + 1] = -rb[1] / (2.0 * r);
        ua[k + 1][0] = ra[0];
        double phase = ra[0];
        for (int n = 2; n <= h; n++) {
            ua[k + 1][n] = ra[n] / (1.0 - n * n);
            ub[k + 1][n] = rb[n] / (1.0 - n * n);
            phase += ua[k + 1][n];
        }
        ua[k + 1][1] = -phase;
        ub[k + 1][1] = 0.0;
        if (k + 1 < order) SERIES_G(k + 1);
        /* the size of the term mu^(k+1) u_{k+1} */
        double mk = pow(mu, k + 1), size = 0.0;
        for (int n = 0; n <= h; n++) size += fabs(ua[k + 1][n]) + fabs(ub[k + 1][n]);
        size *= mk;
        if (size > last) break; /* diverging: keep up to the smallest term */
        for (int n = 0; n <= h; n++) {
            sum_a[n] += mk * ua[k + 1][n];
            sum_b[n] += mk * ub[k + 1][n];
        }
        omega += mk * om[k + 1];
        kept = k + 1;
        out->harmonics = h;
        last = size;
    }
#undef SERIES_G
    /* the amplitude correction of the last order kept is the next order's
     * (B_kept, unknown): it is part of the truncation error */
    memcpy(out->ca, sum_a, sizeof sum_a);
    memcpy(out->sb, sum_b, sizeof sum_b);
    memcpy(out->omega_k, om, sizeof(double) * (size_t)(kept + 1));
    if (!kept) out->harmonics = 1;
    out->omega = omega;
    out->order = kept;
    out->residual = kept ? last / scale : 1.0;
}

double bkf_colloc_series_period(double mu, double nu, int order)
{
    if (!(mu >= 0.0) || !isfinite(mu) || !(fabs(nu) < 1.0) || order < 0) return NAN;
    lindstedt_series s;
    lindstedt(mu, nu, order, &s);
    return 2.0 * M_PI / s.omega;
}

/* u and du/dtau of the series at the angle whose cosine and sine are
 * (c1, s1). */
static void series_eval(const lindstedt_series *s, double c1, double s1, double *u, double *du)
{
    double cn = 1.0, sn = 0.0, v = s->ca[0], d = 0.0;
    for (int n = 1; n <= s->harmonics; n++) {
        double c2 = cn * c1 - sn * s1;
        sn = sn * c1 + cn * s1;
        cn = c2;
        v += s->ca[n] * cn + s->sb[n] * sn;
        d += n * (s->sb[n] * cn - s->ca[n] * sn);
    }
    *u = v;
    *du = d;
}

/* The series order past which Newton's iterations no longer fall: the
 * fewest interval solves of a cold solve at tol 1e-10 (nu 0, -0.5, -0.96,
 * 0.99) came from order 2 up to mu 0.1, 4 at 0.2-0.3, 6 at 0.5-1 (8 at
 * mu 0.7 saved one iteration at nu -0.5 but doubles the grid). */
static int series_order(double mu)
{
    int k = 2;
    while (k < 6 && pow(mu, k) > 0.02) k += 2;
    return k;
}

int bkf_colloc_guess_series(bkf_colloc *c, double mu, double nu, int order, size_t intervals, double *residual,
                            bkf_error *err)
{
    if (!c || intervals < 4 || intervals > MAX_INTERVALS || order < 0 || !(mu > 0.0) || !(fabs(nu) < 1.0))
        return bkf_error_set(err, BKF_EINPUT,
                             "collocation series guess needs mu > 0, |nu| < 1, order >= 0 and intervals in [4, %d]",
                             MAX_INTERVALS);
    if (!reserve(c, intervals)) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    set_params(c, mu, nu);
    lindstedt_series s;
    lindstedt(mu, nu, order ? order : series_order(mu), &s);
    if (residual) *residual = s.residual;
    c->n = intervals;
    c->T = 2.0 * M_PI / s.omega;
    /* the points 2 pi (j + theta) / n by rotations of 2 pi / n from theta */
    const double step = 2.0 * M_PI / (double)intervals, cs = cos(step), ss = sin(step);
    for (int k = 0; k <= M; k++) {
        double theta = k ? c->g.c[k - 1] : 0.0, ck = cos(step * theta), sk = sin(step * theta);
        for (size_t j = 0; j < intervals + (k == 0); j++) {
            double u, du;
            series_eval(&s, ck, sk, &u, &du);
            if (k) {
                c->X[j * M + k - 1] = nu + u;
            } else {
                c->t[j] = (double)j / (double)intervals;
                c->x[j] = nu + u;
                c->y[j] = s.omega * du / c->a + c->b * lienard_F(nu + u);
            }
            double c2 = ck * cs - sk * ss;
            sk = sk * cs + ck * ss;
            ck = c2;
        }
    }
    c->t[intervals] = 1.0;
    c->have_guess = 1;
    c->have_solution = 0;
    c->paired = 0;
    c->uniform = 1;
    return BKF_OK;
}

int bkf_colloc_warm(bkf_colloc *c, double mu, double nu)
{
    if (!c || !c->have_solution) return 0;
    c->paired = 0;
    c->uniform = 0;
    double a0 = c->a, b0 = c->b;
    set_params(c, mu, nu);
    /* same f and f' = a (y - b F(x)) in the new scaling */
    for (size_t j = 0; j <= c->n; j++) {
        double fp = a0 * (c->y[j] - b0 * lienard_F(c->x[j]));
        c->y[j] = fp / c->a + c->b * lienard_F(c->x[j]);
    }
    c->have_guess = 1;
    return 1;
}

/* -------------------------------------------------------------- solve */

static int converge(bkf_colloc *c, double tol, bkf_error *err)
{
    return newton(c, 0.01 * sqrt(tol), err);
}

int bkf_colloc_fixed(bkf_colloc *c, size_t intervals, double *period, bkf_error *err)
{
    if (!c || !c->have_guess) return bkf_error_set(err, BKF_EINPUT, "collocation solve before a guess");
    if (intervals < 4 || intervals > MAX_INTERVALS)
        return bkf_error_set(err, BKF_EINPUT, "intervals = %zu is outside [4, %d]", intervals, MAX_INTERVALS);
    int rc = newton(c, 1e-6, err);
    for (int pass = 0; rc == BKF_OK && pass < 2; pass++) {
        rc = equidistribute(c, intervals);
        if (rc == BKF_ENOMEM) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
        rc = newton(c, pass ? 1e-13 : 1e-8, err);
    }
    if (rc != BKF_OK) return rc;
    c->have_solution = 1;
    *period = c->T;
    return BKF_OK;
}

/* The rounding floor of T's estimate: mesh values rounded at eps of the
 * state (|x| up to 2) are relative perturbations eps / size of a cycle of
 * size 2 sqrt(1 - nu^2) (mu 10, nu -0.9999, tol 1e-12: true 1.5e-13
 * against a floor of 3e-14 without the 1 / size). */
static double round_floor(const bkf_colloc *c, double T)
{
    double size = fmin(1.0, 2.0 * sqrt(fmax(1.0 - c->nu * c->nu, 0.0)));
    return 8.0 * DBL_EPSILON * T * sqrt((double)c->n) / size;
}

/* Keep (which = 0) or restore (1) the current solution. */
static int keep_solution(bkf_colloc *c, int which, size_t *n, double *T, double *trace)
{
    if (!which) {
        size_t need = (3 + M) * (c->n + 1);
        if (need > c->keep_cap) {
            if (!grow(&c->keep, need)) return BKF_ENOMEM;
            c->keep_cap = need;
        }
        *n = c->n;
        *T = c->T;
        *trace = c->trace;
    } else if (!reserve(c, *n)) {
        return BKF_ENOMEM;
    }
    size_t k = *n + 1;
    double *kt = c->keep, *kx = kt + k, *ky = kx + k, *kX = ky + k;
    if (!which) {
        memcpy(kt, c->t, k * sizeof *kt);
        memcpy(kx, c->x, k * sizeof *kx);
        memcpy(ky, c->y, k * sizeof *ky);
        memcpy(kX, c->X, *n * M * sizeof *kX);
    } else {
        memcpy(c->t, kt, k * sizeof *kt);
        memcpy(c->x, kx, k * sizeof *kx);
        memcpy(c->y, ky, k * sizeof *ky);
        memcpy(c->X, kX, *n * M * sizeof *kX);
        c->n = *n;
        c->T = *T;
        c->trace = *trace;
    }
    return BKF_OK;
}

/* Merge the mesh's interval pairs: the merged interval's stages are its
 * halves' polynomials at its Gauss points (fixed Lagrange weights,
 * gauss_table.halves), the mesh values kept.  remesh_to evaluated the
 * basis at each point and re-solved each merged interval by a Gauss step
 * (7-10% of a cold solve at mu 30-1e4); without the Gauss step the
 * coarser Newton took as many iterations (mu 30-1e4, nu 0, -0.96, 0.99,
 * 0.999, tol 1e-10: 3.8% fewer instructions over the 16 points, none more
 * than 1% more), its first correction being the shift of the jumps that
 * the coarser T brings (1e-3 at mu 1e4). */
static void coarsen(bkf_colloc *c)
{
    const gauss_table *g = &c->g;
    size_t n = c->n / 2;
    for (size_t k = 0; k < n; k++) {
        double X[M];
        for (int i = 0; i < M; i++) {
            const double *l = g->halves[i];
            size_t j = 2 * k + (g->c[i] < 0.5 ? 0 : 1);
            double s = l[0] * c->x[j];
            for (int q = 0; q < M; q++) s += l[q + 1] * c->X[j * M + q];
            X[i] = s;
        }
        /* in place: index k was read at k / 2, before this write */
        c->t[k] = c->t[2 * k];
        c->x[k] = c->x[2 * k];
        c->y[k] = c->y[2 * k];
        memcpy(c->X + k * M, X, sizeof X);
    }
    c->n = n;
    c->t[n] = 1.0;
    c->x[n] = c->x[0];
    c->y[n] = c->y[0];
}

/* The solution on c's mesh into *out: T with its estimate est, the log
 * multiplier L with the pair's other value L_other (divided as T's
 * difference is: divisor) and its rounding. */
static void fill_result(bkf_colloc *c, double est, double L, double L_other, double divisor,
                        bkf_colloc_result *out)
{
    out->period = c->T;
    out->period_err = est;
    out->log_multiplier = L;
    out->log_multiplier_err = fabs(L - L_other) / divisor + 8.0 * DBL_EPSILON * sqrt((double)c->n) * fabs(L);
    out->return_map_slope = c->trace - 1.0;
    out->section_y = c->y[0];
    out->intervals = c->n;
    out->newton_iterations = c->iterations;
    out->interval_solves = c->solves;
    c->have_solution = 1;
}

/* The solve from a mesh of half-step pairs (bkf_colloc_guess_turn): Newton
 * on it, then on its coarsening (merged pairs: half the intervals, started
 * from the converged finer solution), the finer T reported with
 * |T_N - T_N/2| / EST_DIVISOR.  A mesh that does not meet tol is built
 * again by a turn from the converged solution at the local tolerance the
 * pair predicts; no equidistribution (from the shot's mesh at mu 1e3 it gave
 * the mesh to spurious derivative spikes on long intervals and Newton
 * stalled). */
static int solve_paired(bkf_colloc *c, double tol, bkf_colloc_result *out, bkf_error *err)
{
    for (int round = 0; round < 5; round++) {
        int rc = newton(c, PAIRED_GOAL * sqrt(tol), err);
        if (rc != BKF_OK) return rc;
        double T1 = c->T, L1 = log_multiplier(c), Tk, trace;
        size_t nk;
        if (keep_solution(c, 0, &nk, &Tk, &trace) != BKF_OK) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
        coarsen(c);
        rc = newton(c, PAIRED_GOAL * sqrt(tol), err);
        double T2 = c->T, L2 = log_multiplier(c);
        if (keep_solution(c, 1, &nk, &Tk, &trace) != BKF_OK) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
        if (rc != BKF_OK) return rc;
        double diff = fabs(T1 - T2);
        /* the coarser Newton starts from the finer solution, so the pair
         * shares what Newton leaves (of the square of its goal): at mu 1e4,
         * nu 0.99, tol 1e-6 the pair agreed to 1e-12 against a true 6e-11 */
        double newton_left = PAIRED_GOAL * PAIRED_GOAL * tol * T1;
        double est = fmax(fmax(diff / PAIRED_DIVISOR, round_floor(c, T1)), TURN_FLOOR * c->local_tol * T1) +
                     newton_left;
        if (ACCEPT_MARGIN * est <= tol * T1) {
            fill_result(c, est, L1, L2, PAIRED_DIVISOR, out);
            c->pair_n = c->n / 2;
            c->paired = 0;
            return BKF_OK;
        }
        /* the error falls like the local tolerance^(2m/(2m+1)): the local
         * tolerance whose pair meets tol, with a margin of 2 */
        double need = diff * 2.0 * ACCEPT_MARGIN / (PAIRED_DIVISOR * tol * T1);
        double local = c->local_tol * pow(fmax(need, 1.5), -(2.0 * M + 1.0) / (2.0 * M));
        rc = turn_mesh(c, c->x[0], c->y[0], c->T, local, 1, 0, err);
        if (rc != BKF_OK) return rc;
    }
    return bkf_error_set(err, BKF_ETOL, "collocation at mu = %.15g, nu = %.15g: estimate did not meet tol = %g",
                         c->mu, c->nu, tol);
}

/* The error of T_N falls like N^-2m: the N whose pair meets tol, with a
 * margin of 2 (0 and err set where that exceeds the budget). */
static size_t next_intervals(const bkf_colloc *c, size_t n, double diff, double tol, double T, bkf_error *err)
{
    double need = diff * 2.0 * ACCEPT_MARGIN / (EST_DIVISOR * tol * T);
    double grow_by = pow(fmax(need, 1.0), 1.0 / (2 * M));
    size_t next = (size_t)ceil((double)n * fmax(grow_by, 1.25));
    if (2 * next > MAX_INTERVALS) {
        bkf_error_set(err, BKF_ETOL, "collocation at mu = %.15g, nu = %.15g: tol = %g needs more than %d intervals",
                      c->mu, c->nu, tol, MAX_INTERVALS);
        return 0;
    }
    return next;
}

/* The pair (T1 on a mesh of n intervals, T2 on its bisection) judged: T2
 * with |T1 - T2| / EST_DIVISOR (or the rounding floor) into *out if that
 * meets tol with the margin. */
static int pair_meets_tol(bkf_colloc *c, double T1, double L1, double T2, double L2, size_t n, double tol,
                          bkf_colloc_result *out)
{
    double est = fmax(fabs(T1 - T2) / EST_DIVISOR, round_floor(c, T2));
    if (!(ACCEPT_MARGIN * est <= tol * T2)) return 0;
    fill_result(c, est, L2, L1, EST_DIVISOR, out);
    c->pair_n = n;
    return 1;
}

/* From the converged mesh of n intervals: equidistributed meshes of n
 * (growing) intervals and their bisections until the pair meets tol. */
static int solve_equidistributed(bkf_colloc *c, double tol, size_t n, bkf_colloc_result *out, bkf_error *err)
{
    int rc;
    for (int round = 0; round < 5; round++) {
        rc = equidistribute(c, n);
        if (rc == BKF_OK) rc = converge(c, tol, err);
        if (rc == BKF_ENOMEM) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
        if (rc != BKF_OK) return rc;
        double T1 = c->T, L1 = log_multiplier(c);
        rc = bisect(c);
        if (rc == BKF_OK) rc = converge(c, tol, err);
        if (rc == BKF_ENOMEM) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
        if (rc != BKF_OK) return rc;
        double T2 = c->T, L2 = log_multiplier(c);
        double diff = fabs(T1 - T2);
        if (pair_meets_tol(c, T1, L1, T2, L2, n, tol, out)) return BKF_OK;
        size_t next = next_intervals(c, n, diff, tol, T2, err);
        if (!next) return BKF_ETOL;
        n = next;
    }
    return bkf_error_set(err, BKF_ETOL, "collocation at mu = %.15g, nu = %.15g: estimate did not meet tol = %g",
                         c->mu, c->nu, tol);
}

/* Bisect a mesh of a smooth cycle from its own polynomials (no Gauss steps
 * as remesh_to takes: those are for fast layers, which a cycle at small mu
 * has none of; the finer Newton corrects the polynomials' stage-order
 * error in two iterations). */
static int bisect_smooth(bkf_colloc *c)
{
    const size_t n = c->n;
    if (!reserve_scratch(c, 2 * n)) return BKF_ENOMEM;
    double lm[M + 1], la[M][M + 1], lb[M][M + 1];
    lagrange_weights(c->g.c, 0.5, lm);
    for (int i = 0; i < M; i++) {
        lagrange_weights(c->g.c, 0.5 * c->g.c[i], la[i]);
        lagrange_weights(c->g.c, 0.5 * (1.0 + c->g.c[i]), lb[i]);
    }
    for (size_t j = 0; j < n; j++) {
        const double *X = c->X + j * M;
        double Y[M], xm = lm[0] * c->x[j], ym = lm[0] * c->y[j];
        stage_y(c, j, Y);
        for (int k = 0; k < M; k++) {
            xm += lm[k + 1] * X[k];
            ym += lm[k + 1] * Y[k];
        }
        c->ts[2 * j] = c->t[j];
        c->ts[2 * j + 1] = 0.5 * (c->t[j] + c->t[j + 1]);
        c->xs[2 * j] = c->x[j];
        c->ys[2 * j] = c->y[j];
        c->xs[2 * j + 1] = xm;
        c->ys[2 * j + 1] = ym;
        for (int i = 0; i < M; i++) {
            double sa = la[i][0] * c->x[j], sb = lb[i][0] * c->x[j];
            for (int k = 0; k < M; k++) {
                sa += la[i][k + 1] * X[k];
                sb += lb[i][k + 1] * X[k];
            }
            c->Xs[2 * j * M + i] = sa;
            c->Xs[(2 * j + 1) * M + i] = sb;
        }
    }
    if (!reserve(c, 2 * n)) return BKF_ENOMEM;
    memcpy(c->t, c->ts, 2 * n * sizeof *c->t);
    memcpy(c->x, c->xs, 2 * n * sizeof *c->x);
    memcpy(c->y, c->ys, 2 * n * sizeof *c->y);
    memcpy(c->X, c->Xs, 2 * n * M * sizeof *c->X);
    c->n = 2 * n;
    c->t[c->n] = 1.0;
    c->x[c->n] = c->x[0];
    c->y[c->n] = c->y[0];
    return BKF_OK;
}

/* The solve from a series guess (bkf_colloc_guess_series): Newton on its
 * uniform mesh, then on the bisection started from the polynomials; where
 * the pair misses tol, the equidistributed rounds go on from there at the
 * predicted size. */
static int solve_uniform(bkf_colloc *c, double tol, bkf_colloc_result *out, bkf_error *err)
{
    c->uniform = 0;
    int rc = converge(c, tol, err);
    if (rc != BKF_OK) return rc;
    size_t n = c->n;
    double T1 = c->T, L1 = log_multiplier(c);
    if (bisect_smooth(c) != BKF_OK) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    rc = converge(c, tol, err);
    if (rc != BKF_OK) return rc;
    double T2 = c->T, L2 = log_multiplier(c);
    double diff = fabs(T1 - T2);
    if (pair_meets_tol(c, T1, L1, T2, L2, n, tol, out)) return BKF_OK;
    /* finer meshes only raise the rounding floor (mu 1e-3, nu 0.9999,
     * tol 1e-12: the rounds went on to 40000 intervals, 7.8M instructions,
     * before refusing) */
    if (ACCEPT_MARGIN * round_floor(c, T2) > tol * T2)
        return bkf_error_set(err, BKF_ETOL,
                             "collocation at mu = %.15g, nu = %.15g: its rounding floor %.2g exceeds tol = %g / %g",
                             c->mu, c->nu, round_floor(c, T2) / T2, tol, ACCEPT_MARGIN);
    size_t next = next_intervals(c, n, diff, tol, T2, err);
    return next ? solve_equidistributed(c, tol, next, out, err) : BKF_ETOL;
}

int bkf_colloc_solve(bkf_colloc *c, double tol, bkf_colloc_result *out, bkf_error *err)
{
    if (!c || !c->have_guess) return bkf_error_set(err, BKF_EINPUT, "collocation solve before a guess");
    c->iterations = c->solves = 0;
    int warm = c->have_solution;
    c->have_solution = 0;
    if (c->paired && !warm) return solve_paired(c, tol, out, err);
    if (c->uniform && !warm) return solve_uniform(c, tol, out, err);
    int rc = converge(c, fmax(tol, 1e-6), err);
    if (rc != BKF_OK) return rc;
    /* a warm start's mesh is the last finer one: the pair starts again from
     * the coarser, or each warm solve would double it */
    size_t n = warm && c->pair_n ? c->pair_n : c->n;
    if (n < MIN_INTERVALS) n = MIN_INTERVALS;
    return solve_equidistributed(c, tol, n, out, err);
}

/* x' = a (y - b F(x)) at (x, y); its time derivative where x' = g is
 * x'' = (nu - x) - mu (x^2 - 1) g. */
static double colloc_xdot(const bkf_colloc *c, double x, double y) { return c->a * (y - c->b * lienard_F(x)); }

/* The zero of x' on interval j's polynomial, between its ends where x'
 * is d0 and d1 of opposite signs (Illinois regula falsi): theta in
 * [0, 1].  The polynomial is of stage order only, so this starts the
 * Gauss steps' Newton below, which is then within its quadratic range
 * (from the linear interpolation of the ends' x', far off in a fast layer
 * where x' falls by e^-3 each 1/mu, it crept along a 1/mu per iteration
 * and did not converge in 20 at mu 300-1e4). */
static double poly_xdot_zero(const bkf_colloc *c, size_t j, double d0, double d1)
{
    double lo = 0.0, hi = 1.0, glo = d0, ghi = d1, theta = 0.5;
    int side = 0;
    for (int it = 0; it < 60 && hi - lo > 1e-12; it++) {
        theta = (lo * ghi - hi * glo) / (ghi - glo);
        if (!(theta > lo && theta < hi)) theta = 0.5 * (lo + hi);
        double xv, yv;
        poly_eval(c, j, theta, &xv, &yv);
        double g = colloc_xdot(c, xv, yv);
        if (g == 0.0) return theta;
        if ((g > 0) == (glo > 0)) {
            lo = theta;
            glo = g;
            if (side == -1) ghi *= 0.5;
            side = -1;
        } else {
            hi = theta;
            ghi = g;
            if (side == 1) glo *= 0.5;
            side = 1;
        }
    }
    return theta;
}

/* Where x at the Gauss step's end is within this of the extremum (second
 * order in the step length's error s - s*: 0.5 |x''| (s - s*)^2), the step
 * is taken as located: below the end values' own error. */
#define EXTREMUM_X_GOAL 1e-15
#define EXTREMUM_X_STALL 1e-10
/* A sign change of x' where no zero is located is left out where the
 * interval's x (its ends and the last step's end) stays inside the
 * extremes found elsewhere by this fraction of their range: on a slow
 * branch at mu 1e4 the mesh values' off-manifold error, within the local
 * tolerance, moves x' = a (y - b F(x)) by mu F'(x) times it (4e-9 x 1.4e4),
 * more than x' itself (-4e-5 at x 1.55, nu 0.99), and x' changes sign
 * between mesh points 600 long where x has no extremum; the extremes
 * themselves lie at the ends of the jumps, on intervals of 1e-4. */
#define EXTREMUM_STRAY_MARGIN 1e-3

int bkf_colloc_extremes(const bkf_colloc *c, double *xmax, double *xmin, bkf_error *err)
{
    if (!c || !c->have_solution) return bkf_error_set(err, BKF_EINPUT, "collocation extremes before a solution");
    double hi = c->nu, lo = c->nu, stray_hi = -INFINITY, stray_lo = INFINITY;
    for (size_t j = 0; j < c->n; j++) {
        double d0 = colloc_xdot(c, c->x[j], c->y[j]), d1 = colloc_xdot(c, c->x[j + 1], c->y[j + 1]);
        if ((d0 > 0) == (d1 > 0)) continue;
        /* Newton on the length s of a Gauss step from mesh point j whose
         * end has x' = 0 (the end values are superconvergent, order 2m),
         * from the polynomial's zero, kept in the bracket of x''s sign
         * change by bisection */
        double tau = (c->t[j + 1] - c->t[j]) * c->T;
        double s = tau * poly_xdot_zero(c, j, d0, d1), xe = c->x[j], ye, X[M], unused, last = INFINITY;
        /* from the nearer end (backwards from j + 1 past the middle): less
         * of a partial step's error in the stiff direction */
        int back = s > 0.5 * tau;
        size_t k = back ? j + 1 : j;
        int located = 0;
        for (int it = 0; it < 20 && !located; it++) {
            double len = back ? s - tau : s;
            for (int i = 0; i < M; i++) poly_eval(c, j, (double)back + c->g.c[i] * len / tau, &X[i], &unused);
            if (!guarded_step(c, c->x[k], c->y[k], len, STAGE_GOAL, 1, X, &xe, &ye)) break;
            double g = colloc_xdot(c, xe, ye), gp = (c->nu - xe) - c->mu * (xe * xe - 1.0) * g;
            double ds = gp != 0.0 ? -g / gp : INFINITY, off = 0.5 * fabs(gp) * ds * ds;
            located = g == 0.0 || off <= EXTREMUM_X_GOAL * (1.0 + fabs(xe)) ||
                      (fabs(ds) > 0.5 * last && off <= EXTREMUM_X_STALL);
            last = fabs(ds);
            s = fmin(fmax(s + ds, 0.0), tau);
        }
        if (!located) {
            stray_hi = fmax(stray_hi, fmax(fmax(c->x[j], c->x[j + 1]), xe));
            stray_lo = fmin(stray_lo, fmin(fmin(c->x[j], c->x[j + 1]), xe));
            continue;
        }
        hi = fmax(hi, xe);
        lo = fmin(lo, xe);
    }
    double margin = EXTREMUM_STRAY_MARGIN * (hi - lo);
    if (stray_hi > hi - margin || stray_lo < lo + margin)
        return bkf_error_set(err, BKF_ENUMERIC, "collocation at mu = %.15g, nu = %.15g: extremum not located", c->mu,
                             c->nu);
    *xmax = hi;
    *xmin = lo;
    return BKF_OK;
}

size_t bkf_colloc_nodes(const bkf_colloc *c, double *z, double *x, double *y, size_t capacity)
{
    if (!c || !(c->have_solution || c->have_guess)) return 0;
    for (size_t j = 0; j < c->n && j < capacity; j++) {
        if (z) z[j] = c->t[j] * c->T;
        if (x) x[j] = c->x[j];
        if (y) y[j] = c->y[j];
    }
    return c->n;
}

/* ------------------------------------------------------- continuation */

/* A path keeps the last two rows of a branch on meshes of the same number
 * of intervals, each a bisection (the pair's finer mesh) of a mesh
 * equidistributed for its row or predicted from two such: mesh index j is
 * then the same feature of the cycle in both (equidistribution moves the
 * points smoothly with the parameter), so the mesh and the solution are
 * predicted per index, as functions of the parameter. */
typedef struct {
    size_t n;
    double mu, nu, lnT;
    double *t, *x, *w, *X; /* w = f' at the mesh points: free of the scaling a, b */
} path_row;

struct bkf_colloc_path {
    path_row row[2]; /* row[1] the newest */
    int rows;
    size_t cap;
    /* |T_N - T_N/2| / T of the newest row on this mesh (0: none) */
    double last_diff;
};

bkf_colloc_path *bkf_colloc_path_alloc(void) { return calloc(1, sizeof(bkf_colloc_path)); }

void bkf_colloc_path_free(bkf_colloc_path *path)
{
    if (!path) return;
    for (int k = 0; k < 2; k++) {
        free(path->row[k].t);
        free(path->row[k].x);
        free(path->row[k].w);
        free(path->row[k].X);
    }
    free(path);
}

static int path_append(bkf_colloc_path *path, const bkf_colloc *c);

static int path_reserve(bkf_colloc_path *path, size_t n)
{
    if (n <= path->cap) return 1;
    size_t cap = n + n / 2 + 16;
    for (int k = 0; k < 2; k++) {
        path_row *r = &path->row[k];
        if (!grow(&r->t, cap + 1) || !grow(&r->x, cap + 1) || !grow(&r->w, cap + 1) || !grow(&r->X, cap * M))
            return 0;
    }
    path->cap = cap;
    return 1;
}

int bkf_colloc_path_push(bkf_colloc_path *path, const bkf_colloc *c)
{
    if (!path || !c || !c->have_solution || c->n % 2) return BKF_EINPUT;
    /* another solve's mesh is not index by index the newest row's (two
     * turns' meshes of as many intervals put them elsewhere: a secant
     * through both took Newton 12 iterations at mu 10 along nu) */
    path->rows = 0;
    path->last_diff = 0.0;
    return path_append(path, c);
}

static int path_append(bkf_colloc_path *path, const bkf_colloc *c)
{
    if (!path_reserve(path, c->n)) return BKF_ENOMEM;
    /* a row at the newest one's parameters replaces it (a secant needs two);
     * one on another number of intervals starts the path again */
    int same = path->rows && path->row[1].mu == c->mu && path->row[1].nu == c->nu;
    if (path->rows && !same && path->row[1].n == c->n) {
        path_row t = path->row[0];
        path->row[0] = path->row[1];
        path->row[1] = t;
        path->rows = 2;
    } else if (!same || path->row[1].n != c->n) {
        path->rows = 1;
    }
    path_row *r = &path->row[1];
    r->n = c->n;
    r->mu = c->mu;
    r->nu = c->nu;
    r->lnT = log(c->T);
    memcpy(r->t, c->t, (c->n + 1) * sizeof *r->t);
    memcpy(r->x, c->x, c->n * sizeof *r->x);
    memcpy(r->X, c->X, c->n * M * sizeof *r->X);
    for (size_t j = 0; j < c->n; j++) r->w[j] = c->a * (c->y[j] - c->b * lienard_F(c->x[j]));
    return BKF_OK;
}

/* The row at (mu, nu) predicted into c: the newest row, or with two the
 * secant through them in ln mu (or nu, when mu is the same) per mesh index:
 * the logarithms of the interval lengths (layers that narrow like a power of
 * mu are then followed exactly), x, f', the stages and ln T. */
static void path_predict(const bkf_colloc_path *path, bkf_colloc *c, double mu, double nu)
{
    const path_row *r1 = &path->row[1], *r0 = &path->row[0];
    size_t n = r1->n;
    double r = 0.0;
    if (path->rows == 2) {
        if (r1->mu != r0->mu) r = log(mu / r1->mu) / log(r1->mu / r0->mu);
        else if (r1->nu != r0->nu) r = (nu - r1->nu) / (r1->nu - r0->nu);
    }
    set_params(c, mu, nu);
    c->n = n;
    if (r == 0.0) {
        memcpy(c->t, r1->t, (n + 1) * sizeof *c->t);
    } else {
        double total = 0.0;
        c->t[0] = 0.0;
        for (size_t j = 0; j < n; j++) {
            double h1 = r1->t[j + 1] - r1->t[j], h0 = r0->t[j + 1] - r0->t[j];
            total += h1 * pow(h1 / h0, r);
            c->t[j + 1] = total;
        }
        for (size_t j = 1; j < n; j++) c->t[j] /= total;
        c->t[n] = 1.0;
    }
    /* (with one row the other's arrays are not a row: 0 times their
     * uninitialised values was NaN where they held NaN, and the row fell
     * back to shooting, after an unrelated allocation pattern such as
     * Python's importing scipy: 5 times the time of a branch) */
    const path_row *base = path->rows == 2 ? r0 : r1;
    for (size_t j = 0; j < n; j++) {
        double xv = r1->x[j] + r * (r1->x[j] - base->x[j]), wv = r1->w[j] + r * (r1->w[j] - base->w[j]);
        c->x[j] = xv;
        c->y[j] = wv / c->a + c->b * lienard_F(xv);
        for (int i = 0; i < M; i++)
            c->X[j * M + i] = r1->X[j * M + i] + r * (r1->X[j * M + i] - base->X[j * M + i]);
    }
    c->x[0] = nu; /* the phase */
    c->x[n] = c->x[0];
    c->y[n] = c->y[0];
    c->T = exp(r1->lnT + r * (r1->lnT - r0->lnT));
    c->paired = 0;
}

/* The finer solution's coarsening (merged interval pairs), its values at
 * the kept points and its polynomials at the new stages: Newton's start for
 * the coarser mesh of the pair (remesh_to's Gauss steps are not needed
 * from a converged solution of the finer mesh). */
static int restrict_to_coarse(bkf_colloc *c)
{
    size_t n = c->n / 2;
    if (!reserve_scratch(c, n)) return BKF_ENOMEM;
    for (size_t k = 0; k < n; k++) {
        double h = c->t[2 * k + 2] - c->t[2 * k];
        for (int i = 0; i < M; i++) {
            double s = c->t[2 * k] + c->g.c[i] * h, unused;
            size_t j = s < c->t[2 * k + 1] ? 2 * k : 2 * k + 1;
            poly_eval(c, j, (s - c->t[j]) / (c->t[j + 1] - c->t[j]), &c->Xs[k * M + i], &unused);
        }
    }
    for (size_t k = 0; k <= n; k++) {
        c->t[k] = c->t[2 * k];
        c->x[k] = c->x[2 * k];
        c->y[k] = c->y[2 * k];
    }
    memcpy(c->X, c->Xs, n * M * sizeof *c->X);
    c->n = n;
    return BKF_OK;
}

/* A refused row leaves the path's newest row in c, as its solution (the
 * caller's warm start). */
static int path_fall_back(const bkf_colloc_path *path, bkf_colloc *c, int rc)
{
    const path_row *r1 = &path->row[1];
    bkf_colloc_path one = {.row = {path->row[0], *r1}, .rows = 1, .cap = path->cap};
    path_predict(&one, c, r1->mu, r1->nu);
    c->have_solution = 1;
    c->pair_n = c->n / 2;
    return rc;
}

int bkf_colloc_continue(bkf_colloc *c, bkf_colloc_path *path, double mu, double nu, double tol,
                        bkf_colloc_result *out, bkf_error *err)
{
    if (!c || !path || !path->rows) return bkf_error_set(err, BKF_EINPUT, "collocation continuation without a path");
    if (!reserve(c, path->row[1].n)) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    c->iterations = c->solves = 0;
    c->have_solution = 0;
    path_predict(path, c, mu, nu);
    int rc = converge(c, tol, err);
    out->newton_iterations = c->iterations;
    out->interval_solves = c->solves;
    if (rc != BKF_OK) return path_fall_back(path, c, rc);
    double T1 = c->T, L1 = log_multiplier(c), Tk, trace;
    size_t nk;
    if (keep_solution(c, 0, &nk, &Tk, &trace) != BKF_OK || restrict_to_coarse(c) != BKF_OK)
        return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    rc = converge(c, tol, err);
    double T2 = c->T, L2 = log_multiplier(c);
    out->newton_iterations = c->iterations;
    out->interval_solves = c->solves;
    if (keep_solution(c, 1, &nk, &Tk, &trace) != BKF_OK) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    if (rc != BKF_OK) return path_fall_back(path, c, rc);
    /* as solve_paired's pair: the coarser Newton starts from the finer
     * solution and shares what Newton leaves */
    /* On one mesh the pair's difference changes sign as the cycle moves
     * (mu 10 along nu: 2.5e-10 T, then 7.6e-11 T against a true 8.3e-11):
     * the last row's difference on the same mesh bounds it from below. */
    double diff = fabs(T1 - T2) / T1;
    double est = fmax(fmax(fmax(diff, path->last_diff) * T1 / EST_DIVISOR, round_floor(c, T1)),
                      TURN_FLOOR * c->local_tol * T1) +
                 1e-4 * tol * T1;
    path->last_diff = diff;
    c->have_solution = 1;
    c->pair_n = c->n / 2;
    if (ACCEPT_MARGIN * est > tol * T1)
        return bkf_error_set(err, BKF_ETOL,
                             "collocation at mu = %.15g, nu = %.15g: the path's mesh misses tol = %g (estimate %.2g)",
                             mu, nu, tol, est / T1);
    fill_result(c, est, L1, L2, EST_DIVISOR, out);
    return path_append(path, c) == BKF_ENOMEM ? bkf_error_set(err, BKF_ENOMEM, "out of memory") : BKF_OK;
}

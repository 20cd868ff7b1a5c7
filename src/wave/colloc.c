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

#include "colloc_internal.h"

#include <float.h>
#include <gsl/gsl_math.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* -------------------------------------------------------------- solve */

int colloc_converge(bkf_colloc *c, double tol, bkf_error *err)
{
    return colloc_newton(c, 0.01 * sqrt(tol), err);
}

int bkf_colloc_fixed(bkf_colloc *c, size_t intervals, double *period, bkf_error *err)
{
    if (!c || !c->have_guess) return bkf_error_set(err, BKF_EINPUT, "collocation solve before a guess");
    if (intervals < 4 || intervals > MAX_INTERVALS)
        return bkf_error_set(err, BKF_EINPUT, "intervals = %zu is outside [4, %d]", intervals, MAX_INTERVALS);
    int rc = colloc_newton(c, 1e-6, err);
    for (int pass = 0; rc == BKF_OK && pass < 2; pass++) {
        rc = colloc_equidistribute(c, intervals);
        if (rc == BKF_ENOMEM) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
        rc = colloc_newton(c, pass ? 1e-13 : 1e-8, err);
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
double colloc_round_floor(const bkf_colloc *c, double T)
{
    double size = fmin(1.0, 2.0 * sqrt(fmax(1.0 - c->nu * c->nu, 0.0)));
    return 8.0 * DBL_EPSILON * T * sqrt((double)c->n) / size;
}

/* Keep (which = 0) or restore (1) the current solution. */
int colloc_keep_solution(bkf_colloc *c, int which, size_t *n, double *T, double *trace)
{
    if (!which) {
        size_t need = (3 + M) * (c->n + 1);
        if (need > c->keep_cap) {
            if (!colloc_grow(&c->keep, need)) return BKF_ENOMEM;
            c->keep_cap = need;
        }
        *n = c->n;
        *T = c->T;
        *trace = c->trace;
    } else if (!colloc_reserve(c, *n)) {
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
void colloc_fill_result(bkf_colloc *c, double est, double L, double L_other, double divisor,
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
        int rc = colloc_newton(c, PAIRED_GOAL * sqrt(tol), err);
        if (rc != BKF_OK) return rc;
        double T1 = c->T, L1 = colloc_log_multiplier(c), Tk, trace;
        size_t nk;
        if (colloc_keep_solution(c, 0, &nk, &Tk, &trace) != BKF_OK)
            return bkf_error_set(err, BKF_ENOMEM, "out of memory");
        coarsen(c);
        rc = colloc_newton(c, PAIRED_GOAL * sqrt(tol), err);
        double T2 = c->T, L2 = colloc_log_multiplier(c);
        if (colloc_keep_solution(c, 1, &nk, &Tk, &trace) != BKF_OK)
            return bkf_error_set(err, BKF_ENOMEM, "out of memory");
        if (rc != BKF_OK) return rc;
        double diff = fabs(T1 - T2);
        /* the coarser Newton starts from the finer solution, so the pair
         * shares what Newton leaves (of the square of its goal): at mu 1e4,
         * nu 0.99, tol 1e-6 the pair agreed to 1e-12 against a true 6e-11 */
        double newton_left = PAIRED_GOAL * PAIRED_GOAL * tol * T1;
        double est = fmax(fmax(diff / PAIRED_DIVISOR, colloc_round_floor(c, T1)), TURN_FLOOR * c->local_tol * T1) +
                     newton_left;
        if (ACCEPT_MARGIN * est <= tol * T1) {
            colloc_fill_result(c, est, L1, L2, PAIRED_DIVISOR, out);
            c->pair_n = c->n / 2;
            c->paired = 0;
            return BKF_OK;
        }
        /* the error falls like the local tolerance^(2m/(2m+1)): the local
         * tolerance whose pair meets tol, with a margin of 2 */
        double need = diff * 2.0 * ACCEPT_MARGIN / (PAIRED_DIVISOR * tol * T1);
        double local = c->local_tol * pow(fmax(need, 1.5), -(2.0 * M + 1.0) / (2.0 * M));
        rc = colloc_turn_mesh(c, c->x[0], c->y[0], c->T, local, 1, 0, err);
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
    double est = fmax(fabs(T1 - T2) / EST_DIVISOR, colloc_round_floor(c, T2));
    if (!(ACCEPT_MARGIN * est <= tol * T2)) return 0;
    colloc_fill_result(c, est, L2, L1, EST_DIVISOR, out);
    c->pair_n = n;
    return 1;
}

/* From the converged mesh of n intervals: equidistributed meshes of n
 * (growing) intervals and their bisections until the pair meets tol. */
static int solve_equidistributed(bkf_colloc *c, double tol, size_t n, bkf_colloc_result *out, bkf_error *err)
{
    int rc;
    for (int round = 0; round < 5; round++) {
        rc = colloc_equidistribute(c, n);
        if (rc == BKF_OK) rc = colloc_converge(c, tol, err);
        if (rc == BKF_ENOMEM) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
        if (rc != BKF_OK) return rc;
        double T1 = c->T, L1 = colloc_log_multiplier(c);
        rc = colloc_bisect(c);
        if (rc == BKF_OK) rc = colloc_converge(c, tol, err);
        if (rc == BKF_ENOMEM) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
        if (rc != BKF_OK) return rc;
        double T2 = c->T, L2 = colloc_log_multiplier(c);
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
    if (!colloc_reserve_scratch(c, 2 * n)) return BKF_ENOMEM;
    double lm[M + 1], la[M][M + 1], lb[M][M + 1];
    colloc_lagrange_weights(c->g.c, 0.5, lm);
    for (int i = 0; i < M; i++) {
        colloc_lagrange_weights(c->g.c, 0.5 * c->g.c[i], la[i]);
        colloc_lagrange_weights(c->g.c, 0.5 * (1.0 + c->g.c[i]), lb[i]);
    }
    for (size_t j = 0; j < n; j++) {
        const double *X = c->X + j * M;
        double Y[M], xm = lm[0] * c->x[j], ym = lm[0] * c->y[j];
        colloc_stage_y(c, j, Y);
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
    if (!colloc_reserve(c, 2 * n)) return BKF_ENOMEM;
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
    int rc = colloc_converge(c, tol, err);
    if (rc != BKF_OK) return rc;
    size_t n = c->n;
    double T1 = c->T, L1 = colloc_log_multiplier(c);
    if (bisect_smooth(c) != BKF_OK) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    rc = colloc_converge(c, tol, err);
    if (rc != BKF_OK) return rc;
    double T2 = c->T, L2 = colloc_log_multiplier(c);
    double diff = fabs(T1 - T2);
    if (pair_meets_tol(c, T1, L1, T2, L2, n, tol, out)) return BKF_OK;
    /* finer meshes only raise the rounding floor (mu 1e-3, nu 0.9999,
     * tol 1e-12: the rounds went on to 40000 intervals, 7.8M instructions,
     * before refusing) */
    if (ACCEPT_MARGIN * colloc_round_floor(c, T2) > tol * T2)
        return bkf_error_set(err, BKF_ETOL,
                             "collocation at mu = %.15g, nu = %.15g: its rounding floor %.2g exceeds tol = %g / %g",
                             c->mu, c->nu, colloc_round_floor(c, T2) / T2, tol, ACCEPT_MARGIN);
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
    int rc = colloc_converge(c, fmax(tol, 1e-6), err);
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
        colloc_poly_eval(c, j, theta, &xv, &yv);
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
            for (int i = 0; i < M; i++) colloc_poly_eval(c, j, (double)back + c->g.c[i] * len / tau, &X[i], &unused);
            if (!colloc_guarded_step(c, c->x[k], c->y[k], len, STAGE_GOAL, 1, X, &xe, &ye)) break;
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


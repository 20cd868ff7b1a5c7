/* The collocation engine's continuation (colloc.c): a branch's rows
 * predicted per mesh index from the last two.  Above the solve, which it
 * calls (colloc.c); nothing calls back. */
#include "colloc_internal.h"

#include <float.h>
#include <gsl/gsl_math.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

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
        if (!colloc_grow(&r->t, cap + 1) || !colloc_grow(&r->x, cap + 1) || !colloc_grow(&r->w, cap + 1) ||
            !colloc_grow(&r->X, cap * M))
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
    colloc_set_params(c, mu, nu);
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
    if (!colloc_reserve_scratch(c, n)) return BKF_ENOMEM;
    for (size_t k = 0; k < n; k++) {
        double h = c->t[2 * k + 2] - c->t[2 * k];
        for (int i = 0; i < M; i++) {
            double s = c->t[2 * k] + c->g.c[i] * h, unused;
            size_t j = s < c->t[2 * k + 1] ? 2 * k : 2 * k + 1;
            colloc_poly_eval(c, j, (s - c->t[j]) / (c->t[j + 1] - c->t[j]), &c->Xs[k * M + i], &unused);
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
    if (!colloc_reserve(c, path->row[1].n)) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    c->iterations = c->solves = 0;
    c->have_solution = 0;
    path_predict(path, c, mu, nu);
    int rc = colloc_converge(c, tol, err);
    out->newton_iterations = c->iterations;
    out->interval_solves = c->solves;
    if (rc != BKF_OK) return path_fall_back(path, c, rc);
    double T1 = c->T, L1 = colloc_log_multiplier(c), Tk, trace;
    size_t nk;
    if (colloc_keep_solution(c, 0, &nk, &Tk, &trace) != BKF_OK || restrict_to_coarse(c) != BKF_OK)
        return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    rc = colloc_converge(c, tol, err);
    double T2 = c->T, L2 = colloc_log_multiplier(c);
    out->newton_iterations = c->iterations;
    out->interval_solves = c->solves;
    if (colloc_keep_solution(c, 1, &nk, &Tk, &trace) != BKF_OK) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    if (rc != BKF_OK) return path_fall_back(path, c, rc);
    /* as solve_paired's pair: the coarser Newton starts from the finer
     * solution and shares what Newton leaves */
    /* On one mesh the pair's difference changes sign as the cycle moves
     * (mu 10 along nu: 2.5e-10 T, then 7.6e-11 T against a true 8.3e-11):
     * the last row's difference on the same mesh bounds it from below. */
    double diff = fabs(T1 - T2) / T1;
    double est = fmax(fmax(fmax(diff, path->last_diff) * T1 / EST_DIVISOR, colloc_round_floor(c, T1)),
                      TURN_FLOOR * c->local_tol * T1) +
                 1e-4 * tol * T1;
    path->last_diff = diff;
    c->have_solution = 1;
    c->pair_n = c->n / 2;
    if (ACCEPT_MARGIN * est > tol * T1)
        return bkf_error_set(err, BKF_ETOL,
                             "collocation at mu = %.15g, nu = %.15g: the path's mesh misses tol = %g (estimate %.2g)",
                             mu, nu, tol, est / T1);
    colloc_fill_result(c, est, L1, L2, EST_DIVISOR, out);
    return path_append(path, c) == BKF_ENOMEM ? bkf_error_set(err, BKF_ENOMEM, "out of memory") : BKF_OK;
}

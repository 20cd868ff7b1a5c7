/* Eigenvalues of a train followed from a nearby one (see trainspec.h,
 * bkf_trainspec_track): Newton on each one's Bloch class alone, on meshes
 * refined until the asked tol, one context (one cycle) for them all. */

#include "trainspec_internal.h"

#include <gsl/gsl_math.h>

#include <complex.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Mesh multipliers tried: 1, 2, 4, ..., the ring spectrum's first pair and
 * its refinements (MESH_REFINEMENTS more). */
enum { LEVELS = MESH_REFINEMENTS + 2 };

/* The meshes of 1, 2, 4, ... substeps (each halving every step of the one
 * before), built when first needed and shared by every eigenvalue. */
typedef struct {
    mesh m[LEVELS];
    int built[LEVELS];
} ladder;

static int ladder_at(ctx *x, ladder *l, int k, const mesh **m, bkf_error *err)
{
    if (!l->built[k]) {
        int rc = trainspec_mesh_build(x, (size_t)SUBSTEPS_START << k, &l->m[k], err);
        if (rc != BKF_OK) return rc;
        l->built[k] = 1;
    }
    *m = &l->m[k];
    return BKF_OK;
}

/* sigma on the ladder's meshes, each polish started from the coarser one's
 * value with its derivative, until the difference / RICHARDSON
 * (fifth-order steps), the last Newton step and the profile's share (the
 * ring spectrum's estimate) meet x->tol.  sigma NaN: Newton did not
 * converge or the tol was not met on the finest mesh. */
static int track_one(ctx *x, ladder *l, size_t j, double complex *sigma, double *err_out, bkf_error *err)
{
    double theta = 2.0 * M_PI * (double)j / (double)x->n;
    double complex coarse = *sigma, deriv[2] = {0, 0};
    double step = INFINITY;
    const mesh *m;
    int rc = ladder_at(x, l, 0, &m, err);
    if (rc != BKF_OK) return rc;
    rc = trainspec_polish(x, m, theta, &coarse, &step, deriv);
    for (int k = 1; rc == BKF_OK && k < LEVELS; k++) {
        int b = ladder_at(x, l, k, &m, err);
        if (b != BKF_OK) return b;
        double complex fine = coarse;
        rc = trainspec_polish(x, m, theta, &fine, &step, deriv);
        if (rc != BKF_OK) break;
        double e = trainspec_estimate(coarse, fine, step);
        coarse = fine;
        if (e <= x->tol) {
            *sigma = fine;
            *err_out = e;
            return BKF_OK;
        }
    }
    if (x->stop) return trainspec_stopped(x, BKF_ENUMERIC, err);
    *sigma = NAN;
    return BKF_OK;
}

int bkf_trainspec_track(const bkf_model_params *p, const bkf_trainspec_train *t, double tol, size_t count,
                        const bkf_trainspec_eigenvalue *from, bkf_trainspec_eigenvalue *to, size_t *followed,
                        bkf_error *err)
{
    int rc = bkf_trainspec_check(p, t, NULL, err);
    if (rc != BKF_OK) return rc;
    if (!(tol >= TOL_MIN && tol <= TOL_MAX))
        return bkf_error_set(err, BKF_EINPUT, "tol must be in [%g, %g]", TOL_MIN, TOL_MAX);
    if (count && (!from || !to)) return bkf_error_set(err, BKF_EINPUT, "from and to are required");
    double reach = 0.0, lowest = 0.0;
    for (size_t i = 0; i < count; i++) {
        if (from[i].j >= t->n)
            return bkf_error_set(err, BKF_EINPUT, "j must be in [0, n - 1] = [0, %zu]", t->n - 1);
        if (!isfinite(from[i].re) || !isfinite(from[i].im))
            return bkf_error_set(err, BKF_EINPUT, "sigma must be finite");
        reach = fmax(reach, hypot(from[i].re, from[i].im));
        lowest = fmin(lowest, from[i].re);
    }
    if (followed) *followed = 0;
    if (!count) return BKF_OK;
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    ctx x;
    rc = trainspec_ctx_init(&x, p, t, tol, NULL, err);
    /* one mesh for them all: the one the largest |sigma| needs, with the
     * ring spectrum's polish margin (from the start values: a step to the
     * new train moves them by far less; a mesh for 2 |sigma| + 1, as
     * bkf_trainspec_eigenvalue_at's, had 3 times the steps at |sigma| 0.2
     * and cost the paper scene's n = 6 branch 0.6 s more), each value's
     * error still its own ladder's */
    x.re_floor = fmin(x.re_floor, lowest - WINDOW_DEPTH * x.gamma);
    if (rc == BKF_OK) rc = trainspec_mesh_needs(&x, POLISH_MARGIN * reach + POLISH_REACH_MIN, err);
    ladder l;
    memset(&l, 0, sizeof l);
    for (size_t i = 0; i < count && rc == BKF_OK; i++) {
        double complex s = from[i].re + I * from[i].im;
        double e = NAN;
        rc = track_one(&x, &l, from[i].j, &s, &e, err);
        to[i] = from[i];
        to[i].re = creal(s);
        to[i].im = cimag(s);
        to[i].err = isfinite(creal(s)) ? e : NAN;
        to[i].kappa = 2.0 * M_PI * (double)from[i].j / p->S;
        if (rc == BKF_OK && followed && isfinite(creal(s))) ++*followed;
    }
    for (int k = 0; k < LEVELS; k++) trainspec_mesh_free(&l.m[k]);
    trainspec_ctx_free(&x);
    bkf_gsl_handler_pop(handler);
    return rc;
}

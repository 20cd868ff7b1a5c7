/* The eigenvalues a branch's verdicts follow from point to point (see
 * fronts_internal.h): between two ring spectra, the last one's eigenvalues
 * are continued by Newton on their own Bloch classes (bkf_trainspec_track,
 * about 1/20 of a ring spectrum each at mu 2-10), and a change of sign is
 * located on the one eigenvalue that crosses. */
#include "fronts_internal.h"

#include <complex.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_roots.h>

/* A followed eigenvalue proves instability when right of 0 by this many of
 * its error estimates plus tol (stabmap's test on a continued eigenvalue). */
#define TRACK_MARGIN 4.0
/* Brent's iterations at most on a followed eigenvalue. */
#define TRACK_CROSSING_ITER 40

static int set_reserve(fronts_track_set *set, size_t count)
{
    if (count <= set->cap) return BKF_OK;
    bkf_trainspec_eigenvalue *e = realloc(set->e, count * sizeof *e);
    if (!e) return BKF_ENOMEM;
    set->e = e;
    set->cap = count;
    return BKF_OK;
}

/* Of a ring spectrum's eigenvalues, those within |sigma_max| / TRACK_BAND
 * (plus 10 tol) of its rightmost are followed, TRACK_MAX at most: in a band
 * of eigenvalues of nearly one real part (gamma 4, c 0.15, nu -0.7, n = 2:
 * Re 0.0090-0.0091 at Im 3.0-4.0 in both classes) the rightmost moves from
 * one to the next as the parameter changes. */
#define TRACK_BAND 1.0
#define TRACK_MAX 16

static int by_re_desc(const void *pa, const void *pb)
{
    const bkf_trainspec_eigenvalue *a = pa, *b = pb;
    return (a->re < b->re) - (a->re > b->re);
}

int fronts_track_seed(fronts_track_set *set, const bkf_trainspec_result *r, double tol)
{
    set->count = 0;
    set->lead = 0;
    if (r->sigma_is_bound) return BKF_OK;
    if (set_reserve(set, r->count)) return BKF_ENOMEM;
    double floor = r->sigma_max - fabs(r->sigma_max) / TRACK_BAND - 10 * tol;
    for (size_t i = 0; i < r->count; i++) {
        const bkf_trainspec_eigenvalue *e = &r->eigenvalues[i];
        /* sigma of class j and its conjugate of class n - j are one
         * eigenvalue followed twice: the first (lower j, the one the ring's
         * sigma_max names) is kept */
        int twin = e->translation || e->re < floor;
        for (size_t k = 0; k < set->count && !twin; k++)
            twin = (set->e[k].j + e->j) % r->n == 0 &&
                   cabs((set->e[k].re - I * set->e[k].im) - (e->re + I * e->im)) <=
                       set->e[k].err + e->err;
        if (!twin) set->e[set->count++] = *e;
    }
    /* stable: equal real parts keep the ring's order, whose first names sigma_max */
    for (size_t i = 1; i < set->count; i++)
        for (size_t k = i; k > 0 && by_re_desc(&set->e[k - 1], &set->e[k]) > 0; k--) {
            bkf_trainspec_eigenvalue t = set->e[k];
            set->e[k] = set->e[k - 1];
            set->e[k - 1] = t;
        }
    if (set->count > TRACK_MAX) set->count = TRACK_MAX;
    return BKF_OK;
}

void fronts_track_set_free(fronts_track_set *set)
{
    free(set->e);
    memset(set, 0, sizeof *set);
}

int fronts_track_point(const bkf_model_params *p, const bkf_speeds_root *root, double tol,
                       fronts_track_set *set, bkf_trainspec_result *out, int *decided,
                       bkf_error *err)
{
    memset(out, 0, sizeof *out);
    *decided = 0;
    out->sigma_max = -INFINITY;
    if (!set->count || root->status != BKF_OK) return BKF_OK;
    bkf_trainspec_eigenvalue *to = malloc(set->count * sizeof *to);
    if (!to) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    bkf_trainspec_train train = {root->n, root->v};
    size_t followed = 0;
    bkf_error e;
    int s = bkf_trainspec_track(p, &train, tol, set->count, set->e, to, &followed, &e);
    if (s == BKF_ENOMEM) {
        free(to);
        return bkf_error_set(err, s, "out of memory");
    }
    if (s) followed = 0; /* a budget or a refused cycle: the ring spectrum says why */
    out->params = *p;
    out->n = root->n;
    out->v = root->v;
    out->mu = root->mu;
    out->eigenvalues = to;
    out->count = s ? 0 : set->count;
    size_t lead = 0;
    for (size_t i = 0; i < out->count; i++) {
        if (!isfinite(to[i].re) || to[i].re <= out->sigma_max) continue;
        lead = i;
        out->sigma_max = to[i].re;
        out->sigma_max_im = to[i].im;
        out->sigma_max_err = to[i].err;
        out->kappa_max = to[i].kappa;
    }
    out->complex_pair = fabs(out->sigma_max_im) > out->sigma_max_err;
    out->verdict = BKF_TRAINSPEC_UNSTABLE;
    if (followed == set->count && lead == set->lead &&
        out->sigma_max - TRACK_MARGIN * out->sigma_max_err > tol) {
        *decided = 1;
        memcpy(set->e, to, set->count * sizeof *to);
    }
    return BKF_OK;
}

/* ------------------------------------------------- a crossing on one eigenvalue */

typedef struct {
    fronts_root_at root_at;
    void *data;
    size_t n;
    double tol;
    /* the eigenvalue at every x tried (the nearest starts the next Newton) */
    double xs[TRACK_CROSSING_ITER + 2];
    bkf_trainspec_eigenvalue at[TRACK_CROSSING_ITER + 2];
    size_t tried;
    bkf_model_params p;
    bkf_speeds_root root;
    double x_last;
    int status;
    bkf_error why;
    size_t evaluations;
} crossing_track;

static double tracked_re(double x, void *data)
{
    crossing_track *c = data;
    size_t near = 0;
    for (size_t i = 0; i < c->tried; i++) {
        if (c->xs[i] == x) return c->at[i].re;
        if (fabs(c->xs[i] - x) < fabs(c->xs[near] - x)) near = i;
    }
    if (c->status || c->tried >= sizeof c->xs / sizeof c->xs[0]) return NAN;
    bkf_trainspec_eigenvalue to;
    int s = c->root_at(x, c->data, &c->p, &c->root, &c->why);
    if (!s) {
        bkf_trainspec_train train = {c->n, c->root.v};
        s = bkf_trainspec_track(&c->p, &train, c->tol, 1, &c->at[near], &to, NULL, &c->why);
        c->evaluations++;
    }
    if (!s && !isfinite(to.re))
        s = bkf_error_set(&c->why, BKF_ENUMERIC, "the eigenvalue was lost by Newton");
    c->status = s;
    if (s) return NAN;
    c->xs[c->tried] = x;
    c->at[c->tried++] = to;
    c->x_last = x;
    return to.re;
}

int fronts_track_crossing(double xa, double xb, const bkf_trainspec_eigenvalue *start, size_t n,
                          double tol, fronts_root_at root_at, void *data, double *x,
                          bkf_model_params *p, bkf_speeds_root *root, size_t *evaluations,
                          bkf_error *err)
{
    crossing_track *c = calloc(1, sizeof *c);
    if (!c) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    c->root_at = root_at;
    c->data = data;
    c->n = n;
    c->tol = tol;
    c->xs[0] = xa;
    c->at[0] = *start;
    c->tried = 1;
    c->x_last = NAN;
    /* the other end: the same eigenvalue must be right of 0 there */
    double fb = tracked_re(xb, c);
    int s = c->status;
    if (!s && !(fb * start->re < 0))
        s = bkf_error_set(err, BKF_ENUMERIC, "the eigenvalue does not change sign");
    gsl_root_fsolver *fs = s ? NULL : gsl_root_fsolver_alloc(gsl_root_fsolver_brent);
    if (!s && !fs) s = bkf_error_set(err, BKF_ENOMEM, "out of memory");
    int located = 0;
    if (!s) {
        gsl_function F = {tracked_re, c};
        bkf_gsl_handler *h = bkf_gsl_handler_push();
        int g = gsl_root_fsolver_set(fs, &F, fmin(xa, xb), fmax(xa, xb));
        for (int it = 0; g == GSL_SUCCESS && !located && it < TRACK_CROSSING_ITER; it++) {
            g = gsl_root_fsolver_iterate(fs);
            double r = gsl_root_fsolver_root(fs);
            if (g == GSL_SUCCESS && r == c->x_last && fabs(c->at[c->tried - 1].re) <= 0.5 * tol)
                located = 1;
            else if (g == GSL_SUCCESS &&
                     gsl_root_test_interval(gsl_root_fsolver_x_lower(fs),
                                            gsl_root_fsolver_x_upper(fs), 0, 1e-13) == GSL_SUCCESS)
                break;
        }
        bkf_gsl_handler_pop(h);
        gsl_root_fsolver_free(fs);
        if (c->status == BKF_ENOMEM) s = bkf_error_set(err, BKF_ENOMEM, "out of memory");
        else if (!located)
            s = bkf_error_set(err, BKF_ENUMERIC, "%s",
                              c->status ? c->why.message : "no zero to the tolerance");
    } else if (c->status == BKF_ENOMEM) {
        s = bkf_error_set(err, BKF_ENOMEM, "out of memory");
    } else if (c->status) {
        s = bkf_error_set(err, BKF_ENUMERIC, "%s", c->why.message);
    }
    *evaluations += c->evaluations;
    if (located) {
        *x = c->x_last;
        *p = c->p;
        *root = c->root;
    }
    free(c);
    return s;
}

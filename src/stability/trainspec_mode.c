/* Single eigenvalues of front trains and their eigenfunctions (see
 * trainspec.h): Newton on one mesh from a given sigma, and the walk that
 * samples the perturbation along the ring. */
#include "bkfront/trainspec.h"

#include "bkfront/options.h"
#include "trainspec_internal.h"

#include <gsl/gsl_math.h>

#include <complex.h>
#include <math.h>
#include <stdlib.h>

#define SUBSTEPS_MAX 4096
#define MODE_SUBSTEPS 8

/* The context and its fine mesh (substeps) resolving |sigma| ~ |sigma0|,
 * and sigma polished on it from sigma0 in class j. */
static int one_eigenvalue(ctx *x, const bkf_model_params *p, const bkf_trainspec_train *t, size_t j,
                          double complex *sigma, size_t substeps, bkf_error *err)
{
    int rc = trainspec_ctx_init(x, p, t, TOL_MIN, NULL, err);
    x->re_floor = fmin(x->re_floor, creal(*sigma) - WINDOW_DEPTH * x->gamma);
    if (rc == BKF_OK) rc = trainspec_mesh_needs(x, 2.0 * cabs(*sigma) + 1.0, err);
    if (rc == BKF_OK) rc = trainspec_mesh_build(x, substeps, &x->fine, err);
    if (rc != BKF_OK) return rc;
    double step;
    double complex s = *sigma;
    int prc = trainspec_polish(x, &x->fine, 2.0 * M_PI * (double)j / (double)t->n, &s, &step, NULL);
    if (x->stop) return trainspec_stopped(x, prc, err);
    if (prc != BKF_OK)
        return bkf_error_set(err, BKF_ENUMERIC,
                             "no eigenvalue of class j = %zu converged from sigma = %.6g%+.6gi (last Newton "
                             "step %.3g)",
                             j, creal(*sigma), cimag(*sigma), step);
    *sigma = s;
    return BKF_OK;
}

static int check_one(const bkf_model_params *p, const bkf_trainspec_train *t, size_t j, double re0, double im0,
                     bkf_error *err)
{
    int rc = bkf_trainspec_check(p, t, NULL, err);
    if (rc != BKF_OK) return rc;
    if (j >= t->n) return bkf_error_set(err, BKF_EINPUT, "j must be in [0, n - 1] = [0, %zu]", t->n - 1);
    if (!isfinite(re0) || !isfinite(im0)) return bkf_error_set(err, BKF_EINPUT, "sigma must be finite");
    return BKF_OK;
}

int bkf_trainspec_eigenvalue_at(const bkf_model_params *p, const bkf_trainspec_train *t, size_t j, double re0,
                                double im0, size_t substeps, double *re, double *im, size_t *mesh_steps,
                                bkf_error *err)
{
    int rc = check_one(p, t, j, re0, im0, err);
    if (rc != BKF_OK) return rc;
    if (substeps < 1 || substeps > SUBSTEPS_MAX)
        return bkf_error_set(err, BKF_EINPUT, "substeps must be in [1, %d]", SUBSTEPS_MAX);
    if (!re || !im) return bkf_error_set(err, BKF_EINPUT, "re and im are required");
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    ctx x;
    double complex s = re0 + I * im0;
    rc = one_eigenvalue(&x, p, t, j, &s, substeps, err);
    if (rc == BKF_OK) {
        *re = creal(s);
        *im = cimag(s);
        if (mesh_steps) *mesh_steps = x.fine.steps;
    }
    trainspec_ctx_free(&x);
    bkf_gsl_handler_pop(handler);
    return rc;
}

typedef struct {
    double r;     /* z within the period, [0, T] */
    double cycle; /* which period (0 .. n-1): its Bloch factor is exp(i cycle theta) */
    size_t at;    /* index of the sample on the ring */
} mode_sample;

static int by_r(const void *pa, const void *pb)
{
    const mode_sample *a = pa, *b = pb;
    return (a->r > b->r) - (a->r < b->r);
}

/* p, p' (radau_step's basis) from the multiplier's eigenvector through the
 * period, recorded at the samples (sorted by r) into u, du times
 * exp(scale_at): mesh steps and samples merged into one walk. */
static int mode_walk(ctx *x, double complex sigma, const double complex y0[2], const mode_sample *smp, size_t N,
                     double complex *u, double complex *du, double *scale_at, bkf_error *err)
{
    double *bounds = NULL, *merged = NULL;
    size_t steps = 0;
    size_t *slot = malloc(N * sizeof *slot);
    mesh walk = {0};
    int rc = slot ? trainspec_mesh_bounds(x, MODE_SUBSTEPS, &bounds, &steps, err) : bkf_error_set(err, BKF_ENOMEM, "out of memory");
    if (rc == BKF_OK && !(merged = malloc((steps + 1 + N) * sizeof *merged)))
        rc = bkf_error_set(err, BKF_ENOMEM, "out of memory");
    size_t count = 0;
    if (rc == BKF_OK) {
        size_t a = 0, b = 0;
        while (a <= steps || b < N) {
            if (b < N && (a > steps || smp[b].r <= bounds[a])) {
                slot[b++] = count;
                merged[count++] = smp[b - 1].r;
            } else {
                merged[count++] = bounds[a++];
            }
        }
        rc = trainspec_mesh_fill(x, merged, count - 1, &walk, err);
    }
    if (rc == BKF_OK) {
        double complex y[2] = {y0[0], y0[1]};
        double scale = 0.0;
        size_t next = 0;
        for (size_t k = 0; k < count; k++) {
            while (next < N && slot[next] == k) {
                u[next] = y[0];
                du[next] = y[1];
                scale_at[next++] = scale;
            }
            if (k + 1 == count) break;
            double complex e[4];
            trainspec_radau_step(x, &walk, k, sigma, e, NULL);
            double complex y1 = e[0] * y[0] + e[1] * y[1], y2 = e[2] * y[0] + e[3] * y[1];
            y[0] = y1, y[1] = y2;
            trainspec_rescale(y, 2, &scale);
        }
    }
    trainspec_mesh_free(&walk);
    free(bounds);
    free(merged);
    free(slot);
    return rc;
}

int bkf_trainspec_mode(const bkf_model_params *p, const bkf_trainspec_train *t, size_t j, double *re, double *im,
                       size_t N, double *p_re, double *p_im, double *q_re, double *q_im, bkf_error *err)
{
    if (!re || !im) return bkf_error_set(err, BKF_EINPUT, "re and im are required");
    int rc = check_one(p, t, j, *re, *im, err);
    if (rc != BKF_OK) return rc;
    if (N < 2 || N > 1u << 24) return bkf_error_set(err, BKF_EINPUT, "N must be in [2, %u]", 1u << 24);
    if (!p_re) return bkf_error_set(err, BKF_EINPUT, "p_re is required");
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    ctx x;
    double complex sigma = *re + I * *im;
    mode_sample *smp = malloc(N * sizeof *smp);
    double complex *u = malloc(N * sizeof *u), *du = malloc(N * sizeof *du);
    double *scale_at = malloc(N * sizeof *scale_at), *r = malloc(N * sizeof *r), *f = malloc(N * sizeof *f),
           *fp = malloc(N * sizeof *fp);
    rc = one_eigenvalue(&x, p, t, j, &sigma, MODE_SUBSTEPS, err);
    if (rc == BKF_OK && (!smp || !u || !du || !scale_at || !r || !f || !fp))
        rc = bkf_error_set(err, BKF_ENOMEM, "out of memory");
    double theta = 2.0 * M_PI * (double)j / (double)t->n;
    if (rc == BKF_OK) {
        /* the eigenvector of the multiplier exp(sigma T / s + i theta): in
         * p's basis (radau_step) the eigenvalue exp(i theta) */
        double complex m[4], want = I * theta;
        double scale;
        trainspec_monodromy_matrix(&x, &x.fine, sigma, m, NULL, &scale);
        double complex half = 0.5 * (m[0] + m[3]), root = csqrt(half * half - (m[0] * m[3] - m[1] * m[2]));
        double complex lam[2] = {half + root, half - root};
        double miss[2];
        for (int k = 0; k < 2; k++) {
            double complex w = clog(lam[k]) + scale - want;
            miss[k] = hypot(creal(w), trainspec_wrap(cimag(w)));
        }
        double complex l = miss[0] <= miss[1] ? lam[0] : lam[1];
        double complex ya[2] = {m[1], l - m[0]}, yb[2] = {l - m[3], m[2]};
        const double complex *y0 = cabs(ya[0]) + cabs(ya[1]) >= cabs(yb[0]) + cabs(yb[1]) ? ya : yb;
        double period = x.T, S = x.S, vs = x.v * x.s;
        for (size_t i = 0; i < N; i++) {
            double z = (double)i * S / (double)N / vs;
            double cyc = fmin(floor(z / period), (double)(t->n - 1));
            smp[i] = (mode_sample){fmin(fmax(z - cyc * period, 0.0), period), cyc, i};
        }
        qsort(smp, N, sizeof *smp, by_r);
        for (size_t i = 0; i < N; i++) r[i] = smp[i].r;
        rc = mode_walk(&x, sigma, y0, smp, N, u, du, scale_at, err);
        if (rc == BKF_OK) rc = bkf_cycle_profile_sample(x.cycle, r, N, f, fp, err);
    }
    if (rc == BKF_OK) {
        /* p (walked in its own basis, radau_step) times the Bloch factor of
         * the period it lies in; magnitudes relative to the largest, then
         * normalised */
        double top = -INFINITY;
        for (size_t i = 0; i < N; i++) {
            double size = fmax(cabs(u[i]), cabs(du[i]));
            if (size > 0) top = fmax(top, scale_at[i] + log(size));
        }
        double pmax = 0.0;
        double complex *pv = u, *qv = du; /* overwritten in place */
        for (size_t i = 0; i < N; i++) {
            double complex factor = cexp(scale_at[i] - top + I * smp[i].cycle * theta);
            double complex pi = factor * u[i];
            double complex dpi = factor * du[i] / (x.v * x.s);
            pv[i] = pi;
            qv[i] = (sigma * pi + x.v * dpi) / x.gamma + bkf_model_friction_slope(f[i]) * pi;
            pmax = fmax(pmax, cabs(pi));
        }
        if (!(pmax > 0) || !isfinite(pmax)) rc = bkf_error_set(err, BKF_ENUMERIC, "the eigenfunction vanished");
        for (size_t i = 0; i < N && rc == BKF_OK; i++) {
            size_t at = smp[i].at;
            p_re[at] = creal(pv[i]) / pmax;
            if (p_im) p_im[at] = cimag(pv[i]) / pmax;
            if (q_re) q_re[at] = creal(qv[i]) / pmax;
            if (q_im) q_im[at] = cimag(qv[i]) / pmax;
        }
        *re = creal(sigma);
        *im = cimag(sigma);
    }
    free(smp);
    free(u);
    free(du);
    free(scale_at);
    free(r);
    free(f);
    free(fp);
    trainspec_ctx_free(&x);
    bkf_gsl_handler_pop(handler);
    return rc;
}

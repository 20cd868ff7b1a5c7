/* The peaks of lambda over the wavenumber (floquet.c): scanned, refined by
 * maximising s * trace(M), and the stability verdict at one nu from them.
 * Above the monodromy (floquet.c), below the boundaries
 * (floquet_threshold.c), which call it. */
#include "floquet_internal.h"

#include "bkfront/continuation.h"
#include "bkfront/model.h"

#include <float.h>
#include <gsl/gsl_errno.h>
#include <gsl/gsl_odeiv2.h>
#include <math.h>
#include <nlopt.h>
#include <stdlib.h>
#include <string.h>

/* ---------------------------------------------------------------- peaks */

typedef struct {
    bkf_floquet *f;
    nlopt_opt opt;
    double sign;
    int status;
    bkf_error *err;
} peak_ctx;

static double peak_objective(unsigned n, const double *x, double *grad, void *data)
{
    (void)n;
    (void)grad;
    peak_ctx *pc = data;
    raw r;
    if (pc->status == BKF_OK) pc->status = floquet_integrate(pc->f, x[0], 0, ENG_FINE, &r, pc->err);
    /* NLopt's objective cannot fail: stop it, the status is read afterwards */
    if (pc->status != BKF_OK) {
        nlopt_force_stop(pc->opt);
        return 0.0;
    }
    return pc->sign * r.tr;
}

/* The K in [lo, hi] maximising sign * trace, searched from *K. */
static int maximise_trace(bkf_floquet *f, double sign, double lo, double hi, double *K,
                          double *value, bkf_error *err)
{
    nlopt_opt opt = nlopt_create(NLOPT_LN_BOBYQA, 1);
    if (!opt) return bkf_error_set(err, BKF_ENOMEM, "out of memory (NLopt)");
    peak_ctx pc = {f, opt, sign, BKF_OK, err};
    nlopt_set_max_objective(opt, peak_objective, &pc);
    nlopt_set_lower_bounds1(opt, lo);
    nlopt_set_upper_bounds1(opt, hi);
    /* the peak's height is quadratic in the error of its place: a relative
     * 1e-7 in K is far below any tolerance in lambda */
    nlopt_set_xtol_rel(opt, 1e-7);
    nlopt_set_maxeval(opt, 200);
    nlopt_set_initial_step1(opt, 0.25 * (hi - lo));
    double x = fmin(fmax(*K, lo), hi), fx = 0.0;
    nlopt_result res = nlopt_optimize(opt, &x, &fx);
    nlopt_destroy(opt);
    if (pc.status != BKF_OK) return pc.status;
    if (res < 0 && res != NLOPT_ROUNDOFF_LIMITED)
        return bkf_error_set(err, BKF_ENUMERIC,
                             "peak of lambda at gamma = %.15g, nu = %.15g near K = %.15g: NLopt failed (%d)",
                             f->gamma, f->nu, *K, (int)res);
    *K = x;
    *value = fx;
    return BKF_OK;
}

/* Local peak of sign * trace near K, searched in windows of half-width w,
 * moved while the maximum sits on a window's edge.  K never goes below 1. */
int floquet_track_peak(bkf_floquet *f, double sign, double *K, double w, double *value,
                       bkf_error *err)
{
    double center = *K;
    for (int attempt = 0; attempt < 8; attempt++) {
        double lo = fmax(1.0, center - w), hi = fmin(K_MAX, center + w);
        double x = center;
        int rc = maximise_trace(f, sign, lo, hi, &x, value, err);
        if (rc != BKF_OK) return rc;
        double edge_tol = 1e-6 * (hi - lo);
        int at_lo = x - lo <= edge_tol && lo > 1.0;
        int at_hi = hi - x <= edge_tol && hi < K_MAX;
        *K = x;
        if (!at_lo && !at_hi) return BKF_OK;
        center = x;
        w *= 1.5;
    }
    return BKF_OK;
}

/* A refined peak: the K of the maximum, then lambda with its error there. */
static int refine_peak(bkf_floquet *f, double sign, double K_guess, double w, peak *out,
                       bkf_error *err)
{
    double K = K_guess, value;
    int rc = floquet_track_peak(f, sign, &K, w, &value, err);
    if (rc != BKF_OK) return rc;
    bkf_floquet_point pt;
    rc = floquet_eval_k2(f, K, &pt, err);
    if (rc != BKF_OK) return rc;
    out->K = K;
    out->lambda = pt.lambda;
    out->lambda_err = pt.lambda_err;
    out->m_re = pt.m1_re;
    out->m_im = pt.m1_im;
    out->sign = sign;
    return BKF_OK;
}

int floquet_stability_scan(bkf_floquet *f, stability_full *sf, bkf_error *err)
{
    memset(sf, 0, sizeof *sf);
    bkf_floquet_stability *s = &sf->s;
    s->nu = f->nu;
    int rc = bkf_floquet_longwave(f, &s->longwave, &s->longwave_err, err);
    if (rc != BKF_OK) return rc;
    size_t n = f->opt.scan_points;
    double dp = f->opt.p_max / (double)n;
    double *tr = malloc((n + 1) * sizeof *tr);
    if (!tr) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    for (size_t j = 0; j <= n && rc == BKF_OK; j++) {
        raw r;
        double p = dp * (double)j;
        rc = floquet_integrate(f, 1.0 + p * p, 0, ENG_SCAN, &r, err);
        tr[j] = r.tr;
    }
    int region = 0;
    double best = -HUGE_VAL;
    for (size_t j = 1; j < n && rc == BKF_OK; j++) {
        if ((tr[j] > 0.0) != (tr[j - 1] > 0.0)) region++;
        double here = fabs(tr[j]);
        if (!(here >= fabs(tr[j - 1]) && here > fabs(tr[j + 1]))) continue;
        double sign = tr[j] > 0.0 ? 1.0 : -1.0;
        /* the long-wave band's own peak is the long-wave instability */
        if (region == 0 && s->longwave > 0.0) continue;
        mults m = multipliers(tr[j], f->L);
        if (m.lambda < PEAK_FLOOR || sf->npeaks == MAX_PEAKS) continue;
        double p = dp * (double)j;
        peak pk;
        rc = refine_peak(f, sign, 1.0 + p * p, dk_of_p(p, dp), &pk, err);
        if (rc != BKF_OK) break;
        pk.region = region;
        sf->peaks[sf->npeaks++] = pk;
        if (pk.lambda > best) {
            best = pk.lambda;
            s->lambda_peak = pk.lambda;
            s->lambda_peak_err = pk.lambda_err;
            s->k2_peak = pk.K;
            s->q_peak = f->c > 0.0 ? sqrt(fmax(pk.K - 1.0, 0.0)) / f->c : 0.0;
            s->m_re = pk.m_re;
            s->m_im = pk.m_im;
        }
    }
    free(tr);
    if (rc != BKF_OK) return rc;
    s->peaks = sf->npeaks;
    if (sf->npeaks == 0) s->lambda_peak = s->lambda_peak_err = s->q_peak = s->k2_peak = s->m_re = s->m_im = NAN;
    s->stable = s->longwave < 0.0 && !(best >= 0.0);
    return BKF_OK;
}

static int floquet_stability_at_body(bkf_floquet *f, bkf_floquet_stability *out, bkf_error *err)
{
    if (!f || !f->ready)
        return bkf_error_set(err, BKF_EINPUT, "floquet: stability before a successful set");
    if (!out) return bkf_error_set(err, BKF_EINPUT, "floquet: stability result is NULL");
    stability_full *sf = malloc(sizeof *sf);
    if (!sf) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    int rc = floquet_stability_scan(f, sf, err);
    if (rc == BKF_OK) *out = sf->s;
    free(sf);
    return rc;
}

int bkf_floquet_stability_at(bkf_floquet *f, bkf_floquet_stability *out, bkf_error *err)
{
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    int rc = floquet_stability_at_body(f, out, err);
    bkf_gsl_handler_pop(handler);
    return rc;
}


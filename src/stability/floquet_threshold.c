/* The stability boundaries in nu (floquet.c): an indicator's zeros
 * located, the scan over nu, the diagram, and the threshold curve followed
 * along c or gamma.  Above the monodromy (floquet.c) and the peaks
 * (floquet_peaks.c), which it calls; nothing calls back. */
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

/* ----------------------------------------------------------- boundaries */

/* One indicator whose zero in nu is a stability boundary: the long-wave
 * coefficient, or the height of the peak of sign * trace tracked from K_a
 * (at nu_a) to K_b (at nu_b). */
typedef struct {
    bkf_floquet *f;
    const bkf_floquet_options *opt;
    double gamma, c;
    int longwave;
    double sign;
    double nu_a, K_a, nu_b, K_b, w;
    double K_last;   /* where the last evaluation found the peak */
    int status;
    bkf_error err;
} indicator;

static int indicator_eval(indicator *ind, double nu, double *value)
{
    int rc = bkf_floquet_set(ind->f, ind->gamma, ind->c, nu, ind->opt, &ind->err);
    if (rc != BKF_OK) return rc;
    if (ind->longwave) return floquet_longwave_at(ind->f, ENG_FINE, value, &ind->err);
    double t = ind->nu_b != ind->nu_a ? (nu - ind->nu_a) / (ind->nu_b - ind->nu_a) : 0.0;
    double K = ind->K_a + t * (ind->K_b - ind->K_a), v;
    rc = floquet_track_peak(ind->f, ind->sign, &K, ind->w, &v, &ind->err);
    if (rc != BKF_OK) return rc;
    ind->K_last = K;
    *value = multipliers(ind->sign * v, ind->f->L).lambda;
    return BKF_OK;
}

/* Brent's method on the indicator over [lo, hi] (values f_lo, f_hi of
 * opposite signs), to |hi - lo| <= xtol.  On return (success or not)
 * root/f_root are the best point and its value, other/f_other the opposite
 * end of the last bracket. */
typedef struct {
    double root, f_root, other, f_other, slope;
} bracket;

static int indicator_root(indicator *ind, double lo, double f_lo, double hi, double f_hi,
                          double xtol, bracket *br)
{
    /* Brent (1973), as in zeroin: b the best, c the opposite end */
    double a = lo, b = hi, c = hi, fa = f_lo, fb = f_hi, fc = f_hi, d = 0.0, e = 0.0;
    int rc = BKF_OK;
    br->slope = (f_hi - f_lo) / (hi - lo);
    for (int iter = 0; iter < 100; iter++) {
        if ((fb > 0.0) == (fc > 0.0)) {
            c = a;
            fc = fa;
            d = e = b - a;
        }
        if (fabs(fc) < fabs(fb)) {
            a = b;
            b = c;
            c = a;
            fa = fb;
            fb = fc;
            fc = fa;
        }
        double tol1 = 2.0 * DBL_EPSILON * fabs(b) + 0.5 * xtol;
        double xm = 0.5 * (c - b);
        if (fabs(xm) <= tol1 || fb == 0.0) break;
        if (fabs(e) >= tol1 && fabs(fa) > fabs(fb)) {
            double s = fb / fa, p, q, r;
            if (a == c) {
                p = 2.0 * xm * s;
                q = 1.0 - s;
            } else {
                q = fa / fc;
                r = fb / fc;
                p = s * (2.0 * xm * q * (q - r) - (b - a) * (r - 1.0));
                q = (q - 1.0) * (r - 1.0) * (s - 1.0);
            }
            if (p > 0.0) q = -q;
            p = fabs(p);
            if (2.0 * p < fmin(3.0 * xm * q - fabs(tol1 * q), fabs(e * q))) {
                e = d;
                d = p / q;
            } else {
                d = xm;
                e = d;
            }
        } else {
            d = xm;
            e = d;
        }
        double from = b, f_from = fb, trial = b + (fabs(d) > tol1 ? d : (xm > 0.0 ? tol1 : -tol1));
        double f_trial = 0.0;
        rc = indicator_eval(ind, trial, &f_trial);
        /* a cycle the engine cannot solve (the inside of a canard explosion
         * is exponentially thin in nu) need not stop the search: the bracket
         * still holds a root, try points nearer the bracket's middle */
        for (int retry = 0; bkf_status_is_numerical(rc) && retry < 4; retry++) {
            trial = from + (0.5 + 0.1 * retry) * (c - from);
            rc = indicator_eval(ind, trial, &f_trial);
        }
        if (rc != BKF_OK) {
            b = from;
            fb = f_from;
            break;
        }
        a = from;
        fa = f_from;
        b = trial;
        fb = f_trial;
        if (c != b && fc != fb) br->slope = (fc - fb) / (c - b);
    }
    br->root = b;
    br->f_root = fb;
    br->other = c;
    br->f_other = fc;
    return rc;
}

/* Past this the indicator did not go to zero in the final bracket: it
 * jumps there.  A continuous crossing with the bracket at the tolerance
 * would need a slope beyond 1e5 per unit nu to leave such a value. */
#define JUMP_VALUE 1e-3

/* Locate one indicator's zero in [nu_a, nu_b] and describe it.  On failure
 * *fail_near is the end of the last bracket nearest nu_a. */
static int locate(indicator *ind, double f_a, double f_b, bkf_floquet_threshold *th,
                  double *fail_near)
{
    bkf_floquet *f = ind->f;
    double lo = fmin(ind->nu_a, ind->nu_b), hi = fmax(ind->nu_a, ind->nu_b);
    double f_lo = ind->nu_a < ind->nu_b ? f_a : f_b, f_hi = ind->nu_a < ind->nu_b ? f_b : f_a;
    double xtol = fmax(0.5 * f->opt.tol, 1e-13);
    bracket br;
    int rc = indicator_root(ind, lo, f_lo, hi, f_hi, xtol, &br);
    if (rc != BKF_OK) {
        if (fail_near)
            *fail_near = fabs(br.root - ind->nu_a) < fabs(br.other - ind->nu_a) ? br.root : br.other;
        return rc;
    }
    double nu = br.root, v;
    int jump = fmin(fabs(br.f_root), fabs(br.f_other)) > JUMP_VALUE;
    rc = indicator_eval(ind, nu, &v);
    if (rc != BKF_OK) return rc;
    memset(th, 0, sizeof *th);
    th->gamma = ind->gamma;
    th->c = ind->c;
    th->nu = nu;
    th->discontinuous = jump;
    double value_err;
    if (ind->longwave) {
        double a, a_err;
        rc = bkf_floquet_longwave(f, &a, &a_err, &ind->err);
        if (rc != BKF_OK) return rc;
        th->kind = BKF_BOUNDARY_LONG_WAVE;
        th->k2 = 1.0;
        th->q = 0.0;
        th->m_re = 1.0;
        th->lambda = 0.0;
        th->longwave = a;
        value_err = a_err + fabs(a - v);
    } else {
        bkf_floquet_point pt;
        rc = floquet_eval_k2(f, ind->K_last, &pt, &ind->err);
        if (rc != BKF_OK) return rc;
        th->kind = ind->sign < 0.0 ? BKF_BOUNDARY_PERIOD_DOUBLING : BKF_BOUNDARY_OTHER;
        th->k2 = pt.k2;
        th->q = pt.q;
        th->m_re = pt.m1_re;
        th->m_im = pt.m1_im;
        th->lambda = pt.lambda;
        value_err = pt.lambda_err + fabs(pt.lambda - v);
        rc = bkf_floquet_longwave(f, &th->longwave, NULL, &ind->err);
        if (rc != BKF_OK) return rc;
    }
    if (jump) th->kind = BKF_BOUNDARY_OTHER;
    double slope = br.slope;
    th->nu_err = fabs(br.root - br.other) +
                 (!jump && slope != 0.0 && isfinite(slope) ? value_err / fabs(slope) : 0.0);
    return BKF_OK;
}

/* The indicators that could explain the change between a stable and an
 * unstable end; the one whose zero lies nearest the stable end is the
 * boundary (a second zero further in is inside the unstable interval). */
static int boundary_between(bkf_floquet *f, double gamma, double c, double nu_s,
                            const stability_full *st_s, double nu_u, const stability_full *st_u,
                            bkf_floquet_threshold *th, bkf_error *err)
{
    int found = 0, failed = 0;
    double fail_dist = HUGE_VAL;
    bkf_error fail_err = {0};
    double dp = f->opt.p_max / (double)f->opt.scan_points;
    indicator ind;
    bkf_floquet_threshold cand;
    if (st_u->s.longwave > 0.0 && st_s->s.longwave < 0.0) {
        memset(&ind, 0, sizeof ind);
        ind = (indicator){.f = f, .opt = &f->opt, .gamma = gamma, .c = c, .longwave = 1,
                          .nu_a = nu_s, .nu_b = nu_u};
        double near = nu_s;
        int rc = locate(&ind, st_s->s.longwave, st_u->s.longwave, &cand, &near);
        if (rc == BKF_OK) {
            *th = cand;
            found = 1;
        } else if (bkf_status_is_numerical(rc)) {
            failed = 1;
            fail_dist = fabs(near - nu_s);
            fail_err = ind.err;
        } else {
            *err = ind.err;
            return rc;
        }
    }
    for (size_t i = 0; i < st_u->npeaks; i++) {
        const peak *pu = &st_u->peaks[i];
        if (!(pu->lambda >= 0.0)) continue;
        /* the same tongue at the stable end: same sign, nearest K */
        double K_s = pu->K, best = HUGE_VAL;
        for (size_t j = 0; j < st_s->npeaks; j++) {
            const peak *ps = &st_s->peaks[j];
            if (ps->sign != pu->sign) continue;
            if (fabs(ps->K - pu->K) < best) {
                best = fabs(ps->K - pu->K);
                K_s = ps->K;
            }
        }
        double p = sqrt(fmax(pu->K - 1.0, 0.0));
        double w = fmax(fabs(K_s - pu->K), 2.0 * dk_of_p(p, dp));
        memset(&ind, 0, sizeof ind);
        ind = (indicator){.f = f, .opt = &f->opt, .gamma = gamma, .c = c, .sign = pu->sign,
                          .nu_a = nu_s, .K_a = K_s, .nu_b = nu_u, .K_b = pu->K, .w = w};
        double v_s, v_u, near = nu_s;
        int rc = indicator_eval(&ind, nu_s, &v_s);
        if (rc == BKF_OK) rc = indicator_eval(&ind, nu_u, &v_u);
        if (rc == BKF_OK && !(v_s < 0.0 && v_u >= 0.0)) continue;
        if (rc == BKF_OK) rc = locate(&ind, v_s, v_u, &cand, &near);
        if (rc == BKF_OK) {
            if (!found || fabs(cand.nu - nu_s) < fabs(th->nu - nu_s)) *th = cand;
            found = 1;
        } else if (bkf_status_is_numerical(rc)) {
            failed = 1;
            fail_dist = fmin(fail_dist, fabs(near - nu_s));
            fail_err = ind.err;
        } else {
            *err = ind.err;
            return rc;
        }
    }
    /* a candidate that failed matters only if its zero could lie nearer the
     * stable end than the boundary found */
    if (failed && (!found || fail_dist < fabs(th->nu - nu_s))) {
        *err = fail_err;
        return BKF_ENUMERIC;
    }
    if (!found)
        return bkf_error_set(err, BKF_ENUMERIC,
                             "stability changes between nu = %.10g and %.10g (gamma = %.15g) but no "
                             "indicator changes sign there",
                             nu_s, nu_u, gamma);
    th->stable_above = nu_s > nu_u;
    return BKF_OK;
}

static int check_scan_inputs(double gamma, double c, double nu_lo, double nu_hi,
                             const bkf_floquet_options *o, bkf_error *err)
{
    int rc = floquet_check_options(o, err);
    if (rc == BKF_OK) rc = floquet_check_gamma_c(gamma, c, err);
    if (rc != BKF_OK) return rc;
    if (!(c > 0.0))
        return bkf_error_set(err, BKF_EINPUT,
                             "c = %.15g: thresholds need c > 0 (with c = 0 every wavenumber is the "
                             "neutral q = 0 mode)",
                             c);
    if ((rc = bkf_model_check_nu_active(nu_lo, err)) || (rc = bkf_model_check_nu_active(nu_hi, err)))
        return rc;
    if (!(nu_lo < nu_hi))
        return bkf_error_set(err, BKF_EINPUT, "the nu range needs lo < hi (got %g, %g)", nu_lo, nu_hi);
    return BKF_OK;
}

/* Scan [nu_lo, nu_hi] upward; `each_boundary` is called for every change of
 * stability (located), `until_first` stops after the first. */
typedef int (*boundary_fn)(const bkf_floquet_threshold *th, double nu_prev, int stable_prev,
                           void *data);

static int scan_nu(double gamma, double c, double nu_lo, double nu_hi,
                   const bkf_floquet_options *o, boundary_fn each, void *data, int *first_stable,
                   int *last_stable, size_t *changes, bkf_error *err)
{
    int rc = check_scan_inputs(gamma, c, nu_lo, nu_hi, o, err);
    if (rc != BKF_OK) return rc;
    bkf_floquet *f = bkf_floquet_alloc();
    stability_full *prev = malloc(sizeof *prev), *cur = malloc(sizeof *cur);
    if (!f || !prev || !cur) {
        bkf_floquet_free(f);
        free(prev);
        free(cur);
        return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    }
    size_t n = (size_t)ceil((nu_hi - nu_lo) / o->nu_step - 1e-9);
    if (n < 1) n = 1;
    *changes = 0;
    for (size_t i = 0; i <= n && rc == BKF_OK; i++) {
        double nu = i == n ? nu_hi : nu_lo + (nu_hi - nu_lo) * (double)i / (double)n;
        rc = bkf_floquet_set(f, gamma, c, nu, o, err);
        if (rc == BKF_OK) rc = floquet_stability_scan(f, cur, err);
        if (rc != BKF_OK) break;
        if (i == 0) *first_stable = cur->s.stable;
        if (i > 0 && cur->s.stable != prev->s.stable) {
            bkf_floquet_threshold th;
            const stability_full *st_s = cur->s.stable ? cur : prev;
            const stability_full *st_u = cur->s.stable ? prev : cur;
            rc = boundary_between(f, gamma, c, st_s->s.nu, st_s, st_u->s.nu, st_u, &th, err);
            if (rc != BKF_OK) break;
            (*changes)++;
            if (each(&th, prev->s.nu, prev->s.stable, data)) break;
        }
        *last_stable = cur->s.stable;
        stability_full *t = prev;
        prev = cur;
        cur = t;
    }
    bkf_floquet_free(f);
    free(prev);
    free(cur);
    return rc;
}

static int keep_first(const bkf_floquet_threshold *th, double nu_prev, int stable_prev, void *data)
{
    (void)nu_prev;
    (void)stable_prev;
    *(bkf_floquet_threshold *)data = *th;
    return 1;
}

static int floquet_threshold_find_body(double gamma, double c, double nu_lo, double nu_hi,
                                       const bkf_floquet_options *options, bkf_floquet_threshold *out,
                                       bkf_error *err)
{
    if (!out) return bkf_error_set(err, BKF_EINPUT, "threshold result is NULL");
    bkf_floquet_options o = options ? *options : bkf_floquet_options_default();
    int first = 0, last = 0;
    size_t changes = 0;
    int rc = scan_nu(gamma, c, nu_lo, nu_hi, &o, keep_first, out, &first, &last, &changes, err);
    if (rc != BKF_OK) return rc;
    if (changes == 0) {
        /* stable or unstable throughout the scan: an answer */
        *out = (bkf_floquet_threshold){.gamma = gamma, .c = c, .nu = NAN, .nu_err = NAN,
                                       .kind = BKF_BOUNDARY_NONE, .q = NAN, .k2 = NAN,
                                       .m_re = NAN, .m_im = NAN, .lambda = NAN,
                                       .stable_above = first, .longwave = NAN};
    }
    return BKF_OK;
}

int bkf_floquet_threshold_find(double gamma, double c, double nu_lo, double nu_hi,
                               const bkf_floquet_options *options, bkf_floquet_threshold *out,
                               bkf_error *err)
{
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    int rc = floquet_threshold_find_body(gamma, c, nu_lo, nu_hi, options, out, err);
    bkf_gsl_handler_pop(handler);
    return rc;
}

/* --------------------------------------------------------------- diagram */

typedef struct {
    double gamma, c, nu_lo, nu_hi;
    bkf_floquet_interval current;
    bkf_floquet_interval_visit visit;
    void *data;
    int stopped;
} diagram_ctx;

static bkf_floquet_threshold scan_end(double gamma, double c, double nu)
{
    bkf_floquet_threshold t;
    memset(&t, 0, sizeof t);
    t.gamma = gamma;
    t.c = c;
    t.nu = nu;
    t.kind = BKF_BOUNDARY_SCAN_END;
    t.q = t.k2 = t.m_re = t.m_im = t.lambda = t.longwave = NAN;
    return t;
}

static int diagram_boundary(const bkf_floquet_threshold *th, double nu_prev, int stable_prev,
                            void *data)
{
    (void)nu_prev;
    diagram_ctx *d = data;
    d->current.stable = stable_prev;
    d->current.to = *th;
    d->current.nu_to = th->nu;
    if (d->visit(&d->current, d->data)) {
        d->stopped = 1;
        return 1;
    }
    d->current.from = *th;
    d->current.nu_from = th->nu;
    return 0;
}

static int floquet_diagram_body(double gamma, double c, double nu_lo, double nu_hi,
                                const bkf_floquet_options *options, bkf_floquet_interval_visit visit,
                                void *data, bkf_error *err)
{
    if (!visit) return bkf_error_set(err, BKF_EINPUT, "diagram visit callback is NULL");
    bkf_floquet_options o = options ? *options : bkf_floquet_options_default();
    diagram_ctx d;
    memset(&d, 0, sizeof d);
    d.gamma = gamma;
    d.c = c;
    d.nu_lo = nu_lo;
    d.nu_hi = nu_hi;
    d.visit = visit;
    d.data = data;
    d.current.from = scan_end(gamma, c, nu_lo);
    d.current.nu_from = nu_lo;
    int first = 0, last = 0;
    size_t changes = 0;
    int rc = scan_nu(gamma, c, nu_lo, nu_hi, &o, diagram_boundary, &d, &first, &last, &changes, err);
    if (rc != BKF_OK || d.stopped) return rc;
    d.current.stable = last;
    d.current.to = scan_end(gamma, c, nu_hi);
    d.current.nu_to = nu_hi;
    visit(&d.current, data);
    return BKF_OK;
}

int bkf_floquet_diagram(double gamma, double c, double nu_lo, double nu_hi,
                        const bkf_floquet_options *options, bkf_floquet_interval_visit visit,
                        void *data, bkf_error *err)
{
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    int rc = floquet_diagram_body(gamma, c, nu_lo, nu_hi, options, visit, data, err);
    bkf_gsl_handler_pop(handler);
    return rc;
}

/* ------------------------------------------------------- threshold curve */

/* Continuation unknowns: finite-q boundary u = (K, nu, s), equations
 * sign * trace - (1 + D) = 0 (a multiplier at sign * 1) and dtrace/dK = 0
 * (at the peak); long-wave boundary u = (nu, s), equation a = 0.  s is c or
 * ln gamma. */
typedef struct {
    bkf_floquet_param along;
    double gamma, c;           /* the fixed one is used */
    bkf_floquet_options opt;
    bkf_floquet *f;
    int longwave;
    double sign;
    double from, to, s_from, s_to;
    double w;                  /* peak window for polishing */
    int stable_above;
    bkf_floquet_threshold_visit visit;
    void *visit_data;
    int visit_status;
    bkf_error *err;
} branch_ctx;

static void branch_params(const branch_ctx *b, double s, double *gamma, double *c)
{
    *gamma = b->along == BKF_FLOQUET_ALONG_GAMMA ? exp(s) : b->gamma;
    *c = b->along == BKF_FLOQUET_ALONG_C ? s : b->c;
}

static int branch_eval(branch_ctx *b, double K, double nu, double s, double *g, bkf_error *err)
{
    double gamma, c;
    branch_params(b, s, &gamma, &c);
    if (!(fabs(nu) < 1.0) || !(K >= 1.0) || !(K <= K_MAX))
        return bkf_error_set(err, BKF_ENUMERIC, "threshold curve left the valid range");
    int rc = bkf_floquet_set(b->f, gamma, c, nu, &b->opt, err);
    /* any failure but memory shrinks the continuation's step */
    if (rc != BKF_OK) return rc == BKF_ENOMEM ? rc : BKF_ENUMERIC;
    if (b->longwave) return floquet_longwave_at(b->f, ENG_FINE, &g[0], err);
    raw r;
    rc = floquet_integrate(b->f, K, 1, ENG_FINE, &r, err);
    if (rc != BKF_OK) return rc;
    g[0] = b->sign * r.tr - (1.0 + exp(r.L));
    g[1] = r.dtr;
    return BKF_OK;
}

static int branch_residual(const double *u, double *g, double *jac, void *data, bkf_error *err)
{
    branch_ctx *b = data;
    int lw = b->longwave;
    size_t n = lw ? 1 : 2, N = n + 1;
    double K = lw ? 1.0 : u[0], nu = u[N - 2], s = u[N - 1];
    int rc = branch_eval(b, K, nu, s, g, err);
    if (rc != BKF_OK || !jac) return rc == BKF_ENOMEM ? rc : (rc ? BKF_ENUMERIC : BKF_OK);
    /* forward differences with steps well above the integration noise
     * (the driver's own would be ~1e-8, where noise of 1e-12 in g is a
     * 1e-4 error in the Jacobian) */
    double uh[3], g2[2];
    for (size_t j = 0; j < N; j++) {
        memcpy(uh, u, N * sizeof *u);
        double h = 1e-6 * fmax(1.0, fabs(u[j]));
        uh[j] += h;
        h = uh[j] - u[j];
        rc = branch_eval(b, lw ? 1.0 : uh[0], uh[N - 2], uh[N - 1], g2, err);
        if (rc != BKF_OK) return rc == BKF_ENOMEM ? rc : BKF_ENUMERIC;
        for (size_t i = 0; i < n; i++) jac[i * N + j] = (g2[i] - g[i]) / h;
    }
    /* put the cycle back at u: the polish after acceptance starts from it */
    return BKF_OK;
}

/* At fixed parameter, the boundary near nu0 by root finding in a bracket
 * widened until the indicator changes sign. */
static int polish(const branch_ctx *b, double gamma, double c, double K0, double nu0,
                  bkf_floquet_threshold *th, bkf_error *err)
{
    indicator ind;
    memset(&ind, 0, sizeof ind);
    ind = (indicator){.f = b->f, .opt = &b->opt, .gamma = gamma, .c = c, .longwave = b->longwave, .sign = b->sign,
                      .K_a = K0, .K_b = K0, .w = b->w};
    double delta = 1e-4;
    for (int attempt = 0; attempt < 5; attempt++, delta *= 8.0) {
        double lo = fmax(nu0 - delta, -1.0 + 1e-9), hi = fmin(nu0 + delta, 1.0 - 1e-9);
        ind.nu_a = lo;
        ind.nu_b = hi;
        double f_lo, f_hi;
        int rc = indicator_eval(&ind, lo, &f_lo);
        if (rc == BKF_OK) rc = indicator_eval(&ind, hi, &f_hi);
        if (rc != BKF_OK) {
            *err = ind.err;
            return rc;
        }
        if ((f_lo < 0.0) == (f_hi < 0.0)) continue;
        rc = locate(&ind, f_lo, f_hi, th, NULL);
        if (rc != BKF_OK) {
            *err = ind.err;
            return rc;
        }
        th->stable_above = b->stable_above;
        return BKF_OK;
    }
    return bkf_error_set(err, BKF_ENUMERIC,
                         "threshold curve: no sign change of the indicator near nu = %.10g", nu0);
}

static int branch_accept(const double *u, const double *tangent, int is_fold, void *data)
{
    (void)tangent;
    (void)is_fold;
    branch_ctx *b = data;
    size_t N = b->longwave ? 2 : 3;
    double s = u[N - 1];
    /* the ends are requested values: give them back exactly */
    double par;
    if (fabs(s - b->s_from) <= 1e-12 * fmax(1.0, fabs(s))) s = b->s_from;
    if (fabs(s - b->s_to) <= 1e-12 * fmax(1.0, fabs(s))) s = b->s_to;
    par = s == b->s_from ? b->from : s == b->s_to ? b->to
          : b->along == BKF_FLOQUET_ALONG_GAMMA ? exp(s)
                                                : s;
    double gamma = b->along == BKF_FLOQUET_ALONG_GAMMA ? par : b->gamma;
    double c = b->along == BKF_FLOQUET_ALONG_C ? par : b->c;
    bkf_floquet_threshold th;
    int rc = polish(b, gamma, c, b->longwave ? 1.0 : u[0], u[N - 2], &th, b->err);
    if (rc != BKF_OK) {
        b->visit_status = rc;
        return 1;
    }
    if (b->visit(&th, b->visit_data) != 0) {
        b->visit_status = -1;
        return 1;
    }
    return 0;
}

static int floquet_threshold_branch_body(bkf_floquet_param along, double from, double to, double gamma,
                                         double c, double nu_lo, double nu_hi,
                                         const bkf_floquet_options *options, size_t max_points,
                                         bkf_floquet_threshold_visit visit, void *data, bkf_error *err)
{
    if (!visit) return bkf_error_set(err, BKF_EINPUT, "threshold visit callback is NULL");
    if (along != BKF_FLOQUET_ALONG_C && along != BKF_FLOQUET_ALONG_GAMMA)
        return bkf_error_set(err, BKF_EINPUT, "threshold curve parameter must be c or gamma");
    bkf_floquet_options o = options ? *options : bkf_floquet_options_default();
    double g_from = along == BKF_FLOQUET_ALONG_GAMMA ? from : gamma;
    double c_from = along == BKF_FLOQUET_ALONG_C ? from : c;
    double g_to = along == BKF_FLOQUET_ALONG_GAMMA ? to : gamma;
    double c_to = along == BKF_FLOQUET_ALONG_C ? to : c;
    int rc = check_scan_inputs(g_from, c_from, nu_lo, nu_hi, &o, err);
    if (rc == BKF_OK) rc = check_scan_inputs(g_to, c_to, nu_lo, nu_hi, &o, err);
    if (rc != BKF_OK) return rc;
    if (from == to) return bkf_error_set(err, BKF_EINPUT, "threshold curve needs from != to");

    bkf_floquet_threshold start;
    rc = bkf_floquet_threshold_find(g_from, c_from, nu_lo, nu_hi, &o, &start, err);
    if (rc != BKF_OK) return rc;
    if (start.kind == BKF_BOUNDARY_NONE)
        return bkf_error_set(err, BKF_ENUMERIC,
                             "no boundary to follow: no change of stability for nu in [%.15g, "
                             "%.15g] at gamma = %.15g, c = %.15g (global oscillations %s "
                             "throughout, scan step %g)",
                             nu_lo, nu_hi, g_from, c_from, start.stable_above ? "stable" : "unstable",
                             o.nu_step);

    branch_ctx b;
    memset(&b, 0, sizeof b);
    b.along = along;
    b.gamma = gamma;
    b.c = c;
    b.opt = o;
    b.f = bkf_floquet_alloc();
    if (!b.f) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    b.longwave = start.kind == BKF_BOUNDARY_LONG_WAVE;
    b.sign = start.kind == BKF_BOUNDARY_PERIOD_DOUBLING ? -1.0 : 1.0;
    b.from = from;
    b.to = to;
    b.s_from = along == BKF_FLOQUET_ALONG_GAMMA ? log(from) : from;
    b.s_to = along == BKF_FLOQUET_ALONG_GAMMA ? log(to) : to;
    double dp = o.p_max / (double)o.scan_points;
    b.w = 2.0 * dk_of_p(sqrt(fmax(start.k2 - 1.0, 0.0)), dp);
    b.stable_above = start.stable_above;
    b.visit = visit;
    b.visit_data = data;
    b.err = err;

    double u0[3];
    size_t n = b.longwave ? 1 : 2;
    if (b.longwave) {
        u0[0] = start.nu;
        u0[1] = b.s_from;
    } else {
        u0[0] = start.k2;
        u0[1] = start.nu;
        u0[2] = b.s_from;
    }
    bkf_cont_options co = bkf_cont_options_default(n);
    co.step_max = 0.1;
    co.step_initial = 0.02;
    co.newton_tol = fmax(1e-9, 10.0 * o.tol);
    co.stop_index = (int)n;
    co.stop_min = fmin(b.s_from, b.s_to);
    co.stop_max = fmax(b.s_from, b.s_to);
    if (max_points) co.max_points = max_points;
    bkf_cont_report report;
    rc = bkf_cont_run(branch_residual, branch_accept, &b, u0, (int)n, b.s_to > b.s_from ? 1 : -1,
                      &co, &report, err);
    bkf_floquet_free(b.f);
    if (b.visit_status > 0) return b.visit_status;
    if (b.visit_status < 0) return BKF_OK;
    return rc;
}

int bkf_floquet_threshold_branch(bkf_floquet_param along, double from, double to, double gamma,
                                 double c, double nu_lo, double nu_hi,
                                 const bkf_floquet_options *options, size_t max_points,
                                 bkf_floquet_threshold_visit visit, void *data, bkf_error *err)
{
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    int rc = floquet_threshold_branch_body(along, from, to, gamma, c, nu_lo, nu_hi, options, max_points, visit, data, err);
    bkf_gsl_handler_pop(handler);
    return rc;
}

#include "bkfront/stabmap.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bkfront/continuation.h"
#include "bkfront/floquet.h"
#include "bkfront/speeds.h"
#include "bkfront/trainspec.h"

bkf_stabmap_options bkf_stabmap_options_default(void)
{
    bkf_stabmap_options o = {1e-6, 1e-3, 0.01, 1000, 0.5};
    return o;
}

const char *bkf_stabmap_end_name(bkf_stabmap_end end)
{
    static const char *const names[] = {"reached", "fold",   "no_root", "refused",
                                         "max_points", "window", "stalled"};
    return (unsigned)end < sizeof names / sizeof names[0] ? names[end] : "?";
}

/* bkf_stabmap_sigma, and in *bound the window's edge when sigma is only
 * that bound (bkf_trainspec_shown_of), else NaN: brackets use the bound's
 * sign, the point printed does not show it as sigma. */
static int sigma_and_bound(const bkf_model_params *params, size_t n, double v_near, double tol,
                           double *sigma, double *sigma_err, double *v, double *mu,
                           double *bound, bkf_error *err)
{
    bkf_speeds_options o = bkf_speeds_options_default();
    o.n_from = o.n_to = n;
    bkf_speeds_table t;
    int s = bkf_speeds_find(params, &o, &t, err);
    if (!s && t.count == 0)
        s = bkf_error_set(err, BKF_EINPUT, "n: n = %zu has no root at nu %.6g, S %.6g", n,
                          params->nu, params->S);
    size_t best = 0;
    if (!s) s = bkf_speeds_nearest(&t, v_near, &best, err);
    if (s) {
        bkf_speeds_table_free(&t);
        return s;
    }
    bkf_speeds_root root = t.roots[best];
    bkf_speeds_table_free(&t);
    bkf_trainspec_result r;
    s = bkf_trainspec_root(params, &root, tol, 1, &r, err);
    if (!s) {
        *sigma = r.sigma_max;
        *sigma_err = r.sigma_max_err;
        *v = root.v;
        *mu = root.mu;
        *bound = bkf_trainspec_shown_of(&r).bound;
    }
    bkf_trainspec_result_free(&r);
    return s;
}

int bkf_stabmap_sigma(const bkf_model_params *params, size_t n, double v_near, double tol,
                      double *sigma, double *sigma_err, double *v, double *mu, bkf_error *err)
{
    double bound;
    return sigma_and_bound(params, n, v_near, tol, sigma, sigma_err, v, mu, &bound, err);
}

/* sigma_max along S at fixed nu, the root continued by v ~ S (v = S/(n T)
 * at slowly varying T). */
typedef struct {
    bkf_model_params p;
    size_t n;
    double tol;
    double v_ref, S_ref;   /* the root followed; v_ref 0: the fastest */
    size_t evaluations;
} sigma_fn;

typedef struct {
    double S, f, err, v, mu, bound;
} sample;

static int eval_at(sigma_fn *fn, double S, sample *out, bkf_error *err)
{
    bkf_model_params p = fn->p;
    p.S = S;
    double v_near = fn->v_ref > 0 ? fn->v_ref * S / fn->S_ref : 0;
    fn->evaluations++;
    out->S = S;
    return sigma_and_bound(&p, fn->n, v_near, fn->tol, &out->f, &out->err, &out->v, &out->mu,
                           &out->bound, err);
}

static int sign_of(double f) { return f > 0 ? 1 : -1; }

/* Closes the bracket [a, b] (f of opposite signs) by the Illinois method:
 * regula falsi whose retained end's value is halved when it is kept twice,
 * so the bracket shrinks on both sides.  *jump 1: the closed bracket's ends
 * are different roots (v apart by more than the root moves over its width,
 * v ~ S): sigma_max jumps there, where a faster root is born in a fold of
 * the speed condition (n = 6 at gamma 2, c 0.3, nu -0.98, S 19.73: v 0.362
 * to 0.481, sigma_max -8e-4 to +), and changes sign without a zero. */
static int close_bracket(sigma_fn *fn, sample a, sample b, double S_tol, bkf_stabmap_point *pt,
                         int *jump, bkf_error *err)
{
    int kept = 0;
    double fa = a.f, fb = b.f;
    sample best = fabs(a.f) < fabs(b.f) ? a : b;
    for (int it = 0; it < 60 && fabs(b.S - a.S) > S_tol; it++) {
        /* sigma within its error of 0: the sign there means nothing */
        if (fabs(best.f) <= best.err) break;
        double S = (a.S * fb - b.S * fa) / (fb - fa);
        double lo = fmin(a.S, b.S), hi = fmax(a.S, b.S), w = hi - lo;
        if (!(S > lo + 0.02 * w && S < hi - 0.02 * w)) S = 0.5 * (lo + hi);
        sample m;
        int s = eval_at(fn, S, &m, err);
        if (s) return s;
        if (fabs(m.f) < fabs(best.f)) best = m;
        if (sign_of(m.f) == sign_of(a.f)) {
            a = m;
            fa = m.f;
            if (kept == -1) fb *= 0.5;
            kept = -1;
        } else {
            b = m;
            fb = m.f;
            if (kept == 1) fa *= 0.5;
            kept = 1;
        }
    }
    double w = fabs(b.S - a.S), v = fmax(a.v, b.v);
    *jump = fabs(best.f) > best.err && fabs(a.v - b.v) > 1e-3 * v + 4 * v * w / fmin(a.S, b.S);
    double slope = (b.f - a.f) / (b.S - a.S);
    double S = fabs(b.S - a.S) > S_tol ? best.S : (a.S * b.f - b.S * a.f) / (b.f - a.f);
    *pt = (bkf_stabmap_point){0};
    pt->nu = fn->p.nu;
    pt->S = S;
    /* stopped with sigma within its error of 0: on the secant the root is
     * within (|sigma| + err) / |slope| of S, less than the bracket */
    double half = 0.5 * fabs(b.S - a.S), lin = (fabs(best.f) + best.err) / fabs(slope);
    pt->S_err = fabs(b.S - a.S) > S_tol ? fmin(half, lin) : fmax(half, best.err / fabs(slope));
    pt->v = best.v;
    pt->mu = best.mu;
    int bounded = isfinite(best.bound);
    pt->sigma = bounded ? NAN : best.f;
    pt->sigma_err = bounded ? NAN : best.err;
    pt->sigma_bound = best.bound;
    pt->slope = slope;
    pt->stable_above = slope < 0;
    pt->nu_slope = NAN;
    return BKF_OK;
}

static int end_of(int status)
{
    if (status == BKF_EINPUT) return BKF_STABMAP_END_NO_ROOT;
    if (status == BKF_ETOL || status == BKF_EBUDGET) return BKF_STABMAP_END_REFUSED;
    return -1;
}

int bkf_stabmap_scan(const bkf_model_params *params, size_t n, double S_from, double S_to,
                     size_t samples, const bkf_stabmap_options *options, bkf_stabmap_point *points,
                     size_t max, size_t *count, bkf_error *err)
{
    bkf_stabmap_options o = options ? *options : bkf_stabmap_options_default();
    *count = 0;
    if (samples < 1 || !(S_from > 0) || !(S_to > 0) || !isfinite(S_from) || !isfinite(S_to))
        return bkf_error_set(err, BKF_EINPUT, "scan: S_from, S_to > 0 and samples >= 1");
    sigma_fn fn = {*params, n, o.tol, 0, 1, 0};
    sample prev = {0};
    int have = 0;
    for (size_t i = 0; i <= samples && *count < max; i++) {
        sample cur;
        double S = S_from + (S_to - S_from) * (double)i / (double)samples;
        bkf_error e;
        fn.v_ref = 0;
        int s = eval_at(&fn, S, &cur, &e);
        if (s && end_of(s) < 0) return bkf_error_set(err, s, "%s", e.message);
        if (s) {  /* no root or refused here: a gap in the scan */
            have = 0;
            continue;
        }
        if (have && sign_of(cur.f) != sign_of(prev.f)) {
            size_t before = fn.evaluations;
            fn.v_ref = cur.v;
            fn.S_ref = cur.S;
            int jump = 0;
            int st = close_bracket(&fn, prev, cur, o.S_tol, &points[*count], &jump, &e);
            if (st && end_of(st) < 0) return bkf_error_set(err, st, "%s", e.message);
            /* a jump of sigma_max is no crossing */
            if (!st && !jump) {
                /* the scan's two samples and the solve's */
                points[*count].evaluations = fn.evaluations - before + 2;
                (*count)++;
            }
        }
        prev = cur;
        have = 1;
    }
    return BKF_OK;
}

int bkf_stabmap_locate(const bkf_model_params *params, size_t n, double S_from, double S_to,
                       size_t samples, const bkf_stabmap_options *options,
                       bkf_stabmap_point *point, int *found, bkf_error *err)
{
    size_t count;
    int s = bkf_stabmap_scan(params, n, S_from, S_to, samples, options, point, 1, &count, err);
    *found = !s && count == 1;
    return s;
}

int bkf_stabmap_follow(const bkf_model_params *params, size_t n,
                       const bkf_stabmap_point *first, double nu_to,
                       const bkf_stabmap_options *options, bkf_stabmap_visit visit, void *data,
                       bkf_stabmap_report *report, bkf_error *err)
{
    bkf_stabmap_options o = options ? *options : bkf_stabmap_options_default();
    bkf_stabmap_report rep = {0};
    rep.end = BKF_STABMAP_END_REACHED;
    if (!(fabs(nu_to) < 1) || !(o.nu_step > 0))
        return bkf_error_set(err, BKF_EINPUT, "follow: nu_to in (-1, 1) and nu_step > 0");
    bkf_stabmap_point cur = *first, old = *first;
    int two = 0;
    double dir = nu_to >= first->nu ? 1 : -1;
    rep.points = 1;
    rep.evaluations = first->evaluations;
    rep.nu_end = first->nu;
    int stop = visit && visit(first, data);
    double h = o.nu_step;
    while (!stop && dir * (nu_to - cur.nu) > 1e-12) {
        if (o.max_points && rep.points >= o.max_points) {
            rep.end = BKF_STABMAP_END_POINTS;
            break;
        }
        double nu = cur.nu + dir * h;
        if (dir * (nu - nu_to) > 0) nu = nu_to;
        rep.nu_end = nu;
        double Sp = two ? cur.S + (cur.S - old.S) / (cur.nu - old.nu) * (nu - cur.nu) : cur.S;
        sigma_fn fn = {*params, n, o.tol, cur.v, cur.S, 0};
        fn.p.nu = nu;
        sample a, b;
        bkf_error e;
        int s = eval_at(&fn, Sp, &a, &e);
        /* Towards the boundary: the side a lies on, by the sign it has. */
        int above = cur.stable_above ? a.f < 0 : a.f > 0;
        double delta = fmax(fmax(2 * fabs(Sp - cur.S), 4 * cur.S_err), 0.01 * cur.S);
        int bracketed = 0;
        for (int k = 0; !s && k < 4 && !bracketed; k++, delta *= 2) {
            s = eval_at(&fn, above ? Sp - delta : Sp + delta, &b, &e);
            if (!s && sign_of(b.f) != sign_of(a.f)) bracketed = 1;
        }
        rep.evaluations += fn.evaluations;
        if (s) {
            int end = end_of(s);
            if (end < 0) return bkf_error_set(err, s, "%s", e.message);
            rep.end = (bkf_stabmap_end)end;
            snprintf(rep.note, sizeof rep.note, "at nu %.6g: %.200s", nu, e.message);
            break;
        }
        if (!bracketed) {
            if (h > o.nu_step / 4) {  /* a smaller step before giving up */
                h *= 0.5;
                continue;
            }
            rep.end = BKF_STABMAP_END_FOLD;
            snprintf(rep.note, sizeof rep.note,
                     "at nu %.6g: no sign change of sigma_max in S within %.4g of %.6g", nu,
                     delta / 2, Sp);
            break;
        }
        bkf_stabmap_point next;
        fn.evaluations = 0;
        int jump = 0;
        s = close_bracket(&fn, a, b, o.S_tol, &next, &jump, err);
        rep.evaluations += fn.evaluations;
        if (!s && jump) {
            rep.end = BKF_STABMAP_END_FOLD;
            snprintf(rep.note, sizeof rep.note,
                     "at nu %.6g: sigma_max jumps at S %.6g, no zero: the root continued ends "
                     "there (v %.6g, another root beyond)", nu, next.S, cur.v);
            break;
        }
        if (s) {
            int end = end_of(s);
            if (end < 0) return s;
            rep.end = (bkf_stabmap_end)end;
            snprintf(rep.note, sizeof rep.note, "at nu %.6g: %.200s", nu, err ? err->message : "");
            break;
        }
        next.evaluations = fn.evaluations + (size_t)2;
        old = cur;
        cur = next;
        two = 1;
        rep.points++;
        stop = visit && visit(&cur, data);
    }
    if (report) *report = rep;
    return BKF_OK;
}

/* ------------------------------------------------------------------ trace */

/* Spectra kept for reuse: the driver evaluates the start twice (its
 * correction, its tangent), and each accepted point is the last spectrum. */
#define TRACE_CACHE 4
/* Halvings of the arclength step before a curve is given up as stalled:
 * each costs a spectrum or two. */
#define TRACE_STEP_MIN (1.0 / 64)

typedef struct {
    double nu, S;
    sample s;
} trace_eval;

typedef struct {
    sigma_fn fn;
    double scale[2];
    double grad[2];        /* d sigma_max / d(nu, S), Broyden-updated */
    trace_eval cache[TRACE_CACHE], last, prev; /* prev: the last point inside */
    size_t cached, next;
    int have_last, have_prev;
    int failed;            /* the last refusal's end kind, or -1 */
    bkf_error why;
    double S_lo, S_hi;
    bkf_stabmap_visit visit;
    void *data;
    bkf_stabmap_report rep;
    size_t max_points, at_last_point;
    double newton_tol;     /* the driver's */
} trace_ctx;

static const trace_eval *trace_cached(const trace_ctx *t, double nu, double S)
{
    for (size_t i = 0; i < t->cached; i++)
        if (t->cache[i].nu == nu && t->cache[i].S == S) return &t->cache[i];
    return NULL;
}

/* Broyden's rank-one secant update in the scaled coordinates, from the
 * previous spectrum to this one, where the change is above the noise
 * (sigma_err): steps along the curve turn the gradient normal to it,
 * Newton's steps across it correct its length. */
static void trace_broyden(trace_ctx *t, const trace_eval *e)
{
    if (t->have_last) {
        double w[2] = {(e->nu - t->last.nu) / t->scale[0], (e->S - t->last.S) / t->scale[1]};
        double G[2] = {t->grad[0] * t->scale[0], t->grad[1] * t->scale[1]};
        double ww = w[0] * w[0] + w[1] * w[1], df = e->s.f - t->last.s.f;
        double pred = G[0] * w[0] + G[1] * w[1], noise = e->s.err + t->last.s.err;
        int bounded = isfinite(e->s.bound) || isfinite(t->last.s.bound);
        if (ww > 1e-16 && !bounded && noise < 0.05 * fmax(fabs(df), fabs(pred))) {
            for (int i = 0; i < 2; i++) G[i] += (df - pred) * w[i] / ww;
            t->grad[0] = G[0] / t->scale[0];
            t->grad[1] = G[1] / t->scale[1];
        }
    }
    t->last = *e;
    t->have_last = 1;
}

/* sigma_max at (nu, S) into *out (cached, the gradient updated); BKF_OK, a
 * refusal's status (t->failed says which), or another failure. */
static int trace_eval_at(trace_ctx *t, double nu, double S, trace_eval *out, bkf_error *err)
{
    const trace_eval *hit = trace_cached(t, nu, S);
    if (hit) {
        *out = *hit;
        return BKF_OK;
    }
    out->nu = nu;
    out->S = S;
    t->fn.p.nu = nu;
    int s = eval_at(&t->fn, S, &out->s, err);
    if (s) {
        t->failed = end_of(s);
        if (t->failed >= 0) {
            snprintf(t->why.message, sizeof t->why.message, "at nu %.6g, S %.6g: %.200s", nu, S,
                     err ? err->message : "");
            t->why.status = s;
        }
        return s;
    }
    t->failed = -1;
    /* the root followed: the next v is predicted from this one */
    t->fn.v_ref = out->s.v;
    t->fn.S_ref = S;
    t->cache[t->next] = *out;
    t->next = (t->next + 1) % TRACE_CACHE;
    if (t->cached < TRACE_CACHE) t->cached++;
    trace_broyden(t, out);
    return BKF_OK;
}

/* u is the last spectrum's point moved by a Newton step the driver judged
 * converged: the driver asks there only for the tangent (the Jacobian),
 * and the point reported is the last spectrum's, whose distance to the
 * zero its S_err and nu_err give. */
static int converged_from_last(const trace_ctx *t, const double *u)
{
    if (!t->have_last || trace_cached(t, u[0], u[1])) return 0;
    const double last[2] = {t->last.nu, t->last.S};
    for (int i = 0; i < 2; i++)
        if (fabs(u[i] - last[i]) > t->newton_tol * fmax(fabs(u[i]), t->scale[i])) return 0;
    return 1;
}

static int trace_residual(const double *u, double *g, double *jac, void *data, bkf_error *err)
{
    trace_ctx *t = data;
    if (!(fabs(u[0]) < 1) || !(u[1] > 0))
        return bkf_error_set(err, BKF_ENUMERIC, "nu %.6g, S %.6g: outside the model's range",
                             u[0], u[1]);
    if (converged_from_last(t, u)) {
        /* the linear model, no spectrum: the driver uses only the Jacobian */
        g[0] = t->last.s.f + t->grad[0] * (u[0] - t->last.nu) + t->grad[1] * (u[1] - t->last.S);
        if (jac) {
            jac[0] = t->grad[0];
            jac[1] = t->grad[1];
        }
        return BKF_OK;
    }
    trace_eval e;
    int s = trace_eval_at(t, u[0], u[1], &e, err);
    /* No root, or a refused spectrum, at a trial point (a predictor past
     * the existence boundary, a Newton iterate off the curve): a shorter
     * step is tried; when the step can shrink no more the curve ends there,
     * with this reason. */
    if (s == BKF_EINPUT || end_of(s) >= 0) return BKF_ENUMERIC;
    if (s) return s;
    g[0] = e.s.f;
    if (jac) {
        jac[0] = t->grad[0];
        jac[1] = t->grad[1];
    }
    return BKF_OK;
}

static bkf_stabmap_point trace_point(trace_ctx *t, const trace_eval *e)
{
    bkf_stabmap_point pt = {0};
    pt.nu = e->nu;
    pt.S = e->S;
    double miss = fabs(e->s.f) + e->s.err;
    pt.S_err = miss / fabs(t->grad[1]);
    pt.nu_err = miss / fabs(t->grad[0]);
    pt.v = e->s.v;
    pt.mu = e->s.mu;
    int bounded = isfinite(e->s.bound);
    pt.sigma = bounded ? NAN : e->s.f;
    pt.sigma_err = bounded ? NAN : e->s.err;
    pt.sigma_bound = e->s.bound;
    pt.slope = t->grad[1];
    pt.nu_slope = t->grad[0];
    pt.stable_above = t->grad[1] < 0;
    pt.evaluations = t->fn.evaluations - t->at_last_point;
    t->at_last_point = t->fn.evaluations;
    return pt;
}

/* The curve left the window in S between the last point inside and e:
 * its crossing of the edge S = Sb, by the Illinois method in nu between
 * the two points' nu (a computed spectrum, as every point), into *out;
 * 0 when the edge shows no sign change between them or a spectrum fails. */
static int trace_land(trace_ctx *t, const trace_eval *e, double Sb, trace_eval *out)
{
    trace_eval a, b;
    bkf_error err;
    if (trace_eval_at(t, t->prev.nu, Sb, &a, &err) || trace_eval_at(t, e->nu, Sb, &b, &err))
        return 0;
    if ((a.s.f > 0) == (b.s.f > 0)) return 0;
    double fa = a.s.f, fb = b.s.f, tol = t->newton_tol * fmax(fabs(e->nu), t->scale[0]);
    trace_eval best = fabs(a.s.f) < fabs(b.s.f) ? a : b;
    int kept = 0;
    for (int it = 0; it < 30 && fabs(b.nu - a.nu) > tol && fabs(best.s.f) > best.s.err; it++) {
        double nu = (a.nu * fb - b.nu * fa) / (fb - fa), lo = fmin(a.nu, b.nu),
               hi = fmax(a.nu, b.nu);
        if (!(nu > lo + 0.02 * (hi - lo) && nu < hi - 0.02 * (hi - lo))) nu = 0.5 * (lo + hi);
        trace_eval m;
        if (trace_eval_at(t, nu, Sb, &m, &err)) return 0;
        if (fabs(m.s.f) < fabs(best.s.f)) best = m;
        if ((m.s.f > 0) == (a.s.f > 0)) {
            a = m;
            fa = m.s.f;
            if (kept == -1) fb *= 0.5;
            kept = -1;
        } else {
            b = m;
            fb = m.s.f;
            if (kept == 1) fa *= 0.5;
            kept = 1;
        }
    }
    *out = best;
    return 1;
}

static int trace_accept(const double *u, const double *tangent, int is_fold, void *data)
{
    (void)tangent;
    (void)is_fold;
    trace_ctx *t = data;
    trace_eval e;
    bkf_error err;
    /* the point is the last spectrum, within Newton's tolerance of u */
    if (converged_from_last(t, u))
        e = t->last;
    else if (trace_eval_at(t, u[0], u[1], &e, &err)) {
        t->rep.end = t->failed >= 0 ? (bkf_stabmap_end)t->failed : BKF_STABMAP_END_STALLED;
        snprintf(t->rep.note, sizeof t->rep.note, "%.250s",
                 t->failed >= 0 ? t->why.message : err.message);
        return 1;
    }
    if (e.S < t->S_lo || e.S > t->S_hi) {
        /* the point outside is not drawn; the crossing of the edge is */
        double Sb = e.S > t->S_hi ? t->S_hi : t->S_lo;
        trace_eval edge;
        int landed = t->have_prev && trace_land(t, &e, Sb, &edge);
        t->rep.end = BKF_STABMAP_END_WINDOW;
        snprintf(t->rep.note, sizeof t->rep.note,
                 "left S in [%.6g, %.6g] towards nu %.6g, S %.6g%s", t->S_lo, t->S_hi, e.nu, e.S,
                 landed ? "; its crossing of the edge computed" : "; the edge not located");
        if (landed) {
            bkf_stabmap_point pt = trace_point(t, &edge);
            t->rep.points++;
            t->rep.nu_end = pt.nu;
            if (t->visit) t->visit(&pt, t->data);
        }
        return 1;
    }
    bkf_stabmap_point pt = trace_point(t, &e);
    t->prev = e;
    t->have_prev = 1;
    t->rep.points++;
    t->rep.nu_end = pt.nu;
    if (t->visit && t->visit(&pt, t->data)) return 1;
    if (t->rep.points >= t->max_points) {
        t->rep.end = BKF_STABMAP_END_POINTS;
        return 1;
    }
    return 0;
}

int bkf_stabmap_trace(const bkf_model_params *params, size_t n, const bkf_stabmap_point *first,
                      int direction, const bkf_stabmap_window *window,
                      const bkf_stabmap_options *options, bkf_stabmap_visit visit, void *data,
                      bkf_stabmap_report *report, bkf_error *err)
{
    bkf_stabmap_options o = options ? *options : bkf_stabmap_options_default();
    if (report) *report = (bkf_stabmap_report){0};
    if (!params || !first || !window || (direction != 1 && direction != -1))
        return bkf_error_set(err, BKF_EINPUT, "trace: params, first, window and direction +-1");
    const bkf_stabmap_window *w = window;
    if (!(w->nu_lo < w->nu_hi) || !(w->nu_lo > -1) || !(w->nu_hi < 1) || !(w->S_lo < w->S_hi) ||
        !(w->S_lo > 0) || !isfinite(w->S_hi))
        return bkf_error_set(err, BKF_EINPUT,
                             "trace: window nu_lo < nu_hi in (-1, 1), 0 < S_lo < S_hi finite");
    if (!(first->nu >= w->nu_lo && first->nu <= w->nu_hi) || !(first->S > 0))
        return bkf_error_set(err, BKF_EINPUT, "trace: first point nu %.6g outside [%.6g, %.6g]",
                             first->nu, w->nu_lo, w->nu_hi);
    if (!(o.nu_step > 0) || !(o.S_step > 0) || !(o.S_tol > 0) || o.max_points < 1)
        return bkf_error_set(err, BKF_EINPUT, "trace: nu_step, S_step, S_tol > 0, max_points >= 1");
    trace_ctx t;
    memset(&t, 0, sizeof t);
    t.fn = (sigma_fn){*params, n, o.tol, first->v, first->S, 0};
    t.scale[0] = o.nu_step;
    t.scale[1] = o.S_step;
    t.failed = -1;
    t.S_lo = w->S_lo;
    t.S_hi = w->S_hi;
    t.visit = visit;
    t.data = data;
    t.max_points = o.max_points;
    t.rep.end = BKF_STABMAP_END_REACHED;
    t.rep.nu_end = first->nu;
    int s = BKF_OK;
    /* Already on the edge it would leave by: nothing to follow. */
    if ((direction > 0 && first->nu >= w->nu_hi) || (direction < 0 && first->nu <= w->nu_lo)) {
        t.rep.points = 1;
        if (visit) visit(first, data);
        goto done;
    }
    /* The start's gradient: d sigma / dS from its bracket, d sigma / d nu
     * from a difference along the way it goes. */
    trace_eval e0, e1;
    double h = 0.25 * o.nu_step * direction;
    if (first->nu + h > w->nu_hi || first->nu + h < w->nu_lo) h = -h;
    bkf_error e;
    s = trace_eval_at(&t, first->nu, first->S, &e0, &e);
    if (!s) s = trace_eval_at(&t, first->nu + h, first->S, &e1, &e);
    if (s) goto failed;
    t.grad[0] = (e1.s.f - e0.s.f) / h;
    t.grad[1] = isfinite(first->slope) && first->slope != 0 ? first->slope : NAN;
    if (!isfinite(t.grad[1])) {
        trace_eval e2;
        double hS = 0.25 * o.S_step;
        s = trace_eval_at(&t, first->nu, first->S + hS, &e2, &e);
        if (s) goto failed;
        t.grad[1] = (e2.s.f - e0.s.f) / hS;
    }
    t.last = e0; /* the driver's first evaluation is at the start */
    bkf_cont_options co = bkf_cont_options_default(1);
    co.scale = t.scale;
    /* the largest step from the start: the driver grows a step only
     * after corrections of two iterations, which a secant gradient rarely
     * gives, and shrinks it on failure */
    co.step_initial = 1;
    co.step_max = 1;
    co.step_min = TRACE_STEP_MIN;
    /* Newton's step judged against max(|u_i|, scale_i): S to within S_tol,
     * nu to within the same distance in the scaled norm (a steep curve's S
     * at fixed nu is then known to S_err, which says how well). */
    double nu_mag = fmax(fmax(fabs(w->nu_lo), fabs(w->nu_hi)), o.nu_step);
    co.newton_tol = fmin(o.S_tol / fmax(w->S_hi, o.S_step), o.S_tol * o.nu_step / (o.S_step * nu_mag));
    t.newton_tol = co.newton_tol;
    co.newton_max_iter = 5;
    co.max_points = o.max_points + 1;
    co.stop_index = 0;
    co.stop_min = w->nu_lo;
    co.stop_max = w->nu_hi;
    double u0[2] = {first->nu, first->S};
    bkf_cont_report cr;
    s = bkf_cont_run(trace_residual, trace_accept, &t, u0, 0, direction, &co, &cr, &e);
    if (!s) {
        if (cr.reached_bound) t.rep.end = BKF_STABMAP_END_REACHED;
        goto done;
    }
failed:
    if (s == BKF_ENUMERIC) {
        t.rep.end = t.failed >= 0 ? (bkf_stabmap_end)t.failed : BKF_STABMAP_END_STALLED;
        snprintf(t.rep.note, sizeof t.rep.note, "%.250s",
                 t.failed >= 0 ? t.why.message : e.message);
        s = BKF_OK;
    } else if (end_of(s) >= 0) {
        t.rep.end = (bkf_stabmap_end)end_of(s);
        snprintf(t.rep.note, sizeof t.rep.note, "%.250s", t.why.message);
        s = BKF_OK;
    } else {
        bkf_error_set(err, s, "%s", e.message);
    }
done:
    t.rep.evaluations = t.fn.evaluations;
    if (report) *report = t.rep;
    return s;
}

int bkf_stabmap_existence(const bkf_model_params *params, size_t n, double *S, int *attained,
                          bkf_error *err)
{
    if (!(params->c > 0))
        return bkf_error_set(err, BKF_EINPUT, "c: existence boundary needs c > 0");
    bkf_speeds_options o = bkf_speeds_options_default();
    o.n_from = o.n_to = n;
    bkf_speeds_table t;
    int s = bkf_speeds_find(params, &o, &t, err);
    if (!s) {
        *S = (double)n * params->c * params->gamma * t.g_inf;
        *attained = t.dips_below_k;
    }
    bkf_speeds_table_free(&t);
    return s;
}

/* lambda at c q = p, and whether its dominant multiplier is real negative. */
static int lambda_at(bkf_floquet *f, double c, double p, double *lambda, int *negative,
                     bkf_error *err)
{
    bkf_floquet_point pt;
    int s = bkf_floquet_eval(f, p / c, &pt, err);
    /* a sign is all the bands need: an estimate above tol still has it
     * unless lambda is within its error of 0 */
    if (s == BKF_ETOL && isfinite(pt.lambda_err)) s = BKF_OK;
    if (!s) {
        *lambda = pt.lambda;
        *negative = pt.kind == BKF_FLOQUET_REAL_NEGATIVE;
    }
    return s;
}

int bkf_stabmap_bands(double gamma, double c, double nu, double p_max, size_t samples,
                      double tol, double *lo, double *hi, int *kind, size_t max,
                      size_t *count, bkf_error *err)
{
    *count = 0;
    if (!(c > 0) || !(p_max > 0) || samples < 2)
        return bkf_error_set(err, BKF_EINPUT, "bands: c > 0, p_max > 0, samples >= 2");
    bkf_floquet *f = bkf_floquet_alloc();
    if (!f) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    bkf_floquet_options fo = bkf_floquet_options_default();
    fo.tol = 1e-8;
    int s = bkf_floquet_set(f, gamma, c, nu, &fo, err);
    double a = 0, a_err = 0;
    if (!s) s = bkf_floquet_longwave(f, &a, &a_err, err);
    /* at p -> 0+, lambda ~ a p^2: the sign of a */
    int unstable = a > 0, neg = 0, band_neg = 0;
    double p_prev = 0;
    double start = 0;
    for (size_t i = 1; !s && i <= samples; i++) {
        double p = p_max * (double)i / (double)samples, l;
        s = lambda_at(f, c, p, &l, &neg, err);
        if (s) break;
        if (unstable && l > 0 && neg) band_neg = 1;
        if ((l > 0) != unstable) {
            /* the edge between p_prev and p by bisection on the sign */
            double x0 = p_prev, x1 = p;
            while (!s && x1 - x0 > tol) {
                double xm = 0.5 * (x0 + x1), lm = 0;
                int nm = 0;
                s = lambda_at(f, c, xm, &lm, &nm, err);
                if (s) break;
                if ((lm > 0) == unstable)
                    x0 = xm;
                else
                    x1 = xm;
                if (unstable && lm > 0 && nm) band_neg = 1;
            }
            double edge = 0.5 * (x0 + x1);
            if (!unstable) {
                start = edge;
                band_neg = neg && l > 0;
            } else if (*count < max) {
                lo[*count] = start;
                hi[*count] = edge;
                kind[*count] = band_neg;
                (*count)++;
            }
            unstable = !unstable;
        }
        p_prev = p;
    }
    if (!s && unstable && *count < max) { /* a band open at p_max */
        lo[*count] = start;
        hi[*count] = p_max;
        kind[*count] = band_neg;
        (*count)++;
    }
    bkf_floquet_free(f);
    return s;
}

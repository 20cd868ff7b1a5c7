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
    bkf_stabmap_options o = {1e-6, 1e-3, 0.01, 1000, 0.5, NULL, NULL};
    return o;
}

const char *bkf_stabmap_end_name(bkf_stabmap_end end)
{
    static const char *const names[] = {"reached", "fold",   "no_root", "refused",
                                         "max_points", "window", "stalled", "closed"};
    return (unsigned)end < sizeof names / sizeof names[0] ? names[end] : "?";
}

/* bkf_stabmap_sigma, and in *bound the window's edge when sigma is only
 * that bound (bkf_trainspec_shown_of), else NaN: brackets use the bound's
 * sign, the point printed does not show it as sigma. */
/* One sigma_max at S. */
typedef struct {
    double S, f, err, v, mu, bound;
    /* the rightmost eigenvalue but the translation: its Bloch class and
     * Im sigma (have_mode 0: the spectrum had none, sigma was a bound) */
    size_t j;
    double im;
    int have_mode;
    int tracked; /* f is that one eigenvalue continued (trace_tracked), no full spectrum */
    int vouched; /* trace: tracked, and the runner-up continued left of it (trace_vouch) */
    /* a ring spectrum's runner-up: the rightmost eigenvalue but the
     * translation, the rightmost and its conjugate (have_second 0: none) */
    int have_second;
    size_t j2;
    double f2, im2;
} sample;

/* Roots of one speeds table kept (a table has one to three here). */
#define ROOT_MEMO 4
/* Ring spectra kept: a bracket's end is asked for again by the Illinois
 * method that closes it (the paper scene's seeds: 3 of 62 ring spectra
 * were a second one at the same point and root). */
#define RING_MEMO 4

/* sigma_max along S at fixed nu, the root continued by v ~ S (v = S/(n T)
 * at slowly varying T); every ring spectrum and tracked eigenvalue of the
 * map is computed through one and counted there. */
typedef struct {
    bkf_model_params p;
    size_t n;
    double tol;
    double v_ref, S_ref;   /* the root followed; v_ref 0: the fastest */
    bkf_stabmap_spectrum_fn spectrum;
    void *spectrum_data;
    /* the ring spectrum's per_kappa (the default spectrum's): 0, the
     * rightmost alone, where sigma_max and its class are all that is read;
     * 1 in the trace, which also reads the runner-up (trace_vouch) */
    size_t per_kappa;
    size_t spectra;        /* ring spectra computed (a refused one too) */
    size_t tracked;        /* eigenvalues continued alone (tracked_sample) */
    double fastest_S, fastest_v; /* a scan down in S: the last sample's fastest root */
    /* The last point's roots of n: a point is asked for twice (a tracked
     * eigenvalue that proves nothing, then the ring spectrum there), and a
     * speeds table costs 4 to 25 ms, more than the tracked eigenvalue. */
    int memo_have;
    double memo_nu, memo_S;
    size_t memo_count;
    bkf_speeds_root memo[ROOT_MEMO];
    sample ring[RING_MEMO]; /* the last ring spectra (nu in ring_nu), oldest overwritten */
    double ring_nu[RING_MEMO];
    size_t rings, ring_next;
} sigma_fn;

static sigma_fn sigma_fn_of(const bkf_model_params *params, size_t n,
                            const bkf_stabmap_options *o, double v_ref, double S_ref)
{
    sigma_fn fn = {.p = *params, .n = n, .tol = o->tol, .v_ref = v_ref, .S_ref = S_ref,
                   .spectrum = o->spectrum, .spectrum_data = o->spectrum_data};
    return fn;
}

/* The root of fn's n at params nearest v_near (v_near <= 0: the fastest). */
static int root_near(sigma_fn *fn, const bkf_model_params *params, double v_near,
                     bkf_speeds_root *root, bkf_error *err)
{
    bkf_speeds_table t = {0};
    int memo = fn->memo_have && fn->memo_nu == params->nu && fn->memo_S == params->S;
    /* A root continued (v_near predicted from a nearby one): the speed
     * condition solved from v_near, a few shots of T (0.5 to 4.5 ms where
     * the table costs 4 to 25 ms); where that finds none (a fold passed),
     * the table's nearest */
    if (!memo && v_near > 0 && !bkf_speeds_near(params, fn->n, v_near, NULL, root, NULL))
        return BKF_OK;
    /* The fastest root one step down in S from a fastest root (fastest_S,
     * fastest_v): going down, the level S / (n c gamma) falls and the first
     * crossing of g moves on to larger s, none born before it (g stays
     * above the old level there); the root continued is the fastest while
     * it exists and has moved as a root does (v ~ S: roots_apart's rule),
     * else (a fold: it and its pair are gone) the table says which is. */
    if (!memo && !(v_near > 0) && fn->fastest_v > 0 && params->S < fn->fastest_S &&
        params->nu == fn->p.nu) {
        double pred = fn->fastest_v * params->S / fn->fastest_S;
        double w = fn->fastest_S - params->S;
        if (!bkf_speeds_near(params, fn->n, pred, NULL, root, NULL) &&
            fabs(root->v - pred) <= 1e-3 * pred + 4 * pred * w / params->S)
            return BKF_OK;
    }
    int s = BKF_OK;
    if (memo) {
        t.roots = fn->memo;
        t.count = fn->memo_count;
    } else {
        bkf_speeds_options o = bkf_speeds_options_default();
        o.n_from = o.n_to = fn->n;
        s = bkf_speeds_find(params, &o, &t, err);
        fn->memo_have = !s && t.count <= ROOT_MEMO;
        if (fn->memo_have) {
            fn->memo_nu = params->nu;
            fn->memo_S = params->S;
            fn->memo_count = t.count;
            if (t.count) memcpy(fn->memo, t.roots, t.count * sizeof *t.roots);
        }
    }
    if (!s && t.count == 0)
        s = bkf_error_set(err, BKF_EINPUT, "n: n = %zu has no root at nu %.6g, S %.6g", fn->n,
                          params->nu, params->S);
    size_t best = 0;
    if (!s) s = bkf_speeds_nearest(&t, v_near, &best, err);
    if (!s) *root = t.roots[best];
    if (!memo) bkf_speeds_table_free(&t);
    return s;
}

/* The ring spectrum r's runner-up to its eigenvalue `top` into out (j2,
 * f2, im2): the rightmost of the others but the translation and top's
 * conjugate (class n - j, -Im sigma: the same real part). */
static void runner_up(const bkf_trainspec_result *r, size_t top, size_t n, sample *out)
{
    const bkf_trainspec_eigenvalue *t = &r->eigenvalues[top];
    for (size_t i = 0; i < r->count; i++) {
        const bkf_trainspec_eigenvalue *ev = &r->eigenvalues[i];
        int conjugate = ev->j == (n - t->j) % n && fabs(ev->im + t->im) <= 1e-6 * (1 + fabs(t->im)) &&
                        fabs(ev->re - t->re) <= 1e-6 * (1 + fabs(t->re));
        if (i == top || ev->translation || conjugate || (out->have_second && ev->re <= out->f2))
            continue;
        out->have_second = 1;
        out->j2 = ev->j;
        out->f2 = ev->re;
        out->im2 = ev->im;
    }
}

/* sigma_max of the root nearest v_near into *out (S, f, err, v, mu, bound,
 * the rightmost's class). */
static int spectrum_sample(sigma_fn *fn, const bkf_model_params *params, double v_near,
                           sample *out, bkf_error *err)
{
    bkf_speeds_root root;
    int s = root_near(fn, params, v_near, &root, err);
    if (s) return s;
    for (size_t i = 0; i < fn->rings; i++)
        if (fn->ring_nu[i] == params->nu && fn->ring[i].S == params->S && fn->ring[i].v == root.v) {
            *out = fn->ring[i];
            return BKF_OK;
        }
    bkf_trainspec_result r;
    s = fn->spectrum ? fn->spectrum(params, &root, fn->tol, &r, err, fn->spectrum_data)
                     : bkf_trainspec_root(params, &root, fn->tol, fn->per_kappa, &r, err);
    fn->spectra++;
    if (!s) {
        *out = (sample){.S = params->S, .f = r.sigma_max, .err = r.sigma_max_err, .v = root.v,
                        .mu = root.mu, .bound = bkf_trainspec_shown_of(&r).bound};
        for (size_t i = 0; i < r.count && !r.sigma_is_bound; i++) {
            const bkf_trainspec_eigenvalue *ev = &r.eigenvalues[i];
            if (ev->translation || (out->have_mode && ev->re <= r.eigenvalues[out->j].re))
                continue;
            out->have_mode = 1;
            out->j = i; /* the index for now, the class below */
        }
        if (out->have_mode) {
            size_t top = out->j;
            out->im = r.eigenvalues[top].im;
            out->j = r.eigenvalues[top].j;
            runner_up(&r, top, fn->n, out);
        }
        fn->ring[fn->ring_next] = *out;
        fn->ring_nu[fn->ring_next] = params->nu;
        fn->ring_next = (fn->ring_next + 1) % RING_MEMO;
        if (fn->rings < RING_MEMO) fn->rings++;
    }
    bkf_trainspec_result_free(&r);
    return s;
}

/* One eigenvalue of class `from`->j continued from `from` (re = f, im) to
 * the root of n at params nearest v_near (v_near <= 0: the fastest), by
 * Newton on that class alone (bkf_trainspec_track: one cycle, meshes of 1,
 * 2, ... substeps until their difference meets tol; about 1/20 of a ring
 * spectrum), into *out (tracked 1: f is that eigenvalue, not sigma_max,
 * which is at least f).  A failure (Newton, the root, tol not met) means
 * only that the ring spectrum is needed. */
static int tracked_sample(sigma_fn *fn, const bkf_model_params *params, double v_near,
                          const sample *from, sample *out, bkf_error *err)
{
    bkf_speeds_root root;
    int s = root_near(fn, params, v_near, &root, err);
    if (s) return s;
    bkf_trainspec_train train = {fn->n, root.v};
    bkf_trainspec_eigenvalue a = {.re = from->f, .im = from->im, .j = from->j}, b;
    size_t followed = 0;
    fn->tracked++;
    s = bkf_trainspec_track(params, &train, fn->tol, 1, &a, &b, &followed, err);
    if (s) return s;
    if (!followed) return bkf_error_set(err, BKF_ENUMERIC, "not followed");
    *out = (sample){.S = params->S, .f = b.re, .err = b.err, .v = root.v, .mu = root.mu,
                    .bound = NAN, .j = from->j, .im = b.im, .have_mode = 1, .tracked = 1};
    return BKF_OK;
}

int bkf_stabmap_sigma(const bkf_model_params *params, size_t n, double v_near,
                      const bkf_stabmap_options *options, double *sigma, double *sigma_err,
                      double *v, double *mu, size_t *spectra, bkf_error *err)
{
    bkf_stabmap_options o = options ? *options : bkf_stabmap_options_default();
    sigma_fn fn = sigma_fn_of(params, n, &o, 0, 1);
    sample x;
    int s = spectrum_sample(&fn, params, v_near, &x, err);
    if (spectra) *spectra += fn.spectra;
    if (!s) {
        *sigma = x.f;
        *sigma_err = x.err;
        *v = x.v;
        *mu = x.mu;
    }
    return s;
}

/* sigma_max at S (fn's nu), the root continued from (v_ref, S_ref). */
static int eval_at(sigma_fn *fn, double S, sample *out, bkf_error *err)
{
    bkf_model_params p = fn->p;
    p.S = S;
    double v_near = fn->v_ref > 0 ? fn->v_ref * S / fn->S_ref : 0;
    return spectrum_sample(fn, &p, v_near, out, err);
}

/* The eigenvalue `from` continued to S (fn's nu), the root likewise. */
static int tracked_at(sigma_fn *fn, double S, const sample *from, sample *out, bkf_error *err)
{
    bkf_model_params p = fn->p;
    p.S = S;
    double v_near = fn->v_ref > 0 ? fn->v_ref * S / fn->S_ref : 0;
    return tracked_sample(fn, &p, v_near, from, out, err);
}

static int sign_of(double f) { return f > 0 ? 1 : -1; }

/* Closes the bracket [a, b] (f of opposite signs) by the Illinois method:
 * regula falsi whose retained end's value is halved when it is kept twice,
 * so the bracket shrinks on both sides.  *jump 1: the closed bracket's ends
 * are different roots (v apart by more than the root moves over its width,
 * v ~ S): sigma_max jumps there, where a faster root is born in a fold of
 * the speed condition (n = 6 at gamma 2, c 0.3, nu -0.98, S 19.73: v 0.362
 * to 0.481, sigma_max -8e-4 to +), and changes sign without a zero. */
/* Illinois iterations on the bracket [*a, *b] until it is S_tol wide or
 * the best value is within its error of 0 (*best: the smallest |f|; with
 * `track`, the eigenvalue `track` continued from sample to sample instead
 * of ring spectra, which fails where it cannot be continued). */
/* The two samples are different roots: v apart by more than the root moves
 * between them (v ~ S), beyond 1e-3 v. */
static int roots_apart(const sample *a, const sample *b)
{
    double w = fabs(b->S - a->S), v = fmax(a->v, b->v);
    return fabs(a->v - b->v) > 1e-3 * v + 4 * v * w / fmin(a->S, b->S);
}

static int illinois(sigma_fn *fn, sample *a, sample *b, double S_tol, sample *best,
                    const sample *track, bkf_error *err)
{
    int kept = 0;
    double fa = a->f, fb = b->f;
    sample from = track ? *track : (sample){0};
    for (int it = 0; it < 60 && fabs(b->S - a->S) > S_tol; it++) {
        /* sigma within its error of 0: the sign there means nothing */
        if (fabs(best->f) <= best->err) break;
        /* ends on two roots are a jump (close_bracket), whatever the
         * width: closing it on would cost 8 to 16 spectra, and an
         * eigenvalue continued from one root to the other means nothing */
        if (roots_apart(a, b)) break;
        double S = (a->S * fb - b->S * fa) / (fb - fa);
        double lo = fmin(a->S, b->S), hi = fmax(a->S, b->S), w = hi - lo;
        if (!(S > lo + 0.02 * w && S < hi - 0.02 * w)) S = 0.5 * (lo + hi);
        sample m;
        int s;
        if (track) {
            s = tracked_at(fn, S, &from, &m, err);
            from = m;
        } else {
            s = eval_at(fn, S, &m, err);
        }
        if (s) return s;
        if (fabs(m.f) < fabs(best->f)) *best = m;
        if (sign_of(m.f) == sign_of(a->f)) {
            *a = m;
            fa = m.f;
            if (kept == -1) fb *= 0.5;
            kept = -1;
        } else {
            *b = m;
            fb = m.f;
            if (kept == 1) fa *= 0.5;
            kept = 1;
        }
    }
    return BKF_OK;
}

static int close_bracket(sigma_fn *fn, sample a, sample b, double S_tol, bkf_stabmap_point *pt,
                         int *jump, bkf_error *err)
{
    /* The eigenvalue right of 0 at the positive end, continued across the
     * bracket and closed on (about 1/20 of a ring spectrum a step), then
     * one ring spectrum where it stops: where that spectrum's sigma_max is
     * the eigenvalue's (no other one right of it beyond tol), the zero is
     * sigma_max's; else (another eigenvalue overtook it in the bracket) the
     * bracket is closed on ring spectra from the start. */
    const sample *pos = a.f > 0 ? &a : &b;
    sample best;
    int closed = 0;
    if (pos->have_mode) {
        sample ta = a, tb = b, full;
        bkf_error e;
        best = *pos;
        if (!illinois(fn, &ta, &tb, S_tol, &best, pos, &e) && roots_apart(&ta, &tb)) {
            /* The eigenvalue was continued across a jump to another root
             * (the bracket closed on it): the ring spectra at its two ends
             * say whether sigma_max jumps across 0 there (no crossing),
             * 2 spectra where closing the bracket on ring spectra from the
             * start took 5 to 11 (the paper scene's seeds at nu -0.98). */
            sample fa, fb;
            int s = eval_at(fn, ta.S, &fa, err);
            if (!s) s = eval_at(fn, tb.S, &fb, err);
            if (s) return s;
            /* the end of the closed bracket whose sign the two ring
             * spectra do not share, and the ring spectrum at its S */
            const sample *odd = sign_of(ta.f) != sign_of(fa.f) ? &ta : &tb;
            const sample *there = odd == &ta ? &fa : &fb;
            if (sign_of(fa.f) != sign_of(fb.f)) {
                a = fa;
                b = fb;
                best = fabs(fa.f) < fabs(fb.f) ? fa : fb;
                closed = 1;
            } else if (roots_apart(odd, there) &&
                       (!odd->tracked || odd->f - 4 * odd->err > fn->tol) &&
                       fabs(fa.f) > fa.err && fabs(fb.f) > fb.err) {
                /* Two roots at odd's S of opposite signs (odd's a ring
                 * spectrum, or an eigenvalue right of 0: proof), and the
                 * bracket's root of one sign across it: sigma_max jumps
                 * from one root to the other, no zero.  Closing it on ring
                 * spectra came to that after 1 to 7 more (the paper
                 * scene's seeds at nu -0.98, n = 2 to 6). */
                a = *odd;
                b = there == &fa ? fb : fa;
                best = b;
                closed = 1;
            }
        } else if (fabs(tb.S - ta.S) <= S_tol || fabs(best.f) <= best.err) {
            int s = eval_at(fn, best.S, &full, err);
            if (s) return s;
            if (fabs(full.f - best.f) <= fn->tol + 4 * (full.err + best.err)) {
                a = ta;
                b = tb;
                best = full;
                closed = 1;
            }
        }
    }
    if (!closed) {
        /* an end that is one eigenvalue (tracked, positive) steers, but
         * the point is a ring spectrum */
        best = b.tracked || (!a.tracked && fabs(a.f) < fabs(b.f)) ? a : b;
        int s = illinois(fn, &a, &b, S_tol, &best, NULL, err);
        if (s) return s;
    }
    *jump = fabs(best.f) > best.err && roots_apart(&a, &b);
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
                     size_t max, size_t *count, bkf_stabmap_report *report, bkf_error *err)
{
    bkf_stabmap_options o = options ? *options : bkf_stabmap_options_default();
    *count = 0;
    if (report) *report = (bkf_stabmap_report){0};
    if (samples < 1 || !(S_from > 0) || !(S_to > 0) || !isfinite(S_from) || !isfinite(S_to))
        return bkf_error_set(err, BKF_EINPUT, "scan: S_from, S_to > 0 and samples >= 1");
    sigma_fn fn = sigma_fn_of(params, n, &o, 0, 1);
    sample prev = {0};
    int have = 0, status = BKF_OK;
    for (size_t i = 0; !status && i <= samples && *count < max; i++) {
        sample cur;
        double S = S_from + (S_to - S_from) * (double)i / (double)samples;
        bkf_error e;
        fn.v_ref = 0;
        fn.fastest_S = have && S < prev.S ? prev.S : 0;
        fn.fastest_v = have && S < prev.S ? prev.v : 0;
        /* Only the sign of sigma_max matters away from a crossing, and one
         * eigenvalue right of 0 (beyond its error and tol) proves it
         * positive: the previous sample's rightmost, continued here, saves
         * the ring spectrum where the train is unstable.  A negative one
         * proves nothing (another may be right of it): the spectrum. */
        int s = 1;
        if (have && prev.have_mode)
            s = tracked_at(&fn, S, &prev, &cur, &e) || !(cur.f - 4 * cur.err > o.tol);
        if (s) s = eval_at(&fn, S, &cur, &e);
        if (s && end_of(s) < 0) {
            status = bkf_error_set(err, s, "%s", e.message);
            break;
        }
        if (s) {  /* no root or refused here: a gap in the scan */
            have = 0;
            continue;
        }
        if (have && sign_of(cur.f) != sign_of(prev.f)) {
            size_t before = fn.spectra;
            fn.v_ref = cur.v;
            fn.S_ref = cur.S;
            int jump = 0;
            int st = close_bracket(&fn, prev, cur, o.S_tol, &points[*count], &jump, &e);
            if (st && end_of(st) < 0) status = bkf_error_set(err, st, "%s", e.message);
            /* a jump of sigma_max is no crossing */
            if (!st && !jump) {
                /* the bracket's ring spectra (its ends are the scan's) */
                points[*count].evaluations = fn.spectra - before;
                (*count)++;
            }
        }
        prev = cur;
        have = 1;
    }
    if (report) {
        report->points = *count;
        report->evaluations = fn.spectra;
        report->tracked = fn.tracked;
    }
    return status;
}

int bkf_stabmap_locate(const bkf_model_params *params, size_t n, double S_from, double S_to,
                       size_t samples, const bkf_stabmap_options *options,
                       bkf_stabmap_point *point, int *found, bkf_error *err)
{
    size_t count;
    int s = bkf_stabmap_scan(params, n, S_from, S_to, samples, options, point, 1, &count, NULL,
                             err);
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
        sigma_fn fn = sigma_fn_of(params, n, &o, cur.v, cur.S);
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
        if (s || !bracketed) {
            rep.evaluations += fn.spectra;
            rep.tracked += fn.tracked;
        }
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
        int jump = 0;
        s = close_bracket(&fn, a, b, o.S_tol, &next, &jump, err);
        rep.evaluations += fn.spectra;
        rep.tracked += fn.tracked;
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
        next.evaluations = fn.spectra; /* the bracket's search and its closing */
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
/* After a stall: restarts at most, each from a step of TRACE_RETRY_STEP
 * (scaled; the full step is 1). */
#define TRACE_RETRIES 3
/* Turns in nu that each add half the work cap. */
#define TRACE_TURNS 2
#define TRACE_RETRY_STEP 0.25
/* Ring spectra at most to correct a point whose own ring spectrum showed
 * another eigenvalue right of the one tracked (trace_flush). */
#define TRACE_FIX 4
/* Ring spectra in a row agreeing with the eigenvalue tracked before a
 * point may go without one (trace_vouch). */
#define TRACE_CALM 2
/* A closed curve's chord passes its first point within this (scaled). */
#define TRACE_CLOSE 0.25

typedef struct {
    double nu, S;
    sample s;
} trace_eval;

typedef struct {
    sigma_fn fn;
    /* The eigenvalue tracked (tracked_sample): the last spectrum's
     * rightmost, continued to each trial point (mode.have_mode 0: none) */
    sample mode;
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
    double first[2];       /* the curve's first point, and whether it got */
    int left;              /* more than 1.5 steps away from it since */
    double newton_tol;     /* the driver's */
    double land_tol;       /* an edge crossing's, relative in nu */
    double tangent[2];     /* the last point's unit tangent (scaled), as the driver gave it */
    int skip_start;        /* a restart: the driver's first point is the last one kept */
    size_t cap, turns;     /* max_points as asked, and the turns in nu that added to it */
    /* Every other point without its ring spectrum (trace_vouch): the last
     * ring spectrum's runner-up, continued; whether the next point may be
     * vouched (the last was a ring spectrum); the vouched point held until
     * the next ring spectrum, and whether a ring spectrum since disagreed
     * with the eigenvalue tracked (another overtook it: the held point
     * then gets its own) */
    sample second;
    double ring_top;       /* that ring spectrum's sigma_max */
    int may_vouch, have_pend, switched;
    int calm;              /* ring spectra in a row that agreed with the eigenvalue tracked */
    int side, side_run;    /* the last point's stable side, and points in a row on it */
    bkf_stabmap_point pend;
    trace_eval pend_e;
} trace_ctx;

/* A cached evaluation at (nu, S), a ring spectrum's first; with `full`,
 * only a ring spectrum's. */
static const trace_eval *trace_cached(const trace_ctx *t, double nu, double S, int full)
{
    const trace_eval *hit = NULL;
    for (size_t i = 0; i < t->cached; i++)
        if (t->cache[i].nu == nu && t->cache[i].S == S) {
            if (!t->cache[i].s.tracked) return &t->cache[i];
            if (!full) hit = &t->cache[i];
        }
    return hit;
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
 * refusal's status (t->failed says which), or another failure.
 * TRACE_TRACKED: the tracked eigenvalue alone where it can be continued
 * (the start's differences).  TRACE_STEER (the driver's predictor and
 * corrections, whose values only steer Newton): likewise, but a ring
 * spectrum where Newton would stop, so that the point accepted is one and
 * a change of the rightmost eigenvalue (another class overtaking the one
 * tracked: n = 4 near nu -0.959, S 23.4, j = 1 past j = 0) corrects
 * Newton on.  TRACE_FULL: the ring spectrum. */
/* A value computed at e: cached, the gradient updated, the root and the
 * eigenvalue followed from it. */
static void trace_keep(trace_ctx *t, const trace_eval *e)
{
    t->failed = -1;
    t->fn.v_ref = e->s.v;
    t->fn.S_ref = e->S;
    t->mode = e->s;
    if (!e->s.tracked) {
        t->second = (sample){.f = e->s.f2, .im = e->s.im2, .j = e->s.j2,
                             .have_mode = e->s.have_second};
        t->ring_top = e->s.f;
    }
    t->cache[t->next] = *e;
    t->next = (t->next + 1) % TRACE_CACHE;
    if (t->cached < TRACE_CACHE) t->cached++;
    trace_broyden(t, e);
}

enum { TRACE_TRACKED = 0, TRACE_FULL = 1, TRACE_STEER = 2 };

/* Newton's next step from the value f at u, on the gradient's model, is
 * within its tolerance (the driver's test, per component against
 * max(|u_i|, scale_i)): the driver will accept the point u, which must be
 * a ring spectrum. */
static int near_converged(const trace_ctx *t, const double *u, double f)
{
    double G[2] = {t->grad[0] * t->scale[0], t->grad[1] * t->scale[1]};
    double GG = G[0] * G[0] + G[1] * G[1];
    if (!(GG > 0) || !isfinite(GG)) return 1;
    for (int i = 0; i < 2; i++)
        if (fabs(f * G[i] / GG) * t->scale[i] > t->newton_tol * fmax(fabs(u[i]), t->scale[i]))
            return 0;
    return 1;
}

/* Whether the point where Newton stops on the tracked eigenvalue s may be
 * drawn without its ring spectrum: the last point was one, and that ring
 * spectrum's runner-up, continued here, lies left of s beyond tol and four
 * times their errors, having moved less than half its distance below the
 * rightmost there (along the paper scene's curves it moves 15 to 25% of
 * it a step; where two classes cross 0 together, as n = 2, 3 at gamma 4,
 * c 0.15, nu -0.985, it was 1e-6 below and moved 1e-3), and the last
 * TRACE_CALM ring spectra agreed with the eigenvalue tracked (there a
 * third eigenvalue overtook the two, again and again).  The ring spectrum
 * of the next point checks that the eigenvalue tracked is still the
 * rightmost (trace_flush). */
static int trace_vouch(trace_ctx *t, double S, const sample *s)
{
    sample sec;
    bkf_error e;
    if (!t->may_vouch || t->calm < TRACE_CALM || !t->second.have_mode ||
        tracked_at(&t->fn, S, &t->second, &sec, &e))
        return 0;
    if (!(sec.f < s->f - (t->fn.tol + 4 * (s->err + sec.err))) ||
        !(fabs(sec.f - t->second.f) < 0.5 * (t->ring_top - t->second.f)))
        return 0;
    t->second = sec;
    return 1;
}

static int trace_eval_at(trace_ctx *t, double nu, double S, int full, trace_eval *out,
                         bkf_error *err)
{
    const trace_eval *hit = trace_cached(t, nu, S, full == TRACE_FULL);
    if (hit) {
        *out = *hit;
        return BKF_OK;
    }
    /* the eigenvalue tracked here, if it was: a ring spectrum that
     * disagrees with it says another eigenvalue overtook it */
    hit = trace_cached(t, nu, S, 0);
    sample here = hit ? hit->s : (sample){0};
    out->nu = nu;
    out->S = S;
    t->fn.p.nu = nu;
    if (full != TRACE_FULL && t->mode.have_mode) {
        bkf_error e;
        const double u[2] = {nu, S};
        if (!tracked_at(&t->fn, S, &t->mode, &out->s, &e)) {
            trace_keep(t, out);
            /* the gradient as the driver will take it, updated by this value */
            if (full == TRACE_TRACKED || !near_converged(t, u, out->s.f)) return BKF_OK;
            here = out->s;
            if (trace_vouch(t, S, &out->s)) {
                out->s.vouched = 1;
                t->last.s.vouched = 1;
                t->cache[(t->next + TRACE_CACHE - 1) % TRACE_CACHE].s.vouched = 1;
                return BKF_OK;
            }
        }
    }
    int s = eval_at(&t->fn, S, &out->s, err);
    if (!s && here.tracked) {
        int agree = fabs(out->s.f - here.f) <= t->fn.tol + 4 * (out->s.err + here.err);
        t->switched |= !agree;
        t->calm = agree ? t->calm + 1 : 0;
    }
    if (s) {
        t->failed = end_of(s);
        if (t->failed >= 0) {
            snprintf(t->why.message, sizeof t->why.message, "at nu %.6g, S %.6g: %.200s", nu, S,
                     err ? err->message : "");
            t->why.status = s;
        }
        return s;
    }
    trace_keep(t, out);
    return BKF_OK;
}

/* u is the last spectrum's point moved by a Newton step within the
 * tolerance: the driver asks there only for the tangent (the Jacobian), or
 * goes on on the linear model, and the point reported is the last
 * spectrum's, whose distance to the zero its S_err and nu_err give.  After
 * a ring spectrum that tolerance is land_tol, what Newton's was before the
 * tracked eigenvalue: where the eigenvalue cannot be continued (its Newton
 * fails) and every value is a ring spectrum, the 8 times tighter driver
 * must not cost more of them than before. */
static int converged_from_last(const trace_ctx *t, const double *u)
{
    if (!t->have_last || trace_cached(t, u[0], u[1], 0)) return 0;
    const double last[2] = {t->last.nu, t->last.S};
    double tol = t->last.s.tracked ? t->newton_tol : t->land_tol;
    for (int i = 0; i < 2; i++)
        if (fabs(u[i] - last[i]) > tol * fmax(fabs(u[i]), t->scale[i])) return 0;
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
    int s = trace_eval_at(t, u[0], u[1], TRACE_STEER, &e, err);
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
    pt.evaluations = t->fn.spectra - t->at_last_point;
    t->at_last_point = t->fn.spectra;
    return pt;
}

/* The curve's crossing of the edge S = Sb between the last point inside
 * and e, by the Illinois method in nu on values of kind `how`
 * (trace_eval_at), into *out; 0 when the edge shows no sign change between
 * them or a value fails. */
static int land_on(trace_ctx *t, const trace_eval *e, double Sb, int how, trace_eval *out)
{
    trace_eval a, b;
    bkf_error err;
    if (trace_eval_at(t, t->prev.nu, Sb, how, &a, &err) ||
        trace_eval_at(t, e->nu, Sb, how, &b, &err))
        return 0;
    if ((a.s.f > 0) == (b.s.f > 0)) return 0;
    double fa = a.s.f, fb = b.s.f, tol = t->land_tol * fmax(fabs(e->nu), t->scale[0]);
    trace_eval best = fabs(a.s.f) < fabs(b.s.f) ? a : b;
    int kept = 0;
    for (int it = 0; it < 30 && fabs(b.nu - a.nu) > tol && fabs(best.s.f) > best.s.err; it++) {
        double nu = (a.nu * fb - b.nu * fa) / (fb - fa), lo = fmin(a.nu, b.nu),
               hi = fmax(a.nu, b.nu);
        if (!(nu > lo + 0.02 * (hi - lo) && nu < hi - 0.02 * (hi - lo))) nu = 0.5 * (lo + hi);
        trace_eval m;
        if (trace_eval_at(t, nu, Sb, how, &m, &err)) return 0;
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

/* The curve left the window in S between the last point inside and e:
 * its crossing of the edge S = Sb (a computed spectrum, as every point),
 * into *out; 0 when the edge shows no sign change between them or a
 * spectrum fails.  Located on the rightmost eigenvalue continued, then one
 * ring spectrum there, which must agree with it to tol (no other
 * eigenvalue right of it); else on ring spectra (5 to 8 of them: most of
 * the paper scene's curves' spectra beyond one a point). */
static int trace_land(trace_ctx *t, const trace_eval *e, double Sb, trace_eval *out)
{
    trace_eval m, full;
    bkf_error err;
    if (t->mode.have_mode && land_on(t, e, Sb, TRACE_TRACKED, &m)) {
        if (!m.s.tracked) {
            *out = m;
            return 1;
        }
        if (!trace_eval_at(t, m.nu, m.S, TRACE_FULL, &full, &err) &&
            fabs(full.s.f - m.s.f) <= t->fn.tol + 4 * (full.s.err + m.s.err)) {
            *out = full;
            return 1;
        }
    }
    return land_on(t, e, Sb, TRACE_FULL, out);
}

/* The scaled distance of the curve's first point from the chord a-b. */
static double chord_distance(const trace_ctx *t, const trace_eval *a, const trace_eval *b)
{
    double d[2] = {(b->nu - a->nu) / t->scale[0], (b->S - a->S) / t->scale[1]};
    double f[2] = {(t->first[0] - a->nu) / t->scale[0], (t->first[1] - a->S) / t->scale[1]};
    double dd = d[0] * d[0] + d[1] * d[1], x = dd > 0 ? (f[0] * d[0] + f[1] * d[1]) / dd : 0;
    x = fmin(fmax(x, 0), 1);
    return hypot(f[0] - x * d[0], f[1] - x * d[1]);
}

/* The vouched point held, drawn (visit) once the ring spectrum after it
 * agrees with the eigenvalue tracked (`confirmed`); else (the curve ends
 * there, or another eigenvalue overtook) only if its own ring spectrum
 * agrees with its tracked eigenvalue, and then with that spectrum's sigma:
 * one that disagrees is not a point of the curve and is left out.  The
 * continuation's state is left as it is.  Nonzero: visit asked to stop. */
static int trace_flush(trace_ctx *t, int confirmed)
{
    if (!t->have_pend) return 0;
    t->have_pend = 0;
    bkf_stabmap_point pt = t->pend;
    if (t->switched || !confirmed) {
        sigma_fn fn = t->fn;
        fn.p.nu = t->pend_e.nu;
        fn.v_ref = t->pend_e.s.v;
        fn.S_ref = t->pend_e.S;
        sample full, prev = {0};
        bkf_error e;
        const sample *held = &t->pend_e.s;
        size_t before = fn.spectra;
        int s = eval_at(&fn, held->S, &full, &e);
        /* Another eigenvalue is right of the one tracked: the point is
         * corrected in S at its nu on ring spectra, by the secant from the
         * gradient's slope in S, to land_tol (at most
         * TRACE_FIX steps, each a ring spectrum, as the corrections there
         * were before a point went without one); a point that does not
         * get there is left out. */
        int agree = !s && fabs(full.f - held->f) <= t->fn.tol + 4 * (full.err + held->err);
        double slope = pt.slope;
        for (int it = 0; !s && !agree && it < TRACE_FIX; it++) {
            if (it) slope = (full.f - prev.f) / (full.S - prev.S);
            double step = -full.f / slope, S = full.S + step;
            if (!isfinite(step) || fabs(step) > t->scale[1] || !(S > 0)) break;
            prev = full;
            s = eval_at(&fn, S, &full, &e);
            agree = !s && fabs(step) <= t->land_tol * fmax(S, t->scale[1]);
        }
        t->fn.spectra = fn.spectra;
        t->fn.tracked = fn.tracked;
        pt.evaluations += fn.spectra - before;
        if (!agree || isfinite(full.bound)) {
            t->rep.points--;
            return 0;
        }
        if (prev.S > 0 && full.S != prev.S) slope = (full.f - prev.f) / (full.S - prev.S);
        double miss = fabs(full.f) + full.err;
        pt.S = full.S;
        pt.v = full.v;
        pt.mu = full.mu;
        pt.sigma = full.f;
        pt.sigma_err = full.err;
        pt.slope = slope;
        pt.stable_above = slope < 0;
        pt.S_err = miss / fabs(slope);
        pt.nu_err = miss / fabs(pt.nu_slope);
    }
    return t->visit && t->visit(&pt, t->data);
}

static int trace_accept(const double *u, const double *tangent, int is_fold, void *data)
{
    (void)is_fold;
    trace_ctx *t = data;
    /* Past a turn in nu the curve crosses the nu range again, which the
     * work cap (twice a curve monotone in both) did not allow for: each
     * turn adds half of it, TRACE_TURNS at most (gamma 1, c 0.6, n 3: 8
     * points up to its turn near nu -0.89, 23 back to nu -0.95 over the
     * turn's high curvature, the cap 30). */
    if (t->have_prev && tangent[0] * t->tangent[0] < 0 && t->turns < TRACE_TURNS) {
        t->turns++;
        t->max_points += (t->cap + 1) / 2;
    }
    t->tangent[0] = tangent[0];
    t->tangent[1] = tangent[1];
    /* a restart's start is the point kept last (the driver corrected it
     * with nu held, within its tolerance): not drawn twice */
    if (t->skip_start) {
        t->skip_start = 0;
        return 0;
    }
    trace_eval e;
    bkf_error err;
    /* the point is the last spectrum, within Newton's tolerance of u (a
     * ring spectrum there if the last was the tracked eigenvalue alone) */
    int s = BKF_OK;
    if (converged_from_last(t, u))
        e = t->last;
    else
        s = trace_eval_at(t, u[0], u[1], TRACE_FULL, &e, &err);
    if (!s && e.s.tracked && !e.s.vouched) s = trace_eval_at(t, e.nu, e.S, TRACE_FULL, &e, &err);
    if (s) {
        trace_flush(t, 0);
        t->rep.end = t->failed >= 0 ? (bkf_stabmap_end)t->failed : BKF_STABMAP_END_STALLED;
        snprintf(t->rep.note, sizeof t->rep.note, "%.250s",
                 t->failed >= 0 ? t->why.message : err.message);
        return 1;
    }
    if (e.S < t->S_lo || e.S > t->S_hi) {
        /* the point outside is not drawn; the crossing of the edge is */
        double Sb = e.S > t->S_hi ? t->S_hi : t->S_lo;
        trace_eval edge;
        if (trace_flush(t, 0)) return 1;
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
    /* A closed curve (a level set has no other way back) would be followed
     * round and round to max_points: once its chord from the last point
     * passes the first point (within TRACE_CLOSE, the chord's sagitta and
     * more), it ends.  Within a step of the first point was not enough:
     * at gamma 1, c 0.6, n 3 the turn's upper half comes back to nu -0.95
     * at S 11.44, 0.9 steps above the lower half's first point. */
    double d0 = hypot((e.nu - t->first[0]) / t->scale[0], (e.S - t->first[1]) / t->scale[1]);
    int closed = t->left && t->have_prev && chord_distance(t, &t->prev, &e) < TRACE_CLOSE;
    if (d0 > 1.5) t->left = 1;
    bkf_stabmap_point pt = trace_point(t, &e);
    t->prev = e;
    t->have_prev = 1;
    t->rep.points++;
    t->rep.nu_end = pt.nu;
    t->side_run = t->side_run && pt.stable_above == t->side ? t->side_run + 1 : 1;
    t->side = pt.stable_above;
    if (e.s.vouched) {
        t->pend = pt;
        t->pend_e = e;
        t->have_pend = 1;
        t->switched = 0;
        t->may_vouch = 0;
    } else {
        if (trace_flush(t, 1)) return 1;
        if (t->visit && t->visit(&pt, t->data)) return 1;
        /* not where the stable side flips from point to point: a corner
         * of sigma_max followed, two classes crossing 0 together */
        t->may_vouch = t->side_run >= 2;
    }
    if ((closed || t->rep.points >= t->max_points) && trace_flush(t, 0)) return 1;
    if (closed) {
        t->rep.end = BKF_STABMAP_END_CLOSED;
        snprintf(t->rep.note, sizeof t->rep.note,
                 "closed: back at nu %.6g, S %.6g, past its first point", e.nu, e.S);
        return 1;
    }
    if (t->rep.points >= t->max_points) {
        t->rep.end = BKF_STABMAP_END_POINTS;
        snprintf(t->rep.note, sizeof t->rep.note,
                 "cut at %zu points (max_points): the rest of the curve not followed",
                 t->rep.points);
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
    t.fn = sigma_fn_of(params, n, &o, first->v, first->S);
    t.fn.per_kappa = 1;
    t.scale[0] = o.nu_step;
    t.scale[1] = o.S_step;
    t.failed = -1;
    t.S_lo = w->S_lo;
    t.S_hi = w->S_hi;
    t.visit = visit;
    t.data = data;
    t.max_points = t.cap = o.max_points;
    t.first[0] = first->nu;
    t.first[1] = first->S;
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
    s = trace_eval_at(&t, first->nu, first->S, TRACE_FULL, &e0, &e);
    if (!s) s = trace_eval_at(&t, first->nu + h, first->S, TRACE_TRACKED, &e1, &e);
    if (s) goto failed;
    t.grad[0] = (e1.s.f - e0.s.f) / h;
    t.grad[1] = isfinite(first->slope) && first->slope != 0 ? first->slope : NAN;
    if (!isfinite(t.grad[1])) {
        trace_eval e2;
        double hS = 0.25 * o.S_step;
        s = trace_eval_at(&t, first->nu, first->S + hS, TRACE_TRACKED, &e2, &e);
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
    t.land_tol = fmin(o.S_tol / fmax(w->S_hi, o.S_step), o.S_tol * o.nu_step / (o.S_step * nu_mag));
    /* Newton's iterates are the tracked eigenvalue, about 1/20 of a ring
     * spectrum each: iterated 8 times closer than that, the one ring
     * spectrum where they stop is nearer the curve than a last spectrum
     * within the tolerance itself (what the points were before) */
    co.newton_tol = t.land_tol / 8;
    t.newton_tol = co.newton_tol;
    co.newton_max_iter = 8;
    /* Newton to newton_tol takes three values from a predictor (two
     * tracked eigenvalues, the ring spectrum where it stops): at the
     * driver's default (grow after two) a step once halved at a corner
     * never grew back (n = 3 at gamma 4, c 0.15, nu -0.987: steps of 0.03,
     * 118 points where 11 reach the window's top) */
    co.grow_iterations = 3;
    /* A turn in nu needs no point of its own (the points on either side
     * draw it), and its location, to newton_tol on the tangent, fails on a
     * sigma_max whose rightmost class changes along the curve: up to 100
     * corrections a turn, each a spectrum (n = 3 above, nu -0.984, S 21) */
    co.locate_folds = 0;
    /* the cap is trace_accept's (it grows at turns in nu) */
    co.max_points = (TRACE_TURNS + 2) * o.max_points + 1;
    co.stop_index = 0;
    co.stop_min = w->nu_lo;
    co.stop_max = w->nu_hi;
    double u0[2] = {first->nu, first->S};
    bkf_cont_report cr;
    int along = 0; /* the component whose sign is the way: nu, or S on a restart */
    for (int retries = 0;; retries++) {
        s = bkf_cont_run(trace_residual, trace_accept, &t, u0, along, direction, &co, &cr, &e);
        if (!(s == BKF_ENUMERIC && t.failed < 0 && t.have_prev && retries < TRACE_RETRIES))
            break;
        /* A stall: on from the last point kept, the way its tangent went,
         * with short steps that grow back.  At a corner of the curve (the
         * rightmost eigenvalue changes class) the tangent turns further than
         * the driver takes in one step however short; from a restart the
         * secant gradient turns over a few short steps (gamma 1, c 0.6,
         * n 3 at its turn in nu near -0.89, S 11.3: stalled after 6 points,
         * the turn's upper half not drawn). */
        co.step_initial = TRACE_RETRY_STEP;
        co.step_min = TRACE_STEP_MIN / 16;
        u0[0] = t.prev.nu;
        u0[1] = t.prev.S;
        /* the way is the tangent's larger component's sign (a restart at a
         * turn in nu, where the tangent's nu is near 0, took the sign of
         * its nu and went back down the curve) */
        along = fabs(t.tangent[1]) > fabs(t.tangent[0]);
        direction = t.tangent[along] < 0 ? -1 : 1;
        t.skip_start = 1;
    }
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
    trace_flush(&t, 0);
    t.rep.evaluations = t.fn.spectra;
    t.rep.tracked = t.fn.tracked;
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

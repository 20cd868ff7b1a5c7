/* The traced curves of the train spectrum (trainspec.c's gather): for
 * each height, the rightmost Re sigma in the window where either
 * multiplier has modulus 1, and the points where its phase is a multiple
 * of 2 pi / classes, the curves' candidates (docs/numerics.md, "Finding
 * every eigenvalue in the window"). */
#include <gsl/gsl_math.h>

#include <complex.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "trainspec_internal.h"

/* ------------------------------------------------------ curve tracing */

typedef struct {
    double y;
    int found;         /* the family's multiplier reaches modulus 1 right of a_lo */
    double a;          /* Re sigma there */
    double slope;      /* da/dy along the curve */
    double phase;      /* arg of the multiplier (principal), then unwrapped */
    double rate;       /* d phase / dy along the curve */
} curve_point;

/* Newton on Re w[f](a + i y) = 0 in a from the prediction g (the last
 * height's point continued along its slope): one pass with the derivative
 * per step, where the bracketing below takes about six passes per height.
 * The point is taken once a step is at most sqrt(tol_a) (quadratic
 * convergence: the error after it is of order tol_a), its phase, slope and
 * rate from the derivative at the step's start (first order in the step).
 * 0 when Newton does not settle inside the window, or Re w does not fall
 * with a there: the bracketing decides. */
static int height_newton(ctx *x, const mesh *m, const window *win, double y, double g, int f, double tol_a,
                         curve_point *p)
{
    double a = g;
    for (int it = 0; it < TRACE_NEWTON_MAX; it++) {
        double complex w[2], dw[2];
        trainspec_monodromy(x, m, a + I * y, w, dw);
        double re = creal(dw[f]), im = cimag(dw[f]);
        if (!(re < 0.0) || !isfinite(creal(w[f])) || !isfinite(cimag(w[f]))) return 0;
        double step = -creal(w[f]) / re, next = a + step;
        if (!(next > win->a_lo && next < win->a_hi)) return 0;
        if (fabs(step) <= sqrt(tol_a)) {
            *p = (curve_point){.y = y, .found = 1, .a = next, .phase = cimag(w[f]) + im * step,
                               .slope = im / re, .rate = (re * re + im * im) / re};
            return 1;
        }
        a = next;
    }
    return 0;
}

/* Both families' rightmost a in [a_lo, a_hi] where Re w(a + i y) = 0: by
 * Newton from the predictions guess[f] where given (NAN otherwise) and it
 * settles, else by the Illinois variant of regula falsi, the bracket
 * shrunk around the prediction first.  Re w decreases in a: the
 * multipliers shrink to the right. */
static int height_at(ctx *x, const mesh *m, window *win, double y, const double guess[FAMILIES],
                     curve_point pt[FAMILIES])
{
    /* the curves only propose candidates (polished on the meshes, their
     * value and error the polish's) and tell where they leave the window:
     * a to 1e-6 is plenty for both, and 1e-3 tol cost two or three more
     * monodromies per family and height */
    double tol_a = fmax(1e-3 * x->tol, TRACE_TOL);
    int settled[FAMILIES], all = 1;
    for (int f = 0; f < FAMILIES; f++) {
        settled[f] = isfinite(guess[f]) && guess[f] > win->a_lo && guess[f] < win->a_hi &&
                     height_newton(x, m, win, y, guess[f], f, tol_a, &pt[f]);
        all &= settled[f];
    }
    if (all) return BKF_OK;
    double complex w[2], wh[2] = {0};
    trainspec_monodromy(x, m, win->a_lo + I * y, w, NULL);
    int inside = 0;
    for (int f = 0; f < FAMILIES; f++) inside |= !settled[f] && creal(w[f]) >= 0.0;
    /* the bracket's right end, only where a family still needs one */
    for (int grow = 0; inside; grow++) {
        trainspec_monodromy(x, m, win->a_hi + I * y, wh, NULL);
        if (creal(wh[0]) < 0.0) break;
        if (grow > 40) return BKF_ENUMERIC;
        win->a_hi *= 2.0;
    }
    for (int f = 0; f < FAMILIES; f++) {
        if (settled[f]) continue;
        curve_point *p = &pt[f];
        p->y = y;
        p->found = 0;
        if (creal(w[f]) < 0.0) continue;
        double lo = win->a_lo, hi = win->a_hi, flo = creal(w[f]), fhi = creal(wh[f]);
        /* shrink the bracket around the prediction */
        if (isfinite(guess[f]) && guess[f] > lo && guess[f] < hi) {
            double g = guess[f], d = fmax(1e-3, 100.0 * tol_a);
            for (int k = 0; k < 2; k++, d *= 8.0) {
                double complex wg[2];
                double t = fmin(fmax(g, lo + 0.5 * tol_a), hi - 0.5 * tol_a);
                trainspec_monodromy(x, m, t + I * y, wg, NULL);
                double ft = creal(wg[f]);
                if (ft >= 0.0) {
                    lo = t, flo = ft;
                    g = t + d;
                } else {
                    hi = t, fhi = ft;
                    g = t - d;
                }
                if (!(g > lo && g < hi)) break;
            }
        }
        int side = 0;
        for (int it = 0; it < 200 && hi - lo > tol_a; it++) {
            double t = (lo * fhi - hi * flo) / (fhi - flo);
            if (!(t > lo && t < hi)) t = 0.5 * (lo + hi);
            double complex wt[2];
            trainspec_monodromy(x, m, t + I * y, wt, NULL);
            double ft = creal(wt[f]);
            if (fabs(ft) < 1e-3 * tol_a) {
                lo = hi = t;
                break;
            }
            if (ft >= 0.0) {
                lo = t, flo = ft;
                if (side == -1) fhi *= 0.5;
                side = -1;
            } else {
                hi = t, fhi = ft;
                if (side == 1) flo *= 0.5;
                side = 1;
            }
        }
        double a = 0.5 * (lo + hi);
        double complex wv[2], dw[2];
        trainspec_monodromy(x, m, a + I * y, wv, dw);
        p->found = 1;
        p->a = a;
        p->phase = cimag(wv[f]);
        /* along Re w = 0: da/dy = Im w' / Re w', dphase/dy = |w'|^2 / Re w' */
        double re = creal(dw[f]), im = cimag(dw[f]);
        if (re == 0.0) return BKF_ENUMERIC;
        p->slope = im / re;
        p->rate = (re * re + im * im) / re;
    }
    return BKF_OK;
}

/* One sampled height: both families. */
typedef struct {
    curve_point fam[FAMILIES];
} height;

typedef struct {
    height *h;
    size_t count, cap;
} curve;

static int curve_insert(curve *c, size_t at, const height *p)
{
    if (c->count == c->cap) {
        size_t cap = c->cap ? 2 * c->cap : 256;
        height *g = realloc(c->h, cap * sizeof *g);
        if (!g) return BKF_ENOMEM;
        c->h = g;
        c->cap = cap;
    }
    memmove(&c->h[at + 1], &c->h[at], (c->count - at) * sizeof *c->h);
    c->h[at] = *p;
    c->count++;
    return BKF_OK;
}

/* Does the interval between two samples need a sample in between: an edge
 * of the curve, a phase step the rates do not account for, or a bend the
 * linear interpolation of a misses. */
static int needs_split(const ctx *x, const curve_point *p, const curve_point *q, double min_dy)
{
    double dy = q->y - p->y;
    if (dy <= min_dy) return 0;
    if (p->found != q->found) return dy > min_dy * (EDGE_FRACTION / CURVE_MIN_FRACTION);
    if (!p->found) return 0;
    double est = 0.5 * (p->rate + q->rate) * dy;
    double darg = trainspec_wrap(q->phase - p->phase);
    double turns = nearbyint((est - darg) / (2.0 * M_PI));
    if (fabs(est - (darg + 2.0 * M_PI * turns)) > 0.3) return 1;
    if (fabs(q->slope - p->slope) * dy > fmax(0.05 * fabs(p->a) + 1e-3, 100.0 * x->tol)) return 1;
    return 0;
}

static void predict(const height *p, const height *q, double y, double guess[FAMILIES])
{
    for (int f = 0; f < FAMILIES; f++) {
        guess[f] = NAN;
        const curve_point *near = p && p->fam[f].found ? &p->fam[f] : q && q->fam[f].found ? &q->fam[f] : NULL;
        if (near) guess[f] = near->a + near->slope * (y - near->y);
    }
}

/* Trace both families over [y0, y1] into c (appending, y increasing),
 * refining where needs_split says so. */
static int trace(ctx *x, window *win, double y0, double y1, double y_scale, curve *c)
{
    double min_dy = y_scale * CURVE_MIN_FRACTION;
    size_t start = c->count;
    for (int i = 0; i <= CURVE_START; i++) {
        if (i == 0 && start > 0) continue; /* y0 is the previous pass's last point */
        double y = y0 + (y1 - y0) * i / CURVE_START, guess[FAMILIES];
        predict(c->count ? &c->h[c->count - 1] : NULL, NULL, y, guess);
        height h;
        int rc = height_at(x, &x->coarse, win, y, guess, h.fam);
        if (rc != BKF_OK) return rc;
        if (curve_insert(c, c->count, &h) != BKF_OK) return BKF_ENOMEM;
    }
    for (size_t i = start ? start - 1 : 0; i + 1 < c->count;) {
        int split = 0;
        for (int f = 0; f < FAMILIES; f++)
            split |= needs_split(x, &c->h[i].fam[f], &c->h[i + 1].fam[f], min_dy);
        if (!split) {
            i++;
            continue;
        }
        double y = 0.5 * (c->h[i].fam[0].y + c->h[i + 1].fam[0].y), guess[FAMILIES];
        predict(&c->h[i], &c->h[i + 1], y, guess);
        height mid;
        int rc = height_at(x, &x->coarse, win, y, guess, mid.fam);
        if (rc != BKF_OK) return rc;
        if (curve_insert(c, i + 1, &mid) != BKF_OK) return BKF_ENOMEM;
    }
    return BKF_OK;
}

/* ------------------------------------------------------------ candidates */

/* Every point of the traced curve where the multiplier's phase is a multiple
 * of 2 pi / classes, with its mirror image below the real axis. */
static int collect(curve *c, int fam, size_t classes, candidates *out)
{
    if (c->count == 0) return BKF_OK;
    double step = 2.0 * M_PI / (double)classes;
    /* unwrap the phase with the rates */
    double psi = 0.0;
    for (size_t i = 0; i < c->count; i++) {
        curve_point *p = &c->h[i].fam[fam];
        if (!p->found) continue;
        if (i > 0 && c->h[i - 1].fam[fam].found) {
            const curve_point *q = &c->h[i - 1].fam[fam];
            double est = 0.5 * (p->rate + q->rate) * (p->y - q->y);
            double darg = trainspec_wrap(p->phase - q->phase);
            psi += darg + 2.0 * M_PI * nearbyint((est - darg) / (2.0 * M_PI));
        } else {
            psi = p->phase;
            /* a point alone on the real axis is a candidate itself */
            double l = psi / step;
            if (p->y == 0.0 && fabs(l - nearbyint(l)) < 1e-6) {
                long cls = ((long)nearbyint(l) % (long)classes + (long)classes) % (long)classes;
                if (trainspec_cand_push(out, (candidate){p->a, 0.0, (size_t)cls, fam, 0}) != BKF_OK) return BKF_ENOMEM;
            }
        }
        p->phase = psi; /* unwrapped from here on */
        if (i == 0 || !c->h[i - 1].fam[fam].found) continue;
        const curve_point *q = &c->h[i - 1].fam[fam];
        double lo = fmin(q->phase, p->phase), hi = fmax(q->phase, p->phase);
        for (double l = floor(lo / step) + 1.0; l * step <= hi; l += 1.0) {
            if (l * step == lo) continue;
            double t = (l * step - q->phase) / (p->phase - q->phase);
            double dy = p->y - q->y;
            /* Hermite interpolation of a with the slopes */
            double h00 = 2 * t * t * t - 3 * t * t + 1, h10 = t * t * t - 2 * t * t + t;
            double h01 = -2 * t * t * t + 3 * t * t, h11 = t * t * t - t * t;
            double a = h00 * q->a + h10 * dy * q->slope + h01 * p->a + h11 * dy * p->slope;
            double y = q->y + t * dy;
            long cls = ((long)l % (long)classes + (long)classes) % (long)classes;
            if (trainspec_cand_push(out, (candidate){a, y, (size_t)cls, fam, 0}) != BKF_OK) return BKF_ENOMEM;
            if (y > 0.0) {
                size_t mirror = (size_t)((classes - (size_t)cls) % classes);
                if (trainspec_cand_push(out, (candidate){a, -y, mirror, fam, 1}) != BKF_OK) return BKF_ENOMEM;
            }
        }
    }
    return BKF_OK;
}

/* The coarse mesh for a window up to height B: a step turns the fastest
 * solution, u ~ exp(+-sqrt(beta) sigma z), by at most RESOLVE_TURN (see
 * mesh_needs).  The fine one only the polish uses: meshes_for_polish
 * builds it, once the trace has settled the window (each build samples
 * the profile at three points a step, a third of a trace pass's cost at
 * mu 2). */
int trainspec_meshes_for(ctx *x, double B, const window *win, bkf_error *err)
{
    trainspec_mesh_free(&x->fine);
    int rc = trainspec_mesh_needs(x, hypot(B, win->a_hi), err);
    return rc != BKF_OK ? rc : trainspec_mesh_build(x, x->substeps, &x->coarse, err);
}

/* ------------------------------------------------------ the edge's noise */

/* Left of some Re sigma < 0 the monodromy of a thin train (large mu) is
 * rounding noise: on the slow branches near the knees, where phi = f^2 - 1
 * is small, the solution the L-stable steps damp grows at -2 sigma / s -
 * mu phi, and the product of the steps cancels e-foldings of it (n = 6 at
 * gamma 1.5, mu 147.5, Im sigma 1: Re w changes by 1 between Re sigma
 * -0.075 and -0.0750001, against 3e-7 off the first-order step at -0.05,
 * 4e-9 at -0.045; at Im sigma 0 none).  The trace took that noise for a
 * band of eigenvalues at Re -0.065 to -0.07 turning the phase 1000-2000
 * rad per unit height, and spent the whole budget on it.  The noise of Re w
 * at a + i y: its departure from the first-order step EDGE_PROBE_STEP to
 * the right (the second-order term is below 1e-12 there). */
#define EDGE_PROBE_STEP 1e-7
/* ... at most this share of tol: an eigenvalue's error from it is this
 * share of tol over |dw/dsigma| (>= 2 on the curves of that train) */
#define EDGE_NOISE_SHARE 1e-2
/* The raised edge keeps at least this share of the window's depth; past
 * it the spectrum is refused: the curves near 0 would then leave the
 * window between the trace's heights (at a_lo -0.001, the eigenvalues at
 * Re 6e-4, Im 0.013 of that train were stepped over). */
#define EDGE_KEEP 0.25
/* Bisections of the edge between a noisy a_lo and 0. */
#define EDGE_BISECTIONS 10

static double edge_noise(ctx *x, double a, double y)
{
    double complex w[2], dw[2], w2[2];
    trainspec_monodromy(x, &x->coarse, a + I * y, w, dw);
    trainspec_monodromy(x, &x->coarse, a + EDGE_PROBE_STEP + I * y, w2, NULL);
    double noise = 0.0;
    for (int f = 0; f < FAMILIES; f++) {
        /* Im w is a principal phase: a step across -pi is no noise */
        double complex d = w2[f] - w[f] - EDGE_PROBE_STEP * dw[f];
        noise = fmax(noise, hypot(creal(d), trainspec_wrap(cimag(d))));
    }
    return isfinite(noise) ? noise : INFINITY;
}

/* The window's left edge raised, where the monodromy is noise there at the
 * heights y0 + (B - y0) / 4, / 2 and B, to the first Re sigma where it is
 * not (bisected, the noise falls steeply to the right); BKF_ETOL where
 * that is right of EDGE_KEEP of the window's first depth a_lo0. */
static int raise_edge(ctx *x, window *win, double y0, double B, double a_lo0, bkf_error *err)
{
    double limit = EDGE_NOISE_SHARE * x->tol;
    static const double at[] = {0.25, 0.5, 1.0};
    for (size_t k = 0; k < sizeof at / sizeof at[0] && !x->stop; k++) {
        double y = y0 + (B - y0) * at[k];
        if (edge_noise(x, win->a_lo, y) <= limit) continue;
        double lo = win->a_lo, hi = EDGE_KEEP * a_lo0;
        if (!(edge_noise(x, hi, y) <= limit)) {
            if (x->stop) break;
            return bkf_error_set(err, BKF_ETOL,
                                 "spectrum: the monodromy is rounding noise right of Re sigma = %.3g at "
                                 "Im sigma %.3g (mu = %.15g: the damped solution grows through the knees "
                                 "and cancels), the window's edge %.3g",
                                 hi, y, x->mu, a_lo0);
        }
        for (int i = 0; i < EDGE_BISECTIONS && !x->stop; i++) {
            double mid = 0.5 * (lo + hi);
            if (edge_noise(x, mid, y) <= limit) hi = mid;
            else lo = mid;
        }
        win->a_lo = hi;
    }
    return BKF_OK;
}

/* Trace both families over [0, B], B grown until the curves stay left of
 * a_lo in its upper quarter; the edge raised right of the monodromy's noise
 * first (raise_edge). */
static int trace_all(ctx *x, window *win, curve *c, double *y_max, bkf_error *err)
{
    /* beyond |sigma| ~ gamma v / c the spectrum is in its asymptotic regime */
    double B = fmax(2.0, x->gamma * x->v / x->c);
    double y0 = 0.0, a_lo0 = win->a_lo;
    for (;;) {
        int mrc = trainspec_meshes_for(x, B, win, err);
        if (mrc == BKF_OK) mrc = raise_edge(x, win, y0, B, a_lo0, err);
        if (mrc != BKF_OK) return mrc;
        int rc = trace(x, win, y0, B, B, c);
        if (rc == BKF_ENOMEM) return bkf_error_set(err, rc, "out of memory");
        if (rc != BKF_OK)
            return bkf_error_set(err, rc, "spectrum: the multiplier curve could not be traced (mu = %.15g)", x->mu);
        int above = 0;
        for (int f = 0; f < FAMILIES; f++)
            for (size_t i = 0; i < c->count; i++)
                if (c->h[i].fam[f].found && c->h[i].fam[f].y > 0.75 * B) above = 1;
        if (!above) break;
        if (2.0 * B > Y_MAX_LIMIT)
            return bkf_error_set(err, BKF_EBUDGET,
                                 "spectrum: eigenvalues right of %.3g reach beyond |Im sigma| = %g", win->a_lo,
                                 Y_MAX_LIMIT);
        y0 = B;
        B *= 2.0;
    }
    *y_max = B;
    return BKF_OK;
}

int trainspec_curves(ctx *x, size_t classes, window *win, candidates *cs, double *y_max, size_t *points,
                     bkf_error *err)
{
    curve heights = {0};
    int rc = trace_all(x, win, &heights, y_max, err);
    if (rc == BKF_OK) *points += heights.count;
    for (int f = 0; f < FAMILIES && rc == BKF_OK; f++)
        if (collect(&heights, f, classes, cs) != BKF_OK) rc = bkf_error_set(err, BKF_ENOMEM, "out of memory");
    free(heights.h);
    return rc;
}

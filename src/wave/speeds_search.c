/* The speeds' search (speeds.c): the grid of T over s = ln sqrt(mu^2 -
 * gamma^2), the cells' bounds on ln g (A2), and the levels bracketed or
 * certified absent (A3).  Below the polishing (speeds_polish.c), the rows
 * (speeds.c) and the branches (speeds_branch.c), which call it. */
#include "speeds_internal.h"

#include "bkfront/asymptotics.h"
#include "bkfront/continuation.h"
#include "bkfront/cycle.h"
#include "bkfront/model.h"

#include <float.h>
#include <gsl/gsl_errno.h>
#include <gsl/gsl_roots.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------- the grid */

/* |nu| up to which the speeds are verified (docs/accuracy.md, Extremes). */
#define NU_VERIFIED 0.9999

/* A refused period as the speeds' failure: the cycle's message (it names mu
 * and nu) and what to try. */
int speeds_period_refused(int rc, const bkf_error *e, double nu, bkf_error *err)
{
    const char *hint = !bkf_status_is_numerical(rc) ? ""
                       : fabs(nu) > NU_VERIFIED
                           ? "; |nu| > 0.9999 is beyond the range where the speeds are verified "
                             "(docs/accuracy.md): try a looser tol, or |nu| <= 0.9999"
                       : rc == BKF_ETOL ? "; a looser tol may succeed"
                                        : "";
    return bkf_error_set(err, rc, "%s%s", e->message, hint);
}

static int tail_ok(const grid *g, double mu, double T)
{
    if (mu < TAIL_MU_MIN) return 0;
    if (g->knee * pow(mu, 2.0 / 3.0) < TAIL_LOG_DOMINANCE * fabs(g->logc) * fmax(log(mu), 1.0))
        return 0;
    double T_asym = bkf_asym_period_large(mu, g->p.nu);
    return fabs(T - T_asym) <= TAIL_KNEE_FRACTION * g->knee * pow(mu, -1.0 / 3.0);
}

/* T at mu; `tol` 0 means the grid's coarse tolerance.  A scout (a solve
 * that only places a root's first precise solve) runs on the precise solver
 * and counts as coarse.  A failed solve is retried from a cold start, then
 * with the other stepper: warm starts from far away and rk8pd inside a
 * canard are what fails in practice. */
int speeds_solve_T_on(grid *g, int scout, double mu, double tol, double *T, double *T_err,
                      bkf_error *err)
{
    int precise = tol > 0 && !scout, on_precise = tol > 0;
    bkf_cycle *cycle = on_precise ? g->precise : g->coarse;
    if (mu > BKF_CYCLE_MU_MAX) mu = BKF_CYCLE_MU_MAX; /* rounding in mu_of_s */
    bkf_cycle_options o = bkf_cycle_options_default();
    o.tol = tol > 0 ? tol : g->tol_coarse;
    /* Above BKF_CYCLE_STIFF_MU the engine takes its stiff stepper only for
     * tol within its range; a looser coarse tol falls back on rk8pd or bsimp,
     * which cost 1.5-2.6 times more there (mu 22-49, nu -0.96) than the
     * stiff stepper at its loosest tol: ask that, it is also tighter. */
    if (!precise && mu > BKF_CYCLE_STIFF_MU && o.tol > BKF_CYCLE_STIFF_TOL_MAX)
        o.tol = fmax(BKF_CYCLE_STIFF_TOL_MAX, g->tol);
    /* The engine's own choice (bd2x2 above BKF_CYCLE_STIFF_MU, rk8pd or
     * above BKF_CYCLE_EXPLICIT_MU_MAX bsimp where bd2x2 refuses); "the
     * other" is the stepper it does not try there. */
    bkf_error e = {0};
    int rc = BKF_ENUMERIC;
    /* A coarse solve warm-started from a sample far away costs more than a
     * cold one (the grid's jump in the tail, mu 29.6 -> 48.6 at nu -0.96:
     * 1.0 ms against 0.44 ms); precise solves gain from it even there
     * (8.7 -> 14.2: 0.87 ms against 1.0 ms). */
    double *mu_last = &g->mu_last[on_precise];
    int warm = *mu_last > 0 && (on_precise || fabs(log(mu / *mu_last)) < WARM_LN_MU_MAX);
    for (int attempt = warm ? 0 : 1; attempt < 3 && bkf_status_is_numerical(rc); attempt++) {
        o.stepper = attempt < 2 ? BKF_STEPPER_AUTO
                    : mu <= BKF_CYCLE_EXPLICIT_MU_MAX ? BKF_STEPPER_IMPLICIT : BKF_STEPPER_EXPLICIT;
        o.warm_start = attempt == 0;
        rc = bkf_cycle_solve(cycle, mu, g->p.nu, &o, &e);
    }
    if (rc != BKF_OK) return speeds_period_refused(rc, &e, g->p.nu, err);
    const bkf_cycle_result *r = bkf_cycle_get(cycle);
    *mu_last = mu;
    *T = r->period;
    *T_err = r->period_err;
    g->last_model = "shooting";
    if (precise) g->precise_solves++;
    else g->coarse_solves++;
    if (mu > g->mu_max_sampled) g->mu_max_sampled = mu;
    return BKF_OK;
}

int speeds_solve_T(grid *g, double mu, double tol, double *T, double *T_err, bkf_error *err)
{
    return speeds_solve_T_on(g, 0, mu, tol, T, T_err, err);
}

static int make_sample(grid *g, double s, int precise, sample *out, bkf_error *err)
{
    double mu = mu_of_s(g->p.gamma, s), T, T_err;
    int rc = speeds_solve_T(g, mu, precise ? g->tol : 0.0, &T, &T_err, err);
    if (rc) return rc;
    out->s = s;
    out->mu = mu;
    out->T = T;
    out->T_err = T_err;
    out->lnT = log(T);
    out->u = T_err / T + 8.0 * DBL_EPSILON;
    out->precise = precise;
    out->tail = tail_ok(g, mu, T);
    out->frozen = 0;
    return BKF_OK;
}

static int insert_sample(grid *g, const sample *smp, bkf_error *err)
{
    if (g->count >= MAX_SAMPLES)
        return bkf_error_set(err, BKF_EBUDGET,
                             "bracketing needed more than %d samples of T (near mu = %.15g)",
                             MAX_SAMPLES, smp->mu);
    if (g->count == g->cap) {
        size_t cap = g->cap ? 2 * g->cap : 64;
        sample *x = realloc(g->x, cap * sizeof *x);
        if (!x) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
        g->x = x;
        g->cap = cap;
    }
    size_t i = g->count;
    while (i > 0 && g->x[i - 1].s > smp->s) i--;
    memmove(g->x + i + 1, g->x + i, (g->count - i) * sizeof *g->x);
    g->x[i] = *smp;
    g->count++;
    return BKF_OK;
}

static int add_sample(grid *g, double s, bkf_error *err)
{
    sample smp;
    int rc = make_sample(g, s, 0, &smp, err);
    return rc ? rc : insert_sample(g, &smp, err);
}

/* Re-solve a sample at the requested tolerance: its sign against a level
 * was within the coarse noise. */
int speeds_upgrade(grid *g, size_t j, bkf_error *err)
{
    if (g->x[j].precise) return BKF_OK;
    sample smp;
    int rc = make_sample(g, g->x[j].s, 1, &smp, err);
    if (!rc) g->x[j] = smp;
    return rc;
}

/* ---------------------------------------------------------- cell bounds */

static double secant(const grid *g, size_t i)
{
    const sample *a = &g->x[i], *b = &g->x[i + 1];
    return (b->lnT - a->lnT) / (b->s - a->s);
}

double speeds_noise(const grid *g, size_t i)
{
    return (g->x[i].u + g->x[i + 1].u) / (g->x[i + 1].s - g->x[i].s);
}

/* max over t in [0, h] of min(y0 + m1 t, y1 - m0 (h - t)), m0 <= m1: the
 * highest ln g can reach on a cell from values y0, y1 at its ends with its
 * slope in [m0, m1]. */
static double envelope_max(double y0, double y1, double h, double m0, double m1)
{
    double best = fmax(fmin(y0, y1 - m0 * h), fmin(y0 + m1 * h, y1));
    if (m1 > m0) {
        double t = (y1 - y0 - m0 * h) / (m1 - m0);
        if (t > 0 && t < h) best = fmax(best, y0 + m1 * t);
    }
    return best;
}

/* A2: the slope eps = d ln T/ds on cell i lies within the secant slopes of
 * the cell and its (informative) neighbours, widened by SPREAD_FACTOR times
 * their spread and by the noise of T; ln g = ln T - s has slope eps - 1. */
cell_info speeds_classify(const grid *g, size_t i)
{
    cell_info c = {CELL_UNKNOWN, 0, 0};
    const sample *a = &g->x[i], *b = &g->x[i + 1];
    double sig = secant(g, i), nz = speeds_noise(g, i);
    double lo = sig - nz, hi = sig + nz, slo = sig, shi = sig;
    int neighbours = 0;
    for (int d = -1; d <= 1; d += 2) {
        if ((d < 0 && i == 0) || (d > 0 && i + 2 >= g->count)) continue;
        size_t j = d < 0 ? i - 1 : i + 1;
        double nj = speeds_noise(g, j);
        if (nj > 0.1) continue; /* a secant drowned in noise says nothing */
        double sj = secant(g, j);
        slo = fmin(slo, sj);
        shi = fmax(shi, sj);
        lo = fmin(lo, sj - nj);
        hi = fmax(hi, sj + nj);
        neighbours++;
    }
    double widen = neighbours ? SPREAD_FACTOR * (shi - slo) : LONE_SPREAD;
    lo -= widen;
    hi += widen;
    if (a->tail || hi < 1.0) c.shape = CELL_DEC;
    else if (lo > 1.0) c.shape = CELL_INC;
    double ua = a->u, ub = b->u, h = b->s - a->s;
    if (c.shape != CELL_UNKNOWN) {
        c.lo = fmin(lng(a) - ua, lng(b) - ub);
        c.hi = fmax(lng(a) + ua, lng(b) + ub);
    } else {
        c.hi = envelope_max(lng(a) + ua, lng(b) + ub, h, lo - 1.0, hi - 1.0);
        c.lo = -envelope_max(-(lng(a) - ua), -(lng(b) - ub), h, 1.0 - hi, 1.0 - lo);
    }
    return c;
}

/* Smallest and largest n whose level lies in [lo, hi], clipped to
 * [n_lo, n_hi]; *first > *last when there is none. */
void speeds_levels_in(const grid *g, double lo, double hi, double n_lo, double n_hi,
                      double *first, double *last)
{
    double a = ceil(exp(g->lnA - hi)), b = floor(exp(g->lnA - lo));
    if (!(a >= n_lo)) a = n_lo;
    if (!(b <= n_hi)) b = n_hi;
    *first = a;
    *last = b;
}

/* ----------------------------------------------------------- the search */

void speeds_note_unresolved(search *sr, double n, double mu, const char *why)
{
    if (sr->unresolved == 0)
        snprintf(sr->unresolved_text, sizeof sr->unresolved_text, "n = %.0f near mu = %.6g%s%s",
                 n, mu, why ? ": " : "", why ? why : "");
    sr->unresolved++;
}

/* The first sample, at s_lo: below it ln g must exceed every level of
 * interest, ell_top.  As s -> -inf, mu -> gamma+ and eps = (d ln T/d mu)
 * e^(2s)/mu -> 0, so ln g = ln T - s has slope eps - 1 -> -1.  With d ln T/d mu
 * on [gamma, mu(s_lo)] at most LOW_SLOPE_FACTOR times its secant from
 * T(gamma) (A2 again), eps < 1/2 below s_lo and ln g decreases there: it
 * stays above ln g(s_lo) > ell_top.  Each failed try moves s_lo down by 1. */
int speeds_first_sample(search *sr, double lnT_gamma, double u_gamma, double ell_top,
                        bkf_error *err)
{
    grid *g = &sr->g;
    double s_lo = lnT_gamma - ell_top - LOW_MARGIN;
    sample first;
    for (int tries = 0;; tries++) {
        int rc = make_sample(g, s_lo, 0, &first, err);
        if (rc) return rc;
        double dmu = first.mu - g->p.gamma;
        double K = dmu > 0 ? (fabs(first.lnT - lnT_gamma) + first.u + u_gamma) / dmu : 0.0;
        int slope_ok = LOW_SLOPE_FACTOR * K * exp(2.0 * s_lo) / g->p.gamma < 0.5;
        if (slope_ok && lng(&first) - first.u > ell_top) break;
        if (tries == 40) {
            speeds_note_unresolved(sr, 1, first.mu, "no level-free start found below this mu");
            break;
        }
        s_lo -= 1.0;
    }
    return insert_sample(g, &first, err);
}

/* The grid from the first sample rightwards until A3 holds at the last
 * sample and every requested level above k lies above g there. */
int speeds_build_grid(search *sr, double n_target, bkf_error *err)
{
    grid *g = &sr->g;
    int rc;
    double ell_t = n_target > 0 ? level(g, n_target) : -INFINITY;
    double mu_cap = fmax(MU_GRID_MAX, 2.0 * g->p.gamma);
    if (mu_cap > BKF_CYCLE_MU_MAX) mu_cap = BKF_CYCLE_MU_MAX;
    double s_cap = 0.5 * log((mu_cap - g->p.gamma) * (mu_cap + g->p.gamma));
    for (;;) {
        const sample *last = &g->x[g->count - 1];
        int settled = last->tail && g->count >= 2 && secant(g, g->count - 2) < 1.0;
        int below = lng(last) < ell_t - 2.0 * last->u;
        if (settled && (ell_t <= g->lnk || below)) break;
        if (last->s >= s_cap) {
            sr->asym_mu0 = last->mu;
            if (!settled)
                speeds_note_unresolved(sr, n_target, last->mu, "the large-mu tail is not certified here");
            break;
        }
        double s_next = last->s + GRID_STEP;
        if (settled && !below) {
            /* in the tail g - k ~ (b/k) mu^(-4/3): aim past the root that
             * the expansion predicts instead of walking to it */
            double lo = last->s, hi = last->s + 1.0;
            while (hi < s_cap) {
                double mu = mu_of_s(g->p.gamma, hi);
                if (log(bkf_asym_period_large(mu, g->p.nu)) - hi < ell_t) break;
                lo = hi;
                hi += 2.0 * (hi - last->s);
            }
            for (int it = 0; it < 60 && hi < s_cap; it++) {
                double mid = 0.5 * (lo + hi);
                double mu = mu_of_s(g->p.gamma, mid);
                if (log(bkf_asym_period_large(mu, g->p.nu)) - mid < ell_t) hi = mid;
                else lo = mid;
            }
            s_next = fmax(s_next, hi + 0.1);
        }
        if (s_next > s_cap) s_next = s_cap;
        /* a position where T fails (a canard explosion) is stepped over */
        for (int k = 0;; k++) {
            double at = fmin(s_next + 0.1 * GRID_STEP * k, s_cap);
            rc = add_sample(g, at, err);
            if (!bkf_status_is_numerical(rc) || k == 5 || at == s_cap) break;
        }
        if (rc) return rc;
    }
    return BKF_OK;
}

/* Bisect cell i.  Where T cannot be computed (inside a canard explosion
 * the shooting may not converge) the cell is frozen and reported instead:
 * *inserted tells which happened. */
static int refine_cell(search *sr, size_t i, double n, int *inserted, bkf_error *err)
{
    grid *g = &sr->g;
    *inserted = 0;
    if (g->x[i].frozen) return BKF_OK;
    bkf_error e = {0};
    int rc = add_sample(g, 0.5 * (g->x[i].s + g->x[i + 1].s), &e);
    if (rc == BKF_OK) {
        *inserted = 1;
        return BKF_OK;
    }
    if (!bkf_status_is_numerical(rc)) {
        if (err) *err = e;
        return rc;
    }
    g->x[i].frozen = 1;
    speeds_note_unresolved(sr, n, g->x[i].mu, "T not computable inside this cell");
    return BKF_OK;
}

/* Upgrade sample j; if the requested tolerance cannot be reached there, keep
 * the coarse value and report it. */
static int try_upgrade(search *sr, size_t j, double n, bkf_error *err)
{
    bkf_error e = {0};
    int rc = speeds_upgrade(&sr->g, j, &e);
    if (bkf_status_is_numerical(rc)) {
        sr->g.x[j].precise = 1;
        speeds_note_unresolved(sr, n, sr->g.x[j].mu, "T not computable to tol here");
        return BKF_OK;
    }
    if (rc && err) *err = e;
    return rc;
}

/* n_max: levels above the lowest sampled ln g (or k) have a root by the
 * intermediate value theorem; a lower level has one only if some cell may
 * dip below it, so such cells are refined until they cannot. */
int speeds_find_n_max(search *sr, bkf_error *err)
{
    grid *g = &sr->g;
    for (size_t rounds = 0;; rounds++) {
        double L_up = g->lnk;
        for (size_t j = 0; j < g->count; j++)
            if (lng(&g->x[j]) + 2.0 * g->x[j].u < L_up) L_up = lng(&g->x[j]) + 2.0 * g->x[j].u;
        double x = exp(g->lnA - L_up);
        double n_up = ceil(x) - 1.0;
        if (n_up < 0) n_up = 0;
        sr->n_max = n_up;
        sr->dips = L_up < g->lnk;
        sr->g_inf_ln = L_up;
        double ell_next = level(g, n_up + 1.0);
        int changed = 0;
        for (size_t i = 0; i + 1 < g->count; i++) {
            cell_info c = speeds_classify(g, i);
            if (!(c.lo < ell_next)) continue;
            const sample *a = &g->x[i], *b = &g->x[i + 1];
            if (c.shape != CELL_UNKNOWN) {
                /* the ends hold the minimum; one is within noise of the
                 * level: decide it at the requested tolerance */
                for (size_t j = i; j <= i + 1; j++)
                    if (!g->x[j].precise && lng(&g->x[j]) - 2.0 * g->x[j].u < ell_next) {
                        int rc = try_upgrade(sr, j, n_up + 1.0, err);
                        if (rc) return rc;
                        changed = 1;
                    }
                continue;
            }
            if (b->s - a->s < CELL_MIN) continue; /* reported below */
            int inserted, rc = refine_cell(sr, i, n_up + 1.0, &inserted, err);
            if (rc) return rc;
            if (!inserted) continue;
            changed = 1;
            break;
        }
        if (changed) continue;
        /* settled: what is left could still dip below the next level */
        for (size_t i = 0; i + 1 < g->count; i++) {
            cell_info c = speeds_classify(g, i);
            if (c.shape == CELL_UNKNOWN && c.lo < ell_next && !g->x[i].frozen)
                speeds_note_unresolved(sr, n_up + 1.0, g->x[i].mu, "n_max could be one more");
        }
        return BKF_OK;
    }
}

/* Cell i's enclosure of ln g lies within NOISE_BAND times its ends' noise
 * of their values: a level it leaves undecided is that close to them, and
 * bisecting does not settle it (A2's slope range, widened by the noise
 * over the cell, grows as 1/h: each half's enclosure stays about as wide
 * round its own ends).  Such a cell is left as one at CELL_MIN is: a level
 * crossing it once is polished and flagged near a tangent, one that does
 * not is a place reported unresolved.  Only with the ends at the requested
 * tolerance (else they are what to make precise).  Next to the sonic limit
 * at nu -0.9999, tol 1e-4, every sample is within 2.5 noise of the levels
 * near k and bisecting spent the whole budget of 4000 samples (n
 * 11118-11121 at gamma 1, c 0.3, S 1e4: 3841 of them at mu 1e3-1e4, 8.5 of
 * its 10 s; the places left unresolved 51 -> 12, the rows the same). */
static int noise_bound(const grid *g, size_t i, const cell_info *c)
{
    const sample *a = &g->x[i], *b = &g->x[i + 1];
    if (!(a->precise || g->tol_coarse <= g->tol) || !(b->precise || g->tol_coarse <= g->tol))
        return 0;
    double band = NOISE_BAND * (a->u + b->u);
    return c->lo >= fmin(lng(a), lng(b)) - band && c->hi <= fmax(lng(a), lng(b)) + band;
}

/* Refine until every requested level is decided on every cell. */
int speeds_resolve_levels(search *sr, bkf_error *err)
{
    grid *g = &sr->g;
    for (;;) {
        int changed = 0;
        for (size_t i = 0; i + 1 < g->count && !changed; i++) {
            cell_info c = speeds_classify(g, i);
            double first, last;
            speeds_levels_in(g, c.lo, c.hi, 1.0, sr->grid_last, &first, &last);
            if (first > last) continue;
            const sample *a = &g->x[i], *b = &g->x[i + 1];
            if (c.shape != CELL_UNKNOWN) {
                /* monotone: a level crosses iff it changes sign; make the
                 * signs at the ends certain */
                for (size_t j = i; j <= i + 1 && !changed; j++) {
                    if (g->x[j].precise) continue;
                    double lj = lng(&g->x[j]);
                    double n_near = round(exp(g->lnA - lj));
                    if (n_near < 1) n_near = 1;
                    if (fabs(lj - level(g, n_near)) <= 2.0 * g->x[j].u &&
                        n_near <= sr->grid_last) {
                        int rc = try_upgrade(sr, j, n_near, err);
                        if (rc) return rc;
                        changed = 1;
                    }
                }
                continue;
            }
            if (b->s - a->s < CELL_MIN) continue; /* reported when bracketing */
            if (noise_bound(g, i, &c)) continue; /* reported when bracketing */
            int inserted, rc = refine_cell(sr, i, first, &inserted, err);
            if (rc) return rc;
            changed = inserted;
        }
        if (!changed) return BKF_OK;
    }
}


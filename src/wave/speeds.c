/* Roots and branches of the speed-selection condition (see speeds.h).
 *
 * With c > 0 every n is a level ln R_n of one function of
 * s = ln sqrt(mu^2 - gamma^2):
 *     D_n(s) = ln T(mu(s)) - s - ln R_n,      ln g(s) = ln T - s,
 * so one grid of T serves every n.  The grid's samples are solved at a
 * coarse tolerance (they only have to give signs), the roots at what v
 * needs.  T(mu) is not assumed monotone (it is not, inside canards).  What
 * the search rests on, argued in docs/numerics.md ("why none is missed"):
 *   below the first sample, ln g decreases (eps = d ln T/ds -> 0 as
 *       mu -> gamma+, bounded there from the secant of T from T(gamma));
 *   A2  the slope eps on a cell lies within the secant slopes of the cell
 *       and its neighbours, widened by half their spread and by the noise
 *       of T: where that bound is < 1 (or > 1) ln g = ln T - s is monotone
 *       on the cell, and a level has exactly one root there if it changes
 *       sign, none otherwise; elsewhere the bound still encloses ln g;
 *   A3  beyond a sample M where the large-mu expansion
 *       T = k mu + b mu^(-1/3) + L ln(mu)/mu (b > 0 > L) holds to a quarter
 *       of its knee term and the knee term dominates the log term, g
 *       decreases to k: one root beyond M for levels in (k, g(M)), none for
 *       the others.
 * Cells that A2 cannot certify are bisected while their enclosure holds a
 * level of interest; what remains undecided at the finest cell, or where T
 * cannot be computed, is reported (near-tangent roots, unresolved places). */
#include "bkfront/speeds.h"

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

/* Grid samples only decide signs; 1e-6 costs a third of 1e-10 at mu ~ 50. */
#define COARSE_TOL 1e-6
#define GRID_STEP 0.3
#define CELL_MIN 1e-6
#define MAX_SAMPLES 4000
/* Tail certificate (A3). */
#define TAIL_MU_MIN 10.0
#define TAIL_KNEE_FRACTION 0.25
#define TAIL_LOG_DOMINANCE 4.0
/* The first sample sits this far (in ln g) above every level of interest;
 * below it ln g decreases if d ln T/d mu is at most LOW_SLOPE_FACTOR times
 * its secant from mu = gamma. */
#define LOW_MARGIN 0.5
#define LOW_SLOPE_FACTOR 4.0
/* A2: widening of the secant range, relative to its spread, and the spread
 * assumed for a cell that has no neighbour. */
#define SPREAD_FACTOR 0.5
#define LONE_SPREAD 0.25
#define MAX_POLISH_EVALS 64
/* The grid ends here at the latest (or at 2 gamma when that is larger): at
 * tol 1e-10 the cycle solver stops converging towards mu ~ 1e6 (measured at
 * nu = -0.96), while the large-mu expansion is within 6e-10 of T at 1e5
 * and its error falls as 1/mu^2: beyond, roots come from the expansion. */
#define MU_GRID_MAX 1e5
/* Interpolation relative to the large-mu expansion from here up (measured:
 * the root predictions for nu = -0.96 improve from 1e-5 to 1e-7 at mu > 5). */
#define MODEL_MU_MIN 5.0
/* Coarse solves warm-start only from a sample within this distance in
 * ln mu (the grid's steps are 0.3 and less in ln mu). */
#define WARM_LN_MU_MAX 0.4

bkf_speeds_options bkf_speeds_options_default(void)
{
    return (bkf_speeds_options){.tol = 1e-10, .n_from = 1, .n_to = 0, .method = BKF_METHOD_AUTO};
}

int bkf_speeds_check(const bkf_model_params *p, const bkf_speeds_options *o, bkf_error *err)
{
    if (!p) return bkf_error_set(err, BKF_EINPUT, "parameters are NULL");
    int rc = bkf_model_check_positive("gamma", p->gamma, err);
    if (rc) return rc;
    if (p->gamma < BKF_CYCLE_MU_MIN || p->gamma > BKF_CYCLE_MU_MAX)
        return bkf_error_set(err, BKF_EINPUT,
                             "gamma = %.15g is outside [%g, %g] (mu >= gamma must be solvable)",
                             p->gamma, BKF_CYCLE_MU_MIN, BKF_CYCLE_MU_MAX);
    if ((rc = bkf_model_check_c(p->c, err))) return rc;
    if ((rc = bkf_model_check_positive("S", p->S, err))) return rc;
    if (!isfinite(p->nu) || fabs(p->nu) >= 1.0)
        return bkf_error_set(err, BKF_EINPUT,
                             "nu = %.15g is outside (-1, 1): no fronts, uniform continuous slip "
                             "psi = nu is stable (no limit cycle)", p->nu);
    if (p->c > 0) {
        /* S/(c gamma) counts the fronts that fit (n_bound = S/(k c gamma));
         * beyond 1e15 n is no longer an exact double */
        double lnA = log(p->S) - log(p->c) - log(p->gamma);
        if (lnA > log(1e15))
            return bkf_error_set(err, BKF_EINPUT,
                                 "S/(c gamma) = %g is above 1e15: c is too small for this S "
                                 "(use c = 0)", exp(lnA));
    }
    if (o) {
        if ((rc = bkf_model_check_tol(o->tol, err))) return rc;
        if (o->n_from < 1) return bkf_error_set(err, BKF_EINPUT, "n_from = 0 must be >= 1");
        if (o->n_to && o->n_to < o->n_from)
            return bkf_error_set(err, BKF_EINPUT, "n_to = %zu is below n_from = %zu", o->n_to,
                                 o->n_from);
        if (!bkf_cycle_method_name(o->method))
            return bkf_error_set(err, BKF_EINPUT,
                                 "method must be auto, asymptotic, leading or shooting");
    }
    return BKF_OK;
}

/* ------------------------------------------------------------- the grid */

typedef struct {
    double s, mu, lnT, T, T_err;
    double u;     /* relative uncertainty of T */
    int precise;
    int tail;     /* A3 holds here */
    int frozen;   /* the cell to the right cannot be refined: T failed inside */
} sample;

typedef struct {
    bkf_model_params p;
    double tol, tol_coarse;
    double k, lnk, knee, logc;
    double lnA;               /* ln(S/(c gamma)) */
    bkf_cycle *coarse, *precise;
    bkf_cycle_method method;
    const char *last_model;   /* the model of solve_T's last answer */
    int formula_refused;      /* polish failed because the formula asked for
                                 does not meet the root's tolerance */
    sample *x;
    size_t count, cap;
    size_t coarse_solves, precise_solves, formula_answers;
    double mu_max_sampled;
    double mu_last[2];        /* the last solution in coarse, precise (0: none) */
} grid;

static double mu_of_s(double gamma, double s) { return hypot(gamma, exp(s)); }

/* |nu| up to which the speeds are verified (docs/accuracy.md, Extremes). */
#define NU_VERIFIED 0.9999

/* A refused period as the speeds' failure: the cycle's message (it names mu
 * and nu) and what to try. */
static int period_refused(int rc, const bkf_error *e, double nu, bkf_error *err)
{
    const char *hint = !bkf_status_is_numerical(rc) ? ""
                       : fabs(nu) > NU_VERIFIED
                           ? "; |nu| > 0.9999 is beyond the range where the speeds are verified "
                             "(docs/accuracy.md): try a looser tol, or |nu| <= 0.9999"
                       : rc == BKF_ETOL ? "; a looser tol may succeed"
                                        : "";
    return bkf_error_set(err, rc, "%s%s", e->message, hint);
}

static double level(const grid *g, double n) { return g->lnA - log(n); }

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
static int solve_T_on(grid *g, int scout, double mu, double tol, double *T, double *T_err,
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
    if (rc != BKF_OK) return period_refused(rc, &e, g->p.nu, err);
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

static int solve_T(grid *g, double mu, double tol, double *T, double *T_err, bkf_error *err)
{
    return solve_T_on(g, 0, mu, tol, T, T_err, err);
}

static int make_sample(grid *g, double s, int precise, sample *out, bkf_error *err)
{
    double mu = mu_of_s(g->p.gamma, s), T, T_err;
    int rc = solve_T(g, mu, precise ? g->tol : 0.0, &T, &T_err, err);
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
static int upgrade(grid *g, size_t j, bkf_error *err)
{
    if (g->x[j].precise) return BKF_OK;
    sample smp;
    int rc = make_sample(g, g->x[j].s, 1, &smp, err);
    if (!rc) g->x[j] = smp;
    return rc;
}

static double lng(const sample *x) { return x->lnT - x->s; }

/* ---------------------------------------------------------- cell bounds */

typedef enum { CELL_UNKNOWN = 0, CELL_DEC, CELL_INC } cell_shape;

typedef struct {
    cell_shape shape;
    double lo, hi;     /* enclosure of ln g on the cell */
} cell_info;

static double secant(const grid *g, size_t i)
{
    const sample *a = &g->x[i], *b = &g->x[i + 1];
    return (b->lnT - a->lnT) / (b->s - a->s);
}

static double noise(const grid *g, size_t i)
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
static cell_info classify(const grid *g, size_t i)
{
    cell_info c = {CELL_UNKNOWN, 0, 0};
    const sample *a = &g->x[i], *b = &g->x[i + 1];
    double sig = secant(g, i), nz = noise(g, i);
    double lo = sig - nz, hi = sig + nz, slo = sig, shi = sig;
    int neighbours = 0;
    for (int d = -1; d <= 1; d += 2) {
        if ((d < 0 && i == 0) || (d > 0 && i + 2 >= g->count)) continue;
        size_t j = d < 0 ? i - 1 : i + 1;
        double nj = noise(g, j);
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
static void levels_in(const grid *g, double lo, double hi, double n_lo, double n_hi,
                      double *first, double *last)
{
    double a = ceil(exp(g->lnA - hi)), b = floor(exp(g->lnA - lo));
    if (!(a >= n_lo)) a = n_lo;
    if (!(b <= n_hi)) b = n_hi;
    *first = a;
    *last = b;
}

/* ----------------------------------------------------------- the search */

typedef struct {
    double n;        /* level */
    size_t cell;     /* index of the left sample */
    int near_tangent;
} bracket;

typedef struct {
    grid g;
    double n_from, n_last;       /* requested levels (n_last may be lowered to n_max) */
    double grid_last;            /* levels 1..grid_last shape the grid, whatever was requested */
    double n_max;                /* levels 1..n_max have a root */
    int dips;
    double g_inf_ln;
    /* unresolved places */
    size_t unresolved;
    char unresolved_text[96];
    double asym_mu0;             /* the grid ended at its cap (MU_GRID_MAX) */
} search;

static void note_unresolved(search *sr, double n, double mu, const char *why)
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
static int first_sample(search *sr, double lnT_gamma, double u_gamma, double ell_top,
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
            note_unresolved(sr, 1, first.mu, "no level-free start found below this mu");
            break;
        }
        s_lo -= 1.0;
    }
    return insert_sample(g, &first, err);
}

/* The grid from the first sample rightwards until A3 holds at the last
 * sample and every requested level above k lies above g there. */
static int build_grid(search *sr, double n_target, bkf_error *err)
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
                note_unresolved(sr, n_target, last->mu, "the large-mu tail is not certified here");
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
    note_unresolved(sr, n, g->x[i].mu, "T not computable inside this cell");
    return BKF_OK;
}

/* Upgrade sample j; if the requested tolerance cannot be reached there, keep
 * the coarse value and report it. */
static int try_upgrade(search *sr, size_t j, double n, bkf_error *err)
{
    bkf_error e = {0};
    int rc = upgrade(&sr->g, j, &e);
    if (bkf_status_is_numerical(rc)) {
        sr->g.x[j].precise = 1;
        note_unresolved(sr, n, sr->g.x[j].mu, "T not computable to tol here");
        return BKF_OK;
    }
    if (rc && err) *err = e;
    return rc;
}

/* n_max: levels above the lowest sampled ln g (or k) have a root by the
 * intermediate value theorem; a lower level has one only if some cell may
 * dip below it, so such cells are refined until they cannot. */
static int find_n_max(search *sr, bkf_error *err)
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
            cell_info c = classify(g, i);
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
            cell_info c = classify(g, i);
            if (c.shape == CELL_UNKNOWN && c.lo < ell_next && !g->x[i].frozen)
                note_unresolved(sr, n_up + 1.0, g->x[i].mu, "n_max could be one more");
        }
        return BKF_OK;
    }
}

/* Refine until every requested level is decided on every cell. */
static int resolve_levels(search *sr, bkf_error *err)
{
    grid *g = &sr->g;
    for (;;) {
        int changed = 0;
        for (size_t i = 0; i + 1 < g->count && !changed; i++) {
            cell_info c = classify(g, i);
            double first, last;
            levels_in(g, c.lo, c.hi, 1.0, sr->grid_last, &first, &last);
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
            int inserted, rc = refine_cell(sr, i, first, &inserted, err);
            if (rc) return rc;
            changed = inserted;
        }
        if (!changed) return BKF_OK;
    }
}

/* ------------------------------------------------------------ polishing */

typedef struct {
    double s, D, T, T_err;
    const char *model;
} peval;

typedef struct {
    grid *g;
    double ell, tol;
    peval ev[MAX_POLISH_EVALS];
    size_t nev;
    int status;
    bkf_error *err;
} polish_ctx;

/* D at the requested tolerance; Brent asks again for the bracket's ends,
 * which are answered from the evaluations already made. */
static double polish_f(double s, void *data)
{
    polish_ctx *pc = data;
    for (size_t i = 0; i < pc->nev; i++)
        if (pc->ev[i].s == s) return pc->ev[i].D;
    if (pc->status) return NAN;
    if (pc->nev == MAX_POLISH_EVALS) {
        pc->status = bkf_error_set(pc->err, BKF_EBUDGET,
                                   "root polishing needed more than %d solves near mu = %.15g",
                                   MAX_POLISH_EVALS, mu_of_s(pc->g->p.gamma, s));
        return NAN;
    }
    double T, T_err;
    int rc = solve_T(pc->g, mu_of_s(pc->g->p.gamma, s), pc->tol, &T, &T_err, pc->err);
    if (rc) {
        pc->status = rc;
        return NAN;
    }
    peval *e = &pc->ev[pc->nev++];
    *e = (peval){s, log(T) - s - pc->ell, T, T_err, pc->g->last_model};
    return e->D;
}

/* The closest pair of evaluations of opposite sign. */
static int bracket_of(const polish_ctx *pc, double *lo, double *hi)
{
    double width = INFINITY;
    for (size_t i = 0; i < pc->nev; i++)
        for (size_t j = 0; j < pc->nev; j++) {
            const peval *a = &pc->ev[i], *b = &pc->ev[j];
            if (a->s < b->s && (a->D > 0) != (b->D > 0) && b->s - a->s < width) {
                width = b->s - a->s;
                if (lo) *lo = a->s;
                if (hi) *hi = b->s;
            }
        }
    return isfinite(width);
}

static const peval *best_eval(const polish_ctx *pc)
{
    const peval *best = NULL;
    for (size_t i = 0; i < pc->nev; i++)
        if (!best || fabs(pc->ev[i].D) < fabs(best->D)) best = &pc->ev[i];
    return best;
}

/* ln T between samples: a polynomial through up to INTERP_POINTS samples
 * around the cell, of ln T itself or, where mu >= MODEL_MU_MIN at all of
 * them, of mu^2 (ln T - ln T_expansion), which the next, O(1/mu), term of T
 * makes nearly constant: smoother by far.  The coarse samples are far more
 * accurate than the interpolation (1e-9 against 1e-5 relative at nu -0.96,
 * mu 2-5), so degree 5 rather than 3 predicts the roots 2-30 times closer
 * there (fewer polishing solves: 34 -> 32 for the paper's table, 104 -> 80 at
 * gamma 1, c 0.5, nu 0, S 30); 7 and 8 points gained no more. */
#define INTERP_POINTS 6
/* Relative error of the interpolated slope of D (measured 1e-3 at nu -0.96,
 * mu 2-5): a prediction uncertain by more than target/this gets a coarse
 * solve first (below). */
#define SCOUT_SLOPE_ERROR 1e-3
/* The scout's tolerance relative to the root's (at most the coarse one):
 * 1e-7 instead of 1e-6 costs 10-30% more per scout and saved a precise solve
 * on 2 of 12 roots of the paper's table, 4 of 37 at gamma 1, c 0.5, nu 0. */
#define SCOUT_TOL_FACTOR 1000.0
typedef struct {
    double s[INTERP_POINTS], r[INTERP_POINTS];
    int m, model;
    double gamma, nu;
} interp;

static double model_lnT(const interp *ip, double s)
{
    return ip->model ? log(bkf_asym_period_large(mu_of_s(ip->gamma, s), ip->nu)) : 0.0;
}

static void interp_init(interp *ip, const grid *g, size_t i, size_t points)
{
    size_t half = points / 2, m = g->count < points ? g->count : points;
    size_t j0 = i + 1 >= half ? i + 1 - half : 0;
    if (j0 + m > g->count) j0 = g->count - m;
    size_t j1 = j0 + m - 1;
    ip->m = (int)m;
    ip->gamma = g->p.gamma;
    ip->nu = g->p.nu;
    ip->model = 1;
    for (size_t j = j0; j <= j1; j++)
        if (g->x[j].mu < MODEL_MU_MIN) ip->model = 0;
    for (int q = 0; q < ip->m; q++) {
        const sample *x = &g->x[j0 + (size_t)q];
        ip->s[q] = x->s;
        ip->r[q] = (x->lnT - model_lnT(ip, x->s)) * (ip->model ? x->mu * x->mu : 1.0);
    }
}

static double interp_lnT(const interp *ip, double s)
{
    double sum = 0.0;
    for (int q = 0; q < ip->m; q++) {
        double w = 1.0;
        for (int r = 0; r < ip->m; r++)
            if (r != q) w *= (s - ip->s[r]) / (ip->s[q] - ip->s[r]);
        sum += w * ip->r[q];
    }
    if (!ip->model) return sum;
    double mu = mu_of_s(ip->gamma, s);
    return model_lnT(ip, s) + sum / (mu * mu);
}

/* Predicted root of level ell in cell i (ends of opposite sign) and the
 * slope of D there. */
static void predict(const grid *g, size_t i, double ell, double *root, double *slope,
                    double *uncertainty)
{
    interp ip, lower;
    interp_init(&ip, g, i, INTERP_POINTS);
    interp_init(&lower, g, i, INTERP_POINTS - 2);
    double a = g->x[i].s, b = g->x[i + 1].s;
    double fa = lng(&g->x[i]) - ell;
    for (int it = 0; it < 80 && b - a > 4.0 * DBL_EPSILON * fabs(a + b); it++) {
        double mid = 0.5 * (a + b);
        double fm = interp_lnT(&ip, mid) - mid - ell;
        if ((fm > 0) == (fa > 0)) {
            a = mid;
            fa = fm;
        } else
            b = mid;
    }
    *root = 0.5 * (a + b);
    double h = 1e-4 * (g->x[i + 1].s - g->x[i].s);
    *slope = (interp_lnT(&ip, *root + h) - interp_lnT(&ip, *root - h)) / (2.0 * h) - 1.0;
    /* the interpolant of two lower degree: its distance bounds (in practice
     * overstates) the error of ln T at the prediction */
    *uncertainty = fabs(interp_lnT(&ip, *root) - interp_lnT(&lower, *root));
}

typedef struct {
    double n, s, T, T_err, D, slope;
    unsigned flags;
    const char *model;
} found_root;

/* The root of level n of formula `f` near r0 (within a few cells either
 * side, so that another root of the same n is not taken), by bisection on
 * ln T_f(mu(s)) - s - ell; its bound must meet tol at the root itself. */
static int formula_root(const grid *g, double n, double r0, double width, bkf_asym_formula f,
                        double tol, found_root *out)
{
    double ell = level(g, n), nu = g->p.nu;
#define DF(x) (log(bkf_asym_period(f, mu_of_s(g->p.gamma, (x)), nu)) - (x) - ell)
    double lo = r0 - width, hi = r0 + width, dlo = DF(lo), dhi = DF(hi);
    for (int k = 0; k < 4 && (dlo > 0) == (dhi > 0); k++) {
        lo -= width;
        hi += width;
        dlo = DF(lo);
        dhi = DF(hi);
    }
    if (!isfinite(dlo) || !isfinite(dhi) || (dlo > 0) == (dhi > 0)) return 0;
    for (int it = 0; it < 200 && hi - lo > 4.0 * DBL_EPSILON * fmax(1.0, fabs(lo)); it++) {
        double mid = 0.5 * (lo + hi), dm = DF(mid);
        if ((dm > 0) == (dlo > 0)) {
            lo = mid;
            dlo = dm;
        } else {
            hi = mid;
        }
    }
    double s = 0.5 * (lo + hi), mu = mu_of_s(g->p.gamma, s);
    double bound = bkf_asym_error_bound(f, mu, nu);
    if (!(bound <= tol)) return 0;
    double h = 1e-6 * fmax(1.0, fabs(s));
    double slope = (DF(s + h) - DF(s - h)) / (2.0 * h);
#undef DF
    double T = bkf_asym_period(f, mu, nu);
    *out = (found_root){n, s, T, bound * T, log(T) - s - ell, slope, 0,
                        f == BKF_ASYM_LEADING ? "leading" : "asymptotic"};
    return 1;
}

/* The root of level n in cell i: a precise solve at the interpolated
 * prediction, a Newton step a little past it for a tight bracket, then
 * Brent (gsl_root) until |D| is small enough.
 *
 * tol is asked of v: with sens = |dD/ds| mu^2/gamma^2, a relative error e
 * of T or a residual D moves v by (e or D)/sens relatively, so T is solved
 * to tol sens/2 and D brought below min(tol, tol sens/2).  Near the sonic
 * end sens is large and T may be looser, up to 10 tol (beyond, the noise of
 * T would keep |D| from reaching tol); at a fold sens -> 0 and v_err says
 * what was reached. */
/* A root not polished to tol is tried at this many times tol, to tell a
 * tol beyond what T gives there (refused) from no T at all (unresolved). */
#define LOOSE_FACTOR 100.0

static int polish(grid *g, gsl_root_fsolver *fs, double n, size_t i, found_root *out,
                  bkf_error *err)
{
    polish_ctx pc = {.g = g, .ell = level(g, n), .nev = 0, .status = 0, .err = err};
    double sa = g->x[i].s, sb = g->x[i + 1].s;
    double r0, slope0, unc0;
    predict(g, i, pc.ell, &r0, &slope0, &unc0);
    /* an interpolant through samples crowded into a steep canard can be
     * useless: fall back on the cell's secant */
    if (!isfinite(slope0) || slope0 == 0 || !(r0 > sa && r0 < sb)) {
        unc0 = INFINITY;
        slope0 = (lng(&g->x[i + 1]) - lng(&g->x[i])) / (sb - sa);
        r0 = sa - (lng(&g->x[i]) - pc.ell) / slope0;
        if (!(r0 > sa && r0 < sb)) r0 = 0.5 * (sa + sb);
    }
    double mu0 = mu_of_s(g->p.gamma, r0);
    double sens = fabs(slope0) * (mu0 / g->p.gamma) * (mu0 / g->p.gamma);
    double f = fmin(fmax(0.5 * sens, 0.1), 10.0);
    pc.tol = fmin(fmax(g->tol * f, BKF_TOL_MIN), BKF_TOL_MAX);
    const double target = g->tol * fmin(1.0, f);
    if (g->method != BKF_METHOD_SHOOTING) {
        /* a formula where its verified bound meets what this root needs */
        double Tf, bound = INFINITY;
        int form = -1;
        if (g->method == BKF_METHOD_LEADING) {
            bound = bkf_asym_error_bound(BKF_ASYM_LEADING, mu0, g->p.nu);
            if (bound <= pc.tol) form = BKF_ASYM_LEADING;
        } else {
            form = bkf_asym_choose(mu0, g->p.nu, pc.tol, g->method == BKF_METHOD_AUTO, &Tf, &bound);
            if (form < 0 && g->method == BKF_METHOD_ASYMPTOTIC)
                bound = fmin(bkf_asym_error_bound(BKF_ASYM_LARGE, mu0, g->p.nu),
                             bkf_asym_error_bound(BKF_ASYM_SMALL, mu0, g->p.nu));
        }
        g->formula_refused = 0;
        if (form >= 0 && formula_root(g, n, r0, sb - sa, (bkf_asym_formula)form, pc.tol, out)) {
            g->formula_answers++;
            return BKF_OK;
        }
        g->formula_refused = 1;
        if (g->method != BKF_METHOD_AUTO)
            return bkf_error_set(err, BKF_ETOL,
                                 "%s formula for n = %.0f at mu = %.15g, nu = %.15g: error bound %.2g "
                                 "exceeds the tolerance %g of T this root needs (outside its "
                                 "validity; use --method shooting or auto)",
                                 bkf_cycle_method_name(g->method), n, mu0, g->p.nu, bound, pc.tol);
    }
    if (unc0 * SCOUT_SLOPE_ERROR > target && g->tol_coarse > 10.0 * pc.tol) {
        /* Where the samples predict the root poorly (1e-5..1e-3 in ln T next
         * to a canard, nu -0.96, mu 2-5), the secant step after the first
         * precise solve still misses the target and a third follows.  A
         * looser solve (2-3 times cheaper) moves the prediction first, and
         * warm-starts the precise one. */
        double Tc, Tc_err;
        bkf_error e = {0};
        double scout_tol = fmin(g->tol_coarse, SCOUT_TOL_FACTOR * pc.tol);
        if (solve_T_on(g, 1, mu0, scout_tol, &Tc, &Tc_err, &e) == BKF_OK) {
            double r1 = r0 - (log(Tc) - r0 - pc.ell) / slope0;
            if (r1 > sa && r1 < sb) r0 = r1;
        }
    }
    double D0 = polish_f(r0, &pc);
    if (pc.status) return pc.status;
    /* secant steps from the interpolated slope, kept in the cell; they
     * usually meet the target in one or two solves */
    double r = r0, D = D0, sl = slope0;
    for (int attempt = 0; attempt < 4 && fabs(best_eval(&pc)->D) > target; attempt++) {
        if (bracket_of(&pc, NULL, NULL)) break;
        double r1 = r - D / sl;
        if (!(r1 > sa && r1 < sb)) r1 = r1 >= sb ? 0.5 * (r + sb) : 0.5 * (r + sa);
        double D1 = polish_f(r1, &pc);
        if (pc.status) return pc.status;
        if (r1 != r) sl = (D1 - D) / (r1 - r);
        if (!(sl < 0 || sl > 0) || (sl > 0) != (slope0 > 0)) sl = slope0;
        r = r1;
        D = D1;
    }
    if (fabs(best_eval(&pc)->D) > target) {
        /* Brent on the tightest bracket at hand, or on the whole cell with
         * its ends solved at the root's tolerance */
        double lo, hi;
        if (!bracket_of(&pc, &lo, &hi)) {
            double Da = polish_f(sa, &pc), Db = polish_f(sb, &pc);
            if (pc.status) return pc.status;
            if ((Da > 0) == (Db > 0))
                return bkf_error_set(err, BKF_ENUMERIC,
                                     "the root for n = %.0f near mu = %.15g left its cell at the "
                                     "root's tolerance (T too noisy there?)",
                                     n, mu_of_s(g->p.gamma, r0));
            bracket_of(&pc, &lo, &hi);
        }
        gsl_function F = {polish_f, &pc};
        if (gsl_root_fsolver_set(fs, &F, lo, hi) != GSL_SUCCESS)
            return pc.status ? pc.status
                             : bkf_error_set(err, BKF_ENUMERIC, "Brent could not start near mu = %.15g",
                                             mu_of_s(g->p.gamma, lo));
        for (int it = 0; it < 100 && fabs(best_eval(&pc)->D) > target; it++) {
            int st = gsl_root_fsolver_iterate(fs);
            if (pc.status) return pc.status;
            if (st != GSL_SUCCESS)
                return bkf_error_set(err, BKF_ENUMERIC, "Brent failed near mu = %.15g: %s",
                                     mu_of_s(g->p.gamma, lo), gsl_strerror(st));
            double xl = gsl_root_fsolver_x_lower(fs), xu = gsl_root_fsolver_x_upper(fs);
            if (xu - xl <= 4.0 * DBL_EPSILON * fmax(fabs(xl), fabs(xu)) + DBL_MIN) break;
        }
    }
    const peval *best = best_eval(&pc), *far = NULL;
    double lo, hi;
    if (fabs(best->D) > target && bracket_of(&pc, &lo, &hi)) {
        /* Brent closed on a jump of T: inside a canard explosion (nu
         * -0.9999, mu 35.3659-35.3661: T 13 -> 114) the warm-started solves
         * can land on the wrong side (T 113 at mu 35.365918, where it is
         * 13.2), and the best |D| sat at the cell's far end (mu 46.5 for a
         * root near 35.37: 168 times its v_err, 3.6 tol off).  Where both
         * ends of the bracket miss the level by more than their noise no T
         * meets it: the root is reported as not polished. */
        const peval *end[2] = {NULL, NULL};
        for (size_t j = 0; j < pc.nev; j++) {
            if (pc.ev[j].s == lo) end[0] = &pc.ev[j];
            if (pc.ev[j].s == hi) end[1] = &pc.ev[j];
        }
        int jump = 1;
        for (int k = 0; k < 2; k++)
            if (!end[k] || fabs(end[k]->D) <= 2.0 * (target + end[k]->T_err / end[k]->T)) jump = 0;
        if (jump)
            return bkf_error_set(err, BKF_ENUMERIC,
                                 "T jumps across the level of n = %.0f near mu = %.15g (a canard "
                                 "explosion): no computed T meets it",
                                 n, mu_of_s(g->p.gamma, lo));
    }
    /* the slope for the error estimate: the flattest of the interpolated
     * slope at the root, the secant from the best point to the farthest
     * one and the secants from the best point that stand above the noise
     * of T (ten times the two solves' estimates).  D curves across a cell
     * where T nears k mu: at mu 1409 (gamma 1, c 1, nu -0.5) d ln T/ds - 1
     * is -3.9e-4 at the root, the far secant alone -0.026, and v_err came
     * out 6 times too small. */
    for (size_t j = 0; j < pc.nev; j++)
        if (!far || fabs(pc.ev[j].s - best->s) > fabs(far->s - best->s)) far = &pc.ev[j];
    double slope = far->s != best->s ? (far->D - best->D) / (far->s - best->s) : slope0;
    if (!(slope < 0 || slope > 0) || (slope > 0) != (slope0 > 0)) slope = slope0;
    for (size_t j = 0; j < pc.nev; j++) {
        const peval *e = &pc.ev[j];
        double noise = 10.0 * (e->T_err / e->T + best->T_err / best->T);
        if (e->s == best->s || !(fabs(e->D - best->D) > noise)) continue;
        double sl = (e->D - best->D) / (e->s - best->s);
        if ((sl > 0) == (slope0 > 0) && fabs(sl) < fabs(slope)) slope = sl;
    }
    if (isfinite(slope0) && fabs(slope0) < fabs(slope)) slope = slope0;
    *out = (found_root){n, best->s, best->T, best->T_err, best->D, slope, 0, best->model};
    return BKF_OK;
}

/* The root of a level beyond the grid's cap, on the large-mu expansion,
 * whose next (O(1/mu)) term is estimated from the last sample (solved at
 * the requested tolerance by then). */
static void asymptotic_root(const grid *g, double n, found_root *out)
{
    const sample *last = &g->x[g->count - 1];
    double ell = level(g, n), lo = last->s, hi = last->s + 1.0;
    while (log(bkf_asym_period_large(mu_of_s(g->p.gamma, hi), g->p.nu)) - hi > ell && hi < 700)
        hi = lo + 2.0 * (hi - lo);
    for (int it = 0; it < 200; it++) {
        double mid = 0.5 * (lo + hi);
        if (log(bkf_asym_period_large(mu_of_s(g->p.gamma, mid), g->p.nu)) - mid > ell) lo = mid;
        else hi = mid;
    }
    double s = 0.5 * (lo + hi), mu = mu_of_s(g->p.gamma, s);
    double T = bkf_asym_period_large(mu, g->p.nu);
    double rem = fabs(last->T - bkf_asym_period_large(last->mu, g->p.nu)) * last->mu / mu;
    double h = 1e-6;
    double slope = (log(bkf_asym_period_large(mu_of_s(g->p.gamma, s + h), g->p.nu)) -
                    log(bkf_asym_period_large(mu_of_s(g->p.gamma, s - h), g->p.nu))) / (2 * h) - 1.0;
    *out = (found_root){n, s, T, rem + last->T_err * last->mu / mu, log(T) - s - ell, slope,
                        BKF_SPEEDS_ASYMPTOTIC, "asymptotic"};
}

/* ----------------------------------------------------------------- rows */

static void fill_row(const bkf_model_params *p, double k, const found_root *f,
                     bkf_speeds_root *row)
{
    double n = f->n;
    memset(row, 0, sizeof *row);
    row->n = (size_t)n;
    row->T = f->T;
    row->T_err = f->T_err;
    row->wavelength = p->S / n;
    row->v_asym = p->S / (n * k * p->gamma);
    row->flags = f->flags;
    row->slope = f->slope;
    row->model = f->model;
    double uT = f->T_err / f->T;
    if (p->c > 0) {
        double ratio = hypot(1.0, p->gamma * exp(-f->s)); /* v/c = mu / sqrt(mu^2 - gamma^2) */
        row->mu = mu_of_s(p->gamma, f->s);
        row->v_over_c = ratio;
        row->v = p->c * ratio;
        row->period_fixed = f->T * p->gamma / row->mu;
        row->residual = expm1(f->D);
        /* d ln v / ds = -gamma^2/mu^2; ds = (|D| + uT) / |dD/ds| */
        double g2 = p->gamma / row->mu;
        row->v_err = row->v * (g2 * g2 * (fabs(f->D) + uT) / fabs(f->slope) + 4.0 * DBL_EPSILON);
        if (!isfinite(row->v_err)) row->v_err = INFINITY;
    } else {
        row->mu = p->gamma;
        row->v_over_c = INFINITY;
        row->v = p->S / (n * f->T);
        row->period_fixed = f->T;
        row->residual = n * f->T * row->v / p->S - 1.0;
        row->v_err = row->v * (uT + 4.0 * DBL_EPSILON);
    }
    row->deviation = (row->v - row->v_asym) / row->v;
}

static int push_root(bkf_speeds_table *t, size_t *cap, const bkf_speeds_root *r, bkf_error *err)
{
    if (t->count == *cap) {
        size_t nc = *cap ? 2 * *cap : 16;
        bkf_speeds_root *x = realloc(t->roots, nc * sizeof *x);
        if (!x) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
        t->roots = x;
        *cap = nc;
    }
    t->roots[t->count++] = *r;
    return BKF_OK;
}

static int compare_found(const void *a, const void *b)
{
    const found_root *x = a, *y = b;
    if (x->n != y->n) return x->n < y->n ? -1 : 1;
    return (x->s > y->s) - (x->s < y->s);
}

static void append_note(bkf_speeds_table *t, const char *text)
{
    size_t used = strlen(t->note);
    snprintf(t->note + used, sizeof t->note - used, "%s%s", used ? "; " : "", text);
}

void bkf_speeds_table_free(bkf_speeds_table *t)
{
    if (!t) return;
    free(t->roots);
    t->roots = NULL;
    t->count = 0;
}

static int find_c0(const bkf_model_params *p, const bkf_speeds_options *o, bkf_speeds_table *t,
                   bkf_error *err)
{
    bkf_cycle_options co = bkf_cycle_options_default();
    co.tol = o->tol; /* v = S/(n T): v needs T to tol */
    bkf_cycle_result r;
    bkf_error e = {0};
    bkf_cycle *cycle = bkf_cycle_alloc();
    if (!cycle) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    int rc = bkf_cycle_estimate(cycle, p->gamma, p->nu, &co, o->method, &r, &e);
    bkf_cycle_free(cycle);
    if (rc) return period_refused(rc, &e, p->nu, err);
    if (strcmp(r.model, "shooting") == 0) t->precise_solves = 1;
    else t->formula_answers = 1;
    t->mu_grid_max = p->gamma;
    t->n_max = -1;
    t->g_inf = NAN;
    size_t last = o->n_to ? o->n_to : o->n_from + BKF_SPEEDS_ROWS_C0 - 1, cap = 0;
    for (size_t n = o->n_from; n <= last; n++) {
        found_root f = {(double)n, 0, r.period, r.period_err, 0, 0, 0, r.model};
        bkf_speeds_root row;
        fill_row(p, t->k, &f, &row);
        if ((rc = push_root(t, &cap, &row, err))) return rc;
    }
    append_note(t, "c = 0: every n has the front v = S/(n T(gamma)), mu = gamma");
    return BKF_OK;
}

static int speeds_find_body(const bkf_model_params *p, const bkf_speeds_options *options,
                            bkf_speeds_table *t, bkf_error *err)
{
    if (!t) return bkf_error_set(err, BKF_EINPUT, "table is NULL");
    memset(t, 0, sizeof *t);
    bkf_speeds_options o = options ? *options : bkf_speeds_options_default();
    int rc = bkf_speeds_check(p, &o, err);
    if (rc) return rc;
    t->k = bkf_asym_k(p->nu);
    t->n_bound = p->c > 0 ? p->S / (t->k * p->c * p->gamma) : INFINITY;
    if (p->c == 0) return find_c0(p, &o, t, err);

    search sr;
    memset(&sr, 0, sizeof sr);
    grid *g = &sr.g;
    g->p = *p;
    g->tol = o.tol;
    g->tol_coarse = fmax(o.tol, COARSE_TOL);
    g->method = o.method;
    g->k = t->k;
    g->lnk = log(t->k);
    g->knee = bkf_asym_knee_coefficient(p->nu);
    g->logc = bkf_asym_log_coefficient(p->nu);
    g->lnA = log(p->S) - log(p->c) - log(p->gamma);
    g->coarse = bkf_cycle_alloc();
    g->precise = bkf_cycle_alloc();
    found_root *found = NULL;
    size_t nfound = 0, found_cap = 0, rows_cap = 0;
    gsl_root_fsolver *fs = gsl_root_fsolver_alloc(gsl_root_fsolver_brent);
    if (!g->coarse || !g->precise || !fs) {
        rc = bkf_error_set(err, BKF_ENOMEM, "out of memory");
        goto done;
    }

    double T_gamma, T_gamma_err;
    if ((rc = solve_T(g, p->gamma, 0, &T_gamma, &T_gamma_err, err))) goto done;
    sr.n_from = (double)o.n_from;
    double n_star = ceil(exp(g->lnA - g->lnk)) - 1.0; /* levels strictly above k */
    double n_req_last = o.n_to ? (double)o.n_to : sr.n_from + BKF_SPEEDS_MAX_ROWS - 1;
    /* The grid, its refinement and its precise samples are those of the
     * whole table (levels 1 .. BKF_SPEEDS_MAX_ROWS, or the last requested
     * if beyond), so a root does not depend on which rows were asked for:
     * speeds --n 4 gave 0.48545916040133913 where the table gave
     * 0.48545916040196629 (issue 36). */
    double grid_last = fmax(n_req_last, (double)BKF_SPEEDS_MAX_ROWS);
    double n_target = fmin(grid_last, n_star);
    if (n_target < 1) n_target = 0;
    if ((rc = first_sample(&sr, log(T_gamma), T_gamma_err / T_gamma + 8.0 * DBL_EPSILON,
                           fmax(level(g, 1.0), g->lnk), err)))
        goto done;
    if ((rc = build_grid(&sr, n_target, err))) goto done;
    if ((rc = find_n_max(&sr, err))) goto done;

    t->n_max = (long)sr.n_max;
    t->dips_below_k = sr.dips;
    t->g_inf = sr.dips ? exp(sr.g_inf_ln) : t->k;
    sr.n_last = fmin(n_req_last, sr.n_max);
    sr.grid_last = fmin(grid_last, sr.n_max);
    if (!o.n_to && sr.n_max > n_req_last) t->truncated = 1;

    if (sr.n_last >= sr.n_from) {
        if ((rc = resolve_levels(&sr, err))) goto done;
        /* the last sample's precise solve, as the table's (the tail's roots) */
        if (sr.asym_mu0 > 0 && (rc = upgrade(g, g->count - 1, err))) goto done;
        /* brackets, cell by cell so that precise solves warm-start */
        for (size_t i = 0; i + 1 < g->count; i++) {
            cell_info c = classify(g, i);
            double first, last;
            levels_in(g, c.lo, c.hi, sr.n_from, sr.n_last, &first, &last);
            for (double n = first; n <= last; n++) {
                double ell = level(g, n);
                int da = lng(&g->x[i]) - ell > 0, db = lng(&g->x[i + 1]) - ell > 0;
                if (da == db) {
                    if (c.shape == CELL_UNKNOWN) note_unresolved(&sr, n, g->x[i].mu, NULL);
                    continue;
                }
                if (nfound == found_cap) {
                    size_t nc = found_cap ? 2 * found_cap : 16;
                    found_root *x = realloc(found, nc * sizeof *x);
                    if (!x) {
                        rc = bkf_error_set(err, BKF_ENOMEM, "out of memory");
                        goto done;
                    }
                    found = x;
                    found_cap = nc;
                }
                bkf_error pe = {0};
                /* each root's precise solves start cold: warm from the root
                 * polished before, its value would depend on the rows asked */
                g->mu_last[1] = 0;
                rc = polish(g, fs, n, i, &found[nfound], &pe);
                if (bkf_status_is_numerical(rc) && !(g->formula_refused && g->method != BKF_METHOD_AUTO)) {
                    /* Had at a looser tolerance, the root exists and the tol
                     * asked is beyond what T gives there: refused, never left
                     * out of a table that succeeds (issue 31: at tol 1e-14 the
                     * paper's table kept 4 of its 12 rows, exit 0).  Not had
                     * at all (inside a canard explosion T jumps across the
                     * level): reported as unresolved, the other rows stand. */
                    double tol = g->tol;
                    found_root loose;
                    bkf_error le = {0};
                    g->tol = fmin(LOOSE_FACTOR * tol, BKF_TOL_MAX);
                    g->mu_last[1] = 0;
                    int lrc = g->tol > tol ? polish(g, fs, n, i, &loose, &le) : rc;
                    g->tol = tol;
                    if (lrc == BKF_OK) {
                        rc = bkf_error_set(err, BKF_ETOL,
                                           "n = %.0f: the root near mu = %.6g (v = %.6g) cannot be polished "
                                           "to tol %g, only to %g (%s)",
                                           n, mu_of_s(g->p.gamma, loose.s),
                                           g->p.c / sqrt(1.0 - pow(g->p.gamma / mu_of_s(g->p.gamma, loose.s), 2)),
                                           tol, fmin(LOOSE_FACTOR * tol, BKF_TOL_MAX), pe.message);
                        goto done;
                    }
                    note_unresolved(&sr, n, g->x[i].mu, "root not polished (T failed)");
                    rc = BKF_OK;
                    continue;
                }
                if (rc) {
                    *err = pe;
                    goto done;
                }
                if (c.shape == CELL_UNKNOWN) found[nfound].flags |= BKF_SPEEDS_NEAR_TANGENT;
                nfound++;
            }
        }
        /* levels whose root lies beyond the last sample, at the grid's cap */
        if (sr.asym_mu0 > 0) {
            if ((rc = upgrade(g, g->count - 1, err))) goto done;
            const sample *last = &g->x[g->count - 1];
            double first, lastn;
            levels_in(g, g->lnk, lng(last), sr.n_from, sr.n_last, &first, &lastn);
            for (double n = first; n <= lastn; n++) {
                if (!(level(g, n) > g->lnk && level(g, n) < lng(last))) continue;
                if (nfound == found_cap) {
                    size_t nc = found_cap ? 2 * found_cap : 16;
                    found_root *x = realloc(found, nc * sizeof *x);
                    if (!x) {
                        rc = bkf_error_set(err, BKF_ENOMEM, "out of memory");
                        goto done;
                    }
                    found = x;
                    found_cap = nc;
                }
                asymptotic_root(g, n, &found[nfound++]);
            }
        }
        qsort(found, nfound, sizeof *found, compare_found);
        /* two roots of one n close together sit near a fold */
        for (size_t j = 0; j + 1 < nfound; j++)
            if (found[j].n == found[j + 1].n && found[j + 1].s - found[j].s < 0.05) {
                found[j].flags |= BKF_SPEEDS_NEAR_TANGENT;
                found[j + 1].flags |= BKF_SPEEDS_NEAR_TANGENT;
            }
        for (size_t j = 0; j < nfound; j++) {
            bkf_speeds_root row;
            fill_row(p, t->k, &found[j], &row);
            if ((rc = push_root(t, &rows_cap, &row, err))) goto done;
        }
    }

    char line[400];
    if (t->n_max == 0) {
        if (sr.dips)
            snprintf(line, sizeof line,
                     "no front: S/(c gamma) = %.6g is at most the minimum %.6g of "
                     "T(mu)/sqrt(mu^2 - gamma^2) over mu > gamma (n = 1 needs more)",
                     exp(g->lnA), t->g_inf);
        else
            snprintf(line, sizeof line,
                     "no front: S = %.6g <= k(nu) c gamma = %.6g (n fronts need "
                     "S > n k(nu) c gamma)", p->S, t->k * p->c * p->gamma);
        append_note(t, line);
    } else if (t->count == 0 && sr.n_from > sr.n_max) {
        snprintf(line, sizeof line, "no front with n >= %zu: n_max = %ld", o.n_from, t->n_max);
        append_note(t, line);
    }
    if (t->truncated) {
        snprintf(line, sizeof line, "rows for n <= %.0f only of n_max = %ld", sr.n_last,
                 t->n_max);
        append_note(t, line);
    }
    if (sr.unresolved) {
        snprintf(line, sizeof line,
                 "%zu place(s) left unresolved, where a root or a pair of roots could be "
                 "missing (first: %s)", sr.unresolved, sr.unresolved_text);
        append_note(t, line);
    }
    t->unresolved = sr.unresolved;
    rc = BKF_OK;
done:
    t->samples = g->count;
    t->coarse_solves = g->coarse_solves;
    t->precise_solves = g->precise_solves;
    t->formula_answers = g->formula_answers;
    t->mu_grid_max = g->mu_max_sampled;
    free(found);
    free(g->x);
    bkf_cycle_free(g->coarse);
    bkf_cycle_free(g->precise);
    if (fs) gsl_root_fsolver_free(fs);
    return rc;
}

int bkf_speeds_find(const bkf_model_params *p, const bkf_speeds_options *options,
                    bkf_speeds_table *t, bkf_error *err)
{
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    int rc = speeds_find_body(p, options, t, err);
    bkf_gsl_handler_pop(handler);
    return rc;
}

/* ------------------------------------------------------------- branches */

/* Stop following a branch towards the sonic limit here: the remaining
 * piece is monotone in the expansion's regime and ends at p_sonic. */
#define BRANCH_SONIC_MU 1e3
#define BRANCH_STEP_MAX 0.2

typedef struct {
    bkf_model_params p;          /* the start; the continued component varies */
    bkf_speeds_param along;
    double n, tol, from, to;
    bkf_cycle *cycle;
    /* the last evaluation, which the driver makes at every accepted point
     * (for its tangent) just before accepting it */
    double last_u[2], last_T, last_T_err, last_G, last_Gs;
    int have_last;
    double prev_s, prev_Gs;       /* the previous regular point, for G_ss at a fold */
    int have_prev;
    bkf_speeds_visit visit;
    void *data;
    int stop_status;              /* > 0 error, < 0 visit stopped, 0 running */
    bkf_error *err;
    bkf_speeds_branch_report rep;
} branch_ctx;

static double *param_slot(bkf_model_params *q, bkf_speeds_param along)
{
    switch (along) {
    case BKF_SPEEDS_ALONG_S: return &q->S;
    case BKF_SPEEDS_ALONG_NU: return &q->nu;
    case BKF_SPEEDS_ALONG_GAMMA: return &q->gamma;
    default: return &q->c;
    }
}

static const char *param_name(bkf_speeds_param along)
{
    static const char *const names[] = {"S", "nu", "gamma", "c"};
    return names[along];
}

static bkf_model_params params_at(const branch_ctx *b, double p)
{
    bkf_model_params q = b->p;
    *param_slot(&q, b->along) = p;
    return q;
}

static int branch_T(branch_ctx *b, double mu, double nu, double *T, double *T_err, bkf_error *err)
{
    bkf_cycle_options o = bkf_cycle_options_default();
    o.tol = b->tol;
    bkf_error e = {0};
    int rc = bkf_cycle_solve(b->cycle, mu, nu, &o, &e);
    if (rc) return period_refused(rc, &e, nu, err);
    *T = bkf_cycle_get(b->cycle)->period;
    if (T_err) *T_err = bkf_cycle_get(b->cycle)->period_err;
    b->rep.solves++;
    return BKF_OK;
}

/* G(s, p) = ln T(mu(s), nu) - s - ln(S/(n c gamma)), with the Jacobian by
 * forward differences of T in mu (and in nu when continuing in nu). */
static int branch_residual(const double *u, double *g, double *jac, void *data, bkf_error *err)
{
    branch_ctx *b = data;
    bkf_model_params q = params_at(b, u[1]);
    if (!(q.c > 0) || !(q.S > 0) || !(fabs(q.nu) < 1) || !(q.gamma >= BKF_CYCLE_MU_MIN))
        return bkf_error_set(err, BKF_ENUMERIC, "left the valid range at %s = %g",
                             param_name(b->along), u[1]);
    double mu = mu_of_s(q.gamma, u[0]);
    if (!(mu <= BKF_CYCLE_MU_MAX))
        return bkf_error_set(err, BKF_ENUMERIC, "mu = %.15g beyond %g", mu, BKF_CYCLE_MU_MAX);
    double T, T_err;
    int rc = branch_T(b, mu, q.nu, &T, &T_err, err);
    if (rc) return rc == BKF_ENOMEM ? rc : BKF_ENUMERIC;
    double lnT = log(T);
    g[0] = lnT - u[0] - (log(q.S) - log(b->n * q.c * q.gamma));
    b->have_last = 0;
    if (!jac) return BKF_OK;
    /* With h = 1e-6 mu a relative error u of T moves mu dlnT/dmu by 2u/1e-6:
     * beyond mu ~ 100, where G_s -> 0 as g -> k, that reached |G_s| at tol
     * 1e-8 and put a spurious fold pair on the branch near the sonic end.
     * In the relaxation regime (mu >= TAIL_MU_MIN) ln T is nearly linear in
     * ln mu, so a step of 2 sqrt(u) mu costs no more truncation than noise;
     * below, where T turns fast (canards), the short step stays. */
    double h_rel = mu >= TAIL_MU_MIN ? fmax(1e-6, 2.0 * sqrt(T_err / T)) : 1e-6;
    double h = h_rel * mu, T2;
    if ((rc = branch_T(b, mu + h, q.nu, &T2, NULL, err))) return rc == BKF_ENOMEM ? rc : BKF_ENUMERIC;
    double dlnT_dmu = (log(T2) - lnT) / h;
    double Gs = dlnT_dmu * exp(2.0 * u[0]) / mu - 1.0, Gp;
    switch (b->along) {
    case BKF_SPEEDS_ALONG_S: Gp = -1.0 / q.S; break;
    case BKF_SPEEDS_ALONG_C: Gp = 1.0 / q.c; break;
    case BKF_SPEEDS_ALONG_GAMMA: Gp = dlnT_dmu * q.gamma / mu + 1.0 / q.gamma; break;
    default: {
        double hn = q.nu > 0 ? -1e-6 : 1e-6, T3; /* step towards 0, away from |nu| = 1 */
        if ((rc = branch_T(b, mu, q.nu + hn, &T3, NULL, err)))
            return rc == BKF_ENOMEM ? rc : BKF_ENUMERIC;
        Gp = (log(T3) - lnT) / hn;
    }
    }
    jac[0] = Gs;
    jac[1] = Gp;
    b->last_u[0] = u[0];
    b->last_u[1] = u[1];
    b->last_T = T;
    b->last_T_err = T_err;
    b->last_G = g[0];
    b->last_Gs = Gs;
    b->have_last = 1;
    return BKF_OK;
}

/* p where S = n k(nu) c gamma, the branch's sonic end; NaN if none. */
static double sonic_value(const branch_ctx *b, const bkf_model_params *q)
{
    double k = bkf_asym_k(q->nu);
    switch (b->along) {
    case BKF_SPEEDS_ALONG_S: return b->n * k * q->c * q->gamma;
    case BKF_SPEEDS_ALONG_C: return q->S / (b->n * k * q->gamma);
    case BKF_SPEEDS_ALONG_GAMMA: return q->S / (b->n * k * q->c);
    default: {
        /* k is even in nu and increases from k(0) to 3 as |nu| -> 1 */
        double target = q->S / (b->n * q->c * q->gamma), lo = 0.0, hi = 1.0;
        if (!(target > bkf_asym_k(0.0) && target < 3.0)) return NAN;
        for (int it = 0; it < 200; it++) {
            double mid = 0.5 * (lo + hi);
            if (bkf_asym_k(mid) < target) lo = mid;
            else hi = mid;
        }
        return copysign(0.5 * (lo + hi), q->nu);
    }
    }
}

static int branch_visit(branch_ctx *b, const bkf_speeds_branch_point *pt)
{
    if (b->visit(pt, b->data)) {
        b->stop_status = -1;
        return 1;
    }
    return 0;
}

static int branch_accept(const double *u, const double *tangent, int is_fold, void *data)
{
    branch_ctx *b = data;
    bkf_speeds_branch_point pt;
    memset(&pt, 0, sizeof pt);
    double p = u[1];
    /* the ends are requested values: give them back exactly */
    if (fabs(p - b->to) <= 1e-12 * fmax(fabs(b->to), 1e-300)) p = b->to;
    if (fabs(p - b->from) <= 1e-12 * fmax(fabs(b->from), 1e-300)) p = b->from;
    pt.params = params_at(b, p);
    pt.kind = is_fold ? BKF_SPEEDS_FOLD : BKF_SPEEDS_POINT;
    double k = bkf_asym_k(pt.params.nu);
    double mu = mu_of_s(pt.params.gamma, u[0]);
    if (!is_fold && mu > BRANCH_SONIC_MU && tangent[0] > 0) {
        /* heading to mu -> inf: the sonic limit closes the branch */
        double ps = sonic_value(b, &pt.params);
        if (isfinite(ps)) {
            *param_slot(&pt.params, b->along) = ps;
            bkf_speeds_root *r = &pt.root;
            r->n = (size_t)b->n;
            r->v = pt.params.c;
            r->mu = INFINITY;
            r->T = INFINITY;
            r->T_err = NAN;
            r->model = "leading"; /* mu = inf: T = k mu exactly in the limit */
            r->v_over_c = 1.0;
            r->wavelength = pt.params.S / b->n;
            r->period_fixed = k * pt.params.gamma;
            r->v_asym = pt.params.S / (b->n * k * pt.params.gamma);
            r->deviation = (r->v - r->v_asym) / r->v;
            pt.kind = BKF_SPEEDS_SONIC;
            b->rep.sonic = 1;
            b->rep.sonic_value = ps;
            branch_visit(b, &pt);
            b->stop_status = b->stop_status ? b->stop_status : -2;
            return 1;
        }
    }
    found_root f = {b->n, u[0], 0, 0, 0, 0, 0, "shooting"};
    if (b->have_last && b->last_u[0] == u[0] && b->last_u[1] == u[1]) {
        f.T = b->last_T;
        f.T_err = b->last_T_err;
        f.D = b->last_G;
        f.slope = b->last_Gs;
    } else {
        double g[1], jac[2];
        bkf_error e = {0};
        int rc = branch_residual(u, g, jac, b, &e);
        if (rc) {
            b->stop_status = bkf_error_set(b->err, rc, "at %s = %g: %s", param_name(b->along), u[1],
                                           e.message);
            return 1;
        }
        f.T = b->last_T;
        f.T_err = b->last_T_err;
        f.D = b->last_G;
        f.slope = b->last_Gs;
    }
    /* the driver's corrector stops at its own tolerance: one Newton step in
     * s at this exact p brings the residual to tol, away from folds */
    if (!is_fold && fabs(f.D) > b->tol && fabs(f.slope) > 1e-3) {
        double s1 = u[0] - f.D / f.slope, T1, T1_err;
        double mu1 = mu_of_s(pt.params.gamma, s1);
        bkf_error e = {0};
        if (mu1 <= BKF_CYCLE_MU_MAX && branch_T(b, mu1, pt.params.nu, &T1, &T1_err, &e) == BKF_OK) {
            double D1 = log(T1) - s1 - (log(pt.params.S) - log(b->n * pt.params.c * pt.params.gamma));
            if (fabs(D1) < fabs(f.D)) {
                f.s = s1;
                f.T = T1;
                f.T_err = T1_err;
                f.D = D1;
            }
        }
    }
    fill_row(&pt.params, k, &f, &pt.root);
    if (is_fold) {
        /* a double root: an error e of D moves s by sqrt(2 e / |G_ss|), not
         * by e/|G_s|; G_ss from the slope at the previous point */
        f.flags |= BKF_SPEEDS_NEAR_TANGENT;
        pt.root.flags = f.flags;
        double Gss = b->have_prev && f.s != b->prev_s ? (f.slope - b->prev_Gs) / (f.s - b->prev_s)
                                                      : NAN;
        double g2 = pt.params.gamma / pt.root.mu;
        double ds = sqrt(2.0 * (fabs(f.D) + f.T_err / f.T) / fabs(Gss));
        pt.root.v_err = isfinite(ds) ? pt.root.v * g2 * g2 * ds : INFINITY;
        b->rep.folds++;
    } else {
        b->prev_s = f.s;
        b->prev_Gs = f.slope;
        b->have_prev = 1;
        b->rep.points++;
    }
    return branch_visit(b, &pt);
}

static int speeds_branch_body(const bkf_model_params *start, size_t n, size_t root_index,
                              bkf_speeds_param along, double to, const bkf_speeds_options *options,
                              size_t max_points, bkf_speeds_visit visit, void *data,
                              bkf_speeds_branch_report *report, bkf_error *err)
{
    if (report) memset(report, 0, sizeof *report);
    if (!visit) return bkf_error_set(err, BKF_EINPUT, "visit callback is NULL");
    if ((unsigned)along > BKF_SPEEDS_ALONG_C)
        return bkf_error_set(err, BKF_EINPUT, "the continued parameter must be S, nu, gamma or c");
    bkf_speeds_options o = options ? *options : bkf_speeds_options_default();
    int rc = bkf_speeds_check(start, &o, err);
    if (rc) return rc;
    if (n < 1) return bkf_error_set(err, BKF_EINPUT, "n = 0 must be >= 1");
    if (root_index < 1)
        return bkf_error_set(err, BKF_EINPUT, "root_index = 0 must be >= 1 (1: the fastest)");
    if (!(start->c > 0))
        return bkf_error_set(err, BKF_EINPUT,
                             "c = 0: no continuation needed, v = S/(n T(gamma)) in closed form "
                             "(bkfront speeds); branches need c > 0");
    bkf_model_params end = *start;
    double from = *param_slot(&end, along);
    *param_slot(&end, along) = to;
    if (!isfinite(to))
        return bkf_error_set(err, BKF_EINPUT, "%s: the end value must be finite", param_name(along));
    if (to == from)
        return bkf_error_set(err, BKF_EINPUT, "%s: the end value %g equals the start",
                             param_name(along), to);
    if (along == BKF_SPEEDS_ALONG_C && !(to > 0))
        return bkf_error_set(err, BKF_EINPUT,
                             "c = %.15g: the branch must stay in c > 0 (c = 0 is the closed form "
                             "v = S/(n T(gamma)))", to);
    if ((rc = bkf_speeds_check(&end, NULL, err))) return rc;

    /* the start: every root of this n, then the chosen one */
    bkf_speeds_options fo = o;
    fo.n_from = fo.n_to = n;
    bkf_speeds_table t;
    rc = bkf_speeds_find(start, &fo, &t, err);
    if (rc) {
        bkf_speeds_table_free(&t);
        return rc;
    }
    if (t.count < root_index) {
        long n_max = t.n_max;
        size_t count = t.count;
        bkf_speeds_table_free(&t);
        if (count == 0)
            return bkf_error_set(err, BKF_EINPUT,
                                 "no front with n = %zu at %s = %g (n_max = %ld there): start "
                                 "the branch where one exists",
                                 n, param_name(along), from, n_max);
        return bkf_error_set(err, BKF_EINPUT, "root %zu for n = %zu does not exist at %s = %g "
                                              "(%zu root(s))",
                             root_index, n, param_name(along), from, count);
    }
    double mu0 = t.roots[root_index - 1].mu;
    bkf_speeds_table_free(&t);

    branch_ctx b;
    memset(&b, 0, sizeof b);
    b.p = *start;
    b.along = along;
    b.n = (double)n;
    b.tol = o.tol;
    b.from = from;
    b.to = to;
    b.visit = visit;
    b.data = data;
    b.err = err;
    b.cycle = bkf_cycle_alloc();
    if (!b.cycle) return bkf_error_set(err, BKF_ENOMEM, "out of memory");

    double u0[2] = {0.5 * log((mu0 - start->gamma) * (mu0 + start->gamma)), from};
    /* scale p so that G changes by ~1 per unit: steps weigh s and p alike */
    double g0[1], jac0[2];
    bkf_error e = {0};
    rc = branch_residual(u0, g0, jac0, &b, &e);
    if (rc) {
        bkf_cycle_free(b.cycle);
        return bkf_error_set(err, rc == BKF_ENOMEM ? rc : BKF_ENUMERIC, "at the start: %s",
                             e.message);
    }
    double scale[2] = {1.0, 1.0 / fmax(fabs(jac0[1]), 1e-12)};
    scale[1] = fmin(scale[1], fabs(to - from));
    bkf_cont_options co = bkf_cont_options_default(1);
    co.scale = scale;
    co.step_max = BRANCH_STEP_MAX;
    co.step_initial = 0.25 * BRANCH_STEP_MAX;
    co.step_min = 1e-9;
    co.newton_tol = fmax(10.0 * o.tol, 1e-10);
    co.stop_index = 1;
    co.stop_min = fmin(from, to);
    co.stop_max = fmax(from, to);
    if (max_points) co.max_points = max_points;
    bkf_cont_report cr;
    bkf_error ce = {0};
    rc = bkf_cont_run(branch_residual, branch_accept, &b, u0, 1, to > from ? 1 : -1, &co, &cr, &ce);
    bkf_cycle_free(b.cycle);
    b.rep.reached_end = cr.reached_bound;
    if (report) *report = b.rep;
    if (b.stop_status > 0) return b.stop_status;
    if (b.stop_status < 0) return BKF_OK;
    if (rc) return bkf_error_set(err, rc, "continuation in %s: %s", param_name(along), ce.message);
    return BKF_OK;
}

int bkf_speeds_branch(const bkf_model_params *start, size_t n, size_t root_index,
                      bkf_speeds_param along, double to, const bkf_speeds_options *options,
                      size_t max_points, bkf_speeds_visit visit, void *data,
                      bkf_speeds_branch_report *report, bkf_error *err)
{
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    int rc = speeds_branch_body(start, n, root_index, along, to, options, max_points, visit, data, report, err);
    bkf_gsl_handler_pop(handler);
    return rc;
}

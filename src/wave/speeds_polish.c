/* The speeds' polishing (speeds.c): a bracketed root to the requested
 * tolerance, predicted by interpolation on the grid, solved by Brent on
 * D_n, or answered by an asymptotic formula.  Above the search
 * (speeds_search.c), below the rows (speeds.c). */
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
    int rc = speeds_solve_T(pc->g, mu_of_s(pc->g->p.gamma, s), pc->tol, &T, &T_err, pc->err);
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
    *out = (found_root){.n = n, .s = s, .T = T, .T_err = bound * T, .D = log(T) - s - ell,
                        .slope = slope, .model = f == BKF_ASYM_LEADING ? "leading" : "asymptotic"};
    return 1;
}

/* The slope for the error estimate: the flattest of the interpolated slope
 * at the root (slope0), the secant from the best point to the farthest one
 * and the secants from the best point that stand above the noise of T (ten
 * times the two solves' estimates).  D curves across a cell where T nears
 * k mu: at mu 1409 (gamma 1, c 1, nu -0.5) d ln T/ds - 1 is -3.9e-4 at the
 * root, the far secant alone -0.026, and v_err came out 6 times too small. */
static double estimate_slope(const polish_ctx *pc, const peval *best, double slope0)
{
    const peval *far = NULL;
    for (size_t j = 0; j < pc->nev; j++)
        if (!far || fabs(pc->ev[j].s - best->s) > fabs(far->s - best->s)) far = &pc->ev[j];
    double slope = far->s != best->s ? (far->D - best->D) / (far->s - best->s) : slope0;
    if (!(slope < 0 || slope > 0) || (slope > 0) != (slope0 > 0)) slope = slope0;
    for (size_t j = 0; j < pc->nev; j++) {
        const peval *e = &pc->ev[j];
        double noise = 10.0 * (e->T_err / e->T + best->T_err / best->T);
        if (e->s == best->s || !(fabs(e->D - best->D) > noise)) continue;
        double sl = (e->D - best->D) / (e->s - best->s);
        if ((sl > 0) == (slope0 > 0) && fabs(sl) < fabs(slope)) slope = sl;
    }
    if (isfinite(slope0) && fabs(slope0) < fabs(slope)) slope = slope0;
    return slope;
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

int speeds_polish(grid *g, gsl_root_fsolver *fs, double n, size_t i, found_root *out,
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
        if (speeds_solve_T_on(g, 1, mu0, scout_tol, &Tc, &Tc_err, &e) == BKF_OK) {
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
    const peval *best = best_eval(&pc);
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
    double slope = estimate_slope(&pc, best, slope0);
    *out = (found_root){.n = n, .s = best->s, .T = best->T, .T_err = best->T_err, .D = best->D,
                        .slope = slope, .model = best->model};
    return BKF_OK;
}

/* The root of a level beyond the grid's cap, on the large-mu expansion,
 * whose next (O(1/mu)) term is estimated from the last sample (solved at
 * the requested tolerance by then). */
void speeds_asymptotic_root(const grid *g, double n, found_root *out)
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
    *out = (found_root){.n = n, .s = s, .T = T, .T_err = rem + last->T_err * last->mu / mu,
                        .D = log(T) - s - ell, .slope = slope, .flags = BKF_SPEEDS_ASYMPTOTIC,
                        .model = "asymptotic"};
}


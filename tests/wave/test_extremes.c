/* Issue 7, items 3 and 4: the extremes of every product.  Over mu in
 * [1e-3, 1e4], |nu| up to 0.9999, v -> c+ (n near n_max), c -> 0, S in
 * [1e-2, 1e4], gamma in [1e-2, 1e2], every point of the period T(mu, nu)
 * (bkf_cycle_period), the speeds table (bkf_speeds_find) and the Floquet
 * lambda (bkf_floquet_eval) either meets its tolerance against an
 * independent value or returns BKF_ENUMERIC with a message; and where it
 * returned OK, its error estimate is never optimistic by more than 10.
 *
 * Independent values:
 *  - T: the published T(1, 0); the other GSL stepper of the library at tol
 *    1e-12 (mu <= 300); above, an integration written here in the plain
 *    Lienard plane with GSL's rk4imp (implicit Gauss, a different method,
 *    coordinates and event location), its uncertainty the change between
 *    two tolerances; at mu = 1e4, nu = 0 Dorodnitsyn's series; and the
 *    large-mu formula wherever its verified bound is below tol.
 *  - v: the residual n T v sqrt(1 - c^2/v^2)/S - 1 recomputed at the
 *    reported v with such an independent T, converted to an error of v by
 *    the slope of the residual in v (a secant, also with independent T);
 *    c = 0: the closed form v = S/(n T(gamma)).
 *  - lambda: c q = 0 has the multiplier 1 exactly (lambda = 0); the other
 *    stepper at tol 1e-10; where that cannot decide or lambda < -5, a power
 *    iteration written here (rk4imp, the plain linear system renormalised
 *    every step) for real multipliers, L/2 of an independent cycle solve
 *    for a complex pair; Liouville ln|m1 m2| against that L, within tol
 *    max(1, |L|).  Points nothing independent can check are counted.
 * One line per point is printed: status, true error, estimated error and
 * their ratio; the summary gives the worst ratio per product. */
#include "harness.h"

#include <gsl/gsl_errno.h>
#include <gsl/gsl_odeiv2.h>
#include <string.h>
#include <time.h>

#include "bkfront/asymptotics.h"
#include "bkfront/cycle.h"
#include "bkfront/floquet.h"
#include "bkfront/speeds.h"
#include "taylor_reference.h"

/* ------------------------------------------------- summary per product */

typedef struct {
    const char *name;
    size_t points, ok, refused;
    double worst_ratio;     /* true/estimated where OK */
    double worst_over_tol;  /* true error / (tol scale) where OK */
    char worst_at[256];
} tally;

static void tally_ok(tally *t, double ratio, double over_tol, const char *where)
{
    t->points++;
    t->ok++;
    if (ratio > t->worst_ratio) {
        t->worst_ratio = ratio;
        snprintf(t->worst_at, sizeof t->worst_at, "%s", where);
    }
    if (over_tol > t->worst_over_tol) t->worst_over_tol = over_tol;
}

static void tally_refused(tally *t, int status, const char *message, const char *where)
{
    t->points++;
    t->refused++;
    CHECK_MSG(bkf_status_is_numerical(status), "%s: status %s (%s), want a numerical one", where,
              bkf_status_name(status), message);
    CHECK_MSG(strlen(message) > 10, "%s: refused without a message", where);
    bkf_test_note("%s REFUSED: %s", where, message);
}

static void tally_report(const tally *t)
{
    bkf_test_note("%s: %zu points, %zu OK, %zu refused; worst true/estimated %.3g (%s); "
                  "worst true/tol %.3g",
                  t->name, t->points, t->ok, t->refused, t->worst_ratio, t->worst_at,
                  t->worst_over_tol);
}

/* ------------------------------- T by a method independent of the library */

typedef struct {
    double mu, nu;
} lienard;

static int lienard_rhs(double t, const double s[], double f[], void *params)
{
    (void)t;
    const lienard *q = params;
    double x = s[0];
    f[0] = q->mu * (s[1] - (x * x * x / 3.0 - x));
    f[1] = (q->nu - x) / q->mu;
    return GSL_SUCCESS;
}

static int lienard_jac(double t, const double s[], double *J, double *dt, void *params)
{
    (void)t;
    const lienard *q = params;
    double x = s[0];
    J[0] = -q->mu * (x * x - 1.0);
    J[1] = q->mu;
    J[2] = -1.0 / q->mu;
    J[3] = 0.0;
    dt[0] = dt[1] = 0.0;
    return GSL_SUCCESS;
}

/* Plain Lienard plane x' = mu (y - F), y' = (nu - x)/mu, GSL rk4imp at
 * tol: from the relaxation cycle's corner (2, 2/3) the transient dies
 * within a turn at large mu (multiplier ~ exp(-mu)); T is the time between
 * the 1st and 2nd upward crossings of x = nu (the first is a period in,
 * after both jumps: on the cycle to rounding), each located by safeguarded
 * secant steps, re-integrating from the step before.  The 3rd and 4th, as
 * before, cost twice as much for the same T: at the seven points above mu
 * 300 the two agree within the spread over the tolerances (at mu 1e4, nu
 * 0.9999 4e-11 against a spread of 7.5e-11), and that spread is no wider
 * (4.8e-12 .. 7.5e-11 against 7.5e-12 .. 7.8e-11). */
static double period_rk4imp(double mu, double nu, double tol)
{
    gsl_set_error_handler_off();
    lienard q = {mu, nu};
    gsl_odeiv2_system sys = {lienard_rhs, lienard_jac, 2, &q};
    gsl_odeiv2_driver *d = gsl_odeiv2_driver_alloc_y_new(&sys, gsl_odeiv2_step_rk4imp, 1e-3 / mu, tol, 0.0);
    CHECK(d);
    double s[2] = {2.0, 2.0 / 3.0}, t = 0, h = 1e-3 / mu, tc[2];
    int nc = 0;
    for (long steps = 0; nc < 2; steps++) {
        CHECK_MSG(steps < 5000000, "rk4imp reference at mu %g nu %g: no crossing", mu, nu);
        double sp[2] = {s[0], s[1]}, tp = t;
        CHECK(gsl_odeiv2_evolve_apply(d->e, d->c, d->s, &sys, &t, 1e300, &h, s) == GSL_SUCCESS);
        if (!(sp[0] < nu && s[0] >= nu)) continue;
        double lo = tp, hi = t, glo = sp[0] - nu, ghi = s[0] - nu;
        for (int it = 0; it < 200 && hi - lo > 4e-16 * hi; it++) {
            double tm = lo - glo * (hi - lo) / (ghi - glo);
            if (!(tm > lo && tm < hi) || it % 3 == 2) tm = 0.5 * (lo + hi);
            double sm[2] = {sp[0], sp[1]}, tt = tp;
            gsl_odeiv2_driver_reset(d);
            CHECK(gsl_odeiv2_driver_apply(d, &tt, tm, sm) == GSL_SUCCESS);
            double g = sm[0] - nu;
            if (g == 0) { lo = hi = tm; break; }
            if (g < 0) { lo = tm; glo = g; } else { hi = tm; ghi = g; }
        }
        tc[nc++] = 0.5 * (lo + hi);
    }
    gsl_odeiv2_driver_free(d);
    return tc[1] - tc[0];
}

/* An independent T(mu, nu) and its absolute uncertainty, by a method other
 * than `avoid` (the stepper the product under test used). */
static double reference_T_solve(double mu, double nu, const char *avoid, double *unc);

/* The references already computed: the answer depends on (mu, nu) and on
 * the route alone (below mu 300: whether `avoid` is rk8pd; above: rk4imp
 * whatever `avoid` is), and the period matrix asks one point again at each
 * tol where the product's stepper changes (auto's bd2x2 at 1e-3, colloc at
 * 1e-11): the rk4imp reference at mu 1e3, 1e4 is most of the matrix's cost. */
typedef struct {
    double mu, nu, T, unc;
    int route;
} ref_entry;
static ref_entry ref_cache[128];
static size_t ref_cached;
static double ref_seconds;

static double reference_T(double mu, double nu, const char *avoid, double *unc)
{
    int route = mu <= 300 ? strcmp(avoid, "rk8pd") == 0 : 2;
    for (size_t i = 0; i < ref_cached; i++)
        if (ref_cache[i].mu == mu && ref_cache[i].nu == nu && ref_cache[i].route == route) {
            *unc = ref_cache[i].unc;
            return ref_cache[i].T;
        }
    clock_t c0 = clock();
    double T = reference_T_solve(mu, nu, avoid, unc);
    double secs = (double)(clock() - c0) / CLOCKS_PER_SEC;
    ref_seconds += secs;
    bkf_test_note("reference T mu %g nu %g route %d: %.2f s", mu, nu, route, secs);
    if (ref_cached < sizeof ref_cache / sizeof ref_cache[0])
        ref_cache[ref_cached++] = (ref_entry){mu, nu, T, *unc, route};
    return T;
}

static double reference_T_solve(double mu, double nu, const char *avoid, double *unc)
{
    if (mu == 1.0 && nu == 0.0) {
        *unc = 1e-14;
        return 6.663286859323130;
    }
    if (mu == 1e4 && nu == 0.0) {
        /* Dorodnitsyn: k mu + 3 a1 mu^(-1/3) - (2/3) ln(mu)/mu - 1.3246/mu,
         * next term O(mu^(-4/3) ln mu); 0.05/mu covers it with room */
        *unc = 0.05 / mu;
        return bkf_asym_period_large(mu, 0.0) - 1.3246 / mu;
    }
    if (mu <= 300) {
        bkf_cycle_options o = bkf_cycle_options_default();
        o.warm_start = 0;
        o.stepper = strcmp(avoid, "rk8pd") == 0 ? BKF_STEPPER_IMPLICIT : BKF_STEPPER_EXPLICIT;
        bkf_cycle_result r;
        bkf_error e;
        const double tols[] = {1e-12, 1e-11, 1e-10};
        for (int i = 0; i < 3; i++) {
            o.tol = tols[i];
            if (bkf_cycle_period(mu, nu, &o, &r, &e) == BKF_OK) {
                *unc = fmax(r.period_err, 1e-14 * r.period);
                return r.period;
            }
        }
        /* rk8pd runs out of steps at mu = 300 near |nu| = 1: fall through */
    }
    /* rk4imp's results scatter by ~4e-12 relative from one tolerance to the
     * next at mu = 1e3 (rounding over ~1e5 steps): the uncertainty is three
     * times the spread over the tolerances.  At mu = 1e4 that scatter is
     * ~2e-11 (5e-7 of T = 3e4 at nu 0.9999) from tol 1e-8 down: the pair
     * 1e-8, 1e-9 is as good as 1e-9, 1e-10 (spread 1.05e-10 against 4.8e-11
     * relative, both above the tol 1e-11 they check) at a third of the
     * cost (3.9 -> 1.3 s). */
    const double tols[] = {1e-10, 1e-11, 1e-12};
    size_t n = mu > 3e3 ? 2 : 3;
    double lo = INFINITY, hi = -INFINITY, last = NAN;
    for (size_t i = 0; i < n; i++) {
        last = period_rk4imp(mu, nu, tols[i] * (mu > 3e3 ? 100.0 : 1.0));
        lo = fmin(lo, last);
        hi = fmax(hi, last);
    }
    *unc = 3.0 * (hi - lo) + 1e-14 * last;
    return last;
}

static void fmt_where(char *buf, size_t n, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
#include <stdarg.h>
static void fmt_where(char *buf, size_t n, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, n, fmt, ap);
    va_end(ap);
}

/* ------------------------------------------------------------- period */

TEST(extremes_period_matrix)
{
    const double mus[] = {1e-3, 1e-2, 0.3, 1, 3, 30, 100, 1e3, 1e4};
    const double nus[] = {0, -0.9, 0.99, -0.999, 0.9999};
    const double tols[] = {1e-3, 1e-7, 1e-11};
    tally t = {"period", 0, 0, 0, 0, 0, ""};
    for (size_t i = 0; i < sizeof mus / sizeof mus[0]; i++)
        for (size_t j = 0; j < sizeof nus / sizeof nus[0]; j++) {
            double mu = mus[i], nu = nus[j];
            /* mu = 1e4: the rk4imp reference costs seconds; two nu suffice */
            if (mu == 1e4 && nu != 0.0 && nu != 0.9999) continue;
            if (mu == 1.0 && nu != 0.0) continue;
            /* auto, and where auto is explicit also the implicit stepper
             * (which stepped over half a small cycle near the Hopf point) */
            for (int forced = 0; forced <= (mu <= 30); forced++) {
                double ref = NAN, unc = NAN;
                const char *ref_for = NULL;
                for (size_t k = 0; k < sizeof tols / sizeof tols[0]; k++) {
                    bkf_cycle_options o = bkf_cycle_options_default();
                    o.tol = tols[k];
                    o.warm_start = 0;
                    if (forced) o.stepper = BKF_STEPPER_IMPLICIT;
                    bkf_cycle_result r;
                    bkf_error e = {0};
                    char where[160];
                    fmt_where(where, sizeof where, "T mu %g nu %g tol %g %s", mu, nu, tols[k],
                              forced ? "bsimp" : "auto");
                    int rc = bkf_cycle_period(mu, nu, &o, &r, &e);
                    if (rc != BKF_OK) {
                        tally_refused(&t, rc, e.message, where);
                        continue;
                    }
                    if (!ref_for || strcmp(ref_for, r.stepper) != 0) {
                        ref = reference_T(mu, nu, r.stepper, &unc);
                        ref_for = r.stepper;
                    }
                    /* the large-mu formula, where its bound is the tighter */
                    double bound = bkf_asym_error_bound(BKF_ASYM_LARGE, mu, nu) * r.period;
                    if (bound < unc) {
                        ref = bkf_asym_period(BKF_ASYM_LARGE, mu, nu);
                        unc = bound;
                    }
                    double err = fabs(r.period - ref);
                    double ratio = fmax(err - unc, 0.0) / r.period_err;
                    bkf_test_note("%s: OK, true %.2g est %.2g ratio %.2g (ref +- %.1g)", where,
                                  err / r.period, r.period_err / r.period, ratio, unc / r.period);
                    CHECK_MSG(err <= tols[k] * r.period + unc,
                              "%s: T = %.17g, independent %.17g +- %.2g: error %.3g > tol", where,
                              r.period, ref, unc, err / r.period);
                    CHECK_MSG(ratio <= 10.0, "%s: estimate optimistic by %.3g", where, ratio);
                    tally_ok(&t, ratio, fmax(err - unc, 0.0) / (tols[k] * r.period), where);
                }
            }
        }
    tally_report(&t);
    bkf_test_note("references: %zu solved, %.2f s", ref_cached, ref_seconds);
    CHECK(t.ok >= t.points * 3 / 4);
    /* Today one refusal, mu 1e4 nu 0.9999 at tol 1e-11 (its estimate 1.8e-11
     * just above tol); two more leave room for the other mu 1e4 point and
     * mu 1e3 at that tol, the same edge. */
    CHECK_MSG(t.refused <= 3, "%zu refusals", t.refused);
}

/* Issue 17, item 1: the estimate of T may not flatter, against a reference
 * that shares nothing with the engine (taylor_reference.h: long-double
 * Taylor series in the phase plane, its own uncertainty measured).  Dense
 * in mu across both switches of the engine (rk8pd's fast path changes its
 * tolerance pair at mu = 10, the implicit stepper takes over above 30),
 * and down to tol 1e-14 near |nu| = 1, where rounding amplified by the
 * weak attraction sets a floor: there a refusal is the right answer.
 * Before the fix: mu 51.75, nu 0.5, tol 1e-6 optimistic by 51; mu 31, nu 0
 * by 8.4 at every tol; mu 10, nu -0.999, tol 1e-13 answered 2.8 tol off;
 * mu 10, nu 0.9999, tol 1e-14 20 tol off (63 times its estimate).  Every
 * accepted answer must be within tol and its estimate optimistic by at most
 * 3; T(mu, nu) = T(mu, -nu) must hold within the two estimates. */
typedef struct {
    double mu, nu, tol;
} honest_case;

static void honest_check(tally *t, honest_case k, double *ref, double *unc, double *T_out,
                         double *err_out)
{
    bkf_cycle_options o = bkf_cycle_options_default();
    o.tol = k.tol;
    o.warm_start = 0;
    bkf_cycle_result r;
    bkf_error e = {0};
    char where[160];
    fmt_where(where, sizeof where, "T mu %g nu %g tol %g", k.mu, k.nu, k.tol);
    *T_out = *err_out = NAN;
    int rc = bkf_cycle_period(k.mu, k.nu, &o, &r, &e);
    if (rc != BKF_OK) {
        tally_refused(t, rc, e.message, where);
        return;
    }
    if (!isfinite(*ref)) *ref = taylor_period(k.mu, k.nu, r.section_slope, unc);
    double err = fabs(r.period - *ref), ratio = fmax(err - *unc, 0.0) / r.period_err;
    bkf_test_note("%s %s: true %.2g est %.2g ratio %.2g (ref +- %.1g)", where, r.stepper,
                  err / r.period, r.period_err / r.period, ratio, *unc / r.period);
    CHECK_MSG(*unc <= 1e-3 * k.tol * r.period, "%s: reference uncertain by %.2g", where, *unc / r.period);
    CHECK_MSG(err <= k.tol * r.period + *unc, "%s: T = %.17g, reference %.17g: error %.3g > tol", where,
              r.period, *ref, err / r.period);
    CHECK_MSG(ratio <= 3.0, "%s: estimate %.3g optimistic by %.3g", where, r.period_err / r.period,
              ratio);
    tally_ok(t, ratio, fmax(err - *unc, 0.0) / (k.tol * r.period), where);
    *T_out = r.period;
    *err_out = r.period_err;
}

TEST(extremes_period_estimates_never_flatter)
{
    tally t = {"period (Taylor reference)", 0, 0, 0, 0, 0, ""};
    /* across the switches: mu 9..11 and 27..33 by 0.5, and the reported point */
    double mus[32];
    size_t nm = 0;
    for (double mu = 9.0; mu <= 11.0; mu += 0.5) mus[nm++] = mu;
    for (double mu = 27.0; mu <= 33.0; mu += 0.5) mus[nm++] = mu;
    mus[nm++] = 51.75;
    const double nus[] = {0.0, 0.5, -0.9};
    const double tols[] = {1e-2, 1e-6, 1e-10};
    for (size_t i = 0; i < nm; i++)
        for (size_t j = 0; j < sizeof nus / sizeof nus[0]; j++) {
            double ref = NAN, unc = 0, T, est;
            for (size_t k = 0; k < sizeof tols / sizeof tols[0]; k++)
                honest_check(&t, (honest_case){mus[i], nus[j], tols[k]}, &ref, &unc, &T, &est);
        }
    /* near the Hopf point and in the canard region, to tol 1e-14, both signs
     * of nu (the reference is the same for both: T is even in nu) */
    const double mus_h[] = {2, 6, 10, 20, 28, 40};
    const double nus_h[] = {0.999, 0.9999};
    const double tols_h[] = {1e-10, 1e-12, 1e-13, 1e-14};
    for (size_t i = 0; i < sizeof mus_h / sizeof mus_h[0]; i++)
        for (size_t j = 0; j < sizeof nus_h / sizeof nus_h[0]; j++) {
            double ref = NAN, unc = 0;
            for (size_t k = 0; k < sizeof tols_h / sizeof tols_h[0]; k++) {
                double Tp, ep, Tm, em;
                honest_check(&t, (honest_case){mus_h[i], nus_h[j], tols_h[k]}, &ref, &unc, &Tp, &ep);
                honest_check(&t, (honest_case){mus_h[i], -nus_h[j], tols_h[k]}, &ref, &unc, &Tm, &em);
                if (isfinite(Tp) && isfinite(Tm))
                    CHECK_MSG(fabs(Tp - Tm) <= ep + em,
                              "mu %g nu +-%g tol %g: T(nu) - T(-nu) = %.3g beyond the estimates %.2g + %.2g",
                              mus_h[i], nus_h[j], tols_h[k], Tp - Tm, ep, em);
            }
        }
    tally_report(&t);
    /* near |nu| = 1 tol <= 1e-12 is mostly refused (the rounding floor):
     * today 208 of 267 answered, 59 refused */
    CHECK_MSG(t.ok >= t.points / 2, "%zu of %zu answered", t.ok, t.points);
}

/* ------------------------------------------------------------- speeds */

/* n T(mu(v)) v sqrt(1 - c^2/v^2) / S - 1 with a given T(mu) */
static double speed_residual(const bkf_model_params *p, double n, double v, double T)
{
    double w = p->c > 0 ? sqrt(1.0 - (p->c / v) * (p->c / v)) : 1.0;
    return n * T * v * w / p->S - 1.0;
}

static double mu_of_v(const bkf_model_params *p, double v)
{
    return p->c > 0 ? p->gamma / sqrt(1.0 - (p->c / v) * (p->c / v)) : p->gamma;
}

/* T for the slope only (a conversion factor: 1e-3 would do) */
static double T_plain(double mu, double nu)
{
    if (mu > 1e5) return bkf_asym_period(BKF_ASYM_LARGE, mu, nu);
    bkf_cycle_options o = bkf_cycle_options_default();
    o.tol = 1e-8;
    o.warm_start = 0;
    bkf_cycle_result r;
    bkf_error e;
    if (bkf_cycle_period(mu, nu, &o, &r, &e) != BKF_OK) {
        o.tol = 1e-6; /* inside a canard explosion */
        CHECK_MSG(bkf_cycle_period(mu, nu, &o, &r, &e) == BKF_OK, "slope T at mu %g: %s", mu,
                  e.message);
    }
    return r.period;
}

/* rows of the speeds matrix whose T came from a formula (method auto) */
static size_t speeds_formula_rows;

static void check_speeds_case(tally *t, bkf_model_params p, double tol, size_t n_from, size_t n_to)
{
    bkf_speeds_options o = bkf_speeds_options_default();
    o.tol = tol;
    o.n_from = n_from;
    o.n_to = n_to;
    bkf_speeds_table tab;
    bkf_error e = {0};
    char where[160];
    fmt_where(where, sizeof where, "speeds gamma %g c %g nu %g S %g tol %g n %zu..%zu", p.gamma, p.c,
              p.nu, p.S, tol, n_from, n_to);
    int rc = bkf_speeds_find(&p, &o, &tab, &e);
    if (rc != BKF_OK) {
        tally_refused(t, rc, e.message, where);
        bkf_speeds_table_free(&tab);
        return;
    }
    if (tab.unresolved)
        bkf_test_note("%s: %zu place(s) reported unresolved: %s", where, tab.unresolved, tab.note);
    if (tab.count == 0) bkf_test_note("%s: no row (%s)", where, tab.note);
    for (size_t i = 0; i < tab.count; i++) {
        const bkf_speeds_root *r = &tab.roots[i];
        double n = (double)r->n, v = r->v, mu = mu_of_v(&p, v);
        const char *used = mu > 30 ? "bsimp" : "rk8pd";
        double v_ref, v_unc;
        char at[240];
        fmt_where(at, sizeof at, "%s: n %zu v %.6g mu %.4g", where, r->n, v, mu);
        if (p.c > 0 && v - p.c <= 0.1 * tol * v) {
            /* at the sonic limit v - c is below what tol can see.  The
             * large-mu formula within its bound puts g = T/sqrt(mu^2 -
             * gamma^2) above the level at mu = 1e3, so the true root has
             * mu > 1e3 (g decreases there) and v_true - c < c gamma^2/
             * (2 1e6) (1.01); v is checked against that interval */
            double M = 1e3, R = p.S / (n * p.c * p.gamma);
            double gM = bkf_asym_period(BKF_ASYM_LARGE, M, p.nu) *
                        (1.0 - bkf_asym_error_bound(BKF_ASYM_LARGE, M, p.nu)) /
                        sqrt(M * M - p.gamma * p.gamma);
            CHECK_MSG(gM > R && v > p.c, "%s: not at the sonic limit", at);
            double gap = 1.01 * p.c * p.gamma * p.gamma / (2.0 * M * M);
            v_ref = p.c + 0.5 * gap;
            v_unc = 0.5 * gap;
        } else if (p.c == 0) {
            /* closed form v = S/(n T(gamma)) */
            double unc, T = reference_T(p.gamma, p.nu, used, &unc);
            v_ref = p.S / (n * T);
            v_unc = v_ref * unc / T;
        } else {
            /* one Newton step on the residual with an independent T, the
             * slope by a secant in v */
            double dv = 1e-6 * (v - p.c);
            double slope = (speed_residual(&p, n, v + dv, T_plain(mu_of_v(&p, v + dv), p.nu)) -
                            speed_residual(&p, n, v, T_plain(mu, p.nu))) / dv;
            double unc, T;
            double bound = bkf_asym_error_bound(BKF_ASYM_LARGE, mu, p.nu);
            if (mu > 3e3 || (mu > 300 && bound / fabs(slope * v) <= 0.1 * tol)) {
                /* near the sonic limit v hardly depends on T: the large-mu
                 * formula within its bound is accurate enough */
                T = bkf_asym_period(BKF_ASYM_LARGE, mu, p.nu);
                unc = bound * T;
            } else {
                T = reference_T(mu, p.nu, used, &unc);
            }
            double D = speed_residual(&p, n, v, T);
            v_ref = v - D / slope;
            v_unc = (unc / T) * (1.0 + D) / fabs(slope) + 1e-15 * v;
        }
        double err = fabs(v - v_ref);
        double ratio = fmax(err - v_unc, 0.0) / r->v_err;
        bkf_test_note("%s: OK, true %.2g est %.2g ratio %.2g (ref +- %.1g), T by %s%s", at, err / v,
                      r->v_err / v, ratio, v_unc / v, r->model, r->flags ? " flagged" : "");
        /* the default method is auto: a formula's root is checked against
         * the same independent value as a shot one */
        if (strcmp(r->model, "shooting") != 0) speeds_formula_rows++;
        CHECK_MSG(err <= tol * v + v_unc, "%s: v = %.17g, independent %.17g +- %.2g: error %.3g > tol",
                  at, v, v_ref, v_unc, err / v);
        CHECK_MSG(ratio <= 10.0, "%s: v_err optimistic by %.3g", at, ratio);
        tally_ok(t, ratio, fmax(err - v_unc, 0.0) / (tol * v), at);
    }
    bkf_speeds_table_free(&tab);
}

static size_t n_below_bound(bkf_model_params p)
{
    return (size_t)ceil(p.S / (bkf_asym_k(p.nu) * p.c * p.gamma)) - 1;
}

TEST(extremes_speeds_matrix)
{
    tally t = {"speeds", 0, 0, 0, 0, 0, ""};
    /* the paper, every n to n_max = 12 (mu 2 .. 47) */
    check_speeds_case(&t, (bkf_model_params){2, 0.3, -0.96, 20, 0, BKF_MODEL_CONTINUUM}, 1e-8, 1, 0);
    check_speeds_case(&t, (bkf_model_params){2, 0.3, -0.96, 20, 0, BKF_MODEL_CONTINUUM}, 1e-4, 10, 12);
    /* small gamma, small S: mu from 1e-2 up */
    check_speeds_case(&t, (bkf_model_params){1e-2, 0.3, 0, 1e-2, 0, BKF_MODEL_CONTINUUM}, 1e-8, 1, 0);
    /* large gamma, large S: the fastest and the two slowest (v -> c+) */
    bkf_model_params big = {1e2, 0.3, 0, 1e4, 0, BKF_MODEL_CONTINUUM};
    size_t nb = n_below_bound(big);
    check_speeds_case(&t, big, 1e-8, 1, 1);
    check_speeds_case(&t, big, 1e-8, nb - 1, nb);
    /* c -> 0 with large gamma */
    check_speeds_case(&t, (bkf_model_params){1e2, 1e-3, -0.9, 1, 0, BKF_MODEL_CONTINUUM}, 1e-8, 1, 0);
    /* c -> 0 against the closed form, and c = 0 itself at the box's corners */
    check_speeds_case(&t, (bkf_model_params){1, 1e-6, 0, 10, 0, BKF_MODEL_CONTINUUM}, 1e-8, 1, 3);
    check_speeds_case(&t, (bkf_model_params){1e-2, 0, 0.999, 1e4, 0, BKF_MODEL_CONTINUUM}, 1e-10, 1, 3);
    check_speeds_case(&t, (bkf_model_params){1e2, 0, -0.9999, 1e-2, 0, BKF_MODEL_CONTINUUM}, 1e-6, 1, 2);
    /* huge n_bound (5e5 fronts): the first two and the last two */
    bkf_model_params many = {1e-2, 1, 0.5, 1e4, 0, BKF_MODEL_CONTINUUM};
    nb = n_below_bound(many);
    check_speeds_case(&t, many, 1e-8, 1, 2);
    /* (its last rows sit at v/c - 1 ~ 4e-14, where v itself has 2 digits
     * left: not a useful test of anything) */
    (void)nb;
    /* the sonic limit: S just above k c gamma, root beyond mu = 1e5 */
    check_speeds_case(&t, (bkf_model_params){1, 0.5, 0, (1 + 1e-6) * bkf_asym_k(0) * 0.5, 0, BKF_MODEL_CONTINUUM}, 1e-8, 1, 1);
    /* near the Hopf point (canard region) */
    check_speeds_case(&t, (bkf_model_params){1, 0.3, 0.9999, 20, 0, BKF_MODEL_CONTINUUM}, 1e-6, 1, 3);
    /* loose tol at large mu: the roots from k mu (method auto) */
    check_speeds_case(&t, (bkf_model_params){300, 0.3, 0, 2000, 0, BKF_MODEL_CONTINUUM}, 1e-2, 1, 3);
    tally_report(&t);
    bkf_test_note("speeds: %zu rows with T from a formula (default method auto)", speeds_formula_rows);
    CHECK(speeds_formula_rows >= 3);
    /* Today no case refuses.  Two may: the sonic limit (root beyond mu =
     * 1e5) and the canard near the Hopf point are where a refusal is an
     * honest answer; any other refusal loses a case's rows. */
    CHECK_MSG(t.refused <= 2, "%zu refused cases", t.refused);
}

/* ------------------------------------------------------------- Floquet */

/* The stepper the library does not use by default at gamma (as floquet.c:
 * rk8pd up to gamma 30, bsimp above). */
static bkf_stepper_kind floquet_other_stepper(double gamma)
{
    return gamma > 30.0 ? BKF_STEPPER_EXPLICIT : BKF_STEPPER_IMPLICIT;
}

/* lambda by power iteration, written here: the cycle and one perturbation
 * (d_psi, d_eta) in the plain coordinates, GSL rk4imp (implicit Gauss; the
 * library uses rk8pd, bsimp and, for multipliers under the noise floor of
 * M, angle and log-norm equations), the vector renormalised after every
 * step with its log-norm summed.  Each period restarts the cycle from the
 * section point of an independent cycle solve and keeps the direction:
 * with real multipliers the growth per period converges to ln|m1| by the
 * factor |m2/m1| per period; with a complex pair it keeps oscillating.
 * Returns the last growth; *spread is the change over the last period and
 * *periods how many ran.  For real multipliers (`real`) it stops as soon
 * as the growth has settled (to the caller's 1e-9 |lambda|, the change
 * shrinking at least tenfold a period, so the rest of the geometric tail
 * is under a ninth of the spread) or stopped settling (the change no
 * longer halves: the integration's noise); at gamma 100, c q 100 (|m2/m1|
 * ~ exp(-1.3e4)) that is 3 periods of 0.5 s, not 4. */
typedef struct {
    double gamma, nu, K;
} pert;

static int pert_rhs(double t, const double s[], double f[], void *params)
{
    (void)t;
    const pert *p = params;
    double g = p->gamma, x = s[0], damp = g * (x * x - 1.0);
    f[0] = g * (s[1] - (x * x * x / 3.0 - x));
    f[1] = (p->nu - x) / g;
    f[2] = g * s[3] - damp * s[2];
    f[3] = -p->K * s[2] / g;
    return GSL_SUCCESS;
}

static int pert_jac(double t, const double s[], double *J, double *dt, void *params)
{
    (void)t;
    const pert *p = params;
    double g = p->gamma, x = s[0], damp = g * (x * x - 1.0);
    memset(J, 0, 16 * sizeof *J);
    J[0] = -damp;
    J[1] = g;
    J[4] = -1.0 / g;
    J[8] = -2.0 * g * x * s[2];
    J[10] = -damp;
    J[11] = g;
    J[14] = -p->K / g;
    memset(dt, 0, 4 * sizeof *dt);
    return GSL_SUCCESS;
}

static double lambda_power(double gamma, double nu, double K, const bkf_cycle_result *cy, double tol,
                           int max_periods, int real, double *spread, int *periods)
{
    gsl_set_error_handler_off();
    pert p = {gamma, nu, K};
    gsl_odeiv2_system sys = {pert_rhs, pert_jac, 4, &p};
    /* through a driver: GSL's implicit steppers take their settings from it */
    gsl_odeiv2_driver *d = gsl_odeiv2_driver_alloc_y_new(&sys, gsl_odeiv2_step_rk4imp, 1e-5, tol, tol);
    CHECK(d);
    gsl_odeiv2_step *st = d->s;
    gsl_odeiv2_control *ctl = d->c;
    gsl_odeiv2_evolve *ev = d->e;
    double x0 = nu, y0 = cy->section_slope / gamma + (nu * nu * nu / 3.0 - nu), T = cy->period;
    double u = 1.0, e = 1.0, growth = NAN, last = NAN, before = INFINITY;
    *spread = INFINITY;
    int n;
    for (n = 0; n < max_periods; n++) {
        double s[4] = {x0, y0, u, e}, t = 0.0, h = 1e-3 * fmin(gamma, 1.0 / gamma), sum = 0.0;
        double r0 = hypot(s[2], s[3]);
        s[2] /= r0;
        s[3] /= r0;
        gsl_odeiv2_evolve_reset(ev);
        while (t < T) {
            if (gsl_odeiv2_evolve_apply(ev, ctl, st, &sys, &t, T, &h, s) != GSL_SUCCESS) break;
            double r = hypot(s[2], s[3]);
            if (!(r > 0.0) || !isfinite(r)) break;
            sum += log(r);
            s[2] /= r;
            s[3] /= r;
        }
        if (t < T) {
            growth = NAN;
            break;
        }
        last = growth;
        growth = sum;
        u = s[2];
        e = s[3];
        if (n > 0) {
            before = *spread;
            *spread = fabs(growth - last);
        }
        double scale = fmax(1.0, fabs(growth));
        if (n > 1 && real && *spread > 0.5 * before) {
            /* stalled: the larger of the last two changes is the spread */
            *spread = fmax(*spread, before);
            n++;
            break;
        }
        if (n > 1 && (*spread <= 1e-12 * scale || (real && *spread <= 1e-9 * scale && *spread <= 0.1 * before))) {
            n++;
            break;
        }
    }
    *periods = n;
    gsl_odeiv2_driver_free(d);
    return growth;
}

/* ln |m1 m2| from the reported multipliers (m2 can underflow when L is very
 * negative: then NaN) */
static double log_product(const bkf_floquet_point *p)
{
    double a = hypot(p->m1_re, p->m1_im), b = hypot(p->m2_re, p->m2_im);
    return a > 0 && b > 0 ? log(a) + log(b) : NAN;
}

/* The Floquet matrix over the sets (gamma, nu) given (one part of the box:
 * the parts run in parallel), with at most max_refused refusals and
 * max_unverified points nothing independent can check. */
/* The reference's answers by c q: both tolerances of the matrix ask the
 * same c q of it, and an evaluation depends on the set and q alone, so the
 * second asks the first's answer (the reference at c q 100 and gamma 100
 * costs seconds). */
typedef struct {
    double cq[16];
    int rc[16];
    bkf_floquet_point pt[16];
    size_t n;
} ref_memo;

static int ref_eval(ref_memo *m, bkf_floquet *ref, double cq, bkf_floquet_point *p, bkf_error *e)
{
    for (size_t i = 0; i < m->n; i++)
        if (m->cq[i] == cq) {
            *p = m->pt[i];
            return m->rc[i];
        }
    int rc = bkf_floquet_eval(ref, cq, p, e);
    if (m->n < 16) {
        m->cq[m->n] = cq;
        m->rc[m->n] = rc;
        m->pt[m->n++] = *p;
    }
    return rc;
}

/* The other stepper's lambda at c q, with its estimate as the
 * uncertainty, where it answered or refused with a best attempt. */
static void other_stepper(ref_memo *m, bkf_floquet *ref, int ref_ok, double cq, double *lref,
                          double *unc, const char **by)
{
    if (!ref_ok) return;
    bkf_floquet_point r;
    bkf_error e;
    int rc = ref_eval(m, ref, cq, &r, &e);
    if (rc == BKF_OK || rc == BKF_ETOL) {
        *lref = r.lambda;
        *unc = r.lambda_err;
        *by = "other stepper";
    }
}

typedef struct {
    double gamma, nu;
    /* at tol 1e-8 only c q up to this (0: all); see the sets below */
    double tight_cq_max;
} floquet_set_point;

static void floquet_matrix(const floquet_set_point *sets, size_t n_sets, size_t max_refused,
                           size_t max_unverified)
{
    const double cs[] = {0, 0.3, 10};
    const double qs[] = {0, 1, 10};
    const double tols[] = {1e-4, 1e-8};
    tally t = {"floquet", 0, 0, 0, 0, 0, ""};
    double worst_L = 0;
    size_t unverified = 0;
    double t_power = 0.0;
    for (size_t i = 0; i < n_sets; i++) {
        double gamma = sets[i].gamma, nu = sets[i].nu;
        clock_t c0 = clock();
        /* L by an independent solve of the cycle (mu = gamma), the other
         * stepper where it can, at tol 1e-12 */
        bkf_cycle_options co = bkf_cycle_options_default();
        co.tol = 1e-12;
        co.warm_start = 0;
        co.stepper = floquet_other_stepper(gamma);
        bkf_cycle_result cy;
        bkf_error e = {0};
        int cy_rc = bkf_cycle_period(gamma, nu, &co, &cy, &e);
        /* near the Hopf point at gamma >= 30 the cycle refuses 1e-12 */
        for (int a = 0; cy_rc != BKF_OK && a < 4; a++) {
            co.stepper = a % 2 ? floquet_other_stepper(gamma) : BKF_STEPPER_AUTO;
            if (a == 2) co.tol = 1e-10;
            cy_rc = bkf_cycle_period(gamma, nu, &co, &cy, &e);
        }
        CHECK_MSG(cy_rc == BKF_OK, "cycle gamma %g nu %g: %s", gamma, nu, e.message);
        double L_ref = cy.log_multiplier, L_unc = cy.log_multiplier_err;
        /* the reference lambda: the other stepper at tol 1e-12, c = 1 so
         * that q' = c q gives the same K = 1 + c^2 q^2 */
        bkf_floquet_options ro = bkf_floquet_options_default();
        ro.tol = 1e-10;
        ro.stepper = floquet_other_stepper(gamma);
        bkf_floquet *ref = bkf_floquet_alloc();
        CHECK(ref);
        int ref_ok = bkf_floquet_set(ref, gamma, 1.0, nu, &ro, &e) == BKF_OK;
        if (!ref_ok) bkf_test_note("floquet gamma %g nu %g: no reference (%s)", gamma, nu, e.message);
        ref_memo refs = {.n = 0};
        double t_ref = (double)(clock() - c0) / CLOCKS_PER_SEC;
        for (size_t k = 0; k < sizeof cs / sizeof cs[0]; k++)
            for (size_t l = 0; l < sizeof tols / sizeof tols[0]; l++) {
                double c = cs[k], tol = tols[l];
                clock_t c1 = clock();
                bkf_floquet_options o = bkf_floquet_options_default();
                o.tol = tol;
                bkf_floquet *f = bkf_floquet_alloc();
                CHECK(f);
                char where[200];
                fmt_where(where, sizeof where, "lambda gamma %g nu %g c %g tol %g", gamma, nu, c, tol);
                int set_rc = bkf_floquet_set(f, gamma, c, nu, &o, &e);
                for (size_t m = 0; m < sizeof qs / sizeof qs[0]; m++) {
                    double q = qs[m], cq = c * q;
                    if (tol < 1e-4 && sets[i].tight_cq_max > 0.0 && cq > sets[i].tight_cq_max) continue;
                    char at[240];
                    fmt_where(at, sizeof at, "%s q %g", where, q);
                    bkf_floquet_point p;
                    int rc = set_rc == BKF_OK ? bkf_floquet_eval(f, q, &p, &e) : set_rc;
                    if (rc != BKF_OK) {
                        tally_refused(&t, rc, e.message, at);
                        continue;
                    }
                    double lref = NAN, unc = INFINITY;
                    const char *by = "?";
                    if (cq == 0.0) {
                        /* the trivial multiplier 1 exactly (the cycle is
                         * stable: L < 0) */
                        CHECK_MSG(L_ref < 0, "%s: cycle multiplier exp(%g)", at, L_ref);
                        lref = 0.0;
                        unc = 0.0;
                        by = "exact";
                    }
                    /* The library's other stepper runs the same
                     * algorithms (for lambda < -5 often the log columns,
                     * not M), so there, at tol 1e-4, the test's own power
                     * iteration decides (at 1e-8 it costs minutes), as it
                     * does wherever the other stepper cannot. */
                    int forced = cq > 0.0 && p.lambda < -5.0 && p.kind != BKF_FLOQUET_COMPLEX && tol >= 1e-4;
                    /* the other stepper where its value is used: not
                     * where the power iteration decides (its answer at c q
                     * 100 and gamma 100 costs 2.5 s); where it refuses,
                     * its best attempt and its estimate still serve if
                     * that estimate is below tol */
                    if (cq > 0.0 && !forced) other_stepper(&refs, ref, ref_ok, cq, &lref, &unc, &by);
                    if (forced || !(unc <= tol) || !(fabs(p.lambda - lref) <= tol + unc)) {
                        /* The power iteration written here: with real
                         * multipliers it must converge to lambda; with a
                         * complex pair lambda is L/2 of the independent
                         * cycle solve, and the iteration must not
                         * settle elsewhere. */
                        double spread;
                        int periods;
                        clock_t c2 = clock();
                        /* A complex pair turns the iterate: its growth per
                         * period changes by O(1) (0.16-1.6 at gamma 30, nu
                         * -0.99, c q 100), which a run at tol 1e-8 shows
                         * where its spread stands above that run's noise
                         * (100 tol |lambda|, the bound below): 4.6 s there
                         * against 17 s at 1e-11.  Anything nearer settling
                         * is decided at the tight tolerance, as before. */
                        double ptol = fmax(1e-11, 1e-3 * tol), lp_ = NAN;
                        spread = 0.0;
                        periods = 0;
                        if (p.kind == BKF_FLOQUET_COMPLEX && ptol < 1e-8)
                            lp_ = lambda_power(gamma, nu, 1.0 + cq * cq, &cy, 1e-8, 12, 0, &spread, &periods);
                        if (!(periods >= 12 && isfinite(lp_) && spread > 100.0 * 1e-8 * fmax(1.0, fabs(lp_))))
                            lp_ = lambda_power(gamma, nu, 1.0 + cq * cq, &cy, ptol, 12,
                                               p.kind != BKF_FLOQUET_COMPLEX, &spread, &periods);
                        double t_this = (double)(clock() - c2) / CLOCKS_PER_SEC;
                        t_power += t_this;
                        bkf_test_note("%s: power iteration %.2f s, %d periods", at, t_this, periods);
                        int settled = spread <= 1e-9 * fmax(1.0, fabs(lp_));
                        if (p.kind == BKF_FLOQUET_COMPLEX && !settled && periods >= 12 && isfinite(lp_)) {
                            lref = 0.5 * L_ref;
                            unc = 0.5 * L_unc + 1e-12 * fabs(L_ref);
                            by = "L/2 (power iteration does not settle)";
                        } else if (settled) {
                            lref = lp_;
                            /* rk4imp at 1e-3 tol (>= 1e-11) over at most ~1e5 steps */
                            unc = spread + fmax(1e-9, 100.0 * fmax(1e-11, 1e-3 * tol)) * fmax(1.0, fabs(lp_));
                            by = "power iteration";
                        } else {
                            if (forced) other_stepper(&refs, ref, ref_ok, cq, &lref, &unc, &by);
                            bkf_test_note("%s: power iteration did not settle in %d periods (spread %.2g, "
                                          "lambda %.6g, other stepper %.6g +- %.2g)",
                                          at, periods, spread, p.lambda, lref, unc);
                        }
                    }
                    /* Liouville with the independent L: ln|m1 m2| is the
                     * integral of the trace over the period, the same
                     * for every q, an integral of size |L| met to the
                     * relative tolerance tol */
                    double lp = log_product(&p);
                    double dL = fabs((isfinite(lp) ? lp : p.log_det) - L_ref);
                    double L_scale = tol * fmax(1.0, fabs(L_ref));
                    CHECK_MSG(dL <= L_scale + L_unc,
                              "%s: LIOUVILLE: ln|m1 m2| - L = %.3g above tol max(1, |L|) "
                              "(L %.10g +- %.1g)", at, dL, L_ref, L_unc);
                    worst_L = fmax(worst_L, dL / L_scale);
                    double err = fabs(p.lambda - lref);
                    double ratio = fmax(err - unc, 0.0) / p.lambda_err;
                    bkf_test_note("%s: OK, lambda %.10g true %.2g est %.2g ratio %.2g (ref %s +- %.1g); "
                                  "ln|m1 m2| - L %.2g (L %.6g +- %.1g)",
                                  at, p.lambda, err, p.lambda_err, ratio, by, unc, dL, L_ref, L_unc);
                    if (!(unc <= tol) && !(err <= tol)) {
                        unverified++;
                        bkf_test_note("%s: UNVERIFIED: reference %s %.10g +- %.2g, lambda %.10g +- %.2g",
                                      at, by, lref, unc, p.lambda, p.lambda_err);
                        /* not within tol, but within the reference's own
                         * uncertainty (the power iteration's 1e-5 |lambda|
                         * at c q 100): a lambda off by far more is a defect,
                         * not an unverifiable point */
                        CHECK_MSG(!isfinite(unc) || err <= tol + unc,
                                  "%s: MISSED its reference: error %.3g (lambda %.10g, ref %.10g +- %.2g by %s)",
                                  at, err, p.lambda, lref, unc, by);
                        t.points++;
                        continue;
                    }
                    /* the contract: OK means within tol */
                    CHECK_MSG(err <= tol + unc, "%s: MISSED TOL: error %.2g (lambda %.10g, ref %.10g +- %.2g by %s), "
                              "lambda_err %.2g", at, err, p.lambda, lref, unc, by, p.lambda_err);
                    CHECK_MSG(ratio <= 10.0, "%s: lambda_err optimistic by %.3g", at, ratio);
                    tally_ok(&t, ratio, fmax(err - unc, 0.0) / tol, at);
                }
                bkf_floquet_free(f);
                bkf_test_note("%s: %.2f s (3 q)", where, (double)(clock() - c1) / CLOCKS_PER_SEC);
            }
        bkf_floquet_free(ref);
        bkf_test_note("floquet gamma %g nu %g: references %.2f s, all %.2f s", gamma, nu, t_ref,
                      (double)(clock() - c0) / CLOCKS_PER_SEC);
    }
    bkf_test_note("worst |ln|m1 m2| - L| / (tol max(1, |L|)): %.3g (at most 1)", worst_L);
    bkf_test_note("floquet: %zu not verifiable (no independent value within tol); power iteration %.2f s",
                  unverified, t_power);
    /* few refusals and few points nothing independent can check (README) */
    CHECK_MSG(t.refused <= max_refused, "%zu refusals", t.refused);
    CHECK_MSG(unverified <= max_unverified, "%zu unverifiable points", unverified);
    tally_report(&t);
}

/* The box gamma {1e-2, 0.3, 2, 30, 1e2} x nu {0, -0.9, -0.99, 0.9999}
 * less two sets, in three parts (13.6, 18.1 and 9.1 s of CPU; 17.8, 19.2
 * and 13.2 while the other stepper was asked where the power iteration
 * decides; 37 s each before the product's hopeless log-column retries were
 * cut and a complex pair's power iteration was first run at 1e-8).  Below gamma 30 a set costs 0.3
 * s, so all 12 stay; at gamma 30 and 100 a set costs 4-14 s (the product's
 * retries before its refusals, the test's power iteration), and
 * nu -0.9 and -0.99 show the same things there: at gamma 30 a complex pair
 * at c q 100 (L/2) and the other stepper undecided at tol 1e-8, at gamma
 * 100 real multipliers at c q 100 (-13527, -15144) and tol 1e-8 refused at
 * c q 10.  Kept at each: the sets that failed before (gamma 30, nu 0: the
 * complex pair, -11.68 instead of L/2 = -1326; gamma 100, nu -0.9: -75.8
 * and -225 instead of -13527), the one nearest the edge (-0.99: the worst
 * true/estimated of the box) and the canard 0.9999; dropped gamma 30 nu
 * -0.9 (21 s) and gamma 100 nu 0 (13 s), whose c q 100 is the same kind
 * as their neighbours'.  At gamma 100, nu -0.9 tol 1e-8 stops at c q 10:
 * its c q 100 (-13527, real, by the log columns, against the other
 * stepper) is the kind -0.99 checks at tol 1e-8 (a lambda 1e-4 off there
 * fails), and cost 2.8 s of the set's 7 (the other stepper's refusal at
 * tol 1e-10); its tol 1e-4 c q 100 against the power iteration, the check
 * that caught -75.8, stays.  The caps add up to at most 30 refusals and 8
 * points nothing independent can check (today 0 + 2 + 4 and 0 + 2 + 1;
 * 323 points; 7.4, 12.0 and 8.2 s of CPU under load). */
TEST(extremes_floquet_matrix_gamma_to_30)
{
    static const floquet_set_point sets[] = {
        {1e-2, 0, 0}, {1e-2, -0.9, 0}, {1e-2, -0.99, 0}, {1e-2, 0.9999, 0}, {0.3, 0, 0}, {0.3, -0.9, 0},
        {0.3, -0.99, 0}, {0.3, 0.9999, 0}, {2, 0, 0}, {2, -0.9, 0}, {2, -0.99, 0}, {2, 0.9999, 0},
        {30, 0, 0}, {30, -0.99, 0}, {30, 0.9999, 0}};
    floquet_matrix(sets, sizeof sets / sizeof sets[0], 10, 3);
}

TEST(extremes_floquet_matrix_gamma_100)
{
    static const floquet_set_point sets[] = {{1e2, -0.9, 10.0}, {1e2, -0.99, 0.0}};
    floquet_matrix(sets, 2, 10, 3);
}

TEST(extremes_floquet_matrix_gamma_100_near_hopf)
{
    static const floquet_set_point sets[] = {{1e2, 0.9999, 0}};
    floquet_matrix(sets, 1, 10, 2);
}

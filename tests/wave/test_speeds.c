/* The allowed front speeds (module speeds): every root of
 *     n T(mu(v)) = S / (v sqrt(1 - c^2/v^2)),   mu(v) = gamma / sqrt(1 - c^2/v^2),
 * checked against values computed here independently, the closed form at
 * c = 0, the large-gamma quantization, the existence bound, a brute-force
 * count of roots, and branches through folds to the sonic limit. */
#include "harness.h"

#include <gsl/gsl_errno.h>
#include <gsl/gsl_roots.h>
#include <string.h>

#include "bkfront/asymptotics.h"
#include "bkfront/cycle.h"
#include "bkfront/speeds.h"
#include "taylor_reference.h"

static const bkf_model_params paper = {2.0, 0.3, -0.96, 20.0, 0, BKF_MODEL_CONTINUUM};

static bkf_speeds_table find(bkf_model_params p, double tol, size_t n_from, size_t n_to)
{
    bkf_speeds_options o = bkf_speeds_options_default();
    o.tol = tol;
    o.n_from = n_from;
    o.n_to = n_to;
    bkf_speeds_table t;
    bkf_error e = {0};
    int rc = bkf_speeds_find(&p, &o, &t, &e);
    CHECK_MSG(rc == BKF_OK, "find(gamma %g, c %g, nu %g, S %g): %s", p.gamma, p.c, p.nu, p.S,
              e.message);
    return t;
}

/* ------------------------------------------------ an independent root */

typedef struct {
    bkf_model_params p;
    double n;
} cond;

/* n T v sqrt(1 - c^2/v^2) / S - 1 with v itself as the unknown and T at
 * tol 1e-12, in a fresh solve every time: nothing shared with the module
 * but the cycle solver, and above the stiffness threshold not its stepper
 * either (the module takes the automatic bd2x2 there, this bsimp). */
static double condition_in_v(double v, void *data)
{
    const cond *c = data;
    double w = sqrt(1.0 - (c->p.c / v) * (c->p.c / v));
    bkf_cycle_options o = bkf_cycle_options_default();
    o.tol = 1e-12;
    o.warm_start = 0;
    if (c->p.gamma / w > BKF_CYCLE_STIFF_MU) o.stepper = BKF_STEPPER_IMPLICIT;
    bkf_cycle_result r;
    bkf_error e;
    CHECK_MSG(bkf_cycle_period(c->p.gamma / w, c->p.nu, &o, &r, &e) == BKF_OK, "%s", e.message);
    return c->n * r.period * v * w / c->p.S - 1.0;
}

/* The root in v within a relative distance `width` of v0, by Brent. */
static double reference_v(bkf_model_params p, double n, double v0, double width)
{
    gsl_set_error_handler_off();
    cond c = {p, n};
    gsl_function F = {condition_in_v, &c};
    double lo = v0 * (1.0 - width), hi = v0 * (1.0 + width);
    if (lo <= p.c) lo = 0.5 * (v0 + p.c);
    gsl_root_fsolver *s = gsl_root_fsolver_alloc(gsl_root_fsolver_brent);
    CHECK(s);
    CHECK_MSG(gsl_root_fsolver_set(s, &F, lo, hi) == GSL_SUCCESS, "no bracket around v = %.17g", v0);
    for (int it = 0; it < 100; it++) {
        CHECK(gsl_root_fsolver_iterate(s) == GSL_SUCCESS);
        double a = gsl_root_fsolver_x_lower(s), b = gsl_root_fsolver_x_upper(s);
        if (b - a <= 1e-14 * b) break;
    }
    double v = gsl_root_fsolver_root(s);
    gsl_root_fsolver_free(s);
    return v;
}

/* Every row: a root of the condition as written in v (its residual,
 * recomputed here from the row's T), supersonic, consistent columns. */
static void check_rows(const bkf_model_params *p, const bkf_speeds_table *t, double tol)
{
    for (size_t i = 0; i < t->count; i++) {
        const bkf_speeds_root *r = &t->roots[i];
        double n = (double)r->n;
        CHECK_MSG(fabs(r->residual) <= tol, "n = %zu, v = %.17g: residual %.3g > tol %.3g", r->n,
                  r->v, r->residual, tol);
        /* w = sqrt(1 - c^2/v^2) recomputed from the printed v loses digits
         * near the sonic limit: about eps / w^2 relatively */
        double w2 = p->c > 0 ? 1.0 - (p->c / r->v) * (p->c / r->v) : 1.0, w = sqrt(w2);
        double slack = 1e-15 / w2 + 1e-13;
        double again = n * r->T * r->v * w / p->S - 1.0;
        CHECK_MSG(fabs(again) <= tol + slack, "n = %zu: recomputed residual %.3g", r->n, again);
        CHECK(r->v > p->c);
        if (p->c > 0) {
            CHECK_CLOSE(r->mu, p->gamma / w, slack, 0);
            CHECK_CLOSE(r->v_over_c, r->v / p->c, 1e-14, 0);
        }
        CHECK_CLOSE(r->wavelength, p->S / n, 1e-15, 0);
        CHECK_CLOSE(r->period_fixed, r->T * w, slack, 0);
        CHECK_CLOSE(r->v_asym, p->S / (n * bkf_asym_k(p->nu) * p->gamma), 1e-14, 0);
        CHECK_CLOSE(r->deviation, (r->v - r->v_asym) / r->v, 1e-12, 1e-15);
        CHECK(r->v_err >= 0 && r->T_err >= 0);
        if (i > 0) {
            const bkf_speeds_root *q = &t->roots[i - 1];
            CHECK(q->n < r->n || (q->n == r->n && q->v > r->v));
        }
    }
}

TEST(speeds_paper_table_every_v_to_1e9)
{
    bkf_speeds_table t = find(paper, 1e-10, 1, 0);
    CHECK_MSG(t.n_max == 12 && t.count == 12, "n_max %ld, %zu rows", t.n_max, t.count);
    CHECK(!t.dips_below_k && !t.truncated && t.unresolved == 0 && t.note[0] == '\0');
    CHECK_CLOSE(t.n_bound, paper.S / (bkf_asym_k(paper.nu) * paper.c * paper.gamma), 1e-15, 0);
    check_rows(&paper, &t, 1e-10);
    double worst = 0;
    for (size_t i = 0; i < t.count; i++) {
        const bkf_speeds_root *r = &t.roots[i];
        CHECK(r->n == i + 1 && r->flags == 0);
        double v_ref = reference_v(paper, (double)r->n, r->v, 1e-7);
        double rel = fabs(r->v - v_ref) / v_ref;
        CHECK_MSG(rel <= 1e-9, "n = %zu: v = %.17g, reference %.17g (rel %.2g)", r->n, r->v, v_ref,
                  rel);
        /* the error estimate is honest: within a few times of the truth */
        CHECK_MSG(rel <= 3.0 * r->v_err / r->v + 1e-14, "n = %zu: rel %.2g, v_err/v %.2g", r->n, rel,
                  r->v_err / r->v);
        if (rel > worst) worst = rel;
    }
    /* the cost the paper's table is judged by (issue 20): the prediction,
     * moved by a scout solve where it is uncertain, leaves at most two
     * solves at the root's tolerance per root (it took three below mu 5) */
    CHECK_MSG(t.precise_solves <= 2 * t.count, "%zu precise solves for %zu roots", t.precise_solves,
              t.count);
    bkf_test_note("gamma 2, c 0.3, nu -0.96, S 20: 12 roots, worst |v - v_ref|/v = %.2g; "
                  "%zu coarse + %zu precise solves",
                  worst, t.coarse_solves, t.precise_solves);
    bkf_speeds_table_free(&t);
}

TEST(speeds_residuals_below_tolerance)
{
    const struct {
        bkf_model_params p;
        double tol;
    } cases[] = {
        {{1.0, 0.5, 0.0, 30.0, 0, BKF_MODEL_CONTINUUM}, 1e-10},
        {{0.5, 1.0, 0.5, 10.0, 0, BKF_MODEL_CONTINUUM}, 1e-10},
        {{2.0, 0.3, -0.96, 20.0, 0, BKF_MODEL_CONTINUUM}, 1e-6},
        {{2.0, 0.3, 0.96, 20.0, 0, BKF_MODEL_CONTINUUM}, 1e-12},
        {{1.5, 0.3, -0.96, 20.0, 0, BKF_MODEL_CONTINUUM}, 1e-10},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        bkf_speeds_table t = find(cases[i].p, cases[i].tol, 1, 0);
        CHECK(t.count >= (size_t)t.n_max && t.n_max >= 1);
        check_rows(&cases[i].p, &t, cases[i].tol);
        bkf_test_note("gamma %g c %g nu %g S %g tol %g: %zu roots, n_max %ld", cases[i].p.gamma,
                      cases[i].p.c, cases[i].p.nu, cases[i].p.S, cases[i].tol, t.count, t.n_max);
        bkf_speeds_table_free(&t);
    }
}

/* --method: with auto at loose tol and large mu every root comes from a
 * formula (no solve at the roots' tolerance) and agrees with the shooting
 * roots within its stated v_err; at c = 0 and small gamma the small-mu
 * formula gives v = S/(n T) within v_err of the shooting value; a formula
 * asked for where its bound does not meet what the root needs fails. */
TEST(speeds_method_formula_roots)
{
    bkf_model_params p = {300.0, 0.3, 0.0, 2000.0, 0, BKF_MODEL_CONTINUUM};
    bkf_speeds_options o = bkf_speeds_options_default();
    CHECK(o.method == BKF_METHOD_AUTO);
    o.tol = 1e-2;
    o.n_to = 5;
    bkf_speeds_table a, s;
    bkf_error e = {0};
    CHECK_MSG(bkf_speeds_find(&p, &o, &a, &e) == BKF_OK, "%s", e.message);
    o.method = BKF_METHOD_SHOOTING;
    o.tol = 1e-10;
    CHECK_MSG(bkf_speeds_find(&p, &o, &s, &e) == BKF_OK, "%s", e.message);
    CHECK(a.count == 5 && s.count == 5 && a.precise_solves == 0 && a.formula_answers == 5);
    CHECK(s.formula_answers == 0);
    for (size_t i = 0; i < a.count && i < s.count; i++) {
        CHECK(strcmp(a.roots[i].model, "shooting") != 0 && strcmp(s.roots[i].model, "shooting") == 0);
        CHECK_MSG(fabs(a.roots[i].v - s.roots[i].v) <= a.roots[i].v_err && a.roots[i].v_err <= 1e-2 * a.roots[i].v,
                  "n %zu: %.10g vs %.10g, v_err %g", a.roots[i].n, a.roots[i].v, s.roots[i].v,
                  a.roots[i].v_err);
    }
    bkf_speeds_table_free(&a);
    bkf_speeds_table_free(&s);

    bkf_model_params q = {1e-3, 0.0, 0.5, 10.0, 0, BKF_MODEL_CONTINUUM};
    o = bkf_speeds_options_default();
    o.tol = 1e-8;
    o.n_to = 2;
    CHECK_MSG(bkf_speeds_find(&q, &o, &a, &e) == BKF_OK, "%s", e.message);
    bkf_cycle_options co = bkf_cycle_options_default();
    co.tol = 1e-12;
    bkf_cycle_result r;
    CHECK(bkf_cycle_period(q.gamma, q.nu, &co, &r, &e) == BKF_OK);
    CHECK(a.count == 2 && a.formula_answers == 1 && a.precise_solves == 0);
    for (size_t i = 0; i < a.count; i++) {
        CHECK(strcmp(a.roots[i].model, "asymptotic") == 0);
        double v = q.S / ((double)a.roots[i].n * r.period);
        CHECK_MSG(fabs(a.roots[i].v - v) <= a.roots[i].v_err && a.roots[i].v_err <= 1e-8 * v,
                  "c = 0, n %zu: %.15g vs %.15g, v_err %g", a.roots[i].n, a.roots[i].v, v,
                  a.roots[i].v_err);
    }
    bkf_speeds_table_free(&a);

    o = bkf_speeds_options_default();
    o.tol = 1e-2;
    o.method = BKF_METHOD_ASYMPTOTIC;
    /* the large-mu formula meets tol 1e-2 at the paper's n = 12 (mu 44)
     * alone: the other roots are refused rows saying so, and n = 12 agrees
     * with the shooting root within its v_err */
    CHECK_MSG(bkf_speeds_find(&paper, &o, &a, &e) == BKF_OK && a.count == 12 && a.refused == 11,
              "%zu rows, %zu refused: %s", a.count, a.refused, e.message);
    bkf_speeds_table shot = find(paper, 1e-10, 12, 12);
    for (size_t i = 0; i < a.count && a.count == 12 && shot.count == 1; i++) {
        const bkf_speeds_root *r = &a.roots[i];
        CHECK(r->n == i + 1);
        if (r->n == 12)
            CHECK_MSG(r->status == BKF_OK && strcmp(r->model, "asymptotic") == 0 &&
                          fabs(r->v - shot.roots[0].v) <= r->v_err,
                      "n 12: %.17g vs %.17g, v_err %g", r->v, shot.roots[0].v, r->v_err);
        else
            CHECK(r->status == BKF_ETOL && isnan(r->v) && strstr(r->refusal, "error bound") &&
                  isnan(r->tol_met));
    }
    bkf_speeds_table_free(&shot);
    bkf_speeds_table_free(&a);
    o.method = (bkf_cycle_method)7;
    CHECK(bkf_speeds_find(&paper, &o, &a, &e) == BKF_EINPUT && strstr(e.message, "method"));
    bkf_speeds_table_free(&a);
}

/* nu -> -nu leaves T (and so every speed) unchanged: f -> -f. */
TEST(speeds_symmetric_in_nu)
{
    bkf_model_params q = paper;
    q.nu = -paper.nu;
    bkf_speeds_table a = find(paper, 1e-10, 1, 0), b = find(q, 1e-10, 1, 0);
    CHECK(a.count == b.count && a.n_max == b.n_max);
    for (size_t i = 0; i < a.count; i++) CHECK_CLOSE(a.roots[i].v, b.roots[i].v, 1e-9, 0);
    bkf_speeds_table_free(&a);
    bkf_speeds_table_free(&b);
}

TEST(speeds_c0_closed_form)
{
    bkf_model_params p = {2.0, 0.0, -0.96, 20.0, 0, BKF_MODEL_CONTINUUM};
    bkf_speeds_table t = find(p, 1e-10, 1, 0);
    CHECK(t.n_max == -1 && t.count == BKF_SPEEDS_ROWS_C0 && isinf(t.n_bound));
    bkf_cycle_options o = bkf_cycle_options_default();
    bkf_cycle_result r;
    bkf_error e;
    CHECK(bkf_cycle_period(p.gamma, p.nu, &o, &r, &e) == BKF_OK);
    for (size_t i = 0; i < t.count; i++) {
        const bkf_speeds_root *x = &t.roots[i];
        double n = (double)(i + 1);
        CHECK(x->n == i + 1 && x->mu == p.gamma && isinf(x->v_over_c));
        CHECK_CLOSE(x->T, r.period, 1e-10, 0);
        CHECK_CLOSE(x->v, p.S / (n * x->T), 1e-15, 0);
        CHECK_CLOSE(x->period_fixed, x->T, 0, 0);
        CHECK(fabs(x->residual) < 1e-15);
    }
    check_rows(&p, &t, 1e-10);
    bkf_speeds_table_free(&t);

    /* c -> 0+: the speeds go over continuously into the closed form (the
     * correction is O(c^2)) */
    bkf_model_params q = p;
    q.c = 1e-4;
    bkf_speeds_table a = find(p, 1e-10, 1, 5), b = find(q, 1e-10, 1, 5);
    CHECK(a.count == 5 && b.count == 5);
    for (size_t i = 0; i < 5; i++) CHECK_CLOSE(b.roots[i].v, a.roots[i].v, 1e-6, 0);
    bkf_speeds_table_free(&a);
    bkf_speeds_table_free(&b);

    /* a row range */
    t = find(p, 1e-8, 7, 9);
    CHECK(t.count == 3 && t.roots[0].n == 7 && t.roots[2].n == 9);
    bkf_speeds_table_free(&t);
}

/* gamma -> inf at fixed S/gamma: mu >= gamma is large, T ~ k mu, and the
 * speeds approach the quantization S/(n k gamma) with a relative deviation
 * ~ (b/k) mu^(-4/3), i.e. down by 2^(-4/3) ~ 0.40 per doubling of gamma. */
TEST(speeds_large_gamma_limit)
{
    const double gammas[] = {100.0, 200.0, 400.0};
    double previous[12] = {0};
    for (int i = 0; i < 3; i++) {
        bkf_model_params p = {gammas[i], 0.3, -0.96, 10.0 * gammas[i], 0, BKF_MODEL_CONTINUUM};
        bkf_speeds_table t = find(p, 1e-10, 1, 0);
        CHECK(t.n_max == 12 && t.count == 12);
        check_rows(&p, &t, 1e-10);
        for (size_t j = 0; j < 12; j++) {
            double dev = fabs(t.roots[j].deviation);
            CHECK_MSG(dev < 0.05 * pow(gammas[i] / 100.0, -4.0 / 3.0),
                      "gamma %g n %zu: deviation %.3g", gammas[i], j + 1, dev);
            if (i > 0) {
                double ratio = dev / previous[j];
                CHECK_MSG(ratio > 0.33 && ratio < 0.45, "gamma %g n %zu: ratio %.3f", gammas[i],
                          j + 1, ratio);
            }
            previous[j] = dev;
        }
        bkf_test_note("gamma %g: |v - S/(n k gamma)|/v = %.3g (n = 1) .. %.3g (n = 12)", gammas[i],
                      fabs(t.roots[0].deviation), fabs(t.roots[11].deviation));
        bkf_speeds_table_free(&t);
    }
}

/* S > n k c gamma is the large-mu bound: every n below n_bound has a root,
 * and (where g does not dip below k) none above it. */
TEST(speeds_existence_bound)
{
    double k = bkf_asym_k(-0.96), kcg = k * 0.3 * 2.0;
    const double factors[] = {0.5, 0.999, 1.001, 2.5, 7.3, 12.0001};
    for (size_t i = 0; i < sizeof factors / sizeof factors[0]; i++) {
        bkf_model_params p = {2.0, 0.3, -0.96, factors[i] * kcg, 0, BKF_MODEL_CONTINUUM};
        bkf_speeds_table t = find(p, 1e-8, 1, 0);
        long want = (long)ceil(factors[i]) - 1;
        CHECK_MSG(t.n_max == want, "S = %g kcg: n_max %ld, want %ld", factors[i], t.n_max, want);
        CHECK(t.count == (size_t)want && !t.dips_below_k);
        CHECK_CLOSE(t.n_bound, factors[i], 1e-12, 0);
        if (want == 0) CHECK(strstr(t.note, "no front") && strstr(t.note, "k(nu) c gamma"));
        else check_rows(&p, &t, 1e-8);
        /* just above the bound the root is near the sonic limit */
        if (want >= 1 && factors[i] - floor(factors[i]) < 0.01)
            CHECK(t.roots[want - 1].v_over_c < 1.001);
        bkf_speeds_table_free(&t);
    }
    /* asking beyond n_max gives nothing, with the reason */
    bkf_speeds_table t = find(paper, 1e-8, 13, 20);
    CHECK(t.count == 0 && t.n_max == 12 && strstr(t.note, "n_max = 12"));
    bkf_speeds_table_free(&t);
}

/* Near |nu| -> 1 the canard makes T(mu) rise steeply (even overshoot):
 * g = T/sqrt(mu^2 - gamma^2) dips below k, and n beyond n_bound have roots
 * (two each), while lower n have three. */
TEST(speeds_dip_below_k_beyond_n_bound)
{
    bkf_model_params p = {1.0, 0.3, -0.99, 20.0, 0, BKF_MODEL_CONTINUUM};
    /* the middle roots sit at mu 3.65, in the canard's neighbourhood, where
     * T is not had to 1e-9 (tol 1e-10 and 1e-9 are refused, naming n) */
    bkf_speeds_table t = find(p, 1e-8, 1, 0);
    CHECK(t.dips_below_k && t.g_inf < t.k);
    CHECK_MSG(t.n_max > (long)ceil(t.n_bound), "n_max %ld, n_bound %g", t.n_max, t.n_bound);
    check_rows(&p, &t, 1e-8);
    size_t per_n[64] = {0};
    for (size_t i = 0; i < t.count; i++)
        if (t.roots[i].n < 64) per_n[t.roots[i].n]++;
    for (long n = (long)ceil(t.n_bound); n <= t.n_max; n++)
        CHECK_MSG(per_n[n] == 2, "n = %ld: %zu roots", n, per_n[n]);
    CHECK(per_n[t.n_max + 1] == 0);
    bkf_test_note("gamma 1, c 0.3, nu -0.99, S 20: n_bound %.4g, n_max %ld, %zu roots", t.n_bound,
                  t.n_max, t.count);
    bkf_speeds_table_free(&t);
}

/* One n with three roots: gamma 1.5 puts the steep rise of T(mu) at
 * nu = -0.96 (mu ~ 2) inside mu > gamma, where g turns up between a
 * local minimum and maximum. */
TEST(speeds_three_roots_for_one_n)
{
    bkf_model_params p = {1.5, 0.3, -0.96, 20.0, 0, BKF_MODEL_CONTINUUM};
    bkf_speeds_table t = find(p, 1e-10, 6, 6);
    CHECK_MSG(t.count == 3, "%zu roots for n = 6", t.count);
    check_rows(&p, &t, 1e-10);
    CHECK(t.roots[0].slope < 0 && t.roots[1].slope > 0 && t.roots[2].slope < 0);
    for (size_t i = 0; i < 3; i++) {
        double v_ref = reference_v(p, 6, t.roots[i].v, 1e-8);
        CHECK_CLOSE(t.roots[i].v, v_ref, 1e-9, 0);
    }
    bkf_speeds_table_free(&t);
}

/* The count of roots against a brute-force scan: g on 3000 points evenly
 * spaced in s = ln sqrt(mu^2 - gamma^2), each solved afresh, and its sign
 * changes against every level ln(S/(n c gamma)). */
TEST(speeds_no_root_missed_against_dense_scan)
{
    bkf_model_params p = {1.5, 0.3, -0.96, 20.0, 0, BKF_MODEL_CONTINUUM};
    bkf_speeds_table t = find(p, 1e-10, 1, 0);
    enum { M = 3000 };
    static double lng[M + 1];
    double s_lo = -4.0, s_hi = log(200.0);
    bkf_cycle *c = bkf_cycle_alloc();
    bkf_cycle_options o = bkf_cycle_options_default();
    o.tol = 1e-8;
    for (int j = 0; j <= M; j++) {
        double s = s_lo + (s_hi - s_lo) * j / M, mu = hypot(p.gamma, exp(s));
        bkf_error e;
        CHECK_MSG(bkf_cycle_solve(c, mu, p.nu, &o, &e) == BKF_OK, "%s", e.message);
        lng[j] = log(bkf_cycle_get(c)->period) - s;
    }
    bkf_cycle_free(c);
    /* below s_lo, g > level 1; above s_hi, g < level n_max (checked) */
    double lnA = log(p.S / (p.c * p.gamma));
    CHECK(lng[0] > lnA && lng[M] < lnA - log((double)t.n_max));
    for (long n = 1; n <= t.n_max + 1; n++) {
        double ell = lnA - log((double)n);
        size_t crossings = 0, listed = 0;
        for (int j = 0; j < M; j++) crossings += (lng[j] > ell) != (lng[j + 1] > ell);
        for (size_t i = 0; i < t.count; i++) listed += t.roots[i].n == (size_t)n;
        CHECK_MSG(crossings == listed, "n = %ld: scan %zu crossings, table %zu roots", n, crossings,
                  listed);
    }
    bkf_speeds_table_free(&t);
}

TEST(speeds_rejects_bad_input)
{
    bkf_speeds_table t;
    bkf_error e;
    struct {
        bkf_model_params p;
        const char *name;
    } bad[] = {
        {{0.0, 0.3, -0.96, 20, 0, BKF_MODEL_CONTINUUM}, "gamma"},  {{-1.0, 0.3, -0.96, 20, 0, BKF_MODEL_CONTINUUM}, "gamma"},
        {{2e6, 0.3, -0.96, 20, 0, BKF_MODEL_CONTINUUM}, "gamma"},  {{NAN, 0.3, -0.96, 20, 0, BKF_MODEL_CONTINUUM}, "gamma"},
        {{2.0, -0.1, -0.96, 20, 0, BKF_MODEL_CONTINUUM}, "c"},     {{2.0, INFINITY, -0.96, 20, 0, BKF_MODEL_CONTINUUM}, "c"},
        {{2.0, 0.3, 1.0, 20, 0, BKF_MODEL_CONTINUUM}, "no fronts"}, {{2.0, 0.3, -1.5, 20, 0, BKF_MODEL_CONTINUUM}, "no fronts"},
        {{2.0, 0.3, NAN, 20, 0, BKF_MODEL_CONTINUUM}, "nu"},       {{2.0, 0.3, -0.96, 0, 0, BKF_MODEL_CONTINUUM}, "S"},
        {{2.0, 1e-300, -0.96, 20, 0, BKF_MODEL_CONTINUUM}, "c = 0"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        CHECK_STATUS(bkf_speeds_find(&bad[i].p, NULL, &t, &e), BKF_EINPUT);
        CHECK_MSG(strstr(e.message, bad[i].name), "case %zu: %s", i, e.message);
        CHECK(t.count == 0 && t.roots == NULL);
    }
    bkf_speeds_options o = bkf_speeds_options_default();
    o.tol = 1.0;
    CHECK_STATUS(bkf_speeds_find(&paper, &o, &t, &e), BKF_EINPUT);
    CHECK(strstr(e.message, "tol"));
    o = bkf_speeds_options_default();
    o.n_from = 0;
    CHECK_STATUS(bkf_speeds_find(&paper, &o, &t, &e), BKF_EINPUT);
    o.n_from = 5;
    o.n_to = 4;
    CHECK_STATUS(bkf_speeds_find(&paper, &o, &t, &e), BKF_EINPUT);
    CHECK_STATUS(bkf_speeds_find(&paper, NULL, NULL, &e), BKF_EINPUT);
}

/* --------------------------------------------------------------- branch */

typedef struct {
    bkf_speeds_branch_point pts[1024];
    size_t count;
} collected;

static int collect(const bkf_speeds_branch_point *pt, void *data)
{
    collected *c = data;
    if (c->count < 1024) c->pts[c->count++] = *pt;
    return 0;
}

static size_t roots_at(bkf_model_params p, size_t n)
{
    bkf_speeds_table t = find(p, 1e-8, n, n);
    size_t count = t.count;
    bkf_speeds_table_free(&t);
    return count;
}

/* Along S at gamma 1.5, nu -0.96, n = 6: from one root at S = 30 down
 * through a fold (the fast and middle roots meet), back up through a second
 * (middle and slow), then down to the sonic limit S = 6 k c gamma. */
TEST(branch_passes_two_folds_to_the_sonic_limit)
{
    static collected c;
    c.count = 0;
    bkf_model_params p = {1.5, 0.3, -0.96, 30.0, 0, BKF_MODEL_CONTINUUM};
    bkf_speeds_options o = bkf_speeds_options_default();
    o.tol = 1e-8;
    bkf_speeds_branch_report rep;
    bkf_error e = {0};
    int rc = bkf_speeds_branch(&p, 6, 1, BKF_SPEEDS_ALONG_S, 5.0, &o, 0, collect, &c, &rep, &e);
    CHECK_MSG(rc == BKF_OK, "%s", e.message);
    CHECK_MSG(rep.folds == 2 && rep.sonic, "folds %zu sonic %d", rep.folds, rep.sonic);
    double S_sonic = 6 * bkf_asym_k(p.nu) * p.c * p.gamma;
    CHECK_CLOSE(rep.sonic_value, S_sonic, 1e-14, 0);
    CHECK(c.count >= 10 && c.pts[0].params.S == 30.0);
    const bkf_speeds_branch_point *last = &c.pts[c.count - 1];
    CHECK(last->kind == BKF_SPEEDS_SONIC && last->root.v == p.c && isinf(last->root.mu));
    CHECK_CLOSE(last->params.S, S_sonic, 1e-14, 0);
    double folds[2];
    size_t nf = 0;
    for (size_t i = 0; i < c.count; i++) {
        const bkf_speeds_branch_point *x = &c.pts[i];
        if (x->kind == BKF_SPEEDS_FOLD) {
            CHECK(fabs(x->root.slope) < 1e-5);
            folds[nf++] = x->params.S;
        }
        if (x->kind != BKF_SPEEDS_SONIC) {
            CHECK(fabs(x->root.residual) < 1e-8);
            CHECK(x->params.gamma == p.gamma && x->params.c == p.c && x->params.nu == p.nu);
        }
        /* v decreases along the branch, whichever way S goes */
        if (i > 0) CHECK(x->root.v < c.pts[i - 1].root.v);
    }
    CHECK(nf == 2 && folds[0] < folds[1] && folds[1] < 30.0);
    /* the folds bound the window of three roots */
    CHECK(roots_at((bkf_model_params){1.5, 0.3, -0.96, folds[0] - 0.02, 0, BKF_MODEL_CONTINUUM}, 6) == 1);
    CHECK(roots_at((bkf_model_params){1.5, 0.3, -0.96, 0.5 * (folds[0] + folds[1]), 0, BKF_MODEL_CONTINUUM}, 6) == 3);
    CHECK(roots_at((bkf_model_params){1.5, 0.3, -0.96, folds[1] + 0.02, 0, BKF_MODEL_CONTINUUM}, 6) == 1);
    bkf_test_note("folds at S = %.10g and %.10g, sonic at S = %.10g; %zu points, %zu solves",
                  folds[0], folds[1], rep.sonic_value, rep.points, rep.solves);
}

/* Along c from 0.3 down to 0.1 for the paper's n = 12: the last point sits
 * exactly on c = 0.1 and agrees with the root found there directly. */
TEST(branch_lands_on_its_end_and_agrees_with_speeds)
{
    static collected c;
    c.count = 0;
    bkf_speeds_options o = bkf_speeds_options_default();
    bkf_speeds_branch_report rep;
    bkf_error e = {0};
    int rc = bkf_speeds_branch(&paper, 12, 1, BKF_SPEEDS_ALONG_C, 0.1, &o, 0, collect, &c, &rep, &e);
    CHECK_MSG(rc == BKF_OK, "%s", e.message);
    CHECK(rep.reached_end && !rep.sonic && rep.folds == 0);
    CHECK(c.pts[0].params.c == 0.3 && c.pts[c.count - 1].params.c == 0.1);
    bkf_speeds_table t0 = find(paper, 1e-10, 12, 12);
    CHECK_CLOSE(c.pts[0].root.v, t0.roots[0].v, 1e-9, 0);
    bkf_speeds_table_free(&t0);
    bkf_model_params q = paper;
    q.c = 0.1;
    bkf_speeds_table t1 = find(q, 1e-10, 12, 12);
    CHECK(t1.count == 1);
    CHECK_CLOSE(c.pts[c.count - 1].root.v, t1.roots[0].v, 1e-9, 0);
    for (size_t i = 0; i < c.count; i++) CHECK(fabs(c.pts[i].root.residual) <= 1e-10);
    bkf_speeds_table_free(&t1);
}

TEST(branch_in_nu_and_gamma)
{
    static collected c;
    bkf_speeds_options o = bkf_speeds_options_default();
    o.tol = 1e-9;
    bkf_speeds_branch_report rep;
    bkf_error e = {0};
    const struct {
        bkf_speeds_param along;
        double to;
    } runs[] = {{BKF_SPEEDS_ALONG_NU, -0.5}, {BKF_SPEEDS_ALONG_GAMMA, 1.8}};
    for (int r = 0; r < 2; r++) {
        c.count = 0;
        int rc = bkf_speeds_branch(&paper, 6, 1, runs[r].along, runs[r].to, &o, 0, collect, &c,
                                   &rep, &e);
        CHECK_MSG(rc == BKF_OK, "%s", e.message);
        CHECK(rep.reached_end && c.count >= 3);
        const bkf_speeds_branch_point *last = &c.pts[c.count - 1];
        double end = runs[r].along == BKF_SPEEDS_ALONG_NU ? last->params.nu : last->params.gamma;
        CHECK(end == runs[r].to);
        bkf_speeds_table t = find(last->params, 1e-10, 6, 6);
        CHECK(t.count == 1);
        CHECK_CLOSE(last->root.v, t.roots[0].v, 1e-8, 0);
        bkf_speeds_table_free(&t);
    }
}

TEST(branch_rejects_bad_input)
{
    static collected c;
    bkf_error e;
    bkf_model_params p = paper;
    CHECK_STATUS(bkf_speeds_branch(&p, 6, 1, BKF_SPEEDS_ALONG_S, 20.0, NULL, 0, collect, &c, NULL, &e),
                 BKF_EINPUT);
    CHECK(strstr(e.message, "equals"));
    CHECK_STATUS(bkf_speeds_branch(&p, 6, 1, BKF_SPEEDS_ALONG_NU, 1.0, NULL, 0, collect, &c, NULL, &e),
                 BKF_EINPUT);
    CHECK(strstr(e.message, "nu"));
    CHECK_STATUS(bkf_speeds_branch(&p, 6, 1, BKF_SPEEDS_ALONG_C, 0.0, NULL, 0, collect, &c, NULL, &e),
                 BKF_EINPUT);
    CHECK(strstr(e.message, "c > 0"));
    p.c = 0;
    CHECK_STATUS(bkf_speeds_branch(&p, 6, 1, BKF_SPEEDS_ALONG_S, 10.0, NULL, 0, collect, &c, NULL, &e),
                 BKF_EINPUT);
    CHECK(strstr(e.message, "closed form"));
    p = paper;
    /* no root for n = 13 at S = 20 */
    CHECK_STATUS(bkf_speeds_branch(&p, 13, 1, BKF_SPEEDS_ALONG_S, 30.0, NULL, 0, collect, &c, NULL, &e),
                 BKF_EINPUT);
    CHECK(strstr(e.message, "no front with n = 13"));
    CHECK_STATUS(bkf_speeds_branch(&p, 6, 2, BKF_SPEEDS_ALONG_S, 30.0, NULL, 0, collect, &c, NULL, &e),
                 BKF_EINPUT);
    CHECK_STATUS(bkf_speeds_branch(&p, 6, 1, BKF_SPEEDS_ALONG_S, 30.0, NULL, 0, NULL, NULL, NULL, &e),
                 BKF_EINPUT);
}

/* Honest scan (issue 20): at nu -0.9999 T explodes from 13 to 114 over mu
 * 35.3659-35.3661 (a canard); levels between g's two sides were crossed by
 * that jump, Brent closed on it, and the row reported was the cell's best
 * |D|, far off: gamma 1, S 1e4, n 11118 at mu 46.53 with residual 0.04
 * (tol 1e-4), v 3.6 tol off and 168 times its v_err (warm-started solves
 * gave T 113 at mu 35.365918, where it is 13.2).  Every row must now meet
 * its residual with T from the Taylor reference (nothing shared with the
 * engine) and its v_err may not flatter by more than 3 (a Newton step with a
 * Taylor secant); a level crossed by the jump is reported unresolved. */
static double taylor_T(double mu, double nu, double *unc)
{
    bkf_cycle_options o = bkf_cycle_options_default();
    o.tol = 1e-6;
    o.warm_start = 0;
    bkf_cycle_result r;
    bkf_error e = {0};
    double guess = bkf_cycle_period(mu, nu, &o, &r, &e) == BKF_OK ? r.section_slope : 1.0;
    return taylor_period(mu, nu, guess, unc);
}

TEST(speeds_canard_jump_rows_honest_or_unresolved)
{
    const struct {
        double gamma, S;
        size_t n_from, n_to;
    } cases[] = {{1, 1e4, 11118, 11121}, {0.3, 20, 73, 77}, {0.3, 1e4, 37059, 37062}};
    size_t checked = 0;
    double worst = 0;
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        bkf_model_params p = {cases[k].gamma, 0.3, -0.9999, cases[k].S, 0, BKF_MODEL_CONTINUUM};
        bkf_speeds_table t = find(p, 1e-4, cases[k].n_from, cases[k].n_to);
        CHECK_MSG(t.unresolved > 0, "gamma %g S %g: the jump not reported", p.gamma, p.S);
        /* next to the sonic limit every sample is within noise of the levels
         * near k: bisecting there decides nothing and spent the whole
         * budget of 4000 samples (speeds_search.c, noise_bound) */
        CHECK_MSG(t.samples < 1000, "gamma %g S %g: %zu samples of T", p.gamma, p.S, t.samples);
        for (size_t i = 0; i < t.count; i++) {
            const bkf_speeds_root *r = &t.roots[i];
            if (r->status != BKF_OK) continue; /* refused: it says so, no number to check */
            if (r->mu > 120) continue; /* the sonic tail: Taylor too slow there */
            double unc, T = taylor_T(r->mu, p.nu, &unc);
            double w = sqrt(1.0 - (p.c / r->v) * (p.c / r->v));
            double D = (double)r->n * T * r->v * w / p.S - 1.0;
            /* the slope of the residual in v by a Taylor secant */
            double dv = 1e-4 * (r->v - p.c), v1 = r->v + dv;
            double w1 = sqrt(1.0 - (p.c / v1) * (p.c / v1)), unc1;
            double T1 = taylor_T(p.gamma / w1, p.nu, &unc1);
            double slope = ((double)r->n * T1 * v1 * w1 / p.S - 1.0 - D) / dv;
            double err = fabs(D / slope), ratio = err / r->v_err;
            bkf_test_note("gamma %g S %g n %zu mu %.6g: residual %.2g, true %.2g est %.2g ratio %.2g",
                          p.gamma, p.S, r->n, r->mu, D, err / r->v, r->v_err / r->v, ratio);
            CHECK_MSG(fabs(D) <= 1e-4 + unc / T, "n %zu mu %g: residual %.3g with the Taylor T", r->n,
                      r->mu, D);
            CHECK_MSG(err <= 1e-4 * r->v, "n %zu mu %g: v off by %.3g tol", r->n, r->mu,
                      err / (1e-4 * r->v));
            CHECK_MSG(ratio <= 3.0, "n %zu mu %g: v_err flatters by %.3g", r->n, r->mu, ratio);
            worst = fmax(worst, ratio);
            checked++;
        }
        bkf_speeds_table_free(&t);
    }
    bkf_test_note("%zu rows checked, worst true/estimated %.3g", checked, worst);
    CHECK(checked >= 12);
}

/* Near the sonic limit T nears k mu and the level's D = ln T - s - ell
 * curves across a cell: the secant to the cell's far end, which v_err
 * divided by, was 65 times steeper than D at the root (mu 1409, gamma 1,
 * c 1, nu -0.5: -0.026 against -3.9e-4) and v_err flattered by 6.3 (3.2 at
 * gamma 1, c 0.3, nu 0.5, n 37, tol 1e-4).  Each row against the
 * independent root in v (T at tol 1e-12, Brent), within its v_err. */
TEST(speeds_v_err_honest_near_the_sonic_limit)
{
    const struct {
        bkf_model_params p;
        size_t n;
        double tol, width;
    } cases[] = {{{1.0, 1.0, -0.5, 1e4, 0, BKF_MODEL_CONTINUUM}, 5576, 1e-8, 1e-10},
                 {{1.0, 0.3, 0.5, 20.0, 0, BKF_MODEL_CONTINUUM}, 37, 1e-4, 1e-6},
                 {{0.1, 0.3, -0.5, 20.0, 0, BKF_MODEL_CONTINUUM}, 371, 1e-8, 1e-11}};
    double worst = 0.0;
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        bkf_speeds_table t = find(cases[i].p, cases[i].tol, cases[i].n, cases[i].n);
        CHECK(t.count >= 1);
        for (size_t j = 0; j < t.count; j++) {
            const bkf_speeds_root *r = &t.roots[j];
            double ref = reference_v(cases[i].p, (double)r->n, r->v, cases[i].width);
            double ratio = fabs(r->v - ref) / r->v_err;
            CHECK_MSG(ratio <= 1.0, "gamma %g c %g nu %g n %zu: v %.17g reference %.17g, v_err %.3g", cases[i].p.gamma,
                      cases[i].p.c, cases[i].p.nu, r->n, r->v, ref, r->v_err);
            CHECK_MSG(r->v_err <= cases[i].tol * r->v, "n %zu: v_err %.3g above tol", r->n, r->v_err / r->v);
            worst = fmax(worst, ratio);
        }
        bkf_speeds_table_free(&t);
    }
    bkf_test_note("worst true/estimated %.3g", worst);
}

/* ln T(mu(s)) - s - ell, s = ln sqrt(mu^2 - gamma^2), with T from the
 * long-double Taylor reference; the cycle solve only gives its secant a
 * starting slope (the fixed point does not depend on it). */
static double taylor_D(const bkf_model_params *p, double ell, double s, double *unc)
{
    double mu = hypot(p->gamma, exp(s)), g = 1.0;
    bkf_cycle_options o = bkf_cycle_options_default();
    o.tol = 1e-6;
    o.warm_start = 0;
    bkf_cycle_result r;
    bkf_error e;
    if (bkf_cycle_period(mu, p->nu, &o, &r, &e) == BKF_OK) g = r.section_slope;
    double T = taylor_period(mu, p->nu, g, unc);
    *unc /= T;
    return log(T) - s - ell;
}

/* canard9999: inside the canard explosion at nu 0.9999 (mu 35.1-35.37) v_err
 * flattered because T's estimate did (bd2x2, cycle.c solve_shooting_stepper):
 * against the root of the condition with T from the Taylor reference
 * (Newton in s to convergence, the reference's own uncertainty carried
 * into v), n 61 at tol 1e-8 was 6.7 times v_err off, n 67 at tol 1e-6 7.9
 * times (T 51 and 11 times its estimate).  Since each root's solves start
 * cold (a root independent of the rows asked), the roots at mu 35.36-35.37
 * are had to 1e-7, not 1e-8: at 1e-8 they are refused rows naming why
 * (speeds_tight_tol_refuses_instead_of_dropping_roots has the rule). */
TEST(speeds_v_err_honest_inside_the_canard_at_nu_0_9999)
{
    const struct {
        size_t n_from, n_to;
        double tol;
    } cases[] = {{58, 64, 1e-7}, {64, 68, 1e-6}};
    bkf_model_params p = {1.0, 1.0, 0.9999, 20.0, 0, BKF_MODEL_CONTINUUM};
    double worst = 0.0;
    size_t rows = 0;
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        bkf_speeds_table t = find(p, cases[i].tol, cases[i].n_from, cases[i].n_to);
        for (size_t j = 0; j < t.count; j++) {
            const bkf_speeds_root *r = &t.roots[j];
            double ell = log(p.S / (p.c * p.gamma)) - log((double)r->n);
            double s = 0.5 * log(r->mu * r->mu - p.gamma * p.gamma), unc, up, um, h = 1e-6;
            double slope = (taylor_D(&p, ell, s + h, &up) - taylor_D(&p, ell, s - h, &um)) / (2.0 * h);
            for (int it = 0; it < 3; it++) s -= taylor_D(&p, ell, s, &unc) / slope;
            double D = taylor_D(&p, ell, s, &unc), g2 = p.gamma * p.gamma / (r->mu * r->mu);
            double v_ref = p.c * hypot(1.0, p.gamma * exp(-s));
            double v_unc = v_ref * (g2 * (unc + fabs(D)) / fabs(slope) + 4.0 * DBL_EPSILON);
            double ratio = fmax(fabs(r->v - v_ref) - v_unc, 0.0) / r->v_err;
            CHECK_MSG(ratio <= 1.0, "tol %g n %zu mu %.10g: v %.17g reference %.17g +- %.2g, v_err %.3g", cases[i].tol,
                      r->n, r->mu, r->v, v_ref, v_unc, r->v_err);
            CHECK_MSG(v_unc <= 0.1 * r->v_err, "n %zu: reference uncertain by %.2g", r->n, v_unc / v_ref);
            worst = fmax(worst, ratio);
            rows++;
        }
        bkf_speeds_table_free(&t);
    }
    CHECK(rows >= 10);
    bkf_test_note("%zu rows, worst true/estimated %.3g", rows, worst);
}

/* Issue 36: a root does not depend on which other rows were asked for (the
 * grid, its precise samples and each root's cold start are the whole
 * table's): speeds --n 4 gave 0.48545916040133913, the table
 * 0.48545916040196629. */
TEST(speeds_root_independent_of_the_rows_asked)
{
    bkf_speeds_table all = find(paper, 1e-10, 1, 0);
    CHECK(all.count == 12);
    const size_t ns[] = {1, 4, 7, 12};
    for (size_t k = 0; k < sizeof ns / sizeof ns[0]; k++) {
        bkf_speeds_table one = find(paper, 1e-10, ns[k], ns[k]);
        CHECK(one.count == 1);
        if (one.count == 1 && all.count == 12)
            CHECK_MSG(one.roots[0].v == all.roots[ns[k] - 1].v, "n %zu: %.17g alone, %.17g in the table", ns[k],
                      one.roots[0].v, all.roots[ns[k] - 1].v);
        bkf_speeds_table_free(&one);
    }
    bkf_speeds_table part = find(paper, 1e-10, 3, 6);
    for (size_t i = 0; i < part.count && all.count == 12; i++) CHECK(part.roots[i].v == all.roots[i + 2].v);
    bkf_speeds_table_free(&part);
    bkf_speeds_table_free(&all);
}

/* A refused row: it says why and where, and gives no number for v. */
static void check_refused_row(const bkf_model_params *p, const bkf_speeds_root *r, double tol)
{
    CHECK_MSG(r->status == BKF_ETOL && (r->flags & BKF_SPEEDS_REFUSED), "n %zu: status %d flags %u",
              r->n, r->status, r->flags);
    CHECK_MSG(strstr(r->refusal, "cannot be polished to tol") && strstr(r->refusal, "near mu = "),
              "n %zu: refusal '%s'", r->n, r->refusal);
    CHECK_MSG(r->tol_met > tol && r->tol_met <= 1e4 * tol, "n %zu: tol met %g at tol %g", r->n,
              r->tol_met, tol);
    CHECK(isnan(r->v) && isnan(r->mu) && isnan(r->T) && isnan(r->v_err) && isnan(r->residual));
    CHECK(r->model == NULL && r->wavelength == p->S / (double)r->n);
    bkf_error e = {0};
    CHECK(bkf_speeds_root_status(r, &e) == BKF_ETOL && strstr(e.message, "n = "));
}

/* Issue 31, defect 6, then R1 of the independent audit: a root bracketed
 * but not polished to tol is a refused row naming its reason, never left
 * out of the table (at tol 1e-13 the paper's n = 1 was dropped, exit 0),
 * and never refusing the table whole (then every other row was lost).  The
 * paper's table has one root for each n <= 12; the rows that stand agree
 * with those of tol 1e-10 within both errors. */
TEST(speeds_tight_tol_refuses_instead_of_dropping_roots)
{
    bkf_speeds_table ref = find(paper, 1e-10, 1, 0);
    CHECK(ref.count == 12 && ref.refused == 0);
    size_t refused = 0;
    for (double tol = 1e-12; tol >= 1e-14; tol *= 0.1) {
        bkf_speeds_table t = find(paper, tol, 1, 0);
        CHECK_MSG(t.count == 12, "tol %g: %zu of the 12 rows", tol, t.count);
        size_t here = 0;
        for (size_t i = 0; i < t.count && t.count == 12; i++) {
            const bkf_speeds_root *r = &t.roots[i];
            CHECK(r->n == i + 1);
            if (r->status != BKF_OK) {
                check_refused_row(&paper, r, tol);
                here++;
                continue;
            }
            CHECK_MSG(fabs(r->v - ref.roots[i].v) <= r->v_err + ref.roots[i].v_err,
                      "tol %g, n %zu: %.17g vs %.17g", tol, r->n, r->v, ref.roots[i].v);
        }
        CHECK(t.refused == here);
        bkf_test_note("tol %g: %zu of 12 rows refused%s%s", tol, here, here ? "; " : "", t.note);
        refused += here;
        bkf_speeds_table_free(&t);
    }
    CHECK(refused > 0); /* the refusal is exercised */
    bkf_speeds_table_free(&ref);
}

/* R1 of the independent audit of issue 31: at gamma 0.567489, c 0.432606,
 * nu 0.989398, S 59.5575 one root next to the canard (mu 3.5528) is had to
 * 1e-9 but not to the tol 1e-10 asked, and the table was refused whole for
 * it, losing over a hundred good roots.  It is a refused row; the others
 * stand: one root for each n <= 45 (far from the canard), checked against
 * an independent root of the condition in v. */
TEST(speeds_one_refused_root_keeps_the_others)
{
    const bkf_model_params p = {0.567489, 0.432606, 0.989398, 59.5575, 0, BKF_MODEL_CONTINUUM};
    bkf_speeds_table t = find(p, 1e-10, 1, 0);
    size_t refused = 0, first_n[46] = {0};
    for (size_t i = 0; i < t.count; i++) {
        const bkf_speeds_root *r = &t.roots[i];
        if (r->status != BKF_OK) {
            check_refused_row(&p, r, 1e-10);
            refused++;
        } else if (r->n <= 45) {
            CHECK_MSG(first_n[r->n]++ == 0, "n %zu has two roots", r->n);
        }
    }
    CHECK_MSG(refused >= 1 && refused == t.refused && t.count >= 100 + refused,
              "%zu rows, %zu refused", t.count, refused);
    for (size_t n = 1; n <= 45; n++) CHECK_MSG(first_n[n] == 1, "n %zu: no row", n);
    const size_t ns[] = {1, 15, 30, 45};
    for (size_t k = 0; k < sizeof ns / sizeof ns[0] && t.count > 45; k++) {
        const bkf_speeds_root *r = &t.roots[ns[k] - 1];
        double v = reference_v(p, (double)r->n, r->v, 1e-6);
        CHECK_MSG(fabs(r->v - v) <= r->v_err + 1e-13 * v, "n %zu: %.17g vs %.17g, v_err %.3g",
                  r->n, r->v, v, r->v_err);
    }
    bkf_test_note("%zu rows, %zu refused: %s", t.count, refused, t.note);
    bkf_speeds_table_free(&t);
}

/* A root followed by the secant from a nearby speed (bkf_speeds_near, no
 * bracketing grid) is the bracketed table's root nearest that speed, on
 * random sets of the documented domain (gamma 0.3-8, c 0.05-1.5,
 * nu -0.99..0.99, S 5-60): every root of n = 1..3, started 2% off after S
 * moved 2%, agrees with bkf_speeds_find's at the new S to within both v_err
 * and 1e-9 v; a guess between no roots (v_guess far above the fastest) is
 * BKF_ENUMERIC, and c = 0 or v_guess <= c bad input. */
TEST(speeds_near_is_the_tables_nearest_root)
{
    unsigned long long x = 20261129;
    size_t checked = 0;
    for (int k = 0; k < 6; k++) {
        double u[4];
        for (int i = 0; i < 4; i++) {
            x = x * 6364136223846793005ULL + 1442695040888963407ULL;
            u[i] = (double)(x >> 11) / 9007199254740992.0;
        }
        bkf_model_params p = paper;
        p.gamma = 0.3 + 7.7 * u[0];
        p.c = 0.05 + 1.45 * u[1];
        p.nu = -0.99 + 1.98 * u[2];
        p.S = 5 + 55 * u[3];
        for (size_t n = 1; n <= 3; n++) {
            bkf_speeds_table t = find(p, 1e-10, n, n), t2;
            bkf_model_params q = p;
            q.S = 1.02 * p.S;
            t2 = find(q, 1e-10, n, n);
            for (size_t i = 0; i < t.count && t2.count; i++) {
                if (t.roots[i].status != BKF_OK) continue;
                double guess = 1.02 * t.roots[i].v;
                size_t best = 0;
                bkf_error e;
                if (bkf_speeds_nearest(&t2, guess, &best, &e) != BKF_OK) continue;
                const bkf_speeds_root *want = &t2.roots[best];
                bkf_speeds_root r;
                int rc = bkf_speeds_near(&q, n, guess, NULL, &r, &e);
                /* a root whose neighbour is closer than the step (a fold
                 * near) may go either way or none: not compared */
                int alone = 1;
                for (size_t j = 0; j < t2.count; j++)
                    if (j != best && fabs(t2.roots[j].v - want->v) < 0.1 * want->v) alone = 0;
                if (!alone) continue;
                CHECK_MSG(rc == BKF_OK, "gamma %g c %g nu %g S %g n %zu: %s", q.gamma, q.c, q.nu,
                          q.S, n, e.message);
                if (rc) continue;
                CHECK_MSG(fabs(r.v - want->v) <= r.v_err + want->v_err + 1e-9 * want->v,
                          "gamma %g c %g nu %g S %g n %zu: near %.15g, table %.15g", q.gamma, q.c,
                          q.nu, q.S, n, r.v, want->v);
                CHECK(r.n == n && fabs(r.mu - want->mu) <= 1e-6 * want->mu);
                checked++;
            }
            bkf_speeds_table_free(&t);
            bkf_speeds_table_free(&t2);
        }
    }
    bkf_test_note("%zu roots compared", checked);
    CHECK(checked >= 6);
    bkf_error e;
    bkf_speeds_root r;
    bkf_model_params q = paper;
    CHECK_STATUS(bkf_speeds_near(&q, 4, 1000 * q.c, NULL, &r, &e), BKF_ENUMERIC);
    CHECK_STATUS(bkf_speeds_near(&q, 4, 0.5 * q.c, NULL, &r, &e), BKF_EINPUT);
    q.c = 0;
    CHECK_STATUS(bkf_speeds_near(&q, 4, 1, NULL, &r, &e), BKF_EINPUT);
}

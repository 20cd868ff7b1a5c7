/* The error bounds of the asymptotic formulas (bkf_asym_error_bound) against
 * the numerical period over the box, and the model choice of
 * bkf_cycle_estimate: formulas integrate nothing. */
#include "harness.h"

#include <string.h>

#include "bkfront/asymptotics.h"
#include "bkfront/cycle.h"

/* Every formula, wherever its bound is below 0.1, is within the bound of a
 * shooting T solved to 1e-10 (1e-8 where that is refused); the tightest
 * ratio true/bound is reported. */
TEST(asym_error_bounds_hold_over_the_box)
{
    const double nus[] = {0, 0.5, -0.9, 0.96, -0.99, 0.995, -0.999, 0.9995, 0.9999};
    const char *names[] = {"leading", "large", "small"};
    double worst[3] = {0, 0, 0}, where_mu[3] = {0}, where_nu[3] = {0};
    size_t used[3] = {0};
    bkf_cycle *c = bkf_cycle_alloc();
    for (size_t j = 0; j < sizeof nus / sizeof nus[0]; j++)
        for (int i = 0; i <= 28; i++) {
            double mu = pow(10.0, -3.0 + i / 4.0);
            double b[3];
            int any = 0;
            for (int f = 0; f < 3; f++) {
                b[f] = bkf_asym_error_bound((bkf_asym_formula)f, mu, nus[j]);
                any |= b[f] < 0.1;
            }
            if (!any) continue;
            bkf_cycle_options o = bkf_cycle_options_default();
            o.tol = 1e-10;
            o.warm_start = 0;
            bkf_error e;
            int rc = bkf_cycle_solve(c, mu, nus[j], &o, &e);
            if (rc) {
                o.tol = 1e-8;
                rc = bkf_cycle_solve(c, mu, nus[j], &o, &e);
            }
            CHECK_MSG(rc == BKF_OK, "mu %g nu %g: %s", mu, nus[j], e.message);
            const bkf_cycle_result *r = bkf_cycle_get(c);
            for (int f = 0; f < 3; f++) {
                if (!(b[f] < 0.1)) continue;
                double Tf = bkf_asym_period((bkf_asym_formula)f, mu, nus[j]);
                double err = fabs(Tf - r->period) / r->period;
                double err_max = fmax(err - r->period_err / r->period, 0.0);
                /* the reference's own error estimate is added: at tiny mu
                 * the formula is better than T at 1e-10 */
                CHECK_MSG(err <= b[f] + r->period_err / r->period, "%s at mu %g nu %g: error %.3g > bound %.3g", names[f], mu,
                          nus[j], err, b[f]);
                used[f]++;
                if (err_max / b[f] > worst[f]) {
                    worst[f] = err_max / b[f];
                    where_mu[f] = mu;
                    where_nu[f] = nus[j];
                }
            }
        }
    bkf_cycle_free(c);
    for (int f = 0; f < 3; f++) {
        CHECK(used[f] > 5);
        bkf_test_note("%s: %zu points, largest error/bound %.2f at mu %g, nu %g", names[f], used[f],
                      worst[f], where_mu[f], where_nu[f]);
    }
}

/* The goal: at tol 1e-2 and mu >= 100 auto integrates nothing (and
 * needs no cycle object at all), for |nu| <= 0.98. */
TEST(asym_auto_at_loose_tol_integrates_nothing)
{
    const double nus[] = {0, 0.5, -0.5, 0.9, -0.9, 0.96, -0.96, 0.98, -0.98};
    const double mus[] = {100, 150, 300, 1e3, 3e3, 1e4, 1e5, 1e6};
    for (size_t j = 0; j < sizeof nus / sizeof nus[0]; j++)
        for (size_t i = 0; i < sizeof mus / sizeof mus[0]; i++) {
            bkf_cycle_options o = bkf_cycle_options_default();
            o.tol = 1e-2;
            bkf_cycle_result r;
            bkf_error e;
            int rc = bkf_cycle_estimate(NULL, mus[i], nus[j], &o, BKF_METHOD_AUTO, &r, &e);
            CHECK_MSG(rc == BKF_OK, "mu %g nu %g: %s", mus[i], nus[j], e.message);
            CHECK(r.steps == 0 && r.rhs_calls == 0 && r.jacobian_calls == 0 &&
                  r.newton_iterations == 0);
            CHECK(strcmp(r.model, "shooting") != 0 && strcmp(r.stepper, "none") == 0);
            CHECK(r.period_err <= 1e-2 * r.period);
        }
}

/* A formula asked for where its bound does not meet tol fails; shooting
 * through bkf_cycle_estimate is bkf_cycle_solve (T(1, 0) published). */
TEST(asym_forced_formula_refuses_outside_its_bound)
{
    bkf_cycle_options o = bkf_cycle_options_default();
    bkf_cycle_result r;
    bkf_error e;
    o.tol = 1e-6;
    CHECK_STATUS(bkf_cycle_estimate(NULL, 1e4, 0, &o, BKF_METHOD_LEADING, &r, &e), BKF_ETOL);
    CHECK(strstr(e.message, "bound"));
    CHECK_STATUS(bkf_cycle_estimate(NULL, 30, 0.999, &o, BKF_METHOD_ASYMPTOTIC, &r, &e),
                 BKF_ETOL);
    CHECK_STATUS(bkf_cycle_estimate(NULL, 1, 0, &o, BKF_METHOD_AUTO, &r, &e), BKF_EINPUT);
    bkf_cycle *c = bkf_cycle_alloc();
    o.tol = 1e-10;
    CHECK_STATUS(bkf_cycle_estimate(c, 1, 0, &o, BKF_METHOD_AUTO, &r, &e), BKF_OK);
    /* (the automatic choice at mu 1 is collocation, which calls no
     * right-hand side: the work shows as Newton iterations) */
    CHECK(strcmp(r.model, "shooting") == 0 && r.newton_iterations > 0 && r.steps > 0);
    CHECK_CLOSE(r.period, 6.663286859323130, 1e-10, 0);
    bkf_cycle_free(c);
}

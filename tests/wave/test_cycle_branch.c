/* The cycle branch by pseudo-arclength continuation against independent
 * cold solves at the same parameters. */
#include "harness.h"

#include "bkfront/cycle.h"

typedef struct {
    double param[512];
    double period[512];
    double err[512];
    size_t n;
    bkf_cycle_param along;
} collected;

static int collect(const bkf_cycle_result *r, void *data)
{
    collected *c = data;
    if (c->n < 512) {
        c->param[c->n] = c->along == BKF_CYCLE_ALONG_MU ? r->mu : r->nu;
        c->period[c->n] = r->period;
        c->err[c->n] = r->period_err;
        c->n++;
    }
    return 0;
}

static void check_branch(bkf_cycle_param along, double from, double to, double fixed)
{
    collected got = {.along = along};
    bkf_cycle_options o = bkf_cycle_options_default();
    bkf_error e;
    int rc = bkf_cycle_branch(along, from, to, fixed, &o, 0, collect, &got, &e);
    CHECK_MSG(rc == BKF_OK, "%s", e.message);
    CHECK(got.n >= 5);
    CHECK_CLOSE(got.param[0], from, 1e-12, 1e-12);
    CHECK_CLOSE(got.param[got.n - 1], to, 1e-12, 1e-12);
    for (size_t i = 0; i < got.n; i++) {
        if (i) CHECK((to > from) == (got.param[i] > got.param[i - 1]));
        double mu = along == BKF_CYCLE_ALONG_MU ? got.param[i] : fixed;
        double nu = along == BKF_CYCLE_ALONG_MU ? fixed : got.param[i];
        bkf_cycle_result cold;
        CHECK_STATUS(bkf_cycle_period(mu, nu, &o, &cold, &e), BKF_OK);
        CHECK_CLOSE(got.period[i], cold.period, 2e-10, 0.0);
        CHECK(got.err[i] <= 1e-10 * got.period[i]);
    }
    bkf_test_note("%zu points from %g to %g", got.n, from, to);
}

TEST(cycle_branch_along_mu_matches_cold_solves)
{
    check_branch(BKF_CYCLE_ALONG_MU, 0.1, 200.0, -0.96);
}

TEST(cycle_branch_along_nu_matches_cold_solves)
{
    check_branch(BKF_CYCLE_ALONG_NU, 0.95, -0.95, 2.0);
}

TEST(cycle_branch_rejects_bad_input)
{
    collected got = {0};
    bkf_error e;
    CHECK_STATUS(bkf_cycle_branch(BKF_CYCLE_ALONG_MU, 1.0, -2.0, 0.0, NULL, 0, collect, &got, &e), BKF_EINPUT);
    CHECK_STATUS(bkf_cycle_branch(BKF_CYCLE_ALONG_NU, 0.0, 1.5, 1.0, NULL, 0, collect, &got, &e), BKF_EINPUT);
    CHECK_STATUS(bkf_cycle_branch(BKF_CYCLE_ALONG_MU, 1.0, 2.0, 0.0, NULL, 0, NULL, &got, &e), BKF_EINPUT);
}

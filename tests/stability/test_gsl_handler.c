/* The library leaves the host program's GSL error handler as it found it
 * (status.h): a handler installed before a call is installed after it, on
 * success, on failure and on refused input; during the call, callbacks
 * included, GSL's handler is off, so a GSL error inside the library reaches
 * neither the host's handler nor GSL's abort. */
#define _POSIX_C_SOURCE 200809L
#include "harness.h"

#include <gsl/gsl_errno.h>
#include <pthread.h>
#include <sched.h>

#include "bkfront/asymfit.h"
#include "bkfront/continuation.h"
#include "bkfront/cycle.h"
#include "bkfront/floquet.h"
#include "bkfront/comoving.h"
#include "bkfront/pde.h"
#include "bkfront/seed.h"
#include "bkfront/speeds.h"

static int host_calls;

static void host_handler(const char *reason, const char *file, int line, int gsl_errno)
{
    (void)reason, (void)file, (void)line, (void)gsl_errno;
    host_calls++;
}

/* The installed handler, left installed. */
static gsl_error_handler_t *current_handler(void)
{
    gsl_error_handler_t *h = gsl_set_error_handler(NULL);
    gsl_set_error_handler(h);
    return h;
}

#define CHECK_HOST_HANDLER(what)                                                             \
    CHECK_MSG(current_handler() == host_handler, "%s: the host's GSL handler was replaced", \
              what)

static int seen_inside, visits;

static int visit_point(const bkf_cycle_result *point, void *data)
{
    (void)point, (void)data;
    visits++;
    if (current_handler() == host_handler) seen_inside++;
    return visits >= 3; /* three points are enough */
}

static int line_residual(const double *u, double *g, double *jac, void *data, bkf_error *err)
{
    (void)data, (void)err;
    if (current_handler() == host_handler) seen_inside++;
    g[0] = u[0] - 2.0 * u[1];
    if (jac) jac[0] = 1.0, jac[1] = -2.0;
    return BKF_OK;
}

static int accept_point(const double *u, const double *t, int is_fold, void *data)
{
    (void)u, (void)t, (void)is_fold;
    return ++*(int *)data >= 3;
}

TEST(gsl_handler_of_the_host_survives_library_calls)
{
    gsl_set_error_handler(host_handler);
    bkf_error e = {0};
    bkf_cycle_result r;

    CHECK_STATUS(bkf_cycle_period(1.0, 0.0, NULL, &r, &e), BKF_OK);
    CHECK_HOST_HANDLER("bkf_cycle_period");
    CHECK_CLOSE(r.period, 6.6632868593231301, 1e-9, 0); /* van der Pol, mu = 1 */

    CHECK_STATUS(bkf_cycle_period(-1.0, 0.0, NULL, &r, &e), BKF_EINPUT);
    CHECK_HOST_HANDLER("bkf_cycle_period, refused input");

    bkf_cycle_options tight = bkf_cycle_options_default();
    CHECK_STATUS(bkf_cycle_estimate(NULL, 1e4, 0.0, &tight, BKF_METHOD_LEADING, &r, &e), BKF_ETOL);
    CHECK_HOST_HANDLER("bkf_cycle_estimate, refused tolerance");

    seen_inside = visits = 0;
    CHECK_STATUS(bkf_cycle_branch(BKF_CYCLE_ALONG_MU, 1.0, 2.0, 0.0, NULL, 10, visit_point, NULL,
                                  &e),
                 BKF_OK);
    CHECK_HOST_HANDLER("bkf_cycle_branch");
    CHECK(visits == 3);
    CHECK_MSG(seen_inside == 0, "the host's handler was installed during %d callbacks",
              seen_inside);

    int accepted = 0;
    seen_inside = 0;
    bkf_cont_options co = bkf_cont_options_default(1);
    double u0[2] = {0.0, 0.0};
    CHECK_STATUS(bkf_cont_run(line_residual, accept_point, &accepted, u0, 1, +1, &co, NULL, &e),
                 BKF_OK);
    CHECK_HOST_HANDLER("bkf_cont_run");
    CHECK(accepted == 3 && seen_inside == 0);

    bkf_model_params p = bkf_model_params_paper();
    p.c = 0.0; /* the closed-form table: one cycle solve */
    bkf_speeds_table t;
    CHECK_STATUS(bkf_speeds_find(&p, NULL, &t, &e), BKF_OK);
    bkf_speeds_table_free(&t);
    CHECK_HOST_HANDLER("bkf_speeds_find");

    bkf_floquet *f = bkf_floquet_alloc();
    CHECK(f);
    CHECK_STATUS(bkf_floquet_set(f, 2.0, 0.3, 0.0, NULL, &e), BKF_OK);
    CHECK_HOST_HANDLER("bkf_floquet_set");
    bkf_floquet_point pt;
    CHECK_STATUS(bkf_floquet_eval(f, 0.5, &pt, &e), BKF_OK);
    CHECK_HOST_HANDLER("bkf_floquet_eval");
    bkf_floquet_free(f);

    /* the fit's own model, R = A mu^p + B ln(mu)/mu + D/mu: a GSL fit */
    double mu[12], R[12];
    for (int i = 0; i < 12; i++) {
        mu[i] = pow(10.0, 1.0 + 3.0 * i / 11.0);
        R[i] = 4.2 * pow(mu[i], -0.29) - 1.3 * log(mu[i]) / mu[i] + 0.7 / mu[i];
    }
    bkf_asymfit_large_result fit;
    CHECK_STATUS(bkf_asymfit_correction(mu, R, 12, -0.9, -0.05, &fit, &e), BKF_OK);
    CHECK_CLOSE(fit.p, -0.29, 0, 1e-6);
    CHECK_HOST_HANDLER("bkf_asymfit_correction");

    CHECK_MSG(host_calls == 0, "the host's handler was called %d times", host_calls);
    gsl_set_error_handler(NULL);
}

TEST(gsl_handler_push_pop_nest)
{
    /* push turns it off and hands back what was there; pop restores it, so
     * nested pairs (a public function calling another) end where they began */
    gsl_set_error_handler(host_handler);
    bkf_gsl_handler *outer = bkf_gsl_handler_push();
    CHECK(outer == host_handler);
    CHECK(current_handler() != host_handler && current_handler() != NULL);
    bkf_gsl_handler *inner = bkf_gsl_handler_push();
    CHECK(inner == current_handler());
    gsl_error("an error while off", __FILE__, __LINE__, GSL_EINVAL);
    bkf_gsl_handler_pop(inner);
    CHECK(current_handler() != host_handler);
    bkf_gsl_handler_pop(outer);
    CHECK_HOST_HANDLER("push, push, pop, pop");
    CHECK(host_calls == 0);
    gsl_error("an error with the host's handler back", __FILE__, __LINE__, GSL_EINVAL);
    CHECK(host_calls == 1);
    gsl_set_error_handler(NULL);
}

TEST(gsl_handler_of_the_host_survives_simulations)
{
    gsl_set_error_handler(host_handler);
    bkf_error e;
    bkf_model_params m = bkf_model_params_paper();
    m.N = 64;
    bkf_pde_options o = bkf_pde_options_default();
    bkf_pde *pde = bkf_pde_alloc(&m, &o, &e);
    CHECK(pde != NULL);
    CHECK_HOST_HANDLER("bkf_pde_alloc");
    CHECK_STATUS(bkf_pde_init_uniform(pde, 1e-3, 1, &e), BKF_OK);
    CHECK_HOST_HANDLER("bkf_pde_init_uniform");
    CHECK_STATUS(bkf_pde_run(pde, 1.0, 0.5, NULL, NULL, NULL, NULL, &e), BKF_OK);
    CHECK_HOST_HANDLER("bkf_pde_run");
    bkf_pde_front_spec fs = bkf_pde_front_spec_default();
    fs.n = 4;
    bkf_pde_front_info fi;
    CHECK_STATUS(bkf_seed_front(pde, &fs, &fi, NULL, &e), BKF_OK);
    CHECK_HOST_HANDLER("bkf_seed_front");
    bkf_pde_free(pde);
    bkf_comoving_params cp = bkf_comoving_params_default();
    cp.model = bkf_model_params_paper();
    cp.n = 4;
    cp.v = fi.v;
    cp.points = 64;
    bkf_comoving *cm = bkf_comoving_alloc(&cp, &e);
    CHECK_MSG(cm != NULL, "%s", e.message);
    CHECK_HOST_HANDLER("bkf_comoving_alloc");
    CHECK_STATUS(bkf_comoving_run(cm, 0.5, 0.25, NULL, NULL, &e), BKF_OK);
    CHECK_HOST_HANDLER("bkf_comoving_run");
    bkf_comoving_free(cm);
    CHECK_MSG(host_calls == 0, "the host's handler was called %d times", host_calls);
    gsl_set_error_handler(NULL);
}

/* Pairs in two threads at once: while either is inside, the handler is
 * off (never the host's, never GSL's abort), and after both, the host's. */
static _Atomic int handler_violations;
static pthread_barrier_t handler_start;

static void *push_pop_many(void *arg)
{
    (void)arg;
    pthread_barrier_wait(&handler_start);
    for (int i = 0; i < 20000 && handler_violations < 10; i++) {
        bkf_gsl_handler *h = bkf_gsl_handler_push();
        sched_yield(); /* let the other thread in, also on one core */
        gsl_error_handler_t *now = gsl_set_error_handler_off();
        gsl_set_error_handler(now);
        if (now == host_handler || now == NULL) handler_violations++;
        bkf_gsl_handler_pop(h);
    }
    return NULL;
}

TEST(gsl_handler_pairs_in_two_threads)
{
    gsl_set_error_handler(host_handler);
    pthread_t a, b;
    pthread_barrier_init(&handler_start, NULL, 2);
    CHECK(pthread_create(&a, NULL, push_pop_many, NULL) == 0);
    CHECK(pthread_create(&b, NULL, push_pop_many, NULL) == 0);
    pthread_join(a, NULL);
    pthread_join(b, NULL);
    pthread_barrier_destroy(&handler_start);
    CHECK_MSG(handler_violations == 0, "the handler was on inside a pair %d times",
              (int)handler_violations);
    CHECK_HOST_HANDLER("pairs in two threads");
    gsl_set_error_handler(NULL);
}

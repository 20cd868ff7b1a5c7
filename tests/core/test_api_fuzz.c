/* The public library API driven with hostile arguments: NaN, infinities,
 * negative, zero, tiny and huge values, out-of-range enums and sizes, NULL
 * pointers.  Every status-returning call must refuse them with BKF_EINPUT
 * and a one-line message (never crash, never BKF_OK with a non-finite
 * result); functions returning a double give NaN outside their domain.
 * Each TEST runs in its own process, so a crash fails that test only; under
 * `make sanitize` and `make valgrind` an invalid access fails it too.
 *
 * The bad values are checked one argument at a time, everything else valid,
 * so a refusal is the refusal of that argument. */
#define _POSIX_C_SOURCE 200809L
#include "harness.h"

#include <float.h>
#include <string.h>

#include "bkfront/asymfit.h"
#include "bkfront/asymptotics.h"
#include "bkfront/comoving.h"
#include "bkfront/continuation.h"
#include "bkfront/cycle.h"
#include "bkfront/floquet.h"
#include "bkfront/io.h"
#include "bkfront/measure.h"
#include "bkfront/model.h"
#include "bkfront/pde.h"
#include "bkfront/seed.h"
#include "bkfront/speeds.h"

/* Not a valid value for any parameter below. */
static const double hostile[] = {NAN, INFINITY, -INFINITY, -DBL_MAX, DBL_MAX, 1e300, -1e300};
#define NHOSTILE (sizeof hostile / sizeof hostile[0])

/* BKF_EINPUT with a non-empty one-line message; also with err NULL. */
#define CHECK_EINPUT(call_with_err)                                                    \
    do {                                                                               \
        bkf_error e_;                                                                  \
        memset(&e_, 0, sizeof e_);                                                     \
        bkf_error *err = &e_;                                                          \
        int s_ = (call_with_err);                                                      \
        CHECK_MSG(s_ == BKF_EINPUT, "%s returned %d, want BKF_EINPUT", #call_with_err,  \
                  s_);                                                                 \
        CHECK_MSG(e_.message[0] && !strchr(e_.message, '\n'), "%s: message '%s'",      \
                  #call_with_err, e_.message);                                         \
        err = NULL;                                                                    \
        CHECK((call_with_err) == BKF_EINPUT);                                          \
    } while (0)

/* NULL with the message filled, for the constructors. */
#define CHECK_NULL_EINPUT(call_with_err)                                               \
    do {                                                                               \
        bkf_error e_;                                                                  \
        memset(&e_, 0, sizeof e_);                                                     \
        bkf_error *err = &e_;                                                          \
        void *p_ = (void *)(call_with_err);                                            \
        CHECK_MSG(p_ == NULL, "%s did not refuse", #call_with_err);                    \
        CHECK_MSG(e_.message[0] && !strchr(e_.message, '\n'), "%s: message '%s'",      \
                  #call_with_err, e_.message);                                         \
        err = NULL;                                                                    \
        CHECK((call_with_err) == NULL);                                                \
    } while (0)

TEST(api_fuzz_model_validators)
{
    for (size_t i = 0; i < NHOSTILE; i++) {
        double x = hostile[i];
        CHECK_EINPUT(bkf_model_check_nu_active(x, err));
        CHECK_EINPUT(bkf_model_check_positive("gamma", x < 0 || isnan(x) ? x : -x, err));
        CHECK_EINPUT(bkf_model_check_tol(x, err));
    }
    CHECK_EINPUT(bkf_model_check_nu_active(1.0, err));
    CHECK_EINPUT(bkf_model_check_nu_active(-1.0, err));
    CHECK_EINPUT(bkf_model_check_positive("S", 0.0, err));
    CHECK_EINPUT(bkf_model_check_positive(NULL, -1.0, err));
    CHECK_EINPUT(bkf_model_check_nonnegative("c", -DBL_MIN, err));
    CHECK_EINPUT(bkf_model_check_nonnegative(NULL, NAN, err));
    CHECK_EINPUT(bkf_model_check_nonnegative("c", INFINITY, err));
    CHECK_EINPUT(bkf_model_check_tol(0.0, err));
    CHECK_EINPUT(bkf_model_check_tol(0.5, err));
}

TEST(api_fuzz_asymptotics_nan_outside_domain)
{
    const double bad_nu[] = {NAN, INFINITY, -INFINITY, 1.0, -1.0, 2.0, -1e300};
    const double bad_mu[] = {NAN, INFINITY, -INFINITY, 0.0, -1.0, -1e300};
    for (size_t i = 0; i < sizeof bad_nu / sizeof bad_nu[0]; i++) {
        double nu = bad_nu[i];
        CHECK_MSG(isnan(bkf_asym_k(nu)), "k(%g) = %g", nu, bkf_asym_k(nu));
        CHECK(isnan(bkf_asym_knee_coefficient(nu)));
        CHECK(isnan(bkf_asym_log_coefficient(nu)));
        CHECK(isnan(bkf_asym_small_coefficient(nu)));
        CHECK(isnan(bkf_asym_period_leading(10, nu)));
        CHECK(isnan(bkf_asym_period_large(10, nu)));
        CHECK(isnan(bkf_asym_period_small(0.1, nu)));
        for (int f = 0; f < BKF_ASYMFIT_NFORMULAS; f++)
            CHECK(isnan(bkf_asymfit_formula_period((bkf_asymfit_formula)f, 10, nu)));
    }
    for (size_t i = 0; i < sizeof bad_mu / sizeof bad_mu[0]; i++) {
        double mu = bad_mu[i];
        CHECK_MSG(isnan(bkf_asym_period_leading(mu, 0)), "leading(%g)", mu);
        CHECK(isnan(bkf_asym_period_large(mu, 0)));
        CHECK(isnan(bkf_asym_period_small(mu, 0)));
    }
    CHECK(isnan(bkf_asymfit_formula_period((bkf_asymfit_formula)7, 10, 0)));
    CHECK(bkf_asymfit_formula_name((bkf_asymfit_formula)-1) == NULL);
    /* inside the domain: finite */
    CHECK(isfinite(bkf_asym_period_large(1e4, 0.999)) && isfinite(bkf_asym_k(-0.999)));
}

TEST(api_fuzz_cycle)
{
    bkf_cycle *c = bkf_cycle_alloc();
    CHECK(c);
    bkf_cycle_options o = bkf_cycle_options_default();
    bkf_cycle_result r;
    double f, fp;
    /* nothing solved yet */
    CHECK(bkf_cycle_get(c) == NULL);
    CHECK(bkf_cycle_profile(c, 0.0, &f, &fp, NULL) != BKF_OK);
    for (size_t i = 0; i < NHOSTILE; i++) {
        double x = hostile[i];
        CHECK_EINPUT(bkf_cycle_solve(c, x, 0.0, &o, err));
        CHECK_EINPUT(bkf_cycle_solve(c, 1.0, x, &o, err));
        CHECK_EINPUT(bkf_cycle_period(x, 0.0, &o, &r, err));
        bkf_cycle_options bo = o;
        bo.tol = x;
        CHECK_EINPUT(bkf_cycle_solve(c, 1.0, 0.0, &bo, err));
    }
    CHECK_EINPUT(bkf_cycle_solve(c, 0.0, 0.0, &o, err));
    CHECK_EINPUT(bkf_cycle_solve(c, -1.0, 0.0, &o, err));
    CHECK_EINPUT(bkf_cycle_solve(c, 1e-300, 0.0, &o, err));
    CHECK_EINPUT(bkf_cycle_solve(c, 1.0, 1.0, &o, err));
    CHECK_EINPUT(bkf_cycle_solve(NULL, 1.0, 0.0, &o, err));
    bkf_cycle_options bs = o;
    bs.stepper = (bkf_stepper_kind)42;
    CHECK_EINPUT(bkf_cycle_solve(c, 1.0, 0.0, &bs, err));
    CHECK_EINPUT(bkf_cycle_period(1.0, 0.0, &o, NULL, err));
    CHECK(bkf_cycle_get(c) == NULL);

    /* a good solve, then bad profile arguments */
    CHECK_STATUS(bkf_cycle_solve(c, 1.0, 0.0, &o, NULL), BKF_OK);
    CHECK(isfinite(bkf_cycle_get(c)->period));
    for (size_t i = 0; i < 3; i++) CHECK_EINPUT(bkf_cycle_profile(c, hostile[i], &f, &fp, err));
    CHECK_EINPUT(bkf_cycle_profile(NULL, 0.0, &f, &fp, err));
    /* huge but finite z: periodic, so still an answer, and a finite one */
    if (bkf_cycle_profile(c, 1e300, &f, &fp, NULL) == BKF_OK) CHECK(isfinite(f) && isfinite(fp));
    bkf_cycle_free(c);
    bkf_cycle_free(NULL);

    for (size_t i = 0; i < NHOSTILE; i++) {
        double x = hostile[i];
        CHECK_EINPUT(bkf_cycle_branch(BKF_CYCLE_ALONG_MU, x, 2.0, 0.0, &o, 10, NULL, NULL, err));
        CHECK_EINPUT(bkf_cycle_branch(BKF_CYCLE_ALONG_MU, 1.0, x, 0.0, &o, 10, NULL, NULL, err));
        CHECK_EINPUT(bkf_cycle_branch(BKF_CYCLE_ALONG_NU, 0.0, 0.5, x, &o, 10, NULL, NULL, err));
    }
    CHECK_EINPUT(bkf_cycle_branch((bkf_cycle_param)9, 1.0, 2.0, 0.0, &o, 10, NULL, NULL, err));
    CHECK_EINPUT(bkf_cycle_branch(BKF_CYCLE_ALONG_NU, -0.5, 1.5, 1.0, &o, 10, NULL, NULL, err));
}

static int visit_any(const void *p, void *d)
{
    (void)p;
    (void)d;
    return 0;
}

TEST(api_fuzz_floquet)
{
    bkf_floquet *f = bkf_floquet_alloc();
    CHECK(f);
    bkf_floquet_point pt;
    double a, ae;
    bkf_floquet_stability st;
    /* nothing set yet */
    CHECK(bkf_floquet_cycle(f) == NULL);
    CHECK(bkf_floquet_eval(f, 1.0, &pt, NULL) != BKF_OK);
    CHECK(bkf_floquet_longwave(f, &a, &ae, NULL) != BKF_OK);
    CHECK(bkf_floquet_stability_at(f, &st, NULL) != BKF_OK);
    bkf_floquet_options o = bkf_floquet_options_default();
    for (size_t i = 0; i < NHOSTILE; i++) {
        double x = hostile[i];
        CHECK_EINPUT(bkf_floquet_set(f, x, 0.3, -0.9, &o, err));
        CHECK_EINPUT(bkf_floquet_set(f, 2.0, x < 0 || isnan(x) ? x : -x, -0.9, &o, err));
        CHECK_EINPUT(bkf_floquet_set(f, 2.0, 0.3, x, &o, err));
        bkf_floquet_options bo = o;
        bo.tol = x;
        CHECK_EINPUT(bkf_floquet_set(f, 2.0, 0.3, -0.9, &bo, err));
        bo = o;
        bo.p_max = x;
        CHECK_EINPUT(bkf_floquet_threshold_find(2.0, 0.3, -0.95, -0.9, &bo, NULL, err));
        bo = o;
        bo.nu_step = x;
        CHECK_EINPUT(bkf_floquet_diagram(2.0, 0.3, -0.95, -0.9, &bo,
                                         (bkf_floquet_interval_visit)visit_any, NULL, err));
        CHECK_EINPUT(bkf_floquet_threshold_find(x, 0.3, -0.95, -0.9, &o, NULL, err));
        CHECK_EINPUT(bkf_floquet_threshold_find(2.0, 0.3, x, -0.9, &o, NULL, err));
        CHECK_EINPUT(bkf_floquet_diagram(2.0, x < 0 || isnan(x) ? x : -x, -0.95, -0.9, &o,
                                         (bkf_floquet_interval_visit)visit_any, NULL, err));
        CHECK_EINPUT(bkf_floquet_threshold_branch(BKF_FLOQUET_ALONG_C, 0.3,
                                                  x < 0 || isnan(x) ? x : -x, 2.0, 0.3, -0.95,
                                                  -0.9, &o, 10,
                                                  (bkf_floquet_threshold_visit)visit_any, NULL,
                                                  err));
        if (isnan(x)) { /* NaN in, NaN out */
            CHECK(isnan(bkf_floquet_slip_rate(x, 0.3, -0.9, 1.0)));
            CHECK(isnan(bkf_floquet_slip_rate(2.0, 0.3, x, 1.0)));
            CHECK(isnan(bkf_floquet_slip_rate(2.0, 0.3, -0.9, x)));
        }
    }
    CHECK_EINPUT(bkf_floquet_set(NULL, 2.0, 0.3, -0.9, &o, err));
    CHECK_EINPUT(bkf_floquet_set(f, 0.0, 0.3, -0.9, &o, err));
    CHECK_EINPUT(bkf_floquet_threshold_find(2.0, 0.3, -0.9, -0.95, &o, NULL, err)); /* lo > hi */
    CHECK_EINPUT(bkf_floquet_threshold_find(2.0, 0.0, -0.95, -0.9, &o, NULL, err)); /* c = 0 */

    CHECK_STATUS(bkf_floquet_set(f, 2.0, 0.3, -0.9, NULL, NULL), BKF_OK);
    for (size_t i = 0; i < NHOSTILE; i++) {
        double x = hostile[i];
        if (x > 0 && isfinite(x)) continue; /* a huge q is a valid (strongly damped) mode */
        CHECK_EINPUT(bkf_floquet_eval(f, x, &pt, err));
    }
    CHECK_EINPUT(bkf_floquet_eval(f, -1.0, &pt, err));
    CHECK_EINPUT(bkf_floquet_eval(f, 1.0, NULL, err));
    CHECK_EINPUT(bkf_floquet_eval(NULL, 1.0, &pt, err));
    CHECK_EINPUT(bkf_floquet_stability_at(f, NULL, err));
    /* valid extremes give finite answers */
    CHECK_STATUS(bkf_floquet_eval(f, 0.0, &pt, NULL), BKF_OK);
    CHECK(isfinite(pt.lambda) && isfinite(pt.lambda_err));
    if (bkf_floquet_eval(f, 1e6, &pt, NULL) == BKF_OK) CHECK(!isnan(pt.lambda));
    bkf_floquet_free(f);
    bkf_floquet_free(NULL);
}

TEST(api_fuzz_speeds)
{
    bkf_model_params good = {2.0, 0.3, -0.96, 20.0, 0, BKF_MODEL_CONTINUUM};
    bkf_speeds_options o = bkf_speeds_options_default();
    bkf_speeds_table t;
    memset(&t, 0, sizeof t);
    for (size_t i = 0; i < NHOSTILE; i++) {
        double x = hostile[i];
        for (int k = 0; k < 4; k++) {
            bkf_model_params p = good;
            double *field = k == 0 ? &p.gamma : k == 1 ? &p.c : k == 2 ? &p.nu : &p.S;
            *field = k == 1 && x > 0 && isfinite(x) ? -x : x; /* a huge c is valid */
            CHECK_EINPUT(bkf_speeds_check(&p, &o, err));
            CHECK_EINPUT(bkf_speeds_find(&p, &o, &t, err));
            bkf_speeds_table_free(&t);
        }
        bkf_speeds_options bo = o;
        bo.tol = x;
        CHECK_EINPUT(bkf_speeds_find(&good, &bo, &t, err));
        bkf_speeds_table_free(&t);
        CHECK_EINPUT(bkf_speeds_branch(&good, 1, 1, BKF_SPEEDS_ALONG_S, x, &o, 10,
                                       (bkf_speeds_visit)visit_any, NULL, NULL, err));
    }
    CHECK_EINPUT(bkf_speeds_check(NULL, &o, err));
    CHECK_EINPUT(bkf_speeds_find(NULL, &o, &t, err));
    CHECK_EINPUT(bkf_speeds_find(&good, &o, NULL, err));
    bkf_speeds_options bo = o;
    bo.n_from = 0;
    CHECK_EINPUT(bkf_speeds_find(&good, &bo, &t, err));
    bkf_speeds_table_free(&t);
    bo = o;
    bo.n_from = 5;
    bo.n_to = 2;
    CHECK_EINPUT(bkf_speeds_find(&good, &bo, &t, err));
    bkf_speeds_table_free(&t);
    CHECK_EINPUT(bkf_speeds_branch(NULL, 1, 1, BKF_SPEEDS_ALONG_S, 30, &o, 10,
                                   (bkf_speeds_visit)visit_any, NULL, NULL, err));
    CHECK_EINPUT(bkf_speeds_branch(&good, 0, 1, BKF_SPEEDS_ALONG_S, 30, &o, 10,
                                   (bkf_speeds_visit)visit_any, NULL, NULL, err));
    CHECK_EINPUT(bkf_speeds_branch(&good, 1, 0, BKF_SPEEDS_ALONG_S, 30, &o, 10,
                                   (bkf_speeds_visit)visit_any, NULL, NULL, err));
    CHECK_EINPUT(bkf_speeds_branch(&good, 1, 1, (bkf_speeds_param)17, 30, &o, 10,
                                   (bkf_speeds_visit)visit_any, NULL, NULL, err));
    CHECK_EINPUT(bkf_speeds_branch(&good, 1, 1, BKF_SPEEDS_ALONG_NU, 1.5, &o, 10,
                                   (bkf_speeds_visit)visit_any, NULL, NULL, err));
    bkf_speeds_table_free(NULL);
}

TEST(api_fuzz_pde)
{
    const bkf_model_params good = {2.0, 0.3, -0.96, 20.0, 16, BKF_MODEL_CONTINUUM};
    bkf_pde_options o = bkf_pde_options_default();
    for (size_t i = 0; i < NHOSTILE; i++) {
        double x = hostile[i];
        for (int k = 0; k < 4; k++) {
            bkf_model_params p = good;
            double *field = k == 0 ? &p.gamma : k == 1 ? &p.c : k == 2 ? &p.nu : &p.S;
            if (k == 2 && isfinite(x)) continue; /* any finite nu is valid */
            if (k == 1 && isfinite(x) && x > 0) continue; /* any c >= 0 */
            if ((k == 0 || k == 3) && isfinite(x) && x > 0) continue;
            *field = x;
            CHECK_EINPUT(bkf_pde_check(&p, &o, err));
            CHECK_NULL_EINPUT(bkf_pde_alloc(&p, &o, err));
        }
        bkf_pde_options bo = o;
        bo.tol = x;
        CHECK_EINPUT(bkf_pde_check(&good, &bo, err));
        bo = o;
        bo.filter = x;
        CHECK_EINPUT(bkf_pde_check(&good, &bo, err));
    }
    bkf_model_params p = good;
    p.N = 0;
    CHECK_NULL_EINPUT(bkf_pde_alloc(&p, &o, err));
    p.N = 17; /* odd: not for the spectral continuum */
    CHECK_NULL_EINPUT(bkf_pde_alloc(&p, &o, err));
    p.N = (size_t)-1;
    CHECK_NULL_EINPUT(bkf_pde_alloc(&p, &o, err));
    p = good;
    p.kind = (bkf_model_kind)5;
    CHECK_NULL_EINPUT(bkf_pde_alloc(&p, &o, err));
    bkf_pde_options bo = o;
    bo.stepper = (bkf_pde_stepper)-3;
    CHECK_NULL_EINPUT(bkf_pde_alloc(&good, &bo, err));
    CHECK_NULL_EINPUT(bkf_pde_alloc(NULL, &o, err));

    bkf_pde *m = bkf_pde_alloc(&good, &o, NULL);
    CHECK(m);
    double psi[16], eta[16];
    for (int i = 0; i < 16; i++) psi[i] = eta[i] = 0.1;
    for (size_t i = 0; i < NHOSTILE; i++) {
        double x = hostile[i];
        CHECK_EINPUT(bkf_pde_init_uniform(m, x, 1, err));
        CHECK_EINPUT(bkf_pde_init_oscillation(m, 1, x, err));
        psi[3] = x;
        CHECK_EINPUT(bkf_pde_set_state(m, psi, eta, 0.0, err));
        psi[3] = 0.1;
        eta[5] = x;
        CHECK_EINPUT(bkf_pde_set_state(m, psi, eta, 0.0, err));
        eta[5] = 0.1;
        if (!isfinite(x)) CHECK_EINPUT(bkf_pde_set_state(m, psi, eta, x, err));
        if (!(x > 0 && isfinite(x))) {
            CHECK_EINPUT(bkf_pde_run(m, x, 0.1, NULL, NULL, NULL, NULL, err));
            CHECK_EINPUT(bkf_pde_run(m, 1.0, x, NULL, NULL, NULL, NULL, err));
        }
        bkf_pde_front_spec fs = bkf_pde_front_spec_default();
        fs.noise = x;
        CHECK_EINPUT(bkf_seed_front(m, &fs, NULL, NULL, err));
        fs = bkf_pde_front_spec_default();
        fs.tol = x;
        CHECK_EINPUT(bkf_seed_front(m, &fs, NULL, NULL, err));
        /* the paper's n = 7 wave, one field hostile */
        for (int k = 0; k < 4; k++) {
            bkf_pde_wave w = {7, 0.347551274998819, 3.0, -1, 0.0, 1, 1e-12};
            double *field[4] = {&w.v, &w.mu, &w.noise, &w.tol};
            *field[k] = x;
            if (k == 0 && x > 0.3 && isfinite(x)) continue; /* any v > c is a wave */
            if (k == 1 && x >= BKF_CYCLE_MU_MIN && x <= BKF_CYCLE_MU_MAX) continue;
            if (k == 2 && x >= 0 && x <= 10) continue;
            if (k == 3 && x >= 1e-14 && x <= 1e-4) continue;
            CHECK_EINPUT(bkf_pde_init_front(m, &w, NULL, NULL, err));
        }
    }
    CHECK_EINPUT(bkf_pde_init_uniform(m, -1.0, 1, err));
    CHECK_EINPUT(bkf_pde_init_uniform(NULL, 1e-3, 1, err));
    CHECK_EINPUT(bkf_pde_init_oscillation(m, 8, 1e-3, err)); /* j >= N/2 */
    CHECK_EINPUT(bkf_pde_init_oscillation(m, (size_t)-1, 1e-3, err));
    CHECK_EINPUT(bkf_pde_set_state(m, NULL, eta, 0.0, err));
    CHECK_EINPUT(bkf_pde_set_state(m, psi, NULL, 0.0, err));
    CHECK_EINPUT(bkf_pde_set_state(NULL, psi, eta, 0.0, err));
    CHECK_EINPUT(bkf_pde_init_front(NULL, NULL, NULL, NULL, err));
    CHECK_EINPUT(bkf_pde_init_front(m, NULL, NULL, NULL, err));
    CHECK_EINPUT(bkf_seed_front(NULL, NULL, NULL, NULL, err));
    CHECK_EINPUT(bkf_pde_init_oscillation(NULL, 1, 1e-3, err));
    bkf_pde_front_spec fs = bkf_pde_front_spec_default();
    fs.n = 0;
    CHECK_EINPUT(bkf_seed_front(m, &fs, NULL, NULL, err));
    fs = bkf_pde_front_spec_default();
    fs.root = 0;
    CHECK_EINPUT(bkf_seed_front(m, &fs, NULL, NULL, err));
    fs = bkf_pde_front_spec_default();
    fs.direction = 0;
    CHECK_EINPUT(bkf_seed_front(m, &fs, NULL, NULL, err));
    bkf_pde_wave w = {0, 0.35, 3.0, -1, 0.0, 1, 1e-12}; /* n = 0 */
    CHECK_EINPUT(bkf_pde_init_front(m, &w, NULL, NULL, err));
    w.n = 7;
    w.direction = 0;
    CHECK_EINPUT(bkf_pde_init_front(m, &w, NULL, NULL, err));
    CHECK_EINPUT(bkf_pde_run(NULL, 1.0, 0.1, NULL, NULL, NULL, NULL, err));
    CHECK_EINPUT(bkf_pde_run(m, 0.0, 0.1, NULL, NULL, NULL, NULL, err)); /* not after t */
    /* the refusals left the object usable */
    CHECK_STATUS(bkf_pde_init_uniform(m, 1e-3, 1, NULL), BKF_OK);
    CHECK_STATUS(bkf_pde_run(m, 1.0, 0.5, NULL, NULL, NULL, NULL, NULL), BKF_OK);
    for (int i = 0; i < 16; i++) CHECK(isfinite(bkf_pde_psi(m)[i]) && isfinite(bkf_pde_eta(m)[i]));
    CHECK(isfinite(bkf_pde_energy(m)) && isfinite(bkf_pde_energy_residual(m)));
    /* diagnostics of bad fields: NaN, not a crash or a number */
    CHECK(isnan(bkf_pde_energy_of(m, NULL, eta)) && isnan(bkf_pde_energy_of(m, psi, NULL)));
    CHECK(isnan(bkf_pde_energy_of(NULL, psi, eta)));
    CHECK(isnan(bkf_pde_spectral_tail(m, NULL)) && isnan(bkf_pde_spectral_tail(NULL, psi)));
    CHECK(isnan(bkf_pde_sample_energy_residual(m, NULL)));
    CHECK(isnan(bkf_pde_sample_mean_residual(m, NULL)));
    CHECK(isnan(bkf_pde_time(NULL)) && isnan(bkf_pde_energy(NULL)));
    CHECK(bkf_pde_psi(NULL) == NULL && bkf_pde_get_params(NULL) == NULL);
    CHECK(bkf_pde_size(NULL) == 0 && bkf_pde_get_stats(NULL) == NULL);
    bkf_pde_stats_reset(NULL);
    bkf_pde_free(m);
    bkf_pde_free(NULL);
}

TEST(api_fuzz_measure)
{
    bkf_measure_params good = bkf_measure_params_default();
    good.model = (bkf_model_params){2, 0.3, -0.96, 20, 16, BKF_MODEL_CONTINUUM};
    for (size_t i = 0; i < NHOSTILE; i++) {
        double x = hostile[i];
        for (int k = 0; k < 8; k++) {
            bkf_measure_params p = good;
            double *field[] = {&p.model.S, &p.model.gamma, &p.model.nu, &p.level,
                               &p.window, &p.hysteresis, &p.period_ref, &p.slip_eps};
            if ((k == 2 || k == 3) && isfinite(x)) continue;
            if (k == 3 && isnan(x)) continue; /* NaN level: the default */
            if ((k == 0 || k == 1 || k == 5 || k == 6 || k == 7) && isfinite(x) && x > 0) continue;
            *field[k] = x;
            CHECK_MSG(bkf_measure_alloc(&p, NULL) == NULL, "field %d = %g accepted", k, x);
            CHECK_NULL_EINPUT(bkf_measure_alloc(&p, err));
        }
    }
    bkf_measure_params p = good;
    p.model.N = 0;
    CHECK_NULL_EINPUT(bkf_measure_alloc(&p, err));
    p = good;
    p.probe = 16;
    CHECK_NULL_EINPUT(bkf_measure_alloc(&p, err));
    p = good;
    double ref[16] = {0};
    ref[2] = NAN;
    p.reference = ref;
    CHECK_NULL_EINPUT(bkf_measure_alloc(&p, err));
    CHECK_NULL_EINPUT(bkf_measure_alloc(NULL, err));

    bkf_measure *m = bkf_measure_alloc(&good, NULL);
    CHECK(m);
    double psi[16], eta[16];
    for (int i = 0; i < 16; i++) psi[i] = eta[i] = -0.96;
    bkf_front fr[4];
    size_t count;
    double v, ve;
    bkf_measure_summary sum;
    for (size_t i = 0; i < NHOSTILE; i++) {
        double x = hostile[i];
        if (isfinite(x)) continue; /* any finite field value is data */
        CHECK_EINPUT(bkf_measure_add(m, x, psi, eta, err));
        psi[4] = x;
        CHECK_EINPUT(bkf_measure_add(m, 1.0, psi, eta, err));
        CHECK_EINPUT(bkf_measure_fronts(m, psi, eta, fr, 4, &count, err));
        psi[4] = -0.96;
        eta[9] = x;
        CHECK_EINPUT(bkf_measure_add(m, 1.0, psi, eta, err));
        eta[9] = -0.96;
    }
    CHECK_EINPUT(bkf_measure_add(m, 0.0, NULL, eta, err));
    CHECK_EINPUT(bkf_measure_add(NULL, 0.0, psi, eta, err));
    CHECK_EINPUT(bkf_measure_fronts(NULL, psi, eta, fr, 4, &count, err));
    CHECK_EINPUT(bkf_measure_fronts(m, NULL, eta, fr, 4, &count, err));
    CHECK_EINPUT(bkf_measure_summarize(m, &sum, err)); /* no samples */
    CHECK_EINPUT(bkf_measure_summarize(m, NULL, err));
    CHECK_STATUS(bkf_measure_add(m, 0.0, psi, eta, NULL), BKF_OK);
    CHECK_EINPUT(bkf_measure_add(m, 0.0, psi, eta, err)); /* t does not increase */
    CHECK_STATUS(bkf_measure_add(m, 1.0, psi, eta, NULL), BKF_OK);
    CHECK(bkf_measure_count(m) == 2 && bkf_measure_record_at(m, 2) == NULL);
    CHECK(bkf_measure_count(NULL) == 0 && bkf_measure_record_at(NULL, 0) == NULL);
    for (size_t i = 0; i < 3; i++)
        CHECK_EINPUT(bkf_measure_fit_speed(m, hostile[i], 1.0, &v, &ve, NULL, err));
    CHECK_EINPUT(bkf_measure_fit_speed(m, 0.0, 1.0, NULL, &ve, NULL, err));
    CHECK_STATUS(bkf_measure_summarize(m, &sum, NULL), BKF_OK);
    CHECK(isfinite(sum.mean) && isfinite(sum.variance));
    bkf_measure_free(m);
    bkf_measure_free(NULL);
}

static bkf_comoving_params fuzz_comoving_params(void)
{
    bkf_comoving_params p = bkf_comoving_params_default();
    p.model = (bkf_model_params){2, 0.3, -0.96, 20, 0, BKF_MODEL_CONTINUUM};
    p.n = 7;
    p.v = 0.347551274998819; /* the paper's n = 7 */
    p.points = 64;
    return p;
}

TEST(api_fuzz_comoving)
{
    bkf_error e;
    for (size_t i = 0; i < NHOSTILE; i++) {
        for (int k = 0; k < 8; k++) {
            bkf_comoving_params p = fuzz_comoving_params();
            double *field[8] = {&p.model.gamma, &p.model.c, &p.model.nu, &p.model.S,
                                &p.v,           &p.tol,     &p.noise,    &p.cycle_tol};
            *field[k] = hostile[i];
            bkf_comoving *m = bkf_comoving_alloc(&p, &e);
            /* a few hostile values are valid for some fields (S = 1e300, v
             * far above c); then the object must be whole */
            if (m) CHECK(bkf_comoving_size(m) == 7 * 64 && bkf_comoving_count(m) == 1);
            bkf_comoving_free(m);
        }
    }
    CHECK(bkf_comoving_alloc(NULL, &e) == NULL);
    CHECK_EINPUT(bkf_comoving_run(NULL, 1.0, 0.1, NULL, NULL, err));
    double d, de;
    CHECK_EINPUT(bkf_comoving_fit_drift(NULL, 0, 1, &d, &de, err));
    CHECK(bkf_comoving_size(NULL) == 0 && bkf_comoving_count(NULL) == 0 &&
          bkf_comoving_record_at(NULL, 0) == NULL && bkf_comoving_grid(NULL) == NULL &&
          bkf_comoving_psi(NULL) == NULL && bkf_comoving_eta(NULL) == NULL &&
          isnan(bkf_comoving_time(NULL)) && isnan(bkf_comoving_mu(NULL)));
    bkf_comoving_stats st;
    bkf_comoving_get_stats(NULL, &st);
    CHECK(st.steps == 0);
    bkf_comoving_get_stats(NULL, NULL);
    bkf_comoving_free(NULL);
    /* a valid object refuses hostile run arguments */
    bkf_comoving_params p = fuzz_comoving_params();
    bkf_comoving *m = bkf_comoving_alloc(&p, &e);
    CHECK_MSG(m != NULL, "%s", e.message);
    for (size_t i = 0; m && i < NHOSTILE; i++) {
        if (hostile[i] > 0 && isfinite(hostile[i])) continue;
        CHECK_EINPUT(bkf_comoving_run(m, hostile[i], 0.1, NULL, NULL, err));
        CHECK_EINPUT(bkf_comoving_run(m, 1.0, hostile[i], NULL, NULL, err));
    }
    CHECK_EINPUT(bkf_comoving_fit_drift(m, 0, 1, NULL, &de, err));
    bkf_comoving_free(m);
}

TEST(api_fuzz_asymfit)
{
    bkf_asymfit_large_result lr;
    bkf_asymfit_small_result sr;
    double mu[10], R[10];
    for (int i = 0; i < 10; i++) {
        mu[i] = 100.0 * (i + 1);
        R[i] = 10.0 * pow(mu[i], -1.0 / 3.0);
    }
    for (size_t i = 0; i < NHOSTILE; i++) {
        double x = hostile[i];
        CHECK_EINPUT(bkf_asymfit_large(x, NULL, &lr, err));
        CHECK_EINPUT(bkf_asymfit_small(x, NULL, &sr, err));
        bkf_asymfit_large_options lo = bkf_asymfit_large_options_default();
        lo.mu_lo = x;
        CHECK_EINPUT(bkf_asymfit_large(0.0, &lo, &lr, err));
        lo = bkf_asymfit_large_options_default();
        lo.p_hi = x;
        CHECK_EINPUT(bkf_asymfit_large(0.0, &lo, &lr, err));
        bkf_asymfit_small_options so = bkf_asymfit_small_options_default();
        so.mu_hi = x;
        CHECK_EINPUT(bkf_asymfit_small(0.0, &so, &sr, err));
        double m0 = mu[3];
        mu[3] = x;
        CHECK_EINPUT(bkf_asymfit_correction(mu, R, 10, -0.9, -0.05, &lr, err));
        mu[3] = m0;
        double r0 = R[6];
        R[6] = x;
        if (!isfinite(x)) CHECK_EINPUT(bkf_asymfit_correction(mu, R, 10, -0.9, -0.05, &lr, err));
        R[6] = r0;
        CHECK_EINPUT(bkf_asymfit_correction(mu, R, 10, x, -0.05, &lr, err));
        double nu[1] = {x}, eps[1] = {1e-3};
        bkf_asymfit_boundary b[BKF_ASYMFIT_NFORMULAS];
        CHECK_EINPUT(bkf_asymfit_map(nu, 1, eps, 1, NULL, b, err));
        nu[0] = 0.0;
        eps[0] = x;
        CHECK_EINPUT(bkf_asymfit_map(nu, 1, eps, 1, NULL, b, err));
        bkf_asymfit_grid_point gp;
        double gm[1] = {x}, gn[1] = {0.0};
        CHECK_EINPUT(bkf_asymfit_grid(gm, 1, gn, 1, &gp, err));
        gm[0] = 1.0;
        gn[0] = x;
        CHECK_EINPUT(bkf_asymfit_grid(gm, 1, gn, 1, &gp, err));
    }
    CHECK_EINPUT(bkf_asymfit_large(0.0, NULL, NULL, err));
    CHECK_EINPUT(bkf_asymfit_small(0.0, NULL, NULL, err));
    CHECK_EINPUT(bkf_asymfit_correction(NULL, R, 10, -0.9, -0.05, &lr, err));
    CHECK_EINPUT(bkf_asymfit_correction(mu, R, 3, -0.9, -0.05, &lr, err));
    CHECK_EINPUT(bkf_asymfit_correction(mu, R, (size_t)-1, -0.9, -0.05, &lr, err));
    double nu[1] = {0.0}, eps[1] = {1e-3};
    bkf_asymfit_boundary b[BKF_ASYMFIT_NFORMULAS];
    CHECK_EINPUT(bkf_asymfit_map(NULL, 1, eps, 1, NULL, b, err));
    CHECK_EINPUT(bkf_asymfit_map(nu, 0, eps, 1, NULL, b, err));
    CHECK_EINPUT(bkf_asymfit_map(nu, 1, eps, 1, NULL, NULL, err));
    CHECK_EINPUT(bkf_asymfit_map(nu, (size_t)-1, eps, (size_t)-1, NULL, b, err));
    double gm[1] = {1.0};
    bkf_asymfit_grid_point gp;
    CHECK_EINPUT(bkf_asymfit_grid(gm, 1, nu, 1, NULL, err));
    CHECK_EINPUT(bkf_asymfit_grid(NULL, 1, nu, 1, &gp, err));
    CHECK_EINPUT(bkf_asymfit_grid(gm, (size_t)-1, nu, (size_t)-1, &gp, err));
}

static int cont_residual(const double *u, double *g, double *jac, void *data, bkf_error *err)
{
    (void)data;
    (void)err;
    g[0] = u[0] * u[0] + u[1] * u[1] - 1.0;
    if (jac) {
        jac[0] = 2 * u[0];
        jac[1] = 2 * u[1];
    }
    return BKF_OK;
}

static int cont_accept(const double *u, const double *t, int is_fold, void *data)
{
    (void)u;
    (void)t;
    (void)is_fold;
    (void)data;
    return 0;
}

TEST(api_fuzz_continuation)
{
    double u0[2] = {1.0, 0.0};
    bkf_cont_options o = bkf_cont_options_default(1);
    o.max_points = 5;
    for (size_t i = 0; i < NHOSTILE; i++) {
        double x = hostile[i];
        double ub[2] = {x, 0.0};
        if (!isfinite(x))
            CHECK_EINPUT(bkf_cont_run(cont_residual, cont_accept, NULL, ub, 1, 1, &o, NULL, err));
        bkf_cont_options bo = o;
        bo.step_initial = x < 0 || !isfinite(x) ? x : -x;
        CHECK_EINPUT(bkf_cont_run(cont_residual, cont_accept, NULL, u0, 1, 1, &bo, NULL, err));
        bo = o;
        bo.newton_tol = x < 0 || !isfinite(x) ? x : -x;
        CHECK_EINPUT(bkf_cont_run(cont_residual, cont_accept, NULL, u0, 1, 1, &bo, NULL, err));
        bo = o;
        bo.step_max = x < 0 || !isfinite(x) ? x : -x;
        CHECK_EINPUT(bkf_cont_run(cont_residual, cont_accept, NULL, u0, 1, 1, &bo, NULL, err));
        double sc[2] = {1.0, x < 0 || !isfinite(x) ? x : -x};
        bo = o;
        bo.scale = sc;
        CHECK_EINPUT(bkf_cont_run(cont_residual, cont_accept, NULL, u0, 1, 1, &bo, NULL, err));
    }
    CHECK_EINPUT(bkf_cont_run(NULL, cont_accept, NULL, u0, 1, 1, &o, NULL, err));
    CHECK_EINPUT(bkf_cont_run(cont_residual, NULL, NULL, u0, 1, 1, &o, NULL, err));
    CHECK_EINPUT(bkf_cont_run(cont_residual, cont_accept, NULL, NULL, 1, 1, &o, NULL, err));
    CHECK_EINPUT(bkf_cont_run(cont_residual, cont_accept, NULL, u0, 2, 1, &o, NULL, err));
    CHECK_EINPUT(bkf_cont_run(cont_residual, cont_accept, NULL, u0, -1, 1, &o, NULL, err));
    CHECK_EINPUT(bkf_cont_run(cont_residual, cont_accept, NULL, u0, 1, 0, &o, NULL, err));
    CHECK_EINPUT(bkf_cont_run(cont_residual, cont_accept, NULL, u0, 1, 1, NULL, NULL, err));
    bkf_cont_options bo = o;
    bo.n = 0;
    CHECK_EINPUT(bkf_cont_run(cont_residual, cont_accept, NULL, u0, 1, 1, &bo, NULL, err));
    bo = o;
    bo.n = (size_t)-1 / 2;
    CHECK_EINPUT(bkf_cont_run(cont_residual, cont_accept, NULL, u0, 1, 1, &bo, NULL, err));
    bo = o;
    bo.stop_index = 5;
    CHECK_EINPUT(bkf_cont_run(cont_residual, cont_accept, NULL, u0, 1, 1, &bo, NULL, err));
    bo = o;
    bo.newton_max_iter = 0;
    CHECK_EINPUT(bkf_cont_run(cont_residual, cont_accept, NULL, u0, 1, 1, &bo, NULL, err));
    /* and the valid call works */
    bkf_cont_report rep;
    CHECK_STATUS(bkf_cont_run(cont_residual, cont_accept, NULL, u0, 1, 1, &o, &rep, NULL), BKF_OK);
    CHECK(rep.points == 5);
}

TEST(api_fuzz_io)
{
    bkf_io_column cols[2] = {{"a", BKF_IO_NUMBER}, {"b", BKF_IO_TEXT}};
    FILE *devnull = fopen("/dev/null", "w");
    CHECK(devnull);
    CHECK_NULL_EINPUT(bkf_io_table_alloc(NULL, BKF_IO_TSV, cols, 2, err));
    CHECK_NULL_EINPUT(bkf_io_table_alloc(devnull, (bkf_io_format)9, cols, 2, err));
    CHECK_NULL_EINPUT(bkf_io_table_alloc(devnull, BKF_IO_TSV, NULL, 2, err));
    CHECK_NULL_EINPUT(bkf_io_table_alloc(devnull, BKF_IO_TSV, cols, 0, err));
    bkf_io_column bad[2] = {{NULL, BKF_IO_NUMBER}, {"x\ny", BKF_IO_TEXT}};
    CHECK_NULL_EINPUT(bkf_io_table_alloc(devnull, BKF_IO_TSV, bad, 1, err));
    CHECK_NULL_EINPUT(bkf_io_table_alloc(devnull, BKF_IO_TSV, bad + 1, 1, err));
    bkf_io_column kind[1] = {{"k", (bkf_io_kind)4}};
    CHECK_NULL_EINPUT(bkf_io_table_alloc(devnull, BKF_IO_TSV, kind, 1, err));
    CHECK_EINPUT(bkf_io_table_comment(NULL, "x", err));
    CHECK_EINPUT(bkf_io_table_row(NULL, NULL, err));
    CHECK_EINPUT(bkf_io_table_finish(NULL, err));
    bkf_io_format fmt;
    CHECK_EINPUT(bkf_io_format_parse(NULL, &fmt, err));
    CHECK_EINPUT(bkf_io_format_parse("tsv", NULL, err));
    CHECK_EINPUT(bkf_io_format_parse("TSV\n", &fmt, err));
    bkf_io_table *t = bkf_io_table_alloc(devnull, BKF_IO_JSON, cols, 2, NULL);
    CHECK(t);
    CHECK_EINPUT(bkf_io_table_row(t, NULL, err));
    /* non-finite numbers are data, not errors: null in JSON */
    bkf_io_value v[2] = {{.number = NAN}, {.text = NULL}};
    CHECK_STATUS(bkf_io_table_row(t, v, NULL), BKF_OK);
    CHECK_EINPUT(bkf_io_table_comment(t, "late", err));
    CHECK_STATUS(bkf_io_table_finish(t, NULL), BKF_OK);
    CHECK_EINPUT(bkf_io_table_finish(t, err));
    bkf_io_table_free(t);
    bkf_io_table_free(NULL);
    CHECK(bkf_io_table_rows(NULL) == 0);
    CHECK_NULL_EINPUT(bkf_io_atomic_open(NULL, err));
    CHECK_NULL_EINPUT(bkf_io_atomic_open("", err));
    CHECK_NULL_EINPUT(bkf_io_atomic_open("/nonexistent-dir-bkf/x.tsv", err));
    CHECK_NULL_EINPUT(bkf_io_atomic_open("/dev/null", err));
    CHECK_EINPUT(bkf_io_atomic_commit(NULL, err));
    CHECK(bkf_io_atomic_stream(NULL) == NULL && bkf_io_atomic_temp_path(NULL) == NULL);
    bkf_io_atomic_abort(NULL);
    CHECK_NULL_EINPUT(bkf_io_lock_take(NULL, err));
    CHECK_NULL_EINPUT(bkf_io_lock_take("", err));
    CHECK_NULL_EINPUT(bkf_io_lock_take("/nonexistent-dir-bkf/x.tsv", err));
    bkf_io_lock_release(NULL);
    fclose(devnull);
}

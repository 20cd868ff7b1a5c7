/* The simulator against independent facts: the cycle engine's period for the
 * uniform oscillation, the speeds solver for seeded fronts, the chain's
 * second-order approach to the continuum, the energy balance and the exact
 * linear invariant, the model's symmetries, and bad input. */
#include "harness.h"
#include "cli_support.h"

#include <string.h>

#include "bkfront/cycle.h"
#include "bkfront/measure.h"
#include "bkfront/pde.h"
#include "bkfront/seed.h"
#include "pde_support.h"

static bkf_pde *make(double gamma, double c, double nu, double S, size_t N, bkf_model_kind model,
                     double tol)
{
    bkf_model_params p = {gamma, c, nu, S, N, model};
    bkf_pde_options o = bkf_pde_options_default();
    o.tol = tol;
    return alloc_pde(&p, &o);
}

/* With psi_xx = 0 the model is the van der Pol oscillator at mu = gamma in
 * time t: the uniform oscillation's period is the cycle engine's T(gamma). */
TEST(pde_uniform_oscillation_has_the_cycle_period)
{
    const double gamma = 2, nu = -0.92;
    bkf_cycle_result cr;
    bkf_cycle_options co = bkf_cycle_options_default();
    co.tol = 1e-12;
    bkf_error e;
    CHECK_STATUS(bkf_cycle_period(gamma, nu, &co, &cr, &e), BKF_OK);
    bkf_pde *m = make(gamma, 0.3, nu, 20, 16, BKF_MODEL_CONTINUUM, 1e-11);
    CHECK_STATUS(bkf_pde_init_oscillation(m, 0, 0.0, &e), BKF_OK);
    bkf_measure *ms = make_measure(m, NULL);
    CHECK_STATUS(bkf_pde_run(m, 12 * cr.period, 0.05, measure_sample, ms, NULL, NULL, &e),
                 BKF_OK);
    bkf_measure_summary s;
    CHECK_STATUS(bkf_measure_summarize(ms, &s, &e), BKF_OK);
    CHECK(s.period_multiplicity == 1);
    CHECK_CLOSE(s.period, cr.period, 2e-8, 0);
    CHECK(s.regime == BKF_REGIME_GLOBAL_OSCILLATION);
    /* uniform stays uniform: the spectral Laplacian of a constant is rounding */
    CHECK_MSG(s.std_max < 1e-12, "std_max %g", s.std_max);
    bkf_test_note("period %.15g (PDE, crossings) vs %.15g (cycle engine), rel %.2g", s.period,
                  cr.period, (s.period - cr.period) / cr.period);
    bkf_measure_free(ms);
    bkf_pde_free(m);
}

/* A seeded n-front wave moves at the predicted speed and keeps its count. */
TEST(pde_seeded_front_keeps_its_speed)
{
    bkf_pde *m = make(2, 0.3, -0.96, 20, 512, BKF_MODEL_CONTINUUM, 1e-9);
    bkf_pde_front_spec fs = bkf_pde_front_spec_default();
    fs.n = 2;
    bkf_pde_front_info fi;
    double clean[512];
    bkf_error e;
    CHECK_STATUS(bkf_seed_front(m, &fs, &fi, clean, &e), BKF_OK);
    CHECK_MSG(fabs(fi.residual) < 1e-10, "seed not periodic: residual %g", fi.residual);
    CHECK_CLOSE(fi.period_fixed, fi.T * fi.stretch, 1e-15, 0);
    bkf_measure *ms = make_measure(m, clean);
    CHECK_STATUS(bkf_pde_run(m, 60, 0.1, measure_sample, ms, NULL, NULL, &e), BKF_OK);
    bkf_measure_summary s;
    CHECK_STATUS(bkf_measure_summarize(ms, &s, &e), BKF_OK);
    CHECK(s.fronts_start == 2 && s.fronts_end == 2 && s.count_constant);
    CHECK(s.moving_minus == 2 && s.moving_plus == 0);
    CHECK_MSG(s.speed < 0, "fronts move towards -x: speed %g", s.speed);
    double rel = (-s.speed - fi.v) / fi.v;
    CHECK_MSG(fabs(rel) < 1e-8, "v_meas %.15g v_pred %.15g rel %.3g", -s.speed, fi.v, rel);
    CHECK_MSG(s.speed_err < 1e-8, "speed_err %g", s.speed_err);
    /* the period at a point is the cycle period in t: T sqrt(1 - c^2/v^2) */
    CHECK_CLOSE(s.period, fi.period_fixed, 1e-7, 0);
    CHECK(s.regime == BKF_REGIME_FRONTS);
    CHECK(s.deviation_end < 1e-5);
    bkf_test_note("n = 2: v_meas %.15g, v_pred %.15g, rel %.2g, err %.2g", -s.speed, fi.v, rel,
                  s.speed_err);
    bkf_measure_free(ms);
    bkf_pde_free(m);
}

/* The mirrored seed moves the other way at the same speed; the direction of
 * z = x/v + t is -x. */
TEST(pde_front_direction_is_mirrored)
{
    double v[2];
    for (int k = 0; k < 2; k++) {
        bkf_pde *m = make(2, 0.3, -0.96, 20, 256, BKF_MODEL_CONTINUUM, 1e-9);
        bkf_pde_front_spec fs = bkf_pde_front_spec_default();
        fs.n = 1;
        fs.direction = k ? 1 : -1;
        bkf_error e;
        CHECK_STATUS(bkf_seed_front(m, &fs, NULL, NULL, &e), BKF_OK);
        bkf_measure *ms = make_measure(m, NULL);
        CHECK_STATUS(bkf_pde_run(m, 20, 0.1, measure_sample, ms, NULL, NULL, &e), BKF_OK);
        bkf_measure_summary s;
        CHECK_STATUS(bkf_measure_summarize(ms, &s, &e), BKF_OK);
        v[k] = s.speed;
        bkf_measure_free(ms);
        bkf_pde_free(m);
    }
    CHECK(v[0] < 0 && v[1] > 0);
    CHECK_CLOSE(v[1], -v[0], 1e-9, 0);
}

/* The chain with h = S/N approaches the continuum at second order in h. */
TEST(pde_chain_converges_to_the_continuum)
{
    const double T = 8;
    bkf_error e;
    bkf_pde *ref = make(2, 0.3, -0.5, 20, 128, BKF_MODEL_CONTINUUM, 1e-12);
    CHECK_STATUS(bkf_pde_init_oscillation(ref, 1, 0.2, &e), BKF_OK);
    CHECK_STATUS(bkf_pde_run(ref, T, T, NULL, NULL, NULL, NULL, &e), BKF_OK);
    const double *pr = bkf_pde_psi(ref);
    double errs[4];
    size_t Ns[4] = {16, 32, 64, 128};
    for (int k = 0; k < 4; k++) {
        bkf_pde *m = make(2, 0.3, -0.5, 20, Ns[k], BKF_MODEL_CHAIN, 1e-12);
        CHECK_STATUS(bkf_pde_init_oscillation(m, 1, 0.2, &e), BKF_OK);
        CHECK_STATUS(bkf_pde_run(m, T, T, NULL, NULL, NULL, NULL, &e), BKF_OK);
        const double *p = bkf_pde_psi(m);
        size_t stride = 128 / Ns[k];
        double worst = 0;
        for (size_t i = 0; i < Ns[k]; i++) worst = fmax(worst, fabs(p[i] - pr[i * stride]));
        errs[k] = worst;
        bkf_pde_free(m);
    }
    for (int k = 1; k < 4; k++) {
        double rate = log2(errs[k - 1] / errs[k]);
        bkf_test_note("N %zu -> %zu: max error %.3g -> %.3g, order %.3f", Ns[k - 1], Ns[k],
                      errs[k - 1], errs[k], rate);
        CHECK_MSG(fabs(rate - 2) < 0.1, "order %.3f", rate);
    }
    bkf_pde_free(ref);
}

/* H - D is conserved to the integration's accuracy and the linear invariant
 * to rounding, in both models, through a fully nonlinear run. */
TEST(pde_energy_balance_and_linear_invariant)
{
    for (int model = 0; model < 2; model++) {
        bkf_pde *m = make(2, 0.3, -0.96, 20, model ? 40 : 128,
                          model ? BKF_MODEL_CHAIN : BKF_MODEL_CONTINUUM, 1e-11);
        bkf_error e;
        CHECK_STATUS(bkf_pde_init_uniform(m, 0.3, 7, &e), BKF_OK);
        double H0 = bkf_pde_energy(m);
        CHECK_STATUS(bkf_pde_run(m, 30, 30, NULL, NULL, NULL, NULL, &e), BKF_OK);
        double H = bkf_pde_energy(m), D = bkf_pde_dissipation(m);
        double res = bkf_pde_energy_residual(m), mres = bkf_pde_mean_residual(m);
        bkf_test_note("%s: H %.6g -> %.6g, work %.6g, balance residual %.2g, invariant %.2g",
                      model ? "chain" : "continuum", H0, H, D, res, mres);
        CHECK_MSG(fabs(D) > 1, "the run should do work: D = %g", D);
        CHECK_MSG(fabs(res) < 1e-7 * (fabs(H0) + fabs(D)), "energy residual %g", res);
        CHECK_MSG(fabs(mres) < 1e-12, "linear invariant drifted by %g", mres);
        bkf_pde_free(m);
    }
}

/* (psi, eta, nu) -> (-psi, -eta, -nu) maps solutions to solutions; every
 * operation of the simulator is odd, so the runs agree bit for bit. */
TEST(pde_sign_symmetry_is_exact)
{
    bkf_error e;
    bkf_pde *a = make(2, 0.3, -0.9, 20, 64, BKF_MODEL_CONTINUUM, 1e-8);
    bkf_pde *b = make(2, 0.3, 0.9, 20, 64, BKF_MODEL_CONTINUUM, 1e-8);
    CHECK_STATUS(bkf_pde_init_uniform(a, 0.1, 3, &e), BKF_OK);
    double psi[64], eta[64];
    for (int i = 0; i < 64; i++) {
        psi[i] = -bkf_pde_psi(a)[i];
        eta[i] = -bkf_pde_eta(a)[i];
    }
    CHECK_STATUS(bkf_pde_set_state(b, psi, eta, 0, &e), BKF_OK);
    CHECK_STATUS(bkf_pde_run(a, 15, 15, NULL, NULL, NULL, NULL, &e), BKF_OK);
    CHECK_STATUS(bkf_pde_run(b, 15, 15, NULL, NULL, NULL, NULL, &e), BKF_OK);
    for (int i = 0; i < 64; i++) CHECK(bkf_pde_psi(a)[i] == -bkf_pde_psi(b)[i]);
    CHECK(bkf_pde_get_stats(a)->steps == bkf_pde_get_stats(b)->steps);
    bkf_pde_free(a);
    bkf_pde_free(b);
}

typedef struct {
    double t;
    double psi[32];
    int hit;
} probe_at;

static int grab(const bkf_pde_sample *s, void *data)
{
    probe_at *p = data;
    if (fabs(s->t - p->t) < 1e-12) {
        memcpy(p->psi, s->psi, sizeof p->psi);
        p->hit = 1;
    }
    return 0;
}

static int ignore_sample(const bkf_pde_sample *s, void *data)
{
    (void)s;
    (void)data;
    return 0;
}

/* Samples are as accurate as step ends (issue 17: quintic Hermite samples
 * between rk8pd steps were off by 3.6e-10 at tol 1e-12 in this chain run,
 * 1000 tol).  The sample at t of a run to a later time, at tol 1e-12, is
 * compared with a reference that ends at t: tol 1e-13 and steps of at most
 * 0.02 (sampled every 0.02), about 300 times more accurate. */
TEST(pde_samples_match_a_run_to_the_sample)
{
    bkf_error e;
    static const struct {
        double t, tend;
    } cases[] = {{25, 40}, {7.3, 10}};
    for (size_t k = 0; k < 2; k++) {
        probe_at p = {cases[k].t, {0}, 0};
        bkf_pde *a = make(1, 1, -0.5, 20, 20, BKF_MODEL_CHAIN, 1e-12);
        CHECK_STATUS(bkf_pde_init_uniform(a, 1e-2, 5, &e), BKF_OK);
        CHECK_STATUS(bkf_pde_run(a, cases[k].tend, 0.1, grab, &p, NULL, NULL, &e), BKF_OK);
        CHECK(p.hit);
        bkf_pde *b = make(1, 1, -0.5, 20, 20, BKF_MODEL_CHAIN, 1e-13);
        CHECK_STATUS(bkf_pde_init_uniform(b, 1e-2, 5, &e), BKF_OK);
        CHECK_STATUS(bkf_pde_run(b, cases[k].t, 0.02, ignore_sample, NULL, NULL, NULL, &e),
                     BKF_OK);
        double worst = 0;
        for (int i = 0; i < 20; i++) worst = fmax(worst, fabs(p.psi[i] - bkf_pde_psi(b)[i]));
        bkf_test_note("sample at t = %g (tol 1e-12) vs the reference: %.2g", cases[k].t, worst);
        CHECK_MSG(worst < 1e-11, "difference %g at t = %g", worst, cases[k].t);
        bkf_pde_free(a);
        bkf_pde_free(b);
    }
}

/* Beyond the slip threshold uniform sliding is stable: noise decays. */
TEST(pde_continuous_slip_is_stable_beyond_the_threshold)
{
    bkf_error e;
    bkf_pde *m = make(2, 0.3, -1.2, 20, 64, BKF_MODEL_CONTINUUM, 1e-9);
    CHECK_STATUS(bkf_pde_init_uniform(m, 1e-2, 5, &e), BKF_OK);
    bkf_measure *ms = make_measure(m, NULL);
    CHECK_STATUS(bkf_pde_run(m, 60, 0.2, measure_sample, ms, NULL, NULL, &e), BKF_OK);
    bkf_measure_summary s;
    CHECK_STATUS(bkf_measure_summarize(ms, &s, &e), BKF_OK);
    CHECK(s.regime == BKF_REGIME_CONTINUOUS_SLIP);
    CHECK(s.slip_deviation_end < 1e-6);
    bkf_measure_free(ms);
    bkf_pde_free(m);
}

/* The filter touches only the top of the spectrum: a resolved front runs
 * the same with it and without it. */
TEST(pde_filter_leaves_a_resolved_front_alone)
{
    double psi[2][256];
    for (int k = 0; k < 2; k++) {
        bkf_model_params p = {2, 0.3, -0.96, 20, 256, BKF_MODEL_CONTINUUM};
        bkf_pde_options o = bkf_pde_options_default();
        o.filter = k ? 0.0 : 4.0;
        bkf_error e;
        bkf_pde *m = bkf_pde_alloc(&p, &o, &e);
        CHECK(m);
        bkf_pde_front_spec fs = bkf_pde_front_spec_default();
        CHECK_STATUS(bkf_seed_front(m, &fs, NULL, NULL, &e), BKF_OK);
        CHECK(bkf_pde_spectral_tail(m, bkf_pde_psi(m)) < 1e-11);
        CHECK_STATUS(bkf_pde_run(m, 20, 20, NULL, NULL, NULL, NULL, &e), BKF_OK);
        memcpy(psi[k], bkf_pde_psi(m), sizeof psi[k]);
        bkf_pde_free(m);
    }
    double worst = 0;
    for (int i = 0; i < 256; i++) worst = fmax(worst, fabs(psi[0][i] - psi[1][i]));
    bkf_test_note("filter on vs off after t = 20: %.2g", worst);
    CHECK(worst < 1e-8);
}

TEST(pde_rejects_bad_input)
{
    bkf_error e;
    bkf_model_params good = {2, 0.3, -0.96, 20, 64, BKF_MODEL_CONTINUUM};
    bkf_pde_options o = bkf_pde_options_default();
    struct {
        bkf_model_params p;
        const char *name;
    } bad[] = {
        {{0, 0.3, -0.96, 20, 64, BKF_MODEL_CONTINUUM}, "gamma"},
        {{-1, 0.3, -0.96, 20, 64, BKF_MODEL_CONTINUUM}, "gamma"},
        {{2, -0.1, -0.96, 20, 64, BKF_MODEL_CONTINUUM}, "c"},
        {{2, 0.3, NAN, 20, 64, BKF_MODEL_CONTINUUM}, "nu"},
        {{2, 0.3, -0.96, 0, 64, BKF_MODEL_CONTINUUM}, "S"},
        {{2, 0.3, -0.96, INFINITY, 64, BKF_MODEL_CONTINUUM}, "S"},
        {{2, 0.3, -0.96, 20, 4, BKF_MODEL_CONTINUUM}, "N"},
        {{2, 0.3, -0.96, 20, 65, BKF_MODEL_CONTINUUM}, "even"},
        {{2, 0.3, -0.96, 20, 64, (bkf_model_kind)7}, "model"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        e.message[0] = '\0';
        CHECK(bkf_pde_alloc(&bad[i].p, &o, &e) == NULL);
        CHECK_MSG(strstr(e.message, bad[i].name), "case %zu: '%s' lacks %s", i, e.message,
                  bad[i].name);
    }
    /* odd N is fine for the chain; |nu| >= 1 is fine for a simulation */
    bkf_model_params chain = {2, 0.3, 1.5, 21, 21, BKF_MODEL_CHAIN};
    bkf_pde *m = bkf_pde_alloc(&chain, &o, &e);
    CHECK(m);
    CHECK_STATUS(bkf_pde_init_uniform(m, 1e-3, 1, &e), BKF_OK);
    /* but fronts and the oscillation need a cycle */
    bkf_pde_front_spec fs = bkf_pde_front_spec_default();
    CHECK_STATUS(bkf_seed_front(m, &fs, NULL, NULL, &e), BKF_EINPUT);
    CHECK(strstr(e.message, "nu"));
    CHECK_STATUS(bkf_pde_init_oscillation(m, 1, 0.1, &e), BKF_EINPUT);
    CHECK_STATUS(bkf_pde_run(m, 0, 0.1, NULL, NULL, NULL, NULL, &e), BKF_EINPUT);
    CHECK_STATUS(bkf_pde_run(m, 1, 0, NULL, NULL, NULL, NULL, &e), BKF_EINPUT);
    bkf_pde_free(m);

    bkf_pde_options ot = o;
    ot.tol = 1;
    CHECK(bkf_pde_alloc(&good, &ot, &e) == NULL && strstr(e.message, "tol"));
    ot = o;
    ot.dealias = 1;
    CHECK(bkf_pde_alloc(&chain, &ot, &e) == NULL && strstr(e.message, "dealias"));

    m = bkf_pde_alloc(&good, &o, &e);
    CHECK(m);
    fs.n = 1000; /* far beyond n_max */
    CHECK_STATUS(bkf_seed_front(m, &fs, NULL, NULL, &e), BKF_EINPUT);
    CHECK_MSG(strstr(e.message, "n = 1000"), "%s", e.message);
    fs = bkf_pde_front_spec_default();
    fs.root = 2; /* n = 1 has one root here */
    CHECK_STATUS(bkf_seed_front(m, &fs, NULL, NULL, &e), BKF_EINPUT);
    CHECK_STATUS(bkf_pde_init_oscillation(m, 32, 0.1, &e), BKF_EINPUT);
    double bad_state[64];
    for (int i = 0; i < 64; i++) bad_state[i] = i == 5 ? NAN : 0;
    CHECK_STATUS(bkf_pde_set_state(m, bad_state, bad_state, 0, &e), BKF_EINPUT);
    bkf_pde_free(m);
}

/* In the frame moving with the predicted speed the seeded wave is a steady
 * state: the fronts stay put (their speed in the frame is the lab speed minus
 * the speeds solver's v, an independent value), the shape is kept, and H - D
 * (D now the general dH/dt of the frame's right-hand side) is conserved. */
TEST(pde_moving_frame_holds_the_front_still)
{
    bkf_pde *lab = make(2, 0.3, -0.96, 20, 512, BKF_MODEL_CONTINUUM, 1e-9);
    bkf_pde_front_spec fs = bkf_pde_front_spec_default();
    fs.n = 2;
    bkf_pde_front_info fi;
    bkf_error e;
    CHECK_STATUS(bkf_seed_front(lab, &fs, &fi, NULL, &e), BKF_OK);
    bkf_pde_free(lab);
    bkf_model_params p = {2, 0.3, -0.96, 20, 512, BKF_MODEL_CONTINUUM};
    bkf_pde_options o = bkf_pde_options_default();
    o.frame_speed = -fi.v;
    bkf_pde *m = bkf_pde_alloc(&p, &o, &e);
    CHECK_MSG(m, "alloc: %s", e.message);
    double clean[512];
    CHECK_STATUS(bkf_seed_front(m, &fs, &fi, clean, &e), BKF_OK);
    bkf_measure *ms = make_measure(m, clean);
    CHECK_STATUS(bkf_pde_run(m, 40, 0.1, measure_sample, ms, NULL, NULL, &e), BKF_OK);
    bkf_measure_summary s;
    CHECK_STATUS(bkf_measure_summarize(ms, &s, &e), BKF_OK);
    CHECK(s.fronts_start == 2 && s.fronts_end == 2 && s.count_constant);
    double rel = -s.speed / fi.v;
    CHECK_MSG(fabs(rel) < 1e-8, "speed in the frame %.3g (relative %.3g)", s.speed, rel);
    CHECK(s.deviation_end < 1e-5);
    double res = bkf_pde_energy_residual(m), H = bkf_pde_energy(m);
    CHECK_MSG(fabs(res) < 1e-8 * fabs(H), "H - H0 - D = %g (H %g)", res, H);
    CHECK(fabs(bkf_pde_mean_residual(m)) < 1e-12);
    bkf_test_note("n = 2 in the frame of v_pred: drift %.2g relative, H - H0 - D %.2g, "
                  "%zu steps", rel, res, bkf_pde_get_stats(m)->steps);
    bkf_measure_free(ms);
    bkf_pde_free(m);

    /* the frame is refused where it does not apply */
    p.kind = BKF_MODEL_CHAIN;
    CHECK(bkf_pde_check(&p, &o, &e) == BKF_EINPUT && strstr(e.message, "continuum"));
    p.kind = BKF_MODEL_CONTINUUM;
    o.frame_speed = NAN;
    CHECK(bkf_pde_check(&p, &o, &e) == BKF_EINPUT && strstr(e.message, "frame"));
}

TEST(pde_refuses_a_pulling_rate_beyond_the_field_bound)
{
    /* nu 1e300 used to pass the check and fail the run with "the initial
     * state is not finite or too large": the cause is the parameter. */
    bkf_model_params p = bkf_model_params_paper();
    bkf_pde_options o = bkf_pde_options_default();
    bkf_error e;
    const double bad[] = {1e300, -1e300, 101, NAN, INFINITY};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        p.nu = bad[i];
        CHECK_STATUS(bkf_pde_check(&p, &o, &e), BKF_EINPUT);
        CHECK_MSG(strncmp(e.message, "nu = ", 5) == 0 && strstr(e.message, "[-100, 100]"), "%s",
                  e.message);
    }
    p.nu = -100;
    CHECK_STATUS(bkf_pde_check(&p, &o, &e), BKF_OK);
    bkf_cli_result r = BKF_CLI("simulate", "--nu", "1e300", "--tmax", "1");
    CHECK_MSG(r.code == 2 && r.out[0] == '\0' && strstr(r.err, "--nu"), "%d %s", r.code, r.err);
    bkf_cli_result_free(&r);
}

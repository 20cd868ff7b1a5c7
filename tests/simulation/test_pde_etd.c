/* The exponential integrators (steppers etdrk4 and lawson8) against
 * independent facts:
 * the cycle engine's period, the explicit rk8pd stepper on the same
 * problem, exact steady states (continuous slip; the travelling wave in
 * its own frame, with the speeds solver's v), the sample times asked for,
 * and the inputs it refuses. */
#include "harness.h"

#include <stdlib.h>
#include <string.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#include <fftw3.h>

#include "bkfront/cycle.h"
#include "bkfront/fft.h"
#include "bkfront/measure.h"
#include "bkfront/pde.h"
#include "bkfront/seed.h"
#include "pde_support.h"

static bkf_pde *make(double nu, size_t N, bkf_pde_stepper stepper, double tol, double frame)
{
    bkf_model_params p = {2, 0.3, nu, 20, N, BKF_MODEL_CONTINUUM};
    bkf_pde_options o = bkf_pde_options_default();
    o.tol = tol;
    o.stepper = stepper;
    o.frame_speed = frame;
    return alloc_pde(&p, &o);
}

/* The uniform oscillation is the van der Pol cycle at mu = gamma in t; here
 * everything but the k = 0 oscillator is in the explicit part. */
static void uniform_oscillation(bkf_pde_stepper stepper, double want)
{
    const double nu = -0.92;
    bkf_cycle_result cr;
    bkf_cycle_options co = bkf_cycle_options_default();
    co.tol = 1e-12;
    bkf_error e;
    CHECK_STATUS(bkf_cycle_period(2, nu, &co, &cr, &e), BKF_OK);
    bkf_pde *m = make(nu, 16, stepper, 1e-10, 0);
    CHECK_STATUS(bkf_pde_init_oscillation(m, 0, 0.0, &e), BKF_OK);
    bkf_measure *ms = make_measure(m, NULL);
    CHECK_STATUS(bkf_pde_run(m, 12 * cr.period, 0.05, measure_sample, ms, NULL, NULL, &e),
                 BKF_OK);
    bkf_measure_summary s;
    CHECK_STATUS(bkf_measure_summarize(ms, &s, &e), BKF_OK);
    CHECK(s.period_multiplicity == 1);
    CHECK(s.regime == BKF_REGIME_GLOBAL_OSCILLATION);
    double rel = (s.period - cr.period) / cr.period;
    CHECK_MSG(fabs(rel) < want, "period %.15g vs %.15g", s.period, cr.period);
    bkf_test_note("period %.15g vs %.15g (cycle engine), rel %.2g; %zu steps", s.period,
                  cr.period, rel, bkf_pde_get_stats(m)->steps);
    bkf_measure_free(ms);
    bkf_pde_free(m);
}

TEST(etd_uniform_oscillation_has_the_cycle_period) { uniform_oscillation(BKF_PDE_ETDRK4, 1e-7); }
/* the period from crossings interpolated between samples 0.05 apart:
 * 2e-8 is the Runge-Kutta path's bound (test_pde.c) */
TEST(lawson_uniform_oscillation_has_the_cycle_period)
{
    uniform_oscillation(BKF_PDE_LAWSON8, 2e-8);
}

/* A perturbed two-front wave in the lab frame, integrated by both
 * steppers: the fields agree to the looser tolerance's accuracy; lawson8's
 * quadratures agree with rk8pd's, H - D is conserved to the tolerance's
 * accuracy and the linear invariant to rounding (as on the Runge-Kutta
 * path, test_pde.c). */
static double agreement(bkf_pde_stepper stepper, double tol)
{
    enum { N = 256 };
    bkf_pde *runs[2] = {make(-0.96, N, stepper, tol, 0),
                        make(-0.96, N, BKF_PDE_RK8PD, 1e-13, 0)};
    bkf_pde_front_spec fs = bkf_pde_front_spec_default();
    fs.n = 2;
    fs.noise = 1e-3;
    bkf_error e;
    for (int k = 0; k < 2; k++) {
        CHECK_STATUS(bkf_seed_front(runs[k], &fs, NULL, NULL, &e), BKF_OK);
        CHECK_STATUS(bkf_pde_run(runs[k], 20, 1.0, NULL, NULL, NULL, NULL, &e), BKF_OK);
    }
    double diff = 0;
    const double *a = bkf_pde_psi(runs[0]), *b = bkf_pde_psi(runs[1]);
    const double *ea = bkf_pde_eta(runs[0]), *eb = bkf_pde_eta(runs[1]);
    for (size_t i = 0; i < N; i++) diff = fmax(diff, fmax(fabs(a[i] - b[i]), fabs(ea[i] - eb[i])));
    CHECK(bkf_pde_time(runs[0]) == 20);
    const bkf_pde_stats *se = bkf_pde_get_stats(runs[0]), *sr = bkf_pde_get_stats(runs[1]);
    bkf_test_note("tol %g: max |fields - rk8pd (tol 1e-13)| = %.2g at t = 20; steps %zu vs %zu",
                  tol, diff, se->steps, sr->steps);
    if (stepper == BKF_PDE_ETDRK4) {
        /* the quadratures are not tracked by this stepper, and say so */
        CHECK(isnan(bkf_pde_mean_integral(runs[0])) && isnan(bkf_pde_energy_residual(runs[0])));
    } else {
        double dD = bkf_pde_dissipation(runs[0]) - bkf_pde_dissipation(runs[1]);
        double dQ = bkf_pde_mean_integral(runs[0]) - bkf_pde_mean_integral(runs[1]);
        double res = bkf_pde_energy_residual(runs[0]), mres = bkf_pde_mean_residual(runs[0]);
        bkf_test_note("tol %g: D - D(rk8pd) %.2g, Q - Q(rk8pd) %.2g, H - H0 - D %.2g "
                      "(rk8pd at 1e-13: %.2g), mean residual %.2g",
                      tol, dD, dQ, res, bkf_pde_energy_residual(runs[1]), mres);
        CHECK_MSG(fabs(dD) < 1e2 * tol && fabs(res) < 1e2 * tol, "D off by %g, residual %g", dD,
                  res);
        CHECK_MSG(fabs(dQ) < 1e-10 && fabs(mres) < 1e-12, "Q off by %g, mean residual %g", dQ,
                  mres);
    }
    bkf_pde_free(runs[0]);
    bkf_pde_free(runs[1]);
    return diff;
}

/* lawson8's rates of Q and D (Parseval sums in k) against the Runge-Kutta
 * path's (sums in x; the moving frame's general dH/dt): from one state,
 * with and without the filter and in a moving frame, both at tol 1e-13
 * over t = 0.1, the quadratures agree to rounding. */
TEST(lawson_quadratures_are_the_runge_kutta_paths)
{
    enum { N = 256 };
    bkf_pde *src = make(-0.96, N, BKF_PDE_LAWSON8, 1e-7, 0);
    bkf_pde_front_spec fs = bkf_pde_front_spec_default();
    fs.n = 4;
    fs.noise = 1e-3;
    bkf_error e;
    CHECK_STATUS(bkf_seed_front(src, &fs, NULL, NULL, &e), BKF_OK);
    CHECK_STATUS(bkf_pde_run(src, 5, 5, NULL, NULL, NULL, NULL, &e), BKF_OK);
    const struct {
        double filter, V;
    } cases[] = {{4, 0}, {0, 0}, {4, -1.2}};
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        bkf_pde *runs[2];
        for (int k = 0; k < 2; k++) {
            bkf_model_params p = {2, 0.3, -0.96, 20, N, BKF_MODEL_CONTINUUM};
            bkf_pde_options o = bkf_pde_options_default();
            o.tol = 1e-13;
            o.stepper = k ? BKF_PDE_RK8PD : BKF_PDE_LAWSON8;
            o.filter = cases[c].filter;
            o.frame_speed = cases[c].V;
            runs[k] = alloc_pde(&p, &o);
            CHECK_STATUS(bkf_pde_set_state(runs[k], bkf_pde_psi(src), bkf_pde_eta(src), 0, &e),
                         BKF_OK);
            CHECK_STATUS(bkf_pde_run(runs[k], 0.1, 0.1, NULL, NULL, NULL, NULL, &e), BKF_OK);
        }
        double D = bkf_pde_dissipation(runs[1]), Q = bkf_pde_mean_integral(runs[1]);
        double dD = bkf_pde_dissipation(runs[0]) - D, dQ = bkf_pde_mean_integral(runs[0]) - Q;
        bkf_test_note("filter %g, V %g: D %.6g (rk8pd), lawson8's off by %.2g; Q %.6g, off by "
                      "%.2g", cases[c].filter, cases[c].V, D, dD, Q, dQ);
        CHECK_MSG(fabs(D) > 1e-3 && fabs(dD) < 1e-12, "D %g vs %g", D + dD, D);
        CHECK_MSG(fabs(dQ) < 1e-13, "Q %g vs %g", Q + dQ, Q);
        bkf_pde_free(runs[0]);
        bkf_pde_free(runs[1]);
    }
    bkf_pde_free(src);
}

/* D by the quadrature over lawson8's step ends, against rk8pd at tol
 * 1e-12 on the same seeded n = 4 front (t = 20, tol 1e-9): on N 1024
 * (resolved) the ends carry D (stats.d_err > 0) at the fields' steps of
 * 0.025; on N 512 the seed is not resolved, D'(t) oscillates as the
 * fronts cross grid points (the ends alone gave D 3.5e-5 off) and the
 * stages must take D over.  Both: D within 100 tol of rk8pd's, H - H0 - D
 * likewise, the linear invariant to rounding; the ends' summed estimate
 * (their share of D's error) under that bound too, and none on N 512. */
TEST(lawson_dissipation_by_the_step_ends)
{
    const size_t Ns[2] = {1024, 512};
    for (int g = 0; g < 2; g++) {
        bkf_pde *runs[2] = {make(-0.96, Ns[g], BKF_PDE_LAWSON8, 1e-9, 0),
                            make(-0.96, Ns[g], BKF_PDE_RK8PD, 1e-12, 0)};
        bkf_pde_front_spec fs = bkf_pde_front_spec_default();
        fs.n = 4;
        bkf_error e;
        for (int k = 0; k < 2; k++) {
            CHECK_STATUS(bkf_seed_front(runs[k], &fs, NULL, NULL, &e), BKF_OK);
            CHECK_STATUS(bkf_pde_run(runs[k], 20, 0.1, NULL, NULL, NULL, NULL, &e), BKF_OK);
        }
        const bkf_pde_stats *st = bkf_pde_get_stats(runs[0]);
        double dD = bkf_pde_dissipation(runs[0]) - bkf_pde_dissipation(runs[1]);
        double res = bkf_pde_energy_residual(runs[0]), mres = bkf_pde_mean_residual(runs[0]);
        bkf_test_note("N %zu: %zu steps, d_err %.2g; D - D(rk8pd) %.2g, H - H0 - D %.2g, mean "
                      "residual %.2g", Ns[g], st->steps, st->d_err, dD, res, mres);
        CHECK_MSG(fabs(dD) < 1e-7 && fabs(res) < 1e-7, "D off by %g, residual %g", dD, res);
        CHECK_MSG(fabs(mres) < 1e-12, "mean residual %g", mres);
        if (g == 0) {
            CHECK_MSG(st->d_err > 0 && st->d_err < 1e-7, "d_err %g", st->d_err);
            CHECK_MSG(st->steps <= 810, "%zu steps (the fields' 0.025: 800)", st->steps);
        } else {
            CHECK_MSG(st->d_err == 0, "d_err %g: the ends kept D", st->d_err);
        }
        bkf_pde_free(runs[0]);
        bkf_pde_free(runs[1]);
    }
}

TEST(etd_agrees_with_rk8pd)
{
    double diff = agreement(BKF_PDE_ETDRK4, 1e-9);
    CHECK_MSG(diff < 1e-6, "max |ETD - rk8pd| = %g at t = 20", diff);
}

/* The tolerance contract: the error over t = 20 (about 2 periods, where
 * the perturbation grows) follows tol down, within a factor 1000 of it as
 * the Runge-Kutta steppers' global error is. */
TEST(lawson_agrees_with_rk8pd_and_follows_tol)
{
    double prev = INFINITY;
    for (double tol = 1e-7; tol > 1e-12; tol *= 1e-2) {
        double diff = agreement(BKF_PDE_LAWSON8, tol);
        CHECK_MSG(diff < 1e3 * tol, "tol %g: max |lawson8 - rk8pd| = %g", tol, diff);
        /* below 1e-11 the error is the reference's own (lawson8's fields are
         * more accurate than tol: its steps are set by the quadrature D) */
        CHECK_MSG(diff < prev || diff < 1e-11, "tol %g: error %g did not fall (was %g)", tol,
                  diff, prev);
        prev = diff;
    }
}

/* Continuous slip (|nu| > 1) is a fixed point with psi = nu, eta =
 * phi(nu): every ETD stage returns it, so long steps keep it to rounding
 * (the constant forcing nu/gamma and the k = 0 oscillator must balance). */
static void continuous_slip(bkf_pde_stepper stepper, double drift, double h_max)
{
    bkf_pde *m = make(-1.5, 64, stepper, 1e-9, 0);
    bkf_error e;
    CHECK_STATUS(bkf_pde_run(m, 50, 5.0, NULL, NULL, NULL, NULL, &e), BKF_OK);
    double dev = 0, eta0 = -1.5 * -1.5 * -1.5 / 3 + 1.5;
    for (size_t i = 0; i < 64; i++)
        dev = fmax(dev, fmax(fabs(bkf_pde_psi(m)[i] + 1.5), fabs(bkf_pde_eta(m)[i] - eta0)));
    CHECK_MSG(dev < drift, "continuous slip drifted by %g", dev);
    CHECK_MSG(bkf_pde_get_stats(m)->h_max >= h_max, "h_max %g", bkf_pde_get_stats(m)->h_max);
    bkf_pde_free(m);
}

TEST(etd_keeps_continuous_slip_exactly) { continuous_slip(BKF_PDE_ETDRK4, 1e-13, 0.99); }
/* An integrating-factor method does not keep the steady states of
 * L u + N(u) = 0 exactly (its stages rotate N(u) away from -L u): the
 * fixed point is kept to the tolerance, 1e-9 here, with steps of 0.2
 * (where the explicit stepper's cap on N 64 is 0.45). */
TEST(lawson_keeps_continuous_slip_to_tol) { continuous_slip(BKF_PDE_LAWSON8, 1e-9, 0.15); }

/* In the frame of the speeds solver's v the seeded wave stands still, and
 * the steps are not capped by the grid: on N = 4096 the explicit stepper's
 * stability cap is kappa / (omega_max + v q_max) ~ 0.01. */
static void front_stands_still(bkf_pde_stepper stepper, double h_max)
{
    enum { N = 4096 };
    bkf_pde *probe = make(-0.96, 512, BKF_PDE_RK8PD, 1e-9, 0);
    bkf_pde_front_spec fs = bkf_pde_front_spec_default();
    fs.n = 4;
    fs.noise = 1e-6;
    bkf_pde_front_info fi;
    bkf_error e;
    CHECK_STATUS(bkf_seed_front(probe, &fs, &fi, NULL, &e), BKF_OK);
    bkf_pde_free(probe);
    bkf_pde *m = make(-0.96, N, stepper, 1e-7, -fi.v);
    static double clean[N];
    CHECK_STATUS(bkf_seed_front(m, &fs, &fi, clean, &e), BKF_OK);
    bkf_measure *ms = make_measure(m, clean);
    CHECK_STATUS(bkf_pde_run(m, 40, 0.25, measure_sample, ms, NULL, NULL, &e), BKF_OK);
    bkf_measure_summary s;
    CHECK_STATUS(bkf_measure_summarize(ms, &s, &e), BKF_OK);
    CHECK(s.fronts_start == 4 && s.fronts_end == 4 && s.count_constant);
    double rel = -s.speed / fi.v;
    CHECK_MSG(fabs(rel) < 1e-8, "speed in the frame %.3g (relative %.3g)", s.speed, rel);
    CHECK(s.deviation_end < 1e-4);
    const bkf_pde_stats *st = bkf_pde_get_stats(m);
    double cap = 3.0 / (sqrt(1 + 0.09 * pow(M_PI * N / 20, 2)) + fi.v * M_PI * N / 20);
    CHECK_MSG(st->h_max >= h_max && st->steps < 40 / (4 * cap), "h_max %g, %zu steps (cap %g)",
              st->h_max, st->steps, cap);
    bkf_test_note("n = 4 on N = %d in the frame of v_pred: drift %.2g relative, %zu steps "
                  "(h_max %.3g; the explicit cap would be %.3g)",
                  N, rel, st->steps, st->h_max, cap);
    bkf_measure_free(ms);
    bkf_pde_free(m);
}

TEST(etd_moving_frame_front_stands_still_with_long_steps)
{
    front_stands_still(BKF_PDE_ETDRK4, 0.25);
}
/* not a steady state of lawson8's stages (see above): its steps stay
 * shorter than etdrk4's here, 0.04 (6 times the explicit cap) */
TEST(lawson_moving_frame_front_stands_still_with_long_steps)
{
    front_stands_still(BKF_PDE_LAWSON8, 0.03);
}

typedef struct {
    double t[64];
    size_t n;
} times;

static int record_time(const bkf_pde_sample *s, void *data)
{
    times *tt = data;
    if (tt->n < 64) tt->t[tt->n] = s->t;
    tt->n++;
    CHECK(isfinite(s->psi[0]) && isfinite(s->eta[0]));
    return 0;
}

/* Samples at t0 + k dt and once at t_end, as with the Runge-Kutta loop,
 * also when dt does not divide the span and when the run continues. */
static void samples_at_asked_times(bkf_pde_stepper stepper)
{
    bkf_pde *m = make(-0.96, 64, stepper, 1e-8, 0);
    bkf_error e;
    CHECK_STATUS(bkf_pde_init_uniform(m, 1e-2, 3, &e), BKF_OK);
    times tt = {{0}, 0};
    CHECK_STATUS(bkf_pde_run(m, 2.5, 0.7, record_time, &tt, NULL, NULL, &e), BKF_OK);
    double want[] = {0, 0.7, 1.4, 2.1, 2.5};
    CHECK_MSG(tt.n == 5, "%zu samples", tt.n);
    for (size_t k = 0; k < 5 && k < tt.n; k++) CHECK_CLOSE(tt.t[k], want[k], 0, 1e-14);
    tt.n = 0;
    CHECK_STATUS(bkf_pde_run(m, 4.5, 1.0, record_time, &tt, NULL, NULL, &e), BKF_OK);
    CHECK_MSG(tt.n == 3 && tt.t[0] == 2.5 && tt.t[2] == 4.5, "%zu samples", tt.n);
    CHECK(bkf_pde_time(m) == 4.5);
    bkf_pde_free(m);
}

TEST(etd_samples_at_the_asked_times) { samples_at_asked_times(BKF_PDE_ETDRK4); }
TEST(lawson_samples_at_the_asked_times) { samples_at_asked_times(BKF_PDE_LAWSON8); }

TEST(etd_refuses_what_it_does_not_cover)
{
    bkf_model_params chain = {2, 0.3, -0.96, 20, 20, BKF_MODEL_CHAIN};
    bkf_pde_options o = bkf_pde_options_default();
    o.stepper = BKF_PDE_ETDRK4;
    bkf_error e;
    CHECK(bkf_pde_check(&chain, &o, &e) == BKF_EINPUT && strstr(e.message, "continuum"));
    bkf_model_params cont = {2, 0.3, -0.96, 20, 64, BKF_MODEL_CONTINUUM};
    o.dealias = 1;
    CHECK(bkf_pde_check(&cont, &o, &e) == BKF_EINPUT && strstr(e.message, "dealias"));
    o.dealias = 0;
    o.stepper = (bkf_pde_stepper)9;
    CHECK(bkf_pde_check(&cont, &o, &e) == BKF_EINPUT && strstr(e.message, "etdrk4") &&
          strstr(e.message, "lawson8"));
    o.stepper = BKF_PDE_LAWSON8;
    CHECK(bkf_pde_check(&chain, &o, &e) == BKF_EINPUT && strstr(e.message, "lawson8 stepper"));
    o.dealias = 1;
    CHECK(bkf_pde_check(&cont, &o, &e) == BKF_EINPUT && strstr(e.message, "dealias"));
}

/* The point of lawson8: in the lab frame, where the fronts move through
 * the grid, its steps are set by the dynamics and tol, not by N: the same
 * count on N 1024, 8192 and 16384 (the explicit rk8pd's cap, 3/omega_max,
 * is 0.06, 0.008 and 0.004 there), and the speed agrees with the speeds
 * solver's.  On N 16384 the fastest modes turn by w h > 3.5 pi a step
 * (before their cross-branch coupling was averaged, they grew from
 * rounding and the steps fell to 0.01, twice those on N 1024); the field there must
 * still be the one of N 8192, where nothing is averaged, at the shared
 * points: to 1e-11 (5.7e-13 measured; the modes left out of the explicit
 * term's input move it by 2e-12 at most at FAST_DROP 1e-4), though on
 * N 16384 the stages form that term on 6144 points (product_grid) and on
 * N 8192 on its own 8192. */
TEST(lawson_steps_do_not_depend_on_N)
{
    enum { RUNS = 3 };
    size_t steps[RUNS], points[RUNS];
    size_t Ns[RUNS] = {1024, 8192, 16384};
    double *psi[RUNS] = {NULL};
    for (int k = 0; k < RUNS; k++) {
        bkf_pde *m = make(-0.96, Ns[k], BKF_PDE_LAWSON8, 1e-9, 0);
        bkf_pde_front_spec fs = bkf_pde_front_spec_default();
        fs.n = 4;
        bkf_pde_front_info fi;
        bkf_error e;
        double *clean = malloc(Ns[k] * sizeof *clean);
        CHECK_STATUS(bkf_seed_front(m, &fs, &fi, clean, &e), BKF_OK);
        bkf_measure *ms = make_measure(m, clean);
        CHECK_STATUS(bkf_pde_run(m, 10, 0.1, measure_sample, ms, NULL, NULL, &e), BKF_OK);
        bkf_measure_summary s;
        CHECK_STATUS(bkf_measure_summarize(ms, &s, &e), BKF_OK);
        double rel = (-s.speed - fi.v) / fi.v;
        CHECK_MSG(fabs(rel) < 1e-9 && s.count_constant, "N %zu: speed %.15g vs %.15g", Ns[k],
                  -s.speed, fi.v);
        steps[k] = bkf_pde_get_stats(m)->steps;
        points[k] = bkf_pde_get_stats(m)->product_points;
        double cap = 3.0 / sqrt(1 + 0.09 * pow(M_PI * (double)Ns[k] / 20, 2));
        bkf_test_note("N %zu: %zu steps (h_max %.3g; rk8pd's cap %.3g), speed rel %.2g; "
                      "product on %zu points", Ns[k], steps[k], bkf_pde_get_stats(m)->h_max, cap,
                      rel, points[k]);
        psi[k] = malloc(Ns[k] * sizeof *psi[k]);
        memcpy(psi[k], bkf_pde_psi(m), Ns[k] * sizeof *psi[k]);
        bkf_measure_free(ms);
        bkf_pde_free(m);
        free(clean);
    }
    for (int k = 1; k < RUNS; k++)
        CHECK_MSG(steps[k] <= steps[0] + steps[0] / 10, "steps %zu (N 1024) vs %zu (N %zu)",
                  steps[0], steps[k], Ns[k]);
    CHECK_MSG(points[1] == Ns[1] && points[2] < Ns[1], "product on %zu (N 8192), %zu (N 16384)",
              points[1], points[2]);
    double diff = 0;
    for (size_t i = 0; i < Ns[1]; i++) diff = fmax(diff, fabs(psi[1][i] - psi[2][2 * i]));
    bkf_test_note("max |psi(N 16384) - psi(N 8192)| = %.2g at t = 10", diff);
    CHECK_MSG(diff < 1e-11, "N 16384 vs 8192: %g", diff);
    for (int k = 0; k < RUNS; k++) free(psi[k]);
}

/* A seeded front on N 65536 is the cycle's profile to the cycle's
 * tolerance, and its spectrum above the front's (k >= 2048 of 32769, where
 * the n = 4 front at S 20 has fallen below 1e-15) holds rounding only: the
 * sum (2/N) sum |Re| + |Im| over those modes, the bound lawson8 puts on
 * what it leaves out of the explicit term, was 4e-12 when the profile's
 * pointwise rounding (3e-14, white) and the seam at the wrap filled them,
 * and the fast set was averaged, at three times a step's transforms, for
 * the first 440 steps. */
TEST(front_seed_on_a_fine_grid_holds_no_rounding_tail)
{
    const size_t N = 65536, nc = N / 2 + 1;
    bkf_pde *m = make(-0.96, N, BKF_PDE_LAWSON8, 1e-9, 0);
    bkf_pde_front_spec fs = bkf_pde_front_spec_default();
    fs.n = 4;
    bkf_pde_front_info fi;
    bkf_error e;
    CHECK_STATUS(bkf_seed_front(m, &fs, &fi, NULL, &e), BKF_OK);
    const double *psi = bkf_pde_psi(m);

    bkf_cycle *cy = bkf_cycle_alloc();
    bkf_cycle_options co = bkf_cycle_options_default();
    co.tol = fs.tol;
    CHECK_STATUS(bkf_cycle_solve(cy, fi.mu, -0.96, &co, &e), BKF_OK);
    double worst = 0.0, big = 1.0;
    for (size_t i = 0; i < N; i++) {
        double f, fp, z = (double)i * bkf_pde_spacing(m) / fi.v / fi.stretch;
        CHECK_STATUS(bkf_cycle_profile(cy, z, &f, &fp, &e), BKF_OK);
        worst = fmax(worst, fabs(psi[i] - f));
        big = fmax(big, fabs(f));
    }
    bkf_cycle_free(cy);

    double *in = fftw_alloc_real(N);
    fftw_complex *out = fftw_alloc_complex(nc);
    bkf_fft_lock();
    fftw_plan plan = fftw_plan_dft_r2c_1d((int)N, in, out, FFTW_ESTIMATE);
    bkf_fft_unlock();
    memcpy(in, psi, N * sizeof *in);
    fftw_execute(plan);
    double tail = 0.0;
    for (size_t k = 2048; k < nc; k++) tail += fabs(out[k][0]) + fabs(out[k][1]);
    tail *= 2.0 / (double)N;
    bkf_fft_lock();
    fftw_destroy_plan(plan);
    bkf_fft_unlock();
    fftw_free(in);
    fftw_free(out);
    bkf_test_note("seed vs profile %.2g (tol %.0e x %.3g); tail from k 2048: %.2g", worst, fs.tol,
                  big, tail);
    CHECK_MSG(worst <= fs.tol * big, "seed vs profile %g", worst);
    CHECK_MSG(tail < 1e-13, "rounding tail %g", tail);
    bkf_pde_free(m);
}

/* Each lawson8 step is 13 evaluations (rk8pd's 12 stages after the first
 * and the new end's rate, which starts the next step); a first stage is
 * re-evaluated only where the set left out of the explicit term changes.
 * The lowest mode that may be left out wanders by a few from step to step
 * on N 16384 (709, 713, 705, ...): following it re-evaluated a third of
 * the steps' first stages (13.5 evaluations a step over t = 10). */
TEST(lawson_evaluations_per_step_stay_thirteen)
{
    bkf_pde *m = make(-0.96, 16384, BKF_PDE_LAWSON8, 1e-9, 0);
    bkf_pde_front_spec fs = bkf_pde_front_spec_default();
    fs.n = 4;
    bkf_error e;
    CHECK_STATUS(bkf_seed_front(m, &fs, NULL, NULL, &e), BKF_OK);
    CHECK_STATUS(bkf_pde_run(m, 10, 0.1, NULL, NULL, NULL, NULL, &e), BKF_OK);
    const bkf_pde_stats *st = bkf_pde_get_stats(m);
    double per = (double)st->rhs_calls / (double)(st->steps + st->rejected);
    bkf_test_note("%zu steps, %zu rejected, %zu evaluations: %.3f a step", st->steps,
                  st->rejected, st->rhs_calls, per);
    CHECK_MSG(per < 13.05, "%.3f evaluations a step", per);
    bkf_pde_free(m);
}

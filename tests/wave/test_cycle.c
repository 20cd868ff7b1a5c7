/* The limit-cycle engine against independent values: a published period,
 * the small- and large-mu expansions, the nu -> -nu symmetry, Liouville's
 * formula against the variational equations, and the tolerance contract. */
#include "harness.h"

#include "bkfront/asymptotics.h"
#include "bkfront/cycle.h"

#include <gsl/gsl_math.h>
#include <string.h>

static bkf_cycle_result solve(double mu, double nu, double tol)
{
    bkf_cycle_options o = bkf_cycle_options_default();
    o.tol = tol;
    bkf_cycle_result r;
    bkf_error e;
    int rc = bkf_cycle_period(mu, nu, &o, &r, &e);
    CHECK_MSG(rc == BKF_OK, "mu = %g nu = %g tol = %g: %s", mu, nu, tol, e.message);
    return r;
}

/* T(1, 0) = 6.663286859323130 (published, e.g. Buonomo; Tobias et al.) */
TEST(cycle_period_matches_published_mu_1)
{
    const double published = 6.663286859323130;
    bkf_cycle_result r = solve(1.0, 0.0, 1e-12);
    CHECK_CLOSE(r.period, published, 1e-12, 0.0);
    CHECK(r.period_err >= fabs(r.period - published) / 10.0);
    bkf_test_note("T(1,0) = %.16g, err est %.2g, true err %.2g", r.period, r.period_err,
                  fabs(r.period - published));
}

/* T = 2 pi (1 + s2(nu) mu^2 + O(mu^4)): at mu = 1e-3 the remainder is ~1e-12. */
TEST(cycle_small_mu_limit)
{
    const double nus[] = {0.0, -0.5, 0.7, -0.96, 0.999};
    for (size_t i = 0; i < sizeof nus / sizeof nus[0]; i++) {
        bkf_cycle_result r = solve(1e-3, nus[i], 1e-12);
        CHECK_CLOSE(r.period, bkf_asym_period_small(1e-3, nus[i]), 2e-11, 0.0);
        /* harmonic amplitude 2 sqrt(1 - nu^2) about x = nu */
        double amp = 2.0 * sqrt(1.0 - nus[i] * nus[i]);
        CHECK_CLOSE(r.xmax, nus[i] + amp, 1e-3, 1e-3 * amp);
        CHECK_CLOSE(r.xmin, nus[i] - amp, 1e-3, 1e-3 * amp);
        /* Floquet exponent of the harmonic cycle: -2 pi mu (1 - nu^2) */
        CHECK_CLOSE(r.log_multiplier, -2.0 * M_PI * 1e-3 * (1.0 - nus[i] * nus[i]), 2e-3, 0.0);
    }
}

/* The derived mu^2 coefficient s2(nu) = (1 - nu^2)(3 + 29 nu^2)/48, checked
 * by the difference quotient (T/2pi - 1)/mu^2 at mu = 0.01, whose own
 * O(mu^2) error is ~1e-4 relative. */
TEST(cycle_small_mu_coefficient_derived_for_every_nu)
{
    const double nus[] = {0.0, 0.3, -0.6, 0.9};
    for (size_t i = 0; i < sizeof nus / sizeof nus[0]; i++) {
        double mu = 0.01;
        bkf_cycle_result r = solve(mu, nus[i], 1e-13);
        double quotient = (r.period / (2.0 * M_PI) - 1.0) / (mu * mu);
        CHECK_CLOSE(quotient, bkf_asym_small_coefficient(nus[i]), 2e-3, 0.0);
    }
}

/* nu = 0, large mu (Dorodnitsyn): T = (3 - 2 ln 2) mu + 3 a1 mu^(-1/3)
 * - (2/3) ln(mu)/mu + D/mu + ...; D = -1.3246 in the literature.  The
 * remainder after the log term is within 2/mu at mu = 1e3 and 1e4. */
TEST(cycle_large_mu_series_nu_0)
{
    const double mus[] = {1e3, 1e4};
    for (size_t i = 0; i < 2; i++) {
        bkf_cycle_result r = solve(mus[i], 0.0, 1e-11);
        double series = (3.0 - 2.0 * log(2.0)) * mus[i] + 3.0 * BKF_AIRY_A1 * pow(mus[i], -1.0 / 3.0) -
                        (2.0 / 3.0) * log(mus[i]) / mus[i];
        CHECK_CLOSE(bkf_asym_period_large(mus[i], 0.0), series, 1e-15, 0.0);
        double remainder = (r.period - series) * mus[i];
        bkf_test_note("mu = %g: T = %.15g, mu (T - series) = %.4f (literature D = -1.3246)", mus[i],
                      r.period, remainder);
        CHECK(fabs(remainder + 1.3246) < 0.2);
    }
}

/* T/mu -> k(nu), with the derived knee and log terms: the remainder of the
 * corrected series is O(1/mu), so T - T_asym2 shrinks about tenfold per
 * decade of mu, while T - k mu shrinks only as mu^(-1/3). */
TEST(cycle_large_mu_tends_to_k_nu)
{
    const double nus[] = {-0.96, -0.5, 0.3, 0.9};
    for (size_t i = 0; i < sizeof nus / sizeof nus[0]; i++) {
        bkf_cycle_result a = solve(1e3, nus[i], 1e-11), b = solve(1e4, nus[i], 1e-11);
        CHECK_CLOSE(b.period / 1e4, bkf_asym_k(nus[i]), 1e-3, 0.0);
        double ra = fabs(a.period - bkf_asym_period_large(1e3, nus[i]));
        double rb = fabs(b.period - bkf_asym_period_large(1e4, nus[i]));
        bkf_test_note("nu = %g: |T - T_asym2| = %.3g at 1e3, %.3g at 1e4", nus[i], ra, rb);
        CHECK(rb < ra / 4.0);
        CHECK(rb * 1e4 < 20.0);
    }
}

/* x -> -x, nu -> -nu maps the equation to itself with the same period. */
TEST(cycle_symmetry_nu_to_minus_nu)
{
    const double mus[] = {0.05, 2.0, 300.0};
    for (size_t i = 0; i < 3; i++) {
        bkf_cycle_result p = solve(mus[i], 0.8, 1e-10), m = solve(mus[i], -0.8, 1e-10);
        CHECK_CLOSE(p.period, m.period, 2e-10, 0.0);
        CHECK_CLOSE(p.xmax, -m.xmin, 1e-8, 1e-9);
        CHECK_CLOSE(p.log_multiplier, m.log_multiplier, 1e-8, 1e-12);
    }
}

/* Liouville (integral of the trace) and the variational return-map slope are
 * two independent routes to the nontrivial multiplier. */
TEST(cycle_multiplier_liouville_equals_variational)
{
    const double cases[][2] = {{0.1, 0.0}, {0.5, -0.9}, {1.0, 0.0}, {2.0, 0.5}, {1e-3, 0.999}};
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        bkf_cycle_result r = solve(cases[i][0], cases[i][1], 1e-11);
        CHECK_CLOSE(r.return_map_slope, r.multiplier, 1e-6, 1e-12);
        CHECK(r.multiplier > 0.0 && r.multiplier < 1.0);
    }
}

/* The contract: |T(tol) - T(1e-13)| <= tol T on a grid with every extreme,
 * and the estimate is never optimistic by more than 10.  Where 1e-13 itself
 * is refused as unreachable (the canard region, mu = 10, nu = 0.999, whose
 * rounding noise is ~2e-12 relative) the reference is T(1e-12); the refusal
 * is itself part of the contract: an error, not wrong digits. */
static bkf_cycle_result reference(double mu, double nu)
{
    bkf_cycle_options o = bkf_cycle_options_default();
    bkf_cycle_result r;
    bkf_error e;
    for (o.tol = 1e-13; o.tol < 2e-11; o.tol *= 10.0) {
        int rc = bkf_cycle_period(mu, nu, &o, &r, &e);
        if (rc == BKF_OK) {
            if (o.tol > 1e-13) bkf_test_note("mu %g nu %g: reference at tol %g", mu, nu, o.tol);
            return r;
        }
        CHECK_MSG(bkf_status_is_numerical(rc), "unexpected failure: %s", e.message);
    }
    bkf_test_fail(__FILE__, __LINE__, "mu %g nu %g: no reference below 1e-11", mu, nu);
}

TEST(cycle_tolerance_honoured_on_extremes)
{
    const double mus[] = {1e-3, 0.1, 1.0, 10.0, 100.0, 1e4};
    const double nus[] = {0.0, -0.96, 0.999, -0.999};
    const double tols[] = {1e-4, 1e-7, 1e-10};
    double worst_ratio = 0.0;
    for (size_t i = 0; i < 6; i++)
        for (size_t j = 0; j < 4; j++) {
            bkf_cycle_result ref = reference(mus[i], nus[j]);
            for (size_t k = 0; k < 3; k++) {
                bkf_cycle_result r = solve(mus[i], nus[j], tols[k]);
                double true_err = fabs(r.period - ref.period);
                CHECK_MSG(true_err <= tols[k] * ref.period,
                          "mu %g nu %g tol %g: |T - Tref| = %.3g > tol T", mus[i], nus[j], tols[k],
                          true_err);
                CHECK_MSG(true_err <= 10.0 * r.period_err + ref.period_err,
                          "mu %g nu %g tol %g: true error %.3g, estimate %.3g", mus[i], nus[j],
                          tols[k], true_err, r.period_err);
                double ratio = true_err / r.period_err;
                if (ratio > worst_ratio) worst_ratio = ratio;
            }
        }
    bkf_test_note("largest true/estimated error ratio: %.3g", worst_ratio);
}

/* From scratch (fresh object, no guess) over the whole box. */
TEST(cycle_converges_from_scratch_on_the_box)
{
    const double mus[] = {1e-3, 1e-2, 0.3, 3.0, 30.0, 300.0, 3e3, 1e4};
    const double nus[] = {-0.999, -0.99, -0.9, -0.5, 0.0, 0.5, 0.9, 0.99, 0.999};
    for (size_t i = 0; i < 8; i++)
        for (size_t j = 0; j < 9; j++) {
            bkf_cycle_result r = solve(mus[i], nus[j], 1e-8);
            CHECK(r.period > 2.0 * M_PI * 0.999);
            CHECK(r.xmax > nus[j] && r.xmin < nus[j]);
        }
}

TEST(cycle_profile_is_the_cycle)
{
    bkf_cycle *c = bkf_cycle_alloc();
    bkf_error e;
    bkf_cycle_options o = bkf_cycle_options_default();
    o.tol = 1e-11;
    CHECK_STATUS(bkf_cycle_solve(c, 3.0, -0.4, &o, &e), BKF_OK);
    const bkf_cycle_result *r = bkf_cycle_get(c);
    double f, fp, f2, fp2;
    CHECK_STATUS(bkf_cycle_profile(c, 0.0, &f, &fp, &e), BKF_OK);
    CHECK_CLOSE(f, -0.4, 0.0, 1e-12);
    CHECK(fp > 0.0);
    CHECK_STATUS(bkf_cycle_profile(c, 2.0 * r->period, &f2, &fp2, &e), BKF_OK);
    CHECK_CLOSE(f2, f, 0.0, 1e-9);
    CHECK_CLOSE(fp2, fp, 0.0, 1e-8);
    /* f' is the derivative of f (central differences) and the sampled
     * extremes approach xmax, xmin */
    double fmax = -10, fmin = 10;
    for (int i = 0; i < 4000; i++) {
        double z = r->period * i / 4000.0, h = 1e-5, fa, fb;
        CHECK_STATUS(bkf_cycle_profile(c, z, &f, &fp, &e), BKF_OK);
        if (i % 100 == 0) {
            CHECK_STATUS(bkf_cycle_profile(c, z + h, &fa, NULL, &e), BKF_OK);
            CHECK_STATUS(bkf_cycle_profile(c, z - h, &fb, NULL, &e), BKF_OK);
            CHECK_CLOSE((fa - fb) / (2 * h), fp, 1e-6, 1e-6);
        }
        if (f > fmax) fmax = f;
        if (f < fmin) fmin = f;
    }
    CHECK(fmax <= r->xmax + 1e-10 && fmax > r->xmax - 1e-4);
    CHECK(fmin >= r->xmin - 1e-10 && fmin < r->xmin + 1e-4);
    bkf_cycle_free(c);
}

/* A refused solve keeps the previous solution, its profile included: the
 * profile at z = 0 is still on the kept cycle's section (f = nu, f' its
 * section slope) and closes after a period, though the refused solve (the
 * canard at mu 3.6505, nu 0.99, tol 1e-10) had integrated other cycles. */
TEST(cycle_refused_solve_keeps_the_previous_profile)
{
    bkf_cycle *c = bkf_cycle_alloc();
    bkf_error e;
    bkf_cycle_options o = bkf_cycle_options_default();
    CHECK_STATUS(bkf_cycle_solve(c, 2.0, -0.3, &o, &e), BKF_OK);
    const bkf_cycle_result *r = bkf_cycle_get(c);
    double slope = r->section_slope, period = r->period;
    int rc = bkf_cycle_solve(c, 3.65051977535718, 0.99, &o, &e);
    CHECK_MSG(bkf_status_is_numerical(rc), "the canard point was answered (%d): pick a refused one", rc);
    r = bkf_cycle_get(c);
    CHECK(r->mu == 2.0 && r->nu == -0.3);
    double f, fp, f2;
    CHECK_STATUS(bkf_cycle_profile(c, 0.0, &f, &fp, &e), BKF_OK);
    CHECK_CLOSE(f, -0.3, 0.0, 1e-12);
    CHECK_CLOSE(fp, slope, 1e-10, 1e-10);
    CHECK_STATUS(bkf_cycle_profile(c, 0.37 * period, &f, NULL, &e), BKF_OK);
    CHECK_STATUS(bkf_cycle_profile(c, 1.37 * period, &f2, NULL, &e), BKF_OK);
    CHECK_CLOSE(f2, f, 1e-9, 1e-9);
    bkf_cycle_free(c);
}

TEST(cycle_warm_start_agrees_with_cold)
{
    bkf_cycle *c = bkf_cycle_alloc();
    bkf_error e;
    bkf_cycle_options o = bkf_cycle_options_default();
    for (double mu = 0.5; mu < 60.0; mu *= 1.7) {
        CHECK_STATUS(bkf_cycle_solve(c, mu, -0.96, &o, &e), BKF_OK);
        bkf_cycle_result cold = solve(mu, -0.96, 1e-10);
        CHECK_CLOSE(bkf_cycle_get(c)->period, cold.period, 2e-10, 0.0);
    }
    bkf_cycle_free(c);
}

TEST(cycle_rejects_bad_input)
{
    bkf_cycle_options o = bkf_cycle_options_default();
    bkf_cycle_result r;
    bkf_error e;
    CHECK_STATUS(bkf_cycle_period(0.0, 0.0, &o, &r, &e), BKF_EINPUT);
    CHECK(strstr(e.message, "mu"));
    CHECK_STATUS(bkf_cycle_period(-1.0, 0.0, &o, &r, &e), BKF_EINPUT);
    CHECK_STATUS(bkf_cycle_period(NAN, 0.0, &o, &r, &e), BKF_EINPUT);
    CHECK_STATUS(bkf_cycle_period(INFINITY, 0.0, &o, &r, &e), BKF_EINPUT);
    CHECK_STATUS(bkf_cycle_period(1.0, 1.0, &o, &r, &e), BKF_EINPUT);
    CHECK(strstr(e.message, "nu") && strstr(e.message, "continuous slip"));
    CHECK_STATUS(bkf_cycle_period(1.0, -1.2, &o, &r, &e), BKF_EINPUT);
    CHECK_STATUS(bkf_cycle_period(1.0, NAN, &o, &r, &e), BKF_EINPUT);
    o.tol = 1.0;
    CHECK_STATUS(bkf_cycle_period(1.0, 0.0, &o, &r, &e), BKF_EINPUT);
    CHECK(strstr(e.message, "tol"));
    o.tol = 1e-15;
    CHECK_STATUS(bkf_cycle_period(1.0, 0.0, &o, &r, &e), BKF_EINPUT);
    bkf_cycle *c = bkf_cycle_alloc();
    CHECK_STATUS(bkf_cycle_profile(c, 0.0, NULL, NULL, &e), BKF_EINPUT);
    bkf_cycle_free(c);
}

TEST(cycle_messages_keep_the_digits_of_the_parameters)
{
    /* A refusal at nu = 0.99999999 names that nu, not "nu = 1" (%g's six
     * digits made a value inside the active range read as its edge). */
    bkf_cycle_options o = bkf_cycle_options_default();
    o.tol = 1e-14;
    bkf_cycle_result r;
    bkf_error e;
    int s = bkf_cycle_period(64.6885094197501, 0.99999999, &o, &r, &e);
    CHECK_MSG(s != BKF_OK, "tol 1e-14 at the canard should be refused");
    CHECK_MSG(strstr(e.message, "nu = 0.99999999") != NULL, "%s", e.message);
    CHECK(strstr(e.message, "nu = 1:") == NULL && strstr(e.message, "nu = 1 ") == NULL);
}

TEST(cycle_profile_finite_on_stiff_cycles)
{
    /* mu 50..100, |nu| 0.5..0.9: the explicit profile stepper blew up on
     * stretches of these cycles and NaN went out as f and f'.  Every point
     * is now finite, the profile's range is the solve's [xmin, xmax], and
     * f' agrees with a difference quotient of f. */
    const double mus[] = {50, 75, 100}, nus[] = {-0.9, -0.5, 0.5};
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            bkf_cycle *c = bkf_cycle_alloc();
            bkf_cycle_options o = bkf_cycle_options_default();
            o.tol = 1e-8;
            bkf_error e;
            CHECK_STATUS(bkf_cycle_solve(c, mus[i], nus[j], &o, &e), BKF_OK);
            const bkf_cycle_result *r = bkf_cycle_get(c);
            double lo = INFINITY, hi = -INFINITY;
            for (int k = 0; k < 2000; k++) {
                double z = r->period * k / 2000.0, f, fp, f2;
                CHECK_STATUS(bkf_cycle_profile(c, z, &f, &fp, &e), BKF_OK);
                CHECK_MSG(isfinite(f) && isfinite(fp), "mu %g nu %g z %g: f %g f' %g", mus[i],
                          nus[j], z, f, fp);
                lo = fmin(lo, f);
                hi = fmax(hi, f);
                if (k % 200 == 37) {
                    double dz = 1e-6 * r->period;
                    CHECK_STATUS(bkf_cycle_profile(c, z + dz, &f2, NULL, &e), BKF_OK);
                    CHECK_CLOSE((f2 - f) / dz, fp, 1e-2, 1e-2 * (1 + fabs(fp)));
                }
            }
            CHECK_CLOSE(hi, r->xmax, 0, 1e-2);
            CHECK_CLOSE(lo, r->xmin, 0, 1e-2);
            bkf_cycle_free(c);
        }
}

/* The batch profile (one pass) against the single-point profile (each
 * point integrated from its nearest node), and the mesh's ends. */
TEST(cycle_profile_sample_matches_single_points)
{
    bkf_cycle *cy = bkf_cycle_alloc();
    bkf_error e;
    CHECK(bkf_cycle_solve(cy, 5.0, 0.3, NULL, &e) == BKF_OK);
    double T = bkf_cycle_get(cy)->period;
    double z[50], f[50], fp[50];
    for (int i = 0; i < 50; i++) z[i] = T * i / 49.0;
    CHECK(bkf_cycle_profile_sample(cy, z, 50, f, fp, &e) == BKF_OK);
    for (int i = 0; i < 50; i++) {
        double f1, fp1;
        CHECK(bkf_cycle_profile(cy, z[i], &f1, &fp1, &e) == BKF_OK);
        CHECK_CLOSE(f[i], f1, 0, 1e-8);
        CHECK_CLOSE(fp[i], fp1, 0, 1e-7);
    }
    double zr[2] = {1.0, 0.5};
    CHECK(bkf_cycle_profile_sample(cy, zr, 2, f, fp, &e) == BKF_EINPUT);
    size_t count = bkf_cycle_mesh(cy, NULL, 0);
    CHECK(count > 10);
    double *mesh = malloc(count * sizeof *mesh);
    CHECK(bkf_cycle_mesh(cy, mesh, count) == count);
    CHECK(mesh[0] == 0.0 && mesh[count - 1] < T);
    for (size_t i = 1; i < count; i++) CHECK(mesh[i] > mesh[i - 1]);
    free(mesh);
    bkf_cycle_free(cy);
}

/* Points in any order and any period (a simulation's grid, z = -x / v
 * over n wavelengths, backwards) in one pass, against the single-point
 * profile, each integrated from its nearest node; f may be z itself. */
TEST(cycle_profile_points_any_order_and_period)
{
    bkf_cycle *cy = bkf_cycle_alloc();
    bkf_error e;
    CHECK(bkf_cycle_solve(cy, 5.0, 0.3, NULL, &e) == BKF_OK);
    double T = bkf_cycle_get(cy)->period;
    enum { N = 300 };
    double z[N], f[N], fp[N];
    for (int i = 0; i < N; i++) z[i] = -3.7 * T * i / (N - 1.0) + (i % 7 == 3 ? 9.0 * T : 0.0);
    CHECK(bkf_cycle_profile_points(cy, z, N, f, fp, &e) == BKF_OK);
    for (int i = 0; i < N; i++) {
        double f1, fp1;
        CHECK(bkf_cycle_profile(cy, z[i], &f1, &fp1, &e) == BKF_OK);
        CHECK_CLOSE(f[i], f1, 0, 1e-8);
        CHECK_CLOSE(fp[i], fp1, 0, 1e-7);
    }
    double zf[N];
    memcpy(zf, z, sizeof zf);
    CHECK(bkf_cycle_profile_points(cy, zf, N, zf, NULL, &e) == BKF_OK);
    for (int i = 0; i < N; i++) CHECK(zf[i] == f[i]);
    z[5] = NAN;
    CHECK(bkf_cycle_profile_points(cy, z, N, f, fp, &e) == BKF_EINPUT);
    CHECK(bkf_cycle_profile_points(cy, z, 0, f, fp, &e) == BKF_OK);
    bkf_cycle_free(cy);
}

/* Past mu 100 the profile's stepper is bsimp; points as dense as a
 * spectrum's Radau mesh (24000 over a period at mu 120.8, the paper
 * scene's n = 6 branch near the sonic limit) are sampled by rk8pd (27
 * times faster there): they must agree with single points, each
 * integrated by bsimp from its nearest node. */
TEST(cycle_profile_sample_dense_stiff_matches_single_points)
{
    bkf_cycle *cy = bkf_cycle_alloc();
    bkf_error e;
    bkf_cycle_options o = bkf_cycle_options_default();
    o.tol = 1e-12;
    o.stepper = BKF_STEPPER_IMPLICIT;
    CHECK(bkf_cycle_solve(cy, 120.8, -0.96, &o, &e) == BKF_OK);
    double T = bkf_cycle_get(cy)->period;
    enum { N = 24000 };
    double *z = malloc(N * sizeof *z), *f = malloc(N * sizeof *f), *fp = malloc(N * sizeof *fp);
    for (int i = 0; i < N; i++) z[i] = T * (i + 0.5) / N;
    CHECK(bkf_cycle_profile_sample(cy, z, N, f, fp, &e) == BKF_OK);
    /* every 97th point, through the jumps (|f'| up to 132) and the slow branches */
    for (int i = 0; i < N; i += 97) {
        double f1, fp1;
        CHECK(bkf_cycle_profile(cy, z[i], &f1, &fp1, &e) == BKF_OK);
        CHECK_CLOSE(f[i], f1, 0, 1e-10);
        CHECK_CLOSE(fp[i], fp1, 0, 1e-9 * (1.0 + fabs(fp1))); /* f' = y - mu F(f): mu times the state's */
    }
    free(z);
    free(f);
    free(fp);
    bkf_cycle_free(cy);
}

/* Hill's method against what holds whatever the numerics: the translation
 * eigenvalue 0 at theta = 0, the closed form at c = 0 (where the problem is
 * the cycle's own variational equation, multipliers 1 and exp(L)),
 * conjugation under theta -> -theta and periodicity in theta; its
 * exponential convergence in the number of modes; bad input. */
#include "harness.h"

#include "bkfront/hill.h"

#include <string.h>

#define TWO_PI 6.283185307179586476925286766559

/* The paper's trains (gamma 2, c 0.3, nu -0.96): mu and v of the speeds
 * table for n = 1 and n = 2 fronts. */
static const double paper_gamma = 2.0, paper_c = 0.3, paper_nu = -0.96;
static const double paper_mu[2] = {2.0238619104066755, 2.1226828809768215};
static const double paper_v[2] = {1.959422055120847, 0.89541512114820221};

static bkf_cycle *cycle_at(double mu, double nu)
{
    bkf_cycle *cy = bkf_cycle_alloc();
    CHECK(cy);
    bkf_cycle_options o = bkf_cycle_options_default();
    o.tol = 1e-12;
    bkf_error e;
    int rc = bkf_cycle_solve(cy, mu, nu, &o, &e);
    CHECK_MSG(rc == BKF_OK, "cycle mu %g nu %g: %s", mu, nu, e.message);
    return cy;
}

/* The whole spectrum at M modes (caller frees). */
static bkf_hill_eigenvalue *spectrum(bkf_cycle *cy, double gamma, double theta, size_t M, size_t *n)
{
    bkf_hill_eigenvalue *ev = malloc(sizeof *ev * 2 * (2 * M + 1));
    CHECK(ev);
    bkf_error e;
    int rc = bkf_hill_spectrum(cy, gamma, theta, M, ev, n, &e);
    CHECK_MSG(rc == BKF_OK, "theta %g M %zu: %s", theta, M, e.message);
    CHECK(*n == 2 * (2 * M + 1));
    for (size_t i = 1; i < *n; i++) CHECK(ev[i].re <= ev[i - 1].re);
    return ev;
}

static double nearest(const bkf_hill_eigenvalue *ev, size_t n, double re, double im)
{
    double best = INFINITY;
    for (size_t i = 0; i < n; i++) best = fmin(best, hypot(ev[i].re - re, ev[i].im - im));
    return best;
}

TEST(hill_translation_eigenvalue_is_zero)
{
    for (int t = 0; t < 2; t++) {
        /* the table's mu and v agree through mu = gamma / sqrt(1 - c^2/v^2),
         * which is all of c and v the spectrum needs */
        CHECK_CLOSE(paper_c / sqrt(1.0 - pow(paper_gamma / paper_mu[t], 2)), paper_v[t], 1e-12, 0);
        bkf_cycle *cy = cycle_at(paper_mu[t], paper_nu);
        size_t n;
        bkf_hill_eigenvalue *ev = spectrum(cy, paper_gamma, 0.0, 64, &n);
        double d = nearest(ev, n, 0.0, 0.0);
        bkf_test_note("n = %d fronts: |sigma| of the translation eigenvalue %.3g", t + 1, d);
        CHECK_MSG(d <= 1e-9, "n = %d: nearest eigenvalue to 0 at distance %.3g", t + 1, d);
        free(ev);
        bkf_cycle_free(cy);
    }
}

/* c = 0 (mu = gamma): p = exp(-sigma z) u turns the problem into the
 * cycle's variational equation, so sigma = (ln m - i (theta + 2 pi k))/T
 * with the multipliers m = 1 and exp(L). */
TEST(hill_c0_closed_form)
{
    const double cases[][3] = {{1.0, 0.0, 0.7}, {1.5, 0.5, 2.9}}; /* gamma = mu, nu, theta */
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        double gamma = cases[c][0], nu = cases[c][1], theta = cases[c][2];
        bkf_cycle *cy = cycle_at(gamma, nu);
        double T = bkf_cycle_get(cy)->period, L = bkf_cycle_get(cy)->log_multiplier;
        size_t n;
        bkf_hill_eigenvalue *ev = spectrum(cy, gamma, theta, 32, &n);
        double worst = 0;
        for (int k = -5; k <= 5; k++) {
            double im = -(theta + TWO_PI * k) / T;
            worst = fmax(worst, nearest(ev, n, 0.0, im));
            worst = fmax(worst, nearest(ev, n, L / T, im));
        }
        bkf_test_note("gamma %g nu %g: worst distance to the closed form (|k| <= 5) %.3g", gamma, nu, worst);
        CHECK_MSG(worst <= 1e-8, "gamma %g nu %g: an eigenvalue misses the closed form by %.3g", gamma, nu,
                  worst);
        /* the converged leading ones are those of the closed form, their
         * real parts 0 (the artefacts near the edge frequency, with real
         * parts above 0, are not among them) */
        bkf_hill_eigenvalue lead[6];
        double lead_err[6];
        size_t found, unresolved;
        bkf_error e;
        CHECK_STATUS(bkf_hill_leading(cy, gamma, theta, 32, 1e-8, 6, lead, lead_err, &found, &unresolved, &e),
                     BKF_OK);
        CHECK(found == 6);
        for (size_t i = 0; i < found; i++) {
            CHECK_MSG(fabs(lead[i].re) <= 1e-8 && lead_err[i] <= 1e-8, "leading %zu: %.17g%+.17gi (err %.3g)",
                      i, lead[i].re, lead[i].im, lead_err[i]);
            double k = -(lead[i].im * T + theta) / TWO_PI; /* an integer */
            CHECK_MSG(fabs(k - round(k)) <= 1e-8, "leading %zu: Im sigma %.17g is not -(theta + 2 pi k)/T", i,
                      lead[i].im);
        }
        bkf_test_note("gamma %g nu %g: %zu unconverged eigenvalues above the leading converged ones", gamma, nu,
                      unresolved);
        free(ev);
        bkf_cycle_free(cy);
    }
}

TEST(hill_converges_exponentially_in_modes)
{
    bkf_cycle *cy = cycle_at(paper_mu[0], paper_nu);
    double theta = TWO_PI / 3.0;
    bkf_hill_eigenvalue ref;
    double ref_err;
    size_t found;
    bkf_error e;
    CHECK_STATUS(bkf_hill_leading(cy, paper_gamma, theta, 64, 1e-9, 1, &ref, &ref_err, &found, NULL, &e),
                 BKF_OK);
    CHECK(found == 1);
    bkf_test_note("reference (M = 128): %.15g%+.15gi, estimate %.3g", ref.re, ref.im, ref_err);
    double errs[2];
    const size_t Ms[2] = {16, 48};
    for (int i = 0; i < 2; i++) {
        size_t n;
        bkf_hill_eigenvalue *ev = spectrum(cy, paper_gamma, theta, Ms[i], &n);
        errs[i] = nearest(ev, n, ref.re, ref.im);
        bkf_test_note("M = %zu: error %.3g", Ms[i], errs[i]);
        free(ev);
    }
    CHECK_MSG(errs[1] * 100 <= errs[0], "error at M 16 %.3g, at M 48 %.3g: less than 100-fold", errs[0], errs[1]);
    /* the estimate from 16 against 32 modes covers the error of what it
     * returns (the value at 32) */
    bkf_hill_eigenvalue v;
    double v_err;
    CHECK_STATUS(bkf_hill_leading(cy, paper_gamma, theta, 16, 1e-3, 1, &v, &v_err, &found, NULL, &e), BKF_OK);
    CHECK(found == 1);
    double actual = hypot(v.re - ref.re, v.im - ref.im);
    bkf_test_note("M = 32: error %.3g, estimate %.3g", actual, v_err);
    CHECK_MSG(actual <= v_err, "error %.3g above its estimate %.3g", actual, v_err);
    bkf_cycle_free(cy);
}

/* The matrix at -theta is the conjugate of that at theta with the modes
 * reversed (f is real); theta + 2 pi is theta with the modes shifted by
 * one, which the truncation sees only at its edge. */
TEST(hill_symmetries_in_theta)
{
    bkf_cycle *cy = cycle_at(paper_mu[1], paper_nu);
    const double theta = 1.1;
    size_t n, nm;
    bkf_hill_eigenvalue *ev = spectrum(cy, paper_gamma, theta, 32, &n);
    bkf_hill_eigenvalue *evm = spectrum(cy, paper_gamma, -theta, 32, &nm);
    double conj_worst = 0, self_conj_worst = 0;
    for (size_t i = 0; i < 20; i++) {
        double scale = 1.0 + hypot(ev[i].re, ev[i].im);
        conj_worst = fmax(conj_worst, nearest(evm, nm, ev[i].re, -ev[i].im) / scale);
        self_conj_worst = fmax(self_conj_worst, nearest(ev, n, ev[i].re, -ev[i].im));
    }
    bkf_test_note("-theta against conj(theta): %.3g; theta against its own conjugate: %.3g", conj_worst,
                  self_conj_worst);
    CHECK_MSG(conj_worst <= 1e-9, "spectrum at -theta misses the conjugate by %.3g", conj_worst);
    /* and the test can tell: at theta not 0 or pi the spectrum is not
     * conjugate-symmetric itself */
    CHECK_MSG(self_conj_worst > 1e-3, "spectrum at theta %g is conjugate-symmetric (%.3g)", theta,
              self_conj_worst);
    /* periodicity: the converged leading eigenvalues agree */
    bkf_hill_eigenvalue lead[8], leadp[8];
    double err[8], errp[8];
    size_t found, foundp;
    bkf_error e;
    CHECK_STATUS(bkf_hill_leading(cy, paper_gamma, theta, 32, 1e-6, 8, lead, err, &found, NULL, &e), BKF_OK);
    CHECK_STATUS(bkf_hill_leading(cy, paper_gamma, theta + TWO_PI, 32, 1e-6, 8, leadp, errp, &foundp, NULL, &e),
                 BKF_OK);
    CHECK(found == 8 && foundp == 8);
    for (size_t i = 0; i < found; i++) {
        double d = hypot(lead[i].re - leadp[i].re, lead[i].im - leadp[i].im);
        bkf_test_note("%.15g%+.15gi (estimate %.2g): theta + 2 pi differs by %.2g", lead[i].re, lead[i].im,
                      err[i], d);
        CHECK_MSG(d <= 1e-9, "theta + 2 pi misses %.17g%+.17gi by %.3g", lead[i].re, lead[i].im, d);
    }
    free(ev);
    free(evm);
    bkf_cycle_free(cy);
}

/* At theta = 0 the operator is real and the spectrum is solved by dgeev in
 * the cosine/sine basis; at theta = 1e-13 (the same truncation, the
 * eigenvalues moved by about that) by zgeev in the exponential one: two
 * routes that must give one spectrum, every eigenvalue of the truncation,
 * artefacts included (theta = 2 pi, the same Bloch wave, shifts the
 * truncation's window by a mode: its artefacts differ). */
TEST(hill_real_basis_at_theta_0_is_the_complex_one)
{
    bkf_cycle *cy = cycle_at(paper_mu[1], paper_nu);
    size_t n, n2;
    bkf_hill_eigenvalue *re = spectrum(cy, paper_gamma, 0.0, 24, &n);
    bkf_hill_eigenvalue *cx = spectrum(cy, paper_gamma, 1e-13, 24, &n2);
    CHECK(n == n2 && n == 2 * (2 * 24 + 1));
    double worst = 0;
    for (size_t i = 0; i < n; i++)
        worst = fmax(worst, nearest(cx, n2, re[i].re, re[i].im) / (1.0 + hypot(re[i].re, re[i].im)));
    bkf_test_note("%zu eigenvalues, worst relative distance %.3g", n, worst);
    CHECK_MSG(worst <= 1e-9, "theta 0 and 1e-13 differ by %.3g", worst);
    free(re);
    free(cx);
    bkf_cycle_free(cy);
}

TEST(hill_refuses_bad_input)
{
    bkf_cycle *cy = cycle_at(paper_mu[0], paper_nu);
    bkf_cycle *empty = bkf_cycle_alloc();
    CHECK(empty);
    bkf_hill_eigenvalue ev[2 * (2 * 8 + 1)];
    size_t count = 99, found = 99;
    bkf_error e;
    const struct {
        bkf_cycle *cycle;
        double gamma, theta;
        size_t modes;
        const char *name;
    } bad[] = {
        {cy, 0.0, 0.0, 8, "gamma"},     {cy, -1.0, 0.0, 8, "gamma"},       {cy, NAN, 0.0, 8, "gamma"},
        {cy, 2.1, 0.0, 8, "gamma"},     {cy, 2.0, NAN, 8, "theta"},        {cy, 2.0, INFINITY, 8, "theta"},
        {cy, 2.0, 0.0, 3, "modes"},     {cy, 2.0, 0.0, 2049, "modes"},     {NULL, 2.0, 0.0, 8, "cycle"},
        {empty, 2.0, 0.0, 8, "cycle"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        memset(&e, 0, sizeof e);
        CHECK_STATUS(bkf_hill_spectrum(bad[i].cycle, bad[i].gamma, bad[i].theta, bad[i].modes, ev, &count, &e),
                     BKF_EINPUT);
        CHECK_MSG(strstr(e.message, bad[i].name) && !strchr(e.message, '\n'), "case %zu: message \"%s\"", i,
                  e.message);
        CHECK(count == 0);
        CHECK_STATUS(bkf_hill_leading(bad[i].cycle, bad[i].gamma, bad[i].theta, bad[i].modes, 1e-8, 1, ev, NULL,
                                      &found, NULL, &e),
                     BKF_EINPUT);
        CHECK(found == 0);
    }
    CHECK_STATUS(bkf_hill_spectrum(cy, 2.0, 0.0, 8, NULL, &count, &e), BKF_EINPUT);
    CHECK_STATUS(bkf_hill_spectrum(cy, 2.0, 0.0, 8, ev, NULL, &e), BKF_EINPUT);
    CHECK_STATUS(bkf_hill_leading(cy, 2.0, 0.0, 1025, 1e-8, 1, ev, NULL, &found, NULL, &e), BKF_EINPUT);
    CHECK(strstr(e.message, "modes") && strstr(e.message, "1024"));
    CHECK_STATUS(bkf_hill_leading(cy, 2.0, 0.0, 8, 0.0, 1, ev, NULL, &found, NULL, &e), BKF_EINPUT);
    CHECK(strstr(e.message, "tol"));
    CHECK_STATUS(bkf_hill_leading(cy, 2.0, 0.0, 8, NAN, 1, ev, NULL, &found, NULL, &e), BKF_EINPUT);
    CHECK_STATUS(bkf_hill_leading(cy, 2.0, 0.0, 8, 1e-8, 0, ev, NULL, &found, NULL, &e), BKF_EINPUT);
    CHECK(strstr(e.message, "k "));
    /* a good call still works after the refusals */
    CHECK_STATUS(bkf_hill_spectrum(cy, 2.0, 0.0, 8, ev, &count, &e), BKF_OK);
    CHECK(count == 2 * (2 * 8 + 1));
    bkf_cycle_free(empty);
    bkf_cycle_free(cy);
}

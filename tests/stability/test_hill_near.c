/* Hill's eigenvalues of one truncation nearest given points, by inverse
 * iteration (hill_nearest, the train spectrum's candidate check where the
 * band can no longer vouch), against the truncation's whole spectrum by
 * LAPACK's QR: wherever the whole spectrum has an eigenvalue within 1e-5
 * of a point (a converged pair, bkf_hill_converged's test), the iteration
 * lands on that eigenvalue; wherever it lands, it is an eigenvalue. */
#include "harness.h"

#include "bkfront/hill.h"
#include "../../src/stability/hill_internal.h"

#define TWO_PI 6.283185307179586476925286766559

static double nearest_in(const bkf_hill_eigenvalue *e, size_t n, double re, double im, size_t *at)
{
    double best = INFINITY;
    for (size_t i = 0; i < n; i++) {
        double d = hypot(e[i].re - re, e[i].im - im);
        if (d < best) best = d, *at = i;
    }
    return best;
}

/* Class j of n at (mu, nu), truncations M and M + 4: returns the pairs
 * that converged (within 1e-5). */
static size_t compare_class(double gamma, double mu, double nu, size_t n, size_t j, size_t M)
{
    bkf_cycle *cy = bkf_cycle_alloc();
    bkf_cycle_options co = bkf_cycle_options_default();
    co.tol = 1e-12;
    bkf_error e;
    CHECK_MSG(bkf_cycle_solve(cy, mu, nu, &co, &e) == BKF_OK, "%s", e.message);
    double theta = TWO_PI * (double)j / (double)n;
    size_t Mf = M + 4, n1 = 2 * (2 * M + 1), n2 = 2 * (2 * Mf + 1), got = 0, converged = 0;
    bkf_hill_eigenvalue *coarse = malloc(n1 * sizeof *coarse), *fine = malloc(n2 * sizeof *fine);
    bkf_hill_eigenvalue near[12];
    CHECK(coarse && fine);
    CHECK(bkf_hill_spectrum(cy, gamma, theta, M, coarse, &got, &e) == BKF_OK);
    CHECK(bkf_hill_spectrum(cy, gamma, theta, Mf, fine, &got, &e) == BKF_OK);
    /* the 12 rightmost of the coarse truncation */
    CHECK_MSG(hill_nearest(cy, gamma, theta, Mf, coarse, 12, near, &e) == BKF_OK, "%s", e.message);
    for (size_t i = 0; i < 12; i++) {
        size_t k = 0, l = 0;
        double to_fine = nearest_in(fine, n2, coarse[i].re, coarse[i].im, &k);
        if (to_fine <= 1e-5) {
            converged++;
            CHECK_MSG(hypot(near[i].re - fine[k].re, near[i].im - fine[k].im) <= 1e-9 * (1.0 + hypot(fine[k].re, fine[k].im)),
                      "mu %.4g class %zu: %.12g%+.12gi from %.12g%+.12gi, the QR's nearest %.12g%+.12gi", mu, j,
                      near[i].re, near[i].im, coarse[i].re, coarse[i].im, fine[k].re, fine[k].im);
        }
        if (isfinite(near[i].re)) {
            double off = nearest_in(fine, n2, near[i].re, near[i].im, &l);
            CHECK_MSG(off <= 1e-9 * (1.0 + hypot(near[i].re, near[i].im)),
                      "mu %.4g class %zu: %.12g%+.12gi is %.3g from every eigenvalue of the QR", mu, j, near[i].re,
                      near[i].im, off);
        }
    }
    free(coarse);
    free(fine);
    bkf_cycle_free(cy);
    return converged;
}

TEST(hill_nearest_lands_on_the_qr_eigenvalues)
{
    /* a set whose classes j > 0 have converged eigenvalues right of the
     * window's edge (n = 7, mu 0.433), and the paper's n = 4 (mu 2.54),
     * whose rightmost do not converge at 16 modes */
    size_t a = compare_class(0.303351, 0.43341562433830755, -0.320964, 7, 2, 16);
    size_t b = compare_class(2.0, 2.5438807382090127, -0.96, 4, 1, 16);
    bkf_test_note("converged pairs among the 12 rightmost: %zu at mu 0.433, %zu at mu 2.54", a, b);
    CHECK_MSG(a >= 3, "only %zu converged pairs at mu 0.433: the comparison is not exercised", a);
}

static bkf_cycle *solved_cycle(double mu, double nu)
{
    bkf_cycle *cy = bkf_cycle_alloc();
    bkf_cycle_options co = bkf_cycle_options_default();
    co.tol = 1e-12;
    bkf_error e;
    CHECK(cy);
    CHECK_MSG(bkf_cycle_solve(cy, mu, nu, &co, &e) == BKF_OK, "%s", e.message);
    return cy;
}

/* theta = pi by dgeev in the basis of the conjugation's fixed vectors:
 * every eigenvalue of it, artefacts included, is one of the complex
 * matrix of the same truncation (hill_nearest's complex LU from it lands
 * back on it), the truncation (+-pi/T .. +-(2M - 1) pi/T) is the same
 * for pi rounded as 2 pi 11/22 or written -pi or 11 pi, and at c = 0 the
 * eigenvalues are the closed form sigma = (ln m - i (pi + 2 pi k))/T,
 * m = 1 and exp(L) (the cycle's variational equation). */
TEST(hill_theta_pi_real_basis_is_the_complex_matrix)
{
    const size_t M = 16;
    bkf_error e;
    bkf_cycle *cy = solved_cycle(2.1226828809768215, -0.96); /* the paper's n = 2 */
    size_t n = 0, nt = 0;
    bkf_hill_eigenvalue ev[4 * 32], other[4 * 16], near[4 * 16];
    CHECK_MSG(bkf_hill_spectrum(cy, 2.0, TWO_PI / 2, M, ev, &n, &e) == BKF_OK, "%s", e.message);
    CHECK(n == 4 * M && hill_count(TWO_PI / 2, M) == n && hill_count(1.0, M) == 2 * (2 * M + 1));
    CHECK_MSG(hill_nearest(cy, 2.0, TWO_PI / 2, M, ev, n, near, &e) == BKF_OK, "%s", e.message);
    double worst = 0.0, conj_worst = 0.0;
    for (size_t i = 0; i < n; i++) {
        size_t at = 0;
        double scale = 1.0 + hypot(ev[i].re, ev[i].im);
        worst = fmax(worst, isfinite(near[i].re) ? hypot(near[i].re - ev[i].re, near[i].im - ev[i].im) / scale
                                                 : INFINITY);
        conj_worst = fmax(conj_worst, nearest_in(ev, n, ev[i].re, -ev[i].im, &at) / scale);
    }
    bkf_test_note("%zu eigenvalues: complex inverse iteration %.3g away at worst, conjugates %.3g", n, worst,
                  conj_worst);
    CHECK_MSG(worst <= 1e-9, "an eigenvalue of the real basis is %.3g from the complex matrix's", worst);
    CHECK_MSG(conj_worst <= 1e-9, "the spectrum at pi is not conjugate-symmetric (%.3g)", conj_worst);
    /* 2 pi 11/22 and 11 pi round off pi (by an ulp; remainder) */
    const double thetas[] = {TWO_PI * 11.0 / 22.0, -TWO_PI / 2, 11.0 * TWO_PI / 2};
    for (size_t t = 0; t < 3; t++) {
        CHECK_MSG(bkf_hill_spectrum(cy, 2.0, thetas[t], M, other, &nt, &e) == BKF_OK, "%s", e.message);
        CHECK_MSG(nt == n, "theta %.17g: %zu eigenvalues, not %zu", thetas[t], nt, n);
        double d = 0.0;
        for (size_t i = 0; i < n; i++) {
            size_t at = 0;
            d = fmax(d, nearest_in(other, nt, ev[i].re, ev[i].im, &at) / (1.0 + hypot(ev[i].re, ev[i].im)));
        }
        CHECK_MSG(d <= 1e-9, "theta %.17g differs from pi by %.3g", thetas[t], d);
    }
    bkf_cycle_free(cy);

    cy = solved_cycle(1.2, 0.3); /* c = 0: gamma = mu; 32 modes for 1e-8 */
    double T = bkf_cycle_get(cy)->period, L = bkf_cycle_get(cy)->log_multiplier, closed = 0.0;
    CHECK_MSG(bkf_hill_spectrum(cy, 1.2, TWO_PI / 2, 2 * M, ev, &n, &e) == BKF_OK, "%s", e.message);
    for (int k = -5; k <= 5; k++) {
        size_t at = 0;
        double im = -(TWO_PI / 2 + TWO_PI * k) / T;
        closed = fmax(closed, nearest_in(ev, n, 0.0, im, &at));
        closed = fmax(closed, nearest_in(ev, n, L / T, im, &at));
    }
    bkf_test_note("c = 0: worst distance to the closed form (|k| <= 5) %.3g", closed);
    CHECK_MSG(closed <= 1e-8, "c = 0, theta pi: an eigenvalue misses the closed form by %.3g", closed);
    bkf_cycle_free(cy);
}

/* Asymptotic formulas for the period T(mu, nu) of
 *     f'' + mu (f^2 - 1) f' + f = nu.
 * Derivations are in docs/numerics.md ("Asymptotics of the period"). */
#ifndef BKFRONT_ASYMPTOTICS_H
#define BKFRONT_ASYMPTOTICS_H

#ifdef __cplusplus
extern "C" {
#endif

/* Every function is NaN outside the domain |nu| < 1, mu > 0 (finite). */

/* First zero of Ai(-x). */
#define BKF_AIRY_A1 2.338107410459767

/* k(nu) = 3 + (nu^2 - 1) ln[(4 - nu^2)/(1 - nu^2)], the relaxation-limit slope. */
double bkf_asym_k(double nu);

/* Leading large-mu period k(nu) mu. */
double bkf_asym_period_leading(double mu, double nu);

/* Coefficients of the large-mu expansion
 *   T = k mu + a1 C(nu) mu^(-1/3) + L(nu) mu^(-1) ln mu + O(1/mu). */
double bkf_asym_knee_coefficient(double nu);   /* a1 C(nu) */
double bkf_asym_log_coefficient(double nu);    /* L(nu) = -2/(3 (1 - nu^2)) */

/* k mu + knee term + log term. */
double bkf_asym_period_large(double mu, double nu);

/* Small-mu expansion T = 2 pi (1 + s2(nu) mu^2 + O(mu^4)). */
double bkf_asym_small_coefficient(double nu);  /* s2 = (1 - nu^2)(3 + 29 nu^2)/48 */
double bkf_asym_period_small(double mu, double nu);

/* Conservative bounds on the relative error |T_formula - T|/T, or INFINITY
 * outside the region where the bound has been derived and verified.
 *
 * Corrected large-mu formula (bkf_asym_period_large): the remainder is
 * O(1/mu) (Dorodnitsyn: -1.3246/mu at nu = 0); measured mu |T - T_large| over
 * mu in [10, 1e4], |nu| <= 0.9999 stays below
 *     D(nu) = 2 + 0.35 (1 + ln(1/(1 - |nu|))) / (1 - |nu|),
 * which grows as the knee scale approaches the distance to the Hopf point.
 * The bound is 2 D/mu (a safety factor 2), used only for mu >= 10 and
 * mu^2 (1 - |nu|) >= 1 (a factor 8 away from the canard explosion at
 * 1 - |nu| ~ 1/(8 mu^2), where the relaxation expansion does not apply).
 * Leading term k mu: the dropped knee and log terms plus the same bound.
 * Small-mu formula (bkf_asym_period_small), mu <= 1: the next term
 * 2 pi s4(nu) mu^4, with the measured coefficient bounded by
 * (1 - nu^2)^2 (0.05 + 1.1 nu^4) (s4(0) = -5/3072 classically), times 2.
 * Test asym_error_bounds_hold_over_the_box checks every bound against the
 * numerical T. */
typedef enum {
    BKF_ASYM_LEADING = 0,   /* k mu */
    BKF_ASYM_LARGE = 1,     /* k mu + knee + log terms */
    BKF_ASYM_SMALL = 2      /* 2 pi (1 + s2 mu^2) */
} bkf_asym_formula;

double bkf_asym_period(bkf_asym_formula formula, double mu, double nu);
double bkf_asym_error_bound(bkf_asym_formula formula, double mu, double nu);

/* The cheapest formula whose bound meets tol (leading first, then the
 * better of large and small), or -1 when none does; *T and *rel_bound
 * receive its period and bound (may be NULL). */
int bkf_asym_choose(double mu, double nu, double tol, int allow_leading, double *T,
                    double *rel_bound);

#ifdef __cplusplus
}
#endif

#endif

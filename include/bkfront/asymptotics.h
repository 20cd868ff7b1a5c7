/* Asymptotic formulas for the period T(mu, nu) of
 *     f'' + mu (f^2 - 1) f' + f = nu.
 * Derivations are in README.md ("Asymptotics of the period"). */
#ifndef BKFRONT_ASYMPTOTICS_H
#define BKFRONT_ASYMPTOTICS_H

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

#endif

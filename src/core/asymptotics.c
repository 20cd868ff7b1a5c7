/* Asymptotic expansions of the van der Pol period T(mu, nu).
 *
 * Large mu (relaxation oscillations), derived in docs/numerics.md: the slow branches
 * give k(nu) mu; each fold ("knee") at x = +-1 adds an Airy delay a1 theta
 * plus the shift of the landing point on the opposite branch, where
 * theta = mu^(-1/3) (1 -+ nu)^(-1/3); the next-order slow manifold diverges
 * logarithmically at each knee and, cut off at the knee's inner scale
 * ((1 -+ nu)/mu^2)^(1/3), gives -(1/3) ln(mu) / (mu (1 -+ nu)).
 *
 * Small mu (Lindstedt-Poincare to second order about the harmonic oscillator
 * of amplitude 2 sqrt(1 - nu^2)): omega = 1 - s2 mu^2 + O(mu^4). */
#include "bkfront/asymptotics.h"

#include <gsl/gsl_math.h>
#include <math.h>

/* Outside the domain (|nu| < 1, mu > 0, both finite) every formula is NaN:
 * the expressions would otherwise give finite numbers or infinities that
 * look like periods. */
static int bad_nu(double nu) { return !(fabs(nu) < 1.0); }
static int bad_mu(double mu) { return !(mu > 0.0) || !isfinite(mu); }

double bkf_asym_k(double nu)
{
    if (bad_nu(nu)) return NAN;
    double nu2 = nu * nu;
    return 3.0 + (nu2 - 1.0) * log((4.0 - nu2) / (1.0 - nu2));
}

double bkf_asym_period_leading(double mu, double nu)
{
    return bad_mu(mu) ? NAN : bkf_asym_k(nu) * mu;
}

double bkf_asym_knee_coefficient(double nu)
{
    if (bad_nu(nu)) return NAN;
    double right = 1.0 - nu, left = 1.0 + nu;
    double delays = cbrt(1.0 / right) + cbrt(1.0 / left);
    double landings = cbrt(right * right) / (2.0 + nu) + cbrt(left * left) / (2.0 - nu);
    return BKF_AIRY_A1 * (delays + landings);
}

double bkf_asym_log_coefficient(double nu)
{
    return bad_nu(nu) ? NAN : -2.0 / (3.0 * (1.0 - nu * nu));
}

double bkf_asym_period_large(double mu, double nu)
{
    if (bad_mu(mu) || bad_nu(nu)) return NAN;
    return bkf_asym_k(nu) * mu + bkf_asym_knee_coefficient(nu) * pow(mu, -1.0 / 3.0) +
           bkf_asym_log_coefficient(nu) * log(mu) / mu;
}

double bkf_asym_small_coefficient(double nu)
{
    if (bad_nu(nu)) return NAN;
    double nu2 = nu * nu;
    return (1.0 - nu2) * (3.0 + 29.0 * nu2) / 48.0;
}

double bkf_asym_period_small(double mu, double nu)
{
    if (bad_mu(mu) || bad_nu(nu)) return NAN;
    return 2.0 * M_PI * (1.0 + bkf_asym_small_coefficient(nu) * mu * mu);
}

/* --------------------------------------------------------- error bounds */

/* Envelope of mu |T - T_large| (see asymptotics.h). */
static double large_remainder_envelope(double nu)
{
    double d = 1.0 - fabs(nu);
    return 2.0 + 0.35 * (1.0 + log(1.0 / d)) / d;
}

static int large_valid(double mu, double nu)
{
    return mu >= 10.0 && mu * mu * (1.0 - fabs(nu)) >= 1.0;
}

double bkf_asym_period(bkf_asym_formula formula, double mu, double nu)
{
    switch (formula) {
    case BKF_ASYM_LEADING: return bkf_asym_period_leading(mu, nu);
    case BKF_ASYM_LARGE: return bkf_asym_period_large(mu, nu);
    case BKF_ASYM_SMALL: return bkf_asym_period_small(mu, nu);
    }
    return NAN;
}

double bkf_asym_error_bound(bkf_asym_formula formula, double mu, double nu)
{
    if (!(mu > 0) || !(fabs(nu) < 1.0) || !isfinite(mu)) return INFINITY;
    const double safety = 2.0, rounding = 8.0 * DBL_EPSILON;
    switch (formula) {
    case BKF_ASYM_LARGE:
    case BKF_ASYM_LEADING: {
        if (!large_valid(mu, nu)) return INFINITY;
        double abs_err = safety * large_remainder_envelope(nu) / mu;
        if (formula == BKF_ASYM_LEADING)
            abs_err += fabs(bkf_asym_period_large(mu, nu) - bkf_asym_period_leading(mu, nu));
        double T = bkf_asym_period(formula, mu, nu);
        /* relative to the true T >= T - abs_err */
        return T > 2.0 * abs_err ? abs_err / (T - abs_err) + rounding : INFINITY;
    }
    case BKF_ASYM_SMALL: {
        if (mu > 1.0) return INFINITY;
        double nu2 = nu * nu, w = 1.0 - nu2;
        double s4 = w * w * (0.05 + 1.1 * nu2 * nu2);
        double m2 = mu * mu;
        double rel = safety * s4 * m2 * m2 / (1.0 + bkf_asym_small_coefficient(nu) * m2);
        return rel / (1.0 - rel) + rounding;
    }
    }
    return INFINITY;
}

int bkf_asym_choose(double mu, double nu, double tol, int allow_leading, double *T,
                    double *rel_bound)
{
    int best = -1;
    double bound = INFINITY;
    if (allow_leading && bkf_asym_error_bound(BKF_ASYM_LEADING, mu, nu) <= tol) {
        best = BKF_ASYM_LEADING;
        bound = bkf_asym_error_bound(BKF_ASYM_LEADING, mu, nu);
    } else {
        double bl = bkf_asym_error_bound(BKF_ASYM_LARGE, mu, nu);
        double bs = bkf_asym_error_bound(BKF_ASYM_SMALL, mu, nu);
        if (bl <= bs && bl <= tol) {
            best = BKF_ASYM_LARGE;
            bound = bl;
        } else if (bs < bl && bs <= tol) {
            best = BKF_ASYM_SMALL;
            bound = bs;
        }
    }
    if (best >= 0) {
        if (T) *T = bkf_asym_period((bkf_asym_formula)best, mu, nu);
        if (rel_bound) *rel_bound = bound;
    }
    return best;
}

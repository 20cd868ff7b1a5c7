/* Checks of the asymptotic formulas (module asymptotics) against the numerical
 * period (module cycle): fits of the expansion coefficients, and where in mu
 * each formula holds to a given relative accuracy.
 *
 * Large mu.  The expansion derived in docs/numerics.md is
 *     T = k(nu) mu + A* mu^p* + B* mu^(-1) ln mu + O(1/mu),
 *     A* = a1 C(nu),  p* = -1/3,  B* = L(nu) = -2/(3 (1 - nu^2)).
 * bkf_asymfit_large computes T at log-spaced mu, forms R = T - k mu and fits
 *     R = A mu^p + B ln(mu)/mu + D/mu
 * with all four free (p searched with NLopt, A, B, D by linear least squares
 * at each p), and again with p held at -1/3, so that each derived coefficient
 * is tested by a fit that did not assume it.
 *
 * Small mu.  T = 2 pi (1 + s2(nu) mu^2 + O(mu^4)); bkf_asymfit_small fits
 * T/(2 pi) - 1 = s mu^2 + s4 mu^4.
 *
 * Uncertainties.  The data are far more accurate (T to ~1e-12) than the
 * model is complete (the next terms of each series are dropped), so the
 * residuals are truncation, not noise.  Each coefficient's `_err` is the
 * larger of (a) its standard error from the fit's covariance scaled by the
 * residual variance, and (b) its change when refitted on the lower or the
 * upper half of the points alone: how far the answer moves with the range
 * the truncation acts on.
 *
 * All functions validate their inputs (BKF_EINPUT), return the cycle's status
 * (a numerical one, bkf_status_is_numerical) with the (mu, nu) that failed
 * when a cycle cannot be solved, and never print. */
#ifndef BKFRONT_ASYMFIT_H
#define BKFRONT_ASYMFIT_H

#include <stddef.h>
#include "bkfront/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Cycle tolerance asked first, and the one retried when the solver refuses
 * the first (its two-tolerance error estimate was not met: BKF_ETOL, or any
 * other numerical failure). */
#define BKF_ASYMFIT_TOL 1e-12
#define BKF_ASYMFIT_TOL_FALLBACK 1e-11

#define BKF_ASYMFIT_MAX_POINTS 10000u

/* --- large-mu fit --------------------------------------------------------- */

typedef struct {
    double mu_lo, mu_hi;   /* fit range, 1 <= mu_lo < mu_hi <= BKF_CYCLE_MU_MAX */
    size_t npoints;        /* log-spaced, ends included, in [10, BKF_ASYMFIT_MAX_POINTS] */
    double p_lo, p_hi;     /* interval searched for p, -1 < p_lo < p_hi < 0 */
} bkf_asymfit_large_options;

/* mu in [1e2, 1e4], 12 points, p in [-0.9, -0.05]. */
bkf_asymfit_large_options bkf_asymfit_large_options_default(void);

typedef struct {
    double nu;
    size_t npoints;
    /* all four free */
    double A, A_err, p, p_err, B, B_err, D, D_err;
    double rms_rel;           /* rms of (R - fit)/R over the points */
    /* p held at p* = -1/3 */
    double A_fixed, A_fixed_err, B_fixed, B_fixed_err, D_fixed, D_fixed_err;
    double rms_rel_fixed;
    /* the derived values */
    double A_derived, p_derived, B_derived;
    /* the data: worst relative error estimate of T, solves done */
    double T_rel_err_max;
    size_t solves;
} bkf_asymfit_large_result;

/* options NULL: the defaults. |nu| < 1. */
int bkf_asymfit_large(double nu, const bkf_asymfit_large_options *options,
                      bkf_asymfit_large_result *result, bkf_error *err);

/* The fit alone, on given data: R[i] at mu[i] (n >= 10, mu > 0 increasing,
 * R finite and nonzero), weights 1/R^2 (relative least squares).  Fills the
 * free-p and fixed-p fields of *result and npoints; leaves nu, the derived
 * values and the data fields at zero.  Useful to test the fitter on
 * synthetic data. */
int bkf_asymfit_correction(const double *mu, const double *R, size_t n, double p_lo,
                           double p_hi, bkf_asymfit_large_result *result, bkf_error *err);

/* --- small-mu fit --------------------------------------------------------- */

typedef struct {
    double mu_lo, mu_hi;   /* BKF_CYCLE_MU_MIN <= mu_lo < mu_hi <= 1 */
    size_t npoints;        /* log-spaced, in [6, BKF_ASYMFIT_MAX_POINTS] */
} bkf_asymfit_small_options;

/* mu in [1e-3, 0.1], 12 points. */
bkf_asymfit_small_options bkf_asymfit_small_options_default(void);

typedef struct {
    double nu;
    size_t npoints;
    double s, s_err, s4, s4_err;
    double s_derived;          /* s2(nu) = (1 - nu^2)(3 + 29 nu^2)/48 */
    double rms;                /* rms residual of (T/2pi - 1)/mu^2 */
    double T_rel_err_max;
    size_t solves;
} bkf_asymfit_small_result;

int bkf_asymfit_small(double nu, const bkf_asymfit_small_options *options,
                      bkf_asymfit_small_result *result, bkf_error *err);

/* --- validity map --------------------------------------------------------- */

typedef enum {
    BKF_ASYMFIT_LEADING = 0,   /* k(nu) mu                  (bkf_asym_period_leading) */
    BKF_ASYMFIT_CORRECTED = 1, /* k mu + knee + log terms   (bkf_asym_period_large) */
    BKF_ASYMFIT_SMALL = 2      /* 2 pi (1 + s2 mu^2)        (bkf_asym_period_small) */
} bkf_asymfit_formula;

#define BKF_ASYMFIT_NFORMULAS 3

/* "leading", "corrected", "small"; NULL for anything else. */
const char *bkf_asymfit_formula_name(bkf_asymfit_formula formula);

/* The formula's T at (mu, nu); NaN for an unknown formula. */
double bkf_asymfit_formula_period(bkf_asymfit_formula formula, double mu, double nu);

typedef struct {
    double mu_lo, mu_hi;   /* range scanned, BKF_CYCLE_MU_MIN <= mu_lo < mu_hi <= BKF_CYCLE_MU_MAX */
    size_t per_decade;     /* scan points per decade, in [2, 1000] */
    double refine_ratio;   /* bisect a crossing until hi/lo <= this, in (1, 2] */
} bkf_asymfit_map_options;

/* [1e-3, 1e4], 8 points per decade, 1.02. */
bkf_asymfit_map_options bkf_asymfit_map_options_default(void);

typedef enum {
    BKF_ASYMFIT_CROSSING = 0,  /* the error crosses eps inside the range */
    BKF_ASYMFIT_EVERYWHERE = 1,/* holds on the whole range: boundary is the range end */
    BKF_ASYMFIT_NOWHERE = 2    /* never holds: boundary is NaN */
} bkf_asymfit_extent;

const char *bkf_asymfit_extent_name(bkf_asymfit_extent extent);  /* "crossing", ... */

typedef struct {
    bkf_asymfit_formula formula;
    double eps;
    double nu;
    /* Large-mu formulas: mu_min, the smallest mu with rel. error <= eps at
     * every scan point from there up to mu_hi.  Small-mu formula: mu_max, the
     * largest mu with rel. error <= eps at every scan point from mu_lo up to
     * it.  A crossing is bisected in ln mu; mu_boundary is the end of the
     * final bracket on the side where the formula holds, mu_fail the other
     * end (mu_boundary / mu_fail or its inverse <= refine_ratio).  NaN for
     * BKF_ASYMFIT_NOWHERE; for BKF_ASYMFIT_EVERYWHERE mu_boundary is the
     * range end and mu_fail NaN. */
    double mu_boundary, mu_fail;
    bkf_asymfit_extent extent;
} bkf_asymfit_boundary;

/* For every nu[j] (|nu| < 1), formula f and eps[k] (in [1e-10, 1)): the
 * boundary, into out[(j * BKF_ASYMFIT_NFORMULAS + f) * neps + k], an array of
 * nnu * BKF_ASYMFIT_NFORMULAS * neps entries. options NULL: the defaults. */
int bkf_asymfit_map(const double *nu, size_t nnu, const double *eps, size_t neps,
                    const bkf_asymfit_map_options *options, bkf_asymfit_boundary *out,
                    bkf_error *err);

/* --- raw error grid ------------------------------------------------------- */

typedef struct {
    double mu, nu, T, T_err;
    double rel_err[BKF_ASYMFIT_NFORMULAS];   /* |T_formula - T| / T, by formula */
} bkf_asymfit_grid_point;

/* The grid mu[i] x nu[j], mu fastest: out[j * nmu + i].  mu in
 * [BKF_CYCLE_MU_MIN, BKF_CYCLE_MU_MAX], |nu| < 1, nmu * nnu <= 1e6. */
int bkf_asymfit_grid(const double *mu, size_t nmu, const double *nu, size_t nnu,
                     bkf_asymfit_grid_point *out, bkf_error *err);

#ifdef __cplusplus
}
#endif

#endif

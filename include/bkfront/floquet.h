/* Floquet stability of the global oscillations: the dispersion relation
 * lambda_q, the critical wavenumber q_c, the instability thresholds in nu and
 * the stability diagram over the active range.
 *
 * With psi_xx = 0 the model is the Lienard system of the cycle module with
 * mu = gamma and time t = z.  A perturbation eps(t) exp(iqx) of the global
 * oscillation psi*(t) obeys (docs/numerics.md, "Floquet stability")
 *     d_psi' = gamma (d_eta - (psi*(t)^2 - 1) d_psi)
 *     d_eta' = -(1 + c^2 q^2) d_psi / gamma
 * over one period T.  Its monodromy matrix M_q has two multipliers m1, m2
 * (m1 the dominant one); lambda_q = max Re ln m = ln |m1| is the growth per
 * period.
 *
 * Facts the module relies on, each checked by the tests:
 *  - q enters only through K = 1 + c^2 q^2.  Everything below is a function
 *    of (gamma, nu, K); c only converts K to q = sqrt(K - 1)/c.  With c = 0
 *    every q behaves as q = 0, and in an unbounded domain the thresholds in
 *    nu do not depend on c > 0 at all.
 *  - trace(A) = -gamma (psi*^2 - 1) does not depend on q, so
 *    m1 m2 = exp(L), L = integral of the trace over a period (Liouville),
 *    the same for every q: the cycle's own nontrivial multiplier.  The small
 *    multiplier is computed as exp(L)/m1, free of cancellation.
 *  - A complex pair has |m| = exp(L/2) < 1, so an instability needs a real
 *    multiplier: through +1 (at q = 0 the trivial multiplier is 1) or -1.
 *  - As q -> 0, lambda_q = a c^2 q^2 + O(q^4) with the long-wave coefficient
 *    a = (d trace/dK)/(1 - exp(L)) at K = 1: a > 0 is a long-wave (phase)
 *    instability.
 *
 * Accuracy: `tol` is the absolute accuracy asked of lambda (the relative
 * accuracy of the dominant multiplier).  Each quantity reported with an
 * error estimate comes from two integrations at tolerances a factor 10
 * apart plus the cycle's own error; the reported value is the tighter one.
 * bkf_floquet_eval refuses (BKF_ETOL) a q whose estimate it cannot
 * bring under tol; the threshold and diagram drivers report their own
 * errors in nu instead. */
#ifndef BKFRONT_FLOQUET_H
#define BKFRONT_FLOQUET_H

#include <stddef.h>
#include "bkfront/cycle.h"
#include "bkfront/status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    double tol;               /* absolute accuracy of lambda, [1e-14, 1e-1]; default 1e-10 */
    bkf_stepper_kind stepper; /* as in cycle.h; auto: rk8pd for gamma <= 30;
                                 extrapolation: the cycle by bd2x2, the
                                 monodromy by bsimp (rk8pd where auto would) */
    /* Scans for peaks of lambda over K (threshold, diagram): c q runs over
     * (0, p_max] on scan_points even points, each peak refined by NLopt. */
    double p_max;             /* default 6 */
    size_t scan_points;       /* default 120 */
    /* Scans over nu (threshold, diagram): step and distance kept from the
     * ends of the active range. */
    double nu_step;           /* default 0.01 */
    double nu_edge;           /* default 1e-3: nu in [-1 + edge, 1 - edge] */
} bkf_floquet_options;

bkf_floquet_options bkf_floquet_options_default(void);

typedef enum {
    BKF_FLOQUET_REAL_POSITIVE = 0,
    BKF_FLOQUET_REAL_NEGATIVE = 1,
    BKF_FLOQUET_COMPLEX = 2
} bkf_floquet_kind;

/* "real_positive", "real_negative", "complex". */
const char *bkf_floquet_kind_name(bkf_floquet_kind kind);

typedef struct {
    double q, k2;             /* wavenumber and K = 1 + c^2 q^2 */
    double m1_re, m1_im;      /* dominant multiplier (|m1| >= |m2|; m1_im >= 0) */
    double m2_re, m2_im;
    double lambda;            /* ln |m1|, growth per period */
    double lambda_err;        /* estimated absolute error of lambda */
    double m1_err;            /* estimated absolute error of m1 */
    bkf_floquet_kind kind;    /* of m1 (and m2: both real or a conjugate pair) */
    double trace;             /* trace of the monodromy matrix */
    double log_det;           /* L: ln(m1 m2) by Liouville, q-independent */
    double det_direct;        /* determinant of the integrated matrix (a check) */
    double monodromy[4];      /* row-major, in (d_psi, d_eta) */
    size_t steps;             /* integration steps, both tolerances */
} bkf_floquet_point;

typedef struct bkf_floquet bkf_floquet;

bkf_floquet *bkf_floquet_alloc(void);
void bkf_floquet_free(bkf_floquet *floquet);

/* Fix (gamma, c, nu) and solve the global oscillation (the cycle with
 * mu = gamma).  gamma in [BKF_CYCLE_MU_MIN, BKF_CYCLE_MU_MAX], c >= 0,
 * |nu| < 1; options NULL for the defaults.  On failure the object keeps
 * no usable state. */
int bkf_floquet_set(bkf_floquet *floquet, double gamma, double c, double nu,
                    const bkf_floquet_options *options, bkf_error *err);

/* The cycle behind the last successful set (T, its error, L), or NULL. */
const bkf_cycle_result *bkf_floquet_cycle(const bkf_floquet *floquet);

/* Monodromy, multipliers and lambda at wavenumber q >= 0, to the object's
 * tol or refused.  At K = 1 (q = 0 or c = 0) the multipliers are 1 and
 * exp(L) exactly.  Otherwise M is integrated as it stands; where lambda_err
 * exceeds tol, the dominant multiplier is recomputed without forming the
 * trace (power iteration on the angle and log-norm equations of the
 * perturbation, for real well-separated multipliers) and from the columns
 * of M in log-polar form (multipliers below tol |M|, down to |m1| ~
 * exp(-2e4)), then with the cycle solved tighter (or its share of the
 * error measured) and integrations down to 1e-13.  If no attempt meets tol:
 * BKF_ETOL ("estimated error E of lambda exceeds tol T at q = ..."),
 * with *point holding the best attempt and its lambda_err (> tol).  On
 * any other failure point->lambda_err is NaN. */
int bkf_floquet_eval(bkf_floquet *floquet, double q, bkf_floquet_point *point,
                     bkf_error *err);

/* The long-wave coefficient a (lambda_q = a c^2 q^2 + O(q^4)) and its
 * estimated error. */
int bkf_floquet_longwave(bkf_floquet *floquet, double *a, double *a_err, bkf_error *err);

/* Growth rate of a perturbation of continuous slip psi = nu, per unit
 * time: the largest Re s of s^2 + gamma phi'(nu) s + (1 + c^2 q^2) = 0.
 * Times the oscillation's period T it is the growth per period comparable
 * with lambda_q.  NaN unless gamma > 0, c >= 0 and every argument finite. */
double bkf_floquet_slip_rate(double gamma, double c, double nu, double q);

/* ------------------------------------------------------------ stability */

/* What an instability boundary is. */
typedef enum {
    BKF_BOUNDARY_PERIOD_DOUBLING = 0, /* a finite-q peak of lambda crosses 0 with m1 = -1 */
    BKF_BOUNDARY_LONG_WAVE = 1,       /* the long-wave coefficient a changes sign (q -> 0) */
    BKF_BOUNDARY_OTHER = 2,           /* a finite-q peak crosses 0 with m1 = +1 */
    BKF_BOUNDARY_SCAN_END = 3,        /* end of the scanned range, not a boundary */
    BKF_BOUNDARY_NONE = 4             /* no change of stability in the scanned range */
} bkf_floquet_boundary;

/* "period_doubling", "long_wave", "other", "scan_end", "none". */
const char *bkf_floquet_boundary_name(bkf_floquet_boundary kind);

/* Stability of the global oscillation at the object's nu against every
 * c q in (0, p_max]. */
typedef struct {
    double nu;
    int stable;               /* a < 0 and every finite-q peak has lambda < 0 */
    double longwave;          /* a */
    double longwave_err;
    /* the highest finite-q peak of lambda (the long-wave band's own peak
     * excluded when a > 0); NaN if the scan found none */
    double lambda_peak, lambda_peak_err;
    double q_peak, k2_peak;
    double m_re, m_im;        /* dominant multiplier there */
    size_t peaks;             /* finite-q peaks found */
} bkf_floquet_stability;

int bkf_floquet_stability_at(bkf_floquet *floquet, bkf_floquet_stability *out, bkf_error *err);

/* A stability boundary in nu at fixed (gamma, c). */
typedef struct {
    double gamma, c;
    double nu, nu_err;
    bkf_floquet_boundary kind;
    double q, k2;             /* critical wavenumber (0 for long-wave) */
    double m_re, m_im;        /* critical multiplier: m1 at (q, nu) */
    double lambda;            /* lambda there (~0) */
    int stable_above;         /* the oscillation is stable just above nu */
    double longwave;          /* a at nu (for a finite-q boundary: is the
                                 oscillation also long-wave unstable there?) */
    int discontinuous;        /* the indicator jumps here instead of crossing
                                 zero: the cycle itself changes abruptly (a
                                 canard explosion); kind is then OTHER */
} bkf_floquet_threshold;

/* The lowest stability boundary in [nu_lo, nu_hi] (c > 0): the scan runs
 * upward from nu_lo in steps options->nu_step, and the first change of
 * stability is located by Brent's method on the indicator that changes
 * sign (the maximum of lambda over a tracked peak, found by NLopt, or a),
 * to about options->tol in nu.  No change of stability in the range is an
 * answer, not a failure: BKF_OK with kind BKF_BOUNDARY_NONE, nu NaN and
 * stable_above telling whether the oscillation is stable throughout. */
int bkf_floquet_threshold_find(double gamma, double c, double nu_lo, double nu_hi,
                               const bkf_floquet_options *options,
                               bkf_floquet_threshold *out, bkf_error *err);

/* The threshold curve: starting from the lowest boundary in [nu_lo, nu_hi]
 * at (gamma, c) with the parameter `along` at `from`, follow that boundary
 * (same kind) by pseudo-arclength continuation to `to` (c is continued in
 * c, gamma in ln gamma).  Each accepted point is polished by root finding
 * at fixed parameter (error estimate as for threshold_find) and passed to
 * visit; both ends are included.  max_points 0: no limit beyond the
 * driver's. */
typedef enum { BKF_FLOQUET_ALONG_C = 0, BKF_FLOQUET_ALONG_GAMMA = 1 } bkf_floquet_param;
typedef int (*bkf_floquet_threshold_visit)(const bkf_floquet_threshold *point, void *data);
int bkf_floquet_threshold_branch(bkf_floquet_param along, double from, double to,
                                 double gamma, double c, double nu_lo, double nu_hi,
                                 const bkf_floquet_options *options, size_t max_points,
                                 bkf_floquet_threshold_visit visit, void *data,
                                 bkf_error *err);

/* The stability diagram over [nu_lo, nu_hi] (c > 0): consecutive intervals
 * of one stability, each end a located boundary or the scan's end.
 * Boundaries closer together than options->nu_step may be missed (a stable
 * or unstable window narrower than the scan step). */
typedef struct {
    double nu_from, nu_to;
    int stable;
    bkf_floquet_threshold from, to;  /* from.kind / to.kind SCAN_END at the ends */
} bkf_floquet_interval;
typedef int (*bkf_floquet_interval_visit)(const bkf_floquet_interval *interval, void *data);
int bkf_floquet_diagram(double gamma, double c, double nu_lo, double nu_hi,
                        const bkf_floquet_options *options,
                        bkf_floquet_interval_visit visit, void *data, bkf_error *err);

#ifdef __cplusplus
}
#endif

#endif

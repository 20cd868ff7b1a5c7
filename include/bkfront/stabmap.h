/* Stability across parameters: where in the (nu, S) plane a train of n
 * fronts exists and where it is stable, and where the global oscillation is
 * (`bkfront stability --boundary`, `--diagram`).
 *
 * - The existence boundary of n at nu: the smallest S with a root of the
 *   speed condition, S = n c gamma g_inf(nu) (speeds.h: g_inf is the infimum
 *   of T / sqrt(mu^2 - gamma^2), k(nu) unless g dips below k; then the
 *   sonic limit is approached but not reached and every S above has a root).
 * - A stability boundary of n: a curve S(nu) on which sigma_max (the
 *   rightmost Re sigma of the ring spectrum but the translation,
 *   trainspec.h) of the root continued from the previous point changes
 *   sign.  bkf_stabmap_trace follows it by pseudo-arclength continuation
 *   in (nu, S), through folds in nu (the diagram's curves);
 *   bkf_stabmap_follow by natural-parameter continuation in nu: the
 *   predictor is the secant through the last two points, the corrector
 *   brackets sigma_max = 0 in S around the prediction and closes the
 *   bracket by the Illinois method (`--boundary`).  The S error of a point
 *   is the larger of the final bracket's half-width and sigma_max's error
 *   divided by |d sigma_max / dS|.
 * - The global oscillation on the ring: the allowed wavenumbers are
 *   q = 2 pi m / S, so an unstable band c q in (p_a, p_b) of its Floquet
 *   dispersion at nu (floquet.h) makes the ring unstable for S in
 *   [2 pi m c / p_b, 2 pi m c / p_a], m = 1, 2, ... (a period-doubling
 *   tongue per m); a long-wave band (0, p_b) for S > 2 pi c / p_b.
 *
 * The library never prints and never exits. */
#ifndef BKFRONT_STABMAP_H
#define BKFRONT_STABMAP_H

#include <stddef.h>
#include "bkfront/model.h"
#include "bkfront/status.h"
#include "bkfront/trainspec.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The ring spectrum of a root, as bkf_trainspec_root (the default: per_kappa
 * 0, the rightmost alone, where only sigma_max and its class are read; 1 in
 * bkf_stabmap_trace, which also reads the runner-up): every ring spectrum
 * the map computes is one call, which a caller may count or wrap (a test's
 * independent count of the work). */
typedef int (*bkf_stabmap_spectrum_fn)(const bkf_model_params *params,
                                       const bkf_speeds_root *root, double tol,
                                       bkf_trainspec_result *result, bkf_error *err,
                                       void *data);

typedef struct {
    double tol;      /* absolute accuracy of each sigma (trainspec), default 1e-6 */
    double S_tol;    /* bracket width at which an S solve stops, default 1e-3 */
    double nu_step;  /* continuation step in nu, default 0.01 (trace: the largest) */
    size_t max_points; /* points of one boundary at most; default 1000 */
    double S_step;   /* trace: the largest step in S between points, default 0.5 */
    bkf_stabmap_spectrum_fn spectrum; /* NULL (default): bkf_trainspec_root */
    void *spectrum_data;              /* its last argument */
} bkf_stabmap_options;

bkf_stabmap_options bkf_stabmap_options_default(void);

/* How a followed boundary ended. */
typedef enum {
    BKF_STABMAP_END_REACHED = 0, /* nu reached `to` */
    BKF_STABMAP_END_FOLD = 1,    /* no sign change near the prediction: the
                                    boundary turns back in nu (or a second
                                    crossing met it) */
    BKF_STABMAP_END_NO_ROOT = 2, /* the train has no root of the speed condition there */
    BKF_STABMAP_END_REFUSED = 3, /* trainspec refused sigma (BKF_ETOL, BKF_EBUDGET) */
    BKF_STABMAP_END_POINTS = 4,  /* max_points reached */
    BKF_STABMAP_END_WINDOW = 5,  /* trace: the curve left the window in S */
    BKF_STABMAP_END_STALLED = 6, /* trace: the continuation's step fell below its
                                    minimum, also after three restarts from the last
                                    point with short steps (sigma too rough to
                                    correct on; a corner where the rightmost
                                    eigenvalue changes is passed by a restart) */
    BKF_STABMAP_END_CLOSED = 7   /* trace: its chord passed within a quarter step of
                                    its first point after leaving it: a closed curve,
                                    followed once */
} bkf_stabmap_end;

/* "reached", "fold", "no_root", "refused", "max_points", "window", "stalled",
 * "closed". */
const char *bkf_stabmap_end_name(bkf_stabmap_end end);

typedef struct {
    double nu, S, S_err;
    double v, mu;            /* the root there */
    double sigma, sigma_err; /* sigma_max at (nu, S) as computed: within a few
                                sigma_err of 0; NaN where the spectrum nearest 0
                                was only its window's edge (sigma_bound) */
    double sigma_bound;      /* that edge (every eigenvalue left of it), else NaN */
    double slope;            /* d sigma_max / dS across the final bracket (trace: the
                                secant estimate the continuation corrects with) */
    int stable_above;        /* stable just above S (sigma_max < 0 there) */
    size_t evaluations;      /* spectra computed for this point */
    double nu_err;           /* trace: the error in nu, (|sigma| + sigma_err) / |d sigma_max /
                                d nu| (the curve crosses S = const within it); 0 where nu
                                was held (scan, locate, follow) */
    double nu_slope;         /* trace: d sigma_max / d nu, else NaN */
} bkf_stabmap_point;

typedef int (*bkf_stabmap_visit)(const bkf_stabmap_point *point, void *data);

typedef struct {
    size_t points, evaluations; /* evaluations: ring spectra computed (a refused one too) */
    size_t tracked;          /* eigenvalues continued alone (bkf_trainspec_track,
                                one cycle, about 1/20 of a ring spectrum each) */
    bkf_stabmap_end end;
    double nu_end;           /* the last nu tried */
    char note[256];          /* why it ended, one line */
} bkf_stabmap_report;

/* sigma_max of train n at (params->nu, params->S) at options->tol (NULL:
 * the defaults): the root whose v is nearest v_near (v_near <= 0: the
 * fastest root).  BKF_EINPUT when n has no root there.  *spectra (may be
 * NULL) is incremented when a ring spectrum was computed (refused or not). */
int bkf_stabmap_sigma(const bkf_model_params *params, size_t n, double v_near,
                      const bkf_stabmap_options *options, double *sigma, double *sigma_err,
                      double *v, double *mu, size_t *spectra, bkf_error *err);

/* The first sign change of sigma_max of train n in S, from S_from towards
 * S_to (scanned on `samples` even steps, then closed), at params->nu.
 * BKF_OK with *found 0 when there is none. */
int bkf_stabmap_locate(const bkf_model_params *params, size_t n, double S_from, double S_to,
                       size_t samples, const bkf_stabmap_options *options,
                       bkf_stabmap_point *point, int *found, bkf_error *err);

/* Every sign change of sigma_max of train n in S in [S_from, S_to] at
 * params->nu, the same scan closed at each (at most max, in order of S);
 * samples where n has no root or sigma is refused are gaps.  The samples
 * take the fastest root: where a faster root is born (a fold of the speed
 * condition) sigma_max may jump across 0 without a zero; a closed bracket
 * whose ends are different roots is such a jump, no crossing, and is left
 * out.  A sample needs only sigma_max's sign: where the previous sample's
 * rightmost eigenvalue, continued, is right of 0 beyond tol and its error,
 * no ring spectrum is computed; a bracket is closed on the eigenvalue right
 * of 0 at its positive end, then checked by one ring spectrum (closed on
 * ring spectra where another eigenvalue overtook it).  Each point is a ring
 * spectrum (its evaluations: the bracket's ring spectra).  *report (may be
 * NULL) gets the scan's work: points = *count, evaluations the ring spectra,
 * tracked the eigenvalues continued alone. */
int bkf_stabmap_scan(const bkf_model_params *params, size_t n, double S_from, double S_to,
                     size_t samples, const bkf_stabmap_options *options, bkf_stabmap_point *points,
                     size_t max, size_t *count, bkf_stabmap_report *report, bkf_error *err);

/* The boundary through `first` (a point of bkf_stabmap_locate, its params
 * gamma and c), followed in nu to nu_to; visit gets every point, the first
 * included (nonzero stops).  The end is an answer, not a failure: BKF_OK
 * with report->end; other failures return their status. */
int bkf_stabmap_follow(const bkf_model_params *params, size_t n,
                       const bkf_stabmap_point *first, double nu_to,
                       const bkf_stabmap_options *options, bkf_stabmap_visit visit, void *data,
                       bkf_stabmap_report *report, bkf_error *err);

/* The window a traced curve stays in: nu in [nu_lo, nu_hi] and S in
 * [S_lo, S_hi], the curve's last point on the edge it leaves by. */
typedef struct {
    double nu_lo, nu_hi, S_lo, S_hi;
} bkf_stabmap_window;

/* The boundary through `first` (a point of bkf_stabmap_scan), followed by
 * pseudo-arclength continuation in (nu, S) (continuation.h: unknowns
 * (nu, S), equation sigma_max(nu, S) = 0, the root continued by v ~ S), in
 * the direction of nu's sign `direction` (+1, -1), through folds in nu, to
 * the window's edge.  The gradient of sigma_max is d sigma / dS of `first`'s
 * bracket and one difference in nu at the start, then updated by Broyden's
 * rank-one secant from every value.  The predictor and Newton's
 * corrections take the last spectrum's rightmost eigenvalue continued
 * (bkf_trainspec_track, about 1/20 of a ring spectrum), the ring
 * spectrum only where Newton stops: a point costs about one spectrum
 * (report->evaluations counts ring spectra), every other point none where
 * the last ring spectrum's runner-up, continued there, stays left of the
 * eigenvalue continued (checked by the next ring spectrum, else the point
 * gets its own; docs/cli/stability.md).  Steps are at most
 * options->nu_step in nu and options->S_step in S; Newton stops when
 * its step in S is below about options->S_tol / 8.  Every point is a computed
 * sigma_max (never an interpolation), its S_err = (|sigma| + sigma_err) /
 * |d sigma / dS| and nu_err likewise.  visit gets every point, the first
 * included (nonzero stops: end reached).  The end is an answer: BKF_OK with
 * report->end (reached: nu's edge; window: S left [S_lo, S_hi], the last
 * point its crossing of the edge, located by the Illinois method in nu on
 * S = S_lo or S_hi, when the edge shows the sign change; no_root, refused: the spectrum's refusal, note says
 * where and why; stalled; max_points: options->max_points, grown by half at
 * each of the curve's first two turns in nu). */
int bkf_stabmap_trace(const bkf_model_params *params, size_t n, const bkf_stabmap_point *first,
                      int direction, const bkf_stabmap_window *window,
                      const bkf_stabmap_options *options, bkf_stabmap_visit visit, void *data,
                      bkf_stabmap_report *report, bkf_error *err);

/* The existence boundary S = n c gamma g_inf(nu) at params->nu (c > 0);
 * *attained 1 when g dips below k (a fold: the root at S exists), 0 when
 * it is the sonic limit (roots for every S above, none at S). */
int bkf_stabmap_existence(const bkf_model_params *params, size_t n, double *S,
                          int *attained, bkf_error *err);

/* The unstable bands of the global oscillation at (gamma, c, nu): c q in
 * (lo[i], hi[i]), lo[i] = 0 for a long-wave band, kind[i] 1 when the
 * band's multiplier is real negative (period doubling), 0 otherwise; at most
 * max bands, c q sampled on (0, p_max] at `samples` points, edges to about
 * tol in c q. */
int bkf_stabmap_bands(double gamma, double c, double nu, double p_max, size_t samples,
                      double tol, double *lo, double *hi, int *kind, size_t max,
                      size_t *count, bkf_error *err);

#ifdef __cplusplus
}
#endif

#endif

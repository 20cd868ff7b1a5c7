/* Measurements on simulated fields psi(x, t), eta(x, t) on a periodic grid
 * x_i = i S/N: front positions and their count, front speeds with an
 * uncertainty, the temporal period at a point, spatial mean and variance,
 * the deviation from a reference travelling wave, and a regime label.
 *
 * Fronts.  A front is where psi crosses `level` (default
 * bkf_measure_front_level: the middle of the global oscillation's range) with
 * psi_t = gamma (eta - phi(psi)) > 0 there: the place where the medium is
 * switching to fast slip.  Crossings are found with hysteresis: the field
 * must pass from below level - hysteresis to above level + hysteresis (or
 * back), so a nearly uniform field has no fronts, and one transition gives
 * one crossing even where noise wiggles about the level.  Positions are
 * sub-grid: the crossing is the root, inside its grid cell, of the quintic
 * Hermite interpolant built from psi, psi_x and psi_xx at the cell's ends,
 * the derivatives spectral (FFT); the error is O(h^6) for a resolved field.
 * Each front also carries its instantaneous velocity -psi_t/psi_x (psi_t
 * from a cubic through the four nearest points: a diagnostic, O(h^4)).
 * On the chain (model kind BKF_MODEL_CHAIN) there is no field between the
 * blocks and a front can be one block wide: psi and eta are linear across
 * the cell, and psi_t there is gamma (eta - phi(level)).
 *
 * Fronts are tracked from sample to sample while their count stays the same
 * (matched by the cyclic assignment closest to the positions predicted from
 * the velocities); a change of count starts a new set of tracks.  The speed
 * is the least-squares slope of the unwrapped positions against t, per
 * track, over the fit interval: the part of the last unbroken set of tracks
 * inside the window (the last `window` fraction of the run).  Reported:
 *     speed     mean of the tracks' slopes (signed: < 0 is towards -x)
 *     speed_err sqrt(se^2/n + spread^2/n + (v_a - v_b)^2/4): se the rms
 *               standard error of the slopes, spread their standard
 *               deviation, v_a and v_b the speeds fitted on the two halves
 *               of the interval (drift, i.e. not yet steady).
 * This is the uncertainty of the measurement on the simulated field, not
 * the discretization error of the simulation.
 *
 * Period at a point.  Upward crossings of `level` by psi at the probe point
 * (with the same hysteresis), located by cubic Hermite interpolation in t
 * from psi and psi_t at the samples.  In the window, the smallest p in 1..4
 * for which the crossing intervals repeat with period p (relative tolerance
 * `periodic_tol`) gives the period: the mean of t_{k+p} - t_k.  p = 2 is a
 * period-doubled signal.
 *
 * Regime (criteria evaluated on the window, in this order):
 *   continuous_slip      max |psi - nu| over the window <= slip_eps, and not
 *                        larger at the end than at the window's start
 *   global_oscillation   the largest spatial standard deviation in the
 *                        window <= uniform_eps times the space-time range of
 *                        psi (max - min) in the window
 *   propagating_fronts   the same front count n >= 1 throughout the window,
 *                        one unbroken set of tracks, every track moving the
 *                        same way, |speed| > 10 speed_err and the tracks'
 *                        speeds within 1% of each other, and the window
 *                        settled (below); a product that knows the model's
 *                        allowed speeds also asks the speed to match one
 *                        (bkf_simulate: else transient)
 *   period_doubled_pacemakers
 *                        the signal at the probe is periodic, fronts exist in
 *                        the window and move both ways or change in number,
 *                        and the period is 1.5 to 2.5 times period_ref (when
 *                        period_ref > 0), or p = 2 (when it is not given)
 *   irregular            anything else, in a settled window
 *   transient            anything else: the window has not settled
 * The window has settled when its two halves (before and after its middle
 * time) agree in their time-averaged spatial variance of psi and in their
 * mean front count, each within settled_tol (relative) of the larger.
 *
 * Bounded memory.  Without t_end every sample's record is kept (about
 * 100 bytes plus 8 per front), for bkf_measure_record_at and
 * bkf_measure_fit_speed over any interval.  With t_end the summary's
 * sums over the window are taken as the samples arrive (in the same order,
 * so the summary is the same to the last bit when the last sample is at
 * t_end), and only the last record is kept, plus, inside the window, the
 * records of the current unbroken set of tracks (the speed fit needs their
 * positions) and the probe's crossing times: records before them are not
 * available (bkf_measure_record_at gives NULL, bkf_measure_fit_speed
 * BKF_EINPUT).  A run that stops early (canceled) is summarized over
 * [window start, last sample]; one that stops before the window begins
 * has no summary (BKF_EINPUT).
 *
 * The library never prints and never exits. */
#ifndef BKFRONT_MEASURE_H
#define BKFRONT_MEASURE_H

#include <stddef.h>
#include "bkfront/model.h"
#include "bkfront/status.h"

#ifdef __cplusplus
extern "C" {
#endif
/* The default level of fronts, here and in bkf_comoving: the middle of the
 * global oscillation's range, (xmin + xmax)/2 of the limit cycle at
 * mu = gamma (bkf_cycle_period).  Every relaxation jump crosses it mid-way,
 * where fronts are steepest, also in the period-doubled patterns, whose
 * fronts sit well above nu.  Where there is no cycle (|nu| >= 1, gamma
 * outside the cycle engine's range, or the cycle not found) it is nu.
 * *period (may be NULL) gets the cycle's period, 0 without a cycle.  Uses
 * gamma and nu of `model`. */
double bkf_measure_front_level(const bkf_model_params *model, double *period);


typedef struct {
    /* model: N grid points >= 8, S > 0, gamma > 0 (psi_t = gamma (eta -
     * phi(psi))), nu finite; c and kind are not used */
    bkf_model_params model;
    double level;         /* crossing level; NaN (the default):
                             bkf_measure_front_level(&model) */
    double hysteresis;    /* >= 0; default 0.1 */
    size_t probe;         /* grid index of the point for the period; default 0 */
    double window;        /* (0, 1]: last fraction of the run used for fits; default 0.5 */
    double period_ref;    /* the global oscillation's period, or 0 (unknown) */
    double slip_eps;      /* default 1e-3 */
    double uniform_eps;   /* default 1e-2 */
    double periodic_tol;  /* default 5e-2 */
    double settled_tol;   /* the window's halves alike within it (relative); default 0.1 */
    double frame_speed;   /* the speed of the grid's frame (bkf_pde_options.frame_speed):
                             fronts move on the grid at their velocity less it, which the
                             tracking predicts from; default 0 (the lab frame) */
    const double *reference; /* NULL, or N values of psi at the first sample
                                without perturbation (a seeded travelling wave),
                                copied: the deviation is measured from it */
    double t_end;         /* the time of the run's last sample, or NaN (the
                             default): unknown.  Given, the window is fixed
                             from the start, [t_end - window (t_end - t_first),
                             t_end], and memory does not grow with the run:
                             see "Bounded memory" above */
} bkf_measure_params;

/* Defaults for the optional fields; model.N, .S, .gamma and .nu must be set. */
bkf_measure_params bkf_measure_params_default(void);

typedef struct {
    double x;             /* position in [0, S) */
    double velocity;      /* -psi_t / psi_x at the crossing */
    int rising;           /* psi increases with x across the front (it moves towards -x) */
} bkf_front;

typedef enum {
    BKF_REGIME_CONTINUOUS_SLIP = 0,
    BKF_REGIME_GLOBAL_OSCILLATION = 1,
    BKF_REGIME_PACEMAKERS = 2,
    BKF_REGIME_FRONTS = 3,
    BKF_REGIME_IRREGULAR = 4,
    BKF_REGIME_TRANSIENT = 5
} bkf_regime;

/* "continuous_slip", "global_oscillation", "period_doubled_pacemakers",
 * "propagating_fronts", "irregular", "transient". */
const char *bkf_regime_name(bkf_regime regime);

typedef struct bkf_measure bkf_measure;

bkf_measure *bkf_measure_alloc(const bkf_measure_params *params, bkf_error *err);
void bkf_measure_free(bkf_measure *m);

/* Fronts of one field, without recording it: up to `capacity` into `fronts`
 * (may be NULL with capacity 0), *count is the total found, ordered by x. */
int bkf_measure_fronts(bkf_measure *m, const double *psi, const double *eta, bkf_front *fronts,
                       size_t capacity, size_t *count, bkf_error *err);

/* Per-sample record, for diagnostics tables. */
typedef struct {
    double t;
    double mean, variance;     /* spatial mean and variance of psi */
    double min, max;
    double probe;              /* psi at the probe point */
    size_t fronts;
    double displacement;       /* mean unwrapped displacement of the tracked fronts
                                  since the first sample; NaN once tracking broke */
    double deviation;          /* max |psi(x) - reference(x - displacement)|; NaN
                                  without a reference or without tracking */
} bkf_measure_record;

/* Records a sample (times strictly increasing).  The arrays are not kept. */
int bkf_measure_add(bkf_measure *m, double t, const double *psi, const double *eta,
                    bkf_error *err);

size_t bkf_measure_count(const bkf_measure *m);
const bkf_measure_record *bkf_measure_record_at(const bkf_measure *m, size_t i);

typedef struct {
    double t_start, t_end, window_start;
    size_t samples;
    /* fronts */
    size_t fronts_start, fronts_end;
    size_t fronts_min, fronts_max;    /* over the window */
    int count_constant;               /* the same count at every sample of the run */
    int tracked_throughout;           /* one unbroken set of tracks over the whole run */
    double speed, speed_err;          /* NaN when there is nothing to fit */
    double speed_spread;              /* std of the tracks' slopes */
    size_t tracks;
    size_t moving_minus, moving_plus; /* tracks by direction */
    double fit_start;                 /* start of the fit interval */
    /* period at the probe */
    double period, period_err;        /* NaN when fewer than 3 crossings in the window */
    size_t period_multiplicity;       /* p; 0 when not periodic */
    size_t crossings;                 /* in the window */
    /* statistics over the window */
    double mean, variance;            /* time averages of the spatial mean and variance */
    double std_max;                   /* largest spatial standard deviation */
    double psi_min, psi_max;          /* over space and time */
    double slip_deviation_start, slip_deviation_end; /* max |psi - nu| */
    /* deviation from the reference */
    double deviation_start, deviation_mid, deviation_end; /* first, window start, last */
    double deviation_max;
    double deviation_growth;          /* ln(end/mid) / (t_end - t_mid), per unit time */
    int settled;                      /* the window's halves alike (see the regimes) */
    bkf_regime regime;
} bkf_measure_summary;

/* The speed fitted as above over the records with t in [t_from, t_to],
 * which must belong to one unbroken set of tracks (BKF_ENUMERIC otherwise,
 * or with fewer than 3 samples or no fronts).  `tracks` may be NULL. */
int bkf_measure_fit_speed(const bkf_measure *m, double t_from, double t_to, double *speed,
                          double *speed_err, size_t *tracks, bkf_error *err);

int bkf_measure_summarize(const bkf_measure *m, bkf_measure_summary *summary, bkf_error *err);

#ifdef __cplusplus
}
#endif

#endif

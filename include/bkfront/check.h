/* The check of the predicted front speeds against seeded simulations.
 *
 * For every root of the speed-selection condition (bkf_speeds_find; every n,
 * or one n) the travelling wave of n fronts at the predicted speed is seeded
 * with a small band-limited perturbation and simulated for tmax; the
 * measured speed is compared with the prediction, and the run tells whether
 * the front keeps its count and shape.
 *
 * Grids.  The uniform spectral grid (bkf_pde) runs on the smallest N = N 2^k
 * that resolves the wave (Fourier coefficients above N/3 below `resolution`
 * of the largest); the adapted grid (bkf_comoving) puts `points` points per
 * wavelength where the wave's own length scales need them, in the frame of
 * v_pred.  BKF_CHECK_GRID_AUTO takes the uniform grid while it resolves the
 * wave on at most BKF_CHECK_AUTO_UNIFORM_MAX points, the adapted one beyond
 * (at the paper's parameters n <= 9 uniform, n = 10 .. 12 adapted).
 *
 * Measurements, on both grids the same: the deviation is max |psi - seeded
 * wave shifted with the fronts| (on the adapted grid, from the wave relaxed
 * onto the grid); the growth rate of the perturbation is fitted to the whole
 * linear part of the run (bkf_check_fit_growth; on the uniform grid also per
 * Bloch class, see bkf_check_row.growth); the speed is fitted over the later
 * half of the coherent part of the run (front count kept and deviation <=
 * max(100 perturb, 1e-6), raised to 10 times the largest deviation up to
 * t = min(10, tmax/4): the wave's response to the noise, which steep fronts
 * amplify a hundredfold before it decays, and the plateau a wave the grid
 * does not fully resolve settles on).  Samples every BKF_CHECK_SAMPLE_DT
 * (adapted grid BKF_CHECK_MAPPED_SAMPLE_DT, the chain every shift time), at
 * most BKF_CHECK_SAMPLES_MAX per run: memory does not grow with tmax.
 * Beside the run, the spectrum of the same train (bkf_trainspec_root): a
 * decided growth that contradicts it is a conflict (bkf_check_conflict).
 * The verdict is bkf_check_judge's.
 *
 * The chain (model kind BKF_MODEL_CHAIN, model->N blocks): every rotating
 * wave of bkf_chainwave_find (n = 1 .. N/2, or options->n; tolerance
 * BKF_CHECK_CHAIN_WAVE_TOL, with its multipliers) is set on the blocks
 * plus the band-limited noise (bkf_pde_add_noise) and simulated by bkf_pde
 * (rk8pd, tol options->tol or BKF_CHECK_CHAIN_RUN_TOL), sampled at every
 * shift time m tau, where the unperturbed wave is the start shifted by m
 * blocks, W_m.  There the state u = W_m + delta_m W_m' + w, W_m' the
 * field at W_m and w orthogonal to it: delta_m is the phase the fronts
 * have gained, which a speed v_meas = v_pred (1 + s) makes grow as s t, so
 * s is the least-squares slope of delta over the later half of the coherent
 * part (as above); the deviation is max |w| (the phase is not a
 * deviation: the time translation neither grows nor decays); the front
 * count is the number of rising crossings of nu around the ring.  The
 * growth fit, the verdict and the conflict rule are those of the
 * continuum, with the multipliers' verdict as the spectrum (sigma_max =
 * ln|m| / tau).  Row: grid BKF_CHECK_GRID_CHAIN, N the blocks, root the
 * wave's index within its n (1 the fastest), tail the wave's Newton
 * residual; options N, N_max, stepper, filter, frame, grid, points,
 * resolution and mapped_* are not used.
 *
 * The library never prints and never exits: rows go to the caller's
 * visitor, warnings to its warning callback. */
#ifndef BKFRONT_CHECK_H
#define BKFRONT_CHECK_H

#include <signal.h>
#include <stddef.h>
#include <stdio.h>

#include "bkfront/io.h"
#include "bkfront/model.h"
#include "bkfront/options.h"
#include "bkfront/pde.h"
#include "bkfront/status.h"
#include "bkfront/trainspec.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
    BKF_CHECK_GRID_AUTO = 0,    /* uniform up to BKF_CHECK_AUTO_UNIFORM_MAX, else mapped */
    BKF_CHECK_GRID_UNIFORM = 1, /* always the spectral grid, up to N_max */
    BKF_CHECK_GRID_MAPPED = 2,  /* always the adapted grid (moving frame only) */
    BKF_CHECK_GRID_CHAIN = 3    /* a row's grid only: the chain's own blocks */
} bkf_check_grid;

typedef enum {
    BKF_CHECK_FRAME_MOVING = 0, /* the frame of v_pred: the seeded wave is a steady state */
    BKF_CHECK_FRAME_LAB = 1     /* the lab frame (uniform grid only; auto means uniform) */
} bkf_check_frame;

/* How long each root's run is (continuum only; the chain's runs are
 * always full). */
typedef enum {
    BKF_CHECK_RUNS_AUTO = 0, /* each run stops once it has decided what any run up to tmax
                                could: see bkf_check_options.runs */
    BKF_CHECK_RUNS_FULL = 1  /* every run to tmax */
} bkf_check_runs;

typedef enum {
    BKF_CHECK_AGREES = 0,    /* stable (decided), |rel_err| <= rel_tol */
    BKF_CHECK_DISAGREES = 1, /* stable (decided), rel_err measured and beyond rel_tol */
    BKF_CHECK_UNSTABLE = 2,  /* count or shape not kept, or the spectrum unstable: the
                                speed is not judged */
    BKF_CHECK_UNRESOLVED = 3, /* not run to the end (see bkf_check_row.reason) */
    BKF_CHECK_CONFLICTS = 4, /* the run's decided growth contradicts the spectrum
                                (bkf_check_conflict): an error, whatever the speed */
    BKF_CHECK_UNDECIDED = 5  /* kept by the run, but its stability is decided neither by
                                the spectrum (refused, or within its error of 0) nor by
                                the run (growth not decays), or no speed was measured:
                                bkf_check_row.decide_tmax says what run would decide */
} bkf_check_verdict;

/* "agrees", "disagrees", "unstable", "unresolved", "conflicts",
 * "undecided"; "unknown" otherwise. */
const char *bkf_check_verdict_name(bkf_check_verdict verdict);
/* "auto", "uniform", "mapped", "chain"; "unknown" otherwise. */
const char *bkf_check_grid_name(bkf_check_grid grid);

/* The uniform grid's cap under BKF_CHECK_GRID_AUTO: from N = 16384 on the
 * adapted grid is the cheaper. */
#define BKF_CHECK_AUTO_UNIFORM_MAX 8192
/* The adapted grid's step budget per root: the paper's n = 10..12 take
 * 40-160 steps, an oscillating unstable wave (n = 3) ~2500; beyond it the
 * root is unresolved (BKF_EBUDGET) instead of running for many minutes. */
#define BKF_CHECK_MAPPED_MAX_STEPS 20000
/* Sample spacings of the measurements: the exponential stepper lands on
 * every sample, so on the uniform grid this is also its longest step. */
#define BKF_CHECK_SAMPLE_DT 0.25
#define BKF_CHECK_MAPPED_SAMPLE_DT 0.5
/* Beyond this many samples per run the spacing grows to tmax / 4096 (the
 * chain's: to a whole number of shift times): a run's records, and so its
 * memory, do not grow with tmax. */
#define BKF_CHECK_SAMPLES_MAX 4096
/* Defaults (see bkf_check_options). */
#define BKF_CHECK_N_DEFAULT 512
#define BKF_CHECK_N_MAX_DEFAULT 65536
#define BKF_CHECK_TMAX_DEFAULT 125.0
#define BKF_CHECK_ETD_TOL_DEFAULT 1e-7
#define BKF_CHECK_RK_TOL_DEFAULT 1e-9
#define BKF_CHECK_MAPPED_TOL_DEFAULT 1e-8
#define BKF_CHECK_REL_TOL_DEFAULT 1e-6
#define BKF_CHECK_PERTURB_DEFAULT 1e-6
#define BKF_CHECK_RESOLUTION_DEFAULT 1e-5
/* The chain: the waves' tolerance (their v to ~1e-10, so that a measured
 * speed is judged to 1e-8), and the run's local error tolerance. */
#define BKF_CHECK_CHAIN_WAVE_TOL 1e-10
#define BKF_CHECK_CHAIN_RUN_TOL 1e-12
#define BKF_CHECK_POINTS_DEFAULT 768
/* Ranges (see bkf_check_options). */
#define BKF_CHECK_FRONTS_MAX 100000
#define BKF_CHECK_POINTS_MIN 32
#define BKF_CHECK_POINTS_MAX 1048576
#define BKF_CHECK_TMAX_MAX 1e6
#define BKF_CHECK_PERTURB_MAX 0.1
#define BKF_CHECK_RESOLUTION_MIN 1e-16
#define BKF_CHECK_FILTER_MAX 1000.0

typedef struct {
    size_t n;             /* check this n only, [1, 100000]; 0 (default): every n with a root */
    size_t N;             /* smallest uniform grid, even, [8, BKF_PDE_N_MAX]; default 512
                             (the model's own N is not used: the check picks the grid) */
    size_t N_max;         /* largest uniform grid, [N, BKF_PDE_N_MAX]; roots needing more are
                             unresolved; default 65536, which with grid uniform resolves
                             every n at the paper's parameters but n = 12 (2^18 points,
                             ~16 minutes) */
    double tmax;          /* length of each run, (0, 1e6]; default 125 */
    bkf_pde_stepper stepper; /* uniform grid's stepper; default BKF_PDE_ETDRK4 */
    double tol;           /* uniform grid's local error tolerance, [1e-13, 1e-2]; 0 (default):
                             1e-7 with etdrk4 (its third-order error estimate is far above
                             its fourth-order error: at 1e-7 the paper-parameter speeds and
                             verdicts are those of 1e-9 at a third of the cost), 1e-9 with
                             the Runge-Kutta steppers */
    double filter;        /* spectral filter of bkf_pde, [0, 1000]; default 4 */
    double rel_tol;       /* agreement asked of a stable front, |rel_err|, (0, 1); default 1e-6 */
    double perturb;       /* rms of the noise added to the seeded wave, [0, 0.1]; default 1e-6 */
    unsigned long seed;   /* seed of that noise; default 1 */
    bkf_check_frame frame;   /* default BKF_CHECK_FRAME_MOVING */
    bkf_check_grid grid;     /* default BKF_CHECK_GRID_AUTO */
    size_t points;        /* adapted grid: points per wavelength, [32, 1048576]; default 768
                             (with mapped_tol 1e-8 the paper-parameter speeds agree to ~2e-9) */
    double mapped_tol;    /* adapted grid: CVODE's tolerance, [1e-13, 1e-2]; 0 (default): tol
                             when tol is set, else 1e-8 (well below the perturbation, so that
                             BDF's long steps do not damp a growing perturbation unseen) */
    size_t mapped_max_steps; /* adapted grid: step budget per root; default 20000 */
    double resolution;    /* spectral tail accepted as resolved, [1e-16, 1]; default 1e-5 */
    /* BKF_CHECK_RUNS_AUTO (default): tmax is the longest run, and a run stops
     * at the first of
     *   - the front lost: the count changed (count, growth and speed fits
     *     end there whatever follows, so the row is that of the full run
     *     but for fronts_end, deviation_mid, deviation_end and t_end);
     *   - at t = BKF_CHECK_AUTO_UNSTABLE_FIRST (only a row whose spectrum
     *     is decided unstable by a growth no fit within tmax resolves, with
     *     a speed measured and its growth undecided: its verdict is
     *     unstable whatever the run), then from t = BKF_CHECK_AUTO_FIRST on,
     *     every BKF_CHECK_AUTO_EVERY, the row judged on the run so far (no
     *     conflict) is settled:
     *       spectrum decided stable: agrees, with |rel_err| + 3 v_meas_err /
     *       v_pred <= rel_tol (the run only confirms the speed);
     *       spectrum decided unstable: a speed measured, and the growth
     *       decided grows, or sigma_max + its error below ln 2 / (tmax - t0),
     *       t0 = min(10, tmax/4), which no fit within tmax resolves (the
     *       run can neither see nor contradict it);
     *     an unresolved spectrum runs to tmax.
     * A row that disagrees or conflicts always has its whole run.  On the
     * adapted grid the second run that measures the grid's error in the
     * speed (v_meas_err) is made only for rows that agree or disagree (the
     * only ones whose speed is judged); elsewhere v_meas_err is NaN.
     * BKF_CHECK_RUNS_FULL: every run to tmax, v_meas_err always measured. */
    bkf_check_runs runs;
    size_t threads;       /* roots checked at once (OpenMP threads, each root's row the
                             same as in a serial run), [0, 4096]; 0 (default): every core */
} bkf_check_options;

/* The auto runs' checkpoints (see bkf_check_options.runs): the first at
 * t = 40, past the noise's response (t0 = 10) by three times its length, so
 * that a growth fit there spans 30 time units.  A row whose spectrum is
 * decided unstable by a growth no fit within tmax resolves has its verdict
 * (unstable) whatever the run, which adds only a speed: that row settles
 * already at t = 20 when its growth fit there decides nothing (its speed
 * fitted over [10, 20]; the paper's n = 7..11: half the run). */
#define BKF_CHECK_AUTO_FIRST 40.0
#define BKF_CHECK_AUTO_UNSTABLE_FIRST 20.0
#define BKF_CHECK_AUTO_EVERY 20.0
#define BKF_CHECK_THREADS_MAX 4096

/* Exactly the defaults of `bkfront check`. */
bkf_check_options bkf_check_options_default(void);

/* Validation alone: BKF_EINPUT with a one-line message naming the option
 * (or model parameter) and its range.  The model needs gamma in the cycle
 * solver's range, c >= 0, |nu| < 1 and S > 0; kind continuum (N not used:
 * the check picks the grid) or chain (bkf_chainwave_check: N blocks in
 * [2, 400], gamma <= 30, n <= N). */
int bkf_check_validate(const bkf_model_params *model, const bkf_check_options *options,
                       bkf_error *err);

/* The growth rate of a perturbation from its amplitude a(t) sampled over a
 * run.  The amplitude of a sum of modes exp(sigma t) oscillates (a complex
 * pair beats, several modes interfere: factors of 20-30 are common), so two
 * samples say little.  The fit:
 *   - the samples with t in [t_from, t_to] (the caller's linear part of the
 *     run, after the initial transient), L = their time span;
 *   - their envelope: the largest a in each of BKF_CHECK_GROWTH_WINDOWS
 *     equal windows of [t_from, t_to];
 *   - rate: least-squares slope of ln(envelope) against the maxima's
 *     times (a beating mode's peaks lie on its exponential wherever they
 *     fall in their windows); rate_err: its standard error from the
 *     residuals and half the bend, the difference of the two halves'
 *     (4 windows each) slopes, and at least ln 2 / (2.5 L), the fit's
 *     resolution (a transient slower than the fit, or two modes closer
 *     than about 1 / L, give an envelope as straight as one mode's);
 *   - limit = 2.5 rate_err, so at least ln 2 / L: 2.5 is the two-sided 95%
 *     point of Student's t at 6 degrees of freedom (8 windows, 2
 *     parameters), and a rate below ln 2 / L changes the amplitude by less
 *     than a factor 2 over the whole fit, which the residual wobble of an
 *     envelope can fake;
 *   - unless the envelope bends: the bend beyond its noise (2.78 times its
 *     standard error from the halves' residuals, Student's t at 4 degrees
 *     of freedom) and beyond 0.1 / L.  Then it is not one exponential over
 *     the fit (a start-up transient still rising, a slower mode still
 *     fading) and the whole slope is a mixture of rates: rate is the later
 *     half's slope, rate_err its standard error and the whole bend (the
 *     slope may move as much again), at least ln 2 / (2.5 L/2), and
 *     limit = 2.5 rate_err;
 *   - verdict: grows when rate > limit, decays when rate < -limit, else
 *     undecided (also when there are fewer than 2 samples per window, or an
 *     amplitude is not finite and positive).
 * A rate within limit of 0 is not a measurement of its sign. */
#define BKF_CHECK_GROWTH_WINDOWS 8

typedef enum {
    BKF_CHECK_GROWTH_UNDECIDED = 0,
    BKF_CHECK_GROWTH_GROWS = 1,
    BKF_CHECK_GROWTH_DECAYS = 2
} bkf_check_growth_verdict;

/* "undecided", "grows", "decays"; "unknown" otherwise. */
const char *bkf_check_growth_name(bkf_check_growth_verdict verdict);

typedef struct {
    double rate, rate_err;   /* per unit time; NaN when not fitted */
    double limit;            /* the detection limit above; NaN when not fitted */
    double from, to;         /* the samples' time span */
    bkf_check_growth_verdict verdict;
    double bend;             /* the later half's slope minus the earlier's; NaN when
                                not fitted */
    int bends;               /* 1: bend beyond its noise, rate the later half's */
} bkf_check_growth;

/* Fits `count` samples (t increasing) as above into *growth (always
 * written; undecided with NaN rate when there is too little to fit). */
void bkf_check_fit_growth(const double *t, const double *amplitude, size_t count, double t_from,
                          double t_to, bkf_check_growth *growth);

/* Whether a decided growth contradicts the spectrum: grows while the
 * spectrum is stable (every sigma but the translation below 0 beyond its
 * error), or decays while it is unstable with sigma_max above the fit's
 * detection limit (a weaker instability is invisible to the run).
 * Undecided never contradicts; nor does an unresolved spectrum. */
int bkf_check_conflict(const bkf_check_growth *growth, bkf_trainspec_verdict spectral,
                       double sigma_max);

/* One root's result.  NaN where a quantity was not measured. */
typedef struct {
    size_t n, root;         /* fronts, and the root (1: fastest) of bkf_speeds_find */
    bkf_check_grid grid;    /* UNIFORM or MAPPED: the grid used (or tried last) */
    size_t N;               /* points of that grid; 0: unresolved within N_max */
    double tail;            /* uniform: the seed's spectral tail on the last grid tried;
                               mapped: max |relaxed wave - seed| */
    double v_pred, v_pred_err;  /* predicted speed and its estimated error */
    double v_meas, v_meas_err;  /* measured speed (towards -x) and its uncertainty
                                   (adapted grid: the fit's plus the grid's, from
                                   a second run on 2/3 of the points) */
    double rel_err;         /* (v_meas - v_pred) / v_pred */
    double fit_from, fit_to;    /* the fit's time window */
    double t_end;           /* the run's end: tmax, or earlier when it blew up or (runs
                               auto) stopped once settled; NaN not run */
    double fronts_start, fronts_end; /* front counts at t = 0 and t = t_end */
    double deviation_start, deviation_mid, deviation_end; /* at 0, t_end/2, t_end */
    /* The perturbation's growth rate (bkf_check_fit_growth) over the linear
     * part of the run: from t = min(10, tmax/4) while the count is n and the
     * deviation is <= max(1e-3, 10 perturb).  Fitted to the deviation and,
     * on the uniform grid, to each Bloch class j = 1 .. n/2 of psi: the
     * Fourier coefficients at wavenumbers k = +-j mod n (k in 2 pi / S),
     * where the wave has none, so that they hold the perturbation alone
     * and in the linear regime its modes exp(sigma t) of Bloch number
     * kappa = 2 pi j / S alone (the drift of the fronts turns their phase,
     * not their modulus).  growth is the fit with the largest rate, its
     * verdict grows when any fit grows, decays when every fit decays. */
    bkf_check_growth growth;
    /* The spectrum of the same train (bkf_trainspec_root, tol 1e-4, again at
     * 1e-6 where that leaves the sign of sigma_max undecided; the
     * rightmost sigma per Bloch number): decided STABLE or UNSTABLE, or not
     * decided, UNRESOLVED: sigma_max within its error of 0, or refused (a
     * warning says why; also when the spectrum found no eigenvalue but the
     * translation in its window, which bounds sigma_max by the window's edge
     * but does not measure it). */
    bkf_trainspec_verdict spectral;
    double sigma_max, sigma_max_err; /* NaN when refused or only bounded: a window's
                                        edge is not an eigenvalue */
    double kept;            /* 1 count and shape kept (the run did not blow up, the count
                               never changed, deviation_end <= 1e-2, growth not grows),
                               0 not, NaN not run; not a stability verdict (that is
                               verdict): a kept front can be unstable by its spectrum */
    bkf_check_verdict verdict;
    /* Undecided only: the tmax of a run whose growth fit would resolve the
     * growth still in question (the spectrum's sigma_max + its error when it
     * gives one, else the run's own |growth|), from the fit's detection
     * limit, which falls as 1/L with the fit's length L; NaN when no run up
     * to BKF_CHECK_TMAX_MAX would (a warning then names what would: the
     * spectrum, or a smaller perturbation when no speed was measured). */
    double decide_tmax;
    int reason;             /* a bkf_status: BKF_OK for a run to the end; unstable:
                               BKF_EBLOWUP when the run blew up; unresolved: BKF_ETOL (not
                               resolved within N_max, or the root's speed refused by
                               bkf_speeds_find: v_pred NaN, not run, a warning says
                               why), BKF_EBUDGET (the adapted grid's step
                               budget ran out), or the status of the adapted grid's failed
                               set-up (BKF_EINPUT, BKF_ENUMERIC; a warning says which) */
} bkf_check_row;

/* The verdict from the measured quantities and the spectrum, the one rule
 * of every grid.  The run kept the front (*kept, may be NULL, gets 1)
 * when it did not blow up, the count never changed and started at n,
 * deviation_end is finite and <= 1e-2, and the growth was not decided
 * "grows".  Then: conflicts when bkf_check_conflict; else unstable when the
 * run did not keep the front or the spectrum is unstable (an instability
 * too slow for the run: the spectrum resolves what the run cannot); else,
 * unless the spectrum is decided stable or the run's growth decays (a
 * kept front is not a stable one: a growth below the run's detection limit
 * stays unseen), undecided; else undecided when rel_err is not finite (no
 * speed measured is no disagreement); else agrees when |rel_err| <=
 * rel_tol, else disagrees.  The verdict never outruns its evidence. */
bkf_check_verdict bkf_check_judge(size_t n, int blew_up, int count_constant, size_t fronts_start,
                                  double deviation_end, const bkf_check_growth *growth,
                                  bkf_trainspec_verdict spectral, double sigma_max, double rel_err,
                                  double rel_tol, int *kept);

/* What the run is about to do, handed to the begin callback. */
typedef struct {
    size_t roots;           /* rows to come */
    double k;               /* bkf_speeds_table.k */
    long n_max;             /* bkf_speeds_table.n_max */
    const char *speeds_note; /* bkf_speeds_table.note ("" when none); valid
                                during the call only */
    double tol, mapped_tol; /* the tolerances in effect (defaults resolved) */
    size_t N_cap;           /* the largest uniform grid in effect (N_max, or the auto cap) */
} bkf_check_info;

typedef struct {
    /* Called once before the first root (may be NULL).  Nonzero stops the
     * check (BKF_OK, no rows). */
    int (*begin)(const bkf_check_info *info, void *data);
    /* Called once per root, in bkf_speeds_find order, as soon as it and
     * every root before it are done (may be NULL).  Nonzero stops the check
     * (BKF_OK).  Every callback is called from one thread at a time. */
    int (*row)(const bkf_check_row *row, void *data);
    /* Fraction of the whole check done, in [0, 1], every few steps. */
    void (*progress)(double fraction, void *data);
    /* One line without a newline, e.g. "n = 10, root 1 reported unresolved:
     * ..." (a root whose adapted grid cannot be set up); a root's warnings
     * come just before its row, in the order of a serial run. */
    void (*warning)(const char *message, void *data);
    void *data;             /* handed to each callback */
    /* When non-NULL and *cancel becomes nonzero (e.g. in a signal
     * handler), the check stops within a step: BKF_ECANCELED, the rows done
     * so far delivered. */
    const volatile sig_atomic_t *cancel;
} bkf_check_hooks;

/* Runs the check.  hooks may be NULL.  BKF_EINPUT as bkf_check_validate;
 * BKF_ECANCELED; BKF_ENOMEM; BKF_ENUMERIC (or the simulation's own status)
 * when a root's run fails otherwise than by the outcomes above (the
 * message names n, root and grid). */
int bkf_check_run(const bkf_model_params *model, const bkf_check_options *options,
                  const bkf_check_hooks *hooks, bkf_error *err);

/* The check as a product (`bkfront check`, a scene's check step): a spec
 * filled from bkf_check_spec_default through the table bkf_check_keys,
 * checked, and written as the table of rows with its comment lines. */
typedef struct {
    bkf_model_params model;    /* gamma, c, nu, S, kind (key model); N not used: with
                                  kind chain the blocks are options.N, S when it is
                                  BKF_CHECK_N_DEFAULT (beyond the chain's range) */
    bkf_check_options options; /* frame lab with grid auto means grid uniform */
} bkf_check_spec;

/* The paper's model and bkf_check_options_default: `bkfront check`. */
bkf_check_spec bkf_check_spec_default(void);

/* The keys, named as the flags: gamma, c, nu, S, model, n, N, N-max, tmax,
 * runs, threads, tol, filter, stepper, rel-tol, perturb, seed, frame, grid,
 * points, resolution;
 * scene keys only: mapped-tol, mapped-max-steps.  (Not bkf_check_options,
 * the name of the run's options.) */
extern const bkf_option bkf_check_keys[];
extern const size_t bkf_check_nkeys;

/* What the table cannot judge key by key (N even, N-max >= N, frame lab
 * not with grid mapped), then bkf_check_validate; messages name the keys
 * with `prefix` ("--" or ""). */
int bkf_check_spec_check(const bkf_check_spec *spec, const char *prefix, bkf_error *err);

/* Runs the check and writes the whole table (comments, header, rows) to
 * `out`, once every root is done: on a failure of the run nothing is
 * written.  hooks (may be NULL): progress, warning and cancel as for
 * bkf_check_run; begin and row are called too, after the write's own.
 * When a stable front disagrees (verdict disagrees) or a run's growth
 * contradicts the spectrum (verdict conflicts), the table is written in
 * full and the status is BKF_ENUMERIC, the message naming the n, and
 * *disagree (may be NULL; otherwise set to 0) gets their count: a caller
 * tells this outcome from a failed run by *disagree > 0. */
int bkf_check_write(const bkf_check_spec *spec, FILE *out, bkf_io_format format,
                    const bkf_provenance *provenance, const bkf_check_hooks *hooks,
                    size_t *disagree, bkf_error *err);

#ifdef __cplusplus
}
#endif

#endif

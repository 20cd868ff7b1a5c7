/* Direct simulation of the model on a periodic domain of size S:
 *
 *     psi_t = gamma (eta - phi(psi)),   eta_t = -(psi - nu - c^2 L psi) / gamma,
 *
 * phi(psi) = psi^3/3 - psi, on N points x_i = i S/N, i = 0 .. N-1.
 *
 *  - BKF_MODEL_CONTINUUM: L is the spectral second derivative (FFTW3 real
 *    transforms); N even, >= 8 (any even size works, sizes with small prime
 *    factors are fastest; a power of two is not required).
 *  - BKF_MODEL_CHAIN: the Burridge-Knopoff chain, Eq. (1) of the paper, in the
 *    same variables: L psi_i = (psi_{i+1} - 2 psi_i + psi_{i-1}) / h^2 with
 *    h = S/N.  N = S (h = 1) is the physical chain of S blocks; larger N
 *    refines it towards the continuum (second order in h).
 *
 * Time stepping: an explicit embedded Runge-Kutta pair from GSL odeiv2
 * (default rk8pd, Dormand-Prince 8(7)) under a local error control with
 * absolute and relative tolerance `tol` on every component, our own loop so
 * that the derivative at the end of a step starts the next one.  Samples
 * (for measurements and frames) are step ends: a step that would pass a
 * sample time is cut there, so a sample is as accurate as any step end (a
 * quintic Hermite between the ends of an 8th-order step was 1000 times
 * worse than tol; the cut steps cost about 20% more work at sample_dt 0.1).
 * The step is capped at kappa/omega_max,
 * omega_max = sqrt(1 + c^2 q_max^2), q_max = pi N/S (continuum) or 2N/S
 * (chain), kappa = 3 for rk8pd (where it damps on the imaginary axis) and
 * 0.5 for the 5th-order pairs: the error control cannot see the highest
 * mode while it is at rounding level and would otherwise let it grow.  For
 * large N this cap sets the step, so a run costs ~N^2 log N.
 *
 * Allocation plans FFTs, and FFTW's planner is not thread-safe: allocate
 * from one thread at a time (concurrent runs have not been tested).
 *
 * The spectral filter.  psi_t gets the extra term -F psi, F diagonal in
 * Fourier space with rate sigma_k = sigma_max (k/k_top)^16: modes near the
 * grid's Nyquist are damped (at rate sigma_max/2), modes below k_top/2 feel
 * less than 2e-5 sigma_max.  Without it, modes within ~10% of the Nyquist
 * wavenumber grow at ~0.1 per unit time from rounding in the front states,
 * through the pointwise cubic (the same modes decay on a grid twice as fine,
 * so it is the grid, not the model); a seeded front then breaks up after
 * t ~ 150-250 whatever N and tol.  A resolved field has no content there, so
 * the filter does not change it beyond its own resolution error.
 *
 * Two scalar quadratures ride along with the field (they are part of the
 * integrated state), for the checks in the tests and the diagnostics:
 *   Q(t) = integral of the spatial mean of psi: then
 *          mean(eta)(t) + (Q(t) - nu t)/gamma is conserved exactly by the
 *          semi-discrete system and by any Runge-Kutta method (a linear
 *          invariant), to rounding;
 *   D(t) = integral of -gamma h sum_i phi'(psi_i) u_i psi_t,i (the work of
 *          the friction, u = gamma (eta - phi(psi)) = psi_t without the
 *          filter) plus the filter's work h sum_i gamma eta_t,i (F psi)_i,
 *          so that H(t) - D(t) is conserved, with the energy
 *          H = h sum_i [u^2/2 + (psi - nu)^2/2 - c^2 psi (L psi)/2].
 *
 * The moving frame (frame_speed V != 0, continuum only).  The fields are
 * psi(xi, t) with xi = x - V t, so both equations get the advection term
 * + V d/dxi (spectral; the Nyquist mode's derivative is 0).  A travelling
 * wave moving at velocity V is then a steady state, and an explicit
 * Runge-Kutta method keeps a steady state exactly (every stage is 0): the
 * error control no longer sees the jumps sweep past, and the steps grow to
 * the stability cap, which becomes kappa/(omega_max + |V| q_max).  Front
 * positions and speeds measured on such a run are relative to the frame
 * (add V for the lab).  The quadrature D is then the general
 * dH/dt = h sum [u u_t + (psi - nu - c^2 L psi) psi_t] with the actual
 * psi_t and eta_t (the advection's discrete work included), so H - D stays
 * conserved to the time integration's error.
 *
 * The exponential integrator (stepper BKF_PDE_ETDRK4, continuum only, no
 * dealiasing; src/pde_etd.c).  Cox-Matthews ETDRK4 with the linear wave
 * part of every mode (and a moving frame's advection) solved exactly, the
 * friction, the filter and nu/gamma explicit: no stability cap from N, and
 * a steady state of the semi-discrete system (the seeded wave in the frame
 * of its speed) is kept exactly.  Local error control with the same tol,
 * relative to the state's largest |psi|.  Steps land on the sample times,
 * so samples are step ends, not interpolated.  The quadratures Q and D are
 * not integrated: samples, bkf_pde_dissipation, bkf_pde_mean_integral and
 * the energy and mean residuals give NaN for it.
 *
 * Stepper BKF_PDE_LAWSON8 shares that integrator's variables, sampling and
 * limits (continuum only, no dealiasing) but takes Lawson
 * (integrating-factor) steps: GSL's rk8pd on v = exp(-L tau) u over each
 * step, its embedded estimate against the same tol.  It integrates the
 * quadratures Q and D as the Runge-Kutta path does (the same stages, the
 * same control tol (1 + |Q|), tol (1 + |D|)); on moving fronts D's error,
 * not the fields', sets its steps (0.02 at tol 1e-9, where the fields
 * alone allowed 0.025).  Eighth order: at tol
 * 1e-9 a moving front takes steps of 0.02 where etdrk4 takes 0.003 and
 * rk8pd is capped at 3/omega_max (0.008 at N 8192), the same number of
 * steps from N 512 to 16384 (to 65536 before the quadratures): the modes that turn by more than 3.5 pi a
 * step feel only their own branch of the explicit term (its coupling
 * of the two branches, oscillating at 2 w_k, resonated in rk8pd's stages
 * and grew them from rounding; see src/simulation/pde_etd.c), at the
 * price of two more transform pairs per evaluation.  A steady state of the semi-discrete system
 * is kept to tol only (the stages rotate N(u) away from -L u), so in a
 * travelling wave's frame etdrk4's steps are longer.  Where the modes
 * k >= kin are left out of F's input, its product holds |k| < 3 kin only,
 * and the stages form it without aliasing on M > 6 kin points instead of
 * N (the same rates; stats.product_points): on a resolved field the
 * stages' transforms no longer grow with N (N 65536, n = 4 front: 6144
 * points).
 *
 * The library never prints and never exits; long runs report progress
 * through a callback. */
#ifndef BKFRONT_PDE_H
#define BKFRONT_PDE_H

#include <signal.h>
#include <stddef.h>
#include "bkfront/model.h"
#include "bkfront/status.h"

#ifdef __cplusplus
extern "C" {
#endif


typedef enum {
    BKF_PDE_RK8PD = 0,  /* Dormand-Prince 8(7): the default, best at tight tol */
    BKF_PDE_RKCK = 1,   /* Cash-Karp 5(4) */
    BKF_PDE_RKF45 = 2,  /* Runge-Kutta-Fehlberg 4(5) */
    BKF_PDE_ETDRK4 = 3, /* exponential Runge-Kutta (Cox-Matthews), continuum only;
                           see "The exponential integrator" above */
    BKF_PDE_LAWSON8 = 4 /* integrating-factor rk8pd, continuum only: see "The
                           exponential integrator" */
} bkf_pde_stepper;

/* The steppers' names, indexed by bkf_pde_stepper, NULL-terminated. */
extern const char *const bkf_pde_stepper_names[];

/* The stepper a product's "auto" means for this model: lawson8 for the
 * continuum from N = BKF_PDE_AUTO_LAWSON_N on without dealiasing (its steps
 * do not shrink with N, rk8pd's are capped by the fastest wave mode: at
 * tol 1e-9 lawson8 is 1.6 times faster at N 4096 and about 1.1 times slower
 * at 2048, docs/benchmarks.md), else rk8pd. */
#define BKF_PDE_AUTO_LAWSON_N 4096
bkf_pde_stepper bkf_pde_stepper_auto(const bkf_model_params *model, int dealias);

#define BKF_PDE_N_MIN 8
#define BKF_PDE_N_MAX 1048576
/* The continuous-slip state psi = nu, eta = phi(nu) lies well within the
 * field's blow-up bound 1e6 (phi(100) = 3.3e5) for |nu| <= BKF_PDE_NU_MAX. */
#define BKF_PDE_NU_MAX 100.0
/* gamma in [1e-6, 1e6] (the cycle engine's range of mu); the fastest wave
 * rate c k_max (k_max = pi N/S, 2 N/S for the chain) at most 1e12: beyond,
 * no step is resolved and the right-hand side nears overflow. */
#define BKF_PDE_GAMMA_MIN 1e-6
#define BKF_PDE_GAMMA_MAX 1e6
#define BKF_PDE_WAVE_MAX 1e12
#define BKF_PDE_TOL_MIN 1e-13
#define BKF_PDE_TOL_MAX 1e-2

/* The model: bkf_model_params (model.h), with gamma in [BKF_PDE_GAMMA_MIN,
 * BKF_PDE_GAMMA_MAX], c >= 0 with c k_max <= BKF_PDE_WAVE_MAX, nu finite
 * (|nu| >= 1 is allowed: continuous slip; |nu| <= BKF_PDE_NU_MAX), S > 0, N in [BKF_PDE_N_MIN,
 * BKF_PDE_N_MAX] (even for the continuum). */

typedef struct {
    double tol;              /* local error tolerance, abs and rel; default 1e-9 */
    bkf_pde_stepper stepper; /* default rk8pd */
    int dealias;             /* continuum only: project the right-hand side on
                                |q| <= (N/3) 2 pi/S (2/3 rule); default 0 */
    double filter;           /* continuum only: sigma_max of the spectral filter
                                F, sigma_k = sigma_max (k/k_top)^16 (k_top: N/2,
                                or the 2/3-rule cutoff); 0 turns it off;
                                default 4 (see below); the chain
                                ignores it */
    size_t max_steps;        /* per run call; 0: no limit */
    /* Cancellation: when non-NULL and *cancel becomes nonzero (e.g. set by a
     * signal handler), bkf_pde_run stops after the step in progress and
     * returns BKF_ECANCELED; the state is that of the last accepted step
     * (bkf_pde_time), every sample up to it has been delivered.  Default
     * NULL. */
    const volatile sig_atomic_t *cancel;
    double frame_speed;      /* continuum only: velocity V of the frame the
                                fields live in, xi = x - V t (see below);
                                default 0, the lab frame */
} bkf_pde_options;

bkf_pde_options bkf_pde_options_default(void);

/* Validation alone: BKF_EINPUT with a one-line message naming the parameter
 * and its range. */
int bkf_pde_check(const bkf_model_params *params, const bkf_pde_options *options,
                  bkf_error *err);

typedef struct bkf_pde bkf_pde;

/* NULL with err filled on bad input (BKF_EINPUT) or out of memory.  The state
 * starts as uniform continuous slip psi = nu, eta = phi(nu), t = 0. */
bkf_pde *bkf_pde_alloc(const bkf_model_params *params, const bkf_pde_options *options,
                       bkf_error *err);
void bkf_pde_free(bkf_pde *pde);

const bkf_model_params *bkf_pde_get_params(const bkf_pde *pde);
size_t bkf_pde_size(const bkf_pde *pde);        /* N */
double bkf_pde_spacing(const bkf_pde *pde);     /* h = S/N */
double bkf_pde_time(const bkf_pde *pde);
const double *bkf_pde_psi(const bkf_pde *pde);  /* N values at x_i = i h */
const double *bkf_pde_eta(const bkf_pde *pde);

/* Sets the field (arrays of N finite values, |value| <= 1e6, the bound
 * beyond which a run counts as blown up) and the time; the quadratures
 * Q and D restart from 0. */
int bkf_pde_set_state(bkf_pde *pde, const double *psi, const double *eta, double t,
                      bkf_error *err);

/* ------------------------------------------------------ initial conditions */

/* psi = nu + a random trigonometric polynomial with the modes 1 <= j <= J,
 * J = floor(S/2) (wavelengths down to two blocks of the chain; also capped
 * below the grid's Nyquist mode), Gaussian coefficients from `seed`, scaled
 * to rms `amp`; eta = phi(psi), so psi_t = 0.  The same seed gives the same
 * function of x at every N. */
int bkf_pde_init_uniform(bkf_pde *pde, double amp, unsigned long seed, bkf_error *err);

/* The global oscillation (the limit cycle at mu = gamma, which needs
 * |nu| < 1) at the phase where psi = nu rising, plus amp cos(q_j x) added to
 * psi, with q_j = 2 pi j/S, 0 <= j < N/2. */
int bkf_pde_init_oscillation(bkf_pde *pde, size_t j, double amp, bkf_error *err);

/* Adds band-limited noise of rms `amp` in [0, 10] to psi (eta unchanged),
 * drawn as bkf_pde_init_uniform's: the same seed gives the same function of
 * x at every N.  The global oscillation plus noise is an arbitrary start
 * near the oscillation, every mode perturbed at once; added to a state set
 * by bkf_pde_set_state (a computed wave of the chain), its perturbation.
 * The time is kept. */
int bkf_pde_add_noise(bkf_pde *pde, double amp, unsigned long seed, bkf_error *err);

/* What n fronts of a travelling wave are: the request that
 * bkf_seed_front (products/seed.h) turns into a bkf_pde_wave by solving the
 * speed condition. */
typedef struct {
    size_t n;            /* fronts in the domain */
    size_t root;         /* 1: the fastest root for this n, in bkf_speeds_find order */
    int direction;       /* -1: fronts move towards -x (the default), +1: towards +x */
    double noise;        /* rms of band-limited noise added to psi (as in _uniform); 0: none */
    unsigned long seed;
    double tol;          /* accuracy of the speed root and the cycle; default 1e-12 */
} bkf_pde_front_spec;

bkf_pde_front_spec bkf_pde_front_spec_default(void); /* n 1, root 1, -x, no noise */

/* The wave to seed: n fronts at speed v, the cycle at mu (both from the
 * speeds solver; mu = gamma v / sqrt(v^2 - c^2) there). */
typedef struct {
    size_t n;            /* fronts in the domain, >= 1 */
    double v;            /* speed, > c */
    double mu;           /* the cycle's mu, in [BKF_CYCLE_MU_MIN, BKF_CYCLE_MU_MAX] */
    int direction;       /* -1 or +1, as in bkf_pde_front_spec */
    double noise;        /* as in bkf_pde_front_spec */
    unsigned long seed;
    double tol;          /* accuracy of the cycle, [1e-14, 1e-4] */
} bkf_pde_wave;

typedef struct {
    double v;            /* predicted speed (> c), from bkf_speeds_find */
    double v_err;        /* its estimated absolute error (bkf_seed_front; NaN
                            from bkf_pde_init_front alone) */
    double mu;           /* gamma / sqrt(1 - c^2/v^2) */
    double T;            /* period of the cycle in z */
    double stretch;      /* sqrt(1 - c^2/v^2) */
    double period_fixed; /* T * stretch: period in t at a fixed point */
    double wavelength;   /* S / n */
    double residual;     /* n T v stretch / S - 1: how far the seed is from
                            periodic in x */
    size_t roots_for_n;  /* roots the speeds solver found for this n
                            (bkf_seed_front; 0 from bkf_pde_init_front) */
} bkf_pde_front_info;

/* The travelling wave psi(x, 0) = f(z), z = (x/v)/stretch for direction -1
 * (z = -(x/v)/stretch for +1), f the limit cycle of
 * f'' + mu (f^2 - 1) f' + f = nu, and eta = psi_t/gamma + phi(psi) with
 * psi_t = f'(z)/stretch.  In the model, psi(x, t) = f((x/v + t)/stretch)
 * moves towards -x at speed v.  Needs |nu| < 1 and v > c (BKF_EINPUT
 * otherwise); the wave is not checked to be periodic in x (info->residual
 * says how far).  On the continuum, psi and eta each lose the modes above
 * what the profile resolves: those from the lowest k0 whose field stays
 * within the cycle's tolerance times the field's largest |value| (its
 * rounding, white and at the wrap, would otherwise fill every mode up to
 * the grid's Nyquist; see src/simulation/pde.c: band_limit).  `info` may be NULL; `clean_psi`, if non-NULL, receives the
 * N values of psi before the noise. */
int bkf_pde_init_front(bkf_pde *pde, const bkf_pde_wave *wave, bkf_pde_front_info *info,
                       double *clean_psi, bkf_error *err);

/* --------------------------------------------------------------------- run */

/* A state handed to the observer: a step's end (steps are cut at the
 * sample times). */
typedef struct {
    double t;
    const double *psi, *eta;  /* N values each, valid during the call only */
    double Q, D;              /* the quadratures (see above) at t */
} bkf_pde_sample;

/* Called at each sample time.  Return nonzero to stop the run early
 * (bkf_pde_run then returns BKF_OK). */
typedef int (*bkf_pde_observer)(const bkf_pde_sample *sample, void *data);
/* Called every few steps with the fraction done in [0, 1].  Nonzero stops the
 * run (BKF_OK as above). */
typedef int (*bkf_pde_progress)(double fraction, void *data);

typedef struct {
    size_t steps, rejected, rhs_calls;
    size_t samples;
    double h_last, h_min, h_max;  /* accepted step sizes */
    int stopped;                  /* an observer or the progress callback stopped it */
    /* lawson8: the summed error estimates of D's quadrature over the step
     * ends (D's share of energy_residual's error; 0 for the other steppers,
     * whose error control holds D with the fields) */
    double d_err;
    /* lawson8: the points the last step's stages formed the explicit term
     * on, fewer than N where the modes above the field's content are left
     * out of its input (see "The exponential integrator"); N otherwise and
     * for the other steppers */
    size_t product_points;
} bkf_pde_stats;

/* Integrates from the current time to t_end (> current time), calling
 * `observer` (may be NULL) at t0 + k sample_dt for k = 0, 1, ... while
 * <= t_end, and at t_end (once, also when it falls on the grid).
 * sample_dt > 0.  Stats accumulate over calls (reset with _stats_reset).
 * BKF_EBLOWUP if the field blows up (non-finite or |psi| > 1e6, also a step
 * that keeps leaving the finite range), BKF_EBUDGET if max_steps is
 * exceeded, BKF_ENUMERIC if the step size underflows (tol cannot be met);
 * BKF_ECANCELED when options.cancel was raised (see above). */
int bkf_pde_run(bkf_pde *pde, double t_end, double sample_dt, bkf_pde_observer observer,
                void *observer_data, bkf_pde_progress progress, void *progress_data,
                bkf_error *err);

const bkf_pde_stats *bkf_pde_get_stats(const bkf_pde *pde);
void bkf_pde_stats_reset(bkf_pde *pde);

/* ----------------------------------------------------------- diagnostics */

/* H of the current state (see above), and the quadratures D and Q. */
double bkf_pde_energy(bkf_pde *pde);
double bkf_pde_dissipation(const bkf_pde *pde);  /* D */
double bkf_pde_mean_integral(const bkf_pde *pde); /* Q */

/* Resolution of a field of N values on this grid: the largest modulus of
 * its Fourier coefficients with k > N/3, relative to the largest one
 * (k >= 1); 0 for a constant field.  Near rounding (1e-16) the field is
 * resolved; the 2/3 rule would change it by about this much. */
double bkf_pde_spectral_tail(bkf_pde *pde, const double *field);

/* H for an arbitrary field (N values), e.g. a sample. */
double bkf_pde_energy_of(bkf_pde *pde, const double *psi, const double *eta);

/* The same residuals for a sample of the current run. */
double bkf_pde_sample_energy_residual(bkf_pde *pde, const bkf_pde_sample *sample);
double bkf_pde_sample_mean_residual(const bkf_pde *pde, const bkf_pde_sample *sample);

/* The energy balance residual H(t) - H(t_set) - D(t), and the linear
 * invariant's drift mean(eta)(t) - mean(eta)(t_set) + (Q(t) - nu (t - t_set))/gamma,
 * both measured from the last set_state/init call. */
double bkf_pde_energy_residual(bkf_pde *pde);
double bkf_pde_mean_residual(const bkf_pde *pde);

#ifdef __cplusplus
}
#endif

#endif

/* A seeded travelling wave simulated in its own frame on an adapted grid.
 *
 * Near the sonic limit v -> c the fronts' jumps get very thin: the jump of
 * the cycle of f'' + mu (f^2 - 1) f' + f = nu lasts ~ 2/mu in z, and z =
 * x/(v stretch), so its width in x is ~ 2 v stretch/mu = 2 (v^2 - c^2)/(gamma v).
 * At the paper's parameters, n = 12 has mu = 47 and jumps 5e-4 wide on a
 * domain of 20: the uniform spectral grid needs N = 2^18 (bkf_pde, ~16
 * minutes).  This module puts the points where the wave needs them.
 *
 * Model: the continuum of bkf_pde, in the frame xi = x + v t that moves with
 * the predicted fronts (which move towards -x at speed v):
 *     psi_t = -v psi_xi + gamma (eta - phi(psi)),
 *     eta_t = -v eta_xi - (psi - nu - c^2 psi_xixi)/gamma,
 * periodic in xi with period S.  The seeded wave is a steady state.
 *
 * Grid.  xi = g(s) on M = n m points s_j = j S/M: the same map on each of
 * the n wavelengths, m points per wavelength.  Within a wavelength the
 * points first equidistribute the density (in z)
 *     rho = sqrt(b^2 + (f'/D)^2 + sqrt((f''/D)^2 + b^4) + cbrt((f'''/D)^2 + b^6)),
 * whose terms are inverse local length scales of the wave (D = max f - min
 * f), so a layer gets points in proportion to its own width whatever that
 * is (jumps ~ 1/mu, folds ~ mu^(-1/3)); b sets the background (b T = half
 * the integral without it, about a third of the points spread evenly).
 * That map comes from integrating the cycle with s as the independent
 * variable (GSL rk8pd).  Its periodic part is then convolved with a
 * Gaussian of max(3 cells, 1/(4 I)) of a wavelength (I = the integral of
 * rho: a fixed width in s, so the map converges as m grows; a positive
 * kernel keeps it increasing), and g', g'' are its spectral derivatives.
 * The seed is the cycle's profile at the smoothed points.
 *
 * Space: central differences of order 8 in s (radius 4),
 *     psi_xi = D1 psi / g',   psi_xixi = (D2 psi - (g''/g') D1 psi) / g'^2,
 * plus a grid-scale damping -(v + c)/(256 g' h) delta^8 on both fields
 * (delta^8 the eighth undivided difference, symbol 256 sin^8(k h/2)): at the
 * grid's Nyquist mode it damps at the rate (v + c)/(g' h) of the fastest
 * characteristic crossing a cell, resolved modes feel O((k h)^8) of it
 * (formally order 7, as an upwind scheme).  Without it the grid-scale
 * waves in the densest cells (frequencies ~ 1e5 at n = 12) never decay
 * and the integrator must follow them.
 *
 * Relaxation.  The continuum's wave is not the grid's: their difference
 * (the truncation error, largest in the jumps) would set off fast waves.
 * So before the noise is added, the seed is relaxed onto the grid's own
 * travelling wave by backward Euler steps of lengths 1e-3, 0.01, 0.1, 1, 3 (each
 * a Newton solve with the same exact Newton matrix as the run's, up to 8
 * iterations until the correction stalls at its rounding floor, 1e-8 ..
 * 1e-6, 3e-5 in a hard case; above 1e-3 it is BKF_ENUMERIC: pseudo-
 * transient continuation, which damps every mode faster than ~0.3 per
 * unit time, growing or not, while the wave drifts by only (v_grid - v)
 * 4.1; a last step of 10 was faster still, but its Newton iteration does
 * not converge).  The relaxed wave is what
 * the run perturbs and the reference the deviation is measured from.  Every
 * wavelength is alike, so the relaxation runs on one and is copied to the
 * n (n = 12 at the paper's parameters: 0.08 s against 0.47 s on all 12).
 * With a resolution, the points per wavelength are the fewest of points x
 * {1/3, 1/2, 2/3, 1} whose relaxed wave is within it of the continuum's,
 * each tried on one wavelength (the paper's n = 10: 384, change 3.3e-6;
 * n = 12: 768).
 *
 * Time: SUNDIALS CVODE (variable order BDF, 1..5, stability limit
 * detection), modified Newton with the exact Newton matrix I - gamma J: J
 * is analytic (rhs is linear but for phi(psi)), and the psi-eta coupling
 * of the psi row is diagonal (gamma), so the eta unknowns are eliminated
 * and the M psi unknowns solve a periodic system of half bandwidth 2 R
 * points, banded (half bandwidth 4 R = 16) in the order 0, M-1, 1, M-2, ...
 * and factored by SUNDIALS' band LU: half the unknowns and a band as wide
 * as the whole 2 M system's (4 R + 1), so about half its cost to solve
 * and a quarter to factor (n = 12 at the paper's parameters: the run to
 * t = 40 in 1.3 s against 2.5 s).  Local error tolerance `tol`, relative
 * and absolute; the integrator interpolates the samples (its steps do not
 * land on them).
 * BDF of order 3 to 5 is not A-stable: where a weakly damped fast wave
 * falls in its unstable band the error control holds the steps at the
 * band's edge (gamma 0.5, c 0.75, nu -0.88, S 25.8, n = 21: 20000 steps
 * before t = 40).  Once CVODE's stability-limit detection counts an order
 * reduction, the run goes back to the start of that bkf_comoving_run call
 * and runs again, as do later calls, with BDF at order 2 (A-stable; 209
 * steps there); a run that never meets the limit is unchanged.
 * Keep tol well below the perturbation: at tol 1e-6 BDF's long steps damp a
 * slowly growing oscillatory perturbation of amplitude 1e-5 unseen (n = 3
 * at the paper's parameters looks stable); at 1e-8 it grows as in the
 * spectral simulation.
 *
 * Measurements (per sample): fronts are the upward crossings (in xi) of
 * `level`, with hysteresis 0.1 as in bkf_measure, located by the cubic
 * through the four nearest points in s; their displacement since t = 0 is
 * tracked per front (relative to the frame); the deviation is
 * max_j |psi_j - psi_relaxed(xi_j - d)|, d the fronts' mean displacement,
 * the shifted relaxed wave from 8-point Lagrange interpolation in s.
 *
 * The library never prints and never exits. */
#ifndef BKFRONT_COMOVING_H
#define BKFRONT_COMOVING_H

#include <signal.h>
#include <stddef.h>

#include "bkfront/measure.h"
#include "bkfront/model.h"
#include "bkfront/pde.h"
#include "bkfront/status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    /* model: gamma > 0, c >= 0, |nu| < 1, S > 0; N and kind are not used
     * (the grid is n points per wavelength, the continuum) */
    bkf_model_params model;
    size_t n;             /* fronts in the domain, >= 1 */
    double v;             /* the wave's speed, > c: fronts move towards -x at v,
                             the frame with them; the wave is the cycle at
                             mu = gamma v / sqrt(v^2 - c^2) */
    size_t points;        /* m, points per wavelength, [32, 1 << 20]; default 768;
                             with a resolution the most */
    double tol;           /* CVODE's tolerance, [1e-13, 1e-2]; default 1e-8 */
    double noise;         /* rms of band-limited noise added to psi, as in
                             bkf_pde_init_uniform: the same function of x for
                             the same seed; default 0 */
    unsigned long seed;   /* default 1 */
    double cycle_tol;     /* accuracy of the cycle; default 1e-12 */
    double level;         /* fronts are upward crossings of this level; NaN
                             (the default): bkf_measure_front_level(&model) */
    size_t max_steps;     /* per run call; 0: no limit (the default) */
    const volatile sig_atomic_t *cancel; /* as in bkf_pde_options */
    double resolution;    /* > 0: the fewest points of points x {1/3, 1/2, 2/3, 1}
                             whose relaxed wave is within this of the
                             continuum's (relax_change; points itself whatever
                             its change), [0, 1]; 0 (the default): points */
} bkf_comoving_params;

#define BKF_COMOVING_POINTS_MIN 32
#define BKF_COMOVING_POINTS_MAX (1 << 20)

/* Defaults for the optional fields; model.gamma, .c, .nu, .S, n and v must
 * be set. */
bkf_comoving_params bkf_comoving_params_default(void);

typedef struct bkf_comoving bkf_comoving;

/* Solves the cycle, builds the grid and seeds the wave (plus the noise).
 * NULL with err filled: BKF_EINPUT for bad parameters (one line naming the
 * parameter and its range), BKF_ENUMERIC when the cycle or the map cannot be
 * built to the tolerances, BKF_ENOMEM. */
bkf_comoving *bkf_comoving_alloc(const bkf_comoving_params *params, bkf_error *err);
void bkf_comoving_free(bkf_comoving *m);

size_t bkf_comoving_size(const bkf_comoving *m);     /* M = n m */
const double *bkf_comoving_grid(const bkf_comoving *m); /* M positions xi_j, increasing */
double bkf_comoving_time(const bkf_comoving *m);
const double *bkf_comoving_psi(const bkf_comoving *m); /* M values at xi_j */
const double *bkf_comoving_eta(const bkf_comoving *m);
double bkf_comoving_mu(const bkf_comoving *m);
double bkf_comoving_min_spacing(const bkf_comoving *m);
double bkf_comoving_max_spacing(const bkf_comoving *m);

/* Integrates to t_end (> current time), recording a measurement at every
 * t0 + k sample_dt <= t_end and at t_end (interpolated by CVODE), and
 * calling `progress` (may be NULL) after each.  BKF_ENUMERIC when CVODE
 * fails (the message is CVODE's), BKF_EBLOWUP when the field blows up
 * (non-finite or |psi| > 1e6: the records up to there are kept), BKF_EBUDGET
 * when max_steps is exceeded; BKF_ECANCELED when *cancel was raised. */
int bkf_comoving_run(bkf_comoving *m, double t_end, double sample_dt, bkf_pde_progress progress,
                     void *progress_data, bkf_error *err);

typedef struct {
    double t;
    size_t fronts;        /* upward crossings of the level */
    double displacement;  /* mean displacement of the fronts since t = 0, in the
                             frame; NaN when the count differs from the first */
    double deviation;     /* max |psi - relaxed wave shifted by displacement|; NaN
                             as above */
} bkf_comoving_record;

size_t bkf_comoving_count(const bkf_comoving *m);
const bkf_comoving_record *bkf_comoving_record_at(const bkf_comoving *m, size_t i);

/* The fronts' drift velocity in the frame (d displacement/dt, > 0 towards
 * +xi) fitted over the records with t in [t_from, t_to], which must keep the
 * first count of fronts; the uncertainty as in bkf_measure:
 * sqrt(se^2/n + spread^2/n + (v_a - v_b)^2/4) over the n fronts' own slopes,
 * their standard errors se, spread and the two halves' fits v_a, v_b.
 * BKF_ENUMERIC with fewer than 3 records. */
int bkf_comoving_fit_drift(const bkf_comoving *m, double t_from, double t_to, double *drift,
                           double *drift_err, bkf_error *err);

typedef struct {
    size_t steps, rhs_calls, jacobians, newton_iterations, error_failures; /* jacobians:
                             the Newton matrix's set-ups, each with J at that state */
    double h_last;
    size_t relax_newton;  /* Newton iterations of the seed's relaxation */
    double relax_change;  /* max |psi_relaxed - psi_seed|: how far the grid's
                             wave is from the continuum's (including its
                             drift during the relaxation) */
    int blew_up;          /* the last run stopped on a blown-up field */
    int over_budget;      /* the last run stopped at max_steps */
    int max_order;        /* BDF's highest order allowed: 5, or 2 once a run met
                             the stability limit and was restarted (see Time) */
    size_t discarded_steps; /* steps of the runs so restarted, counted in steps
                             (the other counts are the restarted integration's) */
} bkf_comoving_stats;

void bkf_comoving_get_stats(const bkf_comoving *m, bkf_comoving_stats *stats);

#ifdef __cplusplus
}
#endif

#endif

/* The period-doubled pacemakers as a branch of periodic orbits of the PDE
 * (`bkfront orbit`, issue 34 items 3-4): born where the global oscillation
 * loses stability through a Floquet multiplier at -1 for an allowed mode
 * q_j = 2 pi j/S of the ring (module floquet), followed by pseudo-arclength
 * continuation (core continuation) in nu, gamma, c or S through folds, each
 * point polished and judged by module orbit (Newton-Krylov shooting, the
 * Floquet multipliers by Arnoldi).
 *
 * The switch.  The period-doubling point p* of mode j is the root of
 * lambda(q_j; p) = 0 with the dominant multiplier negative (Brent on
 * floquet's lambda, after a scan of p from `from` towards `to`).  There the
 * monodromy M_q of the oscillation has the eigenvector v = (v_psi, v_eta)
 * for m = -1; the guess for the new orbit is the oscillation at its section
 * (psi = nu rising) plus eps v cos(q_j x), with period 2T.  A first leg of
 * the continuation holds that mode's amplitude (the branch leaves the
 * oscillation as a pitchfork of the period-2T problem, vertical in p), a
 * second follows p.  The period is an unknown throughout: it is near 2T,
 * never set to it.
 *
 * The continuation's unknowns.  The orbit is even about x = 0 (the critical
 * mode is a cosine; the model is reflection-symmetric) and repeats over
 * cells of length S/j (continuum; the chain where j divides N): the state of
 * one cell as cosine coefficients a_k, k = 0..N_c/2, of psi and eta, the
 * period P and the parameter p.  Equations: the coefficients of
 * Phi_P(u) - u (the simulator's flow, bkf_pde_run, rk8pd) and the phase
 * condition mean(psi) = nu at t = 0.  The Jacobian by central differences
 * of the flow.  Folds are those of the continuation in p.
 *
 * Each point (every located fold included) is then solved again by
 * bkf_orbit_solve on the full domain (cells = j, the continuum's shift
 * free, so that the even symmetry is not assumed) to `tol` with its error
 * estimate, and its multipliers computed by bkf_orbit_multipliers.  A point
 * whose polish or multipliers fail is a row whose numbers are NaN and whose
 * verdict is undecided, with the reason: never the continuation's unchecked
 * value.
 *
 * The library never prints and never exits. */
#ifndef BKFRONT_ORBITS_H
#define BKFRONT_ORBITS_H

#include <signal.h>
#include <stddef.h>
#include <stdio.h>
#include "bkfront/io.h"
#include "bkfront/model.h"
#include "bkfront/options.h"
#include "bkfront/orbit.h"
#include "bkfront/status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
    BKF_ORBITS_NU = 0,
    BKF_ORBITS_GAMMA = 1,
    BKF_ORBITS_C = 2,
    BKF_ORBITS_S = 3
} bkf_orbits_param;

/* "nu", "gamma", "c", "S". */
const char *bkf_orbits_param_name(bkf_orbits_param p);

/* The points per cell of the continuum when N is not given. */
#define BKF_ORBITS_CELL_POINTS 32
#define BKF_ORBITS_POINTS_MAX 100000u

typedef struct {
    bkf_model_params model;  /* gamma, c, nu, S, kind; N 0: BKF_ORBITS_CELL_POINTS j
                                (continuum), round(S) (chain) */
    size_t j;                /* the mode; 0: the allowed mode nearest floquet's q_c */
    bkf_orbits_param along;  /* the continuation's parameter */
    double from, to;         /* the scan for p* runs from `from` towards `to`; the
                                branch stays within [min, max] of the two */
    size_t max_points;       /* points of the branch (folds not counted) */
    double tol;              /* each point's accuracy (bkf_orbit_solve's tol) */
    double step;             /* the continuation's largest step (scaled units) */
    int stability;           /* multipliers per point (1) or none (0) */
    size_t k;                /* multipliers per Bloch sector */
    double switch_amplitude; /* the critical mode's amplitude in psi at the first point */
    int (*progress)(double fraction, void *data);
    void *progress_data;
    const volatile sig_atomic_t *cancel;
} bkf_orbits_options;

/* The paper's model, along nu from -0.90 to -0.999, 50 points, tol 1e-3,
 * step 0.5, stability on, k 2, switch amplitude 0.02. */
bkf_orbits_options bkf_orbits_options_default(void);

/* The period-doubling point of the global oscillation for mode j. */
typedef struct {
    bkf_model_params model;  /* the parameters there (p in its place) */
    double p, p_err;         /* the parameter's value and the error of the root */
    size_t j;
    double q, q_eff;         /* 2 pi j/S; the chain's (2/h) sin(q h/2) */
    double period, period_err; /* T of the oscillation there */
    double m_re, lambda, lambda_err; /* the multiplier (~ -1), ln|m| (~ 0) */
    double v_psi, v_eta;     /* its eigenvector at the section, max-norm 1 */
    double psi0, eta0;       /* the section point psi = nu, eta there */
} bkf_orbits_pd;

/* The period-doubling point of mode j (0: auto) along options->along,
 * scanning from options->from towards options->to (steps 0.005 in nu, 2%
 * of the value otherwise), located to about tol.  BKF_ENUMERIC when the scan
 * meets none (the message says where it looked). */
int bkf_orbits_pd_find(const bkf_orbits_options *options, bkf_orbits_pd *pd, bkf_error *err);

/* What happened between a point and the previous one, by the multipliers
 * outside the unit circle and the continuation's folds (flags). */
enum {
    BKF_ORBITS_EV_FOLD = 1u << 0,          /* a located fold in p */
    BKF_ORBITS_EV_PERIOD_DOUBLING = 1u << 1, /* a real negative multiplier crossed |m| = 1 */
    BKF_ORBITS_EV_TORUS = 1u << 2,         /* a complex pair crossed |m| = 1 */
    BKF_ORBITS_EV_REAL = 1u << 3,          /* a real positive one crossed (branch point) */
    BKF_ORBITS_EV_STABILITY = 1u << 4      /* the verdict changed stable <-> unstable */
};

/* "fold+period_doubling" etc. into buf ("-" for none). */
const char *bkf_orbits_events_text(unsigned events, char *buf, size_t size);

typedef struct {
    size_t index;            /* 0: the bifurcation point itself (the oscillation) */
    int is_fold;
    int is_start;            /* row 0: the period-doubling point of the oscillation */
    bkf_model_params model;  /* the parameters of the point */
    double p;                /* along's value */
    double period, period_err; /* P (NaN when the point was refused) */
    double shift;
    double amplitude;        /* max over t in [0, P) of max_x psi - min_x psi */
    double mode_amplitude;   /* the critical mode's amplitude in psi at t = 0 (the
                                continuation's; 0 at the bifurcation) */
    double err;              /* bkf_orbit_result.err */
    double cont_period;      /* the continuation's P (a check on the polish) */
    const char *status;      /* "ok", or why the numbers are NaN */
    int has_spectrum;
    bkf_orbit_verdict verdict;
    double m_abs, m_re, m_im, m_err; /* the largest physical multiplier */
    size_t out_plus, out_minus, out_complex; /* physical |m| > 1: real > 0, real < 0, pairs */
    unsigned events;
    const bkf_orbit_result *orbit;     /* the polished orbit (NULL: none); valid in the visit */
    const bkf_orbit_spectrum *spectrum;/* valid in the visit */
    const double *psi, *eta;           /* the full-domain state at t = 0, valid in the visit */
    const struct bkf_orbits_report *report; /* the switch's point, cells, N so far */
} bkf_orbits_point;

typedef int (*bkf_orbits_visit)(const bkf_orbits_point *point, void *data);

typedef struct bkf_orbits_report {
    bkf_orbits_pd pd;
    size_t cells, N, cell_points;
    size_t points, folds, refused;
    size_t flows;            /* the continuation's flows */
    int reached_bound;
} bkf_orbits_report;

/* The branch: pd found, row 0 (the oscillation's point), then every point
 * of the continuation in order, each passed to visit (nonzero: stop).
 * Memory does not grow with the branch.  BKF_OK also when the run ends on
 * a bound, max_points or the visitor; the continuation's failure to go on
 * (step below its minimum) ends the run with BKF_ENUMERIC after the rows
 * so far. */
int bkf_orbits_branch(const bkf_orbits_options *options, bkf_orbits_visit visit, void *data,
                      bkf_orbits_report *report, bkf_error *err);

/* ---------------------------------------------------------- the product */

#define BKF_ORBITS_NU_FROM (-0.90)
#define BKF_ORBITS_NU_TO (-0.999)

typedef struct {
    double gamma, c, nu, S;  /* NaN: the paper's; the one named by along is not given */
    int model;               /* 0 continuum, 1 chain */
    size_t N;                /* 0: auto (orbits_default_N) */
    size_t j;                /* 0: auto */
    int along;               /* bkf_orbits_param */
    double from, to;         /* NaN: along nu -0.90 and -0.999; required otherwise */
    size_t max_points;
    double tol, step;
    int no_stability;
    size_t k;
    double switch_amplitude;
    double at;               /* the orbit written to the files: the row whose parameter is
                                nearest `at` (NaN: the last row with a result) */
    const char *spacetime;   /* file: psi(x, t) of that orbit over two periods */
    const char *multipliers; /* file: its multipliers */
    /* Item 6 of issue 34: a regime table of bkfront sweep (its columns point,
     * gamma, c, nu, S, regime) read, and per row at this branch's gamma, c, S
     * the solutions known there written to `coexistence`: the global
     * oscillation's stability on the ring (floquet, every allowed mode with
     * c q <= 6), the orbits of the branch at that nu and how many are stable,
     * and whether the simulated regime is one of the stable states. */
    const char *regimes;
    const char *coexistence;
    /* not keys: */
    int (*progress)(double fraction, void *data);
    void *progress_data;
    const volatile sig_atomic_t *cancel;
} bkf_orbits_spec;

bkf_orbits_spec bkf_orbits_spec_default(void);

/* The keys: gamma, c, nu, S, model, N, j, along, from, to, max-points, tol,
 * step, no-stability, k, switch-amplitude, at, spacetime, multipliers. */
extern const bkf_option bkf_orbits_spec_options[];
extern const size_t bkf_orbits_spec_noptions;

/* What the table cannot judge key by key; messages name the keys with
 * prefix. */
int bkf_orbits_check(const bkf_orbits_spec *spec, const char *prefix, bkf_error *err);

/* The spec as the engine's options (after bkf_orbits_check). */
bkf_orbits_options bkf_orbits_options_of(const bkf_orbits_spec *spec);

/* The branch as a table, rows written as they come (the stream holds a
 * partial table on failure: the caller discards it), and the files of the
 * orbit nearest `at`, each replaced atomically. */
int bkf_orbits_write(const bkf_orbits_spec *spec, FILE *out, bkf_io_format format,
                     const bkf_provenance *provenance, bkf_error *err);

#ifdef __cplusplus
}
#endif

#endif

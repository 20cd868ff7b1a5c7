/* Internal to the spectra of front trains (src/stability/trainspec.c, the
 * ring and the line; trainspec_mode.c, single eigenvalues and their
 * eigenfunctions): the context, the Radau meshes and the pieces both use.
 * Not installed, not part of the API. */
#ifndef BKFRONT_TRAINSPEC_INTERNAL_H
#define BKFRONT_TRAINSPEC_INTERNAL_H

#include <complex.h>
#include <math.h>
#include <signal.h>
#include <stddef.h>
#include <stdlib.h>

#include "bkfront/cycle.h"
#include "bkfront/hill.h"
#include "bkfront/trainspec.h"

#define TOL_MIN BKF_TRAINSPEC_TOL_MIN
/* The profile comes from a cycle solved to 1e-12: its share of an
 * eigenvalue's error, per unit |sigma| (at least 1), measured by the
 * nu -> -nu symmetry (whose two cycles differ) at below 1e-9. */
#define PROFILE_ERROR 2e-9
#define TOL_MAX BKF_TRAINSPEC_TOL_MAX
#define PER_KAPPA_MAX 50
/* Mesh multiplier (substeps) of the first pass. */
#define SUBSTEPS_START 1
#define MESH_MAX_STEPS 100000
#define MESH_MIN_STEPS 16
/* Heights sampled per family on the first pass, and the finest interval as
 * a fraction of the window. */
#define CURVE_START 48
#define CURVE_MIN_FRACTION (1.0 / 65536.0)
/* The traced curves' a is located to this (absolute, see height_at). */
#define TRACE_TOL 1e-6
/* Newton steps per family and height before the bracketing takes over. */
#define TRACE_NEWTON_MAX 3
#define Y_MAX_LIMIT 1e4
#define NEWTON_MAX 30
#define MESH_REFINEMENTS 4
#define RESOLVE_TURN 0.5
/* The window reaches this far left of the axis, per unit gamma (or to
 * r_inf / 2 if that is nearer). */
#define WINDOW_DEPTH 0.05
/* The edges of a curve (where it leaves the window) are located to this
 * fraction of the window's height; phase and bends to CURVE_MIN_FRACTION. */
#define EDGE_FRACTION (1.0 / 1024.0)
#define MAX_WORK_DEFAULT 2.5e7
/* A long (stiff) step is used where the fast solution decays by at least
 * this many e-foldings per step over the whole window's Re sigma. */
#define STIFF_MIN 1.0
/* Through the fronts the coefficients change faster than the local rates
 * tell: a step spans at most this change of the profile f (measured: at
 * mu 47 it cuts the error of a 1400-step mesh from 1.6e-4 to 2e-7). */
#define PROFILE_TURN 0.03
/* The constants above resolve the paper's eigenvalues to about 1e-10
 * (estimates of 2e-9 at every tol, the profile's share PROFILE_ERROR
 * alone): at tol 1e-6 the meshes were 500 times finer than asked.  The
 * fifth-order step's error grows as its length to the fifth, so the
 * non-stiff steps' limits (turns, profile change, share of a cycle step)
 * are loosened by (tol / COARSEN_TOL)^(1/5), at most COARSEN_MAX: the
 * earlier meshes at the smallest tol, 2.5 times longer steps at 1e-6,
 * where the paper's estimates were then at most 1.5e-7 (n = 11) and the
 * first pass still met tol (3 at 1e-5 and above: 3.2e-7).  The stiff runs
 * keep theirs (at mu 47 they carry the error and the first pass needs a
 * refinement already: a coarser start there costs more, and with every
 * step 2.5 times longer the translation's first value, 2e-3, lay beyond
 * its recognition).  The turn of the oscillating solution at the window's
 * top is loosened too: the L-stable step damps it by 1.3e-4 a step at a
 * turn of 1 (2e-6 at 0.5), which moves the curves' candidates and shows
 * in the polish's pair of meshes. */
#define COARSEN_TOL TOL_MIN
#define COARSEN_MAX 3.0
/* The cycle's own mesh (adapted to the cycle at tol 1e-12) knows where the
 * coefficients change fast better than the rates do: each of its steps
 * takes at least this share of a step. */
#define NODE_SHARE 0.5
/* The fine mesh halves every step of the coarse one and the Radau step is
 * fifth order: the fine value's error is the difference / 31 once the
 * meshes converge (measured ratios 27-32 at mu 4 to 47, 19 on the first,
 * unconverged pair at mu 47); dividing by 8
 * keeps a margin of 4. */
#define RICHARDSON 8.0

/* The polish meshes resolve |sigma| up to this factor times the largest of
 * the candidates it may polish (plus POLISH_REACH_MIN): Newton's path from a
 * candidate stays near it.  So do bkf_trainspec_track's, from the values it
 * starts from. */
#define POLISH_MARGIN 1.25
#define POLISH_REACH_MIN 0.05

/* An eigenvalue's error from its values on a coarse and a fine mesh (sc,
 * sf), the fine Newton step and the profile's own error: one formula for
 * the ring spectrum and the followed eigenvalues, so both report alike. */
static inline double trainspec_estimate(double complex sc, double complex sf, double step_f)
{
    return cabs(sf - sc) / RICHARDSON + step_f + PROFILE_ERROR * fmax(1.0, cabs(sf));
}

enum { FAMILIES = 2 };

/* Coefficients at the three Radau IIA points of every step,
 * u'' = a u' + (b0 + beta sigma (sigma + gamma phi)) u. */
typedef struct {
    size_t steps;
    double *h, *a, *b0, *phi; /* h per step; a, b0, phi: STRIDE per step */
    unsigned char *pstep;     /* per step: taken in p's basis (stiff), else in u's */
    /* per step, the parts of the stage matrix G and of A bp that do not
     * depend on sigma (see radau_step): G0, M = A diag(phi) A (9 each),
     * A b0 and A phi (3 each) */
    double *g0, *m, *ab0, *aphi;
    double trace_sum;         /* the steps' quadratures of the trace: ln det M */
} mesh;

enum { STRIDE = 3 };

typedef struct {
    double gamma, c, nu, mu, v, s, beta, T, log_m, S, L;
    size_t n;
    double tol;
    bkf_cycle *cycle;
    double *nodes; /* cycle mesh 0..T */
    size_t node_count;
    size_t substeps;
    double sigma_reach; /* largest |sigma| the meshes must resolve */
    double re_floor;    /* smallest Re sigma the meshes must serve (Radau steps
                           need the fast solution to decay there) */
    double *need;       /* per cycle step: the steps it needs at sigma_reach (see mesh_needs) */
    unsigned char *stiff; /* per cycle step: stiff, its steps taken in p's basis (mesh_needs) */
    mesh coarse, fine;
    size_t evaluations;
    double work, max_work;               /* steps taken, and allowed */
    const volatile sig_atomic_t *cancel;
    int stop;                            /* BKF_EBUDGET or BKF_ECANCELED once either is hit */
} ctx;

/* The context of one train: its cycle, solved to 1e-12, the cycle's mesh,
 * the budget and the two Radau meshes (coarse, fine). */
int trainspec_ctx_init(ctx *x, const bkf_model_params *p, const bkf_trainspec_train *t, double tol,
                       const bkf_trainspec_options *o, bkf_error *err);
void trainspec_ctx_free(ctx *x);
/* The steps each cycle step needs for |sigma| up to reach (x->need). */
int trainspec_mesh_needs(ctx *x, double reach, bkf_error *err);
/* The step boundaries of a mesh of `substeps` times the steps needed. */
int trainspec_mesh_bounds(ctx *x, size_t substeps, double **bounds, size_t *steps, bkf_error *err);
/* A mesh on the boundaries bounds[0..steps]: the coefficients at each step's Radau points. */
int trainspec_mesh_fill(ctx *x, const double *bounds, size_t steps, mesh *m, bkf_error *err);
int trainspec_mesh_build(ctx *x, size_t substeps, mesh *m, bkf_error *err);
void trainspec_mesh_free(mesh *m);
/* The Radau IIA step i at sigma, turned into p's basis where it is taken
 * in u's, and its sigma-derivative when de is not NULL. */
void trainspec_radau_step(const ctx *x, const mesh *m, size_t i, double complex sigma, double complex e[4],
                          double complex de[4]);
/* Keeps v's entries near 1 in modulus, the factor's log into *scale. */
void trainspec_rescale(double complex *v, size_t count, double *scale);
/* The monodromy of p over mesh m at sigma (times exp(*scale)), its derivative into dp when not NULL. */
void trainspec_monodromy_matrix(ctx *x, const mesh *m, double complex sigma, double complex p[4],
                                double complex *dp, double *scale);
/* Both multipliers' logs w at sigma over mesh m (w[0] the larger), and
 * their sigma-derivatives into dw when not NULL. */
void trainspec_monodromy(ctx *x, const mesh *m, double complex sigma, double complex w[2], double complex *dw);
/* phase wrapped into [-pi, pi) */
double trainspec_wrap(double phase);
/* Newton on the multiplier exp(i theta) over mesh m from *sigma; deriv (may
 * be NULL): both families' sigma-derivatives from a coarser mesh's polish,
 * used in place of a pass with the derivative, and the last computed ones. */
int trainspec_polish(ctx *x, const mesh *m, double theta, double complex *sigma, double *last_step,
                     double complex deriv[2]);
/* The reason a search was cut short (budget, cancel), over rc. */
int trainspec_stopped(const ctx *x, int rc, bkf_error *err);

/* The window searched: Re sigma in [a_lo, a_hi]. */
typedef struct {
    double a_lo, a_hi;
} window;

/* Candidates for eigenvalues, from the traced curves and from Hill's method. */
typedef struct {
    double a, y;   /* interpolated sigma */
    size_t cls;    /* phase class: the multiplier's phase is 2 pi cls / classes */
    int fam;
    int conj;      /* mirrored from y > 0 */
} candidate;

typedef struct {
    candidate *items;
    size_t count, cap;
} candidates;

/* Appends c (BKF_ENOMEM when out of memory). */
static inline int trainspec_cand_push(candidates *cs, candidate c)
{
    if (cs->count == cs->cap) {
        size_t cap = cs->cap ? 2 * cs->cap : 1024;
        candidate *g = realloc(cs->items, cap * sizeof *g);
        if (!g) return BKF_ENOMEM;
        cs->items = g;
        cs->cap = cap;
    }
    cs->items[cs->count++] = c;
    return BKF_OK;
}

/* The window of a train (Re sigma > a_lo, a_hi its first right end) and
 * the spectrum's asymptote r_inf. */
window trainspec_initial_window(const ctx *x, double *r_inf);

/* Per polished eigenvalue, both families' sigma-derivatives at its last
 * polish (trainspec_polish): the next, finer mesh's polish steps with them. */
typedef struct {
    double complex d[2];
    double complex coarse; /* its value on the coarse mesh (polish_candidates) */
} derivs;

/* The traced curves (trainspec_curves.c). */
/* The coarse mesh for a window up to height B (the fine one is dropped). */
int trainspec_meshes_for(ctx *x, double B, const window *win, bkf_error *err);
/* Both families traced over [0, B], B grown until the curves leave the
 * window in its upper quarter; their candidates into cs, the heights
 * sampled added to *points, the window's height into *y_max. */
int trainspec_curves(ctx *x, size_t classes, window *win, candidates *cs, double *y_max, size_t *points,
                     bkf_error *err);

/* Hill's stage (trainspec_hill.c). */
/* Hill's converged eigenvalues polished, per class, at most (the rightmost first). */
#define HILL_PER_CLASS 6
/* Hill's eigenvalues agree at M and the finer truncation this well
 * (absolute) to be candidates; the polish takes them from there */
#define HILL_CONVERGED 1e-5
/* Hill's value and the polished one agree this well (relative to 1 +
 * |sigma|) where Hill's band stands alone */
#define HILL_AGREE 1e-3
/* the share of the work budget the trace may spend where Hill answered */
#define HILL_TRACE_SHARE 0.2

typedef struct {
    size_t modes;        /* M, 0 when Hill was not used */
    size_t modes_fine;   /* the finer truncation compared with M */
    double y_trust;      /* the band's height: the largest |Im sigma| converged */
    int complete;        /* in every class, no unconverged eigenvalue lies right of the
                            converged ones: Hill vouches for the rightmost of its band */
    int descended;       /* the spectrum leaves the band (HILL_DESCENT) */
    double complex *at;  /* candidates pushed (for the agreement check) */
    size_t count;
    size_t thetas;       /* classes 0..classes/2 */
    bkf_hill_eigenvalue *fine;  /* per class, the spectrum at modes_fine (the next round's coarse) */
    bkf_hill_eigenvalue *conv;  /* scratch: every class's converged eigenvalues */
    double work;         /* sizes cubed solved so far */
} hill_stage;

/* Hill's first round (mu <= HILL_MU_MAX and within HILL_WORK; h->modes 0
 * otherwise): its converged eigenvalues right of a_lo into cs. */
int trainspec_hill_candidates(ctx *x, size_t classes, const window *win, candidates *cs, hill_stage *h,
                              bkf_error *err);
/* M grown until the band vouches for its rightmost or the cost is spent. */
int trainspec_hill_grow(ctx *x, size_t classes, const window *win, candidates *cs, hill_stage *h, bkf_error *err);
void trainspec_hill_stage_free(hill_stage *h);
/* Hill's candidates (cs's with fam < 0, from `modes` modes) validate the
 * polished eigenvalues eig[0..*n_eig) (trainspec.c): where one lies right
 * of its class's rightmost beyond that one's error and Hill's agreement
 * HILL_CONVERGED, the meshes polish it (coarse, then fine: eig's meshes)
 * and it is taken if it stays within HILL_AGREE of Hill's value, else the
 * spectrum is refused (BKF_ETOL).  The traced curves can step over an
 * eigenvalue (two of one class closer than the sampled phase tells):
 * where Hill has converged, the rightmost never rests on them alone.
 * eig and dv must hold one more entry per Hill candidate.  Candidates
 * left of floor are not validated (-inf: none; the rightmost alone cuts
 * them at the rightmost polished, as polish_candidates does). */
int trainspec_hill_validate(ctx *x, size_t classes, size_t modes, double floor, const candidates *cs,
                            bkf_trainspec_eigenvalue *eig, derivs *dv, size_t *n_eig, bkf_error *err);

#endif

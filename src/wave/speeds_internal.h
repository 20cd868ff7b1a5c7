/* Internal to the speeds (src/wave/speeds.c, speeds_search.c,
 * speeds_polish.c, speeds_branch.c): the tuning constants, the grid and
 * search state and the pieces the files share.  Dependencies point one way:
 * speeds_branch.c -> speeds.c (the rows) -> speeds_polish.c ->
 * speeds_search.c.  Not installed, not part of the API. */
#ifndef BKFRONT_SPEEDS_INTERNAL_H
#define BKFRONT_SPEEDS_INTERNAL_H

#include <gsl/gsl_roots.h>
#include <math.h>
#include <stddef.h>

#include "bkfront/cycle.h"
#include "bkfront/model.h"
#include "bkfront/speeds.h"

/* Grid samples only decide signs; 1e-6 costs a third of 1e-10 at mu ~ 50. */
#define COARSE_TOL 1e-6
#define GRID_STEP 0.3
#define CELL_MIN 1e-6
#define MAX_SAMPLES 4000
/* A cell's enclosure within this many times its ends' noise of their
 * values is not bisected (speeds_search.c, noise_bound). */
#define NOISE_BAND 2.0
/* Tail certificate (A3). */
#define TAIL_MU_MIN 10.0
#define TAIL_KNEE_FRACTION 0.25
#define TAIL_LOG_DOMINANCE 4.0
/* The first sample sits this far (in ln g) above every level of interest;
 * below it ln g decreases if d ln T/d mu is at most LOW_SLOPE_FACTOR times
 * its secant from mu = gamma. */
#define LOW_MARGIN 0.5
#define LOW_SLOPE_FACTOR 4.0
/* A2: widening of the secant range, relative to its spread, and the spread
 * assumed for a cell that has no neighbour. */
#define SPREAD_FACTOR 0.5
#define LONE_SPREAD 0.25
#define MAX_POLISH_EVALS 64
/* The grid ends here at the latest (or at 2 gamma when that is larger): at
 * tol 1e-10 the cycle solver stops converging towards mu ~ 1e6 (measured at
 * nu = -0.96), while the large-mu expansion is within 6e-10 of T at 1e5
 * and its error falls as 1/mu^2: beyond, roots come from the expansion. */
#define MU_GRID_MAX 1e5
/* Interpolation relative to the large-mu expansion from here up (measured:
 * the root predictions for nu = -0.96 improve from 1e-5 to 1e-7 at mu > 5). */
#define MODEL_MU_MIN 5.0
/* Coarse solves warm-start only from a sample within this distance in
 * ln mu (the grid's steps are 0.3 and less in ln mu). */
#define WARM_LN_MU_MAX 0.4

typedef struct {
    double s, mu, lnT, T, T_err;
    double u;     /* relative uncertainty of T */
    int precise;
    int tail;     /* A3 holds here */
    int frozen;   /* the cell to the right cannot be refined: T failed inside */
} sample;

typedef struct {
    bkf_model_params p;
    double tol, tol_coarse;
    double k, lnk, knee, logc;
    double lnA;               /* ln(S/(c gamma)) */
    bkf_cycle *coarse, *precise;
    bkf_cycle_method method;
    const char *last_model;   /* the model of solve_T's last answer */
    int formula_refused;      /* polish failed because the formula asked for
                                 does not meet the root's tolerance */
    sample *x;
    size_t count, cap;
    size_t coarse_solves, precise_solves, formula_answers;
    double mu_max_sampled;
    double mu_last[2];        /* the last solution in coarse, precise (0: none) */
} grid;

static inline double mu_of_s(double gamma, double s) { return hypot(gamma, exp(s)); }
static inline double level(const grid *g, double n) { return g->lnA - log(n); }
static inline double lng(const sample *x) { return x->lnT - x->s; }

typedef enum { CELL_UNKNOWN = 0, CELL_DEC, CELL_INC } cell_shape;

typedef struct {
    cell_shape shape;
    double lo, hi;     /* enclosure of ln g on the cell */
} cell_info;

typedef struct {
    double n;        /* level */
    size_t cell;     /* index of the left sample */
    int near_tangent;
} bracket;

typedef struct {
    grid g;
    double n_from, n_last;       /* requested levels (n_last may be lowered to n_max) */
    double grid_last;            /* levels 1..grid_last shape the grid, whatever was requested */
    double n_max;                /* levels 1..n_max have a root */
    int dips;
    double g_inf_ln;
    /* unresolved places */
    size_t unresolved;
    char unresolved_text[96];
    double asym_mu0;             /* the grid ended at its cap (MU_GRID_MAX) */
} search;

typedef struct {
    double n, s, T, T_err, D, slope;
    unsigned flags;
    const char *model;
    int status;                  /* BKF_OK, or the root is refused (flag BKF_SPEEDS_REFUSED) */
    double tol_met;              /* refused: the looser tol it was had to, else NaN */
    char why[BKF_ERROR_LEN];     /* refused: the row's refusal */
} found_root;

/* A root not polished to tol is tried at these many times tol (at most
 * BKF_TOL_MAX), to tell a tol beyond what T gives there (a refused row,
 * saying the tol it has) from no T at all (unresolved).  The first that
 * succeeds is the one said.  Beyond 100 tol only while the looser tol is
 * at most LOOSE_FAR_MAX: where the cycle solver's own floor (about 1e-9 of
 * T next to a canard) is what stops a tight tol.  At tol 1e-12 the root
 * next to the canard at gamma 0.567489, c 0.432606, nu 0.989398,
 * S 59.5575 (n = 50) is had to 1e-9 only: with 10 and 100 alone it was a
 * place left unresolved.  A loose tol is not widened that far: at tol 1e-4
 * a level across a canard's jump (nu -0.9999, mu 35.366) "met" at 0.1 is
 * no root. */
#define LOOSE_FACTORS {10.0, 100.0, 1e3, 1e4}
#define LOOSE_NEAR 2
#define LOOSE_FAR_MAX 1e-6

/* speeds_search.c */
int speeds_period_refused(int rc, const bkf_error *e, double nu, bkf_error *err);
int speeds_solve_T_on(grid *g, int scout, double mu, double tol, double *T, double *T_err,
                      bkf_error *err);
int speeds_solve_T(grid *g, double mu, double tol, double *T, double *T_err, bkf_error *err);
int speeds_upgrade(grid *g, size_t j, bkf_error *err);
double speeds_noise(const grid *g, size_t i);
cell_info speeds_classify(const grid *g, size_t i);
void speeds_levels_in(const grid *g, double lo, double hi, double n_lo, double n_hi,
                      double *first, double *last);
void speeds_note_unresolved(search *sr, double n, double mu, const char *why);
int speeds_first_sample(search *sr, double lnT_gamma, double u_gamma, double ell_top,
                        bkf_error *err);
int speeds_build_grid(search *sr, double n_target, bkf_error *err);
int speeds_find_n_max(search *sr, bkf_error *err);
int speeds_resolve_levels(search *sr, bkf_error *err);

/* speeds_polish.c */
int speeds_polish(grid *g, gsl_root_fsolver *fs, double n, size_t i, found_root *out,
                  bkf_error *err);
void speeds_asymptotic_root(const grid *g, double n, found_root *out);

/* speeds.c */
void speeds_fill_row(const bkf_model_params *p, double k, const found_root *f,
                     bkf_speeds_root *row);

#endif

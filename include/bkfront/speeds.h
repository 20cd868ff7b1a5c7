/* Allowed front speeds: every root of the speed-selection condition
 *     n T(mu(v)) = S / (v sqrt(1 - c^2/v^2)),   mu(v) = gamma / sqrt(1 - c^2/v^2),
 * for n = 1, 2, ..., and the branches v_n(p) along one parameter p.
 *
 * With c > 0 the unknown is s = ln sqrt(mu^2 - gamma^2) in (-inf, inf):
 *     mu = sqrt(gamma^2 + e^(2s)),   v = c sqrt(1 + gamma^2 e^(-2s)),
 * and the condition for n reads
 *     ln T(mu) - s = ln R_n,         R_n = S / (n c gamma),
 * i.e. every n is a level of the same function g = T(mu) / sqrt(mu^2 - gamma^2).
 * s -> -inf is infinite speed (mu -> gamma+), s -> +inf the sonic limit
 * v -> c+ (mu -> inf), where g -> k(nu).  The levels above k always have a
 * root; the ones at or below k have one only where g dips below k.
 *
 * With c = 0, mu = gamma and v = S / (n T(gamma)) for every n >= 1.
 *
 * How the roots are bracketed, and why none is missed, is in docs/numerics.md
 * ("Allowed front speeds").  The library never prints and never exits. */
#ifndef BKFRONT_SPEEDS_H
#define BKFRONT_SPEEDS_H

#include <stddef.h>
#include "bkfront/cycle.h"
#include "bkfront/model.h"
#include "bkfront/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The model: bkf_model_params (model.h); speeds reads gamma in [1e-6, 1e6]
 * (mu >= gamma must be solvable), c >= 0, |nu| < 1, S > 0; kind and N are
 * not used (the continuum). */

/* Rows when n_to is 0 and c = 0 (every n has a root, there is no n_max). */
#define BKF_SPEEDS_ROWS_C0 10
/* Values of n at most when n_to is 0 and c > 0 (one n may give several rows). */
#define BKF_SPEEDS_MAX_ROWS 1000

typedef struct {
    double tol;      /* [1e-14, 1e-1]: the relative accuracy asked of v, and the
                        bound on |residual|; T is solved at each root to what v
                        needs (tol/10 .. 10 tol); default 1e-10 */
    size_t n_from;   /* rows for n in [n_from, n_to]; n_from >= 1 (default 1) */
    size_t n_to;     /* 0: up to n_max, but no more than BKF_SPEEDS_MAX_ROWS
                        values of n (BKF_SPEEDS_ROWS_C0 when c = 0) */
    bkf_cycle_method method; /* how T is obtained at the roots (bkf_cycle_estimate):
                        auto (default) takes a formula wherever its error bound
                        meets the tolerance the root needs, and also for grid
                        samples where it meets the grid's; asymptotic and
                        leading make every root's T the formula's, and fail
                        (BKF_ETOL) where its bound does not meet what the
                        root needs; shooting never uses a formula below the
                        grid's cap (mu = 1e5).  The bracketing grid is sampled
                        by shooting unless auto finds a formula good enough. */
} bkf_speeds_options;

bkf_speeds_options bkf_speeds_options_default(void);

/* Root flags. */
#define BKF_SPEEDS_NEAR_TANGENT 1u /* another root of the same n is close, or the
                                      bracketing reached its finest cell here: the
                                      root is near a fold and v_err is large */
#define BKF_SPEEDS_ASYMPTOTIC 2u   /* mu beyond 1e5 (or 2 gamma), where the grid ends:
                                      T from the large-mu expansion, T_err from its
                                      next order fitted at the grid's end */
#define BKF_SPEEDS_REFUSED 4u      /* the root is bracketed (it exists) but v cannot be
                                      had to tol there: status and refusal say why,
                                      its numbers are NaN (see bkf_speeds_root) */

typedef struct {
    size_t n;
    double v;
    double mu;
    double T, T_err;        /* period in z and its estimated absolute error */
    double v_over_c;        /* inf when c = 0 */
    double wavelength;      /* S / n */
    double period_fixed;    /* T sqrt(1 - c^2/v^2): period in t at a fixed point */
    double v_asym;          /* S / (n k gamma), the large-mu quantization */
    double deviation;       /* (v - v_asym) / v */
    double v_err;           /* estimated absolute error of v (from T_err and the
                               residual, through the local slope of the condition) */
    double residual;        /* n T v sqrt(1 - c^2/v^2) / S - 1 at the reported root */
    double slope;           /* d ln g / ds at the root (c > 0; 0 when c = 0):
                               negative where v_n decreases with n, zero at a fold */
    unsigned flags;
    const char *model;      /* what gave T: "shooting", "asymptotic" (corrected
                               large-mu or small-mu formula) or "leading" (k mu);
                               NULL for a refused root */
    /* A refused root (flag BKF_SPEEDS_REFUSED): a root is bracketed in the
     * search but cannot be polished to tol (the period is not computable that
     * tightly there, or the formula asked for does not meet what the root
     * needs).  It keeps its place in the order (by the looser root, when one
     * was had) so that root numbers do not shift; n, wavelength and v_asym are
     * set, every other number is NaN: a position that is not a result is not
     * given as one (refusal names where it lies). */
    int status;             /* BKF_OK, or BKF_ETOL: refused (the root is had at a looser
                               tol, or the formula asked for does not meet this one) */
    double tol_met;         /* refused: the looser tolerance on v it was polished to
                               (10 or 100 times tol, at most 0.1; also 1e3 or 1e4 times
                               while at most 1e-6); NaN when none was tried (a formula
                               asked for) */
    char refusal[BKF_ERROR_LEN]; /* refused: one line, where and why; else empty */
} bkf_speeds_root;

/* BKF_OK for a root that is a result; for a refused one its status, with err
 * "n = N: " and its refusal.  Every caller that takes one root of a table as
 * its input asks this first. */
int bkf_speeds_root_status(const bkf_speeds_root *root, bkf_error *err);

#define BKF_SPEEDS_NOTE_LEN 512

typedef struct {
    bkf_speeds_root *roots;  /* ordered by n, then by decreasing v */
    size_t count;
    double k;                /* k(nu) */
    double n_bound;          /* S / (k c gamma); inf when c = 0 */
    long n_max;              /* largest n with a root; 0: none; -1: every n (c = 0) */
    double g_inf;            /* inf over mu > gamma of T / sqrt(mu^2 - gamma^2):
                                k, or the interior minimum when g dips below k
                                (c > 0; NaN when c = 0) */
    int dips_below_k;        /* g dips below k: n_max may exceed n_bound */
    int truncated;           /* n_to = 0 and n_max beyond n_from + BKF_SPEEDS_MAX_ROWS - 1 */
    size_t refused;          /* rows refused (flag BKF_SPEEDS_REFUSED); the first in note */
    size_t unresolved;       /* places left unresolved, where a root or a pair
                                could be missing: a pair not excluded at the
                                finest cell, or T not computable (inside a
                                canard explosion); the first is in note */
    char note[BKF_SPEEDS_NOTE_LEN]; /* one line: why there is no row, what was
                                       flagged, or empty */
    /* work */
    size_t samples;          /* grid points of the bracketing */
    size_t coarse_solves, precise_solves; /* shooting solves */
    size_t formula_answers;  /* values of T taken from a formula (no integration) */
    double mu_grid_max;      /* largest mu sampled */
} bkf_speeds_table;

/* Validation alone: BKF_EINPUT with a one-line message naming the parameter
 * and its range, BKF_OK otherwise.  |nu| >= 1 is refused because there are no
 * fronts at all: uniform continuous slip is stable. */
int bkf_speeds_check(const bkf_model_params *params, const bkf_speeds_options *options,
                     bkf_error *err);

/* Every root for n in the options' range.  *table is overwritten (free it
 * with bkf_speeds_table_free, also after a failure).  BKF_OK with count = 0
 * and a note when no n in the range has a root.  A root that is bracketed
 * but cannot be had to tol (its period not computable that tightly, its
 * polishing out of solves, or a formula asked for whose bound does not meet
 * what the root needs) is a refused row (status, refusal), counted in
 * refused; the other rows stand and the call returns BKF_OK.  BKF_EBUDGET
 * when the bracketing grid needs more samples of T than the search allows. */
int bkf_speeds_find(const bkf_model_params *params, const bkf_speeds_options *options,
                    bkf_speeds_table *table, bkf_error *err);
void bkf_speeds_table_free(bkf_speeds_table *table);

/* The index of the root of `table` whose v is nearest `v` (v <= 0 or NaN:
 * the first root) into *index.  BKF_ENUMERIC when the table has no root;
 * when one of its roots is refused, which is nearest cannot be told: that
 * root's refusal (bkf_speeds_root_status). */
int bkf_speeds_nearest(const bkf_speeds_table *table, double v, size_t *index, bkf_error *err);

/* The root of n near a speed v_guess (c > 0, v_guess > c): the speed
 * condition solved by the secant method in s = ln sqrt(mu^2 - gamma^2) from
 * v_guess, T shot at options->tol (NULL: the defaults; n_from, n_to unused),
 * without the bracketing grid of bkf_speeds_find (a few solves of T instead
 * of 16 to 60): for following a root that moves a little, as the stability
 * map does.  BKF_ENUMERIC when the secant leaves v within 20% and ln mu
 * within 0.5 of the guess's or does not converge (no root near: a fold passed, or v_guess far
 * from a root; bkf_speeds_find then tells), with *root untouched; a root
 * found is as bkf_speeds_find's row of it (v to options->tol), though which
 * of two roots close together (near a fold) it is, is not checked. */
int bkf_speeds_near(const bkf_model_params *params, size_t n, double v_guess,
                    const bkf_speeds_options *options, bkf_speeds_root *root, bkf_error *err);

/* ------------------------------------------------------------ branches */

typedef enum {
    BKF_SPEEDS_ALONG_S = 0,
    BKF_SPEEDS_ALONG_NU = 1,
    BKF_SPEEDS_ALONG_GAMMA = 2,
    BKF_SPEEDS_ALONG_C = 3
} bkf_speeds_param;

typedef enum {
    BKF_SPEEDS_POINT = 0,  /* a regular point of the branch */
    BKF_SPEEDS_FOLD = 1,   /* the parameter turns back: two roots meet */
    BKF_SPEEDS_SONIC = 2   /* the limit v -> c+ (mu -> inf): the branch ends at
                              S = n k(nu) c gamma; mu and T are inf there */
} bkf_speeds_point_kind;

typedef struct {
    bkf_model_params params;   /* with the continued parameter at this point */
    bkf_speeds_root root;
    bkf_speeds_point_kind kind;
} bkf_speeds_branch_point;

/* Return nonzero to stop the run (bkf_speeds_branch then returns BKF_OK). */
typedef int (*bkf_speeds_visit)(const bkf_speeds_branch_point *point, void *data);

typedef struct {
    size_t points;       /* regular points */
    size_t folds;
    int sonic;           /* the branch ended at the sonic limit */
    int reached_end;     /* the branch ended on `to` or back on the start value */
    double sonic_value;  /* the parameter's value at the sonic limit, if any */
    size_t solves;
} bkf_speeds_branch_report;

/* The branch of roots for one n through the root number root_index (1: the
 * fastest, in the order of bkf_speeds_find) at `start`, continued in the
 * parameter `along` from its value in `start` towards `to` by pseudo-
 * arclength continuation (module continuation) in (s, p).  It passes folds
 * (visited as BKF_SPEEDS_FOLD points) and ends where p leaves the interval
 * between the start value and `to`, or at the sonic limit (visited as a
 * BKF_SPEEDS_SONIC point), or after max_points points (0: no limit of ours).
 * Needs c > 0 all along (for c = 0, v = S/(n T(gamma)) in closed form);
 * along c the interval must stay in c > 0, along nu in (-1, 1), along S and
 * gamma in their ranges.  BKF_EINPUT when there is no such root at start. */
int bkf_speeds_branch(const bkf_model_params *start, size_t n, size_t root_index,
                      bkf_speeds_param along, double to, const bkf_speeds_options *options,
                      size_t max_points, bkf_speeds_visit visit, void *data,
                      bkf_speeds_branch_report *report, bkf_error *err);

#ifdef __cplusplus
}
#endif

#endif

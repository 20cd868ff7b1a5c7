/* Internal to the collocation engine (src/wave/colloc.c, colloc_mesh.c,
 * colloc_guess.c, colloc_path.c): the object's layout, the tuning constants
 * and the pieces the files share.  Dependencies point one way: colloc_path.c
 * -> colloc.c (the solve) -> colloc_guess.c -> colloc_mesh.c.  Not
 * installed, not part of the API. */
#ifndef BKFRONT_COLLOC_INTERNAL_H
#define BKFRONT_COLLOC_INTERNAL_H

#include <stddef.h>

#include "bkfront/colloc.h"

#define M BKF_COLLOC_M
/* Newton iterations per mesh before the solve refuses. */
#define MAX_NEWTON 30
/* Largest partial product of interval maps, and largest relative mismatch
 * of the forward recursion, that the cyclic solve accepts. */
#define PRODUCT_MAX 1e10
#define CLOSURE_MAX 1e-3
/* Largest mesh of the pair (intervals of the finer). */
#define MAX_INTERVALS 40000
#define MIN_INTERVALS 8
/* The estimate |T_N - T_2N| / EST_DIVISOR of the finer T: the error of
 * Gauss collocation falls like h^(2m) (2^8 = 256 on bisection for m = 4);
 * 16 keeps the estimate honest while the mesh is still outside the
 * asymptotic range. */
#define EST_DIVISOR 16.0
#define ACCEPT_MARGIN 3.0
/* The same for the pair of a turn's mesh and its coarsening (merged
 * pairs), with TURN_FLOOR below: that pair is at the edge of the asymptotic
 * range (mu 20.5, nu -0.96, tol 1e-10: |T_N - T_N/2| was 4 times T_N's
 * error of 1.8e-12; mu 28, nu 0.5: it agreed by chance to 4e-14 against a
 * true 7.6e-13), which the floor covers; a divisor of 2 instead cost a
 * second turn at mu 30-100 (1.7 times the instructions). */
#define PAIRED_DIVISOR 16.0
/* and never below this fraction of the turn's local tolerance (relative):
 * the true error was at most 2e-4 of it over tests/wave/test_colloc.c,
 * test_cycle_engine.c and test_extremes.c (3e-3 made the cycle's estimate
 * at tol 1e-12 too coarse for Floquet's lambda at gamma 10, which
 * colloc_turn_tol now also answers). */
#define TURN_FLOOR 1e-3
/* Newton's goal in that pair, times sqrt(tol): what it leaves, of the
 * square, is 1e-2 tol, added to the estimate.  The turn's mesh values and
 * stages start the finer Newton within about 1e-6 (mu 30-1e4, tol 1e-10),
 * and the coarser from the finer's: 0.01 (converge's) took each a second
 * or third iteration for a T that had moved by 1e-15 relative (the stages
 * were still moving at 1e-7 - 1e-8). */
#define PAIRED_GOAL 0.1

typedef struct {
    double c[M], w[M], A[M][M], A2[M][M], Ac[M], p[M];
    double dd[M + 1];  /* divided-difference weights on the nodes (0, c_1..c_m) */
    double mfact;      /* m! */
    /* a step's stages from the polynomials of its two halves: stage i is
     * the first half's polynomial (on the nodes 0, c) at 2 c_i, or the
     * second's at 2 c_i - 1 */
    double halves[M][M + 1];
    /* the same basis in powers of theta: basis[k][p] */
    double basis[M + 1][M + 1];
    /* the basis at theta = 1: a step's end value from its start and stages */
    double end[M + 1];
} gauss_table;

struct bkf_colloc {
    double mu, nu, a, b;
    size_t n, cap;
    double *t;      /* mesh in s, n + 1 */
    double *x, *y;  /* mesh values, n + 1 (index n duplicates 0) */
    double *X;      /* stage x values, n M */
    double T;
    int have_guess, have_solution;
    /* work */
    double *Z;      /* n x 4 x M condensed columns */
    double *lin;    /* n x 8: G (4), g (2), r (2) */
    double *du;     /* 2 (n + 1) */
    double *ts, *xs, *ys, *Xs; /* remesh scratch */
    size_t scap;
    gauss_table g;
    size_t iterations, solves;
    double trace, log_mult;
    size_t pair_n; /* the coarser mesh of the last accepted pair */
    int paired;    /* the mesh is pairs of half steps (bkf_colloc_guess_turn) */
    int uniform;   /* a uniform mesh of a smooth cycle (bkf_colloc_guess_series) */
    double local_tol; /* of those steps */
    double *keep;  /* the finer solution while its coarsening is solved */
    size_t keep_cap;
};

/* A Gauss step's Newton goal (colloc_gauss_step, colloc_mesh.c). */
#define STAGE_GOAL 1e-12

/* colloc_mesh.c */
void colloc_lagrange_weights(const double *c, double theta, double *l);
int colloc_grow(double **p, size_t count);
int colloc_reserve(bkf_colloc *c, size_t n);
int colloc_reserve_scratch(bkf_colloc *c, size_t n);
void colloc_set_params(bkf_colloc *c, double mu, double nu);
void colloc_stage_y(const bkf_colloc *c, size_t j, double *Y);
void colloc_poly_eval(const bkf_colloc *c, size_t j, double theta, double *xv, double *yv);
int colloc_gauss_step(const bkf_colloc *c, double x0, double y0, double tau, double goal, double *X, double *x1,
                      double *y1);
int colloc_equidistribute(bkf_colloc *c, size_t n);
int colloc_bisect(bkf_colloc *c);
double colloc_log_multiplier(const bkf_colloc *c);
int colloc_newton(bkf_colloc *c, double goal, bkf_error *err);

/* colloc_guess.c */
int colloc_guarded_step(const bkf_colloc *c, double x0, double y0, double tau, double goal, int guessed, double *X,
                        double *x1, double *y1);
int colloc_turn_mesh(bkf_colloc *c, double x0, double y0, double T, double local_tol, int record, int from_below,
                     bkf_error *err);

/* colloc.c */
int colloc_converge(bkf_colloc *c, double tol, bkf_error *err);
double colloc_round_floor(const bkf_colloc *c, double T);
int colloc_keep_solution(bkf_colloc *c, int which, size_t *n, double *T, double *trace);
void colloc_fill_result(bkf_colloc *c, double est, double L, double L_other, double divisor,
                        bkf_colloc_result *out);

static inline double lienard_F(double x) { return x * x * x / 3.0 - x; }

#endif

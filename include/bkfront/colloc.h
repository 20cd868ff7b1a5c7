/* Gauss-Legendre collocation for the limit cycle of
 *     f'' + mu (f^2 - 1) f' + f = nu
 * in the cycle engine's scaled Lienard coordinates (cycle.h):
 *     x' = a (y - b F(x)),  y' = (nu - x)/a,
 * time normalised to s = z/T in [0, 1] with T unknown, phase x(0) = nu
 * (the section, x' > 0).  BKF_COLLOC_M points per mesh interval; Newton with
 * the stage values condensed per interval, then the reduced cyclic system for
 * the mesh values and T.  The mesh equidistributes the (m+1)-th derivative
 * (de Boor); the error estimate comes from a mesh and its bisection (from
 * a turn's mesh, bkf_colloc_guess_turn: the mesh and its coarsening).
 * docs/numerics.md, "The collocation engine".  bkf_cycle_solve uses it
 * (stepper "colloc"); the object here is the engine itself, for the cycle
 * module and for tests of its order. */
#ifndef BKFRONT_COLLOC_H
#define BKFRONT_COLLOC_H

#include <stddef.h>
#include "bkfront/status.h"

#ifdef __cplusplus
extern "C" {
#endif

#define BKF_COLLOC_M 4

typedef struct bkf_colloc bkf_colloc;

typedef struct {
    double period, period_err;
    double log_multiplier, log_multiplier_err; /* Gauss quadrature of -mu (x^2 - 1) */
    double return_map_slope;                  /* trace of the condensed monodromy - 1 */
    double section_y;                         /* y(0) */
    size_t intervals;                         /* of the finer mesh of the estimate */
    size_t newton_iterations;
    size_t interval_solves;                   /* work: condensed interval solves */
} bkf_colloc_result;

bkf_colloc *bkf_colloc_alloc(void);
void bkf_colloc_free(bkf_colloc *colloc);

/* Initial guess by one turn of Gauss steps from (x0, y0) over the time T
 * (a loose shot's section point and period), each step accepted where it
 * and its two halves agree within local_tol (relative to the cycle's size);
 * the mesh is the halves.  The solve's first pair is then that mesh and its
 * coarsening (merged halves), and a finer mesh comes from another turn at
 * a tighter local tolerance: no equidistribution, which the cold start does
 * not survive at large mu. */
int bkf_colloc_guess_turn(bkf_colloc *colloc, double mu, double nu, double x0, double y0, double T,
                          double local_tol, bkf_error *err);

/* The same in the relaxation regime (mu >= 10 past the canard explosion)
 * without the first turn: the landing starts on the left slow branch at
 * x = -1.5 (on the slow manifold to first order) and ends where it crosses
 * the section, which the cycle's attraction through the fold makes the
 * cycle's section point whatever happened before the fold; the turn that
 * is the mesh starts there.  T: a hint of the period (its scale only). */
int bkf_colloc_guess_relaxation(bkf_colloc *colloc, double mu, double nu, double T, double local_tol,
                                bkf_error *err);

/* Initial guess for small mu: the Lindstedt (Poincare-Lindstedt) series of
 * the cycle in mu to `order` (at most 12; 0: the order past which Newton's
 * iterations stop falling, 2 to 6 by mu), truncated earlier at its smallest
 * term where mu is beyond its radius (about 1 at nu 0, less at |nu| ~ 0.5),
 * on `intervals` uniform intervals; *residual (may be NULL): the last term
 * kept over the cycle's radius 2 sqrt(1 - nu^2), the guess's error where
 * the series converges.  The solve then keeps the mesh uniform: the pair
 * is this mesh and its bisection, the finer started from the coarser's
 * polynomials (docs/numerics.md, "The collocation engine"). */
int bkf_colloc_guess_series(bkf_colloc *colloc, double mu, double nu, int order, size_t intervals,
                            double *residual, bkf_error *err);

/* The period 2 pi / omega of that series (the same truncation), NaN
 * outside mu >= 0, |nu| < 1, order >= 0. */
double bkf_colloc_series_period(double mu, double nu, int order);

/* Move the last solution to (mu, nu) (same f, f' on the same mesh) as the
 * guess of the next solve; 0 if there is none. */
int bkf_colloc_warm(bkf_colloc *colloc, double mu, double nu);

/* Solve from the guess to relative accuracy tol of T (estimate from a mesh
 * and its bisection, or a turn's mesh and its coarsening, accepted when 3
 * times it is within tol).  Refuses
 * (BKF_ENUMERIC) where Newton does not converge or the cyclic system is
 * ill-conditioned (the product of interval maps grows past what its
 * rounding allows: canards, where the orbit follows the repelling slow
 * branch), BKF_ETOL where the mesh needed exceeds the engine's budget. */
int bkf_colloc_solve(bkf_colloc *colloc, double tol, bkf_colloc_result *out, bkf_error *err);

/* Newton on exactly `intervals` intervals equidistributed for the guess
 * (no estimate): T into *period.  For studies of the order in the mesh. */
int bkf_colloc_fixed(bkf_colloc *colloc, size_t intervals, double *period, bkf_error *err);

/* The extremes of x over the last solution: where x' changes sign
 * between mesh points, Newton on the length of a Gauss step from the
 * interval's nearer end whose end has x' = 0 (end values superconvergent,
 * x there second order in the step's error), started at the zero of x' on
 * the interval's polynomial.  BKF_ENUMERIC where one is not located. */
int bkf_colloc_extremes(const bkf_colloc *colloc, double *xmax, double *xmin, bkf_error *err);

/* The mesh points of the last solution (or, before the first solve, of
 * the guess): z = s T and (x, y) there; writes at most capacity and
 * returns how many there are. */
size_t bkf_colloc_nodes(const bkf_colloc *colloc, double *z, double *x, double *y, size_t capacity);

/* Continuation: a path holds a branch's last two rows, and each next row
 * is solved on a mesh predicted from them, not re-meshed (the rows of
 * bkf_cycle_branch where collocation answers, up to mu 2: above it the
 * fast layers move across a mesh so predicted, and the rows are built by
 * turns). */
typedef struct bkf_colloc_path bkf_colloc_path;

bkf_colloc_path *bkf_colloc_path_alloc(void);
void bkf_colloc_path_free(bkf_colloc_path *path);

/* Start the path again from colloc's last solution (a bkf_colloc_solve:
 * its mesh, the finer of its pair, an even number of intervals).  Rows
 * that bkf_colloc_continue adds are on meshes predicted from it, index by
 * index.  BKF_EINPUT without a solution, BKF_ENOMEM. */
int bkf_colloc_path_push(bkf_colloc_path *path, const bkf_colloc *colloc);

/* The row at (mu, nu): the mesh, the mesh values, the stages and T
 * predicted per mesh index from the path's two rows (the secant in ln mu,
 * or in nu where mu did not change; the logarithms of the interval lengths,
 * so that layers narrowing like a power of mu are followed), or from its
 * one row; Newton on that mesh and on its coarsening (merged pairs, started
 * from the finer solution), the finer T reported with |T_N - T_N/2| / 16 as
 * bkf_colloc_solve's pair does.  On success the row joins the path.
 * BKF_ETOL when the estimate misses tol (the mesh no longer fits the cycle:
 * colloc then holds the row's solution, from which a warm bkf_colloc_solve
 * re-meshes), BKF_ENUMERIC when Newton refuses (colloc then holds the path's
 * newest row, at its own parameters); out's work counters (Newton
 * iterations, interval solves) are set in either case. */
int bkf_colloc_continue(bkf_colloc *colloc, bkf_colloc_path *path, double mu, double nu, double tol,
                        bkf_colloc_result *out, bkf_error *err);

#ifdef __cplusplus
}
#endif

#endif

/* The limit cycle of the rescaled van der Pol equation
 *     f'' + mu (f^2 - 1) f' + f = nu,     mu > 0, |nu| < 1,
 * its period T(mu, nu), amplitude, nontrivial Floquet multiplier and profile.
 *
 * Method (docs/numerics.md, "The cycle engine"): Newton shooting on the Poincare section f = nu,
 * f' > 0, with the variational equations, in scaled Lienard coordinates
 *     x' = a (y - b F(x)),  y' = (nu - x)/a,   F(x) = x^3/3 - x,
 *     a = sqrt(1 + mu^2),   b = mu/a           (so a b = mu),
 * which are the phase plane (x, x') for small mu and the Lienard plane for
 * large mu, smoothly in between.  An explicit Runge-Kutta (rk8pd) stepper is
 * used for mu <= BKF_CYCLE_STIFF_MU, above it a semi-implicit Bader-Deuflhard extrapolation
 * stepper whose linear algebra is closed-form 2x2 (bd2x2; GSL's bsimp, the
 * same method with a general LU, stays selectable).  The error estimate comes from two solves at
 * integration tolerances a factor BKF_CYCLE_TOL_RATIO apart; the reported
 * values are those of the tighter solve.  The automatic choice is Gauss
 * collocation (colloc.h, BKF_STEPPER_COLLOCATION; docs/numerics.md, "The
 * collocation engine") up to mu 1 at tol <= 1e-6 (from the Lindstedt
 * series) and for mu in [10, 1e4] at tol <= 1e-10 where
 * mu^2 (1 - |nu|) >= 1, falling back to shooting where it refuses. */
#ifndef BKFRONT_CYCLE_H
#define BKFRONT_CYCLE_H

#include <stddef.h>
#include "bkfront/status.h"

#ifdef __cplusplus
extern "C" {
#endif

#define BKF_CYCLE_MU_MIN 1e-6
#define BKF_CYCLE_MU_MAX 1e6
/* Above BKF_CYCLE_EXPLICIT_MU_MAX the automatic stepper is the stiff one
 * (bd2x2); above BKF_CYCLE_STIFF_MU it is too at tol in
 * [BKF_CYCLE_STIFF_TOL_MIN, BKF_CYCLE_STIFF_TOL_MAX] (below, bd2x2's estimate
 * floor cannot meet tol; above, rk8pd is as fast there).  Up to
 * BKF_CYCLE_EXPLICIT_MU_MAX rk8pd is also the fallback where bd2x2 refuses,
 * above it bsimp.  A solve inside the canard window (8 mu^2 (1 - |nu|) in
 * [0.5, 2], mu >= 1) takes rk8pd at every mu: bd2x2's and bsimp's estimates
 * flatter there (docs/accuracy.md); a branch's rows do not.  In the wider
 * neighbourhood (the same x in [0.5, 7]) rk8pd is the fallback where bd2x2
 * refuses at every mu, and bd2x2's and bsimp's estimates (chosen or not)
 * carry a larger floor there: they meet tol more often by refusing, at
 * tight tol (bsimp at 1e-12 near |nu| = 0.9999 mostly refuses). */
#define BKF_CYCLE_STIFF_MU 20.0
#define BKF_CYCLE_EXPLICIT_MU_MAX 30.0
#define BKF_CYCLE_STIFF_TOL_MIN 1e-12
#define BKF_CYCLE_STIFF_TOL_MAX 1e-8

typedef enum {
    BKF_STEPPER_AUTO = 0,     /* collocation where it wins (above), else shooting:
                                 explicit below the stiffness threshold */
    BKF_STEPPER_EXPLICIT = 1, /* gsl rk8pd */
    BKF_STEPPER_IMPLICIT = 2, /* gsl bsimp with analytic Jacobian */
    BKF_STEPPER_EXTRAPOLATION = 3, /* the same method (semi-implicit midpoint
                                     extrapolation) with closed-form 2x2 solves
                                     and only (x, y) under error control; the
                                     default above the stiffness threshold */
    BKF_STEPPER_COLLOCATION = 4  /* Gauss-Legendre collocation (colloc.h) on an
                                    adapted mesh; where it refuses (canards,
                                    conditioning) the solve shoots as auto would */
} bkf_stepper_kind;

/* The stepper's name as in bkf_cycle_result.stepper: "rk8pd", "bsimp",
 * "bd2x2", "colloc" ("auto" for BKF_STEPPER_AUTO); NULL for an unknown kind. */
const char *bkf_cycle_stepper_name(bkf_stepper_kind kind);

typedef struct {
    double tol;               /* requested relative accuracy of T, [1e-14, 1e-1] */
    bkf_stepper_kind stepper;
    int warm_start;           /* start Newton from the previous solution in the object */
} bkf_cycle_options;

/* tol 1e-10, automatic stepper, warm start on. */
bkf_cycle_options bkf_cycle_options_default(void);

typedef struct {
    double mu, nu;
    double period;            /* T, period in z */
    double period_err;        /* estimated absolute error of T */
    double xmax, xmin;        /* max and min of f over the cycle */
    double multiplier;        /* nontrivial Floquet multiplier, exp(log_multiplier) */
    double log_multiplier;    /* = integral over a period of -mu (f^2 - 1) dz (Liouville) */
    double log_multiplier_err;
    double return_map_slope;  /* P'(y*) from the variational equations: the same
                                 multiplier by another route (a check) */
    double section_y;         /* scaled Lienard y where the cycle crosses f = nu upward */
    double section_slope;     /* f'(z) at that crossing */
    /* work counters, summed over every integration of the solve */
    size_t steps;
    size_t rhs_calls;
    size_t jacobian_calls;
    size_t newton_iterations;
    const char *stepper;      /* "rk8pd" or "bsimp"; "none" for a formula */
    const char *model;        /* "shooting", or for bkf_cycle_estimate "asymptotic"
                                 or "leading" (then period_err is the formula's
                                 error bound, the work counters are 0 and the
                                 fields the formula does not give are NaN) */
} bkf_cycle_result;

typedef struct bkf_cycle bkf_cycle;

bkf_cycle *bkf_cycle_alloc(void);
void bkf_cycle_free(bkf_cycle *cycle);

/* Solve for the cycle at (mu, nu).  Inputs are validated (mu in
 * [BKF_CYCLE_MU_MIN, BKF_CYCLE_MU_MAX], |nu| < 1, tol in range).  BKF_ETOL
 * when the estimated error of T stays above tol, BKF_EBUDGET when a period
 * needs more integration steps than the engine allows, BKF_ENUMERIC for
 * other failures (shooting did not converge); on any failure the previous
 * solution in the object is kept. */
int bkf_cycle_solve(bkf_cycle *cycle, double mu, double nu,
                    const bkf_cycle_options *options, bkf_error *err);

/* The last successful solution, or NULL if there is none. */
const bkf_cycle_result *bkf_cycle_get(const bkf_cycle *cycle);

/* Profile of the last solution: f(z) and f'(z) for any real z (periodic,
 * z = 0 on the section f = nu, f' > 0), accurate to the solve's tolerance. */
int bkf_cycle_profile(bkf_cycle *cycle, double z, double *f, double *fprime,
                      bkf_error *err);

/* The profile at many points z[0] <= z[1] <= ... within [0, T], in one
 * pass: f and f' (either may be NULL), to the same accuracy as
 * bkf_cycle_profile, at the cost of about one period's integration. */
int bkf_cycle_profile_sample(bkf_cycle *cycle, const double *z, size_t count, double *f,
                             double *fprime, bkf_error *err);

/* The profile at any real points z[0..count) (periodic, in any order), in
 * one pass as bkf_cycle_profile_sample: f and f' (either may be NULL, f may
 * be z itself) to
 * the same accuracy as bkf_cycle_profile point by point, which integrates
 * from the nearest stored node for each (a simulation's seed on 8192 grid
 * points: that many short integrations, against about one period's). */
int bkf_cycle_profile_points(bkf_cycle *cycle, const double *z, size_t count, double *f,
                             double *fprime, bkf_error *err);

/* The steps of the last solve's final integration, z from 0 to T: a mesh
 * adapted to the cycle (short on the fast jumps).  Writes at most capacity
 * values and returns how many there are (0 before a solve). */
size_t bkf_cycle_mesh(const bkf_cycle *cycle, double *z, size_t capacity);

/* One-shot convenience: solve into *result without keeping an object. */
int bkf_cycle_period(double mu, double nu, const bkf_cycle_options *options,
                     bkf_cycle_result *result, bkf_error *err);

/* How bkf_cycle_estimate obtains T. */
typedef enum {
    BKF_METHOD_AUTO = 0,       /* the cheapest that meets tol: leading, then
                                  asymptotic, then shooting */
    BKF_METHOD_ASYMPTOTIC = 1, /* corrected large-mu or small-mu formula */
    BKF_METHOD_LEADING = 2,    /* k(nu) mu */
    BKF_METHOD_SHOOTING = 3    /* bkf_cycle_solve */
} bkf_cycle_method;

/* "auto", "asymptotic", "leading", "shooting"; NULL otherwise. */
const char *bkf_cycle_method_name(bkf_cycle_method method);

/* T(mu, nu) to options->tol by `method` into *out.  A formula is used only
 * where its error bound (bkf_asym_error_bound) meets tol; a formula asked
 * for explicitly where it does not is refused (BKF_ETOL), never a silent
 * answer.  Shooting (and auto when no formula qualifies) is bkf_cycle_solve
 * on `cycle`, which must then be non-NULL; formulas leave `cycle` alone and
 * integrate nothing (all work counters 0). */
int bkf_cycle_estimate(bkf_cycle *cycle, double mu, double nu, const bkf_cycle_options *options,
                       bkf_cycle_method method, bkf_cycle_result *out, bkf_error *err);

/* The branch of cycles along mu (parameter BKF_CYCLE_ALONG_MU, continued in
 * ln mu) or along nu (BKF_CYCLE_ALONG_NU) from `from` to `to`, the other
 * parameter held at `fixed`, by pseudo-arclength continuation (module
 * continuation) on the shooting equations with warm starts and step control.
 * Every accepted point is given to options->tol with its error estimate
 * (the continuation's last shot there and one tighter solve from it, or a
 * fresh solve where that pair cannot vouch for tol) and passed to `visit`,
 * in order from `from` to `to`; both ends are included.  A point's work
 * counters hold every integration since the previous point.
 * The continuation's parameter derivative comes from the variational
 * equations.  A point the solve cannot meet tol at (inside a canard
 * explosion) is retried at looser tolerances up to 1e-6 (up to |nu| 0.999)
 * and passed with model "shooting-relaxed" and its honest (larger)
 * period_err, or, failing that, with model "refused" and NaN values; the
 * branch goes on past it.
 * At most max_points points (0: no limit, beyond the driver's own, 10000
 * rows: a branch that spends those short of `to`, its steps shrunk to a
 * creep, returns BKF_EBUDGET naming where it stopped, after visiting the
 * rows it has).  Along nu at mu >= 100 a branch crossing nu = 0 is
 * continued as two halves meeting there (the row at 0 visited once;
 * max_points counts both halves' rows, the driver's budget each half's).
 * With the automatic stepper at tol <= 1e-10, or with collocation asked
 * for, the rows outside the steep canard's neighbourhood (mu <= 1e4, not
 * 8 mu^2 (1 - |nu|) in [0.2, 5] for mu >= 1 where |nu| > 0.98, or along nu
 * where nu < 0) are collocation rows (stepper
 * "colloc": a path up to mu 2; above it the cold start's landing from the
 * slow branch in the relaxation regime, elsewhere turns from the predicted
 * section point); from |nu| 0.99 the automatic rows along mu before a
 * canard the branch has yet to cross shoot, as do the canard's own rows.
 * A branch whose rows miss tol 160 times in a row (an explosion thinner
 * than an ulp of mu: |nu| 0.9999, mu 35.37) steps over it by collocation
 * rows along mu towards larger mu (automatic or collocation stepper);
 * elsewhere it returns BKF_ENUMERIC, as any failure past the first row,
 * naming the last row's mu and nu. */
typedef enum { BKF_CYCLE_ALONG_MU = 0, BKF_CYCLE_ALONG_NU = 1 } bkf_cycle_param;
typedef int (*bkf_cycle_visit)(const bkf_cycle_result *point, void *data);
int bkf_cycle_branch(bkf_cycle_param along, double from, double to, double fixed,
                     const bkf_cycle_options *options, size_t max_points,
                     bkf_cycle_visit visit, void *data, bkf_error *err);

#ifdef __cplusplus
}
#endif

#endif

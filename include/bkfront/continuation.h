/* Generic pseudo-arclength continuation of a one-parameter solution branch.
 *
 * Unknowns u in R^(n+1) (the last component is usually the parameter), n
 * equations G(u) = 0.  Each step predicts along the unit tangent, corrects
 * with Newton on [G(u); t.(u - u_pred)] = 0, and adapts the arclength step.
 * Folds (the dir_index component of the tangent changing sign) are passed,
 * not stopped at: each is located and reported to the caller.
 *
 * Lengths, dot products and the unit tangent use the scaled coordinates
 * u_i / scale_i, so components of very different sizes weigh alike. */
#ifndef BKFRONT_CONTINUATION_H
#define BKFRONT_CONTINUATION_H

#include <stddef.h>
#include "bkfront/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Residual G(u) (n values) and, if jac != NULL, its n x (n+1) Jacobian in
 * row-major order.  Return BKF_OK, or an error status to make the driver
 * shrink the step (BKF_ENUMERIC) or stop (any other; the run then returns
 * that status with the message written into err).  A callback that does not
 * compute Jacobians may leave jac untouched: the driver notices and switches
 * to forward differences for the rest of the run. */
typedef int (*bkf_cont_residual)(const double *u, double *g, double *jac,
                                 void *data, bkf_error *err);

/* Called after each accepted point, in order along the branch; return
 * nonzero to stop the run (bkf_cont_run then returns BKF_OK).  is_fold = 1
 * marks a located fold, passed before the regular point that follows it.
 * tangent is the unit tangent in the scaled norm; both arrays are valid only
 * during the call. */
typedef int (*bkf_cont_accept)(const double *u, const double *tangent,
                               int is_fold, void *data);

typedef struct {
    size_t n;                 /* number of equations; unknowns are n + 1 */
    double step_initial;      /* initial arclength step (scaled units) */
    double step_min;
    double step_max;
    /* Newton stops when every |du_i| <= newton_tol * max(|u_i|, scale_i):
     * absolute (in scale units) near zero, relative for large components.
     * Folds are located to about the same accuracy. */
    double newton_tol;
    int newton_max_iter;      /* per corrector */
    /* The step grows 1.5 times after a corrector of at most grow_iterations
     * Newton iterations, is kept after up to 2 more, halved after more: a
     * tight newton_tol that always needs 3 (a quasi-Newton Jacobian) keeps
     * small steps small unless it is raised.  Default 2, in [1, newton_max_iter]. */
    int grow_iterations;
    /* Nonzero (default): a turn of u[dir_index] between two points is
     * located (Illinois on the tangent, up to 100 corrections) and passed
     * to accept as a fold; 0: passed by, as any other point (a caller
     * whose residual is too rough to locate it, or that needs no folds). */
    int locate_folds;
    size_t max_points;        /* regular points, the start included */
    const double *scale;      /* n + 1 positive scales for the norm, or NULL */
    int jacobian_fd;          /* nonzero: ignore jac, use finite differences */
    /* Stop when component stop_index would leave [stop_min, stop_max]; the
     * final point is placed exactly on the boundary.  stop_index < 0: no
     * bounds.  u0[stop_index] must lie inside. */
    int stop_index;
    double stop_min, stop_max;
} bkf_cont_options;

/* step_initial 0.05, step_min 1e-10, step_max 0.5, newton_tol 1e-10,
 * newton_max_iter 8, grow_iterations 2, locate_folds 1, max_points 10000, scale NULL, jacobian_fd 0,
 * stop_index -1 (stop_min -inf, stop_max +inf). */
bkf_cont_options bkf_cont_options_default(size_t n);

typedef struct {
    size_t points;            /* accepted regular points, the start included */
    size_t folds;             /* located folds (not counted in points) */
    size_t newton_iterations;
    size_t rejected_steps;    /* steps retried with half the length */
    int reached_bound;        /* stopped on the stop_index boundary */
} bkf_cont_report;

/* u0: n + 1 values, a solution or close to one (it is corrected first with
 * component dir_index held fixed, so it must not sit on a fold in that
 * component).  direction: +1 or -1, the sign of the initial tangent's
 * component dir_index.  accept must not be NULL; report and err may be.
 *
 * Returns BKF_OK when the run ends on max_points, a bound or the accept
 * callback; BKF_EINPUT for bad arguments; BKF_ENUMERIC when the step falls
 * below step_min (the message gives u[dir_index] where) or a fold cannot be
 * located; BKF_ENOMEM; or a fatal status from the residual. */
int bkf_cont_run(bkf_cont_residual residual, bkf_cont_accept accept, void *data,
                 const double *u0, int dir_index, int direction,
                 const bkf_cont_options *options, bkf_cont_report *report,
                 bkf_error *err);

#ifdef __cplusplus
}
#endif

#endif

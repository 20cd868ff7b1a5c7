/* Generic pseudo-arclength continuation of a one-parameter solution branch.
 *
 * Unknowns u in R^(n+1) (the last component is usually the parameter), n
 * equations G(u) = 0.  Each step predicts along the unit tangent, corrects
 * with Newton on [G(u); t.(u - u_pred)] = 0, and adapts the arclength step.
 * Folds (the parameter component of the tangent changing sign) are passed,
 * not stopped at, and reported to the caller. */
#ifndef BKFRONT_CONTINUATION_H
#define BKFRONT_CONTINUATION_H

#include <stddef.h>
#include "bkfront/status.h"

/* Residual G(u) (n values) and, if jac != NULL, its n x (n+1) Jacobian in
 * row-major order.  Return BKF_OK, or an error status to make the driver
 * shrink the step (BKF_ENUMERIC) or stop (any other). */
typedef int (*bkf_cont_residual)(const double *u, double *g, double *jac,
                                 void *data, bkf_error *err);

/* Called after each accepted point; return nonzero to stop the run. */
typedef int (*bkf_cont_accept)(const double *u, const double *tangent,
                               int is_fold, void *data);

typedef struct {
    size_t n;                 /* number of equations; unknowns are n + 1 */
    double step_initial;      /* initial arclength step (scaled units) */
    double step_min;
    double step_max;
    double newton_tol;        /* on the scaled Newton correction */
    int newton_max_iter;      /* per corrector */
    size_t max_points;
    const double *scale;      /* n + 1 positive scales for the norm, or NULL */
    int jacobian_fd;          /* nonzero: ignore jac, use finite differences */
    /* Stop when component stop_index leaves [stop_min, stop_max]; the final
     * point is placed on the boundary.  stop_index < 0: no bounds. */
    int stop_index;
    double stop_min, stop_max;
} bkf_cont_options;

bkf_cont_options bkf_cont_options_default(size_t n);

typedef struct {
    size_t points;            /* accepted points, the start included */
    size_t folds;
    size_t newton_iterations;
    size_t rejected_steps;
    int reached_bound;        /* stopped on the stop_index boundary */
} bkf_cont_report;

/* u0: n + 1 values, a solution or close to one (it is corrected first with the
 * parameter component stop_index held fixed if stop_index >= 0).  direction:
 * +1 or -1, the sign of the initial tangent's component dir_index. */
int bkf_cont_run(bkf_cont_residual residual, bkf_cont_accept accept, void *data,
                 const double *u0, int dir_index, int direction,
                 const bkf_cont_options *options, bkf_cont_report *report,
                 bkf_error *err);

#endif

/* Pseudo-arclength continuation (see include/bkfront/continuation.h).
 *
 * Every linear solve is the bordered (n+1) x (n+1) system [J; r^T], whose
 * last row is one linear constraint: a held component (starting point, bound
 * landing) or the arclength condition.  Dot products and norms are taken in
 * the scaled coordinates u_i / scale_i, so a row built from a tangent t has
 * entries t_i / scale_i^2. */
#include "bkfront/continuation.h"

#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_linalg.h>
#include <gsl/gsl_matrix.h>
#include <gsl/gsl_permutation.h>
#include <gsl/gsl_vector.h>

/* The chord between two accepted points must not turn the tangent by more
 * than about 40 degrees: beyond that a step may skip a pair of folds or jump
 * to another part of the branch, and the fold search, which parameterises
 * the piece between two points by its projection on the old tangent, needs
 * that projection to be monotone. */
#define TURN_COS_MIN 0.75
/* Corrected points farther than this many step lengths from the previous
 * point are taken as a jump to another branch, not a step along this one. */
#define JUMP_FACTOR 2.0
#define FOLD_MAX_ITER 100

typedef struct {
    size_t n, N; /* equations, unknowns */
    bkf_cont_residual residual;
    void *data;
    const bkf_cont_options *opt;
    int use_fd;
    bkf_error cb_err;           /* the residual writes here, never into err */
    char why[BKF_ERROR_LEN];    /* last recoverable failure, for messages */
    size_t newton_iterations;
    /* work arrays */
    double *g, *g2, *jac, *uh;
    double *A, *rhs, *sol, *row;
    size_t *perm;
} cont_ws;

/* The last row of the bordered system: either u[k] == b exactly, or
 * row . u == b for a general row (the arclength condition). */
typedef struct {
    int fixed;
    size_t k;
    const double *row;
    double b;
} constraint;

static double scale_of(const cont_ws *ws, size_t i)
{
    return ws->opt->scale ? ws->opt->scale[i] : 1.0;
}

static double sdot(const cont_ws *ws, const double *a, const double *b)
{
    double s = 0.0;
    for (size_t i = 0; i < ws->N; i++) {
        double w = scale_of(ws, i);
        s += a[i] * b[i] / (w * w);
    }
    return s;
}

static double snorm_diff(const cont_ws *ws, const double *a, const double *b)
{
    double s = 0.0;
    for (size_t i = 0; i < ws->N; i++) {
        double d = (a[i] - b[i]) / scale_of(ws, i);
        s += d * d;
    }
    return sqrt(s);
}

static void tangent_row(const cont_ws *ws, const double *t, double *row)
{
    for (size_t i = 0; i < ws->N; i++) {
        double w = scale_of(ws, i);
        row[i] = t[i] / (w * w);
    }
}

static int all_finite(const double *x, size_t len)
{
    for (size_t i = 0; i < len; i++)
        if (!isfinite(x[i])) return 0;
    return 1;
}

static int recoverable(cont_ws *ws, const char *what)
{
    size_t len = strlen(what);
    if (len >= sizeof ws->why) len = sizeof ws->why - 1;
    memcpy(ws->why, what, len);
    ws->why[len] = '\0';
    return BKF_ENUMERIC;
}

/* Any status other than BKF_OK and BKF_ENUMERIC from the residual ends the
 * run; its message goes to the caller unchanged when it wrote one. */
static int call_residual(cont_ws *ws, const double *u, double *g, double *jac,
                         bkf_error *err)
{
    ws->cb_err.message[0] = '\0';
    int st = ws->residual(u, g, jac, ws->data, &ws->cb_err);
    if (st == BKF_OK) {
        if (!all_finite(g, ws->n)) return recoverable(ws, "residual is not finite");
        return BKF_OK;
    }
    if (st == BKF_ENUMERIC) {
        if (ws->cb_err.message[0])
            snprintf(ws->why, sizeof ws->why, "residual failed: %.280s", ws->cb_err.message);
        else
            snprintf(ws->why, sizeof ws->why, "residual failed");
        return BKF_ENUMERIC;
    }
    if (ws->cb_err.message[0]) return bkf_error_set(err, st, "%s", ws->cb_err.message);
    return bkf_error_set(err, st, "continuation residual returned status %d", st);
}

/* G(u) into ws->g and, if want_jac, the Jacobian into ws->jac.  The jac
 * buffer is filled with NaN first: a callback that leaves it untouched does
 * not compute Jacobians, and the run switches to finite differences. */
static int evaluate(cont_ws *ws, const double *u, int want_jac, bkf_error *err)
{
    size_t n = ws->n, N = ws->N;
    if (want_jac && !ws->use_fd) {
        for (size_t i = 0; i < n * N; i++) ws->jac[i] = NAN;
        int st = call_residual(ws, u, ws->g, ws->jac, err);
        if (st != BKF_OK) return st;
        int untouched = 1;
        for (size_t i = 0; i < n * N && untouched; i++)
            if (!isnan(ws->jac[i])) untouched = 0;
        if (!untouched) {
            if (!all_finite(ws->jac, n * N))
                return recoverable(ws, "Jacobian is not finite");
            return BKF_OK;
        }
        ws->use_fd = 1;
    } else {
        int st = call_residual(ws, u, ws->g, NULL, err);
        if (st != BKF_OK || !want_jac) return st;
    }
    /* Forward differences: the step follows the size of each component, or
     * its scale where the component is near zero, so that it stays well
     * above rounding in u_j + h. */
    const double root_eps = sqrt(DBL_EPSILON);
    memcpy(ws->uh, u, N * sizeof *u);
    for (size_t j = 0; j < N; j++) {
        double h = root_eps * fmax(fabs(u[j]), scale_of(ws, j));
        ws->uh[j] = u[j] + h;
        h = ws->uh[j] - u[j]; /* the step actually taken in floating point */
        int st = call_residual(ws, ws->uh, ws->g2, NULL, err);
        ws->uh[j] = u[j];
        if (st != BKF_OK) return st;
        for (size_t i = 0; i < n; i++) ws->jac[i * N + j] = (ws->g2[i] - ws->g[i]) / h;
    }
    return BKF_OK;
}

/* Solve [ws->jac; row^T] x = [top; last] (top NULL: zeros).  GSL's LU solve
 * aborts through the default error handler on an exactly singular matrix,
 * so singularity is checked here first. */
static int solve_bordered(cont_ws *ws, const double *row, const double *top,
                          double last, double *x)
{
    size_t n = ws->n, N = ws->N;
    memcpy(ws->A, ws->jac, n * N * sizeof *ws->A);
    memcpy(ws->A + n * N, row, N * sizeof *ws->A);
    for (size_t i = 0; i < n; i++) ws->rhs[i] = top ? top[i] : 0.0;
    ws->rhs[n] = last;

    gsl_matrix_view A = gsl_matrix_view_array(ws->A, N, N);
    gsl_vector_view b = gsl_vector_view_array(ws->rhs, N);
    gsl_vector_view xv = gsl_vector_view_array(x, N);
    gsl_permutation p = {N, ws->perm};
    int signum = 0;
    if (gsl_linalg_LU_decomp(&A.matrix, &p, &signum) != GSL_SUCCESS)
        return recoverable(ws, "LU decomposition failed");
    for (size_t i = 0; i < N; i++) {
        double d = ws->A[i * N + i];
        if (d == 0.0 || !isfinite(d))
            return recoverable(ws, "singular extended Jacobian");
    }
    if (gsl_linalg_LU_solve(&A.matrix, &p, &b.vector, &xv.vector) != GSL_SUCCESS)
        return recoverable(ws, "LU solve failed");
    if (!all_finite(x, N)) return recoverable(ws, "singular extended Jacobian");
    return BKF_OK;
}

/* Newton on [G(u); constraint] from the guess in u.  The step is judged per
 * component against max(|u_i|, scale_i), so that tol means a relative
 * accuracy for large components and an absolute one (in scale units) near
 * zero; an absolute test alone would stall on rounding for large u. */
static int correct(cont_ws *ws, double *u, const constraint *c, int *iterations,
                   bkf_error *err)
{
    size_t n = ws->n, N = ws->N;
    const double tol = ws->opt->newton_tol;
    const double *row = c->row;
    if (c->fixed) {
        for (size_t i = 0; i < N; i++) ws->row[i] = 0.0;
        ws->row[c->k] = 1.0;
        row = ws->row;
        u[c->k] = c->b;
    }
    *iterations = 0;
    for (int it = 1; it <= ws->opt->newton_max_iter; it++) {
        *iterations = it;
        ws->newton_iterations++;
        int st = evaluate(ws, u, 1, err);
        if (st != BKF_OK) return st;
        double cval = 0.0;
        if (!c->fixed) {
            for (size_t i = 0; i < N; i++) cval += row[i] * u[i];
            cval -= c->b;
        }
        for (size_t i = 0; i < n; i++) ws->g[i] = -ws->g[i];
        st = solve_bordered(ws, row, ws->g, -cval, ws->sol);
        if (st != BKF_OK) return st;
        double worst = 0.0;
        for (size_t i = 0; i < N; i++) {
            u[i] += ws->sol[i];
            double rel = fabs(ws->sol[i]) / fmax(fabs(u[i]), scale_of(ws, i));
            if (rel > worst) worst = rel;
        }
        /* Rounding in the solve must not move a held component off its
         * value: a bound landing is promised to be exact. */
        if (c->fixed) u[c->k] = c->b;
        if (!all_finite(u, N)) return recoverable(ws, "Newton iterate is not finite");
        if (worst <= tol) return BKF_OK;
    }
    snprintf(ws->why, sizeof ws->why, "Newton did not converge in %d iterations",
             ws->opt->newton_max_iter);
    return BKF_ENUMERIC;
}

/* Unit (scaled) null vector of the Jacobian at u, normalised so that
 * row . t > 0.  With row built from the previous tangent this is the
 * orientation rule; with row = e_k it fixes t[k] > 0. */
static int tangent_at(cont_ws *ws, const double *u, const double *row, double *t,
                      bkf_error *err)
{
    int st = evaluate(ws, u, 1, err);
    if (st != BKF_OK) return st;
    st = solve_bordered(ws, row, NULL, 1.0, t);
    if (st != BKF_OK) return st;
    double norm = sqrt(sdot(ws, t, t));
    if (!(norm > 0.0) || !isfinite(norm))
        return recoverable(ws, "tangent has no finite norm");
    for (size_t i = 0; i < ws->N; i++) t[i] /= norm;
    return BKF_OK;
}

/* The point on the branch whose projection on t0 from u0 is s, and its
 * tangent oriented along t0. */
static int point_at(cont_ws *ws, const double *u0, const double *t0,
                    const double *row0, double s, double *u, double *t,
                    bkf_error *err)
{
    for (size_t i = 0; i < ws->N; i++) u[i] = u0[i] + s * t0[i];
    constraint c = {0, 0, row0, 0.0};
    for (size_t i = 0; i < ws->N; i++) c.b += row0[i] * u[i];
    int iterations = 0;
    int st = correct(ws, u, &c, &iterations, err);
    if (st != BKF_OK) return st;
    return tangent_at(ws, u, row0, t, err);
}

static int positive(double x) { return x > 0.0; }

/* Between (u0, t0) and a point at projection s_end whose tangent component
 * `dir` has the other sign: t[dir] along the piece is a smooth function of
 * the projection, nearly linear at a quadratic fold, so regula falsi with
 * the Illinois modification converges fast and never leaves the bracket. */
static int locate_fold(cont_ws *ws, const double *u0, const double *t0,
                       const double *row0, double s_end, double f_end, size_t dir,
                       double *uf, double *tf, bkf_error *err)
{
    double a = 0.0, fa = t0[dir], b = s_end, fb = f_end;
    const double ftol = ws->opt->newton_tol;
    const double stol = ws->opt->newton_tol * s_end;
    int side = 0;
    for (int it = 0; it < FOLD_MAX_ITER; it++) {
        double s = (a * fb - b * fa) / (fb - fa);
        if (!(s > a && s < b)) s = 0.5 * (a + b);
        int st = point_at(ws, u0, t0, row0, s, uf, tf, err);
        if (st != BKF_OK) return st;
        double fs = tf[dir];
        if (fabs(fs) <= ftol || b - a <= stol) return BKF_OK;
        if (positive(fs) == positive(fb)) {
            b = s;
            fb = fs;
            if (side == -1) fa *= 0.5;
            side = -1;
        } else {
            a = s;
            fa = fs;
            if (side == +1) fb *= 0.5;
            side = +1;
        }
    }
    return recoverable(ws, "fold search did not converge");
}

static int validate(bkf_cont_residual residual, bkf_cont_accept accept,
                    const double *u0, int dir_index, int direction,
                    const bkf_cont_options *o, bkf_error *err)
{
    if (!residual) return bkf_error_set(err, BKF_EINPUT, "residual must not be NULL");
    if (!accept) return bkf_error_set(err, BKF_EINPUT, "accept must not be NULL");
    if (!u0) return bkf_error_set(err, BKF_EINPUT, "u0 must not be NULL");
    if (!o) return bkf_error_set(err, BKF_EINPUT, "options must not be NULL");
    size_t n = o->n;
    /* The (n+1)^2 matrix and the int indices bound the size. */
    if (n == 0 || n >= (size_t)INT_MAX || n + 1 > SIZE_MAX / sizeof(double) / (n + 1))
        return bkf_error_set(err, BKF_EINPUT,
                             "options->n = %zu must be at least 1 (and the (n+1)^2 "
                             "matrix must fit in memory)", n);
    size_t N = n + 1;
    for (size_t i = 0; i < N; i++)
        if (!isfinite(u0[i]))
            return bkf_error_set(err, BKF_EINPUT, "u0[%zu] = %g must be finite", i, u0[i]);
    if (dir_index < 0 || (size_t)dir_index >= N)
        return bkf_error_set(err, BKF_EINPUT, "dir_index = %d is outside [0, %zu]",
                             dir_index, n);
    if (direction != 1 && direction != -1)
        return bkf_error_set(err, BKF_EINPUT, "direction = %d must be +1 or -1", direction);
    if (!isfinite(o->step_min) || o->step_min <= 0.0)
        return bkf_error_set(err, BKF_EINPUT, "step_min = %g must be a finite number > 0",
                             o->step_min);
    if (!isfinite(o->step_max) || o->step_max < o->step_min)
        return bkf_error_set(err, BKF_EINPUT,
                             "step_max = %g must be finite and >= step_min = %g",
                             o->step_max, o->step_min);
    if (!isfinite(o->step_initial) || o->step_initial < o->step_min ||
        o->step_initial > o->step_max)
        return bkf_error_set(err, BKF_EINPUT,
                             "step_initial = %g is outside [step_min, step_max] = [%g, %g]",
                             o->step_initial, o->step_min, o->step_max);
    if (!isfinite(o->newton_tol) || o->newton_tol <= 0.0 || o->newton_tol >= 1.0)
        return bkf_error_set(err, BKF_EINPUT, "newton_tol = %g is outside (0, 1)",
                             o->newton_tol);
    if (o->newton_max_iter < 1)
        return bkf_error_set(err, BKF_EINPUT, "newton_max_iter = %d must be >= 1",
                             o->newton_max_iter);
    if (o->grow_iterations < 1 || o->grow_iterations > o->newton_max_iter)
        return bkf_error_set(err, BKF_EINPUT,
                             "grow_iterations = %d must be in [1, newton_max_iter = %d]",
                             o->grow_iterations, o->newton_max_iter);
    if (o->max_points < 1)
        return bkf_error_set(err, BKF_EINPUT, "max_points = %zu must be >= 1",
                             o->max_points);
    if (o->scale)
        for (size_t i = 0; i < N; i++)
            if (!isfinite(o->scale[i]) || o->scale[i] <= 0.0)
                return bkf_error_set(err, BKF_EINPUT,
                                     "scale[%zu] = %g must be a finite number > 0", i,
                                     o->scale[i]);
    if (o->stop_index >= 0) {
        if ((size_t)o->stop_index >= N)
            return bkf_error_set(err, BKF_EINPUT, "stop_index = %d is outside [-1, %zu]",
                                 o->stop_index, n);
        if (isnan(o->stop_min) || isnan(o->stop_max) || !(o->stop_min < o->stop_max))
            return bkf_error_set(err, BKF_EINPUT,
                                 "stop_min = %g must be below stop_max = %g",
                                 o->stop_min, o->stop_max);
        double v = u0[o->stop_index];
        if (v < o->stop_min || v > o->stop_max)
            return bkf_error_set(err, BKF_EINPUT,
                                 "u0[stop_index = %d] = %g is outside [stop_min, "
                                 "stop_max] = [%g, %g]",
                                 o->stop_index, v, o->stop_min, o->stop_max);
    }
    return BKF_OK;
}

bkf_cont_options bkf_cont_options_default(size_t n)
{
    bkf_cont_options o;
    o.n = n;
    o.step_initial = 0.05;
    o.step_min = 1e-10;
    o.step_max = 0.5;
    o.newton_tol = 1e-10;
    o.newton_max_iter = 8;
    o.grow_iterations = 2;
    o.locate_folds = 1;
    o.max_points = 10000;
    o.scale = NULL;
    o.jacobian_fd = 0;
    o.stop_index = -1;
    o.stop_min = -INFINITY;
    o.stop_max = INFINITY;
    return o;
}

/* Everything the run allocates, freed in one place. */
typedef struct {
    double *u, *t, *un, *tn, *uf, *tf, *row;
} run_vectors;

static void ws_free(cont_ws *ws, run_vectors *v)
{
    free(ws->g); free(ws->g2); free(ws->jac); free(ws->uh);
    free(ws->A); free(ws->rhs); free(ws->sol); free(ws->row); free(ws->perm);
    free(v->u); free(v->t); free(v->un); free(v->tn); free(v->uf); free(v->tf);
    free(v->row);
}

static int ws_alloc(cont_ws *ws, run_vectors *v)
{
    size_t n = ws->n, N = ws->N, d = sizeof(double);
    ws->g = malloc(n * d);
    ws->g2 = malloc(n * d);
    ws->jac = malloc(n * N * d);
    ws->uh = malloc(N * d);
    ws->A = malloc(N * N * d);
    ws->rhs = malloc(N * d);
    ws->sol = malloc(N * d);
    ws->row = malloc(N * d);
    ws->perm = malloc(N * sizeof(size_t));
    v->u = malloc(N * d);
    v->t = malloc(N * d);
    v->un = malloc(N * d);
    v->tn = malloc(N * d);
    v->uf = malloc(N * d);
    v->tf = malloc(N * d);
    v->row = malloc(N * d);
    return ws->g && ws->g2 && ws->jac && ws->uh && ws->A && ws->rhs && ws->sol &&
           ws->row && ws->perm && v->u && v->t && v->un && v->tn && v->uf && v->tf &&
           v->row;
}

/* One step from (u, t) of length h into (un, tn).  *landed says the point
 * was placed on a stop bound; *proj is its projection on t (h for an
 * ordinary step).  BKF_ENUMERIC: reject the step and shrink. */
static int take_step(cont_ws *ws, const run_vectors *v, double h, int *landed,
                     double *proj, int *iterations, bkf_error *err)
{
    const bkf_cont_options *o = ws->opt;
    size_t N = ws->N;
    int st;
    *landed = 0;
    *proj = h;
    double target = 0.0, theta = 1.0;
    size_t k = o->stop_index >= 0 ? (size_t)o->stop_index : 0;
    if (o->stop_index >= 0) {
        double p = v->u[k] + h * v->t[k];
        if (p > o->stop_max || p < o->stop_min) {
            target = p > o->stop_max ? o->stop_max : o->stop_min;
            theta = (target - v->u[k]) / (h * v->t[k]);
            *landed = 1;
        }
    }
    if (*landed) {
        for (size_t i = 0; i < N; i++) v->un[i] = v->u[i] + theta * h * v->t[i];
    } else {
        for (size_t i = 0; i < N; i++) v->un[i] = v->u[i] + h * v->t[i];
        constraint c = {0, 0, v->row, sdot(ws, v->t, v->un)};
        st = correct(ws, v->un, &c, iterations, err);
        if (st != BKF_OK) return st;
        double x = v->un[k];
        if (o->stop_index >= 0 && (x > o->stop_max || x < o->stop_min)) {
            /* The predictor stayed inside but the branch bends out: restart
             * the landing from the chord, cut where it meets the bound. */
            target = x > o->stop_max ? o->stop_max : o->stop_min;
            theta = (target - v->u[k]) / (x - v->u[k]);
            for (size_t i = 0; i < N; i++)
                v->un[i] = v->u[i] + theta * (v->un[i] - v->u[i]);
            *landed = 1;
        }
    }
    if (*landed) {
        constraint c = {1, k, NULL, target};
        st = correct(ws, v->un, &c, iterations, err);
        if (st != BKF_OK) return st;
        *proj = sdot(ws, v->t, v->un) - sdot(ws, v->t, v->u);
        if (!(*proj > 0.0)) return recoverable(ws, "bound landing went backwards");
    }
    if (snorm_diff(ws, v->un, v->u) > JUMP_FACTOR * h)
        return recoverable(ws, "corrector jumped away from the branch");
    st = tangent_at(ws, v->un, v->row, v->tn, err);
    if (st != BKF_OK) return st;
    if (sdot(ws, v->t, v->tn) < TURN_COS_MIN)
        return recoverable(ws, "tangent turned too far in one step");
    return BKF_OK;
}

static int cont_run_body(bkf_cont_residual residual, bkf_cont_accept accept, void *data,
                         const double *u0, int dir_index, int direction,
                         const bkf_cont_options *options, bkf_cont_report *report,
                         bkf_error *err)
{
    bkf_cont_report rep = {0, 0, 0, 0, 0};
    if (report) *report = rep;
    int st = validate(residual, accept, u0, dir_index, direction, options, err);
    if (st != BKF_OK) return st;

    const bkf_cont_options *o = options;
    cont_ws ws;
    memset(&ws, 0, sizeof ws);
    ws.n = o->n;
    ws.N = o->n + 1;
    ws.residual = residual;
    ws.data = data;
    ws.opt = o;
    ws.use_fd = o->jacobian_fd != 0;
    run_vectors v;
    memset(&v, 0, sizeof v);
    const size_t N = ws.N, dir = (size_t)dir_index;

    if (!ws_alloc(&ws, &v)) {
        st = bkf_error_set(err, BKF_ENOMEM, "continuation: out of memory for n = %zu",
                           o->n);
        goto done;
    }

    /* Holding the direction component fixed makes the start the point of
     * the branch at the parameter value the caller asked for. */
    memcpy(v.u, u0, N * sizeof *u0);
    int iterations = 0;
    constraint hold = {1, dir, NULL, u0[dir]};
    st = correct(&ws, v.u, &hold, &iterations, err);
    if (st == BKF_ENUMERIC) {
        st = bkf_error_set(err, BKF_ENUMERIC,
                           "continuation: could not correct the starting point at "
                           "u[%d] = %.17g: %s", dir_index, u0[dir], ws.why);
        goto done;
    }
    if (st != BKF_OK) goto done;
    for (size_t i = 0; i < N; i++) v.row[i] = i == dir ? 1.0 : 0.0;
    st = tangent_at(&ws, v.u, v.row, v.t, err);
    if (st == BKF_ENUMERIC) {
        st = bkf_error_set(err, BKF_ENUMERIC,
                           "continuation: no tangent at the starting point u[%d] = "
                           "%.17g (a fold in u[%d]?): %s",
                           dir_index, u0[dir], dir_index, ws.why);
        goto done;
    }
    if (st != BKF_OK) goto done;
    for (size_t i = 0; i < N; i++) v.t[i] *= direction;

    rep.points = 1;
    if (accept(v.u, v.t, 0, data)) goto done;

    double h = o->step_initial;
    while (rep.points < o->max_points) {
        size_t k = o->stop_index >= 0 ? (size_t)o->stop_index : 0;
        if (o->stop_index >= 0) {
            /* Already on a bound and heading out: nothing left to add. */
            if ((v.u[k] >= o->stop_max && v.t[k] > 0.0) ||
                (v.u[k] <= o->stop_min && v.t[k] < 0.0)) {
                rep.reached_bound = 1;
                break;
            }
        }
        tangent_row(&ws, v.t, v.row);
        int landed = 0;
        double proj = h;
        st = take_step(&ws, &v, h, &landed, &proj, &iterations, err);
        if (st == BKF_ENUMERIC) {
            rep.rejected_steps++;
            h *= 0.5;
            if (h < o->step_min) {
                st = bkf_error_set(err, BKF_ENUMERIC,
                                   "continuation: step fell below step_min = %g after "
                                   "the point u[%d] = %.17g: %s",
                                   o->step_min, dir_index, v.u[dir], ws.why);
                goto done;
            }
            continue;
        }
        if (st != BKF_OK) goto done;

        if (o->locate_folds && positive(v.t[dir]) != positive(v.tn[dir])) {
            st = locate_fold(&ws, v.u, v.t, v.row, proj, v.tn[dir], dir, v.uf, v.tf, err);
            if (st == BKF_ENUMERIC) {
                st = bkf_error_set(err, BKF_ENUMERIC,
                                   "continuation: could not locate the fold between "
                                   "u[%d] = %.17g and %.17g: %s",
                                   dir_index, v.u[dir], v.un[dir], ws.why);
                goto done;
            }
            if (st != BKF_OK) goto done;
            rep.folds++;
            if (accept(v.uf, v.tf, 1, data)) goto done;
        }

        double *swap = v.u;
        v.u = v.un;
        v.un = swap;
        swap = v.t;
        v.t = v.tn;
        v.tn = swap;
        rep.points++;
        if (accept(v.u, v.t, 0, data)) goto done;
        if (landed) {
            rep.reached_bound = 1;
            break;
        }
        if (iterations <= o->grow_iterations)
            h = fmin(1.5 * h, o->step_max);
        else if (iterations > o->grow_iterations + 2)
            h = fmax(0.5 * h, o->step_min);
    }
    st = BKF_OK;

done:
    rep.newton_iterations = ws.newton_iterations;
    if (report) *report = rep;
    ws_free(&ws, &v);
    return st;
}

int bkf_cont_run(bkf_cont_residual residual, bkf_cont_accept accept, void *data,
                 const double *u0, int dir_index, int direction,
                 const bkf_cont_options *options, bkf_cont_report *report,
                 bkf_error *err)
{
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    int rc = cont_run_body(residual, accept, data, u0, dir_index, direction, options, report, err);
    bkf_gsl_handler_pop(handler);
    return rc;
}

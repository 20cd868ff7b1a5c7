/* Fits of the asymptotic coefficients of T(mu, nu) and the validity map of
 * the asymptotic formulas; see include/bkfront/asymfit.h.
 *
 * The large-mu model R = A mu^p + B ln(mu)/mu + D/mu is linear in A, B, D
 * once p is fixed, so the search is one-dimensional: chi2(p) is the weighted
 * residual of the linear least-squares fit at that p (gsl_multifit_wlinear,
 * SVD with column balancing: the three columns differ by two decades in
 * size).  Near the asymptotic regime chi2(p) is unimodal but very sharp (at
 * nu = 0 the rms relative residual is 3e-6 at the minimum and 3e-3 a step of
 * 0.02 away), and far from it (small mu, |nu| -> 1) nothing guarantees a
 * single minimum; so a coarse scan over the whole interval picks the basin
 * and NLopt (BOBYQA, derivative-free, bounded) polishes within one scan step
 * of it.
 *
 * The weights are 1/R^2 (relative least squares).  The residuals are the
 * dropped terms of the series, O(mu^(-4/3)), not noise; plain least squares
 * would fit the smallest mu, where they are largest, and let the largest mu,
 * where the model is most nearly complete, count least. */
#include "bkfront/asymfit.h"

#include <math.h>
#include <nlopt.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_math.h>
#include <gsl/gsl_multifit.h>

#include "bkfront/asymptotics.h"
#include "bkfront/cycle.h"
#include "bkfront/model.h"

#define P_DERIVED (-1.0 / 3.0)
#define P_SCAN_STEP 0.025
#define NPARAM_FREE 4
#define NPARAM_FIXED 3

/* ---- cycle solves -------------------------------------------------------- */

typedef struct {
    bkf_cycle *cycle;
    size_t solves;
    double rel_err_max;
} solver;

static int solver_init(solver *sv, bkf_error *err)
{
    sv->cycle = bkf_cycle_alloc();
    sv->solves = 0;
    sv->rel_err_max = 0.0;
    if (!sv->cycle) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    return BKF_OK;
}

static void solver_free(solver *sv) { bkf_cycle_free(sv->cycle); }

/* T and its error at (mu, nu).  The tight tolerance is refused only where the
 * two-tolerance error estimate cannot reach it (near |nu| -> 1 and at the
 * largest mu); one decade looser is still far below every eps the map asks. */
static int solve_period(solver *sv, double mu, double nu, double *T, double *T_err,
                        bkf_error *err)
{
    bkf_cycle_options opt = bkf_cycle_options_default();
    opt.warm_start = 1;
    opt.tol = BKF_ASYMFIT_TOL;
    bkf_error e = {0};
    sv->solves++;
    int s = bkf_cycle_solve(sv->cycle, mu, nu, &opt, &e);
    if (bkf_status_is_numerical(s)) {
        opt.tol = BKF_ASYMFIT_TOL_FALLBACK;
        sv->solves++;
        s = bkf_cycle_solve(sv->cycle, mu, nu, &opt, &e);
    }
    if (s) {
        /* The cycle module names the point in most of its messages already. */
        if (strncmp(e.message, "cycle at ", 9) == 0) return bkf_error_set(err, s, "%s", e.message);
        return bkf_error_set(err, s, "cycle at mu = %.15g, nu = %.15g: %s", mu, nu, e.message);
    }
    const bkf_cycle_result *r = bkf_cycle_get(sv->cycle);
    *T = r->period;
    *T_err = r->period_err;
    if (r->period_err / r->period > sv->rel_err_max) sv->rel_err_max = r->period_err / r->period;
    return BKF_OK;
}

/* n log-spaced points from lo to hi, ends exact. */
static void log_space(double lo, double hi, size_t n, double *x)
{
    double a = log(lo), b = log(hi);
    for (size_t i = 0; i < n; i++) x[i] = exp(a + (b - a) * (double)i / (double)(n - 1));
    x[0] = lo;
    x[n - 1] = hi;
}

static int check_finite(const char *name, double x, bkf_error *err)
{
    if (!isfinite(x))
        return bkf_error_set(err, BKF_EINPUT, "%s = %g is not a finite number", name, x);
    return BKF_OK;
}

static int check_nu(double nu, bkf_error *err)
{
    bkf_error e;
    if (bkf_model_check_nu_active(nu, &e) != BKF_OK)
        return bkf_error_set(err, BKF_EINPUT, "%s", e.message);
    return BKF_OK;
}

/* ---- weighted linear least squares -------------------------------------- */

/* One weighted linear fit y ~ X c with its unscaled covariance (X^T W X)^-1;
 * sized for the largest problem and reused for every p and every subset. */
typedef struct {
    /* indexed by the number of columns (parameters) */
    gsl_multifit_linear_workspace *ws[NPARAM_FREE + 1];
    size_t ws_rows[NPARAM_FREE + 1];
    gsl_matrix *X[NPARAM_FREE + 1];
    gsl_matrix *cov[NPARAM_FREE + 1];
    gsl_vector *c[NPARAM_FREE + 1];
    gsl_vector *y, *w;
} lsq;

static void lsq_free(lsq *q)
{
    for (size_t k = 0; k <= NPARAM_FREE; k++) {
        if (q->ws[k]) gsl_multifit_linear_free(q->ws[k]);
        if (q->X[k]) gsl_matrix_free(q->X[k]);
        if (q->cov[k]) gsl_matrix_free(q->cov[k]);
        if (q->c[k]) gsl_vector_free(q->c[k]);
    }
    if (q->y) gsl_vector_free(q->y);
    if (q->w) gsl_vector_free(q->w);
    memset(q, 0, sizeof *q);
}

static int lsq_init(lsq *q, size_t nmax, bkf_error *err)
{
    memset(q, 0, sizeof *q);
    for (size_t k = 1; k <= NPARAM_FREE; k++) {
        q->cov[k] = gsl_matrix_alloc(k, k);
        q->c[k] = gsl_vector_alloc(k);
        if (!q->cov[k] || !q->c[k]) {
            lsq_free(q);
            return bkf_error_set(err, BKF_ENOMEM, "out of memory");
        }
    }
    q->y = gsl_vector_alloc(nmax);
    q->w = gsl_vector_alloc(nmax);
    if (!q->y || !q->w) {
        lsq_free(q);
        return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    }
    return BKF_OK;
}

/* Views of the first n rows; the workspace is reallocated when n changes
 * (GSL's workspace is tied to the problem size). */
static int lsq_prepare(lsq *q, size_t n, size_t k)
{
    if (q->ws[k] && q->X[k] && q->ws_rows[k] == n) return GSL_SUCCESS;
    if (q->ws[k]) gsl_multifit_linear_free(q->ws[k]);
    if (q->X[k]) gsl_matrix_free(q->X[k]);
    q->ws[k] = gsl_multifit_linear_alloc(n, k);
    q->X[k] = gsl_matrix_alloc(n, k);
    q->ws_rows[k] = n;
    return (q->ws[k] && q->X[k]) ? GSL_SUCCESS : GSL_ENOMEM;
}

/* Solves with X[k] (n x k), y and w already filled in their first n rows. */
static int lsq_solve(lsq *q, size_t n, size_t k, double *chi2)
{
    gsl_vector_view y = gsl_vector_subvector(q->y, 0, n);
    gsl_vector_view w = gsl_vector_subvector(q->w, 0, n);
    return gsl_multifit_wlinear(q->X[k], &w.vector, &y.vector, q->c[k], q->cov[k], chi2,
                                q->ws[k]);
}

/* ---- the large-mu fit ---------------------------------------------------- */

typedef struct {
    const double *mu, *R;
    size_t n;
    lsq *q;
    int status;          /* first GSL failure inside the objective */
    size_t evals;
} corr_problem;

typedef struct {
    double A, p, B, D;
    double A_err, p_err, B_err, D_err;   /* scaled covariance only */
    double chi2, rms_rel;
} corr_fit;

static int fill_linear(corr_problem *cp, double p)
{
    int s = lsq_prepare(cp->q, cp->n, NPARAM_FIXED);
    if (s) return s;
    gsl_matrix *X = cp->q->X[NPARAM_FIXED];
    for (size_t i = 0; i < cp->n; i++) {
        double mu = cp->mu[i];
        gsl_matrix_set(X, i, 0, pow(mu, p));
        gsl_matrix_set(X, i, 1, log(mu) / mu);
        gsl_matrix_set(X, i, 2, 1.0 / mu);
        gsl_vector_set(cp->q->y, i, cp->R[i]);
        gsl_vector_set(cp->q->w, i, 1.0 / (cp->R[i] * cp->R[i]));
    }
    return GSL_SUCCESS;
}

/* chi2 of the best A, B, D at this p. */
static double chi2_at(corr_problem *cp, double p)
{
    double chi2 = HUGE_VAL;
    int s = fill_linear(cp, p);
    if (!s) s = lsq_solve(cp->q, cp->n, NPARAM_FIXED, &chi2);
    cp->evals++;
    if (s || !isfinite(chi2)) {
        if (!cp->status) cp->status = s ? s : GSL_EFAILED;
        return HUGE_VAL;
    }
    return chi2;
}

static double nlopt_objective(unsigned n, const double *x, double *grad, void *data)
{
    (void)n;
    (void)grad;   /* derivative-free algorithm */
    return chi2_at(data, x[0]);
}

/* A, B, D at fixed p, with scaled standard errors. */
static int fit_fixed_p(corr_problem *cp, double p, corr_fit *f, bkf_error *err)
{
    double chi2;
    int s = fill_linear(cp, p);
    if (!s) s = lsq_solve(cp->q, cp->n, NPARAM_FIXED, &chi2);
    if (s)
        return bkf_error_set(err, BKF_ENUMERIC, "linear least squares at p = %g failed: %s",
                             p, gsl_strerror(s));
    const gsl_vector *c = cp->q->c[NPARAM_FIXED];
    const gsl_matrix *cov = cp->q->cov[NPARAM_FIXED];
    double s2 = cp->n > NPARAM_FIXED ? chi2 / (double)(cp->n - NPARAM_FIXED) : 0.0;
    f->p = p;
    f->p_err = 0.0;
    f->A = gsl_vector_get(c, 0);
    f->B = gsl_vector_get(c, 1);
    f->D = gsl_vector_get(c, 2);
    f->A_err = sqrt(s2 * gsl_matrix_get(cov, 0, 0));
    f->B_err = sqrt(s2 * gsl_matrix_get(cov, 1, 1));
    f->D_err = sqrt(s2 * gsl_matrix_get(cov, 2, 2));
    f->chi2 = chi2;
    f->rms_rel = sqrt(chi2 / (double)cp->n);
    return BKF_OK;
}

/* All four free: scan, polish with NLopt, then the covariance of the full
 * nonlinear model from its Jacobian at the optimum. */
static int fit_free_p(corr_problem *cp, double p_lo, double p_hi, corr_fit *f, bkf_error *err)
{
    size_t nscan = (size_t)ceil((p_hi - p_lo) / P_SCAN_STEP) + 1;
    double step = (p_hi - p_lo) / (double)(nscan - 1);
    double best_p = p_lo, best = HUGE_VAL;
    cp->status = 0;
    for (size_t i = 0; i < nscan; i++) {
        double p = p_lo + step * (double)i, c2 = chi2_at(cp, p);
        if (c2 < best) best = c2, best_p = p;
    }
    if (cp->status || !isfinite(best))
        return bkf_error_set(err, BKF_ENUMERIC, "linear least squares failed in the p scan: %s",
                             gsl_strerror(cp->status ? cp->status : GSL_EFAILED));

    double lb = fmax(p_lo, best_p - step), ub = fmin(p_hi, best_p + step);
    nlopt_opt opt = nlopt_create(NLOPT_LN_BOBYQA, 1);
    if (!opt) return bkf_error_set(err, BKF_ENOMEM, "out of memory (NLopt)");
    double x = best_p, fx = best;
    nlopt_result r = nlopt_set_lower_bounds(opt, &lb);
    if (r > 0) r = nlopt_set_upper_bounds(opt, &ub);
    if (r > 0) r = nlopt_set_min_objective(opt, nlopt_objective, cp);
    if (r > 0) r = nlopt_set_xtol_abs1(opt, 1e-10);
    if (r > 0) r = nlopt_set_initial_step1(opt, step / 4.0);
    if (r > 0) r = nlopt_set_maxeval(opt, 500);
    if (r > 0) r = nlopt_optimize(opt, &x, &fx);
    nlopt_destroy(opt);
    /* Round-off limited means chi2 stopped changing before xtol was met:
     * the minimum is as well located as the data allow. */
    if ((r < 0 && r != NLOPT_ROUNDOFF_LIMITED) || !isfinite(x) || cp->status)
        return bkf_error_set(err, BKF_ENUMERIC, "NLopt search for p failed (nlopt status %d%s%s)",
                             (int)r, cp->status ? ", " : "",
                             cp->status ? gsl_strerror(cp->status) : "");

    int s = fit_fixed_p(cp, x, f, err);
    if (s) return s;
    if (cp->n <= NPARAM_FREE) {
        f->A_err = f->B_err = f->D_err = f->p_err = 0.0;
        return BKF_OK;
    }

    /* Linearised covariance of (A, p, B, D): s2 (J^T W J)^-1. */
    lsq *q = cp->q;
    if ((s = lsq_prepare(q, cp->n, NPARAM_FREE)))
        return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    gsl_matrix *J = q->X[NPARAM_FREE];
    for (size_t i = 0; i < cp->n; i++) {
        double mu = cp->mu[i], mp = pow(mu, f->p);
        gsl_matrix_set(J, i, 0, mp);
        gsl_matrix_set(J, i, 1, f->A * mp * log(mu));
        gsl_matrix_set(J, i, 2, log(mu) / mu);
        gsl_matrix_set(J, i, 3, 1.0 / mu);
    }
    double unused;
    if ((s = lsq_solve(q, cp->n, NPARAM_FREE, &unused)))
        return bkf_error_set(err, BKF_ENUMERIC, "covariance of the fit failed: %s",
                             gsl_strerror(s));
    double s2 = f->chi2 / (double)(cp->n - NPARAM_FREE);
    const gsl_matrix *cov = q->cov[NPARAM_FREE];
    f->A_err = sqrt(s2 * gsl_matrix_get(cov, 0, 0));
    f->p_err = sqrt(s2 * gsl_matrix_get(cov, 1, 1));
    f->B_err = sqrt(s2 * gsl_matrix_get(cov, 2, 2));
    f->D_err = sqrt(s2 * gsl_matrix_get(cov, 3, 3));
    return BKF_OK;
}

static double spread(double full, double err, double lower, double upper)
{
    return fmax(err, fmax(fabs(lower - full), fabs(upper - full)));
}

static int asymfit_correction_body(const double *mu, const double *R, size_t n, double p_lo,
                                   double p_hi, bkf_asymfit_large_result *result, bkf_error *err)
{
    if (!mu || !R || !result) return bkf_error_set(err, BKF_EINPUT, "NULL argument");
    if (n < 10 || n > BKF_ASYMFIT_MAX_POINTS)
        return bkf_error_set(err, BKF_EINPUT, "n = %zu points: need 10 to %u", n,
                             BKF_ASYMFIT_MAX_POINTS);
    if (!(p_lo > -1.0 && p_lo < p_hi && p_hi < 0.0))
        return bkf_error_set(err, BKF_EINPUT,
                             "p interval [%g, %g]: need -1 < p_lo < p_hi < 0", p_lo, p_hi);
    for (size_t i = 0; i < n; i++) {
        if (!(isfinite(mu[i]) && mu[i] > 0.0) || (i && !(mu[i] > mu[i - 1])))
            return bkf_error_set(err, BKF_EINPUT,
                                 "mu[%zu] = %g: mu must be positive, finite and increasing", i,
                                 mu[i]);
        if (!(isfinite(R[i]) && R[i] != 0.0))
            return bkf_error_set(err, BKF_EINPUT, "R[%zu] = %g: must be finite and nonzero",
                                 i, R[i]);
    }

    lsq q;
    int s = lsq_init(&q, n, err);
    if (s) return s;
    memset(result, 0, sizeof *result);
    result->npoints = n;

    /* Halves share the middle point when n is odd, so each has >= 5 points
     * and at least one degree of freedom for four parameters. */
    size_t half = (n + 1) / 2;
    corr_problem all = {mu, R, n, &q, 0, 0};
    corr_problem lower = {mu, R, half, &q, 0, 0};
    corr_problem upper = {mu + (n - half), R + (n - half), half, &q, 0, 0};
    corr_fit f, fl, fu, g, gl, gu;
    bkf_error e = {0};

    s = fit_free_p(&all, p_lo, p_hi, &f, err);
    if (!s && (s = fit_free_p(&lower, p_lo, p_hi, &fl, &e)))
        bkf_error_set(err, s, "lower half: %s", e.message);
    if (!s && (s = fit_free_p(&upper, p_lo, p_hi, &fu, &e)))
        bkf_error_set(err, s, "upper half: %s", e.message);
    if (!s) s = fit_fixed_p(&all, P_DERIVED, &g, err);
    if (!s) s = fit_fixed_p(&lower, P_DERIVED, &gl, err);
    if (!s) s = fit_fixed_p(&upper, P_DERIVED, &gu, err);
    lsq_free(&q);
    if (s) return s;

    result->A = f.A;
    result->p = f.p;
    result->B = f.B;
    result->D = f.D;
    result->A_err = spread(f.A, f.A_err, fl.A, fu.A);
    result->p_err = spread(f.p, f.p_err, fl.p, fu.p);
    result->B_err = spread(f.B, f.B_err, fl.B, fu.B);
    result->D_err = spread(f.D, f.D_err, fl.D, fu.D);
    result->rms_rel = f.rms_rel;
    result->A_fixed = g.A;
    result->B_fixed = g.B;
    result->D_fixed = g.D;
    result->A_fixed_err = spread(g.A, g.A_err, gl.A, gu.A);
    result->B_fixed_err = spread(g.B, g.B_err, gl.B, gu.B);
    result->D_fixed_err = spread(g.D, g.D_err, gl.D, gu.D);
    result->rms_rel_fixed = g.rms_rel;
    return BKF_OK;
}

int bkf_asymfit_correction(const double *mu, const double *R, size_t n, double p_lo,
                           double p_hi, bkf_asymfit_large_result *result, bkf_error *err)
{
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    int rc = asymfit_correction_body(mu, R, n, p_lo, p_hi, result, err);
    bkf_gsl_handler_pop(handler);
    return rc;
}

bkf_asymfit_large_options bkf_asymfit_large_options_default(void)
{
    return (bkf_asymfit_large_options){1e2, 1e4, 12, -0.9, -0.05};
}

static int asymfit_large_body(double nu, const bkf_asymfit_large_options *options,
                              bkf_asymfit_large_result *result, bkf_error *err)
{
    bkf_asymfit_large_options o = options ? *options : bkf_asymfit_large_options_default();
    if (!result) return bkf_error_set(err, BKF_EINPUT, "NULL result");
    int s = check_nu(nu, err);
    if (s) return s;
    if ((s = check_finite("mu_lo", o.mu_lo, err)) || (s = check_finite("mu_hi", o.mu_hi, err)))
        return s;
    if (!(o.mu_lo >= 1.0 && o.mu_lo < o.mu_hi && o.mu_hi <= BKF_CYCLE_MU_MAX))
        return bkf_error_set(err, BKF_EINPUT,
                             "mu range [%g, %g]: need 1 <= mu_lo < mu_hi <= %g (large-mu fit)",
                             o.mu_lo, o.mu_hi, BKF_CYCLE_MU_MAX);
    if (o.npoints < 10 || o.npoints > BKF_ASYMFIT_MAX_POINTS)
        return bkf_error_set(err, BKF_EINPUT, "npoints = %zu: need 10 to %u", o.npoints,
                             BKF_ASYMFIT_MAX_POINTS);
    if (!(o.p_lo > -1.0 && o.p_lo < o.p_hi && o.p_hi < 0.0))
        return bkf_error_set(err, BKF_EINPUT,
                             "p interval [%g, %g]: need -1 < p_lo < p_hi < 0", o.p_lo, o.p_hi);

    size_t n = o.npoints;
    double *mu = malloc(2 * n * sizeof *mu);
    if (!mu) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    double *R = mu + n;
    solver sv;
    if ((s = solver_init(&sv, err))) {
        free(mu);
        return s;
    }
    log_space(o.mu_lo, o.mu_hi, n, mu);
    double k = bkf_asym_k(nu);
    for (size_t i = 0; !s && i < n; i++) {
        double T, T_err;
        s = solve_period(&sv, mu[i], nu, &T, &T_err, err);
        R[i] = T - k * mu[i];
    }
    if (!s) {
        bkf_error e = {0};
        s = bkf_asymfit_correction(mu, R, n, o.p_lo, o.p_hi, result, &e);
        if (s) bkf_error_set(err, s, "large-mu fit at nu = %.15g: %s", nu, e.message);
    }
    if (!s) {
        result->nu = nu;
        result->A_derived = bkf_asym_knee_coefficient(nu);
        result->p_derived = P_DERIVED;
        result->B_derived = bkf_asym_log_coefficient(nu);
        result->T_rel_err_max = sv.rel_err_max;
        result->solves = sv.solves;
    }
    solver_free(&sv);
    free(mu);
    return s;
}

int bkf_asymfit_large(double nu, const bkf_asymfit_large_options *options,
                      bkf_asymfit_large_result *result, bkf_error *err)
{
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    int rc = asymfit_large_body(nu, options, result, err);
    bkf_gsl_handler_pop(handler);
    return rc;
}

/* ---- the small-mu fit ---------------------------------------------------- */

bkf_asymfit_small_options bkf_asymfit_small_options_default(void)
{
    return (bkf_asymfit_small_options){1e-3, 0.1, 12};
}

/* y = s + s4 mu^2 on rows [first, first + n), unweighted: the scaled
 * quantity y = (T/2pi - 1)/mu^2 carries its truncation error O(mu^4) at the
 * top of the range and its round-off O(eps/mu^2) at the bottom, both well
 * below 1e-6 relative on the default range, so no row needs to dominate. */
static int fit_small_rows(lsq *q, const double *mu, const double *y, size_t first, size_t n,
                          double c[2], double c_err[2], double *rms)
{
    int s = lsq_prepare(q, n, 2);
    if (s) return s;
    for (size_t i = 0; i < n; i++) {
        gsl_matrix_set(q->X[2], i, 0, 1.0);
        gsl_matrix_set(q->X[2], i, 1, mu[first + i] * mu[first + i]);
        gsl_vector_set(q->y, i, y[first + i]);
        gsl_vector_set(q->w, i, 1.0);
    }
    double chi2;
    if ((s = lsq_solve(q, n, 2, &chi2))) return s;
    double s2 = n > 2 ? chi2 / (double)(n - 2) : 0.0;
    for (size_t j = 0; j < 2; j++) {
        c[j] = gsl_vector_get(q->c[2], j);
        c_err[j] = sqrt(s2 * gsl_matrix_get(q->cov[2], j, j));
    }
    *rms = sqrt(chi2 / (double)n);
    return GSL_SUCCESS;
}

static int asymfit_small_body(double nu, const bkf_asymfit_small_options *options,
                              bkf_asymfit_small_result *result, bkf_error *err)
{
    bkf_asymfit_small_options o = options ? *options : bkf_asymfit_small_options_default();
    if (!result) return bkf_error_set(err, BKF_EINPUT, "NULL result");
    int s = check_nu(nu, err);
    if (s) return s;
    if ((s = check_finite("mu_lo", o.mu_lo, err)) || (s = check_finite("mu_hi", o.mu_hi, err)))
        return s;
    if (!(o.mu_lo >= BKF_CYCLE_MU_MIN && o.mu_lo < o.mu_hi && o.mu_hi <= 1.0))
        return bkf_error_set(err, BKF_EINPUT,
                             "mu range [%g, %g]: need %g <= mu_lo < mu_hi <= 1 (small-mu fit)",
                             o.mu_lo, o.mu_hi, BKF_CYCLE_MU_MIN);
    if (o.npoints < 6 || o.npoints > BKF_ASYMFIT_MAX_POINTS)
        return bkf_error_set(err, BKF_EINPUT, "npoints = %zu: need 6 to %u", o.npoints,
                             BKF_ASYMFIT_MAX_POINTS);

    size_t n = o.npoints;
    double *mu = malloc(2 * n * sizeof *mu);
    if (!mu) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    double *y = mu + n;
    solver sv;
    lsq q;
    if ((s = solver_init(&sv, err))) {
        free(mu);
        return s;
    }
    if ((s = lsq_init(&q, n, err))) {
        solver_free(&sv);
        free(mu);
        return s;
    }
    log_space(o.mu_lo, o.mu_hi, n, mu);
    for (size_t i = 0; !s && i < n; i++) {
        double T, T_err;
        s = solve_period(&sv, mu[i], nu, &T, &T_err, err);
        y[i] = (T / (2.0 * M_PI) - 1.0) / (mu[i] * mu[i]);
    }
    if (!s) {
        size_t half = (n + 1) / 2;
        double c[2], ce[2], cl[2], cle[2], cu[2], cue[2], rms, unused;
        int g = fit_small_rows(&q, mu, y, 0, n, c, ce, &rms);
        if (!g) g = fit_small_rows(&q, mu, y, 0, half, cl, cle, &unused);
        if (!g) g = fit_small_rows(&q, mu, y, n - half, half, cu, cue, &unused);
        if (g)
            s = bkf_error_set(err, BKF_ENUMERIC, "small-mu least squares at nu = %.15g failed: %s",
                              nu, gsl_strerror(g));
        else {
            memset(result, 0, sizeof *result);
            result->nu = nu;
            result->npoints = n;
            result->s = c[0];
            result->s4 = c[1];
            result->s_err = spread(c[0], ce[0], cl[0], cu[0]);
            result->s4_err = spread(c[1], ce[1], cl[1], cu[1]);
            result->s_derived = bkf_asym_small_coefficient(nu);
            result->rms = rms;
            result->T_rel_err_max = sv.rel_err_max;
            result->solves = sv.solves;
        }
    }
    lsq_free(&q);
    solver_free(&sv);
    free(mu);
    return s;
}

int bkf_asymfit_small(double nu, const bkf_asymfit_small_options *options,
                      bkf_asymfit_small_result *result, bkf_error *err)
{
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    int rc = asymfit_small_body(nu, options, result, err);
    bkf_gsl_handler_pop(handler);
    return rc;
}

/* ---- formulas, grid, validity map ---------------------------------------- */

const char *bkf_asymfit_formula_name(bkf_asymfit_formula formula)
{
    switch (formula) {
    case BKF_ASYMFIT_LEADING: return "leading";
    case BKF_ASYMFIT_CORRECTED: return "corrected";
    case BKF_ASYMFIT_SMALL: return "small";
    }
    return NULL;
}

double bkf_asymfit_formula_period(bkf_asymfit_formula formula, double mu, double nu)
{
    switch (formula) {
    case BKF_ASYMFIT_LEADING: return bkf_asym_period_leading(mu, nu);
    case BKF_ASYMFIT_CORRECTED: return bkf_asym_period_large(mu, nu);
    case BKF_ASYMFIT_SMALL: return bkf_asym_period_small(mu, nu);
    }
    return NAN;
}

const char *bkf_asymfit_extent_name(bkf_asymfit_extent extent)
{
    switch (extent) {
    case BKF_ASYMFIT_CROSSING: return "crossing";
    case BKF_ASYMFIT_EVERYWHERE: return "everywhere";
    case BKF_ASYMFIT_NOWHERE: return "nowhere";
    }
    return NULL;
}

static double rel_err(bkf_asymfit_formula f, double mu, double nu, double T)
{
    return fabs(bkf_asymfit_formula_period(f, mu, nu) - T) / T;
}

static int check_mu_value(const char *name, double mu, bkf_error *err)
{
    if (!(mu >= BKF_CYCLE_MU_MIN && mu <= BKF_CYCLE_MU_MAX))
        return bkf_error_set(err, BKF_EINPUT, "%s = %g is outside [%g, %g]", name, mu,
                             BKF_CYCLE_MU_MIN, BKF_CYCLE_MU_MAX);
    return BKF_OK;
}

static int asymfit_grid_body(const double *mu, size_t nmu, const double *nu, size_t nnu,
                             bkf_asymfit_grid_point *out, bkf_error *err)
{
    if (!mu || !nu || !out) return bkf_error_set(err, BKF_EINPUT, "NULL argument");
    if (nmu == 0 || nnu == 0 || nmu > 1000000u / nnu)
        return bkf_error_set(err, BKF_EINPUT, "grid of %zu x %zu points: need 1 to 1e6 points",
                             nmu, nnu);
    int s;
    for (size_t i = 0; i < nmu; i++)
        if ((s = check_mu_value("mu", mu[i], err))) return s;
    for (size_t j = 0; j < nnu; j++)
        if ((s = check_nu(nu[j], err))) return s;
    solver sv;
    if ((s = solver_init(&sv, err))) return s;
    for (size_t j = 0; !s && j < nnu; j++)
        for (size_t i = 0; !s && i < nmu; i++) {
            bkf_asymfit_grid_point *pt = &out[j * nmu + i];
            pt->mu = mu[i];
            pt->nu = nu[j];
            s = solve_period(&sv, mu[i], nu[j], &pt->T, &pt->T_err, err);
            for (int f = 0; !s && f < BKF_ASYMFIT_NFORMULAS; f++)
                pt->rel_err[f] = rel_err((bkf_asymfit_formula)f, mu[i], nu[j], pt->T);
        }
    solver_free(&sv);
    return s;
}

int bkf_asymfit_grid(const double *mu, size_t nmu, const double *nu, size_t nnu,
                     bkf_asymfit_grid_point *out, bkf_error *err)
{
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    int rc = asymfit_grid_body(mu, nmu, nu, nnu, out, err);
    bkf_gsl_handler_pop(handler);
    return rc;
}

bkf_asymfit_map_options bkf_asymfit_map_options_default(void)
{
    return (bkf_asymfit_map_options){1e-3, 1e4, 8, 1.02};
}

/* Bisection in ln mu between a point where the formula fails and one where
 * it holds, until their ratio is within refine_ratio. */
static int refine(solver *sv, bkf_asymfit_formula f, double eps, double nu, double ratio,
                  double *hold, double *fail, bkf_error *err)
{
    while (fmax(*hold / *fail, *fail / *hold) > ratio) {
        double mid = sqrt(*hold * *fail), T, T_err;
        int s = solve_period(sv, mid, nu, &T, &T_err, err);
        if (s) return s;
        if (rel_err(f, mid, nu, T) <= eps)
            *hold = mid;
        else
            *fail = mid;
    }
    return BKF_OK;
}

static int asymfit_map_body(const double *nu, size_t nnu, const double *eps, size_t neps,
                            const bkf_asymfit_map_options *options, bkf_asymfit_boundary *out,
                            bkf_error *err)
{
    bkf_asymfit_map_options o = options ? *options : bkf_asymfit_map_options_default();
    if (!nu || !eps || !out) return bkf_error_set(err, BKF_EINPUT, "NULL argument");
    if (nnu == 0 || neps == 0 || nnu > BKF_ASYMFIT_MAX_POINTS || neps > BKF_ASYMFIT_MAX_POINTS)
        return bkf_error_set(err, BKF_EINPUT, "%zu nu and %zu eps values: need 1 to %u of each",
                             nnu, neps, BKF_ASYMFIT_MAX_POINTS);
    int s;
    for (size_t j = 0; j < nnu; j++)
        if ((s = check_nu(nu[j], err))) return s;
    for (size_t k = 0; k < neps; k++)
        if (!(eps[k] >= 1e-10 && eps[k] < 1.0))
            return bkf_error_set(err, BKF_EINPUT,
                                 "eps = %g: the relative-error threshold must be in [1e-10, 1) "
                                 "(below 1e-10 the numerical T is not accurate enough to judge)",
                                 eps[k]);
    if ((s = check_mu_value("mu_lo", o.mu_lo, err)) || (s = check_mu_value("mu_hi", o.mu_hi, err)))
        return s;
    if (!(o.mu_lo < o.mu_hi))
        return bkf_error_set(err, BKF_EINPUT, "mu range [%g, %g]: need mu_lo < mu_hi", o.mu_lo,
                             o.mu_hi);
    if (o.per_decade < 2 || o.per_decade > 1000)
        return bkf_error_set(err, BKF_EINPUT, "per_decade = %zu: need 2 to 1000", o.per_decade);
    if (!(o.refine_ratio > 1.0 && o.refine_ratio <= 2.0))
        return bkf_error_set(err, BKF_EINPUT, "refine_ratio = %g: need (1, 2]", o.refine_ratio);

    size_t m = (size_t)ceil(log10(o.mu_hi / o.mu_lo) * (double)o.per_decade - 1e-9) + 1;
    if (m < 2) m = 2;
    double *mu = malloc(2 * m * sizeof *mu);
    if (!mu) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    double *T = mu + m;
    solver sv;
    if ((s = solver_init(&sv, err))) {
        free(mu);
        return s;
    }
    log_space(o.mu_lo, o.mu_hi, m, mu);

    for (size_t j = 0; !s && j < nnu; j++) {
        for (size_t i = 0; !s && i < m; i++) {
            double T_err;
            s = solve_period(&sv, mu[i], nu[j], &T[i], &T_err, err);
        }
        for (int f = 0; !s && f < BKF_ASYMFIT_NFORMULAS; f++)
            for (size_t k = 0; !s && k < neps; k++) {
                bkf_asymfit_boundary *b = &out[(j * BKF_ASYMFIT_NFORMULAS + (size_t)f) * neps + k];
                bkf_asymfit_formula form = (bkf_asymfit_formula)f;
                b->formula = form;
                b->eps = eps[k];
                b->nu = nu[j];
                b->mu_boundary = b->mu_fail = NAN;
                /* Walk in from the end where the formula is meant to hold;
                 * the first failure ends the run of good points. */
                int large = form != BKF_ASYMFIT_SMALL;
                size_t good = 0;
                while (good < m) {
                    size_t i = large ? m - 1 - good : good;
                    if (!(rel_err(form, mu[i], nu[j], T[i]) <= eps[k])) break;
                    good++;
                }
                if (good == 0)
                    b->extent = BKF_ASYMFIT_NOWHERE;
                else if (good == m) {
                    b->extent = BKF_ASYMFIT_EVERYWHERE;
                    b->mu_boundary = large ? mu[0] : mu[m - 1];
                } else {
                    b->extent = BKF_ASYMFIT_CROSSING;
                    double hold = large ? mu[m - good] : mu[good - 1];
                    double fail = large ? mu[m - good - 1] : mu[good];
                    s = refine(&sv, form, eps[k], nu[j], o.refine_ratio, &hold, &fail, err);
                    b->mu_boundary = hold;
                    b->mu_fail = fail;
                }
            }
    }
    solver_free(&sv);
    free(mu);
    return s;
}

int bkf_asymfit_map(const double *nu, size_t nnu, const double *eps, size_t neps,
                    const bkf_asymfit_map_options *options, bkf_asymfit_boundary *out,
                    bkf_error *err)
{
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    int rc = asymfit_map_body(nu, nnu, eps, neps, options, out, err);
    bkf_gsl_handler_pop(handler);
    return rc;
}

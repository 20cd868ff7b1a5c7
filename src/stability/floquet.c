/* Floquet stability of the global oscillations (floquet.h).
 *
 * Per wavenumber the cycle and the 2x2 fundamental matrix are integrated
 * together (7 components: x, y, M, L), in plain Lienard coordinates with
 * mu = gamma, from the cycle's section point over exactly the cycle's period.
 * Integrating the cycle again rather than storing it costs two components
 * and keeps psi*(t) as accurate as the integration itself, with no
 * interpolation error (GSL steppers have no dense output).  When the
 * derivative with respect to K = 1 + c^2 q^2 is wanted (long-wave
 * coefficient, continuation), dM/dK rides along (4 more components).
 *
 * Peaks of lambda over K are peaks of s * trace(M), s the sign of the
 * trace there: lambda is a monotone function of |trace| where the
 * multipliers are real and flat (L/2) where they are complex, so the trace
 * is the smooth function to maximise.  Instability boundaries in nu are
 * zeros of an indicator that is continuous in nu: the long-wave coefficient,
 * or the height of one tracked peak of lambda. */
#include "bkfront/floquet.h"

#include "floquet_internal.h"

#include "bkfront/continuation.h"
#include "bkfront/model.h"

#include <float.h>
#include <gsl/gsl_errno.h>
#include <gsl/gsl_odeiv2.h>
#include <math.h>
#include <nlopt.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------ the flow */

static double lienard_F(double x) { return x * x * x / 3.0 - x; }

static int lin_rhs(double t, const double s[], double ds[], void *params, size_t dim)
{
    (void)t;
    lin_params *p = params;
    double g = p->gamma, x = s[IX], damp = g * (x * x - 1.0);
    p->rhs_calls++;
    ds[IX] = g * (s[IY] - lienard_F(x));
    ds[IY] = (p->nu - x) / g;
    for (int j = 0; j < 2; j++) {
        double u = s[IM + 2 * j], e = s[IM + 2 * j + 1];
        ds[IM + 2 * j] = g * e - damp * u;
        ds[IM + 2 * j + 1] = -p->K * u / g;
    }
    ds[IL] = -damp;
    if (dim == DIM_DK)
        for (int j = 0; j < 2; j++) {
            double pu = s[IP + 2 * j], pe = s[IP + 2 * j + 1];
            ds[IP + 2 * j] = g * pe - damp * pu;
            ds[IP + 2 * j + 1] = -(p->K * pu + s[IM + 2 * j]) / g;
        }
    return GSL_SUCCESS;
}

/* Zeroes J (n x n) and dfdt, then fills the cycle's own block: the
 * Lienard-plane flow at (x, y) = (s[ix], s[iy]) of every system here. */
static void jacobian_of_cycle(double *J, double *dfdt, size_t n, size_t ix, size_t iy,
                              double damp, double g)
{
    memset(J, 0, sizeof(double) * n * n);
    memset(dfdt, 0, sizeof(double) * n);
    J[ix * n + ix] = -damp;
    J[ix * n + iy] = g;
    J[iy * n + ix] = -1.0 / g;
}

static int lin_jac(double t, const double s[], double *J, double dfdt[], void *params, size_t dim)
{
    (void)t;
    lin_params *p = params;
    double g = p->gamma, x = s[IX], damp = g * (x * x - 1.0), ddamp = 2.0 * g * x;
    size_t n = dim;
    jacobian_of_cycle(J, dfdt, n, IX, IY, damp, g);
    for (int j = 0; j < 2; j++) {
        size_t iu = IM + 2 * j, ie = iu + 1;
        J[iu * n + IX] = -ddamp * s[iu];
        J[iu * n + iu] = -damp;
        J[iu * n + ie] = g;
        J[ie * n + iu] = -p->K / g;
    }
    J[IL * n + IX] = -ddamp;
    if (dim == DIM_DK)
        for (int j = 0; j < 2; j++) {
            size_t iu = IP + 2 * j, ie = iu + 1;
            J[iu * n + IX] = -ddamp * s[iu];
            J[iu * n + iu] = -damp;
            J[iu * n + ie] = g;
            J[ie * n + iu] = -p->K / g;
            J[ie * n + IM + 2 * j] = -1.0 / g;
        }
    return GSL_SUCCESS;
}

static int rhs_plain(double t, const double s[], double ds[], void *p) { return lin_rhs(t, s, ds, p, DIM_PLAIN); }
static int rhs_dk(double t, const double s[], double ds[], void *p) { return lin_rhs(t, s, ds, p, DIM_DK); }
static int jac_plain(double t, const double s[], double *J, double d[], void *p) { return lin_jac(t, s, J, d, p, DIM_PLAIN); }
static int jac_dk(double t, const double s[], double *J, double d[], void *p) { return lin_jac(t, s, J, d, p, DIM_DK); }

/* ------------------------------------------------------------- object */

bkf_floquet_options bkf_floquet_options_default(void)
{
    return (bkf_floquet_options){.tol = 1e-10,
                                 .stepper = BKF_STEPPER_AUTO,
                                 .p_max = 6.0,
                                 .scan_points = 120,
                                 .nu_step = 0.01,
                                 .nu_edge = 1e-3};
}

const char *bkf_floquet_kind_name(bkf_floquet_kind kind)
{
    switch (kind) {
    case BKF_FLOQUET_REAL_POSITIVE: return "real_positive";
    case BKF_FLOQUET_REAL_NEGATIVE: return "real_negative";
    case BKF_FLOQUET_COMPLEX: return "complex";
    }
    return "?";
}

const char *bkf_floquet_boundary_name(bkf_floquet_boundary kind)
{
    switch (kind) {
    case BKF_BOUNDARY_PERIOD_DOUBLING: return "period_doubling";
    case BKF_BOUNDARY_LONG_WAVE: return "long_wave";
    case BKF_BOUNDARY_OTHER: return "other";
    case BKF_BOUNDARY_SCAN_END: return "scan_end";
    case BKF_BOUNDARY_NONE: return "none";
    }
    return "?";
}

bkf_floquet *bkf_floquet_alloc(void)
{
    bkf_floquet *f = calloc(1, sizeof *f);
    if (!f) return NULL;
    f->cycle = bkf_cycle_alloc();
    if (!f->cycle) {
        free(f);
        return NULL;
    }
    return f;
}

static void engines_free(bkf_floquet *f)
{
    for (int d = 0; d < 2; d++) {
        for (int k = 0; k < ENG_SLOTS; k++) {
            if (f->eng[d][k].driver) gsl_odeiv2_driver_free(f->eng[d][k].driver);
            f->eng[d][k].driver = NULL;
        }
    }
    for (int k = 0; k < 2; k++) {
        if (f->eng_log[k].driver) gsl_odeiv2_driver_free(f->eng_log[k].driver);
        f->eng_log[k].driver = NULL;
    }
}

void bkf_floquet_free(bkf_floquet *f)
{
    if (!f) return;
    engines_free(f);
    bkf_cycle_free(f->cycle);
    free(f);
}

const bkf_cycle_result *bkf_floquet_cycle(const bkf_floquet *f)
{
    return f && f->ready ? bkf_cycle_get(f->cycle) : NULL;
}

int floquet_check_options(const bkf_floquet_options *o, bkf_error *err)
{
    int rc = bkf_model_check_tol(o->tol, err);
    if (rc != BKF_OK) return rc;
    if (o->stepper != BKF_STEPPER_AUTO && o->stepper != BKF_STEPPER_EXPLICIT &&
        o->stepper != BKF_STEPPER_IMPLICIT && o->stepper != BKF_STEPPER_EXTRAPOLATION)
        return bkf_error_set(err, BKF_EINPUT,
                             "stepper must be auto, explicit, implicit or extrapolation");
    if (!isfinite(o->p_max) || o->p_max <= 0.0 || o->p_max > 1e4)
        return bkf_error_set(err, BKF_EINPUT, "p_max = %g must be in (0, 1e4]", o->p_max);
    if (o->scan_points < 4 || o->scan_points > 100000)
        return bkf_error_set(err, BKF_EINPUT, "scan_points = %zu must be in [4, 100000]",
                             o->scan_points);
    if (!isfinite(o->nu_step) || o->nu_step <= 0.0 || o->nu_step > 1.0)
        return bkf_error_set(err, BKF_EINPUT, "nu_step = %g must be in (0, 1]", o->nu_step);
    if (!isfinite(o->nu_edge) || o->nu_edge <= 0.0 || o->nu_edge >= 0.5)
        return bkf_error_set(err, BKF_EINPUT, "nu_edge = %g must be in (0, 0.5)", o->nu_edge);
    return BKF_OK;
}

int floquet_check_gamma_c(double gamma, double c, bkf_error *err)
{
    if (!isfinite(gamma) || gamma < BKF_CYCLE_MU_MIN || gamma > BKF_CYCLE_MU_MAX)
        return bkf_error_set(err, BKF_EINPUT, "gamma = %.15g is outside [%g, %g]", gamma,
                             BKF_CYCLE_MU_MIN, BKF_CYCLE_MU_MAX);
    return bkf_model_check_c(c, err);
}

static int engine_get(bkf_floquet *f, int dk, int which, engine **out)
{
    double tol = which == ENG_SCAN ? fmax(SCAN_TOL, f->tol_int)
                 : which == ENG_COARSE ? f->tol_int
                 : which == ENG_FINE ? f->tol_int / TOL_RATIO
                 : which == ENG_RETRY_COARSE ? f->tol_retry
                                             : f->tol_retry / TOL_RATIO;
    engine *e = &f->eng[dk][which];
    if (!e->driver || e->tol != tol) {
        if (e->driver) gsl_odeiv2_driver_free(e->driver);
        e->system = dk ? (gsl_odeiv2_system){rhs_dk, jac_dk, DIM_DK, &f->lp}
                       : (gsl_odeiv2_system){rhs_plain, jac_plain, DIM_PLAIN, &f->lp};
        const gsl_odeiv2_step_type *type =
            f->kind == BKF_STEPPER_IMPLICIT ? gsl_odeiv2_step_bsimp : gsl_odeiv2_step_rk8pd;
        e->driver = gsl_odeiv2_driver_alloc_standard_new(&e->system, type, 1e-2, tol, tol, 1.0, 0.0);
        if (!e->driver) return BKF_ENOMEM;
        e->tol = tol;
    }
    gsl_odeiv2_driver_set_nmax(e->driver, which >= ENG_RETRY_COARSE ? f->retry_nmax : MAX_STEPS);
    *out = e;
    return BKF_OK;
}

/* The cycle at co, and where the engine refuses it, again cold, then 10
 * times looser each time, at most `retries` times; co is left as solved.
 * Why: near the canard (large gamma, |nu| -> 1) a warm start from across
 * an explosion (the small and the relaxation cycle nu-close) can fail and
 * a tight tolerance be refused, while a looser cycle is still usable: its
 * T_err enters lambda_err. */
static int solve_backing_off(bkf_cycle *cycle, double gamma, double nu, bkf_cycle_options *co, int retries,
                             bkf_error *err)
{
    int rc = bkf_cycle_solve(cycle, gamma, nu, co, err);
    for (int attempt = 0; bkf_status_is_numerical(rc) && attempt < retries; attempt++) {
        if (co->warm_start) co->warm_start = 0;
        else if (co->tol < 0.01) co->tol *= 10.0;
        else break;
        rc = bkf_cycle_solve(cycle, gamma, nu, co, err);
    }
    return rc;
}

static int floquet_set_body(bkf_floquet *f, double gamma, double c, double nu,
                            const bkf_floquet_options *options, bkf_error *err)
{
    if (!f) return bkf_error_set(err, BKF_EINPUT, "floquet object is NULL");
    bkf_floquet_options o = options ? *options : bkf_floquet_options_default();
    int rc = floquet_check_options(&o, err);
    if (rc == BKF_OK) rc = floquet_check_gamma_c(gamma, c, err);
    if (rc == BKF_OK) rc = bkf_model_check_nu_active(nu, err);
    if (rc != BKF_OK) return rc;
    f->ready = 0;
    f->cycle_gen++;
    bkf_cycle_options co = bkf_cycle_options_default();
    /* the cycle's error moves lambda by |A| T_err and more through the start
     * point (measured ~20 |A| T_err at gamma 2): keep the cycle two orders
     * tighter than lambda, which costs little (one solve per nu) */
    co.tol = fmax(0.01 * o.tol, 1e-13);
    co.stepper = o.stepper;
    co.warm_start = 1;
    rc = solve_backing_off(f->cycle, gamma, nu, &co, 3, err);
    if (rc != BKF_OK) return rc;
    f->cycle_opt = co;
    f->refused_tol = 0.0;
    const bkf_cycle_result *r = bkf_cycle_get(f->cycle);
    f->gamma = gamma;
    f->c = c;
    f->nu = nu;
    f->opt = o;
    f->x0 = nu;
    f->y0 = r->section_slope / gamma + lienard_F(nu);
    f->T = r->period;
    f->T_err = r->period_err;
    f->L = r->log_multiplier;
    f->lp = (lin_params){gamma, nu, 1.0, 0};
    bkf_stepper_kind kind = o.stepper;
    if (kind == BKF_STEPPER_AUTO) kind = gamma > STIFF_GAMMA ? BKF_STEPPER_IMPLICIT : BKF_STEPPER_EXPLICIT;
    /* bd2x2 integrates the cycle's own states only (cycle.c): the cycle
     * above was solved with it, the monodromy's 2x2 and log systems take
     * the other stiff stepper, as under auto. */
    if (kind == BKF_STEPPER_EXTRAPOLATION) kind = BKF_STEPPER_IMPLICIT;
    /* below these local tolerances the steppers only accumulate rounding */
    double floor_tol = kind == BKF_STEPPER_IMPLICIT ? 1e-14 : 1e-16;
    double tol_int = fmax(0.1 * o.tol, floor_tol * TOL_RATIO);
    if (kind != f->kind || tol_int != f->tol_int) engines_free(f);
    f->kind = kind;
    f->tol_int = tol_int;
    f->tol_floor = floor_tol * TOL_RATIO;
    f->ready = 1;
    return BKF_OK;
}

int bkf_floquet_set(bkf_floquet *f, double gamma, double c, double nu,
                    const bkf_floquet_options *options, bkf_error *err)
{
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    int rc = floquet_set_body(f, gamma, c, nu, options, err);
    bkf_gsl_handler_pop(handler);
    return rc;
}

/* ------------------------------------------------------------ monodromy */

static double k2_of(const bkf_floquet *f, double q) { return 1.0 + f->c * f->c * q * q; }

int floquet_integrate(bkf_floquet *f, double K, int dk, int which, raw *out, bkf_error *err)
{
    engine *e;
    if (engine_get(f, dk, which, &e) != BKF_OK) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    double s[DIM_DK] = {f->x0, f->y0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0};
    double t = 0.0;
    f->lp.K = K;
    gsl_odeiv2_driver_reset(e->driver);
    int rc = gsl_odeiv2_driver_apply(e->driver, &t, f->T, s);
    if (rc != GSL_SUCCESS || !isfinite(s[IM]) || !isfinite(s[IM + 3]))
        return bkf_error_set(err, BKF_ENUMERIC,
                             "monodromy at gamma = %.15g, nu = %.15g, K = %.15g: integration failed at t = %g "
                             "(%s)",
                             f->gamma, f->nu, K, t, rc != GSL_SUCCESS ? gsl_strerror(rc) : "non-finite state");
    out->M[0] = s[IM];
    out->M[1] = s[IM + 2];
    out->M[2] = s[IM + 1];
    out->M[3] = s[IM + 3];
    out->tr = s[IM] + s[IM + 3];
    out->L = s[IL];
    out->det = s[IM] * s[IM + 3] - s[IM + 2] * s[IM + 1];
    out->dtr = dk ? s[IP] + s[IP + 3] : NAN;
    out->steps = e->driver->n;
    return BKF_OK;
}

/* Eigenvalues of a real 2x2 M = e^s Mt from the trace of Mt and ln det M.
 * The determinant is Liouville's, exact where the matrix's own would cancel
 * (det ~ 1e-50 from entries of order 1), and the small multiplier is
 * det/m1.  lambda comes from logs, so it stays right when m1 itself
 * underflows (the log-column integration reaches lambda ~ -2e4). */
mults floquet_multipliers_scaled(double trt, double L, double s)
{
    mults m = {0};
    double Dt = exp(L - 2.0 * s), half = 0.5 * trt, disc = half * half - Dt;
    if (disc >= 0.0) {
        double r = sqrt(disc);
        double m1t = half >= 0.0 ? half + r : half - r;
        double sign = m1t >= 0.0 ? 1.0 : -1.0;
        double l1 = m1t != 0.0 ? s + log(fabs(m1t)) : 0.5 * L;
        m.m1_re = sign * exp(l1);
        m.m2_re = sign * exp(L - l1);
        m.lambda = l1;
        m.m1_abs_scaled = fabs(m1t);
        m.kind = m1t >= 0.0 ? BKF_FLOQUET_REAL_POSITIVE : BKF_FLOQUET_REAL_NEGATIVE;
    } else {
        double im = sqrt(-disc), es = exp(s);
        m.m1_re = m.m2_re = half * es;
        m.m1_im = im * es;
        m.m2_im = -im * es;
        m.lambda = 0.5 * L;
        m.m1_abs_scaled = sqrt(Dt);
        m.kind = BKF_FLOQUET_COMPLEX;
    }
    return m;
}

/* How far lambda may move with the cycle's own error: the end time moves
 * M by A(0) M dT; the start point's error, of the same order in the cycle's
 * accuracy, was measured to move it up to ~20 times more (gamma 2, nu
 * -0.94, cycle tol 1e-7), hence the factor.  normM_rel is |M|/|m1|. */
static double norm_A(const bkf_floquet *f, double K)
{
    double g = f->gamma;
    return g * fabs(f->nu * f->nu - 1.0) + g + (1.0 + K) / g;
}

static double cycle_term(const bkf_floquet *f, double K, double normM_rel)
{
    /* in the plain coordinates, where the factor 30 was measured: with the
     * balanced norm (coupling sqrt(K) both ways) m1_err came out 4 times
     * optimistic at gamma 2, nu -0.94, tol 1e-6.  Where this bound is far
     * too large (gamma 1e-2: it grows as (1 + K)/gamma), the retries of
     * bkf_floquet_eval measure the cycle's share instead. */
    return 30.0 * f->T_err * norm_A(f, K) * fmax(1.0, normM_rel);
}

/* The error terms common to both integrations of M: a and b are the
 * multipliers at the coarse and fine tolerance, tr_a, tr_b the traces of
 * e^-s M, normM = |e^-s M| (as integrated), normM_bal its balanced norm,
 * tl the coarse tolerance.  Returns lambda_err; *m_floor_out is the
 * absolute floor on m1 / e^s. */
static double lambda_error(const bkf_floquet *f, double K, const mults *ma, const mults *mb,
                           double tr_a, double tr_b, double L, double s, double normM,
                           double normM_bal, double tl, double *m_floor_out, double *cyc_out)
{
    double m1t = mb->m1_abs_scaled;
    double cyc = cycle_term(f, K, m1t > 0.0 ? normM_bal / m1t : INFINITY);
    /* An absolute floor: m1 comes from the trace of M, whose entries carry
     * an error of about the integration tolerance times their size whatever
     * the two integrations' difference says.  Where |m1| << |M| (lambda < -8,
     * |m1| < 3e-4) the difference alone was up to 70 times optimistic at tol
     * 1e-6; the coarse tolerance (10 times the fine one) times |M| is the
     * floor on m1, and lambda = ln|m1| inherits it divided by |m1|. */
    double m_floor = tl * normM;
    /* not capped: once m_floor reaches |m1| the computed m1 may be noise
     * and lambda is bounded only from above (a cap at 1 was optimistic by
     * up to 2e3 at gamma 100, c q 100, where |m1| ~ exp(-1.4e4)) */
    double lambda_floor = m1t > 0.0 ? m_floor / m1t : INFINITY;
    /* Near a double multiplier (tr^2 = 4 exp(L): the Hopf point, or where
     * the pair turns complex) m1 = tr/2 + sqrt(tr^2/4 - exp(L)) turns an
     * error e of the discriminant into sqrt(e), and the two integrations can
     * agree with each other far better than with the truth (gamma 0.3, nu
     * 0.9999, q 0, tol 1e-4: error 3.7e-4 against an estimate of 5.5e-5).
     * Bound the square root's response to the trace's error directly. */
    double cond_term = 0.0;
    if (mb->kind != BKF_FLOQUET_COMPLEX && m1t > 0.0) {
        double half = 0.5 * tr_b, disc = fabs(half * half - exp(L - 2.0 * s));
        double d_tr = fabs(tr_a - tr_b) + 2.0 * m_floor;
        double e = fabs(half) * d_tr + 0.25 * d_tr * d_tr;
        double d_root = disc > 0.0 ? fmin(sqrt(e), e / (2.0 * sqrt(disc))) : sqrt(e);
        cond_term = (0.5 * d_tr + d_root) / m1t;
    }
    *m_floor_out = m_floor;
    *cyc_out = cyc;
    /* For real multipliers cond_term already carries the floor (2 m_floor
     * in the trace's error, divided by |m1| and more near a double root):
     * adding lambda_floor too counted it three times, and half the rows of
     * the paper's dispersion at tol 1e-10 then went to a retry. */
    return fabs(ma->lambda - mb->lambda) + cyc +
           (mb->kind != BKF_FLOQUET_COMPLEX && m1t > 0.0 ? cond_term : lambda_floor) +
           4.0 * DBL_EPSILON * fabs(mb->lambda);
}

static void fill_point(bkf_floquet_point *pt, double K, const bkf_floquet *f, const mults *mb)
{
    memset(pt, 0, sizeof *pt);
    pt->k2 = K;
    pt->q = f->c > 0.0 ? sqrt(fmax(K - 1.0, 0.0)) / f->c : 0.0;
    pt->m1_re = mb->m1_re;
    pt->m1_im = mb->m1_im;
    pt->m2_re = mb->m2_re;
    pt->m2_im = mb->m2_im;
    pt->lambda = mb->lambda;
    pt->kind = mb->kind;
}

/* M integrated as it stands (the usual route): slots coarse and fine of
 * the usual or of the retry tolerance. */
static int eval_trace(bkf_floquet *f, double K, int retry, bkf_floquet_point *pt, double *cyc,
                      bkf_error *err)
{
    raw a, b;
    double tl = retry ? f->tol_retry : f->tol_int;
    int rc = BKF_OK;
    if (f->last_fine_key.valid && f->last_fine_key.K == K && f->last_fine_key.tol == tl &&
        f->last_fine_key.cycle_gen == f->cycle_gen) {
        a = f->last_fine;
        a.steps = 0;
    } else {
        rc = floquet_integrate(f, K, 0, retry ? ENG_RETRY_COARSE : ENG_COARSE, &a, err);
    }
    if (rc == BKF_OK) rc = floquet_integrate(f, K, 0, retry ? ENG_RETRY_FINE : ENG_FINE, &b, err);
    f->last_fine_key.valid = 0;
    if (rc != BKF_OK) return rc;
    f->last_fine = b;
    f->last_fine_key.K = K;
    f->last_fine_key.tol = tl / TOL_RATIO;
    f->last_fine_key.cycle_gen = f->cycle_gen;
    f->last_fine_key.valid = 1;
    mults ma = multipliers(a.tr, a.L), mb = multipliers(b.tr, b.L);
    fill_point(pt, K, f, &mb);
    pt->trace = b.tr;
    pt->log_det = b.L;
    pt->det_direct = b.det;
    memcpy(pt->monodromy, b.M, sizeof b.M);
    double normM = sqrt(b.M[0] * b.M[0] + b.M[1] * b.M[1] + b.M[2] * b.M[2] + b.M[3] * b.M[3]);
    double m_floor;
    /* the entries are integrated to tl absolute or relative, whichever is
     * larger: the floor is tl max(1, |M|) */
    pt->lambda_err = lambda_error(f, K, &ma, &mb, a.tr, b.tr, b.L, 0.0, fmax(1.0, normM), normM, tl,
                                  &m_floor, cyc);
    double m1_abs = hypot(mb.m1_re, mb.m1_im);
    pt->m1_err = hypot(ma.m1_re - mb.m1_re, ma.m1_im - mb.m1_im) +
                 cycle_term(f, K, m1_abs > 0.0 ? normM / m1_abs : INFINITY) *
                     m1_abs +
                 m_floor;
    pt->steps = a.steps + b.steps;
    return BKF_OK;
}

int floquet_eval_k2(bkf_floquet *f, double K, bkf_floquet_point *pt, bkf_error *err)
{
    double cyc;
    return eval_trace(f, K, 0, pt, &cyc, err);
}

/* ------------------------------------------------- log-column monodromy */

/* The columns of M in polar form.  In the balanced coordinates
 * (u, w) = (d_psi, d_eta gamma/sqrt(K)) the linearisation is
 *     u' = -damp u + k w,  w' = -k u,   k = sqrt(K), damp = gamma (psi*^2 - 1),
 * and a solution r (cos th, sin th), rho = ln r, obeys
 *     th' = -k + damp sin th cos th,   rho' = -damp cos^2 th.
 * Each column is then known to a relative accuracy set by the absolute
 * errors of th and rho, however small it is: the integration of M itself
 * controls absolute errors of entries that start at 1, so it loses every
 * multiplier below tol |M| (|m1| ~ exp(-1.4e4) at gamma 100, c q 100). */
enum { LX = 0, LY = 1, LT0 = 2, LR0 = 3, LT1 = 4, LR1 = 5, LL = 6, DIM_LOG = 7 };

static int log_rhs(double t, const double s[], double ds[], void *params)
{
    (void)t;
    lin_params *p = params;
    double g = p->gamma, x = s[LX], damp = g * (x * x - 1.0), k = sqrt(p->K);
    p->rhs_calls++;
    ds[LX] = g * (s[LY] - lienard_F(x));
    ds[LY] = (p->nu - x) / g;
    for (int j = 0; j < 2; j++) {
        double th = s[LT0 + 2 * j], c = cos(th), sn = sin(th);
        ds[LT0 + 2 * j] = -k + damp * sn * c;
        ds[LR0 + 2 * j] = -damp * c * c;
    }
    ds[LL] = -damp;
    return GSL_SUCCESS;
}

static int log_jac(double t, const double s[], double *J, double dfdt[], void *params)
{
    (void)t;
    lin_params *p = params;
    double g = p->gamma, x = s[LX], damp = g * (x * x - 1.0), ddamp = 2.0 * g * x;
    const size_t n = DIM_LOG;
    jacobian_of_cycle(J, dfdt, n, LX, LY, damp, g);
    for (int j = 0; j < 2; j++) {
        size_t it = LT0 + 2 * j, ir = it + 1;
        double th = s[it], c = cos(th), sn = sin(th);
        J[it * n + LX] = ddamp * sn * c;
        J[it * n + it] = damp * (c * c - sn * sn);
        J[ir * n + LX] = -ddamp * c * c;
        J[ir * n + it] = 2.0 * damp * sn * c;
    }
    J[LL * n + LX] = -ddamp;
    return GSL_SUCCESS;
}

/* The log system's stepper: the library's, except that bsimp is replaced
 * by rk8pd once the perturbation oscillates at least as fast as the
 * cycle's stiffest rate (sqrt(K) >= gamma): rk8pd's steps are then set by
 * the oscillation anyway, and bsimp took ~10 times longer at gamma 100,
 * c q 100. */
static const gsl_odeiv2_step_type *log_stepper(const bkf_floquet *f, double K)
{
    if (f->kind != BKF_STEPPER_IMPLICIT) return gsl_odeiv2_step_rk8pd;
    if (f->opt.stepper != BKF_STEPPER_IMPLICIT && sqrt(K) >= f->gamma) return gsl_odeiv2_step_rk8pd;
    return gsl_odeiv2_step_bsimp;
}

/* Step budget of a log integration: retry_nmax counts the library
 * stepper's steps; an rk8pd step standing in for bsimp is ~10 times
 * cheaper.  Once a log integration of this wavenumber has succeeded, the
 * next (at most 100 times tighter: its steps grow by 100^(1/p), 1.8 for
 * rk8pd, measured 1.7 for rk8pd and 2.6 for bsimp) gets LOG_RETRY_GROWTH
 * times its steps: an integration that needs more is asking a tolerance
 * below what rounding lets the stepper meet (bsimp at absolute 1e-13 on
 * the logs at gamma 100, nu 0.9999: 357 steps at 1e-12, then 50,000 and
 * over budget, 2.3 s for nothing at each refused q). */
static size_t log_nmax(const bkf_floquet *f, double K)
{
    size_t n = f->kind == BKF_STEPPER_IMPLICIT && log_stepper(f, K) == gsl_odeiv2_step_rk8pd
                   ? 10 * f->retry_nmax
                   : f->retry_nmax;
    if (f->log_fine_steps > 0) n = (size_t)fmin((double)n, LOG_RETRY_GROWTH * (double)f->log_fine_steps);
    return n;
}

typedef struct {
    double s, trt, normt, L;  /* M = e^s Mt (balanced), trace and norm of Mt */
    double M[4];              /* M in the plain coordinates, row-major (may underflow) */
    size_t steps;
} lograw;

static int integrate_log(bkf_floquet *f, double K, int which, double tol, lograw *out,
                         bkf_error *err)
{
    engine *e = &f->eng_log[which];
    if (!e->driver || e->tol != tol || e->driver->s->type != log_stepper(f, K)) {
        if (e->driver) gsl_odeiv2_driver_free(e->driver);
        e->system = (gsl_odeiv2_system){log_rhs, log_jac, DIM_LOG, &f->lp};
        const gsl_odeiv2_step_type *type = log_stepper(f, K);
        /* absolute errors only: th and rho are logs, their absolute error is
         * the relative error of the column, whatever its size */
        e->driver = gsl_odeiv2_driver_alloc_standard_new(&e->system, type, 1e-2, tol, 0.0, 1.0, 0.0);
        if (!e->driver) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
        e->tol = tol;
    }
    gsl_odeiv2_driver_set_nmax(e->driver, log_nmax(f, K));
    double s[DIM_LOG] = {f->x0, f->y0, 0.0, 0.0, 0.5 * 3.14159265358979323846, 0.0, 0.0};
    double t = 0.0;
    f->lp.K = K;
    gsl_odeiv2_driver_reset(e->driver);
    int rc = gsl_odeiv2_driver_apply(e->driver, &t, f->T, s);
    if (rc != GSL_SUCCESS || !isfinite(s[LR0]) || !isfinite(s[LR1]) || !isfinite(s[LT0]) ||
        !isfinite(s[LT1]))
        return bkf_error_set(err, BKF_ENUMERIC,
                             "monodromy (log columns) at gamma = %.15g, nu = %.15g, K = %.15g: integration "
                             "failed at t = %g (%s)",
                             f->gamma, f->nu, K, t, rc != GSL_SUCCESS ? gsl_strerror(rc) : "non-finite state");
    double sc = fmax(s[LR0], s[LR1]);
    double r0 = exp(s[LR0] - sc), r1 = exp(s[LR1] - sc);
    double c0 = cos(s[LT0]), s0 = sin(s[LT0]), c1 = cos(s[LT1]), s1 = sin(s[LT1]);
    out->s = sc;
    out->trt = r0 * c0 + r1 * s1;
    out->normt = sqrt(r0 * r0 + r1 * r1);
    out->L = s[LL];
    /* back to (d_psi, d_eta): M = S^-1 Mb S with S = diag(1, a) */
    double a = f->gamma / sqrt(K), es = exp(sc);
    out->M[0] = es * r0 * c0;
    out->M[1] = es * r1 * c1 * a;
    out->M[2] = es * r0 * s0 / a;
    out->M[3] = es * r1 * s1;
    out->steps = e->driver->n;
    return BKF_OK;
}

static int eval_log(bkf_floquet *f, double K, double tl, bkf_floquet_point *pt, double *cyc,
                    bkf_error *err)
{
    lograw a, b;
    int rc = integrate_log(f, K, 0, tl, &a, err);
    if (rc == BKF_OK) rc = integrate_log(f, K, 1, tl / TOL_RATIO, &b, err);
    if (rc != BKF_OK) return rc;
    f->log_fine_steps = b.steps;
    mults ma = floquet_multipliers_scaled(a.trt, a.L, a.s), mb = floquet_multipliers_scaled(b.trt, b.L, b.s);
    fill_point(pt, K, f, &mb);
    /* the coarse trace on the fine one's scale, for the difference */
    double tra = a.trt * exp(a.s - b.s);
    double m_floor;
    /* each column carries a relative error ~tl (absolute in th and rho) */
    pt->lambda_err = lambda_error(f, K, &ma, &mb, tra, b.trt, b.L, b.s, b.normt, b.normt, tl, &m_floor, cyc);
    double es = exp(b.s);
    pt->trace = b.trt * es;
    pt->log_det = b.L;
    pt->det_direct = b.M[0] * b.M[3] - b.M[1] * b.M[2];
    memcpy(pt->monodromy, b.M, sizeof b.M);
    pt->m1_err = hypot(ma.m1_re - mb.m1_re, ma.m1_im - mb.m1_im) +
                 (pt->lambda_err - fabs(ma.lambda - mb.lambda)) * hypot(mb.m1_re, mb.m1_im);
    pt->steps = a.steps + b.steps;
    return BKF_OK;
}

/* At K = 1 the linearisation is the cycle's own variational equation: the
 * multipliers are 1 (the flow's direction) and exp(L), exactly.  Integrating
 * M there cannot resolve m1 near the Hopf point, where 1 and exp(L),
 * L ~ -1e-5, nearly coincide (errors up to 4e-4 at tol 1e-4), nor at gamma
 * 100 (|M| ~ 1e7): the closed form is the answer.  M is still integrated
 * for the reported matrix and the check det_direct. */
static int eval_trivial(bkf_floquet *f, bkf_floquet_point *pt, bkf_error *err)
{
    double cyc;
    int rc = eval_trace(f, 1.0, 0, pt, &cyc, err);
    if (rc != BKF_OK) return rc;
    const bkf_cycle_result *cy = bkf_cycle_get(f->cycle);
    double L = f->L, L_err = cy ? cy->log_multiplier_err : 0.0;
    pt->m1_re = 1.0;
    pt->m1_im = pt->m2_im = 0.0;
    pt->m2_re = exp(L);
    pt->kind = BKF_FLOQUET_REAL_POSITIVE;
    pt->log_det = L;
    /* the cycle is stable (L < 0) unless L is within its error of 0; then
     * the dominant multiplier is exp(L) and lambda at most L + L_err */
    pt->lambda = fmax(0.0, L);
    pt->lambda_err = fmax(0.0, L + L_err) + DBL_EPSILON;
    pt->m1_err = pt->lambda_err;
    return BKF_OK;
}

/* The cycle again at tolerance tol (warm).  On failure the previous solve
 * is restored (it succeeded at its tolerance before). */
static int resolve_cycle(bkf_floquet *f, double tol, bkf_error *err)
{
    /* A tolerance the cycle refused is refused again: each wavenumber asked
     * it anew, and each refusal's restore solved the cycle again and voided
     * the looser one kept for cycle_measured (at gamma 100, nu 0.9999 a
     * fifth of the extremes matrix's time went to these solves). */
    if (tol == f->refused_tol)
        return bkf_error_set(err, BKF_ETOL, "the cycle at gamma = %.15g, nu = %.15g was refused tol %.3g",
                             f->gamma, f->nu, tol);
    f->cycle_gen++;
    bkf_cycle_options co = f->cycle_opt;
    co.tol = tol;
    co.warm_start = 1;
    int rc = bkf_cycle_solve(f->cycle, f->gamma, f->nu, &co, err);
    if (rc != BKF_OK) co = f->cycle_opt;
    /* The restore can fail too (gamma 44 and 110, nu 0.9999: 1e-12 solved
     * warm, 1e-13 refused, then 1e-12 refused again, warm and cold, and the
     * object was lost): then cold and looser, as bkf_floquet_set does. */
    int back = rc == BKF_OK ? BKF_OK : solve_backing_off(f->cycle, f->gamma, f->nu, &co, 4, err);
    co.warm_start = 1;
    if (back != BKF_OK) {
        f->ready = 0;
        return rc;
    }
    if (rc != BKF_OK) f->refused_tol = tol;
    const bkf_cycle_result *r = bkf_cycle_get(f->cycle);
    f->cycle_opt = co;
    f->y0 = r->section_slope / f->gamma + lienard_F(f->nu);
    f->T = r->period;
    f->T_err = r->period_err;
    f->L = r->log_multiplier;
    return rc;
}

/* The cycle's share of lambda's error, measured instead of bounded: lambda
 * with the cycle 100 times looser moves by d, so with the cycle as it is,
 * by ~d/100 if that error is linear in the cycle's tolerance; d/10 leaves
 * a factor 10.  The bound cycle_term is far above this at tight tolerance
 * (1.3e-10 against a measured 1e-13 at gamma 2, nu -0.9, c q 0.66), where
 * the cycle cannot be solved tighter than CYCLE_TOL_MIN.  Returns NaN if
 * it cannot tell.  *m1_share is m1's own share, relative to |m1|: for a
 * complex pair lambda = L/2 hardly moves with the cycle while m1's phase
 * (the trace) moves with T; m1_err took lambda's share and was 5 times
 * optimistic (gamma 10, nu 0.999, c q 8, tol 1e-10: 2e-11 against m1s of
 * the two steppers 1.1e-10 apart, their cycles' T 1.1e-11 apart). */
static double cycle_measured(bkf_floquet *f, double K, double *m1_share)
{
    bkf_floquet_point a, b;
    double cyc, tight = f->cycle_opt.tol, want = fmin(100.0 * tight, 1e-3);
    bkf_error e;
    /* The looser cycle (warm-started from the tight one) is solved once
     * per cycle and kept, not twice per wavenumber: those solves were most
     * of the cost of the transitions in the paper's dispersion. */
    if (f->loose_tol != want || f->loose_gen != f->cycle_gen) {
        if (resolve_cycle(f, want, &e) != BKF_OK) return NAN;
        f->loose_y0 = f->y0;
        f->loose_T = f->T;
        f->loose_T_err = f->T_err;
        f->loose_L = f->L;
        if (resolve_cycle(f, tight, &e) != BKF_OK) return NAN;
        f->loose_tol = want;
        f->loose_gen = f->cycle_gen;
    }
    if (eval_trace(f, K, 1, &a, &cyc, &e) != BKF_OK) return NAN;
    /* what of a's estimate is the integrations' own */
    double noise = a.lambda_err - cyc;
    double keep[4] = {f->y0, f->T, f->T_err, f->L};
    f->y0 = f->loose_y0;
    f->T = f->loose_T;
    f->T_err = f->loose_T_err;
    f->L = f->loose_L;
    f->last_fine_key.valid = 0;
    int rc = eval_trace(f, K, 1, &b, &cyc, &e);
    noise += b.lambda_err - cyc;
    f->last_fine_key.valid = 0;
    f->y0 = keep[0];
    f->T = keep[1];
    f->T_err = keep[2];
    f->L = keep[3];
    if (rc != BKF_OK) return NAN;
    /* lambda and m1 move with T at the rate the two cycles show: times T's
     * own error where that is above a tenth of their difference.  Near the
     * cycle's floor the looser cycle is hardly looser (gamma 30, nu 0.9999:
     * T 1e-10 apart, the tight one's T_err 9e-11), and a tenth of the
     * difference made lambda_err 4.7e-11 against a true 3.9e-10 at c q 0.3,
     * tol 1e-10. */
    double dT = fabs(keep[1] - f->loose_T);
    double scale = dT > 0.0 ? fmax(0.1, keep[2] / dT) : 0.1;
    /* a rate only where the difference stands above the integrations'
     * noise: below, T_err / dT scaled noise (20 times pessimistic at gamma
     * 100, nu -0.5, c q 0.9, tol 1e-8, and a refusal) */
    double m1_abs = hypot(a.m1_re, a.m1_im);
    double dm = m1_abs > 0.0 ? hypot(a.m1_re - b.m1_re, a.m1_im - b.m1_im) / m1_abs : INFINITY;
    *m1_share = (dm > noise ? scale : 0.1) * dm;
    double d = fabs(a.lambda - b.lambda);
    return (d > noise ? scale : 0.1) * d;
}

/* The best attempt so far at one wavenumber.  Once the cycle's share has
 * been measured (cycle_measured), it replaces the bound in every later
 * attempt made with the same cycle. */
typedef struct {
    bkf_floquet_point best;
    double cyc;               /* the cycle's share of best.lambda_err */
    int have;
    double cyc_measured;      /* INFINITY until measured */
    double cyc_measured_m1;   /* m1's share, relative (cycle_measured) */
    size_t steps;
} retry_best;

/* Replace the cycle's share of a point's estimates, in lambda_err and in
 * m1_err alike (m1 carries it times |m1|): replacing it in lambda_err alone
 * left m1_err at the bound, 3.8e-7 against lambda_err 1e-10 and a true m1
 * error of 2e-11 (gamma 20, c 0.05, nu 0.9, q 2). */
static void replace_cycle_share(bkf_floquet_point *pt, double old_cyc, double new_cyc, double new_m1)
{
    pt->lambda_err += new_cyc - old_cyc;
    pt->m1_err = fmax(pt->m1_err + (fmin(new_m1, old_cyc) - old_cyc) * hypot(pt->m1_re, pt->m1_im), 0.0);
}

static void consider(retry_best *rb, bkf_floquet_point *cand, double cand_cyc)
{
    rb->steps += cand->steps;
    if (rb->cyc_measured < cand_cyc) {
        replace_cycle_share(cand, cand_cyc, rb->cyc_measured, rb->cyc_measured_m1);
        cand_cyc = rb->cyc_measured;
    }
    if (!rb->have || cand->lambda_err < rb->best.lambda_err) {
        rb->best = *cand;
        rb->cyc = cand_cyc;
        rb->have = 1;
    }
}

static int floquet_eval_body(bkf_floquet *f, double q, bkf_floquet_point *pt, bkf_error *err)
{
    if (!f || !f->ready) return bkf_error_set(err, BKF_EINPUT, "floquet: eval before a successful set");
    if (!pt) return bkf_error_set(err, BKF_EINPUT, "floquet: point is NULL");
    /* NaN unless a point is filled: tells a refusal on tol from a failure */
    pt->lambda_err = NAN;
    int rc = bkf_model_check_nonnegative("q", q, err);
    if (rc != BKF_OK) return rc;
    double K = k2_of(f, q);
    if (!(K <= K_MAX))
        return bkf_error_set(err, BKF_EINPUT, "c q = %.15g is too large (at most %g)", f->c * q,
                             sqrt(K_MAX - 1.0));
    if (K == 1.0) {
        rc = eval_trivial(f, pt, err);
        if (rc == BKF_OK) pt->q = q;
        return rc;
    }
    double tol = f->opt.tol, cyc = 0.0, cand_cyc;
    rc = eval_trace(f, K, 0, pt, &cyc, err);
    if (rc == BKF_OK && pt->lambda_err <= tol) return BKF_OK;
    /* The estimate misses tol.  Try, keeping the best estimate: the log
     * columns at the same tolerance (multipliers under the noise floor of
     * M); a tighter cycle where its error dominates; both integrations at
     * tolerances 100 times tighter down to RETRY_TOL_MIN.  Each retry
     * integration may take RETRY_WORK times the steps of the first (bsimp
     * at c q 100 and tol 1e-13 took minutes), at least RETRY_STEPS_MIN. */
    size_t steps = rc == BKF_OK ? pt->steps : 0;
    f->retry_nmax = (size_t)fmax(RETRY_STEPS_MIN, RETRY_WORK * 0.5 * (double)steps);
    f->log_fine_steps = 0;
    retry_best rb = {*pt, cyc, rc == BKF_OK, INFINITY, INFINITY, steps};
    bkf_floquet_point cand;
    bkf_error e2;
    double tl = f->tol_int, tl_min = fmax(f->tol_floor, RETRY_TOL_MIN);
    /* A near miss (estimate within 10 tol: half the paper dispersion's rows
     * at tol 1e-10) is an integration a little too loose: one 10 times
     * tighter settles it, where the log columns at the same tolerance and
     * then a 100 times tighter pair cost twice as much. */
    int near_miss = rb.have && rb.best.lambda_err <= 10.0 * tol;
    if (!near_miss && eval_log(f, K, tl, &cand, &cand_cyc, &e2) == BKF_OK)
        consider(&rb, &cand, cand_cyc);
    int measured = 0, cycle_stuck = 0;
    while (!(rb.have && rb.best.lambda_err <= tol)) {
        /* the cycle's share must matter both against tol and in the total */
        int cycle_matters = rb.have && rb.cyc > 0.3 * tol && rb.cyc > 0.3 * rb.best.lambda_err;
        if (cycle_matters && !cycle_stuck && f->cycle_opt.tol > CYCLE_TOL_MIN) {
            if (resolve_cycle(f, fmax(0.01 * f->cycle_opt.tol, CYCLE_TOL_MIN), &e2) != BKF_OK) {
                /* near the canard the cycle can refuse a tight tolerance */
                if (!f->ready) break;
                cycle_stuck = 1;
                continue;
            }
        } else if (cycle_matters && !measured) {
            measured = 1;
            /* At the tightest retry tolerance, where the integrations'
             * noise stands lowest under the cycle's effect.  It was the
             * last retry's, whatever K that was: 0 on an object's first
             * retry (integrations at tol 0 that ran out of steps, 2 s at
             * gamma 100, nu -0.99, c q 0.3, and no share), a looser one
             * after a wavenumber that settled early (a share lost in the
             * noise, and a refusal at c q 100 that a 1e-13 pair answers). */
            f->tol_retry = tl_min;
            double cm_m1 = INFINITY, cm = cycle_measured(f, K, &cm_m1);
            if (!f->ready) break;
            if (cm < rb.cyc) {
                replace_cycle_share(&rb.best, rb.cyc, cm, cm_m1);
                rb.cyc = cm;
                rb.cyc_measured = cm;
                rb.cyc_measured_m1 = cm_m1;
            }
            continue;
        } else if (measured && (cycle_stuck || f->cycle_opt.tol <= CYCLE_TOL_MIN) &&
                   fmin(cycle_term(f, K, 1.0), rb.cyc_measured) > tol) {
            /* The cycle is as tight as it gets and every attempt with it
             * carries at least this share (the bound at |M| = |m1|, or the
             * measured one): no integration can meet tol (the last 1e-13
             * pair at gamma 30, c q 100 cost 2.5 s for a refusal). */
            break;
        } else if (tl > tl_min) {
            tl = fmax((near_miss ? 0.1 : 0.01) * tl, tl_min);
            /* 0.01 * 1e-11 is an ulp above 1e-13: without the snap the
             * loop ran the tightest pair twice (2.4 s more at each refused
             * q at gamma 100, nu 0.9999) */
            if (tl < 1.5 * tl_min) tl = tl_min;
            near_miss = 0;
        } else {
            break;
        }
        f->tol_retry = tl;
        int ok = 0;
        if (eval_trace(f, K, 1, &cand, &cand_cyc, &e2) == BKF_OK) {
            ok = 1;
            consider(&rb, &cand, cand_cyc);
        }
        if (!(rb.have && rb.best.lambda_err <= tol) && eval_log(f, K, tl, &cand, &cand_cyc, &e2) == BKF_OK) {
            ok = 1;
            consider(&rb, &cand, cand_cyc);
        }
        if (!ok) break; /* over budget at this tolerance: tighter is worse */
    }
    if (!f->ready) return bkf_error_set(err, BKF_ENUMERIC, "floquet: the cycle failed on a retry: %s", e2.message);
    if (!rb.have) return rc;
    *pt = rb.best;
    pt->q = q;
    pt->steps = rb.steps;
    if (!(pt->lambda_err <= tol))
        return bkf_error_set(err, BKF_ETOL,
                             "estimated error %.2g of lambda exceeds tol %.2g at q = %.15g "
                             "(gamma = %.15g, c = %.15g, nu = %.15g, lambda = %.6g)",
                             pt->lambda_err, tol, q, f->gamma, f->c, f->nu, pt->lambda);
    return BKF_OK;
}

int bkf_floquet_eval(bkf_floquet *f, double q, bkf_floquet_point *pt, bkf_error *err)
{
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    int rc = floquet_eval_body(f, q, pt, err);
    bkf_gsl_handler_pop(handler);
    return rc;
}

int floquet_longwave_at(bkf_floquet *f, int which, double *a, bkf_error *err)
{
    raw r;
    int rc = floquet_integrate(f, 1.0, 1, which, &r, err);
    if (rc != BKF_OK) return rc;
    /* m1 + D/m1 = trace with D independent of K, so at m1 = 1:
     * dm1/dK = (dtrace/dK)/(1 - D) */
    double one_minus_D = -expm1(r.L);
    if (!(one_minus_D > 0.0))
        return bkf_error_set(err, BKF_ENUMERIC,
                             "long-wave coefficient at gamma = %.15g, nu = %.15g: cycle multiplier %g "
                             "is not below 1",
                             f->gamma, f->nu, exp(r.L));
    *a = r.dtr / one_minus_D;
    return BKF_OK;
}

static int floquet_longwave_body(bkf_floquet *f, double *a, double *a_err, bkf_error *err)
{
    if (!f || !f->ready)
        return bkf_error_set(err, BKF_EINPUT, "floquet: longwave before a successful set");
    double ac, af;
    int rc = floquet_longwave_at(f, ENG_COARSE, &ac, err);
    if (rc == BKF_OK) rc = floquet_longwave_at(f, ENG_FINE, &af, err);
    if (rc != BKF_OK) return rc;
    if (a) *a = af;
    if (a_err) {
        double g = f->gamma;
        /* dM/dK moves with the end time as M does */
        double normA = g * fabs(f->nu * f->nu - 1.0) + g + 2.0 / g;
        *a_err = fabs(ac - af) + 30.0 * f->T_err * normA * fmax(1.0, fabs(af)) +
                 4.0 * DBL_EPSILON * fabs(af);
    }
    return BKF_OK;
}

int bkf_floquet_longwave(bkf_floquet *f, double *a, double *a_err, bkf_error *err)
{
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    int rc = floquet_longwave_body(f, a, a_err, err);
    bkf_gsl_handler_pop(handler);
    return rc;
}

double bkf_floquet_slip_rate(double gamma, double c, double nu, double q)
{
    if (!(gamma > 0) || !(c >= 0) || !isfinite(gamma + c + nu + q)) return NAN;
    double K = 1.0 + c * c * q * q;
    double b = gamma * (1.0 - nu * nu); /* -gamma phi'(nu) */
    double disc = b * b - 4.0 * K;
    return disc > 0.0 ? 0.5 * (b + sqrt(disc)) : 0.5 * b;
}


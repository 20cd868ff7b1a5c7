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

#include "bkfront/continuation.h"
#include "bkfront/model.h"

#include <float.h>
#include <gsl/gsl_errno.h>
#include <gsl/gsl_odeiv2.h>
#include <math.h>
#include <nlopt.h>
#include <stdlib.h>
#include <string.h>

/* State layout: M is stored by columns, column j = (d_psi, d_eta) from the
 * unit start vector e_j; P = dM/dK the same way. */
enum { IX = 0, IY = 1, IM = 2, IL = 6, IP = 7 };
enum { DIM_PLAIN = 7, DIM_DK = 11 };

/* As in cycle.c: above this gamma the explicit stepper's step is limited by
 * stability, not accuracy. */
#define STIFF_GAMMA 30.0
#define TOL_RATIO 10.0
/* Beyond K ~ 1e8 a period holds ~1e4 oscillations of the perturbation: the
 * integration is no longer a sensible way to get the answer. */
#define K_MAX 1e8
#define MAX_STEPS 5000000
#define MAX_PEAKS 64
/* Grid peaks lower than this are not refined: a refined peak rises above
 * its grid value by far less than this on any grid fine enough to see it. */
#define PEAK_FLOOR (-1.0)
/* Scans only locate peaks, refined afterwards, so they run loose. */
#define SCAN_TOL 1e-7
/* Retries of a wavenumber whose estimate misses tol (bkf_floquet_eval). */
#define RETRY_TOL_MIN 1e-13
#define CYCLE_TOL_MIN 1e-13
#define RETRY_WORK 30.0
#define RETRY_STEPS_MIN 50000.0

/* ------------------------------------------------------------ the flow */

typedef struct {
    double gamma, nu, K;
    size_t rhs_calls;
} lin_params;

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

/* One integration at one tolerance: the GSL driver is kept between
 * wavenumbers, so its step-size guess carries over. */
typedef struct {
    gsl_odeiv2_driver *driver;
    gsl_odeiv2_system system;
    double tol;
} engine;

/* Slots of the trace integration: the scan, the two tolerances of the
 * estimate, and the two of a retry at a tighter tolerance.  Separate slots
 * for the retry keep the usual drivers (and their step-size guesses) when
 * one wavenumber needs more. */
enum { ENG_SCAN = 0, ENG_COARSE = 1, ENG_FINE = 2, ENG_RETRY_COARSE = 3, ENG_RETRY_FINE = 4, ENG_SLOTS = 5 };

typedef struct {
    double M[4];      /* row-major */
    double tr, L, det;
    double dtr;       /* d trace / dK (with dk) */
    size_t steps;
} raw;

struct bkf_floquet {
    double gamma, c, nu;
    bkf_floquet_options opt;
    bkf_cycle *cycle;
    int ready;
    double x0, y0, T, T_err, L;
    lin_params lp;
    bkf_stepper_kind kind;
    engine eng[2][ENG_SLOTS]; /* [with dM/dK][slot] */
    engine eng_log[2];        /* log-column integrations, [coarse, fine] */
    double tol_int;           /* coarse integration tolerance; fine = /TOL_RATIO */
    double tol_floor;         /* tightest coarse tolerance worth a retry */
    double tol_retry;         /* tolerance of the retry slots */
    size_t retry_nmax;        /* step budget of one retry integration */
    bkf_cycle_options cycle_opt; /* of the cycle solved last */
    unsigned cycle_gen;          /* counts the cycles solved */
    /* The finer integration of the last eval_trace: a retry 10 times
     * tighter than that attempt integrates at exactly its tolerance, so
     * it takes it as its coarser half instead of repeating it. */
    struct {
        double K, tol;
        unsigned cycle_gen;
        int valid;
    } last_fine_key;
    raw last_fine;
    /* The cycle 100 times looser (cycle_measured), kept while cycle_gen
     * stays loose_gen. */
    double loose_tol;
    unsigned loose_gen;
    double loose_y0, loose_T, loose_T_err, loose_L;
};

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

static int check_options(const bkf_floquet_options *o, bkf_error *err)
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

static int check_gamma_c(double gamma, double c, bkf_error *err)
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
    int rc = check_options(&o, err);
    if (rc == BKF_OK) rc = check_gamma_c(gamma, c, err);
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

static int integrate(bkf_floquet *f, double K, int dk, int which, raw *out, bkf_error *err)
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

typedef struct {
    double m1_re, m1_im, m2_re, m2_im, lambda;
    bkf_floquet_kind kind;
    double m1_abs_scaled;   /* |m1| / e^s (see multipliers_scaled) */
} mults;

/* Eigenvalues of a real 2x2 M = e^s Mt from the trace of Mt and ln det M.
 * The determinant is Liouville's, exact where the matrix's own would cancel
 * (det ~ 1e-50 from entries of order 1), and the small multiplier is
 * det/m1.  lambda comes from logs, so it stays right when m1 itself
 * underflows (the log-column integration reaches lambda ~ -2e4). */
static mults multipliers_scaled(double trt, double L, double s)
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

static mults multipliers(double tr, double L) { return multipliers_scaled(tr, L, 0.0); }

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
        rc = integrate(f, K, 0, retry ? ENG_RETRY_COARSE : ENG_COARSE, &a, err);
    }
    if (rc == BKF_OK) rc = integrate(f, K, 0, retry ? ENG_RETRY_FINE : ENG_FINE, &b, err);
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

static int eval_k2(bkf_floquet *f, double K, bkf_floquet_point *pt, bkf_error *err)
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
 * cheaper. */
static size_t log_nmax(const bkf_floquet *f, double K)
{
    return f->kind == BKF_STEPPER_IMPLICIT && log_stepper(f, K) == gsl_odeiv2_step_rk8pd
               ? 10 * f->retry_nmax
               : f->retry_nmax;
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
    mults ma = multipliers_scaled(a.trt, a.L, a.s), mb = multipliers_scaled(b.trt, b.L, b.s);
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
            double cm_m1 = INFINITY, cm = cycle_measured(f, K, &cm_m1);
            if (!f->ready) break;
            if (cm < rb.cyc) {
                replace_cycle_share(&rb.best, rb.cyc, cm, cm_m1);
                rb.cyc = cm;
                rb.cyc_measured = cm;
                rb.cyc_measured_m1 = cm_m1;
            }
            continue;
        } else if (tl > tl_min) {
            tl = fmax((near_miss ? 0.1 : 0.01) * tl, tl_min);
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

static int longwave_at(bkf_floquet *f, int which, double *a, bkf_error *err)
{
    raw r;
    int rc = integrate(f, 1.0, 1, which, &r, err);
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
    int rc = longwave_at(f, ENG_COARSE, &ac, err);
    if (rc == BKF_OK) rc = longwave_at(f, ENG_FINE, &af, err);
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

/* ---------------------------------------------------------------- peaks */

typedef struct {
    bkf_floquet *f;
    nlopt_opt opt;
    double sign;
    int status;
    bkf_error *err;
} peak_ctx;

static double peak_objective(unsigned n, const double *x, double *grad, void *data)
{
    (void)n;
    (void)grad;
    peak_ctx *pc = data;
    raw r;
    if (pc->status == BKF_OK) pc->status = integrate(pc->f, x[0], 0, ENG_FINE, &r, pc->err);
    /* NLopt's objective cannot fail: stop it, the status is read afterwards */
    if (pc->status != BKF_OK) {
        nlopt_force_stop(pc->opt);
        return 0.0;
    }
    return pc->sign * r.tr;
}

/* The K in [lo, hi] maximising sign * trace, searched from *K. */
static int maximise_trace(bkf_floquet *f, double sign, double lo, double hi, double *K,
                          double *value, bkf_error *err)
{
    nlopt_opt opt = nlopt_create(NLOPT_LN_BOBYQA, 1);
    if (!opt) return bkf_error_set(err, BKF_ENOMEM, "out of memory (NLopt)");
    peak_ctx pc = {f, opt, sign, BKF_OK, err};
    nlopt_set_max_objective(opt, peak_objective, &pc);
    nlopt_set_lower_bounds1(opt, lo);
    nlopt_set_upper_bounds1(opt, hi);
    /* the peak's height is quadratic in the error of its place: a relative
     * 1e-7 in K is far below any tolerance in lambda */
    nlopt_set_xtol_rel(opt, 1e-7);
    nlopt_set_maxeval(opt, 200);
    nlopt_set_initial_step1(opt, 0.25 * (hi - lo));
    double x = fmin(fmax(*K, lo), hi), fx = 0.0;
    nlopt_result res = nlopt_optimize(opt, &x, &fx);
    nlopt_destroy(opt);
    if (pc.status != BKF_OK) return pc.status;
    if (res < 0 && res != NLOPT_ROUNDOFF_LIMITED)
        return bkf_error_set(err, BKF_ENUMERIC,
                             "peak of lambda at gamma = %.15g, nu = %.15g near K = %.15g: NLopt failed (%d)",
                             f->gamma, f->nu, *K, (int)res);
    *K = x;
    *value = fx;
    return BKF_OK;
}

/* Local peak of sign * trace near K, searched in windows of half-width w,
 * moved while the maximum sits on a window's edge.  K never goes below 1. */
static int track_peak(bkf_floquet *f, double sign, double *K, double w, double *value,
                      bkf_error *err)
{
    double center = *K;
    for (int attempt = 0; attempt < 8; attempt++) {
        double lo = fmax(1.0, center - w), hi = fmin(K_MAX, center + w);
        double x = center;
        int rc = maximise_trace(f, sign, lo, hi, &x, value, err);
        if (rc != BKF_OK) return rc;
        double edge_tol = 1e-6 * (hi - lo);
        int at_lo = x - lo <= edge_tol && lo > 1.0;
        int at_hi = hi - x <= edge_tol && hi < K_MAX;
        *K = x;
        if (!at_lo && !at_hi) return BKF_OK;
        center = x;
        w *= 1.5;
    }
    return BKF_OK;
}

typedef struct {
    double K, lambda, lambda_err, m_re, m_im;
    double sign;
    int region;      /* sign region of the trace counted from K = 1 */
} peak;

typedef struct {
    bkf_floquet_stability s;
    peak peaks[MAX_PEAKS];
    size_t npeaks;   /* refined peaks (region-0 band peak excluded when a > 0) */
} stability_full;

static double dk_of_p(double p, double dp) { return fmax(2.0 * p * dp, dp * dp); }

/* A refined peak: the K of the maximum, then lambda with its error there. */
static int refine_peak(bkf_floquet *f, double sign, double K_guess, double w, peak *out,
                       bkf_error *err)
{
    double K = K_guess, value;
    int rc = track_peak(f, sign, &K, w, &value, err);
    if (rc != BKF_OK) return rc;
    bkf_floquet_point pt;
    rc = eval_k2(f, K, &pt, err);
    if (rc != BKF_OK) return rc;
    out->K = K;
    out->lambda = pt.lambda;
    out->lambda_err = pt.lambda_err;
    out->m_re = pt.m1_re;
    out->m_im = pt.m1_im;
    out->sign = sign;
    return BKF_OK;
}

static int stability_scan(bkf_floquet *f, stability_full *sf, bkf_error *err)
{
    memset(sf, 0, sizeof *sf);
    bkf_floquet_stability *s = &sf->s;
    s->nu = f->nu;
    int rc = bkf_floquet_longwave(f, &s->longwave, &s->longwave_err, err);
    if (rc != BKF_OK) return rc;
    size_t n = f->opt.scan_points;
    double dp = f->opt.p_max / (double)n;
    double *tr = malloc((n + 1) * sizeof *tr);
    if (!tr) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    for (size_t j = 0; j <= n && rc == BKF_OK; j++) {
        raw r;
        double p = dp * (double)j;
        rc = integrate(f, 1.0 + p * p, 0, ENG_SCAN, &r, err);
        tr[j] = r.tr;
    }
    int region = 0;
    double best = -HUGE_VAL;
    for (size_t j = 1; j < n && rc == BKF_OK; j++) {
        if ((tr[j] > 0.0) != (tr[j - 1] > 0.0)) region++;
        double here = fabs(tr[j]);
        if (!(here >= fabs(tr[j - 1]) && here > fabs(tr[j + 1]))) continue;
        double sign = tr[j] > 0.0 ? 1.0 : -1.0;
        /* the long-wave band's own peak is the long-wave instability */
        if (region == 0 && s->longwave > 0.0) continue;
        mults m = multipliers(tr[j], f->L);
        if (m.lambda < PEAK_FLOOR || sf->npeaks == MAX_PEAKS) continue;
        double p = dp * (double)j;
        peak pk;
        rc = refine_peak(f, sign, 1.0 + p * p, dk_of_p(p, dp), &pk, err);
        if (rc != BKF_OK) break;
        pk.region = region;
        sf->peaks[sf->npeaks++] = pk;
        if (pk.lambda > best) {
            best = pk.lambda;
            s->lambda_peak = pk.lambda;
            s->lambda_peak_err = pk.lambda_err;
            s->k2_peak = pk.K;
            s->q_peak = f->c > 0.0 ? sqrt(fmax(pk.K - 1.0, 0.0)) / f->c : 0.0;
            s->m_re = pk.m_re;
            s->m_im = pk.m_im;
        }
    }
    free(tr);
    if (rc != BKF_OK) return rc;
    s->peaks = sf->npeaks;
    if (sf->npeaks == 0) s->lambda_peak = s->lambda_peak_err = s->q_peak = s->k2_peak = s->m_re = s->m_im = NAN;
    s->stable = s->longwave < 0.0 && !(best >= 0.0);
    return BKF_OK;
}

static int floquet_stability_at_body(bkf_floquet *f, bkf_floquet_stability *out, bkf_error *err)
{
    if (!f || !f->ready)
        return bkf_error_set(err, BKF_EINPUT, "floquet: stability before a successful set");
    if (!out) return bkf_error_set(err, BKF_EINPUT, "floquet: stability result is NULL");
    stability_full *sf = malloc(sizeof *sf);
    if (!sf) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    int rc = stability_scan(f, sf, err);
    if (rc == BKF_OK) *out = sf->s;
    free(sf);
    return rc;
}

int bkf_floquet_stability_at(bkf_floquet *f, bkf_floquet_stability *out, bkf_error *err)
{
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    int rc = floquet_stability_at_body(f, out, err);
    bkf_gsl_handler_pop(handler);
    return rc;
}

/* ----------------------------------------------------------- boundaries */

/* One indicator whose zero in nu is a stability boundary: the long-wave
 * coefficient, or the height of the peak of sign * trace tracked from K_a
 * (at nu_a) to K_b (at nu_b). */
typedef struct {
    bkf_floquet *f;
    const bkf_floquet_options *opt;
    double gamma, c;
    int longwave;
    double sign;
    double nu_a, K_a, nu_b, K_b, w;
    double K_last;   /* where the last evaluation found the peak */
    int status;
    bkf_error err;
} indicator;

static int indicator_eval(indicator *ind, double nu, double *value)
{
    int rc = bkf_floquet_set(ind->f, ind->gamma, ind->c, nu, ind->opt, &ind->err);
    if (rc != BKF_OK) return rc;
    if (ind->longwave) return longwave_at(ind->f, ENG_FINE, value, &ind->err);
    double t = ind->nu_b != ind->nu_a ? (nu - ind->nu_a) / (ind->nu_b - ind->nu_a) : 0.0;
    double K = ind->K_a + t * (ind->K_b - ind->K_a), v;
    rc = track_peak(ind->f, ind->sign, &K, ind->w, &v, &ind->err);
    if (rc != BKF_OK) return rc;
    ind->K_last = K;
    *value = multipliers(ind->sign * v, ind->f->L).lambda;
    return BKF_OK;
}

/* Brent's method on the indicator over [lo, hi] (values f_lo, f_hi of
 * opposite signs), to |hi - lo| <= xtol.  On return (success or not)
 * root/f_root are the best point and its value, other/f_other the opposite
 * end of the last bracket. */
typedef struct {
    double root, f_root, other, f_other, slope;
} bracket;

static int indicator_root(indicator *ind, double lo, double f_lo, double hi, double f_hi,
                          double xtol, bracket *br)
{
    /* Brent (1973), as in zeroin: b the best, c the opposite end */
    double a = lo, b = hi, c = hi, fa = f_lo, fb = f_hi, fc = f_hi, d = 0.0, e = 0.0;
    int rc = BKF_OK;
    br->slope = (f_hi - f_lo) / (hi - lo);
    for (int iter = 0; iter < 100; iter++) {
        if ((fb > 0.0) == (fc > 0.0)) {
            c = a;
            fc = fa;
            d = e = b - a;
        }
        if (fabs(fc) < fabs(fb)) {
            a = b;
            b = c;
            c = a;
            fa = fb;
            fb = fc;
            fc = fa;
        }
        double tol1 = 2.0 * DBL_EPSILON * fabs(b) + 0.5 * xtol;
        double xm = 0.5 * (c - b);
        if (fabs(xm) <= tol1 || fb == 0.0) break;
        if (fabs(e) >= tol1 && fabs(fa) > fabs(fb)) {
            double s = fb / fa, p, q, r;
            if (a == c) {
                p = 2.0 * xm * s;
                q = 1.0 - s;
            } else {
                q = fa / fc;
                r = fb / fc;
                p = s * (2.0 * xm * q * (q - r) - (b - a) * (r - 1.0));
                q = (q - 1.0) * (r - 1.0) * (s - 1.0);
            }
            if (p > 0.0) q = -q;
            p = fabs(p);
            if (2.0 * p < fmin(3.0 * xm * q - fabs(tol1 * q), fabs(e * q))) {
                e = d;
                d = p / q;
            } else {
                d = xm;
                e = d;
            }
        } else {
            d = xm;
            e = d;
        }
        double from = b, f_from = fb, trial = b + (fabs(d) > tol1 ? d : (xm > 0.0 ? tol1 : -tol1));
        double f_trial = 0.0;
        rc = indicator_eval(ind, trial, &f_trial);
        /* a cycle the engine cannot solve (the inside of a canard explosion
         * is exponentially thin in nu) need not stop the search: the bracket
         * still holds a root, try points nearer the bracket's middle */
        for (int retry = 0; bkf_status_is_numerical(rc) && retry < 4; retry++) {
            trial = from + (0.5 + 0.1 * retry) * (c - from);
            rc = indicator_eval(ind, trial, &f_trial);
        }
        if (rc != BKF_OK) {
            b = from;
            fb = f_from;
            break;
        }
        a = from;
        fa = f_from;
        b = trial;
        fb = f_trial;
        if (c != b && fc != fb) br->slope = (fc - fb) / (c - b);
    }
    br->root = b;
    br->f_root = fb;
    br->other = c;
    br->f_other = fc;
    return rc;
}

/* Past this the indicator did not go to zero in the final bracket: it
 * jumps there.  A continuous crossing with the bracket at the tolerance
 * would need a slope beyond 1e5 per unit nu to leave such a value. */
#define JUMP_VALUE 1e-3

/* Locate one indicator's zero in [nu_a, nu_b] and describe it.  On failure
 * *fail_near is the end of the last bracket nearest nu_a. */
static int locate(indicator *ind, double f_a, double f_b, bkf_floquet_threshold *th,
                  double *fail_near)
{
    bkf_floquet *f = ind->f;
    double lo = fmin(ind->nu_a, ind->nu_b), hi = fmax(ind->nu_a, ind->nu_b);
    double f_lo = ind->nu_a < ind->nu_b ? f_a : f_b, f_hi = ind->nu_a < ind->nu_b ? f_b : f_a;
    double xtol = fmax(0.5 * f->opt.tol, 1e-13);
    bracket br;
    int rc = indicator_root(ind, lo, f_lo, hi, f_hi, xtol, &br);
    if (rc != BKF_OK) {
        if (fail_near)
            *fail_near = fabs(br.root - ind->nu_a) < fabs(br.other - ind->nu_a) ? br.root : br.other;
        return rc;
    }
    double nu = br.root, v;
    int jump = fmin(fabs(br.f_root), fabs(br.f_other)) > JUMP_VALUE;
    rc = indicator_eval(ind, nu, &v);
    if (rc != BKF_OK) return rc;
    memset(th, 0, sizeof *th);
    th->gamma = ind->gamma;
    th->c = ind->c;
    th->nu = nu;
    th->discontinuous = jump;
    double value_err;
    if (ind->longwave) {
        double a, a_err;
        rc = bkf_floquet_longwave(f, &a, &a_err, &ind->err);
        if (rc != BKF_OK) return rc;
        th->kind = BKF_BOUNDARY_LONG_WAVE;
        th->k2 = 1.0;
        th->q = 0.0;
        th->m_re = 1.0;
        th->lambda = 0.0;
        th->longwave = a;
        value_err = a_err + fabs(a - v);
    } else {
        bkf_floquet_point pt;
        rc = eval_k2(f, ind->K_last, &pt, &ind->err);
        if (rc != BKF_OK) return rc;
        th->kind = ind->sign < 0.0 ? BKF_BOUNDARY_PERIOD_DOUBLING : BKF_BOUNDARY_OTHER;
        th->k2 = pt.k2;
        th->q = pt.q;
        th->m_re = pt.m1_re;
        th->m_im = pt.m1_im;
        th->lambda = pt.lambda;
        value_err = pt.lambda_err + fabs(pt.lambda - v);
        rc = bkf_floquet_longwave(f, &th->longwave, NULL, &ind->err);
        if (rc != BKF_OK) return rc;
    }
    if (jump) th->kind = BKF_BOUNDARY_OTHER;
    double slope = br.slope;
    th->nu_err = fabs(br.root - br.other) +
                 (!jump && slope != 0.0 && isfinite(slope) ? value_err / fabs(slope) : 0.0);
    return BKF_OK;
}

/* The indicators that could explain the change between a stable and an
 * unstable end; the one whose zero lies nearest the stable end is the
 * boundary (a second zero further in is inside the unstable interval). */
static int boundary_between(bkf_floquet *f, double gamma, double c, double nu_s,
                            const stability_full *st_s, double nu_u, const stability_full *st_u,
                            bkf_floquet_threshold *th, bkf_error *err)
{
    int found = 0, failed = 0;
    double fail_dist = HUGE_VAL;
    bkf_error fail_err = {0};
    double dp = f->opt.p_max / (double)f->opt.scan_points;
    indicator ind;
    bkf_floquet_threshold cand;
    if (st_u->s.longwave > 0.0 && st_s->s.longwave < 0.0) {
        memset(&ind, 0, sizeof ind);
        ind = (indicator){.f = f, .opt = &f->opt, .gamma = gamma, .c = c, .longwave = 1,
                          .nu_a = nu_s, .nu_b = nu_u};
        double near = nu_s;
        int rc = locate(&ind, st_s->s.longwave, st_u->s.longwave, &cand, &near);
        if (rc == BKF_OK) {
            *th = cand;
            found = 1;
        } else if (bkf_status_is_numerical(rc)) {
            failed = 1;
            fail_dist = fabs(near - nu_s);
            fail_err = ind.err;
        } else {
            *err = ind.err;
            return rc;
        }
    }
    for (size_t i = 0; i < st_u->npeaks; i++) {
        const peak *pu = &st_u->peaks[i];
        if (!(pu->lambda >= 0.0)) continue;
        /* the same tongue at the stable end: same sign, nearest K */
        double K_s = pu->K, best = HUGE_VAL;
        for (size_t j = 0; j < st_s->npeaks; j++) {
            const peak *ps = &st_s->peaks[j];
            if (ps->sign != pu->sign) continue;
            if (fabs(ps->K - pu->K) < best) {
                best = fabs(ps->K - pu->K);
                K_s = ps->K;
            }
        }
        double p = sqrt(fmax(pu->K - 1.0, 0.0));
        double w = fmax(fabs(K_s - pu->K), 2.0 * dk_of_p(p, dp));
        memset(&ind, 0, sizeof ind);
        ind = (indicator){.f = f, .opt = &f->opt, .gamma = gamma, .c = c, .sign = pu->sign,
                          .nu_a = nu_s, .K_a = K_s, .nu_b = nu_u, .K_b = pu->K, .w = w};
        double v_s, v_u, near = nu_s;
        int rc = indicator_eval(&ind, nu_s, &v_s);
        if (rc == BKF_OK) rc = indicator_eval(&ind, nu_u, &v_u);
        if (rc == BKF_OK && !(v_s < 0.0 && v_u >= 0.0)) continue;
        if (rc == BKF_OK) rc = locate(&ind, v_s, v_u, &cand, &near);
        if (rc == BKF_OK) {
            if (!found || fabs(cand.nu - nu_s) < fabs(th->nu - nu_s)) *th = cand;
            found = 1;
        } else if (bkf_status_is_numerical(rc)) {
            failed = 1;
            fail_dist = fmin(fail_dist, fabs(near - nu_s));
            fail_err = ind.err;
        } else {
            *err = ind.err;
            return rc;
        }
    }
    /* a candidate that failed matters only if its zero could lie nearer the
     * stable end than the boundary found */
    if (failed && (!found || fail_dist < fabs(th->nu - nu_s))) {
        *err = fail_err;
        return BKF_ENUMERIC;
    }
    if (!found)
        return bkf_error_set(err, BKF_ENUMERIC,
                             "stability changes between nu = %.10g and %.10g (gamma = %.15g) but no "
                             "indicator changes sign there",
                             nu_s, nu_u, gamma);
    th->stable_above = nu_s > nu_u;
    return BKF_OK;
}

static int check_scan_inputs(double gamma, double c, double nu_lo, double nu_hi,
                             const bkf_floquet_options *o, bkf_error *err)
{
    int rc = check_options(o, err);
    if (rc == BKF_OK) rc = check_gamma_c(gamma, c, err);
    if (rc != BKF_OK) return rc;
    if (!(c > 0.0))
        return bkf_error_set(err, BKF_EINPUT,
                             "c = %.15g: thresholds need c > 0 (with c = 0 every wavenumber is the "
                             "neutral q = 0 mode)",
                             c);
    if ((rc = bkf_model_check_nu_active(nu_lo, err)) || (rc = bkf_model_check_nu_active(nu_hi, err)))
        return rc;
    if (!(nu_lo < nu_hi))
        return bkf_error_set(err, BKF_EINPUT, "the nu range needs lo < hi (got %g, %g)", nu_lo, nu_hi);
    return BKF_OK;
}

/* Scan [nu_lo, nu_hi] upward; `each_boundary` is called for every change of
 * stability (located), `until_first` stops after the first. */
typedef int (*boundary_fn)(const bkf_floquet_threshold *th, double nu_prev, int stable_prev,
                           void *data);

static int scan_nu(double gamma, double c, double nu_lo, double nu_hi,
                   const bkf_floquet_options *o, boundary_fn each, void *data, int *first_stable,
                   int *last_stable, size_t *changes, bkf_error *err)
{
    int rc = check_scan_inputs(gamma, c, nu_lo, nu_hi, o, err);
    if (rc != BKF_OK) return rc;
    bkf_floquet *f = bkf_floquet_alloc();
    stability_full *prev = malloc(sizeof *prev), *cur = malloc(sizeof *cur);
    if (!f || !prev || !cur) {
        bkf_floquet_free(f);
        free(prev);
        free(cur);
        return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    }
    size_t n = (size_t)ceil((nu_hi - nu_lo) / o->nu_step - 1e-9);
    if (n < 1) n = 1;
    *changes = 0;
    for (size_t i = 0; i <= n && rc == BKF_OK; i++) {
        double nu = i == n ? nu_hi : nu_lo + (nu_hi - nu_lo) * (double)i / (double)n;
        rc = bkf_floquet_set(f, gamma, c, nu, o, err);
        if (rc == BKF_OK) rc = stability_scan(f, cur, err);
        if (rc != BKF_OK) break;
        if (i == 0) *first_stable = cur->s.stable;
        if (i > 0 && cur->s.stable != prev->s.stable) {
            bkf_floquet_threshold th;
            const stability_full *st_s = cur->s.stable ? cur : prev;
            const stability_full *st_u = cur->s.stable ? prev : cur;
            rc = boundary_between(f, gamma, c, st_s->s.nu, st_s, st_u->s.nu, st_u, &th, err);
            if (rc != BKF_OK) break;
            (*changes)++;
            if (each(&th, prev->s.nu, prev->s.stable, data)) break;
        }
        *last_stable = cur->s.stable;
        stability_full *t = prev;
        prev = cur;
        cur = t;
    }
    bkf_floquet_free(f);
    free(prev);
    free(cur);
    return rc;
}

static int keep_first(const bkf_floquet_threshold *th, double nu_prev, int stable_prev, void *data)
{
    (void)nu_prev;
    (void)stable_prev;
    *(bkf_floquet_threshold *)data = *th;
    return 1;
}

static int floquet_threshold_find_body(double gamma, double c, double nu_lo, double nu_hi,
                                       const bkf_floquet_options *options, bkf_floquet_threshold *out,
                                       bkf_error *err)
{
    if (!out) return bkf_error_set(err, BKF_EINPUT, "threshold result is NULL");
    bkf_floquet_options o = options ? *options : bkf_floquet_options_default();
    int first = 0, last = 0;
    size_t changes = 0;
    int rc = scan_nu(gamma, c, nu_lo, nu_hi, &o, keep_first, out, &first, &last, &changes, err);
    if (rc != BKF_OK) return rc;
    if (changes == 0) {
        /* stable or unstable throughout the scan: an answer */
        *out = (bkf_floquet_threshold){.gamma = gamma, .c = c, .nu = NAN, .nu_err = NAN,
                                       .kind = BKF_BOUNDARY_NONE, .q = NAN, .k2 = NAN,
                                       .m_re = NAN, .m_im = NAN, .lambda = NAN,
                                       .stable_above = first, .longwave = NAN};
    }
    return BKF_OK;
}

int bkf_floquet_threshold_find(double gamma, double c, double nu_lo, double nu_hi,
                               const bkf_floquet_options *options, bkf_floquet_threshold *out,
                               bkf_error *err)
{
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    int rc = floquet_threshold_find_body(gamma, c, nu_lo, nu_hi, options, out, err);
    bkf_gsl_handler_pop(handler);
    return rc;
}

/* --------------------------------------------------------------- diagram */

typedef struct {
    double gamma, c, nu_lo, nu_hi;
    bkf_floquet_interval current;
    bkf_floquet_interval_visit visit;
    void *data;
    int stopped;
} diagram_ctx;

static bkf_floquet_threshold scan_end(double gamma, double c, double nu)
{
    bkf_floquet_threshold t;
    memset(&t, 0, sizeof t);
    t.gamma = gamma;
    t.c = c;
    t.nu = nu;
    t.kind = BKF_BOUNDARY_SCAN_END;
    t.q = t.k2 = t.m_re = t.m_im = t.lambda = t.longwave = NAN;
    return t;
}

static int diagram_boundary(const bkf_floquet_threshold *th, double nu_prev, int stable_prev,
                            void *data)
{
    (void)nu_prev;
    diagram_ctx *d = data;
    d->current.stable = stable_prev;
    d->current.to = *th;
    d->current.nu_to = th->nu;
    if (d->visit(&d->current, d->data)) {
        d->stopped = 1;
        return 1;
    }
    d->current.from = *th;
    d->current.nu_from = th->nu;
    return 0;
}

static int floquet_diagram_body(double gamma, double c, double nu_lo, double nu_hi,
                                const bkf_floquet_options *options, bkf_floquet_interval_visit visit,
                                void *data, bkf_error *err)
{
    if (!visit) return bkf_error_set(err, BKF_EINPUT, "diagram visit callback is NULL");
    bkf_floquet_options o = options ? *options : bkf_floquet_options_default();
    diagram_ctx d;
    memset(&d, 0, sizeof d);
    d.gamma = gamma;
    d.c = c;
    d.nu_lo = nu_lo;
    d.nu_hi = nu_hi;
    d.visit = visit;
    d.data = data;
    d.current.from = scan_end(gamma, c, nu_lo);
    d.current.nu_from = nu_lo;
    int first = 0, last = 0;
    size_t changes = 0;
    int rc = scan_nu(gamma, c, nu_lo, nu_hi, &o, diagram_boundary, &d, &first, &last, &changes, err);
    if (rc != BKF_OK || d.stopped) return rc;
    d.current.stable = last;
    d.current.to = scan_end(gamma, c, nu_hi);
    d.current.nu_to = nu_hi;
    visit(&d.current, data);
    return BKF_OK;
}

int bkf_floquet_diagram(double gamma, double c, double nu_lo, double nu_hi,
                        const bkf_floquet_options *options, bkf_floquet_interval_visit visit,
                        void *data, bkf_error *err)
{
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    int rc = floquet_diagram_body(gamma, c, nu_lo, nu_hi, options, visit, data, err);
    bkf_gsl_handler_pop(handler);
    return rc;
}

/* ------------------------------------------------------- threshold curve */

/* Continuation unknowns: finite-q boundary u = (K, nu, s), equations
 * sign * trace - (1 + D) = 0 (a multiplier at sign * 1) and dtrace/dK = 0
 * (at the peak); long-wave boundary u = (nu, s), equation a = 0.  s is c or
 * ln gamma. */
typedef struct {
    bkf_floquet_param along;
    double gamma, c;           /* the fixed one is used */
    bkf_floquet_options opt;
    bkf_floquet *f;
    int longwave;
    double sign;
    double from, to, s_from, s_to;
    double w;                  /* peak window for polishing */
    int stable_above;
    bkf_floquet_threshold_visit visit;
    void *visit_data;
    int visit_status;
    bkf_error *err;
} branch_ctx;

static void branch_params(const branch_ctx *b, double s, double *gamma, double *c)
{
    *gamma = b->along == BKF_FLOQUET_ALONG_GAMMA ? exp(s) : b->gamma;
    *c = b->along == BKF_FLOQUET_ALONG_C ? s : b->c;
}

static int branch_eval(branch_ctx *b, double K, double nu, double s, double *g, bkf_error *err)
{
    double gamma, c;
    branch_params(b, s, &gamma, &c);
    if (!(fabs(nu) < 1.0) || !(K >= 1.0) || !(K <= K_MAX))
        return bkf_error_set(err, BKF_ENUMERIC, "threshold curve left the valid range");
    int rc = bkf_floquet_set(b->f, gamma, c, nu, &b->opt, err);
    /* any failure but memory shrinks the continuation's step */
    if (rc != BKF_OK) return rc == BKF_ENOMEM ? rc : BKF_ENUMERIC;
    if (b->longwave) return longwave_at(b->f, ENG_FINE, &g[0], err);
    raw r;
    rc = integrate(b->f, K, 1, ENG_FINE, &r, err);
    if (rc != BKF_OK) return rc;
    g[0] = b->sign * r.tr - (1.0 + exp(r.L));
    g[1] = r.dtr;
    return BKF_OK;
}

static int branch_residual(const double *u, double *g, double *jac, void *data, bkf_error *err)
{
    branch_ctx *b = data;
    int lw = b->longwave;
    size_t n = lw ? 1 : 2, N = n + 1;
    double K = lw ? 1.0 : u[0], nu = u[N - 2], s = u[N - 1];
    int rc = branch_eval(b, K, nu, s, g, err);
    if (rc != BKF_OK || !jac) return rc == BKF_ENOMEM ? rc : (rc ? BKF_ENUMERIC : BKF_OK);
    /* forward differences with steps well above the integration noise
     * (the driver's own would be ~1e-8, where noise of 1e-12 in g is a
     * 1e-4 error in the Jacobian) */
    double uh[3], g2[2];
    for (size_t j = 0; j < N; j++) {
        memcpy(uh, u, N * sizeof *u);
        double h = 1e-6 * fmax(1.0, fabs(u[j]));
        uh[j] += h;
        h = uh[j] - u[j];
        rc = branch_eval(b, lw ? 1.0 : uh[0], uh[N - 2], uh[N - 1], g2, err);
        if (rc != BKF_OK) return rc == BKF_ENOMEM ? rc : BKF_ENUMERIC;
        for (size_t i = 0; i < n; i++) jac[i * N + j] = (g2[i] - g[i]) / h;
    }
    /* put the cycle back at u: the polish after acceptance starts from it */
    return BKF_OK;
}

/* At fixed parameter, the boundary near nu0 by root finding in a bracket
 * widened until the indicator changes sign. */
static int polish(const branch_ctx *b, double gamma, double c, double K0, double nu0,
                  bkf_floquet_threshold *th, bkf_error *err)
{
    indicator ind;
    memset(&ind, 0, sizeof ind);
    ind = (indicator){.f = b->f, .opt = &b->opt, .gamma = gamma, .c = c, .longwave = b->longwave, .sign = b->sign,
                      .K_a = K0, .K_b = K0, .w = b->w};
    double delta = 1e-4;
    for (int attempt = 0; attempt < 5; attempt++, delta *= 8.0) {
        double lo = fmax(nu0 - delta, -1.0 + 1e-9), hi = fmin(nu0 + delta, 1.0 - 1e-9);
        ind.nu_a = lo;
        ind.nu_b = hi;
        double f_lo, f_hi;
        int rc = indicator_eval(&ind, lo, &f_lo);
        if (rc == BKF_OK) rc = indicator_eval(&ind, hi, &f_hi);
        if (rc != BKF_OK) {
            *err = ind.err;
            return rc;
        }
        if ((f_lo < 0.0) == (f_hi < 0.0)) continue;
        rc = locate(&ind, f_lo, f_hi, th, NULL);
        if (rc != BKF_OK) {
            *err = ind.err;
            return rc;
        }
        th->stable_above = b->stable_above;
        return BKF_OK;
    }
    return bkf_error_set(err, BKF_ENUMERIC,
                         "threshold curve: no sign change of the indicator near nu = %.10g", nu0);
}

static int branch_accept(const double *u, const double *tangent, int is_fold, void *data)
{
    (void)tangent;
    (void)is_fold;
    branch_ctx *b = data;
    size_t N = b->longwave ? 2 : 3;
    double s = u[N - 1];
    /* the ends are requested values: give them back exactly */
    double par;
    if (fabs(s - b->s_from) <= 1e-12 * fmax(1.0, fabs(s))) s = b->s_from;
    if (fabs(s - b->s_to) <= 1e-12 * fmax(1.0, fabs(s))) s = b->s_to;
    par = s == b->s_from ? b->from : s == b->s_to ? b->to
          : b->along == BKF_FLOQUET_ALONG_GAMMA ? exp(s)
                                                : s;
    double gamma = b->along == BKF_FLOQUET_ALONG_GAMMA ? par : b->gamma;
    double c = b->along == BKF_FLOQUET_ALONG_C ? par : b->c;
    bkf_floquet_threshold th;
    int rc = polish(b, gamma, c, b->longwave ? 1.0 : u[0], u[N - 2], &th, b->err);
    if (rc != BKF_OK) {
        b->visit_status = rc;
        return 1;
    }
    if (b->visit(&th, b->visit_data) != 0) {
        b->visit_status = -1;
        return 1;
    }
    return 0;
}

static int floquet_threshold_branch_body(bkf_floquet_param along, double from, double to, double gamma,
                                         double c, double nu_lo, double nu_hi,
                                         const bkf_floquet_options *options, size_t max_points,
                                         bkf_floquet_threshold_visit visit, void *data, bkf_error *err)
{
    if (!visit) return bkf_error_set(err, BKF_EINPUT, "threshold visit callback is NULL");
    if (along != BKF_FLOQUET_ALONG_C && along != BKF_FLOQUET_ALONG_GAMMA)
        return bkf_error_set(err, BKF_EINPUT, "threshold curve parameter must be c or gamma");
    bkf_floquet_options o = options ? *options : bkf_floquet_options_default();
    double g_from = along == BKF_FLOQUET_ALONG_GAMMA ? from : gamma;
    double c_from = along == BKF_FLOQUET_ALONG_C ? from : c;
    double g_to = along == BKF_FLOQUET_ALONG_GAMMA ? to : gamma;
    double c_to = along == BKF_FLOQUET_ALONG_C ? to : c;
    int rc = check_scan_inputs(g_from, c_from, nu_lo, nu_hi, &o, err);
    if (rc == BKF_OK) rc = check_scan_inputs(g_to, c_to, nu_lo, nu_hi, &o, err);
    if (rc != BKF_OK) return rc;
    if (from == to) return bkf_error_set(err, BKF_EINPUT, "threshold curve needs from != to");

    bkf_floquet_threshold start;
    rc = bkf_floquet_threshold_find(g_from, c_from, nu_lo, nu_hi, &o, &start, err);
    if (rc != BKF_OK) return rc;
    if (start.kind == BKF_BOUNDARY_NONE)
        return bkf_error_set(err, BKF_ENUMERIC,
                             "no boundary to follow: no change of stability for nu in [%.15g, "
                             "%.15g] at gamma = %.15g, c = %.15g (global oscillations %s "
                             "throughout, scan step %g)",
                             nu_lo, nu_hi, g_from, c_from, start.stable_above ? "stable" : "unstable",
                             o.nu_step);

    branch_ctx b;
    memset(&b, 0, sizeof b);
    b.along = along;
    b.gamma = gamma;
    b.c = c;
    b.opt = o;
    b.f = bkf_floquet_alloc();
    if (!b.f) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    b.longwave = start.kind == BKF_BOUNDARY_LONG_WAVE;
    b.sign = start.kind == BKF_BOUNDARY_PERIOD_DOUBLING ? -1.0 : 1.0;
    b.from = from;
    b.to = to;
    b.s_from = along == BKF_FLOQUET_ALONG_GAMMA ? log(from) : from;
    b.s_to = along == BKF_FLOQUET_ALONG_GAMMA ? log(to) : to;
    double dp = o.p_max / (double)o.scan_points;
    b.w = 2.0 * dk_of_p(sqrt(fmax(start.k2 - 1.0, 0.0)), dp);
    b.stable_above = start.stable_above;
    b.visit = visit;
    b.visit_data = data;
    b.err = err;

    double u0[3];
    size_t n = b.longwave ? 1 : 2;
    if (b.longwave) {
        u0[0] = start.nu;
        u0[1] = b.s_from;
    } else {
        u0[0] = start.k2;
        u0[1] = start.nu;
        u0[2] = b.s_from;
    }
    bkf_cont_options co = bkf_cont_options_default(n);
    co.step_max = 0.1;
    co.step_initial = 0.02;
    co.newton_tol = fmax(1e-9, 10.0 * o.tol);
    co.stop_index = (int)n;
    co.stop_min = fmin(b.s_from, b.s_to);
    co.stop_max = fmax(b.s_from, b.s_to);
    if (max_points) co.max_points = max_points;
    bkf_cont_report report;
    rc = bkf_cont_run(branch_residual, branch_accept, &b, u0, (int)n, b.s_to > b.s_from ? 1 : -1,
                      &co, &report, err);
    bkf_floquet_free(b.f);
    if (b.visit_status > 0) return b.visit_status;
    if (b.visit_status < 0) return BKF_OK;
    return rc;
}

int bkf_floquet_threshold_branch(bkf_floquet_param along, double from, double to, double gamma,
                                 double c, double nu_lo, double nu_hi,
                                 const bkf_floquet_options *options, size_t max_points,
                                 bkf_floquet_threshold_visit visit, void *data, bkf_error *err)
{
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    int rc = floquet_threshold_branch_body(along, from, to, gamma, c, nu_lo, nu_hi, options, max_points, visit, data, err);
    bkf_gsl_handler_pop(handler);
    return rc;
}

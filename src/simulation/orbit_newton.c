/* Newton-Krylov shooting for periodic orbits: SUNDIALS KINSOL with the
 * SPGMR linear solver; Jacobian-vector products from the tangent flow
 * (orbit_flow.c), never from differences of whole flows.
 *
 *   F(u, T, s) = ( Phi_T(u) - R_s u,  <pt, u - uref>,  <ps, u - uref> )
 *   J (v, dT, ds) = ( DPhi_T(u) v + f(Phi_T u) dT - R_s v - dR_s u/ds ds,
 *                     <pt, v>,  <ps, v> )
 *
 * with the rows and columns of the held unknowns left out. */
#include "orbit_internal.h"

#include <kinsol/kinsol.h>
#include <math.h>
#include <nvector/nvector_serial.h>
#include <stdlib.h>
#include <string.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_spgmr.h>

/* |cos| between f and d_x u beyond which the state is a travelling wave:
 * time and space translation then move it the same way. */
#define TRAVELLING_COS 0.98
/* d_x u below this (relative to the state's size) is a uniform state. */
#define UNIFORM_DX 1e-9

static double dot(const double *a, const double *b, size_t n)
{
    double s = 0.0;
    for (size_t i = 0; i < n; i++) s += a[i] * b[i];
    return s;
}

static double maxabs(const double *a, size_t n)
{
    double m = 0.0;
    for (size_t i = 0; i < n; i++) m = fmax(m, fabs(a[i]));
    return m;
}

void orbit_newton_release(orbit_newton_job *job)
{
    if (!job) return;
    free(job->uref);
    free(job->pt);
    free(job->ps);
    job->uref = job->pt = job->ps = NULL;
}

int orbit_newton_prepare(orbit_flow *fl, orbit_newton_job *job, const double *x,
                         bkf_orbit_shift_mode mode, bkf_error *err)
{
    size_t n2 = 2 * fl->N;
    orbit_newton_release(job);
    job->uref = malloc(n2 * sizeof *job->uref);
    job->pt = malloc(n2 * sizeof *job->pt);
    job->ps = malloc(n2 * sizeof *job->ps);
    if (!job->uref || !job->pt || !job->ps) {
        orbit_newton_release(job);
        return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    }
    memcpy(job->uref, x, n2 * sizeof *x);
    int s = orbit_flow_rhs(fl, x, job->pt, err);
    if (s) return s;
    orbit_flow_dx(fl, x, job->ps);
    double nf = sqrt(dot(job->pt, job->pt, n2)), nd = sqrt(dot(job->ps, job->ps, n2));
    double size = fmax(1.0, maxabs(x, n2));
    if (!(nf > 0))
        return bkf_error_set(err, BKF_EINPUT,
                             "the guess is an equilibrium (f(u) = 0): no period to find");
    for (size_t i = 0; i < n2; i++) job->pt[i] /= nf;
    int uniform = fl->kind == BKF_MODEL_CHAIN || !(maxabs(job->ps, n2) > UNIFORM_DX * size);
    if (nd > 0)
        for (size_t i = 0; i < n2; i++) job->ps[i] /= nd;
    job->symmetry = BKF_ORBIT_SYM_GENERIC;
    job->period_free = 1;
    job->shift_free = 0;
    if (fl->kind == BKF_MODEL_CHAIN) {
        if (mode == BKF_ORBIT_SHIFT_FREE)
            return bkf_error_set(err, BKF_EINPUT,
                                 "shift_mode free needs the continuum: the chain has no "
                                 "continuous space translation (use fixed, whole blocks)");
        double h = fl->S / (double)fl->N, b = x[n2 + 1] / h;
        if (fabs(b - nearbyint(b)) > 1e-9 * fmax(1.0, fabs(b)))
            return bkf_error_set(err, BKF_EINPUT,
                                 "shift = %.15g is not a whole number of blocks (h = %.15g) of "
                                 "the chain", x[n2 + 1], h);
        return BKF_OK;
    }
    if (uniform) {
        /* the global oscillation: no space dependence, nothing to shift */
        job->symmetry = BKF_ORBIT_SYM_UNIFORM;
        return BKF_OK;
    }
    job->shift_free = 1;
    if (fabs(dot(job->pt, job->ps, n2)) > TRAVELLING_COS) {
        job->symmetry = BKF_ORBIT_SYM_TRAVELLING;
        job->period_free = 0;
    }
    return BKF_OK;
}

/* ------------------------------------------------------------ KINSOL */

typedef struct {
    orbit_flow *fl;
    const orbit_newton_job *job;
    size_t n2, n;             /* 2N; KINSOL's unknowns */
    double T, s;              /* the held values */
    double flow_tol;
    double *a, *b, *c, *d;    /* 2N scratch each */
    int status;
    bkf_error err;
    size_t jv, fevals;
    double *prev;             /* the last linearisation point */
    int have_prev;
    double last_step;
} nk_data;

static void unpack(const nk_data *d, const double *x, double *T, double *s)
{
    size_t i = d->n2;
    *T = d->job->period_free ? x[i++] : d->T;
    *s = d->job->shift_free ? x[i] : d->s;
}

static int residual(const double *x, double *F, nk_data *d)
{
    const orbit_newton_job *job = d->job;
    size_t n2 = d->n2;
    double T, s;
    unpack(d, x, &T, &s);
    int st = orbit_flow_run(d->fl, x, NULL, T, d->flow_tol, d->a, NULL, NULL, &d->err);
    if (st) return d->status = st;
    orbit_flow_shift(d->fl, x, s, d->b, NULL);
    for (size_t i = 0; i < n2; i++) F[i] = d->a[i] - d->b[i];
    size_t r = n2;
    if (job->period_free) {
        double p = 0.0;
        for (size_t i = 0; i < n2; i++) p += job->pt[i] * (x[i] - job->uref[i]);
        F[r++] = p;
    }
    if (job->shift_free) {
        double p = 0.0;
        for (size_t i = 0; i < n2; i++) p += job->ps[i] * (x[i] - job->uref[i]);
        F[r++] = p;
    }
    d->fevals++;
    return BKF_OK;
}

static int jtimes(const double *x, const double *v, double *Jv, nk_data *d)
{
    const orbit_newton_job *job = d->job;
    size_t n2 = d->n2;
    double T, s;
    unpack(d, x, &T, &s);
    /* a: DPhi_T v, b: f at Phi_T(u), c: R_s v, then d: dR_s u/ds */
    int st = orbit_flow_run(d->fl, x, v, T, d->flow_tol, NULL, d->a, d->b, &d->err);
    if (st) return d->status = st;
    orbit_flow_shift(d->fl, v, s, d->c, NULL);
    size_t i = n2;
    double dT = job->period_free ? v[i++] : 0.0;
    double ds = job->shift_free ? v[i] : 0.0;
    for (size_t k = 0; k < n2; k++) Jv[k] = d->a[k] + d->b[k] * dT - d->c[k];
    if (job->shift_free) {
        orbit_flow_shift(d->fl, x, s, d->c, d->d);
        for (size_t k = 0; k < n2; k++) Jv[k] -= d->d[k] * ds;
    }
    size_t r = n2;
    if (job->period_free) Jv[r++] = dot(job->pt, v, n2);
    if (job->shift_free) Jv[r++] = dot(job->ps, v, n2);
    d->jv++;
    return BKF_OK;
}

static int kin_residual(N_Vector u, N_Vector f, void *data)
{
    nk_data *d = data;
    if (residual(N_VGetArrayPointer(u), N_VGetArrayPointer(f), d))
        /* a trial point that blew up is recoverable: the line search
         * backs off; cancellation and memory are not */
        return d->status == BKF_EBLOWUP || d->status == BKF_ENUMERIC ? 1 : -1;
    const orbit_newton_job *job = d->job;
    if (job->progress) {
        double frac = 1.0 - 1.0 / (1.0 + 0.25 * (double)d->fevals);
        if (job->progress(job->stage ? job->stage : "newton", frac, job->progress_data)) {
            d->status = bkf_error_set(&d->err, BKF_ECANCELED, "canceled by the progress hook");
            return -1;
        }
    }
    return 0;
}

static int kin_jtimes(N_Vector v, N_Vector Jv, N_Vector u, booleantype *new_u, void *data)
{
    nk_data *d = data;
    const double *x = N_VGetArrayPointer(u);
    if (*new_u) {
        /* a new Newton iterate: the step that led here */
        if (d->have_prev) {
            double m = 0.0;
            for (size_t i = 0; i < d->n; i++) m = fmax(m, fabs(x[i] - d->prev[i]));
            d->last_step = m;
        }
        memcpy(d->prev, x, d->n * sizeof *x);
        d->have_prev = 1;
        *new_u = SUNFALSE;
    }
    return jtimes(x, N_VGetArrayPointer(v), N_VGetArrayPointer(Jv), d) ? -1 : 0;
}

static int ls_atimes(void *data, N_Vector v, N_Vector z)
{
    nk_data *d = data;
    return jtimes(d->prev, N_VGetArrayPointer(v), N_VGetArrayPointer(z), d) ? -1 : 0;
}

static void kin_silent(int code, const char *module, const char *function, char *msg, void *data)
{
    (void)code, (void)module, (void)function, (void)msg, (void)data;
}

/* The solver's state: a context, vectors of the unknowns and SPGMR. */
typedef struct {
    SUNContext ctx;
    N_Vector x, scale, tmp;
    SUNLinearSolver LS;
    nk_data d;
} nk_setup;

static void nk_free(nk_setup *k)
{
    if (k->LS) SUNLinSolFree(k->LS);
    if (k->x) N_VDestroy(k->x);
    if (k->scale) N_VDestroy(k->scale);
    if (k->tmp) N_VDestroy(k->tmp);
    if (k->ctx) SUNContext_Free(&k->ctx);
    free(k->d.a);
    free(k->d.prev);
}

static int nk_init(nk_setup *k, orbit_flow *fl, const orbit_newton_job *job, const double *x,
                   double flow_tol, bkf_error *err)
{
    memset(k, 0, sizeof *k);
    size_t n2 = 2 * fl->N;
    nk_data *d = &k->d;
    d->fl = fl;
    d->job = job;
    d->n2 = n2;
    d->n = n2 + (size_t)job->period_free + (size_t)job->shift_free;
    d->T = x[n2];
    d->s = x[n2 + 1];
    d->flow_tol = flow_tol;
    d->a = malloc(4 * n2 * sizeof *d->a);
    d->prev = malloc(d->n * sizeof *d->prev);
    if (!d->a || !d->prev) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    d->b = d->a + n2;
    d->c = d->b + n2;
    d->d = d->c + n2;
    if (SUNContext_Create(NULL, &k->ctx)) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    k->x = N_VNew_Serial((sunindextype)d->n, k->ctx);
    k->scale = N_VNew_Serial((sunindextype)d->n, k->ctx);
    k->tmp = N_VNew_Serial((sunindextype)d->n, k->ctx);
    if (!k->x || !k->scale || !k->tmp) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    N_VConst(1.0, k->scale);
    double *xv = N_VGetArrayPointer(k->x);
    memcpy(xv, x, n2 * sizeof *x);
    size_t i = n2;
    if (job->period_free) xv[i++] = x[n2];
    if (job->shift_free) xv[i] = x[n2 + 1];
    k->LS = SUNLinSol_SPGMR(k->x, SUN_PREC_NONE, job->krylov_max, k->ctx);
    if (!k->LS) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    SUNLinSol_SPGMRSetMaxRestarts(k->LS, 3);
    return BKF_OK;
}

/* KINSOL's unknowns back into (u, T, s). */
static void nk_unpack(const nk_setup *k, const double *xv, double *x)
{
    size_t n2 = k->d.n2, i = n2;
    memcpy(x, xv, n2 * sizeof *x);
    x[n2] = k->d.job->period_free ? xv[i++] : k->d.T;
    x[n2 + 1] = k->d.job->shift_free ? xv[i] : k->d.s;
}

static const char *kin_flag_name(int flag)
{
    switch (flag) {
    case KIN_LINESEARCH_NONCONV: return "the line search could not reduce the residual";
    case KIN_MAXITER_REACHED: return "the iteration limit was reached";
    case KIN_MXNEWT_5X_EXCEEDED: return "five maximum-length Newton steps in a row (diverging)";
    case KIN_LINESEARCH_BCFAIL: return "the line search failed its condition repeatedly";
    case KIN_LINSOLV_NO_RECOVERY: return "the Krylov solver failed";
    case KIN_SYSFUNC_FAIL: return "the flow failed";
    case KIN_FIRST_SYSFUNC_ERR: return "the flow failed at the guess";
    case KIN_REPTD_SYSFUNC_ERR: return "the flow failed repeatedly";
    default: return "KINSOL failed";
    }
}

int orbit_newton(orbit_flow *fl, orbit_newton_job *job, double *x, bkf_error *err)
{
    nk_setup k;
    int s = nk_init(&k, fl, job, x, job->flow_tol, err);
    void *kin = NULL;
    if (s) goto done;
    kin = KINCreate(k.ctx);
    if (!kin || KINSetErrHandlerFn(kin, kin_silent, NULL) || KINInit(kin, kin_residual, k.x) ||
        KINSetUserData(kin, &k.d) || KINSetLinearSolver(kin, k.LS, NULL) ||
        KINSetJacTimesVecFn(kin, kin_jtimes) || KINSetFuncNormTol(kin, 1e-3 * job->tol) ||
        KINSetScaledStepTol(kin, 1e-4 * job->tol) ||
        KINSetNumMaxIters(kin, job->max_iter)) {
        s = bkf_error_set(err, BKF_ENOMEM, "KINSOL setup failed");
        goto done;
    }
    size_t flows0 = fl->flows;
    int rc = KINSol(kin, k.x, KIN_LINESEARCH, k.scale, k.scale);
    long nni = 0;
    KINGetNumNonlinSolvIters(kin, &nni);
    job->iterations = (size_t)nni;
    job->jv = k.d.jv;
    job->flows = fl->flows - flows0;
    job->last_step = k.d.last_step;
    if (k.d.status == BKF_ECANCELED || k.d.status == BKF_ENOMEM) {
        s = bkf_error_set(err, k.d.status, "%s", k.d.err.message);
        goto done;
    }
    nk_unpack(&k, N_VGetArrayPointer(k.x), x);
    /* the residual where it stopped, measured rather than taken from
     * KINSOL (which may stop on a trial point's norm) */
    double *F = N_VGetArrayPointer(k.tmp);
    k.d.status = 0;
    if ((s = residual(N_VGetArrayPointer(k.x), F, &k.d))) {
        bkf_error_set(err, s, "%s", k.d.err.message);
        goto done;
    }
    job->residual = maxabs(F, k.d.n2);
    int converged = rc == KIN_SUCCESS || rc == KIN_INITIAL_GUESS_OK || rc == KIN_STEP_LT_STPTOL;
    /* At the flow's noise level the line search can no longer reduce the
     * residual: a solution as far as this flow can tell, for the error
     * estimate to judge. */
    if (!converged && (rc == KIN_LINESEARCH_NONCONV || rc == KIN_MAXITER_REACHED ||
                       rc == KIN_LINESEARCH_BCFAIL) &&
        maxabs(F, k.d.n) <= job->tol)
        converged = 1;
    if (!converged) {
        s = bkf_error_set(err, BKF_ENUMERIC,
                          "Newton-Krylov did not converge after %ld iterations: %s (KINSOL "
                          "flag %d; residual %.3g)%s%s",
                          nni, kin_flag_name(rc), rc, job->residual,
                          k.d.status ? ": " : "", k.d.status ? k.d.err.message : "");
        goto done;
    }
    s = BKF_OK;
done:
    if (kin) KINFree(&kin);
    nk_free(&k);
    return s;
}

int orbit_newton_step(orbit_flow *fl, const orbit_newton_job *job, const double *x, double tol,
                      double *step, double *fnorm, bkf_error *err)
{
    nk_setup k;
    int s = nk_init(&k, fl, job, x, tol, err);
    if (s) goto done;
    nk_data *d = &k.d;
    double *xv = N_VGetArrayPointer(k.x);
    memcpy(d->prev, xv, d->n * sizeof *xv);
    double *F = N_VGetArrayPointer(k.tmp);
    if ((s = residual(xv, F, d))) {
        bkf_error_set(err, s, "%s", d->err.message);
        goto done;
    }
    *fnorm = maxabs(F, d->n2);
    double b2 = sqrt(dot(F, F, d->n));
    N_VScale(-1.0, k.tmp, k.tmp);
    N_Vector dx = N_VClone(k.x);
    if (!dx) {
        s = bkf_error_set(err, BKF_ENOMEM, "out of memory");
        goto done;
    }
    N_VConst(0.0, dx);
    if (SUNLinSolSetATimes(k.LS, d, ls_atimes) || SUNLinSolInitialize(k.LS) ||
        SUNLinSolSetup(k.LS, NULL)) {
        N_VDestroy(dx);
        s = bkf_error_set(err, BKF_ENUMERIC, "SPGMR setup failed");
        goto done;
    }
    int rc = b2 > 0 ? SUNLinSolSolve(k.LS, NULL, dx, k.tmp, 1e-6 * b2) : SUNLS_SUCCESS;
    if (d->status) {
        N_VDestroy(dx);
        s = bkf_error_set(err, d->status, "%s", d->err.message);
        goto done;
    }
    if (rc != SUNLS_SUCCESS && rc != SUNLS_RES_REDUCED) {
        N_VDestroy(dx);
        s = bkf_error_set(err, BKF_ENUMERIC, "SPGMR failed on the correction (flag %d)", rc);
        goto done;
    }
    double *dv = N_VGetArrayPointer(dx);
    size_t n2 = d->n2, i = n2;
    memcpy(step, dv, n2 * sizeof *dv);
    step[n2] = job->period_free ? dv[i++] : 0.0;
    step[n2 + 1] = job->shift_free ? dv[i] : 0.0;
    N_VDestroy(dx);
    s = BKF_OK;
done:
    nk_free(&k);
    return s;
}

int orbit_newton_tangent_check(orbit_flow *fl, const orbit_newton_job *job, const double *x,
                               const double *dir, double tol, double *rel, bkf_error *err)
{
    nk_setup k;
    int s = nk_init(&k, fl, job, x, tol, err);
    if (s) goto done;
    nk_data *d = &k.d;
    size_t n = d->n, n2 = d->n2;
    double *v = malloc(3 * n * sizeof *v);
    if (!v) {
        s = bkf_error_set(err, BKF_ENOMEM, "out of memory");
        goto done;
    }
    double *j1 = v + n, *j2 = j1 + n;
    memcpy(v, dir, n2 * sizeof *v);
    size_t i = n2;
    if (job->period_free) v[i++] = dir[n2];
    if (job->shift_free) v[i] = dir[n2 + 1];
    const double *xv = N_VGetArrayPointer(k.x);
    s = jtimes(xv, v, j1, d);
    if (!s) {
        d->flow_tol = 0.1 * tol;
        s = jtimes(xv, v, j2, d);
    }
    if (s) bkf_error_set(err, s, "%s", d->err.message);
    else {
        double diff = 0.0, big = 0.0;
        for (size_t r = 0; r < n2; r++) {
            diff = fmax(diff, fabs(j1[r] - j2[r]));
            big = fmax(big, fabs(j2[r]));
        }
        *rel = big > 0 ? diff / big : 0.0;
    }
    free(v);
done:
    nk_free(&k);
    return s;
}

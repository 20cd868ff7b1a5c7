/* The chain's rotating waves (see include/bkfront/chainwave.h and
 * docs/numerics.md, "The chain's rotating waves"). */
#include "bkfront/chainwave.h"
#include "bkfront/continuation.h"
#include "bkfront/cycle.h"
#include "bkfront/speeds.h"

#include <gsl/gsl_eigen.h>
#include <gsl/gsl_errno.h>
#include <gsl/gsl_linalg.h>
#include <gsl/gsl_odeiv2.h>
#include <cvodes/cvodes.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <math.h>
#include <stdlib.h>
#include <stdio.h>
#include <string.h>

#define NEWTON_MAX_ITER 25
/* Integration tolerance of the continuation in K from the uncoupled chain.
 * It only has to follow the branch and bracket its crossings of the target
 * K (each crossing is then solved by Newton at the caller's tol), so it is
 * loose whatever tol: at 1e-8 it cost 3/4 of the table for the same waves
 * (N = 20, 40: the same crossings and folds at 1e-4 as at 1e-8). */
#define CONT_TOL 1e-4

bkf_chainwave_options bkf_chainwave_options_default(void)
{
    bkf_chainwave_options o = {1e-8, 1, 200000, BKF_CHAINWAVE_STEPPER_AUTO};
    return o;
}

const char *bkf_chainwave_verdict_name(bkf_chainwave_verdict verdict)
{
    switch (verdict) {
    case BKF_CHAINWAVE_STABLE: return "yes";
    case BKF_CHAINWAVE_UNSTABLE: return "no";
    case BKF_CHAINWAVE_UNRESOLVED: return "unresolved";
    default: return "not computed";
    }
}

void bkf_chainwave_clear(bkf_chainwave *wave)
{
    if (!wave) return;
    free(wave->psi);
    free(wave->eta);
    wave->psi = wave->eta = NULL;
}

void bkf_chainwave_table_free(bkf_chainwave_table *table)
{
    if (!table) return;
    for (size_t i = 0; i < table->count; i++) bkf_chainwave_clear(&table->waves[i]);
    free(table->waves);
    table->waves = NULL;
    table->count = 0;
}

int bkf_chainwave_check(const bkf_model_params *p, size_t n, const bkf_chainwave_options *o,
                        bkf_error *err)
{
    if (!p || !o) return bkf_error_set(err, BKF_EINPUT, "chainwave: NULL argument");
    double gmax = o->stepper == BKF_CHAINWAVE_STEPPER_IMPLICIT ? BKF_CHAINWAVE_GAMMA_MAX
                                                               : BKF_CHAINWAVE_GAMMA_EXPLICIT;
    if (!(p->gamma > 0.0 && p->gamma <= gmax))
        return bkf_error_set(err, BKF_EINPUT,
                             "gamma = %g is outside (0, %g] for the chain's waves%s", p->gamma,
                             gmax, gmax < BKF_CHAINWAVE_GAMMA_MAX
                                       ? " (up to 100 with the implicit stepper)" : "");
    int s = bkf_model_check_c(p->c, err);
    if (!s) s = bkf_model_check_nu_active(p->nu, err);
    if (!s) s = bkf_model_check_positive("S", p->S, err);
    if (s) return s;
    if (p->N < BKF_CHAINWAVE_N_MIN || p->N > BKF_CHAINWAVE_N_MAX)
        return bkf_error_set(err, BKF_EINPUT, "N = %zu blocks is outside [%d, %d]", p->N,
                             BKF_CHAINWAVE_N_MIN, BKF_CHAINWAVE_N_MAX);
    if (n < 1 || n > p->N)
        return bkf_error_set(err, BKF_EINPUT, "n = %zu is outside [1, N = %zu]", n, p->N);
    if (!(o->tol >= BKF_CHAINWAVE_TOL_MIN && o->tol <= BKF_CHAINWAVE_TOL_MAX))
        return bkf_error_set(err, BKF_EINPUT, "tol = %g is outside [%g, %g]", o->tol,
                             BKF_CHAINWAVE_TOL_MIN, BKF_CHAINWAVE_TOL_MAX);
    if (o->max_steps < 1)
        return bkf_error_set(err, BKF_EINPUT, "max_steps = 0 must be >= 1");
    if (o->stepper != BKF_CHAINWAVE_STEPPER_AUTO && o->stepper != BKF_CHAINWAVE_STEPPER_EXPLICIT &&
        o->stepper != BKF_CHAINWAVE_STEPPER_IMPLICIT)
        return bkf_error_set(err, BKF_EINPUT, "stepper = %d is not auto (0), explicit (1) or "
                             "implicit (2)", (int)o->stepper);
    return BKF_OK;
}

/* ------------------------------------------------------------- the flow */

/* The chain and its variational equations: y = (psi, eta) followed by
 * ncols columns (w_psi, w_eta); with sens, the last column is d/dK. */
typedef struct {
    size_t N;
    double gamma, nu, K;
    size_t ncols;
    int sens;
    bkf_chainwave_param sens_param; /* what the last column differentiates:
                                       K (h, S, c through K), nu or gamma */
    double *dphi; /* gamma (psi_i^2 - 1) at the current stage */
    size_t max_steps;
    size_t steps;
    bkf_chainwave_stepper stepper;
} flow_ctx;

static double lap(const double *x, size_t i, size_t N)
{
    return x[(i + 1) % N] - 2.0 * x[i] + x[(i + N - 1) % N];
}

/* The linear part of the eta equation, -(x_i - K lap(x)_i) / gamma, for one
 * column: the ring's ends apart so that the inner loop has no modulo and
 * vectorises (the variational columns are most of the work). */
static void eta_coupling(const double *x, double *f, size_t N, double a, double b)
{
    f[0] = a * x[0] + b * (x[1] + x[N - 1]);
    for (size_t i = 1; i + 1 < N; i++) f[i] = a * x[i] + b * (x[i + 1] + x[i - 1]);
    f[N - 1] = a * x[N - 1] + b * (x[0] + x[N - 2]);
}

/* The chain's field at y = (psi, eta) into f; c->dphi keeps the friction's
 * slopes there for the variational columns. */
static void base_rhs(flow_ctx *c, const double *y, double *f)
{
    size_t N = c->N;
    double g = c->gamma, K = c->K;
    /* -(x - K (x+ - 2x + x-))/g = a x + b (x+ + x-) */
    double a = -(1.0 + 2.0 * K) / g, b = K / g;
    const double *psi = y, *eta = y + N;
    for (size_t i = 0; i < N; i++) {
        double p = psi[i];
        c->dphi[i] = g * (p * p - 1.0);
        f[i] = g * (eta[i] - (p * p * p / 3.0 - p));
    }
    eta_coupling(psi, f + N, N, a, b);
    for (size_t i = 0; i < N; i++) f[N + i] += c->nu / g;
}

/* One variational column: fw = J(y) w, with c->dphi set by base_rhs at y. */
static void column_rhs(const flow_ctx *c, const double *w, double *fw)
{
    size_t N = c->N;
    double g = c->gamma, a = -(1.0 + 2.0 * c->K) / g, b = c->K / g;
    for (size_t i = 0; i < N; i++) fw[i] = g * w[N + i] - c->dphi[i] * w[i];
    eta_coupling(w, fw + N, N, a, b);
}

/* The inhomogeneous part of the sensitivity column: d(field)/d(parameter)
 * at y, added to fk. */
static void param_rhs(const flow_ctx *c, const double *y, double *fk)
{
    size_t N = c->N;
    double g = c->gamma, K = c->K;
    const double *psi = y, *eta = y + N;
    if (c->sens_param == BKF_CHAINWAVE_PARAM_NU)
        for (size_t i = 0; i < N; i++) fk[N + i] += 1.0 / g;
    else if (c->sens_param == BKF_CHAINWAVE_PARAM_GAMMA)
        for (size_t i = 0; i < N; i++) {
            double p = psi[i];
            fk[i] += eta[i] - (p * p * p / 3.0 - p);
            fk[N + i] += (p - c->nu - K * lap(psi, i, N)) / (g * g);
        }
    else
        for (size_t i = 0; i < N; i++) fk[N + i] += lap(psi, i, N) / g;
}

static int chain_rhs(double t, const double *y, double *f, void *data)
{
    (void)t;
    flow_ctx *c = data;
    size_t N = c->N;
    base_rhs(c, y, f);
    for (size_t j = 0; j < c->ncols; j++) column_rhs(c, y + 2 * N * (j + 1), f + 2 * N * (j + 1));
    if (c->sens) param_rhs(c, y, f + 2 * N * c->ncols);
    return GSL_SUCCESS;
}

/* ------------------------------------------- the implicit flow (CVODES) */

/* Above BKF_CHAINWAVE_GAMMA_EXPLICIT the blocks' cycle is a stiff
 * relaxation oscillation: on its slow branches the friction's slope
 * gamma (psi^2 - 1) ~ 3 gamma limits an explicit step to ~1/gamma while
 * the branch takes ~gamma.  There the flow and its variational columns
 * are integrated by CVODES: BDF on the 2N states with the analytic
 * Jacobian (dense: the ring's corners make a band as wide as the chain),
 * the 2N + 1 columns as forward sensitivities (staggered corrector on the
 * same Newton matrix, their errors controlled too). */
typedef struct {
    flow_ctx *c;
    char message[200];
} implicit_ctx;

static int cv_rhs(realtype t, N_Vector y, N_Vector f, void *data)
{
    (void)t;
    implicit_ctx *x = data;
    base_rhs(x->c, N_VGetArrayPointer(y), N_VGetArrayPointer(f));
    return 0;
}

static int cv_jac(realtype t, N_Vector y, N_Vector f, SUNMatrix J, void *data, N_Vector t1,
                  N_Vector t2, N_Vector t3)
{
    (void)t, (void)f, (void)t1, (void)t2, (void)t3;
    implicit_ctx *x = data;
    const flow_ctx *c = x->c;
    size_t N = c->N;
    const double *psi = N_VGetArrayPointer(y);
    double g = c->gamma, a = -(1.0 + 2.0 * c->K) / g, b = c->K / g;
    SUNMatZero(J);
    for (size_t i = 0; i < N; i++) {
        SM_ELEMENT_D(J, i, i) = -g * (psi[i] * psi[i] - 1.0);
        SM_ELEMENT_D(J, i, N + i) = g;
        SM_ELEMENT_D(J, N + i, i) += a;
        SM_ELEMENT_D(J, N + i, (i + 1) % N) += b;
        SM_ELEMENT_D(J, N + i, (i + N - 1) % N) += b;
    }
    return 0;
}

static int cv_sens(int ns, realtype t, N_Vector y, N_Vector ydot, N_Vector *yS, N_Vector *ySdot,
                   void *data, N_Vector t1, N_Vector t2)
{
    (void)t, (void)ydot, (void)t1, (void)t2;
    implicit_ctx *x = data;
    flow_ctx *c = x->c;
    const double *Y = N_VGetArrayPointer(y);
    for (size_t i = 0; i < c->N; i++) c->dphi[i] = c->gamma * (Y[i] * Y[i] - 1.0);
    for (int j = 0; j < ns; j++)
        column_rhs(c, N_VGetArrayPointer(yS[j]), N_VGetArrayPointer(ySdot[j]));
    param_rhs(c, Y, N_VGetArrayPointer(ySdot[ns - 1]));
    return 0;
}

static void cv_errors(int code, const char *module, const char *function, char *msg, void *data)
{
    (void)code, (void)module;
    implicit_ctx *x = data;
    snprintf(x->message, sizeof x->message, "%s: %s", function, msg);
}

/* BDF's global error is a multiple of its local tolerance, and its step
 * sequence (so its map) jumps with x at that level, which stalls Newton
 * above the caller's tolerance; the local tolerance is this much tighter
 * than the explicit stepper's. */
#ifndef IMPLICIT_TOL_FACTOR
#define IMPLICIT_TOL_FACTOR 1e-3
#endif

static int flow_implicit(flow_ctx *c, const double *u, double tau, double tol, double *out,
                         double *M, double *dk, bkf_error *err)
{
    size_t N = c->N, n2 = 2 * N;
    int jac = M != NULL, ns = (int)n2 + 1;
    implicit_ctx x = {c, ""};
    tol *= IMPLICIT_TOL_FACTOR;
    SUNContext ctx = NULL;
    void *cv = NULL;
    N_Vector y = NULL, *yS = NULL;
    SUNMatrix A = NULL;
    SUNLinearSolver LS = NULL;
    int s = BKF_OK;
    if (SUNContext_Create(NULL, &ctx) || !(y = N_VNew_Serial((sunindextype)n2, ctx)) ||
        !(cv = CVodeCreate(CV_BDF, ctx)) ||
        !(A = SUNDenseMatrix((sunindextype)n2, (sunindextype)n2, ctx)) ||
        !(LS = SUNLinSol_Dense(y, A, ctx)) || (jac && !(yS = N_VCloneVectorArray(ns, y)))) {
        s = bkf_error_set(err, BKF_ENOMEM, "chainwave: out of memory");
        goto done;
    }
    memcpy(N_VGetArrayPointer(y), u, n2 * sizeof(double));
    if (jac)
        for (int j = 0; j < ns; j++) {
            N_VConst(0.0, yS[j]);
            if (j < (int)n2) N_VGetArrayPointer(yS[j])[j] = 1.0;
        }
    if (CVodeSetErrHandlerFn(cv, cv_errors, &x) || CVodeInit(cv, cv_rhs, 0.0, y) ||
        CVodeSetUserData(cv, &x) || CVodeSStolerances(cv, tol, tol) ||
        CVodeSetLinearSolver(cv, LS, A) || CVodeSetJacFn(cv, cv_jac) ||
        CVodeSetMaxNumSteps(cv, (long)c->max_steps) || CVodeSetStopTime(cv, tau)) {
        s = bkf_error_set(err, BKF_ENUMERIC, "chainwave: CVODES set-up failed: %s", x.message);
        goto done;
    }
    if (jac) {
        double *atol = malloc((size_t)ns * sizeof *atol);
        if (!atol) {
            s = bkf_error_set(err, BKF_ENOMEM, "chainwave: out of memory");
            goto done;
        }
        for (int j = 0; j < ns; j++) atol[j] = tol;
        int bad = CVodeSensInit(cv, ns, CV_STAGGERED, cv_sens, yS) ||
                  CVodeSensSStolerances(cv, tol, atol) || CVodeSetSensErrCon(cv, SUNTRUE);
        free(atol);
        if (bad) {
            s = bkf_error_set(err, BKF_ENUMERIC, "chainwave: CVODES set-up failed: %s",
                              x.message);
            goto done;
        }
    }
    double t = 0.0;
    int cs = CVode(cv, tau, y, &t, CV_NORMAL);
    long nst = 0;
    CVodeGetNumSteps(cv, &nst);
    c->steps += (size_t)nst;
    if (cs == CV_TOO_MUCH_WORK) {
        s = bkf_error_set(err, BKF_EBUDGET, "chainwave: the flow over tau = %g needs more than "
                          "max_steps = %zu steps", tau, c->max_steps);
        goto done;
    }
    if (cs < 0) {
        s = bkf_error_set(err, BKF_ENUMERIC, "chainwave: integration over tau = %g failed (%s)",
                          tau, x.message);
        goto done;
    }
    if (jac && CVodeGetSens(cv, &t, yS)) {
        s = bkf_error_set(err, BKF_ENUMERIC, "chainwave: CVODES sensitivities: %s", x.message);
        goto done;
    }
    const double *Y = N_VGetArrayPointer(y);
    for (size_t i = 0; i < n2; i++)
        if (!isfinite(Y[i])) {
            s = bkf_error_set(err, BKF_EBLOWUP, "chainwave: the flow over tau = %g blew up", tau);
            goto done;
        }
    memcpy(out, Y, n2 * sizeof *out);
    if (jac) {
        for (size_t j = 0; j < n2; j++) {
            const double *w = N_VGetArrayPointer(yS[j]);
            for (size_t i = 0; i < n2; i++) M[i * n2 + j] = w[i];
        }
        memcpy(dk, N_VGetArrayPointer(yS[n2]), n2 * sizeof *dk);
    }
done:
    if (yS) N_VDestroyVectorArray(yS, ns);
    if (LS) SUNLinSolFree(LS);
    if (A) SUNMatDestroy(A);
    if (cv) CVodeFree(&cv);
    if (y) N_VDestroy(y);
    if (ctx) SUNContext_Free(&ctx);
    return s;
}

/* Integrates u over tau at relative and absolute tolerance tol; with jac,
 * also M = dPhi/du (2N x 2N, row-major, into M) and dPhi/dK (into dk). */
static int flow(flow_ctx *c, const double *u, double tau, double tol, double *out, double *M,
                double *dk, bkf_error *err)
{
    if (c->stepper == BKF_CHAINWAVE_STEPPER_IMPLICIT ||
        (c->stepper == BKF_CHAINWAVE_STEPPER_AUTO && c->gamma > BKF_CHAINWAVE_GAMMA_EXPLICIT))
        return flow_implicit(c, u, tau, tol, out, M, dk, err);
    size_t N = c->N, n2 = 2 * N;
    int jac = M != NULL;
    c->ncols = jac ? n2 + 1 : 0;
    c->sens = jac;
    size_t dim = n2 * (1 + c->ncols);
    double *y = calloc(dim, sizeof *y);
    if (!y) return bkf_error_set(err, BKF_ENOMEM, "chainwave: out of memory");
    memcpy(y, u, n2 * sizeof *y);
    if (jac)
        for (size_t j = 0; j < n2; j++) y[n2 * (j + 1) + j] = 1.0;
    gsl_odeiv2_system sys = {chain_rhs, NULL, dim, c};
    double h0 = fmin(0.05, fabs(tau) / 4.0);
    if (!(h0 > 0.0)) h0 = 1e-3;
    gsl_odeiv2_driver *d =
        gsl_odeiv2_driver_alloc_y_new(&sys, gsl_odeiv2_step_rk8pd, h0, tol, tol);
    if (!d) {
        free(y);
        return bkf_error_set(err, BKF_ENOMEM, "chainwave: out of memory");
    }
    gsl_odeiv2_driver_set_nmax(d, c->max_steps);
    double t = 0.0;
    int gs = gsl_odeiv2_driver_apply(d, &t, tau, y);
    c->steps += d->n;
    gsl_odeiv2_driver_free(d);
    int s = BKF_OK;
    if (gs == GSL_EMAXITER)
        s = bkf_error_set(err, BKF_EBUDGET,
                          "chainwave: the flow over tau = %g needs more than max_steps = %zu "
                          "steps", tau, c->max_steps);
    else if (gs != GSL_SUCCESS)
        s = bkf_error_set(err, BKF_ENUMERIC, "chainwave: integration over tau = %g failed (%s)",
                          tau, gsl_strerror(gs));
    for (size_t i = 0; !s && i < dim; i++)
        if (!isfinite(y[i]))
            s = bkf_error_set(err, BKF_EBLOWUP, "chainwave: the flow over tau = %g blew up", tau);
    if (!s) {
        memcpy(out, y, n2 * sizeof *y);
        if (jac) {
            for (size_t j = 0; j < n2; j++)
                for (size_t i = 0; i < n2; i++) M[i * n2 + j] = y[n2 * (j + 1) + i];
            memcpy(dk, y + n2 * (n2 + 1), n2 * sizeof *y);
        }
    }
    free(y);
    return s;
}

/* (shift u)_k = u of the next block. */
static size_t next_index(size_t k, size_t N)
{
    return k < N ? (k + 1) % N : N + (k - N + 1) % N;
}

static void field(const flow_ctx *c, const double *u, double *f)
{
    size_t N = c->N;
    for (size_t i = 0; i < N; i++) {
        double p = u[i];
        f[i] = c->gamma * (u[N + i] - (p * p * p / 3.0 - p));
        f[N + i] = -(p - c->nu - c->K * lap(u, i, N)) / c->gamma;
    }
}

/* Residual G = [Phi_tau(u) - shift(u); psi_0 - nu] at x = (u, tau) and, with
 * J (row stride `stride` >= 2N + 1), its Jacobian in (u, tau) and, if
 * stride > 2N + 1, in K in column 2N + 1. */
typedef struct {
    double *phi, *M, *dk, *fphi;
} work;

static int residual(flow_ctx *c, work *w, const double *x, double tol, double *G, double *J,
                    size_t stride, bkf_error *err)
{
    size_t N = c->N, n2 = 2 * N;
    int s = flow(c, x, x[n2], tol, w->phi, J ? w->M : NULL, w->dk, err);
    if (s) return s;
    for (size_t k = 0; k < n2; k++) G[k] = w->phi[k] - x[next_index(k, N)];
    G[n2] = x[0] - c->nu;
    if (!J) return BKF_OK;
    field(c, w->phi, w->fphi);
    for (size_t k = 0; k < n2; k++) {
        double *row = J + k * stride;
        memcpy(row, w->M + k * n2, n2 * sizeof *row);
        row[next_index(k, N)] -= 1.0;
        row[n2] = w->fphi[k];
        if (stride > n2 + 1) row[n2 + 1] = w->dk[k];
    }
    double *last = J + n2 * stride;
    memset(last, 0, stride * sizeof *last);
    last[0] = 1.0;
    return BKF_OK;
}

static int work_alloc(work *w, size_t N)
{
    size_t n2 = 2 * N;
    w->phi = malloc(n2 * sizeof *w->phi);
    w->M = malloc(n2 * n2 * sizeof *w->M);
    w->dk = malloc(n2 * sizeof *w->dk);
    w->fphi = malloc(n2 * sizeof *w->fphi);
    return w->phi && w->M && w->dk && w->fphi;
}

static void work_free(work *w)
{
    free(w->phi);
    free(w->M);
    free(w->dk);
    free(w->fphi);
}

static double max_abs(const double *x, size_t n)
{
    double m = 0.0;
    for (size_t i = 0; i < n; i++) m = fmax(m, fabs(x[i]));
    return m;
}

/* The Newton matrix of one wave, LU-factorised, kept across iterations and
 * across the two tolerances of solve_x: a variational integration costs
 * 2N + 2 plain ones, so the matrix is rebuilt only when the chord
 * iteration stops contracting. */
typedef struct {
    size_t n;          /* 2N + 1 */
    double *J, *G;
    gsl_permutation *perm;
    gsl_vector *dx;
    int factored;
} newton_lu;

static int newton_lu_alloc(newton_lu *L, size_t N)
{
    L->n = 2 * N + 1;
    L->J = malloc(L->n * L->n * sizeof *L->J);
    L->G = malloc(L->n * sizeof *L->G);
    L->perm = gsl_permutation_alloc(L->n);
    L->dx = gsl_vector_alloc(L->n);
    L->factored = 0;
    return L->J && L->G && L->perm && L->dx;
}

static void newton_lu_free(newton_lu *L)
{
    free(L->J);
    free(L->G);
    if (L->perm) gsl_permutation_free(L->perm);
    if (L->dx) gsl_vector_free(L->dx);
}

/* Residual at x into L->G and, with jac, the Newton matrix, factorised. */
static int newton_eval(flow_ctx *c, work *w, newton_lu *L, const double *x, double tol,
                       int jac, bkf_error *err)
{
    int s = residual(c, w, x, tol, L->G, jac ? L->J : NULL, L->n, err);
    if (s || !jac) return s;
    L->factored = 0;
    gsl_matrix_view Jm = gsl_matrix_view_array(L->J, L->n, L->n);
    int sign;
    if (gsl_linalg_LU_decomp(&Jm.matrix, L->perm, &sign))
        return bkf_error_set(err, BKF_ENUMERIC, "chainwave: singular Newton matrix (a fold?)");
    for (size_t k = 0; k < L->n; k++)
        if (L->J[k * L->n + k] == 0.0 || !isfinite(L->J[k * L->n + k]))
            return bkf_error_set(err, BKF_ENUMERIC, "chainwave: singular Newton matrix (a fold?)");
    L->factored = 1;
    return BKF_OK;
}

/* Chord-Newton at fixed K on x = (u, tau), integrations at tolerance tol,
 * until the step is below tol (relative to max(|x|, 1)); the matrix is
 * L's if factored (a previous solve nearby), else built at x, and rebuilt
 * where the steps stop shrinking fast.  With final_jac the last evaluation
 * at the solution carries the variational matrix (w->M: the monodromy
 * there; L is refactorised with it), else it is a plain flow; either way
 * *res_out is the residual at the returned x. */
static int newton(flow_ctx *c, work *w, newton_lu *L, double *x, double tol, int final_jac,
                  size_t *iterations, double *res_out, bkf_error *err)
{
    size_t n = L->n;
    int fresh = !L->factored;
    int s = newton_eval(c, w, L, x, tol, fresh, err);
    int converged = 0;
    double prev = INFINITY;
    for (int it = 0; !s && it < NEWTON_MAX_ITER; it++) {
        (*iterations)++;
        gsl_matrix_view Jm = gsl_matrix_view_array(L->J, n, n);
        gsl_vector_view Gv = gsl_vector_view_array(L->G, n);
        if (gsl_linalg_LU_solve(&Jm.matrix, L->perm, &Gv.vector, L->dx)) {
            s = bkf_error_set(err, BKF_ENUMERIC, "chainwave: singular Newton matrix (a fold?)");
            break;
        }
        double step = 0.0;
        for (size_t k = 0; k < n; k++) {
            double d = gsl_vector_get(L->dx, k);
            x[k] -= d;
            step = fmax(step, fabs(d) / fmax(1.0, fabs(x[k])));
        }
        if (!(x[n - 1] > 0.0) || !isfinite(step)) {
            s = bkf_error_set(err, BKF_ENUMERIC, "chainwave: Newton left tau > 0");
            break;
        }
        /* the monodromy at x feeds the multipliers, which can be far more
           sensitive to x than v is (gamma 10, n 6: 8e-6 from stopping at a
           step of tol); chord steps are cheap, so go on to 1e-3 tol, or
           until rounding stops the steps shrinking */
        if (step <= 1e-3 * tol || (step <= tol && step > 0.5 * prev)) {
            converged = 1;
            break;
        }
        if (it > 6 && step > prev && fresh) {
            s = bkf_error_set(err, BKF_ENUMERIC, "chainwave: Newton does not converge "
                              "(step %.3g after %d iterations)", step, it + 1);
            break;
        }
        /* a chord step that contracts by less than 10 is not worth
           keeping its matrix: rebuild it at the new point */
        int rebuild = step > 0.1 * prev;
        s = newton_eval(c, w, L, x, tol, rebuild, err);
        fresh = rebuild;
        prev = step;
    }
    if (!s && !converged)
        s = bkf_error_set(err, BKF_ENUMERIC, "chainwave: Newton did not converge in %d "
                          "iterations", NEWTON_MAX_ITER);
    if (!s && final_jac) {
        /* The monodromy is the exact derivative of the discrete map of the
           flow that carries the variational columns (its own, shorter,
           steps), and its multipliers are those of that map's fixed point:
           one full Newton step on that flow moves x there from the plain
           flows' fixed point, which is off by the two flows' truncation
           errors (gamma 10, n 6, |m| 200: error estimates of 20 tol without
           it, against 0.4 tol). */
        s = newton_eval(c, w, L, x, tol, 1, err);
        gsl_matrix_view Jm = gsl_matrix_view_array(L->J, n, n);
        gsl_vector_view Gv = gsl_vector_view_array(L->G, n);
        if (!s && gsl_linalg_LU_solve(&Jm.matrix, L->perm, &Gv.vector, L->dx))
            s = bkf_error_set(err, BKF_ENUMERIC, "chainwave: singular Newton matrix (a fold?)");
        for (size_t k = 0; !s && k < n; k++) x[k] -= gsl_vector_get(L->dx, k);
        if (!s) (*iterations)++;
    }
    if (!s) s = newton_eval(c, w, L, x, tol, final_jac, err);
    if (!s) {
        (*iterations)++;
        *res_out = max_abs(L->G, n);
    }
    return s;
}

/* Multipliers of shift^-1 o Phi_tau from M: the one nearest 1 is the
 * trivial one, the largest modulus of the others the leading one. */
static int multipliers(const flow_ctx *c, const double *M, double *triv_err, double *re,
                       double *im, bkf_error *err)
{
    size_t N = c->N, n2 = 2 * N;
    gsl_matrix *A = gsl_matrix_alloc(n2, n2);
    gsl_vector_complex *ev = gsl_vector_complex_alloc(n2);
    gsl_eigen_nonsymm_workspace *ws = gsl_eigen_nonsymm_alloc(n2);
    int s = (A && ev && ws) ? BKF_OK : bkf_error_set(err, BKF_ENOMEM, "chainwave: out of memory");
    if (!s) {
        /* (shift^-1 M)_k = M of the previous block: row k of M is row next(k) of A. */
        for (size_t k = 0; k < n2; k++)
            for (size_t j = 0; j < n2; j++)
                gsl_matrix_set(A, next_index(k, N), j, M[k * n2 + j]);
        if (gsl_eigen_nonsymm(A, ev, ws))
            s = bkf_error_set(err, BKF_ENUMERIC, "chainwave: eigenvalues did not converge");
    }
    if (!s) {
        size_t itriv = 0;
        double dmin = INFINITY;
        for (size_t k = 0; k < n2; k++) {
            gsl_complex z = gsl_vector_complex_get(ev, k);
            double d = hypot(GSL_REAL(z) - 1.0, GSL_IMAG(z));
            if (d < dmin) dmin = d, itriv = k;
        }
        *triv_err = dmin;
        double amax = -1.0;
        for (size_t k = 0; k < n2; k++) {
            if (k == itriv) continue;
            gsl_complex z = gsl_vector_complex_get(ev, k);
            double a = hypot(GSL_REAL(z), GSL_IMAG(z));
            if (a > amax) amax = a, *re = GSL_REAL(z), *im = fabs(GSL_IMAG(z));
        }
    }
    if (A) gsl_matrix_free(A);
    if (ev) gsl_vector_complex_free(ev);
    if (ws) gsl_eigen_nonsymm_free(ws);
    return s;
}

static void flow_init(flow_ctx *c, const bkf_model_params *p, const bkf_chainwave_options *o)
{
    memset(c, 0, sizeof *c);
    c->N = p->N;
    c->gamma = p->gamma;
    c->nu = p->nu;
    double h = p->S / (double)p->N;
    c->K = p->c * p->c / (h * h);
    c->max_steps = o->max_steps;
    c->stepper = o->stepper;
}

/* Solve from x at two integration tolerances (tol/10, tol/100) and fill wave. */
static int solve_x(flow_ctx *c, work *w, const bkf_model_params *p, size_t n, double *x,
                   const bkf_chainwave_options *o, bkf_chainwave *wave, bkf_error *err)
{
    size_t N = p->N, n2 = 2 * N;
    memset(wave, 0, sizeof *wave);
    wave->N = N;
    wave->n = n;
    wave->h = p->S / (double)N;
    wave->K = c->K;
    double res = 0.0, triv[2] = {NAN, NAN}, mre[2] = {NAN, NAN}, mim[2] = {NAN, NAN};
    double tau[2];
    size_t steps0 = c->steps;
    newton_lu L;
    int s = newton_lu_alloc(&L, N) ? BKF_OK
                                   : bkf_error_set(err, BKF_ENOMEM, "chainwave: out of memory");
    for (int pass = 0; pass < 2 && !s; pass++) {
        double itol = o->tol * (pass == 0 ? 0.1 : 0.01);
        s = newton(c, w, &L, x, itol, o->stability, &wave->newton_iterations, &res, err);
        if (!s) tau[pass] = x[n2];
        if (!s && o->stability)
            s = multipliers(c, w->M, &triv[pass], &mre[pass], &mim[pass], err);
    }
    wave->steps = c->steps - steps0;
    newton_lu_free(&L);
    if (s) return s;
    wave->psi = malloc(N * sizeof *wave->psi);
    wave->eta = malloc(N * sizeof *wave->eta);
    if (!wave->psi || !wave->eta) {
        bkf_chainwave_clear(wave);
        return bkf_error_set(err, BKF_ENOMEM, "chainwave: out of memory");
    }
    memcpy(wave->psi, x, N * sizeof *x);
    memcpy(wave->eta, x + N, N * sizeof *x);
    wave->psi_min = wave->psi_max = x[0];
    for (size_t i = 0; i < N; i++) {
        wave->psi_min = fmin(wave->psi_min, x[i]);
        wave->psi_max = fmax(wave->psi_max, x[i]);
    }
    wave->tau = tau[1];
    /* the Newton residual counts as part of the error of tau */
    wave->tau_err = fabs(tau[1] - tau[0]) + res;
    wave->v = wave->h / wave->tau;
    wave->v_err = wave->v * wave->tau_err / wave->tau;
    wave->P = (double)N * wave->tau / (double)n;
    wave->P_err = (double)N * wave->tau_err / (double)n;
    wave->residual = res;
    wave->verdict = BKF_CHAINWAVE_NOT_COMPUTED;
    wave->mult_re = wave->mult_im = wave->mult_abs = wave->mult_abs_err = NAN;
    wave->sigma_max = wave->sigma_max_err = wave->trivial_err = NAN;
    if (o->stability) {
        wave->mult_re = mre[1];
        wave->mult_im = mim[1];
        wave->mult_abs = hypot(mre[1], mim[1]);
        wave->trivial_err = triv[1];
        /* the gauge bounds how far rounding and truncation moved the
           spectrum; the change between tolerances, how far the tighter one
           can still be off */
        wave->mult_abs_err = fabs(wave->mult_abs - hypot(mre[0], mim[0])) + triv[1];
        wave->sigma_max = log(wave->mult_abs) / wave->tau;
        wave->sigma_max_err = wave->mult_abs_err / (wave->mult_abs * wave->tau);
        if (wave->mult_abs - wave->mult_abs_err > 1.0) wave->verdict = BKF_CHAINWAVE_UNSTABLE;
        else if (wave->mult_abs + wave->mult_abs_err < 1.0) wave->verdict = BKF_CHAINWAVE_STABLE;
        else wave->verdict = BKF_CHAINWAVE_UNRESOLVED;
    }
    if (wave->v_err > o->tol * wave->v)
        s = bkf_error_set(err, BKF_ETOL, "chainwave: estimated relative error %.3g of v for "
                          "n = %zu exceeds tol %g", wave->v_err / wave->v, n, o->tol);
    /* absolute on |m| up to 1, relative beyond: the verdict is decided at
       |m| = 1, and above it |m| is exp(sigma_max tau), whose relative error
       is the absolute error of the growth exponent (the continuum's sigma
       is asked to tol absolute); an absolute tol on |m| ~ 200 (gamma 10,
       n 6) asked 14 digits of it and refused whole tables */
    else if (o->stability && wave->mult_abs_err > o->tol * fmax(1.0, wave->mult_abs))
        s = bkf_error_set(err, BKF_ETOL, "chainwave: estimated error %.3g of the leading "
                          "multiplier |m| = %.6g for n = %zu exceeds tol %g x max(1, |m|)",
                          wave->mult_abs_err, wave->mult_abs, n, o->tol);
    if (s) bkf_chainwave_clear(wave);
    return s;
}

int bkf_chainwave_solve(const bkf_model_params *p, size_t n, const double *psi,
                        const double *eta, double tau, const bkf_chainwave_options *o,
                        bkf_chainwave *wave, bkf_error *err)
{
    int s = bkf_chainwave_check(p, n, o, err);
    if (s) return s;
    if (!psi || !eta || !wave) return bkf_error_set(err, BKF_EINPUT, "chainwave: NULL argument");
    if (!(tau > 0.0 && isfinite(tau)))
        return bkf_error_set(err, BKF_EINPUT, "tau = %g must be positive and finite", tau);
    memset(wave, 0, sizeof *wave);
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    size_t N = p->N;
    flow_ctx c;
    flow_init(&c, p, o);
    work w;
    double *x = malloc((2 * N + 1) * sizeof *x);
    c.dphi = malloc(N * sizeof *c.dphi);
    if (!work_alloc(&w, N) || !x || !c.dphi) {
        s = bkf_error_set(err, BKF_ENOMEM, "chainwave: out of memory");
    } else {
        memcpy(x, psi, N * sizeof *x);
        memcpy(x + N, eta, N * sizeof *x);
        x[2 * N] = tau;
        s = solve_x(&c, &w, p, n, x, o, wave, err);
    }
    work_free(&w);
    free(x);
    free(c.dphi);
    bkf_gsl_handler_pop(handler);
    return s;
}

/* The blocks on the cycle of f'' + mu (f^2 - 1) f' + f = nu, block i at
 * z0 + i dz, with t = stretch z: psi = f, eta = f'/(stretch gamma) + phi(f). */
static int sample_cycle(double mu, double nu, double gamma, double stretch, size_t N, double dz,
                        double tol, double *psi, double *eta, bkf_error *err)
{
    bkf_cycle *cyc = bkf_cycle_alloc();
    double *z = malloc(N * sizeof *z), *f = malloc(N * sizeof *f), *fp = malloc(N * sizeof *fp);
    size_t *idx = malloc(N * sizeof *idx);
    int s = (cyc && z && f && fp && idx) ? BKF_OK
                                         : bkf_error_set(err, BKF_ENOMEM, "chainwave: out of memory");
    bkf_cycle_options co = bkf_cycle_options_default();
    co.tol = fmax(tol, 1e-13);
    if (!s) s = bkf_cycle_solve(cyc, mu, nu, &co, err);
    if (!s) {
        double T = bkf_cycle_get(cyc)->period;
        /* the sampler wants ascending z: insertion sort of the phases */
        for (size_t i = 0; i < N; i++) {
            double zi = fmod((double)i * dz, T);
            if (zi < 0.0) zi += T;
            size_t k = i;
            while (k > 0 && z[k - 1] > zi) {
                z[k] = z[k - 1];
                idx[k] = idx[k - 1];
                k--;
            }
            z[k] = zi;
            idx[k] = i;
        }
        s = bkf_cycle_profile_sample(cyc, z, N, f, fp, err);
    }
    if (!s)
        for (size_t k = 0; k < N; k++) {
            double x = f[k];
            psi[idx[k]] = x;
            eta[idx[k]] = fp[k] / (stretch * gamma) + x * x * x / 3.0 - x;
        }
    bkf_cycle_free(cyc);
    free(z);
    free(f);
    free(fp);
    free(idx);
    return s;
}

int bkf_chainwave_from_continuum(const bkf_model_params *p, size_t n, size_t root_index,
                                 const bkf_chainwave_options *o, bkf_chainwave *wave,
                                 bkf_error *err)
{
    int s = bkf_chainwave_check(p, n, o, err);
    if (s) return s;
    if (!wave) return bkf_error_set(err, BKF_EINPUT, "chainwave: NULL argument");
    memset(wave, 0, sizeof *wave);
    bkf_speeds_options so = bkf_speeds_options_default();
    so.tol = 1e-10;
    so.n_from = so.n_to = n;
    bkf_speeds_table tab;
    s = bkf_speeds_find(p, &so, &tab, err);
    if (!s && (root_index < 1 || root_index > tab.count))
        s = bkf_error_set(err, BKF_EINPUT, "root = %zu is outside [1, %zu] (the continuum's "
                          "roots for n = %zu)", root_index, tab.count, n);
    double v = 0, mu = 0;
    if (!s) s = bkf_speeds_root_status(&tab.roots[root_index - 1], err);
    if (!s) {
        v = tab.roots[root_index - 1].v;
        mu = tab.roots[root_index - 1].mu;
    }
    bkf_speeds_table_free(&tab);
    if (s) return s;
    size_t N = p->N;
    double h = p->S / (double)N;
    double stretch = p->c > 0.0 ? sqrt(1.0 - p->c * p->c / (v * v)) : 1.0;
    double *psi = malloc(N * sizeof *psi), *eta = malloc(N * sizeof *eta);
    if (!psi || !eta) s = bkf_error_set(err, BKF_ENOMEM, "chainwave: out of memory");
    /* psi(x, t) = f((x/v + t)/stretch): block i is (i h / v)/stretch ahead in z */
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    if (!s) s = sample_cycle(mu, p->nu, p->gamma, stretch, N, h / (v * stretch), o->tol, psi,
                             eta, err);
    bkf_gsl_handler_pop(handler);
    if (!s) s = bkf_chainwave_solve(p, n, psi, eta, h / v, o, wave, err);
    free(psi);
    free(eta);
    return s;
}

/* ------------------------------------------------------ all roots of n */

typedef struct {
    flow_ctx *c;
    work *w;
    double tol;
    double Kt;            /* target coupling */
    size_t dim;           /* 2N + 2 */
    double *prev;         /* last accepted point */
    int have_prev;
    double *guesses;      /* crossings of Kt (dim each) */
    size_t nguess, capguess;
    size_t folds;
    int oom;
} cont_data;

static int cont_residual(const double *u, double *g, double *jac, void *data, bkf_error *err)
{
    cont_data *d = data;
    d->c->K = u[d->dim - 1];
    int s = residual(d->c, d->w, u, d->tol, g, jac, d->dim, err);
    /* a failed flow shrinks the step instead of ending the branch */
    if (s == BKF_EBUDGET || s == BKF_EBLOWUP || s == BKF_ENUMERIC) s = BKF_ENUMERIC;
    return s;
}

static int cont_accept(const double *u, const double *tangent, int is_fold, void *data)
{
    (void)tangent;
    cont_data *d = data;
    size_t dim = d->dim;
    double K = u[dim - 1];
    if (is_fold) d->folds++;
    if (d->have_prev) {
        double K0 = d->prev[dim - 1];
        if ((K0 < d->Kt && K >= d->Kt) || (K0 > d->Kt && K <= d->Kt)) {
            if (d->nguess == d->capguess) {
                size_t cap = d->capguess ? 2 * d->capguess : 4;
                double *g = realloc(d->guesses, cap * dim * sizeof *g);
                if (!g) {
                    d->oom = 1;
                    return 1;
                }
                d->guesses = g;
                d->capguess = cap;
            }
            double a = (d->Kt - K0) / (K - K0);
            double *g = d->guesses + d->nguess * dim;
            for (size_t k = 0; k < dim; k++) g[k] = d->prev[k] + a * (u[k] - d->prev[k]);
            d->nguess++;
        }
    }
    memcpy(d->prev, u, dim * sizeof *u);
    d->have_prev = 1;
    return 0;
}

static int append_wave(bkf_chainwave_table *t, size_t *cap, bkf_chainwave *w)
{
    if (t->count == *cap) {
        size_t nc = *cap ? 2 * *cap : 8;
        bkf_chainwave *nw = realloc(t->waves, nc * sizeof *nw);
        if (!nw) return 0;
        t->waves = nw;
        *cap = nc;
    }
    t->waves[t->count++] = *w;
    return 1;
}

static int find_n(const bkf_model_params *p, size_t n, const bkf_chainwave_options *o,
                  flow_ctx *c, work *w, bkf_chainwave_table *t, size_t *cap, bkf_error *err)
{
    size_t N = p->N, n2 = 2 * N, dim = n2 + 2;
    double Kt = c->K;
    double *u0 = malloc(dim * sizeof *u0);
    cont_data d = {c, w, CONT_TOL, Kt, dim, malloc(dim * sizeof(double)), 0, NULL, 0,
                   0, 0, 0};
    int s = (u0 && d.prev) ? BKF_OK : bkf_error_set(err, BKF_ENOMEM, "chainwave: out of memory");
    /* K = 0: the uncoupled blocks on the van der Pol cycle at mu = gamma,
       block i a phase n T / N ahead */
    bkf_cycle_result cr;
    if (!s) {
        bkf_cycle_options co = bkf_cycle_options_default();
        co.tol = 1e-12;
        s = bkf_cycle_period(p->gamma, p->nu, &co, &cr, err);
    }
    double tau0 = 0.0;
    if (!s) {
        tau0 = (double)n * cr.period / (double)N;
        s = sample_cycle(p->gamma, p->nu, p->gamma, 1.0, N, tau0, 1e-12, u0, u0 + N, err);
    }
    if (!s && Kt == 0.0) {
        bkf_chainwave wave;
        u0[n2] = tau0;
        s = solve_x(c, w, p, n, u0, o, &wave, err);
        if (!s && !append_wave(t, cap, &wave)) {
            bkf_chainwave_clear(&wave);
            s = bkf_error_set(err, BKF_ENOMEM, "chainwave: out of memory");
        }
    } else if (!s) {
        u0[n2] = tau0;
        u0[n2 + 1] = 0.0;
        bkf_cont_options co = bkf_cont_options_default(n2 + 1);
        double *scale = malloc(dim * sizeof *scale);
        if (!scale) s = bkf_error_set(err, BKF_ENOMEM, "chainwave: out of memory");
        if (!s) {
            /* the state counts as one unit, whatever N: steps are then
               set by the change of K and of the wave's shape, not by N */
            for (size_t k = 0; k < n2; k++) scale[k] = sqrt((double)n2);
            scale[n2] = cr.period / (double)N;
            scale[n2 + 1] = Kt;
            co.scale = scale;
            co.step_initial = 0.5;
            co.step_max = 1.0;
            co.step_min = 1e-6;
            co.newton_tol = 10.0 * d.tol;
            co.max_points = 400;
            co.stop_index = (int)(n2 + 1);
            co.stop_min = -0.05 * Kt;
            co.stop_max = BKF_CHAINWAVE_K_REACH * Kt;
            bkf_cont_report rep;
            bkf_error ce;
            int cs = bkf_cont_run(cont_residual, cont_accept, &d, u0, (int)(n2 + 1), +1, &co,
                                  &rep, &ce);
            if (d.oom) s = bkf_error_set(err, BKF_ENOMEM, "chainwave: out of memory");
            else if (cs == BKF_ENOMEM || cs == BKF_EINPUT) s = bkf_error_set(err, cs, "%s", ce.message);
            else if (cs != BKF_OK || !rep.reached_bound || d.prev[dim - 1] < Kt) {
                t->ended++;
                if (!t->note[0])
                    snprintf(t->note, sizeof t->note,
                             "n = %zu: the branch from K = 0 ended at K = %.6g (target %.6g)%s%.160s",
                             n, d.prev[dim - 1], Kt, cs ? ": " : "", cs ? ce.message : "");
            }
        }
        free(scale);
        t->folds += d.folds;
        size_t first = t->count;
        for (size_t g = 0; !s && g < d.nguess; g++) {
            c->K = Kt;
            bkf_chainwave wave;
            s = solve_x(c, w, p, n, d.guesses + g * dim, o, &wave, err);
            if (s) break;
            int dup = 0;
            for (size_t k = first; k < t->count; k++)
                if (fabs(t->waves[k].tau - wave.tau) <= 1e3 * t->waves[k].tau_err + 1e-9)
                    dup = 1;
            if (dup) {
                bkf_chainwave_clear(&wave);
            } else if (!append_wave(t, cap, &wave)) {
                bkf_chainwave_clear(&wave);
                s = bkf_error_set(err, BKF_ENOMEM, "chainwave: out of memory");
            }
        }
        /* decreasing v within one n */
        for (size_t i = first + 1; i < t->count; i++)
            for (size_t k = i; k > first && t->waves[k].v > t->waves[k - 1].v; k--) {
                bkf_chainwave tmp = t->waves[k];
                t->waves[k] = t->waves[k - 1];
                t->waves[k - 1] = tmp;
            }
    }
    c->K = Kt;
    free(u0);
    free(d.prev);
    free(d.guesses);
    return s;
}

int bkf_chainwave_find(const bkf_model_params *p, size_t n_from, size_t n_to,
                       const bkf_chainwave_options *o, bkf_chainwave_table *t, bkf_error *err)
{
    if (!t) return bkf_error_set(err, BKF_EINPUT, "chainwave: NULL table");
    memset(t, 0, sizeof *t);
    if (!p) return bkf_error_set(err, BKF_EINPUT, "chainwave: NULL argument");
    if (n_to == 0) n_to = p->N / 2;
    if (n_from < 1) n_from = 1;
    int s = bkf_chainwave_check(p, n_from, o, err);
    if (!s && n_to < n_from)
        s = bkf_error_set(err, BKF_EINPUT, "n range [%zu, %zu] is empty", n_from, n_to);
    if (!s) s = bkf_chainwave_check(p, n_to, o, err);
    if (s) return s;
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    flow_ctx c;
    flow_init(&c, p, o);
    work w;
    c.dphi = malloc(p->N * sizeof *c.dphi);
    size_t cap = 0;
    if (!work_alloc(&w, p->N) || !c.dphi)
        s = bkf_error_set(err, BKF_ENOMEM, "chainwave: out of memory");
    for (size_t n = n_from; !s && n <= n_to; n++) s = find_n(p, n, o, &c, &w, t, &cap, err);
    work_free(&w);
    free(c.dphi);
    bkf_gsl_handler_pop(handler);
    return s;
}

/* ------------------------------------------------------------ branches */

const char *bkf_chainwave_param_name(bkf_chainwave_param param)
{
    switch (param) {
    case BKF_CHAINWAVE_PARAM_H: return "h";
    case BKF_CHAINWAVE_PARAM_S: return "S";
    case BKF_CHAINWAVE_PARAM_C: return "c";
    case BKF_CHAINWAVE_PARAM_NU: return "nu";
    case BKF_CHAINWAVE_PARAM_GAMMA: return "gamma";
    }
    return NULL;
}

typedef struct {
    flow_ctx *c;
    work *w;
    double tol;
    size_t dim, n;
    const bkf_model_params *base;
    bkf_chainwave_param param;
    int stability;
    double *J;            /* (2N + 1)^2 scratch for the multipliers */
    bkf_chainwave_branch_visitor visit;
    void *data;
    bkf_chainwave_branch_report *rep;
    double v0;
    int status;           /* a failure inside accept */
    bkf_error err;
} branch_data;

/* The model at parameter value `value`, into c (and *q); returns dK/dvalue
 * for the parameters that act through K (0 for nu and gamma). */
static double branch_set(const branch_data *b, double value, bkf_model_params *q)
{
    *q = *b->base;
    double N = (double)b->base->N;
    switch (b->param) {
    case BKF_CHAINWAVE_PARAM_H: q->S = value * N; break;
    case BKF_CHAINWAVE_PARAM_S: q->S = value; break;
    case BKF_CHAINWAVE_PARAM_C: q->c = value; break;
    case BKF_CHAINWAVE_PARAM_NU: q->nu = value; break;
    case BKF_CHAINWAVE_PARAM_GAMMA: q->gamma = value; break;
    }
    double h = q->S / N;
    flow_ctx *c = b->c;
    c->K = q->c * q->c / (h * h);
    c->nu = q->nu;
    c->gamma = q->gamma;
    c->sens_param = b->param;
    switch (b->param) {
    case BKF_CHAINWAVE_PARAM_H: return -2.0 * c->K / h;
    case BKF_CHAINWAVE_PARAM_S: return -2.0 * c->K / q->S;
    case BKF_CHAINWAVE_PARAM_C: return 2.0 * q->c / (h * h);
    default: return 0.0;
    }
}

static int branch_residual(const double *u, double *g, double *jac, void *data, bkf_error *err)
{
    branch_data *b = data;
    size_t n2 = b->dim - 2;
    bkf_model_params q;
    double dK = branch_set(b, u[b->dim - 1], &q);
    int s = residual(b->c, b->w, u, b->tol, g, jac, b->dim, err);
    if (s == BKF_EBUDGET || s == BKF_EBLOWUP || s == BKF_ENUMERIC) return BKF_ENUMERIC;
    if (s || !jac) return s;
    /* the sensitivity column is d/dK for h, S and c, the direct one else */
    if (b->param <= BKF_CHAINWAVE_PARAM_C)
        for (size_t k = 0; k < n2; k++) jac[k * b->dim + n2 + 1] *= dK;
    if (b->param == BKF_CHAINWAVE_PARAM_NU) jac[n2 * b->dim + n2 + 1] = -1.0;
    return BKF_OK;
}

static int branch_accept(const double *u, const double *tangent, int is_fold, void *data)
{
    (void)tangent;
    branch_data *b = data;
    size_t n2 = b->dim - 2, N = b->base->N;
    bkf_chainwave_branch_point pt;
    memset(&pt, 0, sizeof pt);
    bkf_model_params q;
    pt.value = u[b->dim - 1];
    branch_set(b, pt.value, &q);
    pt.S = q.S;
    pt.h = q.S / (double)N;
    pt.K = b->c->K;
    pt.c = q.c;
    pt.nu = q.nu;
    pt.gamma = q.gamma;
    pt.tau = u[n2];
    pt.v = pt.h / pt.tau;
    pt.P = (double)N * pt.tau / (double)b->n;
    pt.is_fold = is_fold;
    pt.verdict = BKF_CHAINWAVE_NOT_COMPUTED;
    pt.mult_abs = pt.sigma_max = pt.trivial_err = NAN;
    if (b->stability) {
        double *G = b->J + (n2 + 1) * (n2 + 1);
        double re, im;
        int s = residual(b->c, b->w, u, b->tol, G, b->J, n2 + 1, &b->err);
        if (!s) s = multipliers(b->c, b->w->M, &pt.trivial_err, &re, &im, &b->err);
        if (s) {
            b->status = s;
            return 1;
        }
        pt.mult_abs = hypot(re, im);
        pt.sigma_max = log(pt.mult_abs) / pt.tau;
        if (pt.mult_abs - pt.trivial_err > 1.0) pt.verdict = BKF_CHAINWAVE_UNSTABLE;
        else if (pt.mult_abs + pt.trivial_err < 1.0) pt.verdict = BKF_CHAINWAVE_STABLE;
        else pt.verdict = BKF_CHAINWAVE_UNRESOLVED;
    }
    bkf_chainwave_branch_report *r = b->rep;
    if (is_fold) r->folds++;
    else r->points++;
    r->last_value = pt.value;
    r->last_v = pt.v;
    if (b->v0 == 0.0) b->v0 = pt.v;
    if (b->visit && b->visit(&pt, b->data)) return 1;
    if (pt.v < 1e-3 * b->v0) {
        r->pinned = 1;
        return 1;
    }
    return 0;
}

int bkf_chainwave_branch(const bkf_model_params *p, size_t n, size_t root,
                         bkf_chainwave_param param, double from, double to,
                         const bkf_chainwave_options *o, bkf_chainwave_branch_visitor visit,
                         void *data, bkf_chainwave_branch_report *rep, bkf_error *err)
{
    bkf_chainwave_branch_report own;
    if (!rep) rep = &own;
    memset(rep, 0, sizeof *rep);
    if (!p || !o) return bkf_error_set(err, BKF_EINPUT, "chainwave: NULL argument");
    const char *name = bkf_chainwave_param_name(param);
    if (!name) return bkf_error_set(err, BKF_EINPUT, "param: %d is not h, S, c, nu or gamma",
                                    (int)param);
    if (!(isfinite(from) && isfinite(to) && from != to))
        return bkf_error_set(err, BKF_EINPUT, "from = %g, to = %g: two different finite values "
                             "of %s are needed", from, to, name);
    flow_ctx c;
    flow_init(&c, p, o);
    branch_data b = {&c, NULL, fmin(1e-4, o->tol), 2 * p->N + 2, n, p, param, o->stability,
                     NULL, visit, data, rep, 0.0, 0, {{0}, 0}};
    bkf_model_params qa, qb;
    branch_set(&b, from, &qa);
    branch_set(&b, to, &qb);
    int s = bkf_chainwave_check(&qa, n, o, err);
    if (!s) s = bkf_chainwave_check(&qb, n, o, err);
    if (s) return s;
    if (root < 1) return bkf_error_set(err, BKF_EINPUT, "root = 0 must be >= 1");
    bkf_chainwave_options fo = *o;
    fo.stability = 0;
    bkf_chainwave_table t;
    s = bkf_chainwave_find(&qa, n, n, &fo, &t, err);
    if (!s && t.count < root)
        s = bkf_error_set(err, BKF_EINPUT, "%s = %g: n = %zu has %zu chain wave(s), not root %zu"
                          "%s%s", name, from, n, t.count, root, t.note[0] ? ": " : "", t.note);
    size_t N = p->N, n2 = 2 * N, dim = n2 + 2;
    double *u0 = malloc(dim * sizeof *u0), *scale = malloc(dim * sizeof *scale);
    work w;
    int have_w = work_alloc(&w, N);
    c.dphi = malloc(N * sizeof *c.dphi);
    b.w = &w;
    b.J = o->stability ? malloc((n2 + 2) * (n2 + 1) * sizeof *b.J) : NULL; /* J, then G */
    if (!s && (!u0 || !scale || !have_w || !c.dphi || (o->stability && !b.J)))
        s = bkf_error_set(err, BKF_ENOMEM, "chainwave: out of memory");
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    if (!s) {
        const bkf_chainwave *w0 = &t.waves[root - 1];
        memcpy(u0, w0->psi, N * sizeof *u0);
        memcpy(u0 + N, w0->eta, N * sizeof *u0);
        u0[n2] = w0->tau;
        u0[n2 + 1] = from;
        /* the state counts as one unit whatever N (as in find_n) */
        for (size_t k = 0; k < n2; k++) scale[k] = sqrt((double)n2);
        scale[n2] = w0->tau;
        scale[n2 + 1] = fabs(to - from);
        bkf_cont_options co = bkf_cont_options_default(n2 + 1);
        co.scale = scale;
        co.step_initial = 0.02;
        co.step_max = 0.1;
        co.step_min = 1e-7;
        co.newton_tol = 10.0 * b.tol;
        co.max_points = 4000;
        co.stop_index = (int)(n2 + 1);
        co.stop_min = fmin(from, to);
        co.stop_max = fmax(from, to);
        bkf_cont_report cr;
        bkf_error ce;
        int cs = bkf_cont_run(branch_residual, branch_accept, &b, u0, (int)(n2 + 1),
                              to > from ? +1 : -1, &co, &cr, &ce);
        if (b.status) s = bkf_error_set(err, b.status, "%s", b.err.message);
        else if (cs == BKF_ENOMEM || cs == BKF_EINPUT) s = bkf_error_set(err, cs, "%s", ce.message);
        else {
            rep->reached = cs == BKF_OK && cr.reached_bound && !rep->pinned &&
                           fabs(rep->last_value - to) <= 1e-9 * fabs(to - from);
            if (rep->pinned)
                snprintf(rep->note, sizeof rep->note, "the fronts stop propagating near %s = %.9g "
                         "(v %.3g, below 1e-3 of its start)", name, rep->last_value, rep->last_v);
            else if (!rep->reached)
                snprintf(rep->note, sizeof rep->note, "the branch ends at %s = %.9g (v %.9g)%s%.200s",
                         name, rep->last_value, rep->last_v, cs ? ": " : "", cs ? ce.message : "");
        }
    }
    bkf_gsl_handler_pop(handler);
    bkf_chainwave_table_free(&t);
    free(u0);
    free(scale);
    work_free(&w);
    free(c.dphi);
    free(b.J);
    return s;
}

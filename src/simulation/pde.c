/* Direct simulation: pseudo-spectral continuum and finite-difference chain,
 * explicit embedded Runge-Kutta in time with quintic Hermite dense output.
 * See include/bkfront/pde.h for the model and the conventions. */
#include "bkfront/pde.h"

#include <fftw3.h>
#include <gsl/gsl_errno.h>
#include <gsl/gsl_math.h>
#include <gsl/gsl_odeiv2.h>
#include <gsl/gsl_randist.h>
#include <gsl/gsl_rng.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bkfront/cycle.h"
#include "bkfront/model.h"
#include "bkfront/fft.h"
#include "pde_internal.h"

const char *const bkf_pde_stepper_names[] = {"rk8pd", "rkck", "rkf45", "etdrk4", "lawson8", NULL};

bkf_pde_stepper bkf_pde_stepper_auto(const bkf_model_params *model, int dealias)
{
    return model->kind == BKF_MODEL_CONTINUUM && !dealias && model->N >= BKF_PDE_AUTO_LAWSON_N
               ? BKF_PDE_LAWSON8
               : BKF_PDE_RK8PD;
}

bkf_pde_options bkf_pde_options_default(void)
{
    bkf_pde_options o = {1e-9, BKF_PDE_RK8PD, 0, 4.0, 0, NULL, 0.0};
    return o;
}

bkf_pde_front_spec bkf_pde_front_spec_default(void)
{
    bkf_pde_front_spec s = {1, 1, -1, 0.0, 1, 1e-12};
    return s;
}

int bkf_pde_check(const bkf_model_params *p, const bkf_pde_options *o, bkf_error *err)
{
    if (!p) return bkf_error_set(err, BKF_EINPUT, "parameters are NULL");
    int s;
    if ((s = bkf_model_check_positive("gamma", p->gamma, err))) return s;
    if ((s = bkf_model_check_c(p->c, err))) return s;
    if (!(fabs(p->nu) <= BKF_PDE_NU_MAX))
        return bkf_error_set(err, BKF_EINPUT,
                             "nu = %.15g is outside [-%g, %g]: beyond, the uniform slip state "
                             "psi = nu, eta = phi(nu) is not within the field's bound 1e6",
                             p->nu, BKF_PDE_NU_MAX, BKF_PDE_NU_MAX);
    if ((s = bkf_model_check_positive("S", p->S, err))) return s;
    if (p->kind != BKF_MODEL_CONTINUUM && p->kind != BKF_MODEL_CHAIN)
        return bkf_error_set(err, BKF_EINPUT, "model must be continuum or chain");
    if (p->N < BKF_PDE_N_MIN || p->N > BKF_PDE_N_MAX)
        return bkf_error_set(err, BKF_EINPUT, "N = %zu is outside [%d, %d]", p->N,
                             BKF_PDE_N_MIN, BKF_PDE_N_MAX);
    if (p->kind == BKF_MODEL_CONTINUUM && p->N % 2)
        return bkf_error_set(err, BKF_EINPUT,
                             "N = %zu must be even for the spectral continuum model", p->N);
    /* Parameters whose right-hand side overflows on a field within its bound
     * 1e6 are refused here, by name: the run would otherwise fail at its
     * first evaluation and blame the initial state. */
    if (!(p->gamma >= BKF_PDE_GAMMA_MIN && p->gamma <= BKF_PDE_GAMMA_MAX))
        return bkf_error_set(err, BKF_EINPUT, "gamma = %.15g is outside [%g, %g]", p->gamma,
                             BKF_PDE_GAMMA_MIN, BKF_PDE_GAMMA_MAX);
    double kmax = (p->kind == BKF_MODEL_CHAIN ? 2.0 : 3.14159265358979323846) *
                  (double)p->N / p->S;
    if (!(p->c * kmax <= BKF_PDE_WAVE_MAX))
        return bkf_error_set(err, BKF_EINPUT,
                             "c = %.15g with S = %.15g and N = %zu: the fastest wave rate c "
                             "k_max = %.3g is beyond %g (lower c or N, or raise S)",
                             p->c, p->S, p->N, p->c * kmax, BKF_PDE_WAVE_MAX);
    if (!o) return BKF_OK;
    if (!isfinite(o->tol) || o->tol < BKF_PDE_TOL_MIN || o->tol > BKF_PDE_TOL_MAX)
        return bkf_error_set(err, BKF_EINPUT, "tol = %g is outside [%g, %g]", o->tol,
                             BKF_PDE_TOL_MIN, BKF_PDE_TOL_MAX);
    if (o->stepper != BKF_PDE_RK8PD && o->stepper != BKF_PDE_RKCK &&
        o->stepper != BKF_PDE_RKF45 && o->stepper != BKF_PDE_ETDRK4 &&
        o->stepper != BKF_PDE_LAWSON8)
        return bkf_error_set(err, BKF_EINPUT,
                             "stepper must be rk8pd, rkck, rkf45, etdrk4 or lawson8");
    int exponential = o->stepper == BKF_PDE_ETDRK4 || o->stepper == BKF_PDE_LAWSON8;
    const char *sname = bkf_pde_stepper_names[o->stepper];
    if (exponential && p->kind != BKF_MODEL_CONTINUUM)
        return bkf_error_set(err, BKF_EINPUT, "the %s stepper applies to the continuum model only",
                             sname);
    if (exponential && o->dealias)
        return bkf_error_set(err, BKF_EINPUT, "the %s stepper is not combined with dealiasing",
                             sname);
    if (!isfinite(o->filter) || o->filter < 0 || o->filter > 1e3)
        return bkf_error_set(err, BKF_EINPUT, "filter = %g is outside [0, 1000]", o->filter);
    if (o->dealias && p->kind != BKF_MODEL_CONTINUUM)
        return bkf_error_set(err, BKF_EINPUT, "dealiasing applies to the continuum model only");
    if (!isfinite(o->frame_speed) || fabs(o->frame_speed) > 1e3)
        return bkf_error_set(err, BKF_EINPUT, "frame speed = %g is outside [-1000, 1000]",
                             o->frame_speed);
    if (o->frame_speed != 0 && p->kind != BKF_MODEL_CONTINUUM)
        return bkf_error_set(err, BKF_EINPUT, "a moving frame applies to the continuum model only");
    if (o->frame_speed != 0 && o->dealias)
        return bkf_error_set(err, BKF_EINPUT, "a moving frame is not combined with dealiasing");
    return BKF_OK;
}

/* ------------------------------------------------------------- operators */

/* out = L in (N values) and, when the filter is on and filt is non-NULL,
 * filt = F in (the damping term); in, out and filt are not the FFT buffers. */
static void operators(bkf_pde *m, const double *in, double *out, double *filt)
{
    size_t N = m->N;
    if (m->p.kind == BKF_MODEL_CHAIN) {
        double w = 1.0 / (m->h * m->h);
        for (size_t i = 0; i < N; i++) {
            double l = in[i == 0 ? N - 1 : i - 1], r = in[i + 1 == N ? 0 : i + 1];
            out[i] = w * (l - 2.0 * in[i] + r);
        }
        return;
    }
    memcpy(m->rbuf, in, N * sizeof *in);
    fftw_execute_dft_r2c(m->fwd, m->rbuf, m->cbuf);
    int both = filt && m->fsymbol;
    for (size_t k = 0; k <= N / 2; k++) {
        if (both) {
            m->cbuf2[k][0] = m->cbuf[k][0] * m->fsymbol[k];
            m->cbuf2[k][1] = m->cbuf[k][1] * m->fsymbol[k];
        }
        m->cbuf[k][0] *= m->symbol[k];
        m->cbuf[k][1] *= m->symbol[k];
    }
    fftw_execute_dft_c2r(m->bwd, m->cbuf, m->lap);
    memcpy(out, m->lap, N * sizeof *out);
    if (both) {
        fftw_execute_dft_c2r(m->bwd, m->cbuf2, m->lap);
        memcpy(filt, m->lap, N * sizeof *filt);
    }
}

static void laplacian(bkf_pde *m, const double *in, double *out) { operators(m, in, out, NULL); }

/* The moving frame's operators, two transforms in and three out:
 * lap = L psi, lin = (-F + V d/dx) psi, adv = V d/dx eta. */
static void operators_frame(bkf_pde *m, const double *psi, const double *eta, double *lap,
                            double *lin, double *adv)
{
    size_t N = m->N;
    memcpy(m->rbuf, psi, N * sizeof *psi);
    fftw_execute_dft_r2c(m->fwd, m->rbuf, m->cbuf);
    for (size_t k = 0; k <= N / 2; k++) {
        double ar = m->cbuf[k][0], ai = m->cbuf[k][1];
        double fs = m->fsymbol ? m->fsymbol[k] : 0.0, dq = m->dsymbol[k];
        m->cbuf2[k][0] = ar * m->symbol[k];
        m->cbuf2[k][1] = ai * m->symbol[k];
        m->cbuf3[k][0] = -fs * ar - dq * ai;
        m->cbuf3[k][1] = -fs * ai + dq * ar;
    }
    fftw_execute_dft_c2r(m->bwd, m->cbuf2, m->lap);
    memcpy(lap, m->lap, N * sizeof *lap);
    fftw_execute_dft_c2r(m->bwd, m->cbuf3, m->lap);
    memcpy(lin, m->lap, N * sizeof *lin);
    memcpy(m->rbuf, eta, N * sizeof *eta);
    fftw_execute_dft_r2c(m->fwd, m->rbuf, m->cbuf);
    for (size_t k = 0; k <= N / 2; k++) {
        double ar = m->cbuf[k][0], ai = m->cbuf[k][1], dq = m->dsymbol[k];
        m->cbuf[k][0] = -dq * ai;
        m->cbuf[k][1] = dq * ar;
    }
    fftw_execute_dft_c2r(m->bwd, m->cbuf, m->lap);
    memcpy(adv, m->lap, N * sizeof *adv);
}

/* rhs in the moving frame; D' is the general dH/dt (see pde.h). */
static int rhs_frame(bkf_pde *m, const double *restrict y, double *restrict dydt)
{
    size_t N = m->N;
    const double *restrict psi = y, *restrict eta = y + N;
    double *restrict dpsi = dydt, *restrict deta = dydt + N;
    double g = m->p.gamma, ig = 1.0 / g, c2 = m->p.c * m->p.c, nu = m->p.nu;
    double *restrict lap = m->scr;
    operators_frame(m, psi, eta, lap, dpsi, deta);
    double mean = 0.0, work = 0.0, big = 0.0;
    for (size_t i = 0; i < N; i++) {
        double x = psi[i], lx = lap[i];
        double u = g * (eta[i] - (x * x * x * (1.0 / 3.0) - x));
        double xt = u + dpsi[i];
        double force = x - nu - c2 * lx;
        double et = -force * ig + deta[i];
        dpsi[i] = xt;
        deta[i] = et;
        mean += x;
        work += u * g * (et - (x * x - 1.0) * xt) + force * xt;
        big = fmax(big, fabs(x));
    }
    if (!isfinite(mean) || !isfinite(work) || !(big <= BLOWUP)) return GSL_EBADFUNC;
    dydt[2 * N] = mean / (double)N;
    dydt[2 * N + 1] = m->h * work;
    return GSL_SUCCESS;
}

/* 2/3 rule: keep the modes k < keep of v, in place. */
static void project(bkf_pde *m, double *v)
{
    size_t N = m->N;
    memcpy(m->rbuf, v, N * sizeof *v);
    fftw_execute_dft_r2c(m->fwd, m->rbuf, m->cbuf);
    double scale = 1.0 / (double)N;
    for (size_t k = 0; k <= N / 2; k++) {
        double w = k < m->keep ? scale : 0.0;
        m->cbuf[k][0] *= w;
        m->cbuf[k][1] *= w;
    }
    fftw_execute_dft_c2r(m->bwd, m->cbuf, m->rbuf);
    memcpy(v, m->rbuf, N * sizeof *v);
}

static int rhs(double t, const double y[], double dydt[], void *params)
{
    (void)t;
    bkf_pde *m = params;
    m->stats.rhs_calls++;
    if (m->dsymbol) return rhs_frame(m, y, dydt);
    size_t N = m->N;
    const double *restrict psi = y, *restrict eta = y + N;
    double *restrict dpsi = dydt, *restrict deta = dydt + N;
    double g = m->p.gamma, ig = 1.0 / g, c2 = m->p.c * m->p.c, nu = m->p.nu;
    /* deta holds L psi and dpsi holds F psi for a moment */
    operators(m, psi, deta, m->fsymbol ? dpsi : NULL);
    double mean = 0.0, work = 0.0, big = 0.0;
    if (m->fsymbol && !m->o.dealias) {
        /* The filter's work joins the friction's in D, so that H - D stays
         * conserved: dH/dt = -sum h [gamma phi' u psi_t + (psi - nu - c^2 L psi) F psi]
         * with u = gamma (eta - phi(psi)) and psi_t = u - F psi. */
        for (size_t i = 0; i < N; i++) {
            double x = psi[i], fx = dpsi[i], lx = deta[i];
            double u = g * (eta[i] - (x * x * x * (1.0 / 3.0) - x));
            double xt = u - fx;
            dpsi[i] = xt;
            deta[i] = (nu - x + c2 * lx) * ig;
            mean += x;
            work += g * (x * x - 1.0) * u * xt + (x - nu - c2 * lx) * fx;
            big = fmax(big, fabs(x));
        }
        if (!isfinite(mean) || !isfinite(work) || !(big <= BLOWUP)) return GSL_EBADFUNC;
        dydt[2 * N] = mean / (double)N;
        dydt[2 * N + 1] = -m->h * work;
        return GSL_SUCCESS;
    }
    if (!m->o.dealias) {
        /* One fused pass; a NaN or inf anywhere reaches mean or work. */
        for (size_t i = 0; i < N; i++) {
            double x = psi[i];
            double xt = g * (eta[i] - (x * x * x * (1.0 / 3.0) - x));
            dpsi[i] = xt;
            deta[i] = (nu - x + c2 * deta[i]) * ig;
            mean += x;
            work += (x * x - 1.0) * xt * xt;
            big = fmax(big, fabs(x));
        }
    } else {
        for (size_t i = 0; i < N; i++) {
            double x = psi[i];
            double fx = m->fsymbol ? dpsi[i] : 0.0;
            dpsi[i] = g * (eta[i] - (x * x * x * (1.0 / 3.0) - x)) - fx;
            deta[i] = (nu - x + c2 * deta[i]) * ig;
        }
        project(m, dpsi);
        project(m, deta);
        for (size_t i = 0; i < N; i++) {
            double x = psi[i];
            mean += x;
            work += (x * x - 1.0) * dpsi[i] * dpsi[i];
            big = fmax(big, fabs(x));
        }
    }
    if (!isfinite(mean) || !isfinite(work) || !(big <= BLOWUP)) return GSL_EBADFUNC;
    dydt[2 * N] = mean / (double)N;
    dydt[2 * N + 1] = -g * m->h * work;
    return GSL_SUCCESS;
}

int pde_rhs_eval(bkf_pde *m, const double *y, double *dydt)
{
    return rhs(0.0, y, dydt, m) == GSL_SUCCESS ? BKF_OK : BKF_EBLOWUP;
}

/* The linearisation of rhs's field part, term by term (see rhs): psi_t =
 * gamma (eta - phi(psi)) - F psi, eta_t = (nu - psi + c^2 L psi)/gamma, the
 * 2/3 rule's projection where rhs applies it.  No moving frame (its
 * advection would need operators_frame; no caller uses one). */
int pde_tangent(bkf_pde *m, const double *y, const double *v, double *out)
{
    if (m->dsymbol) return BKF_EINPUT;
    size_t N = m->N;
    const double *psi = y, *dpsi = v, *deta = v + N;
    double *opsi = out, *oeta = out + N;
    double g = m->p.gamma, ig = 1.0 / g, c2 = m->p.c * m->p.c;
    /* oeta holds L dpsi and opsi F dpsi for a moment, as in rhs */
    operators(m, dpsi, oeta, m->fsymbol ? opsi : NULL);
    for (size_t i = 0; i < N; i++) {
        double x = psi[i], fx = m->fsymbol ? opsi[i] : 0.0;
        opsi[i] = g * (deta[i] - (x * x - 1.0) * dpsi[i]) - fx;
        oeta[i] = (c2 * oeta[i] - dpsi[i]) * ig;
    }
    if (m->o.dealias) {
        project(m, opsi);
        project(m, oeta);
    }
    for (size_t i = 0; i < 2 * N; i++)
        if (!isfinite(out[i])) return BKF_EBLOWUP;
    return BKF_OK;
}

/* --------------------------------------------------------- object life */

void bkf_pde_free(bkf_pde *m)
{
    if (!m) return;
    bkf_fft_lock();
    if (m->fwd) fftw_destroy_plan(m->fwd);
    if (m->bwd) fftw_destroy_plan(m->bwd);
    bkf_fft_unlock();
    fftw_free(m->rbuf);
    fftw_free(m->lap);
    fftw_free(m->cbuf);
    free(m->symbol);
    free(m->fsymbol);
    fftw_free(m->cbuf2);
    free(m->dsymbol);
    fftw_free(m->cbuf3);
    free(m->scr);
    if (m->step) gsl_odeiv2_step_free(m->step);
    if (m->control) gsl_odeiv2_control_free(m->control);
    free(m->y);
    free(m->f);
    free(m->ytry);
    free(m->yerr);
    free(m->f1);
    free(m->sample);
    free(m->psit);
    bkf_pde_etd_free(m->etd);
    free(m);
}

static const gsl_odeiv2_step_type *step_type(bkf_pde_stepper s)
{
    switch (s) {
    case BKF_PDE_RKCK: return gsl_odeiv2_step_rkck;
    case BKF_PDE_RKF45: return gsl_odeiv2_step_rkf45;
    default: return gsl_odeiv2_step_rk8pd;
    }
}

static void mark_set(bkf_pde *m);

static bkf_pde *pde_alloc_body(const bkf_model_params *params, const bkf_pde_options *options,
                       bkf_error *err)
{
    bkf_pde_options o = options ? *options : bkf_pde_options_default();
    if (bkf_pde_check(params, &o, err) != BKF_OK) return NULL;
    bkf_pde *m = calloc(1, sizeof *m);
    if (!m) {
        bkf_error_set(err, BKF_ENOMEM, "out of memory");
        return NULL;
    }
    m->p = *params;
    m->o = o;
    size_t N = params->N;
    m->N = N;
    m->dim = 2 * N + 2;
    m->h = params->S / (double)N;
    m->keep = N / 3 + 1;
    size_t nc = N / 2 + 1;
    m->rbuf = fftw_malloc(N * sizeof(double));
    m->lap = fftw_malloc(N * sizeof(double));
    m->cbuf = fftw_malloc(nc * sizeof(fftw_complex));
    m->symbol = malloc(nc * sizeof(double));
    m->cbuf2 = fftw_malloc(nc * sizeof(fftw_complex));
    m->y = calloc(m->dim, sizeof(double));
    m->f = calloc(m->dim, sizeof(double));
    m->ytry = calloc(m->dim, sizeof(double));
    m->yerr = calloc(m->dim, sizeof(double));
    m->f1 = calloc(m->dim, sizeof(double));
    m->sample = calloc(m->dim, sizeof(double));
    m->psit = calloc(N, sizeof(double));
    if (!m->rbuf || !m->lap || !m->cbuf || !m->cbuf2 || !m->symbol || !m->y || !m->f || !m->ytry ||
        !m->yerr || !m->f1 || !m->sample || !m->psit)
        goto nomem;
    /* ESTIMATE: planning by measurement costs more than a short run gains
     * and would make runs differ in the last bits from one call to another. */
    bkf_fft_lock();
    m->fwd = fftw_plan_dft_r2c_1d((int)N, m->rbuf, m->cbuf, FFTW_ESTIMATE);
    m->bwd = fftw_plan_dft_c2r_1d((int)N, m->cbuf, m->lap, FFTW_ESTIMATE);
    bkf_fft_unlock();
    if (!m->fwd || !m->bwd) goto nomem;
    for (size_t k = 0; k < nc; k++) {
        double q = 2.0 * M_PI * (double)k / params->S;
        m->symbol[k] = -q * q / (double)N;
    }
    if (params->kind == BKF_MODEL_CONTINUUM && o.filter > 0) {
        m->fsymbol = malloc(nc * sizeof(double));
        if (!m->fsymbol) goto nomem;
        /* top: the highest mode the state holds (the cutoff with the 2/3 rule) */
        double top = o.dealias ? (double)(m->keep - 1) : (double)(N / 2);
        for (size_t k = 0; k < nc; k++) {
            double r = (double)k / top, r2 = r * r, r4 = r2 * r2, r8 = r4 * r4;
            m->fsymbol[k] = o.filter * r8 * r8 / (double)N;
        }
    }
    if (o.frame_speed != 0) {
        m->dsymbol = malloc(nc * sizeof(double));
        m->cbuf3 = fftw_malloc(nc * sizeof(fftw_complex));
        m->scr = calloc(N, sizeof(double));
        if (!m->dsymbol || !m->cbuf3 || !m->scr) goto nomem;
        for (size_t k = 0; k < nc; k++) {
            double q = 2.0 * M_PI * (double)k / params->S;
            m->dsymbol[k] = 2 * k == N ? 0.0 : o.frame_speed * q / (double)N;
        }
    }
    if (o.stepper == BKF_PDE_ETDRK4 || o.stepper == BKF_PDE_LAWSON8) {
        /* its own state (src/pde_etd.c); no GSL stepper: rk8pd's 13 stages
         * of 2N + 2 values would be 54 MB unused at N = 262144 */
        if (!(m->etd = bkf_pde_etd_alloc(m))) goto nomem;
    } else {
        m->step = gsl_odeiv2_step_alloc(step_type(o.stepper), m->dim);
        m->control = gsl_odeiv2_control_y_new(o.tol, o.tol);
        if (!m->step || !m->control) goto nomem;
    }
    m->sys = (gsl_odeiv2_system){rhs, NULL, m->dim, m};

    /* The highest mode oscillates at omega = sqrt(1 + c^2 q_max^2) with
     * q_max = pi/h (spectral) or 2/h (the chain's Laplacian), far from the
     * physics when N is large.  The error control does not see that mode
     * while its amplitude is at rounding level, so it may choose steps where
     * the method's amplification on the imaginary axis exceeds 1: the mode
     * then grows from rounding and wrecks the run after ~100 time units
     * (seen with rk8pd at omega h ~ 4).  The cap keeps omega h where the
     * method damps (rk8pd: |R(iy)| < 1 for 2 < y < 3.8) or nearly so (the
     * 5th-order pairs have |R(iy)| > 1 for every y; at y = 0.5 the spurious
     * growth is ~1e-5 omega per unit time). */
    double qmax = params->kind == BKF_MODEL_CHAIN ? 2.0 / m->h : M_PI / m->h;
    /* In a moving frame the advection adds |V| q to the frequency. */
    double omega = sqrt(1.0 + params->c * params->c * qmax * qmax) + fabs(o.frame_speed) * qmax;
    double kappa = o.stepper == BKF_PDE_RK8PD ? 3.0 : 0.5;
    m->hcap = kappa / omega;
    /* A first step well inside the explicit stability limit; the control
     * finds the right size within a few steps. */
    m->hstep = 0.1 / (omega + params->gamma * 3.0);
    /* The exponential integrator has no such limit (src/pde_etd.c). */
    if (m->etd) m->hstep = 0.1;

    for (size_t i = 0; i < N; i++) {
        m->y[i] = params->nu;
        m->y[N + i] = bkf_model_friction(params->nu);
    }
    m->t = 0.0;
    mark_set(m);
    m->stats.h_min = INFINITY;
    m->stats.product_points = m->N;
    return m;
nomem:
    bkf_pde_free(m);
    bkf_error_set(err, BKF_ENOMEM, "out of memory");
    return NULL;
}

bkf_pde *bkf_pde_alloc(const bkf_model_params *params, const bkf_pde_options *options,
                       bkf_error *err)
{
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    bkf_pde *made = pde_alloc_body(params, options, err);
    bkf_gsl_handler_pop(handler);
    return made;
}

/* Accessors and diagnostics of a NULL object (or field) give NULL, 0 or
 * NaN rather than crash. */
const bkf_model_params *bkf_pde_get_params(const bkf_pde *m) { return m ? &m->p : NULL; }
size_t bkf_pde_size(const bkf_pde *m) { return m ? m->N : 0; }
double bkf_pde_spacing(const bkf_pde *m) { return m ? m->h : NAN; }
double bkf_pde_time(const bkf_pde *m) { return m ? m->t : NAN; }
const double *bkf_pde_psi(const bkf_pde *m) { return m ? m->y : NULL; }
const double *bkf_pde_eta(const bkf_pde *m) { return m ? m->y + m->N : NULL; }
const bkf_pde_stats *bkf_pde_get_stats(const bkf_pde *m) { return m ? &m->stats : NULL; }

void bkf_pde_stats_reset(bkf_pde *m)
{
    if (!m) return;
    memset(&m->stats, 0, sizeof m->stats);
    m->stats.h_min = INFINITY;
    m->stats.product_points = m->N;
}

/* ------------------------------------------------------------ energy */

double bkf_pde_energy_of(bkf_pde *m, const double *psi, const double *eta)
{
    if (!m || !psi || !eta) return NAN;
    size_t N = m->N;
    double g = m->p.gamma, nu = m->p.nu, c2 = m->p.c * m->p.c;
    laplacian(m, psi, m->psit);
    double H = 0.0;
    for (size_t i = 0; i < N; i++) {
        double x = psi[i];
        double xt = g * (eta[i] - (x * x * x / 3.0 - x));
        H += 0.5 * xt * xt + 0.5 * (x - nu) * (x - nu) - 0.5 * c2 * x * m->psit[i];
    }
    return H * m->h;
}

double bkf_pde_spectral_tail(bkf_pde *m, const double *field)
{
    if (!m || !field) return NAN;
    size_t N = m->N;
    memcpy(m->rbuf, field, N * sizeof *field);
    fftw_execute_dft_r2c(m->fwd, m->rbuf, m->cbuf);
    double top = 0, tail = 0;
    for (size_t k = 1; k <= N / 2; k++) {
        double a = hypot(m->cbuf[k][0], m->cbuf[k][1]);
        if (3 * k <= N) top = fmax(top, a);
        else tail = fmax(tail, a);
    }
    double all = fmax(top, tail);
    return all > 0 ? tail / all : 0.0;
}

double bkf_pde_energy(bkf_pde *m) { return m ? bkf_pde_energy_of(m, m->y, m->y + m->N) : NAN; }
double bkf_pde_dissipation(const bkf_pde *m) { return m ? m->y[2 * m->N + 1] : NAN; }
double bkf_pde_mean_integral(const bkf_pde *m) { return m ? m->y[2 * m->N] : NAN; }

static double mean_of(const double *v, size_t N)
{
    double s = 0.0;
    for (size_t i = 0; i < N; i++) s += v[i];
    return s / (double)N;
}

static void mark_set(bkf_pde *m)
{
    size_t N = m->N;
    if (m->o.dealias) {
        project(m, m->y);
        project(m, m->y + N);
    }
    m->y[2 * N] = 0.0;
    m->y[2 * N + 1] = 0.0;
    m->t_set = m->t;
    m->H_set = bkf_pde_energy(m);
    m->mean_eta_set = mean_of(m->y + N, N);
    m->have_f = 0;
    bkf_pde_etd_invalidate(m->etd);
}

double bkf_pde_energy_residual(bkf_pde *m)
{
    if (!m) return NAN;
    return bkf_pde_energy(m) - m->H_set - m->y[2 * m->N + 1];
}

double bkf_pde_mean_residual(const bkf_pde *m)
{
    if (!m) return NAN;
    size_t N = m->N;
    return mean_of(m->y + N, N) - m->mean_eta_set +
           (m->y[2 * N] - m->p.nu * (m->t - m->t_set)) / m->p.gamma;
}

double bkf_pde_sample_energy_residual(bkf_pde *m, const bkf_pde_sample *s)
{
    if (!m || !s) return NAN;
    return bkf_pde_energy_of(m, s->psi, s->eta) - m->H_set - s->D;
}

double bkf_pde_sample_mean_residual(const bkf_pde *m, const bkf_pde_sample *s)
{
    if (!m || !s || !s->eta) return NAN;
    return mean_of(s->eta, m->N) - m->mean_eta_set + (s->Q - m->p.nu * (s->t - m->t_set)) / m->p.gamma;
}

/* The observer's view of a full state vector. */
int bkf_pde_set_state(bkf_pde *m, const double *psi, const double *eta, double t,
                      bkf_error *err)
{
    if (!m || !psi || !eta) return bkf_error_set(err, BKF_EINPUT, "NULL state");
    if (!isfinite(t)) return bkf_error_set(err, BKF_EINPUT, "t must be finite");
    for (size_t i = 0; i < m->N; i++)
        if (!(fabs(psi[i]) <= BLOWUP) || !(fabs(eta[i]) <= BLOWUP))
            return bkf_error_set(err, BKF_EINPUT,
                                 "the state at i = %zu is not finite or beyond %g, where a run "
                                 "counts as blown up", i, BLOWUP);
    memcpy(m->y, psi, m->N * sizeof *psi);
    memcpy(m->y + m->N, eta, m->N * sizeof *eta);
    m->t = t;
    mark_set(m);
    return BKF_OK;
}

/* ------------------------------------------------- initial conditions */

/* Band-limited noise of rms `amp` into out (N values): modes 1..J, with
 * coefficients drawn in mode order so the function of x does not depend
 * on N. */
static int noise(bkf_pde *m, double amp, unsigned long seed, double *out, bkf_error *err)
{
    size_t N = m->N;
    size_t J = (size_t)floor(m->p.S / 2.0);
    if (J < 1) J = 1;
    if (J > N / 2 - 1) J = N / 2 - 1;
    gsl_rng *r = gsl_rng_alloc(gsl_rng_mt19937);
    if (!r) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    gsl_rng_set(r, seed);
    for (size_t k = 0; k <= N / 2; k++) m->cbuf[k][0] = m->cbuf[k][1] = 0.0;
    double power = 0.0;
    for (size_t j = 1; j <= J; j++) {
        double a = gsl_ran_gaussian(r, 1.0), b = gsl_ran_gaussian(r, 1.0);
        m->cbuf[j][0] = a;
        m->cbuf[j][1] = b;
        power += 2.0 * (a * a + b * b); /* mean square of 2 Re(c e^{iqx}) */
    }
    gsl_rng_free(r);
    double scale = power > 0 ? amp / sqrt(power) : 0.0;
    for (size_t j = 1; j <= J; j++) {
        m->cbuf[j][0] *= scale;
        m->cbuf[j][1] *= scale;
    }
    fftw_execute_dft_c2r(m->bwd, m->cbuf, m->lap);
    memcpy(out, m->lap, N * sizeof *out);
    return BKF_OK;
}

static int check_amp(const char *name, double a, bkf_error *err)
{
    if (!isfinite(a) || a < 0 || a > 10)
        return bkf_error_set(err, BKF_EINPUT, "%s = %g is outside [0, 10]", name, a);
    return BKF_OK;
}

static int pde_init_uniform_body(bkf_pde *m, double amp, unsigned long seed, bkf_error *err)
{
    if (!m) return bkf_error_set(err, BKF_EINPUT, "simulation object is NULL");
    int s = check_amp("amp", amp, err);
    if (s) return s;
    size_t N = m->N;
    if ((s = noise(m, amp, seed, m->y, err))) return s;
    for (size_t i = 0; i < N; i++) {
        m->y[i] += m->p.nu;
        m->y[N + i] = bkf_model_friction(m->y[i]);
    }
    m->t = 0.0;
    mark_set(m);
    return BKF_OK;
}

int bkf_pde_init_uniform(bkf_pde *m, double amp, unsigned long seed, bkf_error *err)
{
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    int rc = pde_init_uniform_body(m, amp, seed, err);
    bkf_gsl_handler_pop(handler);
    return rc;
}

static int pde_init_oscillation_body(bkf_pde *m, size_t j, double amp, bkf_error *err)
{
    if (!m) return bkf_error_set(err, BKF_EINPUT, "simulation object is NULL");
    int s;
    if ((s = check_amp("amp", amp, err))) return s;
    if (j >= m->N / 2)
        return bkf_error_set(err, BKF_EINPUT, "mode j = %zu is outside [0, %zu] (N/2 - 1)", j,
                             m->N / 2 - 1);
    bkf_error e;
    if (bkf_model_check_nu_active(m->p.nu, &e) != BKF_OK)
        return bkf_error_set(err, BKF_EINPUT, "the global oscillation needs a limit cycle: %s",
                             e.message);
    bkf_cycle *cy = bkf_cycle_alloc();
    if (!cy) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    bkf_cycle_options co = bkf_cycle_options_default();
    co.tol = 1e-12;
    s = bkf_cycle_solve(cy, m->p.gamma, m->p.nu, &co, &e);
    if (s) {
        co.tol = 1e-10;
        s = bkf_cycle_solve(cy, m->p.gamma, m->p.nu, &co, &e);
    }
    if (s) {
        bkf_cycle_free(cy);
        return bkf_error_set(err, s, "limit cycle at mu = gamma = %.15g: %s", m->p.gamma,
                             e.message);
    }
    double slope = bkf_cycle_get(cy)->section_slope;
    bkf_cycle_free(cy);
    size_t N = m->N;
    double q = 2.0 * M_PI * (double)j / m->p.S;
    double eta0 = slope / m->p.gamma + bkf_model_friction(m->p.nu);
    for (size_t i = 0; i < N; i++) {
        m->y[i] = m->p.nu + amp * cos(q * (double)i * m->h);
        m->y[N + i] = eta0;
    }
    m->t = 0.0;
    mark_set(m);
    return BKF_OK;
}

int bkf_pde_init_oscillation(bkf_pde *m, size_t j, double amp, bkf_error *err)
{
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    int rc = pde_init_oscillation_body(m, j, amp, err);
    bkf_gsl_handler_pop(handler);
    return rc;
}

static int pde_add_noise_body(bkf_pde *m, double amp, unsigned long seed, bkf_error *err)
{
    if (!m) return bkf_error_set(err, BKF_EINPUT, "simulation object is NULL");
    int s = check_amp("noise", amp, err);
    if (s) return s;
    if ((s = noise(m, amp, seed, m->psit, err))) return s;
    for (size_t i = 0; i < m->N; i++) m->y[i] += m->psit[i];
    mark_set(m);
    return BKF_OK;
}

int bkf_pde_add_noise(bkf_pde *m, double amp, unsigned long seed, bkf_error *err)
{
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    int rc = pde_add_noise_body(m, amp, seed, err);
    bkf_gsl_handler_pop(handler);
    return rc;
}

/* The seed's field v (N values, continuum) without the modes k >= k0 for
 * the lowest k0 whose removed field stays within `bound` everywhere; v is
 * untouched where no mode can go.
 *
 * Why: the cycle's profile is accurate to its tolerance, but its pointwise
 * rounding (about 3e-14 at mu 2.5) is white: at N 65536 the modes above the
 * front's spectrum (k > ~1000 for n = 4, S 20) hold 2e-16 each, whose sum,
 * the bound lawson8 must put on what it leaves out of the explicit term
 * (fast_start in pde_etd.c), exceeded that bound for the first ~440 steps,
 * and the fast set was averaged there at three times a step's transforms.
 * The removed field is measured, not bounded: its maximum from one inverse
 * transform per candidate k0, found by bisection (the tail's maximum
 * shrinks with k0 but not strictly, so the k0 kept is one that was
 * measured). */
static int band_limit(bkf_pde *m, double *v, double bound)
{
    size_t N = m->N, nc = N / 2 + 1;
    fftw_complex *spec = fftw_malloc(nc * sizeof *spec);
    if (!spec) return BKF_ENOMEM;
    memcpy(m->rbuf, v, N * sizeof *v);
    fftw_execute_dft_r2c(m->fwd, m->rbuf, spec);
    double inv = 1.0 / (double)N;
    size_t lo = 1, hi = nc; /* the tail from hi is within bound, from lo not (or untried) */
    while (hi - lo > 1) {
        size_t mid = lo + (hi - lo) / 2;
        memset(m->cbuf2, 0, mid * sizeof *m->cbuf2);
        memcpy(m->cbuf2 + mid, spec + mid, (nc - mid) * sizeof *spec);
        fftw_execute_dft_c2r(m->bwd, m->cbuf2, m->lap);
        double big = 0.0;
        for (size_t i = 0; i < N; i++) big = fmax(big, fabs(m->lap[i]));
        if (big * inv <= bound) hi = mid;
        else lo = mid;
    }
    if (hi < nc) {
        memcpy(m->cbuf2, spec, hi * sizeof *spec);
        memset(m->cbuf2 + hi, 0, (nc - hi) * sizeof *m->cbuf2);
        fftw_execute_dft_c2r(m->bwd, m->cbuf2, m->lap);
        for (size_t i = 0; i < N; i++) v[i] = m->lap[i] * inv;
    }
    fftw_free(spec);
    return BKF_OK;
}

static int pde_init_front_body(bkf_pde *m, const bkf_pde_wave *wave, bkf_pde_front_info *info,
                               double *clean_psi, bkf_error *err)
{
    if (!m) return bkf_error_set(err, BKF_EINPUT, "simulation object is NULL");
    if (!wave) return bkf_error_set(err, BKF_EINPUT, "wave is NULL");
    bkf_pde_wave sp = *wave;
    int s;
    if (sp.n < 1) return bkf_error_set(err, BKF_EINPUT, "the number of fronts n must be >= 1");
    if (sp.direction != -1 && sp.direction != 1)
        return bkf_error_set(err, BKF_EINPUT, "direction must be -1 or +1");
    if ((s = check_amp("noise", sp.noise, err))) return s;
    if (!isfinite(sp.tol) || sp.tol < 1e-14 || sp.tol > 1e-4)
        return bkf_error_set(err, BKF_EINPUT, "front tol = %g is outside [1e-14, 1e-4]", sp.tol);
    bkf_error e;
    if (bkf_model_check_nu_active(m->p.nu, &e) != BKF_OK)
        return bkf_error_set(err, BKF_EINPUT, "fronts need a limit cycle: %s", e.message);
    if (!(isfinite(sp.v) && sp.v > m->p.c))
        return bkf_error_set(err, BKF_EINPUT, "v = %g must be finite and > c = %.15g", sp.v, m->p.c);
    if (!(sp.mu >= BKF_CYCLE_MU_MIN && sp.mu <= BKF_CYCLE_MU_MAX))
        return bkf_error_set(err, BKF_EINPUT, "mu = %.15g is outside [%g, %g] (the cycle engine's "
                             "range)", sp.mu, BKF_CYCLE_MU_MIN, BKF_CYCLE_MU_MAX);

    bkf_cycle *cy = bkf_cycle_alloc();
    if (!cy) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    bkf_cycle_options co = bkf_cycle_options_default();
    co.tol = sp.tol;
    s = bkf_cycle_solve(cy, sp.mu, m->p.nu, &co, &e);
    if (s) {
        co.tol = fmax(sp.tol, 1e-10);
        s = bkf_cycle_solve(cy, sp.mu, m->p.nu, &co, &e);
    }
    if (s) {
        bkf_cycle_free(cy);
        return bkf_error_set(err, s, "cycle at mu = %.15g: %s", sp.mu, e.message);
    }
    double v = sp.v, c = m->p.c;
    /* sqrt(1 - c^2/v^2) without the cancellation near the sonic limit */
    double stretch = sqrt((v - c) * (v + c)) / v;
    size_t N = m->N;
    double g = m->p.gamma;
    /* the grid's points in z, sampled in one pass: f over them in m->y,
     * f' in its second half */
    for (size_t i = 0; i < N; i++) m->y[i] = (double)sp.direction * -1.0 * ((double)i * m->h / v) / stretch;
    s = bkf_cycle_profile_points(cy, m->y, N, m->y, m->y + N, &e);
    if (s) {
        bkf_cycle_free(cy);
        return bkf_error_set(err, s, "cycle profile: %s", e.message);
    }
    for (size_t i = 0; i < N; i++) m->y[N + i] = m->y[N + i] / stretch / g + bkf_model_friction(m->y[i]);
    /* a tenth of the profile's accuracy, relative to each field's size */
    if (m->p.kind == BKF_MODEL_CONTINUUM)
        for (int field = 0; field < 2; field++) {
            double *v = m->y + (size_t)field * N, big = 1.0;
            for (size_t i = 0; i < N; i++) big = fmax(big, fabs(v[i]));
            if ((s = band_limit(m, v, co.tol * big))) {
                bkf_cycle_free(cy);
                return bkf_error_set(err, s, "out of memory");
            }
        }
    const bkf_cycle_result *cr = bkf_cycle_get(cy);
    if (info) {
        info->v = v;
        info->v_err = NAN;
        info->mu = sp.mu;
        info->T = cr->period;
        info->stretch = stretch;
        info->period_fixed = cr->period * stretch;
        info->wavelength = m->p.S / (double)sp.n;
        info->residual = (double)sp.n * cr->period * v * stretch / m->p.S - 1.0;
        info->roots_for_n = 0;
    }
    bkf_cycle_free(cy);
    if (clean_psi) memcpy(clean_psi, m->y, N * sizeof *clean_psi);
    if (sp.noise > 0) {
        if ((s = noise(m, sp.noise, sp.seed, m->psit, err))) return s;
        for (size_t i = 0; i < N; i++) m->y[i] += m->psit[i];
    }
    m->t = 0.0;
    mark_set(m);
    if (clean_psi && m->o.dealias) project(m, clean_psi);
    return BKF_OK;
}

int bkf_pde_init_front(bkf_pde *m, const bkf_pde_wave *wave, bkf_pde_front_info *info,
                       double *clean_psi, bkf_error *err)
{
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    int rc = pde_init_front_body(m, wave, info, clean_psi, err);
    bkf_gsl_handler_pop(handler);
    return rc;
}

/* ---------------------------------------------------------------- run */

static int blown_up(const double *y, size_t N)
{
    for (size_t i = 0; i < 2 * N; i++)
        if (!(fabs(y[i]) <= BLOWUP)) return 1;
    return 0;
}

static int pde_run_body(bkf_pde *m, double t_end, double sample_dt, bkf_pde_observer observer,
                        void *odata, bkf_pde_progress progress, void *pdata, bkf_error *err)
{
    if (!m) return bkf_error_set(err, BKF_EINPUT, "simulation object is NULL");
    double t0 = m->t;
    if (!isfinite(t_end) || !(t_end > t0))
        return bkf_error_set(err, BKF_EINPUT, "t_end = %g must be finite and > t = %g", t_end,
                             t0);
    if (!isfinite(sample_dt) || !(sample_dt > 0))
        return bkf_error_set(err, BKF_EINPUT, "sample_dt = %g must be finite and > 0",
                             sample_dt);
    if (m->etd)
        return bkf_pde_etd_run(m, t_end, sample_dt, observer, odata, progress, pdata, err);
    size_t N = m->N, dim = m->dim;
    m->stats.stopped = 0;
    /* Samples closer than this to t_end are t_end: rounding in t0 + k dt
     * must not add a sliver of a step or a duplicate sample. */
    double slack = 1e-9 * fmax(sample_dt, 1e-300) + 4 * 2.2e-16 * fabs(t_end);
    size_t k_next = 0;
    int end_emitted = 0;

    if (!m->have_f) {
        if (rhs(m->t, m->y, m->f, m) != GSL_SUCCESS)
            return bkf_error_set(err, BKF_EBLOWUP, "the initial state is not finite or too large");
        m->have_f = 1;
    }
    if (observer) {
        k_next = 1;
        if (bkf_pde_emit(m, observer, odata, m->t, m->y)) {
            m->stats.stopped = 1;
            return BKF_OK;
        }
    }
    size_t steps_here = 0;
    double h_floor = 1e-12 * fmax(1.0, fabs(t_end));
    while (m->t < t_end) {
        double natural = fmin(m->hstep, m->hcap);
        double dt = natural;
        int last = 0, clipped = 0;
        if (m->t + dt >= t_end - slack) {
            dt = t_end - m->t;
            last = 1;
        }
        /* Samples are step ends, as accurate as the steps: a quintic
         * Hermite between the ends of an 8th-order step was 1000 times
         * worse than tol (1.2e-9 at tol 1e-12). */
        if (observer) {
            double tk = t0 + (double)k_next * sample_dt;
            if (tk > m->t + slack && tk < m->t + dt - slack) {
                dt = tk - m->t;
                clipped = 1;
                last = 0;
            }
        }
        memcpy(m->ytry, m->y, dim * sizeof *m->y);
        int s = gsl_odeiv2_step_apply(m->step, m->t, dt, m->ytry, m->yerr, m->f, m->f1, &m->sys);
        if (s != GSL_SUCCESS) {
            /* The trial state left the finite range: a step far too long. */
            m->stats.rejected++;
            m->hstep = 0.25 * dt;
            if (m->hstep < h_floor)
                return bkf_error_set(err, BKF_EBLOWUP,
                                     "the field blew up at t = %.6g (|psi| > %g or not finite)",
                                     m->t, BLOWUP);
            continue;
        }
        double hnew = dt;
        int adj = gsl_odeiv2_control_hadjust(m->control, m->step, m->ytry, m->yerr, m->f1, &hnew);
        if (adj == GSL_ODEIV_HADJ_DEC) {
            m->stats.rejected++;
            m->hstep = hnew;
            if (hnew < h_floor)
                return bkf_error_set(err, BKF_ENUMERIC,
                                     "step size underflow at t = %.6g (tol %g cannot be met)",
                                     m->t, m->o.tol);
            continue;
        }
        double t1 = last ? t_end : m->t + dt;
        m->stats.steps++;
        steps_here++;
        m->stats.h_last = dt;
        if (!last || dt >= natural) {
            if (dt < m->stats.h_min) m->stats.h_min = dt;
        }
        if (dt > m->stats.h_max) m->stats.h_max = dt;

        if (observer) {
            /* Every sample time up to t1 is t1 itself (the step was cut
             * there); samples closer together than the slack are one. */
            for (;;) {
                double tk = t0 + (double)k_next * sample_dt;
                if (tk > t1 + slack || tk > t_end + slack) break;
                double ts = t1;
                if (fabs(ts - t_end) <= slack) {
                    ts = t_end;
                    end_emitted = 1;
                }
                k_next++;
                if (fabs(tk - t1) > slack) continue;
                if (bkf_pde_emit(m, observer, odata, ts, m->ytry)) {
                    m->stats.stopped = 1;
                    break;
                }
            }
        }
        /* accept */
        double *tmp = m->y;
        m->y = m->ytry;
        m->ytry = tmp;
        tmp = m->f;
        m->f = m->f1;
        m->f1 = tmp;
        m->t = t1;
        /* a step cut short (at t_end or a sample) says little about the
         * natural one */
        m->hstep = last || clipped ? fmax(hnew, natural) : hnew;
        if (m->stats.stopped) return BKF_OK;
        if (blown_up(m->y, N))
            return bkf_error_set(err, BKF_EBLOWUP,
                                 "the field blew up at t = %.6g (|psi| > %g or not finite)", m->t,
                                 BLOWUP);
        if (progress && progress((m->t - t0) / (t_end - t0), pdata)) {
            m->stats.stopped = 1;
            return BKF_OK;
        }
        if (m->o.cancel && *m->o.cancel && m->t < t_end) {
            m->stats.stopped = 1;
            return bkf_error_set(err, BKF_ECANCELED, "canceled at t = %.9g of %.9g", m->t,
                                 t_end);
        }
        if (m->o.max_steps && steps_here >= m->o.max_steps && m->t < t_end)
            return bkf_error_set(err, BKF_EBUDGET, "more than %zu steps before t = %g",
                                 m->o.max_steps, t_end);
    }
    if (observer && !end_emitted && bkf_pde_emit(m, observer, odata, m->t, m->y)) m->stats.stopped = 1;
    return BKF_OK;
}

int bkf_pde_run(bkf_pde *m, double t_end, double sample_dt, bkf_pde_observer observer,
                void *odata, bkf_pde_progress progress, void *pdata, bkf_error *err)
{
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    int rc = pde_run_body(m, t_end, sample_dt, observer, odata, progress, pdata, err);
    bkf_gsl_handler_pop(handler);
    return rc;
}

/* The flow of one grid for the periodic-orbit solver: the simulator's
 * right-hand side (pde.c, through pde_internal.h) integrated by GSL's
 * rk8pd with the tangent (variational) flow alongside, under the
 * simulator's stability cap; the grid's shift, derivative and resampling. */
#include "orbit_internal.h"

#include <gsl/gsl_errno.h>
#include <gsl/gsl_math.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bkfront/fft.h"

void orbit_flow_free(orbit_flow *fl)
{
    if (!fl) return;
    for (int i = 0; i < 2; i++) {
        if (fl->evolve[i]) gsl_odeiv2_evolve_free(fl->evolve[i]);
        if (fl->control[i]) gsl_odeiv2_control_free(fl->control[i]);
        if (fl->step[i]) gsl_odeiv2_step_free(fl->step[i]);
    }
    bkf_fft_lock();
    if (fl->fwd) fftw_destroy_plan(fl->fwd);
    if (fl->bwd) fftw_destroy_plan(fl->bwd);
    bkf_fft_unlock();
    fftw_free(fl->rbuf);
    fftw_free(fl->cbuf);
    free(fl->y);
    free(fl->work);
    bkf_pde_free(fl->pde);
    free(fl);
}

orbit_flow *orbit_flow_alloc(const bkf_model_params *model, const bkf_orbit_options *o,
                             bkf_error *err)
{
    bkf_pde_options po = bkf_pde_options_default();
    po.dealias = o->dealias;
    po.filter = o->filter;
    po.tol = o->flow_tol > 0 ? o->flow_tol : 1e-10;
    bkf_pde *pde = bkf_pde_alloc(model, &po, err);
    if (!pde) return NULL;
    orbit_flow *fl = calloc(1, sizeof *fl);
    if (!fl) {
        bkf_pde_free(pde);
        bkf_error_set(err, BKF_ENOMEM, "out of memory");
        return NULL;
    }
    fl->pde = pde;
    fl->kind = model->kind;
    fl->N = model->N;
    fl->S = model->S;
    fl->hcap = pde->hcap;
    fl->cancel = o->cancel;
    size_t N = fl->N;
    fl->y = calloc(4 * N + 4, sizeof *fl->y); /* room for f (2N + 2) after the state */
    fl->work = calloc(2 * N, sizeof *fl->work);
    fl->rbuf = fftw_malloc(N * sizeof *fl->rbuf);
    fl->cbuf = fftw_malloc((N / 2 + 1) * sizeof *fl->cbuf);
    if (!fl->y || !fl->work || !fl->rbuf || !fl->cbuf) goto nomem;
    bkf_fft_lock();
    fl->fwd = fftw_plan_dft_r2c_1d((int)N, fl->rbuf, fl->cbuf, FFTW_ESTIMATE);
    fl->bwd = fftw_plan_dft_c2r_1d((int)N, fl->cbuf, fl->rbuf, FFTW_ESTIMATE);
    bkf_fft_unlock();
    if (!fl->fwd || !fl->bwd) goto nomem;
    for (int i = 0; i < 2; i++) {
        size_t dim = (i ? 4 : 2) * N + 2;
        fl->step[i] = gsl_odeiv2_step_alloc(gsl_odeiv2_step_rk8pd, dim);
        fl->control[i] = gsl_odeiv2_control_y_new(po.tol, po.tol);
        fl->control_tol[i] = po.tol;
        fl->evolve[i] = gsl_odeiv2_evolve_alloc(dim);
        if (!fl->step[i] || !fl->control[i] || !fl->evolve[i]) goto nomem;
    }
    return fl;
nomem:
    orbit_flow_free(fl);
    bkf_error_set(err, BKF_ENOMEM, "out of memory");
    return NULL;
}

/* The quadratures Q and D ride in the simulator's state vector; held
 * constant here so that they take no part in the error control. */
static int sys_state(double t, const double y[], double dydt[], void *params)
{
    (void)t;
    orbit_flow *fl = params;
    size_t N = fl->N;
    if (pde_rhs_eval(fl->pde, y, dydt) != BKF_OK) return GSL_EBADFUNC;
    dydt[2 * N] = dydt[2 * N + 1] = 0.0;
    return GSL_SUCCESS;
}

static int sys_tangent(double t, const double y[], double dydt[], void *params)
{
    int s = sys_state(t, y, dydt, params);
    if (s != GSL_SUCCESS) return s;
    orbit_flow *fl = params;
    size_t off = 2 * fl->N + 2;
    return pde_tangent(fl->pde, y, y + off, dydt + off) == BKF_OK ? GSL_SUCCESS : GSL_EBADFUNC;
}

int orbit_flow_rhs(orbit_flow *fl, const double *u, double *f, bkf_error *err)
{
    size_t N = fl->N;
    memcpy(fl->y, u, 2 * N * sizeof *u);
    fl->y[2 * N] = fl->y[2 * N + 1] = 0.0;
    double *dy = fl->y + 2 * N + 2; /* room for 2N + 2 values */
    if (pde_rhs_eval(fl->pde, fl->y, dy) != BKF_OK)
        return bkf_error_set(err, BKF_EBLOWUP, "the state is not finite or beyond the bound");
    memcpy(f, dy, 2 * N * sizeof *f);
    return BKF_OK;
}

int orbit_flow_run(orbit_flow *fl, const double *u0, const double *v0, double T, double tol,
                   double *uT, double *vT, double *fT, bkf_error *err)
{
    size_t N = fl->N, off = 2 * N + 2;
    int tg = v0 != NULL;
    if (!(T > 0) || !isfinite(T))
        return bkf_error_set(err, BKF_ENUMERIC, "the period %g left (0, inf)", T);
    if (fl->cancel && *fl->cancel) return bkf_error_set(err, BKF_ECANCELED, "canceled");
    double *y = fl->y;
    memcpy(y, u0, 2 * N * sizeof *u0);
    y[2 * N] = y[2 * N + 1] = 0.0;
    /* The tangent is integrated at unit size so that the absolute part
     * of the tolerance means the same for every direction. */
    double vscale = 0.0;
    if (tg) {
        for (size_t i = 0; i < 2 * N; i++) vscale = fmax(vscale, fabs(v0[i]));
        double iv = vscale > 0 ? 1.0 / vscale : 0.0;
        for (size_t i = 0; i < 2 * N; i++) y[off + i] = v0[i] * iv;
    }
    gsl_odeiv2_system sys = {tg ? sys_tangent : sys_state, NULL, (tg ? 4 : 2) * N + 2, fl};
    gsl_odeiv2_step *st = fl->step[tg];
    gsl_odeiv2_evolve *ev = fl->evolve[tg];
    if (fl->control_tol[tg] != tol) {
        gsl_odeiv2_control_init(fl->control[tg], tol, tol, 1.0, 0.0);
        fl->control_tol[tg] = tol;
    }
    gsl_odeiv2_step_reset(st);
    gsl_odeiv2_evolve_reset(ev);
    double t = 0.0, h = fmin(0.05 * fl->hcap, 0.01 * T);
    size_t steps = 0;
    while (t < T) {
        if (h > fl->hcap) h = fl->hcap;
        int s = gsl_odeiv2_evolve_apply(ev, fl->control[tg], st, &sys, &t, T, &h, y);
        if (s != GSL_SUCCESS)
            return bkf_error_set(err, BKF_EBLOWUP,
                                 "the flow blew up or failed at t = %.6g of the period %.6g", t, T);
        if (h < 1e-12 * T && t < T)
            return bkf_error_set(err, BKF_ENUMERIC,
                                 "step size underflow at t = %.6g (flow tol %g cannot be met)", t,
                                 tol);
        steps++;
        if (fl->cancel && *fl->cancel)
            return bkf_error_set(err, BKF_ECANCELED, "canceled at t = %.6g of the period", t);
    }
    fl->steps += steps;
    fl->flows++;
    if (tg) fl->tangent_flows++;
    if (uT) memcpy(uT, y, 2 * N * sizeof *uT);
    if (tg && vT)
        for (size_t i = 0; i < 2 * N; i++) vT[i] = y[off + i] * vscale;
    if (fT) {
        /* y's second half held the tangent, copied out above */
        if (pde_rhs_eval(fl->pde, y, y + off) != BKF_OK)
            return bkf_error_set(err, BKF_EBLOWUP, "the flow's end is not finite");
        memcpy(fT, y + off, 2 * N * sizeof *fT);
    }
    return BKF_OK;
}

/* One field's spectrum into cbuf, scaled by 1/N. */
static void forward(orbit_flow *fl, const double *v)
{
    size_t N = fl->N;
    memcpy(fl->rbuf, v, N * sizeof *v);
    fftw_execute_dft_r2c(fl->fwd, fl->rbuf, fl->cbuf);
    double inv = 1.0 / (double)N;
    for (size_t k = 0; k <= N / 2; k++) {
        fl->cbuf[k][0] *= inv;
        fl->cbuf[k][1] *= inv;
    }
}

static void backward(orbit_flow *fl, double *out)
{
    fftw_execute_dft_c2r(fl->bwd, fl->cbuf, fl->rbuf);
    memcpy(out, fl->rbuf, fl->N * sizeof *out);
}

void orbit_flow_shift(orbit_flow *fl, const double *u, double s, double *out, double *dout)
{
    size_t N = fl->N;
    if (fl->kind == BKF_MODEL_CHAIN) {
        double h = fl->S / (double)N;
        long b = lround(s / h);
        size_t sh = (size_t)(((b % (long)N) + (long)N) % (long)N);
        for (int f = 0; f < 2; f++)
            for (size_t i = 0; i < N; i++)
                fl->work[f * N + (i + sh) % N] = u[f * N + i];
        memcpy(out, fl->work, 2 * N * sizeof *out);
        if (dout) memset(dout, 0, 2 * N * sizeof *dout);
        return;
    }
    for (int f = 0; f < 2; f++) {
        const double *v = u + f * N;
        fftw_complex *c = fl->cbuf;
        /* the derivative first, so that out may be u itself */
        for (int pass = dout ? 1 : 0; pass >= 0; pass--) {
            forward(fl, v);
            for (size_t k = 0; k <= N / 2; k++) {
                double q = 2.0 * M_PI * (double)k / fl->S, a = c[k][0], b = c[k][1];
                double cs = cos(q * s), sn = sin(q * s);
                if (2 * k == N) {
                    /* the real Nyquist mode: R_s keeps cos(q s) of it */
                    c[k][0] = pass ? -q * sn * a : cs * a;
                    c[k][1] = 0.0;
                    continue;
                }
                /* (a + ib) e^{-iqs}; its s-derivative -iq (a + ib) e^{-iqs} */
                double re = a * cs + b * sn, im = b * cs - a * sn;
                if (pass) {
                    c[k][0] = q * im;
                    c[k][1] = -q * re;
                } else {
                    c[k][0] = re;
                    c[k][1] = im;
                }
            }
            backward(fl, pass ? dout + f * N : out + f * N);
        }
    }
}

void orbit_flow_dx(orbit_flow *fl, const double *u, double *out)
{
    size_t N = fl->N;
    if (fl->kind == BKF_MODEL_CHAIN) {
        memset(out, 0, 2 * N * sizeof *out);
        return;
    }
    for (int f = 0; f < 2; f++) {
        forward(fl, u + f * N);
        for (size_t k = 0; k <= N / 2; k++) {
            double q = 2 * k == N ? 0.0 : 2.0 * M_PI * (double)k / fl->S;
            double a = fl->cbuf[k][0], b = fl->cbuf[k][1];
            fl->cbuf[k][0] = -q * b;
            fl->cbuf[k][1] = q * a;
        }
        backward(fl, out + f * N);
    }
}

int orbit_flow_resample(orbit_flow *fl, const double *w, size_t M, double *u, bkf_error *err)
{
    size_t N = fl->N;
    if (M == N) {
        memcpy(u, w, 2 * N * sizeof *u);
        return BKF_OK;
    }
    if (fl->kind == BKF_MODEL_CHAIN)
        return bkf_error_set(err, BKF_EINPUT, "the chain is not resampled (N %zu vs %zu)", N, M);
    size_t nc = M / 2 + 1;
    double *rb = fftw_malloc(M * sizeof *rb);
    fftw_complex *cb = fftw_malloc(nc * sizeof *cb);
    fftw_plan p = NULL;
    if (rb && cb) {
        bkf_fft_lock();
        p = fftw_plan_dft_r2c_1d((int)M, rb, cb, FFTW_ESTIMATE);
        bkf_fft_unlock();
    }
    if (!p) {
        fftw_free(rb);
        fftw_free(cb);
        return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    }
    size_t top = (M < N ? M : N) / 2; /* the smaller grid's Nyquist, dropped */
    for (int f = 0; f < 2; f++) {
        memcpy(rb, w + f * M, M * sizeof *rb);
        fftw_execute(p);
        for (size_t k = 0; k <= N / 2; k++) {
            int in = k < top;
            fl->cbuf[k][0] = in ? cb[k][0] / (double)M : 0.0;
            fl->cbuf[k][1] = in ? cb[k][1] / (double)M : 0.0;
        }
        backward(fl, u + f * N);
    }
    bkf_fft_lock();
    fftw_destroy_plan(p);
    bkf_fft_unlock();
    fftw_free(rb);
    fftw_free(cb);
    return BKF_OK;
}

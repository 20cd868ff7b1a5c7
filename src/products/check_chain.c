/* The check of the chain's rotating waves (check.c): the run sampled at
 * the shift times, its phase and deviation judged.  Above the verdicts
 * (check_judge.c), below the product (check.c). */
#include "check_internal.h"

#include <fftw3.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------ the chain */

/* The run sampled at the shift times m tau (see check.h): the phase the
 * fronts gained, the deviation orthogonal to it, the front count. */
typedef struct {
    size_t N, cap, count;
    double tau, nu;
    const double *u0, *f0; /* the wave and the field at it (2N values) */
    double ff;             /* |f0|^2 */
    double *t, *phase, *dev;
    size_t *fronts;
    int oom;
} chain_obs;

/* Rising crossings of nu around the ring. */
static size_t chain_fronts(const double *psi, size_t N, double nu)
{
    size_t count = 0;
    for (size_t i = 0; i < N; i++)
        count += psi[i] < nu && psi[(i + 1) % N] >= nu;
    return count;
}

static int chain_observe(const bkf_pde_sample *smp, void *data)
{
    chain_obs *ob = data;
    size_t N = ob->N;
    if (ob->count == ob->cap) {
        size_t cap = ob->cap ? 2 * ob->cap : 256;
        double *t = realloc(ob->t, cap * sizeof *t);
        if (t) ob->t = t;
        double *ph = realloc(ob->phase, cap * sizeof *ph);
        if (ph) ob->phase = ph;
        double *d = realloc(ob->dev, cap * sizeof *d);
        if (d) ob->dev = d;
        size_t *fr = realloc(ob->fronts, cap * sizeof *fr);
        if (fr) ob->fronts = fr;
        if (!t || !ph || !d || !fr) return ob->oom = 1;
        ob->cap = cap;
    }
    size_t m = (size_t)llround(smp->t / ob->tau) % N;
    /* W_m: block i is block i + m of the start (both fields) */
    double dot = 0.0;
    for (size_t k = 0; k < 2 * N; k++) {
        size_t j = (k < N ? 0 : N) + (k % N + m) % N;
        double u = k < N ? smp->psi[k] : smp->eta[k - N];
        dot += (u - ob->u0[j]) * ob->f0[j];
    }
    double delta = dot / ob->ff, dev = 0.0;
    for (size_t k = 0; k < 2 * N; k++) {
        size_t j = (k < N ? 0 : N) + (k % N + m) % N;
        double u = k < N ? smp->psi[k] : smp->eta[k - N];
        dev = fmax(dev, fabs(u - ob->u0[j] - delta * ob->f0[j]));
    }
    size_t r = ob->count++;
    ob->t[r] = smp->t;
    ob->phase[r] = delta;
    ob->dev[r] = isfinite(dev) ? dev : INFINITY;
    ob->fronts[r] = chain_fronts(smp->psi, N, ob->nu);
    return 0;
}

static void chain_reader(size_t i, const void *data, double *t, size_t *fronts, double *dev)
{
    const chain_obs *ob = data;
    *t = ob->t[i];
    *fronts = ob->fronts[i];
    *dev = ob->dev[i];
}

/* The sample nearest to time t. */
static size_t chain_sample_at(const chain_obs *ob, double t)
{
    size_t best = 0;
    for (size_t r = 1; r < ob->count; r++)
        if (fabs(ob->t[r] - t) < fabs(ob->t[best] - t)) best = r;
    return best;
}

static int check_chain_wave(const check_ctx *c, const bkf_chainwave *w, bkf_check_row *row,
                            bkf_error *err)
{
    const bkf_check_options *o = c->o;
    const bkf_model_params *p = c->model;
    size_t N = p->N, n = w->n;
    bkf_pde_options po = bkf_pde_options_default();
    po.tol = o->tol ? o->tol : BKF_CHECK_CHAIN_RUN_TOL;
    po.stepper = BKF_PDE_RK8PD;
    po.filter = 0;
    po.cancel = check_cancel(c);
    double *f0 = malloc(2 * N * sizeof *f0), *u0 = malloc(2 * N * sizeof *u0);
    chain_obs ob = {N, 0, 0, w->tau, p->nu, u0, f0, 0.0, NULL, NULL, NULL, NULL, 0};
    bkf_pde *pde = NULL;
    int s = (f0 && u0) ? BKF_OK : bkf_error_set(err, BKF_ENOMEM, "out of memory");
    if (!s) {
        double K = p->c * p->c * (double)(N * N) / (p->S * p->S);
        memcpy(u0, w->psi, N * sizeof *u0);
        memcpy(u0 + N, w->eta, N * sizeof *u0);
        for (size_t i = 0; i < N; i++) {
            double x = w->psi[i];
            double lap = w->psi[(i + 1) % N] - 2.0 * x + w->psi[(i + N - 1) % N];
            f0[i] = p->gamma * (w->eta[i] - bkf_model_friction(x));
            f0[N + i] = -(x - p->nu - K * lap) / p->gamma;
        }
        for (size_t k = 0; k < 2 * N; k++) ob.ff += f0[k] * f0[k];
        pde = bkf_pde_alloc(p, &po, err);
        if (!pde) s = BKF_ENOMEM;
    }
    bkf_error e;
    if (!s) s = bkf_pde_set_state(pde, w->psi, w->eta, 0.0, err);
    if (!s) s = bkf_pde_add_noise(pde, o->perturb, o->seed, err);
    /* the run ends on a shift time, the last sample with it; samples at
     * every k-th shift time (k = 1 up to tmax = 1024 tau) */
    double dt = w->tau * ceil(check_sample_dt(w->tau, o->tmax) / w->tau - 1e-9);
    double t_end = ceil(o->tmax / dt - 1e-9) * dt;
    if (!s) {
        s = bkf_pde_run(pde, t_end, dt, chain_observe, &ob, check_progress, (void *)c, &e);
        if (ob.oom) s = bkf_error_set(err, BKF_ENOMEM, "out of memory");
    }
    int blew_up = (s == BKF_EBLOWUP || s == BKF_ENUMERIC) && ob.count >= 2;
    if (blew_up) s = BKF_OK;
    if (s == BKF_ECANCELED) bkf_error_set(err, s, "canceled");
    else if (s && !ob.oom && pde)
        bkf_error_set(err, s, "n = %zu, chain of %zu blocks: %s", n, N, e.message);
    if (!s && ob.count) {
        int constant = 1;
        for (size_t r = 1; r < ob.count; r++) constant &= ob.fronts[r] == ob.fronts[0];
        row->t_end = ob.t[ob.count - 1];
        row->fronts_start = (double)ob.fronts[0];
        row->fronts_end = (double)ob.fronts[ob.count - 1];
        row->deviation_start = ob.dev[0];
        row->deviation_mid = ob.dev[chain_sample_at(&ob, 0.5 * t_end)];
        row->deviation_end = ob.dev[ob.count - 1];
        double t_lin;
        /* the count a rotating wave keeps is its own (a coarse chain shows
           n fronts as n crossings only where they are wider than a block) */
        size_t n_seen = ob.fronts[0];
        if ((s = check_fit_deviation(chain_reader, &ob, ob.count, n_seen, o, &row->growth, &t_lin)))
            bkf_error_set(err, s, "out of memory");
        size_t last = check_coherent_end(chain_reader, &ob, ob.count, n_seen, 1, check_speed_bound(o), o->tmax);
        size_t first = chain_sample_at(&ob, 0.5 * ob.t[last]);
        if (!s && last >= FIT_MIN_RECORDS && last - first >= 2) {
            double mt = 0, mp = 0, stt = 0, stp = 0, rss = 0;
            size_t m = last - first + 1;
            for (size_t r = first; r <= last; r++) mt += ob.t[r] / (double)m, mp += ob.phase[r] / (double)m;
            for (size_t r = first; r <= last; r++) {
                stt += (ob.t[r] - mt) * (ob.t[r] - mt);
                stp += (ob.t[r] - mt) * (ob.phase[r] - mp);
            }
            double slope = stp / stt;
            for (size_t r = first; r <= last; r++) {
                double d = ob.phase[r] - mp - slope * (ob.t[r] - mt);
                rss += d * d;
            }
            /* u(t) = W(t + delta(t)): the fronts run at v (1 + d delta/dt) */
            row->v_meas = w->v * (1.0 + slope);
            row->v_meas_err = w->v * sqrt(rss / (double)(m - 2) / stt);
            row->rel_err = slope;
            row->fit_from = ob.t[first];
            row->fit_to = ob.t[last];
        }
        if (!s) {
            int kept;
            row->verdict = bkf_check_judge(n_seen, blew_up, constant, n_seen, row->deviation_end,
                                           &row->growth, row->spectral, row->sigma_max,
                                           row->rel_err, o->rel_tol, &kept);
            row->kept = kept;
            if (blew_up) row->reason = BKF_EBLOWUP;
        }
    }
    bkf_pde_free(pde);
    free(f0);
    free(u0);
    free(ob.t);
    free(ob.phase);
    free(ob.dev);
    free(ob.fronts);
    return s;
}

static bkf_trainspec_verdict chain_spectral(bkf_chainwave_verdict v)
{
    switch (v) {
    case BKF_CHAINWAVE_STABLE: return BKF_TRAINSPEC_STABLE;
    case BKF_CHAINWAVE_UNSTABLE: return BKF_TRAINSPEC_UNSTABLE;
    default: return BKF_TRAINSPEC_UNRESOLVED;
    }
}

int check_chain_run(const bkf_model_params *model, const bkf_check_options *o,
                           const bkf_check_hooks *hooks, bkf_error *err)
{
    bkf_chainwave_options co = bkf_chainwave_options_default();
    co.tol = BKF_CHECK_CHAIN_WAVE_TOL;
    bkf_chainwave_table tab;
    bkf_error e;
    int s = bkf_chainwave_find(model, o->n ? o->n : 1, o->n, &co, &tab, &e);
    if (s) {
        bkf_chainwave_table_free(&tab);
        return bkf_error_set(err, s, "the chain's waves: %s", e.message);
    }
    check_ctx c = {model, o, hooks, o->tol ? o->tol : BKF_CHECK_CHAIN_RUN_TOL, NAN, 0, 0,
                   tab.count, NULL, NULL};
    bkf_check_info info = {tab.count, NAN, (long)(o->n ? o->n : model->N / 2), tab.note, c.tol,
                           NAN, model->N};
    int stop = hooks && hooks->begin ? hooks->begin(&info, hooks->data) : 0;
    const volatile sig_atomic_t *cancel = check_cancel(&c);
    for (size_t i = 0; !s && !stop && i < tab.count; i++) {
        if (cancel && *cancel) {
            s = bkf_error_set(err, BKF_ECANCELED, "canceled after %zu of %zu waves", i,
                              tab.count);
            break;
        }
        const bkf_chainwave *w = &tab.waves[i];
        size_t root = 1;
        for (size_t k = i; k > 0 && tab.waves[k - 1].n == w->n; k--) root++;
        bkf_check_row row;
        bkf_speeds_root sr = {0};
        sr.v = w->v;
        sr.v_err = w->v_err;
        check_row_init(&row, w->n, root, &sr);
        row.grid = BKF_CHECK_GRID_CHAIN;
        row.N = model->N;
        row.tail = w->residual;
        row.spectral = chain_spectral(w->verdict);
        row.sigma_max = w->sigma_max;
        row.sigma_max_err = w->sigma_max_err;
        c.root_index = i;
        s = check_chain_wave(&c, w, &row, err);
        if (!s && row.verdict == BKF_CHECK_CONFLICTS)
            check_warn(&c, "n = %zu, wave %zu: the simulation's perturbation %s at %.3g +- %.3g "
                       "per unit time, the multipliers say %s (|m| %.9g)", row.n, row.root,
                       bkf_check_growth_name(row.growth.verdict), row.growth.rate,
                       row.growth.rate_err, bkf_chainwave_verdict_name(w->verdict), w->mult_abs);
        if (!s) check_explain_undecided(&c, &row);
        if (!s && hooks && hooks->row) stop = hooks->row(&row, hooks->data);
    }
    bkf_chainwave_table_free(&tab);
    return s;
}


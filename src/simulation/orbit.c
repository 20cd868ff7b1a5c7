/* Periodic orbits of the discretised PDE: the public entry points, the
 * solve on one cell and its error estimate (see include/bkfront/orbit.h).
 * The flow is orbit_flow.c, Newton-Krylov orbit_newton.c, the multipliers
 * orbit_mult.c. */
#include "orbit_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

const char *bkf_orbit_shift_mode_name(bkf_orbit_shift_mode mode)
{
    switch (mode) {
    case BKF_ORBIT_SHIFT_NONE: return "none";
    case BKF_ORBIT_SHIFT_FIXED: return "fixed";
    case BKF_ORBIT_SHIFT_FREE: return "free";
    }
    return "unknown";
}

const char *bkf_orbit_symmetry_name(bkf_orbit_symmetry sym)
{
    switch (sym) {
    case BKF_ORBIT_SYM_GENERIC: return "generic";
    case BKF_ORBIT_SYM_UNIFORM: return "uniform";
    case BKF_ORBIT_SYM_TRAVELLING: return "travelling";
    }
    return "unknown";
}

const char *bkf_orbit_mult_kind_name(bkf_orbit_mult_kind kind)
{
    switch (kind) {
    case BKF_ORBIT_MULT_PHYSICAL: return "physical";
    case BKF_ORBIT_MULT_TRIVIAL_TIME: return "trivial_time";
    case BKF_ORBIT_MULT_TRIVIAL_SPACE: return "trivial_space";
    case BKF_ORBIT_MULT_GRID: return "grid";
    }
    return "unknown";
}

const char *bkf_orbit_verdict_name(bkf_orbit_verdict verdict)
{
    switch (verdict) {
    case BKF_ORBIT_STABLE: return "stable";
    case BKF_ORBIT_UNSTABLE: return "unstable";
    case BKF_ORBIT_UNDECIDED: return "undecided";
    }
    return "unknown";
}

bkf_orbit_options bkf_orbit_options_default(void)
{
    bkf_pde_options po = bkf_pde_options_default();
    bkf_orbit_options o;
    memset(&o, 0, sizeof o);
    o.tol = 1e-8;
    o.cells = 1;
    o.shift_mode = BKF_ORBIT_SHIFT_NONE;
    o.flow_tol = 0.0;
    o.dealias = po.dealias;
    o.filter = po.filter;
    o.newton_max_iter = 40;
    o.krylov_max = 200;
    o.grid_check = 1;
    return o;
}

bkf_orbit_mult_options bkf_orbit_mult_options_default(void)
{
    bkf_orbit_mult_options o = {10, -1, 0.0, 300, 0.1, 0.0, NULL};
    return o;
}

/* The flow tolerance a solve at tol uses. */
static double flow_tol_for(const bkf_orbit_options *o)
{
    if (o->flow_tol > 0) return o->flow_tol;
    return fmin(1e-6, fmax(1e-13, 0.01 * o->tol));
}

static int check_options(const bkf_model_params *p, const bkf_orbit_options *o, bkf_error *err)
{
    if (!(o->tol >= BKF_ORBIT_TOL_MIN && o->tol <= BKF_ORBIT_TOL_MAX))
        return bkf_error_set(err, BKF_EINPUT, "tol = %g is outside [%g, %g]", o->tol,
                             BKF_ORBIT_TOL_MIN, BKF_ORBIT_TOL_MAX);
    if (o->flow_tol != 0 && !(o->flow_tol >= BKF_PDE_TOL_MIN && o->flow_tol <= 1e-4))
        return bkf_error_set(err, BKF_EINPUT, "flow_tol = %g is outside [%g, 1e-4] (0: from tol)",
                             o->flow_tol, BKF_PDE_TOL_MIN);
    if (o->shift_mode != BKF_ORBIT_SHIFT_NONE && o->shift_mode != BKF_ORBIT_SHIFT_FIXED &&
        o->shift_mode != BKF_ORBIT_SHIFT_FREE)
        return bkf_error_set(err, BKF_EINPUT, "shift_mode must be none, fixed or free");
    if (o->shift_mode == BKF_ORBIT_SHIFT_FREE && p->kind != BKF_MODEL_CONTINUUM)
        return bkf_error_set(err, BKF_EINPUT,
                             "shift_mode free needs the continuum: the chain has no continuous "
                             "space translation (use fixed, whole blocks)");
    if (o->newton_max_iter < 1 || o->newton_max_iter > 1000)
        return bkf_error_set(err, BKF_EINPUT, "newton_max_iter = %d is outside [1, 1000]",
                             o->newton_max_iter);
    if (o->krylov_max < 5 || o->krylov_max > 500)
        return bkf_error_set(err, BKF_EINPUT, "krylov_max = %d is outside [5, 500]",
                             o->krylov_max);
    size_t m = o->cells, N = p->N;
    if (m < 1 || m > N || N % m)
        return bkf_error_set(err, BKF_EINPUT, "cells = %zu must divide N = %zu", m, N);
    size_t Nc = N / m;
    if (Nc < BKF_PDE_N_MIN || (p->kind == BKF_MODEL_CONTINUUM && Nc % 2))
        return bkf_error_set(err, BKF_EINPUT,
                             "cells = %zu leaves N/cells = %zu points per cell: at least %d%s",
                             m, Nc, BKF_PDE_N_MIN,
                             p->kind == BKF_MODEL_CONTINUUM ? " and even (continuum)" : "");
    return BKF_OK;
}

static bkf_model_params cell_model(const bkf_model_params *p, size_t m, size_t Nc)
{
    bkf_model_params c = *p;
    c.S = p->S / (double)m;
    c.N = Nc;
    return c;
}

void bkf_orbit_free(bkf_orbit *ob)
{
    if (!ob) return;
    orbit_flow_free(ob->cell);
    orbit_flow_free(ob->full);
    free(ob->psi);
    free(ob->ucell);
    free(ob->ucell2);
    free(ob->warm);
    free(ob->mult);
    free(ob);
}

bkf_orbit *bkf_orbit_alloc(const bkf_model_params *model, const bkf_orbit_options *options,
                           bkf_error *err)
{
    if (!model) {
        bkf_error_set(err, BKF_EINPUT, "model is NULL");
        return NULL;
    }
    bkf_orbit_options o = options ? *options : bkf_orbit_options_default();
    bkf_pde_options po = bkf_pde_options_default();
    po.dealias = o.dealias;
    po.filter = o.filter;
    if (bkf_pde_check(model, &po, err) || check_options(model, &o, err)) return NULL;
    bkf_orbit *ob = calloc(1, sizeof *ob);
    if (!ob) {
        bkf_error_set(err, BKF_ENOMEM, "out of memory");
        return NULL;
    }
    ob->model = *model;
    ob->o = o;
    ob->o.flow_tol = flow_tol_for(&o);
    ob->cells = o.cells;
    ob->Nc = model->N / o.cells;
    bkf_model_params cm = cell_model(model, ob->cells, ob->Nc);
    ob->psi = malloc(2 * model->N * sizeof *ob->psi);
    ob->ucell = malloc(2 * ob->Nc * sizeof *ob->ucell);
    if (!ob->psi || !ob->ucell) {
        bkf_orbit_free(ob);
        bkf_error_set(err, BKF_ENOMEM, "out of memory");
        return NULL;
    }
    ob->eta = ob->psi + model->N;
    if (!(ob->cell = orbit_flow_alloc(&cm, &ob->o, err))) {
        bkf_orbit_free(ob);
        return NULL;
    }
    return ob;
}

const double *bkf_orbit_psi(const bkf_orbit *ob) { return ob && ob->solved ? ob->psi : NULL; }
const double *bkf_orbit_eta(const bkf_orbit *ob) { return ob && ob->solved ? ob->eta : NULL; }
const bkf_orbit_result *bkf_orbit_get(const bkf_orbit *ob)
{
    return ob && ob->solved ? &ob->result : NULL;
}

static double maxdiff(const double *a, const double *b, size_t n)
{
    double m = 0.0;
    for (size_t i = 0; i < n; i++) m = fmax(m, fabs(a[i] - b[i]));
    return m;
}

static double maxabs(const double *a, size_t n)
{
    double m = 0.0;
    for (size_t i = 0; i < n; i++) m = fmax(m, fabs(a[i]));
    return m;
}

static int report(const bkf_orbit *ob, const char *stage, double frac)
{
    if (ob->o.progress && ob->o.progress(stage, frac, ob->o.progress_data)) return 1;
    return ob->o.cancel && *ob->o.cancel;
}

/* Solve on grid fl from x (2N + 2 values, in and out) and estimate the
 * residual's and the flow's shares.  job is prepared here. */
static int solve_on(bkf_orbit *ob, orbit_flow *fl, orbit_newton_job *job, double *x,
                    const char *stage, bkf_orbit_result *r, bkf_error *err)
{
    size_t n2 = 2 * fl->N;
    int s = orbit_newton_prepare(fl, job, x, ob->o.shift_mode, err);
    if (s) return s;
    job->flow_tol = ob->o.flow_tol;
    job->tol = ob->o.tol;
    job->max_iter = ob->o.newton_max_iter;
    job->krylov_max = ob->o.krylov_max;
    job->progress = ob->o.progress;
    job->progress_data = ob->o.progress_data;
    job->stage = stage;
    if ((s = orbit_newton(fl, job, x, err))) return s;
    if (!r) return BKF_OK;
    if (report(ob, "estimate", 0.0))
        return bkf_error_set(err, BKF_ECANCELED, "canceled before the error estimate");
    double *st = malloc(3 * (n2 + 2) * sizeof *st);
    if (!st) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    double *st2 = st + n2 + 2, *dir = st2 + n2 + 2, f1, f2;
    s = orbit_newton_step(fl, job, x, job->flow_tol, st, &f1, err);
    if (!s) s = orbit_newton_step(fl, job, x, 0.1 * job->flow_tol, st2, &f2, err);
    if (!s) {
        /* the tangent's accuracy along the time direction (with a unit
         * change of the period where it is free) */
        memcpy(dir, job->pt, n2 * sizeof *dir);
        dir[n2] = job->period_free ? 1.0 : 0.0;
        dir[n2 + 1] = job->shift_free ? 1.0 : 0.0;
        s = orbit_newton_tangent_check(fl, job, x, dir, job->flow_tol, &r->tangent_rel, err);
    }
    if (!s) {
        r->residual = f1;
        r->err_residual = maxabs(st, n2 + 2);
        /* Twice the change: an 8th-order pair's global error at tol/10 is
         * only 7-8 times smaller than at tol, so the change alone is 0.87 of
         * the error it estimates. */
        r->err_flow = 2.0 * maxdiff(st, st2, n2 + 2) + r->tangent_rel * r->err_residual;
    }
    free(st);
    return s;
}

static int solve_body(bkf_orbit *ob, const bkf_orbit_guess *g, bkf_orbit_result *res,
                      bkf_error *err)
{
    if (!ob || !g || !g->psi || !g->eta)
        return bkf_error_set(err, BKF_EINPUT, "orbit, guess or its state is NULL");
    if (!(g->period > 0) || !isfinite(g->period))
        return bkf_error_set(err, BKF_EINPUT, "period = %g must be finite and > 0", g->period);
    if (!isfinite(g->shift))
        return bkf_error_set(err, BKF_EINPUT, "shift = %g must be finite", g->shift);
    size_t N = ob->model.N, m = ob->cells, Nc = ob->Nc;
    for (size_t i = 0; i < N; i++)
        if (!(fabs(g->psi[i]) <= BLOWUP) || !(fabs(g->eta[i]) <= BLOWUP))
            return bkf_error_set(err, BKF_EINPUT,
                                 "the guess at i = %zu is not finite or beyond %g", i, BLOWUP);
    ob->solved = 0;
    ob->nmult = 0;
    bkf_orbit_result r;
    memset(&r, 0, sizeof r);
    r.cells = m;
    r.flow_tol = ob->o.flow_tol;
    r.err_grid = NAN;
    r.period2 = r.shift2 = NAN;
    size_t n2 = 2 * Nc;
    double *x = malloc((n2 + 2) * sizeof *x);
    if (!x) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    /* the cell: the guess averaged over the m cells (its sector-0 part) */
    for (size_t i = 0; i < Nc; i++) {
        double a = 0.0, b = 0.0;
        for (size_t l = 0; l < m; l++) {
            a += g->psi[l * Nc + i];
            b += g->eta[l * Nc + i];
        }
        x[i] = a / (double)m;
        x[Nc + i] = b / (double)m;
    }
    x[n2] = g->period;
    x[n2 + 1] = ob->o.shift_mode == BKF_ORBIT_SHIFT_NONE ? 0.0 : g->shift;
    orbit_newton_job job;
    memset(&job, 0, sizeof job);
    size_t flows0 = ob->cell->flows;
    int s = solve_on(ob, ob->cell, &job, x, "newton", &r, err);
    r.newton_iterations = job.iterations;
    r.jv_products = job.jv;
    r.symmetry = job.symmetry;
    r.period_held = !job.period_free;
    r.shift_held = !job.shift_free;
    orbit_newton_release(&job);
    if (s) goto done;
    r.period = x[n2];
    r.shift = x[n2 + 1];
    memcpy(ob->ucell, x, n2 * sizeof *x);

    if (ob->model.kind == BKF_MODEL_CHAIN) {
        r.err_grid = 0.0; /* the chain of N blocks is the model itself */
    } else if (ob->o.grid_check) {
        if (report(ob, "grid", 0.0)) {
            s = bkf_error_set(err, BKF_ECANCELED, "canceled before the second grid");
            goto done;
        }
        size_t Nc2 = Nc + Nc / 2;
        Nc2 += Nc2 % 2;
        bkf_model_params cm2 = cell_model(&ob->model, m, Nc2);
        bkf_error e2;
        orbit_flow *fl2 = orbit_flow_alloc(&cm2, &ob->o, &e2);
        double *x2 = malloc(2 * (2 * Nc2 + 2) * sizeof *x2);
        if (!fl2 || !x2) {
            orbit_flow_free(fl2);
            free(x2);
            s = fl2 ? bkf_error_set(err, BKF_ENOMEM, "out of memory")
                    : bkf_error_set(err, e2.status, "second grid N %zu: %s", Nc2 * m, e2.message);
            goto done;
        }
        double *xi = x2 + 2 * Nc2 + 2;
        s = orbit_flow_resample(fl2, x, Nc, x2, err);
        x2[2 * Nc2] = x[n2];
        x2[2 * Nc2 + 1] = x[n2 + 1];
        memcpy(xi, x2, (2 * Nc2 + 2) * sizeof *x2);
        memset(&job, 0, sizeof job);
        if (!s) s = solve_on(ob, fl2, &job, x2, "grid", NULL, err);
        orbit_newton_release(&job);
        if (!s) {
            double *keep = realloc(ob->ucell2, 2 * Nc2 * sizeof *keep);
            if (!keep) s = bkf_error_set(err, BKF_ENOMEM, "out of memory");
            else {
                memcpy(keep, x2, 2 * Nc2 * sizeof *keep);
                ob->ucell2 = keep;
                ob->Nc2 = Nc2;
            }
        }
        if (!s) {
            r.N2 = Nc2 * m;
            r.period2 = x2[2 * Nc2];
            r.shift2 = x2[2 * Nc2 + 1];
            r.err_grid = fmax(maxdiff(x2, xi, 2 * Nc2),
                              fmax(fabs(r.period2 - r.period), fabs(r.shift2 - r.shift)));
        }
        ob->cell->flows += fl2->flows;
        orbit_flow_free(fl2);
        free(x2);
        if (s) goto done;
    }
    r.flows = ob->cell->flows - flows0;
    r.err = r.err_residual + r.err_flow + (isnan(r.err_grid) ? 0.0 : r.err_grid);
    for (size_t l = 0; l < m; l++) {
        memcpy(ob->psi + l * Nc, x, Nc * sizeof *x);
        memcpy(ob->eta + l * Nc, x + Nc, Nc * sizeof *x);
    }
    double lo = INFINITY, hi = -INFINITY;
    for (size_t i = 0; i < N; i++) {
        lo = fmin(lo, ob->psi[i]);
        hi = fmax(hi, ob->psi[i]);
    }
    r.amplitude = hi - lo;
    ob->result = r;
    ob->solved = 1;
    if (!(r.err <= ob->o.tol))
        s = bkf_error_set(err, BKF_ETOL,
                          "estimated error %.3g of the orbit exceeds tol %g (residual %.3g, "
                          "flow %.3g, grid %.3g at N %zu)",
                          r.err, ob->o.tol, r.err_residual, r.err_flow, r.err_grid, r.N2);
done:
    free(x);
    if (res) *res = r;
    return s;
}

int bkf_orbit_solve(bkf_orbit *ob, const bkf_orbit_guess *guess, bkf_orbit_result *result,
                    bkf_error *err)
{
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    int rc = solve_body(ob, guess, result, err);
    bkf_gsl_handler_pop(handler);
    return rc;
}

int bkf_orbit_multipliers(bkf_orbit *ob, const bkf_orbit_mult_options *options,
                          bkf_orbit_spectrum *spectrum, bkf_error *err)
{
    if (!ob || !spectrum) return bkf_error_set(err, BKF_EINPUT, "orbit or spectrum is NULL");
    if (!ob->solved) return bkf_error_set(err, BKF_EINPUT, "no orbit solved yet");
    bkf_orbit_mult_options o = options ? *options : bkf_orbit_mult_options_default();
    if (o.k < 1 || o.k > 200)
        return bkf_error_set(err, BKF_EINPUT, "k = %zu is outside [1, 200]", o.k);
    if (o.sector < -1 || o.sector > (int)(ob->cells / 2))
        return bkf_error_set(err, BKF_EINPUT, "sector = %d is outside [-1, %zu] (-1: every one)",
                             o.sector, ob->cells / 2);
    if (o.arnoldi_tol != 0 && !(o.arnoldi_tol >= 1e-14 && o.arnoldi_tol <= 1e-2))
        return bkf_error_set(err, BKF_EINPUT,
                             "arnoldi_tol = %g is outside [1e-14, 1e-2] (0: from tol)",
                             o.arnoldi_tol);
    if (o.flow_tol != 0 && !(o.flow_tol >= BKF_PDE_TOL_MIN && o.flow_tol <= 1e-4))
        return bkf_error_set(err, BKF_EINPUT,
                             "flow_tol = %g is outside [%g, 1e-4] (0: from tol)", o.flow_tol,
                             BKF_PDE_TOL_MIN);
    if (o.arnoldi_tol == 0) o.arnoldi_tol = fmin(1e-6, fmax(1e-12, 0.01 * ob->o.tol));
    if (o.flow_tol == 0) o.flow_tol = fmin(1e-6, fmax(1e-13, ob->o.tol));
    if (o.max_restarts < 1 || o.max_restarts > 100000)
        return bkf_error_set(err, BKF_EINPUT, "max_restarts = %d is outside [1, 100000]",
                             o.max_restarts);
    if (!(o.grid_tail > 0 && o.grid_tail <= 1))
        return bkf_error_set(err, BKF_EINPUT, "grid_tail = %g is outside (0, 1]", o.grid_tail);
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    int rc = orbit_mult_run(ob, &o, spectrum, err);
    bkf_gsl_handler_pop(handler);
    return rc;
}

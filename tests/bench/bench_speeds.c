/* Benchmark of the speeds module: the whole table of allowed front speeds,
 * wall time on one core (median of repeated runs) and the accuracy of every
 * v against an independent root (Brent in v itself, T at tol 1e-12), as
 * markdown tables for the README.  The goal for the paper's parameters
 * (gamma 2, c 0.3, nu -0.96, S 20) at tol 1e-10: under 50 ms, every v to
 * 1e-9 relative. */
#define _POSIX_C_SOURCE 200809L
#include "bkfront/cycle.h"
#include "bkfront/speeds.h"
#include "bench_util.h"

#include <gsl/gsl_errno.h>
#include <gsl/gsl_roots.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

void bench_speeds(void);

typedef struct {
    bkf_model_params p;
    double n;
    int failed;
} ref_cond;

static double ref_condition(double v, void *data)
{
    ref_cond *c = data;
    double w = sqrt(1.0 - (c->p.c / v) * (c->p.c / v));
    bkf_cycle_options o = bkf_cycle_options_default();
    o.tol = 1e-12;
    o.warm_start = 0;
    bkf_cycle_result r;
    bkf_error e;
    if (bkf_cycle_period(c->p.gamma / w, c->p.nu, &o, &r, &e) != BKF_OK) {
        c->failed = 1;
        return NAN;
    }
    return c->n * r.period * v * w / c->p.S - 1.0;
}

/* The root in v near v0 (relative window 1e-6), or NaN. */
static double ref_root(bkf_model_params p, double n, double v0)
{
    ref_cond c = {p, n, 0};
    gsl_function F = {ref_condition, &c};
    double lo = v0 * (1.0 - 1e-6), hi = v0 * (1.0 + 1e-6);
    if (lo <= p.c) lo = 0.5 * (v0 + p.c);
    gsl_root_fsolver *s = gsl_root_fsolver_alloc(gsl_root_fsolver_brent);
    if (!s || gsl_root_fsolver_set(s, &F, lo, hi) != GSL_SUCCESS) {
        if (s) gsl_root_fsolver_free(s);
        return NAN;
    }
    for (int it = 0; it < 100 && !c.failed; it++) {
        if (gsl_root_fsolver_iterate(s) != GSL_SUCCESS) break;
        if (gsl_root_fsolver_x_upper(s) - gsl_root_fsolver_x_lower(s) <= 1e-14 * v0) break;
    }
    double v = c.failed ? NAN : gsl_root_fsolver_root(s);
    gsl_root_fsolver_free(s);
    return v;
}

typedef struct {
    const char *name;
    bkf_model_params p;
    double tol;
    int reference;   /* check every v against ref_root */
} speeds_case;

static void run_case(const speeds_case *k)
{
    enum { REPS = 11 };
    double times[REPS];
    bkf_speeds_table t = {0};
    bkf_speeds_options o = bkf_speeds_options_default();
    o.tol = k->tol;
    for (int i = 0; i < REPS; i++) {
        bkf_speeds_table_free(&t);
        bkf_error e;
        double t0 = bench_seconds();
        int rc = bkf_speeds_find(&k->p, &o, &t, &e);
        times[i] = bench_seconds() - t0;
        if (rc != BKF_OK) {
            printf("| %s | %g | failed: %s |||||||\n", k->name, k->tol, e.message);
            bkf_speeds_table_free(&t);
            return;
        }
    }
    qsort(times, REPS, sizeof times[0], bench_compare_doubles);
    printf("| %s | %g | %zu | %ld | %.1f ms | %zu | %zu |", k->name, k->tol, t.count, t.n_max,
           times[REPS / 2] * 1e3, t.coarse_solves, t.precise_solves);
    if (k->reference) {
        double worst = 0, worst_est = 0;
        for (size_t i = 0; i < t.count; i++) {
            double v_ref = ref_root(k->p, (double)t.roots[i].n, t.roots[i].v);
            double rel = fabs(t.roots[i].v - v_ref) / v_ref;
            if (!(rel <= worst)) worst = rel;
            if (t.roots[i].v_err / t.roots[i].v > worst_est) worst_est = t.roots[i].v_err / t.roots[i].v;
        }
        printf(" %.1e | %.1e |\n", worst, worst_est);
    } else {
        double worst_est = 0;
        for (size_t i = 0; i < t.count; i++)
            if (t.roots[i].v_err / t.roots[i].v > worst_est) worst_est = t.roots[i].v_err / t.roots[i].v;
        printf(" - | %.1e |\n", worst_est);
    }
    fflush(stdout);
    bkf_speeds_table_free(&t);
}

static int count_point(const bkf_speeds_branch_point *pt, void *data)
{
    (void)pt;
    (*(size_t *)data)++;
    return 0;
}

void bench_speeds(void)
{
    gsl_set_error_handler_off();
    const speeds_case cases[] = {
        {"paper: gamma 2, c 0.3, nu -0.96, S 20", {2.0, 0.3, -0.96, 20.0, 0, BKF_MODEL_CONTINUUM}, 1e-10, 1},
        {"paper", {2.0, 0.3, -0.96, 20.0, 0, BKF_MODEL_CONTINUUM}, 1e-8, 1},
        {"paper", {2.0, 0.3, -0.96, 20.0, 0, BKF_MODEL_CONTINUUM}, 1e-12, 1},
        {"gamma 1, c 0.5, nu 0, S 30", {1.0, 0.5, 0.0, 30.0, 0, BKF_MODEL_CONTINUUM}, 1e-10, 1},
        {"folds: gamma 1.5, c 0.3, nu -0.96, S 20", {1.5, 0.3, -0.96, 20.0, 0, BKF_MODEL_CONTINUUM}, 1e-10, 1},
        {"canard: gamma 1, c 0.3, nu -0.99, S 20", {1.0, 0.3, -0.99, 20.0, 0, BKF_MODEL_CONTINUUM}, 1e-10, 0},
        {"large gamma: gamma 100, c 0.3, nu -0.96, S 1000", {100.0, 0.3, -0.96, 1000.0, 0, BKF_MODEL_CONTINUUM}, 1e-10, 1},
    };
    printf("## speeds: the whole table of allowed speeds, median of 11 runs, one core\n\n");
    printf("| case | tol | roots | n_max | time | coarse solves | precise solves | "
           "max rel. error of v | max v_err/v |\n");
    printf("|:---|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) run_case(&cases[i]);
    printf("\nmax rel. error of v: against Brent in v with T at tol 1e-12 (- : not run, the\n"
           "reference solver cannot reach 1e-12 inside the canard).\n\n");

    printf("## branch: the S-branch of n = 6 at gamma 1.5, c 0.3, nu -0.96 from S = 30 to 5\n\n");
    printf("| tol | points | folds | sonic end | solves | time |\n|---:|---:|---:|:---|---:|---:|\n");
    const double tols[] = {1e-8, 1e-10};
    for (int i = 0; i < 2; i++) {
        bkf_model_params p = {1.5, 0.3, -0.96, 30.0, 0, BKF_MODEL_CONTINUUM};
        bkf_speeds_options o = bkf_speeds_options_default();
        o.tol = tols[i];
        bkf_speeds_branch_report rep;
        bkf_error e;
        size_t visited = 0;
        double t0 = bench_seconds();
        int rc = bkf_speeds_branch(&p, 6, 1, BKF_SPEEDS_ALONG_S, 5.0, &o, 0, count_point, &visited,
                                   &rep, &e);
        double dt = bench_seconds() - t0;
        if (rc != BKF_OK) {
            printf("| %g | failed: %s |||||\n", tols[i], e.message);
            continue;
        }
        printf("| %g | %zu | %zu | S = %.10g | %zu | %.2f s |\n", tols[i], rep.points, rep.folds,
               rep.sonic_value, rep.solves, dt);
        fflush(stdout);
    }
    printf("\n");
}

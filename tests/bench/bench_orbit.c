/* Benchmark of the periodic-orbit solver: CPU seconds (one core) of the
 * global oscillation as an orbit at the paper's parameters (gamma 2, c 0.3,
 * nu -0.96, S 20) to tol 1e-8, and of its ten leading multipliers, at two
 * grids; then the branch of period-doubled orbits of `bkfront orbit` at its
 * defaults (50 points with their multipliers).  Goals (issue 34): the orbit
 * under 10 s, ten multipliers under 5 s, the branch under 2 minutes. */
#define _POSIX_C_SOURCE 200809L
#include "bkfront/orbit.h"
#include "bkfront/orbits.h"
#include "bkfront/pde.h"
#include "bkfront/floquet.h"
#include "bench_util.h"

#include <math.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

void bench_orbit(void);

static double cpu_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

typedef struct {
    size_t rows, stable, unstable, undecided, refused, matvecs;
    double largest_err;
} branch_tally;

static int tally(const bkf_orbits_point *pt, void *data)
{
    branch_tally *t = data;
    if (pt->is_start) return 0;
    t->rows++;
    if (strcmp(pt->status, "ok") != 0) t->refused++;
    else if (pt->verdict == BKF_ORBIT_STABLE) t->stable++;
    else if (pt->verdict == BKF_ORBIT_UNSTABLE) t->unstable++;
    else t->undecided++;
    if (pt->spectrum) t->matvecs += pt->spectrum->matvecs;
    return 0;
}

static void bench_branch(void)
{
    printf("## orbit: the branch of period-doubled orbits at `bkfront orbit`'s defaults "
           "(paper's parameters, j = 9, N 288, tol 1e-3, 50 points, k 2 per sector), "
           "CPU seconds (one core)\n\n");
    bkf_orbits_options o = bkf_orbits_options_default();
    branch_tally t;
    memset(&t, 0, sizeof t);
    bkf_orbits_report rep;
    bkf_error e = {0};
    double t0 = cpu_seconds();
    int s = bkf_orbits_branch(&o, tally, &t, &rep, &e);
    double t1 = cpu_seconds();
    printf("| rows | folds | stable / unstable / undecided / refused | monodromy products | "
           "CPU | per row | status |\n|---:|---:|---|---:|---:|---:|---|\n");
    printf("| %zu | %zu | %zu / %zu / %zu / %zu | %zu | %.1f s | %.2f s | %s |\n\n", t.rows,
           rep.folds, t.stable, t.unstable, t.undecided, t.refused, t.matvecs, t1 - t0,
           t.rows ? (t1 - t0) / (double)t.rows : 0.0, s ? e.message : "ok");
    fflush(stdout);
}

void bench_orbit(void)
{
    printf("## orbit: the global oscillation as a periodic orbit, paper's parameters, "
           "tol 1e-8, CPU seconds (one core)\n\n");
    printf("| N | orbit | estimate | Newton / Jv | 10 multipliers | monodromy products | "
           "largest |m| | their largest error |\n");
    printf("|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    const size_t Ns[] = {128, 512};
    for (size_t k = 0; k < 2; k++) {
        bkf_model_params p = {2, 0.3, -0.96, 20, Ns[k], BKF_MODEL_CONTINUUM};
        bkf_error e;
        bkf_floquet *fq = bkf_floquet_alloc();
        bkf_pde *m = bkf_pde_alloc(&p, NULL, &e);
        bkf_orbit_options o = bkf_orbit_options_default();
        o.tol = 1e-8;
        bkf_orbit *ob = bkf_orbit_alloc(&p, &o, &e);
        if (!fq || !m || !ob || bkf_floquet_set(fq, 2, 0.3, -0.96, NULL, &e) ||
            bkf_pde_init_oscillation(m, 0, 0.0, &e)) {
            printf("| %zu | failed: %s |\n", Ns[k], e.message);
        } else {
            bkf_orbit_guess g = {bkf_pde_psi(m), bkf_pde_eta(m),
                                 1.01 * bkf_floquet_cycle(fq)->period, 0.0};
            bkf_orbit_result r;
            double t0 = cpu_seconds();
            int s = bkf_orbit_solve(ob, &g, &r, &e);
            double t1 = cpu_seconds();
            bkf_orbit_spectrum sp;
            int s2 = s ? s : bkf_orbit_multipliers(ob, NULL, &sp, &e);
            double t2 = cpu_seconds();
            double merr = 0.0;
            for (size_t i = 0; !s && !s2 && i < sp.count; i++) merr = fmax(merr, sp.m[i].err);
            if (s || s2) printf("| %zu | failed: %s |\n", Ns[k], e.message);
            else
                printf("| %zu | %.2f s | %.1e | %zu / %zu | %.2f s | %zu | %.6f | %.1e |\n",
                       Ns[k], t1 - t0, r.err, r.newton_iterations, r.jv_products, t2 - t1,
                       sp.matvecs, sp.largest_abs, merr);
        }
        fflush(stdout);
        bkf_orbit_free(ob);
        bkf_pde_free(m);
        bkf_floquet_free(fq);
    }
    printf("\n");
    bench_branch();
}

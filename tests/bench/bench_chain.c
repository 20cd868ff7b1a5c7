/* Benchmark of the chain's rotating waves (issue 16): the table with
 * stability for the paper's parameters (gamma 2, c 0.3, nu -0.96, S 20) on
 * 20 and 40 blocks, and the continuation of one wave (n = 4, N = 20) from
 * blocks per unit length 16 (h = 1/16) to 1, one core, median wall time, as
 * markdown.  Goals: the N = 20 table under 0.5 s, the continuation under
 * 5 s.  Times are CPU seconds (see chain_now). */
#define _POSIX_C_SOURCE 200809L
#include "bkfront/chainwave.h"

#include <stdio.h>
#include <stdlib.h>
#include <time.h>

void bench_chain(void);

/* CPU time of the process: on a shared machine the wall time measures the
 * other users (single-threaded, the two agree on an idle core) */
static double chain_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int by_seconds(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static void table_row(size_t N, int reps)
{
    bkf_model_params p = bkf_model_params_paper();
    p.kind = BKF_MODEL_CHAIN;
    p.N = N;
    bkf_chainwave_options o = bkf_chainwave_options_default();
    double times[9];
    if (reps > 9) reps = 9;
    size_t stable = 0, count = 0, folds = 0;
    for (int r = 0; r < reps; r++) {
        bkf_chainwave_table t;
        bkf_error e;
        double t0 = chain_now();
        int rc = bkf_chainwave_find(&p, 1, 0, &o, &t, &e);
        times[r] = chain_now() - t0;
        if (rc != BKF_OK) {
            printf("| %zu | failed: %s | | | |\n", N, e.message);
            bkf_chainwave_table_free(&t);
            return;
        }
        stable = 0;
        for (size_t i = 0; i < t.count; i++) stable += t.waves[i].verdict == BKF_CHAINWAVE_STABLE;
        count = t.count;
        folds = t.folds;
        bkf_chainwave_table_free(&t);
    }
    qsort(times, (size_t)reps, sizeof times[0], by_seconds);
    printf("| table N = %zu (n 1..%zu, stability, tol 1e-8) | %zu waves, %zu stable, %zu folds "
           "| %.3f s | %d |\n", N, N / 2, count, stable, folds, times[reps / 2], reps);
}

static void branch_row(void)
{
    bkf_model_params p = bkf_model_params_paper();
    p.kind = BKF_MODEL_CHAIN;
    p.N = 20;
    bkf_chainwave_options o = bkf_chainwave_options_default();
    bkf_chainwave_branch_report rep;
    bkf_error e;
    double t0 = chain_now();
    int rc = bkf_chainwave_branch(&p, 4, 1, BKF_CHAINWAVE_PARAM_H, 1.0 / 16.0, 1.0, &o, NULL,
                                  NULL, &rep, &e);
    double dt = chain_now() - t0;
    if (rc != BKF_OK)
        printf("| branch n = 4, h 1/16 -> 1 | failed: %s | | |\n", e.message);
    else
        printf("| branch n = 4, N = 20, h 1/16 -> 1 (stability) | %zu points, %zu folds, %s "
               "| %.3f s | 1 |\n", rep.points, rep.folds, rep.reached ? "reached" : rep.note, dt);
}

void bench_chain(void)
{
    printf("## chain: rotating waves of the paper's chain, one core\n\n");
    printf("| what | result | CPU time (median) | runs |\n|---|---|---:|---:|\n");
    table_row(20, 5);
    table_row(40, 1);
    branch_row();
    printf("\n");
}

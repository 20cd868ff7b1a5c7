/* Benchmark of the spectra of front trains: the wall time of the ring
 * spectrum of every root of the paper's table (gamma 2, c 0.3, nu -0.96,
 * S 20) at the default tol 1e-6, one core, as a markdown table.  Goals
 * (issue #15): every root under 1 s in total; n = 12 (mu ~ 47) under 0.5 s. */
#define _POSIX_C_SOURCE 200809L
#include "bkfront/speeds.h"
#include "bkfront/trainspec.h"
#include "bench_util.h"

#include <stdio.h>
#include <time.h>

void bench_trainspec(void);

void bench_trainspec(void)
{
    bkf_model_params p = bkf_model_params_paper();
    bkf_speeds_table table;
    bkf_error e;
    printf("## Spectra of front trains (paper table, tol 1e-6)\n\n");
    if (bkf_speeds_find(&p, NULL, &table, &e) != BKF_OK) {
        printf("speeds failed: %s\n\n", e.message);
        bkf_speeds_table_free(&table);
        return;
    }
    printf("| n | mu | stable | sigma_max | steps per period | monodromies | time |\n|---|---|---|---|---|---|---|\n");
    double total = 0;
    for (size_t i = 0; i < table.count; i++) {
        bkf_trainspec_train t = {table.roots[i].n, table.roots[i].v};
        bkf_trainspec_result r;
        double t0 = bench_seconds();
        int rc = bkf_trainspec_ring(&p, &t, NULL, &r, &e);
        double dt = bench_seconds() - t0;
        total += dt;
        if (rc != BKF_OK)
            printf("| %zu | %.4g | refused | %s | | | %.3f s |\n", t.n, table.roots[i].mu, e.message, dt);
        else
            printf("| %zu | %.4g | %s | %.3g | %zu | %zu | %.3f s |\n", t.n, r.mu, bkf_trainspec_verdict_name(r.verdict),
                   r.sigma_max, r.mesh_steps, r.evaluations, dt);
        bkf_trainspec_result_free(&r);
        fflush(stdout);
    }
    printf("\nTotal %.2f s.\n\n", total);
    bkf_speeds_table_free(&table);
}

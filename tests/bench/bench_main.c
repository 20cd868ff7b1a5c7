/* Benchmarks: median wall time per product on one core, printed as markdown
 * tables for the README.  Speed goals live here, not in the tests. */
#define _POSIX_C_SOURCE 200809L
#include "bkfront/cycle.h"
#include "bench_util.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static void bench_period(void)
{
    const double mus[] = {1e-3, 1.0, 10.0, 100.0, 1e4};
    const double nus[] = {0.0, -0.96, 0.999};
    const double tols[] = {1e-6, 1e-10, 1e-13};
    printf("## period: median time per T(mu, nu), cold start, one core\n\n");
    printf("| mu | nu | tol 1e-6 | tol 1e-10 | tol 1e-13 | stepper | shots at 1e-10 |\n");
    printf("|---:|---:|---:|---:|---:|:---|---:|\n");
    for (size_t i = 0; i < sizeof mus / sizeof mus[0]; i++)
        for (size_t j = 0; j < sizeof nus / sizeof nus[0]; j++) {
            printf("| %g | %g |", mus[i], nus[j]);
            bkf_cycle_result r = {0}, r10 = {0};
            for (size_t k = 0; k < 3; k++) {
                int reps = mus[i] > 30 ? 5 : 21;
                bkf_cycle_options o = bkf_cycle_options_default();
                o.tol = tols[k];
                double t = bench_median_period_time(mus[i], nus[j], &o, reps, &r);
                if (k == 1) r10 = r;
                if (t < 0) printf(" refused |");
                else if (t < 1e-3) printf(" %.0f us |", t * 1e6);
                else printf(" %.2f ms |", t * 1e3);
            }
            printf(" %s | %zu |\n", r10.stepper ? r10.stepper : "-", r10.newton_iterations);
            fflush(stdout);
        }
    printf("\n");
}

void bench_floquet(void);
void bench_speeds(void);
void bench_pde(void);
void bench_pde_cost(void);
void bench_trainspec(void);
void bench_stability_tol(void);
void bench_chain(void);
void bench_colloc(void);
void bench_start(void);
void bench_orbit(void);

int main(int argc, char **argv)
{
    const char *only = argc > 1 ? argv[1] : NULL;
    if (!only || strcmp(only, "period") == 0) bench_period();
    if (!only || strcmp(only, "speeds") == 0) bench_speeds();
    if (!only || strcmp(only, "floquet") == 0) bench_floquet();
    if (!only || strcmp(only, "pde") == 0) bench_pde();
    if (!only || strcmp(only, "pde-cost") == 0) bench_pde_cost();
    if (!only || strcmp(only, "trainspec") == 0) bench_trainspec();
    if (!only || strcmp(only, "stability-tol") == 0) bench_stability_tol();
    if (!only || strcmp(only, "chain") == 0) bench_chain();
    if (!only || strcmp(only, "colloc") == 0) bench_colloc();
    if (!only || strcmp(only, "start") == 0) bench_start();
    if (!only || strcmp(only, "orbit") == 0) bench_orbit();
    return 0;
}

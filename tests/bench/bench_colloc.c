/* Collocation against shooting (issue 20 item 1): median wall time of a cold
 * T at tol 1e-10 over 11 solves, at the mus of the goal and three nus. */
#define _POSIX_C_SOURCE 200809L
#include "bkfront/cycle.h"
#include "bench_util.h"

#include <stdio.h>
#include <stdlib.h>
#include <time.h>

/* median seconds of 11 cold solves at tol 1e-10, the last result in *r;
 * negative if refused */
static double median_time(double mu, double nu, bkf_stepper_kind kind, bkf_cycle_result *r)
{
    bkf_cycle_options o = bkf_cycle_options_default();
    o.tol = 1e-10;
    o.stepper = kind;
    return bench_median_period_time(mu, nu, &o, 11, r);
}

static void cell(double t)
{
    if (t < 0) printf(" refused |");
    else printf(" %.0f |", t * 1e6);
}

void bench_colloc(void)
{
    const double mus[] = {0.1, 1, 10, 30, 100, 1e3, 1e4};
    const double nus[] = {0.0, -0.96, 0.99};
    printf("## colloc: median us per cold T at tol 1e-10 (11 solves), one core\n\n");
    printf("| mu | nu | colloc | answered by | shooting | by | auto | by |\n");
    printf("|---:|---:|---:|:---|---:|:---|---:|:---|\n");
    for (size_t i = 0; i < sizeof mus / sizeof mus[0]; i++)
        for (size_t j = 0; j < sizeof nus / sizeof nus[0]; j++) {
            bkf_cycle_result a = {0}, b = {0}, c = {0};
            printf("| %g | %g |", mus[i], nus[j]);
            cell(median_time(mus[i], nus[j], BKF_STEPPER_COLLOCATION, &a));
            printf(" %s |", a.stepper ? a.stepper : "-");
            /* shooting as the automatic choice had it (bd2x2 above mu 20) */
            cell(median_time(mus[i], nus[j], mus[i] > 20 ? BKF_STEPPER_EXTRAPOLATION : BKF_STEPPER_EXPLICIT, &b));
            printf(" %s |", b.stepper ? b.stepper : "-");
            cell(median_time(mus[i], nus[j], BKF_STEPPER_AUTO, &c));
            printf(" %s |\n", c.stepper ? c.stepper : "-");
            fflush(stdout);
        }
    printf("\n");
}

/* Collocation against shooting (issue 20 item 1): median wall time of a cold
 * T at tol 1e-10 over 11 solves, at the mus of the goal and three nus. */
#define _POSIX_C_SOURCE 200809L
#include "bkfront/cycle.h"

#include <stdio.h>
#include <stdlib.h>
#include <time.h>

static double seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int by_value(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* median seconds, the last result in *r; negative if refused */
static double median_time(double mu, double nu, bkf_stepper_kind kind, bkf_cycle_result *r)
{
    enum { REPS = 11 };
    double t[REPS];
    bkf_cycle_options o = bkf_cycle_options_default();
    o.tol = 1e-10;
    o.stepper = kind;
    o.warm_start = 0;
    for (int i = 0; i < REPS; i++) {
        bkf_error e;
        double t0 = seconds();
        int rc = bkf_cycle_period(mu, nu, &o, r, &e);
        t[i] = seconds() - t0;
        if (rc != BKF_OK) return -1.0;
    }
    qsort(t, REPS, sizeof t[0], by_value);
    return t[REPS / 2];
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

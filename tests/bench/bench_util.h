/* Timing helpers shared by the benchmarks (tests/bench/bench_*.c). */
#ifndef BKF_BENCH_UTIL_H
#define BKF_BENCH_UTIL_H

#include "bkfront/cycle.h"

#include <stdlib.h>
#include <time.h>

/* Wall seconds on the monotonic clock. */
static inline double bench_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static inline int bench_compare_doubles(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The median of t[0..n) (t is sorted in place). */
static inline double bench_median(double *t, int n)
{
    qsort(t, (size_t)n, sizeof *t, bench_compare_doubles);
    return t[n / 2];
}

/* Median seconds per cold solve (fresh object, no warm start) of T at
 * (mu, nu) with *options over reps (at most 64) solves, the last result in
 * *last; negative if the solve is refused. */
static inline double bench_median_period_time(double mu, double nu, const bkf_cycle_options *options, int reps,
                                              bkf_cycle_result *last)
{
    double times[64];
    bkf_cycle_options o = *options;
    o.warm_start = 0;
    if (reps > 64) reps = 64;
    for (int i = 0; i < reps; i++) {
        bkf_error e;
        double t0 = bench_seconds();
        int rc = bkf_cycle_period(mu, nu, &o, last, &e);
        times[i] = bench_seconds() - t0;
        if (rc != BKF_OK) return -1.0;
    }
    return bench_median(times, reps);
}

#endif

/* Benchmark of the Floquet module: median wall time of its products at the
 * paper's parameters (gamma 2, c 0.3), one core, as a markdown table.
 * Goals (issue #5): a 241-point dispersion relation at tol 1e-10 under
 * 50 ms; the threshold nu_pd to 1e-8 under 1 s. */
#define _POSIX_C_SOURCE 200809L
#include "bkfront/floquet.h"
#include "bench_util.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

void bench_floquet(void);

static void fq_time(double seconds, char *buf, size_t size)
{
    if (seconds < 0) snprintf(buf, size, "failed");
    else if (seconds < 1e-3) snprintf(buf, size, "%.0f us", seconds * 1e6);
    else if (seconds < 1.0) snprintf(buf, size, "%.1f ms", seconds * 1e3);
    else snprintf(buf, size, "%.2f s", seconds);
}

/* A cold run: new object, the cycle solved, then 241 q in [0, 6]. */
static double dispersion_time(double nu, double tol, int reps, double *worst_err)
{
    double t[32];
    bkf_floquet_options o = bkf_floquet_options_default();
    o.tol = tol;
    *worst_err = 0;
    for (int r = 0; r < reps; r++) {
        double t0 = bench_seconds();
        bkf_floquet *f = bkf_floquet_alloc();
        bkf_error e;
        if (!f || bkf_floquet_set(f, 2.0, 0.3, nu, &o, &e) != BKF_OK) {
            bkf_floquet_free(f);
            return -1;
        }
        for (int i = 0; i <= 240; i++) {
            bkf_floquet_point p;
            if (bkf_floquet_eval(f, 6.0 * i / 240.0, &p, &e) != BKF_OK) {
                bkf_floquet_free(f);
                return -1;
            }
            if (p.lambda > -2 && p.lambda_err > *worst_err) *worst_err = p.lambda_err;
        }
        bkf_floquet_free(f);
        t[r] = bench_seconds() - t0;
    }
    return bench_median(t, reps);
}

static double threshold_time(double tol, int reps, bkf_floquet_threshold *th)
{
    double t[32];
    bkf_floquet_options o = bkf_floquet_options_default();
    o.tol = tol;
    for (int r = 0; r < reps; r++) {
        bkf_error e;
        double t0 = bench_seconds();
        if (bkf_floquet_threshold_find(2.0, 0.3, -0.999, 0.0, &o, th, &e) != BKF_OK) return -1;
        t[r] = bench_seconds() - t0;
    }
    return bench_median(t, reps);
}

static int count_interval(const bkf_floquet_interval *iv, void *data)
{
    (void)iv;
    (*(int *)data)++;
    return 0;
}

static int count_point(const bkf_floquet_threshold *th, void *data)
{
    (void)th;
    (*(int *)data)++;
    return 0;
}

void bench_floquet(void)
{
    char a[32], b[32];
    printf("## floquet: median wall time, gamma 2, c 0.3, one core\n\n");
    printf("| product | tol | time | result | goal |\n");
    printf("|:---|---:|---:|:---|:---|\n");
    const double tols[] = {1e-6, 1e-10, 1e-12};
    for (size_t k = 0; k < 3; k++) {
        double err;
        double t = dispersion_time(-0.94, tols[k], 11, &err);
        fq_time(t, a, sizeof a);
        printf("| dispersion, 241 q in [0, 6], nu -0.94, cold (cycle included) | %g | %s | "
               "largest lambda_err (lambda > -2) %.1e | %s |\n",
               tols[k], a, err, tols[k] == 1e-10 ? "< 50 ms" : "");
        fflush(stdout);
    }
    const double ttols[] = {1e-8, 1e-10};
    for (size_t k = 0; k < 2; k++) {
        bkf_floquet_threshold th;
        double t = threshold_time(ttols[k], 5, &th);
        fq_time(t, a, sizeof a);
        printf("| threshold nu_pd (scan from -0.999, Brent + NLopt) | %g | %s | nu_pd %.11f +- "
               "%.1e, q_c %.5f | %s |\n",
               ttols[k], a, th.nu, th.nu_err, th.q, ttols[k] == 1e-8 ? "< 1 s" : "");
        fflush(stdout);
    }
    {
        bkf_floquet_options o = bkf_floquet_options_default();
        o.tol = 1e-10;
        int n = 0;
        bkf_error e;
        double t0 = bench_seconds();
        int rc = bkf_floquet_diagram(2.0, 0.3, -0.999, 0.999, &o, count_interval, &n, &e);
        double t = rc == BKF_OK ? bench_seconds() - t0 : -1;
        fq_time(t, a, sizeof a);
        printf("| diagram over [-0.999, 0.999], nu step 0.01 | 1e-10 | %s | %d intervals | |\n", a, n);
        o.tol = 1e-8;
        n = 0;
        t0 = bench_seconds();
        rc = bkf_floquet_threshold_branch(BKF_FLOQUET_ALONG_GAMMA, 2.0, 4.0, 0.0, 0.3, -0.999, 0.0,
                                          &o, 0, count_point, &n, &e);
        t = rc == BKF_OK ? bench_seconds() - t0 : -1;
        fq_time(t, b, sizeof b);
        printf("| curve nu_pd(gamma), gamma 2 -> 4 | 1e-8 | %s | %d points | |\n", b, n);
    }
    printf("\n");
}

/* The dense profile's stepper past mu 100 (cycle.c, profile_stepper_for):
 * rk8pd from about 2 mu^2 points over a period where the solve's stiff
 * stepper is bd2x2, which costs about 1 us a point at any mu while
 * rk8pd's cost a point grows with mu. */
#include "harness.h"

#include "bkfront/cycle.h"

#include <math.h>
#include <stdlib.h>
#include <time.h>

static double cpu_seconds(void)
{
    struct timespec t;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

/* n points spread evenly over the period T. */
static double *spread(double T, size_t n)
{
    double *z = malloc(n * sizeof *z);
    CHECK(z);
    for (size_t i = 0; z && i < n; i++) z[i] = T * ((double)i + 0.5) / (double)n;
    return z;
}

/* Both steppers on the same points: at mu 150 (bd2x2 the solve's) the
 * 2 mu^2 = 45000 points and more are sampled by rk8pd, every other one of
 * them (23000) by bd2x2; two integrators, one profile within its tol. */
static void rk8pd_and_bd2x2_agree(void)
{
    bkf_cycle *cy = bkf_cycle_alloc();
    bkf_error e;
    CHECK_MSG(bkf_cycle_solve(cy, 150, -0.96, NULL, &e) == BKF_OK, "%s", e.message);
    double T = bkf_cycle_get(cy)->period;
    enum { N = 46000 };
    double *z = spread(T, N), *f = malloc(N * sizeof *f), *fp = malloc(N * sizeof *fp);
    double *zh = malloc(N / 2 * sizeof *zh), *fh = malloc(N / 2 * sizeof *fh),
           *fph = malloc(N / 2 * sizeof *fph);
    CHECK(z && f && fp && zh && fh && fph);
    for (size_t i = 0; i < N / 2; i++) zh[i] = z[2 * i];
    CHECK_MSG(bkf_cycle_profile_sample(cy, z, N, f, fp, &e) == BKF_OK, "%s", e.message);
    CHECK_MSG(bkf_cycle_profile_sample(cy, zh, N / 2, fh, fph, &e) == BKF_OK, "%s", e.message);
    double worst = 0, worst_p = 0;
    for (size_t i = 0; i < N / 2; i++) {
        worst = fmax(worst, fabs(f[2 * i] - fh[i]));
        /* f' = y - mu F(f): mu times the state's error */
        worst_p = fmax(worst_p, fabs(fp[2 * i] - fph[i]) / (1 + fabs(fph[i])));
    }
    bkf_test_note("mu 150: |f| apart by %.2g at most, |f'| by %.2g (relative)", worst, worst_p);
    CHECK(worst < 1e-10);
    CHECK(worst_p < 1e-9);
    free(z);
    free(f);
    free(fp);
    free(zh);
    free(fh);
    free(fph);
    bkf_cycle_free(cy);
}

/* 65536 points at mu 1000 (bd2x2 the solve's): under 2 mu^2, so bd2x2
 * samples them, in CPU time within a few times the same count at mu 120.8
 * (rk8pd there, above 2 mu^2 = 29000; each about 0.05 s).  Before, the
 * rule (20 points a unit of mu at every mu) gave them to rk8pd: 1.83 s
 * against 0.048, a ratio of 38. */
static void mu_1000_costs_what_mu_120_does(void)
{
    enum { N = 65536 };
    double t[2];
    const double mus[2] = {120.8, 1000};
    for (int k = 0; k < 2; k++) {
        bkf_cycle *cy = bkf_cycle_alloc();
        bkf_error e;
        CHECK_MSG(bkf_cycle_solve(cy, mus[k], -0.96, NULL, &e) == BKF_OK, "%s", e.message);
        double *z = spread(bkf_cycle_get(cy)->period, N), *f = malloc(N * sizeof *f);
        CHECK(z && f);
        t[k] = 1e9;
        for (int r = 0; r < 2; r++) { /* the faster of two: a preemption is not the stepper */
            double t0 = cpu_seconds();
            CHECK_MSG(bkf_cycle_profile_sample(cy, z, N, f, NULL, &e) == BKF_OK, "%s", e.message);
            t[k] = fmin(t[k], cpu_seconds() - t0);
        }
        free(z);
        free(f);
        bkf_cycle_free(cy);
    }
    bkf_test_note("%d points: %.3f s at mu 120.8, %.3f s at mu 1000", N, t[0], t[1]);
    CHECK_MSG(t[1] < 6 * t[0] + 0.01, "mu 1000: %.3f s, %.1f times mu 120.8's", t[1], t[1] / t[0]);
}

TEST(cycle_profile_dense_stepper_past_mu_100)
{
    rk8pd_and_bd2x2_agree();
    mu_1000_costs_what_mu_120_does();
}

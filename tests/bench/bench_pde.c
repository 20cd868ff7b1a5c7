/* Benchmark of the simulator: wall time of runs at the paper's parameters
 * (gamma 2, c 0.3, nu -0.96, S 20), one core, as markdown tables.
 * Goals (issue #4): S = 20, N = 512, tmax = 125 at the default tolerance
 * under 0.3 s; the full paper-parameter check under 10 s. */
#define _POSIX_C_SOURCE 200809L
#include "bkfront/measure.h"
#include "bkfront/pde.h"
#include "bkfront/seed.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

void bench_pde(void);
void bench_pde_cost(void);

static double pd_clock(clockid_t id)
{
    struct timespec ts;
    clock_gettime(id, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double pd_now(void) { return pd_clock(CLOCK_MONOTONIC); }

static int pd_compare(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static void pd_time(double s, char *buf, size_t size)
{
    if (s < 0) snprintf(buf, size, "failed");
    else if (s < 1.0) snprintf(buf, size, "%.0f ms", s * 1e3);
    else snprintf(buf, size, "%.2f s", s);
}

static int pd_observe(const bkf_pde_sample *s, void *data)
{
    bkf_error e;
    return bkf_measure_add(data, s->t, s->psi, s->eta, &e) != BKF_OK;
}

typedef enum { IC_FRONT, IC_UNIFORM, IC_OSCILLATION } pd_ic;

typedef struct {
    double seconds, cpu, h_min;
    size_t steps;
    double v_pred, v_meas;
    const char *regime;
} pd_run;

/* One run: allocation, initial state, integration to tmax, with or without
 * measurements every 0.1. */
static int run_with(pd_ic ic, size_t n, double nu, size_t N, double tol, double tmax, int measure,
                    bkf_pde_stepper stepper, pd_run *out)
{
    bkf_model_params p = {2.0, 0.3, nu, 20.0, N, BKF_MODEL_CONTINUUM};
    bkf_pde_options o = bkf_pde_options_default();
    o.tol = tol;
    o.stepper = stepper;
    bkf_error e;
    double t0 = pd_now(), c0 = pd_clock(CLOCK_PROCESS_CPUTIME_ID);
    bkf_pde *m = bkf_pde_alloc(&p, &o, &e);
    if (!m) return -1;
    bkf_pde_front_info fi = {0};
    int s = BKF_OK;
    if (ic == IC_FRONT) {
        bkf_pde_front_spec fs = bkf_pde_front_spec_default();
        fs.n = n;
        s = bkf_seed_front(m, &fs, &fi, NULL, &e);
    } else if (ic == IC_UNIFORM)
        s = bkf_pde_init_uniform(m, 1e-3, 1, &e);
    else
        s = bkf_pde_init_oscillation(m, 9, 0.3, &e);
    bkf_measure *ms = NULL;
    if (!s && measure) {
        bkf_measure_params mp = bkf_measure_params_default();
        mp.model = (bkf_model_params){2, 0.3, nu, 20, N, BKF_MODEL_CONTINUUM};
        mp.level = nu;
        ms = bkf_measure_alloc(&mp, &e);
        if (!ms) s = -1;
    }
    if (!s) s = bkf_pde_run(m, tmax, measure ? 0.1 : tmax, measure ? pd_observe : NULL, ms, NULL,
                            NULL, &e);
    bkf_measure_summary sum;
    memset(&sum, 0, sizeof sum);
    if (!s && ms) s = bkf_measure_summarize(ms, &sum, &e);
    out->seconds = pd_now() - t0;
    out->cpu = pd_clock(CLOCK_PROCESS_CPUTIME_ID) - c0;
    out->steps = bkf_pde_get_stats(m)->steps;
    out->h_min = bkf_pde_get_stats(m)->h_min;
    out->v_pred = fi.v;
    out->v_meas = ms ? -sum.speed : NAN;
    out->regime = ms ? bkf_regime_name(sum.regime) : "-";
    bkf_measure_free(ms);
    bkf_pde_free(m);
    return s;
}

static int one_run(pd_ic ic, size_t n, double nu, size_t N, double tol, double tmax, int measure,
                   pd_run *out)
{
    return run_with(ic, n, nu, N, tol, tmax, measure, bkf_pde_options_default().stepper, out);
}

static double median_run(pd_ic ic, size_t n, double nu, size_t N, double tol, double tmax,
                         int measure, int reps, pd_run *last)
{
    double t[16];
    if (reps > 16) reps = 16;
    for (int r = 0; r < reps; r++) {
        if (one_run(ic, n, nu, N, tol, tmax, measure, last) != BKF_OK) return -1;
        t[r] = last->seconds;
    }
    qsort(t, (size_t)reps, sizeof *t, pd_compare);
    return t[reps / 2];
}

/* `bkfront check` as built beside this benchmark (build/bkfront relative to
 * the working directory, where `make bench` runs), timed as a whole; extra
 * arguments (NULL-terminated, at most 12) are passed on. */
static double time_check(const char *const *args)
{
    const char *cli = "build/bkfront";
    if (access(cli, X_OK) != 0) return -1;
    const char *argv[16] = {cli, "check", "--no-progress"};
    size_t k = 3;
    for (size_t i = 0; args && args[i] && k < 15; i++) argv[k++] = args[i];
    argv[k] = NULL;
    double t0 = pd_now();
    pid_t pid = fork();
    if (pid < 0) return -1;
    if (pid == 0) {
        FILE *f = freopen("/dev/null", "w", stdout);
        (void)f;
        execv(cli, (char *const *)argv);
        _exit(127);
    }
    int status = 0;
    if (waitpid(pid, &status, 0) != pid || !WIFEXITED(status) || WEXITSTATUS(status) > 1) return -1;
    return pd_now() - t0;
}

void bench_pde(void)
{
    char a[32], b[32];
    printf("## pde: median wall time of one run, S = 20, gamma 2, c 0.3, one core\n\n");
    printf("| initial state | nu | N | tol | tmax | run only | with measurements | steps | "
           "result | goal |\n");
    printf("|:---|---:|---:|---:|---:|---:|---:|---:|:---|:---|\n");
    struct {
        pd_ic ic;
        size_t n;
        double nu;
        size_t N;
        const char *name;
        const char *goal;
    } cases[] = {
        {IC_FRONT, 2, -0.96, 512, "front:n=2", "< 0.3 s"},
        {IC_FRONT, 4, -0.96, 512, "front:n=4", "< 0.3 s"},
        {IC_UNIFORM, 0, -0.96, 512, "uniform (noise 1e-3)", "< 0.3 s"},
        {IC_OSCILLATION, 0, -0.94, 512, "oscillation:j=9,amp=0.3", "< 0.3 s"},
        {IC_FRONT, 4, -0.96, 1024, "front:n=4", ""},
        {IC_FRONT, 6, -0.96, 2048, "front:n=6", ""},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        pd_run r0, r1;
        double t0 = median_run(cases[i].ic, cases[i].n, cases[i].nu, cases[i].N, 1e-9, 125, 0,
                               cases[i].N > 1024 ? 1 : 5, &r0);
        double t1 = median_run(cases[i].ic, cases[i].n, cases[i].nu, cases[i].N, 1e-9, 125, 1,
                               cases[i].N > 1024 ? 1 : 5, &r1);
        pd_time(t0, a, sizeof a);
        pd_time(t1, b, sizeof b);
        char result[96];
        if (cases[i].ic == IC_FRONT)
            snprintf(result, sizeof result, "%s, v rel. err %.1e", r1.regime,
                     (r1.v_meas - r1.v_pred) / r1.v_pred);
        else
            snprintf(result, sizeof result, "%s", r1.regime);
        printf("| %s | %g | %zu | 1e-9 | 125 | %s | %s | %zu | %s | %s |\n", cases[i].name,
               cases[i].nu, cases[i].N, a, b, r0.steps, result, cases[i].goal);
        fflush(stdout);
    }
    printf("\n");

    printf("## pde: measured speed of the seeded n = 4 front against N and tol "
           "(tmax 125, nu -0.96)\n\n");
    printf("| N | tol | v_meas - v_pred (relative) | steps | time |\n|---:|---:|---:|---:|---:|\n");
    const size_t Ns[] = {512, 1024, 2048};
    const double tols[] = {1e-7, 1e-9, 1e-11};
    for (size_t i = 0; i < 3; i++)
        for (size_t j = 0; j < 3; j++) {
            pd_run r;
            double t = median_run(IC_FRONT, 4, -0.96, Ns[i], tols[j], 125, 1, 1, &r);
            pd_time(t, a, sizeof a);
            printf("| %zu | %.0e | %.2e | %zu | %s |\n", Ns[i], tols[j],
                   (r.v_meas - r.v_pred) / r.v_pred, r.steps, a);
            fflush(stdout);
        }
    printf("\n");

    printf("## pde: `bkfront check` at the paper's parameters\n\n");
    printf("| command | time | goal |\n|:---|---:|:---|\n");
    double tc = time_check(NULL);
    pd_time(tc, a, sizeof a);
    printf("| bkfront check (every n; defaults: n = 1..9 on the uniform grid with etdrk4 in "
           "the moving frame, n = 10..12 on the adapted grid) | %s | < 10 s |\n",
           tc < 0 ? "failed" : a);
    fflush(stdout);
    /* each n on its own with the defaults (the grid the resolution rule
     * picks, the adapted grid beyond N = 8192), and the explicit rk8pd in the
     * lab frame (the former default) where it is affordable (n <= 7) */
    static const char *const ns[] = {"1", "2", "3", "4", "5", "6", "7", "8", "9", "10", "11",
                                     "12"};
    for (size_t i = 0; i < sizeof ns / sizeof ns[0]; i++) {
        for (int f = 0; f < 2; f++) {
            if (f && i >= 7) break;
            const char *args[7] = {"--n", ns[i], NULL};
            if (f) {
                args[2] = "--stepper";
                args[3] = "rk8pd";
                args[4] = "--frame";
                args[5] = "lab";
            }
            tc = time_check(args);
            pd_time(tc, a, sizeof a);
            printf("| bkfront check --n %s%s | %s | |\n", ns[i],
                   f ? " --stepper rk8pd --frame lab" : "", tc < 0 ? "failed" : a);
            fflush(stdout);
        }
    }
    printf("\n");
}

/* Issue 20's goal, simulate's cost per unit time no faster than N log N:
 * CPU seconds of the seeded n = 4 front (tol 1e-9, tmax 125, measured
 * every 0.1 as bkfront simulate does) against N for the three steppers
 * that reach large N, one run each (N 8192 with rk8pd takes minutes).
 * N doubles from 512 to 8192, or to BKF_BENCH_PDE_N_MAX (up to 65536 is
 * sensible; rk8pd and etdrk4 stop at 8192 unless BKF_BENCH_PDE_ALL is set).
 * The fit: cost per unit time = C N log2 N by least squares in the log
 * (the spread, the largest factor between a point and the fit, says how
 * far from N log N), and the exponent p of N^p between the first and the
 * last N (N log N alone gives p = 1.08 from 512 to 8192). */
void bench_pde_cost(void)
{
    size_t n_max = 8192;
    const char *env = getenv("BKF_BENCH_PDE_N_MAX");
    if (env && atol(env) >= 512) n_max = (size_t)atol(env);
    int all = getenv("BKF_BENCH_PDE_ALL") != NULL;
    static const struct {
        bkf_pde_stepper s;
        const char *name;
    } steppers[] = {{BKF_PDE_RK8PD, "rk8pd"}, {BKF_PDE_ETDRK4, "etdrk4"},
                    {BKF_PDE_LAWSON8, "lawson8"}};
    const double tmax = 125;
    printf("## pde: cost against N, seeded n = 4 front, tol 1e-9, tmax %g, one run each, "
           "one core\n\n", tmax);
    printf("| stepper | N | steps | smallest step | CPU | CPU per unit time | "
           "/ (N log2 N) | v_meas - v_pred (relative) |\n");
    printf("|:---|---:|---:|---:|---:|---:|---:|---:|\n");
    for (size_t k = 0; k < sizeof steppers / sizeof steppers[0]; k++) {
        double lx[16], ly[16], ln[16];
        size_t m = 0;
        for (size_t N = 512; N <= n_max && m < 16; N *= 2) {
            if (N > 8192 && steppers[k].s != BKF_PDE_LAWSON8 && !all) break;
            pd_run r;
            memset(&r, 0, sizeof r);
            int s = run_with(IC_FRONT, 4, -0.96, N, 1e-9, tmax, 1, steppers[k].s, &r);
            if (s != BKF_OK) {
                printf("| %s | %zu | failed | | | | | |\n", steppers[k].name, N);
                continue;
            }
            double per = r.cpu / tmax, nl = (double)N * log2((double)N);
            printf("| %s | %zu | %zu | %.3g | %.2f s | %.3g s | %.3g us | %.1e |\n",
                   steppers[k].name, N, r.steps, r.h_min, r.cpu, per, per / nl * 1e6,
                   (r.v_meas - r.v_pred) / r.v_pred);
            fflush(stdout);
            lx[m] = log(nl);
            ly[m] = log(per);
            ln[m] = log((double)N);
            m++;
        }
        if (m < 2) continue;
        double c = 0, dev = 0;
        for (size_t i = 0; i < m; i++) c += (ly[i] - lx[i]) / (double)m;
        for (size_t i = 0; i < m; i++) dev = fmax(dev, fabs(ly[i] - lx[i] - c));
        double p = (ly[m - 1] - ly[0]) / (ln[m - 1] - ln[0]);
        printf("| %s fit | | | | | N^%.2f | C = %.3g us (spread x%.2f) | |\n",
               steppers[k].name, p, exp(c) * 1e6, exp(dev));
    }
    printf("\n");
}

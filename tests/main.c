/* Test runner: each registered test runs in its own child process with a
 * time limit, so a crash, an abort from a sanitizer or a hang is one failure,
 * not the end of the suite.  `run_tests PATTERN` runs the tests whose name
 * contains PATTERN.
 *
 * Up to BKF_TEST_JOBS tests run at once (default: the online CPUs).  Each
 * child writes stdout and stderr to a temporary file of its own, printed
 * whole when the test is done, in the sorted order (file, then name), so the
 * report reads the same however many jobs ran.  The slowest tests start
 * first, so that the jobs finish together. */
#define _POSIX_C_SOURCE 200809L
#include "harness.h"

#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdarg.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#define MAX_TESTS 1024
#define TEST_TIME_LIMIT_S 240

typedef struct {
    const char *name;
    const char *file;
    bkf_test_fn fn;
} test_entry;

static test_entry tests[MAX_TESTS];
static size_t test_count;

void bkf_test_register(const char *name, const char *file, bkf_test_fn fn)
{
    if (test_count < MAX_TESTS)
        tests[test_count++] = (test_entry){name, file, fn};
}

void bkf_test_fail(const char *file, int line, const char *fmt, ...)
{
    va_list ap;
    fprintf(stdout, "    %s:%d: ", file, line);
    va_start(ap, fmt);
    vfprintf(stdout, fmt, ap);
    va_end(ap);
    fputc('\n', stdout);
    fflush(stdout);
    _exit(1);
}

void bkf_test_note(const char *fmt, ...)
{
    va_list ap;
    fputs("    # ", stdout);
    va_start(ap, fmt);
    vfprintf(stdout, fmt, ap);
    va_end(ap);
    fputc('\n', stdout);
    fflush(stdout);
}

static int compare_entries(const void *a, const void *b)
{
    const test_entry *x = a, *y = b;
    int c = strcmp(x->file, y->file);
    return c ? c : strcmp(x->name, y->name);
}

/* CPU seconds of the slowest tests (-O2): docs/timings.md's run of
 * 2026-11-29 (5ebcaa7, quiet machine), the tests made cheaper since at
 * their new cost (suitefast2: the extremes matrices, the threshold sweep;
 * canardfast: the canard jump; suitefast3, 2026-11-30: the check's auto
 * runs, the train spectra against simulation, the stability boundary, and
 * three now under 2.5 s; clifast, 2026-11-30: the stuck canard, the Taylor
 * and chainwave tests, the figures, the sweep's threshold, SIGTERM and MPI
 * farm tests; floquetfast: the extremes matrices again; hillreal: the
 * audit's sample, Hill's class pi real);
 * the ones not listed take under 2.5 s.  The sanitized
 * build at -O1 takes about 1.4 times as long, in the same order.  Only the
 * start order depends on it, and only until a run has written
 * BKF_TEST_TIMES (below): a stale entry costs wall time, never a result.
 * CI's fresh clone has no times, so this order is its order: with the
 * list as it was (entries up to 25.6 s for tests that had come down to 6 s)
 * the longest tests did not start first. */
static const struct {
    const char *name;
    double secs;
} known_slow[] = {
    {"speeds_canard_jump_rows_honest_or_unresolved", 5.7},
    {"extremes_floquet_matrix_gamma_100", 12.0},
    {"extremes_floquet_matrix_gamma_to_30", 7.4},
    {"audit_fixed_sample_set_1", 9.0},
    {"cli_sweep_mpi_signals_and_kill_keep_rows_and_resume_completes", 10.5},
    {"figures_keep_every_point_in_view_at_gamma_6_c_0_1", 5.7},
    {"extremes_floquet_matrix_gamma_100_near_hopf", 8.2},
    {"products_orbits_coexistence_sets_regimes_beside_the_solutions", 8.2},
    {"extremes_period_matrix", 4.7},
    {"cli_sweep_threshold_product_is_floquet_threshold_at_each_point", 5.6},
    {"cli_period_continue_stuck_in_the_canard_names_mu_and_nu", 3.3},
    {"cycle_branch_stuck_in_the_canard_fails_fast", 3.2},
    {"figures_keep_every_point_in_view_at_gamma_0_7_c_0_8", 3.9},
    {"cli_sweep_mpi_farm_equals_serial", 5.5},
    {"cli_check_adapted_grid_error_covers_the_grid_thin_fronts", 5.8},
    {"cycle_engine_bd2x2_meets_tol_against_taylor", 2.2},
    {"stabmap_diagram_followed_curves_are_the_scans_crossings", 5.0},
    {"chainwave_large_multiplier_tolerance_is_relative", 1.1},
    {"chainwave_implicit_stepper", 1.2},
    {"cli_sweep_sigterm_keeps_finished_rows_and_resume_completes", 2.4},
    {"trainspec_rightmost_beside_the_translation_and_where_curves_fail", 4.0},
    {"lawson_steps_do_not_depend_on_N", 4.0},
    {"stabmap_trace_points_straddle_the_sign_change", 3.8},
    {"extremes_speeds_matrix", 2.6},
    {"orbit_stable_pacemaker_kept_by_simulation_sectors_and_grid", 3.5},
    {"stabmap_diagram_no_states_for_an_n_whose_curve_stalled", 3.5},
    {"trainspec_hill_grows_where_the_curves_run_out_mu_4_9", 3.4},
    {"cli_speeds_refused_row_keeps_the_table_exit_3", 3.2},
    {"products_threshold_and_diagram_library_rows_are_the_cli_rows", 3.1},
    {"cli_chain_branch_ends_on_the_table", 3.1},
    {"check_auto_runs_keep_verdicts_and_speeds", 3.1},
    {"trainspec_sim_paper", 3.1},
    {"cycle_tolerance_honoured_on_extremes", 3.0},
    {"orbit_travelling_train_has_the_speeds_root", 3.0},
    {"stabmap_boundary_point_recomputed", 3.0},
    {"cli_sweep_scene_gives_the_cli_table", 2.9},
    {"products_orbits_tsv_json_and_library_agree", 2.8},
    {"extremes_period_estimates_never_flatter", 2.8},
    {"floquet_collocation_cycle_in_the_band_against_shooting", 2.7},
    {"cli_simulate_regimes_wait_for_their_evidence", 2.7},
    {"check_growth_weak_instability_is_undecided", 2.7},
    {"trainspec_newton_curves_and_polish_cut_match_hill_per_class_on_random_sets", 2.7},
    {"trainspec_agrees_with_hill_stable_n4", 2.7},
    {"cli_sweep_speeds_product_is_speeds_stability_at_each_point", 2.6},
    {"cycle_branch_nu_through_the_canard_at_mu_10_to_plus_0_999", 2.6},
    {"cli_check_exponential_and_explicit_agree", 2.6},
    {"trainspec_fast_path_matches_hill_and_a_finer_mesh_on_random_sets", 2.6},
    {"trainspec_agrees_with_hill_unstable_n2", 2.5},
};

/* The times of the last runs (BKF_TEST_TIMES, a file of "NAME\tSECONDS"
 * lines that make test keeps in the build folder): where a test has one, it
 * orders the start instead of the list above, which only a fresh build (the
 * CI's clone) still needs. */
static struct {
    char name[128];
    double secs;
} learned[MAX_TESTS];
static size_t learned_count;

static void read_times(const char *path)
{
    FILE *f = path ? fopen(path, "r") : NULL;
    if (!f) return;
    char line[256];
    while (learned_count < MAX_TESTS && fgets(line, sizeof line, f)) {
        char *tab = strchr(line, '\t');
        if (!tab || (size_t)(tab - line) >= sizeof learned[0].name) continue;
        double secs = strtod(tab + 1, NULL);
        if (!(secs >= 0.0)) continue;
        memcpy(learned[learned_count].name, line, (size_t)(tab - line));
        learned[learned_count].name[tab - line] = '\0';
        learned[learned_count++].secs = secs;
    }
    fclose(f);
}

static double expected_secs(const char *name)
{
    for (size_t i = 0; i < learned_count; i++)
        if (strcmp(learned[i].name, name) == 0) return learned[i].secs;
    for (size_t i = 0; i < sizeof known_slow / sizeof known_slow[0]; i++)
        if (strcmp(known_slow[i].name, name) == 0) return known_slow[i].secs;
    return 0.0;
}

/* A selected test and, once it ran, its result. */
typedef struct {
    const test_entry *test;
    double expected;
    pid_t pid;
    int fd;          /* its captured output */
    int done, status;
    double secs, cpu;   /* wall; user + system CPU of the test and what it waited for */
    struct timespec start;
} job;

static job *jobs;
static size_t job_count;

static int compare_expected(const void *a, const void *b)
{
    const job *x = *(job *const *)a, *y = *(job *const *)b;
    if (x->expected != y->expected) return x->expected < y->expected ? 1 : -1;
    return x < y ? -1 : x > y;   /* then the sorted order */
}

static double since(const struct timespec *t0)
{
    struct timespec t1;
    clock_gettime(CLOCK_MONOTONIC, &t1);
    return (double)(t1.tv_sec - t0->tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0->tv_nsec);
}

/* User + system seconds of the reaped children and of what they reaped. */
static double children_cpu(void)
{
    struct rusage ru;
    if (getrusage(RUSAGE_CHILDREN, &ru) != 0) return 0.0;
    return (double)(ru.ru_utime.tv_sec + ru.ru_stime.tv_sec) +
           1e-6 * (double)(ru.ru_utime.tv_usec + ru.ru_stime.tv_usec);
}

/* Interrupted (Ctrl-C): the running tests and what they started go too. */
static void on_interrupt(int sig)
{
    for (size_t i = 0; i < job_count; i++)
        if (jobs[i].pid > 0 && !jobs[i].done) kill(-jobs[i].pid, SIGKILL);
    signal(sig, SIG_DFL);
    raise(sig);
}

/* The time limit for a test starting now: the limit times the load per
 * core, when above 1 (/proc/loadavg; 1 where it cannot be read). On a
 * machine loaded several times over its cores the plain limit failed tests
 * that were only slow (the Floquet matrix, 45 s of CPU, past 240 s at a
 * load of 18 on 2 cores). A CPU-time limit (RLIMIT_CPU) would not stretch,
 * but arming it makes the kernel sample the process's CPU clock at its
 * tick, and bench rows timed with that clock read 0 s. */
static unsigned scaled_limit(unsigned time_limit, long cpus)
{
    double load = 0.0, f = 1.0;
    FILE *p = fopen("/proc/loadavg", "r");
    if (p) {
        if (fscanf(p, "%lf", &load) == 1 && cpus > 0 && load / (double)cpus > 1.0)
            f = fmin(load / (double)cpus, 20.0);
        fclose(p);
    }
    return (unsigned)((double)time_limit * f);
}

static void start(job *j, unsigned time_limit, long cpus)
{
    unsigned limit = scaled_limit(time_limit, cpus);
    char name[] = "/tmp/bkf_test_out_XXXXXX";
    j->fd = mkstemp(name);
    if (j->fd < 0) {
        perror("run_tests: mkstemp");
        exit(2);
    }
    unlink(name);
    fflush(stdout);
    fflush(stderr);
    clock_gettime(CLOCK_MONOTONIC, &j->start);
    j->pid = fork();
    if (j->pid < 0) {
        perror("run_tests: fork");
        exit(2);
    }
    if (j->pid == 0) {
        /* a process group of its own: whatever the test starts ends with it */
        setpgid(0, 0);
        signal(SIGINT, SIG_DFL);
        signal(SIGTERM, SIG_DFL);
        int in = open("/dev/null", O_RDONLY);
        if (in < 0 || dup2(in, 0) < 0 || dup2(j->fd, 1) < 0 || dup2(j->fd, 2) < 0) _exit(3);
        alarm(limit);
        j->test->fn();
        fflush(stdout);
        _exit(0);
    }
    setpgid(j->pid, j->pid);   /* also here: no race with the kill below */
}

static void report(job *j, int *passed, int *failed)
{
    int ok = WIFEXITED(j->status) && WEXITSTATUS(j->status) == 0;
    if (ok) {
        (*passed)++;
        printf("ok   %-48s %7.2fs %7.2fs cpu\n", j->test->name, j->secs, j->cpu);
    } else {
        (*failed)++;
        if (WIFSIGNALED(j->status))
            printf("FAIL %-48s (signal %d)\n", j->test->name, WTERMSIG(j->status));
        else
            printf("FAIL %-48s\n", j->test->name);
    }
    fflush(stdout);
    char buf[65536];
    ssize_t k;
    lseek(j->fd, 0, SEEK_SET);
    while ((k = read(j->fd, buf, sizeof buf)) > 0) fwrite(buf, 1, (size_t)k, stdout);
    close(j->fd);
    fflush(stdout);
}

/* The learned times again, this run's wall seconds replacing theirs (a
 * test not run keeps its old time); written beside and renamed, so that a
 * run cut short leaves the old file. Only the start order depends on it. */
static void write_times(const char *path)
{
    if (!path) return;
    char tmp[4096];
    if (snprintf(tmp, sizeof tmp, "%s.tmp.%ld", path, (long)getpid()) >= (int)sizeof tmp) return;
    FILE *f = fopen(tmp, "w");
    if (!f) return;
    for (size_t i = 0; i < learned_count; i++) {
        int ran = 0;
        for (size_t k = 0; k < job_count && !ran; k++) ran = strcmp(jobs[k].test->name, learned[i].name) == 0;
        if (!ran) fprintf(f, "%s\t%.2f\n", learned[i].name, learned[i].secs);
    }
    for (size_t k = 0; k < job_count; k++) fprintf(f, "%s\t%.2f\n", jobs[k].test->name, jobs[k].secs);
    if (fclose(f) != 0 || rename(tmp, path) != 0) remove(tmp);
}

static unsigned env_unsigned(const char *name, unsigned fallback, unsigned long max)
{
    const char *env = getenv(name);
    if (!env) return fallback;
    char *end;
    unsigned long v = strtoul(env, &end, 10);
    return *env && !*end && v > 0 && v <= max ? (unsigned)v : fallback;
}

int main(int argc, char **argv)
{
    const char *pattern = argc > 1 ? argv[1] : NULL;
    /* BKF_TEST_TIME_LIMIT (seconds) raises the limit for slow runs: under
     * valgrind the extremes matrix takes ~50 times its 13 s. */
    unsigned time_limit = env_unsigned("BKF_TEST_TIME_LIMIT", TEST_TIME_LIMIT_S, 86399 / 20);
    long cpus = sysconf(_SC_NPROCESSORS_ONLN);
    unsigned max_jobs = env_unsigned("BKF_TEST_JOBS", cpus > 0 ? (unsigned)cpus : 1, 256);

    read_times(getenv("BKF_TEST_TIMES"));
    /* no times of its own yet (the sanitized build's first run): another
     * build's times order it better than the list above */
    if (learned_count == 0) read_times(getenv("BKF_TEST_TIMES_SEED"));
    qsort(tests, test_count, sizeof tests[0], compare_entries);
    jobs = calloc(test_count + 1, sizeof *jobs);
    job **order = calloc(test_count + 1, sizeof *order);
    if (!jobs || !order) {
        perror("run_tests");
        return 2;
    }
    for (size_t i = 0; i < test_count; i++) {
        if (pattern && !strstr(tests[i].name, pattern)) continue;
        jobs[job_count] = (job){.test = &tests[i], .expected = expected_secs(tests[i].name), .fd = -1};
        order[job_count] = &jobs[job_count];
        job_count++;
    }
    qsort(order, job_count, sizeof order[0], compare_expected);
    /* an ignored signal stays ignored (nohup, a background job) */
    if (signal(SIGINT, on_interrupt) == SIG_IGN) signal(SIGINT, SIG_IGN);
    if (signal(SIGTERM, on_interrupt) == SIG_IGN) signal(SIGTERM, SIG_IGN);

    int passed = 0, failed = 0;
    size_t started = 0, running = 0, reported = 0;
    double cpu_reaped = children_cpu();
    while (reported < job_count) {
        while (running < max_jobs && started < job_count) {
            start(order[started++], time_limit, cpus);
            running++;
        }
        int status;
        pid_t pid = waitpid(-1, &status, 0);
        if (pid < 0) {
            if (errno == EINTR) continue;
            perror("run_tests: waitpid");
            return 2;
        }
        for (size_t i = 0; i < job_count; i++) {
            job *j = &jobs[i];
            if (j->pid != pid || j->done) continue;
            j->secs = since(&j->start);
            /* the children's total grows by this one's alone at its reaping */
            double cpu = children_cpu();
            j->cpu = cpu - cpu_reaped;
            cpu_reaped = cpu;
            j->status = status;
            j->done = 1;
            running--;
            /* what the test left running (a CLI it started, say) ends now */
            kill(-pid, SIGKILL);
            break;
        }
        /* print as soon as everything before it in the sorted order is done */
        while (reported < job_count && jobs[reported].done) report(&jobs[reported++], &passed, &failed);
    }
    write_times(getenv("BKF_TEST_TIMES"));
    free(order);
    free(jobs);
    printf("%d passed, %d failed\n", passed, failed);
    return failed ? 1 : 0;
}

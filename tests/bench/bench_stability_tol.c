/* Benchmark of `bkfront speeds --stability` (issue 33): the CPU time the
 * user waits for (the process's, start included), against the tolerance
 * asked of each sigma, on the paper's table (gamma 2, c 0.3, nu -0.96,
 * S 20, every root).  CPU seconds of the child (getrusage), median of 5,
 * so that other jobs on the machine blur it less than wall time.  The CLI
 * is $BKFRONT_CLI (make bench sets it); a second binary in
 * $BKFRONT_CLI_BEFORE, when set, is timed beside it (a ratio in one run).
 * Goal (issue 33): under 0.5 s at the default tol 1e-6. */
#define _POSIX_C_SOURCE 200809L
#include "bench_util.h"

#include <fcntl.h>
#include <spawn.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

extern char **environ;

void bench_stability_tol(void);

#define TOL_RUNS 5

static double child_cpu(void)
{
    struct rusage u;
    getrusage(RUSAGE_CHILDREN, &u);
    return (double)u.ru_utime.tv_sec + 1e-6 * (double)u.ru_utime.tv_usec + (double)u.ru_stime.tv_sec +
           1e-6 * (double)u.ru_stime.tv_usec;
}

/* Median CPU seconds of `cli speeds --stability --stability-tol tol`;
 * negative when a run fails (*status its exit status). */
static double median_cpu(const char *cli, const char *tol, int *status)
{
    double t[TOL_RUNS];
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
    posix_spawn_file_actions_addopen(&fa, STDERR_FILENO, "/dev/null", O_WRONLY, 0);
    char *argv[] = {(char *)cli, "speeds", "--stability", "--stability-tol", (char *)tol, NULL};
    *status = 0;
    for (int i = 0; i < TOL_RUNS; i++) {
        double c0 = child_cpu();
        pid_t pid;
        int ws;
        if (posix_spawn(&pid, cli, &fa, NULL, argv, environ) != 0 || waitpid(pid, &ws, 0) != pid ||
            !WIFEXITED(ws) || WEXITSTATUS(ws)) {
            *status = WIFEXITED(ws) ? WEXITSTATUS(ws) : -1;
            posix_spawn_file_actions_destroy(&fa);
            return -1;
        }
        t[i] = child_cpu() - c0;
    }
    posix_spawn_file_actions_destroy(&fa);
    return bench_median(t, TOL_RUNS);
}

void bench_stability_tol(void)
{
    const char *cli = getenv("BKFRONT_CLI"), *before = getenv("BKFRONT_CLI_BEFORE");
    const char *tols[] = {"1e-4", "1e-5", "1e-6", "1e-7", "1e-8", "1e-9", "1e-10"};
    printf("## speeds --stability on the paper's table: CPU seconds against --stability-tol, median of %d\n\n",
           TOL_RUNS);
    if (!cli) {
        printf("(skipped: BKFRONT_CLI does not name the bkfront to time)\n\n");
        return;
    }
    printf("| --stability-tol | CPU |%s\n|---:|---:|%s\n", before ? " before | before / now |" : "",
           before ? "---:|---:|" : "");
    for (size_t i = 0; i < sizeof tols / sizeof tols[0]; i++) {
        int st, st_b = 0;
        double now = median_cpu(cli, tols[i], &st), was = before ? median_cpu(before, tols[i], &st_b) : 0;
        printf("| %s |", tols[i]);
        if (now < 0) printf(" exit %d |", st);
        else printf(" %.2f s |", now);
        if (before) {
            if (was < 0) printf(" exit %d | |", st_b);
            else if (now < 0) printf(" %.2f s | |", was);
            else printf(" %.2f s | %.1f |", was, was / now);
        }
        printf("\n");
        fflush(stdout);
    }
    printf("\n");
}

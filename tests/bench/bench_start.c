/* Process start: wall time of `bkfront --version`, spawned and waited for,
 * against /bin/true (what any process start costs on this machine).  The
 * CLI is $BKFRONT_CLI (make bench sets it). */
#define _POSIX_C_SOURCE 200809L
#include "bench_util.h"

#include <fcntl.h>
#include <spawn.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <unistd.h>

extern char **environ;

#define START_RUNS 100

/* Median wall seconds of `path arg` over START_RUNS runs, stdout to
 * /dev/null; negative if a run fails. */
static double median_start(const char *path, const char *arg, double *fastest)
{
    double t[START_RUNS];
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
    char *argv[] = {(char *)path, (char *)arg, NULL};
    for (int i = 0; i < START_RUNS; i++) {
        double t0 = bench_seconds();
        pid_t pid;
        int status;
        if (posix_spawn(&pid, path, &fa, NULL, argv, environ) != 0 ||
            waitpid(pid, &status, 0) != pid || !WIFEXITED(status) || WEXITSTATUS(status)) {
            posix_spawn_file_actions_destroy(&fa);
            return -1;
        }
        t[i] = bench_seconds() - t0;
    }
    posix_spawn_file_actions_destroy(&fa);
    double m = bench_median(t, START_RUNS);
    *fastest = t[0];
    return m;
}

void bench_start(void)
{
    const char *cli = getenv("BKFRONT_CLI");
    printf("## process start: wall time of a spawn and wait, %d runs\n\n", START_RUNS);
    if (!cli) {
        printf("(skipped: BKFRONT_CLI does not name the bkfront to time)\n\n");
        return;
    }
    printf("| command | median | fastest |\n|:---|---:|---:|\n");
    const char *what[2][3] = {{cli, "--version", "bkfront --version"},
                              {"/bin/true", NULL, "/bin/true (the spawn itself)"}};
    for (int k = 0; k < 2; k++) {
        double fastest = 0, m = median_start(what[k][0], what[k][1], &fastest);
        if (m < 0) printf("| %s | failed | |\n", what[k][2]);
        else printf("| %s | %.2f ms | %.2f ms |\n", what[k][2], m * 1e3, fastest * 1e3);
    }
    printf("\n");
    fflush(stdout);
}

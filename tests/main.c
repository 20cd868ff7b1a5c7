/* Test runner: each registered test runs in its own child process with a
 * time limit, so a crash, an abort from a sanitizer or a hang is one failure,
 * not the end of the suite.  `run_tests PATTERN` runs the tests whose name
 * contains PATTERN. */
#define _POSIX_C_SOURCE 200809L
#include "harness.h"

#include <stdarg.h>
#include <string.h>
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

int main(int argc, char **argv)
{
    const char *pattern = argc > 1 ? argv[1] : NULL;
    /* BKF_TEST_TIME_LIMIT (seconds) raises the limit for slow runs: under
     * valgrind the extremes matrix takes ~50 times its 13 s. */
    unsigned time_limit = TEST_TIME_LIMIT_S;
    const char *env = getenv("BKF_TEST_TIME_LIMIT");
    if (env) {
        char *end;
        unsigned long v = strtoul(env, &end, 10);
        if (*env && !*end && v > 0 && v < 86400) time_limit = (unsigned)v;
    }
    int passed = 0, failed = 0;
    qsort(tests, test_count, sizeof tests[0], compare_entries);
    for (size_t i = 0; i < test_count; i++) {
        if (pattern && !strstr(tests[i].name, pattern)) continue;
        struct timespec t0, t1;
        clock_gettime(CLOCK_MONOTONIC, &t0);
        fflush(stdout);
        pid_t pid = fork();
        if (pid == 0) {
            alarm(time_limit);
            tests[i].fn();
            fflush(stdout);
            _exit(0);
        }
        int status = 0;
        waitpid(pid, &status, 0);
        clock_gettime(CLOCK_MONOTONIC, &t1);
        double secs = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
        int ok = WIFEXITED(status) && WEXITSTATUS(status) == 0;
        if (ok) {
            passed++;
            printf("ok   %-48s %7.2fs\n", tests[i].name, secs);
        } else {
            failed++;
            if (WIFSIGNALED(status))
                printf("FAIL %-48s (signal %d)\n", tests[i].name, WTERMSIG(status));
            else
                printf("FAIL %-48s\n", tests[i].name);
        }
    }
    printf("%d passed, %d failed\n", passed, failed);
    return failed ? 1 : 0;
}

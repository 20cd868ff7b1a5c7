/* A small test harness: TEST(name) registers a test at load time; the runner
 * (tests/main.c) forks one process per test so a crash or a hang fails that
 * test alone, runs BKF_TEST_JOBS of them at once (default: the online CPUs),
 * prints each test's output whole in the sorted order, and ends with the line
 * "N passed, N failed".  Tests therefore share no files: each makes its own
 * temporary folder.  Running the built CLI: cli_support.h. */
#ifndef BKF_TEST_HARNESS_H
#define BKF_TEST_HARNESS_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

typedef void (*bkf_test_fn)(void);
void bkf_test_register(const char *name, const char *file, bkf_test_fn fn);
void bkf_test_fail(const char *file, int line, const char *fmt, ...)
    __attribute__((format(printf, 3, 4), noreturn));
/* Informational line printed under the test's name (measured numbers). */
void bkf_test_note(const char *fmt, ...) __attribute__((format(printf, 1, 2)));

#define TEST(name)                                                        \
    static void test_##name(void);                                        \
    __attribute__((constructor)) static void register_##name(void) {      \
        bkf_test_register(#name, __FILE__, test_##name);                  \
    }                                                                     \
    static void test_##name(void)

#define CHECK(cond)                                                       \
    do {                                                                  \
        if (!(cond)) bkf_test_fail(__FILE__, __LINE__, "%s", #cond);      \
    } while (0)

#define CHECK_MSG(cond, ...)                                              \
    do {                                                                  \
        if (!(cond)) bkf_test_fail(__FILE__, __LINE__, __VA_ARGS__);      \
    } while (0)

/* |got - want| <= abs_tol + rel_tol |want| */
#define CHECK_CLOSE(got, want, rel_tol, abs_tol)                          \
    do {                                                                  \
        double g_ = (got), w_ = (want);                                   \
        double d_ = fabs(g_ - w_);                                        \
        if (!(d_ <= (abs_tol) + (rel_tol) * fabs(w_)))                    \
            bkf_test_fail(__FILE__, __LINE__,                             \
                          "%s = %.17g, want %s = %.17g (diff %.3g)",      \
                          #got, g_, #want, w_, d_);                       \
    } while (0)

#define CHECK_STATUS(expr, want)                                          \
    do {                                                                  \
        int s_ = (expr);                                                  \
        if (s_ != (want))                                                 \
            bkf_test_fail(__FILE__, __LINE__, "%s returned %d, want %d",  \
                          #expr, s_, (int)(want));                        \
    } while (0)

#endif

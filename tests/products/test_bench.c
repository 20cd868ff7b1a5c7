/* The work-precision product through the library alone. */
#define _POSIX_C_SOURCE 200809L
#include "harness.h"

#include <string.h>

#include "bkfront/bench.h"

TEST(bench_refuses_bad_input)
{
    bkf_error e = {0};
    CHECK(bkf_bench_run((bkf_bench_product)7, 1, NULL, &e) == BKF_EINPUT);
    CHECK(strstr(e.message, "period, speeds, pde, all, box") != NULL);
    CHECK(bkf_bench_run(BKF_BENCH_PERIOD, 1, NULL, &e) == BKF_EINPUT);
}

TEST(bench_period_rows_meet_their_tolerance)
{
    /* Every shooting row's achieved error against the reference (published
     * T(1, 0), or the other stepper at tol 1e-13) is within 10 tol. */
    char *data = NULL;
    size_t size = 0;
    FILE *f = open_memstream(&data, &size);
    CHECK(f != NULL);
    size_t ncol;
    const bkf_io_column *cols = bkf_bench_columns(&ncol);
    bkf_error e;
    bkf_io_table *t = bkf_io_table_alloc(f, BKF_IO_TSV, cols, ncol, &e);
    CHECK(t != NULL);
    CHECK_STATUS(bkf_bench_run(BKF_BENCH_PERIOD, 1, t, &e), BKF_OK);
    CHECK_STATUS(bkf_io_table_finish(t, &e), BKF_OK);
    bkf_io_table_free(t);
    fclose(f);
    size_t rows = 0;
    for (char *line = strtok(data, "\n"); line; line = strtok(NULL, "\n")) {
        char method[32], status[16];
        double tol, N, error;
        if (sscanf(line, "period\t%*[^\t]\t%31[^\t]\t%lf\t%lf\t%lf\t%*s\t%*s\t%*s\t%15s", method,
                   &tol, &N, &error, status) != 5)
            continue;
        if (strcmp(method, "rk8pd") && strcmp(method, "bsimp")) continue;
        if (strcmp(status, "ok")) continue;
        rows++;
        CHECK_MSG(error <= 10 * tol, "%s at tol %g: error %g", method, tol, error);
    }
    free(data);
    CHECK(rows >= 4);
}

/* The speed check through the library (bkf_check_*): its verdict rule on
 * synthetic measurements, its refusals, cancellation and early stops, and
 * the same verdicts as `bkfront check` from a C program that links the
 * library alone (docs/examples/check_paper.c). */
#define _POSIX_C_SOURCE 200809L
#include "harness.h"

#include <string.h>
#include <sys/wait.h>

#include "bkfront/check.h"
#include "bkfront/model.h"

#ifndef BKF_CLI_PATH
#error "BKF_CLI_PATH (the built bkfront binary) is defined by the Makefile for tests"
#endif
#ifndef BKF_EXAMPLES_DIR
#error "BKF_EXAMPLES_DIR (the built docs/examples programs) is defined by the Makefile for tests"
#endif

/* ------------------------------------------------------------- verdicts */

TEST(check_judge_each_branch)
{
    int st = -1;
    /* stable: count kept from n on, deviation not growing */
    CHECK(bkf_check_judge(4, 0, 1, 4, 1e-5, 1.5e-5, 2e-7, 1e-6, &st) == BKF_CHECK_AGREES && st == 1);
    CHECK(bkf_check_judge(4, 0, 1, 4, 1e-5, 1.5e-5, -1e-6, 1e-6, &st) == BKF_CHECK_AGREES);
    CHECK(bkf_check_judge(4, 0, 1, 4, 1e-5, 1.5e-5, 3e-6, 1e-6, &st) == BKF_CHECK_DISAGREES &&
          st == 1);
    /* stable but nothing measured: not an agreement */
    CHECK(bkf_check_judge(4, 0, 1, 4, 1e-5, 1.5e-5, NAN, 1e-6, &st) == BKF_CHECK_DISAGREES);
    /* each way of not keeping count and shape */
    CHECK(bkf_check_judge(4, 1, 1, 4, 1e-5, 1.5e-5, 0, 1e-6, &st) == BKF_CHECK_UNSTABLE && st == 0);
    CHECK(bkf_check_judge(4, 0, 0, 4, 1e-5, 1.5e-5, 0, 1e-6, &st) == BKF_CHECK_UNSTABLE);
    CHECK(bkf_check_judge(4, 0, 1, 3, 1e-5, 1.5e-5, 0, 1e-6, &st) == BKF_CHECK_UNSTABLE);
    CHECK(bkf_check_judge(4, 0, 1, 4, 1e-5, 2.1e-5, 0, 1e-6, &st) == BKF_CHECK_UNSTABLE);
    CHECK(bkf_check_judge(4, 0, 1, 4, 9e-3, 1.1e-2, 0, 1e-6, &st) == BKF_CHECK_UNSTABLE);
    CHECK(bkf_check_judge(4, 0, 1, 4, 1e-5, NAN, 0, 1e-6, &st) == BKF_CHECK_UNSTABLE);
    CHECK(bkf_check_judge(4, 0, 1, 4, 1e-5, 1.5e-5, 0, 1e-6, NULL) == BKF_CHECK_AGREES);
    CHECK(strcmp(bkf_check_verdict_name(BKF_CHECK_UNRESOLVED), "unresolved") == 0);
    CHECK(strcmp(bkf_check_grid_name(BKF_CHECK_GRID_MAPPED), "mapped") == 0);
}

/* ------------------------------------------------------------- refusals */

typedef struct {
    size_t rows, begun;
    bkf_check_row first;
    volatile sig_atomic_t *cancel; /* raised by the progress callback when set */
    int stop_after;                /* the row visitor returns nonzero at this row */
} counter;

static int count_begin(const bkf_check_info *info, void *data)
{
    (void)info;
    ((counter *)data)->begun++;
    return 0;
}

static int count_row(const bkf_check_row *row, void *data)
{
    counter *c = data;
    if (c->rows++ == 0) c->first = *row;
    return c->stop_after && (int)c->rows >= c->stop_after;
}

static void raise_cancel(double fraction, void *data)
{
    counter *c = data;
    if (c->cancel && fraction > 0) *c->cancel = 1;
}

static void expect_refused(const bkf_model_params *m, const bkf_check_options *o,
                           const char *name, const char *range)
{
    counter c = {0};
    bkf_check_hooks h = {.begin = count_begin, .row = count_row, .data = &c};
    bkf_error err = {0};
    int s = bkf_check_run(m, o, &h, &err);
    CHECK_MSG(s == BKF_EINPUT, "%s: status %d (%s)", name, s, err.message);
    CHECK_MSG(strstr(err.message, name) && strstr(err.message, range),
              "'%s' or '%s' not in: %s", name, range, err.message);
    CHECK(c.begun == 0 && c.rows == 0);
    CHECK_STATUS(bkf_check_validate(m, o, NULL), BKF_EINPUT);
}

TEST(check_refuses_bad_options)
{
    bkf_model_params m = bkf_model_params_paper();
    bkf_check_options d = bkf_check_options_default(), o;
    CHECK_STATUS(bkf_check_validate(&m, &d, NULL), BKF_OK);
#define BAD(field, value, name, range) \
    (o = d, o.field = value, expect_refused(&m, &o, name, range))
    BAD(points, 16, "points", "[32, 1048576]");
    BAD(rel_tol, 0, "rel_tol", "(0, 1)");
    BAD(perturb, 1, "perturb", "[0, 0.1]");
    BAD(N_max, 256, "N_max", "[N = 512,");
    BAD(N, 513, "N", "even integer in [8,");
    BAD(tmax, -5, "tmax", "(0, 1e+06]");
    BAD(tol, 1, "tol", "[1e-13, 0.01]");
    BAD(mapped_tol, 1e-20, "mapped_tol", "[1e-13, 0.01]");
    BAD(resolution, 2, "resolution", "[1e-16, 1]");
    BAD(filter, -1, "filter", "[0, 1000]");
    BAD(n, 200000, "n", "[1, 100000]");
    BAD(grid, (bkf_check_grid)7, "grid", "bkf_check_grid");
    o = d;
    o.grid = BKF_CHECK_GRID_MAPPED;
    o.frame = BKF_CHECK_FRAME_LAB;
    expect_refused(&m, &o, "frame", "grid mapped");
#undef BAD
    bkf_model_params b = m;
    b.nu = 1;
    expect_refused(&b, &d, "nu", "(-1, 1)");
    b = m;
    b.gamma = 0;
    expect_refused(&b, &d, "gamma", "[1e-06, 1e+06]");
    b = m;
    b.c = -0.1;
    expect_refused(&b, &d, "c", ">= 0");
}

/* --------------------------------------------------- stops and outcomes */

TEST(check_cancel_flag_stops_the_run)
{
    bkf_model_params m = bkf_model_params_paper();
    bkf_check_options o = bkf_check_options_default();
    o.n = 5;
    volatile sig_atomic_t flag = 0;
    counter c = {.cancel = &flag};
    bkf_check_hooks h = {.row = count_row, .progress = raise_cancel, .data = &c, .cancel = &flag};
    bkf_error err;
    CHECK_STATUS(bkf_check_run(&m, &o, &h, &err), BKF_ECANCELED);
    CHECK_MSG(c.rows == 0, "%zu rows after a cancel inside the first run", c.rows);
    /* raised before the run: not one root */
    flag = 1;
    c.cancel = NULL;
    o.n = 0;
    CHECK_STATUS(bkf_check_run(&m, &o, &h, &err), BKF_ECANCELED);
    CHECK(c.rows == 0);
}

TEST(check_row_visitor_stops_the_run)
{
    bkf_model_params m = bkf_model_params_paper();
    bkf_check_options o = bkf_check_options_default();
    counter c = {.stop_after = 1};
    bkf_check_hooks h = {.begin = count_begin, .row = count_row, .data = &c};
    bkf_error err;
    CHECK_STATUS(bkf_check_run(&m, &o, &h, &err), BKF_OK);
    CHECK(c.begun == 1 && c.rows == 1);
    CHECK(c.first.n == 1 && c.first.root == 1 && c.first.grid == BKF_CHECK_GRID_UNIFORM);
}

/* Not a verdict: a wave the grid cap cannot resolve (n = 5 needs N = 1024)
 * and an adapted-grid run over its step budget are unresolved, with the
 * reason. */
TEST(check_unresolved_reasons)
{
    bkf_model_params m = bkf_model_params_paper();
    bkf_check_options o = bkf_check_options_default();
    o.n = 5;
    o.grid = BKF_CHECK_GRID_UNIFORM;
    o.N_max = 512;
    counter c = {0};
    bkf_check_hooks h = {.row = count_row, .data = &c};
    bkf_error err;
    CHECK_STATUS(bkf_check_run(&m, &o, &h, &err), BKF_OK);
    CHECK(c.rows == 1 && c.first.verdict == BKF_CHECK_UNRESOLVED && c.first.reason == BKF_ETOL);
    CHECK(c.first.N == 0 && c.first.tail > o.resolution && isnan(c.first.v_meas));

    o = bkf_check_options_default();
    o.n = 10;
    o.grid = BKF_CHECK_GRID_MAPPED;
    o.mapped_max_steps = 3;
    c = (counter){0};
    CHECK_STATUS(bkf_check_run(&m, &o, &h, &err), BKF_OK);
    CHECK(c.rows == 1 && c.first.verdict == BKF_CHECK_UNRESOLVED);
    CHECK_MSG(c.first.reason == BKF_EBUDGET, "reason %d", c.first.reason);
    CHECK(c.first.grid == BKF_CHECK_GRID_MAPPED && c.first.N == 10 * o.points);
}

/* ------------------------------------------- the library vs the executable */

#define MAX_ROWS 64

typedef struct {
    size_t n, root;
    char verdict[16];
} verdict_row;

/* Runs `command` (its stdout), keeps the columns n, root and verdict of a
 * table (TSV with a header; '#' lines skipped); returns the rows read. */
static size_t read_verdicts(const char *command, verdict_row *rows, int *exit_code)
{
    fflush(stdout);
    FILE *f = popen(command, "r");
    CHECK_MSG(f, "cannot run %s", command);
    char line[8192];
    int col_n = -1, col_root = -1, col_verdict = -1;
    size_t count = 0;
    while (fgets(line, sizeof line, f)) {
        if (line[0] == '#') continue;
        line[strcspn(line, "\n")] = '\0';
        char *fields[64];
        int nf = 0;
        for (char *p = line, *tab; nf < 64; p = tab + 1) {
            fields[nf++] = p;
            if (!(tab = strchr(p, '\t'))) break;
            *tab = '\0';
        }
        if (col_n < 0) {
            for (int i = 0; i < nf; i++) {
                if (strcmp(fields[i], "n") == 0) col_n = i;
                if (strcmp(fields[i], "root") == 0) col_root = i;
                if (strcmp(fields[i], "verdict") == 0) col_verdict = i;
            }
            CHECK_MSG(col_n >= 0 && col_root >= 0 && col_verdict >= 0, "%s: no header", command);
            continue;
        }
        CHECK(count < MAX_ROWS && nf > col_verdict && nf > col_n && nf > col_root);
        rows[count].n = strtoul(fields[col_n], NULL, 10);
        rows[count].root = strtoul(fields[col_root], NULL, 10);
        snprintf(rows[count].verdict, sizeof rows[count].verdict, "%s", fields[col_verdict]);
        count++;
    }
    int status = pclose(f);
    *exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return count;
}

/* The deliverable: a C program linking only libbkfront gets the verdicts of
 * `bkfront check` at the paper's parameters.  n = 2 (unstable), 5
 * (agrees, N = 1024) and 10 (the adapted grid under the default grid
 * choice); the whole check takes ~8 s. */
TEST(check_example_and_cli_verdicts_agree)
{
    verdict_row lib[MAX_ROWS], cli[MAX_ROWS];
    int code;
    size_t nl = read_verdicts(BKF_EXAMPLES_DIR "/check_paper 2 5 10", lib, &code);
    CHECK_MSG(code == 0, "check_paper exit %d", code);
    const char *const ns[] = {"2", "5", "10"};
    size_t nc = 0;
    for (size_t i = 0; i < 3; i++) {
        char cmd[512];
        snprintf(cmd, sizeof cmd, "'%s' check --n %s --no-progress", BKF_CLI_PATH, ns[i]);
        nc += read_verdicts(cmd, cli + nc, &code);
        CHECK_MSG(code == 0, "%s: exit %d", cmd, code);
    }
    CHECK_MSG(nl == 3 && nc == 3, "%zu rows from the library, %zu from the CLI", nl, nc);
    for (size_t i = 0; i < nl; i++) {
        CHECK(lib[i].n == cli[i].n && lib[i].root == cli[i].root);
        CHECK_MSG(strcmp(lib[i].verdict, cli[i].verdict) == 0, "n = %zu root %zu: %s vs %s",
                  lib[i].n, lib[i].root, lib[i].verdict, cli[i].verdict);
        bkf_test_note("n = %zu, root %zu: %s", lib[i].n, lib[i].root, lib[i].verdict);
    }
    /* and the README's table at the paper's parameters: n = 2 unstable,
     * n = 5 and 10 agree (n = 10 also on the uniform grid of 2^14 points) */
    CHECK(strcmp(lib[0].verdict, "unstable") == 0);
    CHECK(strcmp(lib[1].verdict, "agrees") == 0 && strcmp(lib[2].verdict, "agrees") == 0);
}

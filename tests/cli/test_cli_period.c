/* `bkfront period` as a user sees it: the built binary (BKF_CLI_PATH), its
 * stdout, stderr and exit status. */
#define _POSIX_C_SOURCE 200809L
#include "harness.h"
#include "cli_support.h"

#include <fcntl.h>
#include <stdarg.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>
#include "bkfront/period.h"

/* In test_io.c. */
int bkf_test_json_valid(const char *text);

typedef bkf_cli_result run_result;
#define RUN(...) BKF_CLI(__VA_ARGS__)
#define run_free bkf_cli_result_free
#define check_bad_input(r, names, what) bkf_cli_expect_bad_input((r), "period", (names), (what))
#define tsv_field(tsv, row, column, value) bkf_tsv_cell((tsv), (row), (column), (value), NULL, 0)
#define tsv_text(tsv, row, column, buf, size) bkf_tsv_cell((tsv), (row), (column), NULL, (buf), (size))

static const char *const expected_columns =
    "mu\tnu\tT\tT_err\tT_asym\tT_asym2\txmax\txmin\tmultiplier\tlog_multiplier\tsteps\t"
    "rhs_calls\tnewton_iterations\tstepper\tmodel\n";

TEST(cli_period_rejects_nu_outside_active_range)
{
    check_bad_input(RUN("period", "--mu", "1", "--nu", "1"), "nu", "--nu 1");
    check_bad_input(RUN("period", "--mu", "1", "--nu", "-1.5"), "nu", "--nu -1.5");
    check_bad_input(RUN("period", "--mu", "1", "--nu", "-1:0:3"), "nu", "--nu -1:0:3");
    run_result r = RUN("period", "--mu", "1", "--nu", "1");
    CHECK_MSG(strstr(r.err, "no limit cycle") && strstr(r.err, "continuous slip"), "%s", r.err);
    run_free(&r);
}

TEST(cli_period_rejects_bad_mu)
{
    check_bad_input(RUN("period", "--mu", "0", "--nu", "0"), "--mu", "--mu 0");
    check_bad_input(RUN("period", "--mu", "-1", "--nu", "0"), "--mu", "--mu -1");
    check_bad_input(RUN("period", "--mu", "nan", "--nu", "0"), "--mu", "--mu nan");
    check_bad_input(RUN("period", "--mu", "1e", "--nu", "0"), "--mu", "--mu 1e");
    check_bad_input(RUN("period", "--mu", "inf", "--nu", "0"), "--mu", "--mu inf");
    check_bad_input(RUN("period", "--mu", "0x1p0", "--nu", "0"), "--mu", "--mu 0x1p0");
    check_bad_input(RUN("period", "--mu", "2e6", "--nu", "0"), "--mu", "--mu 2e6");
    check_bad_input(RUN("period", "--mu", "1:2e6:3", "--nu", "0"), "--mu", "--mu 1:2e6:3");
    check_bad_input(RUN("period", "--mu", "1:2", "--nu", "0"), "--mu", "--mu 1:2");
    check_bad_input(RUN("period", "--mu", "0:1:3", "--log", "--nu", "0"), "--mu", "--log 0:1:3");
    check_bad_input(RUN("period", "--mu", "", "--nu", "0"), "--mu", "--mu ''");
}

TEST(cli_period_rejects_bad_tol)
{
    check_bad_input(RUN("period", "--mu", "1", "--nu", "0", "--tol", "1"), "--tol", "--tol 1");
    check_bad_input(RUN("period", "--mu", "1", "--nu", "0", "--tol", "1e-20"), "--tol",
                    "--tol 1e-20");
    check_bad_input(RUN("period", "--mu", "1", "--nu", "0", "--tol", "-1e-3"), "--tol",
                    "--tol -1e-3");
    check_bad_input(RUN("period", "--mu", "1", "--nu", "0", "--tol", "nan"), "--tol", "--tol nan");
}

TEST(cli_period_rejects_bad_options)
{
    check_bad_input(RUN("period", "--mu", "1", "--nu", "0", "--bogus"), "--bogus", "--bogus");
    check_bad_input(RUN("period", "--nu", "0"), "--mu", "missing --mu");
    check_bad_input(RUN("period", "--mu", "1"), "--nu", "missing --nu");
    check_bad_input(RUN("period", "--mu", "1", "--nu"), "--nu", "--nu without a value");
    check_bad_input(RUN("period", "--mu", "1", "--mu", "2", "--nu", "0"), "--mu", "--mu twice");
    check_bad_input(RUN("period", "--mu", "1", "--nu", "0", "extra"), "extra", "positional");
    check_bad_input(RUN("period", "--mu", "1", "--nu", "0", "--format", "csv"), "--format",
                    "--format csv");
    check_bad_input(RUN("period", "--mu", "1", "--nu", "0", "--stepper", "rk4"), "--stepper",
                    "--stepper rk4");
    check_bad_input(RUN("period", "--mu", "1", "--nu", "-0.5:0.5:3", "--log"), "--log",
                    "--log with a nu range");
    check_bad_input(RUN("period", "--mu", "1", "--nu", "0", "--continue", "mu"), "--mu",
                    "--continue mu without a range");
    check_bad_input(RUN("period", "--mu", "1:2:3", "--nu", "0:0.5:3", "--continue", "mu"),
                    "--nu", "--continue mu with a nu range");
    check_bad_input(RUN("period", "--mu", "1", "--nu", "0", "--continue", "tau"), "--continue",
                    "--continue tau");
    check_bad_input(RUN("period", "--mu", "1", "--nu", "0", "--out", "/nonexistent_bkf/x.tsv"),
                    "--out", "--out in a missing directory");
}

TEST(cli_usage_help_and_version)
{
    run_result r = RUN("period", "--help");
    CHECK_MSG(r.code == 0 && r.err[0] == '\0', "exit %d: %s", r.code, r.err);
    const char *needles[] = {"--mu", "--nu", "--tol", "--log", "--continue", "--stepper",
                             "--format", "--out", "1e-10", "T_err", "newton_iterations",
                             "stepper"};
    for (size_t i = 0; i < sizeof needles / sizeof needles[0]; i++)
        CHECK_MSG(strstr(r.out, needles[i]), "help lacks %s", needles[i]);
    char *period_help = r.out;
    free(r.err);

    r = RUN("help", "period");
    CHECK(r.code == 0 && strcmp(r.out, period_help) == 0);
    run_free(&r);
    free(period_help);

    r = RUN("--help");
    CHECK(r.code == 0 && strstr(r.out, "period") && strstr(r.out, "usage"));
    run_free(&r);

    r = RUN("--version");
    CHECK(r.code == 0 && strncmp(r.out, "bkfront ", 8) == 0 && bkf_count_lines(r.out) == 1);
    run_free(&r);

    r = RUN("frobnicate");
    CHECK_MSG(r.code == 2 && r.out[0] == '\0' && bkf_count_lines(r.err) == 1 &&
                  strstr(r.err, "frobnicate"),
              "exit %d: %s", r.code, r.err);
    run_free(&r);

    r = RUN("help", "frobnicate");
    CHECK(r.code == 2 && r.out[0] == '\0' && bkf_count_lines(r.err) == 1);
    run_free(&r);

    const char *none[] = {NULL};
    r = bkf_cli_run(none, NULL);
    CHECK(r.code == 2 && r.out[0] == '\0' && strstr(r.err, "usage"));
    run_free(&r);
}

TEST(cli_period_published_value)
{
    run_result r = RUN("period", "--mu", "1", "--nu", "0");
    CHECK_MSG(r.code == 0, "exit %d: %s", r.code, r.err);
    CHECK_MSG(r.err[0] == '\0', "stderr: %s", r.err);
    CHECK_MSG(strstr(r.out, expected_columns), "no header line in:\n%s", r.out);
    CHECK(strstr(r.out, "# command: bkfront period --mu 1 --nu 0\n"));
    double mu, nu, T, T_err, T_asym, T_asym2;
    CHECK(tsv_field(r.out, 0, "mu", &mu) && mu == 1);
    CHECK(tsv_field(r.out, 0, "nu", &nu) && nu == 0);
    CHECK(tsv_field(r.out, 0, "T", &T));
    CHECK_CLOSE(T, 6.663286859323130, 1e-9, 0);
    CHECK(tsv_field(r.out, 0, "T_err", &T_err) && T_err >= 0 && T_err < 1e-8);
    CHECK(tsv_field(r.out, 0, "T_asym", &T_asym));
    CHECK_CLOSE(T_asym, 3 - 2 * log(2.0), 1e-15, 0);
    CHECK(tsv_field(r.out, 0, "T_asym2", &T_asym2) && isfinite(T_asym2));
    CHECK(!tsv_field(r.out, 1, "T", &T)); /* exactly one row */
    bkf_test_note("T(1, 0) = %.17g, T_err = %.3g", T, T_err);
    run_free(&r);
}

TEST(cli_period_grid_mu_fastest)
{
    run_result r = RUN("period", "--mu", "0.5:1:2", "--nu", "-0.2:0.2:2", "--tol", "1e-8");
    CHECK_MSG(r.code == 0, "exit %d: %s", r.code, r.err);
    double want_mu[] = {0.5, 1, 0.5, 1}, want_nu[] = {-0.2, -0.2, 0.2, 0.2};
    for (int i = 0; i < 4; i++) {
        double mu, nu, T;
        CHECK(tsv_field(r.out, i, "mu", &mu) && mu == want_mu[i]);
        CHECK(tsv_field(r.out, i, "nu", &nu) && nu == want_nu[i]);
        CHECK(tsv_field(r.out, i, "T", &T) && T > 6 && T < 8);
    }
    CHECK(!tsv_field(r.out, 4, "mu", &(double){0}));
    run_free(&r);
}

TEST(cli_period_json)
{
    run_result r = RUN("period", "--mu", "1", "--nu", "0", "--format", "json");
    CHECK_MSG(r.code == 0, "exit %d: %s", r.code, r.err);
    CHECK(r.out[0] == '{');
    CHECK(strstr(r.out, "\"rows\""));
    CHECK(strstr(r.out, "\"columns\": [\"mu\", \"nu\", \"T\", \"T_err\""));
    CHECK_MSG(bkf_test_json_valid(r.out), "invalid JSON:\n%s", r.out);
    const char *t = strstr(r.out, "\"T\": ");
    CHECK(t);
    CHECK_CLOSE(strtod(t + 5, NULL), 6.663286859323130, 1e-9, 0);
    run_free(&r);
}

TEST(cli_period_out_file_is_atomic)
{
    char dir[] = "/tmp/bkf_cli_out_XXXXXX";
    CHECK(mkdtemp(dir));
    char path[256];
    snprintf(path, sizeof path, "%s/period.tsv", dir);

    run_result r = RUN("period", "--mu", "1", "--nu", "0", "--out", path);
    CHECK_MSG(r.code == 0, "exit %d: %s", r.code, r.err);
    CHECK_MSG(r.out[0] == '\0' && r.err[0] == '\0', "stdout: %s stderr: %s", r.out, r.err);
    run_free(&r);
    char *text = bkf_cli_read_file(path);
    CHECK(text);
    CHECK(strstr(text, expected_columns));
    double T;
    CHECK(tsv_field(text, 0, "T", &T));
    CHECK_CLOSE(T, 6.663286859323130, 1e-9, 0);

    /* Bad input after --out: the old file stays, no temporary is left. */
    r = RUN("period", "--out", path, "--mu", "1", "--nu", "2");
    CHECK(r.code == 2 && r.out[0] == '\0');
    run_free(&r);
    char *again = bkf_cli_read_file(path);
    CHECK(again);
    CHECK(strcmp(text, again) == 0);
    free(again);
    free(text);

    char cmd[512];
    snprintf(cmd, sizeof cmd, "ls -A '%s' | wc -l", dir);
    FILE *p = popen(cmd, "r");
    int n = -1;
    CHECK(p && fscanf(p, "%d", &n) == 1);
    pclose(p);
    CHECK_MSG(n == 1, "%d files in %s", n, dir);
    unlink(path);
    rmdir(dir);
}

/* The rows of a --continue run: the parameter runs from A to B,
 * monotonically, the other stays fixed, and the ends agree with point solves. */
static void check_branch(const char *along, const char *range, const char *fixed,
                         double from, double to)
{
    int mu_along = strcmp(along, "mu") == 0;
    run_result r = mu_along ? RUN("period", "--mu", range, "--nu", fixed, "--continue", along)
                            : RUN("period", "--mu", fixed, "--nu", range, "--continue", along);
    CHECK_MSG(r.code == 0, "exit %d: %s", r.code, r.err);
    const char *p_name = mu_along ? "mu" : "nu", *o_name = mu_along ? "nu" : "mu";
    double fixed_value = strtod(fixed, NULL), prev = 0, p, o, T = 0, T_first = 0;
    int rows = 0;
    for (; tsv_field(r.out, rows, p_name, &p); rows++) {
        CHECK(tsv_field(r.out, rows, o_name, &o) && o == fixed_value);
        CHECK(tsv_field(r.out, rows, "T", &T) && T > 0);
        if (rows == 0) {
            /* within rounding: mu is continued in ln mu */
            CHECK_CLOSE(p, from, 1e-15, 0);
            T_first = T;
        } else
            CHECK_MSG((to > from) ? p > prev : p < prev, "%s not monotone at row %d", p_name, rows);
        prev = p;
    }
    CHECK_MSG(rows >= 3, "%d rows", rows);
    CHECK_CLOSE(prev, to, 1e-15, 0);
    bkf_test_note("--continue %s %s: %d rows", along, range, rows);
    run_free(&r);

    char a[32], b[32];
    snprintf(a, sizeof a, "%.17g", from);
    snprintf(b, sizeof b, "%.17g", to);
    double ends[2] = {T_first, T};
    const char *at[2] = {a, b};
    for (int i = 0; i < 2; i++) {
        r = mu_along ? RUN("period", "--mu", at[i], "--nu", fixed)
                     : RUN("period", "--mu", fixed, "--nu", at[i]);
        double T_point;
        CHECK(r.code == 0 && tsv_field(r.out, 0, "T", &T_point));
        CHECK_CLOSE(ends[i], T_point, 1e-9, 0);
        run_free(&r);
    }
}

TEST(cli_period_continue_mu)
{
    check_branch("mu", "0.5:2:3", "0", 0.5, 2);
    check_branch("mu", "20:2:7", "-0.5", 20, 2);
}

TEST(cli_period_continue_nu)
{
    check_branch("nu", "-0.5:0.5:3", "1", -0.5, 0.5);
}

/* --method auto at tol 1e-2 and mu >= 100 answers from a formula, whose
 * value is within its bound of the published / shooting value; a formula
 * forced where its bound fails is a numerical failure; a bad method is bad
 * input. */
TEST(cli_period_method_auto_and_forced)
{
    run_result r = RUN("period", "--mu", "100:1e4:3", "--log", "--nu", "0", "--tol", "1e-2");
    CHECK_MSG(r.code == 0, "exit %d: %s", r.code, r.err);
    for (int i = 0; i < 3; i++) {
        char model[32];
        double rhs, T, T_err;
        CHECK(tsv_text(r.out, i, "model", model, sizeof model));
        CHECK_MSG(strcmp(model, "leading") == 0 || strcmp(model, "asymptotic") == 0, "row %d: %s", i, model);
        CHECK(tsv_field(r.out, i, "rhs_calls", &rhs) && rhs == 0);
        CHECK(tsv_field(r.out, i, "T", &T) && tsv_field(r.out, i, "T_err", &T_err));
        CHECK(T_err > 0 && T_err <= 1e-2 * T);
    }
    run_free(&r);
    /* the published T(1, 0) needs shooting at the default tol */
    r = RUN("period", "--mu", "1", "--nu", "0");
    char model[32];
    CHECK(r.code == 0 && tsv_text(r.out, 0, "model", model, sizeof model));
    CHECK(strcmp(model, "shooting") == 0);
    run_free(&r);
    /* small mu, loose tol: the small-mu formula, against the published value
     * at mu = 1 it is not allowed (bound above 1e-6) */
    r = RUN("period", "--mu", "0.01", "--nu", "0", "--tol", "1e-8");
    double T;
    CHECK(r.code == 0 && tsv_text(r.out, 0, "model", model, sizeof model));
    CHECK(strcmp(model, "asymptotic") == 0);
    CHECK(tsv_field(r.out, 0, "T", &T));
    CHECK_CLOSE(T, 2 * 3.14159265358979323846 * (1 + 1e-4 / 16), 1e-15, 0);
    run_free(&r);
    r = RUN("period", "--mu", "1", "--nu", "0", "--method", "leading", "--tol", "1e-2");
    CHECK_MSG(r.code == 1 && r.out[0] == '\0', "exit %d", r.code);
    CHECK_MSG(strstr(r.err, "bound") && bkf_count_lines(r.err) == 1, "%s", r.err);
    run_free(&r);
    r = RUN("period", "--mu", "1e4", "--nu", "0", "--method", "asymptotic", "--tol", "1e-12");
    CHECK_MSG(r.code == 1 && r.out[0] == '\0', "exit %d", r.code);
    run_free(&r);
    check_bad_input(RUN("period", "--mu", "1", "--nu", "0", "--method", "magic"), "--method",
                    "unknown method");
    check_bad_input(RUN("period", "--mu", "1:2:3", "--nu", "0", "--continue", "mu", "--method",
                        "leading"),
                    "--method", "formula with --continue");
}

/* bkfront bench --quick: the work-precision table, one row per method and
 * setting, every achieved error finite and within 10x of the method's own
 * estimate wherever the estimate is finite (honest estimates). */
TEST(cli_bench_quick_work_precision)
{
    run_result r = RUN("bench", "--quick");
    CHECK_MSG(r.code == 0, "exit %d: %s", r.code, r.err);
    CHECK(strstr(r.out, "product\tcase\tmethod\ttol\tN\terror\testimate\tcpu_seconds\twork\tstatus\n"));
    int rows = 0;
    for (int i = 0; i < 64; i++) {
        double err, est, t;
        if (!tsv_field(r.out, i, "error", &err)) break;
        CHECK(tsv_field(r.out, i, "estimate", &est) && tsv_field(r.out, i, "cpu_seconds", &t));
        CHECK_MSG(isfinite(err) && err >= 0 && t > 0, "row %d: error %g time %g", i, err, t);
        if (isfinite(est)) CHECK_MSG(err <= 10 * est + 1e-15, "row %d: error %g estimate %g", i, err, est);
        rows++;
    }
    CHECK_MSG(rows >= 15, "%d rows", rows);
    run_free(&r);
    run_result b = RUN("bench", "--product", "nothing");
    CHECK_MSG(b.code == 2 && strstr(b.err, "--product") && b.out[0] == 0, "exit %d: %s", b.code, b.err);
    run_free(&b);
}

/* bkfront bench --product box --quick: both methods' ratio summaries, and
 * every point answered at tol 1e-6 within 10x of its own estimate against
 * the other stepper's (or the published) value; the small-mu point near
 * the Hopf point is answered by the formula under auto, with no work. */
TEST(cli_bench_box_quick)
{
    run_result r = RUN("bench", "--product", "box", "--quick");
    CHECK_MSG(r.code == 0, "exit %d: %s", r.code, r.err);
    CHECK(strstr(r.out, "# box, --method shooting: time(tol 1e-12)/time(tol 1e-6) per point") != NULL);
    CHECK(strstr(r.out, "# box, --method auto: time(tol 1e-12)/time(tol 1e-6) per point") != NULL);
    CHECK(strstr(r.out, "box\tmu=0.01,nu=0.9999\tauto(asymptotic)\t9.9999999999999995e-07\tnan\t") != NULL);
    int rows = 0;
    for (int i = 0; i < 64; i++) {
        double err, est, tol, work;
        if (!tsv_field(r.out, i, "tol", &tol)) break;
        rows++;
        if (tol != 1e-6 || !tsv_field(r.out, i, "error", &err) || !isfinite(err)) continue;
        CHECK(tsv_field(r.out, i, "estimate", &est) && tsv_field(r.out, i, "work", &work));
        CHECK_MSG(err <= tol && err <= 10 * est + 1e-15, "row %d: error %g estimate %g", i, err, est);
    }
    CHECK_MSG(rows == 24, "%d rows", rows);
    run_free(&r);
}

/* Issue 14: a comma list is accepted by period as by the other commands, and
 * its rows are those of the single points. */
TEST(cli_period_mu_list_matches_single_points)
{
    run_result l = RUN("period", "--mu", "0.5,5", "--nu", "0");
    run_result a = RUN("period", "--mu", "0.5", "--nu", "0");
    run_result b = RUN("period", "--mu", "5", "--nu", "0");
    CHECK_MSG(l.code == 0 && a.code == 0 && b.code == 0, "%s", l.err);
    double x, y;
    CHECK(tsv_field(l.out, 0, "T", &x) && tsv_field(a.out, 0, "T", &y) && x == y);
    CHECK(tsv_field(l.out, 1, "T", &x) && tsv_field(b.out, 0, "T", &y) && x == y);
    CHECK(tsv_field(l.out, 1, "mu", &x) && x == 5);
    run_free(&l);
    run_free(&a);
    run_free(&b);
}

/* A character device is written directly (it cannot be replaced). */
TEST(cli_period_out_dev_null)
{
    run_result r = RUN("period", "--mu", "1", "--nu", "0", "--out", "/dev/null");
    CHECK_MSG(r.code == 0 && r.out[0] == '\0' && r.err[0] == '\0', "exit %d: %s", r.code, r.err);
    run_free(&r);
}

/* The library's product writes the table the CLI writes, given the same
 * provenance. */
TEST(cli_period_library_matches_cli)
{
    run_result r = RUN("period", "--mu", "1:3:3", "--nu", "-0.5", "--tol", "1e-9");
    CHECK(r.code == 0);
    bkf_period_spec spec = bkf_period_spec_default();
    bkf_error e = {0};
    const bkf_option *mu = bkf_option_find(bkf_period_options, bkf_period_noptions, "mu");
    const bkf_option *nu = bkf_option_find(bkf_period_options, bkf_period_noptions, "nu");
    const bkf_option *tol = bkf_option_find(bkf_period_options, bkf_period_noptions, "tol");
    CHECK_STATUS(bkf_option_apply(mu, &spec, "1:3:3", "", &e), BKF_OK);
    CHECK_STATUS(bkf_option_apply(nu, &spec, "-0.5", "", &e), BKF_OK);
    CHECK_STATUS(bkf_option_apply(tol, &spec, "1e-9", "", &e), BKF_OK);
    char *text = NULL;
    size_t size = 0;
    FILE *f = open_memstream(&text, &size);
    bkf_provenance prov = {"bkfront 0.1.0", "bkfront period --mu 1:3:3 --nu -0.5 --tol 1e-9"};
    CHECK_STATUS(bkf_period_write(&spec, f, BKF_IO_TSV, &prov, &e), BKF_OK);
    fclose(f);
    CHECK_MSG(strcmp(text, r.out) == 0, "library:\n%s\nCLI:\n%s", text, r.out);
    free(text);
    bkf_period_spec_free(&spec);
    run_free(&r);
}

/* A branch stuck in the canard explosion at the box's edge (mu 35.3659,
 * nu 0.9999, approached from the relaxation side, where no row steps over
 * it) fails within seconds: exit 1, nothing on stdout, one line naming mu
 * and nu (the library's branch_hop; it crept for minutes before). */
TEST(cli_period_continue_stuck_in_the_canard_names_mu_and_nu)
{
    run_result r = RUN("period", "--mu", "36:35:2", "--nu", "0.9999", "--continue", "mu");
    CHECK_MSG(r.code == 1 && r.out[0] == '\0' && bkf_count_lines(r.err) == 1, "exit %d: %s", r.code, r.err);
    CHECK_MSG(strstr(r.err, "stuck at mu = 35.36") && strstr(r.err, "nu = 0.9999"), "%s", r.err);
    run_free(&r);
}

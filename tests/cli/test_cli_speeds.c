/* `bkfront speeds` and `bkfront branch` as a user sees them: the built
 * binary (BKF_CLI_PATH), its stdout, stderr and exit status. */
#define _POSIX_C_SOURCE 200809L
#include "harness.h"
#include "cli_support.h"

#include <fcntl.h>
#include <math.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "bkfront/asymptotics.h"
#include "bkfront/speeds.h"

/* In test_io.c. */
int bkf_test_json_valid(const char *text);

typedef bkf_cli_result run_result;
#define RUN(...) BKF_CLI(__VA_ARGS__)
#define run_free bkf_cli_result_free
#define bad_input bkf_cli_expect_bad_input
#define field bkf_tsv_cell

static int rows(const char *tsv)
{
    int n = 0;
    while (field(tsv, n, "n", NULL, NULL, 0)) n++;
    return n;
}

static const char *const speeds_header =
    "n\tv\tmu\tT\tT_err\tv_over_c\twavelength\tperiod_fixed\tv_asym\tdeviation\tv_err\t"
    "model\tresidual\tslope\tflags\n";

TEST(cli_speeds_paper_table)
{
    run_result r = RUN("speeds", "--gamma", "2", "--c", "0.3", "--nu", "-0.96", "--S", "20");
    CHECK_MSG(r.code == 0 && r.err[0] == '\0', "exit %d: %s", r.code, r.err);
    CHECK_MSG(strstr(r.out, speeds_header), "no header in:\n%s", r.out);
    CHECK(strstr(r.out, "# n_max 12; n_bound = S/(k c gamma) = 12.28994"));
    CHECK(strstr(r.out, "# command: bkfront speeds --gamma 2 --c 0.3 --nu -0.96 --S 20\n"));
    CHECK(rows(r.out) == 12);
    /* the same numbers as the library, bit for bit (%.17g) */
    bkf_model_params p = {2, 0.3, -0.96, 20, 0, BKF_MODEL_CONTINUUM};
    bkf_speeds_table t;
    bkf_error e;
    CHECK(bkf_speeds_find(&p, NULL, &t, &e) == BKF_OK && t.count == 12);
    for (int i = 0; i < 12; i++) {
        double n, v, res, verr;
        CHECK(field(r.out, i, "n", &n, NULL, 0) && n == i + 1);
        CHECK(field(r.out, i, "v", &v, NULL, 0) && v == t.roots[i].v);
        CHECK(field(r.out, i, "residual", &res, NULL, 0) && fabs(res) <= 1e-10);
        CHECK(field(r.out, i, "v_err", &verr, NULL, 0) && verr <= 1e-10 * v);
        char flags[32];
        CHECK(field(r.out, i, "flags", NULL, flags, sizeof flags) && flags[0] == '\0');
    }
    bkf_speeds_table_free(&t);
    run_free(&r);
}

TEST(cli_speeds_n_and_nmax)
{
    run_result r = RUN("speeds", "--gamma", "2", "--c", "0.3", "--nu", "-0.96", "--S", "20", "--n",
                       "7", "--tol", "1e-8");
    CHECK_MSG(r.code == 0, "exit %d: %s", r.code, r.err);
    double n, v;
    CHECK(rows(r.out) == 1 && field(r.out, 0, "n", &n, NULL, 0) && n == 7);
    CHECK(field(r.out, 0, "v", &v, NULL, 0));
    CHECK_CLOSE(v, 0.34755127499805, 1e-8, 0); /* asked: 1e-8 relative */
    run_free(&r);

    r = RUN("speeds", "--gamma", "2", "--c", "0.3", "--nu", "-0.96", "--S", "20", "--nmax", "3");
    CHECK(r.code == 0 && rows(r.out) == 3);
    run_free(&r);

    /* three roots for one n, the middle one rising */
    r = RUN("speeds", "--gamma", "1.5", "--c", "0.3", "--nu", "-0.96", "--S", "20", "--n", "6");
    CHECK(r.code == 0 && rows(r.out) == 3);
    double slope;
    CHECK(field(r.out, 1, "slope", &slope, NULL, 0) && slope > 0);
    run_free(&r);
}

TEST(cli_speeds_no_front_is_an_empty_table)
{
    run_result r = RUN("speeds", "--gamma", "2", "--c", "0.3", "--nu", "-0.96", "--S", "1");
    CHECK_MSG(r.code == 0 && r.err[0] == '\0', "exit %d: %s", r.code, r.err);
    CHECK(strstr(r.out, speeds_header) && rows(r.out) == 0);
    CHECK(strstr(r.out, "# note: no front: S = 1 <= k(nu) c gamma"));
    run_free(&r);

    r = RUN("speeds", "--gamma", "2", "--c", "0.3", "--nu", "-0.96", "--S", "1", "--format", "json");
    CHECK(r.code == 0 && bkf_test_json_valid(r.out) && strstr(r.out, "\"rows\": []"));
    run_free(&r);
}

TEST(cli_speeds_c0_closed_form_and_json)
{
    run_result r = RUN("speeds", "--gamma", "2", "--c", "0", "--nu", "-0.96", "--S", "20", "--format",
                       "json");
    CHECK_MSG(r.code == 0, "exit %d: %s", r.code, r.err);
    CHECK_MSG(bkf_test_json_valid(r.out), "invalid JSON:\n%s", r.out);
    CHECK(strstr(r.out, "\"v_over_c\": null"));
    CHECK(strstr(r.out, "every n has a front"));
    run_free(&r);

    r = RUN("speeds", "--gamma", "2", "--c", "0", "--nu", "-0.96", "--S", "20");
    CHECK(r.code == 0 && rows(r.out) == BKF_SPEEDS_ROWS_C0);
    double T, v;
    CHECK(field(r.out, 3, "T", &T, NULL, 0) && field(r.out, 3, "v", &v, NULL, 0));
    CHECK_CLOSE(v, 20.0 / (4.0 * T), 1e-15, 0);
    run_free(&r);
}

TEST(cli_speeds_nu_outside_active_range_has_no_fronts)
{
    bad_input(RUN("speeds", "--gamma", "2", "--c", "0.3", "--nu", "1", "--S", "20"), "speeds",
              "no fronts", "--nu 1");
    bad_input(RUN("speeds", "--gamma", "2", "--c", "0.3", "--nu", "-1.2", "--S", "20"), "speeds",
              "--nu", "--nu -1.2");
}

TEST(cli_speeds_rejects_bad_input)
{
    bad_input(RUN("speeds", "--gamma", "0", "--c", "0.3", "--nu", "-0.96", "--S", "20"), "speeds",
              "--gamma", "--gamma 0");
    bad_input(RUN("speeds", "--gamma", "2e6", "--c", "0.3", "--nu", "-0.96", "--S", "20"), "speeds",
              "--gamma", "--gamma 2e6");
    bad_input(RUN("speeds", "--gamma", "2", "--c", "-0.3", "--nu", "-0.96", "--S", "20"), "speeds",
              "--c", "--c -0.3");
    bad_input(RUN("speeds", "--gamma", "2", "--c", "0.3", "--nu", "-0.96", "--S", "0"), "speeds",
              "--S", "--S 0");
    bad_input(RUN("speeds", "--gamma", "2", "--c", "0.3", "--nu", "nan", "--S", "20"), "speeds",
              "--nu", "--nu nan");
    /* (a missing --gamma is the paper's: test_cli_defaults.c) */
    bad_input(RUN("speeds", "--gamma", "2", "--c", "0.3", "--nu", "-0.96", "--S", "20", "--tol",
                  "1"),
              "speeds", "--tol", "--tol 1");
    bad_input(RUN("speeds", "--gamma", "2", "--c", "0.3", "--nu", "-0.96", "--S", "20", "--n", "0"),
              "speeds", "--n", "--n 0");
    bad_input(RUN("speeds", "--gamma", "2", "--c", "0.3", "--nu", "-0.96", "--S", "20", "--n", "2",
                  "--nmax", "3"),
              "speeds", "--nmax", "--n with --nmax");
    bad_input(RUN("speeds", "--gamma", "2", "--c", "0.3", "--nu", "-0.96", "--S", "20", "--bogus"),
              "speeds", "--bogus", "--bogus");
    bad_input(RUN("speeds", "--gamma", "2", "--c", "0.3", "--nu", "-0.96", "--S", "20", "--format",
                  "csv"),
              "speeds", "--format", "--format csv");
    bad_input(RUN("speeds", "--gamma", "2", "--c", "0.3", "--nu", "-0.96", "--S", "20", "--out",
                  "/nonexistent_bkf/x.tsv"),
              "speeds", "--out", "--out in a missing directory");
}

TEST(cli_speeds_out_file_is_atomic)
{
    char dir[] = "/tmp/bkf_cli_speeds_out_XXXXXX";
    CHECK(mkdtemp(dir));
    char path[256];
    snprintf(path, sizeof path, "%s/speeds.tsv", dir);
    run_result r = RUN("speeds", "--gamma", "2", "--c", "0.3", "--nu", "-0.96", "--S", "20", "--out",
                       path, "--tol", "1e-8");
    CHECK_MSG(r.code == 0 && r.out[0] == '\0' && r.err[0] == '\0', "exit %d: %s", r.code, r.err);
    run_free(&r);
    char *text = bkf_cli_read_file(path);
    CHECK(text);
    CHECK(rows(text) == 12);
    r = RUN("speeds", "--out", path, "--gamma", "2", "--c", "0.3", "--nu", "-1", "--S", "20");
    CHECK(r.code == 2 && r.out[0] == '\0');
    run_free(&r);
    char *again = bkf_cli_read_file(path);
    CHECK(again);
    CHECK(strcmp(text, again) == 0);
    free(text);
    free(again);
    unlink(path);
    CHECK(rmdir(dir) == 0); /* no temporary left behind */
}

TEST(cli_speeds_and_branch_help)
{
    run_result r = RUN("speeds", "--help");
    CHECK(r.code == 0 && r.err[0] == '\0');
    const char *needles[] = {"--gamma", "--c", "--nu", "--S", "--n", "--nmax", "--tol", "--format",
                             "--out", "n_max", "v_err", "residual", "near-tangent", "period_fixed"};
    for (size_t i = 0; i < sizeof needles / sizeof needles[0]; i++)
        CHECK_MSG(strstr(r.out, needles[i]), "speeds help lacks %s", needles[i]);
    run_free(&r);
    r = RUN("branch", "--help");
    CHECK(r.code == 0 && r.err[0] == '\0');
    const char *more[] = {"--param", "--from", "--to", "--root", "--max-points", "fold", "sonic"};
    for (size_t i = 0; i < sizeof more / sizeof more[0]; i++)
        CHECK_MSG(strstr(r.out, more[i]), "branch help lacks %s", more[i]);
    run_free(&r);
    r = RUN("--help");
    CHECK(r.code == 0 && strstr(r.out, "speeds") && strstr(r.out, "branch"));
    run_free(&r);
}

TEST(cli_branch_through_folds_to_sonic)
{
    run_result r = RUN("branch", "--param", "S", "--from", "30", "--to", "5", "--n", "6", "--gamma",
                       "1.5", "--c", "0.3", "--nu", "-0.96", "--tol", "1e-8");
    CHECK_MSG(r.code == 0 && r.err[0] == '\0', "exit %d: %s", r.code, r.err);
    CHECK(strstr(r.out, "point\tS\tgamma\tc\tnu\tn\tv\t"));
    CHECK(strstr(r.out, "2 fold(s) at S = "));
    CHECK(strstr(r.out, "ends at the sonic limit v -> c+ at S = 7.32"));
    int n = 0, folds = 0;
    char kind[16];
    double S, first_S = 0;
    while (field(r.out, n, "point", NULL, kind, sizeof kind)) {
        CHECK(field(r.out, n, "S", &S, NULL, 0));
        if (n == 0) first_S = S;
        folds += strcmp(kind, "fold") == 0;
        n++;
    }
    CHECK(first_S == 30 && folds == 2 && strcmp(kind, "sonic") == 0);
    CHECK_CLOSE(S, 6 * bkf_asym_k(-0.96) * 0.3 * 1.5, 1e-14, 0);
    double mu;
    CHECK(field(r.out, n - 1, "mu", &mu, NULL, 0) && isinf(mu));
    run_free(&r);

    r = RUN("branch", "--param", "c", "--from", "0.3", "--to", "0.25", "--n", "12", "--gamma", "2",
            "--nu", "-0.96", "--S", "20", "--format", "json", "--tol", "1e-8");
    CHECK_MSG(r.code == 0, "exit %d: %s", r.code, r.err);
    CHECK(bkf_test_json_valid(r.out) && strstr(r.out, "\"point\": \"point\""));
    CHECK(strstr(r.out, "ends on the range's boundary"));
    run_free(&r);
}

TEST(cli_branch_rejects_bad_input)
{
    bad_input(RUN("branch", "--param", "x", "--from", "1", "--to", "2", "--gamma", "2", "--c", "0.3",
                  "--nu", "-0.96"),
              "branch", "--param", "--param x");
    bad_input(RUN("branch", "--from", "1", "--to", "2", "--gamma", "2", "--c", "0.3", "--nu",
                  "-0.96"),
              "branch", "--param", "missing --param");
    bad_input(RUN("branch", "--param", "S", "--to", "2", "--gamma", "2", "--c", "0.3", "--nu",
                  "-0.96"),
              "branch", "--from", "missing --from");
    bad_input(RUN("branch", "--param", "S", "--from", "20", "--to", "30", "--S", "20", "--gamma",
                  "2", "--c", "0.3", "--nu", "-0.96"),
              "branch", "--S", "--S with --param S");
    bad_input(RUN("branch", "--param", "S", "--from", "20", "--to", "20", "--gamma", "2", "--c",
                  "0.3", "--nu", "-0.96"),
              "branch", "--from", "equal ends");
    bad_input(RUN("branch", "--param", "nu", "--from", "-0.96", "--to", "-1", "--gamma", "2", "--c",
                  "0.3", "--S", "20"),
              "branch", "--to", "--to -1 along nu");
    bad_input(RUN("branch", "--param", "S", "--from", "20", "--to", "30", "--gamma", "2", "--c", "0",
                  "--nu", "-0.96"),
              "branch", "closed form", "c = 0");
    bad_input(RUN("branch", "--param", "c", "--from", "0.3", "--to", "0", "--gamma", "2", "--S",
                  "20", "--nu", "-0.96"),
              "branch", "c must stay > 0", "c to 0");
    bad_input(RUN("branch", "--param", "S", "--from", "20", "--to", "30", "--n", "13", "--gamma",
                  "2", "--c", "0.3", "--nu", "-0.96"),
              "branch", "no front with n = 13", "no root at the start");
}

/* --method auto at loose tol and large mu: the roots come from a formula
 * (no solve at the roots' tolerance) and agree with shooting's roots within
 * the stated v_err; a formula asked for where its bound exceeds what the
 * root needs makes refused rows, exit 3; a bad value exits 2 naming the
 * flag and the values. */
TEST(cli_speeds_method)
{
    run_result a = RUN("speeds", "--gamma", "300", "--c", "0.3", "--nu", "0", "--S", "2000",
                       "--tol", "1e-2", "--nmax", "3", "--method", "auto");
    CHECK_MSG(a.code == 0, "exit %d: %s", a.code, a.err);
    CHECK(strstr(a.out, "0 solves at the roots' tolerance, 3 values of T from a formula") != NULL);
    run_result s = RUN("speeds", "--gamma", "300", "--c", "0.3", "--nu", "0", "--S", "2000",
                       "--tol", "1e-8", "--nmax", "3", "--method", "shooting");
    CHECK_MSG(s.code == 0, "exit %d: %s", s.code, s.err);
    CHECK(rows(a.out) == 3 && rows(s.out) == 3);
    for (int i = 0; i < 3; i++) {
        double va, verr, vs;
        char model[32], smodel[32];
        CHECK(field(a.out, i, "v", &va, NULL, 0) && field(a.out, i, "v_err", &verr, NULL, 0));
        CHECK(field(a.out, i, "model", NULL, model, sizeof model));
        CHECK(strcmp(model, "leading") == 0 || strcmp(model, "asymptotic") == 0);
        CHECK(field(s.out, i, "v", &vs, NULL, 0) && field(s.out, i, "model", NULL, smodel, sizeof smodel));
        CHECK(strcmp(smodel, "shooting") == 0);
        CHECK_MSG(fabs(va - vs) <= verr && verr <= 1e-2 * va, "n %d: |%g - %g| vs v_err %g", i + 1,
                  va, vs, verr);
    }
    run_result r = RUN("speeds", "--gamma", "2", "--c", "0.3", "--nu", "-0.96", "--S", "20",
                       "--tol", "1e-2", "--method", "asymptotic");
    CHECK_MSG(r.code == 3 && rows(r.out) == 12 && strstr(r.err, "11 of 12 roots refused") &&
                  strstr(r.err, "error bound") != NULL,
              "exit %d: %s", r.code, r.err);
    run_result b = RUN("speeds", "--gamma", "2", "--c", "0.3", "--nu", "-0.96", "--S", "20",
                       "--method", "fast");
    CHECK_MSG(b.code == 2 && b.out[0] == '\0' && strstr(b.err, "--method") != NULL &&
                  strstr(b.err, "shooting") != NULL && strchr(b.err, '\n') == b.err + strlen(b.err) - 1,
              "exit %d: %s", b.code, b.err);
    run_free(&a);
    run_free(&s);
    run_free(&r);
    run_free(&b);
}

/* branch --stability as a user sees it: the five columns, the change of
 * stability of n = 3 between S = 20 (unstable, issue 15: sigma_max +0.0244)
 * and S = 15 (the profile of n = 4 at S = 20, stable) as a row of type
 * stability with sigma_max 0 to the tolerance, a comment naming it, the
 * same rows in JSON; bad stability flags exit 2 naming the flag and write
 * nothing, not even an --out file. */
TEST(cli_branch_stability)
{
#define BRANCH3 "branch", "--param", "S", "--from", "20", "--to", "15", "--n", "3", "--gamma", "2", \
                "--c", "0.3", "--nu", "-0.96"
    run_result r = RUN(BRANCH3, "--stability", "--stability-tol", "1e-7");
    CHECK_MSG(r.code == 0 && r.err[0] == '\0', "exit %d: %s", r.code, r.err);
    CHECK(strstr(r.out, "\tflags\tstable\tsigma_max\tsigma_max_err\tkappa_max\tkind\n"));
    CHECK(strstr(r.out, "# stability changes at S = "));
    char type[32], first[32], last[32];
    int n = 0, at = -1;
    for (; field(r.out, n, "point", NULL, type, sizeof type); n++)
        if (strcmp(type, "stability") == 0) at = n;
    CHECK(at > 0 && n > at + 1);
    double sigma, err;
    CHECK(field(r.out, at, "sigma_max", &sigma, NULL, 0) &&
          field(r.out, at, "sigma_max_err", &err, NULL, 0));
    CHECK_MSG(fabs(sigma) <= 1e-7 && err <= 1e-7, "sigma_max %g err %g", sigma, err);
    CHECK(field(r.out, 0, "stable", NULL, first, sizeof first) && strcmp(first, "no") == 0);
    CHECK(field(r.out, n - 1, "stable", NULL, last, sizeof last) && strcmp(last, "yes") == 0);
    run_free(&r);
    r = RUN(BRANCH3, "--stability", "--format", "json");
    CHECK_MSG(r.code == 0, "exit %d: %s", r.code, r.err);
    CHECK(bkf_test_json_valid(r.out) && strstr(r.out, "\"point\": \"stability\"") &&
          strstr(r.out, "\"stable\": \"yes\""));
    run_free(&r);

    bad_input(RUN(BRANCH3, "--stability", "--stability-tol", "1"), "branch", "--stability-tol",
              "--stability-tol 1");
    bad_input(RUN(BRANCH3, "--stability", "--stability-tol", "1e-11"), "branch",
              "--stability-tol", "--stability-tol 1e-11");
    bad_input(RUN(BRANCH3, "--stability-tol", "1e-5"), "branch", "--stability-tol",
              "--stability-tol without --stability");
    char dir[] = "/tmp/bkf_cli_branch_stab_XXXXXX";
    CHECK(mkdtemp(dir));
    char path[256];
    snprintf(path, sizeof path, "%s/branch.tsv", dir);
    bad_input(RUN(BRANCH3, "--stability", "--stability-tol", "x", "--out", path), "branch",
              "--stability-tol", "--stability-tol x");
    CHECK_MSG(access(path, F_OK) != 0, "%s written on bad input", path);
    CHECK(rmdir(dir) == 0);
#undef BRANCH3
}

/* Where the speeds are refused (|nu| so close to 1 that no cycle meets the
 * tolerance), the one error line names the failing cycle once and says what
 * to try: the verified range of nu and a looser tol. */
TEST(cli_speeds_refusal_near_nu_minus_1_says_what_to_try)
{
    bkf_cli_result r = BKF_CLI("speeds", "--gamma", "2", "--c", "0.3", "--nu", "-0.99999999",
                               "--S", "20");
    CHECK_MSG(r.code == 1 && r.out[0] == '\0' && bkf_count_lines(r.err) == 1, "exit %d: %s",
              r.code, r.err);
    int mentions = 0;
    for (const char *m = r.err; (m = strstr(m, "mu = ")); m++) mentions++;
    CHECK_MSG(mentions == 1, "the place is said %d times: %s", mentions, r.err);
    CHECK_MSG(strstr(r.err, "|nu| <= 0.9999") && strstr(r.err, "looser tol"), "no hint: %s", r.err);
    bkf_cli_result_free(&r);
}

/* R1 of issue 31's independent audit: one root that cannot be had to
 * --tol (n = 50 next to the canard here, had to 1e-9 only) refused the
 * whole table, exit 1, nothing written.  Now the table is written with that
 * root a row flagged refused (v, mu nan, no model), its reason in a comment,
 * every other row standing, and exit 3 with one line on stderr: a script
 * tells the partial table from a whole one (0) and from none (1). */
TEST(cli_speeds_refused_row_keeps_the_table_exit_3)
{
    run_result r = RUN("speeds", "--gamma", "0.567489", "--c", "0.432606", "--nu", "0.989398",
                       "--S", "59.5575");
    CHECK_MSG(r.code == 3 && bkf_count_lines(r.err) == 1 && strstr(r.err, "roots refused") &&
                  strstr(r.err, "cannot be polished to tol 1e-10"),
              "exit %d: %s", r.code, r.err);
    CHECK(strstr(r.out, speeds_header) != NULL && strstr(r.out, "\n# refused: n = "));
    int refused = 0, good = 0;
    for (int i = 0; i < rows(r.out); i++) {
        char flags[64], model[32];
        double v, n;
        CHECK(field(r.out, i, "flags", NULL, flags, sizeof flags) &&
              field(r.out, i, "model", NULL, model, sizeof model) && field(r.out, i, "v", &v, NULL, 0) &&
              field(r.out, i, "n", &n, NULL, 0));
        if (strstr(flags, "refused")) {
            CHECK_MSG(isnan(v) && model[0] == '\0', "row %d: v %g, model '%s'", i, v, model);
            refused++;
        } else {
            CHECK_MSG(v > 0.432606 && strcmp(model, "shooting") == 0, "row %d: v %g", i, v);
            good++;
        }
    }
    CHECK_MSG(refused >= 1 && good >= 100, "%d refused, %d good", refused, good);
    /* JSON (n = 50 alone, cheaper): the count in "results", v null */
    run_result j = RUN("speeds", "--gamma", "0.567489", "--c", "0.432606", "--nu", "0.989398",
                       "--S", "59.5575", "--n", "50", "--format", "json");
    CHECK_MSG(j.code == 3 && bkf_test_json_valid(j.out), "exit %d: %s", j.code, j.err);
    CHECK_MSG(strstr(j.out, "\"refused\": 1}") && strstr(j.out, "\"v\": null"), "%s", j.out);
    /* --stability: no spectrum for the refused root, its neighbours' stand */
    run_result st = RUN("speeds", "--gamma", "0.567489", "--c", "0.432606", "--nu", "0.989398",
                        "--S", "59.5575", "--n", "50", "--stability");
    CHECK_MSG(st.code == 3 && rows(st.out) == 3, "exit %d: %s", st.code, st.err);
    for (int i = 0; i < rows(st.out); i++) {
        char flags[64], stable[32];
        double sigma;
        CHECK(field(st.out, i, "flags", NULL, flags, sizeof flags) &&
              field(st.out, i, "stable", NULL, stable, sizeof stable) &&
              field(st.out, i, "sigma_max", &sigma, NULL, 0));
        if (strstr(flags, "refused"))
            CHECK_MSG(strcmp(stable, "refused") == 0 && isnan(sigma), "row %d: %s %g", i, stable, sigma);
        else
            CHECK_MSG((strcmp(stable, "yes") == 0 || strcmp(stable, "no") == 0) && isfinite(sigma),
                      "row %d: %s %g", i, stable, sigma);
    }
    run_free(&r);
    run_free(&j);
    run_free(&st);
}

/* A product that takes one root as its input refuses a refused one with
 * its reason (exit 1, nothing written), never a train at v = nan; the
 * other roots of that n stay usable. */
TEST(cli_refused_root_is_refused_by_its_consumers)
{
    run_result st = RUN("stability", "--gamma", "0.567489", "--c", "0.432606", "--nu", "0.989398",
                        "--S", "59.5575", "--n", "50", "--root", "2");
    CHECK_MSG(st.code == 1 && st.out[0] == '\0' && bkf_count_lines(st.err) == 1 &&
                  strstr(st.err, "n = 50: the root near mu = 3.55") &&
                  strstr(st.err, "cannot be polished to tol 1e-10"),
              "exit %d: %s", st.code, st.err);
    run_result br = RUN("branch", "--param", "S", "--from", "59.5575", "--to", "59", "--gamma",
                        "0.567489", "--c", "0.432606", "--nu", "0.989398", "--n", "50", "--root",
                        "2", "--max-points", "2");
    CHECK_MSG(br.code == 1 && br.out[0] == '\0' && strstr(br.err, "cannot be polished"),
              "exit %d: %s", br.code, br.err);
    run_result ok = RUN("branch", "--param", "S", "--from", "59.5575", "--to", "59", "--gamma",
                        "0.567489", "--c", "0.432606", "--nu", "0.989398", "--n", "50", "--root",
                        "1", "--max-points", "2");
    CHECK_MSG(ok.code == 0 && rows(ok.out) >= 2, "exit %d: %s", ok.code, ok.err);
    run_free(&st);
    run_free(&br);
    run_free(&ok);
}

/* `bkfront floquet` as a user sees it: the built binary (BKF_CLI_PATH), its
 * stdout, stderr and exit status, in its three modes. */
#define _POSIX_C_SOURCE 200809L
#include "harness.h"
#include "cli_support.h"

#include "bkfront/floquet.h"

#include <fcntl.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

/* In test_io.c. */
int bkf_test_json_valid(const char *text);

typedef bkf_cli_result fq_run;
#define FQ(...) BKF_CLI("floquet", __VA_ARGS__)
#define fq_free bkf_cli_result_free
#define fq_bad(r, names, what) bkf_cli_expect_bad_input((r), "floquet", (names), (what))
#define fq_field bkf_tsv_cell

TEST(cli_floquet_help)
{
    fq_run r = FQ("--help");
    CHECK_MSG(r.code == 0 && r.err[0] == '\0', "exit %d: %s", r.code, r.err);
    const char *needles[] = {"--gamma", "--c", "--nu", "--q", "--S", "--threshold", "--along",
                             "--from", "--to", "--diagram", "--search", "--tol", "--cq-max",
                             "--nu-step", "--format", "--out", "m1_re", "m2_im", "kind",
                             "allowed", "lambda_slip", "nu_pd", "q_c", "period_doubling",
                             "long_wave"};
    for (size_t i = 0; i < sizeof needles / sizeof needles[0]; i++)
        CHECK_MSG(strstr(r.out, needles[i]), "help lacks %s", needles[i]);
    fq_free(&r);
}

TEST(cli_floquet_rejects_bad_input)
{
    /* (a missing --gamma, --c, --nu is the paper's: test_cli_defaults.c) */
    fq_bad(FQ("--gamma", "2", "--c", "0.3", "--nu", "-0.9"), "--q", "missing --q");
    fq_bad(FQ("--gamma", "0", "--c", "0.3", "--nu", "-0.9", "--q", "1"), "--gamma", "gamma 0");
    fq_bad(FQ("--gamma", "2", "--c", "-1", "--nu", "-0.9", "--q", "1"), "--c", "c < 0");
    fq_bad(FQ("--gamma", "2", "--c", "0.3", "--nu", "1", "--q", "1"), "--nu", "nu 1");
    fq_bad(FQ("--gamma", "2", "--c", "0.3", "--nu", "-0.9", "--q", "-1:2:4"), "--q", "q < 0");
    fq_bad(FQ("--gamma", "2", "--c", "0.3", "--nu", "-0.9", "--q", "1e6"), "--q", "c q huge");
    fq_bad(FQ("--gamma", "2", "--c", "0.3", "--nu", "-0.9", "--q", "1", "--S", "0"), "--S", "S 0");
    fq_bad(FQ("--gamma", "2", "--c", "0.3", "--nu", "-0.9", "--q", "1", "--tol", "1"), "--tol",
           "tol 1");
    fq_bad(FQ("--gamma", "2", "--c", "0.3", "--nu", "-0.9", "--q", "1", "--search", "-1:0"),
           "--search", "--search in dispersion mode");
    fq_bad(FQ("--threshold", "--diagram", "--gamma", "2", "--c", "0.3"), "--diagram",
           "two modes");
    fq_bad(FQ("--threshold", "--gamma", "2", "--c", "0.3", "--nu", "-0.9"), "--nu",
           "--nu with --threshold");
    fq_bad(FQ("--threshold", "--gamma", "2", "--c", "0"), "--c", "c = 0 with --threshold");
    fq_bad(FQ("--threshold", "--gamma", "2", "--c", "0.3", "--search", "-1:0"), "--search",
           "--search reaching -1");
    fq_bad(FQ("--threshold", "--gamma", "2", "--c", "0.3", "--search", "0:-0.5"), "--search",
           "--search backwards");
    fq_bad(FQ("--threshold", "--along", "c", "--from", "0.1", "--gamma", "2"), "--to",
           "--along without --to");
    fq_bad(FQ("--threshold", "--along", "c", "--from", "0.1", "--to", "1", "--gamma", "2", "--c",
              "0.3"),
           "--c", "--along c with --c");
    fq_bad(FQ("--threshold", "--along", "mu", "--from", "1", "--to", "2", "--c", "0.3"),
           "--along", "--along mu");
    fq_bad(FQ("--threshold", "--along", "gamma", "--from", "2", "--to", "2", "--c", "0.3"),
           "--from", "--from = --to");
    fq_bad(FQ("--gamma", "2", "--c", "0.3", "--nu", "-0.9", "--q", "1", "--from", "1"), "--from",
           "--from without --threshold");
    fq_bad(FQ("--gamma", "2", "--c", "0.3", "--nu", "-0.9", "--q", "1", "--out",
              "/nonexistent_bkf/x.tsv"),
           "--out", "--out in a missing directory");
}

/* The paper's parameters: stable at nu = -0.92, period doubling at q ~ 3
 * at nu = -0.94, and the modes of S = 20 marked. */
/* The refused rows of a table are one warning line on stderr that counts
 * them (none when none is refused). */
static void expect_refusal_summary(const char *err, int refused, int rows)
{
    if (!refused) {
        CHECK_MSG(err[0] == '\0', "no refused row, stderr: %s", err);
        return;
    }
    char want[96];
    snprintf(want, sizeof want, "bkfront floquet: warning: %d of %d rows refused", refused, rows);
    CHECK_MSG(strncmp(err, want, strlen(want)) == 0 && bkf_count_lines(err) == 1,
              "want one line '%s...', stderr:\n%s", want, err);
}

TEST(cli_floquet_dispersion)
{
    fq_run r = FQ("--gamma", "2", "--c", "0.3", "--nu", "-0.94", "--q", "0:6:25", "--S", "20");
    CHECK_MSG(r.code == 0 && r.err[0] == '\0', "exit %d: %s", r.code, r.err);
    CHECK(strstr(r.out, "q\tK\tlambda\tlambda_err\tm1_re\tm1_im\tm2_re\tm2_im\tm1_err\tkind\tallowed\t"
                        "lambda_slip\tdet\tdet_direct\n"));
    CHECK(strstr(r.out, "# command: bkfront floquet --gamma 2 --c 0.3 --nu -0.94 --q 0:6:25 --S 20\n"));
    int rows = 0, allowed = 0, unstable_pd = 0;
    double q, lambda, m1, al, prev = -1, slip;
    char kind[32];
    for (; fq_field(r.out, rows, "q", &q, NULL, 0); rows++) {
        CHECK(q > prev);
        prev = q;
        CHECK(fq_field(r.out, rows, "lambda", &lambda, NULL, 0));
        CHECK(fq_field(r.out, rows, "m1_re", &m1, NULL, 0));
        CHECK(fq_field(r.out, rows, "allowed", &al, NULL, 0));
        CHECK(fq_field(r.out, rows, "kind", NULL, kind, sizeof kind));
        CHECK(fq_field(r.out, rows, "lambda_slip", &slip, NULL, 0) && slip > 0);
        if (al == 1) {
            double j = q * 20.0 / (2.0 * 3.14159265358979323846);
            CHECK_MSG(fabs(j - nearbyint(j)) < 1e-9, "q %.17g marked allowed", q);
            allowed++;
        }
        if (lambda > 0 && m1 < -1 && q > 2.5 && q < 3.5) {
            CHECK(strcmp(kind, "real_negative") == 0);
            unstable_pd++;
        }
        if (q == 0) CHECK_CLOSE(m1, 1.0, 0, 1e-9);
    }
    /* 25 grid points plus the 20 modes 2 pi j/20 <= 6, of which only q = 0
     * (j = 0) is on the grid */
    CHECK_MSG(allowed == 20, "%d allowed rows", allowed);
    CHECK_MSG(rows == 25 + 19, "%d rows", rows);
    CHECK(unstable_pd >= 1);
    fq_free(&r);

    r = FQ("--gamma", "2", "--c", "0.3", "--nu", "-0.92", "--q", "0.1:6:60");
    CHECK_MSG(r.code == 0, "exit %d: %s", r.code, r.err);
    /* a row whose estimate stays above tol is flagged: kind refused, no
     * digits, its estimate above tol, one warning line on stderr each */
    int refused = 0;
    for (int i = 0; fq_field(r.out, i, "lambda", &lambda, NULL, 0); i++) {
        CHECK(fq_field(r.out, i, "kind", NULL, kind, sizeof kind));
        if (!strcmp(kind, "refused")) {
            double le;
            refused++;
            CHECK(isnan(lambda) && fq_field(r.out, i, "lambda_err", &le, NULL, 0) && le > 1e-10);
        } else {
            CHECK_MSG(lambda < 0, "row %d: lambda %g at nu = -0.92", i, lambda);
        }
        CHECK(fq_field(r.out, i, "allowed", &al, NULL, 0) && isnan(al));
    }
    CHECK_MSG(refused <= 3, "%d refused rows", refused);
    expect_refusal_summary(r.err, refused, 60);
    bkf_test_note("nu -0.92, tol 1e-10: %d of 60 rows refused", refused);
    fq_free(&r);

    /* tol 1e-12 is out of reach at q > 0: many refused rows, one line */
    r = FQ("--gamma", "2", "--c", "0.3", "--nu", "-0.96", "--q", "0,0.1,0.2", "--tol", "1e-12");
    CHECK_MSG(r.code == 0, "exit %d: %s", r.code, r.err);
    refused = 0;
    for (int i = 0; fq_field(r.out, i, "kind", NULL, kind, sizeof kind); i++)
        refused += !strcmp(kind, "refused");
    CHECK_MSG(refused >= 2, "%d refused rows at tol 1e-12", refused);
    expect_refusal_summary(r.err, refused, 3);
    fq_free(&r);
}

TEST(cli_floquet_threshold)
{
    fq_run r = FQ("--threshold", "--gamma", "2", "--c", "0.3", "--tol", "1e-9");
    CHECK_MSG(r.code == 0 && r.err[0] == '\0', "exit %d: %s", r.code, r.err);
    double nu, err, q, m, stable_above;
    char kind[32];
    CHECK(fq_field(r.out, 0, "nu_pd", &nu, NULL, 0) && nu > -0.94 && nu < -0.92);
    CHECK(fq_field(r.out, 0, "nu_pd_err", &err, NULL, 0) && err > 0 && err < 1e-8);
    CHECK(fq_field(r.out, 0, "q_c", &q, NULL, 0) && q > 2.5 && q < 3.5);
    CHECK(fq_field(r.out, 0, "m_c_re", &m, NULL, 0));
    CHECK_CLOSE(m, -1.0, 0, 1e-7);
    CHECK(fq_field(r.out, 0, "kind", NULL, kind, sizeof kind) && strcmp(kind, "period_doubling") == 0);
    CHECK(fq_field(r.out, 0, "stable_above", &stable_above, NULL, 0) && stable_above == 1);
    CHECK(!fq_field(r.out, 1, "nu_pd", &nu, NULL, 0));
    bkf_test_note("nu_pd = %.12f +- %.2g, q_c = %.6f", nu, err, q);
    fq_free(&r);

    /* the curve against c: nu_pd does not move, q_c goes as 1/c */
    r = FQ("--threshold", "--along", "c", "--from", "0.3", "--to", "0.6", "--gamma", "2", "--tol",
           "1e-8");
    CHECK_MSG(r.code == 0, "exit %d: %s", r.code, r.err);
    double c0, q0, c, nu0;
    CHECK(fq_field(r.out, 0, "c", &c0, NULL, 0) && c0 == 0.3);
    CHECK(fq_field(r.out, 0, "q_c", &q0, NULL, 0));
    CHECK(fq_field(r.out, 0, "nu_pd", &nu0, NULL, 0));
    int rows = 0;
    for (; fq_field(r.out, rows, "c", &c, NULL, 0); rows++) {
        CHECK(fq_field(r.out, rows, "nu_pd", &nu, NULL, 0));
        CHECK_CLOSE(nu, nu0, 0, 1e-8);
        CHECK(fq_field(r.out, rows, "q_c", &q, NULL, 0));
        CHECK_CLOSE(q * c, q0 * c0, 1e-6, 0);
    }
    CHECK(rows >= 3 && c == 0.6);
    fq_free(&r);
}

TEST(cli_floquet_diagram_json)
{
    fq_run r = FQ("--diagram", "--gamma", "2", "--c", "0.3", "--search", "-0.999:-0.5",
                  "--format", "json", "--tol", "1e-8");
    CHECK_MSG(r.code == 0 && r.err[0] == '\0', "exit %d: %s", r.code, r.err);
    CHECK_MSG(bkf_test_json_valid(r.out), "invalid JSON:\n%s", r.out);
    CHECK(strstr(r.out, "\"columns\": [\"nu_from\", \"nu_to\", \"stability\""));
    /* unstable, stable (period doubling .. long wave), unstable */
    const char *a = strstr(r.out, "\"stability\": \"unstable\"");
    const char *b = a ? strstr(a, "\"stability\": \"stable\"") : NULL;
    const char *c = b ? strstr(b, "\"stability\": \"unstable\"") : NULL;
    CHECK(a && b && c);
    CHECK(strstr(r.out, "\"from_kind\": \"period_doubling\", \"to_kind\": \"long_wave\""));
    fq_free(&r);
}

TEST(cli_floquet_out_file_is_atomic)
{
    char dir[] = "/tmp/bkf_floquet_out_XXXXXX";
    CHECK(mkdtemp(dir));
    char path[256];
    snprintf(path, sizeof path, "%s/d.tsv", dir);
    fq_run r = FQ("--gamma", "2", "--c", "0.3", "--nu", "-0.9", "--q", "0:3:4", "--out", path);
    CHECK_MSG(r.code == 0 && r.out[0] == '\0' && r.err[0] == '\0', "exit %d: %s", r.code, r.err);
    fq_free(&r);
    char *text = bkf_cli_read_file(path);
    CHECK(text);
    double q;
    CHECK(fq_field(text, 3, "q", &q, NULL, 0) && q == 3);
    /* a failed run leaves it as it was */
    r = FQ("--gamma", "2", "--c", "0.3", "--nu", "-0.9", "--q", "-1", "--out", path);
    CHECK(r.code == 2);
    fq_free(&r);
    char *again = bkf_cli_read_file(path);
    CHECK(again);
    CHECK(strcmp(text, again) == 0);
    free(text);
    free(again);
    unlink(path);
    CHECK(rmdir(dir) == 0); /* no temporary left behind */
}

TEST(cli_floquet_no_threshold_is_an_answer)
{
    /* At gamma 1.5 no nu is stable (none for gamma below about 1.76): the
     * command answers so, a row of kind none and a comment saying why, and
     * exits 0. */
    bkf_cli_result r = BKF_CLI("floquet", "--threshold", "--gamma", "1.5", "--c", "0.3");
    CHECK_MSG(r.code == 0, "exit %d: %s", r.code, r.err);
    CHECK(strstr(r.out, "# no threshold: no change of stability") != NULL);
    CHECK(strstr(r.out, "unstable throughout") != NULL);
    CHECK(strstr(r.out, "\tnan\tnan\tnone\t") != NULL);
    bkf_cli_result_free(&r);
}

/* Issue 20: --stepper extrapolation is offered (the cycle by bd2x2, said in
 * the comment line) and gives the library's lambda with that stepper to the
 * digit; an unknown stepper is refused naming all four. */
TEST(cli_floquet_extrapolation_stepper_is_the_library_s)
{
    fq_run r = FQ("--gamma", "100", "--c", "0.3", "--nu", "-0.5", "--q", "3", "--tol", "1e-8",
                  "--stepper", "extrapolation");
    CHECK_MSG(r.code == 0 && r.err[0] == '\0', "exit %d: %s", r.code, r.err);
    CHECK_MSG(strstr(r.out, "; stepper bd2x2;"), "%s", r.out);
    double lambda;
    CHECK(fq_field(r.out, 0, "lambda", &lambda, NULL, 0));
    bkf_floquet_options o = bkf_floquet_options_default();
    o.tol = 1e-8;
    o.stepper = BKF_STEPPER_EXTRAPOLATION;
    bkf_floquet *f = bkf_floquet_alloc();
    bkf_floquet_point p;
    bkf_error e;
    CHECK(f);
    CHECK_MSG(bkf_floquet_set(f, 100.0, 0.3, -0.5, &o, &e) == BKF_OK, "%s", e.message);
    CHECK_MSG(bkf_floquet_eval(f, 3.0, &p, &e) == BKF_OK, "%s", e.message);
    CHECK_MSG(lambda == p.lambda, "CLI %.17g, library %.17g", lambda, p.lambda);
    bkf_floquet_free(f);
    fq_free(&r);
    fq_bad(FQ("--gamma", "2", "--c", "0.3", "--nu", "-0.9", "--q", "1", "--stepper", "bd2x2"),
           "--stepper", "unknown stepper");
    r = FQ("--gamma", "2", "--c", "0.3", "--nu", "-0.9", "--q", "1", "--stepper", "bd2x2");
    CHECK_MSG(strstr(r.err, "extrapolation"), "%s", r.err);
    fq_free(&r);
}

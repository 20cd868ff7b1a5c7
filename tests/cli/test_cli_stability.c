/* `bkfront stability` and `bkfront speeds --stability` as a user sees them:
 * the built binary (BKF_CLI_PATH), its stdout, stderr and exit status,
 * against the library (bkf_speeds_find, bkf_trainspec_ring) and each
 * other. */
#define _POSIX_C_SOURCE 200809L
#include "harness.h"
#include "cli_support.h"

#include <stdlib.h>
#include <string.h>

#include "bkfront/cycle.h"
#include "bkfront/hill.h"
#include "bkfront/speeds.h"
#include "bkfront/trainspec.h"

/* In test_io.c. */
int bkf_test_json_valid(const char *text);

#define PAPER "--gamma", "2", "--c", "0.3", "--nu", "-0.96", "--S", "20"
#define bad_input bkf_cli_expect_bad_input

/* The text after "# stable: " up to ';' (the verdict) into buf. */
static int comment_verdict(const char *tsv, char *buf, size_t size)
{
    const char *at = strstr(tsv, "# stable: ");
    if (!at) return 0;
    at += strlen("# stable: ");
    const char *end = strchr(at, ';');
    if (!end) return 0;
    snprintf(buf, size, "%.*s", (int)(end - at), at);
    return 1;
}

/* The number after "\"NAME\": " in the JSON "results". */
static double json_result(const char *json, const char *name)
{
    const char *results = strstr(json, "\"results\": {");
    CHECK_MSG(results, "no results in: %.300s", json);
    char key[64];
    snprintf(key, sizeof key, "\"%s\": ", name);
    const char *at = strstr(results, key);
    CHECK_MSG(at && at < strchr(results, '}'), "no %s in the results", name);
    return strtod(at + strlen(key), NULL);
}

TEST(cli_stability_sigma_max_is_the_librarys)
{
    bkf_cli_result r = BKF_CLI("stability", PAPER, "--n", "4", "--format", "json");
    CHECK_MSG(r.code == 0 && r.err[0] == '\0', "exit %d: %s", r.code, r.err);
    CHECK_MSG(bkf_test_json_valid(r.out), "invalid JSON:\n%.400s", r.out);
    double sigma = json_result(r.out, "sigma_max"), kappa = json_result(r.out, "kappa_max");
    double v = json_result(r.out, "v");
    /* the library: the root of n = 4, then its ring spectrum */
    bkf_model_params p = {2, 0.3, -0.96, 20, 0, BKF_MODEL_CONTINUUM};
    bkf_speeds_options so = bkf_speeds_options_default();
    so.n_from = so.n_to = 4;
    bkf_speeds_table t;
    bkf_error e;
    CHECK(bkf_speeds_find(&p, &so, &t, &e) == BKF_OK && t.count == 1);
    CHECK(v == t.roots[0].v);
    bkf_trainspec_train train = {4, t.roots[0].v};
    bkf_trainspec_options o = bkf_trainspec_options_default();
    bkf_trainspec_result res;
    CHECK_MSG(bkf_trainspec_ring(&p, &train, &o, &res, &e) == BKF_OK, "%s", e.message);
    CHECK_MSG(sigma == res.sigma_max && kappa == res.kappa_max,
              "cli sigma_max %.17g at %.17g, library %.17g at %.17g", sigma, kappa,
              res.sigma_max, res.kappa_max);
    CHECK(strstr(r.out, bkf_trainspec_verdict_name(res.verdict)));
    bkf_trainspec_result_free(&res);
    bkf_speeds_table_free(&t);
    bkf_cli_result_free(&r);
}

/* The translation mode's row: j = 0, sigma = 0 to the tolerance asked.
 * A stable train has it among the rightmost of j = 0; an unstable one
 * (n = 2: ten sigma with Re > 0 at j = 0) still reports its residual. */
TEST(cli_stability_translation_row_is_zero)
{
    const char *cases[][2] = {{"4", "1e-6"}, {"5", "1e-8"}};
    for (size_t k = 0; k < 2; k++) {
        bkf_cli_result r = BKF_CLI("stability", PAPER, "--n", cases[k][0], "--tol", cases[k][1]);
        CHECK_MSG(r.code == 0, "exit %d: %s", r.code, r.err);
        double tol = strtod(cases[k][1], NULL);
        int found = 0;
        for (int row = 0;; row++) {
            double tr, j, re, im;
            if (!bkf_tsv_cell(r.out, row, "translation", &tr, NULL, 0)) break;
            if (tr != 1) continue;
            found++;
            CHECK(bkf_tsv_cell(r.out, row, "j", &j, NULL, 0) && j == 0);
            CHECK(bkf_tsv_cell(r.out, row, "re", &re, NULL, 0) &&
                  bkf_tsv_cell(r.out, row, "im", &im, NULL, 0));
            CHECK_MSG(fabs(re) <= tol && fabs(im) <= tol, "tol %g: translation %g%+gi", tol, re,
                      im);
        }
        CHECK_MSG(found == 1, "n %s: %d translation rows", cases[k][0], found);
        bkf_cli_result_free(&r);
    }
    bkf_cli_result r = BKF_CLI("stability", PAPER, "--n", "2", "--format", "json");
    CHECK(r.code == 0);
    CHECK(json_result(r.out, "translation_residual") <= 1e-6);
    bkf_cli_result_free(&r);
}

/* speeds --stability's verdict for each n is the stability command's, and
 * its sigma_max the same to the tolerance (the roots differ by the speeds
 * tolerance only). */
TEST(cli_speeds_stability_verdicts_are_the_stability_commands)
{
    bkf_cli_result s = BKF_CLI("speeds", PAPER, "--nmax", "5", "--stability");
    CHECK_MSG(s.code == 0 && s.err[0] == '\0', "exit %d: %s", s.code, s.err);
    CHECK(strstr(s.out, "\tstable\tsigma_max\tsigma_max_err\tkappa_max\tkind\n"));
    for (int row = 0; row < 5; row++) {
        double n, sigma, sigma_err;
        char verdict[32], kind[32];
        CHECK(bkf_tsv_cell(s.out, row, "n", &n, NULL, 0) && n == row + 1);
        CHECK(bkf_tsv_cell(s.out, row, "stable", NULL, verdict, sizeof verdict));
        CHECK(bkf_tsv_cell(s.out, row, "kind", NULL, kind, sizeof kind));
        CHECK(bkf_tsv_cell(s.out, row, "sigma_max", &sigma, NULL, 0) &&
              bkf_tsv_cell(s.out, row, "sigma_max_err", &sigma_err, NULL, 0));
        char nn[16];
        snprintf(nn, sizeof nn, "%d", row + 1);
        bkf_cli_result r = BKF_CLI("stability", PAPER, "--n", nn);
        CHECK_MSG(r.code == 0, "n %s: exit %d: %s", nn, r.code, r.err);
        char want[32];
        CHECK(comment_verdict(r.out, want, sizeof want));
        CHECK_MSG(strcmp(verdict, want) == 0, "n %s: speeds says %s, stability %s", nn, verdict,
                  want);
        CHECK(strstr(r.out, kind));
        const char *at = strstr(r.out, "sigma_max ");
        CHECK(at);
        CHECK_CLOSE(strtod(at + strlen("sigma_max "), NULL), sigma, 0, 2e-6);
        bkf_cli_result_free(&r);
    }
    CHECK(!bkf_tsv_cell(s.out, 5, "n", NULL, NULL, 0));
    bkf_cli_result_free(&s);
}

/* Hill's rightmost Re sigma but the translation (an independent route:
 * Fourier in xi, dense LAPACK) of the n = 1 train at speed v, converged
 * between 32 and 64 modes; *err its estimate. */
static double hill_rightmost(double gamma, double c, double nu, double v, double *err)
{
    bkf_cycle *cy = bkf_cycle_alloc();
    CHECK(cy);
    bkf_cycle_options co = bkf_cycle_options_default();
    co.tol = 1e-12;
    bkf_error e;
    CHECK_MSG(bkf_cycle_solve(cy, gamma / sqrt(1 - c * c / (v * v)), nu, &co, &e) == BKF_OK, "%s",
              e.message);
    bkf_hill_eigenvalue ev[4];
    double ee[4];
    size_t found = 0;
    CHECK_MSG(bkf_hill_leading(cy, gamma, 0.0, 32, 1e-8, 4, ev, ee, &found, NULL, &e) == BKF_OK,
              "%s", e.message);
    bkf_cycle_free(cy);
    for (size_t i = 0; i < found; i++)
        if (hypot(ev[i].re, ev[i].im) > 1e-6) {
            *err = ee[i];
            return ev[i].re;
        }
    CHECK_MSG(0, "Hill: no eigenvalue but the translation converged (%zu)", found);
    return NAN;
}

/* Issue 31, defect 4: where the window held nothing but the translation,
 * speeds --stability and stability printed the window's edge as sigma_max
 * with error 0 (-0.00876 and -0.00799 here; Hill's method: -0.0160 and
 * -0.0139).  The edge is a bound (every eigenvalue left of it, so the
 * verdict stays "yes"), said so in a comment, and sigma_max an eigenvalue
 * within its error of Hill's, or nan. */
TEST(cli_stability_window_edge_is_no_sigma_max)
{
    const char *sets[][4] = {{"0.347068", "0.985633", "-0.949565", "22.4207"},
                             {"0.725442", "1.2769", "0.979048", "15.9207"}};
    for (size_t k = 0; k < 2; k++) {
        const char *const *q = sets[k];
        bkf_cli_result s = BKF_CLI("speeds", "--gamma", q[0], "--c", q[1], "--nu", q[2], "--S",
                                   q[3], "--n", "1", "--stability");
        CHECK_MSG(s.code == 0, "exit %d: %s", s.code, s.err);
        double v, sigma, sigma_err;
        char verdict[32];
        CHECK(bkf_tsv_cell(s.out, 0, "v", &v, NULL, 0));
        CHECK(bkf_tsv_cell(s.out, 0, "stable", NULL, verdict, sizeof verdict));
        CHECK(bkf_tsv_cell(s.out, 0, "sigma_max", &sigma, NULL, 0) &&
              bkf_tsv_cell(s.out, 0, "sigma_max_err", &sigma_err, NULL, 0));
        double herr, hill = hill_rightmost(strtod(q[0], NULL), strtod(q[1], NULL),
                                           strtod(q[2], NULL), v, &herr);
        bkf_test_note("set %zu: Hill %.6g +- %.2g; speeds %s, %.6g +- %.2g", k, hill, herr,
                      verdict, sigma, sigma_err);
        CHECK(hill < 0 && strcmp(verdict, "yes") == 0);
        CHECK_MSG(isnan(sigma) ? isnan(sigma_err) && strstr(s.out, "every eigenvalue left of")
                               : sigma_err > 0 && fabs(sigma - hill) <= sigma_err + herr,
                  "speeds: sigma_max %.10g +- %.3g, Hill %.10g", sigma, sigma_err, hill);
        bkf_cli_result r = BKF_CLI("stability", "--gamma", q[0], "--c", q[1], "--nu", q[2],
                                   "--S", q[3], "--n", "1", "--format", "json");
        CHECK_MSG(r.code == 0 && bkf_test_json_valid(r.out), "exit %d: %s", r.code, r.err);
        const char *at = strstr(r.out, "\"sigma_max\": ");
        CHECK(at);
        at += strlen("\"sigma_max\": ");
        if (strncmp(at, "null", 4) == 0) {
            double bound = json_result(r.out, "sigma_bound");
            CHECK_MSG(bound > hill && bound < 0, "bound %g, Hill %g", bound, hill);
            CHECK(strstr(r.out, "every eigenvalue left of"));
        } else {
            double sj = strtod(at, NULL), ej = json_result(r.out, "sigma_max_err");
            CHECK_MSG(ej > 0 && fabs(sj - hill) <= ej + herr, "stability: %.10g +- %.3g, Hill %.10g",
                      sj, ej, hill);
        }
        bkf_cli_result_free(&r);
        /* branch --stability prints each point's spectrum by the same rule */
        bkf_cli_result b = BKF_CLI("branch", "--gamma", q[0], "--c", q[1], "--nu", q[2], "--n",
                                   "1", "--param", "S", "--from", q[3], "--to", "60",
                                   "--max-points", "1", "--stability");
        CHECK_MSG(b.code == 0, "exit %d: %s", b.code, b.err);
        CHECK(bkf_tsv_cell(b.out, 0, "sigma_max", &sigma, NULL, 0) &&
              bkf_tsv_cell(b.out, 0, "sigma_max_err", &sigma_err, NULL, 0));
        CHECK_MSG(isnan(sigma) ? strstr(b.out, "every eigenvalue left of") != NULL
                               : sigma_err > 0 && fabs(sigma - hill) <= sigma_err + herr,
                  "branch: sigma_max %.10g +- %.3g, Hill %.10g", sigma, sigma_err, hill);
        bkf_cli_result_free(&b);
        bkf_cli_result_free(&s);
    }
}

TEST(cli_stability_line_and_json)
{
    bkf_cli_result r = BKF_CLI("stability", PAPER, "--n", "3", "--line", "--kappa-count", "4",
                               "--format", "json");
    CHECK_MSG(r.code == 0, "exit %d: %s", r.code, r.err);
    CHECK_MSG(bkf_test_json_valid(r.out), "invalid JSON:\n%.400s", r.out);
    CHECK(json_result(r.out, "kappa_count") == 4);
    bkf_cli_result_free(&r);
    r = BKF_CLI("stability", PAPER, "--n", "3", "--line", "--kappa-count", "4");
    CHECK(r.code == 0 && strstr(r.out, "\nkappa\tre\tim\terr\n"));
    /* kappa_i = (2 pi / L) i / M, L = S/n */
    for (int i = 0; i < 4; i++) {
        double kappa;
        CHECK(bkf_tsv_cell(r.out, i, "kappa", &kappa, NULL, 0));
        CHECK_CLOSE(kappa, 6.283185307179586476925 / (20.0 / 3.0) * i / 4.0, 1e-15, 0);
    }
    CHECK(!bkf_tsv_cell(r.out, 4, "kappa", NULL, NULL, 0));
    bkf_cli_result_free(&r);
    r = BKF_CLI("speeds", PAPER, "--n", "4", "--stability", "--format", "json");
    CHECK_MSG(r.code == 0 && bkf_test_json_valid(r.out), "exit %d: %s", r.code, r.err);
    CHECK(strstr(r.out, "\"stable\": \"yes\""));
    bkf_cli_result_free(&r);
}

TEST(cli_stability_rejects_bad_input)
{
    bad_input(BKF_CLI("stability", PAPER, "--n", "0"), "stability", "--n", "--n 0");
    bad_input(BKF_CLI("stability", PAPER, "--n", "4", "--tol", "1e-20"), "stability", "--tol",
              "--tol 1e-20");
    bad_input(BKF_CLI("stability", "--gamma", "2", "--c", "0", "--nu", "-0.96", "--S", "20", "--n",
                      "4"),
              "stability", "--c", "--c 0");
    bad_input(BKF_CLI("stability", PAPER), "stability", "--n", "missing --n");
    bad_input(BKF_CLI("stability", PAPER, "--n", "13"), "stability", "n_max = 12", "--n 13");
    bad_input(BKF_CLI("stability", PAPER, "--n", "4", "--root", "2"), "stability", "root",
              "--root 2");
    bad_input(BKF_CLI("stability", PAPER, "--n", "4", "--per-kappa", "51"), "stability",
              "--per-kappa", "--per-kappa 51");
    bad_input(BKF_CLI("stability", PAPER, "--n", "4", "--line", "--kappa-count", "0"),
              "stability", "--kappa-count", "--kappa-count 0");
    bad_input(BKF_CLI("stability", PAPER, "--n", "4", "--boundary", "--S-to", "24"), "stability",
              "--to", "--boundary without --to");
    bad_input(BKF_CLI("stability", PAPER, "--n", "4", "--boundary", "--to", "-0.9", "--S-to",
                      "10"),
              "stability", "--S-to", "--S-to below --S");
    bad_input(BKF_CLI("stability", PAPER, "--n", "4", "--boundary", "--diagram", "--to", "-0.9",
                      "--S-to", "24"),
              "stability", "--diagram", "--boundary with --diagram");
    bad_input(BKF_CLI("stability", PAPER, "--n", "4", "--to", "-0.9"), "stability", "--to",
              "--to without --boundary");
    bad_input(BKF_CLI("stability", PAPER, "--n", "21", "--diagram", "--to", "-0.9", "--S-to",
                      "24"),
              "stability", "--n", "--diagram --n 21");
    bad_input(BKF_CLI("stability", PAPER, "--n", "4", "--boundary", "--to", "-0.9", "--S-to",
                      "24", "--nu-step", "0"),
              "stability", "--nu-step", "--nu-step 0");
    bad_input(BKF_CLI("speeds", PAPER, "--stability-tol", "1e-5"), "speeds", "--stability-tol",
              "--stability-tol without --stability");
    bad_input(BKF_CLI("speeds", PAPER, "--stability", "--stability-tol", "1"), "speeds",
              "--stability-tol", "--stability-tol 1");
    /* the spectrum's own floor (the profile's error): 1e-9 was accepted and
     * then refused by the library as "tol must be in [1e-08, 0.01]" */
    bad_input(BKF_CLI("speeds", PAPER, "--stability", "--stability-tol", "1e-9"), "speeds",
              "--stability-tol", "--stability-tol 1e-9");
    bad_input(BKF_CLI("stability", PAPER, "--n", "2", "--tol", "1e-9"), "stability", "--tol", "--tol 1e-9");
    bad_input(BKF_CLI("speeds", "--gamma", "2", "--c", "0", "--nu", "-0.96", "--S", "20",
                      "--stability"),
              "speeds", "--stability", "--stability with c 0");
}

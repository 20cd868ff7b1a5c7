/* bkfront speeds --model chain: the CLI against the library, and its bad input. */
#include "harness.h"
#include "cli_support.h"

#include "bkfront/chainwave.h"

#include <string.h>

TEST(cli_chain_speeds_match_library)
{
    char *out = bkf_cli_stdout("speeds --gamma 2 --c 0.3 --nu -0.96 --S 8 --model chain "
                               "--stability --tol 1e-8", NULL);
    bkf_model_params p = bkf_model_params_paper();
    p.S = 8.0;
    p.N = 8;
    p.kind = BKF_MODEL_CHAIN;
    bkf_chainwave_options o = bkf_chainwave_options_default();
    bkf_chainwave_table t;
    bkf_error e;
    CHECK(bkf_chainwave_find(&p, 1, 4, &o, &t, &e) == BKF_OK);
    CHECK(t.count >= 4);
    for (size_t i = 0; i < t.count; i++) {
        double n, v, m;
        char stable[32];
        CHECK(bkf_tsv_cell(out, (int)i, "n", &n, NULL, 0));
        CHECK(bkf_tsv_cell(out, (int)i, "v", &v, NULL, 0));
        CHECK(bkf_tsv_cell(out, (int)i, "mult_abs", &m, NULL, 0));
        CHECK(bkf_tsv_cell(out, (int)i, "stable", NULL, stable, sizeof stable));
        CHECK(n == (double)t.waves[i].n);
        CHECK(v == t.waves[i].v);
        CHECK(m == t.waves[i].mult_abs);
        CHECK(strcmp(stable, bkf_chainwave_verdict_name(t.waves[i].verdict)) == 0);
    }
    bkf_chainwave_table_free(&t);
    free(out);
}

TEST(cli_chain_bad_input)
{
    bkf_cli_expect_bad_input(BKF_CLI("speeds", "--gamma", "2", "--c", "0.3", "--nu", "-0.96",
                                     "--S", "20.5", "--model", "chain"),
                             "speeds", "--N", "S not a whole number");
    bkf_cli_expect_bad_input(BKF_CLI("speeds", "--gamma", "2", "--c", "0.3", "--nu", "-0.96",
                                     "--S", "20", "--model", "chain", "--n", "21"),
                             "speeds", "--n", "n > N");
    bkf_cli_expect_bad_input(BKF_CLI("speeds", "--gamma", "2", "--c", "0.3", "--nu", "-0.96",
                                     "--S", "20", "--model", "chain", "--N", "1"),
                             "speeds", "--N", "N < 2");
    bkf_cli_expect_bad_input(BKF_CLI("speeds", "--gamma", "2", "--c", "0.3", "--nu", "-0.96",
                                     "--S", "20", "--N", "20"),
                             "speeds", "--N", "N without chain");
}

/* bkfront branch --model chain: a branch's end is the wave that
 * bkf_chainwave_find reaches from the uncoupled chain at that parameter
 * (two routes: continuation along the parameter vs along K from K = 0),
 * across two folds in h; the multipliers' verdict as the table's. */
static void branch_end_matches_find(const char *words, bkf_model_params p, size_t n)
{
    char *out = bkf_cli_stdout(words, NULL);
    CHECK(strstr(out, "reached the end"));
    size_t rows = 0;
    double v = NAN, value;
    char point[16], stable[32] = "";
    while (bkf_tsv_cell(out, (int)rows, "value", &value, NULL, 0)) {
        bkf_tsv_cell(out, (int)rows, "v", &v, NULL, 0);
        bkf_tsv_cell(out, (int)rows, "point", NULL, point, sizeof point);
        bkf_tsv_cell(out, (int)rows, "stable", NULL, stable, sizeof stable);
        rows++;
    }
    bkf_chainwave_options o = bkf_chainwave_options_default();
    bkf_chainwave_table t;
    bkf_error e;
    CHECK(bkf_chainwave_find(&p, n, n, &o, &t, &e) == BKF_OK && t.count == 1);
    CHECK_CLOSE(v, t.waves[0].v, 1e-8, 0.0);
    CHECK(strcmp(stable, bkf_chainwave_verdict_name(t.waves[0].verdict)) == 0);
    bkf_test_note("%zu rows; end v %.15g, table %.15g (%s)", rows, v, t.waves[0].v, stable);
    bkf_chainwave_table_free(&t);
    free(out);
}

TEST(cli_chain_branch_ends_on_the_table)
{
    bkf_model_params p = bkf_model_params_paper();
    p.N = 20;
    p.kind = BKF_MODEL_CHAIN;
    /* blocks per unit length 16 -> 1 on 20 blocks (S = 20 h): two folds */
    branch_end_matches_find("branch --model chain --param h --from 0.0625 --to 1 --n 4 --N 20 "
                            "--gamma 2 --c 0.3 --nu -0.96 --tol 1e-8 --stability", p, 4);
    char *out = bkf_cli_stdout("branch --model chain --param h --from 0.0625 --to 1 --n 4 --N 20 "
                               "--gamma 2 --c 0.3 --nu -0.96 --tol 1e-8", NULL);
    CHECK(strstr(out, "2 folds"));
    free(out);
    p.nu = -0.9;
    branch_end_matches_find("branch --model chain --param nu --from -0.96 --to -0.9 --n 4 "
                            "--gamma 2 --c 0.3 --S 20 --tol 1e-8 --stability", p, 4);
    bkf_cli_expect_bad_input(BKF_CLI("branch", "--model", "chain", "--param", "h", "--from",
                                     "0.1", "--to", "1", "--gamma", "2", "--c", "0.3", "--nu",
                                     "-0.96"),
                             "branch", "--N", "h without N");
    bkf_cli_expect_bad_input(BKF_CLI("branch", "--param", "h", "--from", "0.1", "--to", "1",
                                     "--gamma", "2", "--c", "0.3", "--nu", "-0.96", "--S", "20"),
                             "branch", "param", "h on the continuum");
    bkf_cli_expect_bad_input(BKF_CLI("branch", "--model", "chain", "--param", "gamma", "--from",
                                     "2", "--to", "40", "--c", "0.3", "--nu", "-0.96", "--S",
                                     "20"),
                             "branch", "gamma", "gamma beyond 30");
}

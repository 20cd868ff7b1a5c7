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

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

/* bkfront check --model chain: the chain simulated by bkf_pde (its own
 * integrator) from each computed wave plus noise.  Stable waves keep the
 * predicted speed to 1e-8 and agree; the run's growth never contradicts the
 * multipliers (no conflicts), and the verdicts are the library's. */
static void check_chain_table(const char *model, size_t N, double S)
{
    char words[256];
    snprintf(words, sizeof words, "check --model chain %s --no-progress", model);
    int code = -1;
    char *out = bkf_cli_stdout(words, &code);
    CHECK_MSG(code == 0, "%s: exit %d", words, code);
    bkf_model_params p = bkf_model_params_paper();
    CHECK(sscanf(model, "--gamma %lf --c %lf --nu %lf", &p.gamma, &p.c, &p.nu) == 3);
    p.S = S;
    p.N = N;
    p.kind = BKF_MODEL_CHAIN;
    bkf_chainwave_options o = bkf_chainwave_options_default();
    o.tol = 1e-10;
    bkf_chainwave_table t;
    bkf_error e;
    CHECK_MSG(bkf_chainwave_find(&p, 1, 0, &o, &t, &e) == BKF_OK, "%s", e.message);
    size_t stable = 0;
    for (size_t i = 0; i < t.count; i++) {
        const bkf_chainwave *w = &t.waves[i];
        double n, v, rel;
        char verdict[32], spectral[32], growth[32];
        CHECK(bkf_tsv_cell(out, (int)i, "n", &n, NULL, 0) && n == (double)w->n);
        CHECK(bkf_tsv_cell(out, (int)i, "v_pred", &v, NULL, 0) && v == w->v);
        CHECK(bkf_tsv_cell(out, (int)i, "rel_err", &rel, NULL, 0));
        CHECK(bkf_tsv_cell(out, (int)i, "verdict", NULL, verdict, sizeof verdict));
        CHECK(bkf_tsv_cell(out, (int)i, "spectral", NULL, spectral, sizeof spectral));
        CHECK(bkf_tsv_cell(out, (int)i, "growth_verdict", NULL, growth, sizeof growth));
        CHECK(strcmp(spectral, bkf_chainwave_verdict_name(w->verdict)) == 0);
        if (w->verdict == BKF_CHAINWAVE_STABLE) {
            stable++;
            CHECK_MSG(strcmp(verdict, "agrees") == 0, "n = %zu: %s", w->n, verdict);
            CHECK_MSG(fabs(rel) <= 1e-8, "n = %zu: rel_err %g", w->n, rel);
            CHECK_MSG(strcmp(growth, "grows") != 0, "n = %zu: a stable wave grows", w->n);
        } else {
            CHECK_MSG(strcmp(verdict, "unstable") == 0, "n = %zu: %s", w->n, verdict);
            CHECK_MSG(strcmp(growth, "decays") != 0, "n = %zu: an unstable wave decays", w->n);
        }
        bkf_test_note("%s n = %zu: |m| %.9f, rel_err %.2g, run %s, %s", model, w->n,
                      w->mult_abs, rel, growth, verdict);
    }
    CHECK(stable >= 3 && stable < t.count); /* both kinds were judged */
    bkf_chainwave_table_free(&t);
    free(out);
}

TEST(cli_chain_check_paper)
{
    check_chain_table("--gamma 2 --c 0.3 --nu -0.96 --S 20", 20, 20.0);
}

TEST(cli_chain_check_second_set)
{
    check_chain_table("--gamma 3 --c 0.3 --nu -0.9 --S 16", 16, 16.0);
}

/* --init front:n=K on the chain seeds the chain's own wave: its period
 * shows at every block (the continuum's seed turns irregular there). */
TEST(cli_chain_init_front_is_the_chains_wave)
{
    char *out = bkf_cli_stdout("simulate --model chain --init front:n=4 --tmax 100 --frames 2",
                               NULL);
    bkf_model_params p = bkf_model_params_paper();
    p.N = 20;
    p.kind = BKF_MODEL_CHAIN;
    bkf_chainwave_options o = bkf_chainwave_options_default();
    o.stability = 0;
    o.tol = 1e-10;
    bkf_chainwave_table t;
    bkf_error e;
    CHECK(bkf_chainwave_find(&p, 4, 4, &o, &t, &e) == BKF_OK && t.count == 1);
    const char *line = strstr(out, "# front (the chain's own rotating wave): n 4");
    CHECK_MSG(line, "%s", out);
    const char *vp = line ? strstr(line, "v_pred ") : NULL;
    CHECK(vp && strtod(vp + 7, NULL) == t.waves[0].v);
    const char *per = strstr(out, "# period at x = 0: ");
    CHECK(per);
    double P = per ? strtod(per + 19, NULL) : 0;
    CHECK_CLOSE(P, t.waves[0].P, 1e-7, 0.0);
    bkf_test_note("period at a block %.12g, the wave's P %.12g", P, t.waves[0].P);
    bkf_chainwave_table_free(&t);
    free(out);
    bkf_cli_expect_bad_input(BKF_CLI("simulate", "--model", "chain", "--init", "front:n=21"),
                             "simulate", "n = 21", "n > N on the chain");
    bkf_cli_expect_bad_input(BKF_CLI("check", "--model", "chain", "--S", "20.5"), "check",
                             "--N", "chain without blocks");
    bkf_cli_expect_bad_input(BKF_CLI("check", "--model", "chain", "--n", "21"), "check",
                             "n = 21", "n > N");
    bkf_cli_expect_bad_input(BKF_CLI("check", "--model", "chain", "--gamma", "40"), "check",
                             "gamma", "gamma beyond the chain's range");
}

/* simulate's own measurement of a chain seeded with the chain's wave: the
 * fronts tracked on the blocks (one block wide at N = S) keep their count
 * and move at the wave's v from the shift map's Newton (an independent
 * method).  Before the chain's fronts were interpolated linearly, n = 4
 * showed 4 or 8 fronts by turns: `irregular`, |v| 0.237 against 0.485. */
static void simulate_chain_wave(const char *model, size_t N, double S, size_t n)
{
    char words[256];
    snprintf(words, sizeof words,
             "simulate --model chain %s --init front:n=%zu --tmax 300 --frames 300", model, n);
    int code = -1;
    char *out = bkf_cli_stdout(words, &code);
    CHECK_MSG(code == 0, "%s: exit %d", words, code);
    bkf_model_params p = bkf_model_params_paper();
    CHECK(sscanf(model, "--gamma %lf --c %lf --nu %lf", &p.gamma, &p.c, &p.nu) == 3);
    p.S = S;
    p.N = N;
    p.kind = BKF_MODEL_CHAIN;
    bkf_chainwave_options o = bkf_chainwave_options_default();
    o.stability = 0;
    bkf_chainwave_table t;
    bkf_error e;
    CHECK_MSG(bkf_chainwave_find(&p, n, n, &o, &t, &e) == BKF_OK && t.count == 1, "%s",
              e.message);
    CHECK_MSG(strstr(out, "# regime: propagating_fronts"), "%s: %s", words, out);
    char counts[64];
    snprintf(counts, sizeof counts, "%zu .. %zu in the window", n, n);
    CHECK_MSG(strstr(out, counts), "%s: not %s", words, counts);
    const char *sp = strstr(out, "# speed: ");
    CHECK(sp);
    double v = sp ? strtod(sp + 9, NULL) : 0, err = 1.0;
    const char *pm = sp ? strstr(sp, "+- ") : NULL;
    CHECK(pm);
    if (pm) err = strtod(pm + 3, NULL);
    /* towards -x, within its uncertainty (1e-5 relative from the fronts'
       sub-block wiggle over a window of about 70 shifts) */
    CHECK_MSG(v < 0, "%s: speed %g", words, v);
    CHECK_MSG(err < 1e-4 * t.waves[0].v, "%s: speed_err %g", words, err);
    CHECK_MSG(fabs(-v - t.waves[0].v) <= 3.0 * err, "%s: |v| %.9g, wave %.9g +- %.2g", words,
              -v, t.waves[0].v, err);
    bkf_test_note("%s n = %zu: measured %.9f +- %.1e, wave %.9f", model, n, -v, err,
                  t.waves[0].v);
    bkf_chainwave_table_free(&t);
    free(out);
}

TEST(cli_chain_simulate_measures_the_waves_speed)
{
    for (size_t n = 3; n <= 5; n++)
        simulate_chain_wave("--gamma 2 --c 0.3 --nu -0.96 --S 20", 20, 20.0, n);
    simulate_chain_wave("--gamma 3 --c 0.3 --nu -0.9 --S 16", 16, 16.0, 2);
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
    char stable[32] = "";
    while (bkf_tsv_cell(out, (int)rows, "value", &value, NULL, 0)) {
        bkf_tsv_cell(out, (int)rows, "v", &v, NULL, 0);
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
    const char *h_branch = "branch --model chain --param h --from 0.0625 --to 1 --n 4 --N 20 "
                           "--gamma 2 --c 0.3 --nu -0.96 --tol 1e-8 --stability";
    branch_end_matches_find(h_branch, p, 4);
    char *out = bkf_cli_stdout(h_branch, NULL);
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

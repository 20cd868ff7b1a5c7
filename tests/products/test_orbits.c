/* The branch of period-doubled orbits (orbits.h) against independent
 * routes: it leaves the global oscillation where floquet's multiplier of
 * the ring's mode is -1, with twice the cycle module's period; and the
 * product's CLI (bad input, TSV against JSON, the library's rows). */
#include "products_support.h"

#include <math.h>
#include <unistd.h>

#include "bkfront/cycle.h"
#include "bkfront/floquet.h"
#include "bkfront/orbits.h"

typedef struct {
    double nu, period, mode_amp;
} first_orbit;

/* Row 1 is the first orbit of the branch: stop there. */
static int take_first(const bkf_orbits_point *p, void *data)
{
    if (p->index != 1) return 0;
    first_orbit *f = data;
    f->nu = p->p;
    f->period = p->cont_period;
    f->mode_amp = p->mode_amplitude;
    return 1;
}

static first_orbit first_at(double amplitude, bkf_orbits_report *rep)
{
    bkf_orbits_options o = bkf_orbits_options_default();
    o.stability = 0;
    o.max_points = 4;
    o.switch_amplitude = amplitude;
    first_orbit f = {NAN, NAN, NAN};
    bkf_error e = {0};
    int s = bkf_orbits_branch(&o, take_first, &f, rep, &e);
    CHECK_MSG(s == BKF_OK, "branch at amplitude %g: %s", amplitude, e.message);
    CHECK_CLOSE(f.mode_amp, amplitude, 1e-12, 0);
    return f;
}

/* The PDE's orbits near the switch lie on nu = nu_pd + b A^2 + O(A^4) (a
 * pitchfork of the period-2T problem): extrapolated from A and 2A, their
 * nu at A = 0 is floquet's root of lambda(q_j) = 0, found by another
 * method (the 2 x 2 monodromy of the cycle's ODE) on another problem. */
TEST(products_orbits_branch_leaves_the_oscillation_where_floquet_has_minus_one)
{
    const double A = 0.001;
    bkf_orbits_report rep;
    first_orbit a = first_at(A, &rep), b = first_at(2 * A, &rep);
    double nu0 = (4 * a.nu - b.nu) / 3;
    CHECK_MSG(fabs(nu0 - rep.pd.p) < 2e-9, "extrapolated %.12f, floquet %.12f", nu0, rep.pd.p);
    /* the root itself: mode j = 9 of S = 20 at lambda = 0, m = -1, below the
     * continuum's threshold at q_c = 2.89 (the ring's mode is not q_c) */
    CHECK(rep.pd.j == 9);
    CHECK_CLOSE(rep.pd.m_re, -1, 0, 1e-8);
    bkf_floquet_threshold th;
    bkf_error e = {0};
    bkf_floquet_options fo = bkf_floquet_options_default();
    CHECK_STATUS(bkf_floquet_threshold_find(2, 0.3, -0.999, 0.999, &fo, &th, &e), BKF_OK);
    CHECK(th.kind == BKF_BOUNDARY_PERIOD_DOUBLING);
    CHECK_MSG(rep.pd.p < th.nu && th.nu < rep.pd.p + 1e-3, "pd %.9f, threshold %.9f",
              rep.pd.p, th.nu);
    /* the first orbit's period is twice the cycle's at its nu, up to A^2 */
    bkf_cycle *cy = bkf_cycle_alloc();
    bkf_cycle_options co = bkf_cycle_options_default();
    co.tol = 1e-12;
    CHECK_STATUS(bkf_cycle_solve(cy, 2, a.nu, &co, &e), BKF_OK);
    double T = bkf_cycle_get(cy)->period;
    bkf_cycle_free(cy);
    CHECK_MSG(fabs(a.period - 2 * T) < 100 * A * A, "P %.12f, 2T %.12f", a.period, 2 * T);
    CHECK_MSG(a.period != 2 * T, "the period was not solved for");
}

TEST(products_orbits_cli_refuses_bad_input_in_one_line)
{
    bkf_cli_expect_bad_input(BKF_CLI("orbit", "--tol", "0"), "orbit", "--tol", "tol 0");
    bkf_cli_expect_bad_input(BKF_CLI("orbit", "--nu", "-0.94"), "orbit", "--nu",
                             "nu along nu");
    bkf_cli_expect_bad_input(BKF_CLI("orbit", "--along", "gamma", "--nu", "-0.94"), "orbit",
                             "--from", "along gamma without from");
    bkf_cli_expect_bad_input(BKF_CLI("orbit", "--from", "-0.9", "--to", "-1"), "orbit",
                             "--to", "to -1");
    bkf_cli_expect_bad_input(BKF_CLI("orbit", "--N", "145"), "orbit", "--N", "odd N");
    bkf_cli_expect_bad_input(BKF_CLI("orbit", "--N", "140"), "orbit", "N", "N not 18 k");
    bkf_cli_expect_bad_input(BKF_CLI("orbit", "--regimes", "sweep.tsv"), "orbit",
                             "--coexistence", "regimes without coexistence");
}

static int write_orbits(const void *spec, FILE *out, bkf_io_format format,
                        const bkf_provenance *prov, bkf_error *err)
{
    return bkf_orbits_write(spec, out, format, prov, err);
}

/* The library's rows are the CLI's, and its JSON holds the TSV's numbers
 * (N 72, 8 points a cell of mode j = 9: the three branches in 0.8 s of
 * CPU, not 2.7 at the default 288). */
TEST(products_orbits_tsv_json_and_library_agree)
{
    char *tsv = cli_output("orbit --max-points 4 --no-stability --N 72");
    char *json = cli_output("orbit --max-points 4 --no-stability --N 72 --format json");
    bkf_orbits_spec s = bkf_orbits_spec_default();
    s.max_points = 4;
    s.no_stability = 1;
    s.N = 72;
    char *lib = library_output(write_orbits, &s, BKF_IO_TSV);
    char *b1 = table_body(tsv), *b2 = table_body(lib);
    CHECK_MSG(strcmp(b1, b2) == 0, "CLI\n%s\nlibrary\n%s", b1, b2);
    CHECK(bkf_count_lines(b1) == 1 + 5);
    for (int row = 0; row < 5; row++) {
        double nu, P;
        CHECK(bkf_tsv_cell(tsv, row, "nu", &nu, NULL, 0));
        CHECK(bkf_tsv_cell(tsv, row, "period", &P, NULL, 0));
        char key[64];
        snprintf(key, sizeof key, "{\"index\": %d,", row);
        const char *at = strstr(json, key);
        CHECK_MSG(at, "no row %d in the JSON", row);
        const char *f = strstr(at, "\"nu\": "), *g = strstr(at, "\"period\": ");
        CHECK(f && g);
        CHECK(strtod(f + 6, NULL) == nu);
        CHECK(strtod(g + 10, NULL) == P);
    }
    CHECK(strstr(json, "\"j\": 9"));
    free(b1);
    free(b2);
    free(lib);
    free(tsv);
    free(json);
}

/* Item 6: a sweep's regime rows beside the solutions at their nu.  Between
 * the period doubling (-0.935357) and the first orbits the branch has one
 * orbit, unstable (subcritical: the test of that is its multiplier), while
 * floquet's oscillation is stable above the doubling; below it the branch
 * of a few points is not there ("outside"); a row of another gamma is not
 * this branch's. */
TEST(products_orbits_coexistence_sets_regimes_beside_the_solutions)
{
    char dir[] = "/tmp/bkf_orbits_coexist_XXXXXX";
    CHECK(mkdtemp(dir));
    char sweep[512], co[512];
    snprintf(sweep, sizeof sweep, "%s/sweep.tsv", dir);
    snprintf(co, sizeof co, "%s/co.tsv", dir);
    bkf_cli_write_text(sweep, "# a hand-made regime table\n"
                              "point\tgamma\tc\tnu\tS\tregime\n"
                              "0\t2\t0.29999999999999999\t-0.93500000000000005\t20\tglobal_oscillation\n"
                              "1\t2\t0.29999999999999999\t-0.93600000000000005\t20\tirregular\n"
                              "2\t3\t0.29999999999999999\t-0.93500000000000005\t20\tglobal_oscillation\n");
    /* N 72, 8 points a cell of mode j = 9: the same table as the default
     * 288's (the orbit's multiplier 1.0725 against 1.0723), in 1.5 s of
     * CPU, not 7.6 */
    bkf_cli_result r = BKF_CLI("orbit", "--max-points", "4", "--regimes", sweep, "--coexistence",
                               co, "--no-progress", "--N", "72");
    CHECK_MSG(r.code == 0, "exit %d: %s", r.code, r.err);
    bkf_cli_result_free(&r);
    char *t = bkf_cli_read_file(co);
    CHECK(t);
    char *body = table_body(t);
    CHECK(bkf_count_lines(body) == 1 + 2); /* gamma 3 is not this branch's */
    free(body);
    double orbits, stable;
    char osc[32], expected[48], consistent[16];
    CHECK(bkf_tsv_cell(t, 0, "oscillation", NULL, osc, sizeof osc));
    CHECK(bkf_tsv_cell(t, 0, "orbits", &orbits, NULL, 0));
    CHECK(bkf_tsv_cell(t, 0, "stable_orbits", &stable, NULL, 0));
    CHECK(bkf_tsv_cell(t, 0, "expected", NULL, expected, sizeof expected));
    CHECK(bkf_tsv_cell(t, 0, "consistent", NULL, consistent, sizeof consistent));
    CHECK_MSG(strcmp(osc, "stable") == 0 && orbits == 1 && stable == 0, "%s", t);
    CHECK_MSG(strcmp(expected, "global_oscillation") == 0 && strcmp(consistent, "yes") == 0,
              "%s", t);
    CHECK(bkf_tsv_cell(t, 1, "oscillation", NULL, osc, sizeof osc));
    CHECK(bkf_tsv_cell(t, 1, "expected", NULL, expected, sizeof expected));
    CHECK_MSG(strcmp(osc, "unstable") == 0 && strcmp(expected, "outside") == 0, "%s", t);
    free(t);
    remove(co);
    remove(sweep);
    rmdir(dir);
}

/* bkfront friction: a catalogue product run from its own flags. */
#include "harness.h"

#include <math.h>
#include <string.h>

#include "cli_support.h"

TEST(cli_friction_rows_are_the_closed_forms)
{
    bkf_cli_result r = BKF_CLI("friction", "--from", "-0.5", "--to", "2", "--points", "6");
    CHECK_MSG(r.code == 0, "%s", r.err);
    size_t rows = 0;
    for (char *line = strtok(r.out, "\n"); line; line = strtok(NULL, "\n")) {
        double v, psi, cs, cl;
        if (line[0] == '#' || sscanf(line, "%lf\t%lf\t%lf\t%lf", &v, &psi, &cs, &cl) != 4)
            continue;
        rows++;
        /* psi = v - 1, creep-slip (3/2)(psi^3/3 - psi), Carlson-Langer
         * sgn(v)/(1 + |v|) */
        CHECK_CLOSE(psi, v - 1, 0, 1e-15);
        CHECK_CLOSE(cs, 1.5 * (psi * psi * psi / 3 - psi), 1e-14, 1e-15);
        if (v != 0) CHECK_CLOSE(cl, (v > 0 ? 1 : -1) / (1 + (v > 0 ? v : -v)), 1e-15, 0);
    }
    CHECK(rows == 6);
    bkf_cli_result_free(&r);
}

TEST(cli_friction_rejects_bad_input)
{
    const char *bad[][3] = {{"--points", "0", "--points"}, {"--from", "nan", "--from"},
                            {"--to", "x", "--to"}};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        bkf_cli_result r = BKF_CLI("friction", bad[i][0], bad[i][1]);
        CHECK_MSG(r.code == 2 && r.out[0] == '\0' && strstr(r.err, bad[i][2]), "%s: %s",
                  bad[i][0], r.err);
        bkf_cli_result_free(&r);
    }
    bkf_cli_result r = BKF_CLI("friction", "--from", "3", "--to", "1");
    CHECK_MSG(r.code == 2 && r.out[0] == '\0', "%s", r.err);
    bkf_cli_result_free(&r);
}

/* A range whose arithmetic overflows is refused with the range, not
 * printed as inf and nan rows: phi(v - 1) ~ v^3/3 overflows beyond about
 * 5.6e102, and to - from beyond DBL_MAX. */
TEST(cli_friction_refuses_ranges_that_overflow)
{
    const char *bad[][4] = {{"--to", "1e308", "--points", "5"},
                            {"--from", "-1e200", "--to", "1e200"},
                            {"--from", "-1e103", "--to", "0"},
                            {"--from", "1e-3", "--to", "2e100"}};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        bkf_cli_result r = BKF_CLI("friction", bad[i][0], bad[i][1], bad[i][2], bad[i][3]);
        CHECK_MSG(r.code == 2 && r.out[0] == '\0' && strstr(r.err, "1e+100"), "%s %s: %d %s",
                  bad[i][0], bad[i][1], r.code, r.err);
        bkf_cli_result_free(&r);
    }
    /* the ends of the range: every number finite, the closed form's sign */
    bkf_cli_result r = BKF_CLI("friction", "--from", "-1e100", "--to", "1e100", "--points", "3");
    CHECK_MSG(r.code == 0, "%s", r.err);
    double cs;
    CHECK(bkf_tsv_cell(r.out, 0, "creep_slip", &cs, NULL, 0) && isfinite(cs) && cs < -1e299);
    CHECK(bkf_tsv_cell(r.out, 2, "creep_slip", &cs, NULL, 0) && isfinite(cs) && cs > 1e299);
    bkf_cli_result_free(&r);
}

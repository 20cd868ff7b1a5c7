/* v_meas_err on the adapted grid covers the grid's own error in the speed
 * (issue 17 item 7): at the two reproductions of the attack the measured
 * speed missed the prediction by 11 and 10 times v_meas_err (the fit's
 * uncertainty alone).  The reference is v_pred, the speeds solver's root
 * (its error 2e-11 here, at the check's speeds tol 1e-9: a thousandth of
 * the miss), which the simulation does not share. */
#define _POSIX_C_SOURCE 200809L
#include "harness.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cli_support.h"

/* |v_meas - v_pred| <= v_meas_err, and the estimate no more than 30 times
 * the error it covers (a bound that says nothing is not an estimate). */
static void check_covers(const char *words)
{
    char *out = bkf_cli_stdout(words, NULL);
    double v_pred, v_pred_err, v_meas, v_meas_err;
    char grid[16] = "";
    CHECK(bkf_tsv_cell(out, 0, "grid", NULL, grid, sizeof grid) && strcmp(grid, "mapped") == 0);
    CHECK(bkf_tsv_cell(out, 0, "v_pred", &v_pred, NULL, 0));
    CHECK(bkf_tsv_cell(out, 0, "v_pred_err", &v_pred_err, NULL, 0));
    CHECK(bkf_tsv_cell(out, 0, "v_meas", &v_meas, NULL, 0));
    CHECK(bkf_tsv_cell(out, 0, "v_meas_err", &v_meas_err, NULL, 0));
    double miss = fabs(v_meas - v_pred);
    CHECK_MSG(v_pred_err < 0.01 * miss, "v_pred_err %.3g against |v_meas - v_pred| %.3g",
              v_pred_err, miss);
    CHECK_MSG(miss + v_pred_err <= v_meas_err, "|v_meas - v_pred| = %.3g > v_meas_err %.3g",
              miss, v_meas_err);
    CHECK_MSG(v_meas_err <= 30 * miss, "v_meas_err %.3g is %.0f times |v_meas - v_pred| %.3g",
              v_meas_err, v_meas_err / miss, miss);
    bkf_test_note("|v_meas - v_pred| %.3g, v_meas_err %.3g (%.1f times)", miss, v_meas_err,
                  v_meas_err / miss);
    free(out);
}

/* Both rows are unstable by their spectra (n = 20 here: sigma_max 0.0067),
 * whose speed an auto run does not judge, nor so measure the grid's error
 * of: --runs full measures it for every row.  tmax 20 (fit over [10, 20]):
 * miss 3.1e-8, v_meas_err 2.5e-7; without the grid's error (planted) 8.0e-9,
 * below the miss, so the test fails; at tmax 125 3.9e-8 against 1.9e-7
 * (3.5e-9 without), three times the CPU (the early steps, the noise's
 * response, are most of either). */
TEST(cli_check_adapted_grid_error_covers_the_grid_thin_fronts)
{
    check_covers("check --gamma 5 --c 0.2 --nu -0.9 --S 50 --n 20 --tmax 20 --runs full "
                 "--no-progress");
}

/* The second reproduction costs about 190 s of CPU (two runs of 17664 and
 * 11776 points near the sonic limit, v - c = 1.2e-4; shorter runs cost as
 * much, the early steps dominate): more than the whole suite's slowest
 * test by far, so it runs only when BKF_TEST_SLOW is set. */
TEST(cli_check_adapted_grid_error_covers_the_grid_sonic)
{
    const char *slow = getenv("BKF_TEST_SLOW");
    if (!slow || !*slow) {
        bkf_test_note("skipped: about 190 s of CPU; BKF_TEST_SLOW=1 runs it");
        return;
    }
    check_covers("check --gamma 0.5 --c 1 --nu 0.3 --S 20 --n 23 --tmax 60 --runs full --no-progress");
}

/* The check asks the speeds solver for what its verdict needs (rel-tol /
 * 1000, 1e-9), not 1e-12: near nu = 1 (mu 3.55, a fold of the speed
 * condition) n = 46's root 2 cannot be had to 1e-12 and the check left it
 * unresolved, v_pred nan, though the solver has it to 1e-11.  Every root
 * now has a v_pred, within its v_pred_err of the solver's own at tol 1e-11
 * (an independent, tighter polish).  The grid is capped so that no root
 * runs (0.45 s of CPU). */
TEST(cli_check_asks_the_speeds_what_the_verdict_needs)
{
    char *out = bkf_cli_stdout("check --gamma 0.567489 --c 0.432606 --nu 0.989398 --S 59.5575 "
                               "--n 46 --grid uniform --N-max 512 --tmax 1 --no-progress",
                               NULL);
    char *ref = bkf_cli_stdout("speeds --gamma 0.567489 --c 0.432606 --nu 0.989398 --S 59.5575 "
                               "--n 46 --tol 1e-11", NULL);
    int rows = 0;
    for (int r = 0; r < 3; r++) {
        double v, v_err, v_ref, v_ref_err;
        if (!bkf_tsv_cell(ref, r, "v", &v_ref, NULL, 0)) break;
        CHECK(bkf_tsv_cell(ref, r, "v_err", &v_ref_err, NULL, 0));
        CHECK(bkf_tsv_cell(out, r, "v_pred", &v, NULL, 0));
        CHECK(bkf_tsv_cell(out, r, "v_pred_err", &v_err, NULL, 0));
        CHECK_MSG(isfinite(v) && v_err <= 1e-9 * v, "root %d: v_pred %.17g +- %.3g", r + 1, v,
                  v_err);
        CHECK_MSG(fabs(v - v_ref) <= v_err + v_ref_err, "root %d: v_pred %.17g, tol 1e-11 %.17g",
                  r + 1, v, v_ref);
        rows++;
    }
    CHECK_MSG(rows == 3, "%d roots of n = 46 (3 expected)", rows);
    free(out);
    free(ref);
}

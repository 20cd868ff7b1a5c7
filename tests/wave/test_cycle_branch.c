/* The cycle branch by pseudo-arclength continuation against independent
 * cold solves at the same parameters. */
#include "harness.h"

#include "bkfront/cycle.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "taylor_reference.h"

typedef struct {
    double param[512];
    double period[512];
    double err[512];
    size_t n;
    bkf_cycle_param along;
} collected;

static int collect(const bkf_cycle_result *r, void *data)
{
    collected *c = data;
    if (c->n < 512) {
        c->param[c->n] = c->along == BKF_CYCLE_ALONG_MU ? r->mu : r->nu;
        c->period[c->n] = r->period;
        c->err[c->n] = r->period_err;
        c->n++;
    }
    return 0;
}

static void check_branch(bkf_cycle_param along, double from, double to, double fixed)
{
    collected got = {.along = along};
    bkf_cycle_options o = bkf_cycle_options_default();
    bkf_error e;
    int rc = bkf_cycle_branch(along, from, to, fixed, &o, 0, collect, &got, &e);
    CHECK_MSG(rc == BKF_OK, "%s", e.message);
    CHECK(got.n >= 5);
    CHECK_CLOSE(got.param[0], from, 1e-12, 1e-12);
    CHECK_CLOSE(got.param[got.n - 1], to, 1e-12, 1e-12);
    for (size_t i = 0; i < got.n; i++) {
        if (i) CHECK((to > from) == (got.param[i] > got.param[i - 1]));
        double mu = along == BKF_CYCLE_ALONG_MU ? got.param[i] : fixed;
        double nu = along == BKF_CYCLE_ALONG_MU ? fixed : got.param[i];
        bkf_cycle_result cold;
        CHECK_STATUS(bkf_cycle_period(mu, nu, &o, &cold, &e), BKF_OK);
        CHECK_CLOSE(got.period[i], cold.period, 2e-10, 0.0);
        CHECK(got.err[i] <= 1e-10 * got.period[i]);
    }
    bkf_test_note("%zu points from %g to %g", got.n, from, to);
}

TEST(cycle_branch_along_mu_matches_cold_solves)
{
    check_branch(BKF_CYCLE_ALONG_MU, 0.1, 200.0, -0.96);
}

TEST(cycle_branch_along_nu_matches_cold_solves)
{
    check_branch(BKF_CYCLE_ALONG_NU, 0.95, -0.95, 2.0);
}

/* A shooting branch point costs about one cold solve: each row's work
 * counters hold every shot since the previous row (corrector, tangent,
 * estimate), and their sum over the branch is compared with independent
 * cold solves (bkf_cycle_period, no warm start) with the same stepper at
 * the same parameters, whose values must agree with the rows' within the
 * two estimates.  The stepper is named on both sides (rk8pd up to
 * BKF_CYCLE_STIFF_MU, bd2x2 above, as the automatic shooting rows use),
 * since at tol 1e-10 the automatic rows are collocation rows, whose
 * work is checked against cold collocation solves by check_branch_rows.
 * Work counters are deterministic, so the bound is not a timing.  (Not
 * through a canard: there the amplitude walk's root finding costs 3-10
 * shots a row.) */
typedef struct {
    double mu[256], nu[256], period[256], err[256];
    size_t rhs, n, estimated;
} work_rows;

static int collect_work(const bkf_cycle_result *r, void *data)
{
    work_rows *w = data;
    if (w->n < 256) {
        w->mu[w->n] = r->mu;
        w->nu[w->n] = r->nu;
        w->period[w->n] = r->period;
        w->err[w->n] = r->period_err;
        w->n++;
    }
    w->rhs += r->rhs_calls;
    return 0;
}

static void check_branch_work(bkf_cycle_param along, double from, double to, double fixed, double bound)
{
    static work_rows got;
    memset(&got, 0, sizeof got);
    bkf_cycle_options o = bkf_cycle_options_default();
    double mu_top = along == BKF_CYCLE_ALONG_MU ? fmax(from, to) : fixed;
    o.stepper = mu_top > BKF_CYCLE_STIFF_MU ? BKF_STEPPER_EXTRAPOLATION : BKF_STEPPER_EXPLICIT;
    bkf_error e;
    CHECK_STATUS(bkf_cycle_branch(along, from, to, fixed, &o, 0, collect_work, &got, &e), BKF_OK);
    CHECK(got.n >= 5 && got.n < 256);
    size_t cold_rhs = 0;
    for (size_t i = 0; i < got.n && i < 256; i++) {
        bkf_cycle_result cold;
        CHECK_STATUS(bkf_cycle_period(got.mu[i], got.nu[i], &o, &cold, &e), BKF_OK);
        cold_rhs += cold.rhs_calls;
        CHECK(got.err[i] <= o.tol * got.period[i]);
        CHECK_MSG(fabs(got.period[i] - cold.period) <= got.err[i] + cold.period_err,
                  "mu %.17g nu %.17g: T %.17g (err %.2g) cold %.17g (err %.2g)", got.mu[i], got.nu[i],
                  got.period[i], got.err[i], cold.period, cold.period_err);
    }
    double ratio = (double)got.rhs / (double)cold_rhs;
    CHECK_MSG(ratio <= bound, "%s from %g to %g at %g: %zu rows cost %.2f cold solves each",
              along == BKF_CYCLE_ALONG_MU ? "mu" : "nu", from, to, fixed, got.n, ratio);
    bkf_test_note("%zu rows, %.0f rhs calls a row, %.2f cold solves", got.n, (double)got.rhs / got.n, ratio);
}

TEST(cycle_branch_point_costs_about_a_cold_solve)
{
    /* Each half of the range carries its start's cold solve in its first
     * row: 1.73 and 1.55 cold solves a row at nu 0 (11 and 15 rows), 1.50
     * and 1.26 at -0.96, 1.26 at 0.5 (the same numbers on the code before
     * collocation rows; over the whole range 0.1..1e4, one start among 23
     * rows, the automatic shooting rows cost 1.02) */
    check_branch_work(BKF_CYCLE_ALONG_MU, 0.1, BKF_CYCLE_STIFF_MU, 0.0, 2.0);
    check_branch_work(BKF_CYCLE_ALONG_MU, BKF_CYCLE_STIFF_MU * 1.01, 1e4, 0.0, 2.0);
    check_branch_work(BKF_CYCLE_ALONG_MU, 0.1, BKF_CYCLE_STIFF_MU, -0.96, 2.0);
    check_branch_work(BKF_CYCLE_ALONG_MU, BKF_CYCLE_STIFF_MU * 1.01, 1e4, -0.96, 2.0);
    check_branch_work(BKF_CYCLE_ALONG_MU, 1e4, BKF_CYCLE_STIFF_MU * 1.01, 0.5, 2.0);
    /* Along nu the steps (at most 0.05) are short enough for one corrector
     * iteration, whose point is then too far for the estimate's one-step
     * correction: corrector, tangent and two estimate shots, 1.44 cold
     * solves a row at mu 1, 1.20 at mu 100. */
    check_branch_work(BKF_CYCLE_ALONG_NU, -0.9, 0.9, 1.0, 1.5);
    check_branch_work(BKF_CYCLE_ALONG_NU, 0.9, -0.9, 100.0, 1.5);
}

TEST(cycle_branch_rejects_bad_input)
{
    collected got = {0};
    bkf_error e;
    CHECK_STATUS(bkf_cycle_branch(BKF_CYCLE_ALONG_MU, 1.0, -2.0, 0.0, NULL, 0, collect, &got, &e), BKF_EINPUT);
    CHECK_STATUS(bkf_cycle_branch(BKF_CYCLE_ALONG_NU, 0.0, 1.5, 1.0, NULL, 0, collect, &got, &e), BKF_EINPUT);
    CHECK_STATUS(bkf_cycle_branch(BKF_CYCLE_ALONG_MU, 1.0, 2.0, 0.0, NULL, 0, NULL, &got, &e), BKF_EINPUT);
}

/* Through the canard explosion: the branch reaches its end, every row is a
 * value or an honest refusal, and sampled values agree with the long-double
 * Taylor reference (mu <= 20) or with a cold solve within the estimates. */
typedef struct {
    double mu[1024], nu[1024], period[1024], err[1024], slope[1024];
    int relaxed[1024];
    size_t n, refused, refused_outside;
} canard_rows;

/* The canard explosion's neighbourhood (that of the conditioning floor,
 * docs/accuracy.md): the only place a row may be refused. */
static int in_canard(double mu, double nu)
{
    double x = 8.0 * mu * mu * (1.0 - fabs(nu));
    return mu >= 1.0 && x >= 0.5 && x <= 2.0;
}

static int collect_canard(const bkf_cycle_result *r, void *data)
{
    canard_rows *c = data;
    if (!strcmp(r->model, "refused")) {
        c->refused++;
        c->refused_outside += !in_canard(r->mu, r->nu);
    }
    if (c->n < 1024 && strcmp(r->model, "refused")) {
        c->mu[c->n] = r->mu;
        c->nu[c->n] = r->nu;
        c->period[c->n] = r->period;
        c->err[c->n] = r->period_err;
        c->slope[c->n] = r->section_slope;
        c->relaxed[c->n] = !strcmp(r->model, "shooting-relaxed");
        c->n++;
    }
    return 0;
}

static void check_canard_branch(bkf_cycle_param along, double from, double to, double fixed)
{
    static canard_rows got;
    memset(&got, 0, sizeof got);
    bkf_cycle_options o = bkf_cycle_options_default();
    bkf_error e;
    int rc = bkf_cycle_branch(along, from, to, fixed, &o, 0, collect_canard, &got, &e);
    CHECK_MSG(rc == BKF_OK, "%s", e.message);
    if (rc != BKF_OK) return;
    CHECK(got.n >= 10);
    double last = along == BKF_CYCLE_ALONG_MU ? got.mu[got.n - 1] : got.nu[got.n - 1];
    CHECK_CLOSE(last, to, 1e-12, 1e-12);
    CHECK_MSG(got.refused_outside == 0, "%zu refused rows outside the canard", got.refused_outside);
    size_t relaxed = 0, stride = got.n / 8 + 1, checked = 0;
    double worst = 0.0;
    for (size_t i = 0; i < got.n; i++) {
        relaxed += (size_t)got.relaxed[i];
        /* an unrelaxed row meets tol; a relaxed one says by how much it misses */
        if (!got.relaxed[i]) CHECK(got.err[i] <= o.tol * got.period[i]);
        /* every relaxed row and every row inside the canard (where the
         * estimates are hardest) up to mu 20, where the Taylor reference is
         * fast (a relaxed row at mu 3.65053675, nu -0.99 was 26 times its
         * estimate off while the first relaxed row of its branch was
         * honest); elsewhere every stride-th row */
        int hard = (got.relaxed[i] || in_canard(got.mu[i], got.nu[i])) && got.mu[i] <= 20.0;
        if (i % stride && !hard) continue;
        checked++;
        if (got.mu[i] <= 20.0) {
            /* the reference's secant needs a start near the cycle: a loose
             * cold solve's, or where that is refused (inside the canard) the
             * row's own (the fixed point does not depend on the start; from
             * 1.0 at mu 3.65056, nu 0.99 the secant wandered between T 18
             * and 63) */
            bkf_cycle_options loose = o;
            loose.tol = 1e-6;
            bkf_cycle_result guess;
            double slope = bkf_cycle_period(got.mu[i], got.nu[i], &loose, &guess, &e) == BKF_OK
                               ? guess.section_slope
                               : got.slope[i];
            double unc, ref = taylor_period(got.mu[i], got.nu[i], slope, &unc);
            /* a reference that did not settle checks nothing (deep in the
             * canard, mu 11.2141 at nu 0.999, long double's rounding on the
             * repelling branch leaves it 2.5e-11 uncertain: still a tenth of
             * the relaxed rows' estimates there) */
            CHECK_MSG(unc <= fmax(1e-12 * ref, 0.1 * got.err[i]), "mu %.17g nu %.17g: reference uncertainty %.2g", got.mu[i],
                      got.nu[i], unc);
            CHECK_MSG(fabs(got.period[i] - ref) <= 3.0 * got.err[i] + unc,
                      "mu %.17g nu %.17g: T %.17g ref %.17g (unc %.2g) err %.2g", got.mu[i],
                      got.nu[i], got.period[i], ref, unc, got.err[i]);
            worst = fmax(worst, fabs(got.period[i] - ref) / got.err[i]);
        } else {
            bkf_cycle_result cold;
            CHECK_STATUS(bkf_cycle_period(got.mu[i], got.nu[i], &o, &cold, &e), BKF_OK);
            CHECK_MSG(fabs(got.period[i] - cold.period) <= 3.0 * (got.err[i] + cold.period_err),
                      "mu %.17g nu %.17g: T %.17g cold %.17g (err %.2g) err %.2g", got.mu[i], got.nu[i],
                      got.period[i], cold.period, cold.period_err, got.err[i]);
        }
    }
    bkf_test_note("%zu rows, %zu relaxed, %zu refused, %zu checked, worst true/estimated %.2f (Taylor)", got.n,
                  relaxed, got.refused, checked, worst);
}

TEST(cycle_branch_mu_through_the_canard_at_nu_0_99)
{
    check_canard_branch(BKF_CYCLE_ALONG_MU, 0.1, 1e4, 0.99);
}

TEST(cycle_branch_mu_through_the_canard_at_nu_minus_0_99)
{
    check_canard_branch(BKF_CYCLE_ALONG_MU, 0.1, 1e4, -0.99);
}

TEST(cycle_branch_nu_through_the_canard_at_mu_3_65)
{
    check_canard_branch(BKF_CYCLE_ALONG_NU, 0.0, 0.99, 3.65);
    check_canard_branch(BKF_CYCLE_ALONG_NU, 0.0, -0.99, 3.65);
}

TEST(cycle_branch_nu_through_the_canard_at_mu_10)
{
    check_canard_branch(BKF_CYCLE_ALONG_NU, 0.0, -0.999, 10.0);
}

/* Along nu to +0.999 at mu 10: the canard (8 mu^2 (1 - nu) ~ 1 at nu
 * 0.99874045124..., ~1e-12 wide in nu) is crossed by the amplitude walk
 * from the relaxation cycle down to the small cycle, which it follows to
 * the end; before, the walk left on a noisy dG/dq and the next stretch
 * failed below step_min at nu 0.998740451246 (so did mu 8 and 11.2, whose
 * canards lie at nu 0.99802 and 0.99900, the latter next to the end). */
TEST(cycle_branch_nu_through_the_canard_at_mu_10_to_plus_0_999)
{
    check_canard_branch(BKF_CYCLE_ALONG_NU, 0.0, 0.999, 10.0);
    check_canard_branch(BKF_CYCLE_ALONG_NU, 0.0, 0.999, 8.0);
    check_canard_branch(BKF_CYCLE_ALONG_NU, 0.0, 0.999, 11.2);
}

/* Along mu through the narrow canard at nu -0.999 (mu 11.2141, ~1e-9 wide
 * in mu) up to 1e4: the amplitude walk and the mirror's shots. */
TEST(cycle_branch_mu_through_the_canard_at_nu_minus_0_999)
{
    check_canard_branch(BKF_CYCLE_ALONG_MU, 0.1, 1e4, -0.999);
}

/* The same at +0.999, where the relaxed rows inside the canard (mu
 * 11.2134..11.2141) missed the Taylor reference by up to 6.7 times their
 * estimate while the conditioning floor counted one rounding of nu instead
 * of every step's (docs/accuracy.md). */
TEST(cycle_branch_mu_through_the_canard_at_nu_0_999)
{
    check_canard_branch(BKF_CYCLE_ALONG_MU, 0.1, 1e4, 0.999);
}

static int count_rows(const bkf_cycle_result *r, void *data)
{
    (void)r;
    ++*(size_t *)data;
    return 0;
}

/* At the box's edge |nu| = 0.9999 the canard explosion (mu 35.3659) is
 * thinner than an ulp of mu: the shooting rows crept at 1e-7 of mu a row,
 * every row relaxed or refused, and `period --mu 0.1:1e4:9 --log --nu
 * 0.9999 --continue mu` failed after 20-26 minutes.  Now the branch counts
 * the rows that miss tol in a row and, stuck, steps over the explosion by
 * collocation rows (cycle.c, branch_hop).  Every row against the
 * long-double Taylor reference (fast here: 0.1 s a row), none relaxed (the
 * rows that miss tol are refused at this nu), the rows past the explosion
 * within tol, and
 * T's jump from the small cycle to the relaxation cycle with a canard head
 * (T 12.4 -> 113) between two consecutive rows. */
static void check_over_the_explosion(double nu)
{
    static canard_rows got;
    memset(&got, 0, sizeof got);
    bkf_cycle_options o = bkf_cycle_options_default();
    bkf_error e;
    int rc = bkf_cycle_branch(BKF_CYCLE_ALONG_MU, 25.0, 40.0, nu, &o, 0, collect_canard, &got, &e);
    CHECK_MSG(rc == BKF_OK, "%s", e.message);
    if (rc != BKF_OK || got.n < 2) return;
    CHECK_CLOSE(got.mu[got.n - 1], 40.0, 1e-12, 0.0);
    size_t jumps = 0, past = 0;
    double worst = 0.0, worst_relaxed = 0.0, worst_shot = 0.0;
    for (size_t i = 0; i < got.n; i++) {
        if (i) CHECK(got.mu[i] > got.mu[i - 1]);
        if (i && got.period[i] > 100.0 && got.period[i - 1] < 20.0) jumps++;
        if (got.period[i] > 100.0) {
            past++;
            /* past the explosion every row meets tol */
            CHECK_MSG(!got.relaxed[i] && got.err[i] <= o.tol * got.period[i], "mu %.17g: err %.2g", got.mu[i],
                      got.err[i]);
        }
        double unc, ref = taylor_period(got.mu[i], got.nu[i], got.slope[i], &unc);
        CHECK_MSG(unc <= fmax(1e-12 * ref, 0.1 * got.err[i]), "mu %.17g: reference uncertainty %.2g", got.mu[i], unc);
        double ratio = fabs(got.period[i] - ref) / got.err[i];
        if (got.period[i] > 100.0) {
            /* the collocation rows past the explosion: within their estimates */
            CHECK_MSG(fabs(got.period[i] - ref) <= 3.0 * got.err[i] + unc,
                      "mu %.17g nu %g: T %.17g ref %.17g err %.2g", got.mu[i], nu, got.period[i], ref, got.err[i]);
            worst = fmax(worst, ratio);
        } else if (!got.relaxed[i]) {
            /* the shooting rows before it meet tol, their estimates honest
             * within the trust factor 3 (flattered by up to 3.2 at mu 28.4
             * before the stiff pair's floor in the canard's neighbourhood) */
            CHECK_MSG(fabs(got.period[i] - ref) <= o.tol * ref + unc, "mu %.17g nu %g: T %.17g ref %.17g",
                      got.mu[i], nu, got.period[i], ref);
            double shot_ratio = fmax(fabs(got.period[i] - ref) - unc, 0.0) / got.err[i];
            CHECK_MSG(shot_ratio <= 3.0, "mu %.17g nu %g: shooting row optimistic by %.3g", got.mu[i], nu, shot_ratio);
            worst_shot = fmax(worst_shot, shot_ratio);
        } else {
            /* no relaxed row beyond |nu| 0.999: the creep's missed the
             * reference by up to 114 times their estimates */
            worst_relaxed = fmax(worst_relaxed, ratio);
        }
    }
    CHECK_MSG(worst_relaxed == 0.0, "nu %g: relaxed rows, worst true/estimated %.3g", nu, worst_relaxed);
    CHECK(jumps == 1);
    CHECK(past >= 5);
    bkf_test_note("nu %g: %zu rows (%zu past the explosion), %zu refused, worst true/estimated %.2f past it, %.2f "
                  "before it (shooting)",
                  nu, got.n, past, got.refused, worst, worst_shot);
}

TEST(cycle_branch_mu_over_the_canard_at_nu_0_9999)
{
    check_over_the_explosion(0.9999);
    check_over_the_explosion(-0.9999);
}

/* Where the branch cannot step over the explosion (along mu towards it
 * from the relaxation side, where the rows would have to find the small
 * cycle) it fails within seconds, naming where, not after 20 minutes. */
TEST(cycle_branch_stuck_in_the_canard_fails_fast)
{
    bkf_cycle_options o = bkf_cycle_options_default();
    bkf_error e;
    size_t rows = 0;
    int rc = bkf_cycle_branch(BKF_CYCLE_ALONG_MU, 36.0, 35.0, 0.9999, &o, 0, count_rows, &rows, &e);
    CHECK_STATUS(rc, BKF_ENUMERIC);
    CHECK_MSG(strstr(e.message, "stuck at mu = 35.36") && strstr(e.message, "nu = 0.9999"), "%s", e.message);
    CHECK(rows >= 20);
}

/* From the relaxation side at nu 0.9999, tol 1e-7, the shooting stretch
 * stopped at mu 35.37625 and the amplitude walk's first step, on a dG/dq
 * of the wrong sign there, found its root behind the last row (mu 36.11,
 * before the branch's start at 36) and walked back up to mu 145, visiting
 * those rows; the next stretch was refused as bad input (EINPUT, exit 2 in
 * `period --continue mu`).  The first 16 rows: none outside [35, 36], none
 * behind the lowest mu so far by more than the walk's noise band (1e-6 of
 * ln mu), and T at the last row
 * before the walk's crossing, the first after it and the last against the
 * long-double Taylor reference, within three times the rows' estimates. */
TEST(cycle_branch_walk_stays_inside_its_stretch)
{
    static canard_rows got;
    memset(&got, 0, sizeof got);
    bkf_cycle_options o = bkf_cycle_options_default();
    o.tol = 1e-7;
    bkf_error e;
    int rc = bkf_cycle_branch(BKF_CYCLE_ALONG_MU, 36.0, 35.0, 0.9999, &o, 16, collect_canard, &got, &e);
    CHECK_MSG(rc == BKF_OK, "%s", e.message);
    CHECK_MSG(got.n == 16 && got.refused == 0, "%zu rows, %zu refused", got.n, got.refused);
    size_t jump = 0;
    double front = 36.0;
    for (size_t i = 0; i < got.n; i++) {
        CHECK_MSG(got.mu[i] >= 35.0 && got.mu[i] <= 36.0, "row %zu at mu %.17g", i, got.mu[i]);
        CHECK_MSG(got.mu[i] <= front * (1.0 + 4e-6), "row %zu at mu %.17g, behind %.17g", i, got.mu[i], front);
        front = fmin(front, got.mu[i]);
        if (i && got.period[i] < 0.5 * got.period[i - 1]) jump = i;
    }
    CHECK_MSG(jump > 0 && jump + 1 < got.n, "the rows crossed no explosion (%zu)", jump);
    size_t rows[3] = {jump - 1, jump, got.n - 1};
    for (size_t k = 0; k < 3 && jump; k++) {
        size_t i = rows[k];
        double unc, ref = taylor_period(got.mu[i], got.nu[i], got.slope[i], &unc);
        CHECK_MSG(fabs(got.period[i] - ref) <= 3.0 * got.err[i] + unc,
                  "mu %.17g: T %.17g ref %.17g (unc %.2g) err %.2g", got.mu[i], got.period[i], ref, unc, got.err[i]);
        CHECK(got.err[i] <= o.tol * got.period[i]);
    }
}


/* Towards nu -0.999 at mu >= 1e3 the direct shots' steps shrank to 1e-12
 * near -0.9982 and spent the driver's 10000 rows (60 s); the branch's shots
 * are now the mirror image's (T(mu, -nu) = T(mu, nu)), and one that crosses
 * nu = 0 is split there.  Every row against a cold solve at its own nu
 * (the direct problem, not its mirror), the crossing's rows in order with
 * nu = 0 once, and a row cap that counts both halves. */
TEST(cycle_branch_nu_to_minus_0_999_at_large_mu)
{
    check_branch(BKF_CYCLE_ALONG_NU, 0.0, -0.999, 1000.0);
    check_branch(BKF_CYCLE_ALONG_NU, 0.5, -0.999, 1e4);
    check_branch(BKF_CYCLE_ALONG_NU, -0.9999, 0.3, 300.0);
    bkf_cycle_options o = bkf_cycle_options_default();
    bkf_error e;
    size_t rows = 0;
    CHECK_STATUS(bkf_cycle_branch(BKF_CYCLE_ALONG_NU, 0.9, -0.9, 1000.0, &o, 12, count_rows, &rows, &e), BKF_OK);
    CHECK(rows == 12);
}

/* Collocation rows (stepper collocation, outside the canard): every such
 * row against an independent shooting solve at tol 1e-12 (rk8pd up to mu
 * 20, bd2x2 or bsimp above), the true error within the row's own
 * estimate; every row outside the canard band 8 mu^2 (1 - |nu|) in
 * [0.2, 5] (mu >= 1) by collocation; the rows' count bounded (the steps
 * collapsed to 0.02 in ln mu at nu -0.96: 739 rows); their work against
 * cold collocation solves at the same points, in the same counter on both
 * sides (condensed interval solves and the extremes' steps: a row above mu
 * 2 is the cold solve's turns and pair from a predicted section point, a
 * row below it Newton on a path, whose turns neither side counts). */
typedef struct {
    double mu[512], nu[512], period[512], err[512];
    size_t steps[512], n, colloc, outside, outside_colloc, handbacks;
    int last_colloc;
} colloc_rows;

static int outside_canard_band(double mu, double nu)
{
    double x = 8.0 * mu * mu * (1.0 - fabs(nu));
    return mu < 1.0 || x < 0.2 || x > 5.0;
}

static int collect_colloc(const bkf_cycle_result *r, void *data)
{
    colloc_rows *c = data;
    int is_colloc = !strcmp(r->stepper, "colloc");
    if (c->n && is_colloc && !c->last_colloc) c->handbacks++;
    c->last_colloc = is_colloc;
    if (outside_canard_band(r->mu, r->nu)) {
        c->outside++;
        c->outside_colloc += is_colloc;
    }
    if (c->n < 512 && is_colloc) {
        c->mu[c->colloc] = r->mu;
        c->nu[c->colloc] = r->nu;
        c->period[c->colloc] = r->period;
        c->err[c->colloc] = r->period_err;
        c->steps[c->colloc] = r->steps;
        c->colloc++;
    }
    c->n++;
    return 0;
}

static void check_branch_rows(bkf_cycle_param along, double from, double to, double fixed, double work_bound,
                              size_t max_rows, bkf_stepper_kind stepper)
{
    static colloc_rows got;
    memset(&got, 0, sizeof got);
    bkf_cycle_options o = bkf_cycle_options_default();
    o.stepper = stepper;
    bkf_error e;
    int rc = bkf_cycle_branch(along, from, to, fixed, &o, 0, collect_colloc, &got, &e);
    CHECK_MSG(rc == BKF_OK, "%s", e.message);
    CHECK_MSG(got.n <= max_rows, "%zu rows (bound %zu)", got.n, max_rows);
    /* (the shooting row at which the branch hands back to collocation
     * after the band lies outside it) */
    CHECK_MSG(got.outside_colloc + got.handbacks >= got.outside,
              "%zu of %zu rows outside the canard by collocation, %zu hand-backs", got.outside_colloc, got.outside,
              got.handbacks);
    double worst = 0.0;
    size_t row_steps = 0, cold_steps = 0;
    for (size_t i = 0; i < got.colloc; i++) {
        bkf_cycle_options ref = o;
        ref.tol = 1e-12;
        ref.stepper = got.mu[i] <= BKF_CYCLE_STIFF_MU ? BKF_STEPPER_EXPLICIT : BKF_STEPPER_EXTRAPOLATION;
        bkf_cycle_result r, cold;
        int rrc = bkf_cycle_period(got.mu[i], got.nu[i], &ref, &r, &e);
        if (rrc != BKF_OK) {
            ref.stepper = BKF_STEPPER_IMPLICIT;
            rrc = bkf_cycle_period(got.mu[i], got.nu[i], &ref, &r, &e);
        }
        CHECK_STATUS(rrc, BKF_OK);
        CHECK(got.err[i] <= o.tol * got.period[i]);
        double ratio = (fabs(got.period[i] - r.period) - r.period_err) / got.err[i];
        CHECK_MSG(ratio <= 1.0, "mu %.17g nu %.17g: T %.17g (err %.2g) reference %.17g (err %.2g)", got.mu[i],
                  got.nu[i], got.period[i], got.err[i], r.period, r.period_err);
        worst = fmax(worst, ratio);
        CHECK_STATUS(bkf_cycle_period(got.mu[i], got.nu[i], &o, &cold, &e), BKF_OK);
        if (strcmp(cold.stepper, "colloc")) continue;
        cold_steps += cold.steps;
        row_steps += got.steps[i];
    }
    double work = (double)row_steps / (double)cold_steps;
    CHECK_MSG(work <= work_bound, "rows cost %.2f cold collocation solves each (bound %.2f)", work, work_bound);
    bkf_test_note("%zu rows (%zu colloc), worst true/estimated %.2f, %.2f cold collocation solves a row", got.n,
                  got.colloc, worst, work);
}

static void check_colloc_branch(bkf_cycle_param along, double from, double to, double fixed, double work_bound,
                                size_t max_rows)
{
    check_branch_rows(along, from, to, fixed, work_bound, max_rows, BKF_STEPPER_COLLOCATION);
}

/* The automatic rows at tol 1e-10 are collocation rows (no canard band at
 * nu 0; along nu at mu 30 the band lies beyond |nu| 0.9), at nu -0.96 also
 * before the band (mu 1 to 3.95): only from |nu| 0.99, where the amplitude
 * walk must cross the explosion, do the rows before it shoot */
TEST(cycle_branch_automatic_rows_are_collocation)
{
    check_branch_rows(BKF_CYCLE_ALONG_MU, 0.1, 1e4, 0.0, 1.5, 60, BKF_STEPPER_AUTO);
    check_branch_rows(BKF_CYCLE_ALONG_MU, 0.1, 1e4, -0.96, 1.5, 60, BKF_STEPPER_AUTO);
    check_branch_rows(BKF_CYCLE_ALONG_NU, -0.9, 0.9, 30.0, 1.5, 50, BKF_STEPPER_AUTO);
}

/* A branch's rows do not depend on what the heap held before: with one
 * row on the collocation path its prediction read the other row's
 * uninitialised arrays (0 times NaN), and after Python had imported scipy
 * the rows up to mu 2 fell back to shooting, 5 times the time.  Blocks of
 * many sizes are filled with NaN and freed first, so the path's arrays are
 * likely to be carved from them. */
TEST(cycle_branch_colloc_rows_ignore_the_heap_contents)
{
    enum { SIZES = 48, EACH = 4 };
    void *blocks[SIZES * EACH];
    size_t k = 0;
    for (size_t i = 0, size = 64; i < SIZES; i++, size = size * 5 / 4)
        for (int j = 0; j < EACH; j++) {
            double *p = malloc(size);
            if (p)
                for (size_t w = 0; w < size / sizeof *p; w++) p[w] = NAN;
            blocks[k++] = p;
        }
    while (k) free(blocks[--k]);
    check_branch_rows(BKF_CYCLE_ALONG_MU, 0.5, 10.0, 0.0, 1.5, 60, BKF_STEPPER_AUTO);
}

/* At nu 0.5 a shooting step crosses the band (mu in [1, 1.12]) whole: the
 * rows after it must come back to collocation (they stayed warm-started
 * solves on meshes grown row by row, 21 ms a row at mu 1e4) */
TEST(cycle_branch_colloc_rows_back_after_the_band_at_nu_0_5)
{
    check_colloc_branch(BKF_CYCLE_ALONG_MU, 0.1, 1e4, 0.5, 1.5, 60);
}

/* (5 decades of mu: at most 12 rows a decade) */
TEST(cycle_branch_colloc_rows_along_mu)
{
    check_colloc_branch(BKF_CYCLE_ALONG_MU, 0.1, 1e4, 0.0, 1.5, 60);
}

/* nu < 0: the rows are the mirror's at -nu (the section mid-jump) */
TEST(cycle_branch_colloc_rows_along_mu_at_nu_minus_0_96)
{
    check_colloc_branch(BKF_CYCLE_ALONG_MU, 0.1, 1e4, -0.96, 1.5, 60);
}

TEST(cycle_branch_colloc_rows_along_nu)
{
    check_colloc_branch(BKF_CYCLE_ALONG_NU, -0.9, 0.9, 10.0, 1.5, 50);
}

/* at mu 100 the branch runs as two halves meeting at 0, the first the
 * mirror's (112 rows at 11 ms each before the rows followed the layers) */
TEST(cycle_branch_colloc_rows_along_nu_at_mu_100)
{
    check_colloc_branch(BKF_CYCLE_ALONG_NU, -0.9, 0.9, 100.0, 1.5, 50);
}

typedef struct {
    size_t n, colloc, bad_tol;
    double worst;
} taylor_rows;

static int collect_against_taylor(const bkf_cycle_result *r, void *data)
{
    taylor_rows *t = data;
    t->n++;
    t->colloc += !strcmp(r->stepper, "colloc");
    double unc, ref = taylor_period(r->mu, r->nu, r->section_slope, &unc);
    double err = fabs(r->period - ref);
    if (err > 1e-10 * r->period + unc) t->bad_tol++;
    t->worst = fmax(t->worst, fmax(err - unc, 0.0) / r->period_err);
    return 0;
}

static taylor_rows branch_against_taylor(bkf_cycle_param along, double from, double to, double fixed)
{
    taylor_rows t = {0};
    bkf_cycle_options o = bkf_cycle_options_default();
    bkf_error e;
    int rc = bkf_cycle_branch(along, from, to, fixed, &o, 0, collect_against_taylor, &t, &e);
    CHECK_MSG(rc == BKF_OK, "%s", e.message);
    CHECK_MSG(t.bad_tol == 0, "%zu rows beyond tol", t.bad_tol);
    CHECK_MSG(t.worst <= 1.0, "%s %g..%g at %g: true/estimated %.3g", along == BKF_CYCLE_ALONG_MU ? "mu" : "nu", from,
              to, fixed, t.worst);
    return t;
}

/* Up to |nu| 0.98 the canard explosion is mild (mu <= 5.6) and the
 * automatic rows through it are collocation rows too, along mu at nu < 0
 * the mirror's (before, the band's rows shot: at nu -0.96 17 rows over
 * [1, 10] at 290 us each, now 9 at about 100): every row within tol of the
 * Taylor reference, its estimate honest.  Along nu the rows at nu < 0 in
 * the band are not mirrored and shoot; at nu > 0 they are collocation's. */
TEST(cycle_branch_colloc_rows_through_a_mild_canard)
{
    const double nus[] = {-0.96, 0.97, -0.98};
    double worst = 0.0;
    for (size_t i = 0; i < sizeof nus / sizeof nus[0]; i++) {
        taylor_rows t = branch_against_taylor(BKF_CYCLE_ALONG_MU, 1.0, 10.0, nus[i]);
        CHECK_MSG(t.colloc == t.n, "nu %g: %zu of %zu rows by collocation", nus[i], t.colloc, t.n);
        worst = fmax(worst, t.worst);
    }
    taylor_rows up = branch_against_taylor(BKF_CYCLE_ALONG_NU, 0.0, 0.98, 2.0);
    CHECK_MSG(up.colloc == up.n, "nu 0 -> 0.98 at mu 2: %zu of %zu rows by collocation", up.colloc, up.n);
    taylor_rows down = branch_against_taylor(BKF_CYCLE_ALONG_NU, 0.0, -0.98, 2.0);
    CHECK_MSG(down.colloc < down.n, "nu 0 -> -0.98 at mu 2: every row by collocation");
    bkf_test_note("worst true/estimated %.2f along mu, %.2f and %.2f along nu", worst, up.worst, down.worst);
}

typedef struct {
    size_t n, past, jumps, bad_tol;
    double last_T, worst;
} hop_rows;

static int collect_hop(const bkf_cycle_result *r, void *data)
{
    hop_rows *h = data;
    h->n++;
    if (!isfinite(r->period)) return 0;
    if (r->period > 30.0 && h->last_T < 20.0) h->jumps++;
    h->last_T = r->period;
    if (r->period <= 30.0) return 0;
    /* past the explosion: the hop's collocation rows and those after */
    h->past++;
    double unc, ref = taylor_period(r->mu, r->nu, r->section_slope, &unc);
    double err = fabs(r->period - ref);
    /* (a relaxed row says by how much it misses tol) */
    if (err > 1e-10 * r->period + unc && strcmp(r->model, "shooting-relaxed")) h->bad_tol++;
    h->worst = fmax(h->worst, fmax(err - unc, 0.0) / r->period_err);
    return 0;
}

/* With collocation asked for, the amplitude walk found no root of G in the
 * explosion at nu 0.999 (mu 11.2141) and the branch failed; it now goes
 * over it as a stuck branch does (branch_hop), the hop's rows estimated by
 * their pair's whole difference (one was 1.12 times its sixteenth off).
 * Every row past the explosion against the Taylor reference (its first,
 * at the walk's last root, is a relaxed shooting row). */
TEST(cycle_branch_collocation_over_the_canard_at_nu_0_999)
{
    bkf_cycle_options o = bkf_cycle_options_default();
    o.stepper = BKF_STEPPER_COLLOCATION;
    hop_rows h = {.last_T = 0.0};
    bkf_error e;
    int rc = bkf_cycle_branch(BKF_CYCLE_ALONG_MU, 5.0, 15.0, 0.999, &o, 0, collect_hop, &h, &e);
    CHECK_MSG(rc == BKF_OK, "%s", e.message);
    CHECK(h.jumps == 1);
    CHECK(h.past >= 5);
    CHECK_MSG(h.bad_tol == 0, "%zu rows past the explosion beyond tol", h.bad_tol);
    CHECK_MSG(h.worst <= 1.0, "worst true/estimated %.3g past the explosion", h.worst);
    bkf_test_note("%zu rows, %zu past the explosion, worst true/estimated %.2f there", h.n, h.past, h.worst);
}

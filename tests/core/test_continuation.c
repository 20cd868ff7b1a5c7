/* The continuation driver against branches known in closed form: a circle
 * (one fold each way), an S-curve (two folds, then a bound), a two-equation
 * system (no folds), and the ways a run must end. */
#include "harness.h"

#include <string.h>

#include "bkfront/continuation.h"

#define MAX_RECORD 4096

typedef struct {
    size_t count;
    double u[MAX_RECORD][3];
    double t[MAX_RECORD][3];
    int is_fold[MAX_RECORD];
    size_t dim;            /* n + 1 */
    size_t stop_after_folds; /* 0: never */
    size_t folds_seen;
    size_t stop_after_points; /* 0: never */
} record;

static int record_point(const double *u, const double *t, int is_fold, void *data)
{
    record *r = data;
    if (r->count < MAX_RECORD) {
        for (size_t i = 0; i < r->dim; i++) {
            r->u[r->count][i] = u[i];
            r->t[r->count][i] = t[i];
        }
        r->is_fold[r->count] = is_fold;
        r->count++;
    }
    if (is_fold) r->folds_seen++;
    if (r->stop_after_folds && r->folds_seen >= r->stop_after_folds && !is_fold) return 1;
    if (r->stop_after_points && r->count >= r->stop_after_points) return 1;
    return 0;
}

static record *new_record(size_t dim)
{
    record *r = calloc(1, sizeof *r);
    CHECK(r != NULL);
    r->dim = dim;
    return r;
}

/* u = (x, lambda): x^2 + lambda^2 - 1 */
static int circle(const double *u, double *g, double *jac, void *data, bkf_error *err)
{
    (void)data; (void)err;
    g[0] = u[0] * u[0] + u[1] * u[1] - 1.0;
    if (jac) {
        jac[0] = 2.0 * u[0];
        jac[1] = 2.0 * u[1];
    }
    return BKF_OK;
}

/* (x/a)^2 + lambda^2 - 1 with a = 1000, and no Jacobian offered: the driver
 * has to notice and difference. */
static int ellipse_nojac(const double *u, double *g, double *jac, void *data,
                         bkf_error *err)
{
    (void)jac; (void)data; (void)err;
    double x = u[0] / 1000.0;
    g[0] = x * x + u[1] * u[1] - 1.0;
    return BKF_OK;
}

/* x^3 - x - lambda */
static int scurve(const double *u, double *g, double *jac, void *data, bkf_error *err)
{
    (void)data; (void)err;
    g[0] = u[0] * u[0] * u[0] - u[0] - u[1];
    if (jac) {
        jac[0] = 3.0 * u[0] * u[0] - 1.0;
        jac[1] = -1.0;
    }
    return BKF_OK;
}

/* u = (x, y, lambda): x - cos(lambda), y - x^2 */
static int cosine_system(const double *u, double *g, double *jac, void *data,
                         bkf_error *err)
{
    (void)data; (void)err;
    g[0] = u[0] - cos(u[2]);
    g[1] = u[1] - u[0] * u[0];
    if (jac) {
        jac[0] = 1.0; jac[1] = 0.0; jac[2] = sin(u[2]);
        jac[3] = -2.0 * u[0]; jac[4] = 1.0; jac[5] = 0.0;
    }
    return BKF_OK;
}

/* x - lambda, defined only for lambda <= 0.5: the driver must shrink the
 * step against that edge until it gives up. */
static int line_undefined_beyond(const double *u, double *g, double *jac, void *data,
                                 bkf_error *err)
{
    (void)data;
    if (u[1] > 0.5) return bkf_error_set(err, BKF_ENUMERIC, "lambda > 0.5");
    g[0] = u[0] - u[1];
    if (jac) {
        jac[0] = 1.0;
        jac[1] = -1.0;
    }
    return BKF_OK;
}

/* x - lambda, with a status beyond lambda = 0.3 that must end the run. */
static int line_fatal_beyond(const double *u, double *g, double *jac, void *data,
                             bkf_error *err)
{
    (void)data;
    if (u[1] > 0.3) return bkf_error_set(err, BKF_EINPUT, "lambda beyond the model");
    g[0] = u[0] - u[1];
    if (jac) {
        jac[0] = 1.0;
        jac[1] = -1.0;
    }
    return BKF_OK;
}

TEST(cont_circle_passes_fold_at_top)
{
    record *r = new_record(2);
    r->stop_after_folds = 1;
    bkf_cont_options o = bkf_cont_options_default(1);
    bkf_cont_report rep;
    bkf_error err = {0};
    double u0[2] = {-1.0, 0.0};
    CHECK_STATUS(bkf_cont_run(circle, record_point, r, u0, 1, +1, &o, &rep, &err), BKF_OK);
    CHECK(rep.folds == 1);
    CHECK(rep.reached_bound == 0);
    CHECK(rep.points + rep.folds == r->count);
    /* the start, heading up in lambda */
    CHECK(!r->is_fold[0]);
    CHECK_CLOSE(r->u[0][0], -1.0, 0, 1e-12);
    CHECK(r->t[0][1] > 0.0);
    size_t fold = 0;
    for (size_t i = 0; i < r->count; i++) {
        double x = r->u[i][0], l = r->u[i][1];
        CHECK_CLOSE(x * x + l * l - 1.0, 0.0, 0, 1e-9);
        CHECK_CLOSE(r->t[i][0] * r->t[i][0] + r->t[i][1] * r->t[i][1], 1.0, 0, 1e-12);
        if (r->is_fold[i]) fold = i;
    }
    CHECK(fold > 0 && fold + 1 == r->count - 1);
    CHECK_CLOSE(r->u[fold][0], 0.0, 0, 1e-8);
    CHECK_CLOSE(r->u[fold][1], 1.0, 0, 1e-8);
    CHECK_CLOSE(r->t[fold][1], 0.0, 0, 1e-8);
    /* the fold sits between the regular points around it */
    CHECK(r->u[fold - 1][0] < 0.0 && r->u[fold + 1][0] > 0.0);
    bkf_test_note("%zu points, %zu Newton iterations, %zu rejected, fold at x = %.3g",
                  rep.points, rep.newton_iterations, rep.rejected_steps, r->u[fold][0]);
    free(r);
}

/* locate_folds 0: the top of the circle is passed as any point (no fold
 * visited, none counted: the run goes on round to the bottom, x > 0 of
 * the top's points); grow_iterations 1 against 4: the steps stay shorter,
 * so more points reach the same arc (lambda back to 0 on the right). */
TEST(cont_circle_without_fold_search_and_step_growth)
{
    size_t points[2];
    for (int k = 0; k < 2; k++) {
        record *r = new_record(2);
        bkf_cont_options o = bkf_cont_options_default(1);
        o.locate_folds = 0;
        o.grow_iterations = k ? 4 : 1;
        o.max_points = MAX_RECORD;
        o.stop_index = 1;
        o.stop_min = -0.5;
        o.stop_max = 2;
        bkf_cont_report rep;
        double u0[2] = {-1.0, 0.0};
        CHECK_STATUS(bkf_cont_run(circle, record_point, r, u0, 1, +1, &o, &rep, NULL), BKF_OK);
        CHECK(rep.folds == 0 && rep.reached_bound);
        for (size_t i = 0; i < r->count; i++) CHECK(!r->is_fold[i]);
        /* round the top to lambda -0.5 on the right */
        CHECK(r->u[r->count - 1][0] > 0.8 && fabs(r->u[r->count - 1][1] + 0.5) < 1e-9);
        points[k] = rep.points;
        free(r);
    }
    CHECK_MSG(points[1] < points[0], "%zu points growing after 4 iterations, %zu after 1",
              points[1], points[0]);
    bkf_cont_options o = bkf_cont_options_default(1);
    o.grow_iterations = 0;
    double u0[2] = {-1.0, 0.0};
    record *r = new_record(2);
    CHECK_STATUS(bkf_cont_run(circle, record_point, r, u0, 1, +1, &o, NULL, NULL), BKF_EINPUT);
    free(r);
}

TEST(cont_circle_direction_minus_finds_bottom_fold)
{
    record *r = new_record(2);
    r->stop_after_folds = 1;
    bkf_cont_options o = bkf_cont_options_default(1);
    double u0[2] = {-1.0, 0.0};
    CHECK_STATUS(bkf_cont_run(circle, record_point, r, u0, 1, -1, &o, NULL, NULL), BKF_OK);
    CHECK(r->t[0][1] < 0.0);
    size_t fold = 0;
    for (size_t i = 0; i < r->count; i++)
        if (r->is_fold[i]) fold = i;
    CHECK(fold > 0);
    CHECK_CLOSE(r->u[fold][0], 0.0, 0, 1e-8);
    CHECK_CLOSE(r->u[fold][1], -1.0, 0, 1e-8);
    free(r);
}

TEST(cont_scaled_ellipse_without_jacobian_goes_round)
{
    /* Three folds: top, bottom, top again; the scale makes the 1000-wide
     * ellipse a unit circle for step control. */
    record *r = new_record(2);
    r->stop_after_folds = 3;
    double scale[2] = {1000.0, 1.0};
    bkf_cont_options o = bkf_cont_options_default(1);
    o.scale = scale;
    bkf_cont_report rep;
    double u0[2] = {-1000.0, 0.0};
    CHECK_STATUS(bkf_cont_run(ellipse_nojac, record_point, r, u0, 1, +1, &o, &rep, NULL),
                 BKF_OK);
    CHECK(rep.folds == 3);
    double want[3] = {1.0, -1.0, 1.0};
    size_t k = 0;
    for (size_t i = 0; i < r->count; i++) {
        double x = r->u[i][0] / 1000.0, l = r->u[i][1];
        CHECK_CLOSE(x * x + l * l - 1.0, 0.0, 0, 1e-9);
        if (r->is_fold[i]) {
            CHECK(k < 3);
            CHECK_CLOSE(r->u[i][0], 0.0, 0, 1e-5);
            CHECK_CLOSE(r->u[i][1], want[k], 0, 1e-9);
            k++;
        }
    }
    CHECK(k == 3);
    /* about 2 pi * 1.25 of scaled arclength at <= 0.5 per step */
    CHECK(rep.points >= 16 && rep.points < 200);
    free(r);
}

TEST(cont_scurve_two_folds_then_bound)
{
    record *r = new_record(2);
    bkf_cont_options o = bkf_cont_options_default(1);
    o.stop_index = 1;
    o.stop_min = -1.0;
    o.stop_max = 1.0;
    bkf_cont_report rep;
    bkf_error err = {0};
    double u0[2] = {-1.3, -1.0}; /* root near -1.3247, corrected at lambda = -1 */
    CHECK_STATUS(bkf_cont_run(scurve, record_point, r, u0, 1, +1, &o, &rep, &err), BKF_OK);
    CHECK(rep.folds == 2);
    CHECK(rep.reached_bound == 1);
    CHECK_CLOSE(r->u[0][1], -1.0, 0, 0);
    double lf = 2.0 / (3.0 * sqrt(3.0)), xf = 1.0 / sqrt(3.0);
    size_t k = 0;
    for (size_t i = 0; i < r->count; i++) {
        double x = r->u[i][0], l = r->u[i][1];
        CHECK_CLOSE(x * x * x - x - l, 0.0, 0, 1e-9);
        CHECK(l >= -1.0 && l <= 1.0);
        if (r->is_fold[i]) {
            if (k == 0) {
                CHECK_CLOSE(l, lf, 0, 1e-10);
                CHECK_CLOSE(x, -xf, 0, 1e-8);
            } else {
                CHECK_CLOSE(l, -lf, 0, 1e-10);
                CHECK_CLOSE(x, xf, 0, 1e-8);
            }
            k++;
        }
    }
    CHECK(k == 2);
    double *last = r->u[r->count - 1];
    CHECK(!r->is_fold[r->count - 1]);
    CHECK(last[1] == 1.0);
    CHECK_CLOSE(last[0], 1.324717957244746, 1e-12, 0); /* real root of x^3 - x - 1 */
    bkf_test_note("%zu points, %zu rejected", rep.points, rep.rejected_steps);
    free(r);
}

TEST(cont_bound_reached_by_the_corrector_not_the_predictor)
{
    /* From (-1, 0) the tangent has no x component, so predictions keep x = -1
     * while the circle bends to larger x: the bound x <= -0.999 is crossed by
     * the corrected point and the run must land on it all the same. */
    record *r = new_record(2);
    bkf_cont_options o = bkf_cont_options_default(1);
    o.stop_index = 0;
    o.stop_min = -2.0;
    o.stop_max = -0.999;
    bkf_cont_report rep;
    double u0[2] = {-1.0, 0.0};
    CHECK_STATUS(bkf_cont_run(circle, record_point, r, u0, 1, +1, &o, &rep, NULL), BKF_OK);
    CHECK(rep.reached_bound == 1 && rep.folds == 0);
    double *last = r->u[r->count - 1];
    CHECK(last[0] == -0.999);
    CHECK_CLOSE(last[1], sqrt(1.0 - 0.999 * 0.999), 1e-12, 0);
    free(r);
}

static void run_cosine_system(int fd)
{
    record *r = new_record(3);
    bkf_cont_options o = bkf_cont_options_default(2);
    o.jacobian_fd = fd;
    o.stop_index = 2;
    o.stop_min = -10.0;
    o.stop_max = 3.0;
    bkf_cont_report rep;
    bkf_error err = {0};
    double u0[3] = {1.1, 0.9, 0.0}; /* off the branch: the start is corrected */
    CHECK_STATUS(bkf_cont_run(cosine_system, record_point, r, u0, 2, +1, &o, &rep, &err),
                 BKF_OK);
    CHECK(rep.folds == 0);
    CHECK(rep.reached_bound == 1);
    CHECK(r->count == rep.points);
    CHECK(r->u[0][2] == 0.0);
    for (size_t i = 0; i < r->count; i++) {
        double x = r->u[i][0], y = r->u[i][1], l = r->u[i][2];
        CHECK_CLOSE(x, cos(l), 0, 1e-9);
        CHECK_CLOSE(y, cos(l) * cos(l), 0, 1e-9);
        if (i > 0) CHECK(l > r->u[i - 1][2]);
        /* the tangent of (cos l, cos^2 l, l), normalised */
        double d[3] = {-sin(l), -2.0 * sin(l) * cos(l), 1.0};
        double nd = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        for (int j = 0; j < 3; j++) CHECK_CLOSE(r->t[i][j], d[j] / nd, 0, 1e-6);
    }
    CHECK(r->u[r->count - 1][2] == 3.0);
    bkf_test_note("fd = %d: %zu points, %zu Newton iterations", fd, rep.points,
                  rep.newton_iterations);
    free(r);
}

TEST(cont_two_equations_analytic_jacobian) { run_cosine_system(0); }

TEST(cont_two_equations_finite_differences) { run_cosine_system(1); }

TEST(cont_numeric_failure_says_where)
{
    record *r = new_record(2);
    bkf_cont_options o = bkf_cont_options_default(1);
    bkf_cont_report rep;
    bkf_error err = {0};
    double u0[2] = {0.0, 0.0};
    CHECK_STATUS(bkf_cont_run(line_undefined_beyond, record_point, r, u0, 1, +1, &o, &rep, &err),
                 BKF_ENUMERIC);
    CHECK(strstr(err.message, "step_min") != NULL);
    CHECK_MSG(strstr(err.message, "u[1] = 0.4999999") != NULL, "message: %s", err.message);
    CHECK(strstr(err.message, "lambda > 0.5") != NULL);
    CHECK(rep.rejected_steps > 0);
    for (size_t i = 0; i < r->count; i++) CHECK(r->u[i][1] <= 0.5);
    bkf_test_note("%s", err.message);
    free(r);
}

TEST(cont_fatal_residual_status_stops_run)
{
    record *r = new_record(2);
    bkf_cont_options o = bkf_cont_options_default(1);
    bkf_error err = {0};
    double u0[2] = {0.0, 0.0};
    CHECK_STATUS(bkf_cont_run(line_fatal_beyond, record_point, r, u0, 1, +1, &o, NULL, &err),
                 BKF_EINPUT);
    CHECK(strcmp(err.message, "lambda beyond the model") == 0);
    CHECK(r->count > 0);
    for (size_t i = 0; i < r->count; i++) CHECK(r->u[i][1] <= 0.3);
    free(r);
}

static int stop_at_third(const double *u, const double *t, int is_fold, void *data)
{
    (void)u; (void)t; (void)is_fold;
    int *calls = data;
    return ++*calls >= 3;
}

TEST(cont_accept_nonzero_and_max_points_stop_run)
{
    bkf_cont_options o = bkf_cont_options_default(1);
    bkf_cont_report rep;
    double u0[2] = {-1.0, 0.0};
    int calls = 0;
    CHECK_STATUS(bkf_cont_run(circle, stop_at_third, &calls, u0, 1, +1, &o, &rep, NULL),
                 BKF_OK);
    CHECK(calls == 3 && rep.points == 3);

    record *r = new_record(2);
    o.max_points = 5;
    CHECK_STATUS(bkf_cont_run(circle, record_point, r, u0, 1, +1, &o, &rep, NULL), BKF_OK);
    CHECK(rep.points == 5 && r->count == 5 && rep.reached_bound == 0);
    free(r);
}

TEST(cont_invalid_arguments)
{
    double u0[2] = {-1.0, 0.0};
    double bad_u0[2] = {NAN, 0.0};
    double bad_scale[2] = {1.0, 0.0};
    bkf_error err;
    record *r = new_record(2);
    bkf_cont_options ok = bkf_cont_options_default(1), o;

#define EXPECT_EINPUT(call, word)                                              \
    do {                                                                       \
        err.message[0] = '\0';                                                 \
        CHECK_STATUS(call, BKF_EINPUT);                                        \
        CHECK_MSG(strstr(err.message, word) != NULL, "message '%s' lacks '%s'", \
                  err.message, word);                                          \
    } while (0)

    EXPECT_EINPUT(bkf_cont_run(NULL, record_point, r, u0, 1, 1, &ok, NULL, &err), "residual");
    EXPECT_EINPUT(bkf_cont_run(circle, NULL, r, u0, 1, 1, &ok, NULL, &err), "accept");
    EXPECT_EINPUT(bkf_cont_run(circle, record_point, r, NULL, 1, 1, &ok, NULL, &err), "u0");
    EXPECT_EINPUT(bkf_cont_run(circle, record_point, r, u0, 1, 1, NULL, NULL, &err), "options");
    EXPECT_EINPUT(bkf_cont_run(circle, record_point, r, bad_u0, 1, 1, &ok, NULL, &err), "u0[0]");
    EXPECT_EINPUT(bkf_cont_run(circle, record_point, r, u0, 2, 1, &ok, NULL, &err), "dir_index");
    EXPECT_EINPUT(bkf_cont_run(circle, record_point, r, u0, -1, 1, &ok, NULL, &err), "dir_index");
    EXPECT_EINPUT(bkf_cont_run(circle, record_point, r, u0, 1, 0, &ok, NULL, &err), "direction");
    EXPECT_EINPUT(bkf_cont_run(circle, record_point, r, u0, 1, 2, &ok, NULL, &err), "direction");
    o = ok; o.n = 0;
    EXPECT_EINPUT(bkf_cont_run(circle, record_point, r, u0, 1, 1, &o, NULL, &err), "n = 0");
    o = ok; o.step_min = 0.0;
    EXPECT_EINPUT(bkf_cont_run(circle, record_point, r, u0, 1, 1, &o, NULL, &err), "step_min");
    o = ok; o.step_max = 1e-12;
    EXPECT_EINPUT(bkf_cont_run(circle, record_point, r, u0, 1, 1, &o, NULL, &err), "step_max");
    o = ok; o.step_initial = 1.0;
    EXPECT_EINPUT(bkf_cont_run(circle, record_point, r, u0, 1, 1, &o, NULL, &err), "step_initial");
    o = ok; o.step_initial = NAN;
    EXPECT_EINPUT(bkf_cont_run(circle, record_point, r, u0, 1, 1, &o, NULL, &err), "step_initial");
    o = ok; o.newton_tol = -1.0;
    EXPECT_EINPUT(bkf_cont_run(circle, record_point, r, u0, 1, 1, &o, NULL, &err), "newton_tol");
    o = ok; o.newton_max_iter = 0;
    EXPECT_EINPUT(bkf_cont_run(circle, record_point, r, u0, 1, 1, &o, NULL, &err), "newton_max_iter");
    o = ok; o.max_points = 0;
    EXPECT_EINPUT(bkf_cont_run(circle, record_point, r, u0, 1, 1, &o, NULL, &err), "max_points");
    o = ok; o.scale = bad_scale;
    EXPECT_EINPUT(bkf_cont_run(circle, record_point, r, u0, 1, 1, &o, NULL, &err), "scale[1]");
    o = ok; o.stop_index = 2;
    EXPECT_EINPUT(bkf_cont_run(circle, record_point, r, u0, 1, 1, &o, NULL, &err), "stop_index");
    o = ok; o.stop_index = 1; o.stop_min = 1.0; o.stop_max = 0.0;
    EXPECT_EINPUT(bkf_cont_run(circle, record_point, r, u0, 1, 1, &o, NULL, &err), "stop_min");
    o = ok; o.stop_index = 1; o.stop_min = 0.5; o.stop_max = 0.9;
    EXPECT_EINPUT(bkf_cont_run(circle, record_point, r, u0, 1, 1, &o, NULL, &err), "u0[stop_index");
#undef EXPECT_EINPUT
    CHECK(r->count == 0);
    free(r);
}

TEST(cont_options_default_values)
{
    bkf_cont_options o = bkf_cont_options_default(3);
    CHECK(o.n == 3);
    CHECK(o.step_initial == 0.05 && o.step_min == 1e-10 && o.step_max == 0.5);
    CHECK(o.newton_tol == 1e-10 && o.newton_max_iter == 8);
    CHECK(o.max_points == 10000 && o.scale == NULL && o.jacobian_fd == 0);
    CHECK(o.stop_index == -1);
}

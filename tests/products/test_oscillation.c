/* The oscillation product (floquet) through the library: the allowed modes
 * of a finite domain against 2 pi j/S, the dispersion's rows merged with
 * them, and the same rows as the executable in every mode. */
#include "products_support.h"

#include <math.h>

#include "bkfront/oscillation.h"

#define TWO_PI 6.28318530717958647692528676655900577

static int write_oscillation(const void *spec, FILE *out, bkf_io_format format,
                             const bkf_provenance *prov, bkf_error *err)
{
    return bkf_oscillation_write(spec, out, format, prov, err);
}

static void set_q(bkf_oscillation_spec *s, const char *text)
{
    bkf_error e;
    CHECK_MSG(bkf_list_parse(text, 0, 0, 0, "", "q", &s->q, &e) == BKF_OK, "%s", e.message);
}

TEST(products_allowed_modes_are_2_pi_j_over_S)
{
    bkf_error e;
    double *m;
    size_t n;
    /* S = 7 on [0, 6]: j = 0 .. floor(6 * 7 / (2 pi)) = 6 */
    CHECK_STATUS(bkf_oscillation_modes(7, 0, 6, 100, &m, &n, &e), BKF_OK);
    CHECK_MSG(n == 7, "%zu modes", n);
    for (size_t j = 0; j < n; j++) CHECK_CLOSE(m[j], TWO_PI * (double)j / 7, 1e-15, 0);
    free(m);
    /* downward range: the same modes, largest first; ends that are modes
     * are included */
    double a = 3 * TWO_PI / 5, b = TWO_PI / 5;
    CHECK_STATUS(bkf_oscillation_modes(5, a, b, 100, &m, &n, &e), BKF_OK);
    CHECK_MSG(n == 3, "%zu modes", n);
    for (size_t j = 0; j < n; j++) CHECK_CLOSE(m[j], TWO_PI * (double)(3 - j) / 5, 1e-15, 0);
    free(m);
    /* none between two modes */
    CHECK_STATUS(bkf_oscillation_modes(5, 0.1, 1.2, 100, &m, &n, &e), BKF_OK);
    CHECK(n == 0 && m == NULL);
    /* refusals */
    CHECK_STATUS(bkf_oscillation_modes(0, 0, 1, 100, &m, &n, &e), BKF_EINPUT);
    CHECK_STATUS(bkf_oscillation_modes(1e6, 0, 100, 1000, &m, &n, &e), BKF_EINPUT);
    CHECK_MSG(strstr(e.message, "more than 1000"), "%s", e.message);
}

TEST(products_dispersion_rows_merge_the_modes)
{
    const double q[] = {0, 0.5, 1, 1.5, 2};
    double *rows;
    unsigned char *allowed;
    size_t n;
    bkf_error e;
    /* S = 2 pi: modes 0, 1, 2 coincide with grid points (marked, not
     * repeated) */
    CHECK_STATUS(bkf_oscillation_rows(q, 5, TWO_PI, &rows, &allowed, &n, &e), BKF_OK);
    CHECK_MSG(n == 5, "%zu rows", n);
    for (size_t i = 0; i < n; i++) {
        CHECK(rows[i] == q[i]);
        CHECK(allowed[i] == (i % 2 == 0));
    }
    free(rows);
    free(allowed);
    /* S = 4: modes pi/2 j between: 0 (on the grid), 1.5708, 3.14 is beyond */
    CHECK_STATUS(bkf_oscillation_rows(q, 5, 4, &rows, &allowed, &n, &e), BKF_OK);
    CHECK_MSG(n == 6, "%zu rows", n);
    size_t modes = 0;
    for (size_t i = 0; i < n; i++) {
        if (i) CHECK(rows[i] > rows[i - 1]);
        if (allowed[i]) {
            modes++;
            double j = rows[i] * 4 / TWO_PI;
            CHECK_CLOSE(j, round(j), 0, 1e-12);
        }
    }
    CHECK(modes == 2);
    free(rows);
    free(allowed);
    /* no S: the grid alone */
    CHECK_STATUS(bkf_oscillation_rows(q, 5, NAN, &rows, &allowed, &n, &e), BKF_OK);
    CHECK(n == 5);
    free(rows);
    free(allowed);
}

typedef struct {
    size_t rows, allowed, refused;
    double S;
} visit_count;

static int count_row(const bkf_oscillation_row *row, void *data)
{
    visit_count *c = data;
    c->rows++;
    c->refused += row->refused != 0;
    if (row->allowed == 1) {
        c->allowed++;
        double j = row->point.q * c->S / TWO_PI;
        CHECK_CLOSE(j, round(j), 0, 1e-9);
    }
    CHECK(row->allowed >= 0);
    if (!row->refused) CHECK(row->point.lambda_err <= 1e-10);
    return 0;
}

TEST(products_dispersion_library_rows_are_the_cli_rows)
{
    bkf_oscillation_spec s = bkf_oscillation_spec_default();
    s.gamma = 2;
    s.c = 0.3;
    s.nu = -0.92;
    set_q(&s, "0:6:25");
    CHECK(check_same_rows(write_oscillation, &s,
                          "floquet --gamma 2 --c 0.3 --nu -0.92 --q 0:6:25") == 25);
    s.S = 7;
    CHECK(check_same_rows(write_oscillation, &s,
                          "floquet --gamma 2 --c 0.3 --nu -0.92 --q 0:6:25 --S 7") == 31);
    /* the visitor sees the same rows, the 7 allowed modes among them */
    visit_count c = {0, 0, 0, 7};
    bkf_error e;
    bkf_cycle_result cycle;
    CHECK_STATUS(bkf_oscillation_dispersion(&s, count_row, &c, &cycle, &e), BKF_OK);
    CHECK(c.rows == 31 && c.allowed == 7);
    CHECK(cycle.period > 0);
    bkf_oscillation_spec_free(&s);
}

TEST(products_threshold_and_diagram_library_rows_are_the_cli_rows)
{
    bkf_oscillation_spec s = bkf_oscillation_spec_default();
    s.gamma = 2;
    s.c = 0.3;
    s.threshold = 1;
    CHECK(check_same_rows(write_oscillation, &s, "floquet --gamma 2 --c 0.3 --threshold") == 1);
    s.threshold = 0;
    s.diagram = 1;
    CHECK(check_same_rows(write_oscillation, &s, "floquet --gamma 2 --c 0.3 --diagram") == 5);
    s = bkf_oscillation_spec_default();
    s.gamma = 2;
    s.threshold = 1;
    s.along = BKF_FLOQUET_ALONG_C;
    s.from = 0.1;
    s.to = 1;
    CHECK(check_same_rows(write_oscillation, &s,
                          "floquet --gamma 2 --threshold --along c --from 0.1 --to 1") >= 2);
}

TEST(products_oscillation_check_names_the_keys)
{
    bkf_error e;
    bkf_oscillation_spec s = bkf_oscillation_spec_default();
    s.gamma = 2;
    s.c = 0.3;
    s.threshold = s.diagram = 1;
    CHECK_STATUS(bkf_oscillation_check(&s, "--", &e), BKF_EINPUT);
    CHECK_MSG(strstr(e.message, "--diagram"), "%s", e.message);
    s.diagram = 0;
    s.c = 0;
    CHECK_STATUS(bkf_oscillation_check(&s, "--", &e), BKF_EINPUT);
    CHECK_MSG(strncmp(e.message, "--c: ", 5) == 0, "%s", e.message);
    s = bkf_oscillation_spec_default();
    s.gamma = 2;
    s.c = 0.3;
    s.nu = -0.9;
    CHECK_STATUS(bkf_oscillation_check(&s, "", &e), BKF_EINPUT); /* no q */
    CHECK_MSG(strncmp(e.message, "q is required", 13) == 0, "%s", e.message);
    set_q(&s, "1");
    CHECK_STATUS(bkf_oscillation_check(&s, "", &e), BKF_OK);
    s.S = 0;
    CHECK_STATUS(bkf_oscillation_check(&s, "", &e), BKF_EINPUT);
    CHECK_MSG(strncmp(e.message, "S: ", 3) == 0, "%s", e.message);
    bkf_oscillation_spec_free(&s);
}

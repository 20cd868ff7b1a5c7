/* The profile product through the library: P rows per profile, and x over
 * one period spanning one wavelength S/n (the x mapping against the
 * geometry of n fronts on a ring of size S). */
#define _POSIX_C_SOURCE 200809L
#include "bkfront/profile.h"

#include "harness.h"

#include <string.h>

static void set(bkf_profile_spec *s, const char *key, const char *value)
{
    bkf_error e = {0};
    const bkf_option *o = bkf_option_find(bkf_profile_options, bkf_profile_noptions, key);
    CHECK_MSG(o && bkf_option_apply(o, s, value, "", &e) == BKF_OK, "%s %s: %s", key, value,
              e.message);
}

/* Rows of the TSV in `text` as (n, v, T, z, x). */
static size_t rows(const char *text, double (*out)[9], size_t max)
{
    size_t k = 0;
    const char *p = text;
    while (*p == '#') p = strchr(p, '\n') + 1;
    p = strchr(p, '\n') + 1; /* header */
    while (*p && k < max) {
        char *end;
        for (int c = 0; c < 9; c++) {
            out[k][c] = strtod(p, &end);
            p = end + 1;
        }
        k++;
    }
    return k;
}

TEST(profile_rows_and_wavelength)
{
    bkf_profile_spec s = bkf_profile_spec_default();
    set(&s, "gamma", "2");
    set(&s, "c", "0.3");
    set(&s, "nu", "-0.96");
    set(&s, "S", "20");
    set(&s, "n", "1:3:3"); /* an integer range: refused before issue 14 */
    set(&s, "points", "8");
    char *text = NULL;
    size_t size = 0;
    FILE *f = open_memstream(&text, &size);
    bkf_error e = {0};
    CHECK_STATUS(bkf_profile_write(&s, f, BKF_IO_TSV, NULL, &e), BKF_OK);
    fclose(f);
    double r[32][9];
    size_t k = rows(text, r, 32);
    CHECK_MSG(k == 24, "%zu rows, want 3 profiles x 8 points", k);
    for (size_t n = 1; n <= 3; n++) {
        const double *first = r[(n - 1) * 8], *last = r[(n - 1) * 8 + 7];
        CHECK(first[0] == (double)n && first[5] == 0 && last[0] == (double)n);
        /* z = T i / P: the last row is at 7/8 of the period, and x of a
         * whole period is the wavelength S/n. */
        CHECK_CLOSE(last[5], last[4] * 7 / 8, 1e-15, 0);
        CHECK_CLOSE(last[6] * 8 / 7, 20.0 / (double)n, 1e-9, 0);
        CHECK_CLOSE(bkf_profile_x(last[4], last[2], 0.3), 20.0 / (double)n, 1e-9, 0);
    }
    free(text);
    bkf_profile_spec_free(&s);
}

TEST(profile_refuses_mixed_inputs)
{
    bkf_profile_spec s = bkf_profile_spec_default();
    bkf_error e = {0};
    CHECK_STATUS(bkf_profile_check(&s, "--", &e), BKF_EINPUT);
    /* the model defaults to the paper's; the numbers of fronts do not */
    CHECK_MSG(strstr(e.message, "--n: required unless --mu is given"), "%s", e.message);
    set(&s, "nu", "0");
    set(&s, "mu", "2");
    CHECK_STATUS(bkf_profile_check(&s, "--", &e), BKF_OK);
    set(&s, "gamma", "2");
    CHECK_STATUS(bkf_profile_check(&s, "--", &e), BKF_EINPUT);
    CHECK_MSG(strstr(e.message, "--mu: give either --mu or the model"), "%s", e.message);
    bkf_profile_spec_free(&s);
}

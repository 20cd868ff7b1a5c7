/* The simulation product through the catalogue: the same rows as the
 * executable, its JSON results against the speeds solver, an absent
 * measurement said to be absent. */
#define _POSIX_C_SOURCE 200809L
#include "harness.h"

#include <stdlib.h>
#include <string.h>

#include "bkfront/catalog.h"
#include "bkfront/model.h"
#include "bkfront/speeds.h"
#include "cli_support.h"

static char *through_catalog(const char *const *kv, bkf_io_format format)
{
    const bkf_catalog_entry *e = bkf_catalog_find("simulate");
    CHECK(e != NULL);
    bkf_error err;
    void *spec = bkf_catalog_spec_new(e, &err);
    CHECK(spec != NULL);
    for (size_t i = 0; kv[i]; i += 2)
        CHECK_MSG(bkf_catalog_apply(e, spec, kv[i], kv[i + 1], "", &err) == BKF_OK, "%s: %s",
                  kv[i], err.message);
    CHECK_MSG(e->check(spec, "", &err) == BKF_OK, "%s", err.message);
    char *data = NULL;
    size_t size = 0;
    FILE *f = open_memstream(&data, &size);
    CHECK(f != NULL);
    CHECK_MSG(e->write(spec, f, format, NULL, NULL, &err) == BKF_OK, "%s", err.message);
    fclose(f);
    bkf_catalog_spec_free(e, spec);
    return data;
}

static char *rows_of(const char *table)
{
    char *out = calloc(strlen(table) + 1, 1);
    CHECK(out != NULL);
    for (const char *p = table; *p;) {
        const char *end = strchr(p, '\n');
        size_t len = end ? (size_t)(end - p + 1) : strlen(p);
        if (*p != '#') strncat(out, p, len);
        p += len;
    }
    return out;
}

TEST(simulate_catalog_rows_equal_the_cli)
{
    const char *kv[] = {"N", "128", "tmax", "5", "frames", "20", "init", "front:n=6", NULL};
    char *lib = through_catalog(kv, BKF_IO_TSV);
    bkf_cli_result r = BKF_CLI("simulate", "--N", "128", "--tmax", "5", "--frames", "20",
                               "--init", "front:n=6", "--no-progress");
    CHECK_MSG(r.code == 0, "%s", r.err);
    char *a = rows_of(lib), *b = rows_of(r.out);
    CHECK_MSG(strcmp(a, b) == 0, "library:\n%.400s\ncli:\n%.400s", a, b);
    CHECK(strstr(a, "t\tmean\tvariance") == a);
    free(a);
    free(b);
    free(lib);
    bkf_cli_result_free(&r);
}

static double result_of(const char *json, const char *key)
{
    char pat[64];
    snprintf(pat, sizeof pat, "\"%s\": ", key);
    const char *p = strstr(strstr(json, "\"results\""), pat);
    CHECK_MSG(p != NULL, "no %s in results", key);
    p += strlen(pat);
    return strncmp(p, "null", 4) == 0 ? NAN : strtod(p, NULL);
}

TEST(simulate_results_speed_is_the_predicted_one)
{
    /* Six seeded fronts at the paper's parameters keep the speeds solver's
     * v (independent: bkf_speeds_find) to within the measured uncertainty
     * and the resolution of N = 512 over t = 30. */
    const char *kv[] = {"tmax", "30", "frames", "60", "init", "front:n=6", NULL};
    char *json = through_catalog(kv, BKF_IO_JSON);
    CHECK(strstr(json, "\"regime\": \"propagating_fronts\"") != NULL);
    bkf_model_params m = bkf_model_params_paper();
    bkf_speeds_options o = bkf_speeds_options_default();
    o.n_from = o.n_to = 6;
    bkf_speeds_table t = {0};
    bkf_error e;
    CHECK_STATUS(bkf_speeds_find(&m, &o, &t, &e), BKF_OK);
    CHECK(t.count >= 1);
    double v = t.roots[0].v;
    bkf_speeds_table_free(&t);
    double speed = result_of(json, "speed"), err = result_of(json, "speed_err");
    /* both solved to their tolerances: the seed at 1e-12, the table at 1e-10 */
    CHECK_CLOSE(result_of(json, "v_pred"), v, 1e-10, 0);
    CHECK_MSG(speed < 0 && fabs(-speed - v) <= 10 * err + 1e-6 * v,
              "speed %.12g +- %.3g, v %.12g", speed, err, v);
    CHECK(result_of(json, "fronts_start") == 6 && result_of(json, "fronts_end") == 6);
    free(json);
}

TEST(simulate_absent_period_is_said_absent)
{
    /* Continuous slip (|nu| > 1) has no crossings at the probe: no period. */
    const char *kv[] = {"nu", "-1.2", "N", "64", "tmax", "5", "frames", "10", NULL};
    char *tsv = through_catalog(kv, BKF_IO_TSV);
    CHECK_MSG(strstr(tsv, "# period at x = 0: none (0 crossings") != NULL, "%.2000s", tsv);
    CHECK(strstr(tsv, "nan +- nan") == NULL);
    free(tsv);
    char *json = through_catalog(kv, BKF_IO_JSON);
    CHECK(isnan(result_of(json, "period")) && isnan(result_of(json, "speed")));
    CHECK(strstr(json, "\"regime\": \"continuous_slip\"") != NULL);
    free(json);
}

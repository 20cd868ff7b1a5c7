/* The stability product through the library: the same rows as the
 * executable; its ring spectrum against Hill's method (Fourier-Bloch,
 * dense LAPACK: an independent discretisation) at the Bloch angle of the
 * leading eigenvalue, against the symmetries every ring spectrum has
 * (sigma(j) and sigma(n - j) are conjugate, the translation at 0); the key
 * results in JSON; the catalogue and bad specs. */
#include "products_support.h"

#include <math.h>

#include "bkfront/catalog.h"
#include "bkfront/hill.h"
#include "bkfront/speeds.h"
#include "bkfront/stability.h"

/* In test_io.c. */
int bkf_test_json_valid(const char *text);

#define TWO_PI 6.283185307179586476925286766559

static int write_stability(const void *spec, FILE *out, bkf_io_format format,
                           const bkf_provenance *prov, bkf_error *err)
{
    return bkf_stability_write(spec, out, format, prov, err);
}

/* The paper's parameters (gamma 2, c 0.3, nu -0.96, S 20) for n fronts. */
static bkf_stability_spec paper_spec(size_t n)
{
    bkf_stability_spec s = bkf_stability_spec_default();
    s.gamma = 2;
    s.c = 0.3;
    s.nu = -0.96;
    s.S = 20;
    s.n = n;
    return s;
}

static size_t data_rows(const char *tsv)
{
    size_t n = 0;
    while (bkf_tsv_cell(tsv, (int)n, "re", NULL, NULL, 0)) n++;
    return n;
}

TEST(products_stability_library_rows_are_the_cli_rows)
{
    bkf_stability_spec s = paper_spec(4);
    size_t rows = check_same_rows(write_stability, &s,
                                  "stability --gamma 2 --c 0.3 --nu -0.96 --S 20 --n 4");
    /* per_kappa per kappa, and a conjugate pair at the cut kept whole */
    CHECK_MSG(rows >= 4 * s.per_kappa && rows <= 4 * (s.per_kappa + 1), "%zu rows, want per_kappa (+1) for each of the 4 kappa", rows);
    s = paper_spec(5);
    s.line = 1;
    s.kappa_count = 6;
    rows = check_same_rows(write_stability, &s,
                           "stability --gamma 2 --c 0.3 --nu -0.96 --S 20 --n 5 --line "
                           "--kappa-count 6");
    CHECK(rows == 6);
}

/* Hill's method at the root's mu, Bloch angle theta = 2 pi j / n: the
 * rightmost eigenvalues, each within the two methods' estimates (and the
 * cycle's 1e-12) of the product's rows for j. */
TEST(products_stability_ring_agrees_with_hills_method)
{
    const size_t n = 4;
    bkf_stability_spec s = paper_spec(n);
    char *tsv = library_output(write_stability, &s, BKF_IO_TSV);
    bkf_model_params p = {2, 0.3, -0.96, 20, 0, BKF_MODEL_CONTINUUM};
    bkf_speeds_options so = bkf_speeds_options_default();
    so.n_from = so.n_to = n;
    bkf_speeds_table t;
    bkf_error e;
    CHECK(bkf_speeds_find(&p, &so, &t, &e) == BKF_OK && t.count == 1);
    bkf_cycle *cy = bkf_cycle_alloc();
    CHECK(cy);
    bkf_cycle_options co = bkf_cycle_options_default();
    co.tol = 1e-12;
    CHECK(bkf_cycle_solve(cy, t.roots[0].mu, p.nu, &co, &e) == BKF_OK);
    size_t checked = 0;
    for (size_t j = 0; j < n; j++) {
        bkf_hill_eigenvalue h[3];
        double herr[3];
        size_t found = 0;
        CHECK_MSG(bkf_hill_leading(cy, p.gamma, TWO_PI * (double)j / (double)n, 64, 1e-7, 3, h,
                                   herr, &found, NULL, &e) == BKF_OK,
                  "hill j %zu: %s", j, e.message);
        for (size_t k = 0; k < found; k++) {
            /* the nearest of the product's rows for this j */
            double best = INFINITY, best_err = 0;
            for (int r = 0;; r++) {
                double rj, re, im, er;
                if (!bkf_tsv_cell(tsv, r, "j", &rj, NULL, 0)) break;
                if (rj != (double)j) continue;
                CHECK(bkf_tsv_cell(tsv, r, "re", &re, NULL, 0) &&
                      bkf_tsv_cell(tsv, r, "im", &im, NULL, 0) &&
                      bkf_tsv_cell(tsv, r, "err", &er, NULL, 0));
                double d = hypot(re - h[k].re, im - h[k].im);
                if (d < best) best = d, best_err = er;
            }
            /* Hill's leading ones are the product's leading ones, unless the
             * product lists fewer per kappa than Hill converged */
            if (k < s.per_kappa) {
                CHECK_MSG(best <= best_err + herr[k] + 1e-8,
                          "j %zu: Hill's %.10g%+.10gi is %.3g from the nearest row (err %.3g)", j,
                          h[k].re, h[k].im, best, best_err);
                checked++;
            }
        }
    }
    bkf_test_note("n = 4: %zu eigenvalues agree with Hill's method", checked);
    CHECK(checked >= 2 * n);
    bkf_cycle_free(cy);
    bkf_speeds_table_free(&t);
    free(tsv);
}

/* Real coefficients: the spectrum at -kappa, the same as 2 pi (n - j)/S on
 * the ring, is the conjugate of the one at kappa; the translation is 0. */
TEST(products_stability_ring_symmetries)
{
    const size_t n = 5;
    bkf_stability_spec s = paper_spec(n);
    char *tsv = library_output(write_stability, &s, BKF_IO_TSV);
    size_t rows = data_rows(tsv), translations = 0;
    CHECK(rows == n * s.per_kappa);
    for (int r = 0; r < (int)rows; r++) {
        double j, re, im, err, tr, kappa;
        CHECK(bkf_tsv_cell(tsv, r, "j", &j, NULL, 0) && bkf_tsv_cell(tsv, r, "re", &re, NULL, 0) &&
              bkf_tsv_cell(tsv, r, "im", &im, NULL, 0) &&
              bkf_tsv_cell(tsv, r, "err", &err, NULL, 0) &&
              bkf_tsv_cell(tsv, r, "translation", &tr, NULL, 0) &&
              bkf_tsv_cell(tsv, r, "kappa", &kappa, NULL, 0));
        CHECK_CLOSE(kappa, TWO_PI * j / s.S, 1e-15, 0);
        if (tr == 1) {
            translations++;
            CHECK(j == 0 && fabs(re) <= s.tol && fabs(im) <= s.tol);
        }
        /* the conjugate among the rows of n - j (j = 0: of j itself) */
        double mirror = j == 0 ? 0 : (double)n - j, best = INFINITY, best_err = 0, lowest = 0;
        for (int q = 0; q < (int)rows; q++) {
            double jq, req, imq, errq;
            CHECK(bkf_tsv_cell(tsv, q, "j", &jq, NULL, 0));
            if (jq != mirror) continue;
            CHECK(bkf_tsv_cell(tsv, q, "re", &req, NULL, 0) &&
                  bkf_tsv_cell(tsv, q, "im", &imq, NULL, 0) &&
                  bkf_tsv_cell(tsv, q, "err", &errq, NULL, 0));
            double d = hypot(req - re, imq + im);
            if (d < best) best = d, best_err = errq;
            lowest = fmin(lowest, req);
        }
        /* the rows of n - j are its rightmost per_kappa: a conjugate with
         * a larger real part than their last one must be among them */
        if (re > lowest + err)
            CHECK_MSG(best <= err + best_err, "j %g: %g%+gi has no conjugate", j, re, im);
    }
    CHECK(translations == 1);
    free(tsv);
}

/* The value of "NAME": in the JSON object "results" (number, or text
 * copied into text). */
static double result_field(const char *json, const char *name, char *text, size_t size)
{
    const char *results = strstr(json, "\"results\": {");
    CHECK_MSG(results, "no results in: %.300s", json);
    const char *end = strchr(results, '}');
    char key[64];
    snprintf(key, sizeof key, "\"%s\": ", name);
    const char *at = strstr(results, key);
    CHECK_MSG(at && at < end, "no %s in the results", name);
    at += strlen(key);
    if (text) {
        CHECK(*at == '"');
        const char *close = strchr(at + 1, '"');
        snprintf(text, size, "%.*s", (int)(close - at - 1), at + 1);
        return NAN;
    }
    return strtod(at, NULL);
}

TEST(products_stability_json_results)
{
    bkf_stability_spec s = paper_spec(2);
    char *json = library_output(write_stability, &s, BKF_IO_JSON);
    CHECK_MSG(bkf_test_json_valid(json), "invalid JSON:\n%.400s", json);
    char stable[32], kind[32];
    result_field(json, "stable", stable, sizeof stable);
    result_field(json, "kind", kind, sizeof kind);
    CHECK(strcmp(kind, "real") == 0 || strcmp(kind, "complex") == 0);
    double sigma = result_field(json, "sigma_max", NULL, 0);
    double err = result_field(json, "sigma_max_err", NULL, 0);
    /* the verdict is the sign of sigma_max beyond its error */
    CHECK(strcmp(stable, sigma > err ? "no" : sigma < -err ? "yes" : "unresolved") == 0);
    CHECK(result_field(json, "n", NULL, 0) == 2 && result_field(json, "root", NULL, 0) == 1);
    CHECK(result_field(json, "translation_residual", NULL, 0) <= s.tol);
    free(json);
    /* and sigma_max is the rightmost re of the TSV rows but the translation */
    char *tsv = library_output(write_stability, &s, BKF_IO_TSV);
    double top = -INFINITY;
    for (int r = 0; r < (int)data_rows(tsv); r++) {
        double re, tr;
        CHECK(bkf_tsv_cell(tsv, r, "re", &re, NULL, 0) &&
              bkf_tsv_cell(tsv, r, "translation", &tr, NULL, 0));
        if (tr == 0) top = fmax(top, re);
    }
    CHECK(top == sigma);
    free(tsv);
}

TEST(products_stability_reachable_from_the_catalogue)
{
    const bkf_catalog_entry *e = bkf_catalog_find("stability");
    CHECK(e);
    bkf_error err;
    void *spec = bkf_catalog_spec_new(e, &err);
    CHECK(spec);
    CHECK_STATUS(e->check(spec, "", &err), BKF_EINPUT); /* gamma .. n required */
    const char *kv[] = {"gamma", "2", "c", "0.3", "nu", "-0.96", "S", "20", "n", "3",
                        "tol", "1e-5", "per-kappa", "2", "line", NULL, "kappa-count", "5"};
    for (size_t i = 0; i < sizeof kv / sizeof kv[0]; i += 2)
        CHECK_MSG(bkf_catalog_apply(e, spec, kv[i], kv[i + 1], "", &err) == BKF_OK, "%s",
                  err.message);
    CHECK_STATUS(e->check(spec, "", &err), BKF_OK);
    const bkf_stability_spec *st = spec;
    CHECK(st->n == 3 && st->tol == 1e-5 && st->per_kappa == 2 && st->line && st->kappa_count == 5);
    CHECK_STATUS(bkf_catalog_apply(e, spec, "tol", "1e-20", "", &err), BKF_EINPUT);
    CHECK_STATUS(bkf_catalog_apply(e, spec, "c", "0", "", &err), BKF_EINPUT);
    CHECK_STATUS(bkf_catalog_apply(e, spec, "n", "0", "", &err), BKF_EINPUT);
    bkf_catalog_spec_free(e, spec);
}

TEST(products_stability_refuses_bad_specs)
{
    bkf_error e;
    bkf_stability_spec s = paper_spec(4);
    s.c = 0;
    CHECK_STATUS(bkf_stability_check(&s, "", &e), BKF_EINPUT);
    CHECK(strncmp(e.message, "c: ", 3) == 0);
    s = paper_spec(0);
    CHECK_STATUS(bkf_stability_check(&s, "--", &e), BKF_EINPUT);
    CHECK(strncmp(e.message, "--n: ", 5) == 0);
    s = paper_spec(4);
    s.tol = 1e-20;
    CHECK_STATUS(bkf_stability_check(&s, "", &e), BKF_EINPUT);
    CHECK(strncmp(e.message, "tol: ", 5) == 0);
    s = paper_spec(4);
    s.nu = 1;
    CHECK_STATUS(bkf_stability_check(&s, "", &e), BKF_EINPUT);
    CHECK(strncmp(e.message, "nu: ", 4) == 0);
    /* beyond n_max (12 here: speeds' n_bound 12.29): known once the roots are found */
    s = paper_spec(13);
    char *data = NULL;
    size_t size = 0;
    FILE *f = open_memstream(&data, &size);
    CHECK(f);
    CHECK_STATUS(bkf_stability_write(&s, f, BKF_IO_TSV, NULL, &e), BKF_EINPUT);
    CHECK(fclose(f) == 0 && size == 0);
    CHECK_MSG(strstr(e.message, "n = 13") && strstr(e.message, "n_max = 12"), "%s", e.message);
    free(data);
}

/* The stability product through the library: the same rows as the
 * executable; its ring spectrum against Hill's method (Fourier-Bloch,
 * dense LAPACK: an independent discretisation) at the Bloch angle of the
 * leading eigenvalue, against the symmetries every ring spectrum has
 * (sigma(j) and sigma(n - j) are conjugate, the translation at 0); the key
 * results in JSON; the catalogue and bad specs. */
#include "products_support.h"

#include <math.h>
#include <string.h>

#include "bkfront/catalog.h"
#include "bkfront/floquet.h"
#include "bkfront/hill.h"
#include "bkfront/asymptotics.h"
#include "bkfront/speeds.h"
#include "bkfront/stabmap.h"
#include "bkfront/trainspec.h"
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
 * cycle's 1e-12) of the product's rows for j.  The operator is real, so
 * Hill's spectrum at -theta is the conjugate of that at theta: solved for
 * j <= n/2, it gives class n - j's.  48 modes against 96 converge to 3e-8
 * here (64 against 128, at twice the CPU: 2e-10). */
TEST(products_stability_ring_agrees_with_hills_method)
{
    enum { n = 4 }; /* a constant: the arrays of Hill's classes below are no VLAs */
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
    bkf_hill_eigenvalue hill[n / 2 + 1][3];
    double hill_err[n / 2 + 1][3];
    size_t hill_found[n / 2 + 1];
    for (size_t j = 0; 2 * j <= n; j++) {
        hill_found[j] = 0;
        CHECK_MSG(bkf_hill_leading(cy, p.gamma, TWO_PI * (double)j / (double)n, 48, 1e-7, 3, hill[j],
                                   hill_err[j], &hill_found[j], NULL, &e) == BKF_OK,
                  "hill j %zu: %s", j, e.message);
    }
    for (size_t j = 0; j < n; j++) {
        size_t jh = 2 * j <= n ? j : n - j, found = hill_found[jh];
        bkf_hill_eigenvalue h[3];
        const double *herr = hill_err[jh];
        for (size_t k = 0; k < found; k++)
            h[k] = (bkf_hill_eigenvalue){hill[jh][k].re, jh == j ? hill[jh][k].im : -hill[jh][k].im};
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
    /* per_kappa per Bloch number and the translation besides them (a
     * conjugate pair at the cut kept whole) */
    CHECK_MSG(rows >= n * s.per_kappa + 1 && rows <= n * (s.per_kappa + 1) + 1, "%zu rows", rows);
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
    CHECK_STATUS(e->check(spec, "", &err), BKF_EINPUT); /* n required */
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

/* The stability boundary of n = 4 at the paper's nu, located in S by the
 * scan, recomputed independently: sigma_max at that (nu, S) within a few
 * errors of 0, of opposite signs just either side (the side given by
 * stable_above), and each point the continuation reaches again. */
static void check_crossing(const bkf_model_params *p, const bkf_stabmap_point *pt)
{
    bkf_model_params q = *p;
    q.nu = pt->nu;
    bkf_error e;
    double sig, err, v, mu, h = fmax(10 * pt->S_err, 0.05);
    q.S = pt->S;
    CHECK_STATUS(bkf_stabmap_sigma(&q, 4, 0, NULL, &sig, &err, &v, &mu, NULL, &e), BKF_OK);
    CHECK(fabs(sig) <= fabs(pt->slope) * pt->S_err + 3 * err);
    q.S = pt->S + h;
    CHECK_STATUS(bkf_stabmap_sigma(&q, 4, 0, NULL, &sig, &err, &v, &mu, NULL, &e), BKF_OK);
    CHECK(pt->stable_above ? sig < -err : sig > err);
    q.S = pt->S - h;
    CHECK_STATUS(bkf_stabmap_sigma(&q, 4, 0, NULL, &sig, &err, &v, &mu, NULL, &e), BKF_OK);
    CHECK(pt->stable_above ? sig > err : sig < -err);
}

static int keep_points(const bkf_stabmap_point *pt, void *data)
{
    bkf_stabmap_point *last = data;
    *last = *pt;
    return 0;
}

typedef struct {
    bkf_stabmap_point *p;
    size_t n;
} point_list;

static int keep_all(const bkf_stabmap_point *pt, void *data)
{
    point_list *l = data;
    bkf_stabmap_point *g = realloc(l->p, (l->n + 1) * sizeof *g);
    if (!g) return 1;
    l->p = g;
    l->p[l->n++] = *pt;
    return 0;
}

TEST(stabmap_boundary_point_recomputed)
{
    bkf_error e;
    bkf_model_params p = bkf_model_params_paper();
    bkf_stabmap_options o = bkf_stabmap_options_default();
    bkf_stabmap_point pt;
    int found;
    /* n = 4 is stable at S = 20 and unstable at 24 (docs/cli/stability.md) */
    CHECK_STATUS(bkf_stabmap_locate(&p, 4, 18, 26, 4, &o, &pt, &found, &e), BKF_OK);
    CHECK(found);
    CHECK(pt.S > 20 && pt.S < 24 && !pt.stable_above);
    check_crossing(&p, &pt);
    bkf_stabmap_point last;
    bkf_stabmap_report rep;
    /* to nu -0.95: 5 points, S 22.4 to 29.7 (to -0.94, 9 points to S 51.5
     * cost 2.5 times as much: the trains stiffen as S grows) */
    CHECK_STATUS(bkf_stabmap_follow(&p, 4, &pt, -0.95, &o, keep_points, &last, &rep, &e), BKF_OK);
    CHECK(rep.points >= 3);
    CHECK(fabs(last.nu + 0.95) < 1e-12 || rep.end != BKF_STABMAP_END_REACHED);
    check_crossing(&p, &last);
}

/* The boundary followed by pseudo-arclength continuation in (nu, S): every
 * point where direct spectra (bkf_stabmap_sigma, the fastest root: not the
 * trace's continued one) on either side in S have opposite signs, the side
 * given by stable_above, within the S_err the point claims, and that below
 * S_tol (Newton's iterates on the tracked eigenvalue, 8 times inside its
 * tolerance; before, the last ring spectrum within it: S_err 0.0074 at nu
 * -0.9553, where the curve is steep in S); the last point likewise in nu
 * (at fixed S, by the sign of d sigma / d nu) within its nu_err, and on
 * the window's edge exactly.  A point costs about one ring spectrum (before:
 * 23 for 8 points, the predictor's and every correction's). */
TEST(stabmap_trace_points_straddle_the_sign_change)
{
    bkf_error e;
    bkf_model_params p = bkf_model_params_paper();
    bkf_stabmap_options o = bkf_stabmap_options_default();
    o.nu_step = 0.004;
    o.S_step = 0.5;
    bkf_stabmap_point pt;
    int found;
    CHECK_STATUS(bkf_stabmap_locate(&p, 4, 18, 26, 4, &o, &pt, &found, &e), BKF_OK);
    CHECK(found);
    bkf_stabmap_window w = {-0.965, -0.955, 2, 40};
    point_list pts = {0};
    bkf_stabmap_report rep;
    CHECK_STATUS(bkf_stabmap_trace(&p, 4, &pt, 1, &w, &o, keep_all, &pts, &rep, &e), BKF_OK);
    CHECK_MSG(rep.end == BKF_STABMAP_END_REACHED, "end %s: %s", bkf_stabmap_end_name(rep.end),
              rep.note);
    CHECK(pts.n == rep.points && pts.n >= 3);
    CHECK(pts.n > 0 && pts.p[pts.n - 1].nu == -0.955);
    CHECK_MSG(rep.evaluations <= 1.5 * (double)rep.points + 2, "%zu spectra for %zu points",
              rep.evaluations, rep.points);
    for (size_t i = 0; i < pts.n; i++) {
        CHECK_MSG(pts.p[i].S_err > 0 && pts.p[i].S_err < o.S_tol, "point %zu: S_err %g", i,
                  pts.p[i].S_err);
        CHECK(i == 0 || pts.p[i].nu > pts.p[i - 1].nu);
        check_crossing(&p, &pts.p[i]);
    }
    bkf_stabmap_point *last = &pts.p[pts.n - 1];
    bkf_model_params q = p;
    q.S = last->S;
    double h = fmax(10 * last->nu_err, 1e-3), sig[2], err, v, mu;
    for (int k = 0; k < 2; k++) {
        q.nu = last->nu + (k ? h : -h);
        CHECK_STATUS(bkf_stabmap_sigma(&q, 4, 0, NULL, &sig[k], &err, &v, &mu, NULL, &e), BKF_OK);
        CHECK(fabs(sig[k]) > err);
    }
    CHECK(last->nu_slope > 0 ? sig[1] > 0 && sig[0] < 0 : sig[1] < 0 && sig[0] > 0);
    free(pts.p);
    /* bad input: a window that does not hold the point */
    w.nu_lo = -0.95;
    w.nu_hi = -0.94;
    CHECK_STATUS(bkf_stabmap_trace(&p, 4, &pt, 1, &w, &o, keep_all, &pts, &rep, &e), BKF_EINPUT);
}

/* Where a faster root of n is born in a fold of the speed condition, the
 * fastest root's sigma_max jumps across 0 without a zero: n = 1 at nu -0.98
 * has one root at S 3.2 and three at 3.35 (bkf_speeds_find, the fold
 * itself), sigma_max of the fastest root is negative at 2.8 and positive at
 * 3.8, and the scan must report no crossing between (before the fix: one
 * at S 3.2885 with sigma_max -0.035, drawn as the paper diagram's n = 1
 * boundary). */
TEST(stabmap_scan_skips_a_jump_to_a_faster_root)
{
    bkf_error e;
    bkf_model_params p = bkf_model_params_paper();
    p.nu = -0.98;
    bkf_speeds_options so = bkf_speeds_options_default();
    so.n_from = so.n_to = 1;
    const double S[2] = {3.2, 3.35};
    const size_t roots[2] = {1, 3};
    for (int k = 0; k < 2; k++) {
        bkf_speeds_table t;
        p.S = S[k];
        CHECK_STATUS(bkf_speeds_find(&p, &so, &t, &e), BKF_OK);
        CHECK_MSG(t.count == roots[k], "S %g: %zu roots", S[k], t.count);
        bkf_speeds_table_free(&t);
    }
    double sig[2], err, v, mu;
    for (int k = 0; k < 2; k++) {
        p.S = k ? 3.8 : 2.8;
        CHECK_STATUS(bkf_stabmap_sigma(&p, 1, 0, NULL, &sig[k], &err, &v, &mu, NULL, &e), BKF_OK);
    }
    CHECK(sig[0] < -err && sig[1] > err);
    bkf_stabmap_options o = bkf_stabmap_options_default();
    bkf_stabmap_point pts[4];
    size_t count = 9;
    CHECK_STATUS(bkf_stabmap_scan(&p, 1, 2.8, 3.8, 2, &o, pts, 4, &count, NULL, &e), BKF_OK);
    CHECK_MSG(count == 0, "a crossing at S %.6g, sigma_max %.3g", pts[0].S, pts[0].sigma);
    /* down in S (as the diagram's seed columns), where each sample's
     * fastest root is the one above continued while it exists: past the
     * fold it is gone, and the table's fastest is the slow root */
    count = 9;
    CHECK_STATUS(bkf_stabmap_scan(&p, 1, 3.8, 2.8, 2, &o, pts, 4, &count, NULL, &e), BKF_OK);
    CHECK_MSG(count == 0, "down: a crossing at S %.6g, sigma_max %.3g", pts[0].S, pts[0].sigma);
}

/* A planted sigma_max (stabmap.h's spectrum hook): A (1 - x^2 - y^2), x =
 * (nu + 0.96) / 0.02, y = (S - 20) / 3, no eigenvalue listed (so nothing is
 * tracked): its zero set is a closed ellipse, which the real spectra give
 * only at parameters that are expensive to find. */
static int ellipse_spectrum(const bkf_model_params *params, const bkf_speeds_root *root,
                            double tol, bkf_trainspec_result *r, bkf_error *err, void *data)
{
    (void)root;
    (void)tol;
    (void)err;
    size_t *calls = data;
    (*calls)++;
    double x = (params->nu + 0.96) / 0.02, y = (params->S - 20) / 3;
    memset(r, 0, sizeof *r);
    r->sigma_max = 0.01 * (1 - x * x - y * y);
    r->sigma_max_err = 1e-12;
    r->verdict = r->sigma_max < 0 ? BKF_TRAINSPEC_STABLE : BKF_TRAINSPEC_UNSTABLE;
    return BKF_OK;
}

/* A curve that closes: traced either way from the ellipse's top, it goes
 * round (its points reach the ellipse's four extremes, each on it) and
 * ends `closed` back near its first point, with fewer points than twice
 * the ellipse's perimeter in steps; the report's ring spectra are the
 * hook's calls.  Without the closed end it went round again to max_points. */
TEST(stabmap_trace_ends_closed_on_its_first_point)
{
    bkf_model_params p = bkf_model_params_paper();
    bkf_stabmap_options o = bkf_stabmap_options_default();
    size_t calls = 0;
    o.spectrum = ellipse_spectrum;
    o.spectrum_data = &calls;
    o.nu_step = 0.01;
    o.S_step = 1;
    o.max_points = 200;
    bkf_stabmap_window w = {-0.99, -0.93, 10, 30};
    bkf_stabmap_point first = {0};
    first.nu = -0.96;
    first.S = 23;
    first.slope = -0.02 / 3; /* d sigma / dS at the top */
    first.stable_above = 1;
    first.nu_slope = NAN;
    for (int d = -1; d <= 1; d += 2) {
        point_list pts = {NULL, 0};
        bkf_stabmap_report rep;
        bkf_error e;
        calls = 0;
        CHECK_STATUS(bkf_stabmap_trace(&p, 4, &first, d, &w, &o, keep_all, &pts, &rep, &e),
                     BKF_OK);
        CHECK_MSG(rep.end == BKF_STABMAP_END_CLOSED, "direction %d: end %s (%s) after %zu points",
                  d, bkf_stabmap_end_name(rep.end), rep.note, rep.points);
        CHECK(rep.points == pts.n && rep.evaluations == calls && rep.tracked == 0);
        /* the perimeter is about 2 pi sqrt((2^2 + 3^2) / 2) = 16 steps */
        CHECK_MSG(pts.n >= 8 && pts.n <= 40, "%zu points", pts.n);
        double lo[2] = {1, 1e9}, hi[2] = {-1, -1e9};
        for (size_t i = 0; i < pts.n; i++) {
            double x = (pts.p[i].nu + 0.96) / 0.02, y = (pts.p[i].S - 20) / 3;
            CHECK_MSG(fabs(x * x + y * y - 1) < 1e-3, "point %zu at nu %.6f, S %.4f off the "
                      "ellipse", i, pts.p[i].nu, pts.p[i].S);
            lo[0] = fmin(lo[0], pts.p[i].nu);
            hi[0] = fmax(hi[0], pts.p[i].nu);
            lo[1] = fmin(lo[1], pts.p[i].S);
            hi[1] = fmax(hi[1], pts.p[i].S);
        }
        /* round: within a step (1 in S, 0.01 in nu) of each extreme */
        CHECK(lo[0] < -0.975 && hi[0] > -0.945 && lo[1] < 18 && hi[1] > 22.5);
        const bkf_stabmap_point *last = &pts.p[pts.n - 1];
        CHECK(hypot((last->nu - first.nu) / 0.01, last->S - first.S) < 1);
        free(pts.p);
    }
}

/* A boundary that turns in nu at a corner of sigma_max: at gamma 1, c 0.6,
 * the stable tongue of n = 3 (the root continued from S 8.85 at nu -0.95)
 * is bounded below and above by two eigenvalues' zero sets that meet near
 * nu -0.890, S 11.3, where the curve turns back in nu with a corner.
 * Traced from the scan's crossing at nu -0.95, S 8.85, it goes through the
 * corner and back to nu -0.95 on the upper half, stable below there: the
 * spectra of the root it continued, computed directly at fixed S 0.05 on
 * either side of its last point, have the signs its stable side says.
 * (The fastest root there is another train above S 10.6, unstable: the scan
 * drops that jump.)  Before, the trace stalled at the corner (6 points,
 * `stalled`) and the upper half was not drawn. */
TEST(stabmap_trace_passes_a_corner_at_a_turn_in_nu)
{
    bkf_error e;
    bkf_model_params p = bkf_model_params_paper();
    p.gamma = 1;
    p.c = 0.6;
    p.nu = -0.95;
    bkf_stabmap_options o = bkf_stabmap_options_default();
    o.tol = 1e-5;
    o.S_step = 1;
    o.max_points = 30; /* the diagram's cap for this window: 2 (8 + 6) + 2 */
    bkf_stabmap_point x[4];
    size_t count = 0;
    CHECK_STATUS(bkf_stabmap_scan(&p, 3, 14, 8, 6, &o, x, 4, &count, NULL, &e), BKF_OK);
    size_t lo = 0;
    for (size_t i = 1; i < count; i++)
        if (x[i].S < x[lo].S) lo = i;
    CHECK_MSG(count >= 1 && x[lo].S > 8.8 && x[lo].S < 8.9 && x[lo].stable_above,
              "%zu crossings, the lowest at S %.4f", count, count ? x[lo].S : NAN);
    if (!count) return;
    bkf_stabmap_window w = {-0.95, -0.87, 8, 14};
    point_list pts = {0};
    bkf_stabmap_report rep;
    CHECK_STATUS(bkf_stabmap_trace(&p, 3, &x[lo], 1, &w, &o, keep_all, &pts, &rep, &e), BKF_OK);
    CHECK_MSG(rep.end == BKF_STABMAP_END_REACHED, "end %s (%s) after %zu points",
              bkf_stabmap_end_name(rep.end), rep.note, rep.points);
    if (!pts.n) return;
    const bkf_stabmap_point *last = &pts.p[pts.n - 1];
    double turn = -1;
    for (size_t i = 0; i < pts.n; i++) turn = fmax(turn, pts.p[i].nu);
    bkf_test_note("%zu points, %zu ring spectra; turn at nu %.5f; back at nu %.6f, S %.5f",
                  pts.n, rep.evaluations, turn, last->nu, last->S);
    CHECK(turn > -0.9 && turn < -0.88);
    CHECK(fabs(last->nu + 0.95) < 1e-9 && last->S > 11 && last->S < 12);
    CHECK(pts.p[0].stable_above && !last->stable_above);
    bkf_model_params q = p;
    for (int side = -1; side <= 1; side += 2) {
        double sig, err, v, mu;
        q.S = last->S + 0.05 * side;
        CHECK_STATUS(bkf_stabmap_sigma(&q, 3, last->v, &o, &sig, &err, &v, &mu, NULL, &e),
                     BKF_OK);
        CHECK_MSG(side < 0 ? sig < -err : sig > err, "S %.4f: sigma_max %.3g (err %.2g)", q.S,
                  sig, err);
        CHECK(fabs(v - last->v) < 0.01 * last->v);
    }
    free(pts.p);
}

/* The diagram's "work: N ring spectra and M eigenvalues ..." comment: N,
 * and M into *tracked. */
/* not inlined: gcc 12 then takes the call for a use of library_output's
 * memory-stream buffer pointer out of its scope (-Wdangling-pointer) */
__attribute__((noinline)) static size_t work_said(const char *tsv, size_t *tracked)
{
    const char *work = tsv ? strstr(tsv, "# work: ") : NULL;
    char *end = NULL;
    size_t said = work ? (size_t)strtoul(work + 8, &end, 10) : 0;
    const char *mid = " ring spectra and ";
    int got = end && strncmp(end, mid, strlen(mid)) == 0;
    if (got) *tracked = (size_t)strtoul(end + strlen(mid), &end, 10);
    CHECK_MSG(got && strncmp(end, " eigenvalues", 12) == 0, "no work comment in: %.300s",
              tsv ? tsv : "");
    return said;
}

/* A counting wrapper of the ring spectrum (the diagram's every spectrum
 * goes through it, from two threads). */
static int counted_spectrum(const bkf_model_params *params, const bkf_speeds_root *root,
                            double tol, bkf_trainspec_result *r, bkf_error *err, void *data)
{
    size_t *calls = data;
#pragma omp atomic
    (*calls)++;
    return bkf_trainspec_root(params, root, tol, 1, r, err);
}

/* The diagram's rows of one kind and n: curve, nu, S, above. */
typedef struct {
    size_t curve[256];
    double nu[256], S[256];
    int above[256];
    size_t count;
} diagram_rows;

static void rows_of(const char *tsv, const char *kind, int n, diagram_rows *r)
{
    char k[32];
    double x;
    r->count = 0;
    for (int i = 0; bkf_tsv_cell(tsv, i, "kind", NULL, k, sizeof k) && r->count < 256; i++) {
        CHECK(bkf_tsv_cell(tsv, i, "n", &x, NULL, 0));
        if (strcmp(k, kind) != 0 || (int)x != n) continue;
        size_t j = r->count++;
        double c, a;
        CHECK(bkf_tsv_cell(tsv, i, "curve", &c, NULL, 0) && bkf_tsv_cell(tsv, i, "nu", &r->nu[j], NULL, 0) &&
              bkf_tsv_cell(tsv, i, "S", &r->S[j], NULL, 0) && bkf_tsv_cell(tsv, i, "above", &a, NULL, 0));
        r->curve[j] = (size_t)c;
        r->above[j] = a != 0;
    }
}

/* Whether a followed curve (consecutive rows of one curve) crosses the
 * column nu = x within dS of S, with the same stable side. */
static int followed_crosses(const diagram_rows *f, double x, double S, int above, double dS)
{
    for (size_t i = 0; i + 1 < f->count; i++) {
        if (f->curve[i] != f->curve[i + 1]) continue;
        double a = f->nu[i], b = f->nu[i + 1];
        if (!((a <= x && x <= b) || (b <= x && x <= a))) continue;
        double t = a == b ? 0 : (x - a) / (b - a), Sx = f->S[i] + t * (f->S[i + 1] - f->S[i]);
        if (fabs(Sx - S) <= dS && f->above[i] == above) return 1;
    }
    return 0;
}

/* The followed diagram against the grid scan (--scan: every column of the
 * grid scanned in S and each sign change closed there, no continuation)
 * at the paper's gamma 2, c 0.3, n = 2 (its boundary from S 4.6 at nu
 * -0.98 to 7.2 at -0.92), seeds on the two end columns only, so that the
 * middle column's crossing is the continuation's: every crossing the scan
 * finds is on a followed curve of the same n and stable side within one
 * scan step in S, and every followed curve that crosses a grid column
 * inside the window is a crossing the scan finds there within a step.
 * The table's work comment counts every ring spectrum computed, as a
 * counter in the spectrum hook does (before: every seed sample counted as
 * a spectrum, though those proven unstable by one tracked eigenvalue are
 * none: 29 said here for the 22 computed). */
TEST(stabmap_diagram_followed_curves_are_the_scans_crossings)
{
    bkf_stability_spec s = paper_spec(2);
    s.diagram = 1;
    s.nu = -0.98;
    s.to = -0.94;
    s.nu_step = 0.02;
    /* S from 4 (n = 2 exists above 3.39 here): below, the trains of n = 1
     * near their fold (S 3.29), which the test does not compare, were 40%
     * of its cost; the scan's step stays 1 */
    s.S = 4;
    s.S_to = 8;
    s.S_samples = 4;
    s.tol = 1e-5;
    s.S_tol = 0.01;
    s.seed_step = 0.04;
    s.threads = 2;
    size_t calls = 0;
    s.spectrum = counted_spectrum;
    s.spectrum_data = &calls;
    char *followed = library_output(write_stability, &s, BKF_IO_TSV);
    CHECK(followed);
    size_t tracked = 0, said = work_said(followed, &tracked);
    CHECK_MSG(said == calls, "the work comment says %zu ring spectra, the hook counted %zu", said,
              calls);
    CHECK(tracked > 0);
    s.scan = 1;
    s.spectrum = NULL;
    s.threads = 1;
    char *scanned = library_output(write_stability, &s, BKF_IO_TSV);
    CHECK(scanned);
    double step = (s.S_to - s.S) / (double)s.S_samples;
    size_t matched = 0, columns = 0;
    /* n = 2 only, S below 8: n = 1's boundary here starts at a fold where
     * a faster root is born (v 0.357 to 0.499 at nu -0.98, S 3.29; n = 2's
     * at twice S, 6.58, and its boundary above 11 at -0.96 comes down to
     * it): the scan takes the fastest root at each S, the continuation the
     * root it follows, and beyond the fold they are different trains */
    for (int n = 2; followed && scanned && n <= 2; n++) {
        diagram_rows f, g;
        rows_of(followed, "stability", n, &f);
        rows_of(scanned, "stability", n, &g);
        CHECK(f.count >= 2);
        for (size_t i = 0; i < g.count; i++) {
            CHECK_MSG(followed_crosses(&f, g.nu[i], g.S[i], g.above[i], step),
                      "n %d: the scan's crossing at nu %.4f, S %.4f is on no followed curve", n,
                      g.nu[i], g.S[i]);
            matched++;
        }
        for (int k = 0; k <= 2; k++) {
            double x = s.nu + 0.02 * k;
            for (size_t i = 0; i + 1 < f.count; i++) {
                if (f.curve[i] != f.curve[i + 1]) continue;
                double a = f.nu[i], b = f.nu[i + 1];
                if (!((a <= x && x < b) || (b < x && x <= a))) continue;
                double Sx = f.S[i] + (x - a) / (b - a) * (f.S[i + 1] - f.S[i]);
                /* inside the window the scan brackets every crossing
                 * that is alone in its step (the three columns' are) */
                if (!(Sx > s.S && Sx < s.S_to)) continue;
                int found = 0;
                for (size_t j = 0; j < g.count; j++)
                    if (fabs(g.nu[j] - x) < 1e-9 && fabs(g.S[j] - Sx) <= step &&
                        g.above[j] == f.above[i])
                        found = 1;
                CHECK_MSG(found, "n %d: the followed curve at nu %.4f, S %.4f: no scan crossing",
                          n, x, Sx);
                columns++;
            }
        }
    }
    /* the scan's n = 2 crossings: one on each of the three columns, the
     * middle one's found by following alone */
    CHECK(matched >= 3);
    /* the followed curve crosses the columns -0.98 and -0.96, each checked
     * (it ends on -0.94, which the half-open segments leave out) */
    CHECK_MSG(columns >= 2, "%zu columns of the followed curve checked", columns);
    bkf_test_note("%zu crossings of the scan on the followed curves; %zu ring spectra", matched,
                  calls);
    free(followed);
    free(scanned);
}

/* A curve that stalls (or is cut at its work cap) leaves the rest of its
 * boundary unseen: its n gets no state rows, as the columns' states would
 * otherwise carry the drawn half's side past where the unseen half turns.
 * At gamma 1, c 0.6, n = 3 turns in nu near -0.89 (S 8.85 at nu -0.95 up
 * to the turn, back to nu -0.95 at S 11.44); the trace stalled at the turn
 * and the states said the columns stable above the lower half up to the
 * window's top.  The trace now passes the turn (2026-11-29 fifth): both
 * ends of n = 3's curve are seen, and its state rows are only on columns
 * beyond the turn, which no curve crosses. */
TEST(stabmap_diagram_no_states_for_an_n_whose_curve_stalled)
{
    bkf_stability_spec s = bkf_stability_spec_default();
    s.diagram = 1;
    s.gamma = 1;
    s.c = 0.6;
    s.n = 3;
    s.nu = -0.95;
    s.to = -0.87;
    s.S = 8;
    s.S_to = 14;
    s.S_samples = 6;
    s.threads = 1;
    char *tsv = library_output(write_stability, &s, BKF_IO_TSV);
    CHECK(tsv);
    if (!tsv) return;
    int unseen[4] = {0}, curves_of_3 = 0;
    for (const char *line = tsv; line && *line; line = strchr(line, '\n') ? strchr(line, '\n') + 1 : NULL) {
        size_t curve;
        int n;
        if (sscanf(line, "# curve %zu (n %d)", &curve, &n) != 2 || n < 1 || n > 3) continue;
        const char *end = strchr(line, '\n');
        size_t len = end ? (size_t)(end - line) : strlen(line);
        char text[1024];
        snprintf(text, sizeof text, "%.*s", (int)(len < sizeof text - 1 ? len : sizeof text - 1), line);
        if (strstr(text, ": stalled") || strstr(text, ": max_points")) unseen[n] = 1;
        if (n == 3) curves_of_3++;
    }
    CHECK(curves_of_3 >= 1);
    for (int n = 1; n <= 3; n++) {
        diagram_rows st;
        rows_of(tsv, "state", n, &st);
        bkf_test_note("n %d: %s, %zu state rows", n, unseen[n] ? "a curve ends unseen" : "curves end seen",
                      st.count);
        if (unseen[n]) CHECK_MSG(st.count == 0, "n %d: a curve stalled, yet %zu state rows", n, st.count);
        for (size_t i = 0; n == 3 && i < st.count; i++)
            CHECK_MSG(st.nu[i] > -0.89, "n 3: a state row at nu %.4f, inside the turn", st.nu[i]);
    }
    CHECK_MSG(!unseen[3], "n 3's curve ends unseen (stalled or cut)");
    free(tsv);
}

/* The existence boundary S = n c gamma g_inf(nu) against the speed solver:
 * no root of n just below it, a root just above; at gamma 2 g does not dip
 * below k, so it is n k(nu) c gamma in closed form. */
TEST(stabmap_existence_against_speeds)
{
    bkf_error e;
    bkf_model_params p = bkf_model_params_paper();
    double S;
    int attained;
    CHECK_STATUS(bkf_stabmap_existence(&p, 3, &S, &attained, &e), BKF_OK);
    CHECK(!attained);
    CHECK(fabs(S - 3 * bkf_asym_k(p.nu) * p.c * p.gamma) < 1e-9 * S);
    bkf_speeds_options so = bkf_speeds_options_default();
    so.n_from = so.n_to = 3;
    bkf_speeds_table t;
    p.S = S * (1 - 1e-3);
    CHECK_STATUS(bkf_speeds_find(&p, &so, &t, &e), BKF_OK);
    CHECK(t.count == 0);
    bkf_speeds_table_free(&t);
    p.S = S * (1 + 1e-3);
    CHECK_STATUS(bkf_speeds_find(&p, &so, &t, &e), BKF_OK);
    CHECK(t.count >= 1);
    bkf_speeds_table_free(&t);
}

/* The train of n fronts on S and the train of one front on S/n are the
 * same wave: same speed, same spectrum on the infinite line. */
TEST(stabmap_train_n_on_S_is_train_1_on_S_over_n)
{
    bkf_error e;
    bkf_model_params p = bkf_model_params_paper(), q = p;
    q.S = p.S / 4;
    bkf_speeds_options so = bkf_speeds_options_default();
    so.n_from = so.n_to = 4;
    bkf_speeds_table t4, t1;
    CHECK_STATUS(bkf_speeds_find(&p, &so, &t4, &e), BKF_OK);
    so.n_from = so.n_to = 1;
    CHECK_STATUS(bkf_speeds_find(&q, &so, &t1, &e), BKF_OK);
    CHECK(t4.count >= 1 && t1.count >= 1);
    CHECK(fabs(t4.roots[0].v - t1.roots[0].v) < 1e-8 * t1.roots[0].v);
    bkf_trainspec_options o = bkf_trainspec_options_default();
    bkf_trainspec_eigenvalue a[6], b[6];
    bkf_trainspec_train ta = {4, t4.roots[0].v}, tb = {1, t1.roots[0].v};
    CHECK_STATUS(bkf_trainspec_line(&p, &ta, &o, 6, a, &e), BKF_OK);
    CHECK_STATUS(bkf_trainspec_line(&q, &tb, &o, 6, b, &e), BKF_OK);
    for (int i = 0; i < 6; i++) {
        CHECK(fabs(a[i].kappa - b[i].kappa) < 1e-12);
        CHECK(fabs(a[i].re - b[i].re) <= a[i].err + b[i].err + 1e-9);
    }
    bkf_speeds_table_free(&t4);
    bkf_speeds_table_free(&t1);
}

/* The oscillation's bands against module floquet's own drivers: at nu
 * -0.94 a long-wave band (lambda ~ a c^2 q^2, a > 0: bkf_floquet_longwave)
 * and a period-doubling band around c q_c = 0.3 x 2.89 (Fig. 4a); at -0.92
 * none (stable: bkf_floquet_diagram's interval (-0.935, -0.827)). */
TEST(stabmap_oscillation_bands)
{
    bkf_error e;
    double lo[4], hi[4];
    int kind[4];
    size_t count;
    CHECK_STATUS(bkf_stabmap_bands(2, 0.3, -0.94, 6, 120, 1e-7, lo, hi, kind, 4, &count, &e),
                 BKF_OK);
    CHECK_MSG(count == 2 && lo[0] == 0 && kind[0] == 0 && kind[1] == 1 &&
                  lo[1] < 0.3 * 2.89 && hi[1] > 0.3 * 2.89,
              "%zu bands, (%g, %g) kind %d", count, lo[0], hi[0], kind[0]);
    bkf_floquet *f = bkf_floquet_alloc();
    bkf_floquet_options fo = bkf_floquet_options_default();
    fo.tol = 1e-8;
    bkf_floquet_point pt;
    CHECK_STATUS(bkf_floquet_set(f, 2, 0.3, -0.94, &fo, &e), BKF_OK);
    for (size_t i = 0; i < count; i++)
        for (int side = 0; side < 2; side++) {
            double p = side ? hi[i] : lo[i];
            if (p == 0) continue;
            CHECK_STATUS(bkf_floquet_eval(f, p / 0.3, &pt, &e), BKF_OK);
            CHECK(fabs(pt.lambda) < 1e-5);
        }
    bkf_floquet_free(f);
    CHECK_STATUS(bkf_stabmap_bands(2, 0.3, -0.92, 6, 120, 1e-7, lo, hi, kind, 4, &count, &e),
                 BKF_OK);
    CHECK(count == 0);
}

/* The asymptotics product through the catalogue, as a scene reaches it: the
 * grid table equals the CLI's (BKF_CLI_PATH) for the same inputs, a row's
 * errors are those of the formulas of asymptotics.h evaluated here, and the
 * cross-key rules answer with scene wording. */
#define _POSIX_C_SOURCE 200809L
#include "bkfront/approx.h"
#include "bkfront/asymptotics.h"
#include "bkfront/catalog.h"
#include "bkfront/version.h"

#include "harness.h"

#include "cli_support.h"

#include <math.h>
#include <string.h>

#ifndef BKF_CLI_PATH
#error "BKF_CLI_PATH (the built bkfront binary) is defined by the Makefile for tests"
#endif

#define GRID_ARGS "--grid --mu 1:1000:4 --log --nu 0,0.5"

static void apply(const bkf_catalog_entry *c, void *spec, const char *key, const char *text)
{
    bkf_error e = {0};
    CHECK_MSG(bkf_catalog_apply(c, spec, key, text, "", &e) == BKF_OK, "%s = %s: %s", key,
              text ? text : "(switch)", e.message);
}

/* The grid of GRID_ARGS through the catalogue, with the CLI's provenance. */
static char *grid_from_catalog(void)
{
    const bkf_catalog_entry *c = bkf_catalog_find("asymptotics");
    CHECK(c);
    if (!c) return NULL;
    bkf_error e = {0};
    void *spec = bkf_catalog_spec_new(c, &e);
    CHECK(spec);
    apply(c, spec, "mode", "grid");
    apply(c, spec, "log", "yes"); /* before mu: it spaces mu's range */
    apply(c, spec, "mu", "1:1000:4");
    apply(c, spec, "nu", "0,0.5");
    CHECK_STATUS(c->check(spec, "", &e), BKF_OK);
    char *text = NULL;
    size_t size = 0;
    FILE *f = open_memstream(&text, &size);
    CHECK(f);
    bkf_provenance prov = {"bkfront " BKF_VERSION_STRING, "bkfront asymptotics " GRID_ARGS};
    int s = c->write(spec, f, BKF_IO_TSV, &prov, NULL, &e);
    CHECK_MSG(s == BKF_OK, "write: %s", e.message);
    fclose(f);
    bkf_catalog_spec_free(c, spec);
    return text;
}

TEST(approx_grid_through_catalog_equals_cli)
{
    char *lib = grid_from_catalog();
    char *cli = bkf_cli_stdout("asymptotics " GRID_ARGS, NULL);
    CHECK(lib && cli);
    if (lib && cli) CHECK_MSG(strcmp(lib, cli) == 0, "library:\n%s\nCLI:\n%s", lib, cli);
    free(cli);

    /* Row by row (TSV at %.17g reads back exactly): the errors are those of
     * the formulas evaluated here, on the numerical T the row carries. */
    const char *q = lib;
    while (q && *q == '#') q = strchr(q, '\n') + 1;
    q = q ? strchr(q, '\n') : NULL; /* the header */
    size_t rows = 0;
    while (q && *++q) {
        double v[7];
        char *end;
        for (int k = 0; k < 7; k++) {
            v[k] = strtod(q, &end);
            q = end;
        }
        double mu = v[0], nu = v[1], T = v[2];
        CHECK_CLOSE(v[4], fabs(bkf_asym_period_leading(mu, nu) - T) / T, 1e-12, 0);
        CHECK_CLOSE(v[5], fabs(bkf_asym_period_large(mu, nu) - T) / T, 1e-12, 0);
        CHECK_CLOSE(v[6], fabs(bkf_asym_period_small(mu, nu) - T) / T, 1e-12, 0);
        if (mu == 1 && nu == 0) /* van der Pol at mu = 1: T = 6.66328685933 (published) */
            CHECK_CLOSE(T, 6.663286859323, 1e-11, 0);
        if (mu == 1000) /* the corrections matter: far closer than k mu alone */
            CHECK_MSG(v[5] < 1e-5 && v[5] < v[4] / 100, "mu = 1000, nu = %g: %g vs %g", nu,
                      v[5], v[4]);
        rows++;
    }
    CHECK_MSG(rows == 8, "%zu rows, want 4 mu x 2 nu", rows);
    free(lib);
}

TEST(approx_rules_in_scene_words)
{
    const bkf_catalog_entry *c = bkf_catalog_find("asymptotics");
    CHECK(c);
    if (!c) return;
    bkf_error e = {0};
    void *spec = bkf_catalog_spec_new(c, &e);
    CHECK(spec);
    /* No mode: the rule names the scene's key. */
    CHECK_STATUS(c->check(spec, "s.scene:3: ", &e), BKF_EINPUT);
    CHECK_MSG(strcmp(e.message, "s.scene:3: mode: give exactly one of fit, map, grid") == 0,
              "%s", e.message);
    /* The switches are the command line's spelling of the mode key; a
     * scene may write either, but only one mode. */
    CHECK_STATUS(bkf_catalog_apply(c, spec, "grid", "yes", "", &e), BKF_OK);
    apply(c, spec, "mode", "map");
    CHECK_STATUS(c->check(spec, "", &e), BKF_EINPUT);
    CHECK_STATUS(bkf_catalog_apply(c, spec, "grid", "no", "", &e), BKF_OK);
    bkf_catalog_spec_free(c, spec);
    spec = bkf_catalog_spec_new(c, &e);
    apply(c, spec, "mode", "map");
    CHECK_STATUS(c->check(spec, "", &e), BKF_OK); /* nu and eps have defaults */
    apply(c, spec, "mu", "10");
    CHECK_STATUS(c->check(spec, "", &e), BKF_EINPUT);
    CHECK_MSG(strcmp(e.message, "mu: not used with mode map") == 0, "%s", e.message);
    bkf_catalog_spec_free(c, spec);

    bkf_approx_spec s = bkf_approx_spec_default();
    s.fit = 1;
    const bkf_option *nu = bkf_option_find(bkf_approx_options, bkf_approx_noptions, "nu");
    const bkf_option *mu = bkf_option_find(bkf_approx_options, bkf_approx_noptions, "mu");
    CHECK(nu && mu);
    if (nu && mu) {
        CHECK_STATUS(bkf_option_apply(nu, &s, "0", "--", &e), BKF_OK);
        CHECK_STATUS(bkf_option_apply(mu, &s, "10:100:5", "--", &e), BKF_OK);
        CHECK_STATUS(bkf_approx_check(&s, "--", &e), BKF_EINPUT);
        CHECK_MSG(strstr(e.message, "--mu: fit range 10:100:5 is outside 1 <= A < B"), "%s",
                  e.message);
        CHECK_STATUS(bkf_option_apply(mu, &s, "10:100:10", "--", &e), BKF_OK);
        CHECK_STATUS(bkf_approx_check(&s, "--", &e), BKF_OK);
    }
    bkf_approx_spec_free(&s);
}

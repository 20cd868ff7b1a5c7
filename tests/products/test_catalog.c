/* The catalogue: every product reachable by name, its keys validated by its
 * own table, and a table written through it equal to the executable's. */
#define _POSIX_C_SOURCE 200809L
#include "harness.h"

#include "cli_support.h"

#include <stdlib.h>
#include <string.h>

#include "bkfront/catalog.h"

TEST(catalog_every_entry_makes_and_frees_a_spec)
{
    CHECK(bkf_catalog_count() >= 6);
    for (size_t i = 0; i < bkf_catalog_count(); i++) {
        const bkf_catalog_entry *e = bkf_catalog_at(i);
        CHECK(e && e->name && e->summary);
        CHECK(bkf_catalog_find(e->name) == e);
        size_t n = 0;
        CHECK(e->options(&n) != NULL && n > 0);
        bkf_error err;
        void *spec = bkf_catalog_spec_new(e, &err);
        CHECK(spec != NULL);
        CHECK_STATUS(bkf_catalog_apply(e, spec, "no-such-key", "1", "", &err), BKF_EINPUT);
        CHECK_MSG(strstr(err.message, e->name) && strstr(err.message, "no-such-key"), "%s",
                  err.message);
        bkf_catalog_spec_free(e, spec);
    }
    CHECK(bkf_catalog_find("nonexistent") == NULL);
    CHECK(bkf_catalog_at(bkf_catalog_count()) == NULL);
}

static char *write_table(const char *product, const char *const *kv)
{
    const bkf_catalog_entry *e = bkf_catalog_find(product);
    CHECK(e != NULL);
    bkf_error err;
    void *spec = bkf_catalog_spec_new(e, &err);
    for (size_t i = 0; kv[i]; i += 2)
        CHECK_MSG(bkf_catalog_apply(e, spec, kv[i], kv[i + 1], "", &err) == BKF_OK, "%s",
                  err.message);
    CHECK_MSG(e->check(spec, "", &err) == BKF_OK, "%s", err.message);
    char *data = NULL;
    size_t size = 0;
    FILE *f = open_memstream(&data, &size);
    CHECK(f != NULL);
    CHECK_MSG(e->write(spec, f, BKF_IO_TSV, NULL, NULL, &err) == BKF_OK, "%s", err.message);
    fclose(f);
    bkf_catalog_spec_free(e, spec);
    return data;
}

/* The rows (no comment lines) of a table. */
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

TEST(catalog_period_is_the_published_value_and_the_cli_table)
{
    const char *kv[] = {"mu", "1", "nu", "0", "tol", "1e-12", NULL};
    char *table = write_table("period", kv);
    /* T(mu = 1, nu = 0) = 6.663286859323130 (published, DESIGN.md). */
    char *rows = rows_of(table);
    char *line2 = strchr(rows, '\n');
    CHECK(line2 != NULL);
    double mu, nu, T;
    CHECK(sscanf(line2 + 1, "%lf\t%lf\t%lf", &mu, &nu, &T) == 3);
    CHECK_CLOSE(T, 6.663286859323130, 1e-12, 0);
    /* The executable, through its flags, writes the same rows. */
    char *buf = bkf_cli_stdout("period --mu 1 --nu 0 --tol 1e-12", NULL);
    char *cli_rows = rows_of(buf);
    free(buf);
    CHECK_MSG(strcmp(rows, cli_rows) == 0, "library:\n%s\ncli:\n%s", rows, cli_rows);
    free(cli_rows);
    free(rows);
    free(table);
}

TEST(catalog_switch_keys_take_yes_or_no)
{
    const bkf_catalog_entry *e = bkf_catalog_find("period");
    bkf_error err;
    void *spec = bkf_catalog_spec_new(e, &err);
    CHECK_STATUS(bkf_catalog_apply(e, spec, "log", "yes", "", &err), BKF_OK);
    CHECK_STATUS(bkf_catalog_apply(e, spec, "log", "no", "", &err), BKF_OK);
    CHECK_STATUS(bkf_catalog_apply(e, spec, "log", "maybe", "", &err), BKF_EINPUT);
    CHECK(strstr(err.message, "log") && strstr(err.message, "yes or no"));
    CHECK_STATUS(bkf_catalog_apply(e, spec, "tol", "1e-30", "", &err), BKF_EINPUT);
    CHECK_MSG(strstr(err.message, "tol") != NULL, "%s", err.message);
    bkf_catalog_spec_free(e, spec);
}

TEST(catalog_required_keys_are_named)
{
    /* The command line's parser enforces required flags; through the
     * catalogue the check does, with the key's name and range. */
    const bkf_catalog_entry *e = bkf_catalog_find("period");
    bkf_error err;
    void *spec = bkf_catalog_spec_new(e, &err);
    CHECK_STATUS(e->check(spec, "", &err), BKF_EINPUT);
    CHECK_MSG(strstr(err.message, "mu is required") == err.message, "%s", err.message);
    CHECK(err.status == BKF_EINPUT);
    bkf_catalog_spec_free(e, spec);

    /* a required choice (branch's param, -1 until given) is named too, not
     * the first number after it */
    e = bkf_catalog_find("branch");
    spec = bkf_catalog_spec_new(e, &err);
    static const char *const kv[] = {"gamma", "2", "c", "0.3", "nu", "-0.96", NULL};
    for (size_t i = 0; kv[i]; i += 2) CHECK_STATUS(bkf_catalog_apply(e, spec, kv[i], kv[i + 1], "", &err), BKF_OK);
    CHECK_STATUS(e->check(spec, "", &err), BKF_EINPUT);
    CHECK_MSG(strstr(err.message, "param is required (one of S, nu, gamma, c, h)") == err.message,
              "%s", err.message);
    bkf_catalog_spec_free(e, spec);
}

/* The hooks' cancel flag stops period between points, on a grid and along a
 * branch (issue 32: Python's Ctrl-C raises it and waits for the product). */
TEST(catalog_period_stops_on_the_cancel_flag)
{
    const bkf_catalog_entry *e = bkf_catalog_find("period");
    const char *grid[] = {"mu", "1:100:100000", "nu", "0.5", NULL};
    const char *along[] = {"mu", "1:100:50", "nu", "0.5", "continue", "mu", NULL};
    const char *const *cases[] = {grid, along};
    for (size_t c = 0; c < 2; c++) {
        bkf_error err = {0};
        void *spec = bkf_catalog_spec_new(e, &err);
        CHECK(spec != NULL);
        for (const char *const *kv = cases[c]; *kv; kv += 2)
            CHECK_STATUS(bkf_catalog_apply(e, spec, kv[0], kv[1], "", &err), BKF_OK);
        CHECK_STATUS(e->check(spec, "", &err), BKF_OK);
        volatile sig_atomic_t cancel = 1;
        bkf_catalog_hooks hooks = {.cancel = &cancel};
        char *buf = NULL;
        size_t size = 0;
        FILE *out = open_memstream(&buf, &size);
        CHECK_STATUS(e->write(spec, out, BKF_IO_TSV, NULL, &hooks, &err), BKF_ECANCELED);
        fclose(out);
        CHECK_MSG(strstr(err.message, "canceled") != NULL, "%s", err.message);
        /* at most the branch's first point: 1e5 points would take minutes */
        CHECK(strstr(buf, "1\t0.5\t") == NULL || c == 1);
        free(buf);
        bkf_catalog_spec_free(e, spec);
    }
}

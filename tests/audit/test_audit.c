/* The audit's fixed small sample (make test): sets drawn by the audit's
 * own rule (seed 1), every product checked against its independent route
 * (tests/audit/audit.c); a defect fails the test with its reproducer.
 * The full run is `make audit` (docs/testing.md). */
#include "harness.h"

#include <string.h>

#include "audit/audit.h"

static void audit_sample(const size_t *indices, size_t count)
{
    audit_options opt = audit_options_default();
    audit_rows rows = {0};
    for (size_t i = 0; i < count; i++) {
        audit_set s = audit_draw(1, indices[i]);
        audit_run_set(indices[i], &s, &opt, &rows);
    }
    size_t ok = 0, refused = 0;
    for (size_t i = 0; i < rows.count; i++) {
        const audit_row *r = &rows.rows[i];
        ok += r->status == AUDIT_OK;
        refused += r->status == AUDIT_REFUSAL;
        CHECK_MSG(r->status != AUDIT_DEFECT, "set %zu %s: %s\n    %s", r->set, r->product, r->detail, r->repro);
    }
    /* every product was reached: a sample that audits nothing cannot fail */
    static const char *products[] = {"period", "speeds", "speeds-scan", "speeds-tight", "stability", "line",
                                     "check", "floquet"};
    for (size_t k = 0; k < sizeof products / sizeof products[0]; k++) {
        size_t n = 0;
        for (size_t i = 0; i < rows.count; i++) n += !strcmp(rows.rows[i].product, products[k]);
        CHECK_MSG(n > 0, "no %s row", products[k]);
    }
    bkf_test_note("%zu rows: %zu OK, %zu refusals, 0 defects", rows.count, ok, refused);
    audit_rows_free(&rows);
}

/* One set a test, so that the two run side by side (set 1 is most of the
 * cost: 20.5 s of CPU against 1.1). */
TEST(audit_fixed_sample_set_1)
{
    /* a stable train near |nu| = 1 (at 7ac1dea the check's sigma_max was a
     * window's edge, error 0) */
    static const size_t sets[] = {1};
    audit_sample(sets, 1);
}

TEST(audit_fixed_sample_set_2)
{
    /* unstable trains at small gamma (the line at kappa 0 gave the
     * translation) */
    static const size_t sets[] = {2};
    audit_sample(sets, 1);
}

/* The rows survive their text form (the workers of `make audit` hand them
 * to the parent as lines). */
TEST(audit_rows_round_trip)
{
    audit_row r = {7, "stability", AUDIT_DEFECT, "n 1: sigma 0.1 vs Hill 0.2", "bkfront stability --n 1"}, back;
    char line[1024];
    FILE *f = tmpfile();
    CHECK(f != NULL);
    audit_row_write(f, &r);
    rewind(f);
    CHECK(fgets(line, sizeof line, f) != NULL);
    fclose(f);
    CHECK(audit_row_read(line, &back) == 0);
    CHECK(back.set == 7 && back.status == AUDIT_DEFECT);
    CHECK(!strcmp(back.product, r.product) && !strcmp(back.detail, r.detail) && !strcmp(back.repro, r.repro));
    /* the draw is a function of (seed, index) alone, inside the domain */
    for (size_t i = 0; i < 60; i++) {
        audit_set a = audit_draw(3, i), b = audit_draw(3, i);
        CHECK(a.gamma == b.gamma && a.c == b.c && a.nu == b.nu && a.S == b.S);
        CHECK(a.gamma >= 0.3 && a.gamma <= 8 && a.c >= 0.05 && a.c <= 1.5);
        CHECK(a.nu >= -0.99 && a.nu <= 0.99 && a.S >= 5 && a.S <= 60);
    }
}

/* Scene kinds as the products declare them (catalog.h): every product of
 * the catalogue has a kind, every key a kind names is its product's, and
 * every key that names a file or folder (BKF_OPT_PATH) stays inside the
 * output folder unless the scene is trusted: the table of those keys is
 * read from the declarations, so a key added later is tried here too. */
#define _POSIX_C_SOURCE 200809L
#include "harness.h"

#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "bkfront/scene.h"
#include "cli_support.h"

#define MODEL "[model]\ngamma = 2\nc = 0.3\nnu = -0.96\nS = 20\n"

/* The kind of this name, or -1. */
static int kind_of(const char *name)
{
    for (size_t k = 0; k < bkf_scene_kind_count(); k++)
        if (strcmp(bkf_scene_kind_name((bkf_scene_kind)k), name) == 0) return (int)k;
    return -1;
}

/* The key of one item of a declaration's keys ("^N?model=chain" is N). */
static void item_key(const char *item, size_t len, char *key, size_t size)
{
    if (*item == '^' || *item == '+' || *item == '@') item++, len--;
    size_t n = strcspn(item, "=!?: ");
    if (n > len) n = len;
    snprintf(key, size, "%.*s", (int)n, item);
}

/* Every key of a step's keys is an option of its product the scene may
 * set, or (the source of an explicit fan-out) the kind's own scene key. */
static void check_step_keys(const char *kind, const bkf_catalog_step *d,
                            const bkf_catalog_entry *product)
{
    size_t n;
    const bkf_option *table = product->options(&n);
    size_t fanouts = 0;
    for (size_t i = 0; i < n; i++) fanouts += (table[i].flags & BKF_OPT_FANOUT) != 0;
    CHECK_MSG(fanouts <= 1, "%s: %zu keys fan out", product->name, fanouts);
    for (const char *c = d->keys ? d->keys : ""; *c;) {
        size_t len = strcspn(c, " ");
        char key[64];
        item_key(c, len, key, sizeof key);
        const bkf_option *o = bkf_option_find(table, n, key);
        CHECK_MSG(o && !(o->flags & BKF_OPT_CLI_ONLY), "kind %s: '%s' is no scene key of %s",
                  kind, key, product->name);
        c += len + (c[len] == ' ');
    }
    const char *switches[] = {d->first, d->last};
    for (int w = 0; w < 2; w++)
        for (const char *c = switches[w] ? switches[w] : ""; *c;) {
            size_t len = strcspn(c, " ");
            char key[64];
            snprintf(key, sizeof key, "%.*s", (int)len, c);
            const bkf_option *o = bkf_option_find(table, n, key);
            /* no-progress is the command line's: a product without it is
             * not given it */
            CHECK_MSG(strcmp(key, "no-progress") == 0 || (o && o->type == BKF_OPT_SWITCH),
                      "kind %s: '%s' is no switch of %s", kind, key, product->name);
            c += len + (c[len] == ' ');
        }
}

TEST(scene_kinds_are_declared_by_every_catalogue_product)
{
    size_t declared = 0;
    for (size_t i = 0; i < bkf_catalog_count(); i++) {
        const bkf_catalog_entry *e = bkf_catalog_at(i);
        CHECK_MSG(e->nkinds >= 1, "product %s declares no scene kind", e->name);
        for (size_t j = 0; j < e->nkinds; j++) {
            const bkf_catalog_kind *k = &e->kinds[j];
            CHECK_MSG(kind_of(k->name) >= 0, "kind %s of %s is no scene kind", k->name, e->name);
            check_step_keys(k->name, &k->step, e);
            if (k->also.product) {
                const bkf_catalog_entry *also = bkf_catalog_find(k->also.product);
                CHECK_MSG(also, "kind %s: no product %s", k->name, k->also.product);
                if (also) check_step_keys(k->name, &k->also, also);
            }
            declared++;
        }
    }
    /* every kind but figure (the scene's own) is a product's */
    CHECK(bkf_scene_kind_count() == declared + 1);
    CHECK(kind_of("figure") == BKF_SCENE_FIGURE);
    /* a kind of its own through the catalogue alone: bench has no enum
     * value, needs no model keys it does not declare, and is planned as
     * any other */
    bkf_scene *s = NULL;
    bkf_error e = {0};
    CHECK_STATUS(bkf_scene_parse_string("[model]\n[bench b]\nproduct = box\nquick = yes\n",
                                        "t.scene", &s, &e),
                 BKF_OK);
    if (!s) return;
    CHECK(s->products[0].kind >= BKF_SCENE_NKINDS);
    bkf_scene_plan plan;
    bkf_scene_plan_options o = {.outdir = "o"};
    CHECK_STATUS(bkf_scene_make_plan(s, &o, &plan, &e), BKF_OK);
    char *cmd = plan.nsteps == 1 ? bkf_scene_step_command(&plan.steps[0]) : NULL;
    CHECK_MSG(cmd && strcmp(cmd, "bench --product box --quick --out o/b.tsv") == 0, "got %s", cmd);
    free(cmd);
    bkf_scene_plan_free(&plan);
    bkf_scene_free(s);
}

/* A section of each kind that parses, before the path key is added; a kind
 * with a path key and no entry here fails the test. */
static const struct {
    const char *kind, *body;
} bases[] = {
    {"spacetime", "tmax = 1\nN = 32\n"},
    {"sweep", "x = nu=-0.98:-0.9:2\ntmax = 1\nN = 32\n"},
    {"orbit", "max-points = 4\n"},
};

static const char *base_of(const char *kind)
{
    for (size_t i = 0; i < sizeof bases / sizeof bases[0]; i++)
        if (strcmp(bases[i].kind, kind) == 0) return bases[i].body;
    return NULL;
}

/* The value the plan passes for `key`, or NULL. */
static const char *planned(const bkf_scene_plan *plan, const char *key)
{
    for (size_t i = 0; i < plan->nsteps; i++)
        for (size_t a = 0; a < plan->steps[i].nargs; a++)
            if (strcmp(plan->steps[i].args[a].key, key) == 0) return plan->steps[i].args[a].value;
    return NULL;
}

/* One path key of one kind with one value: refused (at the key's line,
 * naming it) or passed inside outdir; trusted, passed as written. */
static void try_path(const char *kind, const char *key, const char *value, int outside)
{
    char text[1024], want[256];
    const char *base = base_of(kind);
    snprintf(text, sizeof text, MODEL "[%s t]\n%s%s = %s\n", kind, base, key, value);
    int line = 7 + (int)bkf_count_lines(base);
    bkf_scene *s = NULL;
    bkf_error e = {0};
    /* parsing checks the value; where it may go is the run's to say */
    CHECK_MSG(bkf_scene_parse_string(text, "t.scene", &s, &e) == BKF_OK, "%s %s = %s: %s", kind,
              key, value, e.message);
    if (!s) return;
    bkf_scene_plan plan;
    bkf_scene_plan_options o = {.outdir = "out"};
    int st = bkf_scene_make_plan(s, &o, &plan, &e);
    if (outside) {
        snprintf(want, sizeof want, "t.scene:%d: [%s t]: %s: '%s' is outside the output folder",
                 line, kind, key, value);
        CHECK_MSG(st == BKF_EINPUT && strncmp(e.message, want, strlen(want)) == 0,
                  "%s %s = %s: got %d '%s'", kind, key, value, st, e.message);
        o.trust = 1;
        CHECK_STATUS(bkf_scene_make_plan(s, &o, &plan, &e), BKF_OK);
        const char *v = planned(&plan, key);
        snprintf(want, sizeof want, "%s%s", value[0] == '/' ? "" : "out/", value);
        CHECK_MSG(v && strcmp(v, want) == 0, "trusted %s %s: %s", kind, key, v ? v : "(none)");
    } else {
        CHECK_MSG(st == BKF_OK, "%s %s = %s: %s", kind, key, value, e.message);
        const char *v = st ? NULL : planned(&plan, key);
        snprintf(want, sizeof want, "out/%s", value);
        CHECK_MSG(v && strcmp(v, want) == 0, "%s %s: %s", kind, key, v ? v : "(none)");
    }
    bkf_scene_plan_free(&plan);
    bkf_scene_free(s);
}

TEST(scene_paths_stay_in_the_output_folder)
{
    size_t tried = 0;
    for (size_t k = 0; k < bkf_scene_kind_count(); k++) {
        const char *kind = bkf_scene_kind_name((bkf_scene_kind)k);
        if (k == BKF_SCENE_FIGURE) continue;
        const bkf_catalog_entry *entry = NULL;
        for (size_t i = 0; !entry && i < bkf_catalog_count(); i++)
            for (size_t j = 0; j < bkf_catalog_at(i)->nkinds; j++)
                if (strcmp(bkf_catalog_at(i)->kinds[j].name, kind) == 0) entry = bkf_catalog_at(i);
        CHECK_MSG(entry, "kind %s has no product", kind);
        if (!entry) continue;
        size_t n;
        const bkf_option *table = entry->options(&n);
        for (size_t i = 0; i < n; i++) {
            if (!(table[i].flags & BKF_OPT_PATH) || (table[i].flags & BKF_OPT_CLI_ONLY)) continue;
            CHECK_MSG(base_of(kind), "kind %s: key %s names a file; give the kind a base section "
                      "here", kind, table[i].name);
            if (!base_of(kind)) continue;
            try_path(kind, table[i].name, "/tmp/bkfront-outside", 1);
            try_path(kind, table[i].name, "../outside", 1);
            try_path(kind, table[i].name, "sub/../../outside", 1);
            try_path(kind, table[i].name, "inside.h5", 0);
            tried++;
        }
    }
    /* spacetime's spacetime and snapshots, sweep's fields at least */
    CHECK_MSG(tried >= 3, "%zu keys tried", tried);
}

/* The reproducer of the attack: a scene's snapshots = /ABSOLUTE wrote
 * there, figures or not.  Now nothing is written and the key's line is
 * named; a name inside lands in the output folder. */
TEST(run_writes_no_scene_path_outside_its_folder)
{
    char dir[] = "/tmp/bkfront-paths-XXXXXX";
    CHECK(mkdtemp(dir));
    char scene[256], out[256], victim[256], text[1024];
    snprintf(scene, sizeof scene, "%s/s.scene", dir);
    snprintf(out, sizeof out, "%s/out", dir);
    snprintf(victim, sizeof victim, "%s/victim.tsv", dir);
    snprintf(text, sizeof text, MODEL "[spacetime s]\ntmax = 1\nN = 32\nsnapshots = %s\n", victim);
    FILE *f = fopen(scene, "w");
    CHECK(f);
    if (!f) return;
    fputs(text, f);
    fclose(f);
    bkf_cli_result r = BKF_CLI("run", "--no-figures", "--out", out, scene);
    CHECK_MSG(r.code == 2 && strstr(r.err, "s.scene:9: [spacetime s]: snapshots:"), "rc %d: %s",
              r.code, r.err);
    bkf_cli_result_free(&r);
    struct stat st;
    CHECK(stat(victim, &st) != 0 && stat(out, &st) != 0);
    r = BKF_CLI("run", "--no-figures", "--trust-scene", "--out", out, scene);
    CHECK_MSG(r.code == 0, "trusted: rc %d: %s", r.code, r.err);
    bkf_cli_result_free(&r);
    CHECK(stat(victim, &st) == 0);
    unlink(victim);
    snprintf(text, sizeof text, "%s/s.dat", out);
    unlink(text);
    snprintf(text, sizeof text, "%s/s_diag.tsv", out);
    unlink(text);
    rmdir(out);
    unlink(scene);
    rmdir(dir);
}

/* A section's keys are its product's (and those of the other step its kind
 * makes): what no product has is refused, not passed over, and a value of
 * the other step's list is checked by that step's option under the
 * scene's name for it. */
TEST(scene_keys_are_the_declared_products_keys)
{
    bkf_scene *s = NULL;
    bkf_error e = {0};
    /* threshold's max_points was accepted and never passed (floquet has
     * no such key) */
    CHECK_STATUS(bkf_scene_parse_string(MODEL "[threshold t]\nmax_points = 3\n", "t.scene", &s,
                                        &e),
                 BKF_EINPUT);
    CHECK_MSG(strstr(e.message, "t.scene:7: [threshold t]: unknown key 'max_points'"), "%s",
              e.message);
    CHECK_STATUS(bkf_scene_parse_string(MODEL "[sweep w]\nx = nu=-0.9\nthresholds = 1,0\n",
                                        "t.scene", &s, &e),
                 BKF_EINPUT);
    CHECK_MSG(strstr(e.message, "t.scene:8: thresholds: 0 is not in"), "%s", e.message);
    CHECK_STATUS(bkf_scene_parse_string(MODEL "[sweep w]\nx = nu=-0.9\nsearch = 0.5:0.1\n",
                                        "t.scene", &s, &e),
                 BKF_EINPUT);
    CHECK_MSG(strstr(e.message, "t.scene:8: search"), "%s", e.message);
    /* and the sweep's list makes one Floquet diagram per gamma */
    s = NULL;
    CHECK_STATUS(bkf_scene_parse_string(MODEL "[sweep w]\nx = nu=-0.9\nthresholds = 1:2:3\n",
                                        "t.scene", &s, &e),
                 BKF_OK);
    if (!s) return;
    bkf_scene_plan plan;
    bkf_scene_plan_options o = {.outdir = "o"};
    CHECK_STATUS(bkf_scene_make_plan(s, &o, &plan, &e), BKF_OK);
    CHECK(plan.nsteps == 4);
    char *cmd = plan.nsteps == 4 ? bkf_scene_step_command(&plan.steps[2]) : NULL;
    CHECK_MSG(cmd && strcmp(cmd, "floquet --diagram --gamma 1.5 --c 0.3 --search -0.999:0.999 "
                                 "--tol 1e-6 --out o/w_floquet_2.tsv") == 0,
              "got %s", cmd);
    free(cmd);
    bkf_scene_plan_free(&plan);
    bkf_scene_free(s);
}

/* The plan (scene.h): a scene's sections as steps, one loop over the
 * kinds' declarations, the same computation planned once. */
#define _POSIX_C_SOURCE 200809L
#include "scene_internal.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "bkfront/io.h"
#include "bkfront/plot.h"

/* ------------------------------------------------------------------ plan */

typedef struct {
    bkf_scene_arg *v;
    size_t n, cap;
} arg_list;

static void args_free(bkf_scene_arg *v, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        free(v[i].key);
        free(v[i].value);
    }
    free(v);
}

static int arg_push(arg_list *b, const char *key, const char *value, int output, int fixed)
{
    if (b->n == b->cap) {
        size_t cap = b->cap ? 2 * b->cap : 16;
        bkf_scene_arg *g = realloc(b->v, cap * sizeof *g);
        if (!g) return 0;
        b->v = g;
        b->cap = cap;
    }
    bkf_scene_arg *a = &b->v[b->n];
    *a = (bkf_scene_arg){.key = strdup(key), .value = value ? strdup(value) : NULL,
                         .output = output, .fixed = fixed};
    if (!a->key || (value && !a->value)) {
        free(a->key);
        free(a->value);
        return 0;
    }
    b->n++;
    return 1;
}

static int arg_has(const arg_list *b, const char *key)
{
    for (size_t i = 0; i < b->n; i++)
        if (strcmp(b->v[i].key, key) == 0) return 1;
    return 0;
}

/* The same computation: the same product and settings, whatever the files. */
static int same_computation(const bkf_scene_step *a, const arg_list *b, const char *product)
{
    if (strcmp(a->product, product) != 0) return 0;
    size_t i = 0, j = 0;
    for (;;) {
        while (i < a->nargs && a->args[i].output) i++;
        while (j < b->n && b->v[j].output) j++;
        if (i == a->nargs || j == b->n) return i == a->nargs && j == b->n;
        const bkf_scene_arg *x = &a->args[i], *y = &b->v[j];
        if (strcmp(x->key, y->key) != 0 || !x->value != !y->value ||
            (x->value && strcmp(x->value, y->value) != 0))
            return 0;
        i++, j++;
    }
}

/* What the planner keeps while it builds a plan (bkf_scene_plan.planner_). */
typedef struct {
    scene_lookup computations;   /* product steps by computation_hash */
    size_t steps_cap;
} planner;

/* Over what same_computation compares: the product and the settings that
 * are not outputs. */
static size_t computation_hash(const arg_list *b, const char *product)
{
    size_t h = scene_hash_text(SCENE_HASH_SEED, product);
    for (size_t j = 0; j < b->n; j++) {
        if (b->v[j].output) continue;
        h = scene_hash_text(h, b->v[j].key);
        h = b->v[j].value ? scene_hash_text(h, b->v[j].value) : h * 31u + 1u;
    }
    return h;
}

typedef struct {
    const bkf_scene_plan *plan;
    const arg_list *b;
    const char *product;
} computation_query;

static int same_step(size_t i, const void *data)
{
    const computation_query *q = data;
    return q->plan->steps[i].kind == BKF_SCENE_STEP_PRODUCT &&
           same_computation(&q->plan->steps[i], q->b, q->product);
}

static int plan_add_user(bkf_scene_step *st, size_t product)
{
    for (size_t i = 0; i < st->nusers; i++)
        if (st->users[i] == product) return 1;
    size_t *g = scene_grow_for_push(st->users, st->nusers, sizeof *g);
    if (!g) return 0;
    st->users = g;
    g[st->nusers++] = product;
    return 1;
}

static int product_add_step(bkf_scene_plan *plan, size_t product, size_t step)
{
    bkf_scene_product_plan *pp = &plan->products[product];
    size_t *g = scene_grow_for_push(pp->steps, pp->nsteps, sizeof *g);
    if (!g) return 0;
    pp->steps = g;
    g[pp->nsteps++] = step;
    return plan_add_user(&plan->steps[step], product);
}

/* Adds the step, or finds the same computation already planned.  Takes
 * the args and output over (frees them on failure, or when building failed:
 * ok 0 or no output path). */
static int finish_step(bkf_scene_plan *plan, size_t product, bkf_scene_step_kind kind,
                       const char *name, int ok, arg_list *b, char *output,
                       size_t data_product)
{
    if (!ok || !output) goto fail;
    planner *pl = plan->planner_;
    size_t h = 0;
    if (kind == BKF_SCENE_STEP_PRODUCT) {
        h = computation_hash(b, name);
        computation_query q = {plan, b, name};
        size_t i = scene_lookup_find(&pl->computations, h, same_step, &q);
        if (i != SIZE_MAX) {
            args_free(b->v, b->n);
            free(output);
            plan->deduplicated++;
            return product_add_step(plan, product, i);
        }
    }
    if (plan->nsteps == pl->steps_cap) {
        size_t cap = pl->steps_cap ? 2 * pl->steps_cap : 16;
        bkf_scene_step *g = realloc(plan->steps, cap * sizeof *g);
        if (!g) goto fail;
        plan->steps = g;
        pl->steps_cap = cap;
    }
    if (kind == BKF_SCENE_STEP_PRODUCT && !scene_lookup_add(&pl->computations, h, plan->nsteps))
        goto fail;
    bkf_scene_step *g = plan->steps;
    g[plan->nsteps] = (bkf_scene_step){.kind = kind, .product = name,
                                       .entry = bkf_catalog_find(name), .args = b->v,
                                       .nargs = b->n, .output = output,
                                       .data_product = data_product};
    plan->nsteps++;
    return product_add_step(plan, product, plan->nsteps - 1);
fail:
    free(output);
    args_free(b->v, b->n);
    return 0;
}

static char *out_path(const char *dir, const char *name, const char *suffix)
{
    size_t n = strlen(dir) + strlen(name) + strlen(suffix) + 2;
    char *p = malloc(n);
    if (p) snprintf(p, n, "%s/%s%s", dir, name, suffix);
    return p;
}

/* The switches a kind always passes (its first and last). */
static int fixed_keys(arg_list *b, const char *keys)
{
    char buf[64];
    snprintf(buf, sizeof buf, "%s", keys ? keys : "");
    char *save = NULL;
    for (char *t = strtok_r(buf, " ", &save); t; t = strtok_r(NULL, " ", &save))
        if (!arg_push(b, t, NULL, 0, 1)) return 0;
    return 1;
}

/* ------------------------------------------------------- a kind's steps */

/* What an item passes for p, or NULL. */
static const char *item_value(const bkf_scene *s, const bkf_scene_product *p, const scene_key_item *it)
{
    if (it->always) return it->value;
    const char *v = scene_key(s, p, it->key, it->inherit);
    if (!v && it->has_value && it->value[0] == '$') {
        const char *named = scene_own_value(p, it->value + 1);
        v = named ? scene_key(s, p, named, 1) : NULL;
    } else if (!v && it->has_value) {
        v = it->value;
    }
    if (v && it->omit[0] && strcmp(v, it->omit) == 0) return NULL;
    if (v && it->if_key[0]) {
        const char *c = scene_key(s, p, it->if_key, 1);
        if (!c || strcmp(c, it->if_value) != 0) return NULL;
    }
    return v;
}

/* A file or folder the scene names (a BKF_OPT_PATH key) goes inside the
 * output folder, as the scene's own outputs do: a relative name without
 * "..", taken there.  Elsewhere only when the caller trusts the scene.
 * NULL: refused (*refused set) or out of memory. */
static char *confined_path(const char *dir, const char *value, int trust, int *refused)
{
    int outside = value[0] == '/';
    for (const char *c = value; *c && !outside; c += strcspn(c, "/"), c += *c == '/')
        if (strncmp(c, "..", 2) == 0 && (c[2] == '/' || c[2] == '\0')) outside = 1;
    *refused = outside && !trust;
    if (*refused) return NULL;
    return value[0] == '/' ? strdup(value) : out_path(dir, value, "");
}

typedef struct {
    bkf_scene_plan *plan;
    const bkf_scene *s;
    size_t index;
    const bkf_scene_plan_options *o;
    bkf_error *err;
} plan_context;

/* Pushes key = value of the step's product: a switch as the bare key
 * (left out at "no"); a path kept inside the output folder; a list A:B:N
 * of a key with a log switch followed by that switch. */
static int push_key(const plan_context *c, arg_list *b, const bkf_catalog_entry *entry,
                    const char *key, const char *value)
{
    size_t n;
    const bkf_option *table = entry->options(&n);
    const bkf_option *opt = bkf_option_find(table, n, key);
    if (opt && opt->type == BKF_OPT_SWITCH) {
        if (strcmp(value, "no") == 0) return BKF_OK;
        value = NULL;
    }
    if (opt && (opt->flags & BKF_OPT_PATH)) {
        const bkf_scene_product *p = &c->s->products[c->index];
        int refused;
        char *path = confined_path(c->plan->outdir, value, c->o->trust, &refused);
        if (refused) {
            char shown[96];
            return bkf_error_set(c->err, BKF_EINPUT,
                                 "%s:%d: [%s %s]: %s: '%s' is outside the output folder (a name "
                                 "inside it, without '..'; --trust-scene allows it)",
                                 c->s->path, scene_key_line(c->s, p, key), scene_kind_name(p->kind), p->name,
                                 key, bkf_option_shown(value, shown, sizeof shown));
        }
        int ok = path && arg_push(b, key, path, 0, 0);
        free(path);
        return ok ? BKF_OK : bkf_error_set(c->err, BKF_ENOMEM, "out of memory");
    }
    if (!arg_push(b, key, value, 0, 0)) return bkf_error_set(c->err, BKF_ENOMEM, "out of memory");
    if (opt && (opt->flags & BKF_OPT_LOG_SWITCH) && value && strchr(value, ':'))
        for (size_t i = 0; i < n; i++)
            if (table[i].type == BKF_OPT_SWITCH && table[i].offset == opt->log_offset &&
                !arg_has(b, table[i].name) && !arg_push(b, table[i].name, NULL, 0, 0))
                return bkf_error_set(c->err, BKF_ENOMEM, "out of memory");
    return BKF_OK;
}

/* One step of the declaration: `item` the fan-out key's value for it
 * (NULL: none), `number` its number among count. */
static int plan_one_step(const plan_context *c, const bkf_catalog_entry *entry,
                         const bkf_catalog_step *d, const scene_key_item *items, size_t nitems,
                         const char *fkey, const char *item, size_t number, size_t count,
                         int own)
{
    const bkf_scene_product *p = &c->s->products[c->index];
    arg_list b = {0};
    int st = fixed_keys(&b, d->first) ? BKF_OK : BKF_ENOMEM;
    for (size_t i = 0; !st && i < nitems; i++) {
        const scene_key_item *it = &items[i];
        int skipped = 0;
        for (size_t j = 0; j < nitems; j++) {
            const char *named = items[j].names ? scene_own_value(p, items[j].key) : NULL;
            if (!it->names && named && strcmp(named, it->key) == 0) skipped = 1;
        }
        const char *v = fkey && item && strcmp(it->key, fkey) == 0 ? item : item_value(c->s, p, it);
        if (!skipped && v && !arg_has(&b, it->key)) st = push_key(c, &b, entry, it->key, v);
    }
    /* the section's other keys of the product's table, as written */
    for (size_t i = 0; own && !st && i < p->nentries; i++) {
        char key[sizeof p->entries[i].key];
        scene_option_name(p->entries[i].key, key, sizeof key);
        if (!scene_catalog_option(entry, key) || arg_has(&b, key)) continue;
        const char *v = fkey && item && strcmp(key, fkey) == 0 ? item : p->entries[i].value;
        st = push_key(c, &b, entry, key, v);
    }
    if (!st && !fixed_keys(&b, d->last)) st = BKF_ENOMEM;
    char *output = NULL;
    const char *outputs = d->outputs ? d->outputs : "out=.tsv";
    for (const char *o = outputs; !st && *o;) {
        size_t len = strcspn(o, " "), eq = strcspn(o, "=");
        char key[64], suffix[64], file[BKF_SCENE_NAME_LEN + 96];
        snprintf(key, sizeof key, "%.*s", (int)eq, o);
        snprintf(suffix, sizeof suffix, "%.*s", (int)(len - eq - 1), o + eq + 1);
        char *hash = strchr(suffix, '#');
        if (hash)
            snprintf(file, sizeof file, "%s%.*s%zu%s", p->name, (int)(hash - suffix), suffix,
                     number, hash + 1);
        else if (count > 1)
            snprintf(file, sizeof file, "%s_%zu%s", p->name, number, suffix);
        else
            snprintf(file, sizeof file, "%s%s", p->name, suffix);
        char *path = out_path(c->plan->outdir, file, "");
        if (!path || !arg_push(&b, key, path, 1, 0)) st = BKF_ENOMEM;
        if (!output)
            output = path;
        else
            free(path);
        o += len + (o[len] == ' ');
    }
    if (st) {
        free(output);
        args_free(b.v, b.n);
        return st == BKF_ENOMEM ? bkf_error_set(c->err, st, "out of memory") : st;
    }
    if (!finish_step(c->plan, c->index, BKF_SCENE_STEP_PRODUCT, entry->name, 1, &b, output, 0))
        return bkf_error_set(c->err, BKF_ENOMEM, "out of memory");
    return BKF_OK;
}

/* The steps of one declaration: one per value of its fan-out key's list. */
static int plan_steps(const plan_context *c, const bkf_catalog_entry *entry,
                      const bkf_catalog_step *d, int own)
{
    const bkf_scene_product *p = &c->s->products[c->index];
    size_t nitems;
    scene_key_item *items = scene_parse_items(d->keys, &nitems);
    if (!items && d->keys && *d->keys) return bkf_error_set(c->err, BKF_ENOMEM, "out of memory");
    /* the list: the named section key's ("LIST>KEY": no list, no step), or
     * the table's fan-out key's, as the items pass it (none: one step) */
    char fkey[64] = "";
    const char *list = NULL;
    if (d->fanout) {
        const char *gt = strchr(d->fanout, '>');
        char from[64];
        snprintf(from, sizeof from, "%.*s", (int)(gt - d->fanout), d->fanout);
        snprintf(fkey, sizeof fkey, "%s", gt + 1);
        list = scene_own_value(p, from);
    } else if (scene_fanout_option(entry)) {
        snprintf(fkey, sizeof fkey, "%s", scene_fanout_option(entry)->name);
        list = scene_own_value(p, fkey);
        for (size_t i = 0; i < nitems; i++)
            if (strcmp(items[i].key, fkey) == 0) list = item_value(c->s, p, &items[i]);
    }
    char **values = NULL;
    size_t count = 0;
    int st = BKF_OK;
    if (list && !scene_list_values(list, &values, &count))
        st = bkf_error_set(c->err, BKF_ENOMEM, "out of memory");
    if (!st && !list && !d->fanout)
        st = plan_one_step(c, entry, d, items, nitems, NULL, NULL, 1, 1, own);
    for (size_t i = 0; !st && i < count; i++)
        st = plan_one_step(c, entry, d, items, nitems, fkey, values[i], i + 1, count, own);
    scene_list_values_free(values, count);
    free(items);
    return st;
}

static int plan_figure(bkf_scene_plan *plan, const bkf_scene *s, size_t index,
                       const bkf_scene_plan_options *o)
{
    const bkf_scene_product *p = &s->products[index];
    if (!o->figures) return 1;
    size_t *shown, nshown;
    if (!scene_figure_data(s, scene_own_value(p, "data"), &shown, &nshown, NULL, 0)) return 0;
    if (nshown == 0) { /* checked when parsed */
        free(shown);
        return 0;
    }
    unsigned formats = 0;
    const char *v = scene_own_value(p, "formats");
    if (!v || bkf_plot_parse_formats(v, "", "formats", &formats, NULL) != BKF_OK)
        formats = o->formats ? o->formats : 1u; /* a value is checked when parsed */
    arg_list b = {0};
    int ok = 1;
    char *first = NULL;
    for (int f = 0; ok && f < 3; f++) {
        if (!(formats & (1u << f))) continue;
        char suffix[8];
        snprintf(suffix, sizeof suffix, ".%s", bkf_plot_format_name((bkf_plot_format)f));
        char *path = out_path(plan->outdir, p->name, suffix);
        ok = path && arg_push(&b, "out", path, 1, 0);
        if (!first)
            first = path;
        else
            free(path);
    }
    if (!finish_step(plan, index, BKF_SCENE_STEP_FIGURE, "figure", ok, &b, first, shown[0])) {
        free(shown);
        return 0;
    }
    plan->steps[plan->nsteps - 1].data_products = shown;
    plan->steps[plan->nsteps - 1].ndata = nshown;
    return 1;
}

/* A section's steps: a figure's, or its kind's declaration's. */
static int plan_product(bkf_scene_plan *plan, const bkf_scene *s, size_t index,
                        const bkf_scene_plan_options *o, bkf_error *err)
{
    const bkf_scene_product *p = &s->products[index];
    const scene_kind_info *k = scene_kind_at((int)p->kind);
    if (p->kind == BKF_SCENE_FIGURE)
        return plan_figure(plan, s, index, o) ? BKF_OK : bkf_error_set(err, BKF_ENOMEM, "out of memory");
    if (!k || !k->entry)
        return bkf_error_set(err, BKF_EINPUT, "[%s %s]: no product computes this kind",
                             scene_kind_name(p->kind), p->name);
    plan_context c = {plan, s, index, o, err};
    int st = plan_steps(&c, k->entry, &k->decl->step, 1);
    const bkf_catalog_entry *also = k->decl->also.product ? bkf_catalog_find(k->decl->also.product)
                                                          : NULL;
    if (!st && also) st = plan_steps(&c, also, &k->decl->also, 0);
    return st;
}

/* A figure's `script =` runs a file the scene names, and gnuplot's system()
 * and shell escapes run anything: only in a trusted scene's plan. */
static int untrusted_script(const bkf_scene *s, bkf_error *err)
{
    for (size_t i = 0; i < s->nproducts; i++) {
        const bkf_scene_product *p = &s->products[i];
        if (p->kind != BKF_SCENE_FIGURE) continue;
        for (size_t k = 0; k < p->nentries; k++)
            if (strcmp(p->entries[k].key, "script") == 0)
                return bkf_error_set(err, BKF_EINPUT,
                                     "%s:%d: script = %s: a scene's own gnuplot script can run "
                                     "shell commands; give --trust-scene to run it",
                                     s->path, p->entries[k].line, p->entries[k].value);
    }
    return BKF_OK;
}

int bkf_scene_make_plan(const bkf_scene *s, const bkf_scene_plan_options *o,
                        bkf_scene_plan *plan, bkf_error *err)
{
    *plan = (bkf_scene_plan){0};
    if (!o || !o->outdir || !*o->outdir)
        return bkf_error_set(err, BKF_EINPUT, "plan: no output folder");
    if (o->figures && !o->trust) {
        int st = untrusted_script(s, err);
        if (st) return st;
    }
    if (strpbrk(o->outdir, " \t\n'\""))
        return bkf_error_set(err, BKF_EINPUT,
                             "--out: '%s' holds a space or a quote, which the figure scripts "
                             "cannot take in a file list", o->outdir);
    plan->outdir = strdup(o->outdir);
    plan->products = calloc(s->nproducts ? s->nproducts : 1, sizeof *plan->products);
    plan->nproducts = s->nproducts;
    planner pl = {{0}, 0};
    plan->planner_ = &pl;
    int st = plan->outdir && plan->products ? BKF_OK
                                             : bkf_error_set(err, BKF_ENOMEM, "out of memory");
    /* Data first, figures after everything they could show. */
    for (int pass = 0; !st && pass < 2; pass++)
        for (size_t i = 0; !st && i < s->nproducts; i++)
            if ((s->products[i].kind == BKF_SCENE_FIGURE) == (pass == 1))
                st = plan_product(plan, s, i, o, err);
    scene_lookup_free(&pl.computations);
    plan->planner_ = NULL;
    if (st) bkf_scene_plan_free(plan);
    return st;
}

void bkf_scene_plan_free(bkf_scene_plan *plan)
{
    if (!plan) return;
    for (size_t i = 0; i < plan->nsteps; i++) {
        args_free(plan->steps[i].args, plan->steps[i].nargs);
        free(plan->steps[i].output);
        free(plan->steps[i].users);
        free(plan->steps[i].data_products);
    }
    free(plan->steps);
    for (size_t i = 0; plan->products && i < plan->nproducts; i++) free(plan->products[i].steps);
    free(plan->products);
    free(plan->outdir);
    *plan = (bkf_scene_plan){0};
}

char **bkf_scene_step_argv(const bkf_scene_step *step, int *argc)
{
    char **v = calloc(2 * step->nargs + 2, sizeof *v);
    int n = 0;
    if (!v || !(v[n++] = strdup(step->product))) goto fail;
    for (size_t i = 0; i < step->nargs; i++) {
        const bkf_scene_arg *a = &step->args[i];
        size_t len = strlen(a->key) + 3;
        if (!(v[n] = malloc(len))) goto fail;
        snprintf(v[n++], len, "--%s", a->key);
        if (a->value && !(v[n++] = strdup(a->value))) goto fail;
    }
    if (argc) *argc = n;
    return v;
fail:
    bkf_scene_argv_free(v);
    return NULL;
}

void bkf_scene_argv_free(char **argv)
{
    if (!argv) return;
    for (char **p = argv; *p; p++) free(*p);
    free(argv);
}

double bkf_scene_step_cost(const bkf_scene_step *step)
{
    if (!step || step->kind == BKF_SCENE_STEP_FIGURE || !step->entry) return 0.0;
    if (!step->entry->cost) return 1.0;
    bkf_error e;
    void *spec = bkf_catalog_spec_new(step->entry, &e);
    if (!spec) return 1.0;
    double cost = 1.0;
    /* (outputs not applied: the spec is only read, no file is touched) */
    if (!scene_apply_args(step->entry, step->args, step->nargs, spec, 0, NULL, &e) &&
        !step->entry->check(spec, "", &e))
        cost = step->entry->cost(spec);
    bkf_catalog_spec_free(step->entry, spec);
    return isfinite(cost) && cost >= 0 ? cost : 1.0;
}

char *bkf_scene_step_command(const bkf_scene_step *step)
{
    if (step->kind == BKF_SCENE_STEP_FIGURE) return strdup("gnuplot");
    int argc = 0;
    char **argv = bkf_scene_step_argv(step, &argc);
    if (!argv) return NULL;
    char *line = bkf_io_command_line(argc, (const char *const *)argv);
    bkf_scene_argv_free(argv);
    return line;
}

/* Scene files (scene.h): parsing with libinih and checking, key by key
 * and as a whole (through the plan).  The plan is scene_plan.c's, the
 * kinds and where values come from scene_keys.c's, a run scene_run.c's
 * and scene_jobs.c's. */
#define _POSIX_C_SOURCE 200809L
#include "bkfront/scene.h"

#include <ctype.h>
#include <ini.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "bkfront/cycle.h"
#include "bkfront/io.h"
#include "bkfront/model.h"
#include "bkfront/options.h"
#include "bkfront/pde.h"
#include "bkfront/plot.h"
#include "scene_internal.h"

/* ------------------------------------------------------------ key table */

/* The keys of the scene's own sections: [model], [accuracy] and figures.
 * A product's section has its product's keys (catalog.h). */
typedef enum { V_GAMMA, V_C, V_NU, V_S, V_TOL, V_GRID_N, V_MODEL, V_PIXELS, V_FORMATS, V_TEXT } value_type;

#define K(kind) (1u << (kind))
#define K_MODEL (1u << 30)     /* [model] */
#define K_ACCURACY (1u << 29)  /* [accuracy] */

typedef struct {
    const char *key;
    value_type type;
    unsigned where;
    const char *form;   /* for messages: the valid values */
} key_spec;

static const key_spec keys[] = {
    {"gamma", V_GAMMA, K_MODEL, "a number in [1e-6, 1e6]"},
    {"c", V_C, K_MODEL, "a number >= 0"},
    {"nu", V_NU, K_MODEL, "a number in (-1, 1)"},
    {"S", V_S, K_MODEL, "a number > 0"},
    {"model", V_MODEL, K_MODEL, "continuum or chain"},
    {"tol", V_TOL, K_ACCURACY, "a number in [1e-14, 0.1]"},
    {"N", V_GRID_N, K_ACCURACY, "an integer in [8, 1048576]"},
    {"data", V_TEXT, K(BKF_SCENE_FIGURE), "the name of a product of this scene"},
    {"script", V_TEXT, K(BKF_SCENE_FIGURE), "a gnuplot script path"},
    {"formats", V_FORMATS, K(BKF_SCENE_FIGURE), "png, pdf, svg or a list such as png,svg"},
    {"title", V_TEXT, K(BKF_SCENE_FIGURE), "text"},
    {"width", V_PIXELS, K(BKF_SCENE_FIGURE), "pixels"},
    {"height", V_PIXELS, K(BKF_SCENE_FIGURE), "pixels"},
};
#define NKEYS (sizeof keys / sizeof keys[0])

/* ------------------------------------------------------------- checking */

static int check_value(const key_spec *spec, const char *v, bkf_error *err)
{
    const char *k = spec->key;
    double x;
    size_t n;
    int s;
    switch (spec->type) {
    case V_GAMMA:
        if ((s = bkf_option_parse_double(v, "", k, &x, err))) return s;
        if (!(x >= BKF_CYCLE_MU_MIN && x <= BKF_CYCLE_MU_MAX))
            return bkf_error_set(err, BKF_EINPUT, "gamma: %s is outside [1e-6, 1e6]", v);
        return BKF_OK;
    case V_C:
        if ((s = bkf_option_parse_double(v, "", k, &x, err))) return s;
        if (x < 0) return bkf_error_set(err, BKF_EINPUT, "c: %s must be >= 0", v);
        return BKF_OK;
    case V_NU:
        if ((s = bkf_option_parse_double(v, "", k, &x, err))) return s;
        if (!(fabs(x) < 1))
            return bkf_error_set(err, BKF_EINPUT,
                                 "nu: %s is outside (-1, 1), where there are no fronts or "
                                 "oscillations", v);
        return BKF_OK;
    case V_S:
        if ((s = bkf_option_parse_double(v, "", k, &x, err))) return s;
        if (!(x > 0)) return bkf_error_set(err, BKF_EINPUT, "%s: %s must be > 0", k, v);
        return BKF_OK;
    case V_TOL:
        if ((s = bkf_option_parse_double(v, "", k, &x, err))) return s;
        if (!(x >= 1e-14 && x <= 0.1))
            return bkf_error_set(err, BKF_EINPUT, "tol: %s is outside [%g, %g]", v, 1e-14, 0.1);
        return BKF_OK;
    case V_GRID_N:
        if ((s = bkf_option_parse_count(v, 1, BKF_PDE_N_MAX, "", k, &n, err))) return s;
        if (n < BKF_PDE_N_MIN)
            return bkf_error_set(err, BKF_EINPUT, "N: %s is below %d", v, BKF_PDE_N_MIN);
        return BKF_OK;
    case V_MODEL: {
        static const char *const m[] = {"continuum", "chain", NULL};
        int i;
        return bkf_option_parse_choice(v, m, "", k, &i, err);
    }
    case V_PIXELS:
        return bkf_option_parse_count(v, 1, BKF_PLOT_PIXELS_MAX, "", k, &n, err);
    case V_FORMATS:
        return bkf_plot_parse_formats(v, "", k, NULL, err);
    case V_TEXT:
        if (!*v) return bkf_error_set(err, BKF_EINPUT, "%s: the value is empty", k);
        for (const unsigned char *p = (const unsigned char *)v; *p; p++)
            if (*p < 0x20 || *p == 0x7f)
                return bkf_error_set(err, BKF_EINPUT, "%s: the value holds a control character", k);
        return BKF_OK;
    }
    return BKF_OK;
}

/* A key of a kind's section: an option of its product's table, or one the
 * kind's other step takes from the section (the list that makes its
 * steps, each value that step's KEY; a key of its list its product has). */
typedef struct {
    const bkf_catalog_entry *entry;
    const bkf_option *opt;
    int fanout;               /* a list, checked value by value */
} kind_key;

static int kind_key_find(bkf_scene_kind kind, const char *key, kind_key *out)
{
    const scene_kind_info *k = scene_kind_at((int)kind);
    if (!k || !k->entry) return 0;
    char name[64];
    scene_option_name(key, name, sizeof name);
    const bkf_option *opt = scene_catalog_option(k->entry, name);
    if (opt) {
        *out = (kind_key){k->entry, opt, opt == scene_fanout_option(k->entry)};
        return 1;
    }
    const bkf_catalog_step *also = &k->decl->also;
    const bkf_catalog_entry *a = also->product ? bkf_catalog_find(also->product) : NULL;
    if (!a) return 0;
    const char *gt = also->fanout ? strchr(also->fanout, '>') : NULL;
    if (gt && strlen(key) == (size_t)(gt - also->fanout) &&
        strncmp(key, also->fanout, (size_t)(gt - also->fanout)) == 0) {
        *out = (kind_key){a, scene_catalog_option(a, gt + 1), 1};
        return out->opt != NULL;
    }
    size_t n;
    scene_key_item *items = scene_parse_items(also->keys, &n);
    int found = 0;
    for (size_t i = 0; !found && i < n; i++)
        if (!items[i].always && strcmp(items[i].key, name) == 0 && scene_catalog_option(a, name)) {
            *out = (kind_key){a, scene_catalog_option(a, name), 0};
            found = 1;
        }
    free(items);
    return found;
}

/* The scene keys of a kind, for messages ("gamma, c, nu, ..."). */
static void kind_keys_known(bkf_scene_kind kind, char *known, size_t size)
{
    const scene_kind_info *k = scene_kind_at((int)kind);
    size_t n;
    const bkf_option *table = k && k->entry ? k->entry->options(&n) : NULL;
    for (size_t i = 0; table && i < n; i++)
        if (!(table[i].flags & BKF_OPT_CLI_ONLY)) scene_append(known, size, ", ", table[i].name);
    const bkf_catalog_step *also = k && k->decl ? &k->decl->also : NULL;
    if (!also || !also->product) return;
    if (also->fanout) {
        char list[64];
        snprintf(list, sizeof list, "%.*s", (int)strcspn(also->fanout, ">"), also->fanout);
        scene_append(known, size, ", ", list);
    }
    size_t ni;
    scene_key_item *items = scene_parse_items(also->keys, &ni);
    kind_key kk;
    for (size_t i = 0; i < ni; i++)
        if (!items[i].always && !scene_catalog_option(k->entry, items[i].key) &&
            kind_key_find(kind, items[i].key, &kk))
            scene_append(known, size, ", ", items[i].key);
    free(items);
}

/* A value of a kind's key through the option that checks the flag (a list
 * value by value, as the plan passes them), messages naming the key as
 * the scene wrote it where the option has another name. */
static int kind_key_check(const kind_key *kk, const char *key, const char *value, bkf_error *err)
{
    void *spec = bkf_catalog_spec_new(kk->entry, err);
    if (!spec) return BKF_ENOMEM;
    int s = BKF_OK;
    char name[64];
    scene_option_name(key, name, sizeof name);
    if (kk->fanout) {
        bkf_option named = *kk->opt;
        named.name = strcmp(name, kk->opt->name) == 0 ? kk->opt->name : key;
        bkf_list list;
        s = bkf_list_parse(value, 0, 0, SCENE_MAX_POINTS, "", key, &list, err);
        for (size_t i = 0; !s && i < list.count; i++) {
            char item[64];
            snprintf(item, sizeof item, "%.15g", list.values[i]);
            s = bkf_option_apply(&named, spec, item, "", err);
        }
        bkf_list_free(&list);
    } else {
        s = bkf_catalog_apply(kk->entry, spec, kk->opt->name, value, "", err);
    }
    bkf_catalog_spec_free(kk->entry, spec);
    return s;
}

/* ------------------------------------------------------------- parsing */

typedef struct {
    bkf_scene *s;
    const char *name;
    const char *text;       /* string being read */
    size_t pos;
    int line;               /* of the line last handed to inih */
    int status;
    bkf_error *err;
    char section[BKF_SCENE_VALUE_LEN]; /* inih's current section, as recorded */
    int section_kind;       /* -1 model, -2 accuracy, >= 0: product index */
    int seen_model, seen_accuracy;
} parse_state;

static int fail(parse_state *st, int line, const char *fmt, ...)
{
    if (st->status) return 0;
    char msg[BKF_ERROR_LEN];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    /* the message quotes the user's text: keep it one printable line */
    for (char *c = msg; *c; c++)
        if ((unsigned char)*c < 0x20 || *c == 0x7f) *c = '?';
    st->status = bkf_error_set(st->err, BKF_EINPUT, "%s:%d: %s", st->name, line, msg);
    return 0;
}

static int valid_name(const char *name)
{
    if (!*name || strlen(name) >= BKF_SCENE_NAME_LEN) return 0;
    for (const char *p = name; *p; p++)
        if (!((*p >= 'a' && *p <= 'z') || (*p >= 'A' && *p <= 'Z') || (*p >= '0' && *p <= '9') ||
              *p == '_' || *p == '-'))
            return 0;
    return 1;
}

/* A section header line, seen by the reader before inih parses it: sections
 * with no keys must exist too, and inih does not report them. */
static void header_line(parse_state *st, const char *line)
{
    if (st->status) return;
    /* inih skips what isspace() calls space: so must we, to see the same
     * section headers */
    const char *p = line;
    while (isspace((unsigned char)*p)) p++;
    if (*p != '[') return;
    const char *end = strchr(p, ']');
    if (!end) return;  /* inih reports it */
    char inner[BKF_SCENE_VALUE_LEN];
    snprintf(inner, sizeof inner, "%.*s", (int)(end - p - 1), p + 1);
    /* inih strips the section name's ends too */
    char *a = inner;
    while (isspace((unsigned char)*a)) a++;
    size_t n = strlen(a);
    while (n && isspace((unsigned char)a[n - 1])) a[--n] = '\0';
    snprintf(st->section, sizeof st->section, "%s", a);

    if (strcmp(a, "model") == 0 || strcmp(a, "accuracy") == 0) {
        int *seen = a[0] == 'm' ? &st->seen_model : &st->seen_accuracy;
        if (*seen) {
            fail(st, st->line, "[%s] is given twice", a);
            return;
        }
        *seen = 1;
        st->section_kind = a[0] == 'm' ? -1 : -2;
        return;
    }
    char kind[BKF_SCENE_VALUE_LEN], name[BKF_SCENE_VALUE_LEN] = "", extra[BKF_SCENE_VALUE_LEN] = "";
    int fields = sscanf(a, "%255s %255s %255s", kind, name, extra);
    int k = -1;
    size_t nk = bkf_scene_kind_count();
    for (size_t i = 0; fields >= 1 && i < nk; i++)
        if (strcmp(kind, scene_kind_name((bkf_scene_kind)i)) == 0) k = (int)i;
    if (k < 0) {
        char known[512] = "model, accuracy";
        for (size_t i = 0; i < nk; i++) scene_append(known, sizeof known, ", ", scene_kind_name((bkf_scene_kind)i));
        fail(st, st->line, "unknown section [%s] (%s)", a, known);
        return;
    }
    if (fields == 3) {
        fail(st, st->line, "[%s]: a section is [KIND] or [KIND NAME]", a);
        return;
    }
    if (fields == 1) snprintf(name, sizeof name, "%s", kind);
    if (!valid_name(name)) {
        fail(st, st->line, "[%s]: the name '%s' must be letters, digits, _ or - (at most %d)", a,
             name, BKF_SCENE_NAME_LEN - 1);
        return;
    }
    bkf_scene *s = st->s;
    int is_figure = k == BKF_SCENE_FIGURE;
    size_t h = scene_hash_text(SCENE_HASH_SEED + (size_t)is_figure, name);
    scene_name_query q = {s, name, is_figure};
    scene_lookup *names = s->names_;
    if (!names && (s->names_ = names = calloc(1, sizeof *names)) == NULL) {
        st->status = bkf_error_set(st->err, BKF_ENOMEM, "out of memory");
        return;
    }
    size_t used = scene_lookup_find(names, h, scene_same_name, &q);
    if (used != SIZE_MAX) {
        fail(st, st->line, "[%s]: the name '%s' is already used on line %d", a, name,
             s->products[used].line);
        return;
    }
    bkf_scene_product *grown = scene_grow_for_push(s->products, s->nproducts, sizeof *grown);
    if (!grown || !scene_lookup_add(names, h, s->nproducts)) {
        if (grown) s->products = grown;
        st->status = bkf_error_set(st->err, BKF_ENOMEM, "out of memory");
        return;
    }
    s->products = grown;
    bkf_scene_product *prod = &s->products[s->nproducts];
    *prod = (bkf_scene_product){.kind = (bkf_scene_kind)k, .line = st->line};
    snprintf(prod->name, sizeof prod->name, "%.*s", BKF_SCENE_NAME_LEN - 1, name);
    st->section_kind = (int)s->nproducts++;
}

static char *reader(char *str, int num, void *stream)
{
    parse_state *st = stream;
    if (!st->text[st->pos]) return NULL;
    const char *start = st->text + st->pos;
    size_t len = strcspn(start, "\n");
    st->line++;
    if (len + 1 >= (size_t)num) {
        fail(st, st->line, "the line is longer than %d characters", num - 3);
        st->pos += len;
        if (st->text[st->pos]) st->pos++;
        str[0] = '\0';  /* parse nothing of it */
        return str;
    }
    memcpy(str, start, len);
    str[len] = '\0';
    st->pos += len;
    if (st->text[st->pos]) st->pos++;
    header_line(st, str);
    return str;
}

static bkf_scene_entry *push_entry(bkf_scene_entry **list, size_t *n)
{
    bkf_scene_entry *grown = scene_grow_for_push(*list, *n, sizeof *grown);
    if (!grown) return NULL;
    *list = grown;
    return &grown[(*n)++];
}

static int handler(void *user, const char *section, const char *name, const char *value)
{
    parse_state *st = user;
    if (st->status) return 1;
    if (!*section) return fail(st, st->line, "'%s' comes before any [section]", name);
    /* a header inih accepted but the line reader did not recognise */
    if (st->section_kind < -2 || st->section_kind >= (int)st->s->nproducts ||
        strcmp(section, st->section) != 0)
        return fail(st, st->line, "the section header before '%s' is not understood", name);
    unsigned where;
    bkf_scene_entry **list;
    size_t *count;
    if (st->section_kind == -1 || st->section_kind == -2) {
        where = st->section_kind == -1 ? K_MODEL : K_ACCURACY;
        list = &st->s->model;
        count = &st->s->nmodel;
    } else {
        bkf_scene_product *p = &st->s->products[st->section_kind];
        where = K(p->kind);
        list = &p->entries;
        count = &p->nentries;
    }
    const key_spec *spec = NULL;
    kind_key kk = {0};
    int by_kind = st->section_kind >= 0 &&
                  kind_key_find(st->s->products[st->section_kind].kind, name, &kk);
    char known[512] = "";
    for (size_t i = 0; i < NKEYS; i++) {
        if (!(keys[i].where & where)) continue;
        if (strcmp(keys[i].key, name) == 0) spec = &keys[i];
        scene_append(known, sizeof known, ", ", keys[i].key);
    }
    if (st->section_kind >= 0)
        kind_keys_known(st->s->products[st->section_kind].kind, known, sizeof known);
    if (!spec && !by_kind)
        return fail(st, st->line, "[%s]: unknown key '%s' (%s)", st->section, name, known);
    for (size_t i = 0; i < *count; i++)
        if (strcmp((*list)[i].key, name) == 0)
            return fail(st, st->line, "[%s]: '%s' is already set on line %d", st->section, name,
                        (*list)[i].line);
    if (strlen(value) >= BKF_SCENE_VALUE_LEN)
        return fail(st, st->line, "%s: the value is longer than %d characters", name,
                    BKF_SCENE_VALUE_LEN - 1);
    bkf_error e;
    if (by_kind) {
        int s = kind_key_check(&kk, name, value, &e);
        if (s == BKF_ENOMEM) {
            st->status = bkf_error_set(st->err, s, "out of memory");
            return 0;
        }
        if (s) return fail(st, st->line, "%s", e.message);
    } else if (check_value(spec, value, &e)) {
        return fail(st, st->line, "%s (%s)", e.message, spec->form);
    }
    bkf_scene_entry *entry = push_entry(list, count);
    if (!entry) {
        st->status = bkf_error_set(st->err, BKF_ENOMEM, "out of memory");
        return 0;
    }
    snprintf(entry->key, sizeof entry->key, "%s", name);
    snprintf(entry->value, sizeof entry->value, "%s", value);
    entry->line = st->line;
    return 1;
}

const char *bkf_scene_value(const bkf_scene *s, const bkf_scene_product *p, const char *key)
{
    const char *v = p ? scene_entry_value(p->entries, p->nentries, key) : NULL;
    if (v) return v;
    int accuracy = 0;
    for (size_t i = 0; i < NKEYS; i++)
        accuracy |= (keys[i].where & K_ACCURACY) && strcmp(keys[i].key, key) == 0;
    if (p && accuracy && !scene_takes_inherited(p, key)) return NULL;
    return scene_entry_value(s->model, s->nmodel, key);
}

static int entry_line(const bkf_scene_product *p, const char *key)
{
    for (size_t i = 0; i < p->nentries; i++)
        if (strcmp(p->entries[i].key, key) == 0) return p->entries[i].line;
    return p->line;
}

/* What needs the whole scene: required keys, references, the model's
 * parameters where a product needs them. */
static int check_scene(parse_state *st)
{
    bkf_scene *s = st->s;
    if (!st->seen_model) return fail(st, 1, "the scene has no [model] section");
    if (s->nproducts == 0) return fail(st, st->line, "the scene asks for no product");
    for (size_t i = 0; i < s->nproducts; i++) {
        const bkf_scene_product *p = &s->products[i];
        if (p->kind == BKF_SCENE_FIGURE) {
            const char *data = scene_entry_value(p->entries, p->nentries, "data");
            if (!data) return fail(st, p->line, "[figure %s]: give data = NAME of the product shown", p->name);
            size_t *idx, count;
            char bad[BKF_SCENE_VALUE_LEN];
            if (!scene_figure_data(s, data, &idx, &count, bad, sizeof bad)) {
                st->status = bkf_error_set(st->err, BKF_ENOMEM, "out of memory");
                return 0;
            }
            free(idx);
            if (bad[0])
                return fail(st, entry_line(p, "data"), "data: no product named '%s' in this scene",
                            bad);
            continue;
        }
        /* the keys its kind declares required (+KEY), but the one a
         * continuation varies (@KEY names it) */
        const scene_kind_info *k = scene_kind_at((int)p->kind);
        size_t n = 0;
        scene_key_item *items = k && k->decl ? scene_parse_items(k->decl->step.keys, &n) : NULL;
        const char *missing = NULL;
        for (size_t j = 0; !missing && j < n; j++) {
            int varied = 0;
            for (size_t v = 0; v < n; v++) {
                const char *named = items[v].names ? scene_own_value(p, items[v].key) : NULL;
                varied |= named && strcmp(named, items[j].key) == 0;
            }
            if (items[j].required && !varied && !scene_key(s, p, items[j].key, 1))
                missing = items[j].key;
        }
        if (missing)
            fail(st, p->line, "[%s %s]: %s is not set here nor in [model]", scene_kind_name(p->kind),
                 p->name, missing);
        free(items);
        if (missing) return 0;
    }
    return 1;
}

/* What the catalogue's checks judge on the whole spec (nu inside the active
 * range, what goes together), at parse time: a scene that parses runs its
 * products past their checks.  The message names its key first (options.h:
 * "PREFIXNAME: ..."): the error is given at that key's line. */
static int validate_plan(parse_state *st)
{
    bkf_scene_plan plan;
    /* where the scene's paths may go is the run's to say (trust) */
    bkf_scene_plan_options o = {.outdir = ".", .figures = 0, .trust = 1};
    bkf_error e;
    int made = bkf_scene_make_plan(st->s, &o, &plan, &e);
    if (made) {
        st->status = bkf_error_set(st->err, made, "%s", e.message);
        return 0;
    }
    for (size_t i = 0; !st->status && i < plan.nsteps; i++) {
        const bkf_scene_step *step = &plan.steps[i];
        if (!step->entry) continue;
        void *spec = bkf_catalog_spec_new(step->entry, &e);
        if (!spec) {
            st->status = bkf_error_set(st->err, BKF_ENOMEM, "out of memory");
            break;
        }
        const bkf_scene_product *p = &st->s->products[step->users[0]];
        size_t bad = step->nargs;
        int s = scene_apply_args(step->entry, step->args, step->nargs, spec, 0, &bad, &e);
        if (!s) s = step->entry->check(spec, "", &e);
        bkf_catalog_spec_free(step->entry, spec);
        if (s == BKF_ENOMEM) {
            st->status = bkf_error_set(st->err, s, "out of memory");
        } else if (s) {
            char key[32];
            if (bad < step->nargs)
                snprintf(key, sizeof key, "%s", step->args[bad].key);
            else
                snprintf(key, sizeof key, "%.*s", (int)strcspn(e.message, ":, "), e.message);
            fail(st, scene_key_line(st->s, p, key), "[%s %s]: %s", scene_kind_name(p->kind), p->name,
                 e.message);
        }
    }
    bkf_scene_plan_free(&plan);
    return !st->status;
}

int bkf_scene_parse_string(const char *text, const char *name, bkf_scene **out, bkf_error *err)
{
    *out = NULL;
    if (!text) return bkf_error_set(err, BKF_EINPUT, "scene: no text");
    bkf_scene *s = calloc(1, sizeof *s);
    if (!s || !(s->path = strdup(name ? name : "scene"))) {
        free(s);
        return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    }
    /* A UTF-8 byte order mark, which some editors put first, is not text. */
    if (strncmp(text, "\xEF\xBB\xBF", 3) == 0) text += 3;
    parse_state st = {.s = s, .name = s->path, .text = text, .err = err, .section_kind = -3};
    /* Strict: no Python-style continuation lines, comments with ; or #. */
    ini_allow_multiline = 0;
    ini_allow_inline_comments = 1;
    ini_inline_comment_prefixes = (char *)";#";
    int r = ini_parse_stream(reader, &st, handler, &st);
    if (!st.status && r > 0) fail(&st, r, "not a section header, key = value or comment");
    if (!st.status && r < 0) st.status = bkf_error_set(err, BKF_ENOMEM, "scene: out of memory");
    if (!st.status && check_scene(&st)) validate_plan(&st);
    if (st.status) {
        bkf_scene_free(s);
        return st.status;
    }
    *out = s;
    return BKF_OK;
}

/* The documented limit, exactly: a larger file is refused, not read. */
#define SCENE_MAX_BYTES ((size_t)16 << 20)

int bkf_scene_parse_file(const char *path, bkf_scene **out, bkf_error *err)
{
    *out = NULL;
    FILE *f = fopen(path, "rb");
    if (!f) return bkf_error_set(err, BKF_EINPUT, "scene %s: cannot open it", path);
    size_t cap = 4096, n = 0;
    char *buf = malloc(cap);
    int status = buf ? BKF_OK : bkf_error_set(err, BKF_ENOMEM, "out of memory");
    while (!status) {
        if (n + 1 >= cap) {
            /* one byte beyond the limit tells a file of exactly 16 MiB
             * from a larger one */
            size_t grow = cap * 2 > SCENE_MAX_BYTES + 2 ? SCENE_MAX_BYTES + 2 : cap * 2;
            char *g = grow > cap ? realloc(buf, grow) : NULL;
            if (!g) {
                status = bkf_error_set(err, BKF_ENOMEM, "out of memory");
                break;
            }
            buf = g;
            cap = grow;
        }
        size_t k = fread(buf + n, 1, cap - 1 - n, f);
        n += k;
        if (n > SCENE_MAX_BYTES) {
            status = bkf_error_set(err, BKF_EINPUT, "scene %s: larger than 16 MiB (16777216 bytes)",
                                   path);
            break;
        }
        if (k == 0) break;
    }
    if (!status && ferror(f)) status = bkf_error_set(err, BKF_EINPUT, "scene %s: read error", path);
    fclose(f);
    if (!status && memchr(buf, '\0', n))
        status = bkf_error_set(err, BKF_EINPUT, "scene %s: holds a NUL byte (not a text file)", path);
    if (!status) {
        buf[n] = '\0';
        status = bkf_scene_parse_string(buf, path, out, err);
    }
    free(buf);
    return status;
}

void bkf_scene_free(bkf_scene *s)
{
    if (!s) return;
    if (s->names_) {
        scene_lookup_free(s->names_);
        free(s->names_);
    }
    for (size_t i = 0; i < s->nproducts; i++) free(s->products[i].entries);
    free(s->products);
    free(s->model);
    free(s->path);
    free(s);
}

/* Scene files (scene.h): parsing with libinih, checking, the plan, and
 * its steps carried out through the catalogue. */
#define _POSIX_C_SOURCE 200809L
#include "bkfront/scene.h"

#include <ctype.h>
#include <ini.h>
#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bkfront/cycle.h"
#include "bkfront/io.h"
#include "bkfront/model.h"
#include "bkfront/options.h"
#include "bkfront/pde.h"
#include "bkfront/plot.h"

/* At most this many values in a list key: a list such as nu = A:B:N is one
 * computation per value, planned and run one by one, so the cap is that of
 * a range of computations, not the 1e6 of values inside one product. */
#define SCENE_MAX_POINTS 100000u

/* The kinds of the first releases keep their numbers (scene.h); a kind a
 * product declares later (catalog.h) gets the next.  Every kind but figure
 * is a catalogue product's: its declaration is the whole recipe. */
static const char *const enum_names[BKF_SCENE_NKINDS] = {
    "speeds", "period", "dispersion", "threshold", "branch", "profile",
    "validity", "friction", "spacetime", "check", "stability", "figure", "sweep"};

typedef struct {
    const char *name;
    const bkf_catalog_entry *entry;  /* NULL: figure */
    const bkf_catalog_kind *decl;
} kind_info;

/* The kinds' bits (K below) end under K_ACCURACY. */
#define MAX_KINDS 29
static kind_info kinds[MAX_KINDS];
static size_t nkinds;
static pthread_once_t kinds_once = PTHREAD_ONCE_INIT;

/* A kind past MAX_KINDS is left out; the test that every catalogue kind
 * is a scene's finds it. */
static void build_kinds(void)
{
    for (size_t k = 0; k < BKF_SCENE_NKINDS; k++) kinds[k].name = enum_names[k];
    nkinds = BKF_SCENE_NKINDS;
    for (size_t i = 0; i < bkf_catalog_count(); i++) {
        const bkf_catalog_entry *e = bkf_catalog_at(i);
        for (size_t j = 0; j < e->nkinds; j++) {
            size_t k = 0;
            while (k < nkinds && strcmp(kinds[k].name, e->kinds[j].name) != 0) k++;
            if (k == nkinds && nkinds == MAX_KINDS) continue;
            if (k == nkinds) nkinds++;
            kinds[k] = (kind_info){e->kinds[j].name, e, &e->kinds[j]};
        }
    }
}

static const kind_info *kind_at(int kind)
{
    pthread_once(&kinds_once, build_kinds);
    return kind >= 0 && (size_t)kind < nkinds ? &kinds[kind] : NULL;
}

size_t bkf_scene_kind_count(void)
{
    pthread_once(&kinds_once, build_kinds);
    return nkinds;
}

const char *bkf_scene_kind_name(bkf_scene_kind kind)
{
    const kind_info *k = kind_at((int)kind);
    return k ? k->name : NULL;
}

static const char *kind_name(bkf_scene_kind kind)
{
    const char *n = bkf_scene_kind_name(kind);
    return n ? n : "?";
}

static int append(char *buf, size_t size, const char *sep, const char *text);

/* ------------------------------------------------------------- lookup */

/* Open addressing over item indices, so that finding a product by name
 * while parsing and a computation already planned cost O(1) each: a scene
 * of 50,000 products used to take 46 s to plan (every step compared with
 * every earlier one).  Slots hold index + 1 (0: empty) with its hash. */
typedef struct {
    size_t *item, *hash;
    size_t cap, count;
} lookup;

static size_t hash_text(size_t h, const char *s)
{
    for (; *s; s++) h = (h ^ (unsigned char)*s) * (size_t)1099511628211u;
    return (h ^ 0xff) * (size_t)1099511628211u; /* a separator after each text */
}

#define HASH_SEED ((size_t)14695981039346656037u)

static void lookup_free(lookup *l)
{
    free(l->item);
    free(l->hash);
    *l = (lookup){0};
}

/* The first index i with this hash and same(i, data), or SIZE_MAX. */
static size_t lookup_find(const lookup *l, size_t h, int (*same)(size_t, const void *),
                          const void *data)
{
    if (!l->cap) return SIZE_MAX;
    for (size_t k = h & (l->cap - 1); l->item[k]; k = (k + 1) & (l->cap - 1))
        if (l->hash[k] == h && same(l->item[k] - 1, data)) return l->item[k] - 1;
    return SIZE_MAX;
}

/* Arrays that grow one element at a time keep a capacity of the next power
 * of two, known from the count alone: they move only when the count reaches
 * one, so n pushes cost O(n) whatever realloc does (a realloc that always
 * moves, as AddressSanitizer's, made a scene of 50,000 products quadratic). */
static void *grow_for_push(void *array, size_t count, size_t size)
{
    if (count & (count - 1)) return array; /* not a power of two: room left */
    size_t cap = count ? 2 * count : 1;
    if (cap > SIZE_MAX / size) return NULL;
    return realloc(array, cap * size);
}

/* 0 when out of memory. */
static int lookup_add(lookup *l, size_t h, size_t index)
{
    if (2 * (l->count + 1) > l->cap) {
        lookup g = {.cap = l->cap ? 2 * l->cap : 64};
        g.item = calloc(g.cap, sizeof *g.item);
        g.hash = calloc(g.cap, sizeof *g.hash);
        if (!g.item || !g.hash) {
            lookup_free(&g);
            return 0;
        }
        for (size_t k = 0; k < l->cap; k++)
            if (l->item[k]) {
                size_t j = l->hash[k] & (g.cap - 1);
                while (g.item[j]) j = (j + 1) & (g.cap - 1);
                g.item[j] = l->item[k];
                g.hash[j] = l->hash[k];
            }
        g.count = l->count;
        lookup_free(l);
        *l = g;
    }
    size_t j = h & (l->cap - 1);
    while (l->item[j]) j = (j + 1) & (l->cap - 1);
    l->item[j] = index + 1;
    l->hash[j] = h;
    l->count++;
    return 1;
}

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
    case V_FORMATS: {
        char buf[BKF_SCENE_VALUE_LEN];
        snprintf(buf, sizeof buf, "%s", v);
        char *save = NULL;
        int any = 0;
        for (char *t = strtok_r(buf, ", ", &save); t; t = strtok_r(NULL, ", ", &save)) {
            static const char *const f[] = {"png", "pdf", "svg", NULL};
            int i;
            if ((s = bkf_option_parse_choice(t, f, "", k, &i, err))) return s;
            any = 1;
        }
        if (!any) return bkf_error_set(err, BKF_EINPUT, "formats: give png, pdf or svg");
        return BKF_OK;
    }
    case V_TEXT:
        if (!*v) return bkf_error_set(err, BKF_EINPUT, "%s: the value is empty", k);
        for (const unsigned char *p = (const unsigned char *)v; *p; p++)
            if (*p < 0x20 || *p == 0x7f)
                return bkf_error_set(err, BKF_EINPUT, "%s: the value holds a control character", k);
        return BKF_OK;
    }
    return BKF_OK;
}

/* -------------------------------------------------------- the catalogue */

/* The option of a step's product whose list a scene makes one step per
 * value (BKF_OPT_FANOUT), or NULL. */
static const bkf_option *fanout_option(const bkf_catalog_entry *entry)
{
    size_t n;
    const bkf_option *table = entry->options(&n);
    for (size_t i = 0; i < n; i++)
        if (table[i].flags & BKF_OPT_FANOUT) return &table[i];
    return NULL;
}

/* A scene key as the option's name: max_points is --max-points. */
static const char *option_name(const char *key, char *buf, size_t size)
{
    snprintf(buf, size, "%s", key);
    for (char *c = buf; *c; c++)
        if (*c == '_') *c = '-';
    return buf;
}

static const bkf_option *catalog_option(const bkf_catalog_entry *entry, const char *name)
{
    size_t n;
    const bkf_option *table = entry->options(&n);
    const bkf_option *opt = bkf_option_find(table, n, name);
    return opt && !(opt->flags & BKF_OPT_CLI_ONLY) ? opt : NULL;
}

/* The step's keys into `spec`: switches first (a geometric list reads the
 * log switch), a fixed switch the product does not know not at all
 * (--no-progress is the command line's); *bad: the arg at fault.  Outputs
 * other than the table's own ("out", which the scene writes) and the files
 * a scene names (BKF_OPT_PATH) are the product's data files: applied only
 * for a run (`outputs`), not when a plan is checked at parse time, which
 * must not touch the file system. */
static int apply_args(const bkf_catalog_entry *entry, const bkf_scene_arg *args, size_t n,
                      void *spec, int outputs, size_t *bad, bkf_error *err)
{
    for (int pass = 0; pass < 2; pass++)
        for (size_t i = 0; i < n; i++) {
            const bkf_scene_arg *a = &args[i];
            if (a->output && (!outputs || strcmp(a->key, "out") == 0)) continue;
            const bkf_option *opt = catalog_option(entry, a->key);
            if (!outputs && opt && (opt->flags & BKF_OPT_PATH)) continue;
            if ((a->value == NULL) != (pass == 0)) continue;
            if (a->fixed && !catalog_option(entry, a->key)) continue;
            int s = bkf_catalog_apply(entry, spec, a->key, a->value, "", err);
            if (s) {
                if (bad) *bad = i;
                return s;
            }
        }
    return BKF_OK;
}

/* One item of a kind's keys (catalog.h's bkf_catalog_step): KEY and its
 * marks. */
typedef struct {
    char key[64];
    int inherit, required, names, always, has_value; /* ^ (+), +, @, :=, = */
    char value[BKF_SCENE_VALUE_LEN];       /* =TEXT, =$OTHER, :=TEXT */
    char omit[64];                         /* !TEXT */
    char if_key[64], if_value[64];         /* ?OTHER=TEXT */
} key_item;

static void parse_item(const char *tok, size_t len, key_item *it)
{
    *it = (key_item){0};
    const char *end = tok + len;
    if (*tok == '^' || *tok == '+') it->inherit = 1, it->required = *tok == '+', tok++;
    else if (*tok == '@') it->names = 1, tok++;
    size_t n = strcspn(tok, "=!?: ");
    snprintf(it->key, sizeof it->key, "%.*s", (int)n, tok);
    tok += n;
    while (tok < end) {
        char mark = *tok++;
        if (mark == ':' && tok < end && *tok == '=') it->always = 1, mark = '=', tok++;
        size_t k = strcspn(tok, "!? ");
        if (mark == '=') {
            it->has_value = 1;
            snprintf(it->value, sizeof it->value, "%.*s", (int)k, tok);
        } else if (mark == '!') {
            snprintf(it->omit, sizeof it->omit, "%.*s", (int)k, tok);
        } else if (mark == '?') {
            size_t e = strcspn(tok, "=!? ");
            snprintf(it->if_key, sizeof it->if_key, "%.*s", (int)e, tok);
            if (e < k) snprintf(it->if_value, sizeof it->if_value, "%.*s", (int)(k - e - 1), tok + e + 1);
        }
        tok += k;
    }
}

/* The items of a declaration's keys (malloc'd; NULL with *n 0: none or out
 * of memory, told apart by `text`). */
static key_item *parse_items(const char *text, size_t *n)
{
    *n = 0;
    size_t cap = 1;
    for (const char *c = text ? text : ""; *c; c++) cap += *c == ' ';
    key_item *items = text && *text ? calloc(cap, sizeof *items) : NULL;
    for (const char *c = text; items && *c;) {
        size_t len = strcspn(c, " ");
        if (len) parse_item(c, len, &items[(*n)++]);
        c += len + (c[len] == ' ');
    }
    return items;
}

static const char *entry_value(const bkf_scene_entry *list, size_t n, const char *key)
{
    for (size_t i = 0; i < n; i++)
        if (strcmp(list[i].key, key) == 0) return list[i].value;
    return NULL;
}

/* The section's own value of an option name (written with _ or -). */
static const char *own_value(const bkf_scene_product *p, const char *key)
{
    char name[64];
    for (size_t i = 0; i < p->nentries; i++)
        if (strcmp(option_name(p->entries[i].key, name, sizeof name), key) == 0)
            return p->entries[i].value;
    return NULL;
}

/* The section's own value, else, with `inherit`, [model]'s or [accuracy]'s. */
static const char *scene_key(const bkf_scene *s, const bkf_scene_product *p, const char *key,
                             int inherit)
{
    const char *v = own_value(p, key);
    return v || !inherit ? v : entry_value(s->model, s->nmodel, key);
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
    const kind_info *k = kind_at((int)kind);
    if (!k || !k->entry) return 0;
    char name[64];
    option_name(key, name, sizeof name);
    const bkf_option *opt = catalog_option(k->entry, name);
    if (opt) {
        *out = (kind_key){k->entry, opt, opt == fanout_option(k->entry)};
        return 1;
    }
    const bkf_catalog_step *also = &k->decl->also;
    const bkf_catalog_entry *a = also->product ? bkf_catalog_find(also->product) : NULL;
    if (!a) return 0;
    const char *gt = also->fanout ? strchr(also->fanout, '>') : NULL;
    if (gt && strlen(key) == (size_t)(gt - also->fanout) &&
        strncmp(key, also->fanout, (size_t)(gt - also->fanout)) == 0) {
        *out = (kind_key){a, catalog_option(a, gt + 1), 1};
        return out->opt != NULL;
    }
    size_t n;
    key_item *items = parse_items(also->keys, &n);
    int found = 0;
    for (size_t i = 0; !found && i < n; i++)
        if (!items[i].always && strcmp(items[i].key, name) == 0 && catalog_option(a, name)) {
            *out = (kind_key){a, catalog_option(a, name), 0};
            found = 1;
        }
    free(items);
    return found;
}

/* The scene keys of a kind, for messages ("gamma, c, nu, ..."). */
static void kind_keys_known(bkf_scene_kind kind, char *known, size_t size)
{
    const kind_info *k = kind_at((int)kind);
    size_t n;
    const bkf_option *table = k && k->entry ? k->entry->options(&n) : NULL;
    for (size_t i = 0; table && i < n; i++)
        if (!(table[i].flags & BKF_OPT_CLI_ONLY)) append(known, size, ", ", table[i].name);
    const bkf_catalog_step *also = k && k->decl ? &k->decl->also : NULL;
    if (!also || !also->product) return;
    if (also->fanout) {
        char list[64];
        snprintf(list, sizeof list, "%.*s", (int)strcspn(also->fanout, ">"), also->fanout);
        append(known, size, ", ", list);
    }
    size_t ni;
    key_item *items = parse_items(also->keys, &ni);
    kind_key kk;
    for (size_t i = 0; i < ni; i++)
        if (!items[i].always && !catalog_option(k->entry, items[i].key) &&
            kind_key_find(kind, items[i].key, &kk))
            append(known, size, ", ", items[i].key);
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
    option_name(key, name, sizeof name);
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

typedef struct {
    const bkf_scene *s;
    const char *name;
    int figure;
} same_name_query;

static int same_name(size_t i, const void *data)
{
    const same_name_query *q = data;
    const bkf_scene_product *p = &q->s->products[i];
    return (p->kind == BKF_SCENE_FIGURE) == q->figure && strcmp(p->name, q->name) == 0;
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
        if (strcmp(kind, kind_name((bkf_scene_kind)i)) == 0) k = (int)i;
    if (k < 0) {
        char known[512] = "model, accuracy";
        for (size_t i = 0; i < nk; i++) append(known, sizeof known, ", ", kind_name((bkf_scene_kind)i));
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
    size_t h = hash_text(HASH_SEED + (size_t)is_figure, name);
    same_name_query q = {s, name, is_figure};
    lookup *names = s->names_;
    if (!names && (s->names_ = names = calloc(1, sizeof *names)) == NULL) {
        st->status = bkf_error_set(st->err, BKF_ENOMEM, "out of memory");
        return;
    }
    size_t used = lookup_find(names, h, same_name, &q);
    if (used != SIZE_MAX) {
        fail(st, st->line, "[%s]: the name '%s' is already used on line %d", a, name,
             s->products[used].line);
        return;
    }
    bkf_scene_product *grown = grow_for_push(s->products, s->nproducts, sizeof *grown);
    if (!grown || !lookup_add(names, h, s->nproducts)) {
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
    bkf_scene_entry *grown = grow_for_push(*list, *n, sizeof *grown);
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
        append(known, sizeof known, ", ", keys[i].key);
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

static int takes_inherited(const bkf_scene_product *p, const char *key);

const char *bkf_scene_value(const bkf_scene *s, const bkf_scene_product *p, const char *key)
{
    const char *v = p ? entry_value(p->entries, p->nentries, key) : NULL;
    if (v) return v;
    int accuracy = 0;
    for (size_t i = 0; i < NKEYS; i++)
        accuracy |= (keys[i].where & K_ACCURACY) && strcmp(keys[i].key, key) == 0;
    if (p && accuracy && !takes_inherited(p, key)) return NULL;
    return entry_value(s->model, s->nmodel, key);
}

const bkf_scene_product *bkf_scene_find(const bkf_scene *s, const char *name, int figures)
{
    if (s->names_) {
        same_name_query q = {s, name, figures != 0};
        size_t i = lookup_find(s->names_, hash_text(HASH_SEED + (size_t)(figures != 0), name),
                               same_name, &q);
        return i == SIZE_MAX ? NULL : &s->products[i];
    }
    for (size_t i = 0; i < s->nproducts; i++)
        if ((s->products[i].kind == BKF_SCENE_FIGURE) == (figures != 0) &&
            strcmp(s->products[i].name, name) == 0)
            return &s->products[i];
    return NULL;
}

static int entry_line(const bkf_scene_product *p, const char *key)
{
    for (size_t i = 0; i < p->nentries; i++)
        if (strcmp(p->entries[i].key, key) == 0) return p->entries[i].line;
    return p->line;
}

/* The line that gives `key` (an option name) to product p: its own entry,
 * else [model]/[accuracy], else the section's header. */
static int key_line(const bkf_scene *s, const bkf_scene_product *p, const char *key)
{
    char name[64];
    for (size_t i = 0; i < p->nentries; i++)
        if (strcmp(option_name(p->entries[i].key, name, sizeof name), key) == 0)
            return p->entries[i].line;
    for (size_t i = 0; i < s->nmodel; i++)
        if (strcmp(s->model[i].key, key) == 0) return s->model[i].line;
    return p->line;
}

static int validate_plan(parse_state *st);

/* The products a figure's data = A,B,... names (spaces around the names
 * ignored), as indices into *out (malloc'd; NULL when none); *bad: the
 * first name that is no product of the scene, or NULL.  0: out of memory. */
static int figure_data(const bkf_scene *s, const char *data, size_t **out, size_t *count,
                       char *bad, size_t badsize)
{
    *out = NULL;
    *count = 0;
    if (bad && badsize) bad[0] = '\0';
    char buf[BKF_SCENE_VALUE_LEN];
    snprintf(buf, sizeof buf, "%s", data);
    char *save = NULL;
    for (char *t = strtok_r(buf, ",", &save); t; t = strtok_r(NULL, ",", &save)) {
        while (*t == ' ' || *t == '\t') t++;
        size_t len = strlen(t);
        while (len && (t[len - 1] == ' ' || t[len - 1] == '\t')) t[--len] = '\0';
        const bkf_scene_product *d = bkf_scene_find(s, t, 0);
        if (!d) {
            if (bad && badsize) snprintf(bad, badsize, "%s", t);
            return 1;
        }
        size_t *g = grow_for_push(*out, *count, sizeof *g);
        if (!g) return 0;
        *out = g;
        g[(*count)++] = (size_t)(d - s->products);
    }
    if (*count == 0 && bad && badsize) snprintf(bad, badsize, "%s", data);
    return 1;
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
            const char *data = entry_value(p->entries, p->nentries, "data");
            if (!data) return fail(st, p->line, "[figure %s]: give data = NAME of the product shown", p->name);
            size_t *idx, count;
            char bad[BKF_SCENE_VALUE_LEN];
            if (!figure_data(s, data, &idx, &count, bad, sizeof bad)) {
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
        const kind_info *k = kind_at((int)p->kind);
        size_t n = 0;
        key_item *items = k && k->decl ? parse_items(k->decl->step.keys, &n) : NULL;
        const char *missing = NULL;
        for (size_t j = 0; !missing && j < n; j++) {
            int varied = 0;
            for (size_t v = 0; v < n; v++) {
                const char *named = items[v].names ? own_value(p, items[v].key) : NULL;
                varied |= named && strcmp(named, items[j].key) == 0;
            }
            if (items[j].required && !varied && !scene_key(s, p, items[j].key, 1))
                missing = items[j].key;
        }
        if (missing)
            fail(st, p->line, "[%s %s]: %s is not set here nor in [model]", kind_name(p->kind),
                 p->name, missing);
        free(items);
        if (missing) return 0;
        if (p->kind == BKF_SCENE_BRANCH) {
            if (!entry_value(p->entries, p->nentries, "param"))
                return fail(st, p->line, "[branch %s]: give param = S, nu, gamma or c", p->name);
            if (!entry_value(p->entries, p->nentries, "to"))
                return fail(st, p->line, "[branch %s]: give to = the end value of the parameter",
                            p->name);
        }
        if (p->kind == BKF_SCENE_THRESHOLD) {
            int along = entry_value(p->entries, p->nentries, "along") != NULL;
            int from = entry_value(p->entries, p->nentries, "from") != NULL;
            int to = entry_value(p->entries, p->nentries, "to") != NULL;
            if (along != from || along != to)
                return fail(st, p->line, "[threshold %s]: along, from and to go together", p->name);
        }
        if (p->kind == BKF_SCENE_SPEEDS && entry_value(p->entries, p->nentries, "n") &&
            entry_value(p->entries, p->nentries, "nmax"))
            return fail(st, entry_line(p, "nmax"), "[speeds %s]: give n or nmax, not both", p->name);
    }
    return 1;
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
        lookup_free(s->names_);
        free(s->names_);
    }
    for (size_t i = 0; i < s->nproducts; i++) free(s->products[i].entries);
    free(s->products);
    free(s->model);
    free(s->path);
    free(s);
}

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

/* A list value ("a,b,c" or "A:B:N") as separate texts; 0 when out of
 * memory (the value was checked when parsed). */
static int list_values(const char *text, char ***items, size_t *count)
{
    *items = NULL;
    *count = 0;
    if (strchr(text, ':')) {
        bkf_list r;
        bkf_error e;
        if (bkf_list_parse(text, 0, 0, SCENE_MAX_POINTS, "", "list", &r, &e)) return 0;
        *items = calloc(r.count ? r.count : 1, sizeof **items);
        for (size_t i = 0; *items && i < r.count; i++) {
            char buf[64];
            snprintf(buf, sizeof buf, "%.15g", r.values[i]);
            (*items)[i] = strdup(buf);
            if (!(*items)[i]) break;
            (*count)++;
        }
        size_t want = r.count;
        bkf_list_free(&r);
        return *items && *count == want;
    }
    char buf[BKF_SCENE_VALUE_LEN];
    snprintf(buf, sizeof buf, "%s", text);
    char *save = NULL;
    for (char *t = strtok_r(buf, ",", &save); t; t = strtok_r(NULL, ",", &save)) {
        char **g = grow_for_push(*items, *count, sizeof *g);
        if (!g) return 0;
        *items = g;
        if (!(g[*count] = strdup(t))) return 0;
        (*count)++;
    }
    return 1;
}

static void list_values_free(char **items, size_t count)
{
    for (size_t i = 0; i < count; i++) free(items[i]);
    free(items);
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
    lookup computations;   /* product steps by computation_hash */
    size_t steps_cap;
} planner;

/* Over what same_computation compares: the product and the settings that
 * are not outputs. */
static size_t computation_hash(const arg_list *b, const char *product)
{
    size_t h = hash_text(HASH_SEED, product);
    for (size_t j = 0; j < b->n; j++) {
        if (b->v[j].output) continue;
        h = hash_text(h, b->v[j].key);
        h = b->v[j].value ? hash_text(h, b->v[j].value) : h * 31u + 1u;
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
    size_t *g = grow_for_push(st->users, st->nusers, sizeof *g);
    if (!g) return 0;
    st->users = g;
    g[st->nusers++] = product;
    return 1;
}

static int product_add_step(bkf_scene_plan *plan, size_t product, size_t step)
{
    bkf_scene_product_plan *pp = &plan->products[product];
    size_t *g = grow_for_push(pp->steps, pp->nsteps, sizeof *g);
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
        size_t i = lookup_find(&pl->computations, h, same_step, &q);
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
    if (kind == BKF_SCENE_STEP_PRODUCT && !lookup_add(&pl->computations, h, plan->nsteps))
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
static const char *item_value(const bkf_scene *s, const bkf_scene_product *p, const key_item *it)
{
    if (it->always) return it->value;
    const char *v = scene_key(s, p, it->key, it->inherit);
    if (!v && it->has_value && it->value[0] == '$') {
        const char *named = own_value(p, it->value + 1);
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

/* Whether the kind of p takes [accuracy]'s `key`: where its product has
 * such a key, only when the kind's keys say ^KEY (a simulation's tol is its
 * stepper's, not the accuracy asked of a result). */
static int takes_inherited(const bkf_scene_product *p, const char *key)
{
    const kind_info *k = kind_at((int)p->kind);
    if (!k || !k->entry || !catalog_option(k->entry, key)) return 1;
    size_t n;
    key_item *items = parse_items(k->decl->step.keys, &n);
    int takes = 0;
    for (size_t i = 0; i < n; i++)
        if (strcmp(items[i].key, key) == 0) takes = items[i].inherit;
    free(items);
    return takes;
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
                                 c->s->path, key_line(c->s, p, key), kind_name(p->kind), p->name,
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
                         const bkf_catalog_step *d, const key_item *items, size_t nitems,
                         const char *fkey, const char *item, size_t number, size_t count,
                         int own)
{
    const bkf_scene_product *p = &c->s->products[c->index];
    arg_list b = {0};
    int st = fixed_keys(&b, d->first) ? BKF_OK : BKF_ENOMEM;
    for (size_t i = 0; !st && i < nitems; i++) {
        const key_item *it = &items[i];
        int skipped = 0;
        for (size_t j = 0; j < nitems; j++) {
            const char *named = items[j].names ? own_value(p, items[j].key) : NULL;
            if (!it->names && named && strcmp(named, it->key) == 0) skipped = 1;
        }
        const char *v = fkey && item && strcmp(it->key, fkey) == 0 ? item : item_value(c->s, p, it);
        if (!skipped && v && !arg_has(&b, it->key)) st = push_key(c, &b, entry, it->key, v);
    }
    /* the section's other keys of the product's table, as written */
    for (size_t i = 0; own && !st && i < p->nentries; i++) {
        char key[sizeof p->entries[i].key];
        option_name(p->entries[i].key, key, sizeof key);
        if (!catalog_option(entry, key) || arg_has(&b, key)) continue;
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
    key_item *items = parse_items(d->keys, &nitems);
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
        list = own_value(p, from);
    } else if (fanout_option(entry)) {
        snprintf(fkey, sizeof fkey, "%s", fanout_option(entry)->name);
        list = own_value(p, fkey);
        for (size_t i = 0; i < nitems; i++)
            if (strcmp(items[i].key, fkey) == 0) list = item_value(c->s, p, &items[i]);
    }
    char **values = NULL;
    size_t count = 0;
    int st = BKF_OK;
    if (list && !list_values(list, &values, &count))
        st = bkf_error_set(c->err, BKF_ENOMEM, "out of memory");
    if (!st && !list && !d->fanout)
        st = plan_one_step(c, entry, d, items, nitems, NULL, NULL, 1, 1, own);
    for (size_t i = 0; !st && i < count; i++)
        st = plan_one_step(c, entry, d, items, nitems, fkey, values[i], i + 1, count, own);
    list_values_free(values, count);
    free(items);
    return st;
}

static int plan_figure(bkf_scene_plan *plan, const bkf_scene *s, size_t index,
                       const bkf_scene_plan_options *o)
{
    const bkf_scene_product *p = &s->products[index];
    if (!o->figures) return 1;
    size_t *shown, nshown;
    if (!figure_data(s, own_value(p, "data"), &shown, &nshown, NULL, 0)) return 0;
    if (nshown == 0) { /* checked when parsed */
        free(shown);
        return 0;
    }
    unsigned formats = 0;
    const char *v = own_value(p, "formats");
    if (v) {
        formats |= strstr(v, "png") ? 1u : 0u;
        formats |= strstr(v, "pdf") ? 2u : 0u;
        formats |= strstr(v, "svg") ? 4u : 0u;
    } else
        formats = o->formats ? o->formats : 1u;
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
    const kind_info *k = kind_at((int)p->kind);
    if (p->kind == BKF_SCENE_FIGURE)
        return plan_figure(plan, s, index, o) ? BKF_OK : bkf_error_set(err, BKF_ENOMEM, "out of memory");
    if (!k || !k->entry)
        return bkf_error_set(err, BKF_EINPUT, "[%s %s]: no product computes this kind",
                             kind_name(p->kind), p->name);
    plan_context c = {plan, s, index, o, err};
    int st = plan_steps(&c, k->entry, &k->decl->step, 1);
    const bkf_catalog_entry *also = k->decl->also.product ? bkf_catalog_find(k->decl->also.product)
                                                          : NULL;
    if (!st && also) st = plan_steps(&c, also, &k->decl->also, 0);
    return st;
}

int bkf_scene_make_plan(const bkf_scene *s, const bkf_scene_plan_options *o,
                        bkf_scene_plan *plan, bkf_error *err)
{
    *plan = (bkf_scene_plan){0};
    if (!o || !o->outdir || !*o->outdir)
        return bkf_error_set(err, BKF_EINPUT, "plan: no output folder");
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
    lookup_free(&pl.computations);
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
        int s = apply_args(step->entry, step->args, step->nargs, spec, 0, &bad, &e);
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
            fail(st, key_line(st->s, p, key), "[%s %s]: %s", kind_name(p->kind), p->name,
                 e.message);
        }
    }
    bkf_scene_plan_free(&plan);
    return !st->status;
}

/* ------------------------------------------------------------------- run */

static const char *arg_value(const bkf_scene_step *step, const char *key)
{
    for (size_t i = 0; i < step->nargs; i++)
        if (strcmp(step->args[i].key, key) == 0) return step->args[i].value;
    return NULL;
}

typedef int (*table_writer)(const bkf_scene_step *step, void *spec, FILE *out,
                            const bkf_provenance *prov, const bkf_scene_run_options *o,
                            bkf_error *err);

/* The step's table written atomically onto its output: whole or not at all. */
static int write_output(const bkf_scene_step *step, void *spec, table_writer write,
                        const bkf_scene_run_options *o, bkf_error *err)
{
    char *cmd = bkf_scene_step_command(step);
    size_t n = cmd ? strlen(cmd) + (o->command_prefix ? strlen(o->command_prefix) : 0) + 2 : 0;
    char *command = cmd ? malloc(n) : NULL;
    if (!command) {
        free(cmd);
        return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    }
    snprintf(command, n, "%s%s%s", o->command_prefix ? o->command_prefix : "",
             o->command_prefix ? " " : "", cmd);
    free(cmd);
    /* The table goes to the "out" output; a step without one (a figure's
     * data written by the product itself) to its first output. */
    const char *path = step->output;
    for (size_t i = 0; i < step->nargs; i++)
        if (step->args[i].output && strcmp(step->args[i].key, "out") == 0)
            path = step->args[i].value;
    bkf_error e;
    bkf_io_atomic *file = bkf_io_atomic_open(path, &e);
    if (!file) {
        free(command);
        return bkf_error_set(err, BKF_EINPUT, "out: %s", e.message);
    }
    char temp[4096];
    snprintf(temp, sizeof temp, "%s", bkf_io_atomic_temp_path(file));
    if (o->temp_file) o->temp_file(temp, 1, o->data);
    bkf_provenance prov = {o->program, command};
    int s = write(step, spec, bkf_io_atomic_stream(file), &prov, o, err);
    if (!s)
        s = bkf_io_atomic_commit(file, err);
    else
        bkf_io_atomic_abort(file);
    if (o->temp_file) o->temp_file(temp, 0, o->data);
    free(command);
    return s;
}

static int write_catalogued(const bkf_scene_step *step, void *spec, FILE *out,
                            const bkf_provenance *prov, const bkf_scene_run_options *o,
                            bkf_error *err)
{
    return step->entry->write(spec, out, BKF_IO_TSV, prov, &o->hooks, err);
}

static int append(char *buf, size_t size, const char *sep, const char *text)
{
    size_t used = strlen(buf);
    int n = snprintf(buf + used, size - used, "%s%s", used ? sep : "", text);
    return n >= 0 && (size_t)n < size - used;
}

/* The default script's name: the kind's, but a stability product's shows
 * what its mode computed. */
static int is_chain(const bkf_scene *sc, const bkf_scene_product *p)
{
    const char *m = bkf_scene_value(sc, p, "model");
    return m && strcmp(m, "chain") == 0;
}

static const char *default_script(const bkf_scene *sc, const bkf_scene_step *fig,
                                  const bkf_scene_product *data)
{
    if (data->kind == BKF_SCENE_SWEEP) return "sweep_map";
    /* speeds of chains (beside the continuum's): their own figure */
    if (data->kind == BKF_SCENE_SPEEDS)
        for (size_t d = 0; d < fig->ndata; d++)
            if (is_chain(sc, &sc->products[fig->data_products[d]])) return "chain_speeds";
    if (data->kind != BKF_SCENE_STABILITY) return kind_name(data->kind);
    const char *d = bkf_scene_value(sc, data, "diagram"), *l = bkf_scene_value(sc, data, "line");
    if (d && strcmp(d, "yes") == 0) return "diagram";
    if (l && strcmp(l, "yes") == 0) return "spectrum_line";
    return "spectrum";
}

static int run_figure(const bkf_scene *sc, const bkf_scene_plan *plan,
                      const bkf_scene_step *step, const bkf_scene_run_options *o,
                      char *warning, size_t wsize, bkf_error *err)
{
    const bkf_scene_product *fig = &sc->products[step->users[0]];
    const bkf_scene_product *data = &sc->products[step->data_product];
    const char *scene_dir = o->scene_dir ? o->scene_dir : ".";
    const char *plots_dir = o->plots_dir ? o->plots_dir : "plots";
    char script[4096];
    const char *own = bkf_scene_value(sc, fig, "script");
    if (own && own[0] == '/')
        snprintf(script, sizeof script, "%s", own);
    else if (own)
        snprintf(script, sizeof script, "%.2000s/%.2000s", scene_dir, own);
    else
        snprintf(script, sizeof script, "%.2000s/%.64s.gp", plots_dir,
                 default_script(sc, step, data));

    char files[8192] = "", labels[4096] = "";
    for (size_t d = 0; d < step->ndata; d++) {
        const bkf_scene_product *shown = &sc->products[step->data_products[d]];
        const bkf_scene_product_plan *dp = &plan->products[step->data_products[d]];
        for (size_t i = 0; i < dp->nsteps; i++) {
            const bkf_scene_step *ds = &plan->steps[dp->steps[i]];
            if (!append(files, sizeof files, " ", ds->output))
                return bkf_error_set(err, BKF_EINPUT, "figure %s: too many data files",
                                     fig->name);
            /* each file's value of the list that made it (nu of period
             * and dispersion, n of branch and stability) */
            const bkf_option *fanout = ds->entry ? fanout_option(ds->entry) : NULL;
            const char *value = fanout ? arg_value(ds, fanout->name) : "";
            if (shown->kind == BKF_SCENE_SWEEP)
                /* the map, then the Floquet diagram of each gamma */
                value = strcmp(ds->product, "sweep") == 0 ? "map" : arg_value(ds, "gamma");
            else if (shown->kind == BKF_SCENE_SPEEDS && step->ndata > 1) {
                /* which table is which: the chain's blocks, or the continuum */
                const char *m = arg_value(ds, "model");
                value = "continuum";
                if (m && strcmp(m, "chain") == 0)
                    value = arg_value(ds, "N") ? arg_value(ds, "N") : arg_value(ds, "S");
            }
            if (shown->kind == BKF_SCENE_PROFILE) {
                char **items;
                size_t count;
                if (!list_values(arg_value(ds, "n"), &items, &count))
                    return bkf_error_set(err, BKF_ENOMEM, "out of memory");
                for (size_t k = 0; k < count; k++) append(labels, sizeof labels, " ", items[k]);
                list_values_free(items, count);
            } else if (value && *value)
                append(labels, sizeof labels, " ", value);
        }
    }
    bkf_plot_job *job = bkf_plot_job_alloc(script, err);
    if (!job) return BKF_EINPUT;
    int s = bkf_plot_set_string(job, "files", files, err);
    /* per file: its nu (period, dispersion) or n (branch) */
    if (!s) s = bkf_plot_set_string(job, "values", labels, err);
    if (!s) s = bkf_plot_set_string(job, "plotdir", plots_dir, err);
    if (!s) s = bkf_plot_set_string(job, "kind", kind_name(data->kind), err);
    const char *title = bkf_scene_value(sc, fig, "title");
    if (!s) s = bkf_plot_set_string(job, "title", title ? title : "", err);
    static const char *const numbers[] = {"gamma", "c", "nu", "S", "tmax"};
    for (size_t i = 0; !s && i < sizeof numbers / sizeof numbers[0]; i++) {
        const char *v = bkf_scene_value(sc, data, numbers[i]);
        double x = NAN;
        if (v && !strchr(v, ',') && !strchr(v, ':'))
            bkf_option_parse_double(v, "", numbers[i], &x, NULL);
        s = bkf_plot_set_number(job, numbers[i], x, err);
    }
    const char *param =
        bkf_scene_value(sc, data, data->kind == BKF_SCENE_BRANCH ? "param" : "along");
    if (!s) s = bkf_plot_set_string(job, "param", param ? param : "", err);
    size_t w = 900, h = 600;
    const char *wt = bkf_scene_value(sc, fig, "width"), *ht = bkf_scene_value(sc, fig, "height");
    if (wt) bkf_option_parse_count(wt, 1, BKF_PLOT_PIXELS_MAX, "", "width", &w, NULL);
    if (ht) bkf_option_parse_count(ht, 1, BKF_PLOT_PIXELS_MAX, "", "height", &h, NULL);
    if (!s) s = bkf_plot_set_number(job, "width", (double)w, err);
    if (!s) s = bkf_plot_set_number(job, "height", (double)h, err);
    for (size_t i = 0; !s && i < step->nargs; i++) {
        const char *path = step->args[i].value;
        const char *dot = strrchr(path, '.');
        bkf_plot_format f = strcmp(dot, ".png") == 0   ? BKF_PLOT_PNG
                            : strcmp(dot, ".pdf") == 0 ? BKF_PLOT_PDF
                                                       : BKF_PLOT_SVG;
        s = bkf_plot_add_output(job, f, path, err);
    }
    bkf_plot_report report;
    bkf_plot_options po = bkf_plot_options_default();
    po.cancel = o->hooks.cancel;
    po.temp_file = o->temp_file;
    po.data = o->data;
    if (!s) s = bkf_plot_run(job, &po, &report, err);
    if (!s && warning) snprintf(warning, wsize, "%s", report.warning);
    bkf_plot_job_free(job);
    return s;
}

int bkf_scene_run_step(const bkf_scene *s, const bkf_scene_plan *plan, size_t i,
                       const int *done, const bkf_scene_run_options *options, char *warning,
                       size_t wsize, bkf_error *err)
{
    static const bkf_scene_run_options none = {0};
    const bkf_scene_run_options *o = options ? options : &none;
    if (warning && wsize) warning[0] = '\0';
    if (!s || !plan || i >= plan->nsteps)
        return bkf_error_set(err, BKF_EINPUT, "scene: no such step");
    const bkf_scene_step *step = &plan->steps[i];
    if (step->kind == BKF_SCENE_STEP_FIGURE) {
        for (size_t d = 0; d < step->ndata; d++) {
            const bkf_scene_product_plan *dp = &plan->products[step->data_products[d]];
            for (size_t k = 0; done && k < dp->nsteps; k++)
                if (dp->steps[k] < i && done[dp->steps[k]])
                    return bkf_error_set(err, BKF_ENUMERIC, "skipped: its data failed");
        }
        return run_figure(s, plan, step, o, warning, wsize, err);
    }
    if (step->entry) {
        void *spec = bkf_catalog_spec_new(step->entry, err);
        if (!spec) return BKF_ENOMEM;
        int st = apply_args(step->entry, step->args, step->nargs, spec, 1, NULL, err);
        if (!st) st = step->entry->check(spec, "", err);
        if (!st) st = write_output(step, spec, write_catalogued, o, err);
        bkf_catalog_spec_free(step->entry, spec);
        return st;
    }
    return bkf_error_set(err, BKF_EINPUT, "no product %s in the catalogue", step->product);
}

/* ------------------------------------------------------------------ jobs */

/* Threads, not forked workers: every product is safe to call from two
 * threads at once (a sweep already runs them on OpenMP threads; FFTW's
 * planner is behind bkf_fft_lock, GSL's error handler behind a depth count,
 * the HDF5 calls behind their lock), the signal handler's cancel flag
 * reaches every step without a pipe, and a step's status, message and
 * warnings need no marshalling.  A step writes its own files atomically,
 * so what two steps write never meets. */

enum { STEP_PENDING = 0, STEP_RUNNING, STEP_ENDED };

typedef struct {
    const bkf_scene *s;
    const bkf_scene_plan *plan;
    const bkf_scene_run_options *o;
    int *status;              /* the caller's: written once a step ends */
    int *state;               /* STEP_*, under lock */
    size_t next;              /* no pending step before it */
    size_t running;
    pthread_mutex_t lock;     /* the schedule and the reports */
    pthread_mutex_t hook_lock; /* the caller's hooks, one call at a time */
    pthread_cond_t changed;
} run_queue;

/* One worker's view of the hooks: warnings kept for its step's report,
 * the rest passed on to the caller's, one call at a time. */
typedef struct {
    run_queue *q;
    char warning[BKF_SCENE_WARNINGS][BKF_ERROR_LEN];
    const char *warnings[BKF_SCENE_WARNINGS];
    size_t nwarnings;
} run_worker;

static void worker_warn(const char *message, void *data)
{
    run_worker *w = data;
    /* (a product may warn from threads of its own, a sweep's) */
    pthread_mutex_lock(&w->q->hook_lock);
    if (w->nwarnings < BKF_SCENE_WARNINGS) {
        snprintf(w->warning[w->nwarnings], sizeof w->warning[0], "%s", message);
        w->warnings[w->nwarnings] = w->warning[w->nwarnings];
    }
    w->nwarnings++;
    pthread_mutex_unlock(&w->q->hook_lock);
}

static int worker_progress(double fraction, void *data)
{
    run_worker *w = data;
    const bkf_scene_run_options *o = w->q->o;
    pthread_mutex_lock(&w->q->hook_lock);
    int r = o->hooks.progress(fraction, o->hooks.data);
    pthread_mutex_unlock(&w->q->hook_lock);
    return r;
}

static void worker_hook_temp(const char *path, int armed, void *data)
{
    run_worker *w = data;
    const bkf_scene_run_options *o = w->q->o;
    pthread_mutex_lock(&w->q->hook_lock);
    o->hooks.temp_file(path, armed, o->hooks.data);
    pthread_mutex_unlock(&w->q->hook_lock);
}

static void worker_table_temp(const char *path, int armed, void *data)
{
    run_worker *w = data;
    const bkf_scene_run_options *o = w->q->o;
    pthread_mutex_lock(&w->q->hook_lock);
    o->temp_file(path, armed, o->data);
    pthread_mutex_unlock(&w->q->hook_lock);
}

static int canceled(const bkf_scene_run_options *o)
{
    return o->hooks.cancel && *o->hooks.cancel;
}

/* Whether step i may start: a figure once every step of its data ended
 * (done or failed: bkf_scene_run_step skips it when its data failed). */
static int step_ready(const run_queue *q, size_t i)
{
    const bkf_scene_step *step = &q->plan->steps[i];
    if (step->kind != BKF_SCENE_STEP_FIGURE) return 1;
    for (size_t d = 0; d < step->ndata; d++) {
        const bkf_scene_product_plan *dp = &q->plan->products[step->data_products[d]];
        for (size_t k = 0; k < dp->nsteps; k++)
            if (dp->steps[k] != i && q->state[dp->steps[k]] != STEP_ENDED) return 0;
    }
    return 1;
}

/* The first pending step that may start, or nsteps when none may now;
 * under lock. */
static size_t next_step(run_queue *q)
{
    while (q->next < q->plan->nsteps && q->state[q->next] != STEP_PENDING) q->next++;
    for (size_t i = q->next; i < q->plan->nsteps; i++)
        if (q->state[i] == STEP_PENDING && step_ready(q, i)) return i;
    return q->plan->nsteps;
}

static void *run_worker_loop(void *arg)
{
    run_queue *q = arg;
    const bkf_scene_run_options *o = q->o;
    run_worker w = {.q = q};
    bkf_scene_run_options mine = *o;
    mine.hooks.warn = worker_warn;
    mine.hooks.data = &w;
    mine.hooks.progress = o->hooks.progress ? worker_progress : NULL;
    mine.hooks.temp_file = o->hooks.temp_file ? worker_hook_temp : NULL;
    mine.temp_file = o->temp_file ? worker_table_temp : NULL;
    mine.data = &w;
    size_t n = q->plan->nsteps;
    pthread_mutex_lock(&q->lock);
    for (;;) {
        size_t i = n;
        while (!canceled(o) && q->next < n && (i = next_step(q)) == n && q->running)
            pthread_cond_wait(&q->changed, &q->lock);
        if (canceled(o) || i == n) break;
        q->state[i] = STEP_RUNNING;
        q->running++;
        pthread_mutex_unlock(&q->lock);

        bkf_error e = {0};
        char gnuplot[BKF_ERROR_LEN] = "";
        struct timespec t0, t1;
        clock_gettime(CLOCK_MONOTONIC, &t0);
        /* status[] of this step's data is final (they ended before it
         * started); the entries others are writing are not read. */
        int st = bkf_scene_run_step(q->s, q->plan, i, q->status, &mine, gnuplot, sizeof gnuplot,
                                    &e);
        clock_gettime(CLOCK_MONOTONIC, &t1);
        /* A step that failed once the flag was up was stopped, not wrong;
         * one that finished anyway is complete and kept. */
        if (st && canceled(o)) {
            st = BKF_ECANCELED;
            snprintf(e.message, sizeof e.message, "stopped; its files were not replaced");
        }

        pthread_mutex_lock(&q->lock);
        q->status[i] = st;
        q->state[i] = STEP_ENDED;
        q->running--;
        if (o->step_done) {
            bkf_scene_step_report r = {
                .step = i,
                .status = st,
                .seconds = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec),
                .message = st ? e.message : "",
                .gnuplot_warning = st ? "" : gnuplot,
                .warnings = w.warnings,
                .nwarnings = w.nwarnings};
            o->step_done(&r, o->data);
        }
        w.nwarnings = 0;
        pthread_cond_broadcast(&q->changed);
    }
    pthread_cond_broadcast(&q->changed);
    pthread_mutex_unlock(&q->lock);
    return NULL;
}

int bkf_scene_run(const bkf_scene *s, const bkf_scene_plan *plan,
                  const bkf_scene_run_options *options, int *status, bkf_error *err)
{
    static const bkf_scene_run_options none = {0};
    const bkf_scene_run_options *o = options ? options : &none;
    if (!s || !plan || (plan->nsteps && !status))
        return bkf_error_set(err, BKF_EINPUT, "scene: no plan to run");
    size_t n = plan->nsteps;
    run_queue q = {.s = s, .plan = plan, .o = o, .status = status};
    q.state = calloc(n ? n : 1, sizeof *q.state);
    if (!q.state) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    for (size_t i = 0; i < n; i++) status[i] = BKF_ECANCELED; /* until it is run */
    pthread_mutex_init(&q.lock, NULL);
    pthread_mutex_init(&q.hook_lock, NULL);
    pthread_cond_init(&q.changed, NULL);

    /* The caller's thread is one of the workers; a thread that cannot be
     * made leaves the steps to the others (at worst the caller's alone). */
    size_t jobs = o->jobs > 1 ? o->jobs : 1;
    if (jobs > n) jobs = n ? n : 1;
    pthread_t *threads = jobs > 1 ? calloc(jobs - 1, sizeof *threads) : NULL;
    size_t started = 0;
    for (size_t t = 0; threads && t + 1 < jobs; t++) {
        if (pthread_create(&threads[t], NULL, run_worker_loop, &q) != 0) break;
        started++;
    }
    run_worker_loop(&q);
    for (size_t t = 0; t < started; t++) pthread_join(threads[t], NULL);
    free(threads);

    int unrun = 0;
    for (size_t i = 0; i < n; i++) unrun |= q.state[i] != STEP_ENDED;
    pthread_cond_destroy(&q.changed);
    pthread_mutex_destroy(&q.hook_lock);
    pthread_mutex_destroy(&q.lock);
    free(q.state);
    if (unrun) return bkf_error_set(err, BKF_ECANCELED, "stopped before every step was run");
    return BKF_OK;
}

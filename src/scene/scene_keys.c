/* The scene's kinds (the catalogue's declarations), the keys of a
 * section and where a value comes from ([model], [accuracy], a kind's
 * defaults), and the small tables the parser and the planner share. */
#define _POSIX_C_SOURCE 200809L
#include "scene_internal.h"

#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* The kinds of the first releases keep their numbers (scene.h); a kind a
 * product declares later (catalog.h) gets the next.  Every kind but figure
 * is a catalogue product's: its declaration is the whole recipe. */
static const char *const enum_names[BKF_SCENE_NKINDS] = {
    "speeds", "period", "dispersion", "threshold", "branch", "profile",
    "validity", "friction", "spacetime", "check", "stability", "figure", "sweep"};

/* The kinds' bits (scene.c's K) end under K_ACCURACY. */
#define MAX_KINDS 29
static scene_kind_info kinds[MAX_KINDS];
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
            kinds[k] = (scene_kind_info){e->kinds[j].name, e, &e->kinds[j]};
        }
    }
}

const scene_kind_info *scene_kind_at(int kind)
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
    const scene_kind_info *k = scene_kind_at((int)kind);
    return k ? k->name : NULL;
}

const char *scene_kind_name(bkf_scene_kind kind)
{
    const char *n = bkf_scene_kind_name(kind);
    return n ? n : "?";
}

size_t scene_hash_text(size_t h, const char *s)
{
    for (; *s; s++) h = (h ^ (unsigned char)*s) * (size_t)1099511628211u;
    return (h ^ 0xff) * (size_t)1099511628211u; /* a separator after each text */
}

void scene_lookup_free(scene_lookup *l)
{
    free(l->item);
    free(l->hash);
    *l = (scene_lookup){0};
}

/* The first index i with this hash and same(i, data), or SIZE_MAX. */
size_t scene_lookup_find(const scene_lookup *l, size_t h, int (*same)(size_t, const void *),
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
void *scene_grow_for_push(void *array, size_t count, size_t size)
{
    if (count & (count - 1)) return array; /* not a power of two: room left */
    size_t cap = count ? 2 * count : 1;
    if (cap > SIZE_MAX / size) return NULL;
    return realloc(array, cap * size);
}

/* 0 when out of memory. */
int scene_lookup_add(scene_lookup *l, size_t h, size_t index)
{
    if (2 * (l->count + 1) > l->cap) {
        scene_lookup g = {.cap = l->cap ? 2 * l->cap : 64};
        g.item = calloc(g.cap, sizeof *g.item);
        g.hash = calloc(g.cap, sizeof *g.hash);
        if (!g.item || !g.hash) {
            scene_lookup_free(&g);
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
        scene_lookup_free(l);
        *l = g;
    }
    size_t j = h & (l->cap - 1);
    while (l->item[j]) j = (j + 1) & (l->cap - 1);
    l->item[j] = index + 1;
    l->hash[j] = h;
    l->count++;
    return 1;
}

/* -------------------------------------------------------- the catalogue */

/* The option of a step's product whose list a scene makes one step per
 * value (BKF_OPT_FANOUT), or NULL. */
const bkf_option *scene_fanout_option(const bkf_catalog_entry *entry)
{
    size_t n;
    const bkf_option *table = entry->options(&n);
    for (size_t i = 0; i < n; i++)
        if (table[i].flags & BKF_OPT_FANOUT) return &table[i];
    return NULL;
}

/* A scene key as the option's name: max_points is --max-points. */
const char *scene_option_name(const char *key, char *buf, size_t size)
{
    snprintf(buf, size, "%s", key);
    for (char *c = buf; *c; c++)
        if (*c == '_') *c = '-';
    return buf;
}

const bkf_option *scene_catalog_option(const bkf_catalog_entry *entry, const char *name)
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
int scene_apply_args(const bkf_catalog_entry *entry, const bkf_scene_arg *args, size_t n,
                      void *spec, int outputs, size_t *bad, bkf_error *err)
{
    for (int pass = 0; pass < 2; pass++)
        for (size_t i = 0; i < n; i++) {
            const bkf_scene_arg *a = &args[i];
            if (a->output && (!outputs || strcmp(a->key, "out") == 0)) continue;
            const bkf_option *opt = scene_catalog_option(entry, a->key);
            if (!outputs && opt && (opt->flags & BKF_OPT_PATH)) continue;
            if ((a->value == NULL) != (pass == 0)) continue;
            if (a->fixed && !scene_catalog_option(entry, a->key)) continue;
            int s = bkf_catalog_apply(entry, spec, a->key, a->value, "", err);
            if (s) {
                if (bad) *bad = i;
                return s;
            }
        }
    return BKF_OK;
}

static void parse_item(const char *tok, size_t len, scene_key_item *it)
{
    *it = (scene_key_item){0};
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
scene_key_item *scene_parse_items(const char *text, size_t *n)
{
    *n = 0;
    size_t cap = 1;
    for (const char *c = text ? text : ""; *c; c++) cap += *c == ' ';
    scene_key_item *items = text && *text ? calloc(cap, sizeof *items) : NULL;
    for (const char *c = text; items && *c;) {
        size_t len = strcspn(c, " ");
        if (len) parse_item(c, len, &items[(*n)++]);
        c += len + (c[len] == ' ');
    }
    return items;
}

const char *scene_entry_value(const bkf_scene_entry *list, size_t n, const char *key)
{
    for (size_t i = 0; i < n; i++)
        if (strcmp(list[i].key, key) == 0) return list[i].value;
    return NULL;
}

/* The section's own value of an option name (written with _ or -). */
const char *scene_own_value(const bkf_scene_product *p, const char *key)
{
    char name[64];
    for (size_t i = 0; i < p->nentries; i++)
        if (strcmp(scene_option_name(p->entries[i].key, name, sizeof name), key) == 0)
            return p->entries[i].value;
    return NULL;
}

/* The section's own value, else, with `inherit`, [model]'s or [accuracy]'s. */
const char *scene_key(const bkf_scene *s, const bkf_scene_product *p, const char *key,
                             int inherit)
{
    const char *v = scene_own_value(p, key);
    return v || !inherit ? v : scene_entry_value(s->model, s->nmodel, key);
}

int scene_same_name(size_t i, const void *data)
{
    const scene_name_query *q = data;
    const bkf_scene_product *p = &q->s->products[i];
    return (p->kind == BKF_SCENE_FIGURE) == q->figure && strcmp(p->name, q->name) == 0;
}

const bkf_scene_product *bkf_scene_find(const bkf_scene *s, const char *name, int figures)
{
    if (s->names_) {
        scene_name_query q = {s, name, figures != 0};
        size_t i = scene_lookup_find(s->names_, scene_hash_text(SCENE_HASH_SEED + (size_t)(figures != 0), name),
                               scene_same_name, &q);
        return i == SIZE_MAX ? NULL : &s->products[i];
    }
    for (size_t i = 0; i < s->nproducts; i++)
        if ((s->products[i].kind == BKF_SCENE_FIGURE) == (figures != 0) &&
            strcmp(s->products[i].name, name) == 0)
            return &s->products[i];
    return NULL;
}

/* The line that gives `key` (an option name) to product p: its own entry,
 * else [model]/[accuracy], else the section's header. */
int scene_key_line(const bkf_scene *s, const bkf_scene_product *p, const char *key)
{
    char name[64];
    for (size_t i = 0; i < p->nentries; i++)
        if (strcmp(scene_option_name(p->entries[i].key, name, sizeof name), key) == 0)
            return p->entries[i].line;
    for (size_t i = 0; i < s->nmodel; i++)
        if (strcmp(s->model[i].key, key) == 0) return s->model[i].line;
    return p->line;
}

/* The products a figure's data = A,B,... names (spaces around the names
 * ignored), as indices into *out (malloc'd; NULL when none); *bad: the
 * first name that is no product of the scene, or NULL.  0: out of memory. */
int scene_figure_data(const bkf_scene *s, const char *data, size_t **out, size_t *count,
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
        size_t *g = scene_grow_for_push(*out, *count, sizeof *g);
        if (!g) return 0;
        *out = g;
        g[(*count)++] = (size_t)(d - s->products);
    }
    if (*count == 0 && bad && badsize) snprintf(bad, badsize, "%s", data);
    return 1;
}

/* Whether the kind of p takes [accuracy]'s `key`: where its product has
 * such a key, only when the kind's keys say ^KEY (a simulation's tol is its
 * stepper's, not the accuracy asked of a result). */
int scene_takes_inherited(const bkf_scene_product *p, const char *key)
{
    const scene_kind_info *k = scene_kind_at((int)p->kind);
    if (!k || !k->entry || !scene_catalog_option(k->entry, key)) return 1;
    size_t n;
    scene_key_item *items = scene_parse_items(k->decl->step.keys, &n);
    int takes = 0;
    for (size_t i = 0; i < n; i++)
        if (strcmp(items[i].key, key) == 0) takes = items[i].inherit;
    free(items);
    return takes;
}

/* A list value ("a,b,c" or "A:B:N") as separate texts; 0 when out of
 * memory (the value was checked when parsed). */
int scene_list_values(const char *text, char ***items, size_t *count)
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
        char **g = scene_grow_for_push(*items, *count, sizeof *g);
        if (!g) return 0;
        *items = g;
        if (!(g[*count] = strdup(t))) return 0;
        (*count)++;
    }
    return 1;
}

void scene_list_values_free(char **items, size_t count)
{
    for (size_t i = 0; i < count; i++) free(items[i]);
    free(items);
}

int scene_append(char *buf, size_t size, const char *sep, const char *text)
{
    size_t used = strlen(buf);
    int n = snprintf(buf + used, size - used, "%s%s", used ? sep : "", text);
    return n >= 0 && (size_t)n < size - used;
}

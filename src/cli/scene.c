/* Scene files (scene.h): parsing with libinih, checking, and the plan. */
#define _POSIX_C_SOURCE 200809L
#include "scene.h"

#include <ctype.h>
#include <ini.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

#include "args.h"
#include "bkfront/cycle.h"
#include "bkfront/pde.h"

static const char *const kind_names[SCENE_NKINDS] = {
    "speeds", "period", "dispersion", "threshold", "branch", "profile",
    "validity", "friction", "spacetime", "check", "figure"};

const char *scene_kind_name(scene_kind kind)
{
    return (unsigned)kind < SCENE_NKINDS ? kind_names[kind] : NULL;
}

/* ------------------------------------------------------------ key table */

typedef enum {
    V_GAMMA, V_C, V_NU, V_NU_ANY, V_S, V_TOL, V_PDE_TOL, V_GRID_N, V_MODEL,
    V_COUNT, V_SEED, V_NUMBER, V_POSITIVE, V_NU_LIST, V_COUNT_LIST, V_RANGE_LOG,
    V_RANGE_LIN, V_SEARCH, V_ALONG, V_PARAM, V_METHOD, V_STEPPER, V_FRAME, V_GRID, V_FORMATS, V_TEXT, V_NAME, V_INIT
} value_type;

#define K(kind) (1u << (kind))
#define K_CYCLE (K(SCENE_SPEEDS) | K(SCENE_BRANCH) | K(SCENE_PROFILE) | K(SCENE_CHECK))
#define K_DATA (K_CYCLE | K(SCENE_PERIOD) | K(SCENE_DISPERSION) | K(SCENE_THRESHOLD) | \
                K(SCENE_VALIDITY) | K(SCENE_SPACETIME))
#define K_MODEL (1u << 30)     /* [model] */
#define K_ACCURACY (1u << 29)  /* [accuracy] */

typedef struct {
    const char *key;
    value_type type;
    unsigned where;
    const char *form;   /* for messages: the valid values */
} key_spec;

/* A key may appear in several rows with different types by kind. */
static const key_spec keys[] = {
    {"gamma", V_GAMMA, K_MODEL | K_CYCLE | K(SCENE_DISPERSION) | K(SCENE_THRESHOLD) |
                           K(SCENE_SPACETIME), "a number in [1e-6, 1e6]"},
    {"c", V_C, K_MODEL | K_CYCLE | K(SCENE_DISPERSION) | K(SCENE_THRESHOLD) |
                   K(SCENE_SPACETIME), "a number >= 0"},
    {"nu", V_NU, K_MODEL | K_CYCLE, "a number in (-1, 1)"},
    {"nu", V_NU_ANY, K(SCENE_SPACETIME), "a finite number"},
    {"nu", V_NU_LIST, K(SCENE_PERIOD) | K(SCENE_DISPERSION) | K(SCENE_VALIDITY),
     "V, V1,V2,... or A:B:N, each in (-1, 1)"},
    {"S", V_S, K_MODEL | K_CYCLE | K(SCENE_DISPERSION) | K(SCENE_SPACETIME), "a number > 0"},
    {"model", V_MODEL, K_MODEL | K(SCENE_SPACETIME), "continuum or chain"},
    {"tol", V_TOL, K_ACCURACY | K(SCENE_SPEEDS) | K(SCENE_BRANCH) | K(SCENE_PROFILE) |
                       K(SCENE_PERIOD) | K(SCENE_DISPERSION) | K(SCENE_THRESHOLD),
     "a number in [1e-14, 0.1]"},
    {"tol", V_PDE_TOL, K(SCENE_SPACETIME) | K(SCENE_CHECK), "a number in [1e-13, 0.01]"},
    {"N", V_GRID_N, K_ACCURACY | K(SCENE_SPACETIME) | K(SCENE_CHECK),
     "an integer in [8, 1048576]"},
    {"n", V_COUNT, K(SCENE_SPEEDS) | K(SCENE_CHECK), "an integer >= 1"},
    {"n", V_COUNT_LIST, K(SCENE_BRANCH) | K(SCENE_PROFILE), "K, K1,K2,... or A:B:N, each >= 1"},
    {"nmax", V_COUNT, K(SCENE_SPEEDS), "an integer >= 1"},
    {"root", V_COUNT, K(SCENE_BRANCH) | K(SCENE_PROFILE), "an integer >= 1"},
    {"mu", V_RANGE_LOG, K(SCENE_PERIOD) | K(SCENE_VALIDITY),
     "M or a geometric range A:B:N, in [1e-6, 1e6]"},
    {"q", V_RANGE_LIN, K(SCENE_DISPERSION), "Q or a range A:B:N, >= 0"},
    {"search", V_SEARCH, K(SCENE_THRESHOLD), "A:B with -1 < A < B < 1"},
    {"along", V_ALONG, K(SCENE_THRESHOLD), "c or gamma"},
    {"param", V_PARAM, K(SCENE_BRANCH), "S, nu, gamma or c"},
    {"method", V_METHOD, K(SCENE_PERIOD) | K(SCENE_SPEEDS), "auto, asymptotic, leading or shooting"},
    {"from", V_NUMBER, K(SCENE_THRESHOLD) | K(SCENE_BRANCH) | K(SCENE_FRICTION),
     "a finite number"},
    {"to", V_NUMBER, K(SCENE_THRESHOLD) | K(SCENE_BRANCH) | K(SCENE_FRICTION),
     "a finite number"},
    {"max_points", V_COUNT, K(SCENE_BRANCH) | K(SCENE_THRESHOLD), "an integer >= 1"},
    {"points", V_COUNT, K(SCENE_PROFILE) | K(SCENE_FRICTION) | K(SCENE_CHECK),
     "an integer >= 1"},
    {"init", V_INIT, K(SCENE_SPACETIME), "uniform, front:n=K,..., oscillation:q=Q,... or file:PATH"},
    {"seed", V_SEED, K(SCENE_SPACETIME) | K(SCENE_CHECK), "an integer >= 0"},
    {"tmax", V_POSITIVE, K(SCENE_SPACETIME) | K(SCENE_CHECK), "a number > 0"},
    {"frames", V_COUNT, K(SCENE_SPACETIME), "an integer >= 1"},
    {"rel_tol", V_POSITIVE, K(SCENE_CHECK), "a number > 0"},
    {"stepper", V_STEPPER, K(SCENE_SPACETIME) | K(SCENE_CHECK), "rk8pd, rkck, rkf45 or etdrk4"},
    {"frame", V_FRAME, K(SCENE_CHECK), "moving or lab"},
    {"grid", V_GRID, K(SCENE_CHECK), "auto, uniform or mapped"},
    {"data", V_NAME, K(SCENE_FIGURE), "the name of a product of this scene"},
    {"script", V_TEXT, K(SCENE_FIGURE), "a gnuplot script path"},
    {"formats", V_FORMATS, K(SCENE_FIGURE), "png, pdf, svg or a list such as png,svg"},
    {"title", V_TEXT, K(SCENE_FIGURE), "text"},
    {"width", V_COUNT, K(SCENE_FIGURE), "an integer >= 1 (pixels)"},
    {"height", V_COUNT, K(SCENE_FIGURE), "an integer >= 1 (pixels)"},
};
#define NKEYS (sizeof keys / sizeof keys[0])

/* ------------------------------------------------------------- checking */

static int check_list(const char *key, const char *text, int counts, bkf_error *err)
{
    /* "A:B:N" is a range, anything else a comma list of single values. */
    if (strchr(text, ':')) {
        cli_range r;
        int s = cli_parse_range(key, text, 0, &r, err);
        if (s) return s;
        int bad = 0;
        for (size_t i = 0; i < r.count; i++)
            if (counts ? (r.values[i] < 1 || r.values[i] != floor(r.values[i]))
                       : !(fabs(r.values[i]) < 1))
                bad = 1;
        cli_range_free(&r);
        if (bad)
            return bkf_error_set(err, BKF_EINPUT, "%s: '%s' has values outside %s", key, text,
                                 counts ? "the integers >= 1" : "(-1, 1)");
        return BKF_OK;
    }
    char buf[SCENE_VALUE_LEN];
    snprintf(buf, sizeof buf, "%s", text);
    char *save = NULL;
    int any = 0;
    for (char *tok = strtok_r(buf, ",", &save); tok; tok = strtok_r(NULL, ",", &save)) {
        any = 1;
        if (counts) {
            size_t n;
            int s = cli_parse_count(key, tok, 100000, &n, err);
            if (s) return s;
        } else {
            double v;
            int s = cli_parse_double(key, tok, &v, err);
            if (s) return s;
            if (!(fabs(v) < 1))
                return bkf_error_set(err, BKF_EINPUT, "%s: %s is outside (-1, 1)", key, tok);
        }
    }
    if (!any || text[strlen(text) - 1] == ',' || text[0] == ',')
        return bkf_error_set(err, BKF_EINPUT, "%s: '%s' is not a list", key, text);
    return BKF_OK;
}

static int check_value(const key_spec *spec, const char *v, bkf_error *err)
{
    const char *k = spec->key;
    double x;
    size_t n;
    int s;
    switch (spec->type) {
    case V_GAMMA:
        if ((s = cli_parse_double(k, v, &x, err))) return s;
        if (!(x >= BKF_CYCLE_MU_MIN && x <= BKF_CYCLE_MU_MAX))
            return bkf_error_set(err, BKF_EINPUT, "gamma: %s is outside [1e-6, 1e6]", v);
        return BKF_OK;
    case V_C:
        if ((s = cli_parse_double(k, v, &x, err))) return s;
        if (x < 0) return bkf_error_set(err, BKF_EINPUT, "c: %s must be >= 0", v);
        return BKF_OK;
    case V_NU:
        if ((s = cli_parse_double(k, v, &x, err))) return s;
        if (!(fabs(x) < 1))
            return bkf_error_set(err, BKF_EINPUT,
                                 "nu: %s is outside (-1, 1), where there are no fronts or "
                                 "oscillations", v);
        return BKF_OK;
    case V_NUMBER:
    case V_NU_ANY:
        return cli_parse_double(k, v, &x, err);
    case V_S:
    case V_POSITIVE:
        if ((s = cli_parse_double(k, v, &x, err))) return s;
        if (!(x > 0)) return bkf_error_set(err, BKF_EINPUT, "%s: %s must be > 0", k, v);
        return BKF_OK;
    case V_TOL:
    case V_PDE_TOL: {
        double lo = spec->type == V_TOL ? 1e-14 : BKF_PDE_TOL_MIN;
        double hi = spec->type == V_TOL ? 0.1 : BKF_PDE_TOL_MAX;
        if ((s = cli_parse_double(k, v, &x, err))) return s;
        if (!(x >= lo && x <= hi))
            return bkf_error_set(err, BKF_EINPUT, "tol: %s is outside [%g, %g]", v, lo, hi);
        return BKF_OK;
    }
    case V_GRID_N:
        if ((s = cli_parse_count(k, v, BKF_PDE_N_MAX, &n, err))) return s;
        if (n < BKF_PDE_N_MIN)
            return bkf_error_set(err, BKF_EINPUT, "N: %s is below %d", v, BKF_PDE_N_MIN);
        return BKF_OK;
    case V_MODEL: {
        static const char *const m[] = {"continuum", "chain", NULL};
        int i;
        return cli_parse_choice(k, v, m, &i, err);
    }
    case V_ALONG: {
        static const char *const m[] = {"c", "gamma", NULL};
        int i;
        return cli_parse_choice(k, v, m, &i, err);
    }
    case V_METHOD: {
        static const char *const m[] = {"auto", "asymptotic", "leading", "shooting", NULL};
        int i;
        return cli_parse_choice(k, v, m, &i, err);
    }
    case V_STEPPER: {
        static const char *const m[] = {"rk8pd", "rkck", "rkf45", "etdrk4", NULL};
        int i;
        return cli_parse_choice(k, v, m, &i, err);
    }
    case V_FRAME: {
        static const char *const m[] = {"moving", "lab", NULL};
        int i;
        return cli_parse_choice(k, v, m, &i, err);
    }
    case V_GRID: {
        static const char *const m[] = {"auto", "uniform", "mapped", NULL};
        int i;
        return cli_parse_choice(k, v, m, &i, err);
    }
    case V_PARAM: {
        static const char *const m[] = {"S", "nu", "gamma", "c", NULL};
        int i;
        return cli_parse_choice(k, v, m, &i, err);
    }
    case V_COUNT:
        return cli_parse_count(k, v, 1000000, &n, err);
    case V_SEED:
        if (!*v || strspn(v, "0123456789") != strlen(v) || strlen(v) > 18)
            return bkf_error_set(err, BKF_EINPUT, "seed: '%s' is not an integer in [0, 1e18)",
                                 v);
        return BKF_OK;
    case V_NU_LIST:
        return check_list(k, v, 0, err);
    case V_COUNT_LIST:
        return check_list(k, v, 1, err);
    case V_RANGE_LOG:
    case V_RANGE_LIN: {
        cli_range r;
        int geometric = spec->type == V_RANGE_LOG;
        if ((s = cli_parse_range(k, v, geometric, &r, err))) return s;
        int bad = 0;
        for (size_t i = 0; i < r.count; i++)
            bad |= geometric ? !(r.values[i] >= BKF_CYCLE_MU_MIN && r.values[i] <= BKF_CYCLE_MU_MAX)
                             : !(r.values[i] >= 0);
        size_t count = r.count;
        cli_range_free(&r);
        if (bad)
            return bkf_error_set(err, BKF_EINPUT, "%s: '%s' is not %s", k, v, spec->form);
        if (count > 100000)
            return bkf_error_set(err, BKF_EINPUT, "%s: '%s' has more than 100000 points", k, v);
        return BKF_OK;
    }
    case V_SEARCH: {
        const char *colon = strchr(v, ':');
        double a, b;
        char left[SCENE_VALUE_LEN];
        if (!colon || strchr(colon + 1, ':'))
            return bkf_error_set(err, BKF_EINPUT, "search: '%s' is not A:B", v);
        snprintf(left, sizeof left, "%.*s", (int)(colon - v), v);
        if ((s = cli_parse_double(k, left, &a, err)) || (s = cli_parse_double(k, colon + 1, &b, err)))
            return s;
        if (!(-1 < a && a < b && b < 1))
            return bkf_error_set(err, BKF_EINPUT, "search: '%s' needs -1 < A < B < 1", v);
        return BKF_OK;
    }
    case V_FORMATS: {
        char buf[SCENE_VALUE_LEN];
        snprintf(buf, sizeof buf, "%s", v);
        char *save = NULL;
        int any = 0;
        for (char *t = strtok_r(buf, ", ", &save); t; t = strtok_r(NULL, ", ", &save)) {
            static const char *const f[] = {"png", "pdf", "svg", NULL};
            int i;
            if ((s = cli_parse_choice(k, t, f, &i, err))) return s;
            any = 1;
        }
        if (!any) return bkf_error_set(err, BKF_EINPUT, "formats: give png, pdf or svg");
        return BKF_OK;
    }
    case V_INIT:
        if (!(strcmp(v, "uniform") == 0 || strncmp(v, "uniform:", 8) == 0 ||
              strncmp(v, "front:", 6) == 0 || strncmp(v, "oscillation:", 12) == 0 ||
              strncmp(v, "file:", 5) == 0))
            return bkf_error_set(err, BKF_EINPUT, "init: '%s' is not %s", v, spec->form);
        return BKF_OK;
    case V_NAME:
    case V_TEXT:
        if (!*v) return bkf_error_set(err, BKF_EINPUT, "%s: the value is empty", k);
        for (const unsigned char *p = (const unsigned char *)v; *p; p++)
            if (*p < 0x20 || *p == 0x7f)
                return bkf_error_set(err, BKF_EINPUT, "%s: the value holds a control character", k);
        return BKF_OK;
    }
    return BKF_OK;
}

/* ------------------------------------------------------------- parsing */

typedef struct {
    scene *s;
    const char *name;
    const char *text;       /* string being read */
    size_t pos;
    int line;               /* of the line last handed to inih */
    int status;
    bkf_error *err;
    char section[SCENE_VALUE_LEN]; /* inih's current section, as recorded */
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
    if (!*name || strlen(name) >= SCENE_NAME_LEN) return 0;
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
    char inner[SCENE_VALUE_LEN];
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
    char kind[SCENE_VALUE_LEN], name[SCENE_VALUE_LEN] = "", extra[SCENE_VALUE_LEN] = "";
    int fields = sscanf(a, "%255s %255s %255s", kind, name, extra);
    int k = -1;
    for (int i = 0; fields >= 1 && i < SCENE_NKINDS; i++)
        if (strcmp(kind, kind_names[i]) == 0) k = i;
    if (k < 0) {
        fail(st, st->line,
             "unknown section [%s] (model, accuracy, speeds, period, dispersion, threshold, "
             "branch, profile, validity, friction, spacetime, check, figure)", a);
        return;
    }
    if (fields == 3) {
        fail(st, st->line, "[%s]: a section is [KIND] or [KIND NAME]", a);
        return;
    }
    if (fields == 1) snprintf(name, sizeof name, "%s", kind);
    if (!valid_name(name)) {
        fail(st, st->line, "[%s]: the name '%s' must be letters, digits, _ or - (at most %d)", a,
             name, SCENE_NAME_LEN - 1);
        return;
    }
    scene *s = st->s;
    for (size_t i = 0; i < s->nproducts; i++) {
        int fig_a = s->products[i].kind == SCENE_FIGURE, fig_b = k == SCENE_FIGURE;
        if (fig_a == fig_b && strcmp(s->products[i].name, name) == 0) {
            fail(st, st->line, "[%s]: the name '%s' is already used on line %d", a, name,
                 s->products[i].line);
            return;
        }
    }
    scene_product *grown = realloc(s->products, (s->nproducts + 1) * sizeof *grown);
    if (!grown) {
        st->status = bkf_error_set(st->err, BKF_ENOMEM, "out of memory");
        return;
    }
    s->products = grown;
    scene_product *prod = &s->products[s->nproducts];
    *prod = (scene_product){.kind = (scene_kind)k, .line = st->line};
    snprintf(prod->name, sizeof prod->name, "%.*s", SCENE_NAME_LEN - 1, name);
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

static scene_entry *push_entry(scene_entry **list, size_t *n)
{
    scene_entry *grown = realloc(*list, (*n + 1) * sizeof *grown);
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
    scene_entry **list;
    size_t *count;
    if (st->section_kind == -1 || st->section_kind == -2) {
        where = st->section_kind == -1 ? K_MODEL : K_ACCURACY;
        list = &st->s->model;
        count = &st->s->nmodel;
    } else {
        scene_product *p = &st->s->products[st->section_kind];
        where = K(p->kind);
        list = &p->entries;
        count = &p->nentries;
    }
    const key_spec *spec = NULL;
    char known[512] = "";
    for (size_t i = 0; i < NKEYS; i++) {
        if (!(keys[i].where & where)) continue;
        if (strcmp(keys[i].key, name) == 0) spec = &keys[i];
        int listed = 0;
        for (size_t j = 0; j < i; j++)
            if ((keys[j].where & where) && strcmp(keys[j].key, keys[i].key) == 0) listed = 1;
        if (!listed) {
            size_t used = strlen(known);
            snprintf(known + used, sizeof known - used, "%s%s", used ? ", " : "", keys[i].key);
        }
    }
    if (!spec) return fail(st, st->line, "[%s]: unknown key '%s' (%s)", st->section, name, known);
    for (size_t i = 0; i < *count; i++)
        if (strcmp((*list)[i].key, name) == 0)
            return fail(st, st->line, "[%s]: '%s' is already set on line %d", st->section, name,
                        (*list)[i].line);
    if (strlen(value) >= SCENE_VALUE_LEN)
        return fail(st, st->line, "%s: the value is longer than %d characters", name,
                    SCENE_VALUE_LEN - 1);
    bkf_error e;
    if (check_value(spec, value, &e))
        return fail(st, st->line, "%s (%s)", e.message, spec->form);
    scene_entry *entry = push_entry(list, count);
    if (!entry) {
        st->status = bkf_error_set(st->err, BKF_ENOMEM, "out of memory");
        return 0;
    }
    snprintf(entry->key, sizeof entry->key, "%s", name);
    snprintf(entry->value, sizeof entry->value, "%s", value);
    entry->line = st->line;
    return 1;
}

static const char *entry_value(const scene_entry *list, size_t n, const char *key)
{
    for (size_t i = 0; i < n; i++)
        if (strcmp(list[i].key, key) == 0) return list[i].value;
    return NULL;
}

const char *scene_value(const scene *s, const scene_product *p, const char *key)
{
    const char *v = p ? entry_value(p->entries, p->nentries, key) : NULL;
    if (v) return v;
    /* A simulation's tol is a Runge-Kutta tolerance, not the accuracy asked
     * of a result: it is not inherited. */
    if (p && strcmp(key, "tol") == 0 &&
        (p->kind == SCENE_SPACETIME || p->kind == SCENE_CHECK || p->kind == SCENE_VALIDITY))
        return NULL;
    return entry_value(s->model, s->nmodel, key);
}

const scene_product *scene_find(const scene *s, const char *name, int figures)
{
    for (size_t i = 0; i < s->nproducts; i++)
        if ((s->products[i].kind == SCENE_FIGURE) == (figures != 0) &&
            strcmp(s->products[i].name, name) == 0)
            return &s->products[i];
    return NULL;
}

static int entry_line(const scene_product *p, const char *key)
{
    for (size_t i = 0; i < p->nentries; i++)
        if (strcmp(p->entries[i].key, key) == 0) return p->entries[i].line;
    return p->line;
}

/* What needs the whole scene: required keys, references, the model's
 * parameters where a product needs them. */
static int check_scene(parse_state *st)
{
    scene *s = st->s;
    if (!st->seen_model) return fail(st, 1, "the scene has no [model] section");
    if (s->nproducts == 0) return fail(st, st->line, "the scene asks for no product");
    static const char *const model_keys[] = {"gamma", "c", "nu", "S"};
    for (size_t i = 0; i < s->nproducts; i++) {
        const scene_product *p = &s->products[i];
        if (p->kind == SCENE_FIGURE) {
            const char *data = entry_value(p->entries, p->nentries, "data");
            if (!data) return fail(st, p->line, "[figure %s]: give data = NAME of the product shown", p->name);
            if (!scene_find(s, data, 0))
                return fail(st, entry_line(p, "data"), "data: no product named '%s' in this scene",
                            data);
            continue;
        }
        if (p->kind == SCENE_FRICTION) continue;
        for (size_t k = 0; k < 4; k++) {
            const char *key = model_keys[k];
            if (p->kind == SCENE_THRESHOLD && (strcmp(key, "nu") == 0 || strcmp(key, "S") == 0))
                continue;
            if ((p->kind == SCENE_PERIOD || p->kind == SCENE_VALIDITY) && strcmp(key, "nu") != 0)
                continue;
            if (p->kind == SCENE_DISPERSION && strcmp(key, "S") == 0) continue;
            if (p->kind == SCENE_BRANCH || p->kind == SCENE_THRESHOLD) {
                const char *along = entry_value(p->entries, p->nentries,
                                                p->kind == SCENE_BRANCH ? "param" : "along");
                if (along && strcmp(along, key) == 0) continue;
            }
            if (!scene_value(s, p, key))
                return fail(st, p->line, "[%s %s]: %s is not set here nor in [model]",
                            kind_names[p->kind], p->name, key);
        }
        if (p->kind == SCENE_BRANCH) {
            if (!entry_value(p->entries, p->nentries, "param"))
                return fail(st, p->line, "[branch %s]: give param = S, nu, gamma or c", p->name);
            if (!entry_value(p->entries, p->nentries, "to"))
                return fail(st, p->line, "[branch %s]: give to = the end value of the parameter",
                            p->name);
        }
        if (p->kind == SCENE_THRESHOLD) {
            int along = entry_value(p->entries, p->nentries, "along") != NULL;
            int from = entry_value(p->entries, p->nentries, "from") != NULL;
            int to = entry_value(p->entries, p->nentries, "to") != NULL;
            if (along != from || along != to)
                return fail(st, p->line, "[threshold %s]: along, from and to go together", p->name);
        }
        if (p->kind == SCENE_SPEEDS && entry_value(p->entries, p->nentries, "n") &&
            entry_value(p->entries, p->nentries, "nmax"))
            return fail(st, entry_line(p, "nmax"), "[speeds %s]: give n or nmax, not both", p->name);
    }
    return 1;
}

int scene_parse_string(const char *text, const char *name, scene **out, bkf_error *err)
{
    *out = NULL;
    if (!text) return bkf_error_set(err, BKF_EINPUT, "scene: no text");
    scene *s = calloc(1, sizeof *s);
    if (!s || !(s->path = strdup(name ? name : "scene"))) {
        free(s);
        return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    }
    parse_state st = {.s = s, .name = s->path, .text = text, .err = err, .section_kind = -3};
    /* Strict: no Python-style continuation lines, comments with ; or #. */
    ini_allow_multiline = 0;
    ini_allow_inline_comments = 1;
    ini_inline_comment_prefixes = (char *)";#";
    int r = ini_parse_stream(reader, &st, handler, &st);
    if (!st.status && r > 0) fail(&st, r, "not a section header, key = value or comment");
    if (!st.status && r < 0) st.status = bkf_error_set(err, BKF_ENOMEM, "scene: out of memory");
    if (!st.status) check_scene(&st);
    if (st.status) {
        scene_free(s);
        return st.status;
    }
    *out = s;
    return BKF_OK;
}

int scene_parse_file(const char *path, scene **out, bkf_error *err)
{
    *out = NULL;
    FILE *f = fopen(path, "rb");
    if (!f) return bkf_error_set(err, BKF_EINPUT, "scene %s: cannot open it", path);
    size_t cap = 4096, n = 0;
    char *buf = malloc(cap);
    int status = buf ? BKF_OK : bkf_error_set(err, BKF_ENOMEM, "out of memory");
    while (!status) {
        if (n + 1 >= cap) {
            if (cap > (1u << 24)) {
                status = bkf_error_set(err, BKF_EINPUT, "scene %s: larger than 16 MiB", path);
                break;
            }
            char *g = realloc(buf, cap *= 2);
            if (!g) {
                status = bkf_error_set(err, BKF_ENOMEM, "out of memory");
                break;
            }
            buf = g;
        }
        size_t k = fread(buf + n, 1, cap - 1 - n, f);
        n += k;
        if (k == 0) break;
    }
    if (!status && ferror(f)) status = bkf_error_set(err, BKF_EINPUT, "scene %s: read error", path);
    fclose(f);
    if (!status && memchr(buf, '\0', n))
        status = bkf_error_set(err, BKF_EINPUT, "scene %s: holds a NUL byte (not a text file)", path);
    if (!status) {
        buf[n] = '\0';
        status = scene_parse_string(buf, path, out, err);
    }
    free(buf);
    return status;
}

void scene_free(scene *s)
{
    if (!s) return;
    for (size_t i = 0; i < s->nproducts; i++) free(s->products[i].entries);
    free(s->products);
    free(s->model);
    free(s->path);
    free(s);
}

/* ------------------------------------------------------------------ plan */

typedef struct {
    char **v;
    int n, cap;
} argv_builder;

static int argv_push(argv_builder *b, const char *text)
{
    if (b->n + 2 > b->cap) {
        int cap = b->cap ? 2 * b->cap : 16;
        char **g = realloc(b->v, (size_t)cap * sizeof *g);
        if (!g) return 0;
        b->v = g;
        b->cap = cap;
    }
    if (!(b->v[b->n] = strdup(text))) return 0;
    b->v[++b->n] = NULL;
    return 1;
}

static int argv_pair(argv_builder *b, const char *flag, const char *value)
{
    return !value || (argv_push(b, flag) && argv_push(b, value));
}

static void argv_free(char **v)
{
    if (!v) return;
    for (char **p = v; *p; p++) free(*p);
    free(v);
}

/* A list value ("a,b,c" or "A:B:N") as separate texts. */
int scene_list_values(const char *text, char ***items, size_t *count)
{
    *items = NULL;
    *count = 0;
    if (strchr(text, ':')) {
        cli_range r;
        bkf_error e;
        if (cli_parse_range("list", text, 0, &r, &e)) return 0;
        *items = calloc(r.count, sizeof **items);
        for (size_t i = 0; *items && i < r.count; i++) {
            char buf[64];
            snprintf(buf, sizeof buf, "%.15g", r.values[i]);
            (*items)[i] = strdup(buf);
            if (!(*items)[i]) break;
            (*count)++;
        }
        size_t want = r.count;
        cli_range_free(&r);
        return *items && *count == want;
    }
    char buf[SCENE_VALUE_LEN];
    snprintf(buf, sizeof buf, "%s", text);
    char *save = NULL;
    for (char *t = strtok_r(buf, ",", &save); t; t = strtok_r(NULL, ",", &save)) {
        char **g = realloc(*items, (*count + 1) * sizeof *g);
        if (!g) return 0;
        *items = g;
        if (!(g[*count] = strdup(t))) return 0;
        (*count)++;
    }
    return 1;
}

void scene_list_free(char **items, size_t count)
{
    for (size_t i = 0; i < count; i++) free(items[i]);
    free(items);
}

static int is_output_flag(const char *flag)
{
    return strcmp(flag, "--out") == 0 || strcmp(flag, "--spacetime") == 0;
}

/* Same computation: the same arguments but for the files written. */
static int same_command(char **a, char **b)
{
    int i = 0, j = 0;
    for (;;) {
        while (a[i] && is_output_flag(a[i])) i += 2;
        while (b[j] && is_output_flag(b[j])) j += 2;
        if (!a[i] || !b[j]) return !a[i] && !b[j];
        if (strcmp(a[i], b[j]) != 0) return 0;
        i++, j++;
    }
}

static int plan_add_user(scene_step *st, size_t product)
{
    for (size_t i = 0; i < st->nusers; i++)
        if (st->users[i] == product) return 1;
    size_t *g = realloc(st->users, (st->nusers + 1) * sizeof *g);
    if (!g) return 0;
    st->users = g;
    g[st->nusers++] = product;
    return 1;
}

static int product_add_step(scene_plan *plan, size_t product, size_t step)
{
    scene_product_plan *pp = &plan->products[product];
    size_t *g = realloc(pp->steps, (pp->nsteps + 1) * sizeof *g);
    if (!g) return 0;
    pp->steps = g;
    g[pp->nsteps++] = step;
    return plan_add_user(&plan->steps[step], product);
}

/* Adds the step, or finds the same computation already planned.  Takes
 * ownership of argv and output. */
static int plan_step(scene_plan *plan, size_t product, step_kind kind, char **argv,
                     char *output, size_t data_product)
{
    if (kind == STEP_COMMAND)
        for (size_t i = 0; i < plan->nsteps; i++)
            if (plan->steps[i].kind == STEP_COMMAND && same_command(plan->steps[i].argv, argv)) {
                argv_free(argv);
                free(output);
                plan->deduplicated++;
                return product_add_step(plan, product, i);
            }
    scene_step *g = realloc(plan->steps, (plan->nsteps + 1) * sizeof *g);
    if (!g) {
        argv_free(argv);
        free(output);
        return 0;
    }
    plan->steps = g;
    scene_step *st = &g[plan->nsteps];
    *st = (scene_step){.kind = kind, .argv = argv, .output = output, .data_product = data_product};
    for (char **p = argv; p && *p; p++) st->argc++;
    plan->nsteps++;
    return product_add_step(plan, product, plan->nsteps - 1);
}

/* Ends building one step: hands argv and output over to the plan, or frees
 * them when building failed (ok 0 or no output path). */
static int finish_step(scene_plan *plan, size_t product, step_kind kind, int ok,
                       argv_builder *b, char *output, size_t data_product)
{
    if (!ok || !output) {
        free(output);
        argv_free(b->v);
        return 0;
    }
    return plan_step(plan, product, kind, b->v, output, data_product);
}

static char *out_path(const char *dir, const char *name, const char *suffix)
{
    size_t n = strlen(dir) + strlen(name) + strlen(suffix) + 2;
    char *p = malloc(n);
    if (p) snprintf(p, n, "%s/%s%s", dir, name, suffix);
    return p;
}

/* The model flags every cycle-based command takes. */
static int model_flags(argv_builder *b, const scene *s, const scene_product *p, int with_nu,
                       int with_S)
{
    const char *skip = NULL;
    if (p->kind == SCENE_BRANCH) skip = entry_value(p->entries, p->nentries, "param");
    if (p->kind == SCENE_THRESHOLD) skip = entry_value(p->entries, p->nentries, "along");
    static const char *const names[] = {"gamma", "c", "nu", "S"};
    static const char *const flags[] = {"--gamma", "--c", "--nu", "--S"};
    for (int i = 0; i < 4; i++) {
        if ((i == 2 && !with_nu) || (i == 3 && !with_S)) continue;
        if (skip && strcmp(skip, names[i]) == 0) continue;
        if (!argv_pair(b, flags[i], scene_value(s, p, names[i]))) return 0;
    }
    return 1;
}

static int plan_product(scene_plan *plan, const scene *s, size_t index,
                        const scene_plan_options *o)
{
    const scene_product *p = &s->products[index];
    const char *dir = plan->outdir;
    const char *v;
    argv_builder b = {0};
    int ok = 1;
#define ARG(x) (ok = ok && argv_push(&b, (x)))
#define PAIR(f, x) (ok = ok && argv_pair(&b, (f), (x)))
#define OWN(k, x) (p->entries ? entry_value(p->entries, p->nentries, (x)) : NULL)
    switch (p->kind) {
    case SCENE_SPEEDS: {
        ARG("speeds");
        ok = ok && model_flags(&b, s, p, 1, 1);
        PAIR("--n", OWN(0, "n"));
        PAIR("--nmax", OWN(0, "nmax"));
        PAIR("--tol", scene_value(s, p, "tol"));
        PAIR("--method", OWN(0, "method"));
        char *out = out_path(dir, p->name, ".tsv");
        PAIR("--out", out);
        return finish_step(plan, index, STEP_COMMAND, ok, &b, out, 0);
    }
    case SCENE_PERIOD:
    case SCENE_DISPERSION: {
        char **nus;
        size_t count;
        if (!scene_list_values(scene_value(s, p, "nu"), &nus, &count)) return 0;
        for (size_t i = 0; ok && i < count; i++) {
            b = (argv_builder){0};
            char suffix[32];
            snprintf(suffix, sizeof suffix, count > 1 ? "_%zu.tsv" : ".tsv", i + 1);
            char *out = out_path(dir, p->name, suffix);
            if (p->kind == SCENE_PERIOD) {
                ARG("period");
                const char *mu = OWN(0, "mu");
                PAIR("--mu", mu ? mu : "0.1:1e4:41");
                if (!mu || strchr(mu, ':')) ARG("--log");
                PAIR("--method", OWN(0, "method"));
            } else {
                ARG("floquet");
                PAIR("--gamma", scene_value(s, p, "gamma"));
                PAIR("--c", scene_value(s, p, "c"));
                const char *q = OWN(0, "q");
                PAIR("--q", q ? q : "0:6:241");
                PAIR("--S", scene_value(s, p, "S"));
            }
            PAIR("--nu", nus[i]);
            PAIR("--tol", scene_value(s, p, "tol"));
            PAIR("--out", out);
            ok = finish_step(plan, index, STEP_COMMAND, ok, &b, out, 0);
        }
        scene_list_free(nus, count);
        return ok;
    }
    case SCENE_THRESHOLD: {
        ARG("floquet");
        ARG("--threshold");
        ok = ok && model_flags(&b, s, p, 0, 0);
        PAIR("--along", OWN(0, "along"));
        PAIR("--from", OWN(0, "from"));
        PAIR("--to", OWN(0, "to"));
        PAIR("--search", OWN(0, "search"));
        PAIR("--tol", scene_value(s, p, "tol"));
        char *out = out_path(dir, p->name, ".tsv");
        PAIR("--out", out);
        return finish_step(plan, index, STEP_COMMAND, ok, &b, out, 0);
    }
    case SCENE_BRANCH: {
        char **ns;
        size_t count;
        v = OWN(0, "n");
        if (!scene_list_values(v ? v : "1", &ns, &count)) return 0;
        const char *param = OWN(0, "param");
        const char *from = OWN(0, "from");
        if (!from) from = scene_value(s, p, param);
        for (size_t i = 0; ok && i < count; i++) {
            b = (argv_builder){0};
            char suffix[32];
            snprintf(suffix, sizeof suffix, count > 1 ? "_%zu.tsv" : ".tsv", i + 1);
            char *out = out_path(dir, p->name, suffix);
            ARG("branch");
            PAIR("--param", param);
            PAIR("--from", from);
            PAIR("--to", OWN(0, "to"));
            ok = ok && model_flags(&b, s, p, 1, 1);
            PAIR("--n", ns[i]);
            PAIR("--root", OWN(0, "root"));
            PAIR("--max-points", OWN(0, "max_points"));
            PAIR("--tol", scene_value(s, p, "tol"));
            PAIR("--out", out);
            ok = finish_step(plan, index, STEP_COMMAND, ok, &b, out, 0);
        }
        scene_list_free(ns, count);
        return ok;
    }
    case SCENE_PROFILE: {
        ARG("profile");
        ok = ok && model_flags(&b, s, p, 1, 1);
        v = OWN(0, "n");
        PAIR("--n", v ? v : "1");
        PAIR("--root", OWN(0, "root"));
        PAIR("--points", OWN(0, "points"));
        PAIR("--tol", scene_value(s, p, "tol"));
        char *out = out_path(dir, p->name, ".tsv");
        PAIR("--out", out);
        return finish_step(plan, index, STEP_COMMAND, ok, &b, out, 0);
    }
    case SCENE_VALIDITY: {
        ARG("asymptotics");
        ARG("--grid");
        v = OWN(0, "mu");
        PAIR("--mu", v ? v : "0.1:1e4:21");
        ARG("--log");
        v = OWN(0, "nu");
        PAIR("--nu", v ? v : "-0.99:0.99:12");
        char *out = out_path(dir, p->name, ".tsv");
        PAIR("--out", out);
        return finish_step(plan, index, STEP_COMMAND, ok, &b, out, 0);
    }
    case SCENE_FRICTION: {
        /* argv holds the settings, for the plan's listing and the runner */
        ARG("friction");
        v = OWN(0, "from");
        PAIR("--from", v ? v : "-1");
        v = OWN(0, "to");
        PAIR("--to", v ? v : "4");
        v = OWN(0, "points");
        PAIR("--points", v ? v : "601");
        char *out = out_path(dir, p->name, ".tsv");
        PAIR("--out", out);
        return finish_step(plan, index, STEP_FORMULA, ok, &b, out, 0);
    }
    case SCENE_SPACETIME: {
        ARG("simulate");
        ok = ok && model_flags(&b, s, p, 1, 1);
        PAIR("--model", scene_value(s, p, "model"));
        v = scene_value(s, p, "N");
        PAIR("--N", v ? v : "512");
        v = OWN(0, "tmax");
        PAIR("--tmax", v ? v : "50");
        v = OWN(0, "init");
        PAIR("--init", v ? v : "uniform");
        v = OWN(0, "seed");
        PAIR("--seed", v ? v : "1");
        v = OWN(0, "frames");
        PAIR("--frames", v ? v : "500");
        PAIR("--tol", OWN(0, "tol"));
        PAIR("--stepper", OWN(0, "stepper"));
        ARG("--no-progress");
        char *st = out_path(dir, p->name, ".dat");
        char *out = out_path(dir, p->name, "_diag.tsv");
        PAIR("--spacetime", st);
        ok = ok && out;
        PAIR("--out", out);
        free(out);
        return finish_step(plan, index, STEP_COMMAND, ok, &b, st, 0);
    }
    case SCENE_CHECK: {
        ARG("check");
        ok = ok && model_flags(&b, s, p, 1, 1);
        PAIR("--n", OWN(0, "n"));
        PAIR("--N", scene_value(s, p, "N"));
        PAIR("--tmax", OWN(0, "tmax"));
        PAIR("--tol", OWN(0, "tol"));
        PAIR("--rel-tol", OWN(0, "rel_tol"));
        PAIR("--seed", OWN(0, "seed"));
        PAIR("--stepper", OWN(0, "stepper"));
        PAIR("--frame", OWN(0, "frame"));
        PAIR("--grid", OWN(0, "grid"));
        PAIR("--points", OWN(0, "points"));
        ARG("--no-progress");
        char *out = out_path(dir, p->name, ".tsv");
        PAIR("--out", out);
        return finish_step(plan, index, STEP_COMMAND, ok, &b, out, 0);
    }
    case SCENE_FIGURE: {
        if (!o->figures) return 1;
        const scene_product *data = scene_find(s, OWN(0, "data"), 0);
        size_t di = (size_t)(data - s->products);
        unsigned formats = 0;
        v = OWN(0, "formats");
        if (v) {
            formats |= strstr(v, "png") ? 1u : 0u;
            formats |= strstr(v, "pdf") ? 2u : 0u;
            formats |= strstr(v, "svg") ? 4u : 0u;
        } else
            formats = o->formats ? o->formats : 1u;
        ARG("figure");
        static const char *const ext[] = {"png", "pdf", "svg"};
        char *first = NULL;
        for (int f = 0; f < 3; f++) {
            if (!(formats & (1u << f))) continue;
            char suffix[8];
            snprintf(suffix, sizeof suffix, ".%s", ext[f]);
            char *path = out_path(dir, p->name, suffix);
            PAIR("--out", path);
            if (!first)
                first = path;
            else
                free(path);
        }
        return finish_step(plan, index, STEP_FIGURE, ok, &b, first, di);
    }
    case SCENE_NKINDS:
        break;
    }
#undef ARG
#undef PAIR
#undef OWN
    argv_free(b.v);
    return 1;
}

int scene_make_plan(const scene *s, const scene_plan_options *o, scene_plan *plan,
                    bkf_error *err)
{
    *plan = (scene_plan){0};
    if (!o || !o->outdir || !*o->outdir)
        return bkf_error_set(err, BKF_EINPUT, "plan: no output folder");
    if (strpbrk(o->outdir, " \t\n'\""))
        return bkf_error_set(err, BKF_EINPUT,
                             "--out: '%s' holds a space or a quote, which the figure scripts "
                             "cannot take in a file list", o->outdir);
    plan->outdir = strdup(o->outdir);
    plan->products = calloc(s->nproducts ? s->nproducts : 1, sizeof *plan->products);
    plan->nproducts = s->nproducts;
    int ok = plan->outdir && plan->products;
    /* Data first, figures after everything they could show. */
    for (int pass = 0; ok && pass < 2; pass++)
        for (size_t i = 0; ok && i < s->nproducts; i++)
            if ((s->products[i].kind == SCENE_FIGURE) == (pass == 1))
                ok = plan_product(plan, s, i, o);
    if (!ok) {
        scene_plan_free(plan);
        return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    }
    return BKF_OK;
}

void scene_plan_free(scene_plan *plan)
{
    if (!plan) return;
    for (size_t i = 0; i < plan->nsteps; i++) {
        argv_free(plan->steps[i].argv);
        free(plan->steps[i].output);
        free(plan->steps[i].users);
    }
    free(plan->steps);
    for (size_t i = 0; plan->products && i < plan->nproducts; i++) free(plan->products[i].steps);
    free(plan->products);
    free(plan->outdir);
    *plan = (scene_plan){0};
}

const char *scene_step_label(const scene_step *step)
{
    return step->argv && step->argv[0] ? step->argv[0] : "?";
}

char *scene_step_command(const scene_step *step)
{
    if (step->kind == STEP_FIGURE) return strdup("gnuplot");
    return cli_command_line(step->argc, step->argv);
}

/* Sweeps of the simulation product over a grid (sweep.h). */
#define _POSIX_C_SOURCE 200809L
#include "bkfront/sweep.h"

#include <errno.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <pthread.h>
#include <inttypes.h>
#include <stdarg.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "bkfront/fronts.h"
#include "bkfront/io.h"
#include "bkfront/measure.h"
#include "bkfront/oscillation.h"
#include "bkfront/version.h"

#include "product_internal.h"

/* Seeds pass through a list of doubles: exact up to 2^53. */
#define SEED_MAX 9007199254740992.0

#define SPEC(field) offsetof(bkf_sweep_spec, field)

const char *const bkf_sweep_product_names[] = {"regime", "speeds", "threshold", NULL};

const bkf_option bkf_sweep_options[] = {
    {.name = "x", .type = BKF_OPT_TEXT, .offset = SPEC(x), .form = "NAME=LIST",
     .help = "first axis: NAME one of gamma, c, nu, S, N, tmax, seed;\n"
             "LIST as V1,V2,... or A:B:N"},
    {.name = "y", .type = BKF_OPT_TEXT, .offset = SPEC(y), .form = "NAME=LIST",
     .help = "second axis, as --x"},
    {.name = "product", .type = BKF_OPT_CHOICE, .offset = SPEC(product),
     .choices = bkf_sweep_product_names, .form = "regime|speeds|threshold",
     .shown_default = "regime",
     .help = "what a row holds: regime, the direct simulation's;\n"
             "speeds, the allowed and stable n (bkfront speeds --stability\n"
             "at the point's gamma, c, nu, S); threshold, the global\n"
             "oscillation's Floquet boundaries in nu at its gamma, c\n"
             "(bkfront floquet --threshold and --diagram)"},
    {.name = "zip", .type = BKF_OPT_SWITCH, .offset = SPEC(zip),
     .help = "x and y are a list of pairs (equal lengths), not a grid"},
    {.name = "seeds", .type = BKF_OPT_COUNT_LIST, .offset = SPEC(seeds), .min = 0,
     .max = SEED_MAX, .flags = BKF_OPT_MIN | BKF_OPT_MAX, .max_count = 100000, .form = "LIST",
     .shown_default = "--seed", .help = "seeds of every point, integers in [0, 2^53]"},
    {.name = "inits", .type = BKF_OPT_TEXT, .offset = SPEC(inits), .form = "SPEC;SPEC;...",
     .shown_default = "--init",
     .help = "initial states of every point (as --init), separated by ';'"},
    {.name = "threads", .type = BKF_OPT_COUNT, .offset = SPEC(threads),
     .flags = BKF_OPT_MIN | BKF_OPT_MAX, .min = 1, .max = 4096, .form = "K",
     .shown_default = "every core; under mpirun 1 a rank",
     .help = "OpenMP threads, one run each, in [1, 4096]; under mpirun\n"
             "the compute threads of every rank (rank 0's beside its\n"
             "manager): -np K --threads T runs K T points at once"},
    {.name = "task", .type = BKF_OPT_COUNT, .offset = SPEC(task), .flags = BKF_OPT_MIN | BKF_OPT_MAX,
     .min = 0, .max = 1000000, .form = "I", .shown_default = "0",
     .help = "with --of K: compute only the points i with i % K == I\n"
             "(a job array's index), in [0, K - 1]"},
    {.name = "of", .type = BKF_OPT_COUNT, .offset = SPEC(of), .flags = BKF_OPT_MIN | BKF_OPT_MAX,
     .min = 1, .max = 1000000, .form = "K", .shown_default = "1",
     .help = "number of tasks the points are split into, in [1, 1e6]"},
    {.name = "tmax-budget", .type = BKF_OPT_DOUBLE, .offset = SPEC(tmax_budget),
     .flags = BKF_OPT_MIN | BKF_OPT_MAX | BKF_OPT_MIN_OPEN, .min = 0, .max = BKF_SIMULATE_TMAX_MAX,
     .form = "T", .shown_default = "none (every run stops at tmax)",
     .help = "let a run go on until its regime settles: its length doubles\n"
             "(tmax, 2 tmax, 4 tmax, ...; each a run from t = 0) until the\n"
             "regimes of two successive windows [t/2, t] and [t, 2t] agree\n"
             "(and their front counts, for fronts and pacemakers; two\n"
             "transients never agree), or the next doubling would pass T;\n"
             "column settled says which\n"
             "(settled, budget); T >= tmax, in (0, 1e6]"},
    {.name = "fields", .type = BKF_OPT_TEXT, .offset = SPEC(fields), .form = "DIR",
     .flags = BKF_OPT_PATH, .shown_default = "none",
     .help = "keep each point's spacetime field psi(t, x) as HDF5 in\n"
             "DIR/point_I.h5 (I the point; the file of simulate\n"
             "--spacetime FILE.h5, the parameters as attributes), written\n"
             "atomically by the thread or MPI worker that computes the\n"
             "point; with --tmax-budget the last run's; product regime only;\n"
             "with --resume only the points computed now have one"},
};
const size_t bkf_sweep_noptions = sizeof bkf_sweep_options / sizeof bkf_sweep_options[0];

/* The simulation's keys apply to a sweep spec as they are: sim is its
 * first member. */
_Static_assert(offsetof(bkf_sweep_spec, sim) == 0, "sim must be the sweep spec's first member");

/* The sweep's keys and the simulation's but its files (BKF_OPT_RUN_FILE),
 * allocated once: a fixed table would drop keys silently as simulate gains
 * them. */
static bkf_option *all_keys;
static size_t nall_keys;
static pthread_once_t keys_once = PTHREAD_ONCE_INIT;

static void build_keys(void)
{
    all_keys = malloc((bkf_sweep_noptions + bkf_simulate_noptions) * sizeof *all_keys);
    if (!all_keys) return;
    size_t n = 0;
    for (size_t i = 0; i < bkf_sweep_noptions; i++) all_keys[n++] = bkf_sweep_options[i];
    for (size_t i = 0; i < bkf_simulate_noptions; i++)
        if (!(bkf_simulate_options[i].flags & BKF_OPT_RUN_FILE))
            all_keys[n++] = bkf_simulate_options[i];
    nall_keys = n;
}

const bkf_option *bkf_sweep_keys(size_t *count)
{
    pthread_once(&keys_once, build_keys);
    if (count) *count = nall_keys;
    return all_keys;
}

bkf_sweep_spec bkf_sweep_spec_default(void)
{
    bkf_sweep_spec s;
    memset(&s, 0, sizeof s);
    s.sim = bkf_simulate_spec_default();
    return s;
}

void bkf_sweep_spec_free(bkf_sweep_spec *spec)
{
    if (spec) bkf_list_free(&spec->seeds);
}

/* ------------------------------------------------------------ the plan */

static const char *const axis_names[] = {"gamma", "c", "nu", "S", "N", "tmax", "seed", NULL};

typedef struct {
    const bkf_option *opt; /* NULL: no axis */
    bkf_list values;
} axis;

typedef struct {
    axis x, y;
    size_t nx, ny, nseeds, ninits;
    char **inits;          /* ninits texts; NULL entries: the base's */
    size_t count;
} plan;

static void plan_free(plan *p)
{
    bkf_list_free(&p->x.values);
    bkf_list_free(&p->y.values);
    for (size_t i = 0; p->inits && i < p->ninits; i++) free(p->inits[i]);
    free(p->inits);
    memset(p, 0, sizeof *p);
}

/* A number as the option tables read it: the shortest text that reads
 * back bit for bit. */
static int apply_number(const bkf_option *opt, bkf_simulate_spec *sim, double v, const char *prefix,
                        bkf_error *err)
{
    char text[40];
    if (opt->type == BKF_OPT_SEED || opt->type == BKF_OPT_COUNT)
        snprintf(text, sizeof text, "%.0f", v);
    else
        bkf_format_number(v, text, sizeof text);
    return bkf_option_apply(opt, sim, text, prefix, err);
}

static int parse_axis(const char *text, const char *key, const char *prefix,
                      const bkf_simulate_spec *base, axis *a, bkf_error *err)
{
    char shown[80];
    const char *eq = text ? strchr(text, '=') : NULL;
    if (!eq)
        return bkf_error_set(err, BKF_EINPUT, "%s%s: '%s' is not NAME=LIST", prefix, key,
                             bkf_option_shown(text ? text : "", shown, sizeof shown));
    size_t len = (size_t)(eq - text);
    const char *name = NULL;
    for (size_t i = 0; axis_names[i]; i++)
        if (strlen(axis_names[i]) == len && strncmp(axis_names[i], text, len) == 0)
            name = axis_names[i];
    if (!name)
        return bkf_error_set(err, BKF_EINPUT,
                             "%s%s: '%.*s' is not a parameter of a sweep (gamma, c, nu, S, N, "
                             "tmax, seed)",
                             prefix, key, (int)(len < 40 ? len : 40), text);
    a->opt = bkf_option_find(bkf_simulate_options, bkf_simulate_noptions, name);
    int integer = a->opt->type == BKF_OPT_COUNT || a->opt->type == BKF_OPT_SEED;
    char what[64];
    snprintf(what, sizeof what, "%s (%s)", key, name);
    int s = bkf_list_parse(eq + 1, 0, integer, BKF_SWEEP_POINTS_MAX, prefix, what, &a->values, err);
    if (s) return s;
    /* every value through the simulation's own table: its range, its words */
    for (size_t i = 0; i < a->values.count; i++) {
        double v = a->values.values[i];
        if (a->opt->type == BKF_OPT_SEED && (v < 0 || v > SEED_MAX))
            return bkf_error_set(err, BKF_EINPUT, "%s%s: seed %.17g is not in [0, 2^53]", prefix,
                                 key, v);
        bkf_simulate_spec probe = *base;
        bkf_error e;
        if (apply_number(a->opt, &probe, v, "", &e))
            return bkf_error_set(err, BKF_EINPUT, "%s%s: %s", prefix, key, e.message);
    }
    return BKF_OK;
}

static int make_plan(const bkf_sweep_spec *sp, const char *prefix, plan *p, bkf_error *err)
{
    memset(p, 0, sizeof *p);
    int s = BKF_OK;
    if (sp->x) s = parse_axis(sp->x, "x", prefix, &sp->sim, &p->x, err);
    if (!s && sp->y) {
        if (!sp->x)
            s = bkf_error_set(err, BKF_EINPUT, "%sy: give %sx first", prefix, prefix);
        else
            s = parse_axis(sp->y, "y", prefix, &sp->sim, &p->y, err);
        if (!s && p->y.opt == p->x.opt)
            s = bkf_error_set(err, BKF_EINPUT, "%sy: %s is already the x axis", prefix,
                              p->x.opt->name);
    }
    if (!s && sp->zip && (!p->y.opt || p->x.values.count != p->y.values.count))
        s = bkf_error_set(err, BKF_EINPUT,
                          "%szip: needs %sx and %sy of equal lengths (%zu and %zu values)", prefix,
                          prefix, prefix, p->x.values.count, p->y.values.count);
    if (!s && sp->seeds.count && (p->x.opt && p->x.opt->type == BKF_OPT_SEED))
        s = bkf_error_set(err, BKF_EINPUT, "%sseeds: the seed is already the x axis", prefix);
    if (!s && sp->seeds.count && (p->y.opt && p->y.opt->type == BKF_OPT_SEED))
        s = bkf_error_set(err, BKF_EINPUT, "%sseeds: the seed is already the y axis", prefix);
    if (s) {
        plan_free(p);
        return s;
    }
    p->nx = p->x.opt ? p->x.values.count : 1;
    p->ny = p->y.opt && !sp->zip ? p->y.values.count : 1;
    p->nseeds = sp->seeds.count ? sp->seeds.count : 1;
    /* the initial states: one text per state, split at ';' */
    p->ninits = 1;
    for (const char *c = sp->inits; c && *c; c++) p->ninits += *c == ';';
    if (p->ninits > BKF_SWEEP_INITS_MAX) {
        s = bkf_error_set(err, BKF_EINPUT, "%sinits: %zu states, more than %u", prefix, p->ninits,
                          BKF_SWEEP_INITS_MAX);
        plan_free(p);
        return s;
    }
    p->inits = calloc(p->ninits, sizeof *p->inits);
    if (!p->inits) {
        plan_free(p);
        return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    }
    const char *start = sp->inits;
    for (size_t k = 0; start && k < p->ninits; k++) {
        const char *end = strchr(start, ';');
        size_t n = end ? (size_t)(end - start) : strlen(start);
        p->inits[k] = strndup(start, n);
        if (!p->inits[k]) {
            plan_free(p);
            return bkf_error_set(err, BKF_ENOMEM, "out of memory");
        }
        start = end ? end + 1 : NULL;
    }
    double count = (double)p->nx * (double)p->ny * (double)p->nseeds * (double)p->ninits;
    if (count > BKF_SWEEP_POINTS_MAX) {
        plan_free(p);
        return bkf_error_set(err, BKF_EINPUT, "%sx: the grid has %.0f points, more than %u",
                             prefix, count, BKF_SWEEP_POINTS_MAX);
    }
    p->count = (size_t)count;
    return BKF_OK;
}

/* The simulation of point i.  Its texts (the initial state) belong to the
 * plan. */
static int point_spec(const bkf_sweep_spec *sp, const plan *p, size_t i, bkf_simulate_spec *sim,
                      const char *prefix, bkf_error *err)
{
    size_t seed = i % p->nseeds, rest = i / p->nseeds;
    size_t ix = rest % p->nx;
    rest /= p->nx;
    size_t iy = rest % p->ny, init = rest / p->ny;
    if (sp->zip) iy = ix;
    *sim = sp->sim;
    sim->cancel = sp->cancel;
    int s = BKF_OK;
    if (p->inits[init]) {
        const bkf_option *o = bkf_option_find(bkf_simulate_options, bkf_simulate_noptions, "init");
        char key[16];
        snprintf(key, sizeof key, "%sinits: ", prefix);
        s = bkf_option_apply(o, sim, p->inits[init], "", err);
        if (s) {
            char m[BKF_ERROR_LEN];
            snprintf(m, sizeof m, "%s", err ? err->message : "");
            return bkf_error_set(err, s, "%s%s", key, m);
        }
    }
    if (p->x.opt) s = apply_number(p->x.opt, sim, p->x.values.values[ix], prefix, err);
    if (!s && p->y.opt) s = apply_number(p->y.opt, sim, p->y.values.values[iy], prefix, err);
    if (!s && sp->seeds.count) sim->seed = (uint64_t)sp->seeds.values[seed];
    return s;
}

/* A point of the speeds product: the roots of bkfront speeds --stability
 * (its defaults: tol, method, stability tolerance). */
static bkf_fronts_spec speeds_spec(const bkf_simulate_spec *sim)
{
    bkf_fronts_spec f = bkf_fronts_spec_default();
    f.gamma = sim->model.gamma;
    f.c = sim->model.c;
    f.nu = sim->model.nu;
    f.S = sim->model.S;
    f.stability = 1;
    return f;
}

/* A point of the threshold product: bkfront floquet --threshold's spec. */
static bkf_oscillation_spec threshold_spec(const bkf_simulate_spec *sim)
{
    bkf_oscillation_spec o = bkf_oscillation_spec_default();
    o.threshold = 1;
    o.gamma = sim->model.gamma;
    o.c = sim->model.c;
    return o;
}

/* The point against its product's own checks (the messages name the keys
 * as that product does). */
static int check_product(int product, const bkf_simulate_spec *sim, const char *prefix,
                         bkf_error *err)
{
    if (product == BKF_SWEEP_SPEEDS) {
        if (sim->chain)
            return bkf_error_set(err, BKF_EINPUT, "%smodel: the speeds product is the continuum's",
                                 prefix);
        bkf_fronts_spec f = speeds_spec(sim);
        return bkf_fronts_check(&f, prefix, err);
    }
    if (product == BKF_SWEEP_THRESHOLD) {
        bkf_oscillation_spec o = threshold_spec(sim);
        int s = bkf_oscillation_check(&o, prefix, err);
        bkf_oscillation_spec_free(&o);
        return s;
    }
    return bkf_simulate_check(sim, prefix, err);
}

char *bkf_sweep_field_path(const bkf_sweep_spec *sp, size_t index)
{
    if (!sp || !sp->fields) return NULL;
    size_t len = strlen(sp->fields) + 48;
    char *path = malloc(len);
    if (path) snprintf(path, len, "%s/point_%zu.h5", sp->fields, index);
    return path;
}

/* Point i's simulation writing its field (sweep.h: fields); *path is the
 * file's name, owned by the caller (NULL without fields). */
static int with_field(const bkf_sweep_spec *sp, size_t i, bkf_simulate_spec *sim, char **path,
                      bkf_error *err)
{
    *path = NULL;
    if (!sp->fields) return BKF_OK;
    if (!(*path = bkf_sweep_field_path(sp, i)))
        return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    sim->spacetime = *path;
    sim->spacetime_format = 2; /* hdf5, whatever the directory's name */
    /* a stopped run leaves no partial field under the point's name */
    sim->discard_canceled = 1;
    return BKF_OK;
}

int bkf_sweep_check(const bkf_sweep_spec *sp, const char *prefix, bkf_error *err)
{
    if (!sp) return bkf_error_set(err, BKF_EINPUT, "no sweep spec given");
    if (!prefix) prefix = "";
    if (sp->sim.spacetime || sp->sim.snapshots)
        return bkf_error_set(err, BKF_EINPUT,
                             "%s%s: not in a sweep (a field per point: %sfields DIR)", prefix,
                             sp->sim.spacetime ? "spacetime" : "snapshots", prefix);
    size_t of = sp->of ? sp->of : 1;
    if (sp->task >= of)
        return bkf_error_set(err, BKF_EINPUT, "%stask: %zu is not in [0, %zu] (%sof %zu)", prefix,
                             sp->task, of - 1, prefix, of);
    if (!(sp->tmax_budget >= 0))
        return bkf_error_set(err, BKF_EINPUT, "%stmax-budget: not a number > 0", prefix);
    if (sp->product < BKF_SWEEP_REGIME || sp->product > BKF_SWEEP_THRESHOLD)
        return bkf_error_set(err, BKF_EINPUT, "%sproduct: not one of regime, speeds, threshold",
                             prefix);
    if (sp->product != BKF_SWEEP_REGIME && sp->tmax_budget > 0)
        return bkf_error_set(err, BKF_EINPUT, "%stmax-budget: only with %sproduct regime", prefix,
                             prefix);
    if (sp->fields) {
        struct stat st;
        if (sp->product != BKF_SWEEP_REGIME)
            return bkf_error_set(err, BKF_EINPUT, "%sfields: only with %sproduct regime", prefix,
                                 prefix);
        char shown[80];
        /* a folder of outputs is never reached through a link, as an
         * output file is not (io.h): one planted at its name would send
         * every point's field elsewhere */
        if (lstat(sp->fields, &st) == 0 && S_ISLNK(st.st_mode))
            return bkf_error_set(err, BKF_EINPUT,
                                 "%sfields: '%s' is a symbolic link: outputs never write through "
                                 "one (name the folder itself)",
                                 prefix, bkf_option_shown(sp->fields, shown, sizeof shown));
        if (stat(sp->fields, &st) != 0 || !S_ISDIR(st.st_mode) ||
            access(sp->fields, W_OK | X_OK) != 0)
            return bkf_error_set(err, BKF_EINPUT, "%sfields: '%s' is not a writable directory",
                                 prefix, bkf_option_shown(sp->fields, shown, sizeof shown));
    }
    plan p;
    int s = make_plan(sp, prefix, &p, err);
    if (s) return s;
    /* every point, before any run: a bad corner of the grid is bad input
     * now, not a failed row an hour later */
    for (size_t i = 0; !s && i < p.count; i++) {
        bkf_simulate_spec sim;
        s = point_spec(sp, &p, i, &sim, prefix, err);
        char *field = NULL;
        /* the field's size and its file, as simulate --spacetime judges them */
        if (!s) s = with_field(sp, i, &sim, &field, err);
        if (!s) s = check_product(sp->product, &sim, prefix, err);
        free(field);
        if (!s && sp->tmax_budget > 0 && sp->tmax_budget < sim.tmax) {
            char b[32], m[32];
            s = bkf_error_set(err, BKF_EINPUT, "%stmax-budget: %s is below tmax %s of point %zu",
                              prefix, bkf_format_number(sp->tmax_budget, b, sizeof b),
                              bkf_format_number(sim.tmax, m, sizeof m), i);
        }
    }
    plan_free(&p);
    return s;
}

size_t bkf_sweep_count(const bkf_sweep_spec *sp)
{
    plan p;
    if (!sp || make_plan(sp, "", &p, NULL)) return 0;
    size_t n = p.count;
    plan_free(&p);
    return n;
}

/* ------------------------------------------------------------ the rows */

static const char *const column_names[] = {
    "point", "init", "seed", "gamma", "c", "nu", "S", "tmax", "N", "regime",
    "fronts", "fronts_min", "fronts_max", "speed", "speed_err", "period", "period_err",
    "period_multiplicity", "global_period", "mean", "variance", "std_max", "psi_min", "psi_max",
    "t_end", "steps", "status"};
#define NCOLS (sizeof column_names / sizeof column_names[0])
/* Columns fixed by the point alone (point .. tmax): what --resume compares. */
#define NKEYCOLS 8
/* The other products' columns between the key columns and status. */
static const char *const speeds_columns[] = {"n_max", "allowed_count", "allowed", "stable_count",
                                             "stable", "unresolved"};
static const char *const threshold_columns[] = {
    "nu_threshold", "nu_threshold_err", "kind", "q_c", "stable_above", "nu_period_doubling",
    "nu_long_wave"};

/* The columns of a product between the key columns and status. */
static const char *const *product_columns(int product, size_t *count)
{
    if (product == BKF_SWEEP_SPEEDS) {
        *count = sizeof speeds_columns / sizeof *speeds_columns;
        return speeds_columns;
    }
    if (product == BKF_SWEEP_THRESHOLD) {
        *count = sizeof threshold_columns / sizeof *threshold_columns;
        return threshold_columns;
    }
    *count = NCOLS - NKEYCOLS - 1;
    return column_names + NKEYCOLS;
}

/* A growing text. */
typedef struct {
    char *s;
    size_t len, cap;
    int failed;
} text;

static void addf(text *t, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

static void addf(text *t, const char *fmt, ...)
{
    if (t->failed) return;
    for (;;) {
        va_list ap;
        va_start(ap, fmt);
        int n = vsnprintf(t->s ? t->s + t->len : NULL, t->s ? t->cap - t->len : 0, fmt, ap);
        va_end(ap);
        if (n < 0) {
            t->failed = 1;
            return;
        }
        if (t->s && t->len + (size_t)n < t->cap) {
            t->len += (size_t)n;
            return;
        }
        size_t cap = (t->cap ? t->cap : 256);
        while (cap <= t->len + (size_t)n) cap *= 2;
        char *g = realloc(t->s, cap);
        if (!g) {
            t->failed = 1;
            return;
        }
        t->s = g;
        t->cap = cap;
    }
}

static void add_number(text *t, double x)
{
    if (isnan(x))
        addf(t, "\tnan");
    else
        addf(t, "\t%.17g", x);
}

/* The columns fixed by the point (point .. tmax), without a newline. */
static void add_key(text *t, size_t i, const bkf_simulate_spec *sim)
{
    addf(t, "%zu\t%s\t%" PRIu64, i, sim->init ? sim->init : "uniform", sim->seed);
    add_number(t, sim->model.gamma);
    add_number(t, sim->model.c);
    add_number(t, sim->model.nu);
    add_number(t, sim->model.S);
    add_number(t, sim->tmax);
}

char *bkf_sweep_header(const bkf_sweep_spec *sp, bkf_error *err)
{
    plan p;
    if (make_plan(sp, "", &p, err)) return NULL;
    const bkf_simulate_spec *b = &sp->sim;
    /* simulate's stepper choices (lawson8 was shown as rk8pd: two sweeps
     * that differ only there had one definition) */
    static const char *const steppers[] = {"rk8pd", "rkck", "rkf45", "etdrk4", "lawson8", "auto"};
    char g[32], c[32], nu[32], S[32], tm[32], tol[32], fi[32], lv[32], N[32];
    /* the N the base point's run uses (the rows' N), not the key's 0 */
    if (b->model.N) snprintf(N, sizeof N, "%zu", b->model.N);
    else if (b->chain) snprintf(N, sizeof N, "S");
    else snprintf(N, sizeof N, "%d", BKF_SIMULATE_N_DEFAULT);
    text t = {0};
    static const char *const titles[] = {
        "regime of a direct simulation",
        "allowed and stable numbers of fronts (bkfront speeds --stability)",
        "Floquet boundaries of the global oscillation in nu (bkfront floquet --threshold, "
        "--diagram)"};
    addf(&t, "# bkfront %s sweep: %s at %zu points\n", BKF_VERSION_STRING, titles[sp->product],
         p.count);
    /* The definition: every key that changes a row, and nothing that does
     * not (threads, task, the command line), so that --resume and --merge
     * recognise the same sweep however it was run. */
    /* the product named only when it is not the regime: the tables of
     * sweeps from before the other products stay resumable */
    addf(&t, "# sweep: ");
    if (sp->product != BKF_SWEEP_REGIME)
        addf(&t, "product %s; ", bkf_sweep_product_names[sp->product]);
    addf(&t,
         "x %s; y %s; zip %d; seeds %zu; inits %s; base: gamma %s c %s nu %s S %s N %s "
         "model %s tmax %s tol %s init %s seed %" PRIu64 " stepper %s dealias %d filter %s level "
         "%s frames %zu; version %s\n",
         sp->x ? sp->x : "-", sp->y ? sp->y : "-", sp->zip, sp->seeds.count,
         sp->inits ? sp->inits : "-", bkf_format_number(b->model.gamma, g, sizeof g),
         bkf_format_number(b->model.c, c, sizeof c), bkf_format_number(b->model.nu, nu, sizeof nu),
         bkf_format_number(b->model.S, S, sizeof S), N, b->chain ? "chain" : "continuum",
         bkf_format_number(b->tmax, tm, sizeof tm), bkf_format_number(b->tol, tol, sizeof tol),
         b->init ? b->init : "uniform", b->seed, steppers[(size_t)b->stepper < sizeof steppers / sizeof *steppers ? b->stepper : 0], b->dealias,
         bkf_format_number(b->filter, fi, sizeof fi), bkf_format_number(b->level, lv, sizeof lv),
         b->frames, BKF_VERSION_STRING);
    if (sp->tmax_budget > 0) {
        char tb[32];
        addf(&t, "# settle: tmax-budget %s\n", bkf_format_number(sp->tmax_budget, tb, sizeof tb));
    }
    if (sp->seeds.count) {
        addf(&t, "# seeds:");
        for (size_t k = 0; k < sp->seeds.count; k++) addf(&t, " %.0f", sp->seeds.values[k]);
        addf(&t, "\n");
    }
    addf(&t, "# points: %zu\n", p.count);
    if (sp->product == BKF_SWEEP_REGIME)
        addf(&t, "# regime: continuous_slip, global_oscillation, period_doubled_pacemakers, "
                 "propagating_fronts, irregular, transient (bkfront simulate's, over the last half of the "
                 "run); none when the run failed (status)\n");
    else if (sp->product == BKF_SWEEP_SPEEDS)
        addf(&t, "# speeds: allowed, the n with a root of bkfront speeds; stable, the n with a "
                 "root whose ring spectrum is stable; unresolved, the n with a root whose verdict "
                 "is not resolved; lists as 1,3,4 (- when empty); init, seed and tmax do not "
                 "change a row\n");
    else
        addf(&t, "# threshold: the lowest stability boundary of the global oscillation in nu in "
                 "[-0.999, 0.999] (bkfront floquet --threshold: nu_threshold, its kind, q_c, "
                 "stable_above), and the lowest of each kind over the diagram (floquet --diagram; "
                 "nan: none); nu, S, init, seed and tmax do not change a row\n");
    size_t ncols;
    const char *const *cols = product_columns(sp->product, &ncols);
    for (size_t k = 0; k < NKEYCOLS; k++) addf(&t, "%s%s", k ? "\t" : "", column_names[k]);
    for (size_t k = 0; k < ncols; k++) addf(&t, "\t%s", cols[k]);
    if (sp->tmax_budget > 0) addf(&t, "\tsettled");
    addf(&t, "\tstatus\n");
    plan_free(&p);
    if (t.failed) {
        free(t.s);
        bkf_error_set(err, BKF_ENOMEM, "out of memory");
        return NULL;
    }
    return t.s;
}

/* A row's start, its key, for a point whose product ended with status s
 * (e its error); 1 and err when s is no numerical failure: such a failure
 * stops the sweep, where a numerical one is a row with that status. */
static int row_begin(text *t, size_t i, const bkf_simulate_spec *sim, int s, const bkf_error *e,
                     bkf_error *err)
{
    if (s && !bkf_status_is_numerical(s)) {
        bkf_error_set(err, s, "point %zu: %s", i, e->message);
        return 1;
    }
    add_key(t, i, sim);
    return 0;
}

/* The row's text ended by its status s, or NULL and err (out of memory). */
static char *row_done(text *t, int s, bkf_error *err)
{
    addf(t, "\t%s\n", s ? bkf_status_name(s) : "ok");
    if (t->failed) {
        free(t->s);
        bkf_error_set(err, BKF_ENOMEM, "out of memory");
        return NULL;
    }
    return t->s;
}

/* The n of the roots with flag 1 (all roots: flags NULL), each once, as
 * "1,3,4" ("-" for none); their count into *count. */
static void add_n_list(text *t, const bkf_speeds_table *tab, const int *flags, int want,
                       size_t *count)
{
    size_t k = 0, last = 0;
    for (size_t i = 0; i < tab->count; i++) {
        if (flags && flags[i] != want) continue;
        if (k && tab->roots[i].n == last) continue;
        addf(t, "%s%zu", k ? "," : "", tab->roots[i].n);
        last = tab->roots[i].n;
        k++;
    }
    if (!k) addf(t, "-");
    *count = k;
}

/* The speeds product's cells: the roots are ordered by n, so each list is
 * in increasing n. */
static char *speeds_row(const bkf_simulate_spec *sim, size_t i, bkf_error *err)
{
    bkf_fronts_spec f = speeds_spec(sim);
    bkf_speeds_table tab;
    int *stable = NULL;
    bkf_error e;
    int s = bkf_fronts_find(&f, &tab, &stable, &e);
    text t = {0};
    if (row_begin(&t, i, sim, s, &e, err)) return NULL;
    if (s) {
        addf(&t, "\tnan\tnan\t-\tnan\t-\t-");
    } else {
        /* the counts come before their lists: written after them */
        text lists[3] = {{0}, {0}, {0}};
        size_t n[3];
        add_n_list(&lists[0], &tab, NULL, 0, &n[0]);
        add_n_list(&lists[1], &tab, stable, 1, &n[1]);
        add_n_list(&lists[2], &tab, stable, -1, &n[2]);
        addf(&t, "\t%ld\t%zu\t%s\t%zu\t%s\t%s", tab.n_max, n[0], lists[0].s ? lists[0].s : "",
             n[1], lists[1].s ? lists[1].s : "", lists[2].s ? lists[2].s : "");
        for (int k = 0; k < 3; k++) {
            t.failed |= lists[k].failed;
            free(lists[k].s);
        }
        bkf_speeds_table_free(&tab);
        free(stable);
    }
    return row_done(&t, s, err);
}

/* The lowest boundary of each kind over the diagram. */
typedef struct {
    double pd, lw;
} lowest_boundaries;

static int lowest_of_kind(const bkf_floquet_interval *iv, void *data)
{
    lowest_boundaries *b = data;
    /* intervals come in increasing nu: the first of a kind is its lowest */
    if (iv->to.kind == BKF_BOUNDARY_PERIOD_DOUBLING && isnan(b->pd)) b->pd = iv->nu_to;
    if (iv->to.kind == BKF_BOUNDARY_LONG_WAVE && isnan(b->lw)) b->lw = iv->nu_to;
    return 0;
}

/* The threshold product's cells: the numbers of bkfront floquet --threshold
 * and --diagram at the point's gamma and c. */
static char *threshold_row(const bkf_simulate_spec *sim, size_t i, bkf_error *err)
{
    bkf_oscillation_spec o = threshold_spec(sim);
    bkf_floquet_options fo = bkf_oscillation_floquet_options(&o);
    bkf_floquet_threshold th;
    lowest_boundaries low = {NAN, NAN};
    bkf_error e;
    int s = bkf_floquet_threshold_find(o.gamma, o.c, o.search_lo, o.search_hi, &fo, &th, &e);
    if (!s) s = bkf_floquet_diagram(o.gamma, o.c, o.search_lo, o.search_hi, &fo, lowest_of_kind,
                                    &low, &e);
    bkf_oscillation_spec_free(&o);
    text t = {0};
    if (row_begin(&t, i, sim, s, &e, err)) return NULL;
    if (s) {
        addf(&t, "\tnan\tnan\tnone\tnan\tnan\tnan\tnan");
    } else {
        add_number(&t, th.nu);
        add_number(&t, th.nu_err);
        addf(&t, "\t%s", bkf_floquet_boundary_name(th.kind));
        add_number(&t, th.q);
        addf(&t, "\t%d", th.stable_above);
        add_number(&t, low.pd);
        add_number(&t, low.lw);
    }
    return row_done(&t, s, err);
}

static char *row_of(const bkf_sweep_spec *sp, const plan *p, size_t i, bkf_error *err)
{
    bkf_simulate_spec sim;
    if (point_spec(sp, p, i, &sim, "", err)) return NULL;
    if (sp->product == BKF_SWEEP_SPEEDS) return speeds_row(&sim, i, err);
    if (sp->product == BKF_SWEEP_THRESHOLD) return threshold_row(&sim, i, err);
    char *field;
    if (with_field(sp, i, &sim, &field, err)) return NULL;
    bkf_simulate_outcome o;
    bkf_error e;
    int s = bkf_simulate_outcome_of(&sim, &o, &e);
    /* Long transients: the run is made twice as long (from t = 0: a row
     * stays a function of its point) while the classification of the last
     * window differs from the one before it. */
    const char *settled = "budget";
    for (double tmax = sim.tmax; !s && sp->tmax_budget > 0 && 2 * tmax <= sp->tmax_budget;) {
        bkf_simulate_spec longer = sim;
        longer.tmax = tmax *= 2;
        bkf_simulate_outcome next;
        s = bkf_simulate_outcome_of(&longer, &next, &e);
        if (s) break;
        const bkf_measure_summary *a = &o.summary, *b = &next.summary;
        int counted = b->regime == BKF_REGIME_FRONTS ||
                      b->regime == BKF_REGIME_PACEMAKERS;
        /* two transients in a row are not a settled regime */
        int same = a->regime == b->regime && b->regime != BKF_REGIME_TRANSIENT &&
                   (!counted || a->fronts_end == b->fronts_end);
        o = next;
        if (same) {
            settled = "settled";
            break;
        }
    }
    free(field);
    text t = {0};
    if (row_begin(&t, i, &sim, s, &e, err)) return NULL;
    if (s) {
        addf(&t, "\t%zu\tnone", sim.model.N);
        for (size_t k = NKEYCOLS + 2; k < NCOLS - 1; k++) addf(&t, "\tnan");
        if (sp->tmax_budget > 0) addf(&t, "\tnone");
    } else {
        const bkf_measure_summary *m = &o.summary;
        addf(&t, "\t%zu\t%s\t%zu\t%zu\t%zu", o.N, bkf_regime_name(m->regime), m->fronts_end,
             m->fronts_min, m->fronts_max);
        add_number(&t, m->speed);
        add_number(&t, m->speed_err);
        add_number(&t, m->period);
        add_number(&t, m->period_err);
        addf(&t, "\t%zu", m->period_multiplicity);
        add_number(&t, o.period_ref > 0 ? o.period_ref : NAN);
        add_number(&t, m->mean);
        add_number(&t, m->variance);
        add_number(&t, m->std_max);
        add_number(&t, m->psi_min);
        add_number(&t, m->psi_max);
        add_number(&t, o.t_end);
        addf(&t, "\t%zu", o.steps);
        if (sp->tmax_budget > 0) addf(&t, "\t%s", settled);
    }
    return row_done(&t, s, err);
}

char *bkf_sweep_row(const bkf_sweep_spec *sp, size_t index, bkf_error *err)
{
    plan p;
    if (make_plan(sp, "", &p, err)) return NULL;
    char *r = NULL;
    if (index >= p.count)
        bkf_error_set(err, BKF_EINPUT, "point %zu: the sweep has %zu points", index, p.count);
    else
        r = row_of(sp, &p, index, err);
    plan_free(&p);
    return r;
}

int bkf_sweep_run(const bkf_sweep_spec *sp, const unsigned char *done, bkf_sweep_row_fn fn,
                  void *data, bkf_error *err)
{
    plan p;
    int s = make_plan(sp, "", &p, err);
    if (s) return s;
    size_t of = sp->of ? sp->of : 1, ntodo = 0, finished = 0;
    size_t *todo = malloc((p.count ? p.count : 1) * sizeof *todo);
    if (!todo) {
        plan_free(&p);
        return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    }
    for (size_t i = 0; i < p.count; i++)
        if (i % of == sp->task && !(done && done[i])) todo[ntodo++] = i;
    int status = BKF_OK;
    bkf_error first = {0};
    /* Dynamic: run times vary by orders of magnitude near thresholds; a
     * point is handed out when a thread is free, and its row depends on
     * the point alone. */
    int nthreads = bkf_product_threads(sp->threads);
    (void)nthreads;
#pragma omp parallel for schedule(dynamic, 1) num_threads(nthreads)
    for (size_t k = 0; k < ntodo; k++) {
        int stop;
#pragma omp atomic read
        stop = status;
        if (stop || (sp->cancel && *sp->cancel)) continue;
        bkf_error e = {0};
        char *row = row_of(sp, &p, todo[k], &e);
#pragma omp critical(bkf_sweep_rows)
        {
            int r = row ? BKF_OK : e.status;
            if (row && !status) r = fn(todo[k], row, data, &e);
            if (r && !status) {
                first = e;
#pragma omp atomic write
                status = r;
            }
            if (row && !r) {
                finished++;
                if (sp->progress) sp->progress(finished, ntodo, sp->data);
            }
        }
        free(row);
    }
    if (!status && sp->cancel && *sp->cancel)
        bkf_error_set(&first, status = BKF_ECANCELED, "canceled with %zu of %zu points done",
                      finished, ntodo);
    if (status) bkf_error_set(err, status, "%s", first.message);
    free(todo);
    plan_free(&p);
    return status;
}

/* The rows of bkf_sweep_write, by point. */
typedef struct {
    char **rows;
} collected;

static int collect(size_t index, const char *row, void *data, bkf_error *err)
{
    collected *c = data;
    if (!(c->rows[index] = strdup(row))) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    return BKF_OK;
}

int bkf_sweep_write(const bkf_sweep_spec *sp, FILE *out, bkf_error *err)
{
    if (!sp || !out) return bkf_error_set(err, BKF_EINPUT, "no sweep spec or stream given");
    int s = bkf_sweep_check(sp, "", err);
    if (s) return s;
    char *head = bkf_sweep_header(sp, err);
    if (!head) return err ? err->status : BKF_ENOMEM;
    size_t count = bkf_sweep_count(sp);
    collected c = {calloc(count ? count : 1, sizeof *c.rows)};
    if (!c.rows) s = bkf_error_set(err, BKF_ENOMEM, "out of memory");
    if (!s) s = bkf_sweep_run(sp, NULL, collect, &c, err);
    if (!s) {
        fputs(head, out);
        size_t of = sp->of ? sp->of : 1;
        for (size_t i = 0; i < count; i++)
            if (i % of == sp->task && c.rows[i]) fputs(c.rows[i], out);
        if (ferror(out)) s = bkf_error_set(err, BKF_EIO, "sweep: write error");
    }
    for (size_t i = 0; c.rows && i < count; i++) free(c.rows[i]);
    free(c.rows);
    free(head);
    return s;
}

/* ------------------------------------------------------------ the table */

struct bkf_sweep_table {
    char *path;
    bkf_io_lock *lock;  /* one writer of the table at a time */
    int fd;
    size_t count, rows;
    unsigned char *done;
};

/* A table read back: its head (everything up to and including the column
 * names) and its valid rows. */
typedef struct {
    char *data;
    size_t size;
    size_t head_len;
    size_t points;       /* from "# points: P" */
    size_t nrows;
    struct row {
        size_t index;
        const char *line; /* inside data, with its '\n' */
        size_t len;
    } *rows;
} table_text;

static void table_text_free(table_text *t)
{
    free(t->data);
    free(t->rows);
    memset(t, 0, sizeof *t);
}

static int read_all(const char *path, char **data, size_t *size, bkf_error *err)
{
    FILE *f = fopen(path, "rb");
    if (!f) return bkf_error_set(err, errno == ENOENT ? BKF_EINPUT : BKF_EIO, "%s: %s", path,
                                 strerror(errno));
    size_t cap = 1 << 16, len = 0;
    char *buf = malloc(cap);
    for (size_t got; buf && (got = fread(buf + len, 1, cap - len - 1, f)) > 0;) {
        len += got;
        if (cap - len < 2) {
            char *g = realloc(buf, cap *= 2);
            if (!g) {
                free(buf);
                buf = NULL;
            }
            buf = g;
        }
    }
    int bad = ferror(f);
    fclose(f);
    if (!buf) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    if (bad) {
        free(buf);
        return bkf_error_set(err, BKF_EIO, "%s: read error", path);
    }
    buf[len] = '\0';
    *data = buf;
    *size = len;
    return BKF_OK;
}

/* Reads `path`: the head ends at the first line not starting with '#'
 * (the column names); a row is kept when it is a whole line with as many
 * fields as there are names and a point index below the head's count, seen first, and (with
 * `key`) its key columns are those of its point. */
static int table_read(const char *path, table_text *t, const bkf_sweep_spec *key_spec,
                      const plan *key_plan, int strict, bkf_error *err)
{
    memset(t, 0, sizeof *t);
    int s = read_all(path, &t->data, &t->size, err);
    if (s) return s;
    char *p = t->data, *end = t->data + t->size;
    while (p < end && *p == '#') {
        if (strncmp(p, "# points: ", 10) == 0) t->points = strtoul(p + 10, NULL, 10);
        char *nl = memchr(p, '\n', (size_t)(end - p));
        p = nl ? nl + 1 : end;
    }
    char *nl = p < end ? memchr(p, '\n', (size_t)(end - p)) : NULL;
    if (!nl || !t->points) {
        table_text_free(t);
        return bkf_error_set(err, BKF_EINPUT, "%s: not a table of bkfront sweep", path);
    }
    t->head_len = (size_t)(nl + 1 - t->data);
    size_t names_tabs = 0;
    for (char *q = p; q < nl; q++) names_tabs += *q == '\t';
    /* at[i]: 1 + the place in rows of point i's row, 0 while none */
    size_t *at = calloc(t->points, sizeof *at);
    t->rows = malloc(t->points * sizeof *t->rows);
    if (!at || !t->rows) {
        free(at);
        table_text_free(t);
        return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    }
    for (p = nl + 1; p < end;) {
        nl = memchr(p, '\n', (size_t)(end - p));
        if (!nl) break; /* a partial last line: a write that never finished */
        size_t len = (size_t)(nl + 1 - p), tabs = 0;
        for (char *q = p; q < nl; q++) tabs += *q == '\t';
        char *after;
        errno = 0;
        unsigned long long idx = strtoull(p, &after, 10);
        int whole = tabs == names_tabs && after != p && *after == '\t' && !errno &&
                    idx < t->points;
        int ok = whole && !at[idx];
        /* strict (merge): a point's second row is one row with the first
         * when the bytes are the same, a conflict otherwise */
        const struct row *first = whole && at[idx] ? &t->rows[at[idx] - 1] : NULL;
        if (strict && first && (first->len != len || memcmp(first->line, p, len) != 0)) {
            free(at);
            table_text_free(t);
            return bkf_error_set(err, BKF_EINPUT,
                                 "merge: point %llu has two different rows in %s (a point's row "
                                 "is the same however the sweep is split: one of them is "
                                 "damaged or of another build)",
                                 idx, path);
        }
        if (ok && key_spec) {
            bkf_simulate_spec sim;
            text k = {0};
            ok = !point_spec(key_spec, key_plan, (size_t)idx, &sim, "", NULL);
            if (ok) add_key(&k, (size_t)idx, &sim);
            ok = ok && !k.failed && len > k.len && strncmp(p, k.s, k.len) == 0 && p[k.len] == '\t';
            free(k.s);
        }
        if (ok) {
            t->rows[t->nrows++] = (struct row){(size_t)idx, p, len};
            at[idx] = t->nrows;
        }
        p = nl + 1;
    }
    free(at);
    return BKF_OK;
}

static int by_index(const void *a, const void *b)
{
    size_t x = ((const struct row *)a)->index, y = ((const struct row *)b)->index;
    return (x > y) - (x < y);
}

/* head and rows (sorted or as they are) to `path`, atomically. */
static int table_write(const char *path, const char *head, size_t head_len, struct row *rows,
                       size_t nrows, int sort, bkf_error *err)
{
    if (sort) qsort(rows, nrows, sizeof *rows, by_index);
    bkf_io_atomic *f = bkf_io_atomic_open(path, err);
    if (!f) return err ? err->status : BKF_EIO;
    FILE *out = bkf_io_atomic_stream(f);
    fwrite(head, 1, head_len, out);
    for (size_t i = 0; i < nrows; i++) fwrite(rows[i].line, 1, rows[i].len, out);
    return bkf_io_atomic_commit(f, err);
}

int bkf_sweep_table_open(const char *path, const bkf_sweep_spec *sp, int resume,
                         bkf_sweep_table **table, bkf_error *err)
{
    *table = NULL;
    if (!path) return bkf_error_set(err, BKF_EINPUT, "no table path given");
    char *head = bkf_sweep_header(sp, err);
    if (!head) return err ? err->status : BKF_ENOMEM;
    plan p;
    int s = make_plan(sp, "", &p, err);
    bkf_sweep_table *t = s ? NULL : calloc(1, sizeof *t);
    if (!s && t) {
        t->count = p.count;
        t->fd = -1;
        t->path = strdup(path);
        t->done = calloc(p.count ? p.count : 1, 1);
    }
    if (!s && (!t || !t->path || !t->done)) s = bkf_error_set(err, BKF_ENOMEM, "out of memory");
    /* before reading: a second writer (two sweeps, or one with --resume)
     * would read rows the first is appending and then replace the file
     * under it, losing rows */
    if (!s) t->lock = bkf_io_lock_take(path, err);
    if (!s && !t->lock) s = err ? err->status : BKF_EINPUT;
    struct stat lst;
    if (!s && lstat(path, &lst) == 0 && S_ISLNK(lst.st_mode))
        s = bkf_error_set(err, BKF_EINPUT,
                          "%s is a symbolic link: outputs never write through one (name the "
                          "file itself)", path);
    table_text old = {0};
    int have_old = 0;
    if (!s && resume) {
        bkf_error e;
        int r = table_read(path, &old, sp, &p, 0, &e);
        if (!r) {
            have_old = 1;
            if (old.head_len != strlen(head) || memcmp(old.data, head, old.head_len) != 0)
                s = bkf_error_set(err, BKF_EINPUT,
                                  "--resume: %s is the table of another sweep (its definition "
                                  "line differs)",
                                  path);
        } else if (access(path, F_OK) == 0) {
            s = bkf_error_set(err, BKF_EINPUT, "--resume: %s", e.message);
        }
    }
    if (!s) {
        /* a new table, or the old one without what cannot be trusted */
        s = table_write(path, head, strlen(head), old.rows, have_old ? old.nrows : 0, 0, err);
        for (size_t i = 0; !s && have_old && i < old.nrows; i++) t->done[old.rows[i].index] = 1;
        if (!s && have_old) t->rows = old.nrows;
    }
    if (!s) {
        /* the file just renamed into place; a link put there since is
         * not followed */
        t->fd = open(path, O_WRONLY | O_APPEND | O_NOFOLLOW | O_CLOEXEC);
        if (t->fd < 0) s = bkf_error_set(err, BKF_EIO, "%s: %s", path, strerror(errno));
    }
    table_text_free(&old);
    plan_free(&p);
    free(head);
    if (s) {
        if (t) bkf_sweep_table_close(t, 0, NULL);
        return s;
    }
    *table = t;
    return BKF_OK;
}

const unsigned char *bkf_sweep_table_done(const bkf_sweep_table *t) { return t ? t->done : NULL; }

size_t bkf_sweep_table_rows(const bkf_sweep_table *t) { return t ? t->rows : 0; }

int bkf_sweep_table_append(bkf_sweep_table *t, size_t index, const char *row, bkf_error *err)
{
    if (!t || index >= t->count || !row)
        return bkf_error_set(err, BKF_EINPUT, "sweep table: no such point %zu", index);
    /* one write of the whole line (O_APPEND: never interleaved), then to
     * the disk: a finished row survives a crash or kill -9 that follows */
    size_t len = strlen(row), off = 0;
    while (off < len) {
        ssize_t n = write(t->fd, row + off, len - off);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) return bkf_error_set(err, BKF_EIO, "%s: %s", t->path, strerror(errno));
        off += (size_t)n;
    }
    if (fsync(t->fd) != 0 && errno != EINVAL)
        return bkf_error_set(err, BKF_EIO, "%s: %s", t->path, strerror(errno));
    t->done[index] = 1;
    t->rows++;
    return BKF_OK;
}

int bkf_sweep_table_close(bkf_sweep_table *t, int sort, bkf_error *err)
{
    if (!t) return BKF_OK;
    int s = BKF_OK;
    if (t->fd >= 0 && close(t->fd) != 0)
        s = bkf_error_set(err, BKF_EIO, "%s: %s", t->path, strerror(errno));
    if (!s && sort) {
        table_text tt;
        s = table_read(t->path, &tt, NULL, NULL, 0, err);
        if (!s) s = table_write(t->path, tt.data, tt.head_len, tt.rows, tt.nrows, 1, err);
        table_text_free(&tt);
    }
    bkf_io_lock_release(t->lock);
    free(t->path);
    free(t->done);
    free(t);
    return s;
}

int bkf_sweep_merge(const char *const *inputs, size_t n, const char *out, size_t *missing,
                    bkf_error *err)
{
    if (!n || !inputs || !out) return bkf_error_set(err, BKF_EINPUT, "merge: no tables given");
    table_text *t = calloc(n, sizeof *t);
    if (!t) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    int s = BKF_OK;
    size_t total = 0;
    for (size_t k = 0; !s && k < n; k++) {
        s = table_read(inputs[k], &t[k], NULL, NULL, 1, err);
        if (!s && k && (t[k].head_len != t[0].head_len ||
                        memcmp(t[k].data, t[0].data, t[0].head_len) != 0))
            s = bkf_error_set(err, BKF_EINPUT,
                              "merge: %s is the table of another sweep than %s (definitions "
                              "differ)",
                              inputs[k], inputs[0]);
        if (!s) total += t[k].nrows;
    }
    struct row *all = s ? NULL : malloc((total ? total : 1) * sizeof *all);
    if (!s && !all) s = bkf_error_set(err, BKF_ENOMEM, "out of memory");
    size_t m = 0;
    unsigned char *seen = s ? NULL : calloc(t[0].points, 1);
    if (!s && !seen) s = bkf_error_set(err, BKF_ENOMEM, "out of memory");
    /* a point computed twice (a task run again) is one row: rows are a
     * function of the point, bit for bit, so two copies that differ mean
     * that a table is damaged or not of this sweep: refused, naming the
     * point, rather than keeping one of them at random */
    /* for each point seen: its row's place in `all` and the table it came from */
    size_t *at = s ? NULL : malloc(2 * t[0].points * sizeof *at), *from = at ? at + t[0].points : NULL;
    if (!s && !at) s = bkf_error_set(err, BKF_ENOMEM, "out of memory");
    for (size_t k = 0; !s && k < n; k++)
        for (size_t i = 0; !s && i < t[k].nrows; i++) {
            const struct row *r = &t[k].rows[i];
            if (!seen[r->index]) {
                seen[r->index] = 1;
                from[r->index] = k;
                at[r->index] = m;
                all[m++] = *r;
                continue;
            }
            const struct row *first = &all[at[r->index]];
            if (first->len != r->len || memcmp(first->line, r->line, r->len) != 0)
                s = bkf_error_set(err, BKF_EINPUT,
                                  "merge: point %zu has two different rows, in %s and in %s (a "
                                  "point's row is the same however the sweep is split: one of "
                                  "them is damaged or of another build)",
                                  r->index, inputs[from[r->index]], inputs[k]);
        }
    free(at);
    bkf_io_lock *lock = NULL;
    if (!s && !(lock = bkf_io_lock_take(out, err))) s = err ? err->status : BKF_EINPUT;
    if (!s) s = table_write(out, t[0].data, t[0].head_len, all, m, 1, err);
    bkf_io_lock_release(lock);
    if (!s && missing) *missing = t[0].points - m;
    free(seen);
    free(all);
    for (size_t k = 0; k < n; k++) table_text_free(&t[k]);
    free(t);
    return s;
}

/* The columns that hold text (the others hold numbers). */
static int text_column(const char *name, size_t len)
{
    static const char *const texts[] = {"init",   "regime",     "settled", "status", "allowed",
                                        "stable", "unresolved", "kind"};
    for (size_t k = 0; k < sizeof texts / sizeof *texts; k++)
        if (strlen(texts[k]) == len && strncmp(texts[k], name, len) == 0) return 1;
    return 0;
}

/* The fields of a tab-separated line (without its newline) into copies in
 * `fields` (an array of n pointers into one malloc'ed block, *block). */
static int split_line(const char *line, size_t len, size_t n, char **fields, char **block)
{
    char *b = malloc(len + 1);
    if (!b) return BKF_ENOMEM;
    memcpy(b, line, len);
    b[len] = '\0';
    size_t k = 0;
    for (char *p = b; k < n; k++) {
        fields[k] = p;
        char *tab = strchr(p, '\t');
        if (!tab) {
            k++;
            break;
        }
        *tab = '\0';
        p = tab + 1;
    }
    *block = b;
    return k == n ? BKF_OK : BKF_EINPUT;
}

int bkf_sweep_table_json(const char *path, bkf_error *err)
{
    if (!path) return bkf_error_set(err, BKF_EINPUT, "no table path given");
    table_text t;
    int s = table_read(path, &t, NULL, NULL, 0, err);
    if (s) return s;
    /* the head: comment lines, then the column names */
    const char *names = t.data;
    for (const char *nl; *names == '#' && (nl = strchr(names, '\n'));) names = nl + 1;
    size_t names_len = (size_t)(t.data + t.head_len - 1 - names), ncols = 1;
    for (size_t i = 0; i < names_len; i++) ncols += names[i] == '\t';
    bkf_io_column *cols = calloc(ncols, sizeof *cols);
    char **fields = calloc(ncols, sizeof *fields);
    bkf_io_value *v = calloc(ncols, sizeof *v);
    char *name_block = NULL;
    if (!cols || !fields || !v) s = bkf_error_set(err, BKF_ENOMEM, "out of memory");
    if (!s && split_line(names, names_len, ncols, fields, &name_block))
        s = bkf_error_set(err, BKF_ENOMEM, "out of memory");
    for (size_t k = 0; !s && k < ncols; k++)
        cols[k] = (bkf_io_column){fields[k], text_column(fields[k], strlen(fields[k]))
                                                 ? BKF_IO_TEXT : BKF_IO_NUMBER};
    bkf_io_atomic *f = s ? NULL : bkf_io_atomic_open(path, err);
    if (!s && !f) s = err ? err->status : BKF_EIO;
    bkf_io_table *out = s ? NULL : bkf_io_table_alloc(bkf_io_atomic_stream(f), BKF_IO_JSON, cols,
                                                      ncols, err);
    if (!s && !out) s = err ? err->status : BKF_ENOMEM;
    for (const char *c = t.data; !s && c < names;) {
        const char *nl = strchr(c, '\n'); /* the head's lines are whole */
        const char *text = c + (nl - c >= 2 && c[1] == ' ' ? 2 : 1); /* after "# " */
        size_t len = (size_t)(nl - text);
        char line[1024];
        if (len >= sizeof line)
            s = bkf_error_set(err, BKF_EINPUT, "%s: a comment line longer than %zu bytes", path,
                              sizeof line - 1);
        if (!s) {
            memcpy(line, text, len);
            line[len] = '\0';
            s = bkf_io_table_comment(out, line, err);
        }
        c = nl + 1;
    }
    for (size_t i = 0; !s && i < t.nrows; i++) {
        char *block = NULL;
        /* the row without its newline */
        if (split_line(t.rows[i].line, t.rows[i].len - 1, ncols, fields, &block))
            s = block ? bkf_error_set(err, BKF_EINPUT, "%s: a row without its %zu fields", path,
                                      ncols)
                      : bkf_error_set(err, BKF_ENOMEM, "out of memory");
        for (size_t k = 0; !s && k < ncols; k++) {
            char *end;
            v[k] = (bkf_io_value){0};
            if (cols[k].kind == BKF_IO_TEXT) v[k].text = fields[k];
            else if ((v[k].number = strtod(fields[k], &end)), end == fields[k] || *end)
                s = bkf_error_set(err, BKF_EINPUT, "%s: column %s holds '%s', not a number",
                                  path, cols[k].name, fields[k]);
        }
        if (!s) s = bkf_io_table_row(out, v, err);
        free(block);
    }
    s = bkf_product_table_file_close(out, f, s, err);
    free(name_block);
    free(cols);
    free(fields);
    free(v);
    table_text_free(&t);
    return s;
}

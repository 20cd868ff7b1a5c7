/* The check of the predicted front speeds against seeded simulations: one
 * root at a time on the uniform spectral grid (bkf_pde + bkf_measure) or the
 * adapted comoving grid (bkf_comoving), both judged by bkf_check_judge. */
#include "bkfront/check.h"

#include "check_internal.h"
#include "product_internal.h"

#include <fftw3.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* One root whole: its spectrum, its run, the warning of a conflict; its
 * warnings into c->notes. */
static int check_one(const check_ctx *c, const bkf_speeds_table *tab, size_t i,
                     bkf_check_row *row, bkf_error *err)
{
    size_t root = 1;
    for (size_t k = i; k > 0 && tab->roots[k - 1].n == tab->roots[i].n; k--) root++;
    check_row_init(row, tab->roots[i].n, root, &tab->roots[i]);
    if (tab->roots[i].status != BKF_OK) {
        /* no speed to seed and compare: neither run nor spectrum */
        row->reason = tab->roots[i].status;
        check_warn(c, "n = %zu, root %zu: unresolved: its speed is refused: %s", row->n,
                   row->root, tab->roots[i].refusal);
        return BKF_OK;
    }
    check_spectrum(c, &tab->roots[i], row);
    int s = check_root(c, &tab->roots[i], row, err);
    if (!s && row->verdict == BKF_CHECK_CONFLICTS) {
        char a[32], b[32], d[32], f[32];
        check_warn(c,
                   "n = %zu, root %zu: the simulation's perturbation %s at %s +- %s per unit "
                   "time, the spectrum says %s (sigma_max %s +- %s)",
                   row->n, row->root, bkf_check_growth_name(row->growth.verdict),
                   bkf_format_number(row->growth.rate, a, sizeof a),
                   bkf_format_number(row->growth.rate_err, b, sizeof b),
                   row->spectral == BKF_TRAINSPEC_STABLE ? "stable" : "unstable",
                   bkf_format_number(row->sigma_max, d, sizeof d),
                   bkf_format_number(row->sigma_max_err, f, sizeof f));
    }
    if (!s && row->growth.bends && row->growth.verdict == BKF_CHECK_GROWTH_UNDECIDED) {
        char a[32], b[32];
        check_warn(c,
                   "n = %zu, root %zu: growth undecided: the perturbation's envelope still "
                   "bends over t in [%g, %g] (its slope moved by %s between the fit's halves): "
                   "not yet one exponential (a start-up transient, or a slower mode fading), "
                   "so growth is the later half's slope, %s, its error the bend; a longer "
                   "run (--runs full, --tmax) would measure the rate",
                   row->n, row->root, row->growth.from, row->growth.to,
                   bkf_format_number(row->growth.bend, a, sizeof a),
                   bkf_format_number(row->growth.rate, b, sizeof b));
    }
    if (!s) check_explain_undecided(c, row);
    return s;
}

/* A root's outcome, kept until every root before it is delivered. */
typedef struct {
    bkf_check_row row;
    check_notes notes;
    bkf_error err;
    int status, done;
} check_slot;

int bkf_check_run(const bkf_model_params *model, const bkf_check_options *o,
                  const bkf_check_hooks *hooks, bkf_error *err)
{
    int s = bkf_check_validate(model, o, err);
    if (s) return s;
    if (model->kind == BKF_MODEL_CHAIN) return check_chain_run(model, o, hooks, err);
    bkf_model_params sp = {model->gamma, model->c, model->nu, model->S, 0, BKF_MODEL_CONTINUUM};
    bkf_speeds_options so = bkf_speeds_options_default();
    so.tol = check_speeds_tol(o);
    if (o->n) so.n_from = so.n_to = o->n;
    bkf_speeds_table tab;
    memset(&tab, 0, sizeof tab);
    bkf_error e;
    if ((s = bkf_speeds_find(&sp, &so, &tab, &e))) {
        bkf_speeds_table_free(&tab);
        return bkf_error_set(err, s, "speeds: %s", e.message);
    }
    check_ctx c = {model, o, hooks, check_uniform_tol(o), check_mapped_tol(o), 0, 0, tab.count,
                   NULL, NULL};
    c.level = bkf_measure_front_level(model, NULL);
    bkf_check_info info = {tab.count, tab.k, tab.n_max, tab.note, c.tol, c.mapped_tol,
                           o->grid == BKF_CHECK_GRID_AUTO && o->N_max > BKF_CHECK_AUTO_UNIFORM_MAX
                               ? (size_t)BKF_CHECK_AUTO_UNIFORM_MAX
                               : o->N_max};
    int stop = hooks && hooks->begin ? hooks->begin(&info, hooks->data) : 0;
    const volatile sig_atomic_t *cancel = check_cancel(&c);
    size_t R = tab.count;
    check_slot *slot = calloc(R ? R : 1, sizeof *slot);
    double *fraction = calloc(R ? R : 1, sizeof *fraction);
    check_shared shared = {fraction, R};
    if (!slot || !fraction) {
        free(slot);
        free(fraction);
        bkf_speeds_table_free(&tab);
        return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    }
    /* The roots are independent: each runs in its own thread, and its row,
     * warnings and any failure are delivered in root order once the roots
     * before it are, so that the hooks see what a serial run shows (and,
     * as there, nothing after a failure or a stop). */
    size_t next = 0;  /* the first root not yet delivered */
    int halt = stop;  /* a stop or a failure: no root starts */
    int visited = 0;  /* the row visitor stopped the check */
    int threads = bkf_product_threads(o->threads);
    (void)threads;
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
    for (size_t i = 0; i < R; i++) {
        int skip;
#pragma omp atomic read
        skip = halt;
        if (skip) continue;
        check_slot *k = &slot[i];
        check_ctx ci = c;
        ci.root_index = i;
        ci.shared = &shared;
        ci.notes = &k->notes;
        if (cancel && *cancel)
            k->status = bkf_error_set(&k->err, BKF_ECANCELED, "canceled after %zu of %zu roots",
                                      i, R);
        else
            k->status = check_one(&ci, &tab, i, &k->row, &k->err);
        if (!k->status && k->notes.oom)
            k->status = bkf_error_set(&k->err, BKF_ENOMEM, "out of memory");
#pragma omp critical(bkf_check_hooks)
        {
            k->done = 1;
            fraction[i] = 1;
            int h = halt;
            for (; !h && next < R && slot[next].done; next++) {
                check_slot *d = &slot[next];
                for (size_t at = 0; hooks && hooks->warning && at < d->notes.used;
                     at += strlen(d->notes.text + at) + 1)
                    hooks->warning(d->notes.text + at, hooks->data);
                if (d->status) {
                    s = d->status;
                    *err = d->err;
                    h = 1;
                    break;
                }
                if (hooks && hooks->row && hooks->row(&d->row, hooks->data)) h = visited = 1;
            }
#pragma omp atomic write
            halt = h;
        }
    }
    /* a cancel that left roots unstarted past the last delivered one */
    if (!s && !stop && !visited && next < R && cancel && *cancel)
        s = bkf_error_set(err, BKF_ECANCELED, "canceled after %zu of %zu roots", next, R);
    for (size_t i = 0; i < R; i++) free(slot[i].notes.text);
    free(slot);
    free(fraction);
    bkf_speeds_table_free(&tab);
    return s;
}

/* ------------------------------------------------------------ the product */

/* The choices are read and written as int: the enums must be int-sized. */
_Static_assert(sizeof(bkf_pde_stepper) == sizeof(int), "bkf_pde_stepper is not int-sized");
_Static_assert(sizeof(bkf_check_frame) == sizeof(int), "bkf_check_frame is not int-sized");
_Static_assert(sizeof(bkf_check_grid) == sizeof(int), "bkf_check_grid is not int-sized");

/* Indexed by bkf_check_frame and bkf_check_grid (the steppers'
 * names: bkf_pde_stepper_names). */
static const char *const frame_names[] = {"moving", "lab", NULL};
static const char *const grid_names[] = {"auto", "uniform", "mapped", NULL};
static const char *const model_names[] = {"continuum", "chain", NULL};
static const char *const runs_names[] = {"auto", "full", NULL};
_Static_assert(sizeof(bkf_check_runs) == sizeof(int), "bkf_check_runs is not int-sized");
_Static_assert(sizeof(bkf_model_kind) == sizeof(int), "bkf_model_kind is not int-sized");

/* The seed is an unsigned long: up to 19 digits always fit. */
static int set_seed(void *spec, const char *text, bkf_error *err)
{
    char shown[72];
    if (!*text || strspn(text, "0123456789") != strlen(text) || strlen(text) > 19)
        return bkf_error_set(err, BKF_EINPUT, "'%s' is not an integer in [0, 1e19)",
                             bkf_option_shown(text, shown, sizeof shown));
    unsigned long long v = strtoull(text, NULL, 10);
    if (v > ULONG_MAX)
        return bkf_error_set(err, BKF_EINPUT, "'%s' is out of range", text);
    ((bkf_check_spec *)spec)->options.seed = (unsigned long)v;
    return BKF_OK;
}

#define MODEL(f) (offsetof(bkf_check_spec, model) + offsetof(bkf_model_params, f))
#define OPT(f) (offsetof(bkf_check_spec, options) + offsetof(bkf_check_options, f))
#define BOUNDED (BKF_OPT_MIN | BKF_OPT_MAX)

const bkf_option bkf_check_keys[] = {
    {.name = "gamma", .type = BKF_OPT_DOUBLE, .offset = MODEL(gamma), .flags = BOUNDED,
     .min = BKF_CYCLE_MU_MIN, .max = BKF_CYCLE_MU_MAX, .form = "G", .shown_default = "2",
     .help = "friction strength, in [1e-06, 1e+06]"},
    {.name = "c", .type = BKF_OPT_DOUBLE, .offset = MODEL(c), .flags = BKF_OPT_MIN | BKF_OPT_MAX,
     .min = 0, .max = BKF_MODEL_C_MAX, .form = "C", .shown_default = "0.3",
     .help = "sound speed, in [0, 1e6]"},
    {.name = "nu", .type = BKF_OPT_DOUBLE, .offset = MODEL(nu),
     .flags = BOUNDED | BKF_OPT_MIN_OPEN | BKF_OPT_MAX_OPEN, .min = -1, .max = 1, .form = "V",
     .shown_default = "-0.96", .help = "pulling rate, in (-1, 1): no fronts beyond"},
    {.name = "S", .type = BKF_OPT_DOUBLE, .offset = MODEL(S),
     .flags = BKF_OPT_MIN | BKF_OPT_MIN_OPEN, .min = 0, .form = "S", .shown_default = "20",
     .help = "system size, > 0"},
    {.name = "model", .type = BKF_OPT_CHOICE, .offset = MODEL(kind), .choices = model_names,
     .form = "continuum|chain", .shown_default = "continuum",
     .help = "chain: the chain of --N blocks (spacing h = S/N), its own\n"
             "rotating waves (bkfront speeds --model chain) seeded and\n"
             "simulated on the blocks; columns as below (docs/cli/check.md)"},
    {.name = "n", .type = BKF_OPT_COUNT, .offset = OPT(n), .flags = BOUNDED, .min = 1,
     .max = BKF_CHECK_FRONTS_MAX, .form = "K",
     .help = "check n = K only; default every n with a root"},
    {.name = "N", .type = BKF_OPT_COUNT, .offset = OPT(N), .flags = BOUNDED,
     .min = BKF_PDE_N_MIN, .max = BKF_PDE_N_MAX, .form = "N", .shown_default = "512",
     .help = "smallest grid, even; each root runs on the smallest\n"
             "N = N 2^k that resolves its wave (Fourier coefficients\n"
             "above N/3 below --resolution of the largest); with\n"
             "--model chain: blocks, in [2, 400], default S (whole)"},
    {.name = "N-max", .type = BKF_OPT_COUNT, .offset = OPT(N_max), .flags = BOUNDED,
     .min = BKF_PDE_N_MIN, .max = BKF_PDE_N_MAX, .form = "M", .shown_default = "65536",
     .help = "largest grid, >= --N; roots needing more are reported\n"
             "unresolved and not simulated"},
    {.name = "tmax", .type = BKF_OPT_DOUBLE, .offset = OPT(tmax),
     .flags = BOUNDED | BKF_OPT_MIN_OPEN, .min = 0, .max = BKF_CHECK_TMAX_MAX, .form = "T",
     .shown_default = "125",
     .help = "length of each run (with --runs auto the longest),\nin (0, 1e+06]"},
    {.name = "runs", .type = BKF_OPT_CHOICE, .offset = OPT(runs), .choices = runs_names,
     .form = "auto|full", .shown_default = "auto",
     .help = "auto: --tmax is the longest run; a run stops once the\n"
             "front is lost, or once its row is settled (the spectrum\n"
             "decided and the speed measured; docs/cli/check.md);\n"
             "full: every run to --tmax"},
    {.name = "threads", .type = BKF_OPT_COUNT, .offset = OPT(threads), .flags = BOUNDED,
     .min = 1, .max = BKF_CHECK_THREADS_MAX, .form = "K", .shown_default = "every core",
     .help = "roots checked at once, in [1, 4096]; the table is the\n"
             "same with any number"},
    {.name = "tol", .type = BKF_OPT_DOUBLE, .offset = OPT(tol), .flags = BOUNDED,
     .min = BKF_PDE_TOL_MIN, .max = BKF_PDE_TOL_MAX, .form = "E",
     .help = "local error tolerance, in [1e-13, 0.01]; default 1e-07\n"
             "with etdrk4, 1e-9 with the Runge-Kutta steppers, 1e-08\n"
             "on the adapted grid"},
    {.name = "filter", .type = BKF_OPT_DOUBLE, .offset = OPT(filter), .flags = BOUNDED,
     .min = 0, .max = BKF_CHECK_FILTER_MAX, .form = "F", .shown_default = "4",
     .help = "spectral filter, as in bkfront simulate,\nin [0, 1000]"},
    {.name = "stepper", .type = BKF_OPT_CHOICE, .offset = OPT(stepper), .choices = bkf_pde_stepper_names,
     .form = "S", .shown_default = "etdrk4",
     .help = "etdrk4 (exponential, the wave part of every mode exact,\n"
             "steps set by the physics), lawson8 (the same with rk8pd's\n"
             "order 8), or rk8pd, rkck, rkf45 (explicit, steps capped by\n"
             "the fastest mode ~ 1/N)"},
    {.name = "rel-tol", .type = BKF_OPT_DOUBLE, .offset = OPT(rel_tol),
     .flags = BOUNDED | BKF_OPT_MIN_OPEN | BKF_OPT_MAX_OPEN, .min = 0, .max = 1, .form = "R",
     .shown_default = "1e-06",
     .help = "agreement asked of a stable front,\n"
             "|v_meas - v_pred| / v_pred, in (0, 1)"},
    {.name = "perturb", .type = BKF_OPT_DOUBLE, .offset = OPT(perturb), .flags = BOUNDED,
     .min = 0, .max = BKF_CHECK_PERTURB_MAX, .form = "A", .shown_default = "1e-06",
     .help = "rms of the band-limited noise added to the seeded wave,\n"
             "in [0, 0.1]"},
    {.name = "seed", .type = BKF_OPT_CUSTOM, .set = set_seed, .form = "K",
     .shown_default = "1", .help = "seed of that noise, an integer in [0, 1e19)"},
    {.name = "frame", .type = BKF_OPT_CHOICE, .offset = OPT(frame), .choices = frame_names,
     .form = "lab|moving", .shown_default = "moving",
     .help = "simulate in the frame moving with v_pred, where the seeded\n"
             "wave is a steady state, or in the lab frame (uniform\n"
             "grid only)"},
    {.name = "grid", .type = BKF_OPT_CHOICE, .offset = OPT(grid), .choices = grid_names,
     .form = "G", .shown_default = "auto",
     .help = "auto: the uniform spectral grid when it resolves the wave\n"
             "on N <= 8192, else the adapted grid; uniform: always the\n"
             "spectral grid (up to --N-max); mapped: always the adapted\n"
             "grid (finite differences of order 8 on points placed by\n"
             "the wave's own length scales, in the frame of v_pred,\n"
             "CVODE in time; docs/cli/check.md)"},
    {.name = "points", .type = BKF_OPT_COUNT, .offset = OPT(points), .flags = BOUNDED,
     .min = BKF_CHECK_POINTS_MIN, .max = BKF_CHECK_POINTS_MAX, .form = "M",
     .shown_default = "768",
     .help = "adapted grid: the most points per wavelength, in\n"
             "[32, 1048576]; fewer (M/3, M/2, 2M/3) where they resolve\n"
             "the wave (--resolution)"},
    {.name = "resolution", .type = BKF_OPT_DOUBLE, .offset = OPT(resolution), .flags = BOUNDED,
     .min = BKF_CHECK_RESOLUTION_MIN, .max = 1, .form = "R", .shown_default = "1e-05",
     .help = "the spectral tail accepted as resolved (adapted grid:\n"
             "the grid's wave that far from the continuum's),\nin [1e-16, 1]"},
    {.name = "mapped-tol", .type = BKF_OPT_DOUBLE, .offset = OPT(mapped_tol),
     .flags = BOUNDED, .min = BKF_PDE_TOL_MIN, .max = BKF_PDE_TOL_MAX,
     .form = "E",
     .help = "adapted grid: CVODE's tolerance, in [1e-13, 0.01];\ndefault tol if given, else 1e-08"},
    {.name = "mapped-max-steps", .type = BKF_OPT_COUNT, .offset = OPT(mapped_max_steps),
     .form = "I", .shown_default = "20000",
     .help = "adapted grid: step budget per root (beyond: unresolved)"},
};
const size_t bkf_check_nkeys = sizeof bkf_check_keys / sizeof bkf_check_keys[0];

#undef MODEL
#undef OPT
#undef BOUNDED

bkf_check_spec bkf_check_spec_default(void)
{
    bkf_check_spec s;
    memset(&s, 0, sizeof s);
    s.model = bkf_model_params_paper();
    s.options = bkf_check_options_default();
    return s;
}

/* The model the spec runs: the chain's blocks from the key N (S by default). */
static int spec_model(const bkf_check_spec *spec, const char *p, bkf_model_params *model,
                      bkf_error *err)
{
    *model = spec->model;
    if (model->kind != BKF_MODEL_CHAIN) return BKF_OK;
    size_t N = spec->options.N;
    if (N == BKF_CHECK_N_DEFAULT) {
        double S = model->S;
        if (!(S >= BKF_CHAINWAVE_N_MIN && S <= BKF_CHAINWAVE_N_MAX && S == floor(S)))
            return bkf_error_set(err, BKF_EINPUT, "%sN: the number of blocks, in [%d, %d], is "
                                 "needed with %smodel chain (the default, S = %g, is not one)",
                                 p, BKF_CHAINWAVE_N_MIN, BKF_CHAINWAVE_N_MAX, p, S);
        N = (size_t)S;
    }
    model->N = N;
    return BKF_OK;
}

int bkf_check_spec_check(const bkf_check_spec *spec, const char *prefix, bkf_error *err)
{
    const char *p = prefix ? prefix : "";
    if (!spec) return bkf_error_set(err, BKF_EINPUT, "no spec given");
    const bkf_check_options *o = &spec->options;
    if (spec->model.kind == BKF_MODEL_CHAIN) {
        bkf_model_params m;
        bkf_error e;
        int s = spec_model(spec, p, &m, err);
        if (s) return s;
        bkf_check_options oc = *o;
        oc.N = BKF_CHECK_N_DEFAULT; /* the grid's N: the chain uses its blocks */
        if (bkf_check_validate(&m, &oc, &e))
            return bkf_error_set(err, BKF_EINPUT, "%s%s", p, e.message);
        return BKF_OK;
    }
    if (o->N % 2)
        return bkf_error_set(err, BKF_EINPUT,
                             "%sN: %zu must be even for the continuum model (spectral)", p, o->N);
    if (o->N_max < o->N)
        return bkf_error_set(err, BKF_EINPUT, "%sN-max: %zu is below %sN = %zu", p, o->N_max, p,
                             o->N);
    if (o->grid == BKF_CHECK_GRID_MAPPED && o->frame == BKF_CHECK_FRAME_LAB)
        return bkf_error_set(err, BKF_EINPUT,
                             "%sframe: lab is not available with %sgrid mapped (the adapted grid "
                             "moves with v_pred)",
                             p, p);
    bkf_error e;
    if (bkf_check_validate(&spec->model, o, &e))
        return bkf_error_set(err, BKF_EINPUT, "%s%s", p, e.message);
    return BKF_OK;
}

static const bkf_io_column columns[] = {
    {"n", BKF_IO_NUMBER},
    {"root", BKF_IO_NUMBER},
    {"grid", BKF_IO_TEXT},
    {"N", BKF_IO_NUMBER},
    {"tail", BKF_IO_NUMBER},
    {"v_pred", BKF_IO_NUMBER},
    {"v_pred_err", BKF_IO_NUMBER},
    {"v_meas", BKF_IO_NUMBER},
    {"v_meas_err", BKF_IO_NUMBER},
    {"rel_err", BKF_IO_NUMBER},
    {"fit_from", BKF_IO_NUMBER},
    {"fit_to", BKF_IO_NUMBER},
    {"t_end", BKF_IO_NUMBER},
    {"fronts_start", BKF_IO_NUMBER},
    {"fronts_end", BKF_IO_NUMBER},
    {"deviation_start", BKF_IO_NUMBER},
    {"deviation_mid", BKF_IO_NUMBER},
    {"deviation_end", BKF_IO_NUMBER},
    {"growth", BKF_IO_NUMBER},
    {"growth_err", BKF_IO_NUMBER},
    {"growth_limit", BKF_IO_NUMBER},
    {"growth_verdict", BKF_IO_TEXT},
    {"spectral", BKF_IO_TEXT},
    {"sigma_max", BKF_IO_NUMBER},
    {"sigma_max_err", BKF_IO_NUMBER},
    {"kept", BKF_IO_NUMBER},
    {"verdict", BKF_IO_TEXT},
    {"decide_tmax", BKF_IO_NUMBER},
};
#define NCOLUMNS (sizeof columns / sizeof columns[0])

/* The rows as they come, written once the run is done: the summary comment
 * needs them all. */
typedef struct {
    const bkf_check_hooks *hooks; /* the caller's, or NULL */
    bkf_check_row *rows;
    size_t count, cap;
    bkf_check_info info;
    char note[BKF_SPEEDS_NOTE_LEN];
    int failed; /* out of memory keeping a row */
} check_sink;

static int sink_begin(const bkf_check_info *info, void *data)
{
    check_sink *k = data;
    k->info = *info;
    snprintf(k->note, sizeof k->note, "%s", info->speeds_note);
    k->info.speeds_note = k->note;
    return k->hooks && k->hooks->begin ? k->hooks->begin(info, k->hooks->data) : 0;
}

static int sink_row(const bkf_check_row *row, void *data)
{
    check_sink *k = data;
    if (k->count == k->cap) {
        size_t cap = k->cap ? 2 * k->cap : 16;
        bkf_check_row *r = realloc(k->rows, cap * sizeof *r);
        if (!r) return k->failed = 1;
        k->rows = r;
        k->cap = cap;
    }
    k->rows[k->count++] = *row;
    return k->hooks && k->hooks->row ? k->hooks->row(row, k->hooks->data) : 0;
}

static void sink_progress(double fraction, void *data)
{
    const check_sink *k = data;
    k->hooks->progress(fraction, k->hooks->data);
}

static void sink_warning(const char *message, void *data)
{
    const check_sink *k = data;
    k->hooks->warning(message, k->hooks->data);
}

/* printf onto the end of the string in buf (truncated to size). */
static void append(char *buf, size_t size, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static void append(char *buf, size_t size, const char *fmt, ...)
{
    size_t used = strlen(buf);
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf + used, size - used, fmt, ap);
    va_end(ap);
}

/* "n1, n2, ..." of the rows that pass `keep`, into list. */
static void list_n(const check_sink *k, int (*keep)(const bkf_check_row *), char *list,
                   size_t size)
{
    list[0] = '\0';
    for (size_t i = 0; i < k->count; i++)
        if (keep(&k->rows[i])) {
            size_t used = strlen(list);
            snprintf(list + used, size - used, "%s%zu", used ? ", " : "", k->rows[i].n);
        }
}

static int row_kept(const bkf_check_row *r) { return r->kept == 1; }
static int row_disagrees(const bkf_check_row *r) { return r->verdict == BKF_CHECK_DISAGREES; }
static int row_conflicts(const bkf_check_row *r) { return r->verdict == BKF_CHECK_CONFLICTS; }
static int row_spectral_stable(const bkf_check_row *r)
{
    return r->spectral == BKF_TRAINSPEC_STABLE;
}
static int row_spectral_unstable(const bkf_check_row *r)
{
    return r->spectral == BKF_TRAINSPEC_UNSTABLE;
}

static int write_table(const check_sink *k, const bkf_model_params *m,
                       const bkf_check_options *o, FILE *out, bkf_io_format format,
                       const bkf_provenance *prov, bkf_error *err)
{
    int chain = m->kind == BKF_MODEL_CHAIN;
    char a[32], b[32], c[32], d[32], e[32], f[32], g[32];
    bkf_io_table *t = bkf_io_table_alloc(out, format, columns, NCOLUMNS, err);
    if (!t) return BKF_ENOMEM;
    int s = bkf_io_table_commentf(t, err, "%s check: predicted front speeds against seeded simulations",
                    prov && prov->program ? prov->program : "libbkfront");
    if (!s && chain)
        s = bkf_io_table_commentf(t, err,
                    "model chain: gamma %s, c %s, nu %s, S %s, N %zu blocks (h = %s); its "
                    "rotating waves (tol %.0e, multipliers) seeded on the blocks, run rk8pd tol "
                    "%s, sampled at every shift time tau",
                    bkf_format_number(m->gamma, a, sizeof a), bkf_format_number(m->c, b, sizeof b),
                    bkf_format_number(m->nu, c, sizeof c), bkf_format_number(m->S, d, sizeof d),
                    m->N, bkf_format_number(m->S / (double)m->N, e, sizeof e),
                    BKF_CHECK_CHAIN_WAVE_TOL, bkf_format_number(k->info.tol, f, sizeof f));
    if (!s && chain)
        s = bkf_io_table_commentf(t, err,
                    "tmax %s, perturbation rms %s (seed %lu), agreement asked %s; v_meas from "
                    "the phase the fronts gain, deviation orthogonal to it, spectral = the "
                    "multipliers' verdict, tail = the wave's Newton residual",
                    bkf_format_number(o->tmax, a, sizeof a), bkf_format_number(o->perturb, b, sizeof b),
                    o->seed, bkf_format_number(o->rel_tol, c, sizeof c));
    if (!s && chain)
        s = bkf_io_table_commentf(t, err, "waves: %zu (n <= %ld)%s%s", k->info.roots,
                    k->info.n_max, k->note[0] ? "; " : "", k->note);
    if (!s && !chain)
        s = bkf_io_table_commentf(t, err,
                    "model continuum: gamma %s, c %s, nu %s, S %s, N %zu (h = %s); tol %s, "
                    "stepper %s, dealias off, filter %s",
                    bkf_format_number(m->gamma, a, sizeof a), bkf_format_number(m->c, b, sizeof b), bkf_format_number(m->nu, c, sizeof c),
                    bkf_format_number(m->S, d, sizeof d), o->N, bkf_format_number(m->S / (double)o->N, e, sizeof e),
                    bkf_format_number(k->info.tol, f, sizeof f), bkf_pde_stepper_names[o->stepper],
                    o->filter == 0 ? "off" : bkf_format_number(o->filter, g, sizeof g));
    if (!s && !chain)
        s = bkf_io_table_commentf(t, err, "frame: %s",
                    o->frame == BKF_CHECK_FRAME_LAB ? "lab" : "moving with v_pred of each root");
    if (!s && !chain)
        s = bkf_io_table_commentf(t, err,
                    "tmax %s (%s), perturbation rms %s (seed %lu), agreement asked %s, grid %s: "
                    "uniform %zu .. %zu (resolution %.0e, samples every %s), adapted %zu points "
                    "per wavelength (tol %.0e, samples every %g)",
                    bkf_format_number(o->tmax, a, sizeof a),
                    o->runs == BKF_CHECK_RUNS_FULL ? "every run to it"
                                                   : "the longest run: runs auto stop once settled",
                    bkf_format_number(o->perturb, b, sizeof b), o->seed,
                    bkf_format_number(o->rel_tol, c, sizeof c), bkf_check_grid_name(o->grid), o->N,
                    k->info.N_cap, o->resolution,
                    bkf_format_number(check_sample_dt(BKF_CHECK_SAMPLE_DT, o->tmax), d, sizeof d),
                    o->points, k->info.mapped_tol, check_sample_dt(BKF_CHECK_MAPPED_SAMPLE_DT, o->tmax));
    if (!s && !chain)
        s = bkf_io_table_commentf(t, err, "speeds: tol %.0e, k(nu) %s, n_max %ld, %zu roots%s%s",
                    check_speeds_tol(o), bkf_format_number(k->info.k, a, sizeof a),
                    k->info.n_max, k->info.roots,
                    k->note[0] ? "; " : "", k->note);
    if (!s && prov && prov->command) s = bkf_io_table_commentf(t, err, "command: %s", prov->command);
    size_t kept = 0, agree = 0, unresolved = 0, disagree = 0, conflict = 0, undecided = 0;
    for (size_t i = 0; i < k->count; i++) {
        kept += k->rows[i].kept == 1;
        agree += k->rows[i].verdict == BKF_CHECK_AGREES;
        unresolved += k->rows[i].verdict == BKF_CHECK_UNRESOLVED;
        disagree += k->rows[i].verdict == BKF_CHECK_DISAGREES;
        conflict += k->rows[i].verdict == BKF_CHECK_CONFLICTS;
        undecided += k->rows[i].verdict == BKF_CHECK_UNDECIDED;
    }
    if (!s) {
        char list[512], yes[512], no[512];
        list_n(k, row_kept, list, sizeof list);
        list_n(k, row_spectral_stable, yes, sizeof yes);
        list_n(k, row_spectral_unstable, no, sizeof no);
        s = bkf_io_table_commentf(t, err,
                    "summary: %zu kept by the run (n = %s), %zu agree, %zu disagree, %zu "
                    "conflict, %zu undecided, %zu unresolved; spectrum stable n = %s, unstable "
                    "n = %s",
                    kept, kept ? list : "none", agree, disagree, conflict, undecided,
                    unresolved,
                    yes[0] ? yes : "none", no[0] ? no : "none");
    }
    for (size_t i = 0; !s && i < k->count; i++) {
        const bkf_check_row *r = &k->rows[i];
        bkf_io_value v[NCOLUMNS] = {
            {.number = (double)r->n},          {.number = (double)r->root},
            {.text = bkf_check_grid_name(r->grid)},
            {.number = (double)r->N},          {.number = r->tail},
            {.number = r->v_pred},             {.number = r->v_pred_err},
            {.number = r->v_meas},             {.number = r->v_meas_err},
            {.number = r->rel_err},            {.number = r->fit_from},
            {.number = r->fit_to},             {.number = r->t_end},
            {.number = r->fronts_start},
            {.number = r->fronts_end},         {.number = r->deviation_start},
            {.number = r->deviation_mid},      {.number = r->deviation_end},
            {.number = r->growth.rate},        {.number = r->growth.rate_err},
            {.number = r->growth.limit},
            {.text = bkf_check_growth_name(r->growth.verdict)},
            {.text = bkf_trainspec_verdict_name(r->spectral)},
            {.number = r->sigma_max},          {.number = r->sigma_max_err},
            {.number = r->kept},
            {.text = bkf_check_verdict_name(r->verdict)},
            {.number = r->decide_tmax},
        };
        s = bkf_io_table_row(t, v, err);
    }
    if (!s) s = bkf_io_table_finish(t, err);
    bkf_io_table_free(t);
    return s;
}

int bkf_check_write(const bkf_check_spec *spec, FILE *out, bkf_io_format format,
                    const bkf_provenance *prov, const bkf_check_hooks *hooks, size_t *disagree,
                    bkf_error *err)
{
    if (disagree) *disagree = 0;
    int s = bkf_check_spec_check(spec, "", err);
    if (s) return s;
    bkf_check_options o = spec->options;
    if (o.frame == BKF_CHECK_FRAME_LAB && o.grid == BKF_CHECK_GRID_AUTO)
        o.grid = BKF_CHECK_GRID_UNIFORM;
    check_sink k = {.hooks = hooks};
    bkf_check_hooks own = {.begin = sink_begin, .row = sink_row, .data = &k};
    if (hooks) {
        own.progress = hooks->progress ? sink_progress : NULL;
        own.warning = hooks->warning ? sink_warning : NULL;
        own.cancel = hooks->cancel;
    }
    bkf_model_params model;
    if ((s = spec_model(spec, "", &model, err))) return s;
    if (model.kind == BKF_MODEL_CHAIN) o.N = BKF_CHECK_N_DEFAULT;
    s = bkf_check_run(&model, &o, &own, err);
    if (!s && k.failed) s = bkf_error_set(err, BKF_ENOMEM, "out of memory");
    if (!s) s = write_table(&k, &model, &o, out, format, prov, err);
    size_t nd = 0, nc = 0;
    for (size_t i = 0; !s && i < k.count; i++) {
        nd += row_disagrees(&k.rows[i]);
        nc += row_conflicts(&k.rows[i]);
    }
    if (nd || nc) {
        char ld[512], lc[512], r[32], msg[BKF_ERROR_LEN] = "";
        list_n(&k, row_disagrees, ld, sizeof ld);
        list_n(&k, row_conflicts, lc, sizeof lc);
        if (disagree) *disagree = nd + nc;
        if (nd)
            append(msg, sizeof msg,
                   "%zu stable front(s) disagree with the predicted speed beyond rel-tol %s "
                   "(n = %s); ",
                   nd, bkf_format_number(o.rel_tol, r, sizeof r), ld);
        if (nc)
            append(msg, sizeof msg,
                   "%zu front(s) whose simulated growth contradicts the spectrum (n = %s); ", nc,
                   lc);
        s = bkf_error_set(err, BKF_ENUMERIC, "%ssee the table", msg);
    }
    free(k.rows);
    return s;
}

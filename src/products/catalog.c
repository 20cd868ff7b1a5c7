/* The catalogue (catalog.h): one adapter per product, in the order the CLI
 * lists them. */
#include "bkfront/catalog.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bkfront/approx.h"
#include "bkfront/bench.h"
#include "bkfront/check.h"
#include "bkfront/friction.h"
#include "bkfront/fronts.h"
#include "bkfront/orbits.h"
#include "bkfront/oscillation.h"
#include "bkfront/period.h"
#include "bkfront/profile.h"
#include "bkfront/simulate.h"
#include "bkfront/stability.h"
#include "bkfront/sweep.h"

/* The keys a product requires (BKF_OPT_REQUIRED) have been given: the
 * command line's parser says so for flags; here for every other caller.
 * A required number is NaN until given, a list empty, a text NULL, a
 * choice -1. */
static int required_given(const bkf_option *table, size_t n, const void *spec,
                          const char *prefix, bkf_error *err)
{
    for (size_t i = 0; i < n; i++) {
        const bkf_option *o = &table[i];
        if (!(o->flags & BKF_OPT_REQUIRED)) continue;
        const char *field = (const char *)spec + o->offset;
        int missing = 0;
        switch (o->type) {
        case BKF_OPT_DOUBLE: missing = isnan(*(const double *)field); break;
        case BKF_OPT_DOUBLE_LIST:
        case BKF_OPT_COUNT_LIST: missing = ((const bkf_list *)field)->count == 0; break;
        case BKF_OPT_TEXT: missing = *(const char *const *)field == NULL; break;
        case BKF_OPT_CHOICE: missing = *(const int *)field < 0; break;
        default: break;
        }
        if (missing) {
            char form[128];
            return bkf_error_set(err, BKF_EINPUT, "%s%s is required (%s)", prefix ? prefix : "",
                                 o->name, bkf_option_describe(o, form, sizeof form));
        }
    }
    return BKF_OK;
}

/* The adapters of a product whose module has the usual shape: a spec
 * type T with T PREFIX_spec_default(void), tables PREFIX_options and
 * PREFIX_noptions and int PREFIX_check(const T *, prefix, err); RELEASE
 * frees what the spec owns.  WRITER adapts a write WRITE(const T *, FILE *,
 * format, provenance, err). */
#define ADAPTERS(name, T, PREFIX, RELEASE)                                        \
    static const bkf_option *name##_options(size_t *count)                              \
    {                                                                                    \
        *count = PREFIX##_noptions;                                                      \
        return PREFIX##_options;                                                         \
    }                                                                                    \
    static void name##_init(void *spec) { *(T *)spec = PREFIX##_spec_default(); }       \
    static int name##_check(const void *spec, const char *prefix, bkf_error *err)        \
    {                                                                                    \
        int s_ = required_given(PREFIX##_options, PREFIX##_noptions, spec, prefix, err);  \
        return s_ ? s_ : PREFIX##_check(spec, prefix, err);                              \
    }                                                                                    \
    static void name##_release(void *spec) { RELEASE(spec); }

#define WRITER(name, T, WRITE)                                                           \
    static int name##_write(const void *spec, FILE *out, bkf_io_format format,          \
                            const bkf_provenance *prov, const bkf_catalog_hooks *hooks,  \
                            bkf_error *err)                                              \
    {                                                                                    \
        (void)hooks;                                                                     \
        return WRITE((const T *)spec, out, format, prov, err);                           \
    }

/* A writer whose spec reports its refused rows through a warn callback
 * (fields warn, warn_data): to the hooks' warning. */
#define WARN_WRITER(name, T, WRITE)                                                      \
    static int name##_write(const void *spec, FILE *out, bkf_io_format format,          \
                            const bkf_provenance *prov, const bkf_catalog_hooks *hooks,  \
                            bkf_error *err)                                              \
    {                                                                                    \
        T s_ = *(const T *)spec;                                                         \
        if (hooks && hooks->warn) {                                                      \
            s_.warn = hooks->warn;                                                       \
            s_.warn_data = hooks->data;                                                  \
        }                                                                                \
        return WRITE(&s_, out, format, prov, err);                                       \
    }

static void release_nothing(void *spec) { (void)spec; }
static void period_free(void *spec) { bkf_period_spec_free(spec); }
static void profile_free(void *spec) { bkf_profile_spec_free(spec); }
static void oscillation_free(void *spec) { bkf_oscillation_spec_free(spec); }
static void approx_free(void *spec) { bkf_approx_spec_free(spec); }

ADAPTERS(period, bkf_period_spec, bkf_period, period_free)
/* The hooks' cancel flag stops the table between points. */
static int period_write(const void *spec, FILE *out, bkf_io_format format,
                        const bkf_provenance *prov, const bkf_catalog_hooks *hooks,
                        bkf_error *err)
{
    bkf_period_spec s = *(const bkf_period_spec *)spec;
    if (hooks) s.cancel = hooks->cancel;
    return bkf_period_write(&s, out, format, prov, err);
}
ADAPTERS(profile, bkf_profile_spec, bkf_profile, profile_free)
WRITER(profile, bkf_profile_spec, bkf_profile_write)
ADAPTERS(asymptotics, bkf_approx_spec, bkf_approx, approx_free)
WRITER(asymptotics, bkf_approx_spec, bkf_approx_write)
ADAPTERS(speeds, bkf_fronts_spec, bkf_fronts, release_nothing)
WARN_WRITER(speeds, bkf_fronts_spec, bkf_fronts_write) /* refused roots */
ADAPTERS(branch, bkf_fronts_branch_spec, bkf_fronts_branch, release_nothing)
WRITER(branch, bkf_fronts_branch_spec, bkf_fronts_branch_write)
ADAPTERS(stability, bkf_stability_spec, bkf_stability, release_nothing)
WRITER(stability, bkf_stability_spec, bkf_stability_write)
ADAPTERS(friction, bkf_friction_spec, bkf_friction, release_nothing)
WRITER(friction, bkf_friction_spec, bkf_friction_table)
ADAPTERS(bench, bkf_bench_spec, bkf_bench, release_nothing)
WRITER(bench, bkf_bench_spec, bkf_bench_write)
ADAPTERS(floquet, bkf_oscillation_spec, bkf_oscillation, oscillation_free)
WARN_WRITER(floquet, bkf_oscillation_spec, bkf_oscillation_write) /* refused dispersion rows */

/* ------------------------------------------------------------- orbit */

static const bkf_option *orbit_options(size_t *count)
{
    *count = bkf_orbits_spec_noptions;
    return bkf_orbits_spec_options;
}
static void orbit_init(void *spec) { *(bkf_orbits_spec *)spec = bkf_orbits_spec_default(); }
static int orbit_check(const void *spec, const char *prefix, bkf_error *err)
{
    return bkf_orbits_check(spec, prefix, err);
}
static void orbit_release(void *spec) { (void)spec; }
/* The hooks' progress and cancel flag drive the branch. */
static int orbit_write(const void *spec, FILE *out, bkf_io_format format,
                       const bkf_provenance *prov, const bkf_catalog_hooks *hooks,
                       bkf_error *err)
{
    bkf_orbits_spec s = *(const bkf_orbits_spec *)spec;
    if (hooks) {
        s.progress = hooks->progress;
        s.progress_data = hooks->data;
        s.cancel = hooks->cancel;
    }
    return bkf_orbits_write(&s, out, format, prov, err);
}

ADAPTERS(simulate, bkf_simulate_spec, bkf_simulate, release_nothing)

/* The hooks' progress and cancel flag drive the run; stopped, the complete
 * frames go to the table, the data files only with keep_canceled, and
 * BKF_ECANCELED is returned. */
static int simulate_write(const void *spec, FILE *out, bkf_io_format format,
                          const bkf_provenance *prov, const bkf_catalog_hooks *hooks,
                          bkf_error *err)
{
    bkf_simulate_spec s = *(const bkf_simulate_spec *)spec;
    if (hooks) {
        s.progress = hooks->progress;
        s.cancel = hooks->cancel;
        s.temp_file = hooks->temp_file;
        s.warn = hooks->warn;
        s.data = hooks->data;
    }
    s.discard_canceled = !hooks || !hooks->keep_canceled;
    return bkf_simulate_write(&s, out, format, prov, err);
}

/* -------------------------------------------------------------- sweep */

static const bkf_option *sweep_options(size_t *count) { return bkf_sweep_keys(count); }
static void sweep_init(void *spec) { *(bkf_sweep_spec *)spec = bkf_sweep_spec_default(); }
static int sweep_check(const void *spec, const char *prefix, bkf_error *err)
{
    return bkf_sweep_check(spec, prefix, err);
}
static void sweep_progress(size_t done, size_t total, void *data)
{
    const bkf_catalog_hooks *h = data;
    h->progress(total ? (double)done / (double)total : 1.0, h->data);
}
/* The whole table in point order: a scene's sweep is computed in one go. */
static int sweep_write(const void *spec, FILE *out, bkf_io_format format,
                       const bkf_provenance *prov, const bkf_catalog_hooks *hooks,
                       bkf_error *err)
{
    (void)prov; /* the table's head is the sweep's definition, as --resume compares it */
    if (format != BKF_IO_TSV)
        return bkf_error_set(err, BKF_EINPUT, "format: a sweep's table is TSV only");
    bkf_sweep_spec s = *(const bkf_sweep_spec *)spec;
    if (hooks) {
        s.cancel = hooks->cancel;
        if (hooks->progress) {
            s.progress = sweep_progress;
            s.data = (void *)hooks;
        }
    }
    return bkf_sweep_write(&s, out, err);
}
static void sweep_release(void *spec) { bkf_sweep_spec_free(spec); }

/* -------------------------------------------------------------- check */

static const bkf_option *check_options(size_t *count)
{
    *count = bkf_check_nkeys;
    return bkf_check_keys;
}
static void check_init(void *spec) { *(bkf_check_spec *)spec = bkf_check_spec_default(); }
static int check_check(const void *spec, const char *prefix, bkf_error *err)
{
    int s = required_given(bkf_check_keys, bkf_check_nkeys, spec, prefix, err);
    return s ? s : bkf_check_spec_check(spec, prefix, err);
}
/* The catalogue's progress may answer; the check stops by cancel only. */
static void check_progress(double fraction, void *data)
{
    const bkf_catalog_hooks *h = data;
    h->progress(fraction, h->data);
}
static void check_warning(const char *message, void *data)
{
    const bkf_catalog_hooks *h = data;
    h->warn(message, h->data);
}
/* A stable front that disagrees is BKF_ENUMERIC after the whole table. */
static int check_write(const void *spec, FILE *out, bkf_io_format format,
                       const bkf_provenance *prov, const bkf_catalog_hooks *hooks,
                       bkf_error *err)
{
    bkf_catalog_hooks copy = {0};
    if (hooks) copy = *hooks;
    bkf_check_hooks h = {.progress = copy.progress ? check_progress : NULL,
                         .warning = copy.warn ? check_warning : NULL,
                         .data = &copy,
                         .cancel = copy.cancel};
    return bkf_check_write(spec, out, format, prov, &h, NULL, err);
}
static void check_release(void *spec)
{
    bkf_option_free_lists(bkf_check_keys, bkf_check_nkeys, spec);
}

/* ---------------------------------------------------------- the table */

#define ENTRY(name, T, summary) \
    {#name, summary, NULL, NULL, sizeof(T), name##_options, name##_init, name##_check, \
     name##_write, name##_release, name##_kinds, sizeof name##_kinds / sizeof name##_kinds[0], \
     name##_cost}

/* The scene kinds (bkf_catalog_kind): the keys in the order of the step's
 * command line, the scene's defaults, the files. */
static const bkf_catalog_kind period_kinds[] = {
    {"period", {.keys = "mu=0.1:1e4:41 method +nu ^tol"}, {0}}};
static const bkf_catalog_kind speeds_kinds[] = {
    {"speeds",
     {.keys = "+gamma +c +nu +S ^model!continuum ^N?model=chain n nmax ^tol method"}, {0}}};
static const bkf_catalog_kind branch_kinds[] = {
    {"branch",
     {.keys = "@param from=$param to +gamma +c +nu +S ^model!continuum ^N?model=chain n=1 root "
              "max-points ^tol"},
     {0}}};
static const bkf_catalog_kind stability_kinds[] = {
    {"stability", {.keys = "+gamma +c +nu +S n=1 tol"}, {0}}};
static const bkf_catalog_kind asymptotics_kinds[] = {
    {"validity", {.first = "grid", .keys = "mu=0.1:1e4:21 log:=yes nu=-0.99:0.99:12"}, {0}}};
static const bkf_catalog_kind profile_kinds[] = {
    {"profile", {.keys = "+gamma +c +nu +S n=1 root points ^tol"}, {0}}};
static const bkf_catalog_kind floquet_kinds[] = {
    {"dispersion", {.keys = "+gamma +c q=0:6:241 ^S +nu ^tol"}, {0}},
    {"threshold", {.first = "threshold", .keys = "+gamma +c @along from to search ^tol"}, {0}}};
/* The branch starts from the oscillation's period doubling in nu: a
 * [model]'s nu is not inherited (the branch varies it), nor [accuracy]'s N
 * (a simulation's grid; the orbit's is a multiple of 2 j, 32 j by default). */
static const bkf_catalog_kind orbit_kinds[] = {
    {"orbit",
     {.keys = "+gamma +c +S ^model!continuum N j from to max-points tol at",
      .outputs = "out=.tsv spacetime=_spacetime.dat multipliers=_multipliers.tsv"},
     {0}}};
/* A simulation's tol is its stepper's, not the accuracy asked of a result:
 * not inherited. */
static const bkf_catalog_kind simulate_kinds[] = {
    {"spacetime",
     {.keys = "+gamma +c +nu +S ^model ^N=512 tmax=50 init=uniform seed=1 frames=500 tol stepper",
      .last = "no-progress", .outputs = "spacetime=.dat out=_diag.tsv"},
     {0}}};
static const bkf_catalog_kind check_kinds[] = {
    {"check",
     {.keys = "+gamma +c +nu +S ^model!continuum n ^N tmax runs threads tol rel-tol seed stepper "
              "frame grid points",
      .last = "no-progress"},
     {0}}};
/* With thresholds = G1,G2,...: the global oscillation's stability
 * boundaries at each gamma, to 1e-6 in nu (far finer than any map's grid),
 * for the map's figure to draw over the regimes. */
static const bkf_catalog_kind sweep_kinds[] = {
    {"sweep", {.keys = "+gamma +c +nu +S ^model ^N", .last = "no-progress"},
     {.product = "floquet", .first = "diagram", .fanout = "thresholds>gamma",
      .keys = "gamma ^c search=-0.999:0.999 tol:=1e-6", .outputs = "out=_floquet_#.tsv"}}};
static const bkf_catalog_kind friction_kinds[] = {
    {"friction", {.keys = "from=-1 to=4 points=601"}, {0}}};
static const bkf_catalog_kind bench_kinds[] = {{"bench", {.keys = "product quick"}, {0}}};

/* The products' expected work (catalog.h's cost), in seconds of one core:
 * rates measured on the paper scene's steps (docs/benchmarks.md), scaled
 * by what grows with the spec.  Only their order matters: they decide
 * which of a scene's steps start first when several run at once. */
static double list_count(const bkf_list *l) { return l->count ? (double)l->count : 1.0; }

/* A simulation: N log N per unit of time, N 512 for 50 time units ~ 2 s. */
static double simulation_cost(const bkf_simulate_spec *sp)
{
    double N = sp->model.N ? (double)sp->model.N : sp->chain ? sp->model.S : BKF_SIMULATE_N_DEFAULT;
    if (!(N >= 2)) N = BKF_SIMULATE_N_DEFAULT;
    return 2.0 * (sp->tmax / 50.0) * (N * log2(N)) / (512.0 * 9.0);
}

/* A spectrum of a train of n fronts: ~0.1 s per front at tol 1e-6. */
static double spectrum_cost(size_t n) { return 0.1 * (double)(n ? n : 1); }

static double period_cost(const void *spec)
{
    const bkf_period_spec *sp = spec;
    if (sp->along >= 0) return 1.0;
    return 0.005 * list_count(&sp->mu) * list_count(&sp->nu);
}
static double speeds_cost(const void *spec)
{
    const bkf_fronts_spec *sp = spec;
    double rows = sp->n ? 1.0 : sp->nmax ? (double)sp->nmax : 10.0;
    double cost = 0.02 * rows;
    if (sp->model == 1) cost *= 0.1 * (double)(sp->N ? sp->N : (size_t)fmax(sp->S, 2.0));
    if (sp->stability) cost += rows * spectrum_cost(sp->n ? sp->n : 5);
    return cost;
}
/* A branch: ~100 points, each with its spectrum when asked. */
static double branch_cost(const void *spec)
{
    const bkf_fronts_branch_spec *sp = spec;
    return 0.3 + (sp->stability ? 100.0 * spectrum_cost(sp->n) : 0.0);
}
/* The diagram and the boundary: a spectrum per S sample and bracket step,
 * per n and nu. */
static double stability_cost(const void *spec)
{
    const bkf_stability_spec *sp = spec;
    if (sp->diagram || sp->boundary) {
        double step = sp->nu_step > 0 ? sp->nu_step : 0.01;
        double nus = floor(fabs(sp->to - sp->nu) / step) + 1.0;
        double brackets = (double)sp->S_samples + log2(fmax(sp->S_to - sp->S, 1.0) / sp->S_tol);
        double per = 0.0;
        for (size_t n = sp->diagram ? 1 : sp->n; n <= sp->n; n++) per += spectrum_cost(n);
        return nus * brackets * per;
    }
    return spectrum_cost(sp->n) * (sp->line ? (double)sp->kappa_count / 16.0 : 1.0);
}
static double asymptotics_cost(const void *spec)
{
    (void)spec;
    return 1.0;
}
static double profile_cost(const void *spec)
{
    const bkf_profile_spec *sp = spec;
    return 0.1 * list_count(&sp->n);
}
static double floquet_cost(const void *spec)
{
    const bkf_oscillation_spec *sp = spec;
    if (sp->threshold && sp->along >= 0) return 10.0;
    if (sp->threshold || sp->diagram) return 2.0;
    return 0.0015 * list_count(&sp->q);
}
/* per point: the continuation, the polish and, unless skipped, the
 * multipliers (3.7 s of CPU a point at the paper's parameters, 0.4 s
 * without them) */
static double orbit_cost(const void *spec)
{
    const bkf_orbits_spec *sp = spec;
    return (double)sp->max_points * (sp->no_stability ? 0.4 : 3.7);
}
static double simulate_cost(const void *spec) { return simulation_cost(spec); }
/* Every root's run at up to two grids. */
static double check_cost(const void *spec)
{
    const bkf_check_spec *sp = spec;
    double roots = sp->options.n ? 1.0 : 6.0;
    return roots * 2.0 * (sp->options.tmax / 50.0);
}
static double sweep_cost(const void *spec)
{
    const bkf_sweep_spec *sp = spec;
    return (double)bkf_sweep_count(sp) * simulation_cost(&sp->sim);
}
static double friction_cost(const void *spec)
{
    (void)spec;
    return 0.05;
}
static double bench_cost(const void *spec)
{
    const bkf_bench_spec *sp = spec;
    return sp->quick ? 30.0 : 300.0;
}

static const bkf_catalog_entry entries[] = {
    ENTRY(period, bkf_period_spec,
          "period T(mu, nu) of the reduced front equation, at points, on grids or branches"),
    ENTRY(speeds, bkf_fronts_spec, "allowed front speeds: every root of the speed condition"),
    ENTRY(branch, bkf_fronts_branch_spec,
          "speed branches v_n(p) along one parameter, through folds to the sonic limit"),
    ENTRY(stability, bkf_stability_spec,
          "spectral stability of a train of n fronts: its spectrum on the ring or the line"),
    ENTRY(asymptotics, bkf_approx_spec,
          "asymptotic formulas for T against the numerical period: fits, validity map, errors"),
    ENTRY(profile, bkf_profile_spec,
          "front profiles f(z), f'(z) and their place x along the system"),
    ENTRY(floquet, bkf_oscillation_spec,
          "Floquet stability of the global oscillation: dispersion, threshold, diagram"),
    ENTRY(orbit, bkf_orbits_spec,
          "period-doubled pacemakers as exact orbits: their branch from the oscillation, folds, "
          "stability"),
    ENTRY(simulate, bkf_simulate_spec,
          "direct simulation (continuum or chain) with measurements, spacetime field, snapshots"),
    ENTRY(check, bkf_check_spec, "the predicted front speeds against direct simulation"),
    ENTRY(sweep, bkf_sweep_spec,
          "regime maps: a product at every point of a grid of parameters, seeds and states"),
    ENTRY(friction, bkf_friction_spec, "the friction laws, sampled"),
    ENTRY(bench, bkf_bench_spec,
          "work-precision: achieved error against CPU time for every method and tolerance"),
};
#define NENTRIES (sizeof entries / sizeof entries[0])

size_t bkf_catalog_count(void) { return NENTRIES; }

const bkf_catalog_entry *bkf_catalog_at(size_t i) { return i < NENTRIES ? &entries[i] : NULL; }

const bkf_catalog_entry *bkf_catalog_find(const char *name)
{
    for (size_t i = 0; name && i < NENTRIES; i++)
        if (strcmp(entries[i].name, name) == 0) return &entries[i];
    return NULL;
}

void *bkf_catalog_spec_new(const bkf_catalog_entry *entry, bkf_error *err)
{
    if (!entry) {
        bkf_error_set(err, BKF_EINPUT, "no product given");
        return NULL;
    }
    void *spec = calloc(1, entry->spec_size);
    if (!spec) {
        bkf_error_set(err, BKF_ENOMEM, "out of memory");
        return NULL;
    }
    entry->init(spec);
    return spec;
}

void bkf_catalog_spec_free(const bkf_catalog_entry *entry, void *spec)
{
    if (!entry || !spec) return;
    entry->release(spec);
    free(spec);
}

int bkf_catalog_apply(const bkf_catalog_entry *entry, void *spec, const char *key,
                      const char *text, const char *prefix, bkf_error *err)
{
    if (!entry || !spec || !key)
        return bkf_error_set(err, BKF_EINPUT, "no product, spec or key given");
    size_t n;
    const bkf_option *table = entry->options(&n);
    const bkf_option *opt = bkf_option_find(table, n, key);
    char shown[80];
    if (!opt || (opt->flags & BKF_OPT_CLI_ONLY))
        return bkf_error_set(err, BKF_EINPUT, "%s%s: not a key of %s",
                             prefix ? prefix : "", bkf_option_shown(key, shown, sizeof shown),
                             entry->name);
    if (opt->type == BKF_OPT_SWITCH && text) {
        /* A scene writes a switch as key = yes or no. */
        if (strcmp(text, "no") == 0) {
            *(int *)((char *)spec + opt->offset) = 0;
            return BKF_OK;
        }
        if (strcmp(text, "yes") != 0)
            return bkf_error_set(err, BKF_EINPUT, "%s%s: '%s' is not yes or no",
                                 prefix ? prefix : "", opt->name,
                                 bkf_option_shown(text, shown, sizeof shown));
        text = NULL;
    }
    return bkf_option_apply(opt, spec, text, prefix ? prefix : "", err);
}

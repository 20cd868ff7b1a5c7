#include "bkfront/stability.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bkfront/fronts.h"
#include "bkfront/stabmap.h"

#include "product_internal.h"

static const bkf_io_column ring_columns[] = {
    {"j", BKF_IO_NUMBER},   {"kappa", BKF_IO_NUMBER}, {"re", BKF_IO_NUMBER},
    {"im", BKF_IO_NUMBER},  {"err", BKF_IO_NUMBER},   {"translation", BKF_IO_NUMBER}};
static const bkf_io_column line_columns[] = {
    {"kappa", BKF_IO_NUMBER}, {"re", BKF_IO_NUMBER}, {"im", BKF_IO_NUMBER}, {"err", BKF_IO_NUMBER}};
static const bkf_io_column boundary_columns[] = {
    {"nu", BKF_IO_NUMBER},        {"S", BKF_IO_NUMBER},     {"S_err", BKF_IO_NUMBER},
    {"sigma", BKF_IO_NUMBER},     {"sigma_err", BKF_IO_NUMBER}, {"slope", BKF_IO_NUMBER},
    {"v", BKF_IO_NUMBER},         {"mu", BKF_IO_NUMBER},    {"stable_above", BKF_IO_NUMBER}};
static const bkf_io_column diagram_columns[] = {
    {"curve", BKF_IO_NUMBER}, {"kind", BKF_IO_TEXT},  {"n", BKF_IO_NUMBER},
    {"m", BKF_IO_NUMBER},     {"nu", BKF_IO_NUMBER},  {"S", BKF_IO_NUMBER},
    {"S_err", BKF_IO_NUMBER}, {"above", BKF_IO_NUMBER}, {"nu_err", BKF_IO_NUMBER}};
#define KAPPA_COUNT_DEFAULT 64
#define NRING (sizeof ring_columns / sizeof ring_columns[0])
#define NLINE (sizeof line_columns / sizeof line_columns[0])
#define NBOUNDARY (sizeof boundary_columns / sizeof boundary_columns[0])
#define NDIAGRAM (sizeof diagram_columns / sizeof diagram_columns[0])

/* trainspec's ranges (trainspec.h), repeated in the table for the messages. */
#define TOL_MIN BKF_TRAINSPEC_TOL_MIN
#define TOL_MAX BKF_TRAINSPEC_TOL_MAX
#define PER_KAPPA_MAX 50

#define BOUNDED (BKF_OPT_MIN | BKF_OPT_MAX)
#define FIELD(f) offsetof(bkf_stability_spec, f)

const bkf_option bkf_stability_options[] = {
    BKF_PRODUCT_GAMMA_OPTION(bkf_stability_spec),
    {.name = "c", .type = BKF_OPT_DOUBLE, .offset = FIELD(c),
     .flags = BKF_OPT_MIN | BKF_OPT_MIN_OPEN | BKF_OPT_MAX, .min = 0,
     .max = BKF_MODEL_C_MAX, .form = "C", .shown_default = BKF_TEXT_OF(BKF_PAPER_C),
     .help = "sound speed, in (0, 1e6] (with c = 0 every mode is neutral)"},
    BKF_PRODUCT_NU_OPTION(bkf_stability_spec),
    BKF_PRODUCT_S_OPTION(bkf_stability_spec),
    {.name = "n", .type = BKF_OPT_COUNT, .offset = FIELD(n),
     .flags = BKF_OPT_REQUIRED | BOUNDED | BKF_OPT_FANOUT, .min = 1, .max = 1e9, .form = "N",
     .help = "required; number of fronts (at most n_max, as listed by\n"
             "bkfront speeds)"},
    {.name = "root", .type = BKF_OPT_COUNT, .offset = FIELD(root), .flags = BOUNDED, .min = 1,
     .max = 1e6, .form = "I", .shown_default = "1",
     .help = "which root of this n, 1 being the fastest (as listed by\n"
             "bkfront speeds)"},
    {.name = "tol", .type = BKF_OPT_DOUBLE, .offset = FIELD(tol), .flags = BOUNDED,
     .min = TOL_MIN, .max = TOL_MAX, .form = "E", .shown_default = "1e-6",
     .help = "absolute accuracy asked of each sigma, in [1e-08, 0.01]"},
    {.name = "per-kappa", .type = BKF_OPT_COUNT, .offset = FIELD(per_kappa), .flags = BOUNDED,
     .min = 1, .max = PER_KAPPA_MAX, .form = "K", .shown_default = "3",
     .help = "eigenvalues reported per Bloch number (the rightmost K),\n"
             "in [1, 50]"},
    {.name = "line", .type = BKF_OPT_SWITCH, .offset = FIELD(line),
     .help = "the infinite line's spectrum instead of the ring's: the\n"
             "rightmost sigma for kappa in [0, 2 pi/L), L = S/n"},
    {.name = "kappa-count", .type = BKF_OPT_COUNT, .offset = FIELD(kappa_count),
     .flags = BOUNDED, .min = 1, .max = BKF_STABILITY_KAPPA_MAX, .form = "M",
     .shown_default = BKF_TEXT_OF(KAPPA_COUNT_DEFAULT), .help = "with --line: M Bloch numbers kappa = (2 pi/L) i/M,\n"
                                     "i = 0..M-1, in [1, 100000]"},
    {.name = "boundary", .type = BKF_OPT_SWITCH, .offset = FIELD(boundary),
     .help = "the stability boundary of train n: the first sign change\n"
             "of sigma_max in S between --S and --S-to at --nu,\n"
             "followed in nu to --to"},
    {.name = "diagram", .type = BKF_OPT_SWITCH, .offset = FIELD(diagram),
     .help = "the (nu, S) diagram of the trains 1..n over nu from --nu\n"
             "to --to and S in [--S, --S-to]: where each exists and is\n"
             "stable, and the global oscillation's thresholds"},
    {.name = "to", .type = BKF_OPT_DOUBLE, .offset = FIELD(to), .form = "V2",
     .help = "with --boundary, --diagram: the end in nu, in (-1, 1)"},
    {.name = "S-to", .type = BKF_OPT_DOUBLE, .offset = FIELD(S_to), .form = "L2",
     .help = "with --boundary, --diagram: the end in S, > --S"},
    {.name = "nu-step", .type = BKF_OPT_DOUBLE, .offset = FIELD(nu_step),
     .flags = BKF_OPT_MIN | BKF_OPT_MIN_OPEN | BKF_OPT_MAX, .min = 0, .max = 0.5, .form = "H",
     .shown_default = "0.01", .help = "step in nu of the continuation, in (0, 0.5]"},
    {.name = "S-tol", .type = BKF_OPT_DOUBLE, .offset = FIELD(S_tol), .flags = BOUNDED,
     .min = 1e-8, .max = 1, .form = "E", .shown_default = "1e-3",
     .help = "bracket width in S ending a crossing's solve, in [1e-8, 1]"},
    {.name = "S-samples", .type = BKF_OPT_COUNT, .offset = FIELD(S_samples), .flags = BOUNDED,
     .min = 2, .max = 1000, .form = "K", .shown_default = "12",
     .help = "steps of the scan in S for the first crossings, in\n"
             "[2, 1000]"},
    {.name = "seed-step", .type = BKF_OPT_DOUBLE, .offset = FIELD(seed_step),
     .flags = BKF_OPT_MIN | BKF_OPT_MIN_OPEN | BKF_OPT_MAX, .min = 0, .max = 2, .form = "H2",
     .shown_default = "0.1",
     .help = "with --diagram: spacing in nu of the seed columns,\n"
             "scanned in S, whose crossings are followed, in (0, 2]"},
    {.name = "scan", .type = BKF_OPT_SWITCH, .offset = FIELD(scan),
     .help = "with --diagram: the grid scan instead of following:\n"
             "every nu of --nu-step scanned in S"},
    {.name = "threads", .type = BKF_OPT_COUNT, .offset = FIELD(threads), .flags = BOUNDED,
     .min = 0, .max = 4096, .form = "K", .shown_default = "0",
     .help = "with --diagram: threads, 0 every core"},
};
const size_t bkf_stability_noptions = sizeof bkf_stability_options / sizeof bkf_stability_options[0];

bkf_stability_spec bkf_stability_spec_default(void)
{
    bkf_stability_spec s;
    memset(&s, 0, sizeof s);
    s.gamma = s.c = s.nu = s.S = NAN;
    bkf_model_paper_where_unset(&s.gamma, &s.c, &s.nu, &s.S);
    s.n = 0;
    s.root = 1;
    bkf_trainspec_options o = bkf_trainspec_options_default();
    s.tol = o.tol;
    s.per_kappa = o.per_kappa;
    s.line = 0;
    s.kappa_count = KAPPA_COUNT_DEFAULT;
    s.to = s.S_to = NAN;
    bkf_stabmap_options m = bkf_stabmap_options_default();
    s.nu_step = m.nu_step;
    s.S_tol = m.S_tol;
    s.S_samples = 12;
    s.seed_step = 0.1;
    s.scan = 0;
    s.threads = 0;
    return s;
}

/* The speeds product's spec for the root's n: its check is ours for the
 * model, and its setup finds the root. */
static bkf_fronts_spec fronts_of(const bkf_stability_spec *spec)
{
    bkf_fronts_spec f = bkf_fronts_spec_default();
    f.gamma = spec->gamma;
    f.c = spec->c;
    f.nu = spec->nu;
    f.S = spec->S;
    f.n = spec->n;
    return f;
}

/* The keys of --boundary and --diagram, and which modes go together. */
static int check_across(const bkf_stability_spec *spec, const char *p, bkf_error *err)
{
    char a[32], b[32];
    int across = spec->boundary || spec->diagram;
    if (spec->boundary && spec->diagram)
        return bkf_error_set(err, BKF_EINPUT, "%sdiagram: give %sboundary or %sdiagram, not both",
                             p, p, p);
    if (across && spec->line)
        return bkf_error_set(err, BKF_EINPUT, "%sline: %sline is the spectrum of one train; "
                             "not with %s%s", p, p, p, spec->boundary ? "boundary" : "diagram");
    /* a count the ring's spectrum would silently ignore (found by the
     * independent audit of issue 31) */
    if (!spec->line && spec->kappa_count != KAPPA_COUNT_DEFAULT)
        return bkf_error_set(err, BKF_EINPUT, "%skappa-count: only with %sline", p, p);
    if (!spec->diagram && (spec->scan || spec->seed_step != 0.1 || spec->threads))
        return bkf_error_set(err, BKF_EINPUT, "%s%s: only with %sdiagram", p,
                             spec->scan ? "scan" : spec->threads ? "threads" : "seed-step", p);
    if (!across) {
        if (!isnan(spec->to) || !isnan(spec->S_to))
            return bkf_error_set(err, BKF_EINPUT, "%s%s: only with %sboundary or %sdiagram", p,
                                 isnan(spec->to) ? "S-to" : "to", p, p);
        return BKF_OK;
    }
    if (!(fabs(spec->to) < 1))
        return bkf_error_set(err, BKF_EINPUT, "%sto: to = %s is not in (-1, 1)%s", p,
                             bkf_format_number(spec->to, a, sizeof a),
                             isnan(spec->to) ? " (required with boundary, diagram)" : "");
    if (spec->to == spec->nu)
        return bkf_error_set(err, BKF_EINPUT, "%sto: to = nu = %s: nothing to follow", p,
                             bkf_format_number(spec->to, a, sizeof a));
    if (!(spec->S_to > spec->S) || !isfinite(spec->S_to))
        return bkf_error_set(err, BKF_EINPUT, "%sS-to: S-to = %s is not > S = %s%s", p,
                             bkf_format_number(spec->S_to, a, sizeof a),
                             bkf_format_number(spec->S, b, sizeof b),
                             isnan(spec->S_to) ? " (required with boundary, diagram)" : "");
    if (!(spec->nu_step > 0 && spec->nu_step <= 0.5))
        return bkf_error_set(err, BKF_EINPUT, "%snu-step: nu-step = %s is not in (0, 0.5]", p,
                             bkf_format_number(spec->nu_step, a, sizeof a));
    if (!(spec->S_tol >= 1e-8 && spec->S_tol <= 1))
        return bkf_error_set(err, BKF_EINPUT, "%sS-tol: S-tol = %s is not in [1e-8, 1]", p,
                             bkf_format_number(spec->S_tol, a, sizeof a));
    if (spec->S_samples < 2 || spec->S_samples > 1000)
        return bkf_error_set(err, BKF_EINPUT, "%sS-samples: S-samples = %zu is not in [2, 1000]",
                             p, spec->S_samples);
    if (!(spec->seed_step > 0 && spec->seed_step <= 2))
        return bkf_error_set(err, BKF_EINPUT, "%sseed-step: seed-step = %s is not in (0, 2]", p,
                             bkf_format_number(spec->seed_step, a, sizeof a));
    if (spec->threads > 4096)
        return bkf_error_set(err, BKF_EINPUT, "%sthreads: threads = %zu is not in [0, 4096]", p,
                             spec->threads);
    if (spec->diagram && spec->n > BKF_STABILITY_DIAGRAM_N_MAX)
        return bkf_error_set(err, BKF_EINPUT,
                             "%sn: n = %zu: the diagram takes n = 1..N, N at most %u", p,
                             spec->n, BKF_STABILITY_DIAGRAM_N_MAX);
    return BKF_OK;
}

int bkf_stability_check(const bkf_stability_spec *spec, const char *prefix, bkf_error *err)
{
    if (!spec) return bkf_error_set(err, BKF_EINPUT, "stability: spec is NULL");
    const char *p = prefix ? prefix : "";
    char a[32];
    /* The table's ranges again, for callers that fill the spec directly. */
    if (!(spec->c > 0) || !isfinite(spec->c))
        return bkf_error_set(err, BKF_EINPUT,
                             "%sc: c = %s is not > 0 (with c = 0 the fronts are phase waves of "
                             "uncoupled oscillators: every mode is neutral)",
                             p, bkf_format_number(spec->c, a, sizeof a));
    if (spec->n < 1 || spec->n > 1000000000u)
        return bkf_error_set(err, BKF_EINPUT, "%sn: n = %zu is not in [1, 1000000000]", p, spec->n);
    if (spec->root < 1 || spec->root > 1000000u)
        return bkf_error_set(err, BKF_EINPUT, "%sroot: root = %zu is not in [1, 1000000]", p,
                             spec->root);
    if (!(spec->tol >= TOL_MIN && spec->tol <= TOL_MAX))
        return bkf_error_set(err, BKF_EINPUT, "%stol: tol = %s is not in [1e-08, 0.01]", p,
                             bkf_format_number(spec->tol, a, sizeof a));
    if (spec->per_kappa < 1 || spec->per_kappa > PER_KAPPA_MAX)
        return bkf_error_set(err, BKF_EINPUT, "%sper-kappa: per-kappa = %zu is not in [1, 50]", p,
                             spec->per_kappa);
    if (spec->kappa_count < 1 || spec->kappa_count > BKF_STABILITY_KAPPA_MAX)
        return bkf_error_set(err, BKF_EINPUT,
                             "%skappa-count: kappa-count = %zu is not in [1, 100000]", p,
                             spec->kappa_count);
    int s = check_across(spec, p, err);
    if (s) return s;
    bkf_fronts_spec f = fronts_of(spec);
    return bkf_fronts_check(&f, prefix, err);
}

/* The root (n, root) of the speed condition, or BKF_EINPUT saying why
 * there is none. */
static int find_root(const bkf_stability_spec *spec, bkf_model_params *params,
                     bkf_speeds_root *root, bkf_error *err)
{
    bkf_fronts_spec f = fronts_of(spec);
    bkf_speeds_options o;
    bkf_fronts_setup(&f, params, &o);
    bkf_speeds_table t;
    int s = bkf_speeds_find(params, &o, &t, err);
    if (!s && t.count == 0) {
        if (t.n_max >= 0 && spec->n > (size_t)t.n_max)
            s = bkf_error_set(err, BKF_EINPUT,
                              "n: n = %zu has no front train: n_max = %ld at these parameters "
                              "(bkfront speeds lists the roots)",
                              spec->n, t.n_max);
        else
            s = bkf_error_set(err, BKF_EINPUT, "n: n = %zu has no root here: %s", spec->n,
                              t.note[0] ? t.note : "none found");
    } else if (!s && spec->root > t.count) {
        s = bkf_error_set(err, BKF_EINPUT, "root: root %zu, but n = %zu has %zu root%s",
                          spec->root, spec->n, t.count, t.count == 1 ? "" : "s");
    }
    if (!s) *root = t.roots[spec->root - 1];
    if (!s) s = bkf_speeds_root_status(root, err);
    bkf_speeds_table_free(&t);
    return s;
}

static int number_result(bkf_io_table *t, const char *name, double x, bkf_error *err)
{
    bkf_io_value v = {x, NULL};
    return bkf_io_table_result(t, name, BKF_IO_NUMBER, v, err);
}

static int text_result(bkf_io_table *t, const char *name, const char *text, bkf_error *err)
{
    bkf_io_value v = {0, text};
    return bkf_io_table_result(t, name, BKF_IO_TEXT, v, err);
}

/* The parameters, the root and the tolerance: the first comments and the
 * root's results of both tables. */
static int write_root(bkf_io_table *table, const bkf_stability_spec *spec,
                      const bkf_speeds_root *r, bkf_error *err)
{
    char a[32], b[32], c[32], d[32], e[32];
    int s = bkf_io_table_commentf(
        table, err, "gamma %s, c %s, nu %s, S %s; tol %s (absolute, on sigma)",
        bkf_format_number(spec->gamma, a, sizeof a), bkf_format_number(spec->c, b, sizeof b),
        bkf_format_number(spec->nu, c, sizeof c), bkf_format_number(spec->S, d, sizeof d),
        bkf_format_number(spec->tol, e, sizeof e));
    if (!s)
        s = bkf_io_table_commentf(table, err,
                                  "root: n %zu, root %zu, v %.17g, mu %.17g, T %.17g, L = S/n %.17g",
                                  r->n, spec->root, r->v, r->mu, r->T, r->wavelength);
    if (!s) s = number_result(table, "n", (double)r->n, err);
    if (!s) s = number_result(table, "root", (double)spec->root, err);
    if (!s) s = number_result(table, "v", r->v, err);
    if (!s) s = number_result(table, "mu", r->mu, err);
    if (!s) s = number_result(table, "T", r->T, err);
    return s;
}

static int write_ring(const bkf_stability_spec *spec, const bkf_speeds_root *root,
                      const bkf_trainspec_result *res, FILE *out, bkf_io_format format,
                      const bkf_provenance *prov, bkf_error *err)
{
    bkf_io_table *table;
    int s = bkf_product_table_open(
        out, format, ring_columns, NRING,
        "stability: the spectrum sigma of a train of n fronts on the ring, "
        "perturbations exp(sigma t + i kappa xi), kappa = 2 pi j / S",
        prov, &table, err);
    if (s) return s;
    if (!s) s = write_root(table, spec, root, err);
    const char *verdict = bkf_trainspec_verdict_name(res->verdict);
    bkf_trainspec_shown shown = bkf_trainspec_shown_of(res);
    const char *kind = shown.kind;
    char note[200];
    if (!s && isfinite(shown.bound))
        s = bkf_io_table_commentf(table, err, "stable: %s; %s", verdict,
                                  bkf_trainspec_bound_note(shown.bound, note, sizeof note));
    else if (!s)
        s = bkf_io_table_commentf(
            table, err,
            "stable: %s; sigma_max %.17g%+.17g i (err %.3g) at kappa %.17g, kind %s "
            "(the rightmost sigma but the translation)",
            verdict, shown.sigma_max, shown.sigma_max_im, shown.sigma_max_err, shown.kappa_max,
            kind);
    if (!s)
        s = bkf_io_table_commentf(table, err,
                                  "gauges: translation_residual %.3g (|sigma| of the mode "
                                  "sigma = 0), liouville_residual %.3g (|ln det M - ln m|)",
                                  res->translation_residual, res->liouville_residual);
    if (!s)
        s = bkf_io_table_commentf(
            table, err,
            "window: Re sigma > a_lo = %.6g, |Im sigma| <= y_max = %.6g (r_inf %.6g); "
            "work: %zu mesh steps per period, %zu monodromies, %zu heights (0: Hill's band "
            "alone), Hill's method at %zu modes (0: not used)",
            res->a_lo, res->y_max, res->r_inf, res->mesh_steps, res->evaluations,
            res->curve_points, res->hill_modes);
    if (!s) s = text_result(table, "stable", verdict, err);
    if (!s) s = number_result(table, "sigma_max", shown.sigma_max, err);
    if (!s) s = number_result(table, "sigma_max_im", shown.sigma_max_im, err);
    if (!s) s = number_result(table, "sigma_max_err", shown.sigma_max_err, err);
    if (!s) s = number_result(table, "kappa_max", shown.kappa_max, err);
    if (!s) s = number_result(table, "sigma_bound", shown.bound, err);
    if (!s) s = number_result(table, "hill_modes", (double)res->hill_modes, err);
    if (!s) s = text_result(table, "kind", kind, err);
    if (!s) s = number_result(table, "translation_residual", res->translation_residual, err);
    if (!s) s = number_result(table, "liouville_residual", res->liouville_residual, err);
    if (!s) s = number_result(table, "a_lo", res->a_lo, err);
    if (!s) s = number_result(table, "y_max", res->y_max, err);
    if (!s) s = number_result(table, "mesh_steps", (double)res->mesh_steps, err);
    if (!s) s = number_result(table, "evaluations", (double)res->evaluations, err);
    if (!s) s = bkf_product_table_command(table, prov, err);
    for (size_t i = 0; !s && i < res->count; i++) {
        const bkf_trainspec_eigenvalue *e = &res->eigenvalues[i];
        bkf_io_value v[NRING] = {{(double)e->j, NULL}, {e->kappa, NULL},
                                 {e->re, NULL},        {e->im, NULL},
                                 {e->err, NULL},       {e->translation ? 1 : 0, NULL}};
        s = bkf_io_table_row(table, v, err);
    }
    if (!s) s = bkf_io_table_finish(table, err);
    bkf_io_table_free(table);
    return s;
}

static int write_line(const bkf_stability_spec *spec, const bkf_speeds_root *root,
                      const bkf_trainspec_eigenvalue *e, size_t count, FILE *out,
                      bkf_io_format format, const bkf_provenance *prov, bkf_error *err)
{
    bkf_io_table *table;
    int s = bkf_product_table_open(
        out, format, line_columns, NLINE,
        "stability --line: the rightmost sigma of a train of fronts on the infinite line "
        "against the Bloch number kappa in [0, 2 pi / L)",
        prov, &table, err);
    if (s) return s;
    if (!s) s = write_root(table, spec, root, err);
    size_t top = 0;
    for (size_t i = 1; i < count; i++)
        if (e[i].re > e[top].re) top = i;
    if (!s)
        s = bkf_io_table_commentf(table, err,
                                  "%zu Bloch numbers; largest re %.17g (err %.3g) at kappa %.17g "
                                  "(the translation's branch passes through 0 at kappa 0)",
                                  count, e[top].re, e[top].err, e[top].kappa);
    if (!s) s = number_result(table, "kappa_count", (double)count, err);
    if (!s) s = number_result(table, "re_max", e[top].re, err);
    if (!s) s = number_result(table, "re_max_err", e[top].err, err);
    if (!s) s = number_result(table, "kappa_at_max", e[top].kappa, err);
    if (!s) s = bkf_product_table_command(table, prov, err);
    for (size_t i = 0; !s && i < count; i++) {
        bkf_io_value v[NLINE] = {
            {e[i].kappa, NULL}, {e[i].re, NULL}, {e[i].im, NULL}, {e[i].err, NULL}};
        s = bkf_io_table_row(table, v, err);
    }
    if (!s) s = bkf_io_table_finish(table, err);
    bkf_io_table_free(table);
    return s;
}

static bkf_stabmap_options stabmap_options_of(const bkf_stability_spec *spec)
{
    bkf_stabmap_options o = bkf_stabmap_options_default();
    o.tol = spec->tol;
    o.S_tol = spec->S_tol;
    o.nu_step = spec->nu_step;
    o.spectrum = spec->spectrum;
    o.spectrum_data = spec->spectrum_data;
    return o;
}

static bkf_model_params params_of(const bkf_stability_spec *spec)
{
    bkf_fronts_spec f = fronts_of(spec);
    bkf_model_params params;
    bkf_speeds_options o;
    bkf_fronts_setup(&f, &params, &o);
    return params;
}

/* The boundary's points, collected before the table is opened. */
typedef struct {
    bkf_stabmap_point *p;
    size_t n, cap;
} point_sink;

static int collect(const bkf_stabmap_point *pt, void *data)
{
    point_sink *k = data;
    if (k->n == k->cap) {
        size_t cap = k->cap ? 2 * k->cap : 32;
        bkf_stabmap_point *g = realloc(k->p, cap * sizeof *g);
        if (!g) return 1;
        k->p = g;
        k->cap = cap;
    }
    k->p[k->n++] = *pt;
    return 0;
}

static int write_boundary(const bkf_stability_spec *spec, FILE *out, bkf_io_format format,
                          const bkf_provenance *prov, bkf_error *err)
{
    bkf_model_params params = params_of(spec);
    bkf_stabmap_options o = stabmap_options_of(spec);
    bkf_stabmap_point first;
    int found;
    int s = bkf_stabmap_locate(&params, spec->n, spec->S, spec->S_to, spec->S_samples, &o,
                               &first, &found, err);
    if (!s && !found) {
        char a[32], b[32], c[32];
        return bkf_error_set(err, BKF_EINPUT,
                             "S-to: sigma_max of n = %zu does not change sign for S in [%s, %s] "
                             "at nu %s (%zu steps)",
                             spec->n, bkf_format_number(spec->S, a, sizeof a),
                             bkf_format_number(spec->S_to, b, sizeof b),
                             bkf_format_number(spec->nu, c, sizeof c), spec->S_samples);
    }
    if (s) return s;
    point_sink sink = {0};
    bkf_stabmap_report rep;
    s = bkf_stabmap_follow(&params, spec->n, &first, spec->to, &o, collect, &sink, &rep, err);
    if (!s && sink.n < rep.points)
        s = bkf_error_set(err, BKF_ENOMEM, "out of memory");
    bkf_io_table *table = NULL;
    if (!s)
        s = bkf_product_table_open(
            out, format, boundary_columns, NBOUNDARY,
            "stability --boundary: the S at which the train of n fronts changes stability "
            "(sigma_max = 0), followed in nu",
            prov, &table, err);
    char a[32], b[32], c[32], d[32];
    if (!s)
        s = bkf_io_table_commentf(
            table, err,
            "gamma %s, c %s, n %zu; nu from %s to %s in steps %.6g; tol %.3g (sigma), S-tol %.3g",
            bkf_format_number(spec->gamma, a, sizeof a), bkf_format_number(spec->c, b, sizeof b),
            spec->n, bkf_format_number(spec->nu, c, sizeof c),
            bkf_format_number(spec->to, d, sizeof d), spec->nu_step, spec->tol, spec->S_tol);
    if (!s)
        s = bkf_io_table_commentf(table, err,
                                  "end: %s after %zu points, %zu spectra; last nu tried %.6g%s%s",
                                  bkf_stabmap_end_name(rep.end), rep.points, rep.evaluations,
                                  rep.nu_end, rep.note[0] ? "; " : "", rep.note);
    for (size_t i = 0; !s && i < sink.n; i++)
        if (isfinite(sink.p[i].sigma_bound)) {
            char note[200];
            s = bkf_io_table_commentf(
                table, err, "at nu %s: %s", bkf_format_number(sink.p[i].nu, a, sizeof a),
                bkf_trainspec_bound_note(sink.p[i].sigma_bound, note, sizeof note));
        }
    if (!s) s = text_result(table, "end", bkf_stabmap_end_name(rep.end), err);
    if (!s) s = number_result(table, "points", (double)rep.points, err);
    if (!s) s = number_result(table, "evaluations", (double)rep.evaluations, err);
    if (!s) s = bkf_product_table_command(table, prov, err);
    for (size_t i = 0; !s && i < sink.n; i++) {
        const bkf_stabmap_point *q = &sink.p[i];
        bkf_io_value v[NBOUNDARY] = {{q->nu, NULL},    {q->S, NULL},         {q->S_err, NULL},
                                     {q->sigma, NULL}, {q->sigma_err, NULL}, {q->slope, NULL},
                                     {q->v, NULL},     {q->mu, NULL},
                                     {q->stable_above ? 1 : 0, NULL}};
        s = bkf_io_table_row(table, v, err);
    }
    if (!s) s = bkf_io_table_finish(table, err);
    bkf_io_table_free(table);
    free(sink.p);
    return s;
}

/* ------------------------------------------------------------ diagram */

typedef struct {
    size_t curve, n, m, seq;
    const char *kind;
    double nu, S, S_err, nu_err;
    int above;
} diagram_row;

typedef struct {
    diagram_row *r;
    size_t n, cap, curves;
    int failed;
    char **notes; /* comments on the curves' ends */
    size_t nnotes;
} diagram_sink;

/* What the diagram computed: ring spectra (a refused one too) and
 * eigenvalues continued alone (about 1/20 of a ring spectrum each). */
typedef struct {
    size_t spectra, tracked;
} diagram_work;

static void work_add(diagram_work *w, const bkf_stabmap_report *r)
{
    w->spectra += r->evaluations;
    w->tracked += r->tracked;
}

static int add_row(diagram_sink *k, const char *kind, size_t n, size_t m, double nu, double S,
                   double S_err, double nu_err, int above)
{
    if (k->n == k->cap) {
        size_t cap = k->cap ? 2 * k->cap : 256;
        diagram_row *g = realloc(k->r, cap * sizeof *g);
        if (!g) return k->failed = 1;
        k->r = g;
        k->cap = cap;
    }
    k->r[k->n] = (diagram_row){k->curves, n, m, k->n, kind, nu, S, S_err, nu_err, above};
    k->n++;
    return 0;
}

/* A note on the diagram (printf-style, as long as it needs); a failed
 * allocation fails the sink.  Returns nonzero on failure. */
static int add_note(diagram_sink *k, const char *fmt, ...)
#if defined(__GNUC__) || defined(__clang__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

static int add_note(diagram_sink *k, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int len = vsnprintf(NULL, 0, fmt, ap);
    va_end(ap);
    char *note = len < 0 ? NULL : malloc((size_t)len + 1);
    char **notes = realloc(k->notes, (k->nnotes + 1) * sizeof *notes);
    if (notes) k->notes = notes;
    if (!note || !notes) {
        free(note);
        return k->failed = 1;
    }
    va_start(ap, fmt);
    vsnprintf(note, (size_t)len + 1, fmt, ap);
    va_end(ap);
    k->notes[k->nnotes++] = note;
    return 0;
}

/* The oscillation's bands at one nu (a few suffice: period doubling and
 * long wave are the ones seen). */
#define DIAGRAM_BANDS 4
typedef struct {
    double lo[DIAGRAM_BANDS], hi[DIAGRAM_BANDS];
    int kind[DIAGRAM_BANDS];
    size_t count;
} nu_bands;

/* --scan: every crossing in S at every nu (a boundary may appear anywhere
 * along nu), joined into curves by nearness in S. */
static int scan_stability(const bkf_stability_spec *spec, const double *nus, size_t nnu,
                          const double *g, diagram_sink *k, diagram_work *work, bkf_error *err)
{
    bkf_model_params params = params_of(spec);
    bkf_stabmap_options o = stabmap_options_of(spec);
    double gap = 1.5 * (spec->S_to - spec->S) / (double)spec->S_samples;
    int s = BKF_OK;
    for (size_t n = 1; !s && n <= spec->n && !k->failed; n++) {
        size_t first_curve = k->curves + 1;
        double last_S[64];
        int last_above[64];
        size_t last_i[64], open = 0;
        for (size_t i = 0; !s && i < nnu; i++) {
            bkf_model_params p = params;
            p.nu = nus[i];
            double lo = fmax(spec->S, 1.05 * (double)n * g[i]);
            if (!(lo < spec->S_to)) continue;
            bkf_stabmap_point pts[16];
            size_t count;
            size_t samples = (size_t)ceil((double)spec->S_samples * (spec->S_to - lo) /
                                          (spec->S_to - spec->S));
            bkf_stabmap_report rep;
            s = bkf_stabmap_scan(&p, n, lo, spec->S_to, samples < 2 ? 2 : samples, &o, pts, 16,
                                 &count, &rep, err);
            work_add(work, &rep);
            /* no crossing: the whole column is stable or unstable, and one
             * spectrum says which (a phase diagram fills it); a refused or
             * undecided sigma leaves the column without a row */
            if (!s && count == 0) {
                bkf_model_params q = p;
                q.S = 0.5 * (lo + spec->S_to);
                double sg, sge, v, mu;
                bkf_error e;
                int t = bkf_stabmap_sigma(&q, n, 0, &o, &sg, &sge, &v, &mu, &work->spectra, &e);
                if (t == BKF_ENOMEM) s = bkf_error_set(err, t, "%s", e.message);
                if (!t && fabs(sg) > sge) {
                    size_t curves = k->curves;
                    k->curves = 0;
                    add_row(k, "state", n, 0, nus[i], q.S, 0, 0, sg < 0);
                    k->curves = curves;
                }
            }
            for (size_t j = 0; !s && j < count; j++) {
                size_t c = open;
                for (size_t q = 0; q < open; q++)
                    if (last_i[q] + 1 == i && last_above[q] == pts[j].stable_above &&
                        fabs(last_S[q] - pts[j].S) < gap)
                        c = q;
                if (c == open) {
                    if (open == 64) continue;
                    open++;
                }
                last_S[c] = pts[j].S;
                last_above[c] = pts[j].stable_above;
                last_i[c] = i;
                k->curves = first_curve + c;
                add_row(k, "stability", n, 0, pts[j].nu, pts[j].S, pts[j].S_err, 0,
                        pts[j].stable_above);
            }
        }
        k->curves = first_curve + open - 1;
    }
    return s;
}

/* ------------------------------------------- diagram: the followed curves */

/* A seed column's crossings at most (as the scan's rows). */
#define SEED_MAX 16

typedef struct {
    point_sink pts;            /* in order along the curve */
    bkf_stabmap_report end[2]; /* how each end came about: the first row's, the last's */
} traced_curve;

/* The work of one n: its seed crossings, its curves, its spectra. */
typedef struct {
    size_t n;
    traced_curve *c;
    size_t count;
    diagram_work work;
    int status;
    bkf_error err;
} n_work;

/* One seed column's scan in S of one n. */
typedef struct {
    size_t n, col;
    bkf_stabmap_point pts[SEED_MAX];
    size_t count;
    diagram_work work;
    int status;
    bkf_error err;
} seed_task;

/* Column i's bottom: the window's, or just above the existence boundary
 * (where the root's spectrum is the sonic limit's, refused). */
static double column_lo(const bkf_stability_spec *spec, size_t n, double g)
{
    return fmax(spec->S, 1.05 * (double)n * g);
}

/* The S of each crossing of curve c with the vertical nu = x, into S[]
 * (at most max), with the side that is stable above. */
static size_t curve_crossings(const traced_curve *c, double x, double *S, int *above, size_t max)
{
    size_t m = 0;
    const bkf_stabmap_point *p = c->pts.p;
    if (c->pts.n == 1 && p[0].nu == x && m < max) {
        S[m] = p[0].S;
        above[m++] = p[0].stable_above;
    }
    for (size_t i = 0; i + 1 < c->pts.n && m < max; i++) {
        double a = p[i].nu, b = p[i + 1].nu;
        /* half-open, so a vertex on x counts once */
        if (!((a <= x && x < b) || (b < x && x <= a) || (i + 2 == c->pts.n && b == x))) continue;
        double t = b == a ? 0 : (x - a) / (b - a);
        S[m] = p[i].S + t * (p[i + 1].S - p[i].S);
        above[m++] = t < 0.5 ? p[i].stable_above : p[i + 1].stable_above;
    }
    return m;
}

static int on_a_curve(const n_work *w, const bkf_stabmap_point *pt, double gap)
{
    double S[SEED_MAX];
    int above[SEED_MAX];
    for (size_t c = 0; c < w->count; c++) {
        size_t m = curve_crossings(&w->c[c], pt->nu, S, above, SEED_MAX);
        for (size_t j = 0; j < m; j++)
            if (fabs(S[j] - pt->S) < gap && above[j] == pt->stable_above) return 1;
    }
    return 0;
}

/* The curve through seed point `pt`: traced both ways in nu, the way
 * towards lower nu reversed in front. */
static int trace_both_ways(const bkf_stability_spec *spec, const bkf_model_params *params,
                           size_t n, const bkf_stabmap_point *pt, const bkf_stabmap_window *win,
                           const bkf_stabmap_options *o, traced_curve *c, diagram_work *work,
                           bkf_error *err)
{
    (void)spec;
    point_sink half[2] = {{0}, {0}};
    int s = BKF_OK;
    for (int d = 0; !s && d < 2; d++) {
        s = bkf_stabmap_trace(params, n, pt, d ? 1 : -1, win, o, collect, &half[d], &c->end[d],
                              err);
        if (!s && half[d].n < c->end[d].points) s = bkf_error_set(err, BKF_ENOMEM, "out of memory");
        if (!s) work_add(work, &c->end[d]);
    }
    if (!s) {
        /* Each half starts at the seed as its run corrected it; a half that
         * stood on the window's edge has only the seed as the scan closed it
         * (S to the seed's S-tol): the other half's start replaces it. */
        size_t skip0 = half[0].n == 1 && half[1].n > 1, skip1 = !skip0 && half[0].n >= 1;
        size_t n0 = half[0].n - skip0, n1 = half[1].n - (half[1].n ? skip1 : 0);
        size_t total = n0 + n1;
        c->pts.p = malloc((total ? total : 1) * sizeof *c->pts.p);
        if (!c->pts.p) s = bkf_error_set(err, BKF_ENOMEM, "out of memory");
        for (size_t i = 0; !s && i < n0; i++) c->pts.p[i] = half[0].p[half[0].n - 1 - i];
        for (size_t i = 0; !s && i < n1; i++) c->pts.p[n0 + i] = half[1].p[half[1].n - n1 + i];
        c->pts.n = c->pts.cap = s ? 0 : total;
    }
    free(half[0].p);
    free(half[1].p);
    return s;
}

/* The work cap of a followed curve, each way from its seed: steps are at
 * most nu_step in nu and a scan step in S (1 in the scaled norm), so a
 * curve monotone in both crosses the window in (nu extent / nu_step + S
 * extent / S step) full steps; twice that allows steps of half on average
 * or one turn.  A curve that needs more (steps shrunk at a corner of
 * sigma_max, a curve winding) is cut there and said to be cut. */
static size_t trace_cap(const bkf_stability_spec *spec, const bkf_stabmap_window *win)
{
    double steps = ceil((win->nu_hi - win->nu_lo) / spec->nu_step - 1e-9) +
                   (double)spec->S_samples;
    return 2 * (size_t)steps + 2;
}

/* Every crossing of n's seed columns that no curve found so far passes,
 * followed. */
static void follow_n(const bkf_stability_spec *spec, const seed_task *seeds, size_t ncol,
                     const bkf_stabmap_window *win, n_work *w)
{
    bkf_model_params params = params_of(spec);
    bkf_stabmap_options o = stabmap_options_of(spec);
    o.S_step = (spec->S_to - spec->S) / (double)spec->S_samples;
    o.max_points = trace_cap(spec, win);
    double gap = 1.5 * o.S_step;
    for (size_t k = 0; !w->status && k < ncol; k++) {
        const seed_task *t = &seeds[k];
        for (size_t j = 0; !w->status && j < t->count; j++) {
            if (on_a_curve(w, &t->pts[j], gap)) continue;
            traced_curve *g = realloc(w->c, (w->count + 1) * sizeof *g);
            if (!g) {
                w->status = bkf_error_set(&w->err, BKF_ENOMEM, "out of memory");
                break;
            }
            w->c = g;
            memset(&w->c[w->count], 0, sizeof *w->c);
            w->status = trace_both_ways(spec, &params, w->n, &t->pts[j], win, &o,
                                        &w->c[w->count], &w->work, &w->err);
            if (!w->status) w->count++;
        }
    }
}

/* A run of grid columns where n exists and no curve crosses: one sign
 * throughout (no curve has a point between its columns either) if every
 * boundary was found: the spectra at its middle column's middle S and at
 * its two end columns give its state when they agree. */
typedef struct {
    size_t n, first, last, mid;
    double S;
    int status, stable; /* stable: 1, 0, or -1 (undecided) */
    int split;          /* its ends' spectra disagree */
    size_t spectra;     /* ring spectra computed */
} state_run;

static int curves_between(const n_work *w, double a, double b)
{
    double lo = fmin(a, b), hi = fmax(a, b);
    for (size_t c = 0; c < w->count; c++)
        for (size_t i = 0; i < w->c[c].pts.n; i++)
            if (w->c[c].pts.p[i].nu > lo && w->c[c].pts.p[i].nu < hi) return 1;
    return 0;
}

/* The seed columns' number: grid columns about seed_step apart, both ends
 * included. */
static size_t seed_column_count(const bkf_stability_spec *spec, const double *nus, size_t nnu)
{
    size_t ncol = (size_t)ceil(fabs(nus[nnu - 1] - nus[0]) / spec->seed_step - 1e-9) + 1;
    if (ncol > nnu) ncol = nnu;
    if (ncol < 2 && nnu > 1) ncol = 2;
    return ncol;
}

/* 1. The seed grid: each of every n's seed columns scanned in S, its sign
 * changes closed.  seeds[] holds n * ncol tasks, n's columns together. */
static int scan_seeds(const bkf_stability_spec *spec, const double *nus, const double *g,
                      const size_t *col, size_t ncol, seed_task *seeds, int threads,
                      diagram_work *work, bkf_error *err)
{
    (void)threads;
    bkf_model_params params = params_of(spec);
    /* A seed needs S only to within its curve's continuation, which
     * corrects it: its bracket is closed to 3% of a scan step. */
    bkf_stabmap_options seed_o = stabmap_options_of(spec);
    seed_o.S_tol = fmax(seed_o.S_tol, 0.03 * (spec->S_to - spec->S) / (double)spec->S_samples);
    size_t ntask = spec->n * ncol;
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
    for (size_t i = 0; i < ntask; i++) {
        seed_task *t = &seeds[i];
        t->n = i / ncol + 1;
        t->col = col[i % ncol];
        bkf_model_params p = params;
        p.nu = nus[t->col];
        double lo = column_lo(spec, t->n, g[t->col]);
        if (!(lo < spec->S_to)) continue;
        size_t samples = (size_t)ceil((double)spec->S_samples * (spec->S_to - lo) /
                                      (spec->S_to - spec->S));
        if (samples < 2) samples = 2;
        /* Scanned down from S_to: the samples are the same, but the column's
         * bottom, 1.05 times the existence boundary (mu near 27 at gamma 2),
         * is reached from above, where it is mostly unstable and proven so
         * by the eigenvalue continued from the sample above (a few ms)
         * instead of its ring spectrum (about 1 s there, the first sample of
         * an upward scan: 12 of the paper scene's 19 s of seed scans). */
        bkf_stabmap_report rep;
        t->status = bkf_stabmap_scan(&p, t->n, spec->S_to, lo, samples, &seed_o, t->pts, SEED_MAX,
                                     &t->count, &rep, &t->err);
        work_add(&t->work, &rep);
    }
    int s = BKF_OK;
    for (size_t i = 0; !s && i < ntask; i++) {
        if (seeds[i].status) s = bkf_error_set(err, seeds[i].status, "%s", seeds[i].err.message);
        work->spectra += seeds[i].work.spectra;
        work->tracked += seeds[i].work.tracked;
    }
    return s;
}

/* 2. The curves through the seeds, each n on its own (w[n - 1]). */
static int follow_seeds(const bkf_stability_spec *spec, const double *nus, size_t nnu,
                        const seed_task *seeds, size_t ncol, n_work *w, int threads,
                        diagram_work *work, bkf_error *err)
{
    (void)threads;
    bkf_stabmap_window win = {fmin(nus[0], nus[nnu - 1]), fmax(nus[0], nus[nnu - 1]), spec->S,
                              spec->S_to};
    size_t nn = spec->n;
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
    for (size_t i = 0; i < nn; i++) {
        w[i].n = i + 1;
        follow_n(spec, seeds + i * ncol, ncol, &win, &w[i]);
    }
    int s = BKF_OK;
    for (size_t i = 0; !s && i < nn; i++) {
        if (w[i].status) s = bkf_error_set(err, w[i].status, "%s", w[i].err.message);
        work->spectra += w[i].work.spectra;
        work->tracked += w[i].work.tracked;
    }
    return s;
}

/* The crossings at nu of the first of wn's curves that has any (into S[]
 * and above[], SEED_MAX at most): their number. */
static size_t crossings_at(const n_work *wn, double nu, double *S, int *above)
{
    size_t m = 0;
    for (size_t c = 0; c < wn->count && !m; c++)
        m = curve_crossings(&wn->c[c], nu, S, above, SEED_MAX);
    return m;
}

/* 3. The runs of grid columns where n exists and no curve crosses,
 * appended to runs[] (each with its middle column and S, no state yet). */
static int free_runs(const bkf_stability_spec *spec, const double *nus, size_t nnu,
                     const double *g, const n_work *w, state_run **runs, size_t *nruns,
                     bkf_error *err)
{
    int s = BKF_OK;
    for (size_t i = 0; !s && i < spec->n; i++) {
        size_t n = i + 1;
        state_run cur = {0};
        int open = 0;
        for (size_t j = 0; j <= nnu; j++) {
            int free_col = 0;
            if (j < nnu && column_lo(spec, n, g[j]) < spec->S_to) {
                double S[SEED_MAX];
                int above[SEED_MAX];
                free_col = crossings_at(&w[i], nus[j], S, above) == 0;
            }
            if (open && (!free_col || curves_between(&w[i], nus[cur.last], nus[j]))) {
                state_run *r = realloc(*runs, (*nruns + 1) * sizeof *r);
                if (!r) {
                    s = bkf_error_set(err, BKF_ENOMEM, "out of memory");
                    break;
                }
                *runs = r;
                cur.mid = (cur.first + cur.last) / 2;
                cur.S = 0.5 * (column_lo(spec, n, g[cur.mid]) + spec->S_to);
                (*runs)[(*nruns)++] = cur;
                open = 0;
            }
            if (free_col && !open) {
                cur = (state_run){n, j, j, j, 0, 0, -1, 0, 0};
                open = 1;
            } else if (free_col) {
                cur.last = j;
            }
        }
    }
    return s;
}

/* A run's state: the spectra at its middle and both ends, at its S.  A
 * boundary that crossed no seed column shows as ends that disagree (split),
 * and the run gets no state; so does a refused or undecided sigma. */
static void decide_run(const bkf_model_params *params, const double *nus,
                       const bkf_stabmap_options *o, state_run *run)
{
    bkf_model_params q = *params;
    q.nu = nus[run->mid];
    q.S = run->S;
    const size_t at[3] = {run->mid, run->first, run->last};
    int verdict[3] = {-1, -1, -1};
    for (int k = 0; k < 3 && !run->status; k++) {
        if (k && at[k] == run->mid) {
            verdict[k] = verdict[0];
            continue;
        }
        double sg, sge, v, mu;
        bkf_error e;
        q.nu = nus[at[k]];
        run->status = bkf_stabmap_sigma(&q, run->n, 0, o, &sg, &sge, &v, &mu, &run->spectra, &e);
        if (!run->status && fabs(sg) > sge) verdict[k] = sg < 0;
    }
    run->split = verdict[0] >= 0 && verdict[1] >= 0 && verdict[2] >= 0 &&
                 (verdict[1] != verdict[0] || verdict[2] != verdict[0]);
    if (!run->status && !run->split && verdict[1] == verdict[0] && verdict[2] == verdict[0])
        run->stable = verdict[0];
}

/* The runs' spectra counted; a split run said in a note (its state is not
 * guessed). */
static int note_split_runs(const double *nus, const state_run *runs, size_t nruns,
                           diagram_sink *k, diagram_work *work, bkf_error *err)
{
    int s = BKF_OK;
    for (size_t r = 0; !s && r < nruns; r++) {
        if (runs[r].status == BKF_ENOMEM) s = bkf_error_set(err, BKF_ENOMEM, "out of memory");
        work->spectra += runs[r].spectra;
        if (!runs[r].split || k->failed) continue;
        add_note(k,
                 "n %zu: between nu %.6g and %.6g (S %.6g) the spectra change sign with no "
                 "followed curve between: a stability boundary crossed no seed column and is not "
                 "followed; no state there",
                 runs[r].n, nus[runs[r].first], nus[runs[r].last], runs[r].S);
    }
    return s;
}

/* The rows of the followed curves, by n, each with a note on how its two
 * ends came about. */
static void emit_curves(const n_work *w, size_t nn, diagram_sink *k)
{
    for (size_t i = 0; i < nn; i++)
        for (size_t c = 0; c < w[i].count; c++) {
            const traced_curve *tc = &w[i].c[c];
            k->curves++;
            for (size_t j = 0; j < tc->pts.n; j++) {
                const bkf_stabmap_point *q = &tc->pts.p[j];
                add_row(k, "stability", w[i].n, 0, q->nu, q->S, q->S_err, q->nu_err,
                        q->stable_above);
            }
            const bkf_stabmap_point *a = &tc->pts.p[0], *b = &tc->pts.p[tc->pts.n - 1];
            if (add_note(k,
                         "curve %zu (n %zu): %zu points, %zu spectra; ends at nu %.6g, S %.6g: "
                         "%s%s%.250s; at nu %.6g, S %.6g: %s%s%.250s",
                         k->curves, w[i].n, tc->pts.n,
                         tc->end[0].evaluations + tc->end[1].evaluations, a->nu, a->S,
                         bkf_stabmap_end_name(tc->end[0].end), tc->end[0].note[0] ? ", " : "",
                         tc->end[0].note, b->nu, b->S, bkf_stabmap_end_name(tc->end[1].end),
                         tc->end[1].note[0] ? ", " : "", tc->end[1].note))
                break;
        }
}

/* A run's state against its neighbour column's crossings: where the side
 * of that column's top (or bottom) interval differs from the run's state
 * and no curve has a point between them, a boundary lies there that
 * crossed no seed column; it is said, not guessed. */
static void note_unfollowed_boundaries(const double *nus, size_t nnu, const state_run *runs,
                                       size_t nruns, const n_work *w, diagram_sink *k)
{
    for (size_t r = 0; r < nruns; r++) {
        const state_run *q = &runs[r];
        const n_work *wn = &w[q->n - 1];
        for (int side = 0; q->stable >= 0 && side < 2 && !k->failed; side++) {
            if (side ? q->last + 1 >= nnu : q->first == 0) continue;
            size_t j = side ? q->last + 1 : q->first - 1, edge = side ? q->last : q->first;
            double S[SEED_MAX];
            int above[SEED_MAX];
            size_t m = crossings_at(wn, nus[j], S, above);
            if (!m || curves_between(wn, nus[edge], nus[j])) continue;
            size_t top = 0, bottom = 0;
            for (size_t i = 1; i < m; i++) {
                if (S[i] > S[top]) top = i;
                if (S[i] < S[bottom]) bottom = i;
            }
            /* above a crossing its `above` side, below it the other */
            if (above[top] == q->stable && (!above[bottom]) == q->stable) continue;
            if (add_note(k,
                         "n %zu: between nu %.6g and %.6g a stability boundary crossed no seed "
                         "column and is not followed (the spectrum at nu %.6g, S %.6g is %s; the "
                         "curves at nu %.6g say otherwise there)",
                         q->n, nus[edge], nus[j], nus[q->mid], q->S,
                         q->stable ? "stable" : "unstable", nus[j]))
                break;
        }
    }
}

/* A curve that ends where the continuation could not go on (its work cap,
 * or a step fallen below its minimum): the boundary goes on unseen.  A
 * stall at a turn in nu (gamma 1, c 0.6, n 3, nu -0.891, S 11.09) left the
 * turn's upper half, back to nu -0.95 at S 11.44, undrawn, and the states
 * then called the columns stable above the lower half all the way up. */
static int ends_unseen(bkf_stabmap_end e)
{
    return e == BKF_STABMAP_END_POINTS || e == BKF_STABMAP_END_STALLED;
}

static int has_cut_curve(const n_work *w)
{
    for (size_t c = 0; c < w->count; c++)
        if (ends_unseen(w->c[c].end[0].end) || ends_unseen(w->c[c].end[1].end)) return 1;
    return 0;
}

/* The decided runs' states, as rows of curve 0; none for an n with a cut
 * or stalled curve: where its rest goes is not known, so no column away
 * from the drawn points has a state (the figure hatches them). */
static void emit_states(const double *nus, const state_run *runs, size_t nruns, const n_work *w,
                        size_t nn, diagram_sink *k)
{
    for (size_t i = 0; i < nn && !k->failed; i++)
        if (has_cut_curve(&w[i]))
            add_note(k,
                     "n %zu: a curve cut at its work cap (max_points) or stalled: the rest not followed, "
                     "no state rows for n %zu (undecided away from the curves)",
                     w[i].n, w[i].n);
    for (size_t r = 0; r < nruns; r++) {
        if (runs[r].stable < 0 || has_cut_curve(&w[runs[r].n - 1])) continue;
        size_t curves = k->curves;
        k->curves = 0;
        add_row(k, "state", runs[r].n, 0, nus[runs[r].mid], runs[r].S, 0, 0, runs[r].stable);
        k->curves = curves;
    }
}

/* The stability boundaries followed from seeds: a coarse grid of seed
 * columns scanned in S, a curve continued through every crossing no curve
 * passes yet, and the columns between curves given a state of their own. */
static int follow_stability(const bkf_stability_spec *spec, const double *nus, size_t nnu,
                            const double *g, diagram_sink *k, diagram_work *work, bkf_error *err)
{
    size_t N = spec->n;
    size_t ncol = seed_column_count(spec, nus, nnu);
    size_t *col = malloc(ncol * sizeof *col);
    seed_task *seeds = calloc(N * ncol, sizeof *seeds);
    n_work *w = calloc(N, sizeof *w);
    state_run *runs = NULL;
    size_t nruns = 0;
    int s = col && seeds && w ? BKF_OK : bkf_error_set(err, BKF_ENOMEM, "out of memory");
    int threads = bkf_product_threads(spec->threads);
    for (size_t c = 0; !s && c < ncol; c++)
        col[c] = ncol == 1 ? 0 : (size_t)llround((double)c * (double)(nnu - 1) / (double)(ncol - 1));
    if (!s) s = scan_seeds(spec, nus, g, col, ncol, seeds, threads, work, err);
    if (!s) s = follow_seeds(spec, nus, nnu, seeds, ncol, w, threads, work, err);
    if (!s) s = free_runs(spec, nus, nnu, g, w, &runs, &nruns, err);
    if (!s) {
        bkf_model_params params = params_of(spec);
        bkf_stabmap_options o = stabmap_options_of(spec);
        (void)threads;
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
        for (size_t r = 0; r < nruns; r++) decide_run(&params, nus, &o, &runs[r]);
        s = note_split_runs(nus, runs, nruns, k, work, err);
    }
    if (!s) {
        /* the rows: curves by n, then the states (curve 0) */
        emit_curves(w, N, k);
        note_unfollowed_boundaries(nus, nnu, runs, nruns, w, k);
        emit_states(nus, runs, nruns, w, N, k);
    }
    for (size_t i = 0; w && i < N; i++) {
        for (size_t c = 0; c < w[i].count; c++) free(w[i].c[c].pts.p);
        free(w[i].c);
    }
    free(w);
    free(seeds);
    free(col);
    free(runs);
    return s;
}

static int diagram_curves(const bkf_stability_spec *spec, const double *nus, size_t nnu,
                          diagram_sink *k, diagram_work *work, bkf_error *err)
{
    bkf_model_params params = params_of(spec);
    double *g = calloc(nnu, sizeof *g);
    nu_bands *b = calloc(nnu, sizeof *b);
    int s = g && b ? BKF_OK : bkf_error_set(err, BKF_ENOMEM, "out of memory");
    /* existence: S = n c gamma g_inf(nu), one speeds solve per nu for every n */
    for (size_t i = 0; !s && i < nnu; i++) {
        bkf_model_params p = params;
        p.nu = nus[i];
        int attained;
        s = bkf_stabmap_existence(&p, 1, &g[i], &attained, err);
    }
    for (size_t n = 1; !s && n <= spec->n; n++) {
        k->curves++;
        for (size_t i = 0; i < nnu; i++)
            if (add_row(k, "existence", n, 0, nus[i], (double)n * g[i], 0, 0, 1)) break;
    }
    if (!s && !k->failed)
        s = spec->scan ? scan_stability(spec, nus, nnu, g, k, work, err)
                       : follow_stability(spec, nus, nnu, g, k, work, err);
    /* the oscillation: its unstable bands per nu, then one curve per edge */
    int threads = bkf_product_threads(spec->threads);
    (void)threads;
    int *bs = s ? NULL : calloc(nnu, sizeof *bs);
    bkf_error *be = s ? NULL : calloc(nnu, sizeof *be);
    if (!s && (!bs || !be)) s = bkf_error_set(err, BKF_ENOMEM, "out of memory");
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads)
    for (size_t i = 0; i < (s ? 0 : nnu); i++)
        bs[i] = bkf_stabmap_bands(spec->gamma, spec->c, nus[i], 6, 120, 1e-7, b[i].lo, b[i].hi,
                                  b[i].kind, DIAGRAM_BANDS, &b[i].count, &be[i]);
    for (size_t i = 0; !s && i < nnu; i++)
        if (bs[i]) s = bkf_error_set(err, bs[i], "%s", be[i].message);
    free(bs);
    free(be);
    double two_pi_c = 6.283185307179586477 * spec->c;
    /* long wave: unstable for S > 2 pi c / p_b (m = 1 is in the band first) */
    if (!s) {
        k->curves++;
        int open = 0;
        for (size_t i = 0; i < nnu; i++) {
            int here = 0;
            for (size_t j = 0; j < b[i].count; j++)
                if (b[i].lo[j] == 0) {
                    add_row(k, "long_wave", 0, 1, nus[i], two_pi_c / b[i].hi[j], 0, 0, 0);
                    here = 1;
                }
            /* a nu without the band ends the curve: the next piece is another */
            if (open && !here) k->curves++;
            open = here;
        }
    }
    /* finite-q bands: tongue m between 2 pi m c / p_b (unstable above) and
     * 2 pi m c / p_a (stable above) */
    for (size_t m = 1; !s && m < 100000; m++) {
        int any = 0;
        for (int edge = 0; edge < 2; edge++) {
            k->curves++;
            for (size_t i = 0; i < nnu; i++)
                for (size_t j = 0; j < b[i].count; j++) {
                    if (b[i].lo[j] == 0) continue;
                    double S = two_pi_c * (double)m / (edge ? b[i].lo[j] : b[i].hi[j]);
                    if (two_pi_c * (double)m / b[i].hi[j] > spec->S_to) continue;
                    any = 1;
                    add_row(k, b[i].kind[j] ? "period_doubling" : "other", 0, m, nus[i], S, 0,
                            0, edge);
                }
        }
        if (!any) {
            k->curves -= 2;
            break;
        }
    }
    if (!s && k->failed) s = bkf_error_set(err, BKF_ENOMEM, "out of memory");
    free(g);
    free(b);
    return s;
}

/* Rows by curve, each curve in the order it was found (along nu). */
static int by_curve(const void *a, const void *b)
{
    const diagram_row *x = a, *y = b;
    if (x->curve != y->curve) return x->curve < y->curve ? -1 : 1;
    return x->seq < y->seq ? -1 : x->seq > y->seq;
}

static int write_diagram(const bkf_stability_spec *spec, FILE *out, bkf_io_format format,
                         const bkf_provenance *prov, bkf_error *err)
{
    double dir = spec->to > spec->nu ? 1 : -1;
    size_t nnu = (size_t)floor(fabs(spec->to - spec->nu) / spec->nu_step + 1e-9) + 1;
    double *nus = malloc((nnu + 1) * sizeof *nus);
    if (!nus) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    for (size_t i = 0; i < nnu; i++) nus[i] = spec->nu + dir * (double)i * spec->nu_step;
    if (fabs(nus[nnu - 1] - spec->to) > 1e-9 * spec->nu_step) nus[nnu++] = spec->to;
    diagram_sink k = {0};
    diagram_work work = {0, 0};
    int s = diagram_curves(spec, nus, nnu, &k, &work, err);
    free(nus);
    if (!s) qsort(k.r, k.n, sizeof *k.r, by_curve);
    bkf_io_table *table = NULL;
    if (!s)
        s = bkf_product_table_open(
            out, format, diagram_columns, NDIAGRAM,
            "stability --diagram: where each train of n fronts exists and is stable in the "
            "(nu, S) plane, and where the global oscillation is unstable",
            prov, &table, err);
    char a[32], b[32], c[32], d[32], e[32], f[32];
    if (!s)
        s = bkf_io_table_commentf(
            table, err, "gamma %s, c %s, n = 1..%zu; nu from %s to %s in steps %.6g; S in [%s, %s]; "
            "tol %.3g (sigma), S-tol %.3g",
            bkf_format_number(spec->gamma, a, sizeof a), bkf_format_number(spec->c, b, sizeof b),
            spec->n, bkf_format_number(spec->nu, c, sizeof c),
            bkf_format_number(spec->to, d, sizeof d), spec->nu_step,
            bkf_format_number(spec->S, e, sizeof e), bkf_format_number(spec->S_to, f, sizeof f),
            spec->tol, spec->S_tol);
    if (!s)
        s = bkf_io_table_commentf(
            table, err,
            "kinds: existence (S = n c gamma g_inf(nu): trains exist above), stability "
            "(sigma_max = 0; above 1: stable above; S_err, nu_err: the point's error at fixed "
            "nu, at fixed S), state (curve 0: a nu where n has no crossing in S, its spectrum "
            "at S, which holds for the run of such columns around it that no curve enters, its "
            "ends' spectra the same; "
            "above 1: stable there), long_wave and "
            "period_doubling (the oscillation's mode q = 2 pi m / S at a band edge; above 1: "
            "stable above)");
    if (!s && spec->scan)
        s = bkf_io_table_commentf(table, err,
                                  "work: %zu spectra and %zu eigenvalues continued alone (a "
                                  "scan in S of %zu steps per n and nu, each crossing closed to "
                                  "S-tol)",
                                  work.spectra, work.tracked, spec->S_samples);
    if (!s && !spec->scan)
        s = bkf_io_table_commentf(
            table, err,
            "work: %zu ring spectra and %zu eigenvalues continued alone (each about 1/20 of a "
            "spectrum; seed columns about %.6g apart in nu, each scanned in S in %zu "
            "steps; every crossing no curve passes followed by pseudo-arclength continuation in "
            "(nu, S), steps at most %.6g in nu and %.6g in S; three spectra per run of columns "
            "no curve crosses: the state rows)",
            work.spectra, work.tracked, spec->seed_step, spec->S_samples, spec->nu_step,
            (spec->S_to - spec->S) / (double)spec->S_samples);
    for (size_t i = 0; !s && i < k.nnotes; i++) s = bkf_io_table_commentf(table, err, "%s", k.notes[i]);
    if (!s) s = number_result(table, "curves", (double)k.curves, err);
    if (!s) s = number_result(table, "spectra", (double)work.spectra, err);
    if (!s) s = number_result(table, "tracked", (double)work.tracked, err);
    if (!s) s = bkf_product_table_command(table, prov, err);
    for (size_t i = 0; !s && i < k.n; i++) {
        const diagram_row *r = &k.r[i];
        bkf_io_value v[NDIAGRAM] = {{(double)r->curve, NULL}, {0, r->kind},
                                    {(double)r->n, NULL},     {(double)r->m, NULL},
                                    {r->nu, NULL},            {r->S, NULL},
                                    {r->S_err, NULL},         {r->above, NULL},
                                    {r->nu_err, NULL}};
        s = bkf_io_table_row(table, v, err);
    }
    if (!s) s = bkf_io_table_finish(table, err);
    bkf_io_table_free(table);
    free(k.r);
    for (size_t i = 0; i < k.nnotes; i++) free(k.notes[i]);
    free(k.notes);
    return s;
}

int bkf_stability_write(const bkf_stability_spec *spec, FILE *out, bkf_io_format format,
                        const bkf_provenance *prov, bkf_error *err)
{
    int s = bkf_stability_check(spec, "", err);
    if (s) return s;
    if (spec->boundary) return write_boundary(spec, out, format, prov, err);
    if (spec->diagram) return write_diagram(spec, out, format, prov, err);
    bkf_model_params params;
    bkf_speeds_root root;
    s = find_root(spec, &params, &root, err);
    if (s) return s;
    if (spec->line) {
        bkf_trainspec_eigenvalue *e = calloc(spec->kappa_count, sizeof *e);
        if (!e) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
        bkf_trainspec_train train = {root.n, root.v};
        bkf_trainspec_options o = bkf_trainspec_options_default();
        o.tol = spec->tol;
        o.per_kappa = spec->per_kappa;
        s = bkf_trainspec_line(&params, &train, &o, spec->kappa_count, e, err);
        if (!s) s = write_line(spec, &root, e, spec->kappa_count, out, format, prov, err);
        free(e);
        return s;
    }
    bkf_trainspec_result res;
    s = bkf_trainspec_root(&params, &root, spec->tol, spec->per_kappa, &res, err);
    if (!s) s = write_ring(spec, &root, &res, out, format, prov, err);
    bkf_trainspec_result_free(&res);
    return s;
}

#include "bkfront/stability.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bkfront/fronts.h"

#include "product_internal.h"

static const bkf_io_column ring_columns[] = {
    {"j", BKF_IO_NUMBER},   {"kappa", BKF_IO_NUMBER}, {"re", BKF_IO_NUMBER},
    {"im", BKF_IO_NUMBER},  {"err", BKF_IO_NUMBER},   {"translation", BKF_IO_NUMBER}};
static const bkf_io_column line_columns[] = {
    {"kappa", BKF_IO_NUMBER}, {"re", BKF_IO_NUMBER}, {"im", BKF_IO_NUMBER}, {"err", BKF_IO_NUMBER}};
#define NRING (sizeof ring_columns / sizeof ring_columns[0])
#define NLINE (sizeof line_columns / sizeof line_columns[0])

/* trainspec's ranges (trainspec.h), repeated in the table for the messages. */
#define TOL_MIN 1e-10
#define TOL_MAX 1e-2
#define PER_KAPPA_MAX 50

#define BOUNDED (BKF_OPT_MIN | BKF_OPT_MAX)
#define FIELD(f) offsetof(bkf_stability_spec, f)

const bkf_option bkf_stability_options[] = {
    BKF_PRODUCT_GAMMA_OPTION(bkf_stability_spec, BKF_OPT_REQUIRED),
    {.name = "c", .type = BKF_OPT_DOUBLE, .offset = FIELD(c),
     .flags = BKF_OPT_REQUIRED | BKF_OPT_MIN | BKF_OPT_MIN_OPEN, .min = 0, .form = "C",
     .help = "sound speed, > 0 (with c = 0 every mode is neutral)"},
    BKF_PRODUCT_NU_OPTION(bkf_stability_spec, BKF_OPT_REQUIRED),
    BKF_PRODUCT_S_OPTION(bkf_stability_spec, BKF_OPT_REQUIRED),
    {.name = "n", .type = BKF_OPT_COUNT, .offset = FIELD(n),
     .flags = BKF_OPT_REQUIRED | BOUNDED, .min = 1, .max = 1e9, .form = "N",
     .help = "required; number of fronts (at most n_max, as listed by\n"
             "bkfront speeds)"},
    {.name = "root", .type = BKF_OPT_COUNT, .offset = FIELD(root), .flags = BOUNDED, .min = 1,
     .max = 1e6, .form = "I", .shown_default = "1",
     .help = "which root of this n, 1 being the fastest (as listed by\n"
             "bkfront speeds)"},
    {.name = "tol", .type = BKF_OPT_DOUBLE, .offset = FIELD(tol), .flags = BOUNDED,
     .min = TOL_MIN, .max = TOL_MAX, .form = "E", .shown_default = "1e-6",
     .help = "absolute accuracy asked of each sigma, in [1e-10, 0.01]"},
    {.name = "per-kappa", .type = BKF_OPT_COUNT, .offset = FIELD(per_kappa), .flags = BOUNDED,
     .min = 1, .max = PER_KAPPA_MAX, .form = "K", .shown_default = "3",
     .help = "eigenvalues reported per Bloch number (the rightmost K),\n"
             "in [1, 50]"},
    {.name = "line", .type = BKF_OPT_SWITCH, .offset = FIELD(line),
     .help = "the infinite line's spectrum instead of the ring's: the\n"
             "rightmost sigma for kappa in [0, 2 pi/L), L = S/n"},
    {.name = "kappa-count", .type = BKF_OPT_COUNT, .offset = FIELD(kappa_count),
     .flags = BOUNDED, .min = 1, .max = BKF_STABILITY_KAPPA_MAX, .form = "M",
     .shown_default = "64", .help = "with --line: M Bloch numbers kappa = (2 pi/L) i/M,\n"
                                     "i = 0..M-1, in [1, 100000]"},
};
const size_t bkf_stability_noptions = sizeof bkf_stability_options / sizeof bkf_stability_options[0];

bkf_stability_spec bkf_stability_spec_default(void)
{
    bkf_stability_spec s;
    memset(&s, 0, sizeof s);
    s.gamma = s.c = s.nu = s.S = NAN;
    s.n = 0;
    s.root = 1;
    bkf_trainspec_options o = bkf_trainspec_options_default();
    s.tol = o.tol;
    s.per_kappa = o.per_kappa;
    s.line = 0;
    s.kappa_count = 64;
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
        return bkf_error_set(err, BKF_EINPUT, "%stol: tol = %s is not in [1e-10, 0.01]", p,
                             bkf_format_number(spec->tol, a, sizeof a));
    if (spec->per_kappa < 1 || spec->per_kappa > PER_KAPPA_MAX)
        return bkf_error_set(err, BKF_EINPUT, "%sper-kappa: per-kappa = %zu is not in [1, 50]", p,
                             spec->per_kappa);
    if (spec->kappa_count < 1 || spec->kappa_count > BKF_STABILITY_KAPPA_MAX)
        return bkf_error_set(err, BKF_EINPUT,
                             "%skappa-count: kappa-count = %zu is not in [1, 100000]", p,
                             spec->kappa_count);
    bkf_fronts_spec f = fronts_of(spec);
    return bkf_fronts_check(&f, prefix, err);
}

int bkf_stability_root(const bkf_model_params *params, const bkf_speeds_root *root, double tol,
                       size_t per_kappa, bkf_trainspec_result *result, bkf_error *err)
{
    bkf_trainspec_train train = {root->n, root->v};
    bkf_trainspec_options o = bkf_trainspec_options_default();
    o.tol = tol;
    o.per_kappa = per_kappa;
    return bkf_trainspec_ring(params, &train, &o, result, err);
}

const char *bkf_stability_kind_name(const bkf_trainspec_result *result)
{
    return result->complex_pair ? "complex" : "real";
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
    const char *kind = bkf_stability_kind_name(res);
    if (!s)
        s = bkf_io_table_commentf(
            table, err,
            "stable: %s; sigma_max %.17g%+.17g i (err %.3g) at kappa %.17g, kind %s "
            "(the rightmost sigma but the translation)",
            verdict, res->sigma_max, res->sigma_max_im, res->sigma_max_err, res->kappa_max, kind);
    if (!s)
        s = bkf_io_table_commentf(table, err,
                                  "gauges: translation_residual %.3g (|sigma| of the mode "
                                  "sigma = 0), liouville_residual %.3g (|ln det M - ln m|)",
                                  res->translation_residual, res->liouville_residual);
    if (!s)
        s = bkf_io_table_commentf(
            table, err,
            "window: Re sigma > a_lo = %.6g, |Im sigma| <= y_max = %.6g (r_inf %.6g); "
            "work: %zu mesh steps per period, %zu monodromies, %zu heights",
            res->a_lo, res->y_max, res->r_inf, res->mesh_steps, res->evaluations,
            res->curve_points);
    if (!s) s = text_result(table, "stable", verdict, err);
    if (!s) s = number_result(table, "sigma_max", res->sigma_max, err);
    if (!s) s = number_result(table, "sigma_max_im", res->sigma_max_im, err);
    if (!s) s = number_result(table, "sigma_max_err", res->sigma_max_err, err);
    if (!s) s = number_result(table, "kappa_max", res->kappa_max, err);
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

int bkf_stability_write(const bkf_stability_spec *spec, FILE *out, bkf_io_format format,
                        const bkf_provenance *prov, bkf_error *err)
{
    int s = bkf_stability_check(spec, "", err);
    if (s) return s;
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
    s = bkf_stability_root(&params, &root, spec->tol, spec->per_kappa, &res, err);
    if (!s) s = write_ring(spec, &root, &res, out, format, prov, err);
    bkf_trainspec_result_free(&res);
    return s;
}

#include "bkfront/profile.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bkfront/cycle.h"
#include "bkfront/speeds.h"

static const bkf_io_column columns[] = {
    {"n", BKF_IO_NUMBER},  {"root", BKF_IO_NUMBER}, {"v", BKF_IO_NUMBER},
    {"mu", BKF_IO_NUMBER}, {"T", BKF_IO_NUMBER},    {"z", BKF_IO_NUMBER},
    {"x", BKF_IO_NUMBER},  {"f", BKF_IO_NUMBER},    {"fprime", BKF_IO_NUMBER}};
#define NCOLUMNS (sizeof columns / sizeof columns[0])

#define BOUNDED (BKF_OPT_MIN | BKF_OPT_MAX)

const bkf_option bkf_profile_options[] = {
    {.name = "gamma", .type = BKF_OPT_DOUBLE,
     .offset = offsetof(bkf_profile_spec, params) + offsetof(bkf_model_params, gamma),
     .form = "G", .shown_default = BKF_TEXT_OF(BKF_PAPER_GAMMA),
     .help = "friction strength, as in bkfront speeds"},
    {.name = "c", .type = BKF_OPT_DOUBLE,
     .offset = offsetof(bkf_profile_spec, params) + offsetof(bkf_model_params, c),
     .flags = BKF_OPT_MIN | BKF_OPT_MAX, .min = 0, .max = BKF_MODEL_C_MAX, .form = "C",
     .shown_default = BKF_TEXT_OF(BKF_PAPER_C),
     .help = "sound speed, in [0, 1e6], as in bkfront speeds"},
    {.name = "nu", .type = BKF_OPT_DOUBLE,
     .offset = offsetof(bkf_profile_spec, params) + offsetof(bkf_model_params, nu),
     .form = "V", .shown_default = BKF_TEXT_OF(BKF_PAPER_NU),
     .help = "pulling rate in (-1, 1)"},
    {.name = "S", .type = BKF_OPT_DOUBLE,
     .offset = offsetof(bkf_profile_spec, params) + offsetof(bkf_model_params, S), .form = "L",
     .shown_default = BKF_TEXT_OF(BKF_PAPER_S), .help = "system size, as in bkfront speeds"},
    {.name = "n", .type = BKF_OPT_COUNT_LIST, .offset = offsetof(bkf_profile_spec, n),
     .flags = BKF_OPT_MAX, .max = BKF_PROFILE_MAX_N, .max_count = BKF_PROFILE_MAX_LIST,
     .form = "LIST", .help = "numbers of fronts: K, K1,K2,... or A:B:N (at most 1000)"},
    {.name = "root", .type = BKF_OPT_COUNT, .offset = offsetof(bkf_profile_spec, root),
     .flags = BKF_OPT_MAX, .max = 1000, .form = "I", .shown_default = "1",
     .help = "which root of each n, 1 the fastest"},
    {.name = "mu", .type = BKF_OPT_DOUBLE, .offset = offsetof(bkf_profile_spec, mu),
     .flags = BOUNDED, .min = 1e-6, .max = 1e6, .form = "M",
     .help = "the cycle at mu = M instead, in [1e-06, 1e+06]"},
    {.name = "points", .type = BKF_OPT_COUNT, .offset = offsetof(bkf_profile_spec, points),
     .flags = BOUNDED, .min = 2, .max = BKF_PROFILE_MAX_POINTS, .form = "P",
     .shown_default = "2000", .help = "samples per period (rows per profile), in [2, 100000]"},
    {.name = "tol", .type = BKF_OPT_DOUBLE, .offset = offsetof(bkf_profile_spec, tol),
     .flags = BOUNDED, .min = BKF_TOL_MIN, .max = BKF_TOL_MAX, .form = "E",
     .shown_default = "1e-10",
     .help = "relative accuracy of the cycle and the speed, in [1e-14, 0.1]"},
};
const size_t bkf_profile_noptions = sizeof bkf_profile_options / sizeof bkf_profile_options[0];

bkf_profile_spec bkf_profile_spec_default(void)
{
    bkf_profile_spec s;
    memset(&s, 0, sizeof s);
    s.params = bkf_model_params_paper();
    s.params.gamma = s.params.c = s.params.S = s.params.nu = NAN;
    s.mu = NAN;
    s.points = 2000;
    s.tol = 1e-10;
    return s;
}

void bkf_profile_spec_free(bkf_profile_spec *spec)
{
    bkf_option_free_lists(bkf_profile_options, bkf_profile_noptions, spec);
}

/* The spec with the model not given at the paper's values: nu always, and
 * gamma, c, S without --mu (with it they are not taken). */
static bkf_profile_spec resolved(const bkf_profile_spec *spec)
{
    bkf_profile_spec r = *spec;
    int at_mu = !isnan(spec->mu);
    bkf_model_paper_where_unset(at_mu ? NULL : &r.params.gamma, at_mu ? NULL : &r.params.c,
                                &r.params.nu, at_mu ? NULL : &r.params.S);
    return r;
}

int bkf_profile_check(const bkf_profile_spec *spec, const char *prefix, bkf_error *err)
{
    const char *p = prefix ? prefix : "";
    bkf_error e;
    bkf_profile_spec r = resolved(spec);
    if (bkf_model_check_nu_active(r.params.nu, &e))
        return bkf_error_set(err, BKF_EINPUT, "%snu: %s", p, e.message);
    int model = !isnan(spec->params.gamma) || !isnan(spec->params.c) ||
                !isnan(spec->params.S) || spec->n.count || spec->root;
    if (!isnan(spec->mu)) {
        if (model)
            return bkf_error_set(err, BKF_EINPUT,
                                 "%smu: give either %smu or the model (%sgamma %sc %sS %sn)", p,
                                 p, p, p, p, p);
        return BKF_OK;
    }
    if (!spec->n.count)
        return bkf_error_set(err, BKF_EINPUT, "%sn: required unless %smu is given", p, p);
    bkf_speeds_options o = bkf_speeds_options_default();
    o.tol = spec->tol;
    if (bkf_speeds_check(&r.params, &o, &e))
        return bkf_error_set(err, BKF_EINPUT, "%s", e.message);
    return BKF_OK;
}

double bkf_profile_x(double z, double v, double c)
{
    double stretch = c > 0 ? sqrt(1 - (c / v) * (c / v)) : 1.0;
    return z * v * stretch;
}

/* One period of the cycle in `cycle`, as rows; x needs v and c (NaN v: no x). */
static int write_cycle(bkf_io_table *table, bkf_cycle *cycle, double n, double root, double v,
                       double c, size_t points, bkf_error *err)
{
    const bkf_cycle_result *r = bkf_cycle_get(cycle);
    for (size_t i = 0; i < points; i++) {
        double z = r->period * (double)i / (double)points, f, fp;
        int s = bkf_cycle_profile(cycle, z, &f, &fp, err);
        if (s) return s;
        bkf_io_value row[NCOLUMNS] = {{n, NULL},     {root, NULL},     {v, NULL},
                                      {r->mu, NULL}, {r->period, NULL}, {z, NULL},
                                      {bkf_profile_x(z, v, c), NULL}, {f, NULL}, {fp, NULL}};
        if ((s = bkf_io_table_row(table, row, err))) return s;
    }
    return BKF_OK;
}

int bkf_profile_write(const bkf_profile_spec *p, FILE *out, bkf_io_format format,
                      const bkf_provenance *prov, bkf_error *err)
{
    int s = bkf_profile_check(p, "", err);
    if (s) return s;
    bkf_profile_spec r = resolved(p);
    p = &r;
    bkf_io_table *table = bkf_io_table_alloc(out, format, columns, NCOLUMNS, err);
    if (!table) return BKF_ENOMEM;
    bkf_cycle *cycle = bkf_cycle_alloc();
    bkf_speeds_table speeds = {0};
    char text[512], a[32], b[32], c[32], d[32];
    size_t want_root = p->root ? p->root : 1;
    s = cycle ? BKF_OK : bkf_error_set(err, BKF_ENOMEM, "out of memory");
    if (!s) {
        snprintf(text, sizeof text, "%s profile: f(z), f'(z) over one period of the cycle",
                 prov && prov->program ? prov->program : "libbkfront");
        s = bkf_io_table_comment(table, text, err);
    }
    if (!s && prov && prov->command) {
        snprintf(text, sizeof text, "command: %.480s", prov->command);
        s = bkf_io_table_comment(table, text, err);
    }
    bkf_cycle_options co = bkf_cycle_options_default();
    co.tol = p->tol;
    co.warm_start = 0;
    if (!s && isnan(p->mu)) {
        double lo = p->n.values[0], hi = p->n.values[0];
        for (size_t i = 0; i < p->n.count; i++) {
            lo = fmin(lo, p->n.values[i]);
            hi = fmax(hi, p->n.values[i]);
        }
        bkf_speeds_options so = bkf_speeds_options_default();
        so.tol = p->tol;
        so.n_from = (size_t)lo;
        so.n_to = (size_t)hi;
        s = bkf_speeds_find(&p->params, &so, &speeds, err);
        if (!s) {
            snprintf(text, sizeof text, "gamma %s, c %s, nu %s, S %s; x = z v "
                     "sqrt(1 - c^2/v^2)", bkf_format_number(p->params.gamma, a, sizeof a),
                     bkf_format_number(p->params.c, b, sizeof b),
                     bkf_format_number(p->params.nu, c, sizeof c),
                     bkf_format_number(p->params.S, d, sizeof d));
            s = bkf_io_table_comment(table, text, err);
        }
        for (size_t i = 0; !s && i < p->n.count; i++) {
            size_t n = (size_t)p->n.values[i];
            const bkf_speeds_root *root = NULL;
            size_t seen = 0;
            for (size_t k = 0; k < speeds.count; k++)
                if (speeds.roots[k].n == n && ++seen == want_root) root = &speeds.roots[k];
            if (!root) {
                s = bkf_error_set(err, BKF_EINPUT,
                                  "n = %zu has %zu root%s, not a root %zu (n_max = %ld)", n,
                                  seen, seen == 1 ? "" : "s", want_root, speeds.n_max);
                break;
            }
            if ((s = bkf_speeds_root_status(root, err))) break;
            if (!isfinite(root->mu)) {
                s = bkf_error_set(err, BKF_ENUMERIC, "n = %zu: the root is at the sonic limit", n);
                break;
            }
            s = bkf_cycle_solve(cycle, root->mu, p->params.nu, &co, err);
            if (!s)
                s = write_cycle(table, cycle, (double)n, (double)want_root, root->v,
                                p->params.c, p->points, err);
        }
    } else if (!s) {
        s = bkf_cycle_solve(cycle, p->mu, p->params.nu, &co, err);
        if (!s) s = write_cycle(table, cycle, NAN, NAN, NAN, NAN, p->points, err);
    }
    if (!s) s = bkf_io_table_finish(table, err);
    bkf_speeds_table_free(&speeds);
    bkf_cycle_free(cycle);
    bkf_io_table_free(table);
    return s;
}

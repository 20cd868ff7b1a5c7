#include "bkfront/fronts.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bkfront/cycle.h"

#define ROOT_COLUMNS                                                                   \
    {"n", BKF_IO_NUMBER}, {"v", BKF_IO_NUMBER}, {"mu", BKF_IO_NUMBER},                 \
    {"T", BKF_IO_NUMBER}, {"T_err", BKF_IO_NUMBER}, {"v_over_c", BKF_IO_NUMBER},       \
    {"wavelength", BKF_IO_NUMBER}, {"period_fixed", BKF_IO_NUMBER},                    \
    {"v_asym", BKF_IO_NUMBER}, {"deviation", BKF_IO_NUMBER}, {"v_err", BKF_IO_NUMBER}, \
    {"model", BKF_IO_TEXT}, {"residual", BKF_IO_NUMBER}, {"slope", BKF_IO_NUMBER},     \
    {"flags", BKF_IO_TEXT}

static const bkf_io_column speeds_columns[] = {ROOT_COLUMNS};
static const bkf_io_column branch_columns[] = {
    {"point", BKF_IO_TEXT}, {"S", BKF_IO_NUMBER},  {"gamma", BKF_IO_NUMBER},
    {"c", BKF_IO_NUMBER},   {"nu", BKF_IO_NUMBER}, ROOT_COLUMNS};
#define NSPEEDS (sizeof speeds_columns / sizeof speeds_columns[0])
#define NBRANCH (sizeof branch_columns / sizeof branch_columns[0])
#define NPARAM (NBRANCH - NSPEEDS)

_Static_assert(NSPEEDS == BKF_FRONTS_ROOT_COLUMNS, "the root's columns");

static const char *const param_names[] = {"S", "nu", "gamma", "c"};

/* ---------------------------------------------------------------- speeds */

bkf_fronts_spec bkf_fronts_spec_default(void)
{
    bkf_fronts_spec s;
    memset(&s, 0, sizeof s);
    s.params.gamma = s.params.c = s.params.nu = s.params.S = NAN;
    s.params.kind = BKF_MODEL_CONTINUUM;
    s.options = bkf_speeds_options_default();
    return s;
}

int bkf_fronts_check(const bkf_fronts_spec *spec, bkf_error *err)
{
    if (!spec) return bkf_error_set(err, BKF_EINPUT, "speeds: spec is NULL");
    return bkf_speeds_check(&spec->params, &spec->options, err);
}

const bkf_io_column *bkf_fronts_columns(size_t *count)
{
    if (count) *count = NSPEEDS;
    return speeds_columns;
}

static const char *flag_text(unsigned flags)
{
    if ((flags & BKF_SPEEDS_NEAR_TANGENT) && (flags & BKF_SPEEDS_ASYMPTOTIC))
        return "near-tangent,asymptotic";
    if (flags & BKF_SPEEDS_NEAR_TANGENT) return "near-tangent";
    if (flags & BKF_SPEEDS_ASYMPTOTIC) return "asymptotic";
    return "";
}

void bkf_fronts_root_values(const bkf_speeds_root *r, bkf_io_value *v)
{
    memset(v, 0, NSPEEDS * sizeof *v);
    v[0].number = (double)r->n;
    v[1].number = r->v;
    v[2].number = r->mu;
    v[3].number = r->T;
    v[4].number = r->T_err;
    v[5].number = r->v_over_c;
    v[6].number = r->wavelength;
    v[7].number = r->period_fixed;
    v[8].number = r->v_asym;
    v[9].number = r->deviation;
    v[10].number = r->v_err;
    v[11].text = r->model ? r->model : "shooting";
    v[12].number = r->residual;
    v[13].number = r->slope;
    v[14].text = flag_text(r->flags);
}

static int number_result(bkf_io_table *t, const char *name, double x, bkf_error *err)
{
    bkf_io_value v = {x, NULL};
    return bkf_io_table_result(t, name, BKF_IO_NUMBER, v, err);
}

/* The key results: a comment for TSV and the fields of JSON's "results". */
static int range_of_n(bkf_io_table *table, const bkf_fronts_spec *spec,
                      const bkf_speeds_table *t, bkf_error *err)
{
    char line[640];
    int c_positive = spec->params.c > 0;
    if (c_positive)
        snprintf(line, sizeof line,
                 "n_max %ld; n_bound = S/(k c gamma) = %.17g with k(nu) = %.17g; "
                 "inf of T/sqrt(mu^2 - gamma^2) over mu > gamma: %.17g (%s)",
                 t->n_max, t->n_bound, t->k, t->g_inf,
                 t->dips_below_k ? "dips below k: some n >= n_bound have roots"
                                 : "= k, approached as mu -> inf");
    else
        snprintf(line, sizeof line, "n_max: none (c = 0, every n has a front); k(nu) = %.17g",
                 t->k);
    int s = bkf_io_table_comment(table, line, err);
    /* c = 0: no largest n and no bound, null in JSON */
    if (!s) s = number_result(table, "n_max", c_positive ? (double)t->n_max : NAN, err);
    if (!s) s = number_result(table, "n_bound", c_positive ? t->n_bound : NAN, err);
    if (!s) s = number_result(table, "k", t->k, err);
    if (!s) s = number_result(table, "g_inf", c_positive ? t->g_inf : NAN, err);
    if (!s) s = number_result(table, "dips_below_k", c_positive ? (double)t->dips_below_k : NAN, err);
    return s;
}

static int write_speeds(const bkf_fronts_spec *spec, const bkf_product_output *out,
                        const bkf_speeds_table *t, bkf_error *err)
{
    const bkf_model_params *p = &spec->params;
    bkf_io_table *table;
    int s = bkf_product_table_open(
        out, speeds_columns, NSPEEDS,
        "speeds: roots v > c of n T(mu(v)) = S / (v sqrt(1 - c^2/v^2)), "
        "mu(v) = gamma / sqrt(1 - c^2/v^2)",
        &table, err);
    if (s) return s;
    char a[32], b[32], c[32], d[32], e[32], line[640];
    snprintf(line, sizeof line, "gamma %s, c %s, nu %s, S %s; tol %s (relative, on v)",
             bkf_product_number(p->gamma, a, sizeof a), bkf_product_number(p->c, b, sizeof b),
             bkf_product_number(p->nu, c, sizeof c), bkf_product_number(p->S, d, sizeof d),
             bkf_product_number(spec->options.tol, e, sizeof e));
    s = bkf_io_table_comment(table, line, err);
    if (!s) s = range_of_n(table, spec, t, err);
    if (!s) {
        snprintf(line, sizeof line,
                 "work: %zu grid samples (%zu solves at the coarse tolerance), %zu solves at "
                 "the roots' tolerance, %zu values of T from a formula, largest mu %.6g; "
                 "method %s",
                 t->samples, t->coarse_solves, t->precise_solves, t->formula_answers,
                 t->mu_grid_max, bkf_cycle_method_name(spec->options.method));
        s = bkf_io_table_comment(table, line, err);
    }
    if (!s && t->note[0]) {
        snprintf(line, sizeof line, "note: %s", t->note);
        s = bkf_io_table_comment(table, line, err);
    }
    if (!s) s = bkf_product_table_command(table, out, err);
    for (size_t i = 0; !s && i < t->count; i++) {
        bkf_io_value v[NSPEEDS];
        bkf_fronts_root_values(&t->roots[i], v);
        s = bkf_io_table_row(table, v, err);
    }
    if (!s) s = bkf_io_table_finish(table, err);
    bkf_io_table_free(table);
    return s;
}

int bkf_fronts_write(const bkf_fronts_spec *spec, const bkf_product_output *out,
                     bkf_speeds_table *result, bkf_error *err)
{
    bkf_speeds_table t;
    memset(&t, 0, sizeof t);
    if (result) memset(result, 0, sizeof *result);
    int s = bkf_fronts_check(spec, err);
    if (!s) s = bkf_speeds_find(&spec->params, &spec->options, &t, err);
    if (!s) s = write_speeds(spec, out, &t, err);
    if (result)
        *result = t;
    else
        bkf_speeds_table_free(&t);
    return s;
}

/* ---------------------------------------------------------------- branch */

bkf_fronts_branch_spec bkf_fronts_branch_spec_default(void)
{
    bkf_fronts_branch_spec s;
    memset(&s, 0, sizeof s);
    s.params = bkf_fronts_spec_default().params;
    s.along = BKF_SPEEDS_ALONG_S;
    s.from = s.to = NAN;
    s.n = 1;
    s.root = 1;
    s.max_points = 0;
    s.tol = bkf_speeds_options_default().tol;
    return s;
}

const char *bkf_fronts_param_name(bkf_speeds_param along)
{
    return (unsigned)along < 4 ? param_names[along] : "unknown";
}

const bkf_io_column *bkf_fronts_branch_columns(size_t *count)
{
    if (count) *count = NBRANCH;
    return branch_columns;
}

static double *param_field(bkf_model_params *p, bkf_speeds_param along)
{
    return along == BKF_SPEEDS_ALONG_S       ? &p->S
           : along == BKF_SPEEDS_ALONG_NU    ? &p->nu
           : along == BKF_SPEEDS_ALONG_GAMMA ? &p->gamma
                                             : &p->c;
}

static double param_value(bkf_model_params p, bkf_speeds_param along)
{
    return *param_field(&p, along);
}

bkf_model_params bkf_fronts_branch_start(const bkf_fronts_branch_spec *spec)
{
    bkf_model_params p = spec->params;
    *param_field(&p, spec->along) = spec->from;
    return p;
}

int bkf_fronts_branch_check(const bkf_fronts_branch_spec *spec, bkf_error *err)
{
    if (!spec) return bkf_error_set(err, BKF_EINPUT, "branch: spec is NULL");
    if ((unsigned)spec->along > BKF_SPEEDS_ALONG_C)
        return bkf_error_set(err, BKF_EINPUT, "branch: along is not S, nu, gamma or c");
    const char *name = param_names[spec->along];
    if (!(spec->from != spec->to))
        return bkf_error_set(err, BKF_EINPUT, "branch: from and to (%s) must differ", name);
    bkf_speeds_options o = bkf_speeds_options_default();
    o.tol = spec->tol;
    /* each end in the continued parameter's range */
    const double ends[2] = {spec->from, spec->to};
    for (int i = 0; i < 2; i++) {
        bkf_model_params p = spec->params;
        *param_field(&p, spec->along) = ends[i];
        int s = bkf_speeds_check(&p, &o, err);
        if (s) return s;
    }
    double c_lo = spec->along == BKF_SPEEDS_ALONG_C ? fmin(spec->from, spec->to) : spec->params.c;
    if (!(c_lo > 0))
        return bkf_error_set(err, BKF_EINPUT,
                             "branch: c must stay > 0 (c = 0 is the closed form "
                             "v = S/(n T(gamma)), no continuation)");
    if (spec->n < 1 || spec->root < 1)
        return bkf_error_set(err, BKF_EINPUT, "branch: n and root must be >= 1");
    return BKF_OK;
}

typedef struct {
    bkf_speeds_branch_point *points;
    size_t count, cap;
    int status;
} branch_sink;

static int collect_point(const bkf_speeds_branch_point *pt, void *data)
{
    branch_sink *sink = data;
    if (sink->count == sink->cap) {
        size_t cap = sink->cap ? 2 * sink->cap : 64;
        bkf_speeds_branch_point *x = realloc(sink->points, cap * sizeof *x);
        if (!x) {
            sink->status = BKF_ENOMEM;
            return 1;
        }
        sink->points = x;
        sink->cap = cap;
    }
    sink->points[sink->count++] = *pt;
    return 0;
}

/* "N points, F fold(s) at p = .. (v = ..), ...; ends ..." */
static void summary_line(const bkf_fronts_branch_spec *spec, const branch_sink *sink,
                         const bkf_speeds_branch_report *rep, char *line, size_t size)
{
    const char *pname = param_names[spec->along];
    char a[32], e[32];
    int used = snprintf(line, size, "%zu points, %zu fold(s)", rep->points, rep->folds);
    const char *sep = " at ";
    for (size_t i = 0; i < sink->count && used > 0 && (size_t)used < size; i++)
        if (sink->points[i].kind == BKF_SPEEDS_FOLD) {
            used += snprintf(line + used, size - (size_t)used, "%s%s = %s (v = %s)", sep, pname,
                             bkf_product_number(param_value(sink->points[i].params, spec->along),
                                                a, sizeof a),
                             bkf_product_number(sink->points[i].root.v, e, sizeof e));
            sep = ", ";
        }
    if (used > 0 && (size_t)used < size) {
        if (rep->sonic)
            snprintf(line + used, size - (size_t)used,
                     "; ends at the sonic limit v -> c+ at %s = %s (S = n k(nu) c gamma)", pname,
                     bkf_product_number(rep->sonic_value, a, sizeof a));
        else if (rep->reached_end)
            snprintf(line + used, size - (size_t)used, "; ends on the range's boundary");
        else
            snprintf(line + used, size - (size_t)used, "; stopped after --max-points");
    }
}

static int write_branch(const bkf_fronts_branch_spec *spec, const bkf_product_output *out,
                        const branch_sink *sink, const bkf_speeds_branch_report *rep,
                        bkf_error *err)
{
    bkf_io_table *table;
    int s = bkf_product_table_open(
        out, branch_columns, NBRANCH,
        "branch: one root v_n of n T(mu(v)) = S / (v sqrt(1 - c^2/v^2)) "
        "followed along one parameter by pseudo-arclength continuation",
        &table, err);
    if (s) return s;
    const bkf_model_params *p = &spec->params;
    bkf_speeds_param along = spec->along;
    char a[32], b[32], c[32], d[32], line[640];
    snprintf(line, sizeof line, "%s from %s to %s; n %zu, root %zu at the start; tol %s",
             param_names[along], bkf_product_number(spec->from, a, sizeof a),
             bkf_product_number(spec->to, b, sizeof b), spec->n, spec->root,
             bkf_product_number(spec->tol, c, sizeof c));
    s = bkf_io_table_comment(table, line, err);
    if (!s) {
        snprintf(line, sizeof line, "fixed: %s%s%s%s%s%s%s%s",
                 along == BKF_SPEEDS_ALONG_GAMMA ? "" : "gamma ",
                 along == BKF_SPEEDS_ALONG_GAMMA ? "" : bkf_product_number(p->gamma, a, sizeof a),
                 along == BKF_SPEEDS_ALONG_C ? "" : " c ",
                 along == BKF_SPEEDS_ALONG_C ? "" : bkf_product_number(p->c, b, sizeof b),
                 along == BKF_SPEEDS_ALONG_NU ? "" : " nu ",
                 along == BKF_SPEEDS_ALONG_NU ? "" : bkf_product_number(p->nu, c, sizeof c),
                 along == BKF_SPEEDS_ALONG_S ? "" : " S ",
                 along == BKF_SPEEDS_ALONG_S ? "" : bkf_product_number(p->S, d, sizeof d));
        s = bkf_io_table_comment(table, line, err);
    }
    if (!s) {
        summary_line(spec, sink, rep, line, sizeof line);
        s = bkf_io_table_comment(table, line, err);
    }
    if (!s) s = bkf_product_table_command(table, out, err);
    static const char *const kinds[] = {"point", "fold", "sonic"};
    for (size_t i = 0; !s && i < sink->count; i++) {
        const bkf_speeds_branch_point *pt = &sink->points[i];
        bkf_io_value v[NBRANCH];
        memset(v, 0, sizeof v);
        v[0].text = kinds[pt->kind];
        v[1].number = pt->params.S;
        v[2].number = pt->params.gamma;
        v[3].number = pt->params.c;
        v[4].number = pt->params.nu;
        bkf_fronts_root_values(&pt->root, v + NPARAM);
        s = bkf_io_table_row(table, v, err);
    }
    if (!s) s = bkf_io_table_finish(table, err);
    bkf_io_table_free(table);
    return s;
}

int bkf_fronts_branch_write(const bkf_fronts_branch_spec *spec, const bkf_product_output *out,
                            bkf_error *err)
{
    int s = bkf_fronts_branch_check(spec, err);
    if (s) return s;
    bkf_speeds_options o = bkf_speeds_options_default();
    o.tol = spec->tol;
    bkf_model_params start = bkf_fronts_branch_start(spec);
    branch_sink sink = {0};
    bkf_speeds_branch_report rep;
    s = bkf_speeds_branch(&start, spec->n, spec->root, spec->along, spec->to, &o,
                          spec->max_points, collect_point, &sink, &rep, err);
    if (!s && sink.status) s = bkf_error_set(err, sink.status, "out of memory");
    if (!s) s = write_branch(spec, out, &sink, &rep, err);
    free(sink.points);
    return s;
}

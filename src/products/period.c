#include "bkfront/period.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bkfront/asymptotics.h"
#include "bkfront/cycle.h"
#include "bkfront/model.h"

static const bkf_io_column columns[] = {
    {"mu", BKF_IO_NUMBER},
    {"nu", BKF_IO_NUMBER},
    {"T", BKF_IO_NUMBER},
    {"T_err", BKF_IO_NUMBER},
    {"T_asym", BKF_IO_NUMBER},
    {"T_asym2", BKF_IO_NUMBER},
    {"xmax", BKF_IO_NUMBER},
    {"xmin", BKF_IO_NUMBER},
    {"multiplier", BKF_IO_NUMBER},
    {"log_multiplier", BKF_IO_NUMBER},
    {"steps", BKF_IO_NUMBER},
    {"rhs_calls", BKF_IO_NUMBER},
    {"newton_iterations", BKF_IO_NUMBER},
    {"stepper", BKF_IO_TEXT},
    {"model", BKF_IO_TEXT},
};
#define NCOLUMNS (sizeof columns / sizeof columns[0])

static const char *const stepper_names[] = {"auto", "explicit", "implicit", "extrapolation", "collocation", NULL};
static const bkf_stepper_kind stepper_kinds[] = {BKF_STEPPER_AUTO, BKF_STEPPER_EXPLICIT, BKF_STEPPER_IMPLICIT,
                                                 BKF_STEPPER_EXTRAPOLATION, BKF_STEPPER_COLLOCATION};
static const char *const method_names[] = {"auto", "asymptotic", "leading", "shooting", NULL};
static const bkf_cycle_method method_kinds[] = {BKF_METHOD_AUTO, BKF_METHOD_ASYMPTOTIC,
                                                BKF_METHOD_LEADING, BKF_METHOD_SHOOTING};
static const char *const continue_names[] = {"mu", "nu", NULL};

#define BOUNDED (BKF_OPT_MIN | BKF_OPT_MAX)

const bkf_option bkf_period_options[] = {
    /* log before mu: it decides how mu's A:B:N is spaced. */
    {.name = "log", .type = BKF_OPT_SWITCH, .offset = offsetof(bkf_period_spec, log),
     .help = "geometric --mu range (A, B > 0); default linear. Not\n"
             "allowed with a --nu range, which is always linear"},
    {.name = "mu", .type = BKF_OPT_DOUBLE_LIST, .offset = offsetof(bkf_period_spec, mu),
     .flags = BKF_OPT_REQUIRED | BOUNDED | BKF_OPT_LOG_SWITCH, .min = BKF_CYCLE_MU_MIN,
     .max = BKF_CYCLE_MU_MAX, .log_offset = offsetof(bkf_period_spec, log), .form = "LIST",
     .help = "required; mu in [1e-06, 1e+06]: M, M1,M2,... or A:B:N\n"
             "(N points from A to B, ends included; N = 1 needs A = B)"},
    {.name = "nu", .type = BKF_OPT_DOUBLE_LIST, .offset = offsetof(bkf_period_spec, nu),
     .flags = BKF_OPT_REQUIRED | BKF_OPT_FANOUT, .form = "LIST",
     .help = "required; nu in (-1, 1): for |nu| >= 1 there is no limit\n"
             "cycle (uniform continuous slip is stable)\n"
             "With lists for both, the points form a grid, mu varying\n"
             "fastest; consecutive solves start from the previous cycle."},
    {.name = "tol", .type = BKF_OPT_DOUBLE, .offset = offsetof(bkf_period_spec, tol),
     .flags = BOUNDED, .min = BKF_TOL_MIN, .max = BKF_TOL_MAX, .form = "E",
     .shown_default = "1e-10", .help = "relative accuracy asked of T, in [1e-14, 0.1]"},
    {.name = "continue", .type = BKF_OPT_CHOICE, .offset = offsetof(bkf_period_spec, along),
     .choices = continue_names, .form = "mu|nu",
     .help = "follow the branch of cycles by pseudo-arclength\n"
             "continuation from A to B of that option's range A:B:N\n"
             "(N is ignored: the rows are the continuation's points);\n"
             "the other option must be a single value. Default: solve\n"
             "at the given points only"},
    {.name = "method", .type = BKF_OPT_CHOICE, .offset = offsetof(bkf_period_spec, method),
     .choices = method_names, .form = "auto|asymptotic|leading|shooting", .shown_default = "auto",
     .help = "how T is obtained: shooting (Newton, integrating the ODE),\n"
             "asymptotic (the corrected large-mu or the small-mu formula),\n"
             "leading (k(nu) mu), or auto: the cheapest whose error bound\n"
             "meets --tol (leading, then asymptotic, then shooting).\n"
             "A formula asked for where its bound exceeds --tol is a\n"
             "numerical failure (exit 1). --continue needs shooting or\n"
             "auto (then it shoots)"},
    {.name = "stepper", .type = BKF_OPT_CHOICE, .offset = offsetof(bkf_period_spec, stepper),
     .choices = stepper_names, .form = "auto|explicit|implicit|extrapolation|collocation",
     .shown_default = "auto",
     .help = "integrator: rk8pd (explicit), GSL's bsimp with the analytic\n"
             "Jacobian (implicit; the former stiff default), bd2x2:\n"
             "the same extrapolation method with closed-form 2x2 solves\n"
             "(extrapolation), colloc: Gauss-Legendre collocation on an\n"
             "adapted mesh (collocation; outside canards: there and\n"
             "where it refuses the solve shoots as auto),\n"
             "or auto: colloc up to mu 1 at tol <= 1e-6 and from\n"
             "mu 10 at tol <= 1e-10 where mu^2 (1 - |nu|) >= 1,\n"
             "else bd2x2 above mu 30 (above 20\n"
             "at tol 1e-12..1e-8), else rk8pd"},
};
const size_t bkf_period_noptions = sizeof bkf_period_options / sizeof bkf_period_options[0];

bkf_period_spec bkf_period_spec_default(void)
{
    bkf_period_spec s;
    memset(&s, 0, sizeof s);
    s.tol = 1e-10;
    s.along = -1;
    return s;
}

void bkf_period_spec_free(bkf_period_spec *spec)
{
    bkf_option_free_lists(bkf_period_options, bkf_period_noptions, spec);
}

int bkf_period_check(const bkf_period_spec *spec, const char *prefix, bkf_error *err)
{
    const char *p = prefix ? prefix : "";
    if (!spec->mu.count) return bkf_error_set(err, BKF_EINPUT, "%smu is required", p);
    if (!spec->nu.count) return bkf_error_set(err, BKF_EINPUT, "%snu is required", p);
    if (spec->log && spec->nu.is_range)
        return bkf_error_set(err, BKF_EINPUT,
                             "%slog: geometric ranges are for %smu only; a %snu range is "
                             "linear (drop %slog or give %snu a single value)",
                             p, p, p, p, p);
    for (size_t i = 0; i < spec->nu.count; i++) {
        bkf_error e;
        if (bkf_model_check_nu_active(spec->nu.values[i], &e) != BKF_OK)
            return bkf_error_set(err, BKF_EINPUT, "%snu: %s", p, e.message);
    }
    if (spec->mu.count > BKF_LIST_MAX / spec->nu.count)
        return bkf_error_set(err, BKF_EINPUT,
                             "%smu, %snu: the grid has %zu x %zu points, more than %u", p, p,
                             spec->mu.count, spec->nu.count, BKF_LIST_MAX);
    if (spec->along >= 0) {
        int k = spec->along;
        const bkf_list *on = k == 0 ? &spec->mu : &spec->nu;
        const bkf_list *other = k == 0 ? &spec->nu : &spec->mu;
        if (!on->is_range || on->from == on->to)
            return bkf_error_set(err, BKF_EINPUT,
                                 "%scontinue %s: %s%s must be a range A:B:N with A != B", p,
                                 continue_names[k], p, continue_names[k]);
        if (other->count != 1)
            return bkf_error_set(err, BKF_EINPUT,
                                 "%scontinue %s: %s%s must be a single value, not a range", p,
                                 continue_names[k], p, continue_names[1 - k]);
        if (method_kinds[spec->method] == BKF_METHOD_ASYMPTOTIC ||
            method_kinds[spec->method] == BKF_METHOD_LEADING)
            return bkf_error_set(err, BKF_EINPUT,
                                 "%smethod %s: %scontinue follows the shooting equations; use "
                                 "%smethod shooting or auto",
                                 p, method_names[spec->method], p, p);
    }
    return BKF_OK;
}

typedef struct {
    bkf_io_table *table;
    int status; /* first failure writing a row, or BKF_ECANCELED */
    bkf_error err;
    const volatile sig_atomic_t *cancel;
    size_t rows;
} period_sink;

/* Raised cancel flag: BKF_ECANCELED into the sink, once. */
static int canceled(period_sink *sink)
{
    if (!sink->cancel || !*sink->cancel) return 0;
    if (!sink->status)
        sink->status = bkf_error_set(&sink->err, BKF_ECANCELED, "canceled after %zu rows",
                                     sink->rows);
    return 1;
}

static int add_row(period_sink *sink, const bkf_cycle_result *r)
{
    double mu = r->mu, nu = r->nu;
    bkf_io_value v[NCOLUMNS] = {
        {.number = mu},
        {.number = nu},
        {.number = r->period},
        {.number = r->period_err},
        {.number = bkf_asym_period_leading(mu, nu)},
        {.number = mu >= 1 ? bkf_asym_period_large(mu, nu) : bkf_asym_period_small(mu, nu)},
        {.number = r->xmax},
        {.number = r->xmin},
        {.number = r->multiplier},
        {.number = r->log_multiplier},
        {.number = (double)r->steps},
        {.number = (double)r->rhs_calls},
        {.number = (double)r->newton_iterations},
        {.text = r->stepper},
        {.text = r->model ? r->model : "shooting"},
    };
    int s = bkf_io_table_row(sink->table, v, &sink->err);
    if (s && !sink->status) sink->status = s;
    if (!s) sink->rows++;
    return s;
}

static int visit_branch_point(const bkf_cycle_result *point, void *data)
{
    return add_row(data, point) != BKF_OK || canceled(data);
}

static int write_comments(bkf_io_table *table, const bkf_period_spec *spec,
                          const bkf_provenance *prov, bkf_error *err)
{
    char a[32], b[32], c[32], d[32], line[512];
    const char *program = prov && prov->program ? prov->program : "libbkfront";
    snprintf(line, sizeof line, "%s period: limit cycle of f'' + mu (f^2 - 1) f' + f = nu",
             program);
    int s = bkf_io_table_comment(table, line, err);
    if (!s)
        s = bkf_io_table_comment(
            table,
            "T: period in z; T_err: estimated absolute error of T; T_asym: k(nu) mu; "
            "T_asym2: large-mu expansion (mu >= 1) or small-mu expansion (mu < 1)\n"
            "xmax, xmin: extremes of f; multiplier: nontrivial Floquet multiplier, "
            "log_multiplier: its logarithm; steps, rhs_calls, newton_iterations: work of the "
            "solve; stepper: integrator used; model: what answered (shooting, asymptotic, "
            "leading; for a formula T_err is its error bound)",
            err);
    if (s) return s;
    const char *stepper = stepper_names[spec->stepper];
    if (spec->along < 0)
        snprintf(line, sizeof line,
                 "tol %s (relative, on T), stepper %s; %zu mu x %zu nu points, mu fastest",
                 bkf_format_number(spec->tol, a, sizeof a), stepper, spec->mu.count,
                 spec->nu.count);
    else {
        int mu_along = spec->along == 0;
        const bkf_list *on = mu_along ? &spec->mu : &spec->nu;
        const bkf_list *other = mu_along ? &spec->nu : &spec->mu;
        snprintf(line, sizeof line,
                 "tol %s (relative, on T), stepper %s; continuation in %s from %s to %s at %s = %s",
                 bkf_format_number(spec->tol, a, sizeof a), stepper, mu_along ? "mu" : "nu",
                 bkf_format_number(on->from, b, sizeof b), bkf_format_number(on->to, c, sizeof c),
                 mu_along ? "nu" : "mu", bkf_format_number(other->values[0], d, sizeof d));
    }
    if ((s = bkf_io_table_comment(table, line, err))) return s;
    if (prov && prov->command) {
        size_t n = strlen(prov->command) + 16;
        char *text = malloc(n);
        if (!text) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
        snprintf(text, n, "command: %s", prov->command);
        s = bkf_io_table_comment(table, text, err);
        free(text);
    }
    return s;
}

int bkf_period_write(const bkf_period_spec *spec, FILE *out, bkf_io_format format,
                     const bkf_provenance *prov, bkf_error *err)
{
    char a[32], b[32], c[32];
    int s = bkf_period_check(spec, "", err);
    if (s) return s;
    bkf_cycle_options options = bkf_cycle_options_default();
    options.warm_start = 1;
    options.tol = spec->tol;
    options.stepper = stepper_kinds[spec->stepper];
    bkf_cycle_method method = method_kinds[spec->method];

    period_sink sink = {.cancel = spec->cancel};
    sink.table = bkf_io_table_alloc(out, format, columns, NCOLUMNS, err);
    if (!sink.table) return BKF_ENOMEM;
    s = write_comments(sink.table, spec, prov, err);

    if (!s && spec->along < 0) {
        bkf_cycle *cycle = bkf_cycle_alloc();
        if (!cycle) s = bkf_error_set(err, BKF_ENOMEM, "out of memory");
        for (size_t j = 0; !s && j < spec->nu.count; j++)
            for (size_t i = 0; !s && i < spec->mu.count; i++) {
                if (canceled(&sink)) {
                    s = sink.status;
                    *err = sink.err;
                    break;
                }
                double mu = spec->mu.values[i], nu = spec->nu.values[j];
                bkf_error e;
                bkf_cycle_result r;
                s = bkf_cycle_estimate(cycle, mu, nu, &options, method, &r, &e);
                if (s)
                    bkf_error_set(err, s, "at mu = %s, nu = %s: %s",
                                  bkf_format_number(mu, a, sizeof a),
                                  bkf_format_number(nu, b, sizeof b), e.message);
                else if ((s = add_row(&sink, &r)))
                    *err = sink.err;
            }
        bkf_cycle_free(cycle);
    } else if (!s) {
        int mu_along = spec->along == 0;
        const bkf_list *on = mu_along ? &spec->mu : &spec->nu;
        double fixed = mu_along ? spec->nu.values[0] : spec->mu.values[0];
        bkf_error e = {0};
        /* N only shaped the range's syntax: the continuation's own step
         * control decides the points, hence max_points 0. */
        s = bkf_cycle_branch(mu_along ? BKF_CYCLE_ALONG_MU : BKF_CYCLE_ALONG_NU, on->from,
                             on->to, fixed, &options, 0, visit_branch_point, &sink, &e);
        if (sink.status) {
            s = sink.status;
            *err = sink.err;
        } else if (s)
            bkf_error_set(err, s, "continuation in %s from %s to %s at %s = %s: %s",
                          mu_along ? "mu" : "nu", bkf_format_number(on->from, a, sizeof a),
                          bkf_format_number(on->to, b, sizeof b), mu_along ? "nu" : "mu",
                          bkf_format_number(fixed, c, sizeof c), e.message);
    }
    if (!s) s = bkf_io_table_finish(sink.table, err);
    bkf_io_table_free(sink.table);
    return s;
}

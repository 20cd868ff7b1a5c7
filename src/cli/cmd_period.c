/* bkfront period: T(mu, nu) of f'' + mu (f^2 - 1) f' + f = nu at single
 * points, on a grid, or along a continued branch, with error estimates and
 * the asymptotic approximations beside it.
 *
 * Every input is checked before the first solve, and the table is built in
 * memory and written only when every point succeeded, so a failed run leaves
 * stdout (or the --out file) untouched. */
#include "args.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bkfront/asymptotics.h"
#include "bkfront/cycle.h"
#include "bkfront/io.h"
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

static const char *const stepper_names[] = {"auto", "explicit", "implicit", NULL};
static const bkf_stepper_kind stepper_kinds[] = {BKF_STEPPER_AUTO, BKF_STEPPER_EXPLICIT,
                                                 BKF_STEPPER_IMPLICIT};
static const char *const format_names[] = {"tsv", "json", NULL};
static const char *const method_names[] = {"auto", "asymptotic", "leading", "shooting", NULL};
static const bkf_cycle_method method_kinds[] = {BKF_METHOD_AUTO, BKF_METHOD_ASYMPTOTIC,
                                                BKF_METHOD_LEADING, BKF_METHOD_SHOOTING};
static const char *const continue_names[] = {"mu", "nu", NULL};

#define MU_FORM "M or A:B:N, each in [1e-06, 1e+06]"
#define NU_FORM "V or A:B:N, each in (-1, 1)"

static void period_help(FILE *out)
{
    fprintf(out,
        "usage: bkfront period --mu M --nu V [--tol E] [--log] [--continue mu|nu]\n"
        "                      [--method auto|asymptotic|leading|shooting]\n"
        "                      [--stepper auto|explicit|implicit] [--format tsv|json]\n"
        "                      [--out FILE]\n"
        "\n"
        "Period T(mu, nu) of the limit cycle of f'' + mu (f^2 - 1) f' + f = nu, by\n"
        "Newton shooting, with its error estimate, amplitude, Floquet multiplier and\n"
        "the asymptotic approximations.\n"
        "\n"
        "options:\n"
        "  --mu M|A:B:N      required; mu in [%g, %g]. A:B:N is N points from A to B,\n"
        "                    ends included (N = 1 needs A = B)\n"
        "  --nu V|A:B:N      required; nu in (-1, 1): for |nu| >= 1 there is no limit\n"
        "                    cycle (uniform continuous slip is stable)\n"
        "                    With ranges for both, the points form a grid, mu varying\n"
        "                    fastest; consecutive solves start from the previous cycle.\n"
        "  --tol E           relative accuracy asked of T, in [%g, %g]; default 1e-10\n"
        "  --log             geometric --mu range (A, B > 0); default linear. Not\n"
        "                    allowed with a --nu range, which is always linear\n"
        "  --continue mu|nu  follow the branch of cycles by pseudo-arclength\n"
        "                    continuation from A to B of that option's range A:B:N\n"
        "                    (N is ignored: the rows are the continuation's points);\n"
        "                    the other option must be a single value. Default: solve\n"
        "                    at the given points only\n"
        "  --method auto|asymptotic|leading|shooting\n"
        "                    how T is obtained: shooting (Newton, integrating the ODE),\n"
        "                    asymptotic (the corrected large-mu or the small-mu formula),\n"
        "                    leading (k(nu) mu), or auto: the cheapest whose error bound\n"
        "                    meets --tol (leading, then asymptotic, then shooting).\n"
        "                    A formula asked for where its bound exceeds --tol is a\n"
        "                    numerical failure (exit 1). --continue needs shooting or\n"
        "                    auto (then it shoots). Default auto\n"
        "  --stepper auto|explicit|implicit\n"
        "                    integrator: rk8pd (explicit), bsimp with the analytic\n"
        "                    Jacobian (implicit), or chosen by stiffness; default auto\n"
        "  --format tsv|json output format; default tsv\n"
        "  --out FILE        write to FILE, replaced atomically only on success;\n"
        "                    default standard output\n"
        "  --help            this text\n"
        "\n"
        "columns:\n"
        "  mu, nu              the point\n"
        "  T                   period in z\n"
        "  T_err               estimated absolute error of T (for a formula: its\n"
        "                      error bound times T)\n"
        "  T_asym              k(nu) mu, the leading large-mu term,\n"
        "                      k = 3 + (nu^2 - 1) ln[(4 - nu^2)/(1 - nu^2)]\n"
        "  T_asym2             for mu >= 1 the large-mu expansion\n"
        "                      k mu + a1 C(nu) mu^(-1/3) + L(nu) mu^(-1) ln mu,\n"
        "                      for mu < 1 the small-mu one 2 pi (1 + s2(nu) mu^2)\n"
        "  xmax, xmin          maximum and minimum of f over the cycle\n"
        "  multiplier          nontrivial Floquet multiplier (< 1: the cycle attracts)\n"
        "  log_multiplier      its natural logarithm\n"
        "  steps, rhs_calls, newton_iterations\n"
        "                      work summed over the solve\n"
        "  stepper             GSL stepper used: rk8pd or bsimp (none for a formula)\n"
        "  model               what answered: shooting, asymptotic or leading; for a\n"
        "                      formula xmax, xmin and the multipliers are NaN and the\n"
        "                      work counters 0\n"
        "\n"
        "Output is all or nothing: on any failure nothing is written.\n"
        "exit status: 0 ok, 1 numerical failure, 2 bad input\n",
        BKF_CYCLE_MU_MIN, BKF_CYCLE_MU_MAX, BKF_TOL_MIN, BKF_TOL_MAX);
}

/* Shortest of %.15g / %.17g that reads back exactly: 0.1 stays "0.1" in
 * messages and comments, a computed range point keeps all its bits. */
static const char *num(double x, char *buf, size_t size)
{
    snprintf(buf, size, "%.15g", x);
    if (strtod(buf, NULL) != x) snprintf(buf, size, "%.17g", x);
    return buf;
}

typedef struct {
    const char *mu, *nu, *tol, *continue_, *stepper, *format, *out, *method;
    int log, help;
} period_flags;

typedef struct {
    cli_range mu, nu;
    bkf_cycle_options options;
    bkf_io_format format;
    bkf_cycle_method method;
    int along;               /* -1: points; else BKF_CYCLE_ALONG_MU / _NU */
    const char *out_path;
} period_plan;

static int check_mu_points(const cli_range *mu, bkf_error *err)
{
    char a[32];
    for (size_t i = 0; i < mu->count; i++) {
        double x = mu->values[i];
        if (!(x >= BKF_CYCLE_MU_MIN && x <= BKF_CYCLE_MU_MAX))
            return bkf_error_set(err, BKF_EINPUT, "--mu: mu = %s is outside [%g, %g]",
                                 num(x, a, sizeof a), BKF_CYCLE_MU_MIN, BKF_CYCLE_MU_MAX);
    }
    return BKF_OK;
}

static int check_nu_points(const cli_range *nu, bkf_error *err)
{
    for (size_t i = 0; i < nu->count; i++) {
        bkf_error e;
        if (bkf_model_check_nu_active(nu->values[i], &e) != BKF_OK)
            return bkf_error_set(err, BKF_EINPUT, "--nu: %s", e.message);
    }
    return BKF_OK;
}

/* Everything the user typed, checked, before any computing. */
static int plan_period(int argc, char **argv, period_plan *plan, bkf_error *err)
{
    period_flags f = {0};
    const cli_flag flags[] = {
        {"--mu", &f.mu, MU_FORM, NULL},
        {"--nu", &f.nu, NU_FORM, NULL},
        {"--tol", &f.tol, "a number in [1e-14, 0.1]", NULL},
        {"--log", NULL, NULL, &f.log},
        {"--continue", &f.continue_, "mu or nu", NULL},
        {"--stepper", &f.stepper, "auto, explicit or implicit", NULL},
        {"--method", &f.method, "auto, asymptotic, leading or shooting", NULL},
        {"--format", &f.format, "tsv or json", NULL},
        {"--out", &f.out, "a file name", NULL},
        {"--help", NULL, NULL, &f.help},
    };
    int s = cli_parse_flags(flags, sizeof flags / sizeof flags[0], argc, argv, err);
    if (s) return s;
    if (!f.mu)
        return bkf_error_set(err, BKF_EINPUT, "--mu is required (%s)", MU_FORM);
    if (!f.nu)
        return bkf_error_set(err, BKF_EINPUT, "--nu is required (%s)", NU_FORM);

    if ((s = cli_parse_range("--mu", f.mu, f.log, &plan->mu, err))) return s;
    if ((s = cli_parse_range("--nu", f.nu, 0, &plan->nu, err))) return s;
    if (f.log && plan->nu.is_range)
        return bkf_error_set(err, BKF_EINPUT,
                             "--log: geometric ranges are for --mu only; a --nu range is "
                             "linear (drop --log or give --nu a single value)");
    if ((s = check_mu_points(&plan->mu, err))) return s;
    if ((s = check_nu_points(&plan->nu, err))) return s;
    if (plan->mu.count > CLI_MAX_POINTS / plan->nu.count)
        return bkf_error_set(err, BKF_EINPUT,
                             "--mu, --nu: the grid has %zu x %zu points, more than %u",
                             plan->mu.count, plan->nu.count, CLI_MAX_POINTS);

    plan->options = bkf_cycle_options_default();
    plan->options.warm_start = 1;
    if (f.tol) {
        if ((s = cli_parse_double("--tol", f.tol, &plan->options.tol, err))) return s;
        bkf_error e;
        if (bkf_model_check_tol(plan->options.tol, &e) != BKF_OK)
            return bkf_error_set(err, BKF_EINPUT, "--tol: %s", e.message);
    } else
        plan->options.tol = 1e-10;

    if (f.stepper) {
        int k;
        if ((s = cli_parse_choice("--stepper", f.stepper, stepper_names, &k, err))) return s;
        plan->options.stepper = stepper_kinds[k];
    }
    plan->method = BKF_METHOD_AUTO;
    if (f.method) {
        int k;
        if ((s = cli_parse_choice("--method", f.method, method_names, &k, err))) return s;
        plan->method = method_kinds[k];
    }
    plan->format = BKF_IO_TSV;
    if (f.format) {
        int k;
        if ((s = cli_parse_choice("--format", f.format, format_names, &k, err))) return s;
        plan->format = k == 1 ? BKF_IO_JSON : BKF_IO_TSV;
    }

    plan->along = -1;
    if (f.continue_) {
        int k;
        if ((s = cli_parse_choice("--continue", f.continue_, continue_names, &k, err)))
            return s;
        const cli_range *on = k == 0 ? &plan->mu : &plan->nu;
        const cli_range *other = k == 0 ? &plan->nu : &plan->mu;
        const char *on_flag = k == 0 ? "--mu" : "--nu";
        const char *other_flag = k == 0 ? "--nu" : "--mu";
        if (!on->is_range || on->from == on->to)
            return bkf_error_set(err, BKF_EINPUT,
                                 "--continue %s: %s must be a range A:B:N with A != B",
                                 continue_names[k], on_flag);
        if (other->count != 1)
            return bkf_error_set(err, BKF_EINPUT,
                                 "--continue %s: %s must be a single value, not a range",
                                 continue_names[k], other_flag);
        if (plan->method == BKF_METHOD_ASYMPTOTIC || plan->method == BKF_METHOD_LEADING)
            return bkf_error_set(err, BKF_EINPUT,
                                 "--method %s: --continue follows the shooting equations; use "
                                 "--method shooting or auto", method_names[plan->method]);
        plan->along = k == 0 ? BKF_CYCLE_ALONG_MU : BKF_CYCLE_ALONG_NU;
    }
    if (f.out && !*f.out)
        return bkf_error_set(err, BKF_EINPUT, "--out: the file name is empty");
    plan->out_path = f.out;
    return BKF_OK;
}

typedef struct {
    bkf_io_table *table;
    int status;              /* first failure writing a row */
    bkf_error err;
} period_sink;

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
    return s;
}

static int visit_branch_point(const bkf_cycle_result *point, void *data)
{
    return add_row(data, point) != BKF_OK;
}

static int write_comments(bkf_io_table *table, const period_plan *plan, int argc, char **argv,
                          bkf_error *err)
{
    char a[32], b[32], c[32], d[32], line[512];
    static const char *const kinds[] = {"auto", "explicit", "implicit"};
    const char *stepper = (unsigned)plan->options.stepper < 3 ? kinds[plan->options.stepper] : "?";
    int s = bkf_io_table_comment(
        table,
        CLI_PROGRAM " " CLI_VERSION " period: limit cycle of f'' + mu (f^2 - 1) f' + f = nu\n"
        "T: period in z; T_err: estimated absolute error of T; T_asym: k(nu) mu; "
        "T_asym2: large-mu expansion (mu >= 1) or small-mu expansion (mu < 1)\n"
        "xmax, xmin: extremes of f; multiplier: nontrivial Floquet multiplier, "
        "log_multiplier: its logarithm; steps, rhs_calls, newton_iterations: work of the "
        "solve; stepper: GSL stepper used; model: what answered (shooting, asymptotic, leading; "
        "for a formula T_err is its error bound)",
        err);
    if (s) return s;
    if (plan->along < 0)
        snprintf(line, sizeof line, "tol %s (relative, on T), stepper %s; %zu mu x %zu nu points, mu fastest",
                 num(plan->options.tol, a, sizeof a), stepper, plan->mu.count, plan->nu.count);
    else {
        const cli_range *on = plan->along == BKF_CYCLE_ALONG_MU ? &plan->mu : &plan->nu;
        const cli_range *other = plan->along == BKF_CYCLE_ALONG_MU ? &plan->nu : &plan->mu;
        int mu_along = plan->along == BKF_CYCLE_ALONG_MU;
        snprintf(line, sizeof line,
                 "tol %s (relative, on T), stepper %s; continuation in %s from %s to %s at %s = %s",
                 num(plan->options.tol, a, sizeof a), stepper, mu_along ? "mu" : "nu",
                 num(on->from, b, sizeof b), num(on->to, c, sizeof c), mu_along ? "nu" : "mu",
                 num(other->values[0], d, sizeof d));
    }
    if ((s = bkf_io_table_comment(table, line, err))) return s;
    char *cmd = cli_command_line(argc, argv);
    if (!cmd) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    size_t n = strlen(cmd) + 32;
    char *text = malloc(n);
    if (!text) {
        free(cmd);
        return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    }
    snprintf(text, n, "command: " CLI_PROGRAM " %s", cmd);
    s = bkf_io_table_comment(table, text, err);
    free(text);
    free(cmd);
    return s;
}

/* The table for every point, into `stream`; nothing is printed here. */
static int compute(const period_plan *plan, int argc, char **argv, FILE *stream, bkf_error *err)
{
    char a[32], b[32], c[32];
    period_sink sink = {0};
    sink.table = bkf_io_table_alloc(stream, plan->format, columns, NCOLUMNS, err);
    if (!sink.table) return BKF_ENOMEM;
    int s = write_comments(sink.table, plan, argc, argv, err);

    if (!s && plan->along < 0) {
        bkf_cycle *cycle = bkf_cycle_alloc();
        if (!cycle) s = bkf_error_set(err, BKF_ENOMEM, "out of memory");
        for (size_t j = 0; !s && j < plan->nu.count; j++)
            for (size_t i = 0; !s && i < plan->mu.count; i++) {
                double mu = plan->mu.values[i], nu = plan->nu.values[j];
                bkf_error e;
                bkf_cycle_result r;
                s = bkf_cycle_estimate(cycle, mu, nu, &plan->options, plan->method, &r, &e);
                if (s)
                    bkf_error_set(err, s, "at mu = %s, nu = %s: %s", num(mu, a, sizeof a),
                                  num(nu, b, sizeof b), e.message);
                else if ((s = add_row(&sink, &r)))
                    *err = sink.err;
            }
        bkf_cycle_free(cycle);
    } else if (!s) {
        int mu_along = plan->along == BKF_CYCLE_ALONG_MU;
        const cli_range *on = mu_along ? &plan->mu : &plan->nu;
        double fixed = mu_along ? plan->nu.values[0] : plan->mu.values[0];
        bkf_error e = {{0}};
        /* N only shaped the range's syntax: the continuation's own step
         * control decides the points, hence max_points 0. */
        s = bkf_cycle_branch((bkf_cycle_param)plan->along, on->from, on->to, fixed,
                             &plan->options, 0, visit_branch_point, &sink, &e);
        if (sink.status) {
            s = sink.status;
            *err = sink.err;
        } else if (s)
            bkf_error_set(err, s, "continuation in %s from %s to %s at %s = %s: %s",
                          mu_along ? "mu" : "nu", num(on->from, a, sizeof a),
                          num(on->to, b, sizeof b), mu_along ? "nu" : "mu",
                          num(fixed, c, sizeof c), e.message);
    }
    if (!s) s = bkf_io_table_finish(sink.table, err);
    bkf_io_table_free(sink.table);
    return s;
}

static int period_run(int argc, char **argv, bkf_error *err)
{
    period_plan plan = {0};
    cli_output out = {0};
    cli_buffer buf = {0};
    int s = plan_period(argc, argv, &plan, err);
    if (!s) s = cli_output_open(&out, plan.out_path, "--out", err);
    if (!s) s = cli_buffer_open(&buf, err);
    if (!s) {
        s = compute(&plan, argc, argv, buf.stream, err);
        int c = cli_buffer_close(&buf, s ? NULL : err);
        if (!s) s = c;
    }
    if (!s)
        s = cli_output_write(&out, buf.data, buf.size, err);
    else
        cli_output_abort(&out);
    cli_buffer_free(&buf);
    cli_range_free(&plan.mu);
    cli_range_free(&plan.nu);
    return s;
}

const cli_command cli_cmd_period = {
    "period",
    "period T(mu, nu) of the reduced front equation, at points, on grids or branches",
    period_run,
    period_help,
};

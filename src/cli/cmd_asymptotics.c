/* bkfront asymptotics: the asymptotic formulas for T(mu, nu) checked against
 * the numerical period (module asymfit): fitted against derived
 * coefficients (--fit), where each formula holds to a relative accuracy
 * (--map), and the raw relative errors on a grid (--grid).
 *
 * As in `bkfront period`, every input is checked before the first solve and
 * the table is built in memory and written only when all of it succeeded. */
#include "args.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bkfront/asymfit.h"
#include "bkfront/asymptotics.h"
#include "bkfront/cycle.h"
#include "bkfront/io.h"
#include "bkfront/model.h"

static const bkf_io_column fit_columns[] = {
    {"nu", BKF_IO_NUMBER},       {"fit", BKF_IO_TEXT},        {"coefficient", BKF_IO_TEXT},
    {"fitted", BKF_IO_NUMBER},   {"fitted_err", BKF_IO_NUMBER}, {"derived", BKF_IO_NUMBER},
    {"rel_diff", BKF_IO_NUMBER}, {"mu_lo", BKF_IO_NUMBER},    {"mu_hi", BKF_IO_NUMBER},
    {"npoints", BKF_IO_NUMBER},
};
static const bkf_io_column map_columns[] = {
    {"formula", BKF_IO_TEXT},        {"eps", BKF_IO_NUMBER},   {"nu", BKF_IO_NUMBER},
    {"mu_boundary", BKF_IO_NUMBER},  {"mu_fail", BKF_IO_NUMBER}, {"extent", BKF_IO_TEXT},
};
static const bkf_io_column grid_columns[] = {
    {"mu", BKF_IO_NUMBER},
    {"nu", BKF_IO_NUMBER},
    {"T", BKF_IO_NUMBER},
    {"T_err", BKF_IO_NUMBER},
    {"rel_err_leading", BKF_IO_NUMBER},
    {"rel_err_corrected", BKF_IO_NUMBER},
    {"rel_err_small", BKF_IO_NUMBER},
};
#define COUNT(a) (sizeof (a) / sizeof (a)[0])

static const char *const format_names[] = {"tsv", "json", NULL};

/* The map's default nu: the centre, the middle of each half, and ever closer
 * to the Hopf points nu = +-1 where every expansion degrades. */
static const double default_map_nu[] = {0,     0.5,  -0.5,  0.9,   -0.9,  0.96,
                                        -0.96, 0.99, -0.99, 0.999, -0.999};
static const double default_eps[] = {1e-2, 1e-4, 1e-6};

#define LIST_FORM "V, V1,V2,... or A:B:N"
#define NU_FORM LIST_FORM ", each in (-1, 1)"

static void asymptotics_help(FILE *out)
{
    fprintf(out,
        "usage: bkfront asymptotics --fit --nu LIST [--mu A:B:N] [--small-mu A:B:N]\n"
        "       bkfront asymptotics --map [--nu LIST] [--eps LIST]\n"
        "       bkfront asymptotics --grid --mu M|A:B:N [--log] --nu LIST\n"
        "       (each also takes [--format tsv|json] [--out FILE])\n"
        "\n"
        "The asymptotic formulas for the period T(mu, nu) of\n"
        "f'' + mu (f^2 - 1) f' + f = nu, checked against the numerical T (Newton\n"
        "shooting, tolerance %g, or %g where that is refused):\n"
        "  leading    k(nu) mu,  k = 3 + (nu^2 - 1) ln[(4 - nu^2)/(1 - nu^2)]\n"
        "  corrected  k mu + a1 C(nu) mu^(-1/3) + L(nu) mu^(-1) ln mu\n"
        "  small      2 pi (1 + s2(nu) mu^2),  s2 = (1 - nu^2)(3 + 29 nu^2)/48\n"
        "\n"
        "modes (exactly one):\n"
        "  --fit     fit R = T - k mu = A mu^p + B ln(mu)/mu + D/mu on log-spaced mu,\n"
        "            with p free (NLopt) and with p held at -1/3, and\n"
        "            T/(2 pi) - 1 = s mu^2 + s4 mu^4 at small mu; rows compare the\n"
        "            fitted coefficients with the derived A* = a1 C(nu), p* = -1/3,\n"
        "            B* = L(nu) = -2/(3 (1 - nu^2)), s* = s2(nu). About 1 s per nu.\n"
        "  --map     for each formula, threshold eps and nu, the boundary mu of the\n"
        "            region where |T_formula - T|/T <= eps: for the large-mu formulas\n"
        "            the smallest mu_min from which it holds at every point up to\n"
        "            1e4, for the small-mu one the largest mu_max up to which it holds\n"
        "            from 1e-3 (scan at 8 points per decade, crossing bisected to 2%%).\n"
        "            About 2 s per nu.\n"
        "  --grid    T and the three relative errors on a (mu, nu) grid, mu fastest\n"
        "\n"
        "options:\n"
        "  --nu LIST         nu in (-1, 1): V, a list V1,V2,... or a linear range\n"
        "                    A:B:N. Required for --fit and --grid; --map default\n"
        "                    0,0.5,-0.5,0.9,-0.9,0.96,-0.96,0.99,-0.99,0.999,-0.999\n"
        "  --mu A:B:N        --fit: large-mu fit range, geometric, 1 <= A < B <= %g,\n"
        "                    N >= 10; default 1e2:1e4:12.\n"
        "                    --grid (required): M or A:B:N, each in [%g, %g]\n"
        "  --small-mu A:B:N  --fit: small-mu fit range, geometric, %g <= A < B <= 1,\n"
        "                    N >= 6; default 1e-3:0.1:12\n"
        "  --eps LIST        --map: relative-error thresholds in [1e-10, 1), as V or\n"
        "                    V1,V2,...; default 1e-2,1e-4,1e-6\n"
        "  --log             --grid: geometric --mu range (A, B > 0); default linear\n"
        "  --format tsv|json output format; default tsv\n"
        "  --out FILE        write to FILE, replaced atomically only on success;\n"
        "                    default standard output\n"
        "  --help            this text\n"
        "\n"
        "columns, --fit:\n"
        "  nu                the point\n"
        "  fit               large (A, p, B, D all free), large_p_fixed (p = -1/3;\n"
        "                    A, B, D) or small (s, s4)\n"
        "  coefficient       A, p, B, D, s or s4\n"
        "  fitted, fitted_err  the fitted value and its uncertainty: the larger of\n"
        "                    the residual-scaled standard error and the change when\n"
        "                    refitted on either half of the points\n"
        "  derived           the derived value (nan where none is derived: D, s4)\n"
        "  rel_diff          (fitted - derived)/|derived|\n"
        "  mu_lo, mu_hi, npoints  the fit's range\n"
        "columns, --map:\n"
        "  formula           leading, corrected or small\n"
        "  eps               the relative-error threshold\n"
        "  nu                the point\n"
        "  mu_boundary       mu_min (leading, corrected) or mu_max (small); nan if\n"
        "                    the formula never holds in [1e-3, 1e4]; the range end if\n"
        "                    it holds on all of it\n"
        "  mu_fail           the other end of the final bisection bracket, where the\n"
        "                    formula fails (nan without a crossing)\n"
        "  extent            crossing, everywhere or nowhere\n"
        "columns, --grid:\n"
        "  mu, nu, T, T_err  the point, the period and its estimated absolute error\n"
        "  rel_err_leading, rel_err_corrected, rel_err_small\n"
        "                    |T_formula - T|/T for each formula\n"
        "\n"
        "Output is all or nothing: on any failure nothing is written.\n"
        "exit status: 0 ok, 1 numerical failure, 2 bad input\n",
        BKF_ASYMFIT_TOL, BKF_ASYMFIT_TOL_FALLBACK, BKF_CYCLE_MU_MAX, BKF_CYCLE_MU_MIN,
        BKF_CYCLE_MU_MAX, BKF_CYCLE_MU_MIN);
}

static const char *num(double x, char *buf, size_t size)
{
    return bkf_format_number(x, buf, size);
}

/* The one list grammar (bkfront/options.h); a function of its own for the
 * fuzz target tests/fuzz/fuzz_lists.c. */
static int parse_list(const char *flag, const char *text, cli_range *list, bkf_error *err)
{
    return cli_parse_range(flag, text, 0, list, err);
}

/* A list copied from constants, so that every plan owns its values. */
static int list_of(const double *v, size_t n, cli_range *list, bkf_error *err)
{
    *list = (cli_range){0};
    list->values = malloc(n * sizeof *v);
    if (!list->values) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    memcpy(list->values, v, n * sizeof *v);
    list->count = n;
    list->from = v[0];
    list->to = v[n - 1];
    list->is_range = n > 1;
    return BKF_OK;
}

typedef enum { MODE_FIT, MODE_MAP, MODE_GRID } asym_mode;

typedef struct {
    asym_mode mode;
    cli_range nu, mu, eps;
    bkf_asymfit_large_options large;
    bkf_asymfit_small_options small;
    bkf_io_format format;
    const char *out_path;
} asym_plan;

static void plan_free(asym_plan *plan)
{
    cli_range_free(&plan->nu);
    cli_range_free(&plan->mu);
    cli_range_free(&plan->eps);
}

static int check_nu_list(const cli_range *nu, bkf_error *err)
{
    for (size_t i = 0; i < nu->count; i++) {
        bkf_error e;
        if (bkf_model_check_nu_active(nu->values[i], &e) != BKF_OK)
            return bkf_error_set(err, BKF_EINPUT, "--nu: %s", e.message);
    }
    return BKF_OK;
}

/* A geometric fit range A:B:N with lo <= A < B <= hi and N >= min_n. */
static int parse_fit_range(const char *flag, const char *text, double lo, double hi,
                           size_t min_n, double *from, double *to, size_t *n, bkf_error *err)
{
    char a[32], b[32];
    cli_range r;
    int s = cli_parse_range(flag, text, 1, &r, err);
    if (s) return s;
    *from = r.from;
    *to = r.to;
    *n = r.count;
    int is_range = r.is_range;
    cli_range_free(&r);
    if (!is_range)
        return bkf_error_set(err, BKF_EINPUT, "%s: a fit needs a range A:B:N, not one value",
                             flag);
    if (!(*from >= lo && *from < *to && *to <= hi && *n >= min_n &&
          *n <= BKF_ASYMFIT_MAX_POINTS))
        return bkf_error_set(err, BKF_EINPUT,
                             "%s: fit range %s:%s:%zu is outside %g <= A < B <= %g, "
                             "N in [%zu, %u]",
                             flag, num(*from, a, sizeof a), num(*to, b, sizeof b), *n, lo, hi,
                             min_n, BKF_ASYMFIT_MAX_POINTS);
    return BKF_OK;
}

static int not_with(const char *flag, int given, const char *mode, bkf_error *err)
{
    if (given) return bkf_error_set(err, BKF_EINPUT, "%s: not used with %s", flag, mode);
    return BKF_OK;
}

static int plan_asymptotics(int argc, char **argv, asym_plan *plan, bkf_error *err)
{
    const char *nu = NULL, *mu = NULL, *small_mu = NULL, *eps = NULL, *format = NULL,
               *out = NULL;
    int fit = 0, map = 0, grid = 0, log_ = 0, help = 0;
    const cli_flag flags[] = {
        {"--fit", NULL, NULL, &fit},
        {"--map", NULL, NULL, &map},
        {"--grid", NULL, NULL, &grid},
        {"--nu", &nu, NU_FORM, NULL},
        {"--mu", &mu, "A:B:N (--fit) or M or A:B:N (--grid)", NULL},
        {"--small-mu", &small_mu, "A:B:N", NULL},
        {"--eps", &eps, "V or V1,V2,..., each in [1e-10, 1)", NULL},
        {"--log", NULL, NULL, &log_},
        {"--format", &format, "tsv or json", NULL},
        {"--out", &out, "a file name", NULL},
        {"--help", NULL, NULL, &help},
    };
    int s = cli_parse_flags(flags, COUNT(flags), argc, argv, err);
    if (s) return s;
    if (fit + map + grid != 1)
        return bkf_error_set(err, BKF_EINPUT, "give exactly one of --fit, --map, --grid");
    plan->mode = fit ? MODE_FIT : map ? MODE_MAP : MODE_GRID;
    const char *mode_name = fit ? "--fit" : map ? "--map" : "--grid";

    if ((s = not_with("--small-mu", small_mu && !fit, mode_name, err))) return s;
    if ((s = not_with("--eps", eps && !map, mode_name, err))) return s;
    if ((s = not_with("--log", log_ && !grid, mode_name, err))) return s;
    if ((s = not_with("--mu", mu && map, mode_name, err))) return s;

    if (nu) {
        if ((s = parse_list("--nu", nu, &plan->nu, err))) return s;
    } else if (map) {
        if ((s = list_of(default_map_nu, COUNT(default_map_nu), &plan->nu, err))) return s;
    } else
        return bkf_error_set(err, BKF_EINPUT, "--nu is required with %s (%s)", mode_name,
                             NU_FORM);
    if ((s = check_nu_list(&plan->nu, err))) return s;

    plan->large = bkf_asymfit_large_options_default();
    plan->small = bkf_asymfit_small_options_default();
    if (fit && mu &&
        (s = parse_fit_range("--mu", mu, 1.0, BKF_CYCLE_MU_MAX, 10, &plan->large.mu_lo,
                             &plan->large.mu_hi, &plan->large.npoints, err)))
        return s;
    if (fit && small_mu &&
        (s = parse_fit_range("--small-mu", small_mu, BKF_CYCLE_MU_MIN, 1.0, 6,
                             &plan->small.mu_lo, &plan->small.mu_hi, &plan->small.npoints,
                             err)))
        return s;

    if (map) {
        if (eps) {
            if ((s = parse_list("--eps", eps, &plan->eps, err))) return s;
        } else if ((s = list_of(default_eps, COUNT(default_eps), &plan->eps, err)))
            return s;
        char a[32];
        for (size_t k = 0; k < plan->eps.count; k++) {
            double e = plan->eps.values[k];
            if (!(e >= 1e-10 && e < 1.0))
                return bkf_error_set(err, BKF_EINPUT,
                                     "--eps: eps = %s is outside [1e-10, 1) (below 1e-10 the "
                                     "numerical T cannot judge it)",
                                     num(e, a, sizeof a));
        }
    }

    if (grid) {
        if (!mu)
            return bkf_error_set(err, BKF_EINPUT, "--mu is required with --grid (M or A:B:N)");
        if ((s = cli_parse_range("--mu", mu, log_, &plan->mu, err))) return s;
        char a[32];
        for (size_t i = 0; i < plan->mu.count; i++) {
            double x = plan->mu.values[i];
            if (!(x >= BKF_CYCLE_MU_MIN && x <= BKF_CYCLE_MU_MAX))
                return bkf_error_set(err, BKF_EINPUT, "--mu: mu = %s is outside [%g, %g]",
                                     num(x, a, sizeof a), BKF_CYCLE_MU_MIN, BKF_CYCLE_MU_MAX);
        }
        if (plan->mu.count > CLI_MAX_POINTS / plan->nu.count)
            return bkf_error_set(err, BKF_EINPUT,
                                 "--mu, --nu: the grid has %zu x %zu points, more than %u",
                                 plan->mu.count, plan->nu.count, CLI_MAX_POINTS);
    }

    plan->format = BKF_IO_TSV;
    if (format) {
        int k;
        if ((s = cli_parse_choice("--format", format, format_names, &k, err))) return s;
        plan->format = k == 1 ? BKF_IO_JSON : BKF_IO_TSV;
    }
    if (out && !*out) return bkf_error_set(err, BKF_EINPUT, "--out: the file name is empty");
    plan->out_path = out;
    return BKF_OK;
}

static int comment_command(bkf_io_table *table, int argc, char **argv, bkf_error *err)
{
    char *cmd = cli_command_line(argc, argv);
    if (!cmd) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    size_t n = strlen(cmd) + 32;
    char *text = malloc(n);
    if (!text) {
        free(cmd);
        return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    }
    snprintf(text, n, "command: " CLI_PROGRAM " %s", cmd);
    int s = bkf_io_table_comment(table, text, err);
    free(text);
    free(cmd);
    return s;
}

static int fit_row(bkf_io_table *t, double nu, const char *fit, const char *coef, double value,
                   double value_err, double derived, double lo, double hi, size_t n,
                   bkf_error *err)
{
    double rel = isfinite(derived) ? (value - derived) / fabs(derived) : NAN;
    bkf_io_value v[COUNT(fit_columns)] = {
        {.number = nu},    {.text = fit},        {.text = coef},  {.number = value},
        {.number = value_err}, {.number = derived}, {.number = rel}, {.number = lo},
        {.number = hi},    {.number = (double)n},
    };
    return bkf_io_table_row(t, v, err);
}

/* All fits first, then the table: comments must precede the rows, and they
 * carry each fit's residuals. */
static int run_fit(const asym_plan *plan, bkf_io_table *t, int argc, char **argv,
                   bkf_error *err)
{
    char a[32], b[32], line[512];
    size_t n = plan->nu.count;
    bkf_asymfit_large_result *L = calloc(n, sizeof *L);
    bkf_asymfit_small_result *S = calloc(n, sizeof *S);
    int s = (!L || !S) ? bkf_error_set(err, BKF_ENOMEM, "out of memory") : BKF_OK;
    for (size_t j = 0; !s && j < n; j++) {
        double nu = plan->nu.values[j];
        if (!(s = bkf_asymfit_large(nu, &plan->large, &L[j], err)))
            s = bkf_asymfit_small(nu, &plan->small, &S[j], err);
    }
    if (!s)
        s = bkf_io_table_comment(
            t,
            CLI_PROGRAM " " CLI_VERSION " asymptotics --fit: fitted against derived "
            "coefficients of T(mu, nu)\n"
            "large: R = T - k(nu) mu = A mu^p + B ln(mu)/mu + D/mu, relative least squares, "
            "p by NLopt (BOBYQA) with A, B, D linear at each p; large_p_fixed: the same "
            "with p = -1/3\n"
            "small: (T/(2 pi) - 1) = s mu^2 + s4 mu^4, least squares on (T/(2 pi) - 1)/mu^2\n"
            "derived: A* = a1 C(nu), p* = -1/3, B* = L(nu) = -2/(3 (1 - nu^2)), "
            "s* = (1 - nu^2)(3 + 29 nu^2)/48; fitted_err: max(residual-scaled standard error, "
            "change when refitted on either half of the points)",
            err);
    for (size_t j = 0; !s && j < n; j++) {
        snprintf(line, sizeof line,
                 "nu = %s: rms relative residual %.2e (p free), %.2e (p fixed); small-mu rms "
                 "%.2e; max T_err/T %.1e; %zu cycle solves",
                 num(plan->nu.values[j], a, sizeof a), L[j].rms_rel, L[j].rms_rel_fixed,
                 S[j].rms, fmax(L[j].T_rel_err_max, S[j].T_rel_err_max),
                 L[j].solves + S[j].solves);
        s = bkf_io_table_comment(t, line, err);
    }
    if (!s) {
        snprintf(line, sizeof line, "p searched in [%s, %s]",
                 num(plan->large.p_lo, a, sizeof a), num(plan->large.p_hi, b, sizeof b));
        s = bkf_io_table_comment(t, line, err);
    }
    if (!s) s = comment_command(t, argc, argv, err);
    for (size_t j = 0; !s && j < n; j++) {
        const bkf_asymfit_large_result *r = &L[j];
        const bkf_asymfit_small_result *q = &S[j];
        double nu = r->nu, lo = plan->large.mu_lo, hi = plan->large.mu_hi;
        size_t np = r->npoints;
        if ((s = fit_row(t, nu, "large", "A", r->A, r->A_err, r->A_derived, lo, hi, np, err)) ||
            (s = fit_row(t, nu, "large", "p", r->p, r->p_err, r->p_derived, lo, hi, np, err)) ||
            (s = fit_row(t, nu, "large", "B", r->B, r->B_err, r->B_derived, lo, hi, np, err)) ||
            (s = fit_row(t, nu, "large", "D", r->D, r->D_err, NAN, lo, hi, np, err)) ||
            (s = fit_row(t, nu, "large_p_fixed", "A", r->A_fixed, r->A_fixed_err, r->A_derived,
                         lo, hi, np, err)) ||
            (s = fit_row(t, nu, "large_p_fixed", "B", r->B_fixed, r->B_fixed_err, r->B_derived,
                         lo, hi, np, err)) ||
            (s = fit_row(t, nu, "large_p_fixed", "D", r->D_fixed, r->D_fixed_err, NAN, lo, hi,
                         np, err)) ||
            (s = fit_row(t, nu, "small", "s", q->s, q->s_err, q->s_derived, plan->small.mu_lo,
                         plan->small.mu_hi, q->npoints, err)) ||
            (s = fit_row(t, nu, "small", "s4", q->s4, q->s4_err, NAN, plan->small.mu_lo,
                         plan->small.mu_hi, q->npoints, err)))
            break;
    }
    free(L);
    free(S);
    return s;
}

static int run_map(const asym_plan *plan, bkf_io_table *t, int argc, char **argv,
                   bkf_error *err)
{
    bkf_asymfit_map_options o = bkf_asymfit_map_options_default();
    size_t nnu = plan->nu.count, neps = plan->eps.count;
    if (nnu > CLI_MAX_POINTS / (neps * BKF_ASYMFIT_NFORMULAS))
        return bkf_error_set(err, BKF_EINPUT, "--nu, --eps: too many combinations");
    bkf_asymfit_boundary *b = malloc(nnu * neps * BKF_ASYMFIT_NFORMULAS * sizeof *b);
    if (!b) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    int s = bkf_asymfit_map(plan->nu.values, nnu, plan->eps.values, neps, &o, b, err);
    char line[512], a[32], c[32], d[32];
    if (!s)
        s = bkf_io_table_comment(
            t,
            CLI_PROGRAM " " CLI_VERSION " asymptotics --map: where |T_formula - T|/T <= eps\n"
            "leading: k(nu) mu; corrected: k mu + a1 C(nu) mu^(-1/3) + L(nu) mu^(-1) ln mu; "
            "small: 2 pi (1 + s2(nu) mu^2)\n"
            "mu_boundary: for leading and corrected the smallest mu from which the bound holds "
            "at every scanned mu up to the range's top (mu_min); for small the largest mu up "
            "to which it holds from the range's bottom (mu_max); nan (null in JSON): never holds; "
            "mu_fail: other end of the final bracket",
            err);
    if (!s) {
        snprintf(line, sizeof line,
                 "scan: mu in [%s, %s], %zu points per decade, crossings bisected in ln mu to "
                 "a ratio <= %s; T to tol %g (or %g where refused)",
                 num(o.mu_lo, a, sizeof a), num(o.mu_hi, c, sizeof c), o.per_decade,
                 num(o.refine_ratio, d, sizeof d), BKF_ASYMFIT_TOL, BKF_ASYMFIT_TOL_FALLBACK);
        s = bkf_io_table_comment(t, line, err);
    }
    if (!s) s = comment_command(t, argc, argv, err);
    for (size_t i = 0; !s && i < nnu * neps * BKF_ASYMFIT_NFORMULAS; i++) {
        bkf_io_value v[COUNT(map_columns)] = {
            {.text = bkf_asymfit_formula_name(b[i].formula)},
            {.number = b[i].eps},
            {.number = b[i].nu},
            {.number = b[i].mu_boundary},
            {.number = b[i].mu_fail},
            {.text = bkf_asymfit_extent_name(b[i].extent)},
        };
        s = bkf_io_table_row(t, v, err);
    }
    free(b);
    return s;
}

static int run_grid(const asym_plan *plan, bkf_io_table *t, int argc, char **argv,
                    bkf_error *err)
{
    size_t nmu = plan->mu.count, nnu = plan->nu.count;
    bkf_asymfit_grid_point *g = malloc(nmu * nnu * sizeof *g);
    if (!g) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    int s = bkf_asymfit_grid(plan->mu.values, nmu, plan->nu.values, nnu, g, err);
    char line[256];
    if (!s)
        s = bkf_io_table_comment(
            t,
            CLI_PROGRAM " " CLI_VERSION " asymptotics --grid: relative errors of the "
            "asymptotic formulas\n"
            "T: numerical period; T_err: its estimated absolute error; rel_err_X = "
            "|T_X - T|/T with T_leading = k(nu) mu, T_corrected = k mu + a1 C(nu) mu^(-1/3) "
            "+ L(nu) mu^(-1) ln mu, T_small = 2 pi (1 + s2(nu) mu^2)",
            err);
    if (!s) {
        snprintf(line, sizeof line, "%zu mu x %zu nu points, mu fastest; T to tol %g (or %g "
                 "where refused)", nmu, nnu, BKF_ASYMFIT_TOL, BKF_ASYMFIT_TOL_FALLBACK);
        s = bkf_io_table_comment(t, line, err);
    }
    if (!s) s = comment_command(t, argc, argv, err);
    for (size_t i = 0; !s && i < nmu * nnu; i++) {
        bkf_io_value v[COUNT(grid_columns)] = {
            {.number = g[i].mu},
            {.number = g[i].nu},
            {.number = g[i].T},
            {.number = g[i].T_err},
            {.number = g[i].rel_err[BKF_ASYMFIT_LEADING]},
            {.number = g[i].rel_err[BKF_ASYMFIT_CORRECTED]},
            {.number = g[i].rel_err[BKF_ASYMFIT_SMALL]},
        };
        s = bkf_io_table_row(t, v, err);
    }
    free(g);
    return s;
}

static int compute(const asym_plan *plan, int argc, char **argv, FILE *stream, bkf_error *err)
{
    const bkf_io_column *cols = plan->mode == MODE_FIT   ? fit_columns
                                : plan->mode == MODE_MAP ? map_columns
                                                         : grid_columns;
    size_t ncols = plan->mode == MODE_FIT   ? COUNT(fit_columns)
                   : plan->mode == MODE_MAP ? COUNT(map_columns)
                                            : COUNT(grid_columns);
    bkf_io_table *t = bkf_io_table_alloc(stream, plan->format, cols, ncols, err);
    if (!t) return BKF_ENOMEM;
    int s = plan->mode == MODE_FIT   ? run_fit(plan, t, argc, argv, err)
            : plan->mode == MODE_MAP ? run_map(plan, t, argc, argv, err)
                                     : run_grid(plan, t, argc, argv, err);
    if (!s) s = bkf_io_table_finish(t, err);
    bkf_io_table_free(t);
    return s;
}

static int asymptotics_run(int argc, char **argv, bkf_error *err)
{
    asym_plan plan = {0};
    cli_output out = {0};
    cli_buffer buf = {0};
    int s = plan_asymptotics(argc, argv, &plan, err);
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
    plan_free(&plan);
    return s;
}

const cli_command cli_cmd_asymptotics = {
    "asymptotics",
    "asymptotic formulas for T against the numerical period: fits, validity map, errors",
    asymptotics_run,
    asymptotics_help,
};

#include "bkfront/approx.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bkfront/asymfit.h"
#include "bkfront/cycle.h"
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

/* The map's default nu: the centre, the middle of each half, and ever closer
 * to the Hopf points nu = +-1 where every expansion degrades. */
static const double default_map_nu[] = {0,     0.5,  -0.5,  0.9,   -0.9,  0.96,
                                        -0.96, 0.99, -0.99, 0.999, -0.999};
static const double default_eps[] = {1e-2, 1e-4, 1e-6};

/* Below this the numerical T (tolerance BKF_ASYMFIT_TOL) cannot judge it. */
#define EPS_MIN 1e-10

static const char *const mode_names[] = {"fit", "map", "grid", NULL};

#define NU_FORM "V, V1,V2,... or A:B:N, each in (-1, 1)"

const bkf_option bkf_approx_options[] = {
    {.name = "fit", .type = BKF_OPT_SWITCH, .offset = offsetof(bkf_approx_spec, fit),
     .help = "mode: fit R = T - k mu = A mu^p + B ln(mu)/mu + D/mu on\n"
             "log-spaced mu, with p free (NLopt) and with p held at\n"
             "-1/3, and T/(2 pi) - 1 = s mu^2 + s4 mu^4 at small mu;\n"
             "rows compare the fitted coefficients with the derived\n"
             "A* = a1 C(nu), p* = -1/3, B* = L(nu) = -2/(3 (1 - nu^2)),\n"
             "s* = s2(nu)"},
    {.name = "map", .type = BKF_OPT_SWITCH, .offset = offsetof(bkf_approx_spec, map),
     .help = "mode: for each formula, threshold eps and nu, the\n"
             "boundary mu of the region where |T_formula - T|/T <= eps:\n"
             "for the large-mu formulas the smallest mu_min from which\n"
             "it holds at every point up to 1e4, for the small-mu one\n"
             "the largest mu_max up to which it holds from 1e-3 (scan\n"
             "at 8 points per decade, crossing bisected to 2%)"},
    {.name = "grid", .type = BKF_OPT_SWITCH, .offset = offsetof(bkf_approx_spec, grid),
     .help = "mode: T and the three relative errors on a (mu, nu) grid,\n"
             "mu fastest"},
    {.name = "nu", .type = BKF_OPT_DOUBLE_LIST, .offset = offsetof(bkf_approx_spec, nu),
     .form = "LIST",
     .help = "nu in (-1, 1): V, a list V1,V2,... or a linear range\n"
             "A:B:N. Required for --fit and --grid; --map default\n"
             "0,0.5,-0.5,0.9,-0.9,0.96,-0.96,0.99,-0.99,0.999,-0.999"},
    /* log before mu: it decides how mu's A:B:N is spaced. */
    {.name = "log", .type = BKF_OPT_SWITCH, .offset = offsetof(bkf_approx_spec, log),
     .help = "--grid: geometric --mu range (A, B > 0); default linear"},
    /* Bounds depend on the mode: bkf_approx_check applies them. */
    {.name = "mu", .type = BKF_OPT_DOUBLE_LIST, .offset = offsetof(bkf_approx_spec, mu),
     .flags = BKF_OPT_LOG_SWITCH, .log_offset = offsetof(bkf_approx_spec, log),
     .form = "A:B:N",
     .help = "--fit: large-mu fit range, geometric, 1 <= A < B <= 1e+06,\n"
             "N >= 10; default 1e2:1e4:12.\n"
             "--grid (required): M or A:B:N, each in [1e-06, 1e+06]"},
    {.name = "small-mu", .type = BKF_OPT_DOUBLE_LIST,
     .offset = offsetof(bkf_approx_spec, small_mu), .flags = BKF_OPT_GEOMETRIC,
     .form = "A:B:N",
     .help = "--fit: small-mu fit range, geometric, 1e-06 <= A < B <= 1,\n"
             "N >= 6; default 1e-3:0.1:12"},
    {.name = "eps", .type = BKF_OPT_DOUBLE_LIST, .offset = offsetof(bkf_approx_spec, eps),
     .form = "LIST",
     .help = "--map: relative-error thresholds in [1e-10, 1), as V or\n"
             "V1,V2,...; default 1e-2,1e-4,1e-6"},
    {.name = "mode", .type = BKF_OPT_CHOICE, .offset = offsetof(bkf_approx_spec, mode),
     .flags = BKF_OPT_SCENE_ONLY, .choices = mode_names, .form = "fit|map|grid",
     .help = "fit, map or grid, as the command line's --fit, --map, --grid"},
};
const size_t bkf_approx_noptions = sizeof bkf_approx_options / sizeof bkf_approx_options[0];

bkf_approx_spec bkf_approx_spec_default(void)
{
    bkf_approx_spec s;
    memset(&s, 0, sizeof s);
    s.mode = -1;
    return s;
}

void bkf_approx_spec_free(bkf_approx_spec *spec)
{
    bkf_option_free_lists(bkf_approx_options, bkf_approx_noptions, spec);
}

/* The mode, or -1 when none or more than one was given. */
static int mode_of(const bkf_approx_spec *spec)
{
    int given = (spec->mode >= 0) + !!spec->fit + !!spec->map + !!spec->grid;
    if (given != 1) return -1;
    if (spec->mode >= 0) return spec->mode;
    return spec->fit ? BKF_APPROX_FIT : spec->map ? BKF_APPROX_MAP : BKF_APPROX_GRID;
}

static const char *mode_label(int flags, int mode)
{
    static const char *const switches[] = {"--fit", "--map", "--grid"};
    static const char *const keys[] = {"mode fit", "mode map", "mode grid"};
    return flags ? switches[mode] : keys[mode];
}

static int not_with(const char *p, const char *key, int given, const char *mode,
                    bkf_error *err)
{
    if (given) return bkf_error_set(err, BKF_EINPUT, "%s%s: not used with %s", p, key, mode);
    return BKF_OK;
}

/* A fit range A:B:N with lo <= A < B <= hi and N >= min_n. */
static int check_fit_range(const char *p, const char *key, const bkf_list *r, double lo,
                           double hi, size_t min_n, bkf_error *err)
{
    char a[32], b[32];
    if (!r->is_range)
        return bkf_error_set(err, BKF_EINPUT, "%s%s: a fit needs a range A:B:N, not one value",
                             p, key);
    if (!(r->from >= lo && r->from < r->to && r->to <= hi && r->count >= min_n &&
          r->count <= BKF_ASYMFIT_MAX_POINTS))
        return bkf_error_set(err, BKF_EINPUT,
                             "%s%s: fit range %s:%s:%zu is outside %g <= A < B <= %g, "
                             "N in [%zu, %u]",
                             p, key, bkf_format_number(r->from, a, sizeof a),
                             bkf_format_number(r->to, b, sizeof b), r->count, lo, hi, min_n,
                             BKF_ASYMFIT_MAX_POINTS);
    return BKF_OK;
}

int bkf_approx_check(const bkf_approx_spec *spec, const char *prefix, bkf_error *err)
{
    const char *p = prefix ? prefix : "";
    int flags = strcmp(p, "--") == 0;
    char a[32];
    int mode = mode_of(spec), s;
    if (mode < 0)
        return flags ? bkf_error_set(err, BKF_EINPUT, "give exactly one of --fit, --map, --grid")
                     : bkf_error_set(err, BKF_EINPUT, "%smode: give exactly one of fit, map, grid",
                                     p);
    const char *label = mode_label(flags, mode);
    if ((s = not_with(p, "small-mu", spec->small_mu.count && mode != BKF_APPROX_FIT, label, err)) ||
        (s = not_with(p, "eps", spec->eps.count && mode != BKF_APPROX_MAP, label, err)) ||
        (s = not_with(p, "log", spec->log && mode != BKF_APPROX_GRID, label, err)) ||
        (s = not_with(p, "mu", spec->mu.count && mode == BKF_APPROX_MAP, label, err)))
        return s;

    if (!spec->nu.count && mode != BKF_APPROX_MAP)
        return bkf_error_set(err, BKF_EINPUT, "%snu is required with %s (" NU_FORM ")", p, label);
    for (size_t i = 0; i < spec->nu.count; i++) {
        bkf_error e;
        if (bkf_model_check_nu_active(spec->nu.values[i], &e) != BKF_OK)
            return bkf_error_set(err, BKF_EINPUT, "%snu: %s", p, e.message);
    }

    if (mode == BKF_APPROX_FIT) {
        if (spec->mu.count &&
            (s = check_fit_range(p, "mu", &spec->mu, 1.0, BKF_CYCLE_MU_MAX, 10, err)))
            return s;
        if (spec->small_mu.count &&
            (s = check_fit_range(p, "small-mu", &spec->small_mu, BKF_CYCLE_MU_MIN, 1.0, 6, err)))
            return s;
    } else if (mode == BKF_APPROX_MAP) {
        for (size_t k = 0; k < spec->eps.count; k++) {
            double e = spec->eps.values[k];
            if (!(e >= EPS_MIN && e < 1.0))
                return bkf_error_set(err, BKF_EINPUT,
                                     "%seps: eps = %s is outside [1e-10, 1) (below 1e-10 the "
                                     "numerical T cannot judge it)",
                                     p, bkf_format_number(e, a, sizeof a));
        }
        size_t nnu = spec->nu.count ? spec->nu.count : COUNT(default_map_nu);
        size_t neps = spec->eps.count ? spec->eps.count : COUNT(default_eps);
        if (nnu > BKF_LIST_MAX / (neps * BKF_ASYMFIT_NFORMULAS))
            return bkf_error_set(err, BKF_EINPUT, "%snu, %seps: too many combinations", p, p);
    } else {
        if (!spec->mu.count)
            return bkf_error_set(err, BKF_EINPUT, "%smu is required with %s (M or A:B:N)", p,
                                 label);
        for (size_t i = 0; i < spec->mu.count; i++) {
            double x = spec->mu.values[i];
            if (!(x >= BKF_CYCLE_MU_MIN && x <= BKF_CYCLE_MU_MAX))
                return bkf_error_set(err, BKF_EINPUT, "%smu: mu = %s is outside [%g, %g]", p,
                                     bkf_format_number(x, a, sizeof a), BKF_CYCLE_MU_MIN,
                                     BKF_CYCLE_MU_MAX);
        }
        if (spec->mu.count > BKF_LIST_MAX / spec->nu.count)
            return bkf_error_set(err, BKF_EINPUT,
                                 "%smu, %snu: the grid has %zu x %zu points, more than %u", p, p,
                                 spec->mu.count, spec->nu.count, BKF_LIST_MAX);
    }
    return BKF_OK;
}

/* ------------------------------------------------------------- writing */

/* The spec's nu and eps, or the defaults where none were given. */
typedef struct {
    const double *nu, *eps;
    size_t nnu, neps;
    const char *program;
} approx_inputs;

/* "PROGRAM asymptotics --MODE: " followed by `text`, as comments. */
static int comment_title(bkf_io_table *t, const char *program, const char *mode, const char *text,
                         bkf_error *err)
{
    size_t n = strlen(program) + strlen(mode) + strlen(text) + 32;
    char *line = malloc(n);
    if (!line) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    snprintf(line, n, "%s asymptotics --%s: %s", program, mode, text);
    int s = bkf_io_table_comment(t, line, err);
    free(line);
    return s;
}

static int comment_command(bkf_io_table *t, const bkf_provenance *prov, bkf_error *err)
{
    if (!prov || !prov->command) return BKF_OK;
    size_t n = strlen(prov->command) + 16;
    char *text = malloc(n);
    if (!text) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    snprintf(text, n, "command: %s", prov->command);
    int s = bkf_io_table_comment(t, text, err);
    free(text);
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
static int write_fit(const bkf_approx_spec *spec, const approx_inputs *in, bkf_io_table *t,
                     const bkf_provenance *prov, bkf_error *err)
{
    char a[32], b[32], line[512];
    bkf_asymfit_large_options large = bkf_asymfit_large_options_default();
    bkf_asymfit_small_options small = bkf_asymfit_small_options_default();
    if (spec->mu.count) {
        large.mu_lo = spec->mu.from;
        large.mu_hi = spec->mu.to;
        large.npoints = spec->mu.count;
    }
    if (spec->small_mu.count) {
        small.mu_lo = spec->small_mu.from;
        small.mu_hi = spec->small_mu.to;
        small.npoints = spec->small_mu.count;
    }
    size_t n = in->nnu;
    bkf_asymfit_large_result *L = calloc(n, sizeof *L);
    bkf_asymfit_small_result *S = calloc(n, sizeof *S);
    int s = (!L || !S) ? bkf_error_set(err, BKF_ENOMEM, "out of memory") : BKF_OK;
    for (size_t j = 0; !s && j < n; j++) {
        double nu = in->nu[j];
        if (!(s = bkf_asymfit_large(nu, &large, &L[j], err)))
            s = bkf_asymfit_small(nu, &small, &S[j], err);
    }
    if (!s)
        s = comment_title(
            t, in->program, "fit",
            "fitted against derived coefficients of T(mu, nu)\n"
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
                 bkf_format_number(in->nu[j], a, sizeof a), L[j].rms_rel, L[j].rms_rel_fixed,
                 S[j].rms, fmax(L[j].T_rel_err_max, S[j].T_rel_err_max),
                 L[j].solves + S[j].solves);
        s = bkf_io_table_comment(t, line, err);
    }
    if (!s) {
        snprintf(line, sizeof line, "p searched in [%s, %s]",
                 bkf_format_number(large.p_lo, a, sizeof a),
                 bkf_format_number(large.p_hi, b, sizeof b));
        s = bkf_io_table_comment(t, line, err);
    }
    if (!s) s = comment_command(t, prov, err);
    for (size_t j = 0; !s && j < n; j++) {
        const bkf_asymfit_large_result *r = &L[j];
        const bkf_asymfit_small_result *q = &S[j];
        double nu = r->nu, lo = large.mu_lo, hi = large.mu_hi;
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
            (s = fit_row(t, nu, "small", "s", q->s, q->s_err, q->s_derived, small.mu_lo,
                         small.mu_hi, q->npoints, err)) ||
            (s = fit_row(t, nu, "small", "s4", q->s4, q->s4_err, NAN, small.mu_lo, small.mu_hi,
                         q->npoints, err)))
            break;
    }
    free(L);
    free(S);
    return s;
}

static int write_map(const approx_inputs *in, bkf_io_table *t, const bkf_provenance *prov,
                     bkf_error *err)
{
    bkf_asymfit_map_options o = bkf_asymfit_map_options_default();
    size_t nnu = in->nnu, neps = in->neps, nrows = nnu * neps * BKF_ASYMFIT_NFORMULAS;
    bkf_asymfit_boundary *b = malloc(nrows * sizeof *b);
    if (!b) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    int s = bkf_asymfit_map(in->nu, nnu, in->eps, neps, &o, b, err);
    char line[512], a[32], c[32], d[32];
    if (!s)
        s = comment_title(
            t, in->program, "map",
            "where |T_formula - T|/T <= eps\n"
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
                 bkf_format_number(o.mu_lo, a, sizeof a), bkf_format_number(o.mu_hi, c, sizeof c),
                 o.per_decade, bkf_format_number(o.refine_ratio, d, sizeof d), BKF_ASYMFIT_TOL,
                 BKF_ASYMFIT_TOL_FALLBACK);
        s = bkf_io_table_comment(t, line, err);
    }
    if (!s) s = comment_command(t, prov, err);
    for (size_t i = 0; !s && i < nrows; i++) {
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

static int write_grid(const bkf_approx_spec *spec, const approx_inputs *in, bkf_io_table *t,
                      const bkf_provenance *prov, bkf_error *err)
{
    size_t nmu = spec->mu.count, nnu = in->nnu;
    bkf_asymfit_grid_point *g = malloc(nmu * nnu * sizeof *g);
    if (!g) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    int s = bkf_asymfit_grid(spec->mu.values, nmu, in->nu, nnu, g, err);
    char line[256];
    if (!s)
        s = comment_title(
            t, in->program, "grid",
            "relative errors of the asymptotic formulas\n"
            "T: numerical period; T_err: its estimated absolute error; rel_err_X = "
            "|T_X - T|/T with T_leading = k(nu) mu, T_corrected = k mu + a1 C(nu) mu^(-1/3) "
            "+ L(nu) mu^(-1) ln mu, T_small = 2 pi (1 + s2(nu) mu^2)",
            err);
    if (!s) {
        snprintf(line, sizeof line, "%zu mu x %zu nu points, mu fastest; T to tol %g (or %g "
                 "where refused)", nmu, nnu, BKF_ASYMFIT_TOL, BKF_ASYMFIT_TOL_FALLBACK);
        s = bkf_io_table_comment(t, line, err);
    }
    if (!s) s = comment_command(t, prov, err);
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

int bkf_approx_write(const bkf_approx_spec *spec, FILE *out, bkf_io_format format,
                     const bkf_provenance *prov, bkf_error *err)
{
    int s = bkf_approx_check(spec, "", err);
    if (s) return s;
    int mode = mode_of(spec);
    approx_inputs in = {
        spec->nu.count ? spec->nu.values : default_map_nu,
        spec->eps.count ? spec->eps.values : default_eps,
        spec->nu.count ? spec->nu.count : COUNT(default_map_nu),
        spec->eps.count ? spec->eps.count : COUNT(default_eps),
        prov && prov->program ? prov->program : "libbkfront",
    };
    const bkf_io_column *cols = mode == BKF_APPROX_FIT   ? fit_columns
                                : mode == BKF_APPROX_MAP ? map_columns
                                                         : grid_columns;
    size_t ncols = mode == BKF_APPROX_FIT   ? COUNT(fit_columns)
                   : mode == BKF_APPROX_MAP ? COUNT(map_columns)
                                            : COUNT(grid_columns);
    bkf_io_table *t = bkf_io_table_alloc(out, format, cols, ncols, err);
    if (!t) return BKF_ENOMEM;
    s = mode == BKF_APPROX_FIT   ? write_fit(spec, &in, t, prov, err)
        : mode == BKF_APPROX_MAP ? write_map(&in, t, prov, err)
                                 : write_grid(spec, &in, t, prov, err);
    if (!s) s = bkf_io_table_finish(t, err);
    bkf_io_table_free(t);
    return s;
}

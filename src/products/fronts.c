#include "bkfront/fronts.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_errno.h>
#include <gsl/gsl_roots.h>

#include "bkfront/chainwave.h"
#include "bkfront/cycle.h"
#include "bkfront/trainspec.h"

#include "fronts_internal.h"
#include "product_internal.h"

#define ROOT_COLUMNS                                                                   \
    {"n", BKF_IO_NUMBER}, {"v", BKF_IO_NUMBER}, {"mu", BKF_IO_NUMBER},                 \
    {"T", BKF_IO_NUMBER}, {"T_err", BKF_IO_NUMBER}, {"v_over_c", BKF_IO_NUMBER},       \
    {"wavelength", BKF_IO_NUMBER}, {"period_fixed", BKF_IO_NUMBER},                    \
    {"v_asym", BKF_IO_NUMBER}, {"deviation", BKF_IO_NUMBER}, {"v_err", BKF_IO_NUMBER}, \
    {"model", BKF_IO_TEXT}, {"residual", BKF_IO_NUMBER}, {"slope", BKF_IO_NUMBER},     \
    {"flags", BKF_IO_TEXT}

/* Each root's spectral verdict (speeds and branch with stability). */
#define VERDICT_COLUMNS                                                       \
    {"stable", BKF_IO_TEXT}, {"sigma_max", BKF_IO_NUMBER},                    \
    {"sigma_max_err", BKF_IO_NUMBER}, {"kappa_max", BKF_IO_NUMBER}, {"kind", BKF_IO_TEXT}
#define PARAM_COLUMNS                                                         \
    {"point", BKF_IO_TEXT}, {"S", BKF_IO_NUMBER}, {"gamma", BKF_IO_NUMBER},   \
    {"c", BKF_IO_NUMBER}, {"nu", BKF_IO_NUMBER}

static const bkf_io_column speeds_columns[] = {ROOT_COLUMNS};
static const bkf_io_column stability_columns[] = {ROOT_COLUMNS, VERDICT_COLUMNS};
static const bkf_io_column branch_columns[] = {PARAM_COLUMNS, ROOT_COLUMNS};
static const bkf_io_column branch_stability_columns[] = {PARAM_COLUMNS, ROOT_COLUMNS,
                                                         VERDICT_COLUMNS};
#define NSPEEDS (sizeof speeds_columns / sizeof speeds_columns[0])
#define NBRANCH (sizeof branch_columns / sizeof branch_columns[0])
#define NPARAM (NBRANCH - NSPEEDS)
#define NSTABILITY (sizeof stability_columns / sizeof stability_columns[0])
#define NBRANCH_STABILITY (sizeof branch_stability_columns / sizeof branch_stability_columns[0])

_Static_assert(NSPEEDS == BKF_FRONTS_ROOT_COLUMNS, "the root's columns");

#define CHAIN_COLUMNS                                                                  \
    {"n", BKF_IO_NUMBER}, {"v", BKF_IO_NUMBER}, {"v_err", BKF_IO_NUMBER},              \
    {"P", BKF_IO_NUMBER}, {"P_err", BKF_IO_NUMBER}, {"tau", BKF_IO_NUMBER},           \
    {"h", BKF_IO_NUMBER}, {"wavelength", BKF_IO_NUMBER}, {"residual", BKF_IO_NUMBER}, \
    {"psi_min", BKF_IO_NUMBER}, {"psi_max", BKF_IO_NUMBER}
static const bkf_io_column chain_columns[] = {
    CHAIN_COLUMNS, {"stable", BKF_IO_TEXT}, {"sigma_max", BKF_IO_NUMBER},
    {"sigma_max_err", BKF_IO_NUMBER}, {"mult_abs", BKF_IO_NUMBER},
    {"mult_abs_err", BKF_IO_NUMBER}, {"mult_arg", BKF_IO_NUMBER}, {"trivial_err", BKF_IO_NUMBER}};
_Static_assert(sizeof chain_columns / sizeof chain_columns[0] ==
                   BKF_FRONTS_CHAIN_STABILITY_COLUMNS, "the chain's columns");

static const char *const model_names[] = {"continuum", "chain", NULL};
/* S, nu, gamma, c in bkf_speeds_param order; h the chain's alone */
static const char *const param_names[] = {"S", "nu", "gamma", "c", "h", NULL};
static const char *const method_names[] = {"auto", "asymptotic", "leading", "shooting", NULL};
static const bkf_cycle_method method_kinds[] = {BKF_METHOD_AUTO, BKF_METHOD_ASYMPTOTIC,
                                                BKF_METHOD_LEADING, BKF_METHOD_SHOOTING};

#define BOUNDED (BKF_OPT_MIN | BKF_OPT_MAX)

/* The model's keys, shared by both products' tables, the paper's values by
 * default (branch: but the continued one, which its check sees).  nu's
 * range is the checks' (check_nu), whose message says why. */
#define MODEL_OPTIONS(SPEC)                                                                  \
    BKF_PRODUCT_GAMMA_OPTION(SPEC),                                                          \
    {.name = "c", .type = BKF_OPT_DOUBLE, .offset = offsetof(SPEC, c),                       \
     .flags = BKF_OPT_MIN | BKF_OPT_MAX, .min = 0, .max = BKF_MODEL_C_MAX, .form = "C",       \
     .shown_default = BKF_TEXT_OF(BKF_PAPER_C), .help = "sound speed, in [0, 1e6]"},          \
    BKF_PRODUCT_NU_OPTION(SPEC), BKF_PRODUCT_S_OPTION(SPEC)

#define TOL_OPTION(SPEC, what)                                                                \
    {.name = "tol", .type = BKF_OPT_DOUBLE, .offset = offsetof(SPEC, tol), .flags = BOUNDED,  \
     .min = BKF_TOL_MIN, .max = BKF_TOL_MAX, .form = "E", .shown_default = "1e-10",           \
     .help = what ",\nin [1e-14, 0.1]"}

/* --stability-tol, the same for both products (checked by check_stability). */
#define STABILITY_TOL_OPTION(SPEC)                                                            \
    {.name = "stability-tol", .type = BKF_OPT_DOUBLE, .offset = offsetof(SPEC, stability_tol), \
     .flags = BOUNDED, .min = BKF_TRAINSPEC_TOL_MIN, .max = BKF_TRAINSPEC_TOL_MAX, .form = "E", \
     .shown_default = "1e-6",                                                                 \
     .help = "with --stability: absolute accuracy asked of each sigma,\n"                     \
             "in [1e-08, 0.01]"}

/* ---------------------------------------------------------------- speeds */

const bkf_option bkf_fronts_options[] = {
    MODEL_OPTIONS(bkf_fronts_spec),
    {.name = "n", .type = BKF_OPT_COUNT, .offset = offsetof(bkf_fronts_spec, n), .flags = BOUNDED,
     .min = 1, .max = 1e9, .form = "N", .help = "only the roots for this n"},
    {.name = "nmax", .type = BKF_OPT_COUNT, .offset = offsetof(bkf_fronts_spec, nmax),
     .flags = BOUNDED, .min = 1, .max = BKF_FRONTS_NMAX_MAX, .form = "N",
     .help = "only n <= N; default every n up to n_max, but no more\n"
             "than 1000 values of n (rows n <= 10 when c = 0)"},
    TOL_OPTION(bkf_fronts_spec, "relative accuracy asked of v, and bound on |residual|"),
    {.name = "method", .type = BKF_OPT_CHOICE, .offset = offsetof(bkf_fronts_spec, method),
     .choices = method_names, .form = "auto|asymptotic|leading|shooting", .shown_default = "auto",
     .help = "how T is obtained at the roots (column model): auto\n"
             "takes a formula wherever its verified error bound meets the\n"
             "tolerance the root needs (about tol, 0.1..10 tol), else\n"
             "shooting; asymptotic or leading: the formula at every root,\n"
             "a refused row where its bound exceeds that; shooting: never a formula\n"
             "(except beyond the grid's cap, flag asymptotic)"},
    {.name = "stability", .type = BKF_OPT_SWITCH, .offset = offsetof(bkf_fronts_spec, stability),
     .help = "add each root's spectral stability (its ring spectrum, as\n"
             "bkfront stability): columns stable, sigma_max, sigma_max_err,\n"
             "kappa_max, kind; needs c > 0"},
    STABILITY_TOL_OPTION(bkf_fronts_spec),
    {.name = "model", .type = BKF_OPT_CHOICE, .offset = offsetof(bkf_fronts_spec, model),
     .choices = model_names, .form = "continuum|chain", .shown_default = "continuum",
     .help = "chain: the rotating waves of the chain of --N blocks\n"
             "(spacing h = S/N), with their Floquet multipliers under\n"
             "--stability; --tol in [1e-11, 0.001]; other columns (see below)"},
    {.name = "N", .type = BKF_OPT_COUNT, .offset = offsetof(bkf_fronts_spec, N), .flags = BOUNDED,
     .min = BKF_CHAINWAVE_N_MIN, .max = BKF_CHAINWAVE_N_MAX, .form = "N",
     .help = "with --model chain: blocks, in [2, 400]; default S (a\n"
             "whole number then)"},
};
const size_t bkf_fronts_noptions = sizeof bkf_fronts_options / sizeof bkf_fronts_options[0];

bkf_fronts_spec bkf_fronts_spec_default(void)
{
    bkf_fronts_spec s;
    memset(&s, 0, sizeof s);
    s.gamma = s.c = s.nu = s.S = NAN;
    bkf_model_paper_where_unset(&s.gamma, &s.c, &s.nu, &s.S);
    s.tol = bkf_speeds_options_default().tol;
    s.method = 0;
    return s;
}

/* |nu| >= 1: no limit cycle, hence no fronts. */
static int check_nu(const char *p, double nu, bkf_error *err)
{
    char a[32];
    if (!(fabs(nu) < 1.0))
        return bkf_error_set(err, BKF_EINPUT,
                             "%snu: nu = %s is outside (-1, 1): no fronts, uniform continuous "
                             "slip psi = nu is stable (no limit cycle)",
                             p, bkf_format_number(nu, a, sizeof a));
    return BKF_OK;
}

/* The stability keys (c: the model's, or 1 where the branch checks it). */
static int check_stability(const char *p, int stability, double tol, double c, bkf_error *err)
{
    if (tol != 0 && !stability)
        return bkf_error_set(err, BKF_EINPUT, "%sstability-tol: only with %sstability", p, p);
    if (tol != 0 && !(tol >= BKF_TRAINSPEC_TOL_MIN && tol <= BKF_TRAINSPEC_TOL_MAX))
        return bkf_error_set(err, BKF_EINPUT, "%sstability-tol: not in [%g, %g]", p, BKF_TRAINSPEC_TOL_MIN,
                             BKF_TRAINSPEC_TOL_MAX);
    if (stability && !(c > 0))
        return bkf_error_set(err, BKF_EINPUT,
                             "%sstability: needs %sc > 0 (with c = 0 the fronts are phase waves "
                             "of uncoupled oscillators: every mode is neutral)", p, p);
    return BKF_OK;
}

static bkf_model_params model_of(double gamma, double c, double nu, double S)
{
    bkf_model_params p;
    memset(&p, 0, sizeof p);
    p.gamma = gamma;
    p.c = c;
    p.nu = nu;
    p.S = S;
    p.kind = BKF_MODEL_CONTINUUM;
    return p;
}

void bkf_fronts_setup(const bkf_fronts_spec *spec, bkf_model_params *params,
                      bkf_speeds_options *options)
{
    *params = model_of(spec->gamma, spec->c, spec->nu, spec->S);
    *options = bkf_speeds_options_default();
    options->tol = spec->tol;
    options->method = (unsigned)spec->method < 4 ? method_kinds[spec->method] : BKF_METHOD_AUTO;
    if (spec->n) options->n_from = options->n_to = spec->n;
    if (spec->nmax) options->n_to = spec->nmax;
}

/* The chain's parameters and options from the spec (N defaulting to S). */
static void chain_setup(const bkf_fronts_spec *spec, bkf_model_params *params,
                        bkf_chainwave_options *options)
{
    *params = model_of(spec->gamma, spec->c, spec->nu, spec->S);
    params->kind = BKF_MODEL_CHAIN;
    params->N = spec->N ? spec->N : (size_t)llround(spec->S);
    *options = bkf_chainwave_options_default();
    options->tol = spec->tol;
    options->stability = spec->stability;
}

static int chain_check(const bkf_fronts_spec *spec, const char *p, bkf_error *err)
{
    if (spec->method != 0)
        return bkf_error_set(err, BKF_EINPUT, "%smethod: continuum only (the chain has no "
                             "formula for its waves)", p);
    if (spec->stability_tol != 0)
        return bkf_error_set(err, BKF_EINPUT, "%sstability-tol: continuum only (the chain's "
                             "multipliers are computed to %stol)", p, p);
    if (!spec->N && !(spec->S >= BKF_CHAINWAVE_N_MIN && spec->S <= BKF_CHAINWAVE_N_MAX &&
                      spec->S == floor(spec->S)))
        return bkf_error_set(err, BKF_EINPUT, "%sN: required when S = %g is not a whole number "
                             "in [%d, %d] (blocks, spacing h = S/N)", p, spec->S,
                             BKF_CHAINWAVE_N_MIN, BKF_CHAINWAVE_N_MAX);
    if (!(spec->tol >= BKF_CHAINWAVE_TOL_MIN && spec->tol <= BKF_CHAINWAVE_TOL_MAX))
        return bkf_error_set(err, BKF_EINPUT, "%stol: %g is outside [%g, %g] for the chain", p,
                             spec->tol, BKF_CHAINWAVE_TOL_MIN, BKF_CHAINWAVE_TOL_MAX);
    bkf_model_params params;
    bkf_chainwave_options options;
    chain_setup(spec, &params, &options);
    size_t top = spec->n ? spec->n : spec->nmax ? spec->nmax : params.N / 2;
    if (top > params.N)
        return bkf_error_set(err, BKF_EINPUT, "%s%s: %zu is outside [1, N = %zu]", p,
                             spec->n ? "n" : "nmax", top, params.N);
    bkf_error e;
    if (bkf_chainwave_check(&params, top ? top : 1, &options, &e) != BKF_OK)
        return bkf_error_set(err, BKF_EINPUT, "%sgamma, %sc, %sS, %sN: %s", p, p, p, p, e.message);
    return BKF_OK;
}

int bkf_fronts_check(const bkf_fronts_spec *spec, const char *prefix, bkf_error *err)
{
    if (!spec) return bkf_error_set(err, BKF_EINPUT, "speeds: spec is NULL");
    const char *p = prefix ? prefix : "";
    if ((unsigned)spec->model > 1)
        return bkf_error_set(err, BKF_EINPUT, "%smodel: not continuum or chain", p);
    if (spec->model == 0 && spec->N)
        return bkf_error_set(err, BKF_EINPUT, "%sN: only with %smodel chain", p, p);
    if (spec->n && spec->nmax)
        return bkf_error_set(err, BKF_EINPUT,
                             "%sn, %snmax: give one of them (%sn N: that n only; %snmax N: "
                             "n <= N)", p, p, p, p);
    if ((unsigned)spec->method >= 4)
        return bkf_error_set(err, BKF_EINPUT, "%smethod: not auto, asymptotic, leading or shooting", p);
    int s = check_stability(p, spec->stability, spec->stability_tol, spec->c, err);
    if (s) return s;
    s = check_nu(p, spec->nu, err);
    if (s) return s;
    if (spec->model == 1) return chain_check(spec, p, err);
    bkf_model_params params;
    bkf_speeds_options options;
    bkf_fronts_setup(spec, &params, &options);
    bkf_error e;
    if (bkf_speeds_check(&params, &options, &e) != BKF_OK)
        return bkf_error_set(err, BKF_EINPUT, "%sS, %sc, %sgamma: %s", p, p, p, e.message);
    return BKF_OK;
}

const bkf_io_column *bkf_fronts_columns(size_t *count)
{
    if (count) *count = NSPEEDS;
    return speeds_columns;
}

static const char *flag_text(unsigned flags)
{
    /* indexed by the flags' bits: near-tangent 1, asymptotic 2, refused 4 */
    static const char *const text[8] = {
        "", "near-tangent", "asymptotic", "near-tangent,asymptotic",
        "refused", "near-tangent,refused", "asymptotic,refused",
        "near-tangent,asymptotic,refused"};
    return text[flags & (BKF_SPEEDS_NEAR_TANGENT | BKF_SPEEDS_ASYMPTOTIC | BKF_SPEEDS_REFUSED)];
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
    v[11].text = r->status != BKF_OK ? NULL : r->model ? r->model : "shooting";
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
static int range_of_n(bkf_io_table *table, double c, const bkf_speeds_table *t, bkf_error *err)
{
    char line[640];
    int c_positive = c > 0;
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

/* A root's ring spectrum, or why it has none. */
typedef struct {
    bkf_trainspec_result spectrum;
    bkf_error why; /* status BKF_OK where the spectrum was computed */
} root_verdict;

static double verdict_tol(double stability_tol)
{
    return stability_tol != 0 ? stability_tol : bkf_trainspec_options_default().tol;
}

/* A root whose spectrum does not meet the tolerance within the budget is
 * unresolved (r->why says why); any other failure is the table's.  A
 * refused root has no spectrum: r->why is its refusal. */
static int verdict_find(const bkf_model_params *p, const bkf_speeds_root *root, double tol,
                        size_t per_kappa, root_verdict *r, bkf_error *err)
{
    if (bkf_speeds_root_status(root, &r->why)) return BKF_OK;
    /* per_kappa 1 (or 0, speeds' rows): where sigma_max alone is shown,
     * which does not depend on it beyond its error, fewer eigenvalues to
     * refine cost less (the paper's n = 12: 0.8 s for 1.1 s at 3); a
     * branch's ring spectra 2 (TRACK_PER_KAPPA) */
    int s = bkf_trainspec_root(p, root, tol, per_kappa, &r->spectrum, &r->why);
    r->why.status = s;
    if (s && s != BKF_ETOL && s != BKF_EBUDGET) return bkf_error_set(err, s, "%s", r->why.message);
    return BKF_OK;
}

static int verdict_resolved(const root_verdict *r)
{
    return r->why.status == BKF_OK;
}

/* The stable, sigma_max, sigma_max_err, kappa_max and kind cells; a
 * sigma_max that is only the window's bound is nan (bkf_trainspec_shown_of),
 * its verdict kept. */
static void verdict_values(const bkf_speeds_root *root, const root_verdict *r, bkf_io_value *v)
{
    int ok = verdict_resolved(r);
    bkf_trainspec_shown x = bkf_trainspec_shown_of(&r->spectrum);
    v[0].text = ok                       ? bkf_trainspec_verdict_name(r->spectrum.verdict)
                : root->status != BKF_OK ? "refused"
                                         : "unresolved";
    v[1].number = ok ? x.sigma_max : NAN;
    v[2].number = ok ? x.sigma_max_err : NAN;
    v[3].number = ok ? x.kappa_max : NAN;
    v[4].text = ok ? x.kind : NULL;
}

/* The window's edge when a resolved verdict's sigma_max is only that bound, else NaN. */
static double verdict_bound(const root_verdict *r)
{
    return verdict_resolved(r) ? bkf_trainspec_shown_of(&r->spectrum).bound : NAN;
}

static int verdict_comment(bkf_io_table *table, double tol, bkf_error *err)
{
    char a[32];
    return bkf_io_table_commentf(table, err,
                                 "stability: each root's ring spectrum (bkfront stability), "
                                 "tol %s (absolute, on sigma); sigma_max is the rightmost "
                                 "Re sigma but the translation",
                                 bkf_format_number(tol, a, sizeof a));
}

/* Each root's verdict, for the speeds table. */
typedef struct {
    double tol;
    root_verdict *verdicts; /* one per root */
} root_spectra;

static void root_spectra_free(root_spectra *r, size_t count)
{
    for (size_t i = 0; r->verdicts && i < count; i++)
        bkf_trainspec_result_free(&r->verdicts[i].spectrum);
    free(r->verdicts);
}

static int find_spectra(const bkf_model_params *p, const bkf_speeds_table *t, double tol,
                        root_spectra *r, bkf_error *err)
{
    r->tol = verdict_tol(tol);
    r->verdicts = calloc(t->count ? t->count : 1, sizeof *r->verdicts);
    if (!r->verdicts) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    int s = BKF_OK;
    /* per_kappa 0: the rows show sigma_max alone, and the rightmost alone
     * refined costs less (the paper's n = 12: 3 eigenvalues of 12 on its
     * two finer meshes) */
    for (size_t i = 0; !s && i < t->count; i++)
        s = verdict_find(p, &t->roots[i], r->tol, 0, &r->verdicts[i], err);
    return s;
}

/* The comments on the spectra: the tolerance, and each unresolved root. */
static int spectra_comments(bkf_io_table *table, const bkf_speeds_table *t, const root_spectra *r,
                            bkf_error *err)
{
    int s = verdict_comment(table, r->tol, err);
    for (size_t i = 0, root = 1; !s && i < t->count; i++) {
        root = i > 0 && t->roots[i - 1].n == t->roots[i].n ? root + 1 : 1;
        char note[200];
        double bound = verdict_bound(&r->verdicts[i]);
        if (t->roots[i].status != BKF_OK) continue; /* its own comment says why */
        if (!verdict_resolved(&r->verdicts[i]))
            s = bkf_io_table_commentf(table, err, "stability of n %zu, root %zu unresolved: %s",
                                      t->roots[i].n, root, r->verdicts[i].why.message);
        else if (isfinite(bound))
            s = bkf_io_table_commentf(table, err, "stability of n %zu, root %zu: %s",
                                      t->roots[i].n, root,
                                      bkf_trainspec_bound_note(bound, note, sizeof note));
    }
    return s;
}

/* Each refused root's comment: where it lies and why v cannot be had to
 * tol there (its row's numbers are NaN). */
static int refused_comments(bkf_io_table *table, const bkf_speeds_table *t, bkf_error *err)
{
    int s = number_result(table, "refused", (double)t->refused, err);
    for (size_t i = 0, root = 1; !s && i < t->count; i++) {
        root = i > 0 && t->roots[i - 1].n == t->roots[i].n ? root + 1 : 1;
        if (t->roots[i].status != BKF_OK)
            s = bkf_io_table_commentf(table, err, "refused: n = %zu, root %zu: %s",
                                      t->roots[i].n, root, t->roots[i].refusal);
    }
    return s;
}

/* The one line a caller is told when rows were refused. */
static void warn_refused(const bkf_fronts_spec *spec, const bkf_speeds_table *t)
{
    if (!t->refused || !spec->warn) return;
    for (size_t i = 0; i < t->count; i++) {
        if (t->roots[i].status == BKF_OK) continue;
        /* one line that fits a bkf_error (its prefix under 60 characters):
         * the table's comments have each whole */
        char line[BKF_ERROR_LEN + 100];
        snprintf(line, sizeof line, "%zu of %zu roots refused, the first n = %zu: %.260s",
                 t->refused, t->count, t->roots[i].n, t->roots[i].refusal);
        spec->warn(line, spec->warn_data);
        return;
    }
}

static int write_speeds(const bkf_model_params *p, const bkf_speeds_options *o,
                        const bkf_speeds_table *t, const root_spectra *spectra, FILE *out,
                        bkf_io_format format, const bkf_provenance *prov, bkf_error *err)
{
    bkf_io_table *table;
    int s = bkf_product_table_open(
        out, format, spectra ? stability_columns : speeds_columns,
        spectra ? NSTABILITY : NSPEEDS,
        "speeds: roots v > c of n T(mu(v)) = S / (v sqrt(1 - c^2/v^2)), "
        "mu(v) = gamma / sqrt(1 - c^2/v^2)",
        prov, &table, err);
    if (s) return s;
    char a[32], b[32], c[32], d[32], e[32], line[640];
    snprintf(line, sizeof line, "gamma %s, c %s, nu %s, S %s; tol %s (relative, on v)",
             bkf_format_number(p->gamma, a, sizeof a), bkf_format_number(p->c, b, sizeof b),
             bkf_format_number(p->nu, c, sizeof c), bkf_format_number(p->S, d, sizeof d),
             bkf_format_number(o->tol, e, sizeof e));
    s = bkf_io_table_comment(table, line, err);
    if (!s) s = range_of_n(table, p->c, t, err);
    if (!s) {
        snprintf(line, sizeof line,
                 "work: %zu grid samples (%zu solves at the coarse tolerance), %zu solves at "
                 "the roots' tolerance, %zu values of T from a formula, largest mu %.6g; "
                 "method %s",
                 t->samples, t->coarse_solves, t->precise_solves, t->formula_answers,
                 t->mu_grid_max, bkf_cycle_method_name(o->method));
        s = bkf_io_table_comment(table, line, err);
    }
    if (!s && t->note[0]) {
        snprintf(line, sizeof line, "note: %s", t->note);
        s = bkf_io_table_comment(table, line, err);
    }
    if (!s) s = refused_comments(table, t, err);
    if (!s && spectra) s = spectra_comments(table, t, spectra, err);
    if (!s) s = bkf_product_table_command(table, prov, err);
    for (size_t i = 0; !s && i < t->count; i++) {
        bkf_io_value v[NSTABILITY];
        bkf_fronts_root_values(&t->roots[i], v);
        if (spectra) verdict_values(&t->roots[i], &spectra->verdicts[i], v + NSPEEDS);
        s = bkf_io_table_row(table, v, err);
    }
    if (!s) s = bkf_io_table_finish(table, err);
    bkf_io_table_free(table);
    return s;
}

const bkf_io_column *bkf_fronts_chain_columns(int stability, size_t *count)
{
    if (count) *count = stability ? BKF_FRONTS_CHAIN_STABILITY_COLUMNS : BKF_FRONTS_CHAIN_COLUMNS;
    return chain_columns;
}

static int write_chain(const bkf_fronts_spec *spec, FILE *out, bkf_io_format format,
                       const bkf_provenance *prov, bkf_error *err)
{
    bkf_model_params p;
    bkf_chainwave_options o;
    chain_setup(spec, &p, &o);
    size_t from = spec->n ? spec->n : 1, to = spec->n ? spec->n : spec->nmax ? spec->nmax : p.N / 2;
    bkf_chainwave_table t;
    int s = bkf_chainwave_find(&p, from, to, &o, &t, err);
    bkf_io_table *table = NULL;
    size_t ncol;
    const bkf_io_column *cols = bkf_fronts_chain_columns(spec->stability, &ncol);
    if (!s)
        s = bkf_product_table_open(out, format, cols, ncol,
                                   "speeds --model chain: rotating waves psi_i(t) = F(t + i tau) "
                                   "of N blocks, N tau = n P, v = h / tau",
                                   prov, &table, err);
    char a[32], b[32], c[32], d[32], e[32];
    if (!s)
        s = bkf_io_table_commentf(table, err,
                                  "gamma %s, c %s, nu %s, S %s; N %zu blocks, h = S/N = %.17g, "
                                  "K = c^2/h^2 = %.17g; tol %s (relative, on v)",
                                  bkf_format_number(p.gamma, a, sizeof a),
                                  bkf_format_number(p.c, b, sizeof b),
                                  bkf_format_number(p.nu, c, sizeof c),
                                  bkf_format_number(p.S, d, sizeof d), p.N, p.S / (double)p.N,
                                  p.c * p.c * (double)(p.N * p.N) / (p.S * p.S),
                                  bkf_format_number(o.tol, e, sizeof e));
    if (!s)
        s = bkf_io_table_commentf(table, err,
                                  "n %zu to %zu: every wave on a branch from the uncoupled chain "
                                  "(K = 0), followed in K to %.3g K; %zu folds, %zu branches "
                                  "ended before K", from, to, BKF_CHAINWAVE_K_REACH, t.folds,
                                  t.ended);
    if (!s && t.note[0]) s = bkf_io_table_commentf(table, err, "note: %s", t.note);
    if (!s) s = bkf_product_table_command(table, prov, err);
    for (size_t i = 0; !s && i < t.count; i++) {
        const bkf_chainwave *w = &t.waves[i];
        bkf_io_value v[BKF_FRONTS_CHAIN_STABILITY_COLUMNS];
        memset(v, 0, sizeof v);
        double num[] = {(double)w->n, w->v, w->v_err, w->P, w->P_err, w->tau, w->h,
                        p.S / (double)w->n, w->residual, w->psi_min, w->psi_max, 0,
                        w->sigma_max, w->sigma_max_err, w->mult_abs, w->mult_abs_err,
                        atan2(w->mult_im, w->mult_re), w->trivial_err};
        for (size_t k = 0; k < ncol; k++) v[k].number = num[k];
        v[11].text = bkf_chainwave_verdict_name(w->verdict);
        s = bkf_io_table_row(table, v, err);
    }
    if (!s) s = bkf_io_table_finish(table, err);
    bkf_io_table_free(table);
    bkf_chainwave_table_free(&t);
    return s;
}

int bkf_fronts_find(const bkf_fronts_spec *spec, bkf_speeds_table *table, int **stable,
                    bkf_error *err)
{
    memset(table, 0, sizeof *table);
    *stable = NULL;
    int s = bkf_fronts_check(spec, "", err);
    if (s) return s;
    if (spec->model == 1)
        return bkf_error_set(err, BKF_EINPUT, "model: the roots of the continuum only");
    bkf_model_params params;
    bkf_speeds_options options;
    bkf_fronts_setup(spec, &params, &options);
    s = bkf_speeds_find(&params, &options, table, err);
    if (s || !spec->stability) return s;
    root_spectra spectra = {0};
    s = find_spectra(&params, table, spec->stability_tol, &spectra, err);
    if (!s && !(*stable = malloc((table->count ? table->count : 1) * sizeof **stable)))
        s = bkf_error_set(err, BKF_ENOMEM, "out of memory");
    /* the stable column of the table: yes, no, or unresolved however it was */
    for (size_t i = 0; !s && i < table->count; i++)
        (*stable)[i] = !verdict_resolved(&spectra.verdicts[i])                       ? -1
                       : spectra.verdicts[i].spectrum.verdict == BKF_TRAINSPEC_STABLE ? 1
                       : spectra.verdicts[i].spectrum.verdict == BKF_TRAINSPEC_UNSTABLE ? 0
                                                                                        : -1;
    root_spectra_free(&spectra, table->count);
    if (s) {
        bkf_speeds_table_free(table);
        free(*stable);
        *stable = NULL;
    }
    return s;
}

int bkf_fronts_write(const bkf_fronts_spec *spec, FILE *out, bkf_io_format format,
                     const bkf_provenance *prov, bkf_error *err)
{
    int s = bkf_fronts_check(spec, "", err);
    if (s) return s;
    if (spec->model == 1) return write_chain(spec, out, format, prov, err);
    bkf_model_params params;
    bkf_speeds_options options;
    bkf_fronts_setup(spec, &params, &options);
    bkf_speeds_table t;
    s = bkf_speeds_find(&params, &options, &t, err);
    root_spectra spectra = {0};
    if (!s && spec->stability) s = find_spectra(&params, &t, spec->stability_tol, &spectra, err);
    if (!s)
        s = write_speeds(&params, &options, &t, spec->stability ? &spectra : NULL, out, format,
                         prov, err);
    if (!s) warn_refused(spec, &t);
    root_spectra_free(&spectra, t.count);
    bkf_speeds_table_free(&t);
    return s;
}

/* ---------------------------------------------------------------- branch */

const bkf_option bkf_fronts_branch_options[] = {
    {.name = "param", .type = BKF_OPT_CHOICE, .offset = offsetof(bkf_fronts_branch_spec, along),
     .flags = BKF_OPT_REQUIRED, .choices = param_names, .form = "S|nu|gamma|c|h",
     .help = "required; the continued parameter (h: --model chain only,\n"
             "the spacing, S = N h moving with it)"},
    {.name = "from", .type = BKF_OPT_DOUBLE, .offset = offsetof(bkf_fronts_branch_spec, from),
     .flags = BKF_OPT_REQUIRED, .form = "A", .help = "required; its start value"},
    {.name = "to", .type = BKF_OPT_DOUBLE, .offset = offsetof(bkf_fronts_branch_spec, to),
     .flags = BKF_OPT_REQUIRED, .form = "B", .help = "required; its end value (A != B)"},
    {.name = "n", .type = BKF_OPT_COUNT, .offset = offsetof(bkf_fronts_branch_spec, n),
     .flags = BOUNDED | BKF_OPT_FANOUT, .min = 1, .max = 1e9, .form = "N", .shown_default = "1",
     .help = "number of fronts"},
    {.name = "root", .type = BKF_OPT_COUNT, .offset = offsetof(bkf_fronts_branch_spec, root),
     .flags = BOUNDED, .min = 1, .max = 1e6, .form = "I", .shown_default = "1",
     .help = "which root of this n at p = A to follow, 1 being the\n"
             "fastest (as listed by bkfront speeds)"},
    MODEL_OPTIONS(bkf_fronts_branch_spec),
    TOL_OPTION(bkf_fronts_branch_spec, "relative accuracy asked of T and v"),
    {.name = "max-points", .type = BKF_OPT_COUNT,
     .offset = offsetof(bkf_fronts_branch_spec, max_points), .flags = BOUNDED, .min = 1,
     .max = BKF_LIST_MAX, .form = "N", .help = "at most N regular points; default no limit"},
    {.name = "stability", .type = BKF_OPT_SWITCH,
     .offset = offsetof(bkf_fronts_branch_spec, stability),
     .help = "add each point's spectral stability (its ring spectrum, as\n"
             "bkfront stability): columns stable, sigma_max, sigma_max_err,\n"
             "kappa_max, kind; where sigma_max changes sign, a row of type\n"
             "stability at the parameter where it is 0"},
    STABILITY_TOL_OPTION(bkf_fronts_branch_spec),
    {.name = "model", .type = BKF_OPT_CHOICE, .offset = offsetof(bkf_fronts_branch_spec, model),
     .choices = model_names, .form = "continuum|chain", .shown_default = "continuum",
     .help = "chain: a rotating wave of the chain of --N blocks (as\n"
             "bkfront speeds --model chain) followed at fixed N and n;\n"
             "--stability: its Floquet multipliers; other columns (below)"},
    {.name = "N", .type = BKF_OPT_COUNT, .offset = offsetof(bkf_fronts_branch_spec, N),
     .flags = BOUNDED, .min = BKF_CHAINWAVE_N_MIN, .max = BKF_CHAINWAVE_N_MAX, .form = "N",
     .help = "with --model chain: blocks, in [2, 400]; default S (a\n"
             "whole number then; required with --param S or h)"},
};
const size_t bkf_fronts_branch_noptions =
    sizeof bkf_fronts_branch_options / sizeof bkf_fronts_branch_options[0];

bkf_fronts_branch_spec bkf_fronts_branch_spec_default(void)
{
    bkf_fronts_branch_spec s;
    memset(&s, 0, sizeof s);
    s.along = -1;
    s.from = s.to = NAN;
    s.gamma = s.c = s.nu = s.S = NAN;
    s.n = 1;
    s.root = 1;
    s.max_points = 0;
    s.tol = bkf_speeds_options_default().tol;
    return s;
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

/* The spec with the parameters not given (NaN) at the paper's values, but
 * the continued one (and S with h) left as it is. */
static bkf_fronts_branch_spec branch_resolved(const bkf_fronts_branch_spec *spec)
{
    bkf_fronts_branch_spec r = *spec;
    int moves_S = spec->along == BKF_SPEEDS_ALONG_S || spec->along == ALONG_H;
    bkf_model_paper_where_unset(spec->along == BKF_SPEEDS_ALONG_GAMMA ? NULL : &r.gamma,
                                spec->along == BKF_SPEEDS_ALONG_C ? NULL : &r.c,
                                spec->along == BKF_SPEEDS_ALONG_NU ? NULL : &r.nu,
                                moves_S ? NULL : &r.S);
    return r;
}

/* The fixed parameters with the continued one at x. */
static bkf_model_params branch_params(const bkf_fronts_branch_spec *spec, double x)
{
    bkf_model_params p = model_of(spec->gamma, spec->c, spec->nu, spec->S);
    *param_field(&p, (bkf_speeds_param)spec->along) = x;
    return p;
}

/* One end of the continued parameter in its range, as speeds checks it. */
static int check_end(const bkf_fronts_branch_spec *spec, const char *p, const char *end, double x,
                     bkf_error *err)
{
    const char *name = param_names[spec->along];
    char a[32];
    if (!isfinite(x))
        return bkf_error_set(err, BKF_EINPUT, "%s%s: %s is required", p, end, name);
    int bad = 0;
    if (spec->along == BKF_SPEEDS_ALONG_GAMMA)
        bad = !(x >= BKF_CYCLE_MU_MIN && x <= BKF_CYCLE_MU_MAX);
    else if (spec->along == BKF_SPEEDS_ALONG_C)
        bad = !(x >= 0 && x <= BKF_MODEL_C_MAX);
    else if (spec->along == BKF_SPEEDS_ALONG_S)
        bad = !(x > 0);
    else
        bad = !(fabs(x) < 1);
    if (bad) {
        const char *range = spec->along == BKF_SPEEDS_ALONG_GAMMA ? "[1e-06, 1e+06]"
                            : spec->along == BKF_SPEEDS_ALONG_C   ? "[0, 1e+06]"
                            : spec->along == BKF_SPEEDS_ALONG_S   ? "> 0"
                                                                  : "in (-1, 1)";
        return bkf_error_set(err, BKF_EINPUT, "%s%s: %s = %s is outside its range (%s)", p, end,
                             name, bkf_format_number(x, a, sizeof a), range);
    }
    return BKF_OK;
}

static int chain_branch_check(const bkf_fronts_branch_spec *spec, const char *p, bkf_error *err)
{
    if (spec->along < 0 || spec->along > ALONG_H)
        return bkf_error_set(err, BKF_EINPUT, "%sparam is required (S, nu, gamma, c or h)", p);
    const char *name = param_names[spec->along];
    const double values[5] = {spec->S, spec->nu, spec->gamma, spec->c, NAN};
    for (int k = 0; k < 4; k++) {
        int continued = k == spec->along || (spec->along == ALONG_H && k == BKF_SPEEDS_ALONG_S);
        if (continued && !isnan(values[k]))
            return bkf_error_set(err, BKF_EINPUT, "%s%s: it moves with the continued parameter "
                                 "(%sparam %s); give %sfrom and %sto instead", p,
                                 param_names[k], p, name, p, p);
    }
    bkf_fronts_branch_spec resolved = branch_resolved(spec);
    spec = &resolved;
    if (!(isfinite(spec->from) && isfinite(spec->to)))
        return bkf_error_set(err, BKF_EINPUT, "%sfrom, %sto: %s's ends are required", p, p, name);
    if (spec->from == spec->to)
        return bkf_error_set(err, BKF_EINPUT, "%sfrom, %sto: the ends are equal (need A != B)", p,
                             p);
    if (spec->stability_tol)
        return bkf_error_set(err, BKF_EINPUT, "%sstability-tol: continuum only (the chain's "
                             "multipliers are computed at --tol)", p);
    if (!(spec->tol >= BKF_CHAINWAVE_TOL_MIN && spec->tol <= BKF_CHAINWAVE_TOL_MAX))
        return bkf_error_set(err, BKF_EINPUT, "%stol: %g is outside [%g, %g] for the chain", p,
                             spec->tol, BKF_CHAINWAVE_TOL_MIN, BKF_CHAINWAVE_TOL_MAX);
    bkf_model_params m;
    int s = fronts_chain_branch_model(spec, p, &m, err);
    if (s) return s;
    bkf_chainwave_options o = bkf_chainwave_options_default();
    o.tol = spec->tol;
    bkf_error e;
    /* both ends in range */
    for (int end = 0; end < 2; end++) {
        bkf_fronts_branch_spec q = *spec;
        q.from = end ? spec->to : spec->from;
        fronts_chain_branch_model(&q, p, &m, err);
        if (bkf_chainwave_check(&m, spec->n, &o, &e))
            return bkf_error_set(err, BKF_EINPUT, "%s%s (%s = %g): %s", p, end ? "to" : "from",
                                 name, q.from, e.message);
    }
    return BKF_OK;
}

int bkf_fronts_branch_check(const bkf_fronts_branch_spec *spec, const char *prefix,
                            bkf_error *err)
{
    if (!spec) return bkf_error_set(err, BKF_EINPUT, "branch: spec is NULL");
    const char *p = prefix ? prefix : "";
    if (spec->model == 1) return chain_branch_check(spec, p, err);
    if (spec->model != 0)
        return bkf_error_set(err, BKF_EINPUT, "%smodel: not continuum or chain", p);
    if (spec->N) return bkf_error_set(err, BKF_EINPUT, "%sN: only with %smodel chain", p, p);
    if (spec->along < 0 || spec->along > BKF_SPEEDS_ALONG_C)
        return bkf_error_set(err, BKF_EINPUT, "%sparam is required (S, nu, gamma or c)", p);
    const char *name = param_names[spec->along];
    const double values[4] = {spec->S, spec->nu, spec->gamma, spec->c};
    for (int k = 0; k < 4; k++) {
        if (k == spec->along && !isnan(values[k]))
            return bkf_error_set(err, BKF_EINPUT,
                                 "%s%s: this is the continued parameter (%sparam %s); give its "
                                 "range with %sfrom and %sto instead",
                                 p, name, p, name, p, p);
    }
    bkf_fronts_branch_spec resolved = branch_resolved(spec);
    spec = &resolved;
    int s;
    if (spec->along != BKF_SPEEDS_ALONG_NU && (s = check_nu(p, spec->nu, err))) return s;
    if ((s = check_end(spec, p, "from", spec->from, err))) return s;
    if ((s = check_end(spec, p, "to", spec->to, err))) return s;
    if (spec->from == spec->to)
        return bkf_error_set(err, BKF_EINPUT, "%sfrom, %sto: the ends are equal (need A != B)", p,
                             p);
    if (spec->along != BKF_SPEEDS_ALONG_C && !(spec->c > 0))
        return bkf_error_set(err, BKF_EINPUT,
                             "%sc: c = 0 needs no continuation, v = S/(n T(gamma)) in closed "
                             "form (bkfront speeds); branches need c > 0", p);
    if (spec->along == BKF_SPEEDS_ALONG_C && !(spec->from > 0 && spec->to > 0))
        return bkf_error_set(err, BKF_EINPUT,
                             "%sfrom, %sto: c must stay > 0 along the branch (c = 0 is the "
                             "closed form v = S/(n T(gamma)))", p, p);
    if (spec->n < 1 || spec->root < 1)
        return bkf_error_set(err, BKF_EINPUT, "%sn, %sroot: must be >= 1", p, p);
    /* c > 0 all along is checked above */
    if ((s = check_stability(p, spec->stability, spec->stability_tol, 1, err))) return s;
    bkf_speeds_options o = bkf_speeds_options_default();
    o.tol = spec->tol;
    bkf_model_params start = branch_params(spec, spec->from);
    bkf_error e;
    if (bkf_speeds_check(&start, &o, &e) != BKF_OK)
        return bkf_error_set(err, BKF_EINPUT, "%sS, %sc, %sgamma: %s", p, p, p, e.message);
    return BKF_OK;
}

/* A row of the branch: a point of the continuation (point, fold, sonic) or,
 * with stability, a located change of stability. */
typedef struct {
    bkf_speeds_branch_point point;
    int stability_change;
    root_verdict verdict; /* with stability */
    int skipped;          /* no spectrum tried: mu beyond one that outgrew the budget */
    int tracked;          /* the verdict from eigenvalues followed, no ring spectrum */
} branch_row;

typedef struct {
    branch_row *rows;
    size_t count, cap;
    int status;
} branch_sink;

static int sink_push(branch_sink *sink, const branch_row *row)
{
    if (sink->count == sink->cap) {
        size_t cap = sink->cap ? 2 * sink->cap : 64;
        branch_row *x = realloc(sink->rows, cap * sizeof *x);
        if (!x) return sink->status = BKF_ENOMEM;
        sink->rows = x;
        sink->cap = cap;
    }
    sink->rows[sink->count++] = *row;
    return BKF_OK;
}

static void sink_free(branch_sink *sink)
{
    for (size_t i = 0; i < sink->count; i++) bkf_trainspec_result_free(&sink->rows[i].verdict.spectrum);
    free(sink->rows);
    memset(sink, 0, sizeof *sink);
}

static int collect_point(const bkf_speeds_branch_point *pt, void *data)
{
    branch_row row;
    memset(&row, 0, sizeof row);
    row.point = *pt;
    return sink_push(data, &row) != BKF_OK;
}

static double row_param(const branch_row *r, bkf_speeds_param along)
{
    return param_value(r->point.params, along);
}

/* The Bloch index j of kappa = 2 pi j / S. */
static long bloch_index(const bkf_trainspec_result *x)
{
    return lround(x->kappa_max * x->params.S / (2 * M_PI));
}

/* ------------------------------------------------- changes of stability */

/* Brent's iterations at most: each costs a ring spectrum. */
#define CROSSING_MAX_ITER 40

/* The search for sigma_max = 0 between two consecutive points of the branch.
 * At a trial parameter the root is re-solved (bkf_speeds_find, this n only:
 * a few milliseconds beside the spectrum's ~0.1 s, and it brackets every
 * root of n, so none is missed) and the one nearest the chord between the
 * two points' v is taken: between consecutive continuation steps the
 * branch is that close to its chord, also on the middle branch between two
 * folds.  Re-running the continuation from one point would land on the
 * trial parameter too, but only after stepping in arclength from there. */
typedef struct {
    const bkf_fronts_branch_spec *spec;
    double tol;
    const branch_row *ends[2];
    branch_row at;   /* the last trial, its verdict computed */
    double x_at;     /* its parameter; NaN before the first */
    int status;      /* why the search stopped, in why */
    bkf_error why;
    size_t spectra;
} crossing_search;

/* The train at x: the root of n there nearest the chord between the two
 * ends' v. */
static int root_on_chord(double x, void *data, bkf_model_params *p, bkf_speeds_root *root,
                         bkf_error *err)
{
    crossing_search *c = data;
    bkf_speeds_param along = (bkf_speeds_param)c->spec->along;
    double x0 = row_param(c->ends[0], along), x1 = row_param(c->ends[1], along);
    double v0 = c->ends[0]->point.root.v, v1 = c->ends[1]->point.root.v;
    double chord = v0 + (v1 - v0) * (x - x0) / (x1 - x0);
    *p = branch_params(c->spec, x);
    bkf_speeds_options o = bkf_speeds_options_default();
    o.tol = c->spec->tol;
    o.n_from = o.n_to = c->spec->n;
    bkf_speeds_table t;
    int s = bkf_speeds_find(p, &o, &t, err);
    size_t best = 0;
    if (!s) s = bkf_speeds_nearest(&t, chord, &best, err);
    if (!s) *root = t.roots[best];
    bkf_speeds_table_free(&t);
    return s;
}

static double crossing_sigma(double x, void *data)
{
    crossing_search *c = data;
    bkf_speeds_param along = (bkf_speeds_param)c->spec->along;
    for (int k = 0; k < 2; k++)
        if (x == row_param(c->ends[k], along)) return c->ends[k]->verdict.spectrum.sigma_max;
    if (c->status) return NAN;
    bkf_model_params p;
    bkf_speeds_root root;
    int s = root_on_chord(x, c, &p, &root, &c->why);
    if (!s) {
        bkf_trainspec_result_free(&c->at.verdict.spectrum);
        memset(&c->at, 0, sizeof c->at);
        c->at.point.params = p;
        c->at.point.root = root;
        c->at.point.kind = BKF_SPEEDS_POINT;
        c->at.stability_change = 1;
        s = bkf_trainspec_root(&p, &c->at.point.root, c->tol, 1, &c->at.verdict.spectrum, &c->why);
        c->spectra++;
    }
    c->status = s;
    c->at.verdict.why.status = s;
    c->x_at = s ? NAN : x;
    return s ? NAN : c->at.verdict.spectrum.sigma_max;
}

/* The change of stability between rows a and b (resolved, sigma_max of
 * opposite signs) into *out, located when its |sigma_max| <= tol; else
 * BKF_ENUMERIC (or the search's failure) with the reason in *why. */
static int locate_crossing(const bkf_fronts_branch_spec *spec, double tol, const branch_row *a,
                           const branch_row *b, branch_row *out, bkf_error *why, size_t *spectra)
{
    bkf_speeds_param along = (bkf_speeds_param)spec->along;
    crossing_search c;
    memset(&c, 0, sizeof c);
    c.spec = spec;
    c.tol = tol;
    c.ends[0] = a;
    c.ends[1] = b;
    c.x_at = NAN;
    double xa = row_param(a, along), xb = row_param(b, along);
    gsl_function F = {crossing_sigma, &c};
    gsl_root_fsolver *fs = gsl_root_fsolver_alloc(gsl_root_fsolver_brent);
    if (!fs) return bkf_error_set(why, BKF_ENOMEM, "out of memory");
    bkf_gsl_handler *h = bkf_gsl_handler_push();
    int g = gsl_root_fsolver_set(fs, &F, fmin(xa, xb), fmax(xa, xb));
    int located = 0;
    for (int it = 0; g == GSL_SUCCESS && !located && it < CROSSING_MAX_ITER; it++) {
        g = gsl_root_fsolver_iterate(fs);
        double x = gsl_root_fsolver_root(fs);
        if (g == GSL_SUCCESS && x == c.x_at && fabs(c.at.verdict.spectrum.sigma_max) <= tol)
            located = 1;
        else if (g == GSL_SUCCESS && gsl_root_test_interval(gsl_root_fsolver_x_lower(fs),
                                                            gsl_root_fsolver_x_upper(fs), 0,
                                                            1e-13) == GSL_SUCCESS)
            break;
    }
    bkf_gsl_handler_pop(h);
    gsl_root_fsolver_free(fs);
    *spectra += c.spectra;
    int s = BKF_OK;
    char e[32];
    if (c.status)
        s = bkf_error_set(why, c.status, "%s", c.why.message);
    else if (!located)
        s = bkf_error_set(why, BKF_ENUMERIC,
                          "sigma_max stays above the tolerance in magnitude (%s) as the "
                          "interval shrinks: it jumps there",
                          bkf_format_number(fabs(c.at.verdict.spectrum.sigma_max), e, sizeof e));
    if (s) {
        bkf_trainspec_result_free(&c.at.verdict.spectrum);
        return s;
    }
    *out = c.at;
    return BKF_OK;
}

/* The change between rows a and b located on the one eigenvalue that
 * crosses: the rightmost of the ring spectrum on the stable side (every
 * verdict but unstable is a ring spectrum's), followed across the interval
 * (fronts_track_crossing), then one ring spectrum at the zero found, which
 * must agree (|sigma_max| <= tol: the crossing eigenvalue is the
 * rightmost there).  BKF_ENUMERIC where any step fails: the caller then
 * searches on ring spectra (locate_crossing). */
static int locate_tracked(const bkf_fronts_branch_spec *spec, double tol, const branch_row *a,
                          const branch_row *b, branch_row *out, size_t *spectra,
                          size_t *followed, bkf_error *err)
{
    bkf_speeds_param along = (bkf_speeds_param)spec->along;
    const branch_row *from = a->verdict.spectrum.sigma_max < 0 ? a : b, *to = from == a ? b : a;
    const bkf_trainspec_result *r = &from->verdict.spectrum;
    if (from->tracked || r->sigma_is_bound) return BKF_ENUMERIC;
    const bkf_trainspec_eigenvalue *start = NULL;
    for (size_t i = 0; i < r->count; i++)
        if (!r->eigenvalues[i].translation && (!start || r->eigenvalues[i].re > start->re))
            start = &r->eigenvalues[i];
    if (!start) return BKF_ENUMERIC;
    crossing_search c;
    memset(&c, 0, sizeof c);
    c.spec = spec;
    c.ends[0] = a;
    c.ends[1] = b;
    double x;
    bkf_model_params p;
    bkf_speeds_root root;
    bkf_error e;
    int s = fronts_track_crossing(row_param(from, along), row_param(to, along), start, spec->n,
                                  tol, root_on_chord, &c, &x, &p, &root, followed, &e);
    if (s == BKF_ENOMEM) return bkf_error_set(err, s, "out of memory");
    if (s) return BKF_ENUMERIC;
    memset(out, 0, sizeof *out);
    out->point.params = p;
    out->point.root = root;
    out->point.kind = BKF_SPEEDS_POINT;
    out->stability_change = 1;
    ++*spectra;
    s = verdict_find(&p, &root, tol, 1, &out->verdict, err);
    if (s) return s;
    if (verdict_resolved(&out->verdict) && !out->verdict.spectrum.sigma_is_bound &&
        fabs(out->verdict.spectrum.sigma_max) <= tol)
        return BKF_OK;
    bkf_trainspec_result_free(&out->verdict.spectrum);
    return BKF_ENUMERIC;
}

/* A change of stability that could not be located, between two points. */
typedef struct {
    double from, to;
    bkf_error why;
} missed_change;

typedef struct {
    double tol;
    missed_change *missed; /* at most one per pair of points */
    size_t nmissed, located, spectra;
    size_t tracked;    /* points whose verdict the followed eigenvalues gave */
    size_t redone;     /* followed points recomputed as ring spectra (a check failed) */
    size_t followed;   /* eigenvalues followed in the crossings' searches */
} branch_verdicts;

/* A ring spectrum is taken at least every TRACK_EVERY points and wherever
 * mu has grown TRACK_MU_REACH-fold since the last: each is a check of the
 * eigenvalues followed (and the budget's test, as before, at large mu).
 * No bound on mu: past mu 100 following pays as below it, now that the
 * Radau meshes' profile is sampled by rk8pd there too (cycle.c; with bsimp
 * a mesh cost 15 times what it did at mu 99 and every point past mu 100
 * took its ring spectrum).  n = 6 at gamma 1.5, mu 120.8: the followed
 * eigenvalues 0.43 s against the ring spectrum's 1.7 s, agreeing to 5e-9. */
#define TRACK_EVERY 8
#define TRACK_MU_REACH 2.0
/* The ring spectra along a branch report two eigenvalues per Bloch class
 * and half plane, and both are followed: the second of a class overtaking
 * its first (gamma 4, c 0.15, nu -0.7, n = 2 near S 27.4, j = 0) is then
 * seen. */
#define TRACK_PER_KAPPA 8
/* Past a ring spectrum whose window had to stop short of the monodromy's
 * rounding noise (trainspec_curves.c) and that took more than this many
 * Radau steps (an eighth of its default budget, 2.5e7) the points of
 * larger mu are not tried: the noise's edge moves towards 0 as mu grows
 * (Re sigma -0.052 at mu 120.8, -0.045 at 147.5 on the branch below), the
 * ring spectra past it cost many times as much or are refused, their time
 * outgrowing their work (the meshes' building is not in it), and the
 * eigenvalues followed there cost about as much as a ring spectrum did.
 * n = 6 at gamma 1.5 towards the sonic limit (tol 1e-6): ring spectra of
 * 2.9e6 steps at mu 120.8, 3.7e6 at 147.5 (both stopped short of the
 * noise; main refused 147.5 after its budget); without this rule the
 * branch then took ring spectra refused at mu 220 and 268 (an eigenvalue's
 * error 0.05 at 57000 steps a period) and 1.1e7 steps at mu 328: 18 s
 * for the branch against 7. */
#define RING_WORK_LAST 3e6

/* The check at a ring spectrum after followed points.  Where the set was
 * followed to this point too (every one of them), the ring's rightmost
 * must be theirs (within both errors plus tol); else it must be the
 * rightmost followed to the point before (same class up to the conjugate,
 * within three times the step that one made from its own last value, plus
 * the errors and tol).  A failure: another eigenvalue than those followed
 * overtook them on the way (or Newton landed on another one). */
static int check_fails(const bkf_trainspec_result *ring, const bkf_trainspec_result *here,
                       const bkf_trainspec_eigenvalue *last, double moved, double tol)
{
    if (ring->sigma_is_bound) return 1;
    int all = here->count > 0;
    for (size_t i = 0; i < here->count; i++) all = all && isfinite(here->eigenvalues[i].re);
    if (all)
        return !(fabs(ring->sigma_max - here->sigma_max) <=
                 ring->sigma_max_err + here->sigma_max_err + tol);
    long n = (long)ring->n, j = lround(ring->kappa_max * ring->params.S / (2 * M_PI));
    int same = j % n == (long)last->j % n;
    int conj = (j + (long)last->j) % n == 0;
    double d = fmin(same ? hypot(ring->sigma_max - last->re, ring->sigma_max_im - last->im) : INFINITY,
                    conj ? hypot(ring->sigma_max - last->re, ring->sigma_max_im + last->im) : INFINITY);
    return !(d <= 3 * moved + ring->sigma_max_err + last->err + tol);
}

/* The rightmost of a set, and how far it moved from the set before. */
static const bkf_trainspec_eigenvalue *set_rightmost(const fronts_track_set *set)
{
    const bkf_trainspec_eigenvalue *b = NULL;
    for (size_t i = 0; i < set->count; i++)
        if (!b || set->e[i].re > b->re) b = &set->e[i];
    return b;
}

/* Each row's verdict: a ring spectrum, or where the eigenvalues followed
 * from the last one prove the train unstable (fronts_track_point), theirs.
 * A fold (the translation's partner passes 0 there), a point the followed
 * eigenvalues do not prove unstable (a stable train needs the whole
 * spectrum) or whose rightmost is another than before, every
 * TRACK_EVERY-th point and a TRACK_MU_REACH-fold mu
 * get a ring spectrum; where it shows the followed ones were overtaken,
 * the points followed since the last ring spectrum are redone as ring
 * spectra. */
static int branch_verdicts_find(branch_sink *sink,
                                branch_verdicts *bv, bkf_error *err)
{
    /* The mesh a spectrum needs grows with mu (thinner fronts): past a mu
     * whose spectrum outgrew the budget the next ones would too, each after
     * seconds of trying, as the branch runs to the sonic limit. */
    double refused_mu = INFINITY, mu_ring = NAN, moved = INFINITY;
    bkf_error skip_why = {0};
    size_t last_ring = 0, since = 0;
    fronts_track_set set = {0};
    int s = BKF_OK;
    for (size_t i = 0; i < sink->count && !s; i++) {
        branch_row *r = &sink->rows[i];
        if (r->point.kind == BKF_SPEEDS_SONIC) {
            bkf_error_set(&r->verdict.why, BKF_EINPUT,
                          "the sonic limit v = c, no front train to linearise about");
            continue;
        }
        if (r->point.root.mu >= refused_mu) {
            r->skipped = 1;
            r->verdict.why = skip_why;
            continue;
        }
        /* a fold (the translation's partner passes 0 there), every
         * TRACK_EVERY-th point and a TRACK_MU_REACH-fold mu take a ring
         * spectrum whatever the eigenvalues followed would say */
        int ring = r->point.kind == BKF_SPEEDS_FOLD || set.count == 0 || since + 1 >= TRACK_EVERY ||
                   !(r->point.root.mu <= TRACK_MU_REACH * mu_ring);
        bkf_trainspec_eigenvalue last = {0};
        const bkf_trainspec_eigenvalue *lb = set_rightmost(&set);
        if (lb) last = *lb;
        bkf_trainspec_result f;
        memset(&f, 0, sizeof f);
        if (!ring) {
            int decided = 0;
            s = fronts_track_point(&r->point.params, &r->point.root, bv->tol, &set, &f, &decided,
                                   err);
            if (s) break;
            if (decided) {
                const bkf_trainspec_eigenvalue *nb = set_rightmost(&set);
                moved = lb && nb ? hypot(nb->re - last.re, nb->im - last.im) : INFINITY;
                r->verdict.spectrum = f;
                r->verdict.why.status = BKF_OK;
                r->tracked = 1;
                bv->tracked++;
                since++;
                continue;
            }
        }
        bv->spectra++;
        s = verdict_find(&r->point.params, &r->point.root, bv->tol, TRACK_PER_KAPPA, &r->verdict, err);
        int redo = !s && since && lb && verdict_resolved(&r->verdict) &&
                   check_fails(&r->verdict.spectrum, &f, &last, moved, bv->tol);
        bkf_trainspec_result_free(&f);
        for (size_t k = last_ring + 1; redo && !s && k < i; k++) {
            branch_row *q = &sink->rows[k];
            if (!q->tracked) continue;
            bkf_trainspec_result_free(&q->verdict.spectrum);
            memset(&q->verdict, 0, sizeof q->verdict);
            q->tracked = 0;
            bv->tracked--;
            bv->redone++;
            bv->spectra++;
            s = verdict_find(&q->point.params, &q->point.root, bv->tol, TRACK_PER_KAPPA, &q->verdict, err);
        }
        if (s) break;
        if (r->verdict.why.status == BKF_EBUDGET) {
            refused_mu = r->point.root.mu;
            bkf_error_set(&skip_why, BKF_EBUDGET,
                          "not tried: mu beyond %.6g, where the spectrum outgrew its budget "
                          "(thinner fronts need a finer mesh)", refused_mu);
        } else if (verdict_resolved(&r->verdict) && r->verdict.spectrum.edge_moved &&
                   r->verdict.spectrum.work > RING_WORK_LAST) {
            refused_mu = nextafter(r->point.root.mu, INFINITY);
            bkf_error_set(&skip_why, BKF_EBUDGET,
                          "not tried: mu beyond %.6g, whose ring spectrum took %.3g Radau steps, an "
                          "eighth of its budget, its window stopped short of the monodromy's "
                          "rounding noise (thinner fronts need a finer mesh: the next would cost "
                          "many times as much)", r->point.root.mu, r->verdict.spectrum.work);
        }
        set.count = 0;
        since = 0;
        if (verdict_resolved(&r->verdict)) {
            if (fronts_track_seed(&set, &r->verdict.spectrum, bv->tol))
                s = bkf_error_set(err, BKF_ENOMEM, "out of memory");
            mu_ring = r->point.root.mu;
            last_ring = i;
            moved = INFINITY;
        }
    }
    fronts_track_set_free(&set);
    return s;
}

/* Each row's verdict, then the changes of stability between consecutive
 * resolved points (sigma_max of opposite signs) as rows of their own. */
static int branch_stability(const bkf_fronts_branch_spec *spec, branch_sink *sink,
                            branch_verdicts *bv, bkf_error *err)
{
    bkf_speeds_param along = (bkf_speeds_param)spec->along;
    int s = branch_verdicts_find(sink, bv, err);
    if (s) return s;
    /* room for a change between every two points: moving rows cannot fail */
    size_t cap = 2 * sink->count + 1;
    branch_row *rows = malloc(cap * sizeof *rows);
    bv->missed = malloc(cap * sizeof *bv->missed);
    if (!rows || !bv->missed) {
        free(rows);
        return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    }
    size_t count = 0;
    for (size_t i = 0; i < sink->count; i++) {
        rows[count++] = sink->rows[i];
        if (s || i + 1 == sink->count) continue;
        const branch_row *a = &sink->rows[i], *b = &sink->rows[i + 1];
        if (!verdict_resolved(&a->verdict) || !verdict_resolved(&b->verdict) ||
            !(a->verdict.spectrum.sigma_max * b->verdict.spectrum.sigma_max < 0))
            continue;
        bkf_error why;
        int f = locate_tracked(spec, bv->tol, a, b, &rows[count], &bv->spectra, &bv->followed, err);
        if (f == BKF_ENUMERIC)
            f = locate_crossing(spec, bv->tol, a, b, &rows[count], &why, &bv->spectra);
        else if (f)
            why = *err;
        if (f == BKF_ENOMEM) {
            s = bkf_error_set(err, f, "out of memory");
        } else if (f) {
            missed_change *m = &bv->missed[bv->nmissed++];
            m->from = row_param(a, along);
            m->to = row_param(b, along);
            m->why = why;
        } else {
            count++;
            bv->located++;
        }
    }
    free(sink->rows);
    sink->rows = rows;
    sink->count = count;
    sink->cap = cap;
    return s;
}

/* "N points, F fold(s) at p = .. (v = ..), ...; ends ..." */
static void summary_line(bkf_speeds_param along, const branch_sink *sink,
                         const bkf_speeds_branch_report *rep, char *line, size_t size)
{
    const char *pname = param_names[along];
    char a[32], e[32];
    int used = snprintf(line, size, "%zu points, %zu fold(s)", rep->points, rep->folds);
    const char *sep = " at ";
    for (size_t i = 0; i < sink->count && used > 0 && (size_t)used < size; i++)
        if (sink->rows[i].point.kind == BKF_SPEEDS_FOLD) {
            used += snprintf(line + used, size - (size_t)used, "%s%s = %s (v = %s)", sep, pname,
                             bkf_format_number(row_param(&sink->rows[i], along), a, sizeof a),
                             bkf_format_number(sink->rows[i].point.root.v, e, sizeof e));
            sep = ", ";
        }
    if (used > 0 && (size_t)used < size) {
        if (rep->sonic)
            snprintf(line + used, size - (size_t)used,
                     "; ends at the sonic limit v -> c+ at %s = %s (S = n k(nu) c gamma)", pname,
                     bkf_format_number(rep->sonic_value, a, sizeof a));
        else if (rep->reached_end)
            snprintf(line + used, size - (size_t)used, "; ends on the range's boundary");
        else
            snprintf(line + used, size - (size_t)used, "; stopped after --max-points");
    }
}

/* The comments on the verdicts: the tolerance, each change of stability
 * (as the folds' line), each point left unresolved and each change not
 * located. */
static int branch_verdict_comments(bkf_io_table *table, bkf_speeds_param along,
                                   const branch_sink *sink, const branch_verdicts *bv,
                                   bkf_error *err)
{
    const char *pname = param_names[along];
    char a[32], b[32], c[32], d[32];
    int s = verdict_comment(table, bv->tol, err);
    if (!s)
        s = bkf_io_table_commentf(table, err,
                                  "stability along the branch: %zu change(s) located (rows of "
                                  "type stability, sigma_max = 0 to the tolerance), %zu not; "
                                  "%zu spectra; %zu point(s) followed (unstable by the "
                                  "eigenvalues of the last spectrum continued there, sigma_max "
                                  "the rightmost of them), %zu redone as spectra",
                                  bv->located, bv->nmissed, bv->spectra, bv->tracked, bv->redone);
    for (size_t i = 0; !s && i < sink->count; i++) {
        const branch_row *r = &sink->rows[i];
        double x = row_param(r, along);
        if (r->stability_change) {
            const bkf_trainspec_result *sp = &r->verdict.spectrum;
            /* a change sits between two resolved points */
            const char *before = bkf_trainspec_verdict_name(sink->rows[i - 1].verdict.spectrum.verdict);
            const char *after = bkf_trainspec_verdict_name(sink->rows[i + 1].verdict.spectrum.verdict);
            s = bkf_io_table_commentf(
                table, err,
                "stability changes at %s = %s (v = %s): sigma_max %s at kappa %s (j = %ld), %s; "
                "stable: %s before, %s after along the branch",
                pname, bkf_format_number(x, a, sizeof a),
                bkf_format_number(r->point.root.v, b, sizeof b),
                bkf_format_number(sp->sigma_max, c, sizeof c),
                bkf_format_number(sp->kappa_max, d, sizeof d), bloch_index(sp),
                sp->complex_pair ? "a complex pair crosses (oscillatory)"
                                 : "a real eigenvalue crosses",
                before, after);
        } else if (r->skipped) {
            /* one line for the run of points not tried */
            size_t j = i;
            while (j + 1 < sink->count && sink->rows[j + 1].skipped) j++;
            s = bkf_io_table_commentf(
                table, err, "stability at %zu point(s) from %s = %s to %s (mu %.6g to %.6g) "
                "unresolved: %s", j - i + 1, pname, bkf_format_number(x, a, sizeof a),
                bkf_format_number(row_param(&sink->rows[j], along), b, sizeof b),
                r->point.root.mu, sink->rows[j].point.root.mu, r->verdict.why.message);
            i = j;
        } else if (!verdict_resolved(&r->verdict)) {
            s = bkf_io_table_commentf(table, err, "stability at %s = %s unresolved: %s", pname,
                                      bkf_format_number(x, a, sizeof a), r->verdict.why.message);
        } else if (isfinite(verdict_bound(&r->verdict))) {
            /* one line for the run of points bounded only, at its largest bound */
            size_t j = i;
            double bound = verdict_bound(&r->verdict);
            while (j + 1 < sink->count && !sink->rows[j + 1].stability_change &&
                   isfinite(verdict_bound(&sink->rows[j + 1].verdict)))
                bound = fmax(bound, verdict_bound(&sink->rows[++j].verdict));
            char note[200];
            s = bkf_io_table_commentf(
                table, err, "stability at %zu point(s) from %s = %s to %s: %s", j - i + 1, pname,
                bkf_format_number(x, a, sizeof a),
                bkf_format_number(row_param(&sink->rows[j], along), b, sizeof b),
                bkf_trainspec_bound_note(bound, note, sizeof note));
            i = j;
        }
    }
    for (size_t i = 0; !s && i < bv->nmissed; i++)
        s = bkf_io_table_commentf(table, err,
                                  "stability changes between %s = %s and %s = %s, not located: %s",
                                  pname, bkf_format_number(bv->missed[i].from, a, sizeof a),
                                  pname, bkf_format_number(bv->missed[i].to, b, sizeof b),
                                  bv->missed[i].why.message);
    return s;
}

static int write_branch(const bkf_fronts_branch_spec *spec, const branch_sink *sink,
                        const bkf_speeds_branch_report *rep, const branch_verdicts *bv, FILE *out,
                        bkf_io_format format, const bkf_provenance *prov, bkf_error *err)
{
    bkf_io_table *table;
    int s = bkf_product_table_open(
        out, format, bv ? branch_stability_columns : branch_columns,
        bv ? NBRANCH_STABILITY : NBRANCH,
        "branch: one root v_n of n T(mu(v)) = S / (v sqrt(1 - c^2/v^2)) "
        "followed along one parameter by pseudo-arclength continuation",
        prov, &table, err);
    if (s) return s;
    bkf_speeds_param along = (bkf_speeds_param)spec->along;
    char a[32], b[32], c[32], d[32], line[640];
    snprintf(line, sizeof line, "%s from %s to %s; n %zu, root %zu at the start; tol %s",
             param_names[along], bkf_format_number(spec->from, a, sizeof a),
             bkf_format_number(spec->to, b, sizeof b), spec->n, spec->root,
             bkf_format_number(spec->tol, c, sizeof c));
    s = bkf_io_table_comment(table, line, err);
    if (!s) {
        snprintf(line, sizeof line, "fixed: %s%s%s%s%s%s%s%s",
                 along == BKF_SPEEDS_ALONG_GAMMA ? "" : "gamma ",
                 along == BKF_SPEEDS_ALONG_GAMMA ? "" : bkf_format_number(spec->gamma, a, sizeof a),
                 along == BKF_SPEEDS_ALONG_C ? "" : " c ",
                 along == BKF_SPEEDS_ALONG_C ? "" : bkf_format_number(spec->c, b, sizeof b),
                 along == BKF_SPEEDS_ALONG_NU ? "" : " nu ",
                 along == BKF_SPEEDS_ALONG_NU ? "" : bkf_format_number(spec->nu, c, sizeof c),
                 along == BKF_SPEEDS_ALONG_S ? "" : " S ",
                 along == BKF_SPEEDS_ALONG_S ? "" : bkf_format_number(spec->S, d, sizeof d));
        s = bkf_io_table_comment(table, line, err);
    }
    if (!s) {
        summary_line(along, sink, rep, line, sizeof line);
        s = bkf_io_table_comment(table, line, err);
    }
    if (!s && bv) s = branch_verdict_comments(table, along, sink, bv, err);
    if (!s) s = bkf_product_table_command(table, prov, err);
    static const char *const kinds[] = {"point", "fold", "sonic"};
    for (size_t i = 0; !s && i < sink->count; i++) {
        const bkf_speeds_branch_point *pt = &sink->rows[i].point;
        bkf_io_value v[NBRANCH_STABILITY];
        memset(v, 0, sizeof v);
        v[0].text = sink->rows[i].stability_change ? "stability" : kinds[pt->kind];
        v[1].number = pt->params.S;
        v[2].number = pt->params.gamma;
        v[3].number = pt->params.c;
        v[4].number = pt->params.nu;
        bkf_fronts_root_values(&pt->root, v + NPARAM);
        if (bv) verdict_values(&pt->root, &sink->rows[i].verdict, v + NBRANCH);
        s = bkf_io_table_row(table, v, err);
    }
    if (!s) s = bkf_io_table_finish(table, err);
    bkf_io_table_free(table);
    return s;
}

int bkf_fronts_branch_write(const bkf_fronts_branch_spec *spec, FILE *out, bkf_io_format format,
                            const bkf_provenance *prov, bkf_error *err)
{
    int s = bkf_fronts_branch_check(spec, "", err);
    if (s) return s;
    bkf_fronts_branch_spec resolved = branch_resolved(spec);
    spec = &resolved;
    if (spec->model == 1)
        return fronts_chain_branch_write(spec, param_names[spec->along], out, format, prov, err);
    bkf_speeds_options o = bkf_speeds_options_default();
    o.tol = spec->tol;
    bkf_model_params start = branch_params(spec, spec->from);
    branch_sink sink = {0};
    bkf_speeds_branch_report rep;
    s = bkf_speeds_branch(&start, spec->n, spec->root, (bkf_speeds_param)spec->along, spec->to,
                          &o, spec->max_points, collect_point, &sink, &rep, err);
    if (!s && sink.status) s = bkf_error_set(err, sink.status, "out of memory");
    branch_verdicts bv = {.tol = verdict_tol(spec->stability_tol)};
    if (!s && spec->stability) s = branch_stability(spec, &sink, &bv, err);
    if (!s) s = write_branch(spec, &sink, &rep, spec->stability ? &bv : NULL, out, format, prov, err);
    free(bv.missed);
    sink_free(&sink);
    return s;
}

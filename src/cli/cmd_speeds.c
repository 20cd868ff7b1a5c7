/* bkfront speeds: every supersonic front speed allowed by
 *     n T(mu(v)) = S / (v sqrt(1 - c^2/v^2)),  mu(v) = gamma / sqrt(1 - c^2/v^2);
 * bkfront branch: one of them followed along S, nu, gamma or c.
 *
 * As in `bkfront period`: every input is checked before the first solve and
 * the table is built in memory and written only when the whole computation
 * succeeded, so a failed run leaves stdout (or the --out file) untouched. */
#include "args.h"
#include "product_out.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bkfront/cycle.h"
#include "bkfront/fronts.h"
#include "bkfront/io.h"
#include "bkfront/model.h"
#include "bkfront/product.h"
#include "bkfront/speeds.h"

static const char *const format_names[] = {"tsv", "json", NULL};

#define MAX_NMAX 100000u
static const char *const param_names[] = {"S", "nu", "gamma", "c", NULL};

#define COLUMNS_HELP                                                                   \
    "  n              number of fronts around the system\n"                          \
    "  v              front speed (supersonic: v > c)\n"                             \
    "  mu             gamma / sqrt(1 - c^2/v^2), the reduced equation's parameter\n"   \
    "  T, T_err       period in z of f'' + mu (f^2 - 1) f' + f = nu, its error\n"     \
    "  v_over_c       v / c (inf when c = 0)\n"                                      \
    "  wavelength     S / n, the distance between fronts\n"                          \
    "  period_fixed   T sqrt(1 - c^2/v^2): the period in t seen at a fixed point\n"  \
    "  v_asym         S / (n k(nu) gamma), the large-mu quantization,\n"              \
    "                 k = 3 + (nu^2 - 1) ln[(4 - nu^2)/(1 - nu^2)]\n"                 \
    "  deviation      (v - v_asym) / v\n"                                            \
    "  v_err          estimated absolute error of v (from T_err and the residual)\n"  \
    "  model          what gave T: shooting, asymptotic (corrected large-mu or\n"   \
    "                 small-mu formula, T_err its verified bound) or leading (k mu)\n" \
    "  residual       n T v sqrt(1 - c^2/v^2) / S - 1 at the reported root\n"        \
    "  slope          d ln g / ds at the root, g = T / sqrt(mu^2 - gamma^2),\n"       \
    "                 s = ln sqrt(mu^2 - gamma^2): < 0 on the usual branch, > 0 on\n"  \
    "                 the middle one between two folds, 0 at a fold (0 for c = 0)\n"  \
    "  flags          near-tangent (another root of this n is close: a fold is\n"    \
    "                 near, v_err is large), asymptotic (mu > 1e6: T from the\n"       \
    "                 large-mu expansion)\n"

static void speeds_help(FILE *out)
{
    fprintf(out,
        "usage: bkfront speeds --gamma G --c C --nu V --S L [--n N | --nmax N]\n"
        "                      [--tol E] [--method auto|asymptotic|leading|shooting]\n"
        "                      [--format tsv|json] [--out FILE]\n"
        "\n"
        "Every supersonic speed v at which n fronts propagate around the periodic\n"
        "system: the roots of n T(mu(v)) = S / (v sqrt(1 - c^2/v^2)),\n"
        "mu(v) = gamma / sqrt(1 - c^2/v^2), for each n >= 1, all of them (one n can\n"
        "have several). The range of n is found: n_max is reported in a comment,\n"
        "with n_bound = S / (k(nu) c gamma); every n < n_bound has a root, and\n"
        "larger n have one only where T(mu)/sqrt(mu^2 - gamma^2) dips below k.\n"
        "\n"
        "options:\n"
        "  --gamma G      required; friction strength, in [%g, %g]\n"
        "  --c C          required; sound speed, >= 0. c = 0: mu = gamma and\n"
        "                 v = S/(n T(gamma)) for every n (rows n <= %d by default)\n"
        "  --nu V         required; pulling rate in (-1, 1); |nu| >= 1 has no fronts\n"
        "  --S L          required; system size, > 0\n"
        "  --n N          only the roots for this n\n"
        "  --nmax N       only n <= N (N <= %u); default every n up to n_max, but\n"
        "                 no more than %d values of n\n"
        "  --tol E        relative accuracy asked of v, and bound on |residual|, in\n"
        "                 [%g, %g]; default 1e-10\n"
        "  --method M     how T is obtained at the roots (column model): auto (default)\n"
        "                 takes a formula wherever its verified error bound meets the\n"
        "                 tolerance the root needs (about tol, 0.1..10 tol), else\n"
        "                 shooting; asymptotic or leading: the formula at every root,\n"
        "                 exit 1 where its bound exceeds that; shooting: never a formula\n"
        "                 (except beyond the grid's cap, flag asymptotic)\n"
        "  --format tsv|json  output format; default tsv\n"
        "  --out FILE     write to FILE, replaced atomically only on success;\n"
        "                 default standard output\n"
        "  --help         this text\n"
        "\n"
        "columns:\n" COLUMNS_HELP
        "\n"
        "No front at all (S too small) is an empty table with the reason in a\n"
        "comment, exit status 0. Output is all or nothing: on any failure nothing is\n"
        "written.\n"
        "exit status: 0 ok, 1 numerical failure, 2 bad input\n",
        BKF_CYCLE_MU_MIN, BKF_CYCLE_MU_MAX, BKF_SPEEDS_ROWS_C0, MAX_NMAX, BKF_SPEEDS_MAX_ROWS,
        BKF_TOL_MIN, BKF_TOL_MAX);
}

static void branch_help(FILE *out)
{
    fprintf(out,
        "usage: bkfront branch --param S|nu|gamma|c --from A --to B [--n N] [--root I]\n"
        "                      --gamma G --c C --nu V --S L  (all but the --param one)\n"
        "                      [--tol E] [--max-points N] [--format tsv|json] [--out FILE]\n"
        "\n"
        "The branch v_n(p) of allowed front speeds along one parameter p, by\n"
        "pseudo-arclength continuation from p = A towards p = B. It passes folds,\n"
        "where two roots of one n meet and p turns back (rows of type fold), and\n"
        "ends where p leaves [A, B] or at the sonic limit v -> c+ (mu -> inf),\n"
        "reached at S = n k(nu) c gamma (a row of type sonic, with mu = T = inf).\n"
        "\n"
        "options:\n"
        "  --param S|nu|gamma|c  required; the continued parameter\n"
        "  --from A, --to B      required; its start and end values (A != B)\n"
        "  --n N          number of fronts; default 1\n"
        "  --root I       which root of this n at p = A to follow, 1 being the\n"
        "                 fastest (as listed by bkfront speeds); default 1\n"
        "  --gamma G, --c C, --nu V, --S L\n"
        "                 the other parameters, ranges as in bkfront speeds; c > 0\n"
        "                 (for c = 0, v = S/(n T(gamma)) needs no continuation)\n"
        "  --tol E        relative accuracy asked of T and v, in [%g, %g];\n"
        "                 default 1e-10\n"
        "  --max-points N at most N regular points; default no limit\n"
        "  --format tsv|json  output format; default tsv\n"
        "  --out FILE     write to FILE, replaced atomically only on success\n"
        "  --help         this text\n"
        "\n"
        "columns:\n"
        "  point          point, fold or sonic\n"
        "  S, gamma, c, nu  the parameters at this point\n" COLUMNS_HELP
        "\n"
        "Output is all or nothing: on any failure nothing is written.\n"
        "exit status: 0 ok, 1 numerical failure, 2 bad input\n",
        BKF_TOL_MIN, BKF_TOL_MAX);
}

/* ------------------------------------------------------- shared parsing */

typedef struct {
    const char *gamma, *c, *nu, *S, *tol, *format, *out;
} common_flags;

typedef struct {
    bkf_model_params params;
    double tol;
    bkf_io_format format;
    const char *out_path;
} common_plan;

/* One model parameter: given, a number, in its range; skip = the continued one. */
static int parse_param(const char *flag, const char *text, int skip, double *value,
                       bkf_error *err)
{
    if (skip) {
        if (text)
            return bkf_error_set(err, BKF_EINPUT,
                                 "%s: this is the continued parameter (--param %s); give its "
                                 "range with --from and --to instead",
                                 flag, flag + 2);
        return BKF_OK;
    }
    if (!text) return bkf_error_set(err, BKF_EINPUT, "%s is required", flag);
    int s = cli_parse_double(flag, text, value, err);
    if (s) return s;
    bkf_error e;
    const char *name = flag + 2;
    if (strcmp(name, "gamma") == 0) {
        if (bkf_model_check_positive("gamma", *value, &e) ||
            *value < BKF_CYCLE_MU_MIN || *value > BKF_CYCLE_MU_MAX)
            return bkf_error_set(err, BKF_EINPUT,
                                 "--gamma: gamma = %g is outside [%g, %g] (mu >= gamma must be "
                                 "solvable)", *value, BKF_CYCLE_MU_MIN, BKF_CYCLE_MU_MAX);
    } else if (strcmp(name, "c") == 0) {
        if (bkf_model_check_nonnegative("c", *value, &e))
            return bkf_error_set(err, BKF_EINPUT, "--c: %s", e.message);
    } else if (strcmp(name, "S") == 0) {
        if (bkf_model_check_positive("S", *value, &e))
            return bkf_error_set(err, BKF_EINPUT, "--S: %s", e.message);
    } else if (fabs(*value) >= 1.0) {
        return bkf_error_set(err, BKF_EINPUT,
                             "--nu: nu = %g is outside (-1, 1): no fronts, uniform continuous "
                             "slip psi = nu is stable (no limit cycle)", *value);
    }
    return BKF_OK;
}

static int parse_common(const common_flags *f, int skip, common_plan *plan, bkf_error *err)
{
    int s;
    if ((s = parse_param("--gamma", f->gamma, skip == BKF_SPEEDS_ALONG_GAMMA, &plan->params.gamma, err)))
        return s;
    if ((s = parse_param("--c", f->c, skip == BKF_SPEEDS_ALONG_C, &plan->params.c, err))) return s;
    if ((s = parse_param("--nu", f->nu, skip == BKF_SPEEDS_ALONG_NU, &plan->params.nu, err))) return s;
    if ((s = parse_param("--S", f->S, skip == BKF_SPEEDS_ALONG_S, &plan->params.S, err))) return s;
    plan->tol = 1e-10;
    if (f->tol) {
        if ((s = cli_parse_double("--tol", f->tol, &plan->tol, err))) return s;
        bkf_error e;
        if (bkf_model_check_tol(plan->tol, &e) != BKF_OK)
            return bkf_error_set(err, BKF_EINPUT, "--tol: %s", e.message);
    }
    plan->format = BKF_IO_TSV;
    if (f->format) {
        int k;
        if ((s = cli_parse_choice("--format", f->format, format_names, &k, err))) return s;
        plan->format = k == 1 ? BKF_IO_JSON : BKF_IO_TSV;
    }
    if (f->out && !*f->out) return bkf_error_set(err, BKF_EINPUT, "--out: the file name is empty");
    plan->out_path = f->out;
    return BKF_OK;
}

static int write_speeds(const void *spec, const bkf_product_output *out, bkf_error *err)
{
    return bkf_fronts_write(spec, out, NULL, err);
}

static int write_branch(const void *spec, const bkf_product_output *out, bkf_error *err)
{
    return bkf_fronts_branch_write(spec, out, err);
}

/* --------------------------------------------------------------- speeds */

typedef struct {
    common_plan common;
    bkf_speeds_options options;
} speeds_plan;

static int plan_speeds(int argc, char **argv, speeds_plan *plan, bkf_error *err)
{
    common_flags f = {0};
    const char *n_text = NULL, *nmax_text = NULL, *method_text = NULL;
    int help = 0;
    const cli_flag flags[] = {
        {"--gamma", &f.gamma, "a number in [1e-06, 1e+06]", NULL},
        {"--c", &f.c, "a number >= 0", NULL},
        {"--nu", &f.nu, "a number in (-1, 1)", NULL},
        {"--S", &f.S, "a number > 0", NULL},
        {"--n", &n_text, "an integer >= 1", NULL},
        {"--nmax", &nmax_text, "an integer >= 1", NULL},
        {"--tol", &f.tol, "a number in [1e-14, 0.1]", NULL},
        {"--method", &method_text, "auto, asymptotic, leading or shooting", NULL},
        {"--format", &f.format, "tsv or json", NULL},
        {"--out", &f.out, "a file name", NULL},
        {"--help", NULL, NULL, &help},
    };
    int s = cli_parse_flags(flags, sizeof flags / sizeof flags[0], argc, argv, err);
    if (s) return s;
    if ((s = parse_common(&f, -1, &plan->common, err))) return s;
    plan->options = bkf_speeds_options_default();
    plan->options.tol = plan->common.tol;
    if (method_text) {
        static const char *const method_names[] = {"auto", "asymptotic", "leading", "shooting",
                                                   NULL};
        static const bkf_cycle_method method_kinds[] = {BKF_METHOD_AUTO, BKF_METHOD_ASYMPTOTIC,
                                                        BKF_METHOD_LEADING, BKF_METHOD_SHOOTING};
        int k;
        if ((s = cli_parse_choice("--method", method_text, method_names, &k, err))) return s;
        plan->options.method = method_kinds[k];
    }
    if (n_text && nmax_text)
        return bkf_error_set(err, BKF_EINPUT,
                             "--n, --nmax: give one of them (--n N: that n only; --nmax N: "
                             "n <= N)");
    size_t k;
    if (n_text) {
        if ((s = cli_parse_count("--n", n_text, 1000000000u, &k, err))) return s;
        plan->options.n_from = plan->options.n_to = k;
    }
    if (nmax_text) {
        /* each row costs a few solves: a typo must not mean hours */
        if ((s = cli_parse_count("--nmax", nmax_text, MAX_NMAX, &k, err))) return s;
        plan->options.n_to = k;
    }
    /* the library's own checks: S/(c gamma) below 1e15 */
    bkf_error e;
    if (bkf_speeds_check(&plan->common.params, &plan->options, &e) != BKF_OK)
        return bkf_error_set(err, BKF_EINPUT, "--S, --c, --gamma: %s", e.message);
    return BKF_OK;
}

static int speeds_run(int argc, char **argv, bkf_error *err)
{
    speeds_plan plan;
    memset(&plan, 0, sizeof plan);
    int s = plan_speeds(argc, argv, &plan, err);
    if (s) return s;
    bkf_fronts_spec spec = bkf_fronts_spec_default();
    spec.params = plan.common.params;
    spec.options = plan.options;
    return cli_write_product(plan.common.out_path, plan.common.format, write_speeds, &spec, argc,
                             argv, err);
}

const cli_command cli_cmd_speeds = {
    "speeds",
    "every allowed front speed v_n: all roots of the speed-selection condition",
    speeds_run,
    speeds_help,
};

/* --------------------------------------------------------------- branch */

typedef struct {
    common_plan common;
    bkf_speeds_param along;
    double from, to;
    size_t n, root, max_points;
} branch_plan;

static int plan_branch(int argc, char **argv, branch_plan *plan, bkf_error *err)
{
    common_flags f = {0};
    const char *param = NULL, *from = NULL, *to = NULL, *n_text = NULL, *root_text = NULL,
               *max_text = NULL;
    int help = 0;
    const cli_flag flags[] = {
        {"--param", &param, "S, nu, gamma or c", NULL},
        {"--from", &from, "a number", NULL},
        {"--to", &to, "a number", NULL},
        {"--n", &n_text, "an integer >= 1", NULL},
        {"--root", &root_text, "an integer >= 1", NULL},
        {"--gamma", &f.gamma, "a number in [1e-06, 1e+06]", NULL},
        {"--c", &f.c, "a number > 0", NULL},
        {"--nu", &f.nu, "a number in (-1, 1)", NULL},
        {"--S", &f.S, "a number > 0", NULL},
        {"--tol", &f.tol, "a number in [1e-14, 0.1]", NULL},
        {"--max-points", &max_text, "an integer >= 1", NULL},
        {"--format", &f.format, "tsv or json", NULL},
        {"--out", &f.out, "a file name", NULL},
        {"--help", NULL, NULL, &help},
    };
    int s = cli_parse_flags(flags, sizeof flags / sizeof flags[0], argc, argv, err);
    if (s) return s;
    if (!param) return bkf_error_set(err, BKF_EINPUT, "--param is required (S, nu, gamma or c)");
    int k;
    if ((s = cli_parse_choice("--param", param, param_names, &k, err))) return s;
    plan->along = (bkf_speeds_param)k;
    if (!from) return bkf_error_set(err, BKF_EINPUT, "--from is required (the start value of %s)", param);
    if (!to) return bkf_error_set(err, BKF_EINPUT, "--to is required (the end value of %s)", param);
    if ((s = cli_parse_double("--from", from, &plan->from, err))) return s;
    if ((s = cli_parse_double("--to", to, &plan->to, err))) return s;
    if ((s = parse_common(&f, k, &plan->common, err))) return s;
    /* the ends as values of the continued parameter, checked like the others */
    char flag[16];
    snprintf(flag, sizeof flag, "--%s", param_names[k]);
    const char *ends[2] = {from, to};
    const char *end_flags[2] = {"--from", "--to"};
    for (int i = 0; i < 2; i++) {
        double x;
        bkf_error e;
        if (parse_param(flag, ends[i], 0, &x, &e))
            return bkf_error_set(err, BKF_EINPUT, "%s: %s", end_flags[i],
                                 strchr(e.message, ' ') ? strchr(e.message, ' ') + 1 : e.message);
    }
    if (plan->from == plan->to)
        return bkf_error_set(err, BKF_EINPUT, "--from, --to: the ends are equal (need A != B)");
    if (plan->along != BKF_SPEEDS_ALONG_C && !(plan->common.params.c > 0))
        return bkf_error_set(err, BKF_EINPUT,
                             "--c: c = 0 needs no continuation, v = S/(n T(gamma)) in closed "
                             "form (bkfront speeds); branches need c > 0");
    if (plan->along == BKF_SPEEDS_ALONG_C && !(plan->from > 0 && plan->to > 0))
        return bkf_error_set(err, BKF_EINPUT,
                             "--from, --to: c must stay > 0 along the branch (c = 0 is the "
                             "closed form v = S/(n T(gamma)))");
    *((plan->along == BKF_SPEEDS_ALONG_S)       ? &plan->common.params.S
      : (plan->along == BKF_SPEEDS_ALONG_NU)    ? &plan->common.params.nu
      : (plan->along == BKF_SPEEDS_ALONG_GAMMA) ? &plan->common.params.gamma
                                                : &plan->common.params.c) = plan->from;
    plan->n = 1;
    plan->root = 1;
    if (n_text && (s = cli_parse_count("--n", n_text, 1000000000u, &plan->n, err))) return s;
    if (root_text && (s = cli_parse_count("--root", root_text, 1000000u, &plan->root, err)))
        return s;
    plan->max_points = 0;
    if (max_text && (s = cli_parse_count("--max-points", max_text, CLI_MAX_POINTS, &plan->max_points, err)))
        return s;
    bkf_speeds_options o = bkf_speeds_options_default();
    o.tol = plan->common.tol;
    bkf_error e;
    if (bkf_speeds_check(&plan->common.params, &o, &e) != BKF_OK)
        return bkf_error_set(err, BKF_EINPUT, "--S, --c, --gamma: %s", e.message);
    return BKF_OK;
}

static int branch_run(int argc, char **argv, bkf_error *err)
{
    branch_plan plan;
    memset(&plan, 0, sizeof plan);
    int s = plan_branch(argc, argv, &plan, err);
    if (s) return s;
    bkf_fronts_branch_spec spec = bkf_fronts_branch_spec_default();
    spec.params = plan.common.params;
    spec.along = plan.along;
    spec.from = plan.from;
    spec.to = plan.to;
    spec.n = plan.n;
    spec.root = plan.root;
    spec.max_points = plan.max_points;
    spec.tol = plan.common.tol;
    return cli_write_product(plan.common.out_path, plan.common.format, write_branch, &spec, argc,
                             argv, err);
}

const cli_command cli_cmd_branch = {
    "branch",
    "one front speed v_n followed along S, nu, gamma or c, through folds to the sonic limit",
    branch_run,
    branch_help,
};

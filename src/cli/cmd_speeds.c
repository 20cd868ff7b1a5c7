/* bkfront speeds: every supersonic front speed allowed by
 *     n T(mu(v)) = S / (v sqrt(1 - c^2/v^2)),  mu(v) = gamma / sqrt(1 - c^2/v^2);
 * bkfront branch: one of them followed along S, nu, gamma or c.  The
 * products of bkfront/fronts.h from flags.
 *
 * Every input is checked before the first solve, and the table is built in
 * memory and written only when the whole computation succeeded, so a failed
 * run leaves stdout (or the --out file) untouched. */
#include "commands.h"

#include "bkfront/fronts.h"

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
    "                 near, v_err is large), asymptotic (mu > 1e5: T from the\n"       \
    "                 large-mu expansion), refused (not had to --tol: numbers nan)\n"

#define STABILITY_HELP                                                                 \
    "  stable         yes, no, or unresolved (sigma_max within its error of 0,\n"   \
    "                 or the spectrum failed: a comment says why, numbers nan);\n"  \
    "                 refused for a refused root (no spectrum without a root)\n"   \
    "  sigma_max      the rightmost Re sigma but the translation's 0; nan when the\n" \
    "                 window held nothing else (a comment: every eigenvalue left\n"  \
    "                 of its edge)\n"                                                \
    "  sigma_max_err  its estimated absolute error\n"                               \
    "  kappa_max      its Bloch number 2 pi j / S\n"                                \
    "  kind           real, or complex (a conjugate pair)\n"

static void speeds_help(FILE *out)
{
    fprintf(out,
        "usage: bkfront speeds [--gamma G] [--c C] [--nu V] [--S L] [--n N | --nmax N]\n"
        "                      [--tol E] [--method auto|asymptotic|leading|shooting]\n"
        "                      [--stability [--stability-tol E]]\n"
        "                      [--model continuum|chain [--N N]]\n"
        "                      [--format tsv|json] [--out FILE]\n"
        "\n"
        "Every supersonic speed v at which n fronts propagate around the periodic\n"
        "system: the roots of n T(mu(v)) = S / (v sqrt(1 - c^2/v^2)),\n"
        "mu(v) = gamma / sqrt(1 - c^2/v^2), for each n >= 1, all of them (one n can\n"
        "have several). The range of n is found: n_max is reported in a comment\n"
        "(with --format json also in \"results\"), with n_bound = S / (k(nu) c gamma);\n"
        "every n < n_bound has a root, and larger n have one only where\n"
        "T(mu)/sqrt(mu^2 - gamma^2) dips below k. With c = 0, mu = gamma and\n"
        "v = S/(n T(gamma)) for every n (rows n <= %d by default).\n"
        "\n"
        "options:\n",
        BKF_SPEEDS_ROWS_C0);
    cli_product_options_help("speeds", out);
    fprintf(out,
        "\n"
        "columns:\n" COLUMNS_HELP
        "with --stability, each root's ring spectrum (as bkfront stability):\n"
        STABILITY_HELP
        "\n"
        "With --model chain: the chain of N blocks (spacing h = S/N), its rotating\n"
        "waves psi_i(t) = F(t + i tau), N tau = n P, for n <= N/2 (n and N - n are\n"
        "mirror images), every wave on a branch from the uncoupled chain. Columns:\n"
        "  n, v, v_err    fronts and speed h / tau, its estimated error\n"
        "  P, P_err       period of each block, N tau / n\n"
        "  tau, h         time of one block's shift, spacing S/N\n"
        "  wavelength     S / n\n"
        "  residual       max |Phi_tau(u) - shift(u)| at the wave\n"
        "  psi_min, psi_max  range of psi over the blocks at t = 0\n"
        "and with --stability, from the multipliers m of shift^-1 o Phi_tau:\n"
        "  stable         yes, no, unresolved (|m| within its error of 1)\n"
        "  sigma_max, sigma_max_err  ln |m| / tau of the leading one, its error\n"
        "  mult_abs, mult_abs_err    |m| of the leading one, its error\n"
        "  mult_arg       its argument in [0, pi]\n"
        "  trivial_err    |m - 1| of the trivial multiplier: the accuracy gauge\n"
        "\n"
        "No front at all (S too small) is an empty table with the reason in a\n"
        "comment, exit status 0. A root that is bracketed but cannot be had to --tol\n"
        "is a row with flag refused: its numbers nan but n, wavelength and v_asym,\n"
        "model empty, stable refused, a comment 'refused: n = N, root I: WHY'; the\n"
        "other rows stand, the table is written and the exit status is 3 (a line on\n"
        "stderr counts the refused rows and gives the first one's reason). Output is\n"
        "all or nothing: on any failure nothing is written.\n"
        "exit status: 0 ok, 1 numerical failure, 2 bad input, 3 some rows refused\n");
}

static void branch_help(FILE *out)
{
    fprintf(out,
        "usage: bkfront branch --param S|nu|gamma|c|h --from A --to B [--n N] [--root I]\n"
        "                      [--gamma G] [--c C] [--nu V] [--S L]  (not the --param one)\n"
        "                      [--tol E] [--max-points N] [--stability [--stability-tol E]]\n"
        "                      [--model continuum|chain [--N N]]\n"
        "                      [--format tsv|json] [--out FILE]\n"
        "\n"
        "With --model chain: one rotating wave of the chain of --N blocks (bkfront speeds\n"
        "--model chain; --root in its order) followed at fixed N and n, along S, nu, gamma,\n"
        "c or h (the spacing; S = N h moves with it, S not given); columns point (point or\n"
        "fold), value, S, h, gamma, c, nu, K, n, v, P, tau, stable, mult_abs, sigma_max,\n"
        "trivial_err (the multipliers with --stability); the comments say how the branch\n"
        "ended (the end, a failed step, or pinning: v below 1e-3 of its start).\n"
        "\n"
        "The branch v_n(p) of allowed front speeds along one parameter p, by\n"
        "pseudo-arclength continuation from p = A towards p = B. It passes folds,\n"
        "where two roots of one n meet and p turns back (rows of type fold), and\n"
        "ends where p leaves [A, B] or at the sonic limit v -> c+ (mu -> inf),\n"
        "reached at S = n k(nu) c gamma (a row of type sonic, with mu = T = inf).\n"
        "The parameters other than --param are required; c > 0 (for c = 0,\n"
        "v = S/(n T(gamma)) needs no continuation). With --stability each point\n"
        "gets its spectral verdict, and where sigma_max changes sign between two\n"
        "points the parameter where it is 0 is located (a row of type stability).\n"
        "\n"
        "options:\n");
    cli_product_options_help("branch", out);
    fprintf(out,
        "\n"
        "columns:\n"
        "  point          point, fold, sonic, or (with --stability) stability: where\n"
        "                 sigma_max = 0 to --stability-tol between two points\n"
        "  S, gamma, c, nu  the parameters at this point\n" COLUMNS_HELP
        "with --stability, each point's ring spectrum (as bkfront stability):\n"
        STABILITY_HELP
        "\n"
        "Output is all or nothing: on any failure nothing is written.\n"
        "exit status: 0 ok, 1 numerical failure, 2 bad input\n");
}

/* The line the table reports when it has refused rows. */
static void keep_refusal(const char *message, void *data)
{
    bkf_error *partial = data;
    snprintf(partial->message, sizeof partial->message, "%s", message);
    partial->status = CLI_PARTIAL;
}

static int speeds_run(int argc, char **argv, bkf_error *err)
{
    bkf_error partial = {0};
    const bkf_catalog_hooks hooks = {.warn = keep_refusal, .data = &partial};
    int s = cli_run_product_hooks("speeds", &hooks, argc, argv, err);
    /* written whole, some rows refused: said, and told by the exit status */
    if (!s && partial.status) {
        *err = partial;
        return CLI_PARTIAL;
    }
    return s;
}

static int branch_run(int argc, char **argv, bkf_error *err)
{
    return cli_run_product("branch", argc, argv, err);
}

const cli_command cli_cmd_speeds = {
    "speeds",
    "every allowed front speed v_n: all roots of the speed-selection condition",
    speeds_run,
    speeds_help,
};

const cli_command cli_cmd_branch = {
    "branch",
    "one front speed v_n followed along S, nu, gamma or c, through folds to the sonic limit",
    branch_run,
    branch_help,
};

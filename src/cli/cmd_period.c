/* bkfront period: the period product (bkfront/period.h) from flags.
 *
 * Every input is checked before the first solve, and the table is built in
 * memory and written only when every point succeeded, so a failed run leaves
 * stdout (or the --out file) untouched. */
#include "commands.h"

#include "bkfront/period.h"

static void period_help(FILE *out)
{
    fprintf(out,
        "usage: bkfront period --mu LIST --nu LIST [--tol E] [--log] [--continue mu|nu]\n"
        "                      [--method auto|asymptotic|leading|shooting]\n"
        "                      [--stepper auto|explicit|implicit|extrapolation|collocation]\n"
        "                      [--format tsv|json] [--out FILE]\n"
        "\n"
        "Period T(mu, nu) of the limit cycle of f'' + mu (f^2 - 1) f' + f = nu, by\n"
        "Newton shooting, with its error estimate, amplitude, Floquet multiplier and\n"
        "the asymptotic approximations.\n"
        "\n"
        "options:\n");
    cli_product_options_help("period", out);
    fprintf(out,
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
        "  stepper             integrator used: rk8pd, bsimp, bd2x2 or colloc (none\n"
        "                      for a formula)\n"
        "  model               what answered: shooting, asymptotic or leading; for a\n"
        "                      formula xmax, xmin and the multipliers are NaN and the\n"
        "                      work counters 0\n"
        "\n"
        "Output is all or nothing: on any failure nothing is written.\n"
        "exit status: 0 ok, 1 numerical failure, 2 bad input\n");
}

static int period_run(int argc, char **argv, bkf_error *err)
{
    return cli_run_product("period", argc, argv, err);
}

const cli_command cli_cmd_period = {
    "period",
    "period T(mu, nu) of the reduced front equation, at points, on grids or branches",
    period_run,
    period_help,
};

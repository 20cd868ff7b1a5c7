/* bkfront asymptotics: the asymptotics product (bkfront/approx.h) from flags.
 *
 * As in `bkfront period`, every input is checked before the first solve and
 * the table is built in memory and written only when all of it succeeded. */
#include "commands.h"

#include "bkfront/approx.h"
#include "bkfront/asymfit.h"

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
        "in one of three modes (exactly one of --fit, --map, --grid).\n"
        "\n"
        "options:\n",
        BKF_ASYMFIT_TOL, BKF_ASYMFIT_TOL_FALLBACK);
    cli_product_options_help("asymptotics", out);
    fprintf(out,
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
        "exit status: 0 ok, 1 numerical failure, 2 bad input\n");
}

static int asymptotics_run(int argc, char **argv, bkf_error *err)
{
    return cli_run_product("asymptotics", argc, argv, err);
}

const cli_command cli_cmd_asymptotics = {
    "asymptotics",
    "asymptotic formulas for T against the numerical period: fits, validity map, errors",
    asymptotics_run,
    asymptotics_help,
};

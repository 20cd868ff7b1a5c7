/* bkfront floquet: stability of the global oscillations, the product of
 * bkfront/oscillation.h from flags.  Three modes:
 *   dispersion  lambda_q and the multipliers on a q grid (--nu, --q)
 *   threshold   the lowest stability boundary in nu, or its curve against
 *               c or gamma (--threshold [--along c|gamma --from A --to B])
 *   diagram     every stable and unstable interval of nu (--diagram)
 *
 * Every input is checked before the first solve, and the table is built in
 * memory and written only when everything succeeded. */
#include "commands.h"

#include "bkfront/oscillation.h"

static void floquet_help(FILE *out)
{
    fprintf(out,
        "usage: bkfront floquet [--gamma G] [--c C] [--nu V] --q LIST [--S S]\n"
        "       bkfront floquet --threshold [--gamma G] [--c C] [--search A:B]\n"
        "       bkfront floquet --threshold --along c|gamma --from A --to B\n"
        "                       [--gamma G | --c C] [--search A:B]\n"
        "       bkfront floquet --diagram [--gamma G] [--c C] [--search A:B]\n"
        "   common: [--tol E] [--cq-max P] [--nu-step H]\n"
        "           [--stepper auto|explicit|implicit|extrapolation]\n"
        "           [--format tsv|json] [--out FILE]\n"
        "\n"
        "Floquet stability of the global oscillation psi*(t) (the van der Pol cycle\n"
        "with mu = gamma) against perturbations exp(iqx):\n"
        "    d_psi' = gamma (d_eta - (psi*^2 - 1) d_psi),  d_eta' = -(1 + c^2 q^2) d_psi/gamma\n"
        "over one period T.  lambda = ln|m1|, m1 the dominant multiplier of the\n"
        "monodromy matrix, is the growth per period; lambda > 0 is unstable.\n"
        "The default mode is the dispersion relation, one row per q; --threshold\n"
        "and --diagram scan nu instead.\n"
        "\n"
        "options:\n");
    cli_product_options_help("floquet", out);
    fprintf(out,
        "\n"
        "dispersion columns:\n"
        "  q, K              wavenumber and K = 1 + c^2 q^2 (q enters only through K)\n"
        "  lambda, lambda_err  ln|m1| and its estimated absolute error\n"
        "  m1_re, m1_im, m2_re, m2_im  the multipliers, |m1| >= |m2|\n"
        "  m1_err            estimated absolute error of m1\n"
        "  kind              of m1: real_positive, real_negative or complex; refused\n"
        "                    where lambda_err stays above --tol after the retries\n"
        "                    (lambda and the multipliers are then nan; one warning\n"
        "                    line on stderr counts them and gives the first's reason)\n"
        "  allowed           1 if q = 2 pi j/S for an integer j, else 0; nan without --S\n"
        "  lambda_slip       growth of a perturbation of continuous slip psi = nu over\n"
        "                    the same time T: T max Re s, s^2 + gamma phi'(nu) s + K = 0\n"
        "  det, det_direct   m1 m2 by Liouville (exp of the integrated trace, used for\n"
        "                    m2) and the determinant of the integrated matrix (a check)\n"
        "threshold columns:\n"
        "  gamma, c, nu_pd, nu_pd_err  the boundary and its estimated error\n"
        "  kind              period_doubling (a finite-q peak of lambda crosses 0 with\n"
        "                    m1 = -1), long_wave (lambda ~ a c^2 q^2 changes sign at\n"
        "                    q -> 0), other (a finite-q peak with m1 = +1, or a jump of\n"
        "                    the cycle itself: discontinuous = 1)\n"
        "  q_c, K_c          critical wavenumber (0 for long_wave)\n"
        "  m_c_re, m_c_im    the critical multiplier; lambda_c: lambda there (~0)\n"
        "  stable_above      1 if the oscillation is stable just above nu_pd\n"
        "  longwave          the long-wave coefficient a at nu_pd\n"
        "diagram columns:\n"
        "  nu_from, nu_to, stability (stable|unstable), from_kind, to_kind (as above,\n"
        "  or scan_end), from_err, to_err, from_q, to_q, from_m, to_m\n"
        "\n"
        "Output is all or nothing: on any failure nothing is written.\n"
        "exit status: 0 ok, 1 numerical failure, 2 bad input\n");
}

static void warn_stderr(const char *message, void *data)
{
    (void)data;
    fprintf(stderr, CLI_PROGRAM " floquet: warning: %s\n", message);
}

static int floquet_run(int argc, char **argv, bkf_error *err)
{
    const bkf_catalog_hooks hooks = {.warn = warn_stderr};
    return cli_run_product_hooks("floquet", &hooks, argc, argv, err);
}

const cli_command cli_cmd_floquet = {
    "floquet",
    "Floquet stability of global oscillations: dispersion, thresholds, diagram",
    floquet_run,
    floquet_help,
};

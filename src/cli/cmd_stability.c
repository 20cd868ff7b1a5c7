/* bkfront stability: the spectrum of a train of n fronts, on the ring (one
 * row per eigenvalue) or on the infinite line (--line), the product of
 * bkfront/stability.h from flags.
 *
 * Every input is checked before the first solve, and the table is built in
 * memory and written only when everything succeeded. */
#include "commands.h"

#include "bkfront/stability.h"

static void stability_help(FILE *out)
{
    fprintf(out,
        "usage: bkfront stability [--gamma G] [--c C] [--nu V] [--S L] --n N [--root I]\n"
        "                         [--tol E] [--per-kappa K] [--line [--kappa-count M]]\n"
        "                         [--format tsv|json] [--out FILE]\n"
        "       bkfront stability --boundary | --diagram [--gamma G] [--c C] [--nu V] [--S L]\n"
        "                         --n N --to V2 --S-to L2 [--nu-step H] [--S-tol E]\n"
        "                         [--S-samples K] [--seed-step H2 | --scan] [--threads K]\n"
        "\n"
        "The spectral stability of the train of n fronts at root I of the speed\n"
        "condition (bkfront speeds --n N). In the frame xi = x + v t the train is\n"
        "steady and L-periodic, L = S/n; perturbations exp(sigma t + i kappa xi)\n"
        "times L-periodic functions grow when Re sigma > 0. On the ring of size S\n"
        "the Bloch numbers are kappa = 2 pi j / S, j = 0..n-1: one row per\n"
        "eigenvalue, the rightmost K per kappa, each to the absolute accuracy E\n"
        "(or the command fails). sigma = 0 at j = 0 is the translation of the\n"
        "train, always present. The train is stable when every other sigma has\n"
        "Re sigma < 0 beyond its error. With --line, the rightmost sigma on the\n"
        "infinite line for M Bloch numbers in [0, 2 pi/L).\n"
        "\n"
        "Across parameters: --boundary follows the S at which train N changes\n"
        "stability (sigma_max = 0) in nu from V to V2; --diagram tabulates for\n"
        "n = 1..N where each train exists and where it is stable in the (nu, S)\n"
        "plane, nu from V to V2, S in [L, L2], with the global oscillation's\n"
        "thresholds: the curves sigma_max = 0 followed by pseudo-arclength\n"
        "continuation in (nu, S) from the crossings of seed columns scanned in S\n"
        "(--scan: every nu of the grid scanned instead; docs/cli/stability.md).\n"
        "\n"
        "options:\n");
    cli_product_options_help("stability", out);
    fprintf(out,
        "\n"
        "ring columns:\n"
        "  j, kappa        Bloch index and number kappa = 2 pi j / S\n"
        "  re, im          sigma, per unit time (conjugate pairs both listed)\n"
        "  err             estimated absolute error of sigma (two meshes)\n"
        "  translation     1 for the translation mode (j = 0, sigma = 0), else 0\n"
        "comments (and with --format json the fields of \"results\"): stable\n"
        "(yes, no, or unresolved when sigma_max is within its error of 0),\n"
        "sigma_max (the rightmost Re sigma but the translation), sigma_max_im,\n"
        "sigma_max_err, kappa_max, kind (real or complex); these nan and\n"
        "sigma_bound the window's edge when nothing but the translation lies\n"
        "right of it (every eigenvalue left of sigma_bound), translation_residual,\n"
        "liouville_residual, the window searched (a_lo, y_max), mesh_steps,\n"
        "evaluations, and the root n, v, mu, T.\n"
        "line columns:\n"
        "  kappa           (2 pi/L) i/M, i = 0..M-1\n"
        "  re, im, err     the rightmost sigma at kappa and its error\n"
        "\n"
        "n beyond n_max, or a root I that n does not have, is bad input.\n"
        "Output is all or nothing: on any failure nothing is written.\n"
        "exit status: 0 ok, 1 numerical failure, 2 bad input\n");
}

static int stability_run(int argc, char **argv, bkf_error *err)
{
    return cli_run_product("stability", argc, argv, err);
}

const cli_command cli_cmd_stability = {
    "stability",
    "spectral stability of a train of n fronts: its spectrum on the ring or the line",
    stability_run,
    stability_help,
};

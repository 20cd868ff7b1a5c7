/* bkfront profile: the profile product (bkfront/profile.h) from flags. */
#include "commands.h"

#include "bkfront/profile.h"

static void profile_help(FILE *out)
{
    fprintf(out,
        "usage: bkfront profile [--nu V] ([--gamma G] [--c C] [--S L] --n LIST [--root I] | --mu M)\n"
        "                       [--points P] [--tol E] [--format tsv|json] [--out FILE]\n"
        "\n"
        "The front profile: f(z) and f'(z) over one period of the limit cycle of\n"
        "f'' + mu (f^2 - 1) f' + f = nu, z = 0 where f = nu rising, sampled at\n"
        "z = T i / P, i = 0 .. P - 1. With --n, mu is that of the predicted speed of\n"
        "n fronts (as in bkfront speeds) and x is the position along the system at\n"
        "t = 0 (one wavelength S/n per period); with --mu, the cycle at that mu (n,\n"
        "root, v and x are nan).\n"
        "\n"
        "options:\n");
    cli_product_options_help("profile", out);
    fprintf(out,
        "\n"
        "columns: n, root, v, mu, T (period in z), z, x = z v sqrt(1 - c^2/v^2), f, fprime\n");
}

static int profile_run(int argc, char **argv, bkf_error *err)
{
    return cli_run_product("profile", argc, argv, err);
}

const cli_command cli_cmd_profile = {"profile", "front profiles f(z), f'(z) and x along the system",
                                     profile_run, profile_help};

/* bkfront profile: the profile product (bkfront/profile.h) from flags. */
#include "args.h"

#include "bkfront/profile.h"

typedef struct {
    bkf_profile_spec spec;
    cli_output_spec output;
} profile_args;

static void groups_of(profile_args *a, cli_options g[2])
{
    g[0] = (cli_options){bkf_profile_options, bkf_profile_noptions, a ? &a->spec : NULL};
    g[1] = (cli_options){cli_output_options, cli_output_noptions, a ? &a->output : NULL};
}

static void profile_help(FILE *out)
{
    cli_options g[2];
    groups_of(NULL, g);
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
    cli_options_help(out, g, 2);
    fprintf(out,
        "\n"
        "columns: n, root, v, mu, T (period in z), z, x = z v sqrt(1 - c^2/v^2), f, fprime\n");
}

static int write_profile(const void *spec, FILE *out, bkf_io_format format,
                         const bkf_provenance *prov, bkf_error *err)
{
    return bkf_profile_write(spec, out, format, prov, err);
}

static int profile_run(int argc, char **argv, bkf_error *err)
{
    profile_args a = {bkf_profile_spec_default(), {0}};
    cli_options g[2];
    groups_of(&a, g);
    int s = cli_parse_options(g, 2, argc, argv, NULL, err);
    if (!s) s = bkf_profile_check(&a.spec, "--", err);
    if (!s) s = cli_write_table(&a.output, argc, argv, write_profile, &a.spec, err);
    bkf_profile_spec_free(&a.spec);
    return s;
}

const cli_command cli_cmd_profile = {"profile", "front profiles f(z), f'(z) and x along the system",
                                     profile_run, profile_help};

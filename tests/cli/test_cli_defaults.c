/* One rule for every command: a model parameter (gamma, c, nu, S) that is
 * not given is the paper's (gamma 2, c 0.3, nu -0.96, S 20, model.h), in
 * speeds, branch, stability, floquet and profile as in check, simulate and
 * sweep; what a command varies (branch --param, floquet --along, the nu
 * scan of --threshold) is not defaulted.  The table without the flags is
 * the table with them, and --help says the default. */
#define _GNU_SOURCE
#include "cli_support.h"
#include "harness.h"

#include <string.h>

/* The table's lines but its "# command:" comment. */
static char *without_command(char *text)
{
    char *c = strstr(text, "# command:");
    if (c) {
        char *nl = strchr(c, '\n');
        memmove(c, nl ? nl + 1 : c + strlen(c), strlen(nl ? nl + 1 : c + strlen(c)) + 1);
    }
    return text;
}

static void same_table(const char *bare, const char *full)
{
    char *a = without_command(bkf_cli_stdout(bare, NULL));
    char *b = without_command(bkf_cli_stdout(full, NULL));
    CHECK_MSG(strcmp(a, b) == 0, "'%s' and '%s' differ:\n%s\n---\n%s", bare, full, a, b);
    free(a);
    free(b);
}

#define PAPER "--gamma 2 --c 0.3 --nu -0.96 --S 20"

TEST(cli_model_parameters_default_to_the_paper_s)
{
    same_table("speeds --nmax 3", "speeds " PAPER " --nmax 3");
    same_table("stability --n 4 --per-kappa 1", "stability " PAPER " --n 4 --per-kappa 1");
    same_table("floquet --q 2.8,2.9", "floquet --gamma 2 --c 0.3 --nu -0.96 --q 2.8,2.9");
    same_table("profile --n 4 --points 4", "profile " PAPER " --n 4 --points 4");
    same_table("branch --param S --from 20 --to 19.5 --n 4 --max-points 3",
               "branch --param S --from 20 --to 19.5 --n 4 --max-points 3 --gamma 2 --c 0.3 "
               "--nu -0.96");
    /* the help of each says so */
    const char *cmds[] = {"speeds", "branch", "stability", "floquet", "profile", "check",
                          "simulate", "sweep"};
    for (size_t i = 0; i < sizeof cmds / sizeof *cmds; i++) {
        char words[32];
        snprintf(words, sizeof words, "help %s", cmds[i]);
        char *h = bkf_cli_stdout(words, NULL);
        const char *g = strstr(h, "  --gamma G");
        const char *end = g ? strstr(g, "\n  --c ") : NULL;
        CHECK_MSG(g && end && memmem(g, (size_t)(end - g), "default 2", 9),
                  "%s --help: no 'default 2' for --gamma", cmds[i]);
        free(h);
    }
    /* what a command varies is still not taken */
    bkf_cli_expect_bad_input(BKF_CLI("branch", "--param", "S", "--from", "20", "--to", "19",
                                     "--S", "20"),
                             "branch", "--S", "the continued parameter");
    bkf_cli_expect_bad_input(BKF_CLI("floquet", "--threshold", "--nu", "-0.9"), "floquet",
                             "--nu", "scans nu");
}

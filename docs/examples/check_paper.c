/* The speed check at the paper's parameters from C, with libbkfront alone:
 *
 *     check_paper          every n with a root
 *     check_paper 2 5 10   only these n
 *
 * prints one line "n<TAB>root<TAB>verdict" per root, the verdicts of
 * `bkfront check`.  Exit status 0, or 1 with a message on stderr. */
#include <stdio.h>
#include <stdlib.h>

#include "bkfront/check.h"
#include "bkfront/model.h"

static int print_row(const bkf_check_row *row, void *data)
{
    (void)data;
    printf("%zu\t%zu\t%s\n", row->n, row->root, bkf_check_verdict_name(row->verdict));
    return 0;
}

int main(int argc, char **argv)
{
    bkf_model_params model = bkf_model_params_paper();
    bkf_check_options options = bkf_check_options_default();
    bkf_check_hooks hooks = {.row = print_row};
    bkf_error err;
    printf("n\troot\tverdict\n");
    for (int i = 1; i < argc || i == 1; i++) {
        options.n = 0;
        if (argc > 1) {
            char *end;
            long n = strtol(argv[i], &end, 10);
            if (*end || n < 1) {
                fprintf(stderr, "check_paper: '%s' is not an integer >= 1\n", argv[i]);
                return 1;
            }
            options.n = (size_t)n;
        }
        if (bkf_check_run(&model, &options, &hooks, &err) != BKF_OK) {
            fprintf(stderr, "check_paper: %s\n", err.message);
            return 1;
        }
    }
    return 0;
}

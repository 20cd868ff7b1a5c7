/* The diagram's rule for a stalled curve, reached on purpose: a curve whose
 * continuation stalls leaves the rest of its boundary unseen, so its n gets
 * no state rows (stability.c, emit_states).  The case that used to stall
 * (gamma 1, c 0.6, n 3) is followed through its turn since 2026-11-29, so
 * the rule needs a stall of its own: --S-tol at its documented lower limit
 * (1e-8) with sigma at --tol 1e-3 asks Newton for S to about 1e-9 of the
 * window, below what sigma's own accuracy can correct on, and n = 2's
 * curves at the paper's gamma 2, c 0.3 stall at their seeds ("Newton did
 * not converge": docs/cli/stability.md, `stalled`).  The middle column
 * nu = -0.965 is crossed by no curve of n = 2, so without the rule it gets
 * a state row (checked by hand: "stable" at S 6.5). */
#include "products_support.h"

#include <math.h>

#define STALL_ARGS                                                                        \
    "stability --diagram --gamma 2 --c 0.3 --n 2 --nu -0.97 --to -0.96 --nu-step 0.005 " \
    "--S 4 --S-to 9 --S-samples 3 --seed-step 0.2 --tol 1e-3 --S-tol 1e-8 --threads 1"

TEST(stabmap_diagram_stalled_curve_at_the_s_tol_limit_has_no_states)
{
    char *tsv = cli_output(STALL_ARGS);
    CHECK(tsv);
    if (!tsv) return;
    /* the precondition: n = 2 has a curve, and each of its curves stalled */
    size_t curves_of_2 = 0, stalled_of_2 = 0;
    for (const char *line = tsv; line && *line;
         line = strchr(line, '\n') ? strchr(line, '\n') + 1 : NULL) {
        size_t curve;
        int n;
        if (sscanf(line, "# curve %zu (n %d)", &curve, &n) != 2 || n != 2) continue;
        const char *end = strchr(line, '\n');
        int len = end ? (int)(end - line) : (int)strlen(line);
        char text[1024];
        snprintf(text, sizeof text, "%.*s", len, line);
        curves_of_2++;
        stalled_of_2 += strstr(text, ": stalled") != NULL;
    }
    bkf_test_note("n 2: %zu curves, %zu stalled", curves_of_2, stalled_of_2);
    CHECK_MSG(curves_of_2 >= 1 && stalled_of_2 == curves_of_2,
              "n 2: %zu curves, %zu stalled: the case no longer stalls", curves_of_2,
              stalled_of_2);
    /* the rule: no state row of n = 2, and the note that says why */
    char kind[32];
    double n;
    size_t states_of_2 = 0;
    for (int i = 0; bkf_tsv_cell(tsv, i, "kind", NULL, kind, sizeof kind); i++)
        if (strcmp(kind, "state") == 0 && bkf_tsv_cell(tsv, i, "n", &n, NULL, 0) && n == 2)
            states_of_2++;
    CHECK_MSG(states_of_2 == 0, "n 2: a curve stalled, yet %zu state rows", states_of_2);
    CHECK(strstr(tsv, "no state rows for n 2"));
    free(tsv);
}

/* bkfront bench: the library's work-precision measurements (bench.h) as a
 * table. */
#include "commands.h"

#include "bkfront/bench.h"

static void bench_help(FILE *out)
{
    fprintf(out,
        "usage: bkfront bench [--product period|speeds|pde|all|box] [--quick]\n"
        "                     [--format tsv|json] [--out FILE]\n"
        "\n"
        "Work-precision measurement: achieved error against CPU time for every\n"
        "method and tolerance of each product.\n"
        "  period  T(mu, nu) at mu in {1, 10, 100, 1e4}, nu in {0, -0.96}: the\n"
        "          leading term k mu, the corrected asymptotics (T_asym2), shooting\n"
        "          with rk8pd (explicit) and bsimp (implicit) at tol 1e-2 .. 1e-12.\n"
        "          Reference: the published T(1, 0) = 6.663286859323130, else a\n"
        "          solve at tol 1e-13 (1e-12, 1e-11 where refused) with the OTHER\n"
        "          stepper than the row's where it can (bsimp for mu = 1e4).\n"
        "  speeds  the paper's table (gamma 2, c 0.3, nu -0.96, S 20) at tol\n"
        "          1e-4 .. 1e-12; error: largest |v - v_ref|/v_ref over the roots,\n"
        "          v_ref from the same solver at tol 1e-13.\n"
        "  pde     a seeded n = 4 front (paper's parameters), N in {256, 512, 1024},\n"
        "          tol in {1e-5, 1e-7, 1e-9}, t in [0, 30]; error: |v_meas - v_pred|/v_pred,\n"
        "          v_pred from the speeds solver at tol 1e-12; time: the run only.\n"
        "  box     the cost goal: T at tol 1e-6 against 1e-12 on mu in {1e-3, 1e-2,\n"
        "          0.1, 1, 3, 10, 30, 100, 1e3, 1e4} x nu in {0, -0.9, 0.99, -0.999,\n"
        "          0.9999}, --method shooting and auto (cold calls); comment lines give\n"
        "          the ratio per point (min, median, max) and in aggregate; method\n"
        "          column: method(model that answered). Not part of all.\n"
        "options:\n");
    cli_product_options_help("bench", out);
    fprintf(out,
        "columns: product, case, method, tol, N (pde; NaN otherwise), error (relative,\n"
        "  achieved), estimate (the method's own relative error estimate or bound),\n"
        "  cpu_seconds (process CPU time per call, averaged over repeats), work\n"
        "  (right-hand-side calls for shooting, steps for the PDE, solves for\n"
        "  speeds), status (ok or refused: the method reported it cannot reach tol)\n"
        "exit status: 0 ok, 1 numerical failure, 2 bad input\n");
}

static int bench_run(int argc, char **argv, bkf_error *err)
{
    return cli_run_product("bench", argc, argv, err);
}

const cli_command cli_cmd_bench = {
    "bench",
    "work-precision: achieved error against CPU time for every method and tolerance",
    bench_run,
    bench_help,
};

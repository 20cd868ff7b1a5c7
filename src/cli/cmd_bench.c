/* bkfront bench: the library's work-precision measurements (bench.h) as a
 * table. */
#define _POSIX_C_SOURCE 200809L
#include "args.h"

#include "bkfront/bench.h"
#include "bkfront/io.h"

static const char *const format_names[] = {"tsv", "json", NULL};

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
        "options:\n"
        "  --product P   which product; default all\n"
        "  --quick       fewer cases and tolerances (for tests)\n"
        "  --format tsv|json, --out FILE   as for period\n"
        "columns: product, case, method, tol, N (pde; NaN otherwise), error (relative,\n"
        "  achieved), estimate (the method's own relative error estimate or bound),\n"
        "  cpu_seconds (process CPU time per call, averaged over repeats), work\n"
        "  (right-hand-side calls for shooting, steps for the PDE, solves for\n"
        "  speeds), status (ok or refused: the method reported it cannot reach tol)\n"
        "exit status: 0 ok, 1 numerical failure, 2 bad input\n");
}

/* ------------------------------------------------------------ command */

static int bench_run(int argc, char **argv, bkf_error *err)
{
    const char *product = NULL, *format = NULL, *out_path = NULL;
    int quick = 0, help = 0;
    const cli_flag flags[] = {
        {"--product", &product, "period, speeds, pde, all or box", NULL},
        {"--quick", NULL, NULL, &quick},
        {"--format", &format, "tsv or json", NULL},
        {"--out", &out_path, "a file name", NULL},
        {"--help", NULL, NULL, &help},
    };
    int s = cli_parse_flags(flags, sizeof flags / sizeof flags[0], argc, argv, err);
    if (s) return s;
    int which = 3, fmt = 0;
    if (product && (s = cli_parse_choice("--product", product, bkf_bench_product_names(), &which, err)))
        return s;
    if (format && (s = cli_parse_choice("--format", format, format_names, &fmt, err))) return s;
    if (out_path && !*out_path)
        return bkf_error_set(err, BKF_EINPUT, "--out: the file name is empty");

    cli_output out = {0};
    cli_buffer buf = {0};
    s = cli_output_open(&out, out_path, "--out", err);
    if (!s) s = cli_buffer_open(&buf, err);
    if (!s) {
        size_t ncolumns;
        const bkf_io_column *columns = bkf_bench_columns(&ncolumns);
        bkf_io_table *table = bkf_io_table_alloc(buf.stream, fmt ? BKF_IO_JSON : BKF_IO_TSV,
                                                 columns, ncolumns, err);
        if (!table) s = BKF_ENOMEM;
        if (!s)
            s = bkf_io_table_comment(
                table,
                CLI_PROGRAM " " CLI_VERSION " bench: work-precision (achieved relative error "
                "against CPU seconds per call, one core)",
                err);
        if (!s) s = bkf_bench_run((bkf_bench_product)which, quick, table, err);
        if (!s) s = bkf_io_table_finish(table, err);
        bkf_io_table_free(table);
        int c = cli_buffer_close(&buf, s ? NULL : err);
        if (!s) s = c;
    }
    if (!s)
        s = cli_output_write(&out, buf.data, buf.size, err);
    else
        cli_output_abort(&out);
    cli_buffer_free(&buf);
    return s;
}

const cli_command cli_cmd_bench = {
    "bench",
    "work-precision: achieved error against CPU time for every method and tolerance",
    bench_run,
    bench_help,
};

/* bkfront sweep: the regime of a direct simulation over a grid of points
 * (bkfront/sweep.h), in OpenMP threads, in tasks of a job array, or on an
 * MPI farm (sweep_mpi.c, `make mpi`); rows appended as points finish,
 * --resume, --merge. */
#define _POSIX_C_SOURCE 200809L
#include "progress.h"
#include "sweep_mpi.h"

#include <signal.h>
#include <stdlib.h>
#include <string.h>

#include "bkfront/sweep.h"

typedef struct {
    const char *out;
    int resume;
    const char *merge;
} sweep_cli_spec;

static const bkf_option sweep_cli_options[] = {
    {.name = "out", .type = BKF_OPT_TEXT, .offset = offsetof(sweep_cli_spec, out),
     .flags = BKF_OPT_CLI_ONLY, .form = "FILE",
     .help = "the table (required): rows are appended as points finish\n"
             "and sorted by point at the end"},
    {.name = "resume", .type = BKF_OPT_SWITCH, .offset = offsetof(sweep_cli_spec, resume),
     .flags = BKF_OPT_CLI_ONLY,
     .help = "keep the rows already in --out (the same sweep only) and\n"
             "compute the other points"},
    {.name = "merge", .type = BKF_OPT_TEXT, .offset = offsetof(sweep_cli_spec, merge),
     .flags = BKF_OPT_CLI_ONLY, .form = "FILE,FILE,...",
     .help = "merge the tables of --task runs of one sweep into --out\n"
             "(no other key is needed)"},
};

typedef struct {
    bkf_sweep_spec spec;
    cli_progress_spec progress;
    sweep_cli_spec cli;
    cli_output_spec output; /* its format only: --out is the table's */
} sweep_args;

#define NGROUPS 4

/* The sweep's keys (the simulation's among them, but not its data files),
 * then the command line's own. */
static void groups_of(sweep_args *a, cli_options g[NGROUPS])
{
    size_t n;
    const bkf_option *keys = bkf_sweep_keys(&n);
    g[0] = (cli_options){keys, n, a ? &a->spec : NULL};
    g[1] = (cli_options){cli_progress_options, cli_progress_noptions, a ? &a->progress : NULL};
    g[2] = (cli_options){sweep_cli_options, sizeof sweep_cli_options / sizeof *sweep_cli_options,
                         a ? &a->cli : NULL};
    /* --format (cli_output_options[0]): json converts the finished table */
    g[3] = (cli_options){cli_output_options, 1, a ? &a->output : NULL};
}

/* --format json: the finished table at --out becomes JSON. */
static int finish_format(const sweep_args *a, bkf_error *err)
{
    return a->output.format == BKF_IO_JSON ? bkf_sweep_table_json(a->cli.out, err) : BKF_OK;
}

static void sweep_help(FILE *out)
{
    cli_options g[NGROUPS];
    groups_of(NULL, g);
    fprintf(out,
        "usage: bkfront sweep --out FILE [--x NAME=LIST [--y NAME=LIST [--zip]]] [--seeds LIST]\n"
        "                     [--inits SPEC;SPEC;...] [--threads K] [--task I --of K] [--resume]\n"
        "                     [simulate's keys: --gamma G --c C --nu V --S S --tmax T ...]\n"
        "                     [--format tsv|json]\n"
        "       bkfront sweep --merge FILE,FILE,... --out FILE [--format tsv|json]\n"
        "       mpirun -np K bkfront sweep ...   (the MPI build, make mpi)\n"
        "\n"
        "The regime of a direct simulation (bkfront simulate) at every point of a grid of one or\n"
        "two parameters, times a list of seeds, times a list of initial states: one row per point.\n"
        "Point i = ((init * ny + y) * nx + x) * nseeds + seed; its row depends on the point alone,\n"
        "bit for bit, however the sweep is split or scheduled, and bkfront simulate with the\n"
        "point's parameters gives the same regime, speed and period.\n"
        "\n"
        "options:\n");
    cli_options_help(out, g, NGROUPS);
    fprintf(out,
        "\n"
        "columns (one row per point):\n"
        "  point             index of the point\n"
        "  init, seed        initial state and seed of the run\n"
        "  gamma, c, nu, S   the model at the point\n"
        "  tmax, N           length of the run and grid points\n"
        "  regime            continuous_slip, global_oscillation, period_doubled_pacemakers,\n"
        "                    propagating_fronts, irregular (bkfront simulate's classification\n"
        "                    over the last half of the run); none when the run failed\n"
        "  fronts            fronts at the end; fronts_min, fronts_max over the window\n"
        "  speed, speed_err  fitted front speed (nan without fronts to track)\n"
        "  period, period_err, period_multiplicity\n"
        "                    period at x = 0 and its multiplicity p (2: period doubled)\n"
        "  global_period     the global oscillation's period (nan without a cycle)\n"
        "  mean, variance, std_max, psi_min, psi_max\n"
        "                    window statistics of psi, as bkfront simulate's summary\n"
        "  t_end, steps      where the run ended, accepted steps (of its last run)\n"
        "  settled           with --tmax-budget: settled (two successive windows agree)\n"
        "                    or budget (it ran out first); none when the run failed\n"
        "  status            ok, or why the run failed (numerical, blow-up, budget, ...)\n"
        "\n"
        "columns of --product speeds (after point .. tmax; the continuum, c > 0):\n"
        "  n_max             the largest n with a root (bkfront speeds)\n"
        "  allowed_count, allowed\n"
        "                    the n with a root, as 1,2,3 (- when none)\n"
        "  stable_count, stable\n"
        "                    the n with a root whose ring spectrum is stable\n"
        "  unresolved        the n with a root whose verdict is unresolved\n"
        "columns of --product threshold (after point .. tmax; c > 0):\n"
        "  nu_threshold, nu_threshold_err, kind, q_c, stable_above\n"
        "                    bkfront floquet --threshold at the point's gamma, c\n"
        "  nu_period_doubling, nu_long_wave\n"
        "                    the lowest boundary of each kind (floquet --diagram; nan: none)\n"
        "\n"
        "Rows are appended to --out as points finish, each whole and flushed to disk: a killed\n"
        "sweep loses only the points in flight, and --resume computes the rest (it refuses the\n"
        "table of another sweep: the definition line must match).  Ctrl-C stops the sweep with\n"
        "every finished row kept (exit status 130).  At the end the rows are sorted by point;\n"
        "with --format json the finished table is then replaced by its JSON (no longer\n"
        "resumable; a task's or a resumed table stays TSV, --merge ... --format json converts).\n"
        "One writer at a time: while a sweep writes --out, another sweep (--resume too) or\n"
        "--merge into it is refused (exit 2, naming the writer's process).  --merge refuses two\n"
        "different rows of one point.  Bad input anywhere in the grid is refused before any run.\n"
        "exit status: 0 ok (failed runs are rows with their status), 1 failure, 2 bad input\n");
}

static void on_progress(size_t done, size_t total, void *data)
{
    progress_count(data, done, total);
}

typedef struct {
    bkf_sweep_table *table;
} sink;

static int append(size_t index, const char *row, void *data, bkf_error *err)
{
    return bkf_sweep_table_append(((sink *)data)->table, index, row, err);
}

/* "A,B,C" into a NULL-terminated array of pointers into a copy. */
static int merge_tables(const sweep_args *a, bkf_error *err)
{
    const sweep_cli_spec *c = &a->cli;
    if (!c->out) return bkf_error_set(err, BKF_EINPUT, "--out is required (FILE)");
    char *copy = strdup(c->merge);
    size_t n = 1;
    for (const char *p = c->merge; *p; p++) n += *p == ',';
    const char **files = calloc(n, sizeof *files);
    if (!copy || !files) {
        free(copy);
        free(files);
        return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    }
    n = 0;
    for (char *save = NULL, *tok = strtok_r(copy, ",", &save); tok; tok = strtok_r(NULL, ",", &save))
        files[n++] = tok;
    size_t missing = 0;
    int s = n ? bkf_sweep_merge(files, n, c->out, &missing, err)
              : bkf_error_set(err, BKF_EINPUT, "--merge: no file given");
    if (!s && missing)
        s = bkf_error_set(err, BKF_ENUMERIC,
                          "merge: %zu points are in none of the tables (%s has the others)",
                          missing, c->out);
    if (!s) s = finish_format(a, err);
    free(copy);
    free(files);
    return s;
}

static int sweep_run(int argc, char **argv, bkf_error *err)
{
    sweep_args a = {bkf_sweep_spec_default(), {0}, {0}, {0}};
    int rank = sweep_mpi_start(&argc, &argv);
    cli_options g[NGROUPS];
    groups_of(&a, g);
    int s = cli_parse_options(g, NGROUPS, argc, argv, NULL, err);
    if (!s && a.cli.merge) {
        s = rank == 0 ? merge_tables(&a, err) : BKF_OK;
        goto done;
    }
    if (!s && !a.cli.out) s = bkf_error_set(err, BKF_EINPUT, "--out is required (FILE)");
    if (!s && a.output.format == BKF_IO_JSON && (a.cli.resume || a.spec.of > 1))
        s = bkf_error_set(err, BKF_EINPUT, "--format json: the finished table only, not with "
                          "%s (a task's table or the one resumed stays TSV; --merge FILE,... "
                          "--format json converts)", a.cli.resume ? "--resume" : "--task/--of");
    if (!s) s = bkf_sweep_check(&a.spec, "--", err);
    /* under mpirun the ranks are the cores: one run each unless --threads */
    if (!s && sweep_mpi_on() && !a.spec.threads) a.spec.threads = 1;
    if (!s) s = sweep_mpi_check(&a.spec, err);
    if (s) goto done;
    bkf_sweep_table *table = NULL;
    if (rank == 0) s = bkf_sweep_table_open(a.cli.out, &a.spec, a.cli.resume, &table, err);
    if (sweep_mpi_size() > 1) s = sweep_mpi_agree(s);
    if (s) {
        if (rank == 0) bkf_sweep_table_close(table, 0, NULL);
        goto done;
    }
    progress_bar bar;
    progress_init(&bar, CLI_PROGRAM " sweep", rank == 0 && !a.progress.no_progress);
    a.spec.progress = on_progress;
    a.spec.data = &bar;
    a.spec.cancel = cli_cancel_begin();
    sink k = {table};
    if (sweep_mpi_on())
        s = sweep_mpi_farm(&a.spec, table, &bar, err);
    else
        s = bkf_sweep_run(&a.spec, bkf_sweep_table_done(table), append, &k, err);
    cli_cancel_end();
    progress_end(&bar);
    if (rank == 0) {
        int c = bkf_sweep_table_close(table, !s, s ? NULL : err);
        if (!s) s = c;
        if (!s) s = finish_format(&a, err);
    }
    if (s == BKF_ECANCELED)
        bkf_error_set(err, s, "interrupted (%s): every finished row is in %s; --resume continues",
                      cli_cancel_signal() == SIGTERM ? "SIGTERM" : "SIGINT", a.cli.out);
done:
    bkf_sweep_spec_free(&a.spec);
    return sweep_mpi_end(s);
}

const cli_command cli_cmd_sweep = {
    "sweep",
    "regime maps: simulations over a grid of parameters, seeds and initial states (OpenMP, MPI)",
    sweep_run,
    sweep_help,
};

/* bkfront simulate: the simulation product (bkfront/simulate.h) from flags,
 * with a progress bar and Ctrl-C: an interrupted run writes what was
 * complete, marked, and exits 128 + the signal. */
#define _POSIX_C_SOURCE 200809L
#include "progress.h"

#include <signal.h>

#include "bkfront/simulate.h"

typedef struct {
    bkf_simulate_spec spec;
    cli_progress_spec progress;
    cli_output_spec output;
} simulate_args;

static void groups_of(simulate_args *a, cli_options g[3])
{
    g[0] = (cli_options){bkf_simulate_options, bkf_simulate_noptions, a ? &a->spec : NULL};
    g[1] = (cli_options){cli_progress_options, cli_progress_noptions, a ? &a->progress : NULL};
    g[2] = (cli_options){cli_output_options, cli_output_noptions, a ? &a->output : NULL};
}

static void simulate_help(FILE *out)
{
    cli_options g[3];
    groups_of(NULL, g);
    fprintf(out,
        "usage: bkfront simulate [--gamma G] [--c C] [--nu V] [--S S] [--N N] [--tmax T]\n"
        "                        [--tol E] [--init SPEC] [--seed K] [--model continuum|chain]\n"
        "                        [--stepper rk8pd|rkck|rkf45|etdrk4|lawson8|auto] [--dealias]\n"
        "                        [--frames F]\n"
        "                        [--spacetime FILE] [--spacetime-format text|binary|hdf5]\n"
        "                        [--spacetime-fields LIST] [--spacetime-deflate L]\n"
        "                        [--snapshots FILE] [--snapshot-count K] [--no-progress]\n"
        "                        [--format tsv|json] [--out FILE]\n"
        "\n"
        "Direct simulation of psi_t = gamma (eta - phi(psi)), eta_t = -(psi - nu - c^2 psi_xx)/gamma\n"
        "on a periodic domain of size S, with measurements: front count and positions, front\n"
        "speed, period at x = 0, spatial mean and variance, and the regime.\n"
        "\n"
        "options (defaults: the paper's gamma 2, c 0.3, nu -0.96, S 20):\n");
    cli_options_help(out, g, 3);
    fprintf(out,
        "\n"
        "diagnostics columns (one row per frame):\n"
        "  t                 time\n"
        "  mean, variance    spatial mean and variance of psi\n"
        "  min, max          extremes of psi over x\n"
        "  probe             psi at x = 0\n"
        "  fronts            number of fronts (crossings of the level with psi_t > 0,\n"
        "                    hysteresis 0.1)\n"
        "  displacement      mean displacement of the tracked fronts since t = 0 (nan once\n"
        "                    the front count has changed)\n"
        "  deviation         front init: max |psi - seeded wave shifted by displacement|\n"
        "  energy            H = h sum [psi_t^2/2 + (psi - nu)^2/2 - c^2 psi L psi/2]\n"
        "  energy_residual   H(t) - H(0) - integral of the friction work (0 up to the\n"
        "                    integration error)\n"
        "  mean_residual     drift of mean(eta) + (integral of mean(psi) - nu t)/gamma\n"
        "                    (conserved exactly: rounding only)\n"
        "The comment lines before the table carry the summary: regime, front speed with its\n"
        "uncertainty, period at x = 0, and the work of the run.\n"
        "\n"
        "Output is all or nothing for each file: nothing is written on failure.\n"
        "Ctrl-C (SIGINT) or SIGTERM stops the run cleanly: the frames completed so far are\n"
        "written (each output with a comment 'interrupted ... at t = ...'), one line on\n"
        "stderr says so, exit status 130 (143 for SIGTERM); a second signal ends it at once.\n"
        "exit status: 0 ok, 1 numerical failure, 2 bad input\n");
}

static const char *cancel_reason(void *data)
{
    (void)data;
    return cli_cancel_signal() == SIGTERM ? "SIGTERM" : "SIGINT";
}

/* The data files' temporaries, removed by the signal cleanup if a second
 * signal ends the process. */
typedef struct {
    progress_bar bar;
    const char *temp[2];
    int slot[2];
} simulate_context;

static void guard_temp(const char *path, int armed, void *data)
{
    simulate_context *c = data;
    for (int i = 0; i < 2; i++) {
        if (armed && !c->temp[i]) {
            c->temp[i] = path;
            c->slot[i] = cli_guard_temp(path);
            return;
        }
        if (!armed && c->temp[i] == path) {
            cli_unguard_temp(c->slot[i]);
            c->temp[i] = NULL;
            return;
        }
    }
}

/* Said before the run starts, so before any progress bar. */
static void warn(const char *message, void *data)
{
    (void)data;
    fprintf(stderr, CLI_PROGRAM " simulate: %s\n", message);
}

static int draw(double fraction, void *data)
{
    simulate_context *c = data;
    return progress_draw(fraction, &c->bar);
}

static int write_simulation(const void *spec, FILE *out, bkf_io_format format,
                            const bkf_provenance *prov, bkf_error *err)
{
    return bkf_simulate_write(spec, out, format, prov, err);
}

static int simulate_run(int argc, char **argv, bkf_error *err)
{
    simulate_args a = {bkf_simulate_spec_default(), {0}, {0}};
    cli_options g[3];
    groups_of(&a, g);
    int s = cli_parse_options(g, 3, argc, argv, NULL, err);
    if (!s) s = bkf_simulate_check(&a.spec, "--", err);
    if (s) return s;
    simulate_context ctx = {0};
    progress_init(&ctx.bar, CLI_PROGRAM " simulate", !a.progress.no_progress);
    a.spec.progress = draw;
    a.spec.warn = warn;
    a.spec.temp_file = guard_temp;
    a.spec.cancel_reason = cancel_reason;
    a.spec.data = &ctx;
    a.spec.cancel = cli_cancel_begin();
    s = cli_write_table_kept(&a.output, argc, argv, write_simulation, &a.spec, 1, err);
    cli_cancel_end();
    progress_end(&ctx.bar);
    return s;
}

const cli_command cli_cmd_simulate = {
    "simulate",
    "direct simulation (continuum or chain) with measurements, spacetime field, snapshots",
    simulate_run,
    simulate_help,
};

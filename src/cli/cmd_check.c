/* bkfront check: the speed check product (bkfront/check.h) from flags, with
 * a progress bar and the warnings on stderr.
 *
 * Every input is checked before computing, and the table is built in memory
 * and written only when the run completed (the --out file replaced
 * atomically).  A stable front that disagrees with its predicted speed, or a
 * run whose growth contradicts the spectrum, still gets the whole table, and
 * the exit status 1. */
#include "progress.h"

#include "bkfront/check.h"

typedef struct {
    bkf_check_spec spec;
    cli_progress_spec progress;
    cli_output_spec output;
} check_args;

static void groups_of(check_args *a, cli_options g[3])
{
    g[0] = (cli_options){bkf_check_keys, bkf_check_nkeys, a ? &a->spec : NULL};
    g[1] = (cli_options){cli_progress_options, cli_progress_noptions, a ? &a->progress : NULL};
    g[2] = (cli_options){cli_output_options, cli_output_noptions, a ? &a->output : NULL};
}

static void check_help(FILE *out)
{
    cli_options g[3];
    groups_of(NULL, g);
    fprintf(out,
        "usage: bkfront check [--gamma G] [--c C] [--nu V] [--S S] [--model continuum|chain]\n"
        "                     [--n K] [--N N]\n"
        "                     [--N-max M] [--tmax T] [--runs auto|full] [--threads K]\n"
        "                     [--tol E] [--rel-tol R] [--perturb A]\n"
        "                     [--seed K] [--stepper S] [--frame lab|moving]\n"
        "                     [--grid auto|uniform|mapped] [--points M]\n"
        "                     [--resolution R] [--no-progress] [--format tsv|json] [--out FILE]\n"
        "\n"
        "The predicted front speeds against direct simulation.  For every root of the\n"
        "speed-selection condition (every n, or only --n K) the travelling wave of n fronts\n"
        "at the predicted speed is seeded with a small perturbation and simulated; the\n"
        "measured speed is compared with the prediction, the perturbation's growth rate is\n"
        "fitted, and both are set beside the spectrum of the same train (bkfront\n"
        "stability).\n"
        "\n"
        "options (defaults: the paper's gamma 2, c 0.3, nu -0.96, S 20):\n");
    cli_options_help(out, g, 3);
    fprintf(out,
        "\n"
        "columns:\n"
        "  n, root           number of fronts and the root (1: fastest) of bkf_speeds_find\n"
        "  grid              uniform or mapped (the adapted grid)\n"
        "  N                 points of the grid used (0: unresolved within --N-max)\n"
        "  tail              the seed's spectral tail on the last uniform grid tried; on the\n"
        "                    adapted grid max |relaxed wave - seed| (its truncation error\n"
        "                    plus its drift during the relaxation)\n"
        "  v_pred, v_pred_err  predicted speed and its estimated error\n"
        "  v_meas, v_meas_err  measured speed (fronts move towards -x) and its uncertainty,\n"
        "                    fitted over [fit_from, fit_to]: the later half of the part of\n"
        "                    the run where the wave is coherent (front count kept and\n"
        "                    deviation <= max(100 perturb, 1e-6, 10 times the largest\n"
        "                    deviation up to t = min(10, tmax/4): the wave's response to\n"
        "                    the noise, a grid's plateau below a tail of %.0e)); on the\n"
        "                    adapted grid plus the grid's error (a second run on 2/3 of\n"
        "                    the points), measured with --runs auto only where the verdict\n"
        "                    judges the speed (agrees, disagrees), else nan\n"
        "  rel_err           (v_meas - v_pred) / v_pred\n"
        "  t_end             the run's end: tmax, or earlier when it blew up or (--runs\n"
        "                    auto) stopped: the front lost, or the row settled\n"
        "  fronts_start, fronts_end   front counts at t = 0 and t = t_end\n"
        "  deviation_start, deviation_mid, deviation_end\n"
        "                    max |psi - seeded wave shifted with the fronts| at t = 0,\n"
        "                    t_end/2 and t_end (adapted grid: the wave relaxed onto the grid)\n"
        "  growth, growth_err  the perturbation's growth rate per unit time and its\n"
        "                    uncertainty, fitted from t = min(10, tmax/4) while the count is n\n"
        "                    and the deviation <= max(1e-3, 10 perturb): least squares of the\n"
        "                    log of the envelope (the maximum in each of %d windows, at its\n"
        "                    time); the uncertainty from the residuals and the two halves'\n"
        "                    slopes, at least ln 2 / (2.5 fit length); where the halves'\n"
        "                    slopes differ beyond their noise (a transient, a mode still\n"
        "                    fading) the later half's slope, its error the difference.  On\n"
        "                    the uniform grid also per Bloch class j = 1 .. n/2 (the Fourier\n"
        "                    coefficients at k = +-j mod n, where the wave has none): the\n"
        "                    fastest fit\n"
        "  growth_limit      2.5 growth_err, at least ln 2 / fit length: the detection limit\n"
        "  growth_verdict    grows (growth > limit), decays (< -limit), else undecided\n"
        "  spectral          stable by the spectrum: yes, no, unresolved (within its error\n"
        "                    of 0, or refused, with a warning)\n"
        "  sigma_max, sigma_max_err  the rightmost Re sigma but the translation, its error;\n"
        "                    nan when refused or when only a window's edge bounds it\n"
        "  kept              1 when the run kept the front: the count never changed,\n"
        "                    deviation_end <= 1e-2 and growth_verdict is not grows\n"
        "  verdict           conflicts (the run grows while the spectrum is stable, or\n"
        "                    decays while sigma_max is above growth_limit; a warning on\n"
        "                    stderr), unstable (the run did not keep the front, or the\n"
        "                    spectrum says no), undecided (kept, but stable by neither the\n"
        "                    spectrum nor a decaying growth, or no speed measured; a\n"
        "                    warning says what would decide), agrees, disagrees (stable,\n"
        "                    rel_err within or beyond --rel-tol), unresolved (not run; or\n"
        "                    the adapted grid's run exceeded %d steps or could not be set\n"
        "                    up, with a warning)\n"
        "  decide_tmax       undecided rows: the tmax of a run that would resolve the\n"
        "                    growth in question (nan: none up to 1e6)\n"
        "\n"
        "With --model chain: the chain of --N blocks (default S), every rotating wave of\n"
        "bkfront speeds --model chain seeded with the noise and run on the blocks (rk8pd,\n"
        "tol 1e-12 unless --tol), sampled at shift times m tau: v_meas from the phase\n"
        "the fronts gain, the deviation orthogonal to it, spectral the multipliers'\n"
        "verdict, grid chain, N the blocks, tail the wave's Newton residual.\n"
        "\n"
        "Samples every 0.25 (adapted grid 0.5; the chain every shift time), spaced to\n"
        "tmax/4096 beyond: memory does not grow with tmax.\n"
        "\n"
        "exit status: 0 ok, 1 a stable front disagrees or a run conflicts with the\n"
        "spectrum (the table is written; or a numerical failure), 2 bad input\n",
        BKF_CHECK_RESOLUTION_DEFAULT, BKF_CHECK_GROWTH_WINDOWS, BKF_CHECK_MAPPED_MAX_STEPS);
}

/* What the table writer needs besides the spec; the pointers are written. */
typedef struct {
    const bkf_check_spec *spec;
    progress_bar *bar;
    size_t *disagree;
    bkf_error *verdict; /* the message when a front disagrees or conflicts */
} check_job;

static void show_progress(double fraction, void *data) { progress_draw(fraction, data); }

static void show_warning(const char *message, void *data)
{
    (void)data;
    fprintf(stderr, CLI_PROGRAM " check: warning: %s\n", message);
}

/* A disagreement or a conflict is a result: the table is kept (BKF_OK here) and the
 * command fails afterwards with the verdict's message. */
static int write_check(const void *data, FILE *out, bkf_io_format format,
                       const bkf_provenance *prov, bkf_error *err)
{
    const check_job *job = data;
    bkf_check_hooks hooks = {.progress = show_progress, .warning = show_warning,
                             .data = job->bar};
    int s = bkf_check_write(job->spec, out, format, prov, &hooks, job->disagree, err);
    progress_end(job->bar);
    if (s == BKF_ENUMERIC && *job->disagree) {
        *job->verdict = *err;
        return BKF_OK;
    }
    return s;
}

static int check_run(int argc, char **argv, bkf_error *err)
{
    check_args a = {bkf_check_spec_default(), {0}, {0}};
    cli_options g[3];
    groups_of(&a, g);
    int s = cli_parse_options(g, 3, argc, argv, NULL, err);
    if (!s) s = bkf_check_spec_check(&a.spec, "--", err);
    if (s) return s;
    progress_bar bar;
    size_t disagree = 0;
    bkf_error verdict = {0};
    progress_init(&bar, CLI_PROGRAM " check", !a.progress.no_progress);
    check_job job = {&a.spec, &bar, &disagree, &verdict};
    s = cli_write_table(&a.output, argc, argv, write_check, &job, err);
    if (!s && disagree) {
        *err = verdict;
        return BKF_ENUMERIC;
    }
    return s;
}

const cli_command cli_cmd_check = {
    "check",
    "predicted front speeds against seeded simulations: agreement, growth and spectrum per n",
    check_run,
    check_help,
};

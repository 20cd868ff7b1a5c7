/* bkfront check: the predicted front speeds against seeded simulations
 * (the library's bkf_check_run; this file turns flags into its options and
 * its rows into the table).
 *
 * As in the other subcommands every input is checked before computing, each
 * output is built in memory and written only on success (files replaced
 * atomically), and errors are one line. */
#define _POSIX_C_SOURCE 200809L
#include "simcommon.h"

#include <stdlib.h>
#include <string.h>

#include "bkfront/check.h"
#include "bkfront/cycle.h"
#include "bkfront/io.h"
#include "bkfront/model.h"
#include "bkfront/speeds.h"

static void check_help(FILE *out)
{
    fprintf(out,
        "usage: bkfront check [--gamma G] [--c C] [--nu V] [--S S] [--n K] [--N N]\n"
        "                     [--N-max M] [--tmax T] [--tol E] [--rel-tol R] [--perturb A]\n"
        "                     [--seed K] [--stepper S] [--frame lab|moving]\n"
        "                     [--grid auto|uniform|mapped] [--points M]\n"
        "                     [--resolution R] [--no-progress] [--format tsv|json] [--out FILE]\n"
        "\n"
        "The predicted front speeds against direct simulation.  For every root of the\n"
        "speed-selection condition (every n, or only --n K) the travelling wave of n fronts\n"
        "at the predicted speed is seeded with a small perturbation and simulated; the\n"
        "measured speed is compared with the prediction and the run tells whether the\n"
        "front keeps its count and shape.\n"
        "\n"
        "options (defaults: the paper's gamma 2, c 0.3, nu -0.96, S 20):\n"
        "  --gamma G, --c C, --nu V, --S S   model parameters (|nu| < 1)\n"
        "  --n K             check n = K only; default every n with a root\n"
        "  --grid G          auto (default): the uniform spectral grid when it resolves the\n"
        "                    wave on N <= %d, else the adapted grid; uniform: always the\n"
        "                    spectral grid (up to --N-max); mapped: always the adapted grid\n"
        "                    (finite differences of order 8 on points placed by the wave's\n"
        "                    own length scales, in the frame of v_pred, CVODE in time;\n"
        "                    docs/cli/check.md)\n"
        "  --points M        adapted grid: points per wavelength; default %d\n"
        "  --N N             smallest grid; each root runs on the smallest N = N 2^k that\n"
        "                    resolves its wave (Fourier coefficients above N/3 below %.0e of\n"
        "                    the largest); default %d\n"
        "  --N-max M         largest grid; roots needing more are reported unresolved and\n"
        "                    not simulated; default %d\n"
        "  --tmax T          length of each run; default 125\n"
        "  --stepper S       etdrk4 (default: exponential, the wave part of every mode\n"
        "                    exact, steps set by the physics), or rk8pd, rkck, rkf45\n"
        "                    (explicit, steps capped by the fastest wave mode ~ 1/N)\n"
        "  --tol E           local error tolerance; default %.0e with etdrk4, 1e-9 with\n"
        "                    the Runge-Kutta steppers, %.0e on the adapted grid\n"
        "  --filter F        spectral filter, as in bkfront simulate; default 4\n"
        "  --rel-tol R       agreement asked of a stable front, |v_meas - v_pred| / v_pred;\n"
        "                    default %.0e\n"
        "  --perturb A       rms of the band-limited noise added to the seeded wave;\n"
        "                    default %.0e\n"
        "  --seed K          seed of that noise; default 1\n"
        "  --resolution R    the spectral tail accepted as resolved; default %.0e\n"
        "  --frame lab|moving  simulate in the frame moving with v_pred (default), where\n"
        "                    the seeded wave is a steady state, or in the lab frame\n"
        "  --no-progress, --format tsv|json, --out FILE   as in bkfront simulate\n"
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
        "                    deviation <= max(100 perturb, 1e-6); on uniform grids with a\n"
        "                    tail above %.0e and on the adapted grid also 10 times the\n"
        "                    deviation at t = min(10, tmax/4))\n"
        "  rel_err           (v_meas - v_pred) / v_pred\n"
        "  fronts_start, fronts_end   front counts at t = 0 and t = tmax\n"
        "  deviation_start, deviation_mid, deviation_end\n"
        "                    max |psi - seeded wave shifted with the fronts| at t = 0,\n"
        "                    tmax/2 and tmax (adapted grid: the wave relaxed onto the grid)\n"
        "  growth            ln(deviation_end / deviation_mid) / (tmax/2): growth rate of\n"
        "                    the perturbation over the later half\n"
        "  stable            1 when the front count never changed and the perturbation did\n"
        "                    not grow over the later half (deviation_end <= 2 deviation_mid\n"
        "                    and <= 1e-2): count and shape kept over the run\n"
        "  verdict           agrees, disagrees (stable, rel_err beyond --rel-tol),\n"
        "                    unstable (not judged), unresolved (not run; or the adapted\n"
        "                    grid's run exceeded %d steps or could not be set up, with a\n"
        "                    warning on stderr)\n"
        "\n"
        "exit status: 0 ok, 1 a stable front disagrees (or a numerical failure), 2 bad input\n",
        BKF_CHECK_AUTO_UNIFORM_MAX, BKF_CHECK_POINTS_DEFAULT, BKF_CHECK_RESOLUTION_DEFAULT,
        BKF_CHECK_N_DEFAULT, BKF_CHECK_N_MAX_DEFAULT, BKF_CHECK_ETD_TOL_DEFAULT,
        BKF_CHECK_MAPPED_TOL_DEFAULT, BKF_CHECK_REL_TOL_DEFAULT, BKF_CHECK_PERTURB_DEFAULT,
        BKF_CHECK_RESOLUTION_DEFAULT, BKF_CHECK_RESOLUTION_DEFAULT, BKF_CHECK_MAPPED_MAX_STEPS);
}

static const bkf_io_column check_columns[] = {
    {"n", BKF_IO_NUMBER},
    {"root", BKF_IO_NUMBER},
    {"grid", BKF_IO_TEXT},
    {"N", BKF_IO_NUMBER},
    {"tail", BKF_IO_NUMBER},
    {"v_pred", BKF_IO_NUMBER},
    {"v_pred_err", BKF_IO_NUMBER},
    {"v_meas", BKF_IO_NUMBER},
    {"v_meas_err", BKF_IO_NUMBER},
    {"rel_err", BKF_IO_NUMBER},
    {"fit_from", BKF_IO_NUMBER},
    {"fit_to", BKF_IO_NUMBER},
    {"fronts_start", BKF_IO_NUMBER},
    {"fronts_end", BKF_IO_NUMBER},
    {"deviation_start", BKF_IO_NUMBER},
    {"deviation_mid", BKF_IO_NUMBER},
    {"deviation_end", BKF_IO_NUMBER},
    {"growth", BKF_IO_NUMBER},
    {"stable", BKF_IO_NUMBER},
    {"verdict", BKF_IO_TEXT},
};
#define CHECK_NCOLUMNS (sizeof check_columns / sizeof check_columns[0])

typedef struct {
    model_plan m;
    bkf_check_options opt;
    int progress;
} check_plan;

static int plan_check(int argc, char **argv, check_plan *p, bkf_error *err)
{
    model_flags mf = {0};
    const char *n = NULL, *nmax = NULL, *reltol = NULL, *perturb = NULL, *frame = NULL,
               *resol = NULL, *grid = NULL, *points = NULL;
    int help = 0, noprog = 0;
    const cli_flag flags[] = {
        {"--gamma", &mf.gamma, "a number > 0", NULL},
        {"--c", &mf.c, "a number >= 0", NULL},
        {"--nu", &mf.nu, "a number in (-1, 1)", NULL},
        {"--S", &mf.S, "a number > 0", NULL},
        {"--n", &n, "an integer >= 1", NULL},
        {"--N", &mf.N, "an even integer >= 8", NULL},
        {"--N-max", &nmax, "an even integer >= 8", NULL},
        {"--tmax", &mf.tmax, "a number > 0", NULL},
        {"--tol", &mf.tol, "a number in [1e-13, 0.01]", NULL},
        {"--filter", &mf.filter, "a number in [0, 1000]", NULL},
        {"--stepper", &mf.stepper, "rk8pd, rkck, rkf45 or etdrk4", NULL},
        {"--rel-tol", &reltol, "a number in (0, 1)", NULL},
        {"--perturb", &perturb, "a number in [0, 0.1]", NULL},
        {"--seed", &mf.seed, "an integer >= 0", NULL},
        {"--frame", &frame, "lab or moving", NULL},
        {"--grid", &grid, "auto, uniform or mapped", NULL},
        {"--points", &points, "an integer in [32, 1048576]", NULL},
        {"--resolution", &resol, "a number in [1e-16, 1]", NULL},
        {"--no-progress", NULL, NULL, &noprog},
        {"--format", &mf.format, "tsv or json", NULL},
        {"--out", &mf.out, "a file name", NULL},
        {"--help", NULL, NULL, &help},
    };
    int s = cli_parse_flags(flags, sizeof flags / sizeof flags[0], argc, argv, err);
    if (s) return s;
    if (!mf.stepper) mf.stepper = "etdrk4";
    if ((s = plan_model(&mf, &p->m, err))) return s;
    bkf_check_options *o = &p->opt;
    *o = bkf_check_options_default();
    o->N = p->m.params.N;
    o->tmax = p->m.tmax;
    o->seed = p->m.seed;
    o->stepper = p->m.options.stepper;
    o->filter = p->m.options.filter;
    o->tol = mf.tol ? p->m.options.tol : 0; /* 0: the check's own defaults */
    int k = 0;
    if (grid) {
        static const char *const grid_names[] = {"auto", "uniform", "mapped", NULL};
        if ((s = cli_parse_choice("--grid", grid, grid_names, &k, err))) return s;
        o->grid = (bkf_check_grid)k;
    }
    if (points) {
        if ((s = cli_parse_count("--points", points, BKF_CHECK_POINTS_MAX, &o->points, err)))
            return s;
        if (o->points < BKF_CHECK_POINTS_MIN)
            return bkf_error_set(err, BKF_EINPUT, "--points: %s is outside [%d, %d]", points,
                                 BKF_CHECK_POINTS_MIN, BKF_CHECK_POINTS_MAX);
    }
    if (frame) {
        static const char *const frame_names[] = {"moving", "lab", NULL};
        if ((s = cli_parse_choice("--frame", frame, frame_names, &k, err))) return s;
        o->frame = (bkf_check_frame)k;
    }
    if (o->grid == BKF_CHECK_GRID_MAPPED && o->frame == BKF_CHECK_FRAME_LAB)
        return bkf_error_set(err, BKF_EINPUT,
                             "--frame: lab is not available with --grid mapped (the adapted grid "
                             "moves with v_pred)");
    if (o->frame == BKF_CHECK_FRAME_LAB && o->grid == BKF_CHECK_GRID_AUTO)
        o->grid = BKF_CHECK_GRID_UNIFORM;
    if (resol) {
        if ((s = cli_parse_double("--resolution", resol, &o->resolution, err))) return s;
        if (!(o->resolution >= BKF_CHECK_RESOLUTION_MIN && o->resolution <= 1))
            return bkf_error_set(err, BKF_EINPUT, "--resolution: %s is outside [1e-16, 1]", resol);
    }
    bkf_error e;
    if (bkf_model_check_nu_active(p->m.params.nu, &e))
        return bkf_error_set(err, BKF_EINPUT, "--nu: %s; there are no fronts", e.message);
    if (p->m.params.gamma < BKF_CYCLE_MU_MIN || p->m.params.gamma > BKF_CYCLE_MU_MAX)
        return bkf_error_set(err, BKF_EINPUT, "--gamma: %g is outside [%g, %g]",
                             p->m.params.gamma, BKF_CYCLE_MU_MIN, BKF_CYCLE_MU_MAX);
    if (n && (s = cli_parse_count("--n", n, BKF_CHECK_FRONTS_MAX, &o->n, err))) return s;
    if (nmax && (s = cli_parse_count("--N-max", nmax, BKF_PDE_N_MAX, &o->N_max, err))) return s;
    if (o->N_max < o->N)
        return bkf_error_set(err, BKF_EINPUT, "--N-max: %zu is below --N = %zu", o->N_max, o->N);
    if (reltol) {
        if ((s = cli_parse_double("--rel-tol", reltol, &o->rel_tol, err))) return s;
        if (!(o->rel_tol > 0 && o->rel_tol < 1))
            return bkf_error_set(err, BKF_EINPUT, "--rel-tol: %s is outside (0, 1)", reltol);
    }
    if (perturb) {
        if ((s = cli_parse_double("--perturb", perturb, &o->perturb, err))) return s;
        if (!(o->perturb >= 0 && o->perturb <= BKF_CHECK_PERTURB_MAX))
            return bkf_error_set(err, BKF_EINPUT, "--perturb: %s is outside [0, 0.1]", perturb);
    }
    p->progress = !noprog;
    return BKF_OK;
}

/* The rows as they come, written once the run is done (all or nothing). */
typedef struct {
    check_plan *plan;
    progress_bar *bar;
    bkf_check_row *rows;
    size_t count, cap;
    bkf_check_info info;
    char note[BKF_SPEEDS_NOTE_LEN];
    int failed; /* out of memory in row_keep */
} check_sink;

static int check_begin(const bkf_check_info *info, void *data)
{
    check_sink *k = data;
    k->info = *info;
    snprintf(k->note, sizeof k->note, "%s", info->speeds_note);
    k->info.speeds_note = k->note;
    /* the tolerance in effect, for the provenance comment */
    k->plan->m.options.tol = info->tol;
    return 0;
}

static int check_keep(const bkf_check_row *row, void *data)
{
    check_sink *k = data;
    if (k->count == k->cap) {
        size_t cap = k->cap ? 2 * k->cap : 16;
        bkf_check_row *r = realloc(k->rows, cap * sizeof *r);
        if (!r) return k->failed = 1;
        k->rows = r;
        k->cap = cap;
    }
    k->rows[k->count++] = *row;
    return 0;
}

static void check_progress(double fraction, void *data)
{
    progress_draw(fraction, ((check_sink *)data)->bar);
}

static void check_warning(const char *message, void *data)
{
    (void)data;
    fprintf(stderr, CLI_PROGRAM " check: warning: %s\n", message);
}

static int check_write(const check_sink *k, int argc, char **argv, FILE *out, int *disagree,
                       bkf_error *err)
{
    const check_plan *p = k->plan;
    const bkf_check_options *o = &p->opt;
    char a[32], b[32], c[32], d[32], f[32];
    int s = BKF_OK;
    bkf_io_table *t = bkf_io_table_alloc(out, p->m.format, check_columns, CHECK_NCOLUMNS, err);
    if (!t) s = BKF_ENOMEM;
    if (!s)
        s = bkf_io_table_comment(t, CLI_PROGRAM " " CLI_VERSION " check: predicted front speeds "
                                    "against seeded simulations", err);
    if (!s) s = comment_model(t, &p->m, err);
    if (!s)
        s = commentf(t, err, "frame: %s",
                     o->frame == BKF_CHECK_FRAME_LAB ? "lab" : "moving with v_pred of each root");
    if (!s)
        s = commentf(t, err,
                     "tmax %s, perturbation rms %s (seed %lu), agreement asked %s, grid %s: "
                     "uniform %zu .. %zu (resolution %.0e, samples every %s), adapted %zu points "
                     "per wavelength (tol %.0e, samples every %g)",
                     num(o->tmax, a, sizeof a), num(o->perturb, b, sizeof b), o->seed,
                     num(o->rel_tol, c, sizeof c), bkf_check_grid_name(o->grid), o->N,
                     k->info.N_cap, o->resolution, num(BKF_CHECK_SAMPLE_DT, d, sizeof d),
                     o->points, k->info.mapped_tol, BKF_CHECK_MAPPED_SAMPLE_DT);
    if (!s)
        s = commentf(t, err, "speeds: k(nu) %s, n_max %ld, %zu roots%s%s",
                     num(k->info.k, f, sizeof f), k->info.n_max, k->info.roots,
                     k->note[0] ? "; " : "", k->note);
    if (!s) s = comment_command(t, argc, argv, err);
    size_t stable = 0, agree = 0, unres = 0;
    *disagree = 0;
    for (size_t i = 0; i < k->count; i++) {
        stable += k->rows[i].stable == 1;
        agree += k->rows[i].verdict == BKF_CHECK_AGREES;
        unres += k->rows[i].verdict == BKF_CHECK_UNRESOLVED;
        *disagree += k->rows[i].verdict == BKF_CHECK_DISAGREES;
    }
    if (!s) {
        char list[512] = "";
        for (size_t i = 0; i < k->count; i++)
            if (k->rows[i].stable == 1) {
                size_t used = strlen(list);
                snprintf(list + used, sizeof list - used, "%s%zu", used ? ", " : "",
                         k->rows[i].n);
            }
        s = commentf(t, err, "summary: %zu stable (n = %s), %zu agree, %d disagree, %zu unresolved",
                     stable, stable ? list : "none", agree, *disagree, unres);
    }
    for (size_t i = 0; !s && i < k->count; i++) {
        const bkf_check_row *r = &k->rows[i];
        bkf_io_value v[CHECK_NCOLUMNS] = {
            {.number = (double)r->n},          {.number = (double)r->root},
            {.text = bkf_check_grid_name(r->grid)},
            {.number = (double)r->N},          {.number = r->tail},
            {.number = r->v_pred},             {.number = r->v_pred_err},
            {.number = r->v_meas},             {.number = r->v_meas_err},
            {.number = r->rel_err},            {.number = r->fit_from},
            {.number = r->fit_to},             {.number = r->fronts_start},
            {.number = r->fronts_end},         {.number = r->deviation_start},
            {.number = r->deviation_mid},      {.number = r->deviation_end},
            {.number = r->growth},             {.number = r->stable},
            {.text = bkf_check_verdict_name(r->verdict)},
        };
        s = bkf_io_table_row(t, v, err);
    }
    if (!s) s = bkf_io_table_finish(t, err);
    bkf_io_table_free(t);
    return s;
}

static int check_compute(check_plan *p, int argc, char **argv, progress_bar *bar, FILE *out,
                         int *disagree, bkf_error *err)
{
    check_sink k = {.plan = p, .bar = bar};
    bkf_check_hooks hooks = {.begin = check_begin, .row = check_keep,
                             .progress = check_progress, .warning = check_warning, .data = &k};
    int s = bkf_check_run(&p->m.params, &p->opt, &hooks, err);
    progress_end(bar);
    if (!s && k.failed) s = bkf_error_set(err, BKF_ENOMEM, "out of memory");
    if (!s) s = check_write(&k, argc, argv, out, disagree, err);
    free(k.rows);
    return s;
}

static int check_run(int argc, char **argv, bkf_error *err)
{
    check_plan plan;
    memset(&plan, 0, sizeof plan);
    cli_output out = {0};
    cli_buffer buf = {0};
    progress_bar bar;
    int disagree = 0;
    int s = plan_check(argc, argv, &plan, err);
    if (!s) s = cli_output_open(&out, plan.m.out_path, "--out", err);
    if (!s) s = cli_buffer_open(&buf, err);
    if (!s) {
        progress_init(&bar, CLI_PROGRAM " check", plan.progress);
        s = check_compute(&plan, argc, argv, &bar, buf.stream, &disagree, err);
        int c = cli_buffer_close(&buf, s ? NULL : err);
        if (!s) s = c;
    }
    if (!s)
        s = cli_output_write(&out, buf.data, buf.size, err);
    else
        cli_output_abort(&out);
    cli_buffer_free(&buf);
    if (!s && disagree)
        return bkf_error_set(err, BKF_ENUMERIC,
                             "%d stable front(s) disagree with the predicted speed beyond "
                             "--rel-tol %g (see the table)", disagree, plan.opt.rel_tol);
    return s;
}

const cli_command cli_cmd_check = {
    "check",
    "predicted front speeds against seeded simulations: agreement and stability per n",
    check_run,
    check_help,
};

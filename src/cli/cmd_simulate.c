/* bkfront simulate: direct simulation of the model (continuum or chain) with
 * measurements, diagnostics, the spacetime field and snapshots.
 *
 * As in the other subcommands every input is checked before computing, each
 * output is built in memory and written only on success (files replaced
 * atomically), and errors are one line. */
#define _POSIX_C_SOURCE 200809L
#include "simcommon.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "bkfront/init.h"
#include "bkfront/io.h"
#include "bkfront/measure.h"
#include "bkfront/model.h"
#include "bkfront/pde.h"
#include "bkfront/seed.h"

#define INIT_FORM                                                                          \
    "uniform[:amp=A], oscillation[:q=Q|j=J][,amp=A], front:n=K[,root=R][,dir=left|right]" \
    "[,noise=E], or file:PATH"

/* ============================================================ simulate */

static void simulate_help(FILE *out)
{
    fprintf(out,
        "usage: bkfront simulate [--gamma G] [--c C] [--nu V] [--S S] [--N N] [--tmax T]\n"
        "                        [--tol E] [--init SPEC] [--seed K] [--model continuum|chain]\n"
        "                        [--stepper rk8pd|rkck|rkf45|etdrk4] [--dealias] [--frames F]\n"
        "                        [--spacetime FILE] [--spacetime-format text|binary]\n"
        "                        [--snapshots FILE] [--snapshot-count K] [--no-progress]\n"
        "                        [--format tsv|json] [--out FILE]\n"
        "\n"
        "Direct simulation of psi_t = gamma (eta - phi(psi)), eta_t = -(psi - nu - c^2 psi_xx)/gamma\n"
        "on a periodic domain of size S, with measurements: front count and positions, front\n"
        "speed, period at x = 0, spatial mean and variance, and the regime.\n"
        "\n"
        "options (defaults: the paper's gamma 2, c 0.3, nu -0.96, S 20):\n"
        "  --gamma G         friction strength, > 0; default 2\n"
        "  --c C             sound speed, >= 0; default 0.3\n"
        "  --nu V            pulling rate, any finite value (|nu| >= 1: continuous slip is\n"
        "                    stable; oscillation and front need |nu| < 1); default -0.96\n"
        "  --S S             domain size, > 0; default 20\n"
        "  --N N             grid points, in [%d, %d]; even for the continuum (a power of two\n"
        "                    is not required); default 512, or S blocks for --model chain\n"
        "  --tmax T          final time, in (0, %g]; default 125\n"
        "  --tol E           local error tolerance of the Runge-Kutta stepper (absolute and\n"
        "                    relative), in [%g, %g]; default 1e-9\n"
        "  --init SPEC       initial state; default uniform\n"
        "      uniform[:amp=A]        psi = nu + band-limited noise of rms A (default 1e-3,\n"
        "                             modes 1..S/2), eta = phi(psi)\n"
        "      oscillation[:q=Q|j=J][,amp=A]\n"
        "                             the global oscillation (cycle at mu = gamma) at psi = nu\n"
        "                             rising, plus A cos(q x); q is rounded to the nearest\n"
        "                             2 pi j/S; default j = 0, A = 0\n"
        "      front:n=K[,root=R][,dir=left|right][,noise=E]\n"
        "                             the travelling wave of K fronts at the predicted speed\n"
        "                             (root R of bkf_speeds_find, default 1, the fastest),\n"
        "                             moving left (-x, default) or right, plus noise of rms E\n"
        "      file:PATH              a TSV naming the columns psi and eta (N rows; with a t\n"
        "                             column, the rows of the last t): --snapshots output\n"
        "  --seed K          seed of the noise; default 1\n"
        "  --model M         continuum (pseudo-spectral, FFTW) or chain (Burridge-Knopoff\n"
        "                    blocks, finite differences, h = S/N); default continuum\n"
        "  --stepper S       rk8pd (default), rkck, rkf45: GSL embedded Runge-Kutta pairs;\n"
        "                    etdrk4: exponential Runge-Kutta (continuum only; the wave\n"
        "                    part exact, no step cap from N; energy_residual and\n"
        "                    mean_residual are nan with it)\n"
        "  --dealias         continuum only: 2/3-rule projection of the right-hand side\n"
        "  --filter F        continuum only: rate F of the spectral filter at the highest\n"
        "                    mode, F (k/k_top)^16 (it stops a grid instability of the modes\n"
        "                    near the Nyquist wavenumber; 0 turns it off); default 4\n"
        "  --level L         fronts are crossings of psi = L with psi_t > 0; default the\n"
        "                    middle of the global oscillation's range (nu if |nu| >= 1)\n"
        "  --frames F        rows of the diagnostics and the spacetime field, evenly spaced\n"
        "                    over [0, tmax] (F + 1 rows with t = 0); default %d\n"
        "  --spacetime FILE  psi(x, t) at the frames for gnuplot: text is the nonuniform\n"
        "                    matrix format (first row N x_0 .. x_{N-1}, then t psi ...;\n"
        "                    plot 'FILE' nonuniform matrix with image), binary the same\n"
        "                    numbers as float32 (plot 'FILE' binary matrix with image)\n"
        "  --spacetime-format text|binary   default text\n"
        "  --snapshots FILE  TSV with columns t, x, psi, eta at K frames spread over the run\n"
        "  --snapshot-count K  K >= 1 snapshots (the last at tmax); default 2\n"
        "  --no-progress     no progress bar (it is drawn on a terminal's stderr only,\n"
        "                    once a run has taken 0.5 s)\n"
        "  --format tsv|json diagnostics format; default tsv\n"
        "  --out FILE        diagnostics to FILE, replaced atomically on success;\n"
        "                    default standard output\n"
        "  --help            this text\n"
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
        "exit status: 0 ok, 1 numerical failure, 2 bad input\n",
        BKF_PDE_N_MIN, BKF_PDE_N_MAX, TMAX_MAX, BKF_PDE_TOL_MIN, BKF_PDE_TOL_MAX, DEF_FRAMES);
}

static const bkf_io_column sim_columns[] = {
    {"t", BKF_IO_NUMBER},        {"mean", BKF_IO_NUMBER},
    {"variance", BKF_IO_NUMBER}, {"min", BKF_IO_NUMBER},
    {"max", BKF_IO_NUMBER},      {"probe", BKF_IO_NUMBER},
    {"fronts", BKF_IO_NUMBER},   {"displacement", BKF_IO_NUMBER},
    {"deviation", BKF_IO_NUMBER}, {"energy", BKF_IO_NUMBER},
    {"energy_residual", BKF_IO_NUMBER}, {"mean_residual", BKF_IO_NUMBER},
};
#define SIM_NCOLUMNS (sizeof sim_columns / sizeof sim_columns[0])

typedef struct {
    model_plan m;
    bkf_init_spec init;
    const char *init_text;
    size_t frames, snapshots;
    const char *spacetime_path, *snapshots_path;
    int spacetime_binary, progress;
    double level;               /* NaN: the default (front_level) */
} sim_plan;

static int plan_simulate(int argc, char **argv, sim_plan *p, bkf_error *err)
{
    model_flags mf = {0};
    const char *init = NULL, *frames = NULL, *spacetime = NULL, *stfmt = NULL, *snaps = NULL,
               *snapcount = NULL, *level = NULL;
    int help = 0, noprog = 0;
    const cli_flag flags[] = {
        {"--gamma", &mf.gamma, "a number > 0", NULL},
        {"--c", &mf.c, "a number >= 0", NULL},
        {"--nu", &mf.nu, "a finite number", NULL},
        {"--S", &mf.S, "a number > 0", NULL},
        {"--N", &mf.N, "an integer >= 8", NULL},
        {"--tmax", &mf.tmax, "a number > 0", NULL},
        {"--tol", &mf.tol, "a number in [1e-13, 0.01]", NULL},
        {"--init", &init, INIT_FORM, NULL},
        {"--seed", &mf.seed, "an integer >= 0", NULL},
        {"--model", &mf.model, "continuum or chain", NULL},
        {"--stepper", &mf.stepper, "rk8pd, rkck, rkf45 or etdrk4", NULL},
        {"--dealias", NULL, NULL, &mf.dealias},
        {"--filter", &mf.filter, "a number in [0, 1000]", NULL},
        {"--level", &level, "a finite number", NULL},
        {"--frames", &frames, "an integer >= 1", NULL},
        {"--spacetime", &spacetime, "a file name", NULL},
        {"--spacetime-format", &stfmt, "text or binary", NULL},
        {"--snapshots", &snaps, "a file name", NULL},
        {"--snapshot-count", &snapcount, "an integer >= 1", NULL},
        {"--no-progress", NULL, NULL, &noprog},
        {"--format", &mf.format, "tsv or json", NULL},
        {"--out", &mf.out, "a file name", NULL},
        {"--help", NULL, NULL, &help},
    };
    int s = cli_parse_flags(flags, sizeof flags / sizeof flags[0], argc, argv, err);
    if (s) return s;
    if ((s = plan_model(&mf, &p->m, err))) return s;
    p->init_text = init ? init : "uniform";
    if ((s = bkf_init_parse(p->init_text, &p->init, err))) return s;
    p->init.seed = p->m.seed;
    /* a state file that cannot be read is the user's input, as a bad path */
    if ((s = bkf_init_load(&p->init, err))) return s == BKF_EIO ? BKF_EINPUT : s;
    if ((s = bkf_init_check(&p->init, &p->m.params, p->m.N_given, &p->m.options, err))) return s;
    p->frames = DEF_FRAMES;
    if (frames && (s = cli_parse_count("--frames", frames, 1000000, &p->frames, err))) return s;
    p->snapshots = 2;
    if (snapcount && (s = cli_parse_count("--snapshot-count", snapcount, 100000, &p->snapshots, err)))
        return s;
    if (p->snapshots > p->frames + 1)
        return bkf_error_set(err, BKF_EINPUT, "--snapshot-count: %zu is more than the %zu frames",
                             p->snapshots, p->frames + 1);
    if (stfmt) {
        int k;
        if ((s = cli_parse_choice("--spacetime-format", stfmt, spacetime_names, &k, err))) return s;
        p->spacetime_binary = k == 1;
        if (!spacetime)
            return bkf_error_set(err, BKF_EINPUT, "--spacetime-format: give --spacetime FILE too");
    }
    if (spacetime && !*spacetime)
        return bkf_error_set(err, BKF_EINPUT, "--spacetime: the file name is empty");
    if (snaps && !*snaps) return bkf_error_set(err, BKF_EINPUT, "--snapshots: the file name is empty");
    if (snapcount && !snaps)
        return bkf_error_set(err, BKF_EINPUT, "--snapshot-count: give --snapshots FILE too");
    p->spacetime_path = spacetime;
    p->snapshots_path = snaps;
    p->progress = !noprog;
    p->level = NAN;
    if (level && (s = cli_parse_double("--level", level, &p->level, err))) return s;
    /* frames x N values of the spacetime field are kept in memory */
    if (spacetime && (double)(p->frames + 1) * (double)p->m.params.N > 2e8)
        return bkf_error_set(err, BKF_EINPUT,
                             "--frames: %zu frames of %zu points is more than 2e8 values",
                             p->frames + 1, p->m.params.N);
    return BKF_OK;
}

/* A path must be writable before any work: open the atomic file and drop it
 * again (the real one is written at the end, when the data exist). */
static int probe_path(const char *path, const char *flag, bkf_error *err)
{
    if (!path) return BKF_OK;
    bkf_error e;
    bkf_io_atomic *f = bkf_io_atomic_open(path, &e);
    if (!f) return bkf_error_set(err, BKF_EINPUT, "%s: %s", flag, e.message);
    bkf_io_atomic_abort(f);
    return BKF_OK;
}

typedef struct {
    sim_plan *plan;
    bkf_pde *pde;
    bkf_measure *meas;
    size_t per_frame, sample_index, frame_index;
    /* frame rows, kept until the end */
    double *diag;        /* per frame: SIM_NCOLUMNS values */
    float *field;        /* per frame: psi at N points (spacetime) */
    double *snap;        /* per snapshot: t, psi[N], eta[N] */
    size_t *snap_frame;  /* frame index of each snapshot */
    size_t snap_next;
    int status;
    bkf_error err;
} sim_run;

static int sim_observe(const bkf_pde_sample *smp, void *data)
{
    sim_run *r = data;
    size_t N = r->plan->m.params.N;
    bkf_error e;
    if (bkf_measure_add(r->meas, smp->t, smp->psi, smp->eta, &e)) {
        r->status = bkf_error_set(&r->err, BKF_ENUMERIC, "measurement at t = %g: %s", smp->t,
                                  e.message);
        return 1;
    }
    size_t k = r->sample_index++;
    if (k % r->per_frame != 0 || r->frame_index > r->plan->frames) return 0;
    size_t f = r->frame_index++;
    const bkf_measure_record *rc = bkf_measure_record_at(r->meas, bkf_measure_count(r->meas) - 1);
    double *row = r->diag + f * SIM_NCOLUMNS;
    row[0] = smp->t;
    row[1] = rc->mean;
    row[2] = rc->variance;
    row[3] = rc->min;
    row[4] = rc->max;
    row[5] = rc->probe;
    row[6] = (double)rc->fronts;
    row[7] = rc->displacement;
    row[8] = rc->deviation;
    row[9] = bkf_pde_energy_of(r->pde, smp->psi, smp->eta);
    row[10] = bkf_pde_sample_energy_residual(r->pde, smp);
    row[11] = bkf_pde_sample_mean_residual(r->pde, smp);
    if (r->field)
        for (size_t i = 0; i < N; i++) r->field[f * N + i] = (float)smp->psi[i];
    if (r->snap && r->snap_next < r->plan->snapshots && r->snap_frame[r->snap_next] == f) {
        double *s = r->snap + r->snap_next * (2 * N + 1);
        s[0] = smp->t;
        memcpy(s + 1, smp->psi, N * sizeof *s);
        memcpy(s + 1 + N, smp->eta, N * sizeof *s);
        r->snap_next++;
    }
    return 0;
}

/* `note`, if not NULL, becomes a comment line (text format only). */
static int write_spacetime(const sim_plan *p, const sim_run *r, size_t frames, const char *note,
                           FILE *out, bkf_error *err)
{
    size_t N = p->m.params.N;
    double h = p->m.params.S / (double)N;
    if (p->spacetime_binary) {
        float *row = malloc((N + 1) * sizeof *row);
        if (!row) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
        row[0] = (float)N;
        for (size_t i = 0; i < N; i++) row[i + 1] = (float)((double)i * h);
        int bad = fwrite(row, sizeof *row, N + 1, out) != N + 1;
        for (size_t f = 0; f < frames && !bad; f++) {
            row[0] = (float)r->diag[f * SIM_NCOLUMNS];
            memcpy(row + 1, r->field + f * N, N * sizeof *row);
            bad = fwrite(row, sizeof *row, N + 1, out) != N + 1;
        }
        free(row);
        if (bad) return bkf_error_set(err, BKF_ENOMEM, "out of memory for the spacetime field");
        return BKF_OK;
    }
    fprintf(out, "# bkfront simulate: psi(x, t), gnuplot nonuniform matrix: first row N x_0 .. "
                 "x_{N-1}, then one row per t: t psi(x_0) .. psi(x_{N-1})\n"
                 "# plot 'FILE' nonuniform matrix using 1:2:3 with image\n");
    if (note) fprintf(out, "# %s\n", note);
    fprintf(out, "%zu", N);
    for (size_t i = 0; i < N; i++) fprintf(out, " %.9g", (double)i * h);
    fputc('\n', out);
    for (size_t f = 0; f < frames; f++) {
        fprintf(out, "%.17g", r->diag[f * SIM_NCOLUMNS]);
        for (size_t i = 0; i < N; i++) fprintf(out, " %.9g", (double)r->field[f * N + i]);
        fputc('\n', out);
    }
    return BKF_OK;
}

static int write_snapshots(const sim_plan *p, const sim_run *r, const char *note, FILE *out,
                           bkf_error *err)
{
    static const bkf_io_column cols[] = {
        {"t", BKF_IO_NUMBER}, {"x", BKF_IO_NUMBER}, {"psi", BKF_IO_NUMBER}, {"eta", BKF_IO_NUMBER}};
    size_t N = p->m.params.N;
    double h = p->m.params.S / (double)N;
    bkf_io_table *t = bkf_io_table_alloc(out, BKF_IO_TSV, cols, 4, err);
    if (!t) return BKF_ENOMEM;
    int s = bkf_io_table_comment(t, CLI_PROGRAM " " CLI_VERSION " simulate: snapshots of the "
                                    "field; readable by --init file:PATH (the last t)", err);
    if (!s && note) s = bkf_io_table_comment(t, note, err);
    if (!s && note)
        s = bkf_io_table_comment(t, "the last snapshot is the state where the run stopped: "
                                    "--init file:PATH continues from it", err);
    if (!s) s = comment_model(t, &p->m, err);
    for (size_t k = 0; !s && k < r->snap_next; k++) {
        const double *sn = r->snap + k * (2 * N + 1);
        for (size_t i = 0; !s && i < N; i++) {
            bkf_io_value v[4] = {{.number = sn[0]}, {.number = (double)i * h},
                                 {.number = sn[1 + i]}, {.number = sn[1 + N + i]}};
            s = bkf_io_table_row(t, v, err);
        }
    }
    if (!s) s = bkf_io_table_finish(t, err);
    bkf_io_table_free(t);
    return s;
}

static int write_summary(bkf_io_table *t, const sim_plan *p, const sim_run *r,
                         const bkf_measure_summary *ms, const bkf_pde_front_info *fi,
                         double period_ref, int argc, char **argv, bkf_error *err)
{
    char a[32], b[32], c[32], d[32], e[32];
    int s = bkf_io_table_comment(t, CLI_PROGRAM " " CLI_VERSION " simulate: direct simulation of "
                                    "the elastic excitable medium", err);
    if (!s) s = comment_model(t, &p->m, err);
    if (!s) s = commentf(t, err, "init %s, seed %lu; tmax %s, %zu frames", p->init_text, p->m.seed,
                         num(p->m.tmax, a, sizeof a), p->frames);
    if (!s && p->init.kind == BKF_INIT_FRONT)
        s = commentf(t, err,
                     "front: n %zu, root %zu of %zu, v_pred %s (err %.2g), mu %s, T %s, period at "
                     "a point %s, direction %s",
                     p->init.front.n, p->init.front.root, fi->roots_for_n, num(fi->v, a, sizeof a),
                     fi->v_err, num(fi->mu, b, sizeof b), num(fi->T, c, sizeof c),
                     num(fi->period_fixed, d, sizeof d),
                     p->init.front.direction < 0 ? "-x (left)" : "+x (right)");
    if (!s && p->init.kind == BKF_INIT_OSCILLATION)
        s = commentf(t, err, "oscillation: mode j %zu, q %s, amp %s", p->init.j,
                     num(2 * PI * (double)p->init.j / p->m.params.S, a, sizeof a),
                     num(p->init.amp, b, sizeof b));
    if (!s) s = comment_command(t, argc, argv, err);
    const bkf_pde_stats *st = bkf_pde_get_stats(r->pde);
    if (!s)
        s = commentf(t, err, "work: %zu steps, %zu rejected, %zu rhs calls, step %s .. %s",
                     st->steps, st->rejected, st->rhs_calls, num(st->h_min, a, sizeof a),
                     num(st->h_max, b, sizeof b));
    if (!s) s = commentf(t, err, "regime: %s (window t >= %s)", bkf_regime_name(ms->regime),
                         num(ms->window_start, a, sizeof a));
    if (!s)
        s = commentf(t, err, "fronts are crossings of psi = %s with psi_t > 0 (hysteresis 0.1)",
                     num(p->level, a, sizeof a));
    if (!s)
        s = commentf(t, err, "fronts: %zu at start, %zu at end, %zu .. %zu in the window", ms->fronts_start,
                     ms->fronts_end, ms->fronts_min, ms->fronts_max);
    if (!s && isfinite(ms->speed))
        s = commentf(t, err,
                     "speed: %s +- %.3g (fitted from t = %s; %zu tracks, %zu towards -x, %zu "
                     "towards +x; negative: towards -x)",
                     num(ms->speed, a, sizeof a), ms->speed_err, num(ms->fit_start, b, sizeof b),
                     ms->tracks, ms->moving_minus, ms->moving_plus);
    if (!s && p->init.kind == BKF_INIT_FRONT && isfinite(ms->speed))
        s = commentf(t, err, "speed vs prediction: |v| %s, v_pred %s, relative difference %.3g",
                     num(fabs(ms->speed), a, sizeof a), num(fi->v, b, sizeof b),
                     (fabs(ms->speed) - fi->v) / fi->v);
    if (!s)
        s = commentf(t, err, "period at x = 0: %s +- %.3g (multiplicity %zu, %zu crossings in the "
                             "window); global oscillation period %s",
                     num(ms->period, a, sizeof a), ms->period_err, ms->period_multiplicity,
                     ms->crossings, period_ref > 0 ? num(period_ref, b, sizeof b) : "n/a");
    if (!s)
        s = commentf(t, err, "window: mean %s, variance %s, largest spatial std %s, psi in [%s, %s]",
                     num(ms->mean, a, sizeof a), num(ms->variance, b, sizeof b),
                     num(ms->std_max, c, sizeof c), num(ms->psi_min, d, sizeof d),
                     num(ms->psi_max, e, sizeof e));
    if (!s && p->init.kind == BKF_INIT_FRONT)
        s = commentf(t, err, "deviation from the seeded wave: start %.3g, window start %.3g, end "
                             "%.3g, growth rate %.3g",
                     ms->deviation_start, ms->deviation_mid, ms->deviation_end,
                     ms->deviation_growth);
    return s;
}

static int simulate_compute(sim_plan *p, int argc, char **argv, progress_bar *bar, FILE *out,
                            cli_buffer *st_buf, cli_buffer *sn_buf, bkf_error *err)
{
    size_t N = p->m.params.N;
    bkf_error e;
    sim_run r;
    memset(&r, 0, sizeof r);
    r.plan = p;
    double *clean = NULL;
    bkf_io_table *t = NULL;
    int s = BKF_OK;
    r.pde = bkf_pde_alloc(&p->m.params, &p->m.options, err);
    if (!r.pde) return BKF_ENOMEM;
    bkf_pde_front_info fi;
    memset(&fi, 0, sizeof fi);
    clean = malloc(N * sizeof *clean);
    r.diag = malloc((p->frames + 1) * SIM_NCOLUMNS * sizeof *r.diag);
    if (p->spacetime_path) r.field = malloc((p->frames + 1) * N * sizeof *r.field);
    if (p->snapshots_path) {
        /* one more: the state where an interrupted run stopped */
        r.snap = malloc((p->snapshots + 1) * (2 * N + 1) * sizeof *r.snap);
        r.snap_frame = malloc(p->snapshots * sizeof *r.snap_frame);
    }
    if (!clean || !r.diag || (p->spacetime_path && !r.field) ||
        (p->snapshots_path && (!r.snap || !r.snap_frame))) {
        s = bkf_error_set(err, BKF_ENOMEM, "out of memory");
        goto done;
    }
    if (p->snapshots_path)
        for (size_t k = 0; k < p->snapshots; k++)
            r.snap_frame[k] = bkf_init_snapshot_frame(k, p->snapshots, p->frames);
    if ((s = bkf_seed_init(r.pde, &p->init, &fi, clean, &e))) {
        bkf_error_set(err, s, "--init %s: %s", p->init_text, e.message);
        goto done;
    }
    double period_ref;
    double level = bkf_measure_front_level(&p->m.params, &period_ref);
    if (!isnan(p->level)) level = p->level;
    p->level = level;
    bkf_measure_params mp = bkf_measure_params_default();
    mp.model = p->m.params;
    mp.level = level;
    mp.period_ref = period_ref;
    mp.reference = p->init.kind == BKF_INIT_FRONT ? clean : NULL;
    r.meas = bkf_measure_alloc(&mp, err);
    if (!r.meas) {
        s = BKF_ENOMEM;
        goto done;
    }
    bkf_init_sampling smp;
    if ((s = bkf_init_sampling_plan(p->m.tmax, p->frames, BKF_INIT_SAMPLE_DT_MAX, &smp, err)))
        goto done;
    r.per_frame = smp.per_frame;
    double t0 = bkf_pde_time(r.pde);
    s = bkf_pde_run(r.pde, t0 + p->m.tmax, smp.sample_dt, sim_observe, &r, progress_draw, bar, &e);
    progress_end(bar);
    if (r.status) {
        s = r.status;
        *err = r.err;
        goto done;
    }
    /* Interrupted (SIGINT/SIGTERM through options.cancel): the frames
     * recorded so far are complete rows; they are written, marked. */
    int canceled = s == BKF_ECANCELED;
    if (s && !canceled) {
        bkf_error_set(err, s, "%s", e.message);
        goto done;
    }
    char interrupted[160] = "";
    if (canceled)
        snprintf(interrupted, sizeof interrupted,
                 "interrupted (%s) at t = %.9g of %.9g: %zu complete frames kept",
                 cli_cancel_signal() == SIGTERM ? "SIGTERM" : "SIGINT", bkf_pde_time(r.pde),
                 t0 + p->m.tmax, r.frame_index);
    /* The snapshots end with the state where the run stopped, so that
     * --init file:SNAPSHOTS continues from there. */
    if (canceled && r.snap && (r.snap_next == 0 ||
                               r.snap[(r.snap_next - 1) * (2 * N + 1)] < bkf_pde_time(r.pde))) {
        double *sn = r.snap + r.snap_next * (2 * N + 1);
        sn[0] = bkf_pde_time(r.pde);
        memcpy(sn + 1, bkf_pde_psi(r.pde), N * sizeof *sn);
        memcpy(sn + 1 + N, bkf_pde_eta(r.pde), N * sizeof *sn);
        r.snap_next++;
    }
    bkf_measure_summary ms;
    int have_summary = 0;
    if ((s = bkf_measure_summarize(r.meas, &ms, &e))) {
        if (!canceled) {
            bkf_error_set(err, BKF_ENUMERIC, "measurements: %s", e.message);
            goto done;
        }
    } else
        have_summary = 1;
    s = BKF_OK;
    t = bkf_io_table_alloc(out, p->m.format, sim_columns, SIM_NCOLUMNS, err);
    if (!t) {
        s = BKF_ENOMEM;
        goto done;
    }
    if (canceled) s = bkf_io_table_comment(t, interrupted, err);
    if (!s && have_summary) s = write_summary(t, p, &r, &ms, &fi, period_ref, argc, argv, err);
    if (!s && p->spacetime_path)
        s = commentf(t, err, "spacetime: %s (%s)", p->spacetime_path,
                     p->spacetime_binary ? "binary matrix, float32" : "text nonuniform matrix");
    for (size_t f = 0; !s && f < r.frame_index; f++) {
        bkf_io_value v[SIM_NCOLUMNS];
        for (size_t k = 0; k < SIM_NCOLUMNS; k++) v[k].number = r.diag[f * SIM_NCOLUMNS + k];
        s = bkf_io_table_row(t, v, err);
    }
    if (!s) s = bkf_io_table_finish(t, err);
    if (!s && p->spacetime_path)
        s = write_spacetime(p, &r, r.frame_index, canceled ? interrupted : NULL, st_buf->stream,
                            err);
    if (!s && p->snapshots_path)
        s = write_snapshots(p, &r, canceled ? interrupted : NULL, sn_buf->stream, err);
    if (!s && canceled) s = bkf_error_set(err, BKF_ECANCELED, "%s", interrupted);
done:
    bkf_io_table_free(t);
    bkf_measure_free(r.meas);
    bkf_pde_free(r.pde);
    free(clean);
    free(r.diag);
    free(r.field);
    free(r.snap);
    free(r.snap_frame);
    return s;
}

static int write_file(const char *path, const char *flag, cli_buffer *buf, bkf_error *err)
{
    cli_output o = {0};
    int s = cli_output_open(&o, path, flag, err);
    if (!s) s = cli_output_write(&o, buf->data, buf->size, err);
    return s;
}

static int simulate_run(int argc, char **argv, bkf_error *err)
{
    sim_plan plan;
    memset(&plan, 0, sizeof plan);
    cli_output out = {0};
    cli_buffer buf = {0}, st = {0}, sn = {0};
    progress_bar bar;
    int s = plan_simulate(argc, argv, &plan, err);
    if (!s) s = probe_path(plan.spacetime_path, "--spacetime", err);
    if (!s) s = probe_path(plan.snapshots_path, "--snapshots", err);
    if (!s) s = cli_output_open(&out, plan.m.out_path, "--out", err);
    if (!s) s = cli_buffer_open(&buf, err);
    if (!s && plan.spacetime_path) s = cli_buffer_open(&st, err);
    if (!s && plan.snapshots_path) s = cli_buffer_open(&sn, err);
    if (!s) {
        progress_init(&bar, CLI_PROGRAM " simulate", plan.progress);
        plan.m.options.cancel = cli_cancel_begin();
        s = simulate_compute(&plan, argc, argv, &bar, buf.stream, &st, &sn, err);
        cli_cancel_end();
        int ok = !s || s == BKF_ECANCELED;
        int c1 = cli_buffer_close(&buf, ok ? err : NULL);
        int c2 = cli_buffer_close(&st, ok ? err : NULL);
        int c3 = cli_buffer_close(&sn, ok ? err : NULL);
        if (ok && (c1 || c2 || c3)) s = c1 ? c1 : c2 ? c2 : c3;
    }
    /* An interrupted run writes what was complete (marked as interrupted),
     * then reports BKF_ECANCELED; its message is kept for the end. */
    int canceled = s == BKF_ECANCELED;
    bkf_error cancel_msg = *err;
    if (canceled) s = BKF_OK;
    if (!s && plan.spacetime_path) s = write_file(plan.spacetime_path, "--spacetime", &st, err);
    if (!s && plan.snapshots_path) s = write_file(plan.snapshots_path, "--snapshots", &sn, err);
    if (!s)
        s = cli_output_write(&out, buf.data, buf.size, err);
    else
        cli_output_abort(&out);
    if (!s && canceled) {
        s = BKF_ECANCELED;
        *err = cancel_msg;
    }
    cli_buffer_free(&buf);
    cli_buffer_free(&st);
    cli_buffer_free(&sn);
    bkf_init_free(&plan.init);
    return s;
}

const cli_command cli_cmd_simulate = {
    "simulate",
    "direct simulation (continuum or chain) with measurements, spacetime field, snapshots",
    simulate_run,
    simulate_help,
};


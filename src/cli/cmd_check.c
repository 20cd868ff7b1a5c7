/* bkfront check: the predicted front speeds against seeded simulations.
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

#include "bkfront/comoving.h"
#include "bkfront/cycle.h"
#include "bkfront/io.h"
#include "bkfront/measure.h"
#include "bkfront/model.h"
#include "bkfront/pde.h"
#include "bkfront/speeds.h"

/* =============================================================== check */

/* With --grid uniform: resolves every n at the paper's parameters but
 * n = 12 (which needs N = 2^18 and ~16 minutes; docs/benchmarks.md "The
 * check's budget"). */
#define DEF_N_MAX 65536
/* --grid auto: the uniform spectral grid while it resolves the wave on at
 * most this many points, the adapted comoving grid beyond (at the paper's
 * parameters n <= 9 uniform, n = 10 .. 12 adapted; from N = 16384 on the
 * adapted grid is the cheaper, and it does n = 12 in ~1.5 s). */
#define AUTO_UNIFORM_MAX 8192
/* Points per wavelength on the adapted grid and its tolerance: at 768 and
 * 1e-8 the paper-parameter speeds agree to ~2e-9 (docs/cli/check.md "The
 * adapted grid, measured"); the tolerance well below the perturbation so that BDF's long
 * steps do not damp a growing perturbation unseen. */
#define DEF_POINTS 768
#define CHECK_MAPPED_TOL 1e-8
#define CHECK_MAPPED_SAMPLE_DT 0.5
/* The adapted grid's step budget per root: the paper's n = 10..12 take
 * 40-160 steps, an oscillating unstable wave (n = 3) ~2500; beyond this
 * the root is reported unresolved instead of running for many minutes. */
#define CHECK_MAPPED_MAX_STEPS 20000
#define DEF_REL_TOL 1e-6
#define DEF_PERTURB 1e-6
/* The seeded wave counts as resolved on N points when its Fourier
 * coefficients above N/3 are below this fraction of the largest. */
#define RESOLUTION_TOL 1e-5
/* Sample spacing of the check's measurements.  The exponential stepper
 * lands on every sample, so this is also its longest step; 0.25 is about
 * where its explicit friction term would limit the step anyway. */
#define CHECK_SAMPLE_DT 0.25
/* The check's default tolerance with the exponential stepper: its
 * estimate is the third-order embedded solution's error, far above the
 * fourth-order step's, and at 1e-7 the paper-parameter speeds and verdicts
 * are those of tol 1e-9 (docs/benchmarks.md "The check's budget") at a third of the
 * cost. */
#define CHECK_ETD_TOL 1e-7

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
        "                    README \"The adapted grid\")\n"
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
        AUTO_UNIFORM_MAX, DEF_POINTS, RESOLUTION_TOL, DEF_N, DEF_N_MAX, CHECK_ETD_TOL,
        CHECK_MAPPED_TOL, DEF_REL_TOL, DEF_PERTURB, RESOLUTION_TOL, RESOLUTION_TOL,
        CHECK_MAPPED_MAX_STEPS);
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
    size_t n;          /* 0: every n */
    size_t N_max;
    double rel_tol, perturb;
    double resolution; /* spectral tail accepted as resolved */
    int lab;           /* 1: simulate in the lab frame; 0: in the frame of v_pred */
    int grid;          /* 0 auto, 1 uniform, 2 mapped */
    size_t points;     /* adapted grid: points per wavelength */
    double mapped_tol;
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
    p->mapped_tol = mf.tol ? p->m.options.tol : CHECK_MAPPED_TOL;
    if (!mf.tol && p->m.options.stepper == BKF_PDE_ETDRK4) p->m.options.tol = CHECK_ETD_TOL;
    p->grid = 0;
    if (grid) {
        static const char *const grid_names[] = {"auto", "uniform", "mapped", NULL};
        if ((s = cli_parse_choice("--grid", grid, grid_names, &p->grid, err))) return s;
    }
    p->points = DEF_POINTS;
    if (points) {
        if ((s = cli_parse_count("--points", points, (size_t)1 << 20, &p->points, err))) return s;
        if (p->points < 32)
            return bkf_error_set(err, BKF_EINPUT, "--points: %s is outside [32, 1048576]",
                                 points);
    }
    p->lab = 0;
    if (frame) {
        static const char *const frame_names[] = {"moving", "lab", NULL};
        if ((s = cli_parse_choice("--frame", frame, frame_names, &p->lab, err))) return s;
    }
    if (p->grid == 2 && p->lab)
        return bkf_error_set(err, BKF_EINPUT,
                             "--frame: lab is not available with --grid mapped (the adapted grid "
                             "moves with v_pred)");
    if (p->lab && p->grid == 0) p->grid = 1;

    p->resolution = RESOLUTION_TOL;
    if (resol) {
        if ((s = cli_parse_double("--resolution", resol, &p->resolution, err))) return s;
        if (!(p->resolution >= 1e-16 && p->resolution <= 1))
            return bkf_error_set(err, BKF_EINPUT, "--resolution: %s is outside [1e-16, 1]", resol);
    }
    bkf_error e;
    if (bkf_model_check_nu_active(p->m.params.nu, &e))
        return bkf_error_set(err, BKF_EINPUT, "--nu: %s; there are no fronts", e.message);
    if (p->m.params.gamma < BKF_CYCLE_MU_MIN || p->m.params.gamma > BKF_CYCLE_MU_MAX)
        return bkf_error_set(err, BKF_EINPUT, "--gamma: %g is outside [%g, %g]",
                             p->m.params.gamma, BKF_CYCLE_MU_MIN, BKF_CYCLE_MU_MAX);
    p->n = 0;
    if (n && (s = cli_parse_count("--n", n, 100000, &p->n, err))) return s;
    p->N_max = DEF_N_MAX;
    if (nmax && (s = cli_parse_count("--N-max", nmax, BKF_PDE_N_MAX, &p->N_max, err))) return s;
    if (p->N_max < p->m.params.N)
        return bkf_error_set(err, BKF_EINPUT, "--N-max: %zu is below --N = %zu", p->N_max,
                             p->m.params.N);
    p->rel_tol = DEF_REL_TOL;
    if (reltol) {
        if ((s = cli_parse_double("--rel-tol", reltol, &p->rel_tol, err))) return s;
        if (!(p->rel_tol > 0 && p->rel_tol < 1))
            return bkf_error_set(err, BKF_EINPUT, "--rel-tol: %s is outside (0, 1)", reltol);
    }
    p->perturb = DEF_PERTURB;
    if (perturb) {
        if ((s = cli_parse_double("--perturb", perturb, &p->perturb, err))) return s;
        if (!(p->perturb >= 0 && p->perturb <= 0.1))
            return bkf_error_set(err, BKF_EINPUT, "--perturb: %s is outside [0, 0.1]", perturb);
    }
    p->progress = !noprog;
    return BKF_OK;
}

typedef struct {
    bkf_measure *meas;
    int status;
    bkf_error err;
} check_obs;

static int check_observe(const bkf_pde_sample *smp, void *data)
{
    check_obs *o = data;
    bkf_error e;
    if (bkf_measure_add(o->meas, smp->t, smp->psi, smp->eta, &e)) {
        o->status = bkf_error_set(&o->err, BKF_ENUMERIC, "measurement at t = %g: %s", smp->t,
                                  e.message);
        return 1;
    }
    return 0;
}

typedef struct {
    size_t n, root, N;
    const char *grid;
    double tail;
    double v_pred, v_pred_err, v_meas, v_meas_err, rel_err, fit_from, fit_to;
    double fronts_start, fronts_end, dev_start, dev_mid, dev_end, growth, stable;
    const char *verdict;
} check_row;

/* One root on the adapted comoving grid (bkf_comoving): the same
 * measurements and verdicts as on the uniform grid. */
static int check_root_mapped(const check_plan *p, const bkf_speeds_root *sr, progress_bar *bar,
                             check_row *row, bkf_error *err)
{
    row->grid = "mapped";
    bkf_comoving_params cp = bkf_comoving_params_default();
    cp.gamma = p->m.params.gamma;
    cp.c = p->m.params.c;
    cp.nu = p->m.params.nu;
    cp.S = p->m.params.S;
    cp.n = row->n;
    cp.v = sr->v;
    cp.points = p->points;
    cp.tol = p->mapped_tol;
    cp.noise = p->perturb;
    cp.seed = p->m.seed;
    cp.cancel = p->m.options.cancel;
    cp.max_steps = CHECK_MAPPED_MAX_STEPS;
    double period_ref;
    cp.level = front_level(&p->m.params, &period_ref);
    bkf_error e;
    bkf_comoving *cm = bkf_comoving_alloc(&cp, &e);
    if (!cm) {
        if (strstr(e.message, "out of memory"))
            return bkf_error_set(err, BKF_ENOMEM, "n = %zu: out of memory", row->n);
        /* this root cannot be set up on this grid (the other roots still
         * can): a row, not the end of the table */
        fprintf(stderr, CLI_PROGRAM " check: warning: n = %zu, root %zu reported unresolved: %s\n",
                row->n, row->root, e.message);
        row->verdict = "unresolved";
        return BKF_OK;
    }
    row->N = bkf_comoving_size(cm);
    bkf_comoving_stats st;
    bkf_comoving_get_stats(cm, &st);
    row->tail = st.relax_change;
    int s = bkf_comoving_run(cm, p->m.tmax, CHECK_MAPPED_SAMPLE_DT, progress_draw, bar, &e);
    int broke = 0;
    bkf_comoving_get_stats(cm, &st);
    if (s == BKF_ENUMERIC && st.blew_up && bkf_comoving_count(cm) >= 2) {
        broke = 1; /* a blown-up front is a result (unstable) */
        s = BKF_OK;
    } else if (s == BKF_ENUMERIC && st.over_budget) {
        /* not a verdict: the run was too costly to finish */
        bkf_comoving_free(cm);
        row->verdict = "unresolved";
        return BKF_OK;
    }
    if (s) {
        bkf_comoving_free(cm);
        return bkf_error_set(err, s, "n = %zu, root %zu, adapted grid of %zu points: %s", row->n,
                             row->root, row->N, e.message);
    }
    size_t R = bkf_comoving_count(cm);
    const bkf_comoving_record *first = bkf_comoving_record_at(cm, 0),
                              *last = bkf_comoving_record_at(cm, R - 1), *mid = last;
    int constant = 1;
    for (size_t r = 0; r < R; r++) {
        const bkf_comoving_record *rc = bkf_comoving_record_at(cm, r);
        if (rc->fronts != first->fronts) constant = 0;
        if (rc->t >= 0.5 * last->t && mid == last) mid = rc;
    }
    row->fronts_start = (double)first->fronts;
    row->fronts_end = (double)last->fronts;
    row->dev_start = first->deviation;
    row->dev_mid = mid->deviation;
    row->dev_end = last->deviation;
    row->growth = last->t > mid->t ? log(last->deviation / mid->deviation) / (last->t - mid->t)
                                   : NAN;
    int kept = !broke && constant && first->fronts == row->n && isfinite(row->dev_end) &&
               row->dev_end <= 2 * row->dev_mid && row->dev_end <= 1e-2;
    row->stable = kept;
    /* coherent part, as on the uniform grid; the relaxed wave's own
     * deviation plateau (set by the resolution) counts as coherent */
    double coherent = fmax(100 * p->perturb, 1e-6);
    double t_ref = fmin(10.0, 0.25 * p->m.tmax);
    for (size_t r = 0; r < R; r++) {
        const bkf_comoving_record *rc = bkf_comoving_record_at(cm, r);
        if (rc->t < t_ref) continue;
        if (rc->fronts == row->n && isfinite(rc->deviation))
            coherent = fmax(coherent, 10 * rc->deviation);
        break;
    }
    size_t end = 0;
    for (size_t r = 0; r < R; r++) {
        const bkf_comoving_record *rc = bkf_comoving_record_at(cm, r);
        if (rc->fronts != row->n || !(rc->deviation <= coherent)) break;
        end = r;
    }
    double t_end = bkf_comoving_record_at(cm, end)->t;
    if (end >= 6) {
        double drift, drift_err;
        if (bkf_comoving_fit_drift(cm, 0.5 * t_end, t_end, &drift, &drift_err, &e) == BKF_OK) {
            /* the frame moves with the fronts towards -x at v_pred */
            row->v_meas = sr->v - drift;
            row->v_meas_err = drift_err;
            row->rel_err = -drift / sr->v;
            row->fit_from = 0.5 * t_end;
            row->fit_to = t_end;
        }
    }
    bkf_comoving_free(cm);
    if (!kept) row->verdict = "unstable";
    else if (isfinite(row->rel_err) && fabs(row->rel_err) <= p->rel_tol) row->verdict = "agrees";
    else row->verdict = "disagrees";
    return BKF_OK;
}

/* One root: resolution, the perturbed run, its measurements. */
static int check_root(const check_plan *p, size_t n, size_t root, const bkf_speeds_root *sr,
                      progress_bar *bar, check_row *row, bkf_error *err)
{
    memset(row, 0, sizeof *row);
    row->n = n;
    row->root = root;
    row->v_pred = sr->v;
    row->v_pred_err = sr->v_err;
    row->v_meas = row->v_meas_err = row->rel_err = row->fit_from = row->fit_to = NAN;
    row->tail = NAN;
    row->fronts_start = row->fronts_end = NAN;
    row->dev_start = row->dev_mid = row->dev_end = row->growth = row->stable = NAN;
    bkf_model_params pp = p->m.params;
    bkf_pde_options po = p->m.options;
    /* The seeded fronts move towards -x at v_pred: in that frame the wave is
     * a steady state and the steps grow to the stability cap. */
    po.frame_speed = p->lab ? 0.0 : -sr->v;
    bkf_pde_front_spec fs = bkf_pde_front_spec_default();
    fs.n = n;
    fs.root = root;
    fs.noise = p->perturb;
    fs.seed = p->m.seed;
    bkf_error e;
    bkf_pde *pde = NULL;
    double *clean = NULL;
    bkf_measure *meas = NULL;
    bkf_pde_front_info fi;
    int s = BKF_OK;
    row->grid = "uniform";
    if (p->grid == 2) return check_root_mapped(p, sr, bar, row, err);
    size_t N_cap = p->grid == 0 ? (p->N_max < AUTO_UNIFORM_MAX ? p->N_max : AUTO_UNIFORM_MAX)
                                : p->N_max;
    for (size_t N = p->m.params.N;; N *= 2) {
        if (N > N_cap) {
            if (p->grid == 0) {
                bkf_pde_free(pde);
                free(clean);
                return check_root_mapped(p, sr, bar, row, err);
            }
            row->verdict = "unresolved";
            goto done;
        }
        pp.N = N;
        bkf_pde_free(pde);
        free(clean);
        pde = bkf_pde_alloc(&pp, &po, err);
        clean = malloc(N * sizeof *clean);
        if (!pde || !clean) {
            s = pde ? bkf_error_set(err, BKF_ENOMEM, "out of memory") : BKF_ENOMEM;
            goto done;
        }
        if ((s = bkf_pde_init_front(pde, &fs, &fi, clean, &e))) {
            bkf_error_set(err, s, "n = %zu, root %zu: %s", n, root, e.message);
            goto done;
        }
        row->tail = bkf_pde_spectral_tail(pde, clean);
        if (row->tail <= p->resolution) break;
    }
    row->N = pp.N;
    bkf_measure_params mp = bkf_measure_params_default();
    mp.N = pp.N;
    mp.S = pp.S;
    mp.gamma = pp.gamma;
    mp.nu = pp.nu;
    mp.reference = clean;
    double period_ref;
    mp.level = front_level(&pp, &period_ref);
    if (!(meas = bkf_measure_alloc(&mp, err))) {
        s = BKF_ENOMEM;
        goto done;
    }
    check_obs ob = {meas, 0, {{0}}};
    s = bkf_pde_run(pde, p->m.tmax, CHECK_SAMPLE_DT, check_observe, &ob, progress_draw, bar, &e);
    if (ob.status) {
        s = ob.status;
        *err = ob.err;
        goto done;
    }
    int broke = 0;
    if (s == BKF_ENUMERIC && bkf_measure_count(meas) >= 2) {
        /* A blown-up front is a result (unstable), not a failure of the check. */
        broke = 1;
        s = BKF_OK;
    }
    if (s) {
        bkf_error_set(err, s, "n = %zu, root %zu, N = %zu: %s", n, root, pp.N, e.message);
        goto done;
    }
    bkf_measure_summary ms;
    if ((s = bkf_measure_summarize(meas, &ms, &e))) {
        bkf_error_set(err, BKF_ENUMERIC, "n = %zu: %s", n, e.message);
        goto done;
    }
    row->fronts_start = (double)ms.fronts_start;
    row->fronts_end = (double)ms.fronts_end;
    row->dev_start = ms.deviation_start;
    row->dev_mid = ms.deviation_mid;
    row->dev_end = ms.deviation_end;
    row->growth = ms.deviation_growth;
    int kept = !broke && ms.count_constant && ms.fronts_start == n && isfinite(ms.deviation_end) &&
               ms.deviation_end <= 2 * ms.deviation_mid && ms.deviation_end <= 1e-2;
    row->stable = kept;
    /* coherent part: count kept and deviation small, from the start on.
     * Small: below 100 times the perturbation, or below 10 times the
     * deviation at t_ref = min(10, tmax/4), by when a wave that is not
     * fully resolved has settled into the grid's own travelling wave (its
     * deviation from the seed is then a plateau set by the resolution, not
     * a growing perturbation).  Only on such grids (tail above the default
     * rule's RESOLUTION_TOL). */
    double coherent = fmax(100 * p->perturb, 1e-6);
    size_t R = bkf_measure_count(meas), last = 0;
    double t_ref = fmin(10.0, 0.25 * p->m.tmax);
    for (size_t r = 0; row->tail > RESOLUTION_TOL && r < R; r++) {
        const bkf_measure_record *rc = bkf_measure_record_at(meas, r);
        if (rc->t < t_ref) continue;
        if (rc->fronts == n && isfinite(rc->deviation))
            coherent = fmax(coherent, 10 * rc->deviation);
        break;
    }
    for (size_t r = 0; r < R; r++) {
        const bkf_measure_record *rc = bkf_measure_record_at(meas, r);
        if (rc->fronts != n || !(rc->deviation <= coherent)) break;
        last = r;
    }
    double t_end = bkf_measure_record_at(meas, last)->t;
    if (last >= 6) {
        double t_from = 0.5 * t_end;
        double v, ve;
        if (bkf_measure_fit_speed(meas, t_from, t_end, &v, &ve, NULL, &e) == BKF_OK) {
            /* v is relative to the frame; towards -x in the lab: -(v + V) */
            row->v_meas = -(v + po.frame_speed);
            row->v_meas_err = ve;
            row->rel_err = -(v + po.frame_speed + sr->v) / sr->v;
            row->fit_from = t_from;
            row->fit_to = t_end;
        }
    }
    if (!kept) row->verdict = "unstable";
    else if (isfinite(row->rel_err) && fabs(row->rel_err) <= p->rel_tol) row->verdict = "agrees";
    else row->verdict = "disagrees";
done:
    bkf_measure_free(meas);
    bkf_pde_free(pde);
    free(clean);
    return s;
}

static int check_compute(const check_plan *p, int argc, char **argv, progress_bar *bar, FILE *out,
                         int *disagree, bkf_error *err)
{
    char a[32], b[32], c[32], d[32], f[32];
    bkf_model_params sp = {p->m.params.gamma, p->m.params.c, p->m.params.nu, p->m.params.S, 0, BKF_MODEL_CONTINUUM};
    bkf_speeds_options so = bkf_speeds_options_default();
    so.tol = 1e-12;
    if (p->n) so.n_from = so.n_to = p->n;
    bkf_speeds_table tab;
    memset(&tab, 0, sizeof tab);
    bkf_error e;
    int s = bkf_speeds_find(&sp, &so, &tab, &e);
    if (s) {
        bkf_speeds_table_free(&tab);
        return bkf_error_set(err, s, "speeds: %s", e.message);
    }
    check_row *rows = calloc(tab.count ? tab.count : 1, sizeof *rows);
    if (!rows) {
        bkf_speeds_table_free(&tab);
        return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    }
    size_t done = 0;
    for (size_t i = 0; !s && i < tab.count; i++) {
        size_t root = 1;
        for (size_t k = i; k > 0 && tab.roots[k - 1].n == tab.roots[i].n; k--) root++;
        bar->base = (double)i / (double)tab.count;
        bar->share = 1.0 / (double)tab.count;
        s = check_root(p, tab.roots[i].n, root, &tab.roots[i], bar, &rows[i], err);
        if (!s) done++;
    }
    progress_end(bar);
    bkf_io_table *t = NULL;
    if (!s) {
        t = bkf_io_table_alloc(out, p->m.format, check_columns, CHECK_NCOLUMNS, err);
        if (!t) s = BKF_ENOMEM;
    }
    if (!s)
        s = bkf_io_table_comment(t, CLI_PROGRAM " " CLI_VERSION " check: predicted front speeds "
                                    "against seeded simulations", err);
    if (!s) s = comment_model(t, &p->m, err);
    if (!s)
        s = commentf(t, err, "frame: %s", p->lab ? "lab" : "moving with v_pred of each root");
    if (!s)
        s = commentf(t, err,
                     "tmax %s, perturbation rms %s (seed %lu), agreement asked %s, grid %s: "
                     "uniform %zu .. %zu (resolution %.0e, samples every %s), adapted %zu points "
                     "per wavelength (tol %.0e, samples every %g)",
                     num(p->m.tmax, a, sizeof a), num(p->perturb, b, sizeof b), p->m.seed,
                     num(p->rel_tol, c, sizeof c),
                     p->grid == 0 ? "auto" : p->grid == 1 ? "uniform" : "mapped", p->m.params.N,
                     p->grid == 0 && p->N_max > AUTO_UNIFORM_MAX ? (size_t)AUTO_UNIFORM_MAX
                                                                  : p->N_max,
                     p->resolution, num(CHECK_SAMPLE_DT, d, sizeof d), p->points, p->mapped_tol,
                     CHECK_MAPPED_SAMPLE_DT);
    if (!s)
        s = commentf(t, err, "speeds: k(nu) %s, n_max %ld, %zu roots%s%s",
                     num(tab.k, f, sizeof f), tab.n_max, tab.count, tab.note[0] ? "; " : "",
                     tab.note);
    if (!s) s = comment_command(t, argc, argv, err);
    size_t stable = 0, agree = 0, unres = 0;
    *disagree = 0;
    for (size_t i = 0; i < tab.count; i++) {
        stable += rows[i].stable == 1;
        agree += rows[i].verdict && strcmp(rows[i].verdict, "agrees") == 0;
        unres += rows[i].verdict && strcmp(rows[i].verdict, "unresolved") == 0;
        *disagree += rows[i].verdict && strcmp(rows[i].verdict, "disagrees") == 0;
    }
    if (!s) {
        char list[512] = "";
        for (size_t i = 0; i < tab.count; i++)
            if (rows[i].stable == 1) {
                size_t used = strlen(list);
                snprintf(list + used, sizeof list - used, "%s%zu", used ? ", " : "", rows[i].n);
            }
        s = commentf(t, err, "summary: %zu stable (n = %s), %zu agree, %d disagree, %zu unresolved",
                     stable, stable ? list : "none", agree, *disagree, unres);
    }
    for (size_t i = 0; !s && i < tab.count; i++) {
        const check_row *r = &rows[i];
        bkf_io_value v[CHECK_NCOLUMNS] = {
            {.number = (double)r->n},   {.number = (double)r->root}, {.text = r->grid},
            {.number = (double)r->N},
            {.number = r->tail},        {.number = r->v_pred},      {.number = r->v_pred_err},   {.number = r->v_meas},
            {.number = r->v_meas_err},  {.number = r->rel_err},      {.number = r->fit_from},
            {.number = r->fit_to},      {.number = r->fronts_start}, {.number = r->fronts_end},
            {.number = r->dev_start},   {.number = r->dev_mid},      {.number = r->dev_end},
            {.number = r->growth},      {.number = r->stable},       {.text = r->verdict},
        };
        s = bkf_io_table_row(t, v, err);
    }
    if (!s) s = bkf_io_table_finish(t, err);
    bkf_io_table_free(t);
    free(rows);
    bkf_speeds_table_free(&tab);
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
                             "--rel-tol %g (see the table)", disagree, plan.rel_tol);
    return s;
}

const cli_command cli_cmd_check = {
    "check",
    "predicted front speeds against seeded simulations: agreement and stability per n",
    check_run,
    check_help,
};


/* The check of the predicted front speeds against seeded simulations: one
 * root at a time on the uniform spectral grid (bkf_pde + bkf_measure) or the
 * adapted comoving grid (bkf_comoving), both judged by bkf_check_judge. */
#include "bkfront/check.h"

#include <fftw3.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bkfront/chainwave.h"
#include "bkfront/comoving.h"
#include "bkfront/cycle.h"
#include "bkfront/measure.h"
#include "bkfront/seed.h"
#include "bkfront/speeds.h"
#include "bkfront/stability.h"
#include "bkfront/fft.h"

const char *bkf_check_verdict_name(bkf_check_verdict verdict)
{
    switch (verdict) {
    case BKF_CHECK_AGREES: return "agrees";
    case BKF_CHECK_DISAGREES: return "disagrees";
    case BKF_CHECK_UNSTABLE: return "unstable";
    case BKF_CHECK_UNRESOLVED: return "unresolved";
    case BKF_CHECK_CONFLICTS: return "conflicts";
    case BKF_CHECK_UNDECIDED: return "undecided";
    }
    return "unknown";
}

const char *bkf_check_growth_name(bkf_check_growth_verdict verdict)
{
    switch (verdict) {
    case BKF_CHECK_GROWTH_UNDECIDED: return "undecided";
    case BKF_CHECK_GROWTH_GROWS: return "grows";
    case BKF_CHECK_GROWTH_DECAYS: return "decays";
    }
    return "unknown";
}

const char *bkf_check_grid_name(bkf_check_grid grid)
{
    switch (grid) {
    case BKF_CHECK_GRID_AUTO: return "auto";
    case BKF_CHECK_GRID_UNIFORM: return "uniform";
    case BKF_CHECK_GRID_MAPPED: return "mapped";
    case BKF_CHECK_GRID_CHAIN: return "chain";
    }
    return "unknown";
}

bkf_check_options bkf_check_options_default(void)
{
    bkf_pde_options po = bkf_pde_options_default();
    return (bkf_check_options){
        .n = 0,
        .N = BKF_CHECK_N_DEFAULT,
        .N_max = BKF_CHECK_N_MAX_DEFAULT,
        .tmax = BKF_CHECK_TMAX_DEFAULT,
        .stepper = BKF_PDE_ETDRK4,
        .tol = 0,
        .filter = po.filter,
        .rel_tol = BKF_CHECK_REL_TOL_DEFAULT,
        .perturb = BKF_CHECK_PERTURB_DEFAULT,
        .seed = 1,
        .frame = BKF_CHECK_FRAME_MOVING,
        .grid = BKF_CHECK_GRID_AUTO,
        .points = BKF_CHECK_POINTS_DEFAULT,
        .mapped_tol = 0,
        .mapped_max_steps = BKF_CHECK_MAPPED_MAX_STEPS,
        .resolution = BKF_CHECK_RESOLUTION_DEFAULT,
    };
}

/* The tolerances in effect (0 stands for the defaults). */
static double uniform_tol(const bkf_check_options *o)
{
    if (o->tol) return o->tol;
    return o->stepper == BKF_PDE_ETDRK4 ? BKF_CHECK_ETD_TOL_DEFAULT : BKF_CHECK_RK_TOL_DEFAULT;
}

static double mapped_tol(const bkf_check_options *o)
{
    if (o->mapped_tol) return o->mapped_tol;
    return o->tol ? o->tol : BKF_CHECK_MAPPED_TOL_DEFAULT;
}

static int tol_ok(double tol) { return tol == 0 || (tol >= BKF_PDE_TOL_MIN && tol <= BKF_PDE_TOL_MAX); }

int bkf_check_validate(const bkf_model_params *model, const bkf_check_options *o, bkf_error *err)
{
    if (!model || !o) return bkf_error_set(err, BKF_EINPUT, "model and options must not be NULL");
    bkf_error e;
    if (!(model->gamma >= BKF_CYCLE_MU_MIN && model->gamma <= BKF_CYCLE_MU_MAX))
        return bkf_error_set(err, BKF_EINPUT, "gamma: %g is outside [%g, %g]", model->gamma,
                             BKF_CYCLE_MU_MIN, BKF_CYCLE_MU_MAX);
    if (!(model->c >= 0 && model->c <= BKF_MODEL_C_MAX))
        return bkf_error_set(err, BKF_EINPUT, "c: %g is outside [0, %g]", model->c,
                             BKF_MODEL_C_MAX);
    if (bkf_model_check_nu_active(model->nu, &e))
        return bkf_error_set(err, BKF_EINPUT, "%s; there are no fronts", e.message);
    if (bkf_model_check_positive("S", model->S, err)) return BKF_EINPUT;
    if (model->kind == BKF_MODEL_CHAIN) {
        bkf_chainwave_options co = bkf_chainwave_options_default();
        co.tol = BKF_CHECK_CHAIN_WAVE_TOL;
        if (bkf_chainwave_check(model, o->n ? o->n : 1, &co, err)) return BKF_EINPUT;
    } else if (model->kind != BKF_MODEL_CONTINUUM) {
        return bkf_error_set(err, BKF_EINPUT, "model: %d is not continuum or chain",
                             (int)model->kind);
    }
    if (o->n > BKF_CHECK_FRONTS_MAX)
        return bkf_error_set(err, BKF_EINPUT, "n: %zu is outside [1, %d] (0: every n)", o->n,
                             BKF_CHECK_FRONTS_MAX);
    if (o->N < BKF_PDE_N_MIN || o->N > BKF_PDE_N_MAX || o->N % 2)
        return bkf_error_set(err, BKF_EINPUT, "N: %zu is not an even integer in [%d, %d]", o->N,
                             BKF_PDE_N_MIN, BKF_PDE_N_MAX);
    if (o->N_max < o->N || o->N_max > BKF_PDE_N_MAX)
        return bkf_error_set(err, BKF_EINPUT, "N_max: %zu is outside [N = %zu, %d]", o->N_max,
                             o->N, BKF_PDE_N_MAX);
    if (!(o->tmax > 0 && o->tmax <= BKF_CHECK_TMAX_MAX))
        return bkf_error_set(err, BKF_EINPUT, "tmax: %g is outside (0, %g]", o->tmax,
                             BKF_CHECK_TMAX_MAX);
    if ((unsigned)o->stepper > BKF_PDE_LAWSON8)
        return bkf_error_set(err, BKF_EINPUT, "stepper: %d is not a bkf_pde_stepper",
                             (int)o->stepper);
    if (!tol_ok(o->tol))
        return bkf_error_set(err, BKF_EINPUT, "tol: %g is outside [%g, %g] (0: the default)",
                             o->tol, BKF_PDE_TOL_MIN, BKF_PDE_TOL_MAX);
    if (!(o->filter >= 0 && o->filter <= BKF_CHECK_FILTER_MAX))
        return bkf_error_set(err, BKF_EINPUT, "filter: %g is outside [0, %g]", o->filter,
                             BKF_CHECK_FILTER_MAX);
    if (!(o->rel_tol > 0 && o->rel_tol < 1))
        return bkf_error_set(err, BKF_EINPUT, "rel_tol: %g is outside (0, 1)", o->rel_tol);
    if (!(o->perturb >= 0 && o->perturb <= BKF_CHECK_PERTURB_MAX))
        return bkf_error_set(err, BKF_EINPUT, "perturb: %g is outside [0, %g]", o->perturb,
                             BKF_CHECK_PERTURB_MAX);
    if ((unsigned)o->frame > BKF_CHECK_FRAME_LAB)
        return bkf_error_set(err, BKF_EINPUT, "frame: %d is not a bkf_check_frame", (int)o->frame);
    if ((unsigned)o->grid > BKF_CHECK_GRID_MAPPED)
        return bkf_error_set(err, BKF_EINPUT, "grid: %d is not a bkf_check_grid", (int)o->grid);
    if (o->grid == BKF_CHECK_GRID_MAPPED && o->frame == BKF_CHECK_FRAME_LAB)
        return bkf_error_set(err, BKF_EINPUT,
                             "frame: lab is not available with grid mapped (the adapted grid "
                             "moves with v_pred)");
    if (o->points < BKF_CHECK_POINTS_MIN || o->points > BKF_CHECK_POINTS_MAX)
        return bkf_error_set(err, BKF_EINPUT, "points: %zu is outside [%d, %d]", o->points,
                             BKF_CHECK_POINTS_MIN, BKF_CHECK_POINTS_MAX);
    if (!tol_ok(o->mapped_tol))
        return bkf_error_set(err, BKF_EINPUT,
                             "mapped_tol: %g is outside [%g, %g] (0: the default)", o->mapped_tol,
                             BKF_PDE_TOL_MIN, BKF_PDE_TOL_MAX);
    if (!(o->resolution >= BKF_CHECK_RESOLUTION_MIN && o->resolution <= 1))
        return bkf_error_set(err, BKF_EINPUT, "resolution: %g is outside [%g, 1]", o->resolution,
                             BKF_CHECK_RESOLUTION_MIN);
    return BKF_OK;
}

bkf_check_verdict bkf_check_judge(size_t n, int blew_up, int count_constant, size_t fronts_start,
                                  double deviation_end, const bkf_check_growth *growth,
                                  bkf_trainspec_verdict spectral, double sigma_max, double rel_err,
                                  double rel_tol, int *stable)
{
    int kept = !blew_up && count_constant && fronts_start == n && isfinite(deviation_end) &&
               deviation_end <= 1e-2 && growth->verdict != BKF_CHECK_GROWTH_GROWS;
    if (stable) *stable = kept;
    if (bkf_check_conflict(growth, spectral, sigma_max)) return BKF_CHECK_CONFLICTS;
    if (!kept || spectral == BKF_TRAINSPEC_UNSTABLE) return BKF_CHECK_UNSTABLE;
    /* kept is not stable: a growth below the run's detection limit is
     * unseen, so stability needs the spectrum's word or a decided decay */
    if (spectral != BKF_TRAINSPEC_STABLE && growth->verdict != BKF_CHECK_GROWTH_DECAYS)
        return BKF_CHECK_UNDECIDED;
    if (!isfinite(rel_err)) return BKF_CHECK_UNDECIDED;
    return fabs(rel_err) <= rel_tol ? BKF_CHECK_AGREES : BKF_CHECK_DISAGREES;
}

/* Student's t at 6 degrees of freedom, two-sided 95% (2.447), rounded up. */
#define GROWTH_T95 2.5

/* Least-squares slope of ln y against t over m points, *se its standard
 * error from the residuals. */
static double ls_slope(const double *t, const double *y, size_t m, double *se)
{
    double mt = 0, my = 0;
    for (size_t k = 0; k < m; k++) {
        mt += t[k] / (double)m;
        my += log(y[k]) / (double)m;
    }
    double stt = 0, sty = 0;
    for (size_t k = 0; k < m; k++) {
        stt += (t[k] - mt) * (t[k] - mt);
        sty += (t[k] - mt) * (log(y[k]) - my);
    }
    double slope = sty / stt, rss = 0;
    for (size_t k = 0; k < m; k++) {
        double r = log(y[k]) - my - slope * (t[k] - mt);
        rss += r * r;
    }
    *se = m > 2 ? sqrt(rss / (double)(m - 2) / stt) : NAN;
    return slope;
}

void bkf_check_fit_growth(const double *t, const double *a, size_t count, double t_from,
                          double t_to, bkf_check_growth *g)
{
    *g = (bkf_check_growth){NAN, NAN, NAN, t_from, t_to, BKF_CHECK_GROWTH_UNDECIDED};
    enum { W = BKF_CHECK_GROWTH_WINDOWS };
    double env[W], tc[W];
    size_t in[W] = {0};
    double first = NAN, last = NAN;
    for (size_t i = 0; i < count; i++) {
        if (!(t[i] >= t_from && t[i] <= t_to)) continue;
        if (!(a[i] > 0 && isfinite(a[i]))) return;
        if (isnan(first)) first = t[i];
        last = t[i];
    }
    double L = last - first;
    if (!(L > 0)) return;
    double w = L / W;
    for (size_t i = 0; i < count; i++) {
        if (!(t[i] >= first && t[i] <= last)) continue;
        size_t k = (size_t)((t[i] - first) / w);
        if (k >= W) k = W - 1;
        env[k] = in[k]++ ? fmax(env[k], a[i]) : a[i];
    }
    for (size_t k = 0; k < W; k++) {
        if (in[k] < 2) return;
        tc[k] = first + (k + 0.5) * w;
    }
    double se, rate = ls_slope(tc, env, W, &se);
    /* an envelope not yet a single exponential (a slower mode still fading)
     * bends: the two halves' slopes differ, as much uncertainty as noise */
    double se_half, bend = ls_slope(tc, env, W / 2, &se_half) -
                           ls_slope(tc + W / 2, env + W / 2, W / 2, &se_half);
    g->rate = rate;
    g->rate_err = sqrt(se * se + 0.25 * bend * bend);
    g->limit = fmax(GROWTH_T95 * g->rate_err, log(2.0) / L);
    g->from = first;
    g->to = last;
    g->verdict = rate > g->limit    ? BKF_CHECK_GROWTH_GROWS
                 : rate < -g->limit ? BKF_CHECK_GROWTH_DECAYS
                                    : BKF_CHECK_GROWTH_UNDECIDED;
}

int bkf_check_conflict(const bkf_check_growth *g, bkf_trainspec_verdict spectral, double sigma_max)
{
    if (g->verdict == BKF_CHECK_GROWTH_GROWS) return spectral == BKF_TRAINSPEC_STABLE;
    if (g->verdict == BKF_CHECK_GROWTH_DECAYS)
        return spectral == BKF_TRAINSPEC_UNSTABLE && sigma_max > g->limit;
    return 0;
}

/* Several fits of one run into one: the largest rate, grows when any
 * grows, decays when every one decays. */
static void growth_merge(bkf_check_growth *into, const bkf_check_growth *g, int first)
{
    if (first) {
        *into = *g;
        return;
    }
    bkf_check_growth_verdict v =
        into->verdict == BKF_CHECK_GROWTH_GROWS || g->verdict == BKF_CHECK_GROWTH_GROWS
            ? BKF_CHECK_GROWTH_GROWS
        : into->verdict == BKF_CHECK_GROWTH_DECAYS && g->verdict == BKF_CHECK_GROWTH_DECAYS
            ? BKF_CHECK_GROWTH_DECAYS
            : BKF_CHECK_GROWTH_UNDECIDED;
    /* the reported fit: a growing one when the run grows, the fastest */
    int g_grows = g->verdict == BKF_CHECK_GROWTH_GROWS,
        into_grows = into->verdict == BKF_CHECK_GROWTH_GROWS;
    if (g_grows > into_grows || (g_grows == into_grows && (isnan(into->rate) || g->rate > into->rate)))
        *into = *g;
    into->verdict = v;
}

/* The spacing of a run's samples: `base`, or tmax / BKF_CHECK_SAMPLES_MAX
 * when that is longer, so that the records a run keeps (measurements,
 * Bloch classes, the chain's phases) do not grow with tmax (check --n 4 at
 * the paper's parameters: 15.8 MB at tmax 2e3, 42.6 MB at 4e4 with every
 * 0.25 kept).  Up to tmax = 1024 (the default 125 included) nothing
 * changes; beyond, the fits see as many samples as at tmax 1024. */
static double sample_dt(double base, double tmax) { return fmax(base, tmax / BKF_CHECK_SAMPLES_MAX); }

/* The whole run's state shared by the roots. */
typedef struct {
    const bkf_model_params *model;
    const bkf_check_options *o;
    const bkf_check_hooks *hooks;
    double tol, mapped_tol, level;
    size_t root_index, roots; /* progress: this root's share of the whole */
} check_ctx;

static int check_progress(double fraction, void *data)
{
    const check_ctx *c = data;
    if (c->hooks && c->hooks->progress)
        c->hooks->progress(((double)c->root_index + fraction) / (double)c->roots, c->hooks->data);
    return 0;
}

static const volatile sig_atomic_t *check_cancel(const check_ctx *c)
{
    return c->hooks ? c->hooks->cancel : NULL;
}

static void check_warn(const check_ctx *c, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));
static void check_warn(const check_ctx *c, const char *fmt, ...)
{
    if (!c->hooks || !c->hooks->warning) return;
    char line[BKF_ERROR_LEN + 128];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    c->hooks->warning(line, c->hooks->data);
}

/* The end of the coherent part of a run: the last record, from the start
 * on, whose count is n and whose deviation is below the bound (see
 * check.h); with `settle` the bound rises to 10 times the largest deviation
 * up to t_ref = min(10, tmax/4), the wave's response to the noise: a wave
 * the grid does not fully resolve settles into the grid's own travelling
 * wave (a plateau set by the resolution, not a growing perturbation), and
 * steep fronts amplify the noise before it decays (gamma 6, c 0.1,
 * nu -0.99, S 40, n 2: perturbation 1e-6, deviation 2.4e-4 at t = 6, back
 * to 2e-5 by t = 10; a bound of 1e-4 ended the coherent part at t = 1.5 and
 * left a stable front without a speed).  `at(i, data, &t, &fronts,
 * &deviation)` reads record i of R. */
static double transient_end(double tmax) { return fmin(10.0, 0.25 * tmax); }

typedef void (*record_reader)(size_t i, const void *data, double *t, size_t *fronts,
                              double *deviation);

static size_t coherent_end(record_reader at, const void *data, size_t R, size_t n, int settle,
                           double bound, double tmax)
{
    double t_ref = transient_end(tmax), t, dev;
    size_t fronts, end = 0;
    for (size_t r = 0; settle && r < R; r++) {
        at(r, data, &t, &fronts, &dev);
        if (fronts != n || !isfinite(dev)) break;
        bound = fmax(bound, 10 * dev);
        if (t >= t_ref) break;
    }
    for (size_t r = 0; r < R; r++) {
        at(r, data, &t, &fronts, &dev);
        if (fronts != n || !(dev <= bound)) break;
        end = r;
    }
    return end;
}

/* The deviation up to which the speed is fitted, and up to which the
 * perturbation is taken as linear (its growth fitted; at the default
 * perturbation three decades of growth). */
static double speed_bound(const bkf_check_options *o) { return fmax(100 * o->perturb, 1e-6); }
static double linear_bound(const bkf_check_options *o) { return fmax(10 * o->perturb, 1e-3); }

/* The growth of the deviation over the linear part of the run: from the
 * end of the transient, t = min(10, tmax/4), to the end of the coherent
 * part under linear_bound.  *t_to gets that end (for the Bloch classes). */
static int fit_deviation(record_reader at, const void *data, size_t R, size_t n,
                         const bkf_check_options *o, bkf_check_growth *g, double *t_to)
{
    double *t = malloc((R + 1) * sizeof *t), *d = malloc((R + 1) * sizeof *d);
    if (!t || !d) {
        free(t);
        free(d);
        return BKF_ENOMEM;
    }
    size_t fronts;
    for (size_t r = 0; r < R; r++) at(r, data, &t[r], &fronts, &d[r]);
    size_t end = R ? coherent_end(at, data, R, n, 0, linear_bound(o), o->tmax) : 0;
    *t_to = R ? t[end] : 0;
    bkf_check_fit_growth(t, d, R, transient_end(o->tmax), *t_to, g);
    free(t);
    free(d);
    return BKF_OK;
}

/* A speed fit needs this many coherent records past the first. */
#define FIT_MIN_RECORDS 6

static void measure_reader(size_t i, const void *data, double *t, size_t *fronts, double *dev)
{
    const bkf_measure_record *rc = bkf_measure_record_at(data, i);
    *t = rc->t;
    *fronts = rc->fronts;
    *dev = rc->deviation;
}

static void comoving_reader(size_t i, const void *data, double *t, size_t *fronts, double *dev)
{
    const bkf_comoving_record *rc = bkf_comoving_record_at(data, i);
    *t = rc->t;
    *fronts = rc->fronts;
    *dev = rc->deviation;
}

static bkf_comoving_params mapped_params(const check_ctx *c, const bkf_speeds_root *sr, size_t n,
                                         size_t points)
{
    const bkf_check_options *o = c->o;
    bkf_comoving_params cp = bkf_comoving_params_default();
    cp.model = *c->model;
    cp.n = n;
    cp.v = sr->v;
    cp.points = points;
    cp.tol = c->mapped_tol;
    cp.noise = o->perturb;
    cp.seed = o->seed;
    cp.cancel = check_cancel(c);
    cp.max_steps = o->mapped_max_steps;
    cp.level = c->level;
    return cp;
}

/* The adapted grid's own error in the speed: the same run (same noise, as
 * a function of x) on 2/3 of the points, fitted over the same window; the
 * difference of the two drifts.  Not divided by an assumed order: the
 * grid's wave converges at order 4 to 8 before its floor (gamma 5, c 0.2,
 * nu -0.9, S 50, n 20: errors 2.3e-7, 3.9e-8, 7.0e-9, 3.0e-10 on 512, 768,
 * 1024, 1536 points), so the coarser grid's error is at least twice the
 * finer one's and the difference covers the finer one's (4.9 times
 * there).  A difference taken with a finer grid would not (0.8 times).
 * NaN when the coarser run cannot give a drift over that window. */
static double mapped_grid_error(const check_ctx *c, const bkf_speeds_root *sr, size_t n,
                                double drift, double t_from, double t_to, int *status)
{
    size_t points = 2 * c->o->points / 3;
    if (points < BKF_CHECK_POINTS_MIN) points = BKF_CHECK_POINTS_MIN;
    bkf_comoving_params cp = mapped_params(c, sr, n, points);
    bkf_error e;
    bkf_comoving *cm = bkf_comoving_alloc(&cp, &e);
    *status = BKF_OK;
    if (!cm) {
        if (e.status == BKF_ENOMEM) *status = BKF_ENOMEM;
        return NAN;
    }
    double coarse = NAN, coarse_err;
    int s = bkf_comoving_run(cm, t_to, sample_dt(BKF_CHECK_MAPPED_SAMPLE_DT, c->o->tmax), NULL,
                             NULL, &e);
    if (s == BKF_ECANCELED || s == BKF_ENOMEM) *status = s;
    if (!s && bkf_comoving_fit_drift(cm, t_from, t_to, &coarse, &coarse_err, &e) != BKF_OK)
        coarse = NAN;
    bkf_comoving_free(cm);
    return fabs(drift - coarse);
}

/* One root on the adapted comoving grid. */
static int check_root_mapped(const check_ctx *c, const bkf_speeds_root *sr, bkf_check_row *row,
                             bkf_error *err)
{
    const bkf_check_options *o = c->o;
    row->grid = BKF_CHECK_GRID_MAPPED;
    bkf_comoving_params cp = mapped_params(c, sr, row->n, o->points);
    bkf_error e;
    bkf_comoving *cm = bkf_comoving_alloc(&cp, &e);
    if (!cm) {
        /* Out of memory ends the check, any other failure is this root's
         * alone. */
        if (e.status == BKF_ENOMEM)
            return bkf_error_set(err, BKF_ENOMEM, "n = %zu: out of memory", row->n);
        check_warn(c, "n = %zu, root %zu reported unresolved: %s", row->n, row->root, e.message);
        row->verdict = BKF_CHECK_UNRESOLVED;
        row->reason = e.status;
        return BKF_OK;
    }
    row->N = bkf_comoving_size(cm);
    bkf_comoving_stats st;
    bkf_comoving_get_stats(cm, &st);
    row->tail = st.relax_change;
    int s = bkf_comoving_run(cm, o->tmax, sample_dt(BKF_CHECK_MAPPED_SAMPLE_DT, o->tmax),
                             check_progress, (void *)c, &e);
    bkf_comoving_get_stats(cm, &st);
    size_t R = bkf_comoving_count(cm);
    int blew_up = s == BKF_EBLOWUP && R >= 2;
    if (blew_up) s = BKF_OK; /* a blown-up front is a result (unstable) */
    if (s == BKF_EBUDGET) {
        /* not a verdict: the run was too costly to finish */
        bkf_comoving_free(cm);
        row->verdict = BKF_CHECK_UNRESOLVED;
        row->reason = BKF_EBUDGET;
        return BKF_OK;
    }
    if (s) {
        bkf_comoving_free(cm);
        return bkf_error_set(err, s, "n = %zu, root %zu, adapted grid of %zu points: %s", row->n,
                             row->root, row->N, e.message);
    }
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
    row->deviation_start = first->deviation;
    row->deviation_mid = mid->deviation;
    row->deviation_end = last->deviation;
    double t_lin;
    if (fit_deviation(comoving_reader, cm, R, row->n, o, &row->growth, &t_lin)) {
        bkf_comoving_free(cm);
        return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    }
    /* the relaxed wave's own deviation plateau counts as coherent */
    size_t end = coherent_end(comoving_reader, cm, R, row->n, 1, speed_bound(o), o->tmax);
    double t_end = bkf_comoving_record_at(cm, end)->t;
    if (end >= FIT_MIN_RECORDS) {
        double drift, drift_err;
        if (bkf_comoving_fit_drift(cm, 0.5 * t_end, t_end, &drift, &drift_err, &e) == BKF_OK) {
            /* The fit's uncertainty is that of the simulated field; the
             * grid's own error in the speed is added to it. */
            int gs;
            double grid_err = mapped_grid_error(c, sr, row->n, drift, 0.5 * t_end, t_end, &gs);
            if (gs) {
                bkf_comoving_free(cm);
                return bkf_error_set(err, gs, "n = %zu, root %zu: %s", row->n, row->root,
                                     gs == BKF_ENOMEM ? "out of memory" : "canceled");
            }
            if (isnan(grid_err))
                check_warn(c, "n = %zu, root %zu: the run on %zu points per wavelength gives no "
                           "speed to compare with: v_meas_err is unknown (nan)", row->n,
                           row->root, 2 * o->points / 3);
            /* the frame moves with the fronts towards -x at v_pred */
            row->v_meas = sr->v - drift;
            row->v_meas_err = drift_err + grid_err;
            row->rel_err = -drift / sr->v;
            row->fit_from = 0.5 * t_end;
            row->fit_to = t_end;
        }
    }
    int stable;
    row->verdict = bkf_check_judge(row->n, blew_up, constant, first->fronts, row->deviation_end,
                                   &row->growth, row->spectral, row->sigma_max, row->rel_err,
                                   o->rel_tol, &stable);
    row->stable = stable;
    if (blew_up) row->reason = BKF_EBLOWUP;
    bkf_comoving_free(cm);
    return BKF_OK;
}

/* The Bloch classes of psi on the uniform grid: for j = 1 .. n/2 the rms
 * of the Fourier coefficients at k = +-j mod n (0 < |k| < N/2), the
 * perturbation's part of Bloch number 2 pi j / S (see check.h), one row
 * of `classes` values per sample. */
typedef struct {
    size_t N, n, classes;
    double *in;
    fftw_complex *out;
    fftw_plan plan;
    double *t, *amp;
    size_t count, cap;
} bloch_classes;

static int bloch_init(bloch_classes *b, size_t N, size_t n)
{
    memset(b, 0, sizeof *b);
    b->N = N;
    b->n = n;
    b->classes = n / 2;
    if (!b->classes) return BKF_OK;
    b->in = fftw_malloc(N * sizeof *b->in);
    b->out = fftw_malloc((N / 2 + 1) * sizeof *b->out);
    if (!b->in || !b->out) return BKF_ENOMEM;
    bkf_fft_lock();
    b->plan = fftw_plan_dft_r2c_1d((int)N, b->in, b->out, FFTW_ESTIMATE);
    bkf_fft_unlock();
    return b->plan ? BKF_OK : BKF_ENOMEM;
}

static void bloch_free(bloch_classes *b)
{
    bkf_fft_lock();
    if (b->plan) fftw_destroy_plan(b->plan);
    bkf_fft_unlock();
    fftw_free(b->in);
    fftw_free(b->out);
    free(b->t);
    free(b->amp);
}

static int bloch_add(bloch_classes *b, double t, const double *psi)
{
    if (!b->classes) return BKF_OK;
    if (b->count == b->cap) {
        size_t cap = b->cap ? 2 * b->cap : 512;
        double *nt = realloc(b->t, cap * sizeof *nt);
        if (!nt) return BKF_ENOMEM;
        b->t = nt;
        double *na = realloc(b->amp, cap * b->classes * sizeof *na);
        if (!na) return BKF_ENOMEM;
        b->amp = na;
        b->cap = cap;
    }
    memcpy(b->in, psi, b->N * sizeof *psi);
    fftw_execute(b->plan);
    double *a = b->amp + b->count * b->classes;
    for (size_t j = 0; j < b->classes; j++) a[j] = 0;
    for (size_t k = 1; k < b->N / 2; k++) {
        size_t r = k % b->n, j = r < b->n - r ? r : b->n - r;
        if (j) a[j - 1] += b->out[k][0] * b->out[k][0] + b->out[k][1] * b->out[k][1];
    }
    for (size_t j = 0; j < b->classes; j++) a[j] = sqrt(2 * a[j]) / (double)b->N;
    b->t[b->count++] = t;
    return BKF_OK;
}

/* Each class's growth over [t_from, t_to], merged into *g. */
static int bloch_fit(const bloch_classes *b, double t_from, double t_to, bkf_check_growth *g)
{
    if (!b->classes) return BKF_OK;
    double *a = malloc(b->count * sizeof *a);
    if (!a) return BKF_ENOMEM;
    for (size_t j = 0; j < b->classes; j++) {
        for (size_t r = 0; r < b->count; r++) a[r] = b->amp[r * b->classes + j];
        bkf_check_growth gj;
        bkf_check_fit_growth(b->t, a, b->count, t_from, t_to, &gj);
        growth_merge(g, &gj, 0);
    }
    free(a);
    return BKF_OK;
}

typedef struct {
    bkf_measure *meas;
    bloch_classes *bloch;
    int status;
    bkf_error err;
} check_obs;

static int check_observe(const bkf_pde_sample *smp, void *data)
{
    check_obs *ob = data;
    bkf_error e;
    if (bkf_measure_add(ob->meas, smp->t, smp->psi, smp->eta, &e)) {
        ob->status = bkf_error_set(&ob->err, BKF_ENUMERIC, "measurement at t = %g: %s", smp->t,
                                   e.message);
        return 1;
    }
    if (bloch_add(ob->bloch, smp->t, smp->psi)) {
        ob->status = bkf_error_set(&ob->err, BKF_ENOMEM, "out of memory");
        return 1;
    }
    return 0;
}

/* One root: the grid that resolves it, the perturbed run, its
 * measurements. */
static int check_root(const check_ctx *c, const bkf_speeds_root *sr, bkf_check_row *row,
                      bkf_error *err)
{
    const bkf_check_options *o = c->o;
    size_t n = row->n, root = row->root;
    if (o->grid == BKF_CHECK_GRID_MAPPED) return check_root_mapped(c, sr, row, err);
    bkf_model_params pp = *c->model;
    pp.kind = BKF_MODEL_CONTINUUM;
    bkf_pde_options po = bkf_pde_options_default();
    po.tol = c->tol;
    po.stepper = o->stepper;
    po.filter = o->filter;
    po.cancel = check_cancel(c);
    /* The seeded fronts move towards -x at v_pred: in that frame the wave is
     * a steady state and the steps grow to the stability cap. */
    po.frame_speed = o->frame == BKF_CHECK_FRAME_LAB ? 0.0 : -sr->v;
    bkf_pde_front_spec fs = bkf_pde_front_spec_default();
    fs.n = n;
    fs.root = root;
    fs.noise = o->perturb;
    fs.seed = o->seed;
    bkf_error e;
    bkf_pde *pde = NULL;
    double *clean = NULL;
    bkf_measure *meas = NULL;
    bloch_classes bloch;
    memset(&bloch, 0, sizeof bloch);
    bkf_pde_front_info fi;
    int s = BKF_OK;
    row->grid = BKF_CHECK_GRID_UNIFORM;
    size_t N_cap = o->N_max;
    if (o->grid == BKF_CHECK_GRID_AUTO && N_cap > BKF_CHECK_AUTO_UNIFORM_MAX)
        N_cap = BKF_CHECK_AUTO_UNIFORM_MAX;
    for (size_t N = o->N;; N *= 2) {
        if (N > N_cap) {
            bkf_pde_free(pde);
            free(clean);
            if (o->grid == BKF_CHECK_GRID_AUTO) return check_root_mapped(c, sr, row, err);
            row->verdict = BKF_CHECK_UNRESOLVED;
            row->reason = BKF_ETOL;
            return BKF_OK;
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
        if ((s = bkf_seed_front(pde, &fs, &fi, clean, &e))) {
            bkf_error_set(err, s, "n = %zu, root %zu: %s", n, root, e.message);
            goto done;
        }
        row->tail = bkf_pde_spectral_tail(pde, clean);
        if (row->tail <= o->resolution) break;
    }
    row->N = pp.N;
    bkf_measure_params mp = bkf_measure_params_default();
    mp.model = pp;
    mp.reference = clean;
    mp.level = c->level;
    mp.frame_speed = po.frame_speed;
    if (!(meas = bkf_measure_alloc(&mp, err))) {
        s = BKF_ENOMEM;
        goto done;
    }
    if ((s = bloch_init(&bloch, pp.N, n))) {
        bkf_error_set(err, s, "out of memory");
        goto done;
    }
    check_obs ob = {meas, &bloch, 0, {{0}, 0}};
    s = bkf_pde_run(pde, o->tmax, sample_dt(BKF_CHECK_SAMPLE_DT, o->tmax), check_observe, &ob,
                    check_progress,
                    (void *)c, &e);
    if (ob.status) {
        s = ob.status;
        *err = ob.err;
        goto done;
    }
    /* A blown-up front is a result (unstable), not a failure of the check.
     * bkf_pde reports a blow-up, like a step size underflow in the blow-up's
     * run-up, as BKF_ENUMERIC (no stats field tells them apart): both count,
     * once the run has recorded a start to compare with. */
    int blew_up = (s == BKF_EBLOWUP || s == BKF_ENUMERIC) && bkf_measure_count(meas) >= 2;
    if (blew_up) s = BKF_OK;
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
    row->deviation_start = ms.deviation_start;
    row->deviation_mid = ms.deviation_mid;
    row->deviation_end = ms.deviation_end;
    double t_lin;
    size_t R = bkf_measure_count(meas);
    if ((s = fit_deviation(measure_reader, meas, R, n, o, &row->growth, &t_lin)) ||
        (s = bloch_fit(&bloch, transient_end(o->tmax), t_lin, &row->growth))) {
        bkf_error_set(err, s, "out of memory");
        goto done;
    }
    size_t last = coherent_end(measure_reader, meas, R, n, 1, speed_bound(o), o->tmax);
    double t_end = bkf_measure_record_at(meas, last)->t;
    if (last >= FIT_MIN_RECORDS) {
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
    int stable;
    row->verdict = bkf_check_judge(n, blew_up, ms.count_constant, ms.fronts_start,
                                   ms.deviation_end, &row->growth, row->spectral, row->sigma_max,
                                   row->rel_err, o->rel_tol, &stable);
    row->stable = stable;
    if (blew_up) row->reason = BKF_EBLOWUP;
done:
    bloch_free(&bloch);
    bkf_measure_free(meas);
    bkf_pde_free(pde);
    free(clean);
    return s;
}

static void row_init(bkf_check_row *row, size_t n, size_t root, const bkf_speeds_root *sr)
{
    memset(row, 0, sizeof *row);
    row->n = n;
    row->root = root;
    row->v_pred = sr->v;
    row->v_pred_err = sr->v_err;
    row->v_meas = row->v_meas_err = row->rel_err = row->fit_from = row->fit_to = NAN;
    row->tail = NAN;
    row->fronts_start = row->fronts_end = NAN;
    row->deviation_start = row->deviation_mid = row->deviation_end = NAN;
    bkf_check_fit_growth(NULL, NULL, 0, 0, 0, &row->growth);
    row->spectral = BKF_TRAINSPEC_UNRESOLVED;
    row->sigma_max = row->sigma_max_err = NAN;
    row->stable = NAN;
    row->decide_tmax = NAN;
    row->verdict = BKF_CHECK_UNRESOLVED;
    row->reason = BKF_OK;
}

/* The spectrum's answer as the verdict reads it: decided stable, decided
 * unstable, or not decided (UNRESOLVED) with a reason.  A sigma_max that
 * is only the window's edge (window_edge finite, bkf_trainspec_shown_of)
 * is no eigenvalue, so not printed; nor trusted here, as the other products
 * trust it: the bound was once wrong (gamma 4.06339, c 0.276186,
 * nu 0.959575, S 27.1676, n 1: edge -0.203, Hill's method -4.08e-4), and
 * check's run judges anyway. */
static void spectrum_of(const check_ctx *c, bkf_check_row *row, int status, const char *why,
                        bkf_trainspec_verdict verdict, double sigma_max, double sigma_max_err,
                        double window_edge)
{
    if (status != BKF_OK) {
        check_warn(c, "n = %zu, root %zu: spectrum refused: %s", row->n, row->root, why);
        return;
    }
    if (isfinite(window_edge)) {
        char note[200];
        check_warn(c, "n = %zu, root %zu: spectrum not trusted: %s", row->n, row->root,
                   bkf_trainspec_bound_note(window_edge, note, sizeof note));
        return;
    }
    row->spectral = verdict;
    row->sigma_max = sigma_max;
    row->sigma_max_err = sigma_max_err;
}

/* The spectrum of the root's train, at trainspec's default accuracy (1e-6
 * on sigma, far below any rate a run resolves); a refusal leaves the row's
 * spectrum unresolved, with a warning: the run still judges. */
static void check_spectrum(const check_ctx *c, const bkf_speeds_root *sr, bkf_check_row *row)
{
    bkf_model_params p = *c->model;
    p.kind = BKF_MODEL_CONTINUUM;
    bkf_trainspec_result res;
    bkf_error e;
    int s = bkf_trainspec_root(&p, sr, bkf_trainspec_options_default().tol, 1, &res, &e);
    bkf_trainspec_shown shown = bkf_trainspec_shown_of(&res);
    if (s) spectrum_of(c, row, s, e.message, BKF_TRAINSPEC_UNRESOLVED, NAN, NAN, NAN);
    else spectrum_of(c, row, s, "", res.verdict, shown.sigma_max, shown.sigma_max_err, shown.bound);
    bkf_trainspec_result_free(&res);
}

/* What would decide an undecided row (check.h: decide_tmax), into the row
 * and a warning.  The rate in question is the growth the spectrum allows
 * (sigma_max + its error) when it gives one, else the run's own |growth|;
 * the fit's detection limit falls about as 1/L (its ln 2 / L term exactly,
 * the slope's standard error at least as fast), so a fit L limit / rate
 * long resolves it. */
static void explain_undecided(const check_ctx *c, bkf_check_row *row)
{
    if (row->verdict != BKF_CHECK_UNDECIDED) return;
    const bkf_check_growth *g = &row->growth;
    int stable = row->spectral == BKF_TRAINSPEC_STABLE || g->verdict == BKF_CHECK_GROWTH_DECAYS;
    if (stable) {
        check_warn(c, "n = %zu, root %zu: undecided: stable, but no speed measured (the coherent "
                   "part of the run, count n and deviation within bound, is too short to fit); "
                   "a smaller --perturb keeps it longer", row->n, row->root);
        return;
    }
    int spectral = isfinite(row->sigma_max);
    double rate = spectral ? row->sigma_max + row->sigma_max_err : fabs(g->rate);
    double L = g->to - g->from;
    if (rate > 0 && L > 0 && g->limit > 0) {
        double t = g->from + L * g->limit / rate;
        if (t <= BKF_CHECK_TMAX_MAX) row->decide_tmax = ceil(t);
    }
    const char *what = spectral ? "the spectrum's sigma_max is within its error of 0"
                                : "the spectrum was refused";
    if (!isfinite(g->rate)) {
        check_warn(c, "n = %zu, root %zu: undecided: %s and the run's growth was not fitted "
                   "(its linear part has too few samples); a spectrum decided beyond its "
                   "error, or a longer run, would decide", row->n, row->root, what);
        return;
    }
    if (isfinite(row->decide_tmax))
        check_warn(c, "n = %zu, root %zu: undecided: %s and the run's growth is within its "
                   "detection limit %.2g; a run of tmax %.0f would resolve a growth of %.2g",
                   row->n, row->root, what, g->limit, row->decide_tmax, rate);
    else
        check_warn(c, "n = %zu, root %zu: undecided: %s and the run's growth is within its "
                   "detection limit %.2g; no run up to tmax %g resolves a growth of %.2g: only "
                   "a spectrum decided beyond its error would", row->n, row->root, what,
                   g->limit, BKF_CHECK_TMAX_MAX, rate);
}

/* ------------------------------------------------------------ the chain */

/* The run sampled at the shift times m tau (see check.h): the phase the
 * fronts gained, the deviation orthogonal to it, the front count. */
typedef struct {
    size_t N, cap, count;
    double tau, nu;
    const double *u0, *f0; /* the wave and the field at it (2N values) */
    double ff;             /* |f0|^2 */
    double *t, *phase, *dev;
    size_t *fronts;
    int oom;
} chain_obs;

/* Rising crossings of nu around the ring. */
static size_t chain_fronts(const double *psi, size_t N, double nu)
{
    size_t count = 0;
    for (size_t i = 0; i < N; i++)
        count += psi[i] < nu && psi[(i + 1) % N] >= nu;
    return count;
}

static int chain_observe(const bkf_pde_sample *smp, void *data)
{
    chain_obs *ob = data;
    size_t N = ob->N;
    if (ob->count == ob->cap) {
        size_t cap = ob->cap ? 2 * ob->cap : 256;
        double *t = realloc(ob->t, cap * sizeof *t);
        if (t) ob->t = t;
        double *ph = realloc(ob->phase, cap * sizeof *ph);
        if (ph) ob->phase = ph;
        double *d = realloc(ob->dev, cap * sizeof *d);
        if (d) ob->dev = d;
        size_t *fr = realloc(ob->fronts, cap * sizeof *fr);
        if (fr) ob->fronts = fr;
        if (!t || !ph || !d || !fr) return ob->oom = 1;
        ob->cap = cap;
    }
    size_t m = (size_t)llround(smp->t / ob->tau) % N;
    /* W_m: block i is block i + m of the start (both fields) */
    double dot = 0.0;
    for (size_t k = 0; k < 2 * N; k++) {
        size_t j = (k < N ? 0 : N) + (k % N + m) % N;
        double u = k < N ? smp->psi[k] : smp->eta[k - N];
        dot += (u - ob->u0[j]) * ob->f0[j];
    }
    double delta = dot / ob->ff, dev = 0.0;
    for (size_t k = 0; k < 2 * N; k++) {
        size_t j = (k < N ? 0 : N) + (k % N + m) % N;
        double u = k < N ? smp->psi[k] : smp->eta[k - N];
        dev = fmax(dev, fabs(u - ob->u0[j] - delta * ob->f0[j]));
    }
    size_t r = ob->count++;
    ob->t[r] = smp->t;
    ob->phase[r] = delta;
    ob->dev[r] = isfinite(dev) ? dev : INFINITY;
    ob->fronts[r] = chain_fronts(smp->psi, N, ob->nu);
    return 0;
}

static void chain_reader(size_t i, const void *data, double *t, size_t *fronts, double *dev)
{
    const chain_obs *ob = data;
    *t = ob->t[i];
    *fronts = ob->fronts[i];
    *dev = ob->dev[i];
}

/* The sample nearest to time t. */
static size_t chain_sample_at(const chain_obs *ob, double t)
{
    size_t best = 0;
    for (size_t r = 1; r < ob->count; r++)
        if (fabs(ob->t[r] - t) < fabs(ob->t[best] - t)) best = r;
    return best;
}

static int check_chain_wave(const check_ctx *c, const bkf_chainwave *w, bkf_check_row *row,
                            bkf_error *err)
{
    const bkf_check_options *o = c->o;
    const bkf_model_params *p = c->model;
    size_t N = p->N, n = w->n;
    bkf_pde_options po = bkf_pde_options_default();
    po.tol = o->tol ? o->tol : BKF_CHECK_CHAIN_RUN_TOL;
    po.stepper = BKF_PDE_RK8PD;
    po.filter = 0;
    po.cancel = check_cancel(c);
    double *f0 = malloc(2 * N * sizeof *f0), *u0 = malloc(2 * N * sizeof *u0);
    chain_obs ob = {N, 0, 0, w->tau, p->nu, u0, f0, 0.0, NULL, NULL, NULL, NULL, 0};
    bkf_pde *pde = NULL;
    int s = (f0 && u0) ? BKF_OK : bkf_error_set(err, BKF_ENOMEM, "out of memory");
    if (!s) {
        double K = p->c * p->c * (double)(N * N) / (p->S * p->S);
        memcpy(u0, w->psi, N * sizeof *u0);
        memcpy(u0 + N, w->eta, N * sizeof *u0);
        for (size_t i = 0; i < N; i++) {
            double x = w->psi[i];
            double lap = w->psi[(i + 1) % N] - 2.0 * x + w->psi[(i + N - 1) % N];
            f0[i] = p->gamma * (w->eta[i] - bkf_model_friction(x));
            f0[N + i] = -(x - p->nu - K * lap) / p->gamma;
        }
        for (size_t k = 0; k < 2 * N; k++) ob.ff += f0[k] * f0[k];
        pde = bkf_pde_alloc(p, &po, err);
        if (!pde) s = BKF_ENOMEM;
    }
    bkf_error e;
    if (!s) s = bkf_pde_set_state(pde, w->psi, w->eta, 0.0, err);
    if (!s) s = bkf_pde_add_noise(pde, o->perturb, o->seed, err);
    /* the run ends on a shift time, the last sample with it; samples at
     * every k-th shift time (k = 1 up to tmax = 1024 tau) */
    double dt = w->tau * ceil(sample_dt(w->tau, o->tmax) / w->tau - 1e-9);
    double t_end = ceil(o->tmax / dt - 1e-9) * dt;
    if (!s) {
        s = bkf_pde_run(pde, t_end, dt, chain_observe, &ob, check_progress, (void *)c, &e);
        if (ob.oom) s = bkf_error_set(err, BKF_ENOMEM, "out of memory");
    }
    int blew_up = (s == BKF_EBLOWUP || s == BKF_ENUMERIC) && ob.count >= 2;
    if (blew_up) s = BKF_OK;
    if (s == BKF_ECANCELED) bkf_error_set(err, s, "canceled");
    else if (s && !ob.oom && pde)
        bkf_error_set(err, s, "n = %zu, chain of %zu blocks: %s", n, N, e.message);
    if (!s && ob.count) {
        int constant = 1;
        for (size_t r = 1; r < ob.count; r++) constant &= ob.fronts[r] == ob.fronts[0];
        row->fronts_start = (double)ob.fronts[0];
        row->fronts_end = (double)ob.fronts[ob.count - 1];
        row->deviation_start = ob.dev[0];
        row->deviation_mid = ob.dev[chain_sample_at(&ob, 0.5 * t_end)];
        row->deviation_end = ob.dev[ob.count - 1];
        double t_lin;
        /* the count a rotating wave keeps is its own (a coarse chain shows
           n fronts as n crossings only where they are wider than a block) */
        size_t n_seen = ob.fronts[0];
        if ((s = fit_deviation(chain_reader, &ob, ob.count, n_seen, o, &row->growth, &t_lin)))
            bkf_error_set(err, s, "out of memory");
        size_t last = coherent_end(chain_reader, &ob, ob.count, n_seen, 1, speed_bound(o), o->tmax);
        size_t first = chain_sample_at(&ob, 0.5 * ob.t[last]);
        if (!s && last >= FIT_MIN_RECORDS && last - first >= 2) {
            double mt = 0, mp = 0, stt = 0, stp = 0, rss = 0;
            size_t m = last - first + 1;
            for (size_t r = first; r <= last; r++) mt += ob.t[r] / (double)m, mp += ob.phase[r] / (double)m;
            for (size_t r = first; r <= last; r++) {
                stt += (ob.t[r] - mt) * (ob.t[r] - mt);
                stp += (ob.t[r] - mt) * (ob.phase[r] - mp);
            }
            double slope = stp / stt;
            for (size_t r = first; r <= last; r++) {
                double d = ob.phase[r] - mp - slope * (ob.t[r] - mt);
                rss += d * d;
            }
            /* u(t) = W(t + delta(t)): the fronts run at v (1 + d delta/dt) */
            row->v_meas = w->v * (1.0 + slope);
            row->v_meas_err = w->v * sqrt(rss / (double)(m - 2) / stt);
            row->rel_err = slope;
            row->fit_from = ob.t[first];
            row->fit_to = ob.t[last];
        }
        if (!s) {
            int stable;
            row->verdict = bkf_check_judge(n_seen, blew_up, constant, n_seen, row->deviation_end,
                                           &row->growth, row->spectral, row->sigma_max,
                                           row->rel_err, o->rel_tol, &stable);
            row->stable = stable;
            if (blew_up) row->reason = BKF_EBLOWUP;
        }
    }
    bkf_pde_free(pde);
    free(f0);
    free(u0);
    free(ob.t);
    free(ob.phase);
    free(ob.dev);
    free(ob.fronts);
    return s;
}

static bkf_trainspec_verdict chain_spectral(bkf_chainwave_verdict v)
{
    switch (v) {
    case BKF_CHAINWAVE_STABLE: return BKF_TRAINSPEC_STABLE;
    case BKF_CHAINWAVE_UNSTABLE: return BKF_TRAINSPEC_UNSTABLE;
    default: return BKF_TRAINSPEC_UNRESOLVED;
    }
}

static int check_chain_run(const bkf_model_params *model, const bkf_check_options *o,
                           const bkf_check_hooks *hooks, bkf_error *err)
{
    bkf_chainwave_options co = bkf_chainwave_options_default();
    co.tol = BKF_CHECK_CHAIN_WAVE_TOL;
    bkf_chainwave_table tab;
    bkf_error e;
    int s = bkf_chainwave_find(model, o->n ? o->n : 1, o->n, &co, &tab, &e);
    if (s) {
        bkf_chainwave_table_free(&tab);
        return bkf_error_set(err, s, "the chain's waves: %s", e.message);
    }
    check_ctx c = {model, o, hooks, o->tol ? o->tol : BKF_CHECK_CHAIN_RUN_TOL, NAN, 0, 0,
                   tab.count};
    bkf_check_info info = {tab.count, NAN, (long)(o->n ? o->n : model->N / 2), tab.note, c.tol,
                           NAN, model->N};
    int stop = hooks && hooks->begin ? hooks->begin(&info, hooks->data) : 0;
    const volatile sig_atomic_t *cancel = check_cancel(&c);
    for (size_t i = 0; !s && !stop && i < tab.count; i++) {
        if (cancel && *cancel) {
            s = bkf_error_set(err, BKF_ECANCELED, "canceled after %zu of %zu waves", i,
                              tab.count);
            break;
        }
        const bkf_chainwave *w = &tab.waves[i];
        size_t root = 1;
        for (size_t k = i; k > 0 && tab.waves[k - 1].n == w->n; k--) root++;
        bkf_check_row row;
        bkf_speeds_root sr = {0};
        sr.v = w->v;
        sr.v_err = w->v_err;
        row_init(&row, w->n, root, &sr);
        row.grid = BKF_CHECK_GRID_CHAIN;
        row.N = model->N;
        row.tail = w->residual;
        row.spectral = chain_spectral(w->verdict);
        row.sigma_max = w->sigma_max;
        row.sigma_max_err = w->sigma_max_err;
        c.root_index = i;
        s = check_chain_wave(&c, w, &row, err);
        if (!s && row.verdict == BKF_CHECK_CONFLICTS)
            check_warn(&c, "n = %zu, wave %zu: the simulation's perturbation %s at %.3g +- %.3g "
                       "per unit time, the multipliers say %s (|m| %.9g)", row.n, row.root,
                       bkf_check_growth_name(row.growth.verdict), row.growth.rate,
                       row.growth.rate_err, bkf_chainwave_verdict_name(w->verdict), w->mult_abs);
        if (!s) explain_undecided(&c, &row);
        if (!s && hooks && hooks->row) stop = hooks->row(&row, hooks->data);
    }
    bkf_chainwave_table_free(&tab);
    return s;
}

int bkf_check_run(const bkf_model_params *model, const bkf_check_options *o,
                  const bkf_check_hooks *hooks, bkf_error *err)
{
    int s = bkf_check_validate(model, o, err);
    if (s) return s;
    if (model->kind == BKF_MODEL_CHAIN) return check_chain_run(model, o, hooks, err);
    bkf_model_params sp = {model->gamma, model->c, model->nu, model->S, 0, BKF_MODEL_CONTINUUM};
    bkf_speeds_options so = bkf_speeds_options_default();
    so.tol = 1e-12;
    if (o->n) so.n_from = so.n_to = o->n;
    bkf_speeds_table tab;
    memset(&tab, 0, sizeof tab);
    bkf_error e;
    if ((s = bkf_speeds_find(&sp, &so, &tab, &e))) {
        bkf_speeds_table_free(&tab);
        return bkf_error_set(err, s, "speeds: %s", e.message);
    }
    check_ctx c = {model, o, hooks, uniform_tol(o), mapped_tol(o), 0, 0, tab.count};
    c.level = bkf_measure_front_level(model, NULL);
    bkf_check_info info = {tab.count, tab.k, tab.n_max, tab.note, c.tol, c.mapped_tol,
                           o->grid == BKF_CHECK_GRID_AUTO && o->N_max > BKF_CHECK_AUTO_UNIFORM_MAX
                               ? (size_t)BKF_CHECK_AUTO_UNIFORM_MAX
                               : o->N_max};
    int stop = hooks && hooks->begin ? hooks->begin(&info, hooks->data) : 0;
    const volatile sig_atomic_t *cancel = check_cancel(&c);
    for (size_t i = 0; !s && !stop && i < tab.count; i++) {
        if (cancel && *cancel) {
            s = bkf_error_set(err, BKF_ECANCELED, "canceled after %zu of %zu roots", i, tab.count);
            break;
        }
        size_t root = 1;
        for (size_t k = i; k > 0 && tab.roots[k - 1].n == tab.roots[i].n; k--) root++;
        bkf_check_row row;
        row_init(&row, tab.roots[i].n, root, &tab.roots[i]);
        c.root_index = i;
        check_spectrum(&c, &tab.roots[i], &row);
        s = check_root(&c, &tab.roots[i], &row, err);
        if (!s && row.verdict == BKF_CHECK_CONFLICTS) {
            char a[32], b[32], d[32], f[32];
            check_warn(&c,
                       "n = %zu, root %zu: the simulation's perturbation %s at %s +- %s per unit "
                       "time, the spectrum says %s (sigma_max %s +- %s)",
                       row.n, row.root, bkf_check_growth_name(row.growth.verdict),
                       bkf_format_number(row.growth.rate, a, sizeof a),
                       bkf_format_number(row.growth.rate_err, b, sizeof b),
                       row.spectral == BKF_TRAINSPEC_STABLE ? "stable" : "unstable",
                       bkf_format_number(row.sigma_max, d, sizeof d),
                       bkf_format_number(row.sigma_max_err, f, sizeof f));
        }
        if (!s) explain_undecided(&c, &row);
        if (!s && hooks && hooks->row) stop = hooks->row(&row, hooks->data);
    }
    bkf_speeds_table_free(&tab);
    return s;
}

/* ------------------------------------------------------------ the product */

/* The choices are read and written as int: the enums must be int-sized. */
_Static_assert(sizeof(bkf_pde_stepper) == sizeof(int), "bkf_pde_stepper is not int-sized");
_Static_assert(sizeof(bkf_check_frame) == sizeof(int), "bkf_check_frame is not int-sized");
_Static_assert(sizeof(bkf_check_grid) == sizeof(int), "bkf_check_grid is not int-sized");

/* Indexed by bkf_check_frame and bkf_check_grid (the steppers'
 * names: bkf_pde_stepper_names). */
static const char *const frame_names[] = {"moving", "lab", NULL};
static const char *const grid_names[] = {"auto", "uniform", "mapped", NULL};
static const char *const model_names[] = {"continuum", "chain", NULL};
_Static_assert(sizeof(bkf_model_kind) == sizeof(int), "bkf_model_kind is not int-sized");

/* The seed is an unsigned long: up to 19 digits always fit. */
static int set_seed(void *spec, const char *text, bkf_error *err)
{
    char shown[72];
    if (!*text || strspn(text, "0123456789") != strlen(text) || strlen(text) > 19)
        return bkf_error_set(err, BKF_EINPUT, "'%s' is not an integer in [0, 1e19)",
                             bkf_option_shown(text, shown, sizeof shown));
    unsigned long long v = strtoull(text, NULL, 10);
    if (v > ULONG_MAX)
        return bkf_error_set(err, BKF_EINPUT, "'%s' is out of range", text);
    ((bkf_check_spec *)spec)->options.seed = (unsigned long)v;
    return BKF_OK;
}

#define MODEL(f) (offsetof(bkf_check_spec, model) + offsetof(bkf_model_params, f))
#define OPT(f) (offsetof(bkf_check_spec, options) + offsetof(bkf_check_options, f))
#define BOUNDED (BKF_OPT_MIN | BKF_OPT_MAX)

const bkf_option bkf_check_keys[] = {
    {.name = "gamma", .type = BKF_OPT_DOUBLE, .offset = MODEL(gamma), .flags = BOUNDED,
     .min = BKF_CYCLE_MU_MIN, .max = BKF_CYCLE_MU_MAX, .form = "G", .shown_default = "2",
     .help = "friction strength, in [1e-06, 1e+06]"},
    {.name = "c", .type = BKF_OPT_DOUBLE, .offset = MODEL(c), .flags = BKF_OPT_MIN | BKF_OPT_MAX,
     .min = 0, .max = BKF_MODEL_C_MAX, .form = "C", .shown_default = "0.3",
     .help = "sound speed, in [0, 1e6]"},
    {.name = "nu", .type = BKF_OPT_DOUBLE, .offset = MODEL(nu),
     .flags = BOUNDED | BKF_OPT_MIN_OPEN | BKF_OPT_MAX_OPEN, .min = -1, .max = 1, .form = "V",
     .shown_default = "-0.96", .help = "pulling rate, in (-1, 1): no fronts beyond"},
    {.name = "S", .type = BKF_OPT_DOUBLE, .offset = MODEL(S),
     .flags = BKF_OPT_MIN | BKF_OPT_MIN_OPEN, .min = 0, .form = "S", .shown_default = "20",
     .help = "system size, > 0"},
    {.name = "model", .type = BKF_OPT_CHOICE, .offset = MODEL(kind), .choices = model_names,
     .form = "continuum|chain", .shown_default = "continuum",
     .help = "chain: the chain of --N blocks (spacing h = S/N), its own\n"
             "rotating waves (bkfront speeds --model chain) seeded and\n"
             "simulated on the blocks; columns as below (docs/cli/check.md)"},
    {.name = "n", .type = BKF_OPT_COUNT, .offset = OPT(n), .flags = BOUNDED, .min = 1,
     .max = BKF_CHECK_FRONTS_MAX, .form = "K",
     .help = "check n = K only; default every n with a root"},
    {.name = "N", .type = BKF_OPT_COUNT, .offset = OPT(N), .flags = BOUNDED,
     .min = BKF_PDE_N_MIN, .max = BKF_PDE_N_MAX, .form = "N", .shown_default = "512",
     .help = "smallest grid, even; each root runs on the smallest\n"
             "N = N 2^k that resolves its wave (Fourier coefficients\n"
             "above N/3 below --resolution of the largest); with\n"
             "--model chain: blocks, in [2, 400], default S (whole)"},
    {.name = "N-max", .type = BKF_OPT_COUNT, .offset = OPT(N_max), .flags = BOUNDED,
     .min = BKF_PDE_N_MIN, .max = BKF_PDE_N_MAX, .form = "M", .shown_default = "65536",
     .help = "largest grid, >= --N; roots needing more are reported\n"
             "unresolved and not simulated"},
    {.name = "tmax", .type = BKF_OPT_DOUBLE, .offset = OPT(tmax),
     .flags = BOUNDED | BKF_OPT_MIN_OPEN, .min = 0, .max = BKF_CHECK_TMAX_MAX, .form = "T",
     .shown_default = "125", .help = "length of each run, in (0, 1e+06]"},
    {.name = "tol", .type = BKF_OPT_DOUBLE, .offset = OPT(tol), .flags = BOUNDED,
     .min = BKF_PDE_TOL_MIN, .max = BKF_PDE_TOL_MAX, .form = "E",
     .help = "local error tolerance, in [1e-13, 0.01]; default 1e-07\n"
             "with etdrk4, 1e-9 with the Runge-Kutta steppers, 1e-08\n"
             "on the adapted grid"},
    {.name = "filter", .type = BKF_OPT_DOUBLE, .offset = OPT(filter), .flags = BOUNDED,
     .min = 0, .max = BKF_CHECK_FILTER_MAX, .form = "F", .shown_default = "4",
     .help = "spectral filter, as in bkfront simulate,\nin [0, 1000]"},
    {.name = "stepper", .type = BKF_OPT_CHOICE, .offset = OPT(stepper), .choices = bkf_pde_stepper_names,
     .form = "S", .shown_default = "etdrk4",
     .help = "etdrk4 (exponential, the wave part of every mode exact,\n"
             "steps set by the physics), lawson8 (the same with rk8pd's\n"
             "order 8), or rk8pd, rkck, rkf45 (explicit, steps capped by\n"
             "the fastest mode ~ 1/N)"},
    {.name = "rel-tol", .type = BKF_OPT_DOUBLE, .offset = OPT(rel_tol),
     .flags = BOUNDED | BKF_OPT_MIN_OPEN | BKF_OPT_MAX_OPEN, .min = 0, .max = 1, .form = "R",
     .shown_default = "1e-06",
     .help = "agreement asked of a stable front,\n"
             "|v_meas - v_pred| / v_pred, in (0, 1)"},
    {.name = "perturb", .type = BKF_OPT_DOUBLE, .offset = OPT(perturb), .flags = BOUNDED,
     .min = 0, .max = BKF_CHECK_PERTURB_MAX, .form = "A", .shown_default = "1e-06",
     .help = "rms of the band-limited noise added to the seeded wave,\n"
             "in [0, 0.1]"},
    {.name = "seed", .type = BKF_OPT_CUSTOM, .set = set_seed, .form = "K",
     .shown_default = "1", .help = "seed of that noise, an integer in [0, 1e19)"},
    {.name = "frame", .type = BKF_OPT_CHOICE, .offset = OPT(frame), .choices = frame_names,
     .form = "lab|moving", .shown_default = "moving",
     .help = "simulate in the frame moving with v_pred, where the seeded\n"
             "wave is a steady state, or in the lab frame (uniform\n"
             "grid only)"},
    {.name = "grid", .type = BKF_OPT_CHOICE, .offset = OPT(grid), .choices = grid_names,
     .form = "G", .shown_default = "auto",
     .help = "auto: the uniform spectral grid when it resolves the wave\n"
             "on N <= 8192, else the adapted grid; uniform: always the\n"
             "spectral grid (up to --N-max); mapped: always the adapted\n"
             "grid (finite differences of order 8 on points placed by\n"
             "the wave's own length scales, in the frame of v_pred,\n"
             "CVODE in time; docs/cli/check.md)"},
    {.name = "points", .type = BKF_OPT_COUNT, .offset = OPT(points), .flags = BOUNDED,
     .min = BKF_CHECK_POINTS_MIN, .max = BKF_CHECK_POINTS_MAX, .form = "M",
     .shown_default = "768", .help = "adapted grid: points per wavelength,\nin [32, 1048576]"},
    {.name = "resolution", .type = BKF_OPT_DOUBLE, .offset = OPT(resolution), .flags = BOUNDED,
     .min = BKF_CHECK_RESOLUTION_MIN, .max = 1, .form = "R", .shown_default = "1e-05",
     .help = "the spectral tail accepted as resolved,\nin [1e-16, 1]"},
    {.name = "mapped-tol", .type = BKF_OPT_DOUBLE, .offset = OPT(mapped_tol),
     .flags = BOUNDED, .min = BKF_PDE_TOL_MIN, .max = BKF_PDE_TOL_MAX,
     .form = "E",
     .help = "adapted grid: CVODE's tolerance, in [1e-13, 0.01];\ndefault tol if given, else 1e-08"},
    {.name = "mapped-max-steps", .type = BKF_OPT_COUNT, .offset = OPT(mapped_max_steps),
     .form = "I", .shown_default = "20000",
     .help = "adapted grid: step budget per root (beyond: unresolved)"},
};
const size_t bkf_check_nkeys = sizeof bkf_check_keys / sizeof bkf_check_keys[0];

#undef MODEL
#undef OPT
#undef BOUNDED

bkf_check_spec bkf_check_spec_default(void)
{
    bkf_check_spec s;
    memset(&s, 0, sizeof s);
    s.model = bkf_model_params_paper();
    s.options = bkf_check_options_default();
    return s;
}

/* The model the spec runs: the chain's blocks from the key N (S by default). */
static int spec_model(const bkf_check_spec *spec, const char *p, bkf_model_params *model,
                      bkf_error *err)
{
    *model = spec->model;
    if (model->kind != BKF_MODEL_CHAIN) return BKF_OK;
    size_t N = spec->options.N;
    if (N == BKF_CHECK_N_DEFAULT) {
        double S = model->S;
        if (!(S >= BKF_CHAINWAVE_N_MIN && S <= BKF_CHAINWAVE_N_MAX && S == floor(S)))
            return bkf_error_set(err, BKF_EINPUT, "%sN: the number of blocks, in [%d, %d], is "
                                 "needed with %smodel chain (the default, S = %g, is not one)",
                                 p, BKF_CHAINWAVE_N_MIN, BKF_CHAINWAVE_N_MAX, p, S);
        N = (size_t)S;
    }
    model->N = N;
    return BKF_OK;
}

int bkf_check_spec_check(const bkf_check_spec *spec, const char *prefix, bkf_error *err)
{
    const char *p = prefix ? prefix : "";
    if (!spec) return bkf_error_set(err, BKF_EINPUT, "no spec given");
    const bkf_check_options *o = &spec->options;
    if (spec->model.kind == BKF_MODEL_CHAIN) {
        bkf_model_params m;
        bkf_error e;
        int s = spec_model(spec, p, &m, err);
        if (s) return s;
        bkf_check_options oc = *o;
        oc.N = BKF_CHECK_N_DEFAULT; /* the grid's N: the chain uses its blocks */
        if (bkf_check_validate(&m, &oc, &e))
            return bkf_error_set(err, BKF_EINPUT, "%s%s", p, e.message);
        return BKF_OK;
    }
    if (o->N % 2)
        return bkf_error_set(err, BKF_EINPUT,
                             "%sN: %zu must be even for the continuum model (spectral)", p, o->N);
    if (o->N_max < o->N)
        return bkf_error_set(err, BKF_EINPUT, "%sN-max: %zu is below %sN = %zu", p, o->N_max, p,
                             o->N);
    if (o->grid == BKF_CHECK_GRID_MAPPED && o->frame == BKF_CHECK_FRAME_LAB)
        return bkf_error_set(err, BKF_EINPUT,
                             "%sframe: lab is not available with %sgrid mapped (the adapted grid "
                             "moves with v_pred)",
                             p, p);
    bkf_error e;
    if (bkf_check_validate(&spec->model, o, &e))
        return bkf_error_set(err, BKF_EINPUT, "%s%s", p, e.message);
    return BKF_OK;
}


static const bkf_io_column columns[] = {
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
    {"growth_err", BKF_IO_NUMBER},
    {"growth_limit", BKF_IO_NUMBER},
    {"growth_verdict", BKF_IO_TEXT},
    {"spectral", BKF_IO_TEXT},
    {"sigma_max", BKF_IO_NUMBER},
    {"sigma_max_err", BKF_IO_NUMBER},
    {"stable", BKF_IO_NUMBER},
    {"verdict", BKF_IO_TEXT},
    {"decide_tmax", BKF_IO_NUMBER},
};
#define NCOLUMNS (sizeof columns / sizeof columns[0])

/* The rows as they come, written once the run is done: the summary comment
 * needs them all. */
typedef struct {
    const bkf_check_hooks *hooks; /* the caller's, or NULL */
    bkf_check_row *rows;
    size_t count, cap;
    bkf_check_info info;
    char note[BKF_SPEEDS_NOTE_LEN];
    int failed; /* out of memory keeping a row */
} check_sink;

static int sink_begin(const bkf_check_info *info, void *data)
{
    check_sink *k = data;
    k->info = *info;
    snprintf(k->note, sizeof k->note, "%s", info->speeds_note);
    k->info.speeds_note = k->note;
    return k->hooks && k->hooks->begin ? k->hooks->begin(info, k->hooks->data) : 0;
}

static int sink_row(const bkf_check_row *row, void *data)
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
    return k->hooks && k->hooks->row ? k->hooks->row(row, k->hooks->data) : 0;
}

static void sink_progress(double fraction, void *data)
{
    const check_sink *k = data;
    k->hooks->progress(fraction, k->hooks->data);
}

static void sink_warning(const char *message, void *data)
{
    const check_sink *k = data;
    k->hooks->warning(message, k->hooks->data);
}


/* printf onto the end of the string in buf (truncated to size). */
static void append(char *buf, size_t size, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static void append(char *buf, size_t size, const char *fmt, ...)
{
    size_t used = strlen(buf);
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf + used, size - used, fmt, ap);
    va_end(ap);
}

/* "n1, n2, ..." of the rows that pass `keep`, into list. */
static void list_n(const check_sink *k, int (*keep)(const bkf_check_row *), char *list,
                   size_t size)
{
    list[0] = '\0';
    for (size_t i = 0; i < k->count; i++)
        if (keep(&k->rows[i])) {
            size_t used = strlen(list);
            snprintf(list + used, size - used, "%s%zu", used ? ", " : "", k->rows[i].n);
        }
}

static int row_stable(const bkf_check_row *r) { return r->stable == 1; }
static int row_disagrees(const bkf_check_row *r) { return r->verdict == BKF_CHECK_DISAGREES; }
static int row_conflicts(const bkf_check_row *r) { return r->verdict == BKF_CHECK_CONFLICTS; }
static int row_spectral_stable(const bkf_check_row *r)
{
    return r->spectral == BKF_TRAINSPEC_STABLE;
}
static int row_spectral_unstable(const bkf_check_row *r)
{
    return r->spectral == BKF_TRAINSPEC_UNSTABLE;
}

static int write_table(const check_sink *k, const bkf_model_params *m,
                       const bkf_check_options *o, FILE *out, bkf_io_format format,
                       const bkf_provenance *prov, bkf_error *err)
{
    int chain = m->kind == BKF_MODEL_CHAIN;
    char a[32], b[32], c[32], d[32], e[32], f[32], g[32];
    bkf_io_table *t = bkf_io_table_alloc(out, format, columns, NCOLUMNS, err);
    if (!t) return BKF_ENOMEM;
    int s = bkf_io_table_commentf(t, err, "%s check: predicted front speeds against seeded simulations",
                    prov && prov->program ? prov->program : "libbkfront");
    if (!s && chain)
        s = bkf_io_table_commentf(t, err,
                    "model chain: gamma %s, c %s, nu %s, S %s, N %zu blocks (h = %s); its "
                    "rotating waves (tol %.0e, multipliers) seeded on the blocks, run rk8pd tol "
                    "%s, sampled at every shift time tau",
                    bkf_format_number(m->gamma, a, sizeof a), bkf_format_number(m->c, b, sizeof b),
                    bkf_format_number(m->nu, c, sizeof c), bkf_format_number(m->S, d, sizeof d),
                    m->N, bkf_format_number(m->S / (double)m->N, e, sizeof e),
                    BKF_CHECK_CHAIN_WAVE_TOL, bkf_format_number(k->info.tol, f, sizeof f));
    if (!s && chain)
        s = bkf_io_table_commentf(t, err,
                    "tmax %s, perturbation rms %s (seed %lu), agreement asked %s; v_meas from "
                    "the phase the fronts gain, deviation orthogonal to it, spectral = the "
                    "multipliers' verdict, tail = the wave's Newton residual",
                    bkf_format_number(o->tmax, a, sizeof a), bkf_format_number(o->perturb, b, sizeof b),
                    o->seed, bkf_format_number(o->rel_tol, c, sizeof c));
    if (!s && chain)
        s = bkf_io_table_commentf(t, err, "waves: %zu (n <= %ld)%s%s", k->info.roots,
                    k->info.n_max, k->note[0] ? "; " : "", k->note);
    if (!s && !chain)
        s = bkf_io_table_commentf(t, err,
                    "model continuum: gamma %s, c %s, nu %s, S %s, N %zu (h = %s); tol %s, "
                    "stepper %s, dealias off, filter %s",
                    bkf_format_number(m->gamma, a, sizeof a), bkf_format_number(m->c, b, sizeof b), bkf_format_number(m->nu, c, sizeof c),
                    bkf_format_number(m->S, d, sizeof d), o->N, bkf_format_number(m->S / (double)o->N, e, sizeof e),
                    bkf_format_number(k->info.tol, f, sizeof f), bkf_pde_stepper_names[o->stepper],
                    o->filter == 0 ? "off" : bkf_format_number(o->filter, g, sizeof g));
    if (!s && !chain)
        s = bkf_io_table_commentf(t, err, "frame: %s",
                    o->frame == BKF_CHECK_FRAME_LAB ? "lab" : "moving with v_pred of each root");
    if (!s && !chain)
        s = bkf_io_table_commentf(t, err,
                    "tmax %s, perturbation rms %s (seed %lu), agreement asked %s, grid %s: "
                    "uniform %zu .. %zu (resolution %.0e, samples every %s), adapted %zu points "
                    "per wavelength (tol %.0e, samples every %g)",
                    bkf_format_number(o->tmax, a, sizeof a), bkf_format_number(o->perturb, b, sizeof b), o->seed,
                    bkf_format_number(o->rel_tol, c, sizeof c), bkf_check_grid_name(o->grid), o->N,
                    k->info.N_cap, o->resolution,
                    bkf_format_number(sample_dt(BKF_CHECK_SAMPLE_DT, o->tmax), d, sizeof d),
                    o->points, k->info.mapped_tol, sample_dt(BKF_CHECK_MAPPED_SAMPLE_DT, o->tmax));
    if (!s && !chain)
        s = bkf_io_table_commentf(t, err, "speeds: k(nu) %s, n_max %ld, %zu roots%s%s",
                    bkf_format_number(k->info.k, a, sizeof a), k->info.n_max, k->info.roots,
                    k->note[0] ? "; " : "", k->note);
    if (!s && prov && prov->command) s = bkf_io_table_commentf(t, err, "command: %s", prov->command);
    size_t stable = 0, agree = 0, unresolved = 0, disagree = 0, conflict = 0, undecided = 0;
    for (size_t i = 0; i < k->count; i++) {
        stable += k->rows[i].stable == 1;
        agree += k->rows[i].verdict == BKF_CHECK_AGREES;
        unresolved += k->rows[i].verdict == BKF_CHECK_UNRESOLVED;
        disagree += k->rows[i].verdict == BKF_CHECK_DISAGREES;
        conflict += k->rows[i].verdict == BKF_CHECK_CONFLICTS;
        undecided += k->rows[i].verdict == BKF_CHECK_UNDECIDED;
    }
    if (!s) {
        char list[512], yes[512], no[512];
        list_n(k, row_stable, list, sizeof list);
        list_n(k, row_spectral_stable, yes, sizeof yes);
        list_n(k, row_spectral_unstable, no, sizeof no);
        s = bkf_io_table_commentf(t, err,
                    "summary: %zu kept by the run (n = %s), %zu agree, %zu disagree, %zu "
                    "conflict, %zu undecided, %zu unresolved; spectrum stable n = %s, unstable "
                    "n = %s",
                    stable, stable ? list : "none", agree, disagree, conflict, undecided,
                    unresolved,
                    yes[0] ? yes : "none", no[0] ? no : "none");
    }
    for (size_t i = 0; !s && i < k->count; i++) {
        const bkf_check_row *r = &k->rows[i];
        bkf_io_value v[NCOLUMNS] = {
            {.number = (double)r->n},          {.number = (double)r->root},
            {.text = bkf_check_grid_name(r->grid)},
            {.number = (double)r->N},          {.number = r->tail},
            {.number = r->v_pred},             {.number = r->v_pred_err},
            {.number = r->v_meas},             {.number = r->v_meas_err},
            {.number = r->rel_err},            {.number = r->fit_from},
            {.number = r->fit_to},             {.number = r->fronts_start},
            {.number = r->fronts_end},         {.number = r->deviation_start},
            {.number = r->deviation_mid},      {.number = r->deviation_end},
            {.number = r->growth.rate},        {.number = r->growth.rate_err},
            {.number = r->growth.limit},
            {.text = bkf_check_growth_name(r->growth.verdict)},
            {.text = bkf_trainspec_verdict_name(r->spectral)},
            {.number = r->sigma_max},          {.number = r->sigma_max_err},
            {.number = r->stable},
            {.text = bkf_check_verdict_name(r->verdict)},
            {.number = r->decide_tmax},
        };
        s = bkf_io_table_row(t, v, err);
    }
    if (!s) s = bkf_io_table_finish(t, err);
    bkf_io_table_free(t);
    return s;
}

int bkf_check_write(const bkf_check_spec *spec, FILE *out, bkf_io_format format,
                    const bkf_provenance *prov, const bkf_check_hooks *hooks, size_t *disagree,
                    bkf_error *err)
{
    if (disagree) *disagree = 0;
    int s = bkf_check_spec_check(spec, "", err);
    if (s) return s;
    bkf_check_options o = spec->options;
    if (o.frame == BKF_CHECK_FRAME_LAB && o.grid == BKF_CHECK_GRID_AUTO)
        o.grid = BKF_CHECK_GRID_UNIFORM;
    check_sink k = {.hooks = hooks};
    bkf_check_hooks own = {.begin = sink_begin, .row = sink_row, .data = &k};
    if (hooks) {
        own.progress = hooks->progress ? sink_progress : NULL;
        own.warning = hooks->warning ? sink_warning : NULL;
        own.cancel = hooks->cancel;
    }
    bkf_model_params model;
    if ((s = spec_model(spec, "", &model, err))) return s;
    if (model.kind == BKF_MODEL_CHAIN) o.N = BKF_CHECK_N_DEFAULT;
    s = bkf_check_run(&model, &o, &own, err);
    if (!s && k.failed) s = bkf_error_set(err, BKF_ENOMEM, "out of memory");
    if (!s) s = write_table(&k, &model, &o, out, format, prov, err);
    size_t nd = 0, nc = 0;
    for (size_t i = 0; !s && i < k.count; i++) {
        nd += row_disagrees(&k.rows[i]);
        nc += row_conflicts(&k.rows[i]);
    }
    if (nd || nc) {
        char ld[512], lc[512], r[32], msg[BKF_ERROR_LEN] = "";
        list_n(&k, row_disagrees, ld, sizeof ld);
        list_n(&k, row_conflicts, lc, sizeof lc);
        if (disagree) *disagree = nd + nc;
        if (nd)
            append(msg, sizeof msg,
                   "%zu stable front(s) disagree with the predicted speed beyond rel-tol %s "
                   "(n = %s); ",
                   nd, bkf_format_number(o.rel_tol, r, sizeof r), ld);
        if (nc)
            append(msg, sizeof msg,
                   "%zu front(s) whose simulated growth contradicts the spectrum (n = %s); ", nc,
                   lc);
        s = bkf_error_set(err, BKF_ENUMERIC, "%ssee the table", msg);
    }
    free(k.rows);
    return s;
}

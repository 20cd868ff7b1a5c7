/* The check's verdicts (check.c): a run's records judged (the coherent
 * part, the speed and growth fits, agreement with the prediction), the row
 * a root starts from, and what would decide an undecided one.  Below the
 * continuum and chain runs (check_continuum.c, check_chain.c) and the
 * product (check.c), which call it; it calls none of them. */
#include "check_internal.h"

#include <fftw3.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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
        .runs = BKF_CHECK_RUNS_AUTO,
        .threads = 0,
    };
}

/* The tolerances in effect (0 stands for the defaults). */
double check_uniform_tol(const bkf_check_options *o)
{
    if (o->tol) return o->tol;
    return o->stepper == BKF_PDE_ETDRK4 ? BKF_CHECK_ETD_TOL_DEFAULT : BKF_CHECK_RK_TOL_DEFAULT;
}

double check_mapped_tol(const bkf_check_options *o)
{
    if (o->mapped_tol) return o->mapped_tol;
    return o->tol ? o->tol : BKF_CHECK_MAPPED_TOL_DEFAULT;
}

/* The accuracy asked of v_pred (relative, the speeds solver's tol): what
 * the verdict needs, a thousandth of the agreement asked, so that v_pred's
 * own error moves no |rel_err| across --rel-tol; the runs resolve far less
 * (v_meas_err / v 1e-8 .. 1e-10, the grids' tails 1e-5).  Asked at 1e-12,
 * the speeds solver refused roots it had to 1e-10 (27 of 185 at gamma
 * 0.567489, c 0.432606, nu 0.989398, S 59.5575: n = 46..72), and the check
 * left them unresolved.  Never looser than 1e-6 (a seed's period then
 * misses the domain by at most that, below the noise), nor tighter than
 * 1e-12. */
double check_speeds_tol(const bkf_check_options *o)
{
    return fmin(1e-6, fmax(1e-12, 1e-3 * o->rel_tol));
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
    if ((unsigned)o->runs > BKF_CHECK_RUNS_FULL)
        return bkf_error_set(err, BKF_EINPUT, "runs: %d is not a bkf_check_runs", (int)o->runs);
    if (o->threads > BKF_CHECK_THREADS_MAX)
        return bkf_error_set(err, BKF_EINPUT, "threads: %zu is outside [0, %d] (0: every core)",
                             o->threads, BKF_CHECK_THREADS_MAX);
    if (!(o->resolution >= BKF_CHECK_RESOLUTION_MIN && o->resolution <= 1))
        return bkf_error_set(err, BKF_EINPUT, "resolution: %g is outside [%g, 1]", o->resolution,
                             BKF_CHECK_RESOLUTION_MIN);
    return BKF_OK;
}

bkf_check_verdict bkf_check_judge(size_t n, int blew_up, int count_constant, size_t fronts_start,
                                  double deviation_end, const bkf_check_growth *growth,
                                  bkf_trainspec_verdict spectral, double sigma_max, double rel_err,
                                  double rel_tol, int *kept_out)
{
    int kept = !blew_up && count_constant && fronts_start == n && isfinite(deviation_end) &&
               deviation_end <= 1e-2 && growth->verdict != BKF_CHECK_GROWTH_GROWS;
    if (kept_out) *kept_out = kept;
    if (bkf_check_conflict(growth, spectral, sigma_max)) return BKF_CHECK_CONFLICTS;
    if (!kept || spectral == BKF_TRAINSPEC_UNSTABLE) return BKF_CHECK_UNSTABLE;
    /* kept is not stable: a growth below the run's detection limit is
     * unseen, so stability needs the spectrum's word or a decided decay */
    if (spectral != BKF_TRAINSPEC_STABLE && growth->verdict != BKF_CHECK_GROWTH_DECAYS)
        return BKF_CHECK_UNDECIDED;
    if (!isfinite(rel_err)) return BKF_CHECK_UNDECIDED;
    return fabs(rel_err) <= rel_tol ? BKF_CHECK_AGREES : BKF_CHECK_DISAGREES;
}

/* Student's t at 6 degrees of freedom, two-sided 95% (2.447), rounded up;
 * at 4 (the two halves' lines, 2 parameters each, pooled), 2.776. */
#define GROWTH_T95 2.5
#define GROWTH_T95_HALVES 2.78
/* The least bend, times L, taken as one: the log-envelope's departure from
 * its chord, about bend L / 8, of 1%; below, a bend is the rounding of an
 * envelope with no noise at all. */
#define GROWTH_BEND_MIN 0.1

/* Least-squares slope of ln y against t over m points, *se its standard
 * error from the residuals, *rss their sum of squares, *stt the spread of
 * t (sum of squares about its mean). */
static double ls_slope(const double *t, const double *y, size_t m, double *se, double *rss,
                       double *stt_out)
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
    double slope = sty / stt;
    *rss = 0;
    for (size_t k = 0; k < m; k++) {
        double r = log(y[k]) - my - slope * (t[k] - mt);
        *rss += r * r;
    }
    *se = m > 2 ? sqrt(*rss / (double)(m - 2) / stt) : NAN;
    *stt_out = stt;
    return slope;
}

void bkf_check_fit_growth(const double *t, const double *a, size_t count, double t_from,
                          double t_to, bkf_check_growth *g)
{
    *g = (bkf_check_growth){NAN, NAN, NAN, t_from, t_to, BKF_CHECK_GROWTH_UNDECIDED, NAN, 0};
    enum { W = BKF_CHECK_GROWTH_WINDOWS, H = W / 2 };
    double env[W], tm[W];
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
        /* at the maximum's own time: a beating mode's peaks lie on its
         * exponential wherever they fall in their windows (on the windows'
         * centres a beat of period near the windows' width read 28 standard
         * errors off a rate of -0.02) */
        if (!in[k]++ || a[i] > env[k]) {
            env[k] = a[i];
            tm[k] = t[i];
        }
    }
    for (size_t k = 0; k < W; k++)
        if (in[k] < 2) return;
    double se, rss, stt, rate = ls_slope(tm, env, W, &se, &rss, &stt);
    double se1, rss1, stt1, slope1 = ls_slope(tm, env, H, &se1, &rss1, &stt1);
    double se2, rss2, stt2, slope2 = ls_slope(tm + H, env + H, H, &se2, &rss2, &stt2);
    /* Whether the envelope is one exponential over the fit: the two halves'
     * slopes equal within their noise (the halves' residuals pooled, Student's
     * t at 4 degrees of freedom).  A start-up transient still rising into the
     * fit (or a mode still being amplified by the others, the operator not
     * being normal) bends it down, a slower mode still fading bends it up:
     * either way the whole fit's slope is a mixture of rates, not the
     * perturbation's.  At gamma 0.504908, c 0.749696, nu -0.884803,
     * S 25.7947, n 22 (sigma_max 0.0055) the run's Bloch class j = 11 over
     * [10, 40] rises at 0.051, then 0.033: the whole slope, 0.046 +- 0.009,
     * read the transient as growth 4 of its errors above the rate. */
    double se_bend = sqrt((rss1 + rss2) / (2.0 * (H - 2)) * (1 / stt1 + 1 / stt2));
    g->bend = slope2 - slope1;
    g->bends = fabs(g->bend) > fmax(GROWTH_T95_HALVES * se_bend, GROWTH_BEND_MIN / L);
    /* within the noise, the halves' difference is still an uncertainty;
     * beyond it, the rate so far nearest the asymptotic one is the later
     * half's, with as much uncertainty again as the slope moved over half
     * the fit, and a fit half as long */
    double len = g->bends ? 0.5 * L : L,
           err = g->bends ? sqrt(se2 * se2 + g->bend * g->bend)
                          : sqrt(se * se + 0.25 * g->bend * g->bend);
    g->rate = g->bends ? slope2 : rate;
    /* A fit of length len resolves no rate finer than about 1/len: a
     * transient slower than the fit, or two modes closer than that, give
     * an envelope as straight as one exponential's (draw 2's n = 22 over
     * [10, 20]: the Bloch classes straight at 0.036 .. 0.070 +- 0.003, the
     * rate 0.0055).  The floor is the one the verdict already has: a rate
     * below ln 2 / len changes the amplitude by less than a factor 2 over
     * the fit, which a wobble or a transient can fake; so limit =
     * max(2.5 err, ln 2 / len) = 2.5 rate_err. */
    g->rate_err = fmax(err, log(2.0) / (GROWTH_T95 * len));
    g->limit = GROWTH_T95 * g->rate_err;
    g->from = first;
    g->to = last;
    g->verdict = g->rate > g->limit    ? BKF_CHECK_GROWTH_GROWS
                 : g->rate < -g->limit ? BKF_CHECK_GROWTH_DECAYS
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
void check_growth_merge(bkf_check_growth *into, const bkf_check_growth *g, int first)
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
double check_sample_dt(double base, double tmax) { return fmax(base, tmax / BKF_CHECK_SAMPLES_MAX); }

int check_progress(double fraction, void *data)
{
    const check_ctx *c = data;
    if (!c->hooks || !c->hooks->progress) return 0;
    if (!c->shared) {
        c->hooks->progress(((double)c->root_index + fraction) / (double)c->roots, c->hooks->data);
        return 0;
    }
    /* the roots in flight report in turn; each root's fraction only grows,
     * so their mean does */
#pragma omp critical(bkf_check_hooks)
    {
        check_shared *sh = c->shared;
        sh->fraction[c->root_index] = fmax(sh->fraction[c->root_index], fmin(fraction, 1.0));
        double sum = 0;
        for (size_t i = 0; i < sh->roots; i++) sum += sh->fraction[i];
        c->hooks->progress(sum / (double)sh->roots, c->hooks->data);
    }
    return 0;
}

const volatile sig_atomic_t *check_cancel(const check_ctx *c)
{
    return c->hooks ? c->hooks->cancel : NULL;
}

void check_warn(const check_ctx *c, const char *fmt, ...)
{
    if (!c->hooks || !c->hooks->warning) return;
    char line[BKF_ERROR_LEN + 128];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    check_notes *k = c->notes;
    if (!k) {
        c->hooks->warning(line, c->hooks->data);
        return;
    }
    size_t len = strlen(line) + 1;
    if (k->used + len > k->cap) {
        size_t cap = 2 * (k->used + len);
        char *t = realloc(k->text, cap);
        if (!t) {
            k->oom = 1;
            return;
        }
        k->text = t;
        k->cap = cap;
    }
    memcpy(k->text + k->used, line, len);
    k->used += len;
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
double check_transient_end(double tmax) { return fmin(10.0, 0.25 * tmax); }

size_t check_coherent_end(record_reader at, const void *data, size_t R, size_t n, int settle,
                          double bound, double tmax)
{
    double t_ref = check_transient_end(tmax), t, dev;
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
double check_speed_bound(const bkf_check_options *o) { return fmax(100 * o->perturb, 1e-6); }
double check_linear_bound(const bkf_check_options *o) { return fmax(10 * o->perturb, 1e-3); }

/* The growth of the deviation over the linear part of the run: from the
 * end of the transient, t = min(10, tmax/4), to the end of the coherent
 * part under linear_bound.  *t_to gets that end (for the Bloch classes). */
int check_fit_deviation(record_reader at, const void *data, size_t R, size_t n,
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
    size_t end = R ? check_coherent_end(at, data, R, n, 0, check_linear_bound(o), o->tmax) : 0;
    *t_to = R ? t[end] : 0;
    bkf_check_fit_growth(t, d, R, check_transient_end(o->tmax), *t_to, g);
    free(t);
    free(d);
    return BKF_OK;
}

void check_row_init(bkf_check_row *row, size_t n, size_t root, const bkf_speeds_root *sr)
{
    memset(row, 0, sizeof *row);
    row->n = n;
    row->root = root;
    row->v_pred = sr->v;
    row->v_pred_err = sr->v_err;
    row->v_meas = row->v_meas_err = row->rel_err = row->fit_from = row->fit_to = NAN;
    row->tail = NAN;
    row->t_end = row->fronts_start = row->fronts_end = NAN;
    row->deviation_start = row->deviation_mid = row->deviation_end = NAN;
    bkf_check_fit_growth(NULL, NULL, 0, 0, 0, &row->growth);
    row->spectral = BKF_TRAINSPEC_UNRESOLVED;
    row->sigma_max = row->sigma_max_err = NAN;
    row->kept = NAN;
    row->decide_tmax = NAN;
    row->verdict = BKF_CHECK_UNRESOLVED;
    row->reason = BKF_OK;
}

/* What would decide an undecided row (check.h: decide_tmax), into the row
 * and a warning.  The rate in question is the growth the spectrum allows
 * (sigma_max + its error) when it gives one, else the run's own |growth|;
 * the fit's detection limit falls about as 1/L (its ln 2 / L term exactly,
 * the slope's standard error at least as fast), so a fit L limit / rate
 * long resolves it. */
void check_explain_undecided(const check_ctx *c, bkf_check_row *row)
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


/* Whether a verdict judges the speed: only a front stable by the spectrum
 * or by a decaying run has its speed compared with the prediction. */
int check_speed_judged(const bkf_check_row *row)
{
    return row->verdict == BKF_CHECK_AGREES || row->verdict == BKF_CHECK_DISAGREES;
}

/* Whether an auto run may stop with the row judged on the run so far (see
 * bkf_check_options.runs): nothing a longer run up to tmax could add would
 * change the verdict.  A decided stable spectrum leaves the run only the
 * speed to confirm, which is settled once it agrees by three times its
 * uncertainty; a decided unstable one makes the verdict unstable whatever
 * the run, which then adds a measured speed and a growth that either
 * already has the spectrum's sign or is too slow for any fit within tmax
 * (its detection limit is at least ln 2 / L) to decide either way, so to
 * contradict; the latter (the verdict unstable whatever the run) may settle
 * at BKF_CHECK_AUTO_UNSTABLE_FIRST already, when its short fit decides
 * nothing, every other row from BKF_CHECK_AUTO_FIRST on.  Disagreements and
 * conflicts, errors of the check, and an unresolved spectrum get the whole
 * run. */
int check_auto_settled(const bkf_check_options *o, const bkf_check_row *row, double t)
{
    if (o->runs != BKF_CHECK_RUNS_AUTO || row->verdict == BKF_CHECK_CONFLICTS) return 0;
    double L = o->tmax - check_transient_end(o->tmax);
    /* Before the first checkpoint only a row whose verdict no run can change
     * and whose short fit claims nothing: the spectrum unstable by a growth
     * no fit within tmax resolves, and the run's growth undecided (over
     * [10, 20] the noise's slow response can still read as growth: the
     * paper's n = 12 "grows" there, sigma_max 0.0023, undecided by t = 40).
     * A stable spectrum's run still watches for a growth against it. */
    if (t < BKF_CHECK_AUTO_FIRST)
        return row->spectral == BKF_TRAINSPEC_UNSTABLE && isfinite(row->rel_err) &&
               row->growth.verdict == BKF_CHECK_GROWTH_UNDECIDED &&
               row->sigma_max + row->sigma_max_err < log(2.0) / L;
    if (row->spectral == BKF_TRAINSPEC_STABLE)
        return row->verdict == BKF_CHECK_AGREES &&
               fabs(row->rel_err) + 3 * (row->v_meas_err + row->v_pred_err) / row->v_pred <=
                   o->rel_tol;
    if (row->spectral != BKF_TRAINSPEC_UNSTABLE || !isfinite(row->rel_err)) return 0;
    return row->growth.verdict == BKF_CHECK_GROWTH_GROWS ||
           row->sigma_max + row->sigma_max_err < log(2.0) / L;
}

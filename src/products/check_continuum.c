/* The check of one root of the continuum (check.c): the perturbed run on
 * the uniform spectral grid (bkf_pde, bkf_measure, the Bloch classes) or
 * the adapted comoving grid (bkf_comoving), and the spectrum of its train.
 * Above the verdicts (check_judge.c), below the product (check.c). */
#include "check_internal.h"

#include <fftw3.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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
    /* the fewest points that resolve the wave (the uniform grid's rule) */
    cp.resolution = o->resolution;
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
                                size_t run_points, double drift, double t_from, double t_to,
                                int *status)
{
    size_t points = 2 * run_points / 3;
    if (points < BKF_CHECK_POINTS_MIN) points = BKF_CHECK_POINTS_MIN;
    bkf_comoving_params cp = mapped_params(c, sr, n, points);
    cp.resolution = 0; /* exactly 2/3 of the run's points */
    bkf_error e;
    bkf_comoving *cm = bkf_comoving_alloc(&cp, &e);
    *status = BKF_OK;
    if (!cm) {
        if (e.status == BKF_ENOMEM) *status = BKF_ENOMEM;
        return NAN;
    }
    double coarse = NAN, coarse_err;
    int s = bkf_comoving_run(cm, t_to, check_sample_dt(BKF_CHECK_MAPPED_SAMPLE_DT, c->o->tmax), NULL,
                             NULL, &e);
    if (s == BKF_ECANCELED || s == BKF_ENOMEM) *status = s;
    if (!s && bkf_comoving_fit_drift(cm, t_from, t_to, &coarse, &coarse_err, &e) != BKF_OK)
        coarse = NAN;
    bkf_comoving_free(cm);
    return fabs(drift - coarse);
}

/* The row from the adapted grid's records so far: counts, deviations,
 * growth, the speed (v_meas_err the fit's uncertainty alone) and the
 * verdict. */
static int mapped_row(const check_ctx *c, const bkf_speeds_root *sr, const bkf_comoving *cm,
                      int blew_up, bkf_check_row *row, double *drift_out)
{
    const bkf_check_options *o = c->o;
    size_t R = bkf_comoving_count(cm);
    const bkf_comoving_record *first = bkf_comoving_record_at(cm, 0),
                              *last = bkf_comoving_record_at(cm, R - 1), *mid = last;
    int constant = 1;
    for (size_t r = 0; r < R; r++) {
        const bkf_comoving_record *rc = bkf_comoving_record_at(cm, r);
        if (rc->fronts != first->fronts) constant = 0;
        if (rc->t >= 0.5 * last->t && mid == last) mid = rc;
    }
    row->t_end = last->t;
    row->fronts_start = (double)first->fronts;
    row->fronts_end = (double)last->fronts;
    row->deviation_start = first->deviation;
    row->deviation_mid = mid->deviation;
    row->deviation_end = last->deviation;
    double t_lin;
    if (check_fit_deviation(comoving_reader, cm, R, row->n, o, &row->growth, &t_lin))
        return BKF_ENOMEM;
    /* the relaxed wave's own deviation plateau counts as coherent */
    size_t end = check_coherent_end(comoving_reader, cm, R, row->n, 1, check_speed_bound(o), o->tmax);
    double t_end = bkf_comoving_record_at(cm, end)->t;
    row->v_meas = row->v_meas_err = row->rel_err = row->fit_from = row->fit_to = NAN;
    bkf_error e;
    double drift, drift_err;
    if (end >= FIT_MIN_RECORDS &&
        bkf_comoving_fit_drift(cm, 0.5 * t_end, t_end, &drift, &drift_err, &e) == BKF_OK) {
        /* the frame moves with the fronts towards -x at v_pred */
        row->v_meas = sr->v - drift;
        row->v_meas_err = drift_err;
        *drift_out = drift;
        row->rel_err = -drift / sr->v;
        row->fit_from = 0.5 * t_end;
        row->fit_to = t_end;
    }
    int kept;
    row->verdict = bkf_check_judge(row->n, blew_up, constant, first->fronts, row->deviation_end,
                                   &row->growth, row->spectral, row->sigma_max, row->rel_err,
                                   o->rel_tol, &kept);
    row->kept = kept;
    return BKF_OK;
}

/* The adapted grid's run, watched after every record: an auto run stops
 * once the front is lost or, at its checkpoints, once the row is settled
 * (check_auto_settled). */
typedef struct {
    const check_ctx *c;
    const bkf_speeds_root *sr;
    const bkf_comoving *cm;
    const bkf_check_row *row; /* the spectrum's part */
    double next_check;
    int status;               /* a failure of a checkpoint's fits */
} mapped_watch;

static int mapped_progress(double fraction, void *data)
{
    mapped_watch *w = data;
    check_progress(fraction, (void *)w->c);
    if (w->c->o->runs != BKF_CHECK_RUNS_AUTO) return 0;
    size_t R = bkf_comoving_count(w->cm);
    const bkf_comoving_record *last = bkf_comoving_record_at(w->cm, R - 1);
    if (last->fronts != bkf_comoving_record_at(w->cm, 0)->fronts) return 1;
    if (last->t < w->next_check || last->t >= w->c->o->tmax) return 0;
    while (w->next_check <= last->t) w->next_check += BKF_CHECK_AUTO_EVERY;
    bkf_check_row r = *w->row;
    double drift;
    if ((w->status = mapped_row(w->c, w->sr, w->cm, 0, &r, &drift))) return 1;
    return check_auto_settled(w->c->o, &r, last->t);
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
    mapped_watch w = {c, sr, cm, row, BKF_CHECK_AUTO_UNSTABLE_FIRST, BKF_OK};
    int s = bkf_comoving_run(cm, o->tmax, check_sample_dt(BKF_CHECK_MAPPED_SAMPLE_DT, o->tmax),
                             mapped_progress, &w, &e);
    if (!s && w.status) {
        bkf_comoving_free(cm);
        return bkf_error_set(err, w.status, "out of memory");
    }
    size_t R = bkf_comoving_count(cm);
    int blew_up = s == BKF_EBLOWUP && R >= 2;
    if (blew_up) s = BKF_OK; /* a blown-up front is a result (unstable) */
    if (s == BKF_EBUDGET) {
        /* not a verdict: the run was too costly to finish (said, as every
         * unresolved row's reason is) */
        check_warn(c, "n = %zu, root %zu reported unresolved: the adapted grid's run (%zu "
                   "points) took %s (mapped-max-steps)", row->n, row->root, row->N, e.message);
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
    double drift = NAN;
    if ((s = mapped_row(c, sr, cm, blew_up, row, &drift))) {
        bkf_comoving_free(cm);
        return bkf_error_set(err, s, "out of memory");
    }
    if (blew_up) row->reason = BKF_EBLOWUP;
    bkf_comoving_free(cm);
    if (!isfinite(row->v_meas)) return BKF_OK;
    if (o->runs == BKF_CHECK_RUNS_AUTO && !check_speed_judged(row)) {
        /* the grid's error matters only to a judged speed, and its second
         * run can cost several times the first (n = 12 at the paper's
         * parameters: 11 s against 2.7 s) */
        row->v_meas_err = NAN;
        return BKF_OK;
    }
    /* The fit's uncertainty is that of the simulated field; the grid's own
     * error in the speed is added to it. */
    int gs;
    size_t points = row->N / row->n;
    double grid_err = mapped_grid_error(c, sr, row->n, points, drift, row->fit_from,
                                        row->fit_to, &gs);
    if (gs)
        return bkf_error_set(err, gs, "n = %zu, root %zu: %s", row->n, row->root,
                             gs == BKF_ENOMEM ? "out of memory" : "canceled");
    if (isnan(grid_err))
        check_warn(c, "n = %zu, root %zu: the run on %zu points per wavelength gives no "
                   "speed to compare with: v_meas_err is unknown (nan)", row->n,
                   row->root, 2 * points / 3);
    row->v_meas_err += grid_err;
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
        check_growth_merge(g, &gj, 0);
    }
    free(a);
    return BKF_OK;
}

/* The row from the uniform grid's records so far: counts, deviations,
 * growth (deviation and Bloch classes), the speed and the verdict. */
static int uniform_row(const check_ctx *c, const bkf_speeds_root *sr, const bkf_measure *meas,
                       const bloch_classes *bloch, int blew_up, double frame_speed,
                       bkf_check_row *row, bkf_error *err)
{
    const bkf_check_options *o = c->o;
    size_t n = row->n;
    bkf_measure_summary ms;
    bkf_error e;
    if (bkf_measure_summarize(meas, &ms, &e))
        return bkf_error_set(err, BKF_ENUMERIC, "n = %zu: %s", n, e.message);
    size_t R = bkf_measure_count(meas);
    row->t_end = bkf_measure_record_at(meas, R - 1)->t;
    row->fronts_start = (double)ms.fronts_start;
    row->fronts_end = (double)ms.fronts_end;
    row->deviation_start = ms.deviation_start;
    row->deviation_mid = ms.deviation_mid;
    row->deviation_end = ms.deviation_end;
    double t_lin;
    int s;
    if ((s = check_fit_deviation(measure_reader, meas, R, n, o, &row->growth, &t_lin)) ||
        (s = bloch_fit(bloch, check_transient_end(o->tmax), t_lin, &row->growth)))
        return bkf_error_set(err, s, "out of memory");
    size_t last = check_coherent_end(measure_reader, meas, R, n, 1, check_speed_bound(o), o->tmax);
    double t_end = bkf_measure_record_at(meas, last)->t;
    row->v_meas = row->v_meas_err = row->rel_err = row->fit_from = row->fit_to = NAN;
    if (last >= FIT_MIN_RECORDS) {
        double t_from = 0.5 * t_end;
        double v, ve;
        if (bkf_measure_fit_speed(meas, t_from, t_end, &v, &ve, NULL, &e) == BKF_OK) {
            /* v is relative to the frame; towards -x in the lab: -(v + V) */
            row->v_meas = -(v + frame_speed);
            row->v_meas_err = ve;
            row->rel_err = -(v + frame_speed + sr->v) / sr->v;
            row->fit_from = t_from;
            row->fit_to = t_end;
        }
    }
    int kept;
    row->verdict = bkf_check_judge(n, blew_up, ms.count_constant, ms.fronts_start,
                                   ms.deviation_end, &row->growth, row->spectral, row->sigma_max,
                                   row->rel_err, o->rel_tol, &kept);
    row->kept = kept;
    return BKF_OK;
}

/* The uniform grid's samples, measured; an auto run stops once the front
 * is lost or, at its checkpoints, once the row is settled
 * (check_auto_settled). */
typedef struct {
    const check_ctx *c;
    const bkf_speeds_root *sr;
    const bkf_check_row *row; /* the spectrum's part */
    double frame_speed, next_check;
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
    const bkf_check_options *o = ob->c->o;
    if (o->runs != BKF_CHECK_RUNS_AUTO) return 0;
    size_t R = bkf_measure_count(ob->meas);
    if (bkf_measure_record_at(ob->meas, R - 1)->fronts != bkf_measure_record_at(ob->meas, 0)->fronts)
        return 1;
    if (smp->t < ob->next_check || smp->t >= o->tmax) return 0;
    while (ob->next_check <= smp->t) ob->next_check += BKF_CHECK_AUTO_EVERY;
    bkf_check_row r = *ob->row;
    if ((ob->status = uniform_row(ob->c, ob->sr, ob->meas, ob->bloch, 0, ob->frame_speed, &r,
                                  &ob->err)))
        return 1;
    return check_auto_settled(o, &r, smp->t);
}

/* One root: the grid that resolves it, the perturbed run, its
 * measurements. */
int check_root(const check_ctx *c, const bkf_speeds_root *sr, bkf_check_row *row,
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
    /* the table's own root, not a second speeds solve (bkf_seed_front's,
     * at its own tol, could refuse or renumber what the table gave) */
    bkf_pde_wave wave = {n, sr->v, sr->mu, -1, o->perturb, o->seed,
                         bkf_pde_front_spec_default().tol};
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
        if ((s = bkf_pde_init_front(pde, &wave, &fi, clean, &e))) {
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
    check_obs ob = {c, sr, row, po.frame_speed, BKF_CHECK_AUTO_UNSTABLE_FIRST, meas, &bloch, 0,
                    {{0}, 0}};
    s = bkf_pde_run(pde, o->tmax, check_sample_dt(BKF_CHECK_SAMPLE_DT, o->tmax), check_observe, &ob,
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
    if ((s = uniform_row(c, sr, meas, &bloch, blew_up, po.frame_speed, row, err))) goto done;
    if (blew_up) row->reason = BKF_EBLOWUP;
done:
    bloch_free(&bloch);
    bkf_measure_free(meas);
    bkf_pde_free(pde);
    free(clean);
    return s;
}

/* The spectrum's answer as the verdict reads it: decided stable, decided
 * unstable, or not decided (UNRESOLVED) with a reason.  A sigma_max that
 * is only the window's edge (window_edge finite, bkf_trainspec_shown_of)
 * is no eigenvalue, so not printed; its verdict is read as `stability` and
 * `speeds --stability` read it (one spectrum per train, issue 31): stable
 * when the edge is left of 0 (every eigenvalue but the translation lies
 * left of it), with the bound in a note. */
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
        bkf_trainspec_bound_note(window_edge, note, sizeof note);
        if (verdict != BKF_TRAINSPEC_STABLE) {
            check_warn(c, "n = %zu, root %zu: spectrum not decided: %s", row->n, row->root, note);
            return;
        }
        check_warn(c, "n = %zu, root %zu: spectrum stable, %s", row->n, row->root, note);
        row->spectral = BKF_TRAINSPEC_STABLE;
        row->sigma_max = row->sigma_max_err = NAN;
        return;
    }
    row->spectral = verdict;
    row->sigma_max = sigma_max;
    row->sigma_max_err = sigma_max_err;
}

/* The spectrum of the root's train: first at tol 1e-4, which decides the
 * sign of every sigma_max farther than that from 0 (the paper's twelve
 * roots: all, at half the cost of 1e-6; the smallest |sigma_max| there is
 * 1.4e-4, n = 6), and where it leaves the sign undecided again at
 * trainspec's default accuracy (1e-6).  A refusal at 1e-4 is not retried:
 * its causes (an estimate above tol on the finest mesh, the work budget)
 * only grow with a tighter tol; nor is a window's edge (the window does not
 * depend on tol).  Both rates are far below any a run resolves.  A refusal
 * leaves the row's spectrum unresolved, with a warning: the run still
 * judges.  The row reads sigma_max and the verdict alone: the rightmost
 * alone (per_kappa 0) is asked, whose other eigenvalues are not refined. */
#define CHECK_SPECTRUM_TOL_FIRST 1e-4

void check_spectrum(const check_ctx *c, const bkf_speeds_root *sr, bkf_check_row *row)
{
    bkf_model_params p = *c->model;
    p.kind = BKF_MODEL_CONTINUUM;
    bkf_trainspec_result res;
    bkf_error e;
    double tol = CHECK_SPECTRUM_TOL_FIRST;
    int s = bkf_trainspec_root(&p, sr, tol, 0, &res, &e);
    bkf_trainspec_shown shown = bkf_trainspec_shown_of(&res);
    if (!s && res.verdict == BKF_TRAINSPEC_UNRESOLVED && !isfinite(shown.bound)) {
        bkf_trainspec_result_free(&res);
        s = bkf_trainspec_root(&p, sr, bkf_trainspec_options_default().tol, 0, &res, &e);
        shown = bkf_trainspec_shown_of(&res);
    }
    if (s) spectrum_of(c, row, s, e.message, BKF_TRAINSPEC_UNRESOLVED, NAN, NAN, NAN);
    else spectrum_of(c, row, s, "", res.verdict, shown.sigma_max, shown.sigma_max_err, shown.bound);
    bkf_trainspec_result_free(&res);
}

/* Measurements on simulated fields; definitions and criteria in
 * include/bkfront/measure.h. */
#include "bkfront/measure.h"

#include <fftw3.h>
#include <gsl/gsl_math.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bkfront/model.h"
#include "bkfront/cycle.h"
#include "bkfront/fft.h"

typedef struct {
    double t, psi, psit;
} probe_point;

/* An upward crossing of the level at the probe, and the record it ends in. */
typedef struct {
    double t;
    size_t r;
} crossing;

/* What the summary needs of the window's records, accumulated in record
 * order (the same sums whether streamed in bkf_measure_add or looped over
 * kept records in bkf_measure_summarize). */
typedef struct {
    size_t cnt;
    double msum, vsum, std_max, psi_min, psi_max, slip_max;
    /* the window's two halves (before and after tmid): whether it settled */
    double tmid, half_vsum[2], half_fsum[2];
    size_t half_cnt[2];
    size_t fronts_min, fronts_max, any_minus, any_plus;
    bkf_measure_record first;   /* the window's first record */
    size_t first_index, first_seg;
} window_acc;

struct bkf_measure {
    bkf_measure_params p;
    double h, level;
    size_t nc;
    /* FFT workspace */
    double *rbuf, *d1, *d2, *psit, *shifted;
    fftw_complex *c, *cw, *refhat;
    fftw_plan fwd, bwd;
    double *ref;
    /* records: those from index `base` on are kept, at [r - base]; with
     * t_end unknown base stays 0 */
    bkf_measure_record *rec;
    size_t nrec, caprec, base;
    size_t *seg, *off, *nminus, *nplus; /* per kept record */
    /* unwrapped track positions, per kept record, in track order; off[] is
     * relative to X */
    double *X;
    size_t nX, capX;
    /* streamed over every record */
    bkf_measure_record rec0;    /* the first record */
    int count_constant, dev_nan;
    double dev_max;
    size_t seg_start;           /* first record of the current set of tracks */
    probe_point probe_prev;
    int armed;
    crossing *cross;
    size_t ncross, capcross;
    /* bounded (t_end known): the window [tw, t_end] and its sums */
    int bounded;
    double tw, t_dropped;
    size_t keep_from;           /* records before it are no longer needed */
    window_acc win;
    /* tracking */
    bkf_front *prev, *cur, *tmp;
    size_t nprev, cap_fronts;
    size_t segment;
    double t_prev;
    double *X0;                 /* where each track started (see bkf_measure_add) */
};

const char *bkf_regime_name(bkf_regime r)
{
    switch (r) {
    case BKF_REGIME_CONTINUOUS_SLIP: return "continuous_slip";
    case BKF_REGIME_GLOBAL_OSCILLATION: return "global_oscillation";
    case BKF_REGIME_PACEMAKERS: return "period_doubled_pacemakers";
    case BKF_REGIME_FRONTS: return "propagating_fronts";
    case BKF_REGIME_TRANSIENT: return "transient";
    default: return "irregular";
    }
}

double bkf_measure_front_level(const bkf_model_params *model, double *period)
{
    if (period) *period = 0;
    if (!model) return NAN;
    if (!(fabs(model->nu) < 1) || !(model->gamma >= BKF_CYCLE_MU_MIN) ||
        !(model->gamma <= BKF_CYCLE_MU_MAX))
        return model->nu;
    bkf_cycle_result cr;
    bkf_cycle_options co = bkf_cycle_options_default();
    bkf_error e;
    if (bkf_cycle_period(model->gamma, model->nu, &co, &cr, &e) != BKF_OK) return model->nu;
    if (period) *period = cr.period;
    return 0.5 * (cr.xmin + cr.xmax);
}

bkf_measure_params bkf_measure_params_default(void)
{
    bkf_measure_params p;
    memset(&p, 0, sizeof p);
    p.level = NAN;
    p.hysteresis = 0.1;
    p.window = 0.5;
    p.slip_eps = 1e-3;
    p.uniform_eps = 1e-2;
    p.periodic_tol = 5e-2;
    p.settled_tol = 0.1;
    p.t_end = NAN;
    return p;
}

void bkf_measure_free(bkf_measure *m)
{
    if (!m) return;
    bkf_fft_lock();
    if (m->fwd) fftw_destroy_plan(m->fwd);
    if (m->bwd) fftw_destroy_plan(m->bwd);
    bkf_fft_unlock();
    fftw_free(m->rbuf);
    fftw_free(m->d1);
    fftw_free(m->d2);
    fftw_free(m->c);
    fftw_free(m->cw);
    fftw_free(m->refhat);
    free(m->psit);
    fftw_free(m->shifted);
    free(m->ref);
    free(m->rec);
    free(m->seg);
    free(m->off);
    free(m->nminus);
    free(m->nplus);
    free(m->cross);
    free(m->X);
    free(m->prev);
    free(m->cur);
    free(m->tmp);
    free(m->X0);
    free(m);
}

static int check_params(const bkf_measure_params *p, bkf_error *err)
{
    if (!p) return bkf_error_set(err, BKF_EINPUT, "parameters are NULL");
    if (p->model.N < 8 || p->model.N > (1u << 24))
        return bkf_error_set(err, BKF_EINPUT, "N = %zu is outside [8, %u]", p->model.N, 1u << 24);
    int s;
    if ((s = bkf_model_check_positive("S", p->model.S, err))) return s;
    if ((s = bkf_model_check_positive("gamma", p->model.gamma, err))) return s;
    if (!isfinite(p->model.nu)) return bkf_error_set(err, BKF_EINPUT, "nu must be finite");
    if (!isnan(p->level) && !isfinite(p->level))
        return bkf_error_set(err, BKF_EINPUT, "level must be finite (or NaN for the default)");
    if (!(p->hysteresis >= 0) || !isfinite(p->hysteresis))
        return bkf_error_set(err, BKF_EINPUT, "hysteresis = %g must be finite and >= 0",
                             p->hysteresis);
    if (p->probe >= p->model.N)
        return bkf_error_set(err, BKF_EINPUT, "probe = %zu is outside [0, %zu]", p->probe,
                             p->model.N - 1);
    if (!(p->window > 0 && p->window <= 1))
        return bkf_error_set(err, BKF_EINPUT, "window = %g is outside (0, 1]", p->window);
    if (!(p->period_ref >= 0) || !isfinite(p->period_ref))
        return bkf_error_set(err, BKF_EINPUT, "period_ref = %g must be finite and >= 0",
                             p->period_ref);
    if (!(p->slip_eps > 0) || !(p->uniform_eps > 0) || !(p->periodic_tol > 0) ||
        !(p->settled_tol > 0) ||
        !isfinite(p->slip_eps + p->uniform_eps + p->periodic_tol + p->settled_tol))
        return bkf_error_set(err, BKF_EINPUT, "slip_eps, uniform_eps, periodic_tol and "
                                              "settled_tol must be finite and > 0");
    if (!isfinite(p->frame_speed))
        return bkf_error_set(err, BKF_EINPUT, "frame_speed must be finite");
    if (!isnan(p->t_end) && !isfinite(p->t_end))
        return bkf_error_set(err, BKF_EINPUT, "t_end must be finite (or NaN: unknown)");
    if (p->reference)
        for (size_t i = 0; i < p->model.N; i++)
            if (!isfinite(p->reference[i]))
                return bkf_error_set(err, BKF_EINPUT, "reference[%zu] is not finite", i);
    return BKF_OK;
}

bkf_measure *bkf_measure_alloc(const bkf_measure_params *params, bkf_error *err)
{
    if (check_params(params, err) != BKF_OK) return NULL;
    bkf_measure *m = calloc(1, sizeof *m);
    if (!m) {
        bkf_error_set(err, BKF_ENOMEM, "out of memory");
        return NULL;
    }
    m->p = *params;
    m->p.reference = NULL;
    size_t N = params->model.N;
    m->h = params->model.S / (double)N;
    m->level = isnan(params->level) ? bkf_measure_front_level(&params->model, NULL) : params->level;
    m->nc = N / 2 + 1;
    m->bounded = !isnan(params->t_end);
    m->count_constant = 1;
    m->t_dropped = -INFINITY;
    m->rbuf = fftw_malloc(N * sizeof(double));
    m->d1 = fftw_malloc(N * sizeof(double));
    m->d2 = fftw_malloc(N * sizeof(double));
    m->c = fftw_malloc(m->nc * sizeof(fftw_complex));
    m->cw = fftw_malloc(m->nc * sizeof(fftw_complex));
    m->psit = malloc(N * sizeof(double));
    /* every array handed to an FFTW plan comes from fftw_malloc: the
     * new-array execute calls need the plan's alignment */
    m->shifted = fftw_malloc(N * sizeof(double));
    if (!m->rbuf || !m->d1 || !m->d2 || !m->c || !m->cw || !m->psit || !m->shifted) goto nomem;
    bkf_fft_lock();
    m->fwd = fftw_plan_dft_r2c_1d((int)N, m->rbuf, m->c, FFTW_ESTIMATE);
    m->bwd = fftw_plan_dft_c2r_1d((int)N, m->cw, m->d1, FFTW_ESTIMATE);
    bkf_fft_unlock();
    if (!m->fwd || !m->bwd) goto nomem;
    if (params->reference) {
        m->ref = malloc(N * sizeof(double));
        m->refhat = fftw_malloc(m->nc * sizeof(fftw_complex));
        if (!m->ref || !m->refhat) goto nomem;
        memcpy(m->ref, params->reference, N * sizeof(double));
        memcpy(m->rbuf, m->ref, N * sizeof(double));
        fftw_execute_dft_r2c(m->fwd, m->rbuf, m->refhat);
    }
    return m;
nomem:
    bkf_measure_free(m);
    bkf_error_set(err, BKF_ENOMEM, "out of memory");
    return NULL;
}

/* ------------------------------------------------------------- fronts */

static double wrap(double d, double S) { return d - S * floor(d / S + 0.5); }

/* psi_x and psi_xx into m->d1, m->d2 (spectral). */
static void derivatives(bkf_measure *m, const double *psi)
{
    size_t N = m->p.model.N, nc = m->nc;
    memcpy(m->rbuf, psi, N * sizeof *psi);
    fftw_execute_dft_r2c(m->fwd, m->rbuf, m->c);
    double k0 = 2.0 * M_PI / m->p.model.S, inv = 1.0 / (double)N;
    for (size_t k = 0; k < nc; k++) {
        double q = k0 * (double)k;
        /* The Nyquist mode has no odd part on the grid: its derivative is 0. */
        double qd = (2 * k == N) ? 0.0 : q;
        m->cw[k][0] = -qd * m->c[k][1] * inv;
        m->cw[k][1] = qd * m->c[k][0] * inv;
    }
    fftw_execute_dft_c2r(m->bwd, m->cw, m->d1);
    for (size_t k = 0; k < nc; k++) {
        double q = k0 * (double)k;
        m->cw[k][0] = -q * q * m->c[k][0] * inv;
        m->cw[k][1] = -q * q * m->c[k][1] * inv;
    }
    fftw_execute_dft_c2r(m->bwd, m->cw, m->d2);
}

/* Quintic Hermite on [0, 1] from value, first and second derivative (the
 * derivatives already scaled by the cell width) at both ends. */
static void hermite5(const double a[3], const double b[3], double w, double *v, double *dv)
{
    double w2 = w * w, w3 = w2 * w, w4 = w3 * w, w5 = w4 * w;
    double h0 = 1 - 10 * w3 + 15 * w4 - 6 * w5, d0 = -30 * w2 + 60 * w3 - 30 * w4;
    double h1 = w - 6 * w3 + 8 * w4 - 3 * w5, d1 = 1 - 18 * w2 + 32 * w3 - 15 * w4;
    double h2 = 0.5 * w2 - 1.5 * w3 + 1.5 * w4 - 0.5 * w5,
           d2 = w - 4.5 * w2 + 6 * w3 - 2.5 * w4;
    double h3 = 1 - h0, d3 = -d0;
    double h4 = -4 * w3 + 7 * w4 - 3 * w5, d4 = -12 * w2 + 28 * w3 - 15 * w4;
    double h5 = 0.5 * w3 - w4 + 0.5 * w5, d5 = 1.5 * w2 - 4 * w3 + 2.5 * w4;
    *v = h0 * a[0] + h1 * a[1] + h2 * a[2] + h3 * b[0] + h4 * b[1] + h5 * b[2];
    *dv = d0 * a[0] + d1 * a[1] + d2 * a[2] + d3 * b[0] + d4 * b[1] + d5 * b[2];
}

/* Root of the interpolant minus level in the cell [j, j+1], where the grid
 * values bracket it; returns w in [0, 1] and the slope d psi/dx there.
 * Newton from the linear guess, kept inside a shrinking bracket. */
static double cell_root(const bkf_measure *m, const double *psi, size_t j, double *slope)
{
    size_t N = m->p.model.N, k = (j + 1) % N;
    double h = m->h, L = m->level;
    if (m->p.model.kind == BKF_MODEL_CHAIN) {
        /* a chain has no field between its blocks: the spectral Hermite
           through fronts one block wide invents a shape; linear instead */
        *slope = (psi[k] - psi[j]) / h;
        return (L - psi[j]) / (psi[k] - psi[j]);
    }
    double a[3] = {psi[j] - L, m->d1[j] * h, m->d2[j] * h * h};
    double b[3] = {psi[k] - L, m->d1[k] * h, m->d2[k] * h * h};
    double lo = 0, hi = 1;
    int lo_neg = a[0] < 0;
    double w = a[0] == b[0] ? 0.5 : a[0] / (a[0] - b[0]);
    if (!(w >= 0 && w <= 1)) w = 0.5;
    double v, dv;
    for (int it = 0; it < 60; it++) {
        hermite5(a, b, w, &v, &dv);
        if (v == 0) break;
        if ((v < 0) == lo_neg) lo = w;
        else hi = w;
        double wn = dv != 0 ? w - v / dv : 0.5 * (lo + hi);
        if (!(wn > lo && wn < hi)) wn = 0.5 * (lo + hi);
        if (fabs(wn - w) < 1e-15) {
            w = wn;
            break;
        }
        w = wn;
        if (hi - lo < 1e-15) break;
    }
    hermite5(a, b, w, &v, &dv);
    *slope = dv / h;
    return w;
}

/* Fronts of psi (derivatives already in d1, d2) into `out` (capacity cap);
 * returns the count. */
static size_t find_fronts(bkf_measure *m, const double *psi, const double *eta, bkf_front *out,
                          size_t cap)
{
    size_t N = m->p.model.N;
    double L = m->level, d = m->p.hysteresis, g = m->p.model.gamma;
    for (size_t i = 0; i < N; i++) m->psit[i] = g * (eta[i] - bkf_model_friction(psi[i]));
    size_t i0 = N;
    for (size_t i = 0; i < N; i++)
        if (psi[i] > L + d || psi[i] < L - d) {
            i0 = i;
            break;
        }
    if (i0 == N) return 0;
    int prev_state = psi[i0] > L + d ? 1 : -1;
    size_t prev_idx = i0, count = 0;
    for (size_t step = 1; step <= N; step++) {
        size_t i = (i0 + step) % N;
        int st = psi[i] > L + d ? 1 : psi[i] < L - d ? -1 : 0;
        if (st == 0) continue;
        if (st != prev_state) {
            /* last point on the old side of the level, from prev_idx on */
            size_t j = prev_idx;
            for (size_t q = prev_idx; q != i; q = (q + 1) % N) {
                int below = psi[q] < L;
                if ((prev_state < 0) == below) j = q;
            }
            double slope, pt;
            double w = cell_root(m, psi, j, &slope);
            size_t k = (j + 1) % N;
            if (m->p.model.kind == BKF_MODEL_CHAIN) {
                /* a cubic through four blocks cannot follow psi_t across a
                   front one block wide: its sign flipped at the back of a
                   pulse (N 20, n 4: 4 or 8 fronts by turns).  psi_t where
                   psi = L is gamma (eta - phi(L)), eta the slow variable,
                   linear across the cell as psi is (see cell_root) */
                pt = g * (eta[j] + w * (eta[k] - eta[j]) - bkf_model_friction(L));
            } else {
                /* psi_t at the crossing: cubic Lagrange through j-1 .. j+2 */
                size_t jm = (j + N - 1) % N, kp = (k + 1) % N;
                pt = -w * (w - 1) * (w - 2) / 6 * m->psit[jm] +
                     (w + 1) * (w - 1) * (w - 2) / 2 * m->psit[j] -
                     (w + 1) * w * (w - 2) / 2 * m->psit[k] +
                     (w + 1) * w * (w - 1) / 6 * m->psit[kp];
            }
            if (pt > 0) {
                if (count < cap) {
                    double x = ((double)j + w) * m->h;
                    if (x >= m->p.model.S) x -= m->p.model.S;
                    out[count].x = x;
                    out[count].velocity = slope != 0 ? -pt / slope : (double)NAN;
                    out[count].rising = prev_state < 0;
                }
                count++;
            }
        }
        prev_state = st;
        prev_idx = i;
    }
    /* The walk starts at i0, so the fronts come in x order from there:
     * rotate to start from the smallest x. */
    size_t n = count < cap ? count : cap;
    if (n > 1) {
        size_t first = 0;
        for (size_t r = 1; r < n; r++)
            if (out[r].x < out[first].x) first = r;
        if (first) {
            bkf_front tmpf[64];
            bkf_front *buf = n <= 64 ? tmpf : malloc(n * sizeof *buf);
            if (buf) {
                for (size_t r = 0; r < n; r++) buf[r] = out[(first + r) % n];
                memcpy(out, buf, n * sizeof *buf);
                if (buf != tmpf) free(buf);
            }
        }
    }
    return count;
}

static int check_field(const double *psi, const double *eta, size_t N, bkf_error *err)
{
    if (!psi || !eta) return bkf_error_set(err, BKF_EINPUT, "NULL field");
    for (size_t i = 0; i < N; i++)
        if (!isfinite(psi[i]) || !isfinite(eta[i]))
            return bkf_error_set(err, BKF_EINPUT, "the field is not finite at i = %zu", i);
    return BKF_OK;
}

int bkf_measure_fronts(bkf_measure *m, const double *psi, const double *eta, bkf_front *fronts,
                       size_t capacity, size_t *count, bkf_error *err)
{
    if (!m) return bkf_error_set(err, BKF_EINPUT, "measure object is NULL");
    int s = check_field(psi, eta, m->p.model.N, err);
    if (s) return s;
    derivatives(m, psi);
    size_t n = find_fronts(m, psi, eta, fronts, fronts ? capacity : 0);
    if (count) *count = n;
    return BKF_OK;
}

/* ----------------------------------------------------------- recording */

/* The reference's crossing of the level nearest to x with the same
 * orientation (derivatives of the reference in d1, d2), as a position
 * within S/2 of x; x itself when there is none within a quarter domain. */
static double reference_crossing(const bkf_measure *m, double x, int rising)
{
    long N = (long)m->p.model.N;
    double L = m->level, S = m->p.model.S;
    long c = (long)floor(x / m->h);
    for (long off = 0; off <= N / 4; off++)
        for (int sg = -1; sg <= 1; sg += 2) {
            if (off == 0 && sg > 0) continue;
            size_t j = (size_t)((((c + sg * off) % N) + N) % N), k = (j + 1) % (size_t)N;
            double a = m->ref[j] - L, b = m->ref[k] - L;
            if (rising ? (a < 0 && b >= 0) : (a >= 0 && b < 0)) {
                double slope, w = cell_root(m, m->ref, j, &slope);
                return x + wrap(((double)j + w) * m->h - x, S);
            }
        }
    return x;
}

/* max |psi(x) - ref(x - d)| */
static double deviation(bkf_measure *m, const double *psi, double d)
{
    size_t N = m->p.model.N;
    double k0 = 2.0 * M_PI / m->p.model.S, inv = 1.0 / (double)N;
    for (size_t k = 0; k < m->nc; k++) {
        double ph = -k0 * (double)k * d;
        double cr = cos(ph), ci = sin(ph);
        double re = m->refhat[k][0], im = m->refhat[k][1];
        if (2 * k == N) { /* keep the shifted Nyquist mode real, as on the grid */
            m->cw[k][0] = re * cr * inv;
            m->cw[k][1] = 0;
            continue;
        }
        m->cw[k][0] = (re * cr - im * ci) * inv;
        m->cw[k][1] = (re * ci + im * cr) * inv;
    }
    fftw_execute_dft_c2r(m->bwd, m->cw, m->shifted);
    double dev = 0;
    for (size_t i = 0; i < N; i++) dev = fmax(dev, fabs(psi[i] - m->shifted[i]));
    return dev;
}

/* Upward crossing of level between probe samples a and b by cubic Hermite. */
static double crossing_time(const probe_point *a, const probe_point *b, double L)
{
    double dt = b->t - a->t;
    double p0 = a->psi - L, p1 = b->psi - L, m0 = a->psit * dt, m1 = b->psit * dt;
    double lo = 0, hi = 1, w = p0 / (p0 - p1);
    if (!(w > 0 && w < 1)) w = 0.5;
    for (int it = 0; it < 60; it++) {
        double w2 = w * w, w3 = w2 * w;
        double v = (2 * w3 - 3 * w2 + 1) * p0 + (w3 - 2 * w2 + w) * m0 + (-2 * w3 + 3 * w2) * p1 +
                   (w3 - w2) * m1;
        double dv = (6 * w2 - 6 * w) * p0 + (3 * w2 - 4 * w + 1) * m0 + (-6 * w2 + 6 * w) * p1 +
                    (3 * w2 - 2 * w) * m1;
        if (v < 0) lo = w;
        else hi = w;
        double wn = dv != 0 ? w - v / dv : 0.5 * (lo + hi);
        if (!(wn > lo && wn < hi)) wn = 0.5 * (lo + hi);
        if (fabs(wn - w) < 1e-15 || hi - lo < 1e-15) {
            w = wn;
            break;
        }
        w = wn;
    }
    return a->t + w * dt;
}

static void window_add(window_acc *w, const bkf_measure_record *rc, size_t r, size_t seg,
                       size_t minus, size_t plus, double nu, double tmid)
{
    if (w->cnt == 0) {
        memset(w, 0, sizeof *w);
        w->tmid = tmid;
        w->first = *rc;
        w->first_index = r;
        w->first_seg = seg;
        w->fronts_min = w->fronts_max = rc->fronts;
        w->psi_min = INFINITY;
        w->psi_max = -INFINITY;
    }
    if (rc->fronts < w->fronts_min) w->fronts_min = rc->fronts;
    if (rc->fronts > w->fronts_max) w->fronts_max = rc->fronts;
    w->any_minus += minus;
    w->any_plus += plus;
    w->msum += rc->mean;
    w->vsum += rc->variance;
    w->cnt++;
    int h = rc->t >= w->tmid;
    w->half_vsum[h] += rc->variance;
    w->half_fsum[h] += (double)rc->fronts;
    w->half_cnt[h]++;
    w->std_max = fmax(w->std_max, sqrt(rc->variance));
    w->psi_min = fmin(w->psi_min, rc->min);
    w->psi_max = fmax(w->psi_max, rc->max);
    w->slip_max = fmax(w->slip_max, fmax(fabs(rc->max - nu), fabs(rc->min - nu)));
}

/* Drops the kept records before keep_from (bounded mode), moving the rest
 * and their positions to the front. */
static void compact(bkf_measure *m)
{
    size_t dead = m->keep_from - m->base, live = m->nrec - m->keep_from;
    if (!dead) return;
    m->t_dropped = m->rec[dead - 1].t;
    size_t x0 = live ? m->off[dead] : m->nX;
    memmove(m->rec, m->rec + dead, live * sizeof *m->rec);
    memmove(m->seg, m->seg + dead, live * sizeof *m->seg);
    memmove(m->nminus, m->nminus + dead, live * sizeof *m->nminus);
    memmove(m->nplus, m->nplus + dead, live * sizeof *m->nplus);
    for (size_t j = 0; j < live; j++) m->off[j] = m->off[dead + j] - x0;
    if (x0) { /* X is NULL while no front was ever seen */
        memmove(m->X, m->X + x0, (m->nX - x0) * sizeof *m->X);
        m->nX -= x0;
    }
    m->base = m->keep_from;
}

/* Room for one more record with n positions; bounded runs reuse the
 * space of records no longer needed before growing (amortised: only when
 * they are at least half of what is kept). */
static int reserve(bkf_measure *m, size_t n)
{
    size_t kept = m->nrec - m->base;
    if ((kept + 1 > m->caprec || m->nX + n > m->capX) && m->keep_from > m->base &&
        2 * (m->keep_from - m->base) >= kept)
        compact(m);
    kept = m->nrec - m->base;
    if (kept + 1 > m->caprec) {
        size_t c = m->caprec ? 2 * m->caprec : 256;
        void *q;
#define REGROW(field)                                                          \
        if (!(q = realloc(m->field, c * sizeof *m->field))) return BKF_ENOMEM; \
        m->field = q;
        REGROW(rec) REGROW(seg) REGROW(off) REGROW(nminus) REGROW(nplus)
#undef REGROW
        m->caprec = c;
    }
    if (m->nX + n > m->capX) {
        size_t c = m->capX ? 2 * m->capX : 4096;
        while (c < m->nX + n) c *= 2;
        double *q = realloc(m->X, c * sizeof *q);
        if (!q) return BKF_ENOMEM;
        m->X = q;
        m->capX = c;
    }
    return BKF_OK;
}

/* The probe's crossings, streamed with the hysteresis of period_at_probe:
 * armed once psi went below level - hysteresis. */
static int probe_add(bkf_measure *m, size_t r, const probe_point *b, int keep)
{
    double L = m->level, d = m->p.hysteresis;
    if (b->psi < L - d) m->armed = 1;
    if (r > 0) {
        const probe_point *a = &m->probe_prev;
        if (m->armed && a->psi < L && b->psi >= L) {
            double tc = crossing_time(a, b, L);
            if (keep) {
                if (m->ncross == m->capcross) {
                    size_t c = m->capcross ? 2 * m->capcross : 64;
                    crossing *q = realloc(m->cross, c * sizeof *q);
                    if (!q) return BKF_ENOMEM;
                    m->cross = q;
                    m->capcross = c;
                }
                m->cross[m->ncross++] = (crossing){tc, r};
            }
            m->armed = b->psi < L - d;
        }
    }
    m->probe_prev = *b;
    return BKF_OK;
}

int bkf_measure_add(bkf_measure *m, double t, const double *psi, const double *eta,
                    bkf_error *err)
{
    if (!m) return bkf_error_set(err, BKF_EINPUT, "measure object is NULL");
    if (!isfinite(t)) return bkf_error_set(err, BKF_EINPUT, "t must be finite");
    if (m->nrec && !(t > m->t_prev))
        return bkf_error_set(err, BKF_EINPUT, "sample times must increase (t = %g after %g)", t,
                             m->t_prev);
    size_t N = m->p.model.N;
    int s = check_field(psi, eta, N, err);
    if (s) return s;
    size_t r = m->nrec;

    derivatives(m, psi);
    size_t n = find_fronts(m, psi, eta, m->cur, m->cap_fronts);
    if (n > m->cap_fronts) {
        size_t c = 2 * n;
        void *q;
        if (!(q = realloc(m->cur, c * sizeof *m->cur))) goto nomem;
        m->cur = q;
        if (!(q = realloc(m->prev, c * sizeof *m->prev))) goto nomem;
        m->prev = q;
        if (!(q = realloc(m->tmp, c * sizeof *m->tmp))) goto nomem;
        m->tmp = q;
        m->cap_fronts = c;
        n = find_fronts(m, psi, eta, m->cur, m->cap_fronts);
    }
    if (reserve(m, n)) goto nomem;
    size_t j = r - m->base;

    /* tracking */
    double S = m->p.model.S;
    int continued = r > 0 && n > 0 && n == m->nprev;
    if (continued) {
        double dt = t - m->t_prev;
        size_t best = 0;
        double best_cost = INFINITY;
        for (size_t k = 0; k < n; k++) {
            double cost = 0;
            for (size_t i = 0; i < n; i++) {
                double u = m->prev[i].velocity;
                /* on the grid a front moves at its velocity less the
                 * frame's: in check's frame of v_pred the fronts stand,
                 * and a sample spacing of 10 predicted a lab-frame shift
                 * of one front spacing (n = 4: v_meas 0.997, v_pred 0.485) */
                double pred = m->prev[i].x + (isfinite(u) ? (u - m->p.frame_speed) * dt : 0.0);
                double e = wrap(m->cur[(i + k) % n].x - pred, S);
                cost += e * e;
            }
            if (cost < best_cost) {
                best_cost = cost;
                best = k;
            }
        }
        for (size_t i = 0; i < n; i++) m->tmp[i] = m->cur[(i + best) % n];
        const double *Xp = m->X + m->off[j - 1];
        double *Xc = m->X + m->nX;
        for (size_t i = 0; i < n; i++) Xc[i] = Xp[i] + wrap(m->tmp[i].x - m->prev[i].x, S);
        memcpy(m->cur, m->tmp, n * sizeof *m->cur);
    } else {
        double *Xc = m->X + m->nX;
        for (size_t i = 0; i < n; i++) Xc[i] = m->cur[i].x;
        if (r > 0) m->segment++;
        m->seg_start = r;
    }
    m->seg[j] = m->segment;
    m->off[j] = m->nX;
    size_t nm = 0;
    for (size_t i = 0; i < n; i++) nm += m->cur[i].rising;
    m->nminus[j] = nm;
    m->nplus[j] = n - nm;
    if (r == 0) {
        free(m->X0);
        m->X0 = n ? malloc(n * sizeof *m->X0) : NULL;
        if (n && !m->X0) goto nomem;
        if (n) memcpy(m->X0, m->X + m->nX, n * sizeof *m->X0);
        /* Displacements count from the reference's own fronts: counting from
         * the perturbed first sample would carry the perturbation's shift
         * of each front into every later deviation as a constant floor. */
        if (m->ref && n) {
            derivatives(m, m->ref);
            for (size_t i = 0; i < n; i++)
                m->X0[i] = reference_crossing(m, m->X0[i], m->cur[i].rising);
        }
    }
    bkf_measure_record *rc = &m->rec[j];
    rc->t = t;
    rc->fronts = n;
    rc->displacement = NAN;
    if (m->segment == 0 && n > 0) {
        double dsum = 0;
        for (size_t i = 0; i < n; i++) dsum += m->X[m->nX + i] - m->X0[i];
        rc->displacement = dsum / (double)n;
    }
    rc->deviation = NAN;
    if (m->ref && m->segment == 0) rc->deviation = deviation(m, psi, n ? rc->displacement : 0.0);
    m->nX += n;

    double mean = 0, mn = psi[0], mx = psi[0];
    for (size_t i = 0; i < N; i++) {
        mean += psi[i];
        mn = fmin(mn, psi[i]);
        mx = fmax(mx, psi[i]);
    }
    mean /= (double)N;
    double var = 0;
    for (size_t i = 0; i < N; i++) var += (psi[i] - mean) * (psi[i] - mean);
    rc->mean = mean;
    rc->variance = var / (double)N;
    rc->min = mn;
    rc->max = mx;
    size_t pi = m->p.probe;
    rc->probe = psi[pi];

    /* what the summary needs of every record, streamed */
    if (r == 0) {
        m->rec0 = *rc;
        if (m->bounded) m->tw = m->p.t_end - m->p.window * (m->p.t_end - t);
    }
    if (rc->fronts != m->rec0.fronts) m->count_constant = 0;
    if (isnan(rc->deviation)) m->dev_nan = 1;
    else m->dev_max = fmax(m->dev_max, rc->deviation);
    int in_window = !m->bounded || t >= m->tw;
    probe_point pp = {t, psi[pi], m->p.model.gamma * (eta[pi] - bkf_model_friction(psi[pi]))};
    if (probe_add(m, r, &pp, in_window)) goto nomem;
    if (m->bounded) {
        /* kept: the last record (tracking continues from it) and, in the
         * window, the current set of tracks (the speed fit) */
        if (in_window) {
            window_add(&m->win, rc, r, m->segment, nm, n - nm, m->p.model.nu,
                       0.5 * (m->tw + m->p.t_end));
            m->keep_from = m->seg_start > m->win.first_index ? m->seg_start : m->win.first_index;
        } else
            m->keep_from = r;
    }

    bkf_front *sw = m->prev;
    m->prev = m->cur;
    m->cur = sw;
    m->nprev = n;
    m->t_prev = t;
    m->nrec = r + 1;
    return BKF_OK;
nomem:
    return bkf_error_set(err, BKF_ENOMEM, "out of memory");
}

size_t bkf_measure_count(const bkf_measure *m) { return m ? m->nrec : 0; }

const bkf_measure_record *bkf_measure_record_at(const bkf_measure *m, size_t i)
{
    return m && i < m->nrec && i >= m->base ? &m->rec[i - m->base] : NULL;
}

/* ------------------------------------------------------------- summary */

/* Kept record r (absolute index >= base), its set of tracks, its positions. */
static const bkf_measure_record *rec_of(const bkf_measure *m, size_t r) { return &m->rec[r - m->base]; }
static size_t seg_of(const bkf_measure *m, size_t r) { return m->seg[r - m->base]; }
static const double *x_of(const bkf_measure *m, size_t r) { return m->X + m->off[r - m->base]; }

/* Least-squares slope of y against t, and its standard error. */
static void fit_line(const double *t, const double *y, size_t n, double *slope, double *se)
{
    double tm = 0, ym = 0;
    for (size_t i = 0; i < n; i++) {
        tm += t[i];
        ym += y[i];
    }
    tm /= (double)n;
    ym /= (double)n;
    double stt = 0, sty = 0;
    for (size_t i = 0; i < n; i++) {
        stt += (t[i] - tm) * (t[i] - tm);
        sty += (t[i] - tm) * (y[i] - ym);
    }
    double b = sty / stt, ss = 0;
    for (size_t i = 0; i < n; i++) {
        double e = y[i] - ym - b * (t[i] - tm);
        ss += e * e;
    }
    *slope = b;
    *se = n > 2 ? sqrt(ss / (double)(n - 2) / stt) : 0.0;
}

/* Mean slope over the tracks for records [a, b) of one segment. */
static int track_speeds(const bkf_measure *m, size_t a, size_t b, double *mean, double *se_rms,
                        double *spread, size_t *minus, size_t *plus)
{
    size_t n = rec_of(m, a)->fronts, len = b - a;
    if (n == 0 || len < 3) return -1;
    double *t = malloc(len * sizeof *t), *y = malloc(len * sizeof *y);
    if (!t || !y) {
        free(t);
        free(y);
        return -2;
    }
    for (size_t r = a; r < b; r++) t[r - a] = rec_of(m, r)->t;
    /* sums of the slopes' deviations from the first one: the textbook
     * sum2 - n mean^2 cancels to sqrt(eps) |v| when the slopes agree */
    double sum = 0, sum2 = 0, se2 = 0, first = 0;
    size_t mi = 0, pl = 0;
    for (size_t i = 0; i < n; i++) {
        for (size_t r = a; r < b; r++) y[r - a] = x_of(m, r)[i];
        double sl, se;
        fit_line(t, y, len, &sl, &se);
        if (i == 0) first = sl;
        sum += sl - first;
        sum2 += (sl - first) * (sl - first);
        se2 += se * se;
        if (sl < 0) mi++;
        else pl++;
    }
    free(t);
    free(y);
    double mu = sum / (double)n;
    *mean = first + mu;
    *se_rms = sqrt(se2 / (double)n);
    *spread = n > 1 ? sqrt(fmax(0.0, (sum2 - (double)n * mu * mu) / (double)(n - 1))) : 0.0;
    if (minus) *minus = mi;
    if (plus) *plus = pl;
    return 0;
}

static void period_at_probe(const bkf_measure *m, size_t first, bkf_measure_summary *s)
{
    s->period = s->period_err = NAN;
    s->period_multiplicity = 0;
    s->crossings = 0;
    size_t nc = 0;
    double *c = malloc((m->ncross ? m->ncross : 1) * sizeof *c);
    if (!c) return;
    for (size_t k = 0; k < m->ncross; k++)
        if (m->cross[k].r >= first) c[nc++] = m->cross[k].t;
    s->crossings = nc;
    if (nc < 3) {
        free(c);
        return;
    }
    size_t ni = nc - 1;
    double imean = (c[nc - 1] - c[0]) / (double)ni;
    for (size_t p = 1; p <= 4 && !s->period_multiplicity; p++) {
        if (ni < p + 1) break;
        double worst = 0;
        for (size_t k = 0; k + p < ni; k++)
            worst = fmax(worst, fabs((c[k + p + 1] - c[k + p]) - (c[k + 1] - c[k])));
        if (worst <= m->p.periodic_tol * imean) s->period_multiplicity = p;
    }
    size_t p = s->period_multiplicity ? s->period_multiplicity : 1;
    size_t K = ni / p;
    if (K < 1) {
        free(c);
        return;
    }
    s->period = (c[K * p] - c[0]) / (double)K;
    double v = 0;
    size_t cnt = 0;
    for (size_t k = 0; k + p < nc; k++) {
        double e = c[k + p] - c[k] - s->period;
        v += e * e;
        cnt++;
    }
    s->period_err = cnt > 1 ? sqrt(v / (double)(cnt - 1) / (double)cnt) : NAN;
    free(c);
}

/* Speed over records [a, b) of one segment: mean slope, its uncertainty
 * (see measure.h), the spread of the slopes.  Returns 0, or -1 when there
 * is nothing to fit. */
static int fit_records(const bkf_measure *m, size_t a, size_t b, double *speed, double *err,
                       double *spread_out, size_t *tracks, size_t *minus, size_t *plus)
{
    *speed = *err = NAN;
    if (spread_out) *spread_out = NAN;
    size_t n = rec_of(m, a)->fronts, len = b - a;
    double v, se, spread;
    size_t mi = 0, pl = 0;
    if (n == 0 || track_speeds(m, a, b, &v, &se, &spread, &mi, &pl) != 0) return -1;
    double va, vb, sea, seb, spa, spb, drift = 0;
    if (len >= 8 && track_speeds(m, a, a + len / 2, &va, &sea, &spa, NULL, NULL) == 0 &&
        track_speeds(m, a + len / 2, b, &vb, &seb, &spb, NULL, NULL) == 0)
        drift = va - vb;
    *speed = v;
    *err = sqrt((se * se + spread * spread) / (double)n + 0.25 * drift * drift);
    if (spread_out) *spread_out = spread;
    if (tracks) *tracks = n;
    if (minus) *minus = mi;
    if (plus) *plus = pl;
    return 0;
}

int bkf_measure_fit_speed(const bkf_measure *m, double t_from, double t_to, double *speed,
                          double *speed_err, size_t *tracks, bkf_error *err)
{
    if (!m || !speed || !speed_err) return bkf_error_set(err, BKF_EINPUT, "NULL argument");
    if (!isfinite(t_from) || !isfinite(t_to) || !(t_from < t_to))
        return bkf_error_set(err, BKF_EINPUT, "need finite t_from < t_to (have %g, %g)", t_from,
                             t_to);
    if (t_from <= m->t_dropped)
        return bkf_error_set(err, BKF_EINPUT,
                             "the records up to t = %g are not kept (t_end was given: only the "
                             "summary window's last set of tracks is)", m->t_dropped);
    size_t a = m->base;
    while (a < m->nrec && rec_of(m, a)->t < t_from) a++;
    size_t b = a;
    while (b < m->nrec && rec_of(m, b)->t <= t_to) b++;
    if (b - a < 3)
        return bkf_error_set(err, BKF_ENUMERIC, "fewer than 3 samples in [%g, %g]", t_from, t_to);
    if (seg_of(m, a) != seg_of(m, b - 1))
        return bkf_error_set(err, BKF_ENUMERIC,
                             "the front count changes in [%g, %g]: no single set of tracks",
                             t_from, t_to);
    if (fit_records(m, a, b, speed, speed_err, NULL, tracks, NULL, NULL) != 0)
        return bkf_error_set(err, BKF_ENUMERIC, "no fronts in [%g, %g]", t_from, t_to);
    return BKF_OK;
}

int bkf_measure_summarize(const bkf_measure *m, bkf_measure_summary *s, bkf_error *err)
{
    if (!m || !s) return bkf_error_set(err, BKF_EINPUT, "NULL argument");
    if (m->nrec < 2)
        return bkf_error_set(err, BKF_EINPUT, "at least two samples are needed, have %zu",
                             m->nrec);
    memset(s, 0, sizeof *s);
    size_t R = m->nrec;
    const bkf_measure_record *rl = rec_of(m, R - 1);
    s->samples = R;
    s->t_start = m->rec0.t;
    s->t_end = rl->t;
    /* The window: streamed when t_end was given, else summed here over the
     * records, in the same order. */
    window_acc wa, *w = &wa;
    if (m->bounded) {
        if (m->win.cnt == 0)
            return bkf_error_set(err, BKF_EINPUT,
                                 "the run stopped at t = %.9g, before its summary window (t >= "
                                 "%.9g, from t_end = %.9g) began", rl->t, m->tw, m->p.t_end);
        w = (window_acc *)&m->win;
    } else {
        double tw = s->t_end - m->p.window * (s->t_end - s->t_start);
        size_t first = 0;
        while (first < R - 1 && m->rec[first].t < tw) first++;
        memset(&wa, 0, sizeof wa);
        for (size_t r = first; r < R; r++)
            window_add(&wa, &m->rec[r], r, m->seg[r], m->nminus[r], m->nplus[r], m->p.model.nu,
                       0.5 * (tw + s->t_end));
    }
    size_t first = w->first_index;
    const bkf_measure_record *rf = &w->first;
    s->window_start = rf->t;

    s->fronts_start = m->rec0.fronts;
    s->fronts_end = rl->fronts;
    s->fronts_min = w->fronts_min;
    s->fronts_max = w->fronts_max;
    s->count_constant = m->count_constant;
    s->tracked_throughout = m->segment == 0 && s->fronts_start > 0;

    /* speed: the last segment, from the window start on */
    size_t a = m->seg_start;
    if (a < first) a = first;
    s->fit_start = rec_of(m, a)->t;
    fit_records(m, a, R, &s->speed, &s->speed_err, &s->speed_spread, &s->tracks,
                &s->moving_minus, &s->moving_plus);

    period_at_probe(m, first, s);

    /* window statistics */
    s->std_max = w->std_max;
    s->psi_min = w->psi_min;
    s->psi_max = w->psi_max;
    double slip_max = w->slip_max;
    size_t any_minus = w->any_minus, any_plus = w->any_plus;
    s->mean = w->msum / (double)w->cnt;
    s->variance = w->vsum / (double)w->cnt;
    s->slip_deviation_start = fmax(fabs(rf->max - m->p.model.nu), fabs(rf->min - m->p.model.nu));
    s->slip_deviation_end = fmax(fabs(rl->max - m->p.model.nu), fabs(rl->min - m->p.model.nu));

    s->deviation_start = m->rec0.deviation;
    s->deviation_mid = rf->deviation;
    s->deviation_end = rl->deviation;
    s->deviation_max = m->ref && !m->dev_nan ? m->dev_max : (double)NAN;
    s->deviation_growth = NAN;
    if (isfinite(s->deviation_mid) && isfinite(s->deviation_end) && s->deviation_mid > 0 &&
        s->deviation_end > 0 && rl->t > rf->t)
        s->deviation_growth = log(s->deviation_end / s->deviation_mid) / (rl->t - rf->t);

    /* regime */
    double range = s->psi_max - s->psi_min;
    int one_segment = w->first_seg == m->segment;
    /* settled: the window's halves alike in their mean spatial variance and
     * mean front count (a pattern still growing, decaying or coarsening is
     * not yet a regime) */
    int settled = w->half_cnt[0] > 0 && w->half_cnt[1] > 0;
    if (settled) {
        double va = w->half_vsum[0] / (double)w->half_cnt[0],
               vb = w->half_vsum[1] / (double)w->half_cnt[1],
               fa = w->half_fsum[0] / (double)w->half_cnt[0],
               fb = w->half_fsum[1] / (double)w->half_cnt[1];
        double tol = m->p.settled_tol;
        settled = fabs(va - vb) <= tol * fmax(va, vb) && fabs(fa - fb) <= tol * fmax(fa, fb);
    }
    s->settled = settled;
    if (slip_max <= m->p.slip_eps &&
        s->slip_deviation_end <= 1.01 * s->slip_deviation_start + 1e-12)
        s->regime = BKF_REGIME_CONTINUOUS_SLIP;
    else if (range > m->p.slip_eps && s->std_max <= m->p.uniform_eps * range)
        s->regime = BKF_REGIME_GLOBAL_OSCILLATION;
    else if (s->fronts_min == s->fronts_max && s->fronts_min >= 1 && one_segment &&
             isfinite(s->speed) && (s->moving_minus == 0 || s->moving_plus == 0) &&
             fabs(s->speed) > 10 * s->speed_err && s->speed_spread <= 1e-2 * fabs(s->speed) &&
             settled)
        s->regime = BKF_REGIME_FRONTS;
    else {
        int periodic = s->period_multiplicity > 0 && isfinite(s->period);
        int fronts = s->fronts_max >= 1 &&
                     ((any_minus > 0 && any_plus > 0) || s->fronts_min != s->fronts_max);
        int doubled = m->p.period_ref > 0
                          ? (s->period >= 1.5 * m->p.period_ref && s->period <= 2.5 * m->p.period_ref)
                          : s->period_multiplicity == 2;
        s->regime = periodic && fronts && doubled ? BKF_REGIME_PACEMAKERS
                    : settled                     ? BKF_REGIME_IRREGULAR
                                                  : BKF_REGIME_TRANSIENT;
    }
    return BKF_OK;
}

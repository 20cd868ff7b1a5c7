/* Hill's method as the train spectrum's first stage (trainspec.c's gather):
 * its candidates, and where its band vouches for its rightmost, the band
 * the meshes polish alone. */
#include "bkfront/hill.h"

#include <gsl/gsl_math.h>

#include <complex.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "hill_internal.h"
#include "trainspec_internal.h"

/* Hill's method (hill.h) sees every eigenvalue of a band of frequencies at
 * once, where the traced curves can step over one (two eigenvalues of one
 * class closer than the phase resolves; issue 31: n = 1 at mu 1.2 lost its
 * rightmost pair at Im 18.03 to its neighbour at 17.13) or cannot close
 * the window at all (the curves stay right of a_lo up to |Im| 1e4 when the
 * cycle's multiplier is near 1, mu < 1).  Its converged eigenvalues (M and
 * M + M/4 modes agree, bkf_hill_converged) are candidates: each is polished
 * on the Radau meshes, whose error estimate is the one reported, so Hill's
 * truncation never reaches a result.  The truncation's artefacts do not
 * converge (they move with M, at any height: 0.185 + 1.86i at M 24, mu 4).
 * Used where the profile is smooth enough for few modes (mu <= HILL_MU_MAX)
 * and the dense eigenproblems are cheap (HILL_WORK; HILL_GROW_WORK where
 * the curves could not answer and M grows). */
#define HILL_MU_MAX 6.0
#define HILL_MODES_MIN 16
#define HILL_MODES_MAX 64
/* the matrices' sizes cubed, summed over the classes, of the first round
 * (about 1.3 s of zgeev) and of all rounds where M grows (about 9 s: issue
 * 31's n = 1 at mu 4.9, refused for the trace's budget, converges at M 96) */
#define HILL_WORK 1.5e8
#define HILL_GROW_WORK 1e9
/* Hill's band stands alone only where the spectrum leaves it: in the
 * upper quarter of the band every eigenvalue lies left of the rightmost by
 * at least this share of the way to the window's edge a_lo (the traced
 * curves assume the same past their window's height, where they have left
 * it).  The band is the heights where M and the finer truncation agree to
 * HILL_BAND_TOL, plenty to place an eigenvalue left of that line: it
 * reaches higher than the candidates' HILL_CONVERGED (issue 31's n = 1 at
 * mu 4.9: 55 against 46 at M 120). */
#define HILL_DESCENT 0.05
#define HILL_BAND_TOL 1e-3


void trainspec_hill_stage_free(hill_stage *h)
{
    free(h->at);
    free(h->fine);
    free(h->conv);
}

static size_t hill_size(size_t M)
{
    return 2 * (2 * M + 1);
}

/* The finer truncation compared with M: a quarter more modes, a quarter of
 * the work of twice as many (the dense eigenproblem is cubic in the size);
 * the truncation's artefacts, tied to its top frequency, still move. */
static size_t finer(size_t M)
{
    return M + (M / 4 > 4 ? M / 4 : 4);
}

static double hill_cost(size_t M)
{
    return pow((double)hill_size(M), 3.0);
}

/* A class's candidates once the round cannot vouch for its band (an
 * earlier class left it incomplete, so the band's height, its descent and
 * this class's unconverged eigenvalues no longer matter): only the
 * eigenvalues right of a_lo that converge between M and Mf, and for those
 * the finer truncation's eigenvalue nearest each of M's right of a_lo
 * (inverse iteration, hill_nearest) answers what its whole spectrum did,
 * at a few LU factorisations for one QR.  A pair within HILL_CONVERGED is
 * converged, as in bkf_hill_converged; the candidate is the finer value.
 * Where more than NEAR_MAX of M's eigenvalues lie right of a_lo the whole
 * spectrum is cheaper (*done 0).  On the paper's table (n = 2..8, mu
 * 2.1-4.9) 4-24 of them do and none converges: the finer spectra were
 * a third of Hill's time. */
#define NEAR_MAX 10
static int near_candidates(ctx *x, double theta, size_t cls, const window *win, size_t M, size_t Mf,
                           const bkf_hill_eigenvalue *coarse, candidates *cs, hill_stage *h, double *top, int *done,
                           bkf_error *err)
{
    size_t n1 = hill_count(theta, M), count = 0;
    *done = 0;
    /* coarse is sorted by decreasing Re */
    while (count < n1 && coarse[count].re >= win->a_lo - HILL_CONVERGED) count++;
    if (count > NEAR_MAX) return BKF_OK;
    bkf_hill_eigenvalue near[NEAR_MAX];
    int rc = count ? hill_nearest(x->cycle, x->gamma, theta, Mf, coarse, count, near, err) : BKF_OK;
    if (rc != BKF_OK) return rc;
    /* an LU is a third of n^3 (the QR's cost is counted as n^3) */
    h->work += hill_cost(M) + (double)count * hill_cost(Mf) / 3.0;
    for (size_t i = 0, pushed = 0; i < count && pushed < HILL_PER_CLASS; i++) {
        double re = near[i].re, im = near[i].im;
        if (!(hypot(re - coarse[i].re, im - coarse[i].im) <= HILL_CONVERGED) || re < win->a_lo) continue;
        *top = fmax(*top, re);
        if (trainspec_cand_push(cs, (candidate){re, im, cls, -1, 0}) != BKF_OK)
            return bkf_error_set(err, BKF_ENOMEM, "out of memory");
        if (h->count < h->thetas * HILL_PER_CLASS) h->at[h->count++] = re + I * im;
        pushed++;
    }
    *done = 1;
    return BKF_OK;
}

/* One round of Hill's method: for the classes 0..classes/2 (their
 * conjugates come from the mirror, as for the traced curves), the
 * truncations at M and Mf compared (M's from the last round where it was
 * that round's finer one), the converged eigenvalues right of a_lo pushed
 * as candidates (HILL_PER_CLASS per class, the rightmost first), and
 * whether the band vouches for its rightmost (complete, descended). */
static int hill_round(ctx *x, size_t classes, const window *win, size_t M, size_t Mf, int near, candidates *cs,
                      hill_stage *h, bkf_error *err)
{
    /* per class at most this many (hill_count: fewer at theta = pi) */
    size_t n1 = hill_size(M), n2 = hill_size(Mf);
    int reuse = h->fine && h->modes_fine == M;
    bkf_hill_eigenvalue *coarse = malloc(n1 * sizeof *coarse);
    bkf_hill_eigenvalue *fine = malloc(h->thetas * n2 * sizeof *fine);
    /* every class's converged eigenvalues, for the band's height and descent */
    bkf_hill_eigenvalue *conv = realloc(h->conv, h->thetas * n2 * sizeof *conv);
    if (conv) h->conv = conv;
    if (!coarse || !fine || !conv) {
        free(coarse);
        free(fine);
        return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    }
    cs->count = 0;
    h->count = 0;
    h->modes = M;
    h->complete = 1;
    double top = -INFINITY;
    size_t n_conv = 0;
    int rc = BKF_OK;
    int partial = 0; /* a class's finer spectrum not solved (near_candidates) */
    for (size_t cls = 0; cls < h->thetas && rc == BKF_OK; cls++) {
        double theta = 2.0 * M_PI * (double)cls / (double)classes;
        size_t got = 0, found = 0, unresolved = 0, c1 = hill_count(theta, M), c2 = hill_count(theta, Mf);
        bkf_hill_eigenvalue *f = fine + cls * n2, *c = conv + n_conv;
        if (reuse) memcpy(coarse, h->fine + cls * n1, c1 * sizeof *coarse);
        else if ((rc = bkf_hill_spectrum(x->cycle, x->gamma, theta, M, coarse, &got, err)) != BKF_OK) break;
        if (near && !reuse && !h->complete) {
            int done = 0;
            rc = near_candidates(x, theta, cls, win, M, Mf, coarse, cs, h, &top, &done, err);
            if (rc != BKF_OK) break;
            if (done) {
                partial = 1;
                continue;
            }
        }
        if ((rc = bkf_hill_spectrum(x->cycle, x->gamma, theta, Mf, f, &got, err)) != BKF_OK) break;
        h->work += (reuse ? 0.0 : hill_cost(M)) + hill_cost(Mf);
        /* one more at class 0: the translation is among them */
        size_t k = HILL_PER_CLASS + (cls == 0);
        rc = bkf_hill_converged(coarse, c1, f, c2, HILL_CONVERGED, k, c, NULL, &found, &unresolved, err);
        if (rc != BKF_OK) break;
        if (unresolved > 0 || found == 0) h->complete = 0;
        for (size_t i = 0; i < found; i++) {
            double re = c[i].re, im = c[i].im;
            if ((cls == 0 && hypot(re, im) < 1e-6) || re < win->a_lo) continue;
            top = fmax(top, re);
            if (trainspec_cand_push(cs, (candidate){re, im, cls, -1, 0}) != BKF_OK) {
                rc = bkf_error_set(err, BKF_ENOMEM, "out of memory");
                break;
            }
            if (h->count < h->thetas * HILL_PER_CLASS) h->at[h->count++] = re + I * im;
        }
        if (rc == BKF_OK)
            rc = bkf_hill_converged(coarse, c1, f, c2, HILL_BAND_TOL, c2, c, NULL, &found, NULL, err);
        n_conv += rc == BKF_OK ? found : 0;
    }
    if (rc == BKF_OK) {
        free(h->fine);
        /* a class without its finer spectrum: the next round solves its
         * coarse one itself */
        h->fine = partial ? NULL : fine;
        if (!partial) fine = NULL;
        h->modes_fine = Mf;
        h->y_trust = 0.0;
        for (size_t i = 0; i < n_conv; i++) h->y_trust = fmax(h->y_trust, fabs(conv[i].im));
        double upper = -INFINITY;
        for (size_t i = 0; i < n_conv; i++)
            if (fabs(conv[i].im) >= 0.75 * h->y_trust) upper = fmax(upper, conv[i].re);
        double edge = isfinite(top) ? top - HILL_DESCENT * (top - win->a_lo) : win->a_lo;
        h->descended = upper < edge - HILL_BAND_TOL;
    }
    free(coarse);
    free(fine);
    return rc;
}

/* Hill's first round, at M modes reaching the height where the trace
 * starts (within [HILL_MODES_MIN, HILL_MODES_MAX] and HILL_WORK), and
 * finer(M). */
int trainspec_hill_candidates(ctx *x, size_t classes, const window *win, candidates *cs, hill_stage *h,
                           bkf_error *err)
{
    memset(h, 0, sizeof *h);
    if (x->mu > HILL_MU_MAX) return BKF_OK;
    h->thetas = classes / 2 + 1;
    /* modes to |Im sigma| ~ the band the trace starts with, beyond which the
     * spectrum is in its asymptotic regime (trace_all): mode m sits near
     * |Im sigma| = 2 pi m / (T s) */
    double band = fmax(2.0, x->gamma * x->v / x->c);
    double want = ceil(band * x->T * x->s / (2.0 * M_PI));
    size_t M = (size_t)fmin(fmax(want, HILL_MODES_MIN), HILL_MODES_MAX);
    double th = (double)h->thetas;
    while (M > HILL_MODES_MIN && th * (hill_cost(M) + hill_cost(finer(M))) > HILL_WORK) M = M * 3 / 4;
    if (th * (hill_cost(M) + hill_cost(finer(M))) > HILL_WORK) return BKF_OK;
    h->at = malloc(h->thetas * HILL_PER_CLASS * sizeof *h->at);
    if (!h->at) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    return hill_round(x, classes, win, M, finer(M), 1, cs, h, err);
}

/* Where the curves could not answer: M grown by a quarter (the last finer
 * truncation the next coarse one) until the band vouches for its rightmost
 * or the next round would pass HILL_GROW_WORK. */
int trainspec_hill_grow(ctx *x, size_t classes, const window *win, candidates *cs, hill_stage *h, bkf_error *err)
{
    int rc = BKF_OK;
    while (rc == BKF_OK && !(h->complete && h->descended)) {
        size_t M = h->modes_fine, Mf = finer(M);
        /* a smaller work budget than the default bounds Hill's growth alike */
        double limit = HILL_GROW_WORK * fmin(1.0, x->max_work / MAX_WORK_DEFAULT);
        if (Mf > BKF_HILL_MODES_MAX || h->work + (double)h->thetas * hill_cost(Mf) > limit) break;
        rc = hill_round(x, classes, win, M, Mf, 0, cs, h, err);
    }
    return rc;
}

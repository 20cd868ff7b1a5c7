/* Spectra of front trains by the monodromy of the shifted variational
 * equation (see trainspec.h and docs/numerics.md, "Spectra of front trains"). */
#include "bkfront/trainspec.h"

#include "bkfront/cycle.h"
#include "bkfront/hill.h"
#include "bkfront/options.h"

#include <gsl/gsl_math.h>

#include <complex.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "trainspec_internal.h"

/* ------------------------------------------------------------- polishing */

/* Newton on w(sigma) = i theta (mod 2 pi i), over whichever family fits
 * best, on mesh m.  With deriv (NULL: not wanted) holding both families'
 * derivatives from a polish of the same eigenvalue on a coarser mesh, the
 * steps take those instead of a pass with the derivative (which costs two
 * without it): the derivatives of two meshes differ by the meshes' error,
 * so the iteration contracts by about that much per step and stops on the
 * same small step as Newton's; where it does not settle within CHORD_MAX
 * steps, Newton takes over.  The derivatives last computed go back into
 * deriv. */
#define CHORD_MAX 4
int trainspec_polish(ctx *x, const mesh *m, double theta, double complex *sigma, double *last_step,
                     double complex deriv[2])
{
    double complex s = *sigma;
    *last_step = INFINITY;
    int chord = deriv && deriv[0] != 0 && deriv[1] != 0 && isfinite(creal(deriv[0])) &&
                isfinite(cimag(deriv[0])) && isfinite(creal(deriv[1])) && isfinite(cimag(deriv[1]));
    for (int it = 0, chords = 0; it < NEWTON_MAX; it++) {
        double complex w0[2], dw[2];
        int use_chord = chord && chords < CHORD_MAX;
        if (use_chord) {
            trainspec_monodromy(x, m, s, w0, NULL);
            dw[0] = deriv[0], dw[1] = deriv[1];
            chords++;
        } else {
            trainspec_monodromy(x, m, s, w0, dw);
            if (deriv) deriv[0] = dw[0], deriv[1] = dw[1];
        }
        int fam = 0;
        double complex r[2];
        for (int f = 0; f < FAMILIES; f++) r[f] = creal(w0[f]) + I * trainspec_wrap(cimag(w0[f]) - theta);
        if (cabs(r[1]) < cabs(r[0])) fam = 1;
        if (dw[fam] == 0 || !isfinite(creal(dw[fam])) || !isfinite(cimag(dw[fam]))) return BKF_ENUMERIC;
        double complex step = r[fam] / dw[fam];
        if (cabs(step) > 0.5) step *= 0.5 / cabs(step);
        s -= step;
        *last_step = cabs(step);
        if (!isfinite(creal(s)) || !isfinite(cimag(s))) return BKF_ENUMERIC;
        if (*last_step < 1e-4 * x->tol) break;
    }
    *sigma = s;
    return *last_step < 1e-2 * x->tol ? BKF_OK : BKF_ENUMERIC;
}

static int by_a_desc(const void *pa, const void *pb)
{
    const candidate *a = pa, *b = pb;
    if (a->cls != b->cls) return a->cls < b->cls ? -1 : 1;
    return (a->a < b->a) - (a->a > b->a);
}

static int eig_desc(const void *pa, const void *pb)
{
    const bkf_trainspec_eigenvalue *a = pa, *b = pb;
    if (a->j != b->j) return a->j < b->j ? -1 : 1;
    return (a->re < b->re) - (a->re > b->re);
}

/* ------------------------------------------------------------------ api */

bkf_trainspec_options bkf_trainspec_options_default(void)
{
    return (bkf_trainspec_options){.tol = 1e-6, .per_kappa = 3, .max_work = 0, .cancel = NULL};
}

const char *bkf_trainspec_verdict_name(bkf_trainspec_verdict v)
{
    switch (v) {
    case BKF_TRAINSPEC_STABLE: return "yes";
    case BKF_TRAINSPEC_UNSTABLE: return "no";
    default: return "unresolved";
    }
}

int bkf_trainspec_check(const bkf_model_params *p, const bkf_trainspec_train *t,
                        const bkf_trainspec_options *o, bkf_error *err)
{
    if (!p || !t) return bkf_error_set(err, BKF_EINPUT, "parameters and train are required");
    int rc;
    if ((rc = bkf_model_check_positive("gamma", p->gamma, err)) != BKF_OK) return rc;
    if ((rc = bkf_model_check_positive("S", p->S, err)) != BKF_OK) return rc;
    if ((rc = bkf_model_check_nu_active(p->nu, err)) != BKF_OK) return rc;
    if (!(p->c > 0.0) || !isfinite(p->c))
        return bkf_error_set(err, BKF_EINPUT,
                             "c must be finite and > 0 for a spectrum (with c = 0 the fronts are phase waves "
                             "of uncoupled oscillators: every mode is neutral)");
    if (t->n < 1) return bkf_error_set(err, BKF_EINPUT, "n must be >= 1");
    if (!(t->v > p->c) || !isfinite(t->v))
        return bkf_error_set(err, BKF_EINPUT, "v must be finite and > c = %.15g (fronts are supersonic)", p->c);
    if (o) {
        if (!(o->tol >= TOL_MIN && o->tol <= TOL_MAX))
            return bkf_error_set(err, BKF_EINPUT, "tol must be in [%g, %g]", TOL_MIN, TOL_MAX);
        if (o->per_kappa > PER_KAPPA_MAX)
            return bkf_error_set(err, BKF_EINPUT, "per_kappa must be in [0, %d] (0: the rightmost alone)",
                                 PER_KAPPA_MAX);
        if (o->max_work != 0 && !(o->max_work >= 1e5 && o->max_work <= 1e12))
            return bkf_error_set(err, BKF_EINPUT, "max_work must be 0 (default) or in [1e5, 1e12]");
    }
    return BKF_OK;
}

void trainspec_ctx_free(ctx *x)
{
    trainspec_mesh_free(&x->coarse);
    trainspec_mesh_free(&x->fine);
    bkf_cycle_free(x->cycle);
    free(x->nodes);
    free(x->need);
    free(x->stiff);
}

int trainspec_ctx_init(ctx *x, const bkf_model_params *p, const bkf_trainspec_train *t, double tol,
                    const bkf_trainspec_options *o, bkf_error *err)
{
    memset(x, 0, sizeof *x);
    x->max_work = o && o->max_work > 0 ? o->max_work : MAX_WORK_DEFAULT;
    x->cancel = o ? o->cancel : NULL;
    x->gamma = p->gamma;
    x->c = p->c;
    x->nu = p->nu;
    x->S = p->S;
    x->n = t->n;
    x->v = t->v;
    x->tol = tol;
    x->s = sqrt((t->v - p->c) * (t->v + p->c)) / t->v;
    x->mu = p->gamma / x->s;
    x->beta = (p->c / t->v) * (p->c / t->v) / (x->s * x->s);
    x->L = p->S / (double)t->n;
    x->cycle = bkf_cycle_alloc();
    if (!x->cycle) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    bkf_cycle_options co = bkf_cycle_options_default();
    co.tol = 1e-12;
    /* The Radau meshes subdivide the cycle's own steps (bkf_cycle_mesh).
     * bd2x2, the stiff default since issue 20, takes longer steps than
     * bsimp: on n = 12 (mu 47) 4 substeps a step were then pre-asymptotic
     * (convergence ratio 23 against fifth order's 32); the meshes keep
     * bsimp's steps, for which the substep counts were measured, and
     * rk8pd's up to mu 30 as before bd2x2 took over from mu 20. */
    co.stepper = x->mu > BKF_CYCLE_EXPLICIT_MU_MAX ? BKF_STEPPER_IMPLICIT : BKF_STEPPER_EXPLICIT;
    int rc = bkf_cycle_solve(x->cycle, x->mu, x->nu, &co, err);
    if (rc != BKF_OK) return rc;
    const bkf_cycle_result *cr = bkf_cycle_get(x->cycle);
    x->T = cr->period;
    x->log_m = cr->log_multiplier;
    size_t count = bkf_cycle_mesh(x->cycle, NULL, 0);
    x->nodes = malloc((count + 1) * sizeof *x->nodes);
    if (!x->nodes) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    bkf_cycle_mesh(x->cycle, x->nodes, count);
    x->nodes[count] = x->T;
    x->node_count = count + 1;
    x->substeps = SUBSTEPS_START;
    x->re_floor = -2.0 * WINDOW_DEPTH * x->gamma;
    return BKF_OK;
}

/* ------------------------------------------------- Hill's stage (trainspec_hill.c) */

/* Hill's band alone: the meshes for its height, no curves. */
static int band_alone(ctx *x, const hill_stage *hs, window *win, double a_hi, double *y_max, int *fallback,
                      bkf_error *err)
{
    *fallback = 1;
    x->stop = 0;
    *y_max = hs->y_trust;
    win->a_hi = a_hi;
    x->substeps = SUBSTEPS_START;
    return trainspec_meshes_for(x, hs->y_trust, win, err);
}

/* The candidates of every class: Hill's where it is cheap; where Hill's
 * first round vouches for its band (and no more than HILL_PER_CLASS - 1
 * are asked per class), Hill's band alone; else the traced curves', and
 * where the trace cannot close its window, Hill's band alone, M grown
 * until it vouches (*fallback set; trace_err says why the trace failed). */
static int gather(ctx *x, size_t classes, size_t keep, window *win, candidates *cs, hill_stage *hs, double *y_max,
                  size_t *curve_points, int *fallback, bkf_error *trace_err, bkf_error *err)
{
    *fallback = 0;
    int rc = trainspec_hill_candidates(x, classes, win, cs, hs, err);
    if (rc != BKF_OK) return rc;
    double a_hi = win->a_hi;
    if (hs->modes && hs->complete && hs->descended && keep < HILL_PER_CLASS) {
        bkf_error_set(trace_err, BKF_OK, "not traced: Hill's band vouched for its rightmost");
        return band_alone(x, hs, win, a_hi, y_max, fallback, err);
    }
    double max_work = x->max_work;
    /* where Hill has answered the trace is the cross-check: it may spend a
     * fifth of the budget, the rest polishes */
    if (hs->modes) x->max_work = x->work + HILL_TRACE_SHARE * (max_work - x->work);
    rc = trainspec_curves(x, classes, win, cs, y_max, curve_points, trace_err);
    x->max_work = max_work;
    if (rc != BKF_OK && rc != BKF_ENOMEM && x->stop != BKF_ECANCELED && hs->modes) {
        int hrc = trainspec_hill_grow(x, classes, win, cs, hs, err);
        if (hrc != BKF_OK) return hrc;
    }
    if (rc != BKF_OK && rc != BKF_ENOMEM && x->stop != BKF_ECANCELED && hs->modes && hs->complete &&
        hs->descended)
        return band_alone(x, hs, win, a_hi, y_max, fallback, err);
    if (rc != BKF_OK && err) *err = *trace_err;
    return rc;
}

/* A class polishes at most this many times polish_n of the curves'
 * candidates (the rightmost first): the rest lie left of those and are
 * reached only where many of them fail or repeat one eigenvalue. */
#define POLISH_TRIES 2

/* Does the polish try candidate c, the tried-th of its class's curve
 * candidates (Hill's are all tried, see polish_candidates)? */
static int polish_tries(const candidate *c, size_t classes, size_t polish_n, size_t *tried)
{
    if (2 * c->cls > classes) return 0;
    return c->fam < 0 || (*tried)++ < POLISH_TRIES * polish_n;
}

/* The meshes of the polish, for the |sigma| of the candidates it may polish
 * rather than for the window's height: the window reaches |sigma| 2.8 at the
 * paper's n = 12 (mu 47) where its eigenvalues sit below 0.13, and a mesh
 * for the window's reach has about twice the steps.  Each value's error is
 * still its own pair of meshes' (estimate), so a candidate the meshes
 * resolve less well shows it in its estimate and the refinement. */
static int meshes_for_polish(ctx *x, size_t classes, size_t polish_n, candidates *cs, bkf_error *err)
{
    /* no candidate (items may then be NULL, which qsort may not take) */
    if (cs->count) qsort(cs->items, cs->count, sizeof *cs->items, by_a_desc);
    double reach = 0.0;
    for (size_t i = 0; i < cs->count;) {
        size_t cls = cs->items[i].cls, tried = 0;
        for (; i < cs->count && cs->items[i].cls == cls; i++)
            if (polish_tries(&cs->items[i], classes, polish_n, &tried))
                reach = fmax(reach, hypot(cs->items[i].a, cs->items[i].y));
    }
    reach = POLISH_MARGIN * reach + POLISH_REACH_MIN;
    int rc = BKF_OK;
    if (reach < x->sigma_reach) {
        rc = trainspec_mesh_needs(x, reach, err);
        if (rc == BKF_OK) rc = trainspec_mesh_build(x, x->substeps, &x->coarse, err);
    }
    return rc != BKF_OK ? rc : trainspec_mesh_build(x, 2 * x->substeps, &x->fine, err);
}

/* A candidate further left of its class's keep-th polished value than
 * this (relative to that value, and absolute) is not polished: the
 * candidates' distance from their coarse values was at most 0.05 |Re| +
 * 2.2e-3 (1.1 times it) in 17587 polishes on the paper's table and ten
 * random sets (mu 0.56-462), a quarter of this. */
#define POLISH_SKIP_REL 0.2
#define POLISH_SKIP_ABS 0.01
static double polish_cut(double kth)
{
    return kth - (POLISH_SKIP_REL * fabs(kth) + POLISH_SKIP_ABS);
}
/* ... and a coarse value further left of it than this many times the
 * largest coarse-fine difference of the spectrum's polishes so far
 * (plus 10 tol) is not polished on the fine mesh. */
#define POLISH_SKIP_COARSE 8.0


/* The translation's eigenvalue (sigma = 0 in class 0), as the polish
 * lands on it: flagged by translation(), left out of every rightmost. */
static int near_translation(const ctx *x, size_t cls, double re, double im)
{
    return cls == 0 && hypot(re, im) < 10.0 * x->tol;
}

/* The keep-th largest Re sigma of eig[from..to) (-inf while fewer), the
 * translation aside: the cut reports it besides the keep, never instead of
 * one (counted, it let class 0's rightmost -3.3e-4 be skipped as left of
 * the translation's 1.5e-10). */
static double kth_re(const ctx *x, const bkf_trainspec_eigenvalue *eig, size_t from, size_t to, size_t keep)
{
    double top[PER_KAPPA_MAX + 1];
    size_t n = 0;
    for (size_t k = from; k < to; k++) {
        if (near_translation(x, eig[k].j, eig[k].re, eig[k].im)) continue;
        size_t at = n < keep ? n++ : keep;
        while (at > 0 && top[at - 1] < eig[k].re) {
            if (at < keep) top[at] = top[at - 1];
            at--;
        }
        if (at < keep) top[at] = eig[k].re;
    }
    return n == keep ? top[keep - 1] : -INFINITY;
}

/* The first candidate of each class of cs (sorted by by_a_desc), the
 * classes by their best candidate's a, descending: the rightmost alone
 * (per_kappa 0) polishes the likeliest rightmost first, and the classes
 * left of it are cut at it (polish_candidates).  NULL when out of memory:
 * then in cs's order, the same values at more cost. */
static size_t *class_order(const candidates *cs)
{
    size_t *first = malloc((cs->count ? cs->count : 1) * sizeof *first), n = 0;
    for (size_t i = 0; first && i < cs->count; i++)
        if (i == 0 || cs->items[i].cls != cs->items[i - 1].cls) {
            size_t at = n++;
            while (at > 0 && cs->items[first[at - 1]].a < cs->items[i].a) first[at] = first[at - 1], at--;
            first[at] = i;
        }
    return first;
}

/* The best few candidates of each class polished on both meshes into eig
 * (*n_eig of them), duplicates dropped; mirrored classes (j > classes/2)
 * come out of their partners by conjugation later.  How many are polished
 * per class does not depend on how many are reported: the rightmost must
 * not depend on per_kappa.  Once a class has keep values, a candidate
 * that lies left of the keep-th by more than a candidate's distance from
 * its eigenvalue (POLISH_SKIP_*) is not polished, and a coarse value left
 * of it by more than the coarse mesh's error (8 times the largest
 * coarse-fine difference seen, POLISH_SKIP_COARSE) not on the fine mesh:
 * the cut to keep per class would drop either whatever its value, and
 * those polishes were most of the polish (paper table: 5 per class polished
 * for 1 reported). */
static void polish_candidates(ctx *x, size_t classes, size_t keep, int rightmost, candidates *cs,
                              bkf_trainspec_eigenvalue *eig, derivs *dv, size_t *n_eig)
{
    size_t polish_n = (keep > 3 ? keep : 3) + 2;
    double coarse_err = 0.0;
    if (cs->count) qsort(cs->items, cs->count, sizeof *cs->items, by_a_desc);
    size_t *order = rightmost ? class_order(cs) : NULL, n_cls = 0;
    for (size_t i = 0; i < cs->count; i++) n_cls += i == 0 || cs->items[i].cls != cs->items[i - 1].cls;
    for (size_t c = 0, i = 0; c < n_cls; c++) {
        if (order) i = order[c];
        size_t cls = cs->items[i].cls, taken = 0, tried = 0, start_n = *n_eig;
        for (; i < cs->count && cs->items[i].cls == cls; i++) {
            /* Hill's candidates are few and accurate: every one is polished,
             * whatever the traced ones, whose interpolated a can rank a far
             * eigenvalue before a near one, have taken */
            if ((taken >= polish_n && cs->items[i].fam >= 0) || !polish_tries(&cs->items[i], classes, polish_n, &tried))
                continue;
            candidate cd = cs->items[i];
            double kth = kth_re(x, eig, start_n, *n_eig, keep);
            /* the rightmost alone: every class's values cut as the keep-th of
             * its own would be, at the rightmost of all so far */
            if (rightmost) kth = fmax(kth, kth_re(x, eig, 0, *n_eig, 1));
            if (cd.a < polish_cut(kth)) continue;
            double theta = 2.0 * M_PI * (double)cls / (double)classes;
            double complex sc = cd.a + I * cd.y, sf, d[2] = {NAN, NAN};
            double step_c, step_f;
            if (trainspec_polish(x, &x->coarse, theta, &sc, &step_c, d) != BKF_OK) continue;
            /* one eigenvalue reached again on the same mesh: the same value to
             * Newton's last step, no fine polish needed to tell */
            int seen = 0;
            for (size_t k = start_n; k < *n_eig; k++)
                if (cabs(dv[k].coarse - sc) < 10.0 * x->tol) seen = 1;
            if (seen) continue;
            if (creal(sc) < kth - (POLISH_SKIP_COARSE * coarse_err + 10.0 * x->tol)) continue;
            sf = sc;
            if (trainspec_polish(x, &x->fine, theta, &sf, &step_f, d) != BKF_OK) continue;
            coarse_err = fmax(coarse_err, cabs(sf - sc));
            double e = trainspec_estimate(sc, sf, step_f);
            int dup = 0;
            for (size_t k = start_n; k < *n_eig; k++)
                if (cabs((eig[k].re + I * eig[k].im) - sf) < 10.0 * fmax(e, x->tol)) dup = 1;
            if (dup) continue;
            dv[*n_eig].d[0] = d[0], dv[*n_eig].d[1] = d[1], dv[*n_eig].coarse = sc;
            eig[(*n_eig)++] = (bkf_trainspec_eigenvalue){creal(sf), cimag(sf), e, cls, 0.0, 0};
            taken++;
        }
    }
    free(order);
}

/* The translation mode, polished from 0 where the candidates missed it:
 * the gauge.  Where the traced curves missed it the meshes are too coarse. */
static void translation(ctx *x, bkf_trainspec_eigenvalue *eig, derivs *dv, size_t *n_eig)
{
    size_t k = 0;
    while (k < *n_eig && !near_translation(x, eig[k].j, eig[k].re, eig[k].im)) k++;
    if (k == *n_eig) {
        double complex sc = 0.0, sf, *d = dv[*n_eig].d;
        double step_c, step_f = INFINITY;
        d[0] = d[1] = NAN;
        int ok = trainspec_polish(x, &x->coarse, 0.0, &sc, &step_c, d) == BKF_OK;
        sf = sc;
        ok = ok && trainspec_polish(x, &x->fine, 0.0, &sf, &step_f, d) == BKF_OK;
        eig[(*n_eig)++] = (bkf_trainspec_eigenvalue){creal(sf), cimag(sf), ok ? trainspec_estimate(sc, sf, step_f) : INFINITY,
                                                     0, 0.0, 0};
    }
    eig[k].translation = 1;
}

/* Does eigenvalue k still need a finer mesh: its estimate above tol, or
 * (the translation) its distance from 0. */
static int unsettled(const ctx *x, const bkf_trainspec_eigenvalue *e)
{
    return e->err > x->tol || (e->translation && hypot(e->re, e->im) > x->tol);
}

/* Eigenvalues that the cut to `keep` per class will drop whatever their
 * errors are dropped before the refinement, which would otherwise refine
 * the mesh for them alone: those with keep + 1 others of their class right
 * of them beyond both errors (the cut keeps one beyond `keep` only as the
 * conjugate of the keep-th, and one further would be that one's conjugate,
 * the keep-th's own value: a duplicate). */
static void drop_hidden(bkf_trainspec_eigenvalue *eig, derivs *dv, size_t *n_eig, size_t keep)
{
    size_t w = 0;
    for (size_t i = 0; i < *n_eig; i++) {
        size_t right = 0;
        for (size_t k = 0; k < *n_eig; k++)
            right += k != i && eig[k].j == eig[i].j && !eig[k].translation &&
                     eig[k].re - eig[k].err > eig[i].re + eig[i].err;
        if (eig[i].translation || right < keep + 1) dv[w] = dv[i], eig[w++] = eig[i];
    }
    *n_eig = w;
}

/* The rightmost alone (per_kappa 0): the eigenvalues that lie left of
 * another beyond both errors can be no rightmost whatever the finer meshes
 * make of them, and are dropped (with on, their meshes in refine) before
 * each refinement, which then refines the mesh for the others alone (the
 * paper's n = 12: 3 of 12 polished on its two finer meshes).  The
 * translation stays: it gauges the mesh. */
static void drop_dominated(bkf_trainspec_eigenvalue *eig, derivs *dv, size_t *on, size_t *n_eig)
{
    double left = -INFINITY; /* the largest Re sigma - err */
    for (size_t k = 0; k < *n_eig; k++)
        if (!eig[k].translation) left = fmax(left, eig[k].re - eig[k].err);
    size_t w = 0;
    for (size_t i = 0; i < *n_eig; i++)
        if (eig[i].translation || !(eig[i].re + eig[i].err < left)) {
            dv[w] = dv[i], on[w] = on[i];
            eig[w++] = eig[i];
        }
    *n_eig = w;
}

/* The mesh refined until every estimate meets tol and the translation
 * mode sits at 0 within it.  Each refinement halves every step: the new
 * coarse mesh is the old fine one, on which the values in hand were
 * polished, so only the fine polish is redone, and only for the
 * eigenvalues whose estimate is still above tol (the others keep theirs). */
static int refine(ctx *x, size_t classes, int rightmost, bkf_trainspec_eigenvalue *eig, derivs *dv, size_t *count,
                  bkf_error *err)
{
    size_t n_eig = *count;
    /* per eigenvalue, the substeps of the fine mesh its value was polished on */
    size_t *on = malloc((n_eig ? n_eig : 1) * sizeof *on);
    if (!on) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    for (size_t k = 0; k < n_eig; k++) on[k] = 2 * x->substeps;
    int rc = BKF_OK;
    for (int r = 0;; r++) {
        if (rightmost) drop_dominated(eig, dv, on, &n_eig);
        double worst = 0.0;
        for (size_t k = 0; k < n_eig; k++) {
            worst = fmax(worst, eig[k].err);
            if (eig[k].translation) worst = fmax(worst, hypot(eig[k].re, eig[k].im));
        }
        if (worst <= x->tol) break;
        /* the profile's share no mesh reduces: refused at once, saying so */
        double floor = 0.0, at = 0.0;
        for (size_t k = 0; k < n_eig; k++) {
            double mod = hypot(eig[k].re, eig[k].im), share = PROFILE_ERROR * fmax(1.0, mod);
            if (share > floor) floor = share, at = mod;
        }
        if (floor > x->tol) {
            rc = bkf_error_set(err, BKF_ETOL,
                               "spectrum: the profile's own error (%.2g per unit |sigma|, the cycle solved to "
                               "1e-12) is %.3g at |sigma| %.4g, above tol %.3g",
                               PROFILE_ERROR, floor, at, x->tol);
            break;
        }
        if (r == MESH_REFINEMENTS) {
            rc = bkf_error_set(err, BKF_ETOL,
                               "spectrum: an eigenvalue's estimated error %.3g exceeds tol %.3g at %zu "
                               "steps per period",
                               worst, x->tol, x->fine.steps);
            break;
        }
        x->substeps *= 2;
        mesh t = x->coarse;
        x->coarse = x->fine;
        x->fine = t;
        if ((rc = trainspec_mesh_build(x, 2 * x->substeps, &x->fine, err)) != BKF_OK) break;
        for (size_t k = 0; k < n_eig; k++) {
            if (!unsettled(x, &eig[k])) continue;
            double theta = 2.0 * M_PI * (double)eig[k].j / (double)classes;
            double complex sc = eig[k].re + I * eig[k].im, sf;
            double step_c = 0.0, step_f;
            if (on[k] != x->substeps && trainspec_polish(x, &x->coarse, theta, &sc, &step_c, dv[k].d) != BKF_OK)
                continue;
            sf = sc;
            if (trainspec_polish(x, &x->fine, theta, &sf, &step_f, dv[k].d) != BKF_OK) continue;
            eig[k].re = creal(sf);
            eig[k].im = cimag(sf);
            eig[k].err = trainspec_estimate(sc, sf, step_f);
            on[k] = 2 * x->substeps;
        }
    }
    free(on);
    *count = n_eig;
    return rc;
}

/* The conjugates of the classes 0 < j < classes/2 as the classes
 * classes - j, all sorted, and `keep` per class kept. */
static void mirror_and_cut(size_t classes, size_t keep, bkf_trainspec_eigenvalue *eig, size_t *count)
{
    size_t n_eig = *count;
    for (size_t k = 0, polished = n_eig; k < polished; k++)
        if (eig[k].j > 0 && 2 * eig[k].j < classes) {
            eig[n_eig] = eig[k];
            eig[n_eig].j = classes - eig[k].j;
            eig[n_eig++].im = -eig[k].im;
        }
    qsort(eig, n_eig, sizeof *eig, eig_desc);
    size_t w = 0;
    for (size_t i = 0; i < n_eig; i++) {
        size_t same = 0;
        /* the translation is reported besides the `keep`, never instead of one
         * (with keep 1 it took class 0's only place: issue 31's window edge
         * -0.203 printed for sigma_max -4.08e-4) */
        for (size_t k = 0; k < w; k++) same += eig[k].j == eig[i].j && !eig[k].translation;
        /* a conjugate pair (j = 0 or n/2) is never split by the cut */
        int partner = w > 0 && eig[w - 1].j == eig[i].j &&
                      fabs(eig[w - 1].re - eig[i].re) <= eig[w - 1].err + eig[i].err &&
                      fabs(eig[w - 1].im + eig[i].im) <= eig[w - 1].err + eig[i].err && eig[i].im != 0.0;
        if (same < keep || eig[i].translation || partner) eig[w++] = eig[i];
    }
    *count = w;
}

/* Hill's band alone: its rightmost eigenvalue must be one the meshes
 * confirm, else the band's candidates were not converged. */
static int confirm_band(const hill_stage *hs, const bkf_trainspec_eigenvalue *eig, size_t n_eig,
                        const bkf_error *trace_err, bkf_error *err)
{
    double complex top = NAN;
    for (size_t k = 0; k < n_eig; k++)
        if (!eig[k].translation && !(creal(top) >= eig[k].re)) top = eig[k].re + I * eig[k].im;
    double miss = INFINITY;
    for (size_t k = 0; k < hs->count; k++) miss = fmin(miss, cabs(hs->at[k] - conj(top)));
    for (size_t k = 0; k < hs->count; k++) miss = fmin(miss, cabs(hs->at[k] - top));
    if (isfinite(creal(top)) && !(miss <= HILL_AGREE * (1.0 + cabs(top))))
        return bkf_error_set(err, BKF_ETOL,
                             "spectrum: Hill's method at %zu modes and the Radau meshes disagree on the "
                             "rightmost eigenvalue by %.3g (%s)",
                             hs->modes, miss, trace_err->message);
    return BKF_OK;
}

/* The rightmost polished value of class cls but the translation (re -inf
 * when none), and its error. */
static double class_top(const ctx *x, const bkf_trainspec_eigenvalue *eig, size_t n_eig, size_t cls,
                        double *err)
{
    double top = -INFINITY;
    *err = 0.0;
    for (size_t k = 0; k < n_eig; k++)
        if (eig[k].j == cls && !near_translation(x, cls, eig[k].re, eig[k].im) && eig[k].re > top)
            top = eig[k].re, *err = eig[k].err;
    return top;
}

int trainspec_hill_validate(ctx *x, size_t classes, size_t modes, double floor, const candidates *cs,
                            bkf_trainspec_eigenvalue *eig, derivs *dv, size_t *n_eig, bkf_error *err)
{
    for (size_t i = 0; i < cs->count; i++) {
        const candidate *c = &cs->items[i];
        double top_err, top = class_top(x, eig, *n_eig, c->cls, &top_err);
        /* the translation itself (Hill's value of it within its own
         * HILL_CONVERGED): translation() finds or polishes it */
        int translation_mode = c->cls == 0 && hypot(c->a, c->y) < HILL_CONVERGED + 10.0 * x->tol;
        if (c->fam >= 0 || 2 * c->cls > classes || translation_mode || c->a < floor ||
            !(c->a > top + top_err + HILL_CONVERGED))
            continue;
        double theta = 2.0 * M_PI * (double)c->cls / (double)classes;
        double complex h = c->a + I * c->y, sc = h, sf, d[2] = {NAN, NAN};
        double step_c, step_f = INFINITY;
        int ok = trainspec_polish(x, &x->coarse, theta, &sc, &step_c, d) == BKF_OK;
        sf = sc;
        ok = ok && trainspec_polish(x, &x->fine, theta, &sf, &step_f, d) == BKF_OK;
        if (!ok || !(cabs(sf - h) <= HILL_AGREE * (1.0 + cabs(h))))
            return bkf_error_set(err, BKF_ETOL,
                                 "spectrum: Hill's method at %zu modes finds %.6g%+.6gi (Bloch class %zu) right "
                                 "of the rightmost the meshes found, %.6g, and the meshes do not confirm it",
                                 modes, c->a, c->y, c->cls, top);
        dv[*n_eig].d[0] = d[0], dv[*n_eig].d[1] = d[1], dv[*n_eig].coarse = sc;
        eig[(*n_eig)++] = (bkf_trainspec_eigenvalue){creal(sf), cimag(sf), trainspec_estimate(sc, sf, step_f), c->cls,
                                                     0.0, 0};
    }
    return BKF_OK;
}

/* Spectrum in `classes` phase classes: per class the `keep` rightmost
 * eigenvalues, polished on the fine mesh with error estimates; keep 0:
 * found and polished as for 1, the rightmost alone refined and kept
 * (drop_dominated). */
static int spectrum(ctx *x, size_t classes, size_t keep, bkf_trainspec_eigenvalue **out, size_t *count,
                    window *win, double *y_max, size_t *curve_points, size_t *hill_modes, bkf_error *err)
{
    int rightmost = keep == 0;
    if (rightmost) keep = 1;
    candidates cs = {0};
    hill_stage hs;
    bkf_error trace_err = {0};
    int fallback = 0;
    size_t n_eig = 0;
    bkf_trainspec_eigenvalue *eig = NULL;
    derivs *dv = NULL;
    int rc = gather(x, classes, keep, win, &cs, &hs, y_max, curve_points, &fallback, &trace_err, err);
    *hill_modes = hs.modes;
    size_t polish_n = (keep > 3 ? keep : 3) + 2;
    if (rc == BKF_OK) {
        eig = calloc(2 * (classes + 2) * (polish_n + HILL_PER_CLASS + 1), sizeof *eig);
        dv = calloc(2 * (classes + 2) * (polish_n + HILL_PER_CLASS + 1), sizeof *dv);
        if (!eig || !dv) rc = bkf_error_set(err, BKF_ENOMEM, "out of memory");
    }
    if (rc == BKF_OK) rc = meshes_for_polish(x, classes, polish_n, &cs, err);
    if (rc == BKF_OK) {
        polish_candidates(x, classes, keep, rightmost, &cs, eig, dv, &n_eig);
        /* the rightmost alone: Hill's candidates that polish_candidates would
         * have cut at the rightmost need no validation either */
        double floor = rightmost ? polish_cut(kth_re(x, eig, 0, n_eig, 1)) : -INFINITY;
        if (hs.modes) rc = trainspec_hill_validate(x, classes, hs.modes, floor, &cs, eig, dv, &n_eig, err);
    }
    if (rc == BKF_OK) {
        translation(x, eig, dv, &n_eig);
        drop_hidden(eig, dv, &n_eig, keep);
        rc = refine(x, classes, rightmost, eig, dv, &n_eig, err);
    }
    if (rc == BKF_OK) mirror_and_cut(classes, keep, eig, &n_eig);
    if (rc == BKF_OK && fallback) rc = confirm_band(&hs, eig, n_eig, &trace_err, err);
    trainspec_hill_stage_free(&hs);
    free(cs.items);
    free(dv);
    if (rc != BKF_OK) {
        free(eig);
        return rc;
    }
    *out = eig;
    *count = n_eig;
    return BKF_OK;
}

/* The reason a search was cut short, over whatever failure it produced. */
int trainspec_stopped(const ctx *x, int rc, bkf_error *err)
{
    if (x->stop == BKF_ECANCELED) return bkf_error_set(err, BKF_ECANCELED, "spectrum: canceled");
    if (x->stop == BKF_EBUDGET)
        return bkf_error_set(err, BKF_EBUDGET,
                             "the spectrum needs more than %.3g Radau steps in all (mu = %.15g; the budget is "
                             "max_work)",
                             x->max_work, x->mu);
    return rc;
}

window trainspec_initial_window(const ctx *x, double *r_inf)
{
    *r_inf = x->s * x->log_m / (2.0 * x->T);
    return (window){.a_lo = fmax(0.5 * *r_inf, -WINDOW_DEPTH * x->gamma), .a_hi = fmax(1.0, x->gamma)};
}

void bkf_trainspec_result_free(bkf_trainspec_result *r)
{
    if (!r) return;
    free(r->eigenvalues);
    r->eigenvalues = NULL;
    r->count = 0;
}

int bkf_trainspec_ring(const bkf_model_params *p, const bkf_trainspec_train *t,
                       const bkf_trainspec_options *options, bkf_trainspec_result *r, bkf_error *err)
{
    if (!r) return bkf_error_set(err, BKF_EINPUT, "result is NULL");
    memset(r, 0, sizeof *r);
    bkf_trainspec_options o = options ? *options : bkf_trainspec_options_default();
    int rc = bkf_trainspec_check(p, t, &o, err);
    if (rc != BKF_OK) return rc;
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    ctx x;
    rc = trainspec_ctx_init(&x, p, t, o.tol, &o, err);
    window win = trainspec_initial_window(&x, &r->r_inf);
    double a_lo0 = win.a_lo;
    if (rc == BKF_OK)
        rc = spectrum(&x, t->n, o.per_kappa, &r->eigenvalues, &r->count, &win, &r->y_max,
                      &r->curve_points, &r->hill_modes, err);
    rc = trainspec_stopped(&x, rc, err);
    if (rc == BKF_OK) {
        r->params = *p;
        r->n = t->n;
        r->v = t->v;
        r->mu = x.mu;
        r->T = x.T;
        r->L = x.L;
        r->a_lo = win.a_lo;
        r->edge_moved = win.a_lo > a_lo0;
        r->mesh_steps = x.fine.steps;
        r->liouville_residual = fabs(x.fine.trace_sum - x.log_m);
        for (size_t i = 0; i < r->count; i++)
            if (r->eigenvalues[i].translation)
                r->translation_residual = hypot(r->eigenvalues[i].re, r->eigenvalues[i].im);
        r->sigma_max = -INFINITY;
        for (size_t i = 0; i < r->count; i++) {
            bkf_trainspec_eigenvalue *e = &r->eigenvalues[i];
            e->kappa = 2.0 * M_PI * (double)e->j / p->S;
            if (e->translation || e->re <= r->sigma_max) continue;
            r->sigma_max = e->re;
            r->sigma_max_im = e->im;
            r->sigma_max_err = e->err;
            r->kappa_max = e->kappa;
        }
        if (!isfinite(r->sigma_max)) {
            /* nothing right of a_lo but the translation */
            r->sigma_max = win.a_lo;
            r->sigma_max_err = 0.0;
            r->sigma_is_bound = 1;
            r->verdict = BKF_TRAINSPEC_STABLE;
        } else {
            r->complex_pair = fabs(r->sigma_max_im) > r->sigma_max_err;
            r->verdict = r->sigma_max + r->sigma_max_err < 0.0   ? BKF_TRAINSPEC_STABLE
                         : r->sigma_max - r->sigma_max_err > 0.0 ? BKF_TRAINSPEC_UNSTABLE
                                                                 : BKF_TRAINSPEC_UNRESOLVED;
        }
        r->evaluations = x.evaluations;
        r->work = x.work;
    }
    trainspec_ctx_free(&x);
    bkf_gsl_handler_pop(handler);
    if (rc != BKF_OK) bkf_trainspec_result_free(r);
    return rc;
}

int bkf_trainspec_root(const bkf_model_params *params, const bkf_speeds_root *root, double tol,
                       size_t per_kappa, bkf_trainspec_result *result, bkf_error *err)
{
    if (!root) return bkf_error_set(err, BKF_EINPUT, "root is NULL");
    if (root->status != BKF_OK) {
        if (result) memset(result, 0, sizeof *result);
        return bkf_speeds_root_status(root, err);
    }
    bkf_trainspec_train train = {root->n, root->v};
    bkf_trainspec_options o = bkf_trainspec_options_default();
    o.tol = tol;
    o.per_kappa = per_kappa;
    return bkf_trainspec_ring(params, &train, &o, result, err);
}

const char *bkf_trainspec_kind_name(const bkf_trainspec_result *result)
{
    return result->complex_pair ? "complex" : "real";
}

bkf_trainspec_shown bkf_trainspec_shown_of(const bkf_trainspec_result *r)
{
    if (r->sigma_is_bound) return (bkf_trainspec_shown){NAN, NAN, NAN, NAN, NULL, r->sigma_max};
    return (bkf_trainspec_shown){r->sigma_max, r->sigma_max_im, r->sigma_max_err, r->kappa_max,
                                 bkf_trainspec_kind_name(r), NAN};
}

const char *bkf_trainspec_bound_note(double bound, char *buf, size_t size)
{
    char b[32];
    bkf_format_number(bound, b, sizeof b);
    snprintf(buf, size,
             "sigma_max nan: no eigenvalue but the translation found right of Re sigma = %s (the "
             "edge of the window searched): every eigenvalue left of %s",
             b, b);
    return buf;
}

int bkf_trainspec_line(const bkf_model_params *p, const bkf_trainspec_train *t,
                       const bkf_trainspec_options *options, size_t count, bkf_trainspec_eigenvalue *out,
                       bkf_error *err)
{
    bkf_trainspec_options o = options ? *options : bkf_trainspec_options_default();
    int rc = bkf_trainspec_check(p, t, &o, err);
    if (rc != BKF_OK) return rc;
    if (count < 2 || count > 100000) return bkf_error_set(err, BKF_EINPUT, "count must be in [2, 100000]");
    if (!out) return bkf_error_set(err, BKF_EINPUT, "out is NULL");
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    ctx x;
    rc = trainspec_ctx_init(&x, p, t, o.tol, &o, err);
    double r_inf, y_max;
    size_t points = 0, n_eig = 0;
    window win = trainspec_initial_window(&x, &r_inf);
    bkf_trainspec_eigenvalue *eig = NULL;
    size_t hill_modes = 0;
    if (rc == BKF_OK) rc = spectrum(&x, count, 1, &eig, &n_eig, &win, &y_max, &points, &hill_modes, err);
    rc = trainspec_stopped(&x, rc, err);
    if (rc == BKF_OK) {
        double L = x.L;
        for (size_t i = 0; i < count; i++)
            out[i] = (bkf_trainspec_eigenvalue){NAN, NAN, NAN, i, 2.0 * M_PI * (double)i / ((double)count * L), 0};
        /* the rightmost of each class (the translation too: the branch it is on
         * passes through 0 at kappa 0); not the last listed, which at kappa 0 was
         * the translation below class 0's rightmost (issue 31: 8.8e-11 for 0.0697) */
        for (size_t k = 0; k < n_eig; k++) {
            size_t j = eig[k].j;
            if (out[j].re >= eig[k].re) continue;
            out[j].re = eig[k].re;
            out[j].im = eig[k].im;
            out[j].err = eig[k].err;
        }
    }
    free(eig);
    trainspec_ctx_free(&x);
    bkf_gsl_handler_pop(handler);
    return rc;
}

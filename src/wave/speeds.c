/* Roots and branches of the speed-selection condition (see speeds.h).
 *
 * With c > 0 every n is a level ln R_n of one function of
 * s = ln sqrt(mu^2 - gamma^2):
 *     D_n(s) = ln T(mu(s)) - s - ln R_n,      ln g(s) = ln T - s,
 * so one grid of T serves every n.  The grid's samples are solved at a
 * coarse tolerance (they only have to give signs), the roots at what v
 * needs.  T(mu) is not assumed monotone (it is not, inside canards).  What
 * the search rests on, argued in docs/numerics.md ("why none is missed"):
 *   below the first sample, ln g decreases (eps = d ln T/ds -> 0 as
 *       mu -> gamma+, bounded there from the secant of T from T(gamma));
 *   A2  the slope eps on a cell lies within the secant slopes of the cell
 *       and its neighbours, widened by half their spread and by the noise
 *       of T: where that bound is < 1 (or > 1) ln g = ln T - s is monotone
 *       on the cell, and a level has exactly one root there if it changes
 *       sign, none otherwise; elsewhere the bound still encloses ln g;
 *   A3  beyond a sample M where the large-mu expansion
 *       T = k mu + b mu^(-1/3) + L ln(mu)/mu (b > 0 > L) holds to a quarter
 *       of its knee term and the knee term dominates the log term, g
 *       decreases to k: one root beyond M for levels in (k, g(M)), none for
 *       the others.
 * Cells that A2 cannot certify are bisected while their enclosure holds a
 * level of interest; what remains undecided at the finest cell, or where T
 * cannot be computed, is reported (near-tangent roots, unresolved places). */
#include "bkfront/speeds.h"

#include "speeds_internal.h"

#include "bkfront/asymptotics.h"
#include "bkfront/continuation.h"
#include "bkfront/cycle.h"
#include "bkfront/model.h"

#include <float.h>
#include <gsl/gsl_errno.h>
#include <gsl/gsl_roots.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

bkf_speeds_options bkf_speeds_options_default(void)
{
    return (bkf_speeds_options){.tol = 1e-10, .n_from = 1, .n_to = 0, .method = BKF_METHOD_AUTO};
}

int bkf_speeds_check(const bkf_model_params *p, const bkf_speeds_options *o, bkf_error *err)
{
    if (!p) return bkf_error_set(err, BKF_EINPUT, "parameters are NULL");
    int rc = bkf_model_check_positive("gamma", p->gamma, err);
    if (rc) return rc;
    if (p->gamma < BKF_CYCLE_MU_MIN || p->gamma > BKF_CYCLE_MU_MAX)
        return bkf_error_set(err, BKF_EINPUT,
                             "gamma = %.15g is outside [%g, %g] (mu >= gamma must be solvable)",
                             p->gamma, BKF_CYCLE_MU_MIN, BKF_CYCLE_MU_MAX);
    if ((rc = bkf_model_check_c(p->c, err))) return rc;
    if ((rc = bkf_model_check_positive("S", p->S, err))) return rc;
    if (!isfinite(p->nu) || fabs(p->nu) >= 1.0)
        return bkf_error_set(err, BKF_EINPUT,
                             "nu = %.15g is outside (-1, 1): no fronts, uniform continuous slip "
                             "psi = nu is stable (no limit cycle)", p->nu);
    if (p->c > 0) {
        /* S/(c gamma) counts the fronts that fit (n_bound = S/(k c gamma));
         * beyond 1e15 n is no longer an exact double */
        double lnA = log(p->S) - log(p->c) - log(p->gamma);
        if (lnA > log(1e15))
            return bkf_error_set(err, BKF_EINPUT,
                                 "S/(c gamma) = %g is above 1e15: c is too small for this S "
                                 "(use c = 0)", exp(lnA));
    }
    if (o) {
        if ((rc = bkf_model_check_tol(o->tol, err))) return rc;
        if (o->n_from < 1) return bkf_error_set(err, BKF_EINPUT, "n_from = 0 must be >= 1");
        if (o->n_to && o->n_to < o->n_from)
            return bkf_error_set(err, BKF_EINPUT, "n_to = %zu is below n_from = %zu", o->n_to,
                                 o->n_from);
        if (!bkf_cycle_method_name(o->method))
            return bkf_error_set(err, BKF_EINPUT,
                                 "method must be auto, asymptotic, leading or shooting");
    }
    return BKF_OK;
}

/* ----------------------------------------------------------------- rows */

void speeds_fill_row(const bkf_model_params *p, double k, const found_root *f,
                     bkf_speeds_root *row)
{
    double n = f->n;
    memset(row, 0, sizeof *row);
    row->n = (size_t)n;
    row->wavelength = p->S / n;
    row->v_asym = p->S / (n * k * p->gamma);
    row->flags = f->flags;
    row->tol_met = NAN;
    if (f->status != BKF_OK) {
        /* where the looser root lies is in the refusal's text, not in v */
        row->status = f->status;
        row->flags |= BKF_SPEEDS_REFUSED;
        row->tol_met = f->tol_met;
        snprintf(row->refusal, sizeof row->refusal, "%s", f->why);
        row->v = row->mu = row->T = row->T_err = row->v_over_c = NAN;
        row->period_fixed = row->deviation = row->v_err = row->residual = row->slope = NAN;
        return;
    }
    row->T = f->T;
    row->T_err = f->T_err;
    row->slope = f->slope;
    row->model = f->model;
    double uT = f->T_err / f->T;
    if (p->c > 0) {
        double ratio = hypot(1.0, p->gamma * exp(-f->s)); /* v/c = mu / sqrt(mu^2 - gamma^2) */
        row->mu = mu_of_s(p->gamma, f->s);
        row->v_over_c = ratio;
        row->v = p->c * ratio;
        row->period_fixed = f->T * p->gamma / row->mu;
        row->residual = expm1(f->D);
        /* d ln v / ds = -gamma^2/mu^2; ds = (|D| + uT) / |dD/ds| */
        double g2 = p->gamma / row->mu;
        row->v_err = row->v * (g2 * g2 * (fabs(f->D) + uT) / fabs(f->slope) + 4.0 * DBL_EPSILON);
        if (!isfinite(row->v_err)) row->v_err = INFINITY;
    } else {
        row->mu = p->gamma;
        row->v_over_c = INFINITY;
        row->v = p->S / (n * f->T);
        row->period_fixed = f->T;
        row->residual = n * f->T * row->v / p->S - 1.0;
        row->v_err = row->v * (uT + 4.0 * DBL_EPSILON);
    }
    row->deviation = (row->v - row->v_asym) / row->v;
}

int bkf_speeds_root_status(const bkf_speeds_root *root, bkf_error *err)
{
    if (!root) return bkf_error_set(err, BKF_EINPUT, "root is NULL");
    if (root->status == BKF_OK) return BKF_OK;
    return bkf_error_set(err, root->status, "n = %zu: %s", root->n, root->refusal);
}

int bkf_speeds_nearest(const bkf_speeds_table *t, double v, size_t *index, bkf_error *err)
{
    if (!t || !index) return bkf_error_set(err, BKF_EINPUT, "table or index is NULL");
    if (t->count == 0) return bkf_error_set(err, BKF_ENUMERIC, "no root");
    size_t best = 0;
    for (size_t i = 0; i < t->count; i++) {
        int rc = bkf_speeds_root_status(&t->roots[i], err);
        if (rc) return rc;
        if (v > 0 && fabs(t->roots[i].v - v) < fabs(t->roots[best].v - v)) best = i;
    }
    *index = best;
    return BKF_OK;
}

static int push_root(bkf_speeds_table *t, size_t *cap, const bkf_speeds_root *r, bkf_error *err)
{
    if (t->count == *cap) {
        size_t nc = *cap ? 2 * *cap : 16;
        bkf_speeds_root *x = realloc(t->roots, nc * sizeof *x);
        if (!x) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
        t->roots = x;
        *cap = nc;
    }
    t->roots[t->count++] = *r;
    return BKF_OK;
}

static int compare_found(const void *a, const void *b)
{
    const found_root *x = a, *y = b;
    if (x->n != y->n) return x->n < y->n ? -1 : 1;
    return (x->s > y->s) - (x->s < y->s);
}

static void append_note(bkf_speeds_table *t, const char *text)
{
    size_t used = strlen(t->note);
    snprintf(t->note + used, sizeof t->note - used, "%s%s", used ? "; " : "", text);
}

void bkf_speeds_table_free(bkf_speeds_table *t)
{
    if (!t) return;
    free(t->roots);
    t->roots = NULL;
    t->count = 0;
}

static int find_c0(const bkf_model_params *p, const bkf_speeds_options *o, bkf_speeds_table *t,
                   bkf_error *err)
{
    bkf_cycle_options co = bkf_cycle_options_default();
    co.tol = o->tol; /* v = S/(n T): v needs T to tol */
    bkf_cycle_result r;
    bkf_error e = {0};
    bkf_cycle *cycle = bkf_cycle_alloc();
    if (!cycle) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    int rc = bkf_cycle_estimate(cycle, p->gamma, p->nu, &co, o->method, &r, &e);
    bkf_cycle_free(cycle);
    if (rc) return speeds_period_refused(rc, &e, p->nu, err);
    if (strcmp(r.model, "shooting") == 0) t->precise_solves = 1;
    else t->formula_answers = 1;
    t->mu_grid_max = p->gamma;
    t->n_max = -1;
    t->g_inf = NAN;
    size_t last = o->n_to ? o->n_to : o->n_from + BKF_SPEEDS_ROWS_C0 - 1, cap = 0;
    for (size_t n = o->n_from; n <= last; n++) {
        found_root f = {.n = (double)n, .T = r.period, .T_err = r.period_err, .model = r.model};
        bkf_speeds_root row;
        speeds_fill_row(p, t->k, &f, &row);
        if ((rc = push_root(t, &cap, &row, err))) return rc;
    }
    append_note(t, "c = 0: every n has the front v = S/(n T(gamma)), mu = gamma");
    return BKF_OK;
}

/* The roots found so far, in the order of the cells. */
typedef struct {
    found_root *x;
    size_t count, cap;
} found_list;

/* A new slot at the end of f, or NULL (out of memory). */
static found_root *found_next(found_list *f)
{
    if (f->count == f->cap) {
        size_t nc = f->cap ? 2 * f->cap : 16;
        found_root *x = realloc(f->x, nc * sizeof *x);
        if (!x) return NULL;
        f->x = x;
        f->cap = nc;
    }
    return &f->x[f->count];
}

/* The grid's model and constants for p and o (its solvers allocated). */
static int search_init(search *sr, const bkf_model_params *p, const bkf_speeds_options *o,
                       double k, bkf_error *err)
{
    memset(sr, 0, sizeof *sr);
    grid *g = &sr->g;
    g->p = *p;
    g->tol = o->tol;
    g->tol_coarse = fmax(o->tol, COARSE_TOL);
    g->method = o->method;
    g->k = k;
    g->lnk = log(k);
    g->knee = bkf_asym_knee_coefficient(p->nu);
    g->logc = bkf_asym_log_coefficient(p->nu);
    g->lnA = log(p->S) - log(p->c) - log(p->gamma);
    g->coarse = bkf_cycle_alloc();
    g->precise = bkf_cycle_alloc();
    if (!g->coarse || !g->precise) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    return BKF_OK;
}

static void search_free(search *sr)
{
    free(sr->g.x);
    bkf_cycle_free(sr->g.coarse);
    bkf_cycle_free(sr->g.precise);
}

/* The grid, its certificate and n_max; the levels asked for (sr->n_from,
 * n_last) and the table's range of n. */
static int search_levels(search *sr, const bkf_speeds_options *o, bkf_speeds_table *t,
                         bkf_error *err)
{
    grid *g = &sr->g;
    double T_gamma, T_gamma_err;
    int rc = speeds_solve_T(g, g->p.gamma, 0, &T_gamma, &T_gamma_err, err);
    if (rc) return rc;
    sr->n_from = (double)o->n_from;
    double n_star = ceil(exp(g->lnA - g->lnk)) - 1.0; /* levels strictly above k */
    double n_req_last = o->n_to ? (double)o->n_to : sr->n_from + BKF_SPEEDS_MAX_ROWS - 1;
    /* The grid, its refinement and its precise samples are those of the
     * whole table (levels 1 .. BKF_SPEEDS_MAX_ROWS, or the last requested
     * if beyond), so a root does not depend on which rows were asked for:
     * speeds --n 4 gave 0.48545916040133913 where the table gave
     * 0.48545916040196629 (issue 36). */
    double grid_last = fmax(n_req_last, (double)BKF_SPEEDS_MAX_ROWS);
    double n_target = fmin(grid_last, n_star);
    if (n_target < 1) n_target = 0;
    if ((rc = speeds_first_sample(sr, log(T_gamma), T_gamma_err / T_gamma + 8.0 * DBL_EPSILON,
                                  fmax(level(g, 1.0), g->lnk), err)))
        return rc;
    if ((rc = speeds_build_grid(sr, n_target, err))) return rc;
    if ((rc = speeds_find_n_max(sr, err))) return rc;
    t->n_max = (long)sr->n_max;
    t->dips_below_k = sr->dips;
    t->g_inf = sr->dips ? exp(sr->g_inf_ln) : t->k;
    sr->n_last = fmin(n_req_last, sr->n_max);
    sr->grid_last = fmin(grid_last, sr->n_max);
    if (!o->n_to && sr->n_max > n_req_last) t->truncated = 1;
    return BKF_OK;
}

/* A root of level n bracketed in cell i that speeds_polish could not have
 * to tol (its failure in pe).  Had at a looser tolerance, the root exists
 * and the tol asked is beyond what T gives there: a refused row that says
 * the tol it has (issue 31: a table refused whole for one such root lost
 * every other row; before that, at tol 1e-14 the paper's table kept 4 of
 * its 12 rows, exit 0).  A formula asked for that does not meet what the
 * root needs is refused as it stands.  Not had at all (inside a canard
 * explosion T jumps across the level): *refused stays 0 and the place is
 * reported as unresolved. */
static void refuse_root(search *sr, gsl_root_fsolver *fs, double n, size_t i, const bkf_error *pe,
                        found_root *out, int *refused)
{
    grid *g = &sr->g;
    *refused = 0;
    if (g->formula_refused && g->method != BKF_METHOD_AUTO) {
        *out = (found_root){.n = n, .s = g->x[i].s, .status = BKF_ETOL, .tol_met = NAN};
        snprintf(out->why, sizeof out->why, "%s", pe->message);
        *refused = 1;
        return;
    }
    const double factors[] = LOOSE_FACTORS, tol = g->tol;
    found_root loose;
    int lrc = BKF_ENUMERIC;
    for (size_t k = 0; lrc && k < sizeof factors / sizeof factors[0]; k++) {
        double looser = fmin(factors[k] * tol, BKF_TOL_MAX);
        if (!(looser > g->tol) || (k >= LOOSE_NEAR && looser > LOOSE_FAR_MAX)) break;
        bkf_error le = {0};
        g->tol = looser;
        g->mu_last[1] = 0;
        lrc = speeds_polish(g, fs, n, i, &loose, &le);
    }
    double met = g->tol;
    g->tol = tol;
    if (lrc != BKF_OK) {
        speeds_note_unresolved(sr, n, g->x[i].mu, "root not polished (T failed)");
        return;
    }
    double mu = mu_of_s(g->p.gamma, loose.s);
    *out = (found_root){.n = n, .s = loose.s, .status = BKF_ETOL, .tol_met = met};
    snprintf(out->why, sizeof out->why,
             "the root near mu = %.6g (v = %.6g) cannot be polished to tol %g, only to %g (%.180s)",
             mu, g->p.c / sqrt(1.0 - pow(g->p.gamma / mu, 2)), tol, met, pe->message);
    *refused = 1;
}

/* Every root bracketed between two samples of the grid, polished (or a
 * refused row), cell by cell so that precise solves warm-start. */
static int collect_bracketed(search *sr, gsl_root_fsolver *fs, found_list *f, bkf_error *err)
{
    grid *g = &sr->g;
    for (size_t i = 0; i + 1 < g->count; i++) {
        cell_info c = speeds_classify(g, i);
        double first, last;
        speeds_levels_in(g, c.lo, c.hi, sr->n_from, sr->n_last, &first, &last);
        for (double n = first; n <= last; n++) {
            double ell = level(g, n);
            int da = lng(&g->x[i]) - ell > 0, db = lng(&g->x[i + 1]) - ell > 0;
            if (da == db) {
                if (c.shape == CELL_UNKNOWN) speeds_note_unresolved(sr, n, g->x[i].mu, NULL);
                continue;
            }
            found_root *out = found_next(f);
            if (!out) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
            bkf_error pe = {0};
            /* each root's precise solves start cold: warm from the root
             * polished before, its value would depend on the rows asked */
            g->mu_last[1] = 0;
            int rc = speeds_polish(g, fs, n, i, out, &pe);
            if (bkf_status_is_numerical(rc)) {
                int refused;
                refuse_root(sr, fs, n, i, &pe, out, &refused);
                if (!refused) continue;
            } else if (rc) {
                *err = pe;
                return rc;
            }
            if (c.shape == CELL_UNKNOWN) out->flags |= BKF_SPEEDS_NEAR_TANGENT;
            f->count++;
        }
    }
    return BKF_OK;
}

/* The levels whose root lies beyond the last sample, at the grid's cap:
 * from the large-mu expansion. */
static int collect_tail(search *sr, found_list *f, bkf_error *err)
{
    grid *g = &sr->g;
    int rc = speeds_upgrade(g, g->count - 1, err);
    if (rc) return rc;
    const sample *last = &g->x[g->count - 1];
    double first, lastn;
    speeds_levels_in(g, g->lnk, lng(last), sr->n_from, sr->n_last, &first, &lastn);
    for (double n = first; n <= lastn; n++) {
        if (!(level(g, n) > g->lnk && level(g, n) < lng(last))) continue;
        found_root *out = found_next(f);
        if (!out) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
        speeds_asymptotic_root(g, n, out);
        f->count++;
    }
    return BKF_OK;
}

/* The rows of the roots found, in order, with the folds' flags; the
 * refused ones counted in the note. */
static int table_rows(const bkf_model_params *p, found_list *f, bkf_speeds_table *t,
                      bkf_error *err)
{
    found_root *found = f->x;
    size_t nfound = f->count, cap = 0;
    qsort(found, nfound, sizeof *found, compare_found);
    /* two roots of one n close together sit near a fold */
    for (size_t j = 0; j + 1 < nfound; j++)
        if (found[j].n == found[j + 1].n && found[j + 1].s - found[j].s < 0.05) {
            found[j].flags |= BKF_SPEEDS_NEAR_TANGENT;
            found[j + 1].flags |= BKF_SPEEDS_NEAR_TANGENT;
        }
    size_t first = 0;
    for (size_t j = 0; j < nfound; j++) {
        bkf_speeds_root row;
        speeds_fill_row(p, t->k, &found[j], &row);
        int rc = push_root(t, &cap, &row, err);
        if (rc) return rc;
        if (row.status != BKF_OK && t->refused++ == 0) first = row.n;
    }
    if (t->refused) {
        char line[160];
        snprintf(line, sizeof line, "%zu root(s) refused, not had to tol (flag refused, "
                 "numbers NaN; the first: n = %zu)", t->refused, first);
        append_note(t, line);
    }
    return BKF_OK;
}

/* The note's lines on the range of n and what was left unresolved. */
static void table_notes(const search *sr, const bkf_model_params *p,
                        const bkf_speeds_options *o, bkf_speeds_table *t)
{
    char line[400];
    if (t->n_max == 0) {
        if (sr->dips)
            snprintf(line, sizeof line,
                     "no front: S/(c gamma) = %.6g is at most the minimum %.6g of "
                     "T(mu)/sqrt(mu^2 - gamma^2) over mu > gamma (n = 1 needs more)",
                     exp(sr->g.lnA), t->g_inf);
        else
            snprintf(line, sizeof line,
                     "no front: S = %.6g <= k(nu) c gamma = %.6g (n fronts need "
                     "S > n k(nu) c gamma)", p->S, t->k * p->c * p->gamma);
        append_note(t, line);
    } else if (t->count == 0 && sr->n_from > sr->n_max) {
        snprintf(line, sizeof line, "no front with n >= %zu: n_max = %ld", o->n_from, t->n_max);
        append_note(t, line);
    }
    if (t->truncated) {
        snprintf(line, sizeof line, "rows for n <= %.0f only of n_max = %ld", sr->n_last,
                 t->n_max);
        append_note(t, line);
    }
    if (sr->unresolved) {
        snprintf(line, sizeof line,
                 "%zu place(s) left unresolved, where a root or a pair of roots could be "
                 "missing (first: %s)", sr->unresolved, sr->unresolved_text);
        append_note(t, line);
    }
    t->unresolved = sr->unresolved;
}

/* The search for c > 0: the grid, then the roots of the levels asked. */
static int find_search(const bkf_model_params *p, const bkf_speeds_options *o,
                       bkf_speeds_table *t, bkf_error *err)
{
    search sr;
    found_list found = {0};
    grid *g = &sr.g;
    gsl_root_fsolver *fs = gsl_root_fsolver_alloc(gsl_root_fsolver_brent);
    int rc = search_init(&sr, p, o, t->k, err);
    if (!rc && !fs) rc = bkf_error_set(err, BKF_ENOMEM, "out of memory");
    if (!rc) rc = search_levels(&sr, o, t, err);
    if (!rc && sr.n_last >= sr.n_from) {
        rc = speeds_resolve_levels(&sr, err);
        /* the last sample's precise solve, as the table's (the tail's roots) */
        if (!rc && sr.asym_mu0 > 0) rc = speeds_upgrade(g, g->count - 1, err);
        if (!rc) rc = collect_bracketed(&sr, fs, &found, err);
        if (!rc && sr.asym_mu0 > 0) rc = collect_tail(&sr, &found, err);
        if (!rc) rc = table_rows(p, &found, t, err);
    }
    if (!rc) table_notes(&sr, p, o, t);
    t->samples = g->count;
    t->coarse_solves = g->coarse_solves;
    t->precise_solves = g->precise_solves;
    t->formula_answers = g->formula_answers;
    t->mu_grid_max = g->mu_max_sampled;
    free(found.x);
    search_free(&sr);
    if (fs) gsl_root_fsolver_free(fs);
    return rc;
}

static int speeds_find_body(const bkf_model_params *p, const bkf_speeds_options *options,
                            bkf_speeds_table *t, bkf_error *err)
{
    if (!t) return bkf_error_set(err, BKF_EINPUT, "table is NULL");
    memset(t, 0, sizeof *t);
    bkf_speeds_options o = options ? *options : bkf_speeds_options_default();
    int rc = bkf_speeds_check(p, &o, err);
    if (rc) return rc;
    t->k = bkf_asym_k(p->nu);
    t->n_bound = p->c > 0 ? p->S / (t->k * p->c * p->gamma) : INFINITY;
    if (p->c == 0) return find_c0(p, &o, t, err);
    return find_search(p, &o, t, err);
}

int bkf_speeds_find(const bkf_model_params *p, const bkf_speeds_options *options,
                    bkf_speeds_table *t, bkf_error *err)
{
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    int rc = speeds_find_body(p, options, t, err);
    bkf_gsl_handler_pop(handler);
    return rc;
}

/* F(s) = ln T(mu(s)) - s - ell at s (the speed condition of level ell in
 * log form), T shot to the grid's tol. */
static int near_F(grid *g, double s, double ell, double *F, double *T, double *T_err,
                  bkf_error *err)
{
    int rc = speeds_solve_T(g, mu_of_s(g->p.gamma, s), g->tol, T, T_err, err);
    if (!rc) *F = log(*T) - s - ell;
    return rc;
}

static int speeds_near_body(const bkf_model_params *p, size_t n, double v_guess,
                            const bkf_speeds_options *options, bkf_speeds_root *root,
                            bkf_error *err)
{
    bkf_speeds_options o = options ? *options : bkf_speeds_options_default();
    o.n_from = o.n_to = n;
    int rc = bkf_speeds_check(p, &o, err);
    if (rc) return rc;
    if (!root || n < 1 || !(p->c > 0) || !(v_guess > p->c) || !isfinite(v_guess))
        return bkf_error_set(err, BKF_EINPUT, "near: root, n >= 1, c > 0 and v_guess > c");
    search sr;
    rc = search_init(&sr, p, &o, bkf_asym_k(p->nu), err);
    grid *g = &sr.g;
    double ell = level(g, (double)n);
    /* v/c = hypot(1, gamma e^-s) */
    double s0 = log(p->gamma) - 0.5 * log((v_guess / p->c - 1) * (v_guess / p->c + 1));
    double a = s0, b = s0 + 1e-3, Fa = 0, Fb = 0, T = 0, T_err = 0;
    if (!rc) rc = near_F(g, a, ell, &Fa, &T, &T_err, err);
    if (!rc) rc = near_F(g, b, ell, &Fb, &T, &T_err, err);
    int done = 0;
    for (int it = 0; !rc && !done && it < 16; it++) {
        if (!(Fb != Fa) || !isfinite(Fa) || !isfinite(Fb)) break;
        double c = b - Fb * (b - a) / (Fb - Fa);
        /* within 20% of the guess in v (v/c = hypot(1, gamma e^-s)) and 0.5
         * in ln mu: a root near, no other */
        if (!isfinite(c) || fabs(log(hypot(1.0, p->gamma * exp(-c)) * p->c / v_guess)) > 0.2 ||
            fabs(log(mu_of_s(p->gamma, c) / mu_of_s(p->gamma, s0))) > 0.5)
            break;
        double Fc;
        rc = near_F(g, c, ell, &Fc, &T, &T_err, err);
        done = !rc && fabs(c - b) <= o.tol * fmax(1.0, fabs(c));
        a = b;
        Fa = Fb;
        b = c;
        Fb = Fc;
    }
    if (!rc && !done)
        rc = bkf_error_set(err, BKF_ENUMERIC, "n = %zu: no root of the speed condition near v %.6g "
                           "(the secant did not settle)", n, v_guess);
    if (!rc) {
        found_root f = {0};
        f.n = (double)n;
        f.s = b;
        f.T = T;
        f.T_err = T_err;
        f.D = Fb;
        f.slope = (Fb - Fa) / (b - a);
        f.model = g->last_model;
        speeds_fill_row(p, bkf_asym_k(p->nu), &f, root);
    }
    search_free(&sr);
    return rc;
}

int bkf_speeds_near(const bkf_model_params *p, size_t n, double v_guess,
                    const bkf_speeds_options *options, bkf_speeds_root *root, bkf_error *err)
{
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    int rc = speeds_near_body(p, n, v_guess, options, root, err);
    bkf_gsl_handler_pop(handler);
    return rc;
}

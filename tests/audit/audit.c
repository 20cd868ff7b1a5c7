/* The audit's checks (audit.h).  Each product is compared with a route
 * that shares none of its code path: the references are other parts of
 * the project (another stepper, Hill's method, the Taylor reference of
 * tests/wave) or a direct evaluation of the equation the product solves. */
#define _POSIX_C_SOURCE 200809L
#include "audit.h"

#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bkfront/asymptotics.h"
#include "bkfront/check.h"
#include "bkfront/cycle.h"
#include "bkfront/floquet.h"
#include "bkfront/hill.h"
#include "bkfront/model.h"
#include "bkfront/speeds.h"
#include "bkfront/stability.h"
#include "bkfront/trainspec.h"

#include "../wave/taylor_reference.h"

/* A true error may exceed its estimate by at most this factor
 * (CONTRIBUTING.md: "must not be optimistic by more than 10"). */
#define AUDIT_HONESTY 10.0
/* The Taylor reference's cost grows with mu (its steps resolve the fast
 * jumps): below this it takes well under a second a period. */
#define AUDIT_TAYLOR_MU_MAX 60.0
/* Hill's truncations tried, the finer one when the coarser leaves
 * eigenvalues unconverged (a pair of M and 2M modes each). */
static const size_t hill_modes[] = {32, 96};

audit_options audit_options_default(void)
{
    return (audit_options){1, 1, 1, 1, 1, 1, 1, 4};
}

const char *audit_status_name(audit_status s)
{
    return s == AUDIT_OK ? "OK" : s == AUDIT_DEFECT ? "DEFECT" : "REFUSAL";
}

/* ------------------------------------------------------------ drawing */

static uint64_t mix64(uint64_t x)
{
    x += 0x9e3779b97f4a7c15ULL;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
    return x ^ (x >> 31);
}

static double uniform(uint64_t *state)
{
    *state = mix64(*state);
    return (double)(*state >> 11) * 0x1.0p-53;
}

/* Six significant digits, so that the reproducer's command line (printed
 * with %.6g) gives the very same parameters. */
static double six_digits(double x)
{
    char buf[32];
    snprintf(buf, sizeof buf, "%.6g", x);
    return strtod(buf, NULL);
}

audit_set audit_draw(unsigned long seed, size_t i)
{
    uint64_t st = mix64((uint64_t)seed * 0x100000001b3ULL ^ mix64((uint64_t)i + 1));
    audit_set s;
    s.gamma = 0.3 + 7.7 * uniform(&st);
    s.c = 0.05 + 1.45 * uniform(&st);
    s.nu = -0.99 + 1.98 * uniform(&st);
    s.S = 5.0 + 55.0 * uniform(&st);
    s.kind = "uniform";
    double u = uniform(&st);
    switch (i % 6) {
    case 1:
        s.nu = (uniform(&st) < 0.5 ? -1.0 : 1.0) * (0.95 + 0.04 * u);
        s.kind = "nu-edge";
        break;
    case 2:
        s.gamma = 0.3 + 0.3 * u;
        s.kind = "gamma-small";
        break;
    case 3:
        s.gamma = 6.0 + 2.0 * u;
        s.kind = "gamma-large";
        break;
    case 4: {
        /* n_bound = S / (k c gamma) just above an integer m: the root of
         * n = m has v just above c (mu large) */
        double unit = bkf_asym_k(s.nu) * s.c * s.gamma;
        double m = fmax(1.0, floor(s.S / unit));
        double S = (m + 0.01 + 0.1 * u) * unit;
        if (S >= 5.0 && S <= 60.0) {
            s.S = S;
            s.kind = "c-near-v";
        }
        break;
    }
    default: break;
    }
    s.gamma = six_digits(s.gamma);
    s.c = six_digits(s.c);
    s.nu = six_digits(s.nu);
    s.S = six_digits(s.S);
    return s;
}

/* ------------------------------------------------------------ rows */

void audit_rows_free(audit_rows *rows)
{
    free(rows->rows);
    rows->rows = NULL;
    rows->count = rows->capacity = 0;
}

typedef struct {
    size_t index;
    const audit_set *set;
    const audit_options *opt;
    bkf_model_params p;
    char model[160]; /* the model's flags, for the reproducers */
    audit_rows *out;
} ctx;

static void add_row(ctx *x, const char *product, audit_status status, const char *repro, const char *fmt, ...)
    __attribute__((format(printf, 5, 6)));
static void add_row(ctx *x, const char *product, audit_status status, const char *repro, const char *fmt, ...)
{
    audit_rows *o = x->out;
    if (o->count == o->capacity) {
        size_t cap = o->capacity ? 2 * o->capacity : 32;
        audit_row *grown = realloc(o->rows, cap * sizeof *grown);
        if (!grown) return; /* the audit of this row is lost, nothing else */
        o->rows = grown;
        o->capacity = cap;
    }
    audit_row *r = &o->rows[o->count++];
    memset(r, 0, sizeof *r);
    r->set = x->index;
    snprintf(r->product, sizeof r->product, "%s", product);
    r->status = status;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(r->detail, sizeof r->detail, fmt, ap);
    va_end(ap);
    snprintf(r->repro, sizeof r->repro, "%s", repro ? repro : "");
    /* the row format is tab-separated, one line */
    for (char *c = r->detail; *c; c++)
        if (*c == '\t' || *c == '\n') *c = ' ';
}

void audit_row_write(FILE *f, const audit_row *r)
{
    fprintf(f, "%zu\t%s\t%s\t%s\t%s\n", r->set, r->product, audit_status_name(r->status), r->detail, r->repro);
}

int audit_row_read(const char *line, audit_row *r)
{
    memset(r, 0, sizeof *r);
    char *copy = strdup(line), *save = NULL;
    if (!copy) return -1;
    size_t len = strlen(copy);
    if (len && copy[len - 1] == '\n') copy[len - 1] = 0;
    char *f[5] = {0};
    char *p = copy;
    for (int i = 0; i < 5; i++) {
        f[i] = p;
        char *tab = p ? strchr(p, '\t') : NULL;
        if (tab) {
            *tab = 0;
            p = tab + 1;
        } else {
            p = NULL;
        }
    }
    (void)save;
    int rc = -1;
    if (f[0] && f[1] && f[2] && f[3]) {
        r->set = strtoul(f[0], NULL, 10);
        snprintf(r->product, sizeof r->product, "%s", f[1]);
        r->status = !strcmp(f[2], "OK") ? AUDIT_OK : !strcmp(f[2], "DEFECT") ? AUDIT_DEFECT : AUDIT_REFUSAL;
        snprintf(r->detail, sizeof r->detail, "%s", f[3]);
        snprintf(r->repro, sizeof r->repro, "%s", f[4] ? f[4] : "");
        rc = 0;
    }
    free(copy);
    return rc;
}

/* ------------------------------------------------------------ helpers */

/* mu of a train at speed v (v > c > 0) */
static double mu_of_v(const bkf_model_params *p, double v)
{
    return p->gamma / sqrt(1.0 - (p->c / v) * (p->c / v));
}

/* T by another integrator than the automatic choice at mu (bsimp where
 * the automatic one is bd2x2 or collocation at large mu, rk8pd below),
 * tightest first; 0 on success. */
static int other_period(double mu, double nu, double *T, double *T_err)
{
    static const double tols[] = {1e-12, 1e-10, 1e-8};
    bkf_cycle *cy = bkf_cycle_alloc();
    if (!cy) return -1;
    int rc = -1;
    for (size_t i = 0; i < sizeof tols / sizeof tols[0] && rc != 0; i++) {
        bkf_cycle_options o = bkf_cycle_options_default();
        o.tol = tols[i];
        o.warm_start = 0;
        o.stepper = mu <= 30.0 ? BKF_STEPPER_EXPLICIT : BKF_STEPPER_IMPLICIT;
        bkf_error e;
        if (bkf_cycle_solve(cy, mu, nu, &o, &e) == BKF_OK) {
            const bkf_cycle_result *r = bkf_cycle_get(cy);
            *T = r->period;
            *T_err = r->period_err;
            rc = 0;
        }
    }
    bkf_cycle_free(cy);
    return rc;
}

/* The independent value of T at (mu, nu): the long-double Taylor
 * reference up to AUDIT_TAYLOR_MU_MAX, another integrator above. */
static int reference_period(double mu, double nu, double slope, double *T, double *unc, const char **how)
{
    if (mu <= AUDIT_TAYLOR_MU_MAX && slope > 0) {
        *T = taylor_period(mu, nu, slope, unc);
        *how = "taylor";
        if (isfinite(*T)) return 0;
    }
    *how = mu <= 30.0 ? "rk8pd" : "bsimp";
    return other_period(mu, nu, T, unc);
}

/* ------------------------------------------------------------ period */

static void audit_period(ctx *x, double mu, double tol, const char *where)
{
    char repro[300];
    snprintf(repro, sizeof repro, "bkfront period --mu %.17g --nu %.6g --tol %g", mu, x->p.nu, tol);
    bkf_cycle *cy = bkf_cycle_alloc();
    if (!cy) return;
    bkf_cycle_options o = bkf_cycle_options_default();
    o.tol = tol;
    o.warm_start = 0;
    bkf_error e;
    if (bkf_cycle_solve(cy, mu, x->p.nu, &o, &e) != BKF_OK) {
        add_row(x, "period", AUDIT_REFUSAL, repro, "%s mu %.6g tol %g: %s", where, mu, tol, e.message);
        bkf_cycle_free(cy);
        return;
    }
    bkf_cycle_result r = *bkf_cycle_get(cy);
    bkf_cycle_free(cy);
    if (!isfinite(r.period) || !(r.period_err > 0) || !isfinite(r.period_err)) {
        add_row(x, "period", AUDIT_DEFECT, repro, "%s mu %.6g tol %g: T %g T_err %g not a result", where, mu, tol,
                r.period, r.period_err);
        return;
    }
    double ref, unc;
    const char *how;
    if (reference_period(mu, x->p.nu, r.section_slope, &ref, &unc, &how) != 0) {
        add_row(x, "period", AUDIT_OK, repro, "%s mu %.6g tol %g: T %.12g (no reference solved)", where, mu, tol,
                r.period);
        return;
    }
    double err = fabs(r.period - ref), ratio = fmax(err - unc, 0.0) / r.period_err;
    int outside = err - unc > tol * r.period;
    add_row(x, "period", outside || ratio > AUDIT_HONESTY ? AUDIT_DEFECT : AUDIT_OK, repro,
            "%s mu %.6g tol %g %s: T %.15g, %s %.15g, true/estimate %.3g%s", where, mu, tol, r.stepper, r.period,
            how, ref, ratio, outside ? ", outside tol" : "");
}

/* ------------------------------------------------------------ speeds */

/* The speed condition g(v) = n T(mu(v)) v s / S - 1 with T from another
 * integrator; *g_unc from that T's error. */
static int speed_condition(const bkf_model_params *p, size_t n, double v, double *g, double *g_unc)
{
    double mu = mu_of_v(p, v), s = p->gamma / mu, T, T_err;
    if (other_period(mu, p->nu, &T, &T_err) != 0) return -1;
    *g = (double)n * T * v * s / p->S - 1.0;
    *g_unc = (double)n * T_err * v * s / p->S;
    return 0;
}

static void audit_root(ctx *x, const bkf_speeds_root *rt, double tol)
{
    char repro[300];
    snprintf(repro, sizeof repro, "bkfront speeds %s --n %zu --tol %g", x->model, rt->n, tol);
    if (rt->status != BKF_OK) {
        add_row(x, "speeds", AUDIT_REFUSAL, repro, "n %zu refused: %s", rt->n, rt->refusal);
        return;
    }
    if (!isfinite(rt->v) || !isfinite(rt->mu) || !isfinite(rt->T) || !isfinite(rt->T_err) || !isfinite(rt->v_err)) {
        add_row(x, "speeds", AUDIT_DEFECT, repro, "n %zu: v %g mu %g T %g T_err %g v_err %g: a row not finite",
                rt->n, rt->v, rt->mu, rt->T, rt->T_err, rt->v_err);
        return;
    }
    if (rt->flags & BKF_SPEEDS_ASYMPTOTIC || rt->mu > 1e5) {
        add_row(x, "speeds", AUDIT_OK, repro, "n %zu v %.12g mu %.3g: asymptotic (not re-solved)", rt->n, rt->v,
                rt->mu);
        return;
    }
    /* Newton's step from the reported v on the independent condition */
    double g0, u0, g1, u1, dv = 1e-6 * (rt->v - x->p.c);
    if (speed_condition(&x->p, rt->n, rt->v, &g0, &u0) != 0 ||
        speed_condition(&x->p, rt->n, rt->v + dv, &g1, &u1) != 0) {
        add_row(x, "speeds", AUDIT_OK, repro, "n %zu v %.12g mu %.3g: (no reference solved)", rt->n, rt->v, rt->mu);
        return;
    }
    double slope = (g1 - g0) / dv;
    double err = fabs(g0 / slope), unc = fabs(u0 / slope) + fabs((u0 + u1) / slope) * fabs(g0) / fabs(g1 - g0 + 1e-300);
    double ratio = fmax(err - unc, 0.0) / fmax(rt->v_err, 1e-300);
    int outside = err - unc > tol * rt->v;
    add_row(x, "speeds", outside || ratio > AUDIT_HONESTY ? AUDIT_DEFECT : AUDIT_OK, repro,
            "n %zu v %.15g mu %.4g: independent condition moves v by %.3g (unc %.2g), v_err %.3g, ratio %.3g%s",
            rt->n, rt->v, rt->mu, err, unc, rt->v_err, ratio, outside ? ", outside tol" : "");
}

static size_t roots_of(const bkf_speeds_table *t, size_t n)
{
    size_t k = 0;
    for (size_t i = 0; i < t->count; i++) k += t->roots[i].n == n;
    return k;
}

/* Crossings of n h(mu) = 1, h = T v s / S, on a log grid of mu - gamma
 * (mu from gamma (1 + 1e-6), where v -> inf, to 1e5 gamma, where v -> c):
 * every crossing must be a root of the table (one within the crossing's
 * cell). */
#define SCAN_POINTS 160
static void audit_scan(ctx *x, const bkf_speeds_table *t)
{
    const bkf_model_params *p = &x->p;
    double mu[SCAN_POINTS], h[SCAN_POINTS];
    bkf_cycle *cy = bkf_cycle_alloc();
    if (!cy) return;
    bkf_cycle_options o = bkf_cycle_options_default();
    o.tol = 1e-7;
    for (int i = 0; i < SCAN_POINTS; i++) {
        double xi = pow(10.0, -6.0 + 11.0 * i / (SCAN_POINTS - 1));
        mu[i] = fmin(p->gamma * (1.0 + xi), 1e5);
        double s = p->gamma / mu[i], v = p->c / sqrt(1.0 - s * s);
        bkf_error e;
        h[i] = NAN;
        if (bkf_cycle_solve(cy, mu[i], p->nu, &o, &e) == BKF_OK) h[i] = bkf_cycle_get(cy)->period * v * s / p->S;
    }
    bkf_cycle_free(cy);
    char repro[300];
    snprintf(repro, sizeof repro, "bkfront speeds %s --tol 1e-10", x->model);
    size_t lost = 0, found = 0, refused_n = 0;
    char first[200] = "";
    for (size_t n = 1; n <= x->opt->n_max; n++) {
        for (int i = 0; i + 1 < SCAN_POINTS; i++) {
            double a = (double)n * h[i] - 1.0, b = (double)n * h[i + 1] - 1.0;
            if (!isfinite(a) || !isfinite(b) || (a > 0) == (b > 0)) continue;
            found++;
            int matched = 0, flagged = 0;
            for (size_t k = 0; k < t->count; k++) {
                if (t->roots[k].n == n && t->roots[k].mu >= mu[i] * (1 - 1e-9) && t->roots[k].mu <= mu[i + 1] * (1 + 1e-9))
                    matched = 1;
                /* a refused row of this n has no mu to match: it is there, flagged */
                flagged |= t->roots[k].n == n && t->roots[k].status != BKF_OK;
            }
            if (!matched) {
                if (!lost)
                    snprintf(first, sizeof first, "n %zu: n T v s / S - 1 changes sign over mu [%.6g, %.6g]", n,
                             mu[i], mu[i + 1]);
                lost++;
                refused_n += flagged;
            }
        }
    }
    if (lost && lost == refused_n)
        add_row(x, "speeds-scan", AUDIT_REFUSAL, repro, "%zu of %zu scanned roots not matched, each n with a "
                "refused row: %s", lost, found, t->note);
    else if (lost && t->unresolved)
        add_row(x, "speeds-scan", AUDIT_REFUSAL, repro, "%zu of %zu scanned roots missing, flagged unresolved: %s",
                lost, found, t->note);
    else
        add_row(x, "speeds-scan", lost ? AUDIT_DEFECT : AUDIT_OK, repro,
                "%zu roots by a direct scan of the condition, %zu missing from the table%s%s", found, lost,
                lost ? "; first: " : "", first);
}

/* The same roots at the tightest tol: none may vanish unflagged. */
static void audit_tight(ctx *x, const bkf_speeds_table *loose)
{
    const double tol = 1e-13;
    char repro[300];
    snprintf(repro, sizeof repro, "bkfront speeds %s --tol %g", x->model, tol);
    bkf_speeds_options so = bkf_speeds_options_default();
    so.tol = tol;
    so.n_to = x->opt->n_max;
    bkf_speeds_table t;
    bkf_error e;
    if (bkf_speeds_find(&x->p, &so, &t, &e) != BKF_OK) {
        add_row(x, "speeds-tight", AUDIT_REFUSAL, repro, "tol %g: %s", tol, e.message);
        return;
    }
    size_t lost = 0, first_n = 0;
    for (size_t n = 1; n <= x->opt->n_max; n++)
        if (roots_of(&t, n) < roots_of(loose, n)) {
            if (!lost) first_n = n;
            lost += roots_of(loose, n) - roots_of(&t, n);
        }
    if (lost && t.unresolved)
        add_row(x, "speeds-tight", AUDIT_REFUSAL, repro, "%zu roots of tol 1e-10 not at tol %g, flagged: %s", lost,
                tol, t.note);
    else if (!lost && t.refused)
        add_row(x, "speeds-tight", AUDIT_REFUSAL, repro, "%zu of %zu rows refused at tol %g, none lost: %s",
                t.refused, t.count, tol, t.note);
    else
        add_row(x, "speeds-tight", lost ? AUDIT_DEFECT : AUDIT_OK, repro,
                "%zu rows at tol %g, %zu at 1e-10; %zu lost silently (first n %zu)", t.count, tol, loose->count, lost,
                first_n);
    bkf_speeds_table_free(&t);
}

/* ------------------------------------------------------------ spectra */

typedef struct {
    int decided;     /* 1: converged with no unconverged eigenvalue above */
    double re, im, err;
} hill_answer;

/* Hill's rightmost eigenvalue of the train (n, v) over its Bloch classes,
 * the translation (j = 0, sigma ~ 0) excluded. */
static hill_answer hill_rightmost(const bkf_model_params *p, const bkf_speeds_root *rt)
{
    hill_answer h = {0, NAN, NAN, NAN};
    bkf_cycle *cy = bkf_cycle_alloc();
    if (!cy) return h;
    bkf_cycle_options o = bkf_cycle_options_default();
    o.tol = 1e-12;
    bkf_error e;
    if (bkf_cycle_solve(cy, rt->mu, p->nu, &o, &e) != BKF_OK) {
        o.tol = 1e-10;
        if (bkf_cycle_solve(cy, rt->mu, p->nu, &o, &e) != BKF_OK) {
            bkf_cycle_free(cy);
            return h;
        }
    }
    for (size_t m = 0; m < sizeof hill_modes / sizeof hill_modes[0] && !h.decided; m++) {
        int all = 1;
        double best = -INFINITY, best_im = NAN, best_err = NAN;
        for (size_t j = 0; j < rt->n && all; j++) {
            bkf_hill_eigenvalue ev[6];
            double ee[6];
            size_t found = 0, unresolved = 0;
            double theta = 2.0 * acos(-1.0) * (double)j / (double)rt->n;
            if (bkf_hill_leading(cy, p->gamma, theta, hill_modes[m], 1e-6, 6, ev, ee, &found, &unresolved, &e) !=
                    BKF_OK ||
                unresolved > 0 || found == 0) {
                all = 0;
                break;
            }
            size_t used = 0;
            for (size_t k = 0; k < found; k++) {
                if (j == 0 && hypot(ev[k].re, ev[k].im) <= fmax(1e-6, 10.0 * ee[k])) continue;
                used++;
                if (ev[k].re > best) best = ev[k].re, best_im = ev[k].im, best_err = ee[k];
            }
            if (!used) all = 0;
        }
        if (all && isfinite(best)) h = (hill_answer){1, best, best_im, best_err};
    }
    bkf_cycle_free(cy);
    return h;
}

/* The ring's rightmost at j = 0 other than the translation. */
static double ring_j0(const bkf_trainspec_result *r, double *err)
{
    double best = -INFINITY;
    *err = 0.0;
    for (size_t i = 0; i < r->count; i++)
        if (r->eigenvalues[i].j == 0 && !r->eigenvalues[i].translation && r->eigenvalues[i].re > best) {
            best = r->eigenvalues[i].re;
            *err = r->eigenvalues[i].err;
        }
    return best;
}

static void stage(const char *name);
static void audit_spectrum(ctx *x, const bkf_speeds_root *rt, size_t root_index, hill_answer *hill_out)
{
    char repro[300];
    snprintf(repro, sizeof repro, "bkfront stability %s --n %zu --root %zu", x->model, rt->n, root_index);
    if (rt->status != BKF_OK) {
        *hill_out = (hill_answer){0, NAN, NAN, NAN};
        add_row(x, "stability", AUDIT_REFUSAL, repro, "n %zu: its speed refused: %s", rt->n, rt->refusal);
        return;
    }
    hill_answer h = hill_rightmost(&x->p, rt);
    *hill_out = h;
    stage("hill");
    bkf_trainspec_result r;
    bkf_error e;
    int rc = bkf_trainspec_root(&x->p, rt, 1e-6, 3, &r, &e);
    stage("ring");
    if (rc != BKF_OK) {
        if (h.decided)
            add_row(x, "stability", AUDIT_REFUSAL, repro, "n %zu mu %.4g: %s (Hill answers %.6g%+.6gi +- %.2g)",
                    rt->n, rt->mu, e.message, h.re, h.im, h.err);
        else
            add_row(x, "stability", AUDIT_REFUSAL, repro, "n %zu mu %.4g: %s", rt->n, rt->mu, e.message);
        return;
    }
    bkf_trainspec_shown shown = bkf_trainspec_shown_of(&r);
    if (isfinite(shown.bound)) {
        /* no eigenvalue but a bound (the products print nan): right when
         * Hill's rightmost lies left of it */
        add_row(x, "stability", h.decided && h.re > shown.bound + h.err ? AUDIT_DEFECT : AUDIT_OK, repro,
                "n %zu mu %.4g: every eigenvalue left of %.8g (%s), Hill %.8g +- %.2g%s", rt->n, rt->mu, shown.bound,
                bkf_trainspec_verdict_name(r.verdict), h.re, h.err, h.decided ? "" : " (unconverged)");
    } else if (!isfinite(r.sigma_max) || !isfinite(r.sigma_max_err)) {
        add_row(x, "stability", AUDIT_DEFECT, repro, "n %zu: sigma_max %g +- %g not a result", rt->n, r.sigma_max,
                r.sigma_max_err);
    } else if (h.decided) {
        double diff = fabs(r.sigma_max - h.re), allowed = AUDIT_HONESTY * (r.sigma_max_err + h.err) + 1e-9;
        add_row(x, "stability", diff > allowed ? AUDIT_DEFECT : AUDIT_OK, repro,
                "n %zu mu %.4g: sigma_max %.8g +- %.2g (%s), Hill %.8g%+.6gi +- %.2g", rt->n, rt->mu, r.sigma_max,
                r.sigma_max_err, bkf_trainspec_verdict_name(r.verdict), h.re, h.im, h.err);
    } else {
        add_row(x, "stability", AUDIT_OK, repro, "n %zu mu %.4g: sigma_max %.8g +- %.2g (Hill unconverged)", rt->n,
                rt->mu, r.sigma_max, r.sigma_max_err);
    }
    if (x->opt->line) {
        char lrepro[320];
        snprintf(lrepro, sizeof lrepro, "%s --line", repro);
        bkf_trainspec_train tr = {rt->n, rt->v};
        bkf_trainspec_options to = bkf_trainspec_options_default();
        to.tol = 1e-6;
        /* (the line's Bloch numbers: kappa_i = (2 pi / L) i / count; i = 0 is kappa 0) */
        bkf_trainspec_eigenvalue line[2], l0;
        double j0_err, j0 = ring_j0(&r, &j0_err);
        int lrc = bkf_trainspec_line(&x->p, &tr, &to, 2, line, &e);
        l0 = line[0];
        if (lrc != BKF_OK) {
            add_row(x, "line", AUDIT_REFUSAL, lrepro, "n %zu: %s", rt->n, e.message);
        } else if (!isfinite(l0.re)) {
            add_row(x, "line", AUDIT_DEFECT, lrepro, "n %zu kappa 0: sigma %g not a result", rt->n, l0.re);
        } else if (isfinite(j0)) {
            double allowed = AUDIT_HONESTY * (l0.err + j0_err) + 1e-9;
            add_row(x, "line", j0 > l0.re + allowed ? AUDIT_DEFECT : AUDIT_OK, lrepro,
                    "n %zu kappa 0: line's rightmost %.8g +- %.2g, the ring's at j 0 %.8g +- %.2g", rt->n, l0.re,
                    l0.err, j0, j0_err);
        } else {
            add_row(x, "line", AUDIT_OK, lrepro, "n %zu kappa 0: %.8g (the ring has no other j 0 eigenvalue)", rt->n,
                    l0.re);
        }
    }
    bkf_trainspec_result_free(&r);
}

/* ------------------------------------------------------------ check */

typedef struct {
    bkf_check_row rows[8];
    size_t count;
} check_rows;

static int keep_row(const bkf_check_row *row, void *data)
{
    check_rows *c = data;
    if (c->count < sizeof c->rows / sizeof c->rows[0]) c->rows[c->count++] = *row;
    return 0;
}

static void audit_check(ctx *x, const bkf_speeds_table *t, const hill_answer *hill_first)
{
    char repro[300];
    snprintf(repro, sizeof repro, "bkfront check %s --n 1", x->model);
    bkf_check_options o = bkf_check_options_default();
    o.n = 1;
    check_rows got = {.count = 0};
    bkf_check_hooks hooks = {.row = keep_row, .data = &got};
    bkf_error e;
    if (bkf_check_run(&x->p, &o, &hooks, &e) != BKF_OK) {
        add_row(x, "check", AUDIT_REFUSAL, repro, "%s", e.message);
        return;
    }
    for (size_t i = 0; i < got.count; i++) {
        const bkf_check_row *r = &got.rows[i];
        /* Hill for this root: the first root's is in hand */
        hill_answer h = {0, NAN, NAN, NAN};
        if (r->root == 1 && hill_first) {
            h = *hill_first;
        } else {
            for (size_t k = 0; k < t->count; k++) {
                if (t->roots[k].n != r->n) continue;
                size_t idx = 0;
                for (size_t m = 0; m <= k; m++) idx += t->roots[m].n == r->n;
                if (idx == r->root && t->roots[k].status == BKF_OK) h = hill_rightmost(&x->p, &t->roots[k]);
            }
        }
        int hill_unstable = h.decided && h.re > AUDIT_HONESTY * h.err && h.re > 1e-9;
        int judged_stable = r->verdict == BKF_CHECK_AGREES || r->verdict == BKF_CHECK_DISAGREES;
        const char *name = bkf_check_verdict_name(r->verdict);
        char what[200];
        snprintf(what, sizeof what, "n %zu root %zu: %s, v_meas %.10g, spectral %s sigma_max %.6g +- %.2g, growth %s",
                 r->n, r->root, name, r->v_meas, bkf_trainspec_verdict_name(r->spectral), r->sigma_max,
                 r->sigma_max_err, bkf_check_growth_name(r->growth.verdict));
        if (r->verdict == BKF_CHECK_UNRESOLVED) {
            add_row(x, "check", AUDIT_REFUSAL, repro, "%s", what);
        } else if (r->verdict == BKF_CHECK_AGREES && hill_unstable) {
            add_row(x, "check", AUDIT_DEFECT, repro, "%s; Hill: unstable %.6g +- %.2g", what, h.re, h.err);
        } else if (r->verdict == BKF_CHECK_AGREES && r->spectral != BKF_TRAINSPEC_STABLE &&
                   r->growth.verdict != BKF_CHECK_GROWTH_DECAYS) {
            add_row(x, "check", AUDIT_DEFECT, repro, "%s: agrees without a decided spectrum or decay", what);
        } else if (judged_stable && !isfinite(r->v_meas)) {
            add_row(x, "check", AUDIT_DEFECT, repro, "%s: a verdict on a speed not measured", what);
        } else if (isfinite(r->sigma_max) && !(r->sigma_max_err > 0)) {
            add_row(x, "check", AUDIT_DEFECT, repro, "%s: sigma_max with error %g (a window's edge?)", what,
                    r->sigma_max_err);
        } else if (isfinite(r->sigma_max) && h.decided &&
                   fabs(r->sigma_max - h.re) > AUDIT_HONESTY * (r->sigma_max_err + h.err) + 1e-9) {
            add_row(x, "check", AUDIT_DEFECT, repro, "%s; Hill %.8g +- %.2g", what, h.re, h.err);
        } else {
            add_row(x, "check", AUDIT_OK, repro, "%s", what);
        }
    }
}

/* ------------------------------------------------------------ floquet */

static void audit_floquet(ctx *x)
{
    const double tol = 1e-8, cq[] = {1.0, 4.0};
    for (size_t i = 0; i < sizeof cq / sizeof cq[0]; i++) {
        double q = cq[i] / x->p.c;
        char repro[300];
        snprintf(repro, sizeof repro, "bkfront floquet --gamma %.6g --c %.6g --nu %.6g --q %.17g --tol %g --stepper ",
                 x->p.gamma, x->p.c, x->p.nu, q, tol);
        double lam[2] = {NAN, NAN}, lerr[2] = {NAN, NAN};
        const bkf_stepper_kind kinds[2] = {BKF_STEPPER_EXPLICIT, BKF_STEPPER_IMPLICIT};
        const char *names[2] = {"explicit", "implicit"};
        int refused = 0;
        for (int k = 0; k < 2 && !refused; k++) {
            bkf_floquet *f = bkf_floquet_alloc();
            bkf_floquet_options o = bkf_floquet_options_default();
            o.tol = tol;
            o.stepper = kinds[k];
            bkf_floquet_point pt;
            bkf_error e;
            if (!f) return;
            if (bkf_floquet_set(f, x->p.gamma, x->p.c, x->p.nu, &o, &e) != BKF_OK ||
                bkf_floquet_eval(f, q, &pt, &e) != BKF_OK) {
                char r2[320];
                snprintf(r2, sizeof r2, "%s%s", repro, names[k]);
                add_row(x, "floquet", AUDIT_REFUSAL, r2, "c q %g, %s: %s", cq[i], names[k], e.message);
                refused = 1;
            } else {
                lam[k] = pt.lambda;
                lerr[k] = pt.lambda_err;
            }
            bkf_floquet_free(f);
        }
        if (refused) continue;
        char r2[320];
        snprintf(r2, sizeof r2, "%sexplicit", repro);
        int finite = isfinite(lam[0]) && isfinite(lam[1]) && isfinite(lerr[0]) && isfinite(lerr[1]);
        double diff = fabs(lam[0] - lam[1]);
        add_row(x, "floquet",
                !finite || diff > AUDIT_HONESTY * (lerr[0] + lerr[1]) + 1e-12 ? AUDIT_DEFECT : AUDIT_OK, r2,
                "c q %g: lambda rk8pd %.12g +- %.2g, bsimp %.12g +- %.2g", cq[i], lam[0], lerr[0], lam[1], lerr[1]);
    }
}

/* ------------------------------------------------------------ a set */

/* AUDIT_TIMING=1: each stage's processor time on stderr (where a set's
 * time goes) */
static void stage(const char *name)
{
    static clock_t last;
    clock_t t = clock();
    if (getenv("AUDIT_TIMING") && name) fprintf(stderr, "audit: %-12s %.2f s\n", name, (double)(t - last) / CLOCKS_PER_SEC);
    last = t;
}

void audit_run_set(size_t index, const audit_set *set, const audit_options *options, audit_rows *out)
{
    ctx x = {.index = index, .set = set, .opt = options, .out = out};
    x.p = bkf_model_params_paper();
    x.p.gamma = set->gamma;
    x.p.c = set->c;
    x.p.nu = set->nu;
    x.p.S = set->S;
    snprintf(x.model, sizeof x.model, "--gamma %.6g --c %.6g --nu %.6g --S %.6g", set->gamma, set->c, set->nu,
             set->S);
    stage(NULL);
    if (options->period) {
        audit_period(&x, set->gamma, 1e-4, "oscillation");
        audit_period(&x, set->gamma, 1e-7, "oscillation");
        audit_period(&x, set->gamma, 1e-10, "oscillation");
    }
    stage("period");
    if (options->floquet) audit_floquet(&x);
    stage("floquet");
    if (!options->speeds && !options->stability && !options->check) return;
    bkf_speeds_options so = bkf_speeds_options_default();
    so.n_to = options->n_max;
    bkf_speeds_table t;
    bkf_error e;
    char repro[300];
    snprintf(repro, sizeof repro, "bkfront speeds %s --nmax %zu", x.model, options->n_max);
    if (bkf_speeds_find(&x.p, &so, &t, &e) != BKF_OK) {
        add_row(&x, "speeds", AUDIT_REFUSAL, repro, "%s", e.message);
        return;
    }
    if (options->speeds) {
        if (t.count == 0) add_row(&x, "speeds", AUDIT_OK, repro, "no root for n <= %zu (%s)", options->n_max, t.note);
        stage("speeds");
        for (size_t i = 0; i < t.count; i++) audit_root(&x, &t.roots[i], so.tol);
        stage("roots");
        if (options->scan) audit_scan(&x, &t);
        stage("scan");
        audit_tight(&x, &t);
        stage("tight");
    }
    hill_answer first_n1 = {0, NAN, NAN, NAN};
    int have_first_n1 = 0;
    if (options->stability || options->period) {
        /* the fastest root of n = 1 and of n = 2 */
        for (size_t n = 1; n <= 2; n++) {
            for (size_t i = 0; i < t.count; i++) {
                if (t.roots[i].n != n) continue;
                if (options->period && t.roots[i].mu <= 1e5) audit_period(&x, t.roots[i].mu, 1e-8, "root");
                if (options->stability) {
                    hill_answer h;
                    audit_spectrum(&x, &t.roots[i], 1, &h);
                    if (n == 1) first_n1 = h, have_first_n1 = 1;
                }
                break;
            }
        }
    }
    stage("stability");
    if (options->check && roots_of(&t, 1) > 0) audit_check(&x, &t, have_first_n1 ? &first_n1 : NULL);
    stage("check");
    bkf_speeds_table_free(&t);
}

/* ------------------------------------------------------------ report */

size_t audit_report(FILE *f, const audit_rows *rows, size_t refusals_shown)
{
    static const char *products[] = {"period", "speeds", "speeds-scan", "speeds-tight", "stability",
                                     "line", "check", "floquet"};
    const size_t np = sizeof products / sizeof products[0];
    size_t defects = 0;
    fprintf(f, "%-13s %6s %7s %8s %9s\n", "product", "OK", "defect", "refusal", "refused");
    for (size_t k = 0; k < np; k++) {
        size_t c[3] = {0, 0, 0};
        for (size_t i = 0; i < rows->count; i++)
            if (!strcmp(rows->rows[i].product, products[k])) c[rows->rows[i].status]++;
        size_t all = c[0] + c[1] + c[2];
        fprintf(f, "%-13s %6zu %7zu %8zu %8.1f%%\n", products[k], c[0], c[1], c[2], all ? 100.0 * c[2] / all : 0.0);
        defects += c[1];
    }
    if (defects) {
        fprintf(f, "\ndefects (set, product, what, reproducer):\n");
        for (size_t i = 0; i < rows->count; i++)
            if (rows->rows[i].status == AUDIT_DEFECT)
                fprintf(f, "  set %zu %s: %s\n    %s\n", rows->rows[i].set, rows->rows[i].product,
                        rows->rows[i].detail, rows->rows[i].repro);
    }
    size_t shown = 0;
    for (size_t i = 0; i < rows->count && shown < refusals_shown; i++)
        if (rows->rows[i].status == AUDIT_REFUSAL) {
            if (!shown) fprintf(f, "\nrefusals (first %zu):\n", refusals_shown);
            fprintf(f, "  set %zu %s: %s\n    %s\n", rows->rows[i].set, rows->rows[i].product, rows->rows[i].detail,
                    rows->rows[i].repro);
            shown++;
        }
    return defects;
}

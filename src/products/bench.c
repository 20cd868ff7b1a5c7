/* Work-precision measurements (bench.h): achieved error against CPU time for
 * every method and tolerance of the period, the speeds table and the PDE. */
#define _POSIX_C_SOURCE 200809L
#include "bkfront/bench.h"

#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bkfront/asymptotics.h"
#include "bkfront/cycle.h"
#include "bkfront/measure.h"
#include "bkfront/pde.h"
#include "bkfront/seed.h"
#include "bkfront/speeds.h"
#include "product_internal.h"

static const bkf_io_column columns[] = {
    {"product", BKF_IO_TEXT},  {"case", BKF_IO_TEXT},     {"method", BKF_IO_TEXT},
    {"tol", BKF_IO_NUMBER},    {"N", BKF_IO_NUMBER},      {"error", BKF_IO_NUMBER},
    {"estimate", BKF_IO_NUMBER}, {"cpu_seconds", BKF_IO_NUMBER}, {"work", BKF_IO_NUMBER},
    {"status", BKF_IO_TEXT},
};
#define NCOLUMNS (sizeof columns / sizeof columns[0])

static const char *const product_names[] = {"period", "speeds", "pde", "all", "box", NULL};

const bkf_io_column *bkf_bench_columns(size_t *count)
{
    if (count) *count = NCOLUMNS;
    return columns;
}

const char *const *bkf_bench_product_names(void)
{
    return product_names;
}

static double cpu_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

typedef struct {
    bkf_io_table *table;
    int quick;
} bench_ctx;

static int emit(bench_ctx *b, const char *product, const char *kase, const char *method,
                double tol, double N, double error, double estimate, double seconds, double work,
                const char *status, bkf_error *err)
{
    bkf_io_value v[NCOLUMNS] = {
        {.text = product}, {.text = kase},       {.text = method},   {.number = tol},
        {.number = N},     {.number = error},    {.number = estimate}, {.number = seconds},
        {.number = work},  {.text = status},
    };
    return bkf_io_table_row(b->table, v, err);
}

/* ------------------------------------------------------------- period */

static int period_reference(double mu, double nu, bkf_stepper_kind kind, double *T)
{
    if (mu == 1.0 && nu == 0.0) {
        *T = 6.663286859323130;
        return BKF_OK;
    }
    const double tols[] = {1e-13, 1e-12, 1e-11};
    for (int k = 0; k < 3; k++) {
        bkf_cycle_options o = bkf_cycle_options_default();
        o.tol = tols[k];
        o.stepper = kind;
        bkf_cycle_result r;
        bkf_error e;
        if (bkf_cycle_period(mu, nu, &o, &r, &e) == BKF_OK) {
            *T = r.period;
            return BKF_OK;
        }
    }
    return BKF_ENUMERIC;
}

/* CPU seconds per cold solve (repeated to at least 20 ms), or -1 if refused. */
static double time_solve(double mu, double nu, double tol, bkf_stepper_kind kind,
                         bkf_cycle_result *r)
{
    bkf_cycle_options o = bkf_cycle_options_default();
    o.tol = tol;
    o.stepper = kind;
    bkf_error e;
    int reps = 0;
    double t0 = cpu_now(), t = 0;
    do {
        if (bkf_cycle_period(mu, nu, &o, r, &e) != BKF_OK) return -1;
        reps++;
        t = cpu_now() - t0;
    } while (t < 0.02 && reps < 1000);
    return t / reps;
}

static int bench_period(bench_ctx *b, bkf_error *err)
{
    const double mus[] = {1, 10, 100, 1e4};
    const double nus[] = {0, -0.96};
    const double tols_full[] = {1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12};
    const double tols_quick[] = {1e-2, 1e-6, 1e-12};
    const double *tols = b->quick ? tols_quick : tols_full;
    size_t ntol = b->quick ? 3 : sizeof tols_full / sizeof tols_full[0];
    size_t nmu = b->quick ? 2 : 4, nnu = b->quick ? 1 : 2;
    int s = BKF_OK;
    for (size_t j = 0; j < nnu && !s; j++)
        for (size_t i = 0; i < nmu && !s; i++) {
            double mu = mus[i], nu = nus[j];
            char kase[64];
            snprintf(kase, sizeof kase, "mu=%g,nu=%g", mu, nu);
            /* formulas: their error, their bound, and the (tiny) cost of a call */
            for (int f = 0; f < 2 && !s; f++) {
                bkf_asym_formula form = f == 0 ? BKF_ASYM_LEADING
                                        : mu >= 1 ? BKF_ASYM_LARGE
                                                  : BKF_ASYM_SMALL;
                double Tref;
                if (period_reference(mu, nu, mu > 30 ? BKF_STEPPER_IMPLICIT : BKF_STEPPER_EXPLICIT,
                                     &Tref))
                    return bkf_error_set(err, BKF_ENUMERIC, "no reference at %s", kase);
                volatile double sink = 0;
                double t0 = cpu_now();
                for (int k = 0; k < 100000; k++) sink += bkf_asym_period(form, mu + 1e-300 * k, nu);
                double t = (cpu_now() - t0) / 100000;
                (void)sink;
                double T = bkf_asym_period(form, mu, nu);
                s = emit(b, "period", kase, f == 0 ? "leading" : "asymptotic", NAN, NAN,
                         fabs(T - Tref) / Tref, bkf_asym_error_bound(form, mu, nu), t, 0, "ok", err);
            }
            for (int k = 0; k < 2 && !s; k++) {
                bkf_stepper_kind kind = k == 0 ? BKF_STEPPER_EXPLICIT : BKF_STEPPER_IMPLICIT;
                /* rk8pd at mu = 1e4 takes ~1e6 steps a period: not offered there */
                if (kind == BKF_STEPPER_EXPLICIT && mu > 1e3) continue;
                bkf_stepper_kind other = kind == BKF_STEPPER_EXPLICIT && mu <= 1e3
                                             ? BKF_STEPPER_IMPLICIT
                                             : BKF_STEPPER_EXPLICIT;
                if (mu > 1e3) other = BKF_STEPPER_IMPLICIT;
                double Tref;
                if (period_reference(mu, nu, other, &Tref))
                    return bkf_error_set(err, BKF_ENUMERIC, "no reference at %s", kase);
                for (size_t q = 0; q < ntol && !s; q++) {
                    bkf_cycle_result r;
                    double t = time_solve(mu, nu, tols[q], kind, &r);
                    const char *name = kind == BKF_STEPPER_EXPLICIT ? "rk8pd" : "bsimp";
                    if (t < 0)
                        s = emit(b, "period", kase, name, tols[q], NAN, NAN, NAN, NAN, NAN,
                                 "refused", err);
                    else
                        s = emit(b, "period", kase, name, tols[q], NAN,
                                 fabs(r.period - Tref) / Tref, r.period_err / r.period, t,
                                 (double)r.rhs_calls, "ok", err);
                }
            }
        }
    return s;
}

/* ---------------------------------------------------------------- box */

/* CPU seconds per cold T(mu, nu) by bkf_cycle_estimate (fresh cycle object
 * each call, as a one-off caller has), repeated to at least 20 ms; -1 if
 * refused. */
static double time_estimate(double mu, double nu, double tol, bkf_cycle_method m,
                            bkf_cycle_result *r)
{
    bkf_cycle_options o = bkf_cycle_options_default();
    o.tol = tol;
    bkf_error e;
    int reps = 0;
    double t0 = cpu_now(), t = 0;
    do {
        bkf_cycle *c = bkf_cycle_alloc();
        int rc = c ? bkf_cycle_estimate(c, mu, nu, &o, m, r, &e) : BKF_ENOMEM;
        bkf_cycle_free(c);
        if (rc != BKF_OK) return -1;
        reps++;
        t = cpu_now() - t0;
    } while (t < 0.02 && reps < 100000);
    return t / reps;
}

static int compare_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The cost goal on the whole box: T at tol 1e-6 against 1e-12, per
 * point and in aggregate (sum of the times), with --method shooting and
 * auto.  Everything is measured first: the summary goes in comment lines,
 * which must precede the rows. */
static int bench_box(bench_ctx *b, bkf_error *err)
{
    const double mus_full[] = {1e-3, 1e-2, 0.1, 1, 3, 10, 30, 100, 1e3, 1e4};
    const double mus_quick[] = {1e-2, 1, 100};
    const double nus_full[] = {0, -0.9, 0.99, -0.999, 0.9999};
    const double nus_quick[] = {0, 0.9999};
    const double *mus = b->quick ? mus_quick : mus_full, *nus = b->quick ? nus_quick : nus_full;
    size_t nmu = b->quick ? 3 : 10, nnu = b->quick ? 2 : 5, npt = nmu * nnu;
    const double tols[2] = {1e-6, 1e-12};
    const bkf_cycle_method methods[2] = {BKF_METHOD_SHOOTING, BKF_METHOD_AUTO};
    typedef struct {
        double T, err, t;
        size_t work;
        char model[16];
    } meas;
    meas *m = calloc(npt * 4, sizeof *m);
    double *ratios = calloc(npt, sizeof *ratios);
    if (!m || !ratios) {
        free(m);
        free(ratios);
        return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    }
    for (size_t i = 0; i < npt; i++) {
        double mu = mus[i / nnu], nu = nus[i % nnu];
        for (int k = 0; k < 4; k++) {
            bkf_cycle_result r;
            meas *x = &m[4 * i + k];
            x->t = time_estimate(mu, nu, tols[k % 2], methods[k / 2], &r);
            if (x->t < 0) continue;
            x->T = r.period;
            x->err = r.period_err / r.period;
            x->work = r.rhs_calls;
            snprintf(x->model, sizeof x->model, "%s", r.model);
        }
    }
    int s = BKF_OK;
    for (int q = 0; q < 2 && !s; q++) {
        size_t n = 0;
        double sum6 = 0, sum12 = 0;
        for (size_t i = 0; i < npt; i++) {
            const meas *lo = &m[4 * i + 2 * q], *hi = &m[4 * i + 2 * q + 1];
            if (lo->t < 0 || hi->t < 0) continue;
            ratios[n++] = hi->t / lo->t;
            sum6 += lo->t;
            sum12 += hi->t;
        }
        qsort(ratios, n, sizeof *ratios, compare_double);
        char line[320];
        if (n)
            snprintf(line, sizeof line,
                     "box, --method %s: time(tol 1e-12)/time(tol 1e-6) per point min %.3g, "
                     "median %.3g, max %.3g over %zu points (%zu refused at either tol, left "
                     "out); aggregate (sum of times) %.3g",
                     bkf_cycle_method_name(methods[q]), ratios[0], ratios[n / 2], ratios[n - 1], n,
                     npt - n, sum12 / sum6);
        else
            snprintf(line, sizeof line, "box, --method %s: every point refused",
                     bkf_cycle_method_name(methods[q]));
        s = bkf_io_table_comment(b->table, line, err);
    }
    for (size_t i = 0; i < npt && !s; i++) {
        double mu = mus[i / nnu], nu = nus[i % nnu];
        char kase[64];
        snprintf(kase, sizeof kase, "mu=%g,nu=%g", mu, nu);
        /* reference: the other stepper than the auto choice at tol 1e-12
         * (bsimp above mu = 300, as in the period product) */
        double Tref = NAN;
        if (period_reference(mu, nu, mu > 30 && mu <= 300 ? BKF_STEPPER_EXPLICIT
                                                           : BKF_STEPPER_IMPLICIT, &Tref))
            Tref = NAN;
        for (int k = 0; k < 4 && !s; k++) {
            const meas *x = &m[4 * i + k];
            char method[40];
            snprintf(method, sizeof method, "%s(%s)", bkf_cycle_method_name(methods[k / 2]),
                     x->t < 0 ? "-" : x->model);
            if (x->t < 0)
                s = emit(b, "box", kase, method, tols[k % 2], NAN, NAN, NAN, NAN, NAN, "refused",
                         err);
            else
                s = emit(b, "box", kase, method, tols[k % 2], NAN, fabs(x->T - Tref) / Tref,
                         x->err, x->t, (double)x->work, "ok", err);
        }
    }
    free(m);
    free(ratios);
    return s;
}

/* ------------------------------------------------------------- speeds */

static int bench_speeds(bench_ctx *b, bkf_error *err)
{
    bkf_model_params p = {2.0, 0.3, -0.96, 20.0, 0, BKF_MODEL_CONTINUUM};
    bkf_speeds_options o = bkf_speeds_options_default();
    bkf_speeds_table ref = {0};
    o.tol = 1e-13;
    int s = bkf_speeds_find(&p, &o, &ref, err);
    /* a reference with a root refused or left unresolved (T refused at
     * 1e-13) is no reference */
    if (s || ref.unresolved || ref.refused) {
        bkf_speeds_table_free(&ref);
        o.tol = 1e-12;
        if ((s = bkf_speeds_find(&p, &o, &ref, err))) {
            bkf_speeds_table_free(&ref);
            return s;
        }
        if (ref.unresolved || ref.refused) {
            size_t bad = ref.unresolved + ref.refused;
            bkf_speeds_table_free(&ref);
            return bkf_error_set(err, BKF_ETOL, "bench: the reference speeds table at tol 1e-12 left %zu "
                                 "root(s) refused or place(s) unresolved", bad);
        }
    }
    const double tols_full[] = {1e-4, 1e-6, 1e-8, 1e-10, 1e-12};
    const double tols_quick[] = {1e-6};
    const double *tols = b->quick ? tols_quick : tols_full;
    size_t ntol = b->quick ? 1 : 5;
    for (size_t q = 0; q < ntol && !s; q++) {
        bkf_speeds_table t = {0};
        o.tol = tols[q];
        bkf_error e;
        int reps = 0;
        double t0 = cpu_now(), dt = 0;
        int rc = BKF_OK;
        do {
            bkf_speeds_table_free(&t);
            memset(&t, 0, sizeof t);
            rc = bkf_speeds_find(&p, &o, &t, &e);
            reps++;
            dt = cpu_now() - t0;
        } while (rc == BKF_OK && dt < 0.1 && reps < 50);
        if (rc != BKF_OK || t.count != ref.count || t.refused) {
            s = emit(b, "speeds", "paper", "speeds", tols[q], NAN, NAN, NAN, NAN, NAN, "refused",
                     err);
        } else {
            double worst = 0, est = 0;
            for (size_t i = 0; i < t.count; i++) {
                worst = fmax(worst, fabs(t.roots[i].v - ref.roots[i].v) / ref.roots[i].v);
                est = fmax(est, t.roots[i].v_err / t.roots[i].v);
            }
            s = emit(b, "speeds", "paper", "speeds", tols[q], NAN, worst, est, dt / reps,
                     (double)(t.coarse_solves + t.precise_solves), "ok", err);
        }
        bkf_speeds_table_free(&t);
    }
    bkf_speeds_table_free(&ref);
    return s;
}

/* --------------------------------------------------------------- pde */

static int observe(const bkf_pde_sample *s, void *data)
{
    bkf_error e;
    return bkf_measure_add(data, s->t, s->psi, s->eta, &e) != BKF_OK;
}

static int bench_pde(bench_ctx *b, bkf_error *err)
{
    const size_t Ns_full[] = {256, 512, 1024}, Ns_quick[] = {256};
    const double tols_full[] = {1e-5, 1e-7, 1e-9}, tols_quick[] = {1e-7};
    const size_t *Ns = b->quick ? Ns_quick : Ns_full;
    const double *tols = b->quick ? tols_quick : tols_full;
    size_t nN = b->quick ? 1 : 3, ntol = b->quick ? 1 : 3;
    double tmax = b->quick ? 5.0 : 30.0;
    int s = BKF_OK;
    for (size_t i = 0; i < nN && !s; i++)
        for (size_t q = 0; q < ntol && !s; q++) {
            bkf_model_params p = {2.0, 0.3, -0.96, 20.0, Ns[i], BKF_MODEL_CONTINUUM};
            bkf_pde_options o = bkf_pde_options_default();
            o.tol = tols[q];
            bkf_pde *m = bkf_pde_alloc(&p, &o, err);
            if (!m) return BKF_ENOMEM;
            bkf_pde_front_spec fs = bkf_pde_front_spec_default();
            fs.n = 4;
            bkf_pde_front_info fi;
            s = bkf_seed_front(m, &fs, &fi, NULL, err);
            bkf_measure_params mp = bkf_measure_params_default();
            mp.model = p;
            mp.level = p.nu; /* the bench's fronts: crossings of nu, as ever */
            bkf_measure *ms = s ? NULL : bkf_measure_alloc(&mp, err);
            if (!s && !ms) s = BKF_ENOMEM;
            double t0 = cpu_now();
            bkf_error e;
            int rc = s ? s : bkf_pde_run(m, tmax, 0.1, observe, ms, NULL, NULL, &e);
            double dt = cpu_now() - t0;
            bkf_measure_summary sum;
            if (!s && rc == BKF_OK) rc = bkf_measure_summarize(ms, &sum, &e);
            if (!s) {
                if (rc != BKF_OK)
                    s = emit(b, "pde", "front n=4", "rk8pd", tols[q], (double)Ns[i], NAN, NAN, dt,
                             NAN, "refused", err);
                else
                    s = emit(b, "pde", "front n=4", "rk8pd", tols[q], (double)Ns[i],
                             fabs(-sum.speed - fi.v) / fi.v, sum.speed_err / fi.v, dt,
                             (double)bkf_pde_get_stats(m)->steps, "ok", err);
            }
            bkf_measure_free(ms);
            bkf_pde_free(m);
        }
    return s;
}

int bkf_bench_run(bkf_bench_product which, int quick, bkf_io_table *table, bkf_error *err)
{
    if ((unsigned)which > BKF_BENCH_BOX)
        return bkf_error_set(err, BKF_EINPUT, "bench product %d is not one of period, speeds, "
                             "pde, all, box", (int)which);
    if (!table) return bkf_error_set(err, BKF_EINPUT, "bench: no table to write to");
    bench_ctx b = {table, quick};
    int s = BKF_OK;
    if (which == BKF_BENCH_PERIOD || which == BKF_BENCH_ALL) s = bench_period(&b, err);
    if (!s && (which == BKF_BENCH_SPEEDS || which == BKF_BENCH_ALL)) s = bench_speeds(&b, err);
    if (!s && (which == BKF_BENCH_PDE || which == BKF_BENCH_ALL)) s = bench_pde(&b, err);
    if (!s && which == BKF_BENCH_BOX) s = bench_box(&b, err);
    return s;
}

const bkf_option bkf_bench_options[] = {
    {.name = "product", .type = BKF_OPT_CHOICE, .offset = offsetof(bkf_bench_spec, product),
     .choices = product_names, .form = "P", .shown_default = "all",
     .help = "which measurement: period, speeds, pde, all (those three) or box"},
    {.name = "quick", .type = BKF_OPT_SWITCH, .offset = offsetof(bkf_bench_spec, quick),
     .help = "fewer cases and tolerances (for tests)"},
};
const size_t bkf_bench_noptions = sizeof bkf_bench_options / sizeof bkf_bench_options[0];

bkf_bench_spec bkf_bench_spec_default(void)
{
    return (bkf_bench_spec){BKF_BENCH_ALL, 0};
}

int bkf_bench_check(const bkf_bench_spec *spec, const char *prefix, bkf_error *err)
{
    if (!spec || (unsigned)spec->product > BKF_BENCH_BOX)
        return bkf_error_set(err, BKF_EINPUT, "%sproduct: not one of period, speeds, pde, all, "
                             "box", prefix ? prefix : "");
    return BKF_OK;
}

int bkf_bench_write(const bkf_bench_spec *spec, FILE *out, bkf_io_format format,
                    const bkf_provenance *provenance, bkf_error *err)
{
    int s = bkf_bench_check(spec, "", err);
    if (s) return s;
    bkf_io_table *t;
    s = bkf_product_table_open(out, format, columns, NCOLUMNS,
                               "bench: work-precision (achieved relative error against CPU "
                               "seconds per call, one core)",
                               provenance, &t, err);
    if (s) return s;
    s = bkf_product_table_command(t, provenance, err);
    if (!s) s = bkf_bench_run((bkf_bench_product)spec->product, spec->quick, t, err);
    if (!s) s = bkf_io_table_finish(t, err);
    bkf_io_table_free(t);
    return s;
}

#include "bkfront/oscillation.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bkfront/model.h"

#define COUNT(a) (sizeof(a) / sizeof((a)[0]))

/* strict C11 has no M_PI */
#define TWO_PI 6.28318530717958647692528676655900577

/* Grid points and modes this close (relative) are one wavenumber. */
#define SAME_Q 1e-12

static const bkf_io_column dispersion_columns[] = {
    {"q", BKF_IO_NUMBER},          {"K", BKF_IO_NUMBER},
    {"lambda", BKF_IO_NUMBER},     {"lambda_err", BKF_IO_NUMBER},
    {"m1_re", BKF_IO_NUMBER},      {"m1_im", BKF_IO_NUMBER},
    {"m2_re", BKF_IO_NUMBER},      {"m2_im", BKF_IO_NUMBER},
    {"m1_err", BKF_IO_NUMBER},     {"kind", BKF_IO_TEXT},
    {"allowed", BKF_IO_NUMBER},    {"lambda_slip", BKF_IO_NUMBER},
    {"det", BKF_IO_NUMBER},        {"det_direct", BKF_IO_NUMBER},
};

static const bkf_io_column threshold_columns[] = {
    {"gamma", BKF_IO_NUMBER},   {"c", BKF_IO_NUMBER},         {"nu_pd", BKF_IO_NUMBER},
    {"nu_pd_err", BKF_IO_NUMBER}, {"kind", BKF_IO_TEXT},      {"q_c", BKF_IO_NUMBER},
    {"K_c", BKF_IO_NUMBER},     {"m_c_re", BKF_IO_NUMBER},    {"m_c_im", BKF_IO_NUMBER},
    {"lambda_c", BKF_IO_NUMBER}, {"stable_above", BKF_IO_NUMBER}, {"longwave", BKF_IO_NUMBER},
    {"discontinuous", BKF_IO_NUMBER},
};

static const bkf_io_column diagram_columns[] = {
    {"nu_from", BKF_IO_NUMBER},  {"nu_to", BKF_IO_NUMBER},   {"stability", BKF_IO_TEXT},
    {"from_kind", BKF_IO_TEXT},  {"to_kind", BKF_IO_TEXT},   {"from_err", BKF_IO_NUMBER},
    {"to_err", BKF_IO_NUMBER},   {"from_q", BKF_IO_NUMBER},  {"to_q", BKF_IO_NUMBER},
    {"from_m", BKF_IO_NUMBER},   {"to_m", BKF_IO_NUMBER},
};

bkf_oscillation_spec bkf_oscillation_spec_default(void)
{
    bkf_oscillation_spec s;
    memset(&s, 0, sizeof s);
    s.mode = BKF_OSCILLATION_DISPERSION;
    s.gamma = s.c = s.nu = NAN;
    s.S = 0;
    s.along = BKF_FLOQUET_ALONG_C;
    s.from = s.to = NAN;
    s.search_lo = BKF_OSCILLATION_SEARCH_LO;
    s.search_hi = BKF_OSCILLATION_SEARCH_HI;
    s.options = bkf_floquet_options_default();
    return s;
}

const bkf_io_column *bkf_oscillation_columns(bkf_oscillation_mode mode, size_t *count)
{
    const bkf_io_column *c = mode == BKF_OSCILLATION_DISPERSION ? dispersion_columns
                             : mode == BKF_OSCILLATION_DIAGRAM  ? diagram_columns
                                                                : threshold_columns;
    if (count)
        *count = mode == BKF_OSCILLATION_DISPERSION ? COUNT(dispersion_columns)
                 : mode == BKF_OSCILLATION_DIAGRAM  ? COUNT(diagram_columns)
                                                    : COUNT(threshold_columns);
    return c;
}

/* ------------------------------------------------------------ validation */

static int check_gamma(const char *name, double gamma, bkf_error *err)
{
    char a[32];
    if (!(gamma >= BKF_CYCLE_MU_MIN && gamma <= BKF_CYCLE_MU_MAX))
        return bkf_error_set(err, BKF_EINPUT, "%s: gamma = %s is outside [%g, %g]", name,
                             bkf_product_number(gamma, a, sizeof a), BKF_CYCLE_MU_MIN,
                             BKF_CYCLE_MU_MAX);
    return BKF_OK;
}

static int check_c(const char *name, double c, int positive, bkf_error *err)
{
    char a[32];
    if (positive && !(c > 0))
        return bkf_error_set(err, BKF_EINPUT,
                             "%s: c = %s must be > 0 for thresholds (with c = 0 every wavenumber "
                             "is the neutral q = 0 mode)",
                             name, bkf_product_number(c, a, sizeof a));
    if (!(c >= 0 && isfinite(c)))
        return bkf_error_set(err, BKF_EINPUT, "%s: c = %s must be >= 0", name,
                             bkf_product_number(c, a, sizeof a));
    return BKF_OK;
}

int bkf_oscillation_check(const bkf_oscillation_spec *p, bkf_error *err)
{
    if (!p) return bkf_error_set(err, BKF_EINPUT, "floquet: spec is NULL");
    if ((unsigned)p->mode > BKF_OSCILLATION_DIAGRAM)
        return bkf_error_set(err, BKF_EINPUT, "floquet: mode %d is unknown", (int)p->mode);
    int curve = p->mode == BKF_OSCILLATION_CURVE;
    int scanning = p->mode != BKF_OSCILLATION_DISPERSION;
    char a[32];
    int s;
    if (curve) {
        if (p->along != BKF_FLOQUET_ALONG_C && p->along != BKF_FLOQUET_ALONG_GAMMA)
            return bkf_error_set(err, BKF_EINPUT, "along: not c or gamma");
        int along_c = p->along == BKF_FLOQUET_ALONG_C;
        if ((s = along_c ? check_c("from", p->from, 1, err) : check_gamma("from", p->from, err)))
            return s;
        if ((s = along_c ? check_c("to", p->to, 1, err) : check_gamma("to", p->to, err))) return s;
        if (p->from == p->to)
            return bkf_error_set(err, BKF_EINPUT, "from, to: the curve needs two different ends");
    }
    if (!(curve && p->along == BKF_FLOQUET_ALONG_GAMMA) && (s = check_gamma("gamma", p->gamma, err)))
        return s;
    if (!(curve && p->along == BKF_FLOQUET_ALONG_C) && (s = check_c("c", p->c, scanning, err)))
        return s;
    if ((s = bkf_model_check_tol(p->options.tol, err))) return s;
    if (!(p->options.p_max > 0 && p->options.p_max <= BKF_OSCILLATION_CQ_MAX))
        return bkf_error_set(err, BKF_EINPUT, "cq-max: %s is outside (0, 1e4]",
                             bkf_product_number(p->options.p_max, a, sizeof a));
    if (!(p->options.nu_step > 0 && p->options.nu_step <= 1))
        return bkf_error_set(err, BKF_EINPUT, "nu-step: %s is outside (0, 1]",
                             bkf_product_number(p->options.nu_step, a, sizeof a));
    if (scanning) {
        if (!(p->search_lo > -1.0 && p->search_hi < 1.0 && p->search_lo < p->search_hi))
            return bkf_error_set(err, BKF_EINPUT, "search: needs -1 < lo < hi < 1");
        return BKF_OK;
    }
    if ((s = bkf_model_check_nu_active(p->nu, err))) return s;
    if (!(p->S >= 0 && isfinite(p->S)))
        return bkf_error_set(err, BKF_EINPUT, "S: S = %s must be > 0 (or 0: no allowed modes)",
                             bkf_product_number(p->S, a, sizeof a));
    if (p->nq == 0 || !p->q) return bkf_error_set(err, BKF_EINPUT, "q: no wavenumbers");
    for (size_t i = 0; i < p->nq; i++) {
        if (!(p->q[i] >= 0 && isfinite(p->q[i])))
            return bkf_error_set(err, BKF_EINPUT, "q: q = %s must be >= 0",
                                 bkf_product_number(p->q[i], a, sizeof a));
        if (p->c * p->q[i] > BKF_OSCILLATION_CQ_MAX)
            return bkf_error_set(err, BKF_EINPUT, "q: c q = %s is above 1e4",
                                 bkf_product_number(p->c * p->q[i], a, sizeof a));
    }
    return BKF_OK;
}

/* --------------------------------------------------------- allowed modes */

int bkf_oscillation_modes(double S, double a, double b, size_t max_count, double **modes,
                          size_t *count, bkf_error *err)
{
    *modes = NULL;
    *count = 0;
    if (!(S > 0 && isfinite(S)))
        return bkf_error_set(err, BKF_EINPUT, "S: the domain size must be > 0 and finite");
    if (!(a >= 0 && b >= 0 && isfinite(a) && isfinite(b)))
        return bkf_error_set(err, BKF_EINPUT, "q: the range's ends must be >= 0 and finite");
    double lo = fmin(a, b), hi = fmax(a, b), step = TWO_PI / S;
    double jlo = ceil(lo / step - SAME_Q), jhi = floor(hi / step + SAME_Q);
    if (jhi < jlo) return BKF_OK;
    if (jhi - jlo + 1 > (double)max_count)
        return bkf_error_set(err, BKF_EINPUT, "S: %.0f allowed modes in the q range, more than %zu",
                             jhi - jlo + 1, max_count);
    size_t n = (size_t)(jhi - jlo) + 1;
    double *m = malloc(n * sizeof *m);
    if (!m) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    int up = b >= a;
    for (size_t k = 0; k < n; k++) m[k] = step * (up ? jlo + (double)k : jhi - (double)k);
    *modes = m;
    *count = n;
    return BKF_OK;
}

int bkf_oscillation_rows(const double *q, size_t nq, double S, double **rows,
                         unsigned char **allowed, size_t *count, bkf_error *err)
{
    *rows = NULL;
    *allowed = NULL;
    *count = 0;
    if (!q || nq == 0) return bkf_error_set(err, BKF_EINPUT, "q: no wavenumbers");
    double *modes = NULL;
    size_t nmodes = 0;
    int s = S > 0 ? bkf_oscillation_modes(S, q[0], q[nq - 1], BKF_OSCILLATION_MAX_ROWS, &modes,
                                          &nmodes, err)
                  : BKF_OK;
    if (s) return s;
    size_t cap = nq + nmodes;
    if (cap > BKF_OSCILLATION_MAX_ROWS) {
        free(modes);
        return bkf_error_set(err, BKF_EINPUT, "q, S: %zu rows, more than %u", cap,
                             BKF_OSCILLATION_MAX_ROWS);
    }
    double *r = malloc(cap * sizeof *r);
    unsigned char *al = malloc(cap);
    if (!r || !al) {
        free(modes);
        free(r);
        free(al);
        return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    }
    int up = q[nq - 1] >= q[0];
    double step = S > 0 ? TWO_PI / S : 0;
    size_t i = 0, k = 0, n = 0;
    while (i < nq || k < nmodes) {
        double mode = k < nmodes ? modes[k] : NAN;
        double g = i < nq ? q[i] : NAN;
        if (k < nmodes && i < nq && fabs(g - mode) <= SAME_Q * fmax(fabs(mode), step)) {
            r[n] = g; /* the grid's value, marked */
            al[n++] = 1;
            i++;
            k++;
        } else if (k < nmodes && (i == nq || (up ? mode < g : mode > g))) {
            r[n] = mode;
            al[n++] = 1;
            k++;
        } else {
            r[n] = g;
            al[n++] = 0;
            i++;
        }
    }
    free(modes);
    *rows = r;
    *allowed = al;
    *count = n;
    return BKF_OK;
}

/* ------------------------------------------------------------ dispersion */

/* The dispersion's state between the set-up and the rows, so that the
 * table writer can comment on the cycle before the first row. */
typedef struct {
    const bkf_oscillation_spec *spec;
    bkf_floquet *floquet;
    double *q;
    unsigned char *allowed;
    size_t count;
    const bkf_cycle_result *cycle;
    bkf_error row_err;
} dispersion;

static void dispersion_free(dispersion *d)
{
    bkf_floquet_free(d->floquet);
    free(d->q);
    free(d->allowed);
}

static int dispersion_begin(const bkf_oscillation_spec *p, dispersion *d, bkf_error *err)
{
    memset(d, 0, sizeof *d);
    d->spec = p;
    int s = bkf_oscillation_check(p, err);
    if (s) return s;
    if ((s = bkf_oscillation_rows(p->q, p->nq, p->S, &d->q, &d->allowed, &d->count, err)))
        return s;
    d->floquet = bkf_floquet_alloc();
    if (!d->floquet) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    bkf_error e;
    s = bkf_floquet_set(d->floquet, p->gamma, p->c, p->nu, &p->options, &e);
    if (s) {
        char a[32], b[32];
        return bkf_error_set(err, s, "global oscillation at gamma = %s, nu = %s: %s",
                             bkf_product_number(p->gamma, a, sizeof a),
                             bkf_product_number(p->nu, b, sizeof b), e.message);
    }
    d->cycle = bkf_floquet_cycle(d->floquet);
    return BKF_OK;
}

/* Row i.  A q whose estimate stays above tol is a flagged row: no digits
 * (NaN), the estimate that was reached, and the reason; the other rows
 * stand.  Any other failure ends the table. */
static int dispersion_row(dispersion *d, size_t i, bkf_oscillation_row *row, bkf_error *err)
{
    const bkf_oscillation_spec *p = d->spec;
    memset(row, 0, sizeof *row);
    row->message = "";
    int s = bkf_floquet_eval(d->floquet, d->q[i], &row->point, &d->row_err);
    bkf_floquet_point *pt = &row->point;
    if (s == BKF_ENUMERIC && pt->lambda_err > p->options.tol) {
        row->refused = 1;
        row->message = d->row_err.message;
        pt->lambda = pt->m1_re = pt->m1_im = pt->m2_re = pt->m2_im = pt->m1_err = NAN;
    } else if (s) {
        char a[32];
        return bkf_error_set(err, s, "at q = %s: %s", bkf_product_number(d->q[i], a, sizeof a),
                             d->row_err.message);
    }
    row->allowed = p->S > 0 ? d->allowed[i] : -1;
    row->lambda_slip = d->cycle->period * bkf_floquet_slip_rate(p->gamma, p->c, p->nu, pt->q);
    return BKF_OK;
}

int bkf_oscillation_dispersion(const bkf_oscillation_spec *spec, bkf_oscillation_visit visit,
                               void *data, bkf_cycle_result *cycle, bkf_error *err)
{
    dispersion d;
    int s = dispersion_begin(spec, &d, err);
    if (!s && cycle) *cycle = *d.cycle;
    for (size_t i = 0; !s && i < d.count; i++) {
        bkf_oscillation_row row;
        s = dispersion_row(&d, i, &row, err);
        if (!s && visit && visit(&row, data)) break;
    }
    dispersion_free(&d);
    return s;
}

static int write_dispersion(const bkf_oscillation_spec *p, const bkf_product_output *out,
                            bkf_io_table *t, bkf_error *err)
{
    dispersion d;
    int s = dispersion_begin(p, &d, err);
    char a[32], b[32], c[32], e[32], line[512];
    if (!s) {
        snprintf(line, sizeof line, "gamma %s, c %s, nu %s, tol %s",
                 bkf_product_number(p->gamma, a, sizeof a), bkf_product_number(p->c, b, sizeof b),
                 bkf_product_number(p->nu, c, sizeof c),
                 bkf_product_number(p->options.tol, e, sizeof e));
        s = bkf_io_table_comment(t, line, err);
    }
    if (!s) {
        snprintf(line, sizeof line,
                 "cycle: T = %.17g (err %.3g), ln(m1 m2) = %.17g; stepper %s; %zu rows%s%s",
                 d.cycle->period, d.cycle->period_err, d.cycle->log_multiplier, d.cycle->stepper,
                 d.count, p->S > 0 ? ", allowed modes q = 2 pi j/S with S = " : "",
                 p->S > 0 ? bkf_product_number(p->S, b, sizeof b) : "");
        s = bkf_io_table_comment(t, line, err);
    }
    if (!s) s = bkf_product_table_command(t, out, err);
    for (size_t i = 0; i < d.count && !s; i++) {
        bkf_oscillation_row row;
        if ((s = dispersion_row(&d, i, &row, err))) break;
        const bkf_floquet_point *pt = &row.point;
        if (row.refused && out->warn) {
            snprintf(line, sizeof line, "row q = %s refused: %s",
                     bkf_product_number(d.q[i], a, sizeof a), row.message);
            out->warn(line, out->warn_data);
        }
        bkf_io_value v[COUNT(dispersion_columns)] = {
            {.number = pt->q},
            {.number = pt->k2},
            {.number = pt->lambda},
            {.number = pt->lambda_err},
            {.number = pt->m1_re},
            {.number = pt->m1_im},
            {.number = pt->m2_re},
            {.number = pt->m2_im},
            {.number = pt->m1_err},
            {.text = row.refused ? "refused" : bkf_floquet_kind_name(pt->kind)},
            {.number = row.allowed >= 0 ? (double)row.allowed : NAN},
            {.number = row.lambda_slip},
            {.number = exp(pt->log_det)},
            {.number = pt->det_direct},
        };
        s = bkf_io_table_row(t, v, err);
    }
    dispersion_free(&d);
    return s;
}

/* ------------------------------------------------------- threshold, diagram */

typedef struct {
    bkf_io_table *table;
    int status;
    bkf_error err;
} sink;

static int threshold_row(const bkf_floquet_threshold *th, void *data)
{
    sink *k = data;
    bkf_io_value v[COUNT(threshold_columns)] = {
        {.number = th->gamma},
        {.number = th->c},
        {.number = th->nu},
        {.number = th->nu_err},
        {.text = bkf_floquet_boundary_name(th->kind)},
        {.number = th->q},
        {.number = th->k2},
        {.number = th->m_re},
        {.number = th->m_im},
        {.number = th->lambda},
        {.number = th->stable_above},
        {.number = th->longwave},
        {.number = th->discontinuous},
    };
    int s = bkf_io_table_row(k->table, v, &k->err);
    if (s && !k->status) k->status = s;
    return s != BKF_OK;
}

static int diagram_row(const bkf_floquet_interval *iv, void *data)
{
    sink *k = data;
    bkf_io_value v[COUNT(diagram_columns)] = {
        {.number = iv->nu_from},
        {.number = iv->nu_to},
        {.text = iv->stable ? "stable" : "unstable"},
        {.text = bkf_floquet_boundary_name(iv->from.kind)},
        {.text = bkf_floquet_boundary_name(iv->to.kind)},
        {.number = iv->from.nu_err},
        {.number = iv->to.nu_err},
        {.number = iv->from.q},
        {.number = iv->to.q},
        {.number = iv->from.m_re},
        {.number = iv->to.m_re},
    };
    int s = bkf_io_table_row(k->table, v, &k->err);
    if (s && !k->status) k->status = s;
    return s != BKF_OK;
}

static int comment_scan(bkf_io_table *t, const bkf_oscillation_spec *p,
                        const bkf_product_output *out, bkf_error *err)
{
    char a[32], b[32], c[32], d[32], e[32], line[512];
    snprintf(line, sizeof line,
             "scan: nu in [%s, %s] upward in steps %s, c q in (0, %s] on %zu points; tol %s",
             bkf_product_number(p->search_lo, a, sizeof a),
             bkf_product_number(p->search_hi, b, sizeof b),
             bkf_product_number(p->options.nu_step, c, sizeof c),
             bkf_product_number(p->options.p_max, d, sizeof d), p->options.scan_points,
             bkf_product_number(p->options.tol, e, sizeof e));
    int s = bkf_io_table_comment(t, line, err);
    if (!s)
        s = bkf_io_table_comment(
            t,
            "kinds: period_doubling (finite-q peak of lambda through 0 with m1 = -1), long_wave "
            "(a in lambda ~ a c^2 q^2 through 0), other (finite-q peak with m1 = +1, or a jump of "
            "the cycle), scan_end",
            err);
    if (!s) s = bkf_product_table_command(t, out, err);
    return s;
}

static int write_scan(const bkf_oscillation_spec *p, const bkf_product_output *out,
                      bkf_io_table *t, bkf_error *err)
{
    int s = bkf_oscillation_check(p, err);
    if (!s) s = comment_scan(t, p, out, err);
    if (s) return s;
    char a[32], b[32];
    sink k = {t, 0, {{0}}};
    bkf_error e = {{0}};
    if (p->mode == BKF_OSCILLATION_THRESHOLD) {
        bkf_floquet_threshold th;
        s = bkf_floquet_threshold_find(p->gamma, p->c, p->search_lo, p->search_hi, &p->options,
                                       &th, &e);
        if (s)
            return bkf_error_set(err, s, "threshold at gamma = %s, c = %s: %s",
                                 bkf_product_number(p->gamma, a, sizeof a),
                                 bkf_product_number(p->c, b, sizeof b), e.message);
        threshold_row(&th, &k);
    } else if (p->mode == BKF_OSCILLATION_CURVE) {
        s = bkf_floquet_threshold_branch(p->along, p->from, p->to, p->gamma, p->c, p->search_lo,
                                         p->search_hi, &p->options, 0, threshold_row, &k, &e);
        if (!k.status && s)
            return bkf_error_set(err, s, "threshold curve along %s from %s to %s: %s",
                                 p->along == BKF_FLOQUET_ALONG_C ? "c" : "gamma",
                                 bkf_product_number(p->from, a, sizeof a),
                                 bkf_product_number(p->to, b, sizeof b), e.message);
    } else {
        s = bkf_floquet_diagram(p->gamma, p->c, p->search_lo, p->search_hi, &p->options,
                                diagram_row, &k, &e);
        if (!k.status && s)
            return bkf_error_set(err, s, "diagram at gamma = %s, c = %s: %s",
                                 bkf_product_number(p->gamma, a, sizeof a),
                                 bkf_product_number(p->c, b, sizeof b), e.message);
    }
    if (k.status) {
        if (err) *err = k.err;
        return k.status;
    }
    return BKF_OK;
}

/* ------------------------------------------------------------------ write */

static const char *title(bkf_oscillation_mode mode)
{
    switch (mode) {
    case BKF_OSCILLATION_DISPERSION:
        return "floquet: dispersion relation of the global oscillation\n"
               "lambda = ln|m1| per period T; lambda_slip = T x growth rate of continuous slip; "
               "det = exp(integral of the trace) (Liouville), det_direct = det of the "
               "integrated matrix";
    case BKF_OSCILLATION_DIAGRAM:
        return "floquet --diagram: stability intervals of the global oscillation over nu "
               "(windows narrower than the nu step may be missed)";
    default:
        return "floquet --threshold: lowest stability boundary of the global oscillation in "
               "the scanned nu range";
    }
}

int bkf_oscillation_write(const bkf_oscillation_spec *spec, const bkf_product_output *out,
                          bkf_error *err)
{
    int s = bkf_oscillation_check(spec, err);
    if (s) return s;
    size_t ncols;
    const bkf_io_column *cols = bkf_oscillation_columns(spec->mode, &ncols);
    bkf_io_table *t;
    if ((s = bkf_product_table_open(out, cols, ncols, title(spec->mode), &t, err))) return s;
    s = spec->mode == BKF_OSCILLATION_DISPERSION ? write_dispersion(spec, out, t, err)
                                                 : write_scan(spec, out, t, err);
    if (!s) s = bkf_io_table_finish(t, err);
    bkf_io_table_free(t);
    return s;
}

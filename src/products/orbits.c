/* `bkfront orbit` (orbits.h): the branch of period-doubled orbits as a
 * table, and the files of one orbit (its spacetime over two periods, its
 * multipliers). */
#include "orbits_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <gsl/gsl_math.h>

#include "bkfront/floquet.h"
#include "bkfront/pde.h"

#include "product_internal.h"

static const bkf_io_column columns[] = {
    {"index", BKF_IO_NUMBER},    {"kind", BKF_IO_TEXT},       {"nu", BKF_IO_NUMBER},
    {"gamma", BKF_IO_NUMBER},    {"c", BKF_IO_NUMBER},        {"S", BKF_IO_NUMBER},
    {"period", BKF_IO_NUMBER},   {"period_err", BKF_IO_NUMBER}, {"amplitude", BKF_IO_NUMBER},
    {"mode_amp", BKF_IO_NUMBER}, {"shift", BKF_IO_NUMBER},    {"verdict", BKF_IO_TEXT},
    {"m_abs", BKF_IO_NUMBER},    {"m_re", BKF_IO_NUMBER},     {"m_im", BKF_IO_NUMBER},
    {"m_err", BKF_IO_NUMBER},    {"out_real_plus", BKF_IO_NUMBER},
    {"out_real_minus", BKF_IO_NUMBER}, {"out_complex", BKF_IO_NUMBER},
    {"events", BKF_IO_TEXT},     {"status", BKF_IO_TEXT}};
#define NCOLUMNS (sizeof columns / sizeof columns[0])

static const bkf_io_column mult_columns[] = {
    {"sector", BKF_IO_NUMBER}, {"re", BKF_IO_NUMBER},   {"im", BKF_IO_NUMBER},
    {"abs", BKF_IO_NUMBER},    {"err", BKF_IO_NUMBER},  {"kind", BKF_IO_TEXT},
    {"tail", BKF_IO_NUMBER},   {"alignment", BKF_IO_NUMBER}};
#define NMULT (sizeof mult_columns / sizeof mult_columns[0])

static const char *const model_names[] = {"continuum", "chain", NULL};
static const char *const along_names[] = {"nu", "gamma", "c", "S", NULL};

#define FIELD(f) offsetof(bkf_orbits_spec, f)
#define BOUNDED (BKF_OPT_MIN | BKF_OPT_MAX)

const bkf_option bkf_orbits_spec_options[] = {
    {.name = "gamma", .type = BKF_OPT_DOUBLE, .offset = FIELD(gamma), .flags = BOUNDED,
     .min = 0.01, .max = 100, .form = "G", .shown_default = BKF_TEXT_OF(BKF_PAPER_GAMMA),
     .help = "friction strength, in [0.01, 100]"},
    {.name = "c", .type = BKF_OPT_DOUBLE, .offset = FIELD(c),
     .flags = BOUNDED | BKF_OPT_MIN_OPEN, .min = 0, .max = 100, .form = "C",
     .shown_default = BKF_TEXT_OF(BKF_PAPER_C), .help = "sound speed, in (0, 100]"},
    {.name = "nu", .type = BKF_OPT_DOUBLE, .offset = FIELD(nu),
     .flags = BOUNDED | BKF_OPT_MIN_OPEN | BKF_OPT_MAX_OPEN, .min = -1, .max = 1, .form = "V",
     .shown_default = "the branch's", .help = "pulling rate, in (-1, 1); not with --along nu"},
    {.name = "S", .type = BKF_OPT_DOUBLE, .offset = FIELD(S),
     .flags = BOUNDED | BKF_OPT_MIN_OPEN, .min = 0, .max = 1e4, .form = "L",
     .shown_default = BKF_TEXT_OF(BKF_PAPER_S), .help = "system size (the ring), in (0, 1e4]"},
    {.name = "model", .type = BKF_OPT_CHOICE, .offset = FIELD(model), .choices = model_names,
     .form = "M", .shown_default = "continuum",
     .help = "continuum (pseudo-spectral) or chain (blocks, h = S/N)"},
    {.name = "N", .type = BKF_OPT_COUNT, .offset = FIELD(N), .flags = BOUNDED, .min = 8,
     .max = 65536, .form = "N", .shown_default = "32 j (continuum), S (chain)",
     .help = "grid points or blocks on the ring, in [8, 65536]; the\n"
             "continuum's a multiple of 2 j"},
    {.name = "j", .type = BKF_OPT_COUNT, .offset = FIELD(j), .flags = BOUNDED, .min = 1,
     .max = 10000, .form = "J", .shown_default = "the mode nearest q_c",
     .help = "the mode q_j = 2 pi j/S whose period doubling starts the\n"
             "branch"},
    {.name = "along", .type = BKF_OPT_CHOICE, .offset = FIELD(along), .choices = along_names,
     .form = "nu|gamma|c|S", .shown_default = "nu", .help = "the parameter of the branch"},
    {.name = "from", .type = BKF_OPT_DOUBLE, .offset = FIELD(from), .form = "A",
     .shown_default = "-0.90 along nu",
     .help = "where the scan for the period doubling starts (the\n"
             "oscillation's mode j stable there); required but along nu"},
    {.name = "to", .type = BKF_OPT_DOUBLE, .offset = FIELD(to), .form = "B",
     .shown_default = "-0.999 along nu",
     .help = "where the scan ends; the branch stays between --from and --to"},
    {.name = "max-points", .type = BKF_OPT_COUNT, .offset = FIELD(max_points), .flags = BOUNDED,
     .min = 4, .max = BKF_ORBITS_POINTS_MAX, .form = "M", .shown_default = "50",
     .help = "points of the branch (folds not counted), in [4, 100000]"},
    {.name = "tol", .type = BKF_OPT_DOUBLE, .offset = FIELD(tol), .flags = BOUNDED,
     .min = BKF_ORBIT_TOL_MIN, .max = BKF_ORBIT_TOL_MAX, .form = "E", .shown_default = "1e-3",
     .help = "absolute accuracy asked of each orbit's period, shift and\n"
             "state, in [1e-12, 0.01]; a point that misses it is refused"},
    {.name = "step", .type = BKF_OPT_DOUBLE, .offset = FIELD(step),
     .flags = BOUNDED | BKF_OPT_MIN_OPEN, .min = 0, .max = 10, .form = "H",
     .shown_default = "0.5",
     .help = "largest continuation step (scaled: nu by 0.01, the others\n"
             "by 1% of their value), in (0, 10]"},
    {.name = "no-stability", .type = BKF_OPT_SWITCH, .offset = FIELD(no_stability),
     .help = "skip the multipliers (verdict none)"},
    {.name = "k", .type = BKF_OPT_COUNT, .offset = FIELD(k), .flags = BOUNDED, .min = 1,
     .max = 100, .form = "K", .shown_default = "2",
     .help = "multipliers per Bloch sector, in [1, 100] (the largest of\n"
             "each decide; each costs two flows a sector: the basis is 2k + 6)"},
    {.name = "switch-amplitude", .type = BKF_OPT_DOUBLE, .offset = FIELD(switch_amplitude),
     .flags = BOUNDED | BKF_OPT_MIN_OPEN, .min = 0, .max = 0.5, .form = "A",
     .shown_default = "0.02",
     .help = "amplitude of cos(q_j x) in psi at the first orbit, in\n(0, 0.5]"},
    {.name = "at", .type = BKF_OPT_DOUBLE, .offset = FIELD(at), .form = "P",
     .shown_default = "the last orbit",
     .help = "the orbit of --spacetime and --multipliers: the row whose\n"
             "parameter is nearest P"},
    {.name = "spacetime", .type = BKF_OPT_TEXT, .offset = FIELD(spacetime),
     .flags = BKF_OPT_PATH, .form = "FILE",
     .help = "psi(x, t) of that orbit over two periods (gnuplot\n"
             "nonuniform matrix, as bkfront simulate's)"},
    {.name = "multipliers", .type = BKF_OPT_TEXT, .offset = FIELD(multipliers),
     .flags = BKF_OPT_PATH, .form = "FILE", .help = "its Floquet multipliers (TSV)"},
    {.name = "regimes", .type = BKF_OPT_TEXT, .offset = FIELD(regimes), .form = "FILE",
     .help = "a table of bkfront sweep (product regime): its rows at\n"
             "this gamma, c, S set beside the solutions known there"},
    {.name = "coexistence", .type = BKF_OPT_TEXT, .offset = FIELD(coexistence),
     .flags = BKF_OPT_PATH, .form = "FILE",
     .help = "with --regimes: per row, the oscillation's and the\n"
             "branch's stable states at its nu, and whether the regime\n"
             "simulated is one of them (TSV)"},
};
const size_t bkf_orbits_spec_noptions =
    sizeof bkf_orbits_spec_options / sizeof bkf_orbits_spec_options[0];

bkf_orbits_spec bkf_orbits_spec_default(void)
{
    bkf_orbits_spec s;
    memset(&s, 0, sizeof s);
    s.gamma = s.c = s.nu = s.S = NAN;
    s.from = s.to = s.at = NAN;
    s.along = BKF_ORBITS_NU;
    s.max_points = 50;
    s.tol = 1e-3;
    s.step = 0.5;
    s.k = 2;
    s.switch_amplitude = 0.02;
    return s;
}

int bkf_orbits_check(const bkf_orbits_spec *sp, const char *prefix, bkf_error *err)
{
    const char *p = prefix ? prefix : "";
    if (!sp) return bkf_error_set(err, BKF_EINPUT, "orbit: spec is NULL");
    const char *along = along_names[sp->along >= 0 && sp->along < 4 ? sp->along : 0];
    double given = sp->along == BKF_ORBITS_GAMMA ? sp->gamma
                   : sp->along == BKF_ORBITS_C   ? sp->c
                   : sp->along == BKF_ORBITS_S   ? sp->S
                                                 : sp->nu;
    if (!isnan(given))
        return bkf_error_set(err, BKF_EINPUT,
                             "%s%s: not with %salong %s (the branch varies it from %sfrom)", p,
                             along, p, along, p);
    if (sp->along != BKF_ORBITS_NU && isnan(sp->nu))
        return bkf_error_set(err, BKF_EINPUT, "%snu is required with %salong %s (in (-1, 1))",
                             p, p, along);
    if (sp->along != BKF_ORBITS_NU && (isnan(sp->from) || isnan(sp->to)))
        return bkf_error_set(err, BKF_EINPUT, "%sfrom and %sto are required with %salong %s",
                             p, p, p, along);
    bkf_orbits_options o = bkf_orbits_options_of(sp);
    double lo = fmin(o.from, o.to), hi = fmax(o.from, o.to);
    if (!(o.from != o.to))
        return bkf_error_set(err, BKF_EINPUT, "%sfrom, %sto: must differ", p, p);
    if (sp->along == BKF_ORBITS_NU && !(lo > -1 && hi < 1))
        return bkf_error_set(err, BKF_EINPUT, "%sfrom, %sto: nu must stay in (-1, 1)", p, p);
    if (sp->along == BKF_ORBITS_GAMMA && !(lo >= 0.01 && hi <= 100))
        return bkf_error_set(err, BKF_EINPUT, "%sfrom, %sto: gamma must stay in [0.01, 100]",
                             p, p);
    if (sp->along == BKF_ORBITS_C && !(lo > 0 && hi <= 100))
        return bkf_error_set(err, BKF_EINPUT, "%sfrom, %sto: c must stay in (0, 100]", p, p);
    if (sp->along == BKF_ORBITS_S && !(lo > 0 && hi <= 1e4))
        return bkf_error_set(err, BKF_EINPUT, "%sfrom, %sto: S must stay in (0, 1e4]", p, p);
    if (sp->model == 0 && sp->N % 2)
        return bkf_error_set(err, BKF_EINPUT, "%sN: the continuum's N must be even", p);
    if (!sp->regimes != !sp->coexistence)
        return bkf_error_set(err, BKF_EINPUT, "%s%s: give %sregimes and %scoexistence together",
                             p, sp->regimes ? "regimes" : "coexistence", p, p);
    if (sp->no_stability && sp->coexistence)
        return bkf_error_set(err, BKF_EINPUT, "%scoexistence: not with %sno-stability", p, p);
    if (sp->along != BKF_ORBITS_NU && sp->coexistence)
        return bkf_error_set(err, BKF_EINPUT, "%scoexistence: only along nu", p);
    return BKF_OK;
}

bkf_orbits_options bkf_orbits_options_of(const bkf_orbits_spec *sp)
{
    bkf_orbits_options o = bkf_orbits_options_default();
    double gamma = sp->gamma, c = sp->c, nu = sp->nu, S = sp->S;
    bkf_model_paper_where_unset(&gamma, &c, &nu, &S);
    o.model.gamma = gamma;
    o.model.c = c;
    o.model.nu = nu;
    o.model.S = S;
    o.model.N = sp->N;
    o.model.kind = sp->model ? BKF_MODEL_CHAIN : BKF_MODEL_CONTINUUM;
    o.j = sp->j;
    o.along = (bkf_orbits_param)sp->along;
    if (sp->along == BKF_ORBITS_NU) {
        o.from = isnan(sp->from) ? BKF_ORBITS_NU_FROM : sp->from;
        o.to = isnan(sp->to) ? BKF_ORBITS_NU_TO : sp->to;
    } else {
        o.from = sp->from;
        o.to = sp->to;
    }
    o.max_points = sp->max_points;
    o.tol = sp->tol;
    o.step = sp->step;
    o.stability = !sp->no_stability;
    o.k = sp->k;
    o.switch_amplitude = sp->switch_amplitude;
    o.progress = sp->progress;
    o.progress_data = sp->progress_data;
    o.cancel = sp->cancel;
    return o;
}

/* ------------------------------------------------- regimes and solutions */

#define REGIME_ROWS_MAX 1000000u
#define REGIME_LINE_MAX 65536

typedef struct {
    double point, nu;
    char regime[40];
    int match;                /* at the branch's gamma, c, S */
    int osc;                  /* the oscillation: 1 stable, 0 unstable, -1 undecided */
    size_t orbits, stable, undecided;
} regime_row;

typedef struct {
    regime_row *rows;
    size_t count;
} regime_set;

/* The field `col` of a tab-separated line (0-based), in place: NUL-ended
 * copy into buf. */
static int field_of(const char *line, int col, char *buf, size_t size)
{
    for (int i = 0; i < col; i++) {
        line = strchr(line, '\t');
        if (!line) return 0;
        line++;
    }
    size_t n = strcspn(line, "\t\r\n");
    if (n >= size) return 0;
    memcpy(buf, line, n);
    buf[n] = '\0';
    return 1;
}

static int read_regimes(const char *path, const bkf_model_params *m, regime_set *set,
                        bkf_error *err)
{
    char shown[96];
    FILE *f = fopen(path, "r");
    if (!f)
        return bkf_error_set(err, BKF_EINPUT, "regimes: cannot open %s",
                             bkf_io_shown(path, shown, sizeof shown));
    static const char *const names[] = {"point", "gamma", "c", "nu", "S", "regime"};
    int col[6] = {-1, -1, -1, -1, -1, -1};
    char *line = malloc(REGIME_LINE_MAX);
    int s = line ? BKF_OK : bkf_error_set(err, BKF_ENOMEM, "out of memory");
    int header = 0;
    size_t lineno = 0, cap = 0;
    while (!s && fgets(line, REGIME_LINE_MAX, f)) {
        lineno++;
        if (!strchr(line, '\n') && !feof(f)) {
            s = bkf_error_set(err, BKF_EINPUT, "regimes: line %zu is too long", lineno);
            break;
        }
        if (line[0] == '#' || line[0] == '\n') continue;
        if (!header) {
            char name[64];
            for (int c = 0; field_of(line, c, name, sizeof name); c++)
                for (int k = 0; k < 6; k++)
                    if (strcmp(name, names[k]) == 0) col[k] = c;
            for (int k = 0; k < 6 && !s; k++)
                if (col[k] < 0)
                    s = bkf_error_set(err, BKF_EINPUT,
                                      "regimes: %s has no column %s (a table of bkfront sweep "
                                      "--product regime)",
                                      bkf_io_shown(path, shown, sizeof shown), names[k]);
            header = 1;
            continue;
        }
        if (set->count == REGIME_ROWS_MAX) {
            s = bkf_error_set(err, BKF_EINPUT, "regimes: more than %u rows", REGIME_ROWS_MAX);
            break;
        }
        if (set->count == cap) {
            size_t nc = cap ? 2 * cap : 64;
            regime_row *r = realloc(set->rows, nc * sizeof *r);
            if (!r) {
                s = bkf_error_set(err, BKF_ENOMEM, "out of memory");
                break;
            }
            set->rows = r;
            cap = nc;
        }
        regime_row *r = &set->rows[set->count];
        memset(r, 0, sizeof *r);
        double v[5];
        char buf[64];
        for (int k = 0; k < 5 && !s; k++) {
            char *end;
            if (!field_of(line, col[k], buf, sizeof buf) || (v[k] = strtod(buf, &end), *end))
                s = bkf_error_set(err, BKF_EINPUT, "regimes: line %zu: %s is not a number",
                                  lineno, names[k]);
        }
        if (!s && !field_of(line, col[5], r->regime, sizeof r->regime))
            s = bkf_error_set(err, BKF_EINPUT, "regimes: line %zu: no regime", lineno);
        if (s) break;
        r->point = v[0];
        r->nu = v[3];
        r->osc = -1;
        /* the same model: the table's numbers are %.17g of the same doubles */
        r->match = fabs(v[1] - m->gamma) <= 1e-12 * m->gamma && fabs(v[2] - m->c) <= 1e-12 * m->c &&
                   fabs(v[4] - m->S) <= 1e-12 * m->S;
        set->count++;
    }
    if (!s && ferror(f)) s = bkf_error_set(err, BKF_EIO, "regimes: reading failed");
    if (!s && !header)
        s = bkf_error_set(err, BKF_EINPUT, "regimes: %s has no table",
                          bkf_io_shown(path, shown, sizeof shown));
    free(line);
    fclose(f);
    return s;
}

/* The global oscillation on the ring at nu: every allowed mode j >= 1 with
 * c q_j <= 6 (floquet's scan range), stable when each lambda is below 0 by
 * more than its error. */
static int oscillation_on_ring(const bkf_model_params *m, double nu, size_t N, double tol,
                               int *verdict, bkf_error *err)
{
    bkf_floquet *fl = bkf_floquet_alloc();
    if (!fl) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    bkf_floquet_options fo = bkf_floquet_options_default();
    fo.tol = fmax(tol * 1e-2, 1e-12);
    int s = bkf_floquet_set(fl, m->gamma, m->c, nu, &fo, err);
    int stable = 1, unstable = 0;
    for (size_t j = 1; !s && m->c * 2.0 * M_PI * (double)j / m->S <= 6.0; j++) {
        if (m->kind == BKF_MODEL_CHAIN && 2 * j > N) break;
        bkf_floquet_point pt;
        s = bkf_floquet_eval(fl, orbits_q_effective(m, j, N), &pt, err);
        if (s) break;
        if (pt.lambda > pt.lambda_err) unstable = 1;
        if (!(pt.lambda < -pt.lambda_err)) stable = 0;
    }
    bkf_floquet_free(fl);
    *verdict = unstable ? 0 : stable ? 1 : -1;
    return s;
}

/* ------------------------------------------------------------ the table */

/* The orbit the files show: copied from its row (the branch keeps none). */
typedef struct {
    int have;
    double dist;
    bkf_model_params model;
    double period, shift;
    double *psi, *eta;
    bkf_orbit_multiplier *m;
    size_t count, cap;
    bkf_orbit_verdict verdict;
    int has_spectrum;
} kept_orbit;

typedef struct {
    const bkf_orbits_spec *spec;
    const bkf_orbits_options *o;
    bkf_io_table *t;
    const bkf_provenance *prov;
    int status;
    bkf_error err;
    kept_orbit keep;
    regime_set regimes;
    int have_prev;            /* the previous row, for the branch's segments */
    double prev_nu;
    int prev_verdict;         /* bkf_orbit_verdict, or -1: the bifurcation (neutral) */
    double nu_lo, nu_hi;      /* the nu the branch covered */
} writer;

/* The segment from the previous row to this one: every regime row's nu on
 * it has one more orbit, stable when both ends are (the bifurcation's end
 * counts as the other's). */
static void count_segment(writer *w, const bkf_orbits_point *pt)
{
    double nu = pt->model.nu;
    int v = pt->has_spectrum ? (int)pt->verdict : (int)BKF_ORBIT_UNDECIDED;
    if (pt->is_start) v = -1;
    if (!w->have_prev) {
        w->nu_lo = w->nu_hi = nu;
    } else if (!isnan(pt->period)) {
        w->nu_lo = fmin(w->nu_lo, nu);
        w->nu_hi = fmax(w->nu_hi, nu);
        int a = w->prev_verdict < 0 ? v : w->prev_verdict, b = v;
        double lo = fmin(w->prev_nu, nu), hi = fmax(w->prev_nu, nu);
        for (size_t i = 0; i < w->regimes.count; i++) {
            regime_row *r = &w->regimes.rows[i];
            /* half-open, so that a row on a shared end counts once */
            int on = w->prev_nu < nu ? (r->nu > lo && r->nu <= hi) : (r->nu >= lo && r->nu < hi);
            if (!r->match || !on) continue;
            r->orbits++;
            if (a == BKF_ORBIT_STABLE && b == BKF_ORBIT_STABLE) r->stable++;
            else if (!(a == BKF_ORBIT_UNSTABLE && b == BKF_ORBIT_UNSTABLE)) r->undecided++;
        }
    }
    if (!isnan(pt->period)) {
        w->have_prev = 1;
        w->prev_nu = nu;
        w->prev_verdict = v;
    }
}

static int head(writer *w, const bkf_orbits_point *pt)
{
    const bkf_orbits_report *r = pt->report;
    const bkf_orbits_pd *pd = &r->pd;
    const char *along = bkf_orbits_param_name(w->o->along);
    char g[32], c[32], nu[32], S[32], from[32], to[32], tol[32];
    bkf_error *e = &w->err;
    int s = bkf_io_table_commentf(
        w->t, e, "model %s, gamma %s, c %s, nu %s, S %s; along %s from %s to %s; tol %s",
        w->o->model.kind == BKF_MODEL_CHAIN ? "chain" : "continuum",
        bkf_format_number(w->o->model.gamma, g, sizeof g),
        bkf_format_number(w->o->model.c, c, sizeof c),
        w->o->along == BKF_ORBITS_NU ? "varies" : bkf_format_number(w->o->model.nu, nu, sizeof nu),
        bkf_format_number(w->o->model.S, S, sizeof S), along,
        bkf_format_number(w->o->from, from, sizeof from),
        bkf_format_number(w->o->to, to, sizeof to), bkf_format_number(w->o->tol, tol, sizeof tol));
    if (!s)
        s = bkf_io_table_commentf(
            w->t, e,
            "period doubling of the global oscillation (floquet): mode j = %zu, q_j = %.10g, at "
            "%s = %.12g (err %.2g), T = %.12g, multiplier %.10g; the branch starts there with "
            "period ~ 2T",
            pd->j, pd->q, along, pd->p, pd->p_err, pd->period, pd->m_re);
    if (!s)
        s = bkf_io_table_commentf(
            w->t, e,
            "grid: N %zu, solved on one of %zu identical cells (%zu points) by Newton-Krylov "
            "shooting (bkf_orbit_solve%s); multipliers by Arnoldi per Bloch sector; the "
            "continuation on the cell's even (cosine) state",
            r->N, r->cells, r->cell_points,
            w->o->model.kind == BKF_MODEL_CHAIN ? "" : ", shift free");
    if (!s)
        s = bkf_io_table_comment(
            w->t,
            "columns: kind bifurcation (the oscillation where its multiplier is -1: the "
            "branch's root), orbit, fold (located in the parameter); amplitude = max over a "
            "period of max_x psi - min_x psi; mode_amp = the continuation's amplitude of "
            "cos(q_j x) in psi at t = 0; verdict of the multipliers (none: not computed); "
            "m_* the largest physical multiplier; out_* physical multipliers outside the unit "
            "circle (real > 0, real < 0, complex with im > 0); events since the previous row: "
            "fold, period_doubling, torus, real, stability_change; status ok or why the "
            "numbers are nan",
            e);
    bkf_io_value v;
    if (!s) {
        v.number = pd->p;
        v.text = NULL;
        s = bkf_io_table_result(w->t, "p_pd", BKF_IO_NUMBER, v, e);
    }
    if (!s) {
        v.number = pd->p_err;
        s = bkf_io_table_result(w->t, "p_pd_err", BKF_IO_NUMBER, v, e);
    }
    if (!s) {
        v.number = (double)pd->j;
        s = bkf_io_table_result(w->t, "j", BKF_IO_NUMBER, v, e);
    }
    if (!s) {
        v.number = pd->period;
        s = bkf_io_table_result(w->t, "T_pd", BKF_IO_NUMBER, v, e);
    }
    if (!s) s = bkf_product_table_command(w->t, w->prov, e);
    return s;
}

static int keep_orbit(writer *w, const bkf_orbits_point *pt)
{
    kept_orbit *k = &w->keep;
    if (!pt->psi || !(pt->period > 0)) return BKF_OK;
    double d = isnan(w->spec->at) ? 0 : fabs(pt->p - w->spec->at);
    if (k->have && d > k->dist) return BKF_OK;
    size_t N = pt->model.N;
    if (!k->psi) {
        k->psi = malloc(N * sizeof *k->psi);
        k->eta = malloc(N * sizeof *k->eta);
        if (!k->psi || !k->eta) return bkf_error_set(&w->err, BKF_ENOMEM, "out of memory");
    }
    k->have = 1;
    k->dist = d;
    k->model = pt->model;
    k->period = pt->period;
    k->shift = pt->shift;
    memcpy(k->psi, pt->psi, N * sizeof *k->psi);
    memcpy(k->eta, pt->eta, N * sizeof *k->eta);
    k->has_spectrum = pt->has_spectrum;
    k->verdict = pt->verdict;
    k->count = 0;
    if (pt->spectrum) {
        if (pt->spectrum->count > k->cap) {
            void *m = realloc(k->m, pt->spectrum->count * sizeof *k->m);
            if (!m) return bkf_error_set(&w->err, BKF_ENOMEM, "out of memory");
            k->m = m;
            k->cap = pt->spectrum->count;
        }
        memcpy(k->m, pt->spectrum->m, pt->spectrum->count * sizeof *k->m);
        k->count = pt->spectrum->count;
    }
    return BKF_OK;
}

static int visit_row(const bkf_orbits_point *pt, void *data)
{
    writer *w = data;
    int s = BKF_OK;
    if (pt->is_start) s = head(w, pt);
    char ev[96];
    const char *kind = pt->is_start ? "bifurcation" : pt->is_fold ? "fold" : "orbit";
    const char *verdict = pt->is_start        ? "neutral"
                          : pt->has_spectrum ? bkf_orbit_verdict_name(pt->verdict)
                          : w->o->stability  ? "undecided"
                                             : "none";
    double outp = pt->has_spectrum ? (double)pt->out_plus : NAN;
    double outm = pt->has_spectrum ? (double)pt->out_minus : NAN;
    double outc = pt->has_spectrum ? (double)pt->out_complex : NAN;
    bkf_io_value row[NCOLUMNS] = {
        {(double)pt->index, NULL}, {0, kind},
        {pt->model.nu, NULL},      {pt->model.gamma, NULL},
        {pt->model.c, NULL},       {pt->model.S, NULL},
        {pt->period, NULL},        {pt->period_err, NULL},
        {pt->amplitude, NULL},     {pt->mode_amplitude, NULL},
        {pt->shift, NULL},         {0, verdict},
        {pt->m_abs, NULL},         {pt->m_re, NULL},
        {pt->m_im, NULL},          {pt->m_err, NULL},
        {outp, NULL},              {outm, NULL},
        {outc, NULL},              {0, bkf_orbits_events_text(pt->events, ev, sizeof ev)},
        {0, pt->status}};
    if (!s) s = bkf_io_table_row(w->t, row, &w->err);
    if (!s && (w->spec->spacetime || w->spec->multipliers)) s = keep_orbit(w, pt);
    if (!s && w->regimes.rows) count_segment(w, pt);
    if (s) {
        w->status = s;
        return 1;
    }
    return 0;
}

static int write_spacetime(const writer *w, bkf_error *err)
{
    const kept_orbit *k = &w->keep;
    bkf_pde_options po = bkf_pde_options_default();
    po.tol = 1e-10;
    po.cancel = w->o->cancel;
    bkf_pde *pde = bkf_pde_alloc(&k->model, &po, err);
    if (!pde) return err ? err->status : BKF_ENOMEM;
    size_t N = k->model.N, frames = 400;
    double h = k->model.S / (double)N;
    float *field = malloc((frames + 1) * N * sizeof *field);
    double *t = malloc((frames + 1) * sizeof *t);
    int s = field && t ? BKF_OK : bkf_error_set(err, BKF_ENOMEM, "out of memory");
    if (!s) s = bkf_pde_set_state(pde, k->psi, k->eta, 0.0, err);
    for (size_t f = 0; !s && f <= frames; f++) {
        double tf = 2.0 * k->period * (double)f / (double)frames;
        if (f) s = bkf_pde_run(pde, tf, tf, NULL, NULL, NULL, NULL, err);
        t[f] = tf;
        const double *psi = bkf_pde_psi(pde);
        for (size_t i = 0; !s && i < N; i++) field[f * N + i] = (float)psi[i];
    }
    bkf_pde_free(pde);
    bkf_io_atomic *file = s ? NULL : bkf_io_atomic_open(w->spec->spacetime, err);
    if (!s && !file) s = err ? err->status : BKF_EIO;
    if (!s) {
        FILE *out = bkf_io_atomic_stream(file);
        char nu[32];
        int bad = fprintf(out,
                          "# orbit: psi(x, t) of the period-doubled orbit at nu %s over two "
                          "periods P = %.12g, gnuplot nonuniform matrix: first row N x_0 .. "
                          "x_{N-1}, then one row per t: t psi(x_0) .. psi(x_{N-1})\n",
                          bkf_format_number(k->model.nu, nu, sizeof nu), k->period) < 0;
        bad |= fprintf(out, "%zu", N) < 0;
        for (size_t i = 0; i < N && !bad; i++) bad |= fprintf(out, " %.9g", (double)i * h) < 0;
        bad |= fputc('\n', out) == EOF;
        for (size_t f = 0; f <= frames && !bad; f++) {
            bad |= fprintf(out, "%.17g", t[f]) < 0;
            for (size_t i = 0; i < N && !bad; i++)
                bad |= fprintf(out, " %.9g", (double)field[f * N + i]) < 0;
            bad |= fputc('\n', out) == EOF;
        }
        if (bad) {
            bkf_io_atomic_abort(file);
            s = bkf_error_set(err, BKF_EIO, "spacetime: writing %s failed", w->spec->spacetime);
        } else {
            s = bkf_io_atomic_commit(file, err);
        }
    }
    free(field);
    free(t);
    return s;
}

static int write_multipliers(const writer *w, bkf_error *err)
{
    const kept_orbit *k = &w->keep;
    bkf_io_atomic *file = bkf_io_atomic_open(w->spec->multipliers, err);
    if (!file) return err ? err->status : BKF_EIO;
    bkf_io_table *t = NULL;
    int s = bkf_product_table_open(bkf_io_atomic_stream(file), BKF_IO_TSV, mult_columns, NMULT,
                                   "orbit: Floquet multipliers of one period-doubled orbit",
                                   w->prov, &t, err);
    char nu[32];
    if (!s)
        s = bkf_io_table_commentf(t, err, "nu %s, period %.12g, verdict %s",
                                  bkf_format_number(k->model.nu, nu, sizeof nu), k->period,
                                  k->has_spectrum ? bkf_orbit_verdict_name(k->verdict)
                                                  : "not computed");
    for (size_t i = 0; !s && i < k->count; i++) {
        const bkf_orbit_multiplier *m = &k->m[i];
        bkf_io_value row[NMULT] = {{(double)m->sector, NULL}, {m->re, NULL},
                                   {m->im, NULL},             {m->abs, NULL},
                                   {m->err, NULL},            {0, bkf_orbit_mult_kind_name(m->kind)},
                                   {m->tail, NULL},           {m->alignment, NULL}};
        s = bkf_io_table_row(t, row, err);
    }
    return bkf_product_table_file_close(t, file, s, err);
}

static const bkf_io_column coexist_columns[] = {
    {"point", BKF_IO_NUMBER},     {"nu", BKF_IO_NUMBER},      {"regime", BKF_IO_TEXT},
    {"oscillation", BKF_IO_TEXT}, {"orbits", BKF_IO_NUMBER},  {"stable_orbits", BKF_IO_NUMBER},
    {"undecided_orbits", BKF_IO_NUMBER}, {"expected", BKF_IO_TEXT},
    {"consistent", BKF_IO_TEXT}};
#define NCOEXIST (sizeof coexist_columns / sizeof coexist_columns[0])

static int is_regime(const char *r, const char *name) { return strcmp(r, name) == 0; }

static int write_coexistence(writer *w, size_t N, bkf_error *err)
{
    bkf_io_atomic *file = bkf_io_atomic_open(w->spec->coexistence, err);
    if (!file) return err ? err->status : BKF_EIO;
    bkf_io_table *t = NULL;
    int s = bkf_product_table_open(
        bkf_io_atomic_stream(file), BKF_IO_TSV, coexist_columns, NCOEXIST,
        "orbit: the simulated regimes beside the stable solutions known at their nu", w->prov,
        &t, err);
    if (!s)
        s = bkf_io_table_commentf(
            t, err,
            "the branch covered nu in [%.10g, %.10g]; oscillation: floquet on the ring (every "
            "allowed mode with c q <= 6); orbits: the branch's orbits at that nu (stable: both "
            "neighbouring rows stable); expected: hysteresis (the oscillation and a pacemaker "
            "orbit both stable), global_oscillation, period_doubled_pacemakers, neither (no "
            "stable state known here: fronts, irregular, or another branch's), undecided; "
            "outside: beyond the branch",
            w->nu_lo, w->nu_hi);
    for (size_t i = 0; !s && i < w->regimes.count; i++) {
        regime_row *r = &w->regimes.rows[i];
        if (!r->match) continue;
        s = oscillation_on_ring(&w->o->model, r->nu, N, w->o->tol, &r->osc, err);
        if (s) break;
        int outside = !(r->nu >= w->nu_lo && r->nu <= w->nu_hi);
        int osc = r->osc == 1, pm = !outside && r->stable > 0;
        const char *expected = outside                       ? "outside"
                               : osc && pm                   ? "hysteresis"
                               : osc                         ? "global_oscillation"
                               : pm                          ? "period_doubled_pacemakers"
                               : r->undecided || r->osc < 0  ? "undecided"
                                                             : "neither";
        const char *consistent;
        int known = is_regime(r->regime, "global_oscillation") ||
                    is_regime(r->regime, "period_doubled_pacemakers");
        if (outside || is_regime(r->regime, "transient") || is_regime(r->regime, "none") ||
            is_regime(expected, "undecided"))
            consistent = "undecided";
        else if (is_regime(expected, "neither"))
            consistent = known ? "no" : "yes";
        else if (is_regime(expected, "hysteresis"))
            consistent = known ? "yes" : "no";
        else
            consistent = is_regime(r->regime, expected) ? "yes" : "no";
        const char *osc_text = r->osc == 1 ? "stable" : r->osc == 0 ? "unstable" : "undecided";
        bkf_io_value row[NCOEXIST] = {
            {r->point, NULL},
            {r->nu, NULL},
            {0, r->regime},
            {0, osc_text},
            {outside ? NAN : (double)r->orbits, NULL},
            {outside ? NAN : (double)r->stable, NULL},
            {outside ? NAN : (double)r->undecided, NULL},
            {0, expected},
            {0, consistent}};
        s = bkf_io_table_row(t, row, err);
    }
    return bkf_product_table_file_close(t, file, s, err);
}

int bkf_orbits_write(const bkf_orbits_spec *spec, FILE *out, bkf_io_format format,
                     const bkf_provenance *prov, bkf_error *err)
{
    int s = bkf_orbits_check(spec, "", err);
    if (s) return s;
    bkf_orbits_options o = bkf_orbits_options_of(spec);
    writer w;
    memset(&w, 0, sizeof w);
    w.spec = spec;
    w.o = &o;
    w.prov = prov;
    if (spec->regimes) {
        s = read_regimes(spec->regimes, &o.model, &w.regimes, err);
        if (s) {
            free(w.regimes.rows);
            return s;
        }
    }
    s = bkf_product_table_open(out, format, columns, NCOLUMNS,
                               "orbit: the branch of period-doubled orbits of the PDE born at "
                               "the period doubling of the global oscillation",
                               prov, &w.t, err);
    if (s) {
        free(w.regimes.rows);
        return s;
    }
    bkf_orbits_report rep;
    s = bkf_orbits_branch(&o, visit_row, &w, &rep, err);
    if (w.status) {
        s = w.status;
        if (err) *err = w.err;
    }
    if (!s) s = bkf_io_table_finish(w.t, err);
    if (!s && (spec->spacetime || spec->multipliers) && !w.keep.have)
        s = bkf_error_set(err, BKF_ENUMERIC,
                          "spacetime, multipliers: no row has a solved orbit to write");
    if (!s && spec->spacetime) s = write_spacetime(&w, err);
    if (!s && spec->multipliers) s = write_multipliers(&w, err);
    if (!s && spec->coexistence) s = write_coexistence(&w, rep.N, err);
    free(w.regimes.rows);
    bkf_io_table_free(w.t);
    free(w.keep.psi);
    free(w.keep.eta);
    free(w.keep.m);
    return s;
}

#include "bkfront/oscillation.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bkfront/model.h"

#include "product_internal.h"

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

static const char *const stepper_names[] = {"auto", "explicit", "implicit", "extrapolation",
                                            NULL};
static const bkf_stepper_kind stepper_kinds[] = {BKF_STEPPER_AUTO, BKF_STEPPER_EXPLICIT,
                                                 BKF_STEPPER_IMPLICIT, BKF_STEPPER_EXTRAPOLATION};
#define NSTEPPERS (sizeof stepper_kinds / sizeof stepper_kinds[0])
static const char *const along_names[] = {"c", "gamma", NULL};

/* "A:B" with -1 < A < B < 1. */
static int set_search(void *vspec, const char *text, bkf_error *err)
{
    bkf_oscillation_spec *spec = vspec;
    const char *form = "A:B with -1 < A < B < 1";
    char a[72], left[64];
    const char *colon = text ? strchr(text, ':') : NULL;
    size_t n = colon ? (size_t)(colon - text) : 0;
    if (!colon || strchr(colon + 1, ':') || n >= sizeof left)
        return bkf_error_set(err, BKF_EINPUT, "'%s' is not %s",
                             bkf_option_shown(text, a, sizeof a), form);
    memcpy(left, text, n);
    left[n] = '\0';
    double lo, hi;
    bkf_error e;
    if (bkf_option_parse_double(left, "", "A", &lo, &e) ||
        bkf_option_parse_double(colon + 1, "", "B", &hi, &e) || !(lo > -1.0 && hi < 1.0 && lo < hi))
        return bkf_error_set(err, BKF_EINPUT, "'%s' is not %s",
                             bkf_option_shown(text, a, sizeof a), form);
    spec->search_lo = lo;
    spec->search_hi = hi;
    spec->search_given = 1;
    return BKF_OK;
}

#define BOUNDED (BKF_OPT_MIN | BKF_OPT_MAX)

const bkf_option bkf_oscillation_options[] = {
    {.name = "gamma", .type = BKF_OPT_DOUBLE, .offset = offsetof(bkf_oscillation_spec, gamma),
     .flags = BOUNDED, .min = BKF_CYCLE_MU_MIN, .max = BKF_CYCLE_MU_MAX, .form = "G",
     .shown_default = BKF_TEXT_OF(BKF_PAPER_GAMMA),
     .help = "friction strength, in [1e-06, 1e+06]"},
    {.name = "c", .type = BKF_OPT_DOUBLE, .offset = offsetof(bkf_oscillation_spec, c),
     .flags = BKF_OPT_MIN | BKF_OPT_MAX, .min = 0, .max = BKF_MODEL_C_MAX, .form = "C",
     .shown_default = BKF_TEXT_OF(BKF_PAPER_C),
     .help = "sound speed, in [0, 1e6] (> 0 for --threshold and --diagram:\n"
             "with c = 0 every q is the neutral q = 0 mode)"},
    {.name = "nu", .type = BKF_OPT_DOUBLE, .offset = offsetof(bkf_oscillation_spec, nu),
     .flags = BOUNDED | BKF_OPT_MIN_OPEN | BKF_OPT_MAX_OPEN | BKF_OPT_FANOUT, .min = -1, .max = 1,
     .form = "V", .shown_default = BKF_TEXT_OF(BKF_PAPER_NU),
     .help = "pulling rate, in (-1, 1); dispersion mode only"},
    {.name = "q", .type = BKF_OPT_DOUBLE_LIST, .offset = offsetof(bkf_oscillation_spec, q),
     .flags = BKF_OPT_MIN, .min = 0, .max_count = BKF_OSCILLATION_MAX_ROWS, .form = "LIST",
     .help = "wavenumbers, >= 0, c q <= 1e4: Q, Q1,Q2,... or A:B:N;\n"
             "dispersion mode only"},
    {.name = "S", .type = BKF_OPT_DOUBLE, .offset = offsetof(bkf_oscillation_spec, S),
     .flags = BKF_OPT_MIN | BKF_OPT_MIN_OPEN, .min = 0, .form = "S",
     .help = "system size, > 0: the modes q = 2 pi j/S in the --q range\n"
             "are added to the rows and marked allowed = 1"},
    {.name = "threshold", .type = BKF_OPT_SWITCH,
     .offset = offsetof(bkf_oscillation_spec, threshold),
     .help = "the lowest stability boundary in the --search range of nu\n"
             "(the scan runs upward from A), located by root finding on\n"
             "the height of the peak of lambda (NLopt) or on the\n"
             "long-wave coefficient; with --along, its curve against c or\n"
             "gamma by pseudo-arclength continuation from --from to --to"},
    {.name = "diagram", .type = BKF_OPT_SWITCH, .offset = offsetof(bkf_oscillation_spec, diagram),
     .help = "every interval of the --search range where the oscillation\n"
             "is stable or unstable, each boundary located and labelled"},
    {.name = "along", .type = BKF_OPT_CHOICE, .offset = offsetof(bkf_oscillation_spec, along),
     .choices = along_names, .form = "c|gamma",
     .help = "with --threshold: the parameter of the curve; the option of\n"
             "that name is then not given (it runs from --from to --to)"},
    {.name = "from", .type = BKF_OPT_DOUBLE, .offset = offsetof(bkf_oscillation_spec, from),
     .form = "A", .help = "start of the curve (c > 0; gamma in range)"},
    {.name = "to", .type = BKF_OPT_DOUBLE, .offset = offsetof(bkf_oscillation_spec, to),
     .form = "B", .help = "end of the curve, B != A"},
    {.name = "search", .type = BKF_OPT_CUSTOM, .set = set_search, .form = "A:B",
     .shown_default = "-0.999:0.999",
     .help = "nu range scanned by --threshold and --diagram,\n-1 < A < B < 1"},
    {.name = "tol", .type = BKF_OPT_DOUBLE, .offset = offsetof(bkf_oscillation_spec, tol),
     .flags = BOUNDED, .min = BKF_TOL_MIN, .max = BKF_TOL_MAX, .form = "E",
     .shown_default = "1e-10",
     .help = "absolute accuracy asked of lambda (of the multiplier m1)\n"
             "and of the boundaries in nu, in [1e-14, 0.1]"},
    {.name = "cq-max", .type = BKF_OPT_DOUBLE, .offset = offsetof(bkf_oscillation_spec, cq_max),
     .flags = BOUNDED | BKF_OPT_MIN_OPEN, .min = 0, .max = BKF_OSCILLATION_CQ_MAX, .form = "P",
     .shown_default = "6", .help = "peaks of lambda are sought for c q in (0, P]"},
    {.name = "nu-step", .type = BKF_OPT_DOUBLE, .offset = offsetof(bkf_oscillation_spec, nu_step),
     .flags = BOUNDED | BKF_OPT_MIN_OPEN, .min = 0, .max = 1, .form = "H",
     .shown_default = "0.01",
     .help = "step of the scan in nu, in (0, 1]. Stable or unstable\n"
             "windows narrower than H may be missed"},
    {.name = "stepper", .type = BKF_OPT_CHOICE, .offset = offsetof(bkf_oscillation_spec, stepper),
     .choices = stepper_names, .form = "auto|explicit|implicit|extrapolation",
     .shown_default = "auto",
     .help = "integrator: rk8pd (explicit), bsimp (implicit), the cycle\n"
             "by bd2x2 and the monodromy by bsimp (extrapolation), or by\n"
             "stiffness (auto: the cycle as bkfront period's auto stepper,\n"
             "collocation among them; the monodromy by bsimp above\n"
             "gamma = 30, else rk8pd)"},
};
const size_t bkf_oscillation_noptions =
    sizeof bkf_oscillation_options / sizeof bkf_oscillation_options[0];

bkf_oscillation_spec bkf_oscillation_spec_default(void)
{
    bkf_oscillation_spec s;
    memset(&s, 0, sizeof s);
    s.gamma = s.c = s.nu = s.S = NAN;
    s.along = -1;
    s.from = s.to = NAN;
    s.search_lo = BKF_OSCILLATION_SEARCH_LO;
    s.search_hi = BKF_OSCILLATION_SEARCH_HI;
    s.tol = bkf_floquet_options_default().tol;
    s.cq_max = s.nu_step = NAN;
    return s;
}

void bkf_oscillation_spec_free(bkf_oscillation_spec *spec)
{
    bkf_option_free_lists(bkf_oscillation_options, bkf_oscillation_noptions, spec);
}

bkf_oscillation_mode bkf_oscillation_mode_of(const bkf_oscillation_spec *spec)
{
    return spec->diagram     ? BKF_OSCILLATION_DIAGRAM
           : spec->threshold ? (spec->along >= 0 ? BKF_OSCILLATION_CURVE : BKF_OSCILLATION_THRESHOLD)
                             : BKF_OSCILLATION_DISPERSION;
}

bkf_floquet_options bkf_oscillation_floquet_options(const bkf_oscillation_spec *spec)
{
    bkf_floquet_options o = bkf_floquet_options_default();
    o.tol = spec->tol;
    if (!isnan(spec->cq_max)) o.p_max = spec->cq_max;
    if (!isnan(spec->nu_step)) o.nu_step = spec->nu_step;
    o.stepper = (unsigned)spec->stepper < NSTEPPERS ? stepper_kinds[spec->stepper] : BKF_STEPPER_AUTO;
    return o;
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

static int check_gamma(const char *p, const char *key, double gamma, bkf_error *err)
{
    char a[32];
    if (!(gamma >= BKF_CYCLE_MU_MIN && gamma <= BKF_CYCLE_MU_MAX))
        return bkf_error_set(err, BKF_EINPUT, "%s%s: gamma = %s is outside [%g, %g]", p, key,
                             bkf_format_number(gamma, a, sizeof a), BKF_CYCLE_MU_MIN,
                             BKF_CYCLE_MU_MAX);
    return BKF_OK;
}

static int check_c(const char *p, const char *key, double c, int positive, bkf_error *err)
{
    char a[32];
    if (positive && !(c > 0))
        return bkf_error_set(err, BKF_EINPUT,
                             "%s%s: c = %s must be > 0 for thresholds (with c = 0 every wavenumber "
                             "is the neutral q = 0 mode)",
                             p, key, bkf_format_number(c, a, sizeof a));
    if (!(c >= 0 && c <= BKF_MODEL_C_MAX))
        return bkf_error_set(err, BKF_EINPUT, "%s%s: c = %s must be in [0, 1e+06]", p, key,
                             bkf_format_number(c, a, sizeof a));
    return BKF_OK;
}

/* The spec with what a mode uses and was not given at the paper's values:
 * gamma and c but the one a curve runs along; nu in the dispersion mode. */
static bkf_oscillation_spec resolved(const bkf_oscillation_spec *sp)
{
    bkf_oscillation_spec r = *sp;
    bkf_oscillation_mode mode = bkf_oscillation_mode_of(sp);
    int curve = mode == BKF_OSCILLATION_CURVE;
    bkf_model_paper_where_unset(curve && sp->along == BKF_FLOQUET_ALONG_GAMMA ? NULL : &r.gamma,
                                curve && sp->along == BKF_FLOQUET_ALONG_C ? NULL : &r.c,
                                mode == BKF_OSCILLATION_DISPERSION ? &r.nu : NULL, NULL);
    return r;
}

/* Which keys each mode takes and needs, in the order a user meets them. */
static int check_keys(const bkf_oscillation_spec *sp, const char *p, bkf_error *err)
{
    bkf_oscillation_mode mode = bkf_oscillation_mode_of(sp);
    int given_from = !isnan(sp->from), given_to = !isnan(sp->to);
    if (sp->threshold && sp->diagram)
        return bkf_error_set(err, BKF_EINPUT,
                             "%sthreshold and %sdiagram are separate modes: give one", p, p);
    if (!sp->threshold && (sp->along >= 0 || given_from || given_to))
        return bkf_error_set(err, BKF_EINPUT, "%s%s: only with %sthreshold (the threshold curve)",
                             p, sp->along >= 0 ? "along" : given_from ? "from" : "to", p);
    if (mode == BKF_OSCILLATION_CURVE) {
        if (sp->along > BKF_FLOQUET_ALONG_GAMMA)
            return bkf_error_set(err, BKF_EINPUT, "%salong: not c or gamma", p);
        if (!given_from || !given_to)
            return bkf_error_set(err, BKF_EINPUT, "%s%s is required with %salong (the curve's ends)",
                                 p, given_from ? "to" : "from", p);
        if (sp->along == BKF_FLOQUET_ALONG_C && !isnan(sp->c))
            return bkf_error_set(err, BKF_EINPUT,
                                 "%sc: not given with %salong c (c runs from %sfrom to %sto)", p, p,
                                 p, p);
        if (sp->along == BKF_FLOQUET_ALONG_GAMMA && !isnan(sp->gamma))
            return bkf_error_set(err, BKF_EINPUT,
                                 "%sgamma: not given with %salong gamma (gamma runs from %sfrom to "
                                 "%sto)", p, p, p, p);
    } else if (given_from || given_to)
        return bkf_error_set(err, BKF_EINPUT, "%s%s: only with %salong", p,
                             given_from ? "from" : "to", p);
    if (mode != BKF_OSCILLATION_DISPERSION) {
        if (!isnan(sp->nu))
            return bkf_error_set(err, BKF_EINPUT, "%snu: not used by %s%s, which scans nu (see %ssearch)",
                                 p, p, sp->diagram ? "diagram" : "threshold", p);
        if (sp->q.count) return bkf_error_set(err, BKF_EINPUT, "%sq: only in the dispersion mode", p);
        if (!isnan(sp->S)) return bkf_error_set(err, BKF_EINPUT, "%sS: only in the dispersion mode", p);
        return BKF_OK;
    }
    if (sp->search_given)
        return bkf_error_set(err, BKF_EINPUT, "%ssearch: only with %sthreshold or %sdiagram", p, p, p);
    if (!isnan(sp->cq_max) || !isnan(sp->nu_step))
        return bkf_error_set(err, BKF_EINPUT, "%s%s: only with %sthreshold or %sdiagram", p,
                             !isnan(sp->cq_max) ? "cq-max" : "nu-step", p, p);
    if (!sp->q.count || !sp->q.values)
        return bkf_error_set(err, BKF_EINPUT, "%sq is required (Q, Q1,Q2,... or A:B:N, each >= 0)", p);
    return BKF_OK;
}

int bkf_oscillation_check(const bkf_oscillation_spec *sp, const char *prefix, bkf_error *err)
{
    if (!sp) return bkf_error_set(err, BKF_EINPUT, "floquet: spec is NULL");
    const char *p = prefix ? prefix : "";
    int s = check_keys(sp, p, err);
    if (s) return s;
    bkf_oscillation_spec r = resolved(sp);
    sp = &r;
    bkf_oscillation_mode mode = bkf_oscillation_mode_of(sp);
    int scanning = mode != BKF_OSCILLATION_DISPERSION;
    char a[32];
    if (mode == BKF_OSCILLATION_CURVE) {
        int along_c = sp->along == BKF_FLOQUET_ALONG_C;
        if ((s = along_c ? check_c(p, "from", sp->from, 1, err) : check_gamma(p, "from", sp->from, err)))
            return s;
        if ((s = along_c ? check_c(p, "to", sp->to, 1, err) : check_gamma(p, "to", sp->to, err)))
            return s;
        if (sp->from == sp->to)
            return bkf_error_set(err, BKF_EINPUT,
                                 "%sfrom, %sto: the curve needs two different ends", p, p);
    }
    if (!isnan(sp->gamma) && (s = check_gamma(p, "gamma", sp->gamma, err))) return s;
    if (!isnan(sp->c) && (s = check_c(p, "c", sp->c, scanning, err))) return s;
    bkf_error e;
    if (bkf_model_check_tol(sp->tol, &e))
        return bkf_error_set(err, BKF_EINPUT, "%stol: %s", p, e.message);
    bkf_floquet_options o = bkf_oscillation_floquet_options(sp);
    if (!(o.p_max > 0 && o.p_max <= BKF_OSCILLATION_CQ_MAX))
        return bkf_error_set(err, BKF_EINPUT, "%scq-max: %s is outside (0, 1e4]", p,
                             bkf_format_number(o.p_max, a, sizeof a));
    if (!(o.nu_step > 0 && o.nu_step <= 1))
        return bkf_error_set(err, BKF_EINPUT, "%snu-step: %s is outside (0, 1]", p,
                             bkf_format_number(o.nu_step, a, sizeof a));
    if ((unsigned)sp->stepper >= NSTEPPERS)
        return bkf_error_set(err, BKF_EINPUT,
                             "%sstepper: not auto, explicit, implicit or extrapolation", p);
    if (scanning) {
        if (!(sp->search_lo > -1.0 && sp->search_hi < 1.0 && sp->search_lo < sp->search_hi))
            return bkf_error_set(err, BKF_EINPUT, "%ssearch: needs -1 < A < B < 1", p);
        return BKF_OK;
    }
    if (bkf_model_check_nu_active(sp->nu, &e))
        return bkf_error_set(err, BKF_EINPUT, "%snu: %s", p, e.message);
    if (!isnan(sp->S) && !(sp->S > 0 && isfinite(sp->S)))
        return bkf_error_set(err, BKF_EINPUT, "%sS: S = %s must be > 0", p,
                             bkf_format_number(sp->S, a, sizeof a));
    for (size_t i = 0; i < sp->q.count; i++) {
        if (!(sp->q.values[i] >= 0 && isfinite(sp->q.values[i])))
            return bkf_error_set(err, BKF_EINPUT, "%sq: q = %s must be >= 0", p,
                                 bkf_format_number(sp->q.values[i], a, sizeof a));
        if (sp->c * sp->q.values[i] > BKF_OSCILLATION_CQ_MAX)
            return bkf_error_set(err, BKF_EINPUT, "%sq: c q = %s is above 1e4", p,
                                 bkf_format_number(sp->c * sp->q.values[i], a, sizeof a));
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
    bkf_floquet_options options;
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
    int s = bkf_oscillation_check(p, "", err);
    if (s) return s;
    if (bkf_oscillation_mode_of(p) != BKF_OSCILLATION_DISPERSION)
        return bkf_error_set(err, BKF_EINPUT, "threshold, diagram: not the dispersion's keys");
    d->options = bkf_oscillation_floquet_options(p);
    if ((s = bkf_oscillation_rows(p->q.values, p->q.count, p->S, &d->q, &d->allowed, &d->count,
                                  err)))
        return s;
    d->floquet = bkf_floquet_alloc();
    if (!d->floquet) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    bkf_error e;
    s = bkf_floquet_set(d->floquet, p->gamma, p->c, p->nu, &d->options, &e);
    if (s) {
        char a[32], b[32];
        return bkf_error_set(err, s, "global oscillation at gamma = %s, nu = %s: %s",
                             bkf_format_number(p->gamma, a, sizeof a),
                             bkf_format_number(p->nu, b, sizeof b), e.message);
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
    if (s == BKF_ETOL) {
        row->refused = 1;
        row->message = d->row_err.message;
        pt->lambda = pt->m1_re = pt->m1_im = pt->m2_re = pt->m2_im = pt->m1_err = NAN;
    } else if (s) {
        char a[32];
        return bkf_error_set(err, s, "at q = %s: %s", bkf_format_number(d->q[i], a, sizeof a),
                             d->row_err.message);
    }
    row->allowed = p->S > 0 ? d->allowed[i] : -1;
    row->lambda_slip = d->cycle->period * bkf_floquet_slip_rate(p->gamma, p->c, p->nu, pt->q);
    return BKF_OK;
}

int bkf_oscillation_dispersion(const bkf_oscillation_spec *spec, bkf_oscillation_visit visit,
                               void *data, bkf_cycle_result *cycle, bkf_error *err)
{
    bkf_oscillation_spec r = resolved(spec);
    dispersion d;
    int s = dispersion_begin(&r, &d, err);
    if (!s && cycle) *cycle = *d.cycle;
    for (size_t i = 0; !s && i < d.count; i++) {
        bkf_oscillation_row row;
        s = dispersion_row(&d, i, &row, err);
        if (!s && visit && visit(&row, data)) break;
    }
    dispersion_free(&d);
    return s;
}

static int write_dispersion(const bkf_oscillation_spec *p, const bkf_provenance *prov,
                            bkf_io_table *t, bkf_error *err)
{
    dispersion d;
    int s = dispersion_begin(p, &d, err);
    char a[32], b[32], c[32], e[32], line[512];
    if (!s) {
        snprintf(line, sizeof line, "gamma %s, c %s, nu %s, tol %s",
                 bkf_format_number(p->gamma, a, sizeof a), bkf_format_number(p->c, b, sizeof b),
                 bkf_format_number(p->nu, c, sizeof c),
                 bkf_format_number(d.options.tol, e, sizeof e));
        s = bkf_io_table_comment(t, line, err);
    }
    if (!s) {
        snprintf(line, sizeof line,
                 "cycle: T = %.17g (err %.3g), ln(m1 m2) = %.17g; stepper %s; %zu rows%s%s",
                 d.cycle->period, d.cycle->period_err, d.cycle->log_multiplier, d.cycle->stepper,
                 d.count, p->S > 0 ? ", allowed modes q = 2 pi j/S with S = " : "",
                 p->S > 0 ? bkf_format_number(p->S, b, sizeof b) : "");
        s = bkf_io_table_comment(t, line, err);
    }
    if (!s) s = bkf_product_table_command(t, prov, err);
    /* The refused rows, reported once when the table is done: their count,
     * their q (the first few) and the first one's reason. */
    size_t refused = 0;
    char qs[160] = "", first[256] = "";
    for (size_t i = 0; i < d.count && !s; i++) {
        bkf_oscillation_row row;
        if ((s = dispersion_row(&d, i, &row, err))) break;
        const bkf_floquet_point *pt = &row.point;
        if (row.refused && refused++ < 4) {
            size_t used = strlen(qs);
            snprintf(qs + used, sizeof qs - used, "%s%s", refused > 1 ? ", " : "",
                     refused > 3 ? "..." : bkf_format_number(d.q[i], a, sizeof a));
            if (refused == 1) snprintf(first, sizeof first, "%s", row.message);
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
    if (!s && refused && p->warn) {
        snprintf(line, sizeof line, "%zu of %zu rows refused (kind refused, lambda nan) at "
                 "q = %s; the first: %s", refused, d.count, qs, first);
        p->warn(line, p->warn_data);
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
                        const bkf_floquet_options *o, const bkf_provenance *prov, bkf_error *err)
{
    char a[32], b[32], c[32], d[32], e[32], line[512];
    snprintf(line, sizeof line,
             "scan: nu in [%s, %s] upward in steps %s, c q in (0, %s] on %zu points; tol %s",
             bkf_format_number(p->search_lo, a, sizeof a),
             bkf_format_number(p->search_hi, b, sizeof b),
             bkf_format_number(o->nu_step, c, sizeof c), bkf_format_number(o->p_max, d, sizeof d),
             o->scan_points, bkf_format_number(o->tol, e, sizeof e));
    int s = bkf_io_table_comment(t, line, err);
    if (!s)
        s = bkf_io_table_comment(
            t,
            "kinds: period_doubling (finite-q peak of lambda through 0 with m1 = -1), long_wave "
            "(a in lambda ~ a c^2 q^2 through 0), other (finite-q peak with m1 = +1, or a jump of "
            "the cycle), scan_end, none (no change of stability in the range)",
            err);
    if (!s) s = bkf_product_table_command(t, prov, err);
    return s;
}

static int write_scan(const bkf_oscillation_spec *p, const bkf_provenance *prov,
                      bkf_io_table *t, bkf_error *err)
{
    bkf_floquet_options o = bkf_oscillation_floquet_options(p);
    bkf_oscillation_mode mode = bkf_oscillation_mode_of(p);
    /* the continued one is not given: its value is the curve's */
    double gamma = isnan(p->gamma) ? 0 : p->gamma, c = isnan(p->c) ? 0 : p->c;
    int s = comment_scan(t, p, &o, prov, err);
    if (s) return s;
    char a[32], b[32];
    sink k = {t, 0, {{0}, 0}};
    bkf_error e = {0};
    if (mode == BKF_OSCILLATION_THRESHOLD) {
        bkf_floquet_threshold th;
        s = bkf_floquet_threshold_find(gamma, c, p->search_lo, p->search_hi, &o, &th, &e);
        if (s)
            return bkf_error_set(err, s, "threshold at gamma = %s, c = %s: %s",
                                 bkf_format_number(p->gamma, a, sizeof a),
                                 bkf_format_number(p->c, b, sizeof b), e.message);
        if (th.kind == BKF_BOUNDARY_NONE) {
            char lo[32], hi[32], st[32];
            s = bkf_io_table_commentf(
                t, err,
                "no threshold: no change of stability for nu in [%s, %s] at gamma = %s, c = %s; "
                "global oscillations are %s throughout (scan step %s)",
                bkf_format_number(p->search_lo, lo, sizeof lo),
                bkf_format_number(p->search_hi, hi, sizeof hi),
                bkf_format_number(p->gamma, a, sizeof a), bkf_format_number(p->c, b, sizeof b),
                th.stable_above ? "stable" : "unstable", bkf_format_number(o.nu_step, st, sizeof st));
            if (s) return s;
        }
        threshold_row(&th, &k);
    } else if (mode == BKF_OSCILLATION_CURVE) {
        s = bkf_floquet_threshold_branch((bkf_floquet_param)p->along, p->from, p->to, gamma, c,
                                         p->search_lo, p->search_hi, &o, 0, threshold_row, &k, &e);
        if (!k.status && s)
            return bkf_error_set(err, s, "threshold curve along %s from %s to %s: %s",
                                 p->along == BKF_FLOQUET_ALONG_C ? "c" : "gamma",
                                 bkf_format_number(p->from, a, sizeof a),
                                 bkf_format_number(p->to, b, sizeof b), e.message);
    } else {
        s = bkf_floquet_diagram(gamma, c, p->search_lo, p->search_hi, &o, diagram_row, &k, &e);
        if (!k.status && s)
            return bkf_error_set(err, s, "diagram at gamma = %s, c = %s: %s",
                                 bkf_format_number(p->gamma, a, sizeof a),
                                 bkf_format_number(p->c, b, sizeof b), e.message);
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

int bkf_oscillation_write(const bkf_oscillation_spec *spec, FILE *out, bkf_io_format format,
                          const bkf_provenance *prov, bkf_error *err)
{
    int s = bkf_oscillation_check(spec, "", err);
    if (s) return s;
    bkf_oscillation_spec r = resolved(spec);
    spec = &r;
    bkf_oscillation_mode mode = bkf_oscillation_mode_of(spec);
    size_t ncols;
    const bkf_io_column *cols = bkf_oscillation_columns(mode, &ncols);
    bkf_io_table *t;
    if ((s = bkf_product_table_open(out, format, cols, ncols, title(mode), prov, &t, err)))
        return s;
    s = mode == BKF_OSCILLATION_DISPERSION ? write_dispersion(spec, prov, t, err)
                                           : write_scan(spec, prov, t, err);
    if (!s) s = bkf_io_table_finish(t, err);
    bkf_io_table_free(t);
    return s;
}

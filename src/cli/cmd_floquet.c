/* bkfront floquet: stability of the global oscillations.  Three modes:
 *   dispersion  lambda_q and the multipliers on a q grid (--nu, --q)
 *   threshold   the lowest stability boundary in nu, or its curve against
 *               c or gamma (--threshold [--along c|gamma --from A --to B])
 *   diagram     every stable and unstable interval of nu (--diagram)
 *
 * As in `bkfront period`: every input is checked before the first solve,
 * and the table is built in memory and written only when everything
 * succeeded. */
#include "args.h"
#include "product_out.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bkfront/floquet.h"
#include "bkfront/io.h"
#include "bkfront/model.h"
#include "bkfront/oscillation.h"

#define COUNT(a) (sizeof(a) / sizeof((a)[0]))

static const char *const stepper_names[] = {"auto", "explicit", "implicit", NULL};
static const bkf_stepper_kind stepper_kinds[] = {BKF_STEPPER_AUTO, BKF_STEPPER_EXPLICIT,
                                                 BKF_STEPPER_IMPLICIT};
static const char *const format_names[] = {"tsv", "json", NULL};
static const char *const along_names[] = {"c", "gamma", NULL};

#define DEFAULT_SEARCH_LO BKF_OSCILLATION_SEARCH_LO
#define DEFAULT_SEARCH_HI BKF_OSCILLATION_SEARCH_HI

static void floquet_help(FILE *out)
{
    bkf_floquet_options d = bkf_floquet_options_default();
    fprintf(out,
        "usage: bkfront floquet --gamma G --c C --nu V --q Q|A:B:N [--S S]\n"
        "       bkfront floquet --threshold --gamma G --c C [--search A:B]\n"
        "       bkfront floquet --threshold --along c|gamma --from A --to B\n"
        "                       (--gamma G | --c C) [--search A:B]\n"
        "       bkfront floquet --diagram --gamma G --c C [--search A:B]\n"
        "   common: [--tol E] [--cq-max P] [--nu-step H] [--stepper auto|explicit|implicit]\n"
        "           [--format tsv|json] [--out FILE]\n"
        "\n"
        "Floquet stability of the global oscillation psi*(t) (the van der Pol cycle\n"
        "with mu = gamma) against perturbations exp(iqx):\n"
        "    d_psi' = gamma (d_eta - (psi*^2 - 1) d_psi),  d_eta' = -(1 + c^2 q^2) d_psi/gamma\n"
        "over one period T.  lambda = ln|m1|, m1 the dominant multiplier of the\n"
        "monodromy matrix, is the growth per period; lambda > 0 is unstable.\n"
        "\n"
        "modes:\n"
        "  (default)         dispersion relation: one row per q\n"
        "  --threshold       the lowest stability boundary in the --search range of nu\n"
        "                    (the scan runs upward from A), located by root finding on\n"
        "                    the height of the peak of lambda (NLopt) or on the\n"
        "                    long-wave coefficient; with --along, its curve against c or\n"
        "                    gamma by pseudo-arclength continuation from --from to --to\n"
        "  --diagram         every interval of the --search range where the oscillation\n"
        "                    is stable or unstable, each boundary located and labelled\n"
        "\n"
        "options:\n"
        "  --gamma G         friction strength, in [%g, %g]\n"
        "  --c C             sound speed, >= 0 (> 0 for --threshold and --diagram: with\n"
        "                    c = 0 every q is the neutral q = 0 mode)\n"
        "  --nu V            pulling rate, in (-1, 1); dispersion mode only\n"
        "  --q Q|A:B:N       wavenumbers, >= 0, c q <= 1e4; dispersion mode only\n"
        "  --S S             system size, > 0: the modes q = 2 pi j/S in the --q range\n"
        "                    are added to the rows and marked allowed = 1\n"
        "  --along c|gamma   with --threshold: the parameter of the curve; the option of\n"
        "                    that name is then not given (it runs from --from to --to)\n"
        "  --from A, --to B  ends of the curve, A != B (c > 0; gamma in range)\n"
        "  --search A:B      nu range scanned by --threshold and --diagram, -1 < A < B < 1;\n"
        "                    default %g:%g\n"
        "  --tol E           absolute accuracy asked of lambda (of the multiplier m1)\n"
        "                    and of the boundaries in nu, in [%g, %g]; default %g\n"
        "  --cq-max P        peaks of lambda are sought for c q in (0, P]; default %g\n"
        "  --nu-step H       step of the scan in nu, in (0, 1]; default %g.  Stable or\n"
        "                    unstable windows narrower than H may be missed\n"
        "  --stepper auto|explicit|implicit\n"
        "                    integrator: rk8pd (explicit), bsimp (implicit), or by\n"
        "                    stiffness (implicit above gamma = 30); default auto\n"
        "  --format tsv|json output format; default tsv\n"
        "  --out FILE        write to FILE, replaced atomically only on success\n"
        "  --help            this text\n"
        "\n"
        "dispersion columns:\n"
        "  q, K              wavenumber and K = 1 + c^2 q^2 (q enters only through K)\n"
        "  lambda, lambda_err  ln|m1| and its estimated absolute error\n"
        "  m1_re, m1_im, m2_re, m2_im  the multipliers, |m1| >= |m2|\n"
        "  m1_err            estimated absolute error of m1\n"
        "  kind              of m1: real_positive, real_negative or complex; refused\n"
        "                    where lambda_err stays above --tol after the retries\n"
        "                    (lambda and the multipliers are then nan, and a warning\n"
        "                    goes to stderr)\n"
        "  allowed           1 if q = 2 pi j/S for an integer j, else 0; nan without --S\n"
        "  lambda_slip       growth of a perturbation of continuous slip psi = nu over\n"
        "                    the same time T: T max Re s, s^2 + gamma phi'(nu) s + K = 0\n"
        "  det, det_direct   m1 m2 by Liouville (exp of the integrated trace, used for\n"
        "                    m2) and the determinant of the integrated matrix (a check)\n"
        "threshold columns:\n"
        "  gamma, c, nu_pd, nu_pd_err  the boundary and its estimated error\n"
        "  kind              period_doubling (a finite-q peak of lambda crosses 0 with\n"
        "                    m1 = -1), long_wave (lambda ~ a c^2 q^2 changes sign at\n"
        "                    q -> 0), other (a finite-q peak with m1 = +1, or a jump of\n"
        "                    the cycle itself: discontinuous = 1)\n"
        "  q_c, K_c          critical wavenumber (0 for long_wave)\n"
        "  m_c_re, m_c_im    the critical multiplier; lambda_c: lambda there (~0)\n"
        "  stable_above      1 if the oscillation is stable just above nu_pd\n"
        "  longwave          the long-wave coefficient a at nu_pd\n"
        "diagram columns:\n"
        "  nu_from, nu_to, stability (stable|unstable), from_kind, to_kind (as above,\n"
        "  or scan_end), from_err, to_err, from_q, to_q, from_m, to_m\n"
        "\n"
        "Output is all or nothing: on any failure nothing is written.\n"
        "exit status: 0 ok, 1 numerical failure, 2 bad input\n",
        BKF_CYCLE_MU_MIN, BKF_CYCLE_MU_MAX, DEFAULT_SEARCH_LO, DEFAULT_SEARCH_HI, BKF_TOL_MIN,
        BKF_TOL_MAX, d.tol, d.p_max, d.nu_step);
}

/* Shortest of %.15g / %.17g that reads back exactly. */
static const char *num(double x, char *buf, size_t size)
{
    snprintf(buf, size, "%.15g", x);
    if (strtod(buf, NULL) != x) snprintf(buf, size, "%.17g", x);
    return buf;
}

enum { MODE_DISPERSION = 0, MODE_THRESHOLD = 1, MODE_CURVE = 2, MODE_DIAGRAM = 3 };

typedef struct {
    int mode;
    double gamma, c, nu, S;
    int have_gamma, have_c, have_S;
    cli_range q;              /* dispersion grid */
    int along;                /* BKF_FLOQUET_ALONG_C / _GAMMA */
    double from, to;
    double search_lo, search_hi;
    bkf_floquet_options options;
    bkf_io_format format;
    const char *out_path;
} floquet_plan;

static void plan_free(floquet_plan *p)
{
    cli_range_free(&p->q);
}

static int parse_gamma(const char *flag, const char *text, double *gamma, bkf_error *err)
{
    char a[32];
    int s = cli_parse_double(flag, text, gamma, err);
    if (s) return s;
    if (!(*gamma >= BKF_CYCLE_MU_MIN && *gamma <= BKF_CYCLE_MU_MAX))
        return bkf_error_set(err, BKF_EINPUT, "%s: gamma = %s is outside [%g, %g]", flag,
                             num(*gamma, a, sizeof a), BKF_CYCLE_MU_MIN, BKF_CYCLE_MU_MAX);
    return BKF_OK;
}

static int parse_c(const char *flag, const char *text, int positive, double *c, bkf_error *err)
{
    char a[32];
    int s = cli_parse_double(flag, text, c, err);
    if (s) return s;
    if (positive && !(*c > 0))
        return bkf_error_set(err, BKF_EINPUT,
                             "%s: c = %s must be > 0 for thresholds (with c = 0 every wavenumber "
                             "is the neutral q = 0 mode)",
                             flag, num(*c, a, sizeof a));
    if (!(*c >= 0))
        return bkf_error_set(err, BKF_EINPUT, "%s: c = %s must be >= 0", flag, num(*c, a, sizeof a));
    return BKF_OK;
}

/* "A:B" with -1 < A < B < 1. */
static int parse_search(const char *text, double *lo, double *hi, bkf_error *err)
{
    const char *form = "A:B with -1 < A < B < 1";
    char a[72];
    const char *colon = text ? strchr(text, ':') : NULL;
    if (!colon || strchr(colon + 1, ':'))
        return bkf_error_set(err, BKF_EINPUT, "--search: '%s' is not %s", cli_shown(text, a, sizeof a), form);
    char left[64];
    size_t n = (size_t)(colon - text);
    if (n >= sizeof left)
        return bkf_error_set(err, BKF_EINPUT, "--search: '%s' is not %s", cli_shown(text, a, sizeof a), form);
    memcpy(left, text, n);
    left[n] = '\0';
    int s = cli_parse_double("--search", left, lo, err);
    if (!s) s = cli_parse_double("--search", colon + 1, hi, err);
    if (s) return s;
    if (!(*lo > -1.0 && *hi < 1.0 && *lo < *hi))
        return bkf_error_set(err, BKF_EINPUT, "--search: '%s' is not %s", cli_shown(text, a, sizeof a), form);
    return BKF_OK;
}

/* Everything the user typed, checked, before any computing. */
static int plan_floquet(int argc, char **argv, floquet_plan *plan, bkf_error *err)
{
    struct {
        const char *gamma, *c, *nu, *q, *S, *along, *from, *to, *search, *tol, *cq_max,
            *nu_step, *stepper, *format, *out;
        int threshold, diagram, help;
    } f = {0};
    const cli_flag flags[] = {
        {"--gamma", &f.gamma, "a number in [1e-06, 1e+06]", NULL},
        {"--c", &f.c, "a number >= 0", NULL},
        {"--nu", &f.nu, "a number in (-1, 1)", NULL},
        {"--q", &f.q, "Q or A:B:N, each >= 0", NULL},
        {"--S", &f.S, "a number > 0", NULL},
        {"--threshold", NULL, NULL, &f.threshold},
        {"--diagram", NULL, NULL, &f.diagram},
        {"--along", &f.along, "c or gamma", NULL},
        {"--from", &f.from, "a number", NULL},
        {"--to", &f.to, "a number", NULL},
        {"--search", &f.search, "A:B with -1 < A < B < 1", NULL},
        {"--tol", &f.tol, "a number in [1e-14, 0.1]", NULL},
        {"--cq-max", &f.cq_max, "a number in (0, 1e4]", NULL},
        {"--nu-step", &f.nu_step, "a number in (0, 1]", NULL},
        {"--stepper", &f.stepper, "auto, explicit or implicit", NULL},
        {"--format", &f.format, "tsv or json", NULL},
        {"--out", &f.out, "a file name", NULL},
        {"--help", NULL, NULL, &f.help},
    };
    int s = cli_parse_flags(flags, COUNT(flags), argc, argv, err);
    if (s) return s;
    char a[32];

    if (f.threshold && f.diagram)
        return bkf_error_set(err, BKF_EINPUT, "--threshold and --diagram are separate modes: give one");
    plan->mode = f.diagram ? MODE_DIAGRAM : f.threshold ? (f.along ? MODE_CURVE : MODE_THRESHOLD)
                                                        : MODE_DISPERSION;
    int scanning = plan->mode != MODE_DISPERSION;
    if (!f.threshold && (f.along || f.from || f.to)) {
        const char *which = f.along ? "--along" : f.from ? "--from" : "--to";
        return bkf_error_set(err, BKF_EINPUT, "%s: only with --threshold (the threshold curve)", which);
    }
    if (plan->mode == MODE_CURVE) {
        int k;
        if ((s = cli_parse_choice("--along", f.along, along_names, &k, err))) return s;
        plan->along = k == 0 ? BKF_FLOQUET_ALONG_C : BKF_FLOQUET_ALONG_GAMMA;
        if (!f.from || !f.to)
            return bkf_error_set(err, BKF_EINPUT, "%s is required with --along (%s)",
                                 f.from ? "--to" : "--from", "the curve's ends");
        if (k == 0 && f.c)
            return bkf_error_set(err, BKF_EINPUT,
                                 "--c: not given with --along c (c runs from --from to --to)");
        if (k == 1 && f.gamma)
            return bkf_error_set(err, BKF_EINPUT,
                                 "--gamma: not given with --along gamma (gamma runs from --from to --to)");
        if (k == 0) {
            if ((s = parse_c("--from", f.from, 1, &plan->from, err))) return s;
            if ((s = parse_c("--to", f.to, 1, &plan->to, err))) return s;
        } else {
            if ((s = parse_gamma("--from", f.from, &plan->from, err))) return s;
            if ((s = parse_gamma("--to", f.to, &plan->to, err))) return s;
        }
        if (plan->from == plan->to)
            return bkf_error_set(err, BKF_EINPUT, "--from, --to: the curve needs two different ends");
    } else if (f.from || f.to)
        return bkf_error_set(err, BKF_EINPUT, "%s: only with --along", f.from ? "--from" : "--to");

    int need_gamma = !(plan->mode == MODE_CURVE && plan->along == BKF_FLOQUET_ALONG_GAMMA);
    int need_c = !(plan->mode == MODE_CURVE && plan->along == BKF_FLOQUET_ALONG_C);
    if (need_gamma && !f.gamma)
        return bkf_error_set(err, BKF_EINPUT, "--gamma is required (a number in [%g, %g])",
                             BKF_CYCLE_MU_MIN, BKF_CYCLE_MU_MAX);
    if (need_c && !f.c) return bkf_error_set(err, BKF_EINPUT, "--c is required (a number >= 0)");
    if (f.gamma && (s = parse_gamma("--gamma", f.gamma, &plan->gamma, err))) return s;
    if (f.c && (s = parse_c("--c", f.c, scanning, &plan->c, err))) return s;
    plan->have_gamma = f.gamma != NULL;
    plan->have_c = f.c != NULL;

    if (scanning) {
        if (f.nu)
            return bkf_error_set(err, BKF_EINPUT,
                                 "--nu: not used by --%s, which scans nu (see --search)",
                                 f.diagram ? "diagram" : "threshold");
        if (f.q) return bkf_error_set(err, BKF_EINPUT, "--q: only in the dispersion mode");
        if (f.S) return bkf_error_set(err, BKF_EINPUT, "--S: only in the dispersion mode");
        plan->search_lo = DEFAULT_SEARCH_LO;
        plan->search_hi = DEFAULT_SEARCH_HI;
        if (f.search && (s = parse_search(f.search, &plan->search_lo, &plan->search_hi, err)))
            return s;
    } else {
        if (f.search) return bkf_error_set(err, BKF_EINPUT, "--search: only with --threshold or --diagram");
        if (f.cq_max || f.nu_step)
            return bkf_error_set(err, BKF_EINPUT, "%s: only with --threshold or --diagram",
                                 f.cq_max ? "--cq-max" : "--nu-step");
        if (!f.nu) return bkf_error_set(err, BKF_EINPUT, "--nu is required (a number in (-1, 1))");
        if (!f.q) return bkf_error_set(err, BKF_EINPUT, "--q is required (Q or A:B:N, each >= 0)");
        if ((s = cli_parse_double("--nu", f.nu, &plan->nu, err))) return s;
        bkf_error e;
        if (bkf_model_check_nu_active(plan->nu, &e) != BKF_OK)
            return bkf_error_set(err, BKF_EINPUT, "--nu: %s", e.message);
        if (f.S) {
            if ((s = cli_parse_double("--S", f.S, &plan->S, err))) return s;
            if (!(plan->S > 0))
                return bkf_error_set(err, BKF_EINPUT, "--S: S = %s must be > 0",
                                     num(plan->S, a, sizeof a));
            plan->have_S = 1;
        }
        if ((s = cli_parse_range("--q", f.q, 0, &plan->q, err))) return s;
        for (size_t i = 0; i < plan->q.count && !s; i++) {
            if (!(plan->q.values[i] >= 0))
                s = bkf_error_set(err, BKF_EINPUT, "--q: q = %s must be >= 0",
                                  num(plan->q.values[i], a, sizeof a));
            else if (plan->c * plan->q.values[i] > 1e4)
                s = bkf_error_set(err, BKF_EINPUT, "--q: c q = %s is above 1e4",
                                  num(plan->c * plan->q.values[i], a, sizeof a));
        }
        if (s) return s;
    }

    plan->options = bkf_floquet_options_default();
    if (f.tol) {
        if ((s = cli_parse_double("--tol", f.tol, &plan->options.tol, err))) return s;
        bkf_error e;
        if (bkf_model_check_tol(plan->options.tol, &e) != BKF_OK)
            return bkf_error_set(err, BKF_EINPUT, "--tol: %s", e.message);
    }
    if (f.cq_max) {
        if ((s = cli_parse_double("--cq-max", f.cq_max, &plan->options.p_max, err))) return s;
        if (!(plan->options.p_max > 0 && plan->options.p_max <= 1e4))
            return bkf_error_set(err, BKF_EINPUT, "--cq-max: %s is outside (0, 1e4]",
                                 num(plan->options.p_max, a, sizeof a));
    }
    if (f.nu_step) {
        if ((s = cli_parse_double("--nu-step", f.nu_step, &plan->options.nu_step, err))) return s;
        if (!(plan->options.nu_step > 0 && plan->options.nu_step <= 1))
            return bkf_error_set(err, BKF_EINPUT, "--nu-step: %s is outside (0, 1]",
                                 num(plan->options.nu_step, a, sizeof a));
    }
    if (f.stepper) {
        int k;
        if ((s = cli_parse_choice("--stepper", f.stepper, stepper_names, &k, err))) return s;
        plan->options.stepper = stepper_kinds[k];
    }
    plan->format = BKF_IO_TSV;
    if (f.format) {
        int k;
        if ((s = cli_parse_choice("--format", f.format, format_names, &k, err))) return s;
        plan->format = k == 1 ? BKF_IO_JSON : BKF_IO_TSV;
    }
    if (f.out && !*f.out) return bkf_error_set(err, BKF_EINPUT, "--out: the file name is empty");
    plan->out_path = f.out;
    return BKF_OK;
}

static int write_oscillation(const void *spec, const bkf_product_output *out, bkf_error *err)
{
    return bkf_oscillation_write(spec, out, err);
}

static int floquet_run(int argc, char **argv, bkf_error *err)
{
    floquet_plan plan;
    memset(&plan, 0, sizeof plan);
    int s = plan_floquet(argc, argv, &plan, err);
    if (!s) {
        static const bkf_oscillation_mode modes[] = {
            BKF_OSCILLATION_DISPERSION, BKF_OSCILLATION_THRESHOLD, BKF_OSCILLATION_CURVE,
            BKF_OSCILLATION_DIAGRAM};
        bkf_oscillation_spec spec = bkf_oscillation_spec_default();
        spec.mode = modes[plan.mode];
        spec.gamma = plan.gamma;
        spec.c = plan.c;
        spec.nu = plan.nu;
        spec.q = plan.q.values;
        spec.nq = plan.q.count;
        spec.S = plan.have_S ? plan.S : 0;
        spec.along = (bkf_floquet_param)plan.along;
        spec.from = plan.from;
        spec.to = plan.to;
        spec.search_lo = plan.search_lo;
        spec.search_hi = plan.search_hi;
        spec.options = plan.options;
        s = cli_write_product(plan.out_path, plan.format, write_oscillation, &spec, argc, argv,
                              err);
    }
    plan_free(&plan);
    return s;
}

const cli_command cli_cmd_floquet = {
    "floquet",
    "Floquet stability of global oscillations: dispersion, thresholds, diagram",
    floquet_run,
    floquet_help,
};

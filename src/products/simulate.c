/* The simulation product (simulate.h). */
#define _POSIX_C_SOURCE 200809L
#include "bkfront/simulate.h"

#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

#include "bkfront/chainwave.h"
#include "bkfront/check.h"
#include "bkfront/speeds.h"
#include "bkfront/h5.h"
#include "bkfront/init.h"
#include "bkfront/measure.h"
#include "bkfront/seed.h"
#include "product_internal.h"

#define PI 3.14159265358979323846

static const char *const model_names[] = {"continuum", "chain", NULL};
/* bkf_pde_stepper_names, then "auto" (BKF_SIMULATE_STEPPER_AUTO) */
static const char *const stepper_names[] = {"rk8pd", "rkck", "rkf45", "etdrk4", "lawson8", "auto", NULL};
_Static_assert(BKF_PDE_LAWSON8 + 1 == BKF_SIMULATE_STEPPER_AUTO, "auto follows the steppers");
static const char *const spacetime_names[] = {"text", "binary", "hdf5", NULL};
enum { SPACETIME_TEXT, SPACETIME_BINARY, SPACETIME_HDF5 };

/* The initial state's grammar is checked as the key is given (init.h
 * words its messages for the flag: "--init ..."; the key's name is put in
 * front by the option table). */
static int set_init(void *spec, const char *text, bkf_error *err)
{
    bkf_init_spec init;
    memset(&init, 0, sizeof init);
    int s = bkf_init_parse(text, &init, err);
    bkf_init_free(&init);
    if (s) {
        const char *m = err ? err->message : "";
        if (strncmp(m, "--init", 6) == 0) {
            m += 6;
            if (*m == ':') m++;
            while (*m == ' ') m++;
            char rest[BKF_ERROR_LEN];
            snprintf(rest, sizeof rest, "%s", m);
            return bkf_error_set(err, s, "%s", rest);
        }
        return s;
    }
    ((bkf_simulate_spec *)spec)->init = text;
    return BKF_OK;
}

/* A comma list of psi and eta, each at most once. */
static int set_fields(void *spec, const char *text, bkf_error *err)
{
    unsigned fields = 0;
    const char *p = text;
    for (;;) {
        size_t n = strcspn(p, ",");
        unsigned f = n == 3 && strncmp(p, "psi", 3) == 0   ? BKF_SIMULATE_PSI
                     : n == 3 && strncmp(p, "eta", 3) == 0 ? BKF_SIMULATE_ETA
                                                           : 0;
        if (!f || (fields & f))
            return bkf_error_set(err, BKF_EINPUT, "'%s' is not a list of psi and eta, each at "
                                 "most once (psi, eta, psi,eta)", text);
        fields |= f;
        if (!p[n]) break;
        p += n + 1;
    }
    ((bkf_simulate_spec *)spec)->spacetime_fields = fields;
    return BKF_OK;
}

/* The spacetime file's format: given, or by the name's extension. */
static int spacetime_kind(const bkf_simulate_spec *sp)
{
    if (sp->spacetime_format >= 0) return sp->spacetime_format;
    const char *dot = sp->spacetime ? strrchr(sp->spacetime, '.') : NULL;
    static const char *const ext[] = {".h5", ".hdf5", ".he5"};
    for (size_t i = 0; dot && i < sizeof ext / sizeof ext[0]; i++)
        if (strcmp(dot, ext[i]) == 0) return SPACETIME_HDF5;
    return SPACETIME_TEXT;
}

#define SPEC(field) offsetof(bkf_simulate_spec, field)
#define MODEL(field) (offsetof(bkf_simulate_spec, model) + offsetof(bkf_model_params, field))
#define BOUNDED (BKF_OPT_MIN | BKF_OPT_MAX)

const bkf_option bkf_simulate_options[] = {
    {.name = "gamma", .type = BKF_OPT_DOUBLE, .offset = MODEL(gamma),
     .flags = BKF_OPT_MIN | BKF_OPT_MIN_OPEN, .min = 0, .form = "G", .shown_default = "2",
     .help = "friction strength, > 0"},
    {.name = "c", .type = BKF_OPT_DOUBLE, .offset = MODEL(c), .flags = BKF_OPT_MIN | BKF_OPT_MAX,
     .min = 0, .max = BKF_MODEL_C_MAX, .form = "C", .shown_default = "0.3",
     .help = "sound speed, in [0, 1e6]"},
    {.name = "nu", .type = BKF_OPT_DOUBLE, .offset = MODEL(nu), .flags = BOUNDED,
     .min = -BKF_PDE_NU_MAX, .max = BKF_PDE_NU_MAX, .form = "V", .shown_default = "-0.96",
     .help = "pulling rate, in [-100, 100] (|nu| >= 1: continuous slip\n"
             "is stable; oscillation and front need |nu| < 1)"},
    {.name = "S", .type = BKF_OPT_DOUBLE, .offset = MODEL(S),
     .flags = BKF_OPT_MIN | BKF_OPT_MIN_OPEN, .min = 0, .form = "S", .shown_default = "20",
     .help = "domain size, > 0"},
    {.name = "N", .type = BKF_OPT_COUNT, .offset = MODEL(N), .flags = BOUNDED,
     .min = BKF_PDE_N_MIN, .max = BKF_PDE_N_MAX, .form = "N",
     .shown_default = "512, or S blocks for --model chain",
     .help = "grid points, in [8, 1048576]; even for the continuum (a\npower of two is not required)"},
    {.name = "tmax", .type = BKF_OPT_DOUBLE, .offset = SPEC(tmax),
     .flags = BOUNDED | BKF_OPT_MIN_OPEN, .min = 0, .max = BKF_SIMULATE_TMAX_MAX, .form = "T",
     .shown_default = "125", .help = "final time, in (0, 1e6]"},
    {.name = "tol", .type = BKF_OPT_DOUBLE, .offset = SPEC(tol), .flags = BOUNDED,
     .min = BKF_PDE_TOL_MIN, .max = BKF_PDE_TOL_MAX, .form = "E", .shown_default = "1e-9",
     .help = "local error tolerance of the stepper (absolute and\nrelative), in [1e-13, 0.01]"},
    {.name = "init", .type = BKF_OPT_CUSTOM, .set = set_init, .form = "SPEC",
     .shown_default = "uniform",
     .help = "initial state:\n"
             "uniform[:amp=A]  psi = nu + band-limited noise of rms A\n"
             "  (default 1e-3, modes 1..S/2), eta = phi(psi)\n"
             "oscillation[:q=Q|j=J][,amp=A][,noise=E]  the global\n"
             "  oscillation (cycle at mu = gamma) at psi = nu rising, plus\n"
             "  A cos(q x) and noise of rms E (as uniform's); q is rounded\n"
             "  to the nearest 2 pi j/S; default j = 0, A = 0, E = 0\n"
             "front:n=K[,root=R][,dir=left|right][,noise=E]  the\n"
             "  travelling wave of K fronts at the predicted speed (root R,\n"
             "  default 1, the fastest), moving left (-x, default) or\n"
             "  right, plus noise of rms E\n"
             "file:PATH  a TSV naming the columns psi and eta (N rows;\n"
             "  with a t column, the rows of the last t): --snapshots output"},
    {.name = "seed", .type = BKF_OPT_SEED, .offset = SPEC(seed), .form = "K",
     .shown_default = "1", .help = "seed of the noise"},
    {.name = "model", .type = BKF_OPT_CHOICE, .offset = SPEC(chain), .choices = model_names,
     .form = "M", .shown_default = "continuum",
     .help = "continuum (pseudo-spectral, FFTW) or chain (Burridge-Knopoff\n"
             "blocks, finite differences, h = S/N)"},
    {.name = "stepper", .type = BKF_OPT_CHOICE, .offset = SPEC(stepper), .choices = stepper_names,
     .form = "S", .shown_default = "auto",
     .help = "rk8pd, rkck, rkf45: GSL embedded Runge-Kutta pairs;\n"
             "etdrk4: exponential Runge-Kutta (continuum only; the wave\n"
             "part exact, no step cap from N; energy_residual and\n"
             "mean_residual are nan with it); lawson8: the same with\n"
             "rk8pd's order 8 and both residuals (integrating factor: long\n"
             "steps at tight tol); auto: lawson8 for the continuum from\n"
             "N 4096 without --dealias, else rk8pd (the header names the\n"
             "one used)"},
    {.name = "dealias", .type = BKF_OPT_SWITCH, .offset = SPEC(dealias),
     .help = "continuum only: 2/3-rule projection of the right-hand side"},
    {.name = "filter", .type = BKF_OPT_DOUBLE, .offset = SPEC(filter), .flags = BOUNDED, .min = 0,
     .max = 1000, .form = "F", .shown_default = "4",
     .help = "continuum only: rate F of the spectral filter at the\n"
             "highest mode, F (k/k_top)^16 (it stops a grid instability of\n"
             "the modes near the Nyquist wavenumber; 0 turns it off),\nin [0, 1000]"},
    {.name = "level", .type = BKF_OPT_DOUBLE, .offset = SPEC(level), .form = "L",
     .shown_default = "the middle of the global oscillation's range (nu if |nu| >= 1)",
     .help = "fronts are crossings of psi = L with psi_t > 0"},
    {.name = "frames", .type = BKF_OPT_COUNT, .offset = SPEC(frames), .flags = BOUNDED, .min = 1,
     .max = BKF_SIMULATE_FRAMES_MAX, .form = "F", .shown_default = "500",
     .help = "rows of the diagnostics and the spacetime field, evenly\n"
             "spaced over [0, tmax] (F + 1 rows with t = 0), in [1, 1e6]"},
    {.name = "spacetime", .type = BKF_OPT_TEXT, .offset = SPEC(spacetime), .form = "FILE",
     .flags = BKF_OPT_RUN_FILE | BKF_OPT_PATH,
     .help = "psi(x, t) at the frames for gnuplot: text is the nonuniform\n"
             "matrix format (first row N x_0 .. x_{N-1}, then t psi ...;\n"
             "plot 'FILE' nonuniform matrix with image), binary the same\n"
             "numbers as float32 (plot 'FILE' binary matrix with image),\n"
             "hdf5 datasets psi[t, x] (float32) with t and x as dimension\n"
             "scales and the parameters as attributes (h5py, xarray)"},
    {.name = "spacetime-format", .type = BKF_OPT_CHOICE, .offset = SPEC(spacetime_format),
     .choices = spacetime_names, .form = "text|binary|hdf5", .flags = BKF_OPT_RUN_FILE,
     .shown_default = "hdf5 for FILE.h5, .hdf5, .he5, else text",
     .help = "the spacetime file's format"},
    {.name = "spacetime-fields", .type = BKF_OPT_CUSTOM, .set = set_fields, .form = "LIST",
     .flags = BKF_OPT_RUN_FILE,
     .shown_default = "psi",
     .help = "the fields of the spacetime file: psi, eta or psi,eta\n(eta only in hdf5)"},
    {.name = "spacetime-deflate", .type = BKF_OPT_COUNT, .offset = SPEC(spacetime_deflate),
     .flags = BOUNDED | BKF_OPT_RUN_FILE, .min = 1, .max = BKF_H5_DEFLATE_MAX, .form = "L",
     .shown_default = "none",
     .help = "hdf5 only: gzip level of the fields' chunks, in [1, 9]"},
    {.name = "snapshots", .type = BKF_OPT_TEXT, .offset = SPEC(snapshots), .form = "FILE",
     .flags = BKF_OPT_RUN_FILE | BKF_OPT_PATH,
     .help = "TSV with columns t, x, psi, eta at K frames spread over\nthe run"},
    {.name = "snapshot-count", .type = BKF_OPT_COUNT, .offset = SPEC(snapshot_count),
     .flags = BOUNDED | BKF_OPT_RUN_FILE, .min = 1, .max = BKF_SIMULATE_SNAPSHOTS_MAX, .form = "K",
     .shown_default = "2", .help = "snapshots (the last at tmax), in [1, 1e5]"},
};
const size_t bkf_simulate_noptions = sizeof bkf_simulate_options / sizeof bkf_simulate_options[0];

bkf_simulate_spec bkf_simulate_spec_default(void)
{
    bkf_simulate_spec s;
    memset(&s, 0, sizeof s);
    s.model = bkf_model_params_paper();
    s.model.N = 0;
    s.tol = 1e-9;
    s.filter = bkf_pde_options_default().filter;
    s.tmax = 125;
    s.stepper = BKF_SIMULATE_STEPPER_AUTO;
    s.seed = 1;
    s.level = NAN;
    s.frames = 500;
    s.spacetime_format = -1;
    return s;
}

/* The model and the stepper's options the spec means, and its initial
 * state parsed, read and checked against them.  `init` is freed by the
 * caller (bkf_init_free) whatever the result. */
static int resolve(const bkf_simulate_spec *sp, const char *prefix, bkf_model_params *model,
                   bkf_pde_options *options, bkf_init_spec *init, bkf_error *err)
{
    char a[32];
    *model = sp->model;
    model->kind = sp->chain ? BKF_MODEL_CHAIN : BKF_MODEL_CONTINUUM;
    *options = bkf_pde_options_default();
    options->tol = sp->tol;
    options->stepper = (bkf_pde_stepper)sp->stepper;
    options->dealias = sp->dealias;
    options->filter = sp->filter;
    options->cancel = sp->cancel;
    int N_given = sp->model.N != 0;
    if (N_given && model->kind == BKF_MODEL_CONTINUUM && model->N % 2)
        return bkf_error_set(err, BKF_EINPUT,
                             "%sN: %zu must be even for the continuum model (spectral)", prefix,
                             model->N);
    if (!N_given && model->kind == BKF_MODEL_CHAIN) {
        /* The physical chain: one block per unit length. */
        double S = model->S;
        if (S != floor(S) || S < BKF_PDE_N_MIN || S > BKF_PDE_N_MAX)
            return bkf_error_set(err, BKF_EINPUT,
                                 "%smodel chain: give %sN (the number of blocks); the default "
                                 "N = S needs an integer S in [%d, %d], S = %s",
                                 prefix, prefix, BKF_PDE_N_MIN, BKF_PDE_N_MAX,
                                 bkf_format_number(S, a, sizeof a));
        model->N = (size_t)S;
    } else if (!N_given) {
        model->N = BKF_SIMULATE_N_DEFAULT;
    }
    if (sp->stepper == BKF_SIMULATE_STEPPER_AUTO)
        options->stepper = bkf_pde_stepper_auto(model, sp->dealias);
    if (sp->dealias && model->kind != BKF_MODEL_CONTINUUM)
        return bkf_error_set(err, BKF_EINPUT, "%sdealias: only for %smodel continuum", prefix,
                             prefix);
    bkf_error e;
    if (bkf_pde_check(model, options, &e)) return bkf_error_set(err, BKF_EINPUT, "%s", e.message);
    int s = bkf_init_parse(sp->init ? sp->init : "uniform", init, err);
    if (s) return s;
    init->seed = (unsigned long)sp->seed;
    /* a state file that cannot be read is the user's input, as a bad path */
    if ((s = bkf_init_load(init, err))) return s == BKF_EIO ? BKF_EINPUT : s;
    return bkf_init_check(init, model, N_given, options, err);
}

int bkf_simulate_check(const bkf_simulate_spec *sp, const char *prefix, bkf_error *err)
{
    if (!sp) return bkf_error_set(err, BKF_EINPUT, "no simulation spec given");
    if (!prefix) prefix = "";
    bkf_model_params model;
    bkf_pde_options options;
    bkf_init_spec init;
    memset(&init, 0, sizeof init);
    int s = resolve(sp, prefix, &model, &options, &init, err);
    bkf_init_free(&init);
    if (s) return s;
    size_t snapshots = sp->snapshot_count ? sp->snapshot_count : 2;
    if (snapshots > sp->frames + 1)
        return bkf_error_set(err, BKF_EINPUT, "%ssnapshot-count: %zu is more than the %zu frames",
                             prefix, snapshots, sp->frames + 1);
    const char *needs_file = sp->spacetime_format >= 0 ? "spacetime-format"
                             : sp->spacetime_fields     ? "spacetime-fields"
                             : sp->spacetime_deflate    ? "spacetime-deflate"
                                                        : NULL;
    if (needs_file && !sp->spacetime)
        return bkf_error_set(err, BKF_EINPUT, "%s%s: give %sspacetime FILE too", prefix,
                             needs_file, prefix);
    int kind = spacetime_kind(sp);
    if (kind != SPACETIME_HDF5 && (sp->spacetime_fields & BKF_SIMULATE_ETA))
        return bkf_error_set(err, BKF_EINPUT, "%sspacetime-fields: eta is written only in the "
                             "hdf5 format (%sspacetime FILE.h5 or %sspacetime-format hdf5)",
                             prefix, prefix, prefix);
    if (kind != SPACETIME_HDF5 && sp->spacetime_deflate)
        return bkf_error_set(err, BKF_EINPUT, "%sspacetime-deflate: only for the hdf5 format",
                             prefix);

    if (sp->snapshot_count && !sp->snapshots)
        return bkf_error_set(err, BKF_EINPUT, "%ssnapshot-count: give %ssnapshots FILE too",
                             prefix, prefix);
    /* the files must be writable before any work */
    const char *paths[2] = {sp->spacetime, sp->snapshots}, *keys[2] = {"spacetime", "snapshots"};
    for (int i = 0; i < 2; i++) {
        if (!paths[i]) continue;
        bkf_error e;
        bkf_io_atomic *f = bkf_io_atomic_open(paths[i], &e);
        if (!f) return bkf_error_set(err, BKF_EINPUT, "%s%s: %s", prefix, keys[i], e.message);
        bkf_io_atomic_abort(f);
    }
    if (sp->spacetime) {
        /* hdf5: 4 bytes a value of each field, 8 for each t (and x) */
        int text = kind == SPACETIME_TEXT;
        double fields = sp->spacetime_fields == (BKF_SIMULATE_PSI | BKF_SIMULATE_ETA) ? 2 : 1;
        double bytes = kind == SPACETIME_HDF5
                           ? (double)(sp->frames + 1) * ((double)model.N * 4 * fields + 8) +
                                 8.0 * (double)model.N
                           : (double)(sp->frames + 1) *
                                 ((double)model.N * (text ? 16 : 4) + (text ? 26 : 4));
        if (bytes > BKF_SIMULATE_SPACETIME_BYTES_MAX)
            return bkf_error_set(err, BKF_EINPUT,
                                 "%sframes: %zu frames of %zu points make a %s spacetime file of "
                                 "up to %.3g bytes, more than its limit of 1 GiB (%s)",
                                 prefix, sp->frames + 1, model.N, spacetime_names[kind], bytes,
                                 text ? "binary and hdf5 take 4 bytes a value, text 16"
                                      : "fewer frames or points");
    }
    return BKF_OK;
}

/* ------------------------------------------------------------ the run */

static const bkf_io_column columns[] = {
    {"t", BKF_IO_NUMBER},        {"mean", BKF_IO_NUMBER},
    {"variance", BKF_IO_NUMBER}, {"min", BKF_IO_NUMBER},
    {"max", BKF_IO_NUMBER},      {"probe", BKF_IO_NUMBER},
    {"fronts", BKF_IO_NUMBER},   {"displacement", BKF_IO_NUMBER},
    {"deviation", BKF_IO_NUMBER}, {"energy", BKF_IO_NUMBER},
    {"energy_residual", BKF_IO_NUMBER}, {"mean_residual", BKF_IO_NUMBER},
};
#define NCOLUMNS (sizeof columns / sizeof columns[0])

typedef struct {
    const bkf_simulate_spec *spec;
    bkf_model_params model;
    bkf_pde_options options;
    bkf_init_spec init;
    size_t snapshots;
    double level;
    const bkf_provenance *prov;
    bkf_pde *pde;
    bkf_measure *meas;
    size_t per_frame, sample_index, frame_index;
    /* frame rows, kept until the end */
    double *diag;        /* per frame: NCOLUMNS values */
    float *field;        /* per frame: psi at N points (spacetime) */
    float *field_eta;    /* per frame: eta at N points (spacetime-fields eta) */
    double *snap;        /* per snapshot: t, psi[N], eta[N] */
    size_t *snap_frame;  /* frame index of each snapshot */
    size_t snap_next;
    int status;
    bkf_error err;
    bkf_simulate_outcome *outcome; /* set: the run's summary, no table */
} run;

static int observe(const bkf_pde_sample *smp, void *data)
{
    run *r = data;
    size_t N = r->model.N;
    bkf_error e;
    if (bkf_measure_add(r->meas, smp->t, smp->psi, smp->eta, &e)) {
        r->status = bkf_error_set(&r->err, BKF_ENUMERIC, "measurement at t = %g: %s", smp->t,
                                  e.message);
        return 1;
    }
    size_t k = r->sample_index++;
    if (k % r->per_frame != 0 || r->frame_index > r->spec->frames) return 0;
    size_t f = r->frame_index++;
    const bkf_measure_record *rc = bkf_measure_record_at(r->meas, bkf_measure_count(r->meas) - 1);
    double *row = r->diag + f * NCOLUMNS;
    row[0] = smp->t;
    row[1] = rc->mean;
    row[2] = rc->variance;
    row[3] = rc->min;
    row[4] = rc->max;
    row[5] = rc->probe;
    row[6] = (double)rc->fronts;
    row[7] = rc->displacement;
    row[8] = rc->deviation;
    row[9] = bkf_pde_energy_of(r->pde, smp->psi, smp->eta);
    row[10] = bkf_pde_sample_energy_residual(r->pde, smp);
    row[11] = bkf_pde_sample_mean_residual(r->pde, smp);
    if (r->field)
        for (size_t i = 0; i < N; i++) r->field[f * N + i] = (float)smp->psi[i];
    if (r->field_eta)
        for (size_t i = 0; i < N; i++) r->field_eta[f * N + i] = (float)smp->eta[i];
    if (r->snap && r->snap_next < r->snapshots && r->snap_frame[r->snap_next] == f) {
        double *s = r->snap + r->snap_next * (2 * N + 1);
        s[0] = smp->t;
        memcpy(s + 1, smp->psi, N * sizeof *s);
        memcpy(s + 1 + N, smp->eta, N * sizeof *s);
        r->snap_next++;
    }
    return 0;
}


#define NUM(x, buf) bkf_format_number((x), buf, sizeof buf)

static int comment_model(bkf_io_table *t, const run *r, bkf_error *err)
{
    char a[32], b[32], c[32], d[32], e[32], f[32], g[32];
    const bkf_model_params *m = &r->model;
    return bkf_io_table_commentf(t, err,
                    "model %s: gamma %s, c %s, nu %s, S %s, N %zu (h = %s); tol %s, stepper %s, "
                    "dealias %s, filter %s",
                    model_names[m->kind], NUM(m->gamma, a), NUM(m->c, b), NUM(m->nu, c),
                    NUM(m->S, d), m->N, NUM(m->S / (double)m->N, e), NUM(r->options.tol, f),
                    stepper_names[r->options.stepper],
                    r->options.dealias ? "on (2/3 rule)" : "off",
                    m->kind == BKF_MODEL_CHAIN || r->options.filter == 0
                        ? "off"
                        : NUM(r->options.filter, g));
}

static const char *program(const run *r)
{
    return r->prov && r->prov->program ? r->prov->program : "libbkfront";
}

/* `note`, if not NULL, becomes a comment line (text format only). */
static int write_spacetime(const run *r, size_t frames, const char *note, FILE *out,
                           bkf_error *err)
{
    size_t N = r->model.N;
    double h = r->model.S / (double)N;
    int bad = 0;
    if (spacetime_kind(r->spec) == SPACETIME_BINARY) {
        float *row = malloc((N + 1) * sizeof *row);
        if (!row) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
        row[0] = (float)N;
        for (size_t i = 0; i < N; i++) row[i + 1] = (float)((double)i * h);
        bad = fwrite(row, sizeof *row, N + 1, out) != N + 1;
        for (size_t f = 0; f < frames && !bad; f++) {
            row[0] = (float)r->diag[f * NCOLUMNS];
            memcpy(row + 1, r->field + f * N, N * sizeof *row);
            bad = fwrite(row, sizeof *row, N + 1, out) != N + 1;
        }
        free(row);
    } else {
        bad |= fprintf(out, "# %s simulate: psi(x, t), gnuplot nonuniform matrix: first row N "
                            "x_0 .. x_{N-1}, then one row per t: t psi(x_0) .. psi(x_{N-1})\n"
                            "# plot 'FILE' nonuniform matrix using 1:2:3 with image\n",
                       program(r)) < 0;
        if (note) bad |= fprintf(out, "# %s\n", note) < 0;
        bad |= fprintf(out, "%zu", N) < 0;
        for (size_t i = 0; i < N && !bad; i++) bad |= fprintf(out, " %.9g", (double)i * h) < 0;
        bad |= fputc('\n', out) == EOF;
        for (size_t f = 0; f < frames && !bad; f++) {
            bad |= fprintf(out, "%.17g", r->diag[f * NCOLUMNS]) < 0;
            for (size_t i = 0; i < N && !bad; i++)
                bad |= fprintf(out, " %.9g", (double)r->field[f * N + i]) < 0;
            bad |= fputc('\n', out) == EOF;
        }
    }
    if (bad) return bkf_error_set(err, BKF_EIO, "writing the spacetime field failed");
    return BKF_OK;
}

/* The same field as HDF5 (h5.h): psi and/or eta over the dimension scales
 * t and x, and every parameter of the run as an attribute of the root. */
static int write_spacetime_h5(const run *r, size_t frames, const char *note,
                              bkf_io_atomic *file, bkf_error *err)
{
    const bkf_simulate_spec *sp = r->spec;
    const bkf_model_params *m = &r->model;
    size_t N = m->N;
    double h = m->S / (double)N;
    double *t = malloc((frames ? frames : 1) * sizeof *t), *x = malloc(N * sizeof *x);
    if (!t || !x) {
        free(t);
        free(x);
        return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    }
    for (size_t f = 0; f < frames; f++) t[f] = r->diag[f * NCOLUMNS];
    for (size_t i = 0; i < N; i++) x[i] = (double)i * h;
    bkf_h5_field fields[2];
    size_t nfields = 0;
    if (r->field) fields[nfields++] = (bkf_h5_field){"psi", r->field, "psi(t, x)"};
    if (r->field_eta) fields[nfields++] = (bkf_h5_field){"eta", r->field_eta, "eta(t, x)"};
#define D(n, v) {.name = n, .kind = BKF_H5_DOUBLE, .number = (v)}
#define I(n, v) {.name = n, .kind = BKF_H5_INT, .integer = (long long)(v)}
#define T(n, v) {.name = n, .kind = BKF_H5_TEXT, .text = (v)}
    const bkf_h5_attribute attrs[] = {
        T("title", "psi(t, x) of a direct simulation of the elastic excitable medium"),
        T("program", program(r)),
        T("command", r->prov && r->prov->command ? r->prov->command : ""),
        T("model", model_names[m->kind]),
        D("gamma", m->gamma), D("c", m->c), D("nu", m->nu), D("S", m->S), I("N", N),
        D("h", h), D("tol", r->options.tol), T("stepper", stepper_names[r->options.stepper]),
        I("dealias", r->options.dealias),
        D("filter", m->kind == BKF_MODEL_CHAIN ? 0 : r->options.filter),
        D("tmax", sp->tmax), I("frames", sp->frames), T("init", sp->init ? sp->init : "uniform"),
        I("seed", sp->seed), D("level", r->level),
        T("interrupted", note ? note : ""),
    };
#undef D
#undef I
#undef T
    bkf_h5_grid g = {
        .rows = {"t", t, frames, "time"},
        .columns = {"x", x, N, "position"},
        .fields = fields,
        .nfields = nfields,
        .attributes = attrs,
        /* an uninterrupted run has no "interrupted" attribute */
        .nattributes = sizeof attrs / sizeof attrs[0] - (note ? 0 : 1),
        .deflate = (unsigned)sp->spacetime_deflate,
    };
    bkf_error e;
    int s = bkf_h5_write(file, &g, &e);
    if (s) bkf_error_set(err, s, "spacetime: %s", e.message);
    free(t);
    free(x);
    return s;
}

/* The spacetime file in its format. */
static int write_spacetime_file(const run *r, const char *note, bkf_io_atomic *file,
                                bkf_error *err)
{
    if (spacetime_kind(r->spec) == SPACETIME_HDF5)
        return write_spacetime_h5(r, r->frame_index, note, file, err);
    return write_spacetime(r, r->frame_index, note, bkf_io_atomic_stream(file), err);
}

static int write_snapshots(const run *r, const char *note, FILE *out, bkf_error *err)
{
    static const bkf_io_column cols[] = {
        {"t", BKF_IO_NUMBER}, {"x", BKF_IO_NUMBER}, {"psi", BKF_IO_NUMBER}, {"eta", BKF_IO_NUMBER}};
    size_t N = r->model.N;
    double h = r->model.S / (double)N;
    bkf_io_table *t = bkf_io_table_alloc(out, BKF_IO_TSV, cols, 4, err);
    if (!t) return BKF_ENOMEM;
    int s = bkf_io_table_commentf(t, err, "%s simulate: snapshots of the field; readable by --init "
                             "file:PATH (the last t)", program(r));
    if (!s && note) s = bkf_io_table_comment(t, note, err);
    if (!s && note)
        s = bkf_io_table_comment(t, "the last snapshot is the state where the run stopped: "
                                    "--init file:PATH continues from it", err);
    if (!s) s = comment_model(t, r, err);
    for (size_t k = 0; !s && k < r->snap_next; k++) {
        const double *sn = r->snap + k * (2 * N + 1);
        for (size_t i = 0; !s && i < N; i++) {
            bkf_io_value v[4] = {{.number = sn[0]}, {.number = (double)i * h},
                                 {.number = sn[1 + i]}, {.number = sn[1 + N + i]}};
            s = bkf_io_table_row(t, v, err);
        }
    }
    if (!s) s = bkf_io_table_finish(t, err);
    bkf_io_table_free(t);
    return s;
}

/* The summary: comments for people, "results" fields for programs; a
 * measurement that does not exist says so instead of printing nan. */
static int write_summary(bkf_io_table *t, const run *r, const bkf_measure_summary *ms,
                         const bkf_pde_front_info *fi, double period_ref, bkf_error *err)
{
    char a[32], b[32], c[32], d[32], e[32];
    const bkf_simulate_spec *sp = r->spec;
    const bkf_init_spec *in = &r->init;
    int front = in->kind == BKF_INIT_FRONT;
    int s = comment_model(t, r, err);
    if (!s) s = bkf_io_table_commentf(t, err, "init %s, seed %lu; tmax %s, %zu frames",
                         sp->init ? sp->init : "uniform", (unsigned long)sp->seed, NUM(sp->tmax, a),
                         sp->frames);
    if (!s && front)
        s = bkf_io_table_commentf(t, err,
                     "front%s: n %zu, root %zu of %zu, v_pred %s (err %.2g), mu %s, T %s, period at "
                     "a point %s, direction %s",
                     r->model.kind == BKF_MODEL_CHAIN ? " (the chain's own rotating wave)" : "",
                     in->front.n, in->front.root, fi->roots_for_n, NUM(fi->v, a), fi->v_err,
                     NUM(fi->mu, b), NUM(fi->T, c), NUM(fi->period_fixed, d),
                     in->front.direction < 0 ? "-x (left)" : "+x (right)");
    if (!s && in->kind == BKF_INIT_OSCILLATION)
        s = bkf_io_table_commentf(t, err, "oscillation: mode j %zu, q %s, amp %s%s%s", in->j,
                     NUM(2 * PI * (double)in->j / r->model.S, a), NUM(in->amp, b),
                     in->noise > 0 ? ", noise " : "", in->noise > 0 ? NUM(in->noise, c) : "");
    if (!s) s = bkf_product_table_command(t, r->prov, err);
    const bkf_pde_stats *st = bkf_pde_get_stats(r->pde);
    if (!s)
        s = bkf_io_table_commentf(t, err, "work: %zu steps, %zu rejected, %zu rhs calls, step %s .. %s",
                     st->steps, st->rejected, st->rhs_calls, NUM(st->h_min, a), NUM(st->h_max, b));
    if (!s) s = bkf_io_table_commentf(t, err, "regime: %s (window t >= %s)", bkf_regime_name(ms->regime),
                         NUM(ms->window_start, a));
    if (!s)
        s = bkf_io_table_commentf(t, err, "fronts are crossings of psi = %s with psi_t > 0 (hysteresis 0.1)",
                     NUM(r->level, a));
    if (!s)
        s = bkf_io_table_commentf(t, err, "fronts: %zu at start, %zu at end, %zu .. %zu in the window",
                     ms->fronts_start, ms->fronts_end, ms->fronts_min, ms->fronts_max);
    if (!s && isfinite(ms->speed))
        s = bkf_io_table_commentf(t, err,
                     "speed: %s +- %.3g (fitted from t = %s; %zu tracks, %zu towards -x, %zu "
                     "towards +x; negative: towards -x)",
                     NUM(ms->speed, a), ms->speed_err, NUM(ms->fit_start, b), ms->tracks,
                     ms->moving_minus, ms->moving_plus);
    if (!s && front && isfinite(ms->speed))
        s = bkf_io_table_commentf(t, err, "speed vs prediction: |v| %s, v_pred %s, relative difference %.3g",
                     NUM(fabs(ms->speed), a), NUM(fi->v, b), (fabs(ms->speed) - fi->v) / fi->v);
    if (!s && isfinite(ms->period))
        s = bkf_io_table_commentf(t, err, "period at x = 0: %s +- %.3g (multiplicity %zu, %zu crossings in "
                             "the window); global oscillation period %s",
                     NUM(ms->period, a), ms->period_err, ms->period_multiplicity, ms->crossings,
                     period_ref > 0 ? NUM(period_ref, b) : "n/a");
    else if (!s)
        s = bkf_io_table_commentf(t, err, "period at x = 0: none (%zu crossings in the window, %s); global "
                             "oscillation period %s",
                     ms->crossings, ms->crossings < 3 ? "fewer than 3" : "not periodic",
                     period_ref > 0 ? NUM(period_ref, b) : "n/a");
    if (!s)
        s = bkf_io_table_commentf(t, err, "window: mean %s, variance %s, largest spatial std %s, psi in [%s, %s]",
                     NUM(ms->mean, a), NUM(ms->variance, b), NUM(ms->std_max, c),
                     NUM(ms->psi_min, d), NUM(ms->psi_max, e));
    if (!s && front)
        s = bkf_io_table_commentf(t, err, "deviation from the seeded wave: start %.3g, window start %.3g, end "
                             "%.3g, growth rate %.3g",
                     ms->deviation_start, ms->deviation_mid, ms->deviation_end,
                     ms->deviation_growth);
    /* The same key results as fields (JSON "results"; NaN is null). */
    const struct {
        const char *name;
        double value;
    } results[] = {
        {"fronts_start", (double)ms->fronts_start},
        {"fronts_end", (double)ms->fronts_end},
        {"speed", ms->speed},
        {"speed_err", ms->speed_err},
        {"period", ms->period},
        {"period_err", ms->period_err},
        {"period_multiplicity", isfinite(ms->period) ? (double)ms->period_multiplicity : NAN},
        {"global_period", period_ref > 0 ? period_ref : NAN},
        {"v_pred", front ? fi->v : NAN},
        {"v_pred_err", front ? fi->v_err : NAN},
        {"deviation_growth", front ? ms->deviation_growth : NAN},
    };
    if (!s) s = bkf_io_table_result(t, "regime", BKF_IO_TEXT,
                                    (bkf_io_value){.text = bkf_regime_name(ms->regime)}, err);
    for (size_t i = 0; !s && i < sizeof results / sizeof results[0]; i++)
        s = bkf_io_table_result(t, results[i].name, BKF_IO_NUMBER,
                                (bkf_io_value){.number = results[i].value}, err);
    return s;
}

/* Whether |speed| is an allowed speed of `fronts` fronts: a root of the
 * speed condition (the chain: one of its own rotating waves) within three
 * times the measurement's error and the root's, plus BKF_CHECK_REL_TOL_DEFAULT
 * relative (the simulation's own discretization error, which speed_err does
 * not hold).  Not found, or the roots not computed: no. */
static int allowed_speed(const bkf_model_params *model, size_t fronts, double speed,
                         double speed_err)
{
    double v = fabs(speed);
    int found = 0;
    bkf_error e;
    if (model->kind == BKF_MODEL_CHAIN) {
        bkf_chainwave_options co = bkf_chainwave_options_default();
        co.stability = 0;
        bkf_chainwave_table tab;
        memset(&tab, 0, sizeof tab);
        if (bkf_chainwave_check(model, fronts, &co, &e) == BKF_OK &&
            bkf_chainwave_find(model, fronts, fronts, &co, &tab, &e) == BKF_OK)
            for (size_t i = 0; i < tab.count; i++)
                found |= fabs(v - tab.waves[i].v) <= 3 * (speed_err + tab.waves[i].v_err) +
                                                        BKF_CHECK_REL_TOL_DEFAULT * v;
        bkf_chainwave_table_free(&tab);
        return found;
    }
    bkf_model_params p = *model;
    p.kind = BKF_MODEL_CONTINUUM;
    bkf_speeds_options so = bkf_speeds_options_default();
    so.n_from = so.n_to = fronts;
    bkf_speeds_table tab;
    memset(&tab, 0, sizeof tab);
    if (bkf_speeds_find(&p, &so, &tab, &e) == BKF_OK)
        for (size_t i = 0; i < tab.count; i++)
            found |= fabs(v - tab.roots[i].v) <= 3 * (speed_err + tab.roots[i].v_err) +
                                                    BKF_CHECK_REL_TOL_DEFAULT * v;
    bkf_speeds_table_free(&tab);
    return found;
}

/* The regime as the model's speeds allow: propagating fronts only at an
 * allowed speed (issue 31: gamma 3, c 0.8, nu 0.4, S 15 measured 1.779 +-
 * 0.013, five errors from the only v_1 = 1.7112), else still a transient. */
static void name_regime(const bkf_model_params *model, bkf_measure_summary *ms)
{
    if (ms->regime == BKF_REGIME_FRONTS &&
        !allowed_speed(model, ms->fronts_end, ms->speed, ms->speed_err))
        ms->regime = BKF_REGIME_TRANSIENT;
}

/* Opens `path` (so that a bad one fails before any work), NULL for none. */
static int open_file(const bkf_simulate_spec *sp, const char *path, const char *key,
                     bkf_io_atomic **file, bkf_error *err)
{
    *file = NULL;
    if (!path) return BKF_OK;
    bkf_error e;
    *file = bkf_io_atomic_open(path, &e);
    if (!*file) return bkf_error_set(err, BKF_EINPUT, "%s: %s", key, e.message);
    if (sp->temp_file) sp->temp_file(bkf_io_atomic_temp_path(*file), 1, sp->data);
    return BKF_OK;
}

/* Replaced (keep) or dropped, and the temporary no longer guarded. */
static int close_file(const bkf_simulate_spec *sp, bkf_io_atomic *file, int keep,
                      const char *key, int s, bkf_error *err)
{
    if (!file) return s;
    if (sp->temp_file) sp->temp_file(bkf_io_atomic_temp_path(file), 0, sp->data);
    if (!keep) {
        bkf_io_atomic_abort(file);
        return s;
    }
    bkf_error e;
    int c = bkf_io_atomic_commit(file, &e);
    if (c && !s) s = bkf_error_set(err, c, "%s: %s", key, e.message);
    return s;
}

/* How a run ended, for its table. */
typedef struct {
    bkf_pde_front_info fi;
    double period_ref;
    bkf_measure_summary ms;
    int have_summary, canceled;
    char unresolved[256];  /* the grid's warning, or "" */
    char interrupted[160]; /* why the run stopped early, or "" */
} run_end;

/* The records the run keeps until its end (r's) and the clean seed. */
static int alloc_records(run *r, unsigned fields, double **clean, bkf_error *err)
{
    const bkf_simulate_spec *sp = r->spec;
    size_t N = r->model.N;
    *clean = malloc(N * sizeof **clean);
    r->diag = malloc((sp->frames + 1) * NCOLUMNS * sizeof *r->diag);
    if (sp->spacetime && (fields & BKF_SIMULATE_PSI))
        r->field = malloc((sp->frames + 1) * N * sizeof *r->field);
    if (sp->spacetime && (fields & BKF_SIMULATE_ETA))
        r->field_eta = malloc((sp->frames + 1) * N * sizeof *r->field_eta);
    if (sp->snapshots) {
        /* one more: the state where an interrupted run stopped */
        r->snap = malloc((r->snapshots + 1) * (2 * N + 1) * sizeof *r->snap);
        r->snap_frame = malloc(r->snapshots * sizeof *r->snap_frame);
    }
    if (!*clean || !r->diag || ((fields & BKF_SIMULATE_PSI) && sp->spacetime && !r->field) ||
        ((fields & BKF_SIMULATE_ETA) && sp->spacetime && !r->field_eta) ||
        (sp->snapshots && (!r->snap || !r->snap_frame)))
        return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    if (sp->snapshots)
        for (size_t k = 0; k < r->snapshots; k++)
            r->snap_frame[k] = bkf_init_snapshot_frame(k, r->snapshots, sp->frames);
    return BKF_OK;
}

/* check's test of a seeded wave on a spectral grid: Fourier content
 * above N/3 beyond its threshold means the fronts are thinner than the
 * grid can carry, and the run shows the grid, not the model (gamma 20,
 * c 0.05, nu 0.9, S 100, n 5: N 1024 breaks up, N 8192 propagates). */
static void warn_unresolved(const run *r, const double *clean, run_end *end)
{
    const bkf_simulate_spec *sp = r->spec;
    if (r->init.kind != BKF_INIT_FRONT || r->model.kind != BKF_MODEL_CONTINUUM) return;
    double tail = bkf_pde_spectral_tail(r->pde, clean);
    if (tail > BKF_CHECK_RESOLUTION_DEFAULT) {
        snprintf(end->unresolved, sizeof end->unresolved,
                 "warning: N = %zu does not resolve the seeded fronts (spectral tail %.2g "
                 "above N/3, over check's %.0e): raise N, as bkfront check does",
                 r->model.N, tail, BKF_CHECK_RESOLUTION_DEFAULT);
        if (sp->warn) sp->warn(end->unresolved, sp->data);
    }
}

/* The snapshots end with the state where the run stopped, so that
 * --init file:SNAPSHOTS continues from there. */
static void keep_stopped_state(run *r)
{
    size_t N = r->model.N;
    if (r->snap &&
        (r->snap_next == 0 || r->snap[(r->snap_next - 1) * (2 * N + 1)] < bkf_pde_time(r->pde))) {
        double *sn = r->snap + r->snap_next * (2 * N + 1);
        sn[0] = bkf_pde_time(r->pde);
        memcpy(sn + 1, bkf_pde_psi(r->pde), N * sizeof *sn);
        memcpy(sn + 1 + N, bkf_pde_eta(r->pde), N * sizeof *sn);
        r->snap_next++;
    }
}

/* The frames' table to `out`, then the spacetime and snapshot files. */
static int write_run_table(const run *r, const run_end *end, FILE *out, bkf_io_format format,
                           unsigned fields, bkf_io_atomic *st_file, bkf_io_atomic *sn_file,
                           bkf_error *err)
{
    const bkf_simulate_spec *sp = r->spec;
    const char *interrupted = end->canceled ? end->interrupted : NULL;
    bkf_io_table *t = bkf_io_table_alloc(out, format, columns, NCOLUMNS, err);
    if (!t) return BKF_ENOMEM;
    int s = BKF_OK;
    /* an interruption is the first thing a reader sees, before the title */
    if (end->canceled) s = bkf_io_table_comment(t, end->interrupted, err);
    if (!s)
        s = bkf_io_table_commentf(t, err, "%s simulate: direct simulation of the elastic excitable medium",
                     program(r));
    if (!s && end->unresolved[0]) s = bkf_io_table_comment(t, end->unresolved, err);
    if (!s && end->have_summary)
        s = write_summary(t, r, &end->ms, &end->fi, end->period_ref, err);
    if (!s && sp->spacetime)
        s = bkf_io_table_commentf(t, err, "spacetime: %s (%s)", sp->spacetime,
                     spacetime_kind(sp) == SPACETIME_BINARY ? "binary matrix, float32"
                     : spacetime_kind(sp) == SPACETIME_HDF5
                         ? (fields == BKF_SIMULATE_PSI   ? "hdf5, psi[t, x] float32"
                            : fields == BKF_SIMULATE_ETA ? "hdf5, eta[t, x] float32"
                                                         : "hdf5, psi[t, x] and eta[t, x] float32")
                         : "text nonuniform matrix");
    for (size_t f = 0; !s && f < r->frame_index; f++) {
        bkf_io_value v[NCOLUMNS];
        for (size_t k = 0; k < NCOLUMNS; k++) v[k].number = r->diag[f * NCOLUMNS + k];
        s = bkf_io_table_row(t, v, err);
    }
    if (!s) s = bkf_io_table_finish(t, err);
    if (!s && st_file) s = write_spacetime_file(r, interrupted, st_file, err);
    if (!s && sn_file) s = write_snapshots(r, interrupted, bkf_io_atomic_stream(sn_file), err);
    if (!s && end->canceled) s = bkf_error_set(err, BKF_ECANCELED, "%s", end->interrupted);
    bkf_io_table_free(t);
    return s;
}

static int run_simulation(run *r, FILE *out, bkf_io_format format, bkf_io_atomic *st_file,
                          bkf_io_atomic *sn_file, bkf_error *err)
{
    const bkf_simulate_spec *sp = r->spec;
    size_t N = r->model.N;
    bkf_error e;
    double *clean = NULL;
    unsigned fields = sp->spacetime_fields ? sp->spacetime_fields : BKF_SIMULATE_PSI;
    run_end end;
    memset(&end, 0, sizeof end);
    int s = alloc_records(r, fields, &clean, err);
    if (s) goto done;
    if ((s = bkf_seed_init(r->pde, &r->init, &end.fi, clean, &e))) {
        bkf_error_set(err, s, "--init %s: %s", sp->init ? sp->init : "uniform", e.message);
        goto done;
    }
    warn_unresolved(r, clean, &end);
    r->level = bkf_measure_front_level(&r->model, &end.period_ref);
    if (!isnan(sp->level)) r->level = sp->level;
    bkf_measure_params mp = bkf_measure_params_default();
    mp.model = r->model;
    mp.level = r->level;
    mp.period_ref = end.period_ref;
    mp.reference = r->init.kind == BKF_INIT_FRONT ? clean : NULL;
    /* the run ends at t0 + tmax: the measurements keep only the window */
    double t0 = bkf_pde_time(r->pde);
    mp.t_end = t0 + sp->tmax;
    r->meas = bkf_measure_alloc(&mp, err);
    if (!r->meas) {
        s = BKF_ENOMEM;
        goto done;
    }
    bkf_init_sampling smp;
    if ((s = bkf_init_sampling_plan(sp->tmax, sp->frames, BKF_INIT_SAMPLE_DT_MAX, &smp, err)))
        goto done;
    r->per_frame = smp.per_frame;
    s = bkf_pde_run(r->pde, mp.t_end, smp.sample_dt, observe, r, sp->progress, sp->data, &e);
    if (r->status) {
        s = r->status;
        *err = r->err;
        goto done;
    }
    /* Stopped through the cancel flag: the frames recorded so far are
     * complete rows; they are written, marked. */
    end.canceled = s == BKF_ECANCELED;
    if (s && !end.canceled) {
        bkf_error_set(err, s, "%s", e.message);
        goto done;
    }
    if (end.canceled) {
        snprintf(end.interrupted, sizeof end.interrupted,
                 "interrupted (%s) at t = %.9g of %.9g: %zu complete frames kept",
                 sp->cancel_reason ? sp->cancel_reason(sp->data) : "canceled",
                 bkf_pde_time(r->pde), t0 + sp->tmax, r->frame_index);
        keep_stopped_state(r);
    }
    if ((s = bkf_measure_summarize(r->meas, &end.ms, &e))) {
        if (!end.canceled) {
            bkf_error_set(err, BKF_ENUMERIC, "measurements: %s", e.message);
            goto done;
        }
    } else {
        end.have_summary = 1;
        name_regime(&r->model, &end.ms);
    }
    if (r->outcome) {
        if (end.canceled) {
            s = bkf_error_set(err, BKF_ECANCELED, "%s", end.interrupted);
            goto done;
        }
        /* a sweep's field: the file bkf_simulate_write would write */
        if (st_file && (s = write_spacetime_file(r, NULL, st_file, err))) goto done;
        const bkf_pde_stats *st = bkf_pde_get_stats(r->pde);
        *r->outcome = (bkf_simulate_outcome){end.ms, end.period_ref, bkf_pde_time(r->pde),
                                             st->steps, st->rejected, N};
        s = BKF_OK;
        goto done;
    }
    s = write_run_table(r, &end, out, format, fields, st_file, sn_file, err);
done:
    free(clean);
    return s;
}

/* The table to `out`, or with `outcome` only the run's summary into it. */
static int simulate(const bkf_simulate_spec *sp, FILE *out, bkf_io_format format,
                    const bkf_provenance *provenance, bkf_simulate_outcome *outcome,
                    bkf_error *err)
{
    int s = bkf_simulate_check(sp, "", err);
    if (s) return s;
    run r;
    memset(&r, 0, sizeof r);
    r.outcome = outcome;
    r.spec = sp;
    r.prov = provenance;
    r.snapshots = sp->snapshot_count ? sp->snapshot_count : 2;
    s = resolve(sp, "", &r.model, &r.options, &r.init, err);
    bkf_io_atomic *st_file = NULL, *sn_file = NULL;
    if (!s) s = open_file(sp, sp->spacetime, "spacetime", &st_file, err);
    if (!s) s = open_file(sp, sp->snapshots, "snapshots", &sn_file, err);
    if (!s) {
        r.pde = bkf_pde_alloc(&r.model, &r.options, err);
        if (!r.pde) s = err ? err->status : BKF_ENOMEM;
    }
    if (!s) s = run_simulation(&r, out, format, st_file, sn_file, err);
    /* an interrupted run keeps what was complete */
    int keep = !s || (s == BKF_ECANCELED && !sp->discard_canceled);
    s = close_file(sp, st_file, keep, "spacetime", s, err);
    s = close_file(sp, sn_file, keep, "snapshots", s, err);
    bkf_measure_free(r.meas);
    bkf_pde_free(r.pde);
    free(r.diag);
    free(r.field);
    free(r.field_eta);
    free(r.snap);
    free(r.snap_frame);
    bkf_init_free(&r.init);
    return s;
}

int bkf_simulate_write(const bkf_simulate_spec *sp, FILE *out, bkf_io_format format,
                       const bkf_provenance *provenance, bkf_error *err)
{
    return simulate(sp, out, format, provenance, NULL, err);
}

int bkf_simulate_outcome_of(const bkf_simulate_spec *sp, bkf_simulate_outcome *outcome,
                            bkf_error *err)
{
    if (!outcome) return bkf_error_set(err, BKF_EINPUT, "no outcome given");
    if (sp && sp->snapshots)
        return bkf_error_set(err, BKF_EINPUT, "snapshots: no snapshots without a table");
    return simulate(sp, NULL, BKF_IO_TSV, NULL, outcome, err);
}

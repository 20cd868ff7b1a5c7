/* bkfront simulate: direct simulation of the model (continuum or chain) with
 * measurements, diagnostics, the spacetime field and snapshots.
 * bkfront check: the predicted front speeds against seeded simulations.
 *
 * As in the other subcommands every input is checked before computing, each
 * output is built in memory and written only on success (files replaced
 * atomically), and errors are one line. */
#define _POSIX_C_SOURCE 200809L
#include "args.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "bkfront/comoving.h"
#include "bkfront/cycle.h"
#include "bkfront/io.h"
#include "bkfront/measure.h"
#include "bkfront/model.h"
#include "bkfront/pde.h"
#include "bkfront/speeds.h"

/* Paper's parameters (PRL 79, 527): the defaults of both subcommands. */
#define DEF_GAMMA 2.0
#define DEF_C 0.3
#define DEF_NU -0.96
#define DEF_S 20.0
#define DEF_N 512
#define DEF_TMAX 125.0
#define DEF_TOL 1e-9
#define DEF_FRAMES 500
/* Measurement samples at most this far apart: tracking needs a front to
 * move less than half the spacing between fronts per sample. */
#define SAMPLE_DT_MAX 0.1
#define TMAX_MAX 1e6
#define PI 3.14159265358979323846

static const char *const format_names[] = {"tsv", "json", NULL};
static const char *const model_names[] = {"continuum", "chain", NULL};
static const char *const stepper_names[] = {"rk8pd", "rkck", "rkf45", "etdrk4", NULL};
static const char *const spacetime_names[] = {"text", "binary", NULL};

static const char *num(double x, char *buf, size_t size)
{
    snprintf(buf, size, "%.15g", x);
    if (strtod(buf, NULL) != x) snprintf(buf, size, "%.17g", x);
    return buf;
}

static double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* ------------------------------------------------------------ progress */

/* Drawn on stderr only when it is a terminal and the run has already taken
 * half a second; at most ten redraws a second; erased at the end. */
typedef struct {
    int enabled, drawn;
    double start, last;
    const char *label;
    double base, share; /* this run's part of the whole: base + share * fraction */
} progress_bar;

static void progress_init(progress_bar *p, const char *label, int allowed)
{
    memset(p, 0, sizeof *p);
    p->enabled = allowed && isatty(STDERR_FILENO);
    p->start = now_seconds();
    p->label = label;
    p->share = 1.0;
}

static int progress_draw(double fraction, void *data)
{
    progress_bar *p = data;
    if (!p->enabled) return 0;
    double t = now_seconds();
    if (t - p->start < 0.5 || t - p->last < 0.1) return 0;
    p->last = t;
    double f = p->base + p->share * fraction;
    if (f > 1) f = 1;
    int width = 30, done = (int)(f * width + 0.5);
    char bar[64];
    for (int i = 0; i < width; i++) bar[i] = i < done ? '#' : '.';
    bar[width] = '\0';
    fprintf(stderr, "\r%s [%s] %3.0f%%  %.1fs", p->label, bar, 100 * f, t - p->start);
    fflush(stderr);
    p->drawn = 1;
    return 0;
}

static void progress_end(progress_bar *p)
{
    if (p->drawn) {
        fprintf(stderr, "\r\033[K");
        fflush(stderr);
    }
    p->drawn = 0;
}

/* ---------------------------------------------------- shared parameters */

typedef struct {
    const char *gamma, *c, *nu, *S, *N, *tol, *model, *stepper, *format, *out, *seed, *tmax,
        *filter;
    int dealias;
} model_flags;

typedef struct {
    bkf_pde_params params;
    bkf_pde_options options;
    int N_given;
    unsigned long seed;
    double tmax;
    bkf_io_format format;
    const char *out_path;
} model_plan;

static int parse_positive(const char *flag, const char *text, double *v, bkf_error *err)
{
    int s = cli_parse_double(flag, text, v, err);
    if (s) return s;
    if (!(*v > 0)) return bkf_error_set(err, BKF_EINPUT, "%s: %s must be > 0", flag, text);
    return BKF_OK;
}

static int parse_seed(const char *text, unsigned long *seed, bkf_error *err)
{
    if (!*text || strspn(text, "0123456789") != strlen(text) || strlen(text) > 19)
        return bkf_error_set(err, BKF_EINPUT, "--seed: '%s' is not an integer in [0, 1e19)",
                             text);
    errno = 0;
    unsigned long long v = strtoull(text, NULL, 10);
    if (errno || v > ULONG_MAX)
        return bkf_error_set(err, BKF_EINPUT, "--seed: '%s' is out of range", text);
    *seed = (unsigned long)v;
    return BKF_OK;
}

static int plan_model(const model_flags *f, model_plan *p, bkf_error *err)
{
    int s;
    char a[32];
    p->params = (bkf_pde_params){DEF_GAMMA, DEF_C, DEF_NU, DEF_S, DEF_N, BKF_PDE_CONTINUUM};
    p->options = bkf_pde_options_default();
    p->options.tol = DEF_TOL;
    if (f->gamma && (s = parse_positive("--gamma", f->gamma, &p->params.gamma, err))) return s;
    if (f->c) {
        if ((s = cli_parse_double("--c", f->c, &p->params.c, err))) return s;
        if (!(p->params.c >= 0))
            return bkf_error_set(err, BKF_EINPUT, "--c: %s must be >= 0", f->c);
    }
    if (f->nu && (s = cli_parse_double("--nu", f->nu, &p->params.nu, err))) return s;
    if (f->S && (s = parse_positive("--S", f->S, &p->params.S, err))) return s;
    if (f->model) {
        int k;
        if ((s = cli_parse_choice("--model", f->model, model_names, &k, err))) return s;
        p->params.model = k ? BKF_PDE_CHAIN : BKF_PDE_CONTINUUM;
    }
    p->N_given = f->N != NULL;
    if (f->N) {
        size_t n;
        if ((s = cli_parse_count("--N", f->N, BKF_PDE_N_MAX, &n, err))) return s;
        if (n < BKF_PDE_N_MIN)
            return bkf_error_set(err, BKF_EINPUT, "--N: %zu is below %d", n, BKF_PDE_N_MIN);
        if (p->params.model == BKF_PDE_CONTINUUM && n % 2)
            return bkf_error_set(err, BKF_EINPUT,
                                 "--N: %zu must be even for the continuum model (spectral)", n);
        p->params.N = n;
    } else if (p->params.model == BKF_PDE_CHAIN) {
        /* The physical chain: one block per unit length. */
        double S = p->params.S;
        if (S != floor(S) || S < BKF_PDE_N_MIN || S > BKF_PDE_N_MAX)
            return bkf_error_set(err, BKF_EINPUT,
                                 "--model chain: give --N (the number of blocks); the default "
                                 "N = S needs an integer S in [%d, %d], S = %s",
                                 BKF_PDE_N_MIN, BKF_PDE_N_MAX, num(S, a, sizeof a));
        p->params.N = (size_t)S;
    }
    if (f->tol) {
        if ((s = cli_parse_double("--tol", f->tol, &p->options.tol, err))) return s;
        if (!(p->options.tol >= BKF_PDE_TOL_MIN && p->options.tol <= BKF_PDE_TOL_MAX))
            return bkf_error_set(err, BKF_EINPUT, "--tol: %s is outside [%g, %g]", f->tol,
                                 BKF_PDE_TOL_MIN, BKF_PDE_TOL_MAX);
    }
    if (f->stepper) {
        int k;
        if ((s = cli_parse_choice("--stepper", f->stepper, stepper_names, &k, err))) return s;
        p->options.stepper = (bkf_pde_stepper)k;
    }
    p->options.dealias = f->dealias;
    if (f->filter) {
        if ((s = cli_parse_double("--filter", f->filter, &p->options.filter, err))) return s;
        if (!(p->options.filter >= 0 && p->options.filter <= 1000))
            return bkf_error_set(err, BKF_EINPUT, "--filter: %s is outside [0, 1000]", f->filter);
    }
    if (f->dealias && p->params.model != BKF_PDE_CONTINUUM)
        return bkf_error_set(err, BKF_EINPUT, "--dealias: only for --model continuum");
    p->tmax = DEF_TMAX;
    if (f->tmax) {
        if ((s = parse_positive("--tmax", f->tmax, &p->tmax, err))) return s;
        if (p->tmax > TMAX_MAX)
            return bkf_error_set(err, BKF_EINPUT, "--tmax: %s is above %g", f->tmax, TMAX_MAX);
    }
    p->seed = 1;
    if (f->seed && (s = parse_seed(f->seed, &p->seed, err))) return s;
    p->format = BKF_IO_TSV;
    if (f->format) {
        int k;
        if ((s = cli_parse_choice("--format", f->format, format_names, &k, err))) return s;
        p->format = k ? BKF_IO_JSON : BKF_IO_TSV;
    }
    if (f->out && !*f->out) return bkf_error_set(err, BKF_EINPUT, "--out: the file name is empty");
    p->out_path = f->out;
    bkf_error e;
    if (bkf_pde_check(&p->params, &p->options, &e))
        return bkf_error_set(err, BKF_EINPUT, "%s", e.message);
    return BKF_OK;
}

static int comment_command(bkf_io_table *t, int argc, char **argv, bkf_error *err)
{
    char *cmd = cli_command_line(argc, argv);
    if (!cmd) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    size_t n = strlen(cmd) + 64;
    char *text = malloc(n);
    if (!text) {
        free(cmd);
        return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    }
    snprintf(text, n, "command: " CLI_PROGRAM " %s", cmd);
    int s = bkf_io_table_comment(t, text, err);
    free(text);
    free(cmd);
    return s;
}

static int commentf(bkf_io_table *t, bkf_error *err, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static int commentf(bkf_io_table *t, bkf_error *err, const char *fmt, ...)
{
    char line[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    return bkf_io_table_comment(t, line, err);
}

static int comment_model(bkf_io_table *t, const model_plan *p, bkf_error *err)
{
    char a[32], b[32], c[32], d[32], e[32], f[32], g[32];
    return commentf(t, err,
                    "model %s: gamma %s, c %s, nu %s, S %s, N %zu (h = %s); tol %s, stepper %s, "
                    "dealias %s, filter %s",
                    model_names[p->params.model], num(p->params.gamma, a, sizeof a),
                    num(p->params.c, b, sizeof b), num(p->params.nu, c, sizeof c),
                    num(p->params.S, d, sizeof d), p->params.N,
                    num(p->params.S / (double)p->params.N, e, sizeof e),
                    num(p->options.tol, f, sizeof f), stepper_names[p->options.stepper],
                    p->options.dealias ? "on (2/3 rule)" : "off",
                    p->params.model == BKF_PDE_CHAIN || p->options.filter == 0
                        ? "off"
                        : num(p->options.filter, g, sizeof g));
}

/* --------------------------------------------------------- initial state */

typedef enum { INIT_UNIFORM, INIT_OSCILLATION, INIT_FRONT, INIT_FILE } init_kind;

typedef struct {
    init_kind kind;
    double amp;                 /* uniform, oscillation */
    int q_given;
    double q;                   /* oscillation: requested wavenumber */
    size_t j;                   /* oscillation: mode */
    bkf_pde_front_spec front;
    const char *path;           /* file */
    double *psi, *eta;          /* file contents */
    size_t rows;
    double t0;
} init_plan;

static void init_free(init_plan *p)
{
    free(p->psi);
    free(p->eta);
    p->psi = p->eta = NULL;
}

#define INIT_FORM                                                                          \
    "uniform[:amp=A], oscillation[:q=Q|j=J][,amp=A], front:n=K[,root=R][,dir=left|right]" \
    "[,noise=E], or file:PATH"

/* key=value,key=value after the colon; each key handled by `take`. */
static int parse_pairs(const char *text, const char *kind,
                       int (*take)(const char *key, const char *value, void *data, bkf_error *err),
                       void *data, bkf_error *err)
{
    char buf[256], shown[72];
    if (strlen(text) >= sizeof buf)
        return bkf_error_set(err, BKF_EINPUT, "--init: the %s options are too long", kind);
    strcpy(buf, text);
    char *save = NULL;
    for (char *tok = strtok_r(buf, ",", &save); tok; tok = strtok_r(NULL, ",", &save)) {
        char *eq = strchr(tok, '=');
        if (!eq || eq == tok || !eq[1])
            return bkf_error_set(err, BKF_EINPUT, "--init %s: '%s' is not key=value (%s)", kind,
                                 cli_shown(tok, shown, sizeof shown), INIT_FORM);
        *eq = '\0';
        int s = take(tok, eq + 1, data, err);
        if (s) return s;
    }
    return BKF_OK;
}

static int init_amp(const char *kind, const char *key, const char *value, double *amp,
                    bkf_error *err)
{
    char flag[64];
    snprintf(flag, sizeof flag, "--init %s %s", kind, key);
    int s = cli_parse_double(flag, value, amp, err);
    if (s) return s;
    if (!(*amp >= 0 && *amp <= 10))
        return bkf_error_set(err, BKF_EINPUT, "%s: %s is outside [0, 10]", flag, value);
    return BKF_OK;
}

static int take_uniform(const char *key, const char *value, void *data, bkf_error *err)
{
    init_plan *p = data;
    if (strcmp(key, "amp") == 0) return init_amp("uniform", key, value, &p->amp, err);
    char a[72];
    return bkf_error_set(err, BKF_EINPUT, "--init uniform: unknown key '%s' (amp)",
                         cli_shown(key, a, sizeof a));
}

static int take_oscillation(const char *key, const char *value, void *data, bkf_error *err)
{
    init_plan *p = data;
    if (strcmp(key, "amp") == 0) return init_amp("oscillation", key, value, &p->amp, err);
    if (strcmp(key, "q") == 0) {
        int s = cli_parse_double("--init oscillation q", value, &p->q, err);
        if (s) return s;
        if (!(p->q >= 0))
            return bkf_error_set(err, BKF_EINPUT, "--init oscillation q: %s must be >= 0", value);
        p->q_given = 1;
        return BKF_OK;
    }
    if (strcmp(key, "j") == 0) {
        if (strcmp(value, "0") == 0) {
            p->j = 0;
            p->q_given = 0;
            return BKF_OK;
        }
        return cli_parse_count("--init oscillation j", value, BKF_PDE_N_MAX, &p->j, err);
    }
    char a[72];
    return bkf_error_set(err, BKF_EINPUT, "--init oscillation: unknown key '%s' (q, j, amp)",
                         cli_shown(key, a, sizeof a));
}

static int take_front(const char *key, const char *value, void *data, bkf_error *err)
{
    init_plan *p = data;
    char a[72];
    if (strcmp(key, "n") == 0) return cli_parse_count("--init front n", value, 100000, &p->front.n, err);
    if (strcmp(key, "root") == 0)
        return cli_parse_count("--init front root", value, 100, &p->front.root, err);
    if (strcmp(key, "noise") == 0) return init_amp("front", key, value, &p->front.noise, err);
    if (strcmp(key, "dir") == 0) {
        if (strcmp(value, "left") == 0) p->front.direction = -1;
        else if (strcmp(value, "right") == 0) p->front.direction = 1;
        else
            return bkf_error_set(err, BKF_EINPUT, "--init front dir: '%s' is not left or right",
                                 cli_shown(value, a, sizeof a));
        return BKF_OK;
    }
    return bkf_error_set(err, BKF_EINPUT, "--init front: unknown key '%s' (n, root, dir, noise)",
                         cli_shown(key, a, sizeof a));
}

/* A TSV whose header names psi and eta (snapshots of bkfront simulate are
 * such files); with a t column, the rows of the last t are taken. */
static int read_state_stream(init_plan *p, FILE *f, bkf_error *err)
{
    char path[72], a[72];
    cli_shown(p->path, path, sizeof path);
    char *line = NULL;
    size_t cap = 0;
    ssize_t len;
    int ipsi = -1, ieta = -1, it = -1, ncol = 0, header = 0, status = BKF_OK;
    size_t lineno = 0, rows = 0, rcap = 0;
    double *psi = NULL, *eta = NULL, *tt = NULL;
    while ((len = getline(&line, &cap, f)) >= 0) {
        lineno++;
        while (len > 0 && (line[len - 1] == '\n' || line[len - 1] == '\r')) line[--len] = '\0';
        if (line[0] == '#' || len == 0) continue;
        if (!header) {
            header = 1;
            char *save = NULL;
            int col = 0;
            for (char *tok = strtok_r(line, "\t", &save); tok; tok = strtok_r(NULL, "\t", &save), col++) {
                if (strcmp(tok, "psi") == 0) ipsi = col;
                else if (strcmp(tok, "eta") == 0) ieta = col;
                else if (strcmp(tok, "t") == 0) it = col;
            }
            ncol = col;
            if (ipsi < 0 || ieta < 0) {
                status = bkf_error_set(err, BKF_EINPUT,
                                       "--init file:%s: the header (line %zu) must name the "
                                       "columns psi and eta", path, lineno);
                break;
            }
            continue;
        }
        if (rows == rcap) {
            rcap = rcap ? 2 * rcap : 1024;
            double *a = realloc(psi, rcap * sizeof *a), *b = a ? realloc(eta, rcap * sizeof *b) : NULL,
                   *c = b ? realloc(tt, rcap * sizeof *c) : NULL;
            if (a) psi = a;
            if (b) eta = b;
            if (c) tt = c;
            if (!a || !b || !c) {
                status = bkf_error_set(err, BKF_ENOMEM, "out of memory");
                break;
            }
        }
        char *save = NULL;
        int col = 0;
        double vp = NAN, ve = NAN, vt = 0;
        for (char *tok = strtok_r(line, "\t", &save); tok; tok = strtok_r(NULL, "\t", &save), col++) {
            if (col != ipsi && col != ieta && col != it) continue;
            char *end;
            errno = 0;
            double v = strtod(tok, &end);
            if (*end || end == tok || !isfinite(v) || errno) {
                status = bkf_error_set(err, BKF_EINPUT,
                                       "--init file:%s: line %zu: '%s' is not a finite number",
                                       path, lineno, cli_shown(tok, a, sizeof a));
                break;
            }
            if (col == ipsi) vp = v;
            else if (col == ieta) ve = v;
            else vt = v;
        }
        if (status) break;
        if (col != ncol) {
            status = bkf_error_set(err, BKF_EINPUT, "--init file:%s: line %zu has %d fields, not %d",
                                   path, lineno, col, ncol);
            break;
        }
        psi[rows] = vp;
        eta[rows] = ve;
        tt[rows] = vt;
        rows++;
    }
    free(line);
    if (!status && ferror(f))
        status = bkf_error_set(err, BKF_EINPUT, "--init file:%s: read error", path);
    if (!status && !header)
        status = bkf_error_set(err, BKF_EINPUT, "--init file:%s: no header line", path);
    size_t first = 0;
    if (!status && it >= 0 && rows) {
        double tl = tt[rows - 1];
        first = rows;
        while (first > 0 && tt[first - 1] == tl) first--;
        p->t0 = tl;
    }
    if (!status && rows - first < BKF_PDE_N_MIN)
        status = bkf_error_set(err, BKF_EINPUT, "--init file:%s: %zu rows, need at least %d",
                               path, rows - first, BKF_PDE_N_MIN);
    if (!status) {
        p->rows = rows - first;
        p->psi = malloc(p->rows * sizeof *p->psi);
        p->eta = malloc(p->rows * sizeof *p->eta);
        if (!p->psi || !p->eta) status = bkf_error_set(err, BKF_ENOMEM, "out of memory");
        else {
            memcpy(p->psi, psi + first, p->rows * sizeof *psi);
            memcpy(p->eta, eta + first, p->rows * sizeof *eta);
        }
    }
    free(psi);
    free(eta);
    free(tt);
    return status;
}

static int read_state_file(init_plan *p, bkf_error *err)
{
    FILE *f = fopen(p->path, "r");
    if (!f)
    {
        char a[72];
        return bkf_error_set(err, BKF_EINPUT, "--init file:%s: %s",
                             cli_shown(p->path, a, sizeof a), strerror(errno));
    }
    int s = read_state_stream(p, f, err);
    fclose(f);
    return s;
}

static int parse_init(const char *text, init_plan *p, bkf_error *err)
{
    memset(p, 0, sizeof *p);
    p->front = bkf_pde_front_spec_default();
    const char *colon = strchr(text, ':');
    size_t klen = colon ? (size_t)(colon - text) : strlen(text);
    const char *rest = colon ? colon + 1 : "";
    if (klen == 7 && strncmp(text, "uniform", 7) == 0) {
        p->kind = INIT_UNIFORM;
        p->amp = 1e-3;
        return parse_pairs(rest, "uniform", take_uniform, p, err);
    }
    if (klen == 11 && strncmp(text, "oscillation", 11) == 0) {
        p->kind = INIT_OSCILLATION;
        p->amp = 0;
        return parse_pairs(rest, "oscillation", take_oscillation, p, err);
    }
    if (klen == 5 && strncmp(text, "front", 5) == 0) {
        p->kind = INIT_FRONT;
        int have_n = strstr(rest, "n=") == rest || strstr(rest, ",n=");
        int s = parse_pairs(rest, "front", take_front, p, err);
        if (s) return s;
        if (!have_n)
            return bkf_error_set(err, BKF_EINPUT, "--init front: n=K is required (%s)", INIT_FORM);
        return BKF_OK;
    }
    if (klen == 4 && strncmp(text, "file", 4) == 0) {
        p->kind = INIT_FILE;
        if (!*rest) return bkf_error_set(err, BKF_EINPUT, "--init file: give a path, file:PATH");
        p->path = rest;
        return read_state_file(p, err);
    }
    char a[72];
    return bkf_error_set(err, BKF_EINPUT, "--init: '%s' is not one of %s",
                         cli_shown(text, a, sizeof a), INIT_FORM);
}

/* Cross-checks that need the model parameters. */
static int check_init(init_plan *ip, model_plan *mp, bkf_error *err)
{
    char a[32], b[32], path[72];
    bkf_error e;
    if (ip->kind == INIT_FILE) {
        cli_shown(ip->path, path, sizeof path);
        if (mp->N_given && mp->params.N != ip->rows)
            return bkf_error_set(err, BKF_EINPUT, "--N: %zu differs from the %zu rows of --init "
                                                  "file:%s", mp->params.N, ip->rows, path);
        mp->params.N = ip->rows;
        if (bkf_pde_check(&mp->params, &mp->options, &e))
            return bkf_error_set(err, BKF_EINPUT, "--init file:%s: %s", path, e.message);
    }
    if (ip->kind == INIT_OSCILLATION || ip->kind == INIT_FRONT) {
        if (bkf_model_check_nu_active(mp->params.nu, &e))
            return bkf_error_set(err, BKF_EINPUT, "--init %s needs a limit cycle: --nu: %s",
                                 ip->kind == INIT_FRONT ? "front" : "oscillation", e.message);
        if (mp->params.gamma < BKF_CYCLE_MU_MIN || mp->params.gamma > BKF_CYCLE_MU_MAX)
            return bkf_error_set(err, BKF_EINPUT, "--gamma: %s is outside [%g, %g] (the cycle "
                                                  "engine's range of mu)",
                                 num(mp->params.gamma, a, sizeof a), BKF_CYCLE_MU_MIN,
                                 BKF_CYCLE_MU_MAX);
    }
    if (ip->kind == INIT_OSCILLATION) {
        if (ip->q_given) ip->j = (size_t)floor(ip->q * mp->params.S / (2 * PI) + 0.5);
        if (ip->j >= mp->params.N / 2)
            return bkf_error_set(err, BKF_EINPUT,
                                 "--init oscillation: mode j = %zu (q = %s) is not below N/2 = %zu",
                                 ip->j, num(2 * PI * (double)ip->j / mp->params.S, b, sizeof b),
                                 mp->params.N / 2);
    }
    return BKF_OK;
}

static int apply_init(bkf_pde *pde, const init_plan *ip, const model_plan *mp,
                      bkf_pde_front_info *info, double *clean, bkf_error *err)
{
    switch (ip->kind) {
    case INIT_UNIFORM: return bkf_pde_init_uniform(pde, ip->amp, mp->seed, err);
    case INIT_OSCILLATION: return bkf_pde_init_oscillation(pde, ip->j, ip->amp, err);
    case INIT_FRONT: {
        bkf_pde_front_spec fs = ip->front;
        fs.seed = mp->seed;
        return bkf_pde_init_front(pde, &fs, info, clean, err);
    }
    default: return bkf_pde_set_state(pde, ip->psi, ip->eta, 0.0, err);
    }
}

/* The level whose crossings are fronts: the middle of the global
 * oscillation's range, (xmin + xmax)/2 of the cycle at mu = gamma.  Every
 * relaxation jump crosses it mid-way, where fronts are steepest, also in
 * the period-doubled patterns, whose fronts sit well above nu.  Where there
 * is no cycle (|nu| >= 1) it is nu.  *period gets the cycle's period (0
 * without a cycle). */
static double front_level(const bkf_pde_params *pp, double *period)
{
    *period = 0;
    if (!(fabs(pp->nu) < 1) || pp->gamma < BKF_CYCLE_MU_MIN || pp->gamma > BKF_CYCLE_MU_MAX)
        return pp->nu;
    bkf_cycle_result cr;
    bkf_cycle_options co = bkf_cycle_options_default();
    bkf_error e;
    if (bkf_cycle_period(pp->gamma, pp->nu, &co, &cr, &e) != BKF_OK) return pp->nu;
    *period = cr.period;
    return 0.5 * (cr.xmin + cr.xmax);
}

/* ============================================================ simulate */

static void simulate_help(FILE *out)
{
    fprintf(out,
        "usage: bkfront simulate [--gamma G] [--c C] [--nu V] [--S S] [--N N] [--tmax T]\n"
        "                        [--tol E] [--init SPEC] [--seed K] [--model continuum|chain]\n"
        "                        [--stepper rk8pd|rkck|rkf45|etdrk4] [--dealias] [--frames F]\n"
        "                        [--spacetime FILE] [--spacetime-format text|binary]\n"
        "                        [--snapshots FILE] [--snapshot-count K] [--no-progress]\n"
        "                        [--format tsv|json] [--out FILE]\n"
        "\n"
        "Direct simulation of psi_t = gamma (eta - phi(psi)), eta_t = -(psi - nu - c^2 psi_xx)/gamma\n"
        "on a periodic domain of size S, with measurements: front count and positions, front\n"
        "speed, period at x = 0, spatial mean and variance, and the regime.\n"
        "\n"
        "options (defaults: the paper's gamma 2, c 0.3, nu -0.96, S 20):\n"
        "  --gamma G         friction strength, > 0; default 2\n"
        "  --c C             sound speed, >= 0; default 0.3\n"
        "  --nu V            pulling rate, any finite value (|nu| >= 1: continuous slip is\n"
        "                    stable; oscillation and front need |nu| < 1); default -0.96\n"
        "  --S S             domain size, > 0; default 20\n"
        "  --N N             grid points, in [%d, %d]; even for the continuum (a power of two\n"
        "                    is not required); default 512, or S blocks for --model chain\n"
        "  --tmax T          final time, in (0, %g]; default 125\n"
        "  --tol E           local error tolerance of the Runge-Kutta stepper (absolute and\n"
        "                    relative), in [%g, %g]; default 1e-9\n"
        "  --init SPEC       initial state; default uniform\n"
        "      uniform[:amp=A]        psi = nu + band-limited noise of rms A (default 1e-3,\n"
        "                             modes 1..S/2), eta = phi(psi)\n"
        "      oscillation[:q=Q|j=J][,amp=A]\n"
        "                             the global oscillation (cycle at mu = gamma) at psi = nu\n"
        "                             rising, plus A cos(q x); q is rounded to the nearest\n"
        "                             2 pi j/S; default j = 0, A = 0\n"
        "      front:n=K[,root=R][,dir=left|right][,noise=E]\n"
        "                             the travelling wave of K fronts at the predicted speed\n"
        "                             (root R of bkf_speeds_find, default 1, the fastest),\n"
        "                             moving left (-x, default) or right, plus noise of rms E\n"
        "      file:PATH              a TSV naming the columns psi and eta (N rows; with a t\n"
        "                             column, the rows of the last t): --snapshots output\n"
        "  --seed K          seed of the noise; default 1\n"
        "  --model M         continuum (pseudo-spectral, FFTW) or chain (Burridge-Knopoff\n"
        "                    blocks, finite differences, h = S/N); default continuum\n"
        "  --stepper S       rk8pd (default), rkck, rkf45: GSL embedded Runge-Kutta pairs;\n"
        "                    etdrk4: exponential Runge-Kutta (continuum only; the wave\n"
        "                    part exact, no step cap from N; energy_residual and\n"
        "                    mean_residual are nan with it)\n"
        "  --dealias         continuum only: 2/3-rule projection of the right-hand side\n"
        "  --filter F        continuum only: rate F of the spectral filter at the highest\n"
        "                    mode, F (k/k_top)^16 (it stops a grid instability of the modes\n"
        "                    near the Nyquist wavenumber; 0 turns it off); default 4\n"
        "  --level L         fronts are crossings of psi = L with psi_t > 0; default the\n"
        "                    middle of the global oscillation's range (nu if |nu| >= 1)\n"
        "  --frames F        rows of the diagnostics and the spacetime field, evenly spaced\n"
        "                    over [0, tmax] (F + 1 rows with t = 0); default %d\n"
        "  --spacetime FILE  psi(x, t) at the frames for gnuplot: text is the nonuniform\n"
        "                    matrix format (first row N x_0 .. x_{N-1}, then t psi ...;\n"
        "                    plot 'FILE' nonuniform matrix with image), binary the same\n"
        "                    numbers as float32 (plot 'FILE' binary matrix with image)\n"
        "  --spacetime-format text|binary   default text\n"
        "  --snapshots FILE  TSV with columns t, x, psi, eta at K frames spread over the run\n"
        "  --snapshot-count K  K >= 1 snapshots (the last at tmax); default 2\n"
        "  --no-progress     no progress bar (it is drawn on a terminal's stderr only,\n"
        "                    once a run has taken 0.5 s)\n"
        "  --format tsv|json diagnostics format; default tsv\n"
        "  --out FILE        diagnostics to FILE, replaced atomically on success;\n"
        "                    default standard output\n"
        "  --help            this text\n"
        "\n"
        "diagnostics columns (one row per frame):\n"
        "  t                 time\n"
        "  mean, variance    spatial mean and variance of psi\n"
        "  min, max          extremes of psi over x\n"
        "  probe             psi at x = 0\n"
        "  fronts            number of fronts (crossings of the level with psi_t > 0,\n"
        "                    hysteresis 0.1)\n"
        "  displacement      mean displacement of the tracked fronts since t = 0 (nan once\n"
        "                    the front count has changed)\n"
        "  deviation         front init: max |psi - seeded wave shifted by displacement|\n"
        "  energy            H = h sum [psi_t^2/2 + (psi - nu)^2/2 - c^2 psi L psi/2]\n"
        "  energy_residual   H(t) - H(0) - integral of the friction work (0 up to the\n"
        "                    integration error)\n"
        "  mean_residual     drift of mean(eta) + (integral of mean(psi) - nu t)/gamma\n"
        "                    (conserved exactly: rounding only)\n"
        "The comment lines before the table carry the summary: regime, front speed with its\n"
        "uncertainty, period at x = 0, and the work of the run.\n"
        "\n"
        "Output is all or nothing for each file: nothing is written on failure.\n"
        "Ctrl-C (SIGINT) or SIGTERM stops the run cleanly: the frames completed so far are\n"
        "written (each output with a comment 'interrupted ... at t = ...'), one line on\n"
        "stderr says so, exit status 130 (143 for SIGTERM); a second signal ends it at once.\n"
        "exit status: 0 ok, 1 numerical failure, 2 bad input\n",
        BKF_PDE_N_MIN, BKF_PDE_N_MAX, TMAX_MAX, BKF_PDE_TOL_MIN, BKF_PDE_TOL_MAX, DEF_FRAMES);
}

static const bkf_io_column sim_columns[] = {
    {"t", BKF_IO_NUMBER},        {"mean", BKF_IO_NUMBER},
    {"variance", BKF_IO_NUMBER}, {"min", BKF_IO_NUMBER},
    {"max", BKF_IO_NUMBER},      {"probe", BKF_IO_NUMBER},
    {"fronts", BKF_IO_NUMBER},   {"displacement", BKF_IO_NUMBER},
    {"deviation", BKF_IO_NUMBER}, {"energy", BKF_IO_NUMBER},
    {"energy_residual", BKF_IO_NUMBER}, {"mean_residual", BKF_IO_NUMBER},
};
#define SIM_NCOLUMNS (sizeof sim_columns / sizeof sim_columns[0])

typedef struct {
    model_plan m;
    init_plan init;
    const char *init_text;
    size_t frames, snapshots;
    const char *spacetime_path, *snapshots_path;
    int spacetime_binary, progress;
    double level;               /* NaN: the default (front_level) */
} sim_plan;

static int plan_simulate(int argc, char **argv, sim_plan *p, bkf_error *err)
{
    model_flags mf = {0};
    const char *init = NULL, *frames = NULL, *spacetime = NULL, *stfmt = NULL, *snaps = NULL,
               *snapcount = NULL, *level = NULL;
    int help = 0, noprog = 0;
    const cli_flag flags[] = {
        {"--gamma", &mf.gamma, "a number > 0", NULL},
        {"--c", &mf.c, "a number >= 0", NULL},
        {"--nu", &mf.nu, "a finite number", NULL},
        {"--S", &mf.S, "a number > 0", NULL},
        {"--N", &mf.N, "an integer >= 8", NULL},
        {"--tmax", &mf.tmax, "a number > 0", NULL},
        {"--tol", &mf.tol, "a number in [1e-13, 0.01]", NULL},
        {"--init", &init, INIT_FORM, NULL},
        {"--seed", &mf.seed, "an integer >= 0", NULL},
        {"--model", &mf.model, "continuum or chain", NULL},
        {"--stepper", &mf.stepper, "rk8pd, rkck, rkf45 or etdrk4", NULL},
        {"--dealias", NULL, NULL, &mf.dealias},
        {"--filter", &mf.filter, "a number in [0, 1000]", NULL},
        {"--level", &level, "a finite number", NULL},
        {"--frames", &frames, "an integer >= 1", NULL},
        {"--spacetime", &spacetime, "a file name", NULL},
        {"--spacetime-format", &stfmt, "text or binary", NULL},
        {"--snapshots", &snaps, "a file name", NULL},
        {"--snapshot-count", &snapcount, "an integer >= 1", NULL},
        {"--no-progress", NULL, NULL, &noprog},
        {"--format", &mf.format, "tsv or json", NULL},
        {"--out", &mf.out, "a file name", NULL},
        {"--help", NULL, NULL, &help},
    };
    int s = cli_parse_flags(flags, sizeof flags / sizeof flags[0], argc, argv, err);
    if (s) return s;
    if ((s = plan_model(&mf, &p->m, err))) return s;
    p->init_text = init ? init : "uniform";
    if ((s = parse_init(p->init_text, &p->init, err))) return s;
    if ((s = check_init(&p->init, &p->m, err))) return s;
    p->frames = DEF_FRAMES;
    if (frames && (s = cli_parse_count("--frames", frames, 1000000, &p->frames, err))) return s;
    p->snapshots = 2;
    if (snapcount && (s = cli_parse_count("--snapshot-count", snapcount, 100000, &p->snapshots, err)))
        return s;
    if (p->snapshots > p->frames + 1)
        return bkf_error_set(err, BKF_EINPUT, "--snapshot-count: %zu is more than the %zu frames",
                             p->snapshots, p->frames + 1);
    if (stfmt) {
        int k;
        if ((s = cli_parse_choice("--spacetime-format", stfmt, spacetime_names, &k, err))) return s;
        p->spacetime_binary = k == 1;
        if (!spacetime)
            return bkf_error_set(err, BKF_EINPUT, "--spacetime-format: give --spacetime FILE too");
    }
    if (spacetime && !*spacetime)
        return bkf_error_set(err, BKF_EINPUT, "--spacetime: the file name is empty");
    if (snaps && !*snaps) return bkf_error_set(err, BKF_EINPUT, "--snapshots: the file name is empty");
    if (snapcount && !snaps)
        return bkf_error_set(err, BKF_EINPUT, "--snapshot-count: give --snapshots FILE too");
    p->spacetime_path = spacetime;
    p->snapshots_path = snaps;
    p->progress = !noprog;
    p->level = NAN;
    if (level && (s = cli_parse_double("--level", level, &p->level, err))) return s;
    /* frames x N values of the spacetime field are kept in memory */
    if (spacetime && (double)(p->frames + 1) * (double)p->m.params.N > 2e8)
        return bkf_error_set(err, BKF_EINPUT,
                             "--frames: %zu frames of %zu points is more than 2e8 values",
                             p->frames + 1, p->m.params.N);
    return BKF_OK;
}

/* A path must be writable before any work: open the atomic file and drop it
 * again (the real one is written at the end, when the data exist). */
static int probe_path(const char *path, const char *flag, bkf_error *err)
{
    if (!path) return BKF_OK;
    bkf_error e;
    bkf_io_atomic *f = bkf_io_atomic_open(path, &e);
    if (!f) return bkf_error_set(err, BKF_EINPUT, "%s: %s", flag, e.message);
    bkf_io_atomic_abort(f);
    return BKF_OK;
}

typedef struct {
    sim_plan *plan;
    bkf_pde *pde;
    bkf_measure *meas;
    size_t per_frame, sample_index, frame_index;
    /* frame rows, kept until the end */
    double *diag;        /* per frame: SIM_NCOLUMNS values */
    float *field;        /* per frame: psi at N points (spacetime) */
    double *snap;        /* per snapshot: t, psi[N], eta[N] */
    size_t *snap_frame;  /* frame index of each snapshot */
    size_t snap_next;
    int status;
    bkf_error err;
} sim_run;

static int sim_observe(const bkf_pde_sample *smp, void *data)
{
    sim_run *r = data;
    size_t N = r->plan->m.params.N;
    bkf_error e;
    if (bkf_measure_add(r->meas, smp->t, smp->psi, smp->eta, &e)) {
        r->status = bkf_error_set(&r->err, BKF_ENUMERIC, "measurement at t = %g: %s", smp->t,
                                  e.message);
        return 1;
    }
    size_t k = r->sample_index++;
    if (k % r->per_frame != 0 || r->frame_index > r->plan->frames) return 0;
    size_t f = r->frame_index++;
    const bkf_measure_record *rc = bkf_measure_record_at(r->meas, bkf_measure_count(r->meas) - 1);
    double *row = r->diag + f * SIM_NCOLUMNS;
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
    if (r->snap && r->snap_next < r->plan->snapshots && r->snap_frame[r->snap_next] == f) {
        double *s = r->snap + r->snap_next * (2 * N + 1);
        s[0] = smp->t;
        memcpy(s + 1, smp->psi, N * sizeof *s);
        memcpy(s + 1 + N, smp->eta, N * sizeof *s);
        r->snap_next++;
    }
    return 0;
}

/* `note`, if not NULL, becomes a comment line (text format only). */
static int write_spacetime(const sim_plan *p, const sim_run *r, size_t frames, const char *note,
                           FILE *out, bkf_error *err)
{
    size_t N = p->m.params.N;
    double h = p->m.params.S / (double)N;
    if (p->spacetime_binary) {
        float *row = malloc((N + 1) * sizeof *row);
        if (!row) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
        row[0] = (float)N;
        for (size_t i = 0; i < N; i++) row[i + 1] = (float)((double)i * h);
        int bad = fwrite(row, sizeof *row, N + 1, out) != N + 1;
        for (size_t f = 0; f < frames && !bad; f++) {
            row[0] = (float)r->diag[f * SIM_NCOLUMNS];
            memcpy(row + 1, r->field + f * N, N * sizeof *row);
            bad = fwrite(row, sizeof *row, N + 1, out) != N + 1;
        }
        free(row);
        if (bad) return bkf_error_set(err, BKF_ENOMEM, "out of memory for the spacetime field");
        return BKF_OK;
    }
    fprintf(out, "# bkfront simulate: psi(x, t), gnuplot nonuniform matrix: first row N x_0 .. "
                 "x_{N-1}, then one row per t: t psi(x_0) .. psi(x_{N-1})\n"
                 "# plot 'FILE' nonuniform matrix using 1:2:3 with image\n");
    if (note) fprintf(out, "# %s\n", note);
    fprintf(out, "%zu", N);
    for (size_t i = 0; i < N; i++) fprintf(out, " %.9g", (double)i * h);
    fputc('\n', out);
    for (size_t f = 0; f < frames; f++) {
        fprintf(out, "%.17g", r->diag[f * SIM_NCOLUMNS]);
        for (size_t i = 0; i < N; i++) fprintf(out, " %.9g", (double)r->field[f * N + i]);
        fputc('\n', out);
    }
    return BKF_OK;
}

static int write_snapshots(const sim_plan *p, const sim_run *r, const char *note, FILE *out,
                           bkf_error *err)
{
    static const bkf_io_column cols[] = {
        {"t", BKF_IO_NUMBER}, {"x", BKF_IO_NUMBER}, {"psi", BKF_IO_NUMBER}, {"eta", BKF_IO_NUMBER}};
    size_t N = p->m.params.N;
    double h = p->m.params.S / (double)N;
    bkf_io_table *t = bkf_io_table_alloc(out, BKF_IO_TSV, cols, 4, err);
    if (!t) return BKF_ENOMEM;
    int s = bkf_io_table_comment(t, CLI_PROGRAM " " CLI_VERSION " simulate: snapshots of the "
                                    "field; readable by --init file:PATH (the last t)", err);
    if (!s && note) s = bkf_io_table_comment(t, note, err);
    if (!s && note)
        s = bkf_io_table_comment(t, "the last snapshot is the state where the run stopped: "
                                    "--init file:PATH continues from it", err);
    if (!s) s = comment_model(t, &p->m, err);
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

static int write_summary(bkf_io_table *t, const sim_plan *p, const sim_run *r,
                         const bkf_measure_summary *ms, const bkf_pde_front_info *fi,
                         double period_ref, int argc, char **argv, bkf_error *err)
{
    char a[32], b[32], c[32], d[32], e[32];
    int s = bkf_io_table_comment(t, CLI_PROGRAM " " CLI_VERSION " simulate: direct simulation of "
                                    "the elastic excitable medium", err);
    if (!s) s = comment_model(t, &p->m, err);
    if (!s) s = commentf(t, err, "init %s, seed %lu; tmax %s, %zu frames", p->init_text, p->m.seed,
                         num(p->m.tmax, a, sizeof a), p->frames);
    if (!s && p->init.kind == INIT_FRONT)
        s = commentf(t, err,
                     "front: n %zu, root %zu of %zu, v_pred %s (err %.2g), mu %s, T %s, period at "
                     "a point %s, direction %s",
                     p->init.front.n, p->init.front.root, fi->roots_for_n, num(fi->v, a, sizeof a),
                     fi->v_err, num(fi->mu, b, sizeof b), num(fi->T, c, sizeof c),
                     num(fi->period_fixed, d, sizeof d),
                     p->init.front.direction < 0 ? "-x (left)" : "+x (right)");
    if (!s && p->init.kind == INIT_OSCILLATION)
        s = commentf(t, err, "oscillation: mode j %zu, q %s, amp %s", p->init.j,
                     num(2 * PI * (double)p->init.j / p->m.params.S, a, sizeof a),
                     num(p->init.amp, b, sizeof b));
    if (!s) s = comment_command(t, argc, argv, err);
    const bkf_pde_stats *st = bkf_pde_get_stats(r->pde);
    if (!s)
        s = commentf(t, err, "work: %zu steps, %zu rejected, %zu rhs calls, step %s .. %s",
                     st->steps, st->rejected, st->rhs_calls, num(st->h_min, a, sizeof a),
                     num(st->h_max, b, sizeof b));
    if (!s) s = commentf(t, err, "regime: %s (window t >= %s)", bkf_regime_name(ms->regime),
                         num(ms->window_start, a, sizeof a));
    if (!s)
        s = commentf(t, err, "fronts are crossings of psi = %s with psi_t > 0 (hysteresis 0.1)",
                     num(p->level, a, sizeof a));
    if (!s)
        s = commentf(t, err, "fronts: %zu at start, %zu at end, %zu .. %zu in the window", ms->fronts_start,
                     ms->fronts_end, ms->fronts_min, ms->fronts_max);
    if (!s && isfinite(ms->speed))
        s = commentf(t, err,
                     "speed: %s +- %.3g (fitted from t = %s; %zu tracks, %zu towards -x, %zu "
                     "towards +x; negative: towards -x)",
                     num(ms->speed, a, sizeof a), ms->speed_err, num(ms->fit_start, b, sizeof b),
                     ms->tracks, ms->moving_minus, ms->moving_plus);
    if (!s && p->init.kind == INIT_FRONT && isfinite(ms->speed))
        s = commentf(t, err, "speed vs prediction: |v| %s, v_pred %s, relative difference %.3g",
                     num(fabs(ms->speed), a, sizeof a), num(fi->v, b, sizeof b),
                     (fabs(ms->speed) - fi->v) / fi->v);
    if (!s)
        s = commentf(t, err, "period at x = 0: %s +- %.3g (multiplicity %zu, %zu crossings in the "
                             "window); global oscillation period %s",
                     num(ms->period, a, sizeof a), ms->period_err, ms->period_multiplicity,
                     ms->crossings, period_ref > 0 ? num(period_ref, b, sizeof b) : "n/a");
    if (!s)
        s = commentf(t, err, "window: mean %s, variance %s, largest spatial std %s, psi in [%s, %s]",
                     num(ms->mean, a, sizeof a), num(ms->variance, b, sizeof b),
                     num(ms->std_max, c, sizeof c), num(ms->psi_min, d, sizeof d),
                     num(ms->psi_max, e, sizeof e));
    if (!s && p->init.kind == INIT_FRONT)
        s = commentf(t, err, "deviation from the seeded wave: start %.3g, window start %.3g, end "
                             "%.3g, growth rate %.3g",
                     ms->deviation_start, ms->deviation_mid, ms->deviation_end,
                     ms->deviation_growth);
    return s;
}

static int simulate_compute(sim_plan *p, int argc, char **argv, progress_bar *bar, FILE *out,
                            cli_buffer *st_buf, cli_buffer *sn_buf, bkf_error *err)
{
    size_t N = p->m.params.N;
    bkf_error e;
    sim_run r;
    memset(&r, 0, sizeof r);
    r.plan = p;
    double *clean = NULL;
    bkf_io_table *t = NULL;
    int s = BKF_OK;
    r.pde = bkf_pde_alloc(&p->m.params, &p->m.options, err);
    if (!r.pde) return BKF_ENOMEM;
    bkf_pde_front_info fi;
    memset(&fi, 0, sizeof fi);
    clean = malloc(N * sizeof *clean);
    r.diag = malloc((p->frames + 1) * SIM_NCOLUMNS * sizeof *r.diag);
    if (p->spacetime_path) r.field = malloc((p->frames + 1) * N * sizeof *r.field);
    if (p->snapshots_path) {
        /* one more: the state where an interrupted run stopped */
        r.snap = malloc((p->snapshots + 1) * (2 * N + 1) * sizeof *r.snap);
        r.snap_frame = malloc(p->snapshots * sizeof *r.snap_frame);
    }
    if (!clean || !r.diag || (p->spacetime_path && !r.field) ||
        (p->snapshots_path && (!r.snap || !r.snap_frame))) {
        s = bkf_error_set(err, BKF_ENOMEM, "out of memory");
        goto done;
    }
    if (p->snapshots_path)
        for (size_t k = 0; k < p->snapshots; k++)
            r.snap_frame[k] = p->snapshots == 1
                                  ? p->frames
                                  : (size_t)floor((double)k * (double)p->frames /
                                                      (double)(p->snapshots - 1) + 0.5);
    if ((s = apply_init(r.pde, &p->init, &p->m, &fi, clean, &e))) {
        bkf_error_set(err, s, "--init %s: %s", p->init_text, e.message);
        goto done;
    }
    double period_ref;
    double level = front_level(&p->m.params, &period_ref);
    if (!isnan(p->level)) level = p->level;
    p->level = level;
    bkf_measure_params mp = bkf_measure_params_default();
    mp.level = level;
    mp.N = N;
    mp.S = p->m.params.S;
    mp.gamma = p->m.params.gamma;
    mp.nu = p->m.params.nu;
    mp.period_ref = period_ref;
    mp.reference = p->init.kind == INIT_FRONT ? clean : NULL;
    r.meas = bkf_measure_alloc(&mp, err);
    if (!r.meas) {
        s = BKF_ENOMEM;
        goto done;
    }
    double frame_dt = p->m.tmax / (double)p->frames;
    r.per_frame = (size_t)ceil(frame_dt / SAMPLE_DT_MAX - 1e-9);
    if (r.per_frame < 1) r.per_frame = 1;
    double sample_dt = frame_dt / (double)r.per_frame;
    double t0 = bkf_pde_time(r.pde);
    s = bkf_pde_run(r.pde, t0 + p->m.tmax, sample_dt, sim_observe, &r, progress_draw, bar, &e);
    progress_end(bar);
    if (r.status) {
        s = r.status;
        *err = r.err;
        goto done;
    }
    /* Interrupted (SIGINT/SIGTERM through options.cancel): the frames
     * recorded so far are complete rows; they are written, marked. */
    int canceled = s == BKF_ECANCELED;
    if (s && !canceled) {
        bkf_error_set(err, s, "%s", e.message);
        goto done;
    }
    char interrupted[160] = "";
    if (canceled)
        snprintf(interrupted, sizeof interrupted,
                 "interrupted (%s) at t = %.9g of %.9g: %zu complete frames kept",
                 cli_cancel_signal() == SIGTERM ? "SIGTERM" : "SIGINT", bkf_pde_time(r.pde),
                 t0 + p->m.tmax, r.frame_index);
    /* The snapshots end with the state where the run stopped, so that
     * --init file:SNAPSHOTS continues from there. */
    if (canceled && r.snap && (r.snap_next == 0 ||
                               r.snap[(r.snap_next - 1) * (2 * N + 1)] < bkf_pde_time(r.pde))) {
        double *sn = r.snap + r.snap_next * (2 * N + 1);
        sn[0] = bkf_pde_time(r.pde);
        memcpy(sn + 1, bkf_pde_psi(r.pde), N * sizeof *sn);
        memcpy(sn + 1 + N, bkf_pde_eta(r.pde), N * sizeof *sn);
        r.snap_next++;
    }
    bkf_measure_summary ms;
    int have_summary = 0;
    if ((s = bkf_measure_summarize(r.meas, &ms, &e))) {
        if (!canceled) {
            bkf_error_set(err, BKF_ENUMERIC, "measurements: %s", e.message);
            goto done;
        }
    } else
        have_summary = 1;
    s = BKF_OK;
    t = bkf_io_table_alloc(out, p->m.format, sim_columns, SIM_NCOLUMNS, err);
    if (!t) {
        s = BKF_ENOMEM;
        goto done;
    }
    if (canceled) s = bkf_io_table_comment(t, interrupted, err);
    if (!s && have_summary) s = write_summary(t, p, &r, &ms, &fi, period_ref, argc, argv, err);
    if (!s && p->spacetime_path)
        s = commentf(t, err, "spacetime: %s (%s)", p->spacetime_path,
                     p->spacetime_binary ? "binary matrix, float32" : "text nonuniform matrix");
    for (size_t f = 0; !s && f < r.frame_index; f++) {
        bkf_io_value v[SIM_NCOLUMNS];
        for (size_t k = 0; k < SIM_NCOLUMNS; k++) v[k].number = r.diag[f * SIM_NCOLUMNS + k];
        s = bkf_io_table_row(t, v, err);
    }
    if (!s) s = bkf_io_table_finish(t, err);
    if (!s && p->spacetime_path)
        s = write_spacetime(p, &r, r.frame_index, canceled ? interrupted : NULL, st_buf->stream,
                            err);
    if (!s && p->snapshots_path)
        s = write_snapshots(p, &r, canceled ? interrupted : NULL, sn_buf->stream, err);
    if (!s && canceled) s = bkf_error_set(err, BKF_ECANCELED, "%s", interrupted);
done:
    bkf_io_table_free(t);
    bkf_measure_free(r.meas);
    bkf_pde_free(r.pde);
    free(clean);
    free(r.diag);
    free(r.field);
    free(r.snap);
    free(r.snap_frame);
    return s;
}

static int write_file(const char *path, const char *flag, cli_buffer *buf, bkf_error *err)
{
    cli_output o = {0};
    int s = cli_output_open(&o, path, flag, err);
    if (!s) s = cli_output_write(&o, buf->data, buf->size, err);
    return s;
}

static int simulate_run(int argc, char **argv, bkf_error *err)
{
    sim_plan plan;
    memset(&plan, 0, sizeof plan);
    cli_output out = {0};
    cli_buffer buf = {0}, st = {0}, sn = {0};
    progress_bar bar;
    int s = plan_simulate(argc, argv, &plan, err);
    if (!s) s = probe_path(plan.spacetime_path, "--spacetime", err);
    if (!s) s = probe_path(plan.snapshots_path, "--snapshots", err);
    if (!s) s = cli_output_open(&out, plan.m.out_path, "--out", err);
    if (!s) s = cli_buffer_open(&buf, err);
    if (!s && plan.spacetime_path) s = cli_buffer_open(&st, err);
    if (!s && plan.snapshots_path) s = cli_buffer_open(&sn, err);
    if (!s) {
        progress_init(&bar, CLI_PROGRAM " simulate", plan.progress);
        plan.m.options.cancel = cli_cancel_begin();
        s = simulate_compute(&plan, argc, argv, &bar, buf.stream, &st, &sn, err);
        cli_cancel_end();
        int ok = !s || s == BKF_ECANCELED;
        int c1 = cli_buffer_close(&buf, ok ? err : NULL);
        int c2 = cli_buffer_close(&st, ok ? err : NULL);
        int c3 = cli_buffer_close(&sn, ok ? err : NULL);
        if (ok && (c1 || c2 || c3)) s = c1 ? c1 : c2 ? c2 : c3;
    }
    /* An interrupted run writes what was complete (marked as interrupted),
     * then reports BKF_ECANCELED; its message is kept for the end. */
    int canceled = s == BKF_ECANCELED;
    bkf_error cancel_msg = *err;
    if (canceled) s = BKF_OK;
    if (!s && plan.spacetime_path) s = write_file(plan.spacetime_path, "--spacetime", &st, err);
    if (!s && plan.snapshots_path) s = write_file(plan.snapshots_path, "--snapshots", &sn, err);
    if (!s)
        s = cli_output_write(&out, buf.data, buf.size, err);
    else
        cli_output_abort(&out);
    if (!s && canceled) {
        s = BKF_ECANCELED;
        *err = cancel_msg;
    }
    cli_buffer_free(&buf);
    cli_buffer_free(&st);
    cli_buffer_free(&sn);
    init_free(&plan.init);
    return s;
}

const cli_command cli_cmd_simulate = {
    "simulate",
    "direct simulation (continuum or chain) with measurements, spacetime field, snapshots",
    simulate_run,
    simulate_help,
};

/* =============================================================== check */

/* With --grid uniform: resolves every n at the paper's parameters but
 * n = 12 (which needs N = 2^18 and ~16 minutes; README "The check's
 * budget"). */
#define DEF_N_MAX 65536
/* --grid auto: the uniform spectral grid while it resolves the wave on at
 * most this many points, the adapted comoving grid beyond (at the paper's
 * parameters n <= 9 uniform, n = 10 .. 12 adapted; from N = 16384 on the
 * adapted grid is the cheaper, and it does n = 12 in ~1.5 s). */
#define AUTO_UNIFORM_MAX 8192
/* Points per wavelength on the adapted grid and its tolerance: at 768 and
 * 1e-8 the paper-parameter speeds agree to ~2e-9 (README "The adapted
 * grid"); the tolerance well below the perturbation so that BDF's long
 * steps do not damp a growing perturbation unseen. */
#define DEF_POINTS 768
#define CHECK_MAPPED_TOL 1e-8
#define CHECK_MAPPED_SAMPLE_DT 0.5
/* The adapted grid's step budget per root: the paper's n = 10..12 take
 * 40-160 steps, an oscillating unstable wave (n = 3) ~2500; beyond this
 * the root is reported unresolved instead of running for many minutes. */
#define CHECK_MAPPED_MAX_STEPS 20000
#define DEF_REL_TOL 1e-6
#define DEF_PERTURB 1e-6
/* The seeded wave counts as resolved on N points when its Fourier
 * coefficients above N/3 are below this fraction of the largest. */
#define RESOLUTION_TOL 1e-5
/* Sample spacing of the check's measurements.  The exponential stepper
 * lands on every sample, so this is also its longest step; 0.25 is about
 * where its explicit friction term would limit the step anyway. */
#define CHECK_SAMPLE_DT 0.25
/* The check's default tolerance with the exponential stepper: its
 * estimate is the third-order embedded solution's error, far above the
 * fourth-order step's, and at 1e-7 the paper-parameter speeds and verdicts
 * are those of tol 1e-9 (README "The check's budget") at a third of the
 * cost. */
#define CHECK_ETD_TOL 1e-7

static void check_help(FILE *out)
{
    fprintf(out,
        "usage: bkfront check [--gamma G] [--c C] [--nu V] [--S S] [--n K] [--N N]\n"
        "                     [--N-max M] [--tmax T] [--tol E] [--rel-tol R] [--perturb A]\n"
        "                     [--seed K] [--stepper S] [--frame lab|moving]\n"
        "                     [--grid auto|uniform|mapped] [--points M]\n"
        "                     [--resolution R] [--no-progress] [--format tsv|json] [--out FILE]\n"
        "\n"
        "The predicted front speeds against direct simulation.  For every root of the\n"
        "speed-selection condition (every n, or only --n K) the travelling wave of n fronts\n"
        "at the predicted speed is seeded with a small perturbation and simulated; the\n"
        "measured speed is compared with the prediction and the run tells whether the\n"
        "front keeps its count and shape.\n"
        "\n"
        "options (defaults: the paper's gamma 2, c 0.3, nu -0.96, S 20):\n"
        "  --gamma G, --c C, --nu V, --S S   model parameters (|nu| < 1)\n"
        "  --n K             check n = K only; default every n with a root\n"
        "  --grid G          auto (default): the uniform spectral grid when it resolves the\n"
        "                    wave on N <= %d, else the adapted grid; uniform: always the\n"
        "                    spectral grid (up to --N-max); mapped: always the adapted grid\n"
        "                    (finite differences of order 8 on points placed by the wave's\n"
        "                    own length scales, in the frame of v_pred, CVODE in time;\n"
        "                    README \"The adapted grid\")\n"
        "  --points M        adapted grid: points per wavelength; default %d\n"
        "  --N N             smallest grid; each root runs on the smallest N = N 2^k that\n"
        "                    resolves its wave (Fourier coefficients above N/3 below %.0e of\n"
        "                    the largest); default %d\n"
        "  --N-max M         largest grid; roots needing more are reported unresolved and\n"
        "                    not simulated; default %d\n"
        "  --tmax T          length of each run; default 125\n"
        "  --stepper S       etdrk4 (default: exponential, the wave part of every mode\n"
        "                    exact, steps set by the physics), or rk8pd, rkck, rkf45\n"
        "                    (explicit, steps capped by the fastest wave mode ~ 1/N)\n"
        "  --tol E           local error tolerance; default %.0e with etdrk4, 1e-9 with\n"
        "                    the Runge-Kutta steppers, %.0e on the adapted grid\n"
        "  --filter F        spectral filter, as in bkfront simulate; default 4\n"
        "  --rel-tol R       agreement asked of a stable front, |v_meas - v_pred| / v_pred;\n"
        "                    default %.0e\n"
        "  --perturb A       rms of the band-limited noise added to the seeded wave;\n"
        "                    default %.0e\n"
        "  --seed K          seed of that noise; default 1\n"
        "  --resolution R    the spectral tail accepted as resolved; default %.0e\n"
        "  --frame lab|moving  simulate in the frame moving with v_pred (default), where\n"
        "                    the seeded wave is a steady state, or in the lab frame\n"
        "  --no-progress, --format tsv|json, --out FILE   as in bkfront simulate\n"
        "\n"
        "columns:\n"
        "  n, root           number of fronts and the root (1: fastest) of bkf_speeds_find\n"
        "  grid              uniform or mapped (the adapted grid)\n"
        "  N                 points of the grid used (0: unresolved within --N-max)\n"
        "  tail              the seed's spectral tail on the last uniform grid tried; on the\n"
        "                    adapted grid max |relaxed wave - seed| (its truncation error\n"
        "                    plus its drift during the relaxation)\n"
        "  v_pred, v_pred_err  predicted speed and its estimated error\n"
        "  v_meas, v_meas_err  measured speed (fronts move towards -x) and its uncertainty,\n"
        "                    fitted over [fit_from, fit_to]: the later half of the part of\n"
        "                    the run where the wave is coherent (front count kept and\n"
        "                    deviation <= max(100 perturb, 1e-6); on uniform grids with a\n"
        "                    tail above %.0e and on the adapted grid also 10 times the\n"
        "                    deviation at t = min(10, tmax/4))\n"
        "  rel_err           (v_meas - v_pred) / v_pred\n"
        "  fronts_start, fronts_end   front counts at t = 0 and t = tmax\n"
        "  deviation_start, deviation_mid, deviation_end\n"
        "                    max |psi - seeded wave shifted with the fronts| at t = 0,\n"
        "                    tmax/2 and tmax (adapted grid: the wave relaxed onto the grid)\n"
        "  growth            ln(deviation_end / deviation_mid) / (tmax/2): growth rate of\n"
        "                    the perturbation over the later half\n"
        "  stable            1 when the front count never changed and the perturbation did\n"
        "                    not grow over the later half (deviation_end <= 2 deviation_mid\n"
        "                    and <= 1e-2): count and shape kept over the run\n"
        "  verdict           agrees, disagrees (stable, rel_err beyond --rel-tol),\n"
        "                    unstable (not judged), unresolved (not run; or the adapted\n"
        "                    grid's run exceeded %d steps or could not be set up, with a\n"
        "                    warning on stderr)\n"
        "\n"
        "exit status: 0 ok, 1 a stable front disagrees (or a numerical failure), 2 bad input\n",
        AUTO_UNIFORM_MAX, DEF_POINTS, RESOLUTION_TOL, DEF_N, DEF_N_MAX, CHECK_ETD_TOL,
        CHECK_MAPPED_TOL, DEF_REL_TOL, DEF_PERTURB, RESOLUTION_TOL, RESOLUTION_TOL,
        CHECK_MAPPED_MAX_STEPS);
}

static const bkf_io_column check_columns[] = {
    {"n", BKF_IO_NUMBER},
    {"root", BKF_IO_NUMBER},
    {"grid", BKF_IO_TEXT},
    {"N", BKF_IO_NUMBER},
    {"tail", BKF_IO_NUMBER},
    {"v_pred", BKF_IO_NUMBER},
    {"v_pred_err", BKF_IO_NUMBER},
    {"v_meas", BKF_IO_NUMBER},
    {"v_meas_err", BKF_IO_NUMBER},
    {"rel_err", BKF_IO_NUMBER},
    {"fit_from", BKF_IO_NUMBER},
    {"fit_to", BKF_IO_NUMBER},
    {"fronts_start", BKF_IO_NUMBER},
    {"fronts_end", BKF_IO_NUMBER},
    {"deviation_start", BKF_IO_NUMBER},
    {"deviation_mid", BKF_IO_NUMBER},
    {"deviation_end", BKF_IO_NUMBER},
    {"growth", BKF_IO_NUMBER},
    {"stable", BKF_IO_NUMBER},
    {"verdict", BKF_IO_TEXT},
};
#define CHECK_NCOLUMNS (sizeof check_columns / sizeof check_columns[0])

typedef struct {
    model_plan m;
    size_t n;          /* 0: every n */
    size_t N_max;
    double rel_tol, perturb;
    double resolution; /* spectral tail accepted as resolved */
    int lab;           /* 1: simulate in the lab frame; 0: in the frame of v_pred */
    int grid;          /* 0 auto, 1 uniform, 2 mapped */
    size_t points;     /* adapted grid: points per wavelength */
    double mapped_tol;
    int progress;
} check_plan;

static int plan_check(int argc, char **argv, check_plan *p, bkf_error *err)
{
    model_flags mf = {0};
    const char *n = NULL, *nmax = NULL, *reltol = NULL, *perturb = NULL, *frame = NULL,
               *resol = NULL, *grid = NULL, *points = NULL;
    int help = 0, noprog = 0;
    const cli_flag flags[] = {
        {"--gamma", &mf.gamma, "a number > 0", NULL},
        {"--c", &mf.c, "a number >= 0", NULL},
        {"--nu", &mf.nu, "a number in (-1, 1)", NULL},
        {"--S", &mf.S, "a number > 0", NULL},
        {"--n", &n, "an integer >= 1", NULL},
        {"--N", &mf.N, "an even integer >= 8", NULL},
        {"--N-max", &nmax, "an even integer >= 8", NULL},
        {"--tmax", &mf.tmax, "a number > 0", NULL},
        {"--tol", &mf.tol, "a number in [1e-13, 0.01]", NULL},
        {"--filter", &mf.filter, "a number in [0, 1000]", NULL},
        {"--stepper", &mf.stepper, "rk8pd, rkck, rkf45 or etdrk4", NULL},
        {"--rel-tol", &reltol, "a number in (0, 1)", NULL},
        {"--perturb", &perturb, "a number in [0, 0.1]", NULL},
        {"--seed", &mf.seed, "an integer >= 0", NULL},
        {"--frame", &frame, "lab or moving", NULL},
        {"--grid", &grid, "auto, uniform or mapped", NULL},
        {"--points", &points, "an integer in [32, 1048576]", NULL},
        {"--resolution", &resol, "a number in [1e-16, 1]", NULL},
        {"--no-progress", NULL, NULL, &noprog},
        {"--format", &mf.format, "tsv or json", NULL},
        {"--out", &mf.out, "a file name", NULL},
        {"--help", NULL, NULL, &help},
    };
    int s = cli_parse_flags(flags, sizeof flags / sizeof flags[0], argc, argv, err);
    if (s) return s;
    if (!mf.stepper) mf.stepper = "etdrk4";
    if ((s = plan_model(&mf, &p->m, err))) return s;
    p->mapped_tol = mf.tol ? p->m.options.tol : CHECK_MAPPED_TOL;
    if (!mf.tol && p->m.options.stepper == BKF_PDE_ETDRK4) p->m.options.tol = CHECK_ETD_TOL;
    p->grid = 0;
    if (grid) {
        static const char *const grid_names[] = {"auto", "uniform", "mapped", NULL};
        if ((s = cli_parse_choice("--grid", grid, grid_names, &p->grid, err))) return s;
    }
    p->points = DEF_POINTS;
    if (points) {
        if ((s = cli_parse_count("--points", points, (size_t)1 << 20, &p->points, err))) return s;
        if (p->points < 32)
            return bkf_error_set(err, BKF_EINPUT, "--points: %s is outside [32, 1048576]",
                                 points);
    }
    p->lab = 0;
    if (frame) {
        static const char *const frame_names[] = {"moving", "lab", NULL};
        if ((s = cli_parse_choice("--frame", frame, frame_names, &p->lab, err))) return s;
    }
    if (p->grid == 2 && p->lab)
        return bkf_error_set(err, BKF_EINPUT,
                             "--frame: lab is not available with --grid mapped (the adapted grid "
                             "moves with v_pred)");
    if (p->lab && p->grid == 0) p->grid = 1;

    p->resolution = RESOLUTION_TOL;
    if (resol) {
        if ((s = cli_parse_double("--resolution", resol, &p->resolution, err))) return s;
        if (!(p->resolution >= 1e-16 && p->resolution <= 1))
            return bkf_error_set(err, BKF_EINPUT, "--resolution: %s is outside [1e-16, 1]", resol);
    }
    bkf_error e;
    if (bkf_model_check_nu_active(p->m.params.nu, &e))
        return bkf_error_set(err, BKF_EINPUT, "--nu: %s; there are no fronts", e.message);
    if (p->m.params.gamma < BKF_CYCLE_MU_MIN || p->m.params.gamma > BKF_CYCLE_MU_MAX)
        return bkf_error_set(err, BKF_EINPUT, "--gamma: %g is outside [%g, %g]",
                             p->m.params.gamma, BKF_CYCLE_MU_MIN, BKF_CYCLE_MU_MAX);
    p->n = 0;
    if (n && (s = cli_parse_count("--n", n, 100000, &p->n, err))) return s;
    p->N_max = DEF_N_MAX;
    if (nmax && (s = cli_parse_count("--N-max", nmax, BKF_PDE_N_MAX, &p->N_max, err))) return s;
    if (p->N_max < p->m.params.N)
        return bkf_error_set(err, BKF_EINPUT, "--N-max: %zu is below --N = %zu", p->N_max,
                             p->m.params.N);
    p->rel_tol = DEF_REL_TOL;
    if (reltol) {
        if ((s = cli_parse_double("--rel-tol", reltol, &p->rel_tol, err))) return s;
        if (!(p->rel_tol > 0 && p->rel_tol < 1))
            return bkf_error_set(err, BKF_EINPUT, "--rel-tol: %s is outside (0, 1)", reltol);
    }
    p->perturb = DEF_PERTURB;
    if (perturb) {
        if ((s = cli_parse_double("--perturb", perturb, &p->perturb, err))) return s;
        if (!(p->perturb >= 0 && p->perturb <= 0.1))
            return bkf_error_set(err, BKF_EINPUT, "--perturb: %s is outside [0, 0.1]", perturb);
    }
    p->progress = !noprog;
    return BKF_OK;
}

typedef struct {
    bkf_measure *meas;
    int status;
    bkf_error err;
} check_obs;

static int check_observe(const bkf_pde_sample *smp, void *data)
{
    check_obs *o = data;
    bkf_error e;
    if (bkf_measure_add(o->meas, smp->t, smp->psi, smp->eta, &e)) {
        o->status = bkf_error_set(&o->err, BKF_ENUMERIC, "measurement at t = %g: %s", smp->t,
                                  e.message);
        return 1;
    }
    return 0;
}

typedef struct {
    size_t n, root, N;
    const char *grid;
    double tail;
    double v_pred, v_pred_err, v_meas, v_meas_err, rel_err, fit_from, fit_to;
    double fronts_start, fronts_end, dev_start, dev_mid, dev_end, growth, stable;
    const char *verdict;
} check_row;

/* One root on the adapted comoving grid (bkf_comoving): the same
 * measurements and verdicts as on the uniform grid. */
static int check_root_mapped(const check_plan *p, const bkf_speeds_root *sr, progress_bar *bar,
                             check_row *row, bkf_error *err)
{
    row->grid = "mapped";
    bkf_comoving_params cp = bkf_comoving_params_default();
    cp.gamma = p->m.params.gamma;
    cp.c = p->m.params.c;
    cp.nu = p->m.params.nu;
    cp.S = p->m.params.S;
    cp.n = row->n;
    cp.v = sr->v;
    cp.points = p->points;
    cp.tol = p->mapped_tol;
    cp.noise = p->perturb;
    cp.seed = p->m.seed;
    cp.cancel = p->m.options.cancel;
    cp.max_steps = CHECK_MAPPED_MAX_STEPS;
    double period_ref;
    cp.level = front_level(&p->m.params, &period_ref);
    bkf_error e;
    bkf_comoving *cm = bkf_comoving_alloc(&cp, &e);
    if (!cm) {
        if (strstr(e.message, "out of memory"))
            return bkf_error_set(err, BKF_ENOMEM, "n = %zu: out of memory", row->n);
        /* this root cannot be set up on this grid (the other roots still
         * can): a row, not the end of the table */
        fprintf(stderr, CLI_PROGRAM " check: warning: n = %zu, root %zu reported unresolved: %s\n",
                row->n, row->root, e.message);
        row->verdict = "unresolved";
        return BKF_OK;
    }
    row->N = bkf_comoving_size(cm);
    bkf_comoving_stats st;
    bkf_comoving_get_stats(cm, &st);
    row->tail = st.relax_change;
    int s = bkf_comoving_run(cm, p->m.tmax, CHECK_MAPPED_SAMPLE_DT, progress_draw, bar, &e);
    int broke = 0;
    bkf_comoving_get_stats(cm, &st);
    if (s == BKF_ENUMERIC && st.blew_up && bkf_comoving_count(cm) >= 2) {
        broke = 1; /* a blown-up front is a result (unstable) */
        s = BKF_OK;
    } else if (s == BKF_ENUMERIC && st.over_budget) {
        /* not a verdict: the run was too costly to finish */
        bkf_comoving_free(cm);
        row->verdict = "unresolved";
        return BKF_OK;
    }
    if (s) {
        bkf_comoving_free(cm);
        return bkf_error_set(err, s, "n = %zu, root %zu, adapted grid of %zu points: %s", row->n,
                             row->root, row->N, e.message);
    }
    size_t R = bkf_comoving_count(cm);
    const bkf_comoving_record *first = bkf_comoving_record_at(cm, 0),
                              *last = bkf_comoving_record_at(cm, R - 1), *mid = last;
    int constant = 1;
    for (size_t r = 0; r < R; r++) {
        const bkf_comoving_record *rc = bkf_comoving_record_at(cm, r);
        if (rc->fronts != first->fronts) constant = 0;
        if (rc->t >= 0.5 * last->t && mid == last) mid = rc;
    }
    row->fronts_start = (double)first->fronts;
    row->fronts_end = (double)last->fronts;
    row->dev_start = first->deviation;
    row->dev_mid = mid->deviation;
    row->dev_end = last->deviation;
    row->growth = last->t > mid->t ? log(last->deviation / mid->deviation) / (last->t - mid->t)
                                   : NAN;
    int kept = !broke && constant && first->fronts == row->n && isfinite(row->dev_end) &&
               row->dev_end <= 2 * row->dev_mid && row->dev_end <= 1e-2;
    row->stable = kept;
    /* coherent part, as on the uniform grid; the relaxed wave's own
     * deviation plateau (set by the resolution) counts as coherent */
    double coherent = fmax(100 * p->perturb, 1e-6);
    double t_ref = fmin(10.0, 0.25 * p->m.tmax);
    for (size_t r = 0; r < R; r++) {
        const bkf_comoving_record *rc = bkf_comoving_record_at(cm, r);
        if (rc->t < t_ref) continue;
        if (rc->fronts == row->n && isfinite(rc->deviation))
            coherent = fmax(coherent, 10 * rc->deviation);
        break;
    }
    size_t end = 0;
    for (size_t r = 0; r < R; r++) {
        const bkf_comoving_record *rc = bkf_comoving_record_at(cm, r);
        if (rc->fronts != row->n || !(rc->deviation <= coherent)) break;
        end = r;
    }
    double t_end = bkf_comoving_record_at(cm, end)->t;
    if (end >= 6) {
        double drift, drift_err;
        if (bkf_comoving_fit_drift(cm, 0.5 * t_end, t_end, &drift, &drift_err, &e) == BKF_OK) {
            /* the frame moves with the fronts towards -x at v_pred */
            row->v_meas = sr->v - drift;
            row->v_meas_err = drift_err;
            row->rel_err = -drift / sr->v;
            row->fit_from = 0.5 * t_end;
            row->fit_to = t_end;
        }
    }
    bkf_comoving_free(cm);
    if (!kept) row->verdict = "unstable";
    else if (isfinite(row->rel_err) && fabs(row->rel_err) <= p->rel_tol) row->verdict = "agrees";
    else row->verdict = "disagrees";
    return BKF_OK;
}

/* One root: resolution, the perturbed run, its measurements. */
static int check_root(const check_plan *p, size_t n, size_t root, const bkf_speeds_root *sr,
                      progress_bar *bar, check_row *row, bkf_error *err)
{
    memset(row, 0, sizeof *row);
    row->n = n;
    row->root = root;
    row->v_pred = sr->v;
    row->v_pred_err = sr->v_err;
    row->v_meas = row->v_meas_err = row->rel_err = row->fit_from = row->fit_to = NAN;
    row->tail = NAN;
    row->fronts_start = row->fronts_end = NAN;
    row->dev_start = row->dev_mid = row->dev_end = row->growth = row->stable = NAN;
    bkf_pde_params pp = p->m.params;
    bkf_pde_options po = p->m.options;
    /* The seeded fronts move towards -x at v_pred: in that frame the wave is
     * a steady state and the steps grow to the stability cap. */
    po.frame_speed = p->lab ? 0.0 : -sr->v;
    bkf_pde_front_spec fs = bkf_pde_front_spec_default();
    fs.n = n;
    fs.root = root;
    fs.noise = p->perturb;
    fs.seed = p->m.seed;
    bkf_error e;
    bkf_pde *pde = NULL;
    double *clean = NULL;
    bkf_measure *meas = NULL;
    bkf_pde_front_info fi;
    int s = BKF_OK;
    row->grid = "uniform";
    if (p->grid == 2) return check_root_mapped(p, sr, bar, row, err);
    size_t N_cap = p->grid == 0 ? (p->N_max < AUTO_UNIFORM_MAX ? p->N_max : AUTO_UNIFORM_MAX)
                                : p->N_max;
    for (size_t N = p->m.params.N;; N *= 2) {
        if (N > N_cap) {
            if (p->grid == 0) {
                bkf_pde_free(pde);
                free(clean);
                return check_root_mapped(p, sr, bar, row, err);
            }
            row->verdict = "unresolved";
            goto done;
        }
        pp.N = N;
        bkf_pde_free(pde);
        free(clean);
        pde = bkf_pde_alloc(&pp, &po, err);
        clean = malloc(N * sizeof *clean);
        if (!pde || !clean) {
            s = pde ? bkf_error_set(err, BKF_ENOMEM, "out of memory") : BKF_ENOMEM;
            goto done;
        }
        if ((s = bkf_pde_init_front(pde, &fs, &fi, clean, &e))) {
            bkf_error_set(err, s, "n = %zu, root %zu: %s", n, root, e.message);
            goto done;
        }
        row->tail = bkf_pde_spectral_tail(pde, clean);
        if (row->tail <= p->resolution) break;
    }
    row->N = pp.N;
    bkf_measure_params mp = bkf_measure_params_default();
    mp.N = pp.N;
    mp.S = pp.S;
    mp.gamma = pp.gamma;
    mp.nu = pp.nu;
    mp.reference = clean;
    double period_ref;
    mp.level = front_level(&pp, &period_ref);
    if (!(meas = bkf_measure_alloc(&mp, err))) {
        s = BKF_ENOMEM;
        goto done;
    }
    check_obs ob = {meas, 0, {{0}}};
    s = bkf_pde_run(pde, p->m.tmax, CHECK_SAMPLE_DT, check_observe, &ob, progress_draw, bar, &e);
    if (ob.status) {
        s = ob.status;
        *err = ob.err;
        goto done;
    }
    int broke = 0;
    if (s == BKF_ENUMERIC && bkf_measure_count(meas) >= 2) {
        /* A blown-up front is a result (unstable), not a failure of the check. */
        broke = 1;
        s = BKF_OK;
    }
    if (s) {
        bkf_error_set(err, s, "n = %zu, root %zu, N = %zu: %s", n, root, pp.N, e.message);
        goto done;
    }
    bkf_measure_summary ms;
    if ((s = bkf_measure_summarize(meas, &ms, &e))) {
        bkf_error_set(err, BKF_ENUMERIC, "n = %zu: %s", n, e.message);
        goto done;
    }
    row->fronts_start = (double)ms.fronts_start;
    row->fronts_end = (double)ms.fronts_end;
    row->dev_start = ms.deviation_start;
    row->dev_mid = ms.deviation_mid;
    row->dev_end = ms.deviation_end;
    row->growth = ms.deviation_growth;
    int kept = !broke && ms.count_constant && ms.fronts_start == n && isfinite(ms.deviation_end) &&
               ms.deviation_end <= 2 * ms.deviation_mid && ms.deviation_end <= 1e-2;
    row->stable = kept;
    /* coherent part: count kept and deviation small, from the start on.
     * Small: below 100 times the perturbation, or below 10 times the
     * deviation at t_ref = min(10, tmax/4), by when a wave that is not
     * fully resolved has settled into the grid's own travelling wave (its
     * deviation from the seed is then a plateau set by the resolution, not
     * a growing perturbation).  Only on such grids (tail above the default
     * rule's RESOLUTION_TOL). */
    double coherent = fmax(100 * p->perturb, 1e-6);
    size_t R = bkf_measure_count(meas), last = 0;
    double t_ref = fmin(10.0, 0.25 * p->m.tmax);
    for (size_t r = 0; row->tail > RESOLUTION_TOL && r < R; r++) {
        const bkf_measure_record *rc = bkf_measure_record_at(meas, r);
        if (rc->t < t_ref) continue;
        if (rc->fronts == n && isfinite(rc->deviation))
            coherent = fmax(coherent, 10 * rc->deviation);
        break;
    }
    for (size_t r = 0; r < R; r++) {
        const bkf_measure_record *rc = bkf_measure_record_at(meas, r);
        if (rc->fronts != n || !(rc->deviation <= coherent)) break;
        last = r;
    }
    double t_end = bkf_measure_record_at(meas, last)->t;
    if (last >= 6) {
        double t_from = 0.5 * t_end;
        double v, ve;
        if (bkf_measure_fit_speed(meas, t_from, t_end, &v, &ve, NULL, &e) == BKF_OK) {
            /* v is relative to the frame; towards -x in the lab: -(v + V) */
            row->v_meas = -(v + po.frame_speed);
            row->v_meas_err = ve;
            row->rel_err = -(v + po.frame_speed + sr->v) / sr->v;
            row->fit_from = t_from;
            row->fit_to = t_end;
        }
    }
    if (!kept) row->verdict = "unstable";
    else if (isfinite(row->rel_err) && fabs(row->rel_err) <= p->rel_tol) row->verdict = "agrees";
    else row->verdict = "disagrees";
done:
    bkf_measure_free(meas);
    bkf_pde_free(pde);
    free(clean);
    return s;
}

static int check_compute(const check_plan *p, int argc, char **argv, progress_bar *bar, FILE *out,
                         int *disagree, bkf_error *err)
{
    char a[32], b[32], c[32], d[32], f[32];
    bkf_speeds_params sp = {p->m.params.gamma, p->m.params.c, p->m.params.nu, p->m.params.S};
    bkf_speeds_options so = bkf_speeds_options_default();
    so.tol = 1e-12;
    if (p->n) so.n_from = so.n_to = p->n;
    bkf_speeds_table tab;
    memset(&tab, 0, sizeof tab);
    bkf_error e;
    int s = bkf_speeds_find(&sp, &so, &tab, &e);
    if (s) {
        bkf_speeds_table_free(&tab);
        return bkf_error_set(err, s, "speeds: %s", e.message);
    }
    check_row *rows = calloc(tab.count ? tab.count : 1, sizeof *rows);
    if (!rows) {
        bkf_speeds_table_free(&tab);
        return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    }
    size_t done = 0;
    for (size_t i = 0; !s && i < tab.count; i++) {
        size_t root = 1;
        for (size_t k = i; k > 0 && tab.roots[k - 1].n == tab.roots[i].n; k--) root++;
        bar->base = (double)i / (double)tab.count;
        bar->share = 1.0 / (double)tab.count;
        s = check_root(p, tab.roots[i].n, root, &tab.roots[i], bar, &rows[i], err);
        if (!s) done++;
    }
    progress_end(bar);
    bkf_io_table *t = NULL;
    if (!s) {
        t = bkf_io_table_alloc(out, p->m.format, check_columns, CHECK_NCOLUMNS, err);
        if (!t) s = BKF_ENOMEM;
    }
    if (!s)
        s = bkf_io_table_comment(t, CLI_PROGRAM " " CLI_VERSION " check: predicted front speeds "
                                    "against seeded simulations", err);
    if (!s) s = comment_model(t, &p->m, err);
    if (!s)
        s = commentf(t, err, "frame: %s", p->lab ? "lab" : "moving with v_pred of each root");
    if (!s)
        s = commentf(t, err,
                     "tmax %s, perturbation rms %s (seed %lu), agreement asked %s, grid %s: "
                     "uniform %zu .. %zu (resolution %.0e, samples every %s), adapted %zu points "
                     "per wavelength (tol %.0e, samples every %g)",
                     num(p->m.tmax, a, sizeof a), num(p->perturb, b, sizeof b), p->m.seed,
                     num(p->rel_tol, c, sizeof c),
                     p->grid == 0 ? "auto" : p->grid == 1 ? "uniform" : "mapped", p->m.params.N,
                     p->grid == 0 && p->N_max > AUTO_UNIFORM_MAX ? (size_t)AUTO_UNIFORM_MAX
                                                                  : p->N_max,
                     p->resolution, num(CHECK_SAMPLE_DT, d, sizeof d), p->points, p->mapped_tol,
                     CHECK_MAPPED_SAMPLE_DT);
    if (!s)
        s = commentf(t, err, "speeds: k(nu) %s, n_max %ld, %zu roots%s%s",
                     num(tab.k, f, sizeof f), tab.n_max, tab.count, tab.note[0] ? "; " : "",
                     tab.note);
    if (!s) s = comment_command(t, argc, argv, err);
    size_t stable = 0, agree = 0, unres = 0;
    *disagree = 0;
    for (size_t i = 0; i < tab.count; i++) {
        stable += rows[i].stable == 1;
        agree += rows[i].verdict && strcmp(rows[i].verdict, "agrees") == 0;
        unres += rows[i].verdict && strcmp(rows[i].verdict, "unresolved") == 0;
        *disagree += rows[i].verdict && strcmp(rows[i].verdict, "disagrees") == 0;
    }
    if (!s) {
        char list[512] = "";
        for (size_t i = 0; i < tab.count; i++)
            if (rows[i].stable == 1) {
                size_t used = strlen(list);
                snprintf(list + used, sizeof list - used, "%s%zu", used ? ", " : "", rows[i].n);
            }
        s = commentf(t, err, "summary: %zu stable (n = %s), %zu agree, %d disagree, %zu unresolved",
                     stable, stable ? list : "none", agree, *disagree, unres);
    }
    for (size_t i = 0; !s && i < tab.count; i++) {
        const check_row *r = &rows[i];
        bkf_io_value v[CHECK_NCOLUMNS] = {
            {.number = (double)r->n},   {.number = (double)r->root}, {.text = r->grid},
            {.number = (double)r->N},
            {.number = r->tail},        {.number = r->v_pred},      {.number = r->v_pred_err},   {.number = r->v_meas},
            {.number = r->v_meas_err},  {.number = r->rel_err},      {.number = r->fit_from},
            {.number = r->fit_to},      {.number = r->fronts_start}, {.number = r->fronts_end},
            {.number = r->dev_start},   {.number = r->dev_mid},      {.number = r->dev_end},
            {.number = r->growth},      {.number = r->stable},       {.text = r->verdict},
        };
        s = bkf_io_table_row(t, v, err);
    }
    if (!s) s = bkf_io_table_finish(t, err);
    bkf_io_table_free(t);
    free(rows);
    bkf_speeds_table_free(&tab);
    return s;
}

static int check_run(int argc, char **argv, bkf_error *err)
{
    check_plan plan;
    memset(&plan, 0, sizeof plan);
    cli_output out = {0};
    cli_buffer buf = {0};
    progress_bar bar;
    int disagree = 0;
    int s = plan_check(argc, argv, &plan, err);
    if (!s) s = cli_output_open(&out, plan.m.out_path, "--out", err);
    if (!s) s = cli_buffer_open(&buf, err);
    if (!s) {
        progress_init(&bar, CLI_PROGRAM " check", plan.progress);
        s = check_compute(&plan, argc, argv, &bar, buf.stream, &disagree, err);
        int c = cli_buffer_close(&buf, s ? NULL : err);
        if (!s) s = c;
    }
    if (!s)
        s = cli_output_write(&out, buf.data, buf.size, err);
    else
        cli_output_abort(&out);
    cli_buffer_free(&buf);
    if (!s && disagree)
        return bkf_error_set(err, BKF_ENUMERIC,
                             "%d stable front(s) disagree with the predicted speed beyond "
                             "--rel-tol %g (see the table)", disagree, plan.rel_tol);
    return s;
}

const cli_command cli_cmd_check = {
    "check",
    "predicted front speeds against seeded simulations: agreement and stability per n",
    check_run,
    check_help,
};

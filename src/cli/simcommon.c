#define _POSIX_C_SOURCE 200809L
#include "simcommon.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "bkfront/measure.h"
#include "bkfront/model.h"

const char *const format_names[] = {"tsv", "json", NULL};
const char *const model_names[] = {"continuum", "chain", NULL};
const char *const stepper_names[] = {"rk8pd", "rkck", "rkf45", "etdrk4", NULL};
const char *const spacetime_names[] = {"text", "binary", NULL};
const char *num(double x, char *buf, size_t size)
{
    snprintf(buf, size, "%.15g", x);
    if (strtod(buf, NULL) != x) snprintf(buf, size, "%.17g", x);
    return buf;
}

double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* ------------------------------------------------------------ progress */


void progress_init(progress_bar *p, const char *label, int allowed)
{
    memset(p, 0, sizeof *p);
    p->enabled = allowed && isatty(STDERR_FILENO);
    p->start = now_seconds();
    p->label = label;
    p->share = 1.0;
}

int progress_draw(double fraction, void *data)
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

void progress_end(progress_bar *p)
{
    if (p->drawn) {
        fprintf(stderr, "\r\033[K");
        fflush(stderr);
    }
    p->drawn = 0;
}

/* ---------------------------------------------------- shared parameters */



int parse_positive(const char *flag, const char *text, double *v, bkf_error *err)
{
    int s = cli_parse_double(flag, text, v, err);
    if (s) return s;
    if (!(*v > 0)) return bkf_error_set(err, BKF_EINPUT, "%s: %s must be > 0", flag, text);
    return BKF_OK;
}

int parse_seed(const char *text, unsigned long *seed, bkf_error *err)
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

int plan_model(const model_flags *f, model_plan *p, bkf_error *err)
{
    int s;
    char a[32];
    p->params = (bkf_model_params){DEF_GAMMA, DEF_C, DEF_NU, DEF_S, DEF_N, BKF_MODEL_CONTINUUM};
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
        p->params.kind = k ? BKF_MODEL_CHAIN : BKF_MODEL_CONTINUUM;
    }
    p->N_given = f->N != NULL;
    if (f->N) {
        size_t n;
        if ((s = cli_parse_count("--N", f->N, BKF_PDE_N_MAX, &n, err))) return s;
        if (n < BKF_PDE_N_MIN)
            return bkf_error_set(err, BKF_EINPUT, "--N: %zu is below %d", n, BKF_PDE_N_MIN);
        if (p->params.kind == BKF_MODEL_CONTINUUM && n % 2)
            return bkf_error_set(err, BKF_EINPUT,
                                 "--N: %zu must be even for the continuum model (spectral)", n);
        p->params.N = n;
    } else if (p->params.kind == BKF_MODEL_CHAIN) {
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
    if (f->dealias && p->params.kind != BKF_MODEL_CONTINUUM)
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

int comment_command(bkf_io_table *t, int argc, char **argv, bkf_error *err)
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

int commentf(bkf_io_table *t, bkf_error *err, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
int commentf(bkf_io_table *t, bkf_error *err, const char *fmt, ...)
{
    char line[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    return bkf_io_table_comment(t, line, err);
}

int comment_model(bkf_io_table *t, const model_plan *p, bkf_error *err)
{
    char a[32], b[32], c[32], d[32], e[32], f[32], g[32];
    return commentf(t, err,
                    "model %s: gamma %s, c %s, nu %s, S %s, N %zu (h = %s); tol %s, stepper %s, "
                    "dealias %s, filter %s",
                    model_names[p->params.kind], num(p->params.gamma, a, sizeof a),
                    num(p->params.c, b, sizeof b), num(p->params.nu, c, sizeof c),
                    num(p->params.S, d, sizeof d), p->params.N,
                    num(p->params.S / (double)p->params.N, e, sizeof e),
                    num(p->options.tol, f, sizeof f), stepper_names[p->options.stepper],
                    p->options.dealias ? "on (2/3 rule)" : "off",
                    p->params.kind == BKF_MODEL_CHAIN || p->options.filter == 0
                        ? "off"
                        : num(p->options.filter, g, sizeof g));
}


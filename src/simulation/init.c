/* Initial states from their one-line specifications, and the sampling of a
 * run (see include/bkfront/init.h). */
#define _POSIX_C_SOURCE 200809L
#include "bkfront/init.h"

#include "bkfront/options.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bkfront/cycle.h"

#define TWO_PI 6.28318530717958647692

#define INIT_FORM                                                                          \
    "uniform[:amp=A], oscillation[:q=Q|j=J][,amp=A][,noise=E], "                        \
    "front:n=K[,root=R][,dir=left|right]"                                                  \
    "[,noise=E], or file:PATH"

/* The numbers of a specification read as the CLI reads its flags' (a
 * decimal number, no hex floats, no infinities or NaN), with its messages. */
static int is_nonfinite_word(const char *s)
{
    if (*s == '+' || *s == '-') s++;
    static const char *const words[] = {"nan", "inf", "infinity"};
    for (size_t i = 0; i < sizeof words / sizeof words[0]; i++) {
        size_t n = strlen(words[i]), j = 0;
        for (; j < n && s[j]; j++)
            if ((s[j] | 0x20) != words[i][j]) break;
        if (j == n && (s[j] == '\0' || s[j] == '(')) return 1;
    }
    return 0;
}

static int read_number(const char *key, const char *text, double *value, bkf_error *err)
{
    char a[72];
    const char *what = NULL;
    double x = 0;
    if (is_nonfinite_word(text))
        what = "is not a finite number";
    else if (!*text || strspn(text, "0123456789+-.eE") != strlen(text))
        what = "is not a number";
    else {
        char *end;
        errno = 0;
        x = strtod(text, &end);
        if (end == text || *end != '\0') what = "is not a number";
        else if (!isfinite(x)) what = "is too large for a double";
    }
    if (what)
        return bkf_error_set(err, BKF_EINPUT,
                             "%s: '%s' %s (expected a finite decimal number such as 2, -0.5 or "
                             "1e-3)", key, bkf_io_shown(text, a, sizeof a), what);
    *value = x;
    return BKF_OK;
}

static int read_count(const char *key, const char *text, size_t max, size_t *value,
                      bkf_error *err)
{
    size_t n = 0;
    int ok = *text && strspn(text, "0123456789") == strlen(text);
    for (const char *p = text; ok && *p; p++) {
        size_t d = (size_t)(*p - '0');
        if (d > max || n > (max - d) / 10) ok = 0; /* n * 10 + d > max */
        else n = n * 10 + d;
    }
    if (!ok || n < 1) {
        char a[72];
        return bkf_error_set(err, BKF_EINPUT, "%s: '%s' is not an integer in [1, %zu]", key,
                             bkf_io_shown(text, a, sizeof a), max);
    }
    *value = n;
    return BKF_OK;
}


/* key=value,key=value after the colon; each key handled by `take`. */
static int parse_pairs(const char *text, const char *kind,
                       int (*take)(const char *key, const char *value, bkf_init_spec *spec,
                                   bkf_error *err),
                       bkf_init_spec *spec, bkf_error *err)
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
                                 bkf_io_shown(tok, shown, sizeof shown), INIT_FORM);
        *eq = '\0';
        int s = take(tok, eq + 1, spec, err);
        if (s) return s;
    }
    return BKF_OK;
}

static int take_amp(const char *kind, const char *key, const char *value, double *amp,
                    bkf_error *err)
{
    char flag[64];
    snprintf(flag, sizeof flag, "--init %s %s", kind, key);
    int s = read_number(flag, value, amp, err);
    if (s) return s;
    if (!(*amp >= 0 && *amp <= 10))
        return bkf_error_set(err, BKF_EINPUT, "%s: %s is outside [0, 10]", flag, value);
    return BKF_OK;
}

static int take_uniform(const char *key, const char *value, bkf_init_spec *p, bkf_error *err)
{
    if (strcmp(key, "amp") == 0) return take_amp("uniform", key, value, &p->amp, err);
    char a[72];
    return bkf_error_set(err, BKF_EINPUT, "--init uniform: unknown key '%s' (amp)",
                         bkf_io_shown(key, a, sizeof a));
}

static int take_oscillation(const char *key, const char *value, bkf_init_spec *p,
                            bkf_error *err)
{
    if (strcmp(key, "amp") == 0) return take_amp("oscillation", key, value, &p->amp, err);
    if (strcmp(key, "noise") == 0) return take_amp("oscillation", key, value, &p->noise, err);
    if (strcmp(key, "q") == 0) {
        int s = read_number("--init oscillation q", value, &p->q, err);
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
        return read_count("--init oscillation j", value, BKF_PDE_N_MAX, &p->j, err);
    }
    char a[72];
    return bkf_error_set(err, BKF_EINPUT, "--init oscillation: unknown key '%s' (q, j, amp, noise)",
                         bkf_io_shown(key, a, sizeof a));
}

static int take_front(const char *key, const char *value, bkf_init_spec *p, bkf_error *err)
{
    char a[72];
    if (strcmp(key, "n") == 0) return read_count("--init front n", value, 100000, &p->front.n, err);
    if (strcmp(key, "root") == 0)
        return read_count("--init front root", value, 100, &p->front.root, err);
    if (strcmp(key, "noise") == 0) return take_amp("front", key, value, &p->front.noise, err);
    if (strcmp(key, "dir") == 0) {
        if (strcmp(value, "left") == 0) p->front.direction = -1;
        else if (strcmp(value, "right") == 0) p->front.direction = 1;
        else
            return bkf_error_set(err, BKF_EINPUT, "--init front dir: '%s' is not left or right",
                                 bkf_io_shown(value, a, sizeof a));
        return BKF_OK;
    }
    return bkf_error_set(err, BKF_EINPUT, "--init front: unknown key '%s' (n, root, dir, noise)",
                         bkf_io_shown(key, a, sizeof a));
}

void bkf_init_free(bkf_init_spec *spec)
{
    if (!spec) return;
    free(spec->path);
    spec->path = NULL;
    bkf_io_state_free(&spec->state);
}

int bkf_init_parse(const char *text, bkf_init_spec *p, bkf_error *err)
{
    if (!p) return bkf_error_set(err, BKF_EINPUT, "--init: spec is NULL");
    memset(p, 0, sizeof *p);
    p->front = bkf_pde_front_spec_default();
    p->seed = 1;
    if (!text) return bkf_error_set(err, BKF_EINPUT, "--init: the text is NULL");
    const char *colon = strchr(text, ':');
    size_t klen = colon ? (size_t)(colon - text) : strlen(text);
    const char *rest = colon ? colon + 1 : "";
    if (klen == 7 && strncmp(text, "uniform", 7) == 0) {
        p->kind = BKF_INIT_UNIFORM;
        p->amp = 1e-3;
        return parse_pairs(rest, "uniform", take_uniform, p, err);
    }
    if (klen == 11 && strncmp(text, "oscillation", 11) == 0) {
        p->kind = BKF_INIT_OSCILLATION;
        return parse_pairs(rest, "oscillation", take_oscillation, p, err);
    }
    if (klen == 5 && strncmp(text, "front", 5) == 0) {
        p->kind = BKF_INIT_FRONT;
        int have_n = strstr(rest, "n=") == rest || strstr(rest, ",n=");
        int s = parse_pairs(rest, "front", take_front, p, err);
        if (s) return s;
        if (!have_n)
            return bkf_error_set(err, BKF_EINPUT, "--init front: n=K is required (%s)", INIT_FORM);
        return BKF_OK;
    }
    if (klen == 4 && strncmp(text, "file", 4) == 0) {
        p->kind = BKF_INIT_FILE;
        if (!*rest) return bkf_error_set(err, BKF_EINPUT, "--init file: give a path, file:PATH");
        p->path = strdup(rest);
        if (!p->path) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
        return BKF_OK;
    }
    char a[72];
    return bkf_error_set(err, BKF_EINPUT, "--init: '%s' is not one of %s",
                         bkf_io_shown(text, a, sizeof a), INIT_FORM);
}

int bkf_init_load(bkf_init_spec *p, bkf_error *err)
{
    if (!p) return bkf_error_set(err, BKF_EINPUT, "--init: spec is NULL");
    if (p->kind != BKF_INIT_FILE) return BKF_OK;
    char path[72];
    bkf_io_shown(p->path, path, sizeof path);
    bkf_io_state_free(&p->state);
    FILE *f = fopen(p->path, "r");
    if (!f) return bkf_error_set(err, BKF_EIO, "--init file:%s: %s", path, strerror(errno));
    bkf_error e;
    int s = bkf_io_read_state(f, BKF_INIT_FILE_ROWS_MAX, &p->state, &e);
    fclose(f);
    if (s) return bkf_error_set(err, s, "--init file:%s: %s", path, e.message);
    if (p->state.rows < BKF_PDE_N_MIN) {
        size_t rows = p->state.rows;
        bkf_io_state_free(&p->state);
        return bkf_error_set(err, BKF_EINPUT, "--init file:%s: %zu rows, need at least %d", path,
                             rows, BKF_PDE_N_MIN);
    }
    return BKF_OK;
}

int bkf_init_check(bkf_init_spec *ip, bkf_model_params *model, int N_given,
                   const bkf_pde_options *options, bkf_error *err)
{
    if (!ip || !model) return bkf_error_set(err, BKF_EINPUT, "--init: spec or model is NULL");
    char a[32], b[32], path[72];
    bkf_error e;
    if (ip->kind == BKF_INIT_FILE) {
        bkf_io_shown(ip->path, path, sizeof path);
        if (!ip->state.psi)
            return bkf_error_set(err, BKF_EINPUT, "--init file:%s: not loaded", path);
        if (N_given && model->N != ip->state.rows)
            return bkf_error_set(err, BKF_EINPUT, "--N: %zu differs from the %zu rows of --init "
                                                  "file:%s", model->N, ip->state.rows, path);
        model->N = ip->state.rows;
        if (bkf_pde_check(model, options, &e))
            return bkf_error_set(err, BKF_EINPUT, "--init file:%s: %s", path, e.message);
    }
    if (ip->kind == BKF_INIT_OSCILLATION || ip->kind == BKF_INIT_FRONT) {
        if (bkf_model_check_nu_active(model->nu, &e))
            return bkf_error_set(err, BKF_EINPUT, "--init %s needs a limit cycle: --nu: %s",
                                 ip->kind == BKF_INIT_FRONT ? "front" : "oscillation", e.message);
        if (model->gamma < BKF_CYCLE_MU_MIN || model->gamma > BKF_CYCLE_MU_MAX)
            return bkf_error_set(err, BKF_EINPUT, "--gamma: %s is outside [%g, %g] (the cycle "
                                                  "engine's range of mu)",
                                 bkf_format_number(model->gamma, a, sizeof a), BKF_CYCLE_MU_MIN,
                                 BKF_CYCLE_MU_MAX);
    }
    if (ip->kind == BKF_INIT_OSCILLATION) {
        if (ip->q_given) ip->j = (size_t)floor(ip->q * model->S / TWO_PI + 0.5);
        if (ip->j >= model->N / 2)
            return bkf_error_set(err, BKF_EINPUT,
                                 "--init oscillation: mode j = %zu (q = %s) is not below N/2 = %zu",
                                 ip->j, bkf_format_number(TWO_PI * (double)ip->j / model->S, b, sizeof b),
                                 model->N / 2);
    }
    return BKF_OK;
}

int bkf_init_apply(bkf_pde *pde, const bkf_init_spec *spec, bkf_error *err)
{
    if (!spec) return bkf_error_set(err, BKF_EINPUT, "spec is NULL");
    switch (spec->kind) {
    case BKF_INIT_UNIFORM: return bkf_pde_init_uniform(pde, spec->amp, spec->seed, err);
    case BKF_INIT_OSCILLATION: {
        int s = bkf_pde_init_oscillation(pde, spec->j, spec->amp, err);
        if (!s && spec->noise > 0) s = bkf_pde_add_noise(pde, spec->noise, spec->seed, err);
        return s;
    }
    case BKF_INIT_FILE:
        if (!spec->state.psi) return bkf_error_set(err, BKF_EINPUT, "the state file is not loaded");
        if (pde && bkf_pde_size(pde) != spec->state.rows)
            return bkf_error_set(err, BKF_EINPUT, "the state has %zu rows, the simulation N = %zu",
                                 spec->state.rows, bkf_pde_size(pde));
        return bkf_pde_set_state(pde, spec->state.psi, spec->state.eta, 0.0, err);
    default:
        return bkf_error_set(err, BKF_EINPUT, "a front needs the speeds solver: bkf_seed_init");
    }
}

int bkf_init_sampling_plan(double tmax, size_t frames, double max_dt, bkf_init_sampling *out,
                           bkf_error *err)
{
    if (!out) return bkf_error_set(err, BKF_EINPUT, "sampling is NULL");
    if (!(isfinite(tmax) && tmax > 0))
        return bkf_error_set(err, BKF_EINPUT, "tmax = %g must be finite and > 0", tmax);
    if (!(isfinite(max_dt) && max_dt > 0))
        return bkf_error_set(err, BKF_EINPUT, "max_dt = %g must be finite and > 0", max_dt);
    if (frames < 1) return bkf_error_set(err, BKF_EINPUT, "frames must be >= 1");
    out->frame_dt = tmax / (double)frames;
    /* the 1e-9 keeps a frame_dt of exactly k max_dt at k samples */
    double per = ceil(out->frame_dt / max_dt - 1e-9);
    if (!(per <= 1e15))
        return bkf_error_set(err, BKF_EINPUT, "tmax/frames = %g needs too many samples of %g",
                             out->frame_dt, max_dt);
    out->per_frame = per < 1 ? 1 : (size_t)per;
    out->sample_dt = out->frame_dt / (double)out->per_frame;
    return BKF_OK;
}

size_t bkf_init_snapshot_frame(size_t k, size_t count, size_t frames)
{
    if (count <= 1) return frames;
    return (size_t)floor((double)k * (double)frames / (double)(count - 1) + 0.5);
}

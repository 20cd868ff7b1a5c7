/* open_memstream and sigaction are POSIX 2008. */
#define _POSIX_C_SOURCE 200809L
#include "args.h"

#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define NUMBER_FORM "a finite decimal number such as 2, -0.5 or 1e-3"

/* User text inside a one-line message: control characters would break the
 * line and a pasted megabyte would drown it. */
static const char *shown(const char *text, char *buf, size_t size)
{
    size_t n = 0, limit = size - 4;
    const unsigned char *s = (const unsigned char *)text;
    for (; *s && n < limit; s++) buf[n++] = (*s < 0x20 || *s == 0x7f) ? '?' : (char)*s;
    if (*s) {
        memcpy(buf + n, "...", 3);
        n += 3;
    }
    buf[n] = '\0';
    return buf;
}

const char *cli_shown(const char *text, char *buf, size_t size)
{
    return shown(text ? text : "", buf, size);
}

static int is_nonfinite_word(const char *s)
{
    if (*s == '+' || *s == '-') s++;
    static const char *const words[] = {"nan", "inf", "infinity"};
    for (size_t i = 0; i < sizeof words / sizeof words[0]; i++) {
        size_t n = strlen(words[i]);
        size_t j = 0;
        for (; j < n && s[j]; j++)
            if ((s[j] | 0x20) != words[i][j]) break;
        if (j == n && (s[j] == '\0' || s[j] == '(')) return 1;
    }
    return 0;
}

typedef enum { NUM_OK, NUM_MALFORMED, NUM_NONFINITE, NUM_OVERFLOW } number_verdict;

static number_verdict read_double(const char *text, double *value)
{
    if (is_nonfinite_word(text)) return NUM_NONFINITE;
    /* Only the characters of a decimal number: this is what shuts out
     * strtod's hex floats, nan(...), infinities and leading white space. */
    if (!*text || strspn(text, "0123456789+-.eE") != strlen(text)) return NUM_MALFORMED;
    char *end;
    errno = 0;
    double x = strtod(text, &end);
    if (end == text || *end != '\0') return NUM_MALFORMED;
    /* ERANGE on underflow still gives a usable (tiny or zero) value. */
    if (!isfinite(x)) return NUM_OVERFLOW;
    *value = x;
    return NUM_OK;
}

/* "--mu: 'abc' is not a number (...)", or with a context such as
 * "in range '1:abc:3'" after the quoted part. */
static int number_error(bkf_error *err, const char *flag, const char *part,
                        const char *context, number_verdict verdict)
{
    char a[72], b[72];
    const char *what = verdict == NUM_NONFINITE ? "is not a finite number"
                       : verdict == NUM_OVERFLOW ? "is too large for a double"
                                                 : "is not a number";
    if (context)
        return bkf_error_set(err, BKF_EINPUT, "%s: '%s' in '%s' %s (expected %s)", flag,
                             shown(part, a, sizeof a), shown(context, b, sizeof b), what,
                             NUMBER_FORM);
    return bkf_error_set(err, BKF_EINPUT, "%s: '%s' %s (expected %s)", flag,
                         shown(part, a, sizeof a), what, NUMBER_FORM);
}

int cli_parse_double(const char *flag, const char *text, double *value, bkf_error *err)
{
    double x = 0;
    number_verdict v = read_double(text ? text : "", &x);
    if (v != NUM_OK) return number_error(err, flag, text ? text : "", NULL, v);
    *value = x;
    return BKF_OK;
}

static int read_count(const char *text, size_t max, size_t *value)
{
    if (!*text || strspn(text, "0123456789") != strlen(text)) return 0;
    size_t n = 0;
    for (const char *p = text; *p; p++) {
        size_t d = (size_t)(*p - '0');
        if (d > max || n > (max - d) / 10) return 0;  /* n * 10 + d > max */
        n = n * 10 + d;
    }
    if (n < 1) return 0;
    *value = n;
    return 1;
}

int cli_parse_count(const char *flag, const char *text, size_t max, size_t *value,
                    bkf_error *err)
{
    char a[72];
    if (!read_count(text ? text : "", max, value))
        return bkf_error_set(err, BKF_EINPUT, "%s: '%s' is not an integer in [1, %zu]", flag,
                             shown(text ? text : "", a, sizeof a), max);
    return BKF_OK;
}

int cli_parse_choice(const char *flag, const char *text, const char *const *choices,
                     int *index, bkf_error *err)
{
    char list[256] = "", a[72];
    for (int i = 0; choices[i]; i++) {
        if (text && strcmp(text, choices[i]) == 0) {
            *index = i;
            return BKF_OK;
        }
        size_t used = strlen(list);
        snprintf(list + used, sizeof list - used, "%s%s", i ? ", " : "", choices[i]);
    }
    return bkf_error_set(err, BKF_EINPUT, "%s: '%s' is not one of %s", flag,
                         shown(text ? text : "", a, sizeof a), list);
}

void cli_range_free(cli_range *range)
{
    if (!range) return;
    free(range->values);
    range->values = NULL;
    range->count = 0;
}

int cli_parse_range(const char *flag, const char *text, int geometric, cli_range *range,
                    bkf_error *err)
{
    char a[72], b[72];
    const char *form = geometric ? "a number > 0 or a geometric range A:B:N with A, B > 0"
                                 : "a number or a range A:B:N";
    *range = (cli_range){0};
    if (!text) text = "";
    const char *c1 = strchr(text, ':');
    const char *c2 = c1 ? strchr(c1 + 1, ':') : NULL;
    if ((c1 && !c2) || (c2 && strchr(c2 + 1, ':')))
        return bkf_error_set(err, BKF_EINPUT, "%s: '%s' is not %s", flag,
                             shown(text, a, sizeof a), form);

    double from = 0, to = 0;
    size_t count = 1;
    if (!c1) {
        number_verdict v = read_double(text, &from);
        if (v != NUM_OK) return number_error(err, flag, text, NULL, v);
        to = from;
    } else {
        size_t la = (size_t)(c1 - text), lb = (size_t)(c2 - c1 - 1);
        char *pa = malloc(la + 1), *pb = malloc(lb + 1);
        if (!pa || !pb) {
            free(pa);
            free(pb);
            return bkf_error_set(err, BKF_ENOMEM, "%s: out of memory", flag);
        }
        memcpy(pa, text, la);
        pa[la] = '\0';
        memcpy(pb, c1 + 1, lb);
        pb[lb] = '\0';
        number_verdict va = read_double(pa, &from), vb = read_double(pb, &to);
        int status = BKF_OK;
        if (va != NUM_OK)
            status = number_error(err, flag, pa, text, va);
        else if (vb != NUM_OK)
            status = number_error(err, flag, pb, text, vb);
        free(pa);
        free(pb);
        if (status) return status;
        if (!read_count(c2 + 1, CLI_MAX_POINTS, &count))
            return bkf_error_set(err, BKF_EINPUT,
                                 "%s: N = '%s' in '%s' is not an integer in [1, %u]", flag,
                                 shown(c2 + 1, a, sizeof a), shown(text, b, sizeof b),
                                 CLI_MAX_POINTS);
        if (count == 1 && from != to)
            return bkf_error_set(err, BKF_EINPUT,
                                 "%s: '%s' has N = 1 point, so A and B must be equal "
                                 "(or give the single value A)", flag, shown(text, a, sizeof a));
        range->is_range = 1;
    }
    if (geometric && !(from > 0 && to > 0))
        return bkf_error_set(err, BKF_EINPUT,
                             "%s: '%s' is not %s (--log makes the points geometric)", flag,
                             shown(text, a, sizeof a), form);

    double *values = malloc(count * sizeof *values);
    if (!values) return bkf_error_set(err, BKF_ENOMEM, "%s: out of memory", flag);
    double la = geometric ? log(from) : 0, lb = geometric ? log(to) : 0;
    for (size_t i = 0; i < count; i++) {
        double t = count > 1 ? (double)i / (double)(count - 1) : 0.0;
        /* Weighted sum rather than from + i h: no overflow for ends of
         * opposite sign near DBL_MAX, and t = 0 and 1 give the ends. */
        values[i] = geometric ? exp(la * (1 - t) + lb * t) : from * (1 - t) + to * t;
    }
    values[0] = from;
    values[count - 1] = to;
    range->values = values;
    range->count = count;
    range->from = from;
    range->to = to;
    return BKF_OK;
}

int cli_parse_flags(const cli_flag *flags, size_t nflags, int argc, char **argv,
                    bkf_error *err)
{
    char a[72];
    unsigned char given[64] = {0};
    if (nflags > sizeof given) return bkf_error_set(err, BKF_EINPUT, "too many flags in table");
    for (int i = 1; i < argc; i++) {
        const char *arg = argv[i];
        if (strncmp(arg, "--", 2) != 0 || arg[2] == '\0') {
            return bkf_error_set(err, BKF_EINPUT, "unexpected argument '%s' (options start with --)",
                                 shown(arg, a, sizeof a));
        }
        const char *eq = strchr(arg, '=');
        size_t len = eq ? (size_t)(eq - arg) : strlen(arg);
        size_t k = 0;
        while (k < nflags && !(strlen(flags[k].name) == len && strncmp(flags[k].name, arg, len) == 0))
            k++;
        if (k == nflags) {
            char list[512] = "";
            for (size_t j = 0; j < nflags; j++) {
                size_t used = strlen(list);
                snprintf(list + used, sizeof list - used, "%s%s", j ? ", " : "", flags[j].name);
            }
            char name[64];
            size_t n = len < sizeof name - 1 ? len : sizeof name - 1;
            memcpy(name, arg, n);
            name[n] = '\0';
            return bkf_error_set(err, BKF_EINPUT, "unknown option '%s' (options: %s)",
                                 shown(name, a, sizeof a), list);
        }
        const cli_flag *f = &flags[k];
        if (given[k])
            return bkf_error_set(err, BKF_EINPUT, "%s: given twice (give it once)", f->name);
        given[k] = 1;
        if (f->seen) *f->seen = 1;
        if (!f->value) {
            if (eq) return bkf_error_set(err, BKF_EINPUT, "%s: takes no value", f->name);
            continue;
        }
        if (eq)
            *f->value = eq + 1;
        else if (i + 1 < argc)
            *f->value = argv[++i];
        else
            return bkf_error_set(err, BKF_EINPUT, "%s: missing value (expected %s)", f->name,
                                 f->form ? f->form : "a value");
    }
    return BKF_OK;
}

int cli_wants_help(int argc, char **argv)
{
    for (int i = 1; i < argc; i++)
        if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) return 1;
    return 0;
}

/* Safe unquoted in sh: letters, digits and a few punctuation marks. */
static int shell_plain(const char *s)
{
    if (!*s) return 0;
    for (; *s; s++) {
        unsigned char c = (unsigned char)*s;
        if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
              strchr("-_./:=+,@%", c)))
            return 0;
    }
    return 1;
}

char *cli_command_line(int argc, char **argv)
{
    size_t cap = 1;
    for (int i = 0; i < argc; i++) cap += 4 * strlen(argv[i]) + 3;
    char *line = malloc(cap), *p = line;
    if (!line) return NULL;
    for (int i = 0; i < argc; i++) {
        if (i) *p++ = ' ';
        const char *s = argv[i];
        if (i == 0) {
            /* The program's name, not wherever it happened to be run from. */
            const char *slash = strrchr(s, '/');
            if (slash) s = slash + 1;
        }
        if (shell_plain(s)) {
            size_t n = strlen(s);
            memcpy(p, s, n);
            p += n;
            continue;
        }
        *p++ = '\'';
        for (; *s; s++) {
            if (*s == '\'') {
                memcpy(p, "'\\''", 4);
                p += 4;
            } else
                *p++ = ((unsigned char)*s < 0x20 || *s == 0x7f) ? '?' : *s;
        }
        *p++ = '\'';
    }
    *p = '\0';
    return line;
}

/* --------------------------------------------------------------- output */

/* Signals.  While an output file's temporary exists (at most
 * CLI_MAX_PENDING at once) or a cancellable computation runs, SIGINT,
 * SIGTERM and SIGHUP are caught by on_signal:
 *  - during a cancellable computation the first SIGINT or SIGTERM only
 *    records itself in cancel_flag (the computation stops at its next check
 *    and the command keeps what was complete);
 *  - otherwise (a second signal, SIGHUP, or nothing cancellable) every
 *    pending temporary is unlinked and the process dies of the signal, so
 *    the exit status still says which signal it was.
 * Only async-signal-safe calls in the handler: unlink, signal, raise.
 * A signal that was ignored when the handlers went in (nohup) stays ignored. */
#define CLI_MAX_PENDING 4
static char pending_temp[CLI_MAX_PENDING][4096];
static volatile sig_atomic_t pending_armed[CLI_MAX_PENDING];
static volatile sig_atomic_t cancel_active, cancel_flag;
static const int caught_signals[] = {SIGINT, SIGTERM, SIGHUP};
#define NCAUGHT (sizeof caught_signals / sizeof caught_signals[0])
static struct sigaction saved_actions[NCAUGHT];
static int handlers_installed;

static void on_signal(int sig)
{
    if (cancel_active && !cancel_flag && sig != SIGHUP) {
        cancel_flag = sig;
        return;
    }
    for (size_t i = 0; i < CLI_MAX_PENDING; i++)
        if (pending_armed[i]) unlink(pending_temp[i]);
    signal(sig, SIG_DFL);
    raise(sig); /* delivered when the handler returns (sig is blocked in it) */
}

static void update_handlers(void)
{
    int needed = cancel_active;
    for (size_t i = 0; i < CLI_MAX_PENDING; i++) needed |= pending_armed[i];
    if (needed && !handlers_installed) {
        struct sigaction sa;
        memset(&sa, 0, sizeof sa);
        sa.sa_handler = on_signal;
        sigfillset(&sa.sa_mask); /* one handler at a time */
        for (size_t i = 0; i < NCAUGHT; i++) {
            sigaction(caught_signals[i], &sa, &saved_actions[i]);
            if (saved_actions[i].sa_handler == SIG_IGN)
                sigaction(caught_signals[i], &saved_actions[i], NULL);
        }
        handlers_installed = 1;
    } else if (!needed && handlers_installed) {
        for (size_t i = 0; i < NCAUGHT; i++) sigaction(caught_signals[i], &saved_actions[i], NULL);
        handlers_installed = 0;
    }
}

/* The slot now guarding `temp`, or -1 (no slot free, or a path too long:
 * the file is still written atomically, only a signal may leave its
 * temporary behind, as SIGKILL may). */
static int arm_cleanup(const char *temp)
{
    size_t n = strlen(temp);
    if (n >= sizeof pending_temp[0]) return -1;
    for (int i = 0; i < CLI_MAX_PENDING; i++)
        if (!pending_armed[i]) {
            memcpy(pending_temp[i], temp, n + 1);
            pending_armed[i] = 1;
            update_handlers();
            return i;
        }
    return -1;
}

static void disarm_cleanup(int slot)
{
    if (slot < 0 || slot >= CLI_MAX_PENDING || !pending_armed[slot]) return;
    pending_armed[slot] = 0;
    update_handlers();
}

const volatile sig_atomic_t *cli_cancel_begin(void)
{
    cancel_flag = 0;
    cancel_active = 1;
    update_handlers();
    return &cancel_flag;
}

void cli_cancel_end(void)
{
    cancel_active = 0;
    update_handlers();
}

int cli_cancel_signal(void) { return (int)cancel_flag; }

int cli_exit_code(int status)
{
    switch (status) {
    case BKF_OK: return 0;
    case BKF_EINPUT: return 2;
    case BKF_ECANCELED: return 128 + (cli_cancel_signal() ? cli_cancel_signal() : SIGINT);
    default: return 1;
    }
}

int cli_output_open(cli_output *out, const char *path, const char *flag, bkf_error *err)
{
    out->file = NULL;
    if (!path) return BKF_OK;
    bkf_error e;
    out->file = bkf_io_atomic_open(path, &e);
    if (!out->file) return bkf_error_set(err, BKF_EINPUT, "%s: %s", flag, e.message);
    out->slot = arm_cleanup(bkf_io_atomic_temp_path(out->file));
    return BKF_OK;
}

int cli_output_write(cli_output *out, const char *data, size_t size, bkf_error *err)
{
    if (!out->file) {
        if ((size && fwrite(data, 1, size, stdout) != size) || fflush(stdout) != 0)
            return bkf_error_set(err, BKF_EIO, "cannot write to standard output: %s",
                                 strerror(errno));
        return BKF_OK;
    }
    FILE *f = bkf_io_atomic_stream(out->file);
    int status = BKF_OK;
    if (size && fwrite(data, 1, size, f) != size) {
        status = bkf_error_set(err, BKF_EIO, "writing the output failed: %s",
                               strerror(errno));
        bkf_io_atomic_abort(out->file);
    } else
        status = bkf_io_atomic_commit(out->file, err);
    out->file = NULL;
    disarm_cleanup(out->slot);
    return status;
}

void cli_output_abort(cli_output *out)
{
    if (!out || !out->file) return;
    bkf_io_atomic_abort(out->file);
    out->file = NULL;
    disarm_cleanup(out->slot);
}

int cli_buffer_open(cli_buffer *buf, bkf_error *err)
{
    buf->data = NULL;
    buf->size = 0;
    buf->stream = open_memstream(&buf->data, &buf->size);
    if (!buf->stream) return bkf_error_set(err, BKF_ENOMEM, "out of memory for the output");
    return BKF_OK;
}

int cli_buffer_close(cli_buffer *buf, bkf_error *err)
{
    if (!buf->stream) return BKF_OK;
    int bad = ferror(buf->stream);
    int closed = fclose(buf->stream);
    buf->stream = NULL;
    if (bad || closed != 0) return bkf_error_set(err, BKF_ENOMEM, "out of memory for the output");
    return BKF_OK;
}

void cli_buffer_free(cli_buffer *buf)
{
    if (!buf) return;
    if (buf->stream) fclose(buf->stream);
    buf->stream = NULL;
    free(buf->data);
    buf->data = NULL;
    buf->size = 0;
}

/* open_memstream and sigaction are POSIX 2008. */
#define _POSIX_C_SOURCE 200809L
#include "args.h"

#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <string.h>
#include <unistd.h>

static const char *shown(const char *text, char *buf, size_t size)
{
    return bkf_option_shown(text, buf, size);
}

const char *cli_shown(const char *text, char *buf, size_t size)
{
    return bkf_option_shown(text, buf, size);
}

int cli_parse_double(const char *flag, const char *text, double *value, bkf_error *err)
{
    return bkf_option_parse_double(text, "", flag, value, err);
}

int cli_parse_count(const char *flag, const char *text, size_t max, size_t *value,
                    bkf_error *err)
{
    return bkf_option_parse_count(text, 1, max, "", flag, value, err);
}

int cli_parse_choice(const char *flag, const char *text, const char *const *choices,
                     int *index, bkf_error *err)
{
    return bkf_option_parse_choice(text, choices, "", flag, index, err);
}

void cli_range_free(cli_range *range) { bkf_list_free(range); }

int cli_parse_range(const char *flag, const char *text, int geometric, cli_range *range,
                    bkf_error *err)
{
    return bkf_list_parse(text, geometric, 0, CLI_MAX_POINTS, "", flag, range, err);
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

#define CLI_MAX_OPTIONS 64

int cli_parse_options(const cli_options *groups, size_t ngroups, int argc, char **argv,
                      int *help, bkf_error *err)
{
    char names[CLI_MAX_OPTIONS][48], forms[CLI_MAX_OPTIONS][160];
    const char *values[CLI_MAX_OPTIONS] = {0};
    int seen[CLI_MAX_OPTIONS] = {0}, wants_help = 0;
    cli_flag flags[CLI_MAX_OPTIONS + 1];
    const bkf_option *opts[CLI_MAX_OPTIONS];
    void *specs[CLI_MAX_OPTIONS];
    size_t n = 0;
    for (size_t g = 0; g < ngroups; g++)
        for (size_t i = 0; i < groups[g].n; i++) {
            const bkf_option *o = &groups[g].table[i];
            if (o->flags & BKF_OPT_SCENE_ONLY) continue;
            if (n == CLI_MAX_OPTIONS)
                return bkf_error_set(err, BKF_EINPUT, "too many options in the tables");
            snprintf(names[n], sizeof names[n], "--%s", o->name);
            if (o->type == BKF_OPT_CUSTOM || !o->form)
                bkf_option_describe(o, forms[n], sizeof forms[n]);
            else
                snprintf(forms[n], sizeof forms[n], "%s", o->form);
            flags[n] = (cli_flag){names[n], o->type == BKF_OPT_SWITCH ? NULL : &values[n],
                                  forms[n], &seen[n]};
            opts[n] = o;
            specs[n] = groups[g].spec;
            n++;
        }
    flags[n] = (cli_flag){"--help", NULL, NULL, &wants_help};
    int s = cli_parse_flags(flags, n + 1, argc, argv, err);
    if (help) *help = wants_help;
    if (s) return s;
    for (size_t k = 0; k < n; k++)
        if (!seen[k] && (opts[k]->flags & BKF_OPT_REQUIRED)) {
            char form[160];
            return bkf_error_set(err, BKF_EINPUT, "%s is required (%s)", names[k],
                                 bkf_option_describe(opts[k], form, sizeof form));
        }
    for (size_t k = 0; k < n; k++)
        if (seen[k] && (s = bkf_option_apply(opts[k], specs[k], values[k], "--", err))) return s;
    return BKF_OK;
}

void cli_options_help(FILE *out, const cli_options *groups, size_t ngroups)
{
    for (size_t g = 0; g < ngroups; g++)
        for (size_t i = 0; i < groups[g].n; i++) {
            const bkf_option *o = &groups[g].table[i];
            if (o->flags & BKF_OPT_SCENE_ONLY) continue;
            char head[96];
            int len = snprintf(head, sizeof head, "  --%s%s%s", o->name, o->form ? " " : "",
                               o->form ? o->form : "");
            const char *h = o->help ? o->help : "";
            /* The first help line beside the flag when it fits, else below. */
            if (len < 20)
                fprintf(out, "%-20s", head);
            else
                fprintf(out, "%s\n%20s", head, "");
            size_t line = 0;
            for (;;) {
                line = strcspn(h, "\n");
                fprintf(out, "%.*s", (int)line, h);
                h += line;
                if (!*h) break;
                h++;
                fprintf(out, "\n%20s", "");
            }
            /* The default on the last help line if it fits in 79 columns. */
            if (o->shown_default) {
                if (20 + line + 10 + strlen(o->shown_default) <= 79)
                    fprintf(out, "; default %s", o->shown_default);
                else
                    fprintf(out, "\n%20sdefault %s", "", o->shown_default);
            }
            fputc('\n', out);
        }
    fprintf(out, "%-20s%s\n", "  --help", "this text");
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

int cli_guard_temp(const char *temp) { return arm_cleanup(temp); }

void cli_unguard_temp(int slot) { disarm_cleanup(slot); }

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
    out->device = NULL;
    if (!path) return BKF_OK;
    bkf_error e;
    struct stat st;
    char shown_path[72];
    if (stat(path, &st) == 0 && S_ISCHR(st.st_mode)) {
        out->device = fopen(path, "w");
        if (!out->device)
            return bkf_error_set(err, BKF_EINPUT, "%s: cannot open '%s': %s", flag,
                                 cli_shown(path, shown_path, sizeof shown_path), strerror(errno));
        return BKF_OK;
    }
    out->file = bkf_io_atomic_open(path, &e);
    if (!out->file) return bkf_error_set(err, BKF_EINPUT, "%s: %s", flag, e.message);
    out->slot = arm_cleanup(bkf_io_atomic_temp_path(out->file));
    return BKF_OK;
}

int cli_output_write(cli_output *out, const char *data, size_t size, bkf_error *err)
{
    if (out->device) {
        int bad = (size && fwrite(data, 1, size, out->device) != size);
        bad |= fclose(out->device) != 0;
        out->device = NULL;
        if (bad) return bkf_error_set(err, BKF_EIO, "writing the output failed: %s",
                                      strerror(errno));
        return BKF_OK;
    }
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
    if (out && out->device) {
        fclose(out->device);
        out->device = NULL;
    }
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

static const char *const format_names[] = {"tsv", "json", NULL};

const bkf_option cli_output_options[] = {
    {.name = "format", .type = BKF_OPT_CHOICE, .offset = offsetof(cli_output_spec, format),
     .flags = BKF_OPT_CLI_ONLY, .choices = format_names, .form = "tsv|json",
     .shown_default = "tsv", .help = "output format"},
    {.name = "out", .type = BKF_OPT_TEXT, .offset = offsetof(cli_output_spec, out),
     .flags = BKF_OPT_CLI_ONLY, .form = "FILE",
     .help = "write to FILE, replaced atomically only on success;\n"
             "default standard output"},
};
const size_t cli_output_noptions = sizeof cli_output_options / sizeof cli_output_options[0];

int cli_write_table(const cli_output_spec *output, int argc, char **argv,
                    cli_table_writer write, const void *spec, bkf_error *err)
{
    cli_output out = {0};
    cli_buffer buf = {0};
    char *cmd = NULL, *command = NULL;
    int s = cli_output_open(&out, output->out, "--out", err);
    if (!s) {
        cmd = cli_command_line(argc, argv);
        size_t n = cmd ? strlen(cmd) + sizeof CLI_PROGRAM + 1 : 0;
        command = cmd ? malloc(n) : NULL;
        if (command)
            snprintf(command, n, CLI_PROGRAM " %s", cmd);
        else
            s = bkf_error_set(err, BKF_ENOMEM, "out of memory");
    }
    if (!s) s = cli_buffer_open(&buf, err);
    if (!s) {
        bkf_provenance prov = {CLI_PROGRAM " " CLI_VERSION, command};
        s = write(spec, buf.stream, output->format == 1 ? BKF_IO_JSON : BKF_IO_TSV, &prov, err);
        int c = cli_buffer_close(&buf, s ? NULL : err);
        if (!s) s = c;
    }
    if (!s)
        s = cli_output_write(&out, buf.data, buf.size, err);
    else
        cli_output_abort(&out);
    cli_buffer_free(&buf);
    free(cmd);
    free(command);
    return s;
}

/* All-or-nothing output, cancellation by signals and exit codes (args.h).
 * sigaction is POSIX 2008; fopencookie (the output buffer) is GNU. */
#define _GNU_SOURCE
#include "args.h"

#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdint.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <string.h>
#include <unistd.h>

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
#define CLI_MAX_PENDING 16 /* a step's table and its own files, on each of a few jobs */
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
    case CLI_PARTIAL: return 3;
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

/* A write that cannot be stored whole stores nothing and returns 0, which
 * stdio takes as an error (ferror, and fflush/fclose fail). */
static ssize_t buffer_write(void *cookie, const char *data, size_t size)
{
    cli_buffer *buf = cookie;
    if (buf->failed) return 0;
    if (size > buf->cap - buf->size) {
        size_t cap = buf->cap ? buf->cap : 4096;
        while (cap - buf->size < size) {
            if (cap > SIZE_MAX / 2) {
                buf->failed = 1;
                return 0;
            }
            cap *= 2;
        }
        char *d = realloc(buf->data, cap);
        if (!d) {
            buf->failed = 1;
            return 0;
        }
        buf->data = d;
        buf->cap = cap;
    }
    memcpy(buf->data + buf->size, data, size);
    buf->size += size;
    return (ssize_t)size;
}

int cli_buffer_open(cli_buffer *buf, bkf_error *err)
{
    memset(buf, 0, sizeof *buf);
    cookie_io_functions_t io = {.write = buffer_write};
    buf->stream = fopencookie(buf, "w", io);
    if (!buf->stream) return bkf_error_set(err, BKF_ENOMEM, "out of memory for the output");
    return BKF_OK;
}

int cli_buffer_close(cli_buffer *buf, bkf_error *err)
{
    if (!buf->stream) return BKF_OK;
    int bad = ferror(buf->stream);
    int closed = fclose(buf->stream);
    buf->stream = NULL;
    if (bad || closed != 0 || buf->failed)
        return bkf_error_set(err, BKF_ENOMEM, "out of memory for the output");
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
    buf->cap = 0;
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
    return cli_write_table_kept(output, argc, argv, write, spec, 0, err);
}

int cli_write_table_kept(const cli_output_spec *output, int argc, char **argv,
                         cli_table_writer write, const void *spec, int keep_canceled,
                         bkf_error *err)
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
        int keep = !s || (keep_canceled && s == BKF_ECANCELED);
        int c = cli_buffer_close(&buf, keep ? err : NULL);
        if (keep && c) s = c;
    }
    if (!s || (keep_canceled && s == BKF_ECANCELED)) {
        bkf_error canceled = *err;
        int w = cli_output_write(&out, buf.data, buf.size, err);
        if (w) s = w;
        else if (s) *err = canceled;
    } else
        cli_output_abort(&out);
    cli_buffer_free(&buf);
    free(cmd);
    free(command);
    return s;
}

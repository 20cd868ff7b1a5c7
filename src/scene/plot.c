/* gnuplot jobs and data files (plot.h). */
/* strsignal and prctl's PR_SET_PDEATHSIG are GNU and Linux. */
#define _GNU_SOURCE
#include "bkfront/plot.h"

#include "bkfront/io.h"
#include "bkfront/options.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

static const char *const format_names[BKF_PLOT_NFORMATS] = {"png", "pdf", "svg"};

const char *bkf_plot_format_name(bkf_plot_format format)
{
    return (unsigned)format < BKF_PLOT_NFORMATS ? format_names[format] : NULL;
}

int bkf_plot_parse_formats(const char *text, const char *prefix, const char *name,
                           unsigned *formats, bkf_error *err)
{
    static const char *const choices[] = {"png", "pdf", "svg", NULL};
    if (!prefix) prefix = "";
    if (!name) name = "formats";
    unsigned bits = 0;
    for (const char *p = text ? text : ""; *p;) {
        size_t len = strcspn(p, ", ");
        if (len) {
            char *word = strndup(p, len);
            if (!word) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
            int i, s = bkf_option_parse_choice(word, choices, prefix, name, &i, err);
            free(word);
            if (s) return s;
            bits |= 1u << i;
        }
        p += len;
        if (*p) p++;
    }
    if (!bits) return bkf_error_set(err, BKF_EINPUT, "%s%s: give png, pdf or svg", prefix, name);
    if (formats) *formats = bits;
    return BKF_OK;
}

struct bkf_plot_job {
    char *script;
    char *vars;            /* "a = 1; b = 'x'; " */
    size_t vars_len, vars_cap;
    char *outputs[BKF_PLOT_NFORMATS];
};

bkf_plot_job *bkf_plot_job_alloc(const char *script, bkf_error *err)
{
    if (!script || !*script) {
        bkf_error_set(err, BKF_EINPUT, "plot: no script given");
        return NULL;
    }
    /* Checked here so that a missing script is a clear message, not a
     * gnuplot one about a file it cannot open. */
    if (access(script, R_OK) != 0) {
        bkf_error_set(err, BKF_EINPUT, "plot: cannot read the gnuplot script %s: %s", script,
                      strerror(errno));
        return NULL;
    }
    bkf_plot_job *job = calloc(1, sizeof *job);
    if (job) job->script = strdup(script);
    if (!job || !job->script) {
        bkf_plot_job_free(job);
        bkf_error_set(err, BKF_ENOMEM, "out of memory");
        return NULL;
    }
    return job;
}

void bkf_plot_job_free(bkf_plot_job *job)
{
    if (!job) return;
    free(job->script);
    free(job->vars);
    for (int i = 0; i < BKF_PLOT_NFORMATS; i++) free(job->outputs[i]);
    free(job);
}

static int append(bkf_plot_job *job, const char *text, bkf_error *err)
{
    size_t n = strlen(text);
    if (job->vars_len + n + 1 > job->vars_cap) {
        size_t cap = job->vars_cap ? job->vars_cap : 256;
        while (cap < job->vars_len + n + 1) cap *= 2;
        char *p = realloc(job->vars, cap);
        if (!p) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
        job->vars = p;
        job->vars_cap = cap;
    }
    memcpy(job->vars + job->vars_len, text, n + 1);
    job->vars_len += n;
    return BKF_OK;
}

static int check_name(const char *name, bkf_error *err)
{
    int ok = name && ((*name >= 'A' && *name <= 'Z') || (*name >= 'a' && *name <= 'z') ||
                      *name == '_');
    for (const char *p = name; ok && *p; p++)
        ok = (*p >= 'A' && *p <= 'Z') || (*p >= 'a' && *p <= 'z') ||
             (*p >= '0' && *p <= '9') || *p == '_';
    if (!ok)
        return bkf_error_set(err, BKF_EINPUT, "plot: '%s' is not a gnuplot variable name",
                             name ? name : "(null)");
    if (strcmp(name, "fmt") == 0 || strcmp(name, "out") == 0)
        return bkf_error_set(err, BKF_EINPUT, "plot: the variable '%s' is set per output",
                             name);
    return BKF_OK;
}

int bkf_plot_set_number(bkf_plot_job *job, const char *name, double value, bkf_error *err)
{
    int s = check_name(name, err);
    if (s) return s;
    if (isinf(value))
        return bkf_error_set(err, BKF_EINPUT, "plot: %s is infinite", name);
    char buf[128];
    if (isnan(value))
        snprintf(buf, sizeof buf, "%s = NaN; ", name);
    else
        snprintf(buf, sizeof buf, "%s = %.17g; ", name, value);
    return append(job, buf, err);
}

/* A gnuplot expression for the string `value`, exactly: single-quoted runs
 * (inside single quotes gnuplot interprets nothing: no backslash escapes,
 * no `command` substitution, which double quotes would run) joined by
 * "." to "'" for each single quote.  Doubling a quote inside single
 * quotes is not enough: gnuplot reads two quotes at the start of a token
 * as an empty string, so a value starting with a quote failed. */
static char *quoted(const char *value)
{
    size_t n = 3;
    for (const char *p = value; *p; p++) n += *p == '\'' ? 12 : 1;
    char *q = malloc(n), *w = q;
    if (!q) return NULL;
    int open = 0, pieces = 0;
    for (const char *p = value; *p; p++) {
        if (*p == '\'') {
            if (open) *w++ = '\'';
            open = 0;
            w += sprintf(w, "%s\"'\"", pieces++ ? " . " : "");
            continue;
        }
        if (!open) {
            w += sprintf(w, "%s'", pieces++ ? " . " : "");
            open = 1;
        }
        *w++ = *p;
    }
    if (open) *w++ = '\'';
    if (!pieces) w += sprintf(w, "''");
    *w = '\0';
    return q;
}

static int check_text(const char *what, const char *value, bkf_error *err)
{
    if (!value) return bkf_error_set(err, BKF_EINPUT, "plot: %s is NULL", what);
    for (const unsigned char *p = (const unsigned char *)value; *p; p++)
        if (*p < 0x20 || *p == 0x7f)
            return bkf_error_set(err, BKF_EINPUT, "plot: %s holds a control character",
                                 what);
    return BKF_OK;
}

int bkf_plot_set_string(bkf_plot_job *job, const char *name, const char *value,
                        bkf_error *err)
{
    int s = check_name(name, err);
    if (!s) s = check_text(name, value, err);
    if (s) return s;
    char *q = quoted(value);
    if (!q) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    s = append(job, name, err);
    if (!s) s = append(job, " = ", err);
    if (!s) s = append(job, q, err);
    if (!s) s = append(job, "; ", err);
    free(q);
    return s;
}

int bkf_plot_add_output(bkf_plot_job *job, bkf_plot_format format, const char *path,
                        bkf_error *err)
{
    if ((unsigned)format >= BKF_PLOT_NFORMATS)
        return bkf_error_set(err, BKF_EINPUT, "plot: unknown output format %d", (int)format);
    int s = check_text("the output path", path, err);
    if (s) return s;
    if (!*path) return bkf_error_set(err, BKF_EINPUT, "plot: empty output path");
    if (job->outputs[format])
        return bkf_error_set(err, BKF_EINPUT, "plot: a second %s output",
                             format_names[format]);
    job->outputs[format] = strdup(path);
    if (!job->outputs[format]) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    return BKF_OK;
}

bkf_plot_options bkf_plot_options_default(void)
{
    bkf_plot_options o = {NULL, 60.0, NULL, NULL, NULL};
    return o;
}

static double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int temp_file(void)
{
    const char *dir = getenv("TMPDIR");
    char name[4096];
    snprintf(name, sizeof name, "%s/bkfront-gnuplot-XXXXXX", dir && *dir ? dir : "/tmp");
    int fd = mkstemp(name);
    if (fd < 0) {
        snprintf(name, sizeof name, "/tmp/bkfront-gnuplot-XXXXXX");
        fd = mkstemp(name);
    }
    if (fd >= 0) unlink(name);
    return fd;
}

/* Up to size - 1 bytes of what the child wrote to fd. */
static void read_back(int fd, char *buf, size_t size)
{
    size_t n = 0;
    if (lseek(fd, 0, SEEK_SET) == 0)
        while (n + 1 < size) {
            ssize_t k = read(fd, buf + n, size - 1 - n);
            if (k <= 0) break;
            n += (size_t)k;
        }
    buf[n] = '\0';
}

/* How run_captured's child ended when it did not exit by itself. */
enum { RUN_EXITED = 0, RUN_TIMED_OUT, RUN_CANCELED, RUN_SIGNALED };

/* Runs argv with stdin and stdout on /dev/null and stderr into `errbuf`.
 * Returns the exit code, -1 when it did not exit (*how says why: killed at
 * the timeout, stopped because *cancel was raised, or ended by a signal,
 * *sig) and -2 when it could not be started (127 from the child: exec
 * failed).  The child dies with its parent (PR_SET_PDEATHSIG): a bkfront
 * ended by a second Ctrl-C or SIGKILL leaves no gnuplot drawing on. */
static int run_captured(char *const argv[], double timeout, const volatile sig_atomic_t *cancel,
                        char *errbuf, size_t size, int *how, int *sig)
{
    *how = RUN_EXITED;
    *sig = 0;
    errbuf[0] = '\0';
    int efd = temp_file();
    if (efd < 0) return -2;
    pid_t parent = getpid();
    pid_t pid = fork();
    if (pid < 0) {
        close(efd);
        return -2;
    }
    if (pid == 0) {
        (void)prctl(PR_SET_PDEATHSIG, SIGKILL);
        if (getppid() != parent) _exit(127); /* the parent died before the prctl */
        int null = open("/dev/null", O_RDWR);
        if (null >= 0) {
            dup2(null, 0);
            dup2(null, 1);
        }
        dup2(efd, 2);
        execvp(argv[0], argv);
        _exit(127);
    }
    double t0 = now_seconds();
    int status = 0;
    for (;;) {
        pid_t w = waitpid(pid, &status, WNOHANG);
        if (w == pid) break;
        if (w < 0 && errno != EINTR) break;
        int stop = cancel && *cancel ? RUN_CANCELED
                   : now_seconds() - t0 > timeout ? RUN_TIMED_OUT
                                                  : RUN_EXITED;
        if (stop) {
            kill(pid, SIGKILL);
            while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
            }
            *how = stop;
            break;
        }
        struct timespec nap = {0, 5000000};
        nanosleep(&nap, NULL);
    }
    read_back(efd, errbuf, size);
    close(efd);
    if (*how) return -1;
    if (WIFSIGNALED(status)) {
        *how = RUN_SIGNALED;
        *sig = WTERMSIG(status);
        return -1;
    }
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

/* Whether the file at `path` is a whole image of its format, by its first
 * and last bytes: gnuplot exits 0 even when writing the image failed (a
 * full disk, a file size limit), leaving a truncated file behind.  A PNG
 * ends with its IEND chunk, a PDF with %%EOF, an SVG with </svg> (the text
 * formats perhaps followed by white space). */
static int image_whole(const char *path, bkf_plot_format format, char *why, size_t wsize)
{
    static const char png_sig[8] = "\x89PNG\r\n\x1a\n";
    static const char png_end[12] = "\0\0\0\0IEND\xae\x42\x60\x82";
    int fd = open(path, O_RDONLY | O_NOFOLLOW | O_CLOEXEC);
    struct stat st;
    if (fd < 0 || fstat(fd, &st) != 0) {
        if (fd >= 0) close(fd);
        snprintf(why, wsize, "it cannot be read back");
        return 0;
    }
    char head[17] = {0}, tail[1024];
    size_t nt = st.st_size < (off_t)sizeof tail ? (size_t)st.st_size : sizeof tail;
    ssize_t h = pread(fd, head, sizeof head - 1, 0);
    ssize_t t = pread(fd, tail, nt, st.st_size - (off_t)nt);
    close(fd);
    if (st.st_size == 0) {
        snprintf(why, wsize, "it is empty");
        return 0;
    }
    if (h < 0 || t != (ssize_t)nt) {
        snprintf(why, wsize, "it cannot be read back");
        return 0;
    }
    int ok = 0;
    const char *missing = "";
    if (format == BKF_PLOT_PNG) {
        ok = h >= 8 && memcmp(head, png_sig, 8) == 0 && nt >= 12 &&
             memcmp(tail + nt - 12, png_end, 12) == 0;
        missing = "no IEND chunk at its end";
    } else {
        while (nt && strchr(" \t\r\n", tail[nt - 1])) nt--;
        const char *start = head + strspn(head, " \t\r\n");
        if (format == BKF_PLOT_PDF) {
            ok = memcmp(head, "%PDF-", 5) == 0 && nt >= 5 && memcmp(tail + nt - 5, "%%EOF", 5) == 0;
            missing = "no %%EOF trailer";
        } else {
            ok = (strncmp(start, "<?xml", 5) == 0 || strncmp(start, "<svg", 4) == 0) && nt >= 6 &&
                 memcmp(tail + nt - 6, "</svg>", 6) == 0;
            missing = "no closing </svg>";
        }
    }
    if (!ok) snprintf(why, wsize, "%lld bytes, %s", (long long)st.st_size, missing);
    return ok;
}

/* gnuplot's error report is a few lines: the offending command, a caret,
 * then '"file" line N: message'.  That last kind of line is the one to show;
 * failing that, the last non-empty line. */
static void pick_line(const char *text, int want_warning, char *out, size_t size)
{
    out[0] = '\0';
    const char *best = NULL, *last = NULL;
    size_t best_len = 0, last_len = 0;
    for (const char *p = text; *p;) {
        size_t len = strcspn(p, "\n");
        const char *q = p;
        size_t l = len;
        while (l && (*q == ' ' || *q == '\t')) q++, l--;
        while (l && (q[l - 1] == ' ' || q[l - 1] == '\r')) l--;
        if (l) {
            int has_warning = 0;
            for (size_t i = 0; i + 8 <= l; i++)
                if (strncmp(q + i, "warning:", 8) == 0 || strncmp(q + i, "Warning:", 8) == 0)
                    has_warning = 1;
            if (want_warning) {
                if (has_warning && !best) best = q, best_len = l;
            } else {
                int located = 0;
                for (size_t i = 0; i + 6 <= l; i++)
                    if (strncmp(q + i, " line ", 6) == 0) located = 1;
                if (located && !has_warning) best = q, best_len = l;
                if (!has_warning && *q != '^') last = q, last_len = l;
            }
        }
        p += len;
        if (*p) p++;
    }
    if (!best) best = last, best_len = last_len;
    if (!best) return;
    size_t n = best_len < size - 1 ? best_len : size - 1;
    for (size_t i = 0; i < n; i++)
        out[i] = ((unsigned char)best[i] < 0x20 || best[i] == 0x7f) ? ' ' : best[i];
    out[n] = '\0';
}

int bkf_plot_run(const bkf_plot_job *job, const bkf_plot_options *options,
                 bkf_plot_report *report, bkf_error *err)
{
    bkf_plot_options o = options ? *options : bkf_plot_options_default();
    const char *program = o.gnuplot && *o.gnuplot ? o.gnuplot : "gnuplot";
    double timeout = o.timeout > 0 ? o.timeout : 60.0;
    bkf_plot_report r = {-1, 0.0, {0}};
    if (report) *report = r;

    char *argv[2 + 3 * BKF_PLOT_NFORMATS + 1];
    char *exprs[BKF_PLOT_NFORMATS] = {0};
    /* Each image is drawn into a temporary of its own beside the target,
     * made by io's atomic writer (a fresh name, O_EXCL: two runs into one
     * folder cannot meet, and a link planted there is never followed), and
     * renamed over the target only when gnuplot succeeded. */
    bkf_io_atomic *parts[BKF_PLOT_NFORMATS] = {0};
    int argc = 0, s = BKF_OK, outputs = 0;
    argv[argc++] = (char *)program;
    for (int f = 0; f < BKF_PLOT_NFORMATS && !s; f++) {
        if (!job->outputs[f]) continue;
        outputs++;
        bkf_error e;
        parts[f] = bkf_io_atomic_open(job->outputs[f], &e);
        if (!parts[f]) {
            s = bkf_error_set(err, e.status ? e.status : BKF_EINPUT, "%s", e.message);
            break;
        }
        if (o.temp_file) o.temp_file(bkf_io_atomic_temp_path(parts[f]), 1, o.data);
        char *q = quoted(bkf_io_atomic_temp_path(parts[f]));
        size_t m = (job->vars ? job->vars_len : 0) + (q ? strlen(q) : 0) + 64;
        exprs[f] = q ? malloc(m) : NULL;
        if (!exprs[f]) {
            free(q);
            s = bkf_error_set(err, BKF_ENOMEM, "out of memory");
            break;
        }
        snprintf(exprs[f], m, "%sfmt = '%s'; out = %s", job->vars ? job->vars : "",
                 format_names[f], q);
        free(q);
        argv[argc++] = "-e";
        argv[argc++] = exprs[f];
        argv[argc++] = job->script;
    }
    argv[argc] = NULL;
    if (!s && !outputs) s = bkf_error_set(err, BKF_EINPUT, "plot: the job has no output");

    if (!s) {
        char errbuf[16384], line[BKF_ERROR_LEN - 64];
        int how, sig;
        double t0 = now_seconds();
        int code = run_captured(argv, timeout, o.cancel, errbuf, sizeof errbuf, &how, &sig);
        r.seconds = now_seconds() - t0;
        r.exit_code = code < 0 ? -1 : code;
        if (code == -2 || code == 127) {
            s = bkf_error_set(err, BKF_EINPUT,
                              "cannot run %s (install gnuplot, e.g. the Debian package "
                              "gnuplot-nox)", program);
        } else if (how == RUN_CANCELED) {
            s = bkf_error_set(err, BKF_ECANCELED, "gnuplot stopped: no figure written");
        } else if (how == RUN_TIMED_OUT) {
            s = bkf_error_set(err, BKF_ENUMERIC, "gnuplot %s killed after %g s", job->script,
                              timeout);
        } else if (how == RUN_SIGNALED) {
            s = bkf_error_set(err, BKF_ENUMERIC, "gnuplot %s ended by signal %d (%s)",
                              job->script, sig, strsignal(sig));
        } else if (code != 0) {
            pick_line(errbuf, 0, line, sizeof line);
            s = bkf_error_set(err, BKF_ENUMERIC, "gnuplot exited %d: %s", code,
                              line[0] ? line : "(no message)");
        } else {
            pick_line(errbuf, 1, r.warning, sizeof r.warning);
            for (int f = 0; f < BKF_PLOT_NFORMATS && !s; f++) {
                char why[128];
                if (!parts[f]) continue;
                struct stat st;
                if (stat(bkf_io_atomic_temp_path(parts[f]), &st) != 0 || st.st_size == 0)
                    s = bkf_error_set(err, BKF_ENUMERIC,
                                      "gnuplot exited 0 but wrote no %s (does %s set output?)",
                                      job->outputs[f], job->script);
                else if (!image_whole(bkf_io_atomic_temp_path(parts[f]), (bkf_plot_format)f, why,
                                      sizeof why))
                    s = bkf_error_set(err, BKF_EIO,
                                      "gnuplot exited 0 but its %s image %s is not whole (%s: "
                                      "a full disk or a file size limit?); not written",
                                      format_names[f], job->outputs[f], why);
            }
            for (int f = 0; f < BKF_PLOT_NFORMATS && !s; f++) {
                if (!parts[f]) continue;
                if (o.temp_file) o.temp_file(bkf_io_atomic_temp_path(parts[f]), 0, o.data);
                s = bkf_io_atomic_commit(parts[f], err);
                parts[f] = NULL;
            }
        }
    }
    for (int f = 0; f < BKF_PLOT_NFORMATS; f++) {
        if (parts[f] && o.temp_file) o.temp_file(bkf_io_atomic_temp_path(parts[f]), 0, o.data);
        bkf_io_atomic_abort(parts[f]);
        free(exprs[f]);
    }
    if (report) *report = r;
    return s;
}

int bkf_plot_probe(const char *gnuplot, char *version, size_t size, bkf_error *err)
{
    const char *program = gnuplot && *gnuplot ? gnuplot : "gnuplot";
    char *argv[] = {(char *)program, "-e", "print GPVAL_VERSION", NULL};
    char buf[1024];
    int how, sig;
    int code = run_captured(argv, 20.0, NULL, buf, sizeof buf, &how, &sig);
    if (code != 0)
        return bkf_error_set(err, BKF_EINPUT,
                             "cannot run %s (install gnuplot, e.g. the Debian package "
                             "gnuplot-nox)", program);
    if (version && size) {
        size_t n = strcspn(buf, "\n");
        snprintf(version, size, "gnuplot %.*s", (int)n, buf);
    }
    return BKF_OK;
}

/* ------------------------------------------------------------ data files */

struct bkf_plot_data {
    bkf_io_atomic *file;
    bkf_io_table *table;
};

bkf_plot_data *bkf_plot_data_open(const char *path, const bkf_io_column *columns,
                                  size_t ncolumns, bkf_error *err)
{
    bkf_plot_data *d = calloc(1, sizeof *d);
    if (!d) {
        bkf_error_set(err, BKF_ENOMEM, "out of memory");
        return NULL;
    }
    d->file = bkf_io_atomic_open(path, err);
    if (d->file)
        d->table = bkf_io_table_alloc(bkf_io_atomic_stream(d->file), BKF_IO_TSV, columns,
                                      ncolumns, err);
    if (!d->table) {
        bkf_plot_data_abort(d);
        return NULL;
    }
    return d;
}

bkf_io_table *bkf_plot_data_table(bkf_plot_data *data)
{
    return data->table;
}

int bkf_plot_data_commit(bkf_plot_data *data, bkf_error *err)
{
    int s = bkf_io_table_finish(data->table, err);
    bkf_io_table_free(data->table);
    data->table = NULL;
    if (s) {
        bkf_io_atomic_abort(data->file);
    } else
        s = bkf_io_atomic_commit(data->file, err);
    free(data);
    return s;
}

void bkf_plot_data_abort(bkf_plot_data *data)
{
    if (!data) return;
    bkf_io_table_free(data->table);
    bkf_io_atomic_abort(data->file);
    free(data);
}

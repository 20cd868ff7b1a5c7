/* Open file description locks (F_OFD_SETLK) are Linux's, under
 * _GNU_SOURCE, which also brings POSIX 2008 and flock(). */
#define _GNU_SOURCE
#include "bkfront/io.h"

#include <dirent.h>
#include <errno.h>
#include <stdarg.h>
#include <fcntl.h>
#include <signal.h>
#include <limits.h>
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

/* ------------------------------------------------------------------ tables */

struct bkf_io_table {
    FILE *out;
    bkf_io_format format;
    size_t ncolumns;
    bkf_io_column *columns;  /* names point into `names` */
    char *names;
    size_t rows;
    size_t comments;
    int header_done;         /* TSV header / JSON "columns" written */
    int finished;
    int write_failed;
    int write_errno;
    /* key results for JSON's "results" object, kept until the header */
    size_t nresults;
    char **result_names;
    char **result_texts;     /* NULL for a number */
    double *result_numbers;
};

int bkf_io_format_parse(const char *name, bkf_io_format *format, bkf_error *err)
{
    if (!format) return bkf_error_set(err, BKF_EINPUT, "format pointer is NULL");
    if (name && strcmp(name, "tsv") == 0) {
        *format = BKF_IO_TSV;
        return BKF_OK;
    }
    if (name && strcmp(name, "json") == 0) {
        *format = BKF_IO_JSON;
        return BKF_OK;
    }
    return bkf_error_set(err, BKF_EINPUT, "format must be tsv or json");
}

const char *bkf_io_format_name(bkf_io_format format)
{
    return format == BKF_IO_JSON ? "json" : "tsv";
}

/* Every write goes through here so that one failed write (a full disk, a
 * closed pipe) is remembered and reported by finish even if the caller
 * ignores the row's status. */
static void put(bkf_io_table *t, const char *s, size_t n)
{
    if (t->write_failed || n == 0) return;
    if (fwrite(s, 1, n, t->out) != n) {
        t->write_failed = 1;
        t->write_errno = errno;
    }
}

static void puts_(bkf_io_table *t, const char *s) { put(t, s, strlen(s)); }

static int write_status(const bkf_io_table *t, bkf_error *err)
{
    if (!t->write_failed) return BKF_OK;
    return bkf_error_set(err, BKF_ENUMERIC, "writing the table failed: %s",
                         t->write_errno ? strerror(t->write_errno) : "write error");
}

/* JSON needs "null" where TSV has a spelling for non-finite values. */
static void put_number(bkf_io_table *t, double x)
{
    char buf[40];
    if (isnan(x))
        puts_(t, t->format == BKF_IO_JSON ? "null" : "nan");
    else if (isinf(x))
        puts_(t, t->format == BKF_IO_JSON ? "null" : (x > 0 ? "inf" : "-inf"));
    else {
        int n = snprintf(buf, sizeof buf, "%.17g", x);
        put(t, buf, (size_t)n);
    }
}

static void put_tsv_text(bkf_io_table *t, const char *s)
{
    const char *run = s;
    for (; *s; s++) {
        const char *esc = NULL;
        switch (*s) {
        case '\\': esc = "\\\\"; break;
        case '\t': esc = "\\t"; break;
        case '\n': esc = "\\n"; break;
        case '\r': esc = "\\r"; break;
        default: continue;
        }
        put(t, run, (size_t)(s - run));
        puts_(t, esc);
        run = s + 1;
    }
    put(t, run, (size_t)(s - run));
}

/* Length of the well-formed UTF-8 sequence at s (RFC 3629: no overlong forms,
 * no surrogates, nothing above U+10FFFF), or 0. */
static size_t utf8_sequence(const unsigned char *s)
{
    unsigned char c = s[0];
    size_t len;
    unsigned char lo = 0x80, hi = 0xBF;
    if (c >= 0xC2 && c <= 0xDF) len = 2;
    else if (c >= 0xE0 && c <= 0xEF) {
        len = 3;
        if (c == 0xE0) lo = 0xA0;
        if (c == 0xED) hi = 0x9F;
    } else if (c >= 0xF0 && c <= 0xF4) {
        len = 4;
        if (c == 0xF0) lo = 0x90;
        if (c == 0xF4) hi = 0x8F;
    } else
        return 0;
    if (s[1] < lo || s[1] > hi) return 0;
    for (size_t i = 2; i < len; i++)
        if (s[i] < 0x80 || s[i] > 0xBF) return 0;
    return len;
}

static void put_json_string(bkf_io_table *t, const char *str)
{
    const unsigned char *s = (const unsigned char *)str;
    puts_(t, "\"");
    while (*s) {
        unsigned char c = *s;
        if (c >= 0x80) {
            size_t len = utf8_sequence(s);
            if (len) {
                put(t, (const char *)s, len);
                s += len;
            } else {
                puts_(t, "\\ufffd");
                s++;
            }
            continue;
        }
        char buf[8];
        switch (c) {
        case '"': puts_(t, "\\\""); break;
        case '\\': puts_(t, "\\\\"); break;
        case '\n': puts_(t, "\\n"); break;
        case '\t': puts_(t, "\\t"); break;
        case '\r': puts_(t, "\\r"); break;
        case '\b': puts_(t, "\\b"); break;
        case '\f': puts_(t, "\\f"); break;
        default:
            if (c < 0x20) {
                snprintf(buf, sizeof buf, "\\u%04x", c);
                puts_(t, buf);
            } else
                put(t, (const char *)s, 1);
        }
        s++;
    }
    puts_(t, "\"");
}

bkf_io_table *bkf_io_table_alloc(FILE *out, bkf_io_format format,
                                 const bkf_io_column *columns, size_t ncolumns,
                                 bkf_error *err)
{
    if (!out) {
        bkf_error_set(err, BKF_EINPUT, "table output stream is NULL");
        return NULL;
    }
    if (format != BKF_IO_TSV && format != BKF_IO_JSON) {
        bkf_error_set(err, BKF_EINPUT, "table format %d is not tsv or json", (int)format);
        return NULL;
    }
    if (ncolumns == 0 || !columns) {
        bkf_error_set(err, BKF_EINPUT, "a table needs at least one column");
        return NULL;
    }
    size_t total = 0;
    for (size_t i = 0; i < ncolumns; i++) {
        const char *name = columns[i].name;
        if (!name || !*name) {
            bkf_error_set(err, BKF_EINPUT, "column %zu has no name", i + 1);
            return NULL;
        }
        /* A header starting with '#' would read as a comment, and a control
         * character would break the one-line header. */
        if (name[0] == '#') {
            bkf_error_set(err, BKF_EINPUT, "column name '%s' must not start with '#'", name);
            return NULL;
        }
        for (const unsigned char *p = (const unsigned char *)name; *p; p++)
            if (*p < 0x20 || *p == 0x7f) {
                bkf_error_set(err, BKF_EINPUT,
                              "column %zu's name contains a control character", i + 1);
                return NULL;
            }
        if (columns[i].kind != BKF_IO_NUMBER && columns[i].kind != BKF_IO_TEXT) {
            bkf_error_set(err, BKF_EINPUT, "column '%s' has an unknown kind", name);
            return NULL;
        }
        for (size_t j = 0; j < i; j++)
            if (strcmp(columns[j].name, name) == 0) {
                bkf_error_set(err, BKF_EINPUT, "column name '%s' is used twice", name);
                return NULL;
            }
        total += strlen(name) + 1;
    }
    bkf_io_table *t = calloc(1, sizeof *t);
    if (t) {
        t->columns = malloc(ncolumns * sizeof *t->columns);
        t->names = malloc(total);
    }
    if (!t || !t->columns || !t->names) {
        bkf_io_table_free(t);
        bkf_error_set(err, BKF_ENOMEM, "out of memory allocating a table");
        return NULL;
    }
    char *p = t->names;
    for (size_t i = 0; i < ncolumns; i++) {
        size_t n = strlen(columns[i].name) + 1;
        memcpy(p, columns[i].name, n);
        t->columns[i].name = p;
        t->columns[i].kind = columns[i].kind;
        p += n;
    }
    t->out = out;
    t->format = format;
    t->ncolumns = ncolumns;
    return t;
}

void bkf_io_table_free(bkf_io_table *table)
{
    if (!table) return;
    for (size_t i = 0; i < table->nresults; i++) {
        free(table->result_names[i]);
        free(table->result_texts[i]);
    }
    free(table->result_names);
    free(table->result_texts);
    free(table->result_numbers);
    free(table->columns);
    free(table->names);
    free(table);
}

size_t bkf_io_table_rows(const bkf_io_table *table) { return table ? table->rows : 0; }

static int check_usable(const bkf_io_table *t, bkf_error *err)
{
    if (!t) return bkf_error_set(err, BKF_EINPUT, "table is NULL");
    if (t->finished) return bkf_error_set(err, BKF_EINPUT, "table is already finished");
    return BKF_OK;
}

int bkf_io_table_commentf(bkf_io_table *t, bkf_error *err, const char *fmt, ...)
{
    char line[1024];
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(line, sizeof line, fmt, ap);
    va_end(ap);
    if (n < 0 || (size_t)n >= sizeof line)
        return bkf_error_set(err, BKF_EINPUT, "a comment of %d bytes is longer than %zu", n,
                             sizeof line - 1);
    return bkf_io_table_comment(t, line, err);
}

int bkf_io_table_comment(bkf_io_table *t, const char *text, bkf_error *err)
{
    int s = check_usable(t, err);
    if (s) return s;
    if (t->header_done)
        return bkf_error_set(err, BKF_EINPUT, "comments must come before the first row");
    if (!text) text = "";
    /* Each line its own comment: a newline inside one would end the comment
     * line in TSV and start an uncommented line. */
    for (;;) {
        const char *nl = strchr(text, '\n');
        size_t len = nl ? (size_t)(nl - text) : strlen(text);
        if (len > 0 && text[len - 1] == '\r') len--;
        if (t->format == BKF_IO_TSV) {
            puts_(t, "# ");
            for (size_t i = 0; i < len; i++) {
                /* keep the comment on its line */
                char c = text[i] == '\r' ? ' ' : text[i];
                put(t, &c, 1);
            }
            puts_(t, "\n");
        } else {
            char *line = malloc(len + 1);
            if (!line) return bkf_error_set(err, BKF_ENOMEM, "out of memory writing a comment");
            memcpy(line, text, len);
            line[len] = '\0';
            puts_(t, t->comments == 0 ? "{\n  \"comments\": [\n    " : ",\n    ");
            put_json_string(t, line);
            free(line);
        }
        t->comments++;
        if (!nl) break;
        text = nl + 1;
    }
    return write_status(t, err);
}

static char *copy_text(const char *s)
{
    size_t n = strlen(s) + 1;
    char *c = malloc(n);
    if (c) memcpy(c, s, n);
    return c;
}

int bkf_io_table_result(bkf_io_table *t, const char *name, bkf_io_kind kind,
                        bkf_io_value value, bkf_error *err)
{
    int s = check_usable(t, err);
    if (s) return s;
    if (t->header_done)
        return bkf_error_set(err, BKF_EINPUT, "results must come before the first row");
    if (!name || !*name) return bkf_error_set(err, BKF_EINPUT, "a result needs a name");
    for (size_t i = 0; i < t->nresults; i++)
        if (strcmp(t->result_names[i], name) == 0)
            return bkf_error_set(err, BKF_EINPUT, "result '%s' is given twice", name);
    size_t n = t->nresults + 1;
    char **names = realloc(t->result_names, n * sizeof *names);
    if (names) t->result_names = names;
    char **texts = names ? realloc(t->result_texts, n * sizeof *texts) : NULL;
    if (texts) t->result_texts = texts;
    double *numbers = texts ? realloc(t->result_numbers, n * sizeof *numbers) : NULL;
    if (numbers) t->result_numbers = numbers;
    char *name_copy = numbers ? copy_text(name) : NULL;
    char *text_copy = kind == BKF_IO_TEXT && value.text && name_copy ? copy_text(value.text) : NULL;
    if (!name_copy || (kind == BKF_IO_TEXT && value.text && !text_copy)) {
        free(name_copy);
        return bkf_error_set(err, BKF_ENOMEM, "out of memory storing a result");
    }
    t->result_names[t->nresults] = name_copy;
    t->result_texts[t->nresults] = text_copy;
    t->result_numbers[t->nresults] = kind == BKF_IO_NUMBER ? value.number : NAN;
    t->nresults = n;
    return BKF_OK;
}

static void write_results(bkf_io_table *t)
{
    puts_(t, "  \"results\": {");
    for (size_t i = 0; i < t->nresults; i++) {
        if (i) puts_(t, ", ");
        put_json_string(t, t->result_names[i]);
        puts_(t, ": ");
        if (t->result_texts[i])
            put_json_string(t, t->result_texts[i]);
        else
            put_number(t, t->result_numbers[i]);
    }
    puts_(t, "},\n");
}

static void write_header(bkf_io_table *t)
{
    if (t->format == BKF_IO_TSV) {
        for (size_t i = 0; i < t->ncolumns; i++) {
            if (i) puts_(t, "\t");
            puts_(t, t->columns[i].name);
        }
        puts_(t, "\n");
    } else {
        puts_(t, t->comments == 0 ? "{\n  \"comments\": [],\n" : "\n  ],\n");
        if (t->nresults) write_results(t);
        puts_(t, "  \"columns\": [");
        for (size_t i = 0; i < t->ncolumns; i++) {
            if (i) puts_(t, ", ");
            put_json_string(t, t->columns[i].name);
        }
        /* Each column's declared kind, so that a reader types a column
         * alike whatever its values (or none) look like. */
        puts_(t, "],\n  \"kinds\": [");
        for (size_t i = 0; i < t->ncolumns; i++) {
            if (i) puts_(t, ", ");
            puts_(t, t->columns[i].kind == BKF_IO_NUMBER ? "\"number\"" : "\"text\"");
        }
        puts_(t, "],\n  \"rows\": [");
    }
    t->header_done = 1;
}

int bkf_io_table_row(bkf_io_table *t, const bkf_io_value *values, bkf_error *err)
{
    int s = check_usable(t, err);
    if (s) return s;
    if (!values) return bkf_error_set(err, BKF_EINPUT, "row values are NULL");
    if (!t->header_done) write_header(t);
    if (t->format == BKF_IO_TSV) {
        for (size_t i = 0; i < t->ncolumns; i++) {
            if (i) puts_(t, "\t");
            if (t->columns[i].kind == BKF_IO_NUMBER)
                put_number(t, values[i].number);
            else if (values[i].text)
                put_tsv_text(t, values[i].text);
        }
        puts_(t, "\n");
    } else {
        puts_(t, t->rows == 0 ? "\n    {" : ",\n    {");
        for (size_t i = 0; i < t->ncolumns; i++) {
            if (i) puts_(t, ", ");
            put_json_string(t, t->columns[i].name);
            puts_(t, ": ");
            if (t->columns[i].kind == BKF_IO_NUMBER)
                put_number(t, values[i].number);
            else if (values[i].text)
                put_json_string(t, values[i].text);
            else
                puts_(t, "null");
        }
        puts_(t, "}");
    }
    t->rows++;
    return write_status(t, err);
}

int bkf_io_table_finish(bkf_io_table *t, bkf_error *err)
{
    int s = check_usable(t, err);
    if (s) return s;
    if (!t->header_done) write_header(t);
    if (t->format == BKF_IO_JSON) puts_(t, t->rows ? "\n  ]\n}\n" : "]\n}\n");
    t->finished = 1;
    if (!t->write_failed && (fflush(t->out) != 0 || ferror(t->out))) {
        t->write_failed = 1;
        t->write_errno = errno;
    }
    return write_status(t, err);
}

/* ------------------------------------------------------- atomic replacement */

/* Every target being written in this process (an atomic file from open to
 * commit or abort) and every lock held (bkf_io_lock), so that one file
 * named twice (simulate --snapshots x.tsv --out ./x.tsv, or two hard
 * links of one file) is refused at the second open instead of one output
 * silently replacing the other at commit.  A file is known by its folder
 * (device and inode: every spelling and every link of the folder is the
 * same) and its name there, and, when it exists, by its own device and
 * inode (hard links).  Atomic files may be opened in several threads. */
typedef struct registered {
    struct registered *next;
    dev_t dir_dev;
    ino_t dir_ino;
    const char *base;     /* the target's name in its folder */
    int exists;           /* the target exists: dev and ino are its own */
    dev_t dev;
    ino_t ino;
    const char *shown;    /* the path as the caller spelled it */
} registered;

static pthread_mutex_t registry_mutex = PTHREAD_MUTEX_INITIALIZER;
static registered *writing; /* atomic files open */
static registered *locked;  /* locks held: dev, ino of the lock file */

struct bkf_io_atomic {
    FILE *stream;
    char *target;    /* where commit renames to: the path as given */
    char *temp;
    char *dir;       /* the target's directory, fsynced after the rename */
    registered reg;  /* in `writing` while reg.base is set */
};

static void unregister(registered **list, registered *r)
{
    pthread_mutex_lock(&registry_mutex);
    for (registered **p = list; *p; p = &(*p)->next)
        if (*p == r) {
            *p = r->next;
            break;
        }
    pthread_mutex_unlock(&registry_mutex);
}

static int same_target(const registered *a, const registered *b)
{
    if (a->exists && b->exists && a->dev == b->dev && a->ino == b->ino) return 1;
    return a->dir_dev == b->dir_dev && a->dir_ino == b->dir_ino && strcmp(a->base, b->base) == 0;
}

static void atomic_free(bkf_io_atomic *a)
{
    if (!a) return;
    if (a->reg.base) unregister(&writing, &a->reg);
    free(a->target);
    free(a->temp);
    free(a->dir);
    free(a);
}

static char *dup_string(const char *s)
{
    size_t n = strlen(s) + 1;
    char *d = malloc(n);
    if (d) memcpy(d, s, n);
    return d;
}

/* A path inside a one-line message: control characters become '?', and a
 * long one is cut with "...". */
static const char *shown(const char *text, char *buf, size_t size)
{
    size_t n = 0;
    const unsigned char *s = (const unsigned char *)text;
    for (; *s && n < size - 4; s++) buf[n++] = (*s < 0x20 || *s == 0x7f) ? '?' : (char)*s;
    if (*s) {
        memcpy(buf + n, "...", 3);
        n += 3;
    }
    buf[n] = '\0';
    return buf;
}

/* Temporaries are named DIR/.BASE.tmp.PID.TAG (TAG: up to 8 hex digits),
 * BASE cut to its first TEMP_BASE_MAX bytes so that the name stays within
 * a file system's 255 (a target name of up to 255 bytes is valid; its
 * temporary must be too).  A writer holds an exclusive flock() on its
 * temporary from creation until after the rename; the kernel drops it when
 * the writer dies, however it dies.  One whose PID does not exist here AND
 * that nobody holds locked was left by a run that was killed (SIGKILL,
 * power loss): remove it.  The PID alone proves nothing for a writer in
 * another PID namespace (a container on the same host, sharing the
 * folder): its PID is not ours to look up, but its lock is seen.  When the
 * lock cannot be tested (a file system without flock) nothing is removed.
 * Best effort, silent. */
#define TEMP_BASE_MAX 200

static size_t temp_base_len(const char *base)
{
    size_t n = strlen(base);
    return n < TEMP_BASE_MAX ? n : TEMP_BASE_MAX;
}

/* Whether PID names no live process here: none at all, or one that has
 * exited and waits for its parent to reap it (a zombie holds no file and
 * no lock; a writer killed with its parent, as kill -9 of an MPI job does,
 * stays one until its new parent gets to it). */
static int pid_gone(long pid)
{
    if (kill((pid_t)pid, 0) != 0) return errno == ESRCH;
    char path[48], buf[512];
    snprintf(path, sizeof path, "/proc/%ld/stat", pid);
    FILE *f = fopen(path, "re");
    if (!f) return 0;
    size_t n = fread(buf, 1, sizeof buf - 1, f);
    fclose(f);
    buf[n] = '\0';
    /* "pid (comm) state ...": comm may hold anything, the last ')' ends it */
    const char *end = strrchr(buf, ')');
    return end && end[1] == ' ' && (end[2] == 'Z' || end[2] == 'X');
}

static void remove_stale_temps(const char *dir, const char *base)
{
    DIR *d = opendir(dir);
    if (!d) return;
    size_t blen = temp_base_len(base), dlen = strlen(dir);
    struct dirent *de;
    while ((de = readdir(d)) != NULL) {
        const char *n = de->d_name;
        if (n[0] != '.' || strncmp(n + 1, base, blen) != 0 || strncmp(n + 1 + blen, ".tmp.", 5))
            continue;
        const char *p = n + 1 + blen + 5;
        if (*p < '1' || *p > '9') continue;
        char *end;
        errno = 0;
        long pid = strtol(p, &end, 10);
        if (errno || *end != '.' || pid <= 0 || pid == (long)getpid()) continue;
        const char *tag = end + 1;
        size_t tlen = strlen(tag);
        if (tlen == 0 || tlen > 8 || strspn(tag, "0123456789abcdef") != tlen) continue;
        if (!pid_gone(pid)) continue; /* alive, or not ours */
        size_t nlen = strlen(n);
        char *full = malloc(dlen + nlen + 2);
        if (!full) break;
        memcpy(full, dir, dlen);
        size_t k = dlen;
        if (k && full[k - 1] != '/') full[k++] = '/';
        memcpy(full + k, n, nlen + 1);
        int fd = open(full, O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
        if (fd >= 0) {
            /* removed while we hold the lock: its writer cannot be alive */
            if (flock(fd, LOCK_EX | LOCK_NB) == 0) (void)unlink(full);
            close(fd);
        }
        free(full);
    }
    closedir(d);
}

/* ------------------------------------------------------------------ locks */

/* The lock file of the target DIR/BASE: DIR/.BASE.lock (BASE cut as a
 * temporary's, so that the name fits).  NULL when out of memory. */
static char *lock_path(const char *path)
{
    const char *slash = strrchr(path, '/');
    size_t dlen = slash ? (size_t)(slash - path) + 1 : 0;
    const char *base = path + dlen;
    size_t blen = temp_base_len(base);
    char *l = malloc(dlen + blen + 8);
    if (l) snprintf(l, dlen + blen + 8, "%.*s.%.*s.lock", (int)dlen, path, (int)blen, base);
    return l;
}

/* The PID a holder wrote into its lock file, 0 when unreadable. */
static long lock_holder(int fd)
{
    char buf[32];
    ssize_t n = pread(fd, buf, sizeof buf - 1, 0);
    if (n <= 0) return 0;
    buf[n] = '\0';
    long pid = strtol(buf, NULL, 10);
    return pid > 0 ? pid : 0;
}

static int held_here(const struct stat *st)
{
    int found = 0;
    pthread_mutex_lock(&registry_mutex);
    for (registered *r = locked; r && !found; r = r->next)
        found = r->dev == st->st_dev && r->ino == st->st_ino;
    pthread_mutex_unlock(&registry_mutex);
    return found;
}

/* Whether another process (or another lock of this one) holds the lock of
 * `path`; *pid is the holder's when it said.  Tested without taking it
 * (an open file description lock, F_OFD_GETLK), so that the test never
 * makes the holder's own attempt fail.  A lock file that cannot be opened
 * or tested is no lock. */
static int locked_elsewhere(const char *path, long *pid)
{
    *pid = 0;
    char *lp = lock_path(path);
    if (!lp) return 0;
    int fd = open(lp, O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
    free(lp);
    if (fd < 0) return 0;
    struct stat st;
    struct flock fl = {.l_type = F_WRLCK, .l_whence = SEEK_SET};
    int busy = fstat(fd, &st) == 0 && S_ISREG(st.st_mode) && !held_here(&st) &&
               fcntl(fd, F_OFD_GETLK, &fl) == 0 && fl.l_type != F_UNLCK;
    if (busy) *pid = lock_holder(fd);
    close(fd);
    return busy;
}

struct bkf_io_lock {
    int fd;
    char *path;      /* the lock file, removed on release */
    registered reg;  /* in `locked` */
};

/* Open file description locks (fcntl F_OFD_SETLK) rather than flock():
 * another writer's test (locked_elsewhere) can then ask without taking the
 * lock even for an instant.  A holder removes its lock file on release; a
 * taker that locked a file removed meanwhile (it opened the old one just
 * before) sees that the name no longer leads to its file and tries again. */
bkf_io_lock *bkf_io_lock_take(const char *path, bkf_error *err)
{
    char sp[200];
    if (!path || !*path) {
        bkf_error_set(err, BKF_EINPUT, "lock: the file name is empty");
        return NULL;
    }
    bkf_io_lock *l = calloc(1, sizeof *l);
    if (l) l->path = lock_path(path);
    if (!l || !l->path) {
        free(l);
        bkf_error_set(err, BKF_ENOMEM, "out of memory");
        return NULL;
    }
    l->fd = -1;
    int attempt;
    for (attempt = 0; attempt < 20; attempt++) {
        int fd = open(l->path, O_RDWR | O_CREAT | O_NOFOLLOW | O_CLOEXEC, 0666);
        if (fd < 0) {
            int e = errno;
            bkf_error_set(err, BKF_EINPUT, "cannot lock '%s' (by its lock file %s): %s",
                          shown(path, sp, sizeof sp), l->path,
                          e == ELOOP ? "the lock file is a symbolic link" : strerror(e));
            break;
        }
        struct stat st, now;
        struct flock fl = {.l_type = F_WRLCK, .l_whence = SEEK_SET};
        if (fstat(fd, &st) == 0 && held_here(&st)) {
            close(fd);
            bkf_error_set(err, BKF_EINPUT, "'%s' is already being written by this process",
                          shown(path, sp, sizeof sp));
            break;
        }
        if (fcntl(fd, F_OFD_SETLK, &fl) != 0) {
            int e = errno;
            long pid = (e == EAGAIN || e == EACCES) ? lock_holder(fd) : 0;
            close(fd);
            if (e == EAGAIN || e == EACCES) {
                char who[64] = "";
                if (pid) snprintf(who, sizeof who, " (process %ld)", pid);
                bkf_error_set(err, BKF_EINPUT,
                              "'%s' is being written by another run%s: one writer at a time "
                              "(its lock file is %s)",
                              shown(path, sp, sizeof sp), who, l->path);
            } else
                bkf_error_set(err, BKF_EINPUT, "cannot lock '%s': %s",
                              shown(path, sp, sizeof sp), strerror(e));
            break;
        }
        if (lstat(l->path, &now) != 0 || now.st_dev != st.st_dev || now.st_ino != st.st_ino) {
            close(fd); /* the file we locked was removed by its last holder */
            continue;
        }
        char pid[32];
        int n = snprintf(pid, sizeof pid, "%ld\n", (long)getpid());
        /* only for the message of a refused writer: best effort */
        if (ftruncate(fd, 0) == 0) (void)!pwrite(fd, pid, (size_t)n, 0);
        l->fd = fd;
        l->reg.dev = st.st_dev;
        l->reg.ino = st.st_ino;
        pthread_mutex_lock(&registry_mutex);
        l->reg.next = locked;
        locked = &l->reg;
        pthread_mutex_unlock(&registry_mutex);
        return l;
    }
    if (attempt == 20)
        bkf_error_set(err, BKF_EIO, "cannot lock '%s': its lock file %s keeps being replaced",
                      shown(path, sp, sizeof sp), l->path);
    free(l->path);
    free(l);
    return NULL;
}

void bkf_io_lock_release(bkf_io_lock *l)
{
    if (!l) return;
    unregister(&locked, &l->reg);
    /* removed while still held: whoever opens the name next gets a new file */
    (void)unlink(l->path);
    close(l->fd);
    free(l->path);
    free(l);
}

/* ------------------------------------------------------------ atomic files */

/* Enters a->reg in `writing`, unless another atomic file of this process
 * writes the same target. */
static int register_target(bkf_io_atomic *a, const char *path, const struct stat *target,
                           bkf_error *err)
{
    char sp[200], so[200];
    struct stat dir;
    if (stat(a->dir, &dir) != 0) return BKF_OK; /* the open that follows says why */
    a->reg.dir_dev = dir.st_dev;
    a->reg.dir_ino = dir.st_ino;
    a->reg.exists = target != NULL;
    if (target) {
        a->reg.dev = target->st_dev;
        a->reg.ino = target->st_ino;
    }
    a->reg.shown = a->target;
    const char *slash = strrchr(a->target, '/');
    const char *base = slash ? slash + 1 : a->target;
    a->reg.base = base;
    int status = BKF_OK;
    pthread_mutex_lock(&registry_mutex);
    for (registered *r = writing; r; r = r->next)
        if (same_target(r, &a->reg)) {
            status = bkf_error_set(err, BKF_EINPUT,
                                   "output '%s' is the file '%s' that another output of this "
                                   "run writes: give each output a file of its own",
                                   shown(path, sp, sizeof sp), shown(r->shown, so, sizeof so));
            break;
        }
    if (!status) {
        a->reg.next = writing;
        writing = &a->reg;
    } else
        a->reg.base = NULL;
    pthread_mutex_unlock(&registry_mutex);
    return status;
}

bkf_io_atomic *bkf_io_atomic_open(const char *path, bkf_error *err)
{
    char sp[200];
    if (!path || !*path) {
        bkf_error_set(err, BKF_EINPUT, "output file name is empty");
        return NULL;
    }
    bkf_io_atomic *a = calloc(1, sizeof *a);
    if (!a || !(a->target = dup_string(path))) {
        bkf_error_set(err, BKF_ENOMEM, "out of memory");
        atomic_free(a);
        return NULL;
    }
    size_t tlen = strlen(a->target);
    if (a->target[tlen - 1] == '/') {
        bkf_error_set(err, BKF_EINPUT, "output '%s' names a directory, not a file",
                      shown(path, sp, sizeof sp));
        atomic_free(a);
        return NULL;
    }

    mode_t mode = 0666;  /* open() applies the umask */
    struct stat st;
    /* lstat: a link is never followed.  One planted where an output goes
     * (out/fr.tsv -> ../elsewhere/victim) would otherwise have the file
     * it points to replaced; the rename of commit replaces the link itself
     * (should one appear after this test), never what it points to. */
    int exists = lstat(a->target, &st) == 0;
    if (exists && S_ISLNK(st.st_mode)) {
        bkf_error_set(err, BKF_EINPUT,
                      "output '%s' is a symbolic link: outputs never write through one (remove "
                      "it, or name the file itself)",
                      shown(path, sp, sizeof sp));
        atomic_free(a);
        return NULL;
    }
    if (exists && !S_ISREG(st.st_mode)) {
        /* rename() would replace a device or FIFO with a regular file. */
        bkf_error_set(err, BKF_EINPUT, "output '%s' exists and is not a regular file%s",
                      shown(path, sp, sizeof sp), S_ISDIR(st.st_mode) ? " (a directory)" : "");
        atomic_free(a);
        return NULL;
    }
    long holder;
    if (locked_elsewhere(a->target, &holder)) {
        char who[64] = "";
        if (holder) snprintf(who, sizeof who, " (process %ld)", holder);
        bkf_error_set(err, BKF_EINPUT,
                      "output '%s' is being written by another run%s: one writer at a time",
                      shown(path, sp, sizeof sp), who);
        atomic_free(a);
        return NULL;
    }

    const char *slash = strrchr(a->target, '/');
    size_t dlen = slash ? (size_t)(slash - a->target) + 1 : 0;
    const char *base = a->target + dlen;
    a->dir = malloc(dlen + 2);
    a->temp = malloc(tlen + 64);
    if (!a->dir || !a->temp) {
        bkf_error_set(err, BKF_ENOMEM, "out of memory");
        atomic_free(a);
        return NULL;
    }
    if (dlen) {
        memcpy(a->dir, a->target, dlen);
        a->dir[dlen] = '\0';
    } else
        strcpy(a->dir, ".");
    if (register_target(a, path, exists ? &st : NULL, err)) {
        atomic_free(a);
        return NULL;
    }
    remove_stale_temps(a->dir, base);

    /* O_EXCL with a fresh name rather than mkstemp(): mkstemp forces mode
     * 0600, and the umask cannot be read without changing it. */
    /* atomic: atomic files may be opened in several threads at once */
    static _Atomic unsigned counter;
    struct timespec now;
    clock_gettime(CLOCK_REALTIME, &now);
    int fd = -1, open_errno = 0;
    for (int attempt = 0; attempt < 100 && fd < 0; attempt++) {
        unsigned long tag = (unsigned long)now.tv_nsec ^ ((unsigned long)counter++ * 2654435761u);
        snprintf(a->temp, tlen + 64, "%.*s.%.*s.tmp.%ld.%lx", (int)dlen, a->target,
                 (int)temp_base_len(base), base, (long)getpid(), tag & 0xffffffffUL);
        fd = open(a->temp, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, mode);
        open_errno = errno;
        if (fd < 0 && open_errno != EEXIST) break;
    }
    if (fd < 0) {
        bkf_error_set(err, BKF_EINPUT, "cannot write '%s': %s", shown(path, sp, sizeof sp),
                      strerror(open_errno));
        atomic_free(a);
        return NULL;
    }
    /* Held until the rename: the mark of a live writer (remove_stale_temps).
     * Best effort: without flock the temporary is merely never removed by
     * another run. */
    (void)flock(fd, LOCK_EX | LOCK_NB);
    if (exists) (void)fchmod(fd, st.st_mode & 07777); /* best effort: keep the old mode */
    a->stream = fdopen(fd, "w");
    if (!a->stream) {
        int e = errno;
        close(fd);
        unlink(a->temp);
        bkf_error_set(err, BKF_ENOMEM, "cannot open a stream on '%s': %s",
                      shown(a->temp, sp, sizeof sp), strerror(e));
        atomic_free(a);
        return NULL;
    }
    return a;
}

FILE *bkf_io_atomic_stream(bkf_io_atomic *file) { return file ? file->stream : NULL; }

const char *bkf_io_atomic_temp_path(const bkf_io_atomic *file)
{
    return file ? file->temp : NULL;
}

int bkf_io_atomic_commit(bkf_io_atomic *a, bkf_error *err)
{
    char sp[200];
    if (!a) return bkf_error_set(err, BKF_EINPUT, "atomic file is NULL");
    int status = BKF_OK;
    const char *step = NULL;
    int e = 0;
    if (fflush(a->stream) != 0 || ferror(a->stream)) {
        step = "write";
        e = errno;
    } else if (fsync(fileno(a->stream)) != 0) {
        step = "fsync";
        e = errno;
    }
    /* The lock lives as long as any descriptor of the file: a duplicate
     * keeps it over the close and the rename. */
    int lock_fd = dup(fileno(a->stream));
    if (fclose(a->stream) != 0 && !step) {
        step = "close";
        e = errno;
    }
    a->stream = NULL;
    if (!step && rename(a->temp, a->target) != 0) {
        step = "rename";
        e = errno;
    }
    if (lock_fd >= 0) close(lock_fd);
    if (step) {
        unlink(a->temp);
        status = bkf_error_set(err, BKF_ENUMERIC, "writing '%s' failed (%s): %s",
                               shown(a->target, sp, sizeof sp),
                               step, e ? strerror(e) : "I/O error");
    } else {
        /* The rename is durable only once the directory entry is on disk;
         * some file systems cannot fsync a directory, which is no error. */
        int dfd = open(a->dir, O_RDONLY | O_CLOEXEC);
        if (dfd >= 0) {
            (void)fsync(dfd);
            close(dfd);
        }
    }
    atomic_free(a);
    return status;
}

void bkf_io_atomic_abort(bkf_io_atomic *a)
{
    if (!a) return;
    if (a->stream) fclose(a->stream);
    unlink(a->temp);
    atomic_free(a);
}

/* ------------------------------------------------------------ command line */

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

char *bkf_io_command_line(int argc, const char *const *argv)
{
    size_t cap = 1;
    for (int i = 0; i < argc; i++) cap += 4 * strlen(argv[i]) + 3;
    char *line = malloc(cap), *p = line;
    if (!line) return NULL;
    for (int i = 0; i < argc; i++) {
        if (i) *p++ = ' ';
        const char *t = argv[i];
        if (shell_plain(t)) {
            size_t n = strlen(t);
            memcpy(p, t, n);
            p += n;
            continue;
        }
        *p++ = '\'';
        for (; *t; t++) {
            if (*t == '\'') {
                memcpy(p, "'\\''", 4);
                p += 4;
            } else
                *p++ = ((unsigned char)*t < 0x20 || *t == 0x7f) ? '?' : *t;
        }
        *p++ = '\'';
    }
    *p = '\0';
    return line;
}

/* ------------------------------------------------------------ state reader */

const char *bkf_io_shown(const char *text, char *buf, size_t size)
{
    size_t n = 0, limit = size - 4;
    const unsigned char *s = (const unsigned char *)(text ? text : "");
    for (; *s && n < limit; s++) buf[n++] = (*s < 0x20 || *s == 0x7f) ? '?' : (char)*s;
    if (*s) {
        memcpy(buf + n, "...", 3);
        n += 3;
    }
    buf[n] = '\0';
    return buf;
}

void bkf_io_state_free(bkf_io_state *state)
{
    if (!state) return;
    free(state->psi);
    free(state->eta);
    memset(state, 0, sizeof *state);
}

/* The columns of a data line, split in place; -1 when a cell is not a finite
 * number (*bad points at it). */
static int state_cells(char *line, int ipsi, int ieta, int it, double *vp, double *ve, double *vt,
                       int *fields, char **bad)
{
    char *save = NULL;
    int col = 0;
    for (char *tok = strtok_r(line, "\t", &save); tok; tok = strtok_r(NULL, "\t", &save), col++) {
        if (col != ipsi && col != ieta && col != it) continue;
        char *end;
        errno = 0;
        double v = strtod(tok, &end);
        if (*end || end == tok || !isfinite(v) || errno) {
            *bad = tok;
            return -1;
        }
        if (col == ipsi) *vp = v;
        else if (col == ieta) *ve = v;
        else *vt = v;
    }
    *fields = col;
    return 0;
}

/* Lines of a state file are short (a snapshot row is about 80 bytes); a
 * longer one, a NUL byte or a file beyond its byte budget ends the read, so
 * that /dev/zero or an endless stream cannot take all memory or time. */
#define STATE_LINE_MAX 4096
#define STATE_BYTES_PER_ROW 128

/* The next line into buf (without its newline): 1, 0 at the end of the
 * stream, -1 with err set. */
static int state_line(FILE *in, char *buf, size_t *len, size_t lineno, size_t *bytes,
                      size_t max_bytes, size_t max_rows, bkf_error *err)
{
    size_t n = 0;
    int c;
    while ((c = getc(in)) != EOF) {
        if (++*bytes > max_bytes) {
            bkf_error_set(err, BKF_EINPUT, "larger than %zu bytes (the limit for %zu rows)",
                          max_bytes, max_rows);
            return -1;
        }
        if (c == '\n') break;
        if (c == '\0') {
            bkf_error_set(err, BKF_EINPUT, "line %zu holds a NUL byte (not a text table)", lineno);
            return -1;
        }
        if (n == STATE_LINE_MAX) {
            bkf_error_set(err, BKF_EINPUT, "line %zu is longer than %d bytes", lineno,
                          STATE_LINE_MAX);
            return -1;
        }
        buf[n++] = (char)c;
    }
    buf[n] = '\0';
    *len = n;
    return c != EOF || n > 0;
}

int bkf_io_read_state(FILE *in, size_t max_rows, bkf_io_state *state, bkf_error *err)
{
    if (!state) return bkf_error_set(err, BKF_EINPUT, "state is NULL");
    memset(state, 0, sizeof *state);
    if (!in) return bkf_error_set(err, BKF_EINPUT, "stream is NULL");
    char *line = malloc(STATE_LINE_MAX + 1), a[72];
    if (!line) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    size_t len, bytes = 0;
    size_t max_bytes = max_rows > (SIZE_MAX - (1u << 20)) / STATE_BYTES_PER_ROW
                           ? SIZE_MAX
                           : max_rows * STATE_BYTES_PER_ROW + (1u << 20);
    int ipsi = -1, ieta = -1, it = -1, ncol = 0, header = 0, status = BKF_OK, got;
    size_t lineno = 0, rows = 0, rcap = 0, total_rows = 0;
    double *psi = NULL, *eta = NULL, *tt = NULL;
    while ((got = state_line(in, line, &len, lineno + 1, &bytes, max_bytes, max_rows, err)) > 0) {
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
                                       "the header (line %zu) must name the columns psi and eta",
                                       lineno);
                break;
            }
            continue;
        }
        if (total_rows == max_rows) {
            status = bkf_error_set(err, BKF_EINPUT, "line %zu: more than %zu rows", lineno,
                                   max_rows);
            break;
        }
        if (rows == rcap) {
            rcap = rcap ? 2 * rcap : 1024;
            if (rcap > max_rows) rcap = max_rows;
            double *p = realloc(psi, rcap * sizeof *p), *e = p ? realloc(eta, rcap * sizeof *e) : NULL,
                   *t = e ? realloc(tt, rcap * sizeof *t) : NULL;
            if (p) psi = p;
            if (e) eta = e;
            if (t) tt = t;
            if (!p || !e || !t) {
                status = bkf_error_set(err, BKF_ENOMEM, "out of memory");
                break;
            }
        }
        double vp = NAN, ve = NAN, vt = 0;
        int fields = 0;
        char *bad = NULL;
        if (state_cells(line, ipsi, ieta, it, &vp, &ve, &vt, &fields, &bad)) {
            status = bkf_error_set(err, BKF_EINPUT, "line %zu: '%s' is not a finite number",
                                   lineno, bkf_io_shown(bad, a, sizeof a));
            break;
        }
        if (fields != ncol) {
            status = bkf_error_set(err, BKF_EINPUT, "line %zu has %d fields, not %d", lineno,
                                   fields, ncol);
            break;
        }
        /* Only the last snapshot is kept: a new t starts the rows again,
         * so memory holds one snapshot however many the file has. */
        if (it >= 0 && rows && vt != tt[rows - 1]) rows = 0;
        psi[rows] = vp;
        eta[rows] = ve;
        tt[rows] = vt;
        rows++;
        total_rows++;
    }
    if (got < 0 && !status) status = BKF_EINPUT;
    free(line);
    if (!status && ferror(in)) status = bkf_error_set(err, BKF_EIO, "read error");
    if (!status && !header) status = bkf_error_set(err, BKF_EINPUT, "no header line");
    size_t first = 0;
    if (!status && it >= 0 && rows) {
        double tl = tt[rows - 1];
        first = rows;
        while (first > 0 && tt[first - 1] == tl) first--;
        state->t = tl;
        state->has_t = 1;
    }
    if (!status && rows > first) {
        state->rows = rows - first;
        state->psi = malloc(state->rows * sizeof *state->psi);
        state->eta = malloc(state->rows * sizeof *state->eta);
        if (!state->psi || !state->eta) {
            bkf_io_state_free(state);
            status = bkf_error_set(err, BKF_ENOMEM, "out of memory");
        } else {
            memcpy(state->psi, psi + first, state->rows * sizeof *psi);
            memcpy(state->eta, eta + first, state->rows * sizeof *eta);
        }
    }
    if (status) {
        state->t = 0;
        state->has_t = 0;
    }
    free(psi);
    free(eta);
    free(tt);
    return status;
}

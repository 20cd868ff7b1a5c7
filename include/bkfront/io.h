/* Table output (TSV and JSON) and atomic file replacement.
 *
 * A table has named columns, each holding numbers or text.  The writer
 * streams to a FILE* the caller owns; it never opens, prints to or closes a
 * stream on its own.  Layout:
 *
 *   TSV   "# " comment lines, then one header line naming the columns
 *         (tab-separated), then one line per row.  Numbers are "%.17g", so
 *         they read back bit for bit; NaN is "nan", infinities "inf"/"-inf".
 *         In text cells a backslash, tab, newline and carriage return are
 *         written as \\, \t, \n, \r so that a row stays one line.
 *   JSON  one object {"comments": [...], "columns": [...], "kinds": [...],
 *         "rows": [{...}]}, "kinds" naming each column's kind ("number" or
 *         "text"), each row an object keyed by column name; numbers "%.17g",
 *         non-finite numbers and NULL text are null; strings are escaped and
 *         invalid UTF-8 is replaced by U+FFFD, so the output is always valid
 *         JSON.
 *
 * Comments must all come before the first row (both formats put them first).
 *
 * The atomic writer gives a stream on a temporary file beside the target;
 * commit makes it the target in one rename, abort removes it, so a failed or
 * interrupted run never leaves a truncated target behind.
 *
 * The state reader takes back what bkfront simulate writes as snapshots: a
 * TSV whose header names the columns psi and eta. */
#ifndef BKFRONT_IO_H
#define BKFRONT_IO_H

#include <stddef.h>
#include <stdio.h>
#include "bkfront/status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum { BKF_IO_NUMBER = 0, BKF_IO_TEXT = 1 } bkf_io_kind;

typedef struct {
    const char *name;   /* non-empty, no control characters, not starting with '#' */
    bkf_io_kind kind;
} bkf_io_column;

typedef enum { BKF_IO_TSV = 0, BKF_IO_JSON = 1 } bkf_io_format;

/* "tsv" or "json"; anything else is BKF_EINPUT. */
int bkf_io_format_parse(const char *name, bkf_io_format *format, bkf_error *err);
const char *bkf_io_format_name(bkf_io_format format);

/* One cell: `number` is read for BKF_IO_NUMBER columns, `text` (NULL allowed:
 * empty in TSV, null in JSON) for BKF_IO_TEXT columns. */
typedef struct {
    double number;
    const char *text;
} bkf_io_value;

typedef struct bkf_io_table bkf_io_table;

/* The column array is copied.  NULL (with err filled) on bad columns
 * (BKF_EINPUT: none, empty or duplicate names) or out of memory. */
bkf_io_table *bkf_io_table_alloc(FILE *out, bkf_io_format format,
                                 const bkf_io_column *columns, size_t ncolumns,
                                 bkf_error *err);
void bkf_io_table_free(bkf_io_table *table);

/* A comment; text with newlines becomes several comment lines.  BKF_EINPUT
 * once a row has been written. */
int bkf_io_table_comment(bkf_io_table *table, const char *text, bkf_error *err);

/* The same, printf-style; a comment longer than 1023 bytes is BKF_EINPUT
 * (never cut silently). */
int bkf_io_table_commentf(bkf_io_table *table, bkf_error *err, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/* A key result as a named value (a number, or text with kind BKF_IO_TEXT):
 * in JSON a member of the object "results", written between "comments" and
 * "columns" (only when a table has results); TSV has no place for it, so a
 * caller keeps it in a comment as well.  Before the first row; BKF_EINPUT for
 * an empty or repeated name. */
int bkf_io_table_result(bkf_io_table *table, const char *name, bkf_io_kind kind,
                        bkf_io_value value, bkf_error *err);

/* One row: ncolumns values in column order. */
int bkf_io_table_row(bkf_io_table *table, const bkf_io_value *values, bkf_error *err);

/* Writes what is still due (the header of an empty table, the end of the
 * JSON object) and flushes.  Write errors anywhere in the table's life are
 * reported here, if not earlier, as BKF_ENUMERIC.  Further calls fail. */
int bkf_io_table_finish(bkf_io_table *table, bkf_error *err);

size_t bkf_io_table_rows(const bkf_io_table *table);

/* Atomic replacement of the file at `path`. */
typedef struct bkf_io_atomic bkf_io_atomic;

/* Creates the temporary file (in the target's directory, with the mode of
 * an existing target or else 0666 less the umask), named
 * DIR/.BASE.tmp.PID.TAG for the target DIR/BASE (PID the writing process,
 * TAG up to 8 hex digits), held under an exclusive flock() until it is
 * renamed or removed.  A process killed outright (SIGKILL) leaves its
 * temporary; the next open for the same target removes every such
 * temporary whose PID does not exist here (or is a zombie: exited, not yet
 * reaped) and that no one holds locked (a live writer in another PID
 * namespace keeps its lock, and its temporary).
 *
 * BKF_EINPUT when the target cannot be written there: missing directory,
 * no permission, the target is a directory or another non-regular file
 * such as a device; the target is a symbolic link (never written through,
 * whether it points to a file, a folder or nothing: a link planted where
 * an output goes would have the file it points to replaced); another
 * atomic file of this process is open on the same file (the same folder
 * and name however spelled, or a hard link of it: two outputs given one
 * file); another process holds the target's lock (bkf_io_lock_take). */
bkf_io_atomic *bkf_io_atomic_open(const char *path, bkf_error *err);

FILE *bkf_io_atomic_stream(bkf_io_atomic *file);

/* The temporary file's name, stable until commit or abort, so that a signal
 * handler can unlink() it. */
const char *bkf_io_atomic_temp_path(const bkf_io_atomic *file);

/* fflush, fsync, close, rename over the target, fsync the directory.  On any
 * failure the temporary file is removed and the target left as it was
 * (BKF_ENUMERIC).  Frees `file` in every case. */
int bkf_io_atomic_commit(bkf_io_atomic *file, bkf_error *err);

/* Closes and removes the temporary file and frees `file` (NULL is a no-op). */
void bkf_io_atomic_abort(bkf_io_atomic *file);

/* An exclusive claim on the file at `path` for a writer that keeps it for a
 * long time and in several writes (a sweep's table: rows appended as points
 * finish, then sorted): an open file description lock on DIR/.BASE.lock,
 * which holds the holder's PID and is removed on release.  The kernel drops
 * the lock when the holder dies, however it dies.  While it is held, a
 * second bkf_io_lock_take of the same file, here or in another process, and
 * bkf_io_atomic_open of the file in another process are BKF_EINPUT, named
 * "being written by another run (process PID)".  NULL with err filled. */
typedef struct bkf_io_lock bkf_io_lock;
bkf_io_lock *bkf_io_lock_take(const char *path, bkf_error *err);

/* Removes the lock file and drops the lock (NULL is a no-op). */
void bkf_io_lock_release(bkf_io_lock *lock);

/* The words as one line a POSIX shell reads back as those words: plain
 * words as they are, others in single quotes, control characters shown as
 * '?'.  For provenance comments and printed plans.  Caller frees; NULL when
 * out of memory. */
char *bkf_io_command_line(int argc, const char *const *argv);

/* A field psi(x_i), eta(x_i) read back from a table. */
typedef struct {
    size_t rows;        /* values in psi and eta */
    double *psi, *eta;  /* owned; bkf_io_state_free releases them */
    int has_t;          /* the table had a t column */
    double t;           /* its last value (0 without a t column) */
} bkf_io_state;

/* Reads a TSV from `in`: '#' lines and empty lines are skipped, the first
 * other line is the header, which must name the columns psi and eta (other
 * columns are ignored; with a column t, only the rows of the last t are
 * kept: the last snapshot of a file of several).  Every kept cell must be a
 * finite number and every line have the header's number of fields.  At most
 * max_rows data lines are read, each at most 4096 bytes, no NUL byte, and
 * at most 128 max_rows + 1 MiB bytes in all, and only the rows of the
 * current t are held, so that a huge or endless stream (/dev/zero) takes
 * neither all memory nor unbounded time.  On failure *state is left empty (NULL arrays, 0 rows):
 * BKF_EINPUT for content that is not such a table (the message names the
 * line), BKF_EIO when reading the stream fails, BKF_ENOMEM. */
int bkf_io_read_state(FILE *in, size_t max_rows, bkf_io_state *state, bkf_error *err);

/* Releases the arrays and empties *state (NULL is a no-op). */
void bkf_io_state_free(bkf_io_state *state);

/* `text` made fit for a one-line message into buf (size >= 8): control
 * characters become '?', and beyond size - 4 characters it is cut and ends
 * in "...".  Returns buf. */
const char *bkf_io_shown(const char *text, char *buf, size_t size);
#ifdef __cplusplus
}
#endif

#endif

/* What the bkfront subcommands share: strict parsing of option values, a
 * small flag table, the subcommand descriptor and all-or-nothing output.
 *
 * Every parse error is one line of the form "--flag: <what is wrong>
 * (<valid form or range>)", ready to print after "bkfront CMD: ". */
#ifndef BKFRONT_CLI_ARGS_H
#define BKFRONT_CLI_ARGS_H

#include <signal.h>
#include <stddef.h>
#include <stdio.h>
#include "bkfront/io.h"
#include "bkfront/options.h"
#include "bkfront/status.h"
#include "bkfront/version.h"

#define CLI_PROGRAM "bkfront"
/* The library's version: one number for the program and its provenance. */
#define CLI_VERSION BKF_VERSION_STRING

/* Largest number of points a range or a grid may have: a typo such as
 * 1:2:1e9 should be an error, not an hour of work and a huge table. */
#define CLI_MAX_POINTS BKF_LIST_MAX

/* A subcommand.  run() gets argv[0] = the subcommand's name and returns a
 * bkf_status, with err filled on failure; main prints "bkfront NAME: message"
 * and maps the status to the exit code.  run() is not called for --help. */
typedef struct {
    const char *name;
    const char *summary;                 /* one line for `bkfront --help` */
    int (*run)(int argc, char **argv, bkf_error *err);
    void (*help)(FILE *out);
} cli_command;

/* User text for a one-line message: control characters become '?' and text
 * longer than about size - 4 bytes is cut with "...".  Returns buf. */
const char *cli_shown(const char *text, char *buf, size_t size);

/* The parsers of bkfront/options.h with the whole flag ("--mu") as name. */
int cli_parse_double(const char *flag, const char *text, double *value, bkf_error *err);

int cli_parse_count(const char *flag, const char *text, size_t max, size_t *value,
                    bkf_error *err);

int cli_parse_choice(const char *flag, const char *text, const char *const *choices,
                     int *index, bkf_error *err);

/* A list in the grammar of bkf_list_parse: "A", "V1,V2,..." or "A:B:N" (N
 * points from A to B, both exact, N in [1, CLI_MAX_POINTS]; N = 1 needs
 * A == B), geometric when `geometric` is set (every value > 0). */
typedef bkf_list cli_range;

int cli_parse_range(const char *flag, const char *text, int geometric, cli_range *range,
                    bkf_error *err);
void cli_range_free(cli_range *range);

/* Flag table.  "--name VALUE" and "--name=VALUE" both work; a value is the
 * next argument whatever it looks like, so "--nu -0.5" is a value.  A flag
 * given twice, an unknown flag, a missing value, a value given to a switch or
 * a positional argument is an error naming it. */
typedef struct {
    const char *name;     /* "--mu" */
    const char **value;   /* receives the value text; NULL makes a switch */
    const char *form;     /* the value's form, for messages: "M or A:B:N" */
    int *seen;            /* set to 1 when given; may be NULL */
} cli_flag;

int cli_parse_flags(const cli_flag *flags, size_t nflags, int argc, char **argv,
                    bkf_error *err);

/* Flags from option tables (bkfront/options.h): each entry not marked
 * BKF_OPT_SCENE_ONLY is the flag --NAME; --help is always accepted (and sets
 * *help if given).  Flags are read as by cli_parse_flags, then a missing
 * BKF_OPT_REQUIRED entry is "--NAME is required (FORM)", then every given
 * value is applied in table order (groups in order), so a switch such as
 * --log that shapes a later list comes first in its table. */
typedef struct {
    const bkf_option *table;
    size_t n;
    void *spec;
} cli_options;

int cli_parse_options(const cli_options *groups, size_t ngroups, int argc, char **argv,
                      int *help, bkf_error *err);

/* The options block of a usage text, from the same tables: "  --NAME FORM"
 * then the help lines and the default. */
void cli_options_help(FILE *out, const cli_options *groups, size_t ngroups);

/* Whether argv (after argv[0]) asks for help: "--help" or "-h". */
int cli_wants_help(int argc, char **argv);

/* The command line, shell-quoted and on one line, for a provenance comment.
 * Caller frees; NULL when out of memory. */
char *cli_command_line(int argc, char **argv);

/* All-or-nothing output: standard output, or a file replaced atomically.
 * Open before computing (so a bad path fails before any work), write the
 * finished buffer once, or abort.  While a file is open its temporary is
 * removed if SIGINT, SIGTERM or SIGHUP ends the process (up to 4 files open
 * at once; SIGKILL cannot be caught, see bkf_io_atomic_open for what
 * happens to its temporary). */
typedef struct {
    bkf_io_atomic *file;  /* NULL: standard output (or `device`) */
    int slot;             /* the signal cleanup's slot for its temporary */
    FILE *device;         /* a character device such as /dev/null, written directly:
                             it cannot be replaced, and has nothing to truncate */
} cli_output;

int cli_output_open(cli_output *out, const char *path, const char *flag, bkf_error *err);
int cli_output_write(cli_output *out, const char *data, size_t size, bkf_error *err);
void cli_output_abort(cli_output *out);

/* What every table-writing command takes besides its product's keys. */
typedef struct {
    int format;           /* index in tsv, json */
    const char *out;      /* NULL: standard output */
} cli_output_spec;

extern const bkf_option cli_output_options[];
extern const size_t cli_output_noptions;

/* A product's table writer: the whole table to `out`. */
typedef int (*cli_table_writer)(const void *spec, FILE *out, bkf_io_format format,
                                const bkf_provenance *provenance, bkf_error *err);

/* All or nothing: opens --out (before any work), builds the table in memory
 * with the provenance "bkfront VERSION" and "command: bkfront ARGS", and
 * writes it only when `write` succeeded. */
int cli_write_table(const cli_output_spec *output, int argc, char **argv,
                    cli_table_writer write, const void *spec, bkf_error *err);
/* The same, but a write that returns BKF_ECANCELED after a complete table
 * of what was done (marked so by the product) is written too, and the
 * status kept: an interrupted simulation keeps its frames. */
int cli_write_table_kept(const cli_output_spec *output, int argc, char **argv,
                         cli_table_writer write, const void *spec, int keep_canceled,
                         bkf_error *err);

/* A temporary file that SIGINT/SIGTERM (and the other fatal signals the
 * CLI handles) remove until unguarded, for a file written by the library
 * (bkf_io_atomic): returns its slot, -1 when it cannot be guarded. */
int cli_guard_temp(const char *temp);
void cli_unguard_temp(int slot);

/* Cancellation by SIGINT or SIGTERM: between cli_cancel_begin and
 * cli_cancel_end the first such signal sets the returned flag (give it to a
 * library call that checks one, e.g. bkf_pde_options.cancel) instead of
 * ending the process; a second one ends it (temporaries removed).
 * cli_cancel_signal is the signal that set the flag, or 0. */
const volatile sig_atomic_t *cli_cancel_begin(void);
void cli_cancel_end(void);
int cli_cancel_signal(void);

/* Not a library status: the table is written whole, but some of its rows
 * are refused (each says why); exit 3, so that a script tells a partial
 * table from a whole one (0) and from no table (1). */
#define CLI_PARTIAL 1000

/* The exit code for a status: 0 ok, 2 bad input, 3 CLI_PARTIAL, 128 + the
 * signal for a run canceled by one (130 for SIGINT, as a shell reports
 * Ctrl-C; 130 also when no signal is known), 1 for every other failure
 * (numerical, a refused tolerance, a spent budget, a blow-up, memory, I/O). */
int cli_exit_code(int status);

/* An in-memory stream to build the whole output in.  Unlike glibc's
 * open_memstream, whose failed growth sets no error flag (fflush and fclose
 * then succeed on a silently cut buffer), a write that cannot grow it fails
 * and marks the stream, so close reports it.  The stream keeps a pointer to
 * *buf: buf must not move while the stream is open. */
typedef struct {
    FILE *stream;
    char *data;
    size_t size;
    size_t cap;
    int failed; /* a write could not grow the buffer */
} cli_buffer;

int cli_buffer_open(cli_buffer *buf, bkf_error *err);
/* Closes the stream; data and size are then final.  BKF_ENOMEM when any
 * write could not be stored. */
int cli_buffer_close(cli_buffer *buf, bkf_error *err);
void cli_buffer_free(cli_buffer *buf);

#endif

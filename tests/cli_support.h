/* Running the built bkfront (BKF_CLI_PATH) from a test as a user would: the
 * one fork/exec runner every test of the executable shares.  The child gets
 * the default signal dispositions and an empty signal mask (a runner started
 * in the background may ignore SIGINT, and bkfront keeps an ignored SIGINT,
 * as nohup expects), stdin from /dev/null unless text is given, and stays in
 * the test's process group, so the test runner can end it with the test. */
#ifndef BKF_TEST_CLI_SUPPORT_H
#define BKF_TEST_CLI_SUPPORT_H

#include <stddef.h>
#include <sys/types.h>

typedef struct {
    char *out, *err; /* all of stdout and stderr, NUL-terminated, malloc'd */
    int code;        /* exit status, or -1 when a signal ended the run */
    int signal;      /* that signal, or 0 */
} bkf_cli_result;

typedef struct {
    const char *dir;        /* working directory (NULL: the test's) */
    const char *in;         /* text on stdin (NULL: /dev/null) */
    const char *const *env; /* "NAME=VALUE" entries to set, NULL-terminated */
    unsigned timeout_s;     /* ended by SIGALRM after this many seconds (0:
                               by the test's own time limit only) */
    unsigned long file_limit; /* the largest file it may write, in bytes
                                 (RLIMIT_FSIZE, ulimit -f); 0: no limit */
} bkf_cli_options;

/* bkfront ARGS... (args NULL-terminated, without the program name); o may be
 * NULL.  Output goes to unlinked temporary files rather than pipes: no
 * deadlock however much the child writes. */
bkf_cli_result bkf_cli_run(const char *const *args, const bkf_cli_options *o);
void bkf_cli_result_free(bkf_cli_result *r);

/* Starts bkfront without waiting for it (for tests that signal it):
 * stdout and stderr to the files out_path and err_path (relative to the
 * test's working directory, truncated; NULL: /dev/null).  Returns the pid. */
pid_t bkf_cli_spawn(const char *const *args, const bkf_cli_options *o, const char *out_path,
                    const char *err_path);

/* The whole file at path, NUL-terminated and malloc'd; NULL when it cannot
 * be opened (an output the run should not have left). */
char *bkf_cli_read_file(const char *path);

/* Writes text to path (a test's input file); fails the test if it cannot. */
void bkf_cli_write_text(const char *path, const char *text);

/* The number of newlines in s. */
size_t bkf_count_lines(const char *s);

/* Bad input as every command must answer it: exit 2, nothing on stdout,
 * one line on stderr that starts "bkfront CMD: " and contains `names`.
 * Frees r. */
void bkf_cli_expect_bad_input(bkf_cli_result r, const char *cmd, const char *names,
                              const char *what);

/* Cell `column` of data row `row` (0-based) of a TSV table ('#' lines,
 * then the header): the number into *value and/or the text into text
 * (size bytes).  0 when there is no such cell, or *value is asked and the
 * cell is not a number. */
int bkf_tsv_cell(const char *tsv, int row, const char *column, double *value, char *text,
                 size_t size);

/* stdout of `bkfront WORDS` (words separated by single spaces, no quoting),
 * malloc'd; *code gets the exit status (NULL: it must be 0, else the test
 * fails). */
char *bkf_cli_stdout(const char *words, int *code);

#define BKF_CLI_ARGS(...) ((const char *const[]){__VA_ARGS__, NULL})
/* bkfront ARGS... with the default options */
#define BKF_CLI(...) bkf_cli_run(BKF_CLI_ARGS(__VA_ARGS__), NULL)

#endif

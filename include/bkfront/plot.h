/* Figures with gnuplot, and the data files they read.
 *
 * A figure is a gnuplot script (plots/NAME.gp) run with variables set on the
 * command line (`gnuplot -e "name = value; ..." script`), once per output
 * format, in one gnuplot process.  Every script receives `fmt` ("png",
 * "pdf" or "svg") and `out` (the file to write) besides the job's own
 * variables.  Images are written to a temporary name beside the target and
 * renamed only when gnuplot exits 0 and each file is a whole image, so a failed
 * figure never leaves a half-written image behind.
 *
 * gnuplot is run by fork/exec with standard input and output on /dev/null
 * and its standard error captured: on failure the message is gnuplot's own
 * error line; on success its first warning, if any, is reported.  Nothing
 * is printed. */
#ifndef BKFRONT_PLOT_H
#define BKFRONT_PLOT_H

#include <signal.h>
#include <stddef.h>
#include <stdio.h>
#include "bkfront/io.h"
#include "bkfront/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The largest width and height of a figure, in pixels (a PNG of 30000 x
 * 30000 takes gnuplot 2.5 GB; 8000 x 8000 about 260 MB). */
#define BKF_PLOT_PIXELS_MAX 8000

typedef enum { BKF_PLOT_PNG = 0, BKF_PLOT_PDF = 1, BKF_PLOT_SVG = 2 } bkf_plot_format;
#define BKF_PLOT_NFORMATS 3

/* "png", "pdf", "svg" (also the file extensions); NULL outside the enum. */
const char *bkf_plot_format_name(bkf_plot_format format);

/* A list of formats as a user gives it ("png,pdf", commas or spaces
 * between) into *formats, bit 1 << format for each (a scene's `formats =`,
 * bkfront run --formats).  BKF_EINPUT for an unknown name or an empty list,
 * the message naming PREFIX NAME ("--" "formats"). */
int bkf_plot_parse_formats(const char *text, const char *prefix, const char *name,
                           unsigned *formats, bkf_error *err);

typedef struct bkf_plot_job bkf_plot_job;

/* A job for `script` (a path; it must be readable).  NULL with err filled
 * (BKF_EINPUT: no such script; BKF_ENOMEM). */
bkf_plot_job *bkf_plot_job_alloc(const char *script, bkf_error *err);
void bkf_plot_job_free(bkf_plot_job *job);

/* Variables.  Names are gnuplot identifiers ([A-Za-z_][A-Za-z0-9_]*, not
 * fmt or out); numbers must be finite or NaN; strings may not hold control
 * characters (a single quote is fine).  BKF_EINPUT otherwise. */
int bkf_plot_set_number(bkf_plot_job *job, const char *name, double value, bkf_error *err);
int bkf_plot_set_string(bkf_plot_job *job, const char *name, const char *value,
                        bkf_error *err);

/* One image to make; at most one per format. */
int bkf_plot_add_output(bkf_plot_job *job, bkf_plot_format format, const char *path,
                        bkf_error *err);

typedef struct {
    const char *gnuplot;   /* program, looked up in PATH; NULL: "gnuplot" */
    double timeout;        /* seconds before gnuplot is killed; <= 0: 60 */
    /* Raised (a signal handler's flag): gnuplot is killed at once and
     * nothing is written (BKF_ECANCELED).  NULL: never. */
    const volatile sig_atomic_t *cancel;
    /* Told each image's temporary while it exists (armed 1) and when it is
     * gone (armed 0), so that a signal handler may remove it.  NULL: none. */
    void (*temp_file)(const char *path, int armed, void *data);
    void *data;
} bkf_plot_options;

bkf_plot_options bkf_plot_options_default(void);

typedef struct {
    int exit_code;         /* gnuplot's, or -1 when killed or not started */
    double seconds;
    char warning[BKF_ERROR_LEN];  /* gnuplot's first warning line, or empty */
} bkf_plot_report;

/* Run the job.  BKF_OK when gnuplot exited 0 and wrote every output whole
 * (a PNG ending in its IEND chunk, a PDF in %%EOF, an SVG in </svg>);
 * BKF_EIO when it exited 0 but an image is truncated (gnuplot does not
 * report a failed write: a full disk, a file size limit); BKF_ENUMERIC
 * with gnuplot's error line otherwise (also for a timeout or a signal);
 * BKF_ECANCELED when options->cancel was raised; BKF_EINPUT when gnuplot
 * cannot be started or the job has no output.  No image is replaced unless
 * all are good.  gnuplot dies with the calling process.  report may be
 * NULL. */
int bkf_plot_run(const bkf_plot_job *job, const bkf_plot_options *options,
                 bkf_plot_report *report, bkf_error *err);

/* Whether gnuplot runs: BKF_OK and its version line ("gnuplot 5.4
 * patchlevel 4") in `version` (may be NULL), BKF_EINPUT with the reason. */
int bkf_plot_probe(const char *gnuplot, char *version, size_t size, bkf_error *err);

/* ------------------------------------------------------------ data files */

/* A TSV table written to a temporary file and renamed onto `path` on
 * commit (bkf_io_atomic), so a figure never reads a half-written file. */
typedef struct bkf_plot_data bkf_plot_data;

bkf_plot_data *bkf_plot_data_open(const char *path, const bkf_io_column *columns,
                                  size_t ncolumns, bkf_error *err);
bkf_io_table *bkf_plot_data_table(bkf_plot_data *data);
/* Finish the table and rename it into place; frees data in every case. */
int bkf_plot_data_commit(bkf_plot_data *data, bkf_error *err);
/* Remove the temporary file and free (NULL is a no-op). */
void bkf_plot_data_abort(bkf_plot_data *data);

#ifdef __cplusplus
}
#endif

#endif

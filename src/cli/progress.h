/* A progress bar for long runs, and its flag --no-progress.
 *
 * Drawn on stderr only when it is a terminal and the run has already taken
 * half a second; at most ten redraws a second; erased at the end. */
#ifndef BKFRONT_CLI_PROGRESS_H
#define BKFRONT_CLI_PROGRESS_H

#include "args.h"

typedef struct {
    int enabled, drawn;
    double start, last;
    const char *label;
    double base, share; /* this run's part of the whole: base + share * fraction */
} progress_bar;

/* The command line's alone: no scene key. */
typedef struct {
    int no_progress;
} cli_progress_spec;

extern const bkf_option cli_progress_options[];
extern const size_t cli_progress_noptions;

void progress_init(progress_bar *p, const char *label, int allowed);
/* A bkf_pde_progress: data is the bar; never asks to stop. */
int progress_draw(double fraction, void *data);
/* Points done of total, with the time left at the rate so far. */
void progress_count(progress_bar *p, size_t done, size_t total);
void progress_end(progress_bar *p);

#endif

/* What bkfront simulate and bkfront check share: the paper's defaults, the
 * model flags, number formatting, provenance comments, the progress bar and
 * the front level. */
#ifndef BKFRONT_CLI_SIMCOMMON_H
#define BKFRONT_CLI_SIMCOMMON_H

#include "args.h"

#include "bkfront/init.h"
#include "bkfront/io.h"
#include "bkfront/pde.h"
#include "bkfront/seed.h"

/* Transitional, for src/cli/cmd_check.c until it is moved: its calls of
 * bkf_pde_init_front mean today's bkf_seed_front (the pde function now
 * takes the solved wave).  To be removed when cmd_check.c calls
 * bkf_seed_front. */

/* Paper's parameters (PRL 79, 527): the defaults of both subcommands. */
#define DEF_GAMMA 2.0
#define DEF_C 0.3
#define DEF_NU -0.96
#define DEF_S 20.0
#define DEF_N 512
#define DEF_TMAX 125.0
#define DEF_TOL 1e-9
#define DEF_FRAMES 500
#define TMAX_MAX 1e6
#define PI 3.14159265358979323846

extern const char *const format_names[];
extern const char *const model_names[];
extern const char *const stepper_names[];
extern const char *const spacetime_names[];


/* Drawn on stderr only when it is a terminal and the run has already taken
 * half a second; at most ten redraws a second; erased at the end. */
typedef struct {
    int enabled, drawn;
    double start, last;
    const char *label;
    double base, share; /* this run's part of the whole: base + share * fraction */
} progress_bar;

typedef struct {
    const char *gamma, *c, *nu, *S, *N, *tol, *model, *stepper, *format, *out, *seed, *tmax,
        *filter;
    int dealias;
} model_flags;

typedef struct {
    bkf_model_params params;
    bkf_pde_options options;
    int N_given;
    unsigned long seed;
    double tmax;
    bkf_io_format format;
    const char *out_path;
} model_plan;

const char *num(double x, char *buf, size_t size);
double now_seconds(void);
void progress_init(progress_bar *p, const char *label, int allowed);
int progress_draw(double fraction, void *data);
void progress_end(progress_bar *p);
int parse_positive(const char *flag, const char *text, double *v, bkf_error *err);
int parse_seed(const char *text, unsigned long *seed, bkf_error *err);
int plan_model(const model_flags *f, model_plan *p, bkf_error *err);
int comment_command(bkf_io_table *t, int argc, char **argv, bkf_error *err);
int commentf(bkf_io_table *t, bkf_error *err, const char *fmt, ...);
int comment_model(bkf_io_table *t, const model_plan *p, bkf_error *err);
/* bkf_measure_front_level, for cmd_check.c until it calls that itself. */

#endif

/* Internal to the check product (src/products/check.c, check_judge.c,
 * check_continuum.c, check_chain.c): the run's shared state and the pieces
 * the files share.  Dependencies point one way: check.c (the run and the
 * product) -> check_continuum.c, check_chain.c -> check_judge.c.  Not
 * installed, not part of the API. */
#ifndef BKFRONT_CHECK_INTERNAL_H
#define BKFRONT_CHECK_INTERNAL_H

#include <signal.h>
#include <stddef.h>

#include "bkfront/check.h"
#include "bkfront/chainwave.h"
#include "bkfront/comoving.h"
#include "bkfront/cycle.h"
#include "bkfront/measure.h"
#include "bkfront/seed.h"
#include "bkfront/speeds.h"
#include "bkfront/stability.h"
#include "bkfront/fft.h"

/* A root's warnings, held until its row is delivered (the roots run in
 * threads; the lines come out in the order of a serial run): messages
 * one after the other, each ending in '\0'. */
typedef struct {
    char *text;
    size_t used, cap;
    int oom;
} check_notes;

/* The progress of roots running at once: each root's own fraction, their
 * mean the whole check's. */
typedef struct {
    double *fraction; /* per root */
    size_t roots;
} check_shared;

/* The whole run's state shared by the roots, and the root's own (one copy
 * per root). */
typedef struct {
    const bkf_model_params *model;
    const bkf_check_options *o;
    const bkf_check_hooks *hooks;
    double tol, mapped_tol, level;
    size_t root_index, roots; /* progress: this root's share of the whole */
    check_shared *shared;     /* NULL: progress straight to the hook */
    check_notes *notes;       /* NULL: warnings straight to the hook */
} check_ctx;

typedef void (*record_reader)(size_t i, const void *data, double *t, size_t *fronts,
                              double *deviation);

/* A speed fit needs this many coherent records past the first. */
#define FIT_MIN_RECORDS 6

/* check_judge.c */
double check_uniform_tol(const bkf_check_options *o);
double check_mapped_tol(const bkf_check_options *o);
double check_speeds_tol(const bkf_check_options *o);
void check_growth_merge(bkf_check_growth *into, const bkf_check_growth *g, int first);
double check_sample_dt(double base, double tmax);
int check_progress(double fraction, void *data);
const volatile sig_atomic_t *check_cancel(const check_ctx *c);
void check_warn(const check_ctx *c, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
double check_transient_end(double tmax);
size_t check_coherent_end(record_reader at, const void *data, size_t R, size_t n, int settle,
                          double bound, double tmax);
double check_speed_bound(const bkf_check_options *o);
double check_linear_bound(const bkf_check_options *o);
int check_fit_deviation(record_reader at, const void *data, size_t R, size_t n,
                        const bkf_check_options *o, bkf_check_growth *g, double *t_to);
void check_row_init(bkf_check_row *row, size_t n, size_t root, const bkf_speeds_root *sr);
void check_explain_undecided(const check_ctx *c, bkf_check_row *row);
int check_auto_settled(const bkf_check_options *o, const bkf_check_row *row, double t);
int check_speed_judged(const bkf_check_row *row);

/* check_continuum.c */
int check_root(const check_ctx *c, const bkf_speeds_root *sr, bkf_check_row *row,
               bkf_error *err);
void check_spectrum(const check_ctx *c, const bkf_speeds_root *sr, bkf_check_row *row);

/* check_chain.c */
int check_chain_run(const bkf_model_params *model, const bkf_check_options *o,
                    const bkf_check_hooks *hooks, bkf_error *err);

#endif

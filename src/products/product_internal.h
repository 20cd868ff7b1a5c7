/* What the product modules share in writing a table: the title comment
 * opened by the provenance's program, and its command after the product's
 * own comments (bkf_provenance, options.h); and the threads of their
 * parallel loops. */
#ifndef BKFRONT_PRODUCT_INTERNAL_H
#define BKFRONT_PRODUCT_INTERNAL_H

#include <stddef.h>
#include <stdio.h>
#include "bkfront/cycle.h"
#include "bkfront/io.h"
#include "bkfront/model.h"
#include "bkfront/options.h"
#include "bkfront/status.h"
#ifdef _OPENMP
#include <omp.h>
#endif

/* The threads a product's `threads` option asks for: 0 is every core
 * (OpenMP's default); 1 without OpenMP. */
static inline int bkf_product_threads(size_t asked)
{
#ifdef _OPENMP
    return asked ? (int)asked : omp_get_max_threads();
#else
    (void)asked;
    return 1;
#endif
}

/* *table with "PROGRAM TITLE" written (PROGRAM "libbkfront" without one;
 * TITLE alone without a provenance); NULL on failure. */
int bkf_product_table_open(FILE *out, bkf_io_format format, const bkf_io_column *columns,
                           size_t ncolumns, const char *title, const bkf_provenance *prov,
                           bkf_io_table **table, bkf_error *err);

/* "command: COMMAND" when the provenance has one. */
int bkf_product_table_command(bkf_io_table *table, const bkf_provenance *prov, bkf_error *err);

/* A table written into an atomic file (either may be NULL), closed on
 * status s: finished and the file committed when s is BKF_OK, else the
 * file removed, never left half written.  The status it ends with. */
int bkf_product_table_file_close(bkf_io_table *table, bkf_io_atomic *file, int s,
                                 bkf_error *err);

/* The model's keys as the tables of the cycle-based products write them,
 * each defaulting to the paper's value (bkf_model_paper_where_unset:
 * a spec keeps NaN for "not given"); c's range differs between products. */
#define BKF_PRODUCT_GAMMA_OPTION(SPEC)                                                      \
    {.name = "gamma", .type = BKF_OPT_DOUBLE, .offset = offsetof(SPEC, gamma),              \
     .flags = BKF_OPT_MIN | BKF_OPT_MAX, .min = BKF_CYCLE_MU_MIN,                           \
     .max = BKF_CYCLE_MU_MAX, .form = "G", .shown_default = BKF_TEXT_OF(BKF_PAPER_GAMMA),   \
     .help = "friction strength, in [1e-06, 1e+06] (mu >= gamma must be\n"                  \
             "solvable)"}
#define BKF_PRODUCT_NU_OPTION(SPEC)                                                         \
    {.name = "nu", .type = BKF_OPT_DOUBLE, .offset = offsetof(SPEC, nu), .form = "V",       \
     .shown_default = BKF_TEXT_OF(BKF_PAPER_NU),                                            \
     .help = "pulling rate in (-1, 1); |nu| >= 1 has no fronts"}
#define BKF_PRODUCT_S_OPTION(SPEC)                                                          \
    {.name = "S", .type = BKF_OPT_DOUBLE, .offset = offsetof(SPEC, S),                      \
     .flags = BKF_OPT_MIN | BKF_OPT_MIN_OPEN, .min = 0, .form = "L",                        \
     .shown_default = BKF_TEXT_OF(BKF_PAPER_S), .help = "system size, > 0"}

#endif

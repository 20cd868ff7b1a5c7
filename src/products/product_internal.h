/* What the product modules share in writing a table: the title comment
 * opened by the provenance's program, and its command after the product's
 * own comments (bkf_provenance, options.h). */
#ifndef BKFRONT_PRODUCT_INTERNAL_H
#define BKFRONT_PRODUCT_INTERNAL_H

#include <stddef.h>
#include <stdio.h>
#include "bkfront/cycle.h"
#include "bkfront/io.h"
#include "bkfront/options.h"
#include "bkfront/status.h"

/* *table with "PROGRAM TITLE" written (PROGRAM "libbkfront" without one;
 * TITLE alone without a provenance); NULL on failure. */
int bkf_product_table_open(FILE *out, bkf_io_format format, const bkf_io_column *columns,
                           size_t ncolumns, const char *title, const bkf_provenance *prov,
                           bkf_io_table **table, bkf_error *err);

/* "command: COMMAND" when the provenance has one. */
int bkf_product_table_command(bkf_io_table *table, const bkf_provenance *prov, bkf_error *err);

/* The model's keys as the tables of the cycle-based products write them
 * (REQUIRED: BKF_OPT_REQUIRED or 0); c's range differs between products. */
#define BKF_PRODUCT_GAMMA_OPTION(SPEC, required)                                            \
    {.name = "gamma", .type = BKF_OPT_DOUBLE, .offset = offsetof(SPEC, gamma),              \
     .flags = (required) | BKF_OPT_MIN | BKF_OPT_MAX, .min = BKF_CYCLE_MU_MIN,              \
     .max = BKF_CYCLE_MU_MAX, .form = "G",                                                  \
     .help = "friction strength, in [1e-06, 1e+06] (mu >= gamma must be\n"                  \
             "solvable)"}
#define BKF_PRODUCT_NU_OPTION(SPEC, required)                                               \
    {.name = "nu", .type = BKF_OPT_DOUBLE, .offset = offsetof(SPEC, nu), .flags = (required), \
     .form = "V", .help = "pulling rate in (-1, 1); |nu| >= 1 has no fronts"}
#define BKF_PRODUCT_S_OPTION(SPEC, required)                                                \
    {.name = "S", .type = BKF_OPT_DOUBLE, .offset = offsetof(SPEC, S),                      \
     .flags = (required) | BKF_OPT_MIN | BKF_OPT_MIN_OPEN, .min = 0, .form = "L",           \
     .help = "system size, > 0"}

#endif

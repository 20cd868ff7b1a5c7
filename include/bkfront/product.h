/* What every product's table shares: where it goes and what the caller adds.
 *
 * A product (fronts, oscillation, friction, ...) computes its rows with the
 * numerical modules and writes one table (io.h): a title comment, the
 * product's own comments (parameters, key results, work), then the rows.
 * The caller names the program in the title ("bkfront 0.1.0 speeds: ...")
 * and may add one comment after the product's own, before the rows (the
 * CLI's "command: ..." line); a C program may leave both NULL. */
#ifndef BKFRONT_PRODUCT_H
#define BKFRONT_PRODUCT_H

#include <stddef.h>
#include <stdio.h>
#include "bkfront/io.h"
#include "bkfront/status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    FILE *stream;          /* the caller's; written, flushed, never closed */
    bkf_io_format format;  /* default BKF_IO_TSV */
    const char *program;   /* the title reads "PROGRAM TITLE"; NULL: TITLE alone */
    const char *command;   /* one comment after the product's own, or NULL */
    /* A row kept with a flag instead of failing the table (a refused q of the
     * dispersion) is reported here, one line; NULL: not reported. */
    void (*warn)(const char *message, void *data);
    void *warn_data;
} bkf_product_output;

/* stream, TSV, no program, no command, no warnings. */
bkf_product_output bkf_product_output_default(FILE *stream);

/* For the product modules: *table with its title comment written (NULL on
 * failure). */
int bkf_product_table_open(const bkf_product_output *out, const bkf_io_column *columns,
                           size_t ncolumns, const char *title, bkf_io_table **table,
                           bkf_error *err);
/* The caller's comment (out->command), written after the product's own. */
int bkf_product_table_command(bkf_io_table *table, const bkf_product_output *out,
                              bkf_error *err);

/* The shortest of "%.15g" / "%.17g" that reads back as x, for comments.
 * Returns buf (size >= 32). */
const char *bkf_product_number(double x, char *buf, size_t size);

#ifdef __cplusplus
}
#endif

#endif

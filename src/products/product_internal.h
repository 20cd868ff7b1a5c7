/* What the product modules share in writing a table: the title comment
 * opened by the provenance's program, and its command after the product's
 * own comments (bkf_provenance, options.h). */
#ifndef BKFRONT_PRODUCT_INTERNAL_H
#define BKFRONT_PRODUCT_INTERNAL_H

#include <stddef.h>
#include <stdio.h>
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

#endif

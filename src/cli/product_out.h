/* A library product's table as every subcommand writes it: built in memory,
 * with "bkfront VERSION" in its title and the command line after the
 * product's comments, then written all or nothing (args.h). */
#ifndef BKFRONT_CLI_PRODUCT_OUT_H
#define BKFRONT_CLI_PRODUCT_OUT_H

#include "args.h"
#include "bkfront/product.h"

/* Writes one product's table: write(spec, out, err) is the library call. */
typedef int (*cli_product_write)(const void *spec, const bkf_product_output *out,
                                 bkf_error *err);

/* out_path NULL: standard output.  Warnings of the product go to stderr as
 * "bkfront NAME: warning: ..." with NAME = argv[0]. */
int cli_write_product(const char *out_path, bkf_io_format format, cli_product_write write,
                      const void *spec, int argc, char **argv, bkf_error *err);

#endif

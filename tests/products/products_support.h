/* Helpers of the products' tests: a product written through the library into
 * memory, the same product through the bkfront executable, and the parts of
 * a table the two must share (the header and the rows; the comments differ
 * in their provenance). */
#ifndef BKF_TEST_PRODUCTS_SUPPORT_H
#define BKF_TEST_PRODUCTS_SUPPORT_H

#define _POSIX_C_SOURCE 200809L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bkfront/io.h"
#include "bkfront/options.h"
#include "cli_support.h"
#include "harness.h"

#ifndef BKF_CLI_PATH
#error "BKF_CLI_PATH (the built bkfront binary) is defined by the Makefile for tests"
#endif

/* A product's writer as the library exports it. */
typedef int (*product_writer)(const void *spec, FILE *out, bkf_io_format format,
                              const bkf_provenance *prov, bkf_error *err);

/* The product's whole output through the library (caller frees). */
static inline char *library_output(product_writer write, const void *spec, bkf_io_format format)
{
    char *data = NULL;
    size_t size = 0;
    FILE *f = open_memstream(&data, &size);
    CHECK(f);
    bkf_error e = {0};
    int s = write(spec, f, format, NULL, &e);
    CHECK(fclose(f) == 0);
    CHECK_MSG(s == BKF_OK, "library: %s", e.message);
    return data;
}

/* stdout of `bkfront ARGS` (ARGS words separated by spaces, no quoting),
 * which must exit 0 (caller frees). */
static inline char *cli_output(const char *args) { return bkf_cli_stdout(args, NULL); }

/* The lines of a TSV table that are not comments, in a fresh string. */
static inline char *table_body(const char *tsv)
{
    char *body = malloc(strlen(tsv) + 1);
    CHECK(body);
    size_t n = 0;
    for (const char *line = tsv; *line;) {
        const char *end = strchr(line, '\n');
        size_t len = end ? (size_t)(end - line) + 1 : strlen(line);
        if (line[0] != '#') {
            memcpy(body + n, line, len);
            n += len;
        }
        line += len;
    }
    body[n] = '\0';
    return body;
}

static inline size_t count_lines(const char *text)
{
    size_t n = 0;
    for (; *text; text++) n += *text == '\n';
    return n;
}

/* The library's table and the executable's have the same header and rows,
 * byte for byte; returns the number of rows. */
static inline size_t check_same_rows(product_writer write, const void *spec, const char *args)
{
    char *lib = library_output(write, spec, BKF_IO_TSV);
    char *cli = cli_output(args);
    char *a = table_body(lib), *b = table_body(cli);
    CHECK_MSG(strcmp(a, b) == 0, "bkfront %s: rows differ\nlibrary:\n%s\ncli:\n%s", args, a, b);
    size_t lines = count_lines(a);
    CHECK_MSG(lines >= 1, "bkfront %s: no header", args);
    free(a);
    free(b);
    free(lib);
    free(cli);
    return lines - 1;
}

#endif

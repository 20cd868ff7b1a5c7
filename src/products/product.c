#include "bkfront/product.h"

#include <stdlib.h>
#include <string.h>

bkf_product_output bkf_product_output_default(FILE *stream)
{
    bkf_product_output o = {stream, BKF_IO_TSV, NULL, NULL, NULL, NULL};
    return o;
}

int bkf_product_table_open(const bkf_product_output *out, const bkf_io_column *columns,
                           size_t ncolumns, const char *title, bkf_io_table **table,
                           bkf_error *err)
{
    *table = NULL;
    if (!out || !out->stream) return bkf_error_set(err, BKF_EINPUT, "product output stream is NULL");
    if (out->format != BKF_IO_TSV && out->format != BKF_IO_JSON)
        return bkf_error_set(err, BKF_EINPUT, "product output format %d is not tsv or json",
                             (int)out->format);
    /* the products' columns are valid: what is left is memory */
    bkf_io_table *t = bkf_io_table_alloc(out->stream, out->format, columns, ncolumns, err);
    if (!t) return BKF_ENOMEM;
    int s;
    if (out->program) {
        size_t n = strlen(out->program) + strlen(title) + 2;
        char *line = malloc(n);
        if (!line) {
            bkf_io_table_free(t);
            return bkf_error_set(err, BKF_ENOMEM, "out of memory");
        }
        snprintf(line, n, "%s %s", out->program, title);
        s = bkf_io_table_comment(t, line, err);
        free(line);
    } else {
        s = bkf_io_table_comment(t, title, err);
    }
    if (s) {
        bkf_io_table_free(t);
        return s;
    }
    *table = t;
    return BKF_OK;
}

int bkf_product_table_command(bkf_io_table *table, const bkf_product_output *out,
                              bkf_error *err)
{
    return out->command ? bkf_io_table_comment(table, out->command, err) : BKF_OK;
}

const char *bkf_product_number(double x, char *buf, size_t size)
{
    snprintf(buf, size, "%.15g", x);
    if (strtod(buf, NULL) != x) snprintf(buf, size, "%.17g", x);
    return buf;
}

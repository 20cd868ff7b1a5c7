#include "product_internal.h"

#include <stdlib.h>
#include <string.h>

/* "A B" or "A: B" into a fresh comment. */
static int comment_joined(bkf_io_table *t, const char *a, const char *sep, const char *b,
                          bkf_error *err)
{
    size_t n = strlen(a) + strlen(sep) + strlen(b) + 1;
    char *line = malloc(n);
    if (!line) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    snprintf(line, n, "%s%s%s", a, sep, b);
    int s = bkf_io_table_comment(t, line, err);
    free(line);
    return s;
}

int bkf_product_table_open(FILE *out, bkf_io_format format, const bkf_io_column *columns,
                           size_t ncolumns, const char *title, const bkf_provenance *prov,
                           bkf_io_table **table, bkf_error *err)
{
    *table = NULL;
    if (!out) return bkf_error_set(err, BKF_EINPUT, "the output stream is NULL");
    if (format != BKF_IO_TSV && format != BKF_IO_JSON)
        return bkf_error_set(err, BKF_EINPUT, "format %d is not tsv or json", (int)format);
    /* the products' columns are valid: what is left is memory */
    bkf_io_table *t = bkf_io_table_alloc(out, format, columns, ncolumns, err);
    if (!t) return BKF_ENOMEM;
    /* no provenance: the title alone */
    int s = prov ? comment_joined(t, prov->program ? prov->program : "libbkfront", " ", title, err)
                 : bkf_io_table_comment(t, title, err);
    if (s) {
        bkf_io_table_free(t);
        return s;
    }
    *table = t;
    return BKF_OK;
}

int bkf_product_table_file_close(bkf_io_table *table, bkf_io_atomic *file, int s,
                                 bkf_error *err)
{
    if (!s) s = bkf_io_table_finish(table, err);
    bkf_io_table_free(table);
    if (file) {
        if (s) bkf_io_atomic_abort(file);
        else s = bkf_io_atomic_commit(file, err);
    }
    return s;
}

int bkf_product_table_command(bkf_io_table *table, const bkf_provenance *prov, bkf_error *err)
{
    if (!prov || !prov->command) return BKF_OK;
    return comment_joined(table, "command: ", "", prov->command, err);
}

/* Work-precision measurements: for each product (the period T(mu, nu), the
 * speeds table, the PDE simulation) and every method and tolerance bkfront
 * offers, the achieved error against an independent or tight-tolerance
 * reference, beside the CPU time it took.  One table row per (case, method,
 * setting); `bkfront bench` writes them and plots/work_precision_*.gp draw
 * them (docs/benchmarks.md).  The library never prints and never exits. */
#ifndef BKFRONT_BENCH_H
#define BKFRONT_BENCH_H

#include <stddef.h>
#include "bkfront/io.h"
#include "bkfront/options.h"
#include "bkfront/status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
    BKF_BENCH_PERIOD = 0, /* T(mu, nu): formulas, rk8pd and bsimp at tol 1e-2 .. 1e-12 */
    BKF_BENCH_SPEEDS = 1, /* the paper's speeds table at tol 1e-4 .. 1e-12 */
    BKF_BENCH_PDE = 2,    /* a seeded n = 4 front on N in {256, 512, 1024} */
    BKF_BENCH_ALL = 3,    /* period, speeds and pde */
    BKF_BENCH_BOX = 4     /* the cost of tol 1e-12 against 1e-6 over a (mu, nu) box */
} bkf_bench_product;

/* "period", "speeds", "pde", "all", "box" in enum order, NULL-terminated. */
const char *const *bkf_bench_product_names(void);

/* The table's columns: product, case, method, tol, N, error, estimate,
 * cpu_seconds, work, status. */
const bkf_io_column *bkf_bench_columns(size_t *count);

/* Measures `which` (fewer cases and tolerances with `quick`) and writes the
 * rows (box also comment lines, before its rows) into `table`, which must
 * have bkf_bench_columns's columns. */
int bkf_bench_run(bkf_bench_product which, int quick, bkf_io_table *table, bkf_error *err);

/* As a product with keys (`bkfront bench`, the catalogue): which
 * measurement and how thorough. */
typedef struct {
    int product; /* bkf_bench_product; default BKF_BENCH_ALL */
    int quick;   /* switch */
} bkf_bench_spec;

bkf_bench_spec bkf_bench_spec_default(void);

/* The keys: product, quick. */
extern const bkf_option bkf_bench_options[];
extern const size_t bkf_bench_noptions;

int bkf_bench_check(const bkf_bench_spec *spec, const char *prefix, bkf_error *err);

/* The whole table: title, the caller's command, rows. */
int bkf_bench_write(const bkf_bench_spec *spec, FILE *out, bkf_io_format format,
                    const bkf_provenance *provenance, bkf_error *err);

#ifdef __cplusplus
}
#endif

#endif

/* The asymptotics product: the asymptotic formulas for T(mu, nu) checked
 * against the numerical period (asymfit.h) in one of three modes
 * (`bkfront asymptotics`):
 *   fit   the expansion coefficients fitted on log-spaced mu, beside the
 *         derived ones, per nu;
 *   map   for each formula, threshold eps and nu, the boundary mu of the
 *         region where the formula holds to eps;
 *   grid  T and each formula's relative error on a (mu, nu) grid.
 *
 * bkf_approx_options is the table of its keys; fill a spec from
 * bkf_approx_spec_default, apply values through the table, check, write.
 * The mode is one choice made two ways: the scene key mode = fit|map|grid,
 * or on the command line one of the switches --fit, --map, --grid. */
#ifndef BKFRONT_APPROX_H
#define BKFRONT_APPROX_H

#include <stddef.h>
#include <stdio.h>
#include "bkfront/io.h"
#include "bkfront/options.h"
#include "bkfront/status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum { BKF_APPROX_FIT = 0, BKF_APPROX_MAP = 1, BKF_APPROX_GRID = 2 } bkf_approx_mode;

typedef struct {
    int mode;            /* scene key: a bkf_approx_mode, -1 (default) none */
    int fit, map, grid;  /* the command line's switches for the same choice */
    int log;             /* grid: geometric mu list */
    /* An empty list is one not given. */
    bkf_list nu;         /* |nu| < 1; required for fit and grid, map default
                            0,+-0.5,+-0.9,+-0.96,+-0.99,+-0.999 */
    bkf_list mu;         /* fit: large-mu range A:B:N, 1 <= A < B <= BKF_CYCLE_MU_MAX,
                            N >= 10 (its ends and N; spaced geometrically whatever
                            log says); grid (required): the mu values, each in
                            [BKF_CYCLE_MU_MIN, BKF_CYCLE_MU_MAX] */
    bkf_list small_mu;   /* fit: small-mu range A:B:N, BKF_CYCLE_MU_MIN <= A < B <= 1, N >= 6 */
    bkf_list eps;        /* map: thresholds in [1e-10, 1); default 1e-2,1e-4,1e-6 */
} bkf_approx_spec;

bkf_approx_spec bkf_approx_spec_default(void);

/* The keys: fit, map, grid (command line only), nu, log, mu, small-mu, eps,
 * mode (scene only). */
extern const bkf_option bkf_approx_options[];
extern const size_t bkf_approx_noptions;

/* The rules between keys: exactly one mode, which keys that mode takes
 * (small-mu only with fit, eps only with map, log only with grid, no mu with
 * map), what it requires (nu for fit and grid, mu for grid), the fit ranges,
 * eps and nu inside their ranges, the grid's size.  Messages name the keys
 * with `prefix`; the prefix "--" names the mode by its switches (--fit),
 * any other by the key mode. */
int bkf_approx_check(const bkf_approx_spec *spec, const char *prefix, bkf_error *err);

/* The whole table of the spec's mode (comments, header, rows) to `out`; on
 * failure the stream holds a partial table and the caller discards it. */
int bkf_approx_write(const bkf_approx_spec *spec, FILE *out, bkf_io_format format,
                     const bkf_provenance *provenance, bkf_error *err);

void bkf_approx_spec_free(bkf_approx_spec *spec);

#ifdef __cplusplus
}
#endif

#endif

/* The products of the speed-selection condition (module speeds) as tables:
 * every allowed front speed (`bkfront speeds`) and one speed followed along
 * a parameter (`bkfront branch`).  The numbers are bkf_speeds_find's and
 * bkf_speeds_branch's; this module checks the spec, runs them and tabulates
 * (columns below, the same for both tables after branch's first five).
 *
 * Each table is written whole or the call fails: the caller gives a stream
 * (a memory stream for all-or-nothing output). */
#ifndef BKFRONT_FRONTS_H
#define BKFRONT_FRONTS_H

#include <stddef.h>
#include "bkfront/io.h"
#include "bkfront/model.h"
#include "bkfront/product.h"
#include "bkfront/speeds.h"
#include "bkfront/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---------------------------------------------------------------- speeds */

typedef struct {
    bkf_model_params params;     /* gamma, c, nu, S: required (NaN by default) */
    bkf_speeds_options options;  /* tol, n_from, n_to, method: bkf_speeds_options_default */
} bkf_fronts_spec;

bkf_fronts_spec bkf_fronts_spec_default(void);

/* bkf_speeds_check, with the ranges named: BKF_EINPUT or BKF_OK. */
int bkf_fronts_check(const bkf_fronts_spec *spec, bkf_error *err);

/* The columns of one root: n, v, mu, T, T_err, v_over_c, wavelength,
 * period_fixed, v_asym, deviation, v_err, model, residual, slope, flags. */
#define BKF_FRONTS_ROOT_COLUMNS 15
const bkf_io_column *bkf_fronts_columns(size_t *count);
/* The BKF_FRONTS_ROOT_COLUMNS cells of one root (text cells are static). */
void bkf_fronts_root_values(const bkf_speeds_root *root, bkf_io_value *values);

/* Every root (bkf_speeds_find) as a table.  Comments: the parameters, the
 * range of n (n_max, n_bound = S/(k c gamma), k(nu), the infimum of
 * T/sqrt(mu^2 - gamma^2)), the work, the note; in JSON the same key results
 * are the fields of "results": n_max (null when c = 0: every n), n_bound
 * (null when c = 0), k, g_inf, dips_below_k.  *result (if not NULL) receives
 * the table of roots; free it with bkf_speeds_table_free, also on failure. */
int bkf_fronts_write(const bkf_fronts_spec *spec, const bkf_product_output *out,
                     bkf_speeds_table *result, bkf_error *err);

/* ---------------------------------------------------------------- branch */

typedef struct {
    bkf_model_params params;  /* the fixed parameters; the continued one is `from` */
    bkf_speeds_param along;   /* default BKF_SPEEDS_ALONG_S */
    double from, to;          /* required (NaN by default), from != to */
    size_t n;                 /* number of fronts; default 1 */
    size_t root;              /* which root of n at `from`, 1 the fastest; default 1 */
    size_t max_points;        /* regular points at most; 0 (default): no limit */
    double tol;               /* relative accuracy of T and v; default 1e-10 */
} bkf_fronts_branch_spec;

bkf_fronts_branch_spec bkf_fronts_branch_spec_default(void);

/* "S", "nu", "gamma", "c". */
const char *bkf_fronts_param_name(bkf_speeds_param along);

/* The columns: point, S, gamma, c, nu, then the root's. */
const bkf_io_column *bkf_fronts_branch_columns(size_t *count);

/* The spec's parameters with the continued one at `from`. */
bkf_model_params bkf_fronts_branch_start(const bkf_fronts_branch_spec *spec);

/* The ranges bkf_speeds_branch needs (c > 0 along the branch, from != to,
 * each end in its parameter's range): BKF_EINPUT or BKF_OK. */
int bkf_fronts_branch_check(const bkf_fronts_branch_spec *spec, bkf_error *err);

/* The branch (bkf_speeds_branch) as a table: one row per point, fold and
 * sonic end; comments list the folds and how the branch ended (a C program
 * that wants the points as structs calls bkf_speeds_branch). */
int bkf_fronts_branch_write(const bkf_fronts_branch_spec *spec, const bkf_product_output *out,
                            bkf_error *err);

#ifdef __cplusplus
}
#endif

#endif

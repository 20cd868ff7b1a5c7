/* The products of the speed-selection condition (module speeds) as tables:
 * every allowed front speed (`bkfront speeds`) and one speed followed along
 * a parameter (`bkfront branch`).  The numbers are bkf_speeds_find's and
 * bkf_speeds_branch's; this module checks the spec, runs them and tabulates.
 *
 * bkf_fronts_options and bkf_fronts_branch_options are the tables of their
 * keys (flags and scene keys, options.h): fill a spec from its _default,
 * apply values through the table, check, write. */
#ifndef BKFRONT_FRONTS_H
#define BKFRONT_FRONTS_H

#include <stddef.h>
#include <stdio.h>
#include "bkfront/io.h"
#include "bkfront/model.h"
#include "bkfront/options.h"
#include "bkfront/speeds.h"
#include "bkfront/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* --nmax at most: each n costs a few solves, a typo must not mean hours. */
#define BKF_FRONTS_NMAX_MAX 100000u

/* ---------------------------------------------------------------- speeds */

typedef struct {
    double gamma, c, nu, S; /* required (NaN by default); ranges as bkf_speeds_check */
    size_t n;               /* only this n; 0 (default): every n */
    size_t nmax;            /* only n <= nmax; 0 (default): up to n_max, at most
                               BKF_SPEEDS_MAX_ROWS values of n */
    double tol;             /* relative on v; default 1e-10 */
    int method;             /* index in auto, asymptotic, leading, shooting */
    int stability;          /* add each root's spectral verdict (bkf_trainspec_root; c > 0) */
    double stability_tol;   /* its absolute tolerance on sigma, [1e-10, 1e-2]; 0 (default):
                               trainspec's default, 1e-6; only with stability */
    int model;              /* 0 (default): the continuum; 1: the chain of N blocks, its
                               rotating waves (module chainwave) */
    size_t N;               /* chain only: blocks, [2, 400]; 0 (default): S, which must
                               then be a whole number */
    /* Refused roots (bkf_speeds_root.status, flag refused) are rows with NaN
     * numbers and a comment each; when the table has any, it is written and
     * one line is reported here once: "K of M roots refused, the first
     * n = N: WHY".  NULL: not reported.  Not a key. */
    void (*warn)(const char *message, void *data);
    void *warn_data;
} bkf_fronts_spec;

bkf_fronts_spec bkf_fronts_spec_default(void);

/* The keys: gamma, c, nu, S, n, nmax, tol, method, stability, stability-tol, model, N. */
extern const bkf_option bkf_fronts_options[];
extern const size_t bkf_fronts_noptions;

/* What the table cannot judge key by key (n and nmax together, S/(c gamma)
 * below 1e15); messages name the keys with `prefix` ("--" or ""). */
int bkf_fronts_check(const bkf_fronts_spec *spec, const char *prefix, bkf_error *err);

/* The spec as the speeds module's parameters and options. */
void bkf_fronts_setup(const bkf_fronts_spec *spec, bkf_model_params *params,
                      bkf_speeds_options *options);

/* The columns of one root: n, v, mu, T, T_err, v_over_c, wavelength,
 * period_fixed, v_asym, deviation, v_err, model, residual, slope, flags. */
#define BKF_FRONTS_ROOT_COLUMNS 15
const bkf_io_column *bkf_fronts_columns(size_t *count);
/* The BKF_FRONTS_ROOT_COLUMNS cells of one root (text cells are static). */
void bkf_fronts_root_values(const bkf_speeds_root *root, bkf_io_value *values);

/* Every root (bkf_speeds_find) as a table to `out`; with stability, five
 * more columns from each root's ring spectrum: stable (yes, no, unresolved,
 * refused), sigma_max, sigma_max_err, kappa_max, kind (real, complex).  A
 * root whose spectrum fails (BKF_ETOL, BKF_EBUDGET) is unresolved with NaN
 * numbers and a comment saying why; the table is still written.  A refused
 * root (flags refused) is a row with NaN numbers but n, wavelength and
 * v_asym, model empty, stable refused (no spectrum without a root), a
 * comment "refused: n = N, root I: WHY", and spec->warn is told; the count
 * is the result "refused".  Comments: the
 * parameters, the range of n (n_max, n_bound = S/(k c gamma), k(nu), the
 * infimum of T/sqrt(mu^2 - gamma^2)), the work, the note; in JSON the same
 * key results are the fields of "results": n_max and n_bound (null when
 * c = 0: every n has a root), k, g_inf, dips_below_k.  On failure the stream
 * holds a partial table and the caller discards it. */
int bkf_fronts_write(const bkf_fronts_spec *spec, FILE *out, bkf_io_format format,
                     const bkf_provenance *provenance, bkf_error *err);

/* The numbers of bkf_fronts_write's table without the table (continuum
 * only): every root into *table (free it with bkf_speeds_table_free) and,
 * with spec->stability, its verdict into (*stable)[i] (malloc'ed, NULL
 * without stability): 1 yes, 0 no, -1 unresolved (the table's stable
 * column, a spectrum refused with BKF_ETOL or BKF_EBUDGET and a refused
 * root included). */
int bkf_fronts_find(const bkf_fronts_spec *spec, bkf_speeds_table *table, int **stable,
                    bkf_error *err);

/* With model = chain (bkf_chainwave_find: every wave connected to the
 * uncoupled chain, n <= N/2 unless n or nmax say otherwise; tol in
 * [1e-11, 1e-3]; method and stability-tol do not apply) the columns are
 * those of bkf_fronts_chain_columns: n, v, v_err, P, P_err, tau, h,
 * wavelength, residual, psi_min, psi_max, and with stability: stable,
 * sigma_max, sigma_max_err, mult_abs, mult_abs_err, mult_arg, trivial_err. */
#define BKF_FRONTS_CHAIN_COLUMNS 11
#define BKF_FRONTS_CHAIN_STABILITY_COLUMNS 18
const bkf_io_column *bkf_fronts_chain_columns(int stability, size_t *count);

/* ---------------------------------------------------------------- branch */

typedef struct {
    int along;              /* index in S, nu, gamma, c (bkf_speeds_param); required */
    double from, to;        /* the continued parameter's ends, from != to; required */
    double gamma, c, nu, S; /* every one but the continued one: required (NaN) */
    size_t n;               /* number of fronts; default 1 */
    size_t root;            /* which root of n at `from`, 1 the fastest; default 1 */
    size_t max_points;      /* regular points at most; 0 (default): no limit */
    double tol;             /* relative accuracy of T and v; default 1e-10 */
    int stability;          /* each point's spectral verdict, and where it changes */
    double stability_tol;   /* as bkf_fronts_spec's: [1e-10, 1e-2], 0: 1e-6; only with
                               stability */
    int model;              /* 0 continuum (default), 1 chain: bkf_chainwave_branch on the
                               chain of N blocks, along S, nu, gamma, c or h (index 4, chain
                               only: S = N h moves with it, S not given) */
    size_t N;               /* with model chain: blocks, [2, 400]; 0 (default): S */
} bkf_fronts_branch_spec;

bkf_fronts_branch_spec bkf_fronts_branch_spec_default(void);

/* The keys: param, from, to, n, root, gamma, c, nu, S, tol, max-points,
 * stability, stability-tol, model, N. */
extern const bkf_option bkf_fronts_branch_options[];
extern const size_t bkf_fronts_branch_noptions;

/* The ranges bkf_speeds_branch needs: the continued parameter given only as
 * from and to, each end in its range, c > 0 along the branch. */
int bkf_fronts_branch_check(const bkf_fronts_branch_spec *spec, const char *prefix,
                            bkf_error *err);

/* The columns: point, S, gamma, c, nu, then the root's (without stability). */
const bkf_io_column *bkf_fronts_branch_columns(size_t *count);

/* The branch (bkf_speeds_branch) as a table: one row per point, fold and
 * sonic end; comments list the folds and how the branch ended (a C program
 * that wants the points as structs calls bkf_speeds_branch).
 *
 * With stability, the five columns of bkf_fronts_write's stability for each
 * point (a sonic end, and a point whose spectrum is refused, BKF_ETOL or
 * BKF_EBUDGET, are unresolved with a comment saying why), and where
 * sigma_max changes sign between two consecutive points a row of type
 * stability: the parameter where sigma_max = 0 to stability_tol (Brent on
 * the parameter; the root there is re-solved, the one nearest the chord's
 * v), its Bloch number and kind (complex: an oscillatory crossing), also
 * listed in a comment.  A crossing that cannot be located is a comment.
 * Between ring spectra a point's verdict may come from the last one's
 * eigenvalues followed there (bkf_trainspec_track) where they prove it
 * unstable (sigma_max then the rightmost of them), and a crossing is first
 * located on the eigenvalue that crosses, confirmed by one ring spectrum
 * (docs/cli/branch.md says what is checked where). */
int bkf_fronts_branch_write(const bkf_fronts_branch_spec *spec, FILE *out, bkf_io_format format,
                            const bkf_provenance *provenance, bkf_error *err);

#ifdef __cplusplus
}
#endif

#endif

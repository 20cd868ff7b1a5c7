/* The period product: T(mu, nu) of f'' + mu (f^2 - 1) f' + f = nu at single
 * points, on a (mu, nu) grid (mu fastest), or along a continued branch, with
 * the error estimate, extremes, Floquet multiplier, work and the asymptotic
 * approximations beside it (`bkfront period`).
 *
 * bkf_period_options is the table of its keys (flags and scene keys); fill a
 * spec from bkf_period_spec_default, apply values through the table, check,
 * write. */
#ifndef BKFRONT_PERIOD_H
#define BKFRONT_PERIOD_H

#include <signal.h>
#include <stddef.h>
#include <stdio.h>
#include "bkfront/io.h"
#include "bkfront/options.h"
#include "bkfront/status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct {
    int log;            /* geometric mu list (A:B:N), only with a single nu */
    bkf_list mu, nu;    /* each mu in [BKF_CYCLE_MU_MIN, BKF_CYCLE_MU_MAX], |nu| < 1 */
    double tol;         /* relative on T; default 1e-10 */
    int along;          /* -1: points (default); 0 continue in mu, 1 in nu, from A to B
                           of that list, the other a single value */
    int stepper;        /* index in auto, explicit, implicit, extrapolation */
    int method;         /* index in auto, asymptotic, leading, shooting */
    /* When non-NULL and *cancel becomes nonzero, write stops before the next
     * point with BKF_ECANCELED (the rows written so far stay in `out`). */
    const volatile sig_atomic_t *cancel;
} bkf_period_spec;

bkf_period_spec bkf_period_spec_default(void);

/* The keys: log, mu, nu, tol, continue, method, stepper. */
extern const bkf_option bkf_period_options[];
extern const size_t bkf_period_noptions;

/* What the table cannot judge key by key (mu and nu given, --log only with a
 * single nu, what --continue needs, nu inside the active range, the grid's
 * size); messages name the keys with `prefix` ("--" or ""). */
int bkf_period_check(const bkf_period_spec *spec, const char *prefix, bkf_error *err);

/* The whole table (comments, header, rows) to `out`; on failure the stream
 * holds a partial table and the caller discards it. */
int bkf_period_write(const bkf_period_spec *spec, FILE *out, bkf_io_format format,
                     const bkf_provenance *provenance, bkf_error *err);

void bkf_period_spec_free(bkf_period_spec *spec);

#ifdef __cplusplus
}
#endif

#endif

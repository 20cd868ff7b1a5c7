/* The stability of the global oscillation as tables (`bkfront floquet`):
 * the dispersion relation on a q grid, with the allowed modes of a finite
 * domain; the lowest stability boundary in nu, or its curve along c or
 * gamma; the stability diagram over nu.  The numbers are module floquet's;
 * this module checks the spec, runs it and tabulates. */
#ifndef BKFRONT_OSCILLATION_H
#define BKFRONT_OSCILLATION_H

#include <stddef.h>
#include "bkfront/cycle.h"
#include "bkfront/floquet.h"
#include "bkfront/io.h"
#include "bkfront/product.h"
#include "bkfront/status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
    BKF_OSCILLATION_DISPERSION = 0, /* one row per q */
    BKF_OSCILLATION_THRESHOLD = 1,  /* the lowest boundary in [search_lo, search_hi] */
    BKF_OSCILLATION_CURVE = 2,      /* that boundary along c or gamma, from -> to */
    BKF_OSCILLATION_DIAGRAM = 3     /* every stable and unstable interval of nu */
} bkf_oscillation_mode;

/* The scanned nu range's default: the active range less 1e-3 at each end. */
#define BKF_OSCILLATION_SEARCH_LO (-0.999)
#define BKF_OSCILLATION_SEARCH_HI 0.999
/* c q at most (dispersion), and the largest --cq-max. */
#define BKF_OSCILLATION_CQ_MAX 1e4
/* Rows of the dispersion at most (grid and allowed modes together). */
#define BKF_OSCILLATION_MAX_ROWS 1000000u

typedef struct {
    bkf_oscillation_mode mode;  /* default dispersion */
    double gamma;               /* [BKF_CYCLE_MU_MIN, BKF_CYCLE_MU_MAX]; required (NaN)
                                   except along gamma */
    double c;                   /* >= 0, > 0 for the scans; required (NaN) except along c */
    double nu;                  /* dispersion: (-1, 1); required (NaN) */
    const double *q;            /* dispersion: nq wavenumbers >= 0, c q <= 1e4, in order
                                   (the caller's array) */
    size_t nq;
    double S;                   /* dispersion: > 0 adds the allowed modes q = 2 pi j/S
                                   in the grid's range; 0 (default): none */
    bkf_floquet_param along;    /* curve: c or gamma, from `from` to `to` (from != to) */
    double from, to;
    double search_lo, search_hi;/* scans: -1 < lo < hi < 1; default -0.999, 0.999 */
    bkf_floquet_options options;/* tol, stepper, p_max, nu_step: bkf_floquet_options_default */
} bkf_oscillation_spec;

bkf_oscillation_spec bkf_oscillation_spec_default(void);

/* Every range above: BKF_EINPUT naming the field, or BKF_OK. */
int bkf_oscillation_check(const bkf_oscillation_spec *spec, bkf_error *err);

/* The allowed wavenumbers of a periodic domain of size S > 0: q_j = 2 pi j/S
 * for every integer j with q_j between a and b (ends within 1e-12 relative
 * included), in the direction from a to b.  *modes is malloc'ed (NULL when
 * there is none; free it); BKF_EINPUT for S <= 0, a or b negative or not
 * finite, or more than max_count modes. */
int bkf_oscillation_modes(double S, double a, double b, size_t max_count, double **modes,
                          size_t *count, bkf_error *err);

/* The dispersion's wavenumbers: the grid q[0..nq) with, when S > 0, every
 * allowed mode between q[0] and q[nq - 1] merged in in the grid's direction;
 * a grid point within 1e-12 (relative) of a mode is that mode's row, not a
 * second one.  allowed[i] is 1 for a mode, else 0.  Both arrays malloc'ed. */
int bkf_oscillation_rows(const double *q, size_t nq, double S, double **rows,
                         unsigned char **allowed, size_t *count, bkf_error *err);

/* One row of the dispersion. */
typedef struct {
    bkf_floquet_point point;   /* lambda, the multipliers and m1_err NaN when refused */
    int refused;               /* lambda_err stayed above tol after the retries */
    int allowed;               /* 1: an allowed mode, 0: not, -1: no S given */
    double lambda_slip;        /* T x bkf_floquet_slip_rate: growth of continuous slip
                                  over one period */
    const char *message;       /* why it was refused, or "" */
} bkf_oscillation_row;

/* Return nonzero to stop (the call then returns BKF_OK). */
typedef int (*bkf_oscillation_visit)(const bkf_oscillation_row *row, void *data);

/* The dispersion relation (mode ignored): every row of bkf_oscillation_rows
 * in order to visit.  A q whose estimate stays above tol is a refused row,
 * not a failure; any other failure ends the run.  *cycle (if not NULL)
 * receives the global oscillation (its stepper name is static). */
int bkf_oscillation_dispersion(const bkf_oscillation_spec *spec, bkf_oscillation_visit visit,
                               void *data, bkf_cycle_result *cycle, bkf_error *err);

/* The columns of a mode's table. */
const bkf_io_column *bkf_oscillation_columns(bkf_oscillation_mode mode, size_t *count);

/* The spec's mode as a table (the columns above, comments with the
 * parameters, the cycle or the scan).  Refused dispersion rows go to
 * out->warn as "row q = Q refused: WHY". */
int bkf_oscillation_write(const bkf_oscillation_spec *spec, const bkf_product_output *out,
                          bkf_error *err);

#ifdef __cplusplus
}
#endif

#endif

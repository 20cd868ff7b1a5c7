/* The stability of the global oscillation as tables (`bkfront floquet`):
 * the dispersion relation on a q grid, with the allowed modes of a finite
 * domain; the lowest stability boundary in nu, or its curve along c or
 * gamma; the stability diagram over nu.  The numbers are module floquet's;
 * this module checks the spec, runs it and tabulates.
 *
 * bkf_oscillation_options is the table of its keys (flags and scene keys,
 * options.h): fill a spec from bkf_oscillation_spec_default, apply values
 * through the table, check, write. */
#ifndef BKFRONT_OSCILLATION_H
#define BKFRONT_OSCILLATION_H

#include <stddef.h>
#include <stdio.h>
#include "bkfront/cycle.h"
#include "bkfront/floquet.h"
#include "bkfront/io.h"
#include "bkfront/options.h"
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
    int threshold;          /* switch: the threshold (with along: its curve) */
    int diagram;            /* switch: the diagram */
    double gamma;           /* [BKF_CYCLE_MU_MIN, BKF_CYCLE_MU_MAX]; required (NaN by
                               default) except along gamma */
    double c;               /* >= 0, > 0 for the scans; required (NaN) except along c */
    double nu;              /* dispersion only: (-1, 1); required (NaN) */
    bkf_list q;             /* dispersion only: wavenumbers >= 0, c q <= 1e4; required */
    double S;               /* dispersion only: > 0 adds the allowed modes q = 2 pi j/S
                               in the grid's range; NaN (default): none */
    int along;              /* threshold curve: index in c, gamma; -1 (default): none */
    double from, to;        /* the curve's ends, from != to (NaN: not given) */
    double search_lo, search_hi; /* scans: -1 < lo < hi < 1; default -0.999, 0.999 */
    int search_given;       /* set by the search key: a range was given */
    double tol;             /* absolute on lambda and the boundaries; default 1e-10 */
    double cq_max;          /* scans: peaks sought for c q in (0, cq_max]; NaN: 6 */
    double nu_step;         /* scans: step in nu, (0, 1]; NaN: 0.01 */
    int stepper;            /* index in auto, explicit, implicit, extrapolation */
    /* A refused dispersion row (its estimate stayed above tol) is kept with
     * kind "refused" and reported here as "row q = Q refused: WHY"; NULL:
     * not reported.  Not a key. */
    void (*warn)(const char *message, void *data);
    void *warn_data;
} bkf_oscillation_spec;

bkf_oscillation_spec bkf_oscillation_spec_default(void);
void bkf_oscillation_spec_free(bkf_oscillation_spec *spec);

/* The keys: gamma, c, nu, q, S, threshold, diagram, along, from, to,
 * search, tol, cq-max, nu-step, stepper. */
extern const bkf_option bkf_oscillation_options[];
extern const size_t bkf_oscillation_noptions;

/* The spec's mode: dispersion unless threshold (curve with along) or
 * diagram is set. */
bkf_oscillation_mode bkf_oscillation_mode_of(const bkf_oscillation_spec *spec);

/* The spec as module floquet's options. */
bkf_floquet_options bkf_oscillation_floquet_options(const bkf_oscillation_spec *spec);

/* What the table cannot judge key by key (which keys each mode takes and
 * needs, c > 0 for the scans, c q, the curve's ends); messages name the keys
 * with `prefix` ("--" or ""). */
int bkf_oscillation_check(const bkf_oscillation_spec *spec, const char *prefix, bkf_error *err);

/* The allowed wavenumbers of a periodic domain of size S > 0: q_j = 2 pi j/S
 * for every integer j with q_j between a and b (ends within 1e-12 relative
 * included), in the direction from a to b.  *modes is malloc'ed (NULL when
 * there is none; free it); BKF_EINPUT for S <= 0, a or b negative or not
 * finite, or more than max_count modes. */
int bkf_oscillation_modes(double S, double a, double b, size_t max_count, double **modes,
                          size_t *count, bkf_error *err);

/* The dispersion's wavenumbers: the grid q[0..nq) with, when S > 0 (not
 * NaN), every
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

/* The dispersion relation (the other modes' keys ignored): every row of
 * bkf_oscillation_rows in order to visit.  A q whose estimate stays above tol is a refused row,
 * not a failure; any other failure ends the run.  *cycle (if not NULL)
 * receives the global oscillation (its stepper name is static). */
int bkf_oscillation_dispersion(const bkf_oscillation_spec *spec, bkf_oscillation_visit visit,
                               void *data, bkf_cycle_result *cycle, bkf_error *err);

/* The columns of a mode's table. */
const bkf_io_column *bkf_oscillation_columns(bkf_oscillation_mode mode, size_t *count);

/* The spec's mode as a table to `out` (the columns above, comments with the
 * parameters, the cycle or the scan).  On failure the stream holds a partial
 * table and the caller discards it. */
int bkf_oscillation_write(const bkf_oscillation_spec *spec, FILE *out, bkf_io_format format,
                          const bkf_provenance *provenance, bkf_error *err);

#ifdef __cplusplus
}
#endif

#endif

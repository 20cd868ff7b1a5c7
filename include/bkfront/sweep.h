/* Sweeps (`bkfront sweep`): the regime of a direct simulation (simulate.h)
 * over a grid of one or two parameters, times a list of seeds, times a list
 * of initial states; one TSV row per point.
 *
 * A point is the base simulation with up to four things changed: the x
 * axis and the y axis (each one of gamma, c, nu, S, N, tmax, seed, given
 * as "NAME=LIST" in the list grammar of options.h), the seed (a list) and
 * the initial state (specs of init.h separated by ';').  Point i is
 *     i = ((init * ny + y) * nx + x) * nseeds + seed
 * (with zip, x and y run together: ny = 1 and y = x).  Its row is a pure
 * function of the sweep's definition, the point and the library's version:
 * the same point gives the same row, bit for bit, whichever thread, process
 * or task computes it, and `bkfront simulate` with the point's parameters
 * gives the same regime, speed and period.
 *
 * Table: comment lines (the definition, which --resume and --merge
 * compare), the column names, then one row per point, in the order points
 * finish while a sweep runs and sorted by point at its end.  Rows are
 * appended whole and flushed to disk one by one, so a crash loses only the
 * points in flight; reading a table back drops a partial last line.
 *
 * The library never prints and never exits. */
#ifndef BKFRONT_SWEEP_H
#define BKFRONT_SWEEP_H

#include <signal.h>
#include <stddef.h>
#include <stdio.h>
#include "bkfront/options.h"
#include "bkfront/simulate.h"
#include "bkfront/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The points of one sweep, at most. */
#define BKF_SWEEP_POINTS_MAX 1000000u
#define BKF_SWEEP_INITS_MAX 64u

typedef struct {
    /* The base point: every key of the simulation product (the first
     * member, so that simulate.h's option table fills it in place).  Its
     * data files (spacetime, snapshots) are refused. */
    bkf_simulate_spec sim;
    const char *x;      /* "NAME=LIST", NULL: no axis */
    const char *y;      /* "NAME=LIST", NULL: no second axis */
    int zip;            /* switch: x and y are pairs (equal lengths), not a grid */
    bkf_list seeds;     /* seeds of every point; empty: sim.seed */
    const char *inits;  /* "SPEC;SPEC;...", NULL: sim.init */
    size_t threads;     /* 0: every core (OpenMP's default) */
    size_t task, of;    /* this task's points: i % of == task; of 0: all */
    double tmax_budget; /* > 0: a run goes on past tmax until its regime
                           settles, doubling its length until two successive
                           windows classify alike or the next doubling would
                           pass this; a column says which (settled, budget).
                           0: every run stops at tmax */
    int product;        /* index in regime, speeds, threshold (bkf_sweep_product_names):
                           what a row holds (BKF_SWEEP_REGIME: a simulation's regime;
                           speeds: bkf_fronts_find with stability at the point's
                           gamma, c, nu, S; threshold: the global oscillation's
                           Floquet boundaries in nu at its gamma, c) */
    const char *fields; /* a directory, NULL: none.  Each point's spacetime
                           field psi(t, x) as HDF5 in DIR/point_I.h5 (I the
                           point; bkf_simulate_write's --spacetime FILE.h5,
                           the point's parameters as attributes), written
                           atomically by whoever computes the point; with
                           tmax_budget the last run's.  Regime product only;
                           not part of the definition (it changes no row) */
    /* Not keys: what the caller supplies for a run it may stop or watch. */
    const volatile sig_atomic_t *cancel; /* raised: no new point starts, the
                                            ones in flight stop, BKF_ECANCELED */
    void (*progress)(size_t done, size_t total, void *data); /* after each row */
    void *data;
} bkf_sweep_spec;

enum { BKF_SWEEP_REGIME = 0, BKF_SWEEP_SPEEDS = 1, BKF_SWEEP_THRESHOLD = 2 };
/* "regime", "speeds", "threshold", NULL. */
extern const char *const bkf_sweep_product_names[];

bkf_sweep_spec bkf_sweep_spec_default(void);
/* Frees the lists (seeds). */
void bkf_sweep_spec_free(bkf_sweep_spec *spec);

/* The name of point i's field file under spec->fields (caller frees), NULL
 * without fields or memory. */
char *bkf_sweep_field_path(const bkf_sweep_spec *spec, size_t index);

/* The sweep's own keys: x, y, product, zip, seeds, inits, threads, task, of,
 * tmax-budget, fields.  The
 * simulation's keys are bkf_simulate_options, applied to spec.sim. */
extern const bkf_option bkf_sweep_options[];
extern const size_t bkf_sweep_noptions;

/* Every key of a sweep in one table, offsets in bkf_sweep_spec: its own,
 * then the simulation's but those of one run's data files
 * (BKF_OPT_RUN_FILE: spacetime..., snapshots...).  The flags of `bkfront
 * sweep` and the keys of a scene's [sweep].  Built once; NULL with *count
 * 0 only when that allocation failed. */
const bkf_option *bkf_sweep_keys(size_t *count);

/* The whole grid, before any run: every axis value through the simulation's
 * own option table, every point's spec through bkf_simulate_check, the
 * count within BKF_SWEEP_POINTS_MAX.  One message naming the key, the value
 * and the valid range. */
int bkf_sweep_check(const bkf_sweep_spec *spec, const char *prefix, bkf_error *err);

/* Points of the sweep (0 when the spec does not check). */
size_t bkf_sweep_count(const bkf_sweep_spec *spec);

/* The table's head: comment lines, the definition line and the column
 * names, each ending in '\n'.  Caller frees. */
char *bkf_sweep_header(const bkf_sweep_spec *spec, bkf_error *err);

/* Point i's row, ending in '\n' (caller frees): a failed run is a row too,
 * its status in the last column; bad input or lack of memory is no row
 * (NULL, err).  Canceled: NULL with BKF_ECANCELED. */
char *bkf_sweep_row(const bkf_sweep_spec *spec, size_t index, bkf_error *err);

/* Rows as they finish, each passed whole to `row` (called by one thread at
 * a time; nonzero stops the sweep with that status), over the points of
 * this task not marked in `done` (NULL: none done), in OpenMP threads
 * (spec->threads), dynamically scheduled, one run per thread. */
typedef int (*bkf_sweep_row_fn)(size_t index, const char *row, void *data, bkf_error *err);
int bkf_sweep_run(const bkf_sweep_spec *spec, const unsigned char *done, bkf_sweep_row_fn row,
                  void *data, bkf_error *err);

/* The whole table (bkf_sweep_header, then every row in point order) to
 * `out`: what `bkfront sweep --out` leaves at its end, computed in memory
 * (no --resume; a scene's [sweep]).  Stopped through spec->cancel:
 * BKF_ECANCELED and a partial stream the caller discards. */
int bkf_sweep_write(const bkf_sweep_spec *spec, FILE *out, bkf_error *err);

/* The table file, appended to row by row. */
typedef struct bkf_sweep_table bkf_sweep_table;

/* Opens `path` for the sweep: a new table (its head written), or with
 * `resume` an existing one whose definition must be this sweep's
 * (BKF_EINPUT otherwise), its valid rows kept and the rest (a partial last
 * line, a row of another point) dropped.  Missing with resume: a new one. */
int bkf_sweep_table_open(const char *path, const bkf_sweep_spec *spec, int resume,
                         bkf_sweep_table **table, bkf_error *err);
/* Marks of the points already in the table (count bkf_sweep_count). */
const unsigned char *bkf_sweep_table_done(const bkf_sweep_table *table);
size_t bkf_sweep_table_rows(const bkf_sweep_table *table);
/* One row (from bkf_sweep_row), written whole and flushed to disk. */
int bkf_sweep_table_append(bkf_sweep_table *table, size_t index, const char *row,
                           bkf_error *err);
/* Closes; with `sort` the table is rewritten (atomically) with its rows in
 * point order. */
int bkf_sweep_table_close(bkf_sweep_table *table, int sort, bkf_error *err);

/* The tables of the tasks of one sweep (the same definition) into one,
 * rows in point order, written atomically to `out`.  *missing (may be
 * NULL) gets the number of points in none of them. */
int bkf_sweep_merge(const char *const *inputs, size_t ninputs, const char *out,
                    size_t *missing, bkf_error *err);

/* The finished table at `path` (every row of its sweep, or of a merge)
 * replaced atomically by the same table as JSON, in the layout of every
 * product's JSON (io.h: "comments", "columns", "rows"; text columns as
 * strings, numbers as numbers, nan as null).  A JSON table can no longer be
 * resumed or merged: it is the finished form.  BKF_EINPUT when `path` is
 * not a sweep table or lacks rows. */
int bkf_sweep_table_json(const char *path, bkf_error *err);

#ifdef __cplusplus
}
#endif

#endif

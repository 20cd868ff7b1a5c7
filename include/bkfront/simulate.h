/* The simulation product (`bkfront simulate`, a scene's spacetime): a
 * direct simulation of the continuum or the chain from an initial state
 * (init.h), measured as it runs (measure.h), written as a table of frames
 * with the summary (regime, front speed, period) in comments and in JSON
 * "results", and optionally the spacetime field psi(x, t) and snapshots of
 * the state, each file replaced atomically.
 *
 * bkf_simulate_options is the table of its keys (flags and scene keys);
 * fill a spec from bkf_simulate_spec_default, apply values through the
 * table, check, write.  The library never prints and never exits. */
#ifndef BKFRONT_SIMULATE_H
#define BKFRONT_SIMULATE_H

#include <signal.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include "bkfront/io.h"
#include "bkfront/measure.h"
#include "bkfront/model.h"
#include "bkfront/options.h"
#include "bkfront/pde.h"
#include "bkfront/status.h"

#ifdef __cplusplus
extern "C" {
#endif

#define BKF_SIMULATE_TMAX_MAX 1e6
#define BKF_SIMULATE_FRAMES_MAX 1000000u
#define BKF_SIMULATE_SNAPSHOTS_MAX 100000u
/* The spacetime file's size, counted in bytes: (frames + 1) rows of N
 * values, 16 bytes a value at most in text (" %.9g"), 4 in binary, plus the
 * row's t.  The field is held in memory as float32 until the end, so this
 * also bounds that memory (4 bytes a value). */
#define BKF_SIMULATE_SPACETIME_BYTES_MAX 1073741824.0
/* The fields a spacetime file may hold (spacetime_fields). */
#define BKF_SIMULATE_PSI 1u
#define BKF_SIMULATE_ETA 2u

/* The continuum's grid points when N is not given (the chain's: S blocks). */
#define BKF_SIMULATE_N_DEFAULT 512

/* The simulate stepper that picks one by the model (bkf_pde_stepper_auto). */
#define BKF_SIMULATE_STEPPER_AUTO 5

typedef struct {
    bkf_model_params model; /* N 0: BKF_SIMULATE_N_DEFAULT, or S blocks for the chain */
    int chain;              /* model key: index in continuum, chain */
    double tol;             /* [1e-13, 1e-2]; default 1e-9 */
    int stepper;            /* a bkf_pde_stepper, or BKF_SIMULATE_STEPPER_AUTO
                               (bkf_pde_stepper_auto); default auto */
    int dealias;            /* switch, continuum only */
    double filter;          /* [0, 1000]; default 4 */
    double tmax;            /* (0, 1e6]; default 125 */
    const char *init;       /* init.h grammar; NULL: uniform */
    uint64_t seed;          /* noise; default 1 */
    double level;           /* fronts are crossings of it; NaN: bkf_measure_front_level */
    size_t frames;          /* rows over [0, tmax], plus t = 0; default 500 */
    const char *spacetime;  /* file of psi(x, t) at the frames, or NULL */
    int spacetime_format;   /* index in text, binary, hdf5; -1: not given (hdf5
                               for a name ending .h5, .hdf5 or .he5, else text) */
    unsigned spacetime_fields; /* BKF_SIMULATE_PSI | BKF_SIMULATE_ETA; 0: not
                                  given (psi); eta only in hdf5 */
    size_t spacetime_deflate; /* hdf5: gzip level 1..9; 0: not given (none) */
    const char *snapshots;  /* file of snapshots, or NULL */
    size_t snapshot_count;  /* 0: not given (2) */
    /* Not keys: what the caller supplies for a run it may stop. */
    const volatile sig_atomic_t *cancel;     /* raised: the run stops, what is
                                                complete is written, BKF_ECANCELED */
    const char *(*cancel_reason)(void *data); /* "SIGINT", ...; NULL: "canceled" */
    int discard_canceled;   /* stopped through cancel, replace no data file (a
                               scene: a partial product must not replace a
                               complete one of an earlier run) */
    int (*progress)(double fraction, void *data);
    /* One line the run wants a reader to see (a seed the grid does not
     * resolve); it is also a comment of the table.  NULL: comment only. */
    void (*warn)(const char *message, void *data);
    /* Told each data file's temporary while it exists (armed 1) and when it
     * is gone (armed 0), so that a signal handler may remove it. */
    void (*temp_file)(const char *path, int armed, void *data);
    void *data;
} bkf_simulate_spec;

bkf_simulate_spec bkf_simulate_spec_default(void);

/* The keys: gamma, c, nu, S, N, model, tmax, tol, init, seed, stepper,
 * dealias, filter, level, frames, spacetime, spacetime-format,
 * spacetime-fields, spacetime-deflate, snapshots, snapshot-count. */
extern const bkf_option bkf_simulate_options[];
extern const size_t bkf_simulate_noptions;

/* What the table cannot judge key by key: the grid for the model, the
 * initial state against the model (a state file is read), the files and
 * their formats, the size of the spacetime field.  Messages name the keys
 * with `prefix`. */
int bkf_simulate_check(const bkf_simulate_spec *spec, const char *prefix, bkf_error *err);

/* Runs and writes: the frames' table to `out` (comments: the model, the
 * initial state, the command of `provenance`, the work, the regime, fronts,
 * speed, period, window statistics; JSON "results": regime, fronts, speed,
 * speed_err, period, period_err, v_pred), and the spacetime and snapshot
 * files, opened (so a bad path fails) before the run and replaced only at
 * its end.  Stopped through spec->cancel: everything complete is written,
 * marked "interrupted (REASON) at t = ...", and BKF_ECANCELED returned (with
 * discard_canceled the data files are left as they were, and only `out`
 * gets the marked table, for the caller to discard or keep); on
 * any other failure no file is replaced and `out` holds a partial table
 * the caller discards. */
int bkf_simulate_write(const bkf_simulate_spec *spec, FILE *out, bkf_io_format format,
                       const bkf_provenance *provenance, bkf_error *err);

/* What a run gives without its table (a sweep's point): the summary of
 * the measurements, the global oscillation's period (0: no cycle), where
 * the run ended and its work. */
typedef struct {
    bkf_measure_summary summary;
    double period_ref;
    double t_end;
    size_t steps, rejected;
    size_t N;           /* the grid's points (the default resolved) */
} bkf_simulate_outcome;

/* The run of bkf_simulate_write, the same numbers bit for bit, without a
 * table: spec may name a spacetime file (written as bkf_simulate_write
 * writes it, but for the command attribute: the provenance is none) and no
 * snapshots.  Stopped through spec->cancel: BKF_ECANCELED, no outcome and
 * the spacetime file left as it was. */
int bkf_simulate_outcome_of(const bkf_simulate_spec *spec, bkf_simulate_outcome *outcome,
                            bkf_error *err);

#ifdef __cplusplus
}
#endif

#endif

/* Setting up a simulation: the initial state from a one-line specification
 * (the --init of bkfront simulate), and the sampling of a run into frames
 * and snapshots.
 *
 * Specifications:
 *   uniform[:amp=A]                    psi = nu + band-limited noise of rms A
 *                                      (default 1e-3): bkf_pde_init_uniform
 *   oscillation[:q=Q|j=J][,amp=A][,noise=E]
 *                                      the global oscillation plus A cos(q x),
 *                                      q rounded to 2 pi j/S (default j 0, A 0),
 *                                      plus band-limited noise of rms E (default
 *                                      0; drawn from the seed as uniform's)
 *   front:n=K[,root=R][,dir=left|right][,noise=E]
 *                                      K fronts at the predicted speed (the
 *                                      front is built by bkf_seed_front,
 *                                      products/seed.h)
 *   file:PATH                          a table naming psi and eta (a snapshot
 *                                      file of bkfront simulate; its last t)
 * A in [0, 10], E in [0, 10], K in [1, 100000], R in [1, 100], J < N/2.
 * Messages name the key and its range, prefixed "--init KIND", as the CLI
 * reports them.
 *
 * The library never prints and never exits. */
#ifndef BKFRONT_INIT_H
#define BKFRONT_INIT_H

#include <stddef.h>

#include "bkfront/io.h"
#include "bkfront/model.h"
#include "bkfront/pde.h"
#include "bkfront/status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
    BKF_INIT_UNIFORM = 0,
    BKF_INIT_OSCILLATION = 1,
    BKF_INIT_FRONT = 2,
    BKF_INIT_FILE = 3
} bkf_init_kind;

/* Rows a state file may have (all snapshots together). */
#define BKF_INIT_FILE_ROWS_MAX ((size_t)1 << 24)

typedef struct {
    bkf_init_kind kind;
    double amp;               /* uniform (default 1e-3), oscillation (default 0) */
    int q_given;              /* oscillation: q was given; bkf_init_check sets j */
    double q;                 /* oscillation: requested wavenumber, >= 0 */
    size_t j;                 /* oscillation: mode */
    double noise;             /* oscillation: rms of the noise added to psi; 0: none */
    bkf_pde_front_spec front; /* front: n, root, direction, noise (its seed
                                 field is ignored: `seed` below counts) */
    unsigned long seed;       /* noise of uniform and front; default 1 */
    char *path;               /* file: the path (owned) */
    bkf_io_state state;       /* file: the contents, after bkf_init_load */
} bkf_init_spec;

/* Parses `text` into *spec (owned resources: release with bkf_init_free,
 * also after a failure).  BKF_EINPUT with the key and its range.  No file is
 * read here: bkf_init_load does that. */
int bkf_init_parse(const char *text, bkf_init_spec *spec, bkf_error *err);

/* For file:PATH, reads the state (at most BKF_INIT_FILE_ROWS_MAX rows; at
 * least BKF_PDE_N_MIN in the last snapshot): BKF_EIO when the file cannot
 * be opened or read, BKF_EINPUT for content that is not such a table.  A
 * no-op for the other kinds. */
int bkf_init_load(bkf_init_spec *spec, bkf_error *err);

/* Cross-checks with the model (after bkf_init_load): a file sets model->N to
 * its rows (BKF_EINPUT if N_given and different, or if the model with that
 * N fails bkf_pde_check with `options`); oscillation and front need a limit
 * cycle (|nu| < 1, gamma in the cycle engine's range of mu); an oscillation
 * given by q gets its mode j, which must be below N/2. */
int bkf_init_check(bkf_init_spec *spec, bkf_model_params *model, int N_given,
                   const bkf_pde_options *options, bkf_error *err);

/* Applies uniform, oscillation or file (at t = 0) to `pde`; a front is
 * BKF_EINPUT here (it needs the speeds solver: bkf_seed_init). */
int bkf_init_apply(bkf_pde *pde, const bkf_init_spec *spec, bkf_error *err);

void bkf_init_free(bkf_init_spec *spec);

/* Sampling of a run of length tmax into `frames` frames (frames + 1 rows
 * with the start): measurements need samples at most max_dt apart
 * (tracking needs a front to move less than half the spacing between
 * fronts per sample), so each frame has per_frame samples. */
#define BKF_INIT_SAMPLE_DT_MAX 0.1

typedef struct {
    double frame_dt;   /* tmax / frames */
    size_t per_frame;  /* ceil(frame_dt / max_dt), >= 1 */
    double sample_dt;  /* frame_dt / per_frame <= max_dt */
} bkf_init_sampling;

/* BKF_EINPUT unless tmax and max_dt are finite and > 0 and frames >= 1. */
int bkf_init_sampling_plan(double tmax, size_t frames, double max_dt, bkf_init_sampling *sampling,
                           bkf_error *err);

/* The frame of snapshot k of `count` (k < count <= frames + 1): spread
 * evenly over frames 0 .. frames, the last at `frames`; a single snapshot
 * is the last frame. */
size_t bkf_init_snapshot_frame(size_t k, size_t count, size_t frames);

#ifdef __cplusplus
}
#endif

#endif

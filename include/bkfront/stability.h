/* The spectral stability of a train of n fronts as a table (`bkfront
 * stability`): the root of the speed condition (bkf_speeds_find, n only),
 * then its spectrum on the ring (bkf_trainspec_ring: one row per eigenvalue)
 * or on the infinite line (bkf_trainspec_line: the rightmost sigma against
 * the Bloch number).  The numbers are trainspec's; this module checks the
 * spec, finds the root and tabulates.  `bkfront speeds --stability`, the
 * branch, `check` and the stability map (stabmap.h) call the same
 * bkf_trainspec_root.
 *
 * bkf_stability_options is the table of its keys (flags and scene keys,
 * options.h): fill a spec from its _default, apply values through the
 * table, check, write. */
#ifndef BKFRONT_STABILITY_H
#define BKFRONT_STABILITY_H

#include <stddef.h>
#include <stdio.h>
#include "bkfront/io.h"
#include "bkfront/model.h"
#include "bkfront/options.h"
#include "bkfront/speeds.h"
#include "bkfront/stabmap.h"
#include "bkfront/status.h"
#include "bkfront/trainspec.h"

#ifdef __cplusplus
extern "C" {
#endif

/* --kappa-count at most (one Bloch number costs about one ring spectrum's
 * curve trace). */
#define BKF_STABILITY_KAPPA_MAX 100000u

typedef struct {
    double gamma, c, nu, S; /* required (NaN by default); c > 0, else as bkf_speeds_check */
    size_t n;               /* required (0 by default), >= 1 */
    size_t root;            /* which root of n, 1 the fastest (bkf_speeds_find order); default 1 */
    double tol;             /* absolute accuracy of each sigma, [1e-10, 1e-2]; default 1e-6 */
    size_t per_kappa;       /* eigenvalues per Bloch number, [1, 50]; default 3 */
    int line;               /* the infinite line's spectrum instead of the ring's */
    size_t kappa_count;     /* Bloch numbers sampled with line, [1, 100000]; default 64 */
    /* Across parameters (stabmap.h): */
    int boundary;           /* the stability boundary of train n: the first sign change
                               of sigma_max in S in [S, S_to] at nu, followed in nu to `to` */
    int diagram;            /* the (nu, S) diagram of n = 1..n over nu in [nu, to], S in
                               [S, S_to]: existence, stability, the oscillation's tongues */
    double to;              /* the nu end (required with boundary, diagram), |to| < 1 */
    double S_to;            /* the S end (required with boundary, diagram), > S */
    double nu_step;         /* step in nu, (0, 0.5]; default 0.01 */
    double S_tol;           /* bracket width ending an S solve, [1e-8, 1]; default 1e-3 */
    size_t S_samples;       /* S scan's steps for the first crossing, [2, 1000]; default 12 */
    double seed_step;       /* diagram: spacing in nu of the columns scanned in S whose
                               crossings are followed (bkf_stabmap_trace), (0, 2]; default
                               0.1 (the ends are always columns) */
    int scan;               /* diagram: the grid scan instead (every nu of nu_step scanned
                               in S, crossings joined by nearness: the table before
                               2026-11-29) */
    size_t threads;         /* diagram: OpenMP threads, 0: every core (OpenMP's default) */
    /* boundary, diagram: every ring spectrum computed is one call of this
     * (NULL, the default: bkf_trainspec_root; stabmap.h), called from
     * several threads at once with the diagram's threads */
    bkf_stabmap_spectrum_fn spectrum;
    void *spectrum_data;
} bkf_stability_spec;

/* Diagram: n at most (every n costs one scan and its boundaries). */
#define BKF_STABILITY_DIAGRAM_N_MAX 20u

bkf_stability_spec bkf_stability_spec_default(void);

/* The keys: gamma, c, nu, S, n, root, tol, per-kappa, line, kappa-count,
 * boundary, diagram, to, S-to, nu-step, S-tol, S-samples, seed-step, scan,
 * threads. */
extern const bkf_option bkf_stability_options[];
extern const size_t bkf_stability_noptions;

/* What the table cannot judge key by key (c > 0, |nu| < 1, the speeds
 * module's ranges); messages name the keys with `prefix` ("--" or "").
 * Whether n has a root is known only once the roots are found:
 * bkf_stability_write refuses it then (BKF_EINPUT naming n and n_max). */
int bkf_stability_check(const bkf_stability_spec *spec, const char *prefix, bkf_error *err);

/* The table to `out`.  Ring: one row per eigenvalue (j, kappa, re, im, err,
 * translation), comments with the verdict, sigma_max and its kappa and
 * kind, the gauges (translation and Liouville residuals), the window, the
 * work and the root (n, v, mu, T); in JSON the same are the fields of
 * "results".  Line: rows kappa, re, im, err, and the largest re among them
 * with its kappa as results.  Boundary: rows nu, S, S_err, sigma,
 * sigma_err, slope, v, mu, stable_above, results end, points, evaluations.
 * Diagram: rows curve, kind (existence, stability, state, long_wave,
 * period_doubling, other), n, m, nu, S, S_err, above, nu_err
 * (docs/cli/stability.md); the stability curves followed from a seed grid
 * (bkf_stabmap_trace), or with scan every grid column's crossings.
 * On failure the stream holds a partial table
 * and the caller discards it. */
int bkf_stability_write(const bkf_stability_spec *spec, FILE *out, bkf_io_format format,
                        const bkf_provenance *provenance, bkf_error *err);

#ifdef __cplusplus
}
#endif

#endif

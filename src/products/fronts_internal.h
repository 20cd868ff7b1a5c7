/* Internal to the fronts products (src/products/fronts.c, the tables;
 * fronts_track.c, the eigenvalues a branch's verdicts follow from point to
 * point; fronts_chain.c, the chain's branch).  Not installed, not part of
 * the API. */
#ifndef BKFRONT_FRONTS_INTERNAL_H
#define BKFRONT_FRONTS_INTERNAL_H

#include <stddef.h>

#include <stdio.h>

#include "bkfront/fronts.h"
#include "bkfront/io.h"
#include "bkfront/speeds.h"
#include "bkfront/trainspec.h"

/* The eigenvalues followed along a branch: the last ring spectrum's near
 * its rightmost, then their values at each point followed. */
typedef struct {
    bkf_trainspec_eigenvalue *e;
    size_t count, cap;
    size_t lead; /* the rightmost of them */
} fronts_track_set;

/* The set from a ring spectrum: of the eigenvalues it reports (but the
 * translation, and one of each conjugate pair of classes j and n - j),
 * those right of sigma_max - |sigma_max| / 2 - 10 tol, the rightmost 16
 * at most; empty when its window held nothing but the translation. */
int fronts_track_seed(fronts_track_set *set, const bkf_trainspec_result *r, double tol);
void fronts_track_set_free(fronts_track_set *set);

/* The set followed to the train of `root` (bkf_trainspec_track at tol) as
 * a result in *out (free it with bkf_trainspec_result_free): eigenvalues
 * the followed ones, sigma_max the rightmost of them with its error, Bloch
 * number and kind, verdict unstable.  *decided is 1 when every one was
 * followed, the rightmost is the one that was the rightmost before (the
 * lead did not pass to another: the maximum moving along a band of
 * eigenvalues leaves the set, so the caller takes a ring spectrum) and
 * lies right of 0 by more than 4 errors plus tol: then the train is
 * unstable, whatever was not followed, and the set takes the new values.  Otherwise *out still holds what was followed
 * (sigma_max -inf when nothing was).  Only failures other than Newton's
 * are returned. */
int fronts_track_point(const bkf_model_params *p, const bkf_speeds_root *root, double tol,
                       fronts_track_set *set, bkf_trainspec_result *out, int *decided,
                       bkf_error *err);

/* The train at parameter x of a search: its params and root. */
typedef int (*fronts_root_at)(double x, void *data, bkf_model_params *p, bkf_speeds_root *root,
                              bkf_error *err);

/* Where Re sigma of one eigenvalue, `start` at xa (of a ring spectrum
 * there), vanishes between xa and xb: the eigenvalue followed to each
 * trial x (from the value at the nearest x tried) and Brent's method on
 * its real part until |Re sigma| <= tol / 2.  BKF_OK with the train there
 * in *p, *root (x in *x); BKF_ENUMERIC when the eigenvalue does not change
 * sign between the ends, is lost by Newton or the interval shrinks first
 * (the caller then searches on ring spectra); *evaluations counts the
 * eigenvalues followed. */
int fronts_track_crossing(double xa, double xb, const bkf_trainspec_eigenvalue *start, size_t n,
                          double tol, fronts_root_at root_at, void *data, double *x,
                          bkf_model_params *p, bkf_speeds_root *root, size_t *evaluations,
                          bkf_error *err);

/* bkf_fronts_branch_spec's along for h, the chain's spacing (S = N h). */
#define ALONG_H 4

/* The chain's model at the branch's start (the continued parameter at
 * `from`) and its blocks; messages name the keys with p. */
int fronts_chain_branch_model(const bkf_fronts_branch_spec *spec, const char *p,
                              bkf_model_params *m, bkf_error *err);

/* The chain's branch (bkf_chainwave_branch) as a table; name: the
 * continued parameter's. */
int fronts_chain_branch_write(const bkf_fronts_branch_spec *spec, const char *name, FILE *out,
                              bkf_io_format format, const bkf_provenance *prov, bkf_error *err);

#endif

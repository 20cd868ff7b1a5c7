/* Internal to Hill's method (src/stability/hill.c) and the train
 * spectrum's Hill stage (trainspec_hill.c).  Not installed, not part of
 * the API. */
#ifndef BKFRONT_HILL_INTERNAL_H
#define BKFRONT_HILL_INTERNAL_H

#include <stddef.h>

#include "bkfront/cycle.h"
#include "bkfront/hill.h"

/* How many eigenvalues bkf_hill_spectrum returns at class theta and
 * `modes` modes: 2 (2 modes + 1), but 4 modes at theta an odd multiple of
 * pi (hill.h). */
size_t hill_count(double theta, size_t modes);

/* For each of at[0..count), the eigenvalue of the Hill matrix of class
 * theta at `modes` modes nearest it, by inverse iteration, into out (NaN
 * where the iteration found no eigenpair of small residual): a few
 * eigenvalues of one truncation for the price of a few LU factorisations
 * instead of its whole spectrum. */
int hill_nearest(bkf_cycle *cycle, double gamma, double theta, size_t modes, const bkf_hill_eigenvalue *at,
                 size_t count, bkf_hill_eigenvalue *out, bkf_error *err);

#endif

/* What the branch engine (orbits_branch.c) and the product (orbits.c)
 * share. */
#ifndef BKFRONT_ORBITS_INTERNAL_H
#define BKFRONT_ORBITS_INTERNAL_H

#include "bkfront/orbits.h"

double orbits_param_get(const bkf_model_params *m, bkf_orbits_param p);
void orbits_param_set(bkf_model_params *m, bkf_orbits_param p, double v);
/* N when the model gives none: BKF_ORBITS_CELL_POINTS per cell (continuum),
 * the physical chain's S blocks. */
size_t orbits_default_N(const bkf_model_params *m, size_t j);
/* The wavenumber floquet must see for mode j of N points: 2 pi j/S, the
 * chain's (2/h) sin(q h/2). */
double orbits_q_effective(const bkf_model_params *m, size_t j, size_t N);

#endif

/* Seeding a simulation with a travelling wave predicted by the speeds
 * solver: the request (n fronts, which root) becomes the wave that
 * bkf_pde_init_front builds, and --init specifications are applied whole
 * (the front through the solver, the other kinds through bkf_init_apply).
 *
 * The library never prints and never exits. */
#ifndef BKFRONT_SEED_H
#define BKFRONT_SEED_H

#include "bkfront/init.h"
#include "bkfront/pde.h"
#include "bkfront/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Solves the speed condition for spec->n fronts (bkf_speeds_find at the
 * simulation's gamma, c, nu and S, tolerance spec->tol), takes root
 * spec->root and seeds that wave with bkf_pde_init_front; info also gets
 * the root's v_err and the number of roots for n.  Needs |nu| < 1, c >= 0
 * and a root for (n, root) (BKF_EINPUT otherwise, naming how many n have
 * fronts).  `info` may be NULL; `clean_psi`, if non-NULL, receives the N
 * values of psi before the noise.
 * On the chain (model kind BKF_MODEL_CHAIN) the seed is the chain's own
 * rotating wave instead (bkf_chainwave_find for n, root `root` in its order,
 * tolerance max(spec->tol, 1e-10); mirrored for direction +1), plus the
 * noise (bkf_pde_add_noise); info gets its v, v_err, T = P (the period of
 * each block), stretch 1, mu NaN, and how many waves n has.  n in [1, N];
 * no wave for n (its branch from the uncoupled chain ends before the
 * chain's coupling) is BKF_EINPUT naming n and N. */
int bkf_seed_front(bkf_pde *pde, const bkf_pde_front_spec *spec, bkf_pde_front_info *info,
                   double *clean_psi, bkf_error *err);

/* Applies a parsed, checked and loaded spec (bkf_init_parse, bkf_init_check,
 * bkf_init_load): a front through bkf_seed_front (with spec->seed), any
 * other kind through bkf_init_apply.  `info` (may be NULL) is filled for a
 * front only; `clean_psi` as in bkf_seed_front (front only). */
int bkf_seed_init(bkf_pde *pde, const bkf_init_spec *spec, bkf_pde_front_info *info,
                  double *clean_psi, bkf_error *err);

#ifdef __cplusplus
}
#endif

#endif

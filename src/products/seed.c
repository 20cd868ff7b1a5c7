/* The speeds solver's prediction turned into a simulation's initial state
 * (see include/bkfront/seed.h). */
#include "bkfront/seed.h"

#include <math.h>
#include <string.h>

#include "bkfront/speeds.h"

int bkf_seed_front(bkf_pde *pde, const bkf_pde_front_spec *spec, bkf_pde_front_info *info,
                   double *clean_psi, bkf_error *err)
{
    if (!pde) return bkf_error_set(err, BKF_EINPUT, "simulation object is NULL");
    bkf_pde_front_spec sp = spec ? *spec : bkf_pde_front_spec_default();
    if (sp.n < 1) return bkf_error_set(err, BKF_EINPUT, "the number of fronts n must be >= 1");
    if (sp.root < 1) return bkf_error_set(err, BKF_EINPUT, "root must be >= 1");
    if (sp.direction != -1 && sp.direction != 1)
        return bkf_error_set(err, BKF_EINPUT, "direction must be -1 or +1");
    if (!isfinite(sp.noise) || sp.noise < 0 || sp.noise > 10)
        return bkf_error_set(err, BKF_EINPUT, "noise = %g is outside [0, 10]", sp.noise);
    if (!isfinite(sp.tol) || sp.tol < 1e-14 || sp.tol > 1e-4)
        return bkf_error_set(err, BKF_EINPUT, "front tol = %g is outside [1e-14, 1e-4]", sp.tol);
    const bkf_model_params *p = bkf_pde_get_params(pde);
    bkf_error e;
    if (bkf_model_check_nu_active(p->nu, &e) != BKF_OK)
        return bkf_error_set(err, BKF_EINPUT, "fronts need a limit cycle: %s", e.message);

    /* The speed condition is that of the continuum whatever the medium. */
    bkf_model_params sp_p = {p->gamma, p->c, p->nu, p->S, 0, BKF_MODEL_CONTINUUM};
    bkf_speeds_options so = bkf_speeds_options_default();
    so.tol = sp.tol;
    so.n_from = so.n_to = sp.n;
    bkf_speeds_table tab;
    memset(&tab, 0, sizeof tab);
    int s = bkf_speeds_find(&sp_p, &so, &tab, &e);
    if (s) {
        bkf_speeds_table_free(&tab);
        return bkf_error_set(err, s, "speeds for n = %zu: %s", sp.n, e.message);
    }
    if (tab.count < sp.root) {
        long n_max = tab.n_max;
        size_t have = tab.count;
        bkf_speeds_table_free(&tab);
        if (have == 0)
            return bkf_error_set(err, BKF_EINPUT,
                                 "no front speed for n = %zu (fronts exist for n <= %ld here)",
                                 sp.n, n_max);
        return bkf_error_set(err, BKF_EINPUT, "n = %zu has %zu root(s), not root %zu", sp.n,
                             have, sp.root);
    }
    bkf_speeds_root root = tab.roots[sp.root - 1];
    size_t roots_for_n = tab.count;
    bkf_speeds_table_free(&tab);
    if (root.flags & BKF_SPEEDS_ASYMPTOTIC)
        return bkf_error_set(err, BKF_EINPUT,
                             "n = %zu: mu = %.15g is beyond the cycle engine's range; the front "
                             "cannot be built", sp.n, root.mu);
    bkf_pde_wave wave = {sp.n, root.v, root.mu, sp.direction, sp.noise, sp.seed, sp.tol};
    if ((s = bkf_pde_init_front(pde, &wave, info, clean_psi, err))) return s;
    if (info) {
        info->v_err = root.v_err;
        info->roots_for_n = roots_for_n;
    }
    return BKF_OK;
}

int bkf_seed_init(bkf_pde *pde, const bkf_init_spec *spec, bkf_pde_front_info *info,
                  double *clean_psi, bkf_error *err)
{
    if (!spec) return bkf_error_set(err, BKF_EINPUT, "spec is NULL");
    if (spec->kind != BKF_INIT_FRONT) return bkf_init_apply(pde, spec, err);
    bkf_pde_front_spec fs = spec->front;
    fs.seed = spec->seed;
    return bkf_seed_front(pde, &fs, info, clean_psi, err);
}

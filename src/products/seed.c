/* The speeds solver's prediction turned into a simulation's initial state
 * (see include/bkfront/seed.h). */
#include "bkfront/seed.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bkfront/chainwave.h"
#include "bkfront/speeds.h"

/* The chain's own rotating wave of n fronts (bkf_chainwave_find), not the
 * continuum's sampled on the blocks: near the sonic limit the continuum's
 * fronts are thinner than a block and its seed breaks up on the chain. */
static int seed_chain(bkf_pde *pde, const bkf_pde_front_spec *sp, bkf_pde_front_info *info,
                      double *clean_psi, bkf_error *err)
{
    const bkf_model_params *p = bkf_pde_get_params(pde);
    size_t N = p->N;
    if (sp->n > N)
        return bkf_error_set(err, BKF_EINPUT, "n = %zu is outside [1, N = %zu] (the chain's "
                             "rotating waves)", sp->n, N);
    bkf_chainwave_options o = bkf_chainwave_options_default();
    /* the seed's accuracy as asked, within what the chain's solver offers */
    o.tol = fmin(fmax(sp->tol, 1e-10), BKF_CHAINWAVE_TOL_MAX);
    o.stability = 0;
    bkf_chainwave_table t;
    bkf_error e;
    int s = bkf_chainwave_find(p, sp->n, sp->n, &o, &t, &e);
    if (s) {
        bkf_chainwave_table_free(&t);
        return bkf_error_set(err, s, "the chain's wave for n = %zu: %s", sp->n, e.message);
    }
    if (t.count < sp->root) {
        size_t have = t.count;
        char note[sizeof t.note];
        snprintf(note, sizeof note, "%s", t.note);
        bkf_chainwave_table_free(&t);
        if (have == 0)
            return bkf_error_set(err, BKF_EINPUT, "the chain of N = %zu blocks has no rotating "
                                 "wave of n = %zu fronts (%s)", N, sp->n,
                                 note[0] ? note : "none on the branch from the uncoupled chain");
        return bkf_error_set(err, BKF_EINPUT, "n = %zu has %zu chain wave(s), not root %zu",
                             sp->n, have, sp->root);
    }
    const bkf_chainwave *w = &t.waves[sp->root - 1];
    double *psi = malloc(N * sizeof *psi), *eta = malloc(N * sizeof *eta);
    if (!psi || !eta) s = bkf_error_set(err, BKF_ENOMEM, "out of memory");
    /* block i -> block -i mirrors the ring: the same fronts moving towards +x */
    for (size_t i = 0; !s && i < N; i++) {
        size_t k = sp->direction < 0 ? i : (N - i) % N;
        psi[i] = w->psi[k];
        eta[i] = w->eta[k];
    }
    if (!s) s = bkf_pde_set_state(pde, psi, eta, 0.0, err);
    if (!s && clean_psi) memcpy(clean_psi, psi, N * sizeof *psi);
    if (!s) s = bkf_pde_add_noise(pde, sp->noise, sp->seed, err);
    if (!s && info) {
        info->v = w->v;
        info->v_err = w->v_err;
        info->mu = NAN; /* no cycle of the continuum behind it */
        info->T = w->P;
        info->stretch = 1.0;
        info->period_fixed = w->P;
        info->wavelength = p->S / (double)sp->n;
        info->residual = w->residual;
        info->roots_for_n = t.count;
    }
    free(psi);
    free(eta);
    bkf_chainwave_table_free(&t);
    return s;
}

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
    if (p->kind == BKF_MODEL_CHAIN) return seed_chain(pde, &sp, info, clean_psi, err);

    /* The speed condition is that of the continuum. */
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
    if ((s = bkf_speeds_root_status(&root, &e)))
        return bkf_error_set(err, s, "speeds, root %zu: %s", sp.root, e.message);
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

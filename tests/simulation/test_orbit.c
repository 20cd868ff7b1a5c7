/* Periodic orbits of the discretised PDE against independent routes: the
 * global oscillation's period from the cycle engine (the van der Pol
 * cycle at mu = gamma), its Floquet multipliers from the per-mode ODE of
 * the floquet module (a 2x2 monodromy per wavenumber: another method on
 * another system), the refusal of a tolerance the flow cannot meet, and
 * the period's convergence in tol. */
#include "harness.h"

#include <gsl/gsl_math.h>

#include <math.h>
#include <string.h>

#include "bkfront/cycle.h"
#include "bkfront/floquet.h"
#include "bkfront/orbit.h"
#include "bkfront/pde.h"
#include "pde_support.h"

/* The global oscillation's state (psi = nu rising) as a guess, its period
 * off by 1% so that Newton has work to do. */
typedef struct {
    bkf_pde *pde;
    bkf_floquet *fq;
    double T, T_err;
} uniform_guess;

static void uniform_make(uniform_guess *g, const bkf_model_params *p)
{
    bkf_error e;
    g->fq = bkf_floquet_alloc();
    CHECK_STATUS(bkf_floquet_set(g->fq, p->gamma, p->c, p->nu, NULL, &e), BKF_OK);
    const bkf_cycle_result *cr = bkf_floquet_cycle(g->fq);
    g->T = cr->period;
    g->T_err = cr->period_err;
    g->pde = alloc_pde(p, NULL);
    CHECK_STATUS(bkf_pde_init_oscillation(g->pde, 0, 0.0, &e), BKF_OK);
}

static void uniform_free(uniform_guess *g)
{
    bkf_pde_free(g->pde);
    bkf_floquet_free(g->fq);
}

static bkf_orbit *orbit_make(const bkf_model_params *p, const bkf_orbit_options *o)
{
    bkf_error e;
    bkf_orbit *ob = bkf_orbit_alloc(p, o, &e);
    CHECK_MSG(ob, "orbit alloc: %s", e.message);
    return ob;
}

/* (a) With psi_xx = 0 the model is the van der Pol oscillator at mu =
 * gamma: the uniform orbit's period is the cycle's, within the two
 * estimates; on the continuum and on the chain, at the paper's point and
 * away from it. */
TEST(orbit_uniform_oscillation_has_the_cycle_period)
{
    const bkf_model_params sets[] = {
        {2, 0.3, -0.92, 20, 32, BKF_MODEL_CONTINUUM},
        {0.7, 1.1, 0.35, 37, 16, BKF_MODEL_CONTINUUM},
        {5.5, 0.08, -0.6, 9, 9, BKF_MODEL_CHAIN},
    };
    for (size_t k = 0; k < sizeof sets / sizeof *sets; k++) {
        uniform_guess g;
        uniform_make(&g, &sets[k]);
        bkf_orbit_options o = bkf_orbit_options_default();
        o.tol = 1e-9;
        bkf_orbit *ob = orbit_make(&sets[k], &o);
        bkf_orbit_guess gs = {bkf_pde_psi(g.pde), bkf_pde_eta(g.pde), 1.01 * g.T, 0.0};
        bkf_orbit_result r;
        bkf_error e;
        CHECK_STATUS(bkf_orbit_solve(ob, &gs, &r, &e), BKF_OK);
        CHECK(r.symmetry == BKF_ORBIT_SYM_UNIFORM || sets[k].kind == BKF_MODEL_CHAIN);
        CHECK(r.err <= o.tol);
        CHECK_MSG(fabs(r.period - g.T) <= r.err + g.T_err, "T %.15g cycle %.15g err %.3g",
                  r.period, g.T, r.err);
        CHECK(r.shift == 0.0 && r.shift_held);
        bkf_test_note("set %zu: T %.15g vs cycle %.15g (diff %.2g, estimate %.2g: residual %.2g "
                      "flow %.2g grid %.2g), %zu Newton, %zu Jv",
                      k, r.period, g.T, r.period - g.T, r.err, r.err_residual, r.err_flow,
                      r.err_grid, r.newton_iterations, r.jv_products);
        bkf_orbit_free(ob);
        uniform_free(&g);
    }
}

/* The floquet multiplier at the allowed mode q_k = 2 pi k/S nearest to
 * (re, im), over the modes k in Bloch sector j of m cells (k = +-j mod m);
 * *err its estimate. */
static double nearest_floquet(bkf_floquet *fq, double S, size_t N, size_t m, size_t j, double re,
                              double im, double *err)
{
    double best = INFINITY;
    bkf_error e;
    for (size_t k = 0; k <= N / 2; k++) {
        if (k % m != j && (m - k % m) % m != j) continue;
        bkf_floquet_point fp;
        CHECK_STATUS(bkf_floquet_eval(fq, 2 * M_PI * (double)k / S, &fp, &e), BKF_OK);
        double d1 = hypot(fp.m1_re - re, fp.m1_im - im), d2 = hypot(fp.m2_re - re, fp.m2_im - im);
        double c1 = hypot(fp.m1_re - re, -fp.m1_im - im), c2 = hypot(fp.m2_re - re, -fp.m2_im - im);
        double d = fmin(fmin(d1, d2), fmin(c1, c2));
        if (d < best) {
            best = d;
            *err = fp.m1_err;
        }
    }
    return best;
}

/* (b) The full-domain Arnoldi on the PDE's monodromy, sector by sector
 * over 4 cells, against the per-mode 2x2 monodromies of floquet at the
 * allowed modes: every multiplier found is one of floquet's (within both
 * errors), and the verdict follows floquet's: stable at nu -0.92, unstable
 * past the period doubling at -0.94 with floquet's largest multiplier.
 * The filter is off: it damps the top modes and is not in floquet's
 * model. */
TEST(orbit_uniform_multipliers_match_floquet_by_sector)
{
    const double nus[] = {-0.92, -0.94};
    for (size_t t = 0; t < 2; t++) {
        bkf_model_params p = {2, 0.3, nus[t], 20, 32, BKF_MODEL_CONTINUUM};
        uniform_guess g;
        uniform_make(&g, &p);
        bkf_orbit_options o = bkf_orbit_options_default();
        o.filter = 0;
        o.cells = 4;
        bkf_orbit *ob = orbit_make(&p, &o);
        bkf_orbit_guess gs = {bkf_pde_psi(g.pde), bkf_pde_eta(g.pde), g.T, 0.0};
        bkf_error e;
        CHECK_STATUS(bkf_orbit_solve(ob, &gs, NULL, &e), BKF_OK);
        bkf_orbit_mult_options mo = bkf_orbit_mult_options_default();
        mo.k = 4;
        bkf_orbit_spectrum sp;
        CHECK_STATUS(bkf_orbit_multipliers(ob, &mo, &sp, &e), BKF_OK);
        CHECK(sp.trivial_expected == 1 && sp.trivial_found == 1);
        size_t physical = 0;
        size_t per_sector[3] = {0, 0, 0};
        double largest_fq = 0.0;
        for (size_t k = 1; k <= p.N / 2; k++) {
            bkf_floquet_point fp;
            CHECK_STATUS(bkf_floquet_eval(g.fq, 2 * M_PI * (double)k / p.S, &fp, &e), BKF_OK);
            largest_fq = fmax(largest_fq, hypot(fp.m1_re, fp.m1_im));
        }
        for (size_t i = 0; i < sp.count; i++) {
            const bkf_orbit_multiplier *mu = &sp.m[i];
            if (mu->kind != BKF_ORBIT_MULT_PHYSICAL) continue;
            physical++;
            per_sector[mu->sector]++;
            double ferr = 0;
            double d = nearest_floquet(g.fq, p.S, p.N, 4, mu->sector, mu->re, mu->im, &ferr);
            CHECK_MSG(d <= mu->err + ferr, "sector %zu m %.12g%+.12gi: nearest floquet %.3g away, "
                      "errors %.3g + %.3g", mu->sector, mu->re, mu->im, d, mu->err, ferr);
        }
        CHECK(per_sector[0] >= 1 && per_sector[1] >= 1 && per_sector[2] >= 1);
        CHECK_MSG(fabs(sp.largest_abs - largest_fq) <= sp.largest_err + 1e-9,
                  "largest %.12g vs floquet %.12g", sp.largest_abs, largest_fq);
        CHECK(sp.verdict == (t == 0 ? BKF_ORBIT_STABLE : BKF_ORBIT_UNSTABLE));
        bkf_test_note("nu %g: %zu physical multipliers in 3 sectors, largest %.12g +- %.2g "
                      "(floquet %.12g), trivial |m - 1| %.2g, %s, %zu monodromy products",
                      p.nu, physical, sp.largest_abs, sp.largest_err, largest_fq, sp.trivial_dev,
                      bkf_orbit_verdict_name(sp.verdict), sp.matvecs);
        bkf_orbit_free(ob);
        uniform_free(&g);
    }
}

/* (d) A tolerance the flow cannot meet is refused, and the estimate that
 * refuses it is honest (the period's actual error is within it). */
TEST(orbit_refuses_a_tol_the_flow_cannot_meet)
{
    bkf_model_params p = {1.3, 0.5, -0.3, 14, 16, BKF_MODEL_CONTINUUM};
    uniform_guess g;
    uniform_make(&g, &p);
    bkf_orbit_options o = bkf_orbit_options_default();
    o.tol = 1e-10;
    o.flow_tol = 1e-5;
    bkf_orbit *ob = orbit_make(&p, &o);
    bkf_orbit_guess gs = {bkf_pde_psi(g.pde), bkf_pde_eta(g.pde), 1.02 * g.T, 0.0};
    bkf_orbit_result r;
    bkf_error e;
    CHECK_STATUS(bkf_orbit_solve(ob, &gs, &r, &e), BKF_ETOL);
    CHECK(strstr(e.message, "exceeds tol") != NULL);
    CHECK(r.err > o.tol);
    CHECK_MSG(fabs(r.period - g.T) <= r.err, "T %.15g cycle %.15g estimate %.3g", r.period, g.T,
              r.err);
    bkf_test_note("refused: %s (actual error %.2g)", e.message, fabs(r.period - g.T));
    bkf_orbit_free(ob);
    uniform_free(&g);
}

TEST(orbit_refuses_bad_input)
{
    bkf_model_params p = {2, 0.3, -0.92, 20, 32, BKF_MODEL_CONTINUUM};
    bkf_orbit_options o = bkf_orbit_options_default();
    bkf_error e;
    o.cells = 3;
    CHECK(!bkf_orbit_alloc(&p, &o, &e) && e.status == BKF_EINPUT && strstr(e.message, "cells"));
    o.cells = 8; /* 4 points a cell */
    CHECK(!bkf_orbit_alloc(&p, &o, &e) && e.status == BKF_EINPUT && strstr(e.message, "cells"));
    o = bkf_orbit_options_default();
    o.tol = 1e-15;
    CHECK(!bkf_orbit_alloc(&p, &o, &e) && e.status == BKF_EINPUT && strstr(e.message, "tol"));
    o = bkf_orbit_options_default();
    o.shift_mode = BKF_ORBIT_SHIFT_FREE;
    p.kind = BKF_MODEL_CHAIN;
    CHECK(!bkf_orbit_alloc(&p, &o, &e) && e.status == BKF_EINPUT && strstr(e.message, "chain"));
    p.kind = BKF_MODEL_CONTINUUM;
    bkf_orbit *ob = orbit_make(&p, NULL);
    double z[32] = {0};
    bkf_orbit_guess gs = {z, z, -1.0, 0.0};
    CHECK_STATUS(bkf_orbit_solve(ob, &gs, NULL, &e), BKF_EINPUT);
    CHECK(strstr(e.message, "period") != NULL);
    bkf_orbit_spectrum sp;
    CHECK_STATUS(bkf_orbit_multipliers(ob, NULL, &sp, &e), BKF_EINPUT);
    bkf_orbit_free(ob);
}

/* (e) The period converges in tol: at every tol the estimate meets it and
 * the actual error (against the cycle engine) is within the estimate. */
TEST(orbit_period_converges_in_tol)
{
    bkf_model_params p = {3.1, 0.45, 0.62, 11, 16, BKF_MODEL_CONTINUUM};
    uniform_guess g;
    uniform_make(&g, &p);
    const double tols[] = {1e-4, 1e-6, 1e-8, 1e-10};
    for (size_t k = 0; k < 4; k++) {
        bkf_orbit_options o = bkf_orbit_options_default();
        o.tol = tols[k];
        bkf_orbit *ob = orbit_make(&p, &o);
        bkf_orbit_guess gs = {bkf_pde_psi(g.pde), bkf_pde_eta(g.pde), 0.97 * g.T, 0.0};
        bkf_orbit_result r;
        bkf_error e;
        CHECK_STATUS(bkf_orbit_solve(ob, &gs, &r, &e), BKF_OK);
        double actual = fabs(r.period - g.T);
        CHECK_MSG(actual <= r.err + g.T_err && r.err <= tols[k],
                  "tol %g: actual %.3g estimate %.3g", tols[k], actual, r.err);
        bkf_test_note("tol %g: error %.2g, estimate %.2g", tols[k], actual, r.err);
        bkf_orbit_free(ob);
    }
    uniform_free(&g);
}

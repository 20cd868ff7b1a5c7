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
#include "bkfront/speeds.h"
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

/* (c) A travelling train as an orbit periodic up to a shift: the fastest
 * n = 1 train of the speeds solver (an independent route: the speed
 * condition on the travelling-wave ODE) seeded on the grid, the period held
 * (a relative equilibrium), the shift solved: -s/T is the train's speed.
 * The period is 1.05 of the train's period at a fixed point, so that s is
 * not a whole wavelength (where R_s is the identity).  The grid (N 64) holds
 * the profile to a few 1e-3, s and T far better; the bound is the total
 * estimate over T. */
TEST(orbit_travelling_train_has_the_speeds_root)
{
    bkf_model_params p = {2, 0.3, -0.9, 20, 64, BKF_MODEL_CONTINUUM};
    bkf_speeds_options so = bkf_speeds_options_default();
    so.n_from = so.n_to = 1;
    so.tol = 1e-12;
    bkf_speeds_table tb;
    bkf_error e;
    CHECK_STATUS(bkf_speeds_find(&p, &so, &tb, &e), BKF_OK);
    CHECK(tb.count >= 1);
    const bkf_speeds_root *rt = &tb.roots[0];
    bkf_pde *m = alloc_pde(&p, NULL);
    bkf_pde_wave w = {1, rt->v, rt->mu, -1, 0.0, 1, 1e-12};
    CHECK_STATUS(bkf_pde_init_front(m, &w, NULL, NULL, &e), BKF_OK);
    bkf_orbit_options o = bkf_orbit_options_default();
    o.tol = 1e-2;
    o.shift_mode = BKF_ORBIT_SHIFT_FREE;
    bkf_orbit *ob = orbit_make(&p, &o);
    double T = 1.05 * rt->period_fixed;
    bkf_orbit_guess g = {bkf_pde_psi(m), bkf_pde_eta(m), T, -1.001 * rt->v * T};
    bkf_orbit_result r;
    CHECK_STATUS(bkf_orbit_solve(ob, &g, &r, &e), BKF_OK);
    CHECK(r.symmetry == BKF_ORBIT_SYM_TRAVELLING && r.period_held && !r.shift_held);
    double v = -r.shift / r.period;
    CHECK_MSG(fabs(v - rt->v) <= r.err / r.period + rt->v_err, "v %.12g root %.12g err %.3g", v,
              rt->v, r.err);
    /* the shift alone, against the second grid, is far better than the state */
    CHECK(fabs(r.shift2 - r.shift) < 1e-3 * r.err + 1e-6);
    bkf_test_note("v = -s/T %.12g vs root %.12g (diff %.2g); estimate %.2g (grid %.2g, s on the "
                  "second grid moved %.2g); %zu Jv",
                  v, rt->v, v - rt->v, r.err, r.err_grid, r.shift2 - r.shift, r.jv_products);
    bkf_orbit_free(ob);
    bkf_pde_free(m);
    bkf_speeds_table_free(&tb);
}

/* Trigonometric interpolation of a field of M points to N > M points (the
 * Nyquist mode dropped), by direct sums: independent of the library's FFTs. */
static void trig_interp(const double *in, size_t M, double *out, size_t N)
{
    for (size_t i = 0; i < N; i++) {
        double x = 2 * M_PI * (double)i / (double)N, v = 0.0;
        for (size_t k = 0; k < M / 2; k++) {
            double a = 0.0, b = 0.0;
            for (size_t j = 0; j < M; j++) {
                double y = 2 * M_PI * (double)(k * j) / (double)M;
                a += in[j] * cos(y);
                b += in[j] * sin(y);
            }
            double w = (k == 0 ? 1.0 : 2.0) / (double)M;
            v += w * (a * cos((double)k * x) + b * sin((double)k * x));
        }
        out[i] = v;
    }
}

/* Strobe observer: the change max |psi(kT) - psi((k-1)T)| once a period.
 * Consecutive strobes, not the distance from the orbit: the noise's part
 * along the neutral directions (a shift in time or space) stays as an
 * offset from the orbit for ever, but is the same at every strobe. */
typedef struct {
    size_t N;
    double T, prev[128], d[32];
    size_t n;
} strobe;

static int strobe_sample(const bkf_pde_sample *s, void *data)
{
    strobe *st = data;
    double k = s->t / st->T;
    if (fabs(k - nearbyint(k)) > 1e-6 || st->n >= 32) return 0;
    double d = 0.0;
    for (size_t i = 0; i < st->N; i++) {
        d = fmax(d, fabs(s->psi[i] - st->prev[i]));
        st->prev[i] = s->psi[i];
    }
    st->d[st->n++] = d;
    return 0;
}

/* (f) The paper's Fig. 4(b) point, gamma 2, c 0.3, S 20, nu -0.94: the state
 * a simulation reaches from the oscillation plus its mode 10 (near the
 * period doubling's q_c) is close to a period-doubled pacemaker, which
 * Newton makes exact: non-uniform, reflection-symmetric (s = 0 within its
 * error), its period near but not at twice the oscillation's.  Its largest
 * multiplier is checked by a simulation seeded with it plus noise: the
 * change from one period to the next, strobed, grows by |m| per period
 * (a third route: the plain time stepper, no tangent flow, no Arnoldi). */
TEST(orbit_pacemaker_at_fig4b_and_its_departure_rate)
{
    bkf_model_params p64 = {2, 0.3, -0.94, 20, 64, BKF_MODEL_CONTINUUM};
    bkf_error e;
    uniform_guess g;
    uniform_make(&g, &p64);
    CHECK_STATUS(bkf_pde_init_oscillation(g.pde, 10, 0.05, &e), BKF_OK);
    CHECK_STATUS(bkf_pde_run(g.pde, 300, 1.0, NULL, NULL, NULL, NULL, &e), BKF_OK);
    /* N 64 finds the orbit (the simulation on 128 points wanders elsewhere
     * in 300 time units); its grid error is 0.09, so it only seeds N 128 */
    bkf_orbit_options o = bkf_orbit_options_default();
    o.tol = 1e-3;
    o.grid_check = 0;
    bkf_orbit *ob = orbit_make(&p64, &o);
    bkf_orbit_guess gs = {bkf_pde_psi(g.pde), bkf_pde_eta(g.pde), 2 * g.T, 0.0};
    bkf_orbit_result r;
    CHECK_STATUS(bkf_orbit_solve(ob, &gs, &r, &e), BKF_OK);
    double T64 = r.period;
    bkf_model_params p = p64;
    p.N = 128;
    double u96[2 * 128];
    trig_interp(bkf_orbit_psi(ob), 64, u96, 128);
    trig_interp(bkf_orbit_eta(ob), 64, u96 + 128, 128);
    bkf_orbit_free(ob);
    /* the state's grid error at N 128 is a few 1e-3 (the period's 1e-4) */
    o.grid_check = 1;
    o.tol = 1e-2;
    ob = orbit_make(&p, &o);
    bkf_orbit_guess g96 = {u96, u96 + 128, r.period, 0.0};
    CHECK_MSG(bkf_orbit_solve(ob, &g96, &r, &e) == BKF_OK, "%s", e.message);
    CHECK(r.symmetry == BKF_ORBIT_SYM_GENERIC && r.amplitude > 0.1);
    CHECK_MSG(fabs(r.shift) <= r.err, "shift %.3g err %.3g", r.shift, r.err);
    CHECK_MSG(fabs(r.period - 2 * g.T) > 10 * r.err, "T %.12g vs 2 T_osc %.12g", r.period,
              2 * g.T);
    /* (e) in N: the period moves ten times less from N 128 to the second
     * grid (192) than from 64 to 128 */
    CHECK_MSG(fabs(r.period2 - r.period) < 0.2 * fabs(r.period - T64) && r.N2 == 192,
              "T %.12g, %.12g, %.12g at N 64, 128, %zu", T64, r.period, r.period2, r.N2);
    bkf_orbit_spectrum sp;
    CHECK_STATUS(bkf_orbit_multipliers(ob, NULL, &sp, &e), BKF_OK);
    CHECK(sp.trivial_found == 2);
    CHECK_MSG(sp.verdict == BKF_ORBIT_UNSTABLE, "%s: %s (largest %.6g +- %.2g)",
              bkf_orbit_verdict_name(sp.verdict), sp.reason, sp.largest_abs, sp.largest_err);
    /* seeded simulation: orbit + noise 1e-5 (the simulation's own error per
     * period is ~1e-8, the noise's part along the unstable eigenvector far
     * smaller than the noise), strobed at k T */
    bkf_pde *m = alloc_pde(&p, NULL);
    CHECK_STATUS(bkf_pde_set_state(m, bkf_orbit_psi(ob), bkf_orbit_eta(ob), 0.0, &e), BKF_OK);
    CHECK_STATUS(bkf_pde_add_noise(m, 1e-5, 7, &e), BKF_OK);
    strobe st = {p.N, r.period, {0}, {0}, 0};
    CHECK_STATUS(bkf_pde_run(m, 30 * r.period, r.period, strobe_sample, &st, NULL, NULL, &e),
                 BKF_OK);
    CHECK(st.n == 31);
    /* The rate over periods 24..30, when the unstable mode has overtaken
     * the others (the complex pair of |m| 1.03 beats with it until ~20;
     * the band-limited noise, modes up to S/2, barely touches
     * it: 8% of its content is above N/3). */
    double rate = pow(st.d[30] / st.d[24], 1.0 / 6.0);
    CHECK_MSG(fabs(rate - sp.largest_abs) <= 0.05 * sp.largest_abs,
              "departure per period %.4f vs largest multiplier %.4f", rate, sp.largest_abs);
    bkf_test_note("pacemaker at nu -0.94: T %.9g, %.9g, %.9g at N 64, 128, 192; at 128 %.6f T_osc "
                  "(estimate %.2g, grid %.2g), "
                  "amplitude %.4f, shift %.2g; largest |m| %.6f +- %.2g (%s); a seeded run "
                  "departs by %.4f per period (change %.2g -> %.2g over periods 24..30)",
                  T64, r.period, r.period2, r.period / g.T, r.err, r.err_grid, r.amplitude, r.shift,
                  sp.largest_abs, sp.largest_err, bkf_orbit_verdict_name(sp.verdict), rate,
                  st.d[24], st.d[30]);
    bkf_pde_free(m);
    bkf_orbit_free(ob);
    uniform_free(&g);
}

/* Upward crossings of psi at x = 0 through 0, linearly interpolated
 * between samples. */
typedef struct {
    double t_prev, v_prev, t[64];
    size_t n;
    int have;
} crossings;

static int crossing_sample(const bkf_pde_sample *s, void *data)
{
    crossings *c = data;
    double v = s->psi[0];
    if (c->have && c->v_prev < 0 && v >= 0 && c->n < 64)
        c->t[c->n++] = c->t_prev + (s->t - c->t_prev) * (-c->v_prev) / (v - c->v_prev);
    c->t_prev = s->t;
    c->v_prev = v;
    c->have = 1;
    return 0;
}

/* The stable pacemaker, on two cells of the paper's j = 9 pattern (S =
 * 2 * 20/9, so q_2 = q_9 of the ring of 20), nu -0.933 where the branch of
 * bkfront orbit is stable and coexists with the stable oscillation: a
 * simulation from the oscillation plus its mode 2 lands on it, Newton
 * makes it exact.  Three routes check it:
 *  - a simulation seeded with it plus noise keeps it: the time between
 *    every second crossing of psi(0, t) through 0 (the plain time stepper,
 *    no tangent flow) is the orbit's period, and the strobe change
 *    |u(kP) - u((k-1)P)| dies out;
 *  - the full-domain Arnoldi (one cell of length S) finds the multipliers
 *    of the two Bloch sectors (cells 2), each within both errors;
 *  - on a finer grid (N 128) the period and the largest multiplier move by
 *    less than the N 64 estimates. */
TEST(orbit_stable_pacemaker_kept_by_simulation_sectors_and_grid)
{
    bkf_model_params p = {2, 0.3, -0.933, 40.0 / 9.0, 64, BKF_MODEL_CONTINUUM};
    bkf_error e;
    bkf_pde *m = alloc_pde(&p, NULL);
    CHECK_STATUS(bkf_pde_init_oscillation(m, 2, 0.5, &e), BKF_OK);
    CHECK_STATUS(bkf_pde_run(m, 400, 1.0, NULL, NULL, NULL, NULL, &e), BKF_OK);
    bkf_orbit_options o = bkf_orbit_options_default();
    o.tol = 1e-3;
    o.cells = 2;
    o.shift_mode = BKF_ORBIT_SHIFT_FREE;
    bkf_orbit *ob = orbit_make(&p, &o);
    bkf_orbit_guess g = {bkf_pde_psi(m), bkf_pde_eta(m), 22.35, 0.0};
    bkf_orbit_result r;
    CHECK_MSG(bkf_orbit_solve(ob, &g, &r, &e) == BKF_OK, "%s", e.message);
    CHECK(r.symmetry == BKF_ORBIT_SYM_GENERIC && r.amplitude > 0.1);
    bkf_orbit_mult_options mo = bkf_orbit_mult_options_default();
    mo.k = 4;
    bkf_orbit_spectrum sp;
    CHECK_STATUS(bkf_orbit_multipliers(ob, &mo, &sp, &e), BKF_OK);
    CHECK_MSG(sp.verdict == BKF_ORBIT_STABLE, "%s: %s", bkf_orbit_verdict_name(sp.verdict),
              sp.reason);
    bkf_orbit_multiplier sec[16];
    size_t nsec = 0;
    for (size_t i = 0; i < sp.count && nsec < 16; i++)
        if (sp.m[i].kind == BKF_ORBIT_MULT_PHYSICAL && sp.m[i].abs > 0.05) sec[nsec++] = sp.m[i];
    CHECK(nsec >= 4);

    /* the seeded simulation, sampled finely for the crossings */
    bkf_pde *sim = alloc_pde(&p, NULL);
    CHECK_STATUS(bkf_pde_set_state(sim, bkf_orbit_psi(ob), bkf_orbit_eta(ob), 0.0, &e), BKF_OK);
    CHECK_STATUS(bkf_pde_add_noise(sim, 1e-4, 11, &e), BKF_OK);
    crossings cx;
    memset(&cx, 0, sizeof cx);
    CHECK_STATUS(bkf_pde_run(sim, 12 * r.period, r.period / 400, crossing_sample, &cx, NULL, NULL,
                             &e),
                 BKF_OK);
    CHECK_MSG(cx.n >= 22, "%zu crossings", cx.n);
    /* periods 2..11, after the noise has died (|m| 0.42 a period) */
    double P_sim = (cx.t[cx.n - 1] - cx.t[cx.n - 21]) / 10.0;
    CHECK_MSG(fabs(P_sim - r.period) <= r.err, "simulated period %.9g, orbit %.9g +- %.2g", P_sim,
              r.period, r.err);
    /* and not the oscillation's 2T (22.40 here), which the check above
     * would also tell apart: 50 times the estimate away */
    strobe st = {p.N, r.period, {0}, {0}, 0};
    CHECK_STATUS(bkf_pde_set_state(sim, bkf_orbit_psi(ob), bkf_orbit_eta(ob), 0.0, &e), BKF_OK);
    CHECK_STATUS(bkf_pde_add_noise(sim, 1e-4, 11, &e), BKF_OK);
    CHECK_STATUS(bkf_pde_run(sim, 8 * r.period, r.period, strobe_sample, &st, NULL, NULL, &e),
                 BKF_OK);
    CHECK_MSG(st.n == 9 && st.d[8] < 0.05 * st.d[2], "strobe change %.3g -> %.3g", st.d[2],
              st.d[8]);

    /* the full domain as one cell */
    bkf_orbit_options o1 = o;
    o1.cells = 1;
    bkf_orbit *ob1 = orbit_make(&p, &o1);
    bkf_orbit_guess g1 = {bkf_orbit_psi(ob), bkf_orbit_eta(ob), r.period, r.shift};
    bkf_orbit_result r1;
    CHECK_MSG(bkf_orbit_solve(ob1, &g1, &r1, &e) == BKF_OK, "%s", e.message);
    bkf_orbit_mult_options mo1 = mo;
    mo1.k = 8;
    bkf_orbit_spectrum sp1;
    CHECK_STATUS(bkf_orbit_multipliers(ob1, &mo1, &sp1, &e), BKF_OK);
    CHECK(sp1.verdict == BKF_ORBIT_STABLE);
    double worst = 0.0;
    for (size_t a = 0; a < nsec; a++) {
        double best = INFINITY, best_err = 0.0;
        for (size_t i = 0; i < sp1.count; i++) {
            if (sp1.m[i].kind != BKF_ORBIT_MULT_PHYSICAL) continue;
            double d = hypot(sp1.m[i].re - sec[a].re, sp1.m[i].im - sec[a].im);
            if (d < best) {
                best = d;
                best_err = sp1.m[i].err;
            }
        }
        CHECK_MSG(best <= sec[a].err + best_err,
                  "sector %zu m %.9g%+.9gi: full domain's nearest %.3g away (errors %.2g + %.2g)",
                  sec[a].sector, sec[a].re, sec[a].im, best, sec[a].err, best_err);
        worst = fmax(worst, best);
    }

    /* a finer grid, from the N 64 orbit interpolated */
    bkf_model_params p2 = p;
    p2.N = 128;
    double u2[2 * 128];
    trig_interp(bkf_orbit_psi(ob), 64, u2, 128);
    trig_interp(bkf_orbit_eta(ob), 64, u2 + 128, 128);
    bkf_orbit *ob2 = orbit_make(&p2, &o);
    bkf_orbit_guess g2 = {u2, u2 + 128, r.period, r.shift};
    bkf_orbit_result r2;
    CHECK_MSG(bkf_orbit_solve(ob2, &g2, &r2, &e) == BKF_OK, "%s", e.message);
    bkf_orbit_spectrum sp2;
    mo.k = 2;
    CHECK_STATUS(bkf_orbit_multipliers(ob2, &mo, &sp2, &e), BKF_OK);
    CHECK_MSG(fabs(r2.period - r.period) <= r.err, "P %.9g at N 64 (+- %.2g), %.9g at N 128",
              r.period, r.err, r2.period);
    CHECK_MSG(fabs(sp2.largest_abs - sp.largest_abs) <= sp.largest_err,
              "largest |m| %.6f +- %.2g at N 64, %.6f +- %.2g at N 128", sp.largest_abs,
              sp.largest_err, sp2.largest_abs, sp2.largest_err);
    bkf_test_note("stable pacemaker at nu -0.933: P %.9g +- %.2g (N 64), %.9g +- %.2g (N 128), "
                  "simulated %.9g; largest |m| %.6f +- %.2g (N 64), %.6f +- %.2g (N 128); "
                  "%zu sector multipliers found by the full domain within %.2g; strobe change "
                  "%.2g -> %.2g",
                  r.period, r.err, r2.period, r2.err, P_sim, sp.largest_abs, sp.largest_err,
                  sp2.largest_abs, sp2.largest_err, nsec, worst, st.d[2], st.d[8]);
    bkf_orbit_free(ob2);
    bkf_orbit_free(ob1);
    bkf_pde_free(sim);
    bkf_orbit_free(ob);
    bkf_pde_free(m);
}

static int stop_at_arnoldi(const char *stage, double fraction, void *data)
{
    (void)fraction;
    int *calls = data;
    (*calls)++;
    return strcmp(stage, "arnoldi") == 0;
}

/* The hooks: a raised cancel flag stops the solve at its first flow, a
 * progress callback that returns nonzero stops the multipliers, both with
 * BKF_ECANCELED; the stages reported before are Newton's. */
TEST(orbit_cancel_and_progress_stop_the_work)
{
    bkf_model_params p = {2, 0.3, -0.92, 20, 16, BKF_MODEL_CONTINUUM};
    uniform_guess g;
    uniform_make(&g, &p);
    volatile sig_atomic_t flag = 1;
    bkf_orbit_options o = bkf_orbit_options_default();
    o.cancel = &flag;
    bkf_orbit *ob = orbit_make(&p, &o);
    bkf_orbit_guess gs = {bkf_pde_psi(g.pde), bkf_pde_eta(g.pde), g.T, 0.0};
    bkf_error e;
    CHECK_STATUS(bkf_orbit_solve(ob, &gs, NULL, &e), BKF_ECANCELED);
    CHECK(bkf_orbit_psi(ob) == NULL);
    bkf_orbit_free(ob);
    int calls = 0;
    o = bkf_orbit_options_default();
    o.progress = stop_at_arnoldi;
    o.progress_data = &calls;
    ob = orbit_make(&p, &o);
    CHECK_STATUS(bkf_orbit_solve(ob, &gs, NULL, &e), BKF_OK);
    int before = calls;
    CHECK(before >= 1);
    bkf_orbit_spectrum sp;
    CHECK_STATUS(bkf_orbit_multipliers(ob, NULL, &sp, &e), BKF_ECANCELED);
    CHECK(calls == before + 1);
    bkf_orbit_free(ob);
    uniform_free(&g);
}

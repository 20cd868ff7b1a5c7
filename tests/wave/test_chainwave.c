/* The chain's rotating waves against independent values: the uniform
 * oscillation (n = N) against the cycle engine and the Floquet module, the
 * antiphase wave (n = N/2) against two blocks solved here, the continuum
 * limit at second order in h, and direct simulations of the chain. */
#include "harness.h"

#include "bkfront/chainwave.h"
#include "bkfront/cycle.h"
#include "bkfront/floquet.h"
#include "bkfront/pde.h"
#include "bkfront/speeds.h"

#include <gsl/gsl_errno.h>
#include <gsl/gsl_linalg.h>
#include <gsl/gsl_odeiv2.h>
#include <string.h>

static bkf_model_params chain(size_t N, double S)
{
    bkf_model_params p = bkf_model_params_paper();
    p.kind = BKF_MODEL_CHAIN;
    p.N = N;
    p.S = S;
    return p;
}

static bkf_chainwave find_with(const bkf_model_params *p, size_t n, double tol,
                               bkf_chainwave_stepper stepper)
{
    bkf_chainwave_options o = bkf_chainwave_options_default();
    o.tol = tol;
    o.stepper = stepper;
    bkf_chainwave_table t;
    bkf_error e;
    int s = bkf_chainwave_find(p, n, n, &o, &t, &e);
    CHECK_MSG(s == BKF_OK, "N = %zu n = %zu: %s", p->N, n, e.message);
    CHECK_MSG(t.count == 1, "N = %zu n = %zu: %zu waves", p->N, n, t.count);
    bkf_chainwave w = t.waves[0];
    t.count = 0;
    bkf_chainwave_table_free(&t);
    return w;
}

static bkf_chainwave find_one(const bkf_model_params *p, size_t n, double tol)
{
    return find_with(p, n, tol, BKF_CHAINWAVE_STEPPER_AUTO);
}

/* n = N: every block on the global oscillation, P = T(mu = gamma); the
 * reduced map's multipliers are exp(-2 pi i j/N) m(K_j) with the global
 * oscillation's multipliers at the lattice wavenumber q_j = (2/h) sin(pi j/N)
 * (1 + c^2 q_j^2 = 1 + 4 (c/h)^2 sin^2(pi j/N)): the leading modulus is the
 * largest exp(lambda_q) over j. */
TEST(chainwave_uniform_oscillation)
{
    bkf_model_params p = chain(8, 8.0);
    p.nu = -0.92;
    bkf_chainwave w = find_one(&p, 8, 1e-8);
    bkf_cycle_options co = bkf_cycle_options_default();
    co.tol = 1e-12;
    bkf_cycle_result cr;
    bkf_error e;
    CHECK(bkf_cycle_period(p.gamma, p.nu, &co, &cr, &e) == BKF_OK);
    CHECK_CLOSE(w.P, cr.period, 1e-9, 0.0);
    CHECK(fabs(w.P - cr.period) <= 10.0 * w.P_err + 1e-12);

    bkf_floquet *f = bkf_floquet_alloc();
    bkf_floquet_options fo = bkf_floquet_options_default();
    fo.tol = 1e-9;
    CHECK(bkf_floquet_set(f, p.gamma, p.c, p.nu, &fo, &e) == BKF_OK);
    double h = p.S / (double)p.N, best = 0.0;
    for (size_t j = 1; j < p.N; j++) {
        bkf_floquet_point pt;
        CHECK_MSG(bkf_floquet_eval(f, 2.0 / h * sin(M_PI * (double)j / (double)p.N), &pt, &e) ==
                      BKF_OK, "%s", e.message);
        best = fmax(best, exp(pt.lambda));
    }
    bkf_floquet_free(f);
    CHECK_CLOSE(w.mult_abs, best, 1e-7, 0.0);
    bkf_test_note("P = %.15g (T = %.15g), |m| = %.12g (Floquet %.12g), verdict %s", w.P,
                  cr.period, w.mult_abs, best, bkf_chainwave_verdict_name(w.verdict));
    bkf_chainwave_clear(&w);
}

/* ------------------------------------------------ two blocks in antiphase */

typedef struct {
    double gamma, nu, K;
} two_blocks;

static int two_rhs(double t, const double *y, double *f, void *data)
{
    (void)t;
    const two_blocks *b = data;
    for (int k = 0; k < 2; k++) {
        double p = y[2 * k], e = y[2 * k + 1], other = y[2 * (1 - k)];
        f[2 * k] = b->gamma * (e - (p * p * p / 3.0 - p));
        f[2 * k + 1] = -(p - b->nu - b->K * 2.0 * (other - p)) / b->gamma;
    }
    return GSL_SUCCESS;
}

/* F(x) = (y(T) - swap(y(0)), psi_a(0) - nu) for x = (y(0), T), T = half period */
static void two_residual(two_blocks *b, const double *x, double *F)
{
    double y[4];
    memcpy(y, x, sizeof y);
    gsl_odeiv2_system sys = {two_rhs, NULL, 4, b};
    gsl_odeiv2_driver *d = gsl_odeiv2_driver_alloc_y_new(&sys, gsl_odeiv2_step_rk8pd, 1e-3,
                                                         1e-13, 1e-13);
    double t = 0.0;
    CHECK(gsl_odeiv2_driver_apply(d, &t, x[4], y) == GSL_SUCCESS);
    gsl_odeiv2_driver_free(d);
    F[0] = y[0] - x[2];
    F[1] = y[1] - x[3];
    F[2] = y[2] - x[0];
    F[3] = y[3] - x[1];
    F[4] = x[0] - b->nu;
}

/* n = N/2: psi_{i+2} = psi_i, so the chain is two blocks a, b, each coupled
 * to the other on both sides, b half a period behind a.  Solved here by
 * Newton with a finite-difference Jacobian on 5 unknowns. */
TEST(chainwave_antiphase_is_two_blocks)
{
    bkf_model_params p = chain(20, 20.0);
    bkf_chainwave w = find_one(&p, 10, 1e-8);
    double h = p.S / (double)p.N;
    two_blocks b = {p.gamma, p.nu, p.c * p.c / (h * h)};
    /* a guess off the chain's wave by 1e-2, so the agreement is Newton's */
    double x[5] = {w.psi[0], w.eta[0] + 1e-2, w.psi[1] - 1e-2, w.eta[1], w.P / 2.0 * 1.01};
    for (int it = 0; it < 30; it++) {
        double F[5], J[25];
        two_residual(&b, x, F);
        for (int j = 0; j < 5; j++) {
            double xs[5], Fs[5];
            memcpy(xs, x, sizeof xs);
            double dx = 1e-7 * fmax(1.0, fabs(x[j]));
            xs[j] += dx;
            two_residual(&b, xs, Fs);
            for (int i = 0; i < 5; i++) J[i * 5 + j] = (Fs[i] - F[i]) / dx;
        }
        gsl_matrix_view Jm = gsl_matrix_view_array(J, 5, 5);
        gsl_vector_view Fv = gsl_vector_view_array(F, 5);
        gsl_permutation *perm = gsl_permutation_alloc(5);
        gsl_vector *dx = gsl_vector_alloc(5);
        int sign;
        gsl_linalg_LU_decomp(&Jm.matrix, perm, &sign);
        gsl_linalg_LU_solve(&Jm.matrix, perm, &Fv.vector, dx);
        double step = 0.0;
        for (int i = 0; i < 5; i++) {
            x[i] -= gsl_vector_get(dx, i);
            step = fmax(step, fabs(gsl_vector_get(dx, i)));
        }
        gsl_permutation_free(perm);
        gsl_vector_free(dx);
        if (step < 1e-12) break;
    }
    double P2 = 2.0 * x[4];
    CHECK_CLOSE(w.P, P2, 1e-8, 0.0);
    CHECK_CLOSE(w.v, 2.0 * h / P2, 1e-8, 0.0);
    for (size_t i = 0; i < p.N; i++) {
        CHECK_CLOSE(w.psi[i], x[2 * (i % 2)], 0.0, 1e-7);
        CHECK_CLOSE(w.eta[i], x[2 * (i % 2) + 1], 0.0, 1e-7);
    }
    bkf_test_note("n = N/2 = 10: P = %.15g, two blocks %.15g (v_err %.2g)", w.P, P2, w.v_err);
    bkf_chainwave_clear(&w);
}

/* As h -> 0 at fixed S and n the lattice Laplacian on a mode of
 * wavenumber q is -(4/h^2) sin^2(q h/2) = -q^2 (1 - q^2 h^2/12 + ...): the
 * speed converges to the continuum root at second order, error ratio 4
 * per halving of h, once h is well below the front's width (n = 1 here;
 * n = 4's fronts are ~1 block wide up to 80 blocks and reach the ratio 4
 * only beyond 160: docs/numerics.md). */
TEST(chainwave_continuum_limit_second_order)
{
    bkf_model_params cont = bkf_model_params_paper();
    bkf_speeds_options so = bkf_speeds_options_default();
    so.n_from = so.n_to = 1;
    bkf_speeds_table tab;
    bkf_error e;
    CHECK(bkf_speeds_find(&cont, &so, &tab, &e) == BKF_OK);
    double vc = tab.roots[0].v;
    bkf_speeds_table_free(&tab);
    const size_t Ns[] = {40, 80, 160};
    double err[3];
    bkf_chainwave_options o = bkf_chainwave_options_default();
    o.stability = 0;
    for (int k = 0; k < 3; k++) {
        bkf_model_params p = chain(Ns[k], 20.0);
        bkf_chainwave w;
        CHECK_MSG(bkf_chainwave_from_continuum(&p, 1, 1, &o, &w, &e) == BKF_OK, "%s",
                  e.message);
        err[k] = w.v - vc;
        bkf_test_note("N = %zu: v = %.15g, v - v_continuum = %.6g", Ns[k], w.v, err[k]);
        bkf_chainwave_clear(&w);
    }
    CHECK_CLOSE(err[0] / err[1], 4.0, 0.05, 0.0);
    CHECK_CLOSE(err[1] / err[2], 4.0, 0.02, 0.0);
}

/* The continuation from the uncoupled chain and the continuum's wave
 * polished on the chain are two routes to the same wave. */
TEST(chainwave_two_routes_agree)
{
    bkf_model_params p = chain(20, 20.0);
    bkf_chainwave_options o = bkf_chainwave_options_default();
    bkf_error e;
    for (size_t n = 1; n <= 2; n++) {
        bkf_chainwave a = find_one(&p, n, 1e-8), b;
        CHECK_MSG(bkf_chainwave_from_continuum(&p, n, 1, &o, &b, &e) == BKF_OK, "%s", e.message);
        CHECK_CLOSE(a.v, b.v, 1e-9, 0.0);
        CHECK_CLOSE(a.mult_abs, b.mult_abs, 0.0, 1e-8);
        bkf_chainwave_clear(&a);
        bkf_chainwave_clear(&b);
    }
}

/* The chain simulated (module pde, BKF_MODEL_CHAIN) from a computed wave:
 * after m shifts of tau the state is the wave shifted by m blocks.  A
 * stable wave stays so for a long time; an unstable one departs at the
 * rate sigma_max of its leading multiplier. */
static double departure(bkf_pde *pde, const bkf_chainwave *w, double t)
{
    bkf_error e;
    CHECK(bkf_pde_run(pde, t, t, NULL, NULL, NULL, NULL, &e) == BKF_OK);
    size_t N = w->N, m = (size_t)llround(t / w->tau);
    const double *psi = bkf_pde_psi(pde), *eta = bkf_pde_eta(pde);
    double d = 0.0;
    for (size_t i = 0; i < N; i++) {
        d = fmax(d, fabs(psi[i] - w->psi[(i + m) % N]));
        d = fmax(d, fabs(eta[i] - w->eta[(i + m) % N]));
    }
    return d;
}

TEST(chainwave_simulation_keeps_speed_and_verdict)
{
    bkf_model_params p = chain(20, 20.0);
    bkf_pde_options po = bkf_pde_options_default();
    po.tol = 1e-12;
    bkf_error e;
    /* n = 4: stable; the state after 100 shifts (t ~ 206) */
    bkf_chainwave w = find_one(&p, 4, 1e-9);
    CHECK(w.verdict == BKF_CHAINWAVE_STABLE);
    bkf_pde *pde = bkf_pde_alloc(&p, &po, &e);
    CHECK(pde && bkf_pde_set_state(pde, w.psi, w.eta, 0.0, &e) == BKF_OK);
    double d = departure(pde, &w, 100.0 * w.tau);
    /* a phase error dt shows as |psi'| dt, |psi'| <= ~3: speed to ~1e-9 */
    CHECK_MSG(d < 1e-7, "n = 4 departed by %g after 100 shifts", d);
    bkf_test_note("n = 4 (stable, |m| = %.9f): departure %.2g after t = %.1f", w.mult_abs, d,
                  100.0 * w.tau);
    bkf_pde_free(pde);
    bkf_chainwave_clear(&w);

    /* n = 2: unstable; a 1e-9 perturbation grows at sigma_max */
    w = find_one(&p, 2, 1e-9);
    CHECK(w.verdict == BKF_CHAINWAVE_UNSTABLE);
    pde = bkf_pde_alloc(&p, &po, &e);
    double *psi = malloc(p.N * sizeof *psi);
    for (size_t i = 0; i < p.N; i++) psi[i] = w.psi[i] + 1e-9 * sin(2.0 * M_PI * i / 20.0 + 1.0);
    CHECK(pde && bkf_pde_set_state(pde, psi, w.eta, 0.0, &e) == BKF_OK);
    /* the leading multiplier is complex: the departure oscillates about
       exp(sigma_max t), so the rate is a least-squares slope over many
       shifts, while it grows from 1e-9 to ~1e-4 */
    double st = 0, sy = 0, stt = 0, sty = 0;
    int count = 0;
    for (int k = 20; k <= 170; k++, count++) {
        double t = k * w.tau, y = log(departure(pde, &w, t));
        st += t, sy += y, stt += t * t, sty += t * y;
    }
    double d2 = departure(pde, &w, 171.0 * w.tau);
    double rate = (count * sty - st * sy) / (count * stt - st * st);
    CHECK_CLOSE(rate, w.sigma_max, 0.05, 0.0);
    bkf_test_note("n = 2 (unstable, m = %.6f + %.6f i): departure %.2g at t = %.0f, rate %.6f, sigma_max %.6f", w.mult_re, w.mult_im, d2, 171.0 * w.tau,
                  rate, w.sigma_max);
    free(psi);
    bkf_pde_free(pde);
    bkf_chainwave_clear(&w);
}

TEST(chainwave_bad_input)
{
    bkf_model_params p = chain(20, 20.0);
    bkf_chainwave_options o = bkf_chainwave_options_default();
    bkf_error e;
    CHECK_STATUS(bkf_chainwave_check(&p, 21, &o, &e), BKF_EINPUT);
    CHECK(strstr(e.message, "n = 21") != NULL);
    p.N = 1;
    CHECK_STATUS(bkf_chainwave_check(&p, 1, &o, &e), BKF_EINPUT);
    CHECK(strstr(e.message, "N = 1") != NULL);
    p.N = 20;
    p.nu = -1.0;
    CHECK_STATUS(bkf_chainwave_check(&p, 1, &o, &e), BKF_EINPUT);
    p.nu = -0.96;
    o.tol = 1.0;
    CHECK_STATUS(bkf_chainwave_check(&p, 1, &o, &e), BKF_EINPUT);
}

/* A strongly unstable wave (gamma 10, n 3 on 10 blocks: |m| ~ 200) at tol
 * 1e-8: its modulus is asked to tol |m| (absolute on ln|m|), not to 1e-8
 * absolute, so the wave is answered (it was refused, and with it the whole
 * table); the verdict is certain and the estimate covers the distance to
 * a solve at tol 1e-10 (plus that solve's own estimate).  (n 6 on 20
 * blocks, the same wave on a ring twice as long, |m| 200.34, cost 4.7 s
 * of CPU against 1.1: the variational columns grow as N^2.) */
TEST(chainwave_large_multiplier_tolerance_is_relative)
{
    bkf_model_params p = chain(10, 10.0);
    p.gamma = 10.0;
    bkf_chainwave a = find_one(&p, 3, 1e-8), b = find_one(&p, 3, 1e-10);
    CHECK(a.verdict == BKF_CHAINWAVE_UNSTABLE && b.verdict == BKF_CHAINWAVE_UNSTABLE);
    CHECK(a.mult_abs > 100.0);
    /* beyond 1e-8 absolute: the case the old tolerance refused */
    /* each within tol |m|, and at least one beyond tol absolute: the case
     * the old tolerance refused (which of the two depends on the path the
     * continuation took: 1.04e-8 at 1e-8 and 5.7e-10 at 1e-10 measured) */
    CHECK(a.mult_abs_err <= 1e-8 * a.mult_abs && b.mult_abs_err <= 1e-10 * b.mult_abs);
    CHECK_MSG(a.mult_abs_err > 1e-8 || b.mult_abs_err > 1e-10,
              "mult_abs_err %.3g (tol 1e-8), %.3g (tol 1e-10): neither beyond its tol", a.mult_abs_err,
              b.mult_abs_err);
    double dm = fabs(a.mult_abs - b.mult_abs), dv = fabs(a.v - b.v);
    CHECK_MSG(dm <= a.mult_abs_err + b.mult_abs_err, "|m| %.15g vs %.15g, estimate %.3g",
              a.mult_abs, b.mult_abs, a.mult_abs_err);
    CHECK(dv <= a.v_err + b.v_err);
    bkf_test_note("n = 3: |m| = %.15g +- %.2g (tol 1e-10: %.15g +- %.2g), |dm| = %.2g, "
                  "v %.15g, |dv| = %.2g (v_err %.2g)", a.mult_abs, a.mult_abs_err, b.mult_abs,
                  b.mult_abs_err, dm, a.v, dv, a.v_err);
    bkf_chainwave_clear(&a);
    bkf_chainwave_clear(&b);
}

/* The implicit stepper (CVODES: BDF, the variational columns as
 * sensitivities).  At gamma 40, beyond the explicit stepper's range: n = N
 * is the global oscillation, P = T(mu = gamma) of the cycle engine.  At
 * gamma 10 a travelling wave agrees with the explicit stepper at a tight
 * tol (they share nothing but the right-hand side).  On 4 blocks: the
 * dense BDF solves grow as N^3, and 8 blocks (the same waves: n = N, and
 * n 2 on 8 is n 1 on 4, v 0.1703019403) cost 3.9 s of CPU against 1.2. */
TEST(chainwave_implicit_stepper)
{
    bkf_model_params p = chain(4, 4.0);
    p.gamma = 40.0;
    p.nu = -0.92;
    bkf_chainwave u = find_with(&p, 4, 1e-6, BKF_CHAINWAVE_STEPPER_IMPLICIT);
    bkf_cycle_options co = bkf_cycle_options_default();
    co.tol = 1e-12;
    bkf_cycle_result cr;
    bkf_error e;
    CHECK(bkf_cycle_period(p.gamma, p.nu, &co, &cr, &e) == BKF_OK);
    CHECK_MSG(fabs(u.P - cr.period) <= u.P_err + 1e-12 * cr.period && u.P_err <= 1e-6 * u.P,
              "P %.15g +- %.2g, T %.15g", u.P, u.P_err, cr.period);
    bkf_test_note("gamma 40, n = N = 4: P = %.15g +- %.2g, T(40) = %.15g, |m| %.9f +- %.2g, "
                  "%zu steps", u.P, u.P_err, cr.period, u.mult_abs, u.mult_abs_err, u.steps);
    bkf_chainwave_clear(&u);
    /* without the option gamma 40 is refused, naming gamma */
    bkf_chainwave_options o = bkf_chainwave_options_default();
    CHECK_STATUS(bkf_chainwave_check(&p, 4, &o, &e), BKF_EINPUT);
    CHECK(strstr(e.message, "gamma = 40") != NULL);

    p.gamma = 10.0;
    bkf_chainwave a = find_with(&p, 1, 1e-6, BKF_CHAINWAVE_STEPPER_IMPLICIT);
    bkf_chainwave b = find_with(&p, 1, 1e-9, BKF_CHAINWAVE_STEPPER_EXPLICIT);
    CHECK_MSG(fabs(a.v - b.v) <= a.v_err + b.v_err, "v %.15g +- %.2g, explicit %.15g", a.v,
              a.v_err, b.v);
    CHECK_MSG(fabs(a.mult_abs - b.mult_abs) <= a.mult_abs_err + b.mult_abs_err,
              "|m| %.15g +- %.2g, explicit %.15g", a.mult_abs, a.mult_abs_err, b.mult_abs);
    CHECK(a.verdict == b.verdict && a.verdict != BKF_CHAINWAVE_UNRESOLVED);
    bkf_test_note("gamma 10, n = 1: v %.15g +- %.2g (explicit %.15g), |m| %.12g +- %.2g "
                  "(explicit %.12g), %s; steps %zu (explicit %zu)", a.v, a.v_err, b.v,
                  a.mult_abs, a.mult_abs_err, b.mult_abs, bkf_chainwave_verdict_name(a.verdict),
                  a.steps, b.steps);
    bkf_chainwave_clear(&a);
    bkf_chainwave_clear(&b);
}

/* The spectrum of a front train against direct simulation (issue 15, item
 * 5): the train plus eps times its eigenfunction is simulated with the
 * spectral PDE solver in the frame of the fronts, and the Fourier
 * coefficient of psi at the eigenfunction's own wavenumber is followed.  On
 * the ring of n fronts the wave itself has Fourier content only at indices
 * divisible by n, and the real seed Re(p) puts p at indices j mod n and its
 * conjugate at -j mod n: for j != 0 and 2 j != n the coefficient at index j
 * is eps p_j e^{sigma t} exactly, to first order in eps.  Its log modulus
 * grows at Re sigma and its phase turns at Im sigma, measured by a least
 * squares fit over the whole run: a method that shares nothing with the
 * monodromy (no cycle shooting, no Magnus steps, no Floquet phase). */
#include "harness.h"
#include "pde_support.h"

#include "bkfront/seed.h"
#include "bkfront/speeds.h"
#include "bkfront/trainspec.h"

#include <complex.h>
#include <string.h>
#include <time.h>

#define TWO_PI 6.283185307179586476925286766559

typedef struct {
    size_t k, count, cap;
    double *t, *logmod, *phase;
} follow;

/* The coefficient of psi at index k of an N-point field. */
static double complex coefficient(const double *psi, size_t N, size_t k)
{
    double complex c = 0;
    for (size_t i = 0; i < N; i++) c += psi[i] * cexp(-I * TWO_PI * (double)(k * i % N) / (double)N);
    return c / (double)N;
}

typedef struct {
    follow f;
    size_t N;
} observer_data;

static int observe(const bkf_pde_sample *s, void *data)
{
    observer_data *o = data;
    follow *f = &o->f;
    if (f->count == f->cap) return 1;
    double complex c = coefficient(s->psi, o->N, f->k);
    double ph = carg(c);
    if (f->count > 0) {
        double prev = f->phase[f->count - 1];
        ph += TWO_PI * floor((prev - ph) / TWO_PI + 0.5);
    }
    f->t[f->count] = s->t;
    f->logmod[f->count] = log(cabs(c));
    f->phase[f->count++] = ph;
    return 0;
}

/* Least-squares slope of y against t. */
static double slope(const double *t, const double *y, size_t n)
{
    double st = 0, sy = 0;
    for (size_t i = 0; i < n; i++) st += t[i], sy += y[i];
    st /= (double)n, sy /= (double)n;
    double num = 0, den = 0;
    for (size_t i = 0; i < n; i++) num += (t[i] - st) * (y[i] - sy), den += (t[i] - st) * (t[i] - st);
    return num / den;
}

/* Simulates the train n seeded with eps times the eigenfunction of
 * class j near sigma0; returns the measured sigma and the polished one. */
static void measure(bkf_model_params p, size_t n, size_t j, double complex sigma0, size_t N, double tmax,
                    double complex *measured, double complex *predicted)
{
    p.N = N;
    bkf_error e;
    bkf_pde_options po = bkf_pde_options_default();
    po.stepper = BKF_PDE_ETDRK4;
    po.tol = 1e-10;
    bkf_pde *m = alloc_pde(&p, &po);
    if (!m) return;
    bkf_pde_front_spec fs = bkf_pde_front_spec_default();
    fs.n = n;
    bkf_pde_front_info info;
    CHECK_MSG(bkf_seed_front(m, &fs, &info, NULL, &e) == BKF_OK, "seed: %s", e.message);
    bkf_pde_free(m);
    /* the same run in the frame of the fronts: the wave stands still */
    po.frame_speed = -info.v;
    m = alloc_pde(&p, &po);
    CHECK_MSG(bkf_seed_front(m, &fs, &info, NULL, &e) == BKF_OK, "seed: %s", e.message);

    double *psi = malloc(N * sizeof *psi), *eta = malloc(N * sizeof *eta);
    double *pr = malloc(N * sizeof *pr), *qr = malloc(N * sizeof *qr);
    bkf_trainspec_train train = {n, info.v};
    double re = creal(sigma0), im = cimag(sigma0);
    int rc = bkf_trainspec_mode(&p, &train, j, &re, &im, N, pr, NULL, qr, NULL, &e);
    CHECK_MSG(rc == BKF_OK, "mode: %s", e.message);
    *predicted = re + I * im;
    const double eps = 1e-4;
    memcpy(psi, bkf_pde_psi(m), N * sizeof *psi);
    memcpy(eta, bkf_pde_eta(m), N * sizeof *eta);
    for (size_t i = 0; i < N; i++) psi[i] += eps * pr[i], eta[i] += eps * qr[i];
    CHECK_MSG(bkf_pde_set_state(m, psi, eta, 0.0, &e) == BKF_OK, "%s", e.message);

    /* followed: the largest coefficient of the eigenfunction's class */
    size_t k_best = j;
    double best = 0.0;
    for (size_t k = j; k < N / 2; k += n)
        if (cabs(coefficient(pr, N, k)) > best) best = cabs(coefficient(pr, N, k)), k_best = k;
    size_t cap = (size_t)(tmax / 0.5) + 2;
    observer_data od = {{k_best, 0, cap, malloc(cap * sizeof(double)), malloc(cap * sizeof(double)),
                         malloc(cap * sizeof(double))},
                        N};
    rc = bkf_pde_run(m, tmax, 0.5, observe, &od, NULL, NULL, &e);
    CHECK_MSG(rc == BKF_OK, "run: %s", e.message);
    /* the first time unit is left out: the seeded wave relaxes onto the grid's */
    size_t from = 0;
    while (from < od.f.count && od.f.t[from] < 1.0) from++;
    *measured = slope(od.f.t + from, od.f.logmod + from, od.f.count - from) +
                I * slope(od.f.t + from, od.f.phase + from, od.f.count - from);
    free(od.f.t);
    free(od.f.logmod);
    free(od.f.phase);
    free(psi);
    free(eta);
    free(pr);
    free(qr);
    bkf_pde_free(m);
}

static void report(const char *name, double complex got, double complex want)
{
    printf("  %s: simulated %.9g%+.9gi, spectrum %.9g%+.9gi\n", name, creal(got), cimag(got), creal(want),
           cimag(want));
}

typedef struct {
    double gamma, c, nu, S;
    size_t n, j;
    double complex sigma; /* bkfront stability's value, the start of the polish */
    size_t N;             /* a multiple of n, so that the grid keeps the train's symmetry */
    double tmax;
} sim_case;

/* Re and Im sigma as simulated, to 1e-3 relative (the goal; the
 * runs below meet it with room: 1e-7 .. 7e-6 where the grid resolves the
 * fronts, which is why N grows with n).  The error is the grid's and the
 * seed's, not the fit's: a deterministic run with no noise reads the slope
 * of log |coefficient| to 1e-6 within a fraction of Im sigma's period, so
 * the runs stop at t = 50 where a longer one bought no agreement (n = 7 at
 * t = 200, n = 9 at 100, gamma 5 at 200: the same 1e-7 .. 7e-6 at 2-4
 * times the CPU); n = 8 runs on 3072 points (2.2e-6; on 2048 to t = 100,
 * its grid's 5.7e-5 at more CPU).  A planted 0.2% error of Re sigma fails
 * both tests. */
static void agree(const sim_case *cs, size_t count)
{
    for (size_t i = 0; i < count; i++) {
        const sim_case *k = &cs[i];
        bkf_model_params p = bkf_model_params_paper();
        p.gamma = k->gamma, p.c = k->c, p.nu = k->nu, p.S = k->S;
        double complex got = NAN, want = NAN;
        measure(p, k->n, k->j, k->sigma, k->N, k->tmax, &got, &want);
        char name[80];
        snprintf(name, sizeof name, "gamma %g n %zu j %zu", k->gamma, k->n, k->j);
        report(name, got, want);
        CHECK_MSG(fabs(creal(got) - creal(want)) <= 1e-3 * fabs(creal(want)), "%s: Re %.9g vs %.9g", name,
                  creal(got), creal(want));
        CHECK_MSG(fabs(cimag(got) - cimag(want)) <= 1e-3 * fabs(cimag(want)), "%s: Im %.9g vs %.9g", name,
                  cimag(got), cimag(want));
    }
}

/* The paper's table: n = 3 unstable, n = 4 stable (decays), and n = 7, 8,
 * 9, which the spectrum finds weakly unstable (Re sigma 5e-4 .. 4e-3,
 * oscillatory) where a run of t = 125 with noise 1e-6 sees nothing. */
TEST(trainspec_sim_paper)
{
    const sim_case cs[] = {
        {2, 0.3, -0.96, 20, 3, 2, 0.0243827 + 1.369082 * I, 384, 50},
        {2, 0.3, -0.96, 20, 4, 1, -0.0017319 - 0.111463 * I, 512, 100},
        {2, 0.3, -0.96, 20, 7, 2, 0.00051166 - 0.0995487 * I, 1792, 50},
        {2, 0.3, -0.96, 20, 8, 3, 0.00211607 - 0.117932 * I, 3072, 50},
        {2, 0.3, -0.96, 20, 9, 4, 0.00402923 - 0.1230196 * I, 4608, 50},
    };
    agree(cs, sizeof cs / sizeof cs[0]);
}

/* The two cases where today's check flips: gamma 5 (n = 4, weakly
 * unstable, Re sigma 4.4e-4 in class 1, 4.6e-4 in class 0) and gamma 1
 * (n = 10, growth 0.0128, the ~0.011 the issue saw in the deviation). */
TEST(trainspec_sim_other_parameters)
{
    const sim_case cs[] = {
        {5, 0.2, -0.9, 50, 4, 1, 0.000443807 - 0.81842 * I, 2048, 50},
        {1, 0.5, -0.5, 30, 10, 3, 0.0127629 + 0.443401 * I, 640, 50},
    };
    agree(cs, sizeof cs / sizeof cs[0]);
}

/* The Radau IIA steps are fifth order: halving every step (doubling the
 * substeps) cuts the error 32-fold, so successive differences of sigma
 * shrink by nearly 32 once the meshes resolve the train.  The thinnest
 * train of the paper's table, n = 12 (mu 47, stiff slow branches taken in
 * long steps), class 6; its ring spectrum, which the Magnus meshes of the
 * past refused, holds the limit within its error estimate. */
TEST(trainspec_converges_at_fifth_order_on_the_thinnest_train)
{
    bkf_model_params p = bkf_model_params_paper();
    bkf_speeds_table tab;
    bkf_error e;
    bkf_speeds_options so = bkf_speeds_options_default();
    so.n_from = so.n_to = 12;
    CHECK_MSG(bkf_speeds_find(&p, &so, &tab, &e) == BKF_OK && tab.count == 1, "%s", e.message);
    bkf_trainspec_train t = {12, tab.roots[0].v};
    bkf_speeds_table_free(&tab);
    double complex s[4];
    size_t steps[4];
    for (int i = 0; i < 4; i++) {
        double re, im;
        int rc = bkf_trainspec_eigenvalue_at(&p, &t, 6, 0.0023, -0.0385, (size_t)4 << i, &re, &im, &steps[i], &e);
        CHECK_MSG(rc == BKF_OK, "%s", e.message);
        s[i] = re + I * im;
    }
    CHECK(steps[1] == 2 * steps[0] && steps[3] == 8 * steps[0]);
    double d1 = cabs(s[1] - s[0]), d2 = cabs(s[2] - s[1]), d3 = cabs(s[3] - s[2]);
    printf("  differences %.3g %.3g %.3g: ratios %.2f %.2f\n", d1, d2, d3, d1 / d2, d2 / d3);
    CHECK_MSG(d1 / d2 > 24 && d1 / d2 < 40, "ratio %.3g", d1 / d2);
    CHECK_MSG(d2 / d3 > 24 && d2 / d3 < 40, "ratio %.3g", d2 / d3);
    double complex limit = s[3] + (s[3] - s[2]) / 31.0;
    bkf_trainspec_result r;
    CHECK_MSG(bkf_trainspec_ring(&p, &t, NULL, &r, &e) == BKF_OK, "%s", e.message);
    int seen = 0;
    for (size_t i = 0; i < r.count; i++)
        if (r.eigenvalues[i].j == 6 && cabs(r.eigenvalues[i].re + I * r.eigenvalues[i].im - limit) <= r.eigenvalues[i].err)
            seen = 1;
    CHECK_MSG(seen, "the ring spectrum has no class-6 eigenvalue within its error of %.10g%+.10gi", creal(limit),
              cimag(limit));
    /* the gauges hold at mu 47 too */
    CHECK_MSG(r.translation_residual <= 1e-6, "translation residual %.3g", r.translation_residual);
    printf("  n 12: mu %.4g sigma_max %.10g%+.10gi (err %.2g), limit %.10g%+.10gi, %zu steps per period\n", r.mu,
           r.sigma_max, r.sigma_max_im, r.sigma_max_err, creal(limit), cimag(limit), r.mesh_steps);
    bkf_trainspec_result_free(&r);
}

TEST(trainspec_mode_bad_input)
{
    bkf_model_params p = bkf_model_params_paper();
    bkf_trainspec_train t = {7, 0.34755127499881538};
    double re = 0.0005, im = -0.1, x[16];
    bkf_error e;
    CHECK(bkf_trainspec_mode(&p, &t, 7, &re, &im, 16, x, NULL, NULL, NULL, &e) == BKF_EINPUT);
    CHECK(strstr(e.message, "j must be in [0, n - 1]"));
    CHECK(bkf_trainspec_mode(&p, &t, 2, &re, &im, 1, x, NULL, NULL, NULL, &e) == BKF_EINPUT);
    CHECK(strstr(e.message, "N must be in"));
    CHECK(bkf_trainspec_eigenvalue_at(&p, &t, 2, re, im, 0, &re, &im, NULL, &e) == BKF_EINPUT);
    CHECK(strstr(e.message, "substeps must be in [1, 4096]"));
    CHECK(bkf_trainspec_eigenvalue_at(&p, &t, 2, NAN, im, 1, &re, &im, NULL, &e) == BKF_EINPUT);
    CHECK(strstr(e.message, "sigma must be finite"));
}

/* Eigenvalues followed to a nearby train (bkf_trainspec_track) against the
 * nearby train's own ring spectrum, a second route; and its refusals. */
#include "harness.h"

#include "bkfront/speeds.h"
#include "bkfront/trainspec.h"

#include <math.h>
#include <string.h>

/* The fastest root of n at the paper's gamma, c, nu and size S. */
static bkf_speeds_root root_at(size_t n, double S)
{
    bkf_model_params p = bkf_model_params_paper();
    p.S = S;
    bkf_speeds_options o = bkf_speeds_options_default();
    o.n_from = o.n_to = n;
    bkf_speeds_table t;
    bkf_error e;
    CHECK_STATUS(bkf_speeds_find(&p, &o, &t, &e), BKF_OK);
    CHECK(t.count >= 1);
    bkf_speeds_root r = t.roots[0];
    bkf_speeds_table_free(&t);
    return r;
}

/* The eigenvalues of train ta at pa but its translation, followed to
 * train tb at pb (bkf_trainspec_track), each land on the eigenvalue of its
 * Bloch class nearest it in pb's own ring spectrum, within both errors plus
 * tol, and each error estimate meets tol.  At most 64 are followed. */
static void check_followed_land_on_the_ring(const bkf_model_params *pa, bkf_trainspec_train ta,
                                            const bkf_model_params *pb, bkf_trainspec_train tb,
                                            double tol, size_t at_least, double mu_a, double mu_b)
{
    bkf_trainspec_options o = bkf_trainspec_options_default();
    o.tol = tol;
    o.per_kappa = 2;
    bkf_trainspec_result a, b;
    bkf_error e;
    CHECK_STATUS(bkf_trainspec_ring(pa, &ta, &o, &a, &e), BKF_OK);
    CHECK_STATUS(bkf_trainspec_ring(pb, &tb, &o, &b, &e), BKF_OK);
    if (mu_a > 0) CHECK_MSG(fabs(a.mu - mu_a) < 1 && fabs(b.mu - mu_b) < 1, "mu %g, %g", a.mu, b.mu);
    bkf_trainspec_eigenvalue from[64], to[64];
    size_t count = 0, followed = 0;
    for (size_t i = 0; i < a.count && count < 64; i++)
        if (!a.eigenvalues[i].translation) from[count++] = a.eigenvalues[i];
    CHECK(count >= at_least);
    CHECK_STATUS(bkf_trainspec_track(pb, &tb, tol, count, from, to, &followed, &e), BKF_OK);
    CHECK_MSG(followed == count, "%zu of %zu followed", followed, count);
    for (size_t i = 0; i < count; i++) {
        double best = INFINITY, err = 0;
        for (size_t k = 0; k < b.count; k++) {
            const bkf_trainspec_eigenvalue *x = &b.eigenvalues[k];
            double d = hypot(x->re - to[i].re, x->im - to[i].im);
            if (x->j == to[i].j && !x->translation && d < best) best = d, err = x->err;
        }
        CHECK_MSG(to[i].err <= tol, "j %zu: error %.3g", to[i].j, to[i].err);
        CHECK_MSG(best <= to[i].err + err + tol,
                  "j %zu: followed to %.10g%+.10gi, nearest of the ring %.3g away", to[i].j,
                  to[i].re, to[i].im, best);
    }
    bkf_trainspec_result_free(&a);
    bkf_trainspec_result_free(&b);
}

/* The paper's n = 3 from S 18 to 17.9 (a branch step): every eigenvalue of
 * the ring spectrum at 18 followed to 17.9 is an eigenvalue of 17.9's own
 * ring spectrum, of the same class, within both error estimates plus tol,
 * and each error estimate meets tol. */
TEST(trainspec_track_lands_on_the_ring_spectrum_of_the_next_train)
{
    bkf_model_params pa = bkf_model_params_paper(), pb = pa;
    pa.S = 18;
    pb.S = 17.9;
    bkf_speeds_root ra = root_at(3, pa.S), rb = root_at(3, pb.S);
    check_followed_land_on_the_ring(&pa, (bkf_trainspec_train){3, ra.v}, &pb,
                                    (bkf_trainspec_train){3, rb.v}, 1e-6, 3, 0, 0);
}

/* Past mu 100, where the Radau meshes' profile was bsimp's and the branch
 * took a ring spectrum at every point: the train of the paper scene's
 * n = 6 branch (gamma 1.5) next to the sonic limit, one front of it (n = 1,
 * L = S / 6, same v), followed from mu 98.9 to mu 120.8, lands on mu
 * 120.8's own ring spectrum within both errors plus tol. */
TEST(trainspec_track_past_mu_100_lands_on_the_ring_spectrum)
{
    bkf_model_params pa = {.gamma = 1.5, .c = 0.3, .nu = -0.96, .S = 7.389490447651168 / 6}, pb = pa;
    pb.S = 7.3742860006362232 / 6;
    check_followed_land_on_the_ring(&pa, (bkf_trainspec_train){1, 0.30003450265150527}, &pb,
                                    (bkf_trainspec_train){1, 0.30002312827876482}, 1e-6, 1, 99,
                                    121);
}

TEST(trainspec_track_refuses_bad_input)
{
    bkf_model_params p = bkf_model_params_paper();
    bkf_speeds_root r = root_at(2, p.S);
    bkf_trainspec_train t = {2, r.v};
    bkf_trainspec_eigenvalue from = {0.01, 0.5, 0, 2, 0, 0}, to;
    bkf_error e;
    CHECK_STATUS(bkf_trainspec_track(&p, &t, 1e-6, 1, &from, &to, NULL, &e), BKF_EINPUT);
    CHECK_MSG(strstr(e.message, "j must be"), "%s", e.message);
    from.j = 1;
    CHECK_STATUS(bkf_trainspec_track(&p, &t, 1e-9, 1, &from, &to, NULL, &e), BKF_EINPUT);
    CHECK_MSG(strstr(e.message, "tol"), "%s", e.message);
    from.re = NAN;
    CHECK_STATUS(bkf_trainspec_track(&p, &t, 1e-6, 1, &from, &to, NULL, &e), BKF_EINPUT);
    CHECK_STATUS(bkf_trainspec_track(&p, &t, 1e-6, 0, NULL, NULL, NULL, &e), BKF_OK);
}

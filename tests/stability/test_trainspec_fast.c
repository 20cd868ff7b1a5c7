/* The train spectrum's cheap paths (issue 33 item 1) against independent
 * routes: the traced curves' heights found by Newton from their prediction,
 * and the polish that skips the candidates the cut to per_kappa drops.
 * Each class's rightmost eigenvalue is held to Hill's method (dense
 * Fourier-Bloch eigenproblems, no monodromy, no curves; at 32 against 64
 * modes it converges to 1e-6 up to mu ~3.5, not at mu 4.3-12 on these
 * sets), each class's rightmost with one eigenvalue per class to the one
 * with three, and sigma_max to the same eigenvalue on 16 times the steps,
 * on random sets.  It failed on the cut counting the translation as one of
 * class 0's values (class 0's negative rightmost skipped, set 18), and in a
 * form at mu 6-12 on the curves traced on a mesh of half the steps (a
 * flat top's rightmost missed, mu 6.07). */
#include "harness.h"

#include "audit/audit.h"

#include "bkfront/hill.h"
#include "bkfront/speeds.h"
#include "bkfront/trainspec.h"
#include "trainspec_support.h"

#define TWO_PI 6.283185307179586476925286766559

static bkf_cycle *profile_of(bkf_model_params p, double v)
{
    double mu = p.gamma / sqrt(1.0 - (p.c / v) * (p.c / v));
    bkf_cycle *cy = bkf_cycle_alloc();
    bkf_cycle_options co = bkf_cycle_options_default();
    co.tol = 1e-12;
    bkf_error e;
    CHECK_MSG(bkf_cycle_solve(cy, mu, p.nu, &co, &e) == BKF_OK, "%s", e.message);
    return cy;
}

TEST(trainspec_newton_curves_and_polish_cut_match_hill_per_class_on_random_sets)
{
    size_t compared = 0, classes = 0;
    for (size_t i = 0; i < 60 && compared < 3; i++) {
        audit_set s = audit_draw(3307, i);
        bkf_model_params p = {s.gamma, s.c, s.nu, s.S, 0, BKF_MODEL_CONTINUUM};
        bkf_speeds_options so = bkf_speeds_options_default();
        so.n_from = 1, so.n_to = 4;
        bkf_speeds_table t;
        bkf_error e;
        if (bkf_speeds_find(&p, &so, &t, &e) != BKF_OK) continue;
        size_t best = t.count;
        for (size_t k = 0; k < t.count; k++)
            if (t.roots[k].status == BKF_OK && t.roots[k].mu > 2.0 && t.roots[k].mu <= 3.5 &&
                (best == t.count || t.roots[k].n > t.roots[best].n))
                best = k;
        if (best == t.count) {
            bkf_speeds_table_free(&t);
            continue;
        }
        const bkf_speeds_root *root = &t.roots[best];
        bkf_trainspec_result r;
        if (bkf_trainspec_root(&p, root, 1e-6, 1, &r, &e) != BKF_OK) {
            bkf_test_note("set %zu n %zu mu %.4g: refused (%s)", i, root->n, root->mu, e.message);
            bkf_speeds_table_free(&t);
            continue;
        }
        /* the cut to one per class may move no class's rightmost */
        bkf_trainspec_result r3;
        CHECK_MSG(bkf_trainspec_root(&p, root, 1e-6, 3, &r3, &e) == BKF_OK, "%s", e.message);
        for (size_t j = 0; j < root->n; j++) {
            double e1 = 0.0, e3 = 0.0, t1 = class_top(&r, j, &e1), t3 = class_top(&r3, j, &e3);
            CHECK_MSG(t1 == t3 || fabs(t1 - t3) <= e1 + e3,
                      "set %zu n %zu class %zu: rightmost %.12g with 1 per class, %.12g with 3", i, root->n, j, t1,
                      t3);
        }
        bkf_trainspec_result_free(&r3);
        bkf_cycle *cy = profile_of(p, root->v);
        size_t vouched = 0;
        for (size_t j = 0; 2 * j <= root->n; j++) {
            bkf_hill_eigenvalue h[4];
            double herr[4];
            size_t found = 0, unresolved = 0;
            /* two at class 0: the translation may be the first */
            CHECK(bkf_hill_leading(cy, p.gamma, TWO_PI * (double)j / (double)root->n, 32, 1e-6, 1 + (j == 0), h, herr,
                                   &found, &unresolved, &e) == BKF_OK);
            size_t m = 0;
            while (m < found && j == 0 && hypot(h[m].re, h[m].im) < 1e-6) m++;
            if (m == found || unresolved > 0) continue;
            double err = 0.0, top = class_top(&r, j, &err);
            /* Hill's rightmost right of the window: the spectrum must have it */
            if (!(h[m].re > r.a_lo)) continue;
            CHECK_MSG(fabs(top - h[m].re) <= err + herr[m] + 1e-9,
                      "set %zu n %zu mu %.4g class %zu: rightmost %.12g (err %.2g), Hill's %.12g (err %.2g)", i,
                      root->n, root->mu, j, top, err, h[m].re, herr[m]);
            vouched++;
        }
        bkf_cycle_free(cy);
        if (!r.sigma_is_bound) {
            bkf_trainspec_train tr = {root->n, root->v};
            size_t j = (size_t)lround(r.kappa_max * p.S / TWO_PI) % root->n;
            double re, im;
            CHECK_MSG(bkf_trainspec_eigenvalue_at(&p, &tr, j, r.sigma_max, r.sigma_max_im, 16, &re, &im, NULL, &e) ==
                          BKF_OK,
                      "%s", e.message);
            CHECK_MSG(hypot(re - r.sigma_max, im - r.sigma_max_im) <= r.sigma_max_err,
                      "set %zu n %zu: %.12g%+.12gi on 16 times the steps, %.12g%+.12gi (err %.2g) reported", i,
                      root->n, re, im, r.sigma_max, r.sigma_max_im, r.sigma_max_err);
        }
        bkf_test_note("set %zu (%s) gamma %.4g c %.4g nu %.4g S %.4g n %zu mu %.4g: sigma_max %.10g (err %.2g), "
                      "%zu of %zu classes held to Hill, %zu heights, %.3g steps",
                      i, s.kind, s.gamma, s.c, s.nu, s.S, root->n, root->mu, r.sigma_max, r.sigma_max_err, vouched,
                      root->n / 2 + 1, r.curve_points, r.work);
        classes += vouched;
        compared += vouched > 0;
        bkf_trainspec_result_free(&r);
        bkf_speeds_table_free(&t);
    }
    CHECK_MSG(compared == 3 && classes >= 5, "only %zu sets (%zu classes) held to Hill", compared, classes);
}

/* per_kappa 0 (speeds --stability's rows): the rightmost alone, the other
 * classes cut at it in the polish and dropped before the refinement.  On
 * the paper's n = 10 (the cut polishes less) and n = 12 (mu 47, two
 * refinements) it keeps fewer eigenvalues and works less than per_kappa
 * 1, and its sigma_max, kappa, kind and verdict are those of the whole
 * spectrum at tol 1e-8 (finer meshes, every class refined) within both
 * errors; nothing per_kappa 1 reports lies right of it beyond the errors.
 * It failed with the comparison in drop_dominated reversed (the rightmost
 * dropped: sigma_max 0.00156 against 0.00230). */
TEST(trainspec_rightmost_alone_is_the_whole_spectrums_rightmost)
{
    bkf_model_params p = bkf_model_params_paper();
    bkf_speeds_options so = bkf_speeds_options_default();
    so.n_from = 10, so.n_to = 12;
    bkf_speeds_table t;
    bkf_error e;
    CHECK_MSG(bkf_speeds_find(&p, &so, &t, &e) == BKF_OK && t.count == 3, "%s", e.message);
    for (size_t i = 0; i < t.count; i += 2) {
        bkf_trainspec_result r[3];
        const size_t per[3] = {0, 1, 1};
        const double tol[3] = {1e-6, 1e-6, 1e-8};
        for (int k = 0; k < 3; k++)
            CHECK_MSG(bkf_trainspec_root(&p, &t.roots[i], tol[k], per[k], &r[k], &e) == BKF_OK, "%s", e.message);
        bkf_test_note("n %zu: per_kappa 0 %zu values, work %.4g, sigma_max %.10g (err %.2g); per_kappa 1 %zu, "
                      "work %.4g; tol 1e-8 %.10g (err %.2g)",
                      t.roots[i].n, r[0].count, r[0].work, r[0].sigma_max, r[0].sigma_max_err, r[1].count,
                      r[1].work, r[2].sigma_max, r[2].sigma_max_err);
        CHECK(r[0].count < r[1].count && r[0].work < r[1].work);
        CHECK_CLOSE(r[0].sigma_max, r[2].sigma_max, 0, r[0].sigma_max_err + r[2].sigma_max_err);
        CHECK(r[0].sigma_max_err <= 1e-6 && r[0].kappa_max == r[2].kappa_max && r[0].verdict == r[2].verdict &&
              r[0].complex_pair == r[2].complex_pair);
        for (size_t k = 0; k < r[0].count; k++) CHECK(r[0].eigenvalues[k].err <= 1e-6);
        for (size_t k = 0; k < r[1].count; k++)
            if (!r[1].eigenvalues[k].translation)
                CHECK(r[1].eigenvalues[k].re <= r[0].sigma_max + r[0].sigma_max_err + r[1].eigenvalues[k].err);
        for (int k = 0; k < 3; k++) bkf_trainspec_result_free(&r[k]);
    }
    bkf_speeds_table_free(&t);
}

/* Hill's candidates validate the train spectrum's rightmost (issue 31):
 * the traced curves can step over an eigenvalue, two of one class closer
 * than the sampled phase tells, and a run where they close their window
 * would then report the neighbour.  Here the close is planted: the
 * spectrum handed to the validation is the curves' old answer at n = 1,
 * mu 1.2 (the neighbour 0.0106571 + 17.13i, the rightmost 0.0108024 +
 * 18.03i stepped over), and the validation must take the rightmost from
 * Hill's candidates, as an independent Hill run (64 and 128 modes) gives
 * it; a Hill candidate the meshes do not confirm refuses the spectrum,
 * also one left of the translation's sigma = 0. */
#include "harness.h"

#include "bkfront/hill.h"
#include "bkfront/speeds.h"
#include "bkfront/trainspec.h"

#include <string.h>

#include "../../src/stability/trainspec_internal.h"

static double fastest_root(bkf_model_params p)
{
    bkf_speeds_options so = bkf_speeds_options_default();
    so.n_from = so.n_to = 1;
    bkf_speeds_table t;
    bkf_error e;
    CHECK_MSG(bkf_speeds_find(&p, &so, &t, &e) == BKF_OK && t.count >= 1, "speeds: %s", e.message);
    double v = t.count ? t.roots[0].v : NAN;
    bkf_speeds_table_free(&t);
    return v;
}

/* sigma polished from guess on the context's coarse and fine meshes, as
 * the spectrum polishes a candidate. */
static bkf_trainspec_eigenvalue polished(ctx *x, double complex guess, derivs *dv)
{
    double complex sc = guess, sf;
    double step_c, step_f = INFINITY;
    dv->d[0] = dv->d[1] = NAN;
    CHECK(trainspec_polish(x, &x->coarse, 0.0, &sc, &step_c, dv->d) == BKF_OK);
    sf = sc;
    CHECK(trainspec_polish(x, &x->fine, 0.0, &sf, &step_f, dv->d) == BKF_OK);
    dv->coarse = sc;
    return (bkf_trainspec_eigenvalue){creal(sf), cimag(sf), trainspec_estimate(sc, sf, step_f), 0, 0.0, 0};
}

TEST(trainspec_hill_validates_a_rightmost_the_curves_stepped_over)
{
    bkf_model_params p = {1.20001, 0.188117, 0.2858, 53.5124, 0, BKF_MODEL_CONTINUUM};
    bkf_trainspec_train t = {1, fastest_root(p)};
    bkf_error e = {0};
    ctx x;
    CHECK_MSG(trainspec_ctx_init(&x, &p, &t, 1e-6, NULL, &e) == BKF_OK, "%s", e.message);
    double r_inf;
    window win = trainspec_initial_window(&x, &r_inf);
    candidates cs = {0};
    hill_stage hs;
    CHECK_MSG(trainspec_hill_candidates(&x, 1, &win, &cs, &hs, &e) == BKF_OK && hs.modes > 0, "%s", e.message);

    /* the independent reference: Hill at 64 and 128 modes */
    bkf_hill_eigenvalue ref[3];
    double ref_err[3];
    size_t found = 0;
    CHECK(bkf_hill_leading(x.cycle, p.gamma, 0.0, 64, 1e-7, 3, ref, ref_err, &found, NULL, &e) == BKF_OK);
    size_t k = hypot(ref[0].re, ref[0].im) < 1e-6 ? 1 : 0;
    CHECK(found == 3 && ref[k].re > 0.0108 && ref[k].re < 0.01081);

    /* the meshes the polish would use: for the candidates' |sigma| */
    double reach = 0.0;
    for (size_t i = 0; i < cs.count; i++) reach = fmax(reach, hypot(cs.items[i].a, cs.items[i].y));
    CHECK(trainspec_mesh_needs(&x, 1.25 * reach + 0.05, &e) == BKF_OK);
    CHECK(trainspec_mesh_build(&x, 1, &x.coarse, &e) == BKF_OK);
    CHECK(trainspec_mesh_build(&x, 2, &x.fine, &e) == BKF_OK);

    /* the plant: the curves' answer without the rightmost */
    bkf_trainspec_eigenvalue eig[16];
    derivs dv[16];
    size_t n_eig = 0;
    eig[n_eig] = polished(&x, 0.0106571 + 17.13 * I, &dv[n_eig]);
    n_eig++;
    CHECK_MSG(fabs(eig[0].re - 0.0106571) < 1e-6, "the neighbour polished to %.10g", eig[0].re);
    CHECK(cs.count + n_eig <= 16);
    int rc = trainspec_hill_validate(&x, 1, hs.modes, -INFINITY, &cs, eig, dv, &n_eig, &e);
    CHECK_MSG(rc == BKF_OK, "%s", e.message);
    double top = -INFINITY, top_im = NAN, top_err = NAN;
    for (size_t i = 0; i < n_eig; i++)
        if (eig[i].re > top) top = eig[i].re, top_im = eig[i].im, top_err = eig[i].err;
    bkf_test_note("Hill's candidates at %zu modes: rightmost %.10g%+.8gi (err %.2g), Hill 64/128 %.10g%+.8gi",
                  hs.modes, top, top_im, top_err, ref[k].re, ref[k].im);
    CHECK_MSG(fabs(top - ref[k].re) <= top_err + ref_err[k] + 1e-9, "rightmost %.10g, Hill %.10g", top, ref[k].re);
    CHECK(fabs(fabs(top_im) - fabs(ref[k].im)) <= top_err + ref_err[k] + 1e-9);

    /* a Hill candidate that is no eigenvalue, right of all: refused */
    candidate fake = {0.05, 17.5, 0, -1, 0};
    candidates one = {&fake, 1, 1};
    n_eig = 1;
    e.message[0] = 0;
    CHECK(trainspec_hill_validate(&x, 1, hs.modes, -INFINITY, &one, eig, dv, &n_eig, &e) == BKF_ETOL);
    CHECK_MSG(strstr(e.message, "do not confirm") != NULL, "%s", e.message);

    /* the translation (sigma 0, class 0) hides nothing: with it alone
     * polished, a candidate left of 0 (a stable train's rightmost, here one
     * the meshes do not confirm) is still checked, and refused */
    eig[0] = polished(&x, 0.0, &dv[0]);
    CHECK(hypot(eig[0].re, eig[0].im) < 1e-5);
    candidate left = {-0.005, 17.5, 0, -1, 0};
    candidates behind = {&left, 1, 1};
    n_eig = 1;
    e.message[0] = 0;
    CHECK_MSG(trainspec_hill_validate(&x, 1, hs.modes, -INFINITY, &behind, eig, dv, &n_eig, &e) == BKF_ETOL,
              "a candidate left of the translation: %zu values, %s", n_eig, e.message);

    trainspec_hill_stage_free(&hs);
    free(cs.items);
    trainspec_ctx_free(&x);
}

/* A followed stability curve's points without their own ring spectrum
 * (stabmap.c, trace_vouch: every other point, Newton's zero of the
 * eigenvalue tracked, the last ring spectrum's runner-up continued there
 * and left of it): fewer ring spectra than points, and each point still
 * where sigma_max changes sign, by ring spectra on either side of it. */
#include "harness.h"

#include "bkfront/model.h"
#include "bkfront/stabmap.h"

#include <math.h>
#include <stdlib.h>

static int counted(const bkf_model_params *params, const bkf_speeds_root *root, double tol,
                   bkf_trainspec_result *r, bkf_error *err, void *data)
{
    (*(size_t *)data)++;
    return bkf_trainspec_root(params, root, tol, 1, r, err);
}

typedef struct {
    bkf_stabmap_point p[64];
    size_t n;
} points;

static int keep(const bkf_stabmap_point *pt, void *data)
{
    points *ps = data;
    if (ps->n < 64) ps->p[ps->n++] = *pt;
    return 0;
}

/* n = 2 at the paper's gamma 2, c 0.3 from nu -0.98 (S 4.57) to -0.92
 * (S 7.19), stable above: 8 points; before, each its ring spectrum (8),
 * now 6 for the 8. */
TEST(stabmap_trace_points_without_ring_spectra_still_straddle_the_boundary)
{
    bkf_model_params p = bkf_model_params_paper();
    p.nu = -0.98;
    size_t rings = 0;
    bkf_stabmap_options o = bkf_stabmap_options_default();
    o.tol = 1e-5;
    o.S_tol = 0.01;
    o.nu_step = 0.01;
    o.S_step = 1.25;
    o.max_points = 60;
    o.spectrum = counted;
    o.spectrum_data = &rings;
    bkf_stabmap_point first;
    int found = 0;
    bkf_error e;
    CHECK_STATUS(bkf_stabmap_locate(&p, 2, 3.5, 6, 4, &o, &first, &found, &e), BKF_OK);
    CHECK(found);
    if (!found) return;
    bkf_stabmap_window w = {-0.98, -0.92, 2, 12};
    points ps = {0};
    bkf_stabmap_report rep;
    rings = 0;
    CHECK_STATUS(bkf_stabmap_trace(&p, 2, &first, 1, &w, &o, keep, &ps, &rep, &e), BKF_OK);
    bkf_test_note("%zu points, %zu ring spectra (report %zu), end %s", ps.n, rings,
                  rep.evaluations, bkf_stabmap_end_name(rep.end));
    CHECK(rep.end == BKF_STABMAP_END_REACHED);
    CHECK(ps.n >= 6);
    CHECK(rep.evaluations == rings);
    CHECK_MSG(rings < ps.n, "%zu ring spectra for %zu points", rings, ps.n);
    /* each point between a stable and an unstable train in S at its nu */
    bkf_stabmap_options check = bkf_stabmap_options_default();
    check.tol = 1e-5;
    for (size_t i = 0; i < ps.n; i++) {
        const bkf_stabmap_point *q = &ps.p[i];
        CHECK(q->stable_above);
        double d = fmax(4 * q->S_err, 2e-3 * q->S), side[2];
        for (int k = 0; k < 2; k++) {
            bkf_model_params at = p;
            at.nu = q->nu;
            at.S = q->S + (k ? d : -d);
            double err, v, mu;
            CHECK_STATUS(bkf_stabmap_sigma(&at, 2, q->v * at.S / q->S, &check, &side[k], &err, &v,
                                           &mu, NULL, &e),
                         BKF_OK);
            CHECK(fabs(side[k]) > err);
        }
        CHECK_MSG(side[0] > 0 && side[1] < 0,
                  "nu %.6f, S %.6f (S_err %.2g): sigma_max %.3g below, %.3g above", q->nu, q->S,
                  q->S_err, side[0], side[1]);
    }
}

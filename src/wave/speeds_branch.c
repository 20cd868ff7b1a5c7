/* The speeds' branches (speeds.c): one root v_n followed along a
 * parameter by pseudo-arclength continuation, through folds to the sonic
 * limit.  Above the rows (speeds.c), which it calls; nothing calls back. */
#include "speeds_internal.h"

#include "bkfront/asymptotics.h"
#include "bkfront/continuation.h"
#include "bkfront/cycle.h"
#include "bkfront/model.h"

#include <float.h>
#include <gsl/gsl_errno.h>
#include <gsl/gsl_roots.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------- branches */

/* Stop following a branch towards the sonic limit here: the remaining
 * piece is monotone in the expansion's regime and ends at p_sonic. */
#define BRANCH_SONIC_MU 1e3
#define BRANCH_STEP_MAX 0.2

typedef struct {
    bkf_model_params p;          /* the start; the continued component varies */
    bkf_speeds_param along;
    double n, tol, from, to;
    bkf_cycle *cycle;
    /* the last evaluation, which the driver makes at every accepted point
     * (for its tangent) just before accepting it */
    double last_u[2], last_T, last_T_err, last_G, last_Gs;
    int have_last;
    double prev_s, prev_Gs;       /* the previous regular point, for G_ss at a fold */
    int have_prev;
    bkf_speeds_visit visit;
    void *data;
    int stop_status;              /* > 0 error, < 0 visit stopped, 0 running */
    bkf_error *err;
    bkf_speeds_branch_report rep;
} branch_ctx;

static double *param_slot(bkf_model_params *q, bkf_speeds_param along)
{
    switch (along) {
    case BKF_SPEEDS_ALONG_S: return &q->S;
    case BKF_SPEEDS_ALONG_NU: return &q->nu;
    case BKF_SPEEDS_ALONG_GAMMA: return &q->gamma;
    default: return &q->c;
    }
}

static const char *param_name(bkf_speeds_param along)
{
    static const char *const names[] = {"S", "nu", "gamma", "c"};
    return names[along];
}

static bkf_model_params params_at(const branch_ctx *b, double p)
{
    bkf_model_params q = b->p;
    *param_slot(&q, b->along) = p;
    return q;
}

static int branch_T(branch_ctx *b, double mu, double nu, double *T, double *T_err, bkf_error *err)
{
    bkf_cycle_options o = bkf_cycle_options_default();
    o.tol = b->tol;
    bkf_error e = {0};
    int rc = bkf_cycle_solve(b->cycle, mu, nu, &o, &e);
    if (rc) return speeds_period_refused(rc, &e, nu, err);
    *T = bkf_cycle_get(b->cycle)->period;
    if (T_err) *T_err = bkf_cycle_get(b->cycle)->period_err;
    b->rep.solves++;
    return BKF_OK;
}

/* G(s, p) = ln T(mu(s), nu) - s - ln(S/(n c gamma)), with the Jacobian by
 * forward differences of T in mu (and in nu when continuing in nu). */
static int branch_residual(const double *u, double *g, double *jac, void *data, bkf_error *err)
{
    branch_ctx *b = data;
    bkf_model_params q = params_at(b, u[1]);
    if (!(q.c > 0) || !(q.S > 0) || !(fabs(q.nu) < 1) || !(q.gamma >= BKF_CYCLE_MU_MIN))
        return bkf_error_set(err, BKF_ENUMERIC, "left the valid range at %s = %g",
                             param_name(b->along), u[1]);
    double mu = mu_of_s(q.gamma, u[0]);
    if (!(mu <= BKF_CYCLE_MU_MAX))
        return bkf_error_set(err, BKF_ENUMERIC, "mu = %.15g beyond %g", mu, BKF_CYCLE_MU_MAX);
    double T, T_err;
    int rc = branch_T(b, mu, q.nu, &T, &T_err, err);
    if (rc) return rc == BKF_ENOMEM ? rc : BKF_ENUMERIC;
    double lnT = log(T);
    g[0] = lnT - u[0] - (log(q.S) - log(b->n * q.c * q.gamma));
    b->have_last = 0;
    if (!jac) return BKF_OK;
    /* With h = 1e-6 mu a relative error u of T moves mu dlnT/dmu by 2u/1e-6:
     * beyond mu ~ 100, where G_s -> 0 as g -> k, that reached |G_s| at tol
     * 1e-8 and put a spurious fold pair on the branch near the sonic end.
     * In the relaxation regime (mu >= TAIL_MU_MIN) ln T is nearly linear in
     * ln mu, so a step of 2 sqrt(u) mu costs no more truncation than noise;
     * below, where T turns fast (canards), the short step stays. */
    double h_rel = mu >= TAIL_MU_MIN ? fmax(1e-6, 2.0 * sqrt(T_err / T)) : 1e-6;
    double h = h_rel * mu, T2;
    if ((rc = branch_T(b, mu + h, q.nu, &T2, NULL, err))) return rc == BKF_ENOMEM ? rc : BKF_ENUMERIC;
    double dlnT_dmu = (log(T2) - lnT) / h;
    double Gs = dlnT_dmu * exp(2.0 * u[0]) / mu - 1.0, Gp;
    switch (b->along) {
    case BKF_SPEEDS_ALONG_S: Gp = -1.0 / q.S; break;
    case BKF_SPEEDS_ALONG_C: Gp = 1.0 / q.c; break;
    case BKF_SPEEDS_ALONG_GAMMA: Gp = dlnT_dmu * q.gamma / mu + 1.0 / q.gamma; break;
    default: {
        double hn = q.nu > 0 ? -1e-6 : 1e-6, T3; /* step towards 0, away from |nu| = 1 */
        if ((rc = branch_T(b, mu, q.nu + hn, &T3, NULL, err)))
            return rc == BKF_ENOMEM ? rc : BKF_ENUMERIC;
        Gp = (log(T3) - lnT) / hn;
    }
    }
    jac[0] = Gs;
    jac[1] = Gp;
    b->last_u[0] = u[0];
    b->last_u[1] = u[1];
    b->last_T = T;
    b->last_T_err = T_err;
    b->last_G = g[0];
    b->last_Gs = Gs;
    b->have_last = 1;
    return BKF_OK;
}

/* p where S = n k(nu) c gamma, the branch's sonic end; NaN if none. */
static double sonic_value(const branch_ctx *b, const bkf_model_params *q)
{
    double k = bkf_asym_k(q->nu);
    switch (b->along) {
    case BKF_SPEEDS_ALONG_S: return b->n * k * q->c * q->gamma;
    case BKF_SPEEDS_ALONG_C: return q->S / (b->n * k * q->gamma);
    case BKF_SPEEDS_ALONG_GAMMA: return q->S / (b->n * k * q->c);
    default: {
        /* k is even in nu and increases from k(0) to 3 as |nu| -> 1 */
        double target = q->S / (b->n * q->c * q->gamma), lo = 0.0, hi = 1.0;
        if (!(target > bkf_asym_k(0.0) && target < 3.0)) return NAN;
        for (int it = 0; it < 200; it++) {
            double mid = 0.5 * (lo + hi);
            if (bkf_asym_k(mid) < target) lo = mid;
            else hi = mid;
        }
        return copysign(0.5 * (lo + hi), q->nu);
    }
    }
}

static int branch_visit(branch_ctx *b, const bkf_speeds_branch_point *pt)
{
    if (b->visit(pt, b->data)) {
        b->stop_status = -1;
        return 1;
    }
    return 0;
}

static int branch_accept(const double *u, const double *tangent, int is_fold, void *data)
{
    branch_ctx *b = data;
    bkf_speeds_branch_point pt;
    memset(&pt, 0, sizeof pt);
    double p = u[1];
    /* the ends are requested values: give them back exactly */
    if (fabs(p - b->to) <= 1e-12 * fmax(fabs(b->to), 1e-300)) p = b->to;
    if (fabs(p - b->from) <= 1e-12 * fmax(fabs(b->from), 1e-300)) p = b->from;
    pt.params = params_at(b, p);
    pt.kind = is_fold ? BKF_SPEEDS_FOLD : BKF_SPEEDS_POINT;
    double k = bkf_asym_k(pt.params.nu);
    double mu = mu_of_s(pt.params.gamma, u[0]);
    if (!is_fold && mu > BRANCH_SONIC_MU && tangent[0] > 0) {
        /* heading to mu -> inf: the sonic limit closes the branch */
        double ps = sonic_value(b, &pt.params);
        if (isfinite(ps)) {
            *param_slot(&pt.params, b->along) = ps;
            bkf_speeds_root *r = &pt.root;
            r->n = (size_t)b->n;
            r->v = pt.params.c;
            r->mu = INFINITY;
            r->T = INFINITY;
            r->T_err = NAN;
            r->model = "leading"; /* mu = inf: T = k mu exactly in the limit */
            r->v_over_c = 1.0;
            r->wavelength = pt.params.S / b->n;
            r->period_fixed = k * pt.params.gamma;
            r->v_asym = pt.params.S / (b->n * k * pt.params.gamma);
            r->deviation = (r->v - r->v_asym) / r->v;
            pt.kind = BKF_SPEEDS_SONIC;
            b->rep.sonic = 1;
            b->rep.sonic_value = ps;
            branch_visit(b, &pt);
            b->stop_status = b->stop_status ? b->stop_status : -2;
            return 1;
        }
    }
    found_root f = {.n = b->n, .s = u[0], .model = "shooting"};
    if (b->have_last && b->last_u[0] == u[0] && b->last_u[1] == u[1]) {
        f.T = b->last_T;
        f.T_err = b->last_T_err;
        f.D = b->last_G;
        f.slope = b->last_Gs;
    } else {
        double g[1], jac[2];
        bkf_error e = {0};
        int rc = branch_residual(u, g, jac, b, &e);
        if (rc) {
            b->stop_status = bkf_error_set(b->err, rc, "at %s = %g: %s", param_name(b->along), u[1],
                                           e.message);
            return 1;
        }
        f.T = b->last_T;
        f.T_err = b->last_T_err;
        f.D = b->last_G;
        f.slope = b->last_Gs;
    }
    /* the driver's corrector stops at its own tolerance: one Newton step in
     * s at this exact p brings the residual to tol, away from folds */
    if (!is_fold && fabs(f.D) > b->tol && fabs(f.slope) > 1e-3) {
        double s1 = u[0] - f.D / f.slope, T1, T1_err;
        double mu1 = mu_of_s(pt.params.gamma, s1);
        bkf_error e = {0};
        if (mu1 <= BKF_CYCLE_MU_MAX && branch_T(b, mu1, pt.params.nu, &T1, &T1_err, &e) == BKF_OK) {
            double D1 = log(T1) - s1 - (log(pt.params.S) - log(b->n * pt.params.c * pt.params.gamma));
            if (fabs(D1) < fabs(f.D)) {
                f.s = s1;
                f.T = T1;
                f.T_err = T1_err;
                f.D = D1;
            }
        }
    }
    speeds_fill_row(&pt.params, k, &f, &pt.root);
    if (is_fold) {
        /* a double root: an error e of D moves s by sqrt(2 e / |G_ss|), not
         * by e/|G_s|; G_ss from the slope at the previous point */
        f.flags |= BKF_SPEEDS_NEAR_TANGENT;
        pt.root.flags = f.flags;
        double Gss = b->have_prev && f.s != b->prev_s ? (f.slope - b->prev_Gs) / (f.s - b->prev_s)
                                                      : NAN;
        double g2 = pt.params.gamma / pt.root.mu;
        double ds = sqrt(2.0 * (fabs(f.D) + f.T_err / f.T) / fabs(Gss));
        pt.root.v_err = isfinite(ds) ? pt.root.v * g2 * g2 * ds : INFINITY;
        b->rep.folds++;
    } else {
        b->prev_s = f.s;
        b->prev_Gs = f.slope;
        b->have_prev = 1;
        b->rep.points++;
    }
    return branch_visit(b, &pt);
}

static int speeds_branch_body(const bkf_model_params *start, size_t n, size_t root_index,
                              bkf_speeds_param along, double to, const bkf_speeds_options *options,
                              size_t max_points, bkf_speeds_visit visit, void *data,
                              bkf_speeds_branch_report *report, bkf_error *err)
{
    if (report) memset(report, 0, sizeof *report);
    if (!visit) return bkf_error_set(err, BKF_EINPUT, "visit callback is NULL");
    if ((unsigned)along > BKF_SPEEDS_ALONG_C)
        return bkf_error_set(err, BKF_EINPUT, "the continued parameter must be S, nu, gamma or c");
    bkf_speeds_options o = options ? *options : bkf_speeds_options_default();
    int rc = bkf_speeds_check(start, &o, err);
    if (rc) return rc;
    if (n < 1) return bkf_error_set(err, BKF_EINPUT, "n = 0 must be >= 1");
    if (root_index < 1)
        return bkf_error_set(err, BKF_EINPUT, "root_index = 0 must be >= 1 (1: the fastest)");
    if (!(start->c > 0))
        return bkf_error_set(err, BKF_EINPUT,
                             "c = 0: no continuation needed, v = S/(n T(gamma)) in closed form "
                             "(bkfront speeds); branches need c > 0");
    bkf_model_params end = *start;
    double from = *param_slot(&end, along);
    *param_slot(&end, along) = to;
    if (!isfinite(to))
        return bkf_error_set(err, BKF_EINPUT, "%s: the end value must be finite", param_name(along));
    if (to == from)
        return bkf_error_set(err, BKF_EINPUT, "%s: the end value %g equals the start",
                             param_name(along), to);
    if (along == BKF_SPEEDS_ALONG_C && !(to > 0))
        return bkf_error_set(err, BKF_EINPUT,
                             "c = %.15g: the branch must stay in c > 0 (c = 0 is the closed form "
                             "v = S/(n T(gamma)))", to);
    if ((rc = bkf_speeds_check(&end, NULL, err))) return rc;

    /* the start: every root of this n, then the chosen one */
    bkf_speeds_options fo = o;
    fo.n_from = fo.n_to = n;
    bkf_speeds_table t;
    rc = bkf_speeds_find(start, &fo, &t, err);
    if (rc) {
        bkf_speeds_table_free(&t);
        return rc;
    }
    if (t.count < root_index) {
        long n_max = t.n_max;
        size_t count = t.count;
        bkf_speeds_table_free(&t);
        if (count == 0)
            return bkf_error_set(err, BKF_EINPUT,
                                 "no front with n = %zu at %s = %g (n_max = %ld there): start "
                                 "the branch where one exists",
                                 n, param_name(along), from, n_max);
        return bkf_error_set(err, BKF_EINPUT, "root %zu for n = %zu does not exist at %s = %g "
                                              "(%zu root(s))",
                             root_index, n, param_name(along), from, count);
    }
    double mu0 = t.roots[root_index - 1].mu;
    rc = bkf_speeds_root_status(&t.roots[root_index - 1], err);
    bkf_speeds_table_free(&t);
    if (rc) return rc;

    branch_ctx b;
    memset(&b, 0, sizeof b);
    b.p = *start;
    b.along = along;
    b.n = (double)n;
    b.tol = o.tol;
    b.from = from;
    b.to = to;
    b.visit = visit;
    b.data = data;
    b.err = err;
    b.cycle = bkf_cycle_alloc();
    if (!b.cycle) return bkf_error_set(err, BKF_ENOMEM, "out of memory");

    double u0[2] = {0.5 * log((mu0 - start->gamma) * (mu0 + start->gamma)), from};
    /* scale p so that G changes by ~1 per unit: steps weigh s and p alike */
    double g0[1], jac0[2];
    bkf_error e = {0};
    rc = branch_residual(u0, g0, jac0, &b, &e);
    if (rc) {
        bkf_cycle_free(b.cycle);
        return bkf_error_set(err, rc == BKF_ENOMEM ? rc : BKF_ENUMERIC, "at the start: %s",
                             e.message);
    }
    double scale[2] = {1.0, 1.0 / fmax(fabs(jac0[1]), 1e-12)};
    scale[1] = fmin(scale[1], fabs(to - from));
    bkf_cont_options co = bkf_cont_options_default(1);
    co.scale = scale;
    co.step_max = BRANCH_STEP_MAX;
    co.step_initial = 0.25 * BRANCH_STEP_MAX;
    co.step_min = 1e-9;
    co.newton_tol = fmax(10.0 * o.tol, 1e-10);
    co.stop_index = 1;
    co.stop_min = fmin(from, to);
    co.stop_max = fmax(from, to);
    if (max_points) co.max_points = max_points;
    bkf_cont_report cr;
    bkf_error ce = {0};
    rc = bkf_cont_run(branch_residual, branch_accept, &b, u0, 1, to > from ? 1 : -1, &co, &cr, &ce);
    bkf_cycle_free(b.cycle);
    b.rep.reached_end = cr.reached_bound;
    if (report) *report = b.rep;
    if (b.stop_status > 0) return b.stop_status;
    if (b.stop_status < 0) return BKF_OK;
    if (rc) return bkf_error_set(err, rc, "continuation in %s: %s", param_name(along), ce.message);
    return BKF_OK;
}

int bkf_speeds_branch(const bkf_model_params *start, size_t n, size_t root_index,
                      bkf_speeds_param along, double to, const bkf_speeds_options *options,
                      size_t max_points, bkf_speeds_visit visit, void *data,
                      bkf_speeds_branch_report *report, bkf_error *err)
{
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    int rc = speeds_branch_body(start, n, root_index, along, to, options, max_points, visit, data, report, err);
    bkf_gsl_handler_pop(handler);
    return rc;
}

/* The cycle's shooting (cycle.c): one period from the section, Newton on
 * the return map, and the pieces of the error estimate (the pair's
 * difference, the rounding, the conditioning floor).  Above the flow
 * (cycle_flow.c); below the collocation path (cycle_colloc.c), the solve
 * (cycle.c) and the branch (cycle_branch.c), which call it. */
#include "cycle_internal.h"

#include "bkfront/asymptotics.h"
#include "bkfront/colloc.h"
#include "bkfront/continuation.h"
#include "bkfront/model.h"

#include <float.h>
#include <gsl/gsl_errno.h>
#include <gsl/gsl_math.h>
#include <gsl/gsl_odeiv2.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------ one period */

int cycle_node_push(bkf_cycle *c, double t, const double *s)
{
    if (c->node_count == c->node_capacity) {
        size_t cap = c->node_capacity ? 2 * c->node_capacity : 256;
        node *grown = realloc(c->nodes, cap * sizeof *grown);
        if (!grown) return BKF_ENOMEM;
        c->nodes = grown;
        c->node_capacity = cap;
    }
    c->nodes[c->node_count++] = (node){t, {s[IX], s[IY]}};
    return BKF_OK;
}

/* The rounding of one accepted step: its covariance cov = (xx, xy, yy) is
 * carried across the step by the transition F of the (x, y) block, plus the
 * step's own rounding, independent per step and per coordinate,
 * (DBL_EPSILON |x|)^2 and (DBL_EPSILON |y|)^2 (one to two ulps: a step's
 * stages add to the final sum's half ulp).  Forward, so no inversion: the
 * repelling slow branch grows it, the attracting branches shrink it, as
 * they do the rounding itself.  F is exact where it matters: it takes the
 * flow f0 to f1 (a phase shift stays one: rounding along the flow jitters
 * the time, by up to 1e-13 at a knee, and a leak of it across the flow
 * was multiplied by dT/dy0 ~ 4e6 at mu 3.65, nu -0.99) and its determinant
 * is exp(L1 - L0) (Liouville); only its shear along f1 is estimated, from
 * exp of the step's mean Jacobian with the exact mean trace (closed form). */
static void rounding_step(const flow_params *p, const double *s0, const double *s1, double h, double *cov)
{
    double f0x = cycle_flow_xdot(p, s0), f0y = (p->nu - s0[IX]) / p->a;
    double f1x = cycle_flow_xdot(p, s1), f1y = (p->nu - s1[IX]) / p->a;
    double n0 = hypot(f0x, f0y), n1 = hypot(f1x, f1y);
    if (!(n0 > 0) || !(n1 > 0)) return;
    double u0x = f0x / n0, u0y = f0y / n0, u1x = f1x / n1, u1y = f1y / n1;
    /* exp(A), A = h x mean Jacobian: e^m (c I + d (A - m I)), m = tr A / 2,
     * (A - m I)^2 = q I */
    double j11 = s1[IL] - s0[IL], j12 = p->a * h, j21 = -h / p->a;
    double m = 0.5 * j11, q = m * m + j12 * j21, c, d;
    if (q > 0) {
        double r = sqrt(q);
        c = cosh(r);
        d = sinh(r) / r;
    } else if (q < 0) {
        double r = sqrt(-q);
        c = cos(r);
        d = sin(r) / r;
    } else {
        c = d = 1.0;
    }
    double e = exp(m);
    /* the shear: the estimate's image of the normal -u0y, u0x along u1 */
    double gx = e * ((c + d * (j11 - m)) * -u0y + d * j12 * u0x);
    double gy = e * (d * j21 * -u0y + (c - d * m) * u0x);
    double shear = gx * u1x + gy * u1y, stretch = exp(j11) * n0 / n1, along = n1 / n0;
    /* F = along u1 u0^T + (shear u1 + stretch n1) n0^T, n = (-u_y, u_x) */
    double f11 = along * u1x * u0x + (shear * u1x - stretch * u1y) * -u0y;
    double f12 = along * u1x * u0y + (shear * u1x - stretch * u1y) * u0x;
    double f21 = along * u1y * u0x + (shear * u1y + stretch * u1x) * -u0y;
    double f22 = along * u1y * u0y + (shear * u1y + stretch * u1x) * u0x;
    double xx = cov[0], xy = cov[1], yy = cov[2];
    /* F cov F^T */
    double a11 = f11 * xx + f12 * xy, a12 = f11 * xy + f12 * yy;
    double a21 = f21 * xx + f22 * xy, a22 = f21 * xy + f22 * yy;
    double ex = DBL_EPSILON * s1[IX], ey = DBL_EPSILON * s1[IY];
    cov[0] = a11 * f11 + a12 * f12 + ex * ex;
    cov[1] = a11 * f21 + a12 * f22;
    cov[2] = a21 * f21 + a22 * f22 + ey * ey;
}

/* Integrate one turn from (nu, y0) back to the section.  With `keep` the
 * accepted steps are stored for the profile and the extrema of x located. */
int cycle_shoot(integrator *main_in, integrator *aux, flow_params *p, double y0, const double *p0,
                bkf_cycle *keep, shot *out, bkf_error *err)
{
    double s[DIM_SENS] = {p->nu, y0, 0.0, 1.0, 0.0, p0 ? p0[0] : 0.0, p0 ? p0[1] : 0.0}, s_prev[DIM_SENS];
    double t = 0.0, t_prev, h = 0.01 / fmax(1.0, p->mu);
    int went_below = 0;
    /* The downward passage must go clearly below the section before an
     * upward crossing counts: near |nu| -> 1 at large mu the slow branch
     * creeps past the knee within 1e-3 of x = nu, and step noise there must
     * not be mistaken for the return. */
    double below_margin = 0.25 * fmin(2.0 * sqrt(1.0 - p->nu * p->nu), 1.0);
    double xmax = p->nu, xmin = p->nu;
    double cov[3] = {0.0, 0.0, 0.0};
    if (keep) {
        keep->node_count = 0;
        if (cycle_node_push(keep, t, s) != BKF_OK) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    }
    cycle_integrator_reset(main_in);
    for (size_t n = 0;; n++) {
        if (n > MAX_STEPS_PER_PERIOD)
            return bkf_error_set(err, BKF_EBUDGET,
                                 "cycle at mu = %.15g, nu = %.15g: no return to the section after %d steps",
                                 p->mu, p->nu, MAX_STEPS_PER_PERIOD);
        memcpy(s_prev, s, sizeof s);
        t_prev = t;
        int rc = cycle_integrator_apply(main_in, &t, GSL_POSINF, &h, s);
        main_in->steps++;
        if (rc != BKF_OK || !isfinite(s[IX]) || !isfinite(s[IY]))
            return bkf_error_set(err, BKF_ENUMERIC,
                                 "cycle at mu = %.15g, nu = %.15g: integration failed at z = %g", p->mu,
                                 p->nu, t);
        if (keep) {
            double xd_prev = cycle_flow_xdot(p, s_prev), xd = cycle_flow_xdot(p, s);
            if ((xd_prev > 0) != (xd > 0)) {
                double te, se[DIM_SENS];
                if (cycle_locate_event(aux, p, cycle_event_extremum, t_prev, s_prev, t, s, &te, se) != BKF_OK)
                    return bkf_error_set(err, BKF_ENUMERIC,
                                         "cycle at mu = %.15g, nu = %.15g: extremum not located", p->mu,
                                         p->nu);
                if (se[IX] > xmax) xmax = se[IX];
                if (se[IX] < xmin) xmin = se[IX];
            }
        }
        /* No step may turn the state by more than MAX_TURN radians about
         * the equilibrium in the phase plane (f - nu, f'): bsimp at loose
         * tolerance otherwise steps over the whole lower half of a small
         * cycle near the Hopf point (steps of 4 against a period of 2 pi at
         * mu = 3, nu = 0.9999) and the return counts two turns.  The rate
         * is -1 - mu (f^2 - 1) u f'/(u^2 + f'^2), u = f - nu: about 1 on
         * small cycles, ~0 on the slow branches of relaxation cycles,
         * where steps stay long.  Where the limit, not the tolerance, sets
         * the steps, two tolerances would integrate alike and their
         * difference say nothing: see tighten_turn. */
        {
            double u = s[IX] - p->nu, fp = cycle_flow_xdot(p, s), r2 = u * u + fp * fp;
            if (r2 > 0) {
                double turn = fabs(-1.0 - p->mu * (s[IX] * s[IX] - 1.0) * u * fp / r2);
                if (turn * h > main_in->max_turn) {
                    h = main_in->max_turn / turn;
                    main_in->capped++;
                }
            }
        }
        if (s[IX] < p->nu - below_margin) went_below = 1;
        if (went_below && s[IX] >= p->nu) break;
        if (main_in->rounding) rounding_step(p, s_prev, s, t - t_prev, cov);
        if (keep && cycle_node_push(keep, t, s) != BKF_OK)
            return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    }
    double T, sr[DIM_SENS];
    if (cycle_locate_event(aux, p, cycle_event_section, t_prev, s_prev, t, s, &T, sr) != BKF_OK)
        return bkf_error_set(err, BKF_ENUMERIC,
                             "cycle at mu = %.15g, nu = %.15g: return to the section not located", p->mu,
                             p->nu);
    out->period = T;
    out->y_return = sr[IY];
    out->dP = sr[IVY];
    out->dT = -sr[IVX] / cycle_flow_xdot(p, sr);
    out->log_mult = sr[IL];
    out->xmax = xmax;
    out->xmin = xmin;
    out->px = sr[IPX];
    out->py = sr[IPY];
    out->xdot = cycle_flow_xdot(p, sr);
    if (main_in->rounding) rounding_step(p, s_prev, sr, T - t_prev, cov);
    memcpy(out->rounding, cov, sizeof cov);
    return BKF_OK;
}

/* --------------------------------------------------------------- solve */

bkf_cycle_options bkf_cycle_options_default(void)
{
    return (bkf_cycle_options){.tol = 1e-10, .stepper = BKF_STEPPER_AUTO, .warm_start = 1};
}

bkf_cycle *bkf_cycle_alloc(void) { return calloc(1, sizeof(bkf_cycle)); }

void bkf_cycle_free(bkf_cycle *cycle)
{
    if (!cycle) return;
    free(cycle->nodes);
    bkf_colloc_free(cycle->colloc);
    free(cycle);
}

const bkf_cycle_result *bkf_cycle_get(const bkf_cycle *cycle)
{
    return cycle && cycle->have_solution ? &cycle->result : NULL;
}

/* Section coordinate y0 of a starting guess with slope f'(0) = w. */
double cycle_section_y_of_slope(const flow_params *p, double w)
{
    return w / p->a + p->b * lienard_F(p->nu);
}

/* Slope f' at the upward crossing of f = nu: from the small-mu harmonic
 * cycle of radius 2 sqrt(1 - nu^2), or from the large-mu jump, which leaves
 * the left knee at Lienard height 2/3 plus the Airy overshoot.  Between the
 * Hopf point |nu| = 1 and half-way to the canard explosion (1 - |nu| ~
 * 1/(8 mu^2)) the cycle is small and nearly harmonic at any mu: measured half-amplitude
 * 0.0283 against 2 sqrt(1 - nu^2) = 0.0283 at mu 1 and 3, nu 0.9999; 0.116
 * against 0.089 at mu 10, nu -0.999.  The jump guess there started Newton
 * on a relaxation-sized orbit, 40 times too large, and cost 12-14 shots
 * (now 2-5); closer to the explosion (8 mu^2 (1 - |nu|) ~ 0.7) it was the
 * better guess of the two. */
double cycle_guess_slope(double mu, double nu)
{
    if (mu < 1.0 || 16.0 * mu * mu * (1.0 - fabs(nu)) < 1.0) return 2.0 * sqrt(1.0 - nu * nu);
    double jump_height = 2.0 / 3.0 + BKF_AIRY_A1 * cbrt((1.0 + nu) * (1.0 + nu)) * pow(mu, -4.0 / 3.0);
    double w = mu * (jump_height - lienard_F(nu));
    return w > 0 ? w : 2.0 * sqrt(1.0 - nu * nu);
}

/* The classic pair (tight tolerances) keeps equal turn limits and instead
 * floors the estimate at the looser solve's local tolerance times T when
 * the limit shortened any of its steps (pessimistic, but the tightest
 * accepted tolerances and the Floquet references depend on it; halving the
 * turn there made bsimp refuse tol 1e-11 at mu 30, nu 0.9999, where its
 * old answer was 1.3e-11 off with an estimate of 8e-12). */
double cycle_capped_floor(double period_err, const integrator *looser, double period)
{
    return looser->capped ? fmax(period_err, looser->tol * period) : period_err;
}

/* What |T_a - T_b| cannot see, measured against an independent long-double
 * Taylor integration (tests/wave/taylor_reference.h; docs/accuracy.md):
 *  - Where the two solves' errors happen to coincide, the difference is
 *    small while both are off: bsimp's error is not monotone in the
 *    tolerance (at mu 51.75, nu 0.5 local tolerances 8.7e-6 and 8.7e-7 both
 *    gave T 3.8e-8 low, their difference 7e-10), nor is rk8pd's where its
 *    steps are set by stability (mu 7-9).  A floor proportional to the
 *    tighter solve's tolerance covers this: the largest measured error per
 *    unit tol_b T was 0.56 for bsimp, 16 for bd2x2 and 0.3 for rk8pd
 *    (relative to the cycle's size 2 sqrt(1 - nu^2) where that is below
 *    1, since the tolerance is absolute; BD_ERROR_PER_TOL,
 *    RK8PD_ERROR_PER_TOL); bsimp's floor is under half of that, so that
 *    its estimate is never optimistic by more than 3 (bsimp is no
 *    automatic choice any more), the others' cover it.
 *  - Rounding: one ulp of the return map g moves the fixed point by
 *    ulp/(1 - P') and T by dT/dy0 times that.  Near the Hopf point and in
 *    the canard region that amplification reaches 1e3-1e4 T (mu 10,
 *    nu 0.9999: errors 1.3e-12 at tol 1e-14, reported 2e-14).  bsimp's own
 *    rounding (linear solves, extrapolation) measured 4 times rk8pd's. */
double cycle_error_per_tol(bkf_stepper_kind kind)
{
    return kind == BKF_STEPPER_EXTRAPOLATION ? BD_ERROR_PER_TOL
           : kind != BKF_STEPPER_EXPLICIT    ? 0.25
                                             : RK8PD_ERROR_PER_TOL;
}

/* The cycle's size where it is below 1 (the tolerances are absolute). */
double cycle_size(double nu)
{
    return fmin(1.0, 2.0 * sqrt(1.0 - nu * nu));
}

/* In the canard's neighbourhood the stiff pair's errors at two local
 * tolerances coincide: errors made on the repelling slow branch are
 * amplified like the rounding there, and the pair's difference missed them
 * (nu 0.9999, mu 35.3358, tol 1e-5: bd2x2's pair 2.6e-8 T apart, both
 * 2.9e-7 T off).  Measured against the Taylor reference, the error was
 * 0.016-0.077 times the rounding's standard deviation scaled from
 * DBL_EPSILON to the tighter solve's local tolerance.  At 0.08, the top of
 * that, a scan of the neighbourhood still found 3.5 (bd2x2, nu 0.999, mu
 * 11.18, tol 1e-10) and 3.3 (bsimp, nu 0.995, mu 5.12, tol 1e-12); at 0.12
 * none above 3 in it (docs/accuracy.md, stiffwin). */
#define TRUNCATION_PER_ROUNDING 0.12
/* Beyond the explosion, in the rest of the neighbourhood, the rounding is
 * no longer amplified enough to carry that floor, yet the stiff pair's
 * errors still coincided at up to 6.6 times the pair's floor (bd2x2 at
 * nu 0.9995, mu 31.86, tol 1e-6: true 7.2e-7 T, estimate 1.1e-7 T; bsimp
 * at nu 0.999, mu 16.86, tol 1e-6: 6.1): the floor per unit tol_b T is
 * raised there by this factor. */
#define CANARD_ERROR_PER_TOL_FACTOR 4.0
double cycle_period_error(const converged *a, const converged *b, const flow_params *p,
                          bkf_stepper_kind kind, double cond_floor)
{
    int implicit = kind != BKF_STEPPER_EXPLICIT;
    double tol_floor = cycle_error_per_tol(kind) * b->tol * b->period / cycle_size(p->nu) *
                       (implicit && cycle_canard_neighbourhood(p->mu, p->nu) ? CANARD_ERROR_PER_TOL_FACTOR : 1.0);
    double amplified = b->period + fmax(1.0, fabs(b->y0)) * fabs(b->dT) / (1.0 - fmin(b->return_slope, 0.999999));
    double round_floor = (implicit ? 30.0 : 8.0) * DBL_EPSILON * amplified;
    double diff = fabs(a->period - b->period) + 8.0 * DBL_EPSILON * b->period;
    /* the stiff pair's truncation error, amplified as the rounding is
     * (conditioning_floor) */
    double amplified_truncation = implicit ? TRUNCATION_PER_ROUNDING * cond_floor * b->tol / DBL_EPSILON : 0.0;
    return fmax(fmax(diff, fmax(cond_floor, amplified_truncation)), fmax(tol_floor, round_floor));
}

/* The standard deviation of T due to rounding, from one shot at the fixed
 * point y0 that carries the rounding's covariance (rounding_step) to the
 * return.  There a perturbation (dx, dy) moves the return time by
 * -dx/x' and the return by dy, hence the fixed point by dy/(1 - P') and
 * T by dT/dy0 dy/(1 - P'). */
static int period_rounding(flow_params *p, bkf_stepper_kind kind, double tol, double y0, double *sigma,
                           size_t *steps, bkf_error *err)
{
    flow_params q = *p;
    q.sens = 0;
    integrator in = {0}, aux = {0};
    int rc = BKF_ENOMEM;
    if (cycle_integrator_init(&in, &q, kind, 0, tol) == BKF_OK &&
        cycle_integrator_init(&aux, &q, kind, 1, tol) == BKF_OK) {
        shot sh = {0};
        in.rounding = 1;
        rc = cycle_shoot(&in, &aux, &q, y0, NULL, NULL, &sh, err);
        if (rc == BKF_OK) {
            double zx = -1.0 / sh.xdot, zy = sh.dT / (1.0 - fmin(sh.dP, 0.999999));
            double var = zx * zx * sh.rounding[0] + 2.0 * zx * zy * sh.rounding[1] + zy * zy * sh.rounding[2];
            *sigma = var > 0 ? sqrt(var) : 0.0;
        }
    }
    p->rhs_calls += q.rhs_calls;
    p->jacobian_calls += q.jacobian_calls;
    *steps += in.steps + aux.steps;
    cycle_integrator_free(&in);
    cycle_integrator_free(&aux);
    return rc == BKF_ENOMEM ? bkf_error_set(err, BKF_ENOMEM, "out of memory") : rc;
}

/* The conditioning floor of the estimate inside the canard explosion.
 * There T is so ill-conditioned that the integration's rounding, amplified
 * on the repelling slow branch, moves T more than two tolerances' answers
 * differ: both carry the same rounding-level bias (cold solve at mu
 * 3.6505198, nu 0.99, tol 1e-10: |T_a - T_b| 2.2e-12 T against a true
 * 2.1e-11 T).  The floor is the standard deviation of T over the rounding
 * of every step, DBL_EPSILON relative in x and in y (period_rounding).  It replaced
 * T's response to two ulps of nu, DBL_EPSILON |dT/dnu|, which counted the
 * rounding once where it is injected at every step: against the Taylor
 * reference that floor was optimistic by up to 6.7 at mu 11.214, nu 0.999,
 * where the standard deviation is 5.7-6.5 times it; at mu 3.6505, nu 0.99
 * it is 2.5 times it (docs/accuracy.md).
 * Only in the canard's neighbourhood 8 mu^2 (1 - |nu|) in [0.5, 2] (the
 * explosion is at ~1) does the extra shot run: outside it |d ln T/d nu|
 * stays below 1/(1 - |nu|) and the estimates were measured honest there
 * (docs/accuracy.md), so the work elsewhere is unchanged.  For bd2x2 and
 * bsimp it runs in the wider canard_neighbourhood, where their estimate
 * scales it to their truncation error (TRUNCATION_PER_ROUNDING). */
int cycle_conditioning_floor(flow_params *p, bkf_stepper_kind kind, double tol, double y0, double *floor,
                             size_t *steps, bkf_error *err)
{
    *floor = 0.0;
    if (!cycle_canard_window(p->mu, p->nu) &&
        (kind == BKF_STEPPER_EXPLICIT || !cycle_canard_neighbourhood(p->mu, p->nu)))
        return BKF_OK;
    return period_rounding(p, kind, tol, y0, floor, steps, err);
}

/* The return map's slope for Newton at y0.  A planar flow's return map has
 * the slope exp(L) x'(y0)/x'(P(y0)) (Liouville), *slope_L.  Where the cycle
 * attracts like exp(-O(mu)) that is far below what the variational column
 * resolves, whose dP is then noise of either sign: at mu 1e3 a coarse dP of
 * -0.03 put Newton beyond P(y0), and the safeguard bisected to half the
 * start (two wasted shots).  Only for bd2x2 (no GSL driver): rk8pd's and
 * bsimp's Newton paths, and so their digits, stay as they were. */
double cycle_map_slope(const integrator *in, const shot *sh, double y0, double y_still, double *slope_L)
{
    double w_return = sh->y_return - y_still;
    *slope_L = !in->driver && w_return > 0 ? exp(sh->log_mult) * (y0 - y_still) / w_return : NAN;
    return *slope_L >= 0 && *slope_L < 1e-6 ? *slope_L : sh->dP;
}

/* Newton on g(y0) = P(y0) - y0 at one integration tolerance, from y0,
 * safeguarded by the bracket that each return gives: P is increasing and the
 * cycle attracting, so g(y0) > 0 puts the cycle above both y0 and P(y0).
 *
 * The period is corrected to first order in the last Newton step, so the
 * iteration may stop once that step's square is negligible (|dT step| <=
 * t_goal T) and the step is either below y_goal or no longer shrinking
 * quadratically, i.e. down to the integration's noise. */
int cycle_newton_at(bkf_cycle *c, integrator *in, integrator *aux, double *y0, double t_goal,
                    double y_goal, double y_scale, double q_goal, int keep, int land, size_t *iterations,
                    converged *out, bkf_error *err)
{
    flow_params *p = &c->flow;
    const double y_still = p->b * lienard_F(p->nu); /* x' = 0 on the section */
    double lo = y_still, hi = GSL_POSINF;
    double previous_step = GSL_POSINF, stride = 0.0;
    int inversions = 0;
    in->noisy = 0;
    for (int iter = 0; iter < MAX_NEWTON; iter++) {
        shot sh = {0};
        int rc = cycle_shoot(in, aux, p, *y0, NULL, keep ? c : NULL, &sh, err);
        if (rc != BKF_OK) return rc;
        (*iterations)++;
        double g = sh.y_return - *y0;
        double slope_L, dP = cycle_map_slope(in, &sh, *y0, y_still, &slope_L);
        double step = -g / (dP - 1.0);
        if (g > 0) lo = fmax(lo, sh.y_return);
        else if (g < 0) hi = fmin(hi, sh.y_return);
        double next = *y0 + step;
        /* P' ~ 0 at large mu, where integration error can make it slightly
         * negative and put the Newton point a hair beyond P itself */
        double slack = 1e-3 * fabs(g) + 4.0 * DBL_EPSILON * fabs(*y0);
        int safeguarded = 0, inverted = lo >= hi;
        if (inverted && ++inversions > MAX_INVERSIONS) {
            in->noisy = 1;
            return bkf_error_set(err, BKF_ENUMERIC,
                                 "cycle at mu = %.15g, nu = %.15g: the returns at local tolerance %g are "
                                 "below the integration noise (the bracket of the cycle inverted %d times)",
                                 p->mu, p->nu, in->tol, inversions);
        }
        if (inverted) {
            /* integration noise exceeds the distance to the cycle: the
             * bracket carries no information any more */
            lo = p->b * lienard_F(p->nu);
            hi = GSL_POSINF;
        } else if (!(next >= lo - slack && next <= hi + slack) || !isfinite(next)) {
            /* Newton points the wrong way where the map is locally
             * expanding (orbits inside the cycle near the unstable
             * equilibrium): bisect, or walk outward with growing strides */
            if (isfinite(hi)) {
                next = 0.5 * (lo + hi);
            } else {
                stride = fmax(2.0 * stride, 2.0 * fabs(g));
                next = sh.y_return + stride;
            }
            step = next - *y0;
            safeguarded = 1;
        }
        double t_corr = sh.dT * step;
        int small = fabs(t_corr) <= t_goal * sh.period;
        /* what the integration error alone moves the fixed point by */
        double noise = 10.0 * in->tol * fmax(1.0, fabs(*y0)) / (1.0 - fmin(dP, 0.999999));
        /* or the step is so small that what the first-order correction
         * leaves, ~ step^2 amplified by 1/(1 - P'), is far below the goal */
        double rel_step = fabs(step) / y_scale;
        /* (not when keeping the trajectory: the stored profile is that of
         * this shot, which must itself be within y_goal of the cycle) */
        int quadratic = !keep && q_goal > 0 && rel_step * rel_step <= q_goal * (1.0 - fmin(dP, 0.999999));
        int at_noise = inverted || fabs(step) <= fmax(y_goal, noise) ||
                       fabs(step) > 0.25 * previous_step || quadratic;
        /* A stage that only has to bring y0 within y_goal of the cycle (the
         * coarse one) is done when the Newton point is: where P' ~ 0 the
         * return has landed on the cycle to |P'| |step| plus this shot's
         * integration error, so no shot needs to confirm it. */
        int landed = land && slope_L >= 0 && slope_L < 1e-3 && slope_L * fabs(step) <= y_goal;
        if (!safeguarded && small && (at_noise || landed)) {
            out->period = sh.period + t_corr;
            out->log_mult = sh.log_mult;
            out->y0 = next;
            out->xmax = sh.xmax;
            out->xmin = sh.xmin;
            out->return_slope = sh.dP;
            out->dT = sh.dT;
            out->tol = in->tol;
            *y0 = next;
            return BKF_OK;
        }
        previous_step = safeguarded ? GSL_POSINF : fabs(step);
        *y0 = next;
    }
    return bkf_error_set(err, BKF_ENUMERIC,
                         "cycle at mu = %.15g, nu = %.15g: shooting did not converge in %d Newton steps",
                         p->mu, p->nu, MAX_NEWTON);
}

int cycle_check_inputs(double mu, double nu, const bkf_cycle_options *o, bkf_error *err)
{
    if (!isfinite(mu) || mu < BKF_CYCLE_MU_MIN || mu > BKF_CYCLE_MU_MAX)
        return bkf_error_set(err, BKF_EINPUT, "mu = %.15g is outside [%g, %g]", mu, BKF_CYCLE_MU_MIN,
                             BKF_CYCLE_MU_MAX);
    int rc = bkf_model_check_nu_active(nu, err);
    if (rc != BKF_OK) return rc;
    if (!o) return BKF_OK;
    rc = bkf_model_check_tol(o->tol, err);
    if (rc != BKF_OK) return rc;
    if (o->stepper != BKF_STEPPER_AUTO && o->stepper != BKF_STEPPER_EXPLICIT &&
        o->stepper != BKF_STEPPER_IMPLICIT && o->stepper != BKF_STEPPER_EXTRAPOLATION &&
        o->stepper != BKF_STEPPER_COLLOCATION)
        return bkf_error_set(err, BKF_EINPUT,
                             "stepper must be auto, explicit, implicit, extrapolation or collocation");
    return BKF_OK;
}

/* The accepted solve b, with a the looser solve of the error estimate. */
void cycle_store_result(bkf_cycle *c, const converged *a, const converged *b, double period_err,
                        double y0, bkf_stepper_kind kind, double profile_tol,
                        const integrator *i1, const integrator *i2, const integrator *i3,
                        const integrator *i4, size_t iterations)
{
    const flow_params *p = &c->flow;
    bkf_cycle_result *r = &c->result;
    r->mu = p->mu;
    r->nu = p->nu;
    r->period = b->period;
    r->period_err = period_err;
    r->xmax = b->xmax;
    r->xmin = b->xmin;
    r->log_multiplier = b->log_mult;
    r->log_multiplier_err = fabs(a->log_mult - b->log_mult) + 8.0 * DBL_EPSILON * fabs(b->log_mult);
    r->multiplier = exp(b->log_mult);
    r->return_map_slope = b->return_slope;
    r->section_y = y0;
    r->section_slope = p->a * (y0 - p->b * lienard_F(p->nu));
    r->steps = i1->steps + i2->steps + i3->steps + i4->steps;
    r->rhs_calls = p->rhs_calls;
    r->jacobian_calls = p->jacobian_calls;
    r->newton_iterations = iterations;
    r->stepper = bkf_cycle_stepper_name(kind);
    r->model = "shooting";
    c->have_solution = 1;
    c->profile_tol = profile_tol;
    /* A profile point integrates from the nearest node, a short stretch:
     * bsimp's Jacobian and LU per step made that 18 us a point at mu = 47
     * (seeding a front on 65536 points: 1.2 s), rk8pd 4 us; only well
     * inside the stiff range does bsimp pay. */
    c->profile_stepper = p->mu <= 100 ? BKF_STEPPER_EXPLICIT : kind;
}

/* The looser local tolerance of the classic error-estimate pair (the
 * tighter is TOL_RATIO below it).  The global error of T is a modest
 * multiple of the local tolerance; the safety factor was measured over the
 * benchmark box (docs/benchmarks.md).  Looser local tolerances buy almost
 * nothing with these steppers, and near |nu| = 1 the cycle is small (radius
 * 2 sqrt(1 - nu^2)): at mu = 1e-3, nu = 0.999, a local 1e-3 let the orbit
 * drift off the weakly attracting cycle and never return to the section. */
double cycle_pair_tol(double tol, double nu, bkf_stepper_kind kind)
{
    double tol_int = fmin(0.1 * tol, 1e-5 * fmin(1.0, sqrt(1.0 - nu * nu)));
    double floor = tol_floor_of(kind);
    return tol_int / TOL_RATIO < floor ? floor * TOL_RATIO : tol_int;
}


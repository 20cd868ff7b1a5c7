/* The cycle by collocation (cycle.c): the collocation engine's cold and warm
 * starts, its answer stored as the cycle's, and the automatic choice between
 * it and shooting.  Above the flow and the shooting (cycle_flow.c,
 * cycle_shoot.c), below the solve (cycle.c) and the branch (cycle_branch.c). */
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

/* ------------------------------------------------------ collocation */

/* Up to this mu the cold guess is the Lindstedt series on a uniform mesh
 * (bkf_colloc_guess_series), above it two turns of Gauss steps
 * (bkf_colloc_guess_turn; the cycle attracts like exp(L), L = -7 at mu 1:
 * one turn lands it), or from COLLOC_RELAXATION_MU a quarter turn and one
 * (bkf_colloc_guess_relaxation). */
#define COLLOC_SERIES_MU 1.0
int cycle_colloc_canard_refused(double nu)
{
    return fabs(nu) > COLLOC_CANARD_STEEP_NU || nu < 0.0;
}
/* Beyond the series' radius (mu 1 at |nu| 0.3-0.7: its smallest term is
 * 0.4-0.5 of the radius) Newton needs 12-15 iterations, a cold solve 1.3-1.4M
 * instructions against rk8pd's 0.86-0.89M; at 0.11 (mu 0.7, nu -0.5) 7,
 * 0.48M against 0.84M.  The automatic choice shoots above this. */
#define COLLOC_SERIES_RESIDUAL_MAX 0.2
/* The uniform mesh whose pair with its bisection meets tol at the first
 * try: the fewest intervals that did (tol 1e-10) were 12 at mu 1e-3, 14
 * at 0.1, 18 at 0.3, 20 at 0.5, 24 at 1 (nu 0); at mu 1 26 at nu 0.8, 24
 * at 0.85, 20 at 0.9, 18 at 0.95, 14 at 0.99 (the cycle's sharpest near
 * |nu| 0.8, not at nu 0); they grow like tol^(-1/8) (T's error falls like
 * N^-8: at 1e-12, 24 at mu 0.1, 38 at mu 1; at 1e-6, 6-10).  Too few cost
 * the equidistributed rounds (mu 1, nu 0.85 on 22: 1069k instructions
 * against 430k on 24). */
static size_t colloc_series_intervals(double mu, double nu, double tol)
{
    double shape = 1.1 * fmin(1.0, (1.0 - fabs(nu)) / 0.15);
    double n = (16.0 + 10.0 * mu * shape) * fmax(1.0, pow(1e-10 / tol, 0.125));
    return (size_t)fmin(fmax(ceil(n), 6.0), 4000.0);
}
/* A warm start reuses the last solution within this distance in (ln mu, nu). */
#define COLLOC_WARM_LN_MU 1.0
#define COLLOC_WARM_NU 0.2

/* The local tolerance of the guess's turn for a solve at tol: 1e-8 from
 * tol 1e-10 up, falling like tol^1.5 below.  The collocation error in T is
 * far below the turn's local one (at tol 1e-10, mu 10-1e4, local 1e-8 gave
 * meshes whose pair met tol first time with the least work; 1e-10 meshes
 * 1.3-1.5 times as fine); from 1e-4 the pair's estimate failed at mu 10,
 * tol 1e-6 (outside the asymptotic range), from 1e-7 it was optimistic by
 * 26 at mu 1e4, nu 0.99 (true 6e-11).  Below 1e-10 it falls faster than
 * tol so that the estimate's floor (colloc.c, TURN_FLOOR: 1e-3 of it)
 * stays near 0.01 tol at 1e-12, the cycle tolerance Floquet asks for its
 * own 1e-10 (at 0.1 tol its lambda estimates refused at gamma 10). */
/* Below mu 20 the pair of a 1e-8 mesh missed tol 1e-10 at about 40% of
 * the points of mu 10-18 x nu 0, +-0.5, 0.9, -0.96, 0.99 (its difference
 * 5-10e-10 at mu 10, where 5e-10 passes; 1-3e-10 from mu 20), and each
 * miss cost a second turn and pair (2.0M instructions at mu 10, nu 0
 * against 1.2M): the local tolerance falls like mu / 20 there, at most to
 * its half, only where it is near tol's need (tol 1e-10 and below).  Over
 * mu 10-18 x those nus 71M instructions fell to 55M (callgrind, one cold
 * solve each), mu 20-30 unchanged. */
#define COLLOC_TURN_MU 20.0
#define COLLOC_TURN_MU_FLOOR 0.5
double cycle_colloc_turn_tol(double tol, double mu)
{
    double by_mu = fmin(1.0, fmax(COLLOC_TURN_MU_FLOOR, mu / COLLOC_TURN_MU));
    return 1e-8 * fmin(1.0, pow(tol / 1e-10, 1.5) * by_mu);
}

/* The extremes of x from the collocation nodes where bkf_colloc_extremes
 * fails: each sign change of x' between nodes is located by the shooting
 * engine's event Newton,
 * integrating from the node (x' = 0 makes x there second order in the time
 * error, which the polynomial between mesh points, of stage order m + 1,
 * would not give to tol). */
static int colloc_extremes_shot(bkf_cycle *c, bkf_error *err)
{
    flow_params *p = &c->flow;
    integrator in = {0};
    if (cycle_integrator_init(&in, p, c->profile_stepper, 1, c->profile_tol) != BKF_OK) {
        cycle_integrator_free(&in);
        return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    }
    double xmax = p->nu, xmin = p->nu;
    int rc = BKF_OK;
    for (size_t j = 0; j < c->node_count && rc == BKF_OK; j++) {
        const node *n0 = &c->nodes[j], *n1 = &c->nodes[j + 1 < c->node_count ? j + 1 : 0];
        double s0[DIM] = {n0->s[0], n0->s[1], 0, 0, 0}, s1[DIM] = {n1->s[0], n1->s[1], 0, 0, 0};
        double t1 = j + 1 < c->node_count ? n1->t : c->result.period;
        if ((cycle_flow_xdot(p, s0) > 0) == (cycle_flow_xdot(p, s1) > 0)) continue;
        double te, se[DIM];
        if (cycle_locate_event(&in, p, cycle_event_extremum, n0->t, s0, t1, s1, &te, se) != BKF_OK) {
            rc = bkf_error_set(err, BKF_ENUMERIC, "cycle at mu = %.15g, nu = %.15g: extremum not located", p->mu,
                               p->nu);
            break;
        }
        xmax = fmax(xmax, se[IX]);
        xmin = fmin(xmin, se[IX]);
    }
    c->result.xmax = xmax;
    c->result.xmin = xmin;
    c->result.steps += in.steps;
    cycle_integrator_free(&in);
    return rc;
}

/* From the collocation solution itself (bkf_colloc_extremes: Gauss steps
 * from the mesh point nearer each sign change of x', started at the zero
 * of x' on the interval's polynomial): the event Newton above, integrating
 * from the node with rk8pd or bd2x2 at 0.01 tol, was 69k of the 380k
 * instructions of a cold solve at mu 0.1, nu 0, tol 1e-10 and 14-15% of
 * one at mu 1e4, nu -0.96 (callgrind).  Where it fails, the event Newton. */
static int colloc_extremes(bkf_cycle *c, bkf_error *err)
{
    if (bkf_colloc_extremes(c->colloc, &c->result.xmax, &c->result.xmin, NULL) == BKF_OK) return BKF_OK;
    return colloc_extremes_shot(c, err);
}

/* The cycle by collocation (colloc.h) into c; a numerical failure (refusal)
 * leaves c's solution as it was, and the caller shoots.  declinable (the
 * automatic choice): a small-mu point whose series guess is poor is left
 * to shooting at once. */
int cycle_colloc_attempt(bkf_cycle *c, const bkf_cycle_options *opt, int declinable, bkf_error *err)
{
    flow_params *p = &c->flow;
    const double mu = p->mu, nu = p->nu;
    /* in the canard's neighbourhood the cyclic solve is conditioned like
     * exp(mu x the time on the repelling branch): shooting with its
     * conditioning floor answers there (up to mu 1 that factor is at most
     * e^T and the series path answers: mu 1, nu -0.96 was refused) */
    double canard = 8.0 * mu * mu * (1.0 - fabs(nu));
    if (mu > COLLOC_SERIES_MU && cycle_colloc_canard_refused(nu) && canard > 0.3 && canard < 3.0)
        return bkf_error_set(err, BKF_ENUMERIC, "collocation at mu = %.15g, nu = %.15g: canard region", mu, nu);
    if (!c->colloc && !(c->colloc = bkf_colloc_alloc())) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    int rc = BKF_OK;
    int warm = opt->warm_start && c->have_solution && fabs(log(mu / c->result.mu)) <= COLLOC_WARM_LN_MU &&
               fabs(nu - c->result.nu) <= COLLOC_WARM_NU && bkf_colloc_warm(c->colloc, mu, nu);
    bkf_colloc_result r;
    for (int cold = warm ? 0 : 1; cold < 2; cold++) {
        if (!cold) {
            rc = bkf_colloc_solve(c->colloc, opt->tol, &r, err);
            if (rc == BKF_OK || rc == BKF_ENOMEM) break;
            continue;
        }
        if (mu <= COLLOC_SERIES_MU) {
            double residual;
            rc = bkf_colloc_guess_series(c->colloc, mu, nu, 0, colloc_series_intervals(mu, nu, opt->tol), &residual,
                                         err);
            if (rc == BKF_OK && declinable && residual > COLLOC_SERIES_RESIDUAL_MAX)
                return bkf_error_set(err, BKF_ENUMERIC,
                                     "collocation at mu = %.15g, nu = %.15g: the series guess is off by %.2g: "
                                     "shooting answers",
                                     mu, nu, residual);
        } else if (mu >= COLLOC_RELAXATION_MU && canard >= 3.0) {
            /* a landing from the left slow branch through the fold, then
             * the turn that is the mesh (colloc.h) */
            rc = bkf_colloc_guess_relaxation(c->colloc, mu, nu, bkf_asym_period_leading(mu, nu),
                                             cycle_colloc_turn_tol(opt->tol, mu), err);
        } else {
            /* a turn from the section point of the guessed slope lands on
             * the cycle, another is the mesh (colloc.h) */
            double T_hint = fmax(2.0 * M_PI, bkf_asym_period_leading(mu, nu));
            rc = bkf_colloc_guess_turn(c->colloc, mu, nu, nu, cycle_section_y_of_slope(p, cycle_guess_slope(mu, nu)),
                                       T_hint, cycle_colloc_turn_tol(opt->tol, mu), err);
        }
        if (rc == BKF_OK) rc = bkf_colloc_solve(c->colloc, opt->tol, &r, err);
    }
    if (rc != BKF_OK) return rc;
    return cycle_colloc_store(c, &r, opt, err);
}

/* The collocation solution r (in c->colloc, at c->flow's parameters) as
 * c's solution: its nodes, result and extremes. */
int cycle_colloc_store(bkf_cycle *c, const bkf_colloc_result *rp, const bkf_cycle_options *opt, bkf_error *err)
{
    flow_params *p = &c->flow;
    const double mu = p->mu, nu = p->nu;
    const bkf_colloc_result r = *rp;
    int rc = BKF_OK;
    size_t n = bkf_colloc_nodes(c->colloc, NULL, NULL, NULL, 0);
    double *buf = malloc(3 * n * sizeof *buf);
    if (!buf) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    bkf_colloc_nodes(c->colloc, buf, buf + n, buf + 2 * n, n);
    c->node_count = 0;
    for (size_t j = 0; j < n && rc == BKF_OK; j++)
        rc = cycle_node_push(c, buf[j], (const double[]){buf[n + j], buf[2 * n + j]});
    free(buf);
    if (rc != BKF_OK) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    bkf_cycle_result *res = &c->result;
    res->mu = mu;
    res->nu = nu;
    res->period = r.period;
    res->period_err = r.period_err;
    res->log_multiplier = r.log_multiplier;
    res->log_multiplier_err = r.log_multiplier_err;
    res->multiplier = exp(r.log_multiplier);
    res->return_map_slope = r.return_map_slope;
    res->section_y = r.section_y;
    res->section_slope = p->a * (r.section_y - p->b * lienard_F(nu));
    res->steps = r.interval_solves;
    res->newton_iterations = r.newton_iterations;
    res->stepper = bkf_cycle_stepper_name(BKF_STEPPER_COLLOCATION);
    res->model = "shooting";
    c->profile_tol = fmax(0.01 * opt->tol, 1e-14);
    c->profile_stepper = mu <= 100 ? BKF_STEPPER_EXPLICIT : BKF_STEPPER_EXTRAPOLATION;
    c->have_solution = 1;
    rc = colloc_extremes(c, err);
    res->rhs_calls = p->rhs_calls;
    res->jacobian_calls = p->jacobian_calls;
    if (rc != BKF_OK) c->have_solution = 0;
    return rc;
}

/* The rounding floor of the series path's estimate (colloc.c's
 * round_floor on the bisected mesh): near the Hopf point, where the cycle
 * is small, it exceeds the tightest tolerances (mu 1e-3, nu 0.9999, tol
 * 1e-12), which shooting then answers. */
static double colloc_series_floor(double mu, double nu, double tol)
{
    double size = fmin(1.0, 2.0 * sqrt(1.0 - nu * nu));
    return 8.0 * DBL_EPSILON * sqrt(2.0 * (double)colloc_series_intervals(mu, nu, tol)) / size;
}
/* Where the series is beyond its radius (its smallest term above
 * COLLOC_SERIES_RESIDUAL_MAX; measured: at mu 0.8 for |nu| 0.3-0.6, at
 * 0.85 for 0.15-0.7, at 0.9 for 0.12-0.75, at 1 for 0.08-0.75) the
 * automatic choice shoots without trying it: the series and the mesh's
 * evaluation, thrown away, cost 5-11% of the shot (mu 1, nu -0.5: 912k
 * instructions against 864k).  Outside this outline the residual test in
 * colloc_attempt still declines. */
static int colloc_series_beyond_radius(double mu, double nu)
{
    double a = fabs(nu);
    return (mu >= 0.85 && a >= 0.08 + 0.5 * (1.0 - mu) && a <= 0.78) || (mu >= 0.75 && a >= 0.25 && a <= 0.65);
}

bkf_stepper_kind cycle_solve_stepper(double mu, double nu, double tol, int series_off)
{
    if (!series_off && mu <= COLLOC_SERIES_MU && tol <= COLLOC_AUTO_SERIES_TOL_MAX * (1.0 + 1e-9) &&
        colloc_series_floor(mu, nu, tol) * ACCEPT_MARGIN <= tol && !colloc_series_beyond_radius(mu, nu))
        return BKF_STEPPER_COLLOCATION;
    if (mu >= COLLOC_AUTO_MU_MIN && mu <= COLLOC_AUTO_MU_MAX && tol <= COLLOC_AUTO_TOL_MAX * (1.0 + 1e-9) &&
        mu * mu * (1.0 - fabs(nu)) >= COLLOC_AUTO_RELAXATION)
        return BKF_STEPPER_COLLOCATION;
    return cycle_solve_shooting_stepper(mu, nu, tol);
}


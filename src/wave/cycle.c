/* Limit cycle of f'' + mu (f^2 - 1) f' + f = nu by Newton shooting.
 *
 * Coordinates (see cycle.h): x' = a (y - b F(x)), y' = (nu - x)/a with
 * a = sqrt(1 + mu^2), b = mu/a.  They interpolate between the phase plane,
 * where a small-mu cycle is a circle of radius ~2, and the Lienard plane,
 * where a large-mu cycle has y = O(1) and its fast jumps are horizontal.  In
 * either limit the state stays O(1), which keeps the absolute tolerance
 * meaningful over mu in [1e-6, 1e6].
 *
 * The integrated state is (x, y, dx/dy0, dy/dy0, L): the variational column
 * with respect to the section coordinate y0 gives the Newton derivative, and
 * L = integral of the Jacobian's trace, -mu (x^2 - 1), gives the nontrivial
 * Floquet multiplier by Liouville's formula (the trivial one is 1).  L stays
 * finite where the multiplier itself underflows (large mu).
 *
 * The return to the section x = nu is located by Newton in time, each
 * iterate integrated afresh from the last step's start, so the event is as
 * accurate as the integration itself (GSL steppers have no dense output). */
#include "bkfront/cycle.h"

#include "cycle_internal.h"

#include "bkfront/asymptotics.h"
#include "bkfront/colloc.h"
#include "bkfront/continuation.h"
#include "bkfront/model.h"

#include <gsl/gsl_errno.h>
#include <gsl/gsl_math.h>
#include <gsl/gsl_odeiv2.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* What the stages of one shooting solve share: the flow, the stepper, the
 * section point y0 and its scale, the integrators and the two converged
 * solves a (looser) and b (tighter) whose difference is the estimate. */
typedef struct {
    bkf_cycle *c;
    flow_params *p;
    const bkf_cycle_options *opt;
    bkf_stepper_kind kind;
    double mu, nu;
    double y0, y_scale, q_goal, cond_floor;
    double tol_int, tol_loose, tol_floor;
    integrator coarse, fine, finer, aux;
    size_t iterations;
    converged a, b;
} shoot_state;

static int shoot_no_memory(bkf_error *err)
{
    return bkf_error_set(err, BKF_ENOMEM, "out of memory");
}

/* The coarse solve, a, at tol_loose.  In the canard region an error made
 * on the repelling slow branch grows like exp(mu x the time spent there)
 * before the orbit jumps: at mu 3.65, nu 0.99 the returns at the coarse
 * tolerance 1.4e-6 were 3e-3 off, P looked decreasing and Newton cycled
 * for 60 steps.  Such noise shows as brackets that invert; the coarse
 * solve then tightens its tolerance. */
static int shoot_coarse(shoot_state *S, bkf_error *err)
{
    if (cycle_integrator_init(&S->coarse, S->p, S->kind, 0, S->tol_loose) != BKF_OK ||
        cycle_integrator_init(&S->aux, S->p, S->kind, 1, S->tol_loose) != BKF_OK)
        return shoot_no_memory(err);
    int rc;
    for (double y_start = S->y0;;) {
        rc = cycle_newton_at(S->c, &S->coarse, &S->aux, &S->y0, 1e-3, 1e-4 * S->y_scale, S->y_scale,
                             0.0, 0, 1, &S->iterations, &S->a, err);
        if (rc == BKF_OK || !S->coarse.noisy || S->tol_loose <= S->tol_int) break;
        S->tol_loose = fmax(S->tol_int, 1e-2 * S->tol_loose);
        size_t coarse_steps = S->coarse.steps, aux_steps = S->aux.steps;
        cycle_integrator_free(&S->coarse);
        cycle_integrator_free(&S->aux);
        if (cycle_integrator_init(&S->coarse, S->p, S->kind, 0, S->tol_loose) != BKF_OK ||
            cycle_integrator_init(&S->aux, S->p, S->kind, 1, S->tol_loose) != BKF_OK)
            return shoot_no_memory(err);
        S->coarse.steps = coarse_steps;
        S->aux.steps = aux_steps;
        S->y0 = y_start;
    }
    return rc;
}

/* Fast path for loose tolerances: when the coarse solve is within a
 * factor FAST_SPAN of the integration tolerance asked, it serves as the
 * looser of the two solves of the error estimate, and one Newton solve
 * at tol_b (usually a single shot from the converged coarse point) is
 * all the extra work.  Its estimate |T_a - T_b| is of the coarse error,
 * a larger one than the classic pair gives; if it does not meet tol,
 * the classic pair (shoot_pair) runs: *stored 0.
 *
 * tol_b is only a factor TOL_RATIO below the coarse tolerance, not the
 * tol/10 the classic pair would use: the achieved error is far below the
 * local tolerance (1e-3 of it for rk8pd, ~1e-2 for bsimp, measured), so
 * at tol 1e-6 the answer needs no 1e-7 shot; the estimate stays the
 * coarse solve's, which bounds b's.  Not for rk8pd near its stability
 * limit (mu > EXPLICIT_MU_MAX/3): there its steps are set by stability, not by
 * the tolerance, two tolerances a factor 10 apart take nearly the same
 * steps and their difference missed the error (mu 30, nu 0: true/estimated
 * 14 with a factor 10); there the pair is a factor 100 apart, which makes
 * the tighter solve's steps tolerance-limited again. */
static int shoot_fast(shoot_state *S, int *stored, bkf_error *err)
{
    const bkf_cycle_options *opt = S->opt;
    *stored = 0;
    if (!(S->tol_loose <= 1.01 * FAST_SPAN * S->tol_int)) return BKF_OK;
    int step_set_by_tol = S->kind != BKF_STEPPER_EXPLICIT || S->mu <= EXPLICIT_MU_MAX / 3.0;
    double tol_b = S->tol_loose / (step_set_by_tol ? TOL_RATIO : TOL_RATIO * TOL_RATIO);
    /* (not where the estimate's floor alone would refuse it: at tol
     * 1e-6 the fast pair was solved and thrown away, bd2x2 at mu
     * 30-1e4 took twice as long as at 1e-8) */
    if (!(tol_b >= S->tol_floor &&
          ACCEPT_MARGIN * cycle_error_per_tol(S->kind) * tol_b / cycle_size(S->nu) <= opt->tol))
        return BKF_OK;
    size_t aux_steps = S->aux.steps;
    cycle_integrator_free(&S->aux);
    if (cycle_integrator_init(&S->fine, S->p, S->kind, 0, tol_b) != BKF_OK ||
        cycle_integrator_init(&S->aux, S->p, S->kind, 1, tol_b) != BKF_OK)
        return shoot_no_memory(err);
    tighten_turn(&S->fine);
    S->aux.steps = aux_steps;
    int rc = cycle_newton_at(S->c, &S->fine, &S->aux, &S->y0, 0.1 * sqrt(opt->tol),
                             0.1 * opt->tol * S->y_scale, S->y_scale, S->q_goal, 1, 0,
                             &S->iterations, &S->b, err);
    if (rc != BKF_OK) return rc;
    double period_err = cycle_period_error(&S->a, &S->b, S->p, S->kind, S->cond_floor);
    if (ACCEPT_MARGIN * period_err > opt->tol * S->b.period) {
        /* The coarse Newton stops at loose goals (t_goal 1e-3), so
         * |T_a - T_b| can be its iteration error rather than its
         * integration error (mu 10, nu 0.9999; mu 1e3, nu -0.999 at
         * tol 1e-6: 2-3e-6).  One coarse shot from b's converged
         * point leaves only the latter, for one shot instead of the
         * classic pair's two or more. */
        converged a2;
        double y_b = S->y0;
        rc = cycle_newton_at(S->c, &S->coarse, &S->aux, &y_b, 0.1 * sqrt(opt->tol),
                             0.1 * opt->tol * S->y_scale, S->y_scale, S->q_goal, 0, 0,
                             &S->iterations, &a2, err);
        if (rc != BKF_OK) return rc;
        double err2 = cycle_period_error(&a2, &S->b, S->p, S->kind, S->cond_floor);
        if (ACCEPT_MARGIN * err2 <= opt->tol * S->b.period) {
            S->a = a2;
            period_err = err2;
        }
    }
    if (ACCEPT_MARGIN * period_err <= opt->tol * S->b.period) {
        cycle_store_result(S->c, &S->a, &S->b, period_err, S->y0, S->kind, tol_b, &S->coarse,
                           &S->fine, &S->finer, &S->aux, S->iterations);
        *stored = 1;
        return BKF_OK;
    }
    cycle_integrator_free(&S->fine);
    return BKF_OK;
}

/* The classic pair: a at tol_int, b at tol_int / TOL_RATIO, tightened
 * until their difference meets tol or the floor is reached.
 *
 * Every T solved at or below the looser tolerance of the pair in hand
 * is a sample of the answer at that accuracy: at the tolerance floor the
 * retries repeat the same pair from another start, and accepting the
 * first pair that happens to agree ("retry until lucky") reported
 * 2e-14 at mu 10, nu 0.9999, tol 1e-14 against a true 2e-13.  The
 * spread of all such samples is part of the estimate. */
static int shoot_pair(shoot_state *S, bkf_error *err)
{
    const bkf_cycle_options *opt = S->opt;
    struct {
        double tol, period;
    } seen[8];
    size_t n_seen = 0;
    int rc = BKF_OK;
    for (int attempt = 0; attempt < 4; attempt++) {
        cycle_integrator_free(&S->fine);
        cycle_integrator_free(&S->finer);
        size_t aux_steps = S->aux.steps;
        cycle_integrator_free(&S->aux);
        if (cycle_integrator_init(&S->fine, S->p, S->kind, 0, S->tol_int) != BKF_OK ||
            cycle_integrator_init(&S->finer, S->p, S->kind, 0, S->tol_int / TOL_RATIO) != BKF_OK ||
            cycle_integrator_init(&S->aux, S->p, S->kind, 1, S->tol_int / TOL_RATIO) != BKF_OK)
            return shoot_no_memory(err);
        S->aux.steps = aux_steps;
        rc = cycle_newton_at(S->c, &S->fine, &S->aux, &S->y0, 0.1 * sqrt(opt->tol),
                             opt->tol * S->y_scale, S->y_scale, S->q_goal, 0, 0, &S->iterations,
                             &S->a, err);
        if (rc != BKF_OK) return rc;
        rc = cycle_newton_at(S->c, &S->finer, &S->aux, &S->y0, 0.1 * sqrt(opt->tol),
                             0.1 * opt->tol * S->y_scale, S->y_scale, S->q_goal, 1, 0,
                             &S->iterations, &S->b, err);
        if (rc != BKF_OK) return rc;
        const converged *a = &S->a, *b = &S->b;
        double period_err = cycle_period_error(a, b, S->p, S->kind, S->cond_floor);
        seen[n_seen].tol = a->tol;
        seen[n_seen++].period = a->period;
        seen[n_seen].tol = b->tol;
        seen[n_seen++].period = b->period;
        for (size_t i = 0; i < n_seen; i++)
            if (seen[i].tol <= a->tol * (1.0 + 1e-9))
                period_err = fmax(period_err, fabs(seen[i].period - b->period));
        period_err = cycle_capped_floor(period_err, &S->fine, b->period);
        if (ACCEPT_MARGIN * period_err <= opt->tol * b->period || attempt == 3 ||
            /* (tol_floor * TOL_RATIO / TOL_RATIO may round above tol_floor) */
            S->tol_int / TOL_RATIO <= S->tol_floor * (1.0 + 1e-9)) {
            if (ACCEPT_MARGIN * period_err > opt->tol * b->period)
                return bkf_error_set(err, BKF_ETOL,
                                     "cycle at mu = %.15g, nu = %.15g: estimated relative error %.2g of T, "
                                     "times the safety factor %g, exceeds tol = %g",
                                     S->mu, S->nu, period_err / b->period, ACCEPT_MARGIN, opt->tol);
            cycle_store_result(S->c, a, b, period_err, S->y0, S->kind, S->tol_int / TOL_RATIO,
                               &S->coarse, &S->fine, &S->finer, &S->aux, S->iterations);
            return BKF_OK;
        }
        S->tol_int = fmax(S->tol_int * fmax(0.01, 0.3 * opt->tol * b->period / (ACCEPT_MARGIN * period_err)),
                          S->tol_floor * TOL_RATIO);
    }
    return rc;
}

static int cycle_solve_body(bkf_cycle *c, double mu, double nu, const bkf_cycle_options *options,
                            bkf_error *err)
{
    if (!c) return bkf_error_set(err, BKF_EINPUT, "cycle object is NULL");
    bkf_cycle_options opt = options ? *options : bkf_cycle_options_default();
    int rc = cycle_check_inputs(mu, nu, &opt, err);
    if (rc != BKF_OK) return rc;

    flow_params previous = c->flow;
    double warm_slope = c->have_solution ? c->result.section_slope : 0.0;
    cycle_flow_set(&c->flow, mu, nu);
    flow_params *p = &c->flow;
    p->rhs_calls = p->jacobian_calls = 0;
    bkf_stepper_kind kind = opt.stepper;
    if (kind == BKF_STEPPER_AUTO) kind = cycle_solve_stepper(mu, nu, opt.tol, c->series_off);
    if (kind == BKF_STEPPER_COLLOCATION) {
        /* c->result is overwritten only on success */
        bkf_cycle_result kept = c->result;
        int had = c->have_solution;
        rc = cycle_colloc_attempt(c, &opt, opt.stepper == BKF_STEPPER_AUTO, err);
        if (rc == BKF_OK) return BKF_OK;
        c->result = kept;
        c->have_solution = had;
        if (rc == BKF_ENOMEM) {
            if (had) c->flow = previous;
            return rc;
        }
        kind = cycle_solve_shooting_stepper(mu, nu, opt.tol);
        p->rhs_calls = p->jacobian_calls = 0;
    }

    /* (not from a collocation solution: its section point differs from
     * shooting's within tol, and a list's row would then differ from the
     * same point solved alone, as `period --mu 0.5,5` did at mu 5 in the
     * 16th digit once mu 0.5 was collocation's) */
    int warm_shot = opt.warm_start && c->have_solution && strcmp(c->result.stepper, "colloc") != 0;
    double slope = c->warm_slope > 0 ? c->warm_slope : warm_shot ? warm_slope : cycle_guess_slope(mu, nu);
    c->warm_slope = 0.0;
    shoot_state S = {.c = c, .p = p, .opt = &opt, .kind = kind, .mu = mu, .nu = nu};
    S.y0 = cycle_section_y_of_slope(p, slope);
    S.y_scale = fmax(fabs(S.y0), 1e-3);

    S.tol_int = cycle_pair_tol(opt.tol, nu, kind);
    S.tol_floor = tol_floor_of(kind);
    /* bd2x2's coarse stage lands y0 on the cycle for the tight solves,
     * whose first shot then needs no confirming one if its step is below
     * sqrt(q_goal) (see newton_at): at local tol 1e-5 the landing was
     * 1-3e-6 off at mu 1e3-1e4, just too far at tol 1e-10, and cost one
     * more tight shot than a landing at 1e-6 does.  (Not for rk8pd: inside
     * the canard at mu 3.65 the tighter landing changed which relaxed branch
     * points were accepted, and one's estimate flattered by 5.) */
    double land_tol = kind == BKF_STEPPER_EXTRAPOLATION ? fmin(0.1 * sqrt(opt.tol), 1e-5) : 1e-5;
    S.tol_loose = fmax(S.tol_int, land_tol * fmin(1.0, sqrt(1.0 - nu * nu)));
    /* a Newton step whose square (relative, amplified by 1/(1 - P')) is
     * below q_goal needs no confirming shot: the first-order correction
     * leaves an error of that order */
    S.q_goal = 1e-2 * opt.tol;

    int stored = 0;
    rc = shoot_coarse(&S, err);
    if (rc == BKF_OK)
        rc = cycle_conditioning_floor(p, kind, S.tol_int, S.y0, &S.cond_floor, &S.coarse.steps,
                                      err);
    /* Every estimate of a pair is at least the rounding floor
     * (cycle_period_error), which no tighter local tolerance lowers: where
     * it alone, times the safety factor, exceeds tol at twice the coarse
     * T (the pair's T is the coarse one's to t_goal 1e-3), no pair can
     * meet tol.  They were solved and thrown away: in the canard explosion
     * at nu 0.9999 (mu 35.366) the floor is 2-1e11 times tol, and a branch
     * stuck there spent 4 of its 7 s on such pairs. */
    if (rc == BKF_OK && ACCEPT_MARGIN * S.cond_floor > 2.0 * opt.tol * S.a.period)
        rc = bkf_error_set(err, BKF_ETOL,
                           "cycle at mu = %.15g, nu = %.15g: the rounding floor %.2g of T's estimated "
                           "relative error, times the safety factor %g, exceeds tol = %g",
                           mu, nu, S.cond_floor / S.a.period, ACCEPT_MARGIN, opt.tol);
    if (rc == BKF_OK) rc = shoot_fast(&S, &stored, err);
    if (rc == BKF_OK && !stored) rc = shoot_pair(&S, err);
    cycle_integrator_free(&S.coarse);
    cycle_integrator_free(&S.fine);
    cycle_integrator_free(&S.finer);
    cycle_integrator_free(&S.aux);
    if (rc != BKF_OK) {
        /* keep the previous solution usable: restore its flow */
        if (c->have_solution) c->flow = previous;
    }
    return rc;
}

int bkf_cycle_solve(bkf_cycle *c, double mu, double nu, const bkf_cycle_options *options,
                    bkf_error *err)
{
    if (!c) return bkf_error_set(err, BKF_EINPUT, "cycle object is NULL");
    /* Both engines write the profile's nodes before they know whether the
     * solve meets tol; a failure keeps the previous solution, so its nodes
     * (and their tolerance and stepper) are set aside and put back. */
    node *kept_nodes = c->nodes;
    size_t kept_count = c->node_count, kept_capacity = c->node_capacity;
    double kept_tol = c->profile_tol;
    bkf_stepper_kind kept_stepper = c->profile_stepper;
    c->nodes = NULL;
    c->node_count = c->node_capacity = 0;
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    int rc = cycle_solve_body(c, mu, nu, options, err);
    /* bd2x2's estimate floor is 16 times bsimp's (BD_ERROR_PER_TOL), so at
     * the tightest tolerances it refuses where bsimp answers (mu 47.07,
     * nu -0.96, tol 1e-12: estimate 7.2e-13): the automatic choice then
     * falls back to bsimp, never answering less than before bd2x2. */
    bkf_cycle_options o = options ? *options : bkf_cycle_options_default();
    if (bkf_status_is_numerical(rc) && o.stepper == BKF_STEPPER_AUTO &&
        cycle_solve_shooting_stepper(mu, nu, o.tol) == BKF_STEPPER_EXTRAPOLATION) {
        /* up to EXPLICIT_MU_MAX the engine that answered before bd2x2 took
         * over there: rk8pd; so in the canard's neighbourhood, where bsimp
         * flattered at tol 1e-12 (nu 0.9999, mu 40-88: up to 10.8, answers
         * outside tol) and rk8pd, honest there, took less time */
        o.stepper = mu <= EXPLICIT_MU_MAX || cycle_canard_neighbourhood(mu, nu) ? BKF_STEPPER_EXPLICIT
                                                                          : BKF_STEPPER_IMPLICIT;
        rc = cycle_solve_body(c, mu, nu, &o, err);
    }
    bkf_gsl_handler_pop(handler);
    node *dropped = rc == BKF_OK ? kept_nodes : c->nodes;
    if (rc != BKF_OK) {
        c->nodes = kept_nodes;
        c->node_count = kept_count;
        c->node_capacity = kept_capacity;
        c->profile_tol = kept_tol;
        c->profile_stepper = kept_stepper;
    }
    free(dropped);
    return rc;
}

int bkf_cycle_period(double mu, double nu, const bkf_cycle_options *options,
                     bkf_cycle_result *result, bkf_error *err)
{
    if (!result) return bkf_error_set(err, BKF_EINPUT, "result pointer is NULL");
    bkf_cycle *c = bkf_cycle_alloc();
    if (!c) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    int rc = bkf_cycle_solve(c, mu, nu, options, err);
    if (rc == BKF_OK) *result = c->result;
    bkf_cycle_free(c);
    return rc;
}

/* ------------------------------------------------------ model choice */

const char *bkf_cycle_method_name(bkf_cycle_method method)
{
    switch (method) {
    case BKF_METHOD_AUTO: return "auto";
    case BKF_METHOD_ASYMPTOTIC: return "asymptotic";
    case BKF_METHOD_LEADING: return "leading";
    case BKF_METHOD_SHOOTING: return "shooting";
    }
    return NULL;
}

int bkf_cycle_estimate(bkf_cycle *c, double mu, double nu, const bkf_cycle_options *options,
                       bkf_cycle_method method, bkf_cycle_result *out, bkf_error *err)
{
    if (!out) return bkf_error_set(err, BKF_EINPUT, "result pointer is NULL");
    if (!bkf_cycle_method_name(method))
        return bkf_error_set(err, BKF_EINPUT, "method must be auto, asymptotic, leading or shooting");
    bkf_cycle_options opt = options ? *options : bkf_cycle_options_default();
    int rc = cycle_check_inputs(mu, nu, &opt, err);
    if (rc != BKF_OK) return rc;
    if (method != BKF_METHOD_SHOOTING) {
        double T = NAN, bound = INFINITY;
        int f = -1;
        if (method == BKF_METHOD_LEADING) {
            bound = bkf_asym_error_bound(BKF_ASYM_LEADING, mu, nu);
            T = bkf_asym_period_leading(mu, nu);
            f = BKF_ASYM_LEADING;
        } else {
            f = bkf_asym_choose(mu, nu, opt.tol, method == BKF_METHOD_AUTO, &T, &bound);
            if (f < 0 && method == BKF_METHOD_ASYMPTOTIC) {
                /* report the better of the two bounds in the refusal */
                bound = fmin(bkf_asym_error_bound(BKF_ASYM_LARGE, mu, nu),
                             bkf_asym_error_bound(BKF_ASYM_SMALL, mu, nu));
            }
        }
        if (f >= 0 && bound <= opt.tol) {
            memset(out, 0, sizeof *out);
            out->mu = mu;
            out->nu = nu;
            out->period = T;
            out->period_err = bound * T;
            out->xmax = out->xmin = out->multiplier = out->log_multiplier = NAN;
            out->log_multiplier_err = out->return_map_slope = NAN;
            out->section_y = out->section_slope = NAN;
            out->stepper = "none";
            out->model = f == BKF_ASYM_LEADING ? "leading" : "asymptotic";
            return BKF_OK;
        }
        if (method != BKF_METHOD_AUTO)
            return bkf_error_set(err, BKF_ETOL,
                                 "%s formula at mu = %.15g, nu = %.15g: error bound %.2g exceeds tol = %g "
                                 "(outside its validity; use shooting)",
                                 method == BKF_METHOD_LEADING ? "leading" : "asymptotic", mu, nu,
                                 bound, opt.tol);
    }
    if (!c) return bkf_error_set(err, BKF_EINPUT, "cycle object is NULL (needed for shooting)");
    rc = bkf_cycle_solve(c, mu, nu, &opt, err);
    if (rc == BKF_OK) *out = c->result;
    return rc;
}

/* ------------------------------------------------------------- profile */

/* Past mu 100 the profile's stepper is the solve's stiff one
 * (cycle_store_result): from the nearest node to a lone point it takes a
 * few steps where rk8pd would take its stability-limited ones (about 140 a
 * unit of mu per period).  Among dense points it steps from each to the
 * next, and what a point costs depends on which stiff stepper it is:
 * - bsimp (GSL's, a Jacobian and an LU a step) about 27 us a point at any
 *   mu: rk8pd is as fast from about 20 points a unit of mu on (mu 300 on
 *   6000 points: 0.185 s against 0.165; mu 3000 on 60000: 1.72 against
 *   1.65) and far faster above at moderate mu (mu 120.8 on 24000, a
 *   spectrum's Radau mesh: 0.032 s against 0.66; mu 300 on 30000: 0.087
 *   against 0.84);
 * - bd2x2 (the same method written for this system, the automatic choice
 *   past mu 100) about 1 us a point at any mu, while rk8pd's cost a point
 *   grows with mu (its step-size control restarts at each point below its
 *   stability limit: about 28 us a point at mu 1000 on 24000 to 65536
 *   points, 30 at mu 3000): rk8pd wins only from about 2 mu^2 points on
 *   (points a unit of mu where the two cost the same: 250 at mu 100, 300 at
 *   150, 320 at 200, 500 at 300, 900 at 500, 1000 at 1000; at mu 1000 on
 *   65536 points 0.068 s against 1.83).
 * Measured 2026-11-29 (CPU, best of 3, points spread over the cycle's
 * node mesh, nu -0.5 and -0.96, tol 1e-10).  rk8pd's values within 1e-10 of
 * the stiff stepper's (tests/wave/test_cycle_profile_dense.c). */
#define PROFILE_DENSE_PER_MU 20.0
#define PROFILE_DENSE_PER_MU2_BD 2.0

/* The stepper for `count` sorted points over a period: rk8pd from the
 * count where it costs less than the stiff stepper `stiff`. */
static bkf_stepper_kind profile_stepper_for(bkf_stepper_kind stiff, double mu, size_t count)
{
    double dense = stiff == BKF_STEPPER_EXTRAPOLATION ? PROFILE_DENSE_PER_MU2_BD * mu * mu
                                                      : PROFILE_DENSE_PER_MU * mu;
    return (double)count >= dense ? BKF_STEPPER_EXPLICIT : stiff;
}

/* One integrator for all the points, each continued from the previous one
 * unless a stored node lies between them (a restart there keeps the error
 * that of one short stretch, as for a single point). */
static int cycle_sample_body(bkf_cycle *c, const double *z, size_t count, double *f, double *fprime,
                             bkf_error *err)
{
    if (!c || !c->have_solution)
        return bkf_error_set(err, BKF_EINPUT, "profile requested before a successful solve");
    double T = c->result.period;
    for (size_t i = 0; i < count; i++)
        if (!(z[i] >= 0.0 && z[i] <= T) || (i && z[i] < z[i - 1]))
            return bkf_error_set(err, BKF_EINPUT, "sample points must increase within [0, T = %.15g]", T);
    int rc = BKF_OK;
    bkf_stepper_kind first = profile_stepper_for(c->profile_stepper, c->flow.mu, count);
    for (int attempt = 0; attempt < 2; attempt++) {
        bkf_stepper_kind kind = attempt ? BKF_STEPPER_IMPLICIT : first;
        if (attempt && kind == first) break;
        integrator in = {0};
        if (cycle_integrator_init(&in, &c->flow, kind, 1, c->profile_tol) != BKF_OK) {
            cycle_integrator_free(&in);
            return bkf_error_set(err, BKF_ENOMEM, "out of memory");
        }
        double s[DIM] = {0}, t = -1.0;
        size_t lo = 0;
        rc = BKF_OK;
        for (size_t i = 0; i < count && rc == BKF_OK; i++) {
            while (lo + 1 < c->node_count && c->nodes[lo + 1].t <= z[i]) lo++;
            if (t < c->nodes[lo].t) {
                t = c->nodes[lo].t;
                double s0[DIM] = {c->nodes[lo].s[0], c->nodes[lo].s[1], 0.0, 0.0, 0.0};
                memcpy(s, s0, sizeof s);
            }
            rc = cycle_integrator_to(&in, t, s, z[i]);
            t = z[i];
            if (f) f[i] = s[IX];
            if (fprime) fprime[i] = cycle_flow_xdot(&c->flow, s);
        }
        cycle_integrator_free(&in);
        if (rc == BKF_OK) break;
    }
    if (rc != BKF_OK) return bkf_error_set(err, BKF_ENUMERIC, "profile integration failed");
    return BKF_OK;
}

int bkf_cycle_profile_sample(bkf_cycle *c, const double *z, size_t count, double *f, double *fprime,
                             bkf_error *err)
{
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    int rc = cycle_sample_body(c, z, count, f, fprime, err);
    bkf_gsl_handler_pop(handler);
    return rc;
}

typedef struct {
    double z; /* within [0, T] */
    size_t at;
} profile_point;

static int by_profile_z(const void *pa, const void *pb)
{
    const profile_point *a = pa, *b = pb;
    return (a->z > b->z) - (a->z < b->z);
}

int bkf_cycle_profile_points(bkf_cycle *c, const double *z, size_t count, double *f, double *fprime,
                             bkf_error *err)
{
    if (!c || !c->have_solution)
        return bkf_error_set(err, BKF_EINPUT, "profile requested before a successful solve");
    double T = c->result.period;
    for (size_t i = 0; i < count; i++)
        if (!isfinite(z[i])) return bkf_error_set(err, BKF_EINPUT, "z[%zu] must be finite", i);
    size_t cap = count ? count : 1;
    profile_point *pt = malloc(cap * sizeof *pt);
    double *zs = malloc(cap * sizeof *zs), *fs = malloc(cap * sizeof *fs), *fps = malloc(cap * sizeof *fps);
    int rc = BKF_OK;
    if (!pt || !zs || !fs || !fps) {
        rc = bkf_error_set(err, BKF_ENOMEM, "out of memory");
        goto done;
    }
    for (size_t i = 0; i < count; i++) {
        double zr = fmod(z[i], T); /* as bkf_cycle_profile wraps it */
        if (zr < 0) zr += T;
        pt[i] = (profile_point){fmin(zr, T), i};
    }
    qsort(pt, count, sizeof *pt, by_profile_z);
    for (size_t k = 0; k < count; k++) zs[k] = pt[k].z;
    rc = bkf_cycle_profile_sample(c, zs, count, fs, fps, err);
    for (size_t k = 0; rc == BKF_OK && k < count; k++) {
        if (f) f[pt[k].at] = fs[k];
        if (fprime) fprime[pt[k].at] = fps[k];
    }
done:
    free(pt);
    free(zs);
    free(fs);
    free(fps);
    return rc;
}

size_t bkf_cycle_mesh(const bkf_cycle *c, double *z, size_t capacity)
{
    if (!c || !c->have_solution) return 0;
    for (size_t i = 0; i < c->node_count && i < capacity; i++) z[i] = c->nodes[i].t;
    return c->node_count;
}

int bkf_cycle_profile(bkf_cycle *c, double z, double *f, double *fprime, bkf_error *err)
{
    if (!c || !c->have_solution)
        return bkf_error_set(err, BKF_EINPUT, "profile requested before a successful solve");
    if (!isfinite(z)) return bkf_error_set(err, BKF_EINPUT, "z must be finite");
    double T = c->result.period;
    double zr = fmod(z, T);
    if (zr < 0) zr += T;
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    int rc = cycle_sample_body(c, &zr, 1, f, fprime, err);
    if (rc == BKF_ENUMERIC) rc = bkf_error_set(err, BKF_ENUMERIC, "profile integration failed at z = %.15g", z);
    bkf_gsl_handler_pop(handler);
    return rc;
}


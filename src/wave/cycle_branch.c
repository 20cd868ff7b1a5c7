/* The cycle's branches (cycle.c): T followed along mu or nu by
 * pseudo-arclength continuation of the shooting problem, and by collocation
 * rows over the canard explosion.  Above the solve (cycle.c) and everything
 * below it; nothing calls back. */
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

/* -------------------------------------------------------------- branch */

/* Continuation unknowns u = (ln w0, q): w0 = f'(0) > 0 on the section, q =
 * ln mu or nu.  ln w0 is free of the coordinate scaling (a, b change with
 * mu) and stays O(1) from w0 ~ 2 at small mu to w0 ~ mu at large mu. */
typedef struct {
    bkf_cycle_param along;
    double fixed;
    bkf_cycle_options options;
    bkf_cycle *cycle;
    bkf_cycle_visit visit;
    void *visit_data;
    int visit_status;
    bkf_error *err;
    double from, to, q_from, q_to;
    /* the last accepted point and its tangent, for the amplitude stretches */
    double last_u[2], last_t[2];
    int have_last, skip_visit, steep, landed;
    /* a shooting row outside the collocation rows' domain was seen, and
     * one back inside it hands the branch to them (branch_colloc) */
    int left_colloc, to_colloc;
    int mirror_shots; /* every shot is the mirror image's (branch_mirrors) */
    size_t rows;
    /* rows in a row that missed tol (relaxed or refused), and whether they
     * reached BRANCH_MISSED_MAX: a branch creeping inside an explosion it
     * cannot cross (branch_hop) */
    size_t missed;
    int stuck;
    /* The last shot with derivatives: the continuation evaluates its
     * tangent, and the amplitude walk its last root, at the point it then
     * accepts, so that shot is the looser solve of the point's estimate. */
    struct {
        double u[2], y0;
        shot sh;
        flow_params flow; /* the mirror's where the shots are (mirror_shots) */
        integrator in;    /* its tolerance and turn-limit count (no stepper) */
        int valid;
    } last;
    /* work of every shot since the last visited row, reported with it */
    size_t work_rhs, work_jac, work_steps, work_shots;
} branch_ctx;

static void branch_params(const branch_ctx *b, double q, double *mu, double *nu)
{
    *mu = b->along == BKF_CYCLE_ALONG_MU ? exp(q) : b->fixed;
    *nu = b->along == BKF_CYCLE_ALONG_MU ? b->fixed : q;
}

/* The corrector's integration tolerance.  Its shots need only bring the
 * point within one first-order step of the cycle (co.newton_tol = 0.1
 * sqrt(tol) in ln w0), which each row's estimate then takes at the pair's
 * tolerances (branch_estimate), so they integrate 100 times above that
 * (where P' ~ 0 their error moves the fixed point by as much).  In the
 * canard's neighbourhood (8 mu^2 (1 - |nu|) in [1/4, 4], twice that of the
 * conditioning floor) an error on the repelling slow branch grows like
 * exp(mu x the time there), G at a loose tolerance is noise, and the
 * amplitude walk needs its sign: there the shots are at the looser
 * tolerance of the pair, whose last one is then the estimate's own.  So
 * are rk8pd's: its steps grow only like tol^(-1/8), and a loose corrector
 * saved less than the estimate's extra shot cost (mu 1, along nu: 1.39
 * cold solves a row against 1.2). */
static int branch_near_canard(double mu, double nu)
{
    double x = 8.0 * mu * mu * (1.0 - fabs(nu));
    return mu >= 1.0 && x >= 0.25 && x <= 4.0;
}

static double branch_tol(double tol, double mu, double nu, bkf_stepper_kind kind)
{
    double tight = cycle_pair_tol(tol, nu, kind);
    if (branch_near_canard(mu, nu) || kind == BKF_STEPPER_EXPLICIT) return tight;
    return fmax(tight, 1e-3 * sqrt(tol) * fmin(1.0, sqrt(1.0 - nu * nu)));
}

/* Shots for nu < 0 are those of the mirror image x -> -x, at -nu (same
 * T): there the section x = nu lies where the jump leaves the left knee,
 * f'(0) is tiny (4e-3 at mu 848, nu -0.999) and ln f'(0) carries the
 * return's absolute error magnified 1/f'(0) (G noisy at 1e-8, above the
 * corrector's tolerance); at -nu it is crossed mid-jump.  Along nu only from
 * BRANCH_NU_MIRROR_MU: below it the direct shots pass 0 -> -0.999 (mu 10:
 * 107 rows, none relaxed, where the mirror's 0 -> 0.999 relaxes 10 in the
 * canard); from mu 100 the canard lies beyond the box's |nu| <= 0.9999, and
 * the direct shots' steps shrink towards the knee (0 -> -0.999: 191 rows at
 * mu 100, 227 at 300, and at 1e3 a creep of 1e-12 steps near -0.9982 that
 * spent 10000 rows) while the mirror's take 28-33 rows at every mu from 300
 * to 1e4.  A branch's shots are all the mirror's or none (G's even
 * extension is kinked at nu = 0, where pseudo-arclength from 0 towards
 * -0.999 at mu 100 turned back); one along nu that crosses 0 is split there
 * (bkf_cycle_branch). */
#define BRANCH_NU_MIRROR_MU 100.0
static int branch_mirrors(bkf_cycle_param along, double from, double to, double fixed)
{
    if (along == BKF_CYCLE_ALONG_MU) return fixed < 0;
    return fixed >= BRANCH_NU_MIRROR_MU && from <= 0 && to <= 0 && (from < 0 || to < 0);
}

/* G = ln w(P) - ln w0 and, if dg, its derivatives (d/d ln w0, d/dq) from
 * one shot at (w0, q) that carries the variational column and the
 * parameter sensitivity.  At fixed w0 the start (nu, y0 = w0/a + b F(nu))
 * moves with q, and so do the section and the scaling of w = a (y - b F(nu));
 * y' = 0 on the section, so the moving return time leaves dy/dq = py. */
static int branch_shot(branch_ctx *b, double ln_w0, double q, double *g, double *dg,
                       double *ln_t, double *dln_t, bkf_error *err)
{
    double mu, nu;
    branch_params(b, q, &mu, &nu);
    if (cycle_check_inputs(mu, nu, NULL, err) != BKF_OK)
        return bkf_error_set(err, BKF_ENUMERIC, "branch left the valid range at mu = %.15g, nu = %.15g", mu,
                             nu);
    double mirror = b->mirror_shots ? -1.0 : 1.0;
    nu *= mirror;
    flow_params p = {0};
    cycle_flow_set(&p, mu, nu);
    int along_mu = b->along == BKF_CYCLE_ALONG_MU;
    p.sens = dg ? (along_mu ? 1 : 2) : 0;
    bkf_stepper_kind kind = b->options.stepper;
    if (kind == BKF_STEPPER_AUTO || kind == BKF_STEPPER_COLLOCATION) kind = cycle_shooting_stepper(mu, b->options.tol);
    integrator in = {0}, aux = {0};
    double tol = branch_tol(b->options.tol, mu, nu, kind);
    int rc = BKF_ENOMEM;
    b->last.valid = 0;
    if (cycle_integrator_init(&in, &p, kind, 0, tol) == BKF_OK &&
        cycle_integrator_init(&aux, &p, kind, 1, tol) == BKF_OK) {
        double w0 = exp(ln_w0), Fn = lienard_F(nu), a2 = p.a * p.a;
        double p0[2] = {along_mu ? 0.0 : 1.0,
                        along_mu ? mu * (-w0 * p.b / a2 + Fn / (a2 * p.a)) : p.b * (nu * nu - 1.0)};
        shot sh = {0};
        double y0 = cycle_section_y_of_slope(&p, w0);
        rc = cycle_shoot(&in, &aux, &p, y0, p0, NULL, &sh, err);
        b->work_shots++;
        if (rc == BKF_OK && dg) {
            b->last.u[0] = ln_w0;
            b->last.u[1] = q;
            b->last.y0 = y0;
            b->last.sh = sh;
            b->last.flow = p;
            b->last.in = (integrator){.tol = tol, .capped = in.capped};
            b->last.valid = 1;
        }
        if (rc == BKF_OK) {
            double w_return = p.a * (sh.y_return - p.b * Fn);
            if (!(w_return > 0)) rc = bkf_error_set(err, BKF_ENUMERIC, "return below the section");
            else {
                *g = log(w_return) - ln_w0;
                if (dg) {
                    double dw = along_mu ? mu * p.b * (sh.y_return - p.b * Fn) +
                                               p.a * (sh.py - mu * Fn / (a2 * p.a))
                                         : p.a * (sh.py - p.b * (nu * nu - 1.0));
                    dg[0] = sh.dP * w0 / w_return - 1.0;
                    dg[1] = (along_mu ? 1.0 : mirror) * dw / w_return;
                }
                if (ln_t) {
                    /* the return time and its derivatives (y0 moves by w0/a
                     * per unit ln w0; x(T) = nu, which moves along nu) */
                    *ln_t = log(sh.period);
                    if (dln_t && dg) {
                        dln_t[0] = sh.dT * w0 / p.a / sh.period;
                        dln_t[1] = (along_mu ? -sh.px : mirror * (1.0 - sh.px)) / (sh.xdot * sh.period);
                    }
                }
            }
        }
    }
    b->work_rhs += p.rhs_calls;
    b->work_jac += p.jacobian_calls;
    b->work_steps += in.steps + aux.steps;
    cycle_integrator_free(&in);
    cycle_integrator_free(&aux);
    return rc == BKF_ENOMEM ? bkf_error_set(err, BKF_ENOMEM, "out of memory") : rc;
}

static int branch_residual(const double *u, double *g, double *jac, void *data, bkf_error *err)
{
    branch_ctx *b = data;
    int rc = branch_shot(b, u[0], u[1], g, jac, NULL, NULL, err);
    return rc == BKF_OK || rc == BKF_ENOMEM ? rc : BKF_ENUMERIC;
}

/* The loosest tolerance a refused branch point is retried at, and the
 * largest |nu| at which it is: the relaxed rows' estimates were checked
 * against the Taylor reference through the canards of +-0.99 and +-0.999
 * (within 3 times, tests/wave/test_cycle_branch.c); at +-0.9999 the
 * relaxed rows of the creep before the explosion (mu 31-35.3656) were 81
 * and 114 times their estimates off, so there a row that misses tol is
 * refused. */
#define BRANCH_RELAX_MAX 1e-6
#define BRANCH_RELAX_NU_MAX 0.999

/* One shot's period corrected to the fixed point y0 + step, step the Newton
 * step from that shot, as newton_at accepts it without a confirming shot:
 * the step's first-order effect on T below 0.1 sqrt(tol) T and its square,
 * amplified by 1/(1 - P'), below 1e-2 tol.  0 if the shot is too far from
 * the cycle for that. */
static int branch_one_shot(const integrator *in, const flow_params *p, const shot *sh, double y0, double tol,
                           converged *out)
{
    double y_still = p->b * lienard_F(p->nu), slope_L;
    double dP = cycle_map_slope(in, sh, y0, y_still, &slope_L);
    double step = -(sh->y_return - y0) / (dP - 1.0), rel = step / fmax(fabs(y0), 1e-3);
    if (!(fabs(sh->dT * step) <= 0.1 * sqrt(tol) * sh->period) ||
        !(rel * rel <= 1e-2 * tol * (1.0 - fmin(dP, 0.999999))))
        return 0;
    *out = (converged){.period = sh->period + sh->dT * step, .log_mult = sh->log_mult, .y0 = y0 + step,
                       .xmax = sh->xmax, .xmin = sh->xmin, .return_slope = sh->dP, .dT = sh->dT,
                       .tol = in->tol};
    return 1;
}

/* Where the mirror's cycle (x -> -x, y -> -y) crosses its section
 * downward, the cycle at -nu crosses its own upward: that crossing, located
 * between the stored nodes of the mirror's last shot, is the row's section
 * point.  *y: in the unmirrored coordinates. */
static int branch_mirror_section(bkf_cycle *c, integrator *aux, double *y)
{
    const flow_params *p = &c->flow;
    for (size_t i = 1; i < c->node_count; i++) {
        const node *n0 = &c->nodes[i - 1], *n1 = &c->nodes[i];
        if (!(n0->s[0] > p->nu && n1->s[0] <= p->nu)) continue;
        double s0[DIM] = {n0->s[0], n0->s[1], 0.0, 1.0, 0.0}, s1[DIM] = {n1->s[0], n1->s[1], 0.0, 1.0, 0.0};
        double te, se[DIM];
        if (cycle_locate_event(aux, p, cycle_event_section, n0->t, s0, n1->t, s1, &te, se) != BKF_OK)
            return BKF_ENUMERIC;
        *y = -se[IY];
        return BKF_OK;
    }
    return BKF_ENUMERIC;
}

/* The mirror's result (at -nu) as the row at nu: the extremes swap and
 * change sign, the section point is y_real (branch_mirror_section), and the
 * flow becomes the row's (the stored nodes stay the mirror's: the branch's
 * cycle object only hands on its result). */
static void branch_unmirror_result(bkf_cycle *c, double mu, double nu, double y_real)
{
    bkf_cycle_result *r = &c->result;
    double xmax = r->xmax;
    cycle_flow_set(&c->flow, mu, nu);
    r->mu = mu;
    r->nu = nu;
    r->xmax = -r->xmin;
    r->xmin = -xmax;
    r->section_y = y_real;
    r->section_slope = c->flow.a * (y_real - c->flow.b * lienard_F(nu));
}

/* The row at the accepted point u from the continuation's own last shot
 * there (the looser solve of the estimate, at a cold solve's looser pair
 * tolerance) and one shot TOL_RATIO tighter from its fixed point, each
 * corrected to first order in y0 as newton_at would accept it: the pair a
 * cold solve ends with, without its coarse Newton and without re-solving
 * the point.  Anything else (no such shot, a shot too far from the cycle
 * for one step, an estimate that misses tol) returns nonzero, and the point
 * is solved afresh. */
static int branch_estimate(branch_ctx *b, const double *u, double mu, double nu, bkf_error *err)
{
    int mirrored = b->mirror_shots;
    /* (the row's ends are the requested values: a shot at exp(ln mu) is
     * within an ulp of mu, but one at another nu is not the row's) */
    if (!b->last.valid || b->last.u[0] != u[0] || b->last.u[1] != u[1] ||
        b->last.flow.nu != (mirrored ? -nu : nu))
        return BKF_ENUMERIC;
    /* Near the canard the mirror's estimate flatters (mu 9.4735, nu -0.999:
     * the pair at +0.999 said 1.7e-12, the Taylor reference is 7.7e-12 off;
     * docs/accuracy.md): there a row for nu < 0 is solved at its own nu. */
    if (mirrored && branch_near_canard(mu, nu)) return BKF_ENUMERIC;
    bkf_cycle *c = b->cycle;
    double tol = b->options.tol;
    converged a, fine;
    flow_params *p = &c->flow;
    if (!branch_one_shot(&b->last.in, &b->last.flow, &b->last.sh, b->last.y0, tol, &a)) return BKF_ENUMERIC;
    *p = b->last.flow;
    p->sens = 0;
    p->rhs_calls = p->jacobian_calls = 0;
    /* (the shooting rows of a collocation branch shoot as the automatic
     * ones: they were rk8pd at every mu and named "colloc") */
    bkf_stepper_kind kind = b->options.stepper;
    if (kind == BKF_STEPPER_AUTO || kind == BKF_STEPPER_COLLOCATION) kind = cycle_shooting_stepper(p->mu, tol);
    integrator in = {0}, aux = {0};
    double tol_a = cycle_pair_tol(tol, p->nu, kind), tol_b = tol_a / TOL_RATIO, floor = 0.0, y_real = 0.0;
    double y0 = b->last.y0, y_scale = fmax(fabs(y0), 1e-3);
    size_t steps = 0, shots = 0;
    integrator looser = b->last.in;
    looser.tol = tol_a;
    int rc = BKF_ENOMEM;
    if (cycle_integrator_init(&in, p, kind, 0, tol_a) == BKF_OK &&
        cycle_integrator_init(&aux, p, kind, 1, tol_b) == BKF_OK) {
        rc = BKF_OK;
        /* Inside the canard the one-step correction of the corrector's
         * shot is not trusted: T curves in y0 on a scale far below y0, and
         * rows so corrected missed the Taylor reference by up to 6.2 times
         * their estimate while within tol (mu 3.65, nu 0.98994: true 8.5e-13
         * T, estimate 1.4e-13 T; mu 3.6506251, nu 0.99: 3.25), the pair's
         * tighter solve, started from the corrected point, sharing the
         * error.  Newton at this q is honest there (worst 0.8). */
        if (b->last.in.tol != tol_a || (cycle_canard_window(mu, nu) && mu >= 2.0) ||
            !branch_one_shot(&b->last.in, &b->last.flow, &b->last.sh, y0, tol, &a)) {
            /* a looser corrector shot, or one farther from the cycle than
             * one step corrects: Newton at this q, from that step */
            looser.capped = 0;
            const flow_params *f = &b->last.flow;
            const shot *sh = &b->last.sh;
            double slope_L, dP = cycle_map_slope(&b->last.in, sh, y0, f->b * lienard_F(f->nu), &slope_L);
            y0 -= (sh->y_return - y0) / (dP - 1.0);
            rc = cycle_newton_at(c, &in, &aux, &y0, 0.1 * sqrt(tol), tol * y_scale, y_scale, 1e-2 * tol, 0, 0, &shots,
                                 &a, err);
            steps += in.steps;
            looser.capped += in.capped;
        }
        cycle_integrator_free(&in);
        /* the tighter solve from the looser one's fixed point, usually one
         * shot (its trajectory gives xmax, xmin and the mirror's section) */
        if (rc == BKF_OK && cycle_integrator_init(&in, p, kind, 0, tol_b) != BKF_OK) rc = BKF_ENOMEM;
        y0 = a.y0;
        if (rc == BKF_OK) {
            rc = cycle_newton_at(c, &in, &aux, &y0, 0.1 * sqrt(tol), 0.1 * tol * y_scale, y_scale, 1e-2 * tol, 1, 0,
                                 &shots, &fine, err);
        }
        if (rc == BKF_OK) rc = cycle_conditioning_floor(p, kind, tol_a, fine.y0, &floor, &steps, err);
        if (rc == BKF_OK && mirrored) rc = branch_mirror_section(c, &aux, &y_real);
    }
    if (rc == BKF_OK) {
        double period_err = cycle_capped_floor(cycle_period_error(&a, &fine, p, kind, floor), &looser, fine.period);
        if (ACCEPT_MARGIN * period_err > tol * fine.period) {
            rc = BKF_ETOL;
        } else {
            /* (the work counters are the branch's: branch_accept) */
            integrator none = {0};
            cycle_store_result(c, &a, &fine, period_err, fine.y0, kind, tol_b, &none, &none, &none, &none, 0);
            if (mirrored) branch_unmirror_result(c, mu, nu, y_real);
            cycle_flow_set(p, mu, nu);
            c->result.mu = mu;
            c->result.nu = nu;
        }
    }
    b->work_rhs += p->rhs_calls;
    b->work_jac += p->jacobian_calls;
    b->work_steps += in.steps + aux.steps + steps;
    b->work_shots += shots;
    cycle_integrator_free(&in);
    cycle_integrator_free(&aux);
    return rc;
}

/* Where the branch's tangent in (ln f'(0), q) has a q component below
 * STEEP_ENTER the cycle is inside a canard explosion: its amplitude changes
 * by O(1) over an interval of q as narrow as 1e-9 (mu 11.2, nu 0.999), G
 * moves by dG/dq ~ 1e9 per unit q, and the corrector in q stops on its step
 * (1e-11) with the residual still at the integration noise (1e-2).  There the
 * amplitude is the parameter (branch_amplitude) until the tangent's q
 * component is back above STEEP_LEAVE, both the one from dG and the
 * walk's own secant: inside the canard dG/dq from the variational shot
 * flips between ~1 and ~-1e12 from one root to the next (mu 10, nu
 * 0.998740451246: the walk left on a dG/dq of 0.93 at ln f'(0) 2.6976, and
 * the next stretch predicted past nu = 1), while the roots' q stays within
 * 1e-13. */
#define STEEP_ENTER 1e-3
#define STEEP_LEAVE 0.5

/* A solve of a branch point, its work added to the branch's (a failed
 * solve keeps no counters: its work is not counted). */
static int branch_solve_counted(branch_ctx *b, double mu, double nu, const bkf_cycle_options *o, bkf_error *err)
{
    int rc = bkf_cycle_solve(b->cycle, mu, nu, o, err);
    if (rc == BKF_OK) {
        const bkf_cycle_result *r = &b->cycle->result;
        b->work_rhs += r->rhs_calls;
        b->work_jac += r->jacobian_calls;
        b->work_steps += r->steps;
        b->work_shots += r->newton_iterations;
    }
    return rc;
}

/* A row solved afresh.  Along mu, a row for nu < 0 near the canard is
 * solved as its mirror image at -nu (same T) whose section is crossed
 * mid-jump: at nu itself the section x = nu lies where the jump leaves the
 * left knee, dT/dy0 is ~1e6 times larger (mu 3.6505, nu -0.99: 4.2e6
 * against 4.2), and a warm-started relaxed solve there ended 26 times its
 * estimate off the Taylor reference (mu 3.65053675, nu -0.99: true 3.9e-8
 * T, estimate 1.5e-9 T). */
static int branch_unmirror_row(branch_ctx *b, double mu, double nu, bkf_error *err);

static int branch_solve_row(branch_ctx *b, double mu, double nu, int mirrored, const bkf_cycle_options *o,
                            bkf_error *err)
{
    int rc = branch_solve_counted(b, mu, mirrored ? -nu : nu, o, err);
    if (rc != BKF_OK || !mirrored) return rc;
    return branch_unmirror_row(b, mu, nu, err);
}

/* The mirror's solution in b->cycle (at -nu, its nodes stored) as the row
 * at nu: its section located between the nodes, the result unmirrored. */
static int branch_unmirror_row(branch_ctx *b, double mu, double nu, bkf_error *err)
{
    int rc = BKF_OK;
    bkf_cycle *c = b->cycle;
    integrator aux = {0};
    double y_real = 0.0;
    size_t rhs = c->flow.rhs_calls, jac = c->flow.jacobian_calls;
    if (cycle_integrator_init(&aux, &c->flow, c->profile_stepper, 1, c->profile_tol) != BKF_OK) rc = BKF_ENOMEM;
    else rc = branch_mirror_section(c, &aux, &y_real);
    b->work_rhs += c->flow.rhs_calls - rhs;
    b->work_jac += c->flow.jacobian_calls - jac;
    b->work_steps += aux.steps;
    cycle_integrator_free(&aux);
    if (rc == BKF_ENOMEM) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    if (rc != BKF_OK)
        return bkf_error_set(err, BKF_ENUMERIC, "cycle at mu = %.15g, nu = %.15g: the mirror's section not located",
                             mu, nu);
    branch_unmirror_result(c, mu, nu, y_real);
    return BKF_OK;
}

/* A row's work counters: every shot since the last row (the continuation's
 * corrector and tangent, the amplitude walk's roots, the estimate or the
 * solve), so that they say what the row cost. */
static void branch_work(branch_ctx *b, bkf_cycle_result *r)
{
    r->rhs_calls = b->work_rhs;
    r->jacobian_calls = b->work_jac;
    r->steps = b->work_steps;
    r->newton_iterations = b->work_shots;
    b->work_rhs = b->work_jac = b->work_steps = b->work_shots = 0;
}

/* A row's parameters at q; the ends are requested values: given back
 * exactly, not exp(ln A).  Returns q, snapped to an end within 1e-12. */
static double branch_row_params(const branch_ctx *b, double q, double *mu, double *nu)
{
    if (fabs(q - b->q_from) <= 1e-12 * fmax(1.0, fabs(q))) q = b->q_from;
    if (fabs(q - b->q_to) <= 1e-12 * fmax(1.0, fabs(q))) q = b->q_to;
    branch_params(b, q, mu, nu);
    if (q == b->q_from) *(b->along == BKF_CYCLE_ALONG_MU ? mu : nu) = b->from;
    if (q == b->q_to) *(b->along == BKF_CYCLE_ALONG_MU ? mu : nu) = b->to;
    return q;
}

static int branch_colloc_at(const branch_ctx *b, double mu, double nu);
static int branch_colloc_between(const branch_ctx *b, double q0, double q1);

/* Rows in a row that may miss tol before the branch counts as stuck.  A
 * canard the shots cross takes up to 72 (nu +-0.999 along mu: relaxed rows
 * while the canard grows, refused ones at its head within 1e-10 of mu
 * 11.2141166); at nu 0.9999 the explosion (mu 35.3659) is too thin for
 * any row inside it, and the pseudo-arclength steps crept at 1e-7 of mu a
 * row, every row relaxed or refused, for 20-26 minutes before the walk
 * found no root of G (about 0.07 s a row). */
#define BRANCH_MISSED_MAX 160

static int branch_accept(const double *u, const double *tangent, int is_fold, void *data)
{
    (void)is_fold; /* T(mu) and T(nu) have no folds; a located one is still a valid point */
    branch_ctx *b = data;
    double q_prev = b->have_last ? b->last_u[1] : u[1];
    memcpy(b->last_u, u, sizeof b->last_u);
    if (tangent) memcpy(b->last_t, tangent, sizeof b->last_t);
    b->have_last = 1;
    if (b->skip_visit) {
        /* a restart's first point, visited already at the end of the last stretch */
        b->skip_visit = 0;
        return 0;
    }
    bkf_error solve_err;
    double mu, nu, q = branch_row_params(b, u[1], &mu, &nu);
    int mirrored = b->along == BKF_CYCLE_ALONG_MU && nu < 0 && branch_near_canard(mu, nu);
    /* (u[0] is the mirror's slope where the shots are mirrored: a solve at nu itself then
     * starts from the previous point's cycle) */
    double warm = !b->mirror_shots || mirrored ? exp(u[0]) : 0.0;
    int rc = branch_estimate(b, u, mu, nu, &solve_err);
    if (rc != BKF_OK && rc != BKF_ENOMEM) {
        b->cycle->warm_slope = warm;
        rc = branch_solve_row(b, mu, nu, mirrored, &b->options, &solve_err);
    }
    /* A point whose T cannot be had to tol (inside the canard explosion T
     * moves by dT/dmu ~ 1e5 at mu 3.65, nu 0.99, and forward shooting
     * amplifies the integration's rounding by as much: the solve refuses,
     * or its Newton drowns in that noise) is given at the tightest
     * tolerance it meets, marked, and the branch goes on. */
    bkf_cycle_options relaxed = b->options;
    int refused = bkf_status_is_numerical(rc);
    while (bkf_status_is_numerical(rc) && relaxed.tol < BRANCH_RELAX_MAX &&
           fabs(nu) <= BRANCH_RELAX_NU_MAX * (1.0 + 1e-12)) {
        relaxed.tol = fmin(10.0 * relaxed.tol, BRANCH_RELAX_MAX);
        b->cycle->warm_slope = warm;
        rc = branch_solve_row(b, mu, nu, mirrored, &relaxed, &solve_err);
        if (rc == BKF_OK) b->cycle->result.model = "shooting-relaxed";
    }
    if (refused && rc != BKF_OK && rc != BKF_ENOMEM) {
        /* nothing met even the loosest: a row that says so */
        bkf_cycle_result r = {.mu = mu, .nu = nu, .stepper = "none", .model = "refused"};
        r.period = r.period_err = r.xmax = r.xmin = r.multiplier = r.log_multiplier = NAN;
        r.log_multiplier_err = r.return_map_slope = r.section_y = r.section_slope = NAN;
        branch_work(b, &r);
        if (b->visit(&r, b->visit_data) != 0) {
            b->visit_status = -1;
            return 1;
        }
    } else {
        if (rc != BKF_OK) {
            if (b->err) *b->err = solve_err;
            b->visit_status = rc;
            return 1;
        }
        branch_work(b, &b->cycle->result);
        if (b->visit(&b->cycle->result, b->visit_data) != 0) {
            b->visit_status = -1;
            return 1;
        }
    }
    b->rows++;
    b->missed = refused ? b->missed + 1 : 0;
    if (b->missed >= BRANCH_MISSED_MAX && q != b->q_to) {
        b->stuck = 1;
        return 1;
    }
    if (tangent && fabs(tangent[1]) < STEEP_ENTER && q != b->q_to) {
        b->steep = 1;
        return 1;
    }
    /* (a shooting step can cross the canard band whole: mu 0.95 -> 1.32 at
     * nu 0.5, whose band is mu in [1, 1.12]; the rows then came back to
     * collocation never) */
    int here = branch_colloc_at(b, mu, nu);
    if (!here || !branch_colloc_between(b, q_prev, q)) b->left_colloc = 1;
    if (here && b->left_colloc && q != b->q_to && !refused && strcmp(b->cycle->result.model, "shooting-relaxed")) {
        b->to_colloc = 1;
        return 1;
    }
    return 0;
}

/* The noise band of a canard narrower than its noise around q: how far
 * the last point may sit past an amplitude's root (branch_solve_q), the
 * least the amplitude walk reaches and the most it may fall back. */
static double canard_band(double q)
{
    return 1e-6 * fmax(1.0, fabs(q));
}

/* q where G(ln w0, q) = 0 at a fixed amplitude ln w0, beyond q0 in the
 * direction dir (q is monotone on the branch: dG/d ln w0 = P' - 1 < 0 on an
 * attracting cycle, so q never folds), by a bracket grown from the
 * predicted step and Illinois regula falsi.  No Newton step in q: inside a
 * canard G is noisy at 1e-2 while dG/dq ~ 1e9, and at the corner where the
 * canard grows its head dG/dq does not even have its sign.  The root is
 * known to the band where the noise hides the sign of G: a bracket below
 * 1e-13 of q ends the search (the row is solved afresh at that q anyway).
 * *dg: the derivatives at the root. */
static int branch_solve_q(branch_ctx *b, double ln_w0, double q0, double step, int dir, double tol,
                          double reach, double *q, double *dg, int *shots, bkf_error *err)
{
    const double band = 1e-13 * fmax(1.0, fabs(q0));
    double a = q0, ga, x, gx;
    int rc = branch_shot(b, ln_w0, a, &ga, dg, NULL, NULL, err);
    *shots = 1;
    if (rc != BKF_OK) return rc;
    if (fabs(ga) <= tol) {
        *q = a;
        return BKF_OK;
    }
    /* A canard narrower than its noise (mu 10, nu 0.998740451245: ~1e-12
     * in nu; at nu 0.9999 up to 4e-8 in ln mu 3.5657) may hold the last
     * point past this amplitude's root, but only by that much: a root
     * farther back is the branch behind the last point, reached by an
     * amplitude step the wrong way (a dG/dq of the wrong sign at the
     * explosion: mu 36 -> 35 at nu 0.9999, tol 1e-7, found mu 36.11 and
     * walked back up to mu 145, past the branch's start). */
    const double back = fmin(reach, canard_band(q0));
    double d = fmax(fabs(step), band), g0 = ga;
    for (int way = dir;;) {
        if (d > (way == dir ? reach : back)) {
            if (way != dir)
                return bkf_error_set(err, BKF_ENUMERIC, "no root of G within %g of q = %.15g (%g behind it)", reach,
                                     q0, back);
            way = -dir;
            d = fmin(fmax(fabs(step), band), back);
            a = q0;
            ga = g0;
        }
        x = q0 + way * d;
        rc = branch_shot(b, ln_w0, x, &gx, dg, NULL, NULL, err);
        ++*shots;
        if (rc != BKF_OK) return rc;
        if ((gx > 0) != (ga > 0) || fabs(gx) <= tol) break;
        a = x;
        ga = gx;
        d *= 4.0;
    }
    int side = 0;
    for (int it = 0; it < 100 && fabs(gx) > tol && fabs(x - a) > band; it++) {
        double c = x - gx * (x - a) / (gx - ga), gc;
        if (!(c > fmin(a, x) && c < fmax(a, x))) c = 0.5 * (a + x);
        rc = branch_shot(b, ln_w0, c, &gc, dg, NULL, NULL, err);
        ++*shots;
        if (rc != BKF_OK) return rc;
        if ((gc > 0) == (gx > 0)) {
            x = c;
            gx = gc;
            if (side == 1) ga *= 0.5;
            side = 1;
        } else {
            a = x;
            ga = gx;
            x = c;
            gx = gc;
            side = -1;
        }
    }
    *q = x;
    return BKF_OK;
}

/* Through a canard: steps in ln w0 from the last accepted point, q solved
 * at each (the amplitude as the parameter, as AUTO-like codes continue in a
 * shape measure where the parameter barely moves).  In (ln w0, q) the
 * canard is a segment at one q (to 1e-9), reached through a corner that
 * pseudo-arclength steps above step_min cannot turn; at fixed ln w0 the
 * root in q is smooth.  (While a canard grows its head the jump through
 * the section, and so ln w0, stay the relaxation cycle's: that part of the
 * canard is a point of the plane and is stepped over; its cycles exist
 * only within ~1e-9 of q, where no row meets even 1e-6.)  The amplitude
 * moves along sign(dG/dq) times dir; if no root lies that way the other.
 * Returns once the branch leans back towards q (the tangent's q component
 * and the last step's above STEEP_LEAVE), with the last point in
 * b->last_u; on the way the points are visited.  A canard across the end lands on it (b->landed). */
static int branch_amplitude(branch_ctx *b, int dir, size_t max_rows, int forced, bkf_error *err)
{
    /* entered after a failed stretch: not back before the canard */
    int seen_steep = !forced, shots = 0, tries = 0;
    double u[2] = {b->last_u[0], b->last_u[1]}, dg[2], g, front = u[1];
    const double h_min = 1e-6, h_max = 0.25, tol = fmax(1e-10, 10.0 * b->options.tol);
    int rc = branch_shot(b, u[0], u[1], &g, dg, NULL, NULL, err);
    if (rc != BKF_OK) return rc;
    double sign = (dg[1] > 0 ? 1.0 : -1.0) * dir, h = 0.02, slope = fabs(dg[0] / dg[1]);
    for (int steps = 0; b->rows < max_rows;) {
        double lw = u[0] + sign * h, q = u[1];
        double reach = fmax(canard_band(u[1]), 8.0 * slope * h);
        rc = branch_solve_q(b, lw, u[1], slope * h, dir, tol, reach, &q, dg, &shots, err);
        /* No row behind the walk's front by more than the noise band
         * branch_solve_q searches behind the last point, nor before the
         * branch's start: roots a little behind one another add up to the
         * branch walked backwards (mu 40 -> 35 at nu 0.9999, tol 1e-7: from
         * mu 35.2848 back up to 35.3242 in 1529 rows). */
        int back = rc == BKF_OK && ((q - front) * dir < -canard_band(front) || (q - b->q_from) * dir < 0);
        if (back) rc = bkf_error_set(err, BKF_ENUMERIC, "the amplitude walk turned back at q = %.15g", q);
        if (rc == BKF_OK && (q - b->q_to) * dir >= 0) {
            /* the end lies inside the canard: land on it, ln w0 by Newton
             * at q = q_to (dG/d ln w0 = P' - 1 is well away from 0) */
            double x = u[0] + (lw - u[0]) * (b->q_to - u[1]) / (q - u[1]);
            double lo = fmin(u[0], lw), hi = fmax(u[0], lw);
            for (int it = 0; it < 20; it++) {
                rc = branch_shot(b, x, b->q_to, &g, dg, NULL, NULL, err);
                if (rc != BKF_OK) return rc;
                double next = fmin(hi, fmax(lo, x - g / dg[0]));
                if (fabs(g) <= tol || fabs(next - x) <= 1e-12 * fmax(1.0, fabs(x))) break;
                x = next;
            }
            double end[2] = {x, b->q_to};
            b->landed = 1;
            branch_accept(end, NULL, 0, b);
            return BKF_OK;
        }
        if (rc != BKF_OK) {
            if (rc == BKF_ENOMEM) return rc;
            if ((steps == 0 || back) && tries++ == 0) {
                sign = -sign; /* at the corner dG/dq's sign said nothing */
                continue;
            }
            h *= 0.5;
            if (h < h_min) return rc;
            continue;
        }
        steps++;
        slope = fabs(q - u[1]) / h;
        double dq = q - u[1], secant = fabs(dq) / hypot(lw - u[0], dq);
        u[0] = lw;
        u[1] = q;
        front = dir > 0 ? fmax(front, q) : fmin(front, q);
        double norm = hypot(dg[0], dg[1]);
        /* the unit null vector of (dG/d ln w0, dG/dq), pointing along the walk */
        double t[2] = {sign * fabs(dg[1]) / norm, dir * fabs(dg[0]) / norm};
        if (branch_accept(u, t, 0, b) && !b->steep) return BKF_OK; /* visit asked to stop */
        b->steep = 0;
        if (fabs(t[1]) < STEEP_ENTER) seen_steep = 1;
        if (fabs(t[1]) > STEEP_LEAVE && secant > STEEP_LEAVE && (seen_steep || steps >= 10)) return BKF_OK;
        /* (a root within the canard's width of the last one cost its shots
         * bracketing the noise band, which says nothing of the step: at mu
         * 10, nu 0.99874 the head's corner is crossed in ln f'(0) from 2.70
         * down to 0.4 with q still, and halving there left h at h_min) */
        if (shots <= 6 || fabs(dq) <= 1e-9 * fmax(1.0, fabs(q))) h = fmin(1.5 * h, h_max);
        else if (shots > 12) h = fmax(0.5 * h, h_min);
    }
    return BKF_OK;
}

/* ----------------------------------------------------- collocation rows */

/* Away from the canard the branch's rows are collocation solves on a path
 * (bkf_colloc_continue: the mesh and solution predicted from the last two
 * rows, Newton on the pair, no re-meshing while the pair meets tol), which
 * cost a fraction of a cold solve of either engine.  Their domain: mu up
 * to COLLOC_AUTO_MU_MAX, outside 8 mu^2 (1 - |nu|) in [0.2, 5] for mu >= 1
 * (wider than branch_near_canard's [1/4, 4], where the shooting rows and
 * the amplitude walk keep the canard's rows as they were, and than
 * colloc_attempt's refusal), with the automatic stepper at tol <=
 * COLLOC_AUTO_TOL_MAX or with collocation asked for. */
#define BRANCH_COLLOC_CANARD_LO 0.2
#define BRANCH_COLLOC_CANARD_HI 5.0
/* Steps in q (ln mu or nu): the first, the largest (about as many rows per
 * decade of mu as the shooting branch's, the same largest step along nu),
 * and the smallest before the rows hand over to shooting. */
#define BRANCH_COLLOC_STEP_MU 0.35
#define BRANCH_COLLOC_STEP_NU 0.05
#define BRANCH_COLLOC_STEP_MIN 1e-4
/* Rows on a path up to this mu, by turns above it (branch_colloc_turn). */
#define BRANCH_COLLOC_TURN_MU 2.0

static int branch_colloc_kind(const branch_ctx *b)
{
    return b->options.stepper == BKF_STEPPER_COLLOCATION ||
           (b->options.stepper == BKF_STEPPER_AUTO && b->options.tol <= COLLOC_AUTO_TOL_MAX * (1.0 + 1e-9));
}

/* nu as the branch's rows are solved (the mirror's along mu, nu < 0). */
static double branch_solved_nu(const branch_ctx *b, double nu)
{
    return b->mirror_shots && b->along == BKF_CYCLE_ALONG_MU ? -nu : nu;
}

/* The canard band along mu at nu that collocation rows keep out of, [*lo,
 * *hi] in mu (empty if lo > hi). */
static void branch_colloc_band(const branch_ctx *b, double nu, double *lo, double *hi)
{
    double d = 8.0 * (1.0 - fabs(nu));
    *lo = fmax(1.0, sqrt(BRANCH_COLLOC_CANARD_LO / d));
    *hi = cycle_colloc_canard_refused(branch_solved_nu(b, nu)) ? sqrt(BRANCH_COLLOC_CANARD_HI / d) : 0.0;
}

/* The automatic rows along mu before a canard band that the branch has yet
 * to cross shoot from |nu| 0.99: the amplitude walk through the explosion
 * is sensitive to the steps that reach it, and from collocation rows
 * handing over at the band's edge (mu 5 at nu -0.999) it found no root of
 * G at mu 11.2141, where the shooting rows from mu 0.1 pass (the shooting
 * rows there were the automatic ones before).  Below |nu| 0.99 no walk is
 * needed (nu -0.96, +-0.5, 0.9, +-0.989: the same relaxed rows as
 * before; at nu -0.96 the rows over [0.1, 1] cost 46 us each, the engine's
 * CPU time, where the shooting rows took about 100). */
static int branch_colloc_before_band(const branch_ctx *b, double mu, double nu)
{
    if (b->options.stepper != BKF_STEPPER_AUTO || b->along != BKF_CYCLE_ALONG_MU || fabs(nu) < 0.99) return 0;
    double lo, hi;
    branch_colloc_band(b, nu, &lo, &hi);
    if (lo > hi) return 0;
    return b->to > b->from ? mu < lo && b->to >= lo : mu > hi && b->to <= hi;
}

static int branch_colloc_at(const branch_ctx *b, double mu, double nu)
{
    double x = 8.0 * mu * mu * (1.0 - fabs(nu));
    return branch_colloc_kind(b) && mu <= COLLOC_AUTO_MU_MAX * (1.0 + 1e-12) &&
           !(mu >= 1.0 && cycle_colloc_canard_refused(branch_solved_nu(b, nu)) && x >= BRANCH_COLLOC_CANARD_LO &&
             x <= BRANCH_COLLOC_CANARD_HI) &&
           !branch_colloc_before_band(b, mu, nu);
}

/* The same for every point between q0 and q1: the window's band in q
 * (along mu an interval of mu, along nu one of |nu| on either side) must
 * not meet the segment. */
static int branch_colloc_between(const branch_ctx *b, double q0, double q1)
{
    double mu0, nu0, mu1, nu1;
    branch_params(b, q0, &mu0, &nu0);
    branch_params(b, q1, &mu1, &nu1);
    if (!branch_colloc_at(b, mu0, nu0) || !branch_colloc_at(b, mu1, nu1)) return 0;
    if (b->along == BKF_CYCLE_ALONG_MU) {
        double lo, hi;
        branch_colloc_band(b, nu0, &lo, &hi);
        return !(lo <= hi && fmax(mu0, mu1) >= lo && fmin(mu0, mu1) <= hi);
    }
    if (mu0 < 1.0) return 1;
    /* along nu the rows are not mirrored: the band at nu < 0 whole, at
     * nu > 0 its steep part */
    double d = 8.0 * mu0 * mu0, lo = 1.0 - BRANCH_COLLOC_CANARD_HI / d, hi = 1.0 - BRANCH_COLLOC_CANARD_LO / d;
    double plus_lo = fmax(lo, nextafter(COLLOC_CANARD_STEEP_NU, 1.0));
    double a = fmin(nu0, nu1), z = fmax(nu0, nu1);
    int meets_plus = plus_lo <= hi && z >= plus_lo && a <= hi;
    int meets_minus = -a >= lo && -z <= hi;
    return !(meets_plus || meets_minus);
}

/* The row at (mu, nu) in b->cycle (c->colloc holds r's solution, the
 * mirror's at -nu if mirrored) visited, its work the branch's since the
 * last row. */
static int branch_colloc_visit(branch_ctx *b, const bkf_colloc_result *r, double mu, double nu, int mirrored,
                               bkf_error *err)
{
    bkf_cycle *c = b->cycle;
    c->flow.rhs_calls = c->flow.jacobian_calls = 0;
    int rc = cycle_colloc_store(c, r, &b->options, err);
    if (rc != BKF_OK) return rc;
    b->work_steps += c->result.steps;
    b->work_rhs += c->result.rhs_calls;
    b->work_jac += c->result.jacobian_calls;
    b->work_shots += c->result.newton_iterations;
    if (mirrored && (rc = branch_unmirror_row(b, mu, nu, err)) != BKF_OK) return rc;
    branch_work(b, &c->result);
    if (b->visit(&c->result, b->visit_data) != 0) b->visit_status = -1;
    b->rows++;
    return BKF_OK;
}

/* A row's cycle: in the relaxation regime (as colloc_attempt's cold
 * start) the landing from the left slow branch, whose pair's estimate is
 * tested over the box (colloc_relaxation_start_meets_tol); elsewhere from
 * the predicted section slope w and period T (in the solved coordinates)
 * the cold start's turns from that section point; then the solve of their
 * pair.  (From a predicted section point at mu 733.8, nu 0.5 the pair
 * agreed within the floor while T was 2.4e-11 off, twice the estimate;
 * at mu 100, nu 0.6375 1.4 times: a row costs the same either way.)  At large mu the layers move
 * in normalised time from row to row (the down jump's s at nu 0.96), so a
 * path's mesh predicted index by index needed 15-30 Newton iterations
 * even at steps of 0.02 in ln mu, where a turn from the predicted point
 * follows them and Newton takes 2-4. */
static int branch_colloc_turn(bkf_cycle *c, double w, double T, double tol, bkf_colloc_result *r, bkf_error *err)
{
    const flow_params *p = &c->flow;
    int rc;
    if (p->mu >= COLLOC_RELAXATION_MU && 8.0 * p->mu * p->mu * (1.0 - fabs(p->nu)) >= 3.0)
        rc = bkf_colloc_guess_relaxation(c->colloc, p->mu, p->nu, bkf_asym_period_leading(p->mu, p->nu),
                                         cycle_colloc_turn_tol(tol, p->mu), err);
    else
        rc = bkf_colloc_guess_turn(c->colloc, p->mu, p->nu, p->nu, cycle_section_y_of_slope(p, w), fmax(2.0 * M_PI, T),
                                   cycle_colloc_turn_tol(tol, p->mu), err);
    return rc == BKF_OK ? bkf_colloc_solve(c->colloc, tol, r, err) : rc;
}

/* Collocation rows from q (visited already unless visit_first) towards
 * q_to, for as long as their domain lasts: a cold solve at q, then up to
 * BRANCH_COLLOC_TURN_MU rows on a path (bkf_colloc_continue: the mesh
 * predicted index by index from the last two rows, Newton on the pair; a
 * row whose pair misses tol is re-meshed by turns), above it every row by
 * turns from the section point and period predicted by the secant in q of
 * the last two rows' ln f'(0) and ln T.  The step grows while the rows
 * converge in few iterations and halves where they refuse.  Along mu for
 * nu < 0 the rows are the mirror's, as the shots are (solved at -nu: the
 * section x = nu at the left knee); along nu they are not (mu 100, nu
 * 0.6375: a collocation solve there misses its estimate 1.4 times, at
 * -0.6375 it does not).  Returns with the
 * last visited row's q in b->last_u[1] (b->landed at q_to); a cold solve
 * that refuses is BKF_ENUMERIC with no row visited.  Where the next step
 * would leave the domain or cannot be taken, the caller continues by
 * shooting from that row. */
static int branch_colloc(branch_ctx *b, double q, int dir, size_t limit, int visit_first, bkf_error *err)
{
    bkf_cycle *c = b->cycle;
    const double sign = b->mirror_shots && b->along == BKF_CYCLE_ALONG_MU ? -1.0 : 1.0;
    double mu, nu;
    q = branch_row_params(b, q, &mu, &nu);
    bkf_cycle_options opt = b->options;
    opt.warm_start = 0;
    cycle_flow_set(&c->flow, mu, sign * nu);
    c->flow.rhs_calls = c->flow.jacobian_calls = 0;
    int rc = cycle_colloc_attempt(c, &opt, 0, err);
    /* the last two rows' q, ln f'(0) and ln T in the solved coordinates */
    double hist[2][3] = {{q, log(c->result.section_slope), log(c->result.period)}};
    if (rc == BKF_OK && sign < 0.0) rc = branch_unmirror_row(b, mu, nu, err);
    if (rc != BKF_OK) {
        c->have_solution = 0;
        return rc == BKF_ENOMEM ? rc : BKF_ENUMERIC;
    }
    b->work_steps += c->result.steps;
    b->work_rhs += c->result.rhs_calls;
    b->work_jac += c->result.jacobian_calls;
    b->work_shots += c->result.newton_iterations;
    memcpy(hist[1], hist[0], sizeof hist[1]);
    int have = 1;
    if (visit_first) {
        branch_work(b, &c->result);
        if (b->visit(&c->result, b->visit_data) != 0) b->visit_status = -1;
        b->rows++;
    }
    bkf_colloc_path *path = bkf_colloc_path_alloc();
    if (!path) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    const double step_max = b->along == BKF_CYCLE_ALONG_MU ? BRANCH_COLLOC_STEP_MU : BRANCH_COLLOC_STEP_NU;
    double step = 0.5 * step_max;
    int path_rows = bkf_colloc_path_push(path, c->colloc) == BKF_OK;
    rc = BKF_OK;
    while (b->visit_status == 0 && b->rows < limit && q != b->q_to) {
        double qn = q + dir * step;
        if ((qn - b->q_to) * dir >= 0.0 || fabs(qn - b->q_to) <= 1e-12 * fmax(1.0, fabs(qn))) qn = b->q_to;
        if (!branch_colloc_between(b, q, qn)) break;
        qn = branch_row_params(b, qn, &mu, &nu);
        cycle_flow_set(&c->flow, mu, sign * nu);
        bkf_colloc_result r;
        bkf_error row_err;
        int row = BKF_ETOL, continued = path_rows >= 1 && mu <= BRANCH_COLLOC_TURN_MU;
        if (continued) {
            row = bkf_colloc_continue(c->colloc, path, mu, sign * nu, opt.tol, &r, &row_err);
            b->work_steps += r.interval_solves;
            b->work_shots += r.newton_iterations;
        }
        if (row == BKF_ETOL) {
            continued = 0;
            /* turns from the predicted section point */
            double f = have == 2 ? (qn - hist[1][0]) / (hist[1][0] - hist[0][0]) : 0.0;
            double lw = hist[1][1] + f * (hist[1][1] - hist[0][1]), lT = hist[1][2] + f * (hist[1][2] - hist[0][2]);
            row = branch_colloc_turn(c, exp(lw), exp(lT), opt.tol, &r, &row_err);
            if (row == BKF_OK) {
                b->work_steps += r.interval_solves;
                b->work_shots += r.newton_iterations;
                if (mu <= BRANCH_COLLOC_TURN_MU) {
                    if (bkf_colloc_path_push(path, c->colloc) != BKF_OK) row = BKF_ENOMEM;
                    path_rows = 1;
                }
            } else if (row != BKF_ENOMEM) {
                /* the object's solution is gone: shooting goes on from q */
                break;
            }
        }
        if (row == BKF_ENOMEM) {
            rc = bkf_error_set(err, BKF_ENOMEM, "out of memory");
            break;
        }
        if (row != BKF_OK) {
            step *= 0.5;
            if (step < BRANCH_COLLOC_STEP_MIN) break;
            continue;
        }
        /* (r's counters were added above: the row's visit adds only the
         * extremes' integration and the mirror's section) */
        size_t iterations = r.newton_iterations;
        r.interval_solves = r.newton_iterations = 0;
        memcpy(hist[0], hist[1], sizeof hist[1]);
        hist[1][0] = qn;
        hist[1][1] = log(c->flow.a * (r.section_y - c->flow.b * lienard_F(c->flow.nu)));
        hist[1][2] = log(r.period);
        have = 2;
        rc = branch_colloc_visit(b, &r, mu, nu, sign < 0.0, err);
        if (rc != BKF_OK) break;
        q = qn;
        b->last_u[0] = log(c->result.section_slope);
        b->last_u[1] = q;
        b->have_last = 1;
        if (!continued || iterations <= 7) step = fmin(1.5 * step, step_max);
    }
    bkf_colloc_path_free(path);
    b->last_u[1] = q;
    b->have_last = 1;
    b->landed = q == b->q_to;
    return rc;
}

/* A branch stuck in a canard explosion (b->stuck: BRANCH_MISSED_MAX rows
 * in a row missed tol) goes on past it by collocation rows, along mu
 * towards larger mu only: past the explosion the cycle is the relaxation
 * cycle with at most a canard head, whose cold start lands from the left
 * slow branch (bkf_colloc_guess_relaxation) whatever the head, and whose
 * cyclic solve, from the section at the right knee, sees the attracting
 * branch before the repelling one (the interval maps' products stay
 * small).  Inside the explosion no row of either engine meets tol (at nu
 * 0.9999 it is far thinner than an ulp of mu 35.3659, where T runs from
 * 12.6 through the maximal canard down to 113), so the branch steps over
 * it: the first row 1e-3 in ln mu past the last one, 4 times farther while
 * the solve refuses (up to BRANCH_COLLOC_STEP_MU), then steps growing by
 * 1.5 while the rows answer, halved where one refuses, until the rows are
 * back in branch_colloc's domain (b->to_colloc) or at the end (b->landed).
 * Each row is a cold solve's pair with its estimate (at mu 35.4 the Taylor
 * reference is 4.2e-11 from T 113.126945965576, estimate 3.9e-10; bd2x2
 * at tol 1e-10 answered 8.7e-9 off with an estimate of 2.5e-9).  Elsewhere,
 * or where no row answers, BKF_ENUMERIC naming where the branch stuck. */
#define BRANCH_HOP_FIRST 1e-3
/* Past the steep explosion the hop's rows lie in the canard's neighbourhood
 * that colloc_attempt refuses, where the pair's estimate |T_N - T_N/2| / 16
 * is not verified: at nu 0.999 (a walk that found no root, hopped) one row
 * at mu 11.3056 was 1.12 times it off.  Their estimate is the pair's whole
 * difference (16 times), the solve asked for tol / 16 so that it still
 * meets tol. */
#define HOP_EST_FACTOR 16.0
static int branch_hop(branch_ctx *b, int dir, size_t limit, bkf_error *err)
{
    bkf_cycle *c = b->cycle;
    double q = b->last_u[1], mu, nu;
    branch_params(b, q, &mu, &nu);
    size_t missed = b->missed;
    b->stuck = 0;
    b->missed = 0;
    const double sign = b->mirror_shots ? -1.0 : 1.0;
    const double tol = b->options.tol;
    int hops = b->along == BKF_CYCLE_ALONG_MU && dir > 0 &&
               (b->options.stepper == BKF_STEPPER_AUTO || b->options.stepper == BKF_STEPPER_COLLOCATION);
    double h = BRANCH_HOP_FIRST;
    size_t rows = 0;
    bkf_error row_err = {0};
    while (hops && b->visit_status == 0 && b->rows < limit) {
        double qn = q + dir * h, mu_n, nu_n;
        if ((qn - b->q_to) * dir >= 0.0) qn = b->q_to;
        qn = branch_row_params(b, qn, &mu_n, &nu_n);
        cycle_flow_set(&c->flow, mu_n, sign * nu_n);
        c->flow.rhs_calls = c->flow.jacobian_calls = 0;
        if (!c->colloc && !(c->colloc = bkf_colloc_alloc())) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
        bkf_colloc_result r;
        int rc = bkf_colloc_guess_relaxation(c->colloc, mu_n, sign * nu_n, bkf_asym_period_leading(mu_n, nu_n),
                                             cycle_colloc_turn_tol(tol, mu_n), &row_err);
        if (rc == BKF_OK) rc = bkf_colloc_solve(c->colloc, tol / HOP_EST_FACTOR, &r, &row_err);
        /* (the pair's difference itself, not its sixteenth: HOP_EST_FACTOR) */
        if (rc == BKF_OK) r.period_err *= HOP_EST_FACTOR;
        if (rc == BKF_ENOMEM) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
        if (rc != BKF_OK) {
            c->have_solution = 0;
            if (rows == 0 ? (h *= 4.0) > BRANCH_COLLOC_STEP_MU : (h *= 0.5) < BRANCH_COLLOC_STEP_MIN) break;
            continue;
        }
        b->work_steps += r.interval_solves;
        b->work_shots += r.newton_iterations;
        r.interval_solves = r.newton_iterations = 0;
        if ((rc = branch_colloc_visit(b, &r, mu_n, nu_n, sign < 0.0, err)) != BKF_OK) return rc;
        rows++;
        q = qn;
        b->last_u[0] = log(c->result.section_slope);
        b->last_u[1] = q;
        b->have_last = 1;
        if (q == b->q_to) {
            b->landed = 1;
            return BKF_OK;
        }
        if (branch_colloc_at(b, mu_n, nu_n)) {
            b->to_colloc = 1;
            return BKF_OK;
        }
        h = fmin(1.5 * h, BRANCH_COLLOC_STEP_MU);
    }
    if (b->visit_status != 0 || b->rows >= limit) return BKF_OK;
    if (rows) branch_params(b, q, &mu, &nu);
    return bkf_error_set(err, BKF_ENUMERIC,
                         "branch along %s stuck at mu = %.15g, nu = %.15g (a canard explosion): %zu rows in a "
                         "row missed tol%s%s",
                         b->along == BKF_CYCLE_ALONG_MU ? "mu" : "nu", mu, nu, missed,
                         hops ? "; no collocation row past it answered: " : "", hops ? row_err.message : "");
}

/* The branch past an explosion it is stuck in, by branch_hop: 1 where
 * collocation rows go on from there, 0 where the branch ends (landed, its
 * visit stopped it, its rows spent, or *rc a failure). */
static int branch_over(branch_ctx *b, int dir, size_t limit, int *rc, bkf_error *err)
{
    *rc = branch_hop(b, dir, limit, err);
    return *rc == BKF_OK && b->to_colloc && !b->landed && b->visit_status == 0;
}

/* The shooting continuation's start at q: the slope of a solve there
 * (where the branch's shots are the mirror's, branch_mirrors, so is the
 * slope); the first accepted point is estimated again, from u0. */
static int branch_shooting_start(branch_ctx *b, double q, double *u0, bkf_error *err)
{
    double mu, nu;
    q = branch_row_params(b, q, &mu, &nu);
    int rc = branch_solve_counted(b, mu, b->mirror_shots ? -nu : nu, &b->options, err);
    if (rc != BKF_OK) return rc;
    u0[0] = log(b->cycle->result.section_slope);
    u0[1] = q;
    b->cycle->have_solution = 0;
    return BKF_OK;
}

/* A branch that fails past its first row says where it stopped in the
 * user's parameters (the driver's messages name q, which is ln mu along
 * mu). */
static int branch_failed_at(const branch_ctx *b, int rc, bkf_error *err)
{
    if (!bkf_status_is_numerical(rc) || !err || !b->rows || !b->have_last || strstr(err->message, "stuck at"))
        return rc;
    double mu, nu;
    branch_params(b, b->last_u[1], &mu, &nu);
    char why[BKF_ERROR_LEN];
    snprintf(why, sizeof why, "%s", err->message);
    return bkf_error_set(err, rc, "branch along %s stuck at mu = %.15g, nu = %.15g: %s",
                         b->along == BKF_CYCLE_ALONG_MU ? "mu" : "nu", mu, nu, why);
}

static int cycle_branch_body(bkf_cycle_param along, double from, double to, double fixed,
                             const bkf_cycle_options *options, size_t max_points, bkf_cycle_visit visit,
                             void *data, bkf_error *err)
{
    if (!visit) return bkf_error_set(err, BKF_EINPUT, "visit callback is NULL");
    if (along != BKF_CYCLE_ALONG_MU && along != BKF_CYCLE_ALONG_NU)
        return bkf_error_set(err, BKF_EINPUT, "branch parameter must be mu or nu");
    bkf_cycle_options opt = options ? *options : bkf_cycle_options_default();
    opt.warm_start = 1;
    double mu_from = along == BKF_CYCLE_ALONG_MU ? from : fixed;
    double nu_from = along == BKF_CYCLE_ALONG_MU ? fixed : from;
    double mu_to = along == BKF_CYCLE_ALONG_MU ? to : fixed;
    double nu_to = along == BKF_CYCLE_ALONG_MU ? fixed : to;
    int rc = cycle_check_inputs(mu_from, nu_from, &opt, err);
    if (rc == BKF_OK) rc = cycle_check_inputs(mu_to, nu_to, NULL, err);
    if (rc != BKF_OK) return rc;
    if (from == to) return bkf_error_set(err, BKF_EINPUT, "branch needs from != to");

    branch_ctx b = {.along = along, .fixed = fixed, .options = opt, .cycle = bkf_cycle_alloc(),
                    .visit = visit, .visit_data = data, .err = err,
                    .mirror_shots = branch_mirrors(along, from, to, fixed)};
    if (!b.cycle) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    b.cycle->series_off = 1;
    double q_from = along == BKF_CYCLE_ALONG_MU ? log(from) : from;
    double q_to = along == BKF_CYCLE_ALONG_MU ? log(to) : to;
    b.from = from;
    b.to = to;
    b.q_from = q_from;
    b.q_to = q_to;
    double u0[2];
    int dir = q_to > q_from ? 1 : -1;
    if (branch_colloc_at(&b, mu_from, nu_from)) b.to_colloc = 1;
    else rc = branch_shooting_start(&b, q_from, u0, err);
    if (rc != BKF_OK) {
        bkf_cycle_free(b.cycle);
        return rc;
    }

    bkf_cont_options co = bkf_cont_options_default(1);
    co.step_max = along == BKF_CYCLE_ALONG_MU ? 0.7 : 0.05;
    co.step_initial = 0.5 * co.step_max;
    /* The corrector need only come within one first-order step of the
     * branch: each row's estimate corrects the last shot to the cycle at
     * its q (branch_estimate), whose Newton accepts a step of relative size
     * up to 0.1 sqrt(tol). */
    co.newton_tol = fmax(1e-10, 0.1 * sqrt(opt.tol));
    co.stop_index = 1;
    co.stop_min = fmin(q_from, q_to);
    co.stop_max = fmax(q_from, q_to);
    size_t limit = max_points ? max_points : co.max_points;
    bkf_cont_report report;
    /* pseudo-arclength stretches, and amplitude stretches where the branch
     * stands nearly upright in q (a canard) or where a stretch failed;
     * collocation rows where they answer (branch_colloc_at) */
    for (int stretch = 0;; stretch++) {
        if (b.to_colloc) {
            b.to_colloc = b.left_colloc = 0;
            b.missed = 0;
            int first = b.rows == 0;
            rc = branch_colloc(&b, first ? q_from : b.last_u[1], dir, limit, first, err);
            if (rc == BKF_ENOMEM || b.visit_status != 0 || b.rows >= limit || b.landed) break;
            /* shooting from the last row (not visited again), or from the
             * start where its cold collocation solve refused */
            rc = branch_shooting_start(&b, b.rows ? b.last_u[1] : q_from, u0, err);
            if (rc != BKF_OK) break;
            b.skip_visit = b.rows > 0;
        }
        co.max_points = limit - b.rows + (b.skip_visit ? 1 : 0);
        b.steep = 0;
        rc = bkf_cont_run(branch_residual, branch_accept, &b, u0, 1, dir, &co, &report, err);
        /* the user's input was checked above: a stretch the continuation
         * refuses as bad input is the branch's own failure */
        if (rc == BKF_EINPUT) {
            char why[BKF_ERROR_LEN];
            snprintf(why, sizeof why, "%s", err ? err->message : "");
            rc = bkf_error_set(err, BKF_ENUMERIC, "the continuation refused the branch's stretch: %.200s", why);
        }
        if (b.visit_status != 0 || b.rows >= limit) break;
        if (b.stuck) {
            if (branch_over(&b, dir, limit, &rc, err)) continue;
            break;
        }
        if (b.to_colloc) continue;
        if (rc == BKF_OK && !b.steep) break;
        if (rc != BKF_OK && (rc != BKF_ENUMERIC || !b.have_last || b.rows == 0 || stretch >= 10)) break;
        bkf_error walk_err;
        int walk = branch_amplitude(&b, dir, limit, rc != BKF_OK, &walk_err);
        if (b.visit_status != 0 || b.rows >= limit || (walk == BKF_OK && b.landed)) {
            rc = BKF_OK;
            break;
        }
        if (walk == BKF_OK && b.stuck) {
            if (branch_over(&b, dir, limit, &rc, err)) continue;
            break;
        }
        if (walk == BKF_OK && b.to_colloc) continue;
        if (bkf_status_is_numerical(walk) && b.rows && b.have_last) {
            /* a walk that found no root in the explosion (nu 0.999 with
             * collocation asked for: "no root of G" at mu 11.2141) goes over
             * it as a stuck branch does, or fails with its own message */
            bkf_error hop_err;
            int hop;
            if (branch_over(&b, dir, limit, &hop, &hop_err)) continue;
            if (hop == BKF_OK || hop == BKF_ENOMEM) {
                if (hop == BKF_ENOMEM) *err = hop_err;
                rc = hop;
                break;
            }
        }
        if (walk != BKF_OK) {
            /* the stretch's own failure says more when the walk got nowhere */
            if (rc == BKF_OK) *err = walk_err;
            rc = walk;
            break;
        }
        memcpy(u0, b.last_u, sizeof u0);
        b.skip_visit = 1;
    }
    rc = branch_failed_at(&b, rc, err);
    bkf_cycle_free(b.cycle);
    if (b.visit_status > 0) return b.visit_status;
    /* the driver's own row budget (no max_points asked) is not an end: a
     * branch that spent it short of `to` (steps shrunk to creeping, as
     * towards nu -0.999 at mu 1e3, where the section sits at the knee) is
     * reported, never passed off as complete */
    if (rc == BKF_OK && !max_points && b.visit_status == 0 && b.rows >= limit && b.have_last &&
        fabs(b.last_u[1] - q_to) > 1e-12 * fmax(1.0, fabs(q_to))) {
        int mu_along = along == BKF_CYCLE_ALONG_MU;
        return bkf_error_set(err, BKF_EBUDGET,
                             "branch along %s stopped after %zu rows at %s = %.17g, short of its end %.17g "
                             "(the steps had shrunk; continue from there or split the range)",
                             mu_along ? "mu" : "nu", b.rows, mu_along ? "mu" : "nu",
                             mu_along ? exp(b.last_u[1]) : b.last_u[1], to);
    }
    if (rc == BKF_OK && b.visit_status == 0 && b.rows < limit && b.have_last &&
        fabs(b.last_u[1] - q_to) > 1e-12 * fmax(1.0, fabs(q_to)))
        return bkf_error_set(err, BKF_ENUMERIC, "branch ended at q = %.17g before its end %.17g (canard)",
                             b.last_u[1], q_to);
    if (b.visit_status < 0) return BKF_OK;
    return rc;
}

/* The two halves of a branch along nu split at nu = 0 (branch_mirrors):
 * the second half's first row is the first half's last, so it is not
 * visited again, and its work goes to the row after it. */
typedef struct {
    bkf_cycle_visit visit;
    void *data;
    size_t rows;
    int skip_first, stopped;
    size_t rhs, jac, steps, shots;
} branch_halves;

static int branch_halves_visit(const bkf_cycle_result *point, void *data)
{
    branch_halves *h = data;
    if (h->skip_first) {
        h->skip_first = 0;
        h->rhs = point->rhs_calls;
        h->jac = point->jacobian_calls;
        h->steps = point->steps;
        h->shots = point->newton_iterations;
        return 0;
    }
    bkf_cycle_result r = *point;
    r.rhs_calls += h->rhs;
    r.jacobian_calls += h->jac;
    r.steps += h->steps;
    r.newton_iterations += h->shots;
    h->rhs = h->jac = h->steps = h->shots = 0;
    h->rows++;
    int stop = h->visit(&r, h->data);
    if (stop) h->stopped = 1;
    return stop;
}

int bkf_cycle_branch(bkf_cycle_param along, double from, double to, double fixed,
                     const bkf_cycle_options *options, size_t max_points, bkf_cycle_visit visit,
                     void *data, bkf_error *err)
{
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    int rc;
    if (along == BKF_CYCLE_ALONG_NU && visit && branch_mirrors(along, fmin(from, 0.0), fmin(to, 0.0), fixed) &&
        from * to < 0) {
        branch_halves h = {.visit = visit, .data = data};
        rc = cycle_branch_body(along, from, 0.0, fixed, options, max_points, branch_halves_visit, &h, err);
        if (rc == BKF_OK && !h.stopped && (!max_points || h.rows < max_points)) {
            h.skip_first = 1;
            rc = cycle_branch_body(along, 0.0, to, fixed, options, max_points ? max_points - h.rows + 1 : 0,
                                   branch_halves_visit, &h, err);
        }
    } else {
        rc = cycle_branch_body(along, from, to, fixed, options, max_points, visit, data, err);
    }
    bkf_gsl_handler_pop(handler);
    return rc;
}

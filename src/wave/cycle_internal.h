/* Internal to the cycle (src/wave/cycle.c, cycle_flow.c, cycle_shoot.c,
 * cycle_colloc.c, cycle_branch.c): the object's layout, the tuning
 * constants and the pieces the files share.  Dependencies point one way:
 * cycle_branch.c -> cycle.c (the solve) -> cycle_colloc.c -> cycle_shoot.c
 * -> cycle_flow.c.  Not installed, not part of the API. */
#ifndef BKFRONT_CYCLE_INTERNAL_H
#define BKFRONT_CYCLE_INTERNAL_H

#include <gsl/gsl_odeiv2.h>
#include <stddef.h>

#include "bkfront/colloc.h"
#include "bkfront/cycle.h"

enum { DIM = 5, IX = 0, IY = 1, IVX = 2, IVY = 3, IL = 4 };
/* Branch shots add the sensitivity (px, py) = d(x, y)/dq to the parameter
 * q of the branch (ln mu or nu): the continuation's parameter derivative
 * then comes from the same integration as the rest, where a difference
 * quotient over any fixed step in q either straddled the canard explosion
 * (at mu 10 it is narrower in nu than the step 1e-6: the tangent turned
 * and the steps fell below step_min) or drowned in its noise. */
enum { DIM_SENS = 7, IPX = 5, IPY = 6 };

/* Above this mu the explicit stepper's step is limited by stability, not
 * accuracy (the fast rate is ~mu); measured crossover, see docs/benchmarks.md. */
#define STIFF_MU BKF_CYCLE_STIFF_MU
#define EXPLICIT_MU_MAX BKF_CYCLE_EXPLICIT_MU_MAX
/* Ratio of the two integration tolerances whose answers give the error
 * estimate. */
#define TOL_RATIO 10.0
#define MAX_STEPS_PER_PERIOD 200000
#define MAX_NEWTON 60
/* Inverted brackets (noise above the distance to the cycle) tolerated
 * before Newton gives up at a tolerance. */
#define MAX_INVERSIONS 3
#define MAX_TURN 1.0         /* radians per step about the equilibrium */
/* Largest ratio of the coarse tolerance to the integration tolerance for which
 * the coarse solve serves as the looser solve of the error estimate. */
#define FAST_SPAN 100.0
/* An answer is accepted when its error estimate is below tol / ACCEPT_MARGIN:
 * the estimate is trusted to a factor 3 (period_error), so an estimate just
 * under tol could still hide an error above it (measured: 1.06e-6 at tol
 * 1e-6 with an estimate of 9.8e-7, mu 32.25, nu 0.999). */
#define ACCEPT_MARGIN 3.0

typedef struct {
    double mu, nu, a, b;
    int sens;  /* 0: DIM states; 1: DIM_SENS, (px, py) along ln mu; 2: along nu */
    size_t rhs_calls, jacobian_calls;
} flow_params;

static inline size_t flow_dim(const flow_params *p) { return p->sens ? DIM_SENS : DIM; }

/* An integrator: one GSL step/control/evolve set for one tolerance. */
typedef struct {
    gsl_odeiv2_driver *driver; /* NULL for the closed-form extrapolation stepper */
    gsl_odeiv2_step *step;
    gsl_odeiv2_control *control;
    gsl_odeiv2_evolve *evolve;
    gsl_odeiv2_system system;
    flow_params *flow;
    int row_target; /* extrapolation: the row at which a step is expected to converge */
    double tol;
    size_t steps;
    double max_turn; /* the turn limit of this integrator's shots */
    size_t capped;   /* steps shortened by the turn limit (shoot) */
    int noisy;       /* Newton gave up: the returns are below this tolerance's noise */
    int rounding;    /* shoot carries the rounding's covariance (conditioning_floor) */
    int in_fold_check; /* extrapolation: integrating a fold-crossing step's halves (bd_fold_check) */
} integrator;

typedef struct {
    double t;
    double s[2];
} node;

struct bkf_cycle {
    flow_params flow;
    int have_solution;
    bkf_cycle_result result;
    double section_y; /* section y of the last solution, in its own coordinates */
    double warm_slope; /* if > 0: start the next solve from this f'(0) (branches) */
    /* nodes of the final integration, for the profile */
    node *nodes;
    size_t node_count, node_capacity;
    double profile_tol;
    bkf_stepper_kind profile_stepper;
    bkf_colloc *colloc; /* the collocation engine and its last solution (warm starts) */
    /* the automatic choice keeps shooting up to mu 1 (the branch's rows:
     * its amplitude walk starts from a shooting solve's section point; from
     * the series path's, the canard branches at nu +-0.999 found no root of
     * G, and the branch cost test's mu 0.1 -> 1e4 row rose to 1.30 cold
     * solves) */
    int series_off;
};

static inline double lienard_F(double x) { return x * x * x / 3.0 - x; }

/* The largest true error of T per unit local tolerance times T, measured
 * against the Taylor reference: 11 at mu 31, nu 0.99, local tol 1e-12
 * (relative to the cycle's size, as below), 5.3 at mu 30.5, nu 0.5, local
 * tol 8.7e-7, where |T_a - T_b| was 20 times smaller; over mu 20-100 x
 * |nu| <= 0.99 at tol 1e-4 up to 16 (mu 39.86, nu -0.51: true 3.99 times
 * the estimate with the floor at 4, a third of 11, as it was).  The
 * accepted value is the table's diagonal, but the step is controlled on
 * the error of the row below it, and on the slow branches an error of tol
 * in position is mu tol in time.  At 16 the floor costs 0-4% more work
 * (mu 30-1e4, tol 1e-4..1e-8). */
#define BD_ERROR_PER_TOL 16.0
/* The same for rk8pd: 0.037 at the classic pair's local tolerances, but up
 * to about 0.3 at the loose-tol fast path's (local 1e-6 of the cycle's
 * size: mu 7.47, nu -0.79, tol 1e-5 true 4.7 times an estimate floored at
 * 0.02; mu 3.21, nu -0.65, tol 1e-6 6.4 times), where the errors of two
 * local tolerances a factor 10 apart coincide.  At 0.4 no estimate
 * flattered over mu 0.01-30 x |nu| <= 0.99 x tol 1e-4..1e-10 (test
 * cycle_rk8pd_estimates_honest_at_loose_tol); the fast path then no longer
 * answers tol 1e-6 (the classic pair does: 86 against 51 us a point over
 * mu 0.3-10), elsewhere the work is unchanged. */
#define RK8PD_ERROR_PER_TOL 0.4

typedef double (*event_fn)(const flow_params *p, const double *s, double *gdot);

typedef struct {
    double period;       /* return time */
    double y_return;     /* P(y0) */
    double dP;           /* P'(y0) = dy/dy0 at the return (y' = 0 on the section) */
    double dT;           /* dT/dy0 */
    double log_mult;     /* L at the return */
    double xmax, xmin;
    double px, py;       /* the parameter sensitivity at the return (branch shots) */
    double xdot;         /* x' at the return */
    double rounding[3];  /* with in->rounding: the rounding's covariance (xx, xy, yy) at the return */
} shot;

typedef struct {
    double period, log_mult, y0, xmax, xmin, return_slope;
    double dT;    /* dT/dy0 at the fixed point */
    double tol;   /* integration tolerance of the solve */
} converged;

/* The tighter solve of an error-estimate pair turns by at most half as much
 * per step as the looser one.  Where the turn limit rather than the
 * tolerance sets the steps (small cycles near the Hopf point, and about a
 * quarter of bsimp's steps at mu >= 100), both solves would otherwise take
 * the very same steps and |T_a - T_b| would miss their error: at mu = 1e-3,
 * nu = 0, tol 1e-3 it was 1.8e-15 against a true 3.9e-11.  With different
 * steps everywhere the difference measures the looser solve's error. */
static inline void tighten_turn(integrator *tighter) { tighter->max_turn = 0.5 * MAX_TURN; }

/* Below these local tolerances the steppers only accumulate rounding
 * (measured: bsimp at 1e-15 takes ~1e5 steps a period at mu = 1e4). */
static inline double tol_floor_of(bkf_stepper_kind kind) { return kind != BKF_STEPPER_EXPLICIT ? 1e-14 : 1e-16; }

/* Collocation stays out of the canard's neighbourhood only where the
 * explosion is steep or where its cold start misjudges it.  Up to |nu|
 * 0.98 the explosion lies at mu <= 5.6 and is mild (T 8.7 -> 12.3 over
 * mu 1.9 -> 2.2 at nu 0.96, against 9.4 -> 18 over 3.6 -> 3.7 at 0.99):
 * at nu 0.95-0.98, mu 1.2-5.5, tol 1e-8..1e-12 (520 points a tol,
 * against the Taylor reference) every answer was within tol, estimates
 * at most 0.72 of the truth.  At nu < 0 the turn from the section point
 * x = nu lands with estimates that flatter (mu 2.241, nu -0.97, tol 1e-8:
 * 3.7 times; mu 1.844, nu -0.95, tol 1e-10: 1.46), the mirror's at -nu
 * do not (0.04, 0.06): a branch along mu solves the mirror. */
#define COLLOC_CANARD_STEEP_NU 0.98
/* From this mu (past the canard explosion, 8 mu^2 (1 - |nu|) >= 3) the
 * cold start lands from the left slow branch (bkf_colloc_guess_relaxation):
 * a quarter of a turn instead of a whole one, 0.27-0.38 of the Gauss steps
 * of the landing at mu 30-1e4.  The branch attracts like exp(-0.15 mu^2)
 * on the way to the fold (colloc.c, LANDING_X): below 10 the slow-fast
 * picture it relies on fades. */
#define COLLOC_RELAXATION_MU 10.0

/* The automatic choice of a solve: collocation where it is faster than
 * shooting, measured by wall time per cold solve at tol 1e-10
 * (docs/benchmarks.md, 2026-11-25 colloc2; shared machine): 0.26-0.78 of
 * shooting's from mu 10 to 1e4, 1.4 times shooting's at mu 1, nu 0.
 * At tol 1e-8 it ties from mu 1e3 (its mesh costs about what it does at
 * 1e-10, colloc_turn_tol); looser tolerances stay with shooting, whose
 * switch the tests hold.  Where it refuses (canards, the rounding floor)
 * the solve shoots. */
#define COLLOC_AUTO_MU_MIN 10.0
#define COLLOC_AUTO_MU_MAX 1e4
#define COLLOC_AUTO_TOL_MAX 1e-10
/* and only in the relaxation regime, mu^2 (1 - |nu|) at least this: near
 * the Hopf point and the canard (gamma 100, nu 0.9999 in the extremes
 * matrix) the Floquet products were not checked with it.  1 (was 2): mu
 * 10, |nu| 0.98-0.99, where collocation took 106 us against rk8pd's 590
 * (T within 1.4e-12 of rk8pd's at tol 1e-12; the extremes matrix and the
 * Floquet tests pass). */
#define COLLOC_AUTO_RELAXATION 1.0
/* Up to mu 1 the series path (bkf_colloc_guess_series) from tol 1e-6 down:
 * callgrind instructions per cold solve (docs/benchmarks.md, colsmall),
 * against rk8pd's over mu 3e-3..1 x nu 0, 0.3, -0.6, 0.85, -0.95, 0.999,
 * -0.9999: 0.36-0.69 at tol 1e-10 (217-507k against 404-935k), 0.44-0.84 at
 * tol 1e-6 but 1.00-1.02 at nu -0.9999 from mu 0.5 (169k against 165k:
 * two shots there), 0.38-0.69 at tol 1e-8 and 0.44-0.56 at 1e-12.
 * Beyond the series' radius it declines (COLLOC_SERIES_RESIDUAL_MAX). */
#define COLLOC_AUTO_SERIES_TOL_MAX 1e-6

/* cycle_flow.c */
double cycle_flow_xdot(const flow_params *p, const double *s);
void cycle_flow_set(flow_params *p, double mu, double nu);
int cycle_canard_window(double mu, double nu);
int cycle_canard_neighbourhood(double mu, double nu);
bkf_stepper_kind cycle_shooting_stepper(double mu, double tol);
bkf_stepper_kind cycle_solve_shooting_stepper(double mu, double nu, double tol);
int cycle_integrator_init(integrator *in, flow_params *flow, bkf_stepper_kind kind, int restarts,
                          double tol);
void cycle_integrator_free(integrator *in);
void cycle_integrator_reset(integrator *in);
int cycle_integrator_apply(integrator *in, double *t, double t1, double *h, double *s);
int cycle_integrator_to(integrator *in, double t0, double *s, double t1);
int cycle_locate_event(integrator *in, const flow_params *p, event_fn g, double t0,
                       const double *s0, double t1, const double *s1, double *t_root,
                       double *s);
double cycle_event_section(const flow_params *p, const double *s, double *gdot);
double cycle_event_extremum(const flow_params *p, const double *s, double *gdot);

/* cycle_shoot.c */
int cycle_node_push(bkf_cycle *c, double t, const double *s);
int cycle_shoot(integrator *main_in, integrator *aux, flow_params *p, double y0, const double *p0,
                bkf_cycle *keep, shot *out, bkf_error *err);
double cycle_section_y_of_slope(const flow_params *p, double w);
double cycle_guess_slope(double mu, double nu);
double cycle_capped_floor(double period_err, const integrator *looser, double period);
double cycle_error_per_tol(bkf_stepper_kind kind);
double cycle_size(double nu);
double cycle_period_error(const converged *a, const converged *b, const flow_params *p,
                          bkf_stepper_kind kind, double cond_floor);
int cycle_conditioning_floor(flow_params *p, bkf_stepper_kind kind, double tol, double y0, double *floor,
                             size_t *steps, bkf_error *err);
double cycle_map_slope(const integrator *in, const shot *sh, double y0, double y_still, double *slope_L);
int cycle_newton_at(bkf_cycle *c, integrator *in, integrator *aux, double *y0, double t_goal,
                    double y_goal, double y_scale, double q_goal, int keep, int land, size_t *iterations,
                    converged *out, bkf_error *err);
int cycle_check_inputs(double mu, double nu, const bkf_cycle_options *o, bkf_error *err);
void cycle_store_result(bkf_cycle *c, const converged *a, const converged *b, double period_err,
                        double y0, bkf_stepper_kind kind, double profile_tol,
                        const integrator *i1, const integrator *i2, const integrator *i3,
                        const integrator *i4, size_t iterations);
double cycle_pair_tol(double tol, double nu, bkf_stepper_kind kind);

/* cycle_colloc.c */
int cycle_colloc_canard_refused(double nu);
double cycle_colloc_turn_tol(double tol, double mu);
int cycle_colloc_attempt(bkf_cycle *c, const bkf_cycle_options *opt, int declinable, bkf_error *err);
int cycle_colloc_store(bkf_cycle *c, const bkf_colloc_result *rp, const bkf_cycle_options *opt, bkf_error *err);
bkf_stepper_kind cycle_solve_stepper(double mu, double nu, double tol, int series_off);

#endif

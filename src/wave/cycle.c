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

static size_t flow_dim(const flow_params *p) { return p->sens ? DIM_SENS : DIM; }

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


/* ---------------------------------------------------------------- flow */

static double lienard_F(double x) { return x * x * x / 3.0 - x; }

/* d(px, py)/dz = A (px, py) + df/dq.  With x' = a y - mu F(x) (a b = mu),
 * y' = (nu - x)/a: along ln mu, df/dq = mu (b y - F(x), -b (nu - x)/a^2)
 * (da/dmu = b); along nu, (0, 1/a). */
static void flow_sens_rhs(const flow_params *p, const double *s, double damping, double *ds)
{
    double x = s[IX];
    ds[IPX] = -damping * s[IPX] + p->a * s[IPY];
    ds[IPY] = -s[IPX] / p->a;
    if (p->sens == 1) {
        ds[IPX] += p->mu * (p->b * s[IY] - lienard_F(x));
        ds[IPY] -= p->mu * p->b * (p->nu - x) / (p->a * p->a);
    } else {
        ds[IPY] += 1.0 / p->a;
    }
}

static int flow_rhs(double t, const double s[], double ds[], void *params)
{
    (void)t;
    flow_params *p = params;
    double x = s[IX];
    double damping = p->mu * (x * x - 1.0);
    p->rhs_calls++;
    ds[IX] = p->a * (s[IY] - p->b * lienard_F(x));
    ds[IY] = (p->nu - x) / p->a;
    ds[IVX] = -damping * s[IVX] + p->a * s[IVY];
    ds[IVY] = -s[IVX] / p->a;
    ds[IL] = -damping;
    if (p->sens) flow_sens_rhs(p, s, damping, ds);
    return GSL_SUCCESS;
}

static int flow_jacobian(double t, const double s[], double *dfds, double dfdt[], void *params)
{
    (void)t;
    flow_params *p = params;
    double x = s[IX];
    double damping = p->mu * (x * x - 1.0);
    double ddamping = 2.0 * p->mu * x;
    p->jacobian_calls++;
    const size_t n = flow_dim(p);
    memset(dfds, 0, sizeof(double) * n * n);
    dfds[IX * n + IX] = -damping;
    dfds[IX * n + IY] = p->a;
    dfds[IY * n + IX] = -1.0 / p->a;
    dfds[IVX * n + IX] = -ddamping * s[IVX];
    dfds[IVX * n + IVX] = -damping;
    dfds[IVX * n + IVY] = p->a;
    dfds[IVY * n + IVX] = -1.0 / p->a;
    dfds[IL * n + IX] = -ddamping;
    if (p->sens) {
        dfds[IPX * n + IX] = -ddamping * s[IPX];
        dfds[IPX * n + IPX] = -damping;
        dfds[IPX * n + IPY] = p->a;
        dfds[IPY * n + IPX] = -1.0 / p->a;
        if (p->sens == 1) {
            dfds[IPX * n + IX] -= p->mu * (x * x - 1.0);
            dfds[IPX * n + IY] = p->mu * p->b;
            dfds[IPY * n + IX] = p->mu * p->b / (p->a * p->a);
        }
    }
    for (size_t i = 0; i < n; i++) dfdt[i] = 0.0;
    return GSL_SUCCESS;
}

static double flow_xdot(const flow_params *p, const double *s)
{
    return p->a * (s[IY] - p->b * lienard_F(s[IX]));
}

static double flow_xddot(const flow_params *p, const double *s)
{
    double x = s[IX];
    return p->a * ((p->nu - x) / p->a - p->b * (x * x - 1.0) * flow_xdot(p, s));
}

static void flow_set(flow_params *p, double mu, double nu)
{
    p->mu = mu;
    p->nu = nu;
    p->a = sqrt(1.0 + mu * mu);
    p->b = mu / p->a;
}

/* ------------------------------------- closed-form extrapolation stepper */

/* Bader-Deuflhard semi-implicit midpoint rule with polynomial extrapolation
 * in h^2, the method of GSL's bsimp, written for this system: the Jacobian
 * of (x, y, vx, vy, L) is block lower triangular, the (x, y) block A repeated
 * for (vx, vy), so I - hJ is solved by two closed-form 2x2 solves and a
 * substitution.  Measured with callgrind, GSL's general LU on the 5x5 matrix
 * was about 82% of bsimp's instructions at mu 100 and 1e4.  L is not under
 * error control (it rides on the steps of (x, y); its error is estimated
 * from the two solves): its absolute control, L growing like mu T, halved
 * the steps at large mu for nothing in T. */
#define BD_ROWS 8
#define BD_ROW_START 4
/* The variational column is controlled this much more loosely than (x, y):
 * it gives Newton's derivative and dT/dy0, whose error multiplies the last
 * Newton step (~1e-7) in the first-order correction of T.  Left out of
 * control, dT was 1% off and T 1.2e-10 (mu 100, nu 0, local tol 1e-11);
 * controlled like (x, y) it doubled the steps. */
#define BD_VARIATIONAL_SLACK 1e4
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
static const int bd_n[BD_ROWS] = {2, 6, 10, 14, 22, 34, 50, 70};

typedef struct {
    double det_inv, ha, h_a, cx, cl;
    double kpx, kpy, kqx; /* h d(px', px', py')/d(x, y, x): the sensitivity's coupling */
} bd_matrix;

/* I - h J(s0); 0 if it is (nearly) singular, which an unstable stretch of
 * the cycle (|x| < 1) can make it at long steps: the step is then shortened. */
static int bd_matrix_set(bd_matrix *m, const flow_params *p, const double *s0, double h)
{
    double x = s0[IX], hd = h * p->mu * (x * x - 1.0);
    double det = 1.0 + hd + h * h;
    if (!(fabs(det) > 1e-6 * (1.0 + fabs(hd) + h * h))) return 0;
    m->det_inv = 1.0 / det;
    m->ha = h * p->a;
    m->h_a = h / p->a;
    m->cx = 2.0 * h * p->mu * x * s0[IVX];
    m->cl = 2.0 * h * p->mu * x;
    if (p->sens) {
        int along_mu = p->sens == 1;
        m->kpx = -2.0 * h * p->mu * x * s0[IPX] - (along_mu ? h * p->mu * (x * x - 1.0) : 0.0);
        m->kpy = along_mu ? h * p->mu * p->b : 0.0;
        m->kqx = along_mu ? h * p->mu * p->b / (p->a * p->a) : 0.0;
    }
    return 1;
}

/* One semi-implicit midpoint pass over H in n substeps from s0 (f0 = f(s0)),
 * the right-hand side and the block solve written out on scalars: with
 * arrays of 5 and calls per substep it cost 245 instructions a substep
 * (callgrind, mu 1e4), most of them loads, stores and two divisions. */
static int bd_midpoint(flow_params *p, const double *s0, const double *f0, double H, int n, double *out)
{
    double hs = H / n;
    bd_matrix m;
    if (!bd_matrix_set(&m, p, s0, hs)) return 0;
    const double a = p->a, ia = 1.0 / p->a, mu = p->mu, nu = p->nu;
    const double di = m.det_inv, ha = m.ha, h_a = m.h_a, cx = m.cx, cl = m.cl;
    /* z = (I - hs J)^-1 r: the (x, y) block, then the variational block with
     * its coupling to z0, then L by substitution */
#define BD_SOLVE(r0, r1, r2, r3, r4)                                                              \
    do {                                                                                          \
        z0 = ((r0) + ha * (r1)) * di;                                                             \
        z1 = (r1) - h_a * z0;                                                                     \
        z2 = ((r2) - cx * z0 + ha * (r3)) * di;                                                   \
        z3 = (r3) - h_a * z2;                                                                     \
        z4 = (r4) - cl * z0;                                                                      \
    } while (0)
    /* the sensitivity (px, py): the (x, y) block again, coupled to (z0, z1) */
#define BD_SOLVE_SENS(r5, r6)                                                                     \
    do {                                                                                          \
        double q6 = (r6) + m.kqx * z0;                                                            \
        z5 = ((r5) + m.kpx * z0 + m.kpy * z1 + ha * q6) * di;                                     \
        z6 = q6 - h_a * z5;                                                                       \
    } while (0)
    const int sens = p->sens != 0;
    double z0, z1, z2, z3, z4, z5 = 0.0, z6 = 0.0, d5 = 0.0, d6 = 0.0, px = 0.0, py = 0.0;
    BD_SOLVE(hs * f0[0], hs * f0[1], hs * f0[2], hs * f0[3], hs * f0[4]);
    if (sens) {
        BD_SOLVE_SENS(hs * f0[IPX], hs * f0[IPY]);
        d5 = z5;
        d6 = z6;
        px = s0[IPX] + d5;
        py = s0[IPY] + d6;
    }
    double d0 = z0, d1 = z1, d2 = z2, d3 = z3, d4 = z4;
    double x = s0[0] + d0, y = s0[1] + d1, vx = s0[2] + d2, vy = s0[3] + d3, L = s0[4] + d4;
    for (int k = 1; k <= n; k++) {
        double damping = mu * (x * x - 1.0);
        double g0 = a * y - mu * (x * x * x / 3.0 - x), g1 = (nu - x) * ia;
        double g2 = -damping * vx + a * vy, g3 = -vx * ia, g4 = -damping;
        BD_SOLVE(hs * g0 - d0, hs * g1 - d1, hs * g2 - d2, hs * g3 - d3, hs * g4 - d4);
        if (sens) {
            double st[DIM_SENS] = {x, y, vx, vy, L, px, py}, gs[DIM_SENS];
            flow_sens_rhs(p, st, damping, gs);
            BD_SOLVE_SENS(hs * gs[IPX] - d5, hs * gs[IPY] - d6);
            if (k < n) {
                d5 += 2.0 * z5;
                d6 += 2.0 * z6;
                px += d5;
                py += d6;
            }
        }
        if (k == n) break;
        d0 += 2.0 * z0;
        d1 += 2.0 * z1;
        d2 += 2.0 * z2;
        d3 += 2.0 * z3;
        d4 += 2.0 * z4;
        x += d0;
        y += d1;
        vx += d2;
        vy += d3;
        L += d4;
    }
#undef BD_SOLVE
#undef BD_SOLVE_SENS
    if (sens) {
        out[IPX] = px + z5;
        out[IPY] = py + z6;
    }
    out[0] = x + z0;
    out[1] = y + z1;
    out[2] = vx + z2;
    out[3] = vy + z3;
    out[4] = L + z4;
    p->rhs_calls += (size_t)n;
    return isfinite(out[IX]) && isfinite(out[IY]);
}

/* Work of rows 0..j in right-hand sides (a row of n substeps costs n). */
static double bd_work(int j)
{
    double w = 1.0;
    for (int i = 0; i <= j; i++) w += bd_n[i];
    return w;
}

static int bd_apply(integrator *in, double *t, double t1, double *h, double *s);

/* A step that leaves an attracting branch of the slow manifold (|x| > 1)
 * for the repelling middle (|x| < 1) crosses the fold, where the orbit
 * starts its jump: there the tableau's rows can agree with each other
 * while all are off, and the row difference is no error estimate.  At mu
 * 45.5, nu 0.9, local tol 1e-9 one such step (H 1.39, x 1.044 -> 0.962)
 * moved T by -1.09e-5, 94 times tol T, while every other step of the turn
 * moved it by under 1.2e-8 (each step's contribution measured by finishing
 * the turn from its end at local tol 1e-14); at tol 1e-8 and 1e-9 the
 * pair then differed by 2.9e-6 while both were 1.1-1.4e-5 off.  Such a
 * step is accepted only if the same interval integrated in steps of at
 * most half of it agrees within tol: a local error measured, not
 * extrapolated.  1 when (x1, y1) passes. */
static int bd_fold_check(integrator *in, double t, double H, const double *s0, const double *s1)
{
    if (in->in_fold_check || !((s0[IX] * s0[IX] > 1.0) && (s1[IX] * s1[IX] < 1.0))) return 1;
    integrator half = *in;
    half.in_fold_check = 1;
    half.row_target = BD_ROW_START;
    double s[DIM_SENS], tt = t, t1 = t + H, h = 0.5 * H;
    memcpy(s, s0, sizeof(double) * flow_dim(in->flow));
    for (int guard = 0; tt < t1; guard++) {
        if (guard > 10000 || bd_apply(&half, &tt, t1, &h, s) != BKF_OK) return 0;
        if (h > 0.5 * H) h = 0.5 * H;
    }
    for (int i = IX; i <= IY; i++)
        if (!(fabs(s[i] - s1[i]) <= in->tol * (1.0 + fabs(s[i])))) return 0;
    return 1;
}

/* One accepted step from (*t, s) of at most min(*h, t1 - *t), with the
 * step and order control of Hairer and Wanner's ODEX/SEULEX (the work per
 * unit step decides between neighbouring rows); *h is the next step. */
static int bd_apply(integrator *in, double *t, double t1, double *h, double *s)
{
    flow_params *p = in->flow;
    double f0[DIM_SENS], table[BD_ROWS][DIM_SENS], row[DIM_SENS], hopt[BD_ROWS], work[BD_ROWS];
    const int n = (int)flow_dim(p);
    int k = in->row_target;
    flow_rhs(0.0, s, f0, p);
    for (int attempt = 0; attempt < 200; attempt++) {
        p->jacobian_calls++; /* one Jacobian, at s, per attempt */
        int last = *t + *h >= t1;
        double H = last ? t1 - *t : *h;
        int accepted = -1, jmax = k + 1 < BD_ROWS ? k + 1 : BD_ROWS - 1, j;
        double reduce = 0.25;
        for (j = 0; j <= jmax; j++) {
            if (!bd_midpoint(p, s, f0, H, bd_n[j], row)) break;
            /* Neville's scheme in (H/n)^2 toward 0, one row at a time */
            for (int c = 1; c <= j; c++) {
                double q = (double)bd_n[j] / bd_n[j - c];
                q = 1.0 / (q * q - 1.0);
                for (int i = 0; i < n; i++) {
                    double prev = table[c - 1][i];
                    table[c - 1][i] = row[i];
                    row[i] += (row[i] - prev) * q;
                }
            }
            memcpy(table[j], row, sizeof(double) * (size_t)n);
            /* rows below k - 2 can neither be accepted nor enter the
             * choice of the next row */
            if (j == 0 || j < k - 2) continue;
            double e = 0.0;
            for (int i = IX; i < n; i++) {
                if (i == IL) continue;
                double d = fabs(table[j][i] - table[j - 1][i]) / (in->tol * (1.0 + fabs(table[j][i])));
                if (i >= IVX) d /= BD_VARIATIONAL_SLACK;
                if (d > e) e = d;
            }
            if (!isfinite(e)) break;
            double fac = e > 0.0 ? 0.94 * pow(0.65 / e, 1.0 / (2 * j + 1)) : 4.0;
            hopt[j] = H * fmin(4.0, fmax(0.02, fac));
            work[j] = bd_work(j) / hopt[j];
            if (j >= k - 1 && e <= 1.0) {
                accepted = j;
                break;
            }
            reduce = hopt[j] / H;
        }
        if (accepted >= 0 && !bd_fold_check(in, *t, H, s, table[accepted])) {
            *h = 0.5 * H;
            if (!(fabs(*h) > 1e-14 * fmax(1.0, fabs(*t)))) return BKF_ENUMERIC;
            continue;
        }
        if (accepted < 0) {
            /* a failed pass (singular or non-finite) halves the step */
            *h = H * (j <= jmax ? 0.5 : fmin(0.5, reduce));
            if (!(fabs(*h) > 1e-14 * fmax(1.0, fabs(*t)))) return BKF_ENUMERIC;
            continue;
        }
        memcpy(s, table[accepted], sizeof(double) * (size_t)n);
        *t = last ? t1 : *t + H;
        int knew = accepted;
        if (accepted >= 2 && work[accepted - 1] < 0.8 * work[accepted]) knew = accepted - 1;
        double hn = hopt[knew];
        if (knew == accepted && accepted + 1 < BD_ROWS - 1 &&
            (accepted == 1 || work[accepted] < 0.9 * work[accepted - 1])) {
            hn = hopt[accepted] * bd_work(accepted + 1) / bd_work(accepted);
            knew = accepted + 1;
        }
        in->row_target = knew < 2 ? 2 : knew;
        if (!last || hn < *h) *h = hn;
        return BKF_OK;
    }
    return BKF_ENUMERIC;
}

/* ---------------------------------------------------------- integrator */

/* The implicit stepper is Bader-Deuflhard (bsimp): one-step, so restarts
 * from a stored node (event location, profile) cost nothing extra, and
 * measured far more accurate per tolerance than msbdf near the knees, where
 * the msbdf period wandered at 1e-7 relative whatever the tolerance
 * (mu = 1e4, nu = 0.999). */
static double canard_x(double mu, double nu)
{
    return 8.0 * mu * mu * (1.0 - fabs(nu));
}

/* The canard explosion's neighbourhood (it is at 8 mu^2 (1 - |nu|) ~ 1),
 * where T is ill-conditioned: see conditioning_floor. */
static int canard_window(double mu, double nu)
{
    double x = canard_x(mu, nu);
    return mu >= 1.0 && x >= 0.5 && x <= 2.0;
}

/* The wider neighbourhood where the stiff pair (bd2x2, bsimp) flattered
 * (issue 20, stiffwin): cold solves over x = 8 mu^2 (1 - |nu|) in
 * [0.2, 10] x |nu| 0.98..0.9999 x mu 1..90 x tol 1e-6..1e-12 against the
 * Taylor reference found true/estimated above 3 for bd2x2 or bsimp at x
 * 0.70-6.25 (bsimp at tol 1e-12, nu 0.9999: 8.7 at mu 79.7, answers outside
 * tol at mu 40-69; bd2x2 at tol 1e-6, nu 0.9995: 6.6 at mu 31.86), none
 * below x 0.70 and one above 7 (bsimp, 3.07 at x 8.65, nu 0.999, tol
 * 1e-12); rk8pd at most 1.84 over the whole scan. */
#define CANARD_STIFF_X_MAX 7.0
static int canard_neighbourhood(double mu, double nu)
{
    double x = canard_x(mu, nu);
    return mu >= 1.0 && x >= 0.5 && x <= CANARD_STIFF_X_MAX;
}

/* bd2x2 above STIFF_MU at tol 1e-8..1e-12: measured per T (docs/benchmarks.md,
 * issue 20), rk8pd's stability-limited steps (about 140 a unit of mu per
 * period) cost more than bd2x2 from mu 12-20 on there (mu 30, tol 1e-10:
 * 1.7 ms against 0.73-0.81 ms).  At tol 1e-6 rk8pd is as fast up to mu 30,
 * and bd2x2's loose-tolerance estimate flattered by 3.4 at mu 27.5, nu 0.5,
 * tol 1e-2; below BKF_CYCLE_STIFF_TOL_MIN bd2x2's estimate floor refuses.
 * There rk8pd answers up to EXPLICIT_MU_MAX, as before the switch moved. */
static bkf_stepper_kind shooting_stepper(double mu, double tol)
{
    if (mu > EXPLICIT_MU_MAX ||
        (mu > STIFF_MU && tol >= BKF_CYCLE_STIFF_TOL_MIN && tol <= BKF_CYCLE_STIFF_TOL_MAX))
        return BKF_STEPPER_EXTRAPOLATION;
    return BKF_STEPPER_EXPLICIT;
}

/* A solve's shooting stepper.  Inside the canard window rk8pd answers at
 * every mu: there the errors of bd2x2 and bsimp grow on the repelling slow
 * branch far beyond their floors while their pair's difference misses them
 * (cold, mu 25-36 by 0.02 at nu 0.9999, tol 1e-6..1e-10, against the Taylor
 * reference: bd2x2 up to 32 times its estimate, bsimp 6.8 and 4 answers
 * outside tol, rk8pd at most 1.03; docs/accuracy.md).  (In the rest of
 * the neighbourhood bd2x2 stays the choice: with its floor there it was
 * honest and took 1.5-3 times less time than rk8pd at tol 1e-6..1e-10;
 * where it refuses, rk8pd answers: bkf_cycle_solve.)  The window holds
 * bd2x2 only near |nu| = 1 (mu > STIFF_MU: |nu| > 0.99937).  (Not the
 * branch's rows: with rk8pd there the branch over the explosion at nu
 * 0.9999, mu 25..40, no longer stepped over it: it ran for over 12 minutes,
 * or ended with fewer than 5 rows past it.) */
static bkf_stepper_kind solve_shooting_stepper(double mu, double nu, double tol)
{
    return canard_window(mu, nu) ? BKF_STEPPER_EXPLICIT : shooting_stepper(mu, tol);
}

const char *bkf_cycle_stepper_name(bkf_stepper_kind kind)
{
    switch (kind) {
    case BKF_STEPPER_AUTO: return "auto";
    case BKF_STEPPER_EXPLICIT: return "rk8pd";
    case BKF_STEPPER_IMPLICIT: return "bsimp";
    case BKF_STEPPER_EXTRAPOLATION: return "bd2x2";
    case BKF_STEPPER_COLLOCATION: return "colloc";
    }
    return NULL;
}

static int integrator_init(integrator *in, flow_params *flow, bkf_stepper_kind kind, int restarts,
                           double tol)
{
    static const double scale[DIM_SENS] = {1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0};
    (void)restarts;
    memset(in, 0, sizeof *in);
    in->flow = flow;
    in->tol = tol;
    in->max_turn = MAX_TURN;
    in->row_target = BD_ROW_START;
    if (kind == BKF_STEPPER_EXTRAPOLATION) return BKF_OK;
    const gsl_odeiv2_step_type *type =
        kind == BKF_STEPPER_IMPLICIT ? gsl_odeiv2_step_bsimp : gsl_odeiv2_step_rk8pd;
    in->system = (gsl_odeiv2_system){flow_rhs, flow_jacobian, flow_dim(flow), flow};
    in->driver = gsl_odeiv2_driver_alloc_scaled_new(&in->system, type, 1e-3, tol, tol, 1.0, 0.0, scale);
    if (!in->driver) return BKF_ENOMEM;
    in->step = in->driver->s;
    in->control = in->driver->c;
    in->evolve = in->driver->e;
    return BKF_OK;
}

static void integrator_free(integrator *in)
{
    if (in->driver) gsl_odeiv2_driver_free(in->driver);
    memset(in, 0, sizeof *in);
}

static void integrator_reset(integrator *in)
{
    in->row_target = BD_ROW_START;
    if (!in->driver) return;
    gsl_odeiv2_evolve_reset(in->evolve);
    gsl_odeiv2_step_reset(in->step);
}

/* One accepted step from *t toward t1 (never past it); *h: the next step. */
static int integrator_apply(integrator *in, double *t, double t1, double *h, double *s)
{
    if (!in->driver) return bd_apply(in, t, t1, h, s);
    return gsl_odeiv2_evolve_apply(in->evolve, in->control, in->step, &in->system, t, t1, h, s) ==
                   GSL_SUCCESS
               ? BKF_OK
               : BKF_ENUMERIC;
}

/* Advance s from t0 to exactly t1 under error control. */
static int integrator_to(integrator *in, double t0, double *s, double t1)
{
    double t = t0, h = t1 - t0;
    if (h == 0.0) return BKF_OK;
    integrator_reset(in);
    for (int guard = 0; t != t1; guard++) {
        if (guard > 100000) return BKF_ENUMERIC;
        /* bsimp can suggest a next step of the wrong sign after a rejected
         * step near t1; GSL treats that as a caller error */
        if ((t1 > t && !(h > 0.0)) || (t1 < t && !(h < 0.0))) h = t1 - t;
        if (integrator_apply(in, &t, t1, &h, s) != BKF_OK) return BKF_ENUMERIC;
        /* A non-finite state has a non-finite error estimate, which the
         * step control does not reject: stop here, never hand it on. */
        if (!isfinite(s[0]) || !isfinite(s[1])) return BKF_ENUMERIC;
        in->steps++;
    }
    return BKF_OK;
}

/* Root in [t0, t1] of g(t) = component value - target, with g' given by the
 * flow, by Newton in time safeguarded by the bracket; each trial state is
 * integrated afresh from (t0, s0).  On return s holds the state at the root. */
typedef double (*event_fn)(const flow_params *p, const double *s, double *gdot);

static int locate_event(integrator *in, const flow_params *p, event_fn g, double t0,
                        const double *s0, double t1, const double *s1, double *t_root,
                        double *s)
{
    double unused;
    double g0 = g(p, s0, &unused), g1 = g(p, s1, &unused);
    double lo = t0, hi = t1, glo = g0;
    double t = t0 + (t1 - t0) * g0 / (g0 - g1);
    if (!(t > t0 && t < t1)) t = 0.5 * (t0 + t1);
    for (int iter = 0; iter < 60; iter++) {
        memcpy(s, s0, sizeof(double) * flow_dim(p));
        if (integrator_to(in, t0, s, t) != BKF_OK) return BKF_ENUMERIC;
        double gdot, gt = g(p, s, &gdot);
        if (gt == 0.0) break;
        if ((gt > 0) == (glo > 0)) {
            lo = t;
            glo = gt;
        } else {
            hi = t;
        }
        double next = t - gt / gdot;
        /* converged: the Newton correction is at rounding level, so keep t
         * (whose state s is in hand) rather than risk the bracket test */
        if (fabs(next - t) <= 4.0 * DBL_EPSILON * fabs(t)) break;
        if (!(next > lo && next < hi) || !isfinite(next)) next = 0.5 * (lo + hi);
        if (hi - lo <= 4.0 * DBL_EPSILON * fabs(t)) break;
        t = next;
    }
    *t_root = t;
    return BKF_OK;
}

static double event_section(const flow_params *p, const double *s, double *gdot)
{
    *gdot = flow_xdot(p, s);
    return s[IX] - p->nu;
}

static double event_extremum(const flow_params *p, const double *s, double *gdot)
{
    *gdot = flow_xddot(p, s);
    return flow_xdot(p, s);
}

/* ------------------------------------------------------------ one period */

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

static int node_push(bkf_cycle *c, double t, const double *s)
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
    double f0x = flow_xdot(p, s0), f0y = (p->nu - s0[IX]) / p->a;
    double f1x = flow_xdot(p, s1), f1y = (p->nu - s1[IX]) / p->a;
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
static int shoot(integrator *main_in, integrator *aux, flow_params *p, double y0, const double *p0,
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
        if (node_push(keep, t, s) != BKF_OK) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    }
    integrator_reset(main_in);
    for (size_t n = 0;; n++) {
        if (n > MAX_STEPS_PER_PERIOD)
            return bkf_error_set(err, BKF_EBUDGET,
                                 "cycle at mu = %.15g, nu = %.15g: no return to the section after %d steps",
                                 p->mu, p->nu, MAX_STEPS_PER_PERIOD);
        memcpy(s_prev, s, sizeof s);
        t_prev = t;
        int rc = integrator_apply(main_in, &t, GSL_POSINF, &h, s);
        main_in->steps++;
        if (rc != BKF_OK || !isfinite(s[IX]) || !isfinite(s[IY]))
            return bkf_error_set(err, BKF_ENUMERIC,
                                 "cycle at mu = %.15g, nu = %.15g: integration failed at z = %g", p->mu,
                                 p->nu, t);
        if (keep) {
            double xd_prev = flow_xdot(p, s_prev), xd = flow_xdot(p, s);
            if ((xd_prev > 0) != (xd > 0)) {
                double te, se[DIM_SENS];
                if (locate_event(aux, p, event_extremum, t_prev, s_prev, t, s, &te, se) != BKF_OK)
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
            double u = s[IX] - p->nu, fp = flow_xdot(p, s), r2 = u * u + fp * fp;
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
        if (keep && node_push(keep, t, s) != BKF_OK)
            return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    }
    double T, sr[DIM_SENS];
    if (locate_event(aux, p, event_section, t_prev, s_prev, t, s, &T, sr) != BKF_OK)
        return bkf_error_set(err, BKF_ENUMERIC,
                             "cycle at mu = %.15g, nu = %.15g: return to the section not located", p->mu,
                             p->nu);
    out->period = T;
    out->y_return = sr[IY];
    out->dP = sr[IVY];
    out->dT = -sr[IVX] / flow_xdot(p, sr);
    out->log_mult = sr[IL];
    out->xmax = xmax;
    out->xmin = xmin;
    out->px = sr[IPX];
    out->py = sr[IPY];
    out->xdot = flow_xdot(p, sr);
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
static double section_y_of_slope(const flow_params *p, double w)
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
static double guess_slope(double mu, double nu)
{
    if (mu < 1.0 || 16.0 * mu * mu * (1.0 - fabs(nu)) < 1.0) return 2.0 * sqrt(1.0 - nu * nu);
    double jump_height = 2.0 / 3.0 + BKF_AIRY_A1 * cbrt((1.0 + nu) * (1.0 + nu)) * pow(mu, -4.0 / 3.0);
    double w = mu * (jump_height - lienard_F(nu));
    return w > 0 ? w : 2.0 * sqrt(1.0 - nu * nu);
}

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
static void tighten_turn(integrator *tighter) { tighter->max_turn = 0.5 * MAX_TURN; }

/* The classic pair (tight tolerances) keeps equal turn limits and instead
 * floors the estimate at the looser solve's local tolerance times T when
 * the limit shortened any of its steps (pessimistic, but the tightest
 * accepted tolerances and the Floquet references depend on it; halving the
 * turn there made bsimp refuse tol 1e-11 at mu 30, nu 0.9999, where its
 * old answer was 1.3e-11 off with an estimate of 8e-12). */
static double capped_floor(double period_err, const integrator *looser, double period)
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
static double error_per_tol(bkf_stepper_kind kind)
{
    return kind == BKF_STEPPER_EXTRAPOLATION ? BD_ERROR_PER_TOL
           : kind != BKF_STEPPER_EXPLICIT    ? 0.25
                                             : RK8PD_ERROR_PER_TOL;
}

/* The cycle's size where it is below 1 (the tolerances are absolute). */
static double cycle_size(double nu)
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
static double period_error(const converged *a, const converged *b, const flow_params *p,
                           bkf_stepper_kind kind, double cond_floor)
{
    int implicit = kind != BKF_STEPPER_EXPLICIT;
    double tol_floor = error_per_tol(kind) * b->tol * b->period / cycle_size(p->nu) *
                       (implicit && canard_neighbourhood(p->mu, p->nu) ? CANARD_ERROR_PER_TOL_FACTOR : 1.0);
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
    if (integrator_init(&in, &q, kind, 0, tol) == BKF_OK && integrator_init(&aux, &q, kind, 1, tol) == BKF_OK) {
        shot sh = {0};
        in.rounding = 1;
        rc = shoot(&in, &aux, &q, y0, NULL, NULL, &sh, err);
        if (rc == BKF_OK) {
            double zx = -1.0 / sh.xdot, zy = sh.dT / (1.0 - fmin(sh.dP, 0.999999));
            double var = zx * zx * sh.rounding[0] + 2.0 * zx * zy * sh.rounding[1] + zy * zy * sh.rounding[2];
            *sigma = var > 0 ? sqrt(var) : 0.0;
        }
    }
    p->rhs_calls += q.rhs_calls;
    p->jacobian_calls += q.jacobian_calls;
    *steps += in.steps + aux.steps;
    integrator_free(&in);
    integrator_free(&aux);
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
static int conditioning_floor(flow_params *p, bkf_stepper_kind kind, double tol, double y0, double *floor,
                              size_t *steps, bkf_error *err)
{
    *floor = 0.0;
    if (!canard_window(p->mu, p->nu) && (kind == BKF_STEPPER_EXPLICIT || !canard_neighbourhood(p->mu, p->nu)))
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
static double map_slope(const integrator *in, const shot *sh, double y0, double y_still, double *slope_L)
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
static int newton_at(bkf_cycle *c, integrator *in, integrator *aux, double *y0, double t_goal,
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
        int rc = shoot(in, aux, p, *y0, NULL, keep ? c : NULL, &sh, err);
        if (rc != BKF_OK) return rc;
        (*iterations)++;
        double g = sh.y_return - *y0;
        double slope_L, dP = map_slope(in, &sh, *y0, y_still, &slope_L);
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

static int check_inputs(double mu, double nu, const bkf_cycle_options *o, bkf_error *err)
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
static void store_result(bkf_cycle *c, const converged *a, const converged *b, double period_err,
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

/* Below these local tolerances the steppers only accumulate rounding
 * (measured: bsimp at 1e-15 takes ~1e5 steps a period at mu = 1e4). */
static double tol_floor_of(bkf_stepper_kind kind) { return kind != BKF_STEPPER_EXPLICIT ? 1e-14 : 1e-16; }

/* The looser local tolerance of the classic error-estimate pair (the
 * tighter is TOL_RATIO below it).  The global error of T is a modest
 * multiple of the local tolerance; the safety factor was measured over the
 * benchmark box (docs/benchmarks.md).  Looser local tolerances buy almost
 * nothing with these steppers, and near |nu| = 1 the cycle is small (radius
 * 2 sqrt(1 - nu^2)): at mu = 1e-3, nu = 0.999, a local 1e-3 let the orbit
 * drift off the weakly attracting cycle and never return to the section. */
static double pair_tol(double tol, double nu, bkf_stepper_kind kind)
{
    double tol_int = fmin(0.1 * tol, 1e-5 * fmin(1.0, sqrt(1.0 - nu * nu)));
    double floor = tol_floor_of(kind);
    return tol_int / TOL_RATIO < floor ? floor * TOL_RATIO : tol_int;
}

/* ------------------------------------------------------ collocation */

/* Up to this mu the cold guess is the Lindstedt series on a uniform mesh
 * (bkf_colloc_guess_series), above it two turns of Gauss steps
 * (bkf_colloc_guess_turn; the cycle attracts like exp(L), L = -7 at mu 1:
 * one turn lands it), or from COLLOC_RELAXATION_MU a quarter turn and one
 * (bkf_colloc_guess_relaxation). */
#define COLLOC_SERIES_MU 1.0
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
static int colloc_canard_refused(double nu)
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
/* From this mu (past the canard explosion, 8 mu^2 (1 - |nu|) >= 3) the
 * cold start lands from the left slow branch (bkf_colloc_guess_relaxation):
 * a quarter of a turn instead of a whole one, 0.27-0.38 of the Gauss steps
 * of the landing at mu 30-1e4.  The branch attracts like exp(-0.15 mu^2)
 * on the way to the fold (colloc.c, LANDING_X): below 10 the slow-fast
 * picture it relies on fades. */
#define COLLOC_RELAXATION_MU 10.0
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
static double colloc_turn_tol(double tol, double mu)
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
    if (integrator_init(&in, p, c->profile_stepper, 1, c->profile_tol) != BKF_OK) {
        integrator_free(&in);
        return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    }
    double xmax = p->nu, xmin = p->nu;
    int rc = BKF_OK;
    for (size_t j = 0; j < c->node_count && rc == BKF_OK; j++) {
        const node *n0 = &c->nodes[j], *n1 = &c->nodes[j + 1 < c->node_count ? j + 1 : 0];
        double s0[DIM] = {n0->s[0], n0->s[1], 0, 0, 0}, s1[DIM] = {n1->s[0], n1->s[1], 0, 0, 0};
        double t1 = j + 1 < c->node_count ? n1->t : c->result.period;
        if ((flow_xdot(p, s0) > 0) == (flow_xdot(p, s1) > 0)) continue;
        double te, se[DIM];
        if (locate_event(&in, p, event_extremum, n0->t, s0, t1, s1, &te, se) != BKF_OK) {
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
    integrator_free(&in);
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
static int colloc_store(bkf_cycle *c, const bkf_colloc_result *r, const bkf_cycle_options *opt, bkf_error *err);

static int colloc_attempt(bkf_cycle *c, const bkf_cycle_options *opt, int declinable, bkf_error *err)
{
    flow_params *p = &c->flow;
    const double mu = p->mu, nu = p->nu;
    /* in the canard's neighbourhood the cyclic solve is conditioned like
     * exp(mu x the time on the repelling branch): shooting with its
     * conditioning floor answers there (up to mu 1 that factor is at most
     * e^T and the series path answers: mu 1, nu -0.96 was refused) */
    double canard = 8.0 * mu * mu * (1.0 - fabs(nu));
    if (mu > COLLOC_SERIES_MU && colloc_canard_refused(nu) && canard > 0.3 && canard < 3.0)
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
                                             colloc_turn_tol(opt->tol, mu), err);
        } else {
            /* a turn from the section point of the guessed slope lands on
             * the cycle, another is the mesh (colloc.h) */
            double T_hint = fmax(2.0 * M_PI, bkf_asym_period_leading(mu, nu));
            rc = bkf_colloc_guess_turn(c->colloc, mu, nu, nu, section_y_of_slope(p, guess_slope(mu, nu)), T_hint,
                                       colloc_turn_tol(opt->tol, mu), err);
        }
        if (rc == BKF_OK) rc = bkf_colloc_solve(c->colloc, opt->tol, &r, err);
    }
    if (rc != BKF_OK) return rc;
    return colloc_store(c, &r, opt, err);
}

/* The collocation solution r (in c->colloc, at c->flow's parameters) as
 * c's solution: its nodes, result and extremes. */
static int colloc_store(bkf_cycle *c, const bkf_colloc_result *rp, const bkf_cycle_options *opt, bkf_error *err)
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
        rc = node_push(c, buf[j], (const double[]){buf[n + j], buf[2 * n + j]});
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

static bkf_stepper_kind solve_stepper(double mu, double nu, double tol, int series_off)
{
    if (!series_off && mu <= COLLOC_SERIES_MU && tol <= COLLOC_AUTO_SERIES_TOL_MAX * (1.0 + 1e-9) &&
        colloc_series_floor(mu, nu, tol) * ACCEPT_MARGIN <= tol && !colloc_series_beyond_radius(mu, nu))
        return BKF_STEPPER_COLLOCATION;
    if (mu >= COLLOC_AUTO_MU_MIN && mu <= COLLOC_AUTO_MU_MAX && tol <= COLLOC_AUTO_TOL_MAX * (1.0 + 1e-9) &&
        mu * mu * (1.0 - fabs(nu)) >= COLLOC_AUTO_RELAXATION)
        return BKF_STEPPER_COLLOCATION;
    return solve_shooting_stepper(mu, nu, tol);
}

static int cycle_solve_body(bkf_cycle *c, double mu, double nu, const bkf_cycle_options *options,
                            bkf_error *err)
{
    if (!c) return bkf_error_set(err, BKF_EINPUT, "cycle object is NULL");
    bkf_cycle_options opt = options ? *options : bkf_cycle_options_default();
    int rc = check_inputs(mu, nu, &opt, err);
    if (rc != BKF_OK) return rc;

    flow_params previous = c->flow;
    double warm_slope = c->have_solution ? c->result.section_slope : 0.0;
    flow_set(&c->flow, mu, nu);
    flow_params *p = &c->flow;
    p->rhs_calls = p->jacobian_calls = 0;
    bkf_stepper_kind kind = opt.stepper;
    if (kind == BKF_STEPPER_AUTO) kind = solve_stepper(mu, nu, opt.tol, c->series_off);
    if (kind == BKF_STEPPER_COLLOCATION) {
        /* c->result is overwritten only on success */
        bkf_cycle_result kept = c->result;
        int had = c->have_solution;
        rc = colloc_attempt(c, &opt, opt.stepper == BKF_STEPPER_AUTO, err);
        if (rc == BKF_OK) return BKF_OK;
        c->result = kept;
        c->have_solution = had;
        if (rc == BKF_ENOMEM) {
            if (had) c->flow = previous;
            return rc;
        }
        kind = solve_shooting_stepper(mu, nu, opt.tol);
        p->rhs_calls = p->jacobian_calls = 0;
    }

    /* (not from a collocation solution: its section point differs from
     * shooting's within tol, and a list's row would then differ from the
     * same point solved alone, as `period --mu 0.5,5` did at mu 5 in the
     * 16th digit once mu 0.5 was collocation's) */
    int warm_shot = opt.warm_start && c->have_solution && strcmp(c->result.stepper, "colloc") != 0;
    double slope = c->warm_slope > 0 ? c->warm_slope : warm_shot ? warm_slope : guess_slope(mu, nu);
    c->warm_slope = 0.0;
    double y0 = section_y_of_slope(p, slope);
    double y_scale = fmax(fabs(y0), 1e-3);

    double tol_int = pair_tol(opt.tol, nu, kind);
    const double tol_floor = tol_floor_of(kind);
    /* bd2x2's coarse stage lands y0 on the cycle for the tight solves,
     * whose first shot then needs no confirming one if its step is below
     * sqrt(q_goal) (see newton_at): at local tol 1e-5 the landing was
     * 1-3e-6 off at mu 1e3-1e4, just too far at tol 1e-10, and cost one
     * more tight shot than a landing at 1e-6 does.  (Not for rk8pd: inside
     * the canard at mu 3.65 the tighter landing changed which relaxed branch
     * points were accepted, and one's estimate flattered by 5.) */
    double land_tol = kind == BKF_STEPPER_EXTRAPOLATION ? fmin(0.1 * sqrt(opt.tol), 1e-5) : 1e-5;
    double tol_loose = fmax(tol_int, land_tol * fmin(1.0, sqrt(1.0 - nu * nu)));
    integrator coarse = {0}, fine = {0}, finer = {0}, aux = {0};
    size_t iterations = 0;
    converged a, b;
    rc = BKF_ENOMEM;
    if (integrator_init(&coarse, p, kind, 0, tol_loose) != BKF_OK ||
        integrator_init(&aux, p, kind, 1, tol_loose) != BKF_OK)
        goto fail_mem;

    /* a Newton step whose square (relative, amplified by 1/(1 - P')) is
     * below q_goal needs no confirming shot: the first-order correction
     * leaves an error of that order */
    double q_goal = 1e-2 * opt.tol;
    /* In the canard region an error made on the repelling slow branch grows
     * like exp(mu x the time spent there) before the orbit jumps: at mu 3.65,
     * nu 0.99 the returns at the coarse tolerance 1.4e-6 were 3e-3 off, P
     * looked decreasing and Newton cycled for 60 steps.  Such noise shows as
     * brackets that invert; the coarse solve then tightens its tolerance. */
    for (double y_start = y0;;) {
        rc = newton_at(c, &coarse, &aux, &y0, 1e-3, 1e-4 * y_scale, y_scale, 0.0, 0, 1, &iterations, &a,
                       err);
        if (rc == BKF_OK || !coarse.noisy || tol_loose <= tol_int) break;
        tol_loose = fmax(tol_int, 1e-2 * tol_loose);
        size_t coarse_steps = coarse.steps, aux_steps = aux.steps;
        integrator_free(&coarse);
        integrator_free(&aux);
        if (integrator_init(&coarse, p, kind, 0, tol_loose) != BKF_OK ||
            integrator_init(&aux, p, kind, 1, tol_loose) != BKF_OK)
            goto fail_mem;
        coarse.steps = coarse_steps;
        aux.steps = aux_steps;
        y0 = y_start;
    }
    if (rc != BKF_OK) goto done;
    double cond_floor;
    rc = conditioning_floor(p, kind, tol_int, y0, &cond_floor, &coarse.steps, err);
    if (rc != BKF_OK) goto done;
    /* Fast path for loose tolerances: when the coarse solve is within a
     * factor FAST_SPAN of the integration tolerance asked, it serves as the
     * looser of the two solves of the error estimate, and one Newton solve
     * at tol_b (usually a single shot from the converged coarse point) is
     * all the extra work.  Its estimate |T_a - T_b| is of the coarse error,
     * a larger one than the classic pair gives; if it does not meet tol,
     * the classic pair below runs.
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
    if (tol_loose <= 1.01 * FAST_SPAN * tol_int) {
        int step_set_by_tol = kind != BKF_STEPPER_EXPLICIT || mu <= EXPLICIT_MU_MAX / 3.0;
        double tol_b = tol_loose / (step_set_by_tol ? TOL_RATIO : TOL_RATIO * TOL_RATIO);
        /* (not where the estimate's floor alone would refuse it: at tol
         * 1e-6 the fast pair was solved and thrown away, bd2x2 at mu
         * 30-1e4 took twice as long as at 1e-8) */
        if (tol_b >= tol_floor && ACCEPT_MARGIN * error_per_tol(kind) * tol_b / cycle_size(nu) <= opt.tol) {
            size_t aux_steps = aux.steps;
            integrator_free(&aux);
            if (integrator_init(&fine, p, kind, 0, tol_b) != BKF_OK ||
                integrator_init(&aux, p, kind, 1, tol_b) != BKF_OK)
                goto fail_mem;
            tighten_turn(&fine);
            aux.steps = aux_steps;
            rc = newton_at(c, &fine, &aux, &y0, 0.1 * sqrt(opt.tol), 0.1 * opt.tol * y_scale, y_scale, q_goal, 1,
                           0, &iterations, &b, err);
            if (rc != BKF_OK) goto done;
            double period_err = period_error(&a, &b, p, kind, cond_floor);
            if (ACCEPT_MARGIN * period_err > opt.tol * b.period) {
                /* The coarse Newton stops at loose goals (t_goal 1e-3), so
                 * |T_a - T_b| can be its iteration error rather than its
                 * integration error (mu 10, nu 0.9999; mu 1e3, nu -0.999 at
                 * tol 1e-6: 2-3e-6).  One coarse shot from b's converged
                 * point leaves only the latter, for one shot instead of the
                 * classic pair's two or more. */
                converged a2;
                double y_b = y0;
                rc = newton_at(c, &coarse, &aux, &y_b, 0.1 * sqrt(opt.tol), 0.1 * opt.tol * y_scale,
                               y_scale, q_goal, 0, 0, &iterations, &a2, err);
                if (rc != BKF_OK) goto done;
                double err2 = period_error(&a2, &b, p, kind, cond_floor);
                if (ACCEPT_MARGIN * err2 <= opt.tol * b.period) {
                    a = a2;
                    period_err = err2;
                }
            }
            if (ACCEPT_MARGIN * period_err <= opt.tol * b.period) {
                store_result(c, &a, &b, period_err, y0, kind, tol_b, &coarse, &fine, &finer, &aux,
                             iterations);
                rc = BKF_OK;
                goto done;
            }
            integrator_free(&fine);
        }
    }
    /* Every T solved at or below the looser tolerance of the pair in hand
     * is a sample of the answer at that accuracy: at the tolerance floor the
     * retries repeat the same pair from another start, and accepting the
     * first pair that happens to agree ("retry until lucky") reported
     * 2e-14 at mu 10, nu 0.9999, tol 1e-14 against a true 2e-13.  The
     * spread of all such samples is part of the estimate. */
    struct {
        double tol, period;
    } seen[8];
    size_t n_seen = 0;
    for (int attempt = 0; attempt < 4; attempt++) {
        integrator_free(&fine);
        integrator_free(&finer);
        size_t aux_steps = aux.steps;
        integrator_free(&aux);
        if (integrator_init(&fine, p, kind, 0, tol_int) != BKF_OK ||
            integrator_init(&finer, p, kind, 0, tol_int / TOL_RATIO) != BKF_OK ||
            integrator_init(&aux, p, kind, 1, tol_int / TOL_RATIO) != BKF_OK)
            goto fail_mem;
        aux.steps = aux_steps;
        rc = newton_at(c, &fine, &aux, &y0, 0.1 * sqrt(opt.tol), opt.tol * y_scale, y_scale, q_goal, 0, 0,
                       &iterations, &a, err);
        if (rc != BKF_OK) goto done;
        rc = newton_at(c, &finer, &aux, &y0, 0.1 * sqrt(opt.tol), 0.1 * opt.tol * y_scale, y_scale, q_goal, 1, 0,
                       &iterations, &b, err);
        if (rc != BKF_OK) goto done;
        double period_err = period_error(&a, &b, p, kind, cond_floor);
        seen[n_seen].tol = a.tol;
        seen[n_seen++].period = a.period;
        seen[n_seen].tol = b.tol;
        seen[n_seen++].period = b.period;
        for (size_t i = 0; i < n_seen; i++)
            if (seen[i].tol <= a.tol * (1.0 + 1e-9))
                period_err = fmax(period_err, fabs(seen[i].period - b.period));
        period_err = capped_floor(period_err, &fine, b.period);
        if (ACCEPT_MARGIN * period_err <= opt.tol * b.period || attempt == 3 ||
            /* (tol_floor * TOL_RATIO / TOL_RATIO may round above tol_floor) */
            tol_int / TOL_RATIO <= tol_floor * (1.0 + 1e-9)) {
            if (ACCEPT_MARGIN * period_err > opt.tol * b.period) {
                rc = bkf_error_set(err, BKF_ETOL,
                                   "cycle at mu = %.15g, nu = %.15g: estimated relative error %.2g of T, "
                                   "times the safety factor %g, exceeds tol = %g",
                                   mu, nu, period_err / b.period, ACCEPT_MARGIN, opt.tol);
                goto done;
            }
            store_result(c, &a, &b, period_err, y0, kind, tol_int / TOL_RATIO, &coarse, &fine,
                         &finer, &aux, iterations);
            rc = BKF_OK;
            goto done;
        }
        tol_int = fmax(tol_int * fmax(0.01, 0.3 * opt.tol * b.period / (ACCEPT_MARGIN * period_err)),
                       tol_floor * TOL_RATIO);
    }
    goto done;
fail_mem:
    rc = bkf_error_set(err, BKF_ENOMEM, "out of memory");
done:
    integrator_free(&coarse);
    integrator_free(&fine);
    integrator_free(&finer);
    integrator_free(&aux);
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
        solve_shooting_stepper(mu, nu, o.tol) == BKF_STEPPER_EXTRAPOLATION) {
        /* up to EXPLICIT_MU_MAX the engine that answered before bd2x2 took
         * over there: rk8pd; so in the canard's neighbourhood, where bsimp
         * flattered at tol 1e-12 (nu 0.9999, mu 40-88: up to 10.8, answers
         * outside tol) and rk8pd, honest there, took less time */
        o.stepper = mu <= EXPLICIT_MU_MAX || canard_neighbourhood(mu, nu) ? BKF_STEPPER_EXPLICIT
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
    int rc = check_inputs(mu, nu, &opt, err);
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
    for (int attempt = 0; attempt < 2; attempt++) {
        bkf_stepper_kind kind = attempt ? BKF_STEPPER_IMPLICIT : c->profile_stepper;
        if (attempt && kind == c->profile_stepper) break;
        integrator in = {0};
        if (integrator_init(&in, &c->flow, kind, 1, c->profile_tol) != BKF_OK) {
            integrator_free(&in);
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
            rc = integrator_to(&in, t, s, z[i]);
            t = z[i];
            if (f) f[i] = s[IX];
            if (fprime) fprime[i] = flow_xdot(&c->flow, s);
        }
        integrator_free(&in);
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
    double tight = pair_tol(tol, nu, kind);
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
    if (check_inputs(mu, nu, NULL, err) != BKF_OK)
        return bkf_error_set(err, BKF_ENUMERIC, "branch left the valid range at mu = %.15g, nu = %.15g", mu,
                             nu);
    double mirror = b->mirror_shots ? -1.0 : 1.0;
    nu *= mirror;
    flow_params p = {0};
    flow_set(&p, mu, nu);
    int along_mu = b->along == BKF_CYCLE_ALONG_MU;
    p.sens = dg ? (along_mu ? 1 : 2) : 0;
    bkf_stepper_kind kind = b->options.stepper;
    if (kind == BKF_STEPPER_AUTO || kind == BKF_STEPPER_COLLOCATION) kind = shooting_stepper(mu, b->options.tol);
    integrator in = {0}, aux = {0};
    double tol = branch_tol(b->options.tol, mu, nu, kind);
    int rc = BKF_ENOMEM;
    b->last.valid = 0;
    if (integrator_init(&in, &p, kind, 0, tol) == BKF_OK && integrator_init(&aux, &p, kind, 1, tol) == BKF_OK) {
        double w0 = exp(ln_w0), Fn = lienard_F(nu), a2 = p.a * p.a;
        double p0[2] = {along_mu ? 0.0 : 1.0,
                        along_mu ? mu * (-w0 * p.b / a2 + Fn / (a2 * p.a)) : p.b * (nu * nu - 1.0)};
        shot sh = {0};
        double y0 = section_y_of_slope(&p, w0);
        rc = shoot(&in, &aux, &p, y0, p0, NULL, &sh, err);
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
    integrator_free(&in);
    integrator_free(&aux);
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
    double dP = map_slope(in, sh, y0, y_still, &slope_L);
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
        if (locate_event(aux, p, event_section, n0->t, s0, n1->t, s1, &te, se) != BKF_OK) return BKF_ENUMERIC;
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
    flow_set(&c->flow, mu, nu);
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
    if (kind == BKF_STEPPER_AUTO || kind == BKF_STEPPER_COLLOCATION) kind = shooting_stepper(p->mu, tol);
    integrator in = {0}, aux = {0};
    double tol_a = pair_tol(tol, p->nu, kind), tol_b = tol_a / TOL_RATIO, floor = 0.0, y_real = 0.0;
    double y0 = b->last.y0, y_scale = fmax(fabs(y0), 1e-3);
    size_t steps = 0, shots = 0;
    integrator looser = b->last.in;
    looser.tol = tol_a;
    int rc = BKF_ENOMEM;
    if (integrator_init(&in, p, kind, 0, tol_a) == BKF_OK && integrator_init(&aux, p, kind, 1, tol_b) == BKF_OK) {
        rc = BKF_OK;
        /* Inside the canard the one-step correction of the corrector's
         * shot is not trusted: T curves in y0 on a scale far below y0, and
         * rows so corrected missed the Taylor reference by up to 6.2 times
         * their estimate while within tol (mu 3.65, nu 0.98994: true 8.5e-13
         * T, estimate 1.4e-13 T; mu 3.6506251, nu 0.99: 3.25), the pair's
         * tighter solve, started from the corrected point, sharing the
         * error.  Newton at this q is honest there (worst 0.8). */
        if (b->last.in.tol != tol_a || (canard_window(mu, nu) && mu >= 2.0) ||
            !branch_one_shot(&b->last.in, &b->last.flow, &b->last.sh, y0, tol, &a)) {
            /* a looser corrector shot, or one farther from the cycle than
             * one step corrects: Newton at this q, from that step */
            looser.capped = 0;
            const flow_params *f = &b->last.flow;
            const shot *sh = &b->last.sh;
            double slope_L, dP = map_slope(&b->last.in, sh, y0, f->b * lienard_F(f->nu), &slope_L);
            y0 -= (sh->y_return - y0) / (dP - 1.0);
            rc = newton_at(c, &in, &aux, &y0, 0.1 * sqrt(tol), tol * y_scale, y_scale, 1e-2 * tol, 0, 0, &shots,
                           &a, err);
            steps += in.steps;
            looser.capped += in.capped;
        }
        integrator_free(&in);
        /* the tighter solve from the looser one's fixed point, usually one
         * shot (its trajectory gives xmax, xmin and the mirror's section) */
        if (rc == BKF_OK && integrator_init(&in, p, kind, 0, tol_b) != BKF_OK) rc = BKF_ENOMEM;
        y0 = a.y0;
        if (rc == BKF_OK) {
            rc = newton_at(c, &in, &aux, &y0, 0.1 * sqrt(tol), 0.1 * tol * y_scale, y_scale, 1e-2 * tol, 1, 0,
                           &shots, &fine, err);
        }
        if (rc == BKF_OK) rc = conditioning_floor(p, kind, tol_a, fine.y0, &floor, &steps, err);
        if (rc == BKF_OK && mirrored) rc = branch_mirror_section(c, &aux, &y_real);
    }
    if (rc == BKF_OK) {
        double period_err = capped_floor(period_error(&a, &fine, p, kind, floor), &looser, fine.period);
        if (ACCEPT_MARGIN * period_err > tol * fine.period) {
            rc = BKF_ETOL;
        } else {
            /* (the work counters are the branch's: branch_accept) */
            integrator none = {0};
            store_result(c, &a, &fine, period_err, fine.y0, kind, tol_b, &none, &none, &none, &none, 0);
            if (mirrored) branch_unmirror_result(c, mu, nu, y_real);
            flow_set(p, mu, nu);
            c->result.mu = mu;
            c->result.nu = nu;
        }
    }
    b->work_rhs += p->rhs_calls;
    b->work_jac += p->jacobian_calls;
    b->work_steps += in.steps + aux.steps + steps;
    b->work_shots += shots;
    integrator_free(&in);
    integrator_free(&aux);
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
    if (integrator_init(&aux, &c->flow, c->profile_stepper, 1, c->profile_tol) != BKF_OK) rc = BKF_ENOMEM;
    else rc = branch_mirror_section(c, &aux, &y_real);
    b->work_rhs += c->flow.rhs_calls - rhs;
    b->work_jac += c->flow.jacobian_calls - jac;
    b->work_steps += aux.steps;
    integrator_free(&aux);
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
    double d = fmax(fabs(step), band), g0 = ga;
    for (int way = dir;;) {
        if (d > reach) {
            /* a canard narrower than its noise (mu 10, nu 0.998740451245:
             * ~1e-12 in nu) may hold the last point past this amplitude's root */
            if (way != dir) return bkf_error_set(err, BKF_ENUMERIC, "no root of G within %g of q = %.15g", reach, q0);
            way = -dir;
            d = fmax(fabs(step), band);
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
    double u[2] = {b->last_u[0], b->last_u[1]}, dg[2], g;
    const double h_min = 1e-6, h_max = 0.25, tol = fmax(1e-10, 10.0 * b->options.tol);
    int rc = branch_shot(b, u[0], u[1], &g, dg, NULL, NULL, err);
    if (rc != BKF_OK) return rc;
    double sign = (dg[1] > 0 ? 1.0 : -1.0) * dir, h = 0.02, slope = fabs(dg[0] / dg[1]);
    for (int steps = 0; b->rows < max_rows;) {
        double lw = u[0] + sign * h, q = u[1];
        double reach = fmax(1e-6 * fmax(1.0, fabs(u[1])), 8.0 * slope * h);
        rc = branch_solve_q(b, lw, u[1], slope * h, dir, tol, reach, &q, dg, &shots, err);
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
            if (steps == 0 && tries++ == 0) {
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
    *hi = colloc_canard_refused(branch_solved_nu(b, nu)) ? sqrt(BRANCH_COLLOC_CANARD_HI / d) : 0.0;
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
           !(mu >= 1.0 && colloc_canard_refused(branch_solved_nu(b, nu)) && x >= BRANCH_COLLOC_CANARD_LO &&
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
    int rc = colloc_store(c, r, &b->options, err);
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
                                         colloc_turn_tol(tol, p->mu), err);
    else
        rc = bkf_colloc_guess_turn(c->colloc, p->mu, p->nu, p->nu, section_y_of_slope(p, w), fmax(2.0 * M_PI, T),
                                   colloc_turn_tol(tol, p->mu), err);
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
    flow_set(&c->flow, mu, sign * nu);
    c->flow.rhs_calls = c->flow.jacobian_calls = 0;
    int rc = colloc_attempt(c, &opt, 0, err);
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
        flow_set(&c->flow, mu, sign * nu);
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
        flow_set(&c->flow, mu_n, sign * nu_n);
        c->flow.rhs_calls = c->flow.jacobian_calls = 0;
        if (!c->colloc && !(c->colloc = bkf_colloc_alloc())) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
        bkf_colloc_result r;
        int rc = bkf_colloc_guess_relaxation(c->colloc, mu_n, sign * nu_n, bkf_asym_period_leading(mu_n, nu_n),
                                             colloc_turn_tol(tol, mu_n), &row_err);
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
    int rc = check_inputs(mu_from, nu_from, &opt, err);
    if (rc == BKF_OK) rc = check_inputs(mu_to, nu_to, NULL, err);
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

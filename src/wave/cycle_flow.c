/* The cycle's flow and its integrators (cycle.c): the right-hand side and
 * its Jacobian, the closed-form extrapolation stepper, the GSL steppers
 * behind one interface, and the events located on a step.  Below
 * everything else of the cycle, which calls it; it calls none of it. */
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

/* ---------------------------------------------------------------- flow */

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

double cycle_flow_xdot(const flow_params *p, const double *s)
{
    return p->a * (s[IY] - p->b * lienard_F(s[IX]));
}

static double flow_xddot(const flow_params *p, const double *s)
{
    double x = s[IX];
    return p->a * ((p->nu - x) / p->a - p->b * (x * x - 1.0) * cycle_flow_xdot(p, s));
}

void cycle_flow_set(flow_params *p, double mu, double nu)
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
    } else {
        /* unused without a sensitivity, but gcc -O1 -fsanitize=thread cannot
         * see that p->sens is fixed across bd_midpoint and fails the build */
        m->kpx = m->kpy = m->kqx = 0.0;
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
int cycle_canard_window(double mu, double nu)
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
int cycle_canard_neighbourhood(double mu, double nu)
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
bkf_stepper_kind cycle_shooting_stepper(double mu, double tol)
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
bkf_stepper_kind cycle_solve_shooting_stepper(double mu, double nu, double tol)
{
    return cycle_canard_window(mu, nu) ? BKF_STEPPER_EXPLICIT : cycle_shooting_stepper(mu, tol);
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

int cycle_integrator_init(integrator *in, flow_params *flow, bkf_stepper_kind kind, int restarts,
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

void cycle_integrator_free(integrator *in)
{
    if (in->driver) gsl_odeiv2_driver_free(in->driver);
    memset(in, 0, sizeof *in);
}

void cycle_integrator_reset(integrator *in)
{
    in->row_target = BD_ROW_START;
    if (!in->driver) return;
    gsl_odeiv2_evolve_reset(in->evolve);
    gsl_odeiv2_step_reset(in->step);
}

/* One accepted step from *t toward t1 (never past it); *h: the next step. */
int cycle_integrator_apply(integrator *in, double *t, double t1, double *h, double *s)
{
    if (!in->driver) return bd_apply(in, t, t1, h, s);
    return gsl_odeiv2_evolve_apply(in->evolve, in->control, in->step, &in->system, t, t1, h, s) ==
                   GSL_SUCCESS
               ? BKF_OK
               : BKF_ENUMERIC;
}

/* Advance s from t0 to exactly t1 under error control. */
int cycle_integrator_to(integrator *in, double t0, double *s, double t1)
{
    double t = t0, h = t1 - t0;
    if (h == 0.0) return BKF_OK;
    cycle_integrator_reset(in);
    for (int guard = 0; t != t1; guard++) {
        if (guard > 100000) return BKF_ENUMERIC;
        /* bsimp can suggest a next step of the wrong sign after a rejected
         * step near t1; GSL treats that as a caller error */
        if ((t1 > t && !(h > 0.0)) || (t1 < t && !(h < 0.0))) h = t1 - t;
        if (cycle_integrator_apply(in, &t, t1, &h, s) != BKF_OK) return BKF_ENUMERIC;
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

int cycle_locate_event(integrator *in, const flow_params *p, event_fn g, double t0,
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
        if (cycle_integrator_to(in, t0, s, t) != BKF_OK) return BKF_ENUMERIC;
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

double cycle_event_section(const flow_params *p, const double *s, double *gdot)
{
    *gdot = cycle_flow_xdot(p, s);
    return s[IX] - p->nu;
}

double cycle_event_extremum(const flow_params *p, const double *s, double *gdot)
{
    *gdot = flow_xddot(p, s);
    return cycle_flow_xdot(p, s);
}


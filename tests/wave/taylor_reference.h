/* An independent reference period T(mu, nu) for the tests: nothing shared
 * with the cycle engine (src/wave/cycle.c).  Different method (Taylor
 * series of order TAYLOR_ORDER, coefficients by the recurrences of the
 * polynomial vector field), different precision (long double: 64-bit
 * mantissa on x86, 2^-64 = 5.4e-20), different coordinates (the phase plane
 * f' = g, g' = nu - f - mu (f^2 - 1) g, not the scaled Lienard plane),
 * different event location (Newton on the step's own Taylor polynomial,
 * which is dense output) and a different fixed-point iteration (secant on
 * g0 -> P(g0) - g0, no variational equations).
 *
 * Its own accuracy is measured, not assumed: taylor_period() is run at two
 * truncation levels and the change is returned as the uncertainty. */
#ifndef BKF_TEST_TAYLOR_REFERENCE_H
#define BKF_TEST_TAYLOR_REFERENCE_H

#include <math.h>

#define TAYLOR_ORDER 28

typedef struct {
    long double mu, nu, eps; /* eps: truncation error asked per step, relative to the state */
    long steps;
} taylor_flow;

/* Coefficients f[0..K], g[0..K] of the solution through (f0, g0). */
static void taylor_coefficients(const taylor_flow *q, long double f0, long double g0,
                                long double *f, long double *g)
{
    long double p[TAYLOR_ORDER + 1], r[TAYLOR_ORDER + 1];
    f[0] = f0;
    g[0] = g0;
    for (int k = 0; k < TAYLOR_ORDER; k++) {
        /* (f^2)_k is symmetric in i <-> k - i: half the products */
        long double pk = 0.0L, rk = 0.0L;
        for (int i = 0; i < (k + 1) / 2; i++) pk += f[i] * f[k - i];
        pk *= 2.0L;
        if (k % 2 == 0) pk += f[k / 2] * f[k / 2];
        p[k] = pk;
        for (int i = 0; i <= k; i++) rk += p[i] * g[k - i];
        r[k] = rk - g[k]; /* (f^2 - 1) g */
        f[k + 1] = g[k] / (k + 1);
        g[k + 1] = ((k == 0 ? q->nu : 0.0L) - f[k] - q->mu * r[k]) / (k + 1);
    }
}

static long double taylor_eval(const long double *c, long double t)
{
    long double v = c[TAYLOR_ORDER];
    for (int k = TAYLOR_ORDER - 1; k >= 0; k--) v = v * t + c[k];
    return v;
}

static long double taylor_deriv(const long double *c, long double t)
{
    long double v = TAYLOR_ORDER * c[TAYLOR_ORDER];
    for (int k = TAYLOR_ORDER - 1; k >= 1; k--) v = v * t + k * c[k];
    return v;
}

/* Step size whose last two terms are below eps times the state's size.
 * The root in double: h only chooses the step (the truncation error it
 * allows is eps's to a few ulps of double), and powl cost a quarter of a
 * turn. */
static long double taylor_h(const taylor_flow *q, const long double *f, const long double *g)
{
    long double scale = fmaxl(1.0L, fmaxl(fabsl(f[0]), fabsl(g[0])));
    double h = HUGE_VAL;
    for (int j = TAYLOR_ORDER - 1; j <= TAYLOR_ORDER; j++) {
        long double c = fmaxl(fabsl(f[j]), fabsl(g[j]));
        if (c > 0) h = fmin(h, pow((double)fminl(q->eps * scale / c, 1e300L), 1.0 / j));
    }
    return isfinite(h) ? (long double)h : 1.0L;
}

/* One turn from (nu, g0), g0 > 0, to the next upward crossing of f = nu:
 * the return time and the slope there.  0 on success. */
static int taylor_turn(taylor_flow *q, long double g0, long double *period, long double *g_return)
{
    long double f[TAYLOR_ORDER + 1], g[TAYLOR_ORDER + 1];
    long double x = q->nu, y = g0, t = 0.0L;
    int went_down = 0;
    for (long n = 0; n < 20000000L; n++) {
        taylor_coefficients(q, x, y, f, g);
        long double h = taylor_h(q, f, g);
        long double x1 = taylor_eval(f, h), y1 = taylor_eval(g, h);
        q->steps++;
        if (y1 < 0) went_down = 1;
        if (went_down && x < q->nu && x1 >= q->nu) {
            /* the crossing inside this step: Newton on the polynomial,
             * safeguarded by bisection */
            long double lo = 0.0L, hi = h, s = h * (q->nu - x) / (x1 - x);
            for (int it = 0; it < 200; it++) {
                long double v = taylor_eval(f, s) - q->nu;
                if (v < 0) lo = s;
                else hi = s;
                long double next = s - v / taylor_deriv(f, s);
                if (!(next > lo && next < hi)) next = 0.5L * (lo + hi);
                if (fabsl(next - s) <= 1e-21L * (t + h)) {
                    s = next;
                    break;
                }
                s = next;
            }
            *period = t + s;
            *g_return = taylor_eval(g, s);
            return 0;
        }
        x = x1;
        y = y1;
        t += h;
    }
    return -1;
}

/* T by the secant method on P(g0) - g0 from the guess g0 (any slope near
 * the cycle's; the fixed point does not depend on it); the fixed point in
 * *g_fixed and the change of T over the last iteration in *t_moved (a bound
 * on what the rest of the iteration would change: its steps shrink
 * superlinearly), either may be NULL.  Returns NAN when the iteration
 * fails.  The iteration stops when a step is below 1e-17 of g0 (T then
 * settled far below the 1e-17 T the reference is good for: at mu 300 the
 * turns after that moved T by 1e-20 of it, each a 30,000-step turn), or
 * below 1e-14 and no longer half the one before (it only moves g0 about in
 * the rounding of P). */
static long double taylor_period_eps(long double mu, long double nu, long double g_guess,
                                     long double eps, long *steps, long double *g_fixed,
                                     long double *t_moved)
{
    taylor_flow q = {mu, nu, eps, 0};
    long double a = g_guess, b = g_guess * (1.0L + 1e-6L), Ta, Tb, Pa, Pb;
    if (taylor_turn(&q, a, &Ta, &Pa) || taylor_turn(&q, b, &Tb, &Pb)) return NAN;
    long double ha = Pa - a, hb = Pb - b;
    for (int it = 0; it < 60; it++) {
        if (hb == ha) break;
        long double c = b - hb * (b - a) / (hb - ha);
        if (!(c > 0)) c = 0.5L * b;
        long double last_step = fabsl(b - a);
        a = b;
        ha = hb;
        Ta = Tb;
        b = c;
        if (taylor_turn(&q, b, &Tb, &Pb)) return NAN;
        hb = Pb - b;
        long double step = fabsl(b - a);
        if (step <= 1e-17L * fabsl(b) || (step <= 1e-14L * fabsl(b) && step > 0.5L * last_step)) break;
    }
    if (steps) *steps = q.steps;
    if (g_fixed) *g_fixed = b;
    if (t_moved) *t_moved = fabsl(Tb - Ta);
    return Tb;
}

/* T to about 1e-17 relative; *unc is the change between two truncation
 * levels, plus what the last secant iteration of each moved T and a
 * rounding allowance: the reference's own uncertainty.  The finer level
 * starts from the coarser one's fixed point: the same answer (the fixed
 * point does not depend on the guess) in fewer turns. */
static double taylor_period(double mu, double nu, double g_guess, double *unc)
{
    long double g1 = g_guess, m1 = 0.0L, m2 = 0.0L;
    long double t1 = taylor_period_eps(mu, nu, g_guess, 1e-18L, NULL, &g1, &m1);
    long double t2 = taylor_period_eps(mu, nu, isfinite(t1) ? g1 : g_guess, 1e-21L, NULL, NULL, &m2);
    *unc = (double)(fabsl(t1 - t2) + m1 + m2) + 1e-17 * (double)t2;
    return (double)t2;
}

#endif

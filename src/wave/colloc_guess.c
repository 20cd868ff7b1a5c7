/* The collocation engine's first meshes (colloc.c): a turn of step-doubled
 * Gauss steps, the relaxation landing, and the Lindstedt series for small mu.
 * Above the mesh and Newton (colloc_mesh.c), below the solve (colloc.c). */
#include "colloc_internal.h"

#include <float.h>
#include <gsl/gsl_math.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ------------------------------------------------------------- guesses */

/* Step-doubled Gauss steps: a step of length tau against two of tau/2,
 * accepted where their end values agree within the local tolerance; the
 * error of the end values (superconvergent, order 2m) is of the step's
 * tau^(2m+1), so the next step is scaled by its 1/(2m+1)-th root, and by
 * the predictive factor of Gustafsson's controller (Hairer-Wanner IV.8, as
 * in RADAU5), which extrapolates the change of the error constant from the
 * last two accepted steps: along a slow branch towards its fold the
 * constant grew by 1.4 a step and the plain rule was rejected every third
 * step, in a jump's entry by 1e4 a step (mu 1e3, nu -0.96: 84 rejections
 * in 180 steps of a turn, 17 with the prediction; Gauss steps per turn 786
 * -> 611).  No growth right after a rejection. */
#define TURN_GROW_MAX 4.0
#define TURN_SHRINK 0.25
#define TURN_STAGE_GOAL 1e-4

/* Stage guess of a step from (x0, y0): the Euler line. */
static void stage_guess(const bkf_colloc *c, double x0, double y0, double tau, double *X)
{
    double xd = (c->a * y0 - c->mu * lienard_F(x0)) * tau;
    if (fabs(xd) > 4.0) xd = copysign(4.0, xd);
    for (int l = 0; l < M; l++) X[l] = x0 + c->g.c[l] * xd;
}

/* Stages of a step of ratio r times the length of the last one, which
 * started at x0 with stages X: that step's polynomial beyond its end, at
 * 1 + r c_i (the Euler line's guess took Newton a third iteration). */
static void stage_extrapolate(const gauss_table *g, double x0, const double *X, double r, double *out)
{
    double a[M + 1];
    for (int p = 0; p <= M; p++) {
        a[p] = g->basis[0][p] * x0;
        for (int k = 0; k < M; k++) a[p] += g->basis[k + 1][p] * X[k];
    }
    for (int i = 0; i < M; i++) {
        double theta = 1.0 + r * g->c[i], s = a[M];
        for (int p = M - 1; p >= 0; p--) s = s * theta + a[p];
        out[i] = s;
    }
}

/* Extrapolate only this far (in lengths of the last step). */
#define EXTRAPOLATE_MAX 2.0

/* A Gauss step from the guess in X or, where Newton does not converge from
 * it, from the Euler line. */
int colloc_guarded_step(const bkf_colloc *c, double x0, double y0, double tau, double goal, int guessed, double *X,
                        double *x1, double *y1)
{
    if (guessed) {
        double Xg[M];
        memcpy(Xg, X, sizeof Xg);
        if (colloc_gauss_step(c, x0, y0, tau, goal, Xg, x1, y1)) {
            memcpy(X, Xg, sizeof Xg);
            return 1;
        }
    }
    stage_guess(c, x0, y0, tau, X);
    return colloc_gauss_step(c, x0, y0, tau, goal, X, x1, y1);
}

/* A turn's end values from the step's polynomial at its end, sum_k
 * end_k (x0, X)_k (the collocation polynomial through the start and the
 * stages), not from gauss_step's quadrature x0 + tau a y0 + tau^2 (nu/2 -
 * p^T X) - tau mu w^T F(X): on a slow branch at large mu that sums terms
 * of 1e4 for a change of 1e-3, and its rounding, about eps tau mu, is all
 * the step doubling then measured (at mu 1e4, tol 1e-12 the differences
 * were 0-1e-11 in multiples of 4.5e-13 where the local tolerance is 1e-11,
 * steps of 1-8 where the error allowed about 80).  Both are the same
 * polynomial; the interpolation's rounding is eps |x| (a few 1e-16), and
 * its weight on the stages' Newton error is O(1) where the quadrature's is
 * tau mu. */
static double end_value(const gauss_table *g, double x0, const double *X, double *magnitude)
{
    double s = g->end[0] * x0, m = fabs(s);
    for (int k = 0; k < M; k++) {
        double v = g->end[k + 1] * X[k];
        s += v;
        m += fabs(v);
    }
    if (magnitude) *magnitude = m;
    return s;
}

/* Below ROUND_SIGNAL times the rounding of the step doubling's difference
 * (eps times the sum of end_value's terms for x, and of |y0| + |y1 - y0|
 * for y1 = y0 + tau/a (nu - w^T X)) the difference says nothing about the
 * step's truncation error: such a step is accepted, and the predictive
 * factor (which assumes the error grows like tau^(2m+1)) is not used. */
#define ROUND_SIGNAL 4.0

/* Two Gauss steps of tau/2 from (xs, ys): stages into Xa, Xb, ends into
 * (xa, ya) (the middle) and (xb, yb).  prev (the last half step's start
 * and stages, of length tau/2 / ratio) or NULL: the first stages' guess.
 * (Inlined: out of line, its calls were 1% of a cold T at mu 10.) */
#if defined(__GNUC__)
__attribute__((always_inline))
#endif
static inline int half_steps(const bkf_colloc *c, double xs, double ys, double tau, double goal, const double *prev,
                             double ratio, double *Xa, double *Xb, double *xa, double *ya, double *xb, double *yb)
{
    int guessed = prev && ratio <= EXTRAPOLATE_MAX;
    if (guessed) stage_extrapolate(&c->g, prev[0], prev + 1, ratio, Xa);
    if (!colloc_guarded_step(c, xs, ys, 0.5 * tau, goal, guessed, Xa, xa, ya)) return 0;
    *xa = end_value(&c->g, xs, Xa, NULL);
    stage_extrapolate(&c->g, xs, Xa, 1.0, Xb);
    if (!colloc_guarded_step(c, *xa, *ya, 0.5 * tau, goal, 1, Xb, xb, yb)) return 0;
    *xb = end_value(&c->g, *xa, Xb, NULL);
    return 1;
}

/* One turn from (x0, y0) on the section x = nu (x' > 0) back to it: the
 * turn ends where it next crosses the section upwards after crossing it
 * downwards, so the mesh closes on the section (ending at a fixed T, the
 * closure fell in the jump, where the shot's 1e-5 in T is a shift of
 * O(mu 1e-5 T) in x and Newton, damped, took 8-30 iterations to move it).
 * from_below: (x0, y0) is below the section on the way up (a landing from
 * the left slow branch), and the first upward crossing ends it. */
int colloc_turn_mesh(bkf_colloc *c, double x0, double y0, double T, double local_tol, int record, int from_below,
                     bkf_error *err)
{
    double size = fmin(1.0, 2.0 * sqrt(fmax(1.0 - c->nu * c->nu, 0.0)));
    double tol = local_tol * size;
    /* the stages to a small part of the local tolerance: the turn gives a
     * mesh and a start, which the global Newton corrects anyway */
    double goal = fmax(STAGE_GOAL, TURN_STAGE_GOAL * tol);
    /* the full step only measures the halves' error: what its Newton
     * leaves, of the square of its last correction, is then 1e-2 of the
     * local tolerance (one iteration from the halves' polynomials instead
     * of two) */
    double full_goal = fmax(goal, 0.1 * sqrt(tol));
    /* the first step: a unit of the fast time 1/mu, at most T/64 */
    double t = 0.0, h = fmin(T / 64.0, 1.0 / fmax(c->mu, 1.0)), xs = x0, ys = y0;
    size_t n = 0, n_prev = 0;
    double prev[M + 1], tau_prev = 1.0;
    /* the last accepted step and its error (floored at its rounding: an
     * error of 0 would make the prediction 0), for the predictive factor;
     * signal_acc: that error was above its rounding */
    double e_acc = 0.0, tau_acc = 1.0;
    int closed = 0, went_down = from_below, rejected = 0, signal_acc = 0;
    /* about what mu 1e4 needs, so that the arrays do not grow step by step
     * (their reallocation was 4% of a cold solve there) */
    if (record && !colloc_reserve(c, 640)) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    while (!closed) {
        double tau = h;
        double Xf[M], Xa[M], Xb[M], xf, yf, xa, ya, xb, yb;
        int ok = half_steps(c, xs, ys, tau, goal, n_prev ? prev : NULL, tau / tau_prev, Xa, Xb, &xa, &ya, &xb, &yb);
        if (ok) {
            /* the full step starts from the halves' polynomials, within
             * about the local error of its solution (the Euler line took
             * Newton several iterations more) */
            for (int i = 0; i < M; i++) {
                const double *l = c->g.halves[i];
                int first = c->g.c[i] < 0.5;
                double s = l[0] * (first ? xs : xa);
                for (int k = 0; k < M; k++) s += l[k + 1] * (first ? Xa : Xb)[k];
                Xf[i] = s;
            }
            ok = colloc_gauss_step(c, xs, ys, tau, full_goal, Xf, &xf, &yf);
        }
        double e = INFINITY, rho = 0.0;
        if (ok) {
            double mx;
            xf = end_value(&c->g, xs, Xf, &mx);
            e = fmax(fabs(xf - xb), fabs(yf - yb));
            rho = DBL_EPSILON * (mx + fabs(ys) + fabs(yf - ys));
        }
        /* the tolerance, floored at what the difference can resolve (at
         * tol 1e-14, nu 0.999 the local tolerance, 9e-16 x the cycle's
         * size, is below it) */
        double tol_step = fmax(tol, ROUND_SIGNAL * rho);
        if (!(e <= tol_step)) {
            h = tau * (ok ? fmax(TURN_SHRINK, 0.9 * pow(tol_step / e, 1.0 / (2 * M + 1))) : TURN_SHRINK);
            rejected = 1;
            if (!(h > 1e-14 * T))
                return bkf_error_set(err, BKF_ENUMERIC,
                                     "collocation at mu = %.15g, nu = %.15g: the guess's step underflows",
                                     c->mu, c->nu);
            continue;
        }
        if (xs > c->nu && xb <= c->nu) went_down = 1;
        if (went_down && xs < c->nu && xb >= c->nu) {
            /* the section inside this step: Newton on its length */
            double s = tau * (c->nu - xs) / (xb - xs);
            for (int it = 0; it < 20; it++) {
                if (!half_steps(c, xs, ys, s, goal, NULL, 1.0, Xa, Xb, &xa, &ya, &xb, &yb))
                    return bkf_error_set(err, BKF_ENUMERIC,
                                         "collocation at mu = %.15g, nu = %.15g: the guess's turn does not close",
                                         c->mu, c->nu);
                double xd = c->a * yb - c->mu * lienard_F(xb), ds = (c->nu - xb) / xd;
                if (!(xd > 0.0)) break;
                s = fmin(fmax(s + ds, 0.0), tau);
                if (fabs(ds) <= 1e-13 * (t + s)) break;
            }
            tau = s;
            closed = 1;
        }
        if (record && n + 2 > MAX_INTERVALS)
            return bkf_error_set(err, BKF_ETOL,
                                 "collocation at mu = %.15g, nu = %.15g: local tol %g needs more than %d intervals",
                                 c->mu, c->nu, local_tol, MAX_INTERVALS);
        if (!record) {
            /* (only the landing) */
        } else if (!colloc_reserve(c, n + 2)) {
            return bkf_error_set(err, BKF_ENOMEM, "out of memory");
        } else {
        c->t[n] = t;
        c->x[n] = xs;
        c->y[n] = ys;
        memcpy(c->X + n * M, Xa, sizeof Xa);
        c->t[n + 1] = t + 0.5 * tau;
        c->x[n + 1] = xa;
        c->y[n + 1] = ya;
        memcpy(c->X + (n + 1) * M, Xb, sizeof Xb);
        n += 2;
        }
        t += tau;
        prev[0] = xa;
        memcpy(prev + 1, Xb, sizeof Xb);
        n_prev = 1;
        tau_prev = tau;
        xs = xb;
        ys = yb;
        /* the prediction (tau / tau_acc) (e_acc / ee)^(1/(2m+1)) where it is
         * below 1, under the one root (pow was 4% of a cold solve) */
        int signal = e > ROUND_SIGNAL * rho;
        double ee = signal ? e : fmax(rho, 1e-6 * tol), r = 1.0;
        if (signal && signal_acc) {
            double q = tau / tau_acc, qn = 1.0;
            for (int k = 0; k < 2 * M + 1; k++) qn *= q;
            r = fmin(1.0, qn * e_acc / ee);
        }
        double factor = 0.9 * pow(tol_step / ee * r, 1.0 / (2 * M + 1));
        h = tau * fmin(rejected ? 1.0 : TURN_GROW_MAX, factor);
        e_acc = ee;
        signal_acc = signal;
        tau_acc = tau;
        rejected = 0;
        if (!closed && t > 4.0 * T)
            return bkf_error_set(err, BKF_ENUMERIC,
                                 "collocation at mu = %.15g, nu = %.15g: the guess's turn does not return to the "
                                 "section",
                                 c->mu, c->nu);
    }
    if (!record) {
        c->x[0] = xs;
        c->y[0] = ys;
        c->T = t;
        return BKF_OK;
    }
    for (size_t j = 0; j < n; j++) c->t[j] /= t;
    c->T = t;
    c->n = n;
    c->t[n] = 1.0;
    c->x[n] = c->x[0];
    c->y[n] = c->y[0];
    c->paired = 1;
    c->local_tol = local_tol;
    return BKF_OK;
}

int bkf_colloc_guess_turn(bkf_colloc *c, double mu, double nu, double x0, double y0, double T, double local_tol,
                          bkf_error *err)
{
    if (!c || !(T > 0.0) || !(local_tol > 0.0) || !isfinite(x0) || !isfinite(y0))
        return bkf_error_set(err, BKF_EINPUT, "collocation guess needs T > 0, local_tol > 0 and a finite start");
    colloc_set_params(c, mu, nu);
    c->have_guess = c->have_solution = 0;
    c->uniform = 0;
    if (!colloc_reserve(c, 1)) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    /* a first turn lands on the cycle: from a start off it by d the turn's
     * phase is off by about d mu and the jump by d mu^2, which Newton, damped,
     * moved in 8-13 iterations from a shot's 1e-5 at mu 300-1e4 */
    int rc = colloc_turn_mesh(c, x0, y0, T, local_tol, 0, 0, err);
    if (rc == BKF_OK) rc = colloc_turn_mesh(c, c->x[0], c->y[0], c->T, local_tol, 1, 0, err);
    if (rc == BKF_OK) c->have_guess = 1;
    return rc;
}

/* The landing's start on the left slow branch.  Only what happens from the
 * fold on reaches the section: the branch attracts like exp(-mu^2 times
 * the integral of (x^2 - 1)^2 / (nu - x) dx), about exp(-0.15 mu^2) from
 * here to the fold (15 at mu 10), and every orbit on the branch leaves the
 * fold along the same jump.  (A start nearer the fold saves little: at
 * -1.2, 40 of about 1200 Gauss steps at mu 1e3, and the pair's Newton
 * iterations varied more than that; the attraction at mu 10 would be
 * exp(-1).) */
#define LANDING_X (-1.5)

int bkf_colloc_guess_relaxation(bkf_colloc *c, double mu, double nu, double T, double local_tol, bkf_error *err)
{
    if (!c || !(mu >= 1.0) || !(fabs(nu) < 1.0) || !(T > 0.0) || !(local_tol > 0.0))
        return bkf_error_set(err, BKF_EINPUT,
                             "collocation guess needs mu >= 1, |nu| < 1, T > 0 and local_tol > 0");
    colloc_set_params(c, mu, nu);
    c->have_guess = c->have_solution = 0;
    if (!colloc_reserve(c, 1)) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    /* on the slow manifold to first order: x' = a (y - b F(x)) = y' / (b F'(x)) */
    double x0 = LANDING_X, y0 = c->b * lienard_F(x0) + (nu - x0) / (c->a * c->a * c->b * (x0 * x0 - 1.0));
    int rc = colloc_turn_mesh(c, x0, y0, T, local_tol, 0, 1, err);
    if (rc == BKF_OK) rc = colloc_turn_mesh(c, c->x[0], c->y[0], T, local_tol, 1, 0, err);
    if (rc == BKF_OK) c->have_guess = 1;
    return rc;
}

/* ------------------------------------------------- Lindstedt series */

/* u = f - nu in the time tau = omega z solves
 *     omega^2 u'' + mu omega (d/dtau) G(u) + u = 0,  G(u) = u^3/3 + nu u^2 - w u,
 * w = 1 - nu^2 (G' = (u + nu)^2 - 1).  With u = sum mu^k u_k, omega =
 * sum mu^k omega_k and u_0 = r sin tau, order k + 1 reads
 *     u_{k+1}'' + u_{k+1} = R_{k+1} = sum_{j=1}^{k+1} W_j u_{k+1-j}''
 *                                     - sum_{i=0}^{k} omega_i G_{k-i}',
 * W_j the mu^j coefficient of 1 - omega^2, G_j that of G(u).  Its cos tau
 * part vanishes for one amplitude correction B_k sin tau of u_k (it adds
 * -2 w B_k cos tau: the fundamental of G'(u_0) sin tau is 2 w sin tau),
 * which at k = 0 fixes r = 2 sqrt(w); its sin tau part for omega_{k+1}
 * (-2 omega_{k+1} u_0'' = 2 r omega_{k+1} sin tau).  The rest is solved
 * harmonic by harmonic, with u_{k+1}(0) = 0 (the phase x(0) = nu).
 * Products on a grid of SERIES_GRID points, harmonics by direct sums: u_k
 * has harmonics up to 2k + 1, G_k up to 2k + 3, below SERIES_GRID / 2 up
 * to SERIES_ORDER_MAX.  omega is even in mu (mu -> -mu, tau -> -tau). */
#define SERIES_ORDER_MAX 12
#define SERIES_GRID 64
#define SERIES_HARM (2 * SERIES_ORDER_MAX + 3)

typedef struct {
    double omega;                /* sum of the orders kept */
    double ca[SERIES_HARM + 1];  /* u = sum ca_n cos n tau + sb_n sin n tau */
    double sb[SERIES_HARM + 1];
    int harmonics, order;        /* highest harmonic, highest order kept */
    double residual;             /* the last term kept over the radius */
    double omega_k[SERIES_ORDER_MAX + 1];
} lindstedt_series;

/* DFT of v on the grid of P points: cos and sin coefficients up to
 * harmonic h, from the tables cm[n][p] = cos(2 pi n p / P), sm likewise
 * (dense rows: the loops vectorise). */
typedef double series_row[SERIES_GRID];
static void series_dft(int P, const series_row *cm, const series_row *sm, const double *v, int h, double *a,
                       double *b)
{
    for (int n = 0; n <= h; n++) {
        double sa = 0.0, sbv = 0.0;
        for (int p = 0; p < P; p++) {
            sa += v[p] * cm[n][p];
            sbv += v[p] * sm[n][p];
        }
        a[n] = (n ? 2.0 : 1.0) * sa / P;
        b[n] = n ? 2.0 * sbv / P : 0.0;
    }
}

static void series_grid(int P, const series_row *cm, const series_row *sm, const double *a, const double *b, int h,
                        double *v)
{
    for (int p = 0; p < P; p++) v[p] = a[0];
    for (int n = 1; n <= h; n++)
        for (int p = 0; p < P; p++) v[p] += a[n] * cm[n][p] + b[n] * sm[n][p];
}

/* The series to `order` (at most SERIES_ORDER_MAX), or fewer where its
 * terms stop shrinking (it converges for mu below a radius of order 1,
 * smaller at |nu| ~ 0.5: truncated at its smallest term).  residual: the
 * last term kept, relative to the cycle's radius (the size of what is
 * left out, where the terms shrink geometrically). */
static void lindstedt(double mu, double nu, int order, lindstedt_series *out)
{
    enum { PMAX = SERIES_GRID, K = SERIES_ORDER_MAX, H = SERIES_HARM };
    if (!(mu > 0.0)) order = 0;
    if (order > K) order = K;
    /* the grid resolves G_{order-1}'s harmonics, up to 2 order + 1, without
     * aliasing: P > 2 (2 order + 1) */
    int P = 8;
    while (P <= 2 * (2 * order + 1)) P *= 2;
    double ct[PMAX], st[PMAX];
    series_row cm[H + 1], sm[H + 1];
    for (int p = 0; p < P; p++) {
        ct[p] = cos(2.0 * M_PI * p / P);
        st[p] = sin(2.0 * M_PI * p / P);
    }
    for (int n = 0; n <= 2 * order + 1 && n <= H; n++)
        for (int p = 0, q = 0; p < P; p++, q = (q + n) & (P - 1)) {
            cm[n][p] = ct[q];
            sm[n][p] = st[q];
        }
    const double w = 1.0 - nu * nu, r = 2.0 * sqrt(w);
    static const double zero[H + 1];
    double ua[K + 1][H + 1], ub[K + 1][H + 1], ga[K + 1][H + 1], gb[K + 1][H + 1];
    double u[K + 1][PMAX], sq[K + 1][PMAX], om[K + 1], W[K + 2];
    memset(ua, 0, sizeof ua);
    memset(ub, 0, sizeof ub);
    memset(out, 0, sizeof *out);
    ub[0][1] = r;
    om[0] = 1.0;
    /* the mu^k coefficient of G(u) on the grid, its harmonics into ga, gb */
#define SERIES_G(k)                                                                         \
    do {                                                                                    \
        series_grid(P, cm, sm, ua[k], ub[k], 2 * (k) + 1, u[k]);                            \
        double gv[PMAX];                                                                     \
        for (int p = 0; p < P; p++) {                                                       \
            double s2 = 0.0, s3 = 0.0;                                                      \
            for (int i = 0; i <= (k); i++) s2 += u[i][p] * u[(k) - i][p];                   \
            sq[k][p] = s2;                                                                  \
            for (int i = 0; i <= (k); i++) s3 += u[i][p] * sq[(k) - i][p];                  \
            gv[p] = s3 / 3.0 + nu * s2 - w * u[k][p];                                       \
        }                                                                                   \
        series_dft(P, cm, sm, gv, 2 * (k) + 3, ga[k], gb[k]);                               \
    } while (0)
    SERIES_G(0);
    double sum_a[H + 1] = {0}, sum_b[H + 1] = {0}, omega = 1.0, scale = r, last = r;
    memcpy(sum_b, ub[0], sizeof sum_b);
    int kept = 0;
    for (int k = 0; k < order; k++) {
        double ra[H + 1], rb[H + 1];
        int h = 2 * k + 3;
        for (int pass = 0; pass < 2; pass++) {
            /* W_j = -(sum_{i=0}^{j} omega_i omega_{j-i}), omega_{k+1} not yet known */
            for (int j = 1; j <= k + 1; j++) {
                double s = 0.0;
                for (int i = 1; i < j; i++) s += om[i] * om[j - i];
                W[j] = -(s + (j <= k ? 2.0 * om[j] : 0.0));
            }
            for (int n = 0; n <= h; n++) {
                double sa = 0.0, sbv = 0.0;
                for (int j = 1; j <= k + 1; j++) {
                    const double *pa = n <= 2 * (k + 1 - j) + 1 ? ua[k + 1 - j] : zero;
                    const double *pb = n <= 2 * (k + 1 - j) + 1 ? ub[k + 1 - j] : zero;
                    sa -= W[j] * n * n * pa[n];
                    sbv -= W[j] * n * n * pb[n];
                }
                for (int i = 0; i <= k; i++) {
                    if (n > 2 * (k - i) + 3) continue;
                    sa -= om[i] * n * gb[k - i][n];
                    sbv += om[i] * n * ga[k - i][n];
                }
                ra[n] = sa;
                rb[n] = sbv;
            }
            if (pass || k == 0) break;
            /* the amplitude correction B sin tau of u_k, and what it adds
             * to G_k: G'(u_0) B sin tau = B (2 w sin tau - w sin 3 tau +
             * nu r - nu r cos 2 tau) (r^2 = 4 w), to (u^2)_k 2 u_0 B sin tau */
            double B = ra[1] / (2.0 * w);
            ub[k][1] += B;
            sum_b[1] += pow(mu, k) * B;
            ga[k][0] += B * nu * r;
            ga[k][2] -= B * nu * r;
            gb[k][1] += 2.0 * B * w;
            gb[k][3] -= B * w;
            for (int p = 0, q = 0; p < P; p++, q = (q + 1) & (P - 1)) {
                u[k][p] += B * st[q];
                sq[k][p] += 2.0 * B * st[q] * u[0][p];
            }
        }
        om[k + 1] = -rb[1] / (2.0 * r);
        ua[k + 1][0] = ra[0];
        double phase = ra[0];
        for (int n = 2; n <= h; n++) {
            ua[k + 1][n] = ra[n] / (1.0 - n * n);
            ub[k + 1][n] = rb[n] / (1.0 - n * n);
            phase += ua[k + 1][n];
        }
        ua[k + 1][1] = -phase;
        ub[k + 1][1] = 0.0;
        if (k + 1 < order) SERIES_G(k + 1);
        /* the size of the term mu^(k+1) u_{k+1} */
        double mk = pow(mu, k + 1), size = 0.0;
        for (int n = 0; n <= h; n++) size += fabs(ua[k + 1][n]) + fabs(ub[k + 1][n]);
        size *= mk;
        if (size > last) break; /* diverging: keep up to the smallest term */
        for (int n = 0; n <= h; n++) {
            sum_a[n] += mk * ua[k + 1][n];
            sum_b[n] += mk * ub[k + 1][n];
        }
        omega += mk * om[k + 1];
        kept = k + 1;
        out->harmonics = h;
        last = size;
    }
#undef SERIES_G
    /* the amplitude correction of the last order kept is the next order's
     * (B_kept, unknown): it is part of the truncation error */
    memcpy(out->ca, sum_a, sizeof sum_a);
    memcpy(out->sb, sum_b, sizeof sum_b);
    memcpy(out->omega_k, om, sizeof(double) * (size_t)(kept + 1));
    if (!kept) out->harmonics = 1;
    out->omega = omega;
    out->order = kept;
    out->residual = kept ? last / scale : 1.0;
}

double bkf_colloc_series_period(double mu, double nu, int order)
{
    if (!(mu >= 0.0) || !isfinite(mu) || !(fabs(nu) < 1.0) || order < 0) return NAN;
    lindstedt_series s;
    lindstedt(mu, nu, order, &s);
    return 2.0 * M_PI / s.omega;
}

/* u and du/dtau of the series at the angle whose cosine and sine are
 * (c1, s1). */
static void series_eval(const lindstedt_series *s, double c1, double s1, double *u, double *du)
{
    double cn = 1.0, sn = 0.0, v = s->ca[0], d = 0.0;
    for (int n = 1; n <= s->harmonics; n++) {
        double c2 = cn * c1 - sn * s1;
        sn = sn * c1 + cn * s1;
        cn = c2;
        v += s->ca[n] * cn + s->sb[n] * sn;
        d += n * (s->sb[n] * cn - s->ca[n] * sn);
    }
    *u = v;
    *du = d;
}

/* The series order past which Newton's iterations no longer fall: the
 * fewest interval solves of a cold solve at tol 1e-10 (nu 0, -0.5, -0.96,
 * 0.99) came from order 2 up to mu 0.1, 4 at 0.2-0.3, 6 at 0.5-1 (8 at
 * mu 0.7 saved one iteration at nu -0.5 but doubles the grid). */
static int series_order(double mu)
{
    int k = 2;
    while (k < 6 && pow(mu, k) > 0.02) k += 2;
    return k;
}

int bkf_colloc_guess_series(bkf_colloc *c, double mu, double nu, int order, size_t intervals, double *residual,
                            bkf_error *err)
{
    if (!c || intervals < 4 || intervals > MAX_INTERVALS || order < 0 || !(mu > 0.0) || !(fabs(nu) < 1.0))
        return bkf_error_set(err, BKF_EINPUT,
                             "collocation series guess needs mu > 0, |nu| < 1, order >= 0 and intervals in [4, %d]",
                             MAX_INTERVALS);
    if (!colloc_reserve(c, intervals)) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    colloc_set_params(c, mu, nu);
    lindstedt_series s;
    lindstedt(mu, nu, order ? order : series_order(mu), &s);
    if (residual) *residual = s.residual;
    c->n = intervals;
    c->T = 2.0 * M_PI / s.omega;
    /* the points 2 pi (j + theta) / n by rotations of 2 pi / n from theta */
    const double step = 2.0 * M_PI / (double)intervals, cs = cos(step), ss = sin(step);
    for (int k = 0; k <= M; k++) {
        double theta = k ? c->g.c[k - 1] : 0.0, ck = cos(step * theta), sk = sin(step * theta);
        for (size_t j = 0; j < intervals + (k == 0); j++) {
            double u, du;
            series_eval(&s, ck, sk, &u, &du);
            if (k) {
                c->X[j * M + k - 1] = nu + u;
            } else {
                c->t[j] = (double)j / (double)intervals;
                c->x[j] = nu + u;
                c->y[j] = s.omega * du / c->a + c->b * lienard_F(nu + u);
            }
            double c2 = ck * cs - sk * ss;
            sk = sk * cs + ck * ss;
            ck = c2;
        }
    }
    c->t[intervals] = 1.0;
    c->have_guess = 1;
    c->have_solution = 0;
    c->paired = 0;
    c->uniform = 1;
    return BKF_OK;
}

int bkf_colloc_warm(bkf_colloc *c, double mu, double nu)
{
    if (!c || !c->have_solution) return 0;
    c->paired = 0;
    c->uniform = 0;
    double a0 = c->a, b0 = c->b;
    colloc_set_params(c, mu, nu);
    /* same f and f' = a (y - b F(x)) in the new scaling */
    for (size_t j = 0; j <= c->n; j++) {
        double fp = a0 * (c->y[j] - b0 * lienard_F(c->x[j]));
        c->y[j] = fp / c->a + c->b * lienard_F(c->x[j]);
    }
    c->have_guess = 1;
    return 1;
}

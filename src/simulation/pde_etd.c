/* The exponential integrator of the continuum model (stepper etdrk4).
 *
 * Why: with an explicit Runge-Kutta method the step is capped by the
 * fastest wave mode, omega_max = sqrt(1 + c^2 q_max^2) (+ |V| q_max in a
 * moving frame), so a run costs ~N^2 log N and thin fronts (which need
 * large N) are out of reach.  Here the linear wave part of every Fourier
 * mode is solved exactly and only the friction and the filter are treated
 * explicitly, so the step is set by the physics, not by the grid.
 *
 * Per mode q_k the linear part of
 *     psi_t = gamma eta + [gamma (psi - psi^3/3) - F psi] + V psi_x
 *     eta_t = -(1 + c^2 q^2) psi / gamma + nu / gamma + V eta_x
 * (brackets: the explicit part) is diagonal in
 *     a+- = (psi_k -+ i (gamma/w) eta_k) / 2,  w = sqrt(1 + c^2 q^2),
 * with eigenvalues i (V q +- w) (V q = 0 at the Nyquist mode, as in the
 * Runge-Kutta frame); back: psi_k = a+ + a-, eta_k = i (w/gamma)(a+ - a-).
 * Every linear rate is imaginary, so the phi functions below never meet
 * growth or damping and their arguments stay on the imaginary axis.
 *
 * The scheme is Cox and Matthews' ETDRK4 (J. Comput. Phys. 176, 430
 * (2002)).  Its error estimate is f3 (N(c) - N(u_new)), f3 = h (4 phi3 -
 * phi2) the weight of the last stage: without the linear part this is the
 * classical RK4 with its FSAL-embedded third-order solution (the only
 * third-order weights over the stages and N(u_new) differ from RK4's by a
 * multiple of (0, 0, 0, 1, -1)).  N(u_new) is the next step's first stage,
 * so the estimate costs an evaluation only when a step is rejected.  It is
 * O(h^4) (control exponent 1/4): conservative for the fourth-order result.
 * (The second-order estimate from the same four stages, O(h^3), held the
 * steps of a steady seeded wave 4-8 times shorter at tol 1e-9.)
 * Like every ETD Runge-Kutta scheme (and unlike the integrating-factor
 * form) it keeps a steady state of the semi-discrete system exactly:
 * L u + N(u) = 0 makes every stage equal u and the estimate 0.  In the
 * frame of a travelling wave the steps therefore grow until the slow
 * dynamics of the perturbation, or the explicit friction term
 * (rate ~ gamma (psi^2 - 1) <= ~3 gamma), limits them.
 *
 * Each sample interval is crossed in equal steps, as long as the error
 * control allows (what is left of the interval over the number of steps),
 * so steps land on the sample times exactly (no dense output is needed)
 * and in a settled run one step size recurs, whose coefficients (N complex
 * exponentials) come from a small cache.  A dyadic ladder base 2^-j was
 * tried first: its factor-2 rungs cost up to 1.6x in steps (n = 11 at the
 * paper's parameters wanted ~0.09 and got 0.0625).
 *
 * The quadratures Q and D of the Runge-Kutta path are not tracked by
 * etdrk4 (they would need the time derivatives at every step end, more
 * than doubling the cost): samples and the state carry NaN there, so the
 * energy and mean residuals are NaN for it.  lawson8 carries them as one
 * more complex unknown (index n2: Q + i D): Q's rate is linear and part of
 * L (q_part), D is integrated over the step ends (dq_increment) or, where
 * those do not resolve it, on rk8pd's stages. */
#include <complex.h>
#include <gsl/gsl_errno.h>
#include <gsl/gsl_math.h>
#include <gsl/gsl_odeiv2.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bkfront/fft.h"
#include "bkfront/model.h"
#include "pde_internal.h"

/* Coefficient sets kept (the settled step, its neighbours after a
 * rejection, the last partial sample interval). */
#define ETD_SETS 4
/* Largest step: beyond it the explicit friction term (rate up to ~3 gamma)
 * is what the error control would have to discover by rejections. */
#define ETD_H_MAX 1.0
#define ETD_TAYLOR_TERMS 20

typedef struct {
    double h;               /* 0: unused */
    unsigned long used;     /* for the least-recently-used replacement */
    double complex *E, *E2, *Q, *f1, *f2, *f3;
} etd_set;

/* lawson8: the rotations E(tau) = exp(lam tau) at the stage offsets tau of
 * one step size h (rk8pd's 12 distinct nonzero c_i h), filled as the stages
 * ask for them. */
#define LAWSON_TAUS 16
/* Step ends (times and D') the quadrature of D interpolates, the new end
 * included: degree DQ_POINTS - 1 (see dq_increment) */
#define DQ_POINTS 9
typedef struct {
    double h;
    unsigned long used;
    size_t count;
    double tau[LAWSON_TAUS];
    double complex *E[LAWSON_TAUS];
} lawson_set;

struct bkf_pde_etd {
    size_t nc, n2;          /* nc = N/2 + 1 modes; index k: a+, nc + k: a- */
    double complex *lam;    /* eigenvalue of each index */
    double *ratio;          /* gamma / w_k */
    double *sigma;          /* filter rate of mode k (0 without the filter) */
    /* n2 values each, plus (lawson8) the quadratures Q + i D at index n2 */
    double complex *a, *sa, *s, *nu, *na, *nb, *nc_, *anew, *nnew;
    double complex *pk;     /* psi_k of the state being evaluated */
    double psi_max;         /* max |psi| of the state a (valid with have_nu) */
    int valid, have_nu;
    unsigned long clock;
    etd_set set[ETD_SETS];
    double inv_fact[ETD_TAYLOR_TERMS + 4];
    /* lawson8 (NULL rk otherwise): GSL's rk8pd on the integrating-factor
     * form, anchored at each step's start */
    gsl_odeiv2_step *rk;
    gsl_odeiv2_system sys;
    lawson_set lset[ETD_SETS];
    size_t lsets;           /* sets in use: fewer at large N (memory) */
    lawson_set *lcur;       /* the current step's */
    size_t calls;           /* rk8pd's evaluations in the current step */
    int d_off;              /* this evaluation's D' is unused (0 is put there) */
    /* D by a multistep quadrature over the step ends (see dq_increment) */
    int d_staged;           /* this step carries D on rk8pd's stages instead */
    size_t dq_n;            /* step ends held, newest first */
    double dq_t[DQ_POINTS], dq_r[DQ_POINTS];
    double dq_inc, dq_est;  /* D's increment over the step tried and its error */
    size_t dq_clean;        /* staged steps in a row whose ends would have done */
    bkf_pde *owner;
    /* Fast modes k >= kfast (lawson8; nc: none): see averaged_cross() */
    size_t kfast, nu_kfast;
    int fast_drop, nu_drop; /* the set is left out of F's input (fast_start) */
    size_t kin, nu_kin;     /* modes k >= kin are (nc: none) */
    double *jac, *hr;       /* N values: gamma (1 - psi^2), a branch's field */
    fftw_complex *hc, *hk;  /* nc values: a branch's spectrum, the product's */
    double expo;            /* step control exponent: 1/(order of the estimate + 1) */
    int mirrored;           /* lam[nc + k] = conj(lam[k]) (no moving frame) */
    /* The grid lawson_stage_fused forms F on (see product_grid): M points,
     * 0 for the field's own N; its plans, made for m->cbuf, lap, rbuf */
    size_t cm, cplanned;
    fftw_plan cfwd, cbwd;
};

static double complex *cbuf_of(bkf_pde *m) { return (double complex *)m->cbuf; }

static void set_free(etd_set *s)
{
    free(s->E);
    free(s->E2);
    free(s->Q);
    free(s->f1);
    free(s->f2);
    free(s->f3);
    memset(s, 0, sizeof *s);
}

void bkf_pde_etd_free(bkf_pde_etd *etd)
{
    if (!etd) return;
    for (int i = 0; i < ETD_SETS; i++) {
        set_free(&etd->set[i]);
        for (size_t k = 0; k < LAWSON_TAUS; k++) free(etd->lset[i].E[k]);
    }
    if (etd->rk) gsl_odeiv2_step_free(etd->rk);
    if (etd->cfwd || etd->cbwd) {
        bkf_fft_lock();
        if (etd->cfwd) fftw_destroy_plan(etd->cfwd);
        if (etd->cbwd) fftw_destroy_plan(etd->cbwd);
        bkf_fft_unlock();
    }
    free(etd->lam);
    free(etd->ratio);
    free(etd->sigma);
    free(etd->a);
    free(etd->sa);
    free(etd->s);
    free(etd->nu);
    free(etd->na);
    free(etd->nb);
    free(etd->nc_);
    free(etd->anew);
    free(etd->nnew);
    free(etd->pk);
    fftw_free(etd->jac);
    fftw_free(etd->hr);
    fftw_free(etd->hc);
    fftw_free(etd->hk);
    free(etd);
}

void bkf_pde_etd_invalidate(bkf_pde_etd *etd)
{
    if (etd) etd->valid = etd->have_nu = 0;
}

static int lawson_rhs(double tau, const double y[], double dydt[], void *params);

bkf_pde_etd *bkf_pde_etd_alloc(bkf_pde *m)
{
    bkf_pde_etd *etd = calloc(1, sizeof *etd);
    if (!etd) return NULL;
    size_t N = m->N, nc = N / 2 + 1, n2 = 2 * nc;
    etd->nc = nc;
    etd->n2 = n2;
    etd->lam = malloc(n2 * sizeof *etd->lam);
    etd->ratio = malloc(nc * sizeof *etd->ratio);
    etd->sigma = malloc(nc * sizeof *etd->sigma);
    double complex **arrays[] = {&etd->a,  &etd->sa,  &etd->s,    &etd->nu,  &etd->na,
                                 &etd->nb, &etd->nc_, &etd->anew, &etd->nnew};
    int bad = !etd->lam || !etd->ratio || !etd->sigma;
    for (size_t i = 0; i < sizeof arrays / sizeof arrays[0]; i++) {
        *arrays[i] = calloc(n2 + 1, sizeof(double complex));
        bad |= !*arrays[i];
    }
    etd->pk = calloc(nc, sizeof *etd->pk);
    if (bad || !etd->pk) {
        bkf_pde_etd_free(etd);
        return NULL;
    }
    double g = m->p.gamma, c = m->p.c, V = m->o.frame_speed;
    for (size_t k = 0; k < nc; k++) {
        double q = 2.0 * M_PI * (double)k / m->p.S;
        double w = sqrt(1.0 + c * c * q * q);
        double adv = 2 * k == N ? 0.0 : V * q;
        etd->lam[k] = I * (adv + w);
        etd->lam[nc + k] = I * (adv - w);
        etd->ratio[k] = g / w;
        /* fsymbol holds sigma_k / N for the unnormalised transforms */
        etd->sigma[k] = m->fsymbol ? m->fsymbol[k] * (double)N : 0.0;
    }
    double f = 1.0;
    for (int k = 0; k < ETD_TAYLOR_TERMS + 4; k++) {
        if (k > 0) f *= k;
        etd->inv_fact[k] = 1.0 / f;
    }
    etd->mirrored = V == 0.0;
    etd->owner = m;
    etd->kfast = etd->nu_kfast = etd->kin = etd->nu_kin = nc;
    etd->expo = 0.25;
    if (m->o.stepper == BKF_PDE_LAWSON8) {
        etd->expo = 1.0 / 8.0;
        etd->rk = gsl_odeiv2_step_alloc(gsl_odeiv2_step_rk8pd, 2 * n2 + 2);
        if (!etd->rk) {
            bkf_pde_etd_free(etd);
            return NULL;
        }
        etd->sys = (gsl_odeiv2_system){lawson_rhs, NULL, 2 * n2 + 2, m};
        etd->jac = fftw_malloc(N * sizeof(double));
        etd->hr = fftw_malloc(N * sizeof(double));
        etd->hc = fftw_malloc(nc * sizeof(fftw_complex));
        etd->hk = fftw_malloc(nc * sizeof(fftw_complex));
        if (!etd->jac || !etd->hr || !etd->hc || !etd->hk) {
            bkf_pde_etd_free(etd);
            return NULL;
        }
        /* a set is 12 rotations of n2 values: cache up to 64 MB of them */
        size_t bytes = 12 * n2 * sizeof(double complex);
        etd->lsets = bytes * ETD_SETS <= ((size_t)64 << 20) ? ETD_SETS : 1;
    }
    return etd;
}

/* e^z and phi_1..3(z) = sum_k z^k / (k + j)!.  Below |z| = 1 the closed
 * forms cancel (phi3 loses ~|z|^-3 of its digits), the series does not. */
static void phis(const bkf_pde_etd *etd, double complex z, double complex *e, double complex *p1,
                 double complex *p2, double complex *p3)
{
    if (cabs(z) < 1.0) {
        double complex zk = 1.0, s1 = 0, s2 = 0, s3 = 0;
        for (int k = 0; k < ETD_TAYLOR_TERMS; k++) {
            s1 += zk * etd->inv_fact[k + 1];
            s2 += zk * etd->inv_fact[k + 2];
            s3 += zk * etd->inv_fact[k + 3];
            zk *= z;
        }
        *e = 1.0 + z * s1;
        *p1 = s1;
        *p2 = s2;
        *p3 = s3;
        return;
    }
    double complex E = cexp(z);
    *e = E;
    *p1 = (E - 1.0) / z;
    *p2 = (E - 1.0 - z) / (z * z);
    *p3 = (E - 1.0 - z - 0.5 * z * z) / (z * z * z);
}

/* The coefficient set of step h, from the cache or computed (NULL: out of
 * memory). */
static const etd_set *coefficients(bkf_pde_etd *etd, double h)
{
    etd_set *victim = &etd->set[0];
    for (int i = 0; i < ETD_SETS; i++) {
        etd_set *s = &etd->set[i];
        if (s->h == h) {
            s->used = ++etd->clock;
            return s;
        }
        if (s->used < victim->used) victim = s;
    }
    etd_set *s = victim;
    if (!s->E) {
        size_t n = etd->n2;
        double complex **arrays[] = {&s->E, &s->E2, &s->Q, &s->f1, &s->f2, &s->f3};
        for (size_t i = 0; i < sizeof arrays / sizeof arrays[0]; i++)
            if (!(*arrays[i] = malloc(n * sizeof(double complex)))) {
                set_free(s);
                return NULL;
            }
    }
    for (size_t i = 0; i < etd->n2; i++) {
        double complex z = etd->lam[i] * h, e, p1, p2, p3, eh, p1h, p2h, p3h;
        phis(etd, z, &e, &p1, &p2, &p3);
        phis(etd, 0.5 * z, &eh, &p1h, &p2h, &p3h);
        s->E[i] = e;
        s->E2[i] = eh;
        s->Q[i] = 0.5 * h * p1h;
        s->f1[i] = h * (p1 - 3.0 * p2 + 4.0 * p3);
        s->f2[i] = h * (p2 - 2.0 * p3);
        s->f3[i] = h * (4.0 * p3 - p2);
    }
    s->h = h;
    s->used = ++etd->clock;
    return s;
}

/* The fast modes' explicit part without its cross-branch coupling (lawson8).
 *
 * Why: the explicit terms act on psi = a+ + a-, so they couple the two
 * branches of a mode k, whose rotations differ by 2 w_k.  In the Lawson
 * variables that coupling oscillates at 2 w_k over a step, which rk8pd's
 * 13 stages resolve up to w_k h of about 3 pi only; beyond, near
 * w_k h = m pi (m >= 4) the per-step errors of the coupling add up in
 * phase from step to step and the mode grows (measured on the n = 4 front,
 * N 16384, h 0.025: from rounding, 3e-16, to 3e-13 over t = 10 in bands
 * centred on k/k_top = 0.65, 0.81, 0.98, the predicted m = 4, 5, 6; rk8pd
 * and lawson8 at N <= 8192 keep them at 1e-15).  The error control then
 * shortens the steps until w_max h is about 2 pi: steps grow like N.
 * In the exact flow that coupling averages out over a period 2 pi/(2 w_k)
 * and changes a mode by O(J/w_k) (J = gamma (1 - psi^2) - sigma_k, the
 * explicit term's derivative).  So for the modes with w_k h >= 3.5 pi
 * (m <= 3 is harmless: nothing grew at N 8192, w_max h = 3.07 pi, nor
 * near k/k_top = 0.49 at 16384), where also w_k >= FAST_MARGIN max |J|, the branch a+ (a-) feels only its own
 * part of the high-mode field: with H+- the fields of a+-_k, k >= kfast,
 *     out+_k = (F(psi) - J H- - sigma_k a+_k)_k / 2, and a- alike,
 * the linearisation being exact to rounding there (H is the field's
 * unresolved tail).  As h -> 0 the set empties and the scheme is plain
 * Lawson again, so it still converges to the semi-discrete system.
 * Cost: two more transform pairs per evaluation (three times the
 * transforms) where the set is not empty; below, none.  Used only where
 * the set's content is not negligible (see fast_start). */
#define FAST_MARGIN 16.0
#define FAST_TURNS 3.5

static void averaged_cross(bkf_pde *m, const double complex *a, double complex *out)
{
    bkf_pde_etd *etd = m->etd;
    size_t N = m->N, nc = etd->nc, kf = etd->kfast;
    double inv = 1.0 / (double)N;
    double complex *hc = (double complex *)etd->hc, *hk = (double complex *)etd->hk;
    for (int branch = 0; branch < 2; branch++) {
        /* the other branch's field, times J, into the spectrum hk */
        const double complex *other = a + (branch ? 0 : nc);
        memset(hc, 0, kf * sizeof *hc);
        memcpy(hc + kf, other + kf, (nc - kf) * sizeof *hc);
        fftw_execute_dft_c2r(m->bwd, etd->hc, etd->hr);
        for (size_t i = 0; i < N; i++) etd->hr[i] *= etd->jac[i] * inv;
        fftw_execute_dft_r2c(m->fwd, etd->hr, etd->hk);
        double complex *o = out + (branch ? nc : 0);
        for (size_t k = kf; k < nc; k++) o[k] -= 0.5 * (hk[k] - etd->sigma[k] * other[k]);
    }
}

/* The first fast mode for step h (see averaged_cross; nc: none): the
 * explicit term's rate is at most gamma max(1, psi_max^2 - 1) + sigma_k.
 *
 * Where the set is not empty and the field above some kin <= kfast holds
 * next to nothing, the modes k >= kin are left out of F's input instead
 * (fast_drop; averaged_cross is not called): they turn exactly, forced by
 * the rest through F, and feed nothing back, so no coupling is left to
 * resonate; the fast set keeps its own branch's filter only.  Why:
 * averaged_cross triples the transforms of an evaluation, which made a
 * step at N 16384 cost 4.4 times one at 8192 (N log N: 2.15); a resolved
 * field's tail there is rounding.  Why kin and not kfast: with only the
 * set left out, the modes just below it (w h just under 3.5 pi, n = 4
 * front, N 16384) grew at about 0.25 per unit time from t = 45 and the
 * steps fell to 0.016.  What is left out of F is J H, H the field of the
 * modes k >= kin: with max |H| <= (2/N) sum |a+-_k| over them, its effect
 * on a step, h max|J| max|H|, must stay under FAST_DROP of the step's
 * tolerance (1e-2 moved the N 16384 field from N 8192's by 1.6e-11 at
 * t = 10, 1e-4 by 2e-12, as the averaged set); otherwise the set is
 * averaged as before. */
#define FAST_DROP 1e-4

static size_t fast_start(bkf_pde_etd *etd, const bkf_pde *m, double h)
{
    size_t nc = etd->nc, kf = nc;
    double J = m->p.gamma * fmax(1.0, etd->psi_max * etd->psi_max - 1.0);
    for (size_t k = 1; k < nc && kf == nc; k++) {
        double w = cimag(etd->lam[k] - etd->lam[nc + k]) / 2;
        if (w * h >= FAST_TURNS * M_PI && w >= FAST_MARGIN * (J + etd->sigma[k])) kf = k;
    }
    etd->fast_drop = 0;
    etd->kin = nc;
    if (kf == nc) return kf;
    /* the lowest kin <= kf whose tail meets the bound (|re| + |im| >= |z|:
     * no square root per mode) */
    const double *ar = (const double *)etd->a;
    double tail = 0.0, bound = FAST_DROP * m->o.tol * (1.0 + etd->psi_max) * m->N / (2 * h * J);
    size_t k = nc;
    while (k > 1) {
        size_t j = k - 1;
        double t = tail + fabs(ar[2 * j]) + fabs(ar[2 * j + 1]) + fabs(ar[2 * (nc + j)]) +
                   fabs(ar[2 * (nc + j) + 1]);
        if (t > bound) break;
        tail = t;
        k = j;
    }
    if (k <= kf) {
        etd->fast_drop = 1;
        /* a new kin costs an evaluation (the step's first stage must be
         * the rate of the same kin), and the lowest one wanders by a few
         * modes from step to step: keep the last while it is within the
         * bound (every kin above the lowest is), and move with a margin */
        size_t last = etd->nu_kin;
        etd->kin = etd->nu_drop && last >= k && last <= kf ? last : GSL_MIN(kf, k + k / 16);
    }
    return kf;
}

/* The grid of the explicit term's product where the modes k >= kin are
 * left out of F's input (fast_drop): the smallest M = 2^j or 3 2^j with
 * M > 6 (kin - 1), when it is at most N/2; else 0 (the field's grid).
 *
 * Why: F's input then holds the modes k < kin only, so its cube holds
 * |k| <= 3 (kin - 1) < M/2: on M points, as on the field's N, the
 * pseudo-spectral product has no aliasing, and the two give the same
 * spectrum (the N-point one holds rounding above 3 (kin - 1), the M-point
 * one zeros).  At N 65536 a resolved n = 4 front has kin ~ 770: the
 * stages' transforms run on 6144 points instead of 65536, and a step's
 * transforms no longer grow with N (only the step end's, the error's and
 * the samples' do).  If a plan cannot be made, M is 0: the field's grid,
 * the same rates. */
static void product_grid(bkf_pde_etd *etd, bkf_pde *m)
{
    size_t M = 0;
    if (etd->fast_drop && etd->kin < etd->nc) {
        size_t need = 6 * (etd->kin > 0 ? etd->kin - 1 : 0) + 1, p = 16;
        while (p < need && 3 * (p / 2) < need) p *= 2;
        M = p >= need ? p : 3 * (p / 2);
        if (2 * M > m->N) M = 0;
    }
    /* the plans of the last M are kept while the field's grid is used */
    if (M && M != etd->cplanned) {
        bkf_fft_lock();
        if (etd->cfwd) fftw_destroy_plan(etd->cfwd);
        if (etd->cbwd) fftw_destroy_plan(etd->cbwd);
        etd->cfwd = fftw_plan_dft_r2c_1d((int)M, m->rbuf, m->cbuf, FFTW_ESTIMATE);
        etd->cbwd = fftw_plan_dft_c2r_1d((int)M, m->cbuf, m->lap, FFTW_ESTIMATE);
        bkf_fft_unlock();
        etd->cplanned = etd->cfwd && etd->cbwd ? M : 0;
    }
    etd->cm = M && M == etd->cplanned ? M : 0;
    m->stats.product_points = etd->cm ? etd->cm : m->N;
}

/* D' = dH/dt of the state a (lawson8; pde.h), the rate the Runge-Kutta
 * path integrates (src/simulation/pde.c: rhs, rhs_frame), in a form that needs two more
 * transforms per evaluation where the x-space form of rhs_frame would need
 * four.  With u = gamma (eta - phi(psi)), J = gamma (psi^2 - 1),
 * f = psi - nu - c^2 L psi and the filter F, the general
 *     dH/dt = h sum [u u_t + f psi_t]
 * becomes, after psi_t = u - F psi + V psi_x and eta_t = -f/gamma + V eta_x,
 *     dH/dt = h [gamma V sum u eta_x - sum J u psi_t - sum f F psi]
 * (V sum f psi_x = 0: a skew operator).  Only J u is a product in x; the
 * sums are Parseval sums over the spectra psi_t, u, eta and psi, which the
 * a+- state gives.  Expects what nonlinear() leaves: m->lap = N psi,
 * m->rbuf = gamma (psi - psi^3/3) and m->cbuf its transform, etd->pk. */
static double dissipation_rate(bkf_pde *m, const double complex *a)
{
    bkf_pde_etd *etd = m->etd;
    size_t N = m->N, nc = etd->nc;
    double g = m->p.gamma, inv = 1.0 / (double)N;
    const double *ap = (const double *)a, *am = (const double *)(a + nc);
    const double *pk = (const double *)etd->pk, *rk = (const double *)m->cbuf;
    double *hc = (double *)etd->hc;
    for (size_t k = 0; k < nc; k++) {
        double wg = 1.0 / etd->ratio[k];
        hc[2 * k] = -(ap[2 * k + 1] - am[2 * k + 1]) * wg;
        hc[2 * k + 1] = (ap[2 * k] - am[2 * k]) * wg;
    }
    fftw_execute_dft_c2r(m->bwd, etd->hc, etd->hr);
    for (size_t i = 0; i < N; i++) {
        double x = m->lap[i] * inv;
        etd->hr[i] = g * (x * x - 1.0) * (g * etd->hr[i] * inv + m->rbuf[i]);
    }
    fftw_execute_dft_r2c(m->fwd, etd->hr, etd->hk);
    const double *gk = (const double *)etd->hk;
    double ju = 0.0, ff = 0.0, ue = 0.0;
    for (size_t k = 0; k < nc; k++) {
        double wt = k == 0 || 2 * k == N ? 1.0 : 2.0, wg = 1.0 / etd->ratio[k];
        double adv = cimag(etd->lam[k] + etd->lam[nc + k]) / 2, sg = etd->sigma[k];
        double er = -(ap[2 * k + 1] - am[2 * k + 1]) * wg, ei = (ap[2 * k] - am[2 * k]) * wg;
        double pr = pk[2 * k], pi = pk[2 * k + 1];
        double ur = g * er + rk[2 * k], ui = g * ei + rk[2 * k + 1];
        double xr = ur - sg * pr - adv * pi, xi = ui - sg * pi + adv * pr;
        double w2 = (g * wg) * (g * wg);
        ju += wt * (gk[2 * k] * xr + gk[2 * k + 1] * xi);
        ff += wt * w2 * sg * (pr * pr + pi * pi);
        ue += wt * adv * (ui * er - ur * ei);
    }
    /* Parseval: sum_i a_i b_i = (1/N) sum_k A_k conj(B_k) */
    return m->h * inv * (g * ue - ju - ff);
}

/* The explicit part N(a) in the a+- variables into out (and lawson8's
 * i D' into out[n2] unless d_off); *psi_max gets max |psi|.  Nonzero if
 * the field is not finite or beyond BLOWUP. */
static int nonlinear(bkf_pde *m, const double complex *a, double complex *out, double *psi_max)
{
    bkf_pde_etd *etd = m->etd;
    size_t N = m->N, nc = etd->nc;
    double complex *cb = cbuf_of(m);
    size_t kf = etd->kfast, kin = etd->kin;
    for (size_t k = 0; k < nc; k++) cb[k] = etd->pk[k] = a[k] + a[nc + k];
    /* F's input without a negligible fast set (see fast_start) */
    memset(cb + kin, 0, (nc - kin) * sizeof *cb);
    fftw_execute_dft_c2r(m->bwd, m->cbuf, m->lap);
    double g = m->p.gamma, inv = 1.0 / (double)N, big = 0.0;
    int bad = 0;
    for (size_t i = 0; i < N; i++) {
        double x = m->lap[i] * inv, a = fabs(x);
        /* compare and or, not fmax: this loop is a tenth of a step */
        big = a > big ? a : big;
        bad |= !(a <= BLOWUP);
        m->rbuf[i] = g * (x - x * x * x * (1.0 / 3.0));
    }
    if (!etd->fast_drop && kf < nc)
        for (size_t i = 0; i < N; i++) {
            double x = m->lap[i] * inv;
            etd->jac[i] = g * (1.0 - x * x);
        }
    if (bad) return 1;
    if (psi_max) *psi_max = big;
    fftw_execute_dft_r2c(m->fwd, m->rbuf, m->cbuf);
    /* nu/gamma in eta_t is the k = 0 coefficient nu N / gamma */
    double ne0 = m->p.nu / g * (double)N;
    for (size_t k = 0; k < nc; k++) {
        double complex np = cb[k] - etd->sigma[k] * etd->pk[k];
        double complex ne = k == 0 ? ne0 : 0.0;
        double complex r = I * etd->ratio[k] * ne;
        out[k] = 0.5 * (np - r);
        out[nc + k] = 0.5 * (np + r);
    }
    /* a dropped set keeps only its own branch's filter term */
    if (etd->fast_drop)
        for (size_t k = kf; k < nc; k++) {
            out[k] += 0.5 * etd->sigma[k] * a[nc + k];
            out[nc + k] += 0.5 * etd->sigma[k] * a[k];
        }
    /* Q' = mean(psi) is linear: it belongs to the linear part (q_part) */
    if (etd->rk) out[etd->n2] = I * (etd->d_off ? 0.0 : dissipation_rate(m, a));
    if (!etd->fast_drop && kf < nc) averaged_cross(m, a, out);
    return 0;
}

/* psi and eta of the a+- state a into y (N values each). */
static void to_physical(bkf_pde *m, const double complex *a, double *y)
{
    bkf_pde_etd *etd = m->etd;
    size_t N = m->N, nc = etd->nc;
    double complex *cb = cbuf_of(m);
    double inv = 1.0 / (double)N;
    for (size_t k = 0; k < nc; k++) cb[k] = a[k] + a[nc + k];
    fftw_execute_dft_c2r(m->bwd, m->cbuf, m->lap);
    for (size_t i = 0; i < N; i++) y[i] = m->lap[i] * inv;
    for (size_t k = 0; k < nc; k++) cb[k] = I / etd->ratio[k] * (a[k] - a[nc + k]);
    fftw_execute_dft_c2r(m->bwd, m->cbuf, m->lap);
    for (size_t i = 0; i < N; i++) y[N + i] = m->lap[i] * inv;
    y[2 * N] = etd->rk ? creal(a[etd->n2]) : NAN;
    y[2 * N + 1] = etd->rk ? cimag(a[etd->n2]) : NAN;
}

static void from_physical(bkf_pde *m)
{
    bkf_pde_etd *etd = m->etd;
    size_t N = m->N, nc = etd->nc;
    double complex *cb = cbuf_of(m);
    memcpy(m->rbuf, m->y, N * sizeof *m->y);
    fftw_execute_dft_r2c(m->fwd, m->rbuf, m->cbuf);
    for (size_t k = 0; k < nc; k++) etd->pk[k] = cb[k];
    memcpy(m->rbuf, m->y + N, N * sizeof *m->y);
    fftw_execute_dft_r2c(m->fwd, m->rbuf, m->cbuf);
    for (size_t k = 0; k < nc; k++) {
        double complex r = I * etd->ratio[k] * cb[k];
        etd->a[k] = 0.5 * (etd->pk[k] - r);
        etd->a[nc + k] = 0.5 * (etd->pk[k] + r);
    }
    etd->a[etd->n2] = m->y[2 * N] + I * m->y[2 * N + 1];
    etd->valid = 1;
    etd->have_nu = 0;
}

/* Largest |value| of the field whose a+- coefficients are e, as psi
 * (which = 0) or eta (which = 1). */
static double field_max(bkf_pde *m, const double complex *e, int which)
{
    bkf_pde_etd *etd = m->etd;
    size_t N = m->N, nc = etd->nc;
    double complex *cb = cbuf_of(m);
    for (size_t k = 0; k < nc; k++)
        cb[k] = which ? I / etd->ratio[k] * (e[k] - e[nc + k]) : e[k] + e[nc + k];
    fftw_execute_dft_c2r(m->bwd, m->cbuf, m->lap);
    /* compare, not fmax (a call per point): a NaN is skipped as fmax
     * skips it (the step's fields were checked finite by nonlinear) */
    double big = 0.0;
    for (size_t i = 0; i < N; i++) {
        double v = fabs(m->lap[i]);
        big = v > big ? v : big;
    }
    return big / (double)N;
}

enum { STEP_OK = 0, STEP_NONFINITE = 1, STEP_NOMEM = 2 };

/* One ETDRK4 step of size h from etd->a into etd->anew (and N(anew) into
 * etd->nnew, its largest |psi| into *psi_max_new); *err_ratio gets the
 * estimated local error over the tolerance (accept when <= 1).  N(a) is
 * in etd->nu (bkf_pde_etd_run evaluates it first). */
static int step(bkf_pde *m, double h, double *err_ratio, double *psi_max_new)
{
    bkf_pde_etd *etd = m->etd;
    size_t n2 = etd->n2;
    const etd_set *c = coefficients(etd, h);
    if (!c) return STEP_NOMEM;
    double complex *restrict a = etd->a, *restrict sa = etd->sa, *restrict s = etd->s;
    const double complex *restrict nu = etd->nu;
    double complex *restrict na = etd->na, *restrict nb = etd->nb, *restrict ncv = etd->nc_;
    for (size_t i = 0; i < n2; i++) sa[i] = c->E2[i] * a[i] + c->Q[i] * nu[i];
    m->stats.rhs_calls += 3;
    if (nonlinear(m, sa, na, NULL)) return STEP_NONFINITE;
    for (size_t i = 0; i < n2; i++) s[i] = c->E2[i] * a[i] + c->Q[i] * na[i];
    if (nonlinear(m, s, nb, NULL)) return STEP_NONFINITE;
    for (size_t i = 0; i < n2; i++) s[i] = c->E2[i] * sa[i] + c->Q[i] * (2.0 * nb[i] - nu[i]);
    if (nonlinear(m, s, ncv, NULL)) return STEP_NONFINITE;
    double complex *restrict an = etd->anew;
    for (size_t i = 0; i < n2; i++) {
        an[i] = c->E[i] * a[i] + c->f1[i] * nu[i] + 2.0 * c->f2[i] * (na[i] + nb[i]) +
                c->f3[i] * ncv[i];
    }
    m->stats.rhs_calls++;
    if (nonlinear(m, an, etd->nnew, psi_max_new)) return STEP_NONFINITE;
    for (size_t i = 0; i < n2; i++) s[i] = c->f3[i] * (ncv[i] - etd->nnew[i]);
    /* The Runge-Kutta control's tol (1 + |y|), with the state's largest
     * |psi| as the scale of both fields. */
    double scale = m->o.tol * (1.0 + etd->psi_max);
    double e = fmax(field_max(m, s, 0), field_max(m, s, 1));
    *err_ratio = isfinite(e) ? e / scale : INFINITY;
    return STEP_OK;
}

/* ------------------------------------------------------------- lawson8
 *
 * Lawson's integrating-factor method: with v(tau) = exp(-L tau) a(t_s + tau)
 * over one step from t_s, v' = exp(-L tau) N(exp(L tau) v) has no wave
 * part left, and GSL's rk8pd (Prince-Dormand 8(7), the default explicit
 * stepper's pair) integrates it with its embedded error estimate.  Every
 * linear rate is imaginary, so exp(-L tau) = conj(exp(L tau)) and
 * |exp(L tau)| = 1: the rotations change neither the error's size per
 * mode nor the stability, which the explicit friction (rates ~3 gamma) and
 * the filter (<= its sigma_max) set, not N.  Eighth order lets the steps
 * grow to the dynamics' scale at tight tol where ETDRK4's fourth order
 * keeps them short (tol 1e-9, n = 4 fronts: 0.003 against 0.03). */

/* The set of rotations for step size h (NULL: out of memory). */
static lawson_set *lawson_select(bkf_pde_etd *etd, double h)
{
    lawson_set *victim = &etd->lset[0];
    for (size_t i = 0; i < etd->lsets; i++) {
        lawson_set *s = &etd->lset[i];
        if (s->h == h) {
            s->used = ++etd->clock;
            return etd->lcur = s;
        }
        if (s->used < victim->used) victim = s;
    }
    victim->h = h;
    victim->count = 0;
    victim->used = ++etd->clock;
    return etd->lcur = victim;
}

/* exp(lam tau) of the current set, computed on first use (NULL: out of
 * memory or more offsets than the set holds). */
static const double complex *rotation(bkf_pde_etd *etd, double tau)
{
    lawson_set *s = etd->lcur;
    for (size_t k = 0; k < s->count; k++)
        if (s->tau[k] == tau) return s->E[k];
    if (s->count == LAWSON_TAUS) return NULL;
    size_t k = s->count;
    if (!s->E[k] && !(s->E[k] = malloc(etd->n2 * sizeof(double complex)))) return NULL;
    for (size_t i = 0; i < etd->n2; i++) s->E[k][i] = cexp(etd->lam[i] * tau);
    s->tau[k] = tau;
    s->count++;
    return s->E[k];
}

/* Q's row of exp(L tau) (lawson8), applied to the state x: the change of Q.
 *
 * Why: Q' = psi_0 / N is linear in the state, so it is part of L, with
 * exp(L tau) taking Q to Q + [a+_0 (e^{i tau} - 1)/i - a-_0 (e^{-i tau} - 1)/i] / N
 * (the k = 0 branches turn at +-1).  Then the linear invariant
 * mean(eta) + (Q - nu t)/gamma is a functional l with l L = 0, so
 * l exp(L tau) = l, and l N(u) = nu/gamma for every u: Lawson's stages
 * keep it to rounding, as plain Runge-Kutta does.  As an explicit rate,
 * rotated back by exp(-L tau) like the rest, Q drifted from it by an
 * eighth-order error (1e-12 over t = 20 at tol 1e-7, steps of 0.08).
 * e^{i tau} - 1 is formed from sines: it must not cancel for short tau. */
static double q_part_of(const bkf_pde_etd *etd, double tau, double complex plus0,
                        double complex minus0)
{
    double s = sin(0.5 * tau);
    double complex em1 = -2.0 * s * s + I * sin(tau);
    return creal(-I * em1 * plus0 + I * conj(em1) * minus0) / (double)etd->owner->N;
}

static double q_part(const bkf_pde_etd *etd, double tau, const double complex *x)
{
    return q_part_of(etd, tau, x[0], x[etd->nc]);
}

/* lawson_stage where nothing but the rate itself is wanted (no D', no
 * averaged fast set): the rotation, F's input, the explicit part and the
 * rotation back in two passes over the modes instead of five.
 *
 * Why: past the second-level cache (N >= 16384) the passes, not the
 * arithmetic, set a stage's cost; each pass streams n2 complex values.
 * Nothing is stored between the passes but F's input and output: the
 * second pass forms exp(lam tau) v again from v, and a dropped fast mode's
 * own-branch rate rotated back, conj(E) (F - sigma E v) / 2, is
 * (conj(E) F - sigma v) / 2 (|E| = 1). */
static int lawson_stage_fused(bkf_pde *m, double tau, const double *e, const double *v,
                              double *dydt)
{
    bkf_pde_etd *etd = m->etd;
    size_t N = m->N, nc = etd->nc, kin = etd->kin;
    size_t kf = etd->fast_drop ? etd->kfast : nc;
    /* in the lab frame the a- branch turns back: E- = conj(E+), read once */
    const double *em = etd->mirrored ? e : e + 2 * nc, *vm = v + 2 * nc;
    const double ms = etd->mirrored ? -1.0 : 1.0;
    double *cb = (double *)m->cbuf;
    /* F on M points (product_grid): the spectrum is M/N of the field's */
    size_t M = etd->cm ? etd->cm : N, mc = M / 2 + 1;
    fftw_plan bwd = etd->cm ? etd->cbwd : m->bwd, fwd = etd->cm ? etd->cfwd : m->fwd;
    for (size_t k = 0; k < kin; k++) {
        double er = e[2 * k], ei = e[2 * k + 1], vr = v[2 * k], vi = v[2 * k + 1];
        double fr = em[2 * k], fi = ms * em[2 * k + 1], wr = vm[2 * k], wi = vm[2 * k + 1];
        cb[2 * k] = (er * vr - ei * vi) + (fr * wr - fi * wi);
        cb[2 * k + 1] = (er * vi + ei * vr) + (fr * wi + fi * wr);
    }
    memset(cb + 2 * kin, 0, 2 * (mc - kin) * sizeof *cb);
    fftw_execute_dft_c2r(bwd, m->cbuf, m->lap);
    double g = m->p.gamma, inv = 1.0 / (double)N;
    int bad = 0;
    for (size_t i = 0; i < M; i++) {
        double x = m->lap[i] * inv;
        bad |= !(fabs(x) <= BLOWUP);
        m->rbuf[i] = g * (x - x * x * x * (1.0 / 3.0));
    }
    if (bad) return GSL_EBADFUNC;
    fftw_execute_dft_r2c(fwd, m->rbuf, m->cbuf);
    double *dm = dydt + 2 * nc, scale = (double)N / (double)M;
    for (size_t k = 0; k < nc; k++) {
        double er = e[2 * k], ei = e[2 * k + 1], vr = v[2 * k], vi = v[2 * k + 1];
        double fr = em[2 * k], fi = ms * em[2 * k + 1], wr = vm[2 * k], wi = vm[2 * k + 1];
        double Fr = k < mc ? scale * cb[2 * k] : 0.0, Fi = k < mc ? scale * cb[2 * k + 1] : 0.0;
        double sg = etd->sigma[k];
        /* conj(E) F / 2 for either branch */
        double ar = 0.5 * (er * Fr + ei * Fi), ai = 0.5 * (er * Fi - ei * Fr);
        double br = 0.5 * (fr * Fr + fi * Fi), bi = 0.5 * (fr * Fi - fi * Fr);
        if (k >= kf) {
            dydt[2 * k] = ar - 0.5 * sg * vr;
            dydt[2 * k + 1] = ai - 0.5 * sg * vi;
            dm[2 * k] = br - 0.5 * sg * wr;
            dm[2 * k + 1] = bi - 0.5 * sg * wi;
        } else {
            /* sigma (E+ v+ + E- v-) / 2, rotated back by each branch */
            double pr = 0.5 * sg * ((er * vr - ei * vi) + (fr * wr - fi * wi));
            double pi = 0.5 * sg * ((er * vi + ei * vr) + (fr * wi + fi * wr));
            dydt[2 * k] = ar - (er * pr + ei * pi);
            dydt[2 * k + 1] = ai - (er * pi - ei * pr);
            dm[2 * k] = br - (fr * pr + fi * pi);
            dm[2 * k + 1] = bi - (fr * pi - fi * pr);
        }
    }
    /* k = 0: nu/gamma in eta_t, -+ i ratio_0 nu N / gamma / 2 on the two
     * branches (nonlinear's r), and Q' from the unrotated rates there */
    double complex u0p = (e[0] + I * e[1]) * (v[0] + I * v[1]);
    double complex u0m = (em[0] + I * ms * em[1]) * (vm[0] + I * vm[1]);
    double complex np0 = scale * (cb[0] + I * cb[1]) - etd->sigma[0] * (u0p + u0m);
    double complex r0 = I * etd->ratio[0] * (m->p.nu / g * (double)N);
    double complex o0p = 0.5 * (np0 - r0), o0m = 0.5 * (np0 + r0);
    double complex d0p = conj(e[0] + I * e[1]) * o0p, d0m = conj(em[0] + I * ms * em[1]) * o0m;
    dydt[0] = creal(d0p);
    dydt[1] = cimag(d0p);
    dm[0] = creal(d0m);
    dm[1] = cimag(d0m);
    double *dq = dydt + 2 * etd->n2;
    dq[0] = q_part_of(etd, -tau, o0p, o0m);
    dq[1] = 0.0;
    return GSL_SUCCESS;
}

/* One evaluation of v' = exp(-L tau) N(exp(L tau) v). */
static int lawson_stage(bkf_pde *m, double tau, const double y[], double dydt[])
{
    bkf_pde_etd *etd = m->etd;
    size_t n2 = etd->n2;
    const double complex *v = (const double complex *)y;
    double complex *out = (double complex *)dydt;
    if (tau == 0) return nonlinear(m, v, out, NULL) ? GSL_EBADFUNC : GSL_SUCCESS;
    const double complex *E = rotation(etd, tau);
    if (!E) return GSL_ENOMEM;
    if (etd->d_off && (etd->fast_drop || etd->kfast == etd->nc)) {
        return lawson_stage_fused(m, tau, (const double *)E, y, dydt);
    }
    /* in real arithmetic: C's complex product checks for infinities and
     * costs as much as the transforms here */
    const double *e = (const double *)E, *vv = y;
    double *u = (double *)etd->sa;
    for (size_t i = 0; i < n2; i++) {
        double er = e[2 * i], ei = e[2 * i + 1], vr = vv[2 * i], vi = vv[2 * i + 1];
        u[2 * i] = er * vr - ei * vi;
        u[2 * i + 1] = er * vi + ei * vr;
    }
    if (nonlinear(m, etd->sa, out, NULL)) return GSL_EBADFUNC;
    /* Q and D do not enter N: exp(L tau) v's own Q is not needed */
    out[n2] += q_part(etd, -tau, out);
    for (size_t i = 0; i < n2; i++) {
        double er = e[2 * i], ei = e[2 * i + 1], or_ = dydt[2 * i], oi = dydt[2 * i + 1];
        dydt[2 * i] = er * or_ + ei * oi;
        dydt[2 * i + 1] = er * oi - ei * or_;
    }
    return GSL_SUCCESS;
}

static int lawson_rhs(double tau, const double y[], double dydt[], void *params)
{
    bkf_pde *m = params;
    bkf_pde_etd *etd = m->etd;
    m->stats.rhs_calls++;
    /* GSL evaluates rk8pd's stages 2..13 in order, and stages 2..5 have
     * weight 0 in both of its solutions (its A and Abar): their Q' and D'
     * would reach nothing, as no rate depends on Q or D (a third of the
     * quadratures' cost) */
    size_t stage = ++etd->calls + 1;
    etd->d_off = !etd->d_staged || stage <= 5;
    int rc = lawson_stage(m, tau, y, dydt);
    etd->d_off = 0;
    return rc;
}

/* D over a step from the step ends (lawson8).
 *
 * Why: carried on rk8pd's stages, D had the largest error of the state
 * (0.1-0.8 of tol where the fields' was 0.003): its rate is quadratic in
 * the field and weights the a- branch, which in the Lawson variables turns
 * at (v + c) q where the field turns at v q, so the stages' interior
 * values, accurate enough for the fields, were not for D'.  Under the
 * error control it held the steps at 0.02 instead of 0.025 (25% more)
 * and its two transforms at 9 of the 13 stages cost 70% more per step.
 * At the step ends the field is accurate to tol, and D'(t) there is a
 * smooth function of time (constant for a steady wave): the polynomial
 * through the last DQ_POINTS ends (the new one included) integrated over
 * the step is of order DQ_POINTS + 1 in the step size, at one D'
 * evaluation a step.  Its error estimate is the difference from the
 * polynomial through one end fewer; stats.d_err sums it over the steps.
 * Until DQ_POINTS - 1 ends are known (the first steps after a state is
 * set) D rides on the stages as before, under the error control.
 * Nodes need not be equally spaced; the integral over [0, 1] (the step)
 * of the Lagrange basis is exact with 5 Gauss-Legendre points up to
 * degree 9. */
static double lagrange_integral(const double *s, const double *r, size_t n)
{
    static const double gx[5] = {0.0469100770306680, 0.2307653449471585, 0.5,
                                 0.7692346550528415, 0.9530899229693320};
    static const double gw[5] = {0.1184634425280945, 0.2393143352496832, 0.2844444444444444,
                                 0.2393143352496832, 0.1184634425280945};
    double sum = 0.0;
    for (int g = 0; g < 5; g++)
        for (size_t j = 0; j < n; j++) {
            double l = gw[g] * r[j];
            for (size_t k = 0; k < n; k++)
                if (k != j) l *= (gx[g] - s[k]) / (s[j] - s[k]);
            sum += l;
        }
    return sum;
}

static void dq_increment(bkf_pde_etd *etd, double h, double r_new)
{
    double s[DQ_POINTS], r[DQ_POINTS];
    s[0] = 1.0;
    r[0] = r_new;
    for (size_t j = 1; j < DQ_POINTS; j++) {
        s[j] = (etd->dq_t[j - 1] - etd->dq_t[0]) / h;
        r[j] = etd->dq_r[j - 1];
    }
    double hi = lagrange_integral(s, r, DQ_POINTS), lo = lagrange_integral(s, r, DQ_POINTS - 1);
    etd->dq_inc = h * hi;
    etd->dq_est = h * fabs(hi - lo);
}

/* The accepted step end t and its D' (etd->nu[n2]) join the history. */
static void dq_push(bkf_pde_etd *etd, double t)
{
    memmove(etd->dq_t + 1, etd->dq_t, (DQ_POINTS - 1) * sizeof *etd->dq_t);
    memmove(etd->dq_r + 1, etd->dq_r, (DQ_POINTS - 1) * sizeof *etd->dq_r);
    etd->dq_t[0] = t;
    etd->dq_r[0] = cimag(etd->nu[etd->n2]);
    if (etd->dq_n < DQ_POINTS) etd->dq_n++;
}

/* One lawson8 step, with the contract of step(). */
static int step_lawson(bkf_pde *m, double h, double *err_ratio, double *psi_max_new)
{
    bkf_pde_etd *etd = m->etd;
    size_t n2 = etd->n2;
    lawson_select(etd, h);
    etd->kfast = fast_start(etd, m, h);
    product_grid(etd, m);
    if (etd->kfast != etd->nu_kfast || etd->fast_drop != etd->nu_drop || etd->kin != etd->nu_kin) {
        /* the first stage must be the same right-hand side */
        m->stats.rhs_calls++;
        if (nonlinear(m, etd->a, etd->nu, NULL)) return STEP_NONFINITE;
        etd->nu_kfast = etd->kfast;
        etd->nu_drop = etd->fast_drop;
        etd->nu_kin = etd->kin;
    }
    etd->d_staged = etd->dq_n + 1 < DQ_POINTS || etd->dq_clean < DQ_POINTS;
    for (;;) {
        memcpy(etd->anew, etd->a, (n2 + 1) * sizeof *etd->a);
        etd->calls = 0;
        /* the first stage's D' too is left to dq_increment, unless staged */
        double complex rate0 = etd->nu[n2];
        if (!etd->d_staged) etd->nu[n2] = creal(rate0);
        int rc = gsl_odeiv2_step_apply(etd->rk, 0.0, h, (double *)etd->anew, (double *)etd->s,
                                       (const double *)etd->nu, NULL, &etd->sys);
        etd->nu[n2] = rate0;
        if (rc == GSL_ENOMEM) return STEP_NOMEM;
        if (rc != GSL_SUCCESS) return STEP_NONFINITE;
        const double complex *E = rotation(etd, h);
        if (!E) return STEP_NOMEM;
        etd->anew[n2] += q_part(etd, h, etd->anew);
        etd->s[n2] += q_part(etd, h, etd->s);
        double *an = (double *)etd->anew, *sn = (double *)etd->s;
        const double *e = (const double *)E;
        for (size_t i = 0; i < 2 * n2; i += 2) {
            double er = e[i], ei = e[i + 1], ar = an[i], ai = an[i + 1], sr = sn[i], si = sn[i + 1];
            an[i] = er * ar - ei * ai;
            an[i + 1] = er * ai + ei * ar;
            sn[i] = er * sr - ei * si;
            sn[i + 1] = er * si + ei * sr;
        }
        m->stats.rhs_calls++;
        if (nonlinear(m, etd->anew, etd->nnew, psi_max_new)) return STEP_NONFINITE;
        /* D's bound per step: the Runge-Kutta path's tol (1 + |D|) */
        double d_tol = m->o.tol * (1.0 + fabs(cimag(etd->anew[n2])));
        if (etd->dq_n + 1 >= DQ_POINTS) {
            dq_increment(etd, h, cimag(etd->nnew[n2]));
            /* staged, the ends must resolve D'(t) with a wide margin
             * (DQ_POINTS steps running) before they take D over again */
            if (etd->d_staged) etd->dq_clean = etd->dq_est <= 1e-2 * d_tol ? etd->dq_clean + 1 : 0;
        }
        if (etd->d_staged) break;
        if (etd->dq_est <= d_tol) {
            etd->anew[n2] += I * etd->dq_inc;
            break;
        }
        /* the ends do not resolve D'(t) (on an under-resolved grid it
         * oscillates at the rate the fronts cross grid points): redo the
         * step with D on the stages */
        m->stats.rejected++;
        etd->dq_clean = 0;
        etd->d_staged = 1;
    }
    double scale = m->o.tol * (1.0 + etd->psi_max);
    double e = fmax(field_max(m, etd->s, 0), field_max(m, etd->s, 1));
    *err_ratio = isfinite(e) ? e / scale : INFINITY;
    /* the quadratures under the Runge-Kutta path's control, tol (1 + |y|)
     * per component (D's error is 0 here when dq_increment integrates it) */
    for (int j = 0; j < 2; j++) {
        double q = j ? cimag(etd->anew[n2]) : creal(etd->anew[n2]);
        double dq = j ? cimag(etd->s[n2]) : creal(etd->s[n2]);
        *err_ratio = fmax(*err_ratio, fabs(dq) / (m->o.tol * (1.0 + fabs(q))));
    }
    return STEP_OK;
}

/* Steps per piece of a sample interval, rounded up to 1..6, 8, 10, 12,
 * 16, 20, 24, 32, ...: few distinct sizes, so the coefficient cache hits
 * even where the error control wants a new size at every step (irregular
 * patterns); the rungs are at most 25% apart. */
static double nice_count(double count)
{
    if (count <= 6) return count;
    for (double p = 8;; p *= 2)
        for (int k = 0; k < 3; k++)
            if (p * (1 + 0.25 * k) >= count) return p * (1 + 0.25 * k);
}

/* The integrator's state into m->y at time t (every return path). */
static void sync(bkf_pde *m, double t)
{
    to_physical(m, m->etd->a, m->y);
    m->t = t;
}

int bkf_pde_etd_run(bkf_pde *m, double t_end, double sample_dt, bkf_pde_observer observer,
                    void *odata, bkf_pde_progress progress, void *pdata, bkf_error *err)
{
    bkf_pde_etd *etd = m->etd;
    size_t N = m->N;
    double t0 = m->t;
    m->stats.stopped = 0;
    if (!etd->valid) from_physical(m);
    if (!etd->rk) m->y[2 * N] = m->y[2 * N + 1] = NAN;
    if (!etd->have_nu) {
        if (nonlinear(m, etd->a, etd->nu, &etd->psi_max))
            return bkf_error_set(err, BKF_EBLOWUP, "the initial state is not finite or too large");
        etd->have_nu = 1;
        etd->nu_kfast = etd->kfast;
        etd->nu_drop = etd->fast_drop;
        etd->nu_kin = etd->kin;
        m->stats.rhs_calls++;
        etd->dq_n = 0;
        etd->dq_clean = DQ_POINTS;
        if (etd->rk) dq_push(etd, m->t);
    }
    if (observer && bkf_pde_emit(m, observer, odata, t0, m->y)) {
        m->stats.stopped = 1;
        return BKF_OK;
    }
    /* Samples closer than this to t_end are t_end (as in the Runge-Kutta
     * loop). */
    double span = t_end - t0;
    double slack = 1e-9 * sample_dt + 4 * 2.2e-16 * fabs(t_end);
    size_t full = observer ? (size_t)floor((span + slack) / sample_dt) : 0;
    int tail = !observer || t0 + (double)full * sample_dt < t_end - slack;
    size_t segments = full + (size_t)tail;
    size_t steps_here = 0;
    double h_prev = 0.0;
    const double h_floor = 1e-12 * fmax(1.0, fabs(t_end));
    for (size_t seg = 0; seg < segments; seg++) {
        double ta = m->t;
        double tb = seg + 1 == segments ? t_end : t0 + (double)(seg + 1) * sample_dt;
        double pieces = fmax(1.0, ceil((tb - ta) / ETD_H_MAX - 1e-12));
        for (double piece = 1; piece <= pieces; piece++) {
            double pb = piece == pieces ? tb : ta + (tb - ta) * (piece / pieces);
            int fresh = 1;
            while (m->t < pb) {
                double left = pb - m->t, want = fmin(m->hstep, ETD_H_MAX), h, count;
                double kept = h_prev > 0 ? left / h_prev : 0;
                if (!fresh && h_prev <= want * (1 + 1e-9) && kept >= 0.5 &&
                    fabs(kept - round(kept)) <= 1e-9 * kept) {
                    h = h_prev;
                    count = round(kept);
                } else {
                    count = fmax(1.0, ceil(left / want - 1e-9));
                    if (fresh) count = nice_count(count);
                    h = left / count;
                    if (fabs(h - h_prev) <= 1e-12 * h_prev) h = h_prev;
                }
                fresh = 0;
                double ratio = INFINITY, psi_max_new = NAN;
                int s = etd->rk ? step_lawson(m, h, &ratio, &psi_max_new)
                                : step(m, h, &ratio, &psi_max_new);
                if (s == STEP_NOMEM) {
                    sync(m, m->t);
                    return bkf_error_set(err, BKF_ENOMEM, "out of memory");
                }
                if (s == STEP_NONFINITE || !(ratio <= 1.0)) {
                    m->stats.rejected++;
                    double shrink = s == STEP_NONFINITE || !isfinite(ratio)
                                        ? 0.25
                                        : fmax(0.2, 0.9 * pow(ratio, -etd->expo));
                    m->hstep = fmin(m->hstep, h) * shrink;
                    if (m->hstep < h_floor) {
                        sync(m, m->t);
                        if (s == STEP_NONFINITE)
                            return bkf_error_set(err, BKF_EBLOWUP,
                                                 "the field blew up at t = %.6g (|psi| > %g or not "
                                                 "finite)", m->t, BLOWUP);
                        return bkf_error_set(err, BKF_ENUMERIC,
                                             "step size underflow at t = %.6g (tol %g cannot "
                                             "be met)",
                                             m->t, m->o.tol);
                    }
                    continue;
                }
                h_prev = h;
                double complex *tmp = etd->a;
                etd->a = etd->anew;
                etd->anew = tmp;
                tmp = etd->nu;
                etd->nu = etd->nnew;
                etd->nnew = tmp;
                etd->psi_max = psi_max_new;
                m->t = count == 1 ? pb : m->t + h;
                if (etd->rk) {
                    dq_push(etd, m->t);
                    if (!etd->d_staged) m->stats.d_err += etd->dq_est;
                }
                m->stats.steps++;
                steps_here++;
                m->stats.h_last = h;
                m->stats.h_min = fmin(m->stats.h_min, h);
                m->stats.h_max = fmax(m->stats.h_max, h);
                double grow = ratio > 0 ? fmin(4.0, fmax(0.2, 0.9 * pow(ratio, -etd->expo))) : 4.0;
                m->hstep = fmin(h * grow, ETD_H_MAX);
                if (m->t == tb && observer) {
                    to_physical(m, etd->a, m->sample);
                    if (bkf_pde_emit(m, observer, odata, m->t, m->sample)) {
                        m->stats.stopped = 1;
                        sync(m, m->t);
                        return BKF_OK;
                    }
                }
                if (progress && progress((m->t - t0) / span, pdata)) {
                    m->stats.stopped = 1;
                    sync(m, m->t);
                    return BKF_OK;
                }
                if (m->o.cancel && *m->o.cancel && m->t < t_end) {
                    m->stats.stopped = 1;
                    sync(m, m->t);
                    return bkf_error_set(err, BKF_ECANCELED, "canceled at t = %.9g of %.9g", m->t,
                                         t_end);
                }
                if (m->o.max_steps && steps_here >= m->o.max_steps && m->t < t_end) {
                    sync(m, m->t);
                    return bkf_error_set(err, BKF_EBUDGET, "more than %zu steps before t = %g",
                                         m->o.max_steps, t_end);
                }
            }
        }
    }
    sync(m, t_end);
    return BKF_OK;
}

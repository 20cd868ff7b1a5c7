/* Internal to the periodic-orbit solver (orbit.c, orbit_newton.c,
 * orbit_mult.c, orbit_flow.c): the object's layout and the flow they
 * share.  orbit_flow.c sits below the others (it calls none of them),
 * orbit_newton.c and orbit_mult.c use it, orbit.c uses all three.  Not
 * installed, not part of the API. */
#ifndef BKFRONT_ORBIT_INTERNAL_H
#define BKFRONT_ORBIT_INTERNAL_H

#include <fftw3.h>
#include <gsl/gsl_odeiv2.h>

#include "bkfront/orbit.h"
#include "pde_internal.h"

/* The flow of one grid: the simulator's object for its right-hand side,
 * a GSL rk8pd integrator of the state (2N + 2 values: psi, eta and the
 * simulator's two quadratures, held constant here) with the tangent
 * (2N more) alongside when asked, and the grid's shift operator. */
typedef struct {
    bkf_pde *pde;
    bkf_model_kind kind;
    size_t N;          /* points of this grid */
    double S;          /* its length */
    double hcap;       /* the simulator's stability cap on the step */
    gsl_odeiv2_step *step[2];    /* [0]: state only, [1]: state and tangent */
    gsl_odeiv2_control *control[2];
    gsl_odeiv2_evolve *evolve[2];
    double control_tol[2];
    double *y;         /* 4N + 4: the state (2N + 2), then the tangent or f */
    double *work;      /* 2N scratch */
    /* FFT of one field for shifts and derivatives (continuum) */
    double *rbuf;
    fftw_complex *cbuf;
    fftw_plan fwd, bwd;
    /* counters */
    size_t flows, tangent_flows, steps;
    const volatile sig_atomic_t *cancel;
} orbit_flow;

/* NULL on bad input (err) or out of memory. */
orbit_flow *orbit_flow_alloc(const bkf_model_params *model, const bkf_orbit_options *options,
                             bkf_error *err);
void orbit_flow_free(orbit_flow *fl);

/* u(T) = Phi_T(u0) (2N values), the tangent v(T) = DPhi_T(u0) v0 when v0
 * is non-NULL, and f(u(T)) (the right-hand side at the end) when fT is
 * non-NULL; time integration at local tolerance tol.  uT, vT, fT may be
 * NULL when not wanted. */
int orbit_flow_run(orbit_flow *fl, const double *u0, const double *v0, double T, double tol,
                   double *uT, double *vT, double *fT, bkf_error *err);

/* f(u) (2N values). */
int orbit_flow_rhs(orbit_flow *fl, const double *u, double *f, bkf_error *err);

/* out = R_s u and, if dout non-NULL, dout = d(R_s u)/ds, both 2N values;
 * (R_s u)(x) = u(x - s).  The continuum shifts spectrally (the Nyquist
 * mode as cos(q s), consistently differentiated); the chain by whole
 * blocks only (s/h rounded: the caller has checked it is whole), dout 0.
 * out may be u itself. */
void orbit_flow_shift(orbit_flow *fl, const double *u, double s, double *out, double *dout);

/* d_x u (2N values), spectral; 0 for the chain. */
void orbit_flow_dx(orbit_flow *fl, const double *u, double *out);

/* u on this grid (2N values) from w on a grid of M points of the same
 * length (2M values), by the Fourier series truncated or padded (the
 * continuum), or NULL-equivalent BKF_EINPUT for the chain unless M = N. */
int orbit_flow_resample(orbit_flow *fl, const double *w, size_t M, double *u, bkf_error *err);

/* ------------------------------------------------------------ the object */

struct bkf_orbit {
    bkf_model_params model;   /* the full domain */
    bkf_orbit_options o;
    size_t cells, Nc;         /* m, points per cell */
    orbit_flow *cell;         /* the cell's grid */
    orbit_flow *full;         /* the full domain's (multipliers), lazily */
    int solved;               /* a solution is held (status OK or ETOL) */
    bkf_orbit_result result;
    double *psi, *eta;        /* full domain, N each */
    double *ucell;            /* the cell's solution, 2 Nc */
    double *ucell2;           /* the second grid's (2 Nc2; the multipliers' grid term),
                                 valid while result.N2 > 0 */
    size_t Nc2;
    /* per sector (floor(m/2) + 1 of them), the sum of the last call's
     * Ritz vectors (2N values each): the next call's starts */
    double *warm;
    size_t warm_sectors;
    /* the multipliers' storage */
    bkf_orbit_multiplier *mult;
    size_t nmult, capmult;
};

/* Newton-Krylov on one grid (orbit_newton.c).  The unknowns x are
 * (u (2N), T, s), always 2N + 2 values; which of T and s are free, and the
 * phase conditions, come from orbit_newton_prepare. */
typedef struct {
    /* set by orbit_newton_prepare from the guess */
    int period_free, shift_free;
    bkf_orbit_symmetry symmetry;
    double *uref, *pt, *ps;   /* the guess; unit phase vectors (time, space) */
    /* set by the caller */
    double flow_tol;
    double tol;               /* asked of the unknowns, max-norm */
    int max_iter, krylov_max;
    bkf_orbit_progress progress;
    void *progress_data;
    const char *stage;
    /* out */
    size_t iterations, jv, flows;
    double last_step;         /* max-norm of the last Newton correction */
    double residual;          /* max |Phi_T(u) - R_s u| at exit */
} orbit_newton_job;

/* Decide the free unknowns and the phase conditions for the guess x
 * (2N + 2 values) and mode (see orbit.h: a uniform state holds s, a
 * travelling one holds T, the continuum frees s otherwise, the chain
 * holds it).  BKF_EINPUT for a shift the chain cannot take. */
int orbit_newton_prepare(orbit_flow *fl, orbit_newton_job *job, const double *x,
                         bkf_orbit_shift_mode mode, bkf_error *err);
void orbit_newton_release(orbit_newton_job *job);

/* KINSOL with SPGMR from x (in and out). */
int orbit_newton(orbit_flow *fl, orbit_newton_job *job, double *x, bkf_error *err);

/* One Newton correction of x with the flow at tolerance tol: step (2N + 2
 * values, 0 for held unknowns) = -J^{-1} F(x) by SPGMR to a relative
 * 1e-6; *fnorm the max |F| of the state part at x. */
int orbit_newton_step(orbit_flow *fl, const orbit_newton_job *job, const double *x, double tol,
                      double *step, double *fnorm, bkf_error *err);

/* Relative difference of J v at tolerances tol and tol/10, v = dir
 * (2N + 2 values): the tangent flow's accuracy. */
int orbit_newton_tangent_check(orbit_flow *fl, const orbit_newton_job *job, const double *x,
                               const double *dir, double tol, double *rel, bkf_error *err);

/* The monodromy's leading multipliers on the full grid (orbit_mult.c). */
int orbit_mult_run(bkf_orbit *orbit, const bkf_orbit_mult_options *options,
                   bkf_orbit_spectrum *spectrum, bkf_error *err);

#endif

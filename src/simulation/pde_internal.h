/* Internal to the simulator (src/pde.c, src/pde_etd.c): the object's
 * layout and the pieces the exponential integrator shares with the
 * Runge-Kutta loop, below both: pde.c calls the integrator, which calls
 * nothing of pde.c.  Not installed, not part of the API. */
#ifndef BKFRONT_PDE_INTERNAL_H
#define BKFRONT_PDE_INTERNAL_H

#include <fftw3.h>
#include <gsl/gsl_odeiv2.h>

#include "bkfront/pde.h"

typedef struct bkf_pde_etd bkf_pde_etd;

/* A field this large has left the model's attractor for good (the cycle
 * stays within |psi| < 2.1); stopping beats integrating an overflow. */
#define BLOWUP 1e6

struct bkf_pde {
    bkf_model_params p;
    bkf_pde_options o;
    size_t N, dim;     /* dim = 2N + 2: psi, eta, Q, D */
    double h;          /* grid spacing S/N */
    double t;
    double *y;         /* current state */
    double *f;         /* y' at the current state (valid when have_f) */
    int have_f;
    double hstep;      /* step size proposed for the next step */
    double hcap;       /* stability cap on the step (see bkf_pde_alloc) */

    /* FFTW: aligned buffers, plans made once */
    double *rbuf, *lap;
    fftw_complex *cbuf;
    fftw_plan fwd, bwd;
    double *symbol;    /* -q_k^2 / N, k = 0 .. N/2 */
    double *fsymbol;   /* filter rates sigma_k / N (NULL: no filter) */
    fftw_complex *cbuf2;
    /* moving frame (V = o.frame_speed != 0): V q_k / N, 0 at Nyquist */
    double *dsymbol;
    fftw_complex *cbuf3;
    double *scr;       /* N scratch values (the Laplacian in rhs) */
    size_t keep;       /* modes kept by the 2/3 rule (k < keep) */

    /* integrator */
    gsl_odeiv2_system sys;
    gsl_odeiv2_step *step;
    gsl_odeiv2_control *control;
    double *ytry, *yerr, *f1, *sample, *psit; /* sample: etdrk4's states in x */

    /* reference values for the residuals */
    double t_set, H_set, mean_eta_set;

    bkf_pde_stats stats;

    bkf_pde_etd *etd;  /* exponential integrator (stepper etdrk4), else NULL */
};


/* The observer's view of a full state vector (psi, eta, Q, D).  Here, with
 * the layout both steppers share, so that the exponential integrator hands
 * its samples out without calling back into the simulator (pde.c uses
 * pde_etd.c, never the other way round). */
static inline int bkf_pde_emit(bkf_pde *m, bkf_pde_observer observer, void *data, double t,
                               const double *y)
{
    size_t N = m->N;
    bkf_pde_sample s = {t, y, y + N, y[2 * N], y[2 * N + 1]};
    m->stats.samples++;
    return observer(&s, data);
}

/* The right-hand side bkf_pde_run integrates (every stepper but the
 * exponential ones), for the periodic-orbit solver (orbit*.c), which
 * integrates it with the tangent flow alongside: y and dydt hold 2N + 2
 * values (psi, eta, then the quadratures Q and D's rates).  BKF_EBLOWUP
 * where the state is not finite or beyond the bound. */
int pde_rhs_eval(bkf_pde *m, const double *y, double *dydt);
/* Its Jacobian applied to v (2N values, the field part): out = J(y) v,
 * with the filter and the 2/3 rule as the right-hand side has them.
 * BKF_EINPUT in a moving frame (not linearised), BKF_EBLOWUP if not finite. */
int pde_tangent(bkf_pde *m, const double *y, const double *v, double *out);

/* Exponential integrator (src/pde_etd.c). */
bkf_pde_etd *bkf_pde_etd_alloc(bkf_pde *m);
void bkf_pde_etd_free(bkf_pde_etd *etd);
/* The state m->y changed outside the integrator (set_state, an init). */
void bkf_pde_etd_invalidate(bkf_pde_etd *etd);
int bkf_pde_etd_run(bkf_pde *m, double t_end, double sample_dt, bkf_pde_observer observer,
                    void *odata, bkf_pde_progress progress, void *pdata, bkf_error *err);

#endif

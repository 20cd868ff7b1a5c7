/* The spectrum of a train of n fronts on the ring of size S (and on the
 * infinite line): which of the allowed speeds survive.
 *
 * In the frame xi = x + v t the train is steady and L-periodic, L = S/n.  In
 * the cycle's variable z = xi / (v s), s = sqrt(1 - c^2/v^2) = gamma/mu, a
 * perturbation p = exp(-sigma z / s) u of psi obeys the van der Pol
 * variational equation with one extra term (docs/numerics.md, "Spectra of
 * front trains"):
 *     u'' + mu (f^2 - 1) u' + (1 + 2 mu f f') u = beta sigma (sigma + gamma (f^2 - 1)) u,
 *     beta = c^2/(v^2 - c^2) = (mu/gamma)^2 - 1.
 * sigma is an eigenvalue with Bloch angle theta (kappa = theta / L) when the
 * monodromy M(sigma) of this 2x2 system over one period T, times
 * exp(-sigma T/s), has the multiplier exp(i theta); on the ring theta =
 * 2 pi j / n, j = 0..n-1.  det M = exp(integral of -mu (f^2 - 1)), the
 * cycle's own multiplier, for every sigma (Liouville): a gauge of the
 * integration.  sigma = 0 at theta = 0 (translation) is the other.
 *
 * Method: M(sigma) by three-stage Radau IIA steps (order 5, L-stable) on a
 * mesh built from the cycle's adapted one: steps resolve the local rates,
 * except on the stiff slow branches of thin trains (large mu), where the
 * L-stable step damps the fast solution and resolves the slow one only.  The
 * rightmost spectrum at each height Im sigma = y is the root in a of
 * |multiplier(a + i y)| = 1 for each of the two multipliers; these curves are
 * traced over y in [0, B], where B is extended until the curves have fallen
 * below the window's left edge a_lo = r_inf / 2 (r_inf = s ln m / (2 T), the
 * line they approach as |y| -> inf); the eigenvalues are the points on the
 * curves whose multiplier has phase 2 pi j / n, located on the unwrapped
 * phase and polished by Newton.  Conjugate symmetry gives y < 0.  Each
 * reported sigma is computed on two meshes (the second halving every step
 * of the first); the difference / 8 is its error estimate (the steps are
 * fifth order: the ratio is 31 once converged), and the mesh is refined
 * until that meets tol or the result is refused. */
#ifndef BKFRONT_TRAINSPEC_H
#define BKFRONT_TRAINSPEC_H

#include <signal.h>
#include <stddef.h>
#include "bkfront/model.h"
#include "bkfront/speeds.h"
#include "bkfront/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The range of tol: below 1e-8 the profile's own error (the cycle solved
 * to 1e-12, up to 2e-9 per unit |sigma|) would outgrow it. */
#define BKF_TRAINSPEC_TOL_MIN 1e-8
#define BKF_TRAINSPEC_TOL_MAX 1e-2

typedef struct {
    double tol;        /* absolute accuracy asked of each sigma, [1e-8, 1e-2]; default 1e-6 */
    size_t per_kappa;  /* leading eigenvalues reported per Bloch number, [0, 50]; default 3
                          (one more where the cut would split a conjugate pair); 0: the
                          rightmost alone, found as for 1 but only it (with its conjugate,
                          any other it is not told apart from within the errors, and the
                          translation) refined to tol and reported: cheaper where the
                          meshes must be refined, sigma_max as for 1 within its error */
    double max_work;   /* Radau steps in all, the work budget (a step that also carries
                          the sigma-derivative counts twice), [1e5, 1e12]; 0 (default):
                          2.5e7, about 2 s (the paper's n = 11, mu 14, takes 5e6, n = 12,
                          mu 47, 2e7); a
                          spectrum that needs more is refused (BKF_EBUDGET) */
    const volatile sig_atomic_t *cancel; /* when non-NULL and *cancel becomes nonzero
                          (e.g. in a signal handler), the spectrum stops within one
                          monodromy: BKF_ECANCELED; default NULL */
} bkf_trainspec_options;

bkf_trainspec_options bkf_trainspec_options_default(void);

typedef enum {
    BKF_TRAINSPEC_STABLE = 0,     /* every sigma but the translation has Re sigma < 0 */
    BKF_TRAINSPEC_UNSTABLE = 1,   /* some Re sigma > 0 beyond its error */
    BKF_TRAINSPEC_UNRESOLVED = 2  /* the largest Re sigma is within its error of 0 */
} bkf_trainspec_verdict;

/* "yes", "no", "unresolved" (the answer to "stable?"). */
const char *bkf_trainspec_verdict_name(bkf_trainspec_verdict verdict);

typedef struct {
    double re, im;     /* sigma, per unit time t */
    double err;        /* estimated absolute error of sigma */
    size_t j;          /* Bloch index: kappa = 2 pi j / S */
    double kappa;
    int translation;   /* the translation mode (j = 0, sigma = 0) */
} bkf_trainspec_eigenvalue;

/* The train: n fronts at speed v (v > c > 0), from a root of the speed
 * condition (bkf_speeds_find) or given directly; mu = gamma / sqrt(1 - c^2/v^2). */
typedef struct {
    size_t n;
    double v;
} bkf_trainspec_train;

typedef struct {
    bkf_model_params params;
    size_t n;
    double v, mu, T, L;
    bkf_trainspec_eigenvalue *eigenvalues; /* by j, then by decreasing Re sigma */
    size_t count;
    /* the rightmost eigenvalue other than the translation */
    double sigma_max, sigma_max_im, sigma_max_err, kappa_max;
    int sigma_is_bound;              /* nothing but the translation right of a_lo: sigma_max is
                                        a_lo, error 0, a bound and no eigenvalue (see
                                        bkf_trainspec_shown_of) */
    int complex_pair;                /* Im sigma_max != 0 beyond its error */
    bkf_trainspec_verdict verdict;
    double translation_residual;     /* |sigma| of the translation mode as computed */
    double liouville_residual;       /* |ln det M - ln m| (the cycle's multiplier) */
    double a_lo, y_max;              /* window searched: Re sigma > a_lo, |Im sigma| <= y_max */
    double r_inf;                    /* the line the spectrum approaches as |Im sigma| -> inf */
    size_t mesh_steps;               /* Radau steps per period (finer mesh) */
    size_t evaluations;              /* monodromies computed (with or without the derivative) */
    double work;                     /* Radau steps taken in all (see max_work) */
    size_t curve_points;             /* heights y sampled (0: Hill's band alone, see below) */
    size_t hill_modes;               /* Hill's method's Fourier modes -M..M whose eigenvalues were
                                        candidates too (0: not used, mu > 6 or too many classes) */
    int edge_moved;                  /* a_lo was moved right of where the monodromy is rounding
                                        noise (thin trains: docs/numerics.md, "The window's edge
                                        stops short of the monodromy's noise") */
} bkf_trainspec_result;

/* Validation alone: BKF_EINPUT with a one-line message naming the parameter. */
int bkf_trainspec_check(const bkf_model_params *params, const bkf_trainspec_train *train,
                        const bkf_trainspec_options *options, bkf_error *err);

/* The ring spectrum of the train.  *result is overwritten; free it with
 * bkf_trainspec_result_free (also after a failure).  BKF_ETOL when an
 * eigenvalue's estimate stays above tol at the finest mesh allowed,
 * BKF_EBUDGET when the window's height or the mesh outgrows the budget. */
int bkf_trainspec_ring(const bkf_model_params *params, const bkf_trainspec_train *train,
                       const bkf_trainspec_options *options, bkf_trainspec_result *result,
                       bkf_error *err);
void bkf_trainspec_result_free(bkf_trainspec_result *result);

/* The one spectrum of a root of the speed condition that every product
 * takes (`bkfront stability`, `speeds --stability`, `branch --stability`,
 * `check`, the stability map): bkf_trainspec_ring on the train
 * n = root->n, v = root->v at tol and per_kappa, the other options their
 * defaults.  Its sigma_max does not depend on per_kappa (beyond its error,
 * per_kappa 0: see bkf_trainspec_options).  A refused root
 * (bkf_speeds_root.status) has no spectrum: its refusal, result empty. */
int bkf_trainspec_root(const bkf_model_params *params, const bkf_speeds_root *root, double tol,
                       size_t per_kappa, bkf_trainspec_result *result, bkf_error *err);

/* "real" or "complex": the kind of the rightmost eigenvalue. */
const char *bkf_trainspec_kind_name(const bkf_trainspec_result *result);

/* The rightmost eigenvalue as every product prints it (speeds --stability,
 * stability, branch --stability, check).  When the window held nothing
 * but the translation (sigma_is_bound), the result's sigma_max is the
 * window's left edge a_lo with error 0 and verdict stable when a_lo < 0:
 * every other eigenvalue lies left of a_lo.  That bound is evidence the
 * verdict and the searches that bracket on sigma_max may use, but it is no
 * eigenvalue (issue 31: -0.00876 printed where Hill's method gives
 * -0.0160), so here sigma_max, sigma_max_im, sigma_max_err and kappa_max
 * are NaN, kind NULL and bound a_lo; otherwise they are the result's and
 * bound is NaN. */
typedef struct {
    double sigma_max, sigma_max_im, sigma_max_err, kappa_max;
    const char *kind; /* bkf_trainspec_kind_name, or NULL */
    double bound;     /* every eigenvalue but the translation left of it, or NaN */
} bkf_trainspec_shown;
bkf_trainspec_shown bkf_trainspec_shown_of(const bkf_trainspec_result *result);

/* The products' one line about such a bound (bound finite): "sigma_max
 * nan: no eigenvalue but the translation found right of Re sigma = B (the
 * window's edge): every eigenvalue left of B", into buf; returns buf. */
const char *bkf_trainspec_bound_note(double bound, char *buf, size_t size);

/* The continuous spectrum on the infinite line: for each of `count` Bloch
 * numbers kappa_i = (2 pi / L) i / count, the rightmost sigma (re, im, err
 * in out[i], j = i).  The translation's branch passes through 0 at kappa 0. */
int bkf_trainspec_line(const bkf_model_params *params, const bkf_trainspec_train *train,
                       const bkf_trainspec_options *options, size_t count,
                       bkf_trainspec_eigenvalue *out, bkf_error *err);

/* One eigenvalue on a fixed mesh: Newton from sigma0 = (re0, im0) on the
 * multiplier exp(2 pi i j / n) of Bloch class j (j < n), on the mesh the
 * local rates need at |sigma| ~ |sigma0| with `substeps` times its steps
 * ([1, 4096]; the ring spectrum's meshes take 1 and 2, doubled on
 * refinement).  Doubling substeps halves
 * every step, so the error falls 32-fold (fifth order): for convergence
 * studies and for following one eigenvalue.  No error estimate; BKF_ENUMERIC
 * when Newton does not converge.  *mesh_steps (may be NULL) gets the Radau
 * steps per period. */
int bkf_trainspec_eigenvalue_at(const bkf_model_params *params, const bkf_trainspec_train *train,
                                size_t j, double re0, double im0, size_t substeps, double *re,
                                double *im, size_t *mesh_steps, bkf_error *err);

/* Eigenvalues followed to a nearby train: each from[i] (its class j < n and
 * sigma; a ring spectrum's eigenvalue of a train a continuation step away,
 * or a prediction from two) polished by Newton on its class alone, on
 * meshes of 1, 2, 4, ... substeps (one context, one cycle and one mesh
 * ladder for them all, the mesh the largest |sigma| needs) until the
 * difference of the last two / 8 (fifth order) plus the last Newton step
 * and the profile's share, the ring spectrum's estimate, meets tol
 * ([1e-8, 1e-2]): to[i] (err that estimate, kappa = 2 pi j / S,
 * translation copied), or re, im and err NaN where Newton did not converge
 * or tol was not met by 16 substeps.  *followed (may be NULL) counts the
 * others.  Newton may land on another eigenvalue of the class than the one
 * meant (a step too long, eigenvalues close): the caller judges that, and
 * knows nothing of the eigenvalues not followed (BKF_EBUDGET past the
 * default work budget). */
int bkf_trainspec_track(const bkf_model_params *params, const bkf_trainspec_train *train, double tol,
                        size_t count, const bkf_trainspec_eigenvalue *from, bkf_trainspec_eigenvalue *to,
                        size_t *followed, bkf_error *err);

/* The eigenfunction of the eigenvalue near sigma = (*re, *im) of class j:
 * sigma is first polished as by bkf_trainspec_eigenvalue_at at 8 substeps
 * (the value used goes back into *re, *im), then the perturbations p of psi
 * and q of eta are sampled at the N points x_i = i S / N (N >= 2) of the
 * ring, at t = 0 in the frame of bkf_pde_init_front's wave (psi = f(x / (v s)),
 * fronts moving towards -x), scaled to max |p| = 1.  The state
 * (F + eps Re p, G + eps Re q) then evolves, to first order in eps, as
 * (F + eps Re(p e^{sigma t}), ...) in the frame moving with the fronts:
 * the seed for a simulation that checks sigma.  Arrays of N values each
 * (p_im, q_re, q_im may be NULL). */
int bkf_trainspec_mode(const bkf_model_params *params, const bkf_trainspec_train *train, size_t j,
                       double *re, double *im, size_t N, double *p_re, double *p_im, double *q_re,
                       double *q_im, bkf_error *err);

#ifdef __cplusplus
}
#endif

#endif

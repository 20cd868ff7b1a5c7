/* The Burridge-Knopoff chain's own fronts: rotating waves of N blocks on a
 * ring of size S (spacing h = S/N, coupling K = c^2/h^2),
 *
 *     psi_i' = gamma (eta_i - phi(psi_i)),
 *     eta_i' = -(psi_i - nu - K (psi_{i+1} - 2 psi_i + psi_{i-1})) / gamma,
 *
 * of the form psi_i(t) = F(t + i tau), eta_i(t) = G(t + i tau), F and G of
 * period P, N tau = n P: n fronts moving towards -x at v = h/tau = S/(n P).
 *
 * Method (docs/numerics.md, "The chain's rotating waves"): the state after
 * tau is the state shifted by one block, Phi_tau(u) = shift(u) with
 * shift(u)_i = u_{i+1}.  Newton on (u, tau) in R^(2N+1) with the phase
 * condition psi_0 = nu (block 0 crossing nu), the Jacobian from the
 * variational equations (GSL odeiv2 rk8pd).  The Floquet multipliers of
 * shift^-1 o Phi_tau decide stability (their N-th powers are the
 * multipliers of the full orbit over n periods); the trivial multiplier 1
 * (time translation) is the accuracy gauge.
 *
 * All roots of one n: the waves at K = 0 are known exactly (uncoupled
 * blocks, each on the van der Pol cycle at mu = gamma, block i a phase
 * i n T/N ahead; the cycle is unique, so there is exactly one wave per n),
 * and each is followed in K by pseudo-arclength continuation (module
 * continuation, through folds) up to BKF_CHAINWAVE_K_REACH times the
 * target K; every crossing of the target is a wave, polished by Newton.
 * Waves on branches not connected to K = 0 (isolas) are not found.
 *
 * Error estimates: every wave is solved twice, with integration tolerances
 * tol/10 and tol/100; the differences are the error estimates and the
 * values reported are the tighter solve's.  BKF_ETOL when an estimate
 * stays above tol: relative on v; on the leading multiplier's modulus
 * tol max(1, |m|), absolute up to |m| = 1 where the verdict is decided,
 * relative beyond (the growth exponent ln|m| to tol absolute).
 *
 * The library never prints and never exits. */
#ifndef BKFRONT_CHAINWAVE_H
#define BKFRONT_CHAINWAVE_H

#include <stddef.h>
#include "bkfront/model.h"
#include "bkfront/status.h"

#ifdef __cplusplus
extern "C" {
#endif

#define BKF_CHAINWAVE_N_MIN 2
#define BKF_CHAINWAVE_N_MAX 400
#define BKF_CHAINWAVE_TOL_MIN 1e-11
#define BKF_CHAINWAVE_TOL_MAX 1e-3
/* gamma up to BKF_CHAINWAVE_GAMMA_EXPLICIT: the flow and its variational
 * equations by an explicit stepper (GSL rk8pd).  Where the blocks' cycle
 * is a stiff relaxation oscillation an implicit one (SUNDIALS CVODES: BDF
 * with the analytic Jacobian, the variational columns as forward
 * sensitivities) is the option: gamma up to BKF_CHAINWAVE_GAMMA_MAX, only
 * with options.stepper = BKF_CHAINWAVE_STEPPER_IMPLICIT for now (the
 * continuation from the uncoupled chain is still too slow there for the
 * automatic choice: see docs/numerics.md). */
#define BKF_CHAINWAVE_GAMMA_EXPLICIT 30.0
#define BKF_CHAINWAVE_GAMMA_MAX 100.0
/* How far beyond the target coupling K a branch is followed for crossings
 * that a fold beyond the target would bring back. */
#define BKF_CHAINWAVE_K_REACH 1.5

typedef enum {
    BKF_CHAINWAVE_STEPPER_AUTO = 0,     /* explicit (the only one up to gamma 30) */
    BKF_CHAINWAVE_STEPPER_EXPLICIT = 1, /* GSL rk8pd (slow above it, but independent) */
    BKF_CHAINWAVE_STEPPER_IMPLICIT = 2  /* CVODES BDF with sensitivities */
} bkf_chainwave_stepper;

typedef struct {
    double tol;          /* relative accuracy of v, of the leading |m| tol
                            max(1, |m|); [1e-11, 1e-3]; default 1e-8 */
    int stability;       /* compute the multipliers (default 1) */
    size_t max_steps;    /* integration steps per flow over tau; default 200000 */
    bkf_chainwave_stepper stepper; /* default AUTO */
} bkf_chainwave_options;

bkf_chainwave_options bkf_chainwave_options_default(void);

typedef enum {
    BKF_CHAINWAVE_STABLE = 0,     /* every nontrivial |m| < 1 beyond its error */
    BKF_CHAINWAVE_UNSTABLE = 1,   /* some |m| > 1 beyond its error */
    BKF_CHAINWAVE_UNRESOLVED = 2, /* the leading |m| within its error of 1 */
    BKF_CHAINWAVE_NOT_COMPUTED = 3
} bkf_chainwave_verdict;

/* "yes", "no", "unresolved", "not computed" (the speeds table's words). */
const char *bkf_chainwave_verdict_name(bkf_chainwave_verdict verdict);

typedef struct {
    size_t N, n;
    double h, K;              /* S/N and c^2/h^2 */
    double tau, tau_err;      /* time of one block's shift */
    double v, v_err;          /* h / tau */
    double P, P_err;          /* N tau / n: the period of each block */
    double residual;          /* max |Phi_tau(u) - shift(u)| at the reported wave */
    double psi_min, psi_max;  /* range of psi over the blocks at t = 0 */
    /* stability (verdict NOT_COMPUTED and NaN numbers without it) */
    bkf_chainwave_verdict verdict;
    double mult_re, mult_im;  /* leading nontrivial multiplier of shift^-1 o Phi_tau */
    double mult_abs, mult_abs_err;
    double sigma_max, sigma_max_err; /* ln|m| / tau: growth rate per unit time */
    double trivial_err;       /* |m_trivial - 1|, the accuracy gauge */
    size_t newton_iterations, steps;
    double *psi, *eta;        /* the state at t = 0 (N values each; psi_0 = nu,
                                 rising); owned, freed by bkf_chainwave_clear */
} bkf_chainwave;

void bkf_chainwave_clear(bkf_chainwave *wave);

/* Validation: N in [BKF_CHAINWAVE_N_MIN, BKF_CHAINWAVE_N_MAX] (params->N),
 * 1 <= n <= N, gamma in (0, BKF_CHAINWAVE_GAMMA_MAX], c >= 0, |nu| < 1,
 * S > 0, tol in range.  BKF_EINPUT with a message naming the parameter. */
int bkf_chainwave_check(const bkf_model_params *params, size_t n,
                        const bkf_chainwave_options *options, bkf_error *err);

/* Newton from a guess (psi, eta: N values, tau) to the wave of n fronts,
 * with error estimates and (options->stability) the multipliers.  n only
 * labels the wave (P = N tau / n); the guess decides which wave is found. */
int bkf_chainwave_solve(const bkf_model_params *params, size_t n, const double *psi,
                        const double *eta, double tau, const bkf_chainwave_options *options,
                        bkf_chainwave *wave, bkf_error *err);

/* The continuum's wave of n fronts (root root_index of bkf_speeds_find, 1
 * the fastest) sampled on the blocks, then polished by Newton on the chain:
 * the wave beside the continuum root on a fine chain. */
int bkf_chainwave_from_continuum(const bkf_model_params *params, size_t n, size_t root_index,
                                 const bkf_chainwave_options *options, bkf_chainwave *wave,
                                 bkf_error *err);

typedef struct {
    bkf_chainwave *waves;     /* ordered by n, then by decreasing v */
    size_t count;
    size_t folds;             /* folds in K passed by the continuations */
    size_t ended;             /* branches that did not reach the target K
                                 (folded back for good, or failed) */
    char note[320];           /* why a branch ended, or empty */
} bkf_chainwave_table;

void bkf_chainwave_table_free(bkf_chainwave_table *table);

/* Every wave for n in [n_from, n_to] (n_to 0: N/2; the waves of n and N - n
 * are mirror images of each other, n = N the uniform oscillation) found by
 * continuation in K from the uncoupled chain (see above).  *table is
 * overwritten; free it also after a failure. */
int bkf_chainwave_find(const bkf_model_params *params, size_t n_from, size_t n_to,
                       const bkf_chainwave_options *options, bkf_chainwave_table *table,
                       bkf_error *err);

/* ------------------------------------------------------------ branches */

/* The parameter a branch follows, the chain's N and n held fixed: h moves
 * S = N h with it (blocks per unit length 1/h; so does S, the two differ
 * only in the value reported), c moves K = c^2/h^2 alone, nu and gamma the
 * blocks' own dynamics.  A finer chain of the same S is another N: the
 * discrete family N = 20, 40, 80 is bkf_chainwave_find at each N. */
typedef enum {
    BKF_CHAINWAVE_PARAM_H = 0,
    BKF_CHAINWAVE_PARAM_S = 1,
    BKF_CHAINWAVE_PARAM_C = 2,
    BKF_CHAINWAVE_PARAM_NU = 3,
    BKF_CHAINWAVE_PARAM_GAMMA = 4
} bkf_chainwave_param;

/* "h", "S", "c", "nu", "gamma"; NULL otherwise. */
const char *bkf_chainwave_param_name(bkf_chainwave_param param);

typedef struct {
    double value;             /* the parameter */
    double S, h, K, c, nu, gamma;
    double tau, v, P;         /* v = h / tau, P = N tau / n */
    int is_fold;              /* a fold in the parameter (located) */
    /* with options->stability (else NOT_COMPUTED and NaN): the multipliers
     * at the point, from the variational equations at the branch's
     * tolerance; trivial_err is their gauge */
    bkf_chainwave_verdict verdict;
    double mult_abs, sigma_max, trivial_err;
} bkf_chainwave_branch_point;

/* Called for each accepted point in order along the branch; nonzero stops. */
typedef int (*bkf_chainwave_branch_visitor)(const bkf_chainwave_branch_point *point,
                                            void *data);

typedef struct {
    size_t points, folds;
    int reached;              /* the branch reached `to` */
    int pinned;               /* stopped because v fell below 1e-3 of its start:
                                 the fronts stop propagating */
    double last_value, last_v;
    char note[320];           /* why the branch ended before `to`, or empty */
} bkf_chainwave_branch_report;

/* The wave `root` (1 the fastest, bkf_chainwave_find's order) of n fronts
 * at param = from (the other parameters from params; N fixed) followed by
 * pseudo-arclength continuation (module continuation, through folds) to
 * param = to.  The branch ends early where the continuation cannot go on
 * (report->note), or where the fronts stop propagating (v below 1e-3 of its
 * start: report->pinned); both are results, BKF_OK.  The points' accuracy
 * is that of the continuation's corrector (integration tolerance
 * options->tol / 10); solve a point again with bkf_chainwave_solve for
 * error estimates.  BKF_EINPUT: bad parameters (as bkf_chainwave_check at
 * both ends), from == to, no wave `root` at `from`. */
int bkf_chainwave_branch(const bkf_model_params *params, size_t n, size_t root,
                         bkf_chainwave_param param, double from, double to,
                         const bkf_chainwave_options *options,
                         bkf_chainwave_branch_visitor visit, void *data,
                         bkf_chainwave_branch_report *report, bkf_error *err);

#ifdef __cplusplus
}
#endif

#endif

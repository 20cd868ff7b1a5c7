/* Periodic orbits of the discretised PDE (pde.h) and their Floquet
 * multipliers.
 *
 * The problem.  u = (psi, eta) on the simulator's grid (continuum
 * pseudo-spectral or the chain), Phi_t its flow (the same right-hand side,
 * filter and dealiasing as bkf_pde_run).  A periodic orbit is (u0, T) with
 *
 *     Phi_T(u0) = R_s u0,        (R_s u)(x) = u(x - s),
 *
 * s = 0 for a plain orbit, s != 0 for an orbit periodic up to a shift (a
 * pattern that moves by s per period; a relative periodic orbit).  Time
 * translation, and on the continuum space translation, map solutions to
 * solutions, so the unknowns (u0, T[, s]) get one phase condition per
 * continuous symmetry used:
 *
 *     <f(u_ref), u0 - u_ref> = 0     (time; f the right-hand side)
 *     <d_x u_ref, u0 - u_ref> = 0    (space; continuum, shift free)
 *
 * with u_ref the initial guess.  Newton-Krylov: SUNDIALS KINSOL with SPGMR;
 * Jacobian-vector products from the tangent (variational) flow integrated
 * alongside the state, never from differences of whole flows.
 *
 * Cells.  A pattern of m identical cells (cells = m, m divides N and, for
 * the continuum, N/m is even) is solved on one cell: the domain S/m with
 * N/m points, its state the first cell of the guess averaged over the m
 * cells.  The result holds the full domain (the cell repeated).  Its
 * multipliers come by Bloch sector j = 0 .. floor(m/2): perturbations
 * whose Fourier content sits at the wavenumbers 2 pi k/S with k = +-j mod m
 * (sectors j and m - j are complex conjugates and share one real sector).
 *
 * Degenerate cases, said in the result (bkf_orbit_result.symmetry) rather
 * than refused:
 *  - a spatially uniform guess (the global oscillation) has no space
 *    translation: the shift is held at the guess's and the space phase
 *    condition dropped;
 *  - a travelling wave (f(u) parallel to d_x u: a relative equilibrium, the
 *    time and space orbits coincide) has a one-parameter family of (T, s)
 *    with s/T its velocity: the period is held at the guess's and only the
 *    shift solved (shift_mode FREE), so that -s/T is the wave's velocity
 *    (a train moving towards -x has s < 0 in the convention above).
 *
 * The error estimate, each piece in the result, their sum against tol:
 *  - residual: the remaining Newton correction (KINSOL's last step, in the
 *    max-norm of the unknowns), and the residual's max-norm;
 *  - flow: twice the change of (u0, T, s) from one more Newton step with
 *    the flow integrated at flow tolerance / 10 (how far the solution moves
 *    when the time integration is made ten times more accurate; twice,
 *    since rk8pd's global error at tol/10 is only 7-8 times smaller), plus the tangent
 *    flow's share: its relative accuracy (one Jacobian-vector product at
 *    the two tolerances) times the last correction;
 *  - grid (continuum): the change of T, s and of the state (spectrally
 *    interpolated) when the orbit is solved again on a second grid
 *    N2 = N + N/2 (rounded up to what the cells allow).  The chain of N
 *    blocks is the model itself: its grid error is 0.
 * tol is the absolute accuracy asked of T, s and every value of the state
 * (max-norm).  A tol the estimate does not meet is refused (BKF_ETOL) with
 * the estimate's pieces in the result.
 *
 * Multipliers.  Arnoldi (ARPACK dnaupd/dneupd, reverse communication) on
 * v -> R_s^{-1} DPhi_T(u0) v, the monodromy's action (one tangent flow over
 * the period per product), the k of largest modulus per sector.  The trivial
 * multipliers (1, with eigenvector f(u0) for time and d_x u0 for space) are
 * identified by the alignment of their eigenvectors and reported apart
 * (their distance from 1 is an accuracy check), never counted in the
 * verdict.  An eigenvector whose content sits in the top third of the grid's
 * wavenumbers (its spectral tail, as bkf_pde_spectral_tail, above
 * grid_tail) is classified a grid mode: if the verdict would rest on one it
 * is undecided.  Each multiplier's error: twice the residual |A v - m v|/|v| of its
 * Ritz pair (ARPACK's estimate from the Arnoldi relation), plus the flow's
 * share, twice |A x - A' x|/|x| with A' the monodromy with its flow ten times
 * more accurate and x the largest multiplier's sector's Ritz vectors summed
 * (measured once a call), plus the orbit's own error estimate
 * result.err (a first-order guess: a change e of the orbit moves the
 * monodromy by O(e)), plus the grid's share: the change of the largest
 * physical |m| when its sector is computed again about the orbit on the
 * second grid N2 (the orbit's error bounds the monodromy's change only to
 * first order, and the grid moved the multipliers ten times more than it
 * moved the orbit: 0.41990 +- 5e-4 at N 64 against 0.42487 at N 128 on the
 * stable pacemaker).
 *
 * The library never prints and never exits. */
#ifndef BKFRONT_ORBIT_H
#define BKFRONT_ORBIT_H

#include <signal.h>
#include <stddef.h>
#include "bkfront/model.h"
#include "bkfront/status.h"

#ifdef __cplusplus
extern "C" {
#endif

#define BKF_ORBIT_TOL_MIN 1e-12
#define BKF_ORBIT_TOL_MAX 1e-2

/* On the continuum a non-uniform state always gets the space phase
 * condition and s as its unknown (with s held, space translation leaves the
 * plain problem singular): NONE and FIXED then only say where s starts (0,
 * or the guess's), and the result's shift where it ended (0 within the
 * error for a plain, e.g. reflection-symmetric, orbit). */
typedef enum {
    BKF_ORBIT_SHIFT_NONE = 0,  /* Phi_T(u0) = u0 */
    BKF_ORBIT_SHIFT_FIXED = 1, /* Phi_T(u0) = R_s u0 with s the guess's (on the chain
                                  a whole number of blocks) */
    BKF_ORBIT_SHIFT_FREE = 2   /* s an unknown with the space phase condition
                                  (continuum only) */
} bkf_orbit_shift_mode;

/* "none", "fixed", "free". */
const char *bkf_orbit_shift_mode_name(bkf_orbit_shift_mode mode);

/* Progress: the stage ("newton", "grid", "arnoldi", ...) and a fraction
 * in [0, 1] of that stage (a guess for Newton).  Nonzero stops the work
 * with BKF_ECANCELED. */
typedef int (*bkf_orbit_progress)(const char *stage, double fraction, void *data);

typedef struct {
    double tol;               /* see above; [BKF_ORBIT_TOL_MIN, BKF_ORBIT_TOL_MAX], default 1e-8 */
    size_t cells;             /* m >= 1 identical cells; default 1 */
    bkf_orbit_shift_mode shift_mode; /* default NONE */
    /* The flow: the simulator's options (pde.h) for tol (0: chosen from
     * tol, tol/100 clamped to [1e-13, 1e-6]), dealias and filter
     * (defaults as bkf_pde_options_default: no dealiasing, filter 4); rk8pd. */
    double flow_tol;
    int dealias;
    double filter;
    int newton_max_iter;      /* KINSOL's Newton iterations; default 40 */
    int krylov_max;           /* SPGMR's Krylov dimension; default 200: a travelling
                                 train's monodromy has tens of multipliers near the
                                 unit circle, which restarted GMRES of 40 did not
                                 get past (it stops early where the orbit contracts) */
    int grid_check;           /* 1 (default): the second N on the continuum; 0: skipped,
                                 err_grid NaN and err without it (the result says so
                                 by the NaN; a caller that skips it owns the grid) */
    bkf_orbit_progress progress;
    void *progress_data;
    const volatile sig_atomic_t *cancel; /* raised: BKF_ECANCELED at the next flow */
} bkf_orbit_options;

bkf_orbit_options bkf_orbit_options_default(void);

/* The initial guess on the full domain (N values each, the model's grid). */
typedef struct {
    const double *psi, *eta;
    double period;            /* > 0 */
    double shift;             /* s; used by FIXED and as the start of FREE */
} bkf_orbit_guess;

typedef enum {
    BKF_ORBIT_SYM_GENERIC = 0,   /* every phase condition the mode asks for */
    BKF_ORBIT_SYM_UNIFORM = 1,   /* no space dependence: shift held, no space phase */
    BKF_ORBIT_SYM_TRAVELLING = 2 /* a relative equilibrium: period held, shift solved */
} bkf_orbit_symmetry;

/* "generic", "uniform", "travelling". */
const char *bkf_orbit_symmetry_name(bkf_orbit_symmetry sym);

typedef struct {
    double period, shift;
    double err;               /* the total estimate: residual + flow + grid */
    double err_residual;      /* remaining Newton correction */
    double residual;          /* max |Phi_T(u0) - R_s u0| at the solution */
    double err_flow;          /* the state flow's share (see above) */
    double tangent_rel;       /* relative accuracy of a Jacobian-vector product */
    double err_grid;          /* second N; 0 for the chain; NaN if not checked */
    size_t N2;                /* the second grid (0: none) */
    double period2, shift2;   /* on the second grid */
    size_t cells;             /* m used */
    bkf_orbit_symmetry symmetry;
    int period_held, shift_held;
    double amplitude;         /* max psi - min psi over the state at t = 0 */
    size_t newton_iterations, jv_products, flows;
    double flow_tol;          /* the flow tolerance used */
} bkf_orbit_result;

typedef struct bkf_orbit bkf_orbit;

/* The model: as for bkf_pde_alloc (frame speed 0).  NULL with err on bad
 * input (including cells that do not divide N) or out of memory. */
bkf_orbit *bkf_orbit_alloc(const bkf_model_params *model, const bkf_orbit_options *options,
                           bkf_error *err);
void bkf_orbit_free(bkf_orbit *orbit);

/* Solve from the guess.  BKF_OK: the result meets tol.  BKF_ETOL: solved,
 * but the estimate exceeds tol (result filled, the state kept: it is not a
 * result to print).  BKF_ENUMERIC: Newton did not converge (the message
 * says KINSOL's flag); BKF_EBLOWUP; BKF_ECANCELED. */
int bkf_orbit_solve(bkf_orbit *orbit, const bkf_orbit_guess *guess, bkf_orbit_result *result,
                    bkf_error *err);

/* The solved state at t = 0 on the full domain (N values), or NULL before
 * a solve that reached a solution. */
const double *bkf_orbit_psi(const bkf_orbit *orbit);
const double *bkf_orbit_eta(const bkf_orbit *orbit);
const bkf_orbit_result *bkf_orbit_get(const bkf_orbit *orbit);

/* ------------------------------------------------------------ multipliers */

typedef enum {
    BKF_ORBIT_MULT_PHYSICAL = 0,
    BKF_ORBIT_MULT_TRIVIAL_TIME = 1,  /* eigenvector along f(u0) */
    BKF_ORBIT_MULT_TRIVIAL_SPACE = 2, /* eigenvector along d_x u0 */
    BKF_ORBIT_MULT_GRID = 3           /* eigenvector at the grid scale */
} bkf_orbit_mult_kind;

/* "physical", "trivial_time", "trivial_space", "grid". */
const char *bkf_orbit_mult_kind_name(bkf_orbit_mult_kind kind);

typedef struct {
    double re, im, abs;
    double err;               /* estimated absolute error of the multiplier */
    size_t sector;            /* Bloch sector j (0 with one cell) */
    bkf_orbit_mult_kind kind;
    double tail;              /* spectral tail of the eigenvector (see above) */
    double alignment;         /* |cos| of the eigenvector with f(u0) or d_x u0 (the larger) */
} bkf_orbit_multiplier;

typedef enum {
    BKF_ORBIT_STABLE = 0,     /* every physical |m| < 1 beyond its error */
    BKF_ORBIT_UNSTABLE = 1,   /* a physical |m| > 1 beyond its error */
    BKF_ORBIT_UNDECIDED = 2   /* within the error of 1, or resting on a grid mode,
                                 or a trivial multiplier not found */
} bkf_orbit_verdict;

/* "stable", "unstable", "undecided". */
const char *bkf_orbit_verdict_name(bkf_orbit_verdict verdict);

typedef struct {
    size_t k;                 /* physical multipliers asked per sector, >= 1; default 10 */
    int sector;               /* -1 (default): every sector; else the one j */
    double arnoldi_tol;       /* ARPACK's relative tolerance; 0 (default): the orbit's
                                 tol / 100 in [1e-12, 1e-6] (the multipliers' error
                                 carries the orbit's own, so a tighter Arnoldi only
                                 costs restarts: 1e-10 at tol 1e-3 was 83 tangent
                                 flows a branch point where 1e-5 takes 67) */
    int max_restarts;         /* ARPACK's maxiter; default 300 */
    double grid_tail;         /* tail above which an eigenvector is a grid mode; default
                                 0.1: grid modes' content sits at the cutoff (tails 0.3-0.7
                                 at N 64 on the pacemaker), a physical eigenvector's
                                 tail is near its orbit's own (1e-2 at N 128 there) */
    double flow_tol;          /* the tangent flow's tolerance; 0 (default): the orbit's
                                 tol in [1e-13, 1e-6], the accuracy the orbit was asked
                                 for rather than its own flow's tol / 100 (the flow's
                                 share of the errors is measured with this flow ten
                                 times tighter, so the looser flow shows in them) */
    const struct bkf_orbit *warm_start; /* NULL (default), or an orbit of the same grid
                                 and cells whose last multipliers start Arnoldi here
                                 (their eigenvectors, sector by sector): the previous
                                 point of a branch.  Only the work changes, not what
                                 converges: ARPACK's test is the same */
} bkf_orbit_mult_options;

bkf_orbit_mult_options bkf_orbit_mult_options_default(void);

typedef struct {
    size_t count;             /* multipliers in m (every sector, trivial and grid ones
                                 included), sorted by sector then |m| descending */
    const bkf_orbit_multiplier *m; /* owned by the orbit object, valid until its next call */
    bkf_orbit_verdict verdict;
    double largest_abs;       /* the largest physical |m| (all sectors) */
    double largest_err;
    size_t largest_index;     /* its index in m */
    size_t trivial_found;     /* trivial multipliers identified (expected: 1, 2 with a
                                 free shift on the continuum, 0 for a uniform state's space) */
    size_t trivial_expected;
    double trivial_dev;       /* max |m - 1| over the trivial ones found */
    double flow_dev;          /* the flow's share of every err (see above) */
    double grid_dev;          /* the largest physical |m|'s change on the orbit's second
                                 grid (N2, its sector only), added to every multiplier's
                                 err; 0 for the chain, NaN when the orbit skipped its
                                 grid check */
    char reason[160];         /* why undecided, else empty */
    size_t matvecs;           /* tangent flows over a period */
} bkf_orbit_spectrum;

/* The multipliers of the last solved orbit (its status BKF_OK or
 * BKF_ETOL; the latter's multipliers carry that orbit's error).  BKF_OK with
 * the spectrum; BKF_ENUMERIC if ARPACK fails or does not converge (the
 * message gives its info code); BKF_ECANCELED. */
int bkf_orbit_multipliers(bkf_orbit *orbit, const bkf_orbit_mult_options *options,
                          bkf_orbit_spectrum *spectrum, bkf_error *err);

#ifdef __cplusplus
}
#endif

#endif

/* Spectrum of a periodic train of fronts by Hill's method (Fourier-Bloch
 * with dense LAPACK): the method for smooth trains (small mu), and an
 * independent check of the monodromy methods.
 *
 * The train moves towards -x at speed v > c and is steady in xi = x + v t;
 * with s = sqrt(1 - c^2/v^2), mu = gamma/s and z = xi/(v s) its profile is
 * the van der Pol cycle f(z) of period T at (mu, nu) (cycle.h).  Linearised
 * about it, with D = d/dz and beta = c^2/(v^2 - c^2) = (mu/gamma)^2 - 1,
 *     sigma p = -D p / s - gamma (f^2 - 1) p + gamma q
 *     sigma q = -D q / s - p / gamma + (beta / gamma) D^2 p,
 * sigma the growth rate per unit time t.  Bloch: p, q = exp(i theta z/T)
 * times T-periodic functions, theta the Bloch angle per period (on a ring
 * of n fronts theta = 2 pi j / n).  The periodic parts are expanded in the
 * Fourier modes -M..M, which gives a dense complex eigenproblem of size
 * 2(2M + 1) (docs/numerics.md, "Hill's method").
 *
 * c and v enter only through s = gamma/mu: given the cycle's mu, gamma
 * alone fixes the problem (c = 0 is mu = gamma; for c > 0 the speed is
 * v = c / sqrt(1 - gamma^2/mu^2)), so c is no argument here.
 *
 * The eigenvalues converge exponentially in M for an analytic profile, as
 * fast as the Fourier coefficients of f^2 - 1 decay; the profile's own
 * error (the cycle's tolerance) is not seen by the comparison of two M,
 * so solve the cycle tighter than the accuracy wanted of sigma. */
#ifndef BKFRONT_HILL_H
#define BKFRONT_HILL_H

#include <stddef.h>
#include "bkfront/cycle.h"
#include "bkfront/status.h"

#ifdef __cplusplus
extern "C" {
#endif

#define BKF_HILL_MODES_MIN 4
#define BKF_HILL_MODES_MAX 2048

typedef struct {
    double re, im;
} bkf_hill_eigenvalue;

/* Every eigenvalue of the truncated problem with the Fourier modes
 * -modes..modes, at Bloch angle theta, for the train whose profile is the
 * last solution of `cycle` (non-const: sampling the profile integrates):
 * sorted by decreasing real part (ties by increasing imaginary part).
 * gamma in (0, mu] (mu the cycle's), theta finite, modes in
 * [BKF_HILL_MODES_MIN, BKF_HILL_MODES_MAX].  out must hold 2 (2 modes + 1)
 * entries; *count receives how many were written (all of them).  At theta
 * an odd multiple of pi (within a few ulps) the modes are instead the 2
 * modes whose wavenumbers are +-pi/T, +-3 pi/T, ..., +-(2 modes - 1) pi/T
 * (4 modes eigenvalues): closed under k -> -k like the exact problem, so
 * the truncated spectrum keeps its symmetry under conjugation and is solved
 * as a real eigenproblem (as at theta = 0), about 4 times faster.  Those of
 * high Fourier content (|Im sigma| near the largest resolved frequency)
 * are artefacts of the truncation, some with the largest real parts:
 * bkf_hill_leading tells which are converged. */
int bkf_hill_spectrum(bkf_cycle *cycle, double gamma, double theta, size_t modes,
                      bkf_hill_eigenvalue *out, size_t *count, bkf_error *err);

/* The converged eigenvalues of largest real part.  The truncations at
 * `modes` and at 2 modes are solved; an eigenvalue of the finer one is
 * converged when the nearest eigenvalue of the coarser one lies within tol
 * (absolute), and that distance is its error estimate.  The first k
 * converged ones, sorted as above, go to out[0..*found - 1] and their
 * estimates to out_err (NULL: not wanted); *found < k when fewer converge.
 * *unresolved (NULL: not wanted) receives how many eigenvalues of the finer
 * truncation that did not converge have a real part above the last one
 * returned (above every one when *found is 0): the modes' truncation
 * artefacts sit there, near the largest resolved frequency, but so would a
 * true eigenvalue that needs more modes.  modes in [BKF_HILL_MODES_MIN,
 * BKF_HILL_MODES_MAX / 2], tol > 0, k >= 1; the rest as for
 * bkf_hill_spectrum. */
int bkf_hill_leading(bkf_cycle *cycle, double gamma, double theta, size_t modes, double tol,
                     size_t k, bkf_hill_eigenvalue *out, double *out_err, size_t *found,
                     size_t *unresolved, bkf_error *err);

/* As bkf_hill_leading with the finer truncation at modes_fine modes
 * (modes < modes_fine <= BKF_HILL_MODES_MAX) instead of 2 modes: a quarter
 * more modes costs a quarter of the work of twice as many (the dense
 * eigenproblem is cubic in the size).  The truncation's artefacts, tied to
 * its largest frequency, still move between the two and are not matched;
 * the distance bounds the finer one's error only where the error falls at
 * least twofold between the two truncations (at 2 modes, where it falls by
 * the square, it always does): a filter of candidates more than an error
 * bound. */
int bkf_hill_leading_pair(bkf_cycle *cycle, double gamma, double theta, size_t modes, size_t modes_fine,
                          double tol, size_t k, bkf_hill_eigenvalue *out, double *out_err, size_t *found,
                          size_t *unresolved, bkf_error *err);

/* The matching behind bkf_hill_leading_pair, on two spectra already solved
 * (as bkf_hill_spectrum sorts them: coarse at fewer modes, fine at more),
 * so that a caller that grows M reuses the finer truncation as the next
 * coarse one: out, out_err, *found and *unresolved as there. */
int bkf_hill_converged(const bkf_hill_eigenvalue *coarse, size_t n_coarse, const bkf_hill_eigenvalue *fine,
                       size_t n_fine, double tol, size_t k, bkf_hill_eigenvalue *out, double *out_err,
                       size_t *found, size_t *unresolved, bkf_error *err);

#ifdef __cplusplus
}
#endif

#endif

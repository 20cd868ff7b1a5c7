/* Hill's method for the spectrum of a front train (hill.h).
 *
 * Unknowns: the Fourier coefficients p_m, q_m, m = -M..M, of the periodic
 * parts, in that order (p first).  D acts on mode m as i k_m with
 * k_m = (theta + 2 pi m)/T, and (f^2 - 1) p is the convolution
 * sum_m g_{m'-m} p_m with the coefficients g of f^2 - 1, needed for
 * |m' - m| <= 2M.  They come from a DFT of 4M + 2 uniform samples: every
 * index in -2M..2M is then distinct modulo the sample count, and the
 * aliased coefficients (|k| >= 2M + 2) are far below the truncation error,
 * which is set by |k| ~ M. */
#include "bkfront/hill.h"
#include "bkfront/lazylib.h" /* before lapacke.h: zgeev, dgeev are lazylib.c's */

#include <gsl/gsl_complex_math.h>
#include <gsl/gsl_linalg.h>

#include <complex.h>
#include <float.h>
#include <lapacke.h>
#include <math.h>
#include <stdlib.h>

#include "hill_internal.h"

/* M_PI is not C11 */
#define TWO_PI 6.283185307179586476925286766559

static int check_inputs(const bkf_cycle *cycle, double gamma, double theta, size_t modes,
                        size_t modes_max, bkf_error *err)
{
    const bkf_cycle_result *r = cycle ? bkf_cycle_get(cycle) : NULL;
    if (!r) return bkf_error_set(err, BKF_EINPUT, "cycle must hold a solution (bkf_cycle_solve first)");
    if (!(gamma > 0 && gamma <= r->mu))
        return bkf_error_set(err, BKF_EINPUT,
                             "gamma must be in (0, mu] with mu = %.17g the cycle's (mu = gamma/sqrt(1 - c^2/v^2))",
                             r->mu);
    if (!isfinite(theta)) return bkf_error_set(err, BKF_EINPUT, "theta must be finite");
    if (modes < BKF_HILL_MODES_MIN || modes > modes_max)
        return bkf_error_set(err, BKF_EINPUT, "modes must be in [%d, %zu]", BKF_HILL_MODES_MIN, modes_max);
    return BKF_OK;
}

/* g[k] for k = 0..2M, the Fourier coefficients of f^2 - 1 over one period
 * (g_{-k} = conj g_k: f is real). */
static int profile_coefficients(bkf_cycle *cycle, size_t M, double complex *g, bkf_error *err)
{
    double T = bkf_cycle_get(cycle)->period;
    size_t ns = 4 * M + 2, nk = 2 * M + 1;
    double *h = malloc(sizeof(double) * ns);
    double *cs = malloc(sizeof(double) * 2 * ns);
    if (!h || !cs) {
        free(h);
        free(cs);
        return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    }
    /* the samples in one pass (bkf_cycle_profile_sample): point by point
     * each was an integrator of its own from the nearest node */
    for (size_t j = 0; j < ns; j++) cs[j] = T * (double)j / (double)ns;
    int rc = bkf_cycle_profile_sample(cycle, cs, ns, h, NULL, err);
    for (size_t j = 0; j < ns && rc == BKF_OK; j++) {
        h[j] = h[j] * h[j] - 1.0;
        /* twiddles by exact index, so that (k j mod ns) carries no rounding */
        cs[2 * j] = cos(TWO_PI * (double)j / (double)ns);
        cs[2 * j + 1] = sin(TWO_PI * (double)j / (double)ns);
    }
    for (size_t k = 0; k < nk && rc == BKF_OK; k++) {
        double re = 0.0, im = 0.0;
        for (size_t j = 0, idx = 0; j < ns; j++, idx = (idx + k) % ns) {
            re += h[j] * cs[2 * idx];
            im -= h[j] * cs[2 * idx + 1];
        }
        g[k] = CMPLX(re / (double)ns, im / (double)ns);
    }
    free(h);
    free(cs);
    return rc;
}

static int by_real_part(const void *a, const void *b)
{
    const bkf_hill_eigenvalue *x = a, *y = b;
    if (x->re != y->re) return x->re < y->re ? 1 : -1;
    if (x->im != y->im) return x->im < y->im ? -1 : 1;
    return 0;
}

/* The truncation of class theta at M modes: the modes m0..m0 + nm - 1
 * with wavenumbers k_m = (theta + 2 pi m)/T.  At theta an odd multiple of
 * pi (to a few ulps: 2 pi j/n rounds) the 2M modes of k = +-pi/T, ...,
 * +-(2M - 1) pi/T, closed under k -> -k as the operator is (-M..M there
 * reached 2M + 1 on one side and 2M - 1 on the other, and its spectrum
 * was not conjugate-symmetric); elsewhere -M..M.  *real: the truncation
 * is closed under k -> -k (theta 0 or pi), and the matrix is real in the
 * basis real_eigenvalues uses. */
typedef struct {
    double theta;
    long m0;
    size_t nm;
    int real;
} truncation;

static truncation truncation_of(double theta, size_t M)
{
    double r = remainder(theta, TWO_PI);
    if (fabs(fabs(r) - TWO_PI / 2) <= 4.0 * DBL_EPSILON * fmax(1.0, fabs(theta)))
        return (truncation){TWO_PI / 2, -(long)M, 2 * M, 1};
    return (truncation){theta, -(long)M, 2 * M + 1, theta == 0.0};
}

size_t hill_count(double theta, size_t modes)
{
    return 2 * truncation_of(theta, modes).nm;
}

/* The eigenvalues of the Hill matrix A (column-major, size n = 2 nm) of a
 * truncation closed under k -> -k (theta 0 or pi), where the operator is
 * real: mode i of a block (from the lowest) has wavenumber -k of mode
 * nm - 1 - i's, so A commutes with the conjugation J, (J x)_i =
 * conj(x_{nm-1-i}) within each of the p and q blocks, and in the basis of
 * J's fixed vectors (e_i + e_{nm-1-i})/sqrt 2, i (e_i - e_{nm-1-i})/sqrt 2
 * and, at theta 0, e_M (unitary, two entries a column) it is real: dgeev
 * solves it in about a quarter of zgeev's time (issue 31: the single front
 * at mu 4.9 grows to 156 modes; issue 33: the audit's even trains at pi).
 * Into w (n values). */
static lapack_int real_eigenvalues(const double complex *A, size_t nm, double complex *w)
{
    size_t n = 2 * nm;
    double *R = malloc(n * n * sizeof *R), *wr = malloc(n * sizeof *wr), *wi = malloc(n * sizeof *wi);
    /* basis vector b: up to two (row, coefficient) pairs of A's index space */
    size_t (*idx)[2] = malloc(n * sizeof *idx);
    double complex (*cf)[2] = malloc(n * sizeof *cf);
    lapack_int info = LAPACK_WORK_MEMORY_ERROR;
    if (R && wr && wi && idx && cf) {
        const double h = 0.70710678118654752440;
        for (size_t blk = 0; blk < 2; blk++) {
            size_t o = blk * nm, b = o;
            for (size_t i = 0; i < nm / 2; i++, b += 2) {
                idx[b][0] = idx[b + 1][0] = o + nm - 1 - i;
                idx[b][1] = idx[b + 1][1] = o + i;
                cf[b][0] = h, cf[b][1] = h;
                cf[b + 1][0] = I * h, cf[b + 1][1] = -I * h;
            }
            if (nm % 2) {
                idx[b][0] = idx[b][1] = o + nm / 2;
                cf[b][0] = 1.0, cf[b][1] = 0.0;
            }
        }
        for (size_t b = 0; b < n; b++)
            for (size_t a = 0; a < n; a++) {
                double complex sum = 0.0;
                for (int i = 0; i < 2; i++)
                    for (int j = 0; j < 2; j++)
                        if (cf[a][i] != 0.0 && cf[b][j] != 0.0)
                            sum += conj(cf[a][i]) * A[idx[a][i] + idx[b][j] * n] * cf[b][j];
                R[a + b * n] = creal(sum);
            }
        info = LAPACKE_dgeev(LAPACK_COL_MAJOR, 'N', 'N', (lapack_int)n, R, (lapack_int)n, wr, wi, NULL, 1, NULL, 1);
        for (size_t i = 0; info == 0 && i < n; i++) w[i] = CMPLX(wr[i], wi[i]);
    }
    free(R);
    free(wr);
    free(wi);
    free(idx);
    free(cf);
    return info;
}

/* The Hill matrix of truncation tr at M modes into A (column-major, size
 * n = 2 tr.nm, zeroed by the caller). */
static int hill_matrix(bkf_cycle *cycle, double gamma, truncation tr, size_t M, double complex *A, bkf_error *err)
{
    const bkf_cycle_result *r = bkf_cycle_get(cycle);
    double mu = r->mu, T = r->period;
    double s = gamma / mu, beta = (mu - gamma) * (mu + gamma) / (gamma * gamma);
    size_t nm = tr.nm, n = 2 * nm;
    double complex *g = malloc(sizeof(double complex) * (2 * M + 1));
    if (!g) return bkf_error_set(err, BKF_ENOMEM, "out of memory (Hill matrix of size %zu)", n);
    /* differences of mode indices up to nm - 1 <= 2M */
    int rc = profile_coefficients(cycle, M, g, err);
    if (rc == BKF_OK) {
        /* column-major: A[row + col n] */
        for (size_t c = 0; c < nm; c++) {
            double k = (tr.theta + TWO_PI * (double)(tr.m0 + (long)c)) / T;
            for (size_t row = 0; row < nm; row++) {
                long d = (long)row - (long)c;
                double complex gd = d >= 0 ? g[d] : conj(g[-d]);
                A[row + c * n] = -gamma * gd;
            }
            A[c + c * n] += -I * k / s;
            A[c + (c + nm) * n] = gamma;
            A[(c + nm) + c * n] = -(1.0 + beta * k * k) / gamma;
            A[(c + nm) + (c + nm) * n] = -I * k / s;
        }
    }
    free(g);
    return rc;
}

/* Every eigenvalue of class theta at M modes into out (hill_count's
 * number of them). */
static int spectrum_body(bkf_cycle *cycle, double gamma, double theta, size_t M,
                         bkf_hill_eigenvalue *out, bkf_error *err)
{
    truncation tr = truncation_of(theta, M);
    size_t nm = tr.nm, n = 2 * nm;
    double complex *A = calloc(n * n, sizeof(double complex));
    double complex *w = malloc(sizeof(double complex) * n);
    if (!A || !w) {
        free(A);
        free(w);
        return bkf_error_set(err, BKF_ENOMEM, "out of memory (Hill matrix of size %zu)", n);
    }
    int rc = hill_matrix(cycle, gamma, tr, M, A, err);
    if (rc == BKF_OK) {
        lapack_int info = tr.real ? real_eigenvalues(A, nm, w)
                                       : LAPACKE_zgeev(LAPACK_COL_MAJOR, 'N', 'N', (lapack_int)n, A, (lapack_int)n,
                                                       w, NULL, 1, NULL, 1);
        if (info != 0)
            rc = bkf_error_set(err, info == LAPACK_WORK_MEMORY_ERROR ? BKF_ENOMEM : BKF_ENUMERIC,
                               "zgeev failed (info %d) on the Hill matrix of size %zu", (int)info, n);
    }
    for (size_t i = 0; rc == BKF_OK && i < n; i++) {
        out[i].re = creal(w[i]);
        out[i].im = cimag(w[i]);
        if (!isfinite(out[i].re) || !isfinite(out[i].im))
            rc = bkf_error_set(err, BKF_ENUMERIC, "non-finite eigenvalue of the Hill matrix");
    }
    if (rc == BKF_OK) qsort(out, n, sizeof *out, by_real_part);
    free(A);
    free(w);
    return rc;
}

/* |z|^2 without cabs's hypot and pow: the norms below took 2.6% of
 * speeds --stability's samples */
static double abs2(double complex z)
{
    return creal(z) * creal(z) + cimag(z) * cimag(z);
}

/* Inverse iteration on A - shift, v from a fixed start: the eigenvalue
 * nearest the shift as the Rayleigh quotient of v, once A v - lambda v is
 * below NEAR_RESIDUAL times |A|_F (a backward-stable eigenpair); else NaN.
 * A column-major (n x n, hill_matrix's): [[P, gamma I], [D, Q]] with D
 * and Q diagonal, so (A - shift) (x, y) = (b1, b2) is y = (b2 - D x) /
 * (Q - shift) and S x = b1 - gamma (b2 - D x)... eliminated: S = P - shift
 * - gamma D / (Q - shift), half the size, an LU an eighth of the whole
 * matrix's (the whole one was most of the candidates' check: n = 8 of the
 * paper's table, 28% of its spectrum).  Eliminating the diagonal block
 * first perturbs each of its entries by rounding relative to itself, and
 * the eigenpair is certified by A's own residual all the same.  S (nm x
 * nm) and its permutation are scratch, as are v, w (n each) and q (nm). */
#define NEAR_ITERATIONS 12
#define NEAR_RESIDUAL 1e-12
static double complex nearest_one(const double complex *A, size_t n, double a_norm, double complex shift,
                                  gsl_matrix_complex *S, gsl_permutation *perm, double complex *v,
                                  double complex *w, double complex *q)
{
    size_t nm = n / 2;
    /* an exact eigenvalue as the shift makes the LU singular: nudge it */
    shift += 1e-12 * (1.0 + cabs(shift));
    double gamma = creal(A[(size_t)0 + nm * n]);
    /* q = 1 / (Q - shift); D's entries are A's at (nm + i, i) */
    for (size_t i = 0; i < nm; i++) q[i] = 1.0 / (A[(nm + i) + (nm + i) * n] - shift);
    for (size_t i = 0; i < nm; i++) {
        double *row = S->data + 2 * i * S->tda;
        for (size_t j = 0; j < nm; j++) {
            double complex a = A[i + j * n];
            if (i == j) a -= shift + gamma * A[(nm + i) + i * n] * q[i];
            row[2 * j] = creal(a);
            row[2 * j + 1] = cimag(a);
        }
    }
    int sign;
    if (gsl_linalg_complex_LU_decomp(S, perm, &sign) != GSL_SUCCESS) return NAN;
    /* a start no eigenvector of the structured matrix is orthogonal to in practice */
    for (size_t i = 0; i < n; i++) v[i] = cexp(I * 2.399963229728653 * (double)i) / sqrt((double)n);
    gsl_vector_complex_view xv = gsl_vector_complex_view_array((double *)v, nm);
    for (int it = 0; it < NEAR_ITERATIONS; it++) {
        /* x from S x = b1 - gamma b2 / (Q - shift), in place in v's first half */
        for (size_t i = 0; i < nm; i++) v[i] -= gamma * v[nm + i] * q[i];
        if (gsl_linalg_complex_LU_svx(S, perm, &xv.vector) != GSL_SUCCESS) return NAN;
        for (size_t i = 0; i < nm; i++) v[nm + i] = (v[nm + i] - A[(nm + i) + i * n] * v[i]) * q[i];
        double norm = 0.0;
        for (size_t i = 0; i < n; i++) norm += abs2(v[i]);
        norm = sqrt(norm);
        if (!(norm > 0.0) || !isfinite(norm)) return NAN;
        for (size_t i = 0; i < n; i++) v[i] /= norm;
        /* w = A v (by its blocks), lambda = v^H A v, residual |A v - lambda v| */
        for (size_t i = 0; i < nm; i++) {
            w[i] = gamma * v[nm + i];
            w[nm + i] = A[(nm + i) + i * n] * v[i] + A[(nm + i) + (nm + i) * n] * v[nm + i];
        }
        for (size_t j = 0; j < nm; j++)
            for (size_t i = 0; i < nm; i++) w[i] += A[i + j * n] * v[j];
        double complex lambda = 0.0;
        for (size_t i = 0; i < n; i++) lambda += conj(v[i]) * w[i];
        double res = 0.0;
        for (size_t i = 0; i < n; i++) res += abs2(w[i] - lambda * v[i]);
        if (sqrt(res) <= NEAR_RESIDUAL * a_norm) return lambda;
    }
    return NAN;
}

int hill_nearest(bkf_cycle *cycle, double gamma, double theta, size_t modes, const bkf_hill_eigenvalue *at,
                 size_t count, bkf_hill_eigenvalue *out, bkf_error *err)
{
    int rc = check_inputs(cycle, gamma, theta, modes, BKF_HILL_MODES_MAX, err);
    if (rc != BKF_OK) return rc;
    truncation tr = truncation_of(theta, modes);
    size_t nm = tr.nm, n = 2 * nm;
    double complex *A = calloc(n * n, sizeof *A), *v = malloc(n * sizeof *v), *w = malloc(n * sizeof *w);
    double complex *q = malloc(nm * sizeof *q);
    gsl_matrix_complex *S = gsl_matrix_complex_alloc(nm, nm);
    gsl_permutation *perm = gsl_permutation_alloc(nm);
    if (!A || !v || !w || !q || !S || !perm)
        rc = bkf_error_set(err, BKF_ENOMEM, "out of memory (Hill matrix of size %zu)", n);
    if (rc == BKF_OK) rc = hill_matrix(cycle, gamma, tr, modes, A, err);
    /* GSL reports a singular LU (a shift on an eigenvalue) through its
     * handler: a NaN here, never an abort */
    bkf_gsl_handler *handler = bkf_gsl_handler_push();
    double a_norm = 0.0;
    for (size_t i = 0; rc == BKF_OK && i < n * n; i++) a_norm += abs2(A[i]);
    a_norm = sqrt(a_norm);
    for (size_t k = 0; rc == BKF_OK && k < count; k++) {
        double complex l = nearest_one(A, n, a_norm, at[k].re + I * at[k].im, S, perm, v, w, q);
        out[k].re = creal(l);
        out[k].im = cimag(l);
    }
    bkf_gsl_handler_pop(handler);
    free(A);
    free(v);
    free(w);
    free(q);
    if (S) gsl_matrix_complex_free(S);
    if (perm) gsl_permutation_free(perm);
    return rc;
}

int bkf_hill_spectrum(bkf_cycle *cycle, double gamma, double theta, size_t modes,
                      bkf_hill_eigenvalue *out, size_t *count, bkf_error *err)
{
    if (count) *count = 0;
    int rc = check_inputs(cycle, gamma, theta, modes, BKF_HILL_MODES_MAX, err);
    if (rc != BKF_OK) return rc;
    if (!out || !count) return bkf_error_set(err, BKF_EINPUT, "out and count must not be NULL");
    rc = spectrum_body(cycle, gamma, theta, modes, out, err);
    if (rc == BKF_OK) *count = hill_count(theta, modes);
    return rc;
}

int bkf_hill_converged(const bkf_hill_eigenvalue *coarse, size_t n_coarse, const bkf_hill_eigenvalue *fine,
                       size_t n_fine, double tol, size_t k, bkf_hill_eigenvalue *out, double *out_err,
                       size_t *found, size_t *unresolved, bkf_error *err)
{
    if (found) *found = 0;
    if (unresolved) *unresolved = 0;
    if (!coarse || !fine || !out || !found)
        return bkf_error_set(err, BKF_EINPUT, "coarse, fine, out and found must not be NULL");
    if (!(tol > 0 && isfinite(tol))) return bkf_error_set(err, BKF_EINPUT, "tol must be positive and finite");
    if (k < 1) return bkf_error_set(err, BKF_EINPUT, "k must be at least 1");
    size_t got = 0, skipped = 0, skipped_above = 0;
    for (size_t i = 0; i < n_fine && got < k; i++) {
        double best = INFINITY;
        for (size_t j = 0; j < n_coarse; j++)
            best = fmin(best, hypot(fine[i].re - coarse[j].re, fine[i].im - coarse[j].im));
        if (!(best <= tol)) {
            skipped++;
            continue;
        }
        out[got] = fine[i];
        if (out_err) out_err[got] = best;
        got++;
        skipped_above = skipped;
    }
    *found = got;
    if (unresolved) *unresolved = got ? skipped_above : skipped;
    return BKF_OK;
}

int bkf_hill_leading_pair(bkf_cycle *cycle, double gamma, double theta, size_t modes, size_t modes_fine,
                          double tol, size_t k, bkf_hill_eigenvalue *out, double *out_err, size_t *found,
                          size_t *unresolved, bkf_error *err)
{
    if (found) *found = 0;
    if (unresolved) *unresolved = 0;
    int rc = check_inputs(cycle, gamma, theta, modes, BKF_HILL_MODES_MAX, err);
    if (rc != BKF_OK) return rc;
    if (!(modes_fine > modes && modes_fine <= BKF_HILL_MODES_MAX))
        return bkf_error_set(err, BKF_EINPUT, "modes_fine must be in [modes + 1, %d]", BKF_HILL_MODES_MAX);
    if (!(tol > 0 && isfinite(tol))) return bkf_error_set(err, BKF_EINPUT, "tol must be positive and finite");
    if (k < 1) return bkf_error_set(err, BKF_EINPUT, "k must be at least 1");
    if (!out || !found) return bkf_error_set(err, BKF_EINPUT, "out and found must not be NULL");
    size_t n1 = hill_count(theta, modes), n2 = hill_count(theta, modes_fine);
    bkf_hill_eigenvalue *coarse = malloc(sizeof *coarse * n1), *fine = malloc(sizeof *fine * n2);
    if (!coarse || !fine) rc = bkf_error_set(err, BKF_ENOMEM, "out of memory");
    if (rc == BKF_OK) rc = spectrum_body(cycle, gamma, theta, modes, coarse, err);
    if (rc == BKF_OK) rc = spectrum_body(cycle, gamma, theta, modes_fine, fine, err);
    if (rc == BKF_OK) rc = bkf_hill_converged(coarse, n1, fine, n2, tol, k, out, out_err, found, unresolved, err);
    free(coarse);
    free(fine);
    return rc;
}

int bkf_hill_leading(bkf_cycle *cycle, double gamma, double theta, size_t modes, double tol,
                     size_t k, bkf_hill_eigenvalue *out, double *out_err, size_t *found,
                     size_t *unresolved, bkf_error *err)
{
    if (found) *found = 0;
    if (unresolved) *unresolved = 0;
    int rc = check_inputs(cycle, gamma, theta, modes, BKF_HILL_MODES_MAX / 2, err);
    if (rc != BKF_OK) return rc;
    return bkf_hill_leading_pair(cycle, gamma, theta, modes, 2 * modes, tol, k, out, out_err, found,
                                 unresolved, err);
}

/* LAPACK (through LAPACKE) and ARPACK, loaded at their first call.
 *
 * Linked, liblapacke and libarpack bring liblapack, libblas, libtmglib,
 * libgfortran and libquadmath into every bkfront process: 2 of its 3.7 ms
 * of start (perf stat, task-clock), for `--version` as for a spectrum.
 * Only the Hill matrices' zgeev and dgeev (stability/hill.c) and the
 * orbits' Arnoldi (simulation/orbit_mult.c) call them, so the library
 * defines the four functions it calls: each loads its library once
 * (bkf_lazy_open under pthread_once) and calls the real one.  The callers
 * are the same code as when linked: lazylib.h renames their calls to the
 * bkf_ symbols defined here, so that neither libbkfront.a beside the real
 * liblapacke.a nor libbkfront.so defines LAPACK's or ARPACK's names.
 *
 * Where a library does not load, the call fails as the callers already
 * handle a failed call: zgeev's and dgeev's info and ARPACK's info are set to
 * BKF_LAZY_NOT_LOADED, and bkf_lazy_failure() says which library did not
 * load and why. */
#define _POSIX_C_SOURCE 200809L
#include "bkfront/lazylib.h"
#include "lazylib_internal.h"

#include <dlfcn.h>
#include <pthread.h>
#include <stdio.h>
#include <string.h>

/* The renamed declarations (lazylib.h), hidden: libbkfront.so exports bkf_
 * names, and these are LAPACK's and ARPACK's, not the library's. */
#pragma GCC visibility push(hidden)
#include <arpack/arpack.h>
#include <lapacke.h>
#pragma GCC visibility pop

#ifndef BKF_LIBRARY_SOURCE
#error "lazylib.c is compiled with BKF_LIBRARY_SOURCE (the Makefile sets it for src/): its functions must be the bkf_ names"
#endif
#ifndef BKF_LAPACKE_SONAME
#error "BKF_LAPACKE_SONAME (the soname of liblapacke, e.g. liblapacke.so.3) is set by the Makefile"
#endif
#ifndef BKF_ARPACK_SONAME
#error "BKF_ARPACK_SONAME (the soname of libarpack, e.g. libarpack.so.2) is set by the Makefile"
#endif

int bkf_lazy_open(const char *soname, const char *package, const char *const *names, void **out,
                  size_t count, bkf_error *err)
{
    for (size_t i = 0; i < count; i++) out[i] = NULL;
    void *lib = dlopen(soname, RTLD_NOW | RTLD_LOCAL);
    if (!lib) {
        const char *why = dlerror();
        return bkf_error_set(err, BKF_EIO, "%s does not load: %s (Debian: apt-get install %s)",
                             soname, why ? why : "unknown reason", package);
    }
    for (size_t i = 0; i < count; i++) {
        (void)dlerror();
        if (!(out[i] = dlsym(lib, names[i]))) {
            for (size_t k = 0; k < i; k++) out[k] = NULL;
            return bkf_error_set(err, BKF_EIO, "%s has no symbol %s (Debian: apt-get install %s)",
                                 soname, names[i], package);
        }
    }
    return BKF_OK;
}

static struct {
    __typeof__(LAPACKE_zgeev) *zgeev;
    __typeof__(LAPACKE_dgeev) *dgeev;
    __typeof__(dnaupd_c) *dnaupd;
    __typeof__(dneupd_c) *dneupd;
} real;

/* The first failure's reason, written once under the pthread_once of the
 * load that failed, read after it. */
static char failure[BKF_ERROR_LEN];
static pthread_mutex_t failure_lock = PTHREAD_MUTEX_INITIALIZER;

/* Loads `soname`'s symbols into `out[]`, or NULLs and the failure noted. */
static void load(const char *soname, const char *package, const char *const *names,
                 void **out, size_t count)
{
    bkf_error e;
    if (!bkf_lazy_open(soname, package, names, out, count, &e)) return;
    pthread_mutex_lock(&failure_lock);
    if (!failure[0]) snprintf(failure, sizeof failure, "%s", e.message);
    pthread_mutex_unlock(&failure_lock);
}

static pthread_once_t lapacke_once = PTHREAD_ONCE_INIT, arpack_once = PTHREAD_ONCE_INIT;

static void load_lapacke(void)
{
    static const char *const names[] = {"LAPACKE_zgeev", "LAPACKE_dgeev"};
    void *p[2];
    load(BKF_LAPACKE_SONAME, "liblapacke", names, p, 2);
    real.zgeev = (__typeof__(real.zgeev))p[0];
    real.dgeev = (__typeof__(real.dgeev))p[1];
}

static void load_arpack(void)
{
    static const char *const names[] = {"dnaupd_c", "dneupd_c"};
    void *p[2];
    load(BKF_ARPACK_SONAME, "libarpack2", names, p, 2);
    real.dnaupd = (__typeof__(real.dnaupd))p[0];
    real.dneupd = (__typeof__(real.dneupd))p[1];
}

const char *bkf_lazy_failure(void)
{
    pthread_mutex_lock(&failure_lock);
    const char *s = failure[0] ? failure : NULL;
    pthread_mutex_unlock(&failure_lock);
    return s;
}

/* The stand-ins: written under the real names, defined as bkf_LAPACKE_zgeev,
 * bkf_LAPACKE_dgeev, bkf_dnaupd_c and bkf_dneupd_c (lazylib.h's macros). */
lapack_int LAPACKE_zgeev(int matrix_layout, char jobvl, char jobvr, lapack_int n,
                         lapack_complex_double *a, lapack_int lda, lapack_complex_double *w,
                         lapack_complex_double *vl, lapack_int ldvl, lapack_complex_double *vr,
                         lapack_int ldvr)
{
    pthread_once(&lapacke_once, load_lapacke);
    if (!real.zgeev) return BKF_LAZY_NOT_LOADED;
    return real.zgeev(matrix_layout, jobvl, jobvr, n, a, lda, w, vl, ldvl, vr, ldvr);
}

lapack_int LAPACKE_dgeev(int matrix_layout, char jobvl, char jobvr, lapack_int n, double *a,
                         lapack_int lda, double *wr, double *wi, double *vl, lapack_int ldvl,
                         double *vr, lapack_int ldvr)
{
    pthread_once(&lapacke_once, load_lapacke);
    if (!real.dgeev) return BKF_LAZY_NOT_LOADED;
    return real.dgeev(matrix_layout, jobvl, jobvr, n, a, lda, wr, wi, vl, ldvl, vr, ldvr);
}

void dnaupd_c(a_int *ido, char const *bmat, a_int n, char const *which, a_int nev, double tol,
              double *resid, a_int ncv, double *v, a_int ldv, a_int *iparam, a_int *ipntr,
              double *workd, double *workl, a_int lworkl, a_int *info)
{
    pthread_once(&arpack_once, load_arpack);
    if (!real.dnaupd) {
        *info = BKF_LAZY_NOT_LOADED;
        *ido = 99; /* ARPACK's "done": the caller's loop ends and reads info */
        return;
    }
    real.dnaupd(ido, bmat, n, which, nev, tol, resid, ncv, v, ldv, iparam, ipntr, workd, workl,
                lworkl, info);
}

void dneupd_c(a_int rvec, char const *howmny, a_int const *select, double *dr, double *di,
              double *z, a_int ldz, double sigmar, double sigmai, double *workev,
              char const *bmat, a_int n, char const *which, a_int nev, double tol, double *resid,
              a_int ncv, double *v, a_int ldv, a_int *iparam, a_int *ipntr, double *workd,
              double *workl, a_int lworkl, a_int *info)
{
    pthread_once(&arpack_once, load_arpack);
    if (!real.dneupd) {
        *info = BKF_LAZY_NOT_LOADED;
        return;
    }
    real.dneupd(rvec, howmny, select, dr, di, z, ldz, sigmar, sigmai, workev, bmat, n, which, nev,
                tol, resid, ncv, v, ldv, iparam, ipntr, workd, workl, lworkl, info);
}

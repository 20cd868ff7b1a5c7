/* Libraries loaded at their first use, not at every process's start
 * (src/core/lazylib.c: LAPACKE's zgeev and dgeev and ARPACK's dnaupd/dneupd; HDF5 by
 * h5.c through the same loader).  A call whose library does not load fails as a failed
 * call of that library does, with the info below. */
#ifndef BKFRONT_LAZYLIB_H
#define BKFRONT_LAZYLIB_H

#ifdef __cplusplus
extern "C" {
#endif

/* The info a lazily loaded call returns (zgeev) or sets (dnaupd, dneupd)
 * when its library does not load: outside the ranges LAPACK and ARPACK
 * use. */
#define BKF_LAZY_NOT_LOADED (-7001)

/* Why the first library that failed to load did not ("liblapacke.so.3 does
 * not load: ... (Debian: apt-get install liblapacke)"), or NULL if none
 * failed.  Thread-safe; the text lives as long as the process. */
const char *bkf_lazy_failure(void);

/* Inside the library (the Makefile defines BKF_LIBRARY_SOURCE for src/),
 * the callers keep LAPACKE's and ARPACK's names and signatures, but the
 * symbols are lazylib.c's bkf_ ones: libbkfront.a linked beside the real
 * liblapacke.a or libarpack.a defines none of their names twice.  A file
 * includes this header before <lapacke.h> or <arpack/arpack.h>, whose
 * declarations are then renamed too.  A program of the user's sees the
 * real names. */
#ifdef BKF_LIBRARY_SOURCE
#define LAPACKE_zgeev bkf_LAPACKE_zgeev
#define LAPACKE_dgeev bkf_LAPACKE_dgeev
#define dnaupd_c bkf_dnaupd_c
#define dneupd_c bkf_dneupd_c
#endif

#ifdef __cplusplus
}
#endif

#endif

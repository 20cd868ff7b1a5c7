/* Libraries loaded at their first use, not at every process's start
 * (src/core/lazylib.c: LAPACKE's zgeev and dgeev and ARPACK's dnaupd/dneupd; HDF5 is
 * loaded by h5.c).  A call whose library does not load fails as a failed
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

#ifdef __cplusplus
}
#endif

#endif

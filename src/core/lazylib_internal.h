/* The one loader of the libraries bkfront opens at their first use
 * (lazylib.c: LAPACKE, ARPACK; h5.c: HDF5). */
#ifndef BKFRONT_LAZYLIB_INTERNAL_H
#define BKFRONT_LAZYLIB_INTERNAL_H

#include <stddef.h>

#include "bkfront/status.h"

/* Opens `soname` (dlopen, RTLD_NOW | RTLD_LOCAL) and looks up
 * names[0..count) into out[] (functions and variables alike): BKF_OK; or
 * BKF_EIO, out[] all NULL and `err` saying which library does not load and
 * why, with the Debian package that brings it ("liblapacke.so.3 does not
 * load: WHY (Debian: apt-get install liblapacke)"), or which symbol it
 * lacks.  A library that opened is never closed, even when a symbol is
 * missing: it may have run constructors or registered exit handlers.  Not
 * serialised: each library is loaded once, under the caller's
 * pthread_once or lock.  Hidden: not part of libbkfront.so's interface. */
__attribute__((visibility("hidden"))) int bkf_lazy_open(const char *soname, const char *package,
                                                        const char *const *names, void **out,
                                                        size_t count, bkf_error *err);

#endif

/* Status codes and error reports shared by every bkfront module.
 *
 * Library calls return a bkf_status and, when given a bkf_error, fill it with
 * a one-line message naming the offending parameter and its valid range (bad
 * input) or what failed (numerical failure).  The message is for people; a
 * program tells failures apart by the code alone.  The library never prints
 * and never exits; mapping a status to an exit code is the CLI's business.
 *
 * GSL's error handler.  GSL's default handler aborts the process on any
 * error; the library checks every GSL status itself instead.  Each public
 * function that reaches GSL turns the handler off on entry and puts the
 * caller's handler back before it returns (bkf_gsl_handler_push/pop below),
 * so the host program's choice of handler is left as it was.  While a library
 * call runs, including the callbacks it makes into the caller's code, the
 * handler is off.  GSL keeps one handler for the whole process, so the
 * calls in flight in all threads share it: the first to enter turns it off,
 * the last to leave puts back the one it found, and library calls in several
 * threads at once are safe.  A host program that sets GSL's handler itself
 * must not do so while a library call runs in another thread. */
#ifndef BKFRONT_STATUS_H
#define BKFRONT_STATUS_H

#ifdef __cplusplus
extern "C" {
#endif

typedef enum {
    BKF_OK = 0,
    /* A numerical failure not covered by the finer codes below: an iteration
     * that did not converge (Newton, a root bracket, an integration that
     * failed), a branch that left its valid range, no sign change where one
     * was expected. */
    BKF_ENUMERIC = 1,
    /* Bad input: a parameter outside its valid range, a NULL argument, a
     * malformed option.  The message names the parameter and its range. */
    BKF_EINPUT = 2,
    /* Out of memory. */
    BKF_ENOMEM = 3,
    /* Stopped by the caller's cancellation flag; the work done so far is
     * kept (the message says how far). */
    BKF_ECANCELED = 4,
    /* Refused: the requested tolerance cannot be met here (the error
     * estimate stays above it, or a formula's error bound exceeds it).  A
     * looser tolerance or another method may succeed. */
    BKF_ETOL = 5,
    /* A step, sample or iteration budget ran out before the answer was
     * reached. */
    BKF_EBUDGET = 6,
    /* The state became non-finite or left its physical bounds. */
    BKF_EBLOWUP = 7,
    /* Reading or writing a file or stream failed. */
    BKF_EIO = 8
} bkf_status;

#define BKF_ERROR_LEN 320

typedef struct {
    char message[BKF_ERROR_LEN];
    int status;  /* the code the message goes with, so that a call that
                    returns a pointer (NULL on failure) still tells why */
} bkf_error;

/* printf-style: fills err (if non-NULL) and returns status, so a caller can
 * write `return bkf_error_set(err, BKF_EINPUT, "...", ...);`. */
int bkf_error_set(bkf_error *err, int status, const char *fmt, ...)
#if defined(__GNUC__) || defined(__clang__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/* A short lower-case name: "ok", "numerical", "input", "out of memory",
 * "canceled", "tolerance", "budget", "blow-up", "i/o"; "unknown status" for
 * any other value.  Never NULL; a static string. */
const char *bkf_status_name(int status);

/* Whether status is one of the numerical failures (ENUMERIC, ETOL, EBUDGET,
 * EBLOWUP): what a caller retries with other settings, or reports as "could
 * not compute", as opposed to bad input, lack of memory, cancellation or
 * I/O. */
int bkf_status_is_numerical(int status);

/* GSL's error handler, saved and restored around a library call (see the top
 * of this file).  push turns the handler off and returns the one that was
 * installed (NULL: GSL's default); the pop that ends the last pair in
 * flight, in any thread, installs again the one found by the first (its
 * argument is not used).  Pairs nest.  Thread-safe.  The
 * type is GSL's gsl_error_handler_t, spelled out so this header needs no GSL
 * header. */
typedef void bkf_gsl_handler(const char *reason, const char *file, int line, int gsl_errno);
bkf_gsl_handler *bkf_gsl_handler_push(void);
void bkf_gsl_handler_pop(bkf_gsl_handler *previous);

#ifdef __cplusplus
}
#endif

#endif

/* Status codes and error reports shared by every bkfront module.
 *
 * Library calls return a bkf_status and, when given a bkf_error, fill it with
 * a one-line message naming the offending parameter and its valid range (bad
 * input) or what failed to converge (numerical failure).  The library never
 * prints and never exits; the CLI maps the status to an exit code. */
#ifndef BKFRONT_STATUS_H
#define BKFRONT_STATUS_H

typedef enum {
    BKF_OK = 0,
    BKF_ENUMERIC = 1, /* numerical failure: no convergence, tolerance not met */
    BKF_EINPUT = 2,   /* bad input: parameter outside its valid range */
    BKF_ENOMEM = 3,
    BKF_ECANCELED = 4, /* stopped by the caller's cancellation flag; the work
                          done so far is kept (the message says how far) */
    BKF_ETOL = 5,      /* refused: the requested tolerance cannot be met here */
    BKF_EBUDGET = 6,   /* a step or iteration budget ran out */
    BKF_EBLOWUP = 7,   /* the state became non-finite or left its bounds */
    BKF_EIO = 8        /* reading or writing a file or stream failed */
} bkf_status;

#define BKF_ERROR_LEN 320

typedef struct {
    char message[BKF_ERROR_LEN];
} bkf_error;

/* printf-style: fills err (if non-NULL) and returns status, so a caller can
 * write `return bkf_error_set(err, BKF_EINPUT, "...", ...);`. */
int bkf_error_set(bkf_error *err, int status, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/* Exit code the CLI uses for a status: 0 ok, 1 numerical, 2 input,
 * 130 canceled (128 + SIGINT, as a shell reports Ctrl-C). */
int bkf_status_exit_code(int status);

#endif

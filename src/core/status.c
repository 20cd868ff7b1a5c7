#include "bkfront/status.h"

#include <gsl/gsl_errno.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>

int bkf_error_set(bkf_error *err, int status, const char *fmt, ...)
{
    if (err) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(err->message, sizeof err->message, fmt, ap);
        va_end(ap);
        err->status = status;
    }
    return status;
}

const char *bkf_status_name(int status)
{
    switch (status) {
    case BKF_OK: return "ok";
    case BKF_ENUMERIC: return "numerical";
    case BKF_EINPUT: return "input";
    case BKF_ENOMEM: return "out of memory";
    case BKF_ECANCELED: return "canceled";
    case BKF_ETOL: return "tolerance";
    case BKF_EBUDGET: return "budget";
    case BKF_EBLOWUP: return "blow-up";
    case BKF_EIO: return "i/o";
    default: return "unknown status";
    }
}

int bkf_status_is_numerical(int status)
{
    return status == BKF_ENUMERIC || status == BKF_ETOL || status == BKF_EBUDGET ||
           status == BKF_EBLOWUP;
}

/* GSL's handler is one variable per process.  Were each call to save and
 * restore it on its own, two threads would interleave: the second saves
 * "off" as the caller's, the first restores the default (abort) while the
 * second still runs.  So the calls in flight share one depth count: the
 * first turns the handler off and keeps the caller's, the last puts it back,
 * and in between nobody writes it. */
static pthread_mutex_t handler_lock = PTHREAD_MUTEX_INITIALIZER;
static unsigned long handler_depth;
static bkf_gsl_handler *handler_saved, *handler_off;

bkf_gsl_handler *bkf_gsl_handler_push(void)
{
    pthread_mutex_lock(&handler_lock);
    bkf_gsl_handler *found = handler_off;
    if (handler_depth++ == 0) {
        found = handler_saved = gsl_set_error_handler_off();
        /* GSL's "off" handler has no public name: read it back */
        handler_off = gsl_set_error_handler_off();
    }
    pthread_mutex_unlock(&handler_lock);
    return found;
}

void bkf_gsl_handler_pop(bkf_gsl_handler *previous)
{
    (void)previous; /* the depth count, not the argument, says what to restore */
    pthread_mutex_lock(&handler_lock);
    if (handler_depth > 0 && --handler_depth == 0) gsl_set_error_handler(handler_saved);
    pthread_mutex_unlock(&handler_lock);
}

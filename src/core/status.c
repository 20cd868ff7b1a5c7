#include "bkfront/status.h"

#include <gsl/gsl_errno.h>
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

/* gsl_set_error_handler_off returns the handler it replaces; installing that
 * one again is the whole restore. */
bkf_gsl_handler *bkf_gsl_handler_push(void) { return gsl_set_error_handler_off(); }

void bkf_gsl_handler_pop(bkf_gsl_handler *previous) { gsl_set_error_handler(previous); }

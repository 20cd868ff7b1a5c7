#include "bkfront/status.h"

#include <stdarg.h>
#include <stdio.h>

int bkf_error_set(bkf_error *err, int status, const char *fmt, ...)
{
    if (err) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(err->message, sizeof err->message, fmt, ap);
        va_end(ap);
    }
    return status;
}

int bkf_status_exit_code(int status)
{
    switch (status) {
    case BKF_OK: return 0;
    case BKF_EINPUT: return 2;
    case BKF_ECANCELED: return 130;
    default: return 1;
    }
}

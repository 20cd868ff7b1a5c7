/* Shared by the libFuzzer targets (make fuzz): the input as a C string, and
 * the checks every parser must pass on any input.  A violated check calls
 * abort(), which libFuzzer reports as a finding with the input that did it. */
#ifndef BKF_FUZZ_COMMON_H
#define BKF_FUZZ_COMMON_H

/* fmemopen, strtok_r (POSIX 2008); the same as the CLI's sources define. */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bkfront/status.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* A NUL-terminated copy (an embedded NUL simply ends the string early, as
 * it would on a command line).  Caller frees. */
static inline char *fuzz_string(const uint8_t *data, size_t size)
{
    char *s = malloc(size + 1);
    if (!s) abort();
    if (size) memcpy(s, data, size);
    s[size] = '\0';
    return s;
}

#define FUZZ_CHECK(cond)                                                          \
    do {                                                                          \
        if (!(cond)) {                                                            \
            fprintf(stderr, "fuzz check failed: %s (%s:%d)\n", #cond, __FILE__,  \
                    __LINE__);                                                    \
            abort();                                                              \
        }                                                                         \
    } while (0)

/* The project's error contract: a known status, and on failure a non-empty
 * one-line message without control characters (user text inside it must be
 * sanitized, or a pasted escape sequence would reach the terminal). */
static inline void fuzz_check_status(int status, const bkf_error *err)
{
    FUZZ_CHECK(status == BKF_OK || status == BKF_EINPUT || status == BKF_ENOMEM ||
               bkf_status_is_numerical(status));
    if (status == BKF_OK) return;
    FUZZ_CHECK(err->message[0] != '\0');
    for (const unsigned char *p = (const unsigned char *)err->message; *p; p++)
        FUZZ_CHECK(*p >= 0x20 && *p != 0x7f);
}

#endif

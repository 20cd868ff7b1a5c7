/* The library's version.  The macros are the version a program was compiled
 * against; bkf_version() the one it runs with (they differ only when a
 * program is linked against another build of the library). */
#ifndef BKFRONT_VERSION_H
#define BKFRONT_VERSION_H

#ifdef __cplusplus
extern "C" {
#endif

#define BKF_VERSION_MAJOR 0
#define BKF_VERSION_MINOR 1
#define BKF_VERSION_PATCH 0

#define BKF_VERSION_STR_(x) #x
#define BKF_VERSION_STR(x) BKF_VERSION_STR_(x)
/* "MAJOR.MINOR.PATCH", a string literal. */
#define BKF_VERSION_STRING                                                        \
    BKF_VERSION_STR(BKF_VERSION_MAJOR) "." BKF_VERSION_STR(BKF_VERSION_MINOR) "." \
    BKF_VERSION_STR(BKF_VERSION_PATCH)

/* "MAJOR.MINOR.PATCH" of the library linked in; a static string. */
const char *bkf_version(void);

#ifdef __cplusplus
}
#endif

#endif

#include "bkfront/version.h"

const char *bkf_version(void) { return BKF_VERSION_STRING; }

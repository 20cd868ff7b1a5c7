/* The CLI's side of the contract: exit codes from statuses (unchanged for
 * users) and the version, which is the library's. */
#define _POSIX_C_SOURCE 200809L
#include "harness.h"

#include "cli_support.h"

#include <string.h>

#include "args.h"
#include "bkfront/version.h"

#ifndef BKF_CLI_PATH
#define BKF_CLI_PATH "build/bkfront"
#endif

TEST(cli_exit_codes_by_status)
{
    CHECK(cli_exit_code(BKF_OK) == 0);
    CHECK(cli_exit_code(BKF_EINPUT) == 2);
    /* no signal arrived in this process: canceled reads as Ctrl-C */
    CHECK(cli_exit_code(BKF_ECANCELED) == 130);
    int ones[] = {BKF_ENUMERIC, BKF_ETOL, BKF_EBUDGET, BKF_EBLOWUP, BKF_ENOMEM, BKF_EIO, 99};
    for (size_t i = 0; i < sizeof ones / sizeof ones[0]; i++)
        CHECK_MSG(cli_exit_code(ones[i]) == 1, "%s: %d", bkf_status_name(ones[i]),
                  cli_exit_code(ones[i]));
}

TEST(cli_version_is_the_library_version)
{
    char *line = bkf_cli_stdout("--version", NULL);
    CHECK_MSG(strcmp(line, "bkfront " BKF_VERSION_STRING "\n") == 0, "'%s'", line);
    free(line);
    CHECK(strcmp(BKF_VERSION_STRING, bkf_version()) == 0);
}

/* The manual's command pages carry each command's usage and options block
 * between <!-- options: CMD --> and <!-- /options -->, copied from
 * `bkfront CMD --help`: every line of that block must still be in the
 * page, so a changed flag cannot leave the manual behind. */
#define _POSIX_C_SOURCE 200809L
#include "harness.h"

#include <dirent.h>
#include <stdlib.h>
#include <string.h>

#include "cli_support.h"

#ifndef BKF_SOURCE_DIR
#define BKF_SOURCE_DIR "."
#endif

/* The usage lines (up to the first empty line) and the options block
 * ("options..." and the indented lines after it) of `help`, each looked
 * for in the page's block. */
static size_t check_page(const char *cmd, const char *page_block, char *help)
{
    size_t checked = 0;
    int part = 0; /* 0 usage, 1 between, 2 options, 3 after */
    for (char *line = help, *next; line && *line && part < 3; line = next) {
        next = strchr(line, '\n');
        if (next) *next++ = '\0';
        if (part == 0 && !*line) part = 1;
        if (part == 1 && strncmp(line, "options", 7) == 0) part = 2;
        else if (part == 2 && line[0] != ' ') part = 3;
        if (part == 1 || part == 3 || !*line) continue;
        CHECK_MSG(strstr(page_block, line) != NULL, "docs/cli/%s.md lacks the help line '%s'",
                  cmd, line);
        checked++;
    }
    return checked;
}

TEST(docs_option_blocks_match_help)
{
    DIR *d = opendir(BKF_SOURCE_DIR "/docs/cli");
    CHECK(d != NULL);
    size_t pages = 0;
    for (struct dirent *e; (e = readdir(d)) != NULL;) {
        size_t len = strlen(e->d_name);
        if (len < 4 || strcmp(e->d_name + len - 3, ".md") != 0) continue;
        char path[1024];
        snprintf(path, sizeof path, "%s/docs/cli/%s", BKF_SOURCE_DIR, e->d_name);
        char *page = bkf_cli_read_file(path);
        CHECK(page != NULL);
        char cmd[64];
        snprintf(cmd, sizeof cmd, "%.*s", (int)(len - 3), e->d_name);
        char marker[96];
        snprintf(marker, sizeof marker, "<!-- options: %s -->", cmd);
        char *start = strstr(page, marker), *end = start ? strstr(start, "<!-- /options -->") : NULL;
        CHECK_MSG(start && end, "docs/cli/%s.md has no options block", cmd);
        *end = '\0';
        bkf_cli_result r = BKF_CLI(cmd, "--help");
        CHECK_MSG(r.code == 0, "%s --help: %s", cmd, r.err);
        CHECK(check_page(cmd, start, r.out) >= 3);
        bkf_cli_result_free(&r);
        free(page);
        pages++;
    }
    closedir(d);
    CHECK(pages >= 10);
}

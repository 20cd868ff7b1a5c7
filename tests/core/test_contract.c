/* The library's contract beyond any one module: status names, the version,
 * and the umbrella header, compiled as a user would (C with -pedantic, and
 * C++ where a C++ compiler is installed, linked to check the extern "C"
 * guards). */
#define _POSIX_C_SOURCE 200809L
#include "harness.h"

#include <dirent.h>
#include <string.h>
#include <sys/wait.h>
#include <unistd.h>

#include "bkfront/status.h"
#include "bkfront/version.h"

#ifndef BKF_SOURCE_DIR
#define BKF_SOURCE_DIR "."
#endif

TEST(status_names_are_distinct_and_fixed)
{
    static const struct {
        int status;
        const char *name;
        int numerical;
    } want[] = {
        {BKF_OK, "ok", 0},           {BKF_ENUMERIC, "numerical", 1},
        {BKF_EINPUT, "input", 0},    {BKF_ENOMEM, "out of memory", 0},
        {BKF_ECANCELED, "canceled", 0}, {BKF_ETOL, "tolerance", 1},
        {BKF_EBUDGET, "budget", 1},  {BKF_EBLOWUP, "blow-up", 1},
        {BKF_EIO, "i/o", 0},
    };
    size_t n = sizeof want / sizeof want[0];
    for (size_t i = 0; i < n; i++) {
        CHECK_MSG(strcmp(bkf_status_name(want[i].status), want[i].name) == 0, "%d: '%s'",
                  want[i].status, bkf_status_name(want[i].status));
        CHECK_MSG(bkf_status_is_numerical(want[i].status) == want[i].numerical, "%s",
                  want[i].name);
        for (size_t j = 0; j < i; j++) CHECK(want[i].status != want[j].status);
    }
    CHECK(strcmp(bkf_status_name(-1), "unknown status") == 0);
    CHECK(strcmp(bkf_status_name(BKF_EIO + 1), "unknown status") == 0);
    CHECK(!bkf_status_is_numerical(BKF_EIO + 1));
}

TEST(version_macros_and_function_agree)
{
    char want[64];
    snprintf(want, sizeof want, "%d.%d.%d", BKF_VERSION_MAJOR, BKF_VERSION_MINOR,
             BKF_VERSION_PATCH);
    CHECK_MSG(strcmp(BKF_VERSION_STRING, want) == 0, "%s vs %s", BKF_VERSION_STRING, want);
    CHECK_MSG(strcmp(bkf_version(), BKF_VERSION_STRING) == 0, "%s", bkf_version());
}

static char *slurp(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    char *buf = calloc(1, 1 << 16);
    if (buf) buf[fread(buf, 1, (1 << 16) - 1, f)] = '\0';
    fclose(f);
    return buf;
}

TEST(umbrella_header_includes_every_public_header)
{
    char *umbrella = slurp(BKF_SOURCE_DIR "/include/bkfront/bkfront.h");
    CHECK(umbrella);
    DIR *d = opendir(BKF_SOURCE_DIR "/include/bkfront");
    CHECK(d);
    size_t headers = 0;
    for (struct dirent *e; (e = readdir(d)) != NULL;) {
        size_t len = strlen(e->d_name);
        if (len < 3 || strcmp(e->d_name + len - 2, ".h") != 0 ||
            strcmp(e->d_name, "bkfront.h") == 0)
            continue;
        char line[300];
        snprintf(line, sizeof line, "#include \"bkfront/%s\"", e->d_name);
        CHECK_MSG(strstr(umbrella, line), "bkfront.h lacks %s", line);
        char path[1024];
        snprintf(path, sizeof path, BKF_SOURCE_DIR "/include/bkfront/%s", e->d_name);
        char *text = slurp(path);
        CHECK(text);
        CHECK_MSG(strstr(text, "#ifdef __cplusplus\nextern \"C\" {\n#endif"), "%s: no extern \"C\"",
                  e->d_name);
        free(text);
        headers++;
    }
    closedir(d);
    free(umbrella);
    CHECK_MSG(headers >= 14, "only %zu headers found", headers);
}

/* Runs a shell command in a fresh temporary folder (given as $T), returns
 * its exit status; its output goes to the test's log. */
static int run_in_tmp(const char *script)
{
    char dir[] = "/tmp/bkf_contract_XXXXXX";
    CHECK(mkdtemp(dir));
    char cmd[4096];
    snprintf(cmd, sizeof cmd, "T=%s; S='%s'; %s; rc=$?; rm -rf \"$T\"; exit $rc", dir,
             BKF_SOURCE_DIR, script);
    int st = system(cmd);
    return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

TEST(umbrella_header_compiles_alone_as_pedantic_c)
{
    int rc = run_in_tmp(
        "printf '#include \"bkfront/bkfront.h\"\\n"
        "int main(void) { bkf_error e = {0}; (void)e; return bkf_version()[0] == 0; }\\n'"
        " > \"$T/a.c\" && cc -std=c11 -Wall -Wextra -Werror -pedantic -I\"$S/include\""
        " -c \"$T/a.c\" -o \"$T/a.o\"");
    CHECK_MSG(rc == 0, "cc on a file including only bkfront/bkfront.h: exit %d", rc);
}

TEST(umbrella_header_links_from_cpp)
{
    if (system("command -v g++ >/dev/null 2>&1") != 0) {
        bkf_test_note("skipped: no g++ installed");
        return;
    }
    /* The C++ program calls C functions of the library: without the extern
     * "C" guards their mangled names would not link. */
    int rc = run_in_tmp(
        "printf '#include \"bkfront/bkfront.h\"\\n#include <cstdio>\\n#include <cstring>\\n"
        "int main() { std::printf(\"%%s %%s\", bkf_version(), bkf_status_name(BKF_ETOL));"
        " return std::strcmp(bkf_version(), BKF_VERSION_STRING) != 0; }\\n' > \"$T/a.cpp\""
        " && cc -std=c11 -I\"$S/include\" -c \"$S/src/core/version.c\" -o \"$T/v.o\""
        " && cc -std=c11 -I\"$S/include\" -c \"$S/src/core/status.c\" -o \"$T/s.o\""
        " && g++ -std=c++11 -Wall -Wextra -Werror -pedantic -I\"$S/include\" \"$T/a.cpp\""
        " \"$T/v.o\" \"$T/s.o\" -o \"$T/a\" -lgsl -lgslcblas -lm"
        " && \"$T/a\" > \"$T/out\" && test \"$(cat \"$T/out\")\" = '" BKF_VERSION_STRING
        " tolerance'");
    CHECK_MSG(rc == 0, "C++ program including bkfront/bkfront.h: exit %d", rc);
}

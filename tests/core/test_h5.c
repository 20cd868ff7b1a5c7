/* The HDF5 writer's failures (h5.h): bad grids refused before anything is
 * written, and a write that fails (a file size limit) leaves the target as
 * it was and no temporary behind, with a message and no HDF5 error stack
 * printed.  What a good file holds is read back with h5py
 * (tests/python/test_spacetime_h5.py). */
#define _DEFAULT_SOURCE
#include "harness.h"

#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include "bkfront/h5.h"
#include "bkfront/simulate.h"

static const double axis_values[3] = {0, 1, 2};
static const float field_values[9] = {1, 2, 3, 4, 5, 6, 7, 8, 9};

static bkf_h5_grid grid_of(const bkf_h5_field *fields, size_t n)
{
    return (bkf_h5_grid){.rows = {"t", axis_values, 3, NULL},
                         .columns = {"x", axis_values, 3, NULL},
                         .fields = fields,
                         .nfields = n};
}

static long stream_size(bkf_io_atomic *f)
{
    FILE *s = bkf_io_atomic_stream(f);
    fflush(s);
    return ftell(s);
}

TEST(h5_bad_grids_are_refused_before_writing)
{
    char dir[] = "/tmp/bkf_h5_XXXXXX";
    CHECK(mkdtemp(dir) != NULL);
    char path[64];
    snprintf(path, sizeof path, "%s/out.h5", dir);
    bkf_io_atomic *f = bkf_io_atomic_open(path, NULL);
    CHECK(f != NULL);
    bkf_error e;
    bkf_h5_field psi = {"psi", field_values, NULL}, twice[2] = {psi, psi};
    bkf_h5_field named_t = {"t", field_values, NULL}, slash = {"a/b", field_values, NULL};
    bkf_h5_grid g = grid_of(&psi, 0);
    CHECK_STATUS(bkf_h5_write(f, &g, &e), BKF_EINPUT);
    CHECK(strstr(e.message, "no fields"));
    g = grid_of(twice, 2);
    CHECK_STATUS(bkf_h5_write(f, &g, &e), BKF_EINPUT);
    CHECK(strstr(e.message, "'psi' is given twice"));
    g = grid_of(&named_t, 1);
    CHECK_STATUS(bkf_h5_write(f, &g, &e), BKF_EINPUT);
    g = grid_of(&slash, 1);
    CHECK_STATUS(bkf_h5_write(f, &g, &e), BKF_EINPUT);
    g = grid_of(&psi, 1);
    g.deflate = 10;
    CHECK_STATUS(bkf_h5_write(f, &g, &e), BKF_EINPUT);
    CHECK(strstr(e.message, "deflate 10"));
    CHECK_STATUS(bkf_h5_write(f, NULL, &e), BKF_EINPUT);
    CHECK(stream_size(f) == 0);
    /* the same grid, valid: an HDF5 file (its signature first) */
    g.deflate = 3;
    CHECK_STATUS(bkf_h5_write(f, &g, &e), BKF_OK);
    CHECK(stream_size(f) > 0);
    CHECK_STATUS(bkf_io_atomic_commit(f, &e), BKF_OK);
    FILE *in = fopen(path, "rb");
    CHECK(in != NULL);
    unsigned char sig[8];
    CHECK(fread(sig, 1, 8, in) == 8);
    fclose(in);
    CHECK(memcmp(sig, "\x89HDF\r\n\x1a\n", 8) == 0);
    unlink(path);
    CHECK(rmdir(dir) == 0);
}

/* A spacetime file of about 100 KB under a 64 KiB file size limit: the
 * write fails, the run reports it, the earlier file stays, no temporary. */
TEST(h5_failed_write_keeps_the_old_file)
{
    char dir[] = "/tmp/bkf_h5_XXXXXX";
    CHECK(mkdtemp(dir) != NULL);
    char path[64], errpath[80];
    snprintf(path, sizeof path, "%s/st.h5", dir);
    snprintf(errpath, sizeof errpath, "%s.stderr", dir);
    FILE *old = fopen(path, "w");
    CHECK(old != NULL);
    fputs("complete earlier file\n", old);
    fclose(old);
    pid_t pid = fork();
    CHECK(pid >= 0);
    if (pid == 0) {
        /* HDF5 must print nothing itself: its stack would land here */
        if (!freopen(errpath, "w", stderr)) _exit(10);
        signal(SIGXFSZ, SIG_IGN);
        struct rlimit rl = {64 << 10, 64 << 10};
        if (setrlimit(RLIMIT_FSIZE, &rl)) _exit(11);
        bkf_simulate_spec sp = bkf_simulate_spec_default();
        sp.model.N = 256;
        sp.tmax = 2;
        sp.frames = 100;
        sp.spacetime = path;
        FILE *out = fopen("/dev/null", "w");
        bkf_error e = {0};
        int s = bkf_simulate_write(&sp, out, BKF_IO_TSV, NULL, &e);
        fclose(out);
        if (s != BKF_EIO) _exit(12);
        if (!strstr(e.message, "spacetime: writing the HDF5 file failed")) _exit(13);
        _exit(0);
    }
    int st;
    CHECK(waitpid(pid, &st, 0) == pid);
    CHECK_MSG(WIFEXITED(st) && WEXITSTATUS(st) == 0, "child status %d", st);
    FILE *in = fopen(path, "r");
    CHECK(in != NULL);
    char buf[64] = "";
    CHECK(fgets(buf, sizeof buf, in) != NULL);
    fclose(in);
    CHECK_MSG(strcmp(buf, "complete earlier file\n") == 0, "the target became '%s'", buf);
    FILE *err = fopen(errpath, "r");
    CHECK(err != NULL);
    CHECK_MSG(fgetc(err) == EOF, "the library printed on stderr");
    fclose(err);
    unlink(errpath);
    char cmd[128];
    snprintf(cmd, sizeof cmd, "ls -A '%s'", dir);
    FILE *ls = popen(cmd, "r");
    CHECK(ls != NULL);
    char listing[256] = "";
    size_t n = fread(listing, 1, sizeof listing - 1, ls);
    listing[n] = '\0';
    pclose(ls);
    CHECK_MSG(strcmp(listing, "st.h5\n") == 0, "left in the folder: %s", listing);
    unlink(path);
    CHECK(rmdir(dir) == 0);
}

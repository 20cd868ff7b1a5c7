/* A process start pays only for what its command uses: the CLI's
 * dependency tree (as the dynamic loader resolves it) holds no HDF5 and
 * none of HDF5's own tree (libcurl, ...), no LAPACK and no ARPACK (and
 * none of their tree: libblas, libgfortran); HDF5 is loaded at the first
 * HDF5 write, LAPACKE and ARPACK at their first call (src/core/lazylib.c),
 * and where one cannot be loaded only what needs it fails, with a line
 * that names it.  (What an HDF5 file holds: test_h5.c and
 * tests/python/test_spacetime_h5.py.) */
#define _DEFAULT_SOURCE
#include "cli_support.h"
#include "harness.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

TEST(cli_start_loads_no_hdf5)
{
    /* the loader lists every object it would map, transitively, and stops */
    bkf_cli_options o = {.env = (const char *const[]){"LD_TRACE_LOADED_OBJECTS=1", NULL}};
    bkf_cli_result r = bkf_cli_run(BKF_CLI_ARGS("--version"), &o);
    CHECK_MSG(r.code == 0 && strstr(r.out, "libgsl"), "no loader trace: %s%s", r.out, r.err);
    const char *banned[] = {"libhdf5",  "libcurl",   "libgnutls",   "libkrb5",    "libldap",
                            "liblapack", "libarpack", "libblas",   "libgfortran", "libquadmath"};
    for (size_t i = 0; i < sizeof banned / sizeof banned[0]; i++)
        CHECK_MSG(!strstr(r.out, banned[i]), "bkfront loads %s at start:\n%s", banned[i], r.out);
    bkf_cli_result_free(&r);
}

/* An empty file under `soname` in a new folder, and LD_LIBRARY_PATH=that
 * folder in `env`: the loader finds it first and refuses it. */
static void unloadable(char *dir, const char *soname, char *env, size_t env_size)
{
    CHECK(mkdtemp(dir) != NULL);
    char fake[160];
    snprintf(fake, sizeof fake, "%s/%s", dir, soname);
    FILE *f = fopen(fake, "w");
    CHECK(f != NULL);
    fclose(f);
    snprintf(env, env_size, "LD_LIBRARY_PATH=%s", dir);
}

static void remove_dir(const char *dir)
{
    char cmd[200];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    CHECK(system(cmd) == 0);
}

/* `bkfront --version` runs as `o` says (it needs none of the lazily
 * loaded libraries). */
static void version_runs(const bkf_cli_options *o)
{
    bkf_cli_result r = bkf_cli_run(BKF_CLI_ARGS("--version"), o);
    CHECK_MSG(r.code == 0 && strncmp(r.out, "bkfront ", 8) == 0, "--version: %d %s", r.code,
              r.err);
    bkf_cli_result_free(&r);
}

/* An unloadable HDF5 (an empty file under its soname, found first through
 * LD_LIBRARY_PATH): every other command runs, and an HDF5 spacetime fails
 * with exit 1, one line naming the library, and no file. */
TEST(cli_hdf5_missing_fails_only_the_hdf5_write)
{
    char dir[] = "/tmp/bkf_noh5_XXXXXX", env[160];
    unloadable(dir, BKF_HDF5_SONAME, env, sizeof env);
    bkf_cli_options o = {.dir = dir, .env = (const char *const[]){env, NULL}};
    version_runs(&o);
    bkf_cli_result r = bkf_cli_run(BKF_CLI_ARGS("simulate", "--N", "64", "--S", "16", "--tmax", "1",
                                 "--frames", "2", "--no-progress", "--spacetime", "st.h5",
                                 "--out", "diag.tsv"), &o);
    CHECK_MSG(r.code == 1, "exit %d, stderr %s", r.code, r.err);
    CHECK_MSG(strstr(r.err, "HDF5 output needs the HDF5 library") && strstr(r.err, BKF_HDF5_SONAME)
              && bkf_count_lines(r.err) == 1, "stderr: %s", r.err);
    char path[160];
    snprintf(path, sizeof path, "%s/st.h5", dir);
    CHECK_MSG(access(path, F_OK) != 0, "st.h5 was written");
    snprintf(path, sizeof path, "%s/diag.tsv", dir);
    CHECK_MSG(access(path, F_OK) != 0, "diag.tsv was written by a failed run");
    /* the text format needs no HDF5 */
    bkf_cli_result_free(&r);
    r = bkf_cli_run(BKF_CLI_ARGS("simulate", "--N", "64", "--S", "16", "--tmax", "1",
                                 "--frames", "2", "--no-progress", "--spacetime", "st.dat",
                                 "--out", "diag.tsv"), &o);
    CHECK_MSG(r.code == 0, "text spacetime: exit %d, %s", r.code, r.err);
    bkf_cli_result_free(&r);
    remove_dir(dir);
}

/* An unloadable LAPACKE: --version runs; a spectrum that needs Hill's
 * matrices (gamma 0.5: small mu) fails with exit 1 and one line that names
 * the library, no output. */
TEST(cli_lapacke_missing_fails_only_what_needs_it)
{
    char dir[] = "/tmp/bkf_nolapacke_XXXXXX", env[160];
    unloadable(dir, BKF_LAPACKE_SONAME, env, sizeof env);
    bkf_cli_options o = {.dir = dir, .env = (const char *const[]){env, NULL}};
    version_runs(&o);
    bkf_cli_result r = bkf_cli_run(BKF_CLI_ARGS("stability", "--n", "2", "--gamma", "0.5", "--tol", "1e-3",
                                 "--out", "spec.tsv"), &o);
    CHECK_MSG(r.code == 1, "exit %d, stderr %s", r.code, r.err);
    CHECK_MSG(strstr(r.err, BKF_LAPACKE_SONAME " does not load") &&
              strstr(r.err, "apt-get install liblapacke") && bkf_count_lines(r.err) == 1,
              "stderr: %s", r.err);
    char path[160];
    snprintf(path, sizeof path, "%s/spec.tsv", dir);
    CHECK_MSG(access(path, F_OK) != 0, "spec.tsv was written by a failed run");
    bkf_cli_result_free(&r);
    remove_dir(dir);
}

/* An unloadable ARPACK: the orbits are solved, their multipliers are not
 * (undecided, the row says ARPACK does not load), and nothing else fails. */
TEST(cli_arpack_missing_leaves_the_multipliers_undecided)
{
    char dir[] = "/tmp/bkf_noarpack_XXXXXX", env[160];
    unloadable(dir, BKF_ARPACK_SONAME, env, sizeof env);
    bkf_cli_options o = {.dir = dir, .env = (const char *const[]){env, NULL}};
    bkf_cli_result r = bkf_cli_run(BKF_CLI_ARGS("orbit", "--N", "72", "--max-points", "4",
                                                "--no-progress", "--tol", "1e-4"), &o);
    CHECK_MSG(r.code == 0, "exit %d, stderr %s", r.code, r.err);
    CHECK_MSG(strstr(r.out, "\torbit\t") && strstr(r.out, "\tundecided\t") &&
              strstr(r.out, "multipliers need ARPACK: " BKF_ARPACK_SONAME " does not load") &&
              !strstr(r.out, "\tstable\t") && !strstr(r.out, "\tunstable\t"),
              "out: %s", r.out);
    bkf_cli_result_free(&r);
    remove_dir(dir);
}

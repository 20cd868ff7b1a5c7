/* Nothing written where it must not be, nothing lost (issue 32), through the
 * built CLI as a hostile or careless user would meet it:
 *   - a link planted where an output goes (to a file, a folder, nowhere) is
 *     never written through, by any writer;
 *   - one file given to two outputs of one command is refused;
 *   - a file size limit (ulimit -f) or a full disk is an error that leaves
 *     no temporary and no truncated file, figures included;
 *   - SIGTERM to `bkfront run` while gnuplot draws stops gnuplot and
 *     commits nothing;
 *   - one writer of a sweep table at a time; --merge refuses two different
 *     rows of one point;
 *   - scenes: a figure's text reaches gnuplot as written, width and height
 *     have caps, a UTF-8 byte order mark is accepted. */
#define _DEFAULT_SOURCE /* usleep */
#define _POSIX_C_SOURCE 200809L
#include "harness.h"
#include "cli_support.h"

#include <dirent.h>
#include <errno.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#ifndef BKF_SOURCE_DIR
#define BKF_SOURCE_DIR "."
#endif
#define PLOTS BKF_SOURCE_DIR "/plots"

#define write_text bkf_cli_write_text

static void make_dir(char *templ)
{
    CHECK_MSG(mkdtemp(templ) != NULL, "mkdtemp: %s", strerror(errno));
}

static void remove_tree(const char *dir)
{
    char cmd[4200];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    CHECK(system(cmd) == 0);
}

/* The names in dir (not . and ..), sorted, space-separated, into buf. */
static const char *listing(const char *dir, char *buf, size_t size)
{
    char cmd[4200];
    snprintf(cmd, sizeof cmd, "ls -A '%s' | tr '\\n' ' '", dir);
    FILE *p = popen(cmd, "r");
    buf[0] = '\0';
    if (p) {
        size_t n = fread(buf, 1, size - 1, p);
        buf[n] = '\0';
        pclose(p);
    }
    return buf;
}

static int is_link(const char *path)
{
    struct stat st;
    return lstat(path, &st) == 0 && S_ISLNK(st.st_mode);
}

static int exists(const char *path)
{
    struct stat st;
    return lstat(path, &st) == 0;
}

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static const char scene_text[] = "[model]\ngamma = 2\nc = 0.3\nnu = -0.96\nS = 20\n"
                                 "[friction fr]\npoints = 11\n[figure frfig]\ndata = fr\n";

/* ------------------------------------------------------------ links */

TEST(cli_outputs_never_write_through_a_planted_link)
{
    char dir[] = "/tmp/bkf_outputs_XXXXXX";
    make_dir(dir);
    char path[4096], buf[4096];
    snprintf(path, sizeof path, "%s/out", dir);
    CHECK(mkdir(path, 0755) == 0);
    snprintf(path, sizeof path, "%s/outside", dir);
    CHECK(mkdir(path, 0755) == 0);
    snprintf(path, sizeof path, "%s/outside/folder", dir);
    CHECK(mkdir(path, 0755) == 0);
    snprintf(path, sizeof path, "%s/outside/victim", dir);
    write_text(path, "precious\n");
    snprintf(path, sizeof path, "%s/s.scene", dir);
    write_text(path, scene_text);
    /* where the link goes: a file, a folder, nowhere (it would be created) */
    const char *targets[] = {"../outside/victim", "../outside/folder", "../outside/new"};
    /* every writer: the link's name in out/, then the command (LINK stands
     * for out/NAME) */
    struct {
        const char *name;
        const char *args[16];
    } writers[] = {
        {"f.tsv", {"friction", "--out", "LINK"}},
        {"st.txt", {"simulate", "--tmax", "1", "--N", "32", "--frames", "4", "--spacetime", "LINK",
                    "--out", "out/d.tsv"}},
        {"st.h5", {"simulate", "--tmax", "1", "--N", "32", "--frames", "4", "--spacetime", "LINK"}},
        {"snap.tsv", {"simulate", "--tmax", "1", "--N", "32", "--snapshots", "LINK"}},
        {"sw.tsv", {"sweep", "--tmax", "1", "--N", "32", "--out", "LINK"}},
        {"sw.tsv", {"sweep", "--tmax", "1", "--N", "32", "--resume", "--out", "LINK"}},
        {"fields", {"sweep", "--tmax", "1", "--N", "32", "--fields", "LINK", "--out", "out/s.tsv"}},
        {"fr.tsv", {"run", "--no-figures", "--out", "out", "s.scene"}},
        {"frfig.png", {"run", "--plots", PLOTS, "--out", "out", "s.scene"}},
    };
    for (size_t w = 0; w < sizeof writers / sizeof writers[0]; w++)
        for (size_t k = 0; k < sizeof targets / sizeof targets[0]; k++) {
            char link[4096];
            snprintf(link, sizeof link, "%s/out/%s", dir, writers[w].name);
            CHECK(symlink(targets[k], link) == 0);
            const char *args[17];
            char rel[256];
            snprintf(rel, sizeof rel, "out/%s", writers[w].name);
            size_t n = 0;
            for (; writers[w].args[n]; n++)
                args[n] = strcmp(writers[w].args[n], "LINK") == 0 ? rel : writers[w].args[n];
            args[n] = NULL;
            bkf_cli_result r = bkf_cli_run(args, &(bkf_cli_options){.dir = dir});
            CHECK_MSG(r.code == 1 || r.code == 2, "%s -> %s: exit %d", rel, targets[k], r.code);
            CHECK_MSG(strstr(r.err, "symbolic link") || strstr(r.out, "symbolic link"),
                      "%s -> %s: %s%s", rel, targets[k], r.out, r.err);
            bkf_cli_result_free(&r);
            CHECK_MSG(is_link(link), "%s was replaced", rel);
            snprintf(path, sizeof path, "%s/outside/victim", dir);
            char *v = bkf_cli_read_file(path);
            CHECK_MSG(v && strcmp(v, "precious\n") == 0, "%s -> %s: the victim changed", rel,
                      targets[k]);
            free(v);
            snprintf(path, sizeof path, "%s/outside", dir);
            CHECK_MSG(strcmp(listing(path, buf, sizeof buf), "folder victim ") == 0,
                      "%s -> %s: outside holds %s", rel, targets[k], buf);
            snprintf(path, sizeof path, "%s/outside/folder", dir);
            CHECK_MSG(strcmp(listing(path, buf, sizeof buf), "") == 0,
                      "%s -> %s: the folder holds %s", rel, targets[k], buf);
            unlink(link);
            /* what a refused run may leave: the other outputs of a scene */
            snprintf(path, sizeof path, "%s/out", dir);
            listing(path, buf, sizeof buf);
            CHECK_MSG(!strstr(buf, ".tmp."), "%s: a temporary was left: %s", rel, buf);
            char cmd[4200];
            snprintf(cmd, sizeof cmd, "rm -rf '%s'/out/* '%s'/out/.[!.]*", dir, dir);
            CHECK(system(cmd) == 0);
        }
    remove_tree(dir);
}

/* ------------------------------------------------------ two outputs */

TEST(cli_outputs_refuse_one_file_for_two_outputs)
{
    char dir[] = "/tmp/bkf_outputs_XXXXXX";
    make_dir(dir);
    char path[4096], buf[4096];
    snprintf(path, sizeof path, "%s/sub", dir);
    CHECK(mkdir(path, 0755) == 0);
    snprintf(path, sizeof path, "%s/old.tsv", dir);
    write_text(path, "old\n");
    char hard[4096];
    snprintf(hard, sizeof hard, "%s/hard.tsv", dir);
    CHECK(link(path, hard) == 0);
    const char *cases[][4] = {
        {"--snapshots", "x.tsv", "--out", "x.tsv"},
        {"--snapshots", "sub/../x.tsv", "--out", "./x.tsv"},
        {"--spacetime", "x.txt", "--snapshots", "./x.txt"},
        {"--snapshots", "hard.tsv", "--out", "old.tsv"},
        {"--spacetime", "old.tsv", "--out", "hard.tsv"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        bkf_cli_result r =
            bkf_cli_run(BKF_CLI_ARGS("simulate", "--tmax", "1", "--N", "32", "--frames", "4",
                                     cases[i][0], cases[i][1], cases[i][2], cases[i][3]),
                        &(bkf_cli_options){.dir = dir});
        CHECK_MSG(r.code == 2 && strstr(r.err, "another output") && r.out[0] == '\0',
                  "%s %s %s %s: exit %d, %s", cases[i][0], cases[i][1], cases[i][2], cases[i][3],
                  r.code, r.err);
        bkf_cli_result_free(&r);
        CHECK_MSG(strcmp(listing(dir, buf, sizeof buf), "hard.tsv old.tsv sub ") == 0,
                  "%s %s: left %s", cases[i][1], cases[i][3], buf);
        char *v = bkf_cli_read_file(path);
        CHECK(v && strcmp(v, "old\n") == 0);
        free(v);
    }
    /* distinct files are fine */
    bkf_cli_result r = bkf_cli_run(BKF_CLI_ARGS("simulate", "--tmax", "1", "--N", "32",
                                                "--frames", "4", "--snapshots", "a.tsv", "--out",
                                                "b.tsv"),
                                   &(bkf_cli_options){.dir = dir});
    CHECK_MSG(r.code == 0, "%s", r.err);
    bkf_cli_result_free(&r);
    remove_tree(dir);
}

/* --------------------------------------------------- full disk, ulimit */

/* Under `ulimit -f` a write beyond the limit fails (SIGXFSZ is ignored):
 * exit 1 with one line, never death by SIGXFSZ, no temporary, no file. */
TEST(cli_outputs_file_size_limit_leaves_nothing)
{
    char dir[] = "/tmp/bkf_outputs_XXXXXX";
    make_dir(dir);
    char buf[4096];
    const char *runs[][12] = {
        {"simulate", "--tmax", "5", "--N", "64", "--frames", "200", "--spacetime", "st.txt",
         "--out", "d.tsv"},
        {"simulate", "--tmax", "5", "--N", "64", "--frames", "200", "--spacetime", "st.h5"},
        {"simulate", "--tmax", "5", "--N", "256", "--snapshots", "sn.tsv", "--snapshot-count",
         "50", "--out", "d.tsv"},
        {"friction", "--points", "100000", "--out", "f.tsv"},
        {"friction", "--points", "100000", "--format", "json", "--out", "f.json"},
    };
    for (size_t i = 0; i < sizeof runs / sizeof runs[0]; i++) {
        const char *args[13];
        size_t n = 0;
        for (; n < 12 && runs[i][n]; n++) args[n] = runs[i][n];
        args[n] = NULL;
        bkf_cli_result r =
            bkf_cli_run(args, &(bkf_cli_options){.dir = dir, .file_limit = 20480});
        CHECK_MSG(r.code == 1 && r.signal == 0, "%s %s: exit %d, signal %d", runs[i][0],
                  runs[i][8] ? runs[i][8] : "", r.code, r.signal);
        CHECK_MSG(bkf_count_lines(r.err) == 1, "%s", r.err);
        bkf_cli_result_free(&r);
        CHECK_MSG(strcmp(listing(dir, buf, sizeof buf), "") == 0, "run %zu left %s", i, buf);
    }
    remove_tree(dir);
}

/* A figure gnuplot could not write whole (it exits 0 all the same) fails
 * its step; the scene's data stay, no image and no temporary do. */
TEST(cli_outputs_truncated_figure_is_not_committed)
{
    char dir[] = "/tmp/bkf_outputs_XXXXXX";
    make_dir(dir);
    char path[4096], buf[4096];
    const char *formats[] = {"png", "pdf", "svg"};
    for (int f = 0; f < 3; f++) {
        char scene[1024];
        snprintf(scene, sizeof scene, "%swidth = 3000\nheight = 2000\nformats = %s\n",
                 scene_text, formats[f]);
        snprintf(path, sizeof path, "%s/s.scene", dir);
        write_text(path, scene);
        bkf_cli_result r =
            bkf_cli_run(BKF_CLI_ARGS("run", "--plots", PLOTS, "--out", "out", "s.scene"),
                        &(bkf_cli_options){.dir = dir, .file_limit = 12000});
        CHECK_MSG(r.code == 1 && r.signal == 0, "%s: exit %d, signal %d: %s", formats[f],
                  r.code, r.signal, r.err);
        CHECK_MSG(strstr(r.out, "not whole"), "%s: %s", formats[f], r.out);
        bkf_cli_result_free(&r);
        snprintf(path, sizeof path, "%s/out", dir);
        CHECK_MSG(strcmp(listing(path, buf, sizeof buf), "fr.tsv ") == 0, "%s: out holds %s",
                  formats[f], buf);
        snprintf(path, sizeof path, "%s/out", dir);
        remove_tree(path);
    }
    remove_tree(dir);
}

/* ------------------------------------------------ SIGTERM and gnuplot */

TEST(cli_outputs_sigterm_stops_gnuplot_and_commits_nothing)
{
    char dir[] = "/tmp/bkf_outputs_XXXXXX";
    make_dir(dir);
    char path[4096], buf[4096];
    char scene[1024];
    /* a figure gnuplot takes seconds to draw */
    snprintf(scene, sizeof scene, "%swidth = 8000\nheight = 6000\n", scene_text);
    snprintf(path, sizeof path, "%s/s.scene", dir);
    write_text(path, scene);
    pid_t pid = bkf_cli_spawn(BKF_CLI_ARGS("run", "--plots", PLOTS, "--out", "out", "s.scene"),
                              &(bkf_cli_options){.dir = dir}, NULL, NULL);
    /* the data written: gnuplot is drawing */
    snprintf(path, sizeof path, "%s/out/fr.tsv", dir);
    for (int i = 0; i < 2000 && !exists(path); i++) usleep(5000);
    CHECK(exists(path));
    usleep(300000);
    double t0 = now();
    CHECK(kill(pid, SIGTERM) == 0);
    int st = 0;
    CHECK(waitpid(pid, &st, 0) == pid);
    double dt = now() - t0;
    CHECK_MSG(WIFEXITED(st) && WEXITSTATUS(st) == 143, "status %#x", st);
    CHECK_MSG(dt < 2.0, "bkfront took %.2f s to stop", dt);
    snprintf(path, sizeof path, "%s/out", dir);
    CHECK_MSG(strcmp(listing(path, buf, sizeof buf), "fr.tsv ") == 0, "out holds %s", buf);
    remove_tree(dir);
}

/* ------------------------------------------------------------- sweep */

static int data_rows(const char *tsv, int *points, int max)
{
    int n = 0;
    for (const char *p = tsv; p && *p;) {
        const char *nl = strchr(p, '\n');
        if (*p != '#' && strncmp(p, "point\t", 6) != 0 && *p != '\n') {
            int k = atoi(p);
            if (k >= 0 && k < max) points[k]++;
            n++;
        }
        p = nl ? nl + 1 : NULL;
    }
    return n;
}

TEST(cli_outputs_sweep_table_has_one_writer)
{
    char dir[] = "/tmp/bkf_outputs_XXXXXX";
    make_dir(dir);
    char path[4096];
#define SWEEP "sweep", "--x", "S=10:30:6", "--seeds", "1:6:6", "--tmax", "50", "--N", "64", \
              "--no-progress", "--threads", "1"
    pid_t first = bkf_cli_spawn(BKF_CLI_ARGS(SWEEP, "--out", "r.tsv"),
                                &(bkf_cli_options){.dir = dir}, NULL, NULL);
    snprintf(path, sizeof path, "%s/r.tsv", dir);
    for (int i = 0; i < 2000 && !exists(path); i++) usleep(5000);
    for (int k = 0; k < 2; k++) {
        bkf_cli_result r =
            k ? bkf_cli_run(BKF_CLI_ARGS(SWEEP, "--resume", "--out", "r.tsv"),
                            &(bkf_cli_options){.dir = dir})
              : bkf_cli_run(BKF_CLI_ARGS(SWEEP, "--out", "r.tsv"), &(bkf_cli_options){.dir = dir});
        CHECK_MSG(r.code == 2 && strstr(r.err, "being written by another run"),
                  "%s: exit %d: %s", k ? "--resume" : "", r.code, r.err);
        bkf_cli_result_free(&r);
    }
    int st = 0;
    CHECK(waitpid(first, &st, 0) == first);
    CHECK_MSG(WIFEXITED(st) && WEXITSTATUS(st) == 0, "the first sweep: status %#x", st);
    char *t = bkf_cli_read_file(path);
    int seen[36] = {0};
    CHECK_MSG(data_rows(t, seen, 36) == 36, "%s", t);
    for (int k = 0; k < 36; k++) CHECK_MSG(seen[k] == 1, "point %d: %d rows", k, seen[k]);
    free(t);
    remove_tree(dir);
#undef SWEEP
}

TEST(cli_outputs_merge_refuses_two_rows_of_one_point)
{
    char dir[] = "/tmp/bkf_outputs_XXXXXX";
    make_dir(dir);
    char path[4096];
#define SWEEP "sweep", "--x", "S=10:30:4", "--tmax", "2", "--N", "32", "--no-progress"
    for (int task = 0; task < 2; task++) {
        bkf_cli_result r = bkf_cli_run(BKF_CLI_ARGS(SWEEP, "--task", task ? "1" : "0", "--of",
                                                    "2", "--out", task ? "b.tsv" : "a.tsv"),
                                       &(bkf_cli_options){.dir = dir});
        CHECK_MSG(r.code == 0, "%s", r.err);
        bkf_cli_result_free(&r);
    }
    /* the same point twice, the same bytes: one row */
    bkf_cli_result r = bkf_cli_run(BKF_CLI_ARGS("sweep", "--merge", "a.tsv,b.tsv,a.tsv", "--out",
                                                "m.tsv"),
                                   &(bkf_cli_options){.dir = dir});
    CHECK_MSG(r.code == 0, "%s", r.err);
    bkf_cli_result_free(&r);
    /* row 0 of a.tsv, its status "ok" last */
    snprintf(path, sizeof path, "%s/a.tsv", dir);
    char *a = bkf_cli_read_file(path);
    CHECK(a);
    char *row = strstr(a, "\n0\t");
    CHECK(row);
    char *end = strchr(row + 1, '\n');
    CHECK(end && end - row > 3 && strncmp(end - 2, "ok", 2) == 0);
    /* d.tsv: a.tsv with row 0 again, the same bytes; e.tsv: with row 0
     * again, changed; c.tsv: a.tsv with row 0 changed */
    size_t rlen = (size_t)(end - row); /* "0\t...ok" without its newline */
    char *d = malloc(strlen(a) + rlen + 2);
    CHECK(d);
    sprintf(d, "%s%.*s\n", a, (int)rlen - 1, row + 1);
    snprintf(path, sizeof path, "%s/d.tsv", dir);
    write_text(path, d);
    memcpy(d + strlen(d) - 3, "no", 2);
    snprintf(path, sizeof path, "%s/e.tsv", dir);
    write_text(path, d);
    free(d);
    memcpy(end - 2, "no", 2);
    snprintf(path, sizeof path, "%s/c.tsv", dir);
    write_text(path, a);
    free(a);
    r = bkf_cli_run(BKF_CLI_ARGS("sweep", "--merge", "d.tsv,b.tsv", "--out", "m3.tsv"),
                    &(bkf_cli_options){.dir = dir});
    CHECK_MSG(r.code == 0, "%s", r.err);
    bkf_cli_result_free(&r);
    r = bkf_cli_run(BKF_CLI_ARGS("sweep", "--merge", "e.tsv,b.tsv", "--out", "m3.tsv"),
                    &(bkf_cli_options){.dir = dir});
    CHECK_MSG(r.code == 2 && strstr(r.err, "point 0 ") && strstr(r.err, "e.tsv"), "exit %d: %s",
              r.code, r.err);
    bkf_cli_result_free(&r);
    r = bkf_cli_run(BKF_CLI_ARGS("sweep", "--merge", "a.tsv,b.tsv,c.tsv", "--out", "m2.tsv"),
                    &(bkf_cli_options){.dir = dir});
    CHECK_MSG(r.code == 2 && strstr(r.err, "point 0 ") && strstr(r.err, "a.tsv") &&
                  strstr(r.err, "c.tsv"),
              "exit %d: %s", r.code, r.err);
    bkf_cli_result_free(&r);
    snprintf(path, sizeof path, "%s/m2.tsv", dir);
    CHECK(!exists(path));
    remove_tree(dir);
#undef SWEEP
}

/* ------------------------------------------------------------ scenes */

TEST(cli_outputs_scene_text_caps_and_bom)
{
    char dir[] = "/tmp/bkf_outputs_XXXXXX";
    make_dir(dir);
    char path[4096], scene[2048];
    /* a title starting with a quote, and every character gnuplot quotes */
    snprintf(scene, sizeof scene, "%stitle = 'It''s \"x\" \\back\\ $HOME `id`\n", scene_text);
    snprintf(path, sizeof path, "%s/s.scene", dir);
    write_text(path, scene);
    bkf_cli_result r = bkf_cli_run(BKF_CLI_ARGS("run", "--plots", PLOTS, "--out", "out",
                                                "s.scene"),
                                   &(bkf_cli_options){.dir = dir});
    CHECK_MSG(r.code == 0, "%s%s", r.out, r.err);
    bkf_cli_result_free(&r);
    snprintf(path, sizeof path, "%s/out/frfig.png", dir);
    CHECK(exists(path));
    /* caps: gnuplot would need gigabytes */
    const char *sizes[] = {"width = 30000\n", "height = 8001\n"};
    for (int i = 0; i < 2; i++) {
        snprintf(scene, sizeof scene, "%s%s", scene_text, sizes[i]);
        snprintf(path, sizeof path, "%s/s.scene", dir);
        write_text(path, scene);
        r = bkf_cli_run(BKF_CLI_ARGS("run", "--plan", "s.scene"), &(bkf_cli_options){.dir = dir});
        CHECK_MSG(r.code == 2 && strstr(r.err, "s.scene:10") && strstr(r.err, "8000"), "%s",
                  r.err);
        bkf_cli_result_free(&r);
    }
    /* a byte order mark */
    snprintf(scene, sizeof scene, "\xEF\xBB\xBF%s", scene_text);
    write_text(path, scene);
    r = bkf_cli_run(BKF_CLI_ARGS("run", "--no-figures", "--out", "bom", "s.scene"),
                    &(bkf_cli_options){.dir = dir});
    CHECK_MSG(r.code == 0, "%s", r.err);
    bkf_cli_result_free(&r);
    snprintf(path, sizeof path, "%s/bom/fr.tsv", dir);
    CHECK(exists(path));
    remove_tree(dir);
}

/* bkfront sweep: the table is the same bit for bit however the points are
 * scheduled (1 or 2 threads, tasks merged, resumed after a crash, an MPI
 * farm), its rows agree with bkfront simulate and with the speed-selection
 * theory, and bad input is refused before any run. */
#define _POSIX_C_SOURCE 200809L
#include "harness.h"
#include "cli_support.h"
#include "bkfront/simulate.h"
#include "bkfront/sweep.h"

#include <dirent.h>
#include <math.h>
#include <sys/stat.h>
#include <hdf5.h>
#include <hdf5_hl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <signal.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

/* Two seeded trains (n = 4, 5 at the paper's parameters) and two noisy
 * starts at two nu: six short runs of a few tenths of a second. */
#define GRID "--x", "nu=-0.96,-0.94", "--inits", "front:n=4;uniform:amp=0.01", "--seeds", "1,2", \
             "--tmax", "30", "--N", "256", "--no-progress"
#define POINTS 8

static char *path_in(const char *dir, const char *name)
{
    char *p = malloc(strlen(dir) + strlen(name) + 2);
    sprintf(p, "%s/%s", dir, name);
    return p;
}

static char *run_ok(const char *const *args)
{
    bkf_cli_result r = bkf_cli_run(args, NULL);
    int ok = r.code == 0 && r.err[0] == '\0' && r.out[0] == '\0';
    if (!ok) bkf_test_note("exit %d, stderr: %s", r.code, r.err);
    bkf_cli_result_free(&r);
    return ok ? (char *)1 : NULL;
}

static char *serial_table(const char *dir)
{
    char *one = path_in(dir, "serial.tsv");
    if (!run_ok(BKF_CLI_ARGS("sweep", GRID, "--threads", "1", "--out", one))) {
        free(one);
        return NULL;
    }
    char *t = bkf_cli_read_file(one);
    free(one);
    return t;
}

TEST(cli_sweep_threads_give_the_same_table_and_the_predicted_speed)
{
    char dir[] = "/tmp/bkf_sweep_XXXXXX";
    CHECK(mkdtemp(dir));
    char *serial = serial_table(dir);
    CHECK(serial);
    char *two = path_in(dir, "two.tsv");
    CHECK(run_ok(BKF_CLI_ARGS("sweep", GRID, "--threads", "2", "--out", two)));
    char *parallel = bkf_cli_read_file(two);
    CHECK(parallel);
    CHECK_MSG(strcmp(serial, parallel) == 0, "1 and 2 threads differ:\n%s\n---\n%s", serial,
              parallel);
    /* rows in point order, one per point */
    for (int i = 0; i < POINTS; i++) {
        double p;
        CHECK(bkf_tsv_cell(serial, i, "point", &p, NULL, 0) && p == i);
    }
    CHECK(!bkf_tsv_cell(serial, POINTS, "point", NULL, (char[8]){0}, 8));
    /* point 0 (n = 4, nu -0.96): the speed the selection condition gives,
     * bkfront speeds' v_4 = 0.48545916040167414 (README) */
    char regime[64];
    double v;
    CHECK(bkf_tsv_cell(serial, 0, "regime", NULL, regime, sizeof regime));
    CHECK_MSG(strcmp(regime, "propagating_fronts") == 0, "regime %s", regime);
    CHECK(bkf_tsv_cell(serial, 0, "speed", &v, NULL, 0));
    CHECK_CLOSE(-v, 0.48545916040167414, 1e-4, 0);
    /* point 7 (noise, nu -0.94, seed 2) is bkfront simulate's run */
    int code;
    char *sim = bkf_cli_stdout("simulate --nu -0.94 --init uniform:amp=0.01 --seed 2 --tmax 30 "
                               "--N 256 --format json --no-progress",
                               &code);
    CHECK(sim && code == 0);
    char want[96];
    CHECK(bkf_tsv_cell(serial, 7, "regime", NULL, regime, sizeof regime));
    snprintf(want, sizeof want, "\"regime\": \"%s\"", regime);
    CHECK_MSG(strstr(sim, want), "simulate says otherwise than %s", want);
    double period;
    char text[64];
    const char *same[] = {"global_period", "speed", "speed_err"};
    for (int k = 0; k < 3; k++) {
        CHECK(bkf_tsv_cell(serial, 7, same[k], &period, text, sizeof text));
        snprintf(want, sizeof want, "\"%s\": %s", same[k], text);
        CHECK_MSG(strstr(sim, want), "simulate's %s is not %s", same[k], text);
    }
    free(sim);
    free(two);
    free(parallel);
    free(serial);
}

TEST(cli_sweep_tasks_merged_and_resumed_equal_the_serial_table)
{
    char dir[] = "/tmp/bkf_sweep_XXXXXX";
    CHECK(mkdtemp(dir));
    char *serial = serial_table(dir);
    CHECK(serial);
    /* three tasks of a job array, then the merge */
    char *part[3], list[1024] = "";
    for (int k = 0; k < 3; k++) {
        char name[32], task[8];
        snprintf(name, sizeof name, "part%d.tsv", k);
        snprintf(task, sizeof task, "%d", k);
        part[k] = path_in(dir, name);
        CHECK(run_ok(BKF_CLI_ARGS("sweep", GRID, "--task", task, "--of", "3", "--out", part[k])));
        strcat(list, k ? "," : "");
        strcat(list, part[k]);
    }
    char *merged = path_in(dir, "merged.tsv");
    /* two of three tasks: the merge says what is missing */
    char two_parts[600];
    snprintf(two_parts, sizeof two_parts, "%s,%s", part[0], part[2]);
    bkf_cli_result r = BKF_CLI("sweep", "--merge", two_parts, "--out", merged);
    CHECK_MSG(r.code == 1 && strstr(r.err, "3 points are in none"), "exit %d: %s", r.code, r.err);
    bkf_cli_result_free(&r);
    CHECK(run_ok(BKF_CLI_ARGS("sweep", "--merge", list, "--out", merged)));
    char *m = bkf_cli_read_file(merged);
    CHECK(m && strcmp(m, serial) == 0);
    free(m);

    /* a crash: the last row cut in the middle, another row lost */
    char *crashed = path_in(dir, "crashed.tsv");
    size_t len = strlen(serial);
    char *cut = strdup(serial);
    char *third = cut + len - 1;
    for (int nl = 0; third > cut && nl < 3; third--) nl += *third == '\n';
    third[2] = '\0'; /* drop the last two rows, leave two bytes of the third-to-last */
    FILE *f = fopen(crashed, "w");
    CHECK(f && fputs(cut, f) >= 0 && fclose(f) == 0);
    CHECK(run_ok(BKF_CLI_ARGS("sweep", GRID, "--resume", "--out", crashed)));
    char *resumed = bkf_cli_read_file(crashed);
    CHECK_MSG(resumed && strcmp(resumed, serial) == 0, "resumed:\n%s", resumed);
    free(resumed);

    /* --resume on the table of another sweep: refused, the table kept */
    r = BKF_CLI("sweep", "--x", "nu=-0.96,-0.95", "--inits", "front:n=4;uniform:amp=0.01",
                "--seeds", "1,2", "--tmax", "30", "--N", "256", "--resume", "--out", crashed);
    CHECK_MSG(r.code == 2 && strstr(r.err, "another sweep") && bkf_count_lines(r.err) == 1,
              "exit %d: %s", r.code, r.err);
    bkf_cli_result_free(&r);
    resumed = bkf_cli_read_file(crashed);
    CHECK(resumed && strcmp(resumed, serial) == 0);
    free(resumed);
    for (int k = 0; k < 3; k++) free(part[k]);
    free(cut);
    free(crashed);
    free(merged);
    free(serial);
}

TEST(cli_sweep_refuses_bad_input_anywhere_in_the_grid)
{
    char dir[] = "/tmp/bkf_sweep_XXXXXX";
    CHECK(mkdtemp(dir));
    char *out = path_in(dir, "never.tsv");
    /* the last gamma is out of range: nothing runs, nothing is written */
    bkf_cli_expect_bad_input(BKF_CLI("sweep", "--x", "gamma=2:-1:4", "--out", out), "sweep",
                             "gamma", "a gamma <= 0 in the grid");
    bkf_cli_expect_bad_input(BKF_CLI("sweep", "--x", "colour=1,2", "--out", out), "sweep", "x",
                             "an unknown parameter");
    bkf_cli_expect_bad_input(BKF_CLI("sweep", "--x", "nu=-0.9", "--inits", "front:n=4;wave",
                                     "--out", out),
                             "sweep", "init", "an unknown initial state");
    bkf_cli_expect_bad_input(BKF_CLI("sweep", "--task", "3", "--of", "3", "--out", out), "sweep",
                             "task", "a task index past --of");
    bkf_cli_expect_bad_input(BKF_CLI("sweep", "--x", "nu=-0.9"), "sweep", "out",
                             "no --out");
    /* one run's data files are refused by name; every other simulate key
     * is a sweep key (none dropped from the table) */
    size_t nkeys = 0, expected = bkf_sweep_noptions;
    const bkf_option *keys = bkf_sweep_keys(&nkeys);
    for (size_t i = 0; i < bkf_simulate_noptions; i++) {
        const char *name = bkf_simulate_options[i].name;
        int in_keys = 0;
        for (size_t k = 0; k < nkeys; k++) in_keys |= strcmp(keys[k].name, name) == 0;
        if (bkf_simulate_options[i].flags & BKF_OPT_RUN_FILE) {
            CHECK_MSG(!in_keys, "the run file key %s is a sweep key", name);
            char flag[64];
            snprintf(flag, sizeof flag, "--%s", name);
            bkf_cli_expect_bad_input(BKF_CLI("sweep", flag, "1", "--out", out), "sweep", name,
                                     "one run's data file");
        } else {
            CHECK_MSG(in_keys, "the simulate key %s is missing from the sweep's keys", name);
            expected++;
        }
    }
    CHECK_MSG(nkeys == expected, "%zu sweep keys, expected %zu", nkeys, expected);
    CHECK_MSG(access(out, F_OK) != 0, "a refused sweep wrote %s", out);
    free(out);
}

/* The MPI build and mpirun, kept on this machine (shared memory and
 * loopback only); NULL (the test skipped) when either is missing. */
static const char *mpi_cli(void)
{
    const char *cli = BKF_SOURCE_DIR "/build/mpi/bkfront";
    if (access(cli, X_OK) == 0 && access("/usr/bin/mpirun", X_OK) == 0) return cli;
    bkf_test_note("skipped: %s or mpirun missing (make test-mpi builds and runs it)", cli);
    return NULL;
}

#define MPIRUN "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 exec mpirun " \
               "--oversubscribe --mca btl self,vader --mca oob_tcp_if_include lo "       \
               "--mca btl_tcp_if_include lo"

/* `mpirun -np NP bkfront sweep ARGS` in a shell, its output to log: the
 * shell's pid (the shell becomes mpirun), or the exit status when wait. */
static int mpi_sweep(int np, const char *args, const char *log, int wait)
{
    char cmd[4096];
    snprintf(cmd, sizeof cmd, MPIRUN " -np %d %s sweep %s >%s 2>&1", np, mpi_cli(), args, log);
    if (wait) return system(cmd);
    pid_t pid = fork();
    if (pid == 0) {
        setpgid(0, 0); /* a job of its own, as a terminal would start it */
        execl("/bin/sh", "sh", "-c", cmd, (char *)NULL);
        _exit(127);
    }
    return (int)pid;
}

#define MPI_GRID "--x nu=-0.96,-0.94 --inits 'front:n=4;uniform:amp=0.01' --seeds 1,2 " \
                 "--tmax 30 --N 256 --no-progress"

/* mpirun -np 1 (rank 0 alone: the manager's own compute thread does every
 * point), -np 2, -np 3 and -np 2 with two threads a rank (hybrid) give
 * the serial table, and the fields are the serial run's byte for byte. */
TEST(cli_sweep_mpi_farm_equals_serial)
{
    if (!mpi_cli()) return;
    char dir[] = "/tmp/bkf_sweep_XXXXXX";
    CHECK(mkdtemp(dir));
    /* the table and fields of a serial run, to be the MPI workers' byte
     * for byte (one run: -np 1 and 2 write no fields and must give its
     * table, so the fields do not change it; a second serial run without
     * them cost 0.9 s of CPU) */
    char *serial_fields = path_in(dir, "serial_fields"), *mpi_fields = path_in(dir, "mpi_fields");
    char *fields_table = path_in(dir, "fields.tsv"), *log = path_in(dir, "mpi.log");
    CHECK(mkdir(serial_fields, 0755) == 0 && mkdir(mpi_fields, 0755) == 0);
    CHECK(run_ok(BKF_CLI_ARGS("sweep", GRID, "--threads", "1", "--fields", serial_fields,
                              "--out", fields_table)));
    char *serial = bkf_cli_read_file(fields_table);
    CHECK(serial);
    const struct {
        int np;
        const char *extra;
    } runs[] = {{1, ""}, {2, ""}, {3, "--fields"}, {2, "--threads 2"}};
    for (size_t k = 0; k < sizeof runs / sizeof *runs; k++) {
        char *out = path_in(dir, "mpi.tsv");
        char args[2048];
        snprintf(args, sizeof args, MPI_GRID " %s%s%s --out %s", runs[k].extra,
                 strcmp(runs[k].extra, "--fields") == 0 ? " " : "",
                 strcmp(runs[k].extra, "--fields") == 0 ? mpi_fields : "", out);
        int rc = mpi_sweep(runs[k].np, args, log, 1);
        char *text = bkf_cli_read_file(log);
        CHECK_MSG(rc == 0, "mpirun -np %d %s: status %d: %s", runs[k].np, runs[k].extra, rc,
                  text ? text : "");
        free(text);
        char *t = bkf_cli_read_file(out);
        CHECK_MSG(t && strcmp(t, serial) == 0, "-np %d %s differs from serial:\n%s", runs[k].np,
                  runs[k].extra, t);
        free(t);
        unlink(out);
        free(out);
    }
    /* every point's field, written by the worker that computed it */
    for (int i = 0; i < POINTS; i++) {
        char name[32];
        snprintf(name, sizeof name, "point_%d.h5", i);
        char *a = path_in(serial_fields, name), *b = path_in(mpi_fields, name);
        char cmd[2200];
        snprintf(cmd, sizeof cmd, "cmp -s %s %s", a, b);
        CHECK_MSG(system(cmd) == 0, "-np 3: %s is not the serial run's", b);
        free(a);
        free(b);
    }
    free(log);
    free(serial_fields);
    free(mpi_fields);
    free(fields_table);
    free(serial);
}

/* The data rows of a table (after '#' lines and the column names). */
static size_t data_rows(const char *t)
{
    size_t rows = 0;
    for (const char *p = t; p && (p = strchr(p, '\n')); p++) rows += p[1] && p[1] != '#';
    return rows ? rows - 1 : 0;
}

/* Every line of `part` is a line of `whole` (a finished row is the serial
 * run's row of its point), and part ends with a newline. */
static int rows_are_of(const char *part, const char *whole)
{
    if (!part || !*part || part[strlen(part) - 1] != '\n') return 0;
    for (const char *p = part; *p;) {
        size_t len = (size_t)(strchr(p, '\n') + 1 - p);
        int ok = 0;
        for (const char *w = whole; w && *w && !ok; w = strchr(w, '\n') ? strchr(w, '\n') + 1 : NULL)
            ok = strncmp(w, p, len) == 0;
        if (!ok) {
            bkf_test_note("not a line of the serial table: %.*s", (int)len, p);
            return 0;
        }
        p += len;
    }
    return 1;
}

/* The pids whose parent is `parent` (mpirun's ranks), at most max. */
static size_t children_of(pid_t parent, pid_t *pids, size_t max)
{
    size_t n = 0;
    DIR *d = opendir("/proc");
    for (struct dirent *e; d && n < max && (e = readdir(d));) {
        if (e->d_name[0] < '0' || e->d_name[0] > '9') continue;
        char path[300], buf[512];
        snprintf(path, sizeof path, "/proc/%s/stat", e->d_name);
        FILE *f = fopen(path, "r");
        if (!f) continue;
        size_t len = fread(buf, 1, sizeof buf - 1, f);
        fclose(f);
        buf[len] = '\0';
        /* pid (comm) state ppid: comm may hold spaces, the last ')' ends it */
        char *close = strrchr(buf, ')');
        int ppid;
        if (close && sscanf(close + 1, " %*c %d", &ppid) == 1 && ppid == parent)
            pids[n++] = (pid_t)atoi(e->d_name);
    }
    if (d) closedir(d);
    return n;
}

/* mpirun -np 2 stopped three ways, each after at least two more rows:
 * SIGTERM and SIGINT to mpirun (which sends the ranks SIGCONT, SIGTERM a
 * second later, and SIGKILL as soon as the first rank ends: rank 0, after
 * its "interrupted" line, see sweep_mpi_end), then kill -9 of mpirun and
 * every rank at once.
 * Each time the table holds only whole rows, each the serial run's row of
 * its point, and --resume under mpirun goes on from there; the last
 * resume gives the serial table, and its fields, byte for byte, with no
 * temporary left behind by the killed ranks.  tmax 100 (0.25 s of CPU a
 * point): the three stops take at most 6 of the 24 points plus what runs
 * during a poll of 10 ms; at tmax 400 the test took 42 s of CPU. */
TEST(cli_sweep_mpi_signals_and_kill_keep_rows_and_resume_completes)
{
    if (!mpi_cli()) return;
    char dir[] = "/tmp/bkf_sweep_XXXXXX";
    CHECK(mkdtemp(dir));
#define KILL_GRID "--x", "nu=-0.98:-0.82:6", "--seeds", "1:4:4", "--tmax", "100", "--N", "256", \
                  "--init", "uniform:amp=0.01", "--frames", "50", "--no-progress"
#define POINTS_KILL 24
    char *whole = path_in(dir, "whole.tsv"), *cut = path_in(dir, "cut.tsv");
    char *log = path_in(dir, "mpi.log"), *wf = path_in(dir, "serial_fields");
    char *mf = path_in(dir, "mpi_fields");
    CHECK(mkdir(wf, 0755) == 0 && mkdir(mf, 0755) == 0);
    CHECK(run_ok(BKF_CLI_ARGS("sweep", KILL_GRID, "--fields", wf, "--out", whole)));
    char *serial = bkf_cli_read_file(whole);
    CHECK(serial && data_rows(serial) == POINTS_KILL);
    char args[2048];
    snprintf(args, sizeof args,
             "--x nu=-0.98:-0.82:6 --seeds 1:4:4 --tmax 100 --N 256 --init uniform:amp=0.01 "
             "--frames 50 --no-progress --fields %s --resume --out %s",
             mf, cut);
    const int sigs[] = {SIGTERM, SIGINT, SIGKILL};
    size_t before = 0;
    for (int k = 0; k < 3; k++) {
        pid_t pid = (pid_t)mpi_sweep(2, args, log, 0);
        CHECK(pid > 0);
        /* two more rows than the last run left */
        size_t rows = 0;
        for (int i = 0; i < 3000 && rows < before + 2; i++) {
            char *t = bkf_cli_read_file(cut);
            rows = data_rows(t);
            free(t);
            nanosleep(&(struct timespec){0, 10000000}, NULL);
        }
        CHECK_MSG(rows >= before + 2 && rows < POINTS_KILL, "run %d: %zu rows before the signal", k, rows);
        if (sigs[k] == SIGKILL) {
            pid_t ranks[8];
            size_t n = children_of(pid, ranks, 8);
            CHECK_MSG(n == 2, "%zu ranks under mpirun", n);
            kill(pid, SIGKILL);
            for (size_t r = 0; r < n; r++) kill(ranks[r], SIGKILL);
        } else {
            kill(pid, sigs[k]);
        }
        int st;
        CHECK(waitpid(pid, &st, 0) == pid);
        char *t = bkf_cli_read_file(cut), *l = bkf_cli_read_file(log);
        CHECK_MSG(rows_are_of(t, serial), "run %d: the table after the signal:\n%s", k, t);
        before = data_rows(t);
        CHECK_MSG(before >= rows && before < POINTS_KILL, "run %d: %zu rows", k, before);
        if (sigs[k] != SIGKILL)
            CHECK_MSG(l && strstr(l, "interrupted (SIGTERM): every finished row is in"),
                      "run %d: %s", k, l ? l : "");
        free(l);
        free(t);
    }
    int rc = mpi_sweep(2, args, log, 1);
    CHECK_MSG(rc == 0, "the last resume: status %d", rc);
    char *t = bkf_cli_read_file(cut);
    CHECK_MSG(t && strcmp(t, serial) == 0, "resumed:\n%s", t);
    free(t);
    /* the fields: the serial run's, and nothing else (the killed ranks'
     * temporaries removed when their points were computed again) */
    size_t files = 0;
    DIR *d = opendir(mf);
    for (struct dirent *e; d && (e = readdir(d));) {
        if (strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0) continue;
        char *a = path_in(wf, e->d_name), *b = path_in(mf, e->d_name), cmd[2200];
        snprintf(cmd, sizeof cmd, "cmp -s %s %s", a, b);
        CHECK_MSG(system(cmd) == 0, "%s is not the serial run's field", e->d_name);
        files++;
        free(a);
        free(b);
    }
    if (d) closedir(d);
    CHECK_MSG(files == POINTS_KILL, "%zu files in the fields directory", files);
    free(serial);
    free(whole);
    free(cut);
    free(log);
    free(wf);
    free(mf);
}

/* SIGTERM in the middle: exit 143, one line, every row on disk whole; the
 * resumed table is the uninterrupted one.  The runs are short (tmax 30,
 * 0.06 s of CPU a point): what is checked is the signal's path, and 17
 * points, 0.5 s on two threads, are left when the first row is in (at
 * tmax 150 the test took 16 s, at tmax 50 4.1 s). */
TEST(cli_sweep_sigterm_keeps_finished_rows_and_resume_completes)
{
    char dir[] = "/tmp/bkf_sweep_XXXXXX";
    CHECK(mkdtemp(dir));
#define LONG_GRID "--x", "nu=-0.98:-0.82:9", "--seeds", "1,2", "--tmax", "30", "--N", "256", \
                  "--init", "uniform:amp=0.01", "--no-progress"
    char *whole = path_in(dir, "whole.tsv"), *cut = path_in(dir, "cut.tsv");
    char *err = path_in(dir, "err.txt");
    CHECK(run_ok(BKF_CLI_ARGS("sweep", LONG_GRID, "--threads", "1", "--out", whole)));
    pid_t pid = bkf_cli_spawn(BKF_CLI_ARGS("sweep", LONG_GRID, "--threads", "2", "--out", cut),
                              NULL, NULL, err);
    CHECK(pid > 0);
    /* wait for the head and a first row */
    for (int i = 0; i < 600; i++) {
        char *t = bkf_cli_read_file(cut);
        size_t rows = 0;
        for (char *p = t; p && (p = strchr(p, '\n')); p++) rows += p[1] && p[1] != '#';
        free(t);
        if (rows >= 2) break;
        nanosleep(&(struct timespec){0, 10000000}, NULL);
    }
    kill(pid, SIGTERM);
    int st;
    CHECK(waitpid(pid, &st, 0) == pid);
    char *e = bkf_cli_read_file(err);
    CHECK_MSG(WIFEXITED(st) && WEXITSTATUS(st) == 143 && e && strstr(e, "SIGTERM") &&
                  bkf_count_lines(e) == 1,
              "status %d: %s", st, e ? e : "");
    free(e);
    char *t = bkf_cli_read_file(cut);
    CHECK(t && t[strlen(t) - 1] == '\n');
    free(t);
    CHECK(run_ok(BKF_CLI_ARGS("sweep", LONG_GRID, "--resume", "--out", cut)));
    char *a = bkf_cli_read_file(whole), *b = bkf_cli_read_file(cut);
    CHECK(a && b && strcmp(a, b) == 0);
    free(a);
    free(b);
    free(whole);
    free(cut);
    free(err);
}

/* A scene's [sweep] is the product bkfront sweep computes: the same table,
 * byte for byte, as the command line's (threads 2 against the CLI's 1), and
 * its Floquet boundaries are bkfront floquet --diagram's. */
TEST(cli_sweep_scene_gives_the_cli_table)
{
    char dir[] = "/tmp/bkf_sweep_XXXXXX";
    CHECK(mkdtemp(dir));
    char *serial = serial_table(dir);
    CHECK(serial);
    char *scene = path_in(dir, "map.scene");
    FILE *f = fopen(scene, "w");
    CHECK(f);
    fputs("[model]\ngamma = 2\nc = 0.3\nnu = -0.96\nS = 20\n[accuracy]\nN = 256\n"
          "[sweep map]\nx = nu=-0.96,-0.94\ninits = front:n=4;uniform:amp=0.01\nseeds = 1,2\n"
          "tmax = 30\nthreads = 2\nthresholds = 2\nsearch = -0.999:-0.75\n",
          f);
    fclose(f);
    char *out = path_in(dir, "scene");
    bkf_cli_result r = bkf_cli_run(BKF_CLI_ARGS("run", "--no-figures", "--out", out, scene), NULL);
    CHECK_MSG(r.code == 0, "bkfront run: exit %d, %s", r.code, r.err);
    bkf_cli_result_free(&r);
    char *table = path_in(out, "map.tsv");
    char *got = bkf_cli_read_file(table);
    CHECK_MSG(got && strcmp(got, serial) == 0, "the scene's table differs:\n%s\n---\n%s",
              got ? got : "(none)", serial);
    char *fl = path_in(out, "map_floquet_1.tsv");
    char *diagram = bkf_cli_read_file(fl);
    int code;
    char *want = bkf_cli_stdout("floquet --diagram --gamma 2 --c 0.3 --search -0.999:-0.75 "
                                "--tol 1e-6", &code);
    CHECK(diagram && want && code == 0);
    /* the rows (after the comments, which name the output) agree */
    const char *a = diagram ? strstr(diagram, "\nnu_from") : NULL;
    const char *b = want ? strstr(want, "\nnu_from") : NULL;
    CHECK(a && b && strcmp(a, b) == 0);
    free(want);
    free(diagram);
    free(fl);
    free(got);
    free(table);
    free(out);
    free(scene);
    free(serial);
}

/* bkfront simulate's regime and front count at tmax T (json results). */
static int simulate_regime(const char *init, double tmax, char *regime, size_t size, int *fronts)
{
    char cmd[256];
    snprintf(cmd, sizeof cmd,
             "simulate --nu -0.94 --init %s --tmax %g --N 128 --format json --no-progress", init,
             tmax);
    int code;
    char *out = bkf_cli_stdout(cmd, &code);
    const char *r = out ? strstr(out, "\"regime\": \"") : NULL;
    const char *f = out ? strstr(out, "\"fronts_end\": ") : NULL;
    int ok = code == 0 && r && f;
    if (ok) {
        r += strlen("\"regime\": \"");
        snprintf(regime, size, "%.*s", (int)strcspn(r, "\""), r);
        *fronts = atoi(f + strlen("\"fronts_end\": "));
    }
    free(out);
    return ok;
}

/* --tmax-budget: each row is what bkfront simulate's runs of tmax, 2 tmax,
 * ... give under the stated rule (stop at the first two lengths whose
 * regimes, and front counts for fronts, agree and are not transient, or at
 * the budget), and the
 * default table has no settled column. */
TEST(cli_sweep_settle_mode_follows_simulate_runs_of_doubling_length)
{
    char dir[] = "/tmp/bkf_sweep_XXXXXX";
    CHECK(mkdtemp(dir));
    char *out = path_in(dir, "settle.tsv");
    const char *inits[] = {"uniform:amp=0.01", "front:n=4", "oscillation:noise=0.01"};
    CHECK(run_ok(BKF_CLI_ARGS("sweep", "--nu", "-0.94", "--inits",
                              "uniform:amp=0.01;front:n=4;oscillation:noise=0.01", "--tmax", "20",
                              "--tmax-budget", "80", "--N", "128", "--no-progress", "--out", out)));
    char *table = bkf_cli_read_file(out);
    CHECK(table);
    for (int i = 0; table && i < 3; i++) {
        char prev[64], cur[64], want_settled[16] = "budget";
        int pf, cf;
        double tmax = 20;
        CHECK(simulate_regime(inits[i], tmax, prev, sizeof prev, &pf));
        while (2 * tmax <= 80) {
            tmax *= 2;
            CHECK(simulate_regime(inits[i], tmax, cur, sizeof cur, &cf));
            int counted = strcmp(cur, "propagating_fronts") == 0 ||
                          strcmp(cur, "period_doubled_pacemakers") == 0;
            /* two transients in a row are no settled regime */
            int same = strcmp(prev, cur) == 0 && strcmp(cur, "transient") != 0 &&
                       (!counted || pf == cf);
            snprintf(prev, sizeof prev, "%s", cur);
            pf = cf;
            if (same) {
                snprintf(want_settled, sizeof want_settled, "settled");
                break;
            }
        }
        char regime[64], settled[16];
        double t_end, fronts;
        CHECK(bkf_tsv_cell(table, i, "regime", NULL, regime, sizeof regime));
        CHECK(bkf_tsv_cell(table, i, "settled", NULL, settled, sizeof settled));
        CHECK(bkf_tsv_cell(table, i, "t_end", &t_end, NULL, 0));
        CHECK(bkf_tsv_cell(table, i, "fronts", &fronts, NULL, 0));
        CHECK_MSG(strcmp(regime, prev) == 0 && strcmp(settled, want_settled) == 0 &&
                      t_end == tmax && fronts == pf,
                  "point %d: %s %s t %g, simulate: %s %s t %g", i, regime, settled, t_end, prev,
                  want_settled, tmax);
    }
    free(table);
    /* without a budget, no settled column; a budget below tmax is bad input */
    CHECK(run_ok(BKF_CLI_ARGS("sweep", "--nu", "-0.94", "--tmax", "5", "--N", "64",
                              "--no-progress", "--out", out)));
    table = bkf_cli_read_file(out);
    CHECK(table && !strstr(table, "settled") && !strstr(table, "tmax-budget"));
    free(table);
    char *never = path_in(dir, "never.tsv");
    bkf_cli_expect_bad_input(BKF_CLI("sweep", "--tmax", "50", "--tmax-budget", "40", "--out",
                                     never),
                             "sweep", "tmax-budget", "a budget below tmax");
    free(never);
    free(out);
}

/* The lists of n the sweep's speeds product should give, from a table of
 * `bkfront speeds --stability` (rows in increasing n): allowed, every n;
 * stable, the n with a root whose stable cell is yes. */
static void speeds_lists(const char *table, char *allowed, char *stable, size_t size)
{
    allowed[0] = stable[0] = '\0';
    char verdict[32];
    double n, last_a = -1, last_s = -1;
    for (int r = 0; bkf_tsv_cell(table, r, "n", &n, NULL, 0); r++) {
        if (n != last_a)
            snprintf(allowed + strlen(allowed), size - strlen(allowed), "%s%.0f",
                     *allowed ? "," : "", n);
        last_a = n;
        if (bkf_tsv_cell(table, r, "stable", NULL, verdict, sizeof verdict) &&
            strcmp(verdict, "yes") == 0 && n != last_s) {
            snprintf(stable + strlen(stable), size - strlen(stable), "%s%.0f", *stable ? "," : "",
                     n);
            last_s = n;
        }
    }
    if (!*allowed) snprintf(allowed, size, "-");
    if (!*stable) snprintf(stable, size, "-");
}

/* --product speeds: each row is bkfront speeds --stability at its point
 * (the CLI's table read back), 1 and 2 threads give one table. */
TEST(cli_sweep_speeds_product_is_speeds_stability_at_each_point)
{
    char dir[] = "/tmp/bkf_sweep_XXXXXX";
    CHECK(mkdtemp(dir));
    char *one = path_in(dir, "one.tsv"), *two = path_in(dir, "two.tsv");
#define SPEEDS_GRID "--product", "speeds", "--x", "nu=-0.95,-0.9", "--S", "10", "--no-progress"
    CHECK(run_ok(BKF_CLI_ARGS("sweep", SPEEDS_GRID, "--threads", "1", "--out", one)));
    CHECK(run_ok(BKF_CLI_ARGS("sweep", SPEEDS_GRID, "--threads", "2", "--out", two)));
    char *a = bkf_cli_read_file(one), *b = bkf_cli_read_file(two);
    CHECK(a && b);
    CHECK_MSG(strcmp(a, b) == 0, "1 and 2 threads differ:\n%s\n---\n%s", a, b);
    CHECK(strstr(a, "# sweep: product speeds; "));
    const char *nus[] = {"-0.95", "-0.9"};
    for (int i = 0; i < 2; i++) {
        char cmd[160], allowed[256], stable[256], got[256], status[16];
        snprintf(cmd, sizeof cmd, "speeds --stability --gamma 2 --c 0.3 --nu %s --S 10", nus[i]);
        char *cli = bkf_cli_stdout(cmd, NULL);
        CHECK(cli);
        speeds_lists(cli, allowed, stable, sizeof allowed);
        double count, n_max;
        CHECK(bkf_tsv_cell(a, i, "status", NULL, status, sizeof status) &&
              strcmp(status, "ok") == 0);
        CHECK(bkf_tsv_cell(a, i, "allowed", NULL, got, sizeof got));
        CHECK_MSG(strcmp(got, allowed) == 0, "nu %s: allowed %s, speeds: %s", nus[i], got,
                  allowed);
        CHECK(bkf_tsv_cell(a, i, "allowed_count", &count, NULL, 0));
        CHECK(bkf_tsv_cell(a, i, "n_max", &n_max, NULL, 0));
        CHECK(count >= 1 && n_max == count && strstr(cli, "# n_max ") &&
              atoi(strstr(cli, "# n_max ") + 8) == (int)n_max);
        CHECK(bkf_tsv_cell(a, i, "stable", NULL, got, sizeof got));
        CHECK_MSG(strcmp(got, stable) == 0, "nu %s: stable %s, speeds: %s", nus[i], got, stable);
        free(cli);
    }
    /* the table of another product is not resumed */
    bkf_cli_expect_bad_input(BKF_CLI("sweep", "--product", "threshold", "--x", "nu=-0.95,-0.9",
                                     "--S", "10", "--no-progress", "--resume", "--out", one),
                             "sweep", "resume", "--resume on a speeds table");
    bkf_cli_expect_bad_input(BKF_CLI("sweep", "--x", "nu=-0.95,-0.9", "--S", "10",
                                     "--no-progress", "--resume", "--out", one),
                             "sweep", "resume", "--resume of a regime sweep on a speeds table");
    char *after = bkf_cli_read_file(one);
    CHECK(after && strcmp(after, a) == 0);
    /* a point where the product has no stability (c = 0) is bad input */
    char *never = path_in(dir, "never.tsv");
    bkf_cli_expect_bad_input(BKF_CLI("sweep", "--product", "speeds", "--x", "c=0.3,0", "--out",
                                     never),
                             "sweep", "c", "c = 0 in the grid of the speeds product");
    bkf_cli_expect_bad_input(BKF_CLI("sweep", "--product", "colour", "--out", never), "sweep",
                             "product", "an unknown product");
    CHECK(access(never, F_OK) != 0);
#undef SPEEDS_GRID
    free(never);
    free(after);
    free(a);
    free(b);
    free(one);
    free(two);
}

/* --product threshold: the row is bkfront floquet --threshold at its gamma,
 * c (the same numbers to the digit), and the lowest boundary of each kind
 * is floquet --diagram's, within the two boundaries' errors: a diagram of
 * its own scan, over nu in [-0.999, -0.8] (every lowest boundary of these
 * two gammas lies below -0.82; 0.2 s of CPU against 1.1 for the sweep's
 * whole window, and a second scan, not the sweep's own numbers); 1 thread
 * (the CLI) and 2 (the scene below) give one table.  (A third sweep, the
 * CLI on 2 threads, cost 2.5 of the test's 9.4 s of CPU for what the
 * scene's table shows.) */
TEST(cli_sweep_threshold_product_is_floquet_threshold_at_each_point)
{
    char dir[] = "/tmp/bkf_sweep_XXXXXX";
    CHECK(mkdtemp(dir));
    char *one = path_in(dir, "one.tsv");
    /* 1.875: two long-wave boundaries below 0 and no period doubling; 2:
     * period doubling first */
    CHECK(run_ok(BKF_CLI_ARGS("sweep", "--product", "threshold", "--x", "gamma=1.875,2", "--no-progress",
                              "--threads", "1", "--out", one)));
    char *a = bkf_cli_read_file(one);
    CHECK(a);
    const char *gammas[] = {"1.875", "2"};
    for (int i = 0; i < 2; i++) {
        char cmd[128], x[64], y[64];
        snprintf(cmd, sizeof cmd, "floquet --threshold --gamma %s --c 0.3", gammas[i]);
        char *th = bkf_cli_stdout(cmd, NULL);
        snprintf(cmd, sizeof cmd, "floquet --diagram --gamma %s --c 0.3 --search -0.999:-0.8", gammas[i]);
        char *dg = bkf_cli_stdout(cmd, NULL);
        CHECK(th && dg);
        const char *pairs[][2] = {{"nu_threshold", "nu_pd"}, {"nu_threshold_err", "nu_pd_err"},
                                  {"kind", "kind"}, {"q_c", "q_c"},
                                  {"stable_above", "stable_above"}};
        for (int k = 0; k < 5; k++) {
            CHECK(bkf_tsv_cell(a, i, pairs[k][0], NULL, x, sizeof x));
            CHECK(bkf_tsv_cell(th, 0, pairs[k][1], NULL, y, sizeof y));
            CHECK_MSG(strcmp(x, y) == 0, "gamma %s: %s %s, floquet --threshold: %s", gammas[i],
                      pairs[k][0], x, y);
        }
        /* the diagram's first boundary of each kind (nan: none), within
         * twice its error (the sweep's boundary has an error of the same
         * size) */
        const char *kinds[][2] = {{"period_doubling", "nu_period_doubling"},
                                  {"long_wave", "nu_long_wave"}};
        for (int k = 0; k < 2; k++) {
            double want = NAN, err = 0.0, got;
            for (int r = 0; bkf_tsv_cell(dg, r, "to_kind", NULL, x, sizeof x); r++)
                if (strcmp(x, kinds[k][0]) == 0) {
                    CHECK(bkf_tsv_cell(dg, r, "nu_to", &want, NULL, 0) &&
                          bkf_tsv_cell(dg, r, "to_err", &err, NULL, 0));
                    break;
                }
            CHECK(bkf_tsv_cell(a, i, kinds[k][1], &got, x, sizeof x));
            CHECK_MSG(isnan(want) ? isnan(got) : err > 0 && err < 1e-8 && fabs(got - want) <= 2.0 * err,
                      "gamma %s: %s %s, floquet --diagram: %.17g +- %.2g", gammas[i], kinds[k][1], x,
                      want, err);
        }
        free(th);
        free(dg);
    }
    char kind[32];
    CHECK(bkf_tsv_cell(a, 0, "kind", NULL, kind, sizeof kind) && strcmp(kind, "long_wave") == 0);
    CHECK(bkf_tsv_cell(a, 0, "nu_period_doubling", NULL, kind, sizeof kind) &&
          strcmp(kind, "nan") == 0);
    /* the scene key: a [sweep] with product = threshold writes the CLI's table */
    char *scene = path_in(dir, "th.scene"), *out = path_in(dir, "scene"), *table = NULL;
    FILE *f = fopen(scene, "w");
    CHECK(f);
    fputs("[model]\ngamma = 2\nc = 0.3\nnu = -0.96\nS = 20\n"
          "[sweep th]\nproduct = threshold\nx = gamma=1.875,2\nthreads = 2\n", f);
    fclose(f);
    bkf_cli_result r = bkf_cli_run(BKF_CLI_ARGS("run", "--no-figures", "--out", out, scene), NULL);
    CHECK_MSG(r.code == 0, "bkfront run: exit %d, %s", r.code, r.err);
    bkf_cli_result_free(&r);
    char *path = path_in(out, "th.tsv");
    table = bkf_cli_read_file(path);
    CHECK_MSG(table && strcmp(table, a) == 0, "the scene's table differs:\n%s\n---\n%s",
              table ? table : "(none)", a);
    free(path);
    free(table);
    free(scene);
    free(out);
    free(a);
    free(one);
}

/* Dataset `name` of an HDF5 file as doubles (malloc'ed), its size in *n. */
static double *h5_read(hid_t f, const char *name, size_t *n)
{
    int rank;
    hsize_t dims[2] = {1, 1};
    if (H5LTget_dataset_ndims(f, name, &rank) < 0 || rank < 1 || rank > 2 ||
        H5LTget_dataset_info(f, name, dims, NULL, NULL) < 0)
        return NULL;
    *n = (size_t)(dims[0] * (rank == 2 ? dims[1] : 1));
    double *v = malloc(*n * sizeof *v);
    if (v && H5LTread_dataset_double(f, name, v) < 0) {
        free(v);
        return NULL;
    }
    return v;
}

/* The field files of two runs hold the same t, x and psi, bit for bit, and
 * the same parameters (numbers; the command differs by design). */
static int same_field(const char *a_path, const char *b_path, char *why, size_t size)
{
    hid_t a = H5Fopen(a_path, H5F_ACC_RDONLY, H5P_DEFAULT);
    hid_t b = H5Fopen(b_path, H5F_ACC_RDONLY, H5P_DEFAULT);
    int ok = a >= 0 && b >= 0;
    if (!ok) snprintf(why, size, "cannot open %s or %s", a_path, b_path);
    const char *sets[] = {"t", "x", "psi"};
    for (int k = 0; ok && k < 3; k++) {
        size_t na = 0, nb = 0;
        double *va = h5_read(a, sets[k], &na), *vb = h5_read(b, sets[k], &nb);
        ok = va && vb && na == nb && na > 0 && memcmp(va, vb, na * sizeof *va) == 0;
        if (!ok) snprintf(why, size, "dataset %s differs (%zu and %zu values)", sets[k], na, nb);
        free(va);
        free(vb);
    }
    const char *numbers[] = {"gamma", "c", "nu", "S", "tmax", "tol", "level", "N", "seed",
                             "frames"};
    for (int k = 0; ok && k < 10; k++) {
        double x = NAN, y = NAN;
        ok = H5LTget_attribute_double(a, "/", numbers[k], &x) >= 0 &&
             H5LTget_attribute_double(b, "/", numbers[k], &y) >= 0 && x == y;
        if (!ok) snprintf(why, size, "attribute %s: %.17g and %.17g", numbers[k], x, y);
    }
    if (a >= 0) H5Fclose(a);
    if (b >= 0) H5Fclose(b);
    return ok;
}

/* --fields DIR: one HDF5 file per point, named by the point, each the file
 * bkfront simulate --spacetime X.h5 writes for that point; nothing else in
 * the directory (no temporary left), the table the same as without fields;
 * bad --fields is bad input. */
TEST(cli_sweep_fields_are_simulate_spacetime_files_per_point)
{
    char dir[] = "/tmp/bkf_sweep_XXXXXX";
    CHECK(mkdtemp(dir));
    char *fields = path_in(dir, "fields"), *with = path_in(dir, "with.tsv"),
         *without = path_in(dir, "without.tsv");
    CHECK(mkdir(fields, 0755) == 0);
#define FIELDS_GRID "--x", "nu=-0.96,-0.94", "--inits",                       \
                    "oscillation:noise=0.01;uniform:amp=0.01",                  \
                    "--seeds", "1,2", "--tmax", "8", "--N", "256", "--frames", "16",    \
                    "--no-progress"
    CHECK(run_ok(BKF_CLI_ARGS("sweep", FIELDS_GRID, "--threads", "2", "--fields", fields,
                              "--out", with)));
    CHECK(run_ok(BKF_CLI_ARGS("sweep", FIELDS_GRID, "--threads", "1", "--out", without)));
#undef FIELDS_GRID
    char *a = bkf_cli_read_file(with), *b = bkf_cli_read_file(without);
    CHECK(a && b && strcmp(a, b) == 0);
    size_t files = 0;
    DIR *d = opendir(fields);
    CHECK(d);
    for (struct dirent *e; d && (e = readdir(d));)
        if (e->d_name[0] != '.') {
            int i = -1, n = 0;
            CHECK_MSG(sscanf(e->d_name, "point_%d.h5%n", &i, &n) == 1 &&
                          e->d_name[n] == '\0' && i >= 0 && i < POINTS,
                      "unexpected file %s in --fields", e->d_name);
            files++;
        }
    if (d) closedir(d);
    CHECK_MSG(files == POINTS, "%zu field files for %d points", files, POINTS);
    /* point i = ((init * 2 + x) * 2 + seed) */
    const char *inits[] = {"oscillation:noise=0.01", "uniform:amp=0.01"};
    const char *nus[] = {"-0.96", "-0.94"};
    for (int i = 0; i < POINTS; i++) {
        char name[32], sim_name[32], why[160] = "";
        snprintf(name, sizeof name, "point_%d.h5", i);
        snprintf(sim_name, sizeof sim_name, "simulate_%d.h5", i);
        char *got = path_in(fields, name), *want = path_in(dir, sim_name);
        CHECK(run_ok(BKF_CLI_ARGS("simulate", "--nu", nus[(i / 2) % 2], "--init", inits[i / 4],
                                  "--seed", i % 2 ? "2" : "1", "--tmax", "8", "--N", "256",
                                  "--frames", "16", "--no-progress", "--spacetime", want,
                                  "--out", "/dev/null")));
        CHECK_MSG(same_field(got, want, why, sizeof why), "point %d: %s", i, why);
        free(got);
        free(want);
    }
    char *never = path_in(dir, "never.tsv"), *nodir = path_in(dir, "no_such_dir");
    bkf_cli_expect_bad_input(BKF_CLI("sweep", "--nu", "-0.9", "--fields", nodir, "--out", never),
                             "sweep", "fields", "a missing directory");
    bkf_cli_expect_bad_input(BKF_CLI("sweep", "--product", "threshold", "--fields", fields,
                                     "--out", never),
                             "sweep", "fields", "fields of a theory product");
    CHECK(access(never, F_OK) != 0);
    free(never);
    free(nodir);
    free(a);
    free(b);
    free(fields);
    free(with);
    free(without);
}

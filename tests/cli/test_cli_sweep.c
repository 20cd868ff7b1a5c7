/* bkfront sweep: the table is the same bit for bit however the points are
 * scheduled (1 or 2 threads, tasks merged, resumed after a crash, an MPI
 * farm), its rows agree with bkfront simulate and with the speed-selection
 * theory, and bad input is refused before any run. */
#define _POSIX_C_SOURCE 200809L
#include "harness.h"
#include "cli_support.h"

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
    CHECK_MSG(access(out, F_OK) != 0, "a refused sweep wrote %s", out);
    free(out);
}

/* The MPI build (make mpi): mpirun -np 2 (one worker) and -np 3 (two) give
 * the serial table, with OpenMPI kept on this machine (shared memory and
 * loopback only). */
TEST(cli_sweep_mpi_farm_equals_serial)
{
    const char *mpi_cli = BKF_SOURCE_DIR "/build/mpi/bkfront";
    if (access(mpi_cli, X_OK) != 0 || access("/usr/bin/mpirun", X_OK) != 0) {
        bkf_test_note("skipped: %s or mpirun missing (make test-mpi builds and runs it)", mpi_cli);
        return;
    }
    char dir[] = "/tmp/bkf_sweep_XXXXXX";
    CHECK(mkdtemp(dir));
    char *serial = serial_table(dir);
    CHECK(serial);
    for (int np = 2; np <= 3; np++) {
        char *out = path_in(dir, np == 2 ? "np2.tsv" : "np3.tsv");
        char cmd[2048];
        snprintf(cmd, sizeof cmd,
                 "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 mpirun --oversubscribe "
                 "-np %d --mca btl self,vader --mca oob_tcp_if_include lo --mca "
                 "btl_tcp_if_include lo %s sweep --x nu=-0.96,-0.94 --inits "
                 "'front:n=4;uniform:amp=0.01' --seeds 1,2 --tmax 30 --N 256 --no-progress "
                 "--out %s >%s/mpi.log 2>&1",
                 np, mpi_cli, out, dir);
        int rc = system(cmd);
        char *log = path_in(dir, "mpi.log");
        char *text = bkf_cli_read_file(log);
        CHECK_MSG(rc == 0, "mpirun -np %d: status %d: %s", np, rc, text ? text : "");
        free(text);
        free(log);
        char *t = bkf_cli_read_file(out);
        CHECK_MSG(t && strcmp(t, serial) == 0, "-np %d differs from serial:\n%s", np, t);
        free(t);
        free(out);
    }
    free(serial);
}

/* SIGTERM in the middle: exit 143, one line, every row on disk whole; the
 * resumed table is the uninterrupted one. */
TEST(cli_sweep_sigterm_keeps_finished_rows_and_resume_completes)
{
    char dir[] = "/tmp/bkf_sweep_XXXXXX";
    CHECK(mkdtemp(dir));
#define LONG_GRID "--x", "nu=-0.98:-0.82:9", "--seeds", "1,2", "--tmax", "150", "--N", "256", \
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
 * regimes, and front counts for fronts, agree, or at the budget), and the
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
            int same = strcmp(prev, cur) == 0 && (!counted || pf == cf);
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

/* Interrupted runs, as a user sees them: the built CLI (BKF_CLI_PATH) is
 * started on a run far too long to finish, then stopped by a signal.
 *   SIGINT / SIGTERM  stop cleanly: the complete frames are written, marked,
 *                     one line on stderr, exit 130 / 143;
 *   SIGHUP            (not a cancel) ends it: no output, no temporary left;
 *   SIGKILL           cannot be caught: the previous file (or none) stays, a
 *                     recognisable temporary may stay, and the next run for
 *                     the same target removes it.
 * The library's cancellation flag is checked on its own too: a run canceled
 * and then resumed ends where an uninterrupted run ends. */
#define _POSIX_C_SOURCE 200809L
#include "harness.h"
#include "cli_support.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "bkfront/pde.h"

#define slurp bkf_cli_read_file

#define write_text bkf_cli_write_text

static void make_dir(char *templ)
{
    CHECK_MSG(mkdtemp(templ) != NULL, "mkdtemp: %s", strerror(errno));
}

/* Names in dir starting with `prefix`: how many, the first into `first`. */
static int count_entries(const char *dir, const char *prefix, char *first, size_t size)
{
    DIR *d = opendir(dir);
    CHECK(d);
    int n = 0;
    struct dirent *de;
    while ((de = readdir(d)) != NULL) {
        if (strncmp(de->d_name, prefix, strlen(prefix)) != 0) continue;
        if (n++ == 0 && first) snprintf(first, size, "%s", de->d_name);
    }
    closedir(d);
    return n;
}

static void remove_dir(const char *dir)
{
    DIR *d = opendir(dir);
    if (!d) return;
    struct dirent *de;
    char path[4096];
    while ((de = readdir(d)) != NULL) {
        if (!strcmp(de->d_name, ".") || !strcmp(de->d_name, "..")) continue;
        snprintf(path, sizeof path, "%s/%s", dir, de->d_name);
        unlink(path);
    }
    closedir(d);
    rmdir(dir);
}

/* The CLI in dir with stderr to dir/stderr, stdout to /dev/null. */
static pid_t spawn_cli(const char *dir, const char *const *args)
{
    char errpath[4096];
    snprintf(errpath, sizeof errpath, "%s/stderr", dir);
    return bkf_cli_spawn(args, &(bkf_cli_options){.dir = dir}, NULL, errpath);
}

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void sleep_s(double s)
{
    struct timespec ts = {(time_t)s, (long)((s - (double)(time_t)s) * 1e9)};
    while (nanosleep(&ts, &ts) != 0 && errno == EINTR) {}
}

/* Waits until the run is computing: its temporary for `target` exists (it is
 * created before the work starts), then lets it work `extra` seconds more. */
static void wait_computing(pid_t pid, const char *dir, const char *target, double extra)
{
    char prefix[256];
    snprintf(prefix, sizeof prefix, ".%s.tmp.", target);
    double t0 = now();
    while (count_entries(dir, prefix, NULL, 0) == 0) {
        int status;
        CHECK_MSG(waitpid(pid, &status, WNOHANG) == 0, "the CLI ended before computing");
        CHECK_MSG(now() - t0 < 120, "no temporary after 120 s");
        sleep_s(0.02);
    }
    sleep_s(extra);
}

static int wait_status(pid_t pid)
{
    int status = 0;
    CHECK(waitpid(pid, &status, 0) == pid);
    return status;
}

/* A run that cannot finish within the test: N 128 over t = 1e6 (the
 * default run, N 512 to t = 125, takes seconds). */
#define LONG_RUN "simulate", "--N", "128", "--tmax", "1e6", "--frames", "100000", "--no-progress"

static void check_interrupted(int sig, const char *name, int want_code)
{
    char dir[] = "/tmp/bkf_sig_XXXXXX";
    make_dir(dir);
    const char *args[] = {LONG_RUN, "--out", "d.tsv", "--spacetime", "st.txt", "--snapshots",
                          "sn.tsv", NULL};
    pid_t pid = spawn_cli(dir, args);
    wait_computing(pid, dir, "d.tsv", 1.0);
    CHECK(kill(pid, sig) == 0);
    int status = wait_status(pid);
    CHECK_MSG(WIFEXITED(status) && WEXITSTATUS(status) == want_code,
              "status 0x%x, want exit %d", status, want_code);

    char path[4096];
    snprintf(path, sizeof path, "%s/stderr", dir);
    char *err = slurp(path);
    CHECK(err);
    /* one line naming the interruption and how far it got */
    char want[64];
    snprintf(want, sizeof want, "bkfront simulate: interrupted (%s) at t = ", name);
    CHECK_MSG(strncmp(err, want, strlen(want)) == 0, "stderr: %s", err);
    CHECK(strchr(err, '\n') == err + strlen(err) - 1);
    double t_stop = 0;
    size_t kept = 0;
    CHECK(sscanf(err + strlen(want), "%lf of %*f: %zu complete frames kept", &t_stop, &kept) == 2);
    CHECK(t_stop > 0 && t_stop < 1e6 && kept >= 1);

    /* diagnostics: the marker first, then the kept frames: t = 10 k (frame
     * spacing tmax/frames), each complete, all before the stop */
    snprintf(path, sizeof path, "%s/d.tsv", dir);
    char *d = slurp(path);
    CHECK_MSG(d, "no diagnostics file");
    snprintf(want, sizeof want, "# interrupted (%s) at t = ", name);
    CHECK(strncmp(d, want, strlen(want)) == 0);
    char *line = strstr(d, "\nt\tmean\t");
    CHECK(line);
    line = strchr(line + 1, '\n') + 1;
    size_t rows = 0;
    for (char *p = line; *p; rows++) {
        char *nl = strchr(p, '\n');
        CHECK_MSG(nl, "row %zu is not complete", rows);
        double t = strtod(p, NULL);
        CHECK_CLOSE(t, 10.0 * (double)rows, 1e-12, 1e-9);
        CHECK(t <= t_stop);
        int tabs = 0;
        for (char *q = p; q < nl; q++) tabs += *q == '\t';
        CHECK(tabs == 11);
        p = nl + 1;
    }
    CHECK_MSG(rows == kept, "%zu rows, stderr says %zu", rows, kept);

    /* spacetime: the same frames, after the x row */
    snprintf(path, sizeof path, "%s/st.txt", dir);
    char *st = slurp(path);
    CHECK_MSG(st, "no spacetime file");
    CHECK(strstr(st, want) != NULL);
    size_t st_rows = 0;
    for (char *p = st; *p;) {
        char *nl = strchr(p, '\n');
        CHECK(nl);
        if (*p != '#') st_rows++;
        p = nl + 1;
    }
    CHECK_MSG(st_rows == kept + 1, "%zu spacetime rows, want %zu + the x row", st_rows, kept);

    /* snapshots: t = 0 (the first of the 2 asked), then the state where the
     * run stopped, 128 rows each */
    snprintf(path, sizeof path, "%s/sn.tsv", dir);
    char *sn = slurp(path);
    CHECK_MSG(sn, "no snapshots file");
    CHECK(strstr(sn, want) != NULL);
    line = strstr(sn, "\nt\tx\tpsi\teta\n");
    CHECK(line);
    line += strlen("\nt\tx\tpsi\teta\n");
    size_t at0 = 0, at_stop = 0, other = 0;
    for (char *p = line; *p;) {
        char *nl = strchr(p, '\n');
        CHECK(nl);
        double t = strtod(p, NULL);
        if (t == 0) at0++;
        else if (fabs(t - t_stop) <= 1e-8 * t_stop) at_stop++;
        else other++;
        p = nl + 1;
    }
    CHECK_MSG(at0 == 128 && at_stop == 128 && other == 0, "snapshot rows %zu, %zu, %zu", at0,
              at_stop, other);
    /* and a run continues from it */
    const char *resume[] = {"simulate", "--init", "file:sn.tsv", "--tmax", "0.5", "--frames", "2",
                            "--no-progress", "--out", "r.tsv", NULL};
    pid = spawn_cli(dir, resume);
    status = wait_status(pid);
    CHECK_MSG(WIFEXITED(status) && WEXITSTATUS(status) == 0, "resume: status 0x%x", status);

    CHECK(count_entries(dir, ".d.tsv.tmp.", NULL, 0) == 0);
    CHECK(count_entries(dir, ".st.txt.tmp.", NULL, 0) == 0);
    CHECK(count_entries(dir, ".sn.tsv.tmp.", NULL, 0) == 0);
    bkf_test_note("%s after %.6g time units: %zu frames kept", name, t_stop, kept);
    free(err);
    free(d);
    free(st);
    free(sn);
    remove_dir(dir);
}

TEST(cli_simulate_sigint_keeps_complete_frames) { check_interrupted(SIGINT, "SIGINT", 130); }

TEST(cli_simulate_sigterm_keeps_complete_frames) { check_interrupted(SIGTERM, "SIGTERM", 143); }

TEST(cli_simulate_sighup_leaves_previous_file_and_no_temporary)
{
    char dir[] = "/tmp/bkf_sig_XXXXXX";
    make_dir(dir);
    char path[4096];
    snprintf(path, sizeof path, "%s/d.tsv", dir);
    write_text(path, "previous result\n");
    const char *args[] = {LONG_RUN, "--out", "d.tsv", "--spacetime", "st.txt", NULL};
    pid_t pid = spawn_cli(dir, args);
    wait_computing(pid, dir, "d.tsv", 0.3);
    CHECK(kill(pid, SIGHUP) == 0);
    int status = wait_status(pid);
    CHECK_MSG(WIFSIGNALED(status) && WTERMSIG(status) == SIGHUP, "status 0x%x", status);
    char *d = slurp(path);
    CHECK(d && strcmp(d, "previous result\n") == 0);
    free(d);
    snprintf(path, sizeof path, "%s/st.txt", dir);
    CHECK(access(path, F_OK) != 0);
    /* no temporary is left (nor the spacetime file) */
    CHECK(count_entries(dir, ".", NULL, 0) == 2); /* "." and ".." */
    remove_dir(dir);
}

static void check_killed(int previous)
{
    char dir[] = "/tmp/bkf_sig_XXXXXX";
    make_dir(dir);
    char path[4096];
    snprintf(path, sizeof path, "%s/d.tsv", dir);
    if (previous) write_text(path, "previous result\n");
    const char *args[] = {LONG_RUN, "--out", "d.tsv", NULL};
    pid_t pid = spawn_cli(dir, args);
    wait_computing(pid, dir, "d.tsv", 0.3);
    CHECK(kill(pid, SIGKILL) == 0);
    int status = wait_status(pid);
    CHECK(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL);

    char *d = slurp(path);
    if (previous)
        CHECK(d && strcmp(d, "previous result\n") == 0);
    else
        CHECK(d == NULL);
    free(d);
    /* the temporary stays, named after the target and the killed process */
    char temp[256], want[64];
    snprintf(want, sizeof want, ".d.tsv.tmp.%ld.", (long)pid);
    CHECK(count_entries(dir, ".d.tsv.tmp.", temp, sizeof temp) == 1);
    CHECK_MSG(strncmp(temp, want, strlen(want)) == 0, "temporary %s", temp);

    /* the next run for the same target removes it and writes a whole file */
    const char *again[] = {"simulate", "--N", "16", "--tmax", "1", "--frames", "4",
                           "--no-progress", "--out", "d.tsv", NULL};
    pid = spawn_cli(dir, again);
    status = wait_status(pid);
    CHECK(WIFEXITED(status) && WEXITSTATUS(status) == 0);
    CHECK(count_entries(dir, ".d.tsv.tmp.", NULL, 0) == 0);
    d = slurp(path);
    CHECK(d && strncmp(d, "# bkfront ", 10) == 0);
    size_t n = strlen(d);
    CHECK(n > 0 && d[n - 1] == '\n');
    CHECK(strstr(d, "\n1\t") != NULL); /* the last frame, t = 1 */
    free(d);
    remove_dir(dir);
}

TEST(cli_simulate_sigkill_keeps_previous_file) { check_killed(1); }

TEST(cli_simulate_sigkill_without_previous_file_leaves_none) { check_killed(0); }

/* ------------------------------------------------------------- library */

typedef struct {
    volatile sig_atomic_t *flag;
    double raise_at, last_t;
} cancel_obs;

static int raise_flag(const bkf_pde_sample *s, void *data)
{
    cancel_obs *o = data;
    o->last_t = s->t;
    if (s->t >= o->raise_at) *o->flag = 1;
    return 0;
}

TEST(pde_cancel_flag_stops_and_resumes_exactly)
{
    bkf_model_params pp = {2.0, 0.3, -0.96, 20.0, 64, BKF_MODEL_CONTINUUM};
    bkf_pde_options o = bkf_pde_options_default();
    volatile sig_atomic_t flag = 0;
    o.cancel = &flag;
    bkf_error e;
    bkf_pde *a = bkf_pde_alloc(&pp, &o, &e), *b = bkf_pde_alloc(&pp, NULL, &e);
    CHECK(a && b);
    CHECK_STATUS(bkf_pde_init_uniform(a, 1e-3, 7, &e), BKF_OK);
    CHECK_STATUS(bkf_pde_init_uniform(b, 1e-3, 7, &e), BKF_OK);

    cancel_obs ob = {&flag, 5.0, -1};
    CHECK_STATUS(bkf_pde_run(a, 20.0, 0.5, raise_flag, &ob, NULL, NULL, &e), BKF_ECANCELED);
    double t_stop = bkf_pde_time(a);
    /* stopped after the step in progress: past 5, well before 20, and every
     * sample up to the stop was delivered (none after it) */
    CHECK(t_stop >= 5.0 && t_stop < 20.0);
    CHECK(ob.last_t >= 5.0 && ob.last_t <= t_stop && t_stop - ob.last_t < 0.5 + 1e-12);
    CHECK(strstr(e.message, "canceled at t = ") != NULL);
    CHECK(bkf_pde_get_stats(a)->stopped);

    /* lowered again, the run resumes; it ends where an uninterrupted run ends */
    flag = 0;
    ob.raise_at = 1e300;
    /* samples are step ends, so both runs sample on the same grid (the stop
     * is at a sample, t = 5) to take the same steps */
    CHECK(t_stop == 5.0);
    CHECK_STATUS(bkf_pde_run(a, 20.0, 0.5, raise_flag, &ob, NULL, NULL, &e), BKF_OK);
    cancel_obs never = {&flag, 1e300, -1};
    CHECK_STATUS(bkf_pde_run(b, 20.0, 0.5, raise_flag, &never, NULL, NULL, &e), BKF_OK);
    CHECK(bkf_pde_time(a) == 20.0 && bkf_pde_time(b) == 20.0);
    const double *pa = bkf_pde_psi(a), *pb = bkf_pde_psi(b);
    double diff = 0;
    for (size_t i = 0; i < pp.N; i++) diff = fmax(diff, fabs(pa[i] - pb[i]));
    bkf_test_note("canceled at t = %.6g; resumed vs uninterrupted at t = 20: max |d psi| = %.2g",
                  t_stop, diff);
    /* the stop falls between steps and keeps the step-size history, so the
     * resumed run takes exactly the uninterrupted run's steps */
    CHECK(diff == 0);
    bkf_pde_free(a);
    bkf_pde_free(b);
}

/* One SIGINT stops a whole `bkfront run`: the step under way (a simulation
 * far too long to finish) stops without replacing the complete files of an
 * earlier run, the step done before it keeps its file, no later step (a
 * table, a gnuplot figure) starts, no temporary stays, exit 130. */
TEST(cli_run_sigint_stops_the_whole_scene)
{
    char dir[] = "/tmp/bkf_sig_run_XXXXXX";
    make_dir(dir);
    char path[4096];
    snprintf(path, sizeof path, "%s/t.scene", dir);
    write_text(path, "[model]\ngamma = 2\nc = 0.3\nnu = -0.96\nS = 20\n"
                     "[friction f]\nfrom = -1\nto = 4\n[figure f]\ndata = f\n"
                     "[spacetime b]\ntmax = 1e6\nN = 128\nframes = 1000\n"
                     "[period p]\nmu = 1:10:5\n");
    snprintf(path, sizeof path, "%s/o", dir);
    CHECK(mkdir(path, 0777) == 0);
    static const char earlier[] = "complete data of an earlier run\n";
    snprintf(path, sizeof path, "%s/o/b.dat", dir);
    write_text(path, earlier);
    snprintf(path, sizeof path, "%s/o/b_diag.tsv", dir);
    write_text(path, earlier);
    char outpath[4096], errpath[4096], odir[4096];
    snprintf(outpath, sizeof outpath, "%s/stdout", dir);
    snprintf(errpath, sizeof errpath, "%s/stderr", dir);
    snprintf(odir, sizeof odir, "%s/o", dir);
    /* one job: the order of the steps is the plan's */
    pid_t pid = bkf_cli_spawn(BKF_CLI_ARGS("run", "--jobs", "1", "--out", "o", "t.scene"),
                              &(bkf_cli_options){.dir = dir}, outpath, errpath);
    CHECK(pid > 0);
    wait_computing(pid, odir, "b.dat", 0.3);
    CHECK(kill(pid, SIGINT) == 0);
    int status = wait_status(pid);
    CHECK_MSG(WIFEXITED(status) && WEXITSTATUS(status) == 130, "status %d", status);
    char *out = slurp(outpath), *err = slurp(errpath);
    CHECK(out && err);
    bkf_test_note("stdout: %s", out);
    CHECK(strstr(out, "interrupted (SIGINT): 1 of 4 computations done"));
    CHECK(strstr(err, "interrupted (SIGINT)") && bkf_count_lines(err) == 1);
    const char *kept[] = {"b.dat", "b_diag.tsv"};
    for (int i = 0; i < 2; i++) {
        snprintf(path, sizeof path, "%s/o/%s", dir, kept[i]);
        char *text = slurp(path);
        CHECK_MSG(text && strcmp(text, earlier) == 0, "%s was replaced", kept[i]);
        free(text);
    }
    struct stat sb;
    snprintf(path, sizeof path, "%s/o/f.tsv", dir);
    CHECK_MSG(stat(path, &sb) == 0 && sb.st_size > 0, "the complete step lost its file");
    snprintf(path, sizeof path, "%s/o/p.tsv", dir);
    CHECK_MSG(stat(path, &sb) != 0, "a step after the signal ran");
    snprintf(path, sizeof path, "%s/o/f.png", dir);
    CHECK_MSG(stat(path, &sb) != 0, "the figure after the signal was drawn");
    CHECK_MSG(count_entries(odir, ".", NULL, 0) == 2, "a temporary stayed"); /* . and .. */
    free(out);
    free(err);
    remove_dir(odir);
    remove_dir(dir);
}

/* One SIGINT stops every job of a parallel run: two simulations far too
 * long to finish, running side by side (both temporaries exist at once),
 * both stop without replacing the complete files of an earlier run; the
 * steps left waiting for a free job never start, nor the figure of a
 * stopped step; no temporary stays, exit 130. */
TEST(cli_run_sigint_stops_every_job)
{
    char dir[] = "/tmp/bkf_sig_jobs_XXXXXX";
    make_dir(dir);
    char path[4096];
    snprintf(path, sizeof path, "%s/t.scene", dir);
    write_text(path, "[model]\ngamma = 2\nc = 0.3\nnu = -0.96\nS = 20\n"
                     "[spacetime a]\ntmax = 1e6\nN = 128\nframes = 1000\n"
                     "[spacetime b]\ntmax = 1e6\nN = 128\nframes = 1000\nnu = -0.9\n"
                     "[friction f]\nfrom = -1\nto = 4\n"
                     "[period p]\nmu = 1:10:5\n[figure a]\ndata = a\n");
    snprintf(path, sizeof path, "%s/o", dir);
    CHECK(mkdir(path, 0777) == 0);
    static const char earlier[] = "complete data of an earlier run\n";
    static const char *const kept[] = {"a.dat", "a_diag.tsv", "b.dat", "b_diag.tsv"};
    for (int i = 0; i < 4; i++) {
        snprintf(path, sizeof path, "%s/o/%s", dir, kept[i]);
        write_text(path, earlier);
    }
    char outpath[4096], errpath[4096], odir[4096];
    snprintf(outpath, sizeof outpath, "%s/stdout", dir);
    snprintf(errpath, sizeof errpath, "%s/stderr", dir);
    snprintf(odir, sizeof odir, "%s/o", dir);
    /* two jobs: a and b start at once; f and p wait for a free job */
    pid_t pid = bkf_cli_spawn(BKF_CLI_ARGS("run", "--jobs", "2", "--out", "o", "t.scene"),
                              &(bkf_cli_options){.dir = dir}, outpath, errpath);
    CHECK(pid > 0);
    wait_computing(pid, odir, "a.dat", 0);
    wait_computing(pid, odir, "b.dat", 0.3);
    CHECK_MSG(count_entries(odir, ".a.dat.tmp.", NULL, 0) == 1,
              "the two simulations did not run at once");
    CHECK(kill(pid, SIGINT) == 0);
    int status = wait_status(pid);
    CHECK_MSG(WIFEXITED(status) && WEXITSTATUS(status) == 130, "status %d", status);
    char *out = slurp(outpath), *err = slurp(errpath);
    CHECK(out && err);
    bkf_test_note("stdout: %s", out);
    CHECK(strstr(out, "interrupted (SIGINT): 0 of 5 computations done"));
    CHECK(strstr(out, "stopped by SIGINT"));
    CHECK(strstr(err, "interrupted (SIGINT)") && bkf_count_lines(err) == 1);
    for (int i = 0; i < 4; i++) {
        snprintf(path, sizeof path, "%s/o/%s", dir, kept[i]);
        char *text = slurp(path);
        CHECK_MSG(text && strcmp(text, earlier) == 0, "%s was replaced", kept[i]);
        free(text);
    }
    struct stat sb;
    static const char *const never[] = {"f.tsv", "p.tsv", "a.png"};
    for (int i = 0; i < 3; i++) {
        snprintf(path, sizeof path, "%s/o/%s", dir, never[i]);
        CHECK_MSG(stat(path, &sb) != 0, "%s: written after the signal", never[i]);
    }
    CHECK_MSG(count_entries(odir, ".", NULL, 0) == 2, "a temporary stayed"); /* . and .. */
    free(out);
    free(err);
    remove_dir(odir);
    remove_dir(dir);
}

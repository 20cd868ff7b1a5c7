/* The shared runner of the built CLI (cli_support.h). */
#define _POSIX_C_SOURCE 200809L
#include "cli_support.h"

#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <signal.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include "harness.h"

#ifndef BKF_CLI_PATH
#error "BKF_CLI_PATH (the built bkfront binary) is defined by the Makefile for tests"
#endif

#define MAX_ARGS 64

static int temp_fd(void)
{
    char name[] = "/tmp/bkf_cli_run_XXXXXX";
    int fd = mkstemp(name);
    CHECK_MSG(fd >= 0, "mkstemp failed");
    unlink(name);
    return fd;
}

static char *read_all(int fd)
{
    size_t cap = 4096, n = 0;
    char *buf = malloc(cap);
    CHECK(buf);
    CHECK(lseek(fd, 0, SEEK_SET) == 0);
    for (;;) {
        if (n + 1 >= cap) {
            buf = realloc(buf, cap *= 2);
            CHECK(buf);
        }
        ssize_t k = read(fd, buf + n, cap - n - 1);
        if (k <= 0) break;
        n += (size_t)k;
    }
    buf[n] = '\0';
    return buf;
}

/* In the child: only calls that are safe after fork, then exec; 126 when the
 * set-up fails, 127 when exec does. */
static pid_t spawn_fds(const char *const *args, const bkf_cli_options *o, int in, int out, int err)
{
    char *argv[MAX_ARGS + 2];
    size_t argc = 0;
    argv[argc++] = BKF_CLI_PATH;
    /* execv's argv is char *const[] for history's sake; it does not write */
    for (; args[argc - 1]; argc++) {
        CHECK_MSG(argc <= MAX_ARGS, "more than %d arguments", MAX_ARGS);
        argv[argc] = (char *)args[argc - 1];
    }
    argv[argc] = NULL;
    fflush(stdout);
    fflush(stderr);
    pid_t pid = fork();
    CHECK(pid >= 0);
    if (pid > 0) return pid;

    if (dup2(in, 0) < 0 || dup2(out, 1) < 0 || dup2(err, 2) < 0) _exit(126);
    if (o && o->dir && chdir(o->dir) != 0) _exit(126);
    if (o && o->env)
        for (const char *const *e = o->env; *e; e++) {
            const char *eq = strchr(*e, '=');
            if (!eq) _exit(126);
            char name[256];
            size_t len = (size_t)(eq - *e);
            if (len == 0 || len >= sizeof name) _exit(126);
            memcpy(name, *e, len);
            name[len] = '\0';
            if (setenv(name, eq + 1, 1) != 0) _exit(126);
        }
    if (o && o->file_limit) {
        struct rlimit lim = {o->file_limit, o->file_limit};
        if (setrlimit(RLIMIT_FSIZE, &lim) != 0) _exit(126);
    }
    const int sigs[] = {SIGINT, SIGTERM, SIGHUP, SIGQUIT, SIGPIPE, SIGALRM, SIGXFSZ};
    for (size_t i = 0; i < sizeof sigs / sizeof sigs[0]; i++) signal(sigs[i], SIG_DFL);
    sigset_t none;
    sigemptyset(&none);
    sigprocmask(SIG_SETMASK, &none, NULL);
    /* an alarm set here survives exec: the run's own timeout */
    alarm(o ? o->timeout_s : 0);
    execv(BKF_CLI_PATH, argv);
    _exit(127);
}

static int stdin_fd(const bkf_cli_options *o)
{
    if (!o || !o->in) {
        int fd = open("/dev/null", O_RDONLY);
        CHECK(fd >= 0);
        return fd;
    }
    int fd = temp_fd();
    size_t len = strlen(o->in), done = 0;
    while (done < len) {
        ssize_t k = write(fd, o->in + done, len - done);
        CHECK(k > 0);
        done += (size_t)k;
    }
    CHECK(lseek(fd, 0, SEEK_SET) == 0);
    return fd;
}

bkf_cli_result bkf_cli_run(const char *const *args, const bkf_cli_options *o)
{
    int in = stdin_fd(o), out = temp_fd(), err = temp_fd();
    pid_t pid = spawn_fds(args, o, in, out, err);
    int status = 0;
    CHECK(waitpid(pid, &status, 0) == pid);
    bkf_cli_result r = {read_all(out), read_all(err), WIFEXITED(status) ? WEXITSTATUS(status) : -1,
                        WIFSIGNALED(status) ? WTERMSIG(status) : 0};
    close(in);
    close(out);
    close(err);
    return r;
}

void bkf_cli_result_free(bkf_cli_result *r)
{
    free(r->out);
    free(r->err);
    r->out = r->err = NULL;
}

char *bkf_cli_read_file(const char *path)
{
    int fd = open(path, O_RDONLY);
    if (fd < 0) return NULL;
    char *text = read_all(fd);
    close(fd);
    return text;
}

void bkf_cli_write_text(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    CHECK_MSG(f, "cannot write %s", path);
    CHECK(fputs(text, f) >= 0);
    CHECK(fclose(f) == 0);
}

static int open_out(const char *path)
{
    int fd = path ? open(path, O_WRONLY | O_CREAT | O_TRUNC, 0644) : open("/dev/null", O_WRONLY);
    CHECK_MSG(fd >= 0, "cannot open %s", path ? path : "/dev/null");
    return fd;
}

pid_t bkf_cli_spawn(const char *const *args, const bkf_cli_options *o, const char *out_path,
                    const char *err_path)
{
    int in = stdin_fd(o), out = open_out(out_path), err = open_out(err_path);
    pid_t pid = spawn_fds(args, o, in, out, err);
    close(in);
    close(out);
    close(err);
    return pid;
}

char *bkf_cli_stdout(const char *words, int *code)
{
    char *copy = strdup(words);
    const char *args[64];
    size_t n = 0;
    for (char *w = strtok(copy, " "); w && n < 63; w = strtok(NULL, " ")) args[n++] = w;
    args[n] = NULL;
    bkf_cli_result r = bkf_cli_run(args, NULL);
    free(copy);
    if (code)
        *code = r.code;
    else
        CHECK_MSG(r.code == 0, "bkfront %s: exit %d: %s", words, r.code, r.err);
    char *out = r.out;
    r.out = NULL;
    bkf_cli_result_free(&r);
    return out;
}

size_t bkf_count_lines(const char *s)
{
    size_t n = 0;
    for (; *s; s++) n += *s == '\n';
    return n;
}

void bkf_cli_expect_bad_input(bkf_cli_result r, const char *cmd, const char *names,
                              const char *what)
{
    char prefix[64];
    snprintf(prefix, sizeof prefix, "bkfront %s: ", cmd);
    CHECK_MSG(r.code == 2, "%s: exit %d, stderr: %s", what, r.code, r.err);
    CHECK_MSG(r.out[0] == '\0', "%s: stdout not empty: %s", what, r.out);
    CHECK_MSG(bkf_count_lines(r.err) == 1, "%s: stderr is not one line: %s", what, r.err);
    CHECK_MSG(strncmp(r.err, prefix, strlen(prefix)) == 0, "%s: %s", what, r.err);
    CHECK_MSG(strstr(r.err, names), "%s: '%s' not named in: %s", what, names, r.err);
    bkf_cli_result_free(&r);
}

int bkf_tsv_cell(const char *tsv, int row, const char *column, double *value, char *text,
                 size_t size)
{
    const char *p = tsv;
    while (*p == '#') {
        p = strchr(p, '\n');
        if (!p) return 0;
        p++;
    }
    int col = 0, found = -1;
    size_t clen = strlen(column);
    for (const char *q = p; *q && *q != '\n'; col++) {
        size_t len = strcspn(q, "\t\n");
        if (len == clen && strncmp(q, column, len) == 0) found = col;
        q += len;
        if (*q == '\t') q++;
    }
    if (found < 0) return 0;
    for (int r = 0; r <= row; r++) {
        p = strchr(p, '\n');
        if (!p || !p[1]) return 0;
        p++;
    }
    for (int c = 0; c < found; c++) {
        p = strchr(p, '\t');
        if (!p) return 0;
        p++;
    }
    size_t len = strcspn(p, "\t\n");
    if (text) {
        if (len >= size) return 0;
        memcpy(text, p, len);
        text[len] = '\0';
    }
    if (value) {
        char *end;
        *value = strtod(p, &end);
        if (end != p + len) return 0;
    }
    return 1;
}

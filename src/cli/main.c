/* bkfront SUBCOMMAND [options]: dispatch, help, version, and the one place
 * where a status becomes an error line and an exit code.
 *
 * A subcommand is a cli_command (args.h) defined in its own cmd_NAME.c; adding
 * one is an extern declaration and an entry in commands.c. */
#define _POSIX_C_SOURCE 200809L
#include "args.h"
#include "commands.h"
#include "bkfront/lazylib.h"

#include <errno.h>
#include <fcntl.h>
#include <gsl/gsl_errno.h>
#include <signal.h>
#include <string.h>
#include <unistd.h>

static void print_usage(FILE *out)
{
    fprintf(out,
            "usage: " CLI_PROGRAM " SUBCOMMAND [options]\n"
            "       " CLI_PROGRAM " help SUBCOMMAND\n"
            "       " CLI_PROGRAM " --help | --version\n"
            "\n"
            "Fronts and oscillations of the elastic excitable medium (Burridge-Knopoff\n"
            "model with creep-slip friction), built on the period T(mu, nu) of\n"
            "    f'' + mu (f^2 - 1) f' + f = nu.\n"
            "\n"
            "subcommands:\n");
    for (size_t i = 0; i < cli_command_count(); i++)
        fprintf(out, "  %-12s %s\n", cli_command_at(i)->name, cli_command_at(i)->summary);
    fprintf(out,
            "\n"
            "Output is TSV (comment lines start with '#', then a header line naming the\n"
            "columns; numbers as %%.17g) or JSON with --format json.\n"
            "exit status: 0 ok, 1 numerical failure, 2 bad input\n");
}

/* The names, for error lines that say what would have been valid. */
static void command_list(char *buf, size_t size)
{
    buf[0] = '\0';
    for (size_t i = 0; i < cli_command_count(); i++) {
        size_t used = strlen(buf);
        snprintf(buf + used, size - used, "%s%s", i ? ", " : "", cli_command_at(i)->name);
    }
}

static int unknown_command(const char *name)
{
    char list[256];
    command_list(list, sizeof list);
    /* The name is user text: keep the line one line. */
    char shown[64];
    size_t n = 0;
    for (; name[n] && n < sizeof shown - 1; n++)
        shown[n] = ((unsigned char)name[n] < 0x20 || name[n] == 0x7f) ? '?' : name[n];
    shown[n] = '\0';
    fprintf(stderr, CLI_PROGRAM ": unknown subcommand '%s' (one of: %s; see '" CLI_PROGRAM
                    " --help')\n", shown, list);
    return 2;
}

/* Help and the version go to stdout.  A caller that closed stdout
 * (`bkfront --help >&-`) has said it does not want them: that is success,
 * with nothing written.  Any other failure to write them (a full disk, a
 * broken pipe) is an error, said on stderr, exit 1: the text asked for did
 * not arrive.  (A data command fails on a closed stdout too: its output is
 * the result.) */
static int stdout_closed(void)
{
    return fcntl(STDOUT_FILENO, F_GETFD) == -1 && errno == EBADF;
}

static int finish_text(void)
{
    if (fflush(stdout) == 0 && !ferror(stdout)) return 0;
    fprintf(stderr, CLI_PROGRAM ": cannot write to standard output: %s\n", strerror(errno));
    return 1;
}

static int print_help(const cli_command *cmd)
{
    if (stdout_closed()) return 0;
    if (cmd)
        cmd->help(stdout);
    else
        print_usage(stdout);
    return finish_text();
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        print_usage(stderr);
        return 2;
    }
    /* The CLI reports every failure as a status and an error line, never by
     * GSL's default abort: it keeps GSL's handler off for the whole run (a
     * library call puts back whatever handler it found, this one). */
    gsl_set_error_handler_off();
    /* A write past the file size limit (ulimit -f) kills the process by
     * default, leaving its temporaries behind; ignored, it fails with
     * EFBIG like a full disk, and every writer's error path removes its
     * temporary and reports it.  gnuplot inherits the disposition, and
     * the figure it truncates is refused by its check (plot.h). */
    signal(SIGXFSZ, SIG_IGN);
    const char *first = argv[1];
    if (strcmp(first, "--help") == 0 || strcmp(first, "-h") == 0) return print_help(NULL);
    if (strcmp(first, "--version") == 0) {
        if (stdout_closed()) return 0;
        printf(CLI_PROGRAM " %s\n", bkf_version());
        return finish_text();
    }
    if (strcmp(first, "help") == 0) {
        if (argc == 2) return print_help(NULL);
        if (argc > 3) {
            fprintf(stderr, CLI_PROGRAM " help: give one subcommand name\n");
            return 2;
        }
        const cli_command *cmd = cli_find_command(argv[2]);
        return cmd ? print_help(cmd) : unknown_command(argv[2]);
    }

    const cli_command *cmd = cli_find_command(first);
    if (!cmd) return unknown_command(first);
    int sub_argc = argc - 1;
    char **sub_argv = argv + 1;
    if (cli_wants_help(sub_argc, sub_argv)) return print_help(cmd);

    bkf_error err = {0};
    int status = cmd->run(sub_argc, sub_argv, &err);
    if (status != BKF_OK) {
        /* a lazily loaded library that did not load is the cause the
         * library's message (a failed zgeev, ARPACK call) cannot name */
        const char *lazy = bkf_lazy_failure();
        fprintf(stderr, CLI_PROGRAM " %s: %s%s%s%s\n", cmd->name,
                err.message[0] ? err.message : "failed", lazy ? " (" : "", lazy ? lazy : "",
                lazy ? ")" : "");
    }
    return cli_exit_code(status);
}

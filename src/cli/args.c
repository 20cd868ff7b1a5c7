/* open_memstream and sigaction are POSIX 2008. */
#define _POSIX_C_SOURCE 200809L
#include "args.h"

#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <string.h>
#include <unistd.h>

static const char *shown(const char *text, char *buf, size_t size)
{
    return bkf_option_shown(text, buf, size);
}

const char *cli_shown(const char *text, char *buf, size_t size)
{
    return bkf_option_shown(text, buf, size);
}

int cli_parse_double(const char *flag, const char *text, double *value, bkf_error *err)
{
    return bkf_option_parse_double(text, "", flag, value, err);
}

int cli_parse_count(const char *flag, const char *text, size_t max, size_t *value,
                    bkf_error *err)
{
    return bkf_option_parse_count(text, 1, max, "", flag, value, err);
}

int cli_parse_choice(const char *flag, const char *text, const char *const *choices,
                     int *index, bkf_error *err)
{
    return bkf_option_parse_choice(text, choices, "", flag, index, err);
}

void cli_range_free(cli_range *range) { bkf_list_free(range); }

int cli_parse_range(const char *flag, const char *text, int geometric, cli_range *range,
                    bkf_error *err)
{
    return bkf_list_parse(text, geometric, 0, CLI_MAX_POINTS, "", flag, range, err);
}

int cli_parse_flags(const cli_flag *flags, size_t nflags, int argc, char **argv,
                    bkf_error *err)
{
    char a[72];
    unsigned char given[64] = {0};
    if (nflags > sizeof given) return bkf_error_set(err, BKF_EINPUT, "too many flags in table");
    for (int i = 1; i < argc; i++) {
        const char *arg = argv[i];
        if (strncmp(arg, "--", 2) != 0 || arg[2] == '\0') {
            return bkf_error_set(err, BKF_EINPUT, "unexpected argument '%s' (options start with --)",
                                 shown(arg, a, sizeof a));
        }
        const char *eq = strchr(arg, '=');
        size_t len = eq ? (size_t)(eq - arg) : strlen(arg);
        size_t k = 0;
        while (k < nflags && !(strlen(flags[k].name) == len && strncmp(flags[k].name, arg, len) == 0))
            k++;
        if (k == nflags) {
            char list[512] = "";
            for (size_t j = 0; j < nflags; j++) {
                size_t used = strlen(list);
                snprintf(list + used, sizeof list - used, "%s%s", j ? ", " : "", flags[j].name);
            }
            char name[64];
            size_t n = len < sizeof name - 1 ? len : sizeof name - 1;
            memcpy(name, arg, n);
            name[n] = '\0';
            return bkf_error_set(err, BKF_EINPUT, "unknown option '%s' (options: %s)",
                                 shown(name, a, sizeof a), list);
        }
        const cli_flag *f = &flags[k];
        if (given[k])
            return bkf_error_set(err, BKF_EINPUT, "%s: given twice (give it once)", f->name);
        given[k] = 1;
        if (f->seen) *f->seen = 1;
        if (!f->value) {
            if (eq) return bkf_error_set(err, BKF_EINPUT, "%s: takes no value", f->name);
            continue;
        }
        if (eq)
            *f->value = eq + 1;
        else if (i + 1 < argc)
            *f->value = argv[++i];
        else
            return bkf_error_set(err, BKF_EINPUT, "%s: missing value (expected %s)", f->name,
                                 f->form ? f->form : "a value");
    }
    return BKF_OK;
}

#define CLI_MAX_OPTIONS 64

int cli_parse_options(const cli_options *groups, size_t ngroups, int argc, char **argv,
                      int *help, bkf_error *err)
{
    char names[CLI_MAX_OPTIONS][48], forms[CLI_MAX_OPTIONS][160];
    const char *values[CLI_MAX_OPTIONS] = {0};
    int seen[CLI_MAX_OPTIONS] = {0}, wants_help = 0;
    cli_flag flags[CLI_MAX_OPTIONS + 1];
    const bkf_option *opts[CLI_MAX_OPTIONS];
    void *specs[CLI_MAX_OPTIONS];
    size_t n = 0;
    for (size_t g = 0; g < ngroups; g++)
        for (size_t i = 0; i < groups[g].n; i++) {
            const bkf_option *o = &groups[g].table[i];
            if (o->flags & BKF_OPT_SCENE_ONLY) continue;
            if (n == CLI_MAX_OPTIONS)
                return bkf_error_set(err, BKF_EINPUT, "too many options in the tables");
            snprintf(names[n], sizeof names[n], "--%s", o->name);
            if (o->type == BKF_OPT_CUSTOM || !o->form)
                bkf_option_describe(o, forms[n], sizeof forms[n]);
            else
                snprintf(forms[n], sizeof forms[n], "%s", o->form);
            flags[n] = (cli_flag){names[n], o->type == BKF_OPT_SWITCH ? NULL : &values[n],
                                  forms[n], &seen[n]};
            opts[n] = o;
            specs[n] = groups[g].spec;
            n++;
        }
    flags[n] = (cli_flag){"--help", NULL, NULL, &wants_help};
    int s = cli_parse_flags(flags, n + 1, argc, argv, err);
    if (help) *help = wants_help;
    if (s) return s;
    for (size_t k = 0; k < n; k++)
        if (!seen[k] && (opts[k]->flags & BKF_OPT_REQUIRED)) {
            char form[160];
            return bkf_error_set(err, BKF_EINPUT, "%s is required (%s)", names[k],
                                 bkf_option_describe(opts[k], form, sizeof form));
        }
    for (size_t k = 0; k < n; k++)
        if (seen[k] && (s = bkf_option_apply(opts[k], specs[k], values[k], "--", err))) return s;
    return BKF_OK;
}

void cli_options_help(FILE *out, const cli_options *groups, size_t ngroups)
{
    for (size_t g = 0; g < ngroups; g++)
        for (size_t i = 0; i < groups[g].n; i++) {
            const bkf_option *o = &groups[g].table[i];
            if (o->flags & BKF_OPT_SCENE_ONLY) continue;
            char head[96];
            int len = snprintf(head, sizeof head, "  --%s%s%s", o->name, o->form ? " " : "",
                               o->form ? o->form : "");
            const char *h = o->help ? o->help : "";
            /* The first help line beside the flag when it fits, else below. */
            if (len < 20)
                fprintf(out, "%-20s", head);
            else
                fprintf(out, "%s\n%20s", head, "");
            size_t line = 0;
            for (;;) {
                line = strcspn(h, "\n");
                fprintf(out, "%.*s", (int)line, h);
                h += line;
                if (!*h) break;
                h++;
                fprintf(out, "\n%20s", "");
            }
            /* The default on the last help line if it fits in 79 columns. */
            if (o->shown_default) {
                if (20 + line + 10 + strlen(o->shown_default) <= 79)
                    fprintf(out, "; default %s", o->shown_default);
                else
                    fprintf(out, "\n%20sdefault %s", "", o->shown_default);
            }
            fputc('\n', out);
        }
    fprintf(out, "%-20s%s\n", "  --help", "this text");
}

int cli_wants_help(int argc, char **argv)
{
    for (int i = 1; i < argc; i++)
        if (strcmp(argv[i], "--help") == 0 || strcmp(argv[i], "-h") == 0) return 1;
    return 0;
}

char *cli_command_line(int argc, char **argv)
{
    if (argc <= 0) return bkf_io_command_line(0, NULL);
    const char **words = malloc((size_t)argc * sizeof *words);
    if (!words) return NULL;
    for (int i = 0; i < argc; i++) words[i] = argv[i];
    /* The program's name, not wherever it happened to be run from. */
    const char *slash = strrchr(argv[0], '/');
    if (slash) words[0] = slash + 1;
    char *line = bkf_io_command_line(argc, words);
    free(words);
    return line;
}


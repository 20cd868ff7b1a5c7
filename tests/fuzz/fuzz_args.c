/* libFuzzer target: the CLI's value and flag parsers (src/cli/args.c).
 *
 * The first byte picks the parser and its options, the rest is the text.
 * Besides "no crash, no sanitizer report", each accepted value is checked
 * against the parser's contract (args.h): finite numbers, counts in range,
 * range ends exact and points finite (geometric ones positive), and every
 * rejection is a one-line message without control characters. */
#include "fuzz_common.h"

#include <math.h>

#include "args.h"

static void fuzz_double(const char *text)
{
    bkf_error e = {0};
    double x = 12345;
    int s = cli_parse_double("--x", text, &x, &e);
    fuzz_check_status(s, &e);
    if (s == BKF_OK) {
        FUZZ_CHECK(isfinite(x));
        FUZZ_CHECK(strspn(text, "0123456789+-.eE") == strlen(text));
    } else
        FUZZ_CHECK(x == 12345);
}

static void fuzz_count(const char *text, size_t max)
{
    bkf_error e = {0};
    size_t n = 0;
    int s = cli_parse_count("--n", text, max, &n, &e);
    fuzz_check_status(s, &e);
    if (s == BKF_OK) {
        FUZZ_CHECK(n >= 1 && n <= max);
        /* the digits, read independently */
        char buf[32];
        snprintf(buf, sizeof buf, "%zu", n);
        const char *t = text;
        while (*t == '0' && t[1]) t++;
        FUZZ_CHECK(strcmp(buf, t) == 0);
    }
}

static void fuzz_range(const char *text, int geometric)
{
    bkf_error e = {0};
    cli_range r;
    int s = cli_parse_range("--mu", text, geometric, &r, &e);
    fuzz_check_status(s, &e);
    if (s == BKF_OK) {
        FUZZ_CHECK(r.values && r.count >= 1 && r.count <= CLI_MAX_POINTS);
        FUZZ_CHECK(r.values[0] == r.from && r.values[r.count - 1] == r.to);
        /* one grammar: A:B:N and comma lists are ranges (options.h) */
        FUZZ_CHECK(r.is_range == (strchr(text, ':') != NULL || strchr(text, ',') != NULL));
        for (size_t i = 0; i < r.count; i++) {
            FUZZ_CHECK(isfinite(r.values[i]));
            if (geometric) FUZZ_CHECK(r.values[i] > 0);
        }
    } else
        FUZZ_CHECK(r.values == NULL && r.count == 0);
    cli_range_free(&r);
}

static void fuzz_choice(const char *text)
{
    static const char *const choices[] = {"tsv", "json", "text", NULL};
    bkf_error e = {0};
    int k = -1;
    int s = cli_parse_choice("--format", text, choices, &k, &e);
    fuzz_check_status(s, &e);
    if (s == BKF_OK) FUZZ_CHECK(k >= 0 && k < 3 && strcmp(choices[k], text) == 0);
}

/* The text split at newlines is an argument vector. */
static void fuzz_flags(char *text)
{
    char *argv[64];
    int argc = 0;
    argv[argc++] = "period";
    for (char *p = text; argc < 63;) {
        argv[argc++] = p;
        char *nl = strchr(p, '\n');
        if (!nl) break;
        *nl = '\0';
        p = nl + 1;
    }
    argv[argc] = NULL;
    const char *mu = NULL, *nu = NULL;
    int log_ = 0, seen_mu = 0;
    const cli_flag flags[] = {
        {"--mu", &mu, "M or A:B:N", &seen_mu},
        {"--nu", &nu, "V", NULL},
        {"--log", NULL, NULL, &log_},
    };
    bkf_error e = {0};
    int s = cli_parse_flags(flags, 3, argc, argv, &e);
    fuzz_check_status(s, &e);
    if (s == BKF_OK) {
        FUZZ_CHECK(!mu == !seen_mu);
        /* every accepted value is one of the arguments or inside one */
        for (const char *v = mu; v; v = NULL) {
            int inside = 0;
            for (int i = 1; i < argc; i++)
                inside |= v >= argv[i] && v <= argv[i] + strlen(argv[i]);
            FUZZ_CHECK(inside);
        }
    }
    (void)cli_wants_help(argc, argv);
    char *line = cli_command_line(argc, argv);
    FUZZ_CHECK(line != NULL);
    for (const unsigned char *p = (const unsigned char *)line; *p; p++)
        FUZZ_CHECK(*p >= 0x20 && *p != 0x7f);
    free(line);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 1) return 0;
    unsigned op = data[0];
    char *text = fuzz_string(data + 1, size - 1);
    switch (op % 6) {
    case 0: fuzz_double(text); break;
    case 1: fuzz_count(text, (op & 0x80) ? CLI_MAX_POINTS : (size_t)(op >> 3) + 1); break;
    case 2: fuzz_range(text, 0); break;
    case 3: fuzz_range(text, 1); break;
    case 4: fuzz_choice(text); break;
    default: fuzz_flags(text); break;
    }
    free(text);
    return 0;
}

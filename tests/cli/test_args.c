/* The CLI's strict option parsing: what is a number, a count, a range.
 *
 * args.c belongs to the CLI, not to libbkfront; the test binary links the
 * CLI's objects (all but main) beside the library. */
#define _POSIX_C_SOURCE 200809L
#include "args.h"

#include "harness.h"

#include <string.h>

static int parses(const char *text, double *x)
{
    bkf_error e = {0};
    return cli_parse_double("--mu", text, x, &e) == BKF_OK;
}

static void check_rejected(const char *text)
{
    double x = 12345;
    bkf_error e = {0};
    int s = cli_parse_double("--mu", text, &x, &e);
    CHECK_MSG(s == BKF_EINPUT, "'%s' was accepted as %.17g", text, x);
    CHECK_MSG(x == 12345, "'%s' wrote the output on failure", text);
    CHECK_MSG(strncmp(e.message, "--mu: ", 6) == 0, "message does not name the flag: %s",
              e.message);
    CHECK_MSG(!strchr(e.message, '\n'), "message is not one line: %s", e.message);
}

TEST(args_double_accepts_decimal_forms)
{
    double x;
    CHECK(parses("1", &x) && x == 1);
    CHECK(parses("-0.96", &x) && x == -0.96);
    CHECK(parses("+2.5", &x) && x == 2.5);
    CHECK(parses("1e-3", &x) && x == 1e-3);
    CHECK(parses("1E+4", &x) && x == 1e4);
    CHECK(parses(".5", &x) && x == 0.5);
    CHECK(parses("5.", &x) && x == 5);
    CHECK(parses("-0", &x) && x == 0 && signbit(x));
    CHECK(parses("0.1", &x) && x == 0.1);
    CHECK(parses("1.7976931348623157e308", &x) && x == 1.7976931348623157e308);
    /* Underflow is a tiny number, not an error; range checks judge it. */
    CHECK(parses("1e-400", &x) && x == 0);
}

TEST(args_double_rejects_everything_else)
{
    const char *bad[] = {"", " ", "abc", "1e", "1e+", "1.2.3", "--1", "1-", "+", "-", ".",
                         "e5", " 1", "1 ", "1\n", "0x10", "0x1p3", "1,5", "1_000", "nan",
                         "NaN", "-nan", "nan(1)", "inf", "-inf", "Infinity", "INF", "1e999",
                         "-1e400", "1f", "1d", "2i"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) check_rejected(bad[i]);
}

TEST(args_double_messages)
{
    double x;
    bkf_error e = {0};
    cli_parse_double("--mu", "abc", &x, &e);
    CHECK_MSG(strncmp(e.message, "--mu: 'abc' is not a number", 27) == 0, "%s", e.message);
    cli_parse_double("--nu", "nan", &x, &e);
    CHECK_MSG(strstr(e.message, "--nu: 'nan' is not a finite number"), "%s", e.message);
    cli_parse_double("--tol", "1e999", &x, &e);
    CHECK_MSG(strstr(e.message, "--tol: '1e999' is too large"), "%s", e.message);
    /* Control characters in the echoed text must not split the line. */
    cli_parse_double("--mu", "1\n2", &x, &e);
    CHECK_MSG(!strchr(e.message, '\n') && strstr(e.message, "'1?2'"), "%s", e.message);
}

TEST(args_count)
{
    size_t n = 0;
    bkf_error e = {0};
    CHECK_STATUS(cli_parse_count("--n", "1", 10, &n, &e), BKF_OK);
    CHECK(n == 1);
    CHECK_STATUS(cli_parse_count("--n", "10", 10, &n, &e), BKF_OK);
    CHECK(n == 10);
    const char *bad[] = {"0", "11", "-1", "+1", "1.0", "1e1", "", " 1", "a",
                         "99999999999999999999999999"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        n = 77;
        CHECK_MSG(cli_parse_count("--n", bad[i], 10, &n, &e) == BKF_EINPUT, "'%s' accepted",
                  bad[i]);
        CHECK(n == 77);
        CHECK_MSG(strstr(e.message, "--n: ") && strstr(e.message, "[1, 10]"), "%s", e.message);
    }
}

TEST(args_choice)
{
    static const char *const choices[] = {"tsv", "json", NULL};
    int k = -1;
    bkf_error e = {0};
    CHECK_STATUS(cli_parse_choice("--format", "json", choices, &k, &e), BKF_OK);
    CHECK(k == 1);
    CHECK_STATUS(cli_parse_choice("--format", "JSON", choices, &k, &e), BKF_EINPUT);
    CHECK_MSG(strstr(e.message, "--format: 'JSON' is not one of tsv, json"), "%s", e.message);
}

TEST(args_range_single_and_linear)
{
    cli_range r;
    bkf_error e = {0};
    CHECK_STATUS(cli_parse_range("--nu", "-0.5", 0, &r, &e), BKF_OK);
    CHECK(r.count == 1 && r.values[0] == -0.5 && !r.is_range);
    CHECK(r.from == -0.5 && r.to == -0.5);
    cli_range_free(&r);

    CHECK_STATUS(cli_parse_range("--nu", "0:1:5", 0, &r, &e), BKF_OK);
    CHECK(r.count == 5 && r.is_range);
    double want[] = {0, 0.25, 0.5, 0.75, 1};
    for (size_t i = 0; i < 5; i++) CHECK(r.values[i] == want[i]);
    cli_range_free(&r);

    /* Downward, ends exact even when the step is not representable. */
    CHECK_STATUS(cli_parse_range("--nu", "0.9:-0.3:7", 0, &r, &e), BKF_OK);
    CHECK(r.count == 7 && r.values[0] == 0.9 && r.values[6] == -0.3);
    for (size_t i = 1; i < 7; i++) CHECK(r.values[i] < r.values[i - 1]);
    CHECK_CLOSE(r.values[3], 0.3, 1e-15, 1e-15);
    cli_range_free(&r);

    CHECK_STATUS(cli_parse_range("--nu", "0.3:0.3:1", 0, &r, &e), BKF_OK);
    CHECK(r.count == 1 && r.values[0] == 0.3 && r.is_range);
    cli_range_free(&r);

    /* Ends of opposite sign near the largest double must not overflow. */
    CHECK_STATUS(cli_parse_range("--x", "-1.7e308:1.7e308:3", 0, &r, &e), BKF_OK);
    CHECK(isfinite(r.values[1]) && fabs(r.values[1]) < 1e300);
    cli_range_free(&r);
}

TEST(args_range_geometric)
{
    cli_range r;
    bkf_error e = {0};
    CHECK_STATUS(cli_parse_range("--mu", "1e-1:1e4:6", 1, &r, &e), BKF_OK);
    CHECK(r.count == 6 && r.values[0] == 0.1 && r.values[5] == 1e4);
    for (size_t i = 1; i < 5; i++) CHECK_CLOSE(r.values[i], pow(10.0, (double)i - 1), 1e-14, 0);
    cli_range_free(&r);

    CHECK_STATUS(cli_parse_range("--mu", "100:1:3", 1, &r, &e), BKF_OK);
    CHECK(r.values[0] == 100 && r.values[2] == 1);
    CHECK_CLOSE(r.values[1], 10, 1e-15, 0);
    cli_range_free(&r);

    CHECK_STATUS(cli_parse_range("--mu", "2", 1, &r, &e), BKF_OK);
    CHECK(r.count == 1 && r.values[0] == 2);
    cli_range_free(&r);

    const char *bad[] = {"0:1:3", "-1:1:3", "1:0:3", "1:-2:3", "0", "-2"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        CHECK_MSG(cli_parse_range("--mu", bad[i], 1, &r, &e) == BKF_EINPUT,
                  "'%s' accepted as a geometric range", bad[i]);
        CHECK(r.values == NULL && r.count == 0);
        CHECK_MSG(strncmp(e.message, "--mu: ", 6) == 0 && strstr(e.message, "> 0"), "%s",
                  e.message);
    }
}

TEST(args_range_rejects_malformed)
{
    cli_range r;
    bkf_error e = {0};
    const char *bad[] = {"", ":", "1:2", "1:2:", "1::3", ":2:3", "1:2:3:4", "1:2:0",
                         "1:2:-1", "1:2:2.5", "1:2:1e1", "1:2:1", "a:2:3", "1:b:3",
                         "1:2:c", "nan:1:3", "1:inf:3", "1:2:1000001", "1:2: 3",
                         "1:2:99999999999999999999999"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        CHECK_MSG(cli_parse_range("--nu", bad[i], 0, &r, &e) == BKF_EINPUT,
                  "'%s' accepted as a range", bad[i]);
        CHECK(r.values == NULL);
        CHECK_MSG(strncmp(e.message, "--nu: ", 6) == 0 && !strchr(e.message, '\n'), "%s",
                  e.message);
    }
    cli_parse_range("--nu", "1:2:1", 0, &r, &e);
    CHECK_MSG(strstr(e.message, "N = 1") && strstr(e.message, "equal"), "%s", e.message);
    cli_parse_range("--nu", "1:x:3", 0, &r, &e);
    CHECK_MSG(strstr(e.message, "'x' in '1:x:3' is not a number"), "%s", e.message);
}

TEST(args_flags)
{
    const char *mu = NULL, *nu = NULL;
    int log = 0, seen_mu = 0;
    const cli_flag flags[] = {
        {"--mu", &mu, "M", &seen_mu},
        {"--nu", &nu, "V", NULL},
        {"--log", NULL, NULL, &log},
    };
    bkf_error e = {0};
    char *ok[] = {"period", "--mu", "1", "--nu=-0.5", "--log", NULL};
    CHECK_STATUS(cli_parse_flags(flags, 3, 5, ok, &e), BKF_OK);
    CHECK(mu && strcmp(mu, "1") == 0 && nu && strcmp(nu, "-0.5") == 0 && log && seen_mu);

    /* A value is the next argument even when it looks like an option. */
    mu = NULL;
    char *neg[] = {"period", "--mu", "-1", NULL};
    CHECK_STATUS(cli_parse_flags(flags, 3, 3, neg, &e), BKF_OK);
    CHECK(mu && strcmp(mu, "-1") == 0);

    struct {
        char *argv[4];
        int argc;
        const char *want;
    } bad[] = {
        {{"p", "--bogus", NULL}, 2, "unknown option '--bogus'"},
        {{"p", "--mu", NULL}, 2, "--mu: missing value (expected M)"},
        {{"p", "--mu", "1", "--mu=2"}, 4, "--mu: given twice"},
        {{"p", "--log=1", NULL}, 2, "--log: takes no value"},
        {{"p", "stray", NULL}, 2, "unexpected argument 'stray'"},
        {{"p", "-m", NULL}, 2, "unexpected argument '-m'"},
        {{"p", "--", NULL}, 2, "unexpected argument '--'"},
        {{"p", "--m", NULL}, 2, "unknown option '--m'"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        log = 0;
        CHECK_MSG(cli_parse_flags(flags, 3, bad[i].argc, bad[i].argv, &e) == BKF_EINPUT,
                  "case %zu accepted", i);
        CHECK_MSG(strstr(e.message, bad[i].want), "case %zu: %s", i, e.message);
    }
    cli_parse_flags(flags, 3, 2, bad[0].argv, &e);
    CHECK_MSG(strstr(e.message, "--mu, --nu, --log"), "%s", e.message);
}

TEST(args_help_and_command_line)
{
    char *a[] = {"period", "--mu", "1", "--help", NULL};
    char *b[] = {"period", "--mu", "1", NULL};
    CHECK(cli_wants_help(4, a));
    CHECK(!cli_wants_help(3, b));

    char *c[] = {"/usr/bin/bkfront", "period", "--mu", "1:2:3", "--out", "my file's.tsv", "",
                 NULL};
    char *line = cli_command_line(7, c);
    CHECK(line);
    CHECK_MSG(strcmp(line, "bkfront period --mu 1:2:3 --out 'my file'\\''s.tsv' ''") == 0,
              "%s", line);
    free(line);
}

typedef struct {
    int log;
    bkf_list mu;
    double tol;
    const char *out;
} opt_spec;

static const bkf_option opt_table[] = {
    {.name = "log", .type = BKF_OPT_SWITCH, .offset = offsetof(opt_spec, log),
     .help = "geometric --mu"},
    {.name = "mu", .type = BKF_OPT_DOUBLE_LIST, .offset = offsetof(opt_spec, mu),
     .flags = BKF_OPT_REQUIRED | BKF_OPT_MIN | BKF_OPT_MAX | BKF_OPT_LOG_SWITCH, .min = 1e-6,
     .max = 1e6, .log_offset = offsetof(opt_spec, log), .form = "LIST",
     .help = "mu values\nsecond line"},
    {.name = "tol", .type = BKF_OPT_DOUBLE, .offset = offsetof(opt_spec, tol),
     .flags = BKF_OPT_MIN | BKF_OPT_MAX, .min = 1e-14, .max = 0.1, .form = "E",
     .shown_default = "1e-10", .help = "accuracy"},
    {.name = "scene-key", .type = BKF_OPT_TEXT, .offset = offsetof(opt_spec, out),
     .flags = BKF_OPT_SCENE_ONLY},
};

TEST(args_options_from_a_table)
{
    opt_spec sp = {.tol = 1e-10};
    cli_options g = {opt_table, sizeof opt_table / sizeof opt_table[0], &sp};
    bkf_error e = {0};
    int help = 0;
    /* --log after --mu on the line still makes the list geometric: values
     * are applied in table order. */
    char *ok[] = {"period", "--mu", "1:100:3", "--log", NULL};
    CHECK_STATUS(cli_parse_options(&g, 1, 4, ok, &help, &e), BKF_OK);
    CHECK(sp.log && sp.mu.count == 3 && sp.mu.values[2] == 100 && !help);
    CHECK_CLOSE(sp.mu.values[1], 10, 1e-15, 0);
    CHECK(sp.tol == 1e-10);
    bkf_option_free_lists(opt_table, g.n, &sp);

    opt_spec sq = {0};
    g.spec = &sq;
    char *missing[] = {"period", "--tol", "1e-8", NULL};
    CHECK_STATUS(cli_parse_options(&g, 1, 3, missing, &help, &e), BKF_EINPUT);
    CHECK_MSG(strstr(e.message, "--mu is required (V, V1,V2,... or A:B:N, each in [1e-06, 1e+06])"), "%s", e.message);
    char *bad[] = {"period", "--mu", "1", "--tol", "1", NULL};
    CHECK_STATUS(cli_parse_options(&g, 1, 5, bad, &help, &e), BKF_EINPUT);
    CHECK_MSG(strstr(e.message, "--tol: 1 is not in [1e-14, 0.1]"), "%s", e.message);
    bkf_option_free_lists(opt_table, g.n, &sq);
    char *scene_only[] = {"period", "--scene-key", "x", NULL};
    CHECK_STATUS(cli_parse_options(&g, 1, 3, scene_only, &help, &e), BKF_EINPUT);
    CHECK_MSG(strstr(e.message, "unknown option '--scene-key'"), "%s", e.message);
    char *h[] = {"period", "--help", NULL};
    CHECK_STATUS(cli_parse_options(&g, 1, 2, h, &help, &e), BKF_EINPUT);
    CHECK_MSG(help == 1, "%s", e.message);

    char *text = NULL;
    size_t size = 0;
    FILE *f = open_memstream(&text, &size);
    cli_options_help(f, &g, 1);
    fclose(f);
    CHECK_MSG(strstr(text, "  --log             geometric --mu\n"), "%s", text);
    CHECK_MSG(strstr(text, "  --mu LIST         mu values\n                    second line\n"),
              "%s", text);
    CHECK_MSG(strstr(text, "  --tol E           accuracy; default 1e-10\n"), "%s", text);
    CHECK_MSG(!strstr(text, "scene-key") && strstr(text, "  --help"), "%s", text);
    free(text);
}

/* The option table (bkfront/options.h): each type's good and bad values, the
 * list grammar, and the shortest round-trip number format. */
#include "bkfront/options.h"

#include "harness.h"

#include <stddef.h>
#include <stdint.h>
#include <string.h>

typedef struct {
    int log;
    double tol, nu;
    size_t points;
    bkf_list mu, n, eps;
    int format;
    const char *out;
    uint64_t seed;
    double lo, hi;
} spec_t;

static const char *const formats[] = {"tsv", "json", NULL};

static int set_window(void *spec, const char *text, bkf_error *err)
{
    spec_t *s = spec;
    double lo, hi;
    char tail;
    if (sscanf(text, "%lf/%lf%c", &lo, &hi, &tail) != 2 || !(lo < hi))
        return bkf_error_set(err, BKF_EINPUT, "'%s' is not LO/HI with LO < HI", text);
    s->lo = lo;
    s->hi = hi;
    return BKF_OK;
}

static const bkf_option table[] = {
    {.name = "log", .type = BKF_OPT_SWITCH, .offset = offsetof(spec_t, log)},
    {.name = "tol", .type = BKF_OPT_DOUBLE, .offset = offsetof(spec_t, tol),
     .flags = BKF_OPT_MIN | BKF_OPT_MAX, .min = 1e-14, .max = 0.1},
    {.name = "nu", .type = BKF_OPT_DOUBLE, .offset = offsetof(spec_t, nu),
     .flags = BKF_OPT_MIN | BKF_OPT_MAX | BKF_OPT_MIN_OPEN | BKF_OPT_MAX_OPEN, .min = -1,
     .max = 1},
    {.name = "points", .type = BKF_OPT_COUNT, .offset = offsetof(spec_t, points),
     .flags = BKF_OPT_MIN | BKF_OPT_MAX, .min = 2, .max = 100},
    {.name = "mu", .type = BKF_OPT_DOUBLE_LIST, .offset = offsetof(spec_t, mu),
     .flags = BKF_OPT_MIN | BKF_OPT_MAX | BKF_OPT_LOG_SWITCH, .min = 1e-6, .max = 1e6,
     .log_offset = offsetof(spec_t, log)},
    {.name = "n", .type = BKF_OPT_COUNT_LIST, .offset = offsetof(spec_t, n),
     .flags = BKF_OPT_MAX, .max = 1000, .max_count = 50},
    {.name = "eps", .type = BKF_OPT_DOUBLE_LIST, .offset = offsetof(spec_t, eps),
     .flags = BKF_OPT_GEOMETRIC},
    {.name = "format", .type = BKF_OPT_CHOICE, .offset = offsetof(spec_t, format),
     .choices = formats},
    {.name = "out", .type = BKF_OPT_TEXT, .offset = offsetof(spec_t, out)},
    {.name = "seed", .type = BKF_OPT_SEED, .offset = offsetof(spec_t, seed)},
    {.name = "window", .type = BKF_OPT_CUSTOM, .set = set_window, .form = "LO/HI"},
};
#define NTABLE (sizeof table / sizeof table[0])

static int apply(spec_t *s, const char *name, const char *text, bkf_error *e)
{
    const bkf_option *o = bkf_option_find(table, NTABLE, name);
    CHECK_MSG(o, "no option %s", name);
    return bkf_option_apply(o, s, text, "--", e);
}

/* Refused, with a one-line message that starts with the key and contains
 * `want`; the field is left as it was. */
static void refused(const char *name, const char *text, const char *want)
{
    spec_t s, before;
    memset(&s, 0, sizeof s);
    s.tol = s.nu = 7;
    s.points = 7;
    s.format = 7;
    s.seed = 7;
    memcpy(&before, &s, sizeof s);
    bkf_error e = {0};
    int st = apply(&s, name, text, &e);
    CHECK_MSG(st == BKF_EINPUT, "--%s '%s' accepted", name, text);
    char head[64];
    snprintf(head, sizeof head, "--%s: ", name);
    CHECK_MSG(strncmp(e.message, head, strlen(head)) == 0, "'%s' not first in: %s", head,
              e.message);
    CHECK_MSG(strstr(e.message, want), "--%s '%s': '%s' not in: %s", name, text, want,
              e.message);
    CHECK_MSG(!strchr(e.message, '\n'), "not one line: %s", e.message);
    CHECK(memcmp(&s, &before, sizeof s) == 0);
}

TEST(options_scalars_good)
{
    spec_t s = {0};
    bkf_error e = {0};
    CHECK_STATUS(apply(&s, "log", NULL, &e), BKF_OK);
    CHECK(s.log == 1);
    CHECK_STATUS(apply(&s, "tol", "1e-14", &e), BKF_OK);
    CHECK(s.tol == 1e-14);
    CHECK_STATUS(apply(&s, "tol", "0.1", &e), BKF_OK);
    CHECK(s.tol == 0.1);
    CHECK_STATUS(apply(&s, "nu", "-0.96", &e), BKF_OK);
    CHECK(s.nu == -0.96);
    CHECK_STATUS(apply(&s, "points", "2", &e), BKF_OK);
    CHECK(s.points == 2);
    CHECK_STATUS(apply(&s, "points", "100", &e), BKF_OK);
    CHECK(s.points == 100);
    CHECK_STATUS(apply(&s, "format", "json", &e), BKF_OK);
    CHECK(s.format == 1);
    CHECK_STATUS(apply(&s, "out", "x.tsv", &e), BKF_OK);
    CHECK(s.out && strcmp(s.out, "x.tsv") == 0);
    CHECK_STATUS(apply(&s, "seed", "18446744073709551615", &e), BKF_OK);
    CHECK(s.seed == UINT64_MAX);
    CHECK_STATUS(apply(&s, "seed", "0", &e), BKF_OK);
    CHECK(s.seed == 0);
    CHECK_STATUS(apply(&s, "window", "1/2", &e), BKF_OK);
    CHECK(s.lo == 1 && s.hi == 2);
}

TEST(options_scalars_bad_name_key_and_range)
{
    refused("log", "1", "takes no value");
    refused("tol", "1", "1 is not in [1e-14, 0.1]");
    refused("tol", "1e-15", "[1e-14, 0.1]");
    refused("tol", "abc", "'abc' is not a number");
    refused("tol", "nan", "not a finite number");
    refused("tol", "1e999", "too large");
    refused("tol", NULL, "missing value");
    refused("nu", "1", "1 is not in (-1, 1)");
    refused("nu", "-1", "(-1, 1)");
    refused("points", "1", "not an integer in [2, 100]");
    refused("points", "101", "[2, 100]");
    refused("points", "2.0", "[2, 100]");
    refused("points", "-3", "[2, 100]");
    refused("format", "csv", "'csv' is not one of tsv, json");
    refused("out", "", "empty");
    refused("seed", "18446744073709551616", "not an integer in [0, 18446744073709551615]");
    refused("seed", "-1", "[0, ");
    refused("window", "2/1", "'2/1' is not LO/HI");
}

TEST(options_prefix_for_scenes)
{
    spec_t s = {0};
    bkf_error e = {0};
    const bkf_option *o = bkf_option_find(table, NTABLE, "tol");
    CHECK_STATUS(bkf_option_apply(o, &s, "2", "paper.scene:12: ", &e), BKF_EINPUT);
    CHECK_MSG(strncmp(e.message, "paper.scene:12: tol: 2 is not in", 32) == 0, "%s", e.message);
    CHECK_STATUS(bkf_option_apply(o, &s, "2", "", &e), BKF_EINPUT);
    CHECK_MSG(strncmp(e.message, "tol: ", 5) == 0, "%s", e.message);
    CHECK(bkf_option_find(table, NTABLE, "bogus") == NULL);
}

TEST(options_lists_every_form)
{
    spec_t s = {0};
    bkf_error e = {0};
    CHECK_STATUS(apply(&s, "mu", "2", &e), BKF_OK);
    CHECK(s.mu.count == 1 && s.mu.values[0] == 2 && !s.mu.is_range);
    CHECK_STATUS(apply(&s, "mu", "0.5,5", &e), BKF_OK);
    CHECK(s.mu.count == 2 && s.mu.values[0] == 0.5 && s.mu.values[1] == 5);
    CHECK(s.mu.from == 0.5 && s.mu.to == 5);
    /* Linear: ends exact even where the step is not a double. */
    CHECK_STATUS(apply(&s, "mu", "0.1:0.7:7", &e), BKF_OK);
    CHECK(s.mu.count == 7 && s.mu.values[0] == 0.1 && s.mu.values[6] == 0.7);
    for (size_t i = 0; i < 7; i++) CHECK_CLOSE(s.mu.values[i], 0.1 * (double)(i + 1), 1e-15, 0);
    /* Geometric through the log switch. */
    s.log = 1;
    CHECK_STATUS(apply(&s, "mu", "0.1:1000:5", &e), BKF_OK);
    CHECK(s.mu.values[0] == 0.1 && s.mu.values[4] == 1000);
    for (size_t i = 1; i < 4; i++) CHECK_CLOSE(s.mu.values[i], pow(10.0, (double)i - 1), 1e-14, 0);
    /* Always-geometric entry. */
    CHECK_STATUS(apply(&s, "eps", "1e-4:1e-1:4", &e), BKF_OK);
    CHECK_CLOSE(s.eps.values[1], 1e-3, 1e-14, 0);
    CHECK(s.eps.values[3] == 1e-1);
    bkf_option_free_lists(table, NTABLE, &s);
    CHECK(s.mu.values == NULL && s.eps.values == NULL);
}

TEST(options_integer_lists)
{
    spec_t s = {0};
    bkf_error e = {0};
    /* The case `profile --n 1:10:10` used to refuse: the weighted sum gave
     * 3.9999999999999996 for the fourth point. */
    CHECK_STATUS(apply(&s, "n", "1:10:10", &e), BKF_OK);
    CHECK(s.n.count == 10);
    for (size_t i = 0; i < 10; i++) CHECK(s.n.values[i] == (double)(i + 1));
    CHECK_STATUS(apply(&s, "n", "10:1:4", &e), BKF_OK);
    CHECK(s.n.count == 4 && s.n.values[1] == 7 && s.n.values[2] == 4 && s.n.values[3] == 1);
    CHECK_STATUS(apply(&s, "n", "3,1,7", &e), BKF_OK);
    CHECK(s.n.count == 3 && s.n.values[0] == 3 && s.n.values[2] == 7);
    CHECK_STATUS(apply(&s, "n", "5", &e), BKF_OK);
    CHECK(s.n.count == 1 && s.n.values[0] == 5);
    bkf_option_free_lists(table, NTABLE, &s);

    refused("n", "1:10:3", "does not step by an integer");
    refused("n", "1.5:3:2", "integers");
    refused("n", "0", "n = 0 is not in [1, 1000]");
    refused("n", "1,2000", "n = 2000 (in '1,2000') is not in [1, 1000]");
    refused("n", "1:51:51", "[1, 50]");     /* the entry's cap on values */
    refused("n", "1,2.5", "'2.5' is not an integer");
}

TEST(options_lists_refused)
{
    refused("mu", "", "is not a number");
    refused("mu", "1:2", "is not a number or a range A:B:N");
    refused("mu", "1:2:3:4", "A:B:N");
    refused("mu", "1:2:0", "N = '0' in '1:2:0' is not an integer in [1, 1000000]");
    refused("mu", "1:2:1000001", "[1, 1000000]");
    refused("mu", "1:2:1", "N = 1 point, so A and B must be equal");
    refused("mu", "1:x:3", "'x' in '1:x:3' is not a number");
    refused("mu", "1,,2", "empty item");
    refused("mu", "1,2:3:3", "is not a number or a range");
    refused("mu", "1,nan", "'nan' in '1,nan' is not a finite number");
    refused("mu", "0", "mu = 0 is not in [1e-06, 1e+06]");
    refused("mu", "1:2e6:3", "mu = 1000000.5 (in '1:2e6:3') is not in [1e-06, 1e+06]");
    refused("eps", "0:1:3", "> 0");
    refused("eps", "1,-2", "'-2' in '1,-2' is not > 0");
    refused("eps", "-1", "> 0");
}

TEST(options_list_cap_on_comma_lists)
{
    /* 1000001 items, each "1": one more than BKF_LIST_MAX. */
    size_t n = (size_t)BKF_LIST_MAX + 1;
    char *text = malloc(2 * n);
    CHECK(text);
    for (size_t i = 0; i < n; i++) {
        text[2 * i] = '1';
        text[2 * i + 1] = ',';
    }
    text[2 * n - 1] = '\0';
    bkf_list l;
    bkf_error e = {0};
    CHECK_STATUS(bkf_list_parse(text, 0, 0, 0, "", "x", &l, &e), BKF_EINPUT);
    CHECK_MSG(strstr(e.message, "x: more than 1000000 values"), "%s", e.message);
    CHECK(l.values == NULL && l.count == 0);
    text[2 * n - 3] = '\0'; /* now exactly the cap */
    CHECK_STATUS(bkf_list_parse(text, 0, 0, 0, "", "x", &l, &e), BKF_OK);
    CHECK(l.count == BKF_LIST_MAX && l.to == 1);
    bkf_list_free(&l);
    free(text);
}

TEST(options_describe)
{
    char buf[160];
    CHECK_MSG(strcmp(bkf_option_describe(&table[2], buf, sizeof buf), "a number in (-1, 1)") == 0,
              "%s", buf);
    CHECK_MSG(strcmp(bkf_option_describe(&table[7], buf, sizeof buf), "one of tsv, json") == 0,
              "%s", buf);
    CHECK_MSG(strstr(bkf_option_describe(&table[4], buf, sizeof buf), "[1e-06, 1e+06]"), "%s",
              buf);
}

/* xorshift64*: reproducible doubles over every exponent and mantissa. */
static uint64_t next(uint64_t *s)
{
    *s ^= *s >> 12;
    *s ^= *s << 25;
    *s ^= *s >> 27;
    return *s * 2685821657736338717ull;
}

TEST(options_shortest_number_round_trips)
{
    char buf[40], shorter[400];
    bkf_format_number(0.3, buf, sizeof buf);
    CHECK_MSG(strcmp(buf, "0.3") == 0, "%s", buf);
    bkf_format_number(0.1 + 0.2, buf, sizeof buf);
    CHECK_MSG(strcmp(buf, "0.30000000000000004") == 0, "%s", buf);
    bkf_format_number(-0.96, buf, sizeof buf);
    CHECK_MSG(strcmp(buf, "-0.96") == 0, "%s", buf);
    bkf_format_number(1e-8, buf, sizeof buf);
    CHECK_MSG(strcmp(buf, "1e-08") == 0, "%s", buf);
    bkf_format_number(100, buf, sizeof buf);
    CHECK_MSG(strcmp(buf, "100") == 0, "%s", buf); /* not 1e+02 */
    bkf_format_number(123456789012345, buf, sizeof buf);
    CHECK_MSG(strcmp(buf, "123456789012345") == 0, "%s", buf);
    bkf_format_number(1e20, buf, sizeof buf);
    CHECK_MSG(strcmp(buf, "1e+20") == 0, "%s", buf);
    bkf_format_number(NAN, buf, sizeof buf);
    CHECK(strcmp(buf, "nan") == 0);
    bkf_format_number(-INFINITY, buf, sizeof buf);
    CHECK(strcmp(buf, "-inf") == 0);

    /* 25000 of each kind: every binary exponent about 12 times (2e5 took
     * 2.7 s of CPU for nothing the first 5e4 miss) */
    uint64_t state = 0x9E3779B97F4A7C15ull;
    for (int i = 0; i < 50000; i++) {
        uint64_t bits = next(&state);
        double x;
        if (i % 2) {
            memcpy(&x, &bits, sizeof x);
            if (!isfinite(x)) continue;
        } else {
            /* Short decimals, the common input: k / 10^d. */
            x = (double)(bits % 100000) / pow(10.0, (double)(bits >> 60));
        }
        bkf_format_number(x, buf, sizeof buf);
        CHECK_MSG(strtod(buf, NULL) == x && signbit(strtod(buf, NULL)) == signbit(x),
                  "%.17g printed as %s", x, buf);
        /* One digit fewer must not read back: independent of the loop in
         * bkf_format_number, count the significant digits printed (leading
         * and trailing zeros are not). */
        char sig[40];
        size_t ns = 0;
        for (const char *p = buf; *p && *p != 'e'; p++)
            if (*p >= '0' && *p <= '9' && (ns || *p != '0')) sig[ns++] = *p;
        while (ns && sig[ns - 1] == '0') ns--;
        int digits = (int)ns;
        if (digits > 1) {
            snprintf(shorter, sizeof shorter, "%.*g", digits - 1, x);
            CHECK_MSG(strtod(shorter, NULL) != x, "%.17g: %s is shorter than %s", x, shorter,
                      buf);
        }
    }
}

/* Timings in the manual cannot go stale (issue 33 item 6): a page quotes a
 * timing only through a row of docs/timings.md, the table `make bench` writes
 * (tests/bench/timings.sh) with its date and machine.  The rule, documented in
 * docs/testing.md ("Timings in the manual"):
 *
 * - the pages are README.md, CONTRIBUTING.md, docs/ *.md, docs/cli/ *.md (code
 *   blocks included: a progress line or a --help text quoting seconds goes
 *   stale as well) and the comments of fronts/ *.scene; docs/benchmarks.md
 *   (dated measurements, each section its own record) and docs/changelog.md
 *   (dated history) are the record, not the manual, and are not read;
 * - a timing is a number, or a range "A-B", "A–B", "A..B", "A to B", followed
 *   by a unit of time: s, ms, us, µs, ns, min, sec, second(s), minute(s),
 *   hour(s) ("s" after a space only, so that e^(2s) is no timing; "h" is a
 *   step length here, never a unit);
 * - it passes when its paragraph links a row of the table, as
 *   [timings: `KEY`](...timings.md), and that row's wall or CPU cell is the
 *   same text ("90.3 s"); a link naming no row fails too;
 * - a duration that is a setting, not a measurement (a time limit, a default,
 *   a poll interval, a test's requirement), is listed in `settings` below with
 *   its phrase; an entry whose phrase is no longer on its page fails, so the
 *   list cannot keep what the pages dropped.
 *
 * Re-running `make bench` rewrites the table: a page that copied a number
 * fails until it is copied again, a page that only links the row never does. */
#define _POSIX_C_SOURCE 200809L
#include "cli_support.h"
#include "harness.h"

#include <glob.h>
#include <stdarg.h>
#include <stdbool.h>
#include <string.h>

#ifndef BKF_SOURCE_DIR
#define BKF_SOURCE_DIR "."
#endif

/* Durations that are settings: the page, and the phrase around the number. */
static const struct {
    const char *page, *phrase, *why;
} settings[] = {
    {"docs/testing.md", "time limit (240 s", "the runner's default limit (tests/main.c)"},
    {"docs/testing.md", "raised to 7200 s", "BKF_TEST_TIME_LIMIT under valgrind (Makefile)"},
    {"docs/testing.md", "outgrew 240 s", "the same default"},
    {"docs/testing.md", "executions in 60 s", "FUZZ_SECONDS' default, the table's column"},
    {"docs/testing.md", "default 60 s per target", "FUZZ_SECONDS' default"},
    {"docs/testing.md", "within the poll of 5 ms", "bkfront run's poll of gnuplot (a constant)"},
    {"docs/cli/branch.md", "its goal of 5 s", "a goal, not a measurement"},
    {"docs/python.md", "within 0.5 s", "the test's requirement"},
    {"docs/cli/run.md", "at 0.05 .. 0.3 s into", "the delays the signal test sends at"},
    {"docs/cli/simulate.md", "has already taken 0.5 s", "the progress bar's delay (a constant)"},
    {"docs/cli/sweep.md", "(at most 10 s", "how long MPI ranks wait for mpirun's SIGKILL (sweep_mpi_end)"},
};
#define N_SETTINGS (sizeof settings / sizeof settings[0])

static bool word_char(unsigned char c)
{
    return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_' ||
           c >= 0x80;
}

static size_t number_at(const char *s)
{
    size_t i = 0;
    while (s[i] >= '0' && s[i] <= '9') i++;
    if (i && s[i] == '.' && s[i + 1] >= '0' && s[i + 1] <= '9') {
        i++;
        while (s[i] >= '0' && s[i] <= '9') i++;
    }
    return i;
}

/* A space: ' ' or U+00A0. */
static size_t space_at(const char *s)
{
    if (s[0] == ' ') return 1;
    if ((unsigned char)s[0] == 0xc2 && (unsigned char)s[1] == 0xa0) return 2;
    return 0;
}

/* Length of the timing that starts at s[0] (a digit not inside a word or a
 * number), or 0. */
static size_t timing_at(const char *text, const char *s)
{
    if (s > text) {
        unsigned char p = (unsigned char)s[-1];
        if (word_char(p) || p == '.' || p == '^' || p == '*' || p == '/' || p == '-' || p == '+') return 0;
    }
    size_t i = number_at(s);
    if (!i) return 0;
    /* a range: A-B, A–B, A .. B, A to B */
    static const char *const seps[] = {"-", "\xe2\x80\x93", "..", "to"};
    for (size_t k = 0; k < 4; k++) {
        size_t j = i + space_at(s + i);
        size_t n = strlen(seps[k]);
        if (strncmp(s + j, seps[k], n) != 0) continue;
        j += n;
        j += space_at(s + j);
        size_t m = number_at(s + j);
        if (m) {
            i = j + m;
            break;
        }
    }
    size_t sp = space_at(s + i);
    static const char *const units[] = {"minutes", "minute", "seconds", "second", "hours", "hour",
                                        "min", "sec", "ms", "us", "\xc2\xb5s", "ns", "s"};
    for (size_t k = 0; k < sizeof units / sizeof units[0]; k++) {
        size_t n = strlen(units[k]);
        if (strncmp(s + i + sp, units[k], n) != 0) continue;
        if (word_char((unsigned char)s[i + sp + n])) continue;
        if (!sp && strcmp(units[k], "s") == 0) return 0;   /* e^(2s), 2s-periodic */
        return i + sp + n;
    }
    return 0;
}

/* The timing's text as the table writes it: no '~', spaces plain. */
static void normalise(const char *s, size_t n, char *out, size_t cap)
{
    size_t o = 0;
    for (size_t i = 0; i < n && o + 1 < cap; i++) {
        if (s[i] == '~') continue;
        if ((unsigned char)s[i] == 0xc2 && i + 1 < n && (unsigned char)s[i + 1] == 0xa0) {
            out[o++] = ' ';
            i++;
            continue;
        }
        out[o++] = s[i];
    }
    out[o] = '\0';
}

typedef struct {
    char key[128];
    char wall[32], cpu[32];
} table_row;

#define MAX_ROWS 64
typedef struct {
    table_row rows[MAX_ROWS];
    size_t n;
} table;

static void trim_copy(const char *a, const char *b, char *out, size_t cap)
{
    while (a < b && *a == ' ') a++;
    while (b > a && b[-1] == ' ') b--;
    size_t n = (size_t)(b - a) < cap - 1 ? (size_t)(b - a) : cap - 1;
    memcpy(out, a, n);
    out[n] = '\0';
}

/* The rows "| KEY | what | WALL | CPU |" of the generated table. */
static table read_table(const char *text)
{
    table t = {.n = 0};
    for (const char *line = text; line && *line; line = strchr(line, '\n') ? strchr(line, '\n') + 1 : NULL) {
        if (strncmp(line, "| `", 3) != 0) continue;
        const char *bar[5];
        const char *p = line;
        size_t k = 0;
        while (k < 5 && (p = strchr(p, '|')) && p < (strchr(line, '\n') ? strchr(line, '\n') : line + strlen(line)))
            bar[k++] = p++;
        if (k < 5 || t.n == MAX_ROWS) continue;
        table_row *r = &t.rows[t.n++];
        trim_copy(bar[0] + 1, bar[1], r->key, sizeof r->key);
        trim_copy(bar[2] + 1, bar[3], r->wall, sizeof r->wall);
        trim_copy(bar[3] + 1, bar[4], r->cpu, sizeof r->cpu);
    }
    return t;
}

static const table_row *find_row(const table *t, const char *key)
{
    for (size_t i = 0; i < t->n; i++)
        if (strcmp(t->rows[i].key, key) == 0) return &t->rows[i];
    return NULL;
}

static size_t line_of(const char *text, const char *at)
{
    size_t line = 1;
    for (const char *p = text; p < at; p++) line += *p == '\n';
    return line;
}

/* Appends a failure line to the report (its size is bounded: the first 60). */
typedef struct {
    char text[16384];
    size_t used, count;
} report;

static void complain(report *r, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void complain(report *r, const char *fmt, ...)
{
    r->count++;
    if (r->count > 60 || r->used + 1 >= sizeof r->text) return;
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(r->text + r->used, sizeof r->text - r->used, fmt, ap);
    va_end(ap);
    if (n > 0) r->used = r->used + (size_t)n < sizeof r->text ? r->used + (size_t)n : sizeof r->text - 1;
}

/* Checks one page's text (a scene's non-comment lines already blanked):
 * every timing of a paragraph is a setting or a cell of a row the paragraph
 * links; `used[i]` marks the settings met. */
static void check_page(const char *page, const char *text, const table *t, bool *used, report *rep)
{
    const char *para = text;
    while (*para) {
        /* a paragraph ends at a blank line */
        const char *end = para;
        while (*end) {
            const char *nl = strchr(end, '\n');
            if (!nl) {
                end += strlen(end);
                break;
            }
            end = nl + 1;
            const char *q = end;
            while (*q == ' ' || *q == '\t') q++;
            if (*q == '\n' || !*q) break;
        }
        /* the rows it links */
        const table_row *linked[16];
        size_t n_linked = 0;
        static const char tag[] = "[timings: ";
        for (const char *p = para; (p = strstr(p, tag)) && p < end; p++) {
            const char *close = strstr(p, "](");
            const char *target_end = close ? strchr(close, ')') : NULL;
            if (!close || !target_end || target_end > end) continue;
            char key[128], target[256];
            trim_copy(p + strlen(tag), close, key, sizeof key);
            trim_copy(close + 2, target_end, target, sizeof target);
            if (!strstr(target, "timings.md")) continue;
            const table_row *r = find_row(t, key);
            if (!r)
                complain(rep, "%s:%zu: links [timings: %s], a row docs/timings.md does not have\n", page,
                         line_of(text, p), key);
            else if (n_linked < 16)
                linked[n_linked++] = r;
        }
        for (const char *p = para; p < end; p++) {
            if (*p < '0' || *p > '9') continue;
            size_t n = timing_at(text, p);
            if (!n) continue;
            bool ok = false;
            for (size_t i = 0; i < N_SETTINGS && !ok; i++) {
                if (strcmp(settings[i].page, page) != 0) continue;
                size_t plen = strlen(settings[i].phrase);
                for (const char *q = para; (q = strstr(q, settings[i].phrase)) && q < end; q++)
                    if (q <= p && p + n <= q + plen) {
                        ok = used[i] = true;
                        break;
                    }
            }
            char quoted[64];
            normalise(p, n, quoted, sizeof quoted);
            for (size_t i = 0; i < n_linked && !ok; i++)
                ok = strcmp(linked[i]->wall, quoted) == 0 || strcmp(linked[i]->cpu, quoted) == 0;
            if (!ok)
                complain(rep,
                         "%s:%zu: \"%s\" is a timing, and its paragraph links no row of docs/timings.md "
                         "that holds it\n",
                         page, line_of(text, p), quoted);
            p += n - 1;
        }
        para = end;
    }
}

/* A scene's comments only: other lines become empty (paragraph breaks). */
static void keep_comments(char *text)
{
    for (char *line = text; *line;) {
        char *nl = strchr(line, '\n');
        char *q = line;
        while (*q == ' ' || *q == '\t') q++;
        if (*q != '#')
            for (char *c = line; c < (nl ? nl : line + strlen(line)); c++) *c = ' ';
        if (!nl) break;
        line = nl + 1;
    }
}

TEST(docs_timings_come_from_the_table)
{
    char *table_text = bkf_cli_read_file(BKF_SOURCE_DIR "/docs/timings.md");
    CHECK_MSG(table_text, "docs/timings.md missing: make bench writes it (tests/bench/timings.sh)");
    CHECK_MSG(strstr(table_text, "<!-- generated by tests/bench/timings.sh"),
              "docs/timings.md is not the generated table");
    CHECK_MSG(strstr(table_text, "\nMeasured 20"), "docs/timings.md does not say when it was measured");
    table t = read_table(table_text);
    CHECK_MSG(t.n >= 8, "docs/timings.md has %zu rows", t.n);
    for (size_t i = 0; i < t.n; i++)
        CHECK_MSG(timing_at(t.rows[i].wall, t.rows[i].wall) == strlen(t.rows[i].wall) &&
                      timing_at(t.rows[i].cpu, t.rows[i].cpu) == strlen(t.rows[i].cpu),
                  "docs/timings.md row %s: \"%s\", \"%s\" are not timings", t.rows[i].key,
                  t.rows[i].wall, t.rows[i].cpu);

    static const char *const patterns[] = {"README.md", "CONTRIBUTING.md", "docs/*.md", "docs/cli/*.md",
                                           "fronts/*.scene"};
    static const char *const record[] = {"docs/benchmarks.md", "docs/changelog.md", "docs/timings.md"};
    bool used[N_SETTINGS] = {false};
    static report rep;
    size_t pages = 0;
    for (size_t k = 0; k < sizeof patterns / sizeof patterns[0]; k++) {
        char pattern[1024];
        snprintf(pattern, sizeof pattern, "%s/%s", BKF_SOURCE_DIR, patterns[k]);
        glob_t g;
        if (glob(pattern, 0, NULL, &g) != 0) continue;
        for (size_t i = 0; i < g.gl_pathc; i++) {
            const char *page = g.gl_pathv[i] + strlen(BKF_SOURCE_DIR) + 1;
            bool skip = false;
            for (size_t r = 0; r < 3; r++) skip = skip || strcmp(page, record[r]) == 0;
            if (skip) continue;
            char *text = bkf_cli_read_file(g.gl_pathv[i]);
            CHECK_MSG(text, "cannot read %s", g.gl_pathv[i]);
            if (strstr(page, ".scene")) keep_comments(text);
            check_page(page, text, &t, used, &rep);
            free(text);
            pages++;
        }
        globfree(&g);
    }
    CHECK_MSG(pages > 30, "read only %zu pages", pages);
    for (size_t i = 0; i < N_SETTINGS; i++)
        if (!used[i])
            complain(&rep, "%s: the setting \"%s\" (%s) is no longer there: remove it from the list\n",
                     settings[i].page, settings[i].phrase, settings[i].why);
    CHECK_MSG(rep.count == 0,
              "%zu timing(s) not from docs/timings.md (docs/testing.md, \"Timings in the manual\"):\n%s",
              rep.count, rep.text);
    free(table_text);
}

/* The scanner itself: what it must see as a timing and what it must not. */
TEST(docs_timings_scanner_finds_the_forms_pages_use)
{
    static const struct {
        const char *text;
        const char *timing;   /* NULL: none */
    } cases[] = {
        {"about 90 s on one core", "90 s"},
        {"(~11 s: filled", "11 s"},
        {"failed after 20-26 minutes", "20-26 minutes"},
        {"cheaper (0.05\xe2\x80\x93" "0.44 s)", "0.05\xe2\x80\x93" "0.44 s"},
        {"at 0.05 .. 0.3 s into", "0.05 .. 0.3 s"},
        {"13 to 146 s each", "13 to 146 s"},
        {"3 min 42 s in all", "3 min"},
        {"1 \xc2\xb5s a point", "1 \xc2\xb5s"},
        {"31.7 us at 8192", "31.7 us"},
        {"took 12ms", "12ms"},
        {"about 2\xc2\xa0s", "2\xc2\xa0s"},
        {"16 seconds", "16 seconds"},
        {"e^(2s) is not", NULL},
        {"S = 20 h moves", NULL},
        {"t = 30 and tmax 125", NULL},
        {"tol 1e-6 s", NULL},
        {"v2s 3 steps", NULL},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        const char *s = cases[i].text;
        const char *found = NULL;
        size_t n = 0;
        for (const char *p = s; *p && !found; p++)
            if (*p >= '0' && *p <= '9' && (n = timing_at(s, p))) found = p;
        if (!cases[i].timing)
            CHECK_MSG(!found, "\"%s\": found the timing \"%.*s\"", s, (int)n, found);
        else
            CHECK_MSG(found && n == strlen(cases[i].timing) && strncmp(found, cases[i].timing, n) == 0,
                      "\"%s\": want \"%s\", found \"%.*s\"", s, cases[i].timing, found ? (int)n : 0,
                      found ? found : "");
    }
    /* a paragraph passes through a linked row holding the number, not otherwise */
    table t = read_table("| `make run` | x | 90.3 s | 80.1 s |\n");
    CHECK(t.n == 1);
    static report rep;
    bool used[N_SETTINGS] = {false};
    check_page("x.md", "takes 90.3 s ([timings: `make run`](timings.md)).\n", &t, used, &rep);
    CHECK_MSG(rep.count == 0, "%s", rep.text);
    check_page("x.md", "takes 90.3 s.\n\nSee [timings: `make run`](timings.md).\n", &t, used, &rep);
    CHECK_MSG(rep.count == 1, "a number in another paragraph than its link passed");
    check_page("x.md", "takes 91 s ([timings: `make run`](timings.md)).\n", &t, used, &rep);
    CHECK_MSG(rep.count == 2, "a number the row does not hold passed");
    check_page("x.md", "see [timings: `make test`](timings.md).\n", &t, used, &rep);
    CHECK_MSG(rep.count == 3, "a link to a row the table does not have passed");
}

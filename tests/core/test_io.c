/* Table writer (TSV, JSON) and atomic file replacement. */
#define _DEFAULT_SOURCE /* flock */
#define _POSIX_C_SOURCE 200809L
#include "harness.h"

#include <errno.h>
#include <signal.h>
#include <stdint.h>
#include <string.h>
#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "bkfront/io.h"

/* ---- a strict JSON syntax checker (RFC 8259), also used by the CLI tests */

typedef struct {
    const char *p;
} json_cursor;

static void json_ws(json_cursor *c)
{
    while (*c->p == ' ' || *c->p == '\t' || *c->p == '\n' || *c->p == '\r') c->p++;
}

static int json_value(json_cursor *c, int depth);

static int json_string(json_cursor *c)
{
    if (*c->p != '"') return 0;
    c->p++;
    for (;;) {
        unsigned char ch = (unsigned char)*c->p;
        if (ch == '"') {
            c->p++;
            return 1;
        }
        if (ch < 0x20) return 0;  /* also the end of the text */
        if (ch == '\\') {
            c->p++;
            if (*c->p == 'u') {
                for (int i = 1; i <= 4; i++)
                    if (!strchr("0123456789abcdefABCDEF", c->p[i]) || !c->p[i]) return 0;
                c->p += 5;
                continue;
            }
            if (!*c->p || !strchr("\"\\/bfnrt", *c->p)) return 0;
        }
        c->p++;
    }
}

static int json_number(json_cursor *c)
{
    const char *p = c->p;
    if (*p == '-') p++;
    if (*p == '0')
        p++;
    else if (*p >= '1' && *p <= '9')
        while (*p >= '0' && *p <= '9') p++;
    else
        return 0;
    if (*p == '.') {
        p++;
        if (!(*p >= '0' && *p <= '9')) return 0;
        while (*p >= '0' && *p <= '9') p++;
    }
    if (*p == 'e' || *p == 'E') {
        p++;
        if (*p == '+' || *p == '-') p++;
        if (!(*p >= '0' && *p <= '9')) return 0;
        while (*p >= '0' && *p <= '9') p++;
    }
    c->p = p;
    return 1;
}

static int json_container(json_cursor *c, int depth, char close, int keyed)
{
    c->p++;
    json_ws(c);
    if (*c->p == close) {
        c->p++;
        return 1;
    }
    for (;;) {
        json_ws(c);
        if (keyed) {
            if (!json_string(c)) return 0;
            json_ws(c);
            if (*c->p++ != ':') return 0;
        }
        if (!json_value(c, depth + 1)) return 0;
        json_ws(c);
        if (*c->p == ',') {
            c->p++;
            continue;
        }
        if (*c->p != close) return 0;
        c->p++;
        return 1;
    }
}

static int json_value(json_cursor *c, int depth)
{
    if (depth > 64) return 0;
    json_ws(c);
    switch (*c->p) {
    case '{': return json_container(c, depth, '}', 1);
    case '[': return json_container(c, depth, ']', 0);
    case '"': return json_string(c);
    case 't': return strncmp(c->p, "true", 4) == 0 ? (c->p += 4, 1) : 0;
    case 'f': return strncmp(c->p, "false", 5) == 0 ? (c->p += 5, 1) : 0;
    case 'n': return strncmp(c->p, "null", 4) == 0 ? (c->p += 4, 1) : 0;
    default: return json_number(c);
    }
}

/* Whether text is exactly one JSON value, surrounded only by white space. */
int bkf_test_json_valid(const char *text);
int bkf_test_json_valid(const char *text)
{
    json_cursor c = {text};
    if (!json_value(&c, 0)) return 0;
    json_ws(&c);
    return *c.p == '\0';
}

/* ---- helpers */

typedef struct {
    FILE *f;
    char *data;
    size_t size;
} memout;

static void mem_open(memout *m)
{
    m->data = NULL;
    m->size = 0;
    m->f = open_memstream(&m->data, &m->size);
    CHECK(m->f);
}

static char *mem_close(memout *m)
{
    CHECK(fclose(m->f) == 0);
    return m->data;
}

static const bkf_io_column cols[] = {
    {"mu", BKF_IO_NUMBER}, {"T", BKF_IO_NUMBER}, {"stepper", BKF_IO_TEXT}};

static int same_bits(double a, double b)
{
    uint64_t x, y;
    memcpy(&x, &a, sizeof x);
    memcpy(&y, &b, sizeof y);
    return x == y;
}

static int file_exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0;
}

static char *slurp(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    static char buf[1 << 16];
    size_t n = fread(buf, 1, sizeof buf - 1, f);
    buf[n] = '\0';
    fclose(f);
    return buf;
}

/* A private directory, so that leftovers show up in a listing. */
static void make_dir(char *templ)
{
    CHECK(mkdtemp(templ) != NULL);
}

static int dir_entries(const char *dir)
{
    char cmd[512];
    snprintf(cmd, sizeof cmd, "ls -A '%s' | wc -l", dir);
    FILE *p = popen(cmd, "r");
    int n = -1;
    if (p) {
        if (fscanf(p, "%d", &n) != 1) n = -1;
        pclose(p);
    }
    return n;
}

/* ---- tables */

TEST(io_tsv_layout)
{
    memout m;
    mem_open(&m);
    bkf_error e = {0};
    bkf_io_table *t = bkf_io_table_alloc(m.f, BKF_IO_TSV, cols, 3, &e);
    CHECK(t);
    CHECK_STATUS(bkf_io_table_comment(t, "first\nsecond", &e), BKF_OK);
    bkf_io_value r1[] = {{.number = 1}, {.number = 6.663286859323130}, {.text = "rk8pd"}};
    bkf_io_value r2[] = {{.number = 0.1}, {.number = NAN}, {.text = "a\tb\\c\nd"}};
    bkf_io_value r3[] = {{.number = INFINITY}, {.number = -INFINITY}, {.text = NULL}};
    CHECK_STATUS(bkf_io_table_row(t, r1, &e), BKF_OK);
    CHECK_STATUS(bkf_io_table_row(t, r2, &e), BKF_OK);
    CHECK_STATUS(bkf_io_table_row(t, r3, &e), BKF_OK);
    /* Comments belong before the rows in both formats. */
    CHECK_STATUS(bkf_io_table_comment(t, "late", &e), BKF_EINPUT);
    CHECK_STATUS(bkf_io_table_finish(t, &e), BKF_OK);
    CHECK(bkf_io_table_rows(t) == 3);
    CHECK_STATUS(bkf_io_table_row(t, r1, &e), BKF_EINPUT);
    bkf_io_table_free(t);
    char *out = mem_close(&m);
    const char *want = "# first\n"
                       "# second\n"
                       "mu\tT\tstepper\n"
                       "1\t6.6632868593231303\trk8pd\n"
                       "0.10000000000000001\tnan\ta\\tb\\\\c\\nd\n"
                       "inf\t-inf\t\n";
    CHECK_MSG(strcmp(out, want) == 0, "got:\n%s", out);
    free(out);
}

TEST(io_tsv_numbers_read_back_bitwise)
{
    double xs[] = {0.1, 1.0 / 3.0, -2.5e-300, 4.9406564584124654e-324, 1.7976931348623157e308,
                   -0.0, 6.663286859323130, 1e22, 123456789012345678.0, 3.141592653589793};
    size_t n = sizeof xs / sizeof xs[0];
    memout m;
    mem_open(&m);
    bkf_error e = {0};
    bkf_io_column c[] = {{"x", BKF_IO_NUMBER}};
    bkf_io_table *t = bkf_io_table_alloc(m.f, BKF_IO_TSV, c, 1, &e);
    for (size_t i = 0; i < n; i++) {
        bkf_io_value v = {.number = xs[i]};
        CHECK_STATUS(bkf_io_table_row(t, &v, &e), BKF_OK);
    }
    CHECK_STATUS(bkf_io_table_finish(t, &e), BKF_OK);
    bkf_io_table_free(t);
    char *out = mem_close(&m);
    char *line = strtok(out, "\n");
    CHECK(line && strcmp(line, "x") == 0);
    for (size_t i = 0; i < n; i++) {
        line = strtok(NULL, "\n");
        CHECK(line);
        char *end;
        double y = strtod(line, &end);
        CHECK_MSG(*end == '\0' && same_bits(y, xs[i]), "'%s' is not %.17g", line, xs[i]);
    }
    CHECK(strtok(NULL, "\n") == NULL);
    free(out);
}

TEST(io_json_layout)
{
    memout m;
    mem_open(&m);
    bkf_error e = {0};
    bkf_io_table *t = bkf_io_table_alloc(m.f, BKF_IO_JSON, cols, 3, &e);
    CHECK(t);
    CHECK_STATUS(bkf_io_table_comment(t, "say \"hi\"\\", &e), BKF_OK);
    CHECK_STATUS(bkf_io_table_comment(t, "x\n", &e), BKF_OK);
    bkf_io_value r1[] = {{.number = 1}, {.number = 0.1}, {.text = "rk8pd"}};
    bkf_io_value r2[] = {{.number = NAN}, {.number = -INFINITY}, {.text = NULL}};
    bkf_io_value r3[] = {{.number = -0.0}, {.number = 1e300}, {.text = "\x01\t\xc3\xa9\xff"}};
    CHECK_STATUS(bkf_io_table_row(t, r1, &e), BKF_OK);
    CHECK_STATUS(bkf_io_table_row(t, r2, &e), BKF_OK);
    CHECK_STATUS(bkf_io_table_row(t, r3, &e), BKF_OK);
    CHECK_STATUS(bkf_io_table_finish(t, &e), BKF_OK);
    bkf_io_table_free(t);
    char *out = mem_close(&m);
    const char *want =
        "{\n"
        "  \"comments\": [\n"
        "    \"say \\\"hi\\\"\\\\\",\n"
        "    \"x\",\n"
        "    \"\"\n"
        "  ],\n"
        "  \"columns\": [\"mu\", \"T\", \"stepper\"],\n"
        "  \"kinds\": [\"number\", \"number\", \"text\"],\n"
        "  \"rows\": [\n"
        "    {\"mu\": 1, \"T\": 0.10000000000000001, \"stepper\": \"rk8pd\"},\n"
        "    {\"mu\": null, \"T\": null, \"stepper\": null},\n"
        "    {\"mu\": -0, \"T\": 1.0000000000000001e+300, \"stepper\": \"\\u0001\\t\xc3\xa9\\ufffd\"}\n"
        "  ]\n"
        "}\n";
    CHECK_MSG(strcmp(out, want) == 0, "got:\n%s\nwant:\n%s", out, want);
    CHECK(bkf_test_json_valid(out));
    free(out);
}

TEST(io_json_empty_and_invalid_utf8)
{
    memout m;
    mem_open(&m);
    bkf_error e = {0};
    bkf_io_table *t = bkf_io_table_alloc(m.f, BKF_IO_JSON, cols, 3, &e);
    CHECK_STATUS(bkf_io_table_finish(t, &e), BKF_OK);
    bkf_io_table_free(t);
    char *out = mem_close(&m);
    CHECK_MSG(strcmp(out, "{\n  \"comments\": [],\n  \"columns\": [\"mu\", \"T\", \"stepper\"],\n"
                          "  \"kinds\": [\"number\", \"number\", \"text\"],\n"
                          "  \"rows\": []\n}\n") == 0,
              "got:\n%s", out);
    CHECK(bkf_test_json_valid(out));
    free(out);

    /* Overlong, surrogate, truncated and out-of-range sequences all become
     * U+FFFD; the checker then sees only ASCII escapes and valid UTF-8. */
    const char *bad[] = {"\xc0\xaf", "\xed\xa0\x80", "\xe2\x82", "\xf4\x90\x80\x80", "\x80",
                         "ok \xf0\x9f\x98\x80 ok"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        mem_open(&m);
        t = bkf_io_table_alloc(m.f, BKF_IO_JSON, cols, 3, &e);
        CHECK_STATUS(bkf_io_table_comment(t, bad[i], &e), BKF_OK);
        CHECK_STATUS(bkf_io_table_finish(t, &e), BKF_OK);
        bkf_io_table_free(t);
        out = mem_close(&m);
        CHECK(bkf_test_json_valid(out));
        if (i + 1 < sizeof bad / sizeof bad[0])
            CHECK_MSG(strstr(out, "\\ufffd") && !strpbrk(out, "\x80\x82\x90\xa0\xaf\xc0\xe2\xed\xf4"),
                      "case %zu:\n%s", i, out);
        else
            CHECK_MSG(strstr(out, "ok \xf0\x9f\x98\x80 ok"), "valid UTF-8 was altered:\n%s", out);
        free(out);
    }
}

TEST(io_json_numbers_read_back_bitwise)
{
    double xs[] = {0.1, 1.0 / 3.0, -2.5e-300, 5e-324, 1.7976931348623157e308, 6.663286859323130};
    memout m;
    mem_open(&m);
    bkf_error e = {0};
    bkf_io_column c[] = {{"x", BKF_IO_NUMBER}};
    bkf_io_table *t = bkf_io_table_alloc(m.f, BKF_IO_JSON, c, 1, &e);
    for (size_t i = 0; i < 6; i++) {
        bkf_io_value v = {.number = xs[i]};
        CHECK_STATUS(bkf_io_table_row(t, &v, &e), BKF_OK);
    }
    CHECK_STATUS(bkf_io_table_finish(t, &e), BKF_OK);
    bkf_io_table_free(t);
    char *out = mem_close(&m);
    CHECK(bkf_test_json_valid(out));
    const char *p = out;
    for (size_t i = 0; i < 6; i++) {
        p = strstr(p, "{\"x\": ");
        CHECK(p);
        p += 6;
        char *end;
        double y = strtod(p, &end);
        CHECK_MSG(*end == '}' && same_bits(y, xs[i]), "row %zu: %.30s", i, p);
    }
    free(out);
}

TEST(io_bad_columns_and_formats)
{
    bkf_error e = {0};
    bkf_io_column dup[] = {{"a", BKF_IO_NUMBER}, {"a", BKF_IO_TEXT}};
    bkf_io_column hash[] = {{"#a", BKF_IO_NUMBER}};
    bkf_io_column tab[] = {{"a\tb", BKF_IO_NUMBER}};
    bkf_io_column empty[] = {{"", BKF_IO_NUMBER}};
    CHECK(!bkf_io_table_alloc(stdout, BKF_IO_TSV, dup, 2, &e));
    CHECK(strstr(e.message, "twice"));
    CHECK(!bkf_io_table_alloc(stdout, BKF_IO_TSV, hash, 1, &e));
    CHECK(!bkf_io_table_alloc(stdout, BKF_IO_TSV, tab, 1, &e));
    CHECK(!bkf_io_table_alloc(stdout, BKF_IO_TSV, empty, 1, &e));
    CHECK(!bkf_io_table_alloc(stdout, BKF_IO_TSV, dup, 0, &e));
    CHECK(!bkf_io_table_alloc(NULL, BKF_IO_TSV, cols, 3, &e));

    bkf_io_format f = BKF_IO_TSV;
    CHECK_STATUS(bkf_io_format_parse("json", &f, &e), BKF_OK);
    CHECK(f == BKF_IO_JSON && strcmp(bkf_io_format_name(f), "json") == 0);
    CHECK_STATUS(bkf_io_format_parse("csv", &f, &e), BKF_EINPUT);
    CHECK(f == BKF_IO_JSON);
}

TEST(io_write_error_is_reported)
{
    /* A stream that cannot be written: reading-only /dev/null. */
    FILE *f = fopen("/dev/null", "r");
    CHECK(f);
    bkf_error e = {0};
    bkf_io_table *t = bkf_io_table_alloc(f, BKF_IO_TSV, cols, 3, &e);
    bkf_io_value r[] = {{.number = 1}, {.number = 2}, {.text = "x"}};
    (void)bkf_io_table_row(t, r, &e); /* may be buffered; finish must see it */
    CHECK_STATUS(bkf_io_table_finish(t, &e), BKF_ENUMERIC);
    CHECK(strstr(e.message, "writing the table failed"));
    bkf_io_table_free(t);
    fclose(f);
}

/* ---- atomic files */

TEST(io_atomic_commit_replaces)
{
    char dir[] = "/tmp/bkf_io_test_XXXXXX";
    make_dir(dir);
    char path[256];
    snprintf(path, sizeof path, "%s/out.tsv", dir);
    FILE *old = fopen(path, "w");
    CHECK(old);
    fputs("old contents\n", old);
    fclose(old);
    CHECK(chmod(path, 0640) == 0);

    bkf_error e = {0};
    bkf_io_atomic *a = bkf_io_atomic_open(path, &e);
    CHECK_MSG(a, "%s", e.message);
    const char *temp = bkf_io_atomic_temp_path(a);
    CHECK(temp && strncmp(temp, dir, strlen(dir)) == 0 && strcmp(temp, path) != 0);
    CHECK(file_exists(temp));
    fputs("new contents\n", bkf_io_atomic_stream(a));
    /* Until commit the target keeps its old contents. */
    CHECK(strcmp(slurp(path), "old contents\n") == 0);
    CHECK_STATUS(bkf_io_atomic_commit(a, &e), BKF_OK);
    CHECK(strcmp(slurp(path), "new contents\n") == 0);
    struct stat st;
    CHECK(stat(path, &st) == 0 && (st.st_mode & 0777) == 0640);
    CHECK_MSG(dir_entries(dir) == 1, "leftover files in %s", dir);

    /* A new file appears only at commit. */
    char fresh[256];
    snprintf(fresh, sizeof fresh, "%s/fresh.json", dir);
    a = bkf_io_atomic_open(fresh, &e);
    CHECK(a);
    CHECK(!file_exists(fresh));
    fputs("{}\n", bkf_io_atomic_stream(a));
    CHECK_STATUS(bkf_io_atomic_commit(a, &e), BKF_OK);
    CHECK(strcmp(slurp(fresh), "{}\n") == 0);
    CHECK(dir_entries(dir) == 2);
    unlink(fresh);
    unlink(path);
    rmdir(dir);
}

TEST(io_atomic_abort_leaves_nothing)
{
    char dir[] = "/tmp/bkf_io_test_XXXXXX";
    make_dir(dir);
    char path[256];
    snprintf(path, sizeof path, "%s/out.tsv", dir);
    bkf_error e = {0};
    bkf_io_atomic *a = bkf_io_atomic_open(path, &e);
    CHECK(a);
    fputs("partial", bkf_io_atomic_stream(a));
    bkf_io_atomic_abort(a);
    CHECK(!file_exists(path));
    CHECK_MSG(dir_entries(dir) == 0, "leftover files in %s", dir);

    /* An existing target survives an abort untouched. */
    FILE *old = fopen(path, "w");
    fputs("keep\n", old);
    fclose(old);
    a = bkf_io_atomic_open(path, &e);
    CHECK(a);
    fputs("partial", bkf_io_atomic_stream(a));
    bkf_io_atomic_abort(a);
    CHECK(strcmp(slurp(path), "keep\n") == 0);
    CHECK(dir_entries(dir) == 1);
    bkf_io_atomic_abort(NULL);
    unlink(path);
    rmdir(dir);
}

/* A link where an output goes is never written through: not to a file
 * (which would be replaced), a folder, nothing (a dangling link would
 * create its target) or a chain of links; the link and what it points to
 * stay as they were, and no temporary is left. */
TEST(io_atomic_never_writes_through_a_symlink)
{
    char dir[] = "/tmp/bkf_io_test_XXXXXX";
    make_dir(dir);
    char victim[256], folder[256], link[256], l2[256];
    snprintf(victim, sizeof victim, "%s/victim.tsv", dir);
    snprintf(folder, sizeof folder, "%s/folder", dir);
    snprintf(link, sizeof link, "%s/out.tsv", dir);
    snprintf(l2, sizeof l2, "%s/l2", dir);
    FILE *f = fopen(victim, "w");
    fputs("precious\n", f);
    fclose(f);
    CHECK(mkdir(folder, 0755) == 0);
    const char *targets[] = {"victim.tsv", "folder", "missing.tsv", "l2", "out.tsv"};
    for (size_t i = 0; i < sizeof targets / sizeof targets[0]; i++) {
        unlink(l2);
        if (strcmp(targets[i], "l2") == 0) CHECK(symlink("victim.tsv", l2) == 0);
        CHECK(symlink(targets[i], link) == 0);
        bkf_error e = {0};
        bkf_io_atomic *a = bkf_io_atomic_open(link, &e);
        if (a) { /* the old code: write through the link */
            fputs("new\n", bkf_io_atomic_stream(a));
            bkf_io_atomic_commit(a, &e);
        }
        CHECK_MSG(!a, "a link to %s was written through", targets[i]);
        CHECK_MSG(e.status == BKF_EINPUT && strstr(e.message, "symbolic link"), "%s: %s",
                  targets[i], e.message);
        struct stat st;
        CHECK(lstat(link, &st) == 0 && S_ISLNK(st.st_mode));
        char *v = slurp(victim);
        CHECK_MSG(strcmp(v, "precious\n") == 0, "the file behind a link to %s changed", targets[i]);
        CHECK(lstat(victim, &st) == 0 && S_ISREG(st.st_mode));
        char missing[256];
        snprintf(missing, sizeof missing, "%s/missing.tsv", dir);
        CHECK_MSG(!file_exists(missing), "a dangling link created its target");
        unlink(link);
    }
    unlink(l2);
    /* the folder holds only what the test made: no temporary left */
    CHECK(dir_entries(dir) == 2);
    rmdir(folder);
    unlink(victim);
    rmdir(dir);
}

/* One file given to two outputs open at once (simulate --snapshots x.tsv
 * --out x.tsv) is refused at the second open however it is spelled: the
 * same name, another spelling of the folder, a link to the folder, a hard
 * link of the file.  Once the first is committed the name is free again. */
TEST(io_atomic_refuses_one_file_for_two_outputs)
{
    char dir[] = "/tmp/bkf_io_test_XXXXXX";
    make_dir(dir);
    char path[256], sub[256], dirlink[256], hard[256];
    snprintf(path, sizeof path, "%s/x.tsv", dir);
    snprintf(sub, sizeof sub, "%s/sub", dir);
    snprintf(dirlink, sizeof dirlink, "%s/alias", dir);
    snprintf(hard, sizeof hard, "%s/hard.tsv", dir);
    CHECK(mkdir(sub, 0755) == 0);
    CHECK(symlink(".", dirlink) == 0);
    char spelled[4][300];
    snprintf(spelled[0], sizeof spelled[0], "%s/x.tsv", dir);
    snprintf(spelled[1], sizeof spelled[1], "%s/sub/../x.tsv", dir);
    snprintf(spelled[2], sizeof spelled[2], "%s//./x.tsv", dir);
    snprintf(spelled[3], sizeof spelled[3], "%s/alias/x.tsv", dir);
    for (int exists = 0; exists < 2; exists++) {
        if (exists) {
            FILE *f = fopen(path, "w");
            fputs("old\n", f);
            fclose(f);
            CHECK(link(path, hard) == 0);
        }
        bkf_error e = {0};
        bkf_io_atomic *first = bkf_io_atomic_open(path, &e);
        CHECK_MSG(first, "%s", e.message);
        for (int k = 0; k < 4 + exists; k++) {
            const char *other = k < 4 ? spelled[k] : hard;
            bkf_io_atomic *second = bkf_io_atomic_open(other, &e);
            CHECK_MSG(!second, "%s opened while %s is being written", other, path);
            bkf_io_atomic_abort(second);
            CHECK_MSG(e.status == BKF_EINPUT && strstr(e.message, "another output"), "%s",
                      e.message);
        }
        /* another file in the same folder is no clash */
        char y[300];
        snprintf(y, sizeof y, "%s/y.tsv", dir);
        bkf_io_atomic *other = bkf_io_atomic_open(y, &e);
        CHECK_MSG(other, "%s", e.message);
        bkf_io_atomic_abort(other);
        fputs("new\n", bkf_io_atomic_stream(first));
        CHECK_STATUS(bkf_io_atomic_commit(first, &e), BKF_OK);
        bkf_io_atomic *again = bkf_io_atomic_open(spelled[1], &e);
        CHECK_MSG(again, "%s", e.message);
        bkf_io_atomic_abort(again);
    }
    unlink(hard);
    unlink(path);
    unlink(dirlink);
    rmdir(sub);
    CHECK(dir_entries(dir) == 0);
    rmdir(dir);
}

/* One writer at a time on a file held by bkf_io_lock_take: a second lock
 * (here or in another process) and another process's atomic writer are
 * refused while it is held, named by the holder's PID; the lock file goes
 * on release, and a lock left by a dead holder (SIGKILL) is no lock. */
TEST(io_lock_one_writer_at_a_time)
{
    char dir[] = "/tmp/bkf_io_test_XXXXXX";
    make_dir(dir);
    char path[256], lockfile[300];
    snprintf(path, sizeof path, "%s/r.tsv", dir);
    snprintf(lockfile, sizeof lockfile, "%s/.r.tsv.lock", dir);
    bkf_error e = {0};
    bkf_io_lock *l = bkf_io_lock_take(path, &e);
    CHECK_MSG(l, "%s", e.message);
    CHECK(!bkf_io_lock_take(path, &e));
    CHECK_MSG(strstr(e.message, "already being written by this process"), "%s", e.message);
    /* our own atomic writer may replace the file we hold */
    bkf_io_atomic *a = bkf_io_atomic_open(path, &e);
    CHECK_MSG(a, "%s", e.message);
    fputs("mine\n", bkf_io_atomic_stream(a));
    CHECK_STATUS(bkf_io_atomic_commit(a, &e), BKF_OK);
    bkf_io_lock_release(l);
    CHECK(!file_exists(lockfile));
    /* another process holds it (a child that took it after the fork: a
     * lock taken before would be shared with the child) */
    int up[2], down[2];
    CHECK(pipe(up) == 0 && pipe(down) == 0);
    pid_t kid = fork();
    if (kid == 0) {
        bkf_error k = {0};
        bkf_io_lock *mine = bkf_io_lock_take(path, &k);
        char c = mine ? 'y' : 'n';
        if (write(up[1], &c, 1) != 1 || read(down[0], &c, 1) != 1) _exit(2);
        bkf_io_lock_release(mine);
        _exit(mine ? 0 : 1);
    }
    char c = 0;
    CHECK(read(up[0], &c, 1) == 1 && c == 'y');
    char want[64];
    snprintf(want, sizeof want, "process %ld", (long)kid);
    CHECK(!bkf_io_lock_take(path, &e));
    CHECK_MSG(strstr(e.message, want) && strstr(e.message, "another run"), "%s", e.message);
    a = bkf_io_atomic_open(path, &e);
    CHECK_MSG(!a, "replaced a file another process holds");
    bkf_io_atomic_abort(a);
    CHECK_MSG(strstr(e.message, want) && strstr(e.message, "another run"), "%s", e.message);
    CHECK(write(down[1], "x", 1) == 1);
    int st = 0;
    CHECK(waitpid(kid, &st, 0) == kid);
    CHECK(WIFEXITED(st) && WEXITSTATUS(st) == 0);
    /* a holder killed outright leaves its lock file, but no lock */
    kid = fork();
    if (kid == 0) {
        bkf_error k = {0};
        if (!bkf_io_lock_take(path, &k)) _exit(1);
        raise(SIGKILL);
    }
    CHECK(waitpid(kid, &st, 0) == kid);
    CHECK(WIFSIGNALED(st));
    CHECK(file_exists(lockfile));
    l = bkf_io_lock_take(path, &e);
    CHECK_MSG(l, "%s", e.message);
    bkf_io_lock_release(l);
    /* a link planted at the lock file's name is not followed */
    char victim[256];
    snprintf(victim, sizeof victim, "%s/victim", dir);
    CHECK(symlink("victim", lockfile) == 0);
    CHECK(!bkf_io_lock_take(path, &e));
    CHECK_MSG(strstr(e.message, "symbolic link"), "%s", e.message);
    CHECK(!file_exists(victim));
    unlink(lockfile);
    unlink(path);
    CHECK(dir_entries(dir) == 0);
    rmdir(dir);
}

TEST(io_atomic_rejects_bad_targets)
{
    bkf_error e = {0};
    CHECK(!bkf_io_atomic_open("/nonexistent_bkf_dir/x.tsv", &e));
    CHECK_MSG(strstr(e.message, "/nonexistent_bkf_dir/x.tsv"), "%s", e.message);
    CHECK(!bkf_io_atomic_open("/tmp", &e));
    CHECK(!bkf_io_atomic_open("/tmp/", &e));
    CHECK(!bkf_io_atomic_open("/dev/null", &e));
    CHECK_MSG(strstr(e.message, "not a regular file"), "%s", e.message);
    CHECK(!bkf_io_atomic_open("", &e));
}

TEST(io_json_checker_is_strict)
{
    /* The checker the JSON tests rely on must itself say no. */
    const char *good[] = {"{}", "[]", " {\"a\": [1, -0, 1.5e-3, true, null, \"\\u00e9\"]}\n",
                          "0", "\"x\""};
    const char *bad[] = {"", "{", "{\"a\": 1,}", "[1,]", "{\"a\" 1}", "{a: 1}", "[nan]",
                         "[inf]", "[01]", "[1.]", "[.5]", "[1e]", "\"\t\"", "\"\\x\"",
                         "{} {}", "[\"\\u12\"]", "'a'"};
    for (size_t i = 0; i < sizeof good / sizeof good[0]; i++)
        CHECK_MSG(bkf_test_json_valid(good[i]), "rejected: %s", good[i]);
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++)
        CHECK_MSG(!bkf_test_json_valid(bad[i]), "accepted: %s", bad[i]);
}

TEST(io_atomic_writes_the_longest_file_names)
{
    /* A name of 255 bytes is valid (NAME_MAX on Linux file systems); its
     * temporary must fit too (a 244-byte name used to fail). */
    char dir[] = "/tmp/bkf_io_test_XXXXXX";
    make_dir(dir);
    for (size_t len = 200; len <= 255; len += 11) {
        char name[256], path[512];
        memset(name, 'a', len);
        name[len] = '\0';
        snprintf(path, sizeof path, "%s/%s", dir, name);
        bkf_error e = {0};
        bkf_io_atomic *a = bkf_io_atomic_open(path, &e);
        CHECK_MSG(a, "%zu bytes: %s", len, e.message);
        fputs("x\n", bkf_io_atomic_stream(a));
        CHECK_STATUS(bkf_io_atomic_commit(a, &e), BKF_OK);
        CHECK(strcmp(slurp(path), "x\n") == 0);
        CHECK_MSG(dir_entries(dir) == 1, "leftover temporary beside a %zu-byte name", len);
        unlink(path);
    }
    rmdir(dir);
}

/* A PID that does not exist here: a reaped child's. */
static long dead_pid(void)
{
    pid_t pid = fork();
    CHECK(pid >= 0);
    if (pid == 0) _exit(0);
    int st;
    CHECK(waitpid(pid, &st, 0) == pid);
    return (long)pid;
}

/* A writer in another PID namespace (a container sharing the folder) has a
 * PID we cannot see: its temporary looks orphaned by PID but is locked, and
 * must survive another run's clean-up; once the lock is gone (the writer
 * died) the next open removes it. */
TEST(io_stale_cleanup_spares_a_locked_temporary)
{
    char dir[] = "/tmp/bkf_io_test_XXXXXX";
    make_dir(dir);
    char path[256], temp[300];
    snprintf(path, sizeof path, "%s/out.tsv", dir);
    snprintf(temp, sizeof temp, "%s/.out.tsv.tmp.%ld.1234abcd", dir, dead_pid());
    int fd = open(temp, O_WRONLY | O_CREAT | O_EXCL, 0644);
    CHECK(fd >= 0);
    CHECK(flock(fd, LOCK_EX | LOCK_NB) == 0); /* the live writer */
    bkf_error e = {0};
    bkf_io_atomic *a = bkf_io_atomic_open(path, &e);
    CHECK_MSG(a, "%s", e.message);
    bkf_io_atomic_abort(a);
    CHECK_MSG(file_exists(temp), "a live writer's temporary was removed");
    close(fd); /* the writer is gone */
    a = bkf_io_atomic_open(path, &e);
    CHECK(a);
    bkf_io_atomic_abort(a);
    CHECK_MSG(!file_exists(temp), "a dead writer's temporary stayed");
    /* our own writer holds its lock until the rename */
    a = bkf_io_atomic_open(path, &e);
    CHECK(a);
    int probe = open(bkf_io_atomic_temp_path(a), O_RDONLY);
    CHECK(probe >= 0);
    CHECK(flock(probe, LOCK_EX | LOCK_NB) != 0);
    close(probe);
    CHECK_STATUS(bkf_io_atomic_commit(a, &e), BKF_OK);
    CHECK(dir_entries(dir) == 1);
    unlink(path);
    rmdir(dir);
}

/* A writer killed outright may stay a zombie for a while (its parent died
 * with it, as in kill -9 of an MPI job, and the new parent has not reaped
 * it): its PID still answers kill(pid, 0), but it holds no lock, and its
 * temporary goes at the next open. */
TEST(io_stale_cleanup_removes_a_zombie_writer_s_temporary)
{
    char dir[] = "/tmp/bkf_io_test_XXXXXX";
    make_dir(dir);
    pid_t pid = fork();
    if (pid == 0) _exit(0);
    CHECK(pid > 0);
    /* not reaped yet: a zombie once it has exited */
    char stat_path[64], state = 0;
    snprintf(stat_path, sizeof stat_path, "/proc/%ld/stat", (long)pid);
    for (int i = 0; i < 500 && state != 'Z'; i++) {
        FILE *f = fopen(stat_path, "r");
        char buf[512] = "";
        if (f) {
            size_t n = fread(buf, 1, sizeof buf - 1, f);
            buf[n] = '\0';
            fclose(f);
        }
        const char *end = strrchr(buf, ')');
        state = end ? end[2] : 0;
        if (state != 'Z') usleep(10000);
    }
    CHECK_MSG(state == 'Z' && kill(pid, 0) == 0, "the child is not a zombie (%c)", state);
    char path[256], temp[300];
    snprintf(path, sizeof path, "%s/out.tsv", dir);
    snprintf(temp, sizeof temp, "%s/.out.tsv.tmp.%ld.1234abcd", dir, (long)pid);
    int fd = open(temp, O_WRONLY | O_CREAT | O_EXCL, 0644);
    CHECK(fd >= 0);
    close(fd);
    bkf_error e = {0};
    bkf_io_atomic *a = bkf_io_atomic_open(path, &e);
    CHECK_MSG(a, "%s", e.message);
    bkf_io_atomic_abort(a);
    CHECK_MSG(!file_exists(temp), "a zombie writer's temporary stayed");
    int st;
    CHECK(waitpid(pid, &st, 0) == pid);
    CHECK(dir_entries(dir) == 0);
    rmdir(dir);
}

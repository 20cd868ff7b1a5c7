/* The layers of CONTRIBUTING.md, enforced: core <- wave <- {stability,
 * simulation} <- products <- scene <- cli.  A file in src/LAYER/ (and a
 * public header include/bkfront/X.h, whose layer is that of src/LAYER/X.c)
 * may include the headers of its own layer and of the layers before it;
 * stability and simulation are siblings and may not include each other. */
#define _POSIX_C_SOURCE 200809L
#include "harness.h"

#include <dirent.h>
#include <string.h>
#include <sys/stat.h>

#ifndef BKF_SOURCE_DIR
#define BKF_SOURCE_DIR "."
#endif

typedef struct {
    const char *name;
    int rank;
} layer;

static const layer layers[] = {
    {"core", 0},     {"wave", 1},     {"stability", 2}, {"simulation", 2},
    {"products", 3}, {"scene", 4},    {"cli", 5},
};
#define NLAYERS (sizeof layers / sizeof layers[0])

/* Public headers with no source file of their own name. */
static const struct {
    const char *header;
    const char *layer;
} header_layers[] = {
    {"bkfront.h", "cli"}, /* the umbrella: everything, for users only */
};

static int layer_index(const char *name)
{
    for (size_t i = 0; i < NLAYERS; i++)
        if (strcmp(layers[i].name, name) == 0) return (int)i;
    return -1;
}

/* The layer of public header "X.h": the folder of src/LAYER/X.c. */
static int header_layer(const char *header)
{
    for (size_t i = 0; i < sizeof header_layers / sizeof header_layers[0]; i++)
        if (strcmp(header_layers[i].header, header) == 0)
            return layer_index(header_layers[i].layer);
    char base[256];
    size_t len = strlen(header);
    if (len < 3 || len >= sizeof base || strcmp(header + len - 2, ".h") != 0) return -1;
    memcpy(base, header, len - 2);
    base[len - 2] = '\0';
    for (size_t i = 0; i < NLAYERS; i++) {
        char path[1024];
        struct stat st;
        snprintf(path, sizeof path, "%s/src/%s/%s.c", BKF_SOURCE_DIR, layers[i].name, base);
        if (stat(path, &st) == 0) return (int)i;
    }
    return -1;
}

/* May a file of layer `from` include a header of layer `to`? */
static int allowed(int from, int to)
{
    if (from == to) return 1;
    return layers[to].rank < layers[from].rank;
}

/* Every violation in `text` (a file of layer `from`) is reported through
 * note() and counted; unknown public headers count as violations too. */
static int violations(const char *what, int from, const char *text, int report)
{
    int bad = 0;
    for (const char *p = text; (p = strstr(p, "#include")) != NULL; p++) {
        const char *q = p + 8;
        while (*q == ' ' || *q == '\t') q++;
        if (*q != '"') continue;
        q++;
        const char *end = strchr(q, '"');
        if (!end || end - q > 200) continue;
        char inc[256];
        memcpy(inc, q, (size_t)(end - q));
        inc[end - q] = '\0';
        int to;
        if (strncmp(inc, "bkfront/", 8) == 0) {
            to = header_layer(inc + 8);
        } else if (strchr(inc, '/')) {
            /* "../x/y.h" reaches into another folder: never allowed. */
            to = -1;
        } else {
            to = from; /* a private header beside the file */
        }
        if (to < 0 || !allowed(from, to)) {
            bad++;
            if (report)
                bkf_test_note("%s (%s) includes \"%s\" (%s)", what, layers[from].name, inc,
                              to < 0 ? "unknown layer or path" : layers[to].name);
        }
    }
    return bad;
}

static char *slurp(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    size_t cap = 1 << 16, len = 0;
    char *buf = malloc(cap);
    for (size_t got; buf && (got = fread(buf + len, 1, cap - len - 1, f)) > 0;) {
        len += got;
        if (cap - len < 2) {
            char *g = realloc(buf, cap *= 2);
            if (!g) { free(buf); buf = NULL; break; }
            buf = g;
        }
    }
    fclose(f);
    if (buf) buf[len] = '\0';
    return buf;
}

static int scan_dir(const char *dir, int from, size_t *files)
{
    DIR *d = opendir(dir);
    if (!d) return 0;
    int bad = 0;
    for (struct dirent *e; (e = readdir(d)) != NULL;) {
        size_t len = strlen(e->d_name);
        if (len < 3 || e->d_name[0] == '.') continue;
        if (strcmp(e->d_name + len - 2, ".c") != 0 && strcmp(e->d_name + len - 2, ".h") != 0)
            continue;
        char path[1024];
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        int layer = from;
        if (layer < 0) { /* include/bkfront: the header's own layer */
            layer = header_layer(e->d_name);
            if (layer < 0) {
                bkf_test_note("%s: no src/LAYER/%.*s.c and not in the header map", path,
                              (int)(len - 2), e->d_name);
                bad++;
                continue;
            }
        }
        char *text = slurp(path);
        CHECK_MSG(text != NULL, "cannot read %s", path);
        bad += violations(path, layer, text, 1);
        free(text);
        (*files)++;
    }
    closedir(d);
    return bad;
}

TEST(layers_no_file_includes_a_higher_layer)
{
    int bad = 0;
    size_t files = 0;
    for (size_t i = 0; i < NLAYERS; i++) {
        char dir[1024];
        snprintf(dir, sizeof dir, "%s/src/%s", BKF_SOURCE_DIR, layers[i].name);
        bad += scan_dir(dir, (int)i, &files);
    }
    bad += scan_dir(BKF_SOURCE_DIR "/include/bkfront", -1, &files);
    CHECK_MSG(files > 30, "only %zu files scanned: wrong source folder?", files);
    CHECK_MSG(bad == 0, "%d includes cross the layers upwards (listed above)", bad);
}

TEST(layers_checker_catches_violations)
{
    /* The checker itself: a wave file that includes a simulation header,
     * a simulation file that includes its sibling stability, and a path
     * into another folder are violations; downward includes are not. */
    int wave = layer_index("wave"), sim = layer_index("simulation"),
        cli = layer_index("cli");
    CHECK(violations("t", wave, "#include \"bkfront/pde.h\"\n", 0) == 1);
    CHECK(violations("t", sim, "#include \"bkfront/floquet.h\"\n", 0) == 1);
    CHECK(violations("t", wave, "#include \"../cli/args.h\"\n", 0) == 1);
    CHECK(violations("t", wave, "#include \"bkfront/nonexistent_module.h\"\n", 0) == 1);
    CHECK(violations("t", sim,
                     "#include \"bkfront/cycle.h\"\n#include \"bkfront/status.h\"\n"
                     "#include \"pde_internal.h\"\n#include <math.h>\n", 0) == 0);
    CHECK(violations("t", cli, "#include \"bkfront/pde.h\"\n#include \"bkfront/speeds.h\"\n",
                     0) == 0);
}

/* ------------------------------------------------------------ circles */

/* Inside a layer, dependencies point one way: no file uses another that
 * uses it back (directly or round a longer circle).  File X uses file Y
 * when X includes Y's public header (bkfront/Y.h; Y.c in the same layer)
 * or names a function Y defines (outside comments and strings): the
 * second sees what a shared private header hides (pde.c and pde_etd.c both
 * include pde_internal.h). */

#define MAX_FILES 64
#define MAX_DEFS 512

typedef struct {
    char name[64];            /* "pde" for pde.c */
    char *code;               /* the text without comments and strings */
    char *defs[MAX_DEFS];     /* the functions it defines, not static */
    size_t ndefs;
} unit;

/* The text with comments and string and character literals blanked out. */
static char *code_of(const char *text)
{
    char *c = strdup(text);
    if (!c) return NULL;
    for (char *p = c; *p; p++) {
        if (p[0] == '/' && p[1] == '*') {
            char *e = strstr(p + 2, "*/");
            char *end = e ? e + 2 : p + strlen(p);
            for (; p < end; p++)
                if (*p != '\n') *p = ' ';
            p--;
        } else if (p[0] == '/' && p[1] == '/') {
            for (; *p && *p != '\n'; p++) *p = ' ';
            p--;
        } else if (*p == '"' || *p == '\'') {
            char q = *p;
            for (p++; *p && *p != q; p++) {
                if (*p == '\\' && p[1]) *p++ = ' ';
                if (*p != '\n') *p = ' ';
            }
            if (!*p) break;
        }
    }
    return c;
}

static int ident_char(char c)
{
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
}

/* The functions a file defines at file scope, not static: a body's '{' at
 * the start of a line, after a declaration starting at column 0. */
static void find_defs(unit *u)
{
    const char *code = u->code;
    for (const char *p = code; (p = strstr(p, "\n{")) != NULL; p++) {
        const char *start = p; /* back to the declaration's first line */
        while (start > code) {
            const char *line = start - 1;
            while (line > code && line[-1] != '\n') line--;
            start = line;
            if (*line != ' ' && *line != '\t' && *line != '\n') break;
        }
        if (strncmp(start, "static", 6) == 0) continue;
        const char *paren = memchr(start, '(', (size_t)(p - start));
        if (!paren) continue;
        const char *e = paren;
        while (e > start && e[-1] == ' ') e--;
        const char *b = e;
        while (b > start && ident_char(b[-1])) b--;
        if (b == e || u->ndefs == MAX_DEFS) continue;
        u->defs[u->ndefs] = strndup(b, (size_t)(e - b));
        if (u->defs[u->ndefs]) u->ndefs++;
    }
}

/* Whether `code` names `word` as a whole identifier. */
static int names(const char *code, const char *word)
{
    size_t n = strlen(word);
    for (const char *p = code; (p = strstr(p, word)) != NULL; p += n)
        if ((p == code || !ident_char(p[-1])) && !ident_char(p[n])) return 1;
    return 0;
}

/* Whether `code` includes "bkfront/NAME.h". */
static int includes_header(const char *text, const char *name)
{
    char inc[96];
    snprintf(inc, sizeof inc, "\"bkfront/%s.h\"", name);
    for (const char *p = text; (p = strstr(p, "#include")) != NULL; p++) {
        const char *q = p + 8;
        while (*q == ' ' || *q == '\t') q++;
        if (strncmp(q, inc, strlen(inc)) == 0) return 1;
    }
    return 0;
}

/* Whether unit a uses unit b (texts: the files as written). */
static int uses(const unit *a, const char *a_text, const unit *b)
{
    if (includes_header(a_text, b->name)) return 1;
    for (size_t i = 0; i < b->ndefs; i++)
        if (names(a->code, b->defs[i])) return 1;
    return 0;
}

/* The circles among n units (texts the files as written): every pair i, j
 * where i reaches j and j reaches i.  Returns their number. */
static int circles(const char *layer, unit *u, char **texts, size_t n, int report)
{
    static unsigned char reach[MAX_FILES][MAX_FILES];
    for (size_t i = 0; i < n; i++)
        for (size_t j = 0; j < n; j++) reach[i][j] = i != j && uses(&u[i], texts[i], &u[j]);
    for (size_t k = 0; k < n; k++) /* Warshall: the closure */
        for (size_t i = 0; i < n; i++)
            for (size_t j = 0; i != k && j < n; j++)
                if (reach[i][k] && reach[k][j]) reach[i][j] = 1;
    int bad = 0;
    for (size_t i = 0; i < n; i++)
        for (size_t j = i + 1; j < n; j++) {
            if (!reach[i][j] || !reach[j][i]) continue;
            bad++;
            if (report)
                bkf_test_note("%s: %s.c and %s.c use each other (%s)", layer, u[i].name,
                              u[j].name,
                              reach[i][j] && uses(&u[i], texts[i], &u[j]) &&
                                      uses(&u[j], texts[j], &u[i])
                                  ? "directly"
                                  : "round a circle");
        }
    return bad;
}

static void units_free(unit *u, char **texts, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        free(u[i].code);
        for (size_t d = 0; d < u[i].ndefs; d++) free(u[i].defs[d]);
        free(texts[i]);
    }
}

/* The units of texts[] named names[] (the texts taken over). */
static size_t make_units(unit *u, char **texts, const char *const *unit_names, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        u[i] = (unit){0};
        snprintf(u[i].name, sizeof u[i].name, "%s", unit_names[i]);
        u[i].code = code_of(texts[i]);
        CHECK(u[i].code);
        if (u[i].code) find_defs(&u[i]);
    }
    return n;
}

TEST(layers_have_no_circles_inside)
{
    int bad = 0;
    size_t total = 0;
    for (size_t l = 0; l < NLAYERS; l++) {
        char dir[1024];
        snprintf(dir, sizeof dir, "%s/src/%s", BKF_SOURCE_DIR, layers[l].name);
        DIR *d = opendir(dir);
        CHECK_MSG(d, "cannot open %s", dir);
        if (!d) continue;
        static unit u[MAX_FILES];
        static char *texts[MAX_FILES];
        const char *unit_names[MAX_FILES];
        char stems[MAX_FILES][64];
        size_t n = 0;
        for (struct dirent *e; (e = readdir(d)) != NULL;) {
            size_t len = strlen(e->d_name);
            if (len < 3 || e->d_name[0] == '.' || strcmp(e->d_name + len - 2, ".c") != 0) continue;
            CHECK_MSG(n < MAX_FILES, "more than %d files in %s", MAX_FILES, dir);
            if (n == MAX_FILES) break;
            char path[1400];
            snprintf(path, sizeof path, "%.1023s/%.255s", dir, e->d_name);
            texts[n] = slurp(path);
            CHECK_MSG(texts[n], "cannot read %s", path);
            if (!texts[n]) continue;
            snprintf(stems[n], sizeof stems[n], "%.*s", (int)(len - 2), e->d_name);
            unit_names[n] = stems[n];
            n++;
        }
        closedir(d);
        make_units(u, texts, unit_names, n);
        bad += circles(layers[l].name, u, texts, n, 1);
        total += n;
        units_free(u, texts, n);
    }
    CHECK_MSG(total > 30, "only %zu files read: wrong source folder?", total);
    CHECK_MSG(bad == 0, "%d pairs of files of one layer use each other (listed above)", bad);
}

TEST(layers_circle_checker_catches_circles)
{
    /* planted: a calls b, b calls back a; a circle of three through a
     * header; and a one-way chain, which is no circle */
    const char *const two[] = {"a", "b"};
    char *texts[3];
    unit u[3];
    texts[0] = strdup("#include \"bkfront/b.h\"\nint a_run(void)\n{\n    return b_step();\n}\n");
    texts[1] = strdup("int b_step(void)\n{\n    return a_emit(); /* b_step */\n}\n"
                      "int a_emit_not(void)\n{\n    return 0;\n}\n");
    make_units(u, texts, two, 2);
    CHECK(circles("t", u, texts, 2, 0) == 0); /* a_emit is nobody's */
    units_free(u, texts, 2);

    texts[0] = strdup("int a_emit(void)\n{\n    return 1;\n}\nint a_run(void)\n{\n"
                      "    return b_step();\n}\n");
    texts[1] = strdup("int b_step(void)\n{\n    return a_emit();\n}\n");
    make_units(u, texts, two, 2);
    CHECK(circles("t", u, texts, 2, 0) == 1);
    units_free(u, texts, 2);

    const char *const three[] = {"x", "y", "z"};
    texts[0] = strdup("#include \"bkfront/y.h\"\nint x_f(void)\n{\n    return y_f();\n}\n");
    texts[1] = strdup("int y_f(void)\n{\n    return z_f();\n}\n");
    texts[2] = strdup("#include \"bkfront/x.h\"\nstatic int z_g(void)\n{\n    return 0;\n}\n"
                      "int z_f(void)\n{\n    return z_g();\n}\n");
    make_units(u, texts, three, 3);
    CHECK(circles("t", u, texts, 3, 0) == 3); /* every pair of the three */
    units_free(u, texts, 3);

    /* a comment or a string naming a function is no use of it; a static
     * function is nobody else's */
    texts[0] = strdup("int x_f(void)\n{\n    return 0; /* y_f() */\n}\n"
                      "const char *x_s = \"y_f\";\n");
    texts[1] = strdup("static int x_f(void)\n{\n    return 1;\n}\nint y_f(void)\n{\n"
                      "    return x_f();\n}\n");
    make_units(u, texts, three, 2);
    CHECK(circles("t", u, texts, 2, 0) == 0);
    units_free(u, texts, 2);
}

/* ------------------------------------------------------------ long functions */

/* visit(layer, name, path, data) for every file of every src/LAYER/ (dot
 * files aside); the number of folders that could not be opened. */
static int each_source_file(void (*visit)(size_t layer, const char *name, const char *path,
                                          void *data),
                            void *data)
{
    int missing = 0;
    for (size_t l = 0; l < NLAYERS; l++) {
        char dir[1024];
        snprintf(dir, sizeof dir, "%s/src/%s", BKF_SOURCE_DIR, layers[l].name);
        DIR *d = opendir(dir);
        if (!d) {
            bkf_test_note("cannot open %s", dir);
            missing++;
            continue;
        }
        for (struct dirent *e; (e = readdir(d)) != NULL;) {
            if (e->d_name[0] == '.') continue;
            char path[1400];
            snprintf(path, sizeof path, "%.1023s/%.255s", dir, e->d_name);
            visit(l, e->d_name, path, data);
        }
        closedir(d);
    }
    return missing;
}

/* No function in src/ is over MAX_FUNCTION_LINES lines (from the line of
 * its name to its closing brace) unless listed here with the reason: a long
 * function mixes concerns a reader must hold at once (issue 35).  An entry
 * whose function is no longer long fails too, so the list only shrinks. */
#define MAX_FUNCTION_LINES 150
/* and no file over this many (issue 35: a module past it is split by
 * concern, CONTRIBUTING "Layers") */
#define MAX_FILE_LINES 1500

static const struct {
    const char *file; /* below src/ */
    const char *function;
    const char *reason;
} long_functions[] = {
    /* none today; the terminator keeps the array non-empty (C11) */
    {NULL, NULL, NULL},
};
#define NLONG (sizeof long_functions / sizeof long_functions[0])

/* The text without comments, strings and preprocessor lines (a macro's
 * braces are no function's), newlines kept so line numbers hold. */
static char *code_without_directives(const char *text)
{
    char *c = code_of(text);
    if (!c) return NULL;
    for (char *p = c; *p; p++) {
        if (p != c && p[-1] != '\n') continue;
        char *q = p;
        while (*q == ' ' || *q == '\t') q++;
        if (*q != '#') continue;
        /* the directive and its continuation lines */
        for (; *p; p++) {
            if (*p == '\n') {
                if (p > c && p[-1] == '\\') continue;
                break;
            }
            if (*p != '\\' || p[1] != '\n') *p = ' ';
        }
        if (!*p) break;
    }
    return c;
}

typedef void (*long_visit)(const char *name, size_t lines, void *data);

/* Every function body in `text` (a C file): a '{' at file scope whose
 * previous token is ')' opens one; its name is the identifier before the
 * matching '('.  visit() gets each function over `limit` lines.  Returns
 * the number of functions found, or -1 when the braces do not balance. */
static long long_functions_of(const char *text, size_t limit, long_visit visit, void *data)
{
    char *code = code_without_directives(text);
    if (!code) return -1;
    long found = 0;
    int depth = 0;
    const char *open = NULL;
    char name[128] = "";
    size_t name_line = 0, line = 1;
    for (const char *p = code; *p; p++) {
        if (*p == '\n') line++;
        if (*p == '{') {
            if (depth++ > 0) continue;
            const char *b = p;
            while (b > code && (b[-1] == ' ' || b[-1] == '\t' || b[-1] == '\n')) b--;
            if (b == code || b[-1] != ')') continue;
            /* back over the parameter list to its '(' */
            int paren = 0;
            const char *q = b - 1;
            for (; q >= code; q--) {
                if (*q == ')') paren++;
                else if (*q == '(' && --paren == 0) break;
            }
            if (q < code) continue;
            while (q > code && (q[-1] == ' ' || q[-1] == '\t' || q[-1] == '\n')) q--;
            const char *e = q;
            while (q > code && ident_char(q[-1])) q--;
            if (q == e) continue;
            snprintf(name, sizeof name, "%.*s", (int)(e - q), q);
            name_line = line;
            for (const char *r = q; r < p; r++) name_line -= *r == '\n';
            open = p;
        } else if (*p == '}') {
            if (--depth < 0) break;
            if (depth == 0 && open) {
                size_t lines = line - name_line + 1;
                found++;
                if (lines > limit) visit(name, lines, data);
                open = NULL;
            }
        }
    }
    free(code);
    return depth == 0 ? found : -1;
}

typedef struct {
    const char *file; /* below src/ */
    int bad;
    int seen[NLONG];
    long functions;
} long_scan;

static void long_seen(const char *name, size_t lines, void *data)
{
    long_scan *s = data;
    for (size_t i = 0; i < NLONG && long_functions[i].file; i++)
        if (strcmp(long_functions[i].file, s->file) == 0 &&
            strcmp(long_functions[i].function, name) == 0) {
            s->seen[i] = 1;
            return;
        }
    s->bad++;
    bkf_test_note("src/%s: %s is %zu lines (at most %d; split it by concern, or list it in "
                  "tests/core/test_layers.c with the reason)",
                  s->file, name, lines, MAX_FUNCTION_LINES);
}

static void count_long(const char *name, size_t lines, void *data)
{
    (void)name;
    (void)lines;
    (*(int *)data)++;
}

/* One file's long functions (a C source or header) into the scan. */
static void scan_file_lengths(size_t layer, const char *name, const char *path, void *data)
{
    long_scan *scan = data;
    size_t len = strlen(name);
    if (len < 3 || (strcmp(name + len - 2, ".c") != 0 && strcmp(name + len - 2, ".h") != 0))
        return;
    char file[400];
    snprintf(file, sizeof file, "%s/%.255s", layers[layer].name, name);
    char *text = slurp(path);
    CHECK_MSG(text, "cannot read %s", path);
    if (!text) return;
    scan->file = file;
    size_t lines = 0;
    for (const char *p = text; *p; p++) lines += *p == '\n';
    if (lines > MAX_FILE_LINES) {
        scan->bad++;
        bkf_test_note("src/%s is %zu lines (at most %d: split it by concern)", file, lines,
                      MAX_FILE_LINES);
    }
    long got = long_functions_of(text, MAX_FUNCTION_LINES, long_seen, scan);
    CHECK_MSG(got >= 0, "%s: the braces do not balance (the scan is lost)", path);
    scan->functions += got > 0 ? got : 0;
    free(text);
}

TEST(layers_no_function_is_over_150_lines_nor_file_over_1500)
{
    long_scan scan = {0};
    CHECK(each_source_file(scan_file_lengths, &scan) == 0);
    long functions = scan.functions;
    CHECK_MSG(functions > 1000, "only %ld functions found: wrong source folder?", functions);
    for (size_t i = 0; i < NLONG && long_functions[i].file; i++)
        CHECK_MSG(scan.seen[i], "src/%s: %s is listed as long (%s) but is not: take it off the list",
                  long_functions[i].file, long_functions[i].function, long_functions[i].reason);
    CHECK_MSG(scan.bad == 0, "%d functions over %d lines or files over %d (listed above)",
              scan.bad, MAX_FUNCTION_LINES, MAX_FILE_LINES);
}

TEST(layers_function_length_checker_catches_long_ones)
{
    /* planted: a 200-line function (name to closing brace) after a short one whose strings,
     * character literals, comments and a macro hold stray braces */
    size_t cap = 1 << 14, len = 0;
    char *text = malloc(cap);
    CHECK(text);
    if (!text) return;
    len += (size_t)snprintf(text + len, cap - len,
                            "#define OPEN {\n"
                            "static const char *s = \"}}{\";\n"
                            "int small(int x)\n{\n    char c = '}'; /* { */\n"
                            "    // }\n    return x + (c == '{');\n}\n"
                            "struct t { int a; };\n"
                            "static const int table[] = {1, 2};\n"
                            "static int\nplanted(int x,\n        int y)\n{\n");
    for (int i = 0; i < 195; i++)
        len += (size_t)snprintf(text + len, cap - len, "    x += y * %d; /* } */\n", i);
    snprintf(text + len, cap - len, "    return x;\n}\n");
    int n_long = 0;
    CHECK(long_functions_of(text, MAX_FUNCTION_LINES, count_long, &n_long) == 2);
    CHECK(n_long == 1);
    /* its length: from the name's line (not the type's) to the brace */
    n_long = 0;
    long_functions_of(text, 200, count_long, &n_long);
    CHECK(n_long == 0);
    long_functions_of(text, 199, count_long, &n_long);
    CHECK(n_long == 1);
    /* a brace too many is a lost scan, not a pass */
    CHECK(long_functions_of("int f(void)\n{\n}\n}\n", 150, count_long, &n_long) == -1);
    free(text);
}

/* ------------------------------------------------------------ the map */

/* CONTRIBUTING.md's map of the source follows the tree: every file it names
 * exists, and every file of src/LAYER/ is in that layer's row of the table
 * (by its name in backticks, a module as an item of the row's list, a
 * command as `cmd_NAME.c`, a header with its source file). */

/* A name the "adding a product" recipe makes up: `bkfront trains`, X.c,
 * cmd_NAME.c, src/<layer>/. */
static int made_up(const char *tok)
{
    if (strchr(tok, '<') || strstr(tok, "NAME")) return 1;
    const char *base = strrchr(tok, '/') ? strrchr(tok, '/') + 1 : tok;
    if (base[0] == 'X' && (base[1] == '.' || base[1] == '_')) return 1;
    for (const char *p = tok; (p = strstr(p, "trains")) != NULL; p++)
        if (strncmp(p, "trainspec", 9) != 0) return 1;
    return 0;
}

static int exists(const char *rel)
{
    char path[1400];
    struct stat st;
    snprintf(path, sizeof path, "%s/%.1300s", BKF_SOURCE_DIR, rel);
    return stat(path, &st) == 0;
}

static int has_suffix(const char *s, const char *suffix)
{
    size_t n = strlen(s), m = strlen(suffix);
    return n >= m && strcmp(s + n - m, suffix) == 0;
}

/* Whether a file named in backticks (a path, or a bare name of src/ or of
 * include/bkfront/) exists; 1 for what is no file name. */
static int named_file_exists(const char *tok)
{
    int file = has_suffix(tok, ".c") || has_suffix(tok, ".h") || has_suffix(tok, ".awk") ||
               has_suffix(tok, ".md") || has_suffix(tok, ".gp") || has_suffix(tok, ".sh");
    int path = strncmp(tok, "src/", 4) == 0 || strncmp(tok, "include/", 8) == 0 ||
               strncmp(tok, "tests/", 6) == 0 || strncmp(tok, "docs/", 5) == 0 ||
               strncmp(tok, "plots/", 6) == 0;
    if ((!file && !path) || made_up(tok)) return 1;
    char rel[600];
    if (path) return exists(tok);
    if (strncmp(tok, "bkfront/", 8) == 0) {
        snprintf(rel, sizeof rel, "include/%s", tok);
        return exists(rel);
    }
    if (strchr(tok, '/')) return exists(tok);
    snprintf(rel, sizeof rel, "include/bkfront/%s", tok);
    if (exists(rel)) return 1;
    for (size_t l = 0; l < NLAYERS; l++) {
        snprintf(rel, sizeof rel, "src/%s/%s", layers[l].name, tok);
        if (exists(rel)) return 1;
    }
    return 0;
}

/* Whether `row` lists `module` as an item: after "| ", ", " or "; ",
 * before ',', ';', " (" or " |". */
static int lists_module(const char *row, const char *module)
{
    size_t n = strlen(module);
    for (const char *p = row; (p = strstr(p, module)) != NULL; p++) {
        if (p - row < 2 || p[-1] != ' ' || (p[-2] != '|' && p[-2] != ',' && p[-2] != ';'))
            continue;
        const char *e = p + n;
        if (*e == ',' || *e == ';' || (e[0] == ' ' && (e[1] == '(' || e[1] == '|'))) return 1;
    }
    return 0;
}

/* Whether the layer's row of the map names file `name` of its folder. */
static int row_names(const char *row, const char *name)
{
    char tok[300];
    snprintf(tok, sizeof tok, "`%s`", name);
    if (strstr(row, tok)) return 1;
    if (strncmp(name, "cmd_", 4) == 0 && has_suffix(name, ".c") && strstr(row, "`cmd_NAME.c`"))
        return 1;
    char stem[256];
    snprintf(stem, sizeof stem, "%s", name);
    char *dot = strrchr(stem, '.');
    if (dot) *dot = '\0';
    if (has_suffix(name, ".h")) { /* a header goes with its source file */
        if (has_suffix(stem, "_internal")) stem[strlen(stem) - 9] = '\0';
        char c[300];
        snprintf(c, sizeof c, "%s.c", stem);
        return row_names(row, c);
    }
    return has_suffix(name, ".c") && lists_module(row, stem);
}

typedef struct {
    size_t layer;
    char *names; /* "a.c b.h ..." */
    size_t size;
} name_list;

static void add_name(size_t layer, const char *name, const char *path, void *data)
{
    (void)path;
    name_list *n = data;
    size_t used = strlen(n->names);
    if (layer == n->layer && used + strlen(name) + 2 < n->size)
        snprintf(n->names + used, n->size - used, "%s ", name);
}

/* The problems of the map in `text` (CONTRIBUTING.md), each noted when
 * `report`; `tree` names each layer's files: tree[l] "a.c b.h ..." or NULL
 * to read the folders. */
static int map_problems(const char *text, const char *const *tree, int report)
{
    int bad = 0;
    for (const char *p = text; (p = strchr(p, '`')) != NULL; p++) {
        const char *e = strchr(p + 1, '`');
        if (!e) break;
        char tok[300];
        if (e - p - 1 > 0 && e - p - 1 < (long)sizeof tok && !memchr(p + 1, ' ', (size_t)(e - p - 1))) {
            snprintf(tok, sizeof tok, "%.*s", (int)(e - p - 1), p + 1);
            if (!named_file_exists(tok)) {
                bad++;
                if (report) bkf_test_note("CONTRIBUTING.md names `%s`: no such file", tok);
            }
        }
        p = e;
    }
    for (size_t l = 0; l < NLAYERS; l++) {
        char head[96];
        snprintf(head, sizeof head, "\n| %s | `src/%s/` |", layers[l].name, layers[l].name);
        const char *row = strstr(text, head);
        if (!row) {
            bad++;
            if (report) bkf_test_note("CONTRIBUTING.md: no row for layer %s", layers[l].name);
            continue;
        }
        const char *end = strchr(row + 1, '\n');
        char *line = strndup(row, end ? (size_t)(end - row) : strlen(row));
        if (!line) return bad + 1;
        /* the modules' cell alone: "may use" names layers, not files */
        char *last = strrchr(line, '|');
        if (last) *last = '\0';
        if ((last = strrchr(line, '|')) != NULL) last[1] = '\0';
        char names[8192] = "";
        if (tree) {
            snprintf(names, sizeof names, "%s", tree[l] ? tree[l] : "");
        } else {
            name_list list = {l, names, sizeof names};
            each_source_file(add_name, &list);
        }
        for (char *save = NULL, *f = strtok_r(names, " ", &save); f; f = strtok_r(NULL, " ", &save))
            if (!row_names(line, f)) {
                bad++;
                if (report)
                    bkf_test_note("CONTRIBUTING.md: src/%s/%s is not in the map's %s row",
                                  layers[l].name, f, layers[l].name);
            }
        free(line);
    }
    return bad;
}

TEST(layers_docs_contributing_map_is_the_tree)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/CONTRIBUTING.md", BKF_SOURCE_DIR);
    char *text = slurp(path);
    CHECK_MSG(text, "cannot read %s", path);
    if (!text) return;
    int bad = map_problems(text, NULL, 1);
    CHECK_MSG(bad == 0, "CONTRIBUTING.md's map is not the tree (%d problems, listed above)", bad);
    free(text);
}

TEST(layers_docs_map_checker_catches_strays)
{
    /* planted: a map naming a file that is not there, and a tree with a
     * file the map does not name; the made-up names of the recipe pass */
    const char *rows = "\n| core | `src/core/` | status, model (`io.c` io) | C, plot |"
                       "\n| wave | `src/wave/` | cycle (`cycle_flow.c` the flow) | core |"
                       "\n| stability | `src/stability/` | hill | core |"
                       "\n| simulation | `src/simulation/` | pde | core |"
                       "\n| products | `src/products/` | period | core |"
                       "\n| scene | `src/scene/` | plot | core |"
                       "\n| cli | `src/cli/` | one `cmd_NAME.c` per subcommand | lib |\n"
                       "Say `bkfront trains`: `src/products/trains.c`, `X_<concern>.c`.\n";
    const char *tree[NLAYERS] = {"status.c model.c io.c", "cycle.c cycle_internal.h cycle_flow.c",
                                 "hill.c", "pde.c", "period.c", "plot.c", "cmd_run.c"};
    CHECK(map_problems(rows, tree, 0) == 0);
    /* a piece the row does not name, a module only in prose or in the
     * "may use" cell */
    const char *more[NLAYERS] = {"status.c model.c io.c h5.c plot.c", "cycle.c cycle_shoot.c",
                                 "hill.c", "pde.c", "period.c", "plot.c", "cmd_run.c main.c"};
    CHECK(map_problems(rows, more, 0) == 4);
    /* a named file that is not in the tree */
    char *stale = malloc(strlen(rows) + 64);
    CHECK(stale);
    if (!stale) return;
    snprintf(stale, strlen(rows) + 64, "%s and `src/core/removed_long_ago.c`\n", rows);
    CHECK(map_problems(stale, tree, 0) == 1);
    free(stale);
}

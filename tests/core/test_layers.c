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

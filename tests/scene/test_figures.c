/* The figures adapt to their data: every plot script that bkfront run uses,
 * drawn by a scene at two parameter sets far from the paper's, keeps every
 * point it plots inside the ranges it draws (issue 36).
 *
 * How a point "outside" is seen: the scripts are copied with two lines after
 * each plot command that print gnuplot's own range report (GPVAL_X_MIN ..
 * GPVAL_Y_MAX) and replot the same command into a table, where gnuplot
 * flags each point i (in range), o (outside the drawn ranges) or u
 * (undefined).  A fixed range that hides data (speeds.gp's old yrange
 * [0.2:5], which hid n >= 10 and the line v = c at gamma 6, c 0.1) shows as
 * o points; an empty figure as one without any i point. */
#define _XOPEN_SOURCE 700
#include "harness.h"

#include <dirent.h>
#include <ftw.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cli_support.h"

#ifndef BKF_SOURCE_DIR
#define BKF_SOURCE_DIR "."
#endif

static int remove_one(const char *path, const struct stat *st, int flag, struct FTW *ftw)
{
    (void)st, (void)flag, (void)ftw;
    return remove(path);
}

#define write_text bkf_cli_write_text

/* plots/NAME.gp copied into dir with the probe after each plot command (a
 * line starting "plot", through its continuation lines); a plot that
 * writes a table itself (sweep_map's boundaries) is left alone. */
static void instrument(const char *name, const char *dir, const char *probe_dir)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/plots/%s", BKF_SOURCE_DIR, name);
    char *text = bkf_cli_read_file(path);
    CHECK_MSG(text, "cannot read %s", path);
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE *out = fopen(path, "w");
    CHECK(out);
    int in_plot = 0, own_table = 0;
    for (char *line = text; *line;) {
        size_t len = strcspn(line, "\n");
        const char *p = line;
        while (*p == ' ' || *p == '\t') p++;
        if (!in_plot && strncmp(p, "plot ", 5) == 0) in_plot = 1, own_table = 0;
        fwrite(line, 1, len, out);
        fputc('\n', out);
        if (in_plot) {
            size_t k = len;
            while (k && (line[k - 1] == ' ' || line[k - 1] == '\r')) k--;
            char save = line[len];
            line[len] = '\0';
            if (strstr(line, "with table")) own_table = 1;
            line[len] = save;
            if (!(k && line[k - 1] == '\\')) {
                in_plot = 0;
                size_t dot = strcspn(name, ".");
                if (!own_table)
                    fprintf(out, "bkf_probe = '%s/%.*s.ranges'; load '%s/probe.gp'\n", probe_dir,
                            (int)dot, name, probe_dir);
            }
        }
        line += len + (line[len] == '\n');
    }
    CHECK(fclose(out) == 0);
    free(text);
}

/* Copies plots/ (scripts instrumented, the rest as is) into dir/plots and
 * writes the probe into dir/probe. */
static void instrumented_plots(const char *dir)
{
    char plots[600], probe[600], path[1200];
    snprintf(plots, sizeof plots, "%s/plots", dir);
    snprintf(probe, sizeof probe, "%s/probe", dir);
    CHECK(mkdir(plots, 0700) == 0 && mkdir(probe, 0700) == 0);
    snprintf(path, sizeof path, "%s/probe.gp", probe);
    write_text(path, "set print bkf_probe append\n"
                     "print sprintf('# ranges x %.17g %.17g y %.17g %.17g', GPVAL_X_MIN, "
                     "GPVAL_X_MAX, GPVAL_Y_MIN, GPVAL_Y_MAX)\n"
                     "unset print\n"
                     "set table bkf_probe append\n"
                     "replot\n"
                     "unset table\n");
    DIR *d = opendir(BKF_SOURCE_DIR "/plots");
    CHECK(d);
    struct dirent *e;
    while ((e = readdir(d))) {
        size_t n = strlen(e->d_name);
        if (n > 3 && strcmp(e->d_name + n - 3, ".gp") == 0) {
            instrument(e->d_name, plots, probe);
        } else if (n > 4 && strcmp(e->d_name + n - 4, ".awk") == 0) {
            snprintf(path, sizeof path, "%s/plots/%s", BKF_SOURCE_DIR, e->d_name);
            char *text = bkf_cli_read_file(path);
            CHECK(text);
            snprintf(path, sizeof path, "%s/%s", plots, e->d_name);
            write_text(path, text);
            free(text);
        }
    }
    closedir(d);
}

/* The probe's report of one script: every plot command of it kept its
 * points in view, and the figure drew at least one.  Each fault is noted (the
 * first of each plot); returns their number. */
static int check_ranges(const char *dir, const char *script, const char *set)
{
    char path[1200];
    snprintf(path, sizeof path, "%s/probe/%s.ranges", dir, script);
    char *text = bkf_cli_read_file(path);
    if (!text) {
        bkf_test_note("%s: %s.gp drew nothing", set, script);
        return 1;
    }
    int plots = 0, faults = 0, noted = 0;
    long inside = 0;
    double x0 = 0, x1 = 0, y0 = 0, y1 = 0;
    for (char *line = text;;) {
        size_t len = strcspn(line, "\n");
        char save = line[len];
        line[len] = '\0';
        if (strncmp(line, "# ranges ", 9) == 0) {
            plots++;
            noted = 0;
            CHECK(sscanf(line, "# ranges x %lf %lf y %lf %lf", &x0, &x1, &y0, &y1) == 4);
        } else if (line[0] && line[0] != '#') {
            /* x y ... type: the type is the last word */
            const char *end = line + strlen(line);
            while (end > line && (end[-1] == ' ' || end[-1] == '\t')) end--;
            char type = end > line ? end[-1] : 'u';
            /* gnuplot's own report and its flags agree: x is written in the
             * axis' format (6 digits by default; a format such as 10^{%T}
             * is no number and not compared) */
            char *xend;
            double x = strtod(line, &xend);
            int number = xend != line && (*xend == ' ' || *xend == '\t');
            double slack = 1e-5 * (fabs(x0) + fabs(x1));
            int out = type == 'o' ||
                      (type == 'i' && number && !(x >= x0 - slack && x <= x1 + slack));
            if (out && !noted++)
                bkf_test_note("%s: %s.gp plot %d draws x in [%g, %g], y in [%g, %g]; "
                              "outside: '%s'", set, script, plots, x0, x1, y0, y1, line);
            faults += out;
            inside += type == 'i';
        }
        if (!save) break;
        line += len + 1;
    }
    /* a panel may hold no point (a key of its own, an oscillation stable
     * throughout); a figure may not */
    if (inside == 0) {
        bkf_test_note("%s: %s.gp: %d plots, no point in view", set, script, plots);
        faults++;
    }
    free(text);
    return faults;
}

/* What every figure kind needs, cheaply: short runs, coarse grids. */
#define FAR_BODY                                                                     \
    "[accuracy]\ntol = 1e-8\nN = 128\n"                                                \
    "[friction fric]\npoints = 101\n[figure fric]\ndata = fric\n"                      \
    "[speeds table]\n[figure speeds]\ndata = table\n"                                  \
    "[spacetime st]\ntmax = 4\nframes = 20\ninit = front:n=2,noise=0.01\n"             \
    "[figure st]\ndata = st\n"                                                         \
    "[dispersion disp]\nq = 0:6:25\n[figure disp]\ndata = disp\n"                      \
    "[validity val]\nmu = 0.1:1e4:6\nnu = -0.9:0.9:4\n[figure val]\ndata = val\n"      \
    "[profile prof]\nn = 1,2\npoints = 200\n[figure prof]\ndata = prof\n"              \
    "[stability spec]\nn = 1,2\ntol = 1e-5\n[figure spec]\ndata = spec\n"              \
    "[stability line]\nn = 1\nline = yes\nkappa-count = 6\ntol = 1e-5\n"              \
    "[figure line]\ndata = line\n"                                                     \
    "[speeds chain]\nmodel = chain\nN = 60\nnmax = 2\nstability = yes\n"                       \
    "[speeds cont]\nnmax = 2\n[figure chain]\ndata = cont, chain\n"                    \
    "[check chk]\nn = 2\ntmax = 8\nrel_tol = 0.01\n[figure chk]\ndata = chk\n"

static const struct {
    const char *name, *text;
} far_sets[] = {
    {"gamma 6, c 0.1, nu -0.99, S 40",
     "[model]\ngamma = 6\nc = 0.1\nnu = -0.99\nS = 40\n" FAR_BODY
     "[period per]\nnu = 0,-0.99\nmu = 0.1:1e4:7\n[figure per]\ndata = per\n"
     "[branch br]\nparam = S\nto = 30\nn = 2\ntol = 1e-6\n"
     "[figure br]\ndata = br\n"
     "[threshold th]\nalong = c\nfrom = 0.1\nto = 1\nsearch = -0.999:-0.8\ntol = 1e-6\n"
     "[figure th]\ndata = th\n"
     "[stability diag]\ndiagram = yes\nn = 2\nnu = -0.99\nto = -0.95\nnu-step = 0.04\n"
     "S = 2\nS-to = 40\nS-samples = 2\ntol = 1e-4\nS-tol = 0.5\n[figure diag]\ndata = diag\n"
     "[sweep sw]\nx = nu=-0.99:-0.95:2\ny = gamma=5:6:2\ntmax = 2\nN = 64\n"
     "thresholds = 6\nsearch = -0.999:-0.8\n[figure sw]\ndata = sw\n"
     /* the orbits' own model: at gamma 6, c 0.1 the mode of q_c is j = 46;
      * N 36, 12 points a cell of mode j = 3 (the default 96 cost 2.6 s of
      * CPU against 0.6 for a branch within 1e-8 of it in nu) */
     "[orbit orb]\ngamma = 2.5\nc = 0.6\nS = 15\nmax-points = 5\nno-stability = yes\nN = 36\n"
     "[figure orb]\ndata = orb\n"},
    {"gamma 0.7, c 0.8, nu 0.4, S 15",
     "[model]\ngamma = 0.7\nc = 0.8\nnu = 0.4\nS = 15\n" FAR_BODY
     "[period per]\nnu = 0.4,0.9\nmu = 0.1:1e4:7\n[figure per]\ndata = per\n"
     "[branch br]\nparam = S\nto = 10\nn = 1\ntol = 1e-6\nstability = yes\n"
     "[figure br]\ndata = br\n"
     "[threshold th]\nalong = gamma\nfrom = 2\nto = 4\ntol = 1e-6\n[figure th]\ndata = th\n"
     "[stability diag]\ndiagram = yes\nn = 2\nnu = 0.3\nto = 0.5\nnu-step = 0.2\n"
     "S = 2\nS-to = 15\nS-samples = 2\ntol = 1e-4\nS-tol = 0.5\n[figure diag]\ndata = diag\n"
     "[sweep sw]\nx = nu=0.3:0.5:2\ny = gamma=0.6:0.8:2\ntmax = 2\nN = 64\n"
     "thresholds = 0.7\n[figure sw]\ndata = sw\n"
     /* gamma 0.7 has no period doubling */
     "[orbit orb]\ngamma = 3\nc = 0.8\nS = 15\nmax-points = 5\nno-stability = yes\nN = 36\n"
     "[figure orb]\ndata = orb\n"},
};

/* Every script a scene draws with (plots/KIND.gp but common.gp, logtics.gp
 * and the benchmark's work_precision_*.gp, which draw make bench's table). */
static const char *const scripts[] = {
    "friction", "speeds",        "spacetime", "dispersion", "period",     "validity",
    "profile",  "spectrum",      "branch",    "threshold",  "diagram",    "spectrum_line",
    "check",    "chain_speeds",  "sweep_map", "orbit",
};

/* A script that is neither drawn by the test nor one of the exceptions
 * above fails it: a new figure kind is tested when it comes. */
static int known_script(const char *file)
{
    if (strcmp(file, "common.gp") == 0 || strcmp(file, "logtics.gp") == 0 ||
        strncmp(file, "work_precision_", 15) == 0)
        return 1;
    for (size_t i = 0; i < sizeof scripts / sizeof scripts[0]; i++)
        if (strncmp(file, scripts[i], strlen(scripts[i])) == 0 &&
            strcmp(file + strlen(scripts[i]), ".gp") == 0)
            return 1;
    return 0;
}

/* Draws every figure of the far set k and counts the points out of view. */
static void figures_in_view(size_t k)
{
    DIR *d = opendir(BKF_SOURCE_DIR "/plots");
    CHECK(d);
    for (struct dirent *e; (e = readdir(d));) {
        size_t n = strlen(e->d_name);
        if (n > 3 && strcmp(e->d_name + n - 3, ".gp") == 0)
            CHECK_MSG(known_script(e->d_name), "plots/%s is not drawn by this test",
                      e->d_name);
    }
    closedir(d);
    char dir[] = "/tmp/bkf_figures_XXXXXX";
    CHECK(mkdtemp(dir));
    instrumented_plots(dir);
    char scene[600], out[600], plots[600];
    snprintf(scene, sizeof scene, "%s/far.scene", dir);
    snprintf(out, sizeof out, "%s/out", dir);
    snprintf(plots, sizeof plots, "%s/plots", dir);
    write_text(scene, far_sets[k].text);
    /* svg: the ranges are gnuplot's, whatever the terminal, and the png
     * terminal's rendering cost 1.1 s of CPU a set, a fifth of the test */
    bkf_cli_result r = BKF_CLI("run", "--formats", "svg", "--out", out, "--plots", plots, scene);
    CHECK_MSG(r.code == 0, "%s: exit %d: %s\n%s", far_sets[k].name, r.code, r.err, r.out);
    bkf_cli_result_free(&r);
    int faults = 0;
    for (size_t i = 0; i < sizeof scripts / sizeof scripts[0]; i++)
        faults += check_ranges(dir, scripts[i], far_sets[k].name);
    nftw(dir, remove_one, 16, FTW_DEPTH | FTW_PHYS);
    CHECK_MSG(faults == 0, "%s: %d points out of view or empty figures (above)",
              far_sets[k].name, faults);
}

TEST(figures_keep_every_point_in_view_at_gamma_6_c_0_1)
{
    figures_in_view(0);
}

TEST(figures_keep_every_point_in_view_at_gamma_0_7_c_0_8)
{
    figures_in_view(1);
}

/* The diagram's `state` rows, which fill a column without crossing, say
 * what the paper's table says at nu -0.96, S 20 (docs/cli/stability.md,
 * checked against Hill's method in tests/products/test_stability.c): n = 2
 * and 3 unstable (sigma_max 0.0697, 0.0244), n = 4 stable (-1.7e-3).  The
 * scan's window S in [19.5, 20.5] holds no crossing of theirs (at nu -0.96
 * and -0.959, the grid's end).  Without state rows the columns were empty. */
TEST(diagram_state_rows_are_the_paper_verdicts)
{
    bkf_cli_result r = BKF_CLI("stability", "--gamma", "2", "--c", "0.3", "--nu", "-0.96", "--S",
                               "19.5", "--n", "4", "--diagram", "--to", "-0.959", "--S-to", "20.5",
                               "--nu-step", "0.5", "--S-samples", "2", "--tol", "1e-5");
    CHECK_MSG(r.code == 0, "exit %d: %s", r.code, r.err);
    int verdict[5] = {-1, -1, -1, -1, -1};
    for (int row = 0;; row++) {
        char kind[32];
        double n, above, S;
        if (!bkf_tsv_cell(r.out, row, "kind", NULL, kind, sizeof kind)) break;
        if (strcmp(kind, "state") != 0) continue;
        CHECK(bkf_tsv_cell(r.out, row, "n", &n, NULL, 0) && n >= 1 && n <= 4);
        CHECK(bkf_tsv_cell(r.out, row, "above", &above, NULL, 0));
        CHECK(bkf_tsv_cell(r.out, row, "S", &S, NULL, 0) && S > 19.5 && S < 20.5);
        verdict[(int)n] = (int)above;
    }
    CHECK_MSG(verdict[2] == 0 && verdict[3] == 0 && verdict[4] == 1,
              "state of n = 2, 3, 4: %d %d %d (want 0 0 1)\n%s", verdict[2], verdict[3],
              verdict[4], r.out);
    bkf_cli_result_free(&r);
}

/* Scenes: parsing (good files and bad ones, with line numbers), the lazy
 * plan (products asked for -> computations, counted), `bkfront run` with
 * real gnuplot figures, and `bkfront profile`. */
#define _POSIX_C_SOURCE 200809L
#include "harness.h"

#include <dirent.h>
#include <math.h>
#include <pthread.h>
#include <fcntl.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "bkfront/chainwave.h"
#include "bkfront/plot.h"
#include "bkfront/scene.h"
#include "cli_support.h"

#ifndef BKF_SOURCE_DIR
#define BKF_SOURCE_DIR "."
#endif

static bkf_scene *parse_ok(const char *text)
{
    bkf_scene *s = NULL;
    bkf_error e = {0};
    int status = bkf_scene_parse_string(text, "t.scene", &s, &e);
    CHECK_MSG(status == BKF_OK, "parse failed: %s", e.message);
    return s;
}

/* The scene is refused with a message starting "t.scene:LINE:" and holding
 * `part`. */
static void parse_bad(const char *text, int line, const char *part)
{
    bkf_scene *s = (bkf_scene *)1;
    bkf_error e = {0};
    CHECK_STATUS(bkf_scene_parse_string(text, "t.scene", &s, &e), BKF_EINPUT);
    CHECK(s == NULL);
    char prefix[32];
    snprintf(prefix, sizeof prefix, "t.scene:%d: ", line);
    CHECK_MSG(strncmp(e.message, prefix, strlen(prefix)) == 0, "want '%s...', got '%s'", prefix,
              e.message);
    CHECK_MSG(strstr(e.message, part) != NULL, "want '%s' in '%s'", part, e.message);
    CHECK_MSG(strchr(e.message, '\n') == NULL, "two lines: %s", e.message);
}

#define MODEL "[model]\ngamma = 2\nc = 0.3\nnu = -0.96\nS = 20\n"

TEST(scene_parses_the_paper_scene)
{
    bkf_scene *s = NULL;
    bkf_error e = {0};
    CHECK_STATUS(bkf_scene_parse_file(BKF_SOURCE_DIR "/fronts/paper.scene", &s, &e), BKF_OK);
    size_t figures = 0, kinds[BKF_SCENE_NKINDS] = {0};
    for (size_t i = 0; i < s->nproducts; i++) {
        kinds[s->products[i].kind]++;
        figures += s->products[i].kind == BKF_SCENE_FIGURE;
    }
    /* every paper figure and every figure the issue lists beyond it */
    CHECK(kinds[BKF_SCENE_FRICTION] == 1 && kinds[BKF_SCENE_SPACETIME] == 3);
    CHECK(kinds[BKF_SCENE_DISPERSION] == 1 && kinds[BKF_SCENE_SPEEDS] == 1);
    CHECK(kinds[BKF_SCENE_PERIOD] == 1 && kinds[BKF_SCENE_VALIDITY] == 1);
    CHECK(kinds[BKF_SCENE_PROFILE] == 1 && kinds[BKF_SCENE_BRANCH] == 1);
    CHECK(kinds[BKF_SCENE_STABILITY] == 3);
    CHECK(figures == s->nproducts - figures);
    const bkf_scene_product *fig3a = bkf_scene_find(s, "fig3a", 0);
    CHECK(fig3a && fig3a->kind == BKF_SCENE_SPACETIME);
    CHECK(strcmp(bkf_scene_value(s, fig3a, "nu"), "-0.92") == 0);   /* its own */
    CHECK(strcmp(bkf_scene_value(s, fig3a, "gamma"), "2") == 0);    /* from [model] */
    CHECK(strcmp(bkf_scene_value(s, fig3a, "N"), "512") == 0);      /* from [accuracy] */
    /* a Runge-Kutta tolerance is not the accuracy asked of a result */
    CHECK(bkf_scene_value(s, fig3a, "tol") == NULL);
    const bkf_scene_product *table = bkf_scene_find(s, "table", 0);
    CHECK(strcmp(bkf_scene_value(s, table, "tol"), "1e-10") == 0);
    CHECK(bkf_scene_find(s, "fig3a", 1) && bkf_scene_find(s, "fig3a", 1)->kind == BKF_SCENE_FIGURE);
    bkf_scene_free(s);
}

TEST(scene_keys_inherit_and_sections_keep_their_lines)
{
    bkf_scene *s = parse_ok("# comment\n" MODEL "\n[accuracy]\ntol = 1e-8 ; inline\n"
                        "[speeds]\n\n[speeds second]\nn = 3\nS = 30\n");
    CHECK(s->nproducts == 2);
    CHECK(strcmp(s->products[0].name, "speeds") == 0 && s->products[0].line == 10);
    CHECK(strcmp(s->products[1].name, "second") == 0 && s->products[1].line == 12);
    CHECK(strcmp(bkf_scene_value(s, &s->products[0], "tol"), "1e-8") == 0);
    CHECK(strcmp(bkf_scene_value(s, &s->products[1], "S"), "30") == 0);
    CHECK(strcmp(bkf_scene_value(s, &s->products[0], "S"), "20") == 0);
    CHECK(s->products[1].nentries == 2 && s->products[1].entries[0].line == 13);
    bkf_scene_free(s);
}

TEST(scene_errors_name_the_file_and_line)
{
    parse_bad(MODEL "[spedes]\n", 6, "unknown section [spedes]");
    parse_bad(MODEL "[speeds]\nnmx = 3\n", 7, "unknown key 'nmx'");
    parse_bad(MODEL "[speeds]\nnmax = three\n", 7, "nmax");
    parse_bad("[model]\ngamma = 2\nc = 0.3\nnu = -1.2\nS = 20\n[speeds]\n", 4, "(-1, 1)");
    parse_bad("[model]\ngamma = nan\n", 2, "not a finite number");
    parse_bad("[model]\nc = -1\n", 2, "must be >= 0");
    parse_bad("[model]\nS = 0\n", 2, "must be > 0");
    parse_bad(MODEL "S = 3\n[speeds]\n", 6, "already set on line 5");
    parse_bad(MODEL "[speeds]\n[speeds]\n", 7, "already used on line 6");
    parse_bad(MODEL "[speeds a]\n[figure f]\ntitle = x\n", 7, "give data = NAME");
    parse_bad(MODEL "[speeds a]\n[figure f]\ndata = b\n", 8, "no product named 'b'");
    parse_bad("gamma = 2\n[model]\n", 1, "before any [section]");
    /* (the products' own checks: param before from, which names it) */
    parse_bad(MODEL "[branch b]\nto = 30\n", 6, "[branch b]: param is required (one of S, nu");
    parse_bad(MODEL "[branch b]\nparam = S\n", 6, "[branch b]: to is required");
    parse_bad(MODEL "[threshold t]\nalong = c\nto = 1\n", 6, "from is required with along");
    parse_bad(MODEL "[threshold t]\nfrom = 0.1\nto = 1\n", 7, "from: only with along");
    parse_bad(MODEL "[speeds]\nn = 3\nnmax = 4\n", 7, "n, nmax: give one of them");
    parse_bad(MODEL "[speeds]\nthis line has no equals sign\n", 7, "not a section header");
    parse_bad(MODEL "[speeds two words]\n", 6, "[KIND] or [KIND NAME]");
    parse_bad(MODEL "[accuracy]\ntol = 1\n[speeds]\n", 7, "tol: 1 is outside");
    parse_bad(MODEL "[period p]\nnu = 0,1.5\n", 7, "outside (-1, 1)");
    parse_bad(MODEL "[period p]\nmu = 1:2:1e9\n", 7, "mu");
    parse_bad(MODEL "[spacetime s]\ninit = sine\n", 7, "init: 'sine'");
    parse_bad(MODEL "[figure f]\ndata = f\n", 7, "no product named 'f'");
    parse_bad(MODEL, 5, "asks for no product");
    parse_bad("[speeds]\n", 1, "no [model] section");
    parse_bad("[model]\ngamma = 2\n[speeds]\n", 3, "c is not set here nor in [model]");
    char longline[400];
    memset(longline, 'x', sizeof longline);
    memcpy(longline, "title = ", 8);
    longline[sizeof longline - 1] = '\0';
    char text[600];
    snprintf(text, sizeof text, MODEL "[speeds]\n[figure f]\ndata = speeds\n%s\n", longline);
    parse_bad(text, 9, "longer than");
}

TEST(scene_file_errors)
{
    bkf_scene *s = NULL;
    bkf_error e = {0};
    CHECK_STATUS(bkf_scene_parse_file("/nonexistent/x.scene", &s, &e), BKF_EINPUT);
    CHECK(strstr(e.message, "cannot open"));
}

/* ------------------------------------------------------------------ plan */

typedef struct {
    size_t steps, figures, by_label[16];
    size_t deduplicated;
} plan_count;

static const char *const labels[] = {"speeds", "period", "floquet", "branch", "profile",
                                     "asymptotics", "friction", "simulate", "check", "stability",
                                     "figure",
                                     NULL};

static plan_count count_plan(const char *text, int figures)
{
    bkf_scene *s = parse_ok(text);
    bkf_scene_plan plan;
    bkf_error e = {0};
    bkf_scene_plan_options o = {.outdir = "out", .formats = 1, .figures = figures};
    CHECK_STATUS(bkf_scene_make_plan(s, &o, &plan, &e), BKF_OK);
    plan_count c = {.steps = plan.nsteps, .deduplicated = plan.deduplicated};
    for (size_t i = 0; i < plan.nsteps; i++) {
        const char *l = plan.steps[i].product;
        int found = 0;
        for (int k = 0; labels[k]; k++)
            if (strcmp(l, labels[k]) == 0) c.by_label[k]++, found = 1;
        CHECK_MSG(found, "unknown step %s", l);
        c.figures += plan.steps[i].kind == BKF_SCENE_STEP_FIGURE;
        /* every step serves some product, and every product has a step */
        CHECK(plan.steps[i].nusers >= 1);
    }
    for (size_t i = 0; i < s->nproducts; i++)
        if (figures || s->products[i].kind != BKF_SCENE_FIGURE) CHECK(plan.products[i].nsteps >= 1);
    bkf_scene_plan_free(&plan);
    bkf_scene_free(s);
    return c;
}

static size_t count_of(const plan_count *c, const char *label)
{
    for (int k = 0; labels[k]; k++)
        if (strcmp(labels[k], label) == 0) return c->by_label[k];
    return 0;
}

TEST(plan_runs_only_what_the_products_need)
{
    /* a speeds table: one speeds solve, no simulation, no Floquet */
    plan_count c = count_plan(MODEL "[speeds]\n", 1);
    CHECK(c.steps == 1 && count_of(&c, "speeds") == 1 && count_of(&c, "simulate") == 0);

    /* a spacetime plot seeded with front n = 3: one simulation, which finds
     * the root of n = 3 alone; no speeds table */
    c = count_plan(MODEL "[spacetime s]\ninit = front:n=3\n[figure s]\ndata = s\n", 1);
    CHECK(c.steps == 2 && count_of(&c, "simulate") == 1 && count_of(&c, "speeds") == 0);
    CHECK(c.figures == 1);

    /* three dispersion relations and their figure */
    c = count_plan(MODEL "[dispersion d]\nnu = -0.9,-0.92,-0.94\n[figure d]\ndata = d\n", 1);
    CHECK(count_of(&c, "floquet") == 3 && c.figures == 1 && c.steps == 4);

    /* the same computation asked for twice runs once */
    c = count_plan(MODEL "[speeds a]\n[speeds b]\n[figure fa]\ndata = a\n[figure fb]\ndata = b\n", 1);
    CHECK(count_of(&c, "speeds") == 1 && c.deduplicated == 1 && c.figures == 2);
    /* ... but not when a setting differs */
    c = count_plan(MODEL "[speeds a]\n[speeds b]\ntol = 1e-6\n", 1);
    CHECK(count_of(&c, "speeds") == 2 && c.deduplicated == 0);

    /* --no-figures: the data alone */
    c = count_plan(MODEL "[friction f]\n[figure f]\ndata = f\n", 0);
    CHECK(c.steps == 1 && count_of(&c, "friction") == 1 && c.figures == 0);

    /* branches: one continuation per n; a range of n */
    c = count_plan(MODEL "[branch b]\nparam = S\nto = 30\nn = 4:6:3\n", 1);
    CHECK(count_of(&c, "branch") == 3);

    /* stability: one spectrum per n, the same product as the command (the
     * mode's keys passed on); a figure's default script follows the mode */
    c = count_plan(MODEL "[stability sp]\nn = 2,4\n[figure sp]\ndata = sp\n", 1);
    CHECK(count_of(&c, "stability") == 2 && c.figures == 1);
    c = count_plan(MODEL "[stability d]\ndiagram = yes\nn = 3\nto = -0.9\nS-to = 30\n", 1);
    CHECK(count_of(&c, "stability") == 1);

    /* the paper scene: every figure, one computation per curve */
    bkf_scene *s = NULL;
    bkf_error e = {0};
    CHECK_STATUS(bkf_scene_parse_file(BKF_SOURCE_DIR "/fronts/paper.scene", &s, &e), BKF_OK);
    bkf_scene_plan plan;
    bkf_scene_plan_options o = {.outdir = "out", .formats = 1, .figures = 1};
    CHECK_STATUS(bkf_scene_make_plan(s, &o, &plan, &e), BKF_OK);
    size_t sims = 0, figs = 0;
    for (size_t i = 0; i < plan.nsteps; i++) {
        sims += strcmp(plan.steps[i].product, "simulate") == 0;
        figs += plan.steps[i].kind == BKF_SCENE_STEP_FIGURE;
    }
    CHECK(sims == 3 && figs == 14);
    bkf_test_note("paper scene: %zu computations (%zu simulations, %zu figures)", plan.nsteps,
                  sims, figs);
    bkf_scene_plan_free(&plan);
    bkf_scene_free(s);
}

TEST(plan_refuses_an_output_folder_figures_cannot_list)
{
    bkf_scene *s = parse_ok(MODEL "[speeds]\n");
    bkf_scene_plan plan;
    bkf_error e = {0};
    bkf_scene_plan_options o = {.outdir = "my out", .figures = 1};
    CHECK_STATUS(bkf_scene_make_plan(s, &o, &plan, &e), BKF_EINPUT);
    CHECK(strstr(e.message, "space"));
    bkf_scene_free(s);
}

/* ------------------------------------------------------------------- run */

static void remove_tree(const char *dir)
{
    DIR *d = opendir(dir);
    if (d) {
        struct dirent *ent;
        while ((ent = readdir(d))) {
            if (ent->d_name[0] == '.') continue;
            char path[1024];
            snprintf(path, sizeof path, "%s/%s", dir, ent->d_name);
            struct stat st;
            if (stat(path, &st) == 0 && S_ISDIR(st.st_mode))
                remove_tree(path);
            else
                unlink(path);
        }
        closedir(d);
    }
    rmdir(dir);
}


/* bkf_scene_run, as a library caller sees it: the reports come one at a
 * time, one per step, each figure's after every step of its data; a flag
 * raised before the run leaves every step unrun and unreported. */
typedef struct {
    size_t order[32];
    double start[32]; /* by step: when it started, the report's time less its seconds */
    size_t n;
    int inside;     /* a report under way: two at once would see it set */
    int overlapped;
} report_log;

static void log_report(const bkf_scene_step_report *r, void *data)
{
    report_log *log = data;
    if (log->inside++) log->overlapped = 1;
    if (log->n < 32) log->order[log->n] = r->step;
    struct timespec now;
    clock_gettime(CLOCK_MONOTONIC, &now);
    if (r->step < 32) log->start[r->step] = (double)now.tv_sec + 1e-9 * (double)now.tv_nsec - r->seconds;
    log->n++;
    struct timespec nap = {0, 2000000}; /* long enough for another to come in */
    nanosleep(&nap, NULL);
    log->inside--;
}

TEST(scene_run_reports_each_step_after_its_data)
{
    char dir[] = "/tmp/bkfront-jobs-XXXXXX";
    CHECK(mkdtemp(dir));
    bkf_scene *sc = parse_ok("[model]\ngamma = 1.3\nc = 0.7\nnu = -0.5\nS = 12\n"
                             "[friction fr]\nfrom = -1\nto = 3\n[figure fr]\ndata = fr\n"
                             "[period period]\nnu = 0,-0.5,-0.9\nmu = 0.1:100:9\n"
                             "[figure period]\ndata = period\n"
                             "[profile profiles]\nn = 1,2\n[figure both]\ndata = profiles, fr\n");
    bkf_scene_plan plan;
    bkf_error e = {0};
    bkf_scene_plan_options po = {.outdir = dir, .formats = 1, .figures = 1};
    CHECK_STATUS(bkf_scene_make_plan(sc, &po, &plan, &e), BKF_OK);
    CHECK(plan.nsteps == 8); /* fr, 3 periods, profiles; 3 figures */
    int status[32];
    report_log log = {0};
    bkf_scene_run_options ro = {.plots_dir = BKF_SOURCE_DIR "/plots", .jobs = 4,
                                .step_done = log_report, .data = &log};
    CHECK_STATUS(bkf_scene_run(sc, &plan, &ro, status, &e), BKF_OK);
    CHECK_MSG(log.n == plan.nsteps && !log.overlapped, "%zu reports, overlapped %d", log.n,
              log.overlapped);
    size_t when[32];
    for (size_t i = 0; i < plan.nsteps; i++) when[i] = SIZE_MAX;
    for (size_t k = 0; k < log.n && k < 32; k++) {
        CHECK(log.order[k] < plan.nsteps && when[log.order[k]] == SIZE_MAX);
        when[log.order[k]] = k;
    }
    for (size_t i = 0; i < plan.nsteps; i++) {
        CHECK_MSG(status[i] == BKF_OK, "step %zu: status %d", i + 1, status[i]);
        const bkf_scene_step *st = &plan.steps[i];
        if (st->kind != BKF_SCENE_STEP_FIGURE) continue;
        for (size_t d = 0; d < st->ndata; d++) {
            const bkf_scene_product_plan *pp = &plan.products[st->data_products[d]];
            for (size_t k = 0; k < pp->nsteps; k++)
                CHECK_MSG(when[pp->steps[k]] < when[i], "figure %zu reported before step %zu",
                          i + 1, pp->steps[k] + 1);
        }
    }

    /* canceled before it began: nothing runs, nothing is told */
    static volatile sig_atomic_t raised = 1;
    ro.hooks.cancel = &raised;
    log = (report_log){0};
    CHECK_STATUS(bkf_scene_run(sc, &plan, &ro, status, &e), BKF_ECANCELED);
    CHECK(log.n == 0);
    for (size_t i = 0; i < plan.nsteps; i++) CHECK(status[i] == BKF_ECANCELED);

    bkf_scene_plan_free(&plan);
    bkf_scene_free(sc);
    remove_tree(dir);
}

/* The cost hints against the paper scene's measured serial run
 * (docs/benchmarks.md, `make run` with one and two jobs: the diagram 252
 * s, the two branches 118 s and 80 s, every other step under 10 s): the
 * diagram is the step expected longest, the branches next, each other
 * product step under both branches; a figure costs nothing. */
TEST(scene_step_costs_rank_the_paper_scene_as_measured)
{
    bkf_scene *s = NULL;
    bkf_error e = {0};
    CHECK_STATUS(bkf_scene_parse_file(BKF_SOURCE_DIR "/fronts/paper.scene", &s, &e), BKF_OK);
    bkf_scene_plan plan;
    bkf_scene_plan_options po = {.outdir = "out", .formats = 1, .figures = 1};
    CHECK_STATUS(bkf_scene_make_plan(s, &po, &plan, &e), BKF_OK);
    double diagram = -1, branch_min = INFINITY, other_max = 0;
    for (size_t i = 0; i < plan.nsteps; i++) {
        const bkf_scene_step *st = &plan.steps[i];
        const bkf_scene_product *p = &s->products[st->users[0]];
        double c = bkf_scene_step_cost(st);
        CHECK_MSG(isfinite(c) && c >= 0, "step %zu: cost %g", i + 1, c);
        if (st->kind == BKF_SCENE_STEP_FIGURE)
            CHECK_MSG(c == 0, "figure %s: cost %g", p->name, c);
        else if (strcmp(p->name, "diagram") == 0)
            diagram = c;
        else if (p->kind == BKF_SCENE_BRANCH)
            branch_min = fmin(branch_min, c);
        else
            other_max = fmax(other_max, c);
    }
    CHECK_MSG(diagram > branch_min && branch_min > other_max,
              "diagram %g, branches from %g, the rest up to %g", diagram, branch_min, other_max);
    bkf_scene_plan_free(&plan);
    bkf_scene_free(s);
}

/* Several jobs start the longest expected steps first (the products'
 * cost hints, catalog.h), whatever their place in the plan: two
 * simulations planned after three quick friction tables take both jobs
 * at once, and the frictions start only once one has ended (in the plan's
 * order two frictions would start first); one job keeps the plan's order. */
TEST(scene_run_starts_the_longest_steps_first)
{
    char dir[] = "/tmp/bkfront-cost-XXXXXX";
    CHECK(mkdtemp(dir));
    bkf_scene *sc = parse_ok(MODEL "[friction f1]\n[friction f2]\nto = 3\n[friction f3]\nto = 2\n"
                                   "[spacetime a]\ntmax = 20\nN = 128\nframes = 10\n"
                                   "[spacetime b]\ntmax = 20\nN = 128\nframes = 10\nnu = -0.9\n");
    bkf_scene_plan plan;
    bkf_error e = {0};
    bkf_scene_plan_options po = {.outdir = dir, .formats = 1, .figures = 0};
    CHECK_STATUS(bkf_scene_make_plan(sc, &po, &plan, &e), BKF_OK);
    CHECK(plan.nsteps == 5);
    int status[8];
    for (unsigned jobs = 1; jobs <= 2; jobs++) {
        report_log log = {0};
        bkf_scene_run_options ro = {.jobs = jobs, .step_done = log_report, .data = &log};
        CHECK_STATUS(bkf_scene_run(sc, &plan, &ro, status, &e), BKF_OK);
        CHECK(log.n == 5);
        if (jobs == 1)
            for (size_t k = 0; k < 5; k++) CHECK_MSG(log.order[k] == k, "report %zu: step %zu", k,
                                                     log.order[k] + 1);
        else
            for (size_t f = 0; f < 3; f++)
                CHECK_MSG(log.start[f] > log.start[3] && log.start[f] > log.start[4],
                          "friction %zu started %.3f s after simulation 4, %.3f s after 5",
                          f + 1, log.start[f] - log.start[3], log.start[f] - log.start[4]);
    }
    bkf_scene_plan_free(&plan);
    bkf_scene_free(sc);
    remove_tree(dir);
}

#ifdef BKF_CLI_PATH

typedef bkf_cli_result run_result;

/* The result in one block, so that free(r) releases it all. */
static run_result *run_cli(char *const *args)
{
    bkf_cli_result c = bkf_cli_run((const char *const *)args, NULL);
    size_t n_out = strlen(c.out) + 1, n_err = strlen(c.err) + 1;
    run_result *r = malloc(sizeof *r + n_out + n_err);
    CHECK(r);
    *r = c;
    r->out = memcpy((char *)(r + 1), c.out, n_out);
    r->err = memcpy(r->out + n_out, c.err, n_err);
    bkf_cli_result_free(&c);
    return r;
}

static char *temp_dir(void)
{
    char *d = strdup("/tmp/bkfront-scene-XXXXXX");
    CHECK(d && mkdtemp(d));
    return d;
}

static char *write_scene(const char *dir, const char *text)
{
    char *path = malloc(strlen(dir) + 16);
    CHECK(path);
    sprintf(path, "%s/t.scene", dir);
    FILE *f = fopen(path, "w");
    CHECK(f);
    fputs(text, f);
    fclose(f);
    return path;
}

static long file_size(const char *dir, const char *name)
{
    char path[1200];
    snprintf(path, sizeof path, "%.600s/%.500s", dir, name);
    struct stat st;
    return stat(path, &st) == 0 ? (long)st.st_size : -1;
}

static int starts_with_bytes(const char *dir, const char *name, const char *magic, size_t n)
{
    char path[1200], buf[16] = {0};
    snprintf(path, sizeof path, "%.600s/%.500s", dir, name);
    FILE *f = fopen(path, "rb");
    if (!f) return 0;
    size_t k = fread(buf, 1, n, f);
    fclose(f);
    return k == n && memcmp(buf, magic, n) == 0;
}

/* The friction table against the closed forms, read back from the file. */
static void check_friction_table(const char *dir)
{
    char path[512];
    snprintf(path, sizeof path, "%s/out/fric.tsv", dir);
    FILE *f = fopen(path, "r");
    CHECK(f);
    char line[512];
    size_t rows = 0, checked = 0;
    while (fgets(line, sizeof line, f)) {
        if (line[0] == '#' || line[0] == 'v') continue;
        double v, psi, cs, cl;
        rows++;
        CHECK(sscanf(line, "%lf %lf %lf %lf", &v, &psi, &cs, &cl) == 4);
        CHECK(isnan(cl) == (v == 0));
        if (isnan(cl)) continue;
        CHECK_CLOSE(psi, v - 1, 0, 1e-15);
        CHECK_CLOSE(cs, 1.5 * (psi * psi * psi / 3 - psi), 1e-14, 1e-15);
        CHECK_CLOSE(cl, (v > 0 ? 1.0 : -1.0) / (1 + fabs(v)), 1e-14, 0);
        checked++;
    }
    fclose(f);
    CHECK(rows == 11 && checked == 10);  /* v = 0 is the gap of the jump (nan) */
}

TEST(run_scene_writes_data_and_figures_in_every_format)
{
    char *dir = temp_dir();
    char *path = write_scene(dir, MODEL
                             "[friction fric]\nfrom = -2\nto = 3\npoints = 11\n"
                             "[figure fric]\ndata = fric\nformats = png,pdf,svg\n"
                             "[speeds table]\nn = 3\n[figure tablefig]\ndata = table\n");
    char outdir[512];
    snprintf(outdir, sizeof outdir, "%s/out", dir);
    run_result *r = run_cli((char *[]){"run", "--out", outdir, "--plots",
                                       BKF_SOURCE_DIR "/plots", path, NULL});
    CHECK_MSG(r->code == 0, "exit %d: %s\n%s", r->code, r->err, r->out);
    CHECK(strstr(r->out, "4 computations"));
    CHECK(strstr(r->out, "== [speeds table]"));   /* the table is shown */
    char sub[600];
    snprintf(sub, sizeof sub, "%s/out", dir);
    CHECK(starts_with_bytes(sub, "fric.png", "\x89PNG", 4));
    CHECK(starts_with_bytes(sub, "fric.pdf", "%PDF", 4));
    CHECK(file_size(sub, "fric.svg") > 1000);
    CHECK(starts_with_bytes(sub, "tablefig.png", "\x89PNG", 4));
    CHECK(file_size(sub, "fric.png") > 5000 && file_size(sub, "tablefig.png") > 5000);
    CHECK(file_size(sub, "fric.png.part") < 0);    /* nothing half-written left */
    check_friction_table(dir);
    free(r);
    remove_tree(dir);
    free(path);
    free(dir);
}

/* A stability scene: the ring spectra of n = 2 and 4 side by side in the
 * spectrum figure, their verdicts those of the paper's table (n = 2
 * unstable, 4 stable: docs/cli/stability.md, from Hill's method in
 * tests/products/test_stability.c), each file the command's table. */
TEST(run_stability_scene_writes_spectra_and_figure)
{
    char *dir = temp_dir();
    char *path = write_scene(dir, MODEL "[stability sp]\nn = 2,4\n[figure sp]\ndata = sp\n");
    char outdir[512];
    snprintf(outdir, sizeof outdir, "%s/out", dir);
    run_result *r = run_cli((char *[]){"run", "--out", outdir, "--plots",
                                       BKF_SOURCE_DIR "/plots", path, NULL});
    CHECK_MSG(r->code == 0, "exit %d: %s\n%s", r->code, r->err, r->out);
    CHECK(strstr(r->out, "3 computations"));
    CHECK(starts_with_bytes(outdir, "sp.png", "\x89PNG", 4));
    CHECK(file_size(outdir, "sp.png") > 5000);
    char file[700];
    snprintf(file, sizeof file, "%s/sp_1.tsv", outdir);
    char *t2 = bkf_cli_read_file(file);
    snprintf(file, sizeof file, "%s/sp_2.tsv", outdir);
    char *t4 = bkf_cli_read_file(file);
    CHECK(t2 && strstr(t2, "# root: n 2,") && strstr(t2, "# stable: no;"));
    CHECK(t4 && strstr(t4, "# root: n 4,") && strstr(t4, "# stable: yes;"));
    free(t2);
    free(t4);
    free(r);
    remove_tree(dir);
    free(path);
    free(dir);
}

/* The chain's keys reach the products: `model = chain` in [model] and the
 * blocks N of [accuracy] (or the product's own N) make speeds tables of
 * those chains, read back and put against bkf_chainwave_find on the same
 * chain; a product's own model = continuum keeps the continuum (no blocks);
 * one figure shows the three tables (data = A,B,C) with the chain's
 * script.  Without a model key the plan passes none (continuum scenes plan
 * as before). */
TEST(run_chain_scene_keys_reach_the_products)
{
    const char *text = "[model]\ngamma = 2\nc = 0.3\nnu = -0.96\nS = 8\nmodel = chain\n"
                       "[accuracy]\nN = 16\n"
                       "[speeds cont]\nmodel = continuum\nnmax = 2\n"
                       "[speeds ch16]\nnmax = 2\n"
                       "[speeds ch8]\nN = 8\nnmax = 2\nstability = yes\n"
                       "[figure f]\ndata = cont, ch16,ch8\n";
    bkf_scene *sc = parse_ok(text);
    bkf_scene_plan plan;
    bkf_error e = {0};
    bkf_scene_plan_options po = {.outdir = "out", .formats = 1, .figures = 1};
    CHECK_STATUS(bkf_scene_make_plan(sc, &po, &plan, &e), BKF_OK);
    const bkf_scene_step *fig = &plan.steps[plan.nsteps - 1];
    CHECK(fig->kind == BKF_SCENE_STEP_FIGURE && fig->ndata == 3);
    for (size_t k = 0; k < fig->ndata && k < 3; k++)
        CHECK(fig->data_products[k] == k); /* in the order of data = ... */
    bkf_scene_plan_free(&plan);
    bkf_scene_free(sc);
    sc = parse_ok(MODEL "[speeds]\n");
    CHECK_STATUS(bkf_scene_make_plan(sc, &po, &plan, &e), BKF_OK);
    char *cmd = bkf_scene_step_command(&plan.steps[0]);
    CHECK_MSG(cmd && !strstr(cmd, "--model") && !strstr(cmd, "--N"), "%s", cmd);
    free(cmd);
    bkf_scene_plan_free(&plan);
    bkf_scene_free(sc);

    char *dir = temp_dir();
    char *path = write_scene(dir, text);
    char outdir[512];
    snprintf(outdir, sizeof outdir, "%s/out", dir);
    run_result *r = run_cli((char *[]){"run", "--out", outdir, "--plots",
                                       BKF_SOURCE_DIR "/plots", path, NULL});
    CHECK_MSG(r->code == 0, "exit %d: %s\n%s", r->code, r->err, r->out);
    CHECK(starts_with_bytes(outdir, "f.png", "\x89PNG", 4));
    CHECK(file_size(outdir, "f.png") > 5000);
    static const char *const names[] = {"cont", "ch16", "ch8"};
    static const size_t blocks[] = {0, 16, 8};
    for (int k = 0; k < 3; k++) {
        char file[700];
        snprintf(file, sizeof file, "%s/%s.tsv", outdir, names[k]);
        char *t = bkf_cli_read_file(file);
        CHECK_MSG(t, "%s", file);
        if (!t) continue;
        char want[64];
        snprintf(want, sizeof want, "N %zu blocks", blocks[k]);
        CHECK_MSG(blocks[k] ? strstr(t, want) != NULL : strstr(t, "blocks") == NULL, "%s: %s",
                  names[k], t);
        char stable[32];
        CHECK((k == 2) == bkf_tsv_cell(t, 0, "stable", NULL, stable, sizeof stable));
        if (blocks[k]) {
            bkf_model_params p = bkf_model_params_paper();
            p.S = 8.0;
            p.N = blocks[k];
            p.kind = BKF_MODEL_CHAIN;
            bkf_chainwave_options o = bkf_chainwave_options_default();
            o.stability = 0;
            bkf_chainwave_table w;
            CHECK_MSG(bkf_chainwave_find(&p, 1, 2, &o, &w, &e) == BKF_OK, "%s", e.message);
            double v = NAN;
            CHECK(w.count == 2);
            for (size_t i = 0; i < w.count; i++) {
                CHECK(bkf_tsv_cell(t, (int)i, "v", &v, NULL, 0));
                CHECK_CLOSE(v, w.waves[i].v, 1e-8, 0.0);
            }
            bkf_test_note("%s: n = 2 v %.12g (library %.12g)", names[k], v,
                          w.count ? w.waves[w.count - 1].v : 0);
            bkf_chainwave_table_free(&w);
        }
        free(t);
    }
    free(r);
    remove_tree(dir);
    free(path);
    free(dir);
}

TEST(run_plan_computes_nothing)
{
    char *dir = temp_dir();
    char *path = write_scene(dir, MODEL "[spacetime s]\ninit = front:n=3\n[figure s]\ndata = s\n");
    char outdir[512];
    snprintf(outdir, sizeof outdir, "%s/out", dir);
    run_result *r = run_cli((char *[]){"run", "--plan", "--out", outdir, path, NULL});
    CHECK_MSG(r->code == 0, "exit %d: %s", r->code, r->err);
    CHECK(strstr(r->out, "2 computations for 2 products"));
    CHECK(strstr(r->out, "simulate --gamma 2 --c 0.3 --nu -0.96 --S 20"));
    CHECK(strstr(r->out, "--init front:n=3"));
    CHECK(!strstr(r->out, "\tspeeds\t"));
    struct stat st;
    CHECK(stat(outdir, &st) != 0);   /* not even the folder */
    free(r);
    remove_tree(dir);
    free(path);
    free(dir);
}

/* The stepper a scene names reaches the command it plans, for both kinds
 * that take one; a name outside the list is refused with the list. */
TEST(run_plan_passes_the_stepper)
{
    char *dir = temp_dir();
    char *path = write_scene(dir, MODEL "[spacetime s]\ninit = front:n=3\nstepper = lawson8\n"
                                        "[check c]\nn = 3\nstepper = lawson8\n");
    char outdir[512];
    snprintf(outdir, sizeof outdir, "%s/out", dir);
    run_result *r = run_cli((char *[]){"run", "--plan", "--out", outdir, path, NULL});
    CHECK_MSG(r->code == 0, "exit %d: %s", r->code, r->err);
    const char *sim = strstr(r->out, "simulate --gamma"), *chk = strstr(r->out, "check --gamma");
    CHECK_MSG(sim && chk, "plan: %s", r->out);
    if (sim && chk) {
        const char *sim_end = strchr(sim, '\n'), *chk_end = strchr(chk, '\n');
        const char *s1 = strstr(sim, "--stepper lawson8"), *s2 = strstr(chk, "--stepper lawson8");
        CHECK_MSG(s1 && (!sim_end || s1 < sim_end), "plan: %s", r->out);
        CHECK_MSG(s2 && (!chk_end || s2 < chk_end), "plan: %s", r->out);
    }
    free(r);
    free(path);
    parse_bad(MODEL "[spacetime s]\nstepper = lawson9\n", 7, "etdrk4, lawson8");
    remove_tree(dir);
    free(dir);
}

TEST(run_refuses_a_bad_scene_with_its_line)
{
    char *dir = temp_dir();
    char *path = write_scene(dir, MODEL "[speeds]\nnmax = -3\n");
    char outdir[512];
    snprintf(outdir, sizeof outdir, "%s/out", dir);
    run_result *r = run_cli((char *[]){"run", "--out", outdir, path, NULL});
    CHECK(r->code == 2);
    CHECK(r->out[0] == '\0');
    char want[600];
    snprintf(want, sizeof want, "bkfront run: %s:7: nmax", path);
    CHECK_MSG(strncmp(r->err, want, strlen(want)) == 0, "stderr: %s", r->err);
    CHECK(strchr(r->err, '\n') == r->err + strlen(r->err) - 1);
    struct stat st;
    CHECK(stat(outdir, &st) != 0);
    free(r);

    r = run_cli((char *[]){"run", "--frobnicate", path, NULL});
    CHECK(r->code == 2 && strstr(r->err, "--frobnicate"));
    free(r);
    r = run_cli((char *[]){"run", NULL});
    CHECK(r->code == 2 && strstr(r->err, "SCENE"));
    free(r);
    r = run_cli((char *[]){"run", "--formats", "gif", path, NULL});
    CHECK(r->code == 2 && strstr(r->err, "--formats"));
    free(r);
    remove_tree(dir);
    free(path);
    free(dir);
}

TEST(run_keeps_going_past_a_failed_product)
{
    char *dir = temp_dir();
    /* n = 40 has no front at these parameters (n_max is 12) */
    char *path = write_scene(dir, MODEL "[profile p]\nn = 40\n[figure p]\ndata = p\n"
                                        "[friction f]\n[figure f]\ndata = f\n");
    char outdir[512];
    snprintf(outdir, sizeof outdir, "%s/out", dir);
    /* one after the other, and beside each other: a failure stops no other
     * job, and the figure of its data waits for it and is skipped */
    static char *const jobs[] = {"1", "2"};
    for (int j = 0; j < 2; j++) {
        run_result *r = run_cli((char *[]){"run", "--jobs", jobs[j], "--out", outdir, "--plots",
                                           BKF_SOURCE_DIR "/plots", path, NULL});
        CHECK_MSG(r->code == 2, "--jobs %s: exit %d: %s", jobs[j], r->code, r->err);
        CHECK(strstr(r->out, "skipped: its data failed"));
        CHECK(strstr(r->err, "[profile p]") && strstr(r->err, "n = 40"));
        CHECK(file_size(outdir, "f.png") > 0);
        CHECK(file_size(outdir, "p.tsv") < 0 && file_size(outdir, "p.png") < 0);
        free(r);
        remove_tree(outdir);
    }
    remove_tree(dir);
    free(path);
    free(dir);
}

/* A warning a step raises reaches the terminal under the step's line, not
 * only its file: fronts seeded on a grid too coarse for them (gamma 20,
 * c 0.05, nu 0.9, S 100, n 5 at N 1024, simulate.c's case). */
TEST(run_shows_a_step_s_warnings)
{
    char *dir = temp_dir();
    char *path = write_scene(dir, "[model]\ngamma = 20\nc = 0.05\nnu = 0.9\nS = 100\n"
                                  "[accuracy]\nN = 1024\n"
                                  "[spacetime thin]\ntmax = 0.5\ninit = front:n=5\n"
                                  "[friction f]\n[period p]\nmu = 1:10:5\n");
    char outdir[512];
    snprintf(outdir, sizeof outdir, "%s/out", dir);
    /* two jobs: the warning stays with its step, whichever ends first */
    run_result *r = run_cli((char *[]){"run", "--jobs", "2", "--no-figures", "--out", outdir,
                                       path, NULL});
    CHECK_MSG(r->code == 0, "exit %d: %s", r->code, r->err);
    const char *step = strstr(r->out, "thin.dat\n");
    CHECK_MSG(step && strncmp(step + 9, "        warning: N = 1024 does not resolve", 42) == 0,
              "no warning under the step:\n%s", r->out);
    CHECK_MSG(!strstr(step + 9, "warning: warning"), "%s", r->out);
    free(r);
    remove_tree(dir);
    free(path);
    free(dir);
}

/* Several independent steps and their figures: what a parallel run must
 * keep apart (two threads in gnuplot, a simulation beside the root
 * finders, two rows of one product). */
#define JOBS_SCENE                                                                   \
    "[model]\ngamma = 1.3\nc = 0.7\nnu = -0.5\nS = 12\n[accuracy]\ntol = 1e-8\nN = 128\n" \
    "[friction fr]\nfrom = -1\nto = 3\n[figure fr]\ndata = fr\n"                      \
    "[speeds table]\n[figure speeds]\ndata = table\n"                                 \
    "[period period]\nnu = 0,-0.5\nmu = 0.1:100:9\n[figure period]\ndata = period\n"  \
    "[profile profiles]\nn = 1,2,3\n[figure profiles]\ndata = profiles\n"             \
    "[spacetime st]\ntmax = 10\ninit = oscillation:j=2,amp=0.3\nseed = 3\n"           \
    "[figure st]\ndata = st\n"

static char *read_whole(const char *dir, const char *name, size_t *size)
{
    char path[1200];
    snprintf(path, sizeof path, "%.600s/%.500s", dir, name);
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    char *buf = NULL;
    size_t n = 0, cap = 0;
    for (;;) {
        if (n == cap) {
            cap = cap ? 2 * cap : 65536;
            char *more = realloc(buf, cap);
            CHECK(more);
            buf = more;
        }
        size_t k = fread(buf + n, 1, cap - n, f);
        n += k;
        if (k == 0) break;
    }
    fclose(f);
    *size = n;
    return buf;
}

/* --jobs 3 writes the files --jobs 1 writes, byte for byte (the images
 * too: gnuplot draws the same data the same way), one progress line per
 * step, and each figure's line after the lines of all its data. */
TEST(run_jobs_write_the_serial_files)
{
    char *dir = temp_dir();
    char *path = write_scene(dir, JOBS_SCENE);
    char outdir[512], serial[512];
    snprintf(outdir, sizeof outdir, "%s/out", dir);
    snprintf(serial, sizeof serial, "%s/serial", dir);
    run_result *r = run_cli((char *[]){"run", "--jobs", "1", "--out", outdir, "--plots",
                                       BKF_SOURCE_DIR "/plots", path, NULL});
    CHECK_MSG(r->code == 0, "exit %d: %s\n%s", r->code, r->err, r->out);
    free(r);
    CHECK(rename(outdir, serial) == 0);
    r = run_cli((char *[]){"run", "--jobs", "3", "--out", outdir, "--plots",
                           BKF_SOURCE_DIR "/plots", path, NULL});
    CHECK_MSG(r->code == 0, "exit %d: %s\n%s", r->code, r->err, r->out);
    bkf_test_note("%s", r->out);

    DIR *d = opendir(serial);
    CHECK(d);
    struct dirent *ent;
    size_t files = 0;
    while ((ent = readdir(d))) {
        if (ent->d_name[0] == '.') continue;
        size_t na = 0, nb = 0;
        char *a = read_whole(serial, ent->d_name, &na), *b = read_whole(outdir, ent->d_name, &nb);
        CHECK_MSG(a && b, "%s: missing from one run", ent->d_name);
        CHECK_MSG(na == nb && memcmp(a, b, na) == 0, "%s differs (%zu and %zu bytes)",
                  ent->d_name, na, nb);
        free(a);
        free(b);
        files++;
    }
    closedir(d);
    /* fr, table, period_1, period_2, profiles, st.dat, st_diag; 5 images */
    CHECK_MSG(files == 12, "%zu files", files);
    d = opendir(outdir);
    CHECK(d);
    size_t again = 0;
    while ((ent = readdir(d))) again += ent->d_name[0] != '.';
    closedir(d);
    CHECK_MSG(again == files, "%zu files from --jobs 3, %zu from --jobs 1", again, files);

    /* the lines: [K/11] once each; a figure's after its data's */
    const char *at[12] = {0};
    for (int k = 1; k <= 11; k++) {
        char tag[32];
        snprintf(tag, sizeof tag, "[%d/11] ", k);
        at[k] = strstr(r->out, tag);
        CHECK_MSG(at[k] && !strstr(at[k] + 1, tag), "step %d: not one line\n%s", k, r->out);
    }
    /* steps 1 fr, 2 table, 3-4 period, 5 profiles, 6 st; figures 7-11 in that order */
    static const int first[] = {1, 2, 3, 5, 6}, last[] = {1, 2, 4, 5, 6};
    for (int f = 0; f < 5; f++)
        for (int k = first[f]; k <= last[f]; k++)
            CHECK_MSG(at[k] && at[7 + f] && at[k] < at[7 + f], "figure %d before step %d\n%s",
                      7 + f, k, r->out);
    free(r);
    remove_tree(serial);
    remove_tree(outdir);
    remove_tree(dir);
    free(path);
    free(dir);
}

TEST(run_jobs_checks_its_value)
{
    char *dir = temp_dir();
    char *path = write_scene(dir, MODEL "[friction f]\n");
    static const char *const bad[] = {"0", "-1", "1025", "two", ""};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        run_result *r = run_cli((char *[]){"run", "--jobs", (char *)bad[i], "--no-figures",
                                           "--out", dir, path, NULL});
        CHECK_MSG(r->code == 2 && strstr(r->err, "--jobs") && bkf_count_lines(r->err) == 1,
                  "--jobs '%s': exit %d: %s", bad[i], r->code, r->err);
        CHECK(file_size(dir, "f.tsv") < 0);
        free(r);
    }
    remove_tree(dir);
    free(path);
    free(dir);
}

/* x over one period is one wavelength: n T v sqrt(1 - c^2/v^2) = S, the
 * speed condition itself; and f(0) = nu rising (the section). */
TEST(profile_spans_one_wavelength)
{
    run_result *r = run_cli((char *[]){"profile", "--gamma", "2", "--c", "0.3", "--nu", "-0.96",
                                       "--S", "20", "--n", "4,10", "--points", "100", NULL});
    CHECK_MSG(r->code == 0, "exit %d: %s", r->code, r->err);
    char *line = r->out;
    size_t rows = 0;
    double last_x[2] = {0, 0};
    while (line && *line) {
        char *next = strchr(line, '\n');
        if (next) *next++ = '\0';
        double n, root, v, mu, T, z, x, f, fp;
        if (line[0] != '#' &&
            sscanf(line, "%lf %lf %lf %lf %lf %lf %lf %lf %lf", &n, &root, &v, &mu, &T, &z, &x,
                   &f, &fp) == 9) {
            int k = n == 10;
            if (z == 0) {
                CHECK_CLOSE(f, -0.96, 0, 1e-9);
                CHECK(fp > 0);
            }
            last_x[k] = x;
            rows++;
        }
        line = next;
    }
    /* --points 100: 100 rows per profile (issue 14: was 101, z = T
     * repeating z = 0), the last at z = 99 T / 100. */
    CHECK(rows == 200);
    CHECK_CLOSE(last_x[0] * 100 / 99, 20.0 / 4, 1e-9, 0);
    CHECK_CLOSE(last_x[1] * 100 / 99, 20.0 / 10, 1e-9, 0);
    free(r);
    r = run_cli((char *[]){"profile", "--nu", "0", "--mu", "1", "--n", "3", NULL});
    CHECK(r->code == 2 && strstr(r->err, "--mu"));
    free(r);
    r = run_cli((char *[]){"profile", "--nu", "1.5", "--mu", "1", NULL});
    CHECK(r->code == 2 && strstr(r->err, "--nu"));
    free(r);
}

#endif

/* --------------------------------------------------------------- gnuplot */

TEST(plot_failure_reports_gnuplot_and_leaves_no_image)
{
    char dir[] = "/tmp/bkfront-plot-XXXXXX";
    CHECK(mkdtemp(dir));
    char script[256], out[256];
    snprintf(script, sizeof script, "%s/bad.gp", dir);
    snprintf(out, sizeof out, "%s/bad.png", dir);
    FILE *f = fopen(script, "w");
    CHECK(f);
    fputs("set terminal pngcairo\nset output out\nplot sin(x) with linez\n", f);
    fclose(f);
    bkf_error e = {0};
    bkf_plot_job *job = bkf_plot_job_alloc(script, &e);
    CHECK(job);
    CHECK_STATUS(bkf_plot_add_output(job, BKF_PLOT_PNG, out, &e), BKF_OK);
    bkf_plot_report rep;
    CHECK_STATUS(bkf_plot_run(job, NULL, &rep, &e), BKF_ENUMERIC);
    CHECK(rep.exit_code != 0);
    CHECK_MSG(strstr(e.message, "line 3"), "message: %s", e.message);
    struct stat st;
    CHECK(stat(out, &st) != 0);
    char part[300];
    snprintf(part, sizeof part, "%s.part", out);
    CHECK(stat(part, &st) != 0);
    /* a variable that is not an identifier, a string with a newline */
    CHECK_STATUS(bkf_plot_set_number(job, "1x", 1, &e), BKF_EINPUT);
    CHECK_STATUS(bkf_plot_set_string(job, "t", "a\nb", &e), BKF_EINPUT);
    bkf_plot_job_free(job);
    unlink(script);
    rmdir(dir);
    CHECK(bkf_plot_job_alloc("/nonexistent.gp", &e) == NULL);
}

/* Every scene shipped in fronts/ parses and plans (a typo there would be
 * the first thing a user meets). */
TEST(shipped_scenes_parse_and_plan)
{
    DIR *d = opendir(BKF_SOURCE_DIR "/fronts");
    CHECK(d);
    struct dirent *ent;
    size_t scenes = 0;
    while ((ent = readdir(d))) {
        size_t n = strlen(ent->d_name);
        if (n < 7 || strcmp(ent->d_name + n - 6, ".scene") != 0) continue;
        char path[1200];
        snprintf(path, sizeof path, "%s/fronts/%.500s", BKF_SOURCE_DIR, ent->d_name);
        bkf_scene *s = NULL;
        bkf_error e = {0};
        CHECK_MSG(bkf_scene_parse_file(path, &s, &e) == BKF_OK, "%s", e.message);
        bkf_scene_plan plan;
        bkf_scene_plan_options o = {.outdir = "out", .formats = 1, .figures = 1};
        CHECK_STATUS(bkf_scene_make_plan(s, &o, &plan, &e), BKF_OK);
        CHECK(plan.nsteps >= 1);
        bkf_scene_plan_free(&plan);
        bkf_scene_free(s);
        scenes++;
    }
    closedir(d);
    CHECK(scenes >= 7);
}

/* A figure's temporary is fresh and exclusive: a link planted at the old
 * fixed name OUT.part is not followed, and runs drawing the same image at
 * once do not break each other. */
TEST(plot_temporaries_are_exclusive)
{
    char dir[] = "/tmp/bkfront-plot-XXXXXX";
    CHECK(mkdtemp(dir));
    char script[256], out[256], part[300], victim[256];
    snprintf(script, sizeof script, "%s/ok.gp", dir);
    snprintf(out, sizeof out, "%s/f.png", dir);
    snprintf(part, sizeof part, "%s.part", out);
    snprintf(victim, sizeof victim, "%s/victim", dir);
    FILE *f = fopen(script, "w");
    CHECK(f);
    fputs("set terminal pngcairo size 200,150\nset output out\nplot sin(x)\n", f);
    fclose(f);
    f = fopen(victim, "w");
    CHECK(f);
    fputs("precious\n", f);
    fclose(f);
    CHECK(symlink(victim, part) == 0);
    bkf_error e = {0};
    bkf_plot_job *job = bkf_plot_job_alloc(script, &e);
    CHECK(job);
    CHECK_STATUS(bkf_plot_add_output(job, BKF_PLOT_PNG, out, &e), BKF_OK);
    CHECK_STATUS(bkf_plot_run(job, NULL, NULL, &e), BKF_OK);
    char *v = bkf_cli_read_file(victim);
    CHECK(v && strcmp(v, "precious\n") == 0);
    free(v);
    struct stat st;
    CHECK(stat(out, &st) == 0 && st.st_size > 0);
    unlink(part);
    /* four at once into one folder: every one succeeds */
    pid_t kids[4];
    for (int i = 0; i < 4; i++) {
        kids[i] = fork();
        if (kids[i] == 0) _exit(bkf_plot_run(job, NULL, NULL, &e) == BKF_OK ? 0 : 1);
    }
    for (int i = 0; i < 4; i++) {
        int status = 0;
        waitpid(kids[i], &status, 0);
        CHECK_MSG(WIFEXITED(status) && WEXITSTATUS(status) == 0, "run %d failed", i);
    }
    CHECK(stat(out, &st) == 0 && st.st_size > 0);
    bkf_plot_job_free(job);
    unlink(out);
    unlink(victim);
    unlink(script);
    CHECK(rmdir(dir) == 0);
}

/* Text reaches gnuplot as it was given, whatever it holds: a script
 * prints the variable into its "image" (an SVG, so that the check of a
 * whole image passes) and the file is compared with the text. */
TEST(plot_strings_reach_gnuplot_as_given)
{
    char dir[] = "/tmp/bkfront-plot-XXXXXX";
    CHECK(mkdtemp(dir));
    char script[256], out[256];
    snprintf(script, sizeof script, "%s/echo.gp", dir);
    snprintf(out, sizeof out, "%s/t.svg", dir);
    FILE *f = fopen(script, "w");
    CHECK(f);
    fputs("set print out\nprint '<svg>' . title . '</svg>'\nunset print\n", f);
    fclose(f);
    const char *texts[] = {"'It''s", "'", "''", "\"q\" 'x'", "back\\slash\\", "\\n\\t\\101",
                           "$HOME `id` @x {a_b} \"`id`\"", "", "caf\xc3\xa9"};
    for (size_t i = 0; i < sizeof texts / sizeof texts[0]; i++) {
        bkf_error e = {0};
        bkf_plot_job *job = bkf_plot_job_alloc(script, &e);
        CHECK(job);
        CHECK_STATUS(bkf_plot_set_string(job, "title", texts[i], &e), BKF_OK);
        CHECK_STATUS(bkf_plot_add_output(job, BKF_PLOT_SVG, out, &e), BKF_OK);
        int s = bkf_plot_run(job, NULL, NULL, &e);
        CHECK_MSG(s == BKF_OK, "%s: %s", texts[i], e.message);
        char want[256];
        snprintf(want, sizeof want, "<svg>%s</svg>\n", texts[i]);
        char *got = bkf_cli_read_file(out);
        CHECK_MSG(got && strcmp(got, want) == 0, "%s arrived as %s", texts[i], got ? got : "");
        free(got);
        bkf_plot_job_free(job);
        unlink(out);
    }
    unlink(script);
    CHECK(rmdir(dir) == 0);
}

/* gnuplot exits 0 after a write that failed (a full disk; here the file
 * size limit, SIGXFSZ ignored as bkfront does): the image is truncated and
 * must not be committed.  Run in a child (the limit is its own); the
 * statuses come back through a pipe. */
TEST(plot_truncated_image_is_not_committed)
{
    char dir[] = "/tmp/bkfront-plot-XXXXXX";
    CHECK(mkdtemp(dir));
    char script[256], out[3][256];
    snprintf(script, sizeof script, "%s/big.gp", dir);
    FILE *f = fopen(script, "w");
    CHECK(f);
    fputs("if (fmt eq 'png') set terminal pngcairo size 3000,2000\n"
          "if (fmt eq 'pdf') set terminal pdfcairo size 30cm,20cm\n"
          "if (fmt eq 'svg') set terminal svg size 3000,2000\n"
          "set output out\nset samples 2000\nplot for [i=1:20] sin(i*x)/i\n",
          f);
    fclose(f);
    const char *ext[3] = {"png", "pdf", "svg"};
    int fds[2];
    CHECK(pipe(fds) == 0);
    pid_t kid = fork();
    if (kid == 0) {
        struct rlimit lim = {12000, 12000};
        signal(SIGXFSZ, SIG_IGN);
        if (setrlimit(RLIMIT_FSIZE, &lim) != 0) _exit(2);
        for (int k = 0; k < 3; k++) {
            char path[256];
            snprintf(path, sizeof path, "%s/f.%s", dir, ext[k]);
            bkf_error e = {0};
            bkf_plot_job *job = bkf_plot_job_alloc(script, &e);
            int s = job ? bkf_plot_add_output(job, (bkf_plot_format)k, path, &e) : BKF_ENOMEM;
            if (!s) s = bkf_plot_run(job, NULL, NULL, &e);
            bkf_plot_job_free(job);
            char line[600];
            int n = snprintf(line, sizeof line, "%d %.500s\n", s, e.message);
            if (write(fds[1], line, (size_t)n) != n) _exit(3);
        }
        _exit(0);
    }
    close(fds[1]);
    char buf[4096] = "";
    size_t got = 0;
    for (ssize_t k; (k = read(fds[0], buf + got, sizeof buf - 1 - got)) > 0;) got += (size_t)k;
    buf[got] = '\0';
    close(fds[0]);
    int st = 0;
    CHECK(waitpid(kid, &st, 0) == kid && WIFEXITED(st) && WEXITSTATUS(st) == 0);
    const char *line = buf;
    for (int k = 0; k < 3; k++) {
        int s = atoi(line);
        CHECK_MSG(s == BKF_EIO && strstr(line, "not whole"), "%s: %.300s", ext[k], line);
        snprintf(out[k], sizeof out[k], "%s/f.%s", dir, ext[k]);
        struct stat sb;
        CHECK_MSG(stat(out[k], &sb) != 0, "a truncated %s was committed", ext[k]);
        line = strchr(line, '\n');
        CHECK(line);
        line++;
    }
    /* nothing else is left: no temporary */
    DIR *d = opendir(dir);
    CHECK(d);
    int n = 0;
    for (struct dirent *de; (de = readdir(d)) != NULL;)
        n += de->d_name[0] != '.' || strstr(de->d_name, ".tmp.") != NULL;
    closedir(d);
    CHECK_MSG(n == 1, "%d entries besides the script", n - 1);
    unlink(script);
    CHECK(rmdir(dir) == 0);
}

/* The cancel flag stops gnuplot at once: BKF_ECANCELED, no image.  The
 * flag is raised by a thread (not SIGALRM: the runner's time limit is the
 * test's alarm). */
static volatile sig_atomic_t plot_cancel;
static void *raise_plot_cancel(void *unused)
{
    (void)unused;
    struct timespec nap = {0, 300000000};
    nanosleep(&nap, NULL);
    plot_cancel = 1;
    return NULL;
}

TEST(plot_cancel_stops_gnuplot)
{
    char dir[] = "/tmp/bkfront-plot-XXXXXX";
    CHECK(mkdtemp(dir));
    char script[256], out[256];
    snprintf(script, sizeof script, "%s/slow.gp", dir);
    snprintf(out, sizeof out, "%s/f.png", dir);
    FILE *f = fopen(script, "w");
    CHECK(f);
    fputs("pause 30\nset terminal pngcairo\nset output out\nplot sin(x)\n", f);
    fclose(f);
    bkf_error e = {0};
    bkf_plot_job *job = bkf_plot_job_alloc(script, &e);
    CHECK_STATUS(bkf_plot_add_output(job, BKF_PLOT_PNG, out, &e), BKF_OK);
    pthread_t raiser;
    CHECK(pthread_create(&raiser, NULL, raise_plot_cancel, NULL) == 0);
    bkf_plot_options o = bkf_plot_options_default();
    o.cancel = &plot_cancel;
    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    CHECK_STATUS(bkf_plot_run(job, &o, NULL, &e), BKF_ECANCELED);
    clock_gettime(CLOCK_MONOTONIC, &t1);
    double dt = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
    CHECK(pthread_join(raiser, NULL) == 0);
    CHECK_MSG(dt < 2, "stopped after %.2f s", dt);
    struct stat sb;
    CHECK(stat(out, &sb) != 0);
    bkf_plot_job_free(job);
    unlink(script);
    CHECK(rmdir(dir) == 0);
}

/* ------------------------------------------------------- bounded work */

static double seconds_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* n period products, every other one the same computation as the one
 * before it (shared, run once); plus one figure per 10 products. */
static char *many_products(size_t n)
{
    size_t cap = 64 * n + 256, len = 0;
    char *text = malloc(cap);
    CHECK(text);
    len += (size_t)snprintf(text, cap, "[model]\ngamma = 2\nc = 0.3\nnu = -0.96\nS = 20\n");
    for (size_t i = 0; i < n; i++) {
        len += (size_t)snprintf(text + len, cap - len, "[period p%zu]\nmu = %.6f\n", i,
                                1 + (double)(i / 2) * 1e-4);
        if (i % 10 == 0) len += (size_t)snprintf(text + len, cap - len, "[figure p%zu]\ndata = p%zu\n", i, i);
        CHECK(len < cap);
    }
    return text;
}

/* Planning is linear in the products: 50,000 of them (25,000 distinct
 * computations, 5,000 figures) plan in well under a second, and the time
 * per product at 50,000 is within 4 times that at 5,000 (a quadratic
 * planner, as before, took 46 s: 10 times more per product). */
TEST(plan_of_many_products_is_linear)
{
    double per[2];
    size_t sizes[2] = {5000, 50000};
    for (int k = 0; k < 2; k++) {
        char *text = many_products(sizes[k]);
        double t0 = seconds_now();
        bkf_scene *s = parse_ok(text);
        bkf_scene_plan plan;
        bkf_error e = {0};
        bkf_scene_plan_options o = {.outdir = "out", .formats = 1, .figures = 1};
        CHECK_STATUS(bkf_scene_make_plan(s, &o, &plan, &e), BKF_OK);
        double dt = seconds_now() - t0;
        CHECK(plan.deduplicated == sizes[k] / 2);
        CHECK(plan.nsteps == sizes[k] / 2 + sizes[k] / 10);
        per[k] = dt / (double)sizes[k];
        bkf_test_note("%zu products: %.3f s to parse and plan", sizes[k], dt);
        bkf_scene_plan_free(&plan);
        bkf_scene_free(s);
        free(text);
    }
    CHECK_MSG(per[1] < 4 * per[0] + 2e-6, "%.3g s per product at 50000 against %.3g at 5000",
              per[1], per[0]);
}

/* A list key is one computation per value: capped at 1e5 values, with the
 * key and the limit named. */
TEST(scene_list_of_computations_is_capped)
{
    bkf_scene *s = NULL;
    bkf_error e = {0};
    CHECK_STATUS(bkf_scene_parse_string("[model]\ngamma = 2\n[period p]\nmu = 1\nnu = -0.9:0.9:100001\n", "t.scene",
                                        &s, &e),
                 BKF_EINPUT);
    CHECK_MSG(strstr(e.message, "t.scene:5: nu") && strstr(e.message, "[1, 100000]"), "%s",
              e.message);
    plan_count c = count_plan("[model]\ngamma = 2\n[period p]\nmu = 1\nnu = -0.9:0.9:100000\n", 0);
    CHECK(c.steps == 100000);
}

/* The 16 MiB limit is exact: 16 MiB is read (here refused for its content,
 * a line too long), one byte more is refused for its size. */
TEST(scene_file_size_limit_is_16_mib)
{
    char dir[] = "/tmp/bkf_scene_size_XXXXXX";
    CHECK(mkdtemp(dir));
    char path[256];
    snprintf(path, sizeof path, "%s/big.scene", dir);
    size_t limit = (size_t)16 << 20;
    char *text = malloc(limit + 1);
    CHECK(text);
    memset(text, '#', limit + 1);
    for (size_t i = 100; i < limit + 1; i += 101) text[i] = '\n'; /* comment lines */
    for (int extra = 0; extra < 2; extra++) {
        FILE *f = fopen(path, "wb");
        CHECK(f);
        CHECK(fwrite(text, 1, limit + (size_t)extra, f) == limit + (size_t)extra);
        CHECK(fclose(f) == 0);
        bkf_scene *s = NULL;
        bkf_error e = {0};
        int st = bkf_scene_parse_file(path, &s, &e);
        if (extra) {
            CHECK_STATUS(st, BKF_EINPUT);
            CHECK_MSG(strstr(e.message, "larger than 16 MiB"), "%s", e.message);
        } else {
            /* comments only: a scene with no product, refused for that */
            CHECK_MSG(!strstr(e.message, "larger than"), "%s", e.message);
            bkf_scene_free(s);
        }
    }
    free(text);
    unlink(path);
    rmdir(dir);
}

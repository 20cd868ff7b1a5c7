/* bkfront run SCENE: the products of a scene (bkfront/scene.h), computed
 * lazily, with figures.
 *
 * The library parses the scene, makes the plan and carries out its steps,
 * --jobs of them at once; this file turns flags into those calls and
 * prints the progress lines, the speeds tables and the files written.  A
 * failing product does not stop the others; figures of failed data are
 * skipped and said so. */
#define _POSIX_C_SOURCE 200809L
#include "args.h"
#include "commands.h"

#include <errno.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "bkfront/plot.h"
#include "bkfront/scene.h"

/* The gnuplot scripts' folder when neither --plots nor BKFRONT_PLOTS names
 * one: the source tree's for the build's CLI, PREFIX/share/bkfront/plots for
 * the installed one (Makefile). */
#ifndef BKF_PLOTS_DIR
#define BKF_PLOTS_DIR "plots"
#endif

static void run_help(FILE *out)
{
    fprintf(out,
        "usage: bkfront run [--plan] [--out DIR] [--formats LIST] [--no-figures]\n"
        "                   [--plots DIR] [--trust-scene] [--jobs N] SCENE\n"
        "\n"
        "Compute what the scene file SCENE asks for (an INI file: [model],\n"
        "[accuracy] and one section per product; see docs/scenes.md) and\n"
        "write the data (TSV, gnuplot matrices) and figures into one folder.\n"
        "Only the computations the products need are run, each once.\n"
        "\n"
        "options:\n"
        "  --plan          print the plan (every computation, the products that need\n"
        "                  it and its command line) and compute nothing\n"
        "  --out DIR       output folder, created if missing; default NAME beside\n"
        "                  the scene (DIR/NAME for SCENE = DIR/NAME.scene)\n"
        "  --formats LIST  image formats of figures that set none: png, pdf, svg or\n"
        "                  a list png,pdf; default png\n"
        "  --no-figures    data only (no gnuplot)\n"
        "  --plots DIR     folder of the gnuplot scripts (KIND.gp); default\n"
        "                  $BKFRONT_PLOTS, else this bkfront's own (below)\n"
        "  --trust-scene   let figures run the scene's own scripts (script = ...);\n"
        "                  a gnuplot script can run any shell command, so without\n"
        "                  this flag such a scene is refused; and let keys that\n"
        "                  name files (snapshots, fields) name them outside DIR\n"
        "  --jobs N        computations run at once, 1 to 1024, the longest expected\n"
        "                  first (a figure waits for its data); default the number\n"
        "                  of online CPUs; 1: one after the other, in the plan's\n"
        "                  order. The files are the same for every N\n"
        "\n"
        "Prints one line per computation as it ends, [K/TOTAL] its place in the\n"
        "plan, with the warnings it raised (an under-resolved simulation, refused\n"
        "rows) under it, then the speeds tables and the files written. Ctrl-C\n"
        "(SIGINT) or SIGTERM stops the whole run: the computations under way stop\n"
        "at their next check without replacing their files, the finished ones\n"
        "keep theirs, no later one starts (exit 130, 143 for SIGTERM); a second\n"
        "signal ends it at once. exit status: 0 every product done, 1 a\n"
        "computation or figure failed (the others are still produced), 2 bad\n"
        "scene or options.\n"
        "\n"
        "A scene is trusted input only with --trust-scene (docs/scenes.md#trust).\n"
        "This bkfront's gnuplot scripts: " BKF_PLOTS_DIR "\n");
}

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int make_dirs(const char *path, bkf_error *err)
{
    char buf[4096];
    if (strlen(path) >= sizeof buf) return bkf_error_set(err, BKF_EINPUT, "--out: path too long");
    snprintf(buf, sizeof buf, "%s", path);
    for (char *p = buf + 1; ; p++) {
        if (*p == '/' || *p == '\0') {
            char keep = *p;
            *p = '\0';
            if (mkdir(buf, 0777) != 0 && errno != EEXIST)
                return bkf_error_set(err, BKF_EINPUT, "--out: cannot create %s: %s", buf,
                                     strerror(errno));
            *p = keep;
            if (!keep) break;
        }
    }
    struct stat st;
    if (stat(path, &st) != 0 || !S_ISDIR(st.st_mode))
        return bkf_error_set(err, BKF_EINPUT, "--out: %s is not a folder", path);
    return BKF_OK;
}

/* The folder part of a path ("." when none). */
static void dir_of(const char *path, char *dir, size_t size)
{
    const char *slash = strrchr(path, '/');
    if (!slash)
        snprintf(dir, size, ".");
    else if (slash == path)
        snprintf(dir, size, "/");
    else
        snprintf(dir, size, "%.*s", (int)(slash - path), path);
}

static int is_dir(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 && S_ISDIR(st.st_mode);
}

/* The temporaries being written (each step's table and the data files a
 * product writes itself, e.g. simulate's spacetime and snapshots), each
 * guarded by the signal cleanup until it is committed or removed.  The
 * library calls guard_temp one call at a time, whichever job writes. */
#define RUN_TEMPS 16
typedef struct {
    char path[RUN_TEMPS][4096];
    int slot[RUN_TEMPS];
    int used[RUN_TEMPS];
    const bkf_scene *sc;
    const bkf_scene_plan *plan;
    size_t failed;
    char first_failure[BKF_ERROR_LEN];
} run_context;

static void guard_temp(const char *path, int armed, void *data)
{
    run_context *rc = data;
    for (int i = 0; i < RUN_TEMPS; i++) {
        if (armed && !rc->used[i]) {
            snprintf(rc->path[i], sizeof rc->path[i], "%s", path);
            rc->slot[i] = cli_guard_temp(path);
            rc->used[i] = 1;
            return;
        }
        if (!armed && rc->used[i] && strcmp(rc->path[i], path) == 0) {
            cli_unguard_temp(rc->slot[i]);
            rc->used[i] = 0;
            return;
        }
    }
}

/* One line per step as it ends, [K/TOTAL] its place in the plan, and
 * under it what the step raised: a product's warning (an under-resolved
 * simulation, refused rows) is otherwise only a comment in one of its
 * files.  The library calls this one step at a time. */
static void step_done(const bkf_scene_step_report *r, void *data)
{
    run_context *rc = data;
    const bkf_scene *sc = rc->sc;
    const bkf_scene_step *st = &rc->plan->steps[r->step];
    const bkf_scene_product *p = &sc->products[st->users[0]];
    printf("[%zu/%zu] %-11s %-18s %s %6.2f s  %s\n", r->step + 1, rc->plan->nsteps, st->product,
           p->name,
           r->status == BKF_ECANCELED ? "stopped" : r->status ? "FAILED" : "done  ", r->seconds,
           st->output);
    /* (simulate's messages say "warning:" themselves) */
    for (size_t k = 0; k < r->nwarnings && k < BKF_SCENE_WARNINGS; k++)
        printf("        %s%s\n", strncmp(r->warnings[k], "warning:", 8) ? "warning: " : "",
               r->warnings[k]);
    if (r->nwarnings > BKF_SCENE_WARNINGS)
        printf("        (and %zu more warnings)\n", r->nwarnings - BKF_SCENE_WARNINGS);
    if (r->status) {
        char why[BKF_ERROR_LEN];
        if (r->status == BKF_ECANCELED)
            snprintf(why, sizeof why, "stopped by %s; its files were not replaced",
                     cli_cancel_signal() == SIGTERM ? "SIGTERM" : "SIGINT");
        else
            snprintf(why, sizeof why, "%s", r->message);
        printf("        %s:%d [%s %s]: %s\n", sc->path, p->line, bkf_scene_kind_name(p->kind),
               p->name, why);
        rc->failed++;
        if (!rc->first_failure[0])
            snprintf(rc->first_failure, sizeof rc->first_failure, "%s:%d [%s %s]: %.200s",
                     sc->path, p->line, bkf_scene_kind_name(p->kind), p->name, why);
    } else if (r->gnuplot_warning[0]) {
        printf("        gnuplot: %s\n", r->gnuplot_warning);
    }
    fflush(stdout);
}

/* ------------------------------------------------------------------ run */

/* The report on stdout (the plan, the progress lines, the speeds tables)
 * is output too: a write that failed anywhere in it is an error (exit 1),
 * though the files written stay. */
static int report_status(bkf_error *err)
{
    if (fflush(stdout) == 0 && !ferror(stdout)) return BKF_OK;
    return bkf_error_set(err, BKF_EIO, "cannot write the report to standard output: %s",
                         strerror(errno));
}

static void print_plan(const bkf_scene *sc, const bkf_scene_plan *plan, FILE *out)
{
    fprintf(out, "# plan for %s: %zu computations for %zu products, output in %s\n", sc->path,
            plan->nsteps, sc->nproducts, plan->outdir);
    if (plan->deduplicated)
        fprintf(out, "# %zu computation%s shared between products (run once)\n",
                plan->deduplicated, plan->deduplicated == 1 ? "" : "s");
    for (size_t i = 0; i < plan->nsteps; i++) {
        const bkf_scene_step *st = &plan->steps[i];
        fprintf(out, "%zu\t%s\tfor", i + 1, st->product);
        for (size_t u = 0; u < st->nusers; u++) {
            const bkf_scene_product *p = &sc->products[st->users[u]];
            fprintf(out, "%s[%s %s] (line %d)", u ? ", " : " ", bkf_scene_kind_name(p->kind),
                    p->name, p->line);
        }
        if (st->kind == BKF_SCENE_STEP_FIGURE) {
            fprintf(out, "\tgnuplot on the data of");
            for (size_t k = 0; k < st->ndata; k++) {
                const bkf_scene_product *d = &sc->products[st->data_products[k]];
                fprintf(out, "%s[%s %s]", k ? ", " : " ", bkf_scene_kind_name(d->kind), d->name);
            }
            fprintf(out, " -> %s\n", st->output);
        } else {
            char *cmd = bkf_scene_step_command(st);
            fprintf(out, "\t" CLI_PROGRAM " %s\n", cmd ? cmd : "?");
            free(cmd);
        }
    }
}

/* What the command line asks: the scene and the flags. */
typedef struct {
    const char *scene_path, *out, *plots;
    int plan_only, no_figures, trust;
    unsigned formats;
    size_t jobs;
} run_args;

/* One positional argument, the scene; the rest are flags. */
static int parse_run_args(int argc, char **argv, run_args *a, bkf_error *err)
{
    *a = (run_args){0};
    char **flags_argv = calloc((size_t)argc + 1, sizeof *flags_argv);
    if (!flags_argv) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    static const char *const valued[] = {"--out", "--formats", "--plots", "--jobs", NULL};
    int fargc = 0, s = BKF_OK;
    flags_argv[fargc++] = argv[0];
    for (int i = 1; i < argc; i++) {
        const char *arg = argv[i];
        if (strncmp(arg, "--", 2) == 0) {
            flags_argv[fargc++] = argv[i];
            int takes = 0;
            for (int k = 0; valued[k]; k++)
                if (strcmp(arg, valued[k]) == 0) takes = 1;
            if (takes && i + 1 < argc) flags_argv[fargc++] = argv[++i];
        } else if (!a->scene_path) {
            a->scene_path = arg;
        } else {
            s = bkf_error_set(err, BKF_EINPUT, "'%s': give one scene file (the first was %s)",
                              arg, a->scene_path);
        }
    }
    const char *formats_text = NULL, *jobs_text = NULL;
    const cli_flag flags[] = {
        {"--plan", NULL, NULL, &a->plan_only},
        {"--no-figures", NULL, NULL, &a->no_figures},
        {"--trust-scene", NULL, NULL, &a->trust},
        {"--out", &a->out, "a folder", NULL},
        {"--formats", &formats_text, "png, pdf, svg or a list", NULL},
        {"--plots", &a->plots, "a folder", NULL},
        {"--jobs", &jobs_text, "a count of computations at once", NULL},
    };
    if (!s) s = cli_parse_flags(flags, sizeof flags / sizeof flags[0], fargc, flags_argv, err);
    free(flags_argv);
    if (s) return s;
    if (!a->scene_path) return bkf_error_set(err, BKF_EINPUT, "SCENE: give a scene file, e.g. fronts/paper.scene");
    a->formats = 1;
    if (formats_text && (s = bkf_plot_parse_formats(formats_text, "--", "formats", &a->formats, err)))
        return s;
    /* Every online CPU by default: the steps are independent and each is
     * one thread (a sweep's own threads aside). */
    a->jobs = 1;
    long cpus = sysconf(_SC_NPROCESSORS_ONLN);
    if (cpus > 1) a->jobs = cpus > 1024 ? 1024 : (size_t)cpus;
    if (jobs_text && (s = cli_parse_count("--jobs", jobs_text, 1024, &a->jobs, err))) return s;
    if (a->out && !*a->out) return bkf_error_set(err, BKF_EINPUT, "--out: the folder name is empty");
    return BKF_OK;
}

/* Without --out: NAME beside the scene (DIR/NAME for DIR/NAME.scene). */
static void default_outdir(const char *scene_path, const char *scene_dir, char *outdir,
                           size_t size)
{
    const char *base = strrchr(scene_path, '/');
    base = base ? base + 1 : scene_path;
    size_t len = strcspn(base, ".");
    snprintf(outdir, size, "%s%s%.*s", base == scene_path ? "" : scene_dir,
             base == scene_path ? "" : "/", (int)(len ? len : strlen(base)), base);
}

/* The tables users most want to read, then where everything is. */
static void print_summary(const bkf_scene *sc, const bkf_scene_plan *plan, const int *step_status,
                          double total, const char *outdir)
{
    for (size_t i = 0; i < sc->nproducts; i++) {
        if (sc->products[i].kind != BKF_SCENE_SPEEDS) continue;
        const bkf_scene_product_plan *pp = &plan->products[i];
        for (size_t k = 0; k < pp->nsteps; k++) {
            const bkf_scene_step *st = &plan->steps[pp->steps[k]];
            if (step_status[pp->steps[k]]) continue;
            FILE *f = fopen(st->output, "r");
            if (!f) continue;
            printf("\n== [speeds %s] %s\n", sc->products[i].name, st->output);
            char line[4096];
            while (fgets(line, sizeof line, f)) fputs(line, stdout);
            fclose(f);
        }
    }
    size_t nfig = 0;
    for (size_t i = 0; i < plan->nsteps; i++)
        if (plan->steps[i].kind == BKF_SCENE_STEP_FIGURE && !step_status[i]) nfig++;
    printf("\n%zu computation%s in %.2f s; %zu figure%s", plan->nsteps,
           plan->nsteps == 1 ? "" : "s", total, nfig, nfig == 1 ? "" : "s");
    if (nfig) printf(" in %s:", outdir);
    printf("\n");
    for (size_t i = 0; i < plan->nsteps; i++) {
        const bkf_scene_step *st = &plan->steps[i];
        if (st->kind != BKF_SCENE_STEP_FIGURE || step_status[i]) continue;
        for (size_t k = 0; k < st->nargs; k++) printf("  %s\n", st->args[k].value);
    }
}

/* The plan run into outdir (made if missing) and reported. */
static int run_plan(const bkf_scene *sc, const bkf_scene_plan *plan, bkf_scene_run_options *ro,
                    const run_context *rc, const char *outdir, bkf_error *err)
{
    int s = make_dirs(outdir, err);
    if (s) return s;
    int *step_status = calloc(plan->nsteps ? plan->nsteps : 1, sizeof *step_status);
    if (!step_status) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    double t_all = now();
    /* The first SIGINT or SIGTERM stops the whole run: the steps under way
     * stop at their next check (their files are not replaced), the steps
     * done keep their files, no later step starts.  A second one ends the
     * process at once (temporaries removed). */
    const volatile sig_atomic_t *cancel = cli_cancel_begin();
    ro->hooks.cancel = cancel;
    /* BKF_ECANCELED is told below, with the signal's name */
    int run_status = bkf_scene_run(sc, plan, ro, step_status, err);
    if (run_status == BKF_ENOMEM) {
        cli_cancel_end();
        free(step_status);
        return run_status;
    }
    double total = now() - t_all;
    int canceled = *cancel != 0;
    cli_cancel_end();
    if (canceled) {
        const char *sig = cli_cancel_signal() == SIGTERM ? "SIGTERM" : "SIGINT";
        size_t nsteps = plan->nsteps, done = 0;
        for (size_t i = 0; i < nsteps; i++) done += step_status[i] == BKF_OK;
        printf("\ninterrupted (%s): %zu of %zu computations done, the rest not run\n", sig, done,
               nsteps);
        fflush(stdout);
        free(step_status);
        return bkf_error_set(err, BKF_ECANCELED,
                             "interrupted (%s): %zu of %zu computations done; their files kept, "
                             "none replaced by partial data", sig, done, nsteps);
    }
    print_summary(sc, plan, step_status, total, outdir);
    int reported = report_status(err);
    int worst = bkf_scene_run_status(step_status, plan->nsteps);
    free(step_status);
    if (rc->failed)
        return bkf_error_set(err, worst,
                             "%zu of the computations failed; first: %s", rc->failed,
                             rc->first_failure);
    return reported;
}

static int run_run(int argc, char **argv, bkf_error *err)
{
    run_args a;
    int s = parse_run_args(argc, argv, &a, err);
    if (s) return s;

    bkf_scene *sc = NULL;
    if ((s = bkf_scene_parse_file(a.scene_path, &sc, err))) return s;

    char scene_dir[2048], outdir[4096], plots_dir[4096];
    dir_of(a.scene_path, scene_dir, sizeof scene_dir);
    if (a.out)
        snprintf(outdir, sizeof outdir, "%s", a.out);
    else
        default_outdir(a.scene_path, scene_dir, outdir, sizeof outdir);
    /* Never the scene's own folder: a scene from elsewhere does not choose
     * the scripts by what lies beside it. */
    const char *env_plots = getenv("BKFRONT_PLOTS");
    snprintf(plots_dir, sizeof plots_dir, "%s",
             a.plots ? a.plots : env_plots && *env_plots ? env_plots : BKF_PLOTS_DIR);
    if (!a.no_figures && !a.plan_only && !is_dir(plots_dir)) {
        bkf_scene_free(sc);
        return bkf_error_set(err, BKF_EINPUT,
                             "--plots: %s is not a folder of gnuplot scripts (give --plots DIR, "
                             "set BKFRONT_PLOTS, or --no-figures)", plots_dir);
    }
    run_context rc;
    memset(&rc, 0, sizeof rc);
    bkf_scene_run_options ro = {.program = CLI_PROGRAM " " CLI_VERSION,
                                .command_prefix = CLI_PROGRAM,
                                .plots_dir = plots_dir,
                                .scene_dir = scene_dir,
                                .hooks = {.temp_file = guard_temp, .data = &rc},
                                .temp_file = guard_temp,
                                .data = &rc,
                                .jobs = (unsigned)a.jobs,
                                .step_done = step_done};

    bkf_scene_plan plan;
    bkf_scene_plan_options po = {.outdir = outdir, .formats = a.formats,
                                 .figures = !a.no_figures, .trust = a.trust};
    if ((s = bkf_scene_make_plan(sc, &po, &plan, err))) {
        bkf_scene_free(sc);
        return s;
    }
    rc.sc = sc;
    rc.plan = &plan;
    if (a.plan_only) {
        print_plan(sc, &plan, stdout);
        s = report_status(err);
    } else {
        s = run_plan(sc, &plan, &ro, &rc, outdir, err);
    }
    bkf_scene_plan_free(&plan);
    bkf_scene_free(sc);
    return s;
}

const cli_command cli_cmd_run = {"run", "compute a scene file's products and figures (docs/scenes.md)",
                                 run_run, run_help};

/* bkfront run SCENE: the products of a scene, computed lazily, with figures.
 *
 * Each computation of the plan (scene.h) is a subcommand run in-process with
 * the product's settings and --out into the output folder; figures are
 * gnuplot runs (plot.h) on those files.  A failing product does not stop
 * the others; figures of failed data are skipped and said so. */
#define _POSIX_C_SOURCE 200809L
#include "args.h"
#include "commands.h"
#include "scene.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include "bkfront/friction.h"
#include "bkfront/io.h"
#include "bkfront/model.h"
#include "bkfront/plot.h"

static void run_help(FILE *out)
{
    fprintf(out,
        "usage: bkfront run [--plan] [--out DIR] [--formats LIST] [--no-figures]\n"
        "                   [--plots DIR] SCENE\n"
        "\n"
        "Compute what the scene file SCENE asks for (an INI file: [model],\n"
        "[accuracy] and one section per product; see docs/scenes.md) and\n"
        "write the data (TSV, gnuplot matrices) and figures into one folder.\n"
        "Only the computations the products need are run, each once.\n"
        "\n"
        "options:\n"
        "  --plan          print the plan (every computation, the products that need\n"
        "                  it and its command line) and compute nothing\n"
        "  --out DIR       output folder, created if missing; default\n"
        "                  plots/out/NAME for SCENE = .../NAME.scene\n"
        "  --formats LIST  image formats of figures that set none: png, pdf, svg or\n"
        "                  a list png,pdf; default png\n"
        "  --no-figures    data only (no gnuplot)\n"
        "  --plots DIR     folder of the default gnuplot scripts (KIND.gp); default\n"
        "                  the plots folder beside the scene's folder, else ./plots\n"
        "\n"
        "Prints one line per computation, then the speeds tables and the files\n"
        "written. exit status: 0 every product done, 1 a computation or figure\n"
        "failed (the others are still produced), 2 bad scene or options.\n");
}

/* Which failure a scene reports when several steps fail: memory first, then
 * a cancellation, then bad input, then the rest (all exit 1). */
static int severity(int status)
{
    switch (status) {
    case BKF_OK: return 0;
    case BKF_ENOMEM: return 4;
    case BKF_ECANCELED: return 3;
    case BKF_EINPUT: return 2;
    default: return 1;
    }
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

static const char *arg_after(char **argv, const char *flag)
{
    for (int i = 0; argv && argv[i]; i++)
        if (strcmp(argv[i], flag) == 0 && argv[i + 1]) return argv[i + 1];
    return NULL;
}

/* ------------------------------------------------------------- friction */

static int run_friction(const scene_step *step, bkf_error *err)
{
    bkf_friction_spec spec = bkf_friction_spec_default();
    int s = cli_parse_double("from", arg_after(step->argv, "--from"), &spec.from, err);
    if (!s) s = cli_parse_double("to", arg_after(step->argv, "--to"), &spec.to, err);
    if (!s)
        s = cli_parse_count("points", arg_after(step->argv, "--points"), BKF_FRICTION_POINTS_MAX,
                            &spec.points, err);
    if (!s && !(spec.to > spec.from))
        s = bkf_error_set(err, BKF_EINPUT, "friction: needs from < to");
    if (s) return s;
    cli_output out = {0};
    cli_buffer buf = {0};
    s = cli_output_open(&out, step->output, "--out", err);
    if (!s) s = cli_buffer_open(&buf, err);
    if (!s) s = bkf_friction_table(&spec, buf.stream, BKF_IO_TSV, NULL, err);
    if (buf.stream) {
        int c = cli_buffer_close(&buf, s ? NULL : err);
        if (!s) s = c;
    }
    if (!s)
        s = cli_output_write(&out, buf.data, buf.size, err);
    else
        cli_output_abort(&out);
    cli_buffer_free(&buf);
    return s;
}

/* --------------------------------------------------------------- figure */

typedef struct {
    const scene *sc;
    const scene_plan *plan;
    const char *plots_dir;
    char scene_dir[2048];
} run_context;

static int append(char *buf, size_t size, const char *sep, const char *text)
{
    size_t used = strlen(buf);
    int n = snprintf(buf + used, size - used, "%s%s", used ? sep : "", text);
    return n >= 0 && (size_t)n < size - used;
}

static int run_figure(const run_context *rc, const scene_step *step, char *warning,
                      size_t wsize, bkf_error *err)
{
    const scene_product *fig = &rc->sc->products[step->users[0]];
    const scene_product *data = &rc->sc->products[step->data_product];
    const scene_product_plan *dp = &rc->plan->products[step->data_product];
    char script[4096];
    const char *own = scene_value(rc->sc, fig, "script");
    if (own && own[0] == '/')
        snprintf(script, sizeof script, "%s", own);
    else if (own)
        snprintf(script, sizeof script, "%.2000s/%.2000s", rc->scene_dir, own);
    else
        snprintf(script, sizeof script, "%.2000s/%.64s.gp", rc->plots_dir, scene_kind_name(data->kind));

    char files[8192] = "", labels[4096] = "";
    for (size_t i = 0; i < dp->nsteps; i++) {
        const scene_step *ds = &rc->plan->steps[dp->steps[i]];
        if (!append(files, sizeof files, " ", ds->output))
            return bkf_error_set(err, BKF_EINPUT, "figure %s: too many data files", fig->name);
        const char *value = "";
        if (data->kind == SCENE_PERIOD || data->kind == SCENE_DISPERSION)
            value = arg_after(ds->argv, "--nu");
        else if (data->kind == SCENE_BRANCH)
            value = arg_after(ds->argv, "--n");
        if (data->kind == SCENE_PROFILE) {
            char **items;
            size_t count;
            if (!scene_list_values(arg_after(ds->argv, "--n"), &items, &count))
                return bkf_error_set(err, BKF_ENOMEM, "out of memory");
            for (size_t k = 0; k < count; k++) append(labels, sizeof labels, " ", items[k]);
            scene_list_free(items, count);
        } else if (value && *value)
            append(labels, sizeof labels, " ", value);
    }
    bkf_plot_job *job = bkf_plot_job_alloc(script, err);
    if (!job) return BKF_EINPUT;
    int s = bkf_plot_set_string(job, "files", files, err);
    /* per file: its nu (period, dispersion) or n (branch) */
    if (!s) s = bkf_plot_set_string(job, "values", labels, err);
    if (!s) s = bkf_plot_set_string(job, "plotdir", rc->plots_dir, err);
    if (!s) s = bkf_plot_set_string(job, "kind", scene_kind_name(data->kind), err);
    const char *title = scene_value(rc->sc, fig, "title");
    if (!s) s = bkf_plot_set_string(job, "title", title ? title : "", err);
    static const char *const numbers[] = {"gamma", "c", "nu", "S", "tmax"};
    for (size_t i = 0; !s && i < sizeof numbers / sizeof numbers[0]; i++) {
        const char *v = scene_value(rc->sc, data, numbers[i]);
        double x = NAN;
        if (v && !strchr(v, ',') && !strchr(v, ':')) cli_parse_double(numbers[i], v, &x, NULL);
        s = bkf_plot_set_number(job, numbers[i], x, err);
    }
    const char *param = scene_value(rc->sc, data, data->kind == SCENE_BRANCH ? "param" : "along");
    if (!s) s = bkf_plot_set_string(job, "param", param ? param : "", err);
    size_t w = 900, h = 600;
    const char *wt = scene_value(rc->sc, fig, "width"), *ht = scene_value(rc->sc, fig, "height");
    if (wt) cli_parse_count("width", wt, 1000000, &w, NULL);
    if (ht) cli_parse_count("height", ht, 1000000, &h, NULL);
    if (!s) s = bkf_plot_set_number(job, "width", (double)w, err);
    if (!s) s = bkf_plot_set_number(job, "height", (double)h, err);
    for (int i = 1; !s && i < step->argc; i += 2) {
        const char *path = step->argv[i + 1];
        const char *dot = strrchr(path, '.');
        bkf_plot_format f = strcmp(dot, ".png") == 0   ? BKF_PLOT_PNG
                            : strcmp(dot, ".pdf") == 0 ? BKF_PLOT_PDF
                                                       : BKF_PLOT_SVG;
        s = bkf_plot_add_output(job, f, path, err);
    }
    bkf_plot_report report;
    if (!s) s = bkf_plot_run(job, NULL, &report, err);
    if (!s) snprintf(warning, wsize, "%s", report.warning);
    bkf_plot_job_free(job);
    return s;
}

/* ------------------------------------------------------------------ run */

static void print_plan(const scene *sc, const scene_plan *plan, FILE *out)
{
    fprintf(out, "# plan for %s: %zu computations for %zu products, output in %s\n", sc->path,
            plan->nsteps, sc->nproducts, plan->outdir);
    if (plan->deduplicated)
        fprintf(out, "# %zu computation%s shared between products (run once)\n",
                plan->deduplicated, plan->deduplicated == 1 ? "" : "s");
    for (size_t i = 0; i < plan->nsteps; i++) {
        const scene_step *st = &plan->steps[i];
        fprintf(out, "%zu\t%s\tfor", i + 1, scene_step_label(st));
        for (size_t u = 0; u < st->nusers; u++) {
            const scene_product *p = &sc->products[st->users[u]];
            fprintf(out, "%s[%s %s] (line %d)", u ? ", " : " ", scene_kind_name(p->kind),
                    p->name, p->line);
        }
        if (st->kind == STEP_FIGURE) {
            const scene_product *d = &sc->products[st->data_product];
            fprintf(out, "\tgnuplot on the data of [%s %s] -> %s\n", scene_kind_name(d->kind),
                    d->name, st->output);
        } else if (st->kind == STEP_FORMULA) {
            fprintf(out, "\tclosed forms -> %s\n", st->output);
        } else {
            char *cmd = scene_step_command(st);
            fprintf(out, "\t" CLI_PROGRAM " %s\n", cmd ? cmd : "?");
            free(cmd);
        }
    }
}

static int parse_formats(const char *text, unsigned *formats, bkf_error *err)
{
    char buf[256];
    snprintf(buf, sizeof buf, "%s", text);
    *formats = 0;
    char *save = NULL;
    for (char *t = strtok_r(buf, ",", &save); t; t = strtok_r(NULL, ",", &save)) {
        static const char *const names[] = {"png", "pdf", "svg", NULL};
        int k;
        int s = cli_parse_choice("--formats", t, names, &k, err);
        if (s) return s;
        *formats |= 1u << k;
    }
    if (!*formats) return bkf_error_set(err, BKF_EINPUT, "--formats: give png, pdf or svg");
    return BKF_OK;
}

static int run_run(int argc, char **argv, bkf_error *err)
{
    /* One positional argument, the scene; the rest are flags. */
    char **flags_argv = calloc((size_t)argc + 1, sizeof *flags_argv);
    if (!flags_argv) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    static const char *const valued[] = {"--out", "--formats", "--plots", NULL};
    const char *scene_path = NULL;
    int fargc = 0, s = BKF_OK;
    flags_argv[fargc++] = argv[0];
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (strncmp(a, "--", 2) == 0) {
            flags_argv[fargc++] = argv[i];
            int takes = 0;
            for (int k = 0; valued[k]; k++)
                if (strcmp(a, valued[k]) == 0) takes = 1;
            if (takes && i + 1 < argc) flags_argv[fargc++] = argv[++i];
        } else if (!scene_path) {
            scene_path = a;
        } else {
            s = bkf_error_set(err, BKF_EINPUT, "'%s': give one scene file (the first was %s)",
                              a, scene_path);
        }
    }
    const char *out = NULL, *formats_text = NULL, *plots = NULL;
    int plan_only = 0, no_figures = 0;
    const cli_flag flags[] = {
        {"--plan", NULL, NULL, &plan_only},
        {"--no-figures", NULL, NULL, &no_figures},
        {"--out", &out, "a folder", NULL},
        {"--formats", &formats_text, "png, pdf, svg or a list", NULL},
        {"--plots", &plots, "a folder", NULL},
    };
    if (!s) s = cli_parse_flags(flags, sizeof flags / sizeof flags[0], fargc, flags_argv, err);
    free(flags_argv);
    if (s) return s;
    if (!scene_path) return bkf_error_set(err, BKF_EINPUT, "SCENE: give a scene file, e.g. fronts/paper.scene");
    unsigned formats = 1;
    if (formats_text && (s = parse_formats(formats_text, &formats, err))) return s;
    if (out && !*out) return bkf_error_set(err, BKF_EINPUT, "--out: the folder name is empty");

    scene *sc = NULL;
    if ((s = scene_parse_file(scene_path, &sc, err))) return s;

    run_context rc = {.sc = sc};
    dir_of(scene_path, rc.scene_dir, sizeof rc.scene_dir);
    char outdir[4096], plots_dir[4096];
    if (out)
        snprintf(outdir, sizeof outdir, "%s", out);
    else {
        const char *base = strrchr(scene_path, '/');
        base = base ? base + 1 : scene_path;
        size_t len = strcspn(base, ".");
        snprintf(outdir, sizeof outdir, "plots/out/%.*s", (int)(len ? len : strlen(base)), base);
    }
    if (plots)
        snprintf(plots_dir, sizeof plots_dir, "%s", plots);
    else {
        snprintf(plots_dir, sizeof plots_dir, "%.2000s/../plots", rc.scene_dir);
        if (!is_dir(plots_dir)) snprintf(plots_dir, sizeof plots_dir, "plots");
    }
    rc.plots_dir = plots_dir;

    scene_plan plan;
    scene_plan_options po = {.outdir = outdir, .formats = formats, .figures = !no_figures};
    if ((s = scene_make_plan(sc, &po, &plan, err))) {
        scene_free(sc);
        return s;
    }
    rc.plan = &plan;
    if (plan_only) {
        print_plan(sc, &plan, stdout);
        scene_plan_free(&plan);
        scene_free(sc);
        return fflush(stdout) == 0 ? BKF_OK : bkf_error_set(err, BKF_EIO, "cannot write");
    }
    if ((s = make_dirs(outdir, err))) {
        scene_plan_free(&plan);
        scene_free(sc);
        return s;
    }

    int *step_status = calloc(plan.nsteps ? plan.nsteps : 1, sizeof *step_status);
    if (!step_status) {
        scene_plan_free(&plan);
        scene_free(sc);
        return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    }
    int worst = BKF_OK;
    size_t failed = 0;
    char first_failure[BKF_ERROR_LEN] = "";
    double t_all = now();
    for (size_t i = 0; i < plan.nsteps; i++) {
        scene_step *st = &plan.steps[i];
        const scene_product *p = &sc->products[st->users[0]];
        bkf_error e = {0};
        char warning[BKF_ERROR_LEN] = "";
        double t0 = now();
        int status = BKF_OK;
        const char *skip = NULL;
        if (st->kind == STEP_FIGURE) {
            const scene_product_plan *dp = &plan.products[st->data_product];
            for (size_t k = 0; k < dp->nsteps; k++)
                if (step_status[dp->steps[k]]) skip = "its data failed";
        }
        if (skip) {
            status = BKF_ENUMERIC;
            snprintf(e.message, sizeof e.message, "skipped: %s", skip);
        } else if (st->kind == STEP_COMMAND) {
            const cli_command *cmd = cli_find_command(st->argv[0]);
            status = cmd ? cmd->run(st->argc, st->argv, &e)
                         : bkf_error_set(&e, BKF_EINPUT, "no subcommand %s", st->argv[0]);
        } else if (st->kind == STEP_FORMULA) {
            status = run_friction(st, &e);
        } else {
            status = run_figure(&rc, st, warning, sizeof warning, &e);
        }
        step_status[i] = status;
        double dt = now() - t0;
        printf("[%zu/%zu] %-11s %-18s %s %6.2f s  %s\n", i + 1, plan.nsteps,
               scene_step_label(st), p->name, status ? "FAILED" : "done  ", dt, st->output);
        if (status) {
            printf("        %s:%d [%s %s]: %s\n", sc->path, p->line, scene_kind_name(p->kind),
                   p->name, e.message);
            failed++;
            if (!first_failure[0])
                snprintf(first_failure, sizeof first_failure, "%s:%d [%s %s]: %.200s", sc->path,
                         p->line, scene_kind_name(p->kind), p->name, e.message);
            if (severity(status) > severity(worst)) worst = status;
        } else if (warning[0]) {
            printf("        gnuplot: %s\n", warning);
        }
        fflush(stdout);
    }
    double total = now() - t_all;

    /* The tables users most want to read, then where everything is. */
    for (size_t i = 0; i < sc->nproducts; i++) {
        if (sc->products[i].kind != SCENE_SPEEDS) continue;
        const scene_product_plan *pp = &plan.products[i];
        for (size_t k = 0; k < pp->nsteps; k++) {
            const scene_step *st = &plan.steps[pp->steps[k]];
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
    for (size_t i = 0; i < plan.nsteps; i++)
        if (plan.steps[i].kind == STEP_FIGURE && !step_status[i]) nfig++;
    printf("\n%zu computation%s in %.2f s; %zu figure%s", plan.nsteps,
           plan.nsteps == 1 ? "" : "s", total, nfig, nfig == 1 ? "" : "s");
    if (nfig) printf(" in %s:", outdir);
    printf("\n");
    for (size_t i = 0; i < plan.nsteps; i++) {
        const scene_step *st = &plan.steps[i];
        if (st->kind != STEP_FIGURE || step_status[i]) continue;
        for (int k = 1; k + 1 < st->argc + 1 && st->argv[k]; k += 2) printf("  %s\n", st->argv[k + 1]);
    }
    fflush(stdout);
    free(step_status);
    scene_plan_free(&plan);
    scene_free(sc);
    if (failed)
        return bkf_error_set(err, worst ? worst : BKF_ENUMERIC, "%zu of the computations failed; first: %s",
                             failed, first_failure);
    return BKF_OK;
}

const cli_command cli_cmd_run = {"run", "compute a scene file's products and figures (docs/scenes.md)",
                                 run_run, run_help};

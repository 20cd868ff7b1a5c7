/* One step of a plan: a product's table through the catalogue, written
 * atomically, or a figure through gnuplot. */
#define _POSIX_C_SOURCE 200809L
#include "scene_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bkfront/io.h"
#include "bkfront/plot.h"

/* ------------------------------------------------------------------- run */

static const char *arg_value(const bkf_scene_step *step, const char *key)
{
    for (size_t i = 0; i < step->nargs; i++)
        if (strcmp(step->args[i].key, key) == 0) return step->args[i].value;
    return NULL;
}

typedef int (*table_writer)(const bkf_scene_step *step, void *spec, FILE *out,
                            const bkf_provenance *prov, const bkf_scene_run_options *o,
                            bkf_error *err);

/* The step's table written atomically onto its output: whole or not at all. */
static int write_output(const bkf_scene_step *step, void *spec, table_writer write,
                        const bkf_scene_run_options *o, bkf_error *err)
{
    char *cmd = bkf_scene_step_command(step);
    size_t n = cmd ? strlen(cmd) + (o->command_prefix ? strlen(o->command_prefix) : 0) + 2 : 0;
    char *command = cmd ? malloc(n) : NULL;
    if (!command) {
        free(cmd);
        return bkf_error_set(err, BKF_ENOMEM, "out of memory");
    }
    snprintf(command, n, "%s%s%s", o->command_prefix ? o->command_prefix : "",
             o->command_prefix ? " " : "", cmd);
    free(cmd);
    /* The table goes to the "out" output; a step without one (a figure's
     * data written by the product itself) to its first output. */
    const char *path = step->output;
    for (size_t i = 0; i < step->nargs; i++)
        if (step->args[i].output && strcmp(step->args[i].key, "out") == 0)
            path = step->args[i].value;
    bkf_error e;
    bkf_io_atomic *file = bkf_io_atomic_open(path, &e);
    if (!file) {
        free(command);
        return bkf_error_set(err, BKF_EINPUT, "out: %s", e.message);
    }
    char temp[4096];
    snprintf(temp, sizeof temp, "%s", bkf_io_atomic_temp_path(file));
    if (o->temp_file) o->temp_file(temp, 1, o->data);
    bkf_provenance prov = {o->program, command};
    int s = write(step, spec, bkf_io_atomic_stream(file), &prov, o, err);
    if (!s)
        s = bkf_io_atomic_commit(file, err);
    else
        bkf_io_atomic_abort(file);
    if (o->temp_file) o->temp_file(temp, 0, o->data);
    free(command);
    return s;
}

static int write_catalogued(const bkf_scene_step *step, void *spec, FILE *out,
                            const bkf_provenance *prov, const bkf_scene_run_options *o,
                            bkf_error *err)
{
    return step->entry->write(spec, out, BKF_IO_TSV, prov, &o->hooks, err);
}

/* The default script's name: the kind's, but a stability product's shows
 * what its mode computed. */
static int is_chain(const bkf_scene *sc, const bkf_scene_product *p)
{
    const char *m = bkf_scene_value(sc, p, "model");
    return m && strcmp(m, "chain") == 0;
}

static const char *default_script(const bkf_scene *sc, const bkf_scene_step *fig,
                                  const bkf_scene_product *data)
{
    if (data->kind == BKF_SCENE_SWEEP) return "sweep_map";
    /* speeds of chains (beside the continuum's): their own figure */
    if (data->kind == BKF_SCENE_SPEEDS)
        for (size_t d = 0; d < fig->ndata; d++)
            if (is_chain(sc, &sc->products[fig->data_products[d]])) return "chain_speeds";
    if (data->kind != BKF_SCENE_STABILITY) return scene_kind_name(data->kind);
    const char *d = bkf_scene_value(sc, data, "diagram"), *l = bkf_scene_value(sc, data, "line");
    if (d && strcmp(d, "yes") == 0) return "diagram";
    if (l && strcmp(l, "yes") == 0) return "spectrum_line";
    return "spectrum";
}

static int run_figure(const bkf_scene *sc, const bkf_scene_plan *plan,
                      const bkf_scene_step *step, const bkf_scene_run_options *o,
                      char *warning, size_t wsize, bkf_error *err)
{
    const bkf_scene_product *fig = &sc->products[step->users[0]];
    const bkf_scene_product *data = &sc->products[step->data_product];
    const char *scene_dir = o->scene_dir ? o->scene_dir : ".";
    const char *plots_dir = o->plots_dir ? o->plots_dir : "plots";
    char script[4096];
    const char *own = bkf_scene_value(sc, fig, "script");
    if (own && own[0] == '/')
        snprintf(script, sizeof script, "%s", own);
    else if (own)
        snprintf(script, sizeof script, "%.2000s/%.2000s", scene_dir, own);
    else
        snprintf(script, sizeof script, "%.2000s/%.64s.gp", plots_dir,
                 default_script(sc, step, data));

    char files[8192] = "", labels[4096] = "";
    for (size_t d = 0; d < step->ndata; d++) {
        const bkf_scene_product *shown = &sc->products[step->data_products[d]];
        const bkf_scene_product_plan *dp = &plan->products[step->data_products[d]];
        for (size_t i = 0; i < dp->nsteps; i++) {
            const bkf_scene_step *ds = &plan->steps[dp->steps[i]];
            if (!scene_append(files, sizeof files, " ", ds->output))
                return bkf_error_set(err, BKF_EINPUT, "figure %s: too many data files",
                                     fig->name);
            /* each file's value of the list that made it (nu of period
             * and dispersion, n of branch and stability) */
            const bkf_option *fanout = ds->entry ? scene_fanout_option(ds->entry) : NULL;
            const char *value = fanout ? arg_value(ds, fanout->name) : "";
            if (shown->kind == BKF_SCENE_SWEEP)
                /* the map, then the Floquet diagram of each gamma */
                value = strcmp(ds->product, "sweep") == 0 ? "map" : arg_value(ds, "gamma");
            else if (shown->kind == BKF_SCENE_SPEEDS && step->ndata > 1) {
                /* which table is which: the chain's blocks, or the continuum */
                const char *m = arg_value(ds, "model");
                value = "continuum";
                if (m && strcmp(m, "chain") == 0)
                    value = arg_value(ds, "N") ? arg_value(ds, "N") : arg_value(ds, "S");
            }
            if (shown->kind == BKF_SCENE_PROFILE) {
                char **items;
                size_t count;
                if (!scene_list_values(arg_value(ds, "n"), &items, &count))
                    return bkf_error_set(err, BKF_ENOMEM, "out of memory");
                for (size_t k = 0; k < count; k++) scene_append(labels, sizeof labels, " ", items[k]);
                scene_list_values_free(items, count);
            } else if (value && *value)
                scene_append(labels, sizeof labels, " ", value);
        }
    }
    bkf_plot_job *job = bkf_plot_job_alloc(script, err);
    if (!job) return BKF_EINPUT;
    int s = bkf_plot_set_string(job, "files", files, err);
    /* per file: its nu (period, dispersion) or n (branch) */
    if (!s) s = bkf_plot_set_string(job, "values", labels, err);
    if (!s) s = bkf_plot_set_string(job, "plotdir", plots_dir, err);
    if (!s) s = bkf_plot_set_string(job, "kind", scene_kind_name(data->kind), err);
    const char *title = bkf_scene_value(sc, fig, "title");
    if (!s) s = bkf_plot_set_string(job, "title", title ? title : "", err);
    static const char *const numbers[] = {"gamma", "c", "nu", "S", "tmax"};
    for (size_t i = 0; !s && i < sizeof numbers / sizeof numbers[0]; i++) {
        const char *v = bkf_scene_value(sc, data, numbers[i]);
        double x = NAN;
        if (v && !strchr(v, ',') && !strchr(v, ':'))
            bkf_option_parse_double(v, "", numbers[i], &x, NULL);
        s = bkf_plot_set_number(job, numbers[i], x, err);
    }
    const char *param =
        bkf_scene_value(sc, data, data->kind == BKF_SCENE_BRANCH ? "param" : "along");
    if (!s) s = bkf_plot_set_string(job, "param", param ? param : "", err);
    size_t w = 900, h = 600;
    const char *wt = bkf_scene_value(sc, fig, "width"), *ht = bkf_scene_value(sc, fig, "height");
    if (wt) bkf_option_parse_count(wt, 1, BKF_PLOT_PIXELS_MAX, "", "width", &w, NULL);
    if (ht) bkf_option_parse_count(ht, 1, BKF_PLOT_PIXELS_MAX, "", "height", &h, NULL);
    if (!s) s = bkf_plot_set_number(job, "width", (double)w, err);
    if (!s) s = bkf_plot_set_number(job, "height", (double)h, err);
    for (size_t i = 0; !s && i < step->nargs; i++) {
        const char *path = step->args[i].value;
        const char *dot = strrchr(path, '.');
        bkf_plot_format f = strcmp(dot, ".png") == 0   ? BKF_PLOT_PNG
                            : strcmp(dot, ".pdf") == 0 ? BKF_PLOT_PDF
                                                       : BKF_PLOT_SVG;
        s = bkf_plot_add_output(job, f, path, err);
    }
    bkf_plot_report report;
    bkf_plot_options po = bkf_plot_options_default();
    po.cancel = o->hooks.cancel;
    po.temp_file = o->temp_file;
    po.data = o->data;
    if (!s) s = bkf_plot_run(job, &po, &report, err);
    if (!s && warning) snprintf(warning, wsize, "%s", report.warning);
    bkf_plot_job_free(job);
    return s;
}

int bkf_scene_run_step(const bkf_scene *s, const bkf_scene_plan *plan, size_t i,
                       const int *done, const bkf_scene_run_options *options, char *warning,
                       size_t wsize, bkf_error *err)
{
    static const bkf_scene_run_options none = {0};
    const bkf_scene_run_options *o = options ? options : &none;
    if (warning && wsize) warning[0] = '\0';
    if (!s || !plan || i >= plan->nsteps)
        return bkf_error_set(err, BKF_EINPUT, "scene: no such step");
    const bkf_scene_step *step = &plan->steps[i];
    if (step->kind == BKF_SCENE_STEP_FIGURE) {
        for (size_t d = 0; d < step->ndata; d++) {
            const bkf_scene_product_plan *dp = &plan->products[step->data_products[d]];
            for (size_t k = 0; done && k < dp->nsteps; k++)
                if (dp->steps[k] < i && done[dp->steps[k]])
                    return bkf_error_set(err, BKF_ENUMERIC, "skipped: its data failed");
        }
        return run_figure(s, plan, step, o, warning, wsize, err);
    }
    if (step->entry) {
        void *spec = bkf_catalog_spec_new(step->entry, err);
        if (!spec) return BKF_ENOMEM;
        int st = scene_apply_args(step->entry, step->args, step->nargs, spec, 1, NULL, err);
        if (!st) st = step->entry->check(spec, "", err);
        if (!st) st = write_output(step, spec, write_catalogued, o, err);
        bkf_catalog_spec_free(step->entry, spec);
        return st;
    }
    return bkf_error_set(err, BKF_EINPUT, "no product %s in the catalogue", step->product);
}

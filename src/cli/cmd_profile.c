/* bkfront profile: the shape of a front, f(z) and f'(z) over one period of
 * the limit cycle, at the predicted speed of n fronts (or at a given mu).
 *
 * For n fronts the position along the system is also given:
 * psi(x, t) = f((x/v + t)/stretch), stretch = sqrt(1 - c^2/v^2), so at t = 0
 * the wave spans x = z v stretch, one wavelength S/n per period.  One speeds
 * solve serves every n asked for (the n range of bkf_speeds_find). */
#include "args.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bkfront/cycle.h"
#include "bkfront/io.h"
#include "bkfront/model.h"
#include "bkfront/speeds.h"

#define MAX_POINTS 100000u
#define MAX_N 100000u
#define MAX_LIST 1000u

static const bkf_io_column columns[] = {
    {"n", BKF_IO_NUMBER},  {"root", BKF_IO_NUMBER}, {"v", BKF_IO_NUMBER},
    {"mu", BKF_IO_NUMBER}, {"T", BKF_IO_NUMBER},    {"z", BKF_IO_NUMBER},
    {"x", BKF_IO_NUMBER},  {"f", BKF_IO_NUMBER},    {"fprime", BKF_IO_NUMBER}};
#define NCOLUMNS (sizeof columns / sizeof columns[0])

static const char *const format_names[] = {"tsv", "json", NULL};

static void profile_help(FILE *out)
{
    fprintf(out,
        "usage: bkfront profile --nu V (--gamma G --c C --S L --n K[,K...] [--root I] | --mu M)\n"
        "                       [--points P] [--tol E] [--format tsv|json] [--out FILE]\n"
        "\n"
        "The front profile: f(z) and f'(z) over one period of the limit cycle of\n"
        "f'' + mu (f^2 - 1) f' + f = nu, z = 0 where f = nu rising. With --n, mu is\n"
        "that of the predicted speed of n fronts (as in bkfront speeds) and x is the\n"
        "position along the system at t = 0 (one wavelength S/n per period); with\n"
        "--mu, the cycle at that mu (n, root, v and x are nan).\n"
        "\n"
        "options:\n"
        "  --gamma G, --c C, --S L   model parameters, as in bkfront speeds\n"
        "  --nu V        required; pulling rate in (-1, 1)\n"
        "  --n LIST      numbers of fronts: K, K1,K2,... or A:B:N (at most %u)\n"
        "  --root I      which root of each n, 1 the fastest; default 1\n"
        "  --mu M        the cycle at mu = M instead, in [1e-06, 1e+06]\n"
        "  --points P    samples per period, in [2, %u]; default 2000\n"
        "  --tol E       relative accuracy of the cycle and the speed, in [1e-14, 0.1];\n"
        "                default 1e-10\n"
        "  --format tsv|json, --out FILE   as in bkfront speeds\n"
        "\n"
        "columns: n, root, v, mu, T (period in z), z, x = z v sqrt(1 - c^2/v^2), f, fprime\n",
        MAX_LIST, MAX_POINTS);
}

typedef struct {
    bkf_model_params params;
    size_t *n;
    size_t nn, root, points;
    double mu, tol;
    bkf_io_format format;
    const char *out_path;
} profile_plan;

static int parse_n_list(const char *text, profile_plan *p, bkf_error *err)
{
    size_t cap = 0;
    if (strchr(text, ':')) {
        cli_range r;
        int s = cli_parse_range("--n", text, 0, &r, err);
        if (s) return s;
        if (r.count > MAX_LIST) {
            cli_range_free(&r);
            return bkf_error_set(err, BKF_EINPUT, "--n: '%s' has more than %u values", text,
                                 MAX_LIST);
        }
        p->n = malloc(r.count * sizeof *p->n);
        for (size_t i = 0; p->n && i < r.count; i++) {
            double v = r.values[i];
            if (!(v >= 1 && v <= MAX_N && v == floor(v))) {
                cli_range_free(&r);
                return bkf_error_set(err, BKF_EINPUT, "--n: '%s' has a value that is not an "
                                     "integer in [1, %u]", text, MAX_N);
            }
            p->n[i] = (size_t)v;
        }
        p->nn = p->n ? r.count : 0;
        cli_range_free(&r);
        return p->n ? BKF_OK : bkf_error_set(err, BKF_ENOMEM, "out of memory");
    }
    const char *t = text;
    for (;;) {
        size_t len = strcspn(t, ",");
        char item[32];
        if (len == 0 || len >= sizeof item)
            return bkf_error_set(err, BKF_EINPUT, "--n: '%s' is not K, K1,K2,... or A:B:N", text);
        memcpy(item, t, len);
        item[len] = '\0';
        if (p->nn == MAX_LIST)
            return bkf_error_set(err, BKF_EINPUT, "--n: more than %u values", MAX_LIST);
        if (p->nn == cap) {
            cap = cap ? 2 * cap : 8;
            size_t *g = realloc(p->n, cap * sizeof *g);
            if (!g) return bkf_error_set(err, BKF_ENOMEM, "out of memory");
            p->n = g;
        }
        int s = cli_parse_count("--n", item, MAX_N, &p->n[p->nn], err);
        if (s) return s;
        p->nn++;
        if (!t[len]) break;
        t += len + 1;
    }
    return BKF_OK;
}

static int plan_profile(int argc, char **argv, profile_plan *p, bkf_error *err)
{
    const char *gamma = NULL, *c = NULL, *nu = NULL, *S = NULL, *n = NULL, *root = NULL,
               *mu = NULL, *points = NULL, *tol = NULL, *format = NULL, *out = NULL;
    const cli_flag flags[] = {
        {"--gamma", &gamma, "a number in [1e-6, 1e6]", NULL},
        {"--c", &c, "a number >= 0", NULL},
        {"--nu", &nu, "a number in (-1, 1)", NULL},
        {"--S", &S, "a number > 0", NULL},
        {"--n", &n, "K, K1,K2,... or A:B:N", NULL},
        {"--root", &root, "an integer >= 1", NULL},
        {"--mu", &mu, "a number in [1e-6, 1e6]", NULL},
        {"--points", &points, "an integer >= 2", NULL},
        {"--tol", &tol, "a number in [1e-14, 0.1]", NULL},
        {"--format", &format, "tsv or json", NULL},
        {"--out", &out, "a file name", NULL},
    };
    int s = cli_parse_flags(flags, sizeof flags / sizeof flags[0], argc, argv, err);
    if (s) return s;
    bkf_error e;
    if (!nu) return bkf_error_set(err, BKF_EINPUT, "--nu: required (a number in (-1, 1))");
    if ((s = cli_parse_double("--nu", nu, &p->params.nu, err))) return s;
    if (bkf_model_check_nu_active(p->params.nu, &e))
        return bkf_error_set(err, BKF_EINPUT, "--nu: %s", e.message);
    p->mu = NAN;
    if (mu) {
        if (gamma || c || S || n || root)
            return bkf_error_set(err, BKF_EINPUT,
                                 "--mu: give either --mu or the model (--gamma --c --S --n)");
        if ((s = cli_parse_double("--mu", mu, &p->mu, err))) return s;
        if (!(p->mu >= BKF_CYCLE_MU_MIN && p->mu <= BKF_CYCLE_MU_MAX))
            return bkf_error_set(err, BKF_EINPUT, "--mu: %s is outside [1e-06, 1e+06]", mu);
    } else {
        const char *need[] = {gamma, c, S, n};
        const char *names[] = {"--gamma", "--c", "--S", "--n"};
        for (int i = 0; i < 4; i++)
            if (!need[i])
                return bkf_error_set(err, BKF_EINPUT, "%s: required unless --mu is given",
                                     names[i]);
        if ((s = cli_parse_double("--gamma", gamma, &p->params.gamma, err))) return s;
        if ((s = cli_parse_double("--c", c, &p->params.c, err))) return s;
        if ((s = cli_parse_double("--S", S, &p->params.S, err))) return s;
        if ((s = parse_n_list(n, p, err))) return s;
        p->root = 1;
        if (root && (s = cli_parse_count("--root", root, 1000, &p->root, err))) return s;
    }
    p->points = 2000;
    if (points && (s = cli_parse_count("--points", points, MAX_POINTS, &p->points, err))) return s;
    if (p->points < 2) return bkf_error_set(err, BKF_EINPUT, "--points: %s is below 2", points);
    p->tol = 1e-10;
    if (tol) {
        if ((s = cli_parse_double("--tol", tol, &p->tol, err))) return s;
        if (bkf_model_check_tol(p->tol, &e))
            return bkf_error_set(err, BKF_EINPUT, "--tol: %s", e.message);
    }
    p->format = BKF_IO_TSV;
    if (format) {
        int k;
        if ((s = cli_parse_choice("--format", format, format_names, &k, err))) return s;
        p->format = k ? BKF_IO_JSON : BKF_IO_TSV;
    }
    if (out && !*out) return bkf_error_set(err, BKF_EINPUT, "--out: the file name is empty");
    p->out_path = out;
    if (!mu) {
        bkf_speeds_options o = bkf_speeds_options_default();
        o.tol = p->tol;
        if (bkf_speeds_check(&p->params, &o, &e))
            return bkf_error_set(err, BKF_EINPUT, "%s", e.message);
    }
    return BKF_OK;
}

/* One period of the cycle in `cycle`, as rows. */
static int write_cycle(bkf_io_table *table, bkf_cycle *cycle, double n, double root, double v,
                       double stretch, size_t points, bkf_error *err)
{
    const bkf_cycle_result *r = bkf_cycle_get(cycle);
    for (size_t i = 0; i <= points; i++) {
        double z = r->period * (double)i / (double)points, f, fp;
        int s = bkf_cycle_profile(cycle, z, &f, &fp, err);
        if (s) return s;
        bkf_io_value row[NCOLUMNS] = {{n, NULL},  {root, NULL},        {v, NULL},
                                      {r->mu, NULL}, {r->period, NULL}, {z, NULL},
                                      {z * v * stretch, NULL}, {f, NULL}, {fp, NULL}};
        if ((s = bkf_io_table_row(table, row, err))) return s;
    }
    return BKF_OK;
}

static int fill(const profile_plan *p, int argc, char **argv, FILE *stream, bkf_error *err)
{
    bkf_io_table *table = bkf_io_table_alloc(stream, p->format, columns, NCOLUMNS, err);
    if (!table) return BKF_ENOMEM;
    bkf_cycle *cycle = bkf_cycle_alloc();
    bkf_speeds_table speeds = {0};
    char *cmd = cli_command_line(argc, argv);
    char text[512];
    int s = cycle && cmd ? BKF_OK : bkf_error_set(err, BKF_ENOMEM, "out of memory");
    if (!s) {
        snprintf(text, sizeof text,
                 "bkfront " CLI_VERSION " profile: f(z), f'(z) over one period of the cycle");
        s = bkf_io_table_comment(table, text, err);
    }
    if (!s) {
        snprintf(text, sizeof text, "command: " CLI_PROGRAM " %.480s", cmd);
        s = bkf_io_table_comment(table, text, err);
    }
    bkf_cycle_options co = bkf_cycle_options_default();
    co.tol = p->tol;
    co.warm_start = 0;
    if (!s && isnan(p->mu)) {
        size_t lo = p->n[0], hi = p->n[0];
        for (size_t i = 0; i < p->nn; i++) {
            if (p->n[i] < lo) lo = p->n[i];
            if (p->n[i] > hi) hi = p->n[i];
        }
        bkf_speeds_options so = bkf_speeds_options_default();
        so.tol = p->tol;
        so.n_from = lo;
        so.n_to = hi;
        s = bkf_speeds_find(&p->params, &so, &speeds, err);
        if (!s) {
            snprintf(text, sizeof text, "gamma %.17g, c %.17g, nu %.17g, S %.17g; x = z v "
                     "sqrt(1 - c^2/v^2)", p->params.gamma, p->params.c, p->params.nu,
                     p->params.S);
            s = bkf_io_table_comment(table, text, err);
        }
        for (size_t i = 0; !s && i < p->nn; i++) {
            const bkf_speeds_root *root = NULL;
            size_t seen = 0;
            for (size_t k = 0; k < speeds.count; k++)
                if (speeds.roots[k].n == p->n[i] && ++seen == p->root) root = &speeds.roots[k];
            if (!root) {
                s = bkf_error_set(err, BKF_EINPUT,
                                  "--n: n = %zu has %zu root%s, not a root %zu (n_max = %ld)",
                                  p->n[i], seen, seen == 1 ? "" : "s", p->root, speeds.n_max);
                break;
            }
            if (!isfinite(root->mu)) {
                s = bkf_error_set(err, BKF_ENUMERIC, "n = %zu: the root is at the sonic limit",
                                  p->n[i]);
                break;
            }
            s = bkf_cycle_solve(cycle, root->mu, p->params.nu, &co, err);
            double stretch = p->params.c > 0 ? sqrt(1 - (p->params.c / root->v) *
                                                            (p->params.c / root->v)) : 1.0;
            if (!s)
                s = write_cycle(table, cycle, (double)p->n[i], (double)p->root, root->v,
                                stretch, p->points, err);
        }
    } else if (!s) {
        s = bkf_cycle_solve(cycle, p->mu, p->params.nu, &co, err);
        if (!s) s = write_cycle(table, cycle, NAN, NAN, NAN, NAN, p->points, err);
    }
    if (!s) s = bkf_io_table_finish(table, err);
    free(cmd);
    bkf_speeds_table_free(&speeds);
    bkf_cycle_free(cycle);
    bkf_io_table_free(table);
    return s;
}

static int profile_run(int argc, char **argv, bkf_error *err)
{
    profile_plan p = {0};
    int s = plan_profile(argc, argv, &p, err);
    cli_output out = {0};
    cli_buffer buf = {0};
    if (!s) s = cli_output_open(&out, p.out_path, "--out", err);
    if (!s) {
        s = cli_buffer_open(&buf, err);
        if (!s) {
            s = fill(&p, argc, argv, buf.stream, err);
            int c = cli_buffer_close(&buf, s ? NULL : err);
            if (!s) s = c;
        }
        if (!s)
            s = cli_output_write(&out, buf.data, buf.size, err);
        else
            cli_output_abort(&out);
    }
    cli_buffer_free(&buf);
    free(p.n);
    return s;
}

const cli_command cli_cmd_profile = {"profile", "front profiles f(z), f'(z) and x along the system",
                                     profile_run, profile_help};

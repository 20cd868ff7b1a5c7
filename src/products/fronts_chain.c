/* `bkfront branch --model chain` (see fronts.h): one rotating wave of the
 * chain followed by bkf_chainwave_branch, as a table. */
#include "fronts_internal.h"

#include <math.h>
#include <stdlib.h>

#include "bkfront/chainwave.h"

#include "product_internal.h"

static const bkf_chainwave_param chain_params[] = {BKF_CHAINWAVE_PARAM_S, BKF_CHAINWAVE_PARAM_NU,
                                                   BKF_CHAINWAVE_PARAM_GAMMA, BKF_CHAINWAVE_PARAM_C,
                                                   BKF_CHAINWAVE_PARAM_H};

/* The chain's model at the branch's start (the continued parameter at
 * `from`) and its blocks. */
int fronts_chain_branch_model(const bkf_fronts_branch_spec *spec, const char *p,
                              bkf_model_params *m, bkf_error *err)
{
    double S = spec->along == BKF_SPEEDS_ALONG_S || spec->along == ALONG_H ? NAN : spec->S;
    size_t N = spec->N;
    if (!N && !(S >= BKF_CHAINWAVE_N_MIN && S <= BKF_CHAINWAVE_N_MAX && S == floor(S)))
        return bkf_error_set(err, BKF_EINPUT, "%sN: the number of blocks, in [%d, %d], is "
                             "needed (S is not a whole number there, or it is continued)", p,
                             BKF_CHAINWAVE_N_MIN, BKF_CHAINWAVE_N_MAX);
    if (!N) N = (size_t)S;
    *m = (bkf_model_params){spec->gamma, spec->c, spec->nu, spec->S, N, BKF_MODEL_CHAIN};
    double x = spec->from;
    switch (spec->along) {
    case BKF_SPEEDS_ALONG_S: m->S = x; break;
    case BKF_SPEEDS_ALONG_NU: m->nu = x; break;
    case BKF_SPEEDS_ALONG_GAMMA: m->gamma = x; break;
    case BKF_SPEEDS_ALONG_C: m->c = x; break;
    default: m->S = x * (double)N; break;
    }
    return BKF_OK;
}

static const bkf_io_column chain_branch_columns[] = {
    {"point", BKF_IO_TEXT}, {"value", BKF_IO_NUMBER}, {"S", BKF_IO_NUMBER},
    {"h", BKF_IO_NUMBER}, {"gamma", BKF_IO_NUMBER}, {"c", BKF_IO_NUMBER},
    {"nu", BKF_IO_NUMBER}, {"K", BKF_IO_NUMBER}, {"n", BKF_IO_NUMBER},
    {"v", BKF_IO_NUMBER}, {"P", BKF_IO_NUMBER}, {"tau", BKF_IO_NUMBER},
    {"stable", BKF_IO_TEXT}, {"mult_abs", BKF_IO_NUMBER}, {"sigma_max", BKF_IO_NUMBER},
    {"trivial_err", BKF_IO_NUMBER}};
#define NCHAIN_BRANCH (sizeof chain_branch_columns / sizeof chain_branch_columns[0])

typedef struct {
    bkf_chainwave_branch_point *points;
    size_t count, cap, max_points, regular;
    int oom;
} chain_branch_sink;

static int chain_branch_keep(const bkf_chainwave_branch_point *pt, void *data)
{
    chain_branch_sink *k = data;
    if (k->count == k->cap) {
        size_t cap = k->cap ? 2 * k->cap : 64;
        bkf_chainwave_branch_point *np = realloc(k->points, cap * sizeof *np);
        if (!np) return k->oom = 1;
        k->points = np;
        k->cap = cap;
    }
    k->points[k->count++] = *pt;
    k->regular += !pt->is_fold;
    return k->max_points && k->regular >= k->max_points;
}

int fronts_chain_branch_write(const bkf_fronts_branch_spec *spec, const char *name, FILE *out,
                              bkf_io_format format, const bkf_provenance *prov, bkf_error *err)
{
    bkf_model_params m;
    int s = fronts_chain_branch_model(spec, "", &m, err);
    if (s) return s;
    bkf_chainwave_options o = bkf_chainwave_options_default();
    o.tol = spec->tol;
    o.stability = spec->stability;
    chain_branch_sink k = {NULL, 0, 0, spec->max_points, 0, 0};
    bkf_chainwave_branch_report rep;
    s = bkf_chainwave_branch(&m, spec->n, spec->root, chain_params[spec->along], spec->from,
                             spec->to, &o, chain_branch_keep, &k, &rep, err);
    if (!s && k.oom) s = bkf_error_set(err, BKF_ENOMEM, "out of memory");
    bkf_io_table *t = NULL;
    char title[160];
    snprintf(title, sizeof title, "branch --model chain: one rotating wave of the chain "
             "followed along %s (pseudo-arclength, through folds)", name);
    if (!s)
        s = bkf_product_table_open(out, format, chain_branch_columns, NCHAIN_BRANCH, title, prov,
                                   &t, err);
    char a[32], b[32], c[32], d[32];
    if (!s)
        s = bkf_io_table_commentf(t, err, "wave %zu of n = %zu on N = %zu blocks, %s from %.17g "
                    "to %.17g; start: gamma %s, c %s, nu %s, S %s (h = S/N, K = c^2/h^2); tol %g",
                    spec->root, spec->n, m.N, name, spec->from, spec->to,
                    bkf_format_number(m.gamma, a, sizeof a), bkf_format_number(m.c, b, sizeof b),
                    bkf_format_number(m.nu, c, sizeof c), bkf_format_number(m.S, d, sizeof d),
                    o.tol);
    if (!s)
        s = bkf_io_table_commentf(t, err, "%zu points, %zu folds; %s%s", rep.points, rep.folds,
                    rep.reached ? "reached the end" : rep.pinned ? "pinning: " : "ended: ",
                    rep.reached ? "" : rep.note[0] ? rep.note : "stopped at max-points");
    if (!s) s = bkf_product_table_command(t, prov, err);
    for (size_t i = 0; !s && i < k.count; i++) {
        const bkf_chainwave_branch_point *pt = &k.points[i];
        bkf_io_value v[NCHAIN_BRANCH];
        double num[NCHAIN_BRANCH] = {0,     pt->value, pt->S, pt->h,  pt->gamma,
                                     pt->c, pt->nu,    pt->K, (double)spec->n, pt->v,
                                     pt->P, pt->tau,   0,     pt->mult_abs, pt->sigma_max,
                                     pt->trivial_err};
        for (size_t j = 0; j < NCHAIN_BRANCH; j++) v[j].number = num[j];
        v[0].text = pt->is_fold ? "fold" : "point";
        v[12].text = bkf_chainwave_verdict_name(pt->verdict);
        s = bkf_io_table_row(t, v, err);
    }
    if (!s) s = bkf_io_table_finish(t, err);
    bkf_io_table_free(t);
    free(k.points);
    return s;
}


#include "bkfront/friction.h"

#include <math.h>
#include <string.h>

#include "bkfront/model.h"

#include "product_internal.h"

static const bkf_io_column columns[] = {{"v", BKF_IO_NUMBER},
                                        {"psi", BKF_IO_NUMBER},
                                        {"creep_slip", BKF_IO_NUMBER},
                                        {"carlson_langer", BKF_IO_NUMBER}};
#define NCOLUMNS (sizeof columns / sizeof columns[0])

const bkf_option bkf_friction_options[] = {
    {.name = "from", .type = BKF_OPT_DOUBLE, .offset = offsetof(bkf_friction_spec, from),
     .flags = BKF_OPT_MIN | BKF_OPT_MAX, .min = -BKF_FRICTION_V_MAX, .max = BKF_FRICTION_V_MAX,
     .form = "V", .shown_default = "-1", .help = "lowest block velocity, in [-1e100, 1e100]"},
    {.name = "to", .type = BKF_OPT_DOUBLE, .offset = offsetof(bkf_friction_spec, to),
     .flags = BKF_OPT_MIN | BKF_OPT_MAX, .min = -BKF_FRICTION_V_MAX, .max = BKF_FRICTION_V_MAX,
     .form = "V", .shown_default = "4",
     .help = "highest block velocity, > from, in [-1e100, 1e100]"},
    {.name = "points", .type = BKF_OPT_COUNT, .offset = offsetof(bkf_friction_spec, points),
     .flags = BKF_OPT_MIN | BKF_OPT_MAX, .min = 1, .max = BKF_FRICTION_POINTS_MAX, .form = "N",
     .shown_default = "601", .help = "rows, evenly spaced, both ends included"},
};
const size_t bkf_friction_noptions = sizeof bkf_friction_options / sizeof bkf_friction_options[0];

bkf_friction_spec bkf_friction_spec_default(void)
{
    bkf_friction_spec s = {-1, 4, 601};
    return s;
}

int bkf_friction_check(const bkf_friction_spec *spec, const char *prefix, bkf_error *err)
{
    const char *p = prefix ? prefix : "";
    if (!spec) return bkf_error_set(err, BKF_EINPUT, "friction: spec is NULL");
    /* the table's range, again for a spec filled in C */
    if (!(fabs(spec->from) <= BKF_FRICTION_V_MAX && fabs(spec->to) <= BKF_FRICTION_V_MAX))
        return bkf_error_set(err, BKF_EINPUT, "%sfrom, %sto: each must be in [-1e+100, 1e+100]",
                             p, p);
    if (!(spec->to > spec->from))
        return bkf_error_set(err, BKF_EINPUT, "%sfrom, %sto: friction needs from < to", p, p);
    if (spec->points < 1 || spec->points > BKF_FRICTION_POINTS_MAX)
        return bkf_error_set(err, BKF_EINPUT, "%spoints: not in [1, %u]", p,
                             BKF_FRICTION_POINTS_MAX);
    return BKF_OK;
}

bkf_friction_row bkf_friction_at(double v)
{
    /* the jump of the Carlson-Langer law at v = 0 is drawn as a gap */
    bkf_friction_row r = {v, v - 1, 1.5 * bkf_model_friction(v - 1),
                          v == 0 ? NAN : bkf_model_friction_carlson_langer(v)};
    return r;
}

int bkf_friction_table(const bkf_friction_spec *spec, FILE *out, bkf_io_format format,
                       const bkf_provenance *prov, bkf_error *err)
{
    int s = bkf_friction_check(spec, "", err);
    if (s) return s;
    bkf_io_table *t;
    s = bkf_product_table_open(out, format, columns, NCOLUMNS,
                               "friction laws against block velocity v: creep_slip = "
                               "(3/2) phi(psi), phi = psi^3/3 - psi, psi = v - 1 (slip "
                               "threshold psi = -1 at v = 0, scaled to static friction 1); "
                               "carlson_langer = sgn(v)/(1 + |v|)",
                               prov, &t, err);
    if (s) return s;
    s = bkf_product_table_command(t, prov, err);
    for (size_t i = 0; !s && i < spec->points; i++) {
        double v = spec->points > 1
                       ? spec->from + (spec->to - spec->from) * (double)i / (double)(spec->points - 1)
                       : spec->from;
        bkf_friction_row r = bkf_friction_at(v);
        bkf_io_value row[NCOLUMNS] = {{r.v, NULL}, {r.psi, NULL}, {r.creep_slip, NULL},
                                      {r.carlson_langer, NULL}};
        s = bkf_io_table_row(t, row, err);
    }
    if (!s) s = bkf_io_table_finish(t, err);
    bkf_io_table_free(t);
    return s;
}

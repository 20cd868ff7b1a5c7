/* The friction-law product: the model's creep-slip law beside the
 * Carlson-Langer velocity-weakening law, sampled against the block
 * velocity v for comparison figures (the scene kind "friction").
 *
 * Columns: v; psi = v - 1 (the slip threshold psi = -1 at v = 0);
 * creep_slip = (3/2) phi(psi), phi = psi^3/3 - psi, scaled to static
 * friction 1; carlson_langer = sgn(v)/(1 + |v|), NaN at v = 0 where the law
 * jumps (drawn as a gap).  The closed forms are model.h's. */
#ifndef BKFRONT_FRICTION_H
#define BKFRONT_FRICTION_H

#include <stddef.h>
#include <stdio.h>
#include "bkfront/io.h"
#include "bkfront/options.h"
#include "bkfront/status.h"

#ifdef __cplusplus
extern "C" {
#endif

#define BKF_FRICTION_POINTS_MAX 1000000u
/* |v| at most: phi(v - 1) ~ v^3/3 stays finite (DBL_MAX^(1/3) ~ 5.6e102),
 * and so does to - from. */
#define BKF_FRICTION_V_MAX 1e100

typedef struct {
    double from, to;   /* the velocity range, from < to, each in [-1e100, 1e100];
                          default -1, 4 */
    size_t points;     /* evenly spaced, both ends included; default 601 */
} bkf_friction_spec;

bkf_friction_spec bkf_friction_spec_default(void);

/* The keys: from, to, points. */
extern const bkf_option bkf_friction_options[];
extern const size_t bkf_friction_noptions;

int bkf_friction_check(const bkf_friction_spec *spec, const char *prefix, bkf_error *err);

typedef struct {
    double v, psi, creep_slip, carlson_langer;
} bkf_friction_row;

/* The row at velocity v. */
bkf_friction_row bkf_friction_at(double v);

/* The table of spec->points rows to `out`.  provenance NULL: the comment
 * describes the laws alone (no program, no command). */
int bkf_friction_table(const bkf_friction_spec *spec, FILE *out, bkf_io_format format,
                       const bkf_provenance *provenance, bkf_error *err);

#ifdef __cplusplus
}
#endif

#endif

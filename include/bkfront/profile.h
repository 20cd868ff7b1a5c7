/* The profile product: the shape of a front, f(z) and f'(z) over one period
 * of the limit cycle of f'' + mu (f^2 - 1) f' + f = nu (z = 0 where f = nu
 * rising), at the predicted speed of n fronts (one speeds solve serves every
 * n) or at a given mu (`bkfront profile`).
 *
 * For n fronts the position along the system is also given:
 * psi(x, t) = f((x/v + t)/stretch), stretch = sqrt(1 - c^2/v^2), so at t = 0
 * the wave spans x = z v stretch (bkf_profile_x), one wavelength S/n per
 * period.
 *
 * Rows: `points` samples per period at z = T i / points, i = 0 .. points - 1
 * (z = T would repeat z = 0). */
#ifndef BKFRONT_PROFILE_H
#define BKFRONT_PROFILE_H

#include <stddef.h>
#include <stdio.h>
#include "bkfront/io.h"
#include "bkfront/model.h"
#include "bkfront/options.h"
#include "bkfront/status.h"

#ifdef __cplusplus
extern "C" {
#endif

#define BKF_PROFILE_MAX_POINTS 100000u
#define BKF_PROFILE_MAX_N 100000u
#define BKF_PROFILE_MAX_LIST 1000u

typedef struct {
    bkf_model_params params; /* gamma, c, S: NaN until given; nu required */
    bkf_list n;              /* numbers of fronts; empty with mu */
    size_t root;             /* which root of each n, 1 the fastest; 0: not given (1) */
    double mu;               /* NaN: from the model; else the cycle at this mu */
    size_t points;           /* samples per period; default 2000 */
    double tol;              /* default 1e-10 */
} bkf_profile_spec;

bkf_profile_spec bkf_profile_spec_default(void);
void bkf_profile_spec_free(bkf_profile_spec *spec);

/* The keys: gamma, c, nu, S, n, root, mu, points, tol. */
extern const bkf_option bkf_profile_options[];
extern const size_t bkf_profile_noptions;

/* Either mu or the whole model (gamma, c, S, n), and what speeds needs. */
int bkf_profile_check(const bkf_profile_spec *spec, const char *prefix, bkf_error *err);

/* x = z v sqrt(1 - c^2/v^2) (no stretch at c = 0): the position along the
 * system at t = 0 of the point z of a front moving at v. */
double bkf_profile_x(double z, double v, double c);

/* The whole table (columns n, root, v, mu, T, z, x, f, fprime) to `out`. */
int bkf_profile_write(const bkf_profile_spec *spec, FILE *out, bkf_io_format format,
                      const bkf_provenance *provenance, bkf_error *err);

#ifdef __cplusplus
}
#endif

#endif

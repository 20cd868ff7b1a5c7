/* Helpers shared by the simulator's tests: allocation that fails the test
 * with the library's message, and a measurement fed by a run's observer. */
#ifndef BKF_TEST_PDE_SUPPORT_H
#define BKF_TEST_PDE_SUPPORT_H

#include "bkfront/measure.h"
#include "bkfront/pde.h"
#include "harness.h"

static inline bkf_pde *alloc_pde(const bkf_model_params *params, const bkf_pde_options *options)
{
    bkf_error e;
    bkf_pde *m = bkf_pde_alloc(params, options, &e);
    CHECK_MSG(m, "alloc: %s", e.message);
    return m;
}

/* Observer: every sample into the bkf_measure passed as data. */
static inline int measure_sample(const bkf_pde_sample *s, void *data)
{
    bkf_error e;
    CHECK_MSG(bkf_measure_add(data, s->t, s->psi, s->eta, &e) == BKF_OK, "%s", e.message);
    return 0;
}

/* A measurement on the run's grid and model; reference may be NULL. */
static inline bkf_measure *make_measure(const bkf_pde *m, const double *reference)
{
    const bkf_model_params *pp = bkf_pde_get_params(m);
    bkf_measure_params mp = bkf_measure_params_default();
    mp.model = *pp;
    mp.level = pp->nu; /* the tests' fronts: crossings of nu */
    mp.reference = reference;
    bkf_error e;
    bkf_measure *ms = bkf_measure_alloc(&mp, &e);
    CHECK_MSG(ms, "%s", e.message);
    return ms;
}

#endif

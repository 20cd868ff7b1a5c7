/* A cycle result's T against the long-double Taylor reference
 * (taylor_reference.h), the check most engine tests make. */
#ifndef BKF_TEST_TAYLOR_CHECK_H
#define BKF_TEST_TAYLOR_CHECK_H

#include "harness.h"

#include "bkfront/cycle.h"

#include "taylor_reference.h"

/* r within tol of the reference (solved from r's section slope the first
 * time, *ref NAN, and kept in *ref, *unc for the point's other results),
 * its estimate optimistic by at most bound; returns true/estimated. */
static inline double check_against_taylor(const bkf_cycle_result *r, double tol, double bound, double *ref,
                                          double *unc)
{
    if (!isfinite(*ref)) *ref = taylor_period(r->mu, r->nu, r->section_slope, unc);
    double err = fabs(r->period - *ref), ratio = fmax(err - *unc, 0.0) / r->period_err;
    CHECK_MSG(err <= tol * r->period + *unc, "mu %g nu %g tol %g %s: error %.3g > tol", r->mu, r->nu, tol, r->stepper,
              err / r->period);
    CHECK_MSG(ratio <= bound, "mu %g nu %g tol %g %s: estimate %.3g optimistic by %.3g", r->mu, r->nu, tol,
              r->stepper, r->period_err / r->period, ratio);
    return ratio;
}

#endif

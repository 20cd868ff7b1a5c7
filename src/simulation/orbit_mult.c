/* Floquet multipliers of a solved orbit (placeholder until ARPACK). */
#include "orbit_internal.h"

int orbit_mult_run(bkf_orbit *ob, const bkf_orbit_mult_options *o, bkf_orbit_spectrum *sp,
                   bkf_error *err)
{
    (void)ob, (void)o, (void)sp;
    return bkf_error_set(err, BKF_ENUMERIC, "not yet");
}

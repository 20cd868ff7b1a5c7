/* Helpers shared by the train spectrum's tests. */
#ifndef BKF_TEST_TRAINSPEC_SUPPORT_H
#define BKF_TEST_TRAINSPEC_SUPPORT_H

#include <math.h>
#include <stddef.h>

#include "bkfront/trainspec.h"

/* The reported rightmost of class j (the translation aside), or -inf. */
static inline double class_top(const bkf_trainspec_result *r, size_t j, double *err)
{
    double top = -INFINITY;
    for (size_t k = 0; k < r->count; k++) {
        const bkf_trainspec_eigenvalue *e = &r->eigenvalues[k];
        if (e->j != j || e->translation || !(e->re > top)) continue;
        top = e->re;
        *err = e->err;
    }
    return top;
}

#endif

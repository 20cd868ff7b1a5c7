/* Benchmark of the periodic-orbit solver: CPU seconds (one core) of the
 * global oscillation as an orbit at the paper's parameters (gamma 2, c 0.3,
 * nu -0.96, S 20) to tol 1e-8, and of its ten leading multipliers, at two
 * grids.  Goals (issue 34): the orbit under 10 s, ten multipliers under 5 s. */
#define _POSIX_C_SOURCE 200809L
#include "bkfront/orbit.h"
#include "bkfront/pde.h"
#include "bkfront/floquet.h"
#include "bench_util.h"

#include <stdio.h>
#include <time.h>

void bench_orbit(void);

static double cpu_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void bench_orbit(void)
{
    printf("## orbit: the global oscillation as a periodic orbit, paper's parameters, "
           "tol 1e-8, CPU seconds (one core)\n\n");
    printf("| N | orbit | estimate | Newton / Jv | 10 multipliers | monodromy products | "
           "largest |m| |\n");
    printf("|---:|---:|---:|---:|---:|---:|---:|\n");
    const size_t Ns[] = {128, 512};
    for (size_t k = 0; k < 2; k++) {
        bkf_model_params p = {2, 0.3, -0.96, 20, Ns[k], BKF_MODEL_CONTINUUM};
        bkf_error e;
        bkf_floquet *fq = bkf_floquet_alloc();
        bkf_pde *m = bkf_pde_alloc(&p, NULL, &e);
        bkf_orbit_options o = bkf_orbit_options_default();
        o.tol = 1e-8;
        bkf_orbit *ob = bkf_orbit_alloc(&p, &o, &e);
        if (!fq || !m || !ob || bkf_floquet_set(fq, 2, 0.3, -0.96, NULL, &e) ||
            bkf_pde_init_oscillation(m, 0, 0.0, &e)) {
            printf("| %zu | failed: %s |\n", Ns[k], e.message);
        } else {
            bkf_orbit_guess g = {bkf_pde_psi(m), bkf_pde_eta(m),
                                 1.01 * bkf_floquet_cycle(fq)->period, 0.0};
            bkf_orbit_result r;
            double t0 = cpu_seconds();
            int s = bkf_orbit_solve(ob, &g, &r, &e);
            double t1 = cpu_seconds();
            bkf_orbit_spectrum sp;
            int s2 = s ? s : bkf_orbit_multipliers(ob, NULL, &sp, &e);
            double t2 = cpu_seconds();
            if (s || s2) printf("| %zu | failed: %s |\n", Ns[k], e.message);
            else
                printf("| %zu | %.2f s | %.1e | %zu / %zu | %.2f s | %zu | %.6f |\n", Ns[k],
                       t1 - t0, r.err, r.newton_iterations, r.jv_products, t2 - t1, sp.matvecs,
                       sp.largest_abs);
        }
        fflush(stdout);
        bkf_orbit_free(ob);
        bkf_pde_free(m);
        bkf_floquet_free(fq);
    }
    printf("\n");
}

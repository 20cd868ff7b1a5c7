/* Internal to the Floquet stability (src/stability/floquet.c,
 * floquet_peaks.c, floquet_threshold.c): the object's layout, the
 * constants and the pieces the files share.  Dependencies point one way:
 * floquet_threshold.c -> floquet_peaks.c -> floquet.c.  Not installed,
 * not part of the API. */
#ifndef BKFRONT_FLOQUET_INTERNAL_H
#define BKFRONT_FLOQUET_INTERNAL_H

#include <gsl/gsl_odeiv2.h>
#include <math.h>
#include <stddef.h>

#include "bkfront/cycle.h"
#include "bkfront/floquet.h"

/* State layout: M is stored by columns, column j = (d_psi, d_eta) from the
 * unit start vector e_j; P = dM/dK the same way. */
enum { IX = 0, IY = 1, IM = 2, IL = 6, IP = 7 };
enum { DIM_PLAIN = 7, DIM_DK = 11 };

/* As in cycle.c: above this gamma the explicit stepper's step is limited by
 * stability, not accuracy. */
#define STIFF_GAMMA 30.0
#define TOL_RATIO 10.0
/* Beyond K ~ 1e8 a period holds ~1e4 oscillations of the perturbation: the
 * integration is no longer a sensible way to get the answer. */
#define K_MAX 1e8
#define MAX_STEPS 5000000
#define MAX_PEAKS 64
/* Grid peaks lower than this are not refined: a refined peak rises above
 * its grid value by far less than this on any grid fine enough to see it. */
#define PEAK_FLOOR (-1.0)
/* Scans only locate peaks, refined afterwards, so they run loose. */
#define SCAN_TOL 1e-7
/* Retries of a wavenumber whose estimate misses tol (bkf_floquet_eval). */
#define RETRY_TOL_MIN 1e-13
#define CYCLE_TOL_MIN 1e-13
#define RETRY_WORK 30.0
#define RETRY_STEPS_MIN 50000.0
#define LOG_RETRY_GROWTH 10.0

typedef struct {
    double gamma, nu, K;
    size_t rhs_calls;
} lin_params;

/* One integration at one tolerance: the GSL driver is kept between
 * wavenumbers, so its step-size guess carries over. */
typedef struct {
    gsl_odeiv2_driver *driver;
    gsl_odeiv2_system system;
    double tol;
} engine;

/* Slots of the trace integration: the scan, the two tolerances of the
 * estimate, and the two of a retry at a tighter tolerance.  Separate slots
 * for the retry keep the usual drivers (and their step-size guesses) when
 * one wavenumber needs more. */
enum { ENG_SCAN = 0, ENG_COARSE = 1, ENG_FINE = 2, ENG_RETRY_COARSE = 3, ENG_RETRY_FINE = 4, ENG_SLOTS = 5 };

typedef struct {
    double M[4];      /* row-major */
    double tr, L, det;
    double dtr;       /* d trace / dK (with dk) */
    size_t steps;
} raw;

struct bkf_floquet {
    double gamma, c, nu;
    bkf_floquet_options opt;
    bkf_cycle *cycle;
    int ready;
    double x0, y0, T, T_err, L;
    lin_params lp;
    bkf_stepper_kind kind;
    engine eng[2][ENG_SLOTS]; /* [with dM/dK][slot] */
    engine eng_log[2];        /* log-column integrations, [coarse, fine] */
    double tol_int;           /* coarse integration tolerance; fine = /TOL_RATIO */
    double tol_floor;         /* tightest coarse tolerance worth a retry */
    double tol_retry;         /* tolerance of the retry slots */
    size_t retry_nmax;        /* step budget of one retry integration */
    size_t log_fine_steps;    /* steps of this wavenumber's last finer log integration (0: none) */
    bkf_cycle_options cycle_opt; /* of the cycle solved last */
    double refused_tol;          /* a tighter cycle refused since the set (0: none) */
    unsigned cycle_gen;          /* counts the cycles solved */
    /* The finer integration of the last eval_trace: a retry 10 times
     * tighter than that attempt integrates at exactly its tolerance, so
     * it takes it as its coarser half instead of repeating it. */
    struct {
        double K, tol;
        unsigned cycle_gen;
        int valid;
    } last_fine_key;
    raw last_fine;
    /* The cycle 100 times looser (cycle_measured), kept while cycle_gen
     * stays loose_gen. */
    double loose_tol;
    unsigned loose_gen;
    double loose_y0, loose_T, loose_T_err, loose_L;
};

typedef struct {
    double m1_re, m1_im, m2_re, m2_im, lambda;
    bkf_floquet_kind kind;
    double m1_abs_scaled;   /* |m1| / e^s (see multipliers_scaled) */
} mults;

typedef struct {
    double K, lambda, lambda_err, m_re, m_im;
    double sign;
    int region;      /* sign region of the trace counted from K = 1 */
} peak;

typedef struct {
    bkf_floquet_stability s;
    peak peaks[MAX_PEAKS];
    size_t npeaks;   /* refined peaks (region-0 band peak excluded when a > 0) */
} stability_full;

/* floquet.c */
int floquet_check_options(const bkf_floquet_options *o, bkf_error *err);
int floquet_check_gamma_c(double gamma, double c, bkf_error *err);
mults floquet_multipliers_scaled(double trt, double L, double s);
int floquet_integrate(bkf_floquet *f, double K, int dk, int which, raw *out, bkf_error *err);
int floquet_eval_k2(bkf_floquet *f, double K, bkf_floquet_point *pt, bkf_error *err);
int floquet_longwave_at(bkf_floquet *f, int which, double *a, bkf_error *err);

/* floquet_peaks.c */
int floquet_track_peak(bkf_floquet *f, double sign, double *K, double w, double *value,
                       bkf_error *err);
int floquet_stability_scan(bkf_floquet *f, stability_full *sf, bkf_error *err);
static inline mults multipliers(double tr, double L) { return floquet_multipliers_scaled(tr, L, 0.0); }
static inline double dk_of_p(double p, double dp) { return fmax(2.0 * p * dp, dp * dp); }

#endif

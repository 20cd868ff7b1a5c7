/* The model's parameters, their validation and the friction law.
 *
 * Dimensionless continuum Burridge-Knopoff model (docs/numerics.md):
 *   psi_t = gamma (eta - phi(psi)),  eta_t = -(psi - nu - c^2 psi_xx)/gamma,
 * phi(psi) = psi^3/3 - psi.  The active range, where the uniform slip psi = nu
 * is unstable and a limit cycle exists, is |nu| < 1. */
#ifndef BKFRONT_MODEL_H
#define BKFRONT_MODEL_H

#include <stddef.h>
#include "bkfront/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Which medium: the continuum (spectral in x) or the Burridge-Knopoff chain
 * of N blocks, Eq. (1) of the paper, spacing h = S/N. */
typedef enum { BKF_MODEL_CONTINUUM = 0, BKF_MODEL_CHAIN = 1 } bkf_model_kind;

/* The one parameter set every module takes (each checks the ranges its own
 * problem needs: a limit cycle needs |nu| < 1, a simulation does not). */
typedef struct {
    double gamma;        /* friction strength, > 0 */
    double c;            /* sound speed, >= 0 */
    double nu;           /* pulling rate */
    double S;            /* system size, > 0 */
    size_t N;            /* grid points or blocks; 0 where a module needs none */
    bkf_model_kind kind; /* continuum or chain */
} bkf_model_params;

/* The paper's parameters (gamma 2, c 0.3, nu -0.96, S 20, continuum, N 512):
 * every command's default for the model parameters it does not vary. */
#define BKF_PAPER_GAMMA 2
#define BKF_PAPER_C 0.3
#define BKF_PAPER_NU -0.96
#define BKF_PAPER_S 20
/* A macro's value as text ("2"): the option tables' shown defaults. */
#define BKF_TEXT_OF(x) BKF_TEXT_OF_(x)
#define BKF_TEXT_OF_(x) #x
bkf_model_params bkf_model_params_paper(void);

/* Each of *gamma, *c, *nu, *S (a NULL is skipped) that is NaN (not given)
 * becomes the paper's value. */
void bkf_model_paper_where_unset(double *gamma, double *c, double *nu, double *S);

/* Creep-slip friction phi(psi) = psi^3/3 - psi and its slope. */
double bkf_model_friction(double psi);
double bkf_model_friction_slope(double psi);

/* Carlson-Langer velocity-weakening law F0 sgn(v)/(1+|v|), with F0 = 1, for
 * comparison figures. */
double bkf_model_friction_carlson_langer(double v);

/* Validators: BKF_OK or BKF_EINPUT with a message naming the parameter and its
 * valid range.  NaN and infinities are always rejected. */
int bkf_model_check_nu_active(double nu, bkf_error *err);   /* |nu| < 1 */
int bkf_model_check_positive(const char *name, double value, bkf_error *err);
int bkf_model_check_nonnegative(const char *name, double value, bkf_error *err);
int bkf_model_check_tol(double tol, bkf_error *err);        /* [1e-14, 1e-1] */
int bkf_model_check_c(double c, bkf_error *err);            /* [0, BKF_MODEL_C_MAX] */

#define BKF_TOL_MIN 1e-14
#define BKF_TOL_MAX 1e-1

/* The largest sound speed a product takes: beyond it k(nu) c gamma, c^2 q^2
 * and c/v leave double's range or its precision (at c = 1e308 a Floquet
 * threshold's q_c came out subnormal, 8.7e-309, with digits lost), and no
 * physics of the model lies there (c of order 1). */
#define BKF_MODEL_C_MAX 1e6

#ifdef __cplusplus
}
#endif

#endif

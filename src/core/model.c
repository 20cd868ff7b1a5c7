#include "bkfront/model.h"

#include <math.h>

bkf_model_params bkf_model_params_paper(void)
{
    return (bkf_model_params){.gamma = BKF_PAPER_GAMMA, .c = BKF_PAPER_C, .nu = BKF_PAPER_NU,
                              .S = BKF_PAPER_S, .kind = BKF_MODEL_CONTINUUM, .N = 512};
}

void bkf_model_paper_where_unset(double *gamma, double *c, double *nu, double *S)
{
    if (gamma && isnan(*gamma)) *gamma = BKF_PAPER_GAMMA;
    if (c && isnan(*c)) *c = BKF_PAPER_C;
    if (nu && isnan(*nu)) *nu = BKF_PAPER_NU;
    if (S && isnan(*S)) *S = BKF_PAPER_S;
}

double bkf_model_friction(double psi) { return psi * psi * psi / 3.0 - psi; }

double bkf_model_friction_slope(double psi) { return psi * psi - 1.0; }

double bkf_model_friction_carlson_langer(double v)
{
    if (v == 0.0) return 0.0;
    return (v > 0 ? 1.0 : -1.0) / (1.0 + fabs(v));
}

int bkf_model_check_nu_active(double nu, bkf_error *err)
{
    if (!isfinite(nu))
        return bkf_error_set(err, BKF_EINPUT, "nu must be a finite number in (-1, 1)");
    if (fabs(nu) >= 1.0)
        return bkf_error_set(err, BKF_EINPUT,
                             "nu = %.17g is outside (-1, 1): there is no limit cycle, "
                             "uniform continuous slip psi = nu is stable", nu);
    return BKF_OK;
}

int bkf_model_check_positive(const char *name, double value, bkf_error *err)
{
    if (!isfinite(value) || value <= 0.0)
        return bkf_error_set(err, BKF_EINPUT, "%s = %g must be a finite number > 0",
                             name, value);
    return BKF_OK;
}

int bkf_model_check_nonnegative(const char *name, double value, bkf_error *err)
{
    if (!isfinite(value) || value < 0.0)
        return bkf_error_set(err, BKF_EINPUT, "%s = %g must be a finite number >= 0",
                             name, value);
    return BKF_OK;
}

int bkf_model_check_c(double c, bkf_error *err)
{
    if (!(c >= 0.0 && c <= BKF_MODEL_C_MAX))
        return bkf_error_set(err, BKF_EINPUT, "c = %g is outside [0, %g]", c, BKF_MODEL_C_MAX);
    return BKF_OK;
}

int bkf_model_check_tol(double tol, bkf_error *err)
{
    if (!isfinite(tol) || tol < BKF_TOL_MIN || tol > BKF_TOL_MAX)
        return bkf_error_set(err, BKF_EINPUT, "tol = %g is outside [%g, %g]", tol,
                             BKF_TOL_MIN, BKF_TOL_MAX);
    return BKF_OK;
}

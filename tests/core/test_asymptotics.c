/* Closed-form checks of the asymptotic formulas themselves. */
#include "harness.h"

#include "bkfront/asymptotics.h"

TEST(asym_k_closed_forms)
{
    CHECK_CLOSE(bkf_asym_k(0.0), 3.0 - 2.0 * log(2.0), 1e-15, 0.0);
    CHECK_CLOSE(bkf_asym_k(0.5), bkf_asym_k(-0.5), 1e-15, 0.0);
    /* k -> 3 as |nu| -> 1: the slow branches shrink to the knees' neighbourhood */
    CHECK_CLOSE(bkf_asym_k(1.0 - 1e-9), 3.0, 1e-7, 0.0);
    /* slow-branch integrals done by quadrature (Simpson, 2000 panels) */
    double nu = -0.37, sum = 0.0;
    int n = 2000;
    for (int branch = 0; branch < 2; branch++) {
        double a = branch ? -2.0 : 1.0, b = branch ? -1.0 : 2.0, h = (b - a) / n;
        for (int i = 0; i <= n; i++) {
            double x = a + i * h, w = (i == 0 || i == n) ? 1 : (i % 2 ? 4 : 2);
            sum += w * (x * x - 1.0) / fabs(nu - x) * h / 3.0;
        }
    }
    CHECK_CLOSE(bkf_asym_k(nu), sum, 1e-10, 0.0);
}

TEST(asym_correction_coefficients_at_nu_0)
{
    CHECK_CLOSE(bkf_asym_knee_coefficient(0.0), 3.0 * BKF_AIRY_A1, 1e-15, 0.0);
    CHECK_CLOSE(bkf_asym_log_coefficient(0.0), -2.0 / 3.0, 1e-15, 0.0);
    CHECK_CLOSE(bkf_asym_small_coefficient(0.0), 1.0 / 16.0, 1e-15, 0.0);
    CHECK_CLOSE(bkf_asym_knee_coefficient(0.4), bkf_asym_knee_coefficient(-0.4), 1e-15, 0.0);
}

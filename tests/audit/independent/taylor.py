"""High-accuracy arbiter for T(mu, nu): Taylor-series integration (order 30, long double) of the
Lienard system x' = mu (y - x^3/3 + x), y' = (nu - x)/mu, coefficients by the exact recurrences of
the polynomial right-hand side; the section crossing x = nu (upward) by Newton on the step's
polynomial; the periodic orbit by secant on the return map.  Used where vdp2 (LSODA) and bkfront
disagree beyond both error estimates.  Independent of bkfront's code.
"""
import numpy as np

LD = np.longdouble


def coeffs(x0, y0, mu, nu, K):
    x = np.zeros(K + 1, LD)
    y = np.zeros(K + 1, LD)
    p = np.zeros(K + 1, LD)
    q = np.zeros(K + 1, LD)
    x[0], y[0] = x0, y0
    for k in range(K):
        p[k] = np.dot(x[:k + 1], x[k::-1])
        q[k] = np.dot(p[:k + 1], x[k::-1])
        x[k + 1] = mu * (y[k] - q[k] / 3 + x[k]) / (k + 1)
        y[k + 1] = ((nu if k == 0 else 0) - x[k]) / (mu * (k + 1))
    return x, y


def horner(a, t):
    s = LD(0)
    for c in a[::-1]:
        s = s * t + c
    return s


def ret(y0, mu, nu, K=30, eps=LD(1e-20)):
    mu, nu = LD(mu), LD(nu)
    x, y, t = LD(nu), LD(y0), LD(0)
    went_down = False
    for step in range(10 ** 7):
        cx, cy = coeffs(x, y, mu, nu, K)
        sc = max(LD(1), abs(x), abs(y))
        r1 = (eps * sc / max(abs(cx[K]), abs(cy[K]) * mu, LD(1e-300))) ** (LD(1) / K)
        r2 = (eps * sc / max(abs(cx[K - 1]), abs(cy[K - 1]) * mu, LD(1e-300))) ** (LD(1) / (K - 1))
        h = min(r1, r2)
        xn = horner(cx, h)
        if went_down and xn >= nu:
            # crossing inside [0, h]: Newton from bisection bracket
            a, b = LD(0), h
            dcx = cx[1:] * np.arange(1, K + 1, dtype=LD)
            tau = h / 2
            for it in range(200):
                fa = horner(cx, tau) - nu
                if fa < 0:
                    a = tau
                else:
                    b = tau
                d = horner(dcx, tau)
                tn = tau - fa / d if d != 0 else (a + b) / 2
                if not (a < tn < b):
                    tn = (a + b) / 2
                if abs(tn - tau) < LD(1e-21) * max(LD(1), h):
                    tau = tn
                    break
                tau = tn
            return horner(cy, tau), t + tau
        if xn < nu:
            went_down = True
        x, y, t = xn, horner(cy, h), t + h
    raise RuntimeError("no return")


def period_taylor(mu, nu, y0):
    """T and an error estimate (difference from a run with a 1e4 times looser step criterion)."""
    def fixed(eps):
        yp = LD(y0)
        gp = ret(yp, mu, nu, eps=eps)[0] - yp
        y = yp + gp
        T = None
        for it in range(30):
            y1, T = ret(y, mu, nu, eps=eps)
            g = y1 - y
            if g == gp or abs(g) < LD(1e-19):
                break
            yn = y - g * (y - yp) / (g - gp)
            yp, gp, y = y, g, yn
            if abs(y - yp) < LD(1e-19):
                y1, T = ret(y, mu, nu, eps=eps)
                break
        return T, y
    T1, y = fixed(LD(1e-20))
    T2, _ = fixed(LD(1e-16))
    return float(T1), float(abs(T1 - T2)) + 1e-16 * float(T1)


if __name__ == "__main__":
    import time
    from vdp2 import Cycle
    for mu, nu in [(1, 0), (2.344, -0.919701), (26.5841, -0.919701), (5, 0)]:
        t0 = time.time()
        c = Cycle(mu, nu, 1e-12)
        print(mu, nu, period_taylor(mu, nu, c.y0), c.T, "%.1fs" % (time.time() - t0))

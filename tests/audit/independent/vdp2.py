"""Independent period T(mu, nu) of f'' + mu (f^2 - 1) f' + f = nu (no bkfront code).

Poincare section x = nu (x increasing).  One return: LSODA (scipy odeint, Fortran) over a time
grid until x - nu changes sign upward after having gone down; the exact crossing by Henon's
trick (x as the independent variable: dt/dx = 1/x', dy/dx = y'/x') from the last grid point.
Fixed point of the return map: fixed-point iterations then secant.
Coordinates: (x, x') for mu <= 3, Lienard x' = mu (y - F(x)), y' = (nu - x)/mu above.
"""
import numpy as np
from scipy.integrate import odeint


def Fl(x):
    return x ** 3 / 3 - x


class Cycle:
    def __init__(self, mu, nu, rtol=1e-13, y0=None, Test=None):
        self.Test = Test
        self.mu, self.nu, self.rtol = float(mu), float(nu), rtol
        self.lienard = mu > 3.0
        self.nfev = 0
        self._solve(y0)

    def f(self, u, t):
        mu, nu = self.mu, self.nu
        x, y = u
        if self.lienard:
            return [mu * (y - Fl(x)), (nu - x) / mu]
        return [y, nu - x - mu * (x * x - 1) * y]

    def jac(self, u, t):
        mu = self.mu
        x, y = u
        if self.lienard:
            return [[-mu * (x * x - 1), mu], [-1 / mu, 0.0]]
        return [[0.0, 1.0], [-1 - 2 * mu * x * y, -mu * (x * x - 1)]]

    def henon(self, u, t):
        # dt/dx, dy/dx with x as independent variable; state (t, y), "time" = x
        xdot, ydot = self.f(u, 0)
        return xdot, ydot

    def _to_section(self, x0, y0, t0):
        def g(s, x):
            xd, yd = self.f([x, s[1]], 0)
            return [1.0 / xd, yd / xd]
        out = odeint(g, [t0, y0], [x0, self.nu], rtol=self.rtol, atol=self.rtol * 1e-3, mxstep=100000)
        return out[-1, 0], out[-1, 1]

    def ret(self, y0):
        mu, nu = self.mu, self.nu
        Tguess = getattr(self, "Test", None)
        if Tguess is None:
            Tguess = 3.0 * (3.0 * mu + 2 * np.pi + 5)
        npts = 600
        tmax = 1.25 * Tguess
        ts = np.linspace(0, tmax, npts + 1)
        sol = odeint(self.f, [nu, y0], ts, Dfun=self.jac, rtol=self.rtol, atol=self.rtol * 1e-3,
                     mxstep=10 ** 7)
        x = sol[:, 0] - nu
        if not (np.any(x < 0) and np.any(x[np.argmax(x < 0):] >= 0)):
            self.Test = None
            ts = np.linspace(0, 3 * (3.0 * mu + 2 * np.pi + 5), 4001)
            sol = odeint(self.f, [nu, y0], ts, Dfun=self.jac, rtol=self.rtol, atol=self.rtol * 1e-3,
                         mxstep=10 ** 7)
            x = sol[:, 0] - nu
        # first index where x < 0 (gone down), then the first after that with x >= 0
        down = np.nonzero(x < 0)[0]
        if down.size == 0:
            raise RuntimeError("never went down")
        i0 = down[0]
        up = np.nonzero(x[i0:] >= 0)[0]
        if up.size == 0:
            raise RuntimeError("no return")
        k = i0 + up[0] - 1  # last grid point with x < 0
        t, y = self._to_section(sol[k, 0], sol[k, 1], ts[k])
        self.Test = t
        return y, t

    def _solve(self, y0):
        mu, nu = self.mu, self.nu
        if y0 is None:
            y0 = (2.0 / 3.0 + 0.3) if self.lienard else 2.0 * np.sqrt(max(1 - nu * nu, 1e-4))
        y = y0
        for it in range(8):
            y1, T = self.ret(y)
            if abs(y1 - y) < 1e-4 * max(1, abs(y)):
                y = y1
                break
            y = y1
        yp = y
        gp = self.ret(yp)[0] - yp
        y = yp + gp
        if gp == 0:
            y = yp * (1 + 1e-9) + 1e-12
        T = None
        for it in range(40):
            y1, T = self.ret(y)
            g = y1 - y
            if g == gp or abs(g) <= 2e-16 * max(1, abs(y)):
                break
            yn = y - g * (y - yp) / (g - gp)
            if abs(yn - y) <= 1e-15 * max(1, abs(y)):
                y = yn
                y1, T = self.ret(y)
                break
            yp, gp, y = y, g, yn
        self.y0, self.T, self.resid = y, T, y1 - y

    def profile(self, N):
        """f(z_k), z_k = k T / N, k = 0..N-1 (z = 0 on the upward section)."""
        ts = np.linspace(0, self.T, N + 1)
        sol = odeint(self.f, [self.nu, self.y0], ts, Dfun=self.jac, rtol=self.rtol,
                     atol=self.rtol * 1e-3, mxstep=10 ** 7)
        return sol[:-1, 0]


def period(mu, nu, rtol=1e-13):
    return Cycle(mu, nu, rtol).T


def period_err(mu, nu):
    """T at rtol 1e-13 and the difference from rtol 1e-11 as the error estimate."""
    a = Cycle(mu, nu, 1e-13)
    b = Cycle(mu, nu, 1e-11, y0=a.y0, Test=a.T)
    return a.T, abs(a.T - b.T)


if __name__ == "__main__":
    import time
    for mu, nu in [(1, 0), (0.5, 0), (5, 0), (2, -0.96), (47.07, -0.96), (1000, 0.3), (0.3, 0.98),
                   (0.3, 0), (2, 0.99), (1e4, -0.5)]:
        t0 = time.time()
        a, e = period_err(mu, nu)
        print(mu, nu, repr(a), e, "%.2fs" % (time.time() - t0))

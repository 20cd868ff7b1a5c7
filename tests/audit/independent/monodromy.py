"""Train spectrum by the monodromy over one wavelength (route A of part 2; no bkfront code).

DESIGN.md's linearisation in the frame xi = x + v t,
    sigma p + v p' = gamma (q - (F^2 - 1) p),   sigma q + v q' = -(p - c^2 p'')/gamma,
is second order in p and first in q, but w = v q - (c^2/gamma) p' turns it into a first-order
2 x 2 system without p'' or F' (beta = v - c^2/v > 0 since fronts are supersonic, a = F^2 - 1):
    p' = gamma w/(v beta) - (gamma a + sigma) p/beta
    w' = -p/gamma - sigma w/beta + sigma c^2 (gamma a + sigma) p/(gamma v beta)
(w is p, q times L-periodic coefficients, so the Bloch multipliers are those of (p, q)).
F(xi) = f(xi T/L), f the cycle of f'' + mu (f^2 - 1) f' + f = nu, is integrated with the 2 x 2
fundamental matrix in one stiff solve (scipy's Radau, complex, analytic Jacobian), from the
point of vdp2.Cycle's Poincare section.  sigma is an eigenvalue of Bloch class j (kappa L =
2 pi j/n) iff D_j(sigma) = det(M(sigma) - e^{2 pi i j/n} I) = 0.

The decaying multiplier is about exp(-mu T <F^2 - 1>) (e^-80 at mu 7), so M is nearly rank one
and D is well conditioned near a root: no cancellation between huge entries.
"""
import numpy as np
from scipy.integrate import solve_ivp
from vdp2 import Cycle, Fl


class Train:
    def __init__(self, gamma, c, nu, S, n, v, mu, cyc=None):
        self.gamma, self.c, self.nu, self.S, self.n, self.v, self.mu = gamma, c, nu, S, n, v, mu
        self.cyc = cyc or Cycle(mu, nu, 1e-13)
        self.T = self.cyc.T
        self.L = S / n
        self.beta = v - c * c / v
        self.nfev = 0

    def _rhs(self, sigma):
        # real form for scipy's Radau (no complex support in scipy 1.10):
        # u = (x, y, Re Phi (2 x 2, row-major), Im Phi)
        g, c, v, b, mu, nu = self.gamma, self.c, self.v, self.beta, self.mu, self.nu
        s = self.T / self.L  # dz/dxi
        lien = self.cyc.lienard
        I2 = np.eye(2)

        def Amat(x):
            a = x * x - 1
            return np.array([[-(g * a + sigma) / b, g / (v * b)],
                             [-1 / g + sigma * c * c * (g * a + sigma) / (g * v * b), -sigma / b]])

        def f(xi, u):
            x, y = u[0], u[1]
            if lien:
                dx, dy = mu * (y - Fl(x)), (nu - x) / mu
            else:
                dx, dy = y, nu - x - mu * (x * x - 1) * y
            Phi = (u[2:6] + 1j * u[6:10]).reshape(2, 2)
            dP = (Amat(x) @ Phi).ravel()
            return np.concatenate(([s * dx, s * dy], dP.real, dP.imag))

        def jac(xi, u):
            x, y = u[0], u[1]
            J = np.zeros((10, 10))
            if lien:
                J[0, 0], J[0, 1], J[1, 0] = -s * mu * (x * x - 1), s * mu, -s / mu
            else:
                J[0, 1] = s
                J[1, 0], J[1, 1] = s * (-1 - 2 * mu * x * y), -s * mu * (x * x - 1)
            A = Amat(x)
            Ar, Ai = np.kron(A.real, I2), np.kron(A.imag, I2)
            J[2:6, 2:6], J[2:6, 6:10] = Ar, -Ai
            J[6:10, 2:6], J[6:10, 6:10] = Ai, Ar
            Phi = (u[2:6] + 1j * u[6:10]).reshape(2, 2)
            # dA/dx: only A[0,0] and A[1,0] depend on x (through a = x^2 - 1)
            dA00, dA10 = -g * 2 * x / b, sigma * c * c * 2 * x / (v * b)
            col = np.array([dA00 * Phi[0, 0], dA00 * Phi[0, 1], dA10 * Phi[0, 0], dA10 * Phi[0, 1]])
            J[2:6, 0], J[6:10, 0] = col.real, col.imag
            return J
        return f, jac

    def monodromy(self, sigma, rtol=1e-11):
        f, jac = self._rhs(complex(sigma))
        u0 = np.array([self.nu, self.cyc.y0, 1, 0, 0, 1, 0, 0, 0, 0], float)
        r = solve_ivp(f, (0.0, self.L), u0, method="Radau", jac=jac, rtol=rtol, atol=rtol * 1e-3)
        if not r.success:
            raise RuntimeError(r.message)
        self.nfev += 1
        self.last_steps = r.t.size
        return (r.y[2:6, -1] + 1j * r.y[6:10, -1]).reshape(2, 2)

    def D(self, sigma, j, rtol=1e-11):
        lam = np.exp(2j * np.pi * j / self.n)
        return np.linalg.det(self.monodromy(sigma, rtol) - lam * np.eye(2))

    def newton(self, sigma0, j, rtol=1e-11, h=1e-6, maxit=20, tol=1e-12):
        """Secant iterations on D_j from sigma0; returns (sigma, |last step|, iterations)."""
        s0 = complex(sigma0)
        s1 = s0 + h * (1 + 1j)
        d0, d1 = self.D(s0, j, rtol), self.D(s1, j, rtol)
        step = abs(s1 - s0)
        for it in range(maxit):
            if d1 == d0:
                break
            s2 = s1 - d1 * (s1 - s0) / (d1 - d0)
            step = abs(s2 - s1)
            s0, d0, s1 = s1, d1, s2
            d1 = self.D(s1, j, rtol)
            if step < tol * max(1, abs(s1)):
                break
        return s1, step, it + 1, abs(d1)

    def eigenvalue(self, sigma0, j):
        """Root near sigma0 at rtol 1e-10 and 1e-12; error = their difference + the last step."""
        a, sa, ia, da = self.newton(sigma0, j, rtol=1e-10)
        b, sb, ib, db = self.newton(a, j, rtol=1e-12)
        return {"sigma": b, "err": abs(a - b) + sb + 1e-12, "it": ia + ib, "D": db,
                "dist0": abs(b - complex(sigma0))}

    def asymptote(self, N=4096):
        """gamma (1 - <F^2>)/2: the line the short-wave eigenvalues approach (WKB, |sigma| -> inf)."""
        f = self.cyc.profile(N)
        return self.gamma * (1 - np.mean(f * f)) / 2


if __name__ == "__main__":
    import time
    # paper's parameters (gamma 2, c 0.3, nu -0.96, S 20): Hill (hill.py) gives n = 2: 0.0697435 (j = 0),
    # n = 4: -0.0017318853 (complex, j = 1)
    for n, v, mu, s0, j in [(2, 0.8954151211482031, 2.122682880976821, 0.0697, 0),
                            (4, 0.48545916040196629, 2.5438807382090127, -0.00173 - 0.1115j, 1)]:
        t0 = time.time()
        tr = Train(2, 0.3, -0.96, 20, n, v, mu)
        print(n, "D(0) j=0:", abs(tr.D(0, 0)), tr.last_steps, "steps", "%.1fs" % (time.time() - t0))
        print(tr.eigenvalue(s0, j), "%.1fs" % (time.time() - t0))

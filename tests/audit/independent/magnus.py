"""Train spectrum by the monodromy with a 4th-order Magnus integrator (fast route; no bkfront code).

The same 2 x 2 first-order system as monodromy.py (p, w = v q - (c^2/gamma) p'):
    (p, w)' = A(xi; sigma) (p, w),   A = [[-(g a + s)/b, g/(v b)], [-1/g + s c^2 (g a + s)/(g v b), -s/b]]
a = F^2 - 1, b = v - c^2/v.  A is linear in a, so the profile is sampled once per root (LSODA at
rtol 1e-13 at the Gauss points of a grid adapted to F') and each sigma costs numpy work only:
    Omega = h/2 (A1 + A2) + sqrt(3) h^2/12 [A2, A1],  E = exp(Omega) (2 x 2 closed form),
M = E_N ... E_1 by a pairwise product tree.  Exact exponentials keep the stiff decay (rate
gamma a/b, up to ~ mu^2 over a wavelength) stable.  Error: Richardson between N and 2N (order 4).
"""
import numpy as np
from scipy.integrate import odeint
from vdp2 import Cycle


def expm2(O):
    """exp of a stack of 2 x 2 complex matrices (Cayley-Hamilton)."""
    t = 0.5 * (O[:, 0, 0] + O[:, 1, 1])
    B = O.copy()
    B[:, 0, 0] -= t
    B[:, 1, 1] -= t
    d = np.sqrt(B[:, 0, 0] ** 2 + B[:, 0, 1] * B[:, 1, 0])  # B^2 = d^2 I
    small = np.abs(d) < 1e-8
    ds = np.where(small, 1.0, d)
    sh = np.where(small, 1 + d * d / 6 + d ** 4 / 120, np.sinh(ds) / ds)
    ch = np.cosh(d)
    E = sh[:, None, None] * B
    E[:, 0, 0] += ch
    E[:, 1, 1] += ch
    return np.exp(t)[:, None, None] * E


def prodtree(E):
    """E_N ... E_2 E_1 for a stack E[0] = E_1, ..."""
    while E.shape[0] > 1:
        if E.shape[0] % 2:
            E = np.concatenate((E, np.eye(2, dtype=E.dtype)[None]), axis=0)
        E = E[1::2] @ E[0::2]
    return E[0]


class MagnusTrain:
    def __init__(self, gamma, c, nu, S, n, v, mu, N=20000, cyc=None, alpha=None):
        self.gamma, self.c, self.nu, self.S, self.n, self.v, self.mu = gamma, c, nu, S, n, v, mu
        self.cyc = cyc or Cycle(mu, nu, 1e-13)
        self.T = self.cyc.T
        self.L = S / n
        self.beta = v - c * c / v
        self.grids = {}
        self.N = N
        self._monitor()

    def _z(self, zs):
        """f at times zs (increasing, from the section point) by LSODA at rtol 1e-13."""
        cy = self.cyc
        zs = np.concatenate(([0.0], zs))
        sol = odeint(cy.f, [cy.nu, cy.y0], zs, Dfun=cy.jac, rtol=1e-13, atol=1e-16, mxstep=10 ** 7, hmax=0.0)
        return sol[1:, 0]

    def _monitor(self, K=40000):
        # grid density ~ 1 + |F'| scaled so that the jumps get about half of the points
        z = np.linspace(0, self.T, K + 1)
        f = self._z(z[1:])
        f = np.concatenate(([self.nu], f))
        df = np.abs(np.diff(f)) / (z[1] - z[0])
        m = df / df.mean()
        rho = 1 + m
        cum = np.concatenate(([0.0], np.cumsum(rho)))
        self._cum, self._zgrid = cum / cum[-1], z

    def grid(self, N):
        if N not in self.grids:
            u = np.linspace(0, 1, N + 1)
            zn = np.interp(u, self._cum, self._zgrid)
            zn[0], zn[-1] = 0.0, self.T
            xi = zn * self.L / self.T
            h = np.diff(xi)
            g1 = xi[:-1] + h * (0.5 - np.sqrt(3) / 6)
            g2 = xi[:-1] + h * (0.5 + np.sqrt(3) / 6)
            pts = np.empty(2 * N)
            pts[0::2], pts[1::2] = g1, g2
            F = self._z(pts * self.T / self.L)
            self.grids[N] = (h, F[0::2] ** 2 - 1, F[1::2] ** 2 - 1)
        return self.grids[N]

    def _A(self, a, s):
        g, c, v, b = self.gamma, self.c, self.v, self.beta
        A = np.empty((a.size, 2, 2), complex)
        A[:, 0, 0] = -(g * a + s) / b
        A[:, 0, 1] = g / (v * b)
        A[:, 1, 0] = -1 / g + s * c * c * (g * a + s) / (g * v * b)
        A[:, 1, 1] = -s / b
        return A

    def monodromy(self, sigma, N=None):
        N = N or self.N
        h, a1, a2 = self.grid(N)
        A1, A2 = self._A(a1, complex(sigma)), self._A(a2, complex(sigma))
        hh = h[:, None, None]
        O = 0.5 * hh * (A1 + A2) + (np.sqrt(3) / 12) * hh * hh * (A2 @ A1 - A1 @ A2)
        return prodtree(expm2(O))

    def D(self, sigma, j, N=None):
        lam = np.exp(2j * np.pi * j / self.n)
        M = self.monodromy(sigma, N)
        return (M[0, 0] - lam) * (M[1, 1] - lam) - M[0, 1] * M[1, 0]

    def newton(self, sigma0, j, N=None, h=1e-7, maxit=40, tol=1e-13):
        s = complex(sigma0)
        step = np.inf
        for it in range(maxit):
            d = self.D(s, j, N)
            dd = (self.D(s + h, j, N) - self.D(s - h, j, N)) / (2 * h)
            if dd == 0:
                break
            ds = -d / dd
            # damp steps that leave the neighbourhood (stay near the eigenvalue asked about)
            if abs(ds) > 0.1 * max(1.0, abs(s)):
                ds *= 0.1 * max(1.0, abs(s)) / abs(ds)
            s += ds
            step = abs(ds)
            if step < tol * max(1, abs(s)):
                break
        return s, step, it + 1

    def eigenvalue(self, sigma0, j):
        """Root near sigma0 at N and 2N; error = |difference| (Richardson, order 4) + last step."""
        a, sa, ia = self.newton(sigma0, j, self.N)
        b, sb, ib = self.newton(a, j, 2 * self.N)
        err = abs(a - b) / 15 + sb + sa / 15 + 1e-13 * max(1, abs(b))
        return {"sigma": b, "err": err, "diff_N_2N": abs(a - b), "it": ia + ib, "dist0": abs(b - complex(sigma0))}

    def asymptote(self):
        """gamma (1 - <F^2>)/2: the vertical line the short-wave eigenvalues approach."""
        h, a1, a2 = self.grid(self.N)
        return -self.gamma * np.sum(h * (a1 + a2) / 2) / self.L / 2


if __name__ == "__main__":
    import time
    # paper's parameters: Hill (hill.py): n = 4, j = 1: -0.0017318853321588 - 0.1114629739746345i;
    # monodromy.py (Radau): -0.0017318853297835 - 0.1114629739747089i.  n = 2, j = 0: 0.0697435.
    for n, v, mu, s0, j in [(4, 0.48545916040196629, 2.5438807382090127, -0.00173 - 0.1115j, 1),
                            (2, 0.8954151211482031, 2.122682880976821, 0.0697, 0)]:
        t0 = time.time()
        tr = MagnusTrain(2, 0.3, -0.96, 20, n, v, mu)
        print(n, "D(0) j=0:", abs(tr.D(0, 0)), abs(tr.D(0, 0, 2 * tr.N)), "%.1fs" % (time.time() - t0))
        print(tr.eigenvalue(s0, j), "asymptote %.5g" % tr.asymptote(), "%.1fs" % (time.time() - t0))


# ---------------------------------------------------------------------------------------------
# Many sigma at once (for the argument principle): the 2 x 2 algebra written out elementwise on
# arrays of shape (m sigma, N steps), so that a contour of 1e5 points costs seconds, not hours.

def _mul(X, Y):
    return (X[0] * Y[0] + X[1] * Y[2], X[0] * Y[1] + X[1] * Y[3],
            X[2] * Y[0] + X[3] * Y[2], X[2] * Y[1] + X[3] * Y[3])


def _expm(O):
    t = 0.5 * (O[0] + O[3])
    b00, b11 = O[0] - t, O[3] - t
    d = np.sqrt(b00 * b00 + O[1] * O[2])
    small = np.abs(d) < 1e-6
    ds = np.where(small, 1.0, d)
    sh = np.where(small, 1 + d * d / 6 + d ** 4 / 120, np.sinh(ds) / ds)
    ch = np.cosh(d)
    e = np.exp(t)
    return (e * (ch + sh * b00), e * sh * O[1], e * sh * O[2], e * (ch + sh * b11))


def D_many(tr, sigmas, j, N, chunk=64):
    """D_j(sigma) for an array of sigma (MagnusTrain tr, N Magnus steps)."""
    h, a1, a2 = tr.grid(N)
    g, c, v, b = tr.gamma, tr.c, tr.v, tr.beta
    lam = np.exp(2j * np.pi * j / tr.n)
    out = np.empty(len(sigmas), complex)
    sq = np.sqrt(3) / 12
    for k0 in range(0, len(sigmas), chunk):
        s = np.asarray(sigmas[k0:k0 + chunk], complex)[:, None]

        def A(a):
            return (-(g * a + s) / b, np.full(s.shape, g / (v * b), complex) + 0 * a,
                    -1 / g + s * c * c * (g * a + s) / (g * v * b), -s / b + 0 * a)
        X, Y = A(a2[None, :]), A(a1[None, :])  # X = A(xi_2), Y = A(xi_1)
        hh = h[None, :]
        com = (X[1] * Y[2] - Y[1] * X[2],
               X[0] * Y[1] + X[1] * Y[3] - Y[0] * X[1] - Y[1] * X[3],
               X[2] * Y[0] + X[3] * Y[2] - Y[2] * X[0] - Y[3] * X[2],
               X[2] * Y[1] - Y[2] * X[1])
        O = tuple(0.5 * hh * (X[i] + Y[i]) + sq * hh * hh * com[i] for i in range(4))
        E = _expm(O)
        while E[0].shape[1] > 1:
            if E[0].shape[1] % 2:
                one = np.ones((E[0].shape[0], 1), complex)
                zero = np.zeros_like(one)
                E = tuple(np.concatenate((E[i], one if i in (0, 3) else zero), axis=1) for i in range(4))
            E = _mul(tuple(e[:, 1::2] for e in E), tuple(e[:, 0::2] for e in E))
        M = tuple(e[:, 0] for e in E)
        out[k0:k0 + chunk] = (M[0] - lam) * (M[3] - lam) - M[1] * M[2]
    return out


def winding(tr, j, x0, x1, Y0, N, max_rounds=24, dphi=0.5, per_unit=8.0, Y1=None, samples=False):
    """Zeros of D_j in the box [x0, x1] x [Y0, Y1] (Y1 None: [-Y0, Y0]) by the argument principle.
    Samples start at per_unit a unit length and are refined where consecutive phases differ by
    more than dphi; then every interval is halved once more and the count must not change (the
    guard against a phase that turned by 2 pi between two samples).  Right of the short-wave
    asymptote the Bloch multipliers are small and D ~ e^{4 pi i j/n} turns slowly, so few points
    are needed except near zeros.  Returns (count, count after the halving, min |D| on the
    contour relative to its median, samples, intervals left unresolved)."""
    if Y1 is None:
        Y0, Y1 = -Y0, Y0
    corners = [complex(x0, Y0), complex(x1, Y0), complex(x1, Y1), complex(x0, Y1)]
    pts = []
    for k in range(4):
        a, b = corners[k], corners[(k + 1) % 4]
        m = int(max(16, abs(b - a) * per_unit))
        t = np.linspace(0, 1, m, endpoint=False)
        pts.append(a + t * (b - a))
    z = np.concatenate(pts)
    d = D_many(tr, z, j, N)

    def refine(z, d, everywhere=False):
        zc, dc = np.append(z, z[0]), np.append(d, d[0])
        dp = np.abs(np.angle(dc[1:] / dc[:-1]))
        bad = np.arange(z.size) if everywhere else np.nonzero(dp > dphi)[0]
        if bad.size == 0:
            return z, d, 0
        mid = 0.5 * (zc[bad] + zc[bad + 1])
        dm = D_many(tr, mid, j, N)
        return np.insert(z, bad + 1, mid), np.insert(d, bad + 1, dm), bad.size

    def count(d):
        dc = np.append(d, d[0])
        return np.sum(np.angle(dc[1:] / dc[:-1])) / (2 * np.pi)

    for rnd in range(max_rounds):
        z, d, nb = refine(z, d)
        if nb == 0:
            break
    w1 = count(d)
    z, d, _ = refine(z, d, everywhere=True)
    for rnd in range(max_rounds):
        z, d, nb = refine(z, d)
        if nb == 0:
            break
    w2 = count(d)
    if samples:
        return w1, w2, z, d
    return w1, w2, float(np.min(np.abs(d)) / np.median(np.abs(d))), z.size, nb


def moment(z, d):
    """(1/2 pi i) closed integral of z dlog D over the sampled contour: the sum of the zeros inside."""
    zc, dc = np.append(z, z[0]), np.append(d, d[0])
    dl = np.log(np.abs(dc[1:] / dc[:-1])) + 1j * np.angle(dc[1:] / dc[:-1])
    return np.sum(0.5 * (zc[1:] + zc[:-1]) * dl) / (2j * np.pi)

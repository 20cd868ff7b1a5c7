"""Independent spectrum of a train of n fronts on the ring (Hill's method), from DESIGN.md's
linearisation in the frame xi = x + v t:
    sigma p + v p' = gamma (q - (F^2 - 1) p),   sigma q + v q' = -(p - c^2 p'')/gamma,
F(xi) = f(xi T / L), L = S/n, f the limit cycle of f'' + mu (f^2-1) f' + f = nu (vdp2.py).
Bloch: p, q = exp(i kappa xi) sum_k (P_k, Q_k) exp(2 pi i k xi/L), kappa = 2 pi j/S, j = 0..n-1.
Truncation |k| <= M; an eigenvalue is accepted when it agrees between M and ~1.5 M (to tol_conv);
sigma_max = the rightmost accepted eigenvalue other than the translation (j = 0, sigma ~ 0).
"""
import numpy as np
from vdp2 import Cycle


def hill_matrix(ahat, M, kappa, L, v, gamma, c):
    ks = np.arange(-M, M + 1)
    K = kappa + 2 * np.pi * ks / L
    idx = ks[:, None] - ks[None, :]
    A = ahat(idx)  # Toeplitz of the Fourier coefficients of F^2 - 1
    n = 2 * M + 1
    H = np.zeros((2 * n, 2 * n), complex)
    H[:n, :n] = -1j * v * np.diag(K) - gamma * A
    H[:n, n:] = gamma * np.eye(n)
    H[n:, :n] = -np.diag(1 + c * c * K * K) / gamma
    H[n:, n:] = -1j * v * np.diag(K)
    return H


def spectrum(gamma, c, nu, S, n, v, mu, M=None, Mcap=160, Nf=8192, tol_conv=1e-7, jlist=None, verbose=False):
    cyc = Cycle(mu, nu, 1e-13)
    T = cyc.T
    L = S / n
    f = cyc.profile(Nf)
    a = f * f - 1.0
    ah = np.fft.fft(a) / Nf
    amax = np.abs(ah).max()
    # decay of the coefficients decides M
    mags = np.abs(ah[: Nf // 2])
    if M is None:
        above = np.nonzero(mags > 1e-10 * amax)[0]
        M = int(min(Mcap, max(30, above.max())))

    def ahat(idx):
        return ah[np.mod(idx, Nf)]

    res = {"M": M, "T": T, "tail": float(mags[M:].max() / amax) if M < Nf // 2 else 0.0}
    best = None
    allacc = []
    if jlist is None:
        jlist = range(0, n // 2 + 1)
    for j in jlist:
        kappa = 2 * np.pi * j / S
        e1 = np.linalg.eigvals(hill_matrix(ahat, M, kappa, L, v, gamma, c))
        M2 = int(1.4 * M)
        e2 = np.linalg.eigvals(hill_matrix(ahat, M2, kappa, L, v, gamma, c))
        e2 = e2[np.argsort(-e2.real)]
        acc = []
        for s in e2[: 60]:
            d = np.min(np.abs(e1 - s))
            if d < tol_conv * max(1, abs(s)):
                if j == 0 and abs(s) < 1e-6:
                    continue  # translation
                acc.append((s, d))
        if acc:
            s, d = max(acc, key=lambda t: t[0].real)
            # is it really the rightmost?  any unconverged eigenvalue to its right?
            right_unconv = [x for x in e2[:60] if x.real > s.real + 1e-9 and not (j == 0 and abs(x) < 1e-6)
                            and np.min(np.abs(e1 - x)) >= tol_conv * max(1, abs(x))]
            allacc.append({"j": j, "sigma": s, "conv": d, "unconverged_right": len(right_unconv),
                           "unconv_max_re": max([x.real for x in right_unconv], default=None)})
            if best is None or s.real > best["sigma"].real:
                best = allacc[-1]
        if verbose:
            print(j, acc[:2] if acc else None, flush=True)
    res["per_j"] = allacc
    res["best"] = best
    return res


if __name__ == "__main__":
    import sys, time
    # paper's n = 4 (bkfront: -0.0017318853, complex, kappa 2 pi/20) and n = 2 (0.0697435)
    for n, v, mu in [(4, 0.48545916040196629, 2.5438807382090127), (2, 0.8954151211482031, 2.122682880976821),
                     (1, 1.9594220551124475, 2.0238619104068838)]:
        t0 = time.time()
        r = spectrum(2, 0.3, -0.96, 20, n, v, mu)
        print(n, r["M"], r["tail"], r["best"], "%.1fs" % (time.time() - t0))

# Short-wave limit of the train spectrum: for p, q ~ exp(i K xi), K -> inf, sigma + i v K -> +-i c K - gamma <F^2 - 1>/2,
# <.> the mean over xi (the modes move at v -+ c relative to the train).  So Re sigma -> gamma (1 - <F^2>)/2.
# Hill's eigenvalues per K band (M and 1.4 M) at moderate |Im| show whether they converge to it.
import sys, json, subprocess, numpy as np
from vdp2 import Cycle
from hill import hill_matrix
idx, n = int(sys.argv[1]), int(sys.argv[2])
st = json.load(open("sets.json"))[idx]
J = json.loads(subprocess.run(["bk/build/bkfront", "speeds", "--gamma", repr(st["gamma"]), "--c", repr(st["c"]), "--nu", repr(st["nu"]), "--S", repr(st["S"]), "--n", str(n), "--format", "json"], capture_output=True, text=True).stdout)
r = J["rows"][0]
mu, v, g, c, S = r["mu"], r["v"], st["gamma"], st["c"], st["S"]
cyc = Cycle(mu, st["nu"], 1e-13)
Nf = 8192
f = cyc.profile(Nf)
F2 = float(np.mean(f * f))
print("set", idx, "n", n, "mu", mu, "v", v, "<F>", float(np.mean(f)), "nu", st["nu"], "<F^2>", F2, "limit Re sigma", g * (1 - F2) / 2, flush=True)
ah = np.fft.fft(f * f - 1) / Nf
ahat = lambda i: ah[np.mod(i, Nf)]
L = S / n
for M in [int(a) for a in sys.argv[3:]]:
    e1 = np.linalg.eigvals(hill_matrix(ahat, M, 0.0, L, v, g, c))
    e2 = np.linalg.eigvals(hill_matrix(ahat, int(1.4 * M), 0.0, L, v, g, c))
    conv = [s for s in e2 if np.min(np.abs(e1 - s)) < 1e-8 * max(1, abs(s))]
    conv.sort(key=lambda s: -s.real)
    print("M", M, "converged (j=0), rightmost 6:", ["%.6g%+.4gi" % (s.real, s.imag) for s in conv[:6]],
          "max Re of all:", max(e2.real), flush=True)

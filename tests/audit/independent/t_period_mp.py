# Arbiter for T(mu, nu) where LSODA and bkfront differ beyond both errors (set 5: mu 0.0844055, nu -0.666834):
# Taylor series in mpmath (odefun, 30 digits) in (x, x') coordinates, which suit small mu; the
# section x = nu upward; the cycle by secant on the return map.
import sys, mpmath as mp
mp.mp.dps = int(sys.argv[3]) if len(sys.argv) > 3 else 30
mu, nu = mp.mpf(sys.argv[1]), mp.mpf(sys.argv[2])

def ret(y0):
    f = mp.odefun(lambda t, u: [u[1], nu - u[0] - mu * (u[0] ** 2 - 1) * u[1]], 0, [nu, y0])
    # x - nu goes down at t ~ pi, back up at t ~ 2 pi: the upward crossing near 2 pi
    T = mp.findroot(lambda t: f(t)[0] - nu, 2 * mp.pi)
    return f(T)[1], T

# start from bkfront's neighbourhood: amplitude of the near-harmonic cycle, then secant
y0 = mp.mpf(sys.argv[4]) if len(sys.argv) > 4 else 2 * mp.sqrt(1 - nu * nu)
y1, T = ret(y0)
ya, ga = y0, y1 - y0
yb = y1
for it in range(30):
    y2, T = ret(yb)
    gb = y2 - yb
    print(it, mp.nstr(yb, 25), mp.nstr(gb, 5), mp.nstr(T, 25), flush=True)
    if abs(gb) < mp.mpf(10) ** (-mp.mp.dps + 5):
        break
    ya, ga, yb = yb, gb, yb - gb * (yb - ya) / (gb - ga)
print("T", mp.nstr(T, 25))

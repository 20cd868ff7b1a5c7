"""Random parameter sets, seed 20261130 (never used by the project)."""
import json, math
import numpy as np
rng = np.random.default_rng(20261130)
def k(nu): return 3 + (nu*nu-1)*math.log((4-nu*nu)/(1-nu*nu))
sets = []
for i in range(32):
    g = float(np.exp(rng.uniform(math.log(0.3), math.log(8))))
    c = float(rng.uniform(0.05, 1.5))
    nu = float(rng.uniform(-0.99, 0.99))
    S = float(rng.uniform(5, 60))
    kind = "uniform"
    if i % 8 == 1:   # |nu| > 0.95
        nu = float(rng.choice([-1, 1]) * rng.uniform(0.95, 0.99)); kind = "nu-extreme"
    if i % 8 == 3:   # small gamma
        g = float(rng.uniform(0.3, 0.5)); kind = "gamma-small"
    if i % 8 == 5:   # large gamma
        g = float(rng.uniform(6, 8)); kind = "gamma-large"
    if i % 8 == 7:   # c near the speeds: S just above k c gamma (n = 1 near sonic)
        f = rng.uniform(1.02, 2.5); kind = "near-sonic"
        S = float(k(nu) * c * g * f)
        if S < 5:
            c = float(min(1.5, 5.0 / (k(nu) * g * f)))
            g = float(max(g, 5.0 / (k(nu) * c * f)))
            S = float(k(nu) * c * g * f)
    # round to 6 significant digits (printed as typed by a user)
    st = {k_: float("%.6g" % v) for k_, v in dict(gamma=g, c=c, nu=nu, S=S).items()}
    st["kind"] = kind
    st["n_bound"] = st["S"] / (k(st["nu"]) * st["c"] * st["gamma"])
    sets.append(st)
json.dump(sets, open("sets.json", "w"), indent=1)
for i, s in enumerate(sets): print(i, s)

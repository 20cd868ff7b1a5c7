"""Independent audit of `bkfront speeds` and `bkfront period` on one parameter set.

usage: audit_speeds.py SETFILE INDEX  -> appends a JSON line to results/speeds_INDEX.json
Method (independent of bkfront's code):
  g(mu) = T(mu)/sqrt(mu^2 - gamma^2); a root of n T(mu(v)) = S/(v sqrt(1-c^2/v^2)) is a root of
  g(mu) = S/(n c gamma) with v = c/sqrt(1 - gamma^2/mu^2).  T from vdp2.py (LSODA + Henon).
  Scan g on a grid in ln(mu/gamma - 1) (rtol 1e-10, warm starts), refine near local extrema
  (golden section) and jumps of T; count crossings per level n.  Beyond mu_hi the count assumes
  g decreasing to k(nu) (paper's k formula).  Each audited root: my T at bkfront's mu (rtol 1e-13,
  error = |T(1e-13) - T(1e-12)|), my residual, one Newton step for my root, compared with v_err.
"""
import json, subprocess, sys, math, time, os
import numpy as np
from vdp2 import Cycle

BK = os.path.join(os.path.dirname(os.path.abspath(__file__)), "bk/build/bkfront")


def kfun(nu):
    return 3 + (nu * nu - 1) * math.log((4 - nu * nu) / (1 - nu * nu))


def run(args, timeout=900):
    t0 = time.time()
    p = subprocess.run([BK] + args, capture_output=True, text=True, timeout=timeout)
    return p.returncode, p.stdout, p.stderr, time.time() - t0


class Scan:
    def __init__(self, gamma, nu, rtol=1e-9):
        self.gamma, self.nu, self.rtol = gamma, nu, rtol
        self.pts = {}  # mu -> (T, y0, lienard)
        self.last = None

    def T(self, mu):
        if mu in self.pts:
            return self.pts[mu][0]
        y0 = Test = None
        # warm start from the nearest sample in the same coordinates
        cand = [m for m in self.pts if (m > 3.0) == (mu > 3.0)]
        if cand:
            m = min(cand, key=lambda m: abs(math.log(m / mu)))
            if abs(math.log(m / mu)) < 0.5:
                y0 = self.pts[m][1]
                Test = self.pts[m][0] * (mu / m if mu > 3 else 1.0)
        try:
            c = Cycle(mu, self.nu, self.rtol, y0=y0, Test=Test)
        except Exception:
            c = Cycle(mu, self.nu, self.rtol)
        self.pts[mu] = (c.T, c.y0)
        return c.T

    def g(self, mu):
        return self.T(mu) / math.sqrt(mu * mu - self.gamma ** 2)


def audit(st):
    gamma, c, nu, S = st["gamma"], st["c"], st["nu"], st["S"]
    out = {"set": st, "period": [], "roots": [], "count": [], "notes": []}
    k = kfun(nu)
    # ---- bkfront speeds
    rc, so, se, dt = run(["speeds", "--gamma", repr(gamma), "--c", repr(c), "--nu", repr(nu), "--S", repr(S),
                          "--format", "json"] + (["--tol", os.environ["BKTOL"]] if os.environ.get("BKTOL") else []))
    out["speeds_rc"], out["speeds_time"], out["speeds_stderr"] = rc, dt, se.strip()
    # exit 3: some rows refused (flag refused, numbers nan, reason in a comment): refusals, not defects
    if rc not in (0, 3):
        out["notes"].append("speeds exit %d: %s" % (rc, se.strip()))
        return out
    J = json.loads(so)
    rows = J["rows"]
    out["bk_comments"] = J["comments"]
    out["bk_results"] = J["results"]
    # finiteness of every printed number
    bad = []
    out["refused"] = [{"n": r["n"], "v_asym": r.get("v_asym")} for r in rows if "refused" in (r.get("flags") or "")]
    out["refused_reasons"] = [c for c in J["comments"] if c.startswith("refused")]
    for r in rows:
        if "refused" in (r.get("flags") or ""):
            continue
        for kk, vv in r.items():
            if J["kinds"][J["columns"].index(kk)] == "number" and (vv is None or not math.isfinite(vv)):
                bad.append((r["n"], kk, vv))
    out["nonfinite"] = bad
    # ---- my scan
    sc = Scan(gamma, nu)
    lev1 = S / (c * gamma)
    eps_lo = min(1e-2, 0.5 * (c / S) ** 2)
    mu_hi = 2000.0
    if mu_hi < gamma * 3:
        mu_hi = gamma * 3
    while sc.g(gamma * (1 + eps_lo)) <= 1.5 * lev1:
        eps_lo /= 10
    s = list(np.linspace(math.log(eps_lo), math.log(mu_hi / gamma - 1), 48))
    mus = [gamma * (1 + math.exp(x)) for x in s]
    for m in mus:
        sc.g(m)
    # refine: jumps of ln T, and local extrema of g
    for rnd in range(6):
        ms = sorted(sc.pts)
        add = []
        Ts = [sc.pts[m][0] for m in ms]
        for i in range(len(ms) - 1):
            if abs(math.log(Ts[i + 1] / Ts[i])) > 0.15 and ms[i + 1] / ms[i] > 1 + 1e-9:
                add.append(math.sqrt(ms[i] * ms[i + 1]) if ms[i] > 0 else 0.5 * (ms[i] + ms[i + 1]))
        if not add:
            break
        for m in add:
            sc.g(m)
    ms = sorted(sc.pts)
    gs = [sc.g(m) for m in ms]
    # local extrema: golden section in ln(mu - gamma)
    ext = []
    for i in range(1, len(ms) - 1):
        if (gs[i] - gs[i - 1]) * (gs[i + 1] - gs[i]) < 0:
            ismin = gs[i] < gs[i - 1]
            a, b = math.log(ms[i - 1] - gamma), math.log(ms[i + 1] - gamma)
            fsign = 1 if ismin else -1
            gr = (math.sqrt(5) - 1) / 2
            x1, x2 = b - gr * (b - a), a + gr * (b - a)
            f = lambda x: fsign * sc.g(gamma + math.exp(x))
            f1, f2 = f(x1), f(x2)
            for it in range(14):
                if f1 < f2:
                    b, x2, f2 = x2, x1, f1
                    x1 = b - gr * (b - a)
                    f1 = f(x1)
                else:
                    a, x1, f1 = x1, x2, f2
                    x2 = a + gr * (b - a)
                    f2 = f(x2)
            ext.append(("min" if ismin else "max", gamma + math.exp(x1)))
    out["extrema"] = ext
    ms = np.array(sorted(sc.pts))
    gs = np.array([sc.g(m) for m in ms])
    out["scan_points"] = len(ms)
    out["g_lo"], out["g_hi"], out["mu_hi"] = float(gs[0]), float(gs[-1]), float(ms[-1])
    # ---- counts per n
    bk_n = {}
    for r in rows:
        bk_n.setdefault(r["n"], []).append(r)
    nmax_listed = max(bk_n) if bk_n else 0
    n_top = int(max(nmax_listed, math.floor(S / (c * gamma * min(k, gs.min())))) + 2)
    cnt_mismatch = []
    for n in range(1, n_top + 1):
        L = S / (n * c * gamma)
        d = gs - L
        mine = int(np.sum(np.sign(d[1:]) != np.sign(d[:-1])))
        beyond = 0
        if d[-1] > 0 and L > k:
            beyond = 1  # g decreasing to k beyond mu_hi: one more root (assumption)
        if L < gs[0] and d[0] < 0:
            pass
        nb = len(bk_n.get(n, []))
        nb_beyond = sum(1 for r in bk_n.get(n, []) if r["mu"] > ms[-1])
        if n > 1000:
            continue
        if mine + beyond != nb:
            cnt_mismatch.append({"n": n, "mine_in_scan": mine, "mine_beyond": beyond, "bk": nb,
                                 "bk_beyond": nb_beyond})
    out["count"] = cnt_mismatch
    out["n_total_bk"] = len(rows)
    out["n_levels_checked"] = min(n_top, 1000)
    # ---- precise check on a sample of roots
    ns = sorted(bk_n)
    pick = set(ns[:2]) | set(ns[-2:])
    rng = np.random.default_rng(int(1000 * S) % 100000)
    if len(ns) > 4:
        pick |= set(rng.choice(ns[2:-2], size=min(2, len(ns) - 4), replace=False).tolist())
    pick |= {n for n in ns if len(bk_n[n]) > 1}
    for n in sorted(pick):
        for ir, r in enumerate(bk_n[n]):
            mu = r["mu"]
            rec = {"n": n, "root": ir + 1, "mu": mu, "v": r["v"], "v_err": r["v_err"], "T_bk": r["T"],
                   "T_err_bk": r["T_err"], "model": r["model"], "flags": r["flags"]}
            if "refused" in (r.get("flags") or ""):
                rec["status"] = "refusal"
                out["roots"].append(rec)
                continue
            if mu > ms[-1] or mu > 3000:
                rec["status"] = "skip(mu beyond my reference)"
                out["roots"].append(rec)
                continue
            try:
                a = Cycle(mu, nu, 1e-13)
                b = Cycle(mu, nu, 1e-12, y0=a.y0, Test=a.T)
            except Exception as e:
                rec["status"] = "skip(my solver failed: %s)" % e
                out["roots"].append(rec)
                continue
            T, Te = a.T, abs(a.T - b.T) + 1e-15 * a.T
            rec["T_ref"], rec["T_err_ref"] = T, Te
            rec["T_ok"] = abs(T - r["T"]) <= r["T_err"] + Te
            # slope d ln g / d mu from two nearby precise values
            h = 1e-5 * mu
            c2 = Cycle(mu + h, nu, 1e-13, y0=a.y0, Test=a.T)
            lg = lambda m, TT: math.log(TT / math.sqrt(m * m - gamma * gamma))
            dlg = (lg(mu + h, c2.T) - lg(mu, T)) / h
            L = S / (n * c * gamma)
            D = lg(mu, T) - math.log(L)
            mu_ref = mu - D / dlg
            vf = lambda m: c / math.sqrt(1 - gamma * gamma / (m * m))
            v_ref = vf(mu_ref)
            dvdmu = (vf(mu * (1 + 1e-7)) - vf(mu)) / (mu * 1e-7)
            my_err = abs(dvdmu) * (Te / T) / abs(dlg) + abs(v_ref - r["v"]) * 0.0
            rec.update({"v_ref": v_ref, "v_err_ref": my_err, "dv": r["v"] - v_ref,
                        "v_ok": abs(r["v"] - v_ref) <= r["v_err"] + my_err})
            if not rec["T_ok"] and mu < 60:
                from taylor import period_taylor
                try:
                    Tt, Tte = period_taylor(mu, nu, a.y0)
                    rec["T_taylor"], rec["T_taylor_err"] = Tt, Tte
                    rec["T_ok"] = abs(Tt - r["T"]) <= r["T_err"] + Tte
                    D2 = lg(mu, Tt) - math.log(L)
                    rec["v_ref_taylor"] = vf(mu - D2 / dlg)
                    e2 = abs(dvdmu) * (Tte / Tt) / abs(dlg)
                    rec["v_ok"] = abs(r["v"] - rec["v_ref_taylor"]) <= r["v_err"] + e2
                except Exception as e:
                    rec["taylor_failed"] = str(e)
            rec["status"] = "OK" if (rec["v_ok"] and rec["T_ok"]) else "DEFECT?"
            out["roots"].append(rec)
    # ---- period product at a few mu (roots' mu and random), tol 1e-12
    pm = [r["mu"] for n in sorted(pick) for r in bk_n[n] if "refused" not in (r.get("flags") or "") and r["mu"] < 1000][:2]
    pm += [float(10 ** x) for x in rng.uniform(-1.5, 2.7, size=3)]
    cache = {}
    pm = [float("%.6g" % m) for m in pm]
    for tol in ("1e-10", "1e-12"):
        rc, so, se, dt = run(["period", "--mu", ",".join(repr(m) for m in pm), "--nu", repr(nu), "--tol", tol,
                              "--format", "json"])
        if rc != 0:
            out["period"].append({"tol": tol, "rc": rc, "stderr": se.strip(), "mus": pm})
            continue
        P = json.loads(so)
        for r in P["rows"]:
            mu = r["mu"]
            try:
                if mu not in cache:
                    a = Cycle(mu, nu, 1e-13)
                    b = Cycle(mu, nu, 1e-12, y0=a.y0, Test=a.T)
                    cache[mu] = (a, abs(a.T - b.T) + 1e-15 * a.T)
                a, Te = cache[mu]
            except Exception as e:
                out["period"].append({"tol": tol, "mu": mu, "status": "skip %s" % e})
                continue
            fin = all((v is None or (isinstance(v, str)) or math.isfinite(v)) for v in r.values())
            nonfin = [kk for kk, v in r.items() if not isinstance(v, str) and (v is None or not math.isfinite(v))]
            ok = r["T"] is not None and abs(r["T"] - a.T) <= r["T_err"] + Te
            if not ok:
                from taylor import period_taylor
                try:
                    Tt, Tte = period_taylor(mu, nu, a.y0)
                    ok = abs(r["T"] - Tt) <= r["T_err"] + Tte
                    out["period"].append({"arbiter": "taylor", "mu": mu, "T_taylor": Tt, "T_taylor_err": Tte})
                except Exception as e:
                    out["period"].append({"arbiter": "taylor failed %s" % e, "mu": mu})
            out["period"].append({"tol": tol, "mu": mu, "T_bk": r["T"], "T_err_bk": r["T_err"], "T_ref": a.T,
                                  "T_err_ref": Te, "model": r["model"], "nonfinite": nonfin,
                                  "status": "OK" if ok else "DEFECT?"})
    return out


if __name__ == "__main__":
    sets = json.load(open(sys.argv[1]))
    for idx in [int(a) for a in sys.argv[2:]]:
        t0 = time.time()
        o = audit(sets[idx])
        o["idx"] = idx
        o["wall"] = time.time() - t0
        os.makedirs("results", exist_ok=True)
        with open("results/speeds_%02d%s.json" % (idx, "_tol" + os.environ["BKTOL"] if os.environ.get("BKTOL") else ""), "w") as f:
            json.dump(o, f, indent=1, default=float)
        nr = len(o["roots"])
        bad = [r for r in o["roots"] if r.get("status") not in ("OK",) and not str(r.get("status")).startswith("skip")]
        badp = [p for p in o["period"] if p.get("status") != "OK"]
        print("set %d: %s rows %s, counts mismatch %s, roots checked %d, bad %d, period bad %d, %.0fs" % (
            idx, sets[idx], o.get("n_total_bk"), o["count"][:3], nr, len(bad), len(badp), o["wall"]), flush=True)

"""Independent audit of `speeds --stability`, `stability` and `check` on chosen roots of a set.

usage: audit_stab.py SETFILE IDX... ; writes results/stab_IDX.json
Reference: hill.py (Hill's method from DESIGN.md's linearisation, profile from vdp2.py).
Roots: the first root of n = 1 and one more root with n <= 6, both with mu <= 6 (Hill converges).
check: run on the n = 1 root (timeout 420 s), its verdict against my sigma_max sign.
"""
import json, sys, os, math, time, subprocess
import numpy as np
from hill import spectrum

BK = os.path.join(os.path.dirname(os.path.abspath(__file__)), "bk/build/bkfront")


def run(args, timeout=900):
    t0 = time.time()
    try:
        p = subprocess.run([BK] + args, capture_output=True, text=True, timeout=timeout)
        return p.returncode, p.stdout, p.stderr, time.time() - t0
    except subprocess.TimeoutExpired:
        return None, "", "timeout", time.time() - t0


LARGE = os.environ.get("LARGE") == "1"


def audit(st, do_check=True):
    g, c, nu, S = st["gamma"], st["c"], st["nu"], st["S"]
    P = ["--gamma", repr(g), "--c", repr(c), "--nu", repr(nu), "--S", repr(S)]
    out = {"set": st, "roots": []}
    rc, so, se, dt = run(["speeds"] + P + ["--nmax", "6", "--format", "json"])
    if rc not in (0, 3):
        out["note"] = "speeds rc %s %s" % (rc, se)
        return out
    rows = json.loads(so)["rows"]
    ok = lambda r: "refused" not in (r.get("flags") or "")
    cands = [r for r in rows if ok(r) and r["mu"] <= 6.0]
    pick = []
    if LARGE:
        cands = [r for r in rows if ok(r) and 6.0 < r["mu"] <= 10.0][:1]
        pick = cands
    elif cands:
        pick.append(cands[0])
        others = [r for r in cands[1:] if r["n"] <= 6]
        if others:
            pick.append(others[-1])
    for r in pick:
        n = r["n"]
        iroot = [x for x in rows if x["n"] == n].index(r) + 1
        rec = {"n": n, "root": iroot, "v": r["v"], "mu": r["mu"]}
        # bkfront speeds --stability
        rc, so, se, dt = run(["speeds"] + P + ["--n", str(n), "--stability", "--format", "json"])
        rec["speeds_stab_rc"], rec["speeds_stab_time"] = rc, dt
        if rc in (0, 3):
            J = json.loads(so)
            rr = J["rows"][iroot - 1]
            rec["ss"] = {k: rr.get(k) for k in ("stable", "sigma_max", "sigma_max_err", "kappa_max", "kind")}
            rec["ss_comments"] = [x for x in J["comments"] if "sigma" in x or "stab" in x or "every" in x]
        else:
            rec["ss_err"] = se.strip()
        rc, so, se, dt = run(["stability"] + P + ["--n", str(n), "--root", str(iroot), "--format", "json"])
        rec["stab_rc"], rec["stab_time"] = rc, dt
        if rc == 0:
            J = json.loads(so)
            rec["st"] = {k: J["results"].get(k) for k in ("stable", "sigma_max", "sigma_max_im", "sigma_max_err",
                                                          "sigma_bound", "kappa_max", "kind", "translation_residual",
                                                          "hill_modes")}
        else:
            rec["st_err"] = se.strip()
        # Hill
        t0 = time.time()
        try:
            H = spectrum(g, c, nu, S, n, r["v"], r["mu"], Mcap=300 if LARGE else 160)
            b = H["best"]
            rec["hill"] = {"M": H["M"], "tail": H["tail"], "time": time.time() - t0,
                           "per_j": [{"j": x["j"], "re": x["sigma"].real, "im": x["sigma"].imag, "conv": x["conv"],
                                      "unconv_right": x["unconverged_right"], "unconv_max_re": x["unconv_max_re"]}
                                     for x in H["per_j"]]}
            if b is not None:
                rec["hill"]["sigma_max"] = b["sigma"].real
                rec["hill"]["sigma_im"] = b["sigma"].imag
                rec["hill"]["err"] = b["conv"] + 1e-9
                rec["hill"]["j"] = b["j"]
        except Exception as e:
            rec["hill"] = {"error": str(e)}
        # check on the first pick only
        if do_check and r is pick[0]:
            rc, so, se, dt = run(["check"] + P + ["--n", str(n), "--no-progress", "--format", "json"], timeout=420)
            rec["check_rc"], rec["check_time"], rec["check_stderr"] = rc, dt, se.strip()[-2000:]
            if rc in (0, 1):
                try:
                    J = json.loads(so)
                    rec["check"] = [{k: x.get(k) for k in ("n", "root", "verdict", "spectral", "sigma_max",
                                                          "sigma_max_err", "growth", "growth_limit",
                                                          "growth_verdict", "kept", "rel_err", "v_meas",
                                                          "decide_tmax")} for x in J["rows"]]
                except Exception as e:
                    rec["check_parse"] = str(e)
        out["roots"].append(rec)
    return out


if __name__ == "__main__":
    sets = json.load(open(sys.argv[1]))
    for idx in [int(a) for a in sys.argv[2:]]:
        t0 = time.time()
        o = audit(sets[idx])
        o["idx"], o["wall"] = idx, time.time() - t0
        os.makedirs("results", exist_ok=True)
        json.dump(o, open("results/stab%s_%02d.json" % ("L" if LARGE else "", idx), "w"), indent=1, default=float)
        for r in o["roots"]:
            print(idx, r["n"], r["root"], "mu %.4g" % r["mu"], "ss", r.get("ss", r.get("ss_err")),
                  "st", (r.get("st") or {}).get("sigma_max"), "hill", (r.get("hill") or {}).get("sigma_max"),
                  "check", [x["verdict"] for x in r.get("check", [])], flush=True)
        print("set", idx, "%.0fs" % o["wall"], o.get("note", ""), flush=True)

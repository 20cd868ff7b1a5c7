"""Table OK / defect / refusal per product from results/*.json.

usage: summarize.py [FIRST LAST]   only the sets FIRST..LAST (part 2: `summarize.py 24 31` for the
speeds/period audit of sets 24-31; the results/stab2_*.json of audit_stab2.py are always read)."""
import json, glob, math, sys

SETS = range(int(sys.argv[1]), int(sys.argv[2]) + 1) if len(sys.argv) > 2 else range(0, 10 ** 6)

tab = {k: {"OK": 0, "defect": 0, "refusal": 0, "skip": 0} for k in
       ("period", "speeds-root", "speeds-count", "speeds-finite", "speeds--stability", "stability", "check",
        "speeds--stability table", "stability --line", "bad input", "stability mu>6 (magnus)",
        "speeds--stability mu>6 (magnus)")}
rows_total = rows_refused = 0
defects = []
arb = json.load(open("arbitration.json"))
def arbitrated(i, product, mu):
    for a in arb:
        if a["set"] == i and a["product"] == product and abs(a["mu"] - mu) <= 1e-9 * abs(mu):
            return a
    return None
for fn in sorted(glob.glob("results/speeds_*.json")):
    o = json.load(open(fn))
    i = o["idx"]
    if i not in SETS:
        continue
    if "speeds_rc" in o and o["speeds_rc"] not in (0, 3):
        tab["speeds-root"]["refusal"] += 1
        defects.append((i, "speeds exit", o["speeds_rc"], o.get("speeds_stderr")))
        continue
    nlev = o.get("n_levels_checked", 0)
    bad = len(o["count"])
    tab["speeds-count"]["OK"] += nlev - bad
    tab["speeds-count"]["defect"] += bad
    for c in o["count"]:
        defects.append((i, "count", c))
    tab["speeds-finite"]["OK" if not o.get("nonfinite") else "defect"] += 1
    if o.get("nonfinite"):
        defects.append((i, "nonfinite", o["nonfinite"][:5]))
    rows_total += o.get("n_total_bk", 0)
    rows_refused += len(o.get("refused", []))
    for r in o["roots"]:
        s = r["status"]
        if s == "refusal":
            tab["speeds-root"]["refusal"] += 1
            defects.append((i, "root refused", r["n"], r["root"], [x for x in o.get("refused_reasons", []) if "n = %d," % r["n"] in x][:1]))
        elif s == "OK":
            tab["speeds-root"]["OK"] += 1
        elif s.startswith("skip"):
            tab["speeds-root"]["skip"] += 1
        else:
            tab["speeds-root"]["defect"] += 1
            defects.append((i, "root", r))
    # an arbiter whose own error is large decides nothing (set 5: Taylor's long double at mu 0.084,
    # error 28.7): its "OK" stands only if arbitrated otherwise (arbitration.json)
    weak = {p["mu"] for p in o["period"] if "arbiter" in p and not (p.get("T_taylor_err", 1) < 1e-9 * abs(p.get("T_taylor", 1)))}
    for p in o["period"]:
        if "arbiter" in p:
            continue
        if p.get("mu") in weak and p.get("status") == "OK":
            p["status"] = "DEFECT? (weak arbiter)"
        if "rc" in p:
            tab["period"]["refusal"] += 1
            defects.append((i, "period rc", p))
            continue
        s = p["status"]
        a = arbitrated(i, "period", p.get("mu", float("nan")))
        if s != "OK" and a:
            s = a["verdict"]
            defects.append((i, "period arbitrated " + a["verdict"], p["tol"], p["mu"], a["why"][:80]))
        if s == "OK" and not p.get("nonfinite"):
            tab["period"]["OK"] += 1
        elif s.startswith("skip"):
            tab["period"]["skip"] += 1
        else:
            tab["period"]["defect"] += 1
            defects.append((i, "period", p))


def verdict_of(sig, err):
    if sig is None or (isinstance(sig, float) and math.isnan(sig)):
        return None
    if sig - err > 0:
        return "unstable"
    if sig + err < 0:
        return "stable"
    return None


for fn in sorted(glob.glob("results/stab_*.json") + glob.glob("results/stabL_*.json")):
    o = json.load(open(fn))
    i = o["idx"]
    if i not in SETS:
        continue
    for r in o["roots"]:
        h = r.get("hill", {})
        hs = h.get("sigma_max")
        he = h.get("err", 0)
        # my verdict only when converged and no unconverged eigenvalue right of it claims otherwise
        mine = verdict_of(hs, he)
        for prod, key in (("speeds--stability", "ss"), ("stability", "st")):
            b = r.get(key)
            if b is None:
                tab[prod]["refusal"] += 1
                defects.append((i, prod + " failed", r["n"], r.get(key + "_err")))
                continue
            bs, be = b.get("sigma_max"), b.get("sigma_max_err")
            if bs is None or (isinstance(bs, float) and math.isnan(bs)):
                bound = (r.get("st") or {}).get("sigma_bound")
                if b.get("stable") == "yes" and bound is not None and hs is not None and hs + he < bound:
                    # no sigma, but a decided verdict and a bound (every eigenvalue left of the window's
                    # edge) that Hill's converged rightmost obeys: a true statement, counted OK
                    tab[prod]["OK"] += 1
                    defects.append((i, prod + " bound OK", r["n"], "stable yes, bound", bound, "hill", hs))
                else:
                    tab[prod]["refusal"] += 1
                continue
            if hs is None:
                tab[prod]["skip"] += 1
                continue
            ok = abs(bs - hs) <= (be or 0) + he
            tab[prod]["OK" if ok else "defect"] += 1
            if not ok:
                defects.append((i, prod, r["n"], r["root"], r["mu"], "bk", bs, be, "hill", hs, he, h.get("j"),
                                h.get("sigma_im")))
        for ck in r.get("check", []):
            v = ck["verdict"]
            if mine is None:
                tab["check"]["skip"] += 1
                continue
            if mine == "unstable" and v in ("agrees", "disagrees"):
                tab["check"]["defect"] += 1
                defects.append((i, "check says %s, my spectrum unstable" % v, r["n"], hs, he, ck))
            elif mine == "stable" and v in ("unstable", "conflicts"):
                tab["check"]["defect"] += 1
                defects.append((i, "check says %s, my spectrum stable" % v, r["n"], hs, he, ck))
            elif v in ("undecided", "unresolved"):
                tab["check"]["refusal"] += 1
            else:
                tab["check"]["OK"] += 1
        if "check_rc" in r and r["check_rc"] not in (0, 1):
            tab["check"]["refusal"] += 1
            defects.append((i, "check rc", r["check_rc"], r.get("check_time")))

for fn in sorted(glob.glob("results/full_*.json")):
    o = json.load(open(fn))
    for r in o["rows"]:
        st = r.get("status", "")
        if st == "OK":
            tab["speeds--stability table"]["OK"] += 1
        elif st.startswith("refusal"):
            tab["speeds--stability table"]["refusal"] += 1
            defects.append((o["idx"], "table refusal", r["n"], r["mu"], r.get("stable")))
        elif st == "DEFECT?":
            tab["speeds--stability table"]["defect"] += 1
            defects.append((o["idx"], "table", r))
        else:
            tab["speeds--stability table"]["skip"] += 1
# part 2: stability and speeds --stability at mu > 6 against the Magnus monodromy (audit_stab2.py)
for fn in sorted(glob.glob("results/stab2_*.json")):
    r = json.load(open(fn))
    i = r["idx"]
    st = r.get("st")
    if st is None:
        tab["stability mu>6 (magnus)"]["refusal"] += 1
        defects.append((i, "stability failed", r["n"], r.get("stab_err")))
    elif st.get("sigma_max") is None and st.get("sigma_bound") is None:
        tab["stability mu>6 (magnus)"]["refusal"] += 1
        defects.append((i, "stability refused", r["n"], r.get("st_comments")))
    else:
        ok = r["rightmost_ok"] and r["verdict_ok"] and r.get("newton_ok", True)
        a = arbitrated(i, "stability", st["mu"])
        if not ok and a:
            ok = a["verdict"] == "OK"
            defects.append((i, "stability arbitrated " + a["verdict"], r["n"], a["why"][:100]))
        tab["stability mu>6 (magnus)"]["OK" if ok else "defect"] += 1
        if not ok:
            defects.append((i, "stability", r["n"], r["root"], st, r.get("newton"), r.get("boxes")))
    ss = r.get("ss")
    if ss is None:
        tab["speeds--stability mu>6 (magnus)"]["refusal"] += 1
    else:
        ok = r["ss_same"] and r["rightmost_ok"] and r["verdict_ok"] and r.get("newton_ok", True)
        tab["speeds--stability mu>6 (magnus)"]["OK" if ok else "defect"] += 1
        if not ok:
            defects.append((i, "speeds --stability", r["n"], r["root"], ss, st))
import os
if os.path.exists("results/line.json"):
    for r in json.load(open("results/line.json")):
        if "rc" in r:
            tab["stability --line"]["refusal"] += 1
            defects.append(("line rc", r))
        elif r["status"] == "OK":
            tab["stability --line"]["OK"] += 1
        elif r["kappa"] == 0 and r["hill_re"] is not None and r["hill_re"] < 0 and abs(r["bk_re"]) <= r["bk_err"] + 1e-9:
            # the rightmost sigma at kappa 0 is the translation's 0 when every other one is left of it
            # (hill.py leaves the translation out); bkfront's comment says so
            tab["stability --line"]["OK"] += 1
        else:
            tab["stability --line"]["defect"] += 1
            defects.append(("line", r))
if os.path.exists("badinput.txt"):
    for l in open("badinput.txt"):
        tab["bad input"]["OK" if l.startswith("OK") else "defect"] += 1
        if not l.startswith("OK"):
            defects.append(("badinput", l.strip()))
print("speeds rows listed %d, refused %d" % (rows_total, rows_refused))
for k, v in tab.items():
    print("%-18s %s" % (k, v))
print()
for d in defects:
    print(d)

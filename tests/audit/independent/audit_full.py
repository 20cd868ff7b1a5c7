"""Whole `speeds --stability` table of a set against Hill (hill.py) at every root with mu <= 6."""
import json, sys, subprocess, os, time, math
from hill import spectrum
BK = os.path.join(os.path.dirname(os.path.abspath(__file__)), "bk/build/bkfront")
sets = json.load(open("sets.json"))
for idx in [int(a) for a in sys.argv[1:]]:
    st = sets[idx]
    P = ["--gamma", repr(st["gamma"]), "--c", repr(st["c"]), "--nu", repr(st["nu"]), "--S", repr(st["S"])]
    t0 = time.time()
    p = subprocess.run([BK, "speeds"] + P + ["--stability", "--format", "json"], capture_output=True, text=True)
    res = {"idx": idx, "set": st, "rc": p.returncode, "stderr": p.stderr.strip(), "time": time.time() - t0, "rows": []}
    if p.returncode in (0, 3):
        J = json.loads(p.stdout)
        res["comments"] = J["comments"]
        for r in J["rows"]:
            rec = {k: r.get(k) for k in ("n", "v", "mu", "stable", "sigma_max", "sigma_max_err", "kappa_max", "kind")}
            if "refused" in (r.get("flags") or ""):
                rec["status"] = "refusal (root refused)"
            elif r["mu"] <= 6.0 and r["n"] <= 12:
                H = spectrum(st["gamma"], st["c"], st["nu"], st["S"], r["n"], r["v"], r["mu"])
                b = H["best"]
                if b:
                    rec["hill"], rec["hill_im"], rec["hill_err"], rec["hill_j"] = b["sigma"].real, b["sigma"].imag, b["conv"] + 1e-9, b["j"]
                    if rec["sigma_max"] is None or rec["sigma_max"] != rec["sigma_max"]:
                        rec["status"] = "refusal"
                    else:
                        rec["status"] = "OK" if abs(rec["sigma_max"] - rec["hill"]) <= rec["sigma_max_err"] + rec["hill_err"] else "DEFECT?"
            else:
                rec["status"] = "refusal" if rec["sigma_max"] is None else "not audited"
            res["rows"].append(rec)
            print(idx, rec, flush=True)
    json.dump(res, open("results/full_%02d.json" % idx, "w"), indent=1, default=float)
    print("set", idx, "rc", p.returncode, "%.0fs" % (time.time() - t0), flush=True)

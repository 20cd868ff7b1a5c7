"""`stability --line` against Hill at the same Bloch numbers kappa = (2 pi/L) i/M (my hill.py with
fractional j = kappa S / (2 pi)); the rightmost converged eigenvalue per kappa (translation excluded
at kappa = 0, which is the issue-31 item-5 trap; where every other eigenvalue is left of 0, the
rightmost at kappa = 0 is the translation's 0, and summarize.py accepts 0 within bkfront's error)."""
import json, sys, subprocess, os, numpy as np
from hill import spectrum
BK = os.path.join(os.path.dirname(os.path.abspath(__file__)), "bk/build/bkfront")
sets = json.load(open("sets.json"))
out = []
for spec in sys.argv[1:]:
    idx, n = [int(x) for x in spec.split(":")]
    st = sets[idx]
    P = ["--gamma", repr(st["gamma"]), "--c", repr(st["c"]), "--nu", repr(st["nu"]), "--S", repr(st["S"])]
    sp = json.loads(subprocess.run([BK, "speeds"] + P + ["--n", str(n), "--format", "json"], capture_output=True, text=True).stdout)
    r = sp["rows"][0]
    M = 4
    p = subprocess.run([BK, "stability"] + P + ["--n", str(n), "--line", "--kappa-count", str(M), "--format", "json"],
                       capture_output=True, text=True)
    if p.returncode != 0:
        out.append({"idx": idx, "n": n, "rc": p.returncode, "err": p.stderr.strip()}); print(out[-1]); continue
    J = json.loads(p.stdout)
    cols = J["columns"]
    for row in J["rows"]:
        row = dict(zip(cols, row)) if isinstance(row, list) else row
        kappa = row["kappa"]
        jf = kappa * st["S"] / (2 * np.pi)
        H = spectrum(st["gamma"], st["c"], st["nu"], st["S"], n, r["v"], r["mu"], jlist=[jf])
        b = H["best"]
        rec = {"idx": idx, "n": n, "kappa": kappa, "bk_re": row["re"], "bk_im": row["im"], "bk_err": row["err"],
               "hill_re": b["sigma"].real if b else None, "hill_im": b["sigma"].imag if b else None,
               "hill_conv": b["conv"] if b else None}
        rec["status"] = "OK" if b and abs(rec["bk_re"] - rec["hill_re"]) <= rec["bk_err"] + b["conv"] + 1e-9 else "DEFECT?"
        out.append(rec); print(rec, flush=True)
json.dump(out, open("results/line.json", "w"), indent=1, default=float)

"""Two more routes at the eigenvalues audit_stab2.py found with magnus.py (its reference's error):
 * Radau (monodromy.py: scipy's Radau on the same system, real form, rtol 1e-10 and 1e-11): the
   distance from the Magnus root to Radau's, by one Newton step |D/D'| (D' by a central difference);
 * Hill (hill.py) with M as large as the profile's Fourier tail asks (HILL=1; mu <= 7 only: the
   dense eigenvalues of 2(2M+1) matrices at M ~ 300-450 and 1.4 M).
usage: t_routes.py results/stab2_IDX_n_root.json ...
"""
import json, sys, time, os
import numpy as np
from monodromy import Train

for fn in sys.argv[1:]:
    r = json.load(open(fn))
    st, s = r["set"], r["newton"]
    sig, j = complex(s["sigma_re"], s["sigma_im"]), s["j"]
    tr = Train(st["gamma"], st["c"], st["nu"], st["S"], r["n"], r["st"]["v"], r["st"]["mu"])
    out = {"file": fn, "magnus": [sig.real, sig.imag], "magnus_err": s["err"]}
    for rtol in [float(x) for x in os.environ.get("RTOLS", "1e-10,1e-11").split(",")]:
        t0 = time.time()
        h = 1e-5
        d0 = tr.D(sig, j, rtol)
        dd = (tr.D(sig + h, j, rtol) - tr.D(sig - h, j, rtol)) / (2 * h)
        out["radau_%g" % rtol] = {"offset": abs(d0 / dd), "steps": tr.last_steps, "time": time.time() - t0}
        print(fn, rtol, out["radau_%g" % rtol], flush=True)
    if os.environ.get("HILL") == "1":
        from hill import spectrum
        t0 = time.time()
        H = spectrum(st["gamma"], st["c"], st["nu"], st["S"], r["n"], r["st"]["v"], r["st"]["mu"], Mcap=500,
                     jlist=[j])
        b = H["per_j"][0] if H["per_j"] else None
        out["hill"] = {"M": H["M"], "tail": H["tail"], "time": time.time() - t0,
                       "sigma": [b["sigma"].real, b["sigma"].imag] if b else None, "conv": b["conv"] if b else None,
                       "unconv_right": b["unconverged_right"] if b else None}
        print(fn, "hill", out["hill"], flush=True)
    json.dump(out, open(fn.replace("stab2_", "routes_"), "w"), indent=1)

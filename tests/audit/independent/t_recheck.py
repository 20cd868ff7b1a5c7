"""Re-run bkfront (BK=path) on the roots audit_stab2.py audited and check the new sigma_max against
the stored reference (results/stab2_*.json): Newton distance within err_bk + err_ref, and not right
of the box edge whose count was 0.  For a later main; the contours are not re-run."""
import json, glob, os, subprocess, sys
BK = os.environ.get("BK", "bk/build/bkfront")
for fn in sorted(glob.glob("results/stab2_*.json")):
    r = json.load(open(fn))
    st = r["set"]
    P = ["--gamma", repr(st["gamma"]), "--c", repr(st["c"]), "--nu", repr(st["nu"]), "--S", repr(st["S"])]
    p = subprocess.run([BK, "stability"] + P + ["--n", str(r["n"]), "--root", str(r["root"]), "--format", "json"],
                       capture_output=True, text=True, timeout=600)
    if p.returncode != 0:
        print(fn, "rc", p.returncode, p.stderr.strip()[:150], "(before:", "refused" if not r.get("st") else "answered", ")")
        continue
    R = json.loads(p.stdout)["results"]
    nw = r.get("newton")
    if not nw:
        print(fn, "now answers", R["stable"], R["sigma_max"], R.get("sigma_max_im"), R["sigma_max_err"])
        continue
    d = abs(complex(R["sigma_max"], R.get("sigma_max_im") or 0) - complex(nw["sigma_re"], nw["sigma_im"]))
    d2 = abs(complex(R["sigma_max"], -(R.get("sigma_max_im") or 0)) - complex(nw["sigma_re"], nw["sigma_im"]))
    ok = min(d, d2) <= R["sigma_max_err"] + nw["err"] and R["stable"] == r["st"]["stable"]
    print(fn, "OK" if ok else "DIFFERS", R["stable"], R["sigma_max"], R["sigma_max_err"], "dist %.2g" % min(d, d2),
          "same as before" if R["sigma_max"] == r["st"]["sigma_max"] else "changed from %r" % r["st"]["sigma_max"])

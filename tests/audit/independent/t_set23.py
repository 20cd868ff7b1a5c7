# set 23, n = 1: are Hill's unconverged eigenvalues right of the converged -0.0213 real?  Hill at M and 1.4 M for larger M.
import json, numpy as np
from hill import spectrum
st = json.load(open("sets.json"))[23]
mu, v = 1.2857733453444502, None
import subprocess
J = json.loads(subprocess.run(["bk/build/bkfront", "speeds", "--gamma", repr(st["gamma"]), "--c", repr(st["c"]), "--nu", repr(st["nu"]), "--S", repr(st["S"]), "--n", "1", "--format", "json"], capture_output=True, text=True).stdout)
r = J["rows"][0]
for M in (40, 80, 120):
    H = spectrum(st["gamma"], st["c"], st["nu"], st["S"], 1, r["v"], r["mu"], M=M)
    print(M, H["per_j"], flush=True)

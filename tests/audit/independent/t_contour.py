"""Check of the argument principle (magnus.winding) where the answer is known: set 5, n = 1
(bkfront: 0.0105513 +- 5.1503i and 0.0105503 +- 4.8067i at j = 0).  A box left of both pairs
must count 4 or more, the box right of them 0, at N = 2000, 4000 and 8000 Magnus steps."""
import json, time
from magnus import MagnusTrain, winding
s = json.load(open("sets.json"))[5]
tr = MagnusTrain(s["gamma"], s["c"], s["nu"], s["S"], 1, 1.4513748635037234, 7.4805296992222328)
print("asymptote", tr.asymptote())
for N in (2000, 4000, 8000):
    for x0 in (0.0105, 0.010551, 0.0105525):
        t = time.time()
        w = winding(tr, 0, x0, 3.0, 12.0, N)
        print(N, x0, "count %.3f halved %.3f min|D| %.2g points %d unresolved %d" % w, "%.0fs" % (time.time() - t), flush=True)
for s0 in (0.0105513 + 5.1503j, 0.0105503 + 4.8067j):
    print(tr.eigenvalue(s0, 0))

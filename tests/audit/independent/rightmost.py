"""The rightmost eigenvalue (but the translation) of one Bloch class, from the argument principle
alone (magnus.winding), for roots bkfront refuses or where its answer is disputed.
Bisection on x0 (the count of zeros of D_j in [x0, x1] x [-Y, Y] less the translation), then on
Im sigma inside the strip, then Newton (MagnusTrain.eigenvalue) from the small box's centre.
usage: rightmost.py SETFILE IDX n v mu [j ...]"""
import json, sys, time
import numpy as np
from magnus import MagnusTrain, winding


def count(tr, j, x0, x1, Y0, Y1, N):
    w = winding(tr, j, x0, x1, Y0, N, Y1=Y1)
    return int(round(w[0])) - (1 if (j == 0 and x0 < 0 and Y0 < 0 < Y1) else 0)


def rightmost(tr, j, Y=60.0, N=4000, lo=None, hi=None):
    x1 = max(2.0, 2 * tr.gamma)
    hi = hi if hi is not None else 1.0
    lo = lo if lo is not None else max(tr.asymptote() + 0.05, -1.0)
    if count(tr, j, hi, x1, -Y, Y, N) != 0:
        return {"error": "zeros right of %g" % hi}
    if count(tr, j, lo, x1, -Y, Y, N) == 0:
        return {"none_right_of": lo}
    while hi - lo > 2e-3:
        m = 0.5 * (lo + hi)
        if count(tr, j, m, x1, -Y, Y, N) > 0:
            lo = m
        else:
            hi = m
    # the zeros in the strip [lo, x1]: their sum by the first moment, one half-plane at a time
    # (a class-0 pair is conjugate: the upper half holds one of them)
    from magnus import moment
    y0 = 1e-9 if j == 0 else -Y
    w1, w2, z, d = winding(tr, j, lo, x1, y0, N, Y1=Y, samples=True)
    k = int(round(w1))
    if k != 1:
        return {"strip": [lo, hi], "zeros_in_strip": k, "sum": moment(z, d)}
    s0 = moment(z, d)
    e = tr.eigenvalue(s0, j)
    e["moment"] = s0
    e["strip"] = [lo, hi]
    return e


if __name__ == "__main__":
    st = json.load(open(sys.argv[1]))[int(sys.argv[2])]
    n, v, mu = int(sys.argv[3]), float(sys.argv[4]), float(sys.argv[5])
    js = [int(a) for a in sys.argv[6:]] or list(range(n // 2 + 1))
    tr = MagnusTrain(st["gamma"], st["c"], st["nu"], st["S"], n, v, mu)
    print("asymptote", tr.asymptote(), "translation |D(0)|", abs(tr.D(0.0, 0)), flush=True)
    for j in js:
        t0 = time.time()
        print(j, rightmost(tr, j), "%.0fs" % (time.time() - t0), flush=True)

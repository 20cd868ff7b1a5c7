"""Ctrl-C never crashes (issue 32 item 3): every product of the catalogue,
interrupted 30 times by a real SIGINT at moments spread over the call (one
at a random point of each 30th of 1.2 times its length: as even a cover as
50 uniform draws, which left gaps and cost 40 s of pytest's 54 s of CPU),
leaves the process alive, and the next call gives the uninterrupted call's
table.

Each product runs in its own process (a crash is its exit status, not the
test runner's), at inputs small enough for a call of 0.01-0.3 s: the
interrupts land in the C call, in the JSON decoding and between calls."""
import json
import os
import subprocess
import sys

import pytest

from conftest import sigint_default

# Small inputs, each a product's usual shape (sweep is TSV only: not
# reachable from Python, see docs/python.md).
PRODUCTS = {
    "period": dict(mu="1:100:40", nu=0.5),
    "speeds": dict(gamma=2, c=0.3, nu=-0.96, S=20),
    "branch": dict(param="S", from_=21, to=20.5, n=6, gamma=1.5, c=0.3, nu=-0.96),
    "stability": dict(gamma=2, c=0.3, nu=-0.96, S=20, n=4, tol=1e-4),
    "asymptotics": dict(grid=True, mu="10:100:20", nu="-0.5,0.5"),
    "profile": dict(nu=0.5, mu=10),
    "floquet": dict(gamma=2, c=0.3, nu=-0.94, q="0.5:3:24"),
    "simulate": dict(N=64, tmax=50, frames=2),
    "check": dict(n=4, tmax=10, N=128),
    "friction": dict(points=3000),
    "bench": dict(product="pde", quick=True),
    # N 72 (8 points a cell, the least mode j = 9 allows): 0.26 s a call
    # against 0.9 s at the default 288, which made this product 29 of the
    # suite's 78 s of pytest CPU
    "orbit": dict(max_points=4, no_stability=True, N=72),
}

CALLS = 30

SCRIPT = r"""
import json, os, random, signal, sys, threading, time
import numpy as np
import bkfront

name, keys, calls = sys.argv[1], json.loads(sys.argv[2]), int(sys.argv[3])


def run():
    return bkfront.product(name, **keys)


def same(a, b):
    # bench's timings are the one column that differs from run to run
    return a.columns == b.columns and all(
        np.array_equal(a[c], b[c], equal_nan=a[c].dtype.kind == "f")
        for c in a.columns if c != "cpu_seconds")


ref = run()
t0 = time.monotonic()
run()
duration = time.monotonic() - t0  # the second call: no first-call costs
rng = random.Random(7)
interrupted = completed = 0
for i in range(calls):
    fired = threading.Event()
    delay = (i + rng.random()) / calls * 1.2 * duration

    def kill():
        time.sleep(delay)
        os.kill(os.getpid(), signal.SIGINT)
        fired.set()

    try:  # a signal anywhere in the loop is one the test sent: not a failure
        threading.Thread(target=kill).start()
        try:
            run()
            completed += 1
        except KeyboardInterrupt:
            interrupted += 1
        while not fired.is_set():
            time.sleep(0.001)
        time.sleep(0.002)  # a signal after the call lands here
    except KeyboardInterrupt:
        while not fired.is_set():
            time.sleep(0.001)
print(json.dumps({"duration": duration, "interrupted": interrupted, "completed": completed,
                  "same": same(run(), ref)}))
"""


def keyword_json(keys):
    return json.dumps(keys)


@pytest.mark.parametrize("name", sorted(PRODUCTS))
def test_interrupted_calls_never_crash(name):
    p = subprocess.run([sys.executable, "-c", SCRIPT, name, keyword_json(PRODUCTS[name]),
                        str(CALLS)], capture_output=True, text=True, timeout=300,
                       env=dict(os.environ), preexec_fn=sigint_default)
    assert p.returncode == 0, "exit %d after interrupts: %s" % (p.returncode, p.stderr[-2000:])
    r = json.loads(p.stdout.strip().splitlines()[-1])
    print(name, r)
    assert r["same"], "the call after %d interrupts differs from the first" % CALLS
    # the interrupts did land during calls, not only between them
    assert r["interrupted"] >= CALLS // 4, r


def test_every_product_is_exercised():
    import bkfront
    assert set(PRODUCTS) | {"sweep"} == set(bkfront.products())


REPRODUCER = r"""
import os, random, signal, sys, threading, time
import bkfront

rng = random.Random(11)
interrupted = 0
for i in range(int(sys.argv[1])):
    fired = threading.Event()
    delay = 0.05 + 0.35 * (i + rng.random()) / int(sys.argv[1])

    def kill():
        time.sleep(delay)
        os.kill(os.getpid(), signal.SIGINT)
        fired.set()

    try:
        threading.Thread(target=kill).start()
        t0 = time.monotonic()
        try:
            bkfront.product("period", mu="1:100:1000000", nu="0.5")
        except KeyboardInterrupt:
            interrupted += 1
            waited = time.monotonic() - t0 - delay
            assert waited < 0.5, "the library took %.2f s to stop" % waited
        while not fired.is_set():
            time.sleep(0.001)
        time.sleep(0.002)
    except KeyboardInterrupt:
        while not fired.is_set():
            time.sleep(0.001)
T = bkfront.product("period", mu=1, nu=0, tol=1e-12)["T"][0]
print(interrupted, abs(T - 6.6632868593231301897))
"""


def test_the_issue_reproducer_stops_at_once_and_never_crashes():
    # issue 32: a million-point period, its 8 MB mu list freed under the
    # library after Ctrl-C, segfaulted in 1 of 2-6 runs
    p = subprocess.run([sys.executable, "-c", REPRODUCER, str(CALLS)], capture_output=True,
                       text=True, timeout=300, env=dict(os.environ),
                       preexec_fn=sigint_default)
    assert p.returncode == 0, "exit %d: %s" % (p.returncode, p.stderr[-2000:])
    interrupted, error = p.stdout.split()
    assert int(interrupted) == CALLS and float(error) < 1e-11

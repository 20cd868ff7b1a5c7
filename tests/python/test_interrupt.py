"""Ctrl-C never crashes (issue 32 item 3): every product of the catalogue,
interrupted by real SIGINTs at moments spread over the call (one at a
random point of each k-th of it, or of 1.2 times it), leaves the process
alive, and the next call gives the uninterrupted call's table.  A product
that polls the cancel flag must have stopped there (the KeyboardInterrupt's
cause is the library's Cancelled) in some of those calls; one that has no
cancel point never does (it runs to its end, then KeyboardInterrupt).

Each product runs in its own process, forked from one that imported the
package once (a crash is the child's exit status, not the test runner's),
at inputs small enough for a call of 0.01-0.1 s: the interrupts land in
the C call, in the JSON decoding and between calls.

What Ctrl-C meets differs by product only where the catalogue's adapter
(src/products/catalog.c) hands the product its hooks and where the spec
owns memory; the Python side is one path (bkfront._run).  Each path's
representative takes 30 interrupts (as even a cover as 50 uniform draws);
a product that shares its path takes 4, which still catch a crash, a
changed table and a path that is no longer the one named here."""
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
    # a seeded front on a grid too coarse for it: the warning comes through
    # the warn callback, in the worker thread, while Ctrl-C may land
    "simulate": dict(N=32, tmax=20, frames=2, init="front:n=6"),
    # the one root of n = 1 on a ring S 5 (0.04 s a call against 0.07 s for
    # n = 4 on S 20); its undecided growth a warning through check's hooks
    "check": dict(n=1, S=5, tmax=10, N=64),
    "friction": dict(points=3000),
    "bench": dict(product="pde", quick=True),
    # the paper's q_9 = 2 pi 9/20 as mode j = 1 of a ring S = 20/9, a
    # chain of 8 blocks: 0.08 s a call against 0.26 s for S 20, N 72
    # (whose first half polls no cancel flag), the same cancel points
    "orbit": dict(max_points=4, no_stability=True, model="chain", N=8, S=20 / 9, j=1),
}

# The paths: the cancel flag polled by the product's own loops (CANCELS),
# or ignored, the call running to its end; the spec's own memory, freed by
# whichever thread drops it last; the warn callback into Python.
CANCELS = {"period", "orbit", "simulate", "check"}
REPRESENTS = {
    "period": "the cancel flag between points; the spec owns the mu list",
    "orbit": "the cancel flag in the continuation and its Newton-Krylov solves; progress",
    "simulate": "the cancel flag at each step; progress; a warning through the warn callback",
    "check": "the cancel flag between roots (OpenMP threads) and in their simulations; "
             "a warning through its hooks",
    "floquet": "no cancel point; the spec owns lists (its q); a warn callback set "
               "(called here by simulate's and check's paths only)",
}
# product: the representative of its path
SHARES = {
    "profile": "floquet",      # no cancel point, lists owned; a 340 kB table to decode
    "asymptotics": "floquet",  # no cancel point, lists owned (approx_free)
    "speeds": "floquet",       # no cancel point, a warn callback, nothing owned
    "branch": "floquet",       # no cancel point, nothing owned
    "stability": "floquet",
    "friction": "floquet",     # a 400 kB table to decode
    "bench": "floquet",
}

# Moments over 1.2 times a representative's call (the last few between
# calls), over the call itself for the products sharing a path.
CALLS = 30
SHARED_CALLS = 4

SERVER = r"""
import json, os, random, signal, statistics, sys, tempfile, threading, time, traceback
import numpy as np
import bkfront


def same(a, b):
    # bench's timings are the one column that differs from run to run
    return a.columns == b.columns and all(
        np.array_equal(a[c], b[c], equal_nan=a[c].dtype.kind == "f")
        for c in a.columns if c != "cpu_seconds")


def interrupt(name, keys, calls, span):
    def run():
        return bkfront.product(name, **keys)

    t0 = time.monotonic()
    ref = run()
    t1 = time.monotonic()
    run()
    whole = [t1 - t0, time.monotonic() - t1]
    # the shorter first call, then the median of the whole calls: a call
    # slowed by a busy machine does not spread the moments past the calls
    duration = min(whole)
    rng = random.Random(7)
    interrupted = canceled = completed = 0
    for i in range(calls):
        fired = threading.Event()
        delay = (i + rng.random()) / calls * span * duration

        def kill():
            time.sleep(delay)
            os.kill(os.getpid(), signal.SIGINT)
            fired.set()

        try:  # a signal anywhere in the loop is one the test sent: not a failure
            threading.Thread(target=kill).start()
            try:
                t0 = time.monotonic()
                run()
                completed += 1
                whole.append(time.monotonic() - t0)
                duration = statistics.median(whole)
            except KeyboardInterrupt as e:
                interrupted += 1
                # the library stopped at a cancel point, not at its end
                canceled += isinstance(e.__cause__, bkfront.Cancelled)
            while not fired.is_set():
                time.sleep(0.001)
            time.sleep(0.002)  # a signal after the call lands here
        except KeyboardInterrupt:
            while not fired.is_set():
                time.sleep(0.001)
    return {"duration": duration, "interrupted": interrupted, "canceled": canceled,
            "completed": completed, "same": same(run(), ref)}


# The children are forked before any product ran here: no thread (the
# library's OpenMP pool included) exists to be lost in the fork.
for name, keys, calls, span in json.loads(sys.argv[1]):
    r, w = os.pipe()
    err = tempfile.TemporaryFile()
    pid = os.fork()
    if pid == 0:
        code = 1
        try:
            os.close(r)
            os.dup2(err.fileno(), 2)  # this product's messages apart
            os.write(w, json.dumps(interrupt(name, keys, calls, span)).encode())
            code = 0
        except BaseException:
            traceback.print_exc()
        finally:
            os._exit(code)
    os.close(w)
    out = b""
    while True:
        chunk = os.read(r, 65536)
        if not chunk:
            break
        out += chunk
    os.close(r)
    _, status, use = os.wait4(pid, 0)
    err.seek(0)
    print(json.dumps({"name": name, "status": os.waitstatus_to_exitcode(status),
                      "cpu": use.ru_utime + use.ru_stime,
                      "stderr": err.read().decode(errors="replace")[-2000:],
                      "result": json.loads(out) if out else None}), flush=True)
    err.close()
"""


@pytest.fixture(scope="module")
def interrupted(request):
    """{product: its child's record} for the products this session tests,
    all from one process."""
    names = [item.callspec.params["name"] for item in request.session.items
             if getattr(item, "originalname", None) == "test_interrupted_calls_never_crash"]
    plan = [[n, PRODUCTS[n]] + ([CALLS, 1.2] if n in REPRESENTS else [SHARED_CALLS, 1.0])
            for n in names]
    p = subprocess.run([sys.executable, "-c", SERVER, json.dumps(plan)], capture_output=True,
                       text=True, timeout=600, env=dict(os.environ), preexec_fn=sigint_default)
    records = {}
    for line in p.stdout.splitlines():
        r = json.loads(line)
        records[r["name"]] = r
    return records, p.returncode, p.stderr


@pytest.mark.parametrize("name", sorted(PRODUCTS))
def test_interrupted_calls_never_crash(name, interrupted):
    records, code, stderr = interrupted
    assert name in records, "the forking process ended (exit %d) before %s: %s" % (
        code, name, stderr[-2000:])
    status, r = records[name]["status"], records[name]["result"]
    assert status == 0, "exit %d after interrupts: %s" % (status, records[name]["stderr"])
    print(name, "%.2f s CPU" % records[name]["cpu"], r)
    calls = CALLS if name in REPRESENTS else SHARED_CALLS
    assert r["same"], "the call after %d interrupts differs from the first" % calls
    # the interrupts did land during calls, not only between them
    assert r["interrupted"] >= calls // 4, r
    if name in CANCELS:
        # ... and the product stopped at its cancel points, mid-work
        assert r["canceled"] >= max(1, calls // 6), r
    else:
        assert r["canceled"] == 0, "%s stopped at a cancel point: move it to CANCELS" % name


def test_every_product_is_exercised():
    import bkfront
    assert set(PRODUCTS) | {"sweep"} == set(bkfront.products())
    # each product on one path, each path's representative in full
    assert set(REPRESENTS) | set(SHARES) == set(PRODUCTS)
    assert not set(REPRESENTS) & set(SHARES)
    assert set(SHARES.values()) <= set(REPRESENTS) - CANCELS
    assert CANCELS <= set(REPRESENTS)


REPRODUCER = r"""
import os, random, signal, sys, threading, time
import bkfront

calls = int(sys.argv[1])
rng = random.Random(11)
interrupted = canceled = 0
for i in range(calls):
    fired = threading.Event()
    sent = []
    # once the worker runs (the call is past its 8 MB mu list, in the
    # library), at a moment spread over its first 0.02 s (some hundreds of
    # its points)
    delay = 0.02 * (i + rng.random()) / calls

    def kill():
        while len(sys._current_frames()) < 3:  # the main thread, this one, the worker
            time.sleep(0.0002)
        time.sleep(delay)
        sent.append(time.monotonic())
        os.kill(os.getpid(), signal.SIGINT)
        fired.set()

    killer = threading.Thread(target=kill, daemon=True)  # a failure ends the process
    try:
        killer.start()
        try:
            bkfront.product("period", mu="1:100:1000000", nu="0.5")
        except KeyboardInterrupt as e:
            interrupted += 1
            canceled += isinstance(e.__cause__, bkfront.Cancelled)
            waited = time.monotonic() - sent[0]
            assert waited < 0.5, "the library took %.2f s to stop" % waited
        while not fired.is_set():
            time.sleep(0.001)
        time.sleep(0.002)
    except KeyboardInterrupt:
        while not fired.is_set():
            time.sleep(0.001)
    killer.join()  # this thread and the worker gone before the next call's count
    while len(sys._current_frames()) > 1:
        time.sleep(0.0002)
T = bkfront.product("period", mu=1, nu=0, tol=1e-12)["T"][0]
print(interrupted, canceled, abs(T - 6.6632868593231301897))
"""


def test_the_issue_reproducer_stops_at_once_and_never_crashes():
    # issue 32: a million-point period, its 8 MB mu list freed under the
    # library after Ctrl-C, segfaulted in 1 of 2-6 runs
    p = subprocess.run([sys.executable, "-c", REPRODUCER, str(CALLS)], capture_output=True,
                       text=True, timeout=300, env=dict(os.environ),
                       preexec_fn=sigint_default)
    assert p.returncode == 0, "exit %d: %s" % (p.returncode, p.stderr[-2000:])
    interrupted, canceled, error = p.stdout.split()
    # every signal landed in the library, which stopped at its cancel point
    assert int(interrupted) == int(canceled) == CALLS and float(error) < 1e-11

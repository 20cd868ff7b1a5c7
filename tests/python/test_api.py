"""The Python package against independent values (published, closed forms,
symmetry, the speed condition) and against the CLI for the same inputs."""
import math
import os
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

import bkfront
from conftest import sigint_default, tsv

# T(1, 0) of the van der Pol oscillator, published to 29 digits.
T_1_0 = 6.6632868593231301896996820305


def test_period_matches_the_published_value():
    T, err = bkfront.period(1, 0, errors=True)
    assert isinstance(T, float)
    assert abs(T - T_1_0) <= err <= 1e-10 * T


def test_period_is_vectorised_and_symmetric_in_nu():
    mu = np.array([[0.5, 2.0, 8.0], [20.0, 50.0, 100.0]])
    T, err = bkfront.period(mu, 0.5, errors=True)
    assert T.shape == mu.shape == err.shape
    # T(mu, nu) = T(mu, -nu): f -> -f, z -> z maps one cycle onto the other
    T2, err2 = bkfront.period(mu, -0.5, errors=True)
    assert np.all(np.abs(T - T2) <= err + err2)
    # small mu: 2 pi (1 + O(mu^2)); large mu: k(nu) mu to leading order
    assert abs(bkfront.period(1e-3, 0) / (2 * math.pi) - 1) < 1e-5
    k = 3 + (0.25 - 1) * math.log((4 - 0.25) / (1 - 0.25))
    assert abs(bkfront.period(1e4, 0.5, tol=1e-8) / (k * 1e4) - 1) < 1e-2


def test_period_steppers_agree_within_their_estimates():
    # two methods: collocation and shooting (the extrapolation stepper)
    mu = np.array([30.0, 300.0, 3000.0])
    Tc, ec = bkfront.period(mu, -0.5, stepper="collocation", errors=True)
    Ts, es = bkfront.period(mu, -0.5, stepper="extrapolation", errors=True)
    assert np.all(np.abs(Tc - Ts) <= ec + es)
    with pytest.raises(bkfront.InputError, match="collocation"):
        bkfront.period(1, 0, stepper="spectral")


def test_period_equals_the_cli(cli):
    out = cli("period", "--mu", "0.5:40:9", "--nu", "-0.3").stdout
    cols, rows = tsv(out)
    mu = np.array([float(r["mu"]) for r in rows])
    T = bkfront.period(mu, -0.3)
    # the same solves in the same order (each from the previous cycle): bit for bit
    assert T.tolist() == [float(r["T"]) for r in rows]


def test_speeds_is_the_cli_table(cli):
    t = bkfront.speeds(2, 0.3, -0.96, 20)
    cols, rows = tsv(cli("speeds", "--gamma", 2, "--c", 0.3, "--nu", -0.96, "--S", 20).stdout)
    assert t.columns == cols and len(t) == len(rows) == 12
    for name in cols:
        for i, row in enumerate(rows):
            value = t[name][i]
            if t[name].dtype.kind == "U":
                assert value == row[name]
            else:
                assert value == float(row[name]), (name, i)
    assert t.results["n_max"] == 12
    assert t.to_records()["v"][5] == t["v"][5]


def test_speeds_satisfy_the_speed_condition_and_the_paper():
    gamma, c, nu, S = 2, 0.3, -0.96, 20
    t = bkfront.speeds(gamma, c, nu, S)
    v, n = t["v"], t["n"]
    root = np.sqrt(1 - c**2 / v**2)
    # the condition n T(mu(v)) = S / (v sqrt(1 - c^2/v^2)), T solved afresh
    T = bkfront.period(gamma / root, nu)
    assert np.all(np.abs(n * T * v * root / S - 1) < 1e-9)
    # the paper's Fig. 3(b): six fronts at v_6 = 0.3750
    assert round(float(v[n == 6][0]), 4) == 0.3750


def test_speeds_refused_rows_stay_rows_with_a_warning():
    # issue 31, R1: a root that cannot be had to tol stays a row flagged
    # refused (v nan), every other row stands (a root of the condition),
    # and a RuntimeWarning says why.  The paper's parameters at tol 1e-13
    # refuse n = 1 (had to 1e-12: docs/cli/speeds.md) in 0.05 s; the
    # issue's canard point (0.9 s) is the CLI's test and the page's example.
    gamma, c, nu, S = 2, 0.3, -0.96, 20
    with pytest.warns(RuntimeWarning, match="roots refused"):
        t = bkfront.speeds(gamma, c, nu, S, tol=1e-13)
    refused = np.char.find(t["flags"], "refused") >= 0
    assert t.results["refused"] == refused.sum() >= 1
    assert np.all(np.isnan(t["v"][refused])) and np.all(t["model"][refused] == "")
    v, n = t["v"][~refused], t["n"][~refused]
    root = np.sqrt(1 - c**2 / v**2)
    T = bkfront.period(gamma / root, nu)
    assert len(v) >= 8 and np.all(np.abs(n * T * v * root / S - 1) < 1e-8)


def test_floquet_threshold_is_the_period_doubling(cli):
    t = bkfront.floquet(2, 0.3, threshold=True)
    cols, rows = tsv(cli("floquet", "--gamma", 2, "--c", 0.3, "--threshold").stdout)
    assert t["nu_pd"][0] == float(rows[0]["nu_pd"])
    assert t["kind"][0] == "period_doubling"
    # the paper: stable at nu = -0.92, unstable at -0.94 (Fig. 4a)
    assert -0.94 < t["nu_pd"][0] < -0.92
    # at the threshold the critical multiplier is -1
    assert abs(t["m_c_re"][0] + 1) < 1e-8
    # dispersion: lambda > 0 near q_c only below the threshold
    below = bkfront.floquet(2, 0.3, nu=-0.94, q=[2.89])
    above = bkfront.floquet(2, 0.3, nu=-0.92, q=[2.89])
    assert below["lambda"][0] > 0 > above["lambda"][0]


def test_branch_and_stability_equal_the_cli(cli):
    keys = dict(param="S", to=19, n=6, gamma=1.5, c=0.3, nu=-0.96, tol=1e-8)
    t = bkfront.branch(from_=21, **keys)
    flags = [a for k, v in keys.items() for a in ("--" + k, v)]
    cols, rows = tsv(cli("branch", "--from", 21, *flags).stdout)
    assert t.columns == cols and len(t) == len(rows) > 2
    assert t["v"].tolist() == [float(r["v"]) for r in rows]
    # one fold in S in [19, 21], at S = 19.956758 (docs/library.md): S turns back there
    folds = t["S"][t["point"] == "fold"]
    assert len(folds) == 1 and abs(folds[0] - 19.956758) < 1e-5
    i = int(np.argmax(t["point"] == "fold"))
    assert np.sign(t["S"][i] - t["S"][i - 1]) != np.sign(t["S"][i + 1] - t["S"][i])

    s = bkfront.stability(gamma=2, c=0.3, nu=-0.96, S=20, n=4)
    cols, rows = tsv(cli("stability", "--gamma", 2, "--c", 0.3, "--nu", -0.96, "--S", 20,
                         "--n", 4).stdout)
    assert s.columns == cols and len(s) == len(rows) > 0
    assert s["re"].tolist() == [float(r["re"]) for r in rows]
    # the translation mode: sigma = 0 within its error
    tr = s["translation"] == 1
    assert np.all(np.abs(s["re"][tr]) <= s["err"][tr])
    # n = 4 at the paper's parameters is stable (README): every other Re sigma < 0
    assert np.all(s["re"][~tr] < 0)


def test_simulate_returns_the_field(cli, tmp_path):
    keys = ["--N", 32, "--tmax", 2, "--frames", 4, "--init", "uniform"]
    st = tmp_path / "st.txt"
    cli("simulate", *keys, "--spacetime", st, "--out", tmp_path / "d.tsv")
    t = bkfront.simulate(N=32, tmax=2, frames=4, init="uniform")
    ref = np.loadtxt(st, comments="#")
    assert t.psi.shape == (len(t.t), 32) and len(t.x) == 32
    assert np.array_equal(t.psi, ref[1:, 1:]) and np.array_equal(t.t, ref[1:, 0])
    # the grid: x_i = i S / N on the ring of size S = 20
    assert np.allclose(t.x, np.arange(32) * 20 / 32)
    assert t.t[0] == 0 and t.t[-1] == 2


def test_errors_are_exceptions_of_their_class():
    with pytest.raises(bkfront.InputError, match="nu") as e:
        bkfront.period(1, 1.5)
    assert isinstance(e.value, ValueError) and e.value.status_name
    with pytest.raises(ValueError, match="tol"):
        bkfront.speeds(2, 0.3, -0.96, 20, tol=1e-20)
    with pytest.raises(ValueError, match="frobnicate"):
        bkfront.product("speeds", gamma=2, c=0.3, nu=-0.96, S=20, frobnicate=1)
    # a formula asked for outside its validity is a numerical refusal
    with pytest.raises(bkfront.NumericalError) as e:
        bkfront.period(1, 0, method="leading")
    assert not isinstance(e.value, ValueError)
    assert "error bound" in str(e.value)


def test_ctrl_c_cancels_a_long_call():
    # a run of 1e5 time units (minutes): a SIGINT from outside, sent once the
    # worker thread runs (the call is in the library), stops it at the
    # library's cancel point (the KeyboardInterrupt's cause) within seconds
    code = ("import bkfront, sys, threading, time\n"
            "def running():\n"
            "    while len(sys._current_frames()) < 3:  # main, this thread, the worker\n"
            "        time.sleep(0.001)\n"
            "    print('running', flush=True)\n"
            "threading.Thread(target=running).start()\n"
            "try:\n"
            "    bkfront.simulate(N=4096, tmax=1e5, frames=2)\n"
            "except KeyboardInterrupt as e:\n"
            "    print('interrupted:', repr(e.__cause__), flush=True)\n"
            "    sys.exit(3)\n")
    p = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True,
                         env=dict(os.environ), preexec_fn=sigint_default)
    try:
        assert p.stdout.readline().strip() == "running"
        t0 = time.time()
        p.send_signal(signal.SIGINT)
        out, _ = p.communicate(timeout=30)
    finally:  # a child that missed the signal would run its 1e5 time units on
        if p.poll() is None:
            p.kill()
            p.wait()
    assert p.returncode == 3, out
    assert "interrupted: Cancelled(" in out, out
    assert time.time() - t0 < 5


def test_a_column_is_typed_by_its_kind_never_by_its_values():
    # issue 32: t was int64 at frames=5 (t = 0, 1, ...), float64 at frames=10
    for frames in (5, 10):
        assert bkfront.simulate(tmax=5, N=32, frames=frames)["t"].dtype == np.float64
    f = bkfront.product("friction")
    assert f["v"].dtype == np.float64  # was int64: its values are whole numbers
    full = bkfront.speeds(2, 0.3, -0.96, 20)
    empty = bkfront.speeds(2, 0.3, -0.96, 20, n=13)  # n_max 12: no root
    assert len(empty) == 0 and empty.columns == full.columns
    for name in full.columns:
        assert empty[name].dtype.kind == full[name].dtype.kind, name
    assert full["n"].dtype == np.float64 and full["model"].dtype.kind == "U"
    assert full["flags"].dtype.kind == "U" and empty.kinds == full.kinds


def test_text_with_a_nul_and_a_name_that_is_no_str_are_refused():
    # '20\x00junk' read as 20 through the C string before
    with pytest.raises(bkfront.InputError, match="NUL"):
        bkfront.speeds(2, 0.3, -0.96, "20\x00junk")
    with pytest.raises(bkfront.InputError, match="NUL"):
        bkfront.product("period", mu="1\x002", nu=0)
    for name in (None, 3, b"period"):
        with pytest.raises(bkfront.InputError, match="name"):
            bkfront.product(name)


def test_messages_name_keys_as_the_keywords_they_are():
    # issue 36: branch() said "from is required" though its keyword is from_
    with pytest.raises(bkfront.InputError) as e:
        bkfront.branch(param="S", to=5, n=6, gamma=1.5, c=0.3, nu=-0.96, S=30)
    assert "from_ is required" in str(e.value)
    with pytest.raises(bkfront.InputError, match=r"^stability_tol: "):
        bkfront.speeds(2, 0.3, -0.96, 20, stability_tol=-1)
    with pytest.raises(bkfront.InputError, match=r"^frobnicate: not a key of speeds"):
        bkfront.speeds(2, 0.3, -0.96, 20, frobnicate=1)

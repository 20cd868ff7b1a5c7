"""bkfront.orbit: the same table as the CLI, and its switch point where
floquet puts the multiplier at -1."""
import math

import pytest

import bkfront
from conftest import tsv

# N 72, the least mode j = 9 allows (0.27 s a call against 0.97 at the
# default 288): the switch point is floquet's, the same on every N
ARGS = dict(max_points=4, no_stability=True, N=72)


@pytest.fixture(scope="module")
def table():
    """One call's table, which both tests read (0.26 s of CPU a call)."""
    return bkfront.orbit(**ARGS)


def test_orbit_equals_the_cli(cli, table):
    t = table
    cols, rows = tsv(cli("orbit", "--max-points", 4, "--no-stability", "--N", 72).stdout)
    assert list(t.columns) == cols
    assert len(t) == len(rows) >= 5
    for i, r in enumerate(rows):
        for c in ("nu", "period", "amplitude", "mode_amp"):
            a, b = t[c][i], float(r[c])
            assert (math.isnan(a) and math.isnan(b)) or a == b, (c, i, a, b)
        assert t["kind"][i] == r["kind"]
    assert t.results["j"] == 9


def test_orbit_starts_where_floquet_has_minus_one(table):
    t = table
    nu, j = t.results["p_pd"], int(t.results["j"])
    q = 2 * math.pi * j / 20
    d = bkfront.floquet(2, 0.3, nu=nu, q=[q])
    # floquet's dispersion, an independent call, puts mode j on the unit circle at -1
    assert abs(d["lambda"][0]) < 1e-8
    assert abs(d["m1_re"][0] + 1) < 1e-8
    # below the continuum's threshold q_c (the ring's mode is not q_c)
    th = bkfront.floquet(2, 0.3, threshold=True)
    assert nu < th["nu_pd"][0] < nu + 1e-3

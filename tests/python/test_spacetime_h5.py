"""The HDF5 spacetime file (bkfront simulate --spacetime FILE.h5) read back
with h5py: the same numbers as the text spacetime and the snapshots of the
same run, t and x as dimension scales, the parameters as attributes."""
import numpy as np
import pytest

h5py = pytest.importorskip("h5py")

RUN = ["simulate", "--gamma", "1.5", "--c", "0.4", "--nu", "-0.93", "--S", "16", "--N", "96",
       "--tmax", "6", "--frames", "12", "--init", "uniform:amp=0.01", "--seed", "7",
       "--no-progress"]


@pytest.fixture(scope="module")
def outputs(cli, tmp_path_factory):
    d = tmp_path_factory.mktemp("spacetime")
    cli(*RUN, "--spacetime", d / "st.h5", "--spacetime-fields", "psi,eta",
        "--snapshots", d / "snap.tsv", "--snapshot-count", "13", "--out", d / "diag.tsv")
    cli(*RUN, "--spacetime", d / "st.dat", "--out", d / "diag_text.tsv")
    cli(*RUN, "--spacetime", d / "st.hdf", "--spacetime-format", "hdf5",
        "--spacetime-deflate", "9", "--out", d / "diag_deflate.tsv")
    return d


def test_psi_equals_the_text_spacetime(outputs):
    text = np.loadtxt(outputs / "st.dat", comments="#", ndmin=2)
    with h5py.File(outputs / "st.h5", "r") as f:
        psi, t, x = f["psi"][...], f["t"][...], f["x"][...]
    assert psi.dtype == np.float32 and psi.shape == (13, 96)
    # text is float32 printed with %.9g, which reads back exactly
    assert np.array_equal(psi, text[1:, 1:].astype(np.float32))
    assert np.array_equal(t, text[1:, 0])
    assert np.allclose(x, text[0, 1:], rtol=1e-8, atol=0)
    assert np.allclose(x, np.arange(96) * 16 / 96, rtol=0, atol=1e-12)


def test_eta_equals_the_snapshots(outputs):
    """One snapshot per frame: eta written by another path (TSV, %.17g)."""
    lines = [l for l in open(outputs / "snap.tsv").read().split("\n")
             if l and not l.startswith("#")]
    assert lines[0].split("\t") == ["t", "x", "psi", "eta"]
    values = np.array([[float(v) for v in l.split("\t")] for l in lines[1:]])
    snap = {k: values[:, i] for i, k in enumerate(["t", "x", "psi", "eta"])}
    with h5py.File(outputs / "st.h5", "r") as f:
        eta, psi, t = f["eta"][...], f["psi"][...], f["t"][...]
    frames = np.unique(snap["t"])
    assert np.array_equal(frames, t)
    for k, tk in enumerate(frames):
        rows = snap["t"] == tk
        assert np.array_equal(eta[k], snap["eta"][rows].astype(np.float32))
        assert np.array_equal(psi[k], snap["psi"][rows].astype(np.float32))


def test_dimension_scales_and_attributes(outputs):
    with h5py.File(outputs / "st.h5", "r") as f:
        for name in ("psi", "eta"):
            d = f[name]
            assert [dim.label for dim in d.dims] == ["t", "x"]
            assert d.dims[0][0].name == "/t" and d.dims[1][0].name == "/x"
            assert d.chunks is not None
        assert f["t"].attrs["CLASS"] == b"DIMENSION_SCALE"
        a = dict(f.attrs)
    want = {"gamma": 1.5, "c": 0.4, "nu": -0.93, "S": 16.0, "N": 96, "tmax": 6.0,
            "frames": 12, "seed": 7, "tol": 1e-9, "model": "continuum", "stepper": "rk8pd",
            "init": "uniform:amp=0.01", "dealias": 0, "filter": 4.0}
    for k, v in want.items():
        assert a[k] == v, k
    assert "interrupted" not in a
    assert a["command"].startswith("bkfront simulate --gamma 1.5")
    # the level is the diagnostics' own
    diag = open(outputs / "diag.tsv").read()
    level = float(diag.split("fronts are crossings of psi = ")[1].split()[0])
    assert abs(level - a["level"]) <= 1e-6 * abs(level)


def test_deflate_changes_the_bytes_not_the_numbers(outputs):
    with h5py.File(outputs / "st.h5", "r") as a, h5py.File(outputs / "st.hdf", "r") as b:
        assert b["psi"].compression == "gzip" and b["psi"].compression_opts == 9
        assert b["psi"].shuffle and a["psi"].compression is None
        assert np.array_equal(a["psi"][...], b["psi"][...])
        assert "eta" not in b


def test_the_diagnostics_do_not_depend_on_the_spacetime_format(outputs):
    def rows(name):
        return [l for l in open(outputs / name).read().split("\n") if not l.startswith("#")]
    assert rows("diag.tsv") == rows("diag_text.tsv") == rows("diag_deflate.tsv")


def test_xarray_reads_it(outputs):
    xr = pytest.importorskip("xarray")
    ds = xr.open_dataset(outputs / "st.h5", engine="h5netcdf")
    assert ds["psi"].dims == ("t", "x")
    assert ds.attrs["gamma"] == 1.5


def test_the_python_package_writes_the_same_file(outputs, tmp_path):
    import bkfront
    path = tmp_path / "py.h5"
    keys = {k.lstrip("-").replace("-", "_"): v for k, v in zip(RUN[1::2], RUN[2::2])
            if k != "--no-progress"}
    table = bkfront.simulate(spacetime=str(path), spacetime_fields="psi,eta", **keys)
    assert len(table) == 13 and not hasattr(table, "psi")
    with h5py.File(path, "r") as a, h5py.File(outputs / "st.h5", "r") as b:
        for name in ("psi", "eta", "t", "x"):
            assert np.array_equal(a[name][...], b[name][...]), name
        assert a.attrs["gamma"] == 1.5
    # the message names the key as the keyword it is (issue 36)
    with pytest.raises(bkfront.InputError, match="^spacetime_fields: "):
        bkfront.simulate(spacetime=str(tmp_path / "st.dat"), spacetime_fields="eta", tmax=1)

"""bkfront sweep --format json: the finished table as JSON holds what the
TSV table of the same sweep holds (comments, columns, every cell; nan as
null), and the table's definition names the N its rows use."""
import json
import math
import re

from conftest import tsv

BASE = ["--x", "nu=-0.96,-0.9", "--seeds", "1,2", "--tmax", "2", "--no-progress"]
# N 64: what is compared is the table's form, not the runs (0.06 s a sweep
# against 0.46 at the default 512)
GRID = BASE + ["--N", "64"]


def _cells_equal(text, value):
    if value is None:
        return text == "nan"
    if isinstance(value, str):
        return text == value
    return float(text) == value


def test_json_is_the_tsv_table(cli, tmp_path):
    cli("sweep", *GRID, "--out", tmp_path / "t.tsv")
    cli("sweep", *GRID, "--out", tmp_path / "t.json", "--format", "json")
    text = (tmp_path / "t.tsv").read_text()
    doc = json.loads((tmp_path / "t.json").read_text())
    cols, rows = tsv(text)
    assert doc["columns"] == cols
    assert doc["comments"] == [l[2:] for l in text.splitlines() if l.startswith("# ")]
    assert len(doc["rows"]) == len(rows) == 4
    for want, got in zip(rows, doc["rows"]):
        assert list(got) == cols
        for c in cols:
            assert _cells_equal(want[c], got[c]), (c, want[c], got[c])
    assert isinstance(doc["rows"][0]["regime"], str) and isinstance(doc["rows"][0]["N"], int)


def test_json_merge_and_refusals(cli, tmp_path):
    for k in range(2):
        cli("sweep", *GRID, "--task", str(k), "--of", "2", "--out", tmp_path / ("p%d.tsv" % k))
    parts = "%s,%s" % (tmp_path / "p0.tsv", tmp_path / "p1.tsv")
    cli("sweep", "--merge", parts, "--out", tmp_path / "m.json", "--format", "json")
    merged = json.loads((tmp_path / "m.json").read_text())
    assert [r["point"] for r in merged["rows"]] == [0, 1, 2, 3]
    # a task's table and a resumed one stay TSV (they are merged or resumed)
    for extra in (["--task", "0", "--of", "2"], ["--resume"]):
        r = cli("sweep", *GRID, *extra, "--out", tmp_path / "x.json", "--format", "json",
                check=False)
        assert r.returncode == 2 and r.stdout == "" and "--format json" in r.stderr
        assert len(r.stderr.splitlines()) == 1
        assert not (tmp_path / "x.json").exists()


# one point: the N named, not the runs (a run at the default N 512 costs
# what 4 at N 64 do)
ONE = ["--x", "nu=-0.96", "--seeds", "1", "--tmax", "2", "--no-progress"]


def test_definition_names_the_rows_n(cli, tmp_path):
    for extra, n in (([], 512), (["--N", "64"], 64)):
        out = tmp_path / ("n%d.tsv" % n)
        cli("sweep", *ONE, *extra, "--out", out)
        text = out.read_text()
        header_n = re.search(r" N (\S+) model ", text).group(1)
        _, rows = tsv(text)
        assert {r["N"] for r in rows} == {header_n} == {str(n)}
    # the default and the N it stands for are one sweep: --resume accepts it
    r = cli("sweep", *ONE, "--N", "512", "--resume", "--out", tmp_path / "n512.tsv")
    assert r.returncode == 0

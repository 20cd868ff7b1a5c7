"""make install, as a user runs it: an external C program links the
installed library through pkg-config, the installed CLI runs a scene from
another folder with the installed scripts, the installed Python package
imports; and a DESTDIR staging install lands under DESTDIR and uninstalls.

The link test installs with PREFIX a folder of the build's (no DESTDIR):
a DESTDIR tree is made for packaging and its bkfront.pc rightly names the
final PREFIX, while PKG_CONFIG_SYSROOT_DIR or --define-variable=prefix would
also move the system libraries' paths (gsl, fftw3) into the staging folder."""
import os
import shutil
import subprocess
import sys

import pytest

import bkfront
from conftest import SOURCE, tsv
from test_docs_links import dead_links, pages

PROGRAM = r"""
#include <stdio.h>
#include <string.h>
#include "bkfront/bkfront.h"

int main(void)
{
    bkf_error e;
    bkf_cycle_result r;
    if (bkf_cycle_period(1.0, 0.0, NULL, &r, &e) != BKF_OK) { fprintf(stderr, "%s\n", e.message); return 1; }
    printf("%s %.15g %.3g\n", bkf_version(), r.period, r.period_err);
    return 0;
}
"""


def make(*args, **env):
    build = os.environ.get("BKF_BUILD", "build")
    cmd = os.environ.get("BKF_MAKE", "make").split() + ["-C", SOURCE, "--no-print-directory",
                                                       "BUILD=" + build] + list(args)
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=600,
                       env=dict(os.environ, **env))
    assert r.returncode == 0, r.stdout + r.stderr
    return r


# PREFIX is compiled into the installed CLI and man pages (run's --plots),
# which make rebuilds whenever PREFIX changes.  One PREFIX, a folder of the
# build's, the same on every run, for both installs: the staging install
# first, so that what both use is made under a DESTDIR (where a leak of it
# would show), then the real one, which rebuilds nothing (two rebuilds a
# run before, 1.3 s of CPU: a new temporary folder, then /opt/bkf; one on
# a fresh clone now).
@pytest.fixture(scope="module")
def installs(tmp_path_factory):
    """(PREFIX, the DESTDIR staged into)."""
    p = os.path.join(SOURCE, os.environ.get("BKF_BUILD", "build"), "test-prefix")
    shutil.rmtree(p, ignore_errors=True)
    stage = str(tmp_path_factory.mktemp("stage"))
    make("install", "DESTDIR=" + stage, "PREFIX=" + p)
    make("install", "PREFIX=" + p)
    return p, stage


@pytest.fixture(scope="module")
def prefix(installs):
    return installs[0]


def test_external_program_links_through_pkg_config(prefix, tmp_path):
    env = dict(os.environ, PKG_CONFIG_PATH=os.path.join(prefix, "lib", "pkgconfig"))
    flags = subprocess.run(["pkg-config", "--cflags", "--libs", "bkfront"], env=env,
                           capture_output=True, text=True, check=True).stdout.split()
    libdir = subprocess.run(["pkg-config", "--variable=libdir", "bkfront"], env=env,
                            capture_output=True, text=True, check=True).stdout.strip()
    assert libdir == os.path.join(prefix, "lib")
    src = tmp_path / "prog.c"
    src.write_text(PROGRAM)
    exe = tmp_path / "prog"
    # the documented command alone: a PREFIX outside the loader's folders
    # needs no -Wl,-rpath nor LD_LIBRARY_PATH of the user's
    subprocess.run(["cc", "-std=c11", "-Wall", "-Werror", str(src), "-o", str(exe)] + flags,
                   check=True)
    # linked to the shared library by its SONAME, not the archive
    needed = subprocess.run(["readelf", "-d", str(exe)], capture_output=True, text=True).stdout
    assert "[libbkfront.so.0]" in needed
    run_env = {k: v for k, v in os.environ.items() if k != "LD_LIBRARY_PATH"}
    r = subprocess.run([str(exe)], capture_output=True, text=True, env=run_env)
    assert r.returncode == 0, r.stderr
    out = r.stdout.split()
    assert out[0] == bkfront.version()
    assert abs(float(out[1]) - 6.6632868593231302) <= float(out[2])


def test_only_bkf_names_are_exported(prefix):
    lib = os.path.join(prefix, "lib", "libbkfront.so.0")
    assert os.path.islink(lib) and os.readlink(lib).startswith("libbkfront.so.0.")
    soname = subprocess.run(["readelf", "-d", lib], capture_output=True, text=True).stdout
    assert "Library soname: [libbkfront.so.0]" in soname
    nm = subprocess.run(["nm", "-D", "--defined-only", lib], capture_output=True, text=True,
                        check=True).stdout.split("\n")
    names = [l.split()[-1] for l in nm if l.strip()]
    assert len(names) > 100
    assert [n for n in names if not n.startswith("bkf_")] == []
    assert os.path.exists(os.path.join(prefix, "lib", "libbkfront.a"))


def test_installed_cli_runs_a_scene_from_anywhere(prefix, tmp_path):
    cli = os.path.join(prefix, "bin", "bkfront")
    scripts = os.path.join(prefix, "share", "bkfront", "plots")
    help_text = subprocess.run([cli, "run", "--help"], capture_output=True, text=True).stdout
    assert help_text.rstrip().endswith(scripts)
    work = tmp_path / "work"
    elsewhere = tmp_path / "elsewhere"
    work.mkdir()
    elsewhere.mkdir()
    shutil.copy(os.path.join(prefix, "share", "bkfront", "scenes", "fig1b.scene"), work)
    env = {k: v for k, v in os.environ.items() if k != "BKFRONT_PLOTS"}
    r = subprocess.run([cli, "run", str(work / "fig1b.scene")], cwd=elsewhere, env=env,
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    assert sorted(os.listdir(work / "fig1b")) == ["fig1b.pdf", "fig1b.png", "fig1b.tsv"]
    assert os.listdir(elsewhere) == []
    # a failed figure fails the run: a script that gnuplot refuses
    bad = tmp_path / "bad"
    bad.mkdir()
    (bad / "friction.gp").write_text("this is not gnuplot\n")
    r = subprocess.run([cli, "run", "--out", str(tmp_path / "o"), str(work / "fig1b.scene")],
                       env=dict(env, BKFRONT_PLOTS=str(bad)), capture_output=True, text=True)
    assert r.returncode == 1 and "FAILED" in r.stdout
    # a scene's own script needs --trust-scene; nothing is computed without it
    (work / "own.gp").write_text("load plotdir.'/friction.gp'\n")
    (work / "own.scene").write_text(open(work / "fig1b.scene").read() + "script = own.gp\n")
    r = subprocess.run([cli, "run", str(work / "own.scene")], env=env, capture_output=True,
                       text=True)
    assert r.returncode == 2 and "--trust-scene" in r.stderr and not (work / "own").exists()
    r = subprocess.run([cli, "run", "--trust-scene", str(work / "own.scene")], env=env,
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    assert (work / "own" / "fig1b.png").stat().st_size > 0


def test_installed_python_package(prefix, tmp_path):
    site = [os.path.join(prefix, "lib", d, "dist-packages")
            for d in os.listdir(os.path.join(prefix, "lib")) if d.startswith("python")]
    assert len(site) == 1
    env = {k: v for k, v in os.environ.items() if k not in ("BKFRONT_LIBRARY", "PYTHONPATH")}
    env["PYTHONPATH"] = site[0]
    code = "import bkfront; print(bkfront.__file__); print(bkfront.speeds(2, 0.3, -0.96, 20))"
    r = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=env,
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    lines = r.stdout.splitlines()
    assert lines[0].startswith(site[0])
    cols, rows = tsv("\n".join(lines[1:]))
    assert cols[:3] == ["n", "v", "mu"] and len(rows) == 12
    assert round(float(rows[5]["v"]), 4) == 0.3750


def test_installed_manual_links_resolve(prefix):
    root = os.path.join(prefix, "share", "doc", "bkfront")
    assert len(pages(root)) == len(pages(SOURCE))
    assert dead_links(root) == []


def _words(text):
    return text.split()


def test_installed_man_pages_are_the_help(prefix):
    """bkfront(1) and bkfront-NAME(1) for every subcommand: each renders
    without a groff warning, and its text holds every word of the help,
    in order (nothing lost or mangled by the conversion)."""
    cli = os.path.join(prefix, "bin", "bkfront")
    man1 = os.path.join(prefix, "share", "man", "man1")
    top = subprocess.run([cli, "--help"], capture_output=True, text=True, check=True).stdout
    names = top.split("subcommands:\n")[1].split("\n\n")[0].split("\n")
    names = [l.split()[0] for l in names]
    assert len(names) >= 13 and "speeds" in names
    pages_ = {"bkfront": top}
    for name in names:
        pages_["bkfront-" + name] = subprocess.run([cli, "help", name], capture_output=True,
                                                   text=True, check=True).stdout
    assert sorted(os.listdir(man1)) == sorted(p + ".1" for p in pages_)
    for page, help_text in pages_.items():
        r = subprocess.run(["groff", "-man", "-Tascii", "-ww", "-rHY=0", "-rLL=300n", "-P-cbou",
                            os.path.join(man1, page + ".1")], capture_output=True, text=True)
        assert r.returncode == 0 and r.stderr == "", (page, r.stderr)
        rendered = _words(r.stdout)
        assert page in rendered[:6]
        # every word of the help, in order ("usage:" and the list headings
        # become the page's own headings, a subcommand NAME bkfront-NAME(1))
        k = 0
        for w in _words(help_text):
            if w in ("usage:", "options:", "columns:", "subcommands:"):
                continue
            while k < len(rendered) and rendered[k] not in (w, "bkfront-%s(1)" % w):
                k += 1
            assert k < len(rendered), "%s: the help's word %r is not in the page" % (page, w)
            k += 1


def test_destdir_staging_and_uninstall(installs):
    final, stage = installs
    root = stage + final
    assert sorted(os.listdir(stage)) == [final.split(os.sep)[1]]
    for f in ["bin/bkfront", "include/bkfront/bkfront.h", "lib/libbkfront.so",
              "lib/pkgconfig/bkfront.pc", "share/bkfront/plots/speeds.gp",
              "share/doc/bkfront/docs/python.md", "share/man/man1/bkfront-speeds.1"]:
        assert os.path.exists(os.path.join(root, f)), f
    pc = open(os.path.join(root, "lib/pkgconfig/bkfront.pc")).read()
    assert "prefix=%s\n" % final in pc and stage not in pc
    make("uninstall", "DESTDIR=" + stage, "PREFIX=" + final)
    left = [os.path.join(d, f) for d, _, fs in os.walk(stage) for f in fs]
    assert left == []

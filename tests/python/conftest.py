"""Shared by the pytest suite (make test runs it beside the C suite): where
the build's CLI and the source tree are."""
import os
import subprocess

import pytest

SOURCE = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))


@pytest.fixture(scope="session")
def cli():
    path = os.environ.get("BKFRONT_CLI", os.path.join(SOURCE, "build", "bkfront"))
    if not os.access(path, os.X_OK):
        pytest.fail("no CLI at %s (make build-all)" % path)

    def run(*args, check=True):
        r = subprocess.run([path] + [str(a) for a in args], capture_output=True, text=True,
                           timeout=300)
        if check and r.returncode != 0:
            pytest.fail("bkfront %s: exit %d: %s" % (" ".join(map(str, args)), r.returncode,
                                                    r.stderr))
        return r
    return run


def tsv(text):
    """The CLI's TSV as (columns, rows of strings)."""
    lines = [l for l in text.splitlines() if l and not l.startswith("#")]
    header = lines[0].split("\t")
    return header, [dict(zip(header, l.split("\t"))) for l in lines[1:]]


def sigint_default():
    """preexec_fn for a child Python that must take Ctrl-C: a suite started
    as a background job of a non-interactive shell inherits SIGINT ignored,
    and Python installs its KeyboardInterrupt handler only over the default
    disposition (the interrupt tests then failed under `make bench`'s
    timings run, launched with &)."""
    import signal
    signal.signal(signal.SIGINT, signal.SIG_DFL)

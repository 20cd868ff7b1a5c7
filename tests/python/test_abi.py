"""The structs the Python package declares for cffi (python/bkfront/_lib.py,
ABI mode: nothing checks them at import) against the C headers: a small C
program compiled here prints each struct's size and field offsets, and cffi's
layout must be the same, so a field added in C fails here, not in a user's
call."""
import os
import subprocess

import pytest

from bkfront._lib import ffi

from conftest import SOURCE

STRUCTS = {
    "bkf_error": ["message", "status"],
    "bkf_cycle_options": ["tol", "stepper", "warm_start"],
    "bkf_cycle_result": None,
    "bkf_option": None,
    "bkf_provenance": ["program", "command"],
    "bkf_catalog_hooks": None,
    "bkf_catalog_entry": None,
}


def c_fields(name):
    fields = STRUCTS[name]
    if fields is None:
        fields = [f for f, _ in ffi.typeof(name).fields]
    return fields


def test_struct_layouts_match_the_headers(tmp_path):
    cc = os.environ.get("CC", "cc")
    lines = ['#include "bkfront/bkfront.h"', "#include <stddef.h>", "#include <stdio.h>",
             "int main(void) {"]
    for name in STRUCTS:
        lines.append('  printf("%s size %%zu\\n", sizeof(%s));' % (name, name))
        for f in c_fields(name):
            lines.append('  printf("%s.%s %%zu\\n", offsetof(%s, %s));' % (name, f, name, f))
    lines += ["  return 0;", "}"]
    src = tmp_path / "layout.c"
    src.write_text("\n".join(lines) + "\n")
    exe = tmp_path / "layout"
    pc = subprocess.run(["pkg-config", "--cflags", "gsl", "fftw3", "inih", "lapacke", "nlopt"],
                        capture_output=True, text=True)
    build = subprocess.run([cc, "-std=c11", "-I" + os.path.join(SOURCE, "include")] +
                           pc.stdout.split() + [str(src), "-o", str(exe)],
                           capture_output=True, text=True)
    assert build.returncode == 0, build.stderr
    out = subprocess.run([str(exe)], capture_output=True, text=True, check=True).stdout
    c = dict(line.rsplit(" ", 1) for line in out.splitlines())
    for name in STRUCTS:
        assert int(c[name + " size"]) == ffi.sizeof(name), name
        for f in c_fields(name):
            assert int(c[name + "." + f]) == ffi.offsetof(name, f), name + "." + f

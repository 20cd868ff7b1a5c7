"""The README's Python example (issue 36): run as written, with the
interpreter and PYTHONPATH it names, from a folder laid out as the clone,
and what it prints compared with the README's lines (numbers within their
errors and the rounding they are printed to; the period also against the
published value)."""
import math
import os
import re
import subprocess

from conftest import SOURCE

# T(1, 0) of the van der Pol oscillator, published to 29 digits.
T_1_0 = 6.6632868593231301896996820305


def readme_example():
    """(the shell command, the lines it prints) from the README's section."""
    with open(os.path.join(SOURCE, "README.md"), encoding="utf-8") as f:
        text = f.read()
    section = text[text.index("## From Python\n"):]
    section = section[:section.index("\n## ", 1)]
    lines = section.splitlines()
    start = next(i for i, l in enumerate(lines) if l.startswith("    $ "))
    end = lines.index("    EOF", start)
    command = [lines[start][len("    $ "):]] + [l[4:] for l in lines[start + 1:end + 1]]
    printed = []
    for l in lines[end + 1:]:
        if not l.startswith("    "):
            break
        printed.append(l[4:])
    return "\n".join(command) + "\n", printed


def numbers(line):
    return [float(x) for x in re.findall(r"[-+]?\d+\.?\d*(?:e[-+]?\d+)?", line)]


def test_the_readme_python_example_runs_as_written(tmp_path):
    command, want = readme_example()
    assert "/usr/bin/python3" in command and "PYTHONPATH=python" in command
    # the clone's layout: python/ and build/ beside where the user stands
    for name in ("python", "build"):
        os.symlink(os.path.join(SOURCE, name), tmp_path / name)
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "BKFRONT_LIBRARY")}
    r = subprocess.run(["bash", "-c", command], cwd=tmp_path, capture_output=True, text=True,
                       env=env, timeout=120)
    assert r.returncode == 0, r.stderr
    got = r.stdout.splitlines()
    assert len(got) == len(want) == 3, (got, want)
    # T(1, 0) = T +- err: the README's and the run's T within the run's error
    # and the printed rounding; the errors alike; both T near the published one
    (T_w, e_w), (T_g, e_g) = numbers(want[0])[2:], numbers(got[0])[2:]
    assert abs(T_w - T_g) <= e_g + 1e-13, (want[0], got[0])
    assert abs(T_g - T_1_0) <= e_g and abs(T_w - T_1_0) <= e_w + 1e-13
    assert e_g / 3 <= e_w <= 3 * e_g
    # n = [...]: the same list
    assert want[1] == got[1]
    # v_6 = v +- err, printed to 4 digits: the paper's 0.3750
    (v_w, ev_w), (v_g, ev_g) = numbers(want[2])[1:], numbers(got[2])[1:]
    assert v_w == v_g == 0.375 and ev_g / 3 <= ev_w <= 3 * ev_g
    with open(tmp_path / "speeds.png", "rb") as f:
        assert f.read(8) == b"\x89PNG\r\n\x1a\n"

"""Every `$ bkfront ...` example of the manual (README, docs/) is run as
written (the shell pipeline too, bkfront being the build's) and its output
compared with what the page shows.

What the page shows may leave things out: a line "..." stands for any
number of lines, "..." in a table's header for columns, a row may be one of
every few ("every 4th row"), a cell "8.628..." is cut.  Comparison:
- words exactly;
- a number X of a table whose row also has X_err (or a column err): within
  3 (err shown + err computed), and within the half unit of its last digit
  shown (a rounded cell);
- an error estimate or a gauge (a column *_err, err or *residual*, a number
  after "err"): its magnitude within a factor 100, or both below 1e-12 (an
  estimate, not a result);
- any other number: relative 1e-6, or the half unit of its last digit;
- in comment lines, whole numbers (work counts: steps, spectra) and numbers
  below 1e-6 (below every default tolerance) are not compared, a stated
  "err X" bounds the line's numbers, and lines naming a time in seconds or
  the work of a solve ("work:") are skipped;
- JSON: each member the page shows, by name.
An example whose command cannot run here (a whole scene, minutes) is listed
in SLOW with the reason."""
import json
import math
import os
import re
import subprocess

import pytest

from conftest import SOURCE

SLOW = {"bkfront run fronts/paper.scene": "the whole paper scene (make run; tests/scene runs "
                                          "every shipped scene's plan)"}
# Rows of an example known to differ today, skipped with the reason (the
# example keeps the right value; remove the entry once the code gives it):
# {command: (the rows' first characters, why)}.
KNOWN = {}
NUMBER = re.compile(r"^[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?(\.\.\.)?$")
ANNOTATION = re.compile(r"\s{2,}\(.*\)\s*$")


def examples():
    """(page, line, command, expected lines) of every `$ bkfront` example:
    an indented block's line "$ bkfront ..." and the lines up to the next
    blank line."""
    pages = ["README.md"] + sorted(
        os.path.relpath(p, SOURCE)
        for d, _, fs in os.walk(os.path.join(SOURCE, "docs")) for p in
        (os.path.join(d, f) for f in fs) if p.endswith(".md"))
    found = []
    for page in pages:
        lines = open(os.path.join(SOURCE, page), encoding="utf-8").read().split("\n")
        for i, line in enumerate(lines):
            m = re.match(r"^( {4,})\$ (bkfront .*)$", line)
            if not m:
                continue
            indent = len(m.group(1))
            out = []
            for nxt in lines[i + 1:]:
                if not nxt.strip() or nxt.lstrip().startswith("$ "):
                    break
                out.append(nxt[indent:])
            found.append((page, i + 1, ANNOTATION.sub("", m.group(2)), out))
    return found


def _digits_unit(text):
    """Half a unit of the last digit shown ("2.8913": 5e-5), or the unit
    of a cut one ("8.628...": 1e-3)."""
    cut = text.endswith("...")
    t = text[:-3] if cut else text
    mant, _, exp = t.lower().partition("e")
    dec = len(mant.split(".")[1]) if "." in mant else 0
    unit = 10.0 ** (-dec) * 10.0 ** (int(exp) if exp else 0)
    return unit if cut else 0.5 * unit


def _close(want_text, got, err=None, estimate=False):
    want = float(want_text.rstrip("."))
    if isinstance(got, str):
        try:
            got = float(got)
        except ValueError:
            return False
    if got is None or math.isnan(got):
        return math.isnan(want)
    if math.isnan(want):
        return False
    if estimate:
        a, b = abs(want), abs(got)
        return max(a, b) < 1e-12 or (a > 0 and 0.01 <= b / a <= 100)
    tol = _digits_unit(want_text) + 1e-12 * abs(want)
    tol = max(tol, 3 * err if err is not None else 1e-6 * abs(want))
    return abs(got - want) <= tol


def _cells(line):
    return line.split("\t") if "\t" in line else line.split()


def _is_header(tokens):
    return tokens and all(t == "..." or re.match(r"^[A-Za-z_][A-Za-z0-9_]*$", t)
                          for t in tokens) and any(t != "..." for t in tokens)


def _row_matches(names, want, got_names, got):
    """Row `want` (cells under `names`, "..." skipped) against `got`."""
    index = {n: k for k, n in enumerate(got_names)}
    for name, w in zip(names, want):
        if name == "..." or w == "...":
            continue
        if name not in index or index[name] >= len(got):
            return False
        g = got[index[name]]
        if NUMBER.match(w):
            err = None
            for e in (name + "_err", "err"):
                if e in index and e != name and index[e] < len(got):
                    try:
                        err = float(got[index[e]])
                    except ValueError:
                        pass
                    if e in names and names.index(e) < len(want) and NUMBER.match(want[names.index(e)]):
                        err = (err or 0) + float(want[names.index(e)].rstrip("."))
                    break
            estimate = name.endswith("_err") or name == "err" or "residual" in name
            if not _close(w, g, err, estimate):
                return False
        elif w != g:
            return False
    return True


# A complex number written a+bi or a-bi: its two parts.
COMPLEX = re.compile(r"^([-+]?[\d.]+(?:e[-+]?\d+)?)([-+][\d.]+(?:e[-+]?\d+)?)$")


def _comment_tokens(line):
    out = []
    for t in line.split():
        m = COMPLEX.match(t.strip("(),;:"))
        out += [m.group(1), m.group(2)] if m else [t]
    return out


def _stated_err(tokens):
    """The largest number after "err" in a line (its stated error), or None."""
    errs = [float(tokens[k + 1].strip("(),;:")) for k in range(len(tokens) - 1)
            if tokens[k].strip("(") == "err" and NUMBER.match(tokens[k + 1].strip("(),;:"))]
    return max(errs) if errs else None


def _comment_matches(want, got):
    wt, gt = _comment_tokens(want), _comment_tokens(got)
    if wt and wt[-1] == "...":  # the page cut the line
        wt, gt = wt[:-1], gt[:len(wt) - 1]
    if len(wt) != len(gt):
        return False
    err = max([e for e in (_stated_err(wt), _stated_err(gt)) if e is not None], default=None)
    for k, (w, g) in enumerate(zip(wt, gt)):
        w0, g0 = w.strip("(),;:"), g.strip("(),;:")
        if NUMBER.match(w0) and NUMBER.match(g0):
            if re.match(r"^\d+$", w0):
                continue  # a work count
            if max(abs(float(w0.rstrip("."))), abs(float(g0))) < 1e-6:
                continue  # below every tolerance the commands ask by default
            after_err = k > 0 and wt[k - 1].strip("(") == "err"
            if not _close(w0, g0, err, after_err):
                return False
        elif w != g and not (w.endswith("...") and g.startswith(w[:-3])):
            return False
    return True


def _compare_text(want_lines, got_text, known=None):
    got_lines = [l for l in got_text.split("\n") if l.strip()]
    names = got_names = None
    k = 0
    for w in want_lines:
        ws = w.strip()
        if ws.startswith("...") or (known and w.startswith(known[0])):
            continue
        if ws.startswith("#") and (re.search(r"\b\d+(\.\d+)? s\b", ws) or "work:" in ws):
            continue  # a time, or the work a solve took (its search window, its steps)
        wc = _cells(ws)
        if not ws.startswith("#") and _is_header(wc):
            names = wc
            hdr = next((i for i in range(len(got_lines)) if not got_lines[i].startswith("#")), None)
            assert hdr is not None, "no table in the output for the header %r" % ws
            got_names = _cells(got_lines[hdr])
            missing = [n for n in names if n != "..." and n not in got_names]
            assert not missing, "columns %s not in the output's %s" % (missing, got_names)
            k = hdr + 1
            continue
        while k < len(got_lines):
            g = got_lines[k]
            k += 1
            if ws.startswith("#"):
                if g.startswith("#") and _comment_matches(ws, g):
                    break
            elif names is not None and not g.startswith("#"):
                if _row_matches(names, wc, got_names, _cells(g)):
                    break
            elif names is None and _comment_matches(ws, g):
                break
        else:
            return "the line %r is not in the output (in order)" % ws
    return None


def _compare_json(want_lines, got_text):
    doc = json.loads(got_text)
    for w in want_lines:
        m = re.match(r'^\s*"(\w+)": (.*?),?$', w)
        if not m or "..." in m.group(2):
            continue
        key, value = m.group(1), json.loads(m.group(2))
        if isinstance(value, dict):
            for name, x in value.items():
                g = doc[key].get(name)
                if isinstance(x, (int, float)):
                    if not _close(repr(x) if isinstance(x, int) else json.dumps(x), g,
                                  None, name.endswith("_err")):
                        return "%s.%s: %r, the page %r" % (key, name, g, x)
                elif g != x:
                    return "%s.%s: %r, the page %r" % (key, name, g, x)
        elif doc.get(key) != value:
            return "%s: %r, the page %r" % (key, doc.get(key), value)
    return None


CASES = examples()


def test_the_manual_has_examples():
    assert len(CASES) >= 18


@pytest.mark.parametrize("page,line,command,want", CASES,
                         ids=["%s:%d" % (c[0], c[1]) for c in CASES])
def test_example_output_is_the_page_s(page, line, command, want, tmp_path):
    if command in SLOW:
        pytest.skip(SLOW[command])
    cli = os.environ.get("BKFRONT_CLI", os.path.join(SOURCE, "build", "bkfront"))
    env = dict(os.environ, PATH=os.path.dirname(os.path.abspath(cli)) + os.pathsep +
               os.environ["PATH"])
    r = subprocess.run(["bash", "-o", "pipefail", "-c", command], cwd=SOURCE, env=env,
                       capture_output=True, text=True, timeout=600)
    error_shown = bool(want) and want[0].startswith("bkfront ")
    if error_shown:
        assert r.returncode != 0 and r.stdout == "", (command, r.returncode)
        problem = _compare_text(want, r.stderr)
    else:
        # grep ends a pipeline with 1 when nothing matches: that is a failure too
        assert r.returncode == 0, "%s:%d: %s: exit %d: %s" % (page, line, command,
                                                             r.returncode, r.stderr)
        if want and want[0].strip() == "{":
            problem = _compare_json(want, r.stdout)
        else:
            problem = _compare_text(want, r.stdout, KNOWN.get(command))
    assert problem is None, "%s:%d: %s: %s" % (page, line, command, problem)

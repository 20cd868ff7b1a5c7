"""bkfront from Python: the C library libbkfront over cffi, results as numpy.

    import bkfront
    bkfront.period(1, 0)                      # 6.66328685932...
    t = bkfront.speeds(2, 0.3, -0.96, 20)     # the CLI's table: t["v"], t["n"], ...

Every product takes the CLI's flags as keywords (``stability_tol=1e-7`` is
``--stability-tol 1e-7``; a switch is ``True``), with the CLI's defaults, and
returns the CLI's table as a :class:`Table` (a dict of numpy columns under
the CLI's column names).  Library errors are exceptions carrying the
library's message: :class:`InputError` (a ValueError) for bad input,
:class:`NumericalError` and its subclasses for a numerical refusal.  Long
calls run without the GIL, and Ctrl-C raises the library's cancel flag
(KeyboardInterrupt once the library has stopped).  See docs/python.md.
"""

import _thread
import json
import math
import os
import re
import shutil
import tempfile
import time
import warnings

import numpy as np

from ._lib import ffi, lib, libc
from . import _lib

__all__ = ["period", "speeds", "branch", "floquet", "orbit", "simulate", "check", "stability",
           "product", "products", "options", "version", "Table",
           "Error", "InputError", "NumericalError", "ToleranceError", "BudgetError",
           "BlowupError", "Cancelled"]


# ------------------------------------------------------------------ errors

class Error(Exception):
    """A failure the library reported: ``status`` is its bkf_status code,
    ``status_name`` its short name, the message the library's one line."""

    def __init__(self, message, status):
        super().__init__(message)
        self.status = status
        self.status_name = ffi.string(lib.bkf_status_name(status)).decode()


class InputError(Error, ValueError):
    """Bad input (BKF_EINPUT): a value outside its range, a bad key."""


class NumericalError(Error):
    """A numerical failure (BKF_ENUMERIC) or refusal: the subclasses below."""


class ToleranceError(NumericalError):
    """The requested tolerance cannot be met here (BKF_ETOL)."""


class BudgetError(NumericalError):
    """A step, sample or work budget ran out (BKF_EBUDGET)."""


class BlowupError(NumericalError):
    """The state became non-finite or left its bounds (BKF_EBLOWUP)."""


class Cancelled(Error):
    """Stopped by the cancel flag (BKF_ECANCELED).  Ctrl-C raises
    KeyboardInterrupt; when the library stopped at a cancel point (rather
    than ending the call first), that KeyboardInterrupt's ``__cause__`` is
    the Cancelled saying where ("canceled after 3 of 40 rows")."""


_CLASSES = {_lib.EINPUT: InputError, _lib.ENUMERIC: NumericalError,
            _lib.ETOL: ToleranceError, _lib.EBUDGET: BudgetError,
            _lib.EBLOWUP: BlowupError, _lib.ECANCELED: Cancelled}


def _exception(status, err):
    message = ffi.string(err.message).decode(errors="replace")
    if status == _lib.ENOMEM:
        return MemoryError(message)
    if status == _lib.EIO:
        return OSError(message)
    return _CLASSES.get(status, Error)(message, status)


def _raise(status, err):
    raise _exception(status, err)


def version():
    """The version of the C library loaded ("MAJOR.MINOR.PATCH")."""
    return ffi.string(lib.bkf_version()).decode()


# ------------------------------------------------------------------ period

_METHODS = {"auto": 0, "asymptotic": 1, "leading": 2, "shooting": 3}
_STEPPERS = {"auto": 0, "explicit": 1, "implicit": 2, "extrapolation": 3, "collocation": 4}


def period(mu, nu, tol=1e-10, method="auto", stepper="auto", errors=False):
    """T(mu, nu), the period of f'' + mu (f^2 - 1) f' + f = nu, as
    ``bkfront period`` computes it (same defaults), elementwise over mu and
    nu broadcast together; the points are solved in order, each starting
    from the previous cycle.  A float for scalar input, else an array of the
    broadcast shape; with ``errors=True`` the pair (T, T_err), T_err the
    estimated absolute error."""
    if method not in _METHODS:
        raise InputError("method must be auto, asymptotic, leading or shooting", _lib.EINPUT)
    if stepper not in _STEPPERS:
        raise InputError("stepper must be auto, explicit, implicit, extrapolation or collocation", _lib.EINPUT)
    mu_b, nu_b = np.broadcast_arrays(np.asarray(mu, dtype=float), np.asarray(nu, dtype=float))
    T = np.empty(mu_b.shape)
    T_err = np.empty(mu_b.shape)
    options = lib.bkf_cycle_options_default()
    options.tol = tol
    options.stepper = _STEPPERS[stepper]
    options.warm_start = 1
    m = _METHODS[method]
    result = ffi.new("bkf_cycle_result *")
    err = ffi.new("bkf_error *")
    cycle = lib.bkf_cycle_alloc()
    if cycle == ffi.NULL:
        raise MemoryError("out of memory")
    try:
        estimate = lib.bkf_cycle_estimate
        flat_mu, flat_nu, flat_T, flat_err = mu_b.ravel(), nu_b.ravel(), T.ravel(), T_err.ravel()
        for i in range(flat_mu.size):
            s = estimate(cycle, flat_mu[i], flat_nu[i], ffi.addressof(options), m, result, err)
            if s:
                _raise(s, err)
            flat_T[i] = result.period
            flat_err[i] = result.period_err
    finally:
        lib.bkf_cycle_free(cycle)
    if T.ndim == 0:
        T, T_err = float(T), float(T_err)
    return (T, T_err) if errors else T


# ---------------------------------------------------------- the catalogue

class Table(dict):
    """A product's table: a dict of numpy arrays, one per column, under the
    CLI's column names and in its order.  A column's dtype is its declared
    kind's, never its values': float64 for a number column (NaN where the
    library wrote null), str for a text column, empty tables included.
    ``comments`` holds the comment lines (inputs, work, provenance),
    ``results`` the key results of its JSON form (dict), ``columns`` the
    column names, ``kinds`` their kinds ("number" or "text")."""

    def __init__(self, columns, kinds, rows, comments=(), results=None):
        super().__init__()
        self.columns = list(columns)
        self.kinds = list(kinds)
        if len(self.kinds) != len(self.columns):
            raise Error("the library's table declares %d kinds for %d columns"
                        % (len(self.kinds), len(self.columns)), _lib.ENUMERIC)
        self.comments = list(comments)
        self.results = dict(results or {})
        for name, kind in zip(self.columns, self.kinds):
            self[name] = _column([row.get(name) for row in rows], kind)

    def __len__(self):
        return len(self[self.columns[0]]) if self.columns else 0

    def to_records(self):
        """The rows as a numpy structured array with the same field names."""
        return np.rec.fromarrays([self[c] for c in self.columns], names=self.columns)

    def __repr__(self):
        lines = ["\t".join(self.columns)]
        for i in range(len(self)):
            lines.append("\t".join(_cell(self[c][i]) for c in self.columns))
        return "\n".join(lines)


def _column(values, kind):
    if kind == "number":
        return np.array([math.nan if v is None else float(v) for v in values], dtype=np.float64)
    if kind == "text":
        return np.array(["" if v is None else str(v) for v in values], dtype=np.str_)
    raise Error("the library's table declares the unknown column kind %r" % (kind,),
                _lib.ENUMERIC)


def _cell(value):
    if isinstance(value, (float, np.floating)):
        return repr(float(value))
    return str(value)


def products():
    """The names of the catalogue's products (the CLI's subcommands)."""
    return [ffi.string(lib.bkf_catalog_at(i).name).decode()
            for i in range(lib.bkf_catalog_count())]


def _entry(name):
    if not isinstance(name, str):
        raise InputError("product: the name must be a str, one of %s (not %r)"
                         % (", ".join(products()), name), _lib.EINPUT)
    entry = lib.bkf_catalog_find(_c_text("product", name))
    if entry == ffi.NULL:
        raise InputError("no product %r (one of %s)" % (name, ", ".join(products())),
                         _lib.EINPUT)
    return entry


def options(name):
    """The keys of product `name`: {key: (form, default shown, help)}, the
    CLI's flags without "--" (the keyword spells "-" as "_")."""
    entry = _entry(name)
    count = ffi.new("size_t *")
    table = entry.options(count)
    keys = {}
    for i in range(count[0]):
        o = table[i]
        if o.flags & _lib.OPT_CLI_ONLY:
            continue
        text = lambda p: ffi.string(p).decode() if p != ffi.NULL else None
        keys[text(o.name)] = (text(o.form), text(o.shown_default), text(o.help))
    return keys


def _c_text(key, text):
    """text as the bytes of a C string; a NUL would end it early in C, so
    that '20\\x00junk' would read as 20: refused."""
    if "\0" in text:
        raise InputError("%s: %r holds a NUL character" % (key, text), _lib.EINPUT)
    return text.encode()


def _text(key, value):
    """A keyword's value as the CLI's text: lists joined by commas, numbers
    in their shortest exact form."""
    if isinstance(value, str):
        return value
    if isinstance(value, (bool, np.bool_)):
        return "yes" if value else "no"
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    if isinstance(value, (float, np.floating)):
        return repr(float(value))
    if np.ndim(value) == 1:
        return ",".join(_text(key, v) for v in np.asarray(value).tolist())
    raise InputError("%s: cannot pass %r as a value" % (_keyword(key), value), _lib.EINPUT)


def _keyword(key):
    """A key's name as a Python keyword: "stability-tol" is stability_tol,
    "from" (a Python word) from_."""
    key = key.replace("-", "_")
    return key + "_" if key == "from" else key


# The prefix the library writes before every key it names in a message
# (the CLI passes "--"); replaced by nothing, the key by its keyword.
_MARK = "\x01"


def _python_message(message):
    return re.sub(_MARK + r"([A-Za-z][A-Za-z0-9_-]*)", lambda m: _keyword(m.group(1)),
                  message).replace(_MARK, "")


def _raise_keyed(status, err):
    """_raise with the keys the message names spelled as keywords."""
    text = _python_message(ffi.string(err.message).decode(errors="replace"))
    err.message = text.encode()[:ffi.sizeof(err.message) - 1]
    _raise(status, err)


def _run(name, call, stopped):
    """Runs call(cancel) in a worker thread (cffi releases the GIL for the
    C call) so that Ctrl-C reaches Python at once.  Ctrl-C raises the
    library's cancel flag, then WAITS for the library to return (a further
    Ctrl-C too), then re-raises KeyboardInterrupt: nothing the call uses is
    freed under it.  Thread.join is not used for the wait: in Python 3.11 an
    interrupted timed join marks a live thread stopped (bpo-45274), and a
    later join returns at once.  Whatever the call uses it holds itself
    (cdata kept alive by its closure), so even a KeyboardInterrupt that lands
    before the wait starts frees nothing under the library.  stopped(value)
    maps the finished call's value to the exception the KeyboardInterrupt
    is chained to (None: the call ended on its own)."""
    cancel = ffi.new("int *")
    box = {}
    finished = _thread.allocate_lock()
    finished.acquire()

    def worker():
        try:
            box["value"] = call(cancel)
        except BaseException as exc:  # handed to the caller's thread
            box["error"] = exc
        finally:
            box["done"] = True
            finished.release()

    def wait():
        while not box.get("done"):
            finished.acquire(timeout=0.1)

    started = False
    try:
        _thread.start_new_thread(worker, ())
        started = True
        wait()
    except KeyboardInterrupt as stop:
        cancel[0] = 1
        since = time.monotonic()
        told = False
        while (started or box) and not box.get("done"):
            try:
                finished.acquire(timeout=0.1)
                if not told and not box.get("done") and time.monotonic() - since > 1:
                    told = True  # a silent wait of a minute looks like a hang
                    warnings.warn("bkfront %s: Ctrl-C: waiting for the library to stop (a "
                                  "product without a cancel point runs to its end, "
                                  "docs/python.md)" % name, RuntimeWarning, stacklevel=3)
            except KeyboardInterrupt:
                pass  # still stopping: the library has not returned yet
        if "value" in box:
            # whether the library stopped at a cancel point or had ended
            stop.__cause__ = stopped(box["value"])
        raise
    if "error" in box:
        raise box["error"]
    return box["value"]


def product(name, **keys):
    """Runs catalogue product `name` (``bkfront NAME``) with the keywords as
    its flags and returns its table.  ``None`` or ``False`` leave a key at
    its default; ``True`` sets a switch."""
    entry = _entry(name)
    err = ffi.new("bkf_error *")
    raw = lib.bkf_catalog_spec_new(entry, err)
    if raw == ffi.NULL:
        _raise(err.status or _lib.ENOMEM, err)
    # Freed when its last reference goes: the worker's, while it runs.
    spec = ffi.gc(raw, lambda p: lib.bkf_catalog_spec_free(entry, p))
    count = ffi.new("size_t *")
    table = entry.options(count)
    switches = {ffi.string(table[i].name).decode() for i in range(count[0])
                if table[i].type == _lib.OPT_SWITCH}
    keep = []  # a text key keeps the pointer (options.h): alive as long as the spec
    for key, value in keys.items():
        if value is None or value is False:
            continue
        key = key[:-1] if key == "from_" else key.replace("_", "-")
        text = None if key in switches and value is True else _text(key, value)
        keep.append(ffi.NULL if text is None else ffi.new("char[]", _c_text(_keyword(key), text)))
        s = lib.bkf_catalog_apply(entry, spec, _c_text(_keyword(key), key), keep[-1],
                                  _MARK.encode(), err)
        if s:
            _raise_keyed(s, err)
    s = entry.check(spec, _MARK.encode(), err)
    if s:
        _raise_keyed(s, err)
    messages = []

    @ffi.callback("void(const char *, void *)")
    def warn(message, data):
        messages.append(ffi.string(message).decode(errors="replace"))

    # Handed to the worker, whose return drops the last reference: the spec
    # is freed in that thread, where no KeyboardInterrupt can stop its
    # destructor half-way (Python runs signal handlers in the main thread).
    owned = [spec]
    del spec

    def call(cancel):
        # keep and warn are referenced here: alive until the call returns
        spec = owned.pop()
        buf = ffi.new("char **")
        size = ffi.new("size_t *")
        stream = libc.open_memstream(buf, size)
        if stream == ffi.NULL:
            raise MemoryError("out of memory")
        hooks = ffi.new("bkf_catalog_hooks *", {"warn": warn, "cancel": cancel})
        prov = ffi.new("bkf_provenance *")
        s = entry.write(spec, stream, _lib.IO_JSON, prov, hooks, err)
        libc.fclose(stream)
        text = ffi.string(buf[0], size[0]).decode() if buf[0] != ffi.NULL else ""
        libc.free(buf[0])
        return s, text

    def stopped(value):
        s = value[0]
        return _exception(s, err) if s == _lib.ECANCELED else None

    s, text = _run(name, call, stopped)
    for message in messages:
        warnings.warn("bkfront %s: %s" % (name, message), RuntimeWarning, stacklevel=3)
    if s:
        _raise_keyed(s, err)
    doc = json.loads(text)
    if "kinds" not in doc:
        raise Error("the library %s writes no column kinds: older than this package"
                    % _lib.library_path(), _lib.ENUMERIC)
    return Table(doc["columns"], doc["kinds"], doc.get("rows", []), doc.get("comments", []),
                 doc.get("results"))


def speeds(gamma, c, nu, S, **keys):
    """Every allowed front speed (``bkfront speeds``): columns n, v, mu, T,
    T_err, ..., v_err, model, residual, slope, flags; ``stability=True`` adds
    each root's ring-spectrum verdict.  A root that cannot be had to ``tol``
    stays a row with "refused" in its flags and NaN numbers (``results``
    counts them as "refused", the comments say why), and a RuntimeWarning
    says so: the CLI's exit status 3."""
    return product("speeds", gamma=gamma, c=c, nu=nu, S=S, **keys)


def branch(**keys):
    """A branch of front speeds by continuation (``bkfront branch``), e.g.
    ``branch(param="S", from_=30, to=5, n=6, gamma=1.5, c=0.3, nu=-0.96,
    S=30)``: ``--from`` is the keyword ``from_``."""
    return product("branch", **keys)


def floquet(gamma, c, **keys):
    """The Floquet stability of the global oscillation (``bkfront floquet``):
    dispersion relations (``nu=..., q=...``), the threshold
    (``threshold=True``) or the stability diagram (``diagram=True``)."""
    return product("floquet", gamma=gamma, c=c, **keys)


def orbit(**keys):
    """The branch of period-doubled orbits (``bkfront orbit``): from the global
    oscillation's period doubling of the ring's mode j, one row per orbit
    (kind, nu, period, period_err, amplitude, verdict, the largest multiplier,
    events), e.g. ``orbit(gamma=2, c=0.3, S=20, max_points=20)``; the
    results ``p_pd``, ``p_pd_err``, ``j``, ``T_pd`` are the switch's point."""
    return product("orbit", **keys)


def check(**keys):
    """The predicted front speeds against simulation (``bkfront check``)."""
    return product("check", **keys)


def stability(**keys):
    """The spectrum of a train of n fronts (``bkfront stability``)."""
    return product("stability", **keys)


def simulate(**keys):
    """A simulation (``bkfront simulate``, same defaults): its diagnostics
    table, with the spacetime field as attributes ``t`` (frames), ``x``
    (grid) and ``psi`` (array of shape (len(t), len(x))).  With
    ``spacetime=FILE`` the field is written to FILE instead, as the CLI
    writes it (``FILE.h5``: HDF5; ``spacetime_fields="psi,eta"``,
    ``spacetime_deflate=L``), and the table has no arrays."""
    if "spacetime" in keys:
        return product("simulate", **keys)
    folder = tempfile.mkdtemp(prefix="bkfront-")
    try:
        path = os.path.join(folder, "spacetime.txt")
        table = product("simulate", spacetime=path, spacetime_format="text", **keys)
        field = np.loadtxt(path, comments="#", ndmin=2)
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    table.x = field[0, 1:]
    table.t = field[1:, 0]
    table.psi = field[1:, 1:]
    return table

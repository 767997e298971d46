"""trueaxis: measure, separate, map and compensate geometric errors of machine tools and CMMs.

Units follow trueaxis' files: positions in mm, deviations in µm, angles in µrad.

Straightness separation (JPH0464003B2; Whitehouse 1976):

    >>> import trueaxis
    >>> sim = trueaxis.simulate_straightness(stations=200, offsets=[0, 10, 20])
    >>> r = trueaxis.separate(sim["x"], sim["readings"], offsets=sim["offsets"], method="three-point")
    >>> r["workpiece"]["value"]  # µm, residuals from the least-squares line

Error space and compensation of a virtual machine:

    >>> m = trueaxis.Machine.random(seed=3)
    >>> s = trueaxis.measure_space(m, spacing=100, probe_noise=0.05, verify=1000)
    >>> s["map"].compensate([[400.0, 300.0, 250.0]])  # commands (mm) that hit the wanted points
"""
import difflib as _difflib
import functools as _functools
import os as _os
import re as _re

from . import _trueaxis
from ._trueaxis import Error, ErrorMap, Machine
from ._trueaxis import records

# Parameters that take a table of named columns (a dict of sequences): a pandas DataFrame there
# becomes {column: values}. Anywhere else a DataFrame or Series becomes its numpy array.
_TABLE_PARAMETERS = {"runs"}


def _signatures(fn):
    """Parameter names of each overload, from the signature lines pybind11 writes in __doc__."""
    name = fn.__name__
    out = []
    for line in (fn.__doc__ or "").splitlines():
        m = _re.match(r"^(?:\d+\. )?" + _re.escape(name) + r"\((.*)\)( -> .*)?$", line.strip())
        if not m or m.group(1) == "*args, **kwargs":
            continue
        names, depth, cur = [], 0, ""
        for ch in m.group(1) + ",":
            if ch in "([{":
                depth += 1
            elif ch in ")]}":
                depth -= 1
            if ch == "," and depth == 0:
                p = cur.split(":")[0].split("=")[0].strip()
                if p and p not in ("*", "self", "/"):
                    names.append(p)
                cur = ""
            else:
                cur += ch
        out.append(names)
    return out


def _is_pandas(value, kind):
    t = type(value)
    return t.__name__ == kind and t.__module__.split(".")[0] == "pandas"


def _plain(value, parameter):
    """What the compiled module takes: a path as str, a DataFrame as a table or an array."""
    if isinstance(value, _os.PathLike):
        return _os.fspath(value)
    if _is_pandas(value, "DataFrame"):
        if parameter in _TABLE_PARAMETERS:
            return {str(c): value[c].to_numpy() for c in value.columns}
        return value.to_numpy()
    if _is_pandas(value, "Series"):
        return value.to_numpy()
    return value


class Result(dict):
    """A trueaxis result: a dict (numpy arrays for series, µm and µrad as in the files), which
    trueaxis.save() writes as the file the command line writes for it."""

    __slots__ = ("_save",)


def _result(value):
    """A dict the compiled module marked as savable becomes a Result (lists of them too)."""
    if isinstance(value, dict) and "__save__" in value:
        saver = value.pop("__save__")
        out = Result(value)
        out._save = saver
        return out
    if isinstance(value, list):
        return [_result(v) for v in value]
    return value


def save(result, path):
    """Writes `result` (what a trueaxis function returned, or load() read) as the file the command
    line writes for it: separate → result.json, positioning → positioning.json, ballgauge → a map,
    identify → a parametric model, fit → fit.json, ... Every trueaxis command reads it back
    (`trueaxis report PATH` draws it). Raises TypeError for anything else."""
    saver = getattr(result, "_save", None)
    if saver is None:
        raise TypeError(
            f"trueaxis.save() writes a result a trueaxis function returned, not a {type(result).__name__}"
            " (a dict built by hand has no file form; json.dumps() it after turning arrays into lists)")
    saver(_os.fspath(path))


def _arrays(value):
    """JSON lists of numbers as numpy arrays (nested lists of equal length as 2-D arrays)."""
    import numpy as _np

    if isinstance(value, dict):
        return {k: _arrays(v) for k, v in value.items()}
    if isinstance(value, list):
        if value and all(isinstance(v, (int, float)) and not isinstance(v, bool) or v is None for v in value) \
                and any(v is not None for v in value):
            return _np.array([_np.nan if v is None else v for v in value], dtype=float)
        if value and all(isinstance(v, list) and v and all(isinstance(x, (int, float)) and not isinstance(x, bool)
                                                             for x in v) for v in value) \
                and len({len(v) for v in value}) == 1:
            return _np.array(value, dtype=float)
        return [_arrays(v) for v in value]
    return value


def load(path):
    """Reads any result file trueaxis writes (its "kind" says which) after checking it with the
    reader of its kind (a bad file raises trueaxis.Error naming file:line:col). Returns a Result:
    the file's keys, with lists of numbers as numpy arrays (null as NaN); save() writes the same
    file back."""
    import json as _json

    path = _os.fspath(path)
    _trueaxis._load(path)
    with open(path, encoding="utf-8") as f:
        text = f.read()
    out = Result(_arrays(_json.loads(text)))

    def write(target):
        with open(target, "w", encoding="utf-8") as f:
            f.write(text)

    out._save = write
    return out


def report(result, path, *, meta=None, title=None):
    """Writes the HTML report of `result` to `path`, the page `trueaxis report` draws: a result a
    trueaxis function returned (or load() read), or the path of a result file. `meta` adds header
    rows as the command line's --meta does ({"machine": "...", "operator": "..."}, in order);
    `title` replaces the page's title. Returns the result's kind."""
    import tempfile as _tempfile

    meta = [(str(k), str(v)) for k, v in (meta or {}).items()]
    if isinstance(result, (str, _os.PathLike)):
        return _trueaxis._report(_os.fspath(result), _os.fspath(path), meta, None, title)
    with _tempfile.TemporaryDirectory() as tmp:
        saved = _os.path.join(tmp, "result.json")
        save(result, saved)
        # No file behind it: the page names no data file.
        return _trueaxis._report(saved, _os.fspath(path), meta, "", title)


def export(result, path, format, *, axis="x", at=None, unidirectional=False, **options):
    """Writes the compensation table of `result` for a machine-tool controller: the file
    `trueaxis export FORMAT` writes. format: "linuxcnc", "sinumerik", "heidenhain" or "fanuc".
    result: what positioning() or measure_space() returned, or such a result file's path.
    axis: the machine axis ('x', 'y', 'z'; for a space, the grid line along it); at: a point
    (x, y, z in mm) that line passes through (default the grid's centre); unidirectional: a
    positioning table of one curve where the format could hold both directions (LinuxCNC,
    HEIDENHAIN). Options, named as the command line's flags: linuxcnc: type (1: trims,
    0: actual positions); sinumerik: axis_name ('X1'), encoder, step (mm), max_points;
    heidenhain: axis_name ('X'), name; fanuc: axis_number, axis_name, reference, interval,
    first_number, max_number, magnification, detection_unit, max_feedrate. Returns what was
    written, in words."""
    import tempfile as _tempfile

    at = None if at is None else [float(v) for v in at]
    if isinstance(result, (str, _os.PathLike)):
        return _trueaxis._export(_os.fspath(result), _os.fspath(path), format, axis, at,
                                 unidirectional, options)
    with _tempfile.TemporaryDirectory() as tmp:
        saved = _os.path.join(tmp, "result.json")
        save(result, saved)
        return _trueaxis._export(saved, _os.fspath(path), format, axis, at, unidirectional, options)


def _friendly(fn, method=False):
    """`fn` taking pathlib paths and pandas tables, and naming a misspelt keyword in one line."""
    overloads = _signatures(fn)
    known = sorted({n for names in overloads for n in names})

    @_functools.wraps(fn)
    def call(*args, **kwargs):
        for k in kwargs:
            if overloads and k not in known:
                close = _difflib.get_close_matches(k, known, 1)
                hint = f" (did you mean '{close[0]}'?)" if close else f" (it takes: {', '.join(known)})"
                raise TypeError(f"{fn.__name__}(): no keyword '{k}'{hint}")
        names = overloads[0] if len(overloads) == 1 else []
        first = 1 if method else 0
        args = [a if i < first else _plain(a, names[i - first] if i - first < len(names) else None)
                for i, a in enumerate(args)]
        kwargs = {k: _plain(v, k) for k, v in kwargs.items()}
        return _result(fn(*args, **kwargs))

    return call


for _name in dir(_trueaxis):
    _obj = getattr(_trueaxis, _name)
    if _name.startswith("_") or _name in ("Error",):
        continue
    if isinstance(_obj, type):
        for _attr, _member in list(vars(_obj).items()):
            if _attr.startswith("__") or not callable(getattr(_obj, _attr, None)):
                continue
            if isinstance(_member, staticmethod) or type(_member).__name__ == "builtin_function_or_method":
                setattr(_obj, _attr, staticmethod(_friendly(getattr(_obj, _attr))))
            elif type(_member).__name__ == "instancemethod":
                setattr(_obj, _attr, _friendly(getattr(_obj, _attr), method=True))
    elif callable(_obj):
        globals()[_name] = _friendly(_obj)

__all__ = [
    "Error",
    "ErrorMap",
    "Result",
    "export",
    "load",
    "report",
    "save",
    "Machine",
    "acceptance_e0",
    "acceptance_probing",
    "acceptance_setup",
    "records",
    "analyze_layout",
    "design",
    "ballgauge",
    "circular",
    "identify",
    "fit",
    "guideway",
    "measure_space",
    "moody",
    "positioning",
    "scan",
    "separate",
    "simulate_ballgauge",
    "simulate_circular",
    "simulate_guideway",
    "simulate_part",
    "simulate_positioning",
    "simulate_straightness",
    "straightness",
    "surface",
    "verify_compensation",
    "verify_lengths",
]
__version__ = "0.1.0"

"""One small field validator for every input: command-line flags, scene JSON, schedule CSV,
render-job TOML and rig JSON all check values here, so a bad value reads the same wherever it
came from::

    --mass = 1e-300 is outside the allowed range [1, 1000] kg
    scene.json: figure.body.m = 1e-300 is outside the allowed range [1, 1000] kg
    job.toml: figures[0].period = 89 is outside the allowed range [0.3, 20] s
    schedule.csv: row 2 (line 3), column period = 'fast' is not a number

The ranges come from :mod:`.ranges`.  :class:`Fields` reads one table of a parsed document
(JSON object, TOML table), naming every field by its full path and refusing unknown keys with the
nearest known one.  :func:`read_text` reads a whole text file with the errors of a file (missing,
binary, not UTF-8) named by the file.
"""
from __future__ import annotations

import difflib
import json
from pathlib import Path

import numpy as np

from .ranges import RANGES, Range

__all__ = ["FieldError", "check", "check_range", "Fields", "read_text", "nearest"]

_NUMBER = (int, float, np.integer, np.floating)


class FieldError(ValueError):
    """A value that cannot be used; the message names its source, field, value and range."""


def _label(name: str, source: str) -> str:
    return f"{source}: {name}" if source else name


def check(name: str, value, rng: Range | str, source: str = ""):
    """``value`` as a float (an int for whole-number ranges) if it is a number inside ``rng``
    (a :class:`Range` or a key of ``RANGES``); else :class:`FieldError` naming ``source: name``,
    the value and the range.  Strings and booleans are not numbers."""
    rng = RANGES[rng] if isinstance(rng, str) else rng
    label = _label(name, source)
    if isinstance(value, bool) or not isinstance(value, _NUMBER):
        raise FieldError(f"{label} = {value!r} is not a number; allowed range {rng}")
    v = float(value)
    if not rng.contains(v):
        why = f": {rng.reason}" if rng.explain else ""
        raise FieldError(f"{label} = {value!r} is outside the allowed range {rng}{why}")
    return int(v) if rng.integer else v


def check_range(name: str, value, lo: float, hi: float, *, lo_open: bool = False,
                hi_open: bool = False) -> float:
    """:func:`check` against an ad-hoc interval (for values the table does not list)."""
    return check(name, value, Range(lo, hi, lo_open=lo_open, hi_open=hi_open))


def nearest(key: str, known) -> str:
    """``"; did you mean 'x'?"`` for the closest of ``known``, else the list of known keys."""
    close = difflib.get_close_matches(str(key), sorted(known), n=1, cutoff=0.6)
    if close:
        return f"; did you mean {close[0]!r}?"
    return f" (known: {', '.join(sorted(known))})"


def read_text(path, what: str) -> str:
    """The whole UTF-8 text of ``path`` (a leading byte-order mark dropped), or
    :class:`FieldError` naming ``what`` and the file."""
    try:
        raw = Path(path).read_bytes()
    except OSError as exc:
        raise FieldError(f"{what} {str(path)!r} cannot be read: {exc.strerror}") from None
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise FieldError(f"{what} {str(path)!r} is not a UTF-8 text file (byte "
                         f"0x{raw[exc.start]:02x} at offset {exc.start})") from None
    if "\x00" in text:
        raise FieldError(f"{what} {str(path)!r} is not a text file (it holds NUL bytes)")
    return text


def read_json(path, what: str):
    """The JSON document in ``path`` (:func:`read_text`), or :class:`FieldError` naming
    ``what`` and the file when it is not JSON or is nested deeper than Python can parse."""
    text = read_text(path, what)
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        raise FieldError(f"{what} {str(path)!r} is not valid JSON ({exc})") from None
    except RecursionError:
        raise FieldError(f"{what} {str(path)!r} is nested too deeply") from None


_REQUIRED = object()


class Fields:
    """One table of a parsed document; every error names ``source: path.key``."""

    def __init__(self, doc, source: str, path: str = ""):
        self.doc = doc
        self.source = source
        self.path = path

    def name(self, key) -> str:
        if isinstance(key, int):
            return f"{self.path}[{key}]"
        return f"{self.path}.{key}" if self.path else str(key)

    def fail(self, key, msg: str):
        raise FieldError(f"{_label(self.name(key), self.source)} {msg}")

    def has(self, key) -> bool:
        return key in self.doc

    def keys(self):
        return list(self.doc)

    def only(self, known) -> "Fields":
        """Refuse keys not in ``known``, naming the nearest known key."""
        for k in self.doc:
            if k not in known:
                self.fail(k, f"is not a known field{nearest(k, known)}")
        return self

    def value(self, key, default=_REQUIRED):
        if key in self.doc:
            return self.doc[key]
        if default is _REQUIRED:
            self.fail(key, "is missing")
        return default

    def table(self, key, known=None, required=False) -> "Fields":
        """The sub-table ``key`` (an empty one when absent and not required)."""
        v = self.value(key, _REQUIRED if required else {})
        if not isinstance(v, dict):
            self.fail(key, f"= {_short(v)} is not a table of fields")
        f = Fields(v, self.source, self.name(key))
        return f.only(known) if known is not None else f

    def tables(self, key, known=None) -> list:
        """The list of tables ``key`` (``[[key]]`` in TOML, a list of objects in JSON)."""
        v = self.value(key, [])
        if not isinstance(v, list):
            self.fail(key, f"= {_short(v)} is not a list of tables")
        sub = Fields(v, self.source, self.name(key))
        out = []
        for i, item in enumerate(v):
            if not isinstance(item, dict):
                sub.fail(i, f"= {_short(item)} is not a table of fields")
            f = Fields(item, self.source, sub.name(i))
            out.append(f.only(known) if known is not None else f)
        return out

    def number(self, key, rng: Range | str, default=_REQUIRED):
        v = self.value(key, default)
        if v is None and default is None:
            return None
        return check(self.name(key), v, rng, self.source)

    def boolean(self, key, default=_REQUIRED) -> bool:
        v = self.value(key, default)
        if not isinstance(v, bool):
            self.fail(key, f"= {_short(v)} is not true or false")
        return v

    def string(self, key, default=_REQUIRED, choices=None):
        v = self.value(key, default)
        if v is None and default is None:
            return None
        if not isinstance(v, str):
            self.fail(key, f"= {_short(v)} is not a string")
        if choices is not None and v not in choices:
            self.fail(key, f"= {v!r} is not one of {', '.join(choices)}")
        return v

    def xy(self, key, default=_REQUIRED) -> np.ndarray:
        """An ``[x, y]`` pair of numbers (m) within ``RANGES['coordinate']``."""
        v = self.value(key, default)
        return _pair(self.name(key), v, self.source)

    def points(self, key, min_rows: int = 1, default=_REQUIRED) -> np.ndarray:
        """A list of ``[x, y]`` pairs, shape ``(n, 2)``, at least ``min_rows`` of them."""
        v = self.value(key, default)
        if not isinstance(v, (list, tuple, np.ndarray)):
            self.fail(key, f"= {_short(v)} is not a list of [x, y] pairs")
        if len(v) < min_rows:
            self.fail(key, f"has {len(v)} points; at least {min_rows} are needed")
        return np.array([_pair(f"{self.name(key)}[{i}]", p, self.source)
                         for i, p in enumerate(v)], float).reshape(-1, 2)

    def numbers(self, key, rng: Range | str, default=_REQUIRED) -> list:
        """A non-empty list of numbers, each inside ``rng``."""
        v = self.value(key, default)
        if not isinstance(v, list) or not v:
            self.fail(key, f"= {_short(v)} is not a non-empty list of numbers")
        return [check(f"{self.name(key)}[{i}]", x, rng, self.source) for i, x in enumerate(v)]


def _pair(name: str, v, source: str) -> np.ndarray:
    if not isinstance(v, (list, tuple, np.ndarray)) or len(v) != 2:
        raise FieldError(f"{_label(name, source)} = {_short(v)} is not an [x, y] pair of numbers")
    return np.array([check(f"{name}[{i}]", c, "coordinate", source) for i, c in enumerate(v)])


def _short(v) -> str:
    """``repr(v)``, cut to one readable line."""
    text = repr(v)
    return text if len(text) <= 60 else text[:57] + "..."

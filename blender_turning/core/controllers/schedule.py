"""Parameters given over time (Section 5: "specifying the values of these three parameters over
time"): a constant, samples linearly interpolated (held beyond the ends), or any callable."""
from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from ..ranges import RANGES, Range
from ..validate import FieldError, check, nearest, read_text


class Schedule:
    """A scalar function of time. Build with :meth:`constant`, :meth:`sampled` or :meth:`of`."""

    __slots__ = ("_fn", "_const")

    def __init__(self, fn: Callable[[float], float], const: float | None = None):
        self._fn = fn
        self._const = const

    @classmethod
    def constant(cls, value) -> "Schedule":
        """A constant: a number, or an array with one value per figure of a batch."""
        if np.ndim(value) == 0:
            v = float(value)
        else:
            v = np.array(value, float)
            v.setflags(write=False)
        return cls(lambda t: v, v)

    @classmethod
    def sampled(cls, t, values) -> "Schedule":
        t = np.asarray(t, float)
        v = np.asarray(values, float)
        if t.ndim != 1 or t.shape != v.shape or t.size == 0:
            raise ValueError("schedule needs equal-length 1-D arrays of times and values")
        if np.any(np.diff(t) <= 0):
            raise ValueError("schedule times must increase strictly")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(v))):
            raise ValueError("schedule holds a value that is not a finite number")
        if t.size == 1:
            return cls.constant(v[0])
        return cls(lambda tt: float(np.interp(tt, t, v)))

    @classmethod
    def of(cls, value) -> "Schedule":
        """A schedule from a number, a ``Schedule`` or a callable of time."""
        if isinstance(value, Schedule):
            return value
        if callable(value):
            return cls(value)
        return cls.constant(value)

    @property
    def constant_value(self) -> float | None:
        return self._const

    def __call__(self, t: float) -> float:
        return self._fn(t)


@dataclass(frozen=True)
class TurnSchedule:
    """The parametric controller's three inputs over time (SI: s, rad/s, rad, rad)."""

    omega0: Schedule
    theta_max: Schedule
    heading: Schedule | None = None


_COLUMNS = {"t": "schedule_t", "period": "period", "lean_deg": "theta_max",
            "heading_deg": "heading"}


def read_schedule_csv(path: str | Path, lean: Range | None = None) -> TurnSchedule:
    """Read a CSV with the header ``t, period, lean_deg[, heading_deg]`` (s, s, deg, deg).

    Spaces around names and values and a UTF-8 byte-order mark are allowed; ``heading_deg`` is
    optional (absent or blank on every row: ``heading`` is None).  Each value is checked against
    the table of ranges (``lean``, when given, is the figure's lean range, rad:
    :func:`..ranges.lean_range`); an error names the file, the row (and its line), the column
    and the value.
    """
    src = str(path)
    lines = read_text(path, "schedule file").splitlines()
    try:
        rows = [(n, [c.strip() for c in r]) for n, r in enumerate(csv.reader(lines), 1)
                if any(c.strip() for c in r)]
    except csv.Error as exc:
        raise FieldError(f"{src}: is not a CSV file ({exc})") from None
    if not rows:
        raise FieldError(f"{src}: the file is empty; it needs a header t, period, lean_deg "
                         "(and optionally heading_deg) and at least one row")
    (_, header), data = rows[0], rows[1:]
    for name in header:
        if name not in _COLUMNS:
            raise FieldError(f"{src}: column {name!r} in the header is not known"
                             f"{nearest(name, _COLUMNS)}")
    missing = [c for c in ("t", "period", "lean_deg") if c not in header]
    if missing or len(set(header)) != len(header):
        raise FieldError(f"{src}: the header {','.join(header)!r} needs the columns t, period, "
                         "lean_deg (and optionally heading_deg), each once")
    if not data:
        raise FieldError(f"{src}: the header t, period, lean_deg needs at least one row below "
                         "it")
    cols = {name: [] for name in header}
    for k, (line, cells) in enumerate(data, 1):
        where = f"row {k} (line {line})"
        if len(cells) != len(header):
            raise FieldError(f"{src}: {where} has {len(cells)} values; the header has "
                             f"{len(header)} ({', '.join(header)})")
        for name, text in zip(header, cells):
            if name == "heading_deg" and text == "":
                cols[name].append(None)
                continue
            try:
                value = float(text)
            except ValueError:
                value = text
            rng = lean if name == "lean_deg" and lean is not None else RANGES[_COLUMNS[name]]
            cols[name].append(check(f"{where}, column {name}", value,
                                    rng.deg() if name.endswith("_deg") else rng, src))
    heading = cols.get("heading_deg")
    if heading is not None and None in heading:
        if any(h is not None for h in heading):
            k = heading.index(None) + 1
            raise FieldError(f"{src}: row {k} (line {data[k - 1][0]}), column heading_deg is "
                             "blank; give heading_deg on every row or on none")
        heading = None
    t = np.asarray(cols["t"])
    bad = np.flatnonzero(np.diff(t) <= 0)
    if bad.size:
        k = int(bad[0]) + 2
        raise FieldError(f"{src}: row {k} (line {data[k - 1][0]}), column t = {t[k - 1]!r} "
                         f"does not come after the row before it (t = {t[k - 2]!r})")
    return TurnSchedule(
        omega0=Schedule.sampled(t, 2 * np.pi / np.asarray(cols["period"])),
        theta_max=Schedule.sampled(t, np.radians(cols["lean_deg"])),
        heading=Schedule.sampled(t, np.radians(heading)) if heading else None,
    )

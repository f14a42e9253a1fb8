"""Parameters given over time (Section 5: "specifying the values of these three parameters over
time"): a constant, samples linearly interpolated (held beyond the ends), or any callable."""
from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np


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


def read_schedule_csv(path: str | Path) -> TurnSchedule:
    """Read a CSV with the header ``t, period, lean_deg, heading_deg`` (heading may be blank)."""
    path = Path(path)
    try:
        with path.open(newline="") as fh:
            rows = list(csv.DictReader(fh))
    except OSError as exc:
        raise ValueError(f"schedule file {str(path)!r} cannot be read: {exc.strerror}") from None
    need = ("t", "period", "lean_deg")
    if not rows or any(k not in rows[0] for k in need):
        raise ValueError(f"schedule file {str(path)!r} needs a header with columns t, period, "
                         "lean_deg (and optionally heading_deg) and at least one row")
    try:
        t = [float(r["t"]) for r in rows]
        period = [float(r["period"]) for r in rows]
        lean = [float(r["lean_deg"]) for r in rows]
        has_heading = all(r.get("heading_deg") not in (None, "") for r in rows)
        heading = [float(r["heading_deg"]) for r in rows] if has_heading else None
    except ValueError:
        raise ValueError(f"schedule file {str(path)!r} holds a value that is not a number") from None
    for p in period:
        if not (p > 0 and math.isfinite(p)):
            raise ValueError(f"schedule period = {p!r} is outside the allowed range (0, inf) s")
    for d in lean:
        if not (0 < d < 90):
            raise ValueError(f"schedule lean_deg = {d!r} is outside the allowed range (0, 90)")
    t_arr = np.asarray(t)
    return TurnSchedule(
        omega0=Schedule.sampled(t_arr, 2 * np.pi / np.asarray(period)),
        theta_max=Schedule.sampled(t_arr, np.radians(lean)),
        heading=Schedule.sampled(t_arr, np.radians(heading)) if heading else None,
    )

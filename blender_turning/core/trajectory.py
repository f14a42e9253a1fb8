"""The trajectory: the contract between the core, the mapping layer and Blender.

A :class:`Trajectory` holds equal-length 1-D arrays, one per column of ``COLUMNS`` (SI units,
radians; ``s`` is the foot's distance travelled), plus a small ``meta`` mapping (preset, body
parameters) that travels with it in JSON.  CSV files have exactly these column names in a header
row.  Writers write to a temporary file and rename it, so a failure leaves no partial file.
"""
from __future__ import annotations

import csv
import io
import json
import math
from dataclasses import dataclass, field

import numpy as np

from .files import atomic_write_text
from .phase import TWO_PI

COLUMNS = ("t", "x", "y", "theta_dir", "theta_v", "omega_v", "alpha_v", "C_f", "F_leg", "phi",
           "V_f", "s")

#: Columns resampled with cubic Hermite interpolation, with the column holding their derivative.
_HERMITE = {"theta_v": "omega_v", "omega_v": "alpha_v"}


@dataclass(frozen=True, eq=False)
class Trajectory:
    """Equal-length arrays named by ``COLUMNS``; ``data`` has shape ``(len(COLUMNS), n)``."""

    data: np.ndarray
    meta: dict = field(default_factory=dict)

    def __post_init__(self):
        d = np.asarray(self.data, float)
        if d.ndim != 2 or d.shape[0] != len(COLUMNS):
            raise ValueError(f"trajectory data must have shape ({len(COLUMNS)}, n), not {d.shape}")
        d.setflags(write=False)
        object.__setattr__(self, "data", d)

    @classmethod
    def from_columns(cls, columns: dict, meta: dict | None = None) -> "Trajectory":
        missing = [c for c in COLUMNS if c not in columns]
        if missing:
            raise ValueError(f"trajectory is missing columns: {', '.join(missing)}")
        return cls(np.vstack([np.asarray(columns[c], float) for c in COLUMNS]), dict(meta or {}))

    def __len__(self) -> int:
        return self.data.shape[1]

    def __getattr__(self, name):
        # Columns as attributes: traj.theta_v, traj.C_f ...
        if name in COLUMNS:
            return self.data[COLUMNS.index(name)]
        raise AttributeError(name)

    def columns(self) -> dict:
        return {c: self.data[i] for i, c in enumerate(COLUMNS)}

    @property
    def duration(self) -> float:
        return float(self.t[-1] - self.t[0]) if len(self) else 0.0

    # -- resampling ----------------------------------------------------------------------------
    def resample(self, fps: float, start: float | None = None) -> "Trajectory":
        """Samples at ``start + k / fps`` over the trajectory's span.

        Position and heading use cubic Hermite interpolation with their exact derivatives
        (``V_f cos theta_dir``, ``V_f sin theta_dir``, ``V_f C_f``), the lean with ``omega_v``;
        the phase is unwrapped, interpolated and wrapped again, so it stays continuous.
        """
        if not (fps > 0 and math.isfinite(fps)):
            raise ValueError(f"fps = {fps!r} is outside the allowed range (0, inf)")
        t = self.t
        t0 = t[0] if start is None else float(start)
        n = int(math.floor((t[-1] - t0) * fps + 1e-9)) + 1
        tn = t0 + np.arange(max(n, 0)) / fps
        c = self.columns()
        deriv = {
            "x": c["V_f"] * np.cos(c["theta_dir"]),
            "y": c["V_f"] * np.sin(c["theta_dir"]),
            "theta_dir": c["V_f"] * c["C_f"],
            "s": c["V_f"],
            **{k: c[v] for k, v in _HERMITE.items()},
        }
        out = {"t": tn}
        for name in COLUMNS[1:]:
            if name in deriv:
                out[name] = _hermite(t, c[name], deriv[name], tn)
            elif name == "phi":
                out[name] = np.mod(np.interp(tn, t, np.unwrap(c[name])), TWO_PI)
            else:
                out[name] = np.interp(tn, t, c[name])
        meta = dict(self.meta, fps=float(fps))
        return Trajectory.from_columns(out, meta)

    # -- I/O -----------------------------------------------------------------------------------
    def to_csv(self, path) -> None:
        buf = io.StringIO()
        w = csv.writer(buf, lineterminator="\n")
        w.writerow(COLUMNS)
        for row in self.data.T:
            w.writerow([repr(float(v)) for v in row])
        atomic_write_text(path, buf.getvalue())

    @classmethod
    def from_csv(cls, path) -> "Trajectory":
        with open(path, newline="") as fh:
            rows = list(csv.reader(fh))
        if not rows or tuple(rows[0]) != COLUMNS:
            raise ValueError(f"{path}: the header must be exactly {','.join(COLUMNS)}")
        try:
            data = np.array([[float(v) for v in r] for r in rows[1:] if r], float).T
        except ValueError:
            raise ValueError(f"{path}: a value is not a number") from None
        return cls(data.reshape(len(COLUMNS), -1))

    def to_json(self, path) -> None:
        doc = {"columns": list(COLUMNS), "meta": self.meta,
               "data": {c: self.data[i].tolist() for i, c in enumerate(COLUMNS)}}
        atomic_write_text(path, json.dumps(doc))

    @classmethod
    def from_json(cls, path) -> "Trajectory":
        with open(path) as fh:
            doc = json.load(fh)
        return cls.from_columns(doc["data"], doc.get("meta", {}))


def _hermite(t, y, dy, tn):
    """Cubic Hermite interpolation of samples ``y`` with derivatives ``dy`` at times ``tn``."""
    i = np.clip(np.searchsorted(t, tn, side="right") - 1, 0, len(t) - 2)
    h = t[i + 1] - t[i]
    u = (tn - t[i]) / h
    u2, u3 = u * u, u * u * u
    return ((2 * u3 - 3 * u2 + 1) * y[i] + (u3 - 2 * u2 + u) * h * dy[i]
            + (-2 * u3 + 3 * u2) * y[i + 1] + (u3 - u2) * h * dy[i + 1])

"""The trajectory: the contract between the core, the mapping layer and Blender.

A :class:`Trajectory` holds equal-length 1-D arrays, one per column of ``COLUMNS`` (SI units,
radians; ``s`` is the foot's distance travelled, ``z`` the ground's height at the foot and
``V_cm`` the body's speed: 0 and constant on flat ground at a constant speed; ``skid`` the angle
from the foot's travel to the ski (board, tyre), ``ski_heading = theta_dir + skid`` and
``brake`` the braking force at the foot over the mass, m/s^2: 0, ``theta_dir`` and 0 for a
carved run, docs/skidding.md), plus a small
``meta`` mapping (preset, body parameters, the ground and resistance on terrain) that travels
with it in JSON.  CSV files have exactly these column names in a header
row.  Writers write to a temporary file and rename it, so a failure leaves no partial file.
"""
from __future__ import annotations

import csv
import json
import math
from dataclasses import dataclass, field, fields

import numpy as np

from .dynamics import foot_speed, forward_alpha, leg_force
from ..files import atomic_write_text
from .params import BodyParams, Limits
from ..ground.terrain import FLAT
from ..controllers.phase import phase

COLUMNS = ("t", "x", "y", "theta_dir", "theta_v", "omega_v", "alpha_v", "C_f", "F_leg", "phi",
           "V_f", "s", "z", "V_cm", "skid", "ski_heading", "brake")
CARVED_COLUMNS = COLUMNS[:-3]
"""The columns without ``skid``, ``ski_heading`` and ``brake``: still read, as a carved run
(``skid = 0``, ``ski_heading = theta_dir``, ``brake = 0``; docs/skidding.md)."""
LEGACY_COLUMNS = COLUMNS[:-5]
"""The columns without ``z`` and ``V_cm`` either: still read, as flat ground (``z = 0``)."""


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
        """From named columns.  Without ``z`` the ground is flat (``z = 0``); without ``V_cm``
        the speed is recovered from Eq. (21), ``V_cm = V_f (1 - C_f l sin theta_v)``, with the
        body recorded in ``meta`` (:func:`body_meta`)."""
        columns = _complete(columns, meta or {})
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

    # -- frame output --------------------------------------------------------------------------
    def resample(self, fps: float, start: float | None = None,
                 body: BodyParams | None = None, ground=None,
                 resistance=None, first: int = 0) -> "Trajectory":
        """Samples at ``start + k / fps`` over the trajectory's span, each a state of the model;
        ``k`` from ``first`` (the later samples of the whole span's, bit for bit).

        The state ``(x, y, theta_dir, theta_v, omega_v)`` and ``s`` between two samples is the
        integrator's dense output: the cubic Hermite interpolant through both samples with the
        model's derivatives there (``V_f cos theta_dir``, ``V_f sin theta_dir``, ``V_f C_f``,
        ``omega_v``, ``alpha_v``; ``V_f`` for ``s``), the continuous extension of RK4 that needs
        no extra evaluation (Hairer, Norsett, Wanner, *Solving ODEs I*, Section II.6).  Its
        error is ``h^4 max|y''''| / 384`` per step, the order of RK4's own global error;
        ``tests/test_frame_rows.py`` measures both.  Landing steps on frames would need the
        controller, which a finished trajectory (the Blender bake, the path follower) does not
        carry.

        Between samples ``C_f`` is the chord of the two samples' values.  RK4 has no single
        ``C_f`` inside a step (its stages evaluate the law at different trial states), so this is
        a choice: the chord keeps every Section 3 bound both samples meet (``|C_f| <= C_f_max``;
        ``|dC_f/dt| <= dC_f_max``, its slope being the samples' difference quotient) without
        knowing the limits, and is second-order accurate.  ``V_cm`` is recovered per sample from
        Eq. (21) and interpolated the same way (constant on flat ground).  Every other column
        is computed from the row's state and control, never interpolated: ``alpha_v`` by
        Eq. (2), ``V_f`` by Eq. (21), ``F_leg`` by Appendix A and ``phi`` by Section 4's atan2.
        So each row obeys the model's relations to round-off, and its phase lies in the quadrant
        of its own ``(theta_v, omega_v)``.

        ``phi`` depends on the ellipse only through ``omega0``: it is recovered per sample from
        ``tan phi = theta_v omega0 / omega_v`` and held over the step that starts there, as the
        controllers hold it (the phase-ellipse controller changes its beta only at a step's
        start; Section 6.2's estimate is constant per quadrant visit).  A sample on an axis of
        the phase plane, where the phase does not depend on ``omega0``, takes the next sample's.

        ``body`` defaults to the one recorded in ``meta`` (:func:`body_meta`).

        **On terrain** (a trajectory from the terrain loop, ``meta["ground"]`` set; pass the
        ``ground`` it ran on, :mod:`.terrain`, unless flat; or a trajectory without meta, e.g.
        read from a CSV, given ``ground=`` and ``resistance=``) the state is ``(x, y, theta_dir,
        theta_v, omega_v,
        V_cm)`` and all six, and ``s``, are Hermite-interpolated with the terrain model's
        derivatives at the samples (:func:`.model.rhs` under the recorded
        ``C_f``; the friction and drag recorded in ``meta``).  ``z`` is the ground's height at
        the interpolated ``(x, y)``; ``alpha_v``, ``V_f``, ``F_leg`` come from the terrain
        model at the row's state; ``phi`` (the controller's phase, about its equilibrium lean,
        docs/TERRAIN.md Section 6, which the trajectory does not record) is interpolated along
        the step the shorter way round the circle, exact at the samples.
        """
        if not (fps > 0 and math.isfinite(fps)):
            raise ValueError(f"fps = {fps!r} is outside the allowed range (0, inf)")
        body = body_from_meta(self.meta) if body is None else body
        if body is None:
            raise ValueError("resample needs the figure's body: pass body= or keep the meta "
                             "entries body.m, body.l, body.I_v, body.V_cm and body.g")
        t, c = self.t, self.columns()
        if len(t) == 0 or np.any(np.diff(t) <= 0):
            raise ValueError("a trajectory to resample needs samples at increasing times")
        t0 = t[0] if start is None else float(start)
        n = int(math.floor((t[-1] - t0) * fps + 1e-9)) + 1
        tn = t0 + np.arange(min(first, max(n, 0)), max(n, 0)) / fps
        meta = dict(self.meta, fps=float(fps))
        if len(t) == 1:
            at = np.zeros(int(np.sum(np.abs(tn - t[0]) <= 1e-9)), int)     # the one sample
            return Trajectory(self.data[:, at], meta)
        j = np.clip(np.searchsorted(t, tn, side="right") - 1, 0, len(t) - 1)  # frame's step
        i = np.minimum(j, len(t) - 2)
        if len(tn):                 # the samples the frames lie between (a window: a few)
            lo, hi = int(i[0]), int(i[-1]) + 2
            t, c, i, j = t[lo:hi], {k: v[lo:hi] for k, v in c.items()}, i - lo, j - lo
        u = (tn - t[i]) / (t[i + 1] - t[i])
        ran_on = self.meta.get("ground")          # None: the paper's flat model
        if ran_on is not None or ground is not None or resistance is not None:
            if ground is None:
                if ran_on not in (None, "flat"):
                    raise ValueError(f"this trajectory ran on {ran_on}: pass ground= (the "
                                     "surface it ran on) to resample it")
                ground = FLAT
            rows = _terrain_rows(body, ground, resistance, self.meta, t, c, tn, i, u)
            return Trajectory.from_columns(rows, meta)
        V_f, C_f = c["V_f"], c["C_f"]
        slope = {"x": V_f * np.cos(c["theta_dir"]), "y": V_f * np.sin(c["theta_dir"]),
                 "theta_dir": V_f * C_f, "theta_v": c["omega_v"], "omega_v": c["alpha_v"],
                 "s": V_f}
        out = {"t": tn, **{k: _hermite(t, c[k], dy, i, u) for k, dy in slope.items()}}
        V_cm = V_f * (1.0 - C_f * body.l * np.sin(c["theta_v"]))              # Eq. (21)
        V = (1.0 - u) * V_cm[i] + u * V_cm[i + 1]
        th, om = out["theta_v"], out["omega_v"]
        cf = out["C_f"] = (1.0 - u) * C_f[i] + u * C_f[i + 1]
        sin_t = np.sin(th)
        out["alpha_v"] = forward_alpha(body, th, cf, sin_t, np.cos(th), V)     # Eq. (2)
        out["V_f"] = foot_speed(body, th, cf, sin_t, V)                         # Eq. (21)
        out["F_leg"] = leg_force(body, th, om, out["alpha_v"], cf, V)[0]       # Appendix A
        out["phi"] = phase(th, om, 1.0, _ellipse_rate(c["theta_v"], c["omega_v"], c["phi"])[j])
        out["z"], out["V_cm"] = np.zeros(len(tn)), V
        _skid_rows(out, c, i, u)
        return Trajectory.from_columns(out, meta)

    # -- I/O -----------------------------------------------------------------------------------
    def to_csv(self, path) -> None:
        # The text csv.writer gives (names and float reprs need no quoting), a few times faster:
        # a crowd writes thousands of these.
        rows = [",".join(COLUMNS)]
        rows += [",".join(map(repr, row)) for row in self.data.T.tolist()]
        atomic_write_text(path, "\n".join(rows) + "\n")

    @classmethod
    def from_csv(cls, path, body: BodyParams | None = None) -> "Trajectory":
        """Read a CSV written by :meth:`to_csv`.  A file from before terrain (the header
        ``LEGACY_COLUMNS``) is flat ground: ``z = 0``, ``V_cm`` from Eq. (21) with ``body``."""
        with open(path, newline="") as fh:
            rows = list(csv.reader(fh))
        header = tuple(rows[0]) if rows else ()
        if header not in (COLUMNS, CARVED_COLUMNS, LEGACY_COLUMNS):
            raise ValueError(f"{path}: the header must be exactly {','.join(COLUMNS)}")
        try:
            data = np.array([[float(v) for v in r] for r in rows[1:] if r], float).T
        except ValueError:
            raise ValueError(f"{path}: a value is not a number") from None
        data = data.reshape(len(header), -1)
        if header == COLUMNS:
            return cls(data)
        if header == CARVED_COLUMNS:
            return cls.from_columns(dict(zip(header, data)))
        if body is None:
            raise ValueError(f"{path} has no V_cm column (written before terrain): pass body= to "
                             "recover it from Eq. (21)")
        return cls.from_columns(dict(zip(header, data)), body_meta(body))

    def to_json(self, path) -> None:
        doc = {"columns": list(COLUMNS), "meta": self.meta,
               "data": {c: self.data[i].tolist() for i, c in enumerate(COLUMNS)}}
        atomic_write_text(path, json.dumps(doc))

    @classmethod
    def from_json(cls, path) -> "Trajectory":
        with open(path) as fh:
            doc = json.load(fh)
        return cls.from_columns(doc["data"], doc.get("meta", {}))


def body_meta(body: BodyParams) -> dict:
    """The ``meta`` entries that record ``body``: ``body.m``, ``body.l``, ... (SI units)."""
    return {f"body.{f.name}": float(getattr(body, f.name)) for f in fields(body)}


def body_from_meta(meta: dict) -> BodyParams | None:
    """The body :func:`body_meta` recorded, or ``None`` if ``meta`` holds none."""
    try:
        return BodyParams(**{f.name: float(meta[f"body.{f.name}"]) for f in fields(BodyParams)})
    except KeyError:
        return None


def resistance_meta(resistance) -> dict:
    """The ``meta`` entries that record a :class:`.model.Resistance`."""
    return {f"resistance.{f.name}": float(getattr(resistance, f.name))
            for f in fields(resistance)}


def _terrain_rows(body, ground, res, meta, t, c, tn, i, u) -> dict:
    """:meth:`Trajectory.resample` on terrain: the rows at times ``tn`` (step ``i``, fraction
    ``u``); ``res`` the resistance (``None``: the one recorded in ``meta``, else none)."""
    from . import model
    from .model import Resistance
    if res is None:
        res = Resistance(**{k: float(meta[f"resistance.{k}"]) for k in ("mu", "CdA", "rho")
                            if f"resistance.{k}" in meta})
    free = Limits()                         # the recorded C_f is already bounded
    state = tuple(c[k] for k in ("x", "y", "theta_dir", "theta_v", "omega_v", "V_cm"))
    deriv, _, _, V_f, _, _ = model.rhs(body, free, ground, c["C_f"], state, resistance=res)
    # The recorded braking force, already bounded by the grip; a figure at rest (after a stop)
    # is held there by the snow (docs/skidding.md Section 4).
    V_cm = c["V_cm"]
    moving = V_cm > 0.0
    deriv = tuple(np.where(moving, dy, 0.0) for dy in deriv[:5]) + (np.where(
        moving, deriv[5] - c["brake"] * V_f / np.where(moving, V_cm, 1.0), 0.0),)
    names = ("x", "y", "theta_dir", "theta_v", "omega_v", "V_cm")
    out = {"t": tn, **{k: _hermite(t, c[k], dy, i, u) for k, dy in zip(names, deriv)},
           "s": _hermite(t, c["s"], V_f, i, u)}
    out["V_cm"] = np.maximum(out["V_cm"], 0.0)          # coming to rest: never backwards
    cf = out["C_f"] = (1.0 - u) * c["C_f"][i] + u * c["C_f"][i + 1]
    st = tuple(out[k] for k in names)
    _, _, alpha, V_f, _, fr = model.rhs(body, free, ground, cf, st, resistance=res)
    out["alpha_v"], out["V_f"], out["z"] = alpha, V_f, fr.z
    th, om, V = out["theta_v"], out["omega_v"], out["V_cm"]
    out["F_leg"] = model.leg_force(body, th, om, alpha, cf, V, V_f, fr)[0]
    # The controller's phase is about its equilibrium lean, which the trajectory does not
    # record: interpolated along the step (the shorter way round), exact at the samples.
    dphi = np.mod(c["phi"][i + 1] - c["phi"][i] + np.pi, 2 * np.pi) - np.pi
    out["phi"] = np.mod(c["phi"][i] + u * dphi, 2 * np.pi)
    _skid_rows(out, c, i, u)
    return out


def _skid_rows(out, c, i, u) -> None:
    """The ski's columns at the fraction ``u`` of step ``i``: ``skid`` and ``brake`` the chords
    of the samples' values (controls, as ``C_f``), ``ski_heading = theta_dir + skid``."""
    for k in ("skid", "brake"):
        out[k] = (1.0 - u) * c[k][i] + u * c[k][i + 1]
    out["ski_heading"] = out["theta_dir"] + out["skid"]


def _complete(columns: dict, meta: dict) -> dict:
    """``columns`` with ``z`` (flat: 0), ``V_cm`` (Eq. 21 with the body in ``meta``) and the
    carved ski (``skid = brake = 0``, ``ski_heading = theta_dir``) added when missing."""
    if all(k in columns for k in ("z", "V_cm", "skid", "ski_heading", "brake")):
        return columns
    out = dict(columns)
    if "theta_dir" in out:
        d = np.asarray(out["theta_dir"], float)
        out.setdefault("skid", np.zeros(d.shape))
        out.setdefault("brake", np.zeros(d.shape))
        out.setdefault("ski_heading", d + np.asarray(out["skid"], float))
    if "z" not in out and "x" in out:
        out["z"] = np.zeros(np.shape(out["x"]))
    if "V_cm" not in out and all(k in out for k in ("V_f", "C_f", "theta_v")):
        body = body_from_meta(meta)
        if body is None:
            raise ValueError("trajectory is missing the column V_cm and its meta records no body "
                             "to recover it from V_f (Eq. 21)")
        out["V_cm"] = (np.asarray(out["V_f"], float)
                       * (1.0 - np.asarray(out["C_f"], float) * body.l
                          * np.sin(np.asarray(out["theta_v"], float))))
    return out


def _hermite(t, y, dy, i, u):
    """Cubic Hermite interpolation of samples ``y`` with derivatives ``dy`` on step ``i``
    (from ``t[i]`` to ``t[i + 1]``) at the fraction ``u`` of it."""
    h = t[i + 1] - t[i]
    u2, u3 = u * u, u * u * u
    return ((2 * u3 - 3 * u2 + 1) * y[i] + (u3 - 2 * u2 + u) * h * dy[i]
            + (-2 * u3 + 3 * u2) * y[i + 1] + (u3 - u2) * h * dy[i + 1])


def _ellipse_rate(theta_v, omega_v, phi):
    """The ``omega0`` of each sample's phase, from ``tan phi = theta_v omega0 / omega_v``.

    A sample with ``|sin phi cos phi| < 1e-6`` lies on an axis of the phase plane, where the
    phase does not depend on ``omega0`` and the inversion loses digits: it takes the next
    recoverable sample's value (the last one's at the end), 1 if there is none (a straight run).
    """
    sp, cp = np.sin(phi), np.cos(phi)
    with np.errstate(divide="ignore", invalid="ignore"):
        w = (omega_v * sp) / (theta_v * cp)
    ok = np.flatnonzero(np.isfinite(w) & (w > 0.0) & (np.abs(sp * cp) > 1e-6))
    if len(ok) == 0:
        return np.ones(len(w))
    return w[ok[np.minimum(np.searchsorted(ok, np.arange(len(w))), len(ok) - 1)]]


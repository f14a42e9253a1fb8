"""A scene's ``terrain`` (the format is in docs/cli.md, "Scene files"): the ground the
path is drawn on and what slows the figure there.

- ``{"type": "plane", "slope_deg": 18, "downhill_deg": -90, "origin": [0, 0], "z0": 0}``: an
  inclined plane (:class:`.terrain.Plane`) through ``(origin, z0)``, steepest descent along
  ``downhill_deg`` (CCW from +x);
- ``{"type": "height_field", "heights": [[...], ...], "origin": [x0, y0], "cell": 2}``: heights
  ``heights[j][i]`` at ``(x0 + i cell, y0 + j cell)`` (:class:`.terrain.HeightField`); or
  ``"file": "ground.npy"`` instead of ``heights``, a 2-D numpy array, the path relative to the
  scene file;
- either may give ``friction``, ``drag_area``, ``air_density``; those not given are the sport's
  (each sport record's ``resistance``, sources there; :data:`.model.RESISTANCE`).

Every problem is a ``FieldError`` naming the file and the field (ranges: :mod:`.ranges`).
"""
from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np

from ..ranges import RANGES
from .terrain import HeightField, Plane
from ..physics.model import RESISTANCE, Resistance
from ..validate import Fields, check

__all__ = ["read_terrain"]

_KEYS = {"type", "slope_deg", "downhill_deg", "origin", "z0", "heights", "file", "cell",
         "friction", "drag_area", "air_density"}
_RES = {"friction": "mu", "drag_area": "CdA", "air_density": "rho"}


def read_terrain(tf: Fields, sport: str):
    """``(ground, resistance)`` of a scene's ``terrain`` table ``tf`` for the preset ``sport``."""
    kind = tf.string("type", choices=("plane", "height_field"))
    plane_only = {"slope_deg", "downhill_deg", "z0"}
    field_only = {"heights", "file", "cell"}
    for k in tf.keys():
        if k in (field_only if kind == "plane" else plane_only):
            tf.fail(k, f"is not a field of a {kind} terrain")
    tf.only(_KEYS)
    origin = tf.xy("origin", [0.0, 0.0])
    if kind == "plane":
        slope = math.radians(tf.number("slope_deg", RANGES["slope"].deg()))
        down = math.radians(tf.number("downhill_deg", RANGES["heading"].deg(), -90.0))
        z0 = tf.number("z0", "height", 0.0)
        ground = Plane(slope, down, float(origin[0]), float(origin[1]), z0)
    else:
        ground = HeightField(_heights(tf), float(origin[0]), float(origin[1]),
                             tf.number("cell", "cell"))
    given = {field: tf.number(key, key) for key, field in _RES.items() if tf.has(key)}
    return ground, replace(RESISTANCE.get(sport, Resistance()), **given)


def _heights(tf: Fields) -> np.ndarray:
    if tf.has("heights") == tf.has("file"):
        tf.fail("heights", "or terrain.file: exactly one is needed")
    if tf.has("file"):
        name = tf.string("file")
        path = Path(name)
        if not path.is_absolute() and Path(tf.source).parent.is_dir():
            path = Path(tf.source).parent / path
        try:
            h = np.load(path, allow_pickle=False)
        except (OSError, ValueError) as exc:
            tf.fail("file", f"= {name!r} cannot be read as a .npy array ({exc})")
        key = "file"
    else:
        raw = tf.value("heights")
        ok = isinstance(raw, list) and raw and all(isinstance(r, list) for r in raw)
        if ok:
            n = len(raw[0])
            ok = all(len(r) == n for r in raw) and all(
                isinstance(v, (int, float)) and not isinstance(v, bool) for r in raw for v in r)
        if not ok:
            tf.fail("heights", "is not a list of rows of numbers, all of the same length")
        h = np.array(raw, float)
        key = "heights"
    if h.ndim != 2 or not np.issubdtype(h.dtype, np.number):
        tf.fail(key, f"holds an array of shape {h.shape}; a 2-D grid of heights is needed")
    for axis, what in ((0, "rows"), (1, "columns")):
        check(f"{tf.name(key)} {what}", h.shape[axis], "grid_points", tf.source)
    h = h.astype(float)
    bad = ~np.isfinite(h) | (h < RANGES["height"].lo) | (h > RANGES["height"].hi)
    if bad.any():
        j, i = np.argwhere(bad)[0]
        check(f"{tf.name(key)}[{j}][{i}]", float(h[j, i]), "height", tf.source)
    return h

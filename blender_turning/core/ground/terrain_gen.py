"""A procedural mountain of the project's own, for the demo and the tests: a ski slope with a fall
line, a few rolls and a mogul field, and a road over a hill.  Deterministic from a seed."""
from __future__ import annotations

import math

import numpy as np

from ..physics.params import check_range
from .terrain import HeightField

__all__ = ["ski_slope"]


def ski_slope(length: float = 200.0, width: float = 200.0, slope_deg: float = 18.0,
              cell: float = 1.0, seed: int = 7, moguls: bool = True) -> HeightField:
    """A slope falling toward -y (the fall line, ``downhill = -90 deg``), ``width`` across x and
    ``length`` along y, centred on the origin at height 0.

    On top of the plane: two broad rolls across the fall line (1-2 m high, 40-70 m long), a gentle
    side tilt that varies along the slope (so traverses differ left and right), and, if
    ``moguls``, a mogul field (bumps ~0.5 m high every ~4 m) on the lower left quarter.  Every
    random choice comes from ``seed``.
    """
    check_range("length", length, 10.0, 5000.0)
    check_range("width", width, 10.0, 5000.0)
    check_range("slope_deg", slope_deg, 0.0, 45.0)
    check_range("cell", cell, 0.05, 50.0)
    rng = np.random.default_rng(seed)
    xs = np.arange(-width / 2, width / 2 + 0.5 * cell, cell)
    ys = np.arange(-length / 2, length / 2 + 0.5 * cell, cell)
    X, Y = np.meshgrid(xs, ys)
    h = math.tan(math.radians(slope_deg)) * Y
    for _ in range(2):
        wave = rng.uniform(40.0, 70.0)
        h += rng.uniform(1.0, 2.0) * np.sin(2 * math.pi * Y / wave + rng.uniform(0, 2 * math.pi))
    h += 0.04 * X * np.sin(2 * math.pi * Y / length)
    if moguls:
        spacing = 4.0
        bumps = (0.25 * (1 - np.cos(2 * math.pi * X / spacing))
                 * (1 - np.cos(2 * math.pi * (Y + 0.5 * X) / spacing)) * 0.5)
        # Fade the field in and out smoothly over 10 m so the slope stays C1.
        fx = _smoothstep((-X - 10.0) / 10.0) * _smoothstep((X + width / 2 - 5.0) / 10.0)
        fy = _smoothstep((-Y - 10.0) / 10.0) * _smoothstep((Y + length / 2 - 5.0) / 10.0)
        h += bumps * fx * fy
    return HeightField(h, float(xs[0]), float(ys[0]), cell)


def _smoothstep(u):
    u = np.clip(u, 0.0, 1.0)
    return u * u * (3 - 2 * u)

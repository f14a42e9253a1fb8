"""The ground under the figure: a surface ``z = h(x, y)`` and its local frame (docs/TERRAIN.md).

The paper stops at flat ground (Section 8 calls non-planar terrain "a formidable challenge").
Here the ground is any surface given by its height and its first and second derivatives at a
point; two kinds are shipped:

- :class:`Plane`: slope ``sigma`` and downhill direction ``D`` (steepest descent, CCW from +x);
  ``Plane(0, 0)`` is the paper's flat ground;
- :class:`HeightField`: heights on a regular grid (a terrain scanned from a Blender mesh, a .npy
  file), interpolated by a bicubic Catmull-Rom spline so that the normal is continuous (C1) and
  the normal curvature is finite everywhere.

:func:`surface_frame` gives, at the foot ``(x, y)`` moving with horizontal heading
``theta_dir``, the Darboux frame of the foot path (tangent ``t``, left ``b = n x t``, normal
``n``), the three components of gravity in it, the surface's normal curvature along ``t`` and
the factors that turn an in-surface curvature into a rate of the horizontal heading.  Everything
takes Python floats or numpy arrays (a batch) and broadcasts.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from .params import check_range

__all__ = ["Plane", "HeightField", "FLAT", "SurfaceFrame", "surface_frame"]


@dataclass(frozen=True)
class Plane:
    """An inclined plane through ``(x0, y0, z0)``."""

    slope: float = 0.0
    """Angle between the plane and the horizontal, ``sigma``, rad, in [0, 60 deg]."""
    downhill: float = 0.0
    """Direction of steepest descent ``D``, rad, CCW from +x."""
    x0: float = 0.0
    """A point of the plane, m."""
    y0: float = 0.0
    """A point of the plane, m."""
    z0: float = 0.0
    """The plane's height at ``(x0, y0)``, m."""

    def __post_init__(self):
        # 60 deg is steeper than any skiable or rideable slope (an extreme couloir is ~55 deg).
        check_range("slope", self.slope, 0.0, math.radians(60.0))
        check_range("downhill", self.downhill, -1e3, 1e3)
        for name in ("x0", "y0", "z0"):
            check_range(name, getattr(self, name), -1e6, 1e6)

    @property
    def flat(self) -> bool:
        """True for the paper's horizontal ground."""
        return self.slope == 0.0

    def derivatives(self, x, y):
        """``(h, h_x, h_y, h_xx, h_xy, h_yy)`` at ``(x, y)``."""
        m = math.tan(self.slope)
        hx = -m * math.cos(self.downhill)
        hy = -m * math.sin(self.downhill)
        h = self.z0 + hx * (np.asarray(x) - self.x0) + hy * (np.asarray(y) - self.y0)
        zero = np.zeros_like(h)
        return h, hx + zero, hy + zero, zero, zero, zero


FLAT = Plane()


class HeightField:
    """Heights ``heights[j, i]`` at ``(x0 + i cell, y0 + j cell)``, bicubic Catmull-Rom between.

    Catmull-Rom's tangents are central differences, exact for quadratics, so a plane or a
    quadratic bowl sampled on the grid comes back exactly (away from the border, where the grid is
    extended linearly; a plane comes back exactly everywhere).  The surface is C1: its normal is
    continuous, its curvature jumps at cell borders by the third differences of the data.
    """

    def __init__(self, heights, x0: float, y0: float, cell: float):
        h = np.asarray(heights, dtype=float)
        if h.ndim != 2 or min(h.shape) < 2:
            raise ValueError(f"heights has shape {h.shape}; a grid of at least 2 x 2 is needed")
        if not np.isfinite(h).all():
            raise ValueError("heights holds a value that is not a finite number")
        self.cell = check_range("cell", cell, 0.0, 1e4, lo_open=True)
        self.x0 = check_range("x0", x0, -1e6, 1e6)
        self.y0 = check_range("y0", y0, -1e6, 1e6)
        self.ny, self.nx = h.shape
        # Extend the grid by two rows/columns each side, linearly, so the 4 x 4 stencil exists.
        for axis in (0, 1):
            n = h.shape[axis]
            first = np.take(h, [0], axis) - np.take(h, [1], axis)
            last = np.take(h, [n - 1], axis) - np.take(h, [n - 2], axis)
            h = np.concatenate([np.take(h, [0], axis) + 2 * first, np.take(h, [0], axis) + first,
                                h, np.take(h, [n - 1], axis) + last,
                                np.take(h, [n - 1], axis) + 2 * last], axis)
        self._h = h

    @property
    def flat(self) -> bool:
        return False

    @property
    def extent(self):
        """``(x_min, x_max, y_min, y_max)`` of the grid, m."""
        return (self.x0, self.x0 + (self.nx - 1) * self.cell,
                self.y0, self.y0 + (self.ny - 1) * self.cell)

    def contains(self, x, y):
        """Whether ``(x, y)`` lies on the grid."""
        x_lo, x_hi, y_lo, y_hi = self.extent
        return (x >= x_lo) & (x <= x_hi) & (y >= y_lo) & (y <= y_hi)

    def derivatives(self, x, y):
        """``(h, h_x, h_y, h_xx, h_xy, h_yy)`` at ``(x, y)`` (inside :attr:`extent`)."""
        x = np.asarray(x, dtype=float)
        y = np.asarray(y, dtype=float)
        if not np.all(self.contains(x, y)):
            raise ValueError(f"a point lies off the terrain; it covers x, y in "
                             f"[{self.extent[0]:g}, {self.extent[1]:g}] x "
                             f"[{self.extent[2]:g}, {self.extent[3]:g}] m")
        fx = (x - self.x0) / self.cell
        fy = (y - self.y0) / self.cell
        i = np.minimum(np.floor(fx).astype(int), self.nx - 2)
        j = np.minimum(np.floor(fy).astype(int), self.ny - 2)
        wx, dwx, ddwx = _catmull_rom(fx - i)
        wy, dwy, ddwy = _catmull_rom(fy - j)
        # Stencil rows j-1..j+2 and columns i-1..i+2 of the data: +2 for the padding.
        rows = (j + 1)[..., None] + np.arange(4)
        cols = (i + 1)[..., None] + np.arange(4)
        patch = self._h[rows[..., :, None], cols[..., None, :]]         # (..., 4, 4)

        def ev(a, b):
            return np.einsum("...j,...ji,...i->...", a, patch, b)

        c = self.cell
        return (ev(wy, wx), ev(wy, dwx) / c, ev(dwy, wx) / c,
                ev(wy, ddwx) / (c * c), ev(dwy, dwx) / (c * c), ev(ddwy, wx) / (c * c))


def _catmull_rom(u):
    """Catmull-Rom weights of the 4 stencil points at ``u`` in [0, 1] and their u-derivatives."""
    u2, u3 = u * u, u * u * u
    w = np.stack([-u + 2 * u2 - u3, 2 - 5 * u2 + 3 * u3, u + 4 * u2 - 3 * u3, -u2 + u3], -1)
    dw = np.stack([-1 + 4 * u - 3 * u2, -10 * u + 9 * u2, 1 + 8 * u - 9 * u2, -2 * u + 3 * u2], -1)
    ddw = np.stack([4 - 6 * u, -10 + 18 * u, 8 - 18 * u, -2 + 6 * u], -1)
    return 0.5 * w, 0.5 * dw, 0.5 * ddw


class SurfaceFrame(NamedTuple):
    """The foot's frame on the surface (docs/TERRAIN.md Section 1).  Vectors have shape
    ``(3, ...)``; scalars broadcast with the query."""

    z: object
    """Surface height at the foot, m."""
    t: object
    """Unit tangent of the foot path: the horizontal heading lifted onto the surface."""
    b: object
    """Unit in-surface normal to the left, ``n x t``."""
    n: object
    """Unit surface normal, upward."""
    g_normal: object
    """Gravity into the surface, ``g n_z`` (``g cos sigma`` on a plane), m/s^2."""
    g_lateral: object
    """Gravity along ``b`` (to the left when > 0), m/s^2."""
    g_along: object
    """Gravity along ``t`` (speeds the figure up when > 0), m/s^2."""
    kappa_n: object
    """Normal curvature of the surface along ``t``, 1/m (> 0 where it curves up: a hollow)."""
    turn_gain: object
    """``d theta_dir / d(in-surface turning)``: ``(t_x b_y - t_y b_x) / (t_x^2 + t_y^2)``."""
    bend_gain: object
    """``d theta_dir / d(normal turning)``: ``(t_x n_y - t_y n_x) / (t_x^2 + t_y^2)``."""


def surface_frame(ground, x, y, theta_dir, g: float) -> SurfaceFrame:
    """The frame of a foot at ``(x, y)`` heading ``theta_dir`` (horizontal, CCW from +x)."""
    h, hx, hy, hxx, hxy, hyy = ground.derivatives(x, y)
    c, s = np.cos(theta_dir), np.sin(theta_dir)
    p = hx * c + hy * s                                   # slope along the heading
    inv_t = 1.0 / np.sqrt(1.0 + p * p)
    t = np.stack(np.broadcast_arrays(c * inv_t, s * inv_t, p * inv_t))
    inv_n = 1.0 / np.sqrt(1.0 + hx * hx + hy * hy)
    n = np.stack(np.broadcast_arrays(-hx * inv_n, -hy * inv_n, inv_n))
    b = np.cross(n, t, axis=0)
    # Second fundamental form over the first along (c, s): Euler's normal curvature of a graph.
    kappa_n = (hxx * c * c + 2.0 * hxy * c * s + hyy * s * s) * inv_n * inv_t * inv_t
    hor = t[0] * t[0] + t[1] * t[1]
    return SurfaceFrame(
        z=h, t=t, b=b, n=n,
        g_normal=g * n[2], g_lateral=-g * b[2], g_along=-g * t[2], kappa_n=kappa_n,
        turn_gain=(t[0] * b[1] - t[1] * b[0]) / hor, bend_gain=(t[0] * n[1] - t[1] * n[0]) / hor)

"""The ground under the figure: a surface ``z = h(x, y)`` and its local frame (docs/TERRAIN.md).

The paper stops at flat ground (Section 8 calls non-planar terrain "a formidable challenge").
Here the ground is any surface given by its height and its first and second derivatives at a
point; two kinds are shipped:

- :class:`Plane`: slope ``sigma`` and downhill direction ``D`` (steepest descent, CCW from +x);
  ``Plane(0, 0)`` is the paper's flat ground;
- :class:`HeightField`: heights on a regular grid (a terrain scanned from a Blender mesh, a .npy
  file), interpolated by a biquintic Hermite spline whose curvature is continuous (C2), so the
  right-hand side of the turning model (which holds the curvature through ``kappa_n``) is
  continuous too and a run converges as the step shrinks (docs/TERRAIN.md Section 1).

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

from ..validate import check

__all__ = ["Plane", "HeightField", "LazyHeightField", "FLAT", "SurfaceFrame", "surface_frame",
           "OffTerrain"]


class OffTerrain(ValueError):
    """A point off a :class:`HeightField`'s grid."""


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
        check("slope", self.slope, "slope")                  # ranges: core/ranges.py
        check("downhill", self.downhill, "heading")
        for name, key in (("x0", "coordinate"), ("y0", "coordinate"), ("z0", "height")):
            check(name, getattr(self, name), key)

    @property
    def flat(self) -> bool:
        """True for the paper's horizontal ground."""
        return self.slope == 0.0
    def derivatives_one(self, x: float, y: float):
        """:meth:`derivatives` on Python floats."""
        m = math.tan(self.slope)
        hx = -m * math.cos(self.downhill)
        hy = -m * math.sin(self.downhill)
        return self.z0 + hx * (x - self.x0) + hy * (y - self.y0), hx, hy, 0.0, 0.0, 0.0

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
    """Heights ``heights[j, i]`` at ``(x0 + i cell, y0 + j cell)``, biquintic Hermite between.

    Each grid point carries the height, the first and second differences of its neighbours
    (central, as estimates of ``h_x, h_y, h_xx, h_yy`` and of the cross derivatives up to
    ``h_xxyy``), and each cell is the tensor-product quintic Hermite patch through the values and
    derivatives at its four corners (docs/TERRAIN.md Section 1).  Neighbouring cells share the
    corner data, so the surface and its first and second derivatives are continuous (C2) across
    every cell edge; a cell depends on the 4 x 4 grid points around it, as a Catmull-Rom
    bicubic's would.  Central differences are exact for quadratics, so a plane or a quadratic
    bowl sampled on the grid comes back exactly (away from the border, where the grid is
    extended linearly; a plane comes back exactly everywhere).  The spline interpolates: it
    passes through every grid point.
    """

    def __init__(self, heights, x0: float, y0: float, cell: float):
        h = np.asarray(heights, dtype=float)
        if h.ndim != 2 or min(h.shape) < 2:
            raise ValueError(f"heights has shape {h.shape}; a grid of at least 2 x 2 is needed")
        if not np.isfinite(h).all():
            raise ValueError("heights holds a value that is not a finite number")
        self.cell = check("cell", cell, "cell")
        self.x0 = check("x0", x0, "coordinate")
        self.y0 = check("y0", y0, "coordinate")
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
        self._coef = {}                    # cell index -> its biquintic's coefficients (_cell)
        self.derivatives_one = _float_derivatives(self)
        self.slopes_one = _float_derivatives(self, height=False)

    def __reduce__(self):                  # derivatives_one is a closure: send the heights
        return HeightField, (self._h[2:-2, 2:-2].copy(), self.x0, self.y0, self.cell)

    def _store(self, r0, c0):
        """The padded grid, holding at least the 4 x 4 stencils with top-left corners
        ``(r0, c0)`` (padded indices, ints or arrays): all of it here; :class:`LazyHeightField`
        computes what is asked for."""
        return self._h

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
            raise OffTerrain(f"a point lies off the terrain; it covers x, y in "
                             f"[{self.extent[0]:g}, {self.extent[1]:g}] x "
                             f"[{self.extent[2]:g}, {self.extent[3]:g}] m")
        fx = (x - self.x0) / self.cell
        fy = (y - self.y0) / self.cell
        i = np.minimum(np.floor(fx).astype(int), self.nx - 2)
        j = np.minimum(np.floor(fy).astype(int), self.ny - 2)
        wx, dwx, ddwx = _weights(fx - i)
        wy, dwy, ddwy = _weights(fy - j)
        # Stencil rows j-1..j+2 and columns i-1..i+2 of the data: +2 for the padding.
        rows = (j + 1)[..., None] + np.arange(4)
        cols = (i + 1)[..., None] + np.arange(4)
        patch = self._store(j + 1, i + 1)[rows[..., :, None], cols[..., None, :]]  # (.., 4, 4)
        # About the cell's corner height (the weights sum to 1, their derivatives to 0): the
        # derivatives come from the relief, not from the altitude (less round-off).
        base = patch[..., 1, 1]
        patch = patch - base[..., None, None]

        def ev(a, b):
            return np.einsum("...j,...ji,...i->...", a, patch, b)

        c = self.cell
        return (base + ev(wy, wx), ev(wy, dwx) / c, ev(dwy, wx) / c,
                ev(wy, ddwx) / (c * c), ev(dwy, dwx) / (c * c), ev(ddwy, wx) / (c * c))

    def _cell(self, i: int, j: int):
        """Cell ``(i, j)``'s biquintic as polynomial coefficients in ``u^a v^b``: the weights
        of the 4 x 4 stencil ``P`` are ``w(u) = M (1, u, .., u^5)`` (:data:`_HERMITE_POWERS`), so
        ``h = w(v)^T P w(u) = (1, v, ..)^T (M^T P M) (1, u, ..)`` (``P`` taken about its corner
        ``P[1, 1]``, added back to ``A[0][0]``: the weights sum to 1).  Returned as one tuple:
        the 36 coefficients ``A[b][a]`` (row-major), then those of ``dh/du`` (30, ``(a + 1)
        A[b][a + 1]``) and of ``d2h/du2`` (24), so the float evaluation multiplies by no
        constants in ``u``.  Computed for the :data:`BLOCK` x :data:`BLOCK` cells about it at
        once (one numpy pass: ~4 us a cell against ~16 us one by one, the same numbers bit for
        bit, ``tests/test_terrain.py``) and kept for the cells a figure visits (all cells of a
        0.25 m mesh would be 180 MB): a run near an earlier one (a Live Preview drag) finds
        its cells made."""
        B = BLOCK
        i0, j0 = i - i % B, j - j % B
        jj, ii = np.mgrid[j0:min(j0 + B, self.ny - 1), i0:min(i0 + B, self.nx - 1)]
        jj, ii = jj.ravel(), ii.ravel()
        rows = (jj + 1)[:, None, None] + np.arange(4)[:, None]
        cols = (ii + 1)[:, None, None] + np.arange(4)
        P = self._store(jj + 1, ii + 1)[rows, cols]                      # (cells, 4, 4)
        base = P[:, 1, 1].copy()                 # the corner height apart, as in derivatives
        A = _HERMITE_POWERS.T @ (P - base[:, None, None]) @ _HERMITE_POWERS
        A[:, 0, 0] += base
        Au = A[:, :, 1:] * _POW[1:]
        Auu = Au[:, :, 1:] * _POW[1:-1]
        n = len(P)
        coef = self._coef
        for key, A in zip((jj * self.nx + ii).tolist(), np.concatenate(
                [A.reshape(n, -1), Au.reshape(n, -1), Auu.reshape(n, -1)], 1).tolist()):
            coef[key] = tuple(A)
        return coef[j * self.nx + i]


BLOCK = 4
"""Cells whose polynomials :meth:`HeightField._cell` computes together (BLOCK x BLOCK, 1 m x
1 m on the 0.25 m cells of a Blender Ground mesh of 1 m faces)."""


def _float_derivatives(field: HeightField, height: bool = True):
    """``field.derivatives_one(x, y)``: :meth:`HeightField.derivatives` on Python floats (one
    figure, :mod:`.terrain_one_figure`): the same biquintic as a polynomial in the cell,
    ``h = sum_ab A[b][a] u^a v^b`` (:meth:`HeightField._cell`), evaluated by Horner's rule: ~100
    multiply-adds, no numpy (about twice a bicubic's arithmetic, and a fraction of the cost of
    the 4 x 4 stencil sliced out of the grid and weighted on floats: BENCHMARKS.md, "Terrain:
    the height field").  A closure over the grid's constants (an attribute lookup on the field
    costs more than a multiply-add).
    ``height=False``: ``field.slopes_one``, the five derivatives without ``h`` (what the
    stepper needs; 30 multiply-adds fewer)."""
    x_lo, x_hi, y_lo, y_hi = field.extent
    x0, y0, c = field.x0, field.y0, field.cell
    cc = c * c
    i_max, j_max, nx = field.nx - 2, field.ny - 2, field.nx
    coef, cell, derivatives = field._coef.get, field._cell, field.derivatives

    def derivatives_one(x: float, y: float):
        if not (x_lo <= x <= x_hi and y_lo <= y <= y_hi):
            out = derivatives(x, y)                             # raises OffTerrain
            return out if height else out[1:]
        fx = (x - x0) / c
        fy = (y - y0) / c
        i = int(fx)
        if i > i_max:
            i = i_max
        j = int(fy)
        if j > j_max:
            j = j_max
        A = coef(j * nx + i)
        if A is None:
            A = cell(i, j)
        (a00, a01, a02, a03, a04, a05, a10, a11, a12, a13, a14, a15,
         a20, a21, a22, a23, a24, a25, a30, a31, a32, a33, a34, a35,
         a40, a41, a42, a43, a44, a45, a50, a51, a52, a53, a54, a55,
         p00, p01, p02, p03, p04, p10, p11, p12, p13, p14, p20, p21, p22, p23, p24,
         p30, p31, p32, p33, p34, p40, p41, p42, p43, p44, p50, p51, p52, p53, p54,
         q00, q01, q02, q03, q10, q11, q12, q13, q20, q21, q22, q23,
         q30, q31, q32, q33, q40, q41, q42, q43, q50, q51, q52, q53) = A
        u, v = fx - i, fy - j
        # Each power v^b: its polynomial in u (r), d/du (d) and d2/du2 (e).
        r1 = a10 + u * (a11 + u * (a12 + u * (a13 + u * (a14 + u * a15))))
        r2 = a20 + u * (a21 + u * (a22 + u * (a23 + u * (a24 + u * a25))))
        r3 = a30 + u * (a31 + u * (a32 + u * (a33 + u * (a34 + u * a35))))
        r4 = a40 + u * (a41 + u * (a42 + u * (a43 + u * (a44 + u * a45))))
        r5 = a50 + u * (a51 + u * (a52 + u * (a53 + u * (a54 + u * a55))))
        d0 = p00 + u * (p01 + u * (p02 + u * (p03 + u * p04)))
        d1 = p10 + u * (p11 + u * (p12 + u * (p13 + u * p14)))
        d2 = p20 + u * (p21 + u * (p22 + u * (p23 + u * p24)))
        d3 = p30 + u * (p31 + u * (p32 + u * (p33 + u * p34)))
        d4 = p40 + u * (p41 + u * (p42 + u * (p43 + u * p44)))
        d5 = p50 + u * (p51 + u * (p52 + u * (p53 + u * p54)))
        e0 = q00 + u * (q01 + u * (q02 + u * q03))
        e1 = q10 + u * (q11 + u * (q12 + u * q13))
        e2 = q20 + u * (q21 + u * (q22 + u * q23))
        e3 = q30 + u * (q31 + u * (q32 + u * q33))
        e4 = q40 + u * (q41 + u * (q42 + u * q43))
        e5 = q50 + u * (q51 + u * (q52 + u * q53))
        hx = (d0 + v * (d1 + v * (d2 + v * (d3 + v * (d4 + v * d5))))) / c
        hy = (r1 + v * (2.0 * r2 + v * (3.0 * r3 + v * (4.0 * r4 + v * 5.0 * r5)))) / c
        hxx = (e0 + v * (e1 + v * (e2 + v * (e3 + v * (e4 + v * e5))))) / cc
        hxy = (d1 + v * (2.0 * d2 + v * (3.0 * d3 + v * (4.0 * d4 + v * 5.0 * d5)))) / cc
        hyy = (2.0 * r2 + v * (6.0 * r3 + v * (12.0 * r4 + v * 20.0 * r5))) / cc
        if not height:
            return hx, hy, hxx, hxy, hyy
        r0 = a00 + u * (a01 + u * (a02 + u * (a03 + u * (a04 + u * a05))))
        return r0 + v * (r1 + v * (r2 + v * (r3 + v * (r4 + v * r5)))), hx, hy, hxx, hxy, hyy

    return derivatives_one


class LazyHeightField(HeightField):
    """A :class:`HeightField` whose samples are computed when first needed, in tiles of
    :attr:`TILE` x :attr:`TILE` padded samples: the same field, bit for bit, as
    ``HeightField(sample(arange(ny), arange(nx)), x0, y0, cell)``, for the part of the grid a run
    visits.  ``sample(rows, cols)`` returns the heights at ``(x0 + cols[None, :] cell, y0 +
    rows[:, None] cell)`` (data indices in range), elementwise (a point's height must not
    depend on the others asked with it).

    A Ground mesh read in Blender (:func:`..blender.scene.ground.read_ground`) is one: a
    200 m x 200 m mesh at 0.25 m is 641,601 samples, of which a minute's run visits a few
    percent.  Reading
    :attr:`_h` (all of it: the planner's slope bound) computes the rest; a pickled one (the crowd's
    worker processes) travels as the plain :class:`HeightField` of all samples."""

    TILE = 64

    def __init__(self, sample, nx: int, ny: int, x0: float, y0: float, cell: float):
        if min(nx, ny) < 2:
            raise ValueError(f"the grid is {ny} x {nx}; at least 2 x 2 is needed")
        self.cell = check("cell", cell, "cell")
        self.x0 = check("x0", x0, "coordinate")
        self.y0 = check("y0", y0, "coordinate")
        self.ny, self.nx = int(ny), int(nx)
        self._sample = sample
        self._data = np.empty((self.ny + 4, self.nx + 4))
        T = self.TILE
        self._done = np.zeros((-(-(self.ny + 4) // T), -(-(self.nx + 4) // T)), bool)
        self._coef = {}
        self.derivatives_one = _float_derivatives(self)
        self.slopes_one = _float_derivatives(self, height=False)

    @property
    def _h(self):
        """The whole padded grid (every tile computed)."""
        if not self._done.all():
            self._fill(0, self.ny + 4, 0, self.nx + 4)
            self._done[:] = True
        return self._data

    def __reduce__(self):
        return HeightField, (self._h[2:-2, 2:-2].copy(), self.x0, self.y0, self.cell)

    def _store(self, r0, c0):
        T, done = self.TILE, self._done
        r0, c0 = np.ravel(r0), np.ravel(c0)
        W = done.shape[1]
        a0, a1, b0, b1 = r0 // T * W, (r0 + 3) // T * W, c0 // T, (c0 + 3) // T
        k = np.unique(np.concatenate([a0 + b0, a0 + b1, a1 + b0, a1 + b1]))
        k = k[~done.ravel()[k]]
        if not len(k):
            return self._data
        for a, b in zip(*np.divmod(k, W)):
            if not done[a, b]:
                self._fill(a * T, min((a + 1) * T, self.ny + 4),
                           b * T, min((b + 1) * T, self.nx + 4))
                done[a, b] = True
        return self._data

    def _fill(self, r_lo, r_hi, c_lo, c_hi):
        """Padded rows ``r_lo:r_hi``, columns ``c_lo:c_hi``: the samples, and outside the grid
        :class:`HeightField`'s linear extension (rows first, then columns, as it pads)."""
        ra, rb, rk = _extension(np.arange(r_lo, r_hi) - 2, self.ny)
        ca, cb, ck = _extension(np.arange(c_lo, c_hi) - 2, self.nx)
        rows, cols = np.union1d(ra, rb), np.union1d(ca, cb)
        S = np.asarray(self._sample(rows, cols), dtype=float)
        if not np.isfinite(S).all():
            raise ValueError("heights holds a value that is not a finite number")
        pa, pb = np.searchsorted(rows, ra), np.searchsorted(rows, rb)
        R = S[pa] + rk[:, None] * (S[pa] - S[pb])
        qa, qb = np.searchsorted(cols, ca), np.searchsorted(cols, cb)
        self._data[r_lo:r_hi, c_lo:c_hi] = R[:, qa] + ck * (R[:, qa] - R[:, qb])


def _extension(idx, n):
    """Data indices ``idx`` (``-2 .. n + 1``) as ``(a, b, k)``: the padded value is ``h[a] + k
    (h[a] - h[b])``, :class:`HeightField`'s linear extension (``k = 0`` inside)."""
    a = np.clip(idx, 0, n - 1)
    b = np.where(idx < 0, 1, np.where(idx > n - 1, n - 2, a))
    k = np.where(idx < 0, -idx, np.where(idx > n - 1, idx - (n - 1), 0)).astype(float)
    return a, b, k


#: The biquintic's weights of the 4 stencil points ``h[-1], h[0], h[1], h[2]`` of a cell as
#: polynomials: ``w_k(u) = sum_a M[k, a] u^a``.  The quintic Hermite basis on [0, 1] through the
#: value, slope and second derivative at both ends, each taken from the stencil by central
#: differences (``h'(0) = (h[1] - h[-1]) / 2``, ``h''(0) = h[1] - 2 h[0] + h[-1]``, the same at
#: 1): docs/TERRAIN.md Section 1.  The weights sum to 1 (a constant comes back) and reproduce
#: ``u`` and ``u^2`` (central differences are exact for quadratics).
_HERMITE_POWERS = 0.5 * np.array([[0.0, -1.0, 1.0, 3.0, -5.0, 2.0],
                                  [2.0, 0.0, -2.0, -9.0, 15.0, -6.0],
                                  [0.0, 1.0, 1.0, 9.0, -15.0, 6.0],
                                  [0.0, 0.0, 0.0, -3.0, 5.0, -2.0]])
_POW = np.arange(6.0)


def _weights(u):
    """The weights of the 4 stencil points at ``u`` in [0, 1] and their u-derivatives."""
    u = np.asarray(u, dtype=float)[..., None]
    powers = u ** _POW                                     # (..., 6): 1, u, .., u^5
    dpowers = _POW * u ** np.maximum(_POW - 1.0, 0.0)
    ddpowers = _POW * (_POW - 1.0) * u ** np.maximum(_POW - 2.0, 0.0)
    M = _HERMITE_POWERS.T
    return powers @ M, dpowers @ M, ddpowers @ M


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
    """The frame of a foot at ``(x, y)`` heading ``theta_dir`` (horizontal, CCW from +x).
    Python floats in, floats (and 3-tuples) out: one figure is stepped on floats."""
    scalar = type(x) is float and type(y) is float and type(theta_dir) is float
    if scalar:
        one = getattr(ground, "derivatives_one", None)
        h, hx, hy, hxx, hxy, hyy = (one(x, y) if one is not None else
                                    (float(v) for v in ground.derivatives(x, y)))
    else:
        h, hx, hy, hxx, hxy, hyy = ground.derivatives(x, y)
    if scalar:
        c, s, sqrt = math.cos(theta_dir), math.sin(theta_dir), math.sqrt
    else:
        c, s, sqrt = np.cos(theta_dir), np.sin(theta_dir), np.sqrt
    p = hx * c + hy * s                                   # slope along the heading
    inv_t = 1.0 / sqrt(1.0 + p * p)
    inv_n = 1.0 / sqrt(1.0 + hx * hx + hy * hy)
    if scalar:
        tx, ty, tz = c * inv_t, s * inv_t, p * inv_t
        nx, ny, nz = -hx * inv_n, -hy * inv_n, inv_n
    else:
        tx, ty, tz = np.broadcast_arrays(c * inv_t, s * inv_t, p * inv_t)
        nx, ny, nz = np.broadcast_arrays(-hx * inv_n, -hy * inv_n, inv_n)
    bx, by, bz = ny * tz - nz * ty, nz * tx - nx * tz, nx * ty - ny * tx        # n x t
    # Second fundamental form over the first along (c, s): Euler's normal curvature of a graph.
    kappa_n = (hxx * c * c + 2.0 * hxy * c * s + hyy * s * s) * inv_n * inv_t * inv_t
    hor = tx * tx + ty * ty
    # The scalars stay floats for one figure; the vectors are arrays (3, ...) either way.
    return SurfaceFrame(
        z=h, t=np.array([tx, ty, tz]), b=np.array([bx, by, bz]), n=np.array([nx, ny, nz]),
        g_normal=g * nz, g_lateral=-g * bz, g_along=-g * tz, kappa_n=kappa_n,
        turn_gain=(tx * by - ty * bx) / hor, bend_gain=(tx * ny - ty * nx) / hor)

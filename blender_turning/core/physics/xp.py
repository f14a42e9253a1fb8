"""Two array backends for the same formulas: numpy for arrays, ``math`` for Python floats.

The equations in :mod:`dynamics` and the controllers are written once against this small
namespace (``xp.sin``, ``xp.where``, ``xp.clip`` ...), so each accepts a float or an array.  (The
simulation loop of one figure is :mod:`.one_figure`, fused on floats for speed.)  Both backends
evaluate both branches of ``where``, so formulas guard their own denominators instead of relying
on ``inf`` results.
"""
from __future__ import annotations

import math

import numpy as np


class Scalar:
    """Python floats."""

    sin = staticmethod(math.sin)
    cos = staticmethod(math.cos)
    abs = staticmethod(abs)
    hypot = staticmethod(math.hypot)
    atan2 = staticmethod(math.atan2)
    minimum = staticmethod(min)
    maximum = staticmethod(max)
    isfinite = staticmethod(math.isfinite)
    copysign = staticmethod(math.copysign)

    @staticmethod
    def where(cond, a, b):
        return a if cond else b

    @staticmethod
    def clip(v, lo, hi):
        return lo if v < lo else (hi if v > hi else v)

    @staticmethod
    def sign(v):
        return (v > 0) - (v < 0)

    @staticmethod
    def any(v):
        return bool(v)


class Numpy:
    """numpy arrays (any shape); ``clip`` avoids ``np.clip``'s Python-level wrapper."""

    sin = np.sin
    cos = np.cos
    abs = np.abs
    hypot = np.hypot
    atan2 = np.arctan2
    minimum = np.minimum
    maximum = np.maximum
    isfinite = np.isfinite
    copysign = np.copysign
    where = np.where
    sign = np.sign
    any = np.any

    @staticmethod
    def clip(v, lo, hi):
        return np.minimum(np.maximum(v, lo), hi)


def backend(*values):
    """``Scalar`` if every value is a Python or numpy scalar, else ``Numpy``."""
    for v in values:
        if type(v) is not float and v is not None and not isinstance(v, (float, int)):
            return Numpy
    return Scalar

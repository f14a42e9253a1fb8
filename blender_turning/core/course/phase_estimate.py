"""The phase post-pass of Section 6.2 (Fig. 15).

A path-following motion has no ``omega0`` or ``theta_max`` of its own, so they are estimated from
where the state crosses the axes of the phase plane: the crossing of the ``theta_v`` axis
(``omega_v = 0``) gives ``theta_max`` as ``|theta_v|`` there; the crossing of the ``omega_v`` axis
(``theta_v = 0``) gives ``omega0 theta_max`` as ``|omega_v|`` there.  Each quadrant visit is bounded
by one crossing of each kind (where it enters and where it leaves), so each sample gets the two
intercepts of its own quadrant, and ``phi = atan2(theta_v / theta_max, omega_v / (omega0
theta_max))``.  The phase is then exactly 0, 90, 180 or 270 deg on the axes, so it is continuous
from one quadrant to the next.  Samples before the first or after the last crossing of a kind use
the nearest one; a motion that never crosses an axis gets ``|theta_v|``, ``|omega_v|`` extremes.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..controllers.phase import phase

__all__ = ["PhaseEstimate", "estimate_phase", "axis_crossings"]


@dataclass(frozen=True)
class PhaseEstimate:
    """Per-sample estimates, shape ``(n,)`` each: ``phi`` in [0, 2 pi), ``theta_max`` (rad) and
    ``omega0`` (rad/s)."""

    phi: np.ndarray
    theta_max: np.ndarray
    omega0: np.ndarray


def axis_crossings(t, y, other):
    """Times where ``y`` changes sign (linear interpolation between samples) and ``|other|``
    there.  A sample exactly at zero counts once."""
    t, y, other = (np.asarray(a, float) for a in (t, y, other))
    sgn = np.sign(y)
    # Carry the last non-zero sign over exact zeros so a touch at 0 is not two crossings.
    nz = np.flatnonzero(sgn)
    if len(nz) < 2:
        return np.zeros(0), np.zeros(0)
    i = nz[:-1][sgn[nz[:-1]] != sgn[nz[1:]]]
    j = nz[np.searchsorted(nz, i) + 1]
    w = y[i] / (y[i] - y[j])
    tc = t[i] + w * (t[j] - t[i])
    vc = np.abs(other[i] + w * (other[j] - other[i]))
    return tc, vc


def estimate_phase(t, theta_v, omega_v, min_theta: float = 1e-6) -> PhaseEstimate:
    """Section 6.2: ``theta_max``, ``omega0`` and ``phi`` for every sample of a motion."""
    t, th, om = (np.asarray(a, float) for a in (t, theta_v, omega_v))
    # theta_max from omega_v = 0 crossings, omega0 theta_max from theta_v = 0 crossings.
    t_th, v_th = axis_crossings(t, om, th)
    t_om, v_om = axis_crossings(t, th, om)
    tm = _nearest_in_visit(t, t_th, v_th, t_om, max(np.max(np.abs(th)), min_theta))
    wt = _nearest_in_visit(t, t_om, v_om, t_th, max(np.max(np.abs(om)), min_theta))
    tm = np.maximum(tm, min_theta)
    wt = np.maximum(wt, min_theta)
    omega0 = wt / tm
    return PhaseEstimate(phase(th, om, tm, omega0), tm, omega0)


def _nearest_in_visit(t, tc, vc, t_other, fallback):
    """The intercept of axis crossings ``(tc, vc)`` belonging to each sample's quadrant visit.

    A visit runs from one crossing to the next (of either axis); crossings alternate between the
    two axes, so of the two ends of a visit one is of this axis.  Take the crossing of this axis
    that is not separated from ``t`` by a crossing of the other axis.
    """
    n = len(t)
    if len(tc) == 0:
        return np.full(n, float(fallback))
    k = np.searchsorted(tc, t, side="right")
    prev_i = np.maximum(k - 1, 0)
    next_i = np.minimum(k, len(tc) - 1)
    # Is there a crossing of the other axis between the previous crossing of this one and t?
    if len(t_other):
        ko_t = np.searchsorted(t_other, t, side="right")
        ko_prev = np.searchsorted(t_other, tc[prev_i], side="right")
        prev_ok = (k > 0) & (ko_t == ko_prev)
    else:
        prev_ok = k > 0
    has_next = k < len(tc)
    return np.where(prev_ok, vc[prev_i], np.where(has_next, vc[next_i], vc[prev_i]))

"""The terrain flags of ``simulate`` (issue 10): an inclined plane, friction, drag, target speed.

``--slope-deg S --downhill-deg D`` is the plane (``D`` the direction of steepest descent, deg
CCW from +x); ``--friction MU --drag-area CDA --air-density RHO`` what slows the figure;
``--target-speed V`` brakes by turning across the hill (docs/TERRAIN.md Section 6).  With none
of them the run is today's flat one.  On a slope (``S > 0``) a resistance flag that is not given
takes the sport's default (its record's ``resistance``, sources there): a skier on a
slope slides on snow and through air unless told otherwise; on flat ground (``S = 0``) the
defaults are none, so today's runs are unchanged.
"""
from __future__ import annotations

import math
from dataclasses import replace

from ..core.params import check_range
from ..core.terrain import Plane
from ..core.terrain_dynamics import RESISTANCE, Resistance

# flag -> (Resistance field, allowed range)
RESISTANCE_FLAGS = {"friction": ("mu", 0.0, 1.0), "drag_area": ("CdA", 0.0, 10.0),
                    "air_density": ("rho", 0.0, 2.0)}


def add_terrain_flags(p) -> None:
    g = p.add_argument_group("terrain (docs/TERRAIN.md)")
    g.add_argument("--slope-deg", type=float,
                   help="slope of the ground plane, deg (0-60; default 0: flat)")
    g.add_argument("--downhill-deg", type=float,
                   help="direction of steepest descent, deg CCW from +x (default -90)")
    g.add_argument("--friction", type=float,
                   help="snow friction or rolling resistance mu (0-1; default on a slope: the "
                        "sport's)")
    g.add_argument("--drag-area", type=float,
                   help="drag area C_d A, m^2 (0-10; default on a slope: the sport's)")
    g.add_argument("--air-density", type=float,
                   help="air density, kg/m^3 (0-2; default on a slope: the sport's)")
    g.add_argument("--target-speed", type=float,
                   help="m/s: turn across the hill when faster (phase-ellipse controller)")


def terrain_options(args, sport: str) -> dict:
    """``simulate``'s ``ground``, ``resistance`` and ``target_speed`` from the flags (an empty
    dict: today's flat run)."""
    slope = math.radians(check_range("--slope-deg", 0.0 if args.slope_deg is None
                                     else args.slope_deg, 0.0, 60.0))
    down = math.radians(check_range("--downhill-deg", -90.0 if args.downhill_deg is None
                                    else args.downhill_deg, -3600.0, 3600.0))
    given = {field: check_range(f"--{flag.replace('_', '-')}", getattr(args, flag), lo, hi)
             for flag, (field, lo, hi) in RESISTANCE_FLAGS.items()
             if getattr(args, flag) is not None}
    base = RESISTANCE.get(sport, Resistance()) if slope > 0.0 else Resistance(mu=0.0, CdA=0.0)
    out = {}
    if slope > 0.0:
        out["ground"] = Plane(slope, down)
    if slope > 0.0 or given:
        out["resistance"] = replace(base, **given)
    if args.target_speed is not None:
        out["target_speed"] = check_range("--target-speed", args.target_speed, 0.0, 100.0,
                                          lo_open=True)
    return out

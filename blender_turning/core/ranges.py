"""The one table of allowed ranges: every value a user can give (a command-line flag, a scene
file, a schedule, a render-job config, a Blender property) is checked against the range here.

Ranges are in SI units (radians for angles, as Blender's ``subtype='ANGLE'`` properties store
them); :meth:`Range.deg` gives the same range in degrees for the ``*_deg`` fields and flags.
Each range is what the model handles -- no overflow, no NaN, no numpy warning inside it -- and
its ``reason`` says where the bound comes from.  A Blender property reads its limits from here::

    from ..core.ranges import RANGES
    mass: FloatProperty(min=RANGES["m"].lo, max=RANGES["m"].hi, ...)

(``RANGES["theta_max"].lo`` is in radians, as an ``ANGLE`` property wants it.)  Values are checked
with :func:`.validate.check`, which names the field, the value and the range.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

__all__ = ["Range", "RANGES", "CROWD_RANGES", "MAX_STEPS", "MAX_SAMPLES", "lean_range"]


@dataclass(frozen=True)
class Range:
    """An interval of allowed values, in ``unit``."""

    lo: float
    hi: float
    unit: str = ""
    reason: str = ""
    lo_open: bool = False
    hi_open: bool = False
    integer: bool = False
    """Only whole numbers (counts: stages, choices, pixels)."""
    explain: bool = False
    """An error names the reason too (a range that depends on the figure)."""

    def contains(self, v: float) -> bool:
        if not math.isfinite(v) and not (math.isinf(v) and v in (self.lo, self.hi)):
            return False
        ok = (v > self.lo if self.lo_open else v >= self.lo) and \
            (v < self.hi if self.hi_open else v <= self.hi)
        return ok and (not self.integer or v == int(v))

    def deg(self) -> "Range":
        """The same range in degrees (for ``*_deg`` fields and flags)."""
        unit = {"rad": "deg", "rad/s": "deg/s"}.get(self.unit, self.unit)
        return replace(self, lo=_round(math.degrees(self.lo)), hi=_round(math.degrees(self.hi)),
                       unit=unit)

    def __str__(self) -> str:
        text = (f"{'(' if self.lo_open else '['}{self.lo:g}, {self.hi:g}"
                f"{')' if self.hi_open else ']'}")
        text = f"{text} {self.unit}".rstrip()
        return f"{text} (whole numbers)" if self.integer else text


def _round(v: float) -> float:
    return round(v, 9)


_DEG = math.pi / 180.0

RANGES: dict[str, Range] = {
    # -- the body (Section 3, Fig. 2) -----------------------------------------------------------
    "m": Range(1.0, 1000.0, "kg", "a child on a sledge to a loaded motorbike; below 1 kg "
               "I_v / m in Eq. (2) grows without bound (at 1e-300 kg it overflows to NaN)"),
    "l": Range(0.2, 3.0, "m", "a crouched child to a rider on a tall vehicle; the pendulum of "
               "Fig. 2 needs l well above zero (I_v / (m l) in Eq. 2)"),
    "I_v": Range(0.0, 1000.0, "kg m^2", "up to a radius of gyration of 3.6 m at 75 kg; far "
                 "beyond it the body cannot lean within the curvature bounds and the run "
                 "overflows as it falls (1e5 kg m^2: NaN)"),
    "V_cm": Range(0.5, 60.0, "m/s", "walking pace to a speed skier; near 0 m/s Eq. (1) asks for "
                  "a curvature of order g / V^2 (1e-300 m/s: NaN)"),
    "J": Range(0.0, 100.0, "m", "the inertia term (I_v + l^2 m) / (m l) of Eqs. (1), (2), (9), "
               "1.2 m for the presets; near 300 m the half-turns of the heading table overflow",
               lo_open=True),
    "g": Range(1.0, 30.0, "m/s^2", "the Moon (1.6) to beyond Jupiter (24.8)"),
    # -- the limits (Sections 3, 5.1) ------------------------------------------------------------
    "C_f_max": Range(0.001, 10.0, "1/m", "a 1 km turning radius to a 10 cm one (in the core, "
                     "inf means no bound)"),
    "dC_f_max": Range(0.001, 100.0, "1/(m s)", "how fast the foot may change its curvature (in "
                      "the core, inf means no bound)"),
    "theta_fall": Range(5 * _DEG, 85 * _DEG, "rad", "the pendulum of Fig. 2 is lying on the "
                        "ground at 90 deg"),
    # -- the parametric controller (Section 5) ---------------------------------------------------
    "period": Range(0.3, 20.0, "s", "a quick edge change to a long carve; 2 pi / omega0"),
    "omega0": Range(2 * math.pi / 20.0, 2 * math.pi / 0.3, "rad/s", "2 pi / period"),
    "theta_max": Range(1 * _DEG, 85 * _DEG, "rad", "a gentle wiggle to a racer's 70 deg "
                       "(Reid et al. 2020: edge angles 66-71 deg in slalom; a Eurocarver's hip "
                       "on the snow), below the largest fall angle, 85 deg; each figure's own "
                       "range ends below its fall angle (lean_range)", hi_open=True),
    "heading": Range(-3600 * _DEG, 3600 * _DEG, "rad", "ten full turns either way"),
    # -- the start state --------------------------------------------------------------------------
    "theta_v0": Range(-89 * _DEG, 89 * _DEG, "rad", "the body must start above the ground"),
    "omega_v0": Range(-3600 * _DEG, 3600 * _DEG, "rad/s", "ten turns a second of lean rate"),
    "C_f0": Range(-10.0, 10.0, "1/m", "within the largest C_f_max"),
    "schedule_t": Range(0.0, 1e5, "s", "times of a schedule or speed profile, within a run"),
    # -- a run ------------------------------------------------------------------------------------
    "duration": Range(0.0, 1e5, "s", "a day; the number of steps is bounded too (MAX_STEPS)",
                      lo_open=True),
    "dt": Range(1e-3, 0.03, "s", "RK4 step (Section 3) where the rows obey the model to 1e-3 "
                "of scale under the trapezoid rule for a 2 s turn ((2 pi dt / period)^2 / 12 "
                "<= 1e-3 up to 0.034 s; BENCHMARKS.md 'Turn control accuracy'); a step count "
                "bound applies too"),
    "fps": Range(1.0, 1000.0, "1/s", "frame rates from 1 to 1000"),
    # -- path following (Section 6.1) ------------------------------------------------------------
    "n_stages": Range(1, 16, "", "N; the paper uses 10-12 (Section 6.1) and the search grows "
                      "as q^N", integer=True),
    "q": Range(2, 9, "", "q; the paper uses 5-7 (Section 6.1); on scenes/slalom.json N = 12, "
               "q = 9 plans in 23 s while q = 11 runs for minutes", integer=True),
    "q_near": Range(0, 9, "", "q where an obstacle is within reach (0: q); q's bound, the "
                    "search growing as q^N", integer=True),
    "t_stage": Range(0.0, 60.0, "s", "one stage of constant dC_f/dt", lo_open=True),
    "theta_bound": Range(0.0, 90 * _DEG, "rad", "the lean bound of the search", lo_open=True,
                         hi_open=True),
    "sample_dt": Range(0.0, 60.0, "s", "the interval of the path-distance samples",
                       lo_open=True),
    "planner_dt": Range(1e-4, 1.0, "s", "the planner's RK4 step"),
    "batch": Range(1, 4096, "", "nodes expanded together", integer=True),
    "leg_force_max": Range(0.0, 20.0, "body weights", "the largest leg force a plan may need "
                           "(0: no limit; from 1: less than the figure's weight cannot stand)"),
    "search_size": Range(1, 7.0 ** 16, "", "q^N, the leaves of the full search tree: N = 16, "
                         "q = 7 plans scenes/slalom.json in 24 s, N = 12, q = 9 in 23 s, while "
                         "N = 16, q = 9 takes 183 s and 340 MB (BENCHMARKS.md)"),
    "horizon_steps": Range(1, 2000, "", "RK4 steps in one horizon, N t_stage / dt: the paper's "
                           "is 12 x 0.3 s / 0.05 s = 72", integer=True),
    "horizon_samples": Range(1, 1000, "", "path-distance samples in one horizon, N t_stage / "
                             "sample_dt: the paper's is 36", integer=True),
    "plan_duration": Range(0.0, 3600.0, "s", "an hour of planned motion (a replanning every "
                           "stage)", lo_open=True),
    # -- scenes: places and shapes ---------------------------------------------------------------
    "coordinate": Range(-1e5, 1e5, "m", "100 km from the origin, larger than any ski area; "
                        "squared distances overflow near 1e154 m"),
    "distance": Range(0.0, 1e6, "m", "a distance travelled along the path"),
    "radius": Range(0.0, 1e4, "m", "an obstacle's radius", lo_open=True),
    "clearance": Range(0.0, 100.0, "m", "the distance the track keeps from obstacles"),
    "body_clearance": Range(0.0, 100.0, "m", "the distance a crowd's figure keeps from the "
                            "bodies (foot to CM) of figures planned before it"),
    "crowd_priority": Range(-10000, 10000, "", "a figure's place in the planning order of "
                            "Blender's Follow Path on several figures: lower plans first",
                            integer=True),
    "run_out": Range(0.0, 1e4, "m", "the straight added after the path's end"),
    "samples_per_segment": Range(1, 1000, "", "path samples per spline segment", integer=True),
    # -- scenes: terrain (docs/TERRAIN.md) ----------------------------------------------
    "slope": Range(0.0, 60 * _DEG, "rad", "flat to steeper than any skiable or rideable slope "
                   "(an extreme couloir is ~55 deg)"),
    "friction": Range(0.0, 1.0, "", "snow friction or rolling resistance mu (0.005 to 0.1 for "
                      "the sports: each sport record's resistance)"),
    "drag_area": Range(0.0, 10.0, "m^2", "C_d A, 0.3-0.6 m^2 for a rider or skier"),
    "air_density": Range(0.0, 2.0, "kg/m^3", "vacuum to well above sea level's 1.225"),
    "cell": Range(0.0, 1e4, "m", "a height field's grid spacing", lo_open=True),
    "height": Range(-1e4, 1e4, "m", "a terrain height: below the deepest sea floor to above "
                    "the highest summit"),
    "grid_points": Range(2, 4096, "", "heights per side of a height field (4096^2 doubles: "
                         "134 MB)", integer=True),
    # -- the headless render job (scripts/render_job.py) -----------------------------------------
    "job_seconds": Range(0.0, 600.0, "s", "ten minutes of animation a job", lo_open=True),
    "job_fps": Range(1, 240, "1/s", "Blender's frame rates", integer=True),
    "frame_step": Range(1, 1000, "", "render every n-th frame", integer=True),
    "job_crowd_count": Range(1, 200, "", "followers in a job's crowd (each a rig to bake and "
                             "render)", integer=True),
    "pixels": Range(4, 8192, "px", "Blender renders 4 to 8192 pixels a side", integer=True),
    "render_samples": Range(1, 4096, "", "EEVEE/Cycles samples a pixel", integer=True),
    "camera_distance": Range(0.1, 1e4, "m", "how far behind the figures the camera follows"),
    "camera_height": Range(-1e4, 1e4, "m", "the camera's height above the ground"),
    "lens": Range(1.0, 5000.0, "mm", "Blender's focal-length range"),
    "object_size": Range(0.01, 100.0, "m", "an obstacle object's width"),
    "object_height": Range(0.01, 1000.0, "m", "an obstacle object's height"),
    "plan_curvature_rate": Range(0.0, 100.0, "1/(m s)", "the planner's dC_f/dt (0: the sport "
                                 "preset's); as dC_f_max"),
    # -- terrain (docs/TERRAIN.md Section 3; as core.physics.model.Resistance checks them) ----
    "mu": Range(0.0, 1.0, "", "snow or rolling friction coefficient: waxed ski 0.02-0.1, tyre "
                "0.003-0.006; 1 is rubber on dry rock"),
    "CdA": Range(0.0, 10.0, "m^2", "drag area: a tucked skier 0.15, an upright rider 0.6; 10 m^2 "
                 "is a parachute"),
    "rho": Range(0.0, 2.0, "kg/m^3", "air density: 1.225 at sea level, ~1.0 at 2000 m"),
    "terrain_size": Range(10.0, 5000.0, "m",
                          "a generated terrain's side (core.ground.terrain_gen)"),
    "terrain_cell": Range(0.05, 50.0, "m", "a generated terrain's grid spacing"),
    "terrain_slope": Range(0.0, 45.0, "deg", "a generated ski slope's mean slope; 45 deg is a "
                           "black run's steepest"),
    "terrain_seed": Range(0, 2**31 - 1, "", "the generator's random seed", integer=True),
    "hill_height": Range(-100.0, 100.0, "m", "a generated hill's height (negative: a dip)"),
    "road_width": Range(0.0, 50.0, "m", "a road's width (0: no road)"),
    "target_speed": Range(0.0, 100.0, "m/s", "the speed a figure brakes to by turning across "
                          "the hill (0: none)"),
    # The braking rule's own settings (core/braking.TargetSpeed; Python callers only).
    "brake_speed": Range(0.0, 100.0, "m/s", "the speed a figure brakes to", lo_open=True),
    "brake_tau": Range(0.0, 1e3, "s", "the time a speed error decays in", lo_open=True),
    "brake_reset_time": Range(0.0, math.inf, "s", "the rule's integral time (inf: none)",
                              lo_open=True),
    "brake_max_angle": Range(0.0, math.pi, "rad", "the largest angle from the fall line",
                             lo_open=True),
    "brake_corridor": Range(0.0, 1e5, "m", "the half-width of the zig-zag's corridor",
                            lo_open=True),
    "brake_turn_share": Range(0.0, 1.0, "", "the share of the fastest mean-heading rate used",
                              lo_open=True),
    "brake_reach": Range(0.0, math.pi, "rad", "how far the command may lead the mean heading",
                         lo_open=True),
    "brake_slope_time": Range(0.0, 1e3, "s", "the low-pass time of the slope read"),
    # -- grip and skidding (docs/skidding.md; core/physics/grip.py, core/physics/skidding.py) ------
    "grip": Range(0.01, 2.75, "", "the friction circle's mu at the foot: tyre on dry asphalt "
                  "0.9, wet 0.5, gravel 0.35; hard snow 1, a race piste 2.75 (Brown 1989: snow "
                  "holds a force up to 40-70 deg from its normal)"),
    "grip_shear_angle": Range(0.0, math.radians(60.0), "rad", "how far from the ski base's "
                              "normal the snow holds the ski's force"),
    "stop_at": Range(0.0, 1e6, "s", "when a commanded stop begins"),
}

# The formations of a crowd (blender_turning/crowd: the scene files, the formations, Add Crowd).
CROWD_RANGES = {
    "seed": Range(0, 2**63 - 1, "", "any whole number", integer=True),
    "count": Range(1, 10000, "", "figures a formation adds", integer=True),
    "time_offset": Range(0.0, 1e5, "s", "when a figure starts on the crowd's clock"),
    "gap_s": Range(0.0, 1e4, "s", "time between successive figures", lo_open=True),
    "gap_m": Range(0.0, 1e4, "m", "distance between successive figures or rows",
                   lo_open=True),
    "sync_gap_s": Range(0.0, 1e4, "s", "time between successive figures"),
    "lateral_m": Range(-1e3, 1e3, "m", "sideways offset, to the left of the heading"),
    "spacing_m": Range(0.0, 1e3, "m", "distance between figures side by side"),
    "abreast": Range(1, 100, "", "riders in a row", integer=True),
    "jitter": Range(0.0, 0.3, "", "relative random difference, up to 30 %"),
    "timing_jitter_s": Range(0.0, 1e3, "s", "random difference of the start time (at most "
                             "half the gap)"),
}

def lean_range(theta_fall: float, who: str = "the figure") -> Range:
    """The lean ``theta_max`` (rad) that ``who`` may be asked for: from ``RANGES["theta_max"]``'s
    bottom up to, not including, its fall angle ``theta_fall`` (Section 3: the pendulum of
    Fig. 2 has fallen there).  Every lean input is checked against it once the figure is known
    (``--lean-deg`` and a schedule's, a crowd's and a render job's ``lean_deg``, Blender's Lean);
    the turn followed then stays 8 deg below the fall angle, and within the other bounds, and
    the run says so (:class:`.controllers.feasible.FeasibleTurn`)."""
    deg = _round(math.degrees(theta_fall))
    return replace(RANGES["theta_max"], hi=theta_fall, hi_open=True, explain=True,
                   reason=f"{who}'s fall angle theta_fall is {deg:g} deg: leaning that far, "
                          "the body lies on the ground")


MAX_STEPS = 200_000
"""Most integration steps (``duration / dt``) or output samples of one run: 4000 s of motion at
the default dt of 0.02 s.  Measured (BENCHMARKS.md): 200,000 steps take 4.7 s and 160 MB, 9.4 s
with the 44 MB CSV written; ``--duration 100000 --dt 0.0001`` would be 1e9 steps, hours and
hundreds of GB."""
MAX_SAMPLES = MAX_STEPS

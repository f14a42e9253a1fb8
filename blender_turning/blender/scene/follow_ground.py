"""Follow Path on a Ground mesh: what ``turning.follow_path`` adds when the figure has a
Ground mesh (``turning.ground``).

- The mesh is read once into the core's height field (:func:`.ground.read_ground`) and checked to
  be one: no face may lie under another (an overhang, a fold, a closed solid's underside), since
  the field, like a figure on it, sees only the top of the mesh.
- The path curve is projected onto the ground vertically: its ``x, y`` are kept, its ``z`` is
  dropped (a curve drawn above or below the mesh, or flat at ``z = 0``, is the same path).  The
  planner works in the horizontal plane as on flat ground (docs/TERRAIN.md Section 7: ``d_i``,
  the obstacles and the distance travelled are horizontal), so this is the projection the
  planner itself uses.  Every point of the curve must lie over the mesh; one that does not is
  refused, naming where.
- Obstacles stay the xy footprints of their objects (``scene_adapters.obstacle_footprints``);
  the Ground mesh itself is never one (it is the figure's own, ``follow_scene.own_objects``).
- The planner runs :class:`..core.planner.Problem` on the ground
  (:mod:`..core.planner.terrain_problem`): the speed is a state, starting at the Speed setting at
  the scene's first frame, with the figure's Slope
  Friction, Drag Area and Air Density (``turning.terrain``).  *Target Speed* is not used: it
  steers Bake Turns' turns across the hill, while on a path the drawn line sets where the figure
  goes, and so its speed.
- The result is baked as a terrain Bake Turns is (``pipeline``): the foot's height on every
  frame is a ray cast onto the mesh, the figure stands in the local surface, and the foot track
  is drawn on the surface.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from ...core.errors import PlanInfeasible
from ...core.physics.grip import SNOW
from ...core.planner.speed_cap import SpeedCap
from ...core.sports import sport as sport_record
from .ground import MeshGround, _world_triangles, read_ground
from .scene_adapters import FrameRange, SceneInputError, resistance_from_settings, sampled_setting

#: Path samples per curve segment checked to lie over the mesh.
SAMPLES_PER_SEGMENT = 64

#: A face whose centre lies more than this below the smooth height field is looked at again by a
#: ray cast (m).  The field (a spline through the mesh's top at a quarter of its edge length)
#: stays within 1.5 cm of the mesh (tests/test_blender_ground.py); folds thinner than this are
#: not seen, and do not matter to the figure either.
SCREEN_DEPTH = 0.05

#: A face whose centre lies more than this below the mesh's top there (a ray cast) is hidden (m):
#: far above float32 round-off of the vertices (~1e-5 m at 100 m).
HIDDEN_DEPTH = 0.01


def read_follow_ground(fig, depsgraph) -> MeshGround | None:
    """The figure's Ground mesh read and checked to be a height field, or ``None`` (flat).
    Raises :class:`SceneInputError` naming the object and the problem."""
    obj = fig.turning.ground
    if obj is None:
        return None
    try:
        ground = read_ground(obj, depsgraph)
    except ValueError as exc:
        raise SceneInputError(str(exc)) from None
    check_height_field(obj, depsgraph, ground)
    return ground


def check_height_field(obj, depsgraph, ground: MeshGround) -> None:
    """Raise :class:`SceneInputError` if a face of ``obj`` lies under another one: the figure
    would ride the top and the planner would not see the rest.  Each face's centre is compared
    with the smooth field (all at once), and those more than :data:`SCREEN_DEPTH` below it with
    a ray cast from above onto the mesh (exact)."""
    world, tris = _world_triangles(obj, depsgraph)
    P = world[tris]
    area = np.linalg.norm(np.cross(P[:, 1] - P[:, 0], P[:, 2] - P[:, 0]), axis=1)
    c = P[area > 1e-12].mean(axis=1)                       # centres of faces with an area
    x_lo, x_hi, y_lo, y_hi = ground.field.extent
    cx, cy = np.clip(c[:, 0], x_lo, x_hi), np.clip(c[:, 1], y_lo, y_hi)
    below = ground.field.derivatives(cx, cy)[0] - c[:, 2]
    suspects = np.flatnonzero(below > SCREEN_DEPTH)
    tops = ground.top(c[suspects, 0], c[suspects, 1])
    for k, top in zip(suspects, tops):
        x, y, z = (float(v) for v in c[k])
        if top - z > HIDDEN_DEPTH:              # NaN (no hit) is not
            raise SceneInputError(
                f"ground {obj.name!r} is not a height field: at ({x:.2f}, {y:.2f}) m a face lies "
                f"{top - z:.2f} m under another (an overhang, a fold, or the underside of a "
                "closed solid); the figure rides the top of the mesh: pick a mesh with one "
                "surface over every point (e.g. delete the solid's bottom and sides)")


def over_mesh(ground: MeshGround, xy) -> np.ndarray:
    """Whether a ray cast straight down at each point of ``xy`` ((n, 2)) hits the mesh."""
    xy = np.asarray(xy, float)
    return ~np.isnan(ground.top(xy[:, 0], xy[:, 1]))


def check_path_on_ground(path_obj, path, ground: MeshGround | None) -> None:
    """Raise :class:`SceneInputError` if the path (a :class:`..core.course.path.HermitePath`, the
    curve's ground projection) leaves the Ground mesh, naming where and how far along (``ground
    = None``, flat: it cannot)."""
    if ground is None:
        return
    xy = path.sample(SAMPLES_PER_SEGMENT)
    off = np.flatnonzero(~over_mesh(ground, xy))
    if off.size == 0:
        return
    k = int(off[0])
    along = float(np.sum(np.linalg.norm(np.diff(xy[:k + 1], axis=0), axis=1)))
    x_lo, x_hi, y_lo, y_hi = ground.field.extent
    raise SceneInputError(
        f"path {path_obj.name!r} leaves ground {ground.name!r} at ({xy[k, 0]:.2f}, "
        f"{xy[k, 1]:.2f}) m, {along:.1f} m along it (seen from above, the mesh spans x "
        f"{x_lo:.1f}..{x_hi:.1f} m, y {y_lo:.1f}..{y_hi:.1f} m): draw the path over the ground, "
        "or extend the ground under it")


def plan_inputs(context, fig, figure, depsgraph) -> tuple:
    """``(figure, ground, terrain)`` for planning: on flat ground ``(figure, None, {})``; on the
    figure's Ground mesh the mesh read and checked (:func:`read_follow_ground`), the figure
    starting at the Speed setting at the scene's first frame (the speed is a state from there),
    and ``terrain`` the :class:`.follow_job.FollowJob` keywords: the mesh's height field, the
    Slope Friction, Drag Area and Air Density of ``turning.terrain`` and, with a Target Speed at
    the first frame, the speed cap the planned figure brakes to (within the grip of
    ``turning.skid``)."""
    ground = read_follow_ground(fig, depsgraph)
    if ground is None:
        return figure, None, {}
    scene = context.scene
    first = FrameRange(scene.frame_start, scene.frame_start + 1,
                       scene.render.fps / scene.render.fps_base)
    V0 = float(sampled_setting(fig, "speed", first)[0])
    figure = replace(figure, body=replace(figure.body, V_cm=V0))
    terrain = {"ground": ground.field, "resistance": resistance_from_settings(fig.turning)}
    target = float(sampled_setting(fig, "terrain.target_speed", first)[0])
    if target > 0.0:                      # the planner brakes (docs/skidding.md Section 6)
        k = fig.turning.skid
        record = sport_record(fig.turning.sport)
        grip = record.grip if record.grip is not None else SNOW[k.snow.lower()]
        if k.grip > 0.0:
            grip = replace(grip, mu=float(k.grip))
        terrain["speed_cap"] = SpeedCap(target, grip)
    return figure, ground, terrain


def edge_note(exc, ground: MeshGround | None, reach: float) -> str:
    """For a plan that failed within one horizon's reach of the ground's edge: `` (ground
    'Slope' ends 12.0 m from there; ...)``; otherwise ``''``.  Branches that leave the ground
    are clipped (``core/planner/terrain_problem.py``), so near its edge every branch may be."""
    if ground is None or not isinstance(exc, PlanInfeasible):
        return ""
    x, y = exc.position
    x_lo, x_hi, y_lo, y_hi = ground.field.extent
    gap = min(x - x_lo, x_hi - x, y - y_lo, y_hi - y)
    if gap > reach:
        return ""
    return (f" (ground {ground.name!r} ends {max(gap, 0.0):.1f} m from there; the planner looks "
            f"one horizon, up to {reach:.0f} m, ahead, and a run that leaves the ground is "
            "clipped: extend the ground past the path's end)")


def target_speed_note(fig) -> str:
    """A note for the report of a finished plan when a Target Speed is set on a Ground mesh."""
    s = fig.turning
    if s.ground is None or not s.terrain.target_speed > 0:
        return ""
    return (f" (braking to at most {s.terrain.target_speed:g} m/s at the first frame's Target "
            "Speed, within the grip, docs/skidding.md)")

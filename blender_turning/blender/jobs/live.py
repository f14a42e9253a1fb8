"""Live Preview: a figure whose ``turning.live`` is on is re-baked whenever what its bake reads
changes (docs/live-preview.md).

What a bake reads is summed up in a digest (:func:`fingerprint`): every ``turning`` setting of
the figure (a keyed one by its F-curve's keys, not its value at the current frame), the scene's
frame range and frame rate, and the objects it points at (the Path curve's points, the obstacles'
placement and size, the Ground mesh's placement, vertex count and edits seen by the depsgraph).
The digest of the inputs of the figure's current bake is stored on its action (:data:`KEY`), so
undo, redo and saving keep it with the keys it describes.  A figure is *pending* when Live
Preview is on and its digest differs from the stored one (and from the one that last failed).

:func:`refresh` re-bakes every pending figure: computed first, written only when that succeeded,
into the existing F-curves in place where the channels and frames are the same
(:func:`.bake.rewrite_pose_track`).  A user rig's equipment loses its export keys
(:mod:`..anim.export_ready`; its constraints and drivers move it as before, and the keys would
end where the old bake did); Bake Turns keys it again.  A failure (a fall, a setting out of
range) leaves the last good bake, and is shown in the panel, beside the figure in the viewport
and, for a fall, as a timeline marker at the frame where the figure falls.

In the interface, a change reaches :func:`refresh` through the message bus (any figure setting:
a slider drag publishes every step) or the depsgraph (keys, the Path curve, obstacles, the Ground
mesh), both before the next redraw.  A drag step re-bakes the keys within :data:`WINDOW` frames
of the current frame (what is on screen); once the settings have stood still for :data:`SETTLE`
s the timer re-bakes the whole range and writes the foot track.  Nothing here pushes an undo
step: the step is the one Blender pushes when the drag ends (its undo gives back the bake stored
with the previous step; a redo re-bakes).  Figures with a Path are planned by Follow Path, which
takes seconds: they re-bake once the edit has settled.
"""
from __future__ import annotations

import hashlib
import time
from dataclasses import replace

import bpy
import numpy as np
from bpy.app.handlers import persistent

from ...core import DEFAULT_DT
from ...core.controllers.feasible import nearby_tables
from ...core.errors import FellOver, TurningError
from ...core.physics.terrain_sim import preview_stride
from ...mapping import MAPPINGS
from ...mapping.retarget.retarget import path_length
from ...mapping.sports.snow import tilt_gain
from .. import compat
from ..anim import bake, export_ready, foot_track
from ..props import figure as props
from ..scene import retarget_adapter
from ..scene.figure_context import check_figure, in_settings
from .pipeline import figure_pose_track, ground_of
from ..props.figure import figure_settings
from ..props.crowd import TurningCrowdSettings
from ..props.rig import TurningRigSettings
from ..scene.scene_adapters import (FrameRange, bezier_control_points, sampled_setting,
                                    start_from_object)

#: ID property on the figure's action: the digest of the inputs its baked keys were made from.
KEY = "turning_live_key"
#: Seconds the settings stand still before a drag counts as ended (the whole range, the foot
#: track, Follow Path).
SETTLE = 0.3
#: A drag step re-bakes the frames within WINDOW of the current one (the frame on screen and
#: its neighbours); the simulation runs from the first frame to MARGIN frames past them, and
#: MARGIN frames on either side are mapped too (a pole plant, a quaternion's sign depend on the
#: frames around: from 12 frames of context on, a window's rotations agree with the whole
#: range's to 5e-6 given the same edge tilt, measured on the four sports; the tilt is fitted
#: over the part simulated).  The mapping's cost goes with the frames mapped: 29 here; a user's
#: rig is retargeted on the window's 5 (each frame's own).
WINDOW, MARGIN = 2, 12
#: A drag step on the paper's own model (flat ground, a Speed that is not keyed, no skidding:
#: :func:`.pipeline.simulate_figure`'s ``coarse_dt``) integrates with PREVIEW_STEPS steps a turn
#: period (its shortest over the range), from DEFAULT_DT up to 2 DEFAULT_DT (0.04 s for the
#: default 2 s turns; half the steps): 30 s into a run the foot is within 2 mm and the heading
#: and lean within 0.02 deg of the exact run's (measured over leans of 15-45 deg, speeds of
#: 8-20 m/s, turns of 1.5-3 s, docs/live-preview.md).  The release integrates with DEFAULT_DT.
PREVIEW_STEPS = 50
#: A drag step on a Ground mesh (no Target Speed, no skidding) steps up to PREVIEW_STRIDE
#: DEFAULT_DT at a time where nothing discrete happens, and DEFAULT_DT on the bake's own grid about
#: the lean's zero crossings and a new feasibility table that changes the turn's lean, and where a
#: coarse step would cross more than 1.25 cells of the height field
#: (:func:`...core.physics.terrain_sim.simulate_free`'s ``stride``), keeping PREVIEW_TURN_STEPS
#: steps a turn period (its shortest over the range; the core's ``preview_stride``): 5 DEFAULT_DT
#: for 3 s turns, 3 for 2 s turns (docs/live-preview.md).  The release integrates with
#: DEFAULT_DT.
PREVIEW_STRIDE, PREVIEW_TURN_STEPS = 6, 30
#: A drag step's controller may take the feasible turns of a body within this (relative) of the
#: figure's in what they read of it (its COM height, ``J``, speed and gravity:
#: :func:`..core.controllers.feasible.nearby_tables`); the release bakes its own.
NEARBY_BODY = 0.02
#: Settings that do not change the motion.
_IGNORED = {"rna_type", "name", "live", "show_foot_track", "foot_track", "saved_state",
            "custom_index"}

#: figure name -> :class:`Failure` of the last re-bake of its current inputs.
FAILURES: dict = {}
#: object name -> how many geometry or transform updates the depsgraph reported for it.
_EDITS: dict = {}
_MSGBUS_OWNER = object()
_state = {"last_change": 0.0, "tracks_due": {}}
#: figure name -> the digest of the settings its window was last re-baked for (the rest waits).
_WINDOWS: dict = {}
#: figure name -> (what :func:`_drag_rig` keys it by, its rig's read): a drag's steps read a user's
#: rig once; the next whole re-bake (the release) reads it anew.
_RIGS: dict = {}
#: Ground mesh name -> (what the digest reads of it, its read): a drag step reads the mesh only
#: when the digest sees it changed (a read takes ~15 ms on a 200 x 200 grid, most of it in
#: evaluating the mesh to tell whether it changed); the release reads it anew.
_GROUNDS: dict = {}


class Failure:
    """Why the re-bake of a figure's current settings failed: the digest, the message, the
    frame where the figure falls (``None`` for another failure) and its timeline marker's name."""

    def __init__(self, key: str, message: str, frame: int | None, figure: str):
        self.key, self.message, self.frame = key, message, frame
        self.marker = f"{figure} falls" if frame is not None else ""


def live_changed(fig) -> None:
    """``turning.live`` was switched: on, re-bake the figure (on the timer); off, forget its
    failure."""
    if fig.turning.live:
        schedule(now=False)
    else:
        clear_failure(fig)


def live_figures(scene=None) -> list:
    scene = scene or bpy.context.scene
    return [o for o in scene.objects if figure_settings(o) is not None and o.turning.live]


# -- the digest ----------------------------------------------------------------------------

def _keyed(obj) -> dict:
    bag = compat.channels(obj)
    if bag is None:                      # the bake pushed down onto an NLA strip keeps the keys
        action, strip = bake.find_bake(obj)
        bag = compat.channelbag(action, compat.strip_slot(strip)) if strip is not None else None
    if bag is None:
        return {}
    return {fc.data_path: fc for fc in bag.fcurves if fc.data_path.startswith(bake.PARAM_PREFIX)}


def _curve_bytes(fc) -> bytes:
    n = len(fc.keyframe_points)
    out = np.empty(6 * n, np.float32)
    for i, attr in enumerate(("co", "handle_left", "handle_right")):
        part = np.empty(2 * n, np.float32)
        fc.keyframe_points.foreach_get(attr, part)
        out[2 * i * n:2 * (i + 1) * n] = part
    ipo = np.empty(n, np.int32)
    fc.keyframe_points.foreach_get("interpolation", ipo)
    return out.tobytes() + ipo.tobytes() + bytes([fc.mute])


def _object_bytes(obj, role: str) -> bytes:
    """What a bake reads of an object the figure points at."""
    parts = [obj.name.encode(), np.array(obj.matrix_world, np.float32).tobytes(),
             repr(_EDITS.get(obj.name, 0)).encode()]
    if role == "path":
        try:
            parts.append(bezier_control_points(obj).tobytes())
        except ValueError as exc:          # the re-bake reports it
            parts.append(str(exc).encode())
    elif obj.type == "MESH":
        parts.append(repr((len(obj.data.vertices), tuple(obj.dimensions))).encode())
    return b"|".join(parts)


def _group_digest(h, group, prefix: str, keyed: dict, objects: list) -> None:
    for prop in group.bl_rna.properties:
        name = prop.identifier
        if name in _IGNORED:
            continue
        value = getattr(group, name)
        if prop.type == "POINTER":
            if isinstance(value, bpy.types.PropertyGroup):
                _group_digest(h, value, f"{prefix}{name}.", keyed, objects)
                continue
            h.update(f"{prefix}{name}={getattr(value, 'name', None)!r};".encode())
            if value is not None:
                objects.append((name, value))
        elif prop.type == "COLLECTION":
            for i, item in enumerate(value):
                _group_digest(h, item, f"{prefix}{name}[{i}].", keyed, objects)
        else:
            fc = keyed.get(f"{bake.PARAM_PREFIX}{prefix}{name}")
            if fc is not None:           # keyed: the curve is what the bake reads
                h.update(f"{prefix}{name}~".encode() + _curve_bytes(fc))
            else:
                v = tuple(value) if getattr(prop, "is_array", False) else value
                h.update(f"{prefix}{name}={v!r};".encode())


def fingerprint(fig) -> str:
    """The digest of everything ``fig``'s bake reads (see the module doc)."""
    scene = bpy.context.scene
    h = hashlib.blake2b(digest_size=16)
    h.update(repr((scene.frame_start, scene.frame_end, scene.render.fps,
                   scene.render.fps_base)).encode())
    objects = []
    _group_digest(h, fig.turning, "", _keyed(fig), objects)
    own = {fig, *fig.children_recursive, fig.turning.foot_track}   # never its own obstacles
    for role, obj in objects:
        if isinstance(obj, bpy.types.Collection):
            for o in sorted(obj.all_objects, key=lambda o: o.name):
                # Figures (and their bodies) move with their bakes: two live figures among
                # each other's obstacles would re-bake each other without end.
                if o not in own and figure_settings(o.parent or o) is None:
                    h.update(_object_bytes(o, role))
        elif isinstance(obj, bpy.types.Object):
            h.update(_object_bytes(obj, role))
    if bake.figure_action(fig) is None:  # the first bake starts where the figure stands
        h.update(repr(tuple(fig.location) + tuple(fig.rotation_euler)).encode())
    return h.hexdigest()


def baked_key(fig):
    action = bake.figure_action(fig)
    return None if action is None else action.get(KEY)


def is_pending(fig) -> bool:
    """Does the live figure ``fig`` wait for a re-bake?"""
    if figure_settings(fig) is None or not fig.turning.live:
        return False
    key = fingerprint(fig)
    failed = FAILURES.get(fig.name)
    return key != baked_key(fig) and (failed is None or failed.key != key)


def pending_figures(scene=None) -> list:
    return [f for f in live_figures(scene) if is_pending(f)]


# -- re-baking -----------------------------------------------------------------------------

def _set_failure(fig, key: str, exc, frames: FrameRange) -> Failure:
    clear_failure(fig)
    frame = None
    if isinstance(exc, FellOver):
        frame = frames.start + int(round(exc.t * frames.fps))
        frame += int(round(float(fig.turning.crowd.time_offset) * frames.fps))
    failure = FAILURES[fig.name] = Failure(key, in_settings(str(exc)), frame, fig.name)
    if frame is not None:
        bpy.context.scene.timeline_markers.new(failure.marker, frame=frame)
    return failure


def clear_failure(fig) -> None:
    """Forget ``fig``'s failed re-bake and remove its fall marker."""
    failure = FAILURES.pop(fig.name, None)
    if failure is not None and failure.marker:
        markers = bpy.context.scene.timeline_markers
        for m in [m for m in markers if m.name == failure.marker]:
            markers.remove(m)


def _rebake_turns(fig, frames, grounds, with_track: bool) -> None:
    """Bake Turns for one figure: compute (raises, nothing written), then write in place."""
    check_figure(fig)
    start = start_from_object(fig) if bake.figure_action(fig) is None else None
    height = None if start is None else float(fig.location[2])
    mesh = fig.turning.ground
    if mesh is not None and mesh.name not in grounds:
        grounds[mesh.name] = ground_of(fig)
    traj, track = figure_pose_track(fig, frames, start=start, height=height,
                                    ground=None if mesh is None else grounds[mesh.name])
    track = export_ready.with_take(fig, track)      # the channels Bake Turns writes
    bake.check_track(fig, track)
    if start is not None:                 # as Bake Turns: the height where the user put it stays
        fig.turning.start = (start[0], start[1], float(fig.location[2]))
        fig.turning.start_heading = start[2]
    export_ready.clear_equipment(fig)
    if bake.rewrite_pose_track(fig, track) is None:
        bake.bake_pose_track(fig, track)
    if with_track or fig.turning.foot_track is None:
        foot_track.write_foot_track(fig, traj.x, traj.y, z=traj.z)
    else:
        _state["tracks_due"][fig.name] = (traj.x, traj.y, traj.z)


def _rebake_window(fig, frames: FrameRange) -> bool:
    """A drag step: the keys within :data:`WINDOW` frames of the current frame, in place
    (raises as :func:`_rebake_turns`, nothing written).  ``False`` when a window is no cheaper
    or cannot be written in place (not baked yet, a start offset): then the whole range."""
    from .pipeline import map_track, simulate_figure, surface_normals
    s = fig.turning
    if bake.figure_action(fig) is None or float(s.crowd.time_offset) != 0.0:
        return False
    cur = min(max(bpy.context.scene.frame_current, frames.start), frames.end)
    lo, hi = max(frames.start, cur - WINDOW), min(frames.end, cur + WINDOW)
    mlo, mhi = max(frames.start, lo - MARGIN), min(frames.end, hi + MARGIN)
    if mlo == frames.start and mhi == frames.end:
        return False
    fitted = _drag_rig(fig)
    ground = _window_ground(fig)
    period = float(sampled_setting(fig, "period", frames).min())
    coarse = min(2 * DEFAULT_DT, max(DEFAULT_DT, period / PREVIEW_STEPS))
    options = MAPPINGS[s.sport.lower()].Options()
    fit = hasattr(options, "tilt_gain") and options.tilt_gain is None
    # Sampled from the first frame where the edge tilt is fitted over the run so far or a user's
    # rig's wheels turn by the foot point's chords from it, else at the mapped frames only.
    skip = 0 if fit or fitted is not None else mlo - frames.start
    with nearby_tables(NEARBY_BODY):      # a Body slider's step: no new feasibility table
        traj = simulate_figure(fig, FrameRange(frames.start, mhi, frames.fps), ground=ground,
                               coarse_dt=coarse, skip=skip, stride=preview_stride(
                                   period, DEFAULT_DT, PREVIEW_STRIDE, PREVIEW_TURN_STEPS))
    # What the mapping reads of the whole run, from the part simulated: the edge tilt's fit
    # (Section 7), the distance the wheels turn from (the built-in's from the arc length at the
    # run's first frame, t = 0; a user's rig's from the foot point's chords of one frame).
    k = mlo - frames.start - skip
    meta = {**traj.meta, "s_start": 0.0}
    if skip == 0:
        meta["path_start"] = float(path_length(np.stack([traj.x[:k + 1], traj.y[:k + 1]], 1))[-1])
    part = type(traj)(traj.data[:, k:], meta)
    if fit:
        options = replace(options, tilt_gain=tilt_gain(traj, None))
    # The mapping over the window and its context, the retarget over the window only.
    track = map_track(s.sport, part, FrameRange(mlo, mhi, frames.fps), options, fig,
                      surface_normals(part, ground), rows=(lo - mlo, hi - mlo + 1),
                      fitted=fitted)
    track = export_ready.with_take(fig, track)
    if bake.rewrite_pose_track(fig, track) is None:       # checks the track first
        return False
    export_ready.clear_equipment(fig)
    return True


def _drag_rig(fig):
    """A drag step's check of ``fig``'s rig (:func:`..scene.figure_context.check_figure`) and its
    read of a user's rig (:func:`..scene.retarget_adapter.fitted_rig`, ``None`` for a built-in
    figure; ~2 ms of a step on a Rigify rig): once a drag (:data:`_RIGS`), again when its Sport
    or Your Rig settings, its scale or its armature change."""
    h = hashlib.blake2b(digest_size=16)
    _group_digest(h, fig.turning.rig, "rig.", {}, [])
    key = (h.digest(), fig.turning.sport, tuple(fig.scale), fig.data.as_pointer())
    kept = _RIGS.get(fig.name)
    if kept is None or kept[0] != key:
        check_figure(fig)
        kept = _RIGS[fig.name] = (key, retarget_adapter.fitted_rig(fig))
    return kept[1]


def _window_ground(fig):
    """A drag step's read of ``fig``'s Ground mesh (:data:`_GROUNDS`), ``None`` when flat."""
    mesh = fig.turning.ground
    if mesh is None:
        return None
    seen = _object_bytes(mesh, "ground")
    kept = _GROUNDS.get(mesh.name)
    if kept is None or kept[0] != seen:
        kept = _GROUNDS[mesh.name] = (seen, ground_of(fig))
    return kept[1]


def _rebake_path(fig) -> None:
    """Follow Path for one figure, planned here and now (seconds)."""
    from ..scene import follow_scene     # Follow Path's reader and writer
    job = follow_scene.prepare(bpy.context, fig)
    follow_scene.finish(bpy.context, fig, job, job.run())


def refresh(scene=None, with_tracks: bool = True, paths: bool = True,
            window: bool = False) -> dict:
    """Re-bake every pending live figure of ``scene``; ``{name: None or Failure}``.
    ``with_tracks=False`` (a drag step) leaves the foot tracks for :func:`settle`;
    ``paths=False`` leaves figures with a Path (Follow Path) pending; ``window`` re-bakes only
    the frames around the current one where that is cheaper (the figure stays pending: the
    whole range is the next full refresh's)."""
    scene = scene or bpy.context.scene
    frames = FrameRange.of_scene(scene)
    grounds, out = {}, {}
    for fig in live_figures(scene):
        key = fingerprint(fig)
        if key == baked_key(fig):        # back to the settings of the bake shown
            clear_failure(fig)
            continue
        failed = FAILURES.get(fig.name)
        if (failed is not None and failed.key == key) or (fig.turning.path is not None
                                                          and not paths):
            continue
        if window and _WINDOWS.get(fig.name) == key:
            continue
        try:
            if fig.turning.path is not None:
                _rebake_path(fig)
            elif window and _rebake_window(fig, frames):
                clear_failure(fig)           # a step that failed before: the drag went on
                _WINDOWS[fig.name] = key
                out[fig.name] = None
                continue
            else:
                _rebake_turns(fig, frames, grounds, with_tracks)
        except (ValueError, TurningError) as exc:
            out[fig.name] = _set_failure(fig, key, exc, frames)
            continue
        clear_failure(fig)
        _WINDOWS.pop(fig.name, None)
        _RIGS.pop(fig.name, None)
        bake.figure_action(fig)[KEY] = fingerprint(fig)
        out[fig.name] = None
    if with_tracks:
        settle()
    return out


def settle() -> None:
    """Write the foot tracks that drag steps left out."""
    due, _state["tracks_due"] = _state["tracks_due"], {}
    for name, (x, y, z) in due.items():
        fig = bpy.data.objects.get(name)
        if fig is not None and figure_settings(fig) is not None:
            foot_track.write_foot_track(fig, x, y, z=z)


# -- the interface: message bus, depsgraph, timer --------------------------------------------

def _tick():
    """The timer: pending drag steps; once the settings stood still for :data:`SETTLE` s, the
    foot tracks and the Follow Path figures (the same :func:`refresh` as
    ``turning.refresh_preview``)."""
    refresh(with_tracks=False, paths=False, window=True)
    wait = _state["last_change"] + SETTLE - time.monotonic()
    if wait > 0:
        return wait
    refresh()
    return None


def schedule(now: bool = True) -> None:
    """A change may concern a live figure: re-bake it now (``now``: before the redraw; else on
    the timer's next call) and settle later."""
    if not live_figures():
        return
    _state["last_change"] = time.monotonic()
    if now:
        refresh(with_tracks=False, paths=False, window=True)
    if not bpy.app.timers.is_registered(_tick):
        bpy.app.timers.register(_tick, first_interval=0.0 if not now else SETTLE)


@persistent
def on_depsgraph_update(scene, depsgraph) -> None:
    """Keys, the Path curve, an obstacle or the Ground mesh may have changed."""
    if not live_figures(scene):
        return
    for u in depsgraph.updates:
        if isinstance(u.id, bpy.types.Object) and (u.is_updated_geometry
                                                   or u.is_updated_transform):
            _EDITS[u.id.name] = _EDITS.get(u.id.name, 0) + 1
    schedule(now=False)               # not while the depsgraph hands out its updates


def _subscribe() -> None:
    from ..props.figure import TurningFigureSettings, TurningTerrainSettings
    from ..props.skid import TurningSkidSettings
    bpy.msgbus.clear_by_owner(_MSGBUS_OWNER)
    for struct in (TurningFigureSettings, TurningTerrainSettings, TurningCrowdSettings,
                   TurningRigSettings, TurningSkidSettings):
        bpy.msgbus.subscribe_rna(key=struct, owner=_MSGBUS_OWNER, args=(), notify=schedule,
                                 options={"PERSISTENT"})


@persistent
def on_load_post(*_args) -> None:
    """A file was opened: its figures' failures are not known yet, and the message bus was
    cleared."""
    FAILURES.clear()
    _EDITS.clear()
    _WINDOWS.clear()
    _RIGS.clear()
    _GROUNDS.clear()
    _subscribe()


def draw_failures() -> None:
    """The viewport's overlay: "falls at frame N" (or why it cannot bake) beside every live
    figure whose last re-bake failed, at the figure's place on screen."""
    import blf
    from bpy_extras.view3d_utils import location_3d_to_region_2d
    context = bpy.context
    region, rv3d = context.region, context.region_data
    if not FAILURES or region is None or rv3d is None:
        return
    for name, failure in FAILURES.items():
        fig = bpy.data.objects.get(name)
        if fig is None or not fig.visible_get():
            continue
        xy = location_3d_to_region_2d(region, rv3d, fig.matrix_world.translation)
        if xy is None:
            continue
        text = (f"{name}: falls at frame {failure.frame}" if failure.frame is not None
                else f"{name}: cannot bake these settings")
        blf.size(0, 14)
        blf.color(0, 1.0, 0.25, 0.2, 1.0)
        blf.position(0, xy[0] + 12, xy[1] + 12, 0)
        blf.draw(0, text)


HANDLERS = ((bpy.app.handlers.depsgraph_update_post, on_depsgraph_update),
            (bpy.app.handlers.load_post, on_load_post))


def register():
    props.on_live_switched = live_changed
    for handlers, fn in HANDLERS:
        handlers.append(fn)
    _subscribe()
    _state["overlay"] = bpy.types.SpaceView3D.draw_handler_add(draw_failures, (), "WINDOW",
                                                               "POST_PIXEL")


def unregister():
    props.on_live_switched = None
    for handlers, fn in HANDLERS:
        while fn in handlers:
            handlers.remove(fn)
    bpy.msgbus.clear_by_owner(_MSGBUS_OWNER)
    overlay = _state.pop("overlay", None)
    if overlay is not None:
        bpy.types.SpaceView3D.draw_handler_remove(overlay, "WINDOW")
    if bpy.app.timers.is_registered(_tick):
        bpy.app.timers.unregister(_tick)
    FAILURES.clear()
    _EDITS.clear()
    _WINDOWS.clear()
    _RIGS.clear()
    _GROUNDS.clear()
    _state["tracks_due"] = {}

"""Writing a computed bake onto a figure (keys at every frame or every n-th with smooth
in-betweens, then its foot track), several figures' at once (those with another's motion playing
its bake), and putting a figure without keys back at its start.  Shared by Bake Turns, Follow
Path, Follow Path on several figures and Add Crowd."""
from __future__ import annotations

import math

import bpy
import numpy as np

from ...mapping import shared_motion
from ...mapping.base import BoneChannels, PoseTrack
from . import bake, fewer_keys, foot_track, user_action
from ..scene import retarget_adapter
from . import export_ready as export_ready_mod, export_state


def every_nth(track: PoseTrack, step: int) -> PoseTrack:
    """``track`` at every ``step``-th frame and its last (``step = 1``: ``track`` itself)."""
    if step <= 1:
        return track
    idx = np.arange(0, len(track), step)
    if idx[-1] != len(track) - 1:
        idx = np.append(idx, len(track) - 1)

    def take(a):
        return None if a is None else a[idx]

    return PoseTrack(take(track.frames), take(track.location), take(track.rotation),
                     {b: BoneChannels(take(ch.location), take(ch.rotation))
                      for b, ch in track.bones.items()},
                     {p: take(v) for p, v in track.props.items()})


def _baked_curves(fig) -> dict:
    """``{(data_path, index): (frames, values)}`` of every F-curve the last bake wrote."""
    action = bake.figure_action(fig)
    paths = set(action.get(bake.BAKED_PATHS, "").splitlines())
    out = {}
    for fc in bake.baked_channels(fig).fcurves:
        if fc.data_path in paths:
            co = np.empty(2 * len(fc.keyframe_points))
            fc.keyframe_points.foreach_get("co", co)
            out[(fc.data_path, fc.array_index)] = (co[0::2], co[1::2], fc)
    return out


def set_hermite_handles(fig, slopes: dict) -> None:
    """Bezier keys whose handles carry the exact slope of the every-frame bake (``slopes``:
    ``{(data_path, index): (frames, d value / d frame)}``): each segment is the cubic Hermite
    interpolant of its two keys, so the in-betweens are smooth and follow the motion closely."""
    enum = bpy.types.Keyframe.bl_rna.properties
    bezier = enum["interpolation"].enum_items["BEZIER"].value
    free = enum["handle_left_type"].enum_items["FREE"].value
    for key, (f, v, fc) in _baked_curves(fig).items():
        frames, slope = slopes[key]
        d = np.interp(f, frames, slope)
        h = np.diff(f) / 3.0                                   # handles at thirds: Hermite
        hl = np.r_[h[:1], h]
        hr = np.r_[h, h[-1:]]
        kp = fc.keyframe_points
        n = len(f)
        kp.foreach_set("handle_left", np.column_stack([f - hl, v - d * hl]).ravel())
        kp.foreach_set("handle_right", np.column_stack([f + hr, v + d * hr]).ravel())
        for attr, value in (("interpolation", bezier), ("handle_left_type", free),
                            ("handle_right_type", free)):
            kp.foreach_set(attr, np.full(n, value, np.int32))
        fc.update()


def apply_bake(fig, traj, track, step: int = 1, export_ready: bool = True,
               export_turn_state: bool | None = None, around=None):
    """Write a computed bake: F-curves (every ``step``-th frame, smooth in between), then the
    foot track; ``export_ready``: a user rig's equipment keyed too, for glTF and FBX
    (:mod:`.export_ready`); ``export_turn_state``: the state Empties (:mod:`.export_state`;
    ``None``: made again if the figure has them).  ``around``: :class:`Around` of a crowd's
    bake.  Returns the bake result."""
    if export_ready:
        track = export_ready_mod.with_take(fig, track)
    if step > 1:
        bake.bake_pose_track(fig, track)            # every frame first: the slopes at the keys
        slopes = {k: (f, np.gradient(v, f, edge_order=2))
                  for k, (f, v, _) in _baked_curves(fig).items()}
    result = bake.bake_pose_track(fig, every_nth(track, step))
    if step > 1:
        set_hermite_handles(fig, slopes)
    (around or Around()).write(fig, traj, track.frames, export_ready, export_turn_state)
    return result


class Around:
    """What a bake writes besides the figure's keys: the foot track, the equipment's keys (or
    none), the state Empties.  For a crowd, made once (``crowd``): the guide collections are
    read once and the figures with state Empties found in one look at every object (each is
    O(objects) a figure otherwise)."""

    def __init__(self, crowd: bool = False):
        self.guides = foot_track.guide_collections() if crowd else None
        self.carried = {o.get(export_state.CARRIES) for o in bpy.data.objects
                        if export_state.CARRIES in o} if crowd else None

    def write(self, fig, traj, frames, export_ready, export_turn_state) -> None:
        foot_track.write_foot_track(fig, traj.x, traj.y, z=traj.z,       # on the ground
                                    guides=self.guides)
        if export_ready:
            export_ready_mod.bake_equipment(fig, frames)
        else:
            export_ready_mod.clear_equipment(fig)
        carried = fig in self.carried if self.carried is not None \
            else bool(export_state.carriers(fig))
        if export_turn_state is None:
            export_turn_state = carried
        if export_turn_state:
            export_state.bake_state(fig, frames)
        elif carried:
            export_state.clear_state(fig)


class BakeWriter:
    """Write computed bakes figure by figure (:meth:`write`), in the order of their first frames
    (:func:`...mapping.shared_motion.order`).  With ``share`` (keys on every frame, or Fewer
    Keys), a figure whose pose track is one met before, moved and later by whole frames
    (:class:`...mapping.shared_motion.Matcher`), plays that figure's bake
    (:func:`.bake.share_bake`) instead of baking its own; else :func:`apply_bake` (``fewer``: a
    :class:`...mapping.keys.KeyTolerance`, then Fewer Keys)."""

    def __init__(self, step: int = 1, export_ready: bool = True,
                 export_turn_state: bool | None = None, fewer=None, share: bool = True):
        self.step, self.export_ready, self.export_turn_state = step, export_ready, \
            export_turn_state
        self.fewer = fewer
        self.matcher = shared_motion.Matcher() if share and step == 1 else None
        self.around = Around(crowd=True)
        self.shared = {}                  # figure name -> the figure whose bake it plays
        self.key_reports = {}             # figure name -> fewer_keys.KeyReport
        self.stash_notes = {}             # figure name -> user_action.stash_note

    def write(self, fig, traj, track):
        """Bake (or share) one figure; its :class:`.bake.BakeResult` (sharing: 0 F-curves)."""
        before = user_action.stashes([fig])
        result = self._write(fig, traj, track)
        note = user_action.stash_note(fig, before)
        if note:
            self.stash_notes[fig.name] = note
        return result

    def _write(self, fig, traj, track):
        can = self.matcher is not None and bake.can_share(fig)
        share = self.matcher.match(track) if can else None
        if share is not None:
            source = share.source
            result = bake.share_bake(fig, source, track, share.shift, share.translation)
            self.shared[fig.name] = source.name
            self.around.write(fig, traj, track.frames, self.export_ready,
                              self.export_turn_state)
            return result
        result = apply_bake(fig, traj, track, self.step, self.export_ready,
                            self.export_turn_state, self.around)
        if self.fewer is not None:
            self.key_reports[fig.name] = fewer_keys.reduce_bake(fig, self.fewer)
        if can:
            self.matcher.add(fig, track)
        return result


def write_bakes(figs, trajs, tracks, writer: BakeWriter) -> list:
    """Write the computed bakes of ``figs`` with ``writer``, the earliest-starting first (a
    figure's motion is shared by those starting later); their results in ``figs``' order."""
    out = [None] * len(figs)
    for k in shared_motion.order(tracks):
        out[k] = writer.write(figs[k], trajs[k], tracks[k])
    return out


def reset_pose(fig):
    """Put a figure without baked keys back at its start, in its rest pose (a user's rig: as it
    was before it became a figure)."""
    if retarget_adapter.is_user_rig(fig):
        retarget_adapter.reset_user_rig(fig)
        return
    s = fig.turning
    fig.location = s.start
    fig.rotation_euler = (0.0, 0.0, s.start_heading - math.pi / 2)
    for pb in fig.pose.bones:
        pb.location = (0.0, 0.0, 0.0)
        pb.rotation_quaternion = (1.0, 0.0, 0.0, 0.0)

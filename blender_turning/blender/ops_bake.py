"""``turning.bake_turns`` and ``turning.clear_bake``: the parametric controller (Section 5) over the
scene's frame range, and its removal."""
from __future__ import annotations

import math

import bpy

from ..core.errors import TurningError
from . import bake, foot_track, retarget_adapter
from .ops_common import context_figure, poll_figure
from .pipeline import figure_pose_track
from .scene_adapters import FrameRange, start_from_object


def apply_bake(fig, traj, track):
    """Write a computed bake: F-curves, then the foot track.  Returns the bake result."""
    result = bake.bake_pose_track(fig, track)
    foot_track.write_foot_track(fig, traj.x, traj.y)
    return result


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


class TURNING_OT_bake_turns(bpy.types.Operator):
    """Simulate the active figure's turns over the scene's frame range and bake them to keys"""

    bl_idname = "turning.bake_turns"
    bl_label = "Bake Turns"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        if not poll_figure(cls, context):
            return False
        if context.scene.frame_end <= context.scene.frame_start:
            cls.poll_message_set("The scene's frame range needs at least two frames")
            return False
        return True

    def execute(self, context):
        fig = context_figure(context)
        # Not baked yet: start where the user put the figure; baked: from its Start settings.
        start = start_from_object(fig) if bake.figure_action(fig) is None else None
        try:
            frames = FrameRange.of_scene(context.scene)
            traj, track = figure_pose_track(fig, frames, start=start)   # nothing written yet
        except (ValueError, TurningError) as exc:
            self.report({"ERROR"}, f"Bake Turns: {fig.name}: {exc}")
            return {"CANCELLED"}
        if start is not None:
            fig.turning.start = (start[0], start[1], 0.0)
            fig.turning.start_heading = start[2]
        result = apply_bake(fig, traj, track)
        self.report({"INFO"}, f"Baked {fig.name}: {result.fcurves} F-curves x {result.frames} "
                              f"frames ({frames.start}-{frames.end})")
        return {"FINISHED"}


class TURNING_OT_clear_bake(bpy.types.Operator):
    """Remove the active figure's baked turns and foot track (the user's own keys stay)"""

    bl_idname = "turning.clear_bake"
    bl_label = "Clear Bake"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        if not poll_figure(cls, context):
            return False
        if bake.figure_action(context_figure(context)) is None:
            cls.poll_message_set("The active figure has no baked turns")
            return False
        return True

    def execute(self, context):
        fig = context_figure(context)
        bake.clear_bake(fig)
        foot_track.remove_foot_track(fig)
        reset_pose(fig)
        self.report({"INFO"}, f"Cleared the bake of {fig.name}")
        return {"FINISHED"}


classes = (TURNING_OT_bake_turns, TURNING_OT_clear_bake)
register, unregister = bpy.utils.register_classes_factory(classes)

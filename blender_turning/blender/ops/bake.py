"""``turning.bake_turns`` and ``turning.clear_bake``: the parametric controller (Section 5) for
every selected figure over a frame range, and its removal.

A bake computes every figure first (:class:`..jobs.bake_job.BakeJob`) and writes only when all
succeeded: a
failure or Esc leaves the scene as it was.  With several figures and a window the operator is
modal (one figure per timer tick, a progress bar, Esc cancels between figures).
"""
from __future__ import annotations

import math

import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty

from ...mapping.keys import KeyTolerance
from ..anim import bake, foot_track
from ..anim import export_ready as export_ready_mod, export_state
from ..anim.figure_bake import reset_pose
from ..jobs.bake_job import BakeJob
from ..jobs.model_notes import turn_note
from ..scene.figure_context import end_modal, poll_figure, report_error, selected_figures
from ..scene.scene_adapters import FrameRange

FRAME_RANGES = (
    ("SCENE", "Scene", "The scene's frame range (Output properties)"),
    ("PREVIEW", "Preview", "The scene's preview range (the Timeline's clock button)"),
    ("CUSTOM", "Custom", "The Start and End frames given here"),
)


def bake_frames(scene, choice: str, start: int, end: int) -> FrameRange:
    """The frames to bake: the scene's range, its preview range or ``start..end``."""
    fps = scene.render.fps / scene.render.fps_base
    if choice == "PREVIEW":
        if not scene.use_preview_range:
            raise ValueError("the scene has no preview range (turn it on in the Timeline)")
        return FrameRange(scene.frame_preview_start, scene.frame_preview_end, fps)
    if choice == "CUSTOM":
        return FrameRange(start, end, fps)
    return FrameRange.of_scene(scene)


class TURNING_OT_bake_turns(bpy.types.Operator):
    """Simulate the turns of every selected figure over a frame range and bake them to keys"""

    bl_idname = "turning.bake_turns"
    bl_label = "Bake Turns"
    bl_options = {"REGISTER", "UNDO"}

    # Range and step are not remembered between bakes (SKIP_SAVE): the button always bakes the
    # scene's range on every frame, as the panel says; a custom Start/End is remembered.
    frame_range: EnumProperty(name="Frames", items=FRAME_RANGES, default="SCENE",
                              options={"SKIP_SAVE"}, description="Which frames to bake")
    frame_start: IntProperty(name="Start", default=1, min=-1048574, max=1048574,
                             description="First frame of a custom range")
    frame_end: IntProperty(name="End", default=250, min=-1048574, max=1048574,
                           description="Last frame of a custom range")
    step: IntProperty(name="Step", default=1, min=1, max=1000, soft_max=12,
                      options={"SKIP_SAVE"},
                      description="Key every n-th frame (and the last); smooth (Bezier) in "
                                  "between.  1 keys every frame, exactly")
    fewer_keys: BoolProperty(
        name="Fewer Keys", default=False, options={"SKIP_SAVE"},
        description="Key only where needed to stay within the tolerances of the every-frame "
                    "motion, with smooth (Bezier) handles: curves to edit, and a smaller file")
    key_angle: FloatProperty(
        name="Angle Tolerance", default=math.radians(0.1), min=math.radians(0.001),
        max=math.radians(10.0), subtype="ANGLE", precision=3,
        description="Fewer Keys: how far a rotation may stray from the every-frame motion")
    key_length: FloatProperty(
        name="Length Tolerance", default=0.001, min=1e-5, max=0.1, unit="LENGTH", precision=4,
        description="Fewer Keys: how far a position may stray from the every-frame motion")
    share: BoolProperty(
        name="Share Motion", default=True,
        description="A figure whose motion is another's, moved (a follower strung out along "
                    "the leader's track, a synchronized line in phase), plays that figure's "
                    "baked action from an NLA strip, moved by its Delta Transform, instead of "
                    "baking its own: much less to bake and store. Keys on every frame or Fewer "
                    "Keys only")
    export_ready: BoolProperty(
        name="Export-Ready Equipment", default=True,
        description="A figure made from your own rig: give its skis, poles or bicycle an "
                    "action too (they still follow the rig through their constraints and "
                    "drivers), so glTF exports their motion. Off: glTF leaves them behind")
    export_turn_state: BoolProperty(
        name="Export Turn State", default=False,
        description="Add an Empty per turn_* state property as a child of the figure, its X "
                    "location driven by the property, so glTF and FBX carry the state on every "
                    "frame (docs/export.md)")
    root_motion: BoolProperty(
        name="Root Motion", default=False,
        description="Key the travel on the rig's root bone (Rigify's or the built-in figures' "
                    "'root') instead of the armature object, which then stays where the bake "
                    "starts: for game engines that take a character's motion from its root")

    _job = None
    _timer = None

    @classmethod
    def poll(cls, context):
        return poll_figure(cls, context)

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        layout.prop(self, "frame_range")
        col = layout.column(align=True)
        col.active = self.frame_range == "CUSTOM"
        col.prop(self, "frame_start")
        col.prop(self, "frame_end")
        layout.prop(self, "step")
        layout.prop(self, "fewer_keys")
        col = layout.column(align=True)
        col.active = self.fewer_keys
        col.prop(self, "key_angle")
        col.prop(self, "key_length")
        layout.prop(self, "share")
        layout.prop(self, "export_ready")
        layout.prop(self, "export_turn_state")
        layout.prop(self, "root_motion")

    def _prepare(self, context):
        """The job for the selected figures, or ``None`` (reported)."""
        scene = context.scene
        for name, value in (("frame_start", scene.frame_start), ("frame_end", scene.frame_end)):
            if not self.properties.is_property_set(name):
                setattr(self, name, value)          # a custom range starts as the scene's
        try:
            frames = bake_frames(scene, self.frame_range, self.frame_start, self.frame_end)
            tolerance = KeyTolerance(self.key_angle, self.key_length) if self.fewer_keys \
                else None
            if tolerance is not None and self.step > 1:
                raise ValueError(f"Fewer Keys picks the frames to key; Step = {self.step} keys "
                                 "every n-th frame: use one of them (Step 1 with Fewer Keys)")
        except ValueError as exc:
            self.report({"ERROR"}, f"Bake Turns: {exc}")
            return None
        return BakeJob([f.name for f in selected_figures(context)], frames, self.step,
                       self.export_ready, self.root_motion, tolerance, self.export_turn_state,
                       self.share)

    def _finish(self, job):
        try:
            written = job.write()
        except Exception as exc:
            # Everything that can be checked was, before writing; a failure now is a bug (or the
            # disk).  One line, not a traceback, and FINISHED so that the undo step is pushed:
            # Ctrl+Z takes the scene back to before the bake.
            report_error(self, "Bake Turns", job.current, exc,
                         "; the bake was cut short: Undo (Ctrl+Z) puts the scene back")
            return {"FINISHED"}
        frames = job.frames
        every = "" if job.step == 1 else f", every {job.step} frames"
        what = ", ".join(f"{name} ({r.fcurves} F-curves x {r.frames} keys)" for name, r in written
                         if name not in job.shared)
        self.report({"INFO"}, f"Baked {what} over frames {frames.start}-{frames.end}{every}")
        by = {}
        for name, source in job.shared.items():
            by.setdefault(source, []).append(name)
        for source, names in by.items():
            self.report({"INFO"}, f"Bake Turns: {len(names)} figures play the bake of {source} "
                                  f"(its motion, moved): {', '.join(names)}")
        for name, keyed in job.key_reports.items():
            self.report({"INFO"}, f"Bake Turns: {name}: Fewer Keys: {keyed.summary()}")
        for name, note in job.stash_notes.items():
            self.report({"WARNING"}, f"Bake Turns: {name}: {note}")
        for name, _, traj, _ in job.results:     # last: the status bar shows the last report
            note = turn_note(traj)
            if note:
                self.report({"WARNING"}, f"Bake Turns: {name}: {note}")
        return {"FINISHED"}

    def execute(self, context):
        job = self._prepare(context)
        if job is None:
            return {"CANCELLED"}
        try:                              # everything that can fail, before anything is written
            while not job.done:
                job.compute_next()
        except Exception as exc:
            return report_error(self, "Bake Turns", job.current, exc)
        return self._finish(job)

    def invoke(self, context, event):
        if context.window is None or len(selected_figures(context)) < 2:
            return self.execute(context)
        self._job = self._prepare(context)
        if self._job is None:
            return {"CANCELLED"}
        wm = context.window_manager
        wm.progress_begin(0, len(self._job.names))
        self._timer = wm.event_timer_add(0.01, window=context.window)
        wm.modal_handler_add(self)
        self._status(context)
        return {"RUNNING_MODAL"}

    def _status(self, context):
        job = self._job
        context.workspace.status_text_set(
            f"Bake Turns: {len(job.results)} of {len(job.names)} figures (Esc to cancel)")

    def _cleanup(self, context):
        end_modal(self, context)

    def cancel(self, context):
        """Blender ends the operator (a file opened, Blender quits): stop, write nothing."""
        self._cleanup(context)

    def modal(self, context, event):
        if event.type == "ESC":
            self._cleanup(context)
            self.report({"WARNING"}, "Bake Turns cancelled; nothing was written")
            return {"CANCELLED"}
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        job = self._job
        try:
            job.compute_next()
        except Exception as exc:
            self._cleanup(context)
            return report_error(self, "Bake Turns", job.current, exc)
        context.window_manager.progress_update(len(job.results))
        if not job.done:
            self._status(context)
            return {"RUNNING_MODAL"}
        self._cleanup(context)
        return self._finish(job)


class TURNING_OT_clear_bake(bpy.types.Operator):
    """Remove the baked turns and foot tracks of the selected figures (the user's own keys
    stay)"""

    bl_idname = "turning.clear_bake"
    bl_label = "Clear Bake"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        if not poll_figure(cls, context):
            return False
        if not any(bake.figure_action(f) is not None for f in selected_figures(context)):
            cls.poll_message_set("The selected figures have no baked turns")
            return False
        return True

    def execute(self, context):
        figs = [f for f in selected_figures(context) if bake.figure_action(f) is not None]
        for fig in figs:
            fig.turning.live = False          # else Live Preview would bake it again at once
            recorded = bake.REST in fig       # the pose before the bake, put back exactly
            export_ready_mod.clear_equipment(fig)
            export_state.clear_state(fig)
            bake.clear_bake(fig)
            foot_track.remove_foot_track(fig)
            if not recorded:                  # baked before the pose was recorded
                reset_pose(fig)
        self.report({"INFO"}, f"Cleared the bake of {', '.join(f.name for f in figs)}")
        return {"FINISHED"}


classes = (TURNING_OT_bake_turns, TURNING_OT_clear_bake)
register, unregister = bpy.utils.register_classes_factory(classes)

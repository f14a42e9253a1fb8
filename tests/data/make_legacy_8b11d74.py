"""Made tests/data/legacy_8b11d74*.blend with the add-on as of commit 8b11d74: a skier with keyed
turning.period and turning.lean, baked over 48 frames.  Run from an archive of that commit:
  git archive 8b11d74 | tar -x -C /tmp/base8b1
  PYTHONPATH=/tmp/base8b1 .venv/bin/python tests/data/make_legacy_8b11d74.py OUT.blend
(.venv-bpy42 for the _bpy42 file: Blender 4.2 cannot open a file saved by 5.0)."""
import math, os, sys, tempfile
os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp())
import bpy
from blender_turning import blender as addon
bpy.ops.wm.read_factory_settings(use_empty=True)
addon.register()
sc = bpy.context.scene
sc.frame_start, sc.frame_end = 1, 48
sc.render.fps = 24
sc.cursor.location = (1.0, 2.0, 0.0)
bpy.ops.turning.add_figure(sport="SKIER")
obj = bpy.context.view_layer.objects.active
obj.turning.period = 2.4
obj.keyframe_insert("turning.period", frame=1)
obj.turning.period = 1.8
obj.keyframe_insert("turning.period", frame=48)
obj.turning.lean = math.radians(20)
obj.keyframe_insert("turning.lean", frame=1)
obj.turning.mass = 72.0
obj.turning.use_heading = False
assert bpy.ops.turning.bake_turns() == {"FINISHED"}
bpy.ops.wm.save_as_mainfile(filepath=sys.argv[-1], compress=True)
print("saved", sys.argv[-1], os.path.getsize(sys.argv[-1]))

"""The core and mapping layers import without bpy or mathutils (STYLE.md rule 1)."""
import subprocess
import sys


def test_core_and_mapping_import_without_bpy():
    code = ("import sys, blender_turning.core, blender_turning.mapping; "
            "bad = [m for m in sys.modules if m.split('.')[0] in ('bpy', 'mathutils')]; "
            "print(bad); sys.exit(1 if bad else 0)")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr

"""The layers import only downwards (docs/ARCHITECTURE.md Section 1): every module of core,
mapping, crowd, cli and figures imports in a fresh interpreter without bpy or mathutils, and the
command line never imports the Blender layer (tests/test_import_graph.py reads the same rules
from the source, every import included)."""
import json
import subprocess
import sys

import pytest

# Imports every module of a package (walking its subpackages) in a fresh interpreter and prints
# the modules imported, the bpy/mathutils modules loaded and whether the Blender layer was.
PROBE = r"""
import importlib, json, pkgutil, sys
pkg = importlib.import_module(sys.argv[1])
names = [pkg.__name__]
for info in pkgutil.walk_packages(pkg.__path__, pkg.__name__ + "."):
    importlib.import_module(info.name)
    names.append(info.name)
if sys.argv[1].endswith(".cli"):
    pkg.build_parser()                         # imports each command's module, as a run does
print(json.dumps({
    "modules": names,
    "bpy": sorted(m for m in sys.modules if m.split(".")[0] in ("bpy", "mathutils")),
    "blender": sorted(m for m in sys.modules if m.startswith("blender_turning.blender")),
}))
"""

#: The least number of modules each walk must find (so an empty walk cannot pass).
PACKAGES = {"blender_turning.core": 20, "blender_turning.mapping": 8,
            "blender_turning.crowd": 5, "blender_turning.cli": 4, "blender_turning.figures": 3}


def probe(package):
    r = subprocess.run([sys.executable, "-c", PROBE, package], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout.splitlines()[-1])


@pytest.mark.parametrize("package", sorted(PACKAGES))
def test_every_module_imports_without_bpy_or_mathutils(package):
    got = probe(package)
    assert len(got["modules"]) >= PACKAGES[package], got["modules"]
    assert got["bpy"] == [], got["bpy"]
    assert got["blender"] == [], got["blender"]


def test_the_command_line_entry_point_never_imports_blender():
    code = ("import runpy, sys; sys.argv = ['blender_turning', '--help']\n"
            "try:\n    runpy.run_module('blender_turning', run_name='__main__')\n"
            "except SystemExit:\n    pass\n"
            "bad = [m for m in sys.modules if m.startswith(('bpy', 'mathutils', "
            "'blender_turning.blender'))]\nprint(bad, file=sys.stderr); sys.exit(1 if bad else 0)")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr


def test_hypothesis_draws_the_same_examples_every_run():
    """Fixed seeds (CONTRIBUTING.md): the suite's Hypothesis profile is derandomized and keeps
    no example database, so a property test cannot pass one run and fail the next."""
    from hypothesis import settings
    assert settings.default.derandomize is True
    assert settings.default.database is None

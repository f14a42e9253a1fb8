"""The Blender console examples of README.md and docs/*.md (``<!-- run: blender -->``) run
verbatim on the bpy wheel, in the namespace Blender's Python console gives (``bpy``, ``C``,
``D``, ``from mathutils import *``, ``from math import *``), in the factory startup scene a
user opens; every ``bpy.ops`` statement in them must return ``{'FINISHED'}``.  Each example runs
in a child interpreter with the add-on registered from this checkout and a user folder of its
own (tests/doc_blocks.py: which blocks run where)."""
import os
import subprocess
import sys
import tempfile

import pytest

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-user-"))
pytest.importorskip("bpy")

from doc_blocks import ROOT, all_blocks  # noqa: E402

pytestmark = pytest.mark.blender
TIMEOUT = 300
BLENDER = [pytest.param(b, id=f"{b.page.relative_to(ROOT)}:{b.line}") for b in all_blocks()
           if b.lang == "python" and (b.note, b.arg) == ("run", "blender")]

CONSOLE = r"""
import os, sys, tempfile
os.environ["BLENDER_USER_RESOURCES"] = tempfile.mkdtemp(prefix="turning-user-")
import bpy
sys.path.insert(0, sys.argv[2])
from doc_blocks import checked_ops
from blender_turning import blender as addon
bpy.ops.wm.read_factory_settings(use_empty=False)      # the startup scene a user opens
addon.register()


def __finished__(result, what):
    if result != {"FINISHED"}:
        raise AssertionError(f"{what} returned {result}")


tree = checked_ops(open(sys.argv[1], encoding="utf-8").read())
namespace = {"__builtins__": __builtins__, "__name__": "__console__", "bpy": bpy,
             "C": bpy.context, "D": bpy.data, "__finished__": __finished__}
exec("from mathutils import *\nfrom math import *", namespace)
exec(compile(tree, "<console example>", "exec"), namespace)
print("ran", len(tree.body), "statements")
sys.stdout.flush()
os._exit(0)      # bpy 4.2 may crash while Python tears it down (tests/conftest.py)
"""


@pytest.mark.parametrize("block", BLENDER)
def test_blender_console_example_runs(block, tmp_path):
    src = tmp_path / "example.py"
    src.write_text(block.text, encoding="utf-8")
    r = subprocess.run([sys.executable, "-c", CONSOLE, str(src), str(ROOT / "tests")],
                       cwd=tmp_path, env=dict(os.environ, PYTHONPATH=str(ROOT)),
                       capture_output=True, text=True, timeout=TIMEOUT)
    assert r.returncode == 0 and "ran" in r.stdout, f"{block.where}\n{r.stdout}\n{r.stderr}"


def test_the_examples_are_found():
    assert len(BLENDER) >= 4, BLENDER

"""Every code example of README.md and docs/*.md runs verbatim where it says it runs
(tests/doc_blocks.py: the notes that say where).

- ``bash`` blocks: each ``python -m blender_turning ...`` command runs with this checkout's
  package, from a temporary folder that sees the repository's ``scenes/`` (the pages say "from
  the repository's root"), with the page's ``<!-- file: NAME -->`` blocks written there first.
  A ``--duration`` longer than :data:`SHORT` s runs for :data:`SHORT` s (the only change made to
  a command: the rest of it runs as written).  It must exit 0 and write every file it names.
- ``python`` blocks: in a fresh interpreter, from such a folder.
- ``<!-- run: blender -->`` blocks: tests/test_blender_doc_examples.py.
- ``<!-- run: scene -->`` / ``<!-- run: crowd -->`` JSON blocks: read by the core's scene reader
  and the crowd reader (the crowd's relative paths from ``scenes/crowds/``).
"""
import ast
import json
import os
import shlex
import subprocess
import sys
import tempfile

import pytest

from doc_blocks import ROOT, all_blocks, blocks, checked_ops, commands

#: Seconds a documented ``--duration`` is cut to (a 60 s run shows nothing a 5 s one does not
#: about whether the command works as written).
SHORT = 5.0
TIMEOUT = 300


def _param(b):
    marks = [pytest.mark.slow] if b.note == "slow" else []
    return pytest.param(b, id=f"{b.page.relative_to(ROOT)}:{b.line}", marks=marks)


def _select(pred):
    return [_param(b) for b in all_blocks() if b.note != "not-run" and pred(b)]


SHELL = _select(lambda b: b.lang == "bash")
PYTHON = _select(lambda b: b.lang == "python" and b.note in ("", "slow"))
FILES = _select(lambda b: b.note == "run" and b.arg in ("scene", "crowd"))


def workdir(page) -> str:
    """A temporary folder that sees ``scenes/``, with the page's files written in it."""
    d = tempfile.mkdtemp(prefix="turning-doc-")
    os.symlink(ROOT / "scenes", os.path.join(d, "scenes"))
    for b in blocks(page):
        if b.note == "file":
            with open(os.path.join(d, b.arg), "w", encoding="utf-8") as f:
                f.write(b.text)
    return d


def env() -> dict:
    """The environment of an example's process: this checkout's package first."""
    return dict(os.environ, PYTHONPATH=str(ROOT))


def shortened(argv: list) -> list:
    out = list(argv)
    for i, a in enumerate(out[:-1]):
        if a == "--duration" and float(out[i + 1]) > SHORT:
            out[i + 1] = str(SHORT)
    return out


def written(argv: list) -> list:
    """The files and folders a command says it writes."""
    return [argv[i + 1] for i, a in enumerate(argv[:-1]) if a in ("--out", "--plot", "--stats")]


def test_the_examples_are_found():
    """A walk that finds nothing cannot pass: each kind of example is there."""
    assert len(SHELL) >= 6 and len(PYTHON) >= 2 and len(FILES) >= 2


def test_a_long_duration_is_cut_and_nothing_else():
    assert shortened(["simulate", "--duration", "60", "--dt", "0.02"]) == \
        ["simulate", "--duration", str(SHORT), "--dt", "0.02"]
    assert shortened(["simulate", "--duration", "2"]) == ["simulate", "--duration", "2"]


@pytest.mark.parametrize("block", SHELL)
def test_shell_example_runs(block):
    d = workdir(block.page)
    cmds = commands(block)
    assert cmds, block.where
    for cmd in cmds:
        argv = shortened(shlex.split(cmd))
        assert argv[:3] == ["python", "-m", "blender_turning"], cmd
        r = subprocess.run([sys.executable, *argv[1:]], cwd=d, env=env(), capture_output=True,
                           text=True, timeout=TIMEOUT)
        assert r.returncode == 0, f"{block.where}: {cmd}\n{r.stdout}\n{r.stderr}"
        missing = [p for p in written(argv) if not os.path.exists(os.path.join(d, p))]
        assert not missing, f"{block.where}: {cmd} did not write {missing}"


@pytest.mark.parametrize("block", PYTHON)
def test_python_example_runs(block):
    r = subprocess.run([sys.executable, "-c", block.text], cwd=workdir(block.page), env=env(),
                       capture_output=True, text=True, timeout=TIMEOUT)
    assert r.returncode == 0, f"{block.where}\n{r.stdout}\n{r.stderr}"


@pytest.mark.parametrize("block", FILES)
def test_file_example_reads(block):
    doc = json.loads(block.text)
    if block.arg == "scene":
        from blender_turning.core.course.scene import scene_from_dict
        scene_from_dict(doc, source=block.where)
    else:
        from blender_turning.crowd.reader import crowd_from_dict
        crowd_from_dict(doc, ROOT / "scenes" / "crowds", source=block.where)


def test_every_operator_statement_is_checked():
    """The console check wraps every ``bpy.ops`` statement, nested ones too, and nothing else."""
    tree = checked_ops("bpy.ops.turning.bake_turns()\nfor i in x:\n    bpy.ops.a.b(c=1)\n"
                       "r = bpy.ops.a.b()\nprint(1)\n")
    out = ast.unparse(tree)
    assert out.count("__finished__(") == 2 and "print(1)" in out and "r = bpy.ops.a.b()" in out

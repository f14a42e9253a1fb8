"""Packaging.  `pip install .` carries the whole core: every package of the source tree and the
rigs, which live at the top of the repository (the Blender extension ships them from there) and go
into the wheel as blender_turning/rigs.  The Blender extension is built from the manifest's
[build] paths_exclude_pattern (exactly the add-on's files), with the README's command, on a fresh
copy."""
import importlib.util
import os
import shutil
import subprocess
import sys
import tomllib
import zipfile
from pathlib import Path

import pytest

from blender_turning.mapping.retarget.bone_map import BONE_MAPS
from blender_turning.mapping.rig_spec import RIG_NAMES

ROOT = Path(__file__).resolve().parents[1]


def test_the_package_list_is_the_source_tree():
    tool = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    found = {".".join(p.parent.relative_to(ROOT).parts)
             for p in (ROOT / "blender_turning").rglob("__init__.py")}
    assert set(tool["packages"]) == found | {"blender_turning.rigs"}
    assert tool["package-dir"] == {"blender_turning.rigs": "rigs"}


def test_the_wheel_carries_the_rigs_and_the_mapping_finds_them(tmp_path):
    # Built from a copy of what pip needs, so no build/ left over in the repository can leak in.
    src = tmp_path / "src"
    src.mkdir()
    for name in ("pyproject.toml", "README.md"):
        shutil.copy(ROOT / name, src / name)
    for name in ("blender_turning", "rigs"):
        shutil.copytree(ROOT / name, src / name, ignore=shutil.ignore_patterns("__pycache__"))
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w",
                    str(tmp_path / "dist"), str(src)], check=True, capture_output=True,
                   timeout=300)
    wheel, = (tmp_path / "dist").glob("blender_turning-*.whl")
    with zipfile.ZipFile(wheel) as zf:
        names = set(zf.namelist())
        zf.extractall(tmp_path / "site")
    assert {f"blender_turning/rigs/{n}.json" for n in RIG_NAMES} <= names
    assert {f"blender_turning/rigs/bone_maps/{n}.json" for n in BONE_MAPS} <= names
    assert not any(n.startswith(("tests/", "scripts/", "rigs/")) for n in names)
    # From the unpacked wheel alone (not the repository): the mapping loads every rig.
    code = ("import blender_turning.mapping.rig_spec as r, blender_turning.mapping.retarget.bone_map as b; "
            "[r.load_rig(n) for n in r.RIG_NAMES]; [b.load_bone_map(n) for n in b.BONE_MAPS]; "
            "print(r.RIGS_DIR)")
    out = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True,
                         text=True, env={"PYTHONPATH": str(tmp_path / "site")}, timeout=120)
    assert out.returncode == 0, out.stderr
    assert Path(out.stdout.strip()) == tmp_path / "site" / "blender_turning" / "rigs"


# -- the Blender extension -------------------------------------------------------------------------
# The package is built from the manifest's [build] exclude patterns: exactly the add-on's files.

CLI_ONLY = ("blender_turning/cli/", "blender_turning/figures/", "blender_turning/__main__.py")
STRAYS = ("foo.blend", "foo.blend1", ".DS_Store", "blender_turning/notes.txt",
          "blender_turning/core/.DS_Store", "rigs/notes.txt", "presets/turning_figure/old.py~")


def addon_files(root: Path) -> set:
    """What the add-on needs: its modules (not the command line) and the rigs (the sports'
    presets are their records, docs/registry.md)."""
    mods = {p.relative_to(root).as_posix() for p in (root / "blender_turning").rglob("*.py")
            if "__pycache__" not in p.parts}
    mods = {m for m in mods if not m.startswith(CLI_ONLY)}
    return (mods | {"__init__.py"}
            | {p.relative_to(root).as_posix() for p in (root / "rigs").rglob("*.json")})


def manifest():
    return tomllib.loads((ROOT / "blender_manifest.toml").read_text())


def path_filter():
    """The extension tool's own matcher of ``[build] paths_exclude_pattern`` (from the bpy wheel
    in .venv), as a function ``excluded(path)``; a folder's path ends with ``/``."""
    tool = ROOT / ".venv/lib/python3.11/site-packages/bpy/5.0/scripts/addons_core/bl_pkg/cli"
    if not (tool / "blender_ext.py").is_file():
        pytest.skip("no .venv with the bpy 5.0 wheel (scripts/env.sh makes it)")
    spec = importlib.util.spec_from_file_location("_blender_ext", tool / "blender_ext.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.PathPatternMatch(manifest()["build"]["paths_exclude_pattern"]).test_path


def shipped(root: Path, excluded) -> set:
    """The files of ``root`` the patterns keep, walked as the tool walks: a folder left out is
    not entered."""
    out = set()
    for dirpath, dirs, files in os.walk(root):
        rel = Path(dirpath).relative_to(root).as_posix()
        rel = "" if rel == "." else rel + "/"
        dirs[:] = [d for d in dirs if not excluded(rel + d + "/")]
        out |= {rel + f for f in files if not excluded(rel + f)}
    return out


def test_the_manifest_keeps_exactly_the_addon_files(tmp_path):
    """The exclude patterns keep the add-on's files and nothing else, also a new module of each
    subpackage (it needs no line in the manifest) and nothing of what lies about in a tree."""
    assert "paths" not in manifest()["build"]
    excluded = path_filter()
    src = fresh_copy(tmp_path / "clone")
    new = [p.parent.relative_to(ROOT).as_posix() + "/new_module.py"
           for p in (ROOT / "blender_turning").rglob("__init__.py")
           if p.parent != ROOT / "blender_turning"]
    for rel in (*STRAYS, *new):
        (src / rel).parent.mkdir(parents=True, exist_ok=True)
        (src / rel).write_text("stray" if rel in STRAYS else "")
    need = addon_files(src)
    got = shipped(src, excluded) - {"blender_manifest.toml"}
    assert not need - got, f"left out: {sorted(need - got)}: add a '!' line for them"
    assert not got - need, f"not add-on files: {sorted(got - need)}"


def test_the_manifest_names_a_website_and_a_contact():
    m = manifest()
    assert m["website"].startswith("https://")
    name, _, mail = m["maintainer"].partition("<")
    assert name.strip() and "@" in mail and mail.endswith(">")


def fresh_copy(dest: Path) -> Path:
    """The files a clone would have (tracked and not ignored), and the shared .venv beside them,
    as scripts/env.sh makes it."""
    out = subprocess.run(["git", "-C", str(ROOT), "ls-files", "-z", "--cached", "--others",
                          "--exclude-standard"], capture_output=True, check=True)
    for rel in filter(None, out.stdout.decode().split("\0")):
        if (ROOT / rel).is_file():
            (dest / rel).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(ROOT / rel, dest / rel)
    (dest / ".venv").symlink_to((ROOT / ".venv").resolve(), target_is_directory=True)
    return dest


def readme_build_commands() -> list:
    """The shell commands of the README's extension build block, continuation lines joined."""
    text = (ROOT / "README.md").read_text()
    block = text.split("\n## Install\n", 1)[1].split("```bash\n", 1)[1].split("```")[0]
    block = block.replace("\\\n", " ")
    return [line.split("#", 1)[0].strip() for line in block.splitlines()
            if line.split("#", 1)[0].strip()]


def test_the_readme_build_command_works_on_a_fresh_copy(tmp_path):
    tool = ROOT / ".venv/lib/python3.11/site-packages/bpy/5.0/scripts/addons_core/bl_pkg/cli"
    if not (tool / "blender_ext.py").is_file():
        pytest.skip("no .venv with the bpy 5.0 wheel (scripts/env.sh makes it)")
    src = fresh_copy(tmp_path / "clone")
    for stray in STRAYS:                      # lying in the tree; none of them may be shipped
        (src / stray).parent.mkdir(parents=True, exist_ok=True)
        (src / stray).write_text("stray")
    commands = readme_build_commands()
    assert any(c.startswith(".venv/bin/python") for c in commands), commands
    for cmd in commands:
        if cmd.split()[0] == "blender" and shutil.which("blender") is None:
            continue                          # the binary variant: no Blender binary here
        r = subprocess.run(["bash", "-c", cmd], cwd=src, capture_output=True, text=True,
                           timeout=300)
        assert r.returncode == 0 and "FATAL" not in r.stdout, cmd + "\n" + r.stdout + r.stderr
    with zipfile.ZipFile(src / "dist" / "blender_turning-0.1.0.zip") as zf:
        names = set(zf.namelist())
    assert names == addon_files(ROOT) | {"blender_manifest.toml"}
    assert not any(n.endswith((".blend", ".blend1", ".DS_Store", ".txt", "~")) for n in names)
    assert not any(n.startswith(("scenes/", "tests/", "scripts/")) for n in names)

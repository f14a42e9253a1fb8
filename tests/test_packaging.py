"""`pip install .` carries the whole core: every package of the source tree and the rigs, which
live at the top of the repository (the Blender extension ships them from there) and go into the
wheel as blender_turning/rigs."""
import shutil
import subprocess
import sys
import tomllib
import zipfile
from pathlib import Path

from blender_turning.mapping.bone_map import BONE_MAPS
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
    code = ("import blender_turning.mapping.rig_spec as r, blender_turning.mapping.bone_map as b; "
            "[r.load_rig(n) for n in r.RIG_NAMES]; [b.load_bone_map(n) for n in b.BONE_MAPS]; "
            "print(r.RIGS_DIR)")
    out = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True,
                         text=True, env={"PYTHONPATH": str(tmp_path / "site")}, timeout=120)
    assert out.returncode == 0, out.stderr
    assert Path(out.stdout.strip()) == tmp_path / "site" / "blender_turning" / "rigs"

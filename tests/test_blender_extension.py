"""Packaging: Blender's extension tool validates and builds the add-on; the built zip installs
into the bpy wheel, enables, runs an operator, disables; register/unregister/register leaves
nothing behind.  Each install runs in a fresh interpreter with its own user folder."""
import os
import subprocess
import sys
import tempfile
import textwrap
from pathlib import Path

import pytest

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-user-"))
bpy = pytest.importorskip("bpy")

pytestmark = pytest.mark.blender
ROOT = Path(__file__).resolve().parents[1]
EXT_TOOL = Path(bpy.utils.resource_path("LOCAL")) / "scripts/addons_core/bl_pkg/cli/blender_ext.py"

INSTALL = textwrap.dedent("""
    import os, sys, tempfile
    os.environ["BLENDER_USER_RESOURCES"] = tempfile.mkdtemp(prefix="turning-ext-")
    sys.modules["blender_turning"] = None     # the installed copy must not reach the dev one
    import bpy, addon_utils
    MOD = "bl_ext.user_default.blender_turning"

    def leftovers():
        out = [n for n in dir(bpy.types) if n.startswith(("TURNING_", "VIEW3D_PT_turning"))]
        if hasattr(bpy.types.Object, "turning"):
            out.append("Object.turning")
        out += bpy.utils.preset_paths("turning_figure")
        return out

    assert bpy.ops.extensions.package_install_files(
        filepath=sys.argv[1], repo="user_default", enable_on_install=True) == {"FINISHED"}
    assert MOD in bpy.context.preferences.addons, list(bpy.context.preferences.addons.keys())
    assert hasattr(bpy.types, "TURNING_MT_figure_presets"), "sport presets not registered"
    assert bpy.ops.turning.add_figure(sport="CYCLIST") == {"FINISHED"}
    fig = bpy.context.view_layer.objects.active
    assert fig.turning.is_figure and fig.turning.sport == "CYCLIST", fig
    for _ in range(2):                       # disable, enable, disable: nothing left behind
        addon_utils.disable(MOD, default_set=True)
        assert not leftovers(), leftovers()
        addon_utils.enable(MOD, default_set=True)
        assert hasattr(bpy.types.Object, "turning")
    addon_utils.disable(MOD, default_set=True)
    assert not leftovers(), leftovers()
    print("EXTENSION-OK", bpy.app.version_string)
""")


@pytest.fixture(scope="module")
def built_zip(tmp_path_factory):
    out = tmp_path_factory.mktemp("ext")
    r = subprocess.run([sys.executable, str(EXT_TOOL), "validate", str(ROOT)],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    r = subprocess.run([sys.executable, str(EXT_TOOL), "build", "--source-dir", str(ROOT),
                        "--output-dir", str(out)], capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    (zp,) = out.glob("*.zip")
    return zp


def test_built_zip_holds_the_addon_only(built_zip):
    import zipfile
    names = zipfile.ZipFile(built_zip).namelist()
    assert "__init__.py" in names and "blender_manifest.toml" in names
    assert "blender_turning/blender/anim/bake.py" in names
    assert any(n.startswith("rigs/") for n in names)
    assert any(n.startswith("rigs/bone_maps/") for n in names)
    assert not [n for n in names if n.startswith("presets/")]   # the sports' records are
    assert not [n for n in names if n.startswith((".venv", "tests/", "scripts/", ".git/"))]


def test_install_enable_run_disable(built_zip, tmp_path):
    script = tmp_path / "install.py"
    script.write_text(INSTALL)
    r = subprocess.run([sys.executable, str(script), str(built_zip)], capture_output=True,
                       text=True, timeout=300, cwd=tmp_path)
    assert "EXTENSION-OK" in r.stdout, r.stdout[-3000:] + r.stderr[-3000:]


def test_inner_package_imports_itself_only_relatively():
    """Inside Blender the package is ``bl_ext.<repo>.blender_turning``: an absolute
    ``blender_turning`` import would miss it (or pick up another copy)."""
    import ast
    bad = []
    for path in (ROOT / "blender_turning").rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            names = []
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0:
                names = [node.module or ""]
            bad += [f"{path.relative_to(ROOT)}: {n}" for n in names
                    if n.split(".")[0] == "blender_turning"]
    assert not bad, bad


@pytest.mark.installed
def test_the_installed_run_runs_the_installed_copy():
    """Run with ``TURNING_INSTALLED=1`` (scripts/test.sh), ``blender_turning`` is the installed
    extension's package, the object Blender loaded; otherwise the checkout."""
    import blender_turning
    from blender_turning.blender.jobs import workers
    import installed_addon
    here = Path(blender_turning.__file__).resolve()
    if not installed_addon.ACTIVE:
        assert ROOT in here.parents and workers.PACKAGE == "blender_turning"
        return
    assert ROOT not in here.parents, here
    assert blender_turning is sys.modules[installed_addon.INNER]
    assert workers.PACKAGE == installed_addon.INNER
    assert Path(os.environ["BLENDER_USER_RESOURCES"]) in here.parents


@pytest.mark.installed
def test_the_installed_run_cannot_import_the_checkout():
    """Against the installed extension (scripts/test.sh) nothing but the installed copy is
    ``blender_turning``: without the tests' alias ``import blender_turning`` fails, in the tests'
    process and in a Follow Path worker after it planned a figure (the add-on's pool, its task),
    so code that reached for the checkout would fail there as it does for a user."""
    import installed_addon
    if not installed_addon.ACTIVE:
        pytest.skip("the checkout is the add-on here (TURNING_INSTALLED=1 runs it installed)")
    from blender_turning import core
    from blender_turning.blender.jobs import workers
    from blender_turning.crowd import Crowd, CrowdFigure, Turns, runner
    alias = [f for f in sys.meta_path if isinstance(f, installed_addon._InstalledAlias)]
    saved = sys.modules.pop("blender_turning")
    sys.meta_path[:] = [f for f in sys.meta_path if f not in alias]
    try:
        with pytest.raises(ModuleNotFoundError):
            import blender_turning  # noqa: F401
    finally:
        sys.meta_path[:0] = alias
        sys.modules["blender_turning"] = saved
    task = runner.crowd_tasks(Crowd("c", [CrowdFigure("a", core.preset("skier"),
                                                      Turns(2.0, 0.4))], 3.0))[0]
    pool = workers.worker_pool(1)                    # one process: the task's, then the probe's
    try:
        with workers._plain_main():
            assert pool.submit(runner.run_task, task).result(timeout=120)
            loaded, got = pool.submit(installed_addon.checkout_import).result(timeout=120)
    finally:
        pool.shutdown()
    assert (loaded, got) == ([], "ModuleNotFoundError")

"""The Blender tests against the extension as a user installs it.

With ``TURNING_INSTALLED=1`` (``scripts/test.sh`` runs ``pytest -m installed`` so), the test
session first builds the extension zip with the README's command (Blender's extension tool from
the bpy wheel), installs it into a fresh user configuration (``BLENDER_USER_RESOURCES`` in a
temporary folder) with ``bpy.ops.extensions.package_install_files``, and then every
``import blender_turning...`` in the tests is the installed package
``bl_ext.user_default.blender_turning.blender_turning...``: the very module objects Blender
loaded (:class:`_InstalledAlias`), never the development checkout.  The ``registered`` fixture
then enables the add-on as Blender does (``addon_utils.enable`` of the extension).  So the code
the tests run, its ``__name__`` (which pickled worker tasks carry) and its files are the
installed ones.
"""
from __future__ import annotations

import importlib
import importlib.abc
import importlib.util
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: The extension's module as Blender names it (repository ``user_default``, id ``blender_turning``).
EXTENSION = "bl_ext.user_default.blender_turning"
#: The package the tests import as ``blender_turning``: the extension's inner package.
INNER = EXTENSION + ".blender_turning"
ACTIVE = os.environ.get("TURNING_INSTALLED", "0") == "1"


class _InstalledAlias(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """``blender_turning[.x]`` is the installed ``INNER[.x]``: the same module object (so there
    is one copy of every class, the one Blender registered)."""

    def find_spec(self, name, path=None, target=None):
        if name == "blender_turning" or name.startswith("blender_turning."):
            return importlib.util.spec_from_loader(name, self)
        return None

    def create_module(self, spec):
        return importlib.import_module(INNER + spec.name[len("blender_turning"):])

    def exec_module(self, module):
        pass                                    # the installed module ran already


def build_zip(out: Path, bpy) -> Path:
    """The README's build command, with the extension tool inside the bpy wheel."""
    tool = Path(bpy.utils.resource_path("LOCAL")) / "scripts/addons_core/bl_pkg/cli/blender_ext.py"
    out.mkdir(parents=True, exist_ok=True)
    r = subprocess.run([sys.executable, str(tool), "build", "--source-dir", str(ROOT),
                        "--output-dir", str(out)], capture_output=True, text=True, cwd=ROOT)
    if r.returncode != 0:
        raise RuntimeError(f"extension build failed:\n{r.stdout}{r.stderr}")
    (zp,) = out.glob("*.zip")
    return zp


def install() -> None:
    """Build, install into a temporary user configuration, route ``blender_turning`` imports to
    the installed copy.  Runs before anything imports ``blender_turning`` (``conftest.py``)."""
    if "blender_turning" in sys.modules:
        raise RuntimeError("blender_turning was imported before the installed extension")
    work = Path(tempfile.mkdtemp(prefix="turning-installed-"))
    os.environ["BLENDER_USER_RESOURCES"] = str(work / "user")
    import bpy
    zp = build_zip(work / "dist", bpy)
    result = bpy.ops.extensions.package_install_files(filepath=str(zp), repo="user_default",
                                                      enable_on_install=True)
    if result != {"FINISHED"}:
        raise RuntimeError(f"installing {zp} gave {result}")
    outer = importlib.import_module(EXTENSION)
    inside = Path(outer.__file__).resolve()
    if ROOT in inside.parents:
        raise RuntimeError(f"the installed extension is the checkout: {inside}")
    sys.meta_path.insert(0, _InstalledAlias())
    _record_operator_calls(bpy)


def hide_checkout() -> None:
    """Take the checkout's root off ``sys.path``: pytest puts it there when it imports the root's
    ``__init__.py`` (the extension's entry point, a package to pytest) while it sets up the first
    test, and from there ``import blender_turning`` would find the checkout (in the tests and in
    every worker process they start, which gets this ``sys.path``)."""
    sys.path[:] = [p for p in sys.path if Path(p or os.curdir).resolve() != ROOT]


#: ``turning.*`` operators the installed add-on registered, and those the tests called.
REGISTERED: set = set()
CALLED: set = set()


def _record_operator_calls(bpy) -> None:
    """Note every ``bpy.ops.turning.*`` call, so the session can say which operator the
    installed tests never ran (``conftest.pytest_sessionfinish``)."""
    op_class = type(bpy.ops.turning.add_figure)
    call = op_class.__call__

    def recorded(self, *args, **kw):
        CALLED.add(self.idname_py())
        return call(self, *args, **kw)

    op_class.__call__ = recorded


def uncalled() -> list:
    """The installed add-on's operators that no test called (sorted)."""
    return sorted(REGISTERED - CALLED)


def enable():
    """Enable the installed add-on as Blender does, and keep it enabled through the tests'
    factory resets (``read_factory_settings`` loads the factory preferences, which would disable
    it: the preferences of a user who enabled it keep it enabled)."""
    import addon_utils
    import bpy
    addon_utils.enable(EXTENSION, default_set=True, handle_error=_raise)
    REGISTERED.update("turning." + name for name in dir(bpy.ops.turning))
    if _keep_enabled not in bpy.app.handlers.load_factory_preferences_post:
        bpy.app.handlers.load_factory_preferences_post.append(
            bpy.app.handlers.persistent(_keep_enabled))


def disable():
    import addon_utils
    import bpy
    if _keep_enabled in bpy.app.handlers.load_factory_preferences_post:
        bpy.app.handlers.load_factory_preferences_post.remove(_keep_enabled)
    addon_utils.disable(EXTENSION, default_set=True, handle_error=_raise)


def _keep_enabled(*_args):
    import addon_utils
    addon_utils.enable(EXTENSION, default_set=True, handle_error=_raise)



def _raise(exc):
    raise exc


def checkout_import() -> tuple:
    """Run in a worker process: the modules named ``blender_turning...`` it has loaded (a task
    that reached the checkout's), then what ``import blender_turning`` gives there (the
    exception's name, or the file it imported)."""
    loaded = sorted(m for m in sys.modules if m.split(".")[0] == "blender_turning")
    try:
        import blender_turning
    except ModuleNotFoundError as exc:
        return loaded, type(exc).__name__
    return loaded, blender_turning.__file__

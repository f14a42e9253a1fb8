import math
import os
import sys
from dataclasses import replace

import pytest
from hypothesis import settings

import installed_addon

if installed_addon.ACTIVE:                  # before anything imports blender_turning
    installed_addon.install()

from blender_turning.core import Limits, preset  # noqa: E402

# Fixed seeds (CONTRIBUTING.md): Hypothesis draws the same examples on every run, so a test does
# not pass one run and fail the next; no example database is written.  Tests that set their own
# @settings (max_examples, deadline) inherit these.
settings.register_profile("turning", derandomize=True, database=None)
settings.load_profile("turning")


@pytest.fixture
def skier():
    return preset("skier")


@pytest.fixture
def skier_unbounded(skier):
    """The skier with no bound on C_f or its rate (Section 4's open-loop analysis)."""
    return replace(skier, limits=Limits(theta_fall=math.radians(80)))


@pytest.fixture(scope="module")
def registered():
    """The add-on registered in an empty factory scene, for one Blender test module (which sets
    ``BLENDER_USER_RESOURCES`` before it imports bpy; this fixture imports it only when used)."""
    import bpy
    bpy.ops.wm.read_factory_settings(use_empty=True)
    if installed_addon.ACTIVE:              # as Blender enables the installed extension
        installed_addon.enable()
        yield
        installed_addon.disable()
        return
    from blender_turning import blender as addon
    addon.register()
    yield
    addon.unregister()


#: Set in the interpreter a test marked ``own_process`` runs in (:func:`pytest_pyfunc_call`).
OWN_PROCESS = "TURNING_OWN_PROCESS"


def pytest_pyfunc_call(pyfuncitem):
    """A test marked ``own_process`` runs in a fresh interpreter of its own (pytest on that test
    alone), so nothing it leaves in bpy reaches the tests after it: after Rigify generated a rig,
    bpy 4.2's glTF and FBX exporters and importers crashed later in the same process (segfault,
    abort, a corrupt mesh read) in 9 of 23 runs of ``tests/test_blender_export.py``."""
    if pyfuncitem.get_closest_marker("own_process") is None or os.environ.get(OWN_PROCESS):
        return None
    import subprocess
    root = pyfuncitem.config.rootpath
    run = subprocess.run(
        [sys.executable, *(["-P"] if sys.flags.safe_path else []), "-m", "pytest", "-p",
         "no:cacheprovider", "-q", "-rA", pyfuncitem.nodeid], cwd=root,
        env={**os.environ, OWN_PROCESS: "1"},
        capture_output=True, text=True)
    out = run.stdout + run.stderr
    if run.returncode == 0 and "1 passed" in out:
        return True
    if run.returncode == 0 and "1 skipped" in out:
        pytest.skip(f"in its own process: {out.strip().splitlines()[-1]}")
    pytest.fail(f"in its own process (exit status {run.returncode}):\n{out}", pytrace=False)


@pytest.hookimpl(wrapper=True)
def pytest_runtest_setup(item):
    """Against the installed extension the checkout stays off ``sys.path`` (pytest's setup of the
    first test puts it there: :func:`installed_addon.hide_checkout`)."""
    result = yield
    if installed_addon.ACTIVE:
        installed_addon.hide_checkout()
    return result


def pytest_collection_modifyitems(config, items):
    """Against the installed extension only the tests marked ``installed`` run."""
    if installed_addon.ACTIVE:
        keep = [it for it in items if it.get_closest_marker("installed")]
        config.hook.pytest_deselected(items=[it for it in items if it not in keep])
        items[:] = keep


_EXIT_STATUS = []


def pytest_sessionfinish(session, exitstatus):
    if installed_addon.ACTIVE and not _narrowed(session.config) and exitstatus == 0:
        missing = installed_addon.uncalled()     # every operator runs as installed
        if missing or not installed_addon.REGISTERED:
            print(f"\ninstalled: no test marked 'installed' calls {missing or 'any operator'}")
            exitstatus = session.exitstatus = pytest.ExitCode.TESTS_FAILED
    _EXIT_STATUS.append(int(exitstatus))


def _narrowed(config) -> bool:
    """A run of chosen tests (``-k``, ``file::test``), not the whole installed job."""
    return bool(config.getoption("keyword")) or any("::" in a for a in config.args)


def pytest_unconfigure(config):
    """The bpy 4.2 LTS wheel segfaults while Python tears it down at exit after some Blender test
    sessions, every test having passed (the 4.5 and 5.0 wheels do not; the earlier finding:
    "bpy 4.2 crashes at exit on a registered PointerProperty").  Pytest has reported by now: end
    the process here with pytest's own status, so the crash cannot turn a green run red."""
    bpy = sys.modules.get("bpy")
    if bpy is not None and bpy.app.version < (4, 5, 0) and _EXIT_STATUS:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(_EXIT_STATUS[-1])

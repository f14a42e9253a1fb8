import math
import os
import sys
from dataclasses import replace

import pytest
from hypothesis import settings

from blender_turning.core import Limits, preset

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
    from blender_turning import blender as addon
    bpy.ops.wm.read_factory_settings(use_empty=True)
    addon.register()
    yield
    addon.unregister()


_EXIT_STATUS = []


def pytest_sessionfinish(session, exitstatus):
    _EXIT_STATUS.append(int(exitstatus))


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

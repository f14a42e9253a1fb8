import math
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

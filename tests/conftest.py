import math
from dataclasses import replace

import pytest

from blender_turning.core import Limits, preset


@pytest.fixture
def skier():
    return preset("skier")


@pytest.fixture
def skier_unbounded(skier):
    """The skier with no bound on C_f or its rate (Section 4's open-loop analysis)."""
    return replace(skier, limits=Limits(theta_fall=math.radians(80)))

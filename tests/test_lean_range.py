"""One lean range per figure: below its fall angle (core/ranges.py ``lean_range``), the same for
``--lean-deg``, a schedule's, a crowd's and a render job's ``lean_deg`` and Blender's Lean
(tests/test_blender_model_notes.py).  A lean outside it is refused once the figure is known,
naming the input, the value, the range and the reason; the global table's range is the widest
figure's (85 deg, the racers' and the carver's fall angle)."""
import math

import pytest

from blender_turning.core import PRESETS, preset
from blender_turning.core.ranges import RANGES, lean_range
from blender_turning.crowd import crowd_from_dict
from blender_turning.core.validate import FieldError
from cli_helpers import one_line_error, run

SKIER = "[1, 60) deg: the skier's fall angle theta_fall is 60 deg"


def test_the_skier_cannot_be_asked_past_its_fall_angle(tmp_path):
    """``simulate --preset skier --lean-deg 70``: one line, exit 2, nothing written."""
    r = run("simulate", "--preset", "skier", "--lean-deg", "70", "--duration", "1",
            "--out", tmp_path / "o.csv")
    one_line_error(r, "--lean-deg = 70.0 is outside the allowed range", SKIER)
    assert list(tmp_path.iterdir()) == []


def test_a_schedule_s_lean_is_the_figure_s_range(tmp_path):
    csv = tmp_path / "s.csv"
    csv.write_text("t,period,lean_deg\n0,2,20\n3,2,65\n")
    r = run("simulate", "--preset", "skier", "--schedule", csv, "--duration", "1")
    one_line_error(r, "s.csv: row 2 (line 3), column lean_deg = 65.0", SKIER)
    r = run("simulate", "--preset", "slalom_racer", "--schedule", csv, "--duration", "1")
    assert r.returncode == 0, r.stderr


def test_a_crowd_figure_s_lean_is_its_preset_s_range():
    doc = {"duration": 2, "figures": [{"name": "a", "preset": "telemark",
                                       "turns": {"period": 2, "lean_deg": 56}}]}
    with pytest.raises(FieldError, match=r"figures\[0\]\.turns\.lean_deg = 56 is outside the "
                       r"allowed range \[1, 55\) deg: the telemark's fall angle"):
        crowd_from_dict(doc)
    doc["figures"][0]["preset"] = "carver"
    assert crowd_from_dict(doc).figures[0].controller.lean == math.radians(56)


@pytest.mark.parametrize("name", sorted(PRESETS))
def test_each_preset_s_range_ends_below_its_fall_angle(name):
    """The table's range holds every preset's (its top is the largest fall angle)."""
    fall = preset(name).limits.theta_fall
    rng = lean_range(fall, f"the {name}")
    assert rng.hi == fall and rng.hi_open and not rng.contains(fall)
    assert rng.contains(math.nextafter(fall, 0.0)) and rng.lo == RANGES["theta_max"].lo
    assert RANGES["theta_max"].hi >= fall and RANGES["theta_max"].hi == RANGES["theta_fall"].hi

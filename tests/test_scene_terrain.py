"""A scene's ``terrain``: read and checked like every other field, and ``follow`` on
it writing the foot height ``z`` and the speed ``V_cm``."""
from __future__ import annotations

import csv
import json
import math

import numpy as np
import pytest

from blender_turning.cli import main
from blender_turning.core.course.scene import load_scene, scene_from_dict
from blender_turning.core.ground.terrain import HeightField, Plane
from blender_turning.core.physics.model import RESISTANCE
from blender_turning.core.validate import FieldError


def _doc(**terrain):
    return {"name": "hill", "figure": {"preset": "cyclist", "limits": {"dC_f_max": 0.4}},
            "path": {"polyline": [[0, 0], [25, 0]]}, "clearance": 0.3,
            "obstacles": [{"type": "circle", "center": [14, 1.6], "radius": 0.4}],
            "planner": {"stages": 5, "choices": 3}, "terrain": terrain}


def test_plane_and_resistance():
    sc = scene_from_dict(_doc(type="plane", slope_deg=6, downhill_deg=0, z0=3,
                              friction=0.01))
    assert sc.ground == Plane(math.radians(6), 0.0, 0.0, 0.0, 3.0)
    assert sc.resistance.mu == 0.01 and sc.resistance.CdA == RESISTANCE["cyclist"].CdA
    assert sc.state0.shape == (6,) and sc.state0[5] == sc.figure.body.V_cm


def test_no_terrain_is_flat():
    doc = _doc()
    del doc["terrain"]
    sc = scene_from_dict(doc)
    assert sc.ground is None and sc.state0.shape == (5,)


def test_height_field_inline_and_npy(tmp_path):
    h = np.add.outer(np.linspace(0, 1, 6), -0.1 * np.arange(40)).tolist()
    a = scene_from_dict(_doc(type="height_field", heights=h, origin=[-2, -3], cell=1.0))
    np.save(tmp_path / "ground.npy", np.array(h))
    doc = _doc(type="height_field", file="ground.npy", origin=[-2, -3], cell=1.0)
    (tmp_path / "s.json").write_text(json.dumps(doc))
    b = load_scene(tmp_path / "s.json")               # the file is found beside the scene
    assert isinstance(a.ground, HeightField) and a.ground.extent == (-2.0, 37.0, -3.0, 2.0)
    pts = (np.array([0.3, 10.2, 30.0]), np.array([0.0, -1.5, 1.7]))
    np.testing.assert_array_equal(a.ground.derivatives(*pts)[0], b.ground.derivatives(*pts)[0])


@pytest.mark.parametrize("terrain, words", [
    ({"type": "plane", "slope_deg": 75}, ["terrain.slope_deg = 75", "[0, 60] deg"]),
    ({"type": "plane"}, ["terrain.slope_deg", "missing"]),
    ({"type": "hill"}, ["terrain.type", "plane, height_field"]),
    ({"type": "plane", "slope_deg": 5, "cell": 1}, ["terrain.cell", "plane terrain"]),
    ({"type": "plane", "slope_deg": 5, "friction": 2}, ["terrain.friction = 2", "[0, 1]"]),
    ({"type": "plane", "slope_deg": 5, "drag_area": -1}, ["terrain.drag_area", "[0, 10] m^2"]),
    ({"type": "plane", "slope_deg": 5, "slope": 5}, ["terrain.slope", "slope_deg"]),
    ({"type": "height_field", "heights": [[0, 1], [2]], "cell": 1},
     ["terrain.heights", "same length"]),
    ({"type": "height_field", "heights": [[0, 1], [2, 3]], "cell": 0}, ["terrain.cell = 0"]),
    ({"type": "height_field", "heights": [[0, 1], [2, 1e9]], "cell": 1},
     ["terrain.heights[1][1] = 1000000000.0", "[-10000, 10000] m"]),
    ({"type": "height_field", "heights": [[0, 1, 2]], "cell": 1},
     ["terrain.heights rows = 1", "[2, 4096]"]),
    ({"type": "height_field", "cell": 1}, ["terrain.heights", "terrain.file"]),
    ({"type": "height_field", "file": "nowhere.npy", "cell": 1}, ["terrain.file", "nowhere.npy"]),
])
def test_bad_terrain_names_the_field(terrain, words):
    with pytest.raises(FieldError) as exc:
        scene_from_dict(_doc(**terrain), "hill.json")
    for w in words:
        assert w in str(exc.value), str(exc.value)
    assert str(exc.value).startswith("hill.json")


def test_speed_profile_refused_on_terrain():
    doc = _doc(type="plane", slope_deg=5)
    doc["speed"] = {"by": "time", "at": [0, 1], "V_cm": [5, 6]}
    with pytest.raises(FieldError, match="speed.*computed along the way"):
        scene_from_dict(doc)


def test_follow_cli_writes_z_and_speed(tmp_path, capsys):
    """Down a 6 deg road: the CSV's z is the plane's height under the foot, V_cm grows."""
    p = tmp_path / "hill.json"
    p.write_text(json.dumps(_doc(type="plane", slope_deg=6, downhill_deg=0, z0=2)))
    out = tmp_path / "t.csv"
    assert main(["follow", str(p), "--out", str(out)]) == 0
    with open(out) as fh:
        rows = list(csv.DictReader(fh))
    x = np.array([float(r["x"]) for r in rows])
    z = np.array([float(r["z"]) for r in rows])
    V = np.array([float(r["V_cm"]) for r in rows])
    np.testing.assert_allclose(z, 2.0 - math.tan(math.radians(6)) * x, atol=1e-9)
    assert V[0] == pytest.approx(6.0) and V[-1] > V[0] + 0.5
    assert f"speed 6.0-{V.max():.1f} m/s" in capsys.readouterr().out


def test_follow_cli_bad_terrain_one_line(tmp_path, capsys):
    p = tmp_path / "hill.json"
    p.write_text(json.dumps(_doc(type="plane", slope_deg=-3)))
    assert main(["follow", str(p)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "terrain.slope_deg = -3" in err[0]

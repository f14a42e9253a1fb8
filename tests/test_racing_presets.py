"""The racers' and the carver's presets (docs/racing.md): presets of the skier and the
snowboarder with FIS equipment, reachable as ``--preset``, in scene files and by their sport's
friction; the sidecut relation R = R_sc cos(edge) of their equipment."""
import math
from dataclasses import replace

import numpy as np
import pytest

from cli_helpers import one_line_error, run
from blender_turning.core import PRESETS, RESISTANCE, preset
from blender_turning.core.equipment import (Carving, SportPreset, carving_of, register_preset,
                                            sport_of)
from blender_turning.core.physics.params import Figure
from blender_turning.core.registry import SPORT_PRESETS, SPORTS
from blender_turning.core.course.scene import scene_from_dict
from blender_turning.core.physics.trajectory import Trajectory

RACERS = {"slalom_racer": ("skier", 1.65, 12.5), "gs_racer": ("skier", 1.93, 30.0),
          "carver": ("snowboarder", 1.63, 10.0)}


def test_the_presets_are_registered_with_their_sport_and_fis_equipment():
    for name, (sport, length, radius) in RACERS.items():
        fig = preset(name)
        assert fig.name == name and name in PRESETS and sport_of(name) == sport
        own = SPORTS[sport].resistance
        if name == "gs_racer":                  # its compact stance's own drag area
            assert RESISTANCE[name] == replace(own, CdA=0.4)
        else:
            assert RESISTANCE[name] is own
        c = carving_of(name)
        assert (c.length, c.sidecut_radius) == (length, radius)
        # The curvature bound is the equipment's: the sidecut relation at the largest edge.
        assert fig.limits.C_f_max == pytest.approx(1 / (radius * math.cos(c.edge_max)), rel=1e-12)
    # FIS: GS skis of men at least 193 cm and 30 m; SL at least 165 cm.
    assert carving_of("gs_racer").sidecut_radius >= 30.0 and carving_of("gs_racer").length >= 1.93
    assert carving_of("slalom_racer").length >= 1.65
    assert carving_of("skier") is None and sport_of("skier") == "skier"


def test_the_sidecut_relation_carves_the_curvature_it_is_given():
    c = Carving(length=1.65, sidecut_radius=12.5, edge_max=math.radians(75))
    C = np.linspace(-0.3, 0.3, 601)
    edge = c.edge_angle(C)
    carving = np.abs(C) >= 1 / 12.5
    # Where the ski carves, its edge carves exactly the curvature: R_sc cos(edge) = 1 / |C|.
    assert np.allclose(12.5 * np.cos(edge[carving]), 1 / np.abs(C[carving]), rtol=1e-12)
    assert np.all(edge[~carving] == 0.0) and np.all(np.sign(edge[carving]) == np.sign(C[carving]))
    assert c.edge_angle(0.2) == pytest.approx(math.acos(1 / 2.5), rel=1e-12)
    assert c.radius(math.radians(60)) == pytest.approx(6.25, rel=1e-12)


@pytest.mark.parametrize("bad, message", [
    (dict(sport="luge"), r"sport = 'luge' is not one of"),
    (dict(name="skier"), r"the name is a sport's"),
    (dict(carving=None), r"carving must be a Carving"),
    (dict(drag_area=-0.1), r"drag_area = -0.1 .* \[0, 2\]"),
])
def test_a_bad_preset_is_refused_naming_the_field(bad, message):
    fig = preset("skier")
    kw = dict(name="mine", sport="skier", label="Mine",
              figure=Figure(bad.get("name", "mine"), fig.body, fig.limits),
              carving=Carving(1.6, 13.0, math.radians(70)))
    kw.update(bad)
    with pytest.raises(ValueError, match=message):
        register_preset(SportPreset(**kw))
    assert "mine" not in SPORT_PRESETS
    with pytest.raises(ValueError, match=r"sidecut_radius = 0.5 .* \[1, 100\]"):
        Carving(1.6, 0.5, math.radians(70))


def test_the_command_line_and_a_scene_take_the_presets(tmp_path):
    out = tmp_path / "gs.csv"
    r = run("simulate", "--preset", "gs_racer", "--period", "3", "--lean-deg", "50",
            "--duration", "3", "--out", out)
    assert r.returncode == 0, r.stderr
    assert "simulate: gs_racer" in r.stdout
    assert len(Trajectory.from_csv(out)) > 100
    one_line_error(run("simulate", "--preset", "downhill_racer"), "--preset", "slalom_racer")
    scene = scene_from_dict({"figure": {"preset": "carver"},
                             "path": {"points": [[0, 0], [20, 0]], "tangents": [[10, 0]] * 2},
                             "terrain": {"type": "plane", "slope_deg": 10}}, "carver.json")
    assert scene.figure.name == "carver" and scene.resistance == SPORTS["snowboarder"].resistance

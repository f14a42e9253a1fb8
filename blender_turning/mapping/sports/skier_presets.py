"""The skier's everyday presets (docs/skidding.md Section 8): a beginner in a wedge and a
recreational skier who skids its turns, each with its skis (the sidecut relation,
core/equipment.py) and its speed habit on a slope (core/controllers/speed_habits.py).

Skis: a beginner's ski is short and soft, 150 cm with a sidecut radius of about 11 m; a
recreational all-mountain ski is about head height, 165 cm, radius about 15 m (manufacturers'
piste ranges: beginners' 140-155 cm and 10-13 m, recreational 155-175 cm and 13-17 m).  Neither
edges far: a beginner stands on flat skis and the wedge's inward edges (edge_max 30 deg, edge
change 1.0 s); a recreational skier reaches about 55 deg (0.6 s).

Speeds: recreational skiers measured on groomed pistes ski at 9.0-12.4 m/s (Stepan et al. 2023,
JSAMS Plus): the recreational skier holds 10.5 m/s by skidded turns.  A ski school's beginners
snowplough at walking-to-jogging pace behind their instructor: 4.5 m/s in a wedge, the wedge
goal of docs/skidding.md Section 4 (4 +- 1 m/s).
"""
from __future__ import annotations

import math

from ...core.equipment import Carving, SportPreset, carving_limits, register_preset
from ...core.physics.params import BodyParams, Figure
from ...core.controllers.speed_habits import HABITS, SpeedHabit

BEGINNER_SKI = Carving(length=1.50, sidecut_radius=11.0, edge_max=math.radians(30.0))
RECREATIONAL_SKI = Carving(length=1.65, sidecut_radius=15.0, edge_max=math.radians(55.0))

BEGINNER = register_preset(SportPreset(
    name="beginner", sport="skier", label="Beginner (Wedge)", carving=BEGINNER_SKI,
    figure=Figure(
        "beginner", BodyParams(m=70.0, l=0.95, I_v=10.1, V_cm=4.5),
        carving_limits(BEGINNER_SKI, 1.0, math.radians(45)),
        """A beginner in a wedge on short skis (150 cm, sidecut radius 11 m).  70 kg, centre of
        mass 0.95 m in an upright stance, roll inertia scaled from the skier's (12 kg m^2 x
        70 / 75 x 0.95^2); 4.5 m/s, a ski school's pace.  |C_f| <= 1 / (11 m cos 30 deg) =
        0.105 1/m; edge to edge in 1 s; fallen past 45 deg."""),
))
RECREATIONAL = register_preset(SportPreset(
    name="recreational", sport="skier", label="Recreational Skier", carving=RECREATIONAL_SKI,
    figure=Figure(
        "recreational", BodyParams(m=75.0, l=1.0, I_v=12.0, V_cm=10.5),
        carving_limits(RECREATIONAL_SKI, 0.6, math.radians(60)),
        """A recreational skier on all-mountain skis (165 cm, sidecut radius 15 m): the
        skier's body; 10.5 m/s, the middle of the 9.0-12.4 m/s Stepan et al. (2023) measured
        on groomed pistes.  |C_f| <= 1 / (15 m cos 55 deg) = 0.116 1/m; edge to edge in
        0.6 s; fallen past 60 deg."""),
))
HABITS["beginner"] = SpeedHabit("wedge", 4.5)
HABITS["recreational"] = SpeedHabit("skid", 10.5)

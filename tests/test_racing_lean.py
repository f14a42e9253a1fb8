"""The lean asked is the lean skied (docs/racing.md): the racers and the carver ski at least
95 % of a commanded 70 deg with heading control on, down a 19 deg slope (Reid et al. 2020's
slalom slope) as on the flat; directional control's room comes from the turn's shape
(STEER_BETAS), so a turn away from the bounds keeps all of its lean."""
import math

import numpy as np
import pytest

from blender_turning.cli import main
from blender_turning.core import PhaseEllipse, preset
from blender_turning.core.controllers.feasible import STEER_BETAS, feasible_turns

#: preset -> a period its 70 deg turn fits (s): the slalom racer's and the GS racer's skis are
#: at their C_f bound there, the carver's board is not.
PERIODS = {"slalom_racer": 3.0, "gs_racer": 5.0, "carver": 2.5}


@pytest.mark.parametrize("name", sorted(PERIODS))
def test_a_racer_skis_seventy_degrees_down_a_19_degree_slope(name, capsys):
    """``simulate --preset <racer> --slope-deg 19 --heading-deg -90 --lean-deg 70``: the peak
    lean is at least 66.5 deg (measured: 69.5-70.0 deg; the former fixed 85 % room: at most
    0.85 (85 - 8) = 65.5 deg)."""
    assert main(["simulate", "--preset", name, "--slope-deg", "19", "--heading-deg", "-90",
                 "--lean-deg", "70", "--period", str(PERIODS[name]), "--duration", "12"]) == 0
    out = capsys.readouterr().out
    peak = float(out.split("lean max ")[1].split(" deg")[0])
    assert peak >= 0.95 * 70.0, out


@pytest.mark.parametrize("name", sorted(PERIODS))
def test_the_turn_followed_on_the_flat_is_at_least_95_percent_of_the_asked(name):
    fig = preset(name)
    w = 2 * math.pi / PERIODS[name]
    ctl = PhaseEllipse(fig.body, w, math.radians(70), 0.0, limits=fig.limits)
    turn = ctl.commanded_turn(0.0)
    assert turn.lean >= 0.95 * math.radians(70), turn.describe()


def test_the_steering_room_is_the_modified_half_turns_feasible():
    """At the steerable lean every half-turn directional control may ride, ``(beta theta,
    omega0 / beta)`` for each beta of STEER_BETAS, is feasible, and one is at its bound; a turn
    whose modified half-turns fit keeps all of its lean (23 deg at 2 s on the skier)."""
    fig = preset("gs_racer")
    table = feasible_turns(fig.body, fig.limits)
    for period in (2.0, 3.0, 4.0, 6.0):
        w = 2 * math.pi / period
        lean = table.steerable_lean(w)
        slack = [table.max_lean(w / b) - b * lean for b in STEER_BETAS]
        assert min(slack) >= -1e-12 and lean <= table.max_lean(w)
        assert min(min(slack), table.max_lean(w) - lean) == pytest.approx(0.0, abs=1e-12)
    skier = preset("skier")
    ctl = PhaseEllipse(skier.body, math.pi, math.radians(23), 0.0, limits=skier.limits)
    assert ctl.commanded_turn(0.0).lean == math.radians(23)


@pytest.mark.parametrize("name", ["skier", "telemark", "slalom_racer", "carver"])
def test_steerable_leans_is_steerable_lean_bit_for_bit(name):
    """A crowd's batch asks for the array form every step: the same numbers as the lone
    figure's, for the held heading's room and for braking's."""
    from blender_turning.core.controllers.feasible import BRAKE_BETAS
    fig = preset(name)
    table = feasible_turns(fig.body, fig.limits)
    w = np.exp(np.linspace(math.log(0.3), math.log(20.0), 301))
    for betas in (STEER_BETAS, BRAKE_BETAS):
        np.testing.assert_array_equal(table.steerable_leans(w, betas),
                                      [table.steerable_lean(v, betas) for v in w])


def test_a_cyclist_leans_forty_degrees_with_heading_control(capsys):
    """Cyclists lean 45 deg on dry asphalt; 40 deg at 4 s is skied as asked (measured 40.0;
    the former fixed 85 % room and a 50 deg fall angle: 35.7)."""
    assert main(["simulate", "--preset", "cyclist", "--lean-deg", "40", "--period", "4",
                 "--duration", "12"]) == 0
    out = capsys.readouterr().out
    assert float(out.split("lean max ")[1].split(" deg")[0]) >= 39.9, out     # all of it

"""A sport, a formation and a controller of a user's own, made outside the package as a user makes
them (docs/registry.md): a sport is one module and its rig spec, written into a folder of the
test's; the formation and the controller are records registered after import.  Used by
tests/test_registry.py and tests/test_blender_registry.py."""
import importlib.util
import json
import sys
import textwrap
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SPORT, FORMATION, CONTROLLER = "skibike", "echelon", "half-lean"

#: The user's sport module: everything the add-on needs to know of the sport, in one file.
SPORT_MODULE = textwrap.dedent('''
    """A ski bike: a bicycle frame on short skis, ridden like an alpine skier (the skier's
    pose on the skier's rig, its own body, limits and resistance)."""
    import math
    from pathlib import Path

    from blender_turning.core.physics.params import BodyParams, Figure, Limits
    from blender_turning.core.sports import Retarget, Sport, register_sport
    from blender_turning.core.physics.model import Resistance
    from blender_turning.mapping import bones as B
    from blender_turning.mapping.sports.skier import SkierMapping


    class SkiBikeMapping(SkierMapping):
        sport = "skibike"


    SPORT = register_sport(Sport(
        name="skibike", label="Ski Bike", description="A ski bike on a groomed piste",
        number=17, icon="MOD_ARMATURE",
        figure=Figure("skibike", BodyParams(m=88.0, l=0.8, I_v=9.0, V_cm=9.0),
                      Limits(C_f_max=0.2, dC_f_max=0.6, theta_fall=math.radians(55))),
        resistance=Resistance(mu=0.04, CdA=0.45, rho=1.1),
        plan_curvature_rate=0.25,
        mapping=SkiBikeMapping(),
        bones=(B.ROOT, B.LEAN) + B.HUMAN + B.SKI + B.POLE,
        rig_file=str(Path(__file__).with_name("skibike.json")),
        retarget=Retarget(attach={"ski.L": "foot.L", "ski.R": "foot.R", "pole.L": "hand.L",
                                  "pole.R": "hand.R"}),
        stances=("regular", "goofy")), replace=True)
''')


def write_sport(folder: Path) -> list:
    """Write the sport's two files into ``folder``: its module and its rig spec (the skier's
    rig, renamed).  Returns their paths."""
    rig = json.loads((ROOT / "rigs" / "skier.json").read_text())
    rig["name"] = rig["sport"] = SPORT
    files = [folder / "skibike_sport.py", folder / "skibike.json"]
    files[0].write_text(SPORT_MODULE)
    files[1].write_text(json.dumps(rig))
    return files


def import_sport(module_file: Path):
    """Import the user's module from its file, as a script or another add-on would."""
    spec = importlib.util.spec_from_file_location("skibike_sport", module_file)
    module = importlib.util.module_from_spec(spec)
    sys.modules["skibike_sport"] = module
    spec.loader.exec_module(module)
    return module


def register_formation():
    """``echelon``: followers of a leader, each a gap later and one step further to the left."""
    from blender_turning.core.ranges import CROWD_RANGES
    from blender_turning.crowd.formations import follow_leader, made
    from blender_turning.crowd.registry import Formation, register_formation as reg

    def read(f, leader, seed, name):
        count = f.number("count", CROWD_RANGES["count"])
        step = f.number("step_m", CROWD_RANGES["lateral_m"])
        return made(follow_leader, leader, count, f.number("gap_s", CROWD_RANGES["gap_s"]),
                    "time", [step * (i + 1) for i in range(int(count))], seed, 0.0, 0.0, 0.0,
                    name)

    def build(lead, v, name):
        return follow_leader(lead, v.count, v.gap_time, "time",
                             [v.spacing * (i + 1) for i in range(v.count)], v.seed, 0.0, 0.0,
                             0.0, name)

    return reg(Formation(name=FORMATION, label="Echelon", number=11, template="leader",
                         description="Followers a gap apart, each a step further to the left",
                         keys={"count", "gap_s", "step_m"}, read=read, build=build,
                         fields=lambda v: ("gap_time", "spacing")), replace=True)


def register_controller():
    """``half-lean``: the phase-ellipse controller leaning half as far as asked."""
    from blender_turning.core.controllers import ControllerType, PhaseEllipse
    from blender_turning.core.controllers import register_controller as reg
    return reg(ControllerType(
        name=CONTROLLER, label="Half Lean", description="phase-ellipse turns at half the lean",
        make=lambda fig, w, tm, heading, law: PhaseEllipse(
            fig.body, w, lambda t: 0.5 * tm(t), heading, law=law, limits=fig.limits)),
        replace=True)


def unregister_all():
    from blender_turning.core.controllers import CONTROLLERS, unregister_controller
    from blender_turning.core.registry import SPORTS
    from blender_turning.crowd.registry import FORMATIONS, unregister_formation
    from blender_turning.core.sports import unregister_sport
    for reg, drop, name in ((SPORTS, unregister_sport, SPORT),
                            (FORMATIONS, unregister_formation, FORMATION),
                            (CONTROLLERS, unregister_controller, CONTROLLER)):
        if name in reg:
            drop(name)
    sys.modules.pop("skibike_sport", None)

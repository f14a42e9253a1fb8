"""One record per sport, per formation, per controller (docs/registry.md): a sport, a formation
and a controller registered from outside the package, after import, are listed and used by every
reader, choice list and validator; the built-in sports touch no file but their own."""
import json
import math
import re
from pathlib import Path

import numpy as np
import pytest

import registry_fixtures as fx
from blender_turning.core import preset, simulate, slalom_start
from blender_turning.core.controllers import CONTROLLERS
from blender_turning.core.physics.params import PRESETS, BodyParams, Figure, Limits
from blender_turning.core.registry import SPORTS, Registry
from blender_turning.core.course.scene import scene_from_dict
from blender_turning.core.ground.scene_terrain import read_terrain
from blender_turning.core.sports import Retarget, Sport, register_sport, sport
from blender_turning.core.physics.model import RESISTANCE, Resistance
from blender_turning.core.validate import FieldError, Fields
from blender_turning.crowd import crowd_from_dict
from blender_turning.crowd.formations import FORMATIONS
from blender_turning.mapping import MAPPINGS, map_trajectory
from blender_turning.mapping.bones import REQUIRED
from blender_turning.mapping.retarget.retarget import ATTACH
from blender_turning.mapping.rig_spec import RIG_NAMES, load_rig
from blender_turning.mapping.sports.skier import SkierMapping
from blender_turning.mapping.retarget.stance import STANCES

ROOT = fx.ROOT
SCENE = {"figure": {"preset": fx.SPORT},
         "path": {"points": [[0, 0], [20, 0], [40, 3]], "tangents": [[10, 0]] * 3}}


@pytest.fixture
def own(tmp_path):
    """The user's sport (its module and rig in ``tmp_path``), formation and controller."""
    files = fx.write_sport(tmp_path)
    module = fx.import_sport(files[0])
    fx.register_formation()
    fx.register_controller()
    yield module.SPORT, files
    fx.unregister_all()


def test_the_builtins_are_registered_in_their_blender_order_with_their_stored_numbers():
    # The numbers are what .blend files saved before the registry stored for the Sport and
    # Formation enums (the order of the old static tuples): they may never change.
    assert [(s.key, s.number) for s in SPORTS.values()] == [
        ("SKIER", 0), ("SNOWBOARDER", 1), ("TELEMARK", 2), ("CYCLIST", 3)]
    assert [(f.key, f.number) for f in FORMATIONS.values()] == [
        ("FOLLOW_LEADER", 0), ("SYNCHRONIZED", 1), ("PELOTON", 2)]
    assert set(CONTROLLERS) == {"ellipse", "open-loop", "straight"}


def test_the_partial_views_list_only_the_sports_that_have_the_part():
    """A view of a part some sports lack (a stance, a seat, an anchor) lists only those that
    have it: ``sport in STANCES`` is how the panel and the retargeting decide."""
    from blender_turning.mapping.retarget.retarget import ANCHOR, SEATED, SLIDE, SPIN, TRACKS
    assert list(STANCES) == ["snowboarder"] and list(ANCHOR) == ["telemark"]
    assert list(SEATED) == list(SPIN) == list(SLIDE) == list(TRACKS) == ["cyclist"]
    assert len(STANCES) == 1 and "skier" not in STANCES
    with pytest.raises(KeyError):
        STANCES["skier"]


def test_a_sport_registered_from_outside_is_in_every_table(own):
    record, _ = own
    name = fx.SPORT
    assert PRESETS[name] is record.figure and preset("SkiBike").body.m == 88.0
    assert RESISTANCE[name].mu == 0.04 and MAPPINGS[name] is record.mapping
    assert name in RIG_NAMES and REQUIRED[name] == record.bones
    assert ATTACH[name]["ski.L"] == "foot.L" and STANCES[name] == ("regular", "goofy")
    assert sport("SKIBIKE") is record
    spec = load_rig(name)                      # from the record's own file, not rigs/
    assert spec.name == name and "ski.L" in spec.bone_names


def test_readers_and_validators_take_the_sport_from_the_registry(own):
    sc = scene_from_dict(SCENE, "own.json")
    assert sc.figure.name == fx.SPORT and sc.figure.body.V_cm == 9.0
    crowd = crowd_from_dict({"duration": 2.0, "figures": [
        {"name": "a", "preset": fx.SPORT, "turns": {"period": 2.0, "lean_deg": 15}}]})
    assert crowd.figures[0].figure.body.m == 88.0
    # A slope's default resistance is the sport's own.
    _, res = read_terrain(Fields({"type": "plane", "slope_deg": 10}, "t"), fx.SPORT)
    assert (res.mu, res.CdA, res.rho) == (0.04, 0.45, 1.1)
    # An unknown preset's error lists the registered sports, the new one too.
    with pytest.raises(FieldError, match=r"preset = 'luge' is not one of .*skibike"):
        scene_from_dict({**SCENE, "figure": {"preset": "luge"}}, "own.json")


def test_the_sport_maps_onto_its_own_rig(own):
    fig = preset(fx.SPORT)
    w, tm = 2 * math.pi / 2.0, math.radians(18)
    from blender_turning.core import PhaseEllipse
    traj = simulate(fig, PhaseEllipse(fig.body, w, tm, heading=0.0), 2.0,
                    state0=slalom_start(fig.body, w, tm, 0.0))
    track = map_trajectory(fx.SPORT, traj, fps=24)
    assert len(track) == 49 and "ski.L" in track.bones
    assert np.all(np.isfinite(track.bones["thigh.L"].rotation))


def test_the_command_line_lists_and_runs_the_sport_and_the_controller(own, tmp_path, capsys):
    from blender_turning.cli import build_parser, main
    sim = build_parser()._subparsers._group_actions[0].choices["simulate"]
    choices = {a.dest: a.choices for a in sim._actions if a.choices}
    assert fx.SPORT in choices["preset"] and fx.CONTROLLER in choices["controller"]
    runs = {}
    for ctl in ("ellipse", fx.CONTROLLER):
        out = tmp_path / f"{ctl}.csv"
        assert main(["simulate", "--preset", fx.SPORT, "--controller", ctl, "--duration", "2",
                     "--out", str(out)]) == 0
        runs[ctl] = np.loadtxt(out, delimiter=",", skiprows=1)
    # The record's make was used: the largest lean (theta_v, column 4) is half the ellipse's
    # 23 deg (the start is on the ellipse the controller is made for, so both reach it within
    # the first half-turn; measured 23.0 and 11.5 deg).
    peak = {k: np.abs(v[:, 4]).max() for k, v in runs.items()}
    assert peak["ellipse"] == pytest.approx(math.radians(23), abs=math.radians(0.2))
    assert peak[fx.CONTROLLER] == pytest.approx(math.radians(11.5), abs=math.radians(0.2))
    with pytest.raises(SystemExit) as exc:
        main(["simulate", "--controller", "nope"])
    assert exc.value.code == 2
    assert fx.CONTROLLER in capsys.readouterr().err        # the choices named


def test_a_formation_registered_from_outside_is_read_by_the_crowd_file_and_the_job(own,
                                                                                  tmp_path):
    doc = {"duration": 10.0, "figures": [
        {"name": "lead", "preset": "skier", "turns": {"period": 2.0, "lean_deg": 15,
                                                      "heading_deg": 0}}],
        "formations": [{"type": fx.FORMATION, "leader": "lead", "count": 3, "gap_s": 1.0,
                        "step_m": 2.0}]}
    crowd = crowd_from_dict(doc)
    assert [f.name for f in crowd.figures] == ["lead", "lead-1", "lead-2", "lead-3"]
    ys = [f.position[1] for f in crowd.figures]       # heading 0: left is +y
    assert ys == pytest.approx([0.0, 2.0, 4.0, 6.0])
    bad = {**doc, "formations": [{**doc["formations"][0], "stepm": 2.0}]}
    with pytest.raises(FieldError, match=r"formations\[0\]\.stepm is not a known field.*step_m"):
        crowd_from_dict(bad)
    with pytest.raises(FieldError, match=r"type = 'ring' is not one of .*echelon"):
        crowd_from_dict({**doc, "formations": [{"type": "ring"}]})
    # The render job's crowds: any formation made from a leader, read by its record.
    from blender_turning.blender.render import crowds
    assert fx.FORMATION in crowds._led_formations()


def test_the_render_job_takes_the_sport_from_the_registry(own, tmp_path):
    from types import SimpleNamespace
    from blender_turning.blender.render.config import load_config
    cfg = tmp_path / "job.toml"
    cfg.write_text(f'[[figures]]\nsport = "{fx.SPORT}"\nlean_deg = 20\n')
    flags = SimpleNamespace(name=None, seconds=None, frame_step=None, output=str(tmp_path / "o"),
                            engine=None, resolution=None, device=None, frames=None,
                            no_render=False)
    (fig,) = load_config(cfg, flags)["figures"]
    assert fig["sport"] == fx.SPORT and fig["name"] == "Ski Bike"
    cfg.write_text(f'[[figures]]\nsport = "{fx.SPORT}"\nlean_deg = 56\n')   # its fall: 55 deg
    with pytest.raises(ValueError, match=r"\[1, 55\) deg: the skibike's fall angle"):
        load_config(cfg, flags)


def test_unregistering_removes_the_sport_everywhere(own):
    fx.unregister_all()
    for table in (PRESETS, RESISTANCE, MAPPINGS, RIG_NAMES, REQUIRED, ATTACH, STANCES):
        assert fx.SPORT not in table
    assert fx.FORMATION not in FORMATIONS and fx.CONTROLLER not in CONTROLLERS
    with pytest.raises(ValueError, match="sport = 'skibike' is not one of skier"):
        sport(fx.SPORT)


def _record(**changes):
    base = dict(name="sled", label="Sled", description="A sled", number=40,
                figure=Figure("sled", BodyParams(), Limits()), resistance=Resistance(),
                plan_curvature_rate=0.2, mapping=type("M", (SkierMapping,), {"sport": "sled"})(),
                bones=("root",))
    base.update(changes)
    return Sport(**base)


@pytest.mark.parametrize("changes, message", [
    ({"figure": Figure("skier", BodyParams(), Limits())}, "figure must be a core Figure named"),
    ({"mapping": SkierMapping()}, "mapping must be a Mapping whose sport is 'sled'"),
    ({"number": -1}, r"number = -1 is not a whole number"),
    ({"label": " "}, "label"),
    ({"plan_curvature_rate": -1.0}, "plan_curvature_rate = -1"),
    ({"stances": ("left",)}, "stances"),
    ({"bones": ()}, "bones"),
])
def test_a_bad_sport_record_is_refused_naming_the_field(changes, message):
    with pytest.raises(ValueError, match=message):
        _record(**changes)


def test_a_taken_name_or_number_is_refused():
    with pytest.raises(ValueError, match="sport = 'skier' is already registered"):
        register_sport(_record(name="skier", figure=Figure("skier", BodyParams(), Limits()),
                               mapping=SkierMapping()))
    with pytest.raises(ValueError, match="sport 'sled': number = 2 is taken by 'telemark'"):
        register_sport(_record(number=2))
    assert "sled" not in SPORTS
    reg = Registry("thing")
    with pytest.raises(ValueError, match="thing name = 'Bad Name' is not a lowercase"):
        reg.register(type("R", (), {"name": "Bad Name"})())
    with pytest.raises(ValueError, match="thing = 'x' is not one of"):
        reg.unregister("x")
    with pytest.raises(ValueError, match="spin names 'wheel'"):
        Retarget(attach={"ski": "foot.L"}, spin=("wheel",))


# -- how many files a sport touches ------------------------------------------------------------

_ADDON = [p for p in (ROOT / "blender_turning").rglob("*.py") if "__pycache__" not in p.parts] \
    + [ROOT / "__init__.py", ROOT / "blender_manifest.toml"]


def _touched(sport_name: str) -> set:
    """The add-on's files that would change with the sport: its module and rig (the manifest
    lists them), the package that imports its module, and any file naming the sport as a
    literal (a per-sport table, an enum item, a special case)."""
    literal = re.compile(rf"""["']({sport_name}|{sport_name.upper()})["']""")
    imports = re.compile(rf"^from \.sports\.{sport_name} import", re.M)
    out = {f"rigs/{sport_name}.json"}
    for p in _ADDON:
        text = p.read_text()
        if literal.search(text) or imports.search(text) or \
                f"/{sport_name}.py" in text or f"/{sport_name}.json" in text:
            out.add(p.relative_to(ROOT).as_posix())
    return out


@pytest.mark.parametrize("name", ["snowboarder", "telemark", "cyclist"])
def test_a_built_in_sport_touches_its_module_its_rig_and_one_import(name):
    """A built-in sport is its module (the record) and its rig spec; the mapping package imports
    the module (the explicit list of built-ins).  Nothing else in the add-on names it, not even
    the manifest (its exclude patterns ship every module and rig).  (The skier is left out: it is
    the default sport, named as such by the CLI and the enums.)"""
    assert _touched(name) == {f"blender_turning/mapping/sports/{name}.py", f"rigs/{name}.json",
                              "blender_turning/mapping/__init__.py"}


def test_a_sport_from_outside_is_two_files_and_edits_none(tmp_path):
    before = {p: p.stat().st_mtime_ns for p in _ADDON}
    files = fx.write_sport(tmp_path)
    try:
        fx.import_sport(files[0])
        assert sorted(p.name for p in tmp_path.iterdir()) == ["skibike.json", "skibike_sport.py"]
        assert fx.SPORT in PRESETS and json.loads(files[1].read_text())["sport"] == fx.SPORT
    finally:
        fx.unregister_all()
    assert {p: p.stat().st_mtime_ns for p in _ADDON} == before


# -- from the command line and the render job: --register ---------------------------------------

def test_register_brings_the_users_sport_to_the_command_line_and_the_job(tmp_path):
    """In a fresh interpreter, ``--register FILE`` imports the user's module before the command
    is parsed (its choices are the registry's) and before the job's config is read."""
    import subprocess
    import sys
    from cli_helpers import one_line_error
    module, _ = fx.write_sport(tmp_path)
    env = {**__import__("os").environ, "PYTHONPATH": str(ROOT)}
    out = tmp_path / "t.csv"
    r = subprocess.run([sys.executable, "-m", "blender_turning", "--register", str(module),
                        "simulate", "--preset", fx.SPORT, "--duration", "1", "--out", str(out)],
                       capture_output=True, text=True, env=env, timeout=120)
    assert r.returncode == 0, r.stderr
    assert out.read_text().startswith("t,x,y,theta_dir,theta_v")
    r = subprocess.run([sys.executable, "-m", "blender_turning", "simulate", "--preset",
                        fx.SPORT], capture_output=True, text=True, env=env, timeout=120)
    one_line_error(r, "--preset", "'skibike'")                  # not registered without it
    r = subprocess.run([sys.executable, "-m", "blender_turning", "--register",
                        str(tmp_path / "none.py"), "simulate"], capture_output=True, text=True,
                       env=env, timeout=120)
    one_line_error(r, "--register", "none.py", "no such file")
    cfg = tmp_path / "job.toml"
    cfg.write_text(f'[[figures]]\nsport = "{fx.SPORT}"\nlean_deg = 56\n')   # its fall: 55 deg
    r = subprocess.run([sys.executable, str(ROOT / "scripts" / "render_job.py"), "--register",
                        str(module), "--config", str(cfg), "--output", str(tmp_path / "o")],
                       capture_output=True, text=True, env=env, timeout=120)
    one_line_error(r, "figures[0].lean_deg = 56", "skibike's fall angle theta_fall is 55 deg")

"""The registries in Blender (docs/registry.md): a sport and a formation registered from outside
after the add-on is registered are in the Sport enums, the Add menu, the Sport Presets menu and
Add Crowd's Formation enum, and work end to end (a figure of the sport from its own rig, baked;
a crowd of the formation); the built-ins keep the enum values saved files hold."""
import os
import tempfile

import numpy as np
import pytest

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-user-"))
bpy = pytest.importorskip("bpy")

import registry_fixtures as fx  # noqa: E402
from rig_fixtures import activate, mixamo_skeleton  # noqa: E402
from test_blender_animator import LayoutStub  # noqa: E402
from test_blender_operators import add  # noqa: E402

from blender_turning.blender.ops import figure as ops_figure  # noqa: E402
from blender_turning.blender.ui import presets  # noqa: E402
from blender_turning.blender.registry_items import (formation_items,  # noqa: E402
                                                     retargeted_sport_items, sport_items)

pytestmark = [pytest.mark.blender, pytest.mark.usefixtures("registered")]


@pytest.fixture
def scene(registered):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    sc = bpy.context.scene
    sc.frame_start, sc.frame_end = 1, 48
    sc.render.fps = 24
    return sc


@pytest.fixture
def own(tmp_path):
    files = fx.write_sport(tmp_path)
    fx.import_sport(files[0])
    fx.register_formation()
    yield
    fx.unregister_all()


def _drawn(menu_draw) -> list:
    calls = []
    menu_draw(type("M", (), {"layout": LayoutStub(calls),
                             "preset_operator": presets.TURNING_MT_figure_presets.preset_operator,
                             "preset_subdir": presets.PRESET_SUBDIR})(), bpy.context)
    return calls


def test_the_builtin_sports_keep_the_values_saved_files_hold(scene):
    """An enum property stores its item's number (an ID property of the group): the numbers of
    the static tuple the sports had before the registry, so a saved file reads back the same."""
    obj = add("SKIER")
    for number, key in enumerate(("SKIER", "SNOWBOARDER", "TELEMARK", "CYCLIST")):
        obj.turning.sport = key
        assert obj.turning.get("sport") == number
        obj.turning["sport"] = number                  # what loading an older file does
        assert obj.turning.sport == key


def test_a_sport_registered_after_the_addon_is_in_every_enum_and_menu(scene, own):
    assert ("SKIBIKE", "Ski Bike") in [i[:2] for i in sport_items()]
    assert "SKIBIKE" in [i[0] for i in retargeted_sport_items()]
    add_menu = _drawn(ops_figure.VIEW3D_MT_turning_figure_add.draw)
    assert [c[2]["text"] for c in add_menu if c[0] == "operator"][-1] == "Ski Bike"
    preset_menu = _drawn(presets.TURNING_MT_figure_presets.draw)
    assert ("set", "sport", "SKIBIKE") in preset_menu
    # Add Figure builds it from its own rig file, with its record's body and limits.
    obj = add("SKIBIKE")
    s = obj.turning
    assert s.sport == "SKIBIKE" and s.get("sport") == 17
    assert (s.mass, s.com_height) == pytest.approx((88.0, 0.8))
    assert s.terrain.friction == pytest.approx(0.04)
    assert "ski.L" in obj.data.bones
    assert bpy.ops.turning.bake_turns() == {"FINISHED"}
    assert obj.animation_data.action is not None
    # Its preset (from the record) sets the body back; the Stance panel shows for it.
    s.mass = 60.0
    assert bpy.ops.turning.apply_figure_preset(sport="SKIBIKE") == {"FINISHED"}
    assert s.mass == pytest.approx(88.0)
    assert bpy.types.VIEW3D_PT_turning_stance.poll(bpy.context)


def test_make_figure_offers_the_sport_for_a_users_rig(scene, own):
    rig = mixamo_skeleton()
    activate(rig)
    assert bpy.ops.turning.make_figure(sport="SKIBIKE", bone_map="MIXAMO") == {"FINISHED"}
    assert rig.turning.sport == "SKIBIKE" and rig.turning.rig.is_user_rig
    assert rig.turning.rig.equipment is not None


def test_a_formation_registered_after_the_addon_is_in_add_crowd(scene, own):
    assert ("ECHELON", "Echelon") in [i[:2] for i in formation_items()]
    lead = add("SKIER")
    lead.turning.use_heading, lead.turning.heading = True, 0.0
    lead.turning.start_heading = 0.0
    assert bpy.ops.turning.add_crowd(formation="ECHELON", count=3, gap_time=1.0,
                                     spacing=2.0, staging="WAIT") == {"FINISHED"}   # the crowd's clock
    crowd = sorted((o for o in bpy.data.objects if o.name.startswith(f"{lead.name} ")
                    and o.type == "ARMATURE"), key=lambda o: o.name)
    assert len(crowd) == 3
    # Heading 0: left is +y; follower k starts k * 2 m to the left (its record's build).
    ys = [o.turning.start[1] - lead.turning.start[1] for o in crowd]
    assert ys == pytest.approx([2.0, 4.0, 6.0], abs=1e-5)
    assert [np.round(o.turning.crowd.time_offset, 6) for o in crowd] == [1.0, 2.0, 3.0]


def test_an_unregistered_sport_is_gone_from_the_enum(scene, own):
    fx.unregister_all()
    obj = add("SKIER")
    with pytest.raises(TypeError):
        obj.turning.sport = "SKIBIKE"
    assert "SKIBIKE" not in [i[0] for i in sport_items()]

"""The Turning sidebar drawn without a window (scripts/panel_recorder.py): every registered panel
of the tab draws, each call it makes is one ``UILayout`` takes, every property it shows exists
on its data, every operator, menu and list it names is registered; and the animator's guide
shows a picture of each panel (scripts/panel_pictures.py) that still matches the panel."""
import os
import re
import sys
import tempfile
from pathlib import Path

import pytest

os.environ.setdefault("BLENDER_USER_RESOURCES", tempfile.mkdtemp(prefix="turning-user-"))
bpy = pytest.importorskip("bpy")

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "scripts"))

import panel_pictures as pp  # noqa: E402
import panel_recorder as rec  # noqa: E402

pytestmark = pytest.mark.blender

GUIDE = ROOT / "docs" / "animator-guide.md"
PICTURE_MAX_BYTES = 60_000


@pytest.fixture(scope="module")
def drawn():
    """``({panel class: DrawnPanel}, problems)`` of the scene the pictures are drawn in."""
    problems = []
    shown = pp.draw_every_panel(problems)
    yield shown, problems
    from blender_turning import blender as addon
    addon.unregister()


def items(layout):
    for child in layout.children:
        if isinstance(child, rec.Layout):
            yield from items(child)
        else:
            yield child
            for row in child.rows:
                yield from items(row)


def test_every_panel_of_the_tab_is_drawn(drawn):
    shown, _ = drawn
    registered = rec.panels(pp.CATEGORY)
    assert len(registered) >= 12
    assert set(shown) == set(registered)
    labels = {cls.bl_label for cls in shown}
    assert {"Turning", "Turns", "Bake", "Speed Control", "Your Rig", "Stance", "Crowd"} <= labels


def test_every_call_resolves(drawn):
    """No property the data has not, no operator, operator property, menu or list that is not
    registered, in any panel drawn for any of the pictures' selections."""
    shown, problems = drawn
    assert not problems, "\n".join(problems)
    every = [it for d in shown.values() for it in items(d.body)]
    props = [it for it in every if it.kind == "prop"]
    ops = [it for it in every if it.kind in ("operator", "operator_menu_enum")]
    assert len(props) >= 40 and len(ops) >= 10, (len(props), len(ops))
    assert not [it for it in every if it.widget in ("missing", "placeholder")]


def test_the_pictures_show_what_the_panels_draw(drawn):
    """Values read through the RNA with their units, enum names, operator labels, greyed-out
    rows; the selections give each panel what it shows (Live Preview, Layers, a Stop)."""
    shown, _ = drawn
    text = {cls.bl_label: pp.describe(d) for cls, d in shown.items()}
    assert "Lean: 45°" in text["Turns"] and "Speed: 10 m/s" in text["Turns"]
    assert "ERROR Leans 36.0°, not 45.0°" in text["Turns"]
    assert "Mass: 75 kg" in text["Body"]
    assert "Style: Skid" in text["Speed Control"] and "Stop Side: " in text["Speed Control"]
    assert "~0.050" not in text["Ground"] and "Slope Friction: 0.050" in text["Ground"]
    assert "REC Bake 2 Figures" in text["Bake"] and "PLAY Live Preview on" in text["Bake"]
    assert "Layers (top first)" in text["Bake"]
    assert "Follow Path" in text["Follow Path"] and "Path: Course" in text["Follow Path"]
    assert "(collection 'Crowd')" in text["Crowd"] and "SORTSIZE Follow Path plans: " in text[
        "Crowd"]
    assert "spine / ORG-spine" in text["Your Rig"]
    assert [c.cls.bl_label for c in shown[rec.panels(pp.CATEGORY)[0]].children][:2] == [
        "Turns", "Bake"]


def guide_pictures() -> list:
    return re.findall(r"\]\((panels/[^)\s]+\.png)\)", GUIDE.read_text(encoding="utf-8"))


def test_the_guide_shows_each_panel_as_it_is_drawn(drawn):
    """A picture per panel in the guide, small, and still what the panel draws (its PNG text
    chunk); else: ``.venv/bin/python scripts/panel_pictures.py``."""
    shown, _ = drawn
    pictures = guide_pictures()
    assert {f"panels/{pp.picture_name(cls)}.png" for cls in shown} <= set(pictures)
    for rel in pictures:
        path = GUIDE.parent / rel
        assert path.exists(), f"{rel} is missing: run scripts/panel_pictures.py"
        assert path.stat().st_size < PICTURE_MAX_BYTES, (rel, path.stat().st_size)
    for cls, d in shown.items():
        path = GUIDE.parent / "panels" / f"{pp.picture_name(cls)}.png"
        assert pp.png_text(path).get(pp.CONTENT_KEY) == pp.describe(d), (
            f"{path.name} no longer shows the {cls.bl_label} panel: run "
            ".venv/bin/python scripts/panel_pictures.py")


def test_a_broken_draw_call_is_seen(drawn):
    """What a renamed property, an operator or menu that is gone, an operator property or enum
    value that does not exist, an unknown icon or keyword would do to a panel."""
    fig = bpy.data.objects["Skier"]
    problems = []
    layout = rec.Layout(problems=problems, where="Scratch")
    layout.use_property_split = True
    layout.prop(fig.turning, "lean")
    layout.prop(fig.turning, "lean_angle")
    layout.operator("turning.bake_turn")
    layout.operator("turning.add_figure").sports = "SKIER"
    layout.operator("turning.bake_turns").frame_range = "SELECTED"
    layout.operator_menu_enum("turning.bake_turns", "frames")
    layout.menu("TURNING_MT_figure_preset")
    assert problems == [
        "Scratch: prop(TurningFigureSettings, 'lean_angle'): no such property",
        "Scratch: operator('turning.bake_turn'): no such operator",
        "Scratch: operator('turning.add_figure').sports: no such property",
        "Scratch: operator('turning.bake_turns').frame_range = 'SELECTED': not one of "
        "['SCENE', 'PREVIEW', 'CUSTOM']",
        "Scratch: operator_menu_enum('turning.bake_turns', 'frames'): the operator has no "
        "such enum",
        "Scratch: menu('TURNING_MT_figure_preset'): no such menu",
    ]
    with pytest.raises(TypeError, match="icon 'SKI'"):
        layout.label(text="x", icon="SKI")
    with pytest.raises(TypeError, match="unexpected keyword 'txt'"):
        layout.prop(fig.turning, "lean", txt="Lean")
    with pytest.raises(AttributeError, match="no function 'proprety'"):
        layout.proprety(fig.turning, "lean")
    with pytest.raises(AttributeError, match="no attribute 'use_property_splt'"):
        layout.use_property_splt = True


def test_a_picture_carries_what_it_shows(drawn, tmp_path):
    pytest.importorskip("matplotlib")            # an optional extra (the 4.2 env has none)
    shown, _ = drawn
    cls = next(c for c in shown if c.bl_label == "Your Rig")
    path = tmp_path / "your-rig.png"
    pp.render(shown[cls], path)
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert pp.png_text(path)[pp.CONTENT_KEY] == pp.describe(shown[cls])


def test_without_matplotlib_one_line_and_exit_2(monkeypatch, capsys, tmp_path):
    monkeypatch.setitem(sys.modules, "matplotlib", None)       # import matplotlib fails
    assert pp.main(["--out", str(tmp_path)]) == 2
    out = capsys.readouterr().out
    assert out.count("\n") == 1 and "matplotlib" in out
    assert not list(tmp_path.iterdir())
